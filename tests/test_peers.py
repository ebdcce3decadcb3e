"""The peer samplers: registry, conventions, densities, and their distributions.

The peers' maps of the unit square are tested in tests/warps/ (one file per module, and the contract
every warp keeps in tests/warps/test_registry.py).

Statistical tests use significance 0.01 with a Sidak correction over the
CHI2_TESTS chi-square (and two-sample) tests of this file and of
tests/warps/test_spherical_triangle.py (3 of them), so the chance that
any of them fails for correct samplers is 1%.  Each uses independent rows: one
point per random rotation for the rotated Fibonacci set and one member per
orbit for ``arvo`` (``symsphere.stats.one_per_orbit``).  The reference
densities are ``symsphere.stats.uniform_pdf`` (independent of the peers) and,
for ``cosine``, cos(theta)/pi written out in the test.
"""

import math

import numpy as np
import pytest
from references import ELEMENTARY_ULPS, EPS64, assert_power
from scipy import stats as scipy_stats
from scipy.stats import qmc

import symsphere as ss
from symsphere import peers as P
from symsphere import warps
from symsphere.points import unit_square_points
from symsphere.stats import chi2_test, one_per_orbit, uniform_pdf

SIGNIFICANCE = 0.01
# 6 direct peers + rotated Fibonacci + arvo (sphere) here; arvo on T0 + equal_area on T0 + two-sample in
# tests/warps/test_spherical_triangle.py
CHI2_TESTS = 6 + 1 + 1 + 1 + 1 + 1
N_CHI2 = 50_000
# Power (tests/references.py): the peers are reference samplers from the literature, checked for a wrong
# formula or convention, which is a large effect (test_chi2_has_power: uniform theta is rejected at
# p < 1e-100).  N_CHI2 = 50 000 (392 cells) rejects Cohen's w >= 0.06 with probability 99 %, e.g. a density
# 6 % off on either half of the domain; _check asserts it.  (The library's own maps: w = 0.04, tests/statistical/.)
MUST_DETECT_W = 0.06


def _in_domain(d, domain, tol=1e-6):
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    if domain == "sphere":
        return np.ones(d.shape[:-1], dtype=bool)
    if domain == "hemisphere":
        return z >= -tol
    return (z - x >= -tol) & (x - y >= -tol) & (y >= -tol)


def _check(result, w=MUST_DETECT_W):
    assert result.passed, str(result)
    assert_power(result, w)


# --- registry and conventions -------------------------------------------------


def test_registry():
    assert set(P.PEERS) == {
        "classic",
        "classic_hemisphere",
        "gaussian",
        "octahedral",
        "octahedral_hemisphere",
        "fibonacci",
        "fibonacci_rotated",
        "arvo",
        "cosine",
        "lebedev",
        "lebedev_rotated",
    }
    for name, peer in P.PEERS.items():
        assert peer.name == name and peer.domain in ("sphere", "hemisphere")
        assert peer.is_map == (peer.forward is not None or name == "arvo")
        assert P.get_peer(name) is peer
        with pytest.raises(AttributeError):
            peer.name = "other"  # frozen


@pytest.mark.parametrize("name", list(P.PEERS))
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_sample_conventions(name, dtype):
    peer = P.PEERS[name]
    n = peer.largest_n(96)  # 96, or 86 for the Lebedev rules
    d = peer.sample(n, rng=7, dtype=dtype)
    assert d.shape == (n, 3) and d.dtype == dtype
    assert np.all(np.isfinite(d))
    np.testing.assert_allclose(
        np.linalg.norm(d.astype(np.float64), axis=1), 1, atol=1e-6 if dtype == np.float32 else 1e-14
    )
    assert np.all(_in_domain(d, peer.domain))
    # the same seed (int, SeedSequence, Generator) gives the same output
    np.testing.assert_array_equal(d, peer.sample(n, rng=7, dtype=dtype))
    np.testing.assert_array_equal(
        peer.sample(n, rng=np.random.SeedSequence(3), dtype=dtype),
        peer.sample(n, rng=np.random.default_rng(np.random.SeedSequence(3)), dtype=dtype),
    )
    other = peer.sample(n, rng=8, dtype=dtype)
    assert np.any(d != other) == peer.is_random


