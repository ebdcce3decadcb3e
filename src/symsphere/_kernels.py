"""numba kernels: (draws +) map + orbit (+ frame) fused in one pass, one part of the points per thread.

The map formulas are the elementwise functions of :func:`symsphere.warps.square_to_triangle`
(``register_jitable``), the orbit stores (:mod:`symsphere._vector_stores`) permute by the tables of
:mod:`symsphere.symmetry`, and about a normal a weights table is built from the
same tables, so nothing here restates a formula.  The numpy path
(``warps.Warp.points`` + ``symmetry.orbit`` + ``frames.to_world``) is the
reference the tests compare against.  Random base points are drawn inside the
kernel from numpy's PCG64 stream (:mod:`symsphere._random.pcg64`): each part starts
from the state numpy's own ``PCG64.advance`` gives and steps it as numpy does.

Compile time.  A kernel is specialised at the Python level by (point source,
map, store): :func:`_fill_kernel` makes one small serial function per case, the
case's codes being constants of the function (closure cells, so that numba prunes
the other cases' branches before typing them and caches each case on its own),
and compiles it lazily per output dtype, cached on disk (``cache=True``).  A call
compiles only its own case: ~1-2 s on an empty cache instead of one kernel holding
every map and store.  The parts run on the threads of :mod:`symsphere._threads`
(the kernels release the GIL), not in a numba ``prange``, whose parallel
lowering more than doubled each kernel's compile time.  docs/results/cold-start.md has
the measurements.
"""

from __future__ import annotations

import ctypes
import functools
import mmap
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, cast

import numpy as np
import numpy.typing as npt
from numba import get_num_threads, njit
from numba.extending import register_jitable

from ._numba_cache import invalidate_if_changed
from ._random.pcg64 import pcg64_random, pcg64_state
from ._threads import route_compiles, run_kernel, start_threads
from ._typing import Float64Array, FloatArray, MapMethod
from ._vector_stores import LINE as _LINE
from ._vector_stores import (
    aligned_empty,
    store_fence,
    store_hemisphere_orbit,
    store_rotated_hemisphere,
    store_sphere_orbit,
    stream_rows,
)
from .symmetry import SIGNS, SOURCES, orbit_size
from .warps._triangle import METHODS, triangle_warp  # the module itself: the kernels inline only its formulas

if TYPE_CHECKING:
    from .points import BasePoints

__all__ = [
    "Plan",
    "fill",
    "BATCH",
    "METHOD_CODES",
    "map_batch",
    "rotated_weights",
    "prepare_kernels",
    "fill_orbits",
    "RandomPoints",
    "part_bounds",
    "part_range",
    "part_count",
    "triangle_point",
    "triangle_density",
    "orbit_member",
]

METHOD_CODES = {name: code for code, name in enumerate(METHODS)}
assert METHOD_CODES == {"equal_area": 0, "paper1": 1, "paper2": 2}
# The maps' own elementwise formulas (register_jitable in symsphere.warps), taken from their records.
_EQUAL_AREA, _PAPER1, _PAPER2 = (triangle_warp(name) for name in METHODS)
assert all(w.point is not None and w.density is not None for w in (_EQUAL_AREA, _PAPER1, _PAPER2))
_equal_area_point, _paper1_point, _paper2_point = (
    cast(Callable[..., Any], w.point) for w in (_EQUAL_AREA, _PAPER1, _PAPER2)
)
_equal_area_density, _paper1_density, _paper2_density = (
    cast(Callable[..., Any], w.density) for w in (_EQUAL_AREA, _PAPER1, _PAPER2)
)

_OPTIONS: dict[str, Any] = dict(cache=True, error_model="numpy", nogil=True)


@njit(inline="always")  # numba-IR inlining: a constant *code* of the caller prunes the other maps
def triangle_point(u, v, code):
    """The map *code* of METHOD_CODES at (u, v): a point (x, y, z) of T0."""
    if code == 0:
        return _equal_area_point(u, v)
    if code == 1:
        return _paper1_point(u, v)
    return _paper2_point(u, v)


