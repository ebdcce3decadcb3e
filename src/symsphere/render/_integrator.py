"""The path-tracing kernels: BSDF-sampling-only Monte Carlo solution of the rendering equation.

All numba code of the renderer that is not random-number plumbing
(:mod:`symsphere.render._random`) is here.  Direction sampling at diffuse
vertices goes through the scalar functions of :mod:`symsphere._kernels`
(``triangle_point``, ``triangle_density``, ``orbit_member``), so no map or
orbit formula is restated.

Estimator
---------
A camera path is traced until it escapes, is absorbed (zero throughput) or
is stopped by Russian roulette.  At every vertex the emitted radiance times
the throughput is added (emission is two-sided).  Diffuse vertices sample a
direction with pdf p and multiply the throughput by ``f cos / p``:

- Lambertian reflection: ``f = albedo / pi`` on the side of the incoming ray,
  directions on the hemisphere about the facing normal;
- Lambertian transmission (``translucent``): ``f = reflectance / pi`` on the
  incoming side and ``transmittance / pi`` on the other, directions on the
  whole sphere (the paper's transparent-object case);
- mirror: the reflected direction, times the reflectance;
- smooth dielectric: reflection with probability F (exact unpolarised
  Fresnel), refraction otherwise, times the tint either way.

Russian roulette (as Mitsuba 3's ``path`` integrator): after the throughput
update at vertex v (0-based), if ``v + 1 >= rr_depth`` the path survives with
probability ``q = min(max(throughput), 0.95)`` and is divided by q.
``max_depth`` (default 1024) is a safety net far beyond where roulette has
ended every path (survival after depth 1024 is below 0.95**1019 ~ 1e-23).

Samplers (codes)
----------------
``UNIFORM`` classic uniform directions (z = u or 1 - 2u, phi = 2 pi v);
``COSINE`` Shirley–Chiu concentric disk + Malley (the full sphere: a side
with probability 1/2); ``ORBIT`` a random base point mapped onto T0 and a
uniformly random orbit member, i.i.d.; ``SYMMETRIC`` the paper's pattern
inside a pixel with random base points; ``SYMMETRIC_SOBOL`` the same with
Owen-scrambled Sobol' base points.  See :func:`sample_local` for the exact
mapping of (sample, vertex) to (group, member, base point).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange
from numba.extending import register_jitable

from .. import _kernels, _orbit_stores, maps, symmetry
from .._kernels import orbit_member, triangle_density, triangle_point
from .._numba_cache import invalidate_if_changed
from . import _random
from ._random import below, mix64, next_u64, owen_sobol2, path_state, pixel_key, u01

UNIFORM, COSINE, ORBIT, SYMMETRIC, SYMMETRIC_SOBOL = 0, 1, 2, 3, 4
DIFFUSE, TRANSLUCENT, MIRROR, DIELECTRIC = 0, 1, 2, 3
BOX, TENT = 0, 1

SPHERE_COLUMNS = 5  # rows of the (5, n) sphere table: cx, cy, cz, r, r^2
QUAD_COLUMNS = 16  # rows of the (16, m) quad table: corner, edge1, edge2, unit normal, N / |N|^2 (3 each), n . corner
MATERIAL_COLUMNS = 11  # kind, colour (3), transmittance (3), ior, emission (3)
CAMERA_COLUMNS = 13  # position, unit forward, right and up spanning the image plane at distance 1 (3 each), near

_OPTIONS = dict(cache=True, error_model="numpy", nogil=True, fastmath=False)
_PI = math.pi
_INV_PI = 1.0 / math.pi
_RR_CAP = 0.95
_BASE_U = np.uint64(0x2545F4914F6CDD1D)  # distinct tags that split a group key into u and v
_BASE_V = np.uint64(0x5851F42D4C957F2D)
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_ODD = np.uint64(0xD6E8FEB86659FD93)
_ONE = np.uint64(1)


@register_jitable
def frame_rows(nx, ny, nz):
    """Duff et al. (2017) frame about the unit normal n: rows t, b (n is the third row).

    The scalar twin of :func:`symsphere.frames.frame` (which numba cannot
    compile: it unpacks a generator); a test pins them equal.
    """
    sign = math.copysign(1.0, nz)
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    return (1.0 + sign * nx * nx * a, sign * b, -sign * nx), (b, sign + ny * ny * a, -ny)


@register_jitable
def to_world(lx, ly, lz, nx, ny, nz):
    """Local (x, y, z) about the unit normal n (z along n) to world coordinates."""
    t, b = frame_rows(nx, ny, nz)
    return (
        lx * t[0] + ly * b[0] + lz * nx,
        lx * t[1] + ly * b[1] + lz * ny,
        lx * t[2] + ly * b[2] + lz * nz,
    )


@register_jitable
def sample_local(sampler, code, full, key, s, depth, state):
    """A direction about the local pole (0, 0, 1) and its weight ``|cos| / (pi pdf)``.

    Parameters
    ----------
    sampler, code : int
        Sampler code and map code (``METHOD_CODES``; used by the orbit samplers).
    full : bool
        Sample the whole sphere (Lambertian transmission) rather than the
        upper hemisphere.
    key : uint64
        The pixel's key (:func:`~symsphere.render._random.pixel_key`).
    s, depth : int
        Sample index within the pixel, vertex index along the path (0 = first hit).
    state : uint64
        The path's random stream.

    Returns
    -------
    (x, y, z, weight, state)
        For a BSDF ``f = c / pi`` the throughput factor is ``c * weight``.

    Notes
    -----
    With n = 24 (hemisphere) or 48 (sphere), the symmetric samplers put
    sample s in group ``g = s // n``.  At vertex *depth* the group shares one
    base point B(g, depth) (``SYMMETRIC``: two hashes of (pixel, depth, n,
    g); ``SYMMETRIC_SOBOL``: point g of the Owen-scrambled, index-shuffled
    Sobol' sequence seeded by (pixel, depth, n)) and one offset o(g, depth)
    uniform in 0..n-1 (a third hash), and sample s takes orbit member
    ``(s mod n + o) mod n``.  The n
    samples of a complete group take all n members of B in turn; each sample
    on its own gets a uniform member of a fresh, independent base point at
    every vertex, so each path has exactly the distribution of the i.i.d.
    ``ORBIT`` sampler (unbiased sample by sample, for any spp).  Without the
    offset a sample would keep member s mod n at every vertex, confined to
    one triangle of every local frame: biased.
    """
    if sampler == UNIFORM:
        state, b1 = next_u64(state)
        state, b2 = next_u64(state)
        u = u01(b1)
        phi = 2.0 * _PI * u01(b2)
        if full:
            z = 1.0 - 2.0 * u
            weight = 4.0 * abs(z)
        else:
            z = u
            weight = 2.0 * z
        r = math.sqrt(max(0.0, 1.0 - z * z))
        return r * math.cos(phi), r * math.sin(phi), z, weight, state
    if sampler == COSINE:
        state, b1 = next_u64(state)
        state, b2 = next_u64(state)
        x, y = _concentric_disk(2.0 * u01(b1) - 1.0, 2.0 * u01(b2) - 1.0)
        z = math.sqrt(max(0.0, 1.0 - x * x - y * y))
        if full:
            state, b3 = next_u64(state)
            if b3 >> np.uint64(63):
                z = -z
            return x, y, z, 2.0, state
        return x, y, z, 1.0, state
    n = 48 if full else 24
    if sampler == ORBIT:
        state, b1 = next_u64(state)
        state, b2 = next_u64(state)
        state, b3 = next_u64(state)
        u = u01(b1)
        v = u01(b2)
        member = below(b3, n)
    else:
        if full:  # literal divisors: no integer division instruction
            group = s // 48
        else:
            group = s // 24
        vertex_key = mix64(key ^ (np.uint64(depth) * _GOLDEN + np.uint64(n)))  # (pixel, vertex, orbit size)
        h = mix64(vertex_key ^ ((np.uint64(group) + _ONE) * _ODD))  # ... and group
        member = s - n * group + below(h, n)  # (s mod n + offset) mod n, both terms < n
        if member >= n:
            member -= n
        if sampler == SYMMETRIC:
            u = u01(mix64(h ^ _BASE_U))
            v = u01(mix64(h ^ _BASE_V))
        else:  # point `group` of the sequence scrambled for this (pixel, vertex, orbit size)
            u, v = owen_sobol2(group, vertex_key)
    bx, by, bz = triangle_point(u, v, code)
    density = triangle_density(bx, by, bz, code)
    x, y, z = orbit_member(bx, by, bz, member)
    if density > 0.0:
        weight = abs(z) * n * _INV_PI / density  # density = +inf at the paper maps' vertex: weight 0
    else:
        weight = 0.0  # unreachable: triangle_point clamps into T0, where the density is positive
    return x, y, z, weight, state


@register_jitable
def _concentric_disk(a, b):
    """Shirley & Chiu (1997) concentric map of [-1, 1]^2 onto the unit disk."""
    if a == 0.0 and b == 0.0:
        return 0.0, 0.0
    if abs(a) > abs(b):
        r = a
        phi = (_PI / 4.0) * (b / a)
    else:
        r = b
        phi = (_PI / 2.0) - (_PI / 4.0) * (a / b)
    return r * math.cos(phi), r * math.sin(phi)


@register_jitable
def _tent(bits):
    # smallpt's tent filter on [-1, 1]: r = 2u, r < 1 ? sqrt(r) - 1 : 1 - sqrt(2 - r)
    r = 2.0 * u01(bits)
    if r < 1.0:
        return math.sqrt(r) - 1.0
    return 1.0 - math.sqrt(2.0 - r)


@register_jitable
def _film_offset(pixel_filter, state):
    """Position of a sample inside its pixel: box: uniform in [0, 1); tent: smallpt's, in [-0.25, 1.25]."""
    state, b1 = next_u64(state)
    if pixel_filter == BOX:
        return u01(b1), state
    state, b2 = next_u64(state)
    sub = np.float64(b2 >> np.uint64(63))  # smallpt's 2 x 2 subpixels, one chosen at random
    return (sub + 0.5 + _tent(b1)) * 0.5, state


@register_jitable(inline="always")
def intersect(ox, oy, oz, dx, dy, dz, spheres, quads, eps, scratch):
    """Nearest hit with t > eps: (t, index); index < #spheres a sphere, else #spheres + quad index; -1 none.

    *spheres* (SPHERE_COLUMNS, n) and *quads* (QUAD_COLUMNS, m) are stored
    column-wise (structure of arrays) and every candidate is tested without
    branches, so that LLVM vectorises the loops (AVX-512 on the benchmark
    machine); *scratch* holds at least max(n, m) distances.  The nearest hit
    is then the first smallest distance, spheres before quads: exactly what a
    branchy loop with ``t < t_best`` returns.  Sphere test as smallpt's:
    b = (c - o) . d, det = b^2 - |c - o|^2 + r^2, t = b -+ sqrt(det), in float64
    (the 1e5-radius walls need it).
    """
    t_best = np.inf
    hit = -1
    n = spheres.shape[1]
    if n > 0:
        for i in range(n):  # (2D indexing, no row views: views would cost reference counting)
            px = spheres[0, i] - ox
            py = spheres[1, i] - oy
            pz = spheres[2, i] - oz
            b = px * dx + py * dy + pz * dz
            det = b * b - (px * px + py * py + pz * pz) + spheres[4, i]
            root = math.sqrt(max(det, 0.0))
            near = b - root
            t = near if near > eps else b + root
            scratch[i] = t if (det >= 0.0 and t > eps) else np.inf
        for i in range(n):
            if scratch[i] < t_best:
                t_best = scratch[i]
                hit = i
    m = quads.shape[1]
    if m > 0:
        for j in range(m):
            nx, ny, nz = quads[9, j], quads[10, j], quads[11, j]
            denom = dx * nx + dy * ny + dz * nz
            safe = denom if denom != 0.0 else 1.0
            t = (quads[15, j] - (ox * nx + oy * ny + oz * nz)) / safe
            qx = ox + t * dx - quads[0, j]
            qy = oy + t * dy - quads[1, j]
            qz = oz + t * dz - quads[2, j]
            # alpha = (q x e2) . w, beta = (e1 x q) . w with w = N / |N|^2, N = e1 x e2
            e1x, e1y, e1z = quads[3, j], quads[4, j], quads[5, j]
            e2x, e2y, e2z = quads[6, j], quads[7, j], quads[8, j]
            wx, wy, wz = quads[12, j], quads[13, j], quads[14, j]
            alpha = (qy * e2z - qz * e2y) * wx + (qz * e2x - qx * e2z) * wy + (qx * e2y - qy * e2x) * wz
            beta = (e1y * qz - e1z * qy) * wx + (e1z * qx - e1x * qz) * wy + (e1x * qy - e1y * qx) * wz
            inside = denom != 0.0 and t > eps and alpha >= 0.0 and alpha <= 1.0 and beta >= 0.0 and beta <= 1.0
            scratch[j] = t if inside else np.inf
        for j in range(m):
            if scratch[j] < t_best:
                t_best = scratch[j]
                hit = n + j
    return t_best, hit


@register_jitable(inline="always")  # numba-IR inlining: no call, no reference counting of the arrays
def radiance(
    spheres, sphere_material, quads, quad_material, materials, camera, background, eps, rr_depth, max_depth,
    sampler, code, pixel_filter, key, s, row, col, width, height, scratch,
):  # fmt: skip
    """The radiance estimate of one camera path: sample *s* of pixel (row, col); row 0 is the top."""
    state = path_state(key, s)
    fx, state = _film_offset(pixel_filter, state)
    fy, state = _film_offset(pixel_filter, state)
    sx = (col + fx) / width - 0.5
    sy = ((height - 1 - row) + fy) / height - 0.5
    dx = camera[3] + sx * camera[6] + sy * camera[9]
    dy = camera[4] + sx * camera[7] + sy * camera[10]
    dz = camera[5] + sx * camera[8] + sy * camera[11]
    near = camera[12]
    ox = camera[0] + near * dx  # smallpt: rays start on the plane at distance `near` along forward
    oy = camera[1] + near * dy
    oz = camera[2] + near * dz
    inv = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
    dx *= inv
    dy *= inv
    dz *= inv

    br, bg, bb = 1.0, 1.0, 1.0
    lr, lg, lb = 0.0, 0.0, 0.0
    n_spheres = spheres.shape[1]
    for depth in range(max_depth):
        t, hit = intersect(ox, oy, oz, dx, dy, dz, spheres, quads, eps, scratch)
        if hit < 0:
            lr += br * background[0]
            lg += bg * background[1]
            lb += bb * background[2]
            break
        px = ox + t * dx
        py = oy + t * dy
        pz = oz + t * dz
        if hit < n_spheres:
            inv_r = 1.0 / spheres[3, hit]
            nx = (px - spheres[0, hit]) * inv_r
            ny = (py - spheres[1, hit]) * inv_r
            nz = (pz - spheres[2, hit]) * inv_r
            m = sphere_material[hit]
        else:
            q = hit - n_spheres
            nx, ny, nz = quads[9, q], quads[10, q], quads[11, q]
            m = quad_material[q]
        lr += br * materials[m, 8]
        lg += bg * materials[m, 9]
        lb += bb * materials[m, 10]

        cos_in = dx * nx + dy * ny + dz * nz
        entering = cos_in < 0.0
        if not entering:  # face the normal towards the incoming ray
            nx, ny, nz, cos_in = -nx, -ny, -nz, -cos_in
        kind = np.int64(materials[m, 0])
        if kind == DIFFUSE or kind == TRANSLUCENT:
            full = kind == TRANSLUCENT
            if materials[m, 1] == 0.0 and materials[m, 2] == 0.0 and materials[m, 3] == 0.0:
                if not full or (materials[m, 4] == 0.0 and materials[m, 5] == 0.0 and materials[m, 6] == 0.0):
                    break  # black: absorbed, whatever the direction
            x, y, z, weight, state = sample_local(sampler, code, full, key, s, depth, state)
            if z >= 0.0:
                br *= materials[m, 1] * weight
                bg *= materials[m, 2] * weight
                bb *= materials[m, 3] * weight
            else:
                br *= materials[m, 4] * weight
                bg *= materials[m, 5] * weight
                bb *= materials[m, 6] * weight
            dx, dy, dz = to_world(x, y, z, nx, ny, nz)
        elif kind == MIRROR:
            c2 = 2.0 * cos_in  # cos_in = d . n_facing <= 0
            dx -= c2 * nx
            dy -= c2 * ny
            dz -= c2 * nz
            br *= materials[m, 1]
            bg *= materials[m, 2]
            bb *= materials[m, 3]
        else:  # DIELECTRIC
            ior = materials[m, 7]
            eta = 1.0 / ior if entering else ior  # n_incident / n_transmitted
            cos_i = -cos_in
            sin2_t = eta * eta * (1.0 - cos_i * cos_i)
            state, bits = next_u64(state)
            reflect = True
            cos_t = 0.0
            if sin2_t < 1.0:
                cos_t = math.sqrt(1.0 - sin2_t)
                rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
                rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
                fresnel = 0.5 * (rs * rs + rp * rp)
                reflect = u01(bits) < fresnel
            if reflect:
                c2 = 2.0 * cos_in
                dx -= c2 * nx
                dy -= c2 * ny
                dz -= c2 * nz
            else:
                k = eta * cos_i - cos_t
                dx = eta * dx + k * nx
                dy = eta * dy + k * ny
                dz = eta * dz + k * nz
            br *= materials[m, 1]
            bg *= materials[m, 2]
            bb *= materials[m, 3]

        if depth + 1 >= rr_depth:
            survive = min(max(br, bg, bb), _RR_CAP)
            state, bits = next_u64(state)
            if u01(bits) >= survive:
                break
            inv_q = 1.0 / survive
            br *= inv_q
            bg *= inv_q
            bb *= inv_q
        elif br == 0.0 and bg == 0.0 and bb == 0.0:
            break
        ox, oy, oz = px, py, pz
    return lr, lg, lb


@njit(parallel=True, **_OPTIONS)
def render_pass(
    spheres, sphere_material, quads, quad_material, materials, camera, background, eps, rr_depth, max_depth,
    sampler, code, pixel_filter, seed, sample_start, sample_count, rows, accum,
):  # fmt: skip
    """Add samples sample_start .. sample_start + sample_count - 1 of every pixel into *accum* (H, W, 3).

    Rows are distributed over the threads in the order *rows*; every pixel is
    done by one thread and its random numbers depend only on (seed, pixel,
    sample), so the sum does not depend on the number of threads or passes.
    """
    height = accum.shape[0]
    width = accum.shape[1]
    scratch_size = max(spheres.shape[1], quads.shape[1], 1)
    for i in prange(rows.shape[0]):
        row = rows[i]
        scratch = np.empty(scratch_size)
        for col in range(width):
            key = pixel_key(seed, row * width + col)
            sr, sg, sb = 0.0, 0.0, 0.0
            for s in range(sample_start, sample_start + sample_count):
                lr, lg, lb = radiance(
                    spheres, sphere_material, quads, quad_material, materials, camera, background, eps,
                    rr_depth, max_depth, sampler, code, pixel_filter, key, s, row, col, width, height, scratch,
                )  # fmt: skip
                sr += lr
                sg += lg
                sb += lb
            accum[row, col, 0] += sr
            accum[row, col, 1] += sg
            accum[row, col, 2] += sb


@njit(**_OPTIONS)
def pattern_directions(sampler, code, full, seed, pixel, depth, samples):
    """Local directions and weights that samples 0..samples-1 of *pixel* draw at vertex *depth*.

    The same :func:`sample_local` the integrator calls, with each sample's
    own stream advanced as if its path had reached *depth* with no other
    random draws; for the symmetric samplers the stream is not used.  For
    tests and documentation.
    """
    out = np.empty((samples, 4))
    key = pixel_key(seed, pixel)
    for s in range(samples):
        state = path_state(key, s)
        x, y, z, weight, state = sample_local(sampler, code, full, key, s, depth, state)
        out[s, 0] = x
        out[s, 1] = y
        out[s, 2] = z
        out[s, 3] = weight
    return out


@njit(**_OPTIONS)
def sobol_points(count, key):
    """The first *count* points of the Owen-scrambled 2D Sobol' sequence with 64-bit *key*."""
    out = np.empty((count, 2))
    for i in range(count):
        out[i, 0], out[i, 1] = owen_sobol2(i, key)
    return out


@njit(**_OPTIONS)
def frame_matrix(nx, ny, nz):
    """The frame of :func:`frame_rows` as a (3, 3) array of rows t, b, n (for tests)."""
    t, b = frame_rows(nx, ny, nz)
    out = np.empty((3, 3))
    for j in range(3):
        out[0, j] = t[j]
        out[1, j] = b[j]
    out[2, 0], out[2, 1], out[2, 2] = nx, ny, nz
    return out


invalidate_if_changed(
    render_pass, [_random.__file__, _kernels.__file__, maps.__file__, _orbit_stores.__file__, symmetry.__file__]
)
