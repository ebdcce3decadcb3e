"""The block seam shared by sampling, integration and Dask: validate once, then fill any range of orbits.

A run is fixed before any work starts (:func:`prepare`: the count, dtype, map,
base point source and frame); afterwards any range of base points
``start ... stop - 1`` can be turned into its orbits by :func:`fill_range`, in any
order, on any thread or process, with identical results.  :mod:`symsphere.sampling`
fills one range or a stream of chunks, :mod:`symsphere.distributed` one range per
Dask task, and :mod:`symsphere._integration` one block per partial sum.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ._typing import DTypeLike, Float64Array, FloatArray, MapMethod, PointsLike, RNGLike

from . import frames
from ._kernels import fill_orbits, fill_random_orbits
from ._validation import check_count, check_dtype
from .maps import get_map
from .points import BasePoints
from .symmetry import orbit

__all__ = ["prepare", "fill_range", "reference_orbits"]


def prepare(
    n: int,
    count: int,
    normal: Float64Array | None,
    method: MapMethod,
    points: PointsLike,
    rng: RNGLike,
    dtype: DTypeLike,
    name: str = "n",
) -> tuple[int, np.dtype[np.floating[Any]], MapMethod, BasePoints, Float64Array | None]:
    """Validate (error messages call *n* by *name*); return (n, dtype, method, base point source, frame or None)."""
    n = check_count(n, name, multiple=count)
    dtype = check_dtype(dtype)
    get_map(method)
    source = BasePoints(points, rng, n // count, per_point=count)
    basis = None if normal is None else frames.frame(normal)
    return n, dtype, method, source, basis


def fill_range(
    source: BasePoints, start: int, stop: int, method: MapMethod, count: int, basis: Float64Array | None, out: FloatArray
) -> FloatArray:
    """Write the orbits of base points ``start ... stop - 1`` of *source* into *out*."""
    if source.kind == "random":  # the kernel draws the points itself, in parallel
        assert source.seed_words is not None  # random sources always have the stream's seed
        return fill_random_orbits(source.seed_words, start, stop - start, method, count, basis, out)
    return fill_orbits(source.take(start, stop), method, count, basis, out)


def reference_orbits(uv: Float64Array, method: MapMethod, count: int, basis: Float64Array | None) -> FloatArray:
    """The numpy path (map, orbit, frame): what the kernels must reproduce."""
    directions = orbit(get_map(method).forward(uv), "sphere" if count == 48 else "hemisphere")
    if basis is not None:
        directions = frames.to_world(directions, basis)
    return directions.reshape(-1, 3)
