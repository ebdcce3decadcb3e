"""The record that describes a warp of the unit square: :class:`Warp`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal, TypeAlias

import numpy as np
import numpy.typing as npt

from .._typing import DTypeLike, Float64Array, FloatArray, PointsLike, RNGLike
from .._validation import check_count, check_dtype
from ..points import check_points, unit_square_points

__all__ = ["Warp", "WarpDomain"]

WarpDomain: TypeAlias = Literal["sphere", "hemisphere", "triangle", "wedge", "disk"]
"""Where a warp's points lie: the sphere, the hemisphere z >= 0, T0 = {z >= x >= y >= 0},
the wedge W = {x >= y >= 0, z >= 0}, or the unit disk (points of the plane)."""


@dataclass(frozen=True, kw_only=True)
class Warp:
    """A map of the unit square onto a domain: its triple forward/pdf/inverse and what it preserves.

    Each warp's module states its record, by keyword, beside the triple it describes, and registers it
    (:func:`symsphere.warps.WARPS` is built from those records).

    Attributes
    ----------
    name : str
        The key in :data:`symsphere.warps.WARPS`.
    domain : {'sphere', 'hemisphere', 'triangle', 'wedge', 'disk'}
        Where the points lie: the sphere, the hemisphere z >= 0, T0 = {z >= x >= y >= 0}, the wedge
        W = {x >= y >= 0, z >= 0}, or the unit disk (points of the plane, shape (..., 2)).
    uniform : bool
        Whether the density is constant on the domain.
    orbit_size : int, default 1
        How many images of the domain under the scheme's symmetries tile the sphere or
        hemisphere a sampler covers with it: 48 for T0 (the sphere), 8 for the wedge (the
        hemisphere), 1 for a map onto the whole sphere, hemisphere or disk.
    forward : callable
        ``square_to_X``: points (..., 2) of [0, 1]^2 to points of the domain; validates.
    pdf : callable
        ``square_to_X_pdf``: the density (solid angle; area for the disk), 0 outside; validates.
    inverse : callable
        ``X_to_square``: points of the domain back to the square; validates.
    point, density : callable or None
        The elementwise formulas ``point(u, v) -> (x, y, z)`` and ``density(x, y, z)`` that
        numba compiles into kernels (``register_jitable`` or an ``overload``), where a kernel
        uses them; inside a kernel they trust their inputs.  :meth:`points` and :meth:`densities` apply them to arrays.
    reference : str
        Where the map comes from.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.warps import WARPS
    >>> w = WARPS["equal_area"]
    >>> w.domain, w.uniform, w.orbit_size
    ('triangle', True, 48)
    >>> p = w.forward([[0.5, 0.5], [0.25, 1.0]])
    >>> w.pdf(p)                                             # 12/pi on T0
    array([3.81971863, 3.81971863])
    >>> bool(np.allclose(w.inverse(p), [[0.5, 0.5], [0.25, 1.0]]))
    True
    """

    name: str
    domain: WarpDomain
    uniform: bool
    forward: Callable[[npt.ArrayLike], FloatArray]
    pdf: Callable[[npt.ArrayLike], FloatArray]
    inverse: Callable[[npt.ArrayLike], FloatArray]
    orbit_size: int = 1
    point: Callable[..., Any] | None = None
    density: Callable[..., Any] | None = None
    reference: str = ""

    def sample(
        self, n: int, *, points: PointsLike = "random", rng: RNGLike = None, dtype: DTypeLike = np.float64
    ) -> FloatArray:
        """*n* points of the domain: :attr:`forward` of *n* points of the unit square (computed in float64).

        Parameters
        ----------
        n : int
            Number of points, positive.
        points : str in symsphere.POINT_SETS or scipy.stats.qmc.QMCEngine
            The points of the square: 'random', 'stratified' (n a square), 'sobol', 'halton',
            'sobol_interlaced2', 'sobol_interlaced3', or an engine with ``d == 2``.
        rng : None, int, numpy.random.SeedSequence or numpy.random.Generator
        dtype : {numpy.float64, numpy.float32}

        Returns
        -------
        ndarray, shape (n, 3) (the disk: (n, 2))

        Examples
        --------
        >>> import numpy as np
        >>> from symsphere.warps import WARPS
        >>> d = WARPS["octahedral_sphere"].sample(1024, points="sobol", rng=0)
        >>> d.shape, bool(np.allclose(d.mean(axis=0), 0, atol=0.01))
        ((1024, 3), True)
        """
        n = check_count(n, "n")
        dtype = check_dtype(dtype)
        check_points(points)
        return self.forward(unit_square_points(n, points, rng)).astype(dtype)

    def points(self, uv: Float64Array) -> Float64Array:
        """:attr:`point` on float64 points (..., 2) of the square, unchecked: directions (..., 3)."""
        if self.point is None:
            raise ValueError(f"the warp {self.name!r} has no elementwise formula; use 'forward'")
        return np.stack(self.point(uv[..., 0], uv[..., 1]), axis=-1)

    def densities(self, p: Float64Array) -> Float64Array:
        """:attr:`density` at float64 directions (..., 3), unchecked; 0 outside the domain."""
        if self.density is None:
            raise ValueError(f"the warp {self.name!r} has no elementwise density; use 'pdf'")
        with np.errstate(divide="ignore", over="ignore"):
            return np.asarray(self.density(p[..., 0], p[..., 1], p[..., 2]), dtype=np.float64)
