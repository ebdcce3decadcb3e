"""symsphere.mitsuba's Dr.Jit spherical rectangle (Urena, Fajardo & King 2013), in float64 and float32.

Checked against the numpy map (``symsphere.warps.square_to_spherical_rectangle``, float64) and, since that
one is ours too, against references that share no code with either: the solid angle of the two triangles
by Van Oosterom & Strackee's formula from the world vertices, the ray from the viewer along each sampled
direction meeting the rectangle, the Jacobian of the map by finite differences (pdf = 1/|J| and the mean
of |J| over the square = S, so the density integrates to 1 over it), and Mitsuba's own chi^2 test
(``mitsuba.chi2.ChiSquareTest`` on ``SphericalDomain``, fixed seeds, significance 0.01 Sidak-corrected by
the harness over the CHI2_TESTS tests here), which rejects area sampling of the same rectangle.

Float32 is compared with the float64 numpy map on the same (float32-rounded) inputs; what it loses is
stated case by case in FLOAT32 with the measured value.  The whole module takes 10-21 s on the shared,
loaded 2-core machine (the two 10^6-sample scans 1.3-4.5 s of it).
"""

from __future__ import annotations

import numpy as np
import pytest

from symsphere.warps import (
    spherical_rectangle_to_square,
    square_to_spherical_rectangle,
    square_to_spherical_rectangle_pdf,
)

# (corner, edge1, edge2) seen from the origin
RECTANGLES = {
    "cube face": ([-1, -1, 1], [2, 0, 0], [0, 2, 0]),  # 2 pi / 3
    "off axis": ([0.3, -0.5, 1.2], [2, 0, 0], [0, 1.5, 0]),
    "tilted": ([0.2, 0.1, 1], [1, 0, 1], [0, 2, 0]),
    "rotated": ([0.3, 0.2, 1.0], [0.6, 0.8, 0], [-0.4, 0.3, 0.5]),
    "wall 0.15 away": ([-2, -1.5, 0.15], [4, 0, 0], [0, 3, 0]),  # 5.8 sr
    "nearly a hemisphere": ([-50, -50, 0.01], [100, 0, 0], [0, 100, 0]),  # 2 pi - 1.3e-3
    "1e-7 sr, centred": ([-1.5e-4, -1.5e-4, 1], [3.16e-4, 0, 0], [0, 3.16e-4, 0]),
    "4e-8 sr, off axis": ([0.7, 0.5, 1], [3.16e-4, 0, 0], [0, 3.16e-4, 0]),
    "4e-6 sr, off axis": ([0.7, 0.5, 1], [3.16e-3, 0, 0], [0, 3.16e-3, 0]),
    "2e-7 sr, 1.7e4 away": ([1e4, 1e4, 1e4], [10, 0, 0], [0, 10, 0]),
    "grazing, x0 = 10 z0": ([0.5, 0.0, 0.05], [1, 0, 0], [0, 1, 0]),
    "grazing, x0 = 100 z0": ([5, 0.0, 0.05], [1, 0, 0], [0, 1, 0]),
    "1e-3 above, 2e-3 outside an edge": ([0.002, -1, 0.001], [2, 0, 0], [0, 2, 0]),
    "1e-3 above, 2e-3 inside an edge": ([-0.002, -1, 0.001], [2, 0, 0], [0, 2, 0]),
}

