"""Tests of symsphere.stats, the chi-square harness.

Every sampler and density here is an independent reference: samplers are
built from numpy normals / uniforms (normalised Gaussians, rejection, Malley's
method, inversion of a closed-form CDF) and densities are written in closed
form.  The bins and the per-bin integrals (against antiderivatives) are tested
in tests/test_bins.py.

Statistical tests: each chi-square test that is expected to pass uses
significance SIGNIFICANCE = 0.01 with test_count = TEST_COUNT, the number of
such tests in this file (slow ones included), so with the Sidak correction the
chance that any of them fails for a correct sampler is 1 %.  Seeds are fixed,
so the outcome is deterministic.  The tests expected to reject use the same
level and also require a tiny p-value.
"""

from __future__ import annotations

import dataclasses
import doctest
import math

import numpy as np
import pytest
from references import cosine_pdf, in_t0, linear_triangle_pdf, pole_pdf
from scipy import stats as scipy_stats

from symsphere import stats
from symsphere.bins import bin_probabilities, equal_area_bins
from symsphere.stats import (
    Chi2Result,
    chi2_test,
    uniform_pdf,
)

SIGNIFICANCE = 0.01
TEST_COUNT = 10  # chi-square tests expected to pass, in this file (incl. slow)
LEVEL = dict(significance=SIGNIFICANCE, test_count=TEST_COUNT)
INV_SQRT3 = 1.0 / math.sqrt(3.0)


# ---------------------------------------------------------------------------
# Reference samplers and densities
# ---------------------------------------------------------------------------


def uniform_sphere(n, seed, dtype=np.float64):
    g = np.random.default_rng(seed).standard_normal((n, 3))
    return (g / np.linalg.norm(g, axis=1, keepdims=True)).astype(dtype)


def uniform_hemisphere(n, seed):
    d = uniform_sphere(n, seed)
    d[:, 2] = np.abs(d[:, 2])
    return d


def uniform_triangle_rejection(n, seed):
    """Uniform on T0 by rejection from the uniform sphere (acceptance 1/48)."""
    rng = np.random.default_rng(seed)
    kept, total = [], 0
    while total < n:
        g = rng.standard_normal((1_000_000, 3))
        g /= np.linalg.norm(g, axis=1, keepdims=True)
        g = g[in_t0(g)]
        kept.append(g)
        total += len(g)
    return np.concatenate(kept)[:n]


def uniform_triangle_fold(n, seed):
    """Uniform on T0 by folding the uniform sphere: z = max, x = mid, y = min of |g|."""
    a = np.sort(np.abs(uniform_sphere(n, seed)), axis=1)
    return a[:, [1, 0, 2]]


def cosine_hemisphere_malley(n, seed):
    """Malley's method: uniform point on the unit disk, lifted to the hemisphere."""
    rng = np.random.default_rng(seed)
    u1, u2 = rng.random(n), rng.random(n)
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    z = np.sqrt(np.maximum(1 - r * r, 0))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def pole_sampler(n, seed):
    """phi ~ U[0, pi/4], then x/z = tan(theta) cos(phi) ~ U[0, 1]: lies in T0."""
    rng = np.random.default_rng(seed)
    phi = rng.random(n) * (np.pi / 4)
    v = rng.random(n)
    theta = np.arctan(v / np.cos(phi))
    s = np.sin(theta)
    return np.stack([s * np.cos(phi), s * np.sin(phi), np.cos(theta)], axis=1)


def cap_sampler(n, seed):
    """Uniform on the cap z >= 1/2."""
    rng = np.random.default_rng(seed)
    z = 0.5 + 0.5 * rng.random(n)
    phi = 2 * np.pi * rng.random(n)
    s = np.sqrt(1 - z * z)
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=1)


def cap_pdf(d):
    return np.where(d[:, 2] >= 0.5, 1 / np.pi, 0.0)


# The lower boundary of T0 in cos theta (tests/test_bins.py has the per-bin integrals).
# ---------------------------------------------------------------------------
# Chi-square tests expected to pass (TEST_COUNT of them, incl. slow)
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_uniform_sphere_passes(dtype):  # 2 of TEST_COUNT
    d = uniform_sphere(200_000, seed=1, dtype=dtype)
    res = chi2_test(d, uniform_pdf("sphere"), "sphere", **LEVEL)
    assert res.passed, str(res)
    assert res.observed.shape == (60, 30)  # r = isqrt(200000 // 200) = 31, made even
    assert res.observed.sum() == len(d)
    assert res.threshold == pytest.approx(1 - (1 - SIGNIFICANCE) ** (1 / TEST_COUNT))


