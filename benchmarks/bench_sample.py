"""Throughput of symsphere's samplers next to numpy, scipy, Mitsuba 3 and the memory write limit.

Every case runs in the same process and the cases take turns in every round
(round-robin, the starting case rotating from round to round), so that the
ratios compare like with like on a shared, noisy machine.  Reported: the
median (and the minimum) over the repeats, directions per second, bytes
written per second and speed ratios (reference time / case time: above 1 is
faster than the reference):

* ``vs write limit (touched)`` -- the fastest fill of the same bytes (n * 3 * itemsize)
                        into an already touched buffer: the memory write limit
                        for ``out=`` cases (target >= 0.8).  The fills are those of
                        benchmarks/_write_limit.py, with the samplers' threads: numpy's
                        ``ndarray.fill`` (one thread), a numba ``prange`` loop, the same
                        with non-temporal stores, a numba loop on Python threads.  Files
                        written before had numpy's ``fill`` alone ("vs fill (touched)");
* ``vs write limit (fresh)``  -- the fastest of ``np.empty`` + each fill: the limit for
                        freshly allocated output, page faults included (target >= 0.9;
                        before: ``np.empty`` + numpy's ``fill``, "vs empty+fill");
* ``vs classic``     -- numpy's textbook recipe z = 1 - 2u, phi = 2 pi v in the
                        same dtype (target >= 20);
* ``vs Mitsuba``     -- Mitsuba 3's ``mi.warp.square_to_uniform_sphere`` in the
                        ``llvm_ad_rgb`` variant (float32 only), from an (n, 2) numpy
                        array of uniforms to an (n, 3) numpy array (target >= 1).

``integrate()`` is timed with a trivial integrand next to sample_sphere + numpy
(``--no-integrate`` skips it).  A second table (``--no-profile`` skips it) times
the pieces of ``sample_sphere``/``sample_hemisphere`` separately -- the PCG64
states, the draws alone, the map alone, the orbit stores alone, the kernel with
given points and drawing its own, and a two-thread fill -- each built from the
library's own inlined functions, to show which piece keeps a target out of reach.

Usage::

    python benchmarks/bench_sample.py                       # n = 48 * 2**16, 21 repeats
    python benchmarks/bench_sample.py --n 480000 --repeats 31 --json results.json
    python benchmarks/bench_sample.py --no-mitsuba
    python benchmarks/bench_sample.py --no-integrate --no-profile   # the main table only

Mitsuba is optional (``pip install -e ".[bench]"``).  drjit 1.5 needs a recent
LLVM (Debian: ``apt-get install libllvm19``); if ``DRJIT_LIBLLVM_PATH`` is unset,
the newest libLLVM found in the usual places is used, and the script says which.
Mitsuba is first tried in a subprocess (an LLVM that is too old aborts the
process), and skipped with the reason if that fails; the rest still runs.
"""

from __future__ import annotations

import argparse
import datetime
import glob
import json
import os
import platform
import re
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field

import numpy as np
from _machine import cpu_name, cpu_snapshot, others_cpu  # benchmarks/_machine.py (the script's folder is on sys.path)
from _write_limit import FILLS  # benchmarks/_write_limit.py: the write limit's fills

import symsphere
from symsphere import sample_hemisphere, sample_sphere

FILL_VALUE = 0.5
NORMAL = (1.0, 1.0, 1.0)
DTYPES = (np.float64, np.float32)


@dataclass
class Case:
    """One timed callable.  *kind*: 'out' or 'fresh' (a sampler), 'ref' (a reference), 'piece' (profile)."""

    group: str
    label: str
    dtype: str
    kind: str
    run: object
    directions: int = 0  # directions per call (n; 0 for pieces that make none)
    note: str = ""
    part_of: str = ""  # for a piece: the label of the symsphere case it is a part of (same dtype, or both)
    times: list = field(default_factory=list)

    @property
    def median(self):
        return statistics.median(self.times)

    @property
    def best(self):
        return min(self.times)


# --- references -----------------------------------------------------------------


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


def gaussian_sphere(n, rng, dtype=np.float64):
    """Normalised standard Gaussians (Muller 1959)."""
    g = rng.standard_normal((n, 3), dtype=dtype)
    g /= np.linalg.norm(g, axis=1, keepdims=True)
    return g