@njit(inline="always")
def triangle_density(x, y, z, code):
    """The density of map *code* at a unit direction (x, y, z); 0 outside T0."""
    if code == 0:
        return _equal_area_density(x, y, z)
    if code == 1:
        return _paper1_density(x, y, z)
    return _paper2_density(x, y, z)


_SOURCES = SOURCES.copy()
_SIGNS = SIGNS.copy()


@register_jitable
def orbit_member(x, y, z, k):
    """Image k of (x, y, z): ``(x, y, z) @ SPHERE_MAPS[k]`` (table-driven, for one image)."""
    base = (x, y, z)
    return (
        _SIGNS[k, 0] * base[_SOURCES[k, 0]],
        _SIGNS[k, 1] * base[_SOURCES[k, 1]],
        _SIGNS[k, 2] * base[_SOURCES[k, 2]],
    )


# Base points are handled in batches of _BATCH: first the map for the whole batch, into
# arrays (structure of arrays), then the orbit stores.  The equal-area map has no libm call
# (its sine is a polynomial), so LLVM vectorises the batch loop; the stores of one point no
# longer wait for the next point's dependent chain of square roots and divisions.
_BATCH = 16
_SPHERE, _HEMISPHERE, _HEMISPHERE_ROTATED = 0, 1, 2
_SPHERE_ORBIT, _HEMISPHERE_ORBIT = orbit_size("sphere"), orbit_size("hemisphere")


@njit(inline="always")
def _map_batch(u, v, code, base):
    """base[:, j] = the point of T0 of map *code* at (u[j], v[j]), for all j < _BATCH.

    Inlined in numba's IR: with *code* a constant of the caller (a specialised kernel), numba
    prunes the other maps before typing them.
    """
    # One loop per map, so the default one is branch-free (vectorisable).
    if code == 0:
        for j in range(_BATCH):
            base[0, j], base[1, j], base[2, j] = _equal_area_point(u[j], v[j])
    elif code == 1:
        for j in range(_BATCH):
            base[0, j], base[1, j], base[2, j] = _paper1_point(u[j], v[j])
    else:
        for j in range(_BATCH):
            base[0, j], base[1, j], base[2, j] = _paper2_point(u[j], v[j])


# Rows about a normal are kept on or above its plane where they are stored, not in a pass over the
# output afterwards.  Image k's dot product with the normal is its local third coordinate, one of the
# base point's x, y, z (Table 1 keeps the third coordinate's sign), up to rounding: the stored row's
# dot product is that coordinate within ~1e-6 (float32), so an orbit whose base coordinates are all
# >= _NEAR_PLANE has no row near the plane and is not checked.  The others (rare: a base point within
# 2**-12 of an edge of T0) check every image and move the few that fail.
_NEAR_PLANE = 2.0**-12
_MARGIN = 4 * float(np.finfo(np.float64).eps)


@register_jitable
def _is_above(x, y, z, normal, slack):
    """Whether the stored row (x, y, z) is safely on or above the plane of the unit *normal* (float64).

    Passes if its float64 dot product d . n is >= _MARGIN + slack * sum |d_i n_i|, with *slack* 4 eps of
    the row's dtype: then d . n' >= 0 for the normal as given or scaled to 1 (n' = s n), both in
    float64 and rounded to the row's dtype, however the three-term sum is ordered (with or without
    FMA): the normal's rounding (1 ulp), the products and sums (gamma_3 = 3 u) and this check's own
    float64 sum stay below 4 eps = 8 u of sum |d_i n_i|, and _MARGIN (4 ulps of float64) covers a
    row whose products are all ~0.
    """
    a = np.float64(x) * normal[0]
    b = np.float64(y) * normal[1]
    c = np.float64(z) * normal[2]
    return a + b + c >= _MARGIN + slack * (abs(a) + abs(b) + abs(c))


