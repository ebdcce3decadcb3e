"""Type aliases shared by the annotations of the public API.

A private module with public names, like :mod:`symsphere._validation`: import
them from here in annotations (``from ._typing import RNGLike``).  Only
numpy and typing are imported at run time; scipy's ``QMCEngine`` (``scipy.stats``
costs 0.3 s at start-up) and ``Fraction`` are imported for the type checker only.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any, Literal, Protocol, TypeAlias

import numpy as np
import numpy.typing as npt

if TYPE_CHECKING:
    from fractions import Fraction

    from scipy.stats.qmc import QMCEngine

__all__ = [
    "BoolArray",
    "ChiDomain",
    "Density",
    "Domain",
    "DTypeLike",
    "Float64Array",
    "FloatArray",
    "IntArray",
    "MapMethod",
    "PointSet",
    "PointsLike",
    "Polynomial",
    "RNGLike",
    "Sampler",
]

RNGLike: TypeAlias = "np.random.Generator | np.random.SeedSequence | int | None"
"""What every ``rng=`` accepts (SPEC 7): a Generator, a SeedSequence, an int seed or None."""

Domain: TypeAlias = Literal["sphere", "hemisphere"]
"""The two domains of the symmetric scheme; the hemisphere is z >= 0."""

ChiDomain: TypeAlias = Literal["sphere", "hemisphere", "triangle"]
"""The domains of :mod:`symsphere.stats` and :mod:`symsphere.bins` (the triangle is T0)."""

MapMethod: TypeAlias = Literal["equal_area", "paper1", "paper2"]
"""The maps of the unit square onto T0 (:data:`symsphere.warps.METHODS`)."""

PointSet: TypeAlias = Literal["random", "stratified", "sobol", "halton", "sobol_interlaced2", "sobol_interlaced3"]
"""The named point sets of the unit square (:data:`symsphere.points.POINT_SETS`)."""

PointsLike: TypeAlias = "PointSet | QMCEngine"
"""What every ``points=`` accepts: a named point set or a ``scipy.stats.qmc.QMCEngine`` with d == 2."""

DTypeLike: TypeAlias = npt.DTypeLike
"""What every ``dtype=`` accepts (float32 or float64 at run time)."""

FloatArray: TypeAlias = npt.NDArray[np.floating[Any]]
"""An array of float32 or float64."""

Float64Array: TypeAlias = npt.NDArray[np.float64]
"""An array of float64."""

IntArray: TypeAlias = npt.NDArray[np.int64]
"""An array of int64."""

BoolArray: TypeAlias = npt.NDArray[np.bool_]
"""An array of bools."""

Density: TypeAlias = Callable[[Float64Array], "npt.ArrayLike"]
"""A density on directions: ``pdf(d)`` for float64 ``d`` of shape (m, 3) returns shape (m,) (or a scalar)."""

Polynomial: TypeAlias = Mapping[tuple[int, int, int], "float | Fraction"]
"""A polynomial in x, y, z: ``{(a, b, c): coefficient}`` for the monomials x^a y^b z^c."""


class Sampler(Protocol):
    """A peer's sampler (:attr:`symsphere.peers.Peer.sampler`): ``n`` directions, shape (n, 3)."""

    def __call__(
        self, n: int, *, points: PointsLike = ..., rng: RNGLike = ..., dtype: DTypeLike = ...
    ) -> FloatArray: ...
