"""The integrand suite: exact values against quadrature, lights, orbit averages.

All tests are deterministic (fixed seeds, deterministic quadrature); there is no
statistical test in this file.  Quadratures are adapted to each integrand:
Gauss-Legendre in cos(t) about an axis x trapezoid in the azimuth, with the
axis and the range of cos(t) chosen so that the integrand is smooth on the
region (the cap or the light cone is the whole region), and for the polygon
light a Gauss-Legendre rule on the polygon itself.
"""

import math

import numpy as np
import pytest
from references import cap_rule
from scipy import integrate, special

import symsphere
import symsphere as ss
from symsphere import harmonics as H
from symsphere import integrands as I

Z_AXIS = np.array([0.0, 0.0, 1.0])


def polygon_rule(vertices, order=24):
    """Nodes q on a convex planar polygon and area weights (fan of triangles, Duffy map)."""
    x, w = np.polynomial.legendre.leggauss(order)
    s, ws = (x + 1) / 2, w / 2
    S, T = np.meshgrid(s, s, indexing="ij")
    W = np.outer(ws, ws)
    nodes, weights = [], []
    v0 = vertices[0]
    for v1, v2 in zip(vertices[1:-1], vertices[2:], strict=False):
        q = v0 + S[..., None] * (v1 - v0) + (S * T)[..., None] * (v2 - v1)
        jac = S * np.linalg.norm(np.cross(v1 - v0, v2 - v1))
        nodes.append(q.reshape(-1, 3))
        weights.append((W * jac).ravel())
    return np.concatenate(nodes), np.concatenate(weights)


def polygon_solid_angle_rule(vertices, order=24):
    """Directions through the polygon and their solid-angle weights: dw = |q.N| / |q|^3 dA."""
    q, wa = polygon_rule(vertices, order)
    normal = np.cross(vertices[1] - vertices[0], vertices[2] - vertices[0])
    normal /= np.linalg.norm(normal)
    r = np.linalg.norm(q, axis=1)
    return q / r[:, None], wa * np.abs(q @ normal) / r**3


def lambert_brute_force(vertices, radiance=1.0, order=24):
    """L * integral over the polygon of cos(theta) cos(theta') / r^2 dA at the origin, normal z."""
    d, w = polygon_solid_angle_rule(vertices, order)
    return radiance * np.sum(np.maximum(d[:, 2], 0) * w)


def _base_points(k=64, seed=0):
    return ss.square_to_triangle(np.random.default_rng(seed).random((k, 2)))


# --- cubic harmonics as integrands (tests/test_harmonics.py: the harmonics themselves) ------


