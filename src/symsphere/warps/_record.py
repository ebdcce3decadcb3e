"""The record that describes a warp of the unit square: :class:`Warp`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal, TypeAlias

import numpy as np
import numpy.typing as npt

from .._typing import Float64Array, FloatArray

__all__ = ["Warp", "WarpDomain"]

WarpDomain: TypeAlias = Literal["sphere", "hemisphere", "triangle", "wedge", "disk"]
"""Where a warp's points lie: the sphere, the hemisphere z >= 0, T0 = {z >= x >= y >= 0},
the wedge W = {x >= y >= 0, z >= 0}, or the unit disk (points of the plane)."""


@dataclass(frozen=True)
class Warp:
    """A map of the unit square onto a domain: its triple forward/pdf/inverse and what it preserves.

    Attributes
    ----------
    name : str
        The key in :data:`symsphere.warps.WARPS`.
    domain : {'sphere', 'hemisphere', 'triangle', 'wedge', 'disk'}
        Where the points lie: the sphere, the hemisphere z >= 0, T0 = {z >= x >= y >= 0}, the wedge
        W = {x >= y >= 0, z >= 0}, or the unit disk (points of the plane, shape (..., 2)).
    uniform : bool
        Whether the density is constant on the domain.
    orbit_size : int
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
    orbit_size: int
    forward: Callable[[npt.ArrayLike], FloatArray]
    pdf: Callable[[npt.ArrayLike], FloatArray]
    inverse: Callable[[npt.ArrayLike], FloatArray]
    point: Callable[..., Any] | None = None
    density: Callable[..., Any] | None = None
    reference: str = ""

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
