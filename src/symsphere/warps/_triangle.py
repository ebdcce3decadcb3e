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

import numpy as np
import numpy.typing as npt
from numba.extending import register_jitable

from .._constants import T0_DENSITY
from .._typing import BoolArray, Float64Array, FloatArray, MapMethod
from .._validation import check_choice, check_directions, check_unit_directions, check_uv
from ._record import Warp
from ._registry import register

__all__ = [
    "METHODS",
    "square_to_triangle",
    "square_to_triangle_pdf",
    "triangle_to_square",
    "triangle_warp",
    "TRIANGLE_WARPS",
]

_SQRT2 = np.sqrt(2.0)


def square_to_triangle(uv: npt.ArrayLike, method: MapMethod = "equal_area") -> FloatArray:
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
    >>> from symsphere.warps import square_to_triangle
    >>> square_to_triangle([[0.0, 0.0], [1.0, 1.0]])     # the pole, and the vertex (1, 1, 1)/sqrt 3
    array([[0.        , 0.        , 1.        ],
           [0.57735027, 0.57735027, 0.57735027]])
    """
    uv = check_uv(uv)
    warp = triangle_warp(method)
    return warp.points(uv.astype(np.float64)).astype(uv.dtype, copy=False)


def square_to_triangle_pdf(p: npt.ArrayLike, method: MapMethod = "equal_area") -> FloatArray:
    """Density of a map's points with respect to solid angle on T0.

    Parameters
    ----------
    p : array_like, shape (..., 3)
        Unit directions; those outside T0 have density 0.
    method : {'equal_area', 'paper1', 'paper2'}
        The map of :func:`square_to_triangle` whose density is wanted.

    Returns
    -------
    ndarray, shape (...)
        The density; 0 outside T0.  It integrates to 1 over T0.  For the
        paper's maps the density diverges at the vertex (0, 0, 1) and is
        returned there as ``inf`` (so a 1/pdf weight is 0, its limit).

    Examples
    --------
    >>> from symsphere.warps import square_to_triangle_pdf
    >>> float(square_to_triangle_pdf([0.3, 0.2, 0.93273791]))   # 12/pi
    3.819718634205488
    """
    p = check_unit_directions(p, "p")
    warp = triangle_warp(method)
    density = warp.densities(p.astype(np.float64))
    with np.errstate(over="ignore"):  # beyond float32's range near the vertex: inf, as at the vertex
        return density.astype(p.dtype, copy=False)


def triangle_to_square(p: npt.ArrayLike, method: MapMethod = "equal_area") -> FloatArray:
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
    >>> from symsphere.warps import square_to_triangle, triangle_to_square
    >>> uv = np.array([0.25, 0.75])
    >>> bool(np.allclose(triangle_to_square(square_to_triangle(uv)), uv, rtol=0, atol=1e-14))
    True
    """
    p = check_directions(p, "p")
    method = check_choice(method, "method", METHODS)
    p64 = p.astype(np.float64)
    x, y, z = p64[..., 0], p64[..., 1], p64[..., 2]
    with np.errstate(over="ignore"):  # a huge vector: rejected as non-unit below
        tol = 8 * np.finfo(p.dtype).eps * np.maximum(np.linalg.norm(p64, axis=-1), 1.0)
        inside = np.all((z - x >= -tol) & (x - y >= -tol) & (y >= -tol))
    if not inside:
        raise ValueError("'p' must lie in the triangle T0 = {z >= x >= y >= 0}")
    check_unit_directions(p, "p")  # a zero or non-unit vector would map to NaN or a wrong point
    return _INVERSES[method](p64).astype(p.dtype, copy=False)


def triangle_warp(method: MapMethod) -> Warp:
    """The :class:`~symsphere.warps.Warp` onto T0 called *method*.

    Parameters
    ----------
    method : {'equal_area', 'paper1', 'paper2'}
        One of :data:`METHODS`.

    Returns
    -------
    Warp
        Its ``point`` and ``density`` are the elementwise formulas the kernels compile.

    Raises
    ------
    ValueError
        If *method* is not one of :data:`METHODS` (the message names ``method``).

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.warps import METHODS, triangle_warp
    >>> {name: triangle_warp(name).uniform for name in METHODS}
    {'equal_area': True, 'paper1': False, 'paper2': False}
    >>> triangle_warp("paper1").forward([0.0, 1.0])      # u = 0, v = 1: (1, 0, 1)/sqrt 2
    array([0.70710678, 0.        , 0.70710678])
    """
    return TRIANGLE_WARPS[check_choice(method, "method", METHODS)]


# --- private: the triples ------------------------------------------------------
# Elementwise, numpy ufuncs only (no np.where, no branches): numpy runs them on
# arrays, and numba compiles them to scalar code inside the kernels of
# symsphere._kernels (``register_jitable`` leaves the Python functions unchanged).


