"""Arrays: points of the square, directions, normals and triangles, dtypes, out=, user functions' values, images.

Part of :mod:`symsphere._validation` (import the validators from there).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, overload

import numpy as np
import numpy.typing as npt

from .._typing import Float64Array, FloatArray
from .values import MAX_DIMENSIONS, short_repr

__all__ = [
    "UNIT_TOLERANCE",
    "as_float_array",
    "check_dimensions",
    "check_directions",
    "check_dtype",
    "check_finite_array",
    "check_float32_range",
    "check_image",
    "check_normal",
    "check_out",
    "check_real_arrays",
    "check_real_values",
    "check_samples",
    "check_triangle",
    "check_unit_directions",
    "off_unit",
    "unit_bounds",
    "check_uv",
]


_DTYPES = (np.dtype(np.float64), np.dtype(np.float32))


def check_real_values(values: object, name: str = "f", *, finite: bool = True) -> Float64Array:
    """What a user's function returned, as a finite float64 array; TypeError for complex or non-numeric
    values (converting would drop the imaginary part), ValueError for NaN or inf (``finite=False``: the
    caller checks, to say where).

    Examples
    --------
    >>> from symsphere._validation import check_real_values
    >>> check_real_values([1, 2.5])
    array([1. , 2.5])
    >>> check_real_values([1j])
    Traceback (most recent call last):
        ...
    TypeError: 'f' returned complex values; return the real and imaginary parts as two components (shape (m, 2))
    """
    try:
        arr = np.asarray(values)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"'{name}' must return an array of real numbers ({exc})") from None
    if arr.dtype.kind == "c":
        raise TypeError(
            f"'{name}' returned complex values; return the real and imaginary parts as two components (shape (m, 2))"
        )
    if arr.dtype.kind not in "biuf":
        raise TypeError(f"'{name}' must return real numbers, got dtype {arr.dtype}")
    out: Float64Array = arr.astype(np.float64)
    if finite and not np.all(np.isfinite(out)):
        raise ValueError(f"'{name}' returned non-finite values (NaN or inf)")
    return out


def check_dimensions(arr: npt.NDArray[Any], name: str) -> None:
    """Raise ValueError naming *name* if *arr* has more than :data:`MAX_DIMENSIONS` dimensions."""
    if arr.ndim > MAX_DIMENSIONS:
        raise ValueError(f"'{name}' has {arr.ndim} dimensions; at most {MAX_DIMENSIONS} are supported")


def check_dtype(dtype: npt.DTypeLike, name: str = "dtype") -> np.dtype[Any]:
    """Return *dtype* as float32 or float64, else raise TypeError."""
    try:
        dt = np.dtype(dtype)
    except TypeError as exc:
        raise TypeError(f"'{name}' must be float32 or float64, got {short_repr(dtype)}") from exc
    if dt not in _DTYPES:
        raise TypeError(f"'{name}' must be float32 or float64, got {dt}")
    return dt


def check_out(out: object, shape: Sequence[int], dtype: npt.DTypeLike, name: str = "out") -> FloatArray:
    """Check a user-supplied output array, as ``Generator.random`` does."""
    if not isinstance(out, np.ndarray):
        raise TypeError(f"'{name}' must be a numpy array, got {type(out).__name__}")
    if out.shape != tuple(shape):
        raise ValueError(f"'{name}' must have shape {tuple(shape)}, got {out.shape}")
    if out.dtype != dtype:
        raise TypeError(f"'{name}' has dtype {out.dtype} but dtype={dtype} was asked for; they must match")
    if not (out.flags.c_contiguous and out.flags.writeable and out.flags.aligned):
        raise ValueError(f"'{name}' must be C-contiguous, writeable and aligned")
    return out


def as_float_array(a: object, name: str) -> FloatArray:
    """*a* as a float array (integers and bools become float64); TypeError naming *name* otherwise."""
    if isinstance(a, (str, bytes)):
        raise TypeError(f"'{name}' must be an array of numbers, got {type(a).__name__}")
    try:
        arr = np.asarray(a)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"'{name}' must be an array of numbers") from exc
    if arr.dtype.kind not in "biuf":
        raise TypeError(f"'{name}' must be an array of real numbers, got dtype {arr.dtype}")
    if arr.dtype.kind != "f":
        return arr.astype(np.float64)
    out: FloatArray = arr
    return out


def _rows_of(value: object, name: str, width: int) -> FloatArray:
    """*value* as a float array of shape (..., width), or the error naming *name*."""
    arr = as_float_array(value, name)
    check_dimensions(arr, name)
    if arr.ndim == 0 or arr.shape[-1] != width:
        raise ValueError(f"'{name}' must have shape (..., {width}), got {arr.shape}")
    return arr


def check_uv(uv: object, name: str = "uv") -> FloatArray:
    """Return points of the unit square as a float array of shape (..., 2)."""
    arr = _rows_of(uv, name, 2)
    if not np.all((arr >= 0) & (arr <= 1)):  # also rejects NaN
        raise ValueError(f"'{name}' must lie in the closed unit square [0, 1]^2 (no NaN)")
    return arr


def check_directions(d: object, name: str = "d") -> FloatArray:
    """Return finite vectors as a float array of shape (..., 3)."""
    arr = _rows_of(d, name, 3)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"'{name}' must be finite (no NaN or inf)")
    return arr


def check_finite_array(a: object, name: str) -> FloatArray:
    """*a* as a float array of any shape (at most :data:`MAX_DIMENSIONS`) without NaN or inf.

    Examples
    --------
    >>> from symsphere._validation import check_finite_array
    >>> check_finite_array([1, 2], "c")
    array([1., 2.])
    >>> check_finite_array([0.5, float("nan")], "c")
    Traceback (most recent call last):
        ...
    ValueError: 'c' must be finite (no NaN or inf); got [0.5, nan]
    """
    arr = as_float_array(a, name)
    check_dimensions(arr, name)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"'{name}' must be finite (no NaN or inf); got {short_repr(a)}")
    return arr


UNIT_TOLERANCE = 1e-3
"""How far from 1 the norm of a direction given to a density or an inverse map may be (float32 rounding
and user normalisation pass; a zero, a non-normalised or a mistyped vector does not)."""


def check_unit_directions(d: object, name: str = "d") -> FloatArray:
    """Return unit vectors as a float array of shape (..., 3): :func:`check_directions`, and every norm
    within :data:`UNIT_TOLERANCE` of 1 (a density of a non-unit vector would be silently wrong).

    Examples
    --------
    >>> from symsphere._validation import check_unit_directions
    >>> check_unit_directions([0.0, 0.6, 0.8]).tolist()
    [0.0, 0.6, 0.8]
    >>> check_unit_directions([0.0, 0.0, 2.0])
    Traceback (most recent call last):
        ...
    ValueError: 'd' must be unit vectors (norm 1 within 0.001); got a norm of 2
    """
    arr = check_directions(d, name)
    if arr.size:
        wide = arr.astype(np.float64, copy=False)
        bad = off_unit(wide, UNIT_TOLERANCE)
        if np.any(bad):
            norm = math.hypot(*wide[bad][0].tolist())  # the first bad vector's, without overflow in its squares
            raise ValueError(
                f"'{name}' must be unit vectors (norm 1 within {UNIT_TOLERANCE:g}); got a norm of {norm:.6g}"
            )
    return arr


def off_unit(wide: npt.NDArray[np.float64], tolerance: float) -> npt.NDArray[np.bool_]:
    """Which vectors of *wide* (float64, shape (..., 3)) are not unit vectors: their norm farther than
    *tolerance* from 1, or not finite.  The one test of unit length in the package (the checks of
    arguments here, and :func:`symsphere.stats.chi2_test`'s of a sampler's output, with its own
    tolerance): the squared norm in one pass against :func:`unit_bounds`, no square root.
    """
    lo, hi = unit_bounds(tolerance)
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):  # an overflow (inf) or underflow (0) is off
        squares = np.einsum("...i,...i->...", wide, wide)
    within: npt.NDArray[np.bool_] = (squares >= lo) & (squares <= hi)
    return ~within


def unit_bounds(tolerance: float) -> tuple[float, float]:
    """``((1 - tolerance)**2, (1 + tolerance)**2)``: a vector's norm is within *tolerance* of 1 when its
    squared norm is within these (:func:`off_unit`, and the compiled check of streamed directions)."""
    return (1.0 - tolerance) ** 2, (1.0 + tolerance) ** 2


def check_samples(samples: object, name: str = "samples") -> FloatArray:
    """Return direction samples as a float32 or float64 array of shape (n, 3), n >= 1."""
    d = check_directions(samples, name)
    if d.dtype not in (np.dtype(np.float32), np.dtype(np.float64)):
        raise TypeError(f"'{name}' must be float32 or float64, got {d.dtype}")
    if d.ndim != 2 or d.shape[0] < 1:
        raise ValueError(f"'{name}' must have shape (n, 3) with n >= 1, got {d.shape}")
    return d


def check_triangle(a: npt.ArrayLike, b: npt.ArrayLike, c: npt.ArrayLike) -> Float64Array:
    """Return the vertices of a non-degenerate spherical triangle as unit vectors, shape (3, 3)."""
    for v, name in ((a, "a"), (b, "b"), (c, "c")):
        if v is None:
            raise TypeError(f"'{name}' must be a 3-vector (a vertex of the triangle), got None")
    verts = np.stack([check_normal(v, name) for v, name in ((a, "a"), (b, "b"), (c, "c"))])
    A, B, C = verts
    # Its area by Van Oosterom & Strackee (1983): tan(E/2) = |A.(B x C)| / (1 + A.B + B.C + C.A).
    area = 2.0 * math.atan2(abs(float(np.dot(A, np.cross(B, C)))), 1.0 + A @ B + B @ C + C @ A)
    if area < 1e-12:
        raise ValueError(
            "'a', 'b', 'c' must span a non-degenerate spherical triangle (distinct, not on one great circle)"
        )
    return verts


@overload
def check_normal(normal: None, name: str = ...) -> None: ...


@overload
def check_normal(normal: npt.ArrayLike, name: str = ...) -> Float64Array: ...


def check_normal(normal: npt.ArrayLike | None, name: str = "normal") -> Float64Array | None:
    """Return *normal* as a unit float64 3-vector, or None."""
    if normal is None:
        return None
    arr = as_float_array(normal, name).astype(np.float64)
    if arr.shape != (3,):
        raise ValueError(f"'{name}' must be a 3-vector, got shape {arr.shape}")
    values = arr.tolist()
    if not all(math.isfinite(c) for c in values) or not any(values):
        raise ValueError(f"'{name}' must be a finite, non-zero 3-vector, got {values}")
    # IEEE-only, so the same bits on every machine: squares and the division correctly rounded, the sum
    # exactly rounded (math.fsum), sqrt correctly rounded.  np.linalg.norm's dot product comes from
    # BLAS, whose kernels differ by CPU (OpenBLAS's AVX-512 one uses FMA): 3**-0.5 * (1, 1, 1) was left
    # as it is on an AMD AVX2 machine and changed by 1 ulp on an Intel AVX-512 one.  In Python floats:
    # a sampler calls this after writing its last output, which leaves numpy's code out of the caches
    # (each numpy call then costs ~10-30 us; docs/results/write-limit.md).
    largest = max(abs(c) for c in values)
    if (
        not 1e-150 < largest < 1e150
    ):  # scale first: the squares of [1e200, 0, 0] or [1e-170, 0, 0] overflow or underflow
        values = [c / largest for c in values]
    norm = math.sqrt(math.fsum([c * c for c in values]))
    unit: Float64Array = np.array([c / norm for c in values])
    return unit


def check_real_arrays(*named: tuple[object, str], unit_interval: bool = False) -> list[Any]:
    """Each (value, name) as finite float64, broadcast together (numpy scalars if all are scalars); errors name them.

    For the public scalar functions (frames, wedge, warps) that also run inside numba kernels: from Python
    they check what their array twins check.  With *unit_interval* every value must lie in [0, 1].

    Examples
    --------
    >>> from symsphere._validation import check_real_arrays
    >>> check_real_arrays((0.5, "u"), (2.0, "v"), unit_interval=True)
    Traceback (most recent call last):
        ...
    ValueError: 'v' must lie in [0, 1]; got 2.0
    """
    arrays = []
    for value, name in named:
        if value is None:
            raise TypeError(f"'{name}' must be a real number or an array of real numbers; got None")
        arr = as_float_array(value, name).astype(np.float64, copy=False)
        check_dimensions(arr, name)
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"'{name}' must be finite (no NaN or inf); got {short_repr(value)}")
        if unit_interval and not np.all((arr >= 0) & (arr <= 1)):
            raise ValueError(f"'{name}' must lie in [0, 1]; got {short_repr(value)}")
        arrays.append(arr)
    try:
        np.broadcast_shapes(*(a.shape for a in arrays))
    except ValueError:
        names = ", ".join(f"'{name}'" for _, name in named)
        raise ValueError(f"{names} must broadcast together; got shapes {[a.shape for a in arrays]}") from None
    if any(a.ndim for a in arrays):  # every output then has the broadcast shape (z = sqrt(1 - u) ignores v)
        return list(np.broadcast_arrays(*arrays))
    return [a[()] for a in arrays]


# ---------------------------------------------------------------------------
# Images (symsphere.render.image)
# ---------------------------------------------------------------------------


def check_image(image: object, name: str = "image") -> npt.NDArray[np.floating[Any]]:
    """*image* as a floating-point array of shape (height, width, 3), both sizes >= 1; TypeError or ValueError."""
    try:
        arr = np.asarray(image)
    except (TypeError, ValueError):
        raise TypeError(f"'{name}' must be an array of shape (height, width, 3)") from None
    if arr.ndim != 3 or arr.shape[2] != 3 or arr.shape[0] < 1 or arr.shape[1] < 1:
        raise ValueError(f"'{name}' must have shape (height, width, 3), got {arr.shape}")
    if not np.issubdtype(arr.dtype, np.floating):
        raise TypeError(f"'{name}' must be a floating-point array, got dtype {arr.dtype}")
    out: npt.NDArray[np.floating[Any]] = arr
    return out


def check_float32_range(image: npt.NDArray[np.floating[Any]], name: str = "image") -> None:
    """A PFM holds float32: finite values beyond its range would turn into inf (NaN and inf are kept)."""
    finite = image[np.isfinite(image)]
    largest = float(np.max(np.abs(finite))) if finite.size else 0.0
    limit = float(np.finfo(np.float32).max)
    if largest > limit:
        raise ValueError(
            f"'{name}' has values up to {largest:.3g}, beyond float32's {limit:.3g}, which a PFM cannot hold"
        )