def test_cubic4_forms_agree():
    # the brief's x^4 + y^4 + z^4 - 3/5 is (2/5) times the harmonic polynomial on the sphere
    d = np.random.default_rng(3).standard_normal((100, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    np.testing.assert_allclose(
        I.INTEGRANDS["cubic4"].f(d), 0.4 * H.evaluate_polynomial(H.cubic_harmonic(4), d), atol=1e-14
    )


# --- every integrand: exact value by adapted quadrature ---------------------------


def _adapted_quadrature(g):
    """Quadrature of g over its domain by a rule adapted to g's (dis)continuities."""
    p = g.params
    if g.name == "quad_light":
        d, w = polygon_solid_angle_rule(p["vertices"], order=32)
        assert np.all(g.f(d) > 0)  # every node is inside the light
        return np.sum(g.f(d) * w)
    if g.name.startswith("cap"):
        d, w = cap_rule(p["axis"], p["cos_alpha"], 1, 8, 16)
    elif g.name == "sphere_light":
        d, w = cap_rule(p["center"], p["cos_alpha"], 1, 32, 64)
    elif g.name == "phong":
        d, w = cap_rule(p["direction"], 0, 1, 32, 8)  # a polynomial of degree 20 in cos t
    elif g.name == "phong_hemisphere":
        # smooth up to a C^19 kink where w.r = 0; the lobe is ~1e-9 of its peak there
        d, w = cap_rule(Z_AXIS, 0, 1, 400, 400)
    elif g.domain == "sphere":
        d, w = cap_rule(Z_AXIS, -1, 1, 48, 96)
    else:
        d, w = cap_rule(Z_AXIS, 0, 1, 48, 96)
    return np.sum(g.f(d) * w)


@pytest.mark.parametrize("name", list(I.INTEGRANDS))
def test_exact_value(name):
    g = I.INTEGRANDS[name]
    quad = _adapted_quadrature(g)
    # measured: at most 3.8e-14 relative (and 5.2e-14 absolute where exact = 0)
    assert abs(quad - g.exact) <= 1e-12 * max(1.0, abs(g.exact)), (quad, g.exact)


def test_discontinuous_integrands_need_adapted_quadrature():
    # The same rule about the pole, for comparison: the cap's value is off by 3.9e-3,
    # which is why the test above integrates in coordinates about the cap.
    g = I.INTEGRANDS["cap"]
    d, w = cap_rule(Z_AXIS, -1, 1, 48, 96)
    assert abs(np.sum(g.f(d) * w) - g.exact) > 1e-5


def test_integrand_conventions():
    rng = np.random.default_rng(4)
    d = rng.standard_normal((7, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    for g in I.suite():
        assert g.domain in ("sphere", "hemisphere") and isinstance(g.exact, float) and g.description
        out = g.f(d)
        assert out.shape == (7,) and out.dtype == np.float64 and np.all(np.isfinite(out))
        assert g(d[:1]).shape == (1,)
        with pytest.raises(AttributeError):
            g.exact = 0.0  # frozen
    assert [g.name for g in I.suite("sphere")] + [g.name for g in I.suite("hemisphere")] == sorted(
        I.INTEGRANDS, key=lambda k: (I.INTEGRANDS[k].domain != "sphere", list(I.INTEGRANDS).index(k))
    )
    assert len(I.suite()) == len(I.INTEGRANDS)
    # the brief's minimum: SH of degrees 1-8, invariant ones of degree 4/6/8, shifted ones, and the rest
    sh_degrees = {g.params["l"] for g in I.suite("sphere") if "l" in g.params}
    assert sh_degrees == set(range(1, 9))
    assert {"cubic4", "cubic6", "cubic8", "phong", "cap", "sphere_light", "quad_light", "exp"} <= set(I.INTEGRANDS)


# --- lights ------------------------------------------------------------------------------


def test_lambert_against_brute_force():
    g = I.INTEGRANDS["quad_light"]
    vertices, radiance = g.params["vertices"], g.params["radiance"]
    assert lambert_brute_force(vertices, radiance, order=32) == pytest.approx(g.exact, rel=1e-13)
    # other convex polygons above the horizon: random triangles, a tilted pentagon; either orientation
    rng = np.random.default_rng(5)
    for _ in range(5):
        tri = rng.uniform(-1, 1, (3, 3)) + [0, 0, 1.6]
        assert I.lambert_irradiance(tri, radiance=1.7) == pytest.approx(lambert_brute_force(tri, 1.7), rel=1e-12)
        assert I.lambert_irradiance(tri[::-1]) == pytest.approx(I.lambert_irradiance(tri), rel=1e-14)
    angles = 2 * np.pi * np.arange(5) / 5
    pentagon = np.stack([0.8 * np.cos(angles), 0.8 * np.sin(angles), 0.3 * np.cos(angles)], axis=1) + [0.5, 0.2, 1.0]
    assert I.lambert_irradiance(pentagon) == pytest.approx(lambert_brute_force(pentagon), rel=1e-12)
    # with a tilted normal: the same formula, brute force with cos(theta) = w.n
    n = np.array([0.2, -0.1, 1.0]) / np.linalg.norm([0.2, -0.1, 1.0])
    d, w = polygon_solid_angle_rule(pentagon)
    assert I.lambert_irradiance(pentagon, normal=n) == pytest.approx(np.sum((d @ n) * w), rel=1e-12)


def test_lambert_monte_carlo():
    # Plain Monte Carlo of the integrand itself (10^6 uniform hemisphere directions, seed 6):
    # within 5 standard errors of Lambert's value.
    g = I.INTEGRANDS["quad_light"]
    u = np.random.default_rng(6).random((1_000_000, 2))
    r = np.sqrt(1 - u[:, 0] ** 2)
    d = np.stack([r * np.cos(2 * np.pi * u[:, 1]), r * np.sin(2 * np.pi * u[:, 1]), u[:, 0]], axis=1)
    values = 2 * np.pi * g.f(d)
    assert abs(values.mean() - g.exact) < 5 * values.std() / np.sqrt(len(values))


def test_sphere_light_closed_form():
    g = I.INTEGRANDS["sphere_light"]
    p = g.params
    sin_alpha = p["radius"] / p["distance"]
    assert g.exact == pytest.approx(np.pi * p["radiance"] * sin_alpha**2 * p["center"][2], rel=1e-15)
    assert p["cos_alpha"] == pytest.approx(np.sqrt(1 - sin_alpha**2), rel=1e-15)
    # a light straight overhead: E = pi L sin^2(alpha)
    assert I.sphere_light_irradiance([0, 0, 2], 4.0, 1.0, radiance=2.0) == pytest.approx(np.pi * 2 / 16, rel=1e-15)


def _phong_hemisphere_integral(r, n):
    """Integral over z >= 0 of the normalised Phong lobe (n+1)/(2 pi) max(0, w.r)^n.

    About r, w = cos t r + sin t (cos psi e1 + sin psi e2) with e1 the unit
    vector towards the pole in the plane of r and z, so
    w_z = cos t cos(beta) + sin t sin(beta) cos psi (beta = angle of r from the
    pole).  For t > pi/2 - beta the part cos(psi) < -cot t cot(beta) lies below
    the horizon, a psi-measure of 2 acos(cot t cot(beta)).  With tau = cos t:
    integral = 1 - (n+1)/(2 pi) int_0^{sin beta} tau^n 2 acos(tau cot(beta)/sqrt(1 - tau^2)) dtau.
    """
    cos_b = float(r[2])
    sin_b = math.sqrt(max(0.0, 1.0 - cos_b * cos_b))
    if sin_b == 0:
        return 1.0
    cot_b = cos_b / sin_b

    def below(tau: float) -> float:
        k = min(1.0, tau * cot_b / math.sqrt(1.0 - tau * tau))
        return tau**n * 2.0 * math.acos(k)

    value, _ = integrate.quad(below, 0.0, sin_b, epsabs=0.0, epsrel=1e-13, limit=200)
    return float(1.0 - (n + 1) / (2.0 * math.pi) * value)


def _exp_hemisphere_integral(a):
    """Integral over z >= 0 of exp(w . a) = 2 pi int_0^1 exp(a_z z) I0(rho sqrt(1 - z^2)) dz.

    The phi integral of exp(rho s cos(phi - phi0)) is 2 pi I0(rho s) (s = sin theta).
    """
    rho = math.hypot(a[0], a[1])
    value, _ = integrate.quad(
        lambda z: math.exp(a[2] * z) * special.i0(rho * math.sqrt(max(0.0, 1.0 - z * z))),
        0.0,
        1.0,
        epsabs=0.0,
        epsrel=1e-13,
        limit=200,
    )
    return float(2.0 * math.pi * value)


def test_tabulated_hemisphere_integrals_are_the_quadratures():
    """The two tabulated exact values (no closed form) against scipy's adaptive 1D quadrature.

    Bound: quad's relative tolerance 1e-13 plus a few ulps of libm's acos/exp/I0 (which may differ between
    machines) in each of ~10^3 integrand values: 2e-13 relative.
    """
    phong, expo = I.INTEGRANDS["phong_hemisphere"], I.INTEGRANDS["exp_hemisphere"]
    assert phong.params["exponent"] == 20
    assert phong.exact == pytest.approx(_phong_hemisphere_integral(phong.params["direction"], 20), rel=2e-13, abs=0)
    assert expo.exact == pytest.approx(_exp_hemisphere_integral(expo.params["a"]), rel=2e-13, abs=0)


def test_phong_hemisphere_value():
    # the 1D formula against a brute-force rule about the pole with twice the nodes
    g = I.INTEGRANDS["phong_hemisphere"]
    d, w = cap_rule(Z_AXIS, 0, 1, 800, 800)
    assert np.sum(g.f(d) * w) == pytest.approx(g.exact, rel=1e-13)
    assert 0 < 1 - g.exact < 1e-9  # the lobe crosses the horizon only slightly


# --- orbit averages ------------------------------------------------------------------------


def test_orbit_average_of_non_invariant_degrees_is_zero():
    p = _base_points(64, seed=7)
    for l in (1, 2, 3, 5, 7):
        for m in range(-l, l + 1):
            avg = I.orbit_average(lambda d: H.real_sh(l, m, d), p)
            assert np.abs(avg).max() < 1e-13, (l, m)


def test_orbit_average_of_invariant_harmonics_is_the_function():
    p = _base_points(64, seed=8)
    for degree in (4, 6, 8):
        coeffs = H.cubic_harmonic(degree)
        f = lambda d: H.evaluate_polynomial(coeffs, d)  # noqa: E731
        np.testing.assert_allclose(I.orbit_average(f, p), f(p), rtol=1e-13, atol=1e-13)


def test_orbit_average_is_the_projection_onto_the_invariant_harmonic():
    # For degrees 4, 6, 8 the invariant subspace is one-dimensional: the orbit average of any
    # Y_lm is <Y_lm, K> K with K the normalised cubic harmonic of that degree.
    d, w = cap_rule(Z_AXIS, -1, 1, 20, 40)
    p = _base_points(16, seed=9)
    for degree in (4, 6, 8):
        coeffs = H.cubic_harmonic(degree)
        norm = np.sqrt(np.sum(H.evaluate_polynomial(coeffs, d) ** 2 * w))
        K = lambda q: H.evaluate_polynomial(coeffs, q) / norm  # noqa: E731
        for m in range(-degree, degree + 1):
            Y = lambda q: H.real_sh(degree, m, q)  # noqa: E731
            coef = np.sum(Y(d) * K(d) * w)
            np.testing.assert_allclose(I.orbit_average(Y, p), coef * K(p), rtol=0, atol=1e-13)


def test_dimension_of_invariant_harmonics():
    # The orbit average projects onto the O_h-invariant functions; on the degree-l harmonics
    # its rank is the coefficient of t^l in the Molien series 1/((1 - t^4)(1 - t^6)):
    # 1, 0, 0, 0, 1, 0, 1, 0, 1, 0, 1, 0, 2 for l = 0..12 (none for odd l or l = 2).
    p = _base_points(40, seed=12)
    molien = [sum(1 for a in range(4) for b in range(3) if 4 * a + 6 * b == l) for l in range(13)]
    for l in range(13):
        rows = np.array([I.orbit_average(lambda d, m=m: H.real_sh(l, m, d), p) for m in range(-l, l + 1)])
        sv = np.linalg.svd(rows, compute_uv=False)
        assert int(np.sum(sv > 1e-9 * max(1.0, sv[0]))) == molien[l], (l, sv)


@pytest.mark.parametrize("name", list(I.INTEGRANDS))
def test_flags(name):
    g = I.INTEGRANDS[name]
    area = 4 * np.pi if g.domain == "sphere" else 2 * np.pi
    p = _base_points(64, seed=10)
    estimates = area * I.orbit_average(g.f, p, g.domain)
    scale = max(1.0, abs(g.exact))
    if g.orbit_exact:
        np.testing.assert_allclose(estimates, g.exact, rtol=0, atol=1e-12 * scale)
    else:
        assert np.ptp(estimates) > 1e-6 * scale
    values = g.f(ss.orbit(p, g.domain).reshape(-1, 3)).reshape(len(p), -1)
    spread = np.ptp(values, axis=1)
    if g.invariant:
        assert spread.max() < 1e-12 * scale
    else:
        assert spread.max() > 1e-6 * scale


def test_hemisphere_orbit_is_the_even_extension():
    # The 24 images of p in T0 are the 48 images with z >= 0, so the hemisphere orbit
    # average of f is the sphere orbit average of f(x, y, |z|).
    p = _base_points(32, seed=11)
    for name in ("cosine", "exp_hemisphere", "sh3_0_hemisphere", "quad_light"):
        f = I.INTEGRANDS[name].f
        even = lambda d, f=f: f(np.stack([d[:, 0], d[:, 1], np.abs(d[:, 2])], axis=1))  # noqa: E731
        np.testing.assert_allclose(
            I.orbit_average(f, p, "hemisphere"), I.orbit_average(even, p), rtol=1e-14, atol=1e-15
        )


# --- bad input -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "call, error, word",
    [
        (lambda: I.lambert_irradiance([[0, 0, 1], [1, 0, 1]]), ValueError, "'vertices'"),
        (lambda: I.lambert_irradiance([[0, 0, 1], [1, 0, 1], [1, 1, -0.1]]), ValueError, "'vertices'"),
        (lambda: I.lambert_irradiance([[0, 0, 1], [1, 0, 1], [1, 1, 1]], normal=[0, 0, 0]), ValueError, "'normal'"),
        (lambda: I.lambert_irradiance([[0, 0, 1], [1, 0, 1], [1, 1, 1]], radiance=-1), ValueError, "'radiance'"),
        (lambda: I.sphere_light_irradiance([0, 0, 1], 1.0, 2.0), ValueError, "'radius'"),
        (lambda: I.sphere_light_irradiance([0, 0, 1], -1.0, 0.5), ValueError, "'distance'"),
        (lambda: I.sphere_light_irradiance([1, 0, 0.1], 2.0, 1.0), ValueError, "horizon"),
        (lambda: I.sphere_light_irradiance("up", 2.0, 1.0), TypeError, "'center'"),
        (lambda: I.orbit_average(3.0, [0.1, 0.0, 1.0]), TypeError, "'f'"),
        (lambda: I.orbit_average(np.sum, [0.1, 0.0, 1.0], "disk"), ValueError, "domain"),
        (lambda: I.suite("torus"), ValueError, "domain"),
    ],
)
def test_bad_input(call, error, word):
    with pytest.raises(error, match=word):
        call()


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda v: I.sphere_light_irradiance([0, 0, 1], v, 1.0), "distance"),  # check_positive
        (lambda v: I.sphere_light_irradiance([0, 0, 1], 2.0, 1.0, radiance=v), "radiance"),  # check_nonnegative
        (lambda v: I.lambert_irradiance([[0, 0, 1], [1, 0, 1], [0, 1, 1]], radiance=v), "radiance"),
    ],
)
@pytest.mark.parametrize("value", [10**400, -(10**400)])
def test_an_int_beyond_float64_is_a_value_error_naming_the_argument(call, name, value):
    # A number, only too large: ValueError (not the OverflowError of float(10**400)), its message short.
    with pytest.raises(ValueError, match=f"'{name}' must be a finite real number, got an integer of 401 digits"):
        call(value)


