"""Uniform maps by the hat-box theorem: the square onto the sphere and onto the hemisphere z >= 0.

Archimedes' hat-box theorem: the area of the zone of the unit sphere between two heights is
2 pi times their difference, so a uniform height z and a uniform azimuth phi give a uniform
direction (pbrt-v4 ``SampleUniformSphere``/``SampleUniformHemisphere``, Mitsuba 3
``square_to_uniform_sphere``).  Sphere: z = 1 - 2u, phi = 2 pi v, density 1/(4 pi);
hemisphere: z = u, phi = 2 pi v, density 1/(2 pi).  Each triple (forward, pdf, inverse)
is side by side below; the elementwise formulas (``uniform_sphere_point``, ...) are the
ones numba compiles into the path tracer's kernels.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from .._constants import INV_2PI, INV_4PI
from .._typing import Float64Array, FloatArray
from .._validation import check_directions
from ._common import checked_forward, checked_inverse, elementwise, on_rows, wrap_unit
from ._record import Warp
from ._registry import register

__all__ = [
    "square_to_uniform_sphere",
    "square_to_uniform_sphere_pdf",
    "uniform_sphere_to_square",
    "uniform_sphere_point",
    "square_to_uniform_hemisphere",
    "square_to_uniform_hemisphere_pdf",
    "uniform_hemisphere_to_square",
    "uniform_hemisphere_point",
]


# --- the sphere ---------------------------------------------------------------------------


def square_to_uniform_sphere(uv: npt.ArrayLike) -> FloatArray:
    """Map the unit square onto the sphere: z = 1 - 2u, phi = 2 pi v.

    The radius sin(theta) = 2 sqrt(u (1 - u)), which does not cancel near the
    poles as sqrt(1 - z^2) does.

    Parameters
    ----------
    uv : array_like, shape (..., 2)
        Points of [0, 1]^2: u gives the height z, v the azimuth.

    Returns
    -------
    ndarray, shape (..., 3)
        Unit directions, in the dtype of *uv* (float64 for integers).

    Examples
    --------
    >>> from symsphere.warps import square_to_uniform_sphere
    >>> square_to_uniform_sphere([[0.0, 0.0], [0.5, 0.0], [1.0, 0.0]])
    array([[ 0.,  0.,  1.],
           [ 1.,  0.,  0.],
           [ 0.,  0., -1.]])
    """
    return checked_forward(_uniform_sphere, uv)


def square_to_uniform_sphere_pdf(d: npt.ArrayLike) -> Float64Array:
    """The uniform density on the sphere, 1/(4 pi), of shape ``d.shape[:-1]``.

    Examples
    --------
    >>> from symsphere.warps import square_to_uniform_sphere_pdf
    >>> float(square_to_uniform_sphere_pdf([0.0, 0.0, 1.0]) * 4 * 3.141592653589793)
    1.0
    """
    d = check_directions(d, "d")
    return np.full(d.shape[:-1], INV_4PI)


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
        Points of [0, 1]^2 with v < 1, in the dtype of *d* (float64 for integers).

    Examples
    --------
    >>> from symsphere.warps import uniform_sphere_to_square
    >>> uniform_sphere_to_square([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    array([[0. , 0. ],
           [0.5, 0. ],
           [1. , 0. ]])
    """
    return checked_inverse(_uniform_sphere_inverse, d)


@elementwise()
def uniform_sphere_point(u: Any, v: Any) -> tuple[Any, Any, Any]:
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
    z = 1.0 - 2.0 * u
    r = 2.0 * np.sqrt(u * (1.0 - u))
    phi = 2.0 * np.pi * v
    return r * np.cos(phi), r * np.sin(phi), z


_uniform_sphere = on_rows(uniform_sphere_point)


def _uniform_sphere_inverse(d: Float64Array) -> Float64Array:
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    # 1 - z = (x^2 + y^2)/(1 + z) for unit d: no cancellation in the north.
    u_north = (x * x + y * y) / (2.0 * (1.0 + np.abs(z)))
    u = np.where(z > 0, u_north, 0.5 * (1.0 - z))
    v = wrap_unit(np.arctan2(y, x) / (2.0 * np.pi))
    return np.stack([np.clip(u, 0.0, 1.0), v], axis=-1)


