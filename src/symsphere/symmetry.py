"""The 48 (hemisphere: 24) signed coordinate permutations of the paper's Tables 1 and 2.

The coordinate planes and the three bisector planes x = ±y, x = ±z, y = ±z cut
the unit sphere into 48 congruent orthogonal spherical triangles (Dimov, Penzov
& Stoilova, section 2).  The fundamental one is

    T0 = {z >= x >= y >= 0},   vertices (0, 0, 1), (1, 0, 1)/sqrt 2, (1, 1, 1)/sqrt 3,

of area pi/12.  Every other triangle is the image of T0 under one signed
permutation matrix.  We index those matrices k = 4*i + j, where i is the row of
the paper's table (P0 ... P5, then for the sphere the barred P0 ... P5) and j
the column (P, P', P'', P''').  Row-vector convention, as printed in the paper:
``image = p @ M[k]``.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from ._typing import Domain, FloatArray, IntArray
from ._validation import check_choice, check_directions

__all__ = ["SPHERE_MAPS", "HEMISPHERE_MAPS", "DOMAINS", "orbit", "fold", "orbit_size"]

DOMAINS: tuple[Domain, ...] = ("sphere", "hemisphere")
"""tuple of str: the choices of ``domain=``: the sphere (48 triangles) or the hemisphere z >= 0 (24)."""

# Source coordinate of each output position, per table row (Table 1):
# P0 (x, y, z), P1 (y, x, z), P2 (z, y, x), P3 (z, x, y), P4 (x, z, y), P5 (y, z, x).
_ROW_SOURCES = ((0, 1, 2), (1, 0, 2), (2, 1, 0), (2, 0, 1), (0, 2, 1), (1, 2, 0))
# Signs of the first two output coordinates, per table column: P, P', P'', P'''.
_COLUMN_SIGNS = ((1, 1), (-1, 1), (-1, -1), (1, -1))


def _build_maps() -> np.ndarray:
    maps = np.zeros((48, 3, 3), dtype=np.int64)
    for half, z_sign in enumerate((1, -1)):  # Table 2: barred rows negate the z output
        for i, sources in enumerate(_ROW_SOURCES):
            for j, (sx, sy) in enumerate(_COLUMN_SIGNS):
                k = 24 * half + 4 * i + j
                for out_pos, (src, sign) in enumerate(zip(sources, (sx, sy, z_sign), strict=False)):
                    maps[k, src, out_pos] = sign
    maps.setflags(write=False)
    return maps


SPHERE_MAPS = _build_maps()
"""int array (48, 3, 3): the sphere's signed permutations in the order of Table 2."""

HEMISPHERE_MAPS = SPHERE_MAPS[:24]
"""int array (24, 3, 3): the hemisphere's signed permutations in the order of Table 1."""

# The same maps as gathers, which are exact and cheaper than matrix products:
# (p @ M[k])[..., j] == SIGNS[k, j] * p[..., SOURCES[k, j]].
SOURCES = np.argmax(np.abs(SPHERE_MAPS), axis=1)
SIGNS = np.sum(SPHERE_MAPS, axis=1).astype(np.float64)
SOURCES.setflags(write=False)
SIGNS.setflags(write=False)


def orbit_size(domain: Domain) -> int:
    """Number of triangles of *domain*: 48 for the sphere, 24 for the hemisphere.

    It is the number of directions one base point of T0 gives, so the sample sizes
    ``n`` of the samplers are multiples of it.

    Parameters
    ----------
    domain : {'sphere', 'hemisphere'}
        One of :data:`DOMAINS`.

    Returns
    -------
    int

    Examples
    --------
    >>> from symsphere.symmetry import DOMAINS, orbit, orbit_size
    >>> [orbit_size(domain) for domain in DOMAINS]
    [48, 24]
    >>> orbit([0.2, 0.1, 0.9], "hemisphere").shape[0] == orbit_size("hemisphere")
    True
    """
    return 48 if check_choice(domain, "domain", DOMAINS) == "sphere" else 24


def orbit(p: npt.ArrayLike, domain: Domain = "sphere") -> FloatArray:
    """Images of points under the 48 (hemisphere: 24) maps, in table order.

    Parameters
    ----------
    p : array_like, shape (..., 3)
        Points, usually in T0 (any finite vectors are accepted).
    domain : {'sphere', 'hemisphere'}
        Which table to use.

    Returns
    -------
    ndarray, shape (..., 48, 3) or (..., 24, 3)
        ``orbit(p)[..., k, :] == p @ SPHERE_MAPS[k]``.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere import orbit
    >>> orbit(np.array([0.2, 0.1, 0.9]))[13]   # the paper's P'_3 = (-z, x, y)
    array([-0.9,  0.2,  0.1])
    """
    p = check_directions(p, "p")
    count = orbit_size(domain)
    return _orbit(p, count)