def reference_cases(n, rng):
    from scipy.stats import uniform_direction

    cases = []
    for dtype in DTYPES:
        name = np.dtype(dtype).name
        touched = np.full((n, 3), FILL_VALUE, dtype=dtype)
        cases += [
            Case("limit", "numpy fill, touched buffer", name, "ref", lambda b=touched: b.fill(FILL_VALUE), n),
            Case(
                "limit",
                "np.empty + fill",
                name,
                "ref",
                lambda d=dtype: np.empty((n, 3), dtype=d).fill(FILL_VALUE),
                n,
            ),
        ]
        for way, fill in FILLS.items():
            if way == "numpy fill":  # the two cases above, under the labels of the earlier files
                continue
            touched_way = np.full(n * 3, FILL_VALUE, dtype=dtype)  # its own: see _write_limit.fills
            cases += [
                Case(
                    "limit",
                    f"{way} fill, touched buffer",
                    name,
                    "ref",
                    lambda f=fill, b=touched_way: f(b, FILL_VALUE),
                    n,
                ),
                Case(
                    "limit",
                    f"np.empty + {way} fill",
                    name,
                    "ref",
                    lambda f=fill, d=dtype: f(np.empty(n * 3, dtype=d), FILL_VALUE),
                    n,
                ),  # fmt: skip
            ]
        cases += [
            Case(
                "numpy",
                "numpy classic (z = 1 − 2u, φ = 2πv)",
                name,
                "ref",
                lambda d=dtype: classic_sphere(n, rng, d),
                n,
            ),
            Case("numpy", "normalised Gaussians", name, "ref", lambda d=dtype: gaussian_sphere(n, rng, d), n),
        ]
    direction = uniform_direction(3)
    cases.append(
        Case(
            "scipy",
            "scipy.stats.uniform_direction(3).rvs",
            "float64",
            "ref",
            lambda: direction.rvs(n, random_state=rng),
            n,
        )
    )
    return cases


# --- symsphere ------------------------------------------------------------------


def symsphere_cases(n, rng):
    cases = []
    for dtype in DTYPES:
        name = np.dtype(dtype).name
        out = np.full((n, 3), FILL_VALUE, dtype=dtype)  # touched once, reused by every out= case
        cases += [
            Case("symsphere", "sample_sphere", name, "fresh", lambda d=dtype: sample_sphere(n, rng=rng, dtype=d), n),
            Case(
                "symsphere",
                "sample_sphere, out=",
                name,
                "out",
                lambda d=dtype, o=out: sample_sphere(n, rng=rng, dtype=d, out=o),
                n,
            ),
            Case(
                "symsphere",
                "sample_hemisphere",
                name,
                "fresh",
                lambda d=dtype: sample_hemisphere(n, rng=rng, dtype=d),
                n,
            ),
            Case(
                "symsphere",
                "sample_hemisphere, out=",
                name,
                "out",
                lambda d=dtype, o=out: sample_hemisphere(n, rng=rng, dtype=d, out=o),
                n,
            ),
            Case(
                "symsphere",
                "sample_hemisphere, normal=(1,1,1)",
                name,
                "fresh",
                lambda d=dtype: sample_hemisphere(n, normal=NORMAL, rng=rng, dtype=d),
                n,
            ),
            Case(
                "symsphere",
                "sample_hemisphere, normal=(1,1,1), out=",
                name,
                "out",
                lambda d=dtype, o=out: sample_hemisphere(n, normal=NORMAL, rng=rng, dtype=d, out=o),
                n,
            ),
        ]
    return cases


# --- integrate() -----------------------------------------------------------------


def integrate_cases(n, rng):
    """integrate() throughput with a trivial integrand, next to sampling + numpy.

    f(w) = z costs one strided read, so the time is integrate()'s own: drawing the
    directions block by block (BLOCK orbits at a time), the per-orbit means and the
    running variance.  The reference draws all n directions at once with
    sample_sphere and averages f with numpy (no error estimate).
    """
    from symsphere import integrate

    def f(w):
        return w[:, 2]

    def sample_and_average():
        return f(sample_sphere(n, rng=rng)).mean()

    weights = np.array([0.3, -0.2, 0.9])

    def f_blas(w):
        return w @ weights  # numpy's BLAS, with its own threads

    return [
        Case(
            "integrate",
            "integrate(f(w) = z), random points",
            "float64",
            "fresh",
            lambda: integrate(f, n=n, rng=rng),
            n,
            "per-orbit standard error",
        ),
        Case(
            "integrate",
            "integrate(f(w) = z), points='sobol'",
            "float64",
            "fresh",
            lambda: integrate(f, n=n, points="sobol", rng=rng),
            n,
            "8 scrambled replicates",
        ),
        Case(
            "integrate",
            "integrate(f(w) = w @ a), random points",
            "float64",
            "fresh",
            lambda: integrate(f_blas, n=n, rng=rng),
            n,
            "BLAS threads next to numba's",
        ),
        Case("integrate", "sample_sphere + f + mean (no error estimate)", "float64", "fresh", sample_and_average, n),
    ]


# --- Mitsuba 3 ------------------------------------------------------------------

