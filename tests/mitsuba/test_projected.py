"""The projected-solid-angle map of a triangle in Dr.Jit (symsphere.mitsuba._projected), against numpy.

The Dr.Jit functions compute in the precision of their inputs; each test runs both (``f32``:
``mi.Vector3f``, ``f64``: ``mi.Vector3d``).

- float64: equal to :func:`symsphere.warps.square_to_projected_triangle` on the same inputs within 1e-9 in
  direction (measured 3e-12: Dr.Jit's own sin/cos/atan2 polynomials against libm's, a few ulp, and both
  root finders stop at their rounding level), E and the pdf within 1e-9 relative.
- float32: E and the CDF are sums that cancel for a triangle thin in the projection (near the horizon,
  or seen nearly edge-on: terms large against their sum), so they carry the terms' rounding.  E is
  computed as the projection's flat (shoelace) area plus the arcs' segments, which leaves 1.1e-4 relative
  at worst on these tests' triangles (Lambert's sum as such lost 1.6e-3); a sample moves along the
  azimuth by up to 4.6e-4 rad against float64 (the CDF's sector differences): bounds 2e-3 and 5e-4.
  The pdf stays that of the direction returned (pdf E / cos = 1 within 1e-4), which keeps the
  estimator's variance at rounding level.
- Mitsuba's own chi^2 test (``mitsuba.chi2.ChiSquareTest`` on ``SphericalDomain``) of the Dr.Jit map on
  several triangles and normals, cut by the horizon included, in both precisions; significance 0.01
  corrected over the CHI2_TESTS tests of this module by the harness (Sidak: ``test_count``), fixed seeds.
- The target of projected sampling: a Lambertian point lit by one uniform triangle light, estimated
  with ``L rho / pi cos / pdf`` at 1 spp, has a relative standard deviation <= 1e-3 over many points and
  triangles; its mean is the irradiance from numpy's E (itself checked against quadrature in
  tests/warps/test_projected_triangle.py) within 1e-5 (float64; float32 5e-4, E's own error).
- No NaN or inf for random and adversarial triangles (the full scan of 1e8 samples is
  benchmarks/scan_projected_triangle.py).
"""

from __future__ import annotations

import numpy as np
import pytest

from symsphere.warps import projected_solid_angle, square_to_projected_triangle

CHI2 = {
    "above": ([[1, 0, 0.2], [0, 1, 0.2], [0.6, 0.7, 1.0]], [0, 0, 1]),
    "pole_inside": ([[1, 0, 0.5], [-0.5, 0.9, 0.5], [-0.5, -0.9, 0.5]], [0, 0, 1]),
    "straddling": ([[1, 0, -0.2], [-0.5, 0.9, 0.6], [-0.5, -0.9, 0.3]], [0, 0, 1]),
    "tilted_two_below": ([[1, 0, -0.3], [0, 1, -0.4], [0.5, 0.5, 0.6]], [0.2, -0.3, 0.93]),
    "wall": ([[-2, -1, 0.15], [2, -1, 0.15], [0, 3, 0.15]], [0.0, 0.3, -1.0]),
}
PRECISIONS = ("f32", "f64")
CHI2_TESTS = len(CHI2) * len(PRECISIONS)


