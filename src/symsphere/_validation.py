"""Validators shared by the public functions.

Each raises ``TypeError`` or ``ValueError`` with a message that names the
argument and says what is allowed.  Public functions call these at the
boundary; private helpers trust their inputs.
"""

from __future__ import annotations

import errno
import math
import numbers
import os
import secrets
import stat
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, TypeVar, cast, overload

import numpy as np
import numpy.typing as npt

from ._typing import Density, Float64Array, FloatArray

__all__ = [
    "MAX_BINS",
    "MAX_COUNT",
    "MAX_DIMENSIONS",
    "MAX_PATHS",
    "MAX_PIXELS",
    "MAX_POLYNOMIAL_DEGREE",
    "MAX_QUADRATURE_ORDER",
    "MAX_SH_DEGREE",
    "MAX_SOBOL_POINTS",
    "MAX_TASKS",
    "TEMPORARY_KINDS",
    "UNIT_TOLERANCE",
    "as_float_array",
    "check_bins",
    "check_callable",
    "check_choice",
    "check_coeffs",
    "check_count",
    "check_dimensions",
    "check_directions",
    "check_dtype",
    "check_exponents",
    "check_finite_array",
    "check_index",
    "check_lm",
    "check_nonnegative",
    "check_normal",
    "check_open_unit",
    "check_out",
    "check_output_path",
    "check_path",
    "check_pdf",
    "check_positive",
    "check_positive_real",
    "check_real",
    "check_real_arrays",
    "check_real_values",
    "check_rng",
    "check_samples",
    "check_seed",
    "check_size",
    "check_sobol_size",
    "check_triangle",
    "check_unit_directions",
    "check_uv",
    "file_kind",
    "read_regular_file",
    "real_number",
    "short_repr",
]

_DTYPES = (np.dtype(np.float64), np.dtype(np.float32))
_T = TypeVar("_T")


def check_choice(value: _T, name: str, choices: Sequence[object]) -> _T:
    """Return *value* if it is one of *choices*, else raise ValueError."""
    if not isinstance(value, str) or value not in choices:
        allowed = "{" + ", ".join(repr(c) for c in choices) + "}"
        raise ValueError(f"{_short(value)} is not a valid {name}; use one of {allowed}")
    return value


