"""Urena et al.'s map onto a spherical rectangle (square_to_spherical_rectangle): the triple and its density.

The chi-square reference is independent of the map: the rectangle is cut into a grid of 12 x 12 planar
cells, each cell's solid angle the sum of its two triangles' by Van Oosterom & Strackee's formula; a
sample falls into the cell where its ray meets the plane.  One test per rectangle, family significance
0.01, Sidak-corrected over CHI2_TESTS; fixed seeds.
"""

import math

import numpy as np
import pytest
from numba import njit
from scipy import stats as scipy_stats

from symsphere.warps import (
    rectangle_frame,
    rectangle_point,
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


# --- the scalar formulas: checked from Python, bare inside numba kernels ----------------------------------

CUBE_FACE = (-1.0, -1.0, 1.0, 2.0, 2.0)  # corner (x0, y0, z0), width, height: a face of the cube [-1, 1]^3
FRAME = rectangle_frame(*CUBE_FACE)
POINT_ARGS = (0.3, 0.7, FRAME[0], *FRAME[1:6], *FRAME[7:])  # u, v, S, x0, y0, z0, x1, y1, b0, b1, ck, sk
POINT_NAMES = ("u", "v", "solid_angle", "x0", "y0", "z0", "x1", "y1", "b0", "b1", "ck", "sk")


@pytest.mark.parametrize(
    "index, value, error, message",
    [
        (4, None, TypeError, "'height' must be a real number, got NoneType None"),
        (4, np.nan, ValueError, "'height' must be a finite positive number at most 1e+30, got nan"),
        (3, 0.0, ValueError, "'width' must be a finite positive number at most 1e+30, got 0.0"),
        (3, -2.0, ValueError, "'width' must be a finite positive number at most 1e+30, got -2.0"),
        (0, True, TypeError, "'x0' must be a real number, got bool True"),
        (1, "1", TypeError, "'y0' must be a real number, got str '1'"),
        (1, np.inf, ValueError, "'y0' must be a finite number of magnitude at most 1e+30, got inf"),
        (2, 1e308, ValueError, "'z0' must be a finite number of magnitude at most 1e+30, got 1e+308"),
        (2, -1e-320, ValueError, "'z0' must be 0 or of magnitude at least 1e-30, got -1e-320"),
        (0, np.zeros(2), TypeError, "'x0' must be a real number, got ndarray array([0., 0.])"),
    ],
)
def test_rectangle_frame_names_a_bad_argument(index, value, error, message):
    args = list(CUBE_FACE)
    args[index] = value
    with pytest.raises(error) as info:
        rectangle_frame(*args)
    assert str(info.value) == message


@pytest.mark.parametrize(
    "name, value, error, fragment",
    [
        ("u", 1.5, ValueError, "'u' must be a number in [0, 1], got 1.5"),
        ("v", np.nan, ValueError, "'v' must be a number in [0, 1], got nan"),
        ("solid_angle", 7.0, ValueError, "'solid_angle' must be a solid angle in [0, 2 pi], got 7.0"),
        ("z0", 1.0, ValueError, "'z0' must be negative, of magnitude in [1e-30, 2e+30]"),
        ("z0", -1e-300, ValueError, "'z0' must be negative"),
        ("x1", -2.0, ValueError, "'x1' must be >= 'x0' (-1.0), got -2.0"),
        ("y1", -3.0, ValueError, "'y1' must be >= 'y0' (-1.0), got -3.0"),
        ("x0", 1e31, ValueError, "'x0' must be a finite number of magnitude at most 2e+30"),
        ("ck", 1.5, ValueError, "'ck' must be a number in [-1, 1]"),
        ("b1", None, TypeError, "'b1' must be a real number, got NoneType None"),
    ],
)
def test_rectangle_point_names_a_bad_argument(name, value, error, fragment):
    args = list(POINT_ARGS)
    args[POINT_NAMES.index(name)] = value
    with pytest.raises(error) as info:
        rectangle_point(*args)
    assert str(info.value).startswith(fragment), str(info.value)


def test_the_checked_forms_take_names():
    assert rectangle_frame(x0=-1.0, y0=-1.0, z0=1.0, width=2.0, height=2.0) == FRAME
    assert rectangle_point(*POINT_ARGS[:2], **dict(zip(POINT_NAMES[2:], POINT_ARGS[2:], strict=True))) == (
        rectangle_point(*POINT_ARGS)
    )
    # z0 = 0 (the origin in the rectangle's plane) is allowed: S = 0, as documented
    assert rectangle_frame(-1.0, -1.0, 0.0, 2.0, 2.0)[0] == 0.0


def test_inside_a_kernel_they_are_the_bare_formulas():
    # A NaN height raises from Python; compiled, the call is the formula, which does not check it (NaN out).
    @njit
    def solid_angle_and_y1(height):
        f = rectangle_frame(-1.0, -1.0, 1.0, 2.0, height)
        return f[0], f[5]

    @njit
    def point_x(u):
        f = rectangle_frame(-1.0, -1.0, 1.0, 2.0, 2.0)
        return rectangle_point(u, 0.5, f[0], f[1], f[2], f[3], f[4], f[5], f[7], f[8], f[9], f[10])[0]

    assert math.isclose(solid_angle_and_y1(2.0)[0], FRAME[0], rel_tol=1e-15)  # the same formula, compiled
    assert np.isnan(solid_angle_and_y1(np.nan)[1])  # y1 = y0 + height
    assert math.isclose(point_x(0.3), rectangle_point(0.3, 0.5, *POINT_ARGS[2:])[0], rel_tol=1e-15, abs_tol=1e-15)
    assert np.isfinite(point_x(1.5))  # u outside [0, 1]: no check in the kernel (the clamp keeps x finite)