def _unit(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _vec(mi, rows, precision="f32"):
    if precision == "f64":
        rows = np.asarray(rows, dtype=np.float64)
        return mi.Vector3d(rows[..., 0], rows[..., 1], rows[..., 2])
    rows = np.asarray(rows, dtype=np.float32)
    return mi.Vector3f(rows[..., 0], rows[..., 1], rows[..., 2])


def _point(mi, uv, precision):
    if precision == "f64":
        return mi.Point2d(uv[:, 0].astype(np.float64), uv[:, 1].astype(np.float64))
    return mi.Point2f(uv[:, 0], uv[:, 1])


def _np(v):
    return np.stack([np.asarray(v.x), np.asarray(v.y), np.asarray(v.z)], axis=-1).astype(np.float64)


def _random_triangles(rng, count):
    """Triangles at distance ~1 from a point with normal z in the frame of random normals (numpy)."""
    n = _unit(rng.standard_normal((count, 3)))
    centre = _unit(rng.standard_normal((count, 3)) + 1.2 * n) * rng.uniform(0.3, 3.0, (count, 1))
    size = rng.uniform(0.01, 2.0, (count, 1, 1))
    tri = centre[:, None, :] + size * rng.standard_normal((count, 3, 3))
    return tri, n


def _batch(mi, rng, count, per, precision="f32"):
    """Random triangles (float32 values) that the numpy map accepts with E >= 1e-5, ``per`` lanes each, and
    the Dr.Jit arguments in *precision*: one launch for all of them."""
    tri, n = _random_triangles(rng, count)
    tri, n = tri.astype(np.float32), n.astype(np.float32)
    keep, energies = [], []
    for k in range(count):
        try:
            e = projected_solid_angle(*tri[k].astype(np.float64), n[k].astype(np.float64))
        except ValueError:  # a degenerate triangle of the random draw: tested below
            continue
        if e >= 1e-5:  # (almost) below the horizon: no light, nothing sampled (tested below)
            keep.append(k)
            energies.append(e)
    tri, n = tri[keep], n[keep]
    lanes_tri, lanes_n = np.repeat(tri, per, axis=0), np.repeat(n, per, axis=0)
    args = [_vec(mi, lanes_tri[:, i], precision) for i in range(3)] + [_vec(mi, lanes_n, precision)]
    return tri, n, np.array(energies), args


# precision: (direction, relative E and pdf) bounds against numpy's float64 map
BOUNDS = {"f64": (1e-9, 1e-9), "f32": (2e-3, 5e-4)}
# The tests with numpy's map as their reference run on the worker of tests/warps/test_projected_triangle.py
# (Makefile: --dist loadgroup): its numba kernels (about 6 CPU-s to compile) are compiled once, not by both.
_NUMPY_MAP = pytest.mark.xdist_group("projected_triangle")


@_NUMPY_MAP
@pytest.mark.parametrize("precision", PRECISIONS)
def test_equals_numpy(llvm, precision):
    mi = llvm
    from symsphere._testing import mitsuba_projected as mp

    rng = np.random.default_rng(1)
    per = 300
    tri, n, energies, args = _batch(mi, rng, 60, per, precision)
    assert len(tri) > 30
    uv = rng.random((len(tri) * per, 2)).astype(np.float32)
    d, pdf = mp.square_to_projected_triangle(*args, _point(mi, uv, precision))
    e_drjit = np.asarray(mp.projected_solid_angle(*args), dtype=np.float64)
    again = np.asarray(mp.square_to_projected_triangle_pdf(*args, d), dtype=np.float64)
    got, pdf = _np(d), np.asarray(pdf, dtype=np.float64)
    direction_bound, relative = BOUNDS[precision]
    worst = 0.0
    for k in range(len(tri)):
        lanes = slice(k * per, (k + 1) * per)
        t64, n64, e = tri[k].astype(np.float64), n[k].astype(np.float64), energies[k]
        ref = square_to_projected_triangle(uv[lanes].astype(np.float64), *t64, n64)
        worst = max(worst, float(np.max(np.abs(got[lanes] - ref))))
        np.testing.assert_allclose(e_drjit[lanes], e, rtol=relative)
        # the pdf is the density at the direction returned, with the map's own E
        np.testing.assert_allclose(
            pdf[lanes], got[lanes] @ _unit(n64) / e_drjit[lanes], rtol=1e-4 if precision == "f32" else 1e-9
        )
        np.testing.assert_allclose(pdf[lanes], ref @ _unit(n64) / e, rtol=10 * relative, atol=direction_bound / e)
        # float32: at d rounded to float32 its cosine moves by up to ~1e-7 (absolute)
        np.testing.assert_allclose(again[lanes], pdf[lanes], rtol=1e-6 if precision == "f32" else 1e-12, atol=2e-7 / e)
    assert worst < direction_bound, worst


def _chi2_case(mi, name, precision="f32"):
    from symsphere._testing import mitsuba_projected as mp

    tri, n = CHI2[name]
    vector, point = (mi.Vector3d, mi.Point2d) if precision == "f64" else (mi.Vector3f, mi.Point2f)
    a, b, c = (vector(*(float(x) for x in v)) for v in tri)
    normal = vector(*(float(x) for x in _unit(n)))

    def sample(s):
        return mi.Vector3f(mp.square_to_projected_triangle(a, b, c, normal, point(s))[0])

    def pdf(v):
        return mi.Float(mp.square_to_projected_triangle_pdf(a, b, c, normal, vector(v)))

    return sample, pdf


@pytest.mark.statistical
@pytest.mark.parametrize("precision", PRECISIONS)
@pytest.mark.parametrize("name", list(CHI2))
def test_mitsuba_chi2(llvm, name, precision, tmp_path, monkeypatch):
    mi = llvm
    monkeypatch.chdir(tmp_path)  # a rejected test writes chi2_data.py into the working directory
    from mitsuba.chi2 import ChiSquareTest, SphericalDomain

    sample, pdf = _chi2_case(mi, name, precision)
    seed = list(CHI2).index(name) + len(CHI2) * PRECISIONS.index(precision)
    test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample, pdf_func=pdf, sample_dim=2,
                         sample_count=400_000, res=51, ires=32, seed=seed)  # fmt: skip
    assert test.run(significance_level=0.01, test_count=CHI2_TESTS), test.messages


