"""The scheme as a warp (square_to_sphere, square_to_hemisphere of symsphere.warps): pinned values, inverses, dtypes, corners, chi-square.

Statistical tests: significance 0.01 with a Sidak correction over CHI2_TESTS tests of this file that must
pass.  The references are independent of the warp: ``uniform_pdf`` (constants) for the directions, and
for the inverse a uniform histogram of the unit square; the input points and directions come from
numpy's generator (directions: normalised Gaussians), never from symsphere's samplers.
"""

import math

import numpy as np
import pytest
from scipy import stats as scipy_stats

import symsphere as ss
from symsphere import (
    HEMISPHERE_MAPS,
    METHODS,
    SPHERE_MAPS,
    hemisphere_to_square,
    sphere_to_square,
    square_to_hemisphere,
    square_to_hemisphere_pdf,
    square_to_sphere,
    square_to_sphere_pdf,
)
from symsphere.stats import chi2_test, uniform_pdf
from symsphere.warps import strip_order

SIGNIFICANCE = 0.01
CHI2_TESTS = 4  # sphere, hemisphere (directions), sphere, hemisphere (inverse onto the square)
N = 400_000

WARPS = [
    (square_to_sphere, square_to_sphere_pdf, sphere_to_square, SPHERE_MAPS, "sphere"),
    (square_to_hemisphere, square_to_hemisphere_pdf, hemisphere_to_square, HEMISPHERE_MAPS, "hemisphere"),
]


