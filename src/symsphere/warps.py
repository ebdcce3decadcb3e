"""The peers' maps of the unit square, each a triple side by side: forward, pdf (solid angle), inverse.

As pbrt-v4's ``util/sampling.h`` and Mitsuba 3's ``core/warp.h`` hold them:
``square_to_*`` maps points of [0, 1]^2 onto the domain, ``*_to_square`` is its
exact inverse, ``*_pdf`` the density with respect to solid angle.  The samplers of
:mod:`symsphere.peers` are these maps applied to base points.

===================================== ========================================================
map                                   what
===================================== ========================================================
``square_to_uniform_sphere``          z = 1 - 2u, phi = 2 pi v (Archimedes' hat-box map)
``square_to_uniform_hemisphere``      z = u, phi = 2 pi v
``square_to_octahedral_sphere``       Clarberg's equal-area octahedral map (JGT 2008)
``square_to_octahedral_hemisphere``   its hemisphere variant (the square turned 45 deg)
``square_to_concentric_disk``         Shirley & Chiu (1997), onto the unit disk
``square_to_cosine_hemisphere``       the concentric disk lifted by Malley's method: cos(theta)/pi
===================================== ========================================================

Every map is exact and has no NaN or inf for u, v in {0, 1}, in float64 and
float32.  The uniform, concentric-disk and cosine maps are also written as
elementwise functions of (u, v) (``uniform_sphere_point``, ...) that numba
compiles: the path tracer calls the same formulas.  Arvo's map onto any spherical
triangle is in :mod:`symsphere.spherical_triangles`.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from ._typing import Float64Array, FloatArray
from ._validation import as_float_array, check_directions, check_real_arrays, check_unit_directions, check_uv

__all__ = [
    "square_to_uniform_sphere",
    "uniform_sphere_to_square",
    "uniform_sphere_pdf",
    "square_to_uniform_hemisphere",
    "uniform_hemisphere_to_square",
    "uniform_hemisphere_pdf",
    "square_to_octahedral_sphere",
    "octahedral_sphere_to_square",
    "square_to_octahedral_hemisphere",
    "octahedral_hemisphere_to_square",
    "square_to_concentric_disk",
    "concentric_disk_to_square",
    "square_to_cosine_hemisphere",
    "cosine_hemisphere_to_square",
    "cosine_hemisphere_pdf",
    "uniform_sphere_point",
    "uniform_hemisphere_point",
    "concentric_disk_point",
    "cosine_hemisphere_point",
]

_INV_4PI = 1.0 / (4.0 * math.pi)
_INV_2PI = 1.0 / (2.0 * math.pi)


def square_to_uniform_sphere(uv: npt.ArrayLike) -> FloatArray:
    """Map the unit square onto the sphere: z = 1 - 2u, phi = 2 pi v.

    Archimedes' hat-box theorem: the area of the zone below height z is
    proportional to z, so a uniform z and a uniform phi give a uniform
    direction.  The radius sin(theta) = 2 sqrt(u (1 - u)), which does not
    cancel near the poles as sqrt(1 - z^2) does.

    Parameters
    ----------
    uv : array_like, shape (..., 2)
        Points of [0, 1]^2.

    Returns
    -------
    ndarray, shape (..., 3)
        Unit directions, in the dtype of *uv* (float64 for integers).

    Examples
    --------
    >>> from symsphere.peers import square_to_uniform_sphere
    >>> square_to_uniform_sphere([[0.0, 0.0], [0.5, 0.0], [1.0, 0.0]])
    array([[ 0.,  0.,  1.],
           [ 1.,  0.,  0.],
           [ 0.,  0., -1.]])
    """
    return _public_forward(_uniform_sphere, uv)


def uniform_sphere_to_square(d: npt.ArrayLike) -> FloatArray:
    """Inverse of :func:`square_to_uniform_sphere`.

    ``u = (1 - z)/2``, evaluated as ``(x^2 + y^2) / (2 (1 + z))`` for z > 0
    (no cancellation near the north pole); ``v = atan2(y, x) / (2 pi)``
    wrapped into [0, 1).  At the poles v = 0.

    Parameters
    ----------
    d : array_like, shape (..., 3)
        Unit directions.

    Returns
    -------
    ndarray, shape (..., 2)

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import square_to_uniform_sphere, uniform_sphere_to_square
    >>> uv = np.array([0.2, 0.7])
    >>> bool(np.allclose(uniform_sphere_to_square(square_to_uniform_sphere(uv)), uv))
    True
    """
    return _public_inverse(_uniform_sphere_inverse, d)


def uniform_sphere_pdf(d: npt.ArrayLike) -> Float64Array:
    """The uniform density on the sphere, 1/(4 pi), of shape ``d.shape[:-1]``.

    Examples
    --------
    >>> from symsphere.peers import uniform_sphere_pdf
    >>> float(uniform_sphere_pdf([0.0, 0.0, 1.0]) * 4 * 3.141592653589793)
    1.0
    """
    d = check_directions(d, "d")
    return np.full(d.shape[:-1], _INV_4PI)


def square_to_uniform_hemisphere(uv: npt.ArrayLike) -> FloatArray:
    """Map the unit square onto the hemisphere z >= 0: z = u, phi = 2 pi v.

    sin(theta) = sqrt((1 - u)(1 + u)).  pbrt-v4 ``SampleUniformHemisphere``.

    Examples
    --------
    >>> from symsphere.peers import square_to_uniform_hemisphere
    >>> square_to_uniform_hemisphere([[0.0, 0.25], [1.0, 0.0]])
    array([[6.123234e-17, 1.000000e+00, 0.000000e+00],
           [0.000000e+00, 0.000000e+00, 1.000000e+00]])
    """
    return _public_forward(_uniform_hemisphere, uv)


def uniform_hemisphere_to_square(d: npt.ArrayLike) -> FloatArray:
    """Inverse of :func:`square_to_uniform_hemisphere`: u = z, v = phi / (2 pi).

    Examples
    --------
    >>> from symsphere.peers import uniform_hemisphere_to_square
    >>> uniform_hemisphere_to_square([0.0, -1.0, 0.0])
    array([0.  , 0.75])
    """
    return _public_inverse(_uniform_hemisphere_inverse, d, hemisphere=True)


def uniform_hemisphere_pdf(d: npt.ArrayLike) -> Float64Array:
    """The uniform density on the hemisphere z >= 0: 1/(2 pi) there, 0 below.

    Examples
    --------
    >>> from symsphere.peers import uniform_hemisphere_pdf
    >>> uniform_hemisphere_pdf([[0.0, 0.6, 0.8], [0.0, 0.6, -0.8]]) * 2 * 3.141592653589793
    array([1., 0.])
    """
    d = check_directions(d, "d")
    return np.where(d[..., 2] >= 0, _INV_2PI, 0.0)


def square_to_octahedral_sphere(uv: npt.ArrayLike) -> FloatArray:
    """Clarberg's equal-area map of the square onto the sphere (JGT 2008).

    With (a, b) = 2 (u, v) - 1, the square is an unfolded octahedron: the
    diamond ``|a| + |b| <= 1`` is the upper hemisphere, the four corner triangles
    fold onto the lower one.  In each octant the L1 "radius" r (``|a| + |b|``
    inside the diamond, ``2 - |a| - |b|`` outside) sets ``1 - |z| = r^2``, which is
    equal-area because the area of a triangle with legs r grows like r^2 and
    the polar cap like ``1 - |z|``; the position along the octant's edge,
    linear in the square, sets the azimuth linearly.  So every octant of the
    square (area 1/8) goes to an octant of the sphere (area pi/2): the
    density is 1/(4 pi).  sin(theta) = r sqrt(2 - r^2), without cancellation.

    Parameters
    ----------
    uv : array_like, shape (..., 2)

    Returns
    -------
    ndarray, shape (..., 3)

    Examples
    --------
    >>> from symsphere.peers import square_to_octahedral_sphere
    >>> square_to_octahedral_sphere([[0.5, 0.5], [1.0, 0.5], [0.0, 0.0]])
    array([[ 0.,  0.,  1.],
           [ 1.,  0.,  0.],
           [-0., -0., -1.]])
    """
    return _public_forward(_octahedral_sphere, uv)


def octahedral_sphere_to_square(d: npt.ArrayLike) -> FloatArray:
    """Inverse of :func:`square_to_octahedral_sphere`.

    ``r = sqrt(1 - |z|)``, evaluated as ``sqrt((x^2 + y^2) / (1 + |z|))``; the share
    of the octant's edge is ``(2/pi) atan2(|y|, |x|)``; the signs of x and y pick
    the quadrant of the square, the sign of z the diamond or a corner.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import octahedral_sphere_to_square, square_to_octahedral_sphere
    >>> uv = np.array([[0.1, 0.8], [0.6, 0.3]])
    >>> bool(np.allclose(octahedral_sphere_to_square(square_to_octahedral_sphere(uv)), uv))
    True
    """
    return _public_inverse(_octahedral_sphere_inverse, d)


def square_to_octahedral_hemisphere(uv: npt.ArrayLike) -> FloatArray:
    """Clarberg's equal-area map of the square onto the hemisphere z >= 0.

    The square [-1, 1]^2 is turned by 45 degrees and shrunk onto the diamond
    ``|a'| + |b'| <= 1`` (a' = (a + b)/2, b' = (b - a)/2, a constant Jacobian of
    1/2), which the upper half of :func:`square_to_octahedral_sphere` lifts
    onto the hemisphere: density 1/(2 pi).

    Examples
    --------
    >>> from symsphere.peers import square_to_octahedral_hemisphere
    >>> square_to_octahedral_hemisphere([[0.5, 0.5], [1.0, 1.0]])
    array([[0., 0., 1.],
           [1., 0., 0.]])
    """
    return _public_forward(_octahedral_hemisphere, uv)


def octahedral_hemisphere_to_square(d: npt.ArrayLike) -> FloatArray:
    """Inverse of :func:`square_to_octahedral_hemisphere`.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import octahedral_hemisphere_to_square, square_to_octahedral_hemisphere
    >>> uv = np.array([0.3, 0.9])
    >>> bool(np.allclose(octahedral_hemisphere_to_square(square_to_octahedral_hemisphere(uv)), uv))
    True
    """
    return _public_inverse(_octahedral_hemisphere_inverse, d, hemisphere=True)


def square_to_concentric_disk(uv: npt.ArrayLike) -> FloatArray:
    """Shirley & Chiu's concentric map of the square onto the unit disk (1997).

    With (a, b) = 2 (u, v) - 1, concentric squares go to concentric circles:
    if ``|a| >= |b|``, radius a and angle (pi/4)(b/a); else radius b and angle
    pi/2 - (pi/4)(a/b).  Each of the four triangular sectors is stretched
    uniformly, so the map is area-preserving up to the constant pi/4 per unit
    square area: density 1/pi on the disk.

    Parameters
    ----------
    uv : array_like, shape (..., 2)

    Returns
    -------
    ndarray, shape (..., 2)
        Points of the unit disk.

    Examples
    --------
    >>> from symsphere.peers import square_to_concentric_disk
    >>> square_to_concentric_disk([[0.5, 0.5], [1.0, 0.5], [0.5, 0.0]])
    array([[ 0.,  0.],
           [ 1.,  0.],
           [ 0., -1.]])
    """
    uv = check_uv(uv)
    return _concentric(uv.astype(np.float64)).astype(uv.dtype, copy=False)


def concentric_disk_to_square(p: npt.ArrayLike) -> FloatArray:
    """Inverse of :func:`square_to_concentric_disk`.

    Parameters
    ----------
    p : array_like, shape (..., 2)
        Points of the closed unit disk.

    Returns
    -------
    ndarray, shape (..., 2)

    Examples
    --------
    >>> from symsphere.peers import concentric_disk_to_square
    >>> concentric_disk_to_square([[0.0, 0.0], [0.0, 1.0]])
    array([[0.5, 0.5],
           [0.5, 1. ]])
    """
    arr = as_float_array(p, "p")
    if arr.ndim == 0 or arr.shape[-1] != 2:
        raise ValueError(f"'p' must have shape (..., 2), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError("'p' must be finite (no NaN or inf)")
    a64 = arr.astype(np.float64)
    if np.any(np.hypot(a64[..., 0], a64[..., 1]) > 1 + 1e-6):
        raise ValueError("'p' must lie in the closed unit disk")
    return _concentric_inverse(a64).astype(arr.dtype, copy=False)


def square_to_cosine_hemisphere(uv: npt.ArrayLike) -> FloatArray:
    """Cosine-weighted hemisphere: the concentric disk lifted by Malley's method.

    A uniform point (x, y) of the unit disk, lifted vertically to
    z = sqrt(1 - x^2 - y^2), has density (1/pi) cos(theta) in solid angle,
    since the projection onto the disk scales area by cos(theta)
    (Malley's method; pbrt-v4 ``SampleCosineHemisphere``).  z is evaluated
    as sqrt((1 - rho)(1 + rho)), rho = ``max(|a|, |b|)`` the disk radius.

    Examples
    --------
    >>> from symsphere.peers import square_to_cosine_hemisphere
    >>> square_to_cosine_hemisphere([[0.5, 0.5], [1.0, 0.5]])
    array([[0., 0., 1.],
           [1., 0., 0.]])
    """
    return _public_forward(_cosine_hemisphere, uv)


def cosine_hemisphere_to_square(d: npt.ArrayLike) -> FloatArray:
    """Inverse of :func:`square_to_cosine_hemisphere`: drop z, invert the disk map.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import cosine_hemisphere_to_square, square_to_cosine_hemisphere
    >>> uv = np.array([0.15, 0.65])
    >>> bool(np.allclose(cosine_hemisphere_to_square(square_to_cosine_hemisphere(uv)), uv))
    True
    """
    return _public_inverse(_cosine_hemisphere_inverse, d, hemisphere=True)


def cosine_hemisphere_pdf(d: npt.ArrayLike) -> Float64Array:
    """Density cos(theta)/pi of :func:`square_to_cosine_hemisphere`; 0 for z < 0.

    Examples
    --------
    >>> from symsphere.peers import cosine_hemisphere_pdf
    >>> cosine_hemisphere_pdf([[0.0, 0.0, 1.0], [0.6, 0.0, -0.8]]) * 3.141592653589793
    array([1., 0.])
    """
    d = check_unit_directions(d, "d")
    d64 = d.astype(np.float64)
    return np.maximum(d64[..., 2], 0.0) / (np.linalg.norm(d64, axis=-1) * math.pi)


# =============================================================================
# Private helpers: trust their inputs (float64 arrays)
# =============================================================================


def _public_forward(forward, uv):
    uv = check_uv(uv)
    return forward(uv.astype(np.float64)).astype(uv.dtype, copy=False)


def _public_inverse(inverse, d, hemisphere=False):
    d = check_unit_directions(d, "d")  # a zero or non-unit vector would map to NaN or a wrong point
    d64 = d.astype(np.float64)
    if hemisphere and np.any(d64[..., 2] < -1e-12):
        raise ValueError("'d' must have z >= 0 (directions of the hemisphere about (0, 0, 1))")
    return inverse(d64).astype(d.dtype, copy=False)


def _wrap_unit(t):
    """Fold t into [0, 1): -0.25 -> 0.75, and 1 - tiny rounding to 1 -> 0."""
    t = np.where(t < 0, t + 1.0, t)
    return np.where(t >= 1.0, 0.0, t)


# --- elementwise formulas -------------------------------------------------------------
# Each map below is written once, as an elementwise function of (u, v) that numpy applies to
# arrays and numba compiles for scalars (``register_jitable``): the path tracer's kernels
# (symsphere.render._integrator) call the very same formulas.  ``_pick`` is np.where for
# arrays and a conditional expression in numba.

from numba.extending import overload as _overload  # noqa: E402
from numba.extending import register_jitable as _register_jitable  # noqa: E402


def _pick(condition, a, b):
    """``np.where(condition, a, b)``; in numba code, ``a if condition else b`` (scalars)."""
    return np.where(condition, a, b)


@_overload(_pick)
def _pick_scalar(condition, a, b):
    def impl(condition, a, b):
        return a if condition else b

    return impl


@_register_jitable
def _uniform_sphere_point(u, v):
    """Elementwise: pbrt-v4 / Mitsuba, z = 1 - 2u, r = sqrt(1 - z^2) = 2 sqrt(u (1 - u)), phi = 2 pi v.

    Scalars or arrays in, a tuple (x, y, z) out; numba compiles it (``register_jitable``).

    Examples
    --------
    >>> from symsphere.warps import uniform_sphere_point
    >>> [round(float(c), 6) for c in uniform_sphere_point(0.25, 0.5)]
    [-0.866025, 0.0, 0.5]
    """
    z = 1.0 - 2.0 * u
    r = 2.0 * np.sqrt(u * (1.0 - u))
    phi = 2.0 * np.pi * v
    return r * np.cos(phi), r * np.sin(phi), z


@_register_jitable
def _uniform_hemisphere_point(u, v):
    """Elementwise: z = u, r = sqrt((1 - u)(1 + u)), phi = 2 pi v (pbrt-v4 SampleUniformHemisphere).

    Examples
    --------
    >>> from symsphere.warps import uniform_hemisphere_point
    >>> [round(float(c), 6) for c in uniform_hemisphere_point(0.5, 0.25)]
    [0.0, 0.866025, 0.5]
    """
    r = np.sqrt((1.0 - u) * (1.0 + u))
    phi = 2.0 * np.pi * v
    return r * np.cos(phi), r * np.sin(phi), u


@_register_jitable
def _concentric_disk_point(u, v):
    """Elementwise Shirley & Chiu (1997): concentric squares of [0, 1]^2 -> concentric circles of the disk.

    Examples
    --------
    >>> from symsphere.warps import concentric_disk_point
    >>> [float(c) for c in concentric_disk_point(1.0, 0.5)]
    [1.0, 0.0]
    """
    a = 2.0 * u - 1.0
    b = 2.0 * v - 1.0
    wide = np.abs(a) >= np.abs(b)
    r = _pick(wide, a, b)
    safe = _pick(r != 0, r, 1.0)
    # angle (pi/4)(b/a) in the wide sectors, pi/2 - (pi/4)(a/b) in the others:
    # x = r cos, y = r sin; for the others cos(pi/2 - t) = sin t.
    t = 0.25 * np.pi * _pick(wide, b, a) / safe
    c, s = np.cos(t), np.sin(t)
    return r * _pick(wide, c, s), r * _pick(wide, s, c)


@_register_jitable
def _cosine_hemisphere_point(u, v):
    """Elementwise: the concentric disk lifted to the hemisphere (Malley), z = sqrt((1 - rho)(1 + rho)).

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


# The public elementwise functions: from Python they check (u, v) as the array maps check uv (finite,
# in [0, 1], broadcasting together); inside numba kernels (the path tracer, the study) they are the
# bare formulas above, through the overloads below.


def uniform_sphere_point(u, v):
    """Elementwise: pbrt-v4 / Mitsuba, z = 1 - 2u, r = sqrt(1 - z^2) = 2 sqrt(u (1 - u)), phi = 2 pi v.

    Scalars or arrays (broadcasting together) of [0, 1] in, a tuple (x, y, z) out; numba compiles it
    (inside a kernel the arguments are not checked).  NaN, inf or a value outside [0, 1] is a ValueError
    naming 'u' or 'v'.

    Examples
    --------
    >>> from symsphere.warps import uniform_sphere_point
    >>> [round(float(c), 6) for c in uniform_sphere_point(0.25, 0.5)]
    [-0.866025, 0.0, 0.5]
    """
    return _uniform_sphere_point(*check_real_arrays((u, "u"), (v, "v"), unit_interval=True))


def uniform_hemisphere_point(u, v):
    """Elementwise: z = u, r = sqrt((1 - u)(1 + u)), phi = 2 pi v (pbrt-v4 SampleUniformHemisphere).

    Arguments as for :func:`uniform_sphere_point`.

    Examples
    --------
    >>> from symsphere.warps import uniform_hemisphere_point
    >>> [round(float(c), 6) for c in uniform_hemisphere_point(0.5, 0.25)]
    [0.0, 0.866025, 0.5]
    """
    return _uniform_hemisphere_point(*check_real_arrays((u, "u"), (v, "v"), unit_interval=True))


def concentric_disk_point(u, v):
    """Elementwise Shirley & Chiu (1997): concentric squares of [0, 1]^2 -> concentric circles of the disk.

    Arguments as for :func:`uniform_sphere_point`.

    Examples
    --------
    >>> from symsphere.warps import concentric_disk_point
    >>> [float(c) for c in concentric_disk_point(1.0, 0.5)]
    [1.0, 0.0]
    """
    return _concentric_disk_point(*check_real_arrays((u, "u"), (v, "v"), unit_interval=True))


def cosine_hemisphere_point(u, v):
    """Elementwise: the concentric disk lifted to the hemisphere (Malley), z = sqrt((1 - rho)(1 + rho)).

    Arguments as for :func:`uniform_sphere_point`.

    Examples
    --------
    >>> from symsphere.warps import cosine_hemisphere_point
    >>> [float(c) for c in cosine_hemisphere_point(0.5, 0.5)]
    [0.0, 0.0, 1.0]
    """
    return _cosine_hemisphere_point(*check_real_arrays((u, "u"), (v, "v"), unit_interval=True))


@_overload(uniform_sphere_point, jit_options={}, inline="never", strict=False)
def _uniform_sphere_point_in_kernels(u, v):
    return _uniform_sphere_point


@_overload(uniform_hemisphere_point, jit_options={}, inline="never", strict=False)
def _uniform_hemisphere_point_in_kernels(u, v):
    return _uniform_hemisphere_point


@_overload(concentric_disk_point, jit_options={}, inline="never", strict=False)
def _concentric_disk_point_in_kernels(u, v):
    return _concentric_disk_point


@_overload(cosine_hemisphere_point, jit_options={}, inline="never", strict=False)
def _cosine_hemisphere_point_in_kernels(u, v):
    return _cosine_hemisphere_point


def _uniform_sphere(uv):
    return np.stack(_uniform_sphere_point(uv[..., 0], uv[..., 1]), axis=-1)


def _uniform_sphere_inverse(d):
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    # 1 - z = (x^2 + y^2)/(1 + z) for unit d: no cancellation in the north.
    u_north = (x * x + y * y) / (2.0 * (1.0 + np.abs(z)))
    u = np.where(z > 0, u_north, 0.5 * (1.0 - z))
    v = _wrap_unit(np.arctan2(y, x) / (2.0 * np.pi))
    return np.stack([np.clip(u, 0.0, 1.0), v], axis=-1)


def _uniform_hemisphere(uv):
    return np.stack(_uniform_hemisphere_point(uv[..., 0], uv[..., 1]), axis=-1)


def _uniform_hemisphere_inverse(d):
    u = np.clip(d[..., 2], 0.0, 1.0)
    v = _wrap_unit(np.arctan2(d[..., 1], d[..., 0]) / (2.0 * np.pi))
    return np.stack([u, v], axis=-1)


def _octant_lift(p, q, upper):
    """Lift the octant point with L1 coordinates (p, q) >= 0, r = p + q <= 1.

    1 - |z| = r^2; azimuth within the quadrant phi = (pi/2) q/r, written as
    cos(phi) = sin((pi/2) p/r), sin(phi) = sin((pi/2) q/r) so that the axes
    (p = 0 or q = 0) come out exactly.  Returns |x|, |y|, z.
    """
    r = p + q
    safe = np.where(r > 0, r, 1.0)
    sin_theta = r * np.sqrt(np.maximum(2.0 - r * r, 0.0))
    ax = sin_theta * np.sin(0.5 * np.pi * p / safe)
    ay = sin_theta * np.sin(0.5 * np.pi * q / safe)
    z = np.where(upper, 1.0 - r * r, r * r - 1.0)
    return ax, ay, z


def _octant_unlift(d):
    """(p, q, upper) of unit directions: the inverse of :func:`_octant_lift`."""
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    ax, ay = np.abs(x), np.abs(y)
    r = np.sqrt((ax * ax + ay * ay) / (1.0 + np.abs(z)))  # sqrt(1 - |z|)
    r = np.minimum(r, 1.0)
    p = r * np.arctan2(ax, ay) * (2.0 / np.pi)
    q = r * np.arctan2(ay, ax) * (2.0 / np.pi)
    return p, q, z >= 0


def _octahedral_sphere(uv):
    # Clarberg (2008): inner diamond -> upper hemisphere; corner triangles fold below.
    a = 2.0 * uv[..., 0] - 1.0
    b = 2.0 * uv[..., 1] - 1.0
    aa, ab = np.abs(a), np.abs(b)
    upper = aa + ab <= 1.0
    # Outside the diamond the L1 coordinates of the fold are (1 - |b|, 1 - |a|).
    p = np.where(upper, aa, 1.0 - ab)
    q = np.where(upper, ab, 1.0 - aa)
    ax, ay, z = _octant_lift(p, q, upper)
    return np.stack([np.copysign(ax, a), np.copysign(ay, b), z], axis=-1)


def _octahedral_sphere_inverse(d):
    p, q, upper = _octant_unlift(d)
    aa = np.where(upper, p, 1.0 - q)
    ab = np.where(upper, q, 1.0 - p)
    a = np.copysign(aa, d[..., 0])
    b = np.copysign(ab, d[..., 1])
    return np.clip(np.stack([0.5 * (a + 1.0), 0.5 * (b + 1.0)], axis=-1), 0.0, 1.0)


def _octahedral_hemisphere(uv):
    # Turn the square [-1, 1]^2 by 45 degrees onto the diamond, then lift the upper half.
    a = 2.0 * uv[..., 0] - 1.0
    b = 2.0 * uv[..., 1] - 1.0
    s, t = 0.5 * (a + b), 0.5 * (b - a)
    ax, ay, z = _octant_lift(np.abs(s), np.abs(t), True)
    return np.stack([np.copysign(ax, s), np.copysign(ay, t), z], axis=-1)


def _octahedral_hemisphere_inverse(d):
    p, q, _ = _octant_unlift(d)
    s = np.copysign(p, d[..., 0])
    t = np.copysign(q, d[..., 1])
    a, b = s - t, s + t
    return np.clip(np.stack([0.5 * (a + 1.0), 0.5 * (b + 1.0)], axis=-1), 0.0, 1.0)


def _concentric(uv):
    return np.stack(_concentric_disk_point(uv[..., 0], uv[..., 1]), axis=-1)


def _concentric_inverse(p):
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


def _cosine_hemisphere(uv):
    return np.stack(_cosine_hemisphere_point(uv[..., 0], uv[..., 1]), axis=-1)


def _cosine_hemisphere_inverse(d):
    return _concentric_inverse(d[..., :2])
