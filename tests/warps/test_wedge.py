"""The cosine-weighted wedge map: forward, pdf and inverse side by side, and its 8-fold symmetrisation."""

import itertools
import math

import numpy as np
import pytest
from numba import njit
from references import ELEMENTARY_ULPS, assert_power, assert_within_eps, raises_naming
from scipy import integrate

from symsphere import frames, warps
from symsphere.stats import chi2_test
from symsphere.warps import (
    WEDGE_MAPS,
    cosine_wedge_density,
    cosine_wedge_point,
    cosine_wedge_to_square,
    cosine_wedge_uv,
    square_to_cosine_wedge,
    square_to_cosine_wedge_pdf,
)

# Two chi-square tests below must not reject a correct sampler (test_forward_chi2 and
# test_symmetrised_sampler_chi2_cosine): family-wise significance 0.01, Sidak-corrected to
# 1 - 0.99**(1/2) = 0.005012 per test by chi2_test(test_count=2).
SIGNIFICANCE = 0.01
CHI2_TESTS = 2
# 64 azimuth bins of pi/32 on the hemisphere [-pi, pi): the wedge's edges phi = 0 and pi/4 are
# bin edges 32 and 40, so W is exactly 8 x 16 bins and the pdf is smooth on every bin.
BINS = (64, 16)
N_CHI2 = 200_000
# Power: with these 127 cells, 200 000 samples reject an alternative of Cohen's effect size w >= 0.022 with
# probability 99 % (tests/references.py), e.g. a density 2.2 % off on either half of the hemisphere; what the
# tests must detect is w = 0.04 (as tests/statistical/), asserted below.
MUST_DETECT_W = 0.04


def _interior_uv(n, seed=0, margin=1e-3):
    return margin + (1 - 2 * margin) * np.random.default_rng(seed).random((n, 2))


def _in_wedge(d):
    return (d[..., 0] >= d[..., 1]) & (d[..., 1] >= 0) & (d[..., 2] >= 0)


def _direction(theta, phi):
    return np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])


def _cosine_hemisphere_pdf(d):
    # The reference of the symmetrised sampler, written here independently of the module.
    return np.maximum(np.asarray(d)[..., 2], 0.0) / np.pi


def _symmetrise(p, rng):
    # A uniformly chosen member of the 8 maps applied to each wedge point (row vectors: p @ M).
    k = rng.integers(8, size=len(p))
    return np.einsum("ni,nij->nj", p, WEDGE_MAPS[k].astype(np.float64))


# --- forward -------------------------------------------------------------------------


def test_pinned_values():
    # By hand from r = sqrt(u), phi = (pi/4) v, z = sqrt(1 - u):
    # cos(pi/8) = sqrt(2 + sqrt 2)/2, sin(pi/8) = sqrt(2 - sqrt 2)/2.
    cos8, sin8 = math.sqrt(2 + math.sqrt(2)) / 2, math.sqrt(2 - math.sqrt(2)) / 2
    cases = {
        (0.25, 0.5): (0.5 * cos8, 0.5 * sin8, math.sqrt(3) / 2),  # r = 1/2, phi = pi/8
        (0.5, 1.0): (0.5, 0.5, math.sqrt(0.5)),  # r = 1/sqrt 2, phi = pi/4
        (0.75, 0.0): (math.sqrt(3) / 2, 0.0, 0.5),  # r = sqrt(3)/2, phi = 0
        (0.0, 0.7): (0.0, 0.0, 1.0),  # the pole, for every v
        (1.0, 0.0): (1.0, 0.0, 0.0),  # the rim
        (1.0, 1.0): (math.sqrt(0.5), math.sqrt(0.5), 0.0),
    }
    uv = np.array(list(cases))
    expected = np.array(list(cases.values()))
    # numpy's cos, sin (E = ELEMENTARY_ULPS ulps, tests/references.py) of phi = v (pi/4)_64 (off by <= 1/4 eps),
    # times r = sqrt(u) (1/2 + 1/2), against sqrt-of-sqrt closed forms (<= 3/2): (E + 3) eps on unit vectors.
    assert_within_eps(square_to_cosine_wedge(uv), expected, ELEMENTARY_ULPS + 3, scale=1)
    # the pdf at those points: 8 cos(theta)/pi
    np.testing.assert_allclose(square_to_cosine_wedge_pdf(expected), 8 * expected[:, 2] / np.pi, rtol=1e-15)
    assert square_to_cosine_wedge_pdf(expected[0]) == pytest.approx(4 * math.sqrt(3) / math.pi, rel=1e-15)


