"""Any size costs what the nearest multiple of 48 costs: sample_sphere(n) for n = 48 m + r against 48 m.

For each size, the calls for n and for the multiple m * 48 are interleaved (a, b, a, b, ...), so that a
busy machine's noise hits both alike; the ratio ``time(n) / time(48 m)`` of the medians (and of the
minima) is printed for fresh output and for ``out=``, in float64 and float32.  Target: every ratio of
medians <= 1.10.  The load average before and after is printed: on a shared machine, run it twice.

    python benchmarks/bench_any_size.py [--repeats 400] [--dtype float64 float32] [--json results/....json]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import numpy as np

import symsphere

MULTIPLES = (48 * 2, 48 * 100, 48 * 1024, 48 * 2**16)
OFFSETS = (1, 24, 47, -1)


def interleaved(call_a, call_b, repeats):
    """(median a, median b, min a, min b) over *repeats* rounds, the order alternating by round."""
    times = np.empty((repeats, 2))
    for i in range(repeats):
        for j in (0, 1) if i % 2 == 0 else (1, 0):
            start = time.perf_counter()
            (call_a, call_b)[j]()
            times[i, j] = time.perf_counter() - start
    median, best = np.median(times, axis=0), times.min(axis=0)
    return float(median[0]), float(median[1]), float(best[0]), float(best[1])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--repeats", type=int, default=400, help="calls per size (fewer, at least 100, for the largest)"
    )
    parser.add_argument("--dtype", nargs="+", default=["float64", "float32"], choices=["float64", "float32"])
    parser.add_argument("--json", type=Path, default=None, help="also write the rows as JSON")
    args = parser.parse_args()
    print(
        f"symsphere {symsphere.__version__}, numpy {np.__version__}, {platform.processor() or platform.machine()}, "
        f"{os.cpu_count()} cores, load average {_load()}"
    )
    print("medians over interleaved calls; ratio = time(n) / time(multiple of 48) (of the minima); target <= 1.10\n")
    print("| dtype | multiple | n | fresh: µs, multiple | n | ratio (min) | out=: µs, multiple | n | ratio (min) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    rows = []
    for dtype in args.dtype:
        for multiple in MULTIPLES:
            repeats = max(100, args.repeats // (1 + multiple // 50_000))
            for offset in OFFSETS:
                rows.append(_row(multiple, multiple + offset, np.dtype(dtype), repeats))
    worst = max(max(r["fresh"][1] / r["fresh"][0], r["out"][1] / r["out"][0]) for r in rows)
    print(f"\nworst ratio of medians {worst:.3f}; load average {_load()}")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1), encoding="utf-8")
    return 0


def _row(multiple, n, dtype, repeats):
    """Time sample_sphere(multiple) against sample_sphere(n), fresh and into ``out=``; print a table row."""
    symsphere.sample_sphere(n, rng=1, dtype=dtype)  # compile / warm up
    fresh = interleaved(
        lambda: symsphere.sample_sphere(multiple, rng=1, dtype=dtype),
        lambda: symsphere.sample_sphere(n, rng=1, dtype=dtype),
        repeats,
    )
    out_a, out_b = np.empty((multiple, 3), dtype), np.empty((n, 3), dtype)
    given = interleaved(
        lambda: symsphere.sample_sphere(multiple, rng=1, dtype=dtype, out=out_a),
        lambda: symsphere.sample_sphere(n, rng=1, dtype=dtype, out=out_b),
        repeats,
    )
    print(
        f"| {dtype.name} | {multiple} | {n} | {fresh[0] * 1e6:.0f} | {fresh[1] * 1e6:.0f} | {fresh[1] / fresh[0]:.3f} "
        f"({fresh[3] / fresh[2]:.3f}) | {given[0] * 1e6:.0f} | {given[1] * 1e6:.0f} | "
        f"{given[1] / given[0]:.3f} ({given[3] / given[2]:.3f}) |",
        flush=True,
    )
    return dict(dtype=dtype.name, multiple=multiple, n=n, fresh=fresh, out=given)


def _load():
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


if __name__ == "__main__":
    raise SystemExit(main())
