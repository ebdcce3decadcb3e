"""The contract every warp of symsphere.warps keeps, run on every record of WARPS.

For each warp: the corners and edges of the square give finite points of the domain (float64 and
float32); forward and inverse are inverses (both ways); the pdf is the inverse Jacobian of the forward
map (central differences) and integrates to 1 over the domain (quadrature in the domain's own
coordinates, independent of the map); one point at a time gives what a batch gives; the numba
compilation of the elementwise formula (where the warp has one) agrees with numpy within a stated bound;
and a chi-square test of the forward map of random points against the warp's pdf.

Statistical tests: significance 0.01 for the family of CHI2_TESTS chi-square tests of this file (one per
warp), Sidak-corrected by ``chi2_test(test_count=CHI2_TESTS)``; fixed seeds.
"""

import math

import numpy as np
import pytest
from numba import njit
from references import ELEMENTARY_ULPS, assert_power, assert_within_eps
from scipy import integrate

from symsphere.stats import chi2_test
from symsphere.warps import WARPS, Warp, get_warp

NAMES = list(WARPS)
SIGNIFICANCE = 0.01
CHI2_TESTS = len(WARPS)
N_CHI2 = 100_000
# Power (tests/references.py): at 100 000 samples (about 1000 cells) the chi-square tests reject Cohen's
# w >= 0.06 with probability 99 % (asserted per test), e.g. a density 6 % off on either half of the domain:
# what they must detect is a wrong formula or convention, a large effect (as tests/test_peers.py).
MUST_DETECT_W = 0.06
AREA = {
    "sphere": 4 * math.pi,
    "hemisphere": 2 * math.pi,
    "triangle": math.pi / 12,
    "wedge": math.pi / 4,
    "disk": math.pi,
}
PAPER = {name for name in NAMES if name.endswith(("paper1", "paper2"))}  # densities diverge at a vertex
EDGE_VALUES = (0.0, 1e-300, 1e-17, 0.5, 1 - 1e-16, 1.0)
EDGE_UV = np.array([[a, b] for a in EDGE_VALUES for b in EDGE_VALUES])


def _strips(warp: Warp) -> int:
    """How many strips of the square the warp cuts along u (the scheme's bijections), else 1."""
    return {"sphere": 48, "hemisphere": 24}[warp.domain] if warp.name.startswith(("sphere_", "hemisphere_")) else 1


def _in_domain(d, domain, tol=1e-6):
    x, y = d[..., 0], d[..., 1]
    if domain == "disk":
        return np.hypot(x, y) <= 1 + tol
    z = d[..., 2]
    if domain == "sphere":
        return np.ones(d.shape[:-1], dtype=bool)
    if domain == "hemisphere":
        return z >= -tol
    if domain == "wedge":
        return (x - y >= -tol) & (y >= -tol) & (z >= -tol)
    return (z - x >= -tol) & (x - y >= -tol) & (y >= -tol)


def _domain_points(domain, n, seed):
    """Points of the domain from numpy's Gaussians, folded here (not by symsphere), away from its edges."""
    g = np.random.default_rng(seed).standard_normal((n, 3))
    d = g / np.linalg.norm(g, axis=1, keepdims=True)
    if domain == "disk":
        return (
            d[:, :2] * np.sqrt(np.random.default_rng(seed + 1).random(n))[:, None] / np.hypot(d[:, 0], d[:, 1])[:, None]
        )
    if domain == "hemisphere":
        d[:, 2] = np.abs(d[:, 2])
    elif domain == "triangle":  # z >= x >= y >= 0: the absolute values, sorted
        s = np.sort(np.abs(d), axis=1)
        d = s[:, [1, 0, 2]]
    elif domain == "wedge":  # x >= y >= 0, z >= 0
        xy = np.sort(np.abs(d[:, :2]), axis=1)[:, ::-1]
        d = np.column_stack([xy, np.abs(d[:, 2])])
    # Malley's lift z = sqrt(1 - rho^2) is ill-conditioned at the horizon (dz/drho -> inf): a 1-ulp change of
    # uv moves z by ~1e-16 / z there, so keep z away from 0.
    return d[np.abs(d[:, 2]) > 1e-3]


def _interior_uv(n, seed=0, margin=1e-3):
    return margin + (1 - 2 * margin) * np.random.default_rng(seed).random((n, 2))


