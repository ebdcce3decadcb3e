"""Lebedev quadrature on the sphere, plain and randomly rotated: the peers ``lebedev`` and ``lebedev_rotated``.

A private module with public names (re-exported by :mod:`symsphere.peers`, where they are documented
with the other peers).  The rules are scipy's (``scipy.integrate.lebedev_rule``, orders 3 to 131,
6 to 5810 points; Lebedev & Laikov 1999).  A Lebedev rule is invariant under the octahedral group
O_h: its points are whole orbits (of 6, 8, 12, 24 or 48 points) of the same 48 signed permutations
of (x, y, z) that the symmetric scheme uses, with one weight per orbit, so the rule is itself a sum
over orbits of the scheme's 48 maps, with nodes and weights chosen so that it integrates every
polynomial of degree up to the order exactly.  (The rules of orders 13, 25 and 27 have a negative
weight.)
"""

from __future__ import annotations

import functools
import math

import numpy as np

from ._typing import DTypeLike, Float64Array, FloatArray, RNGLike
from ._validation import check_bool, check_count, check_dtype, check_rng

__all__ = ["LEBEDEV_ORDERS", "LEBEDEV_SIZES", "lebedev_size", "lebedev_weights", "sample_lebedev"]

LEBEDEV_ORDERS: tuple[int, ...] = (
    3,
    5,
    7,
    9,
    11,
    13,
    15,
    17,
    19,
    21,
    23,
    25,
    27,
    29,
    31,
    35,
    41,
    47,
    53,
    59,
    65,
    71,
    77,
    83,
    89,
    95,
    101,
    107,
    113,
    119,
    125,
    131,
)
"""tuple of int: the orders (exact polynomial degrees) of ``scipy.integrate.lebedev_rule``."""

LEBEDEV_SIZES: tuple[int, ...] = (
    6,
    14,
    26,
    38,
    50,
    74,
    86,
    110,
    146,
    170,
    194,
    230,
    266,
    302,
    350,
    434,
    590,
    770,
    974,
    1202,
    1454,
    1730,
    2030,
    2354,
    2702,
    3074,
    3470,
    3890,
    4334,
    4802,
    5294,
    5810,
)
"""tuple of int: the number of points of the rule of each order of :data:`LEBEDEV_ORDERS`."""


def lebedev_size(n: int, *, randomize: bool = False) -> int:
    """The largest number of points at most *n* that :func:`sample_lebedev` accepts.

    A rule's size (:data:`LEBEDEV_SIZES`); with ``randomize=True`` also a multiple r x 5810 (r
    independently rotated copies of the largest rule).

    Parameters
    ----------
    n : int
        At least 6.
    randomize : bool
        Count the multiples of 5810 too, which :func:`sample_lebedev` takes with ``randomize=True``.

    Returns
    -------
    int
        The size, at most *n*.

    Examples
    --------
    >>> from symsphere.peers import lebedev_size
    >>> lebedev_size(1000), lebedev_size(20_000), lebedev_size(20_000, randomize=True)
    (974, 5810, 17430)
    """
    n = check_count(n, "n")
    randomize = check_bool(randomize, "randomize")
    if n < LEBEDEV_SIZES[0]:
        raise ValueError(f"'n' must be at least {LEBEDEV_SIZES[0]} (the smallest Lebedev rule), got {n}")
    if randomize and n >= 2 * LEBEDEV_SIZES[-1]:
        return n // LEBEDEV_SIZES[-1] * LEBEDEV_SIZES[-1]
    return max(size for size in LEBEDEV_SIZES if size <= n)


