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

The kernel takes f as an argument, so numba compiles it once per integrand and process (a few
seconds), and cannot cache it on disk: a function-typed argument is typed by the dispatcher
object, which differs in every process, so a cached entry never matches (measured: saved, never
hit).  An integrand whose kernel was generated from source (the suite's, see
:mod:`symsphere.integrands`, which sets ``kernel.symsphere_source``) gets a *specialised* kernel
instead: a module file written once into a cache directory (``NUMBA_CACHE_DIR`` or
``$XDG_CACHE_HOME/symsphere``, default ``~/.cache/symsphere``) holding the integrand's function
and this module's ``_chunk_statistics`` with f a global instead of an argument, compiled with
``cache=True``.  Its name is the SHA-256 of its text, and its numba cache is dropped when a file
the kernel inlines changes (:mod:`symsphere._numba_cache`), so a later process loads the machine
code (tens of ms) instead of compiling.  If the directory is not writable the generic kernel runs.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.util
import inspect
import os
import sys
import threading
from pathlib import Path
from typing import Any

import numpy as np
from llvmlite import ir
from numba import njit, prange, types
from numba.extending import intrinsic, is_jitted

from ._kernels import (
    BATCH,
    METHOD_CODES,
    map_batch,
    pcg64_advanced,
    pcg64_random,
    pcg64_seeded,
    prepare_kernels,
    rotated_weights,
    triangle_density,
)
from ._numba_cache import invalidate_if_changed, kernel_dependencies
from ._typing import Float64Array
from .points import BLOCK, BasePoints

__all__ = [
    "CHUNK",
    "Compiled",
    "compiled_integrand",
    "fused_partials",
    "vexp",
    "call_xyz",
    "call_vector",
    "cache_directory",
]

CHUNK = 512
"""Orbits per parallel work unit; BLOCK is a multiple, so chunks never straddle blocks."""
assert BLOCK % CHUNK == 0

_RANDOM, _STRATIFIED, _GIVEN = 0, 1, 2
_SEGMENT_BLOCKS = 64  # given base points (QMC) are taken this many blocks at a time: bounded memory
_OPTIONS = dict(error_model="numpy", nogil=True)


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


Compiled = tuple[Any, Any, "str | None"]
"""(the numba function, the caller that adapts its signature: call_xyz or call_vector, the
function's generated source when it has one: the suite's integrands, cached specialised kernels)."""


def compiled_integrand(f: object) -> Compiled | None:
    """(kernel, caller) if *f* is a compiled integrand, else None (the numpy path).

    Compiled: a numba dispatcher of 3 arguments (x, y, z) or of 1 argument (a (3,) array), or
    an object with such a dispatcher as its ``kernel`` attribute (the integrand suite).  The
    function is called once here, at (0, 0, 1), so that a wrong signature or a result that is
    not one real number raises TypeError naming 'f' before any work.
    """
    kernel = getattr(f, "kernel", None) if not is_jitted(f) else f
    if kernel is None or not is_jitted(kernel):
        return None
    source = getattr(kernel, "symsphere_source", None)
    if isinstance(source, str) and source.startswith("def kernel(x, y, z):"):
        return kernel, call_xyz, source  # generated by symsphere.integrands (tested there): no probe, no compilation
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


@njit(parallel=True, **_OPTIONS)
def _chunk_statistics(f, caller, source_kind, seed_words, side, uv, first_point, m, code, uniform, weights, count, out):
    # out[c] = (orbits, sum of orbit estimates, sum of squared deviations) of chunk c, the
    # orbits first_point + c CHUNK ... (+ CHUNK - 1) of the replicate.
    start = pcg64_seeded(seed_words)
    images = weights.shape[1] // 3
    area = 4.0 * np.pi if count == 48 else 2.0 * np.pi
    for c in prange(out.shape[0]):
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
            map_batch(u, v, code, base)
            for j in range(BATCH):
                sums[j] = 0.0
            for k in range(images):
                w00, w01, w02 = weights[0, 3 * k], weights[0, 3 * k + 1], weights[0, 3 * k + 2]
                w10, w11, w12 = weights[1, 3 * k], weights[1, 3 * k + 1], weights[1, 3 * k + 2]
                w20, w21, w22 = weights[2, 3 * k], weights[2, 3 * k + 1], weights[2, 3 * k + 2]
                for j in range(BATCH):  # whole batches (stale lanes are finite points, ignored): vectorisable
                    x, y, z = base[0, j], base[1, j], base[2, j]
                    sums[j] += caller(
                        f, x * w00 + y * w10 + z * w20, x * w01 + y * w11 + z * w21, x * w02 + y * w12 + z * w22, buffer
                    )
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


