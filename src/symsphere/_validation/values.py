"""Numbers, names, counts and sizes: the scalar arguments, the size limits, flags and run objects.

Part of :mod:`symsphere._validation` (import the validators from there).
"""

from __future__ import annotations

import functools
import math
import numbers
import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, TypeVar, cast

import numpy as np

from .._typing import Density

if TYPE_CHECKING:
    from scipy.stats.qmc import QMCEngine

__all__ = [
    "MAX_BINS",
    "MAX_COUNT",
    "MAX_DIMENSIONS",
    "MAX_PATHS",
    "MAX_PIXELS",
    "machine_memory",
    "memory_count_limit",
    "memory_pixel_limit",
    "MAX_POLYNOMIAL_DEGREE",
    "MAX_QUADRATURE_ORDER",
    "MAX_SH_DEGREE",
    "RTOL_FLOOR",
    "check_rtol",
    "MAX_SOBOL_POINTS",
    "MAX_TASKS",
    "check_bins",
    "check_bool",
    "check_callable",
    "check_choice",
    "check_client",
    "check_coeffs",
    "check_count",
    "check_exponents",
    "check_exposure",
    "check_index",
    "check_lm",
    "check_nonnegative",
    "check_open_unit",
    "check_pdf",
    "check_point_set",
    "check_positive",
    "check_positive_real",
    "check_real",
    "check_rng",
    "check_rng_seed",
    "check_seed",
    "check_size",
    "check_sobol_size",
    "check_square_count",
    "check_tasks",
    "real_number",
    "short_repr",
]

_T = TypeVar("_T")


def check_choice(value: _T, name: str, choices: Sequence[object]) -> _T:
    """Return *value* if it is one of *choices*, else raise ValueError."""
    if not isinstance(value, str) or value not in choices:
        allowed = "{" + ", ".join(repr(c) for c in choices) + "}"
        raise ValueError(f"{short_repr(value)} is not a valid {name}; use one of {allowed}")
    return value


def check_count(n: object, name: str = "n", multiple: int = 1, maximum: int | None = None) -> int:
    """Return *n* as a positive int that is a multiple of *multiple* and at most *maximum*.

    *maximum* defaults to :data:`MAX_COUNT` (what index arithmetic in int64 allows); see
    :func:`check_size` for the message.
    """
    if isinstance(n, bool) or not isinstance(n, numbers.Integral):
        raise TypeError(f"'{name}' must be an integer, got {type(n).__name__} {short_repr(n)}")
    n = int(n)
    if n <= 0:
        raise ValueError(f"'{name}' must be positive, got {short_repr(n)}")
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


@functools.cache
def machine_memory() -> int | None:
    """Bytes of memory this process may use: the physical memory, or a smaller cgroup limit (containers,
    batch jobs); None where neither can be read.  Read once per process: every fresh sampling output
    asks, and reading the files after a large write took 0.2-0.4 ms a call (docs/results/write-limit.md)."""
    sizes = []
    try:
        sizes.append(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, OSError, ValueError):  # not POSIX
        pass
    for limit_file in ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"):
        try:
            with open(limit_file) as handle:
                text = handle.read().strip()
        except OSError:
            continue
        if text.isdigit():
            sizes.append(int(text))
    return min(sizes) if sizes else None


def memory_count_limit(bytes_each: int) -> int | None:
    """How many things of *bytes_each* bytes fit in :func:`machine_memory` (None where it cannot be read):
    the one bound of every size whose memory grows with an argument (pixels, partial sums)."""
    memory = machine_memory()
    return None if memory is None else memory // bytes_each


def memory_pixel_limit(bytes_per_pixel: int) -> int:
    """The largest image (width * height) a render may hold at *bytes_per_pixel*: :data:`MAX_PIXELS`, or
    fewer where :func:`machine_memory` is smaller (an image that would not fit is refused at once, not
    after the machine has started swapping or the kernel's OOM killer has ended the run)."""
    limit = memory_count_limit(bytes_per_pixel)
    return MAX_PIXELS if limit is None else max(1, min(MAX_PIXELS, limit))


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
        raise ValueError(f"'{name}'={short_repr(value)} is too large{detail}; at most {limit}{power} is supported")
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
    ratio = _per(n, per_point)
    name, per = ("n", f" ({ratio})") if per_point > 1 else ("m", "")
    already = f" after the engine's {used}" if used else ""
    limit = (MAX_SOBOL_POINTS - used) * per_point
    raise ValueError(
        f"'{name}'={n} needs {total} Sobol' points{per}{already} but the sequence has 2**30: "
        f"use {name} <= {limit}, or points='random' or 'halton'"
    )


