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
estimator, same error bar (to rounding); see ``docs/explanation/fused-integration.md``.

To a tolerance (``atol=``, ``rtol=``, ``n_max=``, scipy's names): n doubles (``'stratified'``:
quadruples, the grid's side doubles; ``'random'``: jumps by the power of 2 that the n**-0.5
law predicts), reusing the points and block sums of the previous stages, until the interval's half-width is at most ``max(atol, rtol * |integral|)``.  To keep
the interval honest however early the rule stops, stage j spends ``alpha / (j (j + 1))`` of
``alpha = 1 - confidence_level`` (the sum over all stages is alpha): every stage's interval,
the returned one included, covers the integral with probability at least
``confidence_level`` (a union bound), so stopping when an interval happens to be narrow
cannot make it lie.

``method='auto'``, ``'lebedev'``, ``'fibonacci'``: randomly rotated rule families and the choice
among them by a pilot on f (:mod:`symsphere._auto`; ``docs/explanation/fused-integration.md``).

Work is done in blocks of ``symsphere.points.BLOCK`` orbits: f sees one block of
directions at a time, so memory stays bounded for any n, and block results are
combined in block order, so the result does not depend on how the work is split
(:mod:`symsphere.distributed` relies on this).
"""

from __future__ import annotations

from typing import Literal, cast

import numpy.typing as npt

from ._auto import RULE_METHODS, integrate_rules
from ._integration import Integrand, IntegrationResult, Request, block_partials, finish, plan, to_tolerance
from ._threads import route_compiles
from ._typing import Domain, MapMethod, PointsLike, RNGLike
from ._validation import check_choice
from .warps import METHODS

__all__ = ["IntegrationResult", "integrate"]


def integrate(
    f: Integrand,
    *,
    domain: Domain = "sphere",
    n: int | None = None,
    method: MapMethod | Literal["auto", "fibonacci", "lebedev"] = "equal_area",
    points: PointsLike | None = None,
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
        per replicate; 'stratified': a 16 x 16 grid).  ``'lebedev'``, ``'fibonacci'``: replicates x
        the points of one of the family's stages (a Lebedev rule's size or r x 5810; 16 x 2**k), and
        only without a tolerance (to a tolerance they start at their smallest stage).
    method : {'equal_area', 'paper1', 'paper2', 'auto', 'fibonacci', 'lebedev'}
        The scheme's map onto T0 (the paper's maps are weighted by 1/pdf, so the estimate
        stays unbiased); or a family of randomly rotated rules, ``'lebedev'`` (Lebedev rules of
        increasing order) or ``'fibonacci'`` (spherical Fibonacci sets), each replicate under its own
        uniform random rotation (the hemisphere: the rule folded about the normal); or ``'auto'``
        (needs ``atol`` or ``rtol``): a pilot of small stages on f itself, then a fresh stage (new
        rotations or base points, 16 x ``replicates`` of them, 8 x on a fast decay where cheaper, or 4 x
        where a rule already measured is predicted far inside the tolerance) of the family predicted to reach the
        tolerance with the fewest evaluations, at the size predicted; the answer is always such a fresh
        stage, and its interval is its own Student-t interval at ``confidence_level``
        (``result.method`` says which family, ``result.history`` why).  A named rule family to a
        tolerance runs the same with that family alone.  Not in
        :func:`symsphere.distributed.integrate`.  See ``docs/explanation/fused-integration.md``.
    points : {'random', 'stratified', 'sobol', 'halton', 'sobol_interlaced2', 'sobol_interlaced3'} \
or scipy.stats.qmc.QMCEngine, optional
        The base points of the unit square (as in :func:`symsphere.sample_sphere`); they decide
        the independent units of the standard error (see the module's description).  Default
        ``'random'``; with ``method='auto'`` the scheme's family uses ``'sobol_interlaced3'``; not
        valid with ``'lebedev'`` and ``'fibonacci'``.
    normal : array_like of 3 floats, optional
        Pole of the hemisphere (``domain='hemisphere'`` only).  For the
        rendering equation, integrate ``L(w) * f_r * max(0, w . normal)``.
    rng : None, int, numpy.random.SeedSequence or numpy.random.Generator
        Seeds the points (or their randomisations).  The same seed gives the same result, however
        the work is split.
    replicates : int, optional
        Independent randomisations for stratified and QMC points and for the rotated rule
        families (default 8); must be None or 1 for random points and for a QMCEngine.  With
        ``'auto'``, ``'lebedev'``, ``'fibonacci'`` to a tolerance: of the pilot's stages; the answering
        stage has 16 times as many (default 128), 8 times (64) on a fast decay where cheaper, 4 times far
        inside the tolerance (32).
    confidence_level : float
        Of the returned confidence interval, in (0, 1).  With a tolerance and one of the scheme's
        maps: of all stages' intervals at once (see the module's description); with ``'auto'``,
        ``'lebedev'``, ``'fibonacci'``: of the answering stage's interval, whose size was fixed
        before its values were seen.
    atol, rtol : float, optional
        Integrate to a tolerance: double n until the interval's half-width is at most
        ``max(atol, rtol * |integral|)``.  Needs an error estimate: not with a QMCEngine, and
        at least 2 replicates for stratified and QMC points.
    n_max : int, optional
        With a tolerance: the largest n to try (default 48 * 2**24, hemisphere 24 * 2**24);
        if the tolerance is not reached there, a warning gives the half-width reached.  With
        ``'auto'``, ``'lebedev'``, ``'fibonacci'``: a bound on every evaluation of every stage (and
        family), the best interval is returned.

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

    Let a pilot on f choose the rule (``result.history`` says why, stage by stage):

    >>> result = integrate(lambda w: np.exp(w[:, 0]), rtol=1e-9, method="auto", rng=4)
    >>> result.method, result.converged, result.n_evaluations
    ('lebedev', True, 4336)
    >>> bool(abs(result.integral - exact) <= 1e-9 * exact), result.history[0]["reason"][:5]
    (True, 'pilot')
    """
    check_choice(method, "method", tuple(sorted((*METHODS, *RULE_METHODS))))
    request = Request(f, domain, n, method, points, normal, rng, replicates, confidence_level, atol, rtol, n_max)
    if method in RULE_METHODS:
        return integrate_rules(request)
    points = "random" if points is None else points
    map_method = cast(MapMethod, method)  # a map (plan checks it)
    if atol is None and rtol is None:
        if n_max is not None:
            raise ValueError("'n_max' is only valid with 'atol' or 'rtol'")
        if n is None:
            raise TypeError("integrate() missing required keyword argument 'n' (or give 'atol' or 'rtol')")
        work = plan(f, domain, n, map_method, points, normal, rng, replicates, confidence_level)
        partials = [block_partials(work, r, 0, work.blocks_per_replicate) for r in range(work.replicates)]
        return finish(work, partials)
    return to_tolerance(request)


route_compiles(globals())  # the first compile of each numba function here: interruptible (_threads)
