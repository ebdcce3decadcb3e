"""Arvo's uniform sampling of a spherical triangle (SIGGRAPH 1995): forward, pdf, inverse.

Arvo's algorithm picks a sub-triangle A B C' of area u * area with C' on the
edge AC, then samples the arc from B to C' uniformly in cos of the distance to
B.  Applied to T0 with the vertices in the order (A, B, C) = ((0, 0, 1),
(1, 0, 1)/sqrt 2, (1, 1, 1)/sqrt 3) (:data:`T0_VERTICES`, as the ``arvo`` peer
uses them) the arcs start from (1, 0, 1)/sqrt 2: a different map with the same
(uniform) distribution as ``equal_area``.  With the order ((1, 0, 1)/sqrt 2,
(0, 0, 1), (1, 1, 1)/sqrt 3) the arcs start from the pole and the map *is*
``square_to_triangle(uv, 'equal_area')``, point by point (to 6e-16 in the tests):
``equal_area`` is Arvo's map in closed form.
"""

from __future__ import annotations

import math
from typing import Any, TypeAlias

import numpy as np
import numpy.typing as npt

from .._typing import Float64Array, FloatArray
from .._validation import check_directions, check_triangle, check_unit_directions, check_uv
from ._record import Warp
from ._registry import register

_Setup: TypeAlias = "tuple[Float64Array, Float64Array, Float64Array, float, float, float]"

__all__ = [
    "T0_VERTICES",
    "square_to_spherical_triangle",
    "spherical_triangle_to_square",
    "square_to_spherical_triangle_pdf",
    "square_to_arvo_triangle",
    "square_to_arvo_triangle_pdf",
    "arvo_triangle_to_square",
]

T0_VERTICES = np.array([[0.0, 0.0, 1.0], [2**-0.5, 0.0, 2**-0.5], [3**-0.5, 3**-0.5, 3**-0.5]])
"""float array (3, 3): the vertices A = (0, 0, 1), B = (1, 0, 1)/sqrt 2, C = (1, 1, 1)/sqrt 3 of T0."""
T0_VERTICES.setflags(write=False)


def square_to_spherical_triangle(uv: npt.ArrayLike, a: npt.ArrayLike, b: npt.ArrayLike, c: npt.ArrayLike) -> FloatArray:
    """Arvo's area-preserving map of the square onto a spherical triangle ABC.

    Arvo, "Stratified sampling of spherical triangles", SIGGRAPH 1995.
    u selects the sub-triangle A B C' of area u * area(ABC), with C' on the
    edge AC: the angle at A is alpha, and the area condition
    alpha + beta' + gamma' - pi = A' together with the spherical law of
    cosines gives ``cos(b') = |AC'|`` in closed form (the paper's q).  Then v
    places the point on the arc from B to C' with cos of its distance to B
    uniform on [C'.B, 1], which is uniform in area because the strip between
    two such arcs through B has area proportional to d(cos).

    Parameters
    ----------
    uv : array_like, shape (..., 2)
    a, b, c : array_like of 3 floats
        The vertices (normalised; the triangle must not be degenerate).
        B is the vertex the arcs of the second step start from; u = 0 is the
        edge AB, u = 1 the edge BC, v = 0 the vertex B, v = 1 the edge AC.

    Returns
    -------
    ndarray, shape (..., 3)
        Unit directions in the triangle, with density 1/area.

    Examples
    --------
    >>> from symsphere.warps import T0_VERTICES, square_to_spherical_triangle
    >>> A, B, C = T0_VERTICES
    >>> square_to_spherical_triangle([[0.7, 0.0], [0.0, 1.0], [1.0, 1.0]], A, B, C).round(12) + 0.0
    array([[0.70710678, 0.        , 0.70710678],
           [0.        , 0.        , 1.        ],
           [0.57735027, 0.57735027, 0.57735027]])
    """
    uv = check_uv(uv)
    setup = _triangle_setup(check_triangle(a, b, c))
    return _arvo_forward(uv.astype(np.float64), *setup).astype(uv.dtype, copy=False)