MIN_LLVM = 16  # drjit 1.5 fails with LLVM 15 (an LLVM ERROR that aborts the process); 19 works

_LLVM_GLOBS = (
    "/usr/lib/llvm-*/lib/libLLVM*.so*",
    "/usr/lib/x86_64-linux-gnu/libLLVM*.so*",
    "/usr/lib/aarch64-linux-gnu/libLLVM*.so*",
    "/usr/lib64/libLLVM*.so*",
    "/usr/lib/libLLVM*.so*",
    "/usr/local/lib/libLLVM*.so*",
    "/usr/local/opt/llvm/lib/libLLVM.dylib",
    "/opt/homebrew/opt/llvm/lib/libLLVM.dylib",
)
_PROBE = (  # the same kernel as the benchmark, on enough points to use the vector code paths
    "import numpy as np, mitsuba as mi; mi.set_variant('llvm_ad_rgb'); u = np.linspace(0, 1, 4096, dtype=np.float32); "
    "print(mi.warp.square_to_uniform_sphere(mi.Point2f(u, u[::-1].copy())).numpy().shape)"
)


def _llvm_version(path):
    """LLVM major version from a library path (libLLVM-19.so, libLLVM.so.19.1, llvm-19/lib/...), or 0."""
    for pattern in (r"libLLVM-(\d+)", r"libLLVM\.so\.(\d+)\.", r"llvm-(\d+)/"):
        match = re.search(pattern, path)
        if match:
            return int(match.group(1))
    return 0


def find_libllvm():
    """(path, message): DRJIT_LIBLLVM_PATH if set, else the newest libLLVM in the usual places."""
    if os.environ.get("DRJIT_LIBLLVM_PATH"):
        path = os.environ["DRJIT_LIBLLVM_PATH"]
        return path, f"DRJIT_LIBLLVM_PATH={path} (from the environment)"
    found = sorted(
        {os.path.realpath(p) for pattern in _LLVM_GLOBS for p in glob.glob(pattern)},
        key=lambda p: (_llvm_version(p), p),
    )
    if not found:
        return None, "DRJIT_LIBLLVM_PATH is unset and no libLLVM was found (Debian: apt-get install libllvm19)"
    path = found[-1]
    message = f"DRJIT_LIBLLVM_PATH was unset; using the newest libLLVM found: {path} (LLVM {_llvm_version(path)})"
    if _llvm_version(path) < MIN_LLVM:
        message += f", older than the LLVM {MIN_LLVM} that drjit 1.5 needs (Debian: apt-get install libllvm19)"
    return path, message


def probe_mitsuba():
    """(ok, message).  Sets DRJIT_LIBLLVM_PATH; tries the llvm_ad_rgb variant in a subprocess first."""
    try:
        import importlib.util

        if importlib.util.find_spec("mitsuba") is None:
            return False, 'mitsuba is not installed (pip install -e ".[bench]")'
    except (ImportError, ValueError) as error:
        return False, f"mitsuba cannot be found: {error}"
    path, message = find_libllvm()
    if path is not None:
        os.environ["DRJIT_LIBLLVM_PATH"] = path
    # drjit caches compiled kernels in ~/.drjit: a cache hit would hide an unusable LLVM, so the
    # test process gets an empty home directory and must really compile.
    with tempfile.TemporaryDirectory(prefix="symsphere-drjit-probe-") as home:
        env = dict(os.environ, HOME=home)
        proc = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True, timeout=300, env=env)
    if proc.returncode != 0:
        tail = ((proc.stderr or proc.stdout).strip().splitlines() or [""])[0][:160]
        return False, (
            f"{message}; the llvm_ad_rgb variant failed in a test process (exit {proc.returncode}): {tail} "
            "-- drjit 1.5 needs a newer LLVM than 15: apt-get install libllvm19, or set DRJIT_LIBLLVM_PATH"
        )
    return True, message