def test_uniform_hemisphere_passes():  # 3
    res = chi2_test(uniform_hemisphere(200_000, seed=2), uniform_pdf("hemisphere"), "hemisphere", **LEVEL)
    assert res.passed, str(res)


def test_uniform_triangle_rejection_passes():  # 4
    d = uniform_triangle_rejection(100_000, seed=3)
    res = chi2_test(d, uniform_pdf("triangle"), "triangle", **LEVEL)
    assert res.passed, str(res)
    assert res.observed.shape == (31, 31)
    # Bins entirely below the boundary have expected count exactly 0 and no samples.
    assert np.any(res.expected == 0)
    assert res.observed[res.expected == 0].sum() == 0


def test_cosine_hemisphere_malley_passes():  # 5
    res = chi2_test(cosine_hemisphere_malley(200_000, seed=4), cosine_pdf, "hemisphere", **LEVEL)
    assert res.passed, str(res)


def test_pole_density_on_triangle_passes():  # 6
    d = pole_sampler(200_000, seed=5)
    assert np.all(in_t0(d) | (np.abs(d[:, 2] - d[:, 0]) < 1e-15))
    res = chi2_test(d, pole_pdf, "triangle", **LEVEL)
    assert res.passed, str(res)


def test_cosine_pooling_passes_and_pools():  # 7
    # Few samples on a fine grid: the bins near the horizon have expected < 5.
    n = 3000
    res = chi2_test(cosine_hemisphere_malley(n, seed=6), cosine_pdf, "hemisphere", bins=(16, 8), **LEVEL)
    assert res.passed, str(res)
    e, o = res.expected.ravel(), res.observed.ravel().astype(float)
    small = e < 5
    assert small.sum() >= 2 and e[small].sum() >= 5  # one pooled cell suffices
    stat = np.sum((o[~small] - e[~small]) ** 2 / e[~small])
    stat += (o[small].sum() - e[small].sum()) ** 2 / e[small].sum()
    assert res.statistic == pytest.approx(stat, rel=1e-12)
    assert res.dof == (~small).sum() + 1 - 1
    assert res.p_value == pytest.approx(scipy_stats.chi2.sf(stat, res.dof), rel=1e-12)
    assert "pooled" in res.message
    large = e >= 5
    ratio = o[large] / e[large]
    assert res.ratio_range == pytest.approx((ratio.min(), ratio.max()))


def test_cap_density_with_zero_bins_passes():  # 8
    # cos edges 0, .25, .5, .75, 1: the two lower rows have expected count exactly 0.
    res = chi2_test(cap_sampler(20_000, seed=7), cap_pdf, "hemisphere", bins=(8, 4), **LEVEL)
    assert res.passed, str(res)
    assert np.all(res.expected[:, :2] == 0)
    assert res.dof == 8 * 2 - 1


@pytest.mark.slow
def test_large_uniform_triangle_fold_passes():  # 9
    # 4e6 samples on the 64 x 64 grid (~1000 per bin): sensitive to expected-count errors.
    d = uniform_triangle_fold(4_000_000, seed=8)
    res = chi2_test(d, uniform_pdf("triangle"), "triangle", **LEVEL)
    assert res.observed.shape == (64, 64)
    assert res.passed, str(res)


@pytest.mark.slow
def test_large_pole_density_passes():  # 10
    res = chi2_test(pole_sampler(4_000_000, seed=9), pole_pdf, "triangle", **LEVEL)
    assert res.passed, str(res)


# ---------------------------------------------------------------------------
# Chi-square tests expected to reject
# ---------------------------------------------------------------------------


def test_stretched_gaussian_fails():
    g = np.random.default_rng(10).standard_normal((100_000, 3))
    g[:, 0] *= 1.2
    d = g / np.linalg.norm(g, axis=1, keepdims=True)
    res = chi2_test(d, uniform_pdf("sphere"), **LEVEL)
    assert not res.passed
    assert res.p_value < 1e-10
    assert "rejected" in res.message and "FAILED" in str(res)


def test_quadratic_cos_sampler_fails():
    rng = np.random.default_rng(11)
    u, phi = rng.random(100_000), 2 * np.pi * rng.random(100_000)
    z = 1 - 2 * u**2
    s = np.sqrt(1 - z * z)
    d = np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=1)
    res = chi2_test(d, uniform_pdf("sphere"), **LEVEL)
    assert not res.passed and res.p_value < 1e-10