@pytest.mark.parametrize("name", [k for k, p in P.PEERS.items() if p.is_map])
@pytest.mark.parametrize("points", ["sobol", "halton", "engine"])
def test_qmc_points(name, points):
    peer = P.PEERS[name]
    n = 48 * 16 if peer.multiple == 48 else 1024  # a power of 2 of base points for Sobol'
    if points == "engine":
        engine = qmc.Sobol(d=2, scramble=True, rng=1)
        d = peer.sample(n, points=engine)
        # an engine is used as given and its state advances
        e2 = qmc.Sobol(d=2, scramble=True, rng=1)
        m = n // peer.multiple
        uv = e2.random(m)
        if peer.forward is not None:
            np.testing.assert_array_equal(d, peer.forward(uv))
        assert engine.num_generated == m
    else:
        d = peer.sample(n, points=points, rng=1)
    assert d.shape == (n, 3) and np.all(np.isfinite(d)) and np.all(_in_domain(d, peer.domain))


def test_qmc_beats_random_on_a_smooth_integrand():
    # 4 pi mean(exp(w.a)) with 4096 Sobol' points vs random points (both seeded).
    a = np.array([0.7, -0.4, 0.5])
    exact = 4 * np.pi * np.sinh(np.linalg.norm(a)) / np.linalg.norm(a)
    for name in ("classic", "octahedral"):
        err = {
            p: abs(4 * np.pi * np.exp(P.PEERS[name].sample(4096, rng=5, points=p) @ a).mean() / exact - 1)
            for p in ("random", "sobol")
        }
        assert err["sobol"] < 1e-4 < err["random"], (name, err)


def _sphere_quadrature(n_cos=64, n_phi=128):
    # Gauss-Legendre in cos(theta) on [-1, 0] and [0, 1] (pdfs jump or kink at the equator) x trapezoid in phi.
    x, w = np.polynomial.legendre.leggauss(n_cos)
    cos = np.concatenate([(x - 1) / 2, (x + 1) / 2])
    wc = np.concatenate([w, w]) / 2
    phi = 2 * np.pi * (np.arange(n_phi) + 0.5) / n_phi
    c, p = np.meshgrid(cos, phi, indexing="ij")
    s = np.sqrt(1 - c * c)
    d = np.stack([s * np.cos(p), s * np.sin(p), c], axis=-1).reshape(-1, 3)
    weights = (wc[:, None] * np.full(n_phi, 2 * np.pi / n_phi)).ravel()
    return d, weights


@pytest.mark.parametrize("name", list(P.PEERS))
def test_pdf_integrates_to_one(name):
    peer = P.PEERS[name]
    d, w = _sphere_quadrature()
    density = peer.pdf(d)
    assert np.all(density >= 0)
    assert np.sum(density * w) == pytest.approx(1.0, abs=1e-13)
    if peer.domain == "hemisphere":
        assert np.all(density[d[:, 2] < 0] == 0)


def test_chi2_arvo_sphere():
    d = one_per_orbit(P.sample_arvo(48 * N_CHI2, rng=11), 48, rng=12)
    _check(chi2_test(d, uniform_pdf("sphere"), "sphere", significance=SIGNIFICANCE, test_count=CHI2_TESTS))


def test_arvo_orbit_layout():
    d = P.sample_arvo(96, rng=13)
    uv = unit_square_points(2, "random", 13, per_point=48)  # the base points sample_arvo draws
    base = warps.square_to_spherical_triangle(uv, *warps.T0_VERTICES)
    np.testing.assert_allclose(d.reshape(2, 48, 3), ss.orbit(base), rtol=0, atol=1e-15)


# --- chi-square of the other random peers ----------------------------------------


def _cosine_pdf(d):  # written out again: cos(theta)/pi above the horizon
    return np.where(d[:, 2] > 0, d[:, 2] / np.pi, 0.0)


