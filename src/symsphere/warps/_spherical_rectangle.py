"""Urena, Fajardo & King's uniform sampling of a spherical rectangle (EGSR 2013): forward, pdf, inverse.

The rectangle ``{corner + s edge1 + t edge2 : s, t in [0, 1]}`` (edges orthogonal) is seen from the
origin.  In the frame of its edges (x along edge1, y along edge2, z along their normal, flipped so that
the rectangle lies at z0 < 0) the corners are (x0 | x1, y0 | y1, z0).  u picks the abscissa xu whose
sub-rectangle [x0, xu] x [y0, y1] has solid angle u S; v then places the point on the segment x = xu
uniformly in ``h = y / sqrt(xu^2 + z0^2 + y^2)`` (the sine of its elevation from the plane y = 0 seen
along x = xu), which is uniform in solid angle.  The density is 1/S.

The scalar formulas (:func:`rectangle_frame`, :func:`rectangle_point`) are the ones the numba renderer
compiles into its kernels (``symsphere.render``'s rectangle lights); the numpy functions run them in a
compiled loop, in float64 whatever the input dtype.  Called from Python the two check their numbers
first (:func:`._common.elementwise`); inside a kernel they are the bare formulas.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt
from numba import njit

from .._threads import route_compiles
from .._typing import Float64Array, FloatArray
from .._validation import check_unit_directions, check_uv, real_number, short_repr
from .._validation.arrays import as_float_array
from ._common import elementwise, formula

__all__ = [
    "square_to_spherical_rectangle",
    "square_to_spherical_rectangle_pdf",
    "spherical_rectangle_to_square",
    "rectangle_frame",
    "rectangle_point",
]

_PI = math.pi
# The largest magnitude of a coordinate (and the smallest of a non-zero z0) that rectangle_frame accepts:
# its complex products multiply eight coordinates, at most 625 L^8 (1e243) and, with |z0| >= 1 / L, at
# least |z0|^4 (1e-120) for the number it divides by, so that every value it returns is finite.
_LIMIT = 1e30


def _number(value: object, name: str) -> float:
    """*value* as a float; TypeError naming *name* unless it is a real number (not a bool, not an array)."""
    result = real_number(value)
    if result is None:
        raise TypeError(f"'{name}' must be a real number, got {type(value).__name__} {short_repr(value)}")
    return result


def _in_range(value: object, name: str, low: float, high: float, what: str) -> float:
    """*value* as a float in [low, high]; ValueError naming *name* and saying *what* otherwise (NaN too)."""
    result = _number(value, name)
    if not low <= result <= high:
        raise ValueError(f"'{name}' must be {what}, got {short_repr(value)}")
    return result


def _frame_arguments(x0: object, y0: object, z0: object, width: object, height: object) -> tuple[float, ...]:
    """The arguments of :func:`rectangle_frame` as floats in its domain, else TypeError/ValueError naming one."""
    coordinate = f"a finite number of magnitude at most {_LIMIT:g}"
    x, y = (_in_range(v, n, -_LIMIT, _LIMIT, coordinate) for v, n in ((x0, "x0"), (y0, "y0")))
    z = _in_range(z0, "z0", -_LIMIT, _LIMIT, coordinate)
    if z != 0.0 and abs(z) < 1.0 / _LIMIT:
        raise ValueError(f"'z0' must be 0 or of magnitude at least {1.0 / _LIMIT:g}, got {short_repr(z0)}")
    positive = f"a finite positive number at most {_LIMIT:g}"
    w, h = (_in_range(v, n, 0.0, _LIMIT, positive) for v, n in ((width, "width"), (height, "height")))
    for value, name, number in ((width, "width", w), (height, "height", h)):
        if number == 0.0:
            raise ValueError(f"'{name}' must be {positive}, got {short_repr(value)}")
    return x, y, z, w, h


def _point_arguments(*values: object) -> tuple[float, ...]:
    """The arguments of :func:`rectangle_point` as floats in its domain, else TypeError/ValueError naming one.

    Only ranges are checked (not that the numbers are one :func:`rectangle_frame`'s): within them every
    value the formula returns is finite.
    """
    u, v, s, x0, y0, z0, x1, y1, b0, b1, ck, sk = values
    coordinate = f"a finite number of magnitude at most {2 * _LIMIT:g} (a corner of rectangle_frame)"
    unit = "a number in [0, 1]"
    cosine = "a number in [-1, 1] (as rectangle_frame returns it)"
    checked = (
        _in_range(u, "u", 0.0, 1.0, unit),
        _in_range(v, "v", 0.0, 1.0, unit),
        _in_range(s, "solid_angle", 0.0, 2 * _PI, "a solid angle in [0, 2 pi]"),
        _in_range(x0, "x0", -2 * _LIMIT, 2 * _LIMIT, coordinate),
        _in_range(y0, "y0", -2 * _LIMIT, 2 * _LIMIT, coordinate),
        _in_range(z0, "z0", -2 * _LIMIT, -1.0 / _LIMIT,
                  f"negative, of magnitude in [{1.0 / _LIMIT:g}, {2 * _LIMIT:g}] (rectangle_frame's flipped z0)"),
        _in_range(x1, "x1", -2 * _LIMIT, 2 * _LIMIT, coordinate),
        _in_range(y1, "y1", -2 * _LIMIT, 2 * _LIMIT, coordinate),
        *(_in_range(c, n, -1.0, 1.0, cosine) for c, n in ((b0, "b0"), (b1, "b1"), (ck, "ck"), (sk, "sk"))),
    )  # fmt: skip
    for low, high, name in ((checked[3], checked[6], "x1"), (checked[4], checked[7], "y1")):
        if high < low:
            raise ValueError(f"'{name}' must be >= '{name[0]}0' ({low!r}), got {high!r}")
    return checked


@elementwise(check=_frame_arguments)
def rectangle_frame(x0: float, y0: float, z0: float, width: float, height: float) -> tuple[float, ...]:
    """The spherical rectangle of the corners (x0 | x0 + width, y0 | y0 + height, z0) seen from the origin.

    Returns (S, x0, y0, z0, x1, y1, zsign, b0, b1, cos k, sin k): the solid angle S, the corners with z0
    flipped to be negative (zsign = -1 if it was), and the constants of :func:`rectangle_point`
    (b0 = n0.z, b1 = n2.z, k = 2 pi - g2 - g3 in Urena et al.'s notation).  S = 0 when the origin lies
    in the rectangle's plane.

    No normal is formed (pbrt-v4: four cross products, four normalisations, four ``asin``): with
    a = -z0 and r_xy the distance to corner (x, y), the angle at that corner has cosine and sine
    proportional to (+-x y, a r_xy), so ``g = pi / 2 -+ A_xy`` with ``A_xy = atan(x y / (a r_xy))``,
    whence S = (A11 - A10) + (A00 - A01) (the classic solid angle of a rectangle; no cancellation
    against 2 pi) and k = pi - (A00 - A01).  The sums of angles are formed as products of the complex
    numbers ``a r_xy + i x y`` (whose arguments are the A_xy), so that one ``atan2`` gives S: in
    [0, pi] unless the foot of the origin lies inside the rectangle, in (0, 2 pi) then (the argument is
    taken of -Z there, which has no branch cut near S = 0).  ``e^{ik}`` is the normalised conjugate of
    -(A00 - A01)'s number: no angle.

    Called from Python the five numbers are checked first; inside a numba kernel this is the bare
    formula, trusting its arguments (the renderer's lights are checked when the scene is read).

    Parameters
    ----------
    x0, y0, z0 : float
        The corner, in the frame of the edges; real numbers of magnitude at most 1e30, z0 either 0 or
        of magnitude at least 1e-30 (within these every returned value is finite).
    width, height : float
        The lengths of the edges along x and y: positive real numbers, at most 1e30.

    Returns
    -------
    tuple of 11 floats
        (S, x0, y0, z0, x1, y1, zsign, b0, b1, cos k, sin k).

    Raises
    ------
    TypeError
        If an argument is not a real number (a bool, a string, an array, None); the message names it.
    ValueError
        If an argument is NaN, inf or outside the ranges above; the message names it.

    Examples
    --------
    >>> import math
    >>> from symsphere.warps import rectangle_frame
    >>> s = rectangle_frame(-1.0, -1.0, 1.0, 2.0, 2.0)[0]      # a face of the cube [-1, 1]^3
    >>> bool(math.isclose(s, 2 * math.pi / 3))
    True
    >>> rectangle_frame(-1.0, -1.0, 1.0, 2.0, float("nan"))
    Traceback (most recent call last):
        ...
    ValueError: 'height' must be a finite positive number at most 1e+30, got nan
    """
    zsign = 1.0
    if z0 > 0.0:
        zsign = -1.0
        z0 = -z0
    if not z0 < 0.0:
        return 0.0, x0, y0, z0, x0, y0, zsign, 0.0, 0.0, 1.0, 0.0
    x1 = x0 + width
    y1 = y0 + height
    a = -z0
    z2 = z0 * z0
    x02, x12, y02, y12 = x0 * x0, x1 * x1, y0 * y0, y1 * y1
    c00 = a * math.sqrt(x02 + y02 + z2)  # e^{i A_xy} is proportional to c_xy + i x y
    c10 = a * math.sqrt(x12 + y02 + z2)
    c01 = a * math.sqrt(x02 + y12 + z2)
    c11 = a * math.sqrt(x12 + y12 + z2)
    s00, s10, s01, s11 = x0 * y0, x1 * y0, x0 * y1, x1 * y1
    re1 = c11 * c10 + s11 * s10  # (c11 + i s11) (c10 - i s10): A11 - A10
    im1 = s11 * c10 - c11 * s10
    re2 = c00 * c01 + s00 * s01  # (c00 + i s00) (c01 - i s01): A00 - A01
    im2 = s00 * c01 - c00 * s01
    re = re1 * re2 - im1 * im2
    im = re1 * im2 + im1 * re2
    if x0 < 0.0 and x1 > 0.0 and y0 < 0.0 and y1 > 0.0:
        solid_angle = _PI + math.atan2(-im, -re)
    else:
        solid_angle = max(0.0, math.atan2(im, re))
    inv2 = 1.0 / math.sqrt(re2 * re2 + im2 * im2)
    b0 = -y0 / math.sqrt(y02 + z2)
    b1 = y1 / math.sqrt(y12 + z2)
    return solid_angle, x0, y0, z0, x1, y1, zsign, b0, b1, -re2 * inv2, im2 * inv2


@elementwise(check=_point_arguments)
def rectangle_point(
    u: float,
    v: float,
    solid_angle: float,
    x0: float,
    y0: float,
    z0: float,
    x1: float,
    y1: float,
    b0: float,
    b1: float,
    ck: float,
    sk: float,
) -> tuple[float, float, float]:
    """The point (xu, yv) of the rectangle's plane z = z0 (frame of :func:`rectangle_frame`) for (u, v),
    and its squared distance from the origin (Urena et al. 2013, section 4).

    au = u S + k; cu = fu / sqrt(fu^2 + b0^2), fu = (cos(au) b0 - b1) / sin(au), and
    xu = -cu z0 / sqrt(1 - cu^2) = -z0 sign(fu) / sqrt(fu^2 - (1 - b0^2)), 1 - b0^2 = z0^2 / (y0^2 + z0^2):
    xu = -z0 sign(nu) sin(au) / sqrt(nu^2 - (1 - b0^2) sin(au)^2) with nu = cos(au) b0 - b1.

    Called from Python the twelve numbers are checked first (their ranges, not that they are one
    frame's); inside a numba kernel this is the bare formula, trusting its arguments.

    Parameters
    ----------
    u, v : float
        The point of the unit square, in [0, 1].
    solid_angle, x0, y0, z0, x1, y1, b0, b1, ck, sk : float
        :func:`rectangle_frame`'s values (all but zsign): S in [0, 2 pi]; the corners of magnitude at
        most 2e30, x0 <= x1, y0 <= y1, z0 negative of magnitude at least 1e-30; b0, b1, ck, sk in
        [-1, 1].

    Returns
    -------
    xu, yv, dist2 : float
        The point of the plane z = z0 and its squared distance from the origin (finite).

    Raises
    ------
    TypeError
        If an argument is not a real number; the message names it.
    ValueError
        If an argument is NaN, inf or outside its range; the message names it.

    Examples
    --------
    >>> from symsphere.warps import rectangle_frame, rectangle_point
    >>> frame = rectangle_frame(-1.0, -1.0, 1.0, 2.0, 2.0)
    >>> x, y, d2 = rectangle_point(0.5, 0.5, frame[0], *frame[1:6], *frame[7:])
    >>> round(x, 12) + 0.0, round(y, 12) + 0.0, round(d2, 12)
    (0.0, 0.0, 1.0)
    >>> rectangle_point(1.5, 0.5, frame[0], *frame[1:6], *frame[7:])
    Traceback (most recent call last):
        ...
    ValueError: 'u' must be a number in [0, 1], got 1.5
    """
    cs = math.cos(u * solid_angle)
    ss = math.sin(u * solid_angle)
    ca = cs * ck - ss * sk
    sa = ss * ck + cs * sk
    nu = ca * b0 - b1
    z2 = z0 * z0
    den = nu * nu - z2 / (y0 * y0 + z2) * (sa * sa)
    xu = -z0 * math.copysign(1.0, nu) * sa / math.sqrt(max(den, 1e-300))
    xu = min(max(xu, x0), x1)
    d2 = xu * xu + z2
    h0 = y0 / math.sqrt(d2 + y0 * y0)
    h1 = y1 / math.sqrt(d2 + y1 * y1)
    hv = h0 + v * (h1 - h0)
    hv2 = hv * hv
    yv = hv * math.sqrt(d2 / (1.0 - hv2)) if hv2 < 1.0 - 1e-12 else y1
    yv = min(max(yv, y0), y1)
    return xu, yv, d2 + yv * yv


_rectangle_frame = formula(rectangle_frame)


# --- the numpy forms -----------------------------------------------------------------------------


def _frame(corner: npt.ArrayLike, edge1: npt.ArrayLike, edge2: npt.ArrayLike) -> tuple[Float64Array, tuple[float, ...]]:
    """The unit frame (rows e, f, g = e x f) of the rectangle and :func:`rectangle_frame` of it."""
    c = as_float_array(corner, "corner").astype(np.float64)
    e1 = as_float_array(edge1, "edge1").astype(np.float64)
    e2 = as_float_array(edge2, "edge2").astype(np.float64)
    for v, name in ((c, "corner"), (e1, "edge1"), (e2, "edge2")):
        if v.shape != (3,) or not np.all(np.isfinite(v)):
            raise ValueError(f"'{name}' must be a finite 3-vector, got {v.tolist()}")
    with np.errstate(over="ignore", invalid="ignore"):
        w, h = float(np.linalg.norm(e1)), float(np.linalg.norm(e2))
        if not (0 < w < np.inf and 0 < h < np.inf) or not abs(float(e1 @ e2)) <= 1e-9 * w * h:
            raise ValueError("'edge1' and 'edge2' must be non-zero, finite and orthogonal (the edges of a rectangle)")
        e, f = e1 / w, e2 / h
        rows = np.array([e, f, np.cross(e, f)])
        x0, y0, z0 = (float(r @ c) for r in rows)
        setup = _rectangle_frame(x0, y0, z0, w, h)  # the bare formula: its result is checked below
    if not (setup[0] > 0.0 and all(math.isfinite(x) for x in setup)):
        raise ValueError(
            "'corner', 'edge1', 'edge2' must give a rectangle of positive, finite solid angle "
            "(the origin not in its plane, coordinates below 1e150)"
        )
    return rows, setup


@njit(cache=True, error_model="numpy")
def _forward_kernel(uv: Any, setup: Any, out: Any) -> None:  # pragma: no cover - compiled
    s, x0, y0, z0, x1, y1, zsign, b0, b1, ck, sk = setup
    for i in range(uv.shape[0]):
        xu, yv, dist2 = rectangle_point(uv[i, 0], uv[i, 1], s, x0, y0, z0, x1, y1, b0, b1, ck, sk)
        inv = 1.0 / math.sqrt(dist2)
        out[i, 0] = xu * inv
        out[i, 1] = yv * inv
        out[i, 2] = z0 * zsign * inv


@njit(cache=True, error_model="numpy")
def _sub_solid_angles(
    x: Any, x0: float, y0: float, z0: float, height: float, out: Any
) -> None:  # pragma: no cover - compiled
    for i in range(x.shape[0]):
        out[i] = rectangle_frame(x0, y0, z0, max(x[i] - x0, 0.0), height)[0]


def square_to_spherical_rectangle(
    uv: npt.ArrayLike, corner: npt.ArrayLike, edge1: npt.ArrayLike, edge2: npt.ArrayLike
) -> FloatArray:
    """Urena et al.'s area-preserving map of the square onto the rectangle seen from the origin.

    Urena, Fajardo & King, "An Area-Preserving Parametrization for Spherical Rectangles", EGSR 2013;
    pbrt-v4 ``SampleSphericalRectangle``.  u = 0 is the edge through *corner* along *edge2*, v = 0 the
    edge through it along *edge1*.

    Parameters
    ----------
    uv : array_like, shape (..., 2)
    corner, edge1, edge2 : array_like of 3 floats
        The rectangle ``corner + s edge1 + t edge2``, s, t in [0, 1]; the edges orthogonal; the origin
        not in its plane.

    Returns
    -------
    ndarray, shape (..., 3)
        Unit directions towards the rectangle, density 1/S (float64 inside; the input's dtype out).

    Examples
    --------
    >>> from symsphere.warps import square_to_spherical_rectangle
    >>> square_to_spherical_rectangle([[0.5, 0.5]], [-1, -1, 1], [2, 0, 0], [0, 2, 0]).round(12) + 0.0
    array([[0., 0., 1.]])
    """
    uv = check_uv(uv)
    rows, setup = _frame(corner, edge1, edge2)
    flat = np.ascontiguousarray(uv.reshape(-1, 2), dtype=np.float64)
    local = np.empty((flat.shape[0], 3))
    _forward_kernel(flat, setup, local)
    d = local @ rows
    return d.reshape(*uv.shape[:-1], 3).astype(uv.dtype, copy=False)


def _local_hits(d: Float64Array, rows: Float64Array, setup: tuple[float, ...]) -> tuple[Any, Any, Any]:
    """(x, y, inside) of the rays d in the rectangle's flipped frame (inside: they hit it)."""
    s, x0, y0, z0, x1, y1, zsign = setup[:7]
    local = d @ rows.T
    dz = local[..., 2] * zsign
    with np.errstate(divide="ignore", invalid="ignore"):
        t = z0 / dz
        x, y = t * local[..., 0], t * local[..., 1]
    inside = (dz < 0) & (x >= x0) & (x <= x1) & (y >= y0) & (y <= y1)
    return np.where(inside, x, x0), np.where(inside, y, y0), inside


def square_to_spherical_rectangle_pdf(
    d: npt.ArrayLike, corner: npt.ArrayLike, edge1: npt.ArrayLike, edge2: npt.ArrayLike
) -> Float64Array:
    """Density of :func:`square_to_spherical_rectangle`: 1/S towards the rectangle, 0 elsewhere.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.warps import square_to_spherical_rectangle_pdf
    >>> p = square_to_spherical_rectangle_pdf([[0, 0, 1], [0, 0, -1]], [-1, -1, 1], [2, 0, 0], [0, 2, 0])
    >>> bool(np.isclose(p[0], 3 / (2 * np.pi))), float(p[1])      # a face of a cube: 2 pi / 3 sr
    (True, 0.0)
    """
    from .._validation import check_directions

    d = check_directions(d, "d").astype(np.float64)
    rows, setup = _frame(corner, edge1, edge2)
    inside = _local_hits(d, rows, setup)[2]
    return np.where(inside, 1.0 / setup[0], 0.0)


def spherical_rectangle_to_square(
    d: npt.ArrayLike, corner: npt.ArrayLike, edge1: npt.ArrayLike, edge2: npt.ArrayLike
) -> FloatArray:
    """Inverse of :func:`square_to_spherical_rectangle` (directions that miss the rectangle: clipped).

    u = S([x0, x] x [y0, y1]) / S, the solid angle of the sub-rectangle up to the hit's abscissa x
    (:func:`rectangle_frame` of it), and v = (h - h0) / (h1 - h0) with h = y / sqrt(x^2 + z0^2 + y^2).

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.warps import spherical_rectangle_to_square, square_to_spherical_rectangle
    >>> rect = ([-1, -0.5, 1.2], [2, 0, 0], [0, 1.5, 0])
    >>> uv = np.array([[0.3, 0.8]])
    >>> bool(np.allclose(spherical_rectangle_to_square(square_to_spherical_rectangle(uv, *rect), *rect), uv))
    True
    """
    d = check_unit_directions(d, "d")
    rows, setup = _frame(corner, edge1, edge2)
    s, x0, y0, z0, x1, y1 = setup[:6]
    x, y, _ = _local_hits(d.astype(np.float64), rows, setup)
    sub = np.empty(x.size)
    _sub_solid_angles(np.ascontiguousarray(x.reshape(-1)), x0, y0, z0, y1 - y0, sub)
    u = sub.reshape(x.shape) / s
    d2 = x * x + z0 * z0
    h0 = y0 / np.sqrt(d2 + y0 * y0)
    h1 = y1 / np.sqrt(d2 + y1 * y1)
    h = y / np.sqrt(d2 + y * y)
    span = h1 - h0
    v = np.where(span > 0, (h - h0) / np.where(span > 0, span, 1.0), 0.0)
    uv: Float64Array = np.clip(np.stack([u, v], axis=-1), 0.0, 1.0)
    return uv.astype(d.dtype, copy=False)


route_compiles(globals())  # the first compile of each numba function here: interruptible (_threads)