def check_count(n: object, name: str = "n", multiple: int = 1, maximum: int | None = None) -> int:
    """Return *n* as a positive int that is a multiple of *multiple* and at most *maximum*.

    *maximum* defaults to :data:`MAX_COUNT` (what index arithmetic in int64 allows); see
    :func:`check_size` for the message.
    """
    if isinstance(n, bool) or not isinstance(n, numbers.Integral):
        raise TypeError(f"'{name}' must be an integer, got {type(n).__name__} {_short(n)}")
    n = int(n)
    if n <= 0:
        raise ValueError(f"'{name}' must be positive, got {_short(n)}")
    check_size(n, name, MAX_COUNT if maximum is None else maximum)
    if n % multiple:
        below = (n // multiple) * multiple
        above = below + multiple
        nearest = f"{below} or {above}" if below > 0 else f"{above}"
        raise ValueError(f"'{name}'={n} is not a multiple of {multiple}; the nearest valid sizes are {nearest}")
    return n


def short_repr(value: object) -> str:
    """repr of *value* on one line, shortened, for a message (of an argument's check or a scene file's):
    an array's repr spans lines, an int of 10**400 would flood a terminal, and one of 10**5000 has no
    repr at all.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere._validation import short_repr
    >>> short_repr(np.zeros((2, 3)))
    'array([[0., 0., 0.], [0., 0., 0.]])'
    >>> short_repr(10**400)
    'an integer of 401 digits'
    """
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**30:
        try:
            return f"an integer of {len(str(abs(value)))} digits"
        except ValueError:  # beyond sys.get_int_max_str_digits()
            return "an integer of thousands of digits"
    if isinstance(value, np.ndarray) and value.size > 12:
        return f"an array of shape {value.shape} and dtype {value.dtype}"
    try:
        text = " ".join(repr(value).split())
    except (ValueError, RecursionError):  # a deep nest; an object whose repr fails
        return f"a {type(value).__name__}"
    return text if len(text) <= 60 else f"{text[:25]}...{text[-10:]} ({len(text)} characters)"


_short = short_repr


# ---------------------------------------------------------------------------
# Size limits: the one place that says how large a run, an array or a degree may be
# ---------------------------------------------------------------------------

MAX_COUNT = 2**56
"""Largest count of anything (directions, orbits, points, tasks) an argument may ask for: 48 times it
still fits the int64 index arithmetic of the kernels (2**62)."""

MAX_SOBOL_POINTS = 2**30
"""Largest number of points of one scrambled Sobol' sequence (``scipy.stats.qmc.Sobol``: 30 bits)."""

MAX_TASKS = 100_000
"""Largest number of tasks of one Dask graph the library builds (building it takes seconds per 10**5)."""

MAX_PATHS = 2**62
"""Largest number of camera paths (width * height * spp) of one render: path indices are int64."""

MAX_PIXELS = 2**28
"""Largest image (width * height pixels) of one render: 16384 x 16384.  The renderer holds the image in
float64 RGB several times over (the sum, a pass, the mean: 24 bytes a pixel each, 6 GiB each at the
limit); ``width = height = 2**31`` used to reach numpy's "array is too big", naming neither."""

MAX_SH_DEGREE = 85
"""Largest degree l of a real spherical harmonic (:mod:`symsphere.harmonics`): its unnormalised Legendre
recurrence and normalisation (factorials up to (2l)!) stay within float64 up to l = 85, accurate to 4e-14
against scipy.special.sph_harm_y; above it they overflow."""

MAX_POLYNOMIAL_DEGREE = 10_000
"""Largest total degree a + b + c of a monomial integrated exactly (:mod:`symsphere.harmonics`: rational
arithmetic whose cost grows faster than the degree squared; 10**4 takes ~0.05 s, 10**7 would take hours)."""

MAX_BINS = 2**20
"""Largest number of cells (n_phi * n_cos) of a chi-square binning (:mod:`symsphere.stats`): the expected
counts are integrated cell by cell, and a million cells is already far beyond any sample's power."""

MAX_QUADRATURE_ORDER = 64
"""Largest Gauss-Legendre order per cell and direction for the expected counts (the default is 12)."""

MAX_DIMENSIONS = 32
"""Largest number of array dimensions (batch dimensions plus the last one) public functions accept:
numpy's indexing and broadcasting are limited to 32 or 64 dimensions, depending on its version."""


def check_size(value: int, name: str, limit: int, what: str = "") -> int:
    """Return *value* if it is at most *limit*, else raise ValueError naming *name* and the limit.

    Examples
    --------
    >>> from symsphere._validation import check_size
    >>> check_size(48, "n", 2**56)
    48
    >>> check_size(48 * 2**64, "n", 2**56)
    Traceback (most recent call last):
        ...
    ValueError: 'n'=885443715538058477568 is too large; at most 72057594037927936 (2**56) is supported
    """
    if value > limit:
        power = f" (2**{limit.bit_length() - 1})" if limit & (limit - 1) == 0 else ""
        detail = f" {what}" if what else ""
        raise ValueError(f"'{name}'={_short(value)} is too large{detail}; at most {limit}{power} is supported")
    return value


def check_sobol_size(points: object, total: int, per_point: int = 1, *, n: int | None = None) -> None:
    """Raise ValueError if a Sobol' point set (by name or a ``scipy.stats.qmc.Sobol`` engine, counting the
    points it has already given) would need more than :data:`MAX_SOBOL_POINTS` points for *total* points;
    the message is in terms of the caller's ``n`` (``total = ceil(n / per_point)``; default ``total * per_point``).

    Examples
    --------
    >>> from symsphere._validation import check_sobol_size
    >>> check_sobol_size("sobol", 2**31, per_point=48)
    Traceback (most recent call last):
        ...
    ValueError: 'n'=103079215104 needs 2147483648 Sobol' points (n/48) but the sequence has 2**30: use n <= 51539607552, or points='random' or 'halton'
    """
    if isinstance(points, str):
        if points != "sobol":
            return
        used = 0
    elif type(points).__name__ == "Sobol":  # scipy.stats.qmc.Sobol (not imported here: 0.3 s)
        used = int(getattr(points, "num_generated", 0))
    else:
        return
    if used + total <= MAX_SOBOL_POINTS:
        return
    n = total * per_point if n is None else n
    ratio = f"n/{per_point}" if n % per_point == 0 else f"ceil(n/{per_point})"
    name, per = ("n", f" ({ratio})") if per_point > 1 else ("m", "")
    already = f" after the engine's {used}" if used else ""
    limit = (MAX_SOBOL_POINTS - used) * per_point
    raise ValueError(
        f"'{name}'={n} needs {total} Sobol' points{per}{already} but the sequence has 2**30: "
        f"use {name} <= {limit}, or points='random' or 'halton'"
    )


def check_real_values(values: object, name: str = "f") -> Float64Array:
    """What a user's function returned, as a finite float64 array; TypeError for complex or non-numeric
    values (converting would drop the imaginary part), ValueError for NaN or inf.

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
    if not np.all(np.isfinite(out)):
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
        raise TypeError(f"'{name}' must be float32 or float64, got {_short(dtype)}") from exc
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


def check_rng(rng: object, name: str = "rng") -> np.random.Generator:
    """Return a ``numpy.random.Generator`` from None, int, SeedSequence or Generator (SPEC 7)."""
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None or isinstance(rng, (np.random.SeedSequence, np.random.BitGenerator)):
        return np.random.default_rng(rng)
    if isinstance(rng, numbers.Integral) and not isinstance(rng, bool):
        if rng < 0:
            raise ValueError(f"'{name}' must be a non-negative integer seed, got {rng}")
        return np.random.default_rng(int(rng))
    raise TypeError(
        f"'{name}' must be None, an int, a numpy SeedSequence or a numpy Generator, got {type(rng).__name__}"
    )


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


def check_uv(uv: object, name: str = "uv") -> FloatArray:
    """Return points of the unit square as a float array of shape (..., 2)."""
    arr = as_float_array(uv, name)
    check_dimensions(arr, name)
    if arr.ndim == 0 or arr.shape[-1] != 2:
        raise ValueError(f"'{name}' must have shape (..., 2), got {arr.shape}")
    if not np.all((arr >= 0) & (arr <= 1)):  # also rejects NaN
        raise ValueError(f"'{name}' must lie in the closed unit square [0, 1]^2 (no NaN)")
    return arr


def check_directions(d: object, name: str = "d") -> FloatArray:
    """Return finite vectors as a float array of shape (..., 3)."""
    arr = as_float_array(d, name)
    check_dimensions(arr, name)
    if arr.ndim == 0 or arr.shape[-1] != 3:
        raise ValueError(f"'{name}' must have shape (..., 3), got {arr.shape}")
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
        raise ValueError(f"'{name}' must be finite (no NaN or inf); got {_short(a)}")
    return arr


def check_path(path: object, name: str = "path") -> Path:
    """*path* (a str or os.PathLike naming a file) as a Path; TypeError or ValueError naming *name*.

    Bytes, integers (which ``open`` would take as a file descriptor: 0 is standard input) and other
    types are TypeErrors; an empty name or one with a NUL character is a ValueError.

    Examples
    --------
    >>> from symsphere._validation import check_path
    >>> check_path("out.npy")
    PosixPath('out.npy')
    >>> check_path(0)
    Traceback (most recent call last):
        ...
    TypeError: 'path' must be a str or os.PathLike file name; got int 0
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"'{name}' must be a str or os.PathLike file name; got {type(path).__name__} {_short(path)}")
    text = os.fspath(path)
    if not isinstance(text, str):
        raise TypeError(f"'{name}' must be a str or os.PathLike file name; got {type(text).__name__} {_short(text)}")
    if not text or "\0" in text:
        raise ValueError(f"'{name}' must be a non-empty file name without NUL characters; got {_short(text)}")
    return Path(text)


