"""Validators shared by the public functions.

Each raises ``TypeError`` or ``ValueError`` with a message that names the
argument and says what is allowed.  Public functions call these at the
boundary; private helpers trust their inputs.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from typing import Any, TypeVar, cast, overload

import numpy as np
import numpy.typing as npt

from ._typing import Density, Float64Array, FloatArray

__all__ = [
    "as_float_array",
    "check_choice",
    "check_count",
    "check_directions",
    "check_dtype",
    "check_normal",
    "check_out",
    "check_rng",
    "check_uv",
]

_DTYPES = (np.dtype(np.float64), np.dtype(np.float32))
_T = TypeVar("_T")


def check_choice(value: _T, name: str, choices: Sequence[object]) -> _T:
    """Return *value* if it is one of *choices*, else raise ValueError."""
    if not isinstance(value, str) or value not in choices:
        allowed = "{" + ", ".join(repr(c) for c in choices) + "}"
        raise ValueError(f"{value!r} is not a valid {name}; use one of {allowed}")
    return value


def check_count(n: object, name: str = "n", multiple: int = 1) -> int:
    """Return *n* as a positive int that is a multiple of *multiple*."""
    if isinstance(n, bool) or not isinstance(n, numbers.Integral):
        raise TypeError(f"'{name}' must be an integer, got {type(n).__name__} {n!r}")
    n = int(n)
    if n <= 0:
        raise ValueError(f"'{name}' must be positive, got {n}")
    if n % multiple:
        below = (n // multiple) * multiple
        above = below + multiple
        nearest = f"{below} or {above}" if below > 0 else f"{above}"
        raise ValueError(
            f"'{name}'={n} is not a multiple of {multiple}; "
            f"the nearest valid sizes are {nearest}"
        )
    return n


def check_dtype(dtype: npt.DTypeLike, name: str = "dtype") -> np.dtype[Any]:
    """Return *dtype* as float32 or float64, else raise TypeError."""
    try:
        dt = np.dtype(dtype)
    except TypeError as exc:
        raise TypeError(f"'{name}' must be float32 or float64, got {dtype!r}") from exc
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
        raise TypeError(
            f"'{name}' has dtype {out.dtype} but dtype={dtype} was asked for; "
            "they must match"
        )
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
        f"'{name}' must be None, an int, a numpy SeedSequence or a numpy Generator, "
        f"got {type(rng).__name__}"
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
    if arr.ndim == 0 or arr.shape[-1] != 2:
        raise ValueError(f"'{name}' must have shape (..., 2), got {arr.shape}")
    if not np.all((arr >= 0) & (arr <= 1)):  # also rejects NaN
        raise ValueError(f"'{name}' must lie in the closed unit square [0, 1]^2 (no NaN)")
    return arr


def check_directions(d: object, name: str = "d") -> FloatArray:
    """Return finite vectors as a float array of shape (..., 3)."""
    arr = as_float_array(d, name)
    if arr.ndim == 0 or arr.shape[-1] != 3:
        raise ValueError(f"'{name}' must have shape (..., 3), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"'{name}' must be finite (no NaN or inf)")
    return arr


# ---------------------------------------------------------------------------
# Validators of stats, bins, harmonics, integrands and peers
# ---------------------------------------------------------------------------

__all__ += [
    "check_bins",
    "check_coeffs",
    "check_exponents",
    "check_lm",
    "check_nonnegative",
    "check_open_unit",
    "check_pdf",
    "check_positive",
    "check_positive_real",
    "check_real",
    "check_samples",
    "check_triangle",
]


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
        raise TypeError(
            f"'pdf' must be a callable taking directions of shape (m, 3), "
            f"got {type(pdf).__name__}"
        )
    return cast("Density", pdf)


def check_bins(bins: Any) -> tuple[int, int]:
    """Return *bins* as a pair ``(n_phi, n_cos)`` of positive ints."""
    msg = f"'bins' must be a pair (n_phi, n_cos) of positive integers, got {bins!r}"
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
    return (int(pair[0]), int(pair[1]))


def check_real(value: object, name: str) -> float:
    """Return *value* as a finite float: TypeError if it is not a real number, ValueError if not finite."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"'{name}' must be a real number, got {type(value).__name__}")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"'{name}' must be finite, got {value}")
    return value


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