def mitsuba_cases(n, rng):
    """Mitsuba's square_to_uniform_sphere, numpy in, numpy out; the uniforms are made outside the timing."""
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    uv = rng.random((n, 2), dtype=np.float32)  # llvm_ad_rgb is float32; the input is made once, untimed
    u, v = np.ascontiguousarray(uv[:, 0]), np.ascontiguousarray(uv[:, 1])

    def columns_to_view():
        # The comparison of the issue: (n, 2) numpy array -> Point2f -> warp -> numpy (n, 3).
        # .numpy() of a Vector3f is (3, n); .T is an (n, 3) view (Fortran order), no copy.
        return mi.warp.square_to_uniform_sphere(mi.Point2f(uv[:, 0], uv[:, 1])).numpy().T

    def soa_to_view():
        # Mitsuba's best case: contiguous u and v in, (3, n) out viewed as (n, 3).
        return mi.warp.square_to_uniform_sphere(mi.Point2f(u, v)).numpy().T

    def columns_to_rows():
        # Same memory layout as symsphere's output: C-contiguous (n, 3).
        return np.ascontiguousarray(mi.warp.square_to_uniform_sphere(mi.Point2f(uv[:, 0], uv[:, 1])).numpy().T)

    def with_uniforms():
        # The whole pipeline, uniforms included (symsphere's timings include its random numbers).
        fresh = rng.random((n, 2), dtype=np.float32)
        return mi.warp.square_to_uniform_sphere(mi.Point2f(fresh[:, 0], fresh[:, 1])).numpy().T

    c = float(np.sqrt(1 / 3))
    frame = mi.Frame3f(mi.Vector3f(c, c, c))  # the normal (1, 1, 1) of the symsphere hemisphere cases

    def hemisphere():
        return mi.warp.square_to_uniform_hemisphere(mi.Point2f(uv[:, 0], uv[:, 1])).numpy().T

    def hemisphere_frame():
        return frame.to_world(mi.warp.square_to_uniform_hemisphere(mi.Point2f(uv[:, 0], uv[:, 1]))).numpy().T

    threads = dr.thread_count() if hasattr(dr, "thread_count") else None
    meta = {"mitsuba": mi.__version__, "drjit": dr.__version__, "drjit_threads": threads}
    cases = [
        Case("mitsuba", "Mitsuba warp: (n,2) → Point2f → .numpy().T", "float32", "ref", columns_to_view, n),
        Case("mitsuba", "Mitsuba warp: contiguous u, v → .numpy().T", "float32", "ref", soa_to_view, n),
        Case("mitsuba", "Mitsuba warp: (n,2) → C-contiguous (n,3)", "float32", "ref", columns_to_rows, n),
        Case("mitsuba", "Mitsuba warp incl. rng.random((n,2)) uniforms", "float32", "ref", with_uniforms, n),
        Case("mitsuba", "Mitsuba hemisphere warp: (n,2) → .numpy().T", "float32", "ref", hemisphere, n),
        Case("mitsuba", "Mitsuba hemisphere warp + Frame3f((1,1,1)).to_world", "float32", "ref", hemisphere_frame, n),
    ]
    return cases, meta


# --- profile pieces ---------------------------------------------------------------


