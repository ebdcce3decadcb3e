"""symsphere.render._integrator and _emitters: frame, MIS, emitter sampling, NEE, statistics (the directions: test_directions.py).

Statistical tests use fixed seeds (a run passes or fails reproducibly); each
family's threshold is Sidak-corrected so that a correct renderer fails any
test of the family with probability FAMILY_SIGNIFICANCE = 0.01 over the choice
of seeds, and each compares against an independent reference: a closed form,
or the other integrator.

Furnace
    Inside a closed diffuse sphere of albedo rho emitting Le, the radiance is
    exactly Le / (1 - rho).  Pixels have independent random streams (and
    independent scrambles), so they are the independent units: the stated
    error is the standard deviation of the pixel means over sqrt(#pixels).
    Each test asks for the mean within 4 standard errors (two-sided
    p = 6.3e-5; 156 tests: family-wise 0.0098).  Uniform-direction samplers
    (every sampler but the five cosine ones) weight a bounce by
    X = 2 rho cos(theta) with cos(theta) uniform, E[X^2] = 4 rho^2 / 3, which
    exceeds 1 for rho > sqrt(3)/2 = 0.866: their variance in the closed diffuse
    furnace is then infinite and no standard error means anything.  So the
    closed diffuse furnace uses rho = 0.3, 0.6 and 0.85 for them (0.9 for the
    cosine samplers); the translucent furnace (Lambertian reflection +
    transmission, full-sphere sampling, background Le / (1 - rho)), where only
    reflected paths continue (E[X^2 1{reflected}] = 2 rho^2 / 3), runs all
    samplers at rho = 0.3, 0.6, 0.9.  Every (integrator, sampler) pair.

Closed-form direct lighting (NEE and MIS)
    A diffuse plane under a spherical light (irradiance pi L (r/D)^2 cos(beta),
    ``integrands.sphere_light_irradiance``) and under a square light (Lambert's
    polygon formula, ``integrands.lambert_irradiance``); the light is black, so
    the plane's radiance is exactly (rho / pi) E.  The reference pixel value is
    that closed form integrated over the pixel by 4 x 4 Gauss-Legendre
    quadrature (the box filter).  Per 8 x 8 block, t = mean residual /
    (its standard deviation / 8), 63 degrees of freedom; 2 lights x 6 samplers
    x 6 blocks = 72 tests, Sidak-corrected.

Unbiasedness against the other integrator
    Every (integrator, sampler) pair renders a 32 x 24 Cornell box as R = 8
    independent replicates of 48 spp; the reference of the ``path`` pairs is
    8 replicates of 512 spp with ``bsdf`` and ``cosine``, that of the ``bsdf``
    pairs 8 replicates of 256 spp with ``path`` and ``cosine`` (other seeds).
    Per pixel, the replicate mean and its variance (sample variance / R); per
    8 x 8 block and channel, the block mean and its variance (sum of the pixel
    variances / 64^2: pixels are independent).  z = (block mean - reference
    block mean) / sqrt(var + reference var), two-sided, 12 blocks x 3 channels
    x 26 pairs = 936 tests, Sidak-corrected.  The translucent scene (two quad
    lights, Lambertian transmission) does the same for 4 ``path`` samplers
    against ``bsdf``/``cosine``.
"""

import dataclasses
import functools
import json
import math
import os
import subprocess
import sys
import zlib

import numpy as np
import pytest
from numba import njit
from scipy import stats

from symsphere import frames
from symsphere._testing import kernels, strategies
from symsphere._testing import render_emitters as E
from symsphere._testing import render_integrator as K
from symsphere._testing import render_probes as P
from symsphere.integrands import lambert_irradiance, sphere_light_irradiance
from symsphere.render import (
    INTEGRATORS,
    SAMPLERS,
    Camera,
    HalfSpace,
    Material,
    Quad,
    Scene,
    Sphere,
    cornell,
    diffuse,
    furnace,
    render,
    translucent_scene,
)

METHOD_CODES = kernels.METHOD_CODES


def _words(sampler):
    """render()'s strategy, points and method for an earlier sampler name (the cases' names: their seeds
    come from their index, so that they stay those of docs/results/render-validation.md)."""
    strategy, points, method = strategies.SAMPLER_SPELLINGS[sampler]
    return dict(strategy=strategy, points=points, method=method)


FAMILY_SIGNIFICANCE = 0.01
# The interlaced samplers' pairs last: the seeds of the others (from their index) stay those of docs/results/render-validation.md.
_PAIRS = sorted(((i, s) for i in INTEGRATORS for s in SAMPLERS), key=lambda pair: "interlaced" in pair[1])
_COSINE_SAMPLERS = (
    "cosine", "symmetric_cosine", "symmetric_cosine_sobol", "symmetric_cosine_sobol_interlaced2",
    "symmetric_cosine_sobol_interlaced3",
)  # fmt: skip


def _sidak(tests, family=FAMILY_SIGNIFICANCE):
    """Per-test significance so that `tests` independent tests fail with probability `family` together."""
    return 1 - (1 - family) ** (1 / tests)


# --- the frame ------------------------------------------------------------------