@pytest.mark.parametrize(
    "name", ["classic", "classic_hemisphere", "gaussian", "octahedral", "octahedral_hemisphere", "cosine"]
)
def test_chi2_peer(name):
    peer = P.PEERS[name]
    d = peer.sample(N_CHI2, rng=20 + len(name))
    pdf = _cosine_pdf if name == "cosine" else uniform_pdf(peer.domain)
    _check(chi2_test(d, pdf, peer.domain, significance=SIGNIFICANCE, test_count=CHI2_TESTS))


def test_chi2_fibonacci_rotated():
    # The points of one rotated set are dependent: take one point of each of many sets.
    peer = P.PEERS["fibonacci_rotated"]
    children = np.random.SeedSequence(30).spawn(10_000)
    picks = np.random.default_rng(31).integers(0, 37, size=len(children))
    d = np.array([peer.sample(37, rng=child)[k] for child, k in zip(children, picks, strict=False)])
    # 10 000 independent sets (one sample each, a Python loop): 72 cells, w >= 0.096 at 99 % power
    _check(chi2_test(d, uniform_pdf("sphere"), "sphere", significance=SIGNIFICANCE, test_count=CHI2_TESTS), w=0.1)


def test_chi2_has_power():
    # A wrong sampler at the same size is rejected: uniform theta instead of uniform cos(theta).
    uv = np.random.default_rng(32).random((N_CHI2, 2))
    theta, phi = np.pi * uv[:, 0], 2 * np.pi * uv[:, 1]
    d = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=1)
    result = chi2_test(d, uniform_pdf("sphere"), "sphere")
    assert not result.passed and result.p_value < 1e-100


# --- Fibonacci --------------------------------------------------------------------


def test_fibonacci_formula():
    n = 1000
    d = P.fibonacci_points(n)
    i = np.arange(n)
    np.testing.assert_allclose(d[:, 2], 1 - (2 * i + 1) / n, rtol=0, atol=1e-15)
    golden = (1 + np.sqrt(5)) / 2
    phi = np.mod(np.arctan2(d[:, 1], d[:, 0]), 2 * np.pi)
    expected = 2 * np.pi * np.mod(i / golden, 1.0)
    err = np.abs((phi - expected + np.pi) % (2 * np.pi) - np.pi)
    assert err.max() < 1e-12
    # |d|^2 = s^2 (cos^2 + sin^2) + z^2 with numpy's cos, sin within E ulps each (tests/references.py), plus the
    # products, sum and sqrt: |d| - 1 <= (E + 2) eps
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1, atol=(ELEMENTARY_ULPS + 2) * EPS64)


def test_fibonacci_large_index_phase():
    # frac(i (Phi - 1)) from 64-bit fixed point, against exact integer arithmetic with 200 bits.
    # The phase is read back from point i of a set of n = 2 i + 1 points (on the equator, z = 0) by atan2:
    # numpy's cos, sin and atan2 add a few eps to frac, far below the bound's k 2^-64.
    i = np.array([10**9, 10**9 + 7, 2**40 + 3, 10**15], dtype=np.int64)
    points = np.array([P.fibonacci_point(int(k), 2 * int(k) + 1) for k in i])
    assert np.all(points[:, 2] == 0.0)
    frac = np.mod(np.arctan2(points[:, 1], points[:, 0]) / (2 * np.pi), 1.0)
    scale = 200
    golden_minus_1 = math.isqrt(5 << (2 * scale)) - (1 << scale)  # 2^(scale+1) (Phi - 1), floored
    for k, f in zip(i.tolist(), frac, strict=False):
        exact = ((k * golden_minus_1) >> 1) % (1 << scale) / 2.0**scale
        assert abs(f - exact) < 1e-15 * max(1, k / 2**53) + 2**-53 + k * 2.0**-64
    # the naive float64 product is visibly worse at i = 10^15
    naive = (10**15 * (np.sqrt(5) - 1) / 2) % 1.0
    exact = ((10**15 * golden_minus_1) >> 1) % (1 << scale) / 2.0**scale
    assert abs(naive - exact) > 1e-3 > abs(frac[-1] - exact)


