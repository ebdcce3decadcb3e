"""Arvo's map onto a spherical triangle (square_to_spherical_triangle), and on T0 (square_to_arvo_triangle).

Statistical tests: three of the family of CHI2_TESTS = 11 chi-square (and two-sample) tests that
tests/test_peers.py holds the other eight of, at family significance 0.01, Sidak-corrected over all 11:
the chance that any of them fails for correct maps is 1%.  The reference density is
``symsphere.stats.uniform_pdf`` (independent of the maps).

Arvo's map on adversarial spherical triangles: 1e-7 sr to 2 pi - 1e-3 sr, slivers, near-collinear vertices.

The reference is independent of the map: each triangle is cut into a fan of 60 geodesic sub-triangles
about its centroid, whose solid angles come from Van Oosterom & Strackee's formula here; a sample falls
into the sub-triangle whose three edge planes it is inside.  Pearson's chi-square over those cells, one test per
triangle, at family significance 0.01, Sidak-corrected over the ROBUST_CHI2_TESTS triangles; fixed seeds.
"""

import math

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


ROBUST_N_CHI2 = 200_000
PER_EDGE = 20  # 60 cells


def _unit(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def _small(size):
    c = _unit([0.3, 0.2, 0.9])
    t = _unit(np.cross(c, [0.0, 0.0, 1.0]))
    b = np.cross(c, t)
    return [_unit(c + size * t), _unit(c + size * (-0.5 * t + 0.8 * b)), _unit(c + size * (-0.5 * t - 0.8 * b))]


def _sliver(height, middle_second=False):
    a, b = _unit([1.0, 0.0, 0.2]), _unit([0.0, 1.0, 0.2])
    m = _unit((a + b) / 2 + height * np.array([0.0, 0.0, 1.0]))
    return [a, m, b] if middle_second else [a, b, m]


def _large(z):  # three vertices 120 degrees apart just above the equator: nearly a hemisphere
    return [_unit([math.cos(p), math.sin(p), z]) for p in (0.0, 2 * math.pi / 3, 4 * math.pi / 3)]


TRIANGLES = {
    "small_1e-7sr": _small(4.5e-4),  # 2.4e-7 sr
    "small_1e-8sr": _small(1e-4),
    "sliver_1e-5": _sliver(1e-5),
    "sliver_1e-7": _sliver(1e-7),  # 1.1e-7 sr, width 1e-7 rad
    "sliver_1e-7_middle_b": _sliver(1e-7, middle_second=True),
    "needle": [_unit([1, 0, 0]), _unit([-0.2, 1, 0]), _unit([-0.2, 1, 1e-6])],
    "large_5.3sr": _large(0.1),
    "large_2pi-1e-3": _large(3e-4),  # 6.280 sr = 2 pi - 3e-3 ... see test_solid_angles
    "large_2pi-1e-4": _large(3e-5),
}
ROBUST_CHI2_TESTS = len(TRIANGLES)
ROBUST_EDGE_VALUES = (0.0, 1e-300, 1e-17, 1e-8, 0.5, 1 - 1e-8, 1 - 1e-16, 1.0)
ROBUST_EDGE_UV = np.array([[a, b] for a in ROBUST_EDGE_VALUES for b in ROBUST_EDGE_VALUES])


def _solid_angle(a, b, c):
    # Van Oosterom & Strackee (1983), with vectors of any length
    la, lb, lc = (np.linalg.norm(x, axis=-1) for x in (a, b, c))
    triple = np.abs(np.sum(a * np.cross(b, c), axis=-1))
    den = la * lb * lc + np.sum(a * b, -1) * lc + np.sum(a * c, -1) * lb + np.sum(b * c, -1) * la
    return 2 * np.arctan2(triple, den)


def test_solid_angles():
    areas = {name: float(_solid_angle(*(np.array(v) for v in tri))) for name, tri in TRIANGLES.items()}
    assert areas["small_1e-7sr"] == pytest.approx(2.4e-7, rel=0.05)
    assert areas["sliver_1e-7"] == pytest.approx(1.08e-7, rel=0.05)
    assert 2 * math.pi - 1e-2 < areas["large_2pi-1e-3"] < 2 * math.pi - 1e-3
    assert 2 * math.pi - 1e-3 < areas["large_2pi-1e-4"] < 2 * math.pi - 1e-4


def _sub_triangles(tri, per_edge):
    """A fan of 3 per_edge geodesic triangles about the normalised centroid o: (o, e_k, e_k+1) for the
    normalised points e_k of the planar triangle's edges, which lie on the spherical triangle's edges.
    A spherical triangle is convex, so the fan tiles it (a nearly-hemisphere one evenly, o at its pole)."""
    a, b, c = tri
    o = _unit(a + b + c)
    t = np.arange(per_edge)[:, None] / per_edge
    ring = np.concatenate([(1 - t) * p + t * q for p, q in ((a, b), (b, c), (c, a))])
    ring /= np.linalg.norm(ring, axis=1, keepdims=True)
    return np.array([(o, ring[k], ring[(k + 1) % len(ring)]) for k in range(len(ring))])


def _cells(d, cells, chunk=8192):
    """Index of the first cell (a geodesic triangle) that holds each direction; -1 for none.

    Every cell's three edge normals, oriented inward by the cell's orientation, are one matrix per edge, so
    that a chunk of directions meets all cells in three products (the same sides, cell by cell, as
    ``orient * (d @ n) >= 0``; a pass over all directions per cell and edge took 2.5x the CPU time)."""
    orient = np.array([np.sign(a @ np.cross(b, c)) for a, b, c in cells])
    normals = np.stack([orient[:, None] * np.cross(cells[:, i], cells[:, j]) for i, j in ((0, 1), (1, 2), (2, 0))])
    index = np.full(len(d), -1)
    for lo in range(0, len(d), chunk):
        block = d[lo : lo + chunk]
        inside = (block @ normals[0].T >= 0) & (block @ normals[1].T >= 0) & (block @ normals[2].T >= 0)
        index[lo : lo + chunk] = np.where(inside.any(axis=1), inside.argmax(axis=1), -1)
    return index


@pytest.mark.parametrize("name", list(TRIANGLES))
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_finite_unit_and_inside(name, dtype):
    tri = TRIANGLES[name]
    uv = np.concatenate([np.random.default_rng(1).random((20_000, 2)), ROBUST_EDGE_UV]).astype(dtype)
    d = square_to_spherical_triangle(uv, *tri)
    assert d.dtype == dtype and np.all(np.isfinite(d))
    np.testing.assert_allclose(np.linalg.norm(d.astype(np.float64), axis=1), 1, atol=4 * np.finfo(dtype).eps)
    # The map runs in float64 whatever the dtype; float32 output is the float64 map's, rounded.
    np.testing.assert_array_equal(d, square_to_spherical_triangle(uv.astype(np.float64), *tri).astype(dtype))
    if dtype == np.float64:  # in float32 a rounded direction may leave a triangle narrower than its ulp
        assert np.all(square_to_spherical_triangle_pdf(d[:20_000], *tri) > 0)
        a, b, c = (np.asarray(v) for v in tri)
        orient = np.sign(a @ np.cross(b, c))
        for p, q in ((a, b), (b, c), (c, a)):  # the edges' images: on the edge to rounding
            n = np.cross(p, q)
            assert np.all(orient * (d @ n) / np.linalg.norm(n) >= -1e-11)
    back = spherical_triangle_to_square(d, *tri)
    assert np.all(np.isfinite(back)) and np.all((back >= 0) & (back <= 1))


@pytest.mark.parametrize("name", list(TRIANGLES))
def test_round_trip(name):
    # Measured: <= 3e-13 for the large triangles, 6e-8 for the 1e-7 sr slivers, 5e-5 in v for the sliver
    # whose arcs start at its near-straight vertex (two tiny distances' ratio).  The forward map is the
    # accurate one (checked against 40-digit arithmetic while writing this test).
    tri = TRIANGLES[name]
    uv = 1e-3 + (1 - 2e-3) * np.random.default_rng(2).random((20_000, 2))
    atol = 1e-4 if name.startswith(("sliver", "small")) else 1e-11
    np.testing.assert_allclose(
        spherical_triangle_to_square(square_to_spherical_triangle(uv, *tri), *tri), uv, atol=atol
    )


@pytest.mark.parametrize("name", ["large_5.3sr", "large_2pi-1e-3", "needle", "sliver_1e-5"])
def test_pdf_is_inverse_jacobian(name):
    tri = TRIANGLES[name]
    uv = 0.01 + 0.98 * np.random.default_rng(3).random((500, 2))
    h = 1e-6
    f = lambda x: square_to_spherical_triangle(x, *tri)  # noqa: E731
    fu = (f(uv + [h, 0]) - f(uv - [h, 0])) / (2 * h)
    fv = (f(uv + [0, h]) - f(uv - [0, h])) / (2 * h)
    jac = np.linalg.norm(np.cross(fu, fv), axis=-1)
    np.testing.assert_allclose(square_to_spherical_triangle_pdf(f(uv), *tri) * jac, 1.0, rtol=1e-5)


@pytest.mark.parametrize("name", list(TRIANGLES))
def test_chi2_against_sub_triangles(name):
    tri = [np.asarray(v) for v in TRIANGLES[name]]
    d = square_to_spherical_triangle(
        np.random.default_rng(10 + list(TRIANGLES).index(name)).random((ROBUST_N_CHI2, 2)), *tri
    )
    cells = _sub_triangles(tri, PER_EDGE)
    index = _cells(d, cells)
    assert np.all(index >= 0)
    counts = np.bincount(index, minlength=len(cells))
    probs = np.array([_solid_angle(*cell) for cell in cells])
    probs /= probs.sum()
    keep = probs > 0
    expected, observed = probs[keep] * ROBUST_N_CHI2, counts[keep]
    small = expected < 5  # near a nearly-hemisphere triangle's vertices: pooled into one cell
    if small.any():
        expected = np.append(expected[~small], expected[small].sum())
        observed = np.append(observed[~small], observed[small].sum())
    assert expected.min() > 5 and len(expected) > 40
    result = scipy_stats.chisquare(observed, expected)
    threshold = 1 - (1 - SIGNIFICANCE) ** (1 / ROBUST_CHI2_TESTS)
    assert result.pvalue >= threshold, result