def check_rng(rng: object, name: str = "rng") -> np.random.Generator:
    """Return a ``numpy.random.Generator`` from None, int, SeedSequence or Generator (SPEC 7)."""
    seed = check_rng_seed(rng, name)
    return seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)


def check_rng_seed(rng: object, name: str = "rng") -> np.random.Generator | np.random.SeedSequence | int:
    """As :func:`check_rng`, but an int or a SeedSequence as it is and None as a fresh SeedSequence: a seed
    of ``default_rng``'s stream, the same at every use, without making a Generator (which costs a small
    call more than its work after a large write).  A Generator (or BitGenerator) is returned as one."""
    if isinstance(rng, np.random.Generator):
        return rng
    if isinstance(rng, np.random.BitGenerator):
        return np.random.Generator(rng)
    if isinstance(rng, np.random.SeedSequence):
        return rng
    if rng is None:
        return np.random.SeedSequence()
    if isinstance(rng, numbers.Integral) and not isinstance(rng, bool):
        if rng < 0:
            raise ValueError(f"'{name}' must be a non-negative integer seed, got {rng}")
        return int(rng)
    raise TypeError(
        f"'{name}' must be None, an int, a numpy SeedSequence or a numpy Generator, got {type(rng).__name__}"
    )


def check_callable(value: object, name: str, optional: bool = False) -> None:
    """TypeError naming *name* unless *value* is callable (or None, if *optional*)."""
    if not (callable(value) or (optional and value is None)):
        allowed = "a callable or None" if optional else "a callable"
        raise TypeError(f"'{name}' must be {allowed}; got {type(value).__name__} {short_repr(value)}")


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
        raise TypeError(f"'{name}' must be an integer; got {type(value).__name__} {short_repr(value)}")
    index = int(value)
    if not low <= index <= high:
        raise ValueError(f"'{name}' must be in [{low}, {high}]; got {short_repr(value)}")
    return index


def check_pdf(pdf: object) -> Density:
    """Return *pdf* if it is callable, else raise TypeError."""
    if not callable(pdf):
        raise TypeError(f"'pdf' must be a callable taking directions of shape (m, 3), got {type(pdf).__name__}")
    return cast("Density", pdf)


def check_bins(bins: Any) -> tuple[int, int]:
    """Return *bins* as a pair ``(n_phi, n_cos)`` of positive ints."""
    msg = f"'bins' must be a pair (n_phi, n_cos) of positive integers, got {short_repr(bins)}"
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
        raise ValueError(f"'{name}' must be finite, got {short_repr(value)}")
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
        raise TypeError(f"'{name}' must be a finite real number, got {short_repr(value)}")
    if not math.isfinite(result):
        raise ValueError(f"'{name}' must be a finite real number, got {short_repr(value)}")
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


RTOL_FLOOR = float(np.finfo(np.float64).eps)
"""The smallest positive relative tolerance: the relative spacing of float64 numbers (2.2e-16); below it
a half-width relative to a value cannot be resolved, so such a tolerance could never be met."""


def check_rtol(value: object, name: str = "rtol") -> float:
    """*value* as a float, 0 or at least :data:`RTOL_FLOOR`; ValueError naming *name* otherwise.

    Examples
    --------
    >>> check_rtol(1e-300, "--rtol")
    Traceback (most recent call last):
        ...
    ValueError: '--rtol'=1e-300 is below what float64 resolves: use 0 (with atol) or at least 2.22e-16
    """
    result = check_nonnegative(value, name)
    if 0 < result < RTOL_FLOOR:
        raise ValueError(
            f"'{name}'={result:.3g} is below what float64 resolves: use 0 (with atol) or at least {RTOL_FLOOR:.3g}"
        )
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
            raise ValueError(f"'coeffs' keys must be exponent triples (a, b, c), got {short_repr(key)}")
        check_exponents(*key)
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
            raise TypeError(
                f"'coeffs' values must be real numbers; got {type(value).__name__} {short_repr(value)} at {key}"
            )
        try:
            finite = math.isfinite(value)
        except OverflowError:  # an int or Fraction beyond float64: exact, and finite
            finite = True
        if not finite:
            raise ValueError(f"'coeffs' values must be finite; got {short_repr(value)} at {key}")
    return coeffs


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
        raise TypeError(f"'{name}' must be a non-negative integer, got {type(seed).__name__} {short_repr(seed)}")
    if seed < 0:
        raise ValueError(f"'{name}' must be a non-negative integer, got {short_repr(seed)}")
    return int(seed)


