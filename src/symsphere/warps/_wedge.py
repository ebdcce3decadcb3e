"""A cosine-weighted map of the unit square onto the wedge W of the upper hemisphere.

The wedge is W = {0 <= phi <= pi/4, z >= 0} = {x >= y >= 0, z >= 0}, with phi the
azimuth of (x, y) and z = cos(theta).  The eight signed permutations that keep z,
(x, y, z) -> (+-x, +-y, z) and (+-y, +-x, z) (:data:`WEDGE_MAPS`), tile the upper
hemisphere with eight copies of W.  The map is a triple, side by side as in
:func:`symsphere.warps.square_to_triangle`: forward :func:`square_to_cosine_wedge`, pdf
:func:`square_to_cosine_wedge_pdf` and inverse :func:`cosine_wedge_to_square`.

Derivation (Malley's method restricted to a wedge)
    Project W vertically onto the unit disk: W becomes the sector
    S = {0 <= phi <= pi/4, r <= 1} of area pi/8.  Sample S uniformly in area
    with ``r = sqrt(u)``, ``phi = (pi/4) v``: its area element is
    ``r dr dphi = (1/2) du (pi/4) dv = (pi/8) du dv``, so the Jacobian is the
    constant pi/8 and the density on S is 8/pi per unit disk area.  Lift the
    point to the sphere, ``z = sqrt(1 - r^2) = sqrt(1 - u)``.  The projection
    scales solid angle by cos(theta) (dA = cos(theta) d(omega)), hence the
    density with respect to solid angle on W is

        pdf_W(x, y, z) = (8/pi) cos(theta) = 8 z / pi,

    which integrates to 1 over W.  Applying a uniformly chosen member of the
    eight maps gives the density (1/8) pdf_W = cos(theta)/pi on the whole
    upper hemisphere, i.e. cosine-weighted (Lambertian) sampling; the eight
    images of one base point share z, so all eight have the same weight.

Why polar and not concentric
    Shirley & Chiu's concentric map, restricted to one of its eight octant
    triangles {0 <= b <= a <= 1}, is ``r = a``, ``phi = (pi/4)(b/a)``; fed by the
    standard area-preserving warp of the square onto that triangle,
    ``a = sqrt(u)``, ``b = a v``, it gives exactly ``r = sqrt(u)``,
    ``phi = (pi/4) v``.  On a pi/4 sector the concentric construction *is* this
    polar map, so nothing is lost by the simpler formula.

Numerics
    All computation is in float64; results take the floating dtype of the input.
    ``z = sqrt(1 - u)`` is evaluated directly (``1 - u`` is exact for u >= 1/2 by
    Sterbenz's lemma) instead of ``sqrt(1 - r^2)``, which would cancel near the
    rim; ``r = sqrt(u)`` keeps all digits near the pole.  ``y`` is clamped into
    ``[0, x]`` to absorb rounding, so u, v in {0, 1} give finite points of W and
    no NaN.  The inverse is ``u = x^2 + y^2`` (the projection onto the disk,
    without cancellation anywhere) and ``v = (4/pi) atan2(y, x)``, both clipped
    into [0, 1]; at the pole ``v = 0`` by convention.

The elementwise functions :func:`cosine_wedge_point`, :func:`cosine_wedge_density`
and :func:`cosine_wedge_uv` use numpy ufuncs only (no branches, no ``np.where``),
so the same source runs on numpy arrays and, through ``numba.extending.overload``,
inside scalar numba kernels.  Called from Python they validate their arguments as
their array twins do (finite real numbers or arrays that broadcast together, in
[0, 1] for u and v, unit vectors for x, y, z, in W for the inverse); inside a
kernel they are the bare formulas, trusting the kernel's values.  A kernel module that inlines them
with ``cache=True`` should list this file in its
:func:`symsphere._numba_cache.invalidate_if_changed` dependencies.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from .._threads import route_compiles
from .._validation import check_directions, check_real_arrays, check_unit_directions, check_uv
from ..symmetry import HEMISPHERE_MAPS
from ._common import elementwise, formula
from ._record import Warp
from ._registry import register

__all__ = [
    "WEDGE_MAPS",
    "square_to_cosine_wedge",
    "square_to_cosine_wedge_pdf",
    "cosine_wedge_to_square",
    "cosine_wedge_point",
    "cosine_wedge_density",
    "cosine_wedge_uv",
]

_Real = float | np.ndarray  # the elementwise functions take and return floats or float64 arrays

_QUARTER_PI = np.pi / 4
_FOUR_OVER_PI = 4 / np.pi
_WEDGE_DENSITY = 8 / np.pi  # pdf_W / cos(theta)

WEDGE_MAPS = HEMISPHERE_MAPS[:8]
"""int array (8, 3, 3): the signed permutations that keep z, ``image = p @ WEDGE_MAPS[k]``.