def test_u_is_disk_area_and_v_is_azimuth():
    # The projected radius squared is u (uniform disk area); the azimuth is linear in v.
    uv = _interior_uv(1000, seed=7, margin=0.0)
    d = square_to_cosine_wedge(uv)
    np.testing.assert_allclose(d[:, 0] ** 2 + d[:, 1] ** 2, uv[:, 0], rtol=1e-15, atol=1e-300)
    np.testing.assert_allclose(np.arctan2(d[:, 1], d[:, 0]), uv[:, 1] * np.pi / 4, rtol=1e-14, atol=1e-300)
    np.testing.assert_allclose(d[:, 2], np.sqrt(1 - uv[:, 0]), rtol=1e-15)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_edges_and_corners_finite_inside_unit(dtype):
    values = np.array([0.0, 1e-300, 1e-17, 0.5, 1 - 1e-16, 1.0])
    uv = np.array(np.meshgrid(values, values)).reshape(2, -1).T.astype(dtype)
    d = square_to_cosine_wedge(uv)
    assert d.dtype == dtype
    assert np.all(np.isfinite(d)) and np.all(_in_wedge(d))
    np.testing.assert_allclose(np.linalg.norm(d.astype(np.float64), axis=-1), 1, atol=4 * np.finfo(dtype).eps)
    pdf = square_to_cosine_wedge_pdf(d)
    assert np.all(np.isfinite(pdf)) and np.all(pdf >= 0)
    back = cosine_wedge_to_square(d)
    assert np.all(np.isfinite(back)) and np.all((back >= 0) & (back <= 1))
    corners = square_to_cosine_wedge(np.array([[0, 0], [0, 1], [1, 0], [1, 1]], dtype=dtype))
    h = np.float32(math.sqrt(0.5)) if dtype == np.float32 else math.sqrt(0.5)
    np.testing.assert_allclose(corners, [[0, 0, 1], [0, 0, 1], [1, 0, 0], [h, h, 0]], rtol=0, atol=np.finfo(dtype).eps)


def test_no_cancellation_near_pole_and_rim():
    # Near the pole u = r^2 carries all the digits; near the rim z = sqrt(1 - u) does, since
    # 1 - u is exact for u >= 1/2 (sqrt(1 - r^2) would lose them).
    uv = np.array([[1e-20, 0.3], [1e-200, 0.7]])
    np.testing.assert_allclose(cosine_wedge_to_square(square_to_cosine_wedge(uv)), uv, rtol=1e-12)
    for k in (20, 40, 52):
        d = square_to_cosine_wedge([1 - 2.0**-k, 0.5])
        assert d[2] == 2.0 ** (-k / 2)  # exactly sqrt(2^-k)


# --- inverse -------------------------------------------------------------------------


