"""Monte Carlo and quasi-Monte Carlo integration over the sphere and hemisphere, with honest error bars.

The estimator weights every direction by 1/pdf of the scheme, so it is unbiased
for every map (the paper's too).  The 48 (24) directions of an orbit are not
independent; the independent units are:

- ``points='random'``: the orbits.  Each orbit gives one estimate (the weighted
  mean of f over its directions); the standard error is the standard deviation
  of those estimates over sqrt(#orbits).
- ``points='stratified'``, ``'sobol'``, ``'halton'``: *replicates*, independent
  randomisations (jitter or scrambling) of the whole point set, spawned from
  ``rng`` as ``scipy.integrate.qmc_quad`` does.  The orbits of one stratified or
  QMC set are negatively correlated by design, so a per-orbit error would
  overstate the error, often by orders of magnitude; replicates measure it.
- any ``scipy.stats.qmc.QMCEngine``: one run from the engine's state; no error
  estimate (``standard_error`` is NaN), since replicates of a given engine cannot
  be made independent.

A compiled ``f`` (a numba ``@njit`` function of one direction, ``f(x, y, z)`` or ``f(w)``
with w of shape (3,), or an integrand of :mod:`symsphere.integrands`) is evaluated inside
the parallel kernel: directions are never stored, orbit sums stay in registers.  Same
estimator, same error bar (to rounding); see ``docs/integration.md``.

To a tolerance (``atol=``, ``rtol=``, ``n_max=``, scipy's names): n doubles (``'stratified'``:
quadruples, the grid's side doubles; ``'random'``: jumps by the power of 2 that the n**-0.5
law predicts), reusing the points and block sums of the previous stages, until the interval's half-width is at most ``max(atol, rtol * |integral|)``.  To keep
the interval honest however early the rule stops, stage j spends ``alpha / (j (j + 1))`` of
``alpha = 1 - confidence_level`` (the sum over all stages is alpha): every stage's interval,
the returned one included, covers the integral with probability at least
``confidence_level`` (a union bound), so stopping when an interval happens to be narrow
cannot make it lie.

Work is done in blocks of ``symsphere.points.BLOCK`` orbits: f sees one block of
directions at a time, so memory stays bounded for any n, and block results are
combined in block order, so the result does not depend on how the work is split
(:mod:`symsphere.distributed` relies on this).
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import numpy.typing as npt

from ._integration import DEFAULT_REPLICATES, IntegrationResult, Integrand, Partial, Plan, block_partials, finish, plan
from ._typing import Domain, MapMethod, PointsLike, RNGLike
from ._validation import check_choice, check_count, check_nonnegative
from .points import BLOCK, check_points
from .symmetry import DOMAINS

__all__ = ["IntegrationResult", "integrate"]


def integrate(
    f: Integrand,
    *,
    domain: Domain = "sphere",
    n: int | None = None,
    method: MapMethod = "equal_area",
    points: PointsLike = "random",
    normal: npt.ArrayLike | None = None,
    rng: RNGLike = None,
    replicates: int | None = None,
    confidence_level: float = 0.95,
    atol: float | None = None,
    rtol: float | None = None,
    n_max: int | None = None,
) -> IntegrationResult:
    """Integrate f over the sphere or a hemisphere with the symmetric scheme.

    Parameters
    ----------
    f : callable
        Takes an (m, 3) float64 array of unit directions and returns an (m,)
        or (m, k) array of finite values.  Or compiled, evaluated inside the kernel: a
        numba ``@njit`` function of one direction, ``f(x, y, z) -> float`` or ``f(w) -> float``
        with w of shape (3,), or a :class:`symsphere.integrands.Integrand` (its ``kernel``).
    domain : {'sphere', 'hemisphere'}
    n : int
        Evaluations of f in all: a multiple of 48 (hemisphere: 24), and of
        48 * replicates (24 * replicates) when replicates are used.  Required unless
        ``atol`` or ``rtol`` is given; then it is the first stage's n (default: 256 orbits
        per replicate; 'stratified': a 16 x 16 grid).
    method : {'equal_area', 'paper1', 'paper2'}
        Map onto T0; the paper's maps are weighted by 1/pdf, so the estimate
        stays unbiased.
    points : {'random', 'stratified', 'sobol', 'halton'} or scipy.stats.qmc.QMCEngine
        The base points of the unit square (as in :func:`symsphere.sample_sphere`); they decide
        the independent units of the standard error (see the module's description).
    normal : array_like of 3 floats, optional
        Pole of the hemisphere (``domain='hemisphere'`` only).  For the
        rendering equation, integrate ``L(w) * f_r * max(0, w . normal)``.
    rng : None, int, numpy.random.SeedSequence or numpy.random.Generator
        Seeds the points (or their randomisations).  The same seed gives the same result, however
        the work is split.
    replicates : int, optional
        Independent randomisations for stratified and QMC points (default 8);
        must be None or 1 for random points and for a QMCEngine.
    confidence_level : float
        Of the returned confidence interval, in (0, 1).  With a tolerance: of all stages'
        intervals at once (see the module's description).
    atol, rtol : float, optional
        Integrate to a tolerance: double n until the interval's half-width is at most
        ``max(atol, rtol * |integral|)``.  Needs an error estimate: not with a QMCEngine, and
        at least 2 replicates for stratified and QMC points.
    n_max : int, optional
        With a tolerance: the largest n to try (default 48 * 2**24, hemisphere 24 * 2**24);
        if the tolerance is not reached there, a warning gives the half-width reached.

    Returns
    -------
    IntegrationResult
        The estimate, its standard error and confidence interval, and the number of independent
        units behind them; with a tolerance also ``tolerance``, ``n_stages``, ``converged``, and
        ``n_evaluations`` is the n of the last stage (every evaluation made, since the stages
        reuse their points; 'stratified' grids are not nested: see the module's description).

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere import integrate
    >>> result = integrate(lambda w: np.exp(w[:, 0]), n=48 * 4096, rng=1)
    >>> exact = 2 * np.pi * (np.e - 1 / np.e)
    >>> bool(abs(result.integral - exact) < 4 * result.standard_error)
    True
    >>> cosine = lambda w: np.maximum(w @ [0.0, 0.6, 0.8], 0.0)     # irradiance of L = 1: pi
    >>> result = integrate(cosine, domain="hemisphere", normal=[0, 0.6, 0.8], n=24 * 2**12, points="sobol", rng=2)
    >>> round(float(result.integral), 4), result.unit
    (3.1416, 'replicate')

    To a tolerance, with a compiled integrand evaluated inside the kernel:

    >>> from numba import njit
    >>> @njit
    ... def g(x, y, z):
    ...     return np.exp(x)
    >>> result = integrate(g, rtol=1e-7, points="sobol", rng=3)
    >>> result.converged, bool(abs(result.integral - exact) <= 1e-7 * exact)
    (True, True)
    >>> low, high = result.confidence_interval
    >>> bool((high - low) / 2 <= result.tolerance), result.n_evaluations, result.n_stages
    (True, 393216, 3)
    """
    if atol is None and rtol is None:
        if n_max is not None:
            raise ValueError("'n_max' is only valid with 'atol' or 'rtol'")
        if n is None:
            raise TypeError("integrate() missing required keyword argument 'n' (or give 'atol' or 'rtol')")
        work = plan(f, domain, n, method, points, normal, rng, replicates, confidence_level)
        partials = [block_partials(work, r, 0, work.blocks_per_replicate) for r in range(work.replicates)]
        return finish(work, partials)
    return _to_tolerance(f, domain, n, method, points, normal, rng, replicates, confidence_level, atol, rtol, n_max)


def _to_tolerance(
    f: Integrand,
    domain: Domain,
    n: int | None,
    method: MapMethod,
    points: PointsLike,
    normal: npt.ArrayLike | None,
    rng: RNGLike,
    replicates: int | None,
    confidence_level: float,
    atol: float | None,
    rtol: float | None,
    n_max: int | None,
) -> IntegrationResult:
    """Double n, reusing the blocks already summed, until the half-width meets the tolerance."""
    atol = 0.0 if atol is None else check_nonnegative(atol, "atol")
    rtol = 0.0 if rtol is None else check_nonnegative(rtol, "rtol")
    if atol == 0 and rtol == 0:
        raise ValueError("'atol' or 'rtol' must be positive")
    count = 48 if check_choice(domain, "domain", DOMAINS) == "sphere" else 24
    if check_points(points) is not None:
        raise ValueError(
            "'atol' and 'rtol' need an error estimate, which a QMCEngine does not give "
            "(its replicates cannot be made independent); use points='sobol' or 'halton' (scrambled replicates)"
        )
    stratified = points == "stratified"
    if points != "random":
        replicates = DEFAULT_REPLICATES if replicates is None else check_count(replicates, "replicates")
        if replicates < 2:
            raise ValueError(f"'replicates' must be at least 2 with 'atol' or 'rtol' (an error estimate), got {replicates}")
    unit = count * (replicates or 1)
    n = unit * (16**2 if stratified else 256) if n is None else check_count(n, "n", multiple=unit)
    n_max = count * 2**24 if n_max is None else check_count(n_max, "n_max", multiple=count)
    if n_max < n:
        raise ValueError(f"'n_max' must be at least n={n}, got {n_max}")
    growth = 4 if stratified else 2
    largest_n = n
    while largest_n * growth <= n_max:
        largest_n *= growth
    # One plan for the largest stage: its point sources address every stage's points by index.
    # 'stratified' grids are not nested (a finer grid is other points), so each stage plans anew.
    largest = plan(f, domain, largest_n, method, points, normal, rng, replicates, confidence_level)
    kept: dict[tuple[int, int], Partial] = {}  # (replicate, block) -> the partial of a whole block
    alpha = 1.0 - largest.confidence_level
    stage, n_stage = 1, n
    while True:
        level = 1.0 - alpha / (stage * (stage + 1))
        if stratified:
            work = plan(f, domain, n_stage, method, points, normal, rng, replicates, level)
            kept.clear()
        else:
            orbits = n_stage // unit
            work = dataclasses.replace(
                largest, orbits_per_replicate=orbits, blocks_per_replicate=-(-orbits // BLOCK), confidence_level=level
            )
        result = _stage_result(work, kept, stage, atol, rtol)
        if result.converged or n_stage == largest_n:
            break
        factor = growth
        if points == "random":  # the error falls as n**-0.5 exactly: jump to the n predicted for the next level
            factor = max(2, _predicted_factor(result, alpha / ((stage + 1) * (stage + 2))))
        while n_stage * factor > largest_n:
            factor //= 2
        stage, n_stage = stage + 1, n_stage * factor
    if not result.converged:
        low, high = result.confidence_interval
        warnings.warn(
            f"integrate: the tolerance {result.tolerance:.3g} was not reached by n_max={n_max}: at n={n_stage} the "
            f"half-width of the {100 * result.confidence_level:.4g}% interval is {np.max((high - low) / 2):.3g}",
            UserWarning,  # as scipy's IntegrationWarning
            stacklevel=3,  # the caller of integrate
        )
    return result


def _predicted_factor(result: IntegrationResult, next_alpha: float) -> int:
    """The power of 2 by which n must grow for the next stage's half-width to meet the tolerance,
    if the standard error falls as n**-0.5 (random points: exactly, in expectation)."""
    from scipy import special  # not at import: the t quantile, as scipy.stats.t.ppf computes it

    assert result.tolerance is not None
    t = special.stdtrit(result.n_units - 1, 1 - next_alpha / 2)
    ratio = float(np.max(t * np.asarray(result.standard_error))) / result.tolerance if result.tolerance > 0 else np.inf
    if not np.isfinite(ratio):
        return 2
    return int(2 ** max(1, int(np.ceil(np.log2(max(ratio * ratio, 1.0))))))


def _stage_result(work: Plan, kept: dict[tuple[int, int], Partial], stage: int, atol: float, rtol: float) -> IntegrationResult:
    """The result at one stage: whole blocks from *kept*, the rest summed now (and whole ones kept)."""
    partials = []
    for replicate in range(work.replicates):
        reused = 0
        while (replicate, reused) in kept and reused < work.blocks_per_replicate:
            reused += 1
        fresh = block_partials(work, replicate, reused, work.blocks_per_replicate)
        for block, partial in enumerate(fresh, start=reused):
            if partial[0] == BLOCK:
                kept[(replicate, block)] = partial
        partials.append([kept[(replicate, b)] for b in range(reused)] + fresh)
    result = finish(work, partials)
    low, high = result.confidence_interval
    tolerance = np.maximum(atol, rtol * np.abs(result.integral))
    converged = bool(np.all((np.asarray(high) - np.asarray(low)) / 2 <= tolerance))
    return dataclasses.replace(result, tolerance=float(np.min(tolerance)), n_stages=stage, converged=converged)