def check_positive(value: object, name: str) -> float:
    """Return *value* as a positive float; TypeError unless it is a finite real number.

    See :func:`check_positive_real` for the variant that raises ValueError
    for inf and NaN.
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise TypeError(f"'{name}' must be a finite real number, got {value!r}")
    if value <= 0:
        raise ValueError(f"'{name}' must be positive, got {value}")
    return float(value)


def check_nonnegative(value: object, name: str) -> float:
    """Return *value* as a float >= 0; TypeError unless it is a finite real number."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise TypeError(f"'{name}' must be a finite real number, got {value!r}")
    if value < 0:
        raise ValueError(f"'{name}' must be >= 0, got {value}")
    return float(value)


def check_lm(l: object, m: object) -> tuple[int, int]:
    """Return the degree and order of a spherical harmonic as ints, l >= 0 and -l <= m <= l."""
    for value, name in ((l, "l"), (m, "m")):
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            raise TypeError(f"'{name}' must be an integer, got {type(value).__name__}")
    degree, order = int(l), int(m)  # type: ignore[call-overload]  # Integral, checked above
    if degree < 0:
        raise ValueError(f"'l' must be >= 0, got {degree}")
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
    return out[0], out[1], out[2]


def check_coeffs(coeffs: object) -> Mapping[tuple[int, int, int], Any]:
    """Return a polynomial ``{(a, b, c): coefficient}`` if its keys are exponent triples."""
    if not isinstance(coeffs, Mapping):
        raise TypeError(f"'coeffs' must be a mapping {{(a, b, c): coefficient}}, got {type(coeffs).__name__}")
    for key in coeffs:
        if not (isinstance(key, tuple) and len(key) == 3):
            raise ValueError(f"'coeffs' keys must be exponent triples (a, b, c), got {key!r}")
        check_exponents(*key)
    return coeffs


def check_triangle(a: npt.ArrayLike, b: npt.ArrayLike, c: npt.ArrayLike) -> Float64Array:
    """Return the vertices of a non-degenerate spherical triangle as unit vectors, shape (3, 3)."""
    verts = np.stack([check_normal(v, name) for v, name in ((a, "a"), (b, "b"), (c, "c"))])
    A, B, C = verts
    # Its area by Van Oosterom & Strackee (1983): tan(E/2) = |A.(B x C)| / (1 + A.B + B.C + C.A).
    area = 2.0 * math.atan2(abs(float(np.dot(A, np.cross(B, C)))), 1.0 + A @ B + B @ C + C @ A)
    if area < 1e-12:
        raise ValueError(
            "'a', 'b', 'c' must span a non-degenerate spherical triangle "
            "(distinct, not on one great circle)"
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
    norm = np.linalg.norm(arr)
    if not np.isfinite(norm) or norm == 0:
        raise ValueError(f"'{name}' must be a finite, non-zero 3-vector, got {arr.tolist()}")
    return arr / norm


def check_seed(seed: int, name: str = "seed") -> int:
    """Return *seed* as a non-negative int (not a bool), else raise ValueError naming *name*.

    For a seed that must be reproducible and printable (a report, a command line): unlike
    :func:`check_rng` it accepts no Generator or SeedSequence.

    Examples
    --------
    >>> from symsphere._validation import check_seed
    >>> check_seed(3)
    3
    """
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"'{name}' must be a non-negative integer, got {seed!r}")
    return int(seed)


__all__ += ["check_seed"]  # appended here, not in the list above, to keep this addition in one place