@pytest.mark.statistical
def test_mitsuba_chi2_rejects_solid_angle_sampling(llvm, tmp_path, monkeypatch):
    # the power of the tests above: the same triangle sampled uniformly in solid angle (the cosine left out)
    mi = llvm
    import drjit as dr

    monkeypatch.chdir(tmp_path)
    from mitsuba.chi2 import ChiSquareTest, SphericalDomain

    from symsphere._testing import mitsuba_warps

    _, pdf = _chi2_case(mi, "pole_inside")
    tri, _ = CHI2["pole_inside"]
    corners = [mi.Vector3d(*(float(x) for x in v)) for v in tri]

    def sample(s):
        d, _ = mitsuba_warps.square_to_spherical_triangle((mi.Float64(s.x), mi.Float64(s.y)), *corners)
        return mi.Vector3f(dr.normalize(d))

    test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample, pdf_func=pdf, sample_dim=2,
                         sample_count=400_000, res=51, ires=32, seed=99)  # fmt: skip
    assert not test.run(significance_level=0.01, test_count=1)


@_NUMPY_MAP
@pytest.mark.parametrize("precision", PRECISIONS)
def test_lambertian_direct_light_relative_std(llvm, precision):
    """Unoccluded Lambertian points lit by one triangle light: relative std of L rho/pi cos/pdf <= 1e-3."""
    mi = llvm
    from symsphere._testing import mitsuba_projected as mp

    rng = np.random.default_rng(7)
    per = 256
    tri, n, energies, args = _batch(mi, rng, 200, per, precision)
    assert len(tri) > 100
    radiance, albedo = 3.0, 0.7
    uv = rng.random((len(tri) * per, 2)).astype(np.float32)
    d, pdf = mp.square_to_projected_triangle(*args, _point(mi, uv, precision))
    # the cosine of the returned direction, here in float64
    cos = np.sum(_np(d) * np.repeat(_unit(n.astype(np.float64)), per, axis=0), axis=1)
    estimate = (radiance * albedo / np.pi * cos / np.asarray(pdf, dtype=np.float64)).reshape(len(tri), per)
    relative_std = np.std(estimate, axis=1) / np.mean(estimate, axis=1)
    mean_error = np.abs(np.mean(estimate, axis=1) / (radiance * albedo / np.pi * energies) - 1)
    assert np.max(relative_std) <= 1e-3, np.max(relative_std)
    # float32: E's own rounding error (1.1e-4 relative at worst here)
    assert np.max(mean_error) <= (5e-4 if precision == "f32" else 1e-5), np.max(mean_error)