def test_inverse_round_trip():
    uv = _interior_uv(100_000)
    d = square_to_cosine_wedge(uv)
    back = cosine_wedge_to_square(d)
    np.testing.assert_allclose(back, uv, rtol=0, atol=1e-14)  # measured max error 3.3e-16
    # measured 3.5e-15.  Bound: back's u = x^2 + y^2 is within 2E + 2 eps (x, y within E + 1/2 each:
    # numpy's cos, sin, E = ELEMENTARY_ULPS), and near the rim dz = du / (2z) with z >= sqrt(1e-3) here,
    # r = sqrt(u) likewise near the pole (dr = du / (2r), r >= sqrt(1e-3)): (2E + 2) / (2 sqrt(1e-3)) eps,
    # plus v's atan2 (3E + 3/2, times r) and the forward map's own E + 1.
    e = ELEMENTARY_ULPS
    assert_within_eps(square_to_cosine_wedge(back), d, (2 * e + 2) / (2 * math.sqrt(1e-3)) + 4 * e + 3, scale=1)
    # and from the direction side: unit vectors of W drawn independently of the map
    rng = np.random.default_rng(11)
    theta, phi = np.arccos(rng.uniform(0.03, 1.0, 10_000)), rng.uniform(0, np.pi / 4, 10_000)
    w = _direction(theta, phi).T
    np.testing.assert_allclose(square_to_cosine_wedge(cosine_wedge_to_square(w)), w, rtol=0, atol=1e-14)


def test_inverse_round_trip_float32():
    uv = _interior_uv(10_000, seed=5).astype(np.float32)
    d = square_to_cosine_wedge(uv)
    back = cosine_wedge_to_square(d)
    assert back.dtype == np.float32
    np.testing.assert_allclose(back, uv, rtol=0, atol=1e-6)
    # z = sqrt(1 - u) amplifies the float32 error of u by 1/(2z): <= 1.5e-6 for u <= 0.999
    np.testing.assert_allclose(square_to_cosine_wedge(back), d, rtol=0, atol=2e-6)


def test_inverse_at_pole_and_boundary():
    np.testing.assert_array_equal(cosine_wedge_to_square([0.0, 0.0, 1.0]), [0.0, 0.0])
    np.testing.assert_array_equal(cosine_wedge_to_square([1.0, 0.0, 0.0]), [1.0, 0.0])
    assert cosine_wedge_to_square([0.6, 0.6, math.sqrt(0.28)])[1] == 1.0
    # a few ulps outside W (rounding) is accepted and clipped
    uv = cosine_wedge_to_square([[0.6, 0.6 + 1e-16, math.sqrt(0.28)], [0.8, -1e-17, 0.6], [1.0, 0.0, -1e-16]])
    assert np.all((uv >= 0) & (uv <= 1))


# --- pdf -----------------------------------------------------------------------------


def test_pdf_is_inverse_jacobian():
    # An independent check of the pdf: 1 / |dF/du x dF/dv| by central differences.
    uv = _interior_uv(200, seed=2, margin=0.01)
    h = 1e-6
    du = (square_to_cosine_wedge(uv + [h, 0]) - square_to_cosine_wedge(uv - [h, 0])) / (2 * h)
    dv = (square_to_cosine_wedge(uv + [0, h]) - square_to_cosine_wedge(uv - [0, h])) / (2 * h)
    jacobian = np.linalg.norm(np.cross(du, dv), axis=-1)
    np.testing.assert_allclose(square_to_cosine_wedge_pdf(square_to_cosine_wedge(uv)), 1 / jacobian, rtol=1e-6)


def test_pdf_integrates_to_one():
    # Quadrature in (theta, phi) over W, d(omega) = sin(theta) d(theta) d(phi); exact value 1.
    def integrand(theta, phi):
        return float(square_to_cosine_wedge_pdf(_direction(theta, phi))) * math.sin(theta)

    total, _ = integrate.dblquad(integrand, 0, np.pi / 4, 0, np.pi / 2, epsabs=1e-12, epsrel=1e-12)
    assert total == pytest.approx(1.0, abs=1e-10)
    # the rest of the sphere carries nothing (the pdf is 0 outside W)
    rest, _ = integrate.dblquad(integrand, np.pi / 4, 2 * np.pi, 0, np.pi, epsabs=1e-12)
    assert rest == 0.0


