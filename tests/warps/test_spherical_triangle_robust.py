"""Arvo's map on adversarial spherical triangles: 1e-7 sr to 2 pi - 1e-3 sr, slivers, near-collinear vertices.

The reference is independent of the map: each triangle is cut into a fan of 60 geodesic sub-triangles
about its centroid, whose solid angles come from Van Oosterom & Strackee's formula here; a sample falls
into the sub-triangle whose three edge planes it is inside.  Pearson's chi-square over those cells, one test per
triangle, at family significance 0.01, Sidak-corrected over the CHI2_TESTS triangles; fixed seeds.
"""

import math

import numpy as np
import pytest
from scipy import stats as scipy_stats

from symsphere.warps import (
    spherical_triangle_to_square,
    square_to_spherical_triangle,
    square_to_spherical_triangle_pdf,
)

SIGNIFICANCE = 0.01
N_CHI2 = 200_000
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
CHI2_TESTS = len(TRIANGLES)
EDGE_VALUES = (0.0, 1e-300, 1e-17, 1e-8, 0.5, 1 - 1e-8, 1 - 1e-16, 1.0)
EDGE_UV = np.array([[a, b] for a in EDGE_VALUES for b in EDGE_VALUES])


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


def _cells(d, cells):
    """Index of the first cell (a geodesic triangle) that holds each direction; -1 for none."""
    index = np.full(len(d), -1)
    for k, (a, b, c) in enumerate(cells):
        orient = np.sign(a @ np.cross(b, c))
        inside = np.ones(len(d), dtype=bool)
        for p, q in ((a, b), (b, c), (c, a)):
            inside &= orient * (d @ np.cross(p, q)) >= 0
        index[(index < 0) & inside] = k
    return index


@pytest.mark.parametrize("name", list(TRIANGLES))
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_finite_unit_and_inside(name, dtype):
    tri = TRIANGLES[name]
    uv = np.concatenate([np.random.default_rng(1).random((20_000, 2)), EDGE_UV]).astype(dtype)
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
    d = square_to_spherical_triangle(np.random.default_rng(10 + list(TRIANGLES).index(name)).random((N_CHI2, 2)), *tri)
    cells = _sub_triangles(tri, PER_EDGE)
    index = _cells(d, cells)
    assert np.all(index >= 0)
    counts = np.bincount(index, minlength=len(cells))
    probs = np.array([_solid_angle(*cell) for cell in cells])
    probs /= probs.sum()
    keep = probs > 0
    expected, observed = probs[keep] * N_CHI2, counts[keep]
    small = expected < 5  # near a nearly-hemisphere triangle's vertices: pooled into one cell
    if small.any():
        expected = np.append(expected[~small], expected[small].sum())
        observed = np.append(observed[~small], observed[small].sum())
    assert expected.min() > 5 and len(expected) > 40
    result = scipy_stats.chisquare(observed, expected)
    threshold = 1 - (1 - SIGNIFICANCE) ** (1 / CHI2_TESTS)
    assert result.pvalue >= threshold, result
