"""The spherical Fibonacci point set, plain and under a random rotation: the peers ``fibonacci`` and
``fibonacci_rotated``.

A private module with public names (re-exported by :mod:`symsphere.peers`, where they are documented with
the other peers).  Point i of n (Keinert et al., "Spherical Fibonacci Mapping", SIGGRAPH Asia 2015,
eq. 2): ``z_i = 1 - (2 i + 1)/n``, ``phi_i = 2 pi frac(i / Phi)`` with the golden ratio Phi.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba.extending import overload, register_jitable

from ._constants import GOLDEN_BITS, TWO_POW_M53
from ._typing import DTypeLike, Float64Array, FloatArray, RNGLike
from ._validation import check_bool, check_count, check_dtype, check_rng, short_repr

__all__ = ["sample_fibonacci", "fibonacci_points", "fibonacci_point"]

_GOLDEN_FRACTION_BITS = np.uint64(GOLDEN_BITS)  # floor(2^64 (Phi - 1)), a numba constant


def sample_fibonacci(
    n: int, *, randomize: bool = False, rng: RNGLike = None, dtype: DTypeLike = np.float64
) -> FloatArray:
    """The spherical Fibonacci point set, optionally under a random rotation.

    Point i of n (Keinert et al., "Spherical Fibonacci Mapping", SIGGRAPH Asia
    2015, eq. 2): ``z_i = 1 - (2 i + 1)/n``, ``phi_i = 2 pi frac(i / Phi)`` with
    the golden ratio Phi; see :func:`fibonacci_points`.  The set is
    deterministic.  With ``randomize=True`` it is rotated by one uniformly
    random rotation (``scipy.spatial.transform.Rotation.random``), so that
    every point is marginally uniform and ``4 pi mean(f)`` is an unbiased
    estimate of the integral of f; the points of one set stay dependent.

    Parameters
    ----------
    n : int
        Number of points, positive.
    randomize : bool
        Apply a uniformly random rotation drawn from ``rng``.
    rng : None, int, numpy.random.SeedSequence or numpy.random.Generator
        Only used when ``randomize`` is True (but validated always).
    dtype : {numpy.float64, numpy.float32}
        Of the result; the points are computed in float64.

    Returns
    -------
    ndarray, shape (n, 3)
        Row i is point i of :func:`fibonacci_points` (rotated, with ``randomize=True``).

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import sample_fibonacci
    >>> d = sample_fibonacci(10_000)
    >>> f = np.exp(d @ [0.3, -0.5, 0.6])
    >>> a = np.sqrt(0.3**2 + 0.5**2 + 0.6**2)
    >>> bool(abs(4 * np.pi * f.mean() / (4 * np.pi * np.sinh(a) / a) - 1) < 1e-5)
    True
    """
    n = check_count(n, "n")
    dtype = check_dtype(dtype)
    rng = check_rng(rng)
    randomize = check_bool(randomize, "randomize")
    d = _fibonacci(n)
    if randomize:
        from scipy.spatial.transform import Rotation  # function-level: scipy.spatial adds ~0.3 s to every CLI start

        d = Rotation.random(rng=rng).apply(d)
    return d.astype(dtype)


def fibonacci_points(n: int, *, start: int = 0, stop: int | None = None) -> Float64Array:
    """The n spherical Fibonacci points (Keinert et al. 2015), deterministic; rows *start* to *stop* - 1.

    ``z_i = 1 - (2 i + 1)/n`` and ``phi_i = 2 pi frac(i (Phi - 1))`` for
    i = 0, ..., n - 1 (1/Phi = Phi - 1).  The fractional part is computed in
    64-bit fixed point: ``i * floor(2^64 (Phi - 1)) mod 2^64`` is an exact
    integer product, so phi_i has an error below 2 pi i 2^-64 (about 3e-10
    at i = 10^9) instead of the ~i 1e-16 of the float64 product.
    sin(theta_i) = sqrt((2 i + 1)(2 n - 2 i - 1))/n, without cancellation.

    Parameters
    ----------
    n : int
    start, stop : int, optional
        A range of the points (default all): a large set in bounded memory, piece by piece.

    Returns
    -------
    ndarray, shape (stop - start, 3), float64

    Examples
    --------
    >>> from symsphere.peers import fibonacci_points
    >>> bool((fibonacci_points(4, start=2) == fibonacci_points(4)[2:]).all())
    True
    >>> fibonacci_points(4).round(6)
    array([[ 0.661438,  0.      ,  0.75    ],
           [-0.713954, -0.654041,  0.25    ],
           [ 0.08465 ,  0.964538, -0.25    ],
           [ 0.402444, -0.524918, -0.75    ]])
    """
    n = check_count(n, "n")
    stop = n if stop is None else stop
    for value, name in ((start, "start"), (stop, "stop")):
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or not 0 <= value <= n:
            raise ValueError(f"'{name}' must be an integer with 0 <= {name} <= n = {n}; got {short_repr(value)}")
    if start > stop:
        raise ValueError(f"'start' must be at most 'stop'; got start={start}, stop={stop}")
    return np.stack(_fibonacci_point(np.arange(start, stop, dtype=np.int64), n), axis=-1).reshape(-1, 3)


def _fibonacci(n: int) -> Float64Array:
    return np.stack(_fibonacci_point(np.arange(n, dtype=np.int64), n), axis=-1)


@register_jitable
def _fibonacci_point(i: Any, n: Any) -> Any:
    # Keinert et al. (2015): z_i = 1 - (2i + 1)/n, phi_i = 2 pi frac(i / Phi).  numpy applies it to an
    # int64 array i, numba compiles it for one int (the study's kernels, through fibonacci_point).
    odd = 2.0 * i + 1.0  # exact: i < 2^52
    z = 1.0 - odd / n
    sin_theta = np.sqrt(odd * (2.0 * n - odd)) / n
    # frac(i (Phi - 1)) in 64-bit fixed point: the product wraps mod 2^64 exactly.
    frac_bits = np.uint64(i) * _GOLDEN_FRACTION_BITS
    frac = np.float64(frac_bits >> np.uint64(11)) * TWO_POW_M53
    phi = 2.0 * np.pi * frac
    return sin_theta * np.cos(phi), sin_theta * np.sin(phi), z


def fibonacci_point(i: int, n: int) -> tuple[float, float, float]:
    """Point *i* of the *n* spherical Fibonacci points, elementwise: what :func:`fibonacci_points` gives in row i.

    Numba compiles it (the study's compiled peers call it in their kernels); from Python, *i* and *n* are
    checked (``0 <= i < n``).

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import fibonacci_point, fibonacci_points
    >>> bool(np.array_equal(fibonacci_point(2, 4), fibonacci_points(4)[2]))
    True
    """
    n = check_count(n, "n")
    if isinstance(i, bool) or not isinstance(i, int | np.integer) or not 0 <= i < n:
        raise ValueError(f"'i' must be an integer with 0 <= i < n = {n}; got {short_repr(i)}")
    with np.errstate(over="ignore"):  # the fixed-point product wraps mod 2^64 by design
        x, y, z = _fibonacci_point(np.int64(i), n)
    return float(x), float(y), float(z)


@overload(fibonacci_point, jit_options={}, inline="never", strict=False)
def _fibonacci_point_in_kernels(i: Any, n: Any) -> Any:
    return _fibonacci_point