def _adversarial(rng):
    """Triangles that break samplers: tiny, slivers, edge-on, below or grazing the horizon, huge, degenerate."""
    out = []
    base = _unit([0.3, 0.2, 0.9])
    for size in (1e-1, 1e-3, 1e-5, 1e-7):
        t = _unit(np.cross(base, [1.0, 0.0, 0.0]))
        b = np.cross(base, t)
        out.append(([base + size * t, base - size * (0.5 * t - 0.8 * b), base - size * (0.5 * t + 0.8 * b)], [0, 0, 1]))
    for h in (1e-3, 1e-6, 1e-9, 0.0):  # slivers, the last collinear
        out.append(([[1, 0, 0.2], [0, 1, 0.2], [0.5, 0.5, 0.2 + h]], [0, 0, 1]))
    for z in (1e-3, 1e-6, 0.0, -1e-6):  # edge-on / grazing: a triangle in (or just off) the tangent plane
        out.append(([[1, 0, z], [0, 1, z], [-1, -1, z]], [0, 0, 1]))
        out.append(([[1, 0, -0.5], [0, 1, -0.5], [0.3, 0.3, z]], [0, 0, 1]))
    out.append(([[1, 0, 0], [1, 0, 0], [0, 1, 0.3]], [0, 0, 1]))  # two equal vertices
    out.append(([[0, 0, 0], [1, 0, 0.3], [0, 1, 0.3]], [0, 0, 1]))  # a vertex at the shading point
    out.append(([[-1e3, -1e3, 1e-3], [1e3, -1e3, 1e-3], [0, 1e3, 1e-3]], [0, 0, 1]))  # nearly a hemisphere
    out.append(([[0, 0, 1], [1, 0, 1], [0, 1, 1]], [0, 0, 1]))  # the pole at a vertex
    out.append(([[-1, 0, 1], [1, 0, 1], [0, 1, 1]], [0, 0, 1]))  # the pole on an edge
    out.append(([[1, 0, 0.2], [0, 1, 0.2], [0.3, 0.3, 1.0]], [0.3, -0.2, 0.9]))  # n in an edge's plane
    tri, n = _random_triangles(rng, 40)
    out += list(zip(tri, n, strict=True))
    return out


@pytest.mark.parametrize("precision", PRECISIONS)
def test_no_nan_or_inf(llvm, precision):
    """The adversarial triangles at three scales (1, 1e-3, 1e3: the same shapes), all in one launch."""
    mi = llvm
    from symsphere._testing import mitsuba_projected as mp

    rng = np.random.default_rng(11)
    cases = _adversarial(rng)
    per = 512
    uv = rng.random((per, 2)).astype(np.float32)
    uv[:4] = [[0, 0], [1, 1], [0, 1], [1, 0]]
    uv[4:8] = [[1e-7, 0.5], [1 - 6e-8, 0.5], [0.5, 1e-7], [0.5, 1 - 6e-8]]
    scales = (1.0, 1e-3, 1e3)
    tri = np.concatenate([np.broadcast_to(np.asarray(t, dtype=np.float64) * scale, (per, 3, 3))
                          for scale in scales for t, _ in cases])  # fmt: skip
    n = np.concatenate([np.broadcast_to(_unit(np.asarray(nn, dtype=np.float64)), (per, 3)) for _, nn in cases])
    n = np.tile(n, (len(scales), 1))
    args = [_vec(mi, tri[:, i], precision) for i in range(3)] + [_vec(mi, n, precision)]
    sample = np.tile(uv, (len(scales) * len(cases), 1))
    d, pdf = mp.square_to_projected_triangle(*args, _point(mi, sample, precision))
    got, pdf = _np(d), np.asarray(pdf)
    assert np.all(np.isfinite(got)) and np.all(np.isfinite(pdf)) and np.all(pdf >= 0)
    np.testing.assert_allclose(np.linalg.norm(got, axis=1), 1, atol=1e-6)
    assert np.all(np.sum(got * n, axis=1)[pdf > 0] >= -1e-6)  # never below the horizon
    e = np.asarray(mp.projected_solid_angle(*args))
    assert np.all(np.isfinite(e)) and np.all(e >= 0)
    assert np.all(pdf[e == 0] == 0)  # nothing above the horizon: contributes nothing
    back = np.asarray(mp.square_to_projected_triangle_pdf(*args, d))
    assert np.all(np.isfinite(back)) and np.all(back >= 0)


