"""Fused integration: map + orbit + f + per-orbit statistics in one parallel numba pass, nothing stored.

:func:`symsphere.integrate` takes this path when ``f`` is compiled: a numba ``@njit``
function of one direction, ``f(x, y, z) -> float`` or ``f(w) -> float`` with ``w`` a (3,)
array, or a :class:`symsphere.integrands.Integrand` with a ``kernel``.  The kernel
below is the sampling kernel of :mod:`symsphere._kernels` with the store replaced by
an evaluation: the same inlined PCG64 stream (random and stratified base points are
drawn inside the kernel, addressed by index), the same batch map (``map_batch``, a
structure-of-arrays batch of ``BATCH`` base points, vectorised for ``'equal_area'``)
and the same image weights (``rotated_weights``: image k of p is
``p @ W[:, 3k:3k+3]``; about a normal W includes the frame).  For each image the batch
loop evaluates f on all ``BATCH`` base points, so an f without libm calls is vectorised
across base points too.  Orbit sums stay in registers; per-orbit estimates
``(sum / count) * weight`` (weight: 1/pdf of the scheme, shared by the orbit) are reduced
at once to (count, sum, sum of squared deviations) per batch, merged into chunks of
``CHUNK`` orbits (the parallel unit) and then into the integrator's blocks, in order,
with the pairwise update of :func:`symsphere._integration.combine`.

Difference from the numpy path (equal to rounding, not bit for bit): the numpy path
takes the block's sum of squared deviations about the block mean in one pass
after the fact; here it is merged from batches of ``BATCH`` orbits (Chan et al.),
and the 48 (24) values of an orbit are summed in image order; about a normal the
images are ``x W0 + y W1 + z W2`` instead of numpy's ``local @ basis``.  The result
does not depend on the thread count or on how the blocks are split between tasks.

One serial kernel per (integrand, map), specialised by closure cells (as
:func:`symsphere._kernels._fill_kernel` is): the cells say where f comes from and which map the batch
takes, so numba prunes the other maps before typing them; the chunks of a call are split into parts
run at once on the threads of :mod:`symsphere._threads` (each chunk's stream and statistics depend on
nothing but its index, so the result does not depend on the parts).  Measured on the 2-core Intel
host, a user's f: ~4 s for its first kernel (the helpers shared with later ones included) and ~2 s
for each further map, against ~7 s for the one ``prange`` kernel of every map this replaced (on the
Zen 4 host, 2026-12-04: 0.6-0.85 s for each further kernel, 0.9-1.1 s before the integrand's branch
moved into the kernel's own IR, where numba prunes it before inlining).  A
user's compiled f is an argument, so numba compiles its kernel once per integrand, map and process,
and cannot cache it on disk: a function-typed argument is
typed by the dispatcher object, which differs in every process, so a cached entry never matches
(measured: saved, never hit).  A suite integrand (:mod:`symsphere.integrands`, whose kernel carries
its spec ``(kind, params)``, see :mod:`symsphere._integrand_kernels`) is compiled into the kernel
instead: the spec is in the cells, numba folds it into the machine code and caches the kernel on
disk keyed by the cells' values (numba hashes a closure's cell contents into its cache index), so a
later process loads the machine code (tens of ms) instead of compiling.  The cache is numba's, next
to this module (or under ``NUMBA_CACHE_DIR``), dropped when a file the kernel inlines changes
(:mod:`symsphere._numba_cache`).
"""

from __future__ import annotations

import functools
import inspect
import threading
from typing import Any

import numpy as np
from numba import get_num_threads, njit
from numba.extending import is_jitted

from ._constants import HEMISPHERE_AREA, SPHERE_AREA
from ._integrand_kernels import no_chain
from ._integrand_kernels import value as spec_value
from ._kernels import (
    BATCH,
    METHOD_CODES,
    map_batch,
    prepare_kernels,
    rotated_weights,
    triangle_density,
)
from ._numba_cache import invalidate_if_changed
from ._random.pcg64 import pcg64_advanced, pcg64_random, pcg64_seeded
from ._threads import route, route_compiles, run_kernel
from ._typing import Float64Array, MapMethod
from .points import BLOCK, BasePoints
from .symmetry import orbit_size

_SPHERE_ORBIT = orbit_size("sphere")  # a global: numba freezes it as a constant

__all__ = [
    "CHUNK",
    "Compiled",
    "compiled_integrand",
    "fused_partials",
    "NonFiniteBlock",
    "vectorised",
    "call_xyz",
    "call_vector",
    "specialised_kernels",
]

