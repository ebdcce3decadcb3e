"""Urena et al.'s map onto a spherical rectangle (square_to_spherical_rectangle): the triple and its density.

The chi-square reference is independent of the map: the rectangle is cut into a grid of 12 x 12 planar
cells, each cell's solid angle the sum of its two triangles' by Van Oosterom & Strackee's formula; a
sample falls into the cell where its ray meets the plane.  One test per rectangle, family significance
0.01, Sidak-corrected over CHI2_TESTS; fixed seeds.
"""

import numpy as np
import pytest
from scipy import stats as scipy_stats

from symsphere.warps import (
    spherical_rectangle_to_square,
    square_to_spherical_rectangle,
    square_to_spherical_rectangle_pdf,
)

RECTANGLES = {
    "cube_face": ([-1.0, -1.0, 1.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]),  # 2 pi / 3 sr
    "off_axis": ([0.4, -0.2, -0.9], [1.5, 0.0, 0.0], [0.0, 0.7, 0.0]),
    "close_wall": ([-2.0, -1.0, 0.15], [4.0, 0.0, 0.0], [0.0, 3.0, 0.0]),  # nearly a hemisphere
    "tilted_far": ([3.0, 1.0, 2.0], [0.3, 0.4, 0.0], [-0.8, 0.6, 0.5]),
    "small": ([0.5, 0.5, 10.0], [0.01, 0.0, 0.0], [0.0, 0.02, 0.0]),  # 2e-6 sr
}
SIGNIFICANCE = 0.01
CHI2_TESTS = len(RECTANGLES)
N_CHI2 = 200_000
GRID = 12
EDGE_VALUES = (0.0, 1e-300, 1e-17, 0.5, 1 - 1e-16, 1.0)
EDGE_UV = np.array([[a, b] for a in EDGE_VALUES for b in EDGE_VALUES])


def _tilted(rect):  # make edge2 of "tilted_far" orthogonal to edge1
    c, e1, e2 = (np.array(v, dtype=np.float64) for v in rect)
    e2 = e2 - (e2 @ e1) / (e1 @ e1) * e1
    return c, e1, e2


RECTANGLES = {name: _tilted(rect) for name, rect in RECTANGLES.items()}


def _solid_angle(a, b, c):
    la, lb, lc = (np.linalg.norm(x, axis=-1) for x in (a, b, c))
    triple = np.abs(np.sum(a * np.cross(b, c), axis=-1))
    den = la * lb * lc + np.sum(a * b, -1) * lc + np.sum(a * c, -1) * lb + np.sum(b * c, -1) * la
    return 2 * np.arctan2(triple, den)


def _cells(rect):
    c, e1, e2 = rect
    s = np.arange(GRID + 1) / GRID
    p = c + s[:, None, None] * e1 + s[None, :, None] * e2
    a, b, cc, d = p[:-1, :-1], p[1:, :-1], p[1:, 1:], p[:-1, 1:]
    return (_solid_angle(a, b, cc) + _solid_angle(a, cc, d)).ravel()


def _cell_index(dirs, rect):
    c, e1, e2 = rect
    n = np.cross(e1, e2)
    t = (c @ n) / (dirs @ n)
    q = t[:, None] * dirs - c
    s1, s2 = q @ e1 / (e1 @ e1), q @ e2 / (e2 @ e2)
    i, j = np.clip((s1 * GRID).astype(int), 0, GRID - 1), np.clip((s2 * GRID).astype(int), 0, GRID - 1)
    return i * GRID + j


def test_cube_face_solid_angle():
    p = square_to_spherical_rectangle_pdf([[0.0, 0.0, 1.0]], *RECTANGLES["cube_face"])
    assert p[0] == pytest.approx(3 / (2 * np.pi), rel=1e-14)


