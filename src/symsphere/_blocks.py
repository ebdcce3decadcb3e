"""What sampling, integration and Dask share around the kernels' one entry (:func:`symsphere._kernels.fill`).

A run is a :class:`symsphere._kernels.Plan` (base point source, map, orbit size, frame), fixed
before any work starts; any range of base points ``start ... stop - 1`` is then turned into its
orbits by ``_kernels.fill``, in any order, on any thread or process, with identical results:
:mod:`symsphere.sampling` fills one range or a stream of chunks, :mod:`symsphere.distributed` one
range per Dask task, and :mod:`symsphere._integration` one block per partial sum.  Here: the base
point source with its warnings attributed to the user's line (:func:`base_points`), where a cut
orbit's members start (:func:`cut_offset`), a fresh output on cache lines and large pages
(:func:`empty_rows`), and the numpy reference the kernels are tested against.
"""

from __future__ import annotations

import os
import sys
import warnings
from types import FrameType
from typing import TypeVar

import numpy as np
import numpy.typing as npt

from . import frames
from ._random.splitmix import GOLDEN, mix64_int
from ._typing import Float64Array, FloatArray, MapMethod, PointsLike, RNGLike
from ._vector_stores import LINE as _LINE
from ._vector_stores import aligned_empty
from .points import BasePoints
from .symmetry import orbit, orbit_size
from .warps import triangle_warp

__all__ = ["CUT_ORBIT_KEY", "base_points", "cut_offset", "empty_rows", "reference_orbits", "warn_at_caller"]

_PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__))
CUT_ORBIT_KEY = 2
"""Namespace of the cut orbit's member order in its key (points.py's spawn keys are 0 and 1)."""


def base_points(points: PointsLike, rng: RNGLike, total: int, count: int, n: int | None = None) -> BasePoints:
    """``BasePoints(points, rng, total, per_point=count, n=n)``, its warnings (scipy's Sobol' balance
    warning) attributed to the user's line that called into symsphere, not to a line of the package."""
    if isinstance(points, str) and points == "random":  # no engine: nothing warns (catching costs ~40 us)
        return BasePoints(points, rng, total, per_point=count, n=n)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        source = BasePoints(points, rng, total, per_point=count, n=n)
    for warning in caught:
        warn_at_caller(str(warning.message), warning.category)
    return source


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


_HUGE_PAGE = 2**21
_HUGE_FROM = 2**22  # numpy asks the operating system for huge pages (madvise) for arrays from 4 MiB on
_Scalar = TypeVar("_Scalar", bound=np.generic)


def empty_rows(n: int, dtype: np.dtype[_Scalar]) -> npt.NDArray[_Scalar]:
    """An empty (n, 3) array of *dtype* for the kernels to fill: C-contiguous, writeable, a view of an
    allocation of its own (its ``base``) 64 bytes larger, or 2 MiB from 4 MiB on.

    Its first row starts a 64-byte line, and from 4 MiB on a 2 MiB page.  numpy's large arrays start 16
    bytes into a line (malloc's header): every 64-byte float64 store of a rotated orbit, and half its
    32-byte float32 stores, then span two lines.  And numpy asks for 2 MiB pages from 4 MiB on, but a
    range that does not start on one is mapped in 4 KiB pages up to the first 2 MiB boundary and after
    the last: ~500 page faults more per call, each stopping the thread that stores (docs/results/
    bench-stores.md).  The bytes before the first row are never written; after the last row at most
    one 2 MiB page more may be mapped, when the allocation covers it whole.
    """
    align = _HUGE_PAGE if 3 * n * dtype.itemsize >= _HUGE_FROM else _LINE
    rows: npt.NDArray[_Scalar] = aligned_empty(3 * n, dtype, align).reshape(n, 3)
    return rows


def reference_orbits(uv: Float64Array, method: MapMethod, count: int, basis: Float64Array | None) -> FloatArray:
    """The numpy path (map, orbit, frame): what the kernels must reproduce."""
    directions = orbit(triangle_warp(method).points(uv), "sphere" if count == orbit_size("sphere") else "hemisphere")
    if basis is not None:
        directions = frames.to_world(directions, basis)
    return directions.reshape(-1, 3)
