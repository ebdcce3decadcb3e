"""The integrator: closed forms within the interval, honest error bars, bounded memory, bad input."""

import warnings

import numpy as np
import pytest
from scipy.stats import qmc

import symsphere
from symsphere import METHODS, integrate
from symsphere.points import BLOCK

A = np.array([0.7, -0.4, 0.5])
# Closed-form checks use 99.9% intervals: with ~15 such tests at fixed seeds, a correct
# estimator fails one of them with probability ~1.5%.
LEVEL = 0.999


def exp_dot(w):
    return np.exp(w @ A)


EXP_DOT_SPHERE = 4 * np.pi * np.sinh(np.linalg.norm(A)) / np.linalg.norm(A)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("points", ["random", "stratified", "sobol", "halton"])
def test_closed_form_within_interval(method, points):
    n = 48 * 8 * 32**2 if points == "stratified" else 48 * 2**13
    result = integrate(exp_dot, n=n, method=method, points=points, rng=3, confidence_level=LEVEL)
    low, high = result.confidence_interval
    assert low <= EXP_DOT_SPHERE <= high, str(result)
    assert result.n_evaluations == n
    assert result.unit == ("orbit" if points == "random" else "replicate")


def test_hemisphere_irradiance_about_a_normal():
    # A uniform unit radiance over the hemisphere about n gives irradiance pi.
    normal = np.array([0.3, -0.9, 0.2])
    unit = normal / np.linalg.norm(normal)
    result = integrate(
        lambda w: np.maximum(w @ unit, 0.0),
        domain="hemisphere",
        normal=normal,
        n=24 * 2**12,
        rng=4,
        confidence_level=LEVEL,
    )
    low, high = result.confidence_interval
    assert low <= np.pi <= high


def test_vector_valued_integrand():
    f = lambda w: np.stack([w[:, 0] ** 2, np.ones(len(w)), exp_dot(w)], axis=1)  # noqa: E731
    result = integrate(f, n=48 * 2**12, rng=5)
    assert result.integral.shape == (3,)
    np.testing.assert_allclose(result.integral[:2], [4 * np.pi / 3, 4 * np.pi], rtol=1e-12)  # orbit-exact
    assert abs(result.integral[2] - EXP_DOT_SPHERE) < 4 * result.standard_error[2]


def test_orbit_average_is_exact_for_non_invariant_harmonics():
    # x^2 averages to 1/3 over every orbit: zero variance, exact to rounding.
    result = integrate(lambda w: w[:, 0] ** 2 + w[:, 1] * w[:, 2] ** 3, n=48 * 100, rng=6)
    assert result.integral == pytest.approx(4 * np.pi / 3, rel=1e-14)
    assert result.standard_error < 1e-13


def test_same_seed_same_result_and_memory_bounded():
    sizes = []

    def spy(w):
        sizes.append(len(w))
        return exp_dot(w)

    a = integrate(spy, n=48 * (2 * BLOCK + 5), rng=7)
    assert max(sizes) == 48 * BLOCK and sum(sizes) == 48 * (2 * BLOCK + 5)
    b = integrate(exp_dot, n=48 * (2 * BLOCK + 5), rng=7)
    assert a.integral == b.integral and a.standard_error == b.standard_error


def test_qmc_engine_gives_estimate_without_error():
    result = integrate(exp_dot, n=48 * 256, points=qmc.Sobol(d=2, scramble=True, rng=1))
    assert result.unit == "run" and np.isnan(result.standard_error)
    assert result.integral == pytest.approx(EXP_DOT_SPHERE, rel=1e-4)


COVERAGE_SEEDS = 1000


@pytest.mark.slow
@pytest.mark.parametrize(
    "points, method, n",
    [
        ("random", "equal_area", 48 * 64),
        ("random", "paper1", 48 * 64),
        ("stratified", "equal_area", 48 * 8 * 16),
        ("sobol", "equal_area", 48 * 8 * 16),
        ("halton", "paper2", 48 * 8 * 16),
    ],
)
def test_standard_error_is_honest(points, method, n):
    # Over 1000 seeds the 95% interval must cover the truth 92-98% of the time.  For a correct
    # interval the count is Binomial(1000, 0.95): 920 and 980 are 4.4 standard deviations away,
    # so this test fails a correct estimator with probability ~1e-5, and a 90% or 99% one surely.
    f = lambda w: np.exp(2 * w @ A) + (w[:, 2] > 0.3)  # noqa: E731 - smooth plus a discontinuous cap
    exact = 4 * np.pi * np.sinh(2 * np.linalg.norm(A)) / (2 * np.linalg.norm(A)) + 2 * np.pi * 0.7
    covered = 0
    for seed in range(COVERAGE_SEEDS):
        low, high = integrate(f, n=n, method=method, points=points, rng=seed).confidence_interval
        covered += low <= exact <= high
    assert 0.92 <= covered / COVERAGE_SEEDS <= 0.98, covered


@pytest.mark.parametrize(
    "kwargs, error, match",
    [
        ({"f": 3}, TypeError, "'f' must be callable"),
        ({"f": lambda w: w[:5]}, ValueError, r"'f' must return shape \(m,\) or \(m, k\)"),
        ({"f": lambda w: np.ones(3)}, ValueError, "'f' must return shape"),
        ({"f": lambda w: np.full(len(w), np.nan)}, ValueError, "'f' returned non-finite values"),
        ({"domain": "disk"}, ValueError, "'disk' is not a valid domain"),
        ({"n": 100}, ValueError, r"'n'=100 is not a multiple of 48"),
        ({"n": 48, "points": "sobol"}, ValueError, r"'n'=48 is not a multiple of 384"),
        ({"replicates": 4}, ValueError, "'replicates' must be None or 1 with points='random'"),
        ({"points": "sobol", "replicates": 0}, ValueError, "'replicates' must be positive"),
        ({"normal": [0, 0, 1]}, ValueError, "'normal' is only valid with domain='hemisphere'"),
        ({"confidence_level": 1.5}, ValueError, "'confidence_level' must be in"),
        ({"method": "arvo"}, ValueError, "'arvo' is not a valid method"),
        ({"rng": "seed"}, TypeError, "'rng' must be None"),
    ],
)
def test_bad_input(kwargs, error, match):
    kwargs = {"f": exp_dot, "n": 48 * 8, **kwargs}
    with pytest.raises(error, match=match):
        integrate(**kwargs)


def test_module_is_not_named_after_the_function():
    """``symsphere.integrate`` is the function; the module is ``symsphere.integration``."""
    import importlib
    import importlib.util
    import types

    import symsphere
    import symsphere.integration as module

    assert isinstance(module, types.ModuleType) and module.integrate is symsphere.integrate
    assert callable(symsphere.integrate) and not isinstance(symsphere.integrate, types.ModuleType)
    assert importlib.util.find_spec("symsphere.integrate") is None
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("symsphere.integrate")


def test_sobol_balance_warning_once_at_the_callers_line():
    """scipy's balance warning (n not a power of 2) is issued once, attributed to this file."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        integrate(lambda d: d[:, 2] ** 2, n=48 * 3 * 8, points="sobol", rng=1)
    balance = [w for w in caught if "balance" in str(w.message)]
    assert len(balance) == 1
    assert balance[0].filename == __file__


# --- f of shape (m, 0) ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("options", [dict(n=96), dict(atol=1e-2)])
def test_integrate_rejects_empty_components(options):
    with pytest.raises(ValueError, match="'f' must return shape"):
        symsphere.integrate(lambda d: np.zeros((len(d), 0)), rng=1, **options)