def check_callable(value: object, name: str, optional: bool = False) -> None:
    """TypeError naming *name* unless *value* is callable (or None, if *optional*)."""
    if not (callable(value) or (optional and value is None)):
        allowed = "a callable or None" if optional else "a callable"
        raise TypeError(f"'{name}' must be {allowed}; got {type(value).__name__} {_short(value)}")


def check_index(value: object, name: str, low: int, high: int) -> int:
    """*value* as an int in [*low*, *high*]: TypeError if it is not an integer (bools are not), ValueError
    if out of range, naming *name*.

    Examples
    --------
    >>> from symsphere._validation import check_index
    >>> check_index(2, "first_pass", 0, 4)
    2
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"'{name}' must be an integer; got {type(value).__name__} {_short(value)}")
    index = int(value)
    if not low <= index <= high:
        raise ValueError(f"'{name}' must be in [{low}, {high}]; got {_short(value)}")
    return index


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
        wide = arr.astype(np.float64)
        scale = np.max(np.abs(wide), axis=-1, keepdims=True)  # no overflow in the squares
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):  # an inf norm is reported below
            norms = np.where(scale[..., 0] > 0, scale[..., 0] * np.sqrt(np.sum((wide / scale) ** 2, axis=-1)), 0.0)
        bad = np.abs(norms - 1.0) > UNIT_TOLERANCE
        if np.any(bad):
            raise ValueError(
                f"'{name}' must be unit vectors (norm 1 within {UNIT_TOLERANCE:g}); "
                f"got a norm of {float(norms[bad].flat[0]):.6g}"
            )
    return arr


# ---------------------------------------------------------------------------
# Validators of stats, bins, harmonics, integrands and peers
# ---------------------------------------------------------------------------


def check_samples(samples: object, name: str = "samples") -> FloatArray:
    """Return direction samples as a float32 or float64 array of shape (n, 3), n >= 1."""
    d = check_directions(samples, name)
    if d.dtype not in (np.dtype(np.float32), np.dtype(np.float64)):
        raise TypeError(f"'{name}' must be float32 or float64, got {d.dtype}")
    if d.ndim != 2 or d.shape[0] < 1:
        raise ValueError(f"'{name}' must have shape (n, 3) with n >= 1, got {d.shape}")
    return d


def check_pdf(pdf: object) -> Density:
    """Return *pdf* if it is callable, else raise TypeError."""
    if not callable(pdf):
        raise TypeError(f"'pdf' must be a callable taking directions of shape (m, 3), got {type(pdf).__name__}")
    return cast("Density", pdf)


def check_bins(bins: Any) -> tuple[int, int]:
    """Return *bins* as a pair ``(n_phi, n_cos)`` of positive ints."""
    msg = f"'bins' must be a pair (n_phi, n_cos) of positive integers, got {_short(bins)}"
    try:
        pair = tuple(bins)
    except TypeError as exc:
        raise TypeError(msg) from exc
    if len(pair) != 2:
        raise ValueError(msg)
    for b in pair:
        if isinstance(b, bool) or not isinstance(b, numbers.Integral):
            raise TypeError(msg)
        if b <= 0:
            raise ValueError(msg)
    check_size(int(pair[0]) * int(pair[1]), "bins", MAX_BINS, "(n_phi * n_cos cells)")
    return (int(pair[0]), int(pair[1]))


def real_number(value: object) -> float | None:
    """The number rule, shared by the arguments' checks and the scene files' (``render._scene_checks``):
    a real number that is not a bool, as a float (an int beyond float64 becomes +-inf); None if
    *value* is not one.

    Examples
    --------
    >>> from symsphere._validation import real_number
    >>> real_number(2), real_number(-(10**400)), real_number(True), real_number("1")
    (2.0, -inf, None, None)
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return None
    try:
        return float(value)
    except OverflowError:  # an int beyond float64
        return math.inf if value > 0 else -math.inf  # type: ignore[operator]  # numbers.Real has no __gt__ in typeshed