# Float32 against the float64 map (same inputs): bounds on the direction (rad; None: not bounded, the map
# stretches a float32 rounding of uv into a large angle there), on the position of the float32 sample in
# the square (the numpy inverse of the float32 direction against the uv it came from) and on the float32
# round trip uv -> d -> uv, each with what was measured.  What is left in u for a small rectangle far
# off the axis is the rounding of its corner's coordinates in the edges' frame (eps32 |corner| / width).
FLOAT32 = {  # name: bounds (direction, uv, round trip)     measured
    "cube face": (3e-6, 2e-6, 2e-6),  # 1.0e-6, 6.0e-7, 7.2e-7
    "off axis": (5e-6, 5e-6, 5e-6),  # 9.6e-7, 7.3e-7, 7.7e-7
    "tilted": (5e-6, 5e-6, 5e-6),  # 8.0e-7, 1.3e-6, 1.1e-6
    "rotated": (5e-6, 5e-6, 5e-6),  # 5.3e-7, 7.4e-7, 9.5e-7
    "wall 0.15 away": (2e-5, 2e-6, 2e-6),  # 4.1e-6, 2.6e-7, 3.6e-7
    "nearly a hemisphere": (None, 2e-4, 5e-4),  # 0.13 rad at the horizon, 4.1e-5 (on the edge u = 0), 9.5e-5
    "1e-7 sr, centred": (2e-7, 5e-6, 5e-6),  # 2.8e-8, 6.8e-7, 7.2e-7
    "4e-8 sr, off axis": (1e-6, 2e-3, 2e-3),  # 1.5e-7, 4.0e-4, 4.5e-4
    "4e-6 sr, off axis": (1e-6, 2e-4, 2e-4),  # 1.5e-7, 5.0e-5, 4.9e-5
    "2e-7 sr, 1.7e4 away": (1e-6, 2e-3, 2e-3),  # 1.8e-7, 3.3e-4, 3.7e-4
    "grazing, x0 = 10 z0": (5e-6, 5e-6, 5e-6),  # 8.2e-7, 1.0e-6, 1.0e-6
    "grazing, x0 = 100 z0": (5e-6, 1e-4, 1e-4),  # 6.0e-7, 1.9e-5, 1.9e-5
    "1e-3 above, 2e-3 outside an edge": (None, 5e-5, 5e-5),  # 4.2e-3 rad at the edge, 8.2e-6, 8.3e-6
    "1e-3 above, 2e-3 inside an edge": (None, 5e-6, 5e-6),  # 1.5e-3 rad at the edge, 9.4e-7, 8.9e-7
}
N = 20_000


def _uv(n=N, seed=0):
    uv = np.random.default_rng(seed).random((n, 2))
    uv[:8] = [[0, 0], [1, 1], [0, 1], [1, 0], [0, 0.5], [1, 0.5], [0.5, 0], [0.5, 1]]  # corners, edges
    return uv


def _types(mi, f64):
    return (mi.Vector3d, mi.Float64, mi.Point2d) if f64 else (mi.Vector3f, mi.Float, mi.Point2f)


def _rect(mi, rect, f64):
    vector, _, _ = _types(mi, f64)
    return [vector(*(float(x) for x in v)) for v in rect]


def _rounded(rect, f64):
    """The rectangle as the Dr.Jit map sees it: its float32 rounding for float32."""
    return [np.asarray(v, dtype=np.float64 if f64 else np.float32).astype(np.float64) for v in rect]


def _sample(mi, uv, rect, f64):
    import symsphere.mitsuba as sm

    _, real, point = _types(mi, f64)
    dtype = np.float64 if f64 else np.float32
    d = sm.square_to_spherical_rectangle(
        point(real(uv[:, 0].astype(dtype)), real(uv[:, 1].astype(dtype))), *_rect(mi, rect, f64)
    )
    return d, np.stack([d.x.numpy(), d.y.numpy(), d.z.numpy()], axis=1).astype(np.float64)


def _vos(a, b, c):
    """Solid angle of the triangle abc (vectors from the viewer): Van Oosterom & Strackee (1983)."""
    la, lb, lc = (np.linalg.norm(v) for v in (a, b, c))
    triple = abs(np.dot(a, np.cross(b, c)))
    return 2 * np.arctan2(triple, la * lb * lc + np.dot(a, b) * lc + np.dot(a, c) * lb + np.dot(b, c) * la)


def _reference_solid_angle(rect):
    c, e1, e2 = (np.asarray(v, dtype=np.float64) for v in rect)
    return _vos(c, c + e1, c + e1 + e2) + _vos(c, c + e1 + e2, c + e2)


