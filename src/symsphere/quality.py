"""Measures of quality of a Monte Carlo rule: RMSE, convergence slope and spherical-cap discrepancy.

- :func:`rmse`: the root-mean-square error of repeated estimates about the exact value;
- :func:`fit_slope` (:class:`SlopeFit`): the convergence order, by least squares on log-log axes,
  with its standard error;
- :func:`cap_discrepancy_squared`, :func:`cap_discrepancy`: the spherical-cap L2 discrepancy of a
  point set (optionally weighted) on S², exact, by Stolarsky's invariance principle.

The convergence study (``symsphere study``, :mod:`symsphere.apps.study`) is built on these; they are
library code, usable on any estimator or point set.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
import numpy.typing as npt

from ._threads import route_compiles, start_threads
from ._typing import Float64Array
from ._validation import as_float_array, check_positive_real

__all__ = ["LOG_FLOOR", "SlopeFit", "cap_discrepancy", "cap_discrepancy_squared", "fit_slope", "rmse"]

LOG_FLOOR = 1e-300
"""log(0) guard of :func:`fit_slope`: values below it are raised to it."""


def rmse(estimates: npt.ArrayLike, exact: float | npt.ArrayLike) -> np.ndarray:
    """Root-mean-square error of *estimates* (last axis: repetitions) about *exact*.

    Parameters
    ----------
    estimates : array_like, shape (..., R)
        R >= 1 repeated estimates along the last axis.
    exact : float or array_like
        The exact value, broadcast against *estimates*.

    Returns
    -------
    ndarray, shape (...)
        ``sqrt(mean((estimates - exact)**2, axis=-1))`` (a 0-d array for 1-D *estimates*).

    Examples
    --------
    >>> from symsphere.quality import rmse
    >>> float(rmse([1.0, 3.0], 2.0))
    1.0
    """
    estimates = _finite(estimates, "estimates")
    exact_values = _finite(exact, "exact")
    if estimates.ndim == 0 or estimates.shape[-1] < 1:
        raise ValueError("'estimates' must hold at least one repetition")
    try:
        deviation = estimates - exact_values
    except ValueError:
        raise ValueError(
            f"'exact' of shape {exact_values.shape} does not broadcast against 'estimates' of shape {estimates.shape}"
        ) from None
    with np.errstate(over="raise"):
        try:
            error: npt.NDArray[Any] = np.sqrt(np.mean(deviation**2, axis=-1))
        except FloatingPointError:
            raise ValueError(
                "'estimates' and 'exact' are too far apart: their squared errors overflow float64"
            ) from None
    return error


@dataclass(frozen=True)
class SlopeFit:
    """Least-squares fit log(rmse) = intercept + slope * log(n), as :func:`fit_slope` returns it.

    Attributes
    ----------
    slope : float
        The convergence order: -1/2 for Monte Carlo, steeper for good quasi-Monte Carlo rules.
    standard_error : float
        The usual OLS standard error of the slope (NaN with fewer than three points).
    intercept : float
        log of the fitted value at n = 1.
    points : int
        The number of points used.

    Examples
    --------
    >>> import numpy as np
    >>> import symsphere
    >>> from symsphere.quality import fit_slope, rmse
    >>> f, exact = lambda d: np.exp(d[:, 0]), 2 * np.pi * (np.e - 1 / np.e)
    >>> ns = [48 * 16, 48 * 64, 48 * 256]
    >>> errors = [rmse([symsphere.integrate(f, n=n, rng=seed).integral for seed in range(16)], exact) for n in ns]
    >>> fit = fit_slope(ns, errors)
    >>> fit.points, bool(abs(fit.slope + 0.5) < 3 * fit.standard_error + 0.05)    # Monte Carlo: -1/2
    (3, True)
    >>> predicted = np.exp(fit.intercept) * np.array(ns) ** fit.slope
    >>> bool(np.allclose(predicted, errors, rtol=0.2))
    True
    """

    slope: float
    standard_error: float
    intercept: float
    points: int


def fit_slope(n: npt.ArrayLike, values: npt.ArrayLike, *, floor: float = LOG_FLOOR) -> SlopeFit:
    """Fit the convergence slope of *values* (e.g. RMSE) against *n* on log-log axes.

    Values below *floor* (an exact zero) are raised to it, so the log is finite.

    Parameters
    ----------
    n : array_like, shape (m,)
        Sample sizes, at least two distinct values (if m >= 2).
    values : array_like, shape (m,)
        The measured values, e.g. RMSE, at those sizes.
    floor : float, optional
        Lower bound applied to *values* before the log (default :data:`LOG_FLOOR`).

    Returns
    -------
    SlopeFit
        Slope, its standard error (NaN for m < 3), intercept and the number of points; all NaN
        but ``points`` for m < 2.

    Examples
    --------
    >>> from symsphere.quality import fit_slope
    >>> fit = fit_slope([100, 400, 1600], [0.1, 0.05, 0.025])
    >>> round(fit.slope, 12), round(fit.standard_error, 12)
    (-0.5, 0.0)
    """
    counts = _finite(n, "n")
    if np.any(counts <= 0):
        raise ValueError("'n' must be positive")
    x = np.log(counts)
    v = _finite(values, "values")
    floor = check_positive_real(floor, "floor")
    if x.shape != v.shape or x.ndim != 1:
        raise ValueError(f"'n' and 'values' must be 1-D of the same length, got {x.shape} and {v.shape}")
    if len(x) < 2:
        return SlopeFit(math.nan, math.nan, math.nan, len(x))
    y = np.log(np.maximum(v, floor))
    xm, ym = x.mean(), y.mean()
    sxx = float(np.sum((x - xm) ** 2))
    if sxx == 0:
        raise ValueError("'n' must hold at least two distinct values")
    slope = float(np.sum((x - xm) * (y - ym)) / sxx)
    intercept = float(ym - slope * xm)
    if len(x) > 2:
        residual = y - (intercept + slope * x)
        se = math.sqrt(float(np.sum(residual**2)) / (len(x) - 2) / sxx)
    else:
        se = math.nan
    return SlopeFit(slope, se, intercept, len(x))


def cap_discrepancy_squared(points: npt.ArrayLike, weights: npt.ArrayLike | None = None) -> float:
    """Squared spherical-cap L2 discrepancy of points on S², exact, by Stolarsky's invariance principle.

    With the caps C(x, t) = {y : x.y >= t} and sigma the normalised surface
    measure (sigma(C(x, t)) = (1 - t)/2)::

        D^2 = integral over t in [-1, 1] and x in S^2 of
              (sum_i w_i 1[x_i in C(x, t)] - sigma(C(x, t)))^2 dsigma(x) dt.

    Stolarsky's invariance principle (Stolarsky 1973; Brauchart & Dick, Proc.
    AMS 141 (2013) 2085-2096, with C_2 = 1/4 on S^2) turns it into a sum of
    distances: the kernel integral of the product of two cap indicators is
    ``1 - |y - z|/4``, so::

        D^2 = (sum w)^2 - (1/4) sum_{i,j} w_i w_j |x_i - x_j| - (4/3) sum w + 2/3,

    which for equal weights w_i = 1/N is the classical
    ``D^2 = 1/3 - (1/(4 N^2)) sum_{i,j} |x_i - x_j|``.  For N independent uniform
    points E D^2 = 1/(3N) (since ``E|x - y| = 4/3``).  D is also the worst-case
    error of the rule sum_i w_i f(x_i) for the mean of f over the sphere in
    the Sobolev space H^(3/2)(S^2) with reproducing kernel ``1 - |x - y|/4``.

    Parameters
    ----------
    points : array_like, shape (N, 3)
        Unit vectors (normalised here).
    weights : array_like, shape (N,), optional
        Non-negative; default 1/N each.  For an importance-sampling rule use 1/(N 4 pi pdf(x_i)).

    Returns
    -------
    float
        D^2 (exact up to rounding; the O(N^2) sum runs in parallel, rows paired
        for balance, without storing the distance matrix).

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.quality import cap_discrepancy_squared
    >>> octahedron = np.vstack([np.eye(3), -np.eye(3)])
    >>> round(cap_discrepancy_squared(octahedron), 12)      # 1/3 - (24 sqrt 2 + 6 * 2)/(4 * 36)
    0.014297739604
    """
    x = _finite(points, "points")
    if x.ndim != 2 or x.shape[1] != 3 or len(x) == 0:
        raise ValueError(f"'points' must have shape (N, 3) with N >= 1, got {x.shape}")
    x = x / np.maximum(np.max(np.abs(x), axis=1, keepdims=True), 1e-300)  # no overflow in the norm
    norm = np.linalg.norm(x, axis=1)
    if np.any(norm == 0):
        raise ValueError("'points' must be finite and non-zero")
    x = np.ascontiguousarray(x / norm[:, None])
    n = len(x)
    if weights is None:
        w = np.full(n, 1.0 / n)
    else:
        w = np.ascontiguousarray(_finite(weights, "weights"))
        if w.shape != (n,) or not np.all(np.isfinite(w)):
            raise ValueError(f"'weights' must be finite with shape ({n},), got {w.shape}")
        if np.any(w < 0):  # a quadrature rule's weights; negative ones made D^2 meaningless (10.68 once)
            raise ValueError(f"'weights' must be >= 0; got {float(w[w < 0][0]):.6g}")
    total = float(np.sum(w))
    start_threads()  # a parallel kernel: passive OpenMP waiting, as for the sampling kernels
    pair_sum = float(_weighted_distance_sum(x, w))
    return total * total - 0.25 * pair_sum - (4.0 / 3.0) * total + 2.0 / 3.0


def cap_discrepancy(points: npt.ArrayLike, weights: npt.ArrayLike | None = None) -> float:
    """Spherical-cap L2 discrepancy: the square root of :func:`cap_discrepancy_squared` (clipped at 0).

    Parameters
    ----------
    points : array_like, shape (N, 3)
        Unit vectors (normalised here).
    weights : array_like, shape (N,), optional
        Default 1/N each.

    Returns
    -------
    float
        D >= 0.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.quality import cap_discrepancy
    >>> round(cap_discrepancy(np.vstack([np.eye(3), -np.eye(3)])), 6)
    0.119573
    """
    return math.sqrt(max(cap_discrepancy_squared(points, weights), 0.0))


@numba.njit(cache=True)
def _row_distance_sum(x: Float64Array, w: Float64Array, i: int) -> float:  # pragma: no cover - compiled
    """w_i * sum over j > i of w_j |x_i - x_j|."""
    xi, yi, zi = x[i, 0], x[i, 1], x[i, 2]
    row = 0.0
    for j in range(i + 1, x.shape[0]):
        dx, dy, dz = xi - x[j, 0], yi - x[j, 1], zi - x[j, 2]
        row += w[j] * math.sqrt(dx * dx + dy * dy + dz * dz)
    return float(w[i] * row)


@numba.njit(parallel=True, cache=True)
def _weighted_distance_sum(x: Float64Array, w: Float64Array) -> float:  # pragma: no cover - compiled
    """sum over i != j of w_i w_j |x_i - x_j|: rows r and N-1-r share a task, so the tasks are equal."""
    n = x.shape[0]
    total = 0.0
    for r in numba.prange((n + 1) // 2):
        other = n - 1 - r
        acc = _row_distance_sum(x, w, r)
        if other != r:
            acc += _row_distance_sum(x, w, other)
        total += acc
    return 2.0 * total


def _finite(values: object, name: str) -> Float64Array:
    array: Float64Array = as_float_array(values, name).astype(np.float64)
    if not np.all(np.isfinite(array)):
        raise ValueError(f"'{name}' must be finite (no NaN or inf)")
    return array


route_compiles(globals())  # the first compile of each numba function here: interruptible (_threads)