@register_jitable
def _clamped_into_t0(
    x: Float64Array, y: Float64Array, z: Float64Array
) -> tuple[Float64Array, Float64Array, Float64Array]:
    """Clamp rounding errors so that z >= x >= y >= 0."""
    x = np.minimum(x, z)
    return x, np.minimum(np.maximum(y, 0.0), x), z


@register_jitable
def _in_triangle(x: Float64Array, y: Float64Array, z: Float64Array) -> BoolArray:
    return (z >= x) & (x >= y) & (y >= 0.0)


@register_jitable
def _one_minus_cos_theta_max(cos_phi: Float64Array) -> Float64Array:
    # 1 - c/sqrt(1+c^2) rewritten without cancellation: 1 / (r (r + c)), r = sqrt(1+c^2).
    r = np.sqrt(1.0 + cos_phi * cos_phi)
    return 1.0 / (r * (r + cos_phi))


def _azimuth_to_u(p: Float64Array) -> Float64Array:
    """u = 4 phi / pi with phi = atan2(y, x) (both paper maps use phi = u pi/4)."""
    return np.clip(np.arctan2(p[..., 1], p[..., 0]) * (4 / np.pi), 0.0, 1.0)


@register_jitable
def _equal_area_point(u: Float64Array, v: Float64Array) -> tuple[Float64Array, Float64Array, Float64Array]:
    # tan(phi) = sqrt2 sin(s) / (sqrt2 cos(s) - 1) =: a / b with s = u pi/12 in [0, pi/12]; then
    # (cos phi, sin phi) = (b, a) / |(a, b)|, with b >= sqrt2 cos(pi/12) - 1 > 0.36.  One sine
    # (cos s = sqrt(1 - sin^2 s) is exact enough for sin s <= 0.26) and no atan2, sin, cos of phi.
    sin_s = sin_small(u * (np.pi / 12))
    a = _SQRT2 * sin_s
    b = _SQRT2 * np.sqrt(1.0 - sin_s * sin_s) - 1.0
    inv_norm = 1.0 / np.sqrt(a * a + b * b)
    cos_phi, sin_phi = b * inv_norm, a * inv_norm
    w = v * _one_minus_cos_theta_max(cos_phi)  # w = 1 - cos(theta)
    sin_theta = np.sqrt(w * (2.0 - w))  # no cancellation near the pole
    return _clamped_into_t0(sin_theta * cos_phi, sin_theta * sin_phi, 1.0 - w)


@register_jitable
def sin_small(s: Float64Array) -> Float64Array:
    """sin s for 0 <= s <= pi/12: the polynomial of the equal-area map (public for its accuracy test only)."""
    # sin s for 0 <= s <= pi/12 by its Taylor polynomial to s^13 (Horner in s^2): the remainder is
    # below s^15/15! < 2e-21, far under half an ulp, and measured against an 80-bit sine on 2e7
    # points it is within 0.534 ulp (glibc's sin: 0.516), correctly rounded as often.  A polynomial,
    # unlike a libm call, lets LLVM vectorise the map over a batch of base points in the kernels.
    s2 = s * s
    p: Float64Array | float = 1.0 / 6227020800.0  # (an annotation only: no bytecode for numba)
    p = p * s2 - 1.0 / 39916800.0
    p = p * s2 + 1.0 / 362880.0
    p = p * s2 - 1.0 / 5040.0
    p = p * s2 + 1.0 / 120.0
    p = p * s2 - 1.0 / 6.0
    return s + s * (s2 * p)


@register_jitable
def _equal_area_density(x: Float64Array, y: Float64Array, z: Float64Array) -> FloatArray:
    return _in_triangle(x, y, z) * T0_DENSITY


def _equal_area_inverse(p: Float64Array) -> Float64Array:
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    phi = np.clip(np.arctan2(y, x), 0.0, np.pi / 4)
    u = np.clip((phi - np.arcsin(np.sin(phi) / _SQRT2)) * T0_DENSITY, 0.0, 1.0)
    one_minus_cos = (x * x + y * y) / (1.0 + z)  # 1 - z for unit p, without cancellation
    v = np.clip(one_minus_cos / _one_minus_cos_theta_max(np.cos(phi)), 0.0, 1.0)
    return np.stack([u, v], axis=-1)


@register_jitable
def _paper1_point(u: Float64Array, v: Float64Array) -> tuple[Float64Array, Float64Array, Float64Array]:
    # Algorithm 1 as printed: phi = u pi/4, theta = arctan(v / cos phi).
    phi = u * (np.pi / 4)
    theta = np.arctan(v / np.cos(phi))
    return _clamped_into_t0(np.cos(phi) * np.sin(theta), np.sin(phi) * np.sin(theta), np.cos(theta))


@register_jitable
def _paper1_density(x: Float64Array, y: Float64Array, z: Float64Array) -> FloatArray:
    # (a, b) = (x/z, y/z) = (v, v tan phi): |J| = pi (x^2 + y^2) / (4 x z), d(omega) = z^3 da db,
    # so pdf = 4 x / (pi z^2 (x^2 + y^2)).
    return _vertex_singular_density(x, y, _in_triangle(x, y, z), 4.0, np.pi * z * z)


