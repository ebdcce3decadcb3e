"""Throughput of symsphere's samplers next to numpy's classic uniform-sphere recipe.

Every case is timed in the same process, interleaved round by round, so that
the ratios compare like with like (same machine, same load, same numpy).
Prints a Markdown table: median time over the repeats, directions per
second, and the speed relative to the classic recipe

    z = 1 - 2u,  phi = 2 pi v,  (x, y) = sqrt(1 - z^2) (cos phi, sin phi)

written into an (n, 3) array (a ratio above 1 means faster than it).

Usage::

    python benchmarks/bench_sample.py                  # n = 48 * 2**16, 15 repeats
    python benchmarks/bench_sample.py --n 4800000 --repeats 7
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time

import numpy as np

import symsphere
from symsphere import sample_hemisphere, sample_sphere


def classic_sphere(n, rng, dtype=np.float64):
    """numpy's textbook uniform directions: z uniform in [-1, 1], phi uniform in [0, 2 pi)."""
    u = rng.random(n, dtype=dtype)
    v = rng.random(n, dtype=dtype)
    out = np.empty((n, 3), dtype=dtype)
    z = out[:, 2]
    np.subtract(1, 2 * u, out=z)
    phi = (2 * np.pi) * v
    r = np.sqrt(np.maximum(1 - z * z, 0))  # max: rounding can make 1 - z^2 slightly negative
    np.multiply(r, np.cos(phi), out=out[:, 0])
    np.multiply(r, np.sin(phi), out=out[:, 1])
    return out


def build_cases(n):
    """(label, dtype, callable) per case; each callable draws n directions with a fresh seed stream."""
    rng = np.random.default_rng(12345)
    out64 = np.empty((n, 3), dtype=np.float64)
    out32 = np.empty((n, 3), dtype=np.float32)
    return [
        ("numpy classic (z = 1 − 2u, φ = 2πv)", "float64", lambda: classic_sphere(n, rng)),
        ("numpy classic (z = 1 − 2u, φ = 2πv)", "float32", lambda: classic_sphere(n, rng, np.float32)),
        ("sample_sphere", "float64", lambda: sample_sphere(n, rng=rng)),
        ("sample_sphere, out=", "float64", lambda: sample_sphere(n, rng=rng, out=out64)),
        ("sample_sphere", "float32", lambda: sample_sphere(n, rng=rng, dtype=np.float32)),
        ("sample_sphere, out=", "float32", lambda: sample_sphere(n, rng=rng, dtype=np.float32, out=out32)),
        ("sample_hemisphere", "float64", lambda: sample_hemisphere(n, rng=rng)),
        ("sample_hemisphere, normal=(1, 1, 1)", "float64", lambda: sample_hemisphere(n, normal=(1, 1, 1), rng=rng)),
    ]


def measure(cases, repeats):
    """Median seconds per case; the cases take turns in every round."""
    for _, _, run in cases:  # warm up: imports, first-touch page faults, scipy's lazy loads
        run()
    times = [[] for _ in cases]
    for _ in range(repeats):
        for k, (_, _, run) in enumerate(cases):
            start = time.perf_counter()
            run()
            times[k].append(time.perf_counter() - start)
    return [statistics.median(t) for t in times]


def markdown_table(n, cases, medians):
    classic = {dtype: medians[k] for k, (label, dtype, _) in enumerate(cases) if label.startswith("numpy classic")}
    lines = [
        "| sampler | dtype | median time (ms) | directions/s | vs numpy classic (same dtype) |",
        "|---|---|---:|---:|---:|",
    ]
    for (label, dtype, _), seconds in zip(cases, medians):
        ratio = classic[dtype] / seconds
        lines.append(f"| {label} | {dtype} | {seconds * 1e3:.2f} | {n / seconds:.3g} | {ratio:.2f}× |")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--n", type=int, default=48 * 2**16, help="directions per call, a multiple of 48 (default: %(default)s)"
    )
    parser.add_argument(
        "--repeats", type=int, default=15, help="timed calls per case; the median is reported (default: %(default)s)"
    )
    args = parser.parse_args(argv)
    if args.n <= 0 or args.n % 48:
        parser.error(f"--n must be a positive multiple of 48, got {args.n}")
    if args.repeats < 1:
        parser.error(f"--repeats must be at least 1, got {args.repeats}")

    cases = build_cases(args.n)
    medians = measure(cases, args.repeats)
    print(
        f"n = {args.n} directions per call, median of {args.repeats} repeats; symsphere {symsphere.__version__}, "
        f"numpy {np.__version__}, Python {platform.python_version()}, {platform.machine()}, "
        f"{os.cpu_count()} CPUs\n"
    )
    print(markdown_table(args.n, cases, medians))


if __name__ == "__main__":
    main()
