"""The three unit-square-to-T0 maps: forward, pdf and inverse side by side."""

import warnings

import mpmath
import numpy as np
import pytest
from references import ELEMENTARY_ULPS, assert_within_eps
from scipy import integrate

import symsphere
from symsphere.warps import METHODS, square_to_triangle, square_to_triangle_pdf, triangle_to_square

VERTICES = {  # (u, v) -> vertex of T0, the same for all three maps
    (0.0, 0.0): (0.0, 0.0, 1.0),
    (1.0, 0.0): (0.0, 0.0, 1.0),
    (0.0, 1.0): (2**-0.5, 0.0, 2**-0.5),
    (1.0, 1.0): (3**-0.5, 3**-0.5, 3**-0.5),
}


def _interior_uv(n, seed=0, margin=1e-3):
    return margin + (1 - 2 * margin) * np.random.default_rng(seed).random((n, 2))


def _in_t0(p):
    return (p[..., 2] >= p[..., 0]) & (p[..., 0] >= p[..., 1]) & (p[..., 1] >= 0)


def _direction(phi, one_minus_cos):
    sin_theta = np.sqrt(one_minus_cos * (2 - one_minus_cos))
    return np.array([sin_theta * np.cos(phi), sin_theta * np.sin(phi), 1 - one_minus_cos])


def _cos_theta_max(phi):
    # the edge x = z of T0: tan(theta) cos(phi) = 1
    return np.cos(phi) / np.sqrt(1 + np.cos(phi) ** 2)


@pytest.mark.parametrize("method", METHODS)
def test_vertices(method):
    uv = np.array(list(VERTICES))
    expected = np.array(list(VERTICES.values()))
    if method == "equal_area":
        # no elementary function (+, -, *, /, sqrt and a polynomial sine): the same bits on every machine
        np.testing.assert_allclose(square_to_triangle(uv, method), expected, rtol=0, atol=1e-15)
    else:
        # numpy's cos, sin, atan (E = ELEMENTARY_ULPS each, tests/references.py) propagate to 4E + 1 (paper1)
        # and 4E + 5/2 (paper2) per component (the derivation: tests/test_kernels.py, MAP_EPS / 2), plus
        # phi = (pi/4)_64 (1/4) and the expected 2**-0.5, 3**-0.5 (libm's pow: 1): 4E + 4 eps.
        assert_within_eps(square_to_triangle(uv, method), expected, 4 * ELEMENTARY_ULPS + 4, scale=1)


def test_paper_maps_as_printed():
    # Algorithm 1 and 2 transcribed once more from the paper, at a few points.
    for u, v in [(0.5, 0.5), (0.1, 0.9), (0.77, 0.23)]:
        phi = u * np.pi / 4
        theta = np.arctan(v / np.cos(u * np.pi / 4))
        p1 = [np.cos(phi) * np.sin(theta), np.sin(phi) * np.sin(theta), np.cos(theta)]
        np.testing.assert_allclose(square_to_triangle([u, v], "paper1"), p1, rtol=1e-15)
        theta = v * np.pi / 4
        norm = np.sqrt(np.sin(theta) ** 2 + np.cos(theta) ** 2 * np.cos(phi) ** 2)
        p2 = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta) * np.cos(phi)]) / norm
        np.testing.assert_allclose(square_to_triangle([u, v], "paper2"), p2, rtol=1e-15)


def test_equal_area_known_values():
    # u splits T0 by azimuth into equal areas: A(phi) = phi - asin(sin(phi)/sqrt 2) = u pi/12.
    # A(phi) is evaluated exactly (mpmath, 80 bits) at the map's point: in floating point its subtraction
    # loses ~2 digits (A ~ 0.29 phi), so numpy's arctan2, sin, arcsin (up to 4 ulps each on some machines)
    # would give ~1e-14 by themselves.  What remains is the map's own error (IEEE operations only, a few eps
    # per component; A's condition number in x, y is phi / A < 3.5): 1e-14 is 45 eps.
    for u in [0.25, 0.5, 0.9]:
        p = square_to_triangle([u, 1.0])  # on the edge x = z
        with mpmath.workprec(80):
            phi = mpmath.atan2(float(p[1]), float(p[0]))
            ratio = float((phi - mpmath.asin(mpmath.sin(phi) / mpmath.sqrt(2))) / (mpmath.mpf(u) * mpmath.pi / 12))
        assert ratio == pytest.approx(1.0, rel=1e-14)
        assert p[0] == pytest.approx(p[2], rel=1e-15)
    # v splits each azimuth's arc into equal solid angle: cos(theta) is linear in v
    p = square_to_triangle([[0.3, 0.0], [0.3, 0.5], [0.3, 1.0]])
    assert p[1, 2] == pytest.approx((p[0, 2] + p[2, 2]) / 2, rel=1e-15)