CHUNK = 512
"""Orbits per parallel work unit; BLOCK is a multiple, so chunks never straddle blocks."""
assert BLOCK % CHUNK == 0

_RANDOM, _STRATIFIED, _GIVEN = 0, 1, 2
_SEGMENT_BLOCKS = 64  # given base points (QMC) are taken this many blocks at a time: bounded memory
_OPTIONS: dict[str, Any] = dict(error_model="numpy", nogil=True)


@njit(inline="always")
def call_xyz(f, x, y, z, buffer):
    """f(x, y, z): a compiled integrand of three coordinates."""
    return f(x, y, z)


@njit(inline="always")
def call_vector(f, x, y, z, buffer):
    """f(w) with w = (x, y, z) in a per-thread (3,) buffer: a compiled integrand of one array."""
    buffer[0] = x
    buffer[1] = y
    buffer[2] = z
    return f(buffer)


Compiled = tuple[Any, Any, "tuple[int, tuple[float, ...], Any] | None"]
"""(the numba function, the caller that adapts its signature: call_xyz or call_vector, the
function's spec ``(kind, params)`` when it has one: the suite's integrands, compiled into a
disk-cached kernel)."""


def compiled_integrand(f: object) -> Compiled | None:
    """(kernel, caller) if *f* is a compiled integrand, else None (the numpy path).

    Compiled: a numba dispatcher of 3 arguments (x, y, z) or of 1 argument (a (3,) array), or
    an object with such a dispatcher as its ``kernel`` attribute (the integrand suite).  The
    function is called once here, at (0, 0, 1), so that a wrong signature or a result that is
    not one real number raises TypeError naming 'f' before any work.
    """
    kernel: Any = getattr(f, "kernel", None) if not is_jitted(f) else f  # type: ignore[arg-type]
    if kernel is None or not is_jitted(kernel):
        return None
    spec = getattr(kernel, "symsphere_spec", None)
    if spec is not None:
        return kernel, call_xyz, spec  # made by symsphere._integrand_kernels (tested there): no probe, no compilation
    try:
        arity = len(inspect.signature(kernel.py_func).parameters)
    except (TypeError, ValueError):  # pragma: no cover - numba dispatchers always have py_func
        arity = -1
    if arity not in (1, 3):
        raise TypeError(
            f"a compiled 'f' must take one direction, as f(x, y, z) or f(w) with w of shape (3,); got {arity} parameters"
        )
    try:
        value = kernel(0.0, 0.0, 1.0) if arity == 3 else kernel(np.array([0.0, 0.0, 1.0]))
    except Exception as error:
        raise TypeError(f"a compiled 'f' could not be called on one direction: {error}") from None
    if not isinstance(value, (float, int, np.floating, np.integer)) or isinstance(value, (bool, np.bool_)):
        raise TypeError(f"a compiled 'f' must return one real number, got {type(value).__name__}")
    return kernel, (call_xyz if arity == 3 else call_vector), None


class NonFiniteBlock(ValueError):
    """A block's statistics are not finite; *block* says which (the numpy path then finds the direction)."""

    def __init__(self, message: str, block: int) -> None:
        super().__init__(message)
        self.block = block


def vectorised(compiled: Compiled) -> Any:
    """A numpy f for a compiled one: (m, 3) directions to (m,) values, f called row by row in a numba loop."""
    f, caller, _ = compiled

    def apply(directions: Float64Array) -> Float64Array:
        directions = np.ascontiguousarray(directions, dtype=np.float64)
        out = np.empty(len(directions))
        _apply_rows(f, caller, directions, out)
        return out

    return apply


@njit(**_OPTIONS)
def _apply_rows(f, caller, directions, out):
    buffer = np.empty(3)
    for i in range(len(directions)):
        out[i] = caller(f, directions[i, 0], directions[i, 1], directions[i, 2], buffer)


_ARGUMENT = -1  # the kind of a user's f: an argument of the kernel, called as f(x, y, z) or f(w) (the *vector* cell)