@register_jitable
def _keep_above(rows, i, normal):
    """Move the images in *rows*[i] (3 count, the output dtype) that fail :func:`_is_above` onto the
    upper side of the plane of *normal*, in place.

    A direction on the equator of the local hemisphere (z = 0), rotated onto the normal and rounded
    to the output dtype, can come out with d . n ~ -1e-8 in float32: its pdf counts it as on the
    plane, but a ray spawned from it enters the surface.  Such a row is projected onto the plane in
    float64 (if below it), nudged up by 1, 2, 4, ... 64 ulps of the dtype along the normal and
    renormalised, until it passes.  Only rows within rounding of the plane are moved (by a few ulps),
    so the density is unchanged.
    """
    eps = np.finfo(rows.dtype).eps
    slack = 4.0 * eps
    for k in range(rows.shape[1] // 3):
        if _is_above(rows[i, 3 * k], rows[i, 3 * k + 1], rows[i, 3 * k + 2], normal, slack):
            continue
        x, y, z = np.float64(rows[i, 3 * k]), np.float64(rows[i, 3 * k + 1]), np.float64(rows[i, 3 * k + 2])
        below = min(x * normal[0] + y * normal[1] + z * normal[2], 0.0)
        x, y, z = x - below * normal[0], y - below * normal[1], z - below * normal[2]
        lift = eps
        for _ in range(7):
            a = x + lift * normal[0]
            b = y + lift * normal[1]
            c = z + lift * normal[2]
            norm = np.sqrt(a * a + b * b + c * c)
            rows[i, 3 * k], rows[i, 3 * k + 1], rows[i, 3 * k + 2] = a / norm, b / norm, c / norm
            if _is_above(rows[i, 3 * k], rows[i, 3 * k + 1], rows[i, 3 * k + 2], normal, slack):
                break
            lift *= 2.0


@register_jitable
def _stage_on_lines(count, columns, dtype):
    """An empty (count, columns) array of *dtype* whose first element starts a 64-byte line.

    The orbit stores write it in 64-byte vectors (a batch of _BATCH orbits is whole lines): a store
    that spans two lines costs two, and numba's arrays start on 32 bytes, not always 64.  Its copy out
    (:func:`~symsphere._vector_stores.stream_rows`) then loads across lines where the output starts
    within one (numpy's large arrays: 16 bytes in), which measured cheaper than the stores doing so.
    """
    return aligned_empty(count * columns, dtype, _LINE).reshape((count, columns))


@register_jitable
def _copy_members(scratch, tail, offset):
    """tail[i] = member ``(offset + i) % count`` of the orbit stored in *scratch* (1, 3 count)."""
    count = scratch.shape[1] // 3
    for i in range(tail.shape[0]):
        k = (offset + i) % count
        for l in range(3):
            tail[i, l] = scratch[0, 3 * k + l]


def _rotated_weights(basis, count):
    """W (3, 3 count) with image k of p = p @ M_k @ basis = p @ W[:, 3k:3k+3] (float64, exact).

    Kept for the last 16 bases (the kernels only read them): a call about a normal follows the write of
    its last output, which leaves numpy's code out of the caches, and building them took 0.1-0.3 ms a
    call there against ~30 us to find them (docs/results/write-limit.md).
    """
    assert basis.dtype == np.float64 and basis.shape == (3, 3)  # the key is its 72 bytes
    return _weights_of(basis.tobytes(), count)


@functools.lru_cache(maxsize=16)
def _weights_of(basis_bytes, count):
    """M_k moves coordinate SOURCES[k, l] to place l with sign SIGNS[k, l], so row SOURCES[k, l] of
    M_k @ basis is SIGNS[k, l] * basis[l]: W[SOURCES[k, l], 3k + l'] = SIGNS[k, l] * basis[l, l'] (a
    gather and a sign).  Each row (72 values, 9 lines) starts a cache line: the rotated store loads
    them in 64-byte vectors, 27 per orbit, and one spanning two lines costs two (float32 rows about a
    normal took ~18 % more CPU with numpy's 16 bytes into a line, docs/results/write-limit.md)."""
    index, sign = np.empty((3, 3 * count), dtype=np.intp), np.empty((3, 3 * count))
    rows, columns = _SOURCES[:count, :, None], 3 * np.arange(count)[:, None, None] + np.arange(3)
    index[rows, columns] = 3 * np.arange(3)[None, :, None] + np.arange(3)
    sign[rows, columns] = _SIGNS[:count, :, None]
    weights = aligned_empty(9 * count, np.float64, _LINE)
    np.multiply(np.frombuffer(basis_bytes).take(index.ravel()), sign.ravel(), out=weights)
    return weights.reshape(3, 3 * count)


@register_jitable
def part_range(m, parts, part):
    """Points ``lo ... hi - 1`` of part *part* when m points are split into *parts* stretches of
    whole batches (fewer parts than asked if there are fewer batches: see :func:`part_count`)."""
    batches = (m + _BATCH - 1) // _BATCH
    lo = min(m, (batches * part // parts) * _BATCH)
    hi = min(m, (batches * (part + 1) // parts) * _BATCH)
    return lo, hi


@register_jitable
def part_count(m, parts):
    """How many parts m points are split into: *parts*, but at most one per batch, at least one."""
    return max(1, min(parts, (m + _BATCH - 1) // _BATCH))


_GIVEN, _RANDOM = 0, 1


@functools.cache
def _fill_kernel(source: int, code: int, kind: int, streamed: bool = False) -> Any:
    """The serial kernel of one case: base points given (*source* = _GIVEN) or drawn (_RANDOM), map
    *code*, store *kind*.  It fills points ``lo ... hi - 1`` of the call (one part).

    *source*, *code* and *kind* are closure cells, hence constants to numba: the branches of
    the other cases are pruned before typing, and numba's cache keys the case by their values
    (numba hashes a closure's cell contents into the cache index), so every case is cached on
    its own, and a process compiles only the cases it uses.

    The output is *rows* (whole, 3 count): the whole orbits, one per row, and *tail* (rest, 3):
    if rest > 0, the last of the m = whole + 1 points has its orbit cut to rest members from
    *offset* on, in the same call (stored whole by the same store as every other orbit, so the
    members are bit for bit those of a whole orbit, then copied).  Given points are *points* (m, 2); random ones
    are drawn from *points*, the PCG64 stream at point *lo* (uint64[4], :func:`~symsphere._random.pcg64.pcg64_state`),
    u then v per point; the next batch's points are drawn between the current batch's orbit
    stores, so that the generator's dependent chain of 128-bit multiplications overlaps the
    stores instead of following them.

    *streamed* (a closure cell too): each batch's orbits are stored into a stage of two batches (in
    L1) and copied out non-temporally (:func:`~symsphere._vector_stores.stream_rows`) while the next
    batch is computed, one batch late, so that the copy's loads find the stage's stores written
    (a load that spans two stores still in the store buffer waits for both); the same values, written
    without reading the output's lines first (:func:`_streams` says when).
    """

    @njit(**_OPTIONS)
    def fill(points, lo, hi, weights, normal, rows, tail, offset):  # pragma: no cover - compiled by numba
        # The branches on source and kind are at this function's top level and the map's in
        # _map_batch, inlined in numba's IR: numba prunes them all.  The stores are intrinsics
        # (symsphere._vector_stores): a few vector instructions in place, no call per orbit.
        whole = rows.shape[0]
        u = np.empty(_BATCH)
        v = np.empty(_BATCH)
        for j in range(_BATCH):  # a partial batch maps these lanes too (np.full: one more overload to compile)
            u[j] = 0.5
            v[j] = 0.5
        base = np.empty((3, _BATCH))
        scratch = np.empty((1, rows.shape[1]), dtype=tail.dtype)  # the cut orbit, stored whole
        stage = _stage_on_lines(2 * _BATCH if streamed else 0, rows.shape[1], tail.dtype)
        target = stage if streamed else rows  # once: a reference taken per orbit costs a call (NRT_incref)
        half = 0
        pending = 0
        pending_first = 0
        if source == _RANDOM:
            for j in range(min(_BATCH, hi - lo)):
                u[j] = pcg64_random(points)
                v[j] = pcg64_random(points)
        for first in range(lo, hi, _BATCH):
            stop = min(first + _BATCH, hi)
            if source == _GIVEN:
                for j in range(stop - first):
                    u[j] = points[first + j, 0]
                    v[j] = points[first + j, 1]
            _map_batch(u, v, code, base)  # inlined in numba's IR: the other maps pruned
            upcoming = min(_BATCH, hi - stop)
            for j in range(min(stop, whole) - first):
                at = half * _BATCH + j if streamed else first + j
                if kind == _SPHERE:
                    store_sphere_orbit(base[0, j], base[1, j], base[2, j], target, at)
                elif kind == _HEMISPHERE:
                    store_hemisphere_orbit(base[0, j], base[1, j], base[2, j], target, at)
                else:
                    store_rotated_hemisphere(base[0, j], base[1, j], base[2, j], target, at, weights)
                    if normal.shape[0] and min(base[0, j], base[1, j], base[2, j]) < _NEAR_PLANE:
                        _keep_above(target, at, normal)
                if source == _RANDOM and j < upcoming:
                    u[j] = pcg64_random(points)
                    v[j] = pcg64_random(points)
            if streamed:  # the batch before this one: its stores have left the store buffer
                stream_rows(stage, (1 - half) * _BATCH, rows, pending_first, pending)
                half, pending, pending_first = 1 - half, min(stop, whole) - first, first
            if stop > whole:  # the last point (of the last part), its orbit cut: stored whole, then copied
                j = whole - first
                if kind == _SPHERE:
                    store_sphere_orbit(base[0, j], base[1, j], base[2, j], scratch, 0)
                elif kind == _HEMISPHERE:
                    store_hemisphere_orbit(base[0, j], base[1, j], base[2, j], scratch, 0)
                else:
                    store_rotated_hemisphere(base[0, j], base[1, j], base[2, j], scratch, 0, weights)
                    if normal.shape[0] and min(base[0, j], base[1, j], base[2, j]) < _NEAR_PLANE:
                        _keep_above(scratch, 0, normal)
                _copy_members(scratch, tail, offset)
        if streamed:
            stream_rows(stage, (1 - half) * _BATCH, rows, pending_first, pending)
            store_fence()

    return fill


_ready = False


def _prepare_kernels():
    """Before the first kernel runs: drop a stale disk cache, start the threads (nothing at import)."""
    global _ready
    if not _ready:
        invalidate_if_changed(_fill_kernel(_GIVEN, 0, _SPHERE))  # the module's cache directory: every case's entries
        start_threads()
        _ready = True


def _run(source, method, count, basis, out, m, parts, part_input, offset, above):
    """Run the case's kernel over the parts of m points (the entry of :func:`fill_orbits`, which takes
    the run's facts one by one instead of a :class:`Plan`)."""
    _prepare_kernels()
    kind, weights = _store_kind(count, basis)
    normal = np.ascontiguousarray(basis[2], dtype=np.float64) if above and kind == _HEMISPHERE_ROTATED else _NO_NORMAL
    _launch(
        _fill_kernel(source, METHOD_CODES[method], kind, _streams(out)),
        weights,
        normal,
        count,
        out,
        m,
        parts,
        part_input,
        offset,
    )


def _launch(kernel, weights, normal, count, out, m, parts, part_input, offset):
    """Run *kernel* over the parts of m points, on the threads of symsphere._threads.

    *part_input(lo)* is the kernel's *points* argument for the part starting at point lo.
    """
    rows, tail = _split(out, count)
    parts = part_count(m, parts or _default_parts(m))

    def arguments(index):
        lo, hi = part_range(m, parts, index)
        return part_input(lo), lo, hi, weights, normal, rows, tail, offset

    run_kernel(kernel, arguments, parts)


@dataclass(frozen=True)
class Plan:
    """A run fixed before any work starts: what every kernel call of it needs, built once.

    *source* gives the base points (its ``kind`` says whether the kernel draws them itself:
    ``'random'``), *method* the map onto T0, *count* the orbit size
    (:func:`symsphere.symmetry.orbit_size`), *basis* the frame of the normal or None; the store
    kind, the image weights and the normal the rows are kept above follow from them.
    """

    source: BasePoints
    method: MapMethod
    count: int
    basis: Float64Array | None = None
    kind: int = field(init=False, repr=False, compare=False)
    weights: Float64Array = field(init=False, repr=False, compare=False)
    normal: Float64Array = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        kind, weights = _store_kind(self.count, self.basis)
        basis = self.basis
        normal = _NO_NORMAL if basis is None else np.ascontiguousarray(basis[2], dtype=np.float64)
        object.__setattr__(self, "kind", kind)
        object.__setattr__(self, "weights", weights)
        object.__setattr__(self, "normal", normal)


def fill(plan: Plan, start: int, stop: int, out: FloatArray, offset: int = 0, parts: int = 0) -> FloatArray:
    """Write the orbits of base points ``start ... stop - 1`` of *plan* into *out*: one kernel call.

    As :func:`fill_orbits` with ``above=True``: if *out* has fewer rows than
    ``(stop - start) * count``, the last orbit is cut to its members ``(offset + i) % count``.
    Random points are drawn inside the kernel (point i: draws 2i, 2i + 1 of the source's PCG64
    stream); other sources' points are taken from *plan.source*.
    """
    _prepare_kernels()
    source = plan.source
    part_input: Callable[[int], npt.NDArray[Any]]
    if source.kind == "random":
        assert source.seed_words is not None  # random sources always have the stream's seed
        part_input = RandomPoints(source.seed_words, start, stop - start).part_input
        kernel = _fill_kernel(_RANDOM, METHOD_CODES[plan.method], plan.kind, _streams(out))
    else:
        uv = np.ascontiguousarray(source.take(start, stop), dtype=np.float64)

        def part_input(lo: int) -> npt.NDArray[Any]:
            return uv

        kernel = _fill_kernel(_GIVEN, METHOD_CODES[plan.method], plan.kind, _streams(out))
    _launch(kernel, plan.weights, plan.normal, plan.count, out, stop - start, parts, part_input, offset)
    return out


@dataclass(frozen=True)
class RandomPoints:
    """The random base points ``first ... first + m - 1``: point i is draws 2i, 2i + 1 of numpy's
    ``PCG64(seed_sequence)``, *seed_words* = ``seed_sequence.generate_state(4, np.uint64)``
    (:attr:`symsphere.points.BasePoints.seed_words`); the kernel draws them itself."""

    seed_words: npt.NDArray[np.unsignedinteger[Any]]
    first: int
    m: int

    def part_input(self, lo: int) -> npt.NDArray[np.uint64]:
        """The kernel's *points* for the part from point ``first + lo`` on: the stream's state there."""
        return pcg64_state(self.seed_words, 2 * (self.first + lo))


def fill_orbits(
    points: FloatArray | RandomPoints,
    method: str,
    count: int,
    basis: Float64Array | None,
    out: FloatArray,
    parts: int = 0,
    offset: int = 0,
    above: bool = False,
) -> FloatArray:
    """Write the orbits of the m base *points* into *out* (m * count, 3): points given as an (m, 2) array
    of (u, v), or :class:`RandomPoints`, which the kernel draws.

    *basis* is None or the (3, 3) frame of :func:`symsphere.frames.frame`
    (hemisphere only).  Trusts its inputs: *out* C-contiguous float32 or float64.  *parts*: how many
    stretches to split the points into (0: numba's thread count, but at most one part per 256 points;
    the output does not depend on it).  If *out* has
    ``(m - 1) * count + rest`` rows, ``0 < rest < count``, the last point's orbit is cut:
    the last *rest* rows are its members ``(offset + i) % count``, ``i < rest``, in the
    same kernel call.  With *above* (and a *basis*), every row is on or above the plane of the
    normal ``basis[2]`` (scaled or not), its dot product with it >= 0 in *out*'s dtype and in float64
    whatever the order of the sum (:func:`_is_above`; moved in the store by :func:`_keep_above`);
    without, the rows are the rotated images as computed.
    """
    if isinstance(points, RandomPoints):
        _run(_RANDOM, method, count, basis, out, points.m, parts, points.part_input, offset, above)
    else:
        uv = np.ascontiguousarray(points, dtype=np.float64)
        _run(_GIVEN, method, count, basis, out, len(uv), parts, lambda lo: uv, offset, above)
    return out


# Fewer points than this per part are not worth a thread hand-off (~20 us): one part of 256 base
# points is 12 288 directions, ~20 us of work.
_MIN_PART = 256


def _default_parts(m):
    return max(1, min(get_num_threads(), m // _MIN_PART))


def _split(out, count):
    """*out*'s whole orbits as rows of 3 count columns, and the rest (the cut orbit's rows, maybe none)."""
    whole = len(out) // count * count
    return out[:whole].reshape(-1, 3 * count), out[whole:]


# The same batch map, batch size and image weights for the fused integration kernels
# (symsphere._fused), which evaluate f where these kernels store directions.
BATCH = _BATCH
map_batch = _map_batch
rotated_weights = _rotated_weights
prepare_kernels = _prepare_kernels


def part_bounds(m, parts=0):
    """The bounds of the parts of the kernels (for benchmarks and tests): an int64 array."""
    _prepare_kernels()
    count = part_count(m, parts or get_num_threads())
    return np.array([part_range(m, count, p)[0] for p in range(count)] + [m], dtype=np.int64)


# Non-temporal stores (symsphere._vector_stores.stream_rows) write a touched output up to ~2x faster
# than plain ones, which read each line first (measured down to 0.6 MB), but a fresh one (np.empty:
# pages the operating system clears at the first write, through the cache) ~1.4-1.7x slower; and an
# output that fits in a core's cache (2 MiB of L2 on the Intel host) is better left there for whoever
# reads it next, so only twice that and more.  docs/results/write-limit.md has the measurements.
STREAM_BYTES = 4 * 2**20
"""Outputs of at least this many bytes whose pages are already in memory are written non-temporally."""
stream_override: bool | None = None
"""True/False: every output written non-temporally / with plain stores (for benchmarks); None: the rule."""
_PAGE = mmap.PAGESIZE
_mincore: Any
try:  # POSIX: which pages of a range are in memory
    _mincore = ctypes.CDLL(None).mincore
    _mincore.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_char_p]
except (AttributeError, OSError, TypeError):  # pragma: no cover - e.g. Windows: plain stores only
    _mincore = None


def _streams(out):
    """Whether the kernel writes *out* with non-temporal stores: large, and its pages already in memory
    (a buffer written before, as ``out=`` usually is).  Its middle and last pages tell: np.empty's
    pages, and a new memmap's, are mapped when first written (a new memmap's last page when made)."""
    if stream_override is not None:
        return stream_override
    if out.nbytes < STREAM_BYTES or _mincore is None:
        return False
    resident = ctypes.create_string_buffer(1)
    for at in (out.nbytes // 2, out.nbytes - 1):
        address = out.ctypes.data + at
        if _mincore(ctypes.c_void_p(address - address % _PAGE), _PAGE, resident) != 0 or not resident.raw[0] & 1:
            return False  # not yet written (or memory mincore does not know): plain stores
    return True


_NO_WEIGHTS = np.zeros((3, 0))
_NO_NORMAL = np.zeros(0)


def _store_kind(count, basis):
    """(kind of store, the image weights: none without a frame)."""
    if basis is None:
        return (_SPHERE if count == _SPHERE_ORBIT else _HEMISPHERE), _NO_WEIGHTS
    if count != _HEMISPHERE_ORBIT:
        raise ValueError(f"a frame applies to the hemisphere's orbits of {_HEMISPHERE_ORBIT}, not {count}")
    return _HEMISPHERE_ROTATED, _rotated_weights(np.ascontiguousarray(basis, dtype=np.float64), count)


route_compiles(globals())  # the first compile of each numba function here: interruptible (_threads)