def profile_cases(n, rng):
    """The pieces of sample_sphere / sample_hemisphere, each timed alone (kind 'piece').

    Each piece runs the library's own functions (``pcg64_random``, ``_map_batch``,
    the orbit stores ``store_sphere_orbit`` / ``store_hemisphere_orbit``) in the kernel's layout --
    one part per numba thread, batches of ``_BATCH`` base points -- with the other pieces left out, so that the sum of the
    pieces against the whole kernel shows how much of them overlaps.
    """
    import numba
    from numba import njit, prange

    from symsphere._kernels import (
        _BATCH,
        RandomPoints,
        _map_batch,
        fill_orbits,
        part_bounds,
    )
    from symsphere._random.pcg64 import pcg64_advanced, pcg64_random, pcg64_seeded
    from symsphere._vector_stores import store_hemisphere_orbit, store_sphere_orbit
    from symsphere.points import BasePoints

    @njit(parallel=True, cache=False)
    def draws_only(seed_words, bounds, sink):
        # the base points' uniforms alone: seeding, each part's jump, then two PCG64 draws per point
        start = pcg64_seeded(seed_words)
        for part in prange(len(bounds) - 1):
            stream = pcg64_advanced(start, 2 * bounds[part])
            total = 0.0
            for _ in range(bounds[part], bounds[part + 1]):
                total += pcg64_random(stream) + pcg64_random(stream)
            sink[part] = total

    @njit(parallel=True, cache=False)
    def map_only(uv, bounds, sink):
        # the vectorised map alone, batch by batch as in the kernel (a checksum, nothing stored)
        for part in prange(len(bounds) - 1):
            u = np.full(_BATCH, 0.5)
            v = np.full(_BATCH, 0.5)
            base = np.empty((3, _BATCH))
            total = 0.0
            for first in range(bounds[part], bounds[part + 1], _BATCH):
                stop = min(first + _BATCH, bounds[part + 1])
                for j in range(stop - first):
                    u[j] = uv[first + j, 0]
                    v[j] = uv[first + j, 1]
                _map_batch(u, v, 0, base)
                total += base[0, 0] + base[1, _BATCH - 1]
            sink[part] = total

    @njit(parallel=True, cache=False)
    def stores_only(bounds, count, rows):
        # the orbit stores alone, of a fixed point (no draws, no map)
        for part in prange(len(bounds) - 1):
            for i in range(bounds[part], bounds[part + 1]):
                if count == 48:
                    store_sphere_orbit(0.25, 0.125, 0.5, rows, i)
                else:
                    store_hemisphere_orbit(0.25, 0.125, 0.5, rows, i)

    @njit(parallel=True, cache=False)
    def parallel_fill(flat, value):
        for i in prange(flat.shape[0]):
            flat[i] = value

    basis = symsphere.frames.frame(np.asarray(NORMAL) / np.linalg.norm(NORMAL))
    sink = np.zeros(numba.get_num_threads() + 1)
    cases = []
    for count, whole in ((48, "sample_sphere, out="), (24, "sample_hemisphere, out=")):
        m = n // count
        source = BasePoints("random", 1, m, per_point=count)
        uv = source.take(0, m)
        bounds = part_bounds(m)
        domain = "sphere" if count == 48 else "hemisphere"
        cases += [
            Case(
                "base points",
                f"{domain}: BasePoints('random', ...) (Python)",
                "float64",
                "piece",
                lambda c=count, k=m: BasePoints("random", rng, k, per_point=c).seed_words,
                0,
                "root seed, the stream's seed words",
                whole,
            ),
            Case(
                "base points",
                f"{domain}: draws only (2 per point, parallel)",
                "float64",
                "piece",
                lambda s=source, b=bounds: draws_only(s.seed_words, b, sink),
                0,
                f"{m} points",
                whole,
            ),
            Case(
                "map",
                f"{domain}: map only (vectorised, batches of {_BATCH})",
                "float64",
                "piece",
                lambda u=uv, b=bounds: map_only(u, b, sink),
                0,
                f"{m} evaluations, nothing stored",
                whole,
            ),
        ]
        for dtype in DTYPES:
            name = np.dtype(dtype).name
            out = np.full((n, 3), FILL_VALUE, dtype=dtype)
            rows = out.reshape(m, 3 * count)
            cases += [
                Case(
                    "stores",
                    f"{domain}: stores only",
                    name,
                    "piece",
                    lambda b=bounds, r=rows, c=count: stores_only(b, c, r),
                    n,
                    "a fixed point, no draws, no map",
                    whole,
                ),
                Case(
                    "kernel",
                    f"{domain}: kernel, points given (fill_orbits)",
                    name,
                    "piece",
                    lambda u=uv, o=out, c=count: fill_orbits(u, "equal_area", c, None, o),
                    n,
                    "map + stores",
                    whole,
                ),
                Case(
                    "kernel",
                    f"{domain}: kernel drawing its points (fill_orbits, RandomPoints)",
                    name,
                    "piece",
                    lambda s=source, o=out, c=count, k=m: fill_orbits(
                        RandomPoints(s.seed_words, 0, k), "equal_area", c, None, o
                    ),
                    n,
                    "draws + map + stores",
                    whole,
                ),
            ]
            if count == 24:
                cases.append(
                    Case(
                        "kernel",
                        "hemisphere: kernel drawing its points, normal=(1,1,1)",
                        name,
                        "piece",
                        lambda s=source, o=out, k=m: fill_orbits(
                            RandomPoints(s.seed_words, 0, k), "equal_area", 24, basis, o
                        ),
                        n,
                        "draws + map + rotated stores",
                        "sample_hemisphere, normal=(1,1,1), out=",
                    )
                )
            if count == 48:
                flat = out.reshape(-1)
                cases.append(
                    Case(
                        "limit",
                        f"fill, numba prange ({numba.get_num_threads()} threads)",
                        name,
                        "piece",
                        lambda f=flat: parallel_fill(f, FILL_VALUE),
                        n,
                        "the write limit with all threads",
                    )
                )
    return cases


# --- measuring ------------------------------------------------------------------


def measure(cases, repeats, warmup=2):
    """Warm every case up (compilation, lazy imports, JIT caches), then time round-robin."""
    for case in cases:
        for _ in range(warmup):
            case.run()
    count = len(cases)
    for round_index in range(repeats):
        start = round_index % count  # rotate the order so no case always follows the same one
        for case in cases[start:] + cases[:start]:
            t0 = time.perf_counter()
            case.run()
            case.times.append(time.perf_counter() - t0)


def write_limit(cases):
    """Whether *cases* have the write limit's fills (results files written before have numpy's alone)."""
    return any(c.group == "limit" and c.kind == "ref" and c.label.startswith("numba") for c in cases)


def _fastest(cases, dtype, fresh, best=False):
    """The fastest write-limit case of *dtype* (fresh: ``np.empty`` + a fill; else into a touched buffer)."""
    found = [c for c in cases if c.group == "limit" and c.kind == "ref" and c.dtype == dtype
             and c.label.startswith("np.empty") == fresh and (fresh or c.label.endswith("touched buffer"))]  # fmt: skip
    return min(found, key=lambda c: c.best if best else c.median, default=None)


