"""The projected-solid-angle map of a spherical triangle (square_to_projected_triangle): its contract.

As tests/warps/test_contract.py for the registered warps, on triangles wholly above the horizon (the
pole n inside or outside), cut by it, nearly a hemisphere, small and sliver-thin: finite unit
directions inside the triangle and above the horizon for the square's corners and edges (float64 and
float32); forward and inverse are inverses both ways; the pdf is the inverse Jacobian (central
differences); E (hence the pdf's integral) against an independent quadrature of cos over the flat
triangle; numba's compilation of the scalar formula against the same formula run by Python; and a
chi-square test against cells whose probabilities come from that quadrature, not from the map.

Statistical tests: family significance 0.01 over the CHI2_TESTS chi-square tests of this file, Sidak-corrected;
fixed seeds.
"""

import math

import numpy as np
import pytest
from numba import njit
from scipy import stats as scipy_stats

from symsphere.warps import (
    projected_solid_angle,
    projected_triangle_point,
    projected_triangle_setup,
    projected_triangle_to_square,
    projected_triangle_uv,
    square_to_projected_triangle,
    square_to_projected_triangle_pdf,
)


def _unit(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def _small(size, centre=(0.3, 0.2, 0.9)):
    c = _unit(centre)
    t = _unit(np.cross(c, [0.0, 0.0, 1.0]))
    b = np.cross(c, t)
    return [_unit(c + size * t), _unit(c + size * (-0.5 * t + 0.8 * b)), _unit(c + size * (-0.5 * t - 0.8 * b))]


Z = [0.0, 0.0, 1.0]
CASES = {
    "above_pole_outside": ([[1, 0, 0.2], [0, 1, 0.2], [0.6, 0.7, 1.0]], Z),
    "above_pole_inside": ([[1, 0, 0.5], [-0.5, 0.9, 0.5], [-0.5, -0.9, 0.5]], Z),
    "tilted_normal": ([[1, 0, 0.2], [0, 1, 0.2], [0.3, 0.3, 1.0]], [0.3, -0.2, 0.9]),
    "straddling_one_below": ([[1, 0, 0.3], [0, 1, 0.4], [0.5, 0.5, -0.6]], Z),
    "straddling_two_below": ([[1, 0, -0.3], [0, 1, -0.4], [0.5, 0.5, 0.6]], Z),
    "straddling_pole_inside": ([[1, 0, -0.2], [-0.5, 0.9, 0.6], [-0.5, -0.9, 0.3]], Z),
    "large_close_wall": ([[-2, -1, 0.15], [2, -1, 0.15], [0, 3, 0.15]], [0.0, 0.3, -1.0]),
    "small_1e-6sr": (_small(1e-3), Z),
    "sliver": ([[1, 0, 0.2], [0, 1, 0.2], [0.5, 0.5, 0.2 + 1e-4]], Z),
}
CASES = {name: ([_unit(v) for v in tri], _unit(n)) for name, (tri, n) in CASES.items()}
SIGNIFICANCE = 0.01
# with the numpy references of tests/mitsuba/test_projected.py: one worker compiles the map's kernels
pytestmark = pytest.mark.xdist_group("projected_triangle")
CHI2_TESTS = len(CASES)
N_CHI2 = 200_000
EDGE_VALUES = (0.0, 1e-300, 1e-17, 1e-8, 0.5, 1 - 1e-8, 1 - 1e-16, 1.0)
EDGE_UV = np.array([[a, b] for a in EDGE_VALUES for b in EDGE_VALUES])


def _flat_quadrature(a, b, c, f, cells=48, order=8):
    """The integral of f(d) d(omega) over the spherical triangle abc, from the flat triangle
    a + s (b - a) + s t (c - b) (Duffy), composite Gauss-Legendre on cells x cells squares."""
    x, w = np.polynomial.legendre.leggauss(order)
    edges = np.arange(cells + 1) / cells
    nodes = ((edges[:-1, None] + edges[1:, None]) / 2 + (x[None, :] / 2) / cells).ravel()
    weights = np.tile(w / 2 / cells, cells)
    s, t = np.meshgrid(nodes, nodes, indexing="ij")
    ws = np.outer(weights, weights)
    p = a + s[..., None] * (b - a) + (s * t)[..., None] * (c - b)
    r = np.linalg.norm(p, axis=-1)
    normal = np.cross(b - a, c - b)
    jac = s * np.abs(p @ normal) / r**3
    return float(np.sum(f(p / r[..., None]) * jac * ws))


def _cos(n):
    return lambda d: np.maximum(d @ n, 0.0)


def _inside(d, tri):
    a, b, c = tri
    orient = np.sign(a @ np.cross(b, c))
    ok = np.ones(d.shape[:-1], dtype=bool)
    for p, q in ((a, b), (b, c), (c, a)):
        m = np.cross(p, q)
        ok &= orient * (d @ m) / np.linalg.norm(m) >= -1e-10
    return ok


def _triangle_points(tri, n, count, seed):
    """Directions in the triangle above the horizon, from the flat triangle (not from the map)."""
    a, b, c = tri
    st = np.random.default_rng(seed).random((count, 2))
    st = np.where(st.sum(axis=1, keepdims=True) > 1, 1 - st, st)
    p = a + st[:, :1] * (b - a) + st[:, 1:] * (c - a)
    d = p / np.linalg.norm(p, axis=1, keepdims=True)
    return d[d @ n > 1e-3]


@pytest.mark.parametrize("name", list(CASES))
def test_projected_solid_angle_against_quadrature(name):
    tri, n = CASES[name]
    reference = _flat_quadrature(*tri, _cos(n))
    # straddling triangles: the kink of max(0, cos) at the horizon limits the quadrature to ~1e-6
    smooth = all(v @ n >= 0 for v in tri)
    assert projected_solid_angle(*tri, n) == pytest.approx(reference, rel=1e-10 if smooth else 2e-5)


def test_known_values():
    x, y, z = np.eye(3)
    assert projected_solid_angle(x, y, z, z) == pytest.approx(math.pi / 4, rel=1e-15)  # an octant
    assert projected_solid_angle(x, y, -z, z) == 0.0  # below the horizon
    assert projected_solid_angle(x, y, z, -z) == 0.0
    # the octant seen about a normal in its edge plane x = 0: half of it above the horizon
    assert projected_solid_angle(x, y, z, [-1, 0, 0]) == 0.0
    assert square_to_projected_triangle_pdf([[0, 0, 1], [0, 0, -1]], x, y, z, z) * math.pi / 4 == pytest.approx([1, 0])


@pytest.mark.parametrize("name", list(CASES))
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_edges_finite_unit_inside(name, dtype):
    tri, n = CASES[name]
    uv = np.concatenate([np.random.default_rng(1).random((20_000, 2)), EDGE_UV]).astype(dtype)
    d = square_to_projected_triangle(uv, *tri, n)
    assert d.dtype == dtype and np.all(np.isfinite(d))
    np.testing.assert_allclose(np.linalg.norm(d.astype(np.float64), axis=1), 1, atol=4 * np.finfo(dtype).eps)
    # float64 inside; float32 output is the float64 map's, rounded
    np.testing.assert_array_equal(d, square_to_projected_triangle(uv.astype(np.float64), *tri, n).astype(dtype))
    if dtype == np.float64:
        assert np.all(d @ n >= -1e-15) and np.all(_inside(d, tri))
        assert np.all(square_to_projected_triangle_pdf(d[:20_000], *tri, n) >= 0)
    back = projected_triangle_to_square(d, *tri, n)
    assert back.dtype == dtype and np.all(np.isfinite(back)) and np.all((back >= 0) & (back <= 1))
    pdf = square_to_projected_triangle_pdf(d, *tri, n)
    assert np.all(np.isfinite(pdf)) and np.all(pdf >= 0)


@pytest.mark.parametrize("name", list(CASES))
def test_round_trip(name):
    tri, n = CASES[name]
    small = name.startswith(("small", "sliver"))
    uv = 1e-3 + (1 - 2e-3) * np.random.default_rng(2).random((20_000, 2))
    back = projected_triangle_to_square(square_to_projected_triangle(uv, *tri, n), *tri, n)
    np.testing.assert_allclose(back, uv, rtol=0, atol=1e-8 if small else 1e-11)
    d = _triangle_points(tri, n, 20_000, seed=3)
    again = square_to_projected_triangle(projected_triangle_to_square(d, *tri, n), *tri, n)
    # u carries an absolute error of eps E; where phi's density (r_hi^2 - r_lo^2) / 2 is small (near a
    # vertex) that is a larger error in phi: measured 2e-11 for the nearly-hemisphere triangle, 6e-10 for
    # the sliver (whose width, 1e-4, divides it)
    np.testing.assert_allclose(again, d, rtol=0, atol=1e-8 if small else 1e-10)


@pytest.mark.parametrize("name", [name for name in CASES if name != "small_1e-6sr"])
def test_pdf_is_inverse_jacobian(name):
    tri, n = CASES[name]
    uv = 0.01 + 0.98 * np.random.default_rng(4).random((2000, 2))
    h = 1e-6

    def f(x):
        return square_to_projected_triangle(x, *tri, n)

    fu = (f(uv + [h, 0]) - f(uv - [h, 0])) / (2 * h)
    fv = (f(uv + [0, h]) - f(uv - [0, h])) / (2 * h)
    jac = np.linalg.norm(np.cross(fu, fv), axis=-1)
    # the sliver: its Jacobian is of the sliver's width (1e-4) and the differences lose 4 more digits
    rtol = 1e-3 if name == "sliver" else 1e-5
    np.testing.assert_allclose(square_to_projected_triangle_pdf(f(uv), *tri, n) * jac, 1.0, rtol=rtol)


def test_pdf_is_cosine_over_e():
    tri, n = CASES["straddling_pole_inside"]
    d = _triangle_points(tri, n, 1000, seed=5)
    e = _flat_quadrature(*tri, _cos(n))
    np.testing.assert_allclose(square_to_projected_triangle_pdf(d, *tri, n), d @ n / e, rtol=2e-5)
    outside = -d
    assert np.all(square_to_projected_triangle_pdf(outside, *tri, n) == 0)


def test_numba_matches_python():
    # The scalar formulas compiled by numba (libm) against the same formulas run by Python (math): the same
    # operations; a step of the root finder may end one rounding apart, so 1e-13 in direction.
    tri, n = CASES["straddling_pole_inside"]
    s = projected_triangle_setup(np.array(tri), n)

    @njit
    def points(uv, s):
        out = np.empty((uv.shape[0], 3))
        for i in range(uv.shape[0]):
            x, y, z, _ = projected_triangle_point(uv[i, 0], uv[i, 1], s)
            out[i, 0], out[i, 1], out[i, 2] = x, y, z
        return out

    uv = np.random.default_rng(6).random((200, 2))
    python = np.array([projected_triangle_point(u, v, s)[:3] for u, v in uv])
    np.testing.assert_allclose(points(uv, s), python, rtol=0, atol=1e-13)
    back = np.array([projected_triangle_uv(*p, s) for p in python])
    np.testing.assert_allclose(back, uv, rtol=0, atol=1e-11)


def _fan(tri, n, per_edge=12):
    """Cells of the triangle: a fan of geodesic sub-triangles about its centroid (as the Arvo tests)."""
    a, b, c = tri
    o = _unit(a + b + c)
    t = np.arange(per_edge)[:, None] / per_edge
    ring = np.concatenate([(1 - t) * p + t * q for p, q in ((a, b), (b, c), (c, a))])
    ring /= np.linalg.norm(ring, axis=1, keepdims=True)
    return [(o, ring[k], ring[(k + 1) % len(ring)]) for k in range(len(ring))]


def _cell_index(d, cells):
    index = np.full(len(d), -1)
    for k, (a, b, c) in enumerate(cells):
        orient = np.sign(a @ np.cross(b, c))
        inside = np.ones(len(d), dtype=bool)
        for p, q in ((a, b), (b, c), (c, a)):
            inside &= orient * (d @ np.cross(p, q)) >= 0
        index[(index < 0) & inside] = k
    return index


@pytest.mark.parametrize("name", list(CASES))
def test_chi2_against_quadrature_cells(name):
    tri, n = CASES[name]
    seed = 30 + list(CASES).index(name)
    d = square_to_projected_triangle(np.random.default_rng(seed).random((N_CHI2, 2)), *tri, n)
    cells = _fan(tri, n)
    index = _cell_index(d, cells)
    assert np.all(index >= 0)
    counts = np.bincount(index, minlength=len(cells))
    probs = np.array([_flat_quadrature(*cell, _cos(n), cells=16) for cell in cells])
    probs /= probs.sum()
    keep = probs > 0
    assert counts[~keep].sum() == 0  # nothing below the horizon
    expected, observed = probs[keep] * N_CHI2, counts[keep]
    small = expected < 5
    if small.any():
        expected = np.append(expected[~small], expected[small].sum())
        observed = np.append(observed[~small], observed[small].sum())
    assert len(expected) > 10
    result = scipy_stats.chisquare(observed, expected)
    assert result.pvalue >= 1 - (1 - SIGNIFICANCE) ** (1 / CHI2_TESTS), result


def test_chi2_detects_solid_angle_sampling():
    # the power of the test above: uniform solid-angle sampling (the cosine left out) is rejected
    from symsphere.warps import square_to_spherical_triangle

    tri, n = CASES["straddling_pole_inside"]
    d = square_to_spherical_triangle(np.random.default_rng(40).random((N_CHI2, 2)), *tri)
    d = d[d @ n > 0]
    cells = _fan(tri, n)
    counts = np.bincount(_cell_index(d, cells), minlength=len(cells))
    probs = np.array([_flat_quadrature(*cell, _cos(n), cells=16) for cell in cells])
    keep = probs > 0
    assert scipy_stats.chisquare(counts[keep], probs[keep] / probs.sum() * len(d)).pvalue < 1e-10


@pytest.mark.parametrize(
    "call, word",
    [
        (lambda: square_to_projected_triangle([0.5, 0.5], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, 0]), "'n'"),
        (lambda: square_to_projected_triangle([0.5, 0.5], [1, 0, 0], [1, 0, 0], [0, 0, 1], [0, 0, 1]), "'a', 'b'"),
        (lambda: square_to_projected_triangle([0.5, 0.5], [1, 0, -1], [0, 1, -1], [0, 0, -1], [0, 0, 1]), "horizon"),
        (lambda: projected_triangle_to_square([0, 0, 1], [1, 0, -1], [0, 1, -1], [0, 0, -1], [0, 0, 1]), "'n'"),
        (lambda: square_to_projected_triangle([1.5, 0.5], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, 1]), "'uv'"),
    ],
)
def test_bad_input(call, word):
    with pytest.raises(ValueError, match=word):
        call()