def test_fibonacci_integrates_exp():
    # Deterministic set, n = 10^4: the relative error of 4 pi mean(exp(w.a)) measured 5.6e-7
    # (the brief's bound was 1e-4); we allow 2e-6.
    a = np.array([0.3, -0.5, 0.6])
    exact = 4 * np.pi * np.sinh(np.linalg.norm(a)) / np.linalg.norm(a)
    estimate = 4 * np.pi * np.exp(P.sample_fibonacci(10_000) @ a).mean()
    assert abs(estimate / exact - 1) < 2e-6
    # the rotated sets (seeds 0-4) are as accurate for this smooth integrand: at most 6.5e-7 measured
    rotated = [4 * np.pi * np.exp(P.sample_fibonacci(10_000, randomize=True, rng=k) @ a).mean() for k in range(5)]
    assert max(abs(r / exact - 1) for r in rotated) < 2e-6


# --- bad input ---------------------------------------------------------------------


@pytest.mark.parametrize(
    "call, error, word",
    [
        (lambda: P.sample_classic(0), ValueError, "'n'"),
        (lambda: P.sample_classic(2.5), TypeError, "'n'"),
        (lambda: P.sample_octahedral(True), TypeError, "'n'"),
        (lambda: P.sample_arvo(50), ValueError, "'n'"),
        (lambda: P.sample_gaussian(4, rng="seed"), TypeError, "'rng'"),
        (lambda: P.sample_cosine(4, rng=-1), ValueError, "'rng'"),
        (lambda: P.sample_classic(4, dtype=np.int32), TypeError, "'dtype'"),
        (lambda: P.sample_fibonacci(4, dtype="float16"), TypeError, "'dtype'"),
        (lambda: P.sample_classic(4, points="sobel"), ValueError, "points"),
        (lambda: P.sample_octahedral(4, points=qmc.Sobol(d=3)), ValueError, "'points'"),
        (lambda: P.sample_arvo(48 * 3, points="stratified"), ValueError, "square"),
        (lambda: P.PEERS["gaussian"].sample(4, points="sobol"), ValueError, "'points'"),
        (lambda: P.PEERS["fibonacci"].sample(4, points="halton"), ValueError, "'points'"),
        (lambda: P.sample_fibonacci(4, randomize=1), TypeError, "'randomize'"),
        (lambda: P.fibonacci_point(4, 4), ValueError, "'i'"),
        (lambda: P.fibonacci_point(0, 0), ValueError, "'n'"),
        (lambda: P.fibonacci_points(-3), ValueError, "'n'"),
        (lambda: P.get_peer("uniform"), ValueError, "'name'"),
        (lambda: P.sample_lebedev(100), ValueError, "'n'=100 is not the size of a Lebedev rule"),
        (lambda: P.sample_lebedev(2 * 5810), ValueError, "'n'"),
        (lambda: P.sample_lebedev(50, randomize="yes"), TypeError, "'randomize'"),
        (lambda: P.lebedev_size(5), ValueError, "'n'"),
        (lambda: P.PEERS["lebedev"].sample(50, points="sobol"), ValueError, "'points'"),
        (lambda: P.PEERS["arvo"].largest_n(47), ValueError, "'n'"),
    ],
)
def test_bad_input(call, error, word):
    with pytest.raises(error, match=word):
        call()


def test_map_peers_are_their_warps():
    # The warp record a map peer is built on says what the peer says: domain (T0 for arvo), uniformity, orbit size.
    for name, peer in P.PEERS.items():
        assert (peer.warp is not None) == peer.is_map
        if peer.warp is None:
            continue
        assert peer.warp is warps.WARPS[peer.warp.name] and peer.warp.uniform == peer.uniform
        if name == "arvo":
            assert peer.warp.domain == "triangle" and peer.orbit_size == peer.warp.orbit_size == 48
            assert peer.forward is None and peer.inverse is None
        else:
            assert peer.warp.domain == peer.domain and peer.warp.orbit_size == peer.orbit_size == 1
            assert peer.forward is peer.warp.forward and peer.inverse is peer.warp.inverse