def spherical_triangle_to_square(d: npt.ArrayLike, a: npt.ArrayLike, b: npt.ArrayLike, c: npt.ArrayLike) -> FloatArray:
    """Inverse of :func:`square_to_spherical_triangle`.

    The arc from B through d meets the edge AC at C' (the intersection of
    the two great circles); u = area(A B C') / area(ABC) and
    v = (1 - d.B) / (1 - C'.B), both differences evaluated as ``|p - B|^2 / 2``.
    At d = B, u = 0 by convention.

    Parameters
    ----------
    d : array_like, shape (..., 3)
        Unit directions in the triangle.
    a, b, c : array_like of 3 floats

    Returns
    -------
    ndarray, shape (..., 2)
        Points of [0, 1]^2 that :func:`square_to_spherical_triangle` maps to *d* with the same
        vertices, in the dtype of *d*.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.warps import T0_VERTICES, spherical_triangle_to_square, square_to_spherical_triangle
    >>> uv = np.array([0.3, 0.6])
    >>> p = square_to_spherical_triangle(uv, *T0_VERTICES)
    >>> bool(np.allclose(spherical_triangle_to_square(p, *T0_VERTICES), uv))
    True
    """
    d = check_unit_directions(d, "d")
    setup = _triangle_setup(check_triangle(a, b, c))
    return _arvo_inverse(d.astype(np.float64), *setup).astype(d.dtype, copy=False)


def square_to_spherical_triangle_pdf(
    d: npt.ArrayLike, a: npt.ArrayLike, b: npt.ArrayLike, c: npt.ArrayLike
) -> Float64Array:
    """Density of :func:`square_to_spherical_triangle`: 1/area inside ABC, 0 outside.

    Inside means on the inner side of the three edges' great circles, with a
    tolerance of 1e-12.  The area is Van Oosterom & Strackee's
    ``2 atan2(|A.(B x C)|, 1 + A.B + B.C + C.A)``.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.warps import T0_VERTICES, square_to_spherical_triangle_pdf
    >>> square_to_spherical_triangle_pdf([[0.3, 0.2, 0.93273791], [0.0, 0.0, -1.0]], *T0_VERTICES) * np.pi
    array([12.,  0.])
    """
    d = check_directions(d, "d")
    verts = check_triangle(a, b, c)
    A, B, C = verts
    orient = np.sign(np.dot(A, np.cross(B, C)))
    d64 = d.astype(np.float64)
    inside = np.ones(d.shape[:-1], dtype=bool)
    for p, q in ((A, B), (B, C), (C, A)):
        inside &= orient * (d64 @ np.cross(p, q)) >= -1e-12
    return np.where(inside, 1.0 / _triangle_area(A, B, C), 0.0)


def square_to_arvo_triangle(uv: npt.ArrayLike) -> FloatArray:
    """Arvo's map onto T0: :func:`square_to_spherical_triangle` with ``T0_VERTICES`` as they are.

    The vertices are taken in the order A = (0, 0, 1), B = (1, 0, 1)/sqrt 2,
    C = (1, 1, 1)/sqrt 3 and not normalised again, so the result is bit for bit
    what the ``arvo`` peer's sampler gives.

    Examples
    --------
    >>> from symsphere.warps import square_to_arvo_triangle
    >>> square_to_arvo_triangle([[0.0, 0.0], [1.0, 1.0]]).round(6)
    array([[0.707107, 0.      , 0.707107],
           [0.57735 , 0.57735 , 0.57735 ]])
    """
    uv = check_uv(uv)
    return _arvo_forward(uv.astype(np.float64), *_T0_SETUP).astype(uv.dtype, copy=False)


