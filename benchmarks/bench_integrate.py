"""Fused integration benchmark: integrate(f) with f in numpy vs compiled f evaluated inside the kernel.

At n = 48 * 2**20 directions (random points, equal_area, sphere; one run, interleaved rounds,
medians), for each integrand:

- ``numpy f``: ``symsphere.integrate`` with f written with numpy on (m, 3) blocks (for the suite's
  ``exp``: the suite's own numpy ``f``, ``np.exp(np.asarray(d, dtype=np.float64) @ a)``);
- ``plain lambda``: ``symsphere.integrate(lambda w: np.exp(w @ a))`` for the exp rows (the
  polynomial's numpy f is already the plain expression);
- ``lambda, BLAS 1 thread``: the same with numpy's OpenBLAS held to one thread around the call
  (its ``w @ a`` threads otherwise alternate with numba's on the same cores, block by block): the
  fastest numpy path found, so the honest baseline;
- ``fused``: ``symsphere.integrate`` with a compiled f (numba ``@njit`` of (x, y, z), or the
  integrand suite's generated kernel): the kernel maps, takes the 48 images and evaluates f in
  registers, with per-orbit statistics for the error bar;
- ``limit``: "map + orbit + f in registers" alone: the same pieces (inlined PCG64, the batch
  map, the image weights, f) summing f to one number per thread, no weights, no statistics,
  no block reduction -- the compute limit of the fused path.

Integrands: the polynomial x^4 + y^4 + z^4 + xyz/2 + z; exp(w . a) as a user's @njit function
(numba's scalar libm exp); the suite's ``exp`` integrand (its kernel uses a libm-free
polynomial exp, so the batch loop vectorises); and the polynomial as f(w) of a (3,) array.

numba's thread pool is started through symsphere (passive OpenMP waiting, as ``integrate`` does)
before anything else asks numba for its threads: before 2026-11-30 12:00 this script called
``numba.get_num_threads()`` first, which started the pool with libgomp's default (spinning) wait and
slowed the numpy path 1.5-2x (``--early-threads`` reproduces that; see docs/results/bench-integrate.md).

    python benchmarks/bench_integrate.py [--log2-orbits 20] [--rounds 5] [--json PATH] [--early-threads]
"""

from __future__ import annotations

import argparse
import contextlib
import ctypes
import glob
import json
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from numba import get_num_threads, njit, prange

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import cpu_name

import symsphere
from symsphere._fused import call_vector, call_xyz
from symsphere._kernels import (
    BATCH,
    map_batch,
    prepare_kernels,
    rotated_weights,
)
from symsphere._random.pcg64 import pcg64_advanced, pcg64_random, pcg64_seeded
from symsphere.integrands import INTEGRANDS
from symsphere.points import BasePoints

A = np.array([0.7, -0.4, 0.5])


@njit
def poly_xyz(x, y, z):
    return x**4 + y**4 + z**4 + x * y * z / 2 + z


@njit
def poly_vector(w):
    return w[0] ** 4 + w[1] ** 4 + w[2] ** 4 + w[0] * w[1] * w[2] / 2 + w[2]


@njit
def exp_xyz(x, y, z):
    return np.exp(0.7 * x - 0.4 * y + 0.5 * z)


@contextlib.contextmanager
def blas_threads(count):
    """numpy's OpenBLAS (scipy-openblas, as pip's numpy ships it) held to *count* threads inside."""
    libs = glob.glob(os.path.join(os.path.dirname(np.__file__), os.pardir, "numpy.libs", "*openblas*"))
    lib = ctypes.CDLL(libs[0]) if libs else None
    if lib is None or not hasattr(lib, "scipy_openblas_set_num_threads64_"):
        raise RuntimeError("numpy's OpenBLAS not found: cannot set its thread count")
    before = lib.scipy_openblas_get_num_threads64_()
    lib.scipy_openblas_set_num_threads64_(count)
    try:
        yield
    finally:
        lib.scipy_openblas_set_num_threads64_(before)


def poly_numpy(w):
    return (w**4).sum(axis=1) + w[:, 0] * w[:, 1] * w[:, 2] / 2 + w[:, 2]


def exp_numpy(w):
    return np.exp(w @ A)