@pytest.mark.parametrize("precision", PRECISIONS)
def test_degenerate_triangles_contribute_nothing(llvm, precision):
    mi = llvm
    from symsphere._testing import mitsuba_projected as mp

    cases = [
        [[1, 0, -0.2], [0, 1, -0.2], [0.3, 0.3, -1.0]],  # below the horizon
        [[1, 0, 0.0], [0, 1, 0.0], [-1, -1, 0.0]],  # in the tangent plane (edge-on)
        [[1, 0, 0.3], [1, 0, 0.3], [0, 1, 0.3]],  # zero area
        [[1, 0, 0.3], [2, 0, 0.6], [3, 0, 0.9]],  # collinear with the shading point
        [[0, 0, 0], [0, 0, 0], [0, 0, 0]],  # a triangle at the shading point
    ]
    tri = np.asarray(cases, dtype=np.float64)
    args = [_vec(mi, tri[:, i], precision) for i in range(3)]
    args.append(_vec(mi, np.tile([0.0, 0.0, 1.0], (len(cases), 1)), precision))
    d, pdf = mp.square_to_projected_triangle(*args, _point(mi, np.tile([[0.4, 0.6]], (len(cases), 1)), precision))
    assert np.all(np.asarray(pdf) == 0) and np.all(np.isfinite(_np(d)))
    assert np.all(np.asarray(mp.projected_solid_angle(*args)) == 0)
    assert np.all(np.asarray(mp.square_to_projected_triangle_pdf(*args, _vec(mi, [0.0, 0.0, 1.0], precision))) == 0)


# --- emitter_sampling='cosine': Arvo's map warped bilinearly by the cosine, and the table's use of it ---


def _cosine_warp_case(mi, name):
    """(sample, pdf) of the warped map on CHI2's triangle *name*: the density from numpy (the inverse of
    Arvo's map, its pdf 1/Omega, and the bilinear density of the square), not from the code under test."""
    from symsphere._testing import mitsuba_projected as mp
    from symsphere.warps import spherical_triangle_to_square, square_to_spherical_triangle_pdf

    tri, n = CHI2[name]
    tri64, n64 = np.asarray(tri, dtype=np.float64), _unit(n)
    a, b, c = (mi.Vector3f(*(float(x) for x in v)) for v in tri)
    normal = mi.Vector3f(*(float(x) for x in n64))
    wa, wb, wc = (max(float(_unit(v) @ n64), 0.01) for v in tri64)

    def sample(s):
        return mp.square_to_cosine_spherical_triangle(a, b, c, normal, (s.x, s.y))[0]

    def pdf(v):
        d = _unit(_np(v))
        solid = square_to_spherical_triangle_pdf(d, *tri64)  # 1 / Omega inside, 0 outside
        uv = np.clip(spherical_triangle_to_square(np.where(solid[:, None] > 0, d, _unit(tri64.sum(0))), *tri64), 0, 1)
        x, y = uv[:, 0], uv[:, 1]
        bilinear = 4 * ((1 - y) * wb + y * ((1 - x) * wa + x * wc)) / (2 * wb + wa + wc)
        return mi.Float((solid * bilinear).astype(np.float32))

    return sample, pdf