def square_to_arvo_triangle_pdf(d: npt.ArrayLike) -> Float64Array:
    """Density of :func:`square_to_arvo_triangle`: 12/pi in T0, 0 outside.

    :func:`square_to_spherical_triangle_pdf` with ``T0_VERTICES``.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.warps import square_to_arvo_triangle_pdf
    >>> square_to_arvo_triangle_pdf([[0.3, 0.2, 0.93273791], [0.0, 0.0, -1.0]]) * np.pi
    array([12.,  0.])
    """
    return square_to_spherical_triangle_pdf(d, *T0_VERTICES)


def arvo_triangle_to_square(d: npt.ArrayLike) -> FloatArray:
    """Inverse of :func:`square_to_arvo_triangle`: :func:`spherical_triangle_to_square` with ``T0_VERTICES``.

    Examples
    --------
    >>> from symsphere.warps import T0_VERTICES, arvo_triangle_to_square
    >>> arvo_triangle_to_square(T0_VERTICES)   # A; B (u = 0 by convention); C
    array([[0., 1.],
           [0., 0.],
           [1., 1.]])
    """
    d = check_unit_directions(d, "d")
    return _arvo_inverse(d.astype(np.float64), *_T0_SETUP).astype(d.dtype, copy=False)


# --- private helpers: trust their inputs ------------------------------------------


def _triangle_area(A: Float64Array, B: Float64Array, C: Float64Array) -> float:
    # Van Oosterom & Strackee (1983): tan(E/2) = |A.(B x C)| / (1 + A.B + B.C + C.A).
    return 2.0 * math.atan2(abs(float(np.dot(A, np.cross(B, C)))), float(1.0 + A @ B + B @ C + C @ A))


def _unit(v: Float64Array) -> Float64Array:
    unit: Float64Array = v / np.linalg.norm(v, axis=-1, keepdims=True)
    return unit


def _triangle_setup(verts: Any) -> _Setup:
    """Per-triangle constants of Arvo's algorithm: vertices, alpha, cos c, area."""
    A, B, C = (np.asarray(v, dtype=np.float64) for v in verts)
    # Angle at A between the arcs AB and AC, from the tangent vectors at A.
    tb, tc = B - (A @ B) * A, C - (A @ C) * A
    alpha = math.atan2(float(np.linalg.norm(np.cross(tb, tc))), float(tb @ tc))
    return A, B, C, alpha, float(A @ B), _triangle_area(A, B, C)


def _arvo_forward(
    uv: Float64Array, A: Float64Array, B: Float64Array, C: Float64Array, alpha: float, cos_c: float, area: float
) -> Float64Array:
    # Arvo (1995), Fig. 2: the sub-triangle A B C' of area A' = u * area has
    #   q = cos|AC'| = [cos c (t cos(alpha) - 1) - s sin(alpha)] / D,
    #   D = 1 - t cos(alpha) + s sin(alpha) cos c,  (s, t) = (sin, cos)(A' - alpha)
    # (the paper's q with its common factor sin(alpha) cancelled).  Near A, q -> 1
    # and sqrt(1 - q^2) would lose half the digits, so we use the exact factorisations
    #   1 - q = (1 + cos c)(1 - cos A') / D,
    #   1 + q = (1 - cos c)(1 - cos(A' - 2 alpha)) / D,
    #   D = 2 sin^2(A'/2) - sin(A' - alpha) sin(alpha) (1 - cos c),
    # hence sin|AC'| = 2 sin c |sin(A'/2) sin(A'/2 - alpha)| / D.
    area_hat = uv[..., 0] * area
    half = 0.5 * area_hat
    sin_a = math.sin(alpha)
    one_minus_cos_c = 0.5 * float(np.sum((A - B) ** 2))
    sin_c = float(np.linalg.norm(np.cross(A, B)))
    sin_half = np.sin(half)
    denom = 2.0 * sin_half**2 - np.sin(area_hat - alpha) * sin_a * one_minus_cos_c
    cos_b = 1.0 - (1.0 + cos_c) * 2.0 * sin_half**2 / denom
    sin_b = 2.0 * sin_c * np.abs(sin_half * np.sin(half - alpha)) / denom
    c_perp = _unit(C - (C @ A) * A)
    c_hat = _unit(cos_b[..., None] * A + sin_b[..., None] * c_perp)
    # ... then cos of the distance to B uniform on [C'.B, 1]: w = 1 - cos = v (1 - C'.B).
    one_minus_cb = 0.5 * np.sum((c_hat - B) ** 2, axis=-1)
    w = uv[..., 1] * one_minus_cb
    sin_d = np.sqrt(np.maximum(w * (2.0 - w), 0.0))
    tangent = c_hat - np.sum(c_hat * B, axis=-1, keepdims=True) * B
    # When C' is nearly antipodal to B (a triangle of nearly a hemisphere), the tangent is short and,
    # normalised, off orthogonal to B by eps / |tangent| (|d| - 1 was 2e-12): orthogonalise it once more.
    norm = np.linalg.norm(tangent, axis=-1, keepdims=True)
    tangent = tangent / np.where(norm > 0, norm, 1.0)
    tangent = tangent - np.sum(tangent * B, axis=-1, keepdims=True) * B
    norm = np.linalg.norm(tangent, axis=-1, keepdims=True)
    tangent = tangent / np.where(norm > 0, norm, 1.0)
    d: Float64Array = (1.0 - w)[..., None] * B + sin_d[..., None] * tangent
    return d


