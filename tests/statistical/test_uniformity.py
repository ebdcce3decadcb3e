"""Chi-square tests of the samplers against independent reference densities.

Every test here uses significance 0.01 with a Sidak correction over the
CHI2_TESTS tests of this file that must pass, so the chance that any one fails
for a correct sampler is 1%.  Bins are equal-area in (phi, cos theta), and the
reference densities are ``symsphere.stats.uniform_pdf`` (an inequality test on
T0, constants on the sphere and hemisphere), independent of the maps.

The 48 (24) directions of one orbit are dependent, which a chi-square test does
not allow for; the sphere and hemisphere tests therefore take one member per
orbit, chosen at random independently of the base point.  Those are independent
and have the scheme's marginal density, which is what ``sphere_pdf`` states.
"""

import numpy as np
import pytest
from references import assert_power

from symsphere import (
    METHODS,
    fold,
    sample_hemisphere,
    sample_sphere,
    sphere_pdf,
    square_to_triangle,
    square_to_triangle_pdf,
)
from symsphere.stats import chi2_test, one_per_orbit, uniform_pdf

SIGNIFICANCE = 0.01
# equal_area on T0 (4 point sets) + sphere + hemisphere (2) + paper maps on T0 (2) + sphere pdfs (3) + quick
CHI2_TESTS = 4 + 1 + 2 + 2 + 3 + 1
N_BASE = 512**2  # a square (stratified) and a power of 2 (Sobol)
N_T0 = N_BASE  # the paper maps on T0 (independent points): the target's power, at a third of 10^6 points' CPU time
N_ORBITS = 400_000
# What the tests that must pass must also detect, with probability >= 99 % at their Sidak-corrected level:
# an alternative of Cohen's effect size w = 0.04 over the default bins (tests/references.py), e.g. a density
# 4 % too high on half the domain and 4 % too low on the other half, or 12 % too high on a tenth.  The
# default bins grow with n (2079 cells for 512^2 points, 3872 for 400 000), so the smallest w detected at
# 99 % power falls only as n^(-1/4): N_BASE = 512^2 detects w >= 0.038, N_ORBITS w >= 0.036 (sized to the
# target), N_T0 = N_BASE too (the paper maps against their own pdf).  _check asserts the power for each test.
MUST_DETECT_W = 0.04


def _check(result, w=MUST_DETECT_W):
    assert result.passed, str(result)
    assert_power(result, w)


@pytest.mark.slow
@pytest.mark.parametrize("points", ["random", "stratified", "sobol", "halton"])
def test_equal_area_uniform_on_t0(points):
    d = sample_sphere(48 * N_BASE, points=points, rng=11)
    base = fold(d[::48])[1]
    _check(chi2_test(base, uniform_pdf("triangle"), "triangle", significance=SIGNIFICANCE, test_count=CHI2_TESTS))


@pytest.mark.slow
def test_equal_area_uniform_on_sphere():
    d = one_per_orbit(sample_sphere(48 * N_ORBITS, rng=12), 48, rng=13)
    _check(chi2_test(d, uniform_pdf("sphere"), "sphere", significance=SIGNIFICANCE, test_count=CHI2_TESTS))


@pytest.mark.slow
def test_equal_area_uniform_on_hemisphere():
    d = one_per_orbit(sample_hemisphere(24 * N_ORBITS, rng=14), 24, rng=15)
    _check(chi2_test(d, uniform_pdf("hemisphere"), "hemisphere", significance=SIGNIFICANCE, test_count=CHI2_TESTS))


@pytest.mark.slow
def test_equal_area_uniform_on_hemisphere_about_a_normal():
    normal = np.array([0.48, -0.6, 0.64])
    d = one_per_orbit(sample_hemisphere(24 * N_ORBITS, normal=normal, rng=16), 24, rng=17)
    # rotate back with an independent frame (Gram-Schmidt), then test on the z-hemisphere
    n = normal / np.linalg.norm(normal)
    t = np.cross(n, [1.0, 0.0, 0.0])
    t /= np.linalg.norm(t)
    local = d @ np.stack([t, np.cross(n, t), n]).T
    _check(chi2_test(local, uniform_pdf("hemisphere"), "hemisphere", significance=SIGNIFICANCE, test_count=CHI2_TESTS))


@pytest.mark.slow
@pytest.mark.parametrize("method", ["paper1", "paper2"])
def test_paper_maps_match_their_own_pdf(method):
    uv = np.random.default_rng(18).random((N_T0, 2))
    p = square_to_triangle(uv, method)
    _check(
        chi2_test(
            p, lambda q: square_to_triangle_pdf(q, method), "triangle", significance=SIGNIFICANCE, test_count=CHI2_TESTS
        )
    )


@pytest.mark.slow
@pytest.mark.parametrize("method", ["paper1", "paper2"])
def test_paper_maps_are_not_uniform(method):
    # The paper claims uniformity; the same test that passes equal_area rejects them.
    uv = np.random.default_rng(19).random((N_T0, 2))
    result = chi2_test(
        square_to_triangle(uv, method),
        uniform_pdf("triangle"),
        "triangle",
        significance=SIGNIFICANCE,
        test_count=CHI2_TESTS,
    )
    assert not result.passed
    assert result.p_value < 1e-100


@pytest.mark.slow
@pytest.mark.parametrize("method", METHODS)
def test_sphere_scheme_matches_sphere_pdf(method):
    d = one_per_orbit(sample_sphere(48 * N_ORBITS, method=method, rng=20), 48, rng=21)
    _check(chi2_test(d, lambda q: sphere_pdf(q, method), "sphere", significance=SIGNIFICANCE, test_count=CHI2_TESTS))


def test_quick_equal_area_on_t0():
    # A fast version of the T0 test for the default (not slow) run: 10^5 points (774 cells) detect w >= 0.05
    # with 99 % power (a density 5 % off on either half of T0); the slow tests detect MUST_DETECT_W.
    uv = np.random.default_rng(22).random((100_000, 2))
    _check(
        chi2_test(
            square_to_triangle(uv),
            uniform_pdf("triangle"),
            "triangle",
            significance=SIGNIFICANCE,
            test_count=CHI2_TESTS,
        ),
        w=0.05,
    )
