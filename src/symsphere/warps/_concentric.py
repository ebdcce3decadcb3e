"""Shirley & Chiu's concentric map onto the unit disk (1997), and Malley's lift of it: cosine-weighted.

Derivation.  With (a, b) = 2 (u, v) - 1, concentric squares go to concentric circles: if
``|a| >= |b|``, radius a and angle (pi/4)(b/a); else radius b and angle pi/2 - (pi/4)(a/b).
Each of the four triangular sectors is stretched uniformly, so the map is area-preserving up
to the constant pi/4 per unit square area: density 1/pi on the disk.  Malley's method lifts a
uniform point (x, y) of the disk vertically to z = sqrt(1 - x^2 - y^2); the projection onto
the disk scales area by cos(theta), so the lifted point has density cos(theta)/pi in solid
angle (pbrt-v4 ``SampleCosineHemisphere``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt

from .._constants import INV_PI
from .._typing import Float64Array, FloatArray
from .._validation import as_float_array, check_unit_directions, check_uv
from ._common import checked_forward, checked_inverse, elementwise, formula, on_rows, pick
from ._record import Warp
from ._registry import register

__all__ = [
    "square_to_concentric_disk",
    "square_to_concentric_disk_pdf",
    "concentric_disk_to_square",
    "concentric_disk_point",
    "square_to_cosine_hemisphere",
    "square_to_cosine_hemisphere_pdf",
    "cosine_hemisphere_to_square",
    "cosine_hemisphere_point",
]


# --- the disk -----------------------------------------------------------------------------


def square_to_concentric_disk(uv: npt.ArrayLike) -> FloatArray:
    """Shirley & Chiu's concentric map of the square onto the unit disk (1997).

    Parameters
    ----------
    uv : array_like, shape (..., 2)

    Returns
    -------
    ndarray, shape (..., 2)
        Points of the unit disk, density 1/pi.

    Examples
    --------
    >>> from symsphere.warps import square_to_concentric_disk
    >>> square_to_concentric_disk([[0.5, 0.5], [1.0, 0.5], [0.5, 0.0]])
    array([[ 0.,  0.],
           [ 1.,  0.],
           [ 0., -1.]])
    """
    uv = check_uv(uv)
    return _concentric(uv.astype(np.float64)).astype(uv.dtype, copy=False)


def square_to_concentric_disk_pdf(p: npt.ArrayLike) -> Float64Array:
    """Density (per unit area) of :func:`square_to_concentric_disk`: 1/pi in the closed disk, 0 outside.

    Parameters
    ----------
    p : array_like, shape (..., 2)
        Points of the plane.

    Examples
    --------
    >>> from symsphere.warps import square_to_concentric_disk_pdf
    >>> square_to_concentric_disk_pdf([[0.0, 1.0], [0.8, 0.8]]) * 3.141592653589793
    array([1., 0.])
    """
    a64 = _check_plane_points(p).astype(np.float64)
    return np.where(np.hypot(a64[..., 0], a64[..., 1]) <= 1.0, INV_PI, 0.0)


def concentric_disk_to_square(p: npt.ArrayLike) -> FloatArray:
    """Inverse of :func:`square_to_concentric_disk`.

    Parameters
    ----------
    p : array_like, shape (..., 2)
        Points of the closed unit disk.

    Returns
    -------
    ndarray, shape (..., 2)
        Points of [0, 1]^2; the centre goes to (0.5, 0.5).

    Examples
    --------
    >>> from symsphere.warps import concentric_disk_to_square
    >>> concentric_disk_to_square([[0.0, 0.0], [0.0, 1.0]])
    array([[0.5, 0.5],
           [0.5, 1. ]])
    """
    arr = _check_plane_points(p)
    a64 = arr.astype(np.float64)
    if np.any(np.hypot(a64[..., 0], a64[..., 1]) > 1 + 1e-6):
        raise ValueError("'p' must lie in the closed unit disk")
    return _concentric_inverse(a64).astype(arr.dtype, copy=False)


def _check_plane_points(p: npt.ArrayLike) -> FloatArray:
    arr = as_float_array(p, "p")
    if arr.ndim == 0 or arr.shape[-1] != 2:
        raise ValueError(f"'p' must have shape (..., 2), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError("'p' must be finite (no NaN or inf)")
    return arr


@elementwise()
def concentric_disk_point(u: Any, v: Any) -> tuple[Any, Any]:
    """Elementwise Shirley & Chiu (1997): concentric squares of [0, 1]^2 -> concentric circles of the disk.

    Arguments as for :func:`symsphere.warps.uniform_sphere_point`.

    Examples
    --------
    >>> from symsphere.warps import concentric_disk_point
    >>> [float(c) for c in concentric_disk_point(1.0, 0.5)]
    [1.0, 0.0]
    """
    a = 2.0 * u - 1.0
    b = 2.0 * v - 1.0
    wide = np.abs(a) >= np.abs(b)
    r = pick(wide, a, b)
    safe = pick(r != 0, r, 1.0)
    # angle (pi/4)(b/a) in the wide sectors, pi/2 - (pi/4)(a/b) in the others:
    # x = r cos, y = r sin; for the others cos(pi/2 - t) = sin t.
    t = 0.25 * np.pi * pick(wide, b, a) / safe
    c, s = np.cos(t), np.sin(t)
    return r * pick(wide, c, s), r * pick(wide, s, c)


_concentric = on_rows(concentric_disk_point)
_concentric_disk_point = formula(concentric_disk_point)  # the bare formula, for the lifted map below


def _concentric_inverse(p: Float64Array) -> Float64Array:
    x, y = p[..., 0], p[..., 1]
    rho = np.minimum(np.hypot(x, y), 1.0)
    wide = np.abs(x) >= np.abs(y)
    big = np.where(wide, x, y)
    small = np.where(wide, y, x)
    safe = np.where(big != 0, big, 1.0)
    r = np.copysign(rho, big)
    other = r * np.arctan(small / safe) * (4.0 / np.pi)  # (4/pi) * angle * r
    a = np.where(wide, r, other)
    b = np.where(wide, other, r)
    return np.clip(np.stack([0.5 * (a + 1.0), 0.5 * (b + 1.0)], axis=-1), 0.0, 1.0)


register(
    Warp(name="concentric_disk", domain="disk", uniform=True, forward=square_to_concentric_disk,
         pdf=square_to_concentric_disk_pdf, inverse=concentric_disk_to_square, point=concentric_disk_point,
         reference="Shirley & Chiu 1997"),
)  # fmt: skip


# --- the cosine-weighted hemisphere -------------------------------------------------------


def square_to_cosine_hemisphere(uv: npt.ArrayLike) -> FloatArray:
    """Cosine-weighted hemisphere: the concentric disk lifted by Malley's method.

    z is evaluated as sqrt((1 - rho)(1 + rho)), rho = ``max(|a|, |b|)`` the disk radius.

    Examples
    --------
    >>> from symsphere.warps import square_to_cosine_hemisphere
    >>> square_to_cosine_hemisphere([[0.5, 0.5], [1.0, 0.5]])
    array([[0., 0., 1.],
           [1., 0., 0.]])
    """
    return checked_forward(_cosine_hemisphere, uv)


def square_to_cosine_hemisphere_pdf(d: npt.ArrayLike) -> Float64Array:
    """Density cos(theta)/pi of :func:`square_to_cosine_hemisphere`; 0 for z < 0.

    Examples
    --------
    >>> from symsphere.warps import square_to_cosine_hemisphere_pdf
    >>> square_to_cosine_hemisphere_pdf([[0.0, 0.0, 1.0], [0.6, 0.0, -0.8]]) * 3.141592653589793
    array([1., 0.])
    """
    d = check_unit_directions(d, "d")
    d64 = d.astype(np.float64)
    density: Float64Array = np.maximum(d64[..., 2], 0.0) / (np.linalg.norm(d64, axis=-1) * math.pi)
    return density


def cosine_hemisphere_to_square(d: npt.ArrayLike) -> FloatArray:
    """Inverse of :func:`square_to_cosine_hemisphere`: drop z, invert the disk map.

    Examples
    --------
    >>> from symsphere.warps import cosine_hemisphere_to_square
    >>> cosine_hemisphere_to_square([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])   # the pole; the rim at phi = 0
    array([[0.5, 0.5],
           [1. , 0.5]])
    """
    return checked_inverse(_cosine_hemisphere_inverse, d, hemisphere=True)


@elementwise()
def cosine_hemisphere_point(u: Any, v: Any) -> tuple[Any, Any, Any]:
    """Elementwise: the concentric disk lifted to the hemisphere (Malley), z = sqrt((1 - rho)(1 + rho)).

    Arguments as for :func:`symsphere.warps.uniform_sphere_point`.

    Examples
    --------
    >>> from symsphere.warps import cosine_hemisphere_point
    >>> [float(c) for c in cosine_hemisphere_point(0.5, 0.5)]
    [0.0, 0.0, 1.0]
    """
    x, y = _concentric_disk_point(u, v)
    rho = np.maximum(np.abs(2.0 * u - 1.0), np.abs(2.0 * v - 1.0))
    z = np.sqrt(np.maximum((1.0 - rho) * (1.0 + rho), 0.0))
    return x, y, z


_cosine_hemisphere = on_rows(cosine_hemisphere_point)


def _cosine_hemisphere_inverse(d: Float64Array) -> Float64Array:
    return _concentric_inverse(d[..., :2])


register(
    Warp(name="cosine_hemisphere", domain="hemisphere", uniform=False, forward=square_to_cosine_hemisphere,
         pdf=square_to_cosine_hemisphere_pdf, inverse=cosine_hemisphere_to_square, point=cosine_hemisphere_point,
         reference="Shirley & Chiu 1997 (concentric map) + Malley's method; pbrt-v4 SampleCosineHemisphere"),
)  # fmt: skip