# ---------------------------------------------------------------------------
# Flags, run sizes and the objects a run is given
# ---------------------------------------------------------------------------


def check_bool(value: object, name: str) -> bool:
    """*value* (a bool or a numpy bool) as a bool; TypeError naming *name* otherwise (1 and "yes" are not flags).

    Examples
    --------
    >>> from symsphere._validation import check_bool
    >>> check_bool(True, "progress")
    True
    >>> check_bool("yes", "randomize")
    Traceback (most recent call last):
        ...
    TypeError: 'randomize' must be True or False, got 'yes'
    """
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"'{name}' must be True or False, got {short_repr(value)}")
    return bool(value)


def check_tasks(tasks: int, name: str, what: str) -> None:
    """ValueError if *tasks* Dask tasks (*what* makes them) are more than :data:`MAX_TASKS`: raise *name*."""
    if tasks > MAX_TASKS:
        raise ValueError(
            f"{what} make {tasks} Dask tasks, more than the {MAX_TASKS} a graph may have: "
            f"raise '{name}', or split the run"
        )


def check_client(client: object) -> Any:
    """A distributed.Client, or None for a local cluster; TypeError naming 'client' otherwise."""
    if client is None:
        return None
    from distributed import Client  # only when a client is given: dask is an optional extra

    if not isinstance(client, Client):
        raise TypeError(f"'client' must be a distributed.Client or None, got {type(client).__name__}")
    return client


def check_exposure(exposure: object, name: str = "exposure") -> float:
    """*exposure* (a multiplier of linear radiance) as a positive finite float; TypeError or ValueError."""
    value = real_number(exposure)
    if value is None:
        raise TypeError(f"'{name}' must be a positive number, got {type(exposure).__name__}")
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"'{name}' must be a positive finite number, got {short_repr(exposure)}")
    return value


# ---------------------------------------------------------------------------
# Point sets of the unit square (the choices of ``points=``, symsphere.points)
# ---------------------------------------------------------------------------


def check_point_set(points: object, names: Sequence[str]) -> QMCEngine | None:
    """None if *points* is one of *names*, the engine if it is a ``scipy.stats.qmc.QMCEngine`` with d == 2;
    ValueError or TypeError naming 'points' otherwise (:func:`symsphere.points.check_points`)."""
    if isinstance(points, str):
        check_choice(points, "points", names)
        return None
    from scipy.stats import qmc  # not at import: scipy.stats costs 0.3 s at start-up

    if isinstance(points, qmc.QMCEngine):
        if points.d != 2:
            raise ValueError(f"'points' engine must have d=2 (points of the unit square), got d={points.d}")
        return points
    raise TypeError(f"'points' must be one of {set(names)} or a scipy.stats.qmc.QMCEngine, got {type(points).__name__}")


def check_square_count(m: int, per_point: int, n: int | None) -> int:
    """The side of the square grid of *m* base points (points='stratified'); ValueError if *m* is not a
    square, naming the caller's nearest valid ``n`` (``m = ceil(n / per_point)``)."""
    side = math.isqrt(m)
    if side * side != m:
        options = [c for c in (side * side, (side + 1) ** 2) if c > 0]
        if per_point > 1:
            sizes = " or ".join(f"n={per_point * c}" for c in options)
            n = per_point * m if n is None else n
            got = f"n={n} gives {m} ({_per(n, per_point)})"
        else:
            sizes = " or ".join(str(c) for c in options)
            got = f"got {m}"
        raise ValueError(f"points='stratified' needs a square number of base points; {got}; use {sizes}")
    return side


def _per(n: int, per_point: int) -> str:
    """How *n* gives its number of base points, as the messages say it: ``n/48`` or ``ceil(n/48)``."""
    return f"n/{per_point}" if n % per_point == 0 else f"ceil(n/{per_point})"