def _limit_kernel(vector):
    """The "limit" kernel for f called as f(w) if *vector* else f(x, y, z).

    *vector* is a closure cell, not an argument, as in the library's fused kernels: numba then
    prunes the other branch and inlines the call (an argument caller is an opaque call that LLVM
    cannot inline, which made a polynomial f ~2.8x slower per thread).
    """

    @njit(parallel=True, error_model="numpy", nogil=True)
    def limit(f, seed_words, m, parts, weights):
        # map + orbit + f in registers: random base points drawn in the kernel, 48 images, f summed.
        start = pcg64_seeded(seed_words)
        totals = np.zeros(parts)
        images = weights.shape[1] // 3
        for part in prange(parts):
            lo, hi = m * part // parts, m * (part + 1) // parts
            stream = pcg64_advanced(start, 2 * lo)
            u = np.full(BATCH, 0.5)
            v = np.full(BATCH, 0.5)
            base = np.empty((3, BATCH))
            sums = np.zeros(BATCH)
            buffer = np.empty(3)
            for first in range(lo, hi, BATCH):
                for j in range(min(BATCH, hi - first)):
                    u[j] = pcg64_random(stream)
                    v[j] = pcg64_random(stream)
                map_batch(u, v, 0, base)
                for k in range(images):
                    w00, w01, w02 = weights[0, 3 * k], weights[0, 3 * k + 1], weights[0, 3 * k + 2]
                    w10, w11, w12 = weights[1, 3 * k], weights[1, 3 * k + 1], weights[1, 3 * k + 2]
                    w20, w21, w22 = weights[2, 3 * k], weights[2, 3 * k + 1], weights[2, 3 * k + 2]
                    for j in range(BATCH):
                        x, y, z = base[0, j], base[1, j], base[2, j]
                        a = x * w00 + y * w10 + z * w20
                        b = x * w01 + y * w11 + z * w21
                        c = x * w02 + y * w12 + z * w22
                        if vector:
                            sums[j] += call_vector(f, a, b, c, buffer)
                        else:
                            sums[j] += call_xyz(f, a, b, c, buffer)
            totals[part] = sums.sum()
        return totals.sum() * (4 * np.pi / 48) / m

    return limit


_LIMITS = {False: _limit_kernel(False), True: _limit_kernel(True)}