def _hits(d, rect):
    """(s, t) where the ray along d meets the plane of corner + s edge1 + t edge2, and whether it is in front."""
    c, e1, e2 = (np.asarray(v, dtype=np.float64) for v in rect)
    normal = np.cross(e1, e2)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (c @ normal) / (d @ normal)
        p = t[:, None] * d - c
        return np.stack([p @ e1 / (e1 @ e1), p @ e2 / (e2 @ e2)], axis=1), t > 0


@pytest.mark.parametrize("name", RECTANGLES)
def test_float64_equals_numpy_and_independent_references(llvm, name):
    """Float64: the numpy map's directions within 1e-8 (measured <= 1.4e-9, nearly a hemisphere; <= 1.2e-14
    elsewhere but beside an edge, 1.8e-10), its
    solid angle within 1e-8 relative (numpy's own formula loses 2.4e-9 at 1e-7 sr; Van Oosterom &
    Strackee's agrees to 1e-12), pdf = 1/S at every sample, the rays hit the rectangle, and the inverse
    returns uv within 1e-8 (1.6e-12 measured) and the numpy inverse's result."""
    mi = llvm
    import symsphere.mitsuba as sm

    rect = RECTANGLES[name]
    uv = _uv()
    d, got = _sample(mi, uv, rect, True)
    ref = square_to_spherical_rectangle(uv, *rect)
    assert np.max(np.linalg.norm(got - ref, axis=1)) < 1e-8
    s = sm.spherical_rectangle_solid_angle(*_rect(mi, rect, True)).numpy()[0]
    reference = _reference_solid_angle(rect)
    assert s == pytest.approx(reference, rel=1e-12)
    assert 1 / square_to_spherical_rectangle_pdf(ref[8:9], *rect)[0] == pytest.approx(s, rel=1e-8)
    pdf = sm.square_to_spherical_rectangle_pdf(d, *_rect(mi, rect, True)).numpy()
    np.testing.assert_allclose(pdf, 1 / s, rtol=1e-15)
    st, front = _hits(got, rect)
    assert np.all(front) and np.all((st >= -1e-9) & (st <= 1 + 1e-9))
    back = sm.spherical_rectangle_to_square(d, *_rect(mi, rect, True))
    back = np.stack([back.x.numpy(), back.y.numpy()], axis=1)
    np.testing.assert_allclose(back, uv, rtol=0, atol=1e-8)
    interior = np.all((uv > 1e-3) & (uv < 1 - 1e-3), axis=1)  # the numpy inverse clips rays on an edge to 0
    np.testing.assert_allclose(back[interior], spherical_rectangle_to_square(ref, *rect)[interior], rtol=0, atol=1e-8)


