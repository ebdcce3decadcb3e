"""symsphere.quality: the cap discrepancy (against independent references), RMSE and the slope fit."""

import math

import numpy as np
import pytest

from symsphere import quality
from symsphere.quality import cap_discrepancy, cap_discrepancy_squared, fit_slope, rmse


def _unit(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _rotation(angle_xyz):
    """A rotation matrix from three angles (independent of symsphere and scipy)."""
    a, b, c = angle_xyz
    rx = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
    rz = np.array([[math.cos(c), -math.sin(c), 0], [math.sin(c), math.cos(c), 0], [0, 0, 1]])
    return rz @ ry @ rx


# --- cap discrepancy -----------------------------------------------------------------


def _brute_force_cap_discrepancy_squared(points, weights=None, n_z=200, n_phi=400):
    """D² = ∫_{-1}^{1} ∫_{S²} (Σ w_i 1[x_i·c ≥ t] − (1 − t)/2)² dσ(c) dt, straight from the definition.

    For a fixed cap centre c the integrand is piecewise quadratic in t (the count changes at
    t = x_i·c), so the t-integral is exact: with g(t) = W − 1/2 + t/2 on an interval where the
    weight inside is W, ∫ g² dt = (2/3)(g(b)³ − g(a)³).  The centres c are integrated by
    Gauss–Legendre in z times the midpoint rule in φ; the integrand is continuous in c with kinks,
    so the rule converges like h².
    """
    x = _unit(points)
    n = len(x)
    w = np.full(n, 1.0 / n) if weights is None else np.asarray(weights, dtype=np.float64)
    z, gauss = np.polynomial.legendre.leggauss(n_z)
    phi = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    zz, pp = np.meshgrid(z, phi, indexing="ij")
    r = np.sqrt(1 - zz**2)
    centres = np.stack([r * np.cos(pp), r * np.sin(pp), zz], axis=-1).reshape(-1, 3)
    quadrature = (gauss[:, None] * np.full(n_phi, 2 * np.pi / n_phi)[None, :]).reshape(-1) / (4 * np.pi)
    total = 0.0
    for start in range(0, len(centres), 20000):
        c = centres[start : start + 20000]
        s = c @ x.T
        order = np.argsort(s, axis=1)
        s_sorted = np.take_along_axis(s, order, axis=1)
        w_sorted = w[order]
        # tail[:, k]: weight of the points with sorted index >= k, i.e. inside the cap for t in (b_k, b_k+1)
        tail = np.concatenate([np.cumsum(w_sorted[:, ::-1], axis=1)[:, ::-1], np.zeros((len(c), 1))], axis=1)
        edges = np.concatenate([-np.ones((len(c), 1)), np.clip(s_sorted, -1, 1), np.ones((len(c), 1))], axis=1)
        low = tail - 0.5 + edges[:, :-1] / 2
        high = tail - 0.5 + edges[:, 1:] / 2
        total += quadrature[start : start + 20000] @ ((2.0 / 3.0) * (high**3 - low**3)).sum(axis=1)
    return total


def test_stolarsky_matches_the_definition_for_the_octahedron():
    octahedron = np.vstack([np.eye(3), -np.eye(3)]) @ _rotation((0.3, 0.7, 1.1)).T
    exact = 1 / 3 - (24 * math.sqrt(2) + 12) / (4 * 36)  # 4 neighbours at sqrt 2 and one at 2, per point
    assert cap_discrepancy_squared(octahedron) == pytest.approx(exact, rel=1e-13)
    # Measured: the quadrature agrees to ~1e-6 relative; the tolerance leaves room.
    assert _brute_force_cap_discrepancy_squared(octahedron) == pytest.approx(exact, rel=2e-5)


@pytest.mark.parametrize("weighted", [False, True])
def test_stolarsky_matches_the_definition_for_random_points(weighted):
    rng = np.random.default_rng(20)
    x = _unit(rng.standard_normal((20, 3)))
    w = rng.uniform(0.5, 1.5, 20) / 20 if weighted else None  # weights need not sum to 1
    brute = _brute_force_cap_discrepancy_squared(x, w)
    assert cap_discrepancy_squared(x, w) == pytest.approx(brute, rel=2e-5)  # measured: 2e-7


def test_discrepancy_is_rotation_invariant_and_agrees_with_dense_distances():
    rng = np.random.default_rng(3)
    x = _unit(rng.standard_normal((301, 3)))  # odd N: the paired rows of the kernel meet in the middle
    w = rng.random(301)
    dense = np.linalg.norm(x[:, None, :] - x[None, :, :], axis=-1)
    expected = w.sum() ** 2 - 0.25 * (w @ dense @ w) - 4 / 3 * w.sum() + 2 / 3
    assert cap_discrepancy_squared(x, w) == pytest.approx(expected, rel=1e-12)
    rotated = x @ _rotation((1.0, -0.4, 2.2)).T
    assert cap_discrepancy_squared(rotated, w) == pytest.approx(expected, rel=1e-10)
    assert cap_discrepancy(x) == pytest.approx(math.sqrt(cap_discrepancy_squared(x)))


def test_expected_discrepancy_of_iid_uniform_points_is_one_over_3n():
    # E|x - y| = 4/3 for independent uniform x, y on S², and the N diagonal terms vanish, so
    # E D² = 1/3 - (1/(4N²)) N(N - 1) 4/3 = 1/(3N).
    rng = np.random.default_rng(11)
    n, sets = 50, 400
    values = np.array([cap_discrepancy_squared(_unit(rng.standard_normal((n, 3)))) for _ in range(sets)])
    standard_error = values.std(ddof=1) / math.sqrt(sets)
    assert abs(values.mean() - 1 / (3 * n)) < 4 * standard_error


def test_expected_weighted_discrepancy_of_importance_samples():
    # x_i i.i.d. with density p = (1 + z/2)/(4 pi), weights w_i = 1/(N 4 pi p(x_i)): E sum w = 1,
    # E sum_{i != j} w_i w_j |x_i - x_j| = (1 - 1/N) 4/3 and Var(sum w) = (E_sigma[1/(1 + z/2)] - 1)/N
    # = (ln 3 - 1)/N, so E D_w² = (ln 3 - 1)/N + 1/(3N).
    rng = np.random.default_rng(12)
    n, sets = 40, 400
    values = []
    for _ in range(sets):
        x = np.empty((0, 3))
        while len(x) < n:  # rejection sampling from the uniform density
            candidates = _unit(rng.standard_normal((2 * n, 3)))
            keep = rng.random(2 * n) < (1 + candidates[:, 2] / 2) / 1.5
            x = np.vstack([x, candidates[keep]])
        x = x[:n]
        values.append(cap_discrepancy_squared(x, 1 / (n * (1 + x[:, 2] / 2))))
    values = np.array(values)
    expected = (math.log(3) - 1) / n + 1 / (3 * n)
    assert abs(values.mean() - expected) < 4 * values.std(ddof=1) / math.sqrt(sets)


def test_discrepancy_rejects_bad_input():
    with pytest.raises(ValueError, match="points"):
        cap_discrepancy_squared(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="points"):
        cap_discrepancy_squared(np.zeros((4, 3)))
    with pytest.raises(ValueError, match="weights"):
        cap_discrepancy_squared(np.eye(3), [1.0, 2.0])


# --- RMSE and slope --------------------------------------------------------------------


def test_rmse_of_synthetic_errors():
    errors = np.array([0.3, -0.4, 0.0, 1.2])
    assert rmse(2.5 + errors, 2.5) == pytest.approx(math.sqrt(np.mean(errors**2)), rel=1e-15)
    table = np.array([[1.0, 3.0], [2.0, 2.0]])
    np.testing.assert_allclose(rmse(table, 2.0), [1.0, 0.0])


def test_fit_slope_recovers_a_known_slope():
    n = 48 * 2 ** np.arange(2, 15)
    fit = fit_slope(n, 3.0 * n**-0.73)
    assert fit.slope == pytest.approx(-0.73, abs=1e-12)
    assert fit.intercept == pytest.approx(math.log(3.0), abs=1e-9)
    assert fit.standard_error < 1e-12 and fit.points == len(n)


def test_fit_slope_standard_error_is_calibrated():
    rng = np.random.default_rng(5)
    n = 48 * 2 ** np.arange(2, 15)
    z = []
    for _ in range(300):
        fit = fit_slope(n, n**-1.0 * np.exp(0.3 * rng.standard_normal(len(n))))
        z.append((fit.slope + 1.0) / fit.standard_error)
    z = np.array(z)
    # (slope - true) / se is Student t with 11 degrees of freedom: mean 0, variance 11/9.
    assert abs(z.mean()) < 4 * math.sqrt(11 / 9 / len(z))
    assert 0.8 < z.var() / (11 / 9) < 1.25


def test_fit_slope_floors_zeros_without_warnings():
    fit = fit_slope([10, 100, 1000], [1e-3, 0.0, 1e-5])  # RuntimeWarnings are errors in this suite
    assert math.isfinite(fit.slope)
    assert math.isnan(fit_slope([10, 100], [1.0, 0.1]).standard_error)
    with pytest.raises(ValueError, match="distinct"):
        fit_slope([10, 10, 10], [1.0, 2.0, 3.0])


# --- weights -------------------------------------------------------------------------------------------------------


def test_cap_discrepancy_refuses_negative_weights():
    x = np.vstack([np.eye(3), -np.eye(3)])
    with pytest.raises(ValueError, match="'weights' must be >= 0"):
        quality.cap_discrepancy(x, weights=np.array([1.0, -1, 1, 1, 1, 1]))
