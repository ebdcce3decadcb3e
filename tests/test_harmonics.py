"""Spherical harmonics and polynomials (symsphere.harmonics): orthonormality, known
values, exact moments and the cubic harmonics.

All tests are deterministic; quadratures are Gauss-Legendre in cos(t) about the
z axis x trapezoid in the azimuth, exact for the degrees involved.
"""

import itertools
import math

import numpy as np
import pytest
from references import cap_rule, raises_naming
from scipy import special

import symsphere as ss
from symsphere import harmonics
from symsphere import harmonics as H
from symsphere import integrands as I

Z_AXIS = np.array([0.0, 0.0, 1.0])


def _base_points(k=64, seed=0):
    return ss.square_to_triangle(np.random.default_rng(seed).random((k, 2)))


# --- spherical harmonics ----------------------------------------------------------


def test_sh_orthonormal():
    # GL with 20 nodes in z is exact for degree <= 39 and the 40-point trapezoid for
    # trigonometric degree < 40: products of two l <= 8 harmonics are integrated exactly.
    d, w = cap_rule(Z_AXIS, -1, 1, 20, 40)
    basis = H.real_sh_basis(8, d)
    gram = (basis * w[:, None]).T @ basis
    assert np.abs(gram - np.eye(81)).max() < 1e-12


