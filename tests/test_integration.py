"""The integrator: closed forms within the interval, honest error bars, bounded memory, bad input.

Hostile integrands and tolerances: one error naming f (and where), never inf, nan or a run to n_max.

Integration to a tolerance: doubling with reuse, the alpha-spending interval, its coverage.
"""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
from numba import njit
from references import one_line_error
from scipy import stats
from scipy.stats import qmc

import symsphere
from symsphere import METHODS, distributed, integrate
from symsphere.apps.cli import main
from symsphere.integrands import orbit_average
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


DIRECTION = r"\[-?[0-9.e-]+, -?[0-9.e-]+, -?[0-9.e-]+\]"


def huge(w):
    return np.full(len(w), 1e308)


@njit
def huge_compiled(x, y, z):
    return 1e308


@njit
def nan_right(x, y, z):
    return np.nan if x > 0.5 else 1.0


def raising(w):
    raise ZeroDivisionError("division by zero")


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(n=96, rng=1),
        dict(atol=1e-3, rng=1),
        dict(n=384, points="sobol", rng=1),
        dict(rtol=1e-3, method="auto", rng=1),
    ],
    ids=["fixed-n", "atol", "sobol", "auto"],
)
@pytest.mark.parametrize("f", [huge, huge_compiled], ids=["numpy", "compiled"])
def test_overflowing_sums_are_one_error_naming_f(f, kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no numpy RuntimeWarning, no "tolerance nan was not reached"
        with pytest.raises(ValueError, match=f"'f' returned .*overflows float64.*{DIRECTION}"):
            symsphere.integrate(f, **kwargs)


def test_huge_values_whose_sums_fit_are_integrated():
    result = symsphere.integrate(lambda w: np.full(len(w), 1e200), n=96, rng=1)
    assert result.integral == pytest.approx(4 * np.pi * 1e200, rel=1e-14)


@pytest.mark.parametrize("f", [lambda w: np.where(w[:, 0] > 0.5, np.nan, 1.0), nan_right], ids=["numpy", "compiled"])
def test_nan_names_f_and_the_first_offending_direction(f):
    with pytest.raises(ValueError, match=f"'f' returned non-finite values \\(nan at direction {DIRECTION}") as info:
        symsphere.integrate(f, n=48 * 64, rng=2)
    x = float(re.search(r"direction \[(-?[0-9.e-]+)", str(info.value)).group(1))
    assert x > 0.5  # the direction named is one where f is NaN


def test_raising_f_names_f_and_the_directions():
    with pytest.raises(ValueError, match=f"'f' raised ZeroDivisionError: division by zero .*first {DIRECTION}") as info:
        symsphere.integrate(raising, n=96, rng=1)
    assert isinstance(info.value.__cause__, ZeroDivisionError)


def test_wrong_shape_names_f_and_a_direction():
    with pytest.raises(ValueError, match=f"'f' must return shape .*{DIRECTION}"):
        symsphere.integrate(lambda w: np.ones(len(w) + 1), n=96, rng=1)


def test_orbit_average_of_values_near_the_largest_float_is_their_mean():
    # An orbit's mean of finite values is finite (each value divided first when the plain sum overflows),
    # with no RuntimeWarning; integrate, whose 4 pi x mean does overflow, names f (above).
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert orbit_average(huge, [0.3, 0.2, 0.9]) == pytest.approx(1e308)


@pytest.mark.xdist_group("dask")  # on the session's cluster, with the other cluster tests (Makefile: --dist loadgroup)
def test_distributed_integrate_overflow_names_f(dask_client):
    with pytest.raises(ValueError, match="'f' returned .*overflows float64"):
        distributed.integrate(huge, client=dask_client, n=96, rng=1)


@pytest.mark.parametrize("rtol", [1e-300, 1e-17, -1e-3])
def test_rtol_that_float64_cannot_resolve_is_refused(rtol):
    with pytest.raises(ValueError, match="'rtol'"):
        symsphere.integrate(huge, rtol=rtol, rng=1)


def test_tiny_atol_does_not_overflow_the_stage_prediction():
    with pytest.warns(UserWarning, match="the tolerance 1e-300 was not reached"):
        result = symsphere.integrate(lambda w: np.exp(w[:, 0]), atol=1e-300, n_max=48 * 2**10, rng=1)
    assert not result.converged


def test_cli_rtol_below_float64_is_one_line_naming_it(capsys):
    assert main(["integrate", "--integrand", "exp", "--seed", "1", "--rtol", "1e-300"]) == 2
    line = one_line_error(capsys.readouterr().err)
    assert "'--rtol'=1e-300" in line


@pytest.mark.parametrize("replicates, n", [(10**9, 48 * 1024), (4, 96)])
def test_too_many_replicates_for_n_names_replicates(replicates, n):
    # Each replicate needs one orbit of its own: the error names what cannot fit (it had named only n).
    with pytest.raises(ValueError, match=r"'replicates'=\d+ needs 'n' >= \d+"):
        symsphere.integrate(lambda w: w[:, 0], points="sobol", replicates=replicates, n=n)


EXACT = 4 * np.pi * np.sinh(np.linalg.norm(A)) / np.linalg.norm(A)


@njit
def exp_dot_xyz(x, y, z):
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
    result = integrate(exp_dot_xyz, atol=1e-5, points="stratified", rng=1)
    assert result.converged and result.tolerance == 1e-5
    orbits = result.n_evaluations // (48 * 8)
    assert orbits == (16 * 2 ** (result.n_stages - 1)) ** 2
    assert abs(result.integral - EXACT) < 1e-5


def test_hemisphere_and_fused_equal_numpy():
    kwargs = dict(domain="hemisphere", normal=[0, 0.6, 0.8], rtol=1e-3, rng=2)
    fused, numpy_path = integrate(exp_dot_xyz, **kwargs), integrate(exp_numpy, **kwargs)
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
        result = integrate(exp_dot_xyz, rtol=rtol, points=points, rng=seed)
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


# --- sizes whose partial sums cannot fit in memory: refused at once, naming the argument and the limit ---

GIB_MACHINE_MOST_N = 2**30 // 512 * 4096 * 48  # a 1 GiB machine: 2**21 block partials of ~512 bytes


@pytest.fixture
def one_gib_machine(monkeypatch):
    from symsphere._testing import validation

    monkeypatch.setattr(validation.values, "machine_memory", lambda: 2**30)


@pytest.mark.parametrize(
    "kwargs, named, most",
    [
        (dict(n=GIB_MACHINE_MOST_N + 48 * 4096), f"'n'={GIB_MACHINE_MOST_N + 48 * 4096}", GIB_MACHINE_MOST_N),
        (dict(n=48 * 10**13), "'n'=480000000000000", GIB_MACHINE_MOST_N),
        (dict(n=48 * 10**13, points="sobol"), "'n'=480000000000000", GIB_MACHINE_MOST_N),
        (dict(atol=1e-9, n_max=48 * 10**13), "'n_max'=480000000000000", GIB_MACHINE_MOST_N),
        (dict(n=48 * 2**22, points="sobol", replicates=2**22), "'replicates'=4194304", 2**21),
    ],
)  # fmt: skip
def test_sizes_beyond_memory_are_refused_naming_the_argument_and_the_limit(one_gib_machine, kwargs, named, most):
    # The partial sum of every block is held until the reduction: 48 * 10**13 evaluations would hold
    # 1.2 TB of them (the run had started, for years, without a word).
    with pytest.raises(ValueError) as caught:
        symsphere.integrate(lambda w: w[:, 0], rng=1, **kwargs)
    message = str(caught.value)
    assert message.startswith(f"{named} is too large for this machine's memory"), message
    assert f"at most {most} here" in message, message


def test_the_largest_n_that_fits_is_planned(one_gib_machine):
    from symsphere._testing import validation

    assert validation.memory_count_limit(512) == 2**21
    # What fits is accepted (its plan made; not run): the bound is memory, not a constant.
    with pytest.raises(ValueError, match="'f' raised ZeroDivisionError"):
        symsphere.integrate(lambda w: 1 / 0, n=GIB_MACHINE_MOST_N, rng=1)


def test_distributed_integrate_beyond_memory_names_n(one_gib_machine):
    with pytest.raises(ValueError, match="'n'=480000000000000 is too large for this machine's memory"):
        distributed.integrate(lambda w: w[:, 0], n=48 * 10**13, client=None)


def test_cli_integrate_beyond_memory_is_one_line_before_any_estimate(one_gib_machine, capsys):
    assert main(["integrate", "--integrand", "exp", "--n", str(48 * 10**13), "--allow-long"]) == 2
    line = one_line_error(capsys.readouterr().err)
    assert f"'--n'={48 * 10**13} is too large for this machine's memory" in line and "at most" in line
    assert main(["integrate", "--integrand", "exp", "--atol", "1e-9", "--n-max", str(48 * 10**13), "--allow-long"]) == 2
    assert "'--n-max'" in one_line_error(capsys.readouterr().err)
