"""Integration to a tolerance: doubling with reuse, the alpha-spending interval, its coverage."""

import warnings

import numpy as np
import pytest
from numba import njit
from scipy import stats
from scipy.stats import qmc

from symsphere import integrate

A = np.array([0.7, -0.4, 0.5])
EXACT = 4 * np.pi * np.sinh(np.linalg.norm(A)) / np.linalg.norm(A)


@njit
def exp_dot(x, y, z):
    return np.exp(0.7 * x - 0.4 * y + 0.5 * z)


def exp_numpy(w):
    return np.exp(w @ A)


@pytest.mark.parametrize("points", ["random", "sobol", "halton"])
def test_stage_equals_fixed_n_run(points):
    """The stages reuse the points by index: the result is the fixed-n run at the n used."""
    result = integrate(exp_numpy, rtol=2e-5 if points == "random" else 1e-7, points=points, rng=4)
    assert result.converged and result.n_stages > 1
    fixed = integrate(exp_numpy, n=result.n_evaluations, points=points, rng=4)
    assert result.integral == fixed.integral and result.standard_error == fixed.standard_error
    low, high = result.confidence_interval
    assert (
        (high - low) / 2
        <= result.tolerance
        == pytest.approx(2e-5 * abs(result.integral) if points == "random" else 1e-7 * abs(result.integral))
    )
    stage = result.n_stages
    assert result.confidence_level == pytest.approx(1 - 0.05 / (stage * (stage + 1)))


def test_stratified_quadruples_and_atol():
    result = integrate(exp_dot, atol=1e-5, points="stratified", rng=1)
    assert result.converged and result.tolerance == 1e-5
    orbits = result.n_evaluations // (48 * 8)
    assert orbits == (16 * 2 ** (result.n_stages - 1)) ** 2
    assert abs(result.integral - EXACT) < 1e-5


def test_hemisphere_and_fused_equal_numpy():
    kwargs = dict(domain="hemisphere", normal=[0, 0.6, 0.8], rtol=1e-3, rng=2)
    fused, numpy_path = integrate(exp_dot, **kwargs), integrate(exp_numpy, **kwargs)
    assert fused.n_evaluations == numpy_path.n_evaluations and fused.n_stages == numpy_path.n_stages
    assert fused.integral == pytest.approx(numpy_path.integral, rel=1e-12)


def test_n_max_warns_at_the_callers_line():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = integrate(exp_numpy, rtol=1e-9, n=48 * 64, n_max=48 * 256, rng=0)
    assert not result.converged and result.n_evaluations == 48 * 256 and result.n_stages == 2  # 64 -> 256 orbits
    assert len(caught) == 1 and caught[0].filename == __file__
    assert "not reached by n_max=12288" in str(caught[0].message) and "half-width" in str(caught[0].message)
    assert "NOT reached" in str(result)


@pytest.mark.parametrize(
    "kwargs, error, match",
    [
        (dict(rtol=1e-3, points=qmc.Sobol(d=2, rng=0)), ValueError, "QMCEngine does not give"),
        (dict(rtol=1e-3, points="sobol", replicates=1), ValueError, "at least 2"),
        (dict(rtol=1e-3, n=48 * 512, n_max=48 * 256), ValueError, "'n_max' must be at least"),
        (dict(rtol=-1.0), ValueError, "'rtol' must be >= 0"),
        (dict(atol=float("nan")), TypeError, "'atol' must be a finite real"),
        (dict(rtol=0.0, atol=0.0), ValueError, "'atol' or 'rtol' must be positive"),
        (dict(n=48, n_max=480), ValueError, "'n_max' is only valid"),
        (dict(), TypeError, "missing required keyword argument 'n'"),
        (dict(rtol=1e-3, n=50), ValueError, "'n'"),
    ],
)
def test_bad_tolerance_arguments(kwargs, error, match):
    with pytest.raises(error, match=match):
        integrate(exp_numpy, **kwargs)


@pytest.mark.slow
@pytest.mark.statistical
@pytest.mark.parametrize("points, rtol", [("random", 1e-4), ("stratified", 1e-6), ("sobol", 1e-7)])
def test_coverage_over_seeds(points, rtol):
    """Over 200 seeds the exact integral lies within the returned half-width (and so within the
    tolerance) at least 95% x the nominal 95% rate.

    With alpha spending every stage's interval covers with probability >= 95% (a union bound), so
    the count of covering seeds is at least Binomial(200, 0.95); the bound 181 = ceil(0.9025 * 200)
    rejects a correct rule with probability P(Bin(200, .95) < 181) = 0.2% per point set (0.6% for
    the three: Sidak), and one that covers 85% of the time with probability 0.985 (its count has mean
    170, sd 5).  The rtol values make the rule stop after different numbers of stages (measured over
    these seeds: random 2-3, stratified 2-3, sobol 1-5), so that stopping early matters; each is the
    largest that does, as the work grows with 1/rtol^2 (random) and the coverage does not depend on
    it.  Reference: the closed form 4 pi sinh|a| / |a|.
    """
    seeds = 200
    covered = within_tolerance = 0
    stages = []
    for seed in range(seeds):
        result = integrate(exp_dot, rtol=rtol, points=points, rng=seed)
        assert result.converged
        low, high = result.confidence_interval
        covered += low <= EXACT <= high
        within_tolerance += abs(result.integral - EXACT) <= result.tolerance
        stages.append(result.n_stages)
    bound = int(np.ceil(0.95 * 0.95 * seeds))
    assert stats.binom.cdf(bound - 1, seeds, 0.95) < 0.003
    assert max(stages) > 1, "the rule must stop at different stages for the test to mean anything"
    assert covered >= bound, (covered, np.bincount(stages))
    assert within_tolerance >= covered


def test_cli_rtol(capsys):
    from symsphere.apps.cli import main

    assert main(["integrate", "--integrand", "exp", "--rtol", "1e-4", "--seed", "1"]) == 0
    out = capsys.readouterr().out
    assert "tolerance" in out and "reached: half-width" in out and "stages" in out
    assert main(["integrate", "--integrand", "exp", "--atol", "1e-9", "--n-max", "24576", "--seed", "1"]) == 0
    assert "NOT reached (n_max)" in capsys.readouterr().out


@pytest.mark.parametrize(
    "argv, message",
    [
        ([], "--n is required unless --rtol or --atol is given"),
        (["--n", "480", "--n-max", "960"], "--n-max is only valid with --rtol or --atol"),
        (["--rtol", "-1"], "'--rtol' must be >= 0"),
        (["--rtol", "1e-300"], "'--rtol'=1e-300 is below what float64 resolves"),
    ],
)
def test_cli_tolerance_errors(capsys, argv, message):
    from symsphere.apps.cli import main

    assert main(["integrate", "--integrand", "exp", *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