@pytest.mark.parametrize("name", list(P.PEERS))
def test_peer_facts_agree_with_the_peer(name):
    """The fields a study reads instead of testing names: orbit size, uniformity, point sets."""
    peer = P.PEERS[name]
    assert (peer.orbit_size == 1) == peer.independent_rows
    if peer.orbit_size not in (1, None):
        assert peer.multiple % peer.orbit_size == 0
    d = peer.sample(peer.largest_n(96), rng=3)
    density = peer.pdf(d)
    area = 4 * np.pi if peer.domain == "sphere" else 2 * np.pi
    assert np.allclose(density, 1 / area, rtol=1e-12) == peer.uniform
    assert peer.point_sets == (P.POINT_SETS if peer.is_map else ("random",))


# --- Lebedev rules --------------------------------------------------------------------


def _monomial_integral(a, b, c):
    """Integral of x^a y^b z^c over the unit sphere (closed form; 0 unless all exponents are even)."""
    if a % 2 or b % 2 or c % 2:
        return 0.0
    double_factorial = lambda k: math.prod(range(k, 0, -2)) if k > 0 else 1  # noqa: E731
    return (
        4
        * math.pi
        * double_factorial(a - 1)
        * double_factorial(b - 1)
        * double_factorial(c - 1)
        / (double_factorial(a + b + c + 1))
    )


@pytest.mark.parametrize("order", [3, 11, 35, 131])
def test_lebedev_rules_are_exact_up_to_their_order(order):
    n = P.LEBEDEV_SIZES[P.LEBEDEV_ORDERS.index(order)]
    d, w = P.sample_lebedev(n), P.lebedev_weights(n)
    assert d.shape == (n, 3) and w.shape == (n,) and math.isclose(w.sum(), 4 * math.pi, rel_tol=1e-13)
    rng = np.random.default_rng(order)
    for _ in range(20):  # random monomials of degree <= order
        a, b = rng.integers(0, order + 1, size=2)
        a, b = int(a), int(min(b, order - a))
        c = int(rng.integers(0, order - a - b + 1))
        value = np.sum(w * d[:, 0] ** a * d[:, 1] ** b * d[:, 2] ** c)
        assert abs(value - _monomial_integral(a, b, c)) < 1e-12, (a, b, c)
    # Zonal harmonics P_k(d . e) about a generic axis e integrate to 0 for k >= 1: exactly (to rounding)
    # up to the order, and not beyond (measured |error| 0.13 ... 1.8 at k = order + 1).  High monomials
    # alone cannot show this: their projections on the harmonics of degree order + 1 are tiny.
    from scipy.special import eval_legendre

    e = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    assert max(abs(np.sum(w * eval_legendre(k, d @ e))) for k in range(1, order + 1)) < 1e-13
    assert abs(np.sum(w * eval_legendre(order + 1, d @ e))) > 0.1


@pytest.mark.parametrize("order", [11, 13, 131])
def test_lebedev_rules_are_sums_over_the_48_images(order):
    # The rule is invariant under the 48 signed permutations of (x, y, z) (built here with itertools,
    # independently of symsphere.symmetry): each maps the nodes onto the nodes, weights included.
    import itertools

    n = P.LEBEDEV_SIZES[P.LEBEDEV_ORDERS.index(order)]
    d, w = P.sample_lebedev(n), P.lebedev_weights(n)
    key = lambda x: np.lexsort(np.round(x, 12).T)  # noqa: E731
    reference = key(d)
    maps = 0
    for permutation in itertools.permutations(range(3)):
        for signs in itertools.product((1, -1), repeat=3):
            image = d[:, permutation] * np.array(signs)
            order_of_image = key(image)
            np.testing.assert_allclose(image[order_of_image], d[reference], atol=1e-13)
            np.testing.assert_allclose(w[order_of_image], w[reference], rtol=1e-12)
            maps += 1
    assert maps == 48


