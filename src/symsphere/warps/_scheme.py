"""The scheme as a warp of the unit square: Mitsuba's and pbrt-v4's form, for your own (u, v).

:func:`square_to_sphere` is a bijection of the unit square onto the sphere
built from the 48 triangles of the scheme (:func:`square_to_hemisphere`: 24,
onto the hemisphere about +z).  The first coordinate chooses a strip of the
square, and so a triangle, and the point inside it::

    t = 48 u,   j = min(floor(t), 47),   u' = t - j  if j is even,  1 - (t - j)  if j is odd
    d = orbit(square_to_triangle((u', v), method))[k_j]      # = p @ SPHERE_MAPS[k_j]

so the strip ``j/48 <= u < (j+1)/48`` of the square goes onto triangle
``k_j`` of the paper's Table 2, by the chosen map of :func:`symsphere.warps.square_to_triangle`
stretched 48 times along u (mirrored in every other strip).  The order
``k_0, k_1, ...`` (:func:`strip_order`) walks around the six axes: the 8
triangles about (0, 0, 1) first (``k_0 = 0``, so the first strip is
``square_to_triangle`` itself), then the fan about the next axis, and so on
(the hemisphere: the 8 about +z, then 4 about each of the four horizontal
axes).  Consecutive strips of one fan share the edge between them, so the warp
is continuous across it.  The inverse folds a direction into T0
(:func:`symsphere.fold`: the triangle k and the base point), inverts the map
and puts u' back into k's strip.  Each function triple is as in Mitsuba's
``warp.h`` (``square_to_X``, ``square_to_X_pdf``, ``X_to_square``).

What it preserves
-----------------
- Area, for ``method='equal_area'``: the warp is exactly area-preserving
  (pdf ``1/(4 pi)``, ``1/(2 pi)`` on the hemisphere), so an equal-area
  stratification of the square is one of the sphere.  The paper's maps
  (``'paper1'``, ``'paper2'``) are not uniform; the pdf is then
  ``square_to_triangle_pdf(base) / 48`` and diverges at the six axes.
- Strata: a rectangle ``[a, b) x [c, d)`` of the square with ``48 a`` and
  ``48 b`` in the same integer interval is one cell of one triangle.  A jittered
  grid of ``N x M`` strata with N a multiple of 48 (24) gives every triangle the
  same ``N/48 x M`` cells, each of area ``4 pi / (N M)`` for ``'equal_area'``.
  The 48 points ``u = (j + t_j) / 48`` with ``t_j = u'`` for even j and
  ``1 - u'`` for odd j, all at the same v, are exactly one orbit of the scheme.
  Low-discrepancy sets keep their structure along v and, strip by strip, in u'.
- Continuity, within each fan: the warp is continuous in u across the
  boundaries between strips of one fan (the two strips meet on the shared edge,
  point for point) and jumps at the 5 boundaries between fans (hemisphere: 4),
  as a cube map jumps between faces; v = 0 is the fan's axis.  Where full
  continuity matters, e.g. a smooth integrand with Sobol' points, Clarberg's
  octahedral map (:func:`square_to_octahedral_sphere`) is continuous everywhere.

The strips' boundaries, where two triangles meet, are sets of measure zero:
there ``sphere_to_square(square_to_sphere(uv))`` may return the point of the
neighbouring strip (same direction).  Everywhere else the two are exact inverses up to
rounding.  All computation is in float64; results take the floating dtype of
the input; ``u, v`` in {0, 1} give no NaN.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from .._typing import Domain, FloatArray, MapMethod
from .._validation import check_choice, check_unit_directions, check_uv
from ..symmetry import DOMAINS, HEMISPHERE_MAPS, SPHERE_MAPS, base_point, fold, orbit_size
from ._record import Warp
from ._registry import register
from ._triangle import METHODS, triangle_to_square, triangle_warp

__all__ = [
    "square_to_sphere",
    "square_to_sphere_pdf",
    "sphere_to_square",
    "square_to_hemisphere",
    "square_to_hemisphere_pdf",
    "hemisphere_to_square",
    "strip_order",
]


def square_to_sphere(uv: npt.ArrayLike, method: MapMethod = "equal_area") -> FloatArray:
    """Map points of the unit square onto the sphere through the 48 triangles.

    Parameters
    ----------
    uv : array_like, shape (..., 2)
        Points of [0, 1]^2.  ``j = floor(48 u)`` chooses the triangle
        ``strip_order('sphere')[j]`` (an index into :data:`symsphere.SPHERE_MAPS`),
        ``48 u - j`` (``1 - (48 u - j)`` for odd j) and v the point in it.
    method : {'equal_area', 'paper1', 'paper2'}
        The map of the square onto T0 (:func:`square_to_triangle`); only
        ``'equal_area'`` makes the warp uniform.

    Returns
    -------
    ndarray, shape (..., 3)
        Unit directions, in the dtype of *uv* (float64 for integer input).

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere import orbit, square_to_sphere, square_to_triangle
    >>> square_to_sphere([[0.0, 0.0], [1.0, 1.0]])       # the pole; a vertex of the last triangle
    array([[ 0.        ,  0.        ,  1.        ],
           [ 0.70710678,  0.        , -0.70710678]])
    >>> from symsphere.warps import strip_order
    >>> j, u, v = 12, 0.25, 0.75                          # u' = 0.25 in strip 12 (even: not mirrored)
    >>> k = strip_order("sphere")[j]
    >>> bool(np.allclose(square_to_sphere([(j + u) / 48, v]), orbit(square_to_triangle([u, v]))[k]))
    True
    """
    return _forward(uv, method, "sphere")


def square_to_sphere_pdf(d: npt.ArrayLike, method: MapMethod = "equal_area") -> FloatArray:
    """Density (solid angle) of :func:`square_to_sphere` at directions *d*.

    Parameters
    ----------
    d : array_like, shape (..., 3)
        Unit directions, float64 or float32: the density has their dtype.
    method : {'equal_area', 'paper1', 'paper2'}
        The map onto T0 that :func:`square_to_sphere` was given.

    Returns
    -------
    ndarray, shape (...)
        ``square_to_triangle_pdf(base, method) / 48`` with ``base`` the fold of *d* into
        T0: ``1/(4 pi)`` for ``'equal_area'``; ``inf`` on the axes for the
        paper's maps, whose density diverges there.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere import square_to_sphere_pdf
    >>> float(square_to_sphere_pdf([0.0, 0.6, -0.8]) * 4 * np.pi)
    1.0
    """
    return _pdf(d, method, orbit_size("sphere"))


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
        Points of [0, 1]^2: with ``k, base = fold(d)`` and
        ``(u', v) = triangle_to_square(base, method)``, ``u = (j + u') / 48``
        where strip j holds triangle k (``1 - u'`` for odd j).  On a boundary
        between triangles the lowest k is taken (the rule of :func:`symsphere.fold`).

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
        Points of [0, 1]^2.  ``j = floor(24 u)`` chooses the triangle
        ``strip_order('hemisphere')[j]`` (an index into :data:`symsphere.HEMISPHERE_MAPS`),
        ``24 u - j`` (``1 - (24 u - j)`` for odd j) and v the point in it.
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
    return _forward(uv, method, "hemisphere")


def square_to_hemisphere_pdf(d: npt.ArrayLike, method: MapMethod = "equal_area") -> FloatArray:
    """Density (solid angle) of :func:`square_to_hemisphere` at directions *d*.

    Arguments as for :func:`square_to_sphere_pdf`; the density is ``square_to_triangle_pdf(base, method) / 24``
    for z >= 0, 0 below (as :func:`symsphere.hemisphere_pdf`), of shape ``d.shape[:-1]``.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere import square_to_hemisphere_pdf
    >>> square_to_hemisphere_pdf([[0.0, 0.6, 0.8], [0.0, 0.6, -0.8]]) * 2 * np.pi
    array([1., 0.])
    """
    return _pdf(d, method, orbit_size("hemisphere"))


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
        Points of [0, 1]^2, ``u = (j + u') / 24`` as in :func:`sphere_to_square`.

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


def strip_order(domain: Domain = "sphere") -> npt.NDArray[np.int64]:
    """Which triangle each strip of the square goes onto: the order of the warp's strips.

    Parameters
    ----------
    domain : {'sphere', 'hemisphere'}

    Returns
    -------
    ndarray of int64, shape (48,) or (24,)
        ``strip_order(domain)[j]`` is the table index (:data:`symsphere.SPHERE_MAPS`,
        :data:`symsphere.HEMISPHERE_MAPS`) of strip j; odd strips are mirrored in u'.
        Found from the maps: the triangles are grouped by the image of T0's vertex
        (0, 0, 1) (the fan about one axis), and each fan is walked so that strip j
        leaves over the edge by which strip j + 1 enters (T0's edge x = y after an
        unmirrored strip, y = 0 after a mirrored one).

    Examples
    --------
    >>> from symsphere.warps import strip_order
    >>> strip_order("sphere")[:8]            # the fan of 8 triangles about (0, 0, 1)
    array([0, 4, 5, 1, 2, 6, 7, 3])
    >>> sorted(strip_order("hemisphere")) == list(range(24))
    True
    """
    order = _ORDER[check_choice(domain, "domain", DOMAINS)]
    return order.copy()


# --- private ------------------------------------------------------------------


_PLANE_ULPS = 16  # see scheme_pdf


def _walk_fans(maps: npt.NDArray[np.float64]) -> npt.NDArray[np.int64]:
    """The strip order of :func:`strip_order`: each fan of triangles about one axis, edge to shared edge."""
    # A point inside T0's edge y = 0 and one inside its edge x = y: two images agree iff the edge is shared.
    edges = (np.array([0.3, 0.0, np.sqrt(0.91)]), np.array([0.3, 0.3, np.sqrt(0.82)]))
    fans: dict[tuple[float, ...], list[int]] = {}
    for k in range(len(maps)):
        fans.setdefault(tuple(np.array([0.0, 0.0, 1.0]) @ maps[k]), []).append(k)
    order: list[int] = []
    for fan in sorted(fans.values(), key=min):
        for start in fan:  # the first start whose walk covers the fan (a half fan on the hemisphere: an end)
            walk = [start]
            while len(walk) < len(fan):
                edge = edges[(len(order) + len(walk)) % 2]  # leaves an even strip over x = y, an odd one over y = 0
                shared = [k for k in fan if k not in walk and np.array_equal(edge @ maps[k], edge @ maps[walk[-1]])]
                if not shared:
                    break
                walk.append(shared[0])
            if len(walk) == len(fan):
                order += walk
                break
        else:  # pragma: no cover - the tables make every fan walkable
            raise AssertionError(f"no walk through the fan {fan}")
    return np.array(order, dtype=np.int64)


_MAPS = {"sphere": SPHERE_MAPS, "hemisphere": HEMISPHERE_MAPS}
_ORDER = {domain: _walk_fans(maps) for domain, maps in _MAPS.items()}


def _forward(uv: npt.ArrayLike, method: MapMethod, domain: Domain) -> FloatArray:
    uv = check_uv(uv)
    warp = triangle_warp(method)
    maps, order, count = _MAPS[domain], _ORDER[domain], orbit_size(domain)
    uv64 = uv.astype(np.float64)
    t = uv64[..., 0] * count
    j = np.minimum(np.floor(t), count - 1).astype(np.int64)
    local_u = np.where(j % 2 == 1, 1.0 - (t - j), t - j)
    base = warp.points(np.stack([local_u, uv64[..., 1]], axis=-1))
    d: FloatArray = np.einsum("...i,...ij->...j", base, maps[order[j]])
    return d.astype(uv.dtype, copy=False)


def _pdf(d: npt.ArrayLike, method: MapMethod, count: int) -> FloatArray:
    d = check_unit_directions(d, "d")
    return scheme_pdf(d.astype(np.float64), method, count, d.dtype)


def scheme_pdf(d: FloatArray, method: MapMethod, count: int, dtype: npt.DTypeLike) -> FloatArray:
    """The scheme's density at unit directions *d* (float64, about +z), in *dtype*: within the package.

    A strip of 1/count of the square goes onto one triangle, so the density is the base point's in T0
    over *count* (48: the sphere, 24: the hemisphere, 0 below it).  On the hemisphere, directions within
    16 ulps (of *dtype*) of the plane count as on it, so that a sample on the equator rotated onto
    another pole (a few ulps below the plane) keeps a positive density.  :func:`symsphere.sphere_pdf`
    and :func:`symsphere.hemisphere_pdf` are this, after their checks (and rotation).
    """
    warp = triangle_warp(method)
    base = base_point(d)  # fold's base point, without the sub-domain index a density does not need
    density = warp.densities(base.astype(np.float64, copy=False)) / count
    if count == orbit_size("hemisphere"):
        on = d[..., 2] >= -_PLANE_ULPS * np.finfo(dtype).eps
        density = np.where(on, density, 0.0)
    return density.astype(dtype, copy=False)


def _inverse(d: npt.ArrayLike, method: MapMethod, domain: Domain) -> FloatArray:
    d = check_unit_directions(d, "d")
    method = check_choice(method, "method", METHODS)
    count = orbit_size(domain)
    d64 = d.astype(np.float64)
    if domain == "hemisphere" and np.any(d64[..., 2] < 0):
        raise ValueError("'d' must lie in the hemisphere z >= 0 (rotate other poles with symsphere.frames.to_local)")
    k, base = fold(d64)
    local = triangle_to_square(base.astype(np.float64, copy=False), method)
    j = np.argsort(_ORDER[domain])[k]  # the strip of triangle k
    local_u = np.clip(local[..., 0], 0.0, 1.0)
    u = (j + np.where(j % 2 == 1, 1.0 - local_u, local_u)) / count
    return np.stack([u, local[..., 1]], axis=-1).astype(d.dtype, copy=False)


def _scheme_warp(domain: Domain, method: MapMethod) -> Warp:
    """The bijection onto *domain* through the scheme's triangles, each by *method*."""
    forward, pdf, inverse = (
        (square_to_sphere, square_to_sphere_pdf, sphere_to_square)
        if domain == "sphere"
        else (square_to_hemisphere, square_to_hemisphere_pdf, hemisphere_to_square)
    )
    return Warp(
        name=f"{domain}_{method}",
        domain=domain,
        uniform=method == "equal_area",
        forward=lambda uv: forward(uv, method),
        pdf=lambda d: pdf(d, method),
        inverse=lambda d: inverse(d, method),
        reference=f"the scheme's triangles as strips of the square, each by {method!r}",
    )


register(*(_scheme_warp(domain, method) for method in METHODS for domain in DOMAINS))
