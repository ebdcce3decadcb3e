"""numba kernels: map + orbit (+ frame) fused in one pass, parallel over all cores.

The map formulas are the elementwise functions of :mod:`symsphere.maps`
(``register_jitable``), the orbit stores are generated from the tables of
:mod:`symsphere.symmetry` (:mod:`symsphere._codegen`), so nothing here restates
a formula.  The numpy path (``maps.TriangleMap.forward`` + ``symmetry._orbit`` +
``frames.to_world``) is the reference the tests compare against.

Kernels compile lazily per output dtype and are cached on disk (``cache=True``),
so a new process with a warm cache pays no compilation.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange
from numba.extending import register_jitable

from . import _orbit_stores, maps, symmetry
from ._numba_cache import invalidate_if_changed
from ._orbit_stores import store_orbit_24, store_orbit_24_rotated, store_orbit_48
from .maps import (
    METHODS,
    _equal_area_density,
    _equal_area_point,
    _paper1_density,
    _paper1_point,
    _paper2_density,
    _paper2_point,
)
from .symmetry import SIGNS, SOURCES

__all__ = ["METHOD_CODES", "fill_orbits", "triangle_point", "triangle_density", "orbit_member"]

METHOD_CODES = {name: code for code, name in enumerate(METHODS)}
assert METHOD_CODES == {"equal_area": 0, "paper1": 1, "paper2": 2}

_OPTIONS = dict(cache=True, error_model="numpy", nogil=True)
invalidate_if_changed(__file__, [maps.__file__, _orbit_stores.__file__, symmetry.__file__])


@register_jitable
def triangle_point(u, v, code):
    """The map *code* of METHOD_CODES at (u, v): a point (x, y, z) of T0."""
    if code == 0:
        return _equal_area_point(u, v)
    if code == 1:
        return _paper1_point(u, v)
    return _paper2_point(u, v)


@register_jitable
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


# Each parallel iteration maps _BATCH base points first and stores their orbits after: the
# maps' chains of sin, sqrt and divisions then overlap one another instead of stalling the
# stores (measured: the float32 kernel 2.96 ms -> about 1.3 ms for 48 * 2**16 directions).
_BATCH = 16


@njit(inline="always")
def _map_batch(uv, code, first, stop, base):
    for j in range(stop - first):
        x, y, z = triangle_point(uv[first + j, 0], uv[first + j, 1], code)
        base[j, 0] = x
        base[j, 1] = y
        base[j, 2] = z


_SPHERE, _HEMISPHERE, _HEMISPHERE_ROTATED = 0, 1, 2


@njit(parallel=True, **_OPTIONS)
def _fill(uv, code, kind, basis, rows):
    for batch in prange((uv.shape[0] + _BATCH - 1) // _BATCH):
        first = batch * _BATCH
        stop = min(first + _BATCH, uv.shape[0])
        base = np.empty((_BATCH, 3))
        _map_batch(uv, code, first, stop, base)
        for j in range(stop - first):
            x, y, z = base[j, 0], base[j, 1], base[j, 2]
            if kind == _SPHERE:
                store_orbit_48(rows, first + j, x, y, z)
            elif kind == _HEMISPHERE:
                store_orbit_24(rows, first + j, x, y, z)
            else:
                store_orbit_24_rotated(rows, first + j, x, y, z, basis)


def fill_orbits(uv, method, count, basis, out):
    """Write the orbits of the points *uv* (m, 2) into *out* (m * count, 3).

    *basis* is None or the (3, 3) frame of :func:`symsphere.frames.frame`
    (hemisphere only).  Trusts its inputs: *uv* float64 C-contiguous, *out*
    C-contiguous float32 or float64.
    """
    code = METHOD_CODES[method]
    rows = out.reshape(len(uv), 3 * count)
    if count == 48:
        kind = _SPHERE
    else:
        kind = _HEMISPHERE if basis is None else _HEMISPHERE_ROTATED
    frame = np.eye(3) if basis is None else np.ascontiguousarray(basis, dtype=np.float64)
    _fill(uv, code, kind, frame, rows)
    return out
