"""Validators shared by the public functions.

Each raises ``TypeError`` or ``ValueError`` with a message that names the
argument and says what is allowed.  Public functions call these at the
boundary; private helpers trust their inputs.
"""

from __future__ import annotations

import numbers

import numpy as np

__all__ = [
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


def check_choice(value, name, choices):
    """Return *value* if it is one of *choices*, else raise ValueError."""
    if not isinstance(value, str) or value not in choices:
        allowed = "{" + ", ".join(repr(c) for c in choices) + "}"
        raise ValueError(f"{value!r} is not a valid {name}; use one of {allowed}")
    return value


def check_count(n, name="n", multiple=1):
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


def check_dtype(dtype, name="dtype"):
    """Return *dtype* as float32 or float64, else raise TypeError."""
    try:
        dt = np.dtype(dtype)
    except TypeError as exc:
        raise TypeError(f"'{name}' must be float32 or float64, got {dtype!r}") from exc
    if dt not in _DTYPES:
        raise TypeError(f"'{name}' must be float32 or float64, got {dt}")
    return dt


def check_out(out, shape, dtype, name="out"):
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


def check_rng(rng, name="rng"):
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


def _as_float_array(a, name):
    if isinstance(a, (str, bytes)):
        raise TypeError(f"'{name}' must be an array of numbers, got {type(a).__name__}")
    try:
        arr = np.asarray(a)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"'{name}' must be an array of numbers") from exc
    if arr.dtype.kind not in "biuf":
        raise TypeError(f"'{name}' must be an array of real numbers, got dtype {arr.dtype}")
    if arr.dtype.kind != "f":
        arr = arr.astype(np.float64)
    return arr


def check_uv(uv, name="uv"):
    """Return points of the unit square as a float array of shape (..., 2)."""
    arr = _as_float_array(uv, name)
    if arr.ndim == 0 or arr.shape[-1] != 2:
        raise ValueError(f"'{name}' must have shape (..., 2), got {arr.shape}")
    if not np.all((arr >= 0) & (arr <= 1)):  # also rejects NaN
        raise ValueError(f"'{name}' must lie in the closed unit square [0, 1]^2 (no NaN)")
    return arr


def check_directions(d, name="d"):
    """Return finite vectors as a float array of shape (..., 3)."""
    arr = _as_float_array(d, name)
    if arr.ndim == 0 or arr.shape[-1] != 3:
        raise ValueError(f"'{name}' must have shape (..., 3), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"'{name}' must be finite (no NaN or inf)")
    return arr


def check_normal(normal, name="normal"):
    """Return *normal* as a unit float64 3-vector, or None."""
    if normal is None:
        return None
    arr = _as_float_array(normal, name).astype(np.float64)
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