def _chunk_kernel(kind, params, chain, code, vector, cache):
    """The fused kernel of integrands of *kind* with constants *params* and of map *code* (closure cells:
    constants to numba); kind _ARGUMENT: of the argument f, f(w) if *vector* else f(x, y, z) (a cell too,
    so that numba inlines the call and LLVM then f: with the caller passed as an argument the call was
    opaque and the batch loop of a polynomial f ran 2.8x slower, measured), not cacheable on disk (see the
    module's docstring)."""

    @njit(cache=cache, **_OPTIONS)
    def chunk_statistics(
        f, source_kind, seed_words, side, uv, first_point, m, uniform, weights, count, c_lo, c_hi, out
    ):  # pragma: no cover - compiled by numba
        # out[c] = (orbits, sum of orbit estimates, sum of squared deviations) of chunk c, the
        # orbits first_point + c CHUNK ... (+ CHUNK - 1) of the replicate, for c_lo <= c < c_hi (one part).
        # f: the integrand for kind _ARGUMENT, else an unused zero.
        start = pcg64_seeded(seed_words)
        images = weights.shape[1] // 3
        area = SPHERE_AREA if count == _SPHERE_ORBIT else HEMISPHERE_AREA
        for c in range(c_lo, c_hi):
            lo = c * CHUNK
            hi = min(m, lo + CHUNK)
            stream = pcg64_advanced(start, 2 * (first_point + lo))
            u = np.full(BATCH, 0.5)
            v = np.full(BATCH, 0.5)
            base = np.empty((3, BATCH))
            sums = np.empty(BATCH)
            estimates = np.empty(BATCH)
            buffer = np.empty(3)
            orbits, total, m2 = 0.0, 0.0, 0.0
            for first in range(lo, hi, BATCH):
                b = min(BATCH, hi - first)
                for j in range(b):
                    if source_kind == _GIVEN:
                        u[j] = uv[first + j, 0]
                        v[j] = uv[first + j, 1]
                    else:
                        ju = pcg64_random(stream)
                        jv = pcg64_random(stream)
                        if source_kind == _RANDOM:
                            u[j], v[j] = ju, jv
                        else:  # as BasePoints.take: (corner + jitter) / side
                            cell = first_point + first + j
                            u[j] = (cell // side + ju) / side
                            v[j] = (cell % side + jv) / side
                map_batch(u, v, code, base)  # inlined in numba's IR: the other maps pruned
                for j in range(BATCH):
                    sums[j] = 0.0
                for k in range(images):
                    w00, w01, w02 = weights[0, 3 * k], weights[0, 3 * k + 1], weights[0, 3 * k + 2]
                    w10, w11, w12 = weights[1, 3 * k], weights[1, 3 * k + 1], weights[1, 3 * k + 2]
                    w20, w21, w22 = weights[2, 3 * k], weights[2, 3 * k + 1], weights[2, 3 * k + 2]
                    for j in range(BATCH):  # whole batches (stale lanes are finite points, ignored): vectorisable
                        x, y, z = base[0, j], base[1, j], base[2, j]
                        wx = x * w00 + y * w10 + z * w20
                        wy = x * w01 + y * w11 + z * w21
                        wz = x * w02 + y * w12 + z * w22
                        # f at (wx, wy, wz).  The branches are on cells, so numba prunes them in this
                        # function's IR before it inlines the calls: a user's f never copies the suite's
                        # formulas (spec_value) into its kernel only to drop them (~0.3 s of each compile).
                        if kind == _ARGUMENT:
                            if vector:
                                sums[j] += call_vector(f, wx, wy, wz, buffer)
                            else:
                                sums[j] += call_xyz(f, wx, wy, wz, buffer)
                        else:
                            sums[j] += spec_value(kind, params, chain, wx, wy, wz)
                batch_total = 0.0
                for j in range(b):
                    weight = area if uniform else count / triangle_density(base[0, j], base[1, j], base[2, j], code)
                    estimates[j] = (sums[j] / count) * weight
                    batch_total += estimates[j]
                batch_mean = batch_total / b
                batch_m2 = 0.0
                for j in range(b):
                    d = estimates[j] - batch_mean
                    batch_m2 += d * d
                if orbits == 0.0:
                    m2 = batch_m2
                else:
                    delta = batch_mean - total / orbits
                    m2 += batch_m2 + delta * delta * orbits * b / (orbits + b)
                orbits += b
                total += batch_total
            out[c, 0] = orbits
            out[c, 1] = total
            out[c, 2] = m2

    return route(chunk_statistics)  # made per integrand: its first compile interruptible too (_threads)


_kernels_lock = threading.Lock()
_generic_kernels: dict[tuple[int, bool], Any] = {}  # (map code, f(w)?) -> the kernel of a user's f, compiled per f
_specialised_kernels: dict[tuple[tuple[int, tuple[float, ...], Any], int], Any] = {}
_cache_checked = False


def specialised_kernels() -> list[Any]:
    """The disk-cached kernels made in this process, in order (their ``stats`` show cache hits)."""
    with _kernels_lock:
        return list(_specialised_kernels.values())


def _kernel(spec: tuple[int, tuple[float, ...], Any] | None, code: int, caller: Any) -> Any:
    """The fused kernel of map *code* for a user's f called by *caller* (*spec* None: f an argument,
    compiled per f) or the disk-cached one of the suite's integrands of *spec*; each made once per process."""
    global _cache_checked
    with _kernels_lock:
        if spec is None:
            vector = caller is call_vector
            kernel = _generic_kernels.get((code, vector))
            if kernel is None:
                kernel = _generic_kernels[code, vector] = _chunk_kernel(
                    _ARGUMENT, (0.0,), no_chain, code, vector, False
                )
            return kernel
        if not _cache_checked:  # before the first cached kernel of this module runs
            invalidate_if_changed(_merge_chunks)
            _cache_checked = True
        kernel = _specialised_kernels.get((spec, code))
        if kernel is None:
            kernel = _specialised_kernels[spec, code] = _chunk_kernel(spec[0], spec[1], spec[2], code, False, True)
        return kernel


@njit(cache=True, **_OPTIONS)
def _merge_chunks(chunks, per_block, out):
    # Chunks to blocks, in order, with symsphere._integration.combine's update.
    for block in range(out.shape[0]):
        first = block * per_block
        count, total, m2 = chunks[first, 0], chunks[first, 1], chunks[first, 2]
        for c in range(first + 1, min(first + per_block, chunks.shape[0])):
            n_b, sum_b, m2_b = chunks[c, 0], chunks[c, 1], chunks[c, 2]
            delta = sum_b / n_b - total / count
            m2 = m2 + m2_b + delta * delta * count * n_b / (count + n_b)
            count, total = count + n_b, total + sum_b
        out[block, 0], out[block, 1], out[block, 2] = count, total, m2


_IDENTITY = np.eye(3)


def _part_arguments(arguments: tuple[Any, ...], chunks: Float64Array, parts: int, index: int) -> tuple[Any, ...]:
    """The kernel's arguments for part *index* of *parts*: chunks ``lo ... hi - 1`` of *chunks*."""
    return (*arguments, len(chunks) * index // parts, len(chunks) * (index + 1) // parts, chunks)


def fused_partials(
    compiled: Compiled,
    source: BasePoints,
    orbits: int,
    first_block: int,
    stop_block: int,
    method: MapMethod,
    count: int,
    basis: Float64Array | None,
    uniform: bool,
) -> list[tuple[int, Float64Array, Float64Array]]:
    """Block partials (orbits, sum, M2) of blocks ``first_block ... stop_block - 1`` of a replicate of
    *orbits* base points, as :func:`symsphere._integration.block_partial` gives them (to rounding)."""
    prepare_kernels()
    f, caller, spec = compiled
    kernel = _kernel(spec, METHOD_CODES[method], caller)
    if spec is not None:
        f = 0  # compiled into the kernel: the argument is unused
    weights = rotated_weights(_IDENTITY if basis is None else np.ascontiguousarray(basis, dtype=np.float64), count)
    kind = {"random": _RANDOM, "stratified": _STRATIFIED}.get(source.kind, _GIVEN)
    seed_words = source.seed_words if source.seed_words is not None else np.zeros(4, dtype=np.uint64)
    side = int(round(np.sqrt(source.total))) if kind == _STRATIFIED else 1
    partials: list[tuple[int, Float64Array, Float64Array]] = []
    for segment in range(first_block, stop_block, _SEGMENT_BLOCKS):
        start = segment * BLOCK
        stop = min(min(segment + _SEGMENT_BLOCKS, stop_block) * BLOCK, orbits)
        m = stop - start
        uv = np.ascontiguousarray(source.take(start, stop)) if kind == _GIVEN else np.empty((0, 2))
        chunks = np.empty(((m + CHUNK - 1) // CHUNK, 3))
        parts = max(1, min(get_num_threads(), len(chunks)))
        arguments = (f, kind, seed_words, side, uv, start, m, uniform, weights, count)
        run_kernel(kernel, functools.partial(_part_arguments, arguments, chunks, parts), parts)
        blocks = np.empty(((m + BLOCK - 1) // BLOCK, 3))
        _merge_chunks(chunks, BLOCK // CHUNK, blocks)
        if not np.all(np.isfinite(blocks)):
            bad = int(np.flatnonzero(~np.all(np.isfinite(blocks), axis=1))[0])
            raise NonFiniteBlock("'f' returned non-finite values, or values whose sum overflows", segment + bad)
        partials += [(int(row[0]), row[1:2].copy(), row[2:3].copy()) for row in blocks]
    return partials


route_compiles(globals())  # the first compile of each numba function here: interruptible (_threads)