def fused_partials(
    compiled: Compiled,
    source: BasePoints,
    orbits: int,
    first_block: int,
    stop_block: int,
    method: str,
    count: int,
    basis: Float64Array | None,
    uniform: bool,
) -> list[tuple[int, Float64Array, Float64Array]]:
    """Block partials (orbits, sum, M2) of blocks ``first_block ... stop_block - 1`` of a replicate of
    *orbits* base points, as :func:`symsphere._integration.block_partial` gives them (to rounding)."""
    prepare_kernels()
    kernel, caller, source_text = compiled
    specialised = _specialised(source_text) if source_text is not None else None
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
        arguments = (kind, seed_words, side, uv, start, m, METHOD_CODES[method], uniform, weights, count, chunks)
        if specialised is not None:
            specialised(*arguments)
        else:
            _chunk_statistics(kernel, caller, *arguments)
        blocks = np.empty(((m + BLOCK - 1) // BLOCK, 3))
        _merge_chunks(chunks, BLOCK // CHUNK, blocks)
        if not np.all(np.isfinite(blocks)):
            raise ValueError("'f' returned non-finite values")
        partials += [(int(row[0]), row[1:2].copy(), row[2:3].copy()) for row in blocks]
    return partials


# --- specialised kernels of generated integrands, cached on disk ------------------------


def cache_directory() -> Path:
    """Where the specialised kernels' modules are written: ``NUMBA_CACHE_DIR`` if set, else
    ``$XDG_CACHE_HOME/symsphere`` (default ``~/.cache/symsphere``)."""
    numba_dir = os.environ.get("NUMBA_CACHE_DIR")
    if numba_dir:
        return Path(numba_dir) / "symsphere-fused"
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "symsphere" / "fused"


_specialised_lock = threading.Lock()
_specialised_kernels: dict[str, Any] = {}


def _specialised_source(function_source: str) -> str:
    """The module text: the integrand as ``kernel``, and ``_chunk_statistics`` calling it as a global."""
    template = inspect.getsource(_chunk_statistics.py_func)
    header = "def _chunk_statistics(f, caller, source_kind,"
    call = "sums[j] += caller(\n                        f, "
    assert template.count(header) == 1 and template.count(call) == 1, "the template of _chunk_statistics changed"
    body = template[template.index(header) :].replace(header, "def chunk_statistics(source_kind,")
    body = body.replace(call, "sums[j] += kernel(\n                        ").replace(
        ", buffer\n                    )", "\n                    )"
    )
    assert "caller" not in body and "buffer\n" not in body
    return "\n".join(
        [
            '"""A fused integration kernel for one integrand. GENERATED by symsphere._fused: do not edit."""',
            "import numpy as np",
            "from numba import njit, prange",
            "from symsphere._fused import vexp",
            "from symsphere._kernels import BATCH, map_batch, pcg64_advanced, pcg64_random, pcg64_seeded, triangle_density",
            "",
            f"CHUNK = {CHUNK}",
            f"_RANDOM, _STRATIFIED, _GIVEN = {_RANDOM}, {_STRATIFIED}, {_GIVEN}",
            "",
            '@njit(cache=True, error_model="numpy", nogil=True)',
            function_source.rstrip(),
            "",
            "",
            '@njit(parallel=True, cache=True, error_model="numpy", nogil=True)',
            body.rstrip(),
            "",
        ]
    )


def _specialised(function_source: str) -> Any:
    """The cached specialised kernel of an integrand generated from *function_source*, or None."""
    text = _specialised_source(function_source)
    name = "symsphere_fused_" + hashlib.sha256(text.encode()).hexdigest()[:24]
    with _specialised_lock:
        if name in _specialised_kernels:
            return _specialised_kernels[name]
        kernel = None
        with contextlib.suppress(OSError):  # not writable: the generic kernel
            folder = cache_directory()
            folder.mkdir(parents=True, exist_ok=True)
            path = folder / f"{name}.py"
            if not (path.is_file() and path.read_text() == text):
                partial = path.with_suffix(f".{os.getpid()}.tmp")
                partial.write_text(text)
                partial.replace(path)  # atomic: concurrent processes write the same text
            spec = importlib.util.spec_from_file_location(name, path)
            assert spec is not None and spec.loader is not None
            module = importlib.util.module_from_spec(spec)
            sys.modules[name] = module
            spec.loader.exec_module(module)
            kernel = module.chunk_statistics
            invalidate_if_changed(kernel, kernel_dependencies(_chunk_statistics))
        _specialised_kernels[name] = kernel
        return kernel


# --- a vectorisable exp, for integrands --------------------------------------------------


@intrinsic
def _float_bits(typingctx, x):
    """The bits of a float64 as an int64 (a bitcast: no instruction)."""

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(64))

    return types.int64(types.float64), codegen


@intrinsic
def _bits_float(typingctx, i):
    """The float64 whose bits are the int64 *i*."""

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.DoubleType())

    return types.float64(types.int64), codegen


_SHIFTER = 6755399441055744.0  # 1.5 * 2**52: adding it rounds to an integer kept in the low bits
_LN2_HI = 0.693145751953125  # ln 2 split for an exact k * ln2_hi (Cody & Waite)
_LN2_LO = 1.42860682030941723212e-6
_INV_LN2 = 1.4426950408889634


@njit(error_model="numpy", nogil=True)
def vexp(t):
    """exp(t) without a libm call, so that LLVM can vectorise loops around it.

    t = k ln 2 + r with |r| <= ln2 / 2 (Cody-Waite), exp(r) by its Taylor polynomial to r^13
    (remainder below 4e-18), 2^k put into the exponent bits.  Within 1 ulp of numpy's exp on
    [-708, 709] (tested); t is clamped to that range (no inf, no NaN for finite t).
    """
    t = min(max(t, -708.0), 709.0)
    shifted = t * _INV_LN2 + _SHIFTER
    k = shifted - _SHIFTER
    r = (t - k * _LN2_HI) - k * _LN2_LO
    p = 1.0 / 6227020800.0
    p = p * r + 1.0 / 479001600.0
    p = p * r + 1.0 / 39916800.0
    p = p * r + 1.0 / 3628800.0
    p = p * r + 1.0 / 362880.0
    p = p * r + 1.0 / 40320.0
    p = p * r + 1.0 / 5040.0
    p = p * r + 1.0 / 720.0
    p = p * r + 1.0 / 120.0
    p = p * r + 1.0 / 24.0
    p = p * r + 1.0 / 6.0
    p = p * r + 0.5
    p = p * r + 1.0
    p = p * r + 1.0
    scale = _bits_float((_float_bits(shifted) + 1023) << 52)  # 2^k: k sits in the low bits of shifted
    return p * scale