@pytest.mark.parametrize("name", RECTANGLES)
def test_float32_against_the_float64_map(llvm, name):
    """Float32 against the numpy float64 map on the same float32 inputs (FLOAT32's bounds); its solid angle
    within 2e-6 relative of Van Oosterom & Strackee's (measured <= 7.6e-7, 1e-7 sr included), pdf = 1/S at every sample (the
    pdf accepts directions within rounding of an edge), every direction finite, unit and hitting the
    rectangle (its sample point is clamped into it), the inverse in [0, 1]^2."""
    mi = llvm
    import symsphere.mitsuba as sm

    rect = RECTANGLES[name]
    f32 = _rounded(rect, False)
    uv = _uv().astype(np.float32).astype(np.float64)
    d, got = _sample(mi, uv, rect, False)
    assert np.all(np.isfinite(got)) and np.allclose(np.linalg.norm(got, axis=1), 1, atol=1e-6)
    direction_bound, uv_bound, round_trip_bound = FLOAT32[name]
    if direction_bound is not None:
        ref = square_to_spherical_rectangle(uv, *f32)
        assert np.max(np.linalg.norm(got - ref, axis=1)) < direction_bound
    unit = got / np.linalg.norm(got, axis=1, keepdims=True)
    inside = square_to_spherical_rectangle_pdf(unit, *f32) > 0  # the numpy inverse clips the rest to (0, 0)
    assert inside.mean() > 0.99
    where = spherical_rectangle_to_square(unit, *f32)
    assert np.max(np.abs(where - uv)[inside]) < uv_bound
    s = sm.spherical_rectangle_solid_angle(*_rect(mi, rect, False)).numpy()[0]
    assert s == pytest.approx(_reference_solid_angle(f32), rel=2e-6)
    pdf = sm.square_to_spherical_rectangle_pdf(d, *_rect(mi, rect, False)).numpy()
    assert np.all(pdf == np.float32(1) / np.float32(s))
    # every direction within float32's rounding of one that meets the rectangle: the angle to the nearest
    # point of the rectangle (where the ray meets its plane, clamped into it) below 4e-7 rad
    st, front = _hits(got, f32)
    c, e1, e2 = f32
    nearest = c + np.clip(st[:, :1], 0, 1) * e1 + np.clip(st[:, 1:], 0, 1) * e2
    nearest /= np.linalg.norm(nearest, axis=1, keepdims=True)
    assert np.all(front) and np.max(np.linalg.norm(np.cross(got, nearest), axis=1)) < 4e-7
    back = sm.spherical_rectangle_to_square(d, *_rect(mi, rect, False))
    back = np.stack([back.x.numpy(), back.y.numpy()], axis=1)
    assert np.all(np.isfinite(back)) and np.all((back >= 0) & (back <= 1))
    assert np.max(np.abs(back - uv)) < round_trip_bound


@pytest.mark.parametrize("f64", [True, False], ids=["float64", "float32"])
@pytest.mark.parametrize("name", ["cube face", "tilted", "wall 0.15 away", "grazing, x0 = 10 z0"])
def test_pdf_equals_numpy_on_any_direction(llvm, name, f64):
    """The pdf of 2 * 10^5 directions, half uniform on the sphere and half within 1e-4 rad of the rectangle's
    plane (where a slack for rounding that grew as the ray grazes the plane once let a band of directions
    in): 1/S or 0 as the numpy pdf says, except within 1e-5 (float32; 1e-12 float64) of an edge of the
    rectangle (s or t of the ray's hit), where rounding decides."""
    mi = llvm
    import symsphere.mitsuba as sm

    rect = _rounded(RECTANGLES[name], f64)
    rng = np.random.default_rng(21)
    d = rng.normal(size=(200_000, 3))
    c, e1, e2 = rect
    normal = np.cross(e1, e2) / np.linalg.norm(np.cross(e1, e2))
    d[100_000:] -= (d[100_000:] @ normal)[:, None] * normal  # into the plane through the viewer,
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    d[100_000:] += rng.uniform(-1e-4, 1e-4, (100_000, 1)) * normal  # then off it by up to 1e-4 rad
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    if not f64:
        d = d.astype(np.float32).astype(np.float64)
    vector, real, _ = _types(mi, f64)
    dtype = np.float64 if f64 else np.float32
    got = sm.square_to_spherical_rectangle_pdf(
        vector(*(real(d[:, i].astype(dtype)) for i in range(3))), *_rect(mi, RECTANGLES[name], f64)
    ).numpy()
    want = square_to_spherical_rectangle_pdf(d, *rect)
    st, front = _hits(d, rect)
    slack = 1e-12 if f64 else 1e-5
    near_edge = (
        front
        & np.all((st > -slack) & (st < 1 + slack), axis=1)
        & np.any((np.abs(st) < slack) | (np.abs(st - 1) < slack), axis=1)
    )
    assert np.all(((got > 0) == (want > 0)) | near_edge)
    assert np.count_nonzero(want > 0) > 300
    s = sm.spherical_rectangle_solid_angle(*_rect(mi, RECTANGLES[name], f64)).numpy()[0]
    assert np.all(got[got > 0] == got.dtype.type(1) / got.dtype.type(s))