def check_real(value: object, name: str) -> float:
    """Return *value* as a finite float: TypeError if it is not a real number, ValueError if not finite."""
    result = real_number(value)
    if result is None:
        raise TypeError(f"'{name}' must be a real number, got {type(value).__name__}")
    if not math.isfinite(result):
        raise ValueError(f"'{name}' must be finite, got {_short(value)}")
    return result


def check_open_unit(value: object, name: str) -> float:
    """Return *value* as a float in the open interval (0, 1) (see :func:`check_real`)."""
    value = check_real(value, name)
    if not 0.0 < value < 1.0:
        raise ValueError(f"'{name}' must lie in the open interval (0, 1), got {value}")
    return value


def check_positive_real(value: object, name: str) -> float:
    """Return *value* as a positive finite float (see :func:`check_real`).

    Unlike :func:`check_positive`, a non-finite value (inf, NaN) is a
    ValueError here, and the messages name the type, not the value.
    """
    value = check_real(value, name)
    if value <= 0:
        raise ValueError(f"'{name}' must be positive, got {value}")
    return value


def _finite_real(value: object, name: str) -> float:
    # check_positive's and check_nonnegative's rule: TypeError unless a finite real number, except
    # an int beyond float64 (a number, too large): ValueError
    result = real_number(value)
    if result is None or (not math.isfinite(result) and not isinstance(value, numbers.Integral)):
        raise TypeError(f"'{name}' must be a finite real number, got {_short(value)}")
    if not math.isfinite(result):
        raise ValueError(f"'{name}' must be a finite real number, got {_short(value)}")
    return result