@pytest.mark.statistical
@pytest.mark.parametrize("name", list(CHI2))
def test_cosine_warp_mitsuba_chi2(llvm, name, tmp_path, monkeypatch):
    """Mitsuba's chi^2 test of the warped map against numpy's density, significance 0.01 Sidak-corrected
    over the len(CHI2) tests (float32: as the light table runs it)."""
    mi = llvm
    monkeypatch.chdir(tmp_path)
    from mitsuba.chi2 import ChiSquareTest, SphericalDomain

    sample, pdf = _cosine_warp_case(mi, name)
    test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample, pdf_func=pdf, sample_dim=2,
                         sample_count=400_000, res=51, ires=32, seed=20 + list(CHI2).index(name))  # fmt: skip
    assert test.run(significance_level=0.01, test_count=len(CHI2)), test.messages


def test_cosine_warp_follows_the_cosine(llvm):
    """The warp's point: cos / pdf varies less than with Arvo's map alone (relative standard deviation, the
    same points of the square) wherever the cosine varies over the triangle's vertices; and no NaN or inf,
    a density 0 (nothing sampled) only for a degenerate triangle, on the adversarial triangles."""
    mi = llvm
    from symsphere._testing import mitsuba_projected as mp
    from symsphere._testing import mitsuba_warps as mw

    rng = np.random.default_rng(23)
    uv = rng.random((20_000, 2)).astype(np.float32)
    point = (mi.Float(uv[:, 0]), mi.Float(uv[:, 1]))
    for name in ("above", "straddling", "tilted_two_below", "wall"):
        tri, n = CHI2[name]
        n64 = _unit(n)
        a, b, c = (mi.Vector3f(*(float(x) for x in v)) for v in tri)
        d, inv = mp.square_to_cosine_spherical_triangle(a, b, c, mi.Vector3f(*(float(x) for x in n64)), point)
        warped = np.maximum(_unit(_np(d)) @ n64, 0) * np.asarray(inv, dtype=np.float64)
        d0, omega = mw.square_to_spherical_triangle(point, a, b, c)
        plain = np.maximum(_unit(_np(d0)) @ n64, 0) * np.asarray(omega, dtype=np.float64)
        assert np.std(warped) / np.mean(warped) < 0.7 * np.std(plain) / np.mean(plain), name
    cases = _adversarial(rng)
    per = 64
    tri = np.concatenate([np.broadcast_to(np.asarray(t, dtype=np.float64), (per, 3, 3)) for t, _ in cases])
    n = np.concatenate([np.broadcast_to(_unit(np.asarray(nn, dtype=np.float64)), (per, 3)) for _, nn in cases])
    sample = np.tile(uv[:per], (len(cases), 1))
    args = [_vec(mi, tri[:, i]) for i in range(3)] + [_vec(mi, n)]
    d, inv = mp.square_to_cosine_spherical_triangle(*args, (mi.Float(sample[:, 0]), mi.Float(sample[:, 1])))
    got, inv = _np(d), np.asarray(inv)
    assert np.all(np.isfinite(got)) and np.all(np.isfinite(inv)) and np.all(inv >= 0)
    np.testing.assert_allclose(np.linalg.norm(got[inv > 0], axis=1), 1, atol=1e-6)


SIZE, SPP, SEEDS = 16, 32, 12