def sample_lebedev(
    n: int, *, randomize: bool = False, rng: RNGLike = None, dtype: DTypeLike = np.float64
) -> FloatArray:
    """The nodes of a Lebedev rule with *n* points, optionally under random rotations.

    ``sum(lebedev_weights(n) * f(sample_lebedev(n)))`` is the rule's estimate of the integral of f
    over the sphere.  Unrotated (deterministic), it is exact for polynomials of degree up to the
    order.  With ``randomize=True`` the rule is rotated by a uniformly random rotation
    (``scipy.spatial.transform.Rotation.random``): every node is then marginally uniform and the
    estimate is unbiased for every integrable f, with an error that replicates (independent
    rotations) measure; *n* = r x 5810 gives r independently rotated copies of the order-131
    rule, rows ``5810 i ... 5810 i + 5809`` for copy i, each weighted 1/r.

    Parameters
    ----------
    n : int
        A size of :data:`LEBEDEV_SIZES`, or (``randomize=True``) a multiple of 5810
        (:func:`lebedev_size` gives the largest usable size up to a budget).
    randomize : bool
        Rotate the rule (each copy of it) by a uniformly random rotation drawn from ``rng``.
    rng : None, int, numpy.random.SeedSequence or numpy.random.Generator
        The rotations (validated always, used only with ``randomize=True``).
    dtype : {numpy.float64, numpy.float32}
        Of the result; the nodes are computed in float64.

    Returns
    -------
    ndarray, shape (n, 3)
        The nodes in the order of :func:`lebedev_weights`.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import lebedev_weights, sample_lebedev
    >>> d, w = sample_lebedev(50), lebedev_weights(50)          # order 11: exact up to degree 11
    >>> bool(np.isclose(np.sum(w * d[:, 0] ** 4 * d[:, 1] ** 6), 4 * np.pi * 3 * 15 / (11 * 9 * 7 * 5 * 3)))
    True
    >>> d = sample_lebedev(2 * 5810, randomize=True, rng=1)   # two rotated copies of the order-131 rule
    >>> a = np.array([0.3, -0.5, 0.6])
    >>> exact = 4 * np.pi * np.sinh(np.linalg.norm(a)) / np.linalg.norm(a)
    >>> bool(abs(np.sum(lebedev_weights(2 * 5810, randomize=True) * np.exp(d @ a)) / exact - 1) < 1e-12)
    True
    """
    n = check_count(n, "n")
    dtype = check_dtype(dtype)
    rng = check_rng(rng)
    copies, size = _layout(n, check_bool(randomize, "randomize"))
    nodes, _ = _rule(size)
    if not randomize:
        out: FloatArray = nodes.astype(dtype)
        return out
    from scipy.spatial.transform import Rotation  # function-level: scipy.spatial adds ~0.3 s to every CLI start

    rotations = Rotation.random(copies, rng=rng).as_matrix()  # (copies, 3, 3)
    out = np.einsum("rij,mj->rmi", rotations, nodes).reshape(n, 3).astype(dtype)
    return out


def lebedev_weights(n: int, *, randomize: bool = False) -> Float64Array:
    """The weights of the rows of ``sample_lebedev(n, randomize=randomize)``; they add up to 4 pi.

    Parameters
    ----------
    n : int
        As in :func:`sample_lebedev`.
    randomize : bool
        Needed for n = r x 5810 with r > 1 (r rotated copies, each weighted 1/r).

    Returns
    -------
    ndarray, shape (n,), float64

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import lebedev_weights
    >>> w = lebedev_weights(6)      # order 3: the octahedron's vertices, equal weights
    >>> bool(np.allclose(w, 4 * np.pi / 6))
    True
    """
    copies, size = _layout(check_count(n, "n"), check_bool(randomize, "randomize"))
    _, weights = _rule(size)
    return np.tile(weights / copies, copies)


def _layout(n: int, randomize: bool) -> tuple[int, int]:
    """(copies, rule size) of *n* points; ValueError naming the nearest usable sizes otherwise."""
    largest = LEBEDEV_SIZES[-1]
    if n in LEBEDEV_SIZES:
        return 1, n
    if randomize and n % largest == 0:
        return n // largest, largest
    lower = [s for s in LEBEDEV_SIZES if s < n]
    hint = f"the largest below is {lower[-1]}" if lower else f"the smallest is {LEBEDEV_SIZES[0]}"
    extra = " or, randomized, a multiple of 5810" if randomize else ""
    raise ValueError(f"'n'={n} is not the size of a Lebedev rule{extra} ({hint}; see lebedev_size)")


@functools.cache
def _rule(size: int) -> tuple[Float64Array, Float64Array]:
    """(nodes (size, 3), weights (size,)) of scipy's Lebedev rule with *size* points; weights sum to 4 pi."""
    from scipy.integrate import lebedev_rule  # scipy >= 1.15; imported when first needed

    nodes, weights = lebedev_rule(LEBEDEV_ORDERS[LEBEDEV_SIZES.index(size)])
    nodes = np.ascontiguousarray(nodes.T, dtype=np.float64)
    nodes /= np.linalg.norm(nodes, axis=1, keepdims=True)
    weights = np.asarray(weights, dtype=np.float64)
    assert math.isclose(weights.sum(), 4 * math.pi, rel_tol=1e-12)
    nodes.setflags(write=False)
    weights.setflags(write=False)
    return nodes, weights