def _limit(f, caller, seed_words, m, parts, weights):
    return _LIMITS[caller is call_vector](f, seed_words, m, parts, weights)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--log2-orbits", type=int, default=20, help="n = 48 * 2**this (default 20)")
    parser.add_argument("--rounds", type=int, default=5, help="interleaved rounds; medians are reported")
    parser.add_argument("--json", type=Path, default=None, help="write the measurements here")
    parser.add_argument(
        "--early-threads",
        action="store_true",
        help="reproduce the old artifact: start numba's threads (spinning wait) before symsphere does",
    )
    args = parser.parse_args(argv)
    if args.early_threads:
        get_num_threads()
    prepare_kernels()  # numba's threads, started as symsphere starts them (passive waiting)
    orbits = 2**args.log2_orbits
    n = 48 * orbits
    seed_words = BasePoints("random", 1, orbits).seed_words
    weights = rotated_weights(np.eye(3), 48)
    parts = max(get_num_threads(), orbits // 512)  # as many parts as the fused kernel has chunks
    suite_exp = INTEGRANDS["exp"]
    cases = {  # name: (numpy f, compiled f for integrate, (kernel, caller) for the limit, plain numpy lambda)
        "x^4+y^4+z^4+xyz/2+z": (poly_numpy, poly_xyz, (poly_xyz, call_xyz), None),
        "exp(w.a), user @njit (libm exp)": (exp_numpy, exp_xyz, (exp_xyz, call_xyz), exp_numpy),
        "suite 'exp' (polynomial exp)": (suite_exp.f, suite_exp, (suite_exp.kernel, call_xyz), exp_numpy),
        "x^4+... as f(w), w a (3,) array": (poly_numpy, poly_vector, (poly_vector, call_vector), None),
    }

    def numpy_run(f, blas=None):
        def run():
            with blas_threads(blas) if blas else contextlib.nullcontext():
                return symsphere.integrate(f, n=n, rng=1).integral

        return run

    runs = {}  # each distinct numpy baseline is timed once per round
    baselines = {
        "poly numpy f": numpy_run(poly_numpy),
        "exp: suite f": numpy_run(suite_exp.f),
        "exp: plain lambda": numpy_run(exp_numpy),
        "exp: plain lambda, BLAS 1 thread": numpy_run(exp_numpy, 1),
    }
    for key, run in baselines.items():
        runs[("numpy", key)] = run
    for name, (_numpy_f, compiled, (kernel, caller), _) in cases.items():
        runs[(name, "fused")] = lambda f=compiled: symsphere.integrate(f, n=n, rng=1).integral
        runs[(name, "limit")] = lambda k=kernel, c=caller: _limit(k, c, seed_words, orbits, parts, weights)
    values = {}
    for key, run in runs.items():  # warm up: compile, and check that they agree
        if key[1] == "fused":
            symsphere.integrate(cases[key[0]][1], n=48 * 4096, rng=1)
        values[key] = run()
    times = {key: [] for key in runs}
    for _ in range(args.rounds):
        for key, run in runs.items():
            start = time.perf_counter()
            run()
            times[key].append(time.perf_counter() - start)
    medians = {key: statistics.median(t) for key, t in times.items()}
    print(
        f"n = 48 * 2**{args.log2_orbits} = {n:,} directions, {get_num_threads()} threads, {cpu_name()}, "
        f"medians of {args.rounds} interleaved rounds, load average {os.getloadavg()[0]:.1f}"
        + (" (--early-threads)" if args.early_threads else "")
    )
    print(
        "| integrand | numpy f (s) | plain lambda (s) | lambda, BLAS 1 thread (s) | fused (s) | limit (s) | "
        "numpy f M/s | best numpy M/s | fused M/s | limit M/s | fused / numpy f | fused / best numpy | fused / limit |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    rows = []
    for name, (numpy_f, *_, plain) in cases.items():
        own = medians[
            (
                "numpy",
                "exp: suite f"
                if numpy_f is suite_exp.f
                else "poly numpy f"
                if numpy_f is poly_numpy
                else "exp: plain lambda",
            )
        ]
        t_plain = medians[("numpy", "exp: plain lambda")] if plain is not None else own
        t_blas1 = medians[("numpy", "exp: plain lambda, BLAS 1 thread")] if plain is not None else own
        best = min(own, t_plain, t_blas1)
        t_fused, t_limit = medians[(name, "fused")], medians[(name, "limit")]
        row = dict(
            integrand=name,
            numpy=own,
            plain_lambda=t_plain,
            lambda_blas1=t_blas1,
            best_numpy=best,
            fused=t_fused,
            limit=t_limit,
            speedup=own / t_fused,
            speedup_best=best / t_fused,
            of_limit=t_limit / t_fused,
            integral_fused=float(values[(name, "fused")]),
            integral_limit=float(values[(name, "limit")]),
        )
        rows.append(row)
        blas = "-" if plain is None else f"{t_blas1:.3f}"
        lam = "-" if plain is None else f"{t_plain:.3f}"
        print(
            f"| {name} | {own:.3f} | {lam} | {blas} | {t_fused:.3f} | {t_limit:.3f} | {n / own / 1e6:.0f} | "
            f"{n / best / 1e6:.0f} | {n / t_fused / 1e6:.0f} | {n / t_limit / 1e6:.0f} | {row['speedup']:.1f}x | "
            f"{row['speedup_best']:.1f}x | {row['of_limit']:.2f}x |"
        )
    if args.json:
        args.json.write_text(
            json.dumps(
                dict(
                    n=n,
                    threads=get_num_threads(),
                    cpu=cpu_name(),
                    rounds=args.rounds,
                    load_average=os.getloadavg(),
                    early_threads=args.early_threads,
                    rows=rows,
                    integrals={f"{k[0]} | {k[1]}": float(v) for k, v in values.items()},
                    times={f"{k[0]} | {k[1]}": v for k, v in times.items()},
                ),
                indent=2,
            )
        )


if __name__ == "__main__":
    main()
