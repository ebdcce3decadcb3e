"""Closed forms of irradiance at the origin, for integrands with exact integrals: from a polygonal light
(Lambert 1760) and from a spherical one.  Public through :mod:`symsphere.integrands`.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from ._validation import (
    check_directions,
    check_nonnegative,
    check_normal,
    check_positive,
)

__all__ = ["lambert_irradiance", "sphere_light_irradiance"]


def lambert_irradiance(vertices: npt.ArrayLike, normal: npt.ArrayLike | None = None, radiance: float = 1.0) -> float:
    """Irradiance at the origin from a polygonal light of constant radiance (Lambert 1760).

    ``E = (L/2) |sum_i Theta_i (n . Gamma_i)|``, where for the edge from
    vertex i to i + 1 (directions v_i from the origin) ``Theta_i`` is the
    angle it subtends, ``atan2(|v_i x v_i+1|, v_i . v_i+1)``, and ``Gamma_i``
    the unit normal ``(v_i x v_i+1)/|v_i x v_i+1|`` of the plane through the
    edge and the origin.  This is the flux of the "vector irradiance"
    (Arvo 1994) through the surface; the absolute value fixes the
    orientation of the vertex order.  Valid for a polygon entirely above
    the surface (n . p > 0 for all its points), so that cos(theta) >= 0 over
    it; then it equals ``L * integral over the polygon's solid angle of cos(theta)``.

    Parameters
    ----------
    vertices : array_like, shape (k, 3)
        The polygon's vertices in order (k >= 3), as points relative to the
        receiving point.
    normal : array_like of 3 floats, optional
        The surface normal (default (0, 0, 1)); normalised.
    radiance : float
        L, the light's radiance, the same at every point and in every direction (default 1).

    Returns
    -------
    float
        E, the irradiance at the origin: L times the polygon's cosine-weighted solid angle.

    Examples
    --------
    >>> import math
    >>> from symsphere.integrands import lambert_irradiance
    >>> # a huge square at height 1 sees almost the whole hemisphere: E -> pi L
    >>> big = [[-1e4, -1e4, 1], [1e4, -1e4, 1], [1e4, 1e4, 1], [-1e4, 1e4, 1]]
    >>> round(lambert_irradiance(big) / math.pi, 3)
    1.0
    """
    v = check_directions(vertices, "vertices").astype(np.float64)
    if v.ndim != 2 or v.shape[0] < 3:
        raise ValueError(f"'vertices' must have shape (k, 3) with k >= 3, got {v.shape}")
    n = check_normal((0.0, 0.0, 1.0) if normal is None else normal)
    radiance = check_nonnegative(radiance, "radiance")
    if np.any(v @ n <= 0):
        raise ValueError("'vertices' must lie strictly above the surface (vertices @ normal > 0)")
    u = v / np.linalg.norm(v, axis=1, keepdims=True)
    w = np.roll(u, -1, axis=0)
    cross = np.cross(u, w)
    sin = np.linalg.norm(cross, axis=1)
    theta = np.arctan2(sin, np.sum(u * w, axis=1))
    gamma_n = (cross @ n) / np.where(sin > 0, sin, 1.0)
    irradiance = 0.5 * radiance * abs(math.fsum((theta * gamma_n).tolist()))
    if not math.isfinite(irradiance):
        raise ValueError(f"'radiance'={radiance} is too large: the irradiance overflows float64")
    return irradiance


def sphere_light_irradiance(center: npt.ArrayLike, distance: float, radius: float, radiance: float = 1.0) -> float:
    """Irradiance from a spherical light entirely above the surface z = 0.

    The light subtends the cone of half-angle alpha, ``sin(alpha) = R/D``,
    about its centre direction c.  Since ``integral over the cone of w dw =
    pi sin^2(alpha) c`` (by symmetry only the component along c survives:
    ``2 pi integral_{cos alpha}^1 t dt``), ``E = L n . (pi sin^2(alpha) c) =
    pi L (R/D)^2 cos(beta)`` with cos(beta) = c . n -- the classic sphere form
    factor, valid when beta + alpha <= pi/2 (the cone does not cross the
    horizon).

    Parameters
    ----------
    center : array_like of 3 floats
        Direction of the light's centre (normalised).
    distance, radius : float
        D > R > 0.
    radiance : float
        L, constant over the sphere's surface (default 1).

    Returns
    -------
    float
        E = pi L (R/D)^2 cos(beta).

    Examples
    --------
    >>> import math
    >>> from symsphere.integrands import sphere_light_irradiance
    >>> sphere_light_irradiance([0, 0, 1], 2.0, 1.0) / math.pi   # sin^2(alpha) = 1/4
    0.25
    """
    if center is None:
        raise TypeError("'center' must be a 3-vector (the direction to the sphere), got None")
    c = check_normal(center, "center")
    distance = check_positive(distance, "distance")
    radius = check_positive(radius, "radius")
    radiance = check_nonnegative(radiance, "radiance")
    if radius >= distance:
        raise ValueError(f"'radius' must be smaller than 'distance', got {radius} >= {distance}")
    sin_alpha = radius / distance
    if math.asin(sin_alpha) + math.acos(min(1.0, float(c[2]))) > math.pi / 2 + 1e-15:
        raise ValueError("the light must lie entirely above the horizon: beta + alpha <= pi/2")
    irradiance = math.pi * radiance * sin_alpha**2 * float(c[2])
    if not math.isfinite(irradiance):
        raise ValueError(f"'radiance'={radiance} is too large: the irradiance overflows float64")
    return irradiance
