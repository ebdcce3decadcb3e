"""Hostile integrands and tolerances: one error naming f (and where), never inf, nan or a run to n_max."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
from numba import njit
from references import one_line_error

import symsphere
from symsphere import distributed
from symsphere.apps.cli import main
from symsphere.integrands import orbit_average

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


def test_distributed_integrate_overflow_names_f():
    client = distributed.local_client(1)
    try:
        with pytest.raises(ValueError, match="'f' returned .*overflows float64"):
            distributed.integrate(huge, client=client, n=96, rng=1)
    finally:
        distributed.close_client(client)


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