def check_positive(value: object, name: str) -> float:
    """Return *value* as a positive float; TypeError unless it is a finite real number.

    See :func:`check_positive_real` for the variant that raises ValueError
    for inf and NaN.
    """
    result = _finite_real(value, name)
    if result <= 0:
        raise ValueError(f"'{name}' must be positive, got {value}")
    return result


def check_nonnegative(value: object, name: str) -> float:
    """Return *value* as a float >= 0; TypeError unless it is a finite real number."""
    result = _finite_real(value, name)
    if result < 0:
        raise ValueError(f"'{name}' must be >= 0, got {value}")
    return result


def check_lm(l: object, m: object, l_name: str = "l") -> tuple[int, int]:
    """Return the degree and order of a spherical harmonic as ints, l >= 0 and -l <= m <= l."""
    for value, name in ((l, l_name), (m, "m")):
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            raise TypeError(f"'{name}' must be an integer, got {type(value).__name__}")
    degree, order = int(l), int(m)  # type: ignore[call-overload]  # Integral, checked above
    if degree < 0:
        raise ValueError(f"'{l_name}' must be >= 0, got {degree}")
    check_size(degree, l_name, MAX_SH_DEGREE)
    if abs(order) > degree:
        raise ValueError(f"'m' must satisfy -l <= m <= l, got l={degree}, m={order}")
    return degree, order


def check_exponents(a: object, b: object, c: object) -> tuple[int, int, int]:
    """Return the exponents of a monomial x^a y^b z^c as non-negative ints."""
    out = []
    for value, name in ((a, "a"), (b, "b"), (c, "c")):
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            raise TypeError(f"exponent '{name}' must be an integer, got {type(value).__name__}")
        if value < 0:
            raise ValueError(f"exponent '{name}' must be >= 0, got {value}")
        out.append(int(value))
    check_size(sum(out), "a + b + c", MAX_POLYNOMIAL_DEGREE, "(the total degree)")
    return out[0], out[1], out[2]