def _near_light_scene(mi):
    """A floor under a 1.2 x 1.2 rectangle light 0.12 above it and a 24-triangle disk light, a ball of two
    blended diffuse BSDFs (diffuse, not Lambertian: Arvo's map there) and one of rough plastic (Mitsuba's
    sampling): every technique of emitter_sampling='cosine' in one image."""
    T = mi.ScalarTransform4f

    def diffuse(value):
        return {"type": "diffuse", "reflectance": {"type": "rgb", "value": value}}

    emitter = {"type": "area", "radiance": {"type": "rgb", "value": [5, 5, 4]}}
    return mi.load_dict({
        "type": "scene",
        "sensor": {"type": "perspective", "fov": 70, "to_world": T().look_at(origin=[0, 2.2, 2.0], target=[0, 0, -0.3], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": SIZE, "height": SIZE, "rfilter": {"type": "box"}}},
        "floor": {"type": "rectangle", "to_world": T().rotate([1, 0, 0], -90).scale(3), "bsdf": {"type": "twosided", "bsdf": diffuse([0.7, 0.7, 0.7])}},
        "light": {"type": "rectangle", "to_world": T().translate([-0.5, 0.12, -0.3]).rotate([1, 0, 0], 90).scale(0.6), "emitter": emitter},
        "disk": {"type": "disk", "to_world": T().translate([0.9, 0.6, -0.6]).rotate([1, 0, 0], 90).scale(0.4), "emitter": emitter},
        "blend": {"type": "sphere", "center": [0.6, 0.3, 0.4], "radius": 0.3,
                  "bsdf": {"type": "blendbsdf", "weight": 0.5, "bsdf_0": diffuse([0.8, 0.3, 0.2]), "bsdf_1": diffuse([0.2, 0.3, 0.8])}},
        "plastic": {"type": "sphere", "center": [-0.9, 0.3, 0.5], "radius": 0.3, "bsdf": {"type": "roughplastic", "alpha": 0.2}},
    })  # fmt: skip


@pytest.mark.statistical
def test_cosine_emitter_sampling_agrees_with_mitsubas_path(llvm):
    """The mean image of symsphere_path with emitter_sampling='cosine' against Mitsuba's path (SEEDS renders
    each, 4 x 4 blocks, the mean of R, G, B): Welch's t-test, two-sided, 0.01 Sidak-corrected over the
    blocks; fixed seeds.  The floor has points where the rectangle's triangles are large (projected solid
    angle), medium (the warped map) and small (by area) as seen from them (checked)."""
    mi = llvm
    from scipy import stats

    import symsphere.mitsuba  # noqa: F401
    from symsphere._testing import mitsuba_lights as lights
    from symsphere._testing import mitsuba_projected as mp

    scene = _near_light_scene(mi)
    # which technique each rectangle triangle takes from the floor's primary hits
    sensor = scene.sensors()[0]
    xs, ys = np.meshgrid((np.arange(SIZE) + 0.5) / SIZE, (np.arange(SIZE) + 0.5) / SIZE)
    rays, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(xs.ravel(), ys.ravel()), mi.Point2f(0.5, 0.5))
    p = _np(scene.ray_intersect(rays).p)
    table = lights.LightTable(scene)
    kinds = set()
    for tri in table.tris[:2]:
        centroid = tri.mean(axis=0)
        ratio = np.max(np.linalg.norm(tri - centroid, axis=1)) / np.linalg.norm(p - centroid, axis=1)
        kinds |= {0 if r < lights.AREA_BELOW else 2 if r >= mp.HUGE_ABOVE else 1 for r in ratio}
    assert kinds == {0, 1, 2}

    def renders(spec):
        integrator = mi.load_dict({**spec, "max_depth": 3})
        images = [np.array(mi.render(scene, integrator=integrator, spp=SPP, seed=s))[..., :3] for s in range(SEEDS)]
        lum = np.stack(images).mean(axis=-1).reshape(SEEDS, SIZE // 4, 4, SIZE // 4, 4)
        return lum.mean(axis=(2, 4)).reshape(SEEDS, -1)

    ours = renders({"type": "symsphere_path", "strategy": "bsdf", "emitter_sampling": "cosine"})
    ref = renders({"type": "path"})
    result = stats.ttest_ind(ours, ref, axis=0, equal_var=False)
    sidak = 1.0 - (1.0 - 0.01) ** (1.0 / ours.shape[1])
    assert np.min(result.pvalue) > sidak, (np.min(result.pvalue), ours.mean(0), ref.mean(0))