def test_orbit_average_names_p_when_its_rows_are_not_directions():
    with pytest.raises(
        ValueError, match=r"images of 'p', whose rows are far from unit directions \(a norm of 1.73e\+308\)"
    ):
        with np.errstate(over="ignore"):
            I.orbit_average(lambda d: np.exp(d[:, 0]), [[1e308] * 3])
    with pytest.raises(ValueError, match=r"^'f'"):  # at directions, the integrand is to blame
        I.orbit_average(lambda d: np.full(len(d), np.inf), [0.3, 0.2, 0.9])
    # finite values near the largest float64: their mean is finite (the sum of 48 overflowed to NaN)
    assert I.orbit_average(lambda d: np.full(len(d), 1e308), [[1e308] * 3])[0] == pytest.approx(1e308)


# --- functions of f refuse NaN and complex values ------------------------------------------------------------------


def test_functions_of_f_reject_nan_and_complex():
    from symsphere.integrands import orbit_average

    with pytest.raises(ValueError, match="'f' returned non-finite"):
        orbit_average(lambda d: np.where(d[:, 0] > 0, np.nan, 1.0), [0.3, 0.2, 0.9])
    with pytest.raises(TypeError, match="complex"):
        symsphere.integrate(lambda d: np.exp(1j * d[:, 0]), n=48, rng=1)