def check_coeffs(coeffs: object) -> Mapping[tuple[int, int, int], Any]:
    """Return a polynomial ``{(a, b, c): coefficient}`` if its keys are exponent triples."""
    if not isinstance(coeffs, Mapping):
        raise TypeError(f"'coeffs' must be a mapping {{(a, b, c): coefficient}}, got {type(coeffs).__name__}")
    for key, value in coeffs.items():
        if not (isinstance(key, tuple) and len(key) == 3):
            raise ValueError(f"'coeffs' keys must be exponent triples (a, b, c), got {_short(key)}")
        check_exponents(*key)
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
            raise TypeError(
                f"'coeffs' values must be real numbers; got {type(value).__name__} {_short(value)} at {key}"
            )
        try:
            finite = math.isfinite(value)
        except OverflowError:  # an int or Fraction beyond float64: exact, and finite
            finite = True
        if not finite:
            raise ValueError(f"'coeffs' values must be finite; got {_short(value)} at {key}")
    return coeffs


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
    if not np.all(np.isfinite(arr)) or not np.any(arr):
        raise ValueError(f"'{name}' must be a finite, non-zero 3-vector, got {arr.tolist()}")
    largest = float(np.max(np.abs(arr)))
    if 1e-150 < largest < 1e150:  # the squares neither overflow nor underflow: the plain norm (as before)
        plain: Float64Array = arr / np.linalg.norm(arr)
        return plain
    # Scale by the largest component first: the norm of [1e200, 0, 0] or [1e-170, 0, 0] would
    # overflow or underflow, but the direction is well defined.
    scaled = arr / largest
    unit: Float64Array = scaled / math.sqrt(float(scaled @ scaled))
    return unit


def check_seed(seed: int, name: str = "seed") -> int:
    """Return *seed* as a non-negative int (not a bool): TypeError for another type, ValueError if negative.

    For a seed that must be reproducible and printable (a report, a command line): unlike
    :func:`check_rng` it accepts no Generator or SeedSequence.

    Examples
    --------
    >>> from symsphere._validation import check_seed
    >>> check_seed(3)
    3
    """
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):  # a Generator, a float: a wrong type
        raise TypeError(f"'{name}' must be a non-negative integer, got {type(seed).__name__} {_short(seed)}")
    if seed < 0:
        raise ValueError(f"'{name}' must be a non-negative integer, got {_short(seed)}")
    return int(seed)


# ---------------------------------------------------------------------------
# Output files: what may be written, checked before any work
# ---------------------------------------------------------------------------

TEMPORARY_KINDS = ("tmp", "old", "probe")
"""The last suffix of the hidden files an atomic write makes beside its target, ``.NAME.<8 hex>.KIND``:
the temporary (``tmp``), the previous version kept during the renames of a set (``old``) and the
file that :func:`check_output_path` creates and removes at once (``probe``)."""

_KINDS = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISSOCK, "a socket"),
)


def file_kind(mode: int) -> str:
    """What a file of the ``st_mode`` *mode* is, in words: ``'a regular file'``, ``'a FIFO (named pipe)'``, ...

    Examples
    --------
    >>> import stat
    >>> from symsphere._validation import file_kind
    >>> file_kind(stat.S_IFCHR | 0o666)
    'a character device'
    """
    if stat.S_ISREG(mode):
        return "a regular file"
    for test, words in _KINDS:
        if test(mode):
            return words
    return "not a regular file"