def _paper1_inverse(p: Float64Array) -> Float64Array:
    v = np.clip(np.divide(p[..., 0], p[..., 2]), 0.0, 1.0)
    return np.stack([_azimuth_to_u(p), v], axis=-1)


@register_jitable
def _paper2_point(u: Float64Array, v: Float64Array) -> tuple[Float64Array, Float64Array, Float64Array]:
    # Algorithm 2 as printed: phi = u pi/4, theta = v pi/4, P = N'_x x N'_y / |N'_x x N'_y|.
    phi = u * (np.pi / 4)
    theta = v * (np.pi / 4)
    sin_t, cos_t, cos_p = np.sin(theta), np.cos(theta), np.cos(phi)
    norm = np.sqrt(sin_t * sin_t + cos_t * cos_t * cos_p * cos_p)
    return _clamped_into_t0(sin_t * cos_p / norm, sin_t * np.sin(phi) / norm, cos_t * cos_p / norm)


@register_jitable
def _paper2_density(x: Float64Array, y: Float64Array, z: Float64Array) -> FloatArray:
    # (a, b) = (tan theta, tan theta tan phi): |J| = (pi/4)^2 (x^2+z^2)(x^2+y^2) / (x z^3),
    # so pdf = 16 x / (pi^2 (x^2 + z^2)(x^2 + y^2)).
    return _vertex_singular_density(x, y, _in_triangle(x, y, z), 16.0, np.pi**2 * (x * x + z * z))


def _paper2_inverse(p: Float64Array) -> Float64Array:
    v = np.clip(np.arctan2(p[..., 0], p[..., 2]) * (4 / np.pi), 0.0, 1.0)
    return np.stack([_azimuth_to_u(p), v], axis=-1)


@register_jitable
def _vertex_singular_density(
    x: Float64Array, y: Float64Array, inside: BoolArray, constant: float, smooth_factor: Float64Array
) -> FloatArray:
    """``constant x / (smooth_factor (x^2 + y^2))`` on T0, 0 outside, +inf at the vertex (0, 0, 1).

    Evaluated as ``constant cos(phi) / (smooth_factor r)`` with r = hypot(x, y), so
    that it neither underflows to 0/0 near the vertex nor loses digits.  At the
    vertex (r = 0, cos(phi) := 1) the division gives +inf, the density's limit from
    every side.  Outside T0, r and smooth_factor are shifted by 1 so that the
    product with ``inside = 0`` is 0, never 0 * inf.
    """
    outside = 1.0 - inside
    r: Float64Array = np.hypot(x, y) + outside  # (annotations only: no bytecode for numba)
    at_vertex: BoolArray = r == 0.0
    cos_phi = (x + at_vertex) / (r + at_vertex)
    return inside * (constant * cos_phi / ((smooth_factor + outside) * r))


_INVERSES = {"equal_area": _equal_area_inverse, "paper1": _paper1_inverse, "paper2": _paper2_inverse}
_POINTS = {"equal_area": _equal_area_point, "paper1": _paper1_point, "paper2": _paper2_point}
_DENSITIES = {"equal_area": _equal_area_density, "paper1": _paper1_density, "paper2": _paper2_density}
_REFERENCES = {
    "equal_area": "Arvo, Stratified sampling of spherical triangles, SIGGRAPH 1995, in closed form on T0",
    "paper1": "Dimov, Penzov, Stoilova, Algorithm 1 as printed",
    "paper2": "Dimov, Penzov, Stoilova, Algorithm 2 as printed",
}


def _triangle_warp_record(method: MapMethod) -> Warp:
    def forward(uv: npt.ArrayLike) -> FloatArray:
        return square_to_triangle(uv, method)

    def pdf(p: npt.ArrayLike) -> FloatArray:
        return square_to_triangle_pdf(p, method)

    def inverse(p: npt.ArrayLike) -> FloatArray:
        return triangle_to_square(p, method)

    return Warp(
        name=method,
        domain="triangle",
        uniform=method == "equal_area",
        orbit_size=48,
        forward=forward,
        pdf=pdf,
        inverse=inverse,
        point=_POINTS[method],
        density=_DENSITIES[method],
        reference=_REFERENCES[method],
    )


TRIANGLE_WARPS: dict[MapMethod, Warp] = {
    method: _triangle_warp_record(method) for method in ("equal_area", "paper1", "paper2")
}
"""dict method -> :class:`~symsphere.warps.Warp`: the maps onto T0, the choices of ``method=``."""
register(*TRIANGLE_WARPS.values())
METHODS: tuple[MapMethod, ...] = tuple(TRIANGLE_WARPS)
"""tuple of str: the names of the maps onto T0, the choices of ``method=``.

Only ``'equal_area'``, the default, is uniform; ``'paper1'`` and ``'paper2'`` are the paper's
Algorithms 1 and 2 as printed, with their exact densities (:func:`square_to_triangle_pdf`)."""