def test_sh_known_values():
    d = np.random.default_rng(1).standard_normal((50, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    x, y, z = d.T
    c0, c1 = 0.5 / np.sqrt(np.pi), np.sqrt(3 / (4 * np.pi))
    np.testing.assert_allclose(H.real_sh(0, 0, d), c0, rtol=1e-15)
    np.testing.assert_allclose(H.real_sh(1, -1, d), c1 * y, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(H.real_sh(1, 0, d), c1 * z, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(H.real_sh(1, 1, d), c1 * x, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(H.real_sh(2, -2, d), 0.5 * np.sqrt(15 / np.pi) * x * y, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(H.real_sh(2, 0, d), 0.25 * np.sqrt(5 / np.pi) * (3 * z * z - 1), rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(H.real_sh(3, -2, d), 0.5 * np.sqrt(105 / np.pi) * x * y * z, rtol=1e-13, atol=1e-15)
    # the basis agrees with the single evaluations, and sh_polynomial with both
    basis = H.real_sh_basis(8, d)
    for l in range(9):
        for m in range(-l, l + 1):
            np.testing.assert_allclose(basis[:, l * l + l + m], H.real_sh(l, m, d), rtol=0, atol=1e-15)
            np.testing.assert_allclose(
                H.evaluate_polynomial(H.sh_polynomial(l, m), d), H.real_sh(l, m, d), rtol=0, atol=1e-13
            )


def test_sh_addition_theorem():
    # sum_m Y_lm(d)^2 = (2l + 1)/(4 pi) for every direction: checks the normalisation per degree.
    d = np.random.default_rng(2).standard_normal((100, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    basis = H.real_sh_basis(8, d)
    for l in range(9):
        np.testing.assert_allclose(
            (basis[:, l * l : (l + 1) ** 2] ** 2).sum(axis=1), (2 * l + 1) / (4 * np.pi), rtol=1e-13
        )


# --- moments and cubic harmonics ---------------------------------------------------


@pytest.mark.parametrize("domain", ["sphere", "hemisphere"])
def test_monomial_integrals(domain):
    d, w = cap_rule(Z_AXIS, -1 if domain == "sphere" else 0, 1, 16, 32)
    for a, b, c in itertools.product(range(8), repeat=3):
        quad = np.sum(d[:, 0] ** a * d[:, 1] ** b * d[:, 2] ** c * w)
        assert H.monomial_integral(a, b, c, domain) == pytest.approx(quad, rel=1e-13, abs=1e-14), (a, b, c)
        # the Gamma-function form, written independently
        g = special.gamma
        if a % 2 or b % 2 or (domain == "sphere" and c % 2):
            expected = 0.0
        else:
            expected = g((a + 1) / 2) * g((b + 1) / 2) * g((c + 1) / 2) / g((a + b + c + 3) / 2)
            expected *= 2 if domain == "sphere" else 1
        assert H.monomial_integral(a, b, c, domain) == pytest.approx(expected, rel=1e-13, abs=1e-300)


def _laplacian(coeffs):
    out = {}
    for (a, b, c), k in coeffs.items():
        for i, e in enumerate((a, b, c)):
            if e >= 2:
                key = [a, b, c]
                key[i] -= 2
                out[tuple(key)] = out.get(tuple(key), 0.0) + k * e * (e - 1)
    return {key: v for key, v in out.items() if v != 0}


@pytest.mark.parametrize("degree", [4, 6, 8])
def test_cubic_harmonics(degree):
    coeffs = H.cubic_harmonic(degree)
    assert all(sum(key) == degree for key in coeffs)  # homogeneous
    assert _laplacian(coeffs) == {}  # harmonic, exactly
    p = _base_points(32, seed=degree)
    values = H.evaluate_polynomial(coeffs, ss.orbit(p))  # invariant under the 48 maps
    np.testing.assert_allclose(values, np.broadcast_to(values[:, :1], values.shape), rtol=1e-13, atol=1e-13)
    # a pure degree-l harmonic: orthogonal to every Y_l'm' with l' != l (l' <= 8), by exact quadrature
    d, w = cap_rule(Z_AXIS, -1, 1, 20, 40)
    basis = H.real_sh_basis(8, d)
    f = H.evaluate_polynomial(coeffs, d)
    proj = (basis * w[:, None]).T @ f
    degrees = np.array([math.isqrt(k) for k in range(81)])
    assert np.abs(proj[degrees != degree]).max() < 1e-12 * np.sqrt(np.sum(f * f * w))
    assert H.polynomial_integral(coeffs) == 0.0


def test_the_building_blocks_have_one_home():
    # integrands uses the harmonics but does not list them: their one public home is symsphere.harmonics
    assert not set(H.__all__) & set(I.__all__)


# --- bad input -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "call, error, word",
    [
        (lambda: H.real_sh(-1, 0, [0, 0, 1]), ValueError, "'l'"),
        (lambda: H.real_sh(2, 3, [0, 0, 1]), ValueError, "'m'"),
        (lambda: H.real_sh(1.5, 0, [0, 0, 1]), TypeError, "'l'"),
        (lambda: H.real_sh(2, None, [0, 0, 1]), TypeError, "'m'"),
        (lambda: H.real_sh(2, 0, [0, 1]), ValueError, "'d'"),
        (lambda: H.real_sh_basis(-2, [0, 0, 1]), ValueError, "'lmax'"),
        (lambda: H.sh_polynomial(3, -4), ValueError, "'m'"),
        (lambda: H.monomial_integral(-1, 0, 0), ValueError, "'a'"),
        (lambda: H.monomial_integral(0, 1.0, 0), TypeError, "'b'"),
        (lambda: H.monomial_integral(0, 0, 2, "torus"), ValueError, "domain"),
        (lambda: H.polynomial_integral([1, 2]), TypeError, "'coeffs'"),
        (lambda: H.polynomial_integral({(1, 2): 1.0}), ValueError, "'coeffs'"),
        (lambda: H.evaluate_polynomial({(0, 0, -2): 1.0}, [0, 0, 1]), ValueError, "'c'"),
        (lambda: H.cubic_harmonic(5), ValueError, "'degree'"),
    ],
)
def test_bad_input(call, error, word):
    with pytest.raises(error, match=word):
        call()


# --- wrong types and values name the argument ----------------------------------------------------------------------


@pytest.mark.parametrize(
    "call, error, named",
    [
        (lambda: harmonics.polynomial_integral({(2, 0, 0): math.inf}), ValueError, "'coeffs'"),
        (lambda: harmonics.polynomial_integral({(2, 0, 0): math.nan}), ValueError, "'coeffs'"),
        (lambda: harmonics.polynomial_integral({(2, 0, 0): "1"}), TypeError, "'coeffs'"),
    ],
)  # fmt: skip
def test_wrong_types_and_values_name_the_argument(call, error, named):
    raises_naming(call, error, named)