def check_output_path(path: object, name: str = "path", *, probe: bool = True) -> Path:
    """*path* as a Path that an atomic write may replace, checked before any work is done.

    The target, followed through symbolic links, must be absent or a regular file (a device, a
    FIFO, a socket or a directory is never replaced, nor written into), and its directory must
    exist; with *probe*, a hidden file ``.NAME.<hex>.probe`` is created in it and removed at once,
    so that a directory that takes no new files (read-only, ``/proc``, no permission) fails now,
    not after minutes of work.  Errors name *path* as the user gave it: TypeError or ValueError
    for a bad name (see :func:`check_path`), else an ``OSError`` whose ``filename`` is *path*.

    Examples
    --------
    >>> from symsphere._validation import check_output_path
    >>> check_output_path("/dev/null")
    Traceback (most recent call last):
        ...
    OSError: [Errno 22] is a character device, not a regular file: only regular files are replaced: '/dev/null'
    """
    given = check_path(path, name)
    target = Path(os.path.realpath(given))  # through symbolic links, as the writer goes
    try:
        mode = os.stat(target).st_mode
    except (FileNotFoundError, NotADirectoryError):  # absent, or a "directory" that is a file: below
        mode = None
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror, str(given)) from None
    if mode is not None and stat.S_ISDIR(mode):
        raise IsADirectoryError(errno.EISDIR, "is a directory, not a file", str(given))
    if mode is not None and not stat.S_ISREG(mode):
        shown = f" ({target})" if str(target) != os.path.abspath(given) else ""  # reached through a link
        raise OSError(
            errno.EINVAL,
            f"is {file_kind(mode)}{shown}, not a regular file: only regular files are replaced",
            str(given),
        )
    folder = target.parent
    if not folder.exists():
        raise FileNotFoundError(errno.ENOENT, f"its directory {str(given.parent)!r} does not exist", str(given))
    if not folder.is_dir():
        raise NotADirectoryError(errno.ENOTDIR, f"{str(given.parent)!r} is not a directory", str(given))
    if probe:
        trial = folder / f".{target.name}.{secrets.token_hex(4)}.probe"
        try:
            os.close(os.open(trial, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
        except OSError as exc:
            raise OSError(exc.errno, f"cannot create a file in {str(folder)!r} ({exc.strerror})", str(given)) from None
        os.unlink(trial)
    return given


def read_regular_file(path: Path, where: str, limit: int | None = None) -> bytes:
    """The bytes of the regular file *path* (at most *limit* + 1 of them), refusing anything else first.

    A FIFO would block the reader until a writer comes (forever, for a scene file), and ``/dev/zero`` or
    ``/dev/urandom`` never end: what *path* is (through symbolic links) is checked before it is opened,
    and again on the opened descriptor (opened without blocking), so that nothing is read from such a
    file.  *where* starts the messages (``"scene file 'x.json'"``).  FileNotFoundError if it does not
    exist, ValueError naming what it is otherwise.

    Examples
    --------
    >>> from pathlib import Path
    >>> from symsphere._validation import read_regular_file
    >>> read_regular_file(Path("/dev/zero"), "scene file '/dev/zero'")
    Traceback (most recent call last):
        ...
    ValueError: scene file '/dev/zero': is a character device, not a regular file
    """
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise FileNotFoundError(errno.ENOENT, os.strerror(errno.ENOENT), str(path)) from None
    if not stat.S_ISREG(mode):
        raise ValueError(f"{where}: is {file_kind(mode)}, not a regular file")
    descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK)  # swapped for a FIFO meanwhile: no wait
    with os.fdopen(descriptor, "rb") as handle:
        mode = os.fstat(descriptor).st_mode
        if not stat.S_ISREG(mode):
            raise ValueError(f"{where}: is {file_kind(mode)}, not a regular file")
        return handle.read() if limit is None else handle.read(limit + 1)


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
            raise ValueError(f"'{name}' must be finite (no NaN or inf); got {_short(value)}")
        if unit_interval and not np.all((arr >= 0) & (arr <= 1)):
            raise ValueError(f"'{name}' must lie in [0, 1]; got {_short(value)}")
        arrays.append(arr)
    try:
        np.broadcast_shapes(*(a.shape for a in arrays))
    except ValueError:
        names = ", ".join(f"'{name}'" for _, name in named)
        raise ValueError(f"{names} must broadcast together; got shapes {[a.shape for a in arrays]}") from None
    if any(a.ndim for a in arrays):  # every output then has the broadcast shape (z = sqrt(1 - u) ignores v)
        return list(np.broadcast_arrays(*arrays))
    return [a[()] for a in arrays]
