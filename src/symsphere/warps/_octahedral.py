"""Clarberg's equal-area octahedral maps of the square onto the sphere and the hemisphere (JGT 2008).

Derivation.  With (a, b) = 2 (u, v) - 1 the square is an unfolded octahedron: the diamond
``|a| + |b| <= 1`` is the upper hemisphere, the four corner triangles fold onto the lower one.
In each octant the L1 "radius" r (``|a| + |b|`` inside the diamond, ``2 - |a| - |b|`` outside)
sets ``1 - |z| = r^2``, which is equal-area because the area of a triangle with legs r grows
like r^2 and the polar cap like ``1 - |z|``; the position along the octant's edge, linear in
the square, sets the azimuth linearly.  So every octant of the square (area 1/8) goes to an
octant of the sphere (area pi/2): density 1/(4 pi).  The hemisphere variant turns the square
by 45 degrees onto the diamond (constant Jacobian 1/2) and lifts it: density 1/(2 pi).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt
from numba.extending import register_jitable

from .._typing import Float64Array, FloatArray
from ._common import checked_forward, checked_inverse, elementwise, on_rows, pick
from ._record import Warp
from ._registry import register
from ._uniform import square_to_uniform_hemisphere_pdf, square_to_uniform_sphere_pdf

__all__ = [
    "square_to_octahedral_sphere",
    "square_to_octahedral_sphere_pdf",
    "octahedral_sphere_to_square",
    "octahedral_sphere_point",
    "square_to_octahedral_hemisphere",
    "square_to_octahedral_hemisphere_pdf",
    "octahedral_hemisphere_to_square",
]


# --- the sphere ---------------------------------------------------------------------------


def square_to_octahedral_sphere(uv: npt.ArrayLike) -> FloatArray:
    """Clarberg's equal-area map of the square onto the sphere (JGT 2008).

    See the module docstring for the derivation; sin(theta) = r sqrt(2 - r^2),
    without cancellation.

    Parameters
    ----------
    uv : array_like, shape (..., 2)
        Points of [0, 1]^2; the centre (0.5, 0.5) goes to the pole (0, 0, 1).

    Returns
    -------
    ndarray, shape (..., 3)
        Unit directions, uniform for uniform *uv*.

    Examples
    --------
    >>> from symsphere.warps import square_to_octahedral_sphere
    >>> square_to_octahedral_sphere([[0.5, 0.5], [1.0, 0.5], [0.0, 0.0]])
    array([[ 0.,  0.,  1.],
           [ 1.,  0.,  0.],
           [-0., -0., -1.]])
    """
    return checked_forward(_octahedral_sphere, uv)


def square_to_octahedral_sphere_pdf(d: npt.ArrayLike) -> Float64Array:
    """The density of :func:`square_to_octahedral_sphere`: 1/(4 pi), of shape ``d.shape[:-1]``.

    Examples
    --------
    >>> from symsphere.warps import square_to_octahedral_sphere_pdf
    >>> float(square_to_octahedral_sphere_pdf([0.0, 0.0, -1.0]) * 4 * 3.141592653589793)
    1.0
    """
    return square_to_uniform_sphere_pdf(d)  # the map is equal-area


def octahedral_sphere_to_square(d: npt.ArrayLike) -> FloatArray:
    """Inverse of :func:`square_to_octahedral_sphere`.

    ``r = sqrt(1 - |z|)``, evaluated as ``sqrt((x^2 + y^2) / (1 + |z|))``; the share
    of the octant's edge is ``(2/pi) atan2(|y|, |x|)``; the signs of x and y pick
    the quadrant of the square, the sign of z the diamond or a corner.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.warps import octahedral_sphere_to_square, square_to_octahedral_sphere
    >>> uv = np.array([[0.1, 0.8], [0.6, 0.3]])
    >>> bool(np.allclose(octahedral_sphere_to_square(square_to_octahedral_sphere(uv)), uv))
    True
    """
    return checked_inverse(_octahedral_sphere_inverse, d)


@register_jitable
def _octant_lift(p: Any, q: Any, upper: Any) -> Any:
    """Lift the octant point with L1 coordinates (p, q) >= 0, r = p + q <= 1.

    1 - |z| = r^2; azimuth within the quadrant phi = (pi/2) q/r, written as
    cos(phi) = sin((pi/2) p/r), sin(phi) = sin((pi/2) q/r) so that the axes
    (p = 0 or q = 0) come out exactly.  Returns |x|, |y|, z.
    """
    r = p + q
    safe = pick(r > 0, r, 1.0)
    sin_theta = r * np.sqrt(np.maximum(2.0 - r * r, 0.0))
    ax = sin_theta * np.sin(0.5 * np.pi * p / safe)
    ay = sin_theta * np.sin(0.5 * np.pi * q / safe)
    z = pick(upper, 1.0 - r * r, r * r - 1.0)
    return ax, ay, z


@elementwise()
def octahedral_sphere_point(u: Any, v: Any) -> tuple[Any, Any, Any]:
    """Elementwise :func:`square_to_octahedral_sphere`: (u, v) to (x, y, z); numba compiles it.

    Scalars or arrays (broadcasting together) of [0, 1] in, checked as for
    :func:`symsphere.warps.uniform_sphere_point` (inside a numba kernel: not checked).

    Examples
    --------
    >>> from symsphere.warps import octahedral_sphere_point
    >>> [float(c) for c in octahedral_sphere_point(1.0, 0.5)]
    [1.0, 0.0, 0.0]
    """
    # The inner diamond goes onto the upper hemisphere; the corner triangles fold below.
    a = 2.0 * u - 1.0
    b = 2.0 * v - 1.0
    aa, ab = np.abs(a), np.abs(b)
    upper = aa + ab <= 1.0
    # Outside the diamond the L1 coordinates of the fold are (1 - |b|, 1 - |a|).
    p = pick(upper, aa, 1.0 - ab)
    q = pick(upper, ab, 1.0 - aa)
    ax, ay, z = _octant_lift(p, q, upper)
    return np.copysign(ax, a), np.copysign(ay, b), z


_octahedral_sphere = on_rows(octahedral_sphere_point)


def _octant_unlift(d: Float64Array) -> tuple[Float64Array, Float64Array, npt.NDArray[np.bool_]]:
    """(p, q, upper) of unit directions: the inverse of :func:`_octant_lift`."""
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    ax, ay = np.abs(x), np.abs(y)
    r = np.sqrt((ax * ax + ay * ay) / (1.0 + np.abs(z)))  # sqrt(1 - |z|)
    r = np.minimum(r, 1.0)
    p = r * np.arctan2(ax, ay) * (2.0 / np.pi)
    q = r * np.arctan2(ay, ax) * (2.0 / np.pi)
    return p, q, z >= 0


def _octahedral_sphere_inverse(d: Float64Array) -> Float64Array:
    p, q, upper = _octant_unlift(d)
    aa = np.where(upper, p, 1.0 - q)
    ab = np.where(upper, q, 1.0 - p)
    a = np.copysign(aa, d[..., 0])
    b = np.copysign(ab, d[..., 1])
    return np.clip(np.stack([0.5 * (a + 1.0), 0.5 * (b + 1.0)], axis=-1), 0.0, 1.0)


register(
    Warp(name="octahedral_sphere", domain="sphere", uniform=True, forward=square_to_octahedral_sphere,
         pdf=square_to_octahedral_sphere_pdf, inverse=octahedral_sphere_to_square, point=octahedral_sphere_point,
         reference="Clarberg, Fast equal-area mapping of the (hemi)sphere using SIMD, JGT 2008"),
)  # fmt: skip


# --- the hemisphere -----------------------------------------------------------------------


def square_to_octahedral_hemisphere(uv: npt.ArrayLike) -> FloatArray:
    """Clarberg's equal-area map of the square onto the hemisphere z >= 0.

    The square [-1, 1]^2 is turned by 45 degrees and shrunk onto the diamond
    ``|a'| + |b'| <= 1`` (a' = (a + b)/2, b' = (b - a)/2, a constant Jacobian of
    1/2), which the upper half of :func:`square_to_octahedral_sphere` lifts
    onto the hemisphere: density 1/(2 pi).

    Examples
    --------
    >>> from symsphere.warps import square_to_octahedral_hemisphere
    >>> square_to_octahedral_hemisphere([[0.5, 0.5], [1.0, 1.0]])
    array([[0., 0., 1.],
           [1., 0., 0.]])
    """
    return checked_forward(_octahedral_hemisphere, uv)


def square_to_octahedral_hemisphere_pdf(d: npt.ArrayLike) -> Float64Array:
    """The density of :func:`square_to_octahedral_hemisphere`: 1/(2 pi) for z >= 0, 0 below.

    Examples
    --------
    >>> from symsphere.warps import square_to_octahedral_hemisphere_pdf
    >>> square_to_octahedral_hemisphere_pdf([[0.0, 0.6, 0.8], [0.0, 0.6, -0.8]]) * 2 * 3.141592653589793
    array([1., 0.])
    """
    return square_to_uniform_hemisphere_pdf(d)  # the map is equal-area


def octahedral_hemisphere_to_square(d: npt.ArrayLike) -> FloatArray:
    """Inverse of :func:`square_to_octahedral_hemisphere`.

    Examples
    --------
    >>> from symsphere.warps import octahedral_hemisphere_to_square
    >>> octahedral_hemisphere_to_square([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])   # the pole; a corner
    array([[0.5, 0.5],
           [1. , 1. ]])
    """
    return checked_inverse(_octahedral_hemisphere_inverse, d, hemisphere=True)


def _octahedral_hemisphere(uv: Float64Array) -> Float64Array:
    # Turn the square [-1, 1]^2 by 45 degrees onto the diamond, then lift the upper half.
    a = 2.0 * uv[..., 0] - 1.0
    b = 2.0 * uv[..., 1] - 1.0
    s, t = 0.5 * (a + b), 0.5 * (b - a)
    ax, ay, z = _octant_lift(np.abs(s), np.abs(t), True)
    return np.stack([np.copysign(ax, s), np.copysign(ay, t), z], axis=-1)


def _octahedral_hemisphere_inverse(d: Float64Array) -> Float64Array:
    p, q, _ = _octant_unlift(d)
    s = np.copysign(p, d[..., 0])
    t = np.copysign(q, d[..., 1])
    a, b = s - t, s + t
    return np.clip(np.stack([0.5 * (a + 1.0), 0.5 * (b + 1.0)], axis=-1), 0.0, 1.0)


register(
    Warp(name="octahedral_hemisphere", domain="hemisphere", uniform=True, forward=square_to_octahedral_hemisphere,
         pdf=square_to_octahedral_hemisphere_pdf, inverse=octahedral_hemisphere_to_square,
         reference="Clarberg, JGT 2008 (hemisphere variant)"),
)  # fmt: skip
