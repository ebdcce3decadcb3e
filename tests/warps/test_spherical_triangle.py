"""Arvo's map onto a spherical triangle (square_to_spherical_triangle), and on T0 (square_to_arvo_triangle).

Statistical tests: three of the family of CHI2_TESTS = 11 chi-square (and two-sample) tests that
tests/test_peers.py holds the other eight of, at family significance 0.01, Sidak-corrected over all 11:
the chance that any of them fails for correct maps is 1%.  The reference density is
``symsphere.stats.uniform_pdf`` (independent of the maps).
"""

import numpy as np
import pytest
from references import assert_power
from scipy import stats as scipy_stats

import symsphere as ss
from symsphere.stats import chi2_test, uniform_pdf
from symsphere.warps import (
    T0_VERTICES,
    arvo_triangle_to_square,
    spherical_triangle_to_square,
    square_to_arvo_triangle,
    square_to_arvo_triangle_pdf,
    square_to_spherical_triangle,
    square_to_spherical_triangle_pdf,
)

SIGNIFICANCE = 0.01
CHI2_TESTS = 11  # the family shared with tests/test_peers.py (see the module docstring)
N_CHI2 = 50_000
MUST_DETECT_W = 0.06  # as tests/test_peers.py: a wrong formula or convention
EDGE_VALUES = (0.0, 1e-300, 1e-17, 0.5, 1 - 1e-16, 1.0)
EDGE_UV = np.array([[a, b] for a in EDGE_VALUES for b in EDGE_VALUES])
# A generic (obtuse, large) triangle for Arvo's general algorithm.
TRIANGLE = np.array([[0.1, -0.3, 0.95], [0.9, 0.4, -0.2], [-0.6, 0.7, 0.3]])
TRIANGLE = TRIANGLE / np.linalg.norm(TRIANGLE, axis=1, keepdims=True)


def _interior_uv(n, seed=0, margin=1e-3):
    return margin + (1 - 2 * margin) * np.random.default_rng(seed).random((n, 2))


def _check(result, w=MUST_DETECT_W):
    assert result.passed, str(result)
    assert_power(result, w)


def test_corners():
    A, B, C = T0_VERTICES
    np.testing.assert_allclose(square_to_spherical_triangle([[0.3, 0], [0, 1], [1, 1]], A, B, C), [B, A, C], atol=1e-15)


def test_vertices_are_normalised_to_1_ulp_on_every_machine():
    # The vertices are normalised IEEE-only (correctly rounded squares, an exactly rounded sum, sqrt, the
    # division), not with numpy's norm, whose BLAS dot product differs by CPU (with and without FMA).
    # The reference is exact (mpmath, 50 digits); bound: four roundings of <= 0.5 ulp each, <= 2 ulps of
    # the vertex's largest component (1.5 eps relative to it).  The image of v = 0 is B as normalised.
    mpmath = pytest.importorskip("mpmath")
    mpmath.mp.dps = 50
    rng = np.random.default_rng(11)
    A, _, C = T0_VERTICES
    vectors = [v for v in rng.normal(size=(300, 3)) if abs(v @ np.cross(A, C)) > 0.1]  # not on the arc AC
    vectors += [np.array([1e-160, 3e-161, 2e-160]), np.array([1e200, 3e199, 5e199])]  # scaled before squaring
    for b in vectors:
        norm = mpmath.sqrt(mpmath.fsum(mpmath.mpf(float(x)) ** 2 for x in b))
        exact = np.array([float(mpmath.mpf(float(x)) / norm) for x in b])
        got = square_to_spherical_triangle([0.3, 0.0], A, b, C)
        np.testing.assert_allclose(got, exact, rtol=0, atol=1.5 * np.finfo(np.float64).eps * np.max(np.abs(exact)))
    # T0's vertices are unit to rounding (3**-0.5 (1, 1, 1)'s norm rounds to 1): normalised, they stay as they are,
    # which is why the next test can ask for the same bits.
    A, B, C = T0_VERTICES
    for a, b, c in ((B, A, C), (A, B, C), (A, C, B)):
        np.testing.assert_array_equal(square_to_spherical_triangle([0.3, 0.0], a, b, c), b)


def test_arvo_triangle_is_the_general_map_on_t0():
    uv = np.concatenate([_interior_uv(10_000, seed=1), EDGE_UV])
    np.testing.assert_array_equal(square_to_arvo_triangle(uv), square_to_spherical_triangle(uv, *T0_VERTICES))
    d = square_to_arvo_triangle(uv)
    np.testing.assert_array_equal(arvo_triangle_to_square(d), spherical_triangle_to_square(d, *T0_VERTICES))
    np.testing.assert_array_equal(square_to_arvo_triangle_pdf(d), square_to_spherical_triangle_pdf(d, *T0_VERTICES))


def test_round_trip_general_triangle():
    uv = _interior_uv(50_000, seed=3)
    p = square_to_spherical_triangle(uv, *TRIANGLE)
    assert np.all(square_to_spherical_triangle_pdf(p, *TRIANGLE) > 0)
    np.testing.assert_allclose(spherical_triangle_to_square(p, *TRIANGLE), uv, rtol=0, atol=1e-12)


def _jacobian(forward, uv, h=1e-6):
    du, dv = np.array([h, 0.0]), np.array([0.0, h])
    fu = (forward(uv + du) - forward(uv - du)) / (2 * h)
    fv = (forward(uv + dv) - forward(uv - dv)) / (2 * h)
    return np.linalg.norm(np.cross(fu, fv), axis=-1)