@pytest.mark.parametrize("name", ["cube face", "tilted", "wall 0.15 away", "4e-6 sr, off axis"])
def test_pdf_is_the_inverse_jacobian(llvm, name):
    """Float64, central differences (step 1e-5) on a 40 x 40 midpoint grid: |d_u x d_v| / S = 1 within 1e-5
    (the map is area-preserving: pdf = 1/S = 1/|J|), and the mean of |J| over the grid is Van Oosterom &
    Strackee's S within 1e-5 relative (the density 1/S integrates to 1 over the square)."""
    mi = llvm
    rect = RECTANGLES[name]
    g = (np.arange(40) + 0.5) / 40
    uv = np.stack(np.meshgrid(g, g, indexing="ij"), axis=-1).reshape(-1, 2)
    h = 1e-5

    def at(p):
        return _sample(mi, p, rect, True)[1]

    du = (at(uv + [h, 0]) - at(uv - [h, 0])) / (2 * h)
    dv = (at(uv + [0, h]) - at(uv - [0, h])) / (2 * h)
    jacobian = np.linalg.norm(np.cross(du, dv), axis=1)
    s = _reference_solid_angle(rect)
    np.testing.assert_allclose(jacobian / s, 1, rtol=1e-5)
    assert jacobian.mean() == pytest.approx(s, rel=1e-5)


@pytest.mark.parametrize("f64", [True, False], ids=["float64", "float32"])
def test_degenerate_rectangles_give_no_nan(llvm, f64):
    """Seen edge-on, the viewer in the plane inside or outside the rectangle or at a corner, within
    rounding of the plane, an edge of zero or non-finite length, coordinates of 1e30: S = 0, pdf 0, the
    direction finite and unit, the inverse (0, 0)."""
    mi = llvm
    import symsphere.mitsuba as sm

    cases = [
        ([1, 0, 0], [1, 0, 0], [0, 1, 0]),  # in the plane, outside
        ([-1, -1, 0], [2, 0, 0], [0, 2, 0]),  # in the plane, inside
        ([0, 0, 0], [1, 0, 0], [0, 1, 0]),  # at a corner
        ([-1, -1, 1e-12 if f64 else 1e-6], [1e3, 0, 0], [0, 1e3, 0]),  # within rounding of the plane
        ([-1, -1, 1], [0, 0, 0], [0, 1, 0]),  # a zero edge
        ([-1, -1, 1], [float("inf"), 0, 0], [0, 1, 0]),
        ([1e30, 1e30, 1e30], [1e30, 0, 0], [0, 1e30, 0]),
    ]
    _, real, point = _types(mi, f64)
    uv = _uv(64, seed=5)
    for rect in cases:
        r = _rect(mi, rect, f64)
        s = sm.spherical_rectangle_solid_angle(*r).numpy()
        if rect[0][0] != 1e30 or not f64:  # float64 sees the 1e30 rectangle: a proper one
            assert np.all(s == 0), rect
        d = sm.square_to_spherical_rectangle(point(real(uv[:, 0]), real(uv[:, 1])), *r)
        got = np.stack([d.x.numpy(), d.y.numpy(), d.z.numpy()], axis=1).astype(np.float64)
        assert np.all(np.isfinite(got)) and np.allclose(np.linalg.norm(got, axis=1), 1, atol=1e-6), rect
        pdf = sm.square_to_spherical_rectangle_pdf(d, *r).numpy()
        back = sm.spherical_rectangle_to_square(d, *r)
        back = np.stack([back.x.numpy(), back.y.numpy()], axis=1)
        assert np.all(np.isfinite(pdf)) and np.all(np.isfinite(back)), rect
        if np.all(s == 0):
            assert np.all(pdf == 0) and np.all(back == 0), rect