def _smooth_uv(warp, n, seed):
    # Away from the kinks: u, v = 1/2 (octahedral axes), |a| + |b| = 1 (its equator), |a| = |b| (the
    # concentric sectors and the hemisphere octahedral axes), and the scheme's strip boundaries.
    uv = _interior_uv(8 * n, seed, margin=1e-3)
    a, b = 2 * uv[:, 0] - 1, 2 * uv[:, 1] - 1
    ok = (np.abs(a) > 1e-3) & (np.abs(b) > 1e-3) & (np.abs(np.abs(a) + np.abs(b) - 1) > 1e-3)
    ok &= np.abs(np.abs(a) - np.abs(b)) > 1e-3
    t = uv[:, 0] * _strips(warp)
    ok &= np.abs(t - np.round(t)) > 1e-2
    return uv[ok][:n]


def _jacobian(forward, uv, h=1e-6):
    du, dv = np.array([h, 0.0]), np.array([0.0, h])
    fu = (forward(uv + du) - forward(uv - du)) / (2 * h)
    fv = (forward(uv + dv) - forward(uv - dv)) / (2 * h)
    if fu.shape[-1] == 2:  # the disk: an area Jacobian in the plane
        return np.abs(fu[:, 0] * fv[:, 1] - fu[:, 1] * fv[:, 0])
    return np.linalg.norm(np.cross(fu, fv), axis=-1)


def test_registry():
    assert NAMES and all(get_warp(name) is WARPS[name] and WARPS[name].name == name for name in NAMES)
    for warp in WARPS.values():
        assert warp.domain in AREA and warp.orbit_size == {"triangle": 48, "wedge": 8}.get(warp.domain, 1)
        assert callable(warp.forward) and callable(warp.pdf) and callable(warp.inverse)
    with pytest.raises(ValueError, match="'name'"):
        get_warp("octahedral")
    with pytest.raises(AttributeError):
        WARPS["equal_area"].uniform = False  # frozen


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_edges_finite_and_in_domain(name, dtype):
    warp = WARPS[name]
    d = warp.forward(EDGE_UV.astype(dtype))
    assert d.dtype == dtype and np.all(np.isfinite(d))
    if warp.domain != "disk":
        np.testing.assert_allclose(np.linalg.norm(d.astype(np.float64), axis=1), 1, atol=1e-6)
    assert np.all(_in_domain(d.astype(np.float64), warp.domain, tol=1e-6))
    uv = warp.inverse(d)
    assert uv.dtype == dtype and np.all(np.isfinite(uv)) and np.all((uv >= 0) & (uv <= 1))
    pdf = warp.pdf(d)
    assert np.all(pdf >= 0)
    if name not in PAPER:  # the paper's maps: inf at their vertex, by design (tests/warps/test_triangle.py)
        assert np.all(np.isfinite(pdf))