def _find(cases, group, label, dtype):
    for case in cases:
        if case.group == group and case.label.startswith(label) and case.dtype == dtype:
            return case
    return None


def _ratio(reference, case, best=False):
    if reference is None:
        return None
    return reference.best / case.best if best else reference.median / case.median


def _fmt_ratio(value):
    return "—" if value is None else f"{value:.2f}×"


def ratios(cases):
    """Per case: vs fill (touched), vs empty+fill, vs numpy classic, vs Mitsuba (f32, issue's form)."""
    mitsuba_sphere = _find(cases, "mitsuba", "Mitsuba warp: (n,2) → Point2f", "float32")
    mitsuba_hemisphere = _find(cases, "mitsuba", "Mitsuba hemisphere warp: (n,2)", "float32")
    mitsuba_frame = _find(cases, "mitsuba", "Mitsuba hemisphere warp + Frame3f", "float32")
    result = {}
    for case in cases:
        mitsuba = mitsuba_sphere  # the same domain: sphere, hemisphere about z, hemisphere about (1, 1, 1)
        if case.label.startswith("sample_hemisphere, normal"):
            mitsuba = mitsuba_frame
        elif case.label.startswith("sample_hemisphere"):
            mitsuba = mitsuba_hemisphere
        classic = _find(cases, "numpy", "numpy classic", case.dtype)
        result[id(case)] = {}
        for best, suffix in ((False, ""), (True, "_min")):  # the fastest fill by medians, and by minima
            references = {
                "vs_fill": _fastest(cases, case.dtype, False, best) if case.directions else None,
                "vs_empty_fill": _fastest(cases, case.dtype, True, best) if case.directions else None,
                "vs_classic": classic if case.kind != "piece" else None,
                "vs_mitsuba": mitsuba if case.dtype == "float32" and case.kind != "piece" else None,
            }
            result[id(case)].update({key + suffix: _ratio(ref, case, best) for key, ref in references.items()})
    return result


def _limit_headers(cases):
    """The write-limit columns' headers: the fastest fill, or numpy's fill in files written before."""
    if write_limit(cases):
        return "vs write limit (touched)", "vs write limit (fresh)"
    return "vs fill (touched)", "vs empty+fill"