def test_equal_area_sine_polynomial_is_as_accurate_as_libm():
    # The map's sine of u pi/12 is a polynomial (vectorisable); against an 80-bit sine it must
    # stay within 0.6 ulp (a correctly rounded sine is within 0.5; glibc measured 0.516).
    from symsphere._testing import warps_triangle

    sin_small = warps_triangle.sin_small

    if np.finfo(np.longdouble).nmant < 63:
        pytest.skip("needs an 80-bit long double as the reference")
    u = np.concatenate([np.linspace(0.0, 1.0, 1_000_001), [5e-324, 1e-300, 1e-8]])
    s = u * (np.pi / 12)
    got = sin_small(s)
    exact = np.sin(s.astype(np.longdouble))
    ulps = np.abs(got.astype(np.longdouble) - exact) / np.spacing(got).astype(np.longdouble)
    assert got[0] == 0.0 and np.all(np.isfinite(got))
    assert float(ulps.max()) < 0.6


@pytest.mark.parametrize("method", METHODS)
def test_edges_and_corners_finite_inside_unit(method):
    values = np.array([0.0, 1e-300, 1e-17, 0.5, 1 - 1e-16, 1.0])
    uv = np.array(np.meshgrid(values, values)).reshape(2, -1).T
    for dtype in (np.float64, np.float32):
        p = square_to_triangle(uv.astype(dtype), method)
        assert p.dtype == dtype
        assert np.all(np.isfinite(p)) and np.all(_in_t0(p))
        np.testing.assert_allclose(np.linalg.norm(p.astype(np.float64), axis=-1), 1, atol=4 * np.finfo(dtype).eps)
        back = triangle_to_square(p, method)
        assert np.all(np.isfinite(back)) and np.all((back >= 0) & (back <= 1))


@pytest.mark.parametrize("method", METHODS)
def test_inverse_round_trip(method):
    uv = _interior_uv(100_000)
    p = square_to_triangle(uv, method)
    np.testing.assert_allclose(triangle_to_square(p, method), uv, rtol=0, atol=1e-12)
    np.testing.assert_allclose(square_to_triangle(triangle_to_square(p, method), method), p, rtol=0, atol=1e-14)


def test_equal_area_no_cancellation_near_pole():
    # 1 - cos(theta) ~ 1e-20 is lost in cos(theta); the map must keep it through sin(theta).
    uv = np.array([[0.3, 1e-20], [0.7, 1e-200]])
    np.testing.assert_allclose(triangle_to_square(square_to_triangle(uv)), uv, rtol=1e-12)


@pytest.mark.parametrize("method", METHODS)
def test_pdf_is_inverse_jacobian(method):
    # An independent check of each pdf: 1 / |dF/du x dF/dv| by central differences.
    uv = _interior_uv(200, seed=2, margin=0.01)
    h = 1e-6
    du = (square_to_triangle(uv + [h, 0], method) - square_to_triangle(uv - [h, 0], method)) / (2 * h)
    dv = (square_to_triangle(uv + [0, h], method) - square_to_triangle(uv - [0, h], method)) / (2 * h)
    jacobian = np.linalg.norm(np.cross(du, dv), axis=-1)
    np.testing.assert_allclose(square_to_triangle_pdf(square_to_triangle(uv, method), method), 1 / jacobian, rtol=1e-6)


@pytest.mark.parametrize("method", METHODS)
def test_pdf_integrates_to_one(method):
    # Quadrature over T0 in (phi, s) with 1 - cos(theta) = s^2, which absorbs the paper
    # maps' 1/sin(theta) singularity at the pole: d(omega) = d(phi) d(cos theta) = 2 s ds d(phi).
    def integrand(s, phi):
        return float(square_to_triangle_pdf(_direction(phi, s * s), method)) * 2 * s

    total, error = integrate.dblquad(
        integrand, 0, np.pi / 4, 0, lambda phi: np.sqrt(1 - _cos_theta_max(phi)), epsabs=1e-11, epsrel=1e-11
    )
    assert total == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize("method", METHODS)