def _adversarial(n, rng):
    """n rectangles (corner, edge1, edge2) in random orthonormal frames, a seventh of each kind: random;
    tiny (10^2..10^4.5 away, 1e-7 sr and below); nearly a hemisphere (10..1000 wide, 1e-5..0.1 away);
    edge-on (z0 exactly 0, 1e-30, 1e-20, 1e-12, 1e-7); grazing (10..1e4 along x, 1e-4..0.1 above); the
    viewer at a corner or on an edge (in the plane, 1e-6 or 1 above); slivers (1e-8..1e-4 wide)."""
    kind = rng.integers(0, 7, n)
    q = rng.normal(size=(n, 3))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    t = rng.normal(size=(n, 3))
    t -= (t * q).sum(1, keepdims=True) * q
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    normal = np.cross(q, t)
    w, h = 10 ** rng.uniform(-2, 1, n), 10 ** rng.uniform(-2, 1, n)
    x0, y0 = rng.uniform(-2, 1, n) * w, rng.uniform(-2, 1, n) * h
    z = 10 ** rng.uniform(-2, 1, n) * rng.choice([-1, 1], n)
    k = kind == 1
    dist = 10 ** rng.uniform(2, 4.5, n)
    x0, y0, z = (
        np.where(k, rng.uniform(-1, 1, n) * dist, x0),
        np.where(k, rng.uniform(-1, 1, n) * dist, y0),
        np.where(k, dist, z),
    )
    w, h = np.where(k, 10 ** rng.uniform(-1, 0.5, n), w), np.where(k, 10 ** rng.uniform(-1, 0.5, n), h)
    k = kind == 2
    x0, y0 = np.where(k, -(10 ** rng.uniform(1, 3, n)), x0), np.where(k, -(10 ** rng.uniform(1, 3, n)), y0)
    w, h = np.where(k, -2 * x0 * rng.uniform(0.9, 1.1, n), w), np.where(k, -2 * y0 * rng.uniform(0.9, 1.1, n), h)
    z = np.where(k, 10 ** rng.uniform(-5, -1, n), z)
    z = np.where(kind == 3, rng.choice([0.0, 1e-30, -1e-20, 1e-12, 1e-7], n), z)
    k = kind == 4
    x0, z = np.where(k, 10 ** rng.uniform(1, 4, n), x0), np.where(k, 10 ** rng.uniform(-4, -1, n), z)
    k = kind == 5
    x0, y0 = np.where(k, 0.0, x0), np.where(k, rng.choice([0.0, -0.5], n) * h, y0)
    z = np.where(k, rng.choice([0.0, 1e-6, 1.0], n), z)
    w = np.where(kind == 6, 10 ** rng.uniform(-8, -4, n), w)
    corner = x0[:, None] * q + y0[:, None] * t + z[:, None] * normal
    return corner, w[:, None] * q, h[:, None] * t


def adversarial_samples(mi, sm, f64, n, rng):
    """The maps on n adversarial rectangles (:func:`_adversarial`), 10 % of the points on the square's
    corners and edges: (directions, S, pdf, inverse) as float64 numpy arrays (also the 10^8 scan's,
    benchmarks/scan_spherical_rectangle_drjit.py)."""
    corner, edge1, edge2 = _adversarial(n, rng)
    uv = rng.random((n, 2))
    edge = rng.random(n) < 0.05
    uv[edge] = rng.choice([0.0, 1.0], size=(edge.sum(), 2))
    edge = rng.random(n) < 0.05
    uv[edge, 0] = rng.choice([0.0, 1.0], size=edge.sum())
    vector, real, point = _types(mi, f64)
    dtype = np.float64 if f64 else np.float32
    r = [vector(*(real(a[:, i].astype(dtype)) for i in range(3))) for a in (corner, edge1, edge2)]
    d = sm.square_to_spherical_rectangle(point(real(uv[:, 0].astype(dtype)), real(uv[:, 1].astype(dtype))), *r)
    s = sm.spherical_rectangle_solid_angle(*r).numpy().astype(np.float64)
    pdf = sm.square_to_spherical_rectangle_pdf(d, *r).numpy().astype(np.float64)
    back = sm.spherical_rectangle_to_square(d, *r)
    got = np.stack([d.x.numpy(), d.y.numpy(), d.z.numpy()], axis=1).astype(np.float64)
    return got, s, pdf, np.stack([back.x.numpy(), back.y.numpy()], axis=1)