def main_table(cases, table_ratios, n):
    touched, fresh = _limit_headers(cases)
    lines = [
        f"| case | dtype | median ms | min ms | directions/s | GB/s written | {touched} "
        f"| {fresh} | vs numpy classic | vs Mitsuba (f32, same domain) |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for case in cases:
        if case.kind == "piece":
            continue
        r = table_ratios[id(case)]
        gbs = n * 3 * np.dtype(case.dtype).itemsize / case.median / 1e9
        lines.append(
            f"| {case.label} | {case.dtype} | {case.median * 1e3:.2f} | {case.best * 1e3:.2f} "
            f"| {n / case.median / 1e6:.0f} M | {gbs:.1f} | {_fmt_ratio(r['vs_fill'])} "
            f"| {_fmt_ratio(r['vs_empty_fill'])} | {_fmt_ratio(r['vs_classic'])} | {_fmt_ratio(r['vs_mitsuba'])} |"
        )
    return "\n".join(lines)


def profile_table(cases, table_ratios):
    lines = [
        "| piece | dtype | median ms | min ms | share of the whole call (float64 / float32) "
        f"| {_limit_headers(cases)[0]} | note |",
        "|---|---|---:|---:|---|---:|---|",
    ]
    for case in cases:
        if case.kind != "piece":
            continue
        share = "—"
        if case.part_of:
            # dtype-independent pieces (base points, the map) are shares of both dtypes' calls
            dtypes = (case.dtype,) if case.directions else ("float64", "float32")
            parts = []
            for dtype in dtypes:
                whole = next(
                    (c for c in cases if c.kind != "piece" and c.label == case.part_of and c.dtype == dtype), None
                )
                parts.append("—" if whole is None else f"{case.median / whole.median:.0%}")
            share = f"{' / '.join(parts)} of `{case.part_of}`"
        lines.append(
            f"| {case.label} | {case.dtype} | {case.median * 1e3:.2f} | {case.best * 1e3:.2f} | {share} "
            f"| {_fmt_ratio(table_ratios[id(case)]['vs_fill'])} | {case.note} |"
        )
    return "\n".join(lines)


TARGETS = (
    # (what, label of the symsphere case, dtype, ratio key, threshold)
    ("sample_sphere f64, out= ≥ 0.8 × fill", "sample_sphere, out=", "float64", "vs_fill", 0.8),
    ("sample_sphere f32, out= ≥ 0.8 × fill", "sample_sphere, out=", "float32", "vs_fill", 0.8),
    ("sample_sphere f64, fresh ≥ 0.9 × (empty+fill)", "sample_sphere", "float64", "vs_empty_fill", 0.9),
    ("sample_sphere f32, fresh ≥ 0.9 × (empty+fill)", "sample_sphere", "float32", "vs_empty_fill", 0.9),
    ("sample_sphere f64 ≥ 20 × numpy classic", "sample_sphere", "float64", "vs_classic", 20),
    ("sample_sphere f32 ≥ 20 × numpy classic", "sample_sphere", "float32", "vs_classic", 20),
    ("sample_sphere f32 ≥ 1 × Mitsuba warp→numpy", "sample_sphere", "float32", "vs_mitsuba", 1),
    ("sample_sphere f32, out= ≥ 1 × Mitsuba warp→numpy", "sample_sphere, out=", "float32", "vs_mitsuba", 1),
    ("hemisphere normal f64, out= ≥ 0.8 × fill", "sample_hemisphere, normal=(1,1,1), out=", "float64", "vs_fill", 0.8),
    ("hemisphere normal f32, out= ≥ 0.8 × fill", "sample_hemisphere, normal=(1,1,1), out=", "float32", "vs_fill", 0.8),
    (
        "hemisphere normal f64, fresh ≥ 0.9 × (empty+fill)",
        "sample_hemisphere, normal=(1,1,1)",
        "float64",
        "vs_empty_fill",
        0.9,
    ),
    (
        "hemisphere normal f32, fresh ≥ 0.9 × (empty+fill)",
        "sample_hemisphere, normal=(1,1,1)",
        "float32",
        "vs_empty_fill",
        0.9,
    ),
    ("hemisphere normal f64 ≥ 20 × numpy classic", "sample_hemisphere, normal=(1,1,1)", "float64", "vs_classic", 20),
    ("hemisphere normal f32 ≥ 20 × numpy classic", "sample_hemisphere, normal=(1,1,1)", "float32", "vs_classic", 20),
    (
        "hemisphere normal f32 ≥ 1 × Mitsuba hemisphere warp + frame",
        "sample_hemisphere, normal=(1,1,1)",
        "float32",
        "vs_mitsuba",
        1,
    ),
    (
        "hemisphere normal f32, out= ≥ 1 × Mitsuba hemisphere warp + frame",
        "sample_hemisphere, normal=(1,1,1), out=",
        "float32",
        "vs_mitsuba",
        1,
    ),
)


def target_rows(cases, table_ratios):
    rows = []
    for what, label, dtype, key, threshold in TARGETS:
        if write_limit(cases):
            what = what.replace("× (empty+fill)", "× write limit (fresh)").replace("× fill", "× write limit")
        case = next((c for c in cases if c.group == "symsphere" and c.label == label and c.dtype == dtype), None)
        value = None if case is None else table_ratios[id(case)][key]
        best = None if case is None else table_ratios[id(case)][key + "_min"]
        rows.append(
            {
                "target": what,
                "threshold": threshold,
                "ratio": value,
                "ratio_of_minima": best,
                "reached": None if value is None else value >= threshold,
            }
        )
    return rows


def targets_table(rows):
    lines = [
        "| target | ratio of medians | reached (medians) | ratio of minima |",
        "|---|---:|---|---:|",
    ]
    for row in rows:
        reached = "not measured" if row["reached"] is None else ("yes" if row["reached"] else "**no**")
        lines.append(
            f"| {row['target']} | {_fmt_ratio(row['ratio'])} | {reached} | {_fmt_ratio(row['ratio_of_minima'])} |"
        )
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--n", type=int, default=48 * 2**16, help="directions per call, a multiple of 48 (default: %(default)s)"
    )
    parser.add_argument(
        "--repeats", type=int, default=21, help="timed rounds; medians are reported (default: %(default)s)"
    )
    parser.add_argument("--json", metavar="FILE", help="also write the results as JSON to FILE")
    parser.add_argument("--no-mitsuba", action="store_true", help="skip the Mitsuba 3 cases")
    parser.add_argument("--no-profile", action="store_true", help="skip the profile pieces")
    parser.add_argument("--no-integrate", action="store_true", help="skip the integrate() cases")
    parser.add_argument(
        "--find-llvm",
        action="store_true",
        help=f"only say which libLLVM Mitsuba would use; exit 1 if none of LLVM >= {MIN_LLVM} is found (for make bench)",
    )
    args = parser.parse_args(argv)
    if args.find_llvm:
        path, message = find_libllvm()
        print(message)
        explicit = bool(os.environ.get("DRJIT_LIBLLVM_PATH"))
        sys.exit(0 if path is not None and (explicit or _llvm_version(path) >= MIN_LLVM) else 1)
    if args.n <= 0 or args.n % 48:
        parser.error(f"--n must be a positive multiple of 48, got {args.n}")
    if args.repeats < 1:
        parser.error(f"--repeats must be at least 1, got {args.repeats}")

    import numba
    import scipy

    # the write limit's prange may start numba's OpenMP threads before symsphere does: make them wait
    # passively as symsphere would (spinning, they hold the cores the samplers' threads need)
    os.environ.setdefault("OMP_WAIT_POLICY", "passive")
    n = args.n
    rng = np.random.default_rng(12345)
    load_before = os.getloadavg()
    cases = reference_cases(n, rng) + symsphere_cases(n, rng)
    if not args.no_integrate:
        cases += integrate_cases(n, rng)
    meta = {}
    if args.no_mitsuba:
        mitsuba_message = "skipped (--no-mitsuba)"
    else:
        ok, mitsuba_message = probe_mitsuba()
        if ok:
            try:
                more, meta = mitsuba_cases(n, rng)
                cases += more
            except Exception as error:
                mitsuba_message += f"; skipped: {type(error).__name__}: {error}"
        else:
            mitsuba_message = "skipped: " + mitsuba_message
    if not args.no_profile:
        cases += profile_cases(n, rng)
    print(f"Mitsuba: {mitsuba_message}\nmeasuring {len(cases)} cases x {args.repeats} rounds ...", file=sys.stderr)

    snapshot, wall = cpu_snapshot(), time.perf_counter()
    measure(cases, args.repeats)
    others = others_cpu(snapshot, cpu_snapshot(), time.perf_counter() - wall)
    load_after = os.getloadavg()

    meta.update(
        {
            "date": datetime.datetime.now().isoformat(timespec="seconds"),
            "command": " ".join([os.path.relpath(sys.executable)] + sys.argv) if argv is None else None,
            "n": n,
            "repeats": args.repeats,
            "symsphere": symsphere.__version__,
            "numpy": np.__version__,
            "scipy": scipy.__version__,
            "numba": numba.__version__,
            "numba_threads": numba.get_num_threads(),
            "numba_threading_layer": numba.threading_layer(),
            "python": platform.python_version(),
            "machine": platform.machine(),
            "cpu": cpu_name(),
            "cpus": os.cpu_count(),
            "loadavg_before": load_before,
            "loadavg_after": load_after,
            "mitsuba_status": mitsuba_message,
            "other_processes": others,
        }
    )
    table_ratios = ratios(cases)
    targets = target_rows(cases, table_ratios)

    print(
        f"n = {n} directions per call ({n * 24 / 1e6:.1f} MB in float64), median of {args.repeats} rounds; "
        f"{meta['date']}; {meta['cpu']}, {meta['cpus']} CPUs; numba {meta['numba_threads']} threads "
        f"({meta['numba_threading_layer']}); symsphere {meta['symsphere']}, numpy {meta['numpy']}, "
        f"scipy {meta['scipy']}, numba {meta['numba']}, Python {meta['python']}"
        + (
            f"; Mitsuba {meta['mitsuba']}, drjit {meta['drjit']} ({meta['drjit_threads']} threads)"
            if "mitsuba" in meta
            else ""
        )
        + f"; load average {load_before[0]:.2f} before, {load_after[0]:.2f} after (this run included)"
        + (
            f"; other processes used {others['cpu_s']:.1f} CPU-s in the {others['wall_s']:.0f} s of timing "
            f"({others['share_of_all_cpus']:.0%} of all CPUs)"
            if others
            else ""
        )
        + "\n"
    )
    print(f"Mitsuba: {mitsuba_message}\n")
    print(main_table(cases, table_ratios, n))
    print()
    print(targets_table(targets))
    if not args.no_profile:
        print("\nProfile: the pieces, each timed alone in the same rounds\n")
        print(profile_table(cases, table_ratios))

    if args.json:
        from tables import source_hashes  # benchmarks/tables.py: what was measured, for its stale note

        payload = {
            "meta": meta,
            "sources": source_hashes(),
            "cases": [
                {
                    "group": c.group,
                    "label": c.label,
                    "dtype": c.dtype,
                    "kind": c.kind,
                    "directions": c.directions,
                    "note": c.note,
                    "part_of": c.part_of,
                    "median_s": c.median,
                    "min_s": c.best,
                    "times_s": c.times,
                    **table_ratios[id(c)],
                }
                for c in cases
            ],
            "targets": targets,
        }
        with open(args.json, "w", encoding="utf-8") as handle:
            json.dump(payload, handle, indent=1)


if __name__ == "__main__":
    main()