def test_pdf_integrates_to_one_monte_carlo():
    # Uniform directions on the whole sphere: 4 pi mean(pdf) estimates the integral, 1.
    rng = np.random.default_rng(2024)
    d = rng.standard_normal((1_000_000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    values = 4 * np.pi * square_to_cosine_wedge_pdf(d)
    stderr = values.std() / math.sqrt(len(values))
    assert abs(values.mean() - 1) < 5 * stderr
    assert np.count_nonzero(values) == pytest.approx(len(values) / 16, rel=0.02)  # W is 1/16 of the sphere


def test_pdf_zero_outside_wedge():
    # Interior points of the seven other images of W, and of the lower hemisphere.
    rng = np.random.default_rng(3)
    theta, phi = np.arccos(rng.uniform(0.01, 0.99, 100)), rng.uniform(0.01, np.pi / 4 - 0.01, 100)
    w = _direction(theta, phi).T
    assert np.all(square_to_cosine_wedge_pdf(w) > 0)
    for k in range(1, 8):
        assert np.all(square_to_cosine_wedge_pdf(w @ WEDGE_MAPS[k]) == 0), k
    below = w * [1, 1, -1]
    assert np.all(square_to_cosine_wedge_pdf(below) == 0)
    # W is closed: its edges phi = 0 and phi = pi/4 are inside, just beyond them is not
    edge = np.array([[0.6, 0.0, 0.8], [0.6, 0.6, math.sqrt(0.28)]])
    np.testing.assert_allclose(square_to_cosine_wedge_pdf(edge), 8 * edge[:, 2] / np.pi, rtol=1e-15)
    beyond = np.array([[0.6, -1e-300, 0.8], [0.6, 0.6 + 1e-16, math.sqrt(0.28)], [1.0, 0.0, -1e-300]])
    assert np.all(square_to_cosine_wedge_pdf(beyond) == 0)
    assert not np.any(np.signbit(square_to_cosine_wedge_pdf(np.array([[0.6, 0.0, -0.8], [0.0, 0.6, 0.8]]))))


def test_forward_chi2():
    # The forward map's samples against its pdf.  The bin probabilities that chi2_test
    # integrates from the pdf are checked against the closed form of the integral first:
    # P(bin) = (8/pi) dphi (c1^2 - c0^2)/2 on W's bins, 0 elsewhere.
    rng = np.random.default_rng(20261130)
    d = square_to_cosine_wedge(rng.random((N_CHI2, 2)))
    res = chi2_test(
        d, square_to_cosine_wedge_pdf, "hemisphere", bins=BINS, significance=SIGNIFICANCE, test_count=CHI2_TESTS
    )
    dphi, c = 2 * np.pi / BINS[0], np.linspace(0, 1, BINS[1] + 1)
    closed_form = np.zeros(BINS)
    closed_form[32:40] = (8 / np.pi) * dphi * np.diff(c**2) / 2
    np.testing.assert_allclose(res.expected / N_CHI2, closed_form, rtol=1e-12, atol=1e-15)
    assert res.dof == 8 * 16 - 1
    assert res.passed, str(res)
    assert_power(res, MUST_DETECT_W)


def test_chi2_has_power():
    # A plausible bug, r = u instead of sqrt(u) (uniform in radius, not in area), is rejected.
    rng = np.random.default_rng(1)
    u, v = rng.random((2, N_CHI2))
    phi = v * np.pi / 4
    d = np.stack([u * np.cos(phi), u * np.sin(phi), np.sqrt(1 - u * u)], axis=-1)
    res = chi2_test(
        d, square_to_cosine_wedge_pdf, "hemisphere", bins=BINS, significance=SIGNIFICANCE, test_count=CHI2_TESTS
    )
    assert not res.passed and res.p_value < 1e-12


# --- the 8-fold symmetrisation ------------------------------------------------------------


def test_wedge_maps_are_the_signed_permutations_keeping_z():
    expected = set()
    for swap, sx, sy in itertools.product((False, True), (1, -1), (1, -1)):
        m = np.zeros((3, 3), dtype=int)
        src = (1, 0) if swap else (0, 1)
        m[src[0], 0], m[src[1], 1], m[2, 2] = sx, sy, 1  # row vectors: (p @ m)[j] = sign * p[src[j]]
        expected.add(m.tobytes())
    assert WEDGE_MAPS.shape == (8, 3, 3)
    assert {np.asarray(m, dtype=int).tobytes() for m in WEDGE_MAPS} == expected
    # the order documented in WEDGE_MAPS's docstring (rows P0 and P1 of the paper's Table 1)
    p = np.array([1, 2, 3])
    images = [tuple(int(c) for c in p @ m) for m in WEDGE_MAPS]
    assert images == [(1, 2, 3), (-1, 2, 3), (-1, -2, 3), (1, -2, 3), (2, 1, 3), (-2, 1, 3), (-2, -1, 3), (2, -1, 3)]
    assert not WEDGE_MAPS.flags.writeable


def test_wedge_images_tile_the_hemisphere():
    # Almost every direction of the upper hemisphere lies in exactly one image W @ M[k]: its
    # preimage d @ M[k].T (M is orthogonal) is in W for exactly one k.  Hence the symmetrised
    # density (1/8) sum_k pdf_W(d @ M[k].T) is cos(theta)/pi, pointwise.
    rng = np.random.default_rng(4)
    d = rng.standard_normal((100_000, 3))
    d[:, 2] = np.abs(d[:, 2])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    pre = np.einsum("nj,kij->kni", d, WEDGE_MAPS.astype(np.float64))  # d @ M[k].T
    assert np.all(_in_wedge(pre).sum(axis=0) == 1)
    symmetrised = np.mean([square_to_cosine_wedge_pdf(p) for p in pre], axis=0)
    np.testing.assert_allclose(symmetrised, _cosine_hemisphere_pdf(d), rtol=1e-15)


def test_symmetrised_sampler_chi2_cosine():
    # A uniformly chosen member of the 8 maps applied to the wedge point: cos(theta)/pi.
    rng = np.random.default_rng(8)
    d = _symmetrise(square_to_cosine_wedge(rng.random((N_CHI2, 2))), rng)
    res = chi2_test(
        d, _cosine_hemisphere_pdf, "hemisphere", bins=BINS, significance=SIGNIFICANCE, test_count=CHI2_TESTS
    )
    assert res.dof == BINS[0] * BINS[1] - 1
    assert res.passed, str(res)
    assert_power(res, MUST_DETECT_W)
    assert d[:, 2].mean() == pytest.approx(2 / 3, abs=5 * math.sqrt(1 / 18 / N_CHI2))  # E[cos] = 2/3


def test_group_of_eight_estimates_irradiance():
    # Groups of 8 sharing a base point: each image weighs 1 / (cos(theta)/pi), the same for all 8,
    # and the group mean is an unbiased estimate.  f = max(n . w, 0) with n tilted (its integral
    # over the hemisphere z >= 0 is cut by the horizon) against scipy's quadrature.
    n = np.array([0.3, -0.5, math.sqrt(1 - 0.34)])

    def f(w):
        return np.maximum(w @ n, 0.0)

    exact, _ = integrate.dblquad(
        lambda t, p: float(f(_direction(t, p))) * math.sin(t), 0, 2 * np.pi, 0, np.pi / 2, epsabs=1e-10
    )
    rng = np.random.default_rng(6)
    base = square_to_cosine_wedge(rng.random((20_000, 2)))
    images = np.einsum("ni,kij->nkj", base, WEDGE_MAPS.astype(np.float64))  # (m, 8, 3)
    assert np.all(images[:, :, 2] == base[:, None, 2])
    weights = 1 / _cosine_hemisphere_pdf(images)
    per_group = np.mean(f(images) * weights, axis=1)
    stderr = per_group.std() / math.sqrt(len(per_group))
    assert abs(per_group.mean() - exact) < 5 * stderr


# --- numba, vectorisation, dtypes, validation --------------------------------------------


@njit
def _numba_triple(uv):
    out = np.empty((uv.shape[0], 6))
    for i in range(uv.shape[0]):
        x, y, z = cosine_wedge_point(uv[i, 0], uv[i, 1])
        u, v = cosine_wedge_uv(x, y, z)
        out[i, 0], out[i, 1], out[i, 2] = x, y, z
        out[i, 3] = cosine_wedge_density(x, y, z)
        out[i, 4], out[i, 5] = u, v
    return out


def test_numba_matches_numpy():
    # The register_jitable functions inside a scalar @njit kernel against the numpy path: the same
    # formulas, but the kernel's sin, cos, atan2 are libm's and numpy's may be its own SIMD versions
    # (AVX2, AVX-512/SVML: they differ by 2 ulps on an Intel AVX-512 machine).  The bound, from the
    # error model of tests/references.py (E = ELEMENTARY_ULPS per function, relative errors in eps):
    # - r = sqrt(u), phi = v pi/4, z = sqrt(1 - u) are correctly rounded: the same bits, hence the
    #   density 8 z / pi too (inside W on both paths: y is clamped into [0, x]);
    # - x = r cos(phi), y = r sin(phi): E + 1/2 per path, so the paths differ by 2E + 1;
    # - u' = x^2 + y^2 (both terms >= 0): 2 (E + 1/2) + 1/2 + 1/2 = 2E + 2 per path: 4E + 4;
    # - v' = (4/pi) atan2(y, x): atan2's condition numbers are |x y| / (r^2 atan2) <= 1 for x's and
    #   y's relative errors, so (E + 1/2) + (E + 1/2) + E + 1/2 = 3E + 3/2 per path: 6E + 3.
    # (Measured on the AMD EPYC reference machine: the paths agree bit for bit.)
    values = np.array([0.0, 1e-300, 0.5, 1.0])
    corners = np.array(np.meshgrid(values, values)).reshape(2, -1).T
    uv = np.concatenate([corners, _interior_uv(10_000, seed=9, margin=0.0)])
    got = _numba_triple(uv)
    d = square_to_cosine_wedge(uv)
    expected = np.column_stack([d, square_to_cosine_wedge_pdf(d), cosine_wedge_to_square(d)])
    e = ELEMENTARY_ULPS
    for column, k in enumerate([2 * e + 1, 2 * e + 1, 0, 0, 4 * e + 4, 6 * e + 3]):  # x, y, z, pdf, u', v'
        assert_within_eps(got[:, column], expected[:, column], k)
    # and outside W the kernel's density is 0 as well
    assert njit(lambda x, y, z: cosine_wedge_density(x, y, z))(0.0, 0.6, 0.8) == 0.0


def test_vectorised_equals_scalar():
    uv = _interior_uv(20, seed=3)
    batch = square_to_cosine_wedge(uv)
    for i, point in enumerate(uv):
        assert np.array_equal(square_to_cosine_wedge(point), batch[i])
        assert np.array_equal(cosine_wedge_to_square(batch[i]), cosine_wedge_to_square(batch)[i])
        assert square_to_cosine_wedge_pdf(batch[i]) == square_to_cosine_wedge_pdf(batch)[i]
    assert square_to_cosine_wedge(uv.reshape(4, 5, 2)).shape == (4, 5, 3)
    assert square_to_cosine_wedge_pdf(batch.reshape(4, 5, 3)).shape == (4, 5)
    assert cosine_wedge_to_square(batch.reshape(4, 5, 3)).shape == (4, 5, 2)
    # the elementwise functions on arrays are the array functions
    np.testing.assert_array_equal(np.stack(cosine_wedge_point(uv[:, 0], uv[:, 1]), axis=-1), batch)


def test_float32_close_to_float64():
    uv = _interior_uv(1000, seed=4).astype(np.float32)
    d32 = square_to_cosine_wedge(uv)
    assert d32.dtype == np.float32
    np.testing.assert_allclose(d32, square_to_cosine_wedge(uv.astype(np.float64)), rtol=0, atol=1e-7)
    assert square_to_cosine_wedge_pdf(d32).dtype == np.float32
    np.testing.assert_allclose(
        square_to_cosine_wedge_pdf(d32), square_to_cosine_wedge_pdf(d32.astype(np.float64)), rtol=2e-7
    )
    assert cosine_wedge_to_square(d32).dtype == np.float32


def test_integer_input_gives_float64():
    assert square_to_cosine_wedge([1, 0]).dtype == np.float64
    assert square_to_cosine_wedge_pdf([1, 0, 0]).dtype == np.float64
    assert cosine_wedge_to_square([0, 0, 1]).dtype == np.float64


@pytest.mark.parametrize(
    "call, error, match",
    [
        (lambda: square_to_cosine_wedge([0.5, 1.5]), ValueError, r"'uv' must lie in the closed unit square"),
        (lambda: square_to_cosine_wedge([-1e-18, 0.5]), ValueError, r"'uv' must lie"),
        (lambda: square_to_cosine_wedge([np.nan, 0.5]), ValueError, r"'uv' must lie"),
        (lambda: square_to_cosine_wedge([0.5, 0.5, 0.5]), ValueError, r"'uv' must have shape \(\.\.\., 2\)"),
        (lambda: square_to_cosine_wedge(0.5), ValueError, r"'uv' must have shape"),
        (lambda: square_to_cosine_wedge([["a", "b"]]), TypeError, r"'uv'"),
        (lambda: square_to_cosine_wedge_pdf([0.0, 1.0]), ValueError, r"'d' must have shape \(\.\.\., 3\)"),
        (lambda: square_to_cosine_wedge_pdf([0.0, np.inf, 1.0]), ValueError, r"'d' must be finite"),
        (lambda: square_to_cosine_wedge_pdf("xyz"), TypeError, r"'d'"),
        (lambda: cosine_wedge_to_square([0.0, 0.6, 0.8]), ValueError, r"'d' must lie in the wedge W"),
        (lambda: cosine_wedge_to_square([0.6, -0.1, 0.79]), ValueError, r"'d' must lie in the wedge W"),
        (lambda: cosine_wedge_to_square([0.6, 0.0, -0.8]), ValueError, r"'d' must lie in the wedge W"),
        (lambda: cosine_wedge_to_square([[0.6, 0.0, np.nan]]), ValueError, r"'d' must be finite"),
    ],
)
def test_bad_input(call, error, match):
    with pytest.raises(error, match=match):
        call()


# --- the scalar functions still compile in kernels -----------------------------------------------------------------


def test_scalar_functions_still_compile_in_kernels():
    from numba import njit

    @njit
    def kernel(u, v):
        x, y, z = warps.cosine_wedge_point(u, v)
        t, b = frames.frame_rows(x, y, z)
        return z, t[0], warps.cosine_wedge_density(x, y, z), warps.cosine_wedge_uv(x, y, z)[0]

    z, t0, density, u = kernel(0.75, 0.3)
    assert z == 0.5 and abs(density - 4 / math.pi) < 1e-15 and abs(u - 0.75) < 1e-15
    assert t0 == frames.frame_rows(*warps.cosine_wedge_point(0.75, 0.3))[0][0]


@pytest.mark.parametrize(
    "call, error, named",
    [
        (lambda: warps.cosine_wedge_point(-1.0, 0.4), ValueError, "'u'"),
        (lambda: warps.cosine_wedge_point(0.5, math.nan), ValueError, "'v'"),
        (lambda: warps.cosine_wedge_density(None, 0.0, 1.0), TypeError, "'x'"),
        (lambda: warps.cosine_wedge_density(0.0, 0.0, 2.0), ValueError, "'x, y, z'"),
        (lambda: warps.cosine_wedge_uv(0.0, 0.6, 0.8), ValueError, "'x', 'y', 'z'"),
    ],
)  # fmt: skip
def test_wrong_types_and_values_name_the_argument(call, error, named):
    raises_naming(call, error, named)