def test_uniform_hemisphere_rejected_by_cosine_pdf():
    res = chi2_test(uniform_hemisphere(50_000, seed=12), cosine_pdf, "hemisphere", **LEVEL)
    assert not res.passed and res.p_value < 1e-10


def test_pole_sampler_rejected_by_uniform_triangle():
    res = chi2_test(pole_sampler(50_000, seed=13), uniform_pdf("triangle"), "triangle", **LEVEL)
    assert not res.passed and res.p_value < 1e-10


def test_uniform_triangle_rejected_by_linear_pdf():
    # A mild deviation: the linear density varies only by a factor sqrt 3 over T0.
    res = chi2_test(uniform_triangle_fold(200_000, seed=14), linear_triangle_pdf, "triangle", **LEVEL)
    assert not res.passed and res.p_value < 1e-10


# ---------------------------------------------------------------------------
# Quadrature accuracy as the test sees it (tests/test_bins.py: per-bin accuracy)
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("domain", ["sphere", "hemisphere", "triangle"])
@pytest.mark.parametrize("bins", [(8, 4), (7, 5), (64, 64)])
def test_uniform_integral_is_one(domain, bins):
    # res.integral is the sum of bin_probabilities over these bins (tests/test_bins.py checks that function itself)
    res = chi2_test(
        uniform_sphere(1000, 0)
        if domain == "sphere"
        else uniform_hemisphere(1000, 0)
        if domain == "hemisphere"
        else uniform_triangle_fold(1000, 0),
        uniform_pdf(domain),
        domain,
        bins=bins,
    )
    assert abs(res.integral - 1) < 1e-6
    assert abs(res.expected.sum() - 1000) < 1e-6 * 1000


# ---------------------------------------------------------------------------
# Binning and edges
# ---------------------------------------------------------------------------


def test_bin_assignment_at_phi_pi_and_poles():
    d = np.array(
        [
            [-1.0, 0.0, 0.0],  # phi = +pi  -> wrapped to -pi: phi bin 0
            [-1.0, -0.0, 0.0],  # phi = -pi: phi bin 0
            [0.0, 0.0, 1.0],  # cos = 1 exactly: last cos bin
            [0.0, 0.0, -1.0],  # cos = -1: first cos bin
            [1.0, 0.0, 0.0],  # phi = 0: bin 2 of 4
        ]
    )
    res = chi2_test(d, uniform_pdf("sphere"), bins=(4, 2))
    expected_counts = np.zeros((4, 2), dtype=int)
    expected_counts[0, 1] = 2
    expected_counts[2, 1] = 2
    expected_counts[2, 0] = 1
    np.testing.assert_array_equal(res.observed, expected_counts)


def test_triangle_vertices_are_inside():
    v = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [1.0, 1.0, 1.0]])
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    res = chi2_test(v, uniform_pdf("triangle"), "triangle", bins=(4, 4))
    assert "outside" not in res.message
    obs = np.zeros((4, 4), dtype=int)
    obs[0, 3] = 1  # pole: phi = 0, cos = 1
    obs[3, 0] = 1  # (1,1,1)/sqrt 3: phi = pi/4, cos = 1/sqrt 3
    obs[0, int((1 / math.sqrt(2) - INV_SQRT3) / (1 - INV_SQRT3) * 4)] += 1
    np.testing.assert_array_equal(res.observed, obs)


def test_default_bins():
    assert chi2_test(uniform_sphere(100, 0), uniform_pdf("sphere")).observed.shape == (8, 4)
    res = chi2_test(uniform_sphere(2_000_000, 0, np.float32), uniform_pdf("sphere"))
    assert res.observed.shape == (128, 64)


# ---------------------------------------------------------------------------
# Failing samplers: outside the domain, not unit, zero-probability bins, bad pdf
# ---------------------------------------------------------------------------


def test_sample_below_hemisphere_fails():
    d = uniform_hemisphere(10_000, seed=15)
    d[17] = [0.6, 0.0, -0.8]
    res = chi2_test(d, uniform_pdf("hemisphere"), "hemisphere")
    assert not res.passed and res.p_value == 0 and res.statistic == math.inf
    assert "outside the hemisphere" in res.message and "sample 17" in res.message
    assert res.observed.sum() == len(d) - 1