register(
    Warp(name="uniform_sphere", domain="sphere", uniform=True, forward=square_to_uniform_sphere,
         pdf=square_to_uniform_sphere_pdf, inverse=uniform_sphere_to_square, point=uniform_sphere_point,
         reference="Archimedes' hat-box map; pbrt-v4 SampleUniformSphere, Mitsuba 3 square_to_uniform_sphere"),
)  # fmt: skip


# --- the hemisphere -----------------------------------------------------------------------


def square_to_uniform_hemisphere(uv: npt.ArrayLike) -> FloatArray:
    """Map the unit square onto the hemisphere z >= 0: z = u, phi = 2 pi v.

    sin(theta) = sqrt((1 - u)(1 + u)).  pbrt-v4 ``SampleUniformHemisphere``.

    Examples
    --------
    >>> from symsphere.warps import square_to_uniform_hemisphere
    >>> square_to_uniform_hemisphere([[0.0, 0.25], [1.0, 0.0]])
    array([[6.123234e-17, 1.000000e+00, 0.000000e+00],
           [0.000000e+00, 0.000000e+00, 1.000000e+00]])
    """
    return checked_forward(_uniform_hemisphere, uv)


def square_to_uniform_hemisphere_pdf(d: npt.ArrayLike) -> Float64Array:
    """The uniform density on the hemisphere z >= 0: 1/(2 pi) there, 0 below.

    Examples
    --------
    >>> from symsphere.warps import square_to_uniform_hemisphere_pdf
    >>> square_to_uniform_hemisphere_pdf([[0.0, 0.6, 0.8], [0.0, 0.6, -0.8]]) * 2 * 3.141592653589793
    array([1., 0.])
    """
    d = check_directions(d, "d")
    return np.where(d[..., 2] >= 0, INV_2PI, 0.0)


def uniform_hemisphere_to_square(d: npt.ArrayLike) -> FloatArray:
    """Inverse of :func:`square_to_uniform_hemisphere`: u = z, v = phi / (2 pi).

    Examples
    --------
    >>> from symsphere.warps import uniform_hemisphere_to_square
    >>> uniform_hemisphere_to_square([0.0, -1.0, 0.0])
    array([0.  , 0.75])
    """
    return checked_inverse(_uniform_hemisphere_inverse, d, hemisphere=True)


@elementwise()
def uniform_hemisphere_point(u: Any, v: Any) -> tuple[Any, Any, Any]:
    """Elementwise: z = u, r = sqrt((1 - u)(1 + u)), phi = 2 pi v (pbrt-v4 SampleUniformHemisphere).

    Arguments as for :func:`uniform_sphere_point`.

    Examples
    --------
    >>> from symsphere.warps import uniform_hemisphere_point
    >>> [round(float(c), 6) for c in uniform_hemisphere_point(0.5, 0.25)]
    [0.0, 0.866025, 0.5]
    """
    r = np.sqrt((1.0 - u) * (1.0 + u))
    phi = 2.0 * np.pi * v
    return r * np.cos(phi), r * np.sin(phi), u


_uniform_hemisphere = on_rows(uniform_hemisphere_point)


def _uniform_hemisphere_inverse(d: Float64Array) -> Float64Array:
    u = np.clip(d[..., 2], 0.0, 1.0)
    v = wrap_unit(np.arctan2(d[..., 1], d[..., 0]) / (2.0 * np.pi))
    return np.stack([u, v], axis=-1)


register(
    Warp(name="uniform_hemisphere", domain="hemisphere", uniform=True, forward=square_to_uniform_hemisphere,
         pdf=square_to_uniform_hemisphere_pdf, inverse=uniform_hemisphere_to_square, point=uniform_hemisphere_point,
         reference="pbrt-v4 SampleUniformHemisphere"),
)  # fmt: skip
