"""Maps from the unit square onto the fundamental triangle T0 = {z >= x >= y >= 0}.

Each map is a triple, side by side as in Mitsuba's ``warp.h``: forward
(``(u, v)`` to a direction in T0), pdf (density with respect to solid angle,
integrating to 1 over T0) and inverse.

``equal_area`` (the default)
    Exact and area-preserving: pdf = 12/pi.  Arvo's spherical-triangle
    sampling (SIGGRAPH 1995) specialised to T0, whose angle at the pole
    (0, 0, 1) is pi/4 and whose third edge lies on the great circle x = z.
    The area of T0 with azimuth below phi is
    ``A(phi) = phi - asin(sin(phi) / sqrt 2)``, and ``A(pi/4) = pi/12``.
    Solving ``A(phi) = u pi/12 =: s`` gives
    ``tan(phi) = sqrt 2 sin s / (sqrt 2 cos s - 1)``.  Given phi, cos(theta) is
    uniform between 1 and ``cos(theta_max) = cos(phi) / sqrt(1 + cos^2 phi)``.
``paper1``, ``paper2``
    The paper's Algorithms 1 and 2, exactly as printed.  They are *not*
    uniform: in gnomonic coordinates ``(a, b) = (x/z, y/z)`` Algorithm 1 is
    ``(v, v tan(phi))`` and Algorithm 2 ``(tan(theta), tan(theta) tan(phi))``;
    their Jacobians give the densities below, which diverge like 1/sin(theta)
    at the vertex (0, 0, 1).  With these pdfs, estimators that weight by
    1/pdf stay unbiased.

All computation is in float64; results take the floating dtype of the input.
Outputs are clamped into T0 (``z >= x >= y >= 0``) to absorb rounding, so
``u, v`` in {0, 1} give no NaN and no point outside the triangle.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ._validation import check_choice, check_directions, check_uv

__all__ = [
    "METHODS",
    "square_to_triangle",
    "triangle_pdf",
    "triangle_to_square",
    "TriangleMap",
    "get_map",
]

_SQRT2 = np.sqrt(2.0)
TRIANGLE_AREA = np.pi / 12


@dataclass(frozen=True)
class TriangleMap:
    """A map from the unit square onto T0: forward, pdf and inverse.

    The three callables take and return float64 arrays and trust their
    inputs; the public functions of this module validate.
    """

    name: str
    forward: Callable[[np.ndarray], np.ndarray]
    pdf: Callable[[np.ndarray], np.ndarray]
    inverse: Callable[[np.ndarray], np.ndarray]
    uniform: bool


def square_to_triangle(uv, method="equal_area"):
    """Map points of the unit square onto the triangle T0.

    Parameters
    ----------
    uv : array_like, shape (..., 2)
        Points of [0, 1]^2.
    method : {'equal_area', 'paper1', 'paper2'}
        ``'equal_area'`` is exact and uniform; ``'paper1'`` and ``'paper2'``
        are the paper's Algorithms 1 and 2 as printed (not uniform).

    Returns
    -------
    ndarray, shape (..., 3)
        Unit directions in T0 = {z >= x >= y >= 0}, in the dtype of *uv*
        (float64 for integer input).

    Examples
    --------
    >>> from symsphere import square_to_triangle
    >>> square_to_triangle([[0.0, 0.0], [1.0, 1.0]])     # the pole, and the vertex (1, 1, 1)/sqrt 3
    array([[0.        , 0.        , 1.        ],
           [0.57735027, 0.57735027, 0.57735027]])
    """
    uv = check_uv(uv)
    triangle_map = get_map(method)
    return triangle_map.forward(uv.astype(np.float64)).astype(uv.dtype, copy=False)


def triangle_pdf(p, method="equal_area"):
    """Density of a map's points with respect to solid angle on T0.

    Parameters
    ----------
    p : array_like, shape (..., 3)
        Unit directions.
    method : {'equal_area', 'paper1', 'paper2'}

    Returns
    -------
    ndarray, shape (...)
        The density; 0 outside T0.  It integrates to 1 over T0.  For the
        paper's maps the density diverges at the vertex (0, 0, 1) and is
        returned there as ``inf`` (so a 1/pdf weight is 0, its limit).

    Examples
    --------
    >>> from symsphere import triangle_pdf
    >>> float(triangle_pdf([0.3, 0.2, 0.93273791]))   # 12/pi
    3.819718634205488
    """
    p = check_directions(p, "p")
    triangle_map = get_map(method)
    return triangle_map.pdf(p.astype(np.float64)).astype(p.dtype, copy=False)


def triangle_to_square(p, method="equal_area"):
    """Inverse of :func:`square_to_triangle`.

    Parameters
    ----------
    p : array_like, shape (..., 3)
        Unit directions in T0 (up to a few ulps of rounding).
    method : {'equal_area', 'paper1', 'paper2'}

    Returns
    -------
    ndarray, shape (..., 2)
        Points of [0, 1]^2.  At the vertex (0, 0, 1), where every u maps to the
        same point, u = 0 is returned.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere import square_to_triangle, triangle_to_square
    >>> uv = np.array([0.25, 0.75])
    >>> bool(np.allclose(triangle_to_square(square_to_triangle(uv)), uv, rtol=0, atol=1e-14))
    True
    """
    p = check_directions(p, "p")
    triangle_map = get_map(method)
    p64 = p.astype(np.float64)
    tol = 8 * np.finfo(p.dtype).eps * np.maximum(np.linalg.norm(p64, axis=-1), 1.0)
    x, y, z = p64[..., 0], p64[..., 1], p64[..., 2]
    if not np.all((z - x >= -tol) & (x - y >= -tol) & (y >= -tol)):
        raise ValueError("'p' must lie in the triangle T0 = {z >= x >= y >= 0}")
    return triangle_map.inverse(p64).astype(p.dtype, copy=False)


def get_map(method) -> TriangleMap:
    """The registered :class:`TriangleMap` called *method*."""
    return _REGISTRY[check_choice(method, "method", METHODS)]


# --- private: the triples ----------------------------------------------------


def _stack(x, y, z):
    """Clamp into T0 (z >= x >= y >= 0) and stack to (..., 3)."""
    x = np.minimum(x, z)
    y = np.clip(y, 0.0, x)
    return np.stack([x, y, z], axis=-1)


def _azimuth_to_u(p):
    """u = 4 phi / pi with phi = atan2(y, x) (both paper maps use phi = u pi/4)."""
    return np.clip(np.arctan2(p[..., 1], p[..., 0]) * (4 / np.pi), 0.0, 1.0)


def _in_triangle(p):
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    return (z >= x) & (x >= y) & (y >= 0)


def _one_minus_cos_theta_max(cos_phi):
    # 1 - c/sqrt(1+c^2) rewritten without cancellation: 1 / (r (r + c)), r = sqrt(1+c^2).
    r = np.sqrt(1.0 + cos_phi * cos_phi)
    return 1.0 / (r * (r + cos_phi))


def _equal_area_forward(uv):
    s = uv[..., 0] * (np.pi / 12)
    phi = np.clip(np.arctan2(_SQRT2 * np.sin(s), _SQRT2 * np.cos(s) - 1.0), 0.0, np.pi / 4)
    cos_phi, sin_phi = np.cos(phi), np.sin(phi)
    w = uv[..., 1] * _one_minus_cos_theta_max(cos_phi)  # w = 1 - cos(theta)
    sin_theta = np.sqrt(w * (2.0 - w))  # no cancellation near the pole
    return _stack(sin_theta * cos_phi, sin_theta * sin_phi, 1.0 - w)


def _equal_area_pdf(p):
    return np.where(_in_triangle(p), 12 / np.pi, 0.0)


def _equal_area_inverse(p):
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    phi = np.clip(np.arctan2(y, x), 0.0, np.pi / 4)
    u = np.clip((phi - np.arcsin(np.sin(phi) / _SQRT2)) * (12 / np.pi), 0.0, 1.0)
    one_minus_cos = (x * x + y * y) / (1.0 + z)  # 1 - z for unit p, without cancellation
    v = np.clip(one_minus_cos / _one_minus_cos_theta_max(np.cos(phi)), 0.0, 1.0)
    return np.stack([u, v], axis=-1)


def _paper1_forward(uv):
    # Algorithm 1 as printed: phi = u pi/4, theta = arctan(v / cos phi).
    phi = uv[..., 0] * (np.pi / 4)
    theta = np.arctan(uv[..., 1] / np.cos(phi))
    return _stack(np.cos(phi) * np.sin(theta), np.sin(phi) * np.sin(theta), np.cos(theta))


def _paper1_pdf(p):
    # (a, b) = (x/z, y/z) = (v, v tan phi): |J| = pi (x^2 + y^2) / (4 x z), d(omega) = z^3 da db.
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    return _singular_density(p, 4.0, np.pi * z * z)


def _paper1_inverse(p):
    v = np.clip(np.divide(p[..., 0], p[..., 2]), 0.0, 1.0)
    return np.stack([_azimuth_to_u(p), v], axis=-1)


def _paper2_forward(uv):
    # Algorithm 2 as printed: phi = u pi/4, theta = v pi/4, P = N'_x x N'_y / |N'_x x N'_y|.
    phi = uv[..., 0] * (np.pi / 4)
    theta = uv[..., 1] * (np.pi / 4)
    sin_t, cos_t, cos_p = np.sin(theta), np.cos(theta), np.cos(phi)
    norm = np.sqrt(sin_t**2 + cos_t**2 * cos_p**2)
    return _stack(sin_t * cos_p / norm, sin_t * np.sin(phi) / norm, cos_t * cos_p / norm)


def _paper2_pdf(p):
    # (a, b) = (tan theta, tan theta tan phi): |J| = (pi/4)^2 (x^2+z^2)(x^2+y^2) / (x z^3).
    x, z = p[..., 0], p[..., 2]
    return _singular_density(p, 16.0, np.pi**2 * (x * x + z * z))


def _paper2_inverse(p):
    v = np.clip(np.arctan2(p[..., 0], p[..., 2]) * (4 / np.pi), 0.0, 1.0)
    return np.stack([_azimuth_to_u(p), v], axis=-1)


def _singular_density(p, constant, smooth_factor):
    """``constant * x / (smooth_factor * (x^2 + y^2))`` on T0, 0 outside.

    Written as ``constant * cos(phi) / (smooth_factor * r)`` with r = hypot(x, y), so
    that it neither underflows to 0/0 near the vertex (0, 0, 1) nor loses accuracy.
    At the vertex itself (r = 0) the density is +inf, its limit from every side.
    """
    x, y = p[..., 0], p[..., 1]
    r = np.hypot(x, y)
    pole = r == 0
    safe_r = np.where(pole, 1.0, r)
    with np.errstate(over="ignore"):  # within ~1e-308 of the vertex the density exceeds float64
        density = constant * (x / safe_r) / (smooth_factor * safe_r)
    return np.where(_in_triangle(p), np.where(pole, np.inf, density), 0.0)


_REGISTRY = {
    "equal_area": TriangleMap("equal_area", _equal_area_forward, _equal_area_pdf, _equal_area_inverse, True),
    "paper1": TriangleMap("paper1", _paper1_forward, _paper1_pdf, _paper1_inverse, False),
    "paper2": TriangleMap("paper2", _paper2_forward, _paper2_pdf, _paper2_inverse, False),
}
METHODS = tuple(_REGISTRY)