def test_pdf_is_inverse_jacobian_general_triangle():
    # pdf = 1 / |dF/du x dF/dv| by central differences: an independent check of the map's algebra.
    def forward(uv):
        return square_to_spherical_triangle(uv, *TRIANGLE)

    uv = _interior_uv(2000, seed=4)
    pdf = square_to_spherical_triangle_pdf(forward(uv), *TRIANGLE)
    np.testing.assert_allclose(pdf * _jacobian(forward, uv), 1.0, rtol=2e-7)


def test_triangle_pdf_matches_girard():
    # 1/pdf = area = angle excess (Girard), from the angles between the edge planes.
    for tri in (T0_VERTICES, TRIANGLE):
        A, B, C = tri
        angles = []
        for p, q, r in ((A, B, C), (B, C, A), (C, A, B)):
            n1, n2 = np.cross(p, q), np.cross(p, r)
            angles.append(np.arccos(n1 @ n2 / np.linalg.norm(n1) / np.linalg.norm(n2)))
        centroid = (A + B + C) / np.linalg.norm(A + B + C)
        assert 1 / square_to_spherical_triangle_pdf(centroid, *tri) == pytest.approx(sum(angles) - np.pi, rel=1e-13)
        assert square_to_spherical_triangle_pdf(-centroid, *tri) == 0
    assert square_to_spherical_triangle_pdf([0.3, 0.2, 0.9], *T0_VERTICES) == pytest.approx(12 / np.pi, rel=1e-14)


# --- Arvo versus equal_area -----------------------------------------------------


def test_arvo_relabelled_is_equal_area_pointwise():
    # With B = (0, 0, 1) as the vertex the arcs start from (Arvo's vertices (B, A, C) of
    # T0), Arvo's sub-triangle of area u pi/12 is T0's part with azimuth below phi and
    # the arc from the pole is sampled uniformly in cos(theta): exactly equal_area.
    A, B, C = T0_VERTICES
    uv = np.concatenate([np.random.default_rng(6).random((100_000, 2)), EDGE_UV])
    np.testing.assert_allclose(square_to_spherical_triangle(uv, B, A, C), ss.square_to_triangle(uv), rtol=0, atol=1e-12)


def test_arvo_as_labelled_is_a_different_map():
    # With A = (0, 0, 1) (the labelling of the sampler `arvo`) the arcs start from
    # (1, 0, 1)/sqrt 2: the same distribution (tested below), a different map.
    uv = _interior_uv(10_000, seed=7)
    diff = np.linalg.norm(square_to_spherical_triangle(uv, *T0_VERTICES) - ss.square_to_triangle(uv), axis=1)
    assert diff.max() > 0.5 and np.median(diff) > 0.05


def test_chi2_arvo_on_t0():
    p = square_to_spherical_triangle(np.random.default_rng(8).random((N_CHI2, 2)), *T0_VERTICES)
    _check(chi2_test(p, uniform_pdf("triangle"), "triangle", significance=SIGNIFICANCE, test_count=CHI2_TESTS))


def test_chi2_equal_area_on_t0():
    p = ss.square_to_triangle(np.random.default_rng(9).random((N_CHI2, 2)))
    _check(chi2_test(p, uniform_pdf("triangle"), "triangle", significance=SIGNIFICANCE, test_count=CHI2_TESTS))


def test_arvo_and_equal_area_same_histogram():
    # Two-sample chi-square (homogeneity) on the (phi, cos theta) histogram of T0's bounding rectangle.
    rng = np.random.default_rng(10)
    arvo = square_to_spherical_triangle(rng.random((N_CHI2, 2)), *T0_VERTICES)
    equal = ss.square_to_triangle(rng.random((N_CHI2, 2)))
    edges = (np.linspace(0, np.pi / 4, 11), np.linspace(1 / np.sqrt(3), 1, 11))
    counts = [np.histogram2d(np.arctan2(p[:, 1], p[:, 0]), p[:, 2], bins=edges)[0].ravel() for p in (arvo, equal)]
    table = np.array(counts)
    table = table[:, table.sum(axis=0) > 0]
    result = scipy_stats.chi2_contingency(table)
    threshold = 1 - (1 - SIGNIFICANCE) ** (1 / CHI2_TESTS)
    assert result.pvalue >= threshold, result


@pytest.mark.parametrize(
    "call, error, word",
    [
        (lambda: square_to_spherical_triangle([0.1, 0.2], [0, 0, 1], [0, 0, 2], [1, 0, 0]), ValueError, "'a'"),
        (lambda: square_to_spherical_triangle([0.1, 0.2], [0, 0, 1], [0, 0, 0], [1, 0, 0]), ValueError, "'b'"),
        (lambda: square_to_spherical_triangle_pdf([0, 0, 1], [0, 0, 1], [1, 0, 0], [1, 2]), ValueError, "'c'"),
        (lambda: spherical_triangle_to_square([0.0, 0.0, 0.0], *T0_VERTICES), ValueError, "'d'"),
        (lambda: square_to_arvo_triangle([0.5, 2.0]), ValueError, "'uv'"),
        (lambda: arvo_triangle_to_square([0.0, 0.0, 2.0]), ValueError, "'d'"),
    ],
)
def test_bad_input(call, error, word):
    with pytest.raises(error, match=word):
        call()