def test_lebedev_rotated_layout_and_weights():
    d = P.sample_lebedev(3 * 5810, randomize=True, rng=4)
    w = P.lebedev_weights(3 * 5810, randomize=True)
    base, base_w = P.sample_lebedev(5810), P.lebedev_weights(5810)
    assert math.isclose(w.sum(), 4 * math.pi, rel_tol=1e-13)
    for copy in range(3):  # each copy: the order-131 rule under its own rotation, weighted 1/3
        block = d[5810 * copy : 5810 * (copy + 1)]
        rotation, *_ = np.linalg.lstsq(base, block, rcond=None)
        np.testing.assert_allclose(base @ rotation, block, atol=1e-12)
        np.testing.assert_allclose(rotation.T @ rotation, np.eye(3), atol=1e-12)
        np.testing.assert_allclose(w[5810 * copy : 5810 * (copy + 1)], base_w / 3)
    assert P.PEERS["lebedev_rotated"].largest_n(20_000) == 17_430
    assert P.PEERS["lebedev"].largest_n(20_000) == 5810


@pytest.mark.slow
@pytest.mark.statistical
def test_lebedev_rotated_is_unbiased():
    # The order-11 rule (50 points) randomly rotated, on f = exp(w . a) with |a| = 3 (the rule's error
    # is about 1e-4 relative, far above rounding) and on a cap indicator: the mean of 2000 estimates
    # against the closed forms; Student t test, family significance 1e-3, Sidak over the 2 tests.
    # The unrotated rule's error on the same f shows that the test can see a bias of that size.
    a, centre, t = np.array([2.0, -1.0, 2.0]), np.array([1.0, 2.0, 2.0]) / 3.0, 0.3
    cases = [
        (lambda x: np.exp(x @ a), 4 * np.pi * np.sinh(3.0) / 3.0),
        (lambda x: (x @ centre > t).astype(np.float64), 2 * np.pi * (1 - t)),
    ]
    peer, count = P.PEERS["lebedev_rotated"], 2000
    threshold = scipy_stats.t.ppf(1 - (1 - (1 - 1e-3) ** 0.5) / 2, count - 1)
    for f, exact in cases:
        estimates = np.array([peer.estimate(f, 50, rng=child) for child in np.random.SeedSequence(40).spawn(count)])
        standard_error = estimates.std(ddof=1) / math.sqrt(count)
        assert abs(estimates.mean() - exact) < threshold * standard_error
        assert abs(P.PEERS["lebedev"].estimate(f, 50) - exact) > threshold * standard_error


def test_peer_estimate_is_the_weighted_mean():
    f = lambda x: np.exp(x[:, 0]) + x[:, 2] ** 2  # noqa: E731
    for name, points, n in (("octahedral", "sobol", 512), ("cosine", "random", 500), ("arvo", "random", 480)):
        peer = P.PEERS[name]
        d = peer.sample(n, rng=2, points=points)
        assert math.isclose(
            peer.estimate(f, n, rng=2, points=points), float(np.mean(f(d) / peer.pdf(d))), rel_tol=1e-13
        )
    d = P.sample_lebedev(590)
    assert P.PEERS["lebedev"].estimate(f, 590) == float(np.sum(P.lebedev_weights(590) * f(d)))


def test_peer_over_a_warp_takes_its_facts():
    # A peer over a map is a record over the warp: its sampler, density, uniformity and reference are the
    # warp's, and it samples what the warp samples.
    for name, peer in P.PEERS.items():
        if peer.warp is not None and peer.warp.domain == peer.domain:
            assert P.Peer.over(peer.warp, name=name) == peer
            np.testing.assert_array_equal(
                peer.sample(64, rng=3, points="halton"), peer.warp.sample(64, rng=3, points="halton")
            )
    with pytest.raises(ValueError, match="'warp'"):
        P.Peer.over(warps.WARPS["equal_area"], name="t0")