@pytest.mark.parametrize("name", list(RECTANGLES))
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_finite_unit_inside(name, dtype):
    rect = RECTANGLES[name]
    uv = np.concatenate([np.random.default_rng(1).random((5000, 2)), EDGE_UV]).astype(dtype)
    d = square_to_spherical_rectangle(uv, *rect)
    assert d.dtype == dtype and np.all(np.isfinite(d))
    np.testing.assert_allclose(np.linalg.norm(d.astype(np.float64), axis=1), 1, atol=4 * np.finfo(dtype).eps)
    np.testing.assert_array_equal(d, square_to_spherical_rectangle(uv.astype(np.float64), *rect).astype(dtype))
    if dtype == np.float64:
        assert np.all(square_to_spherical_rectangle_pdf(d[:5000], *rect) > 0)
    back = spherical_rectangle_to_square(d, *rect)
    assert np.all(np.isfinite(back)) and np.all((back >= 0) & (back <= 1))


@pytest.mark.parametrize("name", list(RECTANGLES))
def test_round_trip(name):
    rect = RECTANGLES[name]
    uv = 1e-3 + (1 - 2e-3) * np.random.default_rng(2).random((20_000, 2))
    back = spherical_rectangle_to_square(square_to_spherical_rectangle(uv, *rect), *rect)
    np.testing.assert_allclose(back, uv, atol=1e-6 if name == "small" else 1e-10)


@pytest.mark.parametrize("name", [n for n in RECTANGLES if n != "small"])
def test_pdf_is_inverse_jacobian(name):
    rect = RECTANGLES[name]
    uv = 0.01 + 0.98 * np.random.default_rng(3).random((500, 2))
    h = 1e-6

    def f(x):
        return square_to_spherical_rectangle(x, *rect)

    fu = (f(uv + [h, 0]) - f(uv - [h, 0])) / (2 * h)
    fv = (f(uv + [0, h]) - f(uv - [0, h])) / (2 * h)
    jac = np.linalg.norm(np.cross(fu, fv), axis=-1)
    np.testing.assert_allclose(square_to_spherical_rectangle_pdf(f(uv), *rect) * jac, 1.0, rtol=1e-5)


@pytest.mark.parametrize("name", list(RECTANGLES))
def test_chi2_against_grid_cells(name):
    rect = RECTANGLES[name]
    seed = 20 + list(RECTANGLES).index(name)
    d = square_to_spherical_rectangle(np.random.default_rng(seed).random((N_CHI2, 2)), *rect)
    probs = _cells(rect)
    probs /= probs.sum()
    counts = np.bincount(_cell_index(d, rect), minlength=GRID * GRID)
    expected = probs * N_CHI2
    small = expected < 5
    if small.any():
        expected = np.append(expected[~small], expected[small].sum())
        counts = np.append(counts[~small], counts[small].sum())
    result = scipy_stats.chisquare(counts, expected)
    assert result.pvalue >= 1 - (1 - SIGNIFICANCE) ** (1 / CHI2_TESTS), result


def test_chi2_detects_area_sampling():
    # the power of the test above: area sampling of the nearly-hemispherical rectangle is rejected
    c, e1, e2 = RECTANGLES["close_wall"]
    st = np.random.default_rng(4).random((N_CHI2, 2))
    q = c + st[:, :1] * e1 + st[:, 1:] * e2
    d = q / np.linalg.norm(q, axis=1, keepdims=True)
    probs = _cells(RECTANGLES["close_wall"])
    counts = np.bincount(_cell_index(d, RECTANGLES["close_wall"]), minlength=GRID * GRID)
    assert scipy_stats.chisquare(counts, probs / probs.sum() * N_CHI2).pvalue < 1e-10


@pytest.mark.parametrize(
    "args, word",
    [
        (([0, 0, 1], [1, 0, 0], [1, 1, 0]), "orthogonal"),
        (([0, 0, 1], [0, 0, 0], [0, 1, 0]), "orthogonal"),
        (([0, 0, 0], [1, 0, 0], [0, 1, 0]), "plane"),
        (([0, 0, 1], [1, 0, 0], [0, np.nan, 0]), "'edge2'"),
    ],
)
def test_bad_input(args, word):
    with pytest.raises(ValueError, match=word):
        square_to_spherical_rectangle([0.5, 0.5], *args)