def test_pdf_zero_outside_and_inf_only_at_pole(method):
    outside = np.array([[0.5, 0.6, 0.62449980], [0.8, 0.1, 0.59160798], [0.1, -0.1, 0.98994949]])
    assert np.all(square_to_triangle_pdf(outside, method) == 0)
    pole = square_to_triangle_pdf([0.0, 0.0, 1.0], method)
    assert pole == (12 / np.pi if method == "equal_area" else np.inf)
    p = square_to_triangle(np.array([[0.5, 1e-300], [0.5, 1e-12]]), method)
    assert np.all(np.isfinite(square_to_triangle_pdf(p, method)))


@pytest.mark.parametrize("method", ["paper1", "paper2"])
def test_paper_maps_are_not_uniform(method):
    # Their density diverges at the pole and drops below uniform at the far edge.
    near_pole = square_to_triangle([0.5, 1e-6], method)
    far_edge = square_to_triangle([0.5, 1.0], method)
    assert square_to_triangle_pdf(near_pole, method) > 1e5 * 12 / np.pi
    assert square_to_triangle_pdf(far_edge, method) < 12 / np.pi


@pytest.mark.parametrize("method", METHODS)
def test_vectorised_equals_scalar(method):
    uv = _interior_uv(20, seed=3)
    batch = square_to_triangle(uv, method)
    for i, point in enumerate(uv):
        assert np.array_equal(square_to_triangle(point, method), batch[i])
        assert np.array_equal(triangle_to_square(batch[i], method), triangle_to_square(batch, method)[i])
        assert square_to_triangle_pdf(batch[i], method) == square_to_triangle_pdf(batch, method)[i]
    assert square_to_triangle(uv.reshape(4, 5, 2), method).shape == (4, 5, 3)


@pytest.mark.parametrize("method", METHODS)
def test_float32_close_to_float64(method):
    uv = _interior_uv(1000, seed=4).astype(np.float32)
    p32 = square_to_triangle(uv, method)
    assert p32.dtype == np.float32
    np.testing.assert_allclose(p32, square_to_triangle(uv.astype(np.float64), method), atol=1e-7)
    assert square_to_triangle_pdf(p32, method).dtype == np.float32
    assert triangle_to_square(p32, method).dtype == np.float32


@pytest.mark.parametrize(
    "call, error, match",
    [
        (lambda: square_to_triangle([0.5, 1.5]), ValueError, r"'uv' must lie in the closed unit square"),
        (lambda: square_to_triangle([0.5, -1e-18]), ValueError, r"'uv' must lie"),
        (lambda: square_to_triangle([np.nan, 0.5]), ValueError, r"'uv' must lie"),
        (lambda: square_to_triangle([0.5, 0.5, 0.5]), ValueError, r"'uv' must have shape \(\.\.\., 2\)"),
        (lambda: square_to_triangle(0.5), ValueError, r"'uv' must have shape"),
        (lambda: square_to_triangle([["a", "b"]]), TypeError, r"'uv'"),
        (lambda: square_to_triangle([0.5, 0.5], "arvo"), ValueError, r"'arvo' is not a valid method; use one of"),
        (lambda: square_to_triangle([0.5, 0.5], method=None), ValueError, r"not a valid method"),
        (lambda: square_to_triangle_pdf([0.0, 1.0]), ValueError, r"'p' must have shape \(\.\.\., 3\)"),
        (lambda: square_to_triangle_pdf([0.0, np.inf, 1.0]), ValueError, r"'p' must be finite"),
        (lambda: triangle_to_square([0.6, 0.0, 0.5]), ValueError, r"'p' must lie in the triangle T0"),
        (lambda: triangle_to_square([0.1, 0.2, 0.97]), ValueError, r"'p' must lie in the triangle T0"),
        (lambda: triangle_to_square([0.5, 0.5, 0.5], "x"), ValueError, r"'x' is not a valid method"),
    ],
)
def test_bad_input(call, error, match):
    with pytest.raises(error, match=match):
        call()


# --- float32 near the vertex ---------------------------------------------------------------------------------------


def test_triangle_pdf_float32_near_the_vertex_is_quiet():
    p = np.array([1e-30, 0.0, 1.0], dtype=np.float32)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for method in ("paper1", "paper2"):
            density = symsphere.square_to_triangle_pdf(p, method)
            assert density.dtype == np.float32 and density > 0
