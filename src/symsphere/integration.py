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

Work is done in blocks of ``symsphere.points.BLOCK`` orbits: f sees one block of
directions at a time, so memory stays bounded for any n, and block results are
combined in block order, so the result does not depend on how the work is split
(:mod:`symsphere.distributed` relies on this).
"""

from __future__ import annotations

import numpy.typing as npt

from ._integration import DEFAULT_REPLICATES, IntegrationResult, Integrand, block_partials, finish, plan
from ._typing import Domain, MapMethod, PointsLike, RNGLike

__all__ = ["IntegrationResult", "integrate"]


def integrate(
    f: Integrand,
    *,
    domain: Domain = "sphere",
    n: int,
    method: MapMethod = "equal_area",
    points: PointsLike = "random",
    normal: npt.ArrayLike | None = None,
    rng: RNGLike = None,
    replicates: int | None = None,
    confidence_level: float = 0.95,
) -> IntegrationResult:
    """Integrate f over the sphere or a hemisphere with the symmetric scheme.

    Parameters
    ----------
    f : callable
        Takes an (m, 3) float64 array of unit directions and returns an (m,)
        or (m, k) array of finite values.
    domain : {'sphere', 'hemisphere'}
    n : int
        Evaluations of f in all: a multiple of 48 (hemisphere: 24), and of
        48 * replicates (24 * replicates) when replicates are used.
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
        Of the returned confidence interval, in (0, 1).

    Returns
    -------
    IntegrationResult
        The estimate, its standard error and confidence interval, and the number of independent
        units behind them.

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
    """
    work = plan(f, domain, n, method, points, normal, rng, replicates, confidence_level)
    partials = [block_partials(work, r, 0, work.blocks_per_replicate) for r in range(work.replicates)]
    return finish(work, partials)