def test_sample_in_rectangle_but_outside_triangle_fails():
    d = uniform_triangle_fold(10_000, seed=16)
    phi, c = 0.1, 0.6  # cmax(0.1) = 0.705 > 0.6: inside the rectangle, below T0
    s = math.sqrt(1 - c * c)
    d[3] = [s * math.cos(phi), s * math.sin(phi), c]
    res = chi2_test(d, uniform_pdf("triangle"), "triangle")
    assert not res.passed and res.p_value == 0
    assert "outside the triangle" in res.message


def test_sample_outside_triangle_rectangle_fails():
    d = uniform_triangle_fold(10_000, seed=17)
    d[0] = [0.0, 0.0, -1.0]
    res = chi2_test(d, uniform_pdf("triangle"), "triangle")
    assert not res.passed and res.p_value == 0 and "outside" in res.message


def test_non_unit_sample_fails():
    d = uniform_sphere(10_000, seed=18)
    d[5] *= 2
    res = chi2_test(d, uniform_pdf("sphere"))
    assert not res.passed and res.p_value == 0 and "not unit vectors" in res.message


def test_sample_in_zero_probability_bin_fails():
    # Uniform hemisphere samples against a pdf supported on the cap z >= 1/2.
    res = chi2_test(uniform_hemisphere(10_000, seed=19), cap_pdf, "hemisphere", bins=(8, 4))
    assert not res.passed and res.p_value == 0
    assert "integrates to 0" in res.message


def test_unnormalised_pdf_fails():
    d = uniform_sphere(10_000, seed=20)
    res = chi2_test(d, lambda x: np.full(len(x), 1.002 / (4 * np.pi)))
    assert not res.passed
    assert res.integral == pytest.approx(1.002, rel=1e-12)
    assert "integrates to" in res.message
    # Within tolerance it is accepted (the samples are uniform).
    res = chi2_test(d, lambda x: np.full(len(x), 1.0005 / (4 * np.pi)), **LEVEL)
    assert "integrates" not in res.message


def test_too_few_cells_fails():
    res = chi2_test(uniform_sphere(3, 0), uniform_pdf("sphere"), bins=(2, 1))
    assert not res.passed and math.isnan(res.p_value) and "nothing to test" in res.message


# ---------------------------------------------------------------------------
# Sidak correction and result object
# ---------------------------------------------------------------------------


def _two_bin_samples(n, k):
    """n samples on the equator, k with y < 0 (phi bin 0 of 2), n - k with y > 0."""
    d = np.zeros((n, 3))
    d[:k] = [0.0, -1.0, 0.0]
    d[k:] = [0.0, 1.0, 0.0]
    return d


def test_sidak_threshold_decides():
    # Two bins of expected 500: statistic (2k - n)^2 / n = 8.1, dof 1, p = 0.0044.
    d = _two_bin_samples(1000, 545)
    one = chi2_test(d, uniform_pdf("sphere"), bins=(2, 1), significance=0.01)
    ten = chi2_test(d, uniform_pdf("sphere"), bins=(2, 1), significance=0.01, test_count=10)
    assert one.statistic == pytest.approx(8.1, rel=1e-12) and one.dof == 1
    assert one.p_value == pytest.approx(scipy_stats.chi2.sf(8.1, 1), rel=1e-12)
    assert 0.001 < one.p_value < 0.01
    assert one.threshold == pytest.approx(0.01, rel=1e-14)
    assert ten.threshold == pytest.approx(1 - 0.99 ** (1 / 10), rel=1e-12)
    assert not one.passed
    assert ten.passed, str(ten)


def test_result_is_frozen_and_printable():
    res = chi2_test(uniform_sphere(20_000, 21), uniform_pdf("sphere"), **LEVEL)
    with pytest.raises(dataclasses.FrozenInstanceError):
        res.passed = False
    with pytest.raises(ValueError):
        res.observed[0, 0] = 1
    text = str(res)
    assert "sphere" in text and ("PASSED" if res.passed else "FAILED") in text
    assert res.message in text
    assert isinstance(res, Chi2Result)