They are the rows P0 (x, y, z) and P1 (y, x, z) of the paper's Table 1 with the
four sign columns, i.e. ``HEMISPHERE_MAPS[:8]``: (x, y, z), (-x, y, z),
(-x, -y, z), (x, -y, z), (y, x, z), (-y, x, z), (-y, -x, z), (y, -x, z).  Their
images of W tile the upper hemisphere.
"""


def square_to_cosine_wedge(uv: npt.ArrayLike) -> np.ndarray:
    """Map points of the unit square onto the wedge W, cosine-weighted.

    ``r = sqrt(u)``, ``phi = (pi/4) v`` is uniform on the disk sector
    0 <= phi <= pi/4 (Jacobian pi/8), lifted to the sphere by Malley's method,
    ``z = sqrt(1 - u)``.

    Parameters
    ----------
    uv : array_like, shape (..., 2)
        Points of [0, 1]^2.

    Returns
    -------
    ndarray, shape (..., 3)
        Unit directions in W = {x >= y >= 0, z >= 0}, in the dtype of *uv*
        (float64 for integer input), with density ``8 cos(theta) / pi``
        with respect to solid angle (:func:`square_to_cosine_wedge_pdf`).  u = 0 is the
        pole (0, 0, 1), u = 1 the rim z = 0; v = 0 is the half-plane y = 0,
        v = 1 the half-plane x = y.

    See Also
    --------
    square_to_cosine_wedge_pdf, cosine_wedge_to_square, cosine_wedge_point

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.warps import square_to_cosine_wedge
    >>> square_to_cosine_wedge([[0.0, 0.3], [1.0, 0.0], [1.0, 1.0]])  # pole; rim at phi = 0, pi/4
    array([[0.        , 0.        , 1.        ],
           [1.        , 0.        , 0.        ],
           [0.70710678, 0.70710678, 0.        ]])
    >>> d = square_to_cosine_wedge([0.25, 0.5])       # r = 1/2, phi = pi/8, z = sqrt(3)/2
    >>> bool(np.allclose(d, [0.5 * np.cos(np.pi / 8), 0.5 * np.sin(np.pi / 8), np.sqrt(0.75)]))
    True
    """
    uv = check_uv(uv)
    uv64 = uv.astype(np.float64)
    d = np.stack(_point(uv64[..., 0], uv64[..., 1]), axis=-1)
    return d.astype(uv.dtype, copy=False)


def square_to_cosine_wedge_pdf(d: npt.ArrayLike) -> np.ndarray:
    """Density of :func:`square_to_cosine_wedge` with respect to solid angle.

    ``8 cos(theta) / pi = 8 z / pi`` inside the (closed) wedge
    W = {x >= y >= 0, z >= 0}, 0 outside; it integrates to 1 over W.  The
    symmetrised sampler, which applies a uniformly chosen member of
    :data:`WEDGE_MAPS` to the wedge point, has the cosine density
    ``cos(theta) / pi`` on the whole upper hemisphere (one eighth of this).

    Parameters
    ----------
    d : array_like, shape (..., 3)
        Unit directions (finite; they are not normalised).

    Returns
    -------
    ndarray, shape (...)
        The density, in the dtype of *d* (float64 for integer input).

    See Also
    --------
    square_to_cosine_wedge : the map.
    cosine_wedge_density : the same density, elementwise (also inside numba kernels).

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.warps import square_to_cosine_wedge_pdf
    >>> square_to_cosine_wedge_pdf([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.0, 0.6, 0.8]]) * np.pi  # 8, 6.4, outside
    array([8. , 6.4, 0. ])
    """
    d = check_unit_directions(d, "d")
    d64 = d.astype(np.float64)
    density = _density(d64[..., 0], d64[..., 1], d64[..., 2])
    return np.asarray(density, dtype=np.float64).astype(d.dtype, copy=False)


def cosine_wedge_to_square(d: npt.ArrayLike) -> np.ndarray:
    """Inverse of :func:`square_to_cosine_wedge`.

    ``u = x^2 + y^2`` (Malley's projection onto the disk, ``r^2``) and
    ``v = (4/pi) atan2(y, x)``, both clipped into [0, 1].

    Parameters
    ----------
    d : array_like, shape (..., 3)
        Unit directions in W = {x >= y >= 0, z >= 0}, up to a few ulps of
        rounding.

    Returns
    -------
    ndarray, shape (..., 2)
        Points of [0, 1]^2, in the dtype of *d* (float64 for integer input).
        At the pole (0, 0, 1), where every v maps to the same point, v = 0 is
        returned.

    Raises
    ------
    ValueError
        If *d* has the wrong shape, is not finite or does not lie in W.

    See Also
    --------
    square_to_cosine_wedge : the map this inverts.
    cosine_wedge_uv : the same inverse, elementwise (also inside numba kernels).

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.warps import cosine_wedge_to_square, square_to_cosine_wedge
    >>> uv = np.array([[0.25, 0.5], [0.9, 0.1]])
    >>> bool(np.allclose(cosine_wedge_to_square(square_to_cosine_wedge(uv)), uv, rtol=0, atol=1e-15))
    True
    >>> cosine_wedge_to_square([0.0, 0.0, 1.0])
    array([0., 0.])
    """
    d = check_directions(d, "d")
    d64 = d.astype(np.float64)
    x, y, z = d64[..., 0], d64[..., 1], d64[..., 2]
    with np.errstate(over="ignore"):  # a huge vector: rejected as non-unit below
        tol = 8 * np.finfo(d.dtype).eps * np.maximum(np.linalg.norm(d64, axis=-1), 1.0)
        inside = np.all((x - y >= -tol) & (y >= -tol) & (z >= -tol))
    if not inside:
        raise ValueError("'d' must lie in the wedge W = {x >= y >= 0, z >= 0}")
    check_unit_directions(d, "d")  # a zero or non-unit vector would map to a wrong point
    uv = np.stack(_uv(x, y, z), axis=-1)
    return uv.astype(d.dtype, copy=False)


# --- the elementwise triple --------------------------------------------------------
# numpy ufuncs only (no np.where, no branches): numpy runs the formulas on float64 arrays,
# numba compiles them to scalar code inside kernels (the overloads at the end).  The public
# functions check their arguments first; the formulas trust theirs.


@elementwise()
def cosine_wedge_point(u: _Real, v: _Real) -> tuple[_Real, _Real, _Real]:
    """Elementwise forward map: (u, v) in [0, 1]^2 to the direction (x, y, z) in W.

    ``r = sqrt(u)``, ``phi = (pi/4) v``, ``(x, y) = r (cos phi, sin phi)``,
    ``z = sqrt(1 - u)``, with y clamped into [0, x].  Inputs are not
    validated (use :func:`square_to_cosine_wedge` for that); numpy float64
    arrays or scalars, or scalars inside a numba kernel.

    Parameters
    ----------
    u, v : float or ndarray of float64
        Coordinates in [0, 1].

    Returns
    -------
    x, y, z : float or ndarray of float64

    Examples
    --------
    >>> from numba import njit
    >>> from symsphere.warps import cosine_wedge_point
    >>> [round(float(c), 12) for c in cosine_wedge_point(0.64, 0.0)]
    [0.8, 0.0, 0.6]

    Inside a numba kernel:

    >>> @njit
    ... def rim_distance(u, v):
    ...     x, y, z = cosine_wedge_point(u, v)
    ...     return z
    >>> rim_distance(0.75, 0.3)     # sqrt(1 - u)
    0.5
    """
    r = np.sqrt(u)
    phi = v * _QUARTER_PI
    x = r * np.cos(phi)
    y = np.minimum(np.maximum(r * np.sin(phi), 0.0), x)
    return x, y, np.sqrt(1.0 - u)


@elementwise(check=lambda x, y, z: _unit(x, y, z))
def cosine_wedge_density(x: _Real, y: _Real, z: _Real) -> _Real:
    """Elementwise pdf: ``8 z / pi`` where x >= y >= 0 and z >= 0, else 0.

    Checked as :func:`square_to_cosine_wedge_pdf` checks its input (finite unit vectors), except
    inside a numba kernel.

    Parameters
    ----------
    x, y, z : float or ndarray of float64
        Components of unit directions.

    Returns
    -------
    float or ndarray of float64

    Examples
    --------
    >>> import math
    >>> from symsphere.warps import cosine_wedge_density
    >>> float(cosine_wedge_density(0.6, 0.0, 0.8)) == 6.4 / math.pi
    True
    >>> float(cosine_wedge_density(0.0, 0.6, 0.8))     # phi = pi/2: outside W
    0.0
    """
    inside = (x >= y) & (y >= 0.0) & (z >= 0.0)
    return inside * (_WEDGE_DENSITY * np.maximum(z, 0.0))


@elementwise(check=lambda x, y, z: _in_wedge(*_unit(x, y, z)))
def cosine_wedge_uv(x: _Real, y: _Real, z: _Real) -> tuple[_Real, _Real]:
    """Elementwise inverse: a unit direction (x, y, z) of W to (u, v) in [0, 1]^2.

    ``u = x^2 + y^2``, ``v = (4/pi) atan2(y, x)``, both clipped into [0, 1]; z is
    not needed (Malley's projection drops it).  Checked as :func:`cosine_wedge_to_square`
    checks its input (finite unit vectors of W), except inside a numba kernel.

    Parameters
    ----------
    x, y, z : float or ndarray of float64
        Components of unit directions in W.

    Returns
    -------
    u, v : float or ndarray of float64

    Examples
    --------
    >>> from symsphere.warps import cosine_wedge_uv
    >>> [round(float(c), 12) for c in cosine_wedge_uv(0.6, 0.0, 0.8)]
    [0.36, 0.0]
    """
    u = np.minimum(x * x + y * y, 1.0)
    v = np.minimum(np.maximum(np.arctan2(y, x) * _FOUR_OVER_PI, 0.0), 1.0)
    return u, v


def _unit(x: _Real, y: _Real, z: _Real) -> tuple[Any, Any, Any]:
    """x, y, z (see _reals) whose vectors are unit vectors (norm 1 within 10**-3), else ValueError naming them."""
    x, y, z = check_real_arrays((x, "x"), (y, "y"), (z, "z"))
    check_unit_directions(np.stack(np.broadcast_arrays(x, y, z), axis=-1), "x, y, z")
    return x, y, z


def _in_wedge(x: Any, y: Any, z: Any) -> tuple[Any, Any, Any]:
    """x, y, z (unit vectors) that lie in W (within 8 eps), else ValueError naming them."""
    d = np.stack(np.broadcast_arrays(x, y, z), axis=-1)
    tol = 8 * np.finfo(np.float64).eps
    if not np.all((d[..., 0] - d[..., 1] >= -tol) & (d[..., 1] >= -tol) & (d[..., 2] >= -tol)):
        raise ValueError("'x', 'y', 'z' must lie in the wedge W = {x >= y >= 0, z >= 0}")
    return x, y, z


# The bare formulas, for the array maps above (their inputs are checked there).
_point = formula(cosine_wedge_point)
_density = formula(cosine_wedge_density)
_uv = formula(cosine_wedge_uv)

register(
    Warp(name="cosine_wedge", domain="wedge", uniform=False, orbit_size=8, forward=square_to_cosine_wedge,
         pdf=square_to_cosine_wedge_pdf, inverse=cosine_wedge_to_square, point=cosine_wedge_point,
         density=cosine_wedge_density, reference="Malley's method on the disk sector 0 <= phi <= pi/4"),
)  # fmt: skip


route_compiles(globals())  # the first compile of each numba function here: interruptible (_threads)