@pytest.mark.parametrize("f64", [True, False], ids=["float64", "float32"])
def test_no_nan_or_inf_on_a_million_adversarial_samples(llvm, f64):
    """10^6 samples, each lane its own rectangle (_adversarial), 10 % of the points on the square's corners
    and edges: every direction finite and unit, every S in [0, 2 pi], every pdf finite and 1/S at the
    map's own direction where S > 0 (so the direction hits the rectangle), every inverse in [0, 1]^2.
    1.3-4.5 s per dtype; benchmarks/scan_spherical_rectangle_drjit.py repeats it for 10^8 samples."""
    mi = llvm
    import symsphere.mitsuba as sm

    got, s, pdf, back = adversarial_samples(mi, sm, f64, 1_000_000, np.random.default_rng(17 if f64 else 18))
    assert np.all(np.isfinite(got)) and np.allclose(np.linalg.norm(got, axis=1), 1, atol=1e-5)
    assert np.all((s >= 0) & (s <= float(np.float32(2 * np.pi))))
    valid = s > 0
    assert 0.6 < valid.mean() < 0.95  # the edge-on kinds are degenerate (more of them in float32)
    assert np.all(np.isfinite(pdf)) and np.all(pdf[~valid] == 0)
    np.testing.assert_allclose(pdf[valid] * s[valid], 1, rtol=1e-6)
    assert np.all(np.isfinite(back)) and np.all((back >= 0) & (back <= 1))


# --- Mitsuba's chi^2 test ---------------------------------------------------------------------------

CHI2_CASES = [(name, f64) for name in ("cube face", "tilted", "wall 0.15 away") for f64 in (True, False)]
CHI2_TESTS = len(CHI2_CASES) + 1  # and the rejection of area sampling


def _chi2(mi, sample, pdf, seed):
    from mitsuba.chi2 import ChiSquareTest, SphericalDomain

    return ChiSquareTest(domain=SphericalDomain(), sample_func=sample, pdf_func=pdf, sample_dim=2,
                         sample_count=400_000, res=51, ires=32, seed=seed)  # fmt: skip


@pytest.mark.statistical
@pytest.mark.parametrize("name, f64", CHI2_CASES)
def test_mitsuba_chi2(llvm, name, f64, tmp_path, monkeypatch):
    mi = llvm
    monkeypatch.chdir(tmp_path)  # a rejected test writes chi2_data.py into the working directory
    import symsphere.mitsuba as sm

    r = _rect(mi, RECTANGLES[name], f64)
    _, real, point = _types(mi, f64)

    def sample(s):
        d = sm.square_to_spherical_rectangle(point(real(s.x), real(s.y)), *r)
        return mi.Vector3f(mi.Float(d.x), mi.Float(d.y), mi.Float(d.z))

    def pdf(v):
        return mi.Float(sm.square_to_spherical_rectangle_pdf(v, *r))

    test = _chi2(mi, sample, pdf, CHI2_CASES.index((name, f64)))
    assert test.run(significance_level=0.01, test_count=CHI2_TESTS), test.messages


@pytest.mark.statistical
def test_mitsuba_chi2_rejects_area_sampling(llvm, tmp_path, monkeypatch):
    """The harness has the power to see the map's point: uniform in area, the wall 0.15 away is rejected."""
    mi = llvm
    monkeypatch.chdir(tmp_path)
    import drjit as dr

    import symsphere.mitsuba as sm

    corner, edge1, edge2 = _rect(mi, RECTANGLES["wall 0.15 away"], False)

    def sample(s):
        return dr.normalize(corner + s.x * edge1 + s.y * edge2)

    def pdf(v):
        return sm.square_to_spherical_rectangle_pdf(v, corner, edge1, edge2)

    test = _chi2(mi, sample, pdf, 99)
    assert not test.run(significance_level=0.01, test_count=CHI2_TESTS)