def test_docstring_examples():
    failures, attempted = doctest.testmod(stats, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert attempted > 10 and failures == 0


# ---------------------------------------------------------------------------
# Argument validation
# ---------------------------------------------------------------------------

GOOD = uniform_sphere(100, 0)


@pytest.mark.parametrize(
    "kwargs,exc,match",
    [
        (
            dict(domain="torus"),
            ValueError,
            r"'torus' is not a valid domain; use one of \{'sphere', 'hemisphere', 'triangle'\}",
        ),
        (dict(bins=(0, 4)), ValueError, "'bins'"),
        (dict(bins=(4, -1)), ValueError, "'bins'"),
        (dict(bins=(4.5, 4)), TypeError, "'bins'"),
        (dict(bins=(True, 4)), TypeError, "'bins'"),
        (dict(bins=5), TypeError, "'bins'"),
        (dict(bins=(1, 2, 3)), ValueError, "'bins'"),
        (dict(samples=np.zeros((10, 2))), ValueError, "'samples'"),
        (dict(samples=np.zeros(3)), ValueError, "'samples'"),
        (dict(samples=np.zeros((0, 3))), ValueError, "'samples'"),
        (dict(samples=np.full((4, 3), np.nan)), ValueError, "'samples'"),
        (dict(samples="abc"), TypeError, "'samples'"),
        (dict(samples=GOOD.astype(np.float16)), TypeError, "'samples'"),
        (dict(pdf=0.25), TypeError, "'pdf'"),
        (dict(significance=0.0), ValueError, "'significance'"),
        (dict(significance=1.0), ValueError, "'significance'"),
        (dict(significance=1.5), ValueError, "'significance'"),
        (dict(significance=float("nan")), ValueError, "'significance'"),
        (dict(significance="0.01"), TypeError, "'significance'"),
        (dict(test_count=0), ValueError, "'test_count'"),
        (dict(test_count=2.0), TypeError, "'test_count'"),
        (dict(min_expected=0), ValueError, "'min_expected'"),
        (dict(quadrature_order=0), ValueError, "'quadrature_order'"),
        (dict(pdf=lambda d: np.ones((len(d), 2))), ValueError, "'pdf' must return shape"),
        (dict(pdf=lambda d: np.full(len(d), np.nan)), ValueError, "'pdf' returned non-finite"),
        (dict(pdf=lambda d: -np.ones(len(d))), ValueError, "'pdf' returned negative"),
    ],
)
def test_bad_arguments(kwargs, exc, match):
    args = dict(samples=GOOD, pdf=uniform_pdf("sphere"))
    args.update(kwargs)
    with pytest.raises(exc, match=match):
        chi2_test(args.pop("samples"), args.pop("pdf"), **args)


def test_bad_arguments_of_helpers():
    with pytest.raises(ValueError, match="'bins'"):
        equal_area_bins("sphere", (0, 1))
    with pytest.raises(ValueError, match="not a valid domain"):
        uniform_pdf("cube")
    with pytest.raises(TypeError, match="'pdf'"):
        bin_probabilities(None, "sphere", (4, 2))


def test_uniform_pdf_values():
    d = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, -0.8], [0.3, 0.2, 0.9], [0.2, 0.3, 0.9]])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    np.testing.assert_allclose(uniform_pdf("sphere")(d), 1 / (4 * np.pi))
    np.testing.assert_allclose(uniform_pdf("hemisphere")(d), [1 / (2 * np.pi), 0, 1 / (2 * np.pi), 1 / (2 * np.pi)])
    np.testing.assert_allclose(uniform_pdf("triangle")(d), [12 / np.pi, 0, 12 / np.pi, 0])


def test_one_per_orbit_picks_a_member_of_each_orbit():
    from symsphere import fold, sample_sphere
    from symsphere.stats import one_per_orbit

    d = sample_sphere(48 * 2000, rng=3)
    picked = one_per_orbit(d, 48, rng=4)
    assert picked.shape == (2000, 3)
    orbits = d.reshape(2000, 48, 3)
    member = np.argmax(np.all(orbits == picked[:, None, :], axis=-1), axis=1)
    assert np.all(np.all(orbits[np.arange(2000), member] == picked, axis=-1))
    assert set(member.tolist()) == set(range(48))  # every member is chosen somewhere
    assert np.array_equal(fold(picked)[1], fold(d[::48])[1])
    assert np.array_equal(picked, one_per_orbit(d, 48, rng=4))


@pytest.mark.parametrize(
    "args, error, match",
    [
        ((np.zeros((96, 3)), 47), ValueError, "'orbit_size' must be 48"),
        ((np.zeros((50, 3)), 48), ValueError, r"'directions' must have shape \(m \* 48, 3\)"),
        ((np.zeros((48, 2)), 48), ValueError, "'directions' must have shape"),
        ((np.zeros((48, 3)), True), ValueError, "'orbit_size'"),
    ],
)
def test_one_per_orbit_bad_input(args, error, match):
    from symsphere.stats import one_per_orbit

    with pytest.raises(error, match=match):
        one_per_orbit(*args)