def _arvo_inverse(
    d: Float64Array, A: Float64Array, B: Float64Array, C: Float64Array, alpha: float, cos_c: float, area: float
) -> Float64Array:
    d = _unit(d)
    m = np.cross(B, d)  # normal of the great circle through B and d
    n_ac = np.cross(A, C)
    c_hat = np.cross(m, n_ac)
    norm = np.linalg.norm(c_hat, axis=-1, keepdims=True)
    at_b = norm[..., 0] == 0
    c_hat = c_hat / np.where(norm > 0, norm, 1.0)
    # Of the two antipodal intersections, C' is the one on the arc AC.
    c_hat = np.where((c_hat @ (A + C))[..., None] < 0, -c_hat, c_hat)
    # When B lies close to the great circle AC (a sliver), m and A x C are nearly parallel: their cross
    # product is short and, normalised, carries an error of eps / |m x n_ac| in every direction,
    # off the circle AC too, which the sub-triangle's area (of the sliver's width) magnifies (8e-4 in u
    # for a 1e-7 sr sliver).  Its angle along AC is what the intersection determines; put C' back on
    # the circle there.
    c_perp = _unit(C - (C @ A) * A)
    s = np.arctan2(c_hat @ c_perp, c_hat @ A)
    c_hat = np.cos(s)[..., None] * A + np.sin(s)[..., None] * c_perp
    triple = np.abs(np.cross(B, c_hat) @ A)
    sub_area = 2.0 * np.arctan2(triple, 1.0 + A @ B + c_hat @ B + c_hat @ A)
    u = np.where(at_b, 0.0, sub_area / area)
    one_minus_cb = 0.5 * np.sum((c_hat - B) ** 2, axis=-1)
    one_minus_db = 0.5 * np.sum((d - B) ** 2, axis=-1)
    v = np.where(at_b, 0.0, one_minus_db / np.where(at_b, 1.0, one_minus_cb))
    uv: Float64Array = np.clip(np.stack([u, v], axis=-1), 0.0, 1.0)
    return uv


_T0_SETUP = _triangle_setup(T0_VERTICES)

register(
    Warp(name="arvo_triangle", domain="triangle", uniform=True, orbit_size=48, forward=square_to_arvo_triangle,
         pdf=square_to_arvo_triangle_pdf, inverse=arvo_triangle_to_square,
         reference="Arvo, Stratified sampling of spherical triangles, SIGGRAPH 1995"),
)  # fmt: skip