@njit
def _compiled_frame(normals):
    out = np.empty((normals.shape[0], 3, 3))
    for i in range(normals.shape[0]):
        t, b = frames.frame_rows(normals[i, 0], normals[i, 1], normals[i, 2])
        for j in range(3):
            out[i, 0, j] = t[j]
            out[i, 1, j] = b[j]
            out[i, 2, j] = normals[i, j]
    return out


def test_the_kernels_frame_is_frames_frame():
    """One formula (frames.frame_rows): compiled by numba, as the kernels use it, it equals frames.frame bit for bit."""
    rng = np.random.default_rng(0)
    normals = rng.normal(size=(200, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.vstack([normals, [[0, 0, 1], [0, 0, -1], [1, 0, 0], [0, -1, 0], [0.6, 0, -0.8]]])
    compiled = _compiled_frame(normals)
    for n, f in zip(normals, compiled, strict=False):
        np.testing.assert_array_equal(f, frames.frame(n))
        np.testing.assert_allclose(f @ f.T, np.eye(3), atol=1e-15)


# --- MIS ---------------------------------------------------------------------------


@njit
def _heuristic(a, b):
    return E.power_heuristic(a, b)


def test_power_heuristic():
    assert _heuristic(1.0, 1.0) == 0.5
    assert _heuristic(3.0, 1.0) == pytest.approx(0.9)
    rng = np.random.default_rng(1)
    for a, b in rng.exponential(size=(100, 2)):
        assert _heuristic(a, b) + _heuristic(b, a) == pytest.approx(1.0, abs=1e-15)
        assert _heuristic(a, b) == pytest.approx(a * a / (a * a + b * b), rel=1e-14)
    assert _heuristic(math.inf, 2.0) == 1.0 and _heuristic(2.0, math.inf) == 0.0  # the paper maps' vertex
    assert _heuristic(0.0, 1.0) == 0.0 and _heuristic(1.0, 0.0) == 1.0


# --- emitter sampling and the clipped sphere ------------------------------------------------


def _tables(spheres=(), quads=()):
    camera = Camera((0, 0, 10), (0, 0, -1), 40)
    scene = Scene("t", camera, {"lamp": diffuse(0.0, emission=1.0)}, tuple(spheres), tuple(quads))
    a = scene.arrays(4, 4)
    return a["spheres"], a["quads"]


def _cone(axis, cos_max, count, rng):
    """Uniform directions in a cone (numpy, independent of the kernels) and their pdf."""
    axis = np.asarray(axis, dtype=np.float64) / np.linalg.norm(axis)
    helper = np.array([1.0, 0, 0]) if abs(axis[0]) < 0.9 else np.array([0, 1.0, 0])
    t = np.cross(axis, helper)
    t /= np.linalg.norm(t)
    b = np.cross(axis, t)
    cos_t = 1 - rng.random(count) * (1 - cos_max)
    phi = 2 * np.pi * rng.random(count)
    sin_t = np.sqrt(1 - cos_t**2)
    d = (sin_t * np.cos(phi))[:, None] * t + (sin_t * np.sin(phi))[:, None] * b + cos_t[:, None] * axis
    return d, 1 / (2 * np.pi * (1 - cos_max))


_CORNELL_LIGHT = Sphere((50, 681.6 - 0.27, 81.6), 600, "lamp", HalfSpace((50, 81.6, 81.6), (0, -1, 0)))
_PDF_CASES = [
    # (name, emitter, point, axis of a cone that holds it, cos of the cone's half-angle: 1 - ... ; -1: all directions)
    ("cap from below its centre", _CORNELL_LIGHT, (50, 10, 81.6), (0, 1, 0), math.cos(math.atan(19 / 71.3))),
    ("cap from the side", _CORNELL_LIGHT, (20, 40, 30), (30, 41.5, 51.6), math.cos(0.4)),
    ("sphere from outside (cone)", Sphere((0, 0, 0), 1.0, "lamp"), (0.3, -0.5, 2.5), (-0.3, 0.5, -2.5), math.cos(0.45)),
    ("sphere from inside (area)", Sphere((0, 0, 0), 1.0, "lamp"), (0.3, 0.2, -0.5), (0, 0, 1), -1.0),
    ("clipped sphere from inside", Sphere((0, 0, 0), 1.0, "lamp", HalfSpace((0, 0.2, 0), (0.6, 0.8, 0))),
     (0.1, -0.2, 0.1), (0, 0, 1), -1.0),
    ("quad", Quad((-0.5, -0.5, 0), (1, 0, 0), (0, 1.5, 0), "lamp"), (0.2, 0.3, -1.5), (-0.2, -0.05, 1.5),
     math.cos(0.6)),
]  # fmt: skip


# The tests of the emitter probes (first_hits, emitter_pdfs, emitter_samples) on one xdist worker (Makefile:
# --dist loadgroup): the probes' compile (~3 CPU-s) is done once, not by both workers at once.
_EMITTER_PROBES = pytest.mark.xdist_group("emitter_probes")


@_EMITTER_PROBES
@pytest.mark.parametrize("name, emitter, point, axis, cos_max", _PDF_CASES, ids=[c[0] for c in _PDF_CASES])
def test_emitter_pdf_integrates_to_one_over_the_visible_emitter(name, emitter, point, axis, cos_max):
    """E over directions uniform in a cone holding the emitter of [hit] emitter_pdf / q = 1 (each point seen once).

    The directions and their density q are numpy's (independent of the
    kernels); the hits are the kernel's intersection.  Sidak over the cases.
    """
    is_quad = isinstance(emitter, Quad)
    spheres, quads = _tables(quads=(emitter,)) if is_quad else _tables(spheres=(emitter,))
    rng = np.random.default_rng(zlib.crc32(name.encode()))  # a fixed seed per case (hash() of a str is not)
    count = 400_000
    directions, q = _cone(axis, cos_max, count, rng)
    origins = np.broadcast_to(np.asarray(point, dtype=np.float64), directions.shape).copy()
    ts, hits = P.first_hits(origins, directions, spheres, quads, 1e-9)
    hit = hits == 0
    assert 0.05 < hit.mean() <= 1.0
    if is_quad:
        cosines = np.abs(directions[hit] @ np.array(quads[9:12, 0]))
    else:
        normals = (origins[hit] + ts[hit, None] * directions[hit] - spheres[:3, 0]) / spheres[3, 0]
        cosines = np.abs(np.sum(normals * directions[hit], axis=1))
    values = np.zeros(count)
    values[hit] = P.emitter_pdfs(np.asarray(point, dtype=np.float64), 0, ts[hit], cosines, spheres, quads) / q
    mean, error = values.mean(), values.std(ddof=1) / math.sqrt(count)
    critical = stats.norm.isf(_sidak(len(_PDF_CASES)) / 2)
    assert abs(mean - 1) < critical * error and error < 0.01, (mean, error)


@_EMITTER_PROBES
@pytest.mark.parametrize("name, emitter, point, axis, cos_max", _PDF_CASES, ids=[c[0] for c in _PDF_CASES])
def test_emitter_samples_lie_on_the_emitter_with_the_stated_pdf(name, emitter, point, axis, cos_max):
    """sample_emitter: points on the (clipped) emitter, visible from p, and emitter_pdf gives their pdf."""
    is_quad = isinstance(emitter, Quad)
    spheres, quads = _tables(quads=(emitter,)) if is_quad else _tables(spheres=(emitter,))
    p = np.asarray(point, dtype=np.float64)
    out = P.emitter_samples(p, 0, 3, 20_000, spheres, quads)
    assert np.all(out[:, 5] == 1) and np.all(np.isfinite(out)) and np.all(out[:, 4] > 0)
    w = out[:, :3]
    np.testing.assert_allclose(np.linalg.norm(w, axis=1), 1, atol=1e-14)
    ts, hits = P.first_hits(np.broadcast_to(p, w.shape).copy(), w, spheres, quads, 1e-9)
    assert np.all(hits == 0)  # every sampled direction reaches the emitter
    np.testing.assert_allclose(ts, out[:, 3], rtol=1e-9)  # the first hit is the sampled point (cone: its distance)
    q = p + ts[:, None] * w
    if is_quad:
        cosines = np.abs(w @ quads[9:12, 0])
    else:
        normals = (q - spheres[:3, 0]) / spheres[3, 0]
        np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1, atol=1e-9)
        cosines = np.abs(np.sum(normals * w, axis=1))
        if emitter.clip is not None:
            a, d = spheres[5:8, 0], spheres[8, 0]
            assert np.all(q @ a >= d - 1e-9 * np.abs(d) - 1e-12)
    np.testing.assert_allclose(P.emitter_pdfs(p, 0, ts, cosines, spheres, quads), out[:, 4], rtol=1e-6)


@_EMITTER_PROBES
def test_cap_and_cone_and_quad_samples_have_their_distributions():
    """Kolmogorov-Smirnov: cap heights and azimuths uniform (Archimedes), cone cosines uniform, quad points uniform.

    Five tests, Sidak-corrected.
    """
    critical_p = _sidak(5)
    # cornell's cap: the height y of the sampled point is uniform on [81.33, 81.6]
    spheres, quads = _tables(spheres=(_CORNELL_LIGHT,))
    p = np.array([40.0, 20.0, 70.0])
    out = P.emitter_samples(p, 0, 81, 4000, spheres, quads)
    y = p[1] + out[:, 3] * out[:, 1]
    assert y.max() <= 81.6 + 1e-9 and y.min() >= 81.33 - 1e-9
    assert stats.kstest((y - 81.33) / 0.27, "uniform").pvalue > critical_p
    q = p + out[:, 3:4] * out[:, :3]
    azimuth = np.arctan2(q[:, 2] - 81.6, q[:, 0] - 50)
    assert stats.kstest((azimuth + np.pi) / (2 * np.pi), "uniform").pvalue > critical_p
    # a sphere from outside: cos to the centre uniform on [cos theta_max, 1]
    spheres, quads = _tables(spheres=(Sphere((0, 0, 0), 1.0, "lamp"),))
    p = np.array([0.0, 0.0, 3.0])
    out = P.emitter_samples(p, 0, 82, 4000, spheres, quads)
    cos_max = math.sqrt(1 - 1 / 9)
    assert stats.kstest((-out[:, 2] - cos_max) / (1 - cos_max), "uniform").pvalue > critical_p
    # a parallelogram: both coordinates uniform
    quad = Quad((-0.5, -0.5, 0), (1, 0, 0), (0.5, 1.5, 0), "lamp")
    spheres, quads = _tables(quads=(quad,))
    p = np.array([0.1, 0.2, -1.0])
    out = P.emitter_samples(p, 0, 83, 4000, spheres, quads)
    q = p + out[:, 3:4] * out[:, :3]
    st = np.linalg.solve(np.array([[1, 0.5], [0, 1.5]]), (q[:, :2] - [-0.5, -0.5]).T).T
    for column in st.T:
        assert stats.kstest(column, "uniform").pvalue > critical_p


def _triangle_solid_angle(a, b, c):
    """Van Oosterom & Strackee (1983): tan(E/2) = |a . (b x c)| / (|a||b||c| + (a.b)|c| + (a.c)|b| + (b.c)|a|)."""
    la, lb, lc = (np.linalg.norm(v, axis=-1) for v in (a, b, c))
    numerator = np.abs(np.sum(a * np.cross(b, c), axis=-1))
    denominator = la * lb * lc + np.sum(a * b, axis=-1) * lc + np.sum(a * c, axis=-1) * lb + np.sum(b * c, axis=-1) * la
    return 2 * np.arctan2(numerator, denominator)


@_EMITTER_PROBES
@pytest.mark.parametrize("point", [(0.2, 0.3, -0.8), (2.5, -0.4, 0.3), (0.1, 0.2, 0.05)])
def test_rectangle_samples_are_uniform_in_solid_angle(point):
    """Urena et al. 2013: a 4 x 4 grid of sub-rectangles receives samples in proportion to their solid angles.

    Solid angles by Van Oosterom & Strackee (two triangles per cell, numpy);
    chi-square with 15 degrees of freedom, 3 points of view, Sidak-corrected.
    """
    corner, e1, e2 = np.array([-0.5, -0.5, 0.0]), np.array([1.0, 0, 0]), np.array([0, 1.5, 0])
    spheres, quads = _tables(quads=(Quad(tuple(corner), tuple(e1), tuple(e2), "lamp"),))
    assert quads[25, 0] == 1.0  # recognised as a rectangle
    p = np.asarray(point, dtype=np.float64)
    count = 40_000
    out = P.emitter_samples(p, 0, 17, count, spheres, quads)
    assert np.all(out[:, 5] == 1)
    q = p + out[:, 3:4] * out[:, :3]
    np.testing.assert_allclose(q[:, 2], 0.0, atol=1e-12)  # on the rectangle's plane ...
    s, t = (q[:, 0] + 0.5) / 1.0, (q[:, 1] + 0.5) / 1.5
    assert s.min() >= -1e-12 and s.max() <= 1 + 1e-12 and t.min() >= -1e-12 and t.max() <= 1 + 1e-12  # ... inside
    edges = np.linspace(0, 1, 5)
    cells = np.array([[corner + a * e1 + b * e2 for a in edges] for b in edges]) - p  # (5, 5, 3), rows: t
    omega = _triangle_solid_angle(cells[:-1, :-1], cells[:-1, 1:], cells[1:, 1:]) + _triangle_solid_angle(
        cells[:-1, :-1], cells[1:, 1:], cells[1:, :-1]
    )
    np.testing.assert_allclose(out[:, 4], 1 / omega.sum(), rtol=1e-9)  # pdf = 1 / solid angle
    counts = np.histogram2d(np.clip(t, 0, 1 - 1e-15), np.clip(s, 0, 1 - 1e-15), bins=[edges, edges])[0]
    expected = count * omega / omega.sum()
    statistic = np.sum((counts - expected) ** 2 / expected)
    assert stats.chi2.sf(statistic, df=15) > _sidak(3), (statistic, counts, expected)


@_EMITTER_PROBES
def test_rectangle_solid_angle_everywhere():
    """emitter_pdf of a rectangle = 1 / its solid angle (Van Oosterom & Strackee, numpy) from points all around it.

    The kernel forms the solid angle from one atan2 of a product of complex
    numbers, on either side of pi: points far off (solid angle near the
    1e-3 threshold), next to its plane over its interior (near 2 pi), off to
    a side, behind it; and an edge not along an axis.
    """
    rng = np.random.default_rng(20261130)
    corner, e1, e2 = np.array([0.3, -0.2, 0.1]), np.array([0.8, 0.6, 0.0]), np.array([0.0, 0.0, 1.3]) * 1.0
    spheres, quads = _tables(quads=(Quad(tuple(corner), tuple(e1), tuple(e2), "lamp"),))
    assert quads[25, 0] == 1.0
    normal = np.cross(e1, e2) / np.linalg.norm(np.cross(e1, e2))
    st = rng.uniform(-1.5, 2.5, (4000, 2))
    height = np.concatenate([rng.uniform(-30, 30, 1000), rng.uniform(-1, 1, 1000), rng.uniform(-1e-3, 1e-3, 2000)])
    points = corner + st[:, :1] * e1 + st[:, 1:] * e2 + height[:, None] * normal
    a, b, c, d = (corner + i * e1 + j * e2 - points for i, j in ((0, 0), (1, 0), (1, 1), (0, 1)))
    omega = _triangle_solid_angle(a, b, c) + _triangle_solid_angle(a, c, d)
    keep = omega > 1.1e-3
    assert keep.sum() > 2000 and omega.max() > 6.2  # up to almost 2 pi
    for p, expected in zip(points[keep], omega[keep], strict=False):
        pdf = P.emitter_pdfs(p, 0, np.array([1.0]), np.array([1.0]), spheres, quads)[0]
        assert math.isclose(pdf, 1 / expected, rel_tol=1e-8), (p, pdf, 1 / expected)


@_EMITTER_PROBES
def test_clipped_sphere_intersection_against_numpy():
    """The kernel's nearest kept root equals a direct numpy solution of the quadratic with the half-space test."""
    center, radius = np.array([0.2, -0.1, 0.3]), 1.3
    point, normal = np.array([0.0, 0.3, 0.0]), np.array([0.6, 0.8, 0.0])
    spheres, quads = _tables(spheres=(Sphere(tuple(center), radius, "lamp", HalfSpace(tuple(point), tuple(normal))),))
    rng = np.random.default_rng(12)
    origins = rng.uniform(-3, 3, size=(100_000, 3))  # outside and inside the sphere ...
    directions = center + rng.uniform(-1.5, 1.5, size=(100_000, 3)) - origins  # ... aimed near it
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    eps = 1e-7
    ts, hits = P.first_hits(origins, directions, spheres, quads, eps)
    oc = origins - center
    b = -np.sum(oc * directions, axis=1)
    disc = b * b - np.sum(oc * oc, axis=1) + radius * radius
    root = np.sqrt(np.maximum(disc, 0))
    expected = np.full(len(origins), np.inf)
    for t in (b + root, b - root):  # the nearer kept root wins: test the far one first
        inside = ((origins + t[:, None] * directions - point) @ normal) >= 0
        expected = np.where((disc >= 0) & (t > eps) & inside, t, expected)
    np.testing.assert_array_equal(hits == 0, np.isfinite(expected))
    np.testing.assert_allclose(ts[hits == 0], expected[hits == 0], rtol=1e-12)
    assert 0.1 < np.mean(hits == 0) < 0.9  # both outcomes occur often


# --- closed-form direct lighting: NEE with MIS ----------------------------------------------

_RHO, _LE = 0.5, 3.0
_GL = np.polynomial.legendre.leggauss(4)


def _direct_scene(light):
    materials = {"ground": diffuse(_RHO), "lamp": diffuse(0.0, emission=_LE)}
    ground = Quad((-30, -30, 0), (60, 0, 0), (0, 60, 0), "ground")
    camera = Camera((0, -4, 1.2), (0, 4.5, -1.2), 20, up=(0, 0, 1))
    if light == "sphere":
        return Scene("sphere light", camera, materials, (Sphere((0, 0, 2), 0.5, "lamp"),), (ground,))
    return Scene("quad light", camera, materials, (), (ground, Quad((-0.5, -0.5, 2), (1, 0, 0), (0, 1, 0), "lamp")))


def _direct_reference(light, width, height):
    """Pixel means of (rho / pi) E(x) over the box filter, by 4 x 4 Gauss-Legendre quadrature."""
    cam = _direct_scene(light).camera_array(width, height)
    nodes, weights = (_GL[0] + 1) / 2, _GL[1] / 2
    fx, fy = np.meshgrid(nodes, nodes, indexing="ij")
    w = np.outer(weights, weights).ravel()
    image = np.zeros((height, width))
    for row in range(height):
        for col in range(width):
            sx = (col + fx.ravel()) / width - 0.5
            sy = (height - 1 - row + fy.ravel()) / height - 0.5
            d = cam[3:6] + sx[:, None] * cam[6:9] + sy[:, None] * cam[9:12]
            x = cam[:3] - (cam[2] / d[:, 2])[:, None] * d  # the ground z = 0 (near = 0)
            e = np.empty(len(x))
            for k, point in enumerate(x):
                if light == "sphere":
                    to_center = np.array([0, 0, 2.0]) - point
                    distance = np.linalg.norm(to_center)
                    e[k] = sphere_light_irradiance(to_center / distance, distance, 0.5, _LE)
                else:
                    corners = np.array([[-0.5, -0.5, 2], [0.5, -0.5, 2], [0.5, 0.5, 2], [-0.5, 0.5, 2]]) - point
                    e[k] = lambert_irradiance(corners, (0, 0, 1), _LE)
            image[row, col] = np.sum(w * _RHO / np.pi * e)
    return image


_DIRECT_SAMPLERS = (
    "cosine", "uniform", "symmetric_sobol", "symmetric_cosine_sobol", "symmetric_sobol_interlaced2",
    "symmetric_cosine_sobol_interlaced3",
)  # fmt: skip


@functools.cache
def _direct_reference_24x16(light):
    """The reference image of a light, once per process: not a module-scoped fixture, which pytest tears down
    whenever xdist runs another module's tests in between."""
    return _direct_reference(light, 24, 16)


# One xdist worker runs the cases (Makefile: --dist loadgroup): the renderer's kernel for these scenes (a
# specialisation no other test uses, ~4 CPU-s for each light) is compiled once, not by both workers at once.
@pytest.mark.xdist_group("direct_lighting")
@pytest.mark.parametrize("sampler", _DIRECT_SAMPLERS)
@pytest.mark.parametrize("light", ["sphere", "quad"])
def test_direct_lighting_matches_the_closed_form(light, sampler):
    """NEE + MIS on a diffuse plane under a sphere or a square light equals (rho / pi) E per pixel (t-test per block)."""
    reference = _direct_reference_24x16(light)
    seed = 100 * _DIRECT_SAMPLERS.index(sampler) + (light == "quad")
    image = render(_direct_scene(light), width=24, height=16, spp=64, **_words(sampler), seed=seed).image
    np.testing.assert_array_equal(image[..., 0], image[..., 2])  # grey
    residual = (image[..., 0] - reference).reshape(2, 8, 3, 8).transpose(0, 2, 1, 3).reshape(6, 64)
    t = residual.mean(axis=1) / (residual.std(axis=1, ddof=1) / 8)
    critical = stats.t.isf(_sidak(2 * len(_DIRECT_SAMPLERS) * 6) / 2, df=63)
    assert np.all(np.abs(t) < critical), (t, critical)
    blocks = reference.reshape(2, 8, 3, 8).mean(axis=(1, 3)).ravel()
    assert np.all(residual.std(axis=1, ddof=1) / 8 < 0.03 * blocks)  # the test has teeth: 3 % per block
    assert reference.min() > 1e-4 and reference.max() < 0.5  # lit everywhere


def test_nee_beats_bsdf_sampling_on_the_small_light():
    """Same spp: the path integrator's error on the sphere-light plane is far below the BSDF integrator's."""
    reference = _direct_reference("sphere", 12, 8)
    errors = {}
    for integrator in INTEGRATORS:
        image = render(
            _direct_scene("sphere"), width=12, height=8, spp=32, strategy="cosine", seed=5, integrator=integrator
        )
        errors[integrator] = np.sqrt(np.mean((image.image[..., 0] - reference) ** 2))
    assert errors["path"] < 0.25 * errors["bsdf"], errors


# --- furnace ------------------------------------------------------------------------

_FURNACE_CASES = [
    (integrator, sampler, rho, translucent)
    for integrator, sampler in _PAIRS
    for translucent in (False, True)
    for rho in (0.3, 0.6, (0.9 if translucent or sampler in _COSINE_SAMPLERS else 0.85))
]


@pytest.mark.parametrize("integrator, sampler, rho, translucent", _FURNACE_CASES)
def test_furnace_radiance_is_le_over_one_minus_rho(integrator, sampler, rho, translucent):
    emission = 0.7
    scene = furnace(albedo=rho, emission=emission, translucent=translucent)
    seed = round(1000 * rho) + translucent + 7 * (integrator == "path")
    result = render(scene, width=32, height=32, spp=48, **_words(sampler), seed=seed, integrator=integrator)
    image = result.image
    np.testing.assert_array_equal(image[..., 0], image[..., 1])  # grey scene, same paths for every channel
    pixels = image[..., 0].ravel()
    mean = pixels.mean()
    standard_error = pixels.std(ddof=1) / math.sqrt(pixels.size)
    expected = emission / (1 - rho)
    assert abs(mean - expected) <= 4 * standard_error, (mean, expected, standard_error)
    assert standard_error < 0.05 * expected  # the test has teeth


# --- unbiasedness against the other integrator --------------------------------------

_W, _H, _BLOCK = 32, 24, 8
_REPLICATES = 8


def _replicate_stats(scene, integrator, sampler, spp, seed0):
    images = np.stack(
        [
            render(scene, width=_W, height=_H, spp=spp, **_words(sampler), seed=seed0 + r, integrator=integrator).image
            for r in range(_REPLICATES)
        ]
    )
    mean = images.mean(axis=0)
    variance_of_mean = images.var(axis=0, ddof=1) / _REPLICATES
    blocks = lambda a: a.reshape(_H // _BLOCK, _BLOCK, _W // _BLOCK, _BLOCK, 3)  # noqa: E731
    block_mean = blocks(mean).mean(axis=(1, 3))
    block_variance = blocks(variance_of_mean).sum(axis=(1, 3)) / _BLOCK**4
    return block_mean, block_variance


@pytest.fixture(scope="module")
def references():
    return {
        "path": _replicate_stats("cornell", "bsdf", "cosine", 512, seed0=90_000),  # for the path pairs
        "bsdf": _replicate_stats("cornell", "path", "cosine", 256, seed0=80_000),  # for the bsdf pairs
    }


_TRANSLUCENT_SAMPLERS = ("cosine", "symmetric", "symmetric_cosine_sobol", "symmetric_sobol_interlaced2")
_Z_TESTS = (len(_PAIRS) + len(_TRANSLUCENT_SAMPLERS)) * (_H // _BLOCK) * (_W // _BLOCK) * 3


def _z_check(block_mean, block_variance, ref_mean, ref_variance, teeth=0.15):
    z = (block_mean - ref_mean) / np.sqrt(block_variance + ref_variance)
    critical = stats.norm.isf(_sidak(_Z_TESTS) / 2)  # about 4.3
    assert np.all(np.abs(z) < critical), (np.abs(z).max(), critical, np.unravel_index(np.abs(z).argmax(), z.shape))
    # the test has teeth: the blocks are well estimated where there is light (relative standard error)
    lit = ref_mean > 0.05
    assert np.all(np.sqrt(block_variance[lit]) < teeth * ref_mean[lit]), np.max(
        np.sqrt(block_variance[lit]) / ref_mean[lit]
    )


# The pairs and the translucent scene on one xdist worker (Makefile: --dist loadgroup): their module-scoped
# references (renders of 256-512 spp) are made once, not once per worker.
_REFERENCES = pytest.mark.xdist_group("render_references")


@_REFERENCES
@pytest.mark.slow
@pytest.mark.parametrize("integrator, sampler", _PAIRS)
def test_every_pair_agrees_with_the_other_integrator(integrator, sampler, references):
    seed0 = 1000 * (_PAIRS.index((integrator, sampler)) + 1)
    block_mean, block_variance = _replicate_stats("cornell", integrator, sampler, 48, seed0)
    _z_check(block_mean, block_variance, *references[integrator])


@pytest.fixture(scope="module")
def translucent_reference():
    return _replicate_stats(translucent_scene(), "bsdf", "cosine", 384, seed0=70_000)


@_REFERENCES
@pytest.mark.slow
@pytest.mark.parametrize("sampler", _TRANSLUCENT_SAMPLERS)
def test_translucent_scene_path_agrees_with_bsdf(sampler, translucent_reference):
    """Quad lights (area sampling, selection by power) and NEE through Lambertian transmission."""
    seed0 = 60_000 + 100 * _TRANSLUCENT_SAMPLERS.index(sampler)
    block_mean, block_variance = _replicate_stats(translucent_scene(), "path", sampler, 96, seed0)
    _z_check(block_mean, block_variance, *translucent_reference, teeth=0.2)


def test_the_disk_cache_guard_covers_every_module_the_kernel_inlines():
    # The guard's file list is derived from the kernel module's imports: the emitters, split out of
    # _integrator.py, and the random numbers are in it; the test probes (their own guard) are not.
    from pathlib import Path

    from symsphere._testing import numba_cache

    kernel_dependencies = numba_cache.kernel_dependencies

    paths = kernel_dependencies(K.render_pass)
    names = {Path(p).name for p in paths}
    # the warps' modules whose formulas it inlines: the uniform and cosine maps, the cosine wedge
    assert {"_integrator.py", "_directions.py", "_emitters.py", "_kernels.py", "frames.py"} <= names
    # the random streams it inlines (symsphere._random)
    assert {"hashes.py", "owen_sobol.py", "splitmix.py"} <= {
        Path(p).name for p in paths if Path(p).parent.name == "_random"
    }
    assert {"_uniform.py", "_concentric.py", "_wedge.py", "_triangle.py"} <= names
    assert "_probes.py" not in names
    assert {"_probes.py", "_integrator.py", "_emitters.py"} <= {Path(p).name for p in kernel_dependencies(P.first_hits)}


def test_the_disk_cache_guard_also_covers_the_emitters_cached_functions(tmp_path):
    # The kernel calls cached numba functions of _emitters.py and _directions.py, which LLVM inlines into
    # it: numba keys their cache on their own module alone, so the guard must also drop theirs when _random.py or frames.py
    # change. The guard leaves its digest next to each module's cache entries: in a new process with an
    # empty cache directory, preparing the kernels writes both.
    import os
    import subprocess
    import sys

    code = "from symsphere._testing import render_integrator as K; K.prepare_kernels()"
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    subprocess.run([sys.executable, "-c", code], env=env, check=True, timeout=120)
    stamps = {p.name for p in tmp_path.rglob("*.deps-sha256")}
    assert {"_integrator.deps-sha256", "_directions.deps-sha256", "_emitters.deps-sha256"} <= stamps


COLD_RENDER = """
import json
from numba.core import event
from symsphere.render import cornell, render
from symsphere.render.renderer import compile_in_background
from symsphere._testing import compile_ahead as C, render_emitters as E, render_integrator as K
with compile_in_background() as ready:  # what symsphere demo does on a new install
    cold = not K.kernel_is_cached()
    ready()
with event.install_recorder("numba:compile") as recorder:  # numba's events: what this process compiles
    image = render(cornell(), width=8, height=6, spp=48, seed=5).image
a = cornell().arrays(8, 6)
parts = K.kernel_parts(K.light_kinds(a["spheres"], a["sphere_material"], a["quads"], a["quad_material"], a["materials"]))
print(json.dumps({
    "cold": cold,
    "cached": K.kernel_is_cached(),
    "compiled": sorted({ev.data["dispatcher"].py_func.__name__ for _, ev in recorder.buffer}),
    "image": image.tobytes().hex(),
    "on_disk": {name: C.cached_signatures(d) for name, (d, _) in parts.items()},
    "expected": {name: str(tuple(t)) for name, (_, t) in parts.items()},
    "absent_kinds": {f.__name__: C.cached_signatures(f) for f in (E.spherical_rectangle, E._sphere_cone)},
}))
"""


def test_a_cold_kernel_compiled_in_the_background_is_loaded_for_kernel_parts_types_with_the_warm_image(tmp_path):
    # A new install (an empty cache): renderer.compile_in_background has a second process compile the kernel
    # by a small render (a cold render, which has symsphere._compile_ahead compile kernel_parts() for the
    # types listed there, some in a third process), as symsphere demo does while it samples.  The render
    # here must then compile nothing (it loads the kernel, whose machine code holds its parts), and the
    # cache must hold each part for exactly the types kernel_parts() lists and no others (what the second
    # and third processes compiled: a part compiled for other types shows a second entry).  Its image is
    # the one this process renders from its own (warm) kernels, to the bit.
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    result = subprocess.run([sys.executable, "-c", COLD_RENDER], env=env, capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr
    cold = json.loads(result.stdout.splitlines()[-1])
    assert cold["cold"] and cold["cached"]
    assert cold["on_disk"] == {name: [types] for name, types in cold["expected"].items()}
    # cornell's one light is a clipped sphere: the rectangle's and the full sphere's code was never compiled
    assert cold["absent_kinds"] == {"spherical_rectangle": [], "_sphere_cone": []}
    if len(os.sched_getaffinity(0) if hasattr(os, "sched_getaffinity") else range(os.cpu_count() or 1)) >= 2:
        assert cold["compiled"] == [], cold["compiled"]  # the kernel: loaded, not compiled here
    warm = render(cornell(), width=8, height=6, spp=48, seed=5).image
    assert cold["image"] == warm.tobytes().hex()


def test_light_kinds_are_those_of_the_scene_emitters():
    # True for the cone and the rectangle if the scene has an emitter of that kind, None otherwise (the
    # kernel then does not compile its code); the sphere cap and the parallelogram always True (their code is
    # small, and scenes then share kernels); every kind at once: a scene with a full sphere, a clipped sphere,
    # a rectangle and a parallelogram lit; the expected kinds are read off the scene's description, not the
    # tables.
    def kinds(scene):
        a = scene.arrays(8, 6)
        return K.light_kinds(a["spheres"], a["sphere_material"], a["quads"], a["quad_material"], a["materials"])

    box = cornell()  # a clipped sphere light (smallpt's lamp sunk into the ceiling)
    assert kinds(box) == (True, None, True, None)
    lamp = Material("diffuse", emission=(1.0, 1.0, 1.0))
    materials = {**box.materials, "lamp2": lamp}
    full = dataclasses.replace(
        box, materials=materials, spheres=(*box.spheres, Sphere((30.0, 40.0, 60.0), 6.0, "lamp2"))
    )
    assert kinds(full) == (True, True, True, None)
    dark = tuple(s for s in box.spheres if box.materials[s.material].emission == (0.0, 0.0, 0.0))
    square = Quad((20.0, 70.0, 50.0), (10.0, 0.0, 0.0), (0.0, 0.0, 10.0), "lamp2")
    slanted = Quad((60.0, 70.0, 40.0), (10.0, 0.0, 0.0), (5.0, 0.0, 10.0), "lamp2")
    assert kinds(dataclasses.replace(box, materials=materials, spheres=dark, quads=(slanted,))) == (
        True,
        None,
        True,
        None,
    )
    assert kinds(dataclasses.replace(box, materials=materials, quads=(square,))) == (True, None, True, True)
    assert kinds(dataclasses.replace(box, spheres=dark)) == (True, None, True, None)  # no light at all


def test_the_two_groups_of_parts_are_kernel_parts():
    # compile_ahead's split (compiled here / in the second process; measured cold by docs/results/cold-start.md):
    # every part in exactly one group, no unknown name (the second process would fail on it, and this one
    # would then compile the part itself: slower, not wrong, so no image shows it).
    here, there = set(K.COMPILE_HERE), set(K.COMPILE_THERE)
    assert not here & there and here | there == set(K.kernel_parts())


def test_compile_in_background_starts_nothing_for_a_cached_kernel(monkeypatch):
    from symsphere._testing import compile_ahead
    from symsphere.render.renderer import compile_in_background

    render(cornell(), width=4, height=4, spp=24, seed=0)  # the kernel is in the cache now
    monkeypatch.setattr(compile_ahead, "_cpus", lambda: 2)  # two CPUs: only the cache decides
    calls = []
    monkeypatch.setattr(subprocess, "Popen", lambda *a, **k: calls.append(a))
    with compile_in_background() as ready:
        ready()
    assert calls == []
