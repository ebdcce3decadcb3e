"""The scheme as a warp of the unit square: Mitsuba's and pbrt-v4's form, for your own (u, v).

:func:`square_to_sphere` is a bijection of the unit square onto the sphere
built from the 48 triangles of the scheme (:func:`square_to_hemisphere`: 24,
onto the hemisphere about +z).  The first coordinate chooses the triangle and
the point inside it::

    t = 48 u,   k = min(floor(t), 47),   u' = t - k
    d = orbit(square_to_triangle((u', v), method))[k]      # = p @ SPHERE_MAPS[k]

so the strip ``k/48 <= u < (k+1)/48`` of the square goes onto the k-th triangle
of the paper's Table 2, by the chosen map of :mod:`symsphere.maps` stretched 48
times along u.  The inverse folds a direction into T0 (:func:`symsphere.fold`:
the triangle k and the base point) and inverts the map:
``u = (k + u') / 48``.  Each function pair is a triple as in Mitsuba's
``warp.h`` (``square_to_X``, ``square_to_X_pdf``, ``X_to_square``).

What it preserves
-----------------
- Area, for ``method='equal_area'``: the warp is exactly area-preserving
  (pdf ``1/(4 pi)``, ``1/(2 pi)`` on the hemisphere), so an equal-area
  stratification of the square is one of the sphere.  The paper's maps
  (``'paper1'``, ``'paper2'``) are not uniform; the pdf is then
  ``triangle_pdf(base) / 48`` and diverges at the six axes.
- Strata: a rectangle ``[a, b) x [c, d)`` of the square with ``48 a`` and
  ``48 b`` in the same integer interval is one cell of one triangle.  A jittered
  grid of ``N x M`` strata with N a multiple of 48 (24) gives every triangle the
  same ``N/48 x M`` cells, each of area ``4 pi / (N M)``; 48 points whose u lie
  one in each strip, at the same ``u'`` and v, are exactly one orbit of the
  scheme.  Low-discrepancy sets keep their property along v and in
  ``u' = 48 u mod 1`` within each strip.
- Not continuity: neighbouring strips are not always neighbouring triangles, so the
  warp is discontinuous at some strip boundaries (as any 48-piece map of one
  square is); use :mod:`symsphere.warps` (Clarberg's octahedral map) where
  continuity matters, e.g. for a smooth integrand with Sobol' points.

The strips' boundaries, where two triangles meet, are sets of measure zero:
there ``sphere_to_square(square_to_sphere(uv))`` may return the other strip's
end (same direction).  Everywhere else the two are exact inverses up to
rounding.  All computation is in float64; results take the floating dtype of
the input; ``u, v`` in {0, 1} give no NaN.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from ._typing import FloatArray, MapMethod
from ._validation import check_directions, check_uv
from .maps import get_map
from .symmetry import HEMISPHERE_MAPS, SPHERE_MAPS, fold

__all__ = [
    "square_to_sphere",
    "square_to_sphere_pdf",
    "sphere_to_square",
    "square_to_hemisphere",
    "square_to_hemisphere_pdf",
    "hemisphere_to_square",
]


def square_to_sphere(uv: npt.ArrayLike, method: MapMethod = "equal_area") -> FloatArray:
    """Map points of the unit square onto the sphere through the 48 triangles.

    Parameters
    ----------
    uv : array_like, shape (..., 2)
        Points of [0, 1]^2.  ``floor(48 u)`` chooses the triangle (table order
        of :data:`symsphere.SPHERE_MAPS`), ``(48 u mod 1, v)`` the point in it.
    method : {'equal_area', 'paper1', 'paper2'}
        The map of the square onto T0 (:mod:`symsphere.maps`); only
        ``'equal_area'`` makes the warp uniform.

    Returns
    -------
    ndarray, shape (..., 3)
        Unit directions, in the dtype of *uv* (float64 for integer input).

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere import orbit, square_to_sphere, square_to_triangle
    >>> square_to_sphere([[0.0, 0.0], [1.0, 1.0]])       # the pole; the last triangle's far vertex
    array([[ 0.        ,  0.        ,  1.        ],
           [ 0.57735027, -0.57735027, -0.57735027]])
    >>> k, u, v = 13, 0.25, 0.75                          # u' = 0.25 in triangle 13
    >>> bool(np.allclose(square_to_sphere([(k + u) / 48, v]), orbit(square_to_triangle([u, v]))[k]))
    True
    """
    return _forward(uv, method, SPHERE_MAPS)


def square_to_sphere_pdf(d: npt.ArrayLike, method: MapMethod = "equal_area") -> FloatArray:
    """Density (solid angle) of :func:`square_to_sphere` at directions *d*.

    Parameters
    ----------
    d : array_like, shape (..., 3)
        Unit directions.
    method : {'equal_area', 'paper1', 'paper2'}

    Returns
    -------
    ndarray, shape (...)
        ``triangle_pdf(base, method) / 48`` with ``base`` the fold of *d* into
        T0: ``1/(4 pi)`` for ``'equal_area'``; ``inf`` on the axes for the
        paper's maps, whose density diverges there.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere import square_to_sphere_pdf
    >>> float(square_to_sphere_pdf([0.0, 0.6, -0.8]) * 4 * np.pi)
    1.0
    """
    return _pdf(d, method, 48)


def sphere_to_square(d: npt.ArrayLike, method: MapMethod = "equal_area") -> FloatArray:
    """Inverse of :func:`square_to_sphere`.

    Parameters
    ----------
    d : array_like, shape (..., 3)
        Unit directions (up to rounding).
    method : {'equal_area', 'paper1', 'paper2'}

    Returns
    -------
    ndarray, shape (..., 2)
        Points of [0, 1]^2: ``u = (k + u') / 48`` with ``k, base = fold(d)`` and
        ``(u', v) = triangle_to_square(base, method)``.  On a boundary between
        triangles the lowest k is taken (the rule of :func:`symsphere.fold`).

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere import sphere_to_square, square_to_sphere
    >>> uv = np.array([[0.3, 0.6], [0.91, 0.05]])
    >>> bool(np.allclose(sphere_to_square(square_to_sphere(uv)), uv, rtol=0, atol=1e-12))
    True
    """
    return _inverse(d, method, "sphere")


def square_to_hemisphere(uv: npt.ArrayLike, method: MapMethod = "equal_area") -> FloatArray:
    """Map points of the unit square onto the hemisphere z >= 0 through its 24 triangles.

    Parameters
    ----------
    uv : array_like, shape (..., 2)
        Points of [0, 1]^2.  ``floor(24 u)`` chooses the triangle (table order
        of :data:`symsphere.HEMISPHERE_MAPS`), ``(24 u mod 1, v)`` the point in it.
    method : {'equal_area', 'paper1', 'paper2'}

    Returns
    -------
    ndarray, shape (..., 3)
        Unit directions with z >= 0, in the dtype of *uv*.  Rotate them onto
        another pole with :func:`symsphere.frames.to_world`.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere import square_to_hemisphere
    >>> d = square_to_hemisphere(np.random.default_rng(0).random((1000, 2)))
    >>> d.shape, bool(np.all(d[:, 2] >= 0)), bool(np.allclose(np.linalg.norm(d, axis=1), 1))
    ((1000, 3), True, True)
    """
    return _forward(uv, method, HEMISPHERE_MAPS)


def square_to_hemisphere_pdf(d: npt.ArrayLike, method: MapMethod = "equal_area") -> FloatArray:
    """Density (solid angle) of :func:`square_to_hemisphere` at directions *d*.

    Parameters
    ----------
    d : array_like, shape (..., 3)
        Unit directions.
    method : {'equal_area', 'paper1', 'paper2'}

    Returns
    -------
    ndarray, shape (...)
        ``triangle_pdf(base, method) / 24`` for z >= 0, 0 below.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere import square_to_hemisphere_pdf
    >>> square_to_hemisphere_pdf([[0.0, 0.6, 0.8], [0.0, 0.6, -0.8]]) * 2 * np.pi
    array([1., 0.])
    """
    return _pdf(d, method, 24)


def hemisphere_to_square(d: npt.ArrayLike, method: MapMethod = "equal_area") -> FloatArray:
    """Inverse of :func:`square_to_hemisphere`.

    Parameters
    ----------
    d : array_like, shape (..., 3)
        Unit directions with z >= 0.
    method : {'equal_area', 'paper1', 'paper2'}

    Returns
    -------
    ndarray, shape (..., 2)
        Points of [0, 1]^2, ``u = (k + u') / 24``.

    Raises
    ------
    ValueError
        If a direction has z < 0.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere import hemisphere_to_square, square_to_hemisphere
    >>> uv = np.array([[0.3, 0.6], [0.999, 0.05]])
    >>> bool(np.allclose(hemisphere_to_square(square_to_hemisphere(uv)), uv, rtol=0, atol=1e-12))
    True
    """
    return _inverse(d, method, "hemisphere")


# --- private ------------------------------------------------------------------


def _forward(uv: npt.ArrayLike, method: MapMethod, maps: npt.NDArray[np.float64]) -> FloatArray:
    uv = check_uv(uv)
    triangle_map = get_map(method)
    count = len(maps)
    uv64 = uv.astype(np.float64)
    t = uv64[..., 0] * count
    k = np.minimum(np.floor(t), count - 1).astype(np.int64)
    local = np.stack([t - k, uv64[..., 1]], axis=-1)
    base = triangle_map.forward(local)
    d = np.einsum("...i,...ij->...j", base, maps[k])
    return d.astype(uv.dtype, copy=False)


def _pdf(d: npt.ArrayLike, method: MapMethod, count: int) -> FloatArray:
    d = check_directions(d, "d")
    triangle_map = get_map(method)
    d64 = d.astype(np.float64)
    _, base = fold(d64)
    density = triangle_map.pdf(base) / count
    if count == 24:
        density = np.where(d64[..., 2] >= 0, density, 0.0)
    return np.asarray(density).astype(d.dtype, copy=False)


def _inverse(d: npt.ArrayLike, method: MapMethod, domain: str) -> FloatArray:
    d = check_directions(d, "d")
    triangle_map = get_map(method)
    count = 48 if domain == "sphere" else 24
    d64 = d.astype(np.float64)
    if count == 24 and np.any(d64[..., 2] < 0):
        raise ValueError("'d' must lie in the hemisphere z >= 0 (rotate other poles with symsphere.frames.to_local)")
    k, base = fold(d64)
    local = triangle_map.inverse(base)
    u = (k + np.clip(local[..., 0], 0.0, 1.0)) / count
    return np.stack([u, local[..., 1]], axis=-1).astype(d.dtype, copy=False)