@pytest.mark.parametrize("name", NAMES)
def test_round_trip(name):
    warp = WARPS[name]
    uv = _interior_uv(100_000, seed=1)
    if _strips(warp) > 1:  # on a strip boundary the inverse may give the neighbouring strip's point
        t = uv[:, 0] * _strips(warp)
        uv = uv[np.abs(t - np.round(t)) > 1e-9]
    np.testing.assert_allclose(warp.inverse(warp.forward(uv)), uv, rtol=0, atol=1e-12)
    # and point -> square -> point, from points that are not images of uv
    d = _domain_points(warp.domain, 20_000, seed=2)
    np.testing.assert_allclose(warp.forward(warp.inverse(d)), d, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", NAMES)
def test_pdf_is_inverse_jacobian(name):
    # pdf = 1 / |dF/du x dF/dv| by central differences: an independent check of each map's algebra.
    warp = WARPS[name]
    uv = _smooth_uv(warp, 2000, seed=4)
    rtol = 1e-6 if name in PAPER else 2e-7  # the paper's maps: larger third derivatives near their vertex
    np.testing.assert_allclose(warp.pdf(warp.forward(uv)) * _jacobian(warp.forward, uv), 1.0, rtol=rtol)


def _direction(phi, one_minus_cos):
    sin_theta = np.sqrt(one_minus_cos * (2 - one_minus_cos))
    return np.stack([sin_theta * np.cos(phi), sin_theta * np.sin(phi), 1 - one_minus_cos], axis=-1)


def _t0_integral(pdf):
    # Over T0 in (phi, s) with 1 - cos(theta) = s^2, which absorbs the paper maps' 1/sin(theta) at the pole:
    # d(omega) = 2 s ds d(phi); T0's far edge x = z is tan(theta) cos(phi) = 1.
    def cmax(phi):
        return np.cos(phi) / np.sqrt(1 + np.cos(phi) ** 2)

    total, _ = integrate.dblquad(
        lambda s, phi: float(pdf(_direction(phi, s * s))) * 2 * s,
        0, np.pi / 4, 0, lambda phi: np.sqrt(1 - cmax(phi)), epsabs=1e-11, epsrel=1e-11,
    )  # fmt: skip
    return total


def _gauss_legendre(a, b, n):
    x, w = np.polynomial.legendre.leggauss(n)
    return (b - a) / 2 * x + (a + b) / 2, (b - a) / 2 * w


@pytest.mark.parametrize("name", NAMES)
def test_pdf_integrates_to_one(name):
    warp = WARPS[name]
    if warp.domain == "triangle":
        total = _t0_integral(warp.pdf)
    elif warp.domain == "disk":  # polar Gauss-Legendre: r dr dphi
        r, wr = _gauss_legendre(0, 1, 64)
        phi, wp = _gauss_legendre(0, 2 * np.pi, 128)
        rr, pp = np.meshgrid(r, phi, indexing="ij")
        p = np.stack([rr * np.cos(pp), rr * np.sin(pp)], axis=-1).reshape(-1, 2)
        total = float(np.sum(warp.pdf(p) * (wr[:, None] * rr * wp[None, :]).ravel()))
    elif warp.domain == "wedge":  # Gauss-Legendre in phi on [0, pi/4] and in cos(theta) on [0, 1]
        phi, wp = _gauss_legendre(0, np.pi / 4, 32)
        c, wc = _gauss_legendre(0, 1, 32)
        cc, pp = np.meshgrid(c, phi, indexing="ij")
        d = _direction(pp, 1 - cc).reshape(-1, 3)
        total = float(np.sum(warp.pdf(d) * (wc[:, None] * wp[None, :]).ravel()))
    elif name in PAPER:
        # The scheme's paper densities diverge at the axes: by the 48 (24) symmetries of the scheme, checked
        # here at random directions, the integral is 48 (24) times that over T0.
        count = 48 if warp.domain == "sphere" else 24
        d = _domain_points(warp.domain, 1000, seed=5)
        base = np.sort(np.abs(d), axis=1)[:, [1, 0, 2]]
        np.testing.assert_allclose(warp.pdf(d), warp.pdf(base), rtol=1e-12)
        total = count * _t0_integral(warp.pdf)
    else:  # Gauss-Legendre in cos(theta) on [-1, 0] and [0, 1] (pdfs jump or kink at the equator) x trapezoid
        x, w = np.polynomial.legendre.leggauss(64)
        cos = np.concatenate([(x - 1) / 2, (x + 1) / 2])
        wc = np.concatenate([w, w]) / 2
        phi = 2 * np.pi * (np.arange(128) + 0.5) / 128
        cc, pp = np.meshgrid(cos, phi, indexing="ij")
        d = _direction(pp, 1 - cc).reshape(-1, 3)
        total = float(np.sum(warp.pdf(d) * (wc[:, None] * np.full(128, 2 * np.pi / 128)).ravel()))
    assert total == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize("name", NAMES)
def test_vectorised_equals_scalar(name):
    # One point at a time and a batch run the same numpy ufuncs on the same operands.  numpy may pick a
    # different loop (SIMD or not) for a batch than for one element, so the bound is the error model's
    # (tests/references.py): each path within 4 E + 4 eps of the exact value per unit-vector component
    # (at most four elementary functions of E ulps, with condition numbers <= 1, and a few rounded
    # operations), so two paths differ by 2 (4 E + 4) eps.  The wedge and the maps onto T0 are also
    # checked bit for bit in their own files.
    warp = WARPS[name]
    bound = 2 * (4 * ELEMENTARY_ULPS + 4)
    uv = _interior_uv(20, seed=3)
    batch = warp.forward(uv)
    back = warp.inverse(batch)
    density = warp.pdf(batch)
    for i, point in enumerate(uv):
        assert_within_eps(warp.forward(point), batch[i], bound, scale=1)
        assert_within_eps(warp.inverse(batch[i]), back[i], bound, scale=1)
        assert_within_eps(warp.pdf(batch[i]), density[i], bound)
    assert warp.forward(uv.reshape(4, 5, 2)).shape == (4, 5, batch.shape[-1])
    assert warp.pdf(batch.reshape(4, 5, -1)).shape == (4, 5)


def _compiled_points(point):
    @njit
    def points(uv):  # the formula is a compile-time constant of the kernel, as in the library's kernels
        out = np.empty((uv.shape[0], 3))
        for i in range(uv.shape[0]):
            x, y, z = point(uv[i, 0], uv[i, 1])
            out[i, 0], out[i, 1], out[i, 2] = x, y, z
        return out

    return points


@pytest.mark.parametrize("name", [name for name, w in WARPS.items() if w.point is not None and w.domain != "disk"])
def test_numba_matches_numpy(name):
    # The elementwise formula compiled by numba (libm's sin, cos, ...) against numpy's (its SIMD code): the
    # same operations, different elementary functions; the bound as in test_vectorised_equals_scalar.
    warp = WARPS[name]
    uv = np.concatenate([_interior_uv(10_000, seed=6), EDGE_UV])
    assert_within_eps(_compiled_points(warp.point)(uv), warp.points(uv), 2 * (4 * ELEMENTARY_ULPS + 4), scale=1)


def _lifted_disk_pdf(warp):
    # A point of the disk lifted to the hemisphere (Malley): solid angle = area / cos(theta).
    return lambda d: warp.pdf(d[:, :2]) * np.maximum(d[:, 2], 0.0)


@pytest.mark.parametrize("name", NAMES)
def test_chi2(name):
    warp = WARPS[name]
    d = warp.forward(np.random.default_rng(100 + NAMES.index(name)).random((N_CHI2, 2)))
    domain, pdf, bins = warp.domain, warp.pdf, None
    if domain == "disk":
        d = np.column_stack([d, np.sqrt(np.maximum(1 - np.sum(d * d, axis=1), 0.0))])
        domain, pdf = "hemisphere", _lifted_disk_pdf(warp)
    elif domain == "wedge":  # 64 azimuth bins of pi/32: the wedge's edges are bin edges
        domain, bins = "hemisphere", (64, 16)
    elif (
        name in PAPER and domain != "triangle"
    ):  # fold into T0 (here: absolute values, sorted), where the divergence is at a vertex
        count = 48 if domain == "sphere" else 24
        d = np.sort(np.abs(d), axis=1)[:, [1, 0, 2]]
        domain = "triangle"
        pdf = (lambda warp, count: lambda p: count * warp.pdf(p))(warp, count)
    result = chi2_test(d, pdf, domain, bins=bins, significance=SIGNIFICANCE, test_count=CHI2_TESTS)
    assert result.passed, str(result)
    assert_power(result, MUST_DETECT_W)


@pytest.mark.parametrize("name", NAMES)
def test_sample(name):
    # Warp.sample is the forward map of the documented points of the square (symsphere.points), computed in
    # float64 and cast: the same rows for every point set, in the domain, in the requested dtype.
    from symsphere.points import unit_square_points

    warp = WARPS[name]
    for points, n in (("random", 64), ("stratified", 64), ("sobol", 64)):
        d = warp.sample(n, points=points, rng=7, dtype=np.float32)
        expected = warp.forward(unit_square_points(n, points, 7)).astype(np.float32)
        assert d.dtype == np.float32 and d.shape == expected.shape
        np.testing.assert_array_equal(d, expected)
        assert np.all(_in_domain(d.astype(np.float64), warp.domain, tol=1e-6))
    with pytest.raises(ValueError, match="'n'"):
        warp.sample(0)
    with pytest.raises(ValueError, match="not a valid points"):
        warp.sample(4, points="grid")
    with pytest.raises((TypeError, ValueError), match="'dtype'"):
        warp.sample(4, dtype=np.int32)


def test_namespace_lists_each_name_once():
    # The namespace is built from the modules' __all__ (warps/__init__.py): nothing listed twice, every
    # registered warp's triple reachable there by its own name, and the records keyword-only.
    import symsphere.warps as warps

    assert len(warps.__all__) == len(set(warps.__all__))
    assert all(hasattr(warps, name) for name in warps.__all__)
    for warp in WARPS.values():
        for f in (warp.forward, warp.pdf, warp.inverse):
            assert "<locals>" in f.__qualname__ or getattr(warps, f.__name__) is f  # a map of the namespace, or
            # one bound to its method (the maps onto T0 and the scheme's bijections)
    with pytest.raises(TypeError):
        Warp(
            "x",
            "sphere",
            True,
            WARPS["uniform_sphere"].forward,
            WARPS["uniform_sphere"].pdf,
            WARPS["uniform_sphere"].inverse,
        )
