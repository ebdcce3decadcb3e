"""The block seam shared by sampling, integration and Dask: validate once, then fill any range of orbits.

A run is fixed before any work starts (:func:`prepare`: the count, dtype, map,
base point source and frame); afterwards any range of base points
``start ... stop - 1`` can be turned into its orbits by :func:`fill_range`, in any
order, on any thread or process, with identical results.  :mod:`symsphere.sampling`
fills one range or a stream of chunks, :mod:`symsphere.distributed` one range per
Dask task, and :mod:`symsphere._integration` one block per partial sum.
"""

from __future__ import annotations

import os
import sys
import warnings
from types import FrameType
from typing import Any

import numpy as np

from . import frames
from ._kernels import Plan, fill
from ._random.splitmix import GOLDEN, mix64_int
from ._typing import DTypeLike, Float64Array, FloatArray, MapMethod, PointsLike, RNGLike
from ._validation import check_count, check_dtype
from .points import BasePoints
from .symmetry import orbit, orbit_size
from .warps import triangle_warp

__all__ = [
    "CUT_ORBIT_KEY", "base_points", "prepare", "fill_range", "fill_rows", "cut_offset",
    "reference_orbits",
    "warn_at_caller",
]  # fmt: skip

_PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__))
CUT_ORBIT_KEY = 2
"""Namespace of the cut orbit's member order in its key (points.py's spawn keys are 0 and 1)."""


def prepare(
    n: int,
    count: int,
    normal: Float64Array | None,
    method: MapMethod,
    points: PointsLike,
    rng: RNGLike,
    dtype: DTypeLike,
    *,
    any_size: bool = False,
    name: str = "n",
) -> tuple[int, np.dtype[np.floating[Any]], MapMethod, BasePoints, Float64Array | None]:
    """Validate; return (n, dtype, method, base point source, frame or None).

    With *any_size*, *n* need not be a multiple of *count*: the source then has
    ``ceil(n / count)`` points, the last orbit to be cut short by :func:`fill_rows`.
    A warning of the point set (scipy's Sobol' balance warning) is attributed to the
    user's line that called into symsphere, not to a line of the package.
    """
    n = check_count(n, name, multiple=1 if any_size else count)
    dtype = check_dtype(dtype)
    triangle_warp(method)
    source = base_points(points, rng, -(-n // count), count, n)
    basis = None if normal is None else frames.frame(normal)
    return n, dtype, method, source, basis


def base_points(points: PointsLike, rng: RNGLike, total: int, count: int, n: int | None = None) -> BasePoints:
    """``BasePoints(points, rng, total, per_point=count, n=n)``, its warnings (scipy's Sobol' balance
    warning) attributed to the user's line that called into symsphere, not to a line of the package."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        source = BasePoints(points, rng, total, per_point=count, n=n)
    for warning in caught:
        warn_at_caller(str(warning.message), warning.category)
    return source


def fill_range(
    source: BasePoints,
    start: int,
    stop: int,
    method: MapMethod,
    count: int,
    basis: Float64Array | None,
    out: FloatArray,
) -> FloatArray:
    """Write the orbits of base points ``start ... stop - 1`` of *source* into *out*."""
    return _fill(source, start, stop, method, count, basis, out, 0)


def fill_rows(
    source: BasePoints, start: int, method: MapMethod, count: int, basis: Float64Array | None, out: FloatArray
) -> FloatArray:
    """Fill *out* (any number of rows) with the orbits of base points ``start, start + 1, ...``.

    Whole orbits are written in place.  If ``len(out)`` is not a multiple of *count*, the
    last ``len(out) % count`` rows are members of one more orbit, from a random offset on
    (:func:`cut_offset`), made in the same kernel call: row k of a whole orbit always lies in
    triangle k, so the first rows in table order would favour the first triangles; a random
    offset makes every row of the cut orbit uniform (for a uniform map), and the mean of f over
    any n rows unbiased.
    """
    whole, rest = divmod(len(out), count)
    if not rest:
        return _fill(source, start, start + whole, method, count, basis, out, 0)
    return _fill(source, start, start + whole + 1, method, count, basis, out, cut_offset(source, start + whole, count))


def _fill(
    source: BasePoints,
    start: int,
    stop: int,
    method: MapMethod,
    count: int,
    basis: Float64Array | None,
    out: FloatArray,
    offset: int,
) -> FloatArray:
    """One kernel call: the orbits of points ``start ... stop - 1``, the last one cut to *out*'s rows."""
    return fill(Plan(source, method, count, basis), start, stop, out, offset)


_MASK = (1 << 64) - 1


def cut_offset(source: BasePoints, orbit_index: int, count: int) -> int:
    """Where a cut orbit's members start: rows ``(s + i) % count``, ``i < n % count``, are taken.

    The offset s is uniform on ``range(count)`` and independent of the base points:
    SplitMix64's finaliser (:mod:`symsphere._random.splitmix`) of a key made from the source's root
    entropy, :data:`CUT_ORBIT_KEY` and the orbit's index.  So each row of a cut orbit is a
    uniformly chosen member (uniform on the sphere for a uniform map), no member is taken
    twice, and it costs about a microsecond: any n runs as fast as the nearest multiple of the
    orbit size.
    """
    w0, w1, w2, w3 = source.root_entropy
    key = (w0 ^ (w1 << 1) ^ (w2 << 2) ^ (w3 << 3) ^ (CUT_ORBIT_KEY << 62) ^ orbit_index * int(GOLDEN)) & _MASK
    return mix64_int(key) % count


def warn_at_caller(message: str, category: type[Warning] = UserWarning) -> None:
    """``warnings.warn`` with the stack level of the first frame outside this package."""
    level, frame = 2, sys._getframe(1)  # stacklevel 2: our caller
    inside = _PACKAGE_DIR + os.sep
    caller: FrameType | None = frame
    while caller is not None and os.path.abspath(caller.f_code.co_filename).startswith(inside):
        level, caller = level + 1, caller.f_back
    warnings.warn(message, category, stacklevel=level)


def reference_orbits(uv: Float64Array, method: MapMethod, count: int, basis: Float64Array | None) -> FloatArray:
    """The numpy path (map, orbit, frame): what the kernels must reproduce."""
    directions = orbit(triangle_warp(method).points(uv), "sphere" if count == orbit_size("sphere") else "hemisphere")
    if basis is not None:
        directions = frames.to_world(directions, basis)
    return directions.reshape(-1, 3)