def _gaussian_directions(n, seed, hemisphere=False):
    d = np.random.default_rng(seed).standard_normal((n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    if hemisphere:
        d[:, 2] = np.abs(d[:, 2])
    return d


@pytest.mark.parametrize("j", [0, 12, 46])
@pytest.mark.parametrize("v", [0.0, 0.5, 1.0])
def test_pinned_values_on_the_azimuth_zero_edge(j, v):
    # u = j/48 with j even is u' = 0, the edge phi = 0 of T0, where the equal-area map is
    # cos(theta) = 1 - v (1 - 1/sqrt 2) (the far edge x = z meets phi = 0 at cos(theta) = 1/sqrt 2);
    # written out here, not taken from symsphere.warps.square_to_triangle.
    c = 1 - v * (1 - 1 / math.sqrt(2))
    base = np.array([math.sqrt(1 - c * c), 0.0, c])
    expected = base @ SPHERE_MAPS[strip_order("sphere")[j]]
    assert np.allclose(square_to_sphere([j / 48, v]), expected, rtol=0, atol=1e-14)


def test_pinned_values():
    d = square_to_sphere([[0.0, 0.0], [0.0, 1.0], [1 / 48, 1.0], [1 / 96, 0.0], [1.0, 1.0]])
    s, h = 1 / math.sqrt(3), 1 / math.sqrt(2)
    # (0, 0): the pole; (0, 1): T0's vertex (1, 0, 1)/sqrt 2; (1/48, 1): its vertex (1, 1, 1)/sqrt 3, where the
    # first strip ends (u' = 1); v = 0: the fan's axis; (1, 1): the last strip is mirrored (u' = 0), so the
    # vertex (1, 0, 1)/sqrt 2 under triangle strip_order[47] = 27, the paper's (x, -y, -z).
    assert SPHERE_MAPS[27].tolist() == [[1, 0, 0], [0, -1, 0], [0, 0, -1]]
    assert np.allclose(d, [[0, 0, 1], [h, 0, h], [s, s, s], [0, 0, 1], [h, 0, -h]], rtol=0, atol=1e-15)
    assert strip_order("sphere").tolist() == [
        0, 4, 5, 1, 2, 6, 7, 3, 8, 12, 36, 32, 35, 39, 15, 11, 9, 13, 37, 33, 34, 38, 14, 10,
        16, 20, 21, 17, 41, 45, 44, 40, 18, 22, 23, 19, 43, 47, 46, 42, 24, 28, 29, 25, 26, 30, 31, 27,
    ]  # fmt: skip


@pytest.mark.parametrize("forward, pdf, inverse, maps, domain", WARPS)
def test_continuous_within_fans(forward, pdf, inverse, maps, domain):
    # Across a strip boundary inside a fan the two strips meet on their shared edge, point for point;
    # between fans (every 8 strips; hemisphere: 8, then every 4) the warp jumps, as a cube map does.
    count = len(maps)
    v = np.linspace(0.0, 1.0, 41)
    jumps = []
    for j in range(1, count):
        below = forward(np.stack([np.full_like(v, j / count - 1e-13), v], axis=1))
        above = forward(np.stack([np.full_like(v, j / count), v], axis=1))
        if np.abs(below - above).max() > 1e-9:
            jumps.append(j)
    assert jumps == ([8, 16, 24, 32, 40] if count == 48 else [8, 12, 16, 20])


@pytest.mark.parametrize("forward, pdf, inverse, maps, domain", WARPS)
@pytest.mark.parametrize("method", METHODS)
def test_strips_are_the_scheme_orbits(forward, pdf, inverse, maps, domain, method):
    # u' in the even strips and 1 - u' in the odd ones, at the same v: exactly one orbit of the scheme.
    count = len(maps)
    local = np.array([0.3, 0.7])
    j = np.arange(count)
    uv = np.stack([(j + np.where(j % 2, 1 - local[0], local[0])) / count, np.full(count, local[1])], axis=1)
    orbit = ss.orbit(ss.square_to_triangle(local, method), domain)
    assert np.allclose(forward(uv, method=method), orbit[strip_order(domain)], rtol=0, atol=1e-14)
    assert sorted(strip_order(domain)) == list(range(count))


@pytest.mark.parametrize("forward, pdf, inverse, maps, domain", WARPS)
@pytest.mark.parametrize("method", METHODS)
def test_round_trips(forward, pdf, inverse, maps, domain, method):
    uv = np.random.default_rng(1).random((20_000, 2))
    d = forward(uv, method=method)
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-14)
    assert np.abs(inverse(d, method=method) - uv).max() < 1e-9
    w = _gaussian_directions(20_000, 2, hemisphere=domain == "hemisphere")
    assert np.abs(forward(inverse(w, method=method), method=method) - w).max() < 1e-9


@pytest.mark.parametrize("forward, pdf, inverse, maps, domain", WARPS)
@pytest.mark.parametrize("method", METHODS)
def test_float32_and_the_closed_square(forward, pdf, inverse, maps, domain, method):
    edge = np.linspace(0.0, 1.0, 97)  # every strip boundary k/48 (k/24) is on this grid
    uv = np.stack(np.meshgrid(edge, edge, indexing="ij"), axis=-1).reshape(-1, 2)
    d32 = forward(uv.astype(np.float32), method=method)
    d64 = forward(uv.astype(np.float32).astype(np.float64), method=method)  # the same inputs, in float64
    assert d64.dtype == np.float64 and d32.dtype == np.float32 and d32.shape == (len(uv), 3)
    assert np.all(np.isfinite(d64)) and np.all(np.isfinite(d32))
    assert np.allclose(np.linalg.norm(d64, axis=1), 1.0, atol=1e-14)
    assert np.abs(d32 - d64).max() < 1e-6
    back = inverse(d32, method=method)
    assert back.dtype == np.float32 and np.all((back >= 0) & (back <= 1))
    density = pdf(d32, method=method)
    assert density.dtype == np.float32 and np.all(density > 0)  # inf for the paper maps on the axes


@pytest.mark.parametrize("forward, pdf, inverse, maps, domain", WARPS)
def test_pdf(forward, pdf, inverse, maps, domain):
    w = _gaussian_directions(1000, 3, hemisphere=domain == "hemisphere")
    area = 4 * np.pi if domain == "sphere" else 2 * np.pi
    assert np.allclose(pdf(w), 1 / area, rtol=1e-15)
    for method in ("paper1", "paper2"):  # the triangle's density shared by all 48 (24)
        _, base = ss.fold(w)
        assert np.allclose(pdf(w, method=method), ss.square_to_triangle_pdf(base, method) / len(maps), rtol=1e-15)
    if domain == "hemisphere":
        assert float(pdf([0.0, 0.6, -0.8])) == 0.0


def test_bad_input():
    with pytest.raises(ValueError, match="'uv' must lie in the closed unit square"):
        square_to_sphere([1.5, 0.2])
    with pytest.raises(ValueError, match="'uv' must have shape"):
        square_to_sphere([0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match="'method'|method"):
        square_to_sphere([0.1, 0.2], method="nope")
    with pytest.raises(ValueError, match="'d' must lie in the hemisphere z >= 0"):
        hemisphere_to_square([0.0, 0.6, -0.8])
    with pytest.raises(ValueError, match="'d' must be finite"):
        sphere_to_square([np.nan, 0.0, 1.0])


@pytest.mark.statistical
@pytest.mark.parametrize("forward, pdf, inverse, maps, domain", WARPS)
def test_uniform_points_give_uniform_directions(forward, pdf, inverse, maps, domain):
    d = forward(np.random.default_rng(4).random((N, 2)))
    result = chi2_test(d, uniform_pdf(domain), domain, significance=SIGNIFICANCE, test_count=CHI2_TESTS)
    assert result.passed, str(result)
    # and the paper's map, the same way, is measurably not uniform
    bad = chi2_test(forward(np.random.default_rng(5).random((N, 2)), method="paper1"), uniform_pdf(domain), domain)
    assert bad.p_value < 1e-10


@pytest.mark.statistical
@pytest.mark.parametrize("forward, pdf, inverse, maps, domain", WARPS)
def test_uniform_directions_give_uniform_points(forward, pdf, inverse, maps, domain):
    # The inverse of an area-preserving bijection sends uniform directions to uniform points: 48 x 20 cells.
    uv = inverse(_gaussian_directions(N, 6, hemisphere=domain == "hemisphere"))
    counts, _, _ = np.histogram2d(uv[:, 0], uv[:, 1], bins=(len(maps) * 2, 20), range=((0, 1), (0, 1)))
    p = scipy_stats.chisquare(counts.ravel()).pvalue
    assert p >= 1 - (1 - SIGNIFICANCE) ** (1 / CHI2_TESTS), p


def test_exported_at_top_level():
    names = {"square_to_sphere", "square_to_sphere_pdf", "sphere_to_square"}
    names |= {"square_to_hemisphere", "square_to_hemisphere_pdf", "hemisphere_to_square"}
    assert names <= set(ss.__all__) and names <= set(ss.warps.__all__)
    # one home: the top-level names are the warps' own functions
    assert all(getattr(ss, name) is getattr(ss.warps, name) for name in names)
    assert all(getattr(ss, name).__module__.startswith("symsphere.warps.") for name in names)