def fold(d: npt.ArrayLike, domain: Domain = "sphere") -> tuple[IntArray, FloatArray]:
    """Sub-domain index and preimage in T0 of directions.

    Parameters
    ----------
    d : array_like, shape (..., 3)
        Directions (any finite vectors; the norm is kept).  For
        ``domain='hemisphere'`` they must have ``z >= 0``.
    domain : {'sphere', 'hemisphere'}

    Returns
    -------
    k : ndarray of int, shape (...)
        Index into the table, so that ``orbit(base, domain)[..., k, :] == d``
        exactly.
    base : ndarray, shape (..., 3)
        The point of T0 = {z >= x >= y >= 0} with the same absolute
        coordinates as *d*: ``(middle, smallest, largest)`` of ``|d|``.

    Notes
    -----
    A direction on the boundary between triangles (two equal absolute
    coordinates, or a zero coordinate) is the image of its base under several
    maps.  The rule: *k is the lowest table index whose image equals d*.  So
    the equator ``z = 0`` folds into the upper half (k < 24).  The rule is
    applied through a table computed once from the maps themselves, keyed by
    the sign pattern of ``d`` and the order of ``|d|``.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere import fold, orbit
    >>> d = np.array([-0.9, 0.2, 0.1])
    >>> k, base = fold(d)
    >>> int(k), base
    (13, array([0.2, 0.1, 0.9]))
    >>> bool(np.all(orbit(base)[k] == d))
    True
    """
    d = check_directions(d, "d")
    count = orbit_size(domain)
    if count == 24 and np.any(d[..., 2] < 0):
        raise ValueError("'d' must have z >= 0 for domain='hemisphere'")
    return _fold(d)


# --- private helpers: trust their inputs -----------------------------------


def _orbit(p: FloatArray, count: int) -> FloatArray:
    images: FloatArray = p[..., SOURCES[:count]] * SIGNS[:count].astype(p.dtype)
    return images


def fold_key(d: np.ndarray) -> np.ndarray:
    """Key of the sign pattern of d and the weak order of |d| (729 possible values): within the package
    (:data:`FOLD_TABLE` maps it to the sub-domain index; ``mitsuba._warps`` computes it on Dr.Jit arrays).

    Base-3 digits, most significant first: the signs of x, y, z, then the weak orders of |x| vs |y|,
    |x| vs |z|, |y| vs |z| (each digit -1, 0, 1 plus 1).
    """
    sign = (d > 0).astype(np.int64) - (d < 0)  # -0.0 counts as 0
    a = np.abs(d)
    pairs = ((0, 1), (0, 2), (1, 2))
    key = np.zeros(d.shape[:-1], dtype=np.int64)
    for j in range(3):
        key = key * 3 + (sign[..., j] + 1)
    for i, j in pairs:
        key = key * 3 + ((a[..., i] > a[..., j]).astype(np.int64) - (a[..., i] < a[..., j]) + 1)
    return key


def base_point(d: np.ndarray) -> np.ndarray:
    """The point of T0 with the absolute coordinates of *d*, ``(middle, smallest, largest)`` of ``|d|``
    (what :func:`fold` returns as ``base``): within the package, for callers that checked *d* and need
    no sub-domain index (the densities).  Exact: a min/max network selects the coordinates, as sorting
    would, in one pass each and without a sort along an axis of length 3.
    """
    a = np.abs(d)
    x, y, z = a[..., 0], a[..., 1], a[..., 2]
    lo_xy, hi_xy = np.minimum(x, y), np.maximum(x, y)
    middle = np.maximum(lo_xy, np.minimum(hi_xy, z))
    return np.stack([middle, np.minimum(lo_xy, z), np.maximum(hi_xy, z)], axis=-1)


def _build_fold_table() -> np.ndarray:
    # Every key is realised by a vector with coordinates in {-3, ..., 3}:
    # enumerate them and record the lowest k whose image is exact.
    grid = np.array(np.meshgrid(*[np.arange(-3, 4.0)] * 3, indexing="ij")).reshape(3, -1).T
    table = np.full(3**6, -1, dtype=np.int64)
    keys = fold_key(grid)
    matches = np.all(_orbit(base_point(grid), 48) == grid[:, None, :], axis=-1)
    table[keys] = np.argmax(matches, axis=-1)
    table.setflags(write=False)
    return table


FOLD_TABLE = _build_fold_table()
"""The sub-domain index k of every :func:`fold_key` (-1 for the keys no vector has): the lowest k whose
image of the base point is the vector exactly."""


def _fold(d: FloatArray) -> tuple[IntArray, FloatArray]:
    return FOLD_TABLE[fold_key(d)], base_point(d)
