"""The path-tracing kernels: two estimators of the rendering equation, one numba kernel.

The renderer's numba code is here, except the direction sampling at diffuse vertices
(:mod:`symsphere.render._directions`: the strategies and their densities), the emitters
(:mod:`symsphere.render._emitters`: sampling, densities, selection, the power
heuristic), the random-number plumbing (:mod:`symsphere._random`) and
the small kernels for the tests (:mod:`symsphere.render._probes`).  The
functions of the hot path are numba functions of their own (``INLINED``: typed and compiled
once each, cached), which LLVM inlines into the one kernel that :func:`render_pass` runs.  The
frame at a vertex is :func:`symsphere.frames.frame_rows`, so no formula is restated.

Estimators (``integrator``)
---------------------------
``BSDF`` (smallpt's): a camera path is traced until it escapes, is absorbed
(zero throughput) or is stopped by Russian roulette.  At every vertex the
emitted radiance times the throughput is added (emission is two-sided).
Diffuse vertices sample a direction with pdf p and multiply the throughput by
``f cos / p``:

- Lambertian reflection: ``f = albedo / pi`` on the side of the incoming ray,
  directions on the hemisphere about the facing normal;
- Lambertian transmission (``translucent``): ``f = reflectance / pi`` on the
  incoming side and ``transmittance / pi`` on the other, directions on the
  whole sphere (the paper's transparent-object case);
- mirror: the reflected direction, times the reflectance;
- smooth dielectric: reflection with probability F (exact unpolarised
  Fresnel), refraction otherwise, times the tint either way.

``PATH`` (the default): the same paths, plus next-event estimation (NEE) at
every diffuse and translucent vertex, combined with the BSDF-sampled hits by
multiple importance sampling (Veach 1997, power heuristic beta = 2; pbrt-v4
``PathIntegrator``, Mitsuba 3 ``path``).  At such a vertex x one emitter is
chosen with probability proportional to its power (mean emitted radiance x
area; ``lights`` of :meth:`symsphere.render.Scene.arrays`), a point or direction on it
is sampled (:func:`~symsphere.render._emitters.sample_emitter`) with solid-angle pdf p_l (times the
selection probability), one shadow ray decides visibility, and
``f |cos| Le w_l / p_l`` is added with ``w_l = p_l^2 / (p_l^2 + p_b^2)``, p_b
the density with which the vertex's direction sampler draws that direction
(:func:`bsdf_pdf`).  When the BSDF-sampled ray from x hits an emitter, its
emission is weighted by ``w_b = p_b^2 / (p_b^2 + p_l^2)`` with p_l from
:func:`~symsphere.render._emitters.emitter_pdf`.  Emission seen by the camera or after a mirror or
dielectric (specular) bounce is counted by BSDF sampling alone (weight 1),
as is the background.  NEE is skipped at the last vertex allowed by
``max_depth``, so that both estimators estimate the same truncated sum.

Emitters are sampled as pbrt-v4 and Mitsuba 3 do (:mod:`symsphere.render._emitters`):
a full sphere seen from outside uniformly in the cone it subtends, from
inside (or on it) by area; a clipped sphere (a spherical cap) by area on the
cap; a rectangle uniformly in solid angle, any other parallelogram by area.

Russian roulette (as Mitsuba 3's ``path`` integrator): after the throughput
update at vertex v (0-based), if ``v + 1 >= rr_depth`` the path survives with
probability ``q = min(max(throughput), 0.95)`` and is divided by q.
``max_depth`` (default 1024) is a safety net far beyond where roulette has
ended every path (survival after depth 1024 is below 0.95**1019 ~ 1e-23).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import get_num_threads, njit, types
from numba.extending import register_jitable

from .._compile_ahead import compile_ahead, is_cached
from .._constants import INV_PI
from .._numba_cache import invalidate_if_changed
from .._random.hashes import next_u64, path_state, pixel_key, u01
from .._threads import route_compiles, run_kernel, start_threads
from ..frames import frame_rows
from ._directions import bsdf_pdf, fixed_sampler, is_cosine, sample_local
from ._emitters import (
    INLINED,
    choose_light,
    emitter_pdf,
    light_kinds,
    power_heuristic,
    rows_to_world,
    sample_emitter,
)

PATH, BSDF = 0, 1
DIFFUSE, TRANSLUCENT, MIRROR, DIELECTRIC = 0, 1, 2, 3
BOX, TENT = 0, 1

# rows of the (17, n) sphere table: centre (3), r, r^2, clip axis a (3, unit, into the kept side; +z if
# unclipped), clip offset d (keep a . p >= d; -inf if unclipped), cap height h (2 r if unclipped), 1 / r,
# t and b (3 each): with a, the frame in which a cap is sampled (frames.frame_rows(a))
SPHERE_COLUMNS = 17
# rows of the (26, m) quad table: corner, edge1, edge2, unit normal, N / |N|^2 (3 each), n . corner, area,
# edge1 / |edge1|, edge2 / |edge2| (3 each), |edge1|, |edge2|, 1 if a rectangle (edges orthogonal) else 0
QUAD_COLUMNS = 26
MATERIAL_COLUMNS = 11  # kind, colour (3), transmittance (3), ior, emission (3)
CAMERA_COLUMNS = 13  # position, unit forward, right and up spanning the image plane at distance 1 (3 each), near
# lights: a (2, L) table, rows object index (spheres first, then quads) and cumulative selection probability;
# light_pmf: the selection probability of every object (0 for non-emitters)

KERNEL_OPTIONS: dict[str, Any] = dict(cache=True, error_model="numpy", nogil=True, fastmath=False)
# The pass kernel: no reference counting (it allocates nothing; see render/_emitters.py)
_PASS_KERNEL_OPTIONS: dict[str, Any] = dict(KERNEL_OPTIONS, _nrt=False)
_INV_PI = INV_PI  # the kernels' spelling
_RR_CAP = 0.95
_SHADOW_TOLERANCE = 1e-6  # relative: a shadow ray reaches the sampled point if nothing is hit this much before it


@register_jitable
def _tent(bits):
    # smallpt's tent filter on [-1, 1]: r = 2u, r < 1 ? sqrt(r) - 1 : 1 - sqrt(2 - r)
    r = 2.0 * u01(bits)
    if r < 1.0:
        return math.sqrt(r) - 1.0
    return 1.0 - math.sqrt(2.0 - r)


@njit(**INLINED)
def _film_offset(pixel_filter, state):
    """Position of a sample inside its pixel: box: uniform in [0, 1); tent: smallpt's, in [-0.25, 1.25]."""
    state, b1 = next_u64(state)
    if pixel_filter == BOX:
        return u01(b1), state
    state, b2 = next_u64(state)
    sub = np.float64(b2 >> np.uint64(63))  # smallpt's 2 x 2 subpixels, one chosen at random
    return (sub + 0.5 + _tent(b1)) * 0.5, state


@register_jitable
def _sphere_roots(cx, cy, cz, r2, ox, oy, oz, dx, dy, dz):
    """smallpt's quadratic for the ray o + t d and the sphere (centre c, radius^2 r2): (det, near, far).

    b = (c - o) . d, det = b^2 - |c - o|^2 + r^2, roots b -+ sqrt(max(det, 0)) (valid if det >= 0).
    Scalar, inlined into both sphere loops of :func:`intersect` (by LLVM): no call, the loops still vectorise.
    """
    px = cx - ox
    py = cy - oy
    pz = cz - oz
    b = px * dx + py * dy + pz * dz
    det = b * b - (px * px + py * py + pz * pz) + r2
    root = math.sqrt(max(det, 0.0))
    return det, b - root, b + root


@njit(**INLINED)  # speed vs compile time: see render/_emitters.py
def intersect(ox, oy, oz, dx, dy, dz, spheres, plain, quads, eps, scratch, t_max):
    """Nearest hit with eps < t < t_max: (t, index); index < #spheres a sphere, else #spheres + quad index; -1 none.

    The first *plain* spheres are unclipped (:func:`plain_spheres`), the others clipped.

    *spheres* (SPHERE_COLUMNS, n) and *quads* (QUAD_COLUMNS, m) are stored
    column-wise (structure of arrays) and every candidate is tested without
    branches, so that LLVM vectorises the loops (AVX-512 on the benchmark
    machine); *scratch* holds at least max(n, m) distances.  The nearest hit
    is then the first smallest distance, spheres before quads: exactly what a
    branchy loop with ``t < t_best`` returns.  Sphere test as smallpt's:
    b = (c - o) . d, det = b^2 - |c - o|^2 + r^2, t = b -+ sqrt(det), in float64
    (the 1e5-radius walls need it).  A clipped sphere keeps a root only if
    its point is in the half-space a . p >= d, i.e. ``(a . o - d) + t (a . d) >= 0``;
    the nearer kept root wins.  Clipped spheres have their own loop, so that
    the common unclipped ones cost what they did before clipping existed
    (smallpt's 8 unclipped spheres fill one AVX-512 vector).
    """
    t_best = t_max  # (a shadow ray: only what lies before the sampled point counts)
    hit = -1
    n = spheres.shape[1]
    if n > 0:
        for i in range(plain):  # (2D indexing, no row views: views would cost reference counting)
            det, near, far = _sphere_roots(
                spheres[0, i], spheres[1, i], spheres[2, i], spheres[4, i], ox, oy, oz, dx, dy, dz
            )
            t = near if near > eps else far
            scratch[i] = t if (det >= 0.0 and t > eps) else np.inf
        for i in range(plain, n):  # clipped spheres: keep a root only if its point is in the half-space
            det, near, far = _sphere_roots(
                spheres[0, i], spheres[1, i], spheres[2, i], spheres[4, i], ox, oy, oz, dx, dy, dz
            )
            ax, ay, az = spheres[5, i], spheres[6, i], spheres[7, i]
            side = (ax * ox + ay * oy + az * oz) - spheres[8, i]
            slope = ax * dx + ay * dy + az * dz
            near_ok = near > eps and side + near * slope >= 0.0
            far_ok = far > eps and side + far * slope >= 0.0
            t = near if near_ok else (far if far_ok else np.inf)
            scratch[i] = t if det >= 0.0 else np.inf
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


@register_jitable
def plain_spheres(spheres):
    """The number of unclipped spheres: the table holds them first (:meth:`Scene.arrays`)."""
    n = 0
    while n < spheres.shape[1] and spheres[8, n] == -np.inf:
        n += 1
    return n


@njit(**INLINED)  # speed vs compile time: see render/_emitters.py
def _light_sample(
    px, py, pz, nx, ny, nz, t_row, b_row, full, m, lights, light_pmf, materials, sphere_material, quad_material,
    spheres, quads, state, kinds_sphere, kinds_cone, kinds_quad, kinds_rectangle,
):  # fmt: skip
    """Next-event estimation at a diffuse vertex, the part that does not depend on the sampler.

    One emitter chosen by power, a point or direction on it; returns (ok, world direction w,
    local direction (lx, ly, lz) in the frame (t_row, b_row, n), distance, solid-angle pdf
    times the selection probability, the vertex's reflectance (or transmittance) towards w,
    the emitter's material, state).  ok is False when w is on the wrong side or the BSDF
    is black there.  The ``kinds_`` arguments: the scene's emitter kinds (:func:`light_kinds`).  Inlined by LLVM (see :mod:`symsphere.render._emitters` for why).
    """
    choice = 0
    if lights.shape[1] > 1:
        state, b1 = next_u64(state)
        choice = choose_light(lights, u01(b1))
    obj = np.int64(lights[0, choice])
    wx, wy, wz, dist, p_light, ok, state = sample_emitter(
        px, py, pz, obj, state, spheres, quads, kinds_sphere, kinds_cone, kinds_quad, kinds_rectangle
    )
    lz = wx * nx + wy * ny + wz * nz
    lx, ly, fr, fg, fb = 0.0, 0.0, 0.0, 0.0, 0.0
    lm = np.int64(0)
    if ok and (lz > 0.0 or (full and lz < 0.0)):
        c = 1 if lz > 0.0 else 4  # reflectance on the incoming side, transmittance on the other
        fr, fg, fb = materials[m, c], materials[m, c + 1], materials[m, c + 2]
        ok = fr != 0.0 or fg != 0.0 or fb != 0.0
        if ok:
            p_light *= light_pmf[obj]
            lx = wx * t_row[0] + wy * t_row[1] + wz * t_row[2]
            ly = wx * b_row[0] + wy * b_row[1] + wz * b_row[2]
            n_spheres = spheres.shape[1]
            lm = np.int64(sphere_material[obj] if obj < n_spheres else quad_material[obj - n_spheres])
    else:
        ok = False
    return ok, wx, wy, wz, lx, ly, lz, dist, p_light, fr, fg, fb, lm, state


@njit(**INLINED)  # speed vs compile time: see render/_emitters.py
def _specular_direction(kind, dx, dy, dz, nx, ny, nz, cos_in, entering, ior, state):
    """The direction after a mirror or a smooth dielectric (exact unpolarised Fresnel), and the state.

    *cos_in* = d . n with n facing the incoming ray (<= 0).
    """
    if kind == MIRROR:
        c2 = 2.0 * cos_in
        return dx - c2 * nx, dy - c2 * ny, dz - c2 * nz, state
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
        return dx - c2 * nx, dy - c2 * ny, dz - c2 * nz, state
    k = eta * cos_i - cos_t
    return eta * dx + k * nx, eta * dy + k * ny, eta * dz + k * nz, state


@njit(**INLINED)  # inlined by LLVM into the kernel: no call, no reference counting
def radiance(
    spheres, sphere_material, quads, quad_material, materials, lights, light_pmf, camera, background, eps,
    rr_depth, max_depth, integrator, sampler, fixed, cosine, code, pixel_filter, key, s, row, col, width, height, scratch,
    plain, kinds_sphere, kinds_cone, kinds_quad, kinds_rectangle,
):  # fmt: skip
    """The radiance estimate of one camera path: sample *s* of pixel (row, col); row 0 is the top.

    The ``kinds_`` arguments: the scene's emitter kinds (:func:`light_kinds`; None: none of that kind,
    whose code is then not compiled)."""
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
    nee = integrator == PATH and lights.shape[1] > 0
    specular = True  # the previous vertex (the camera counts) was specular: emission gets weight 1
    pdf_bsdf = 0.0  # solid-angle pdf of the direction sampled at the previous diffuse vertex
    # One intersect() site traces the path rays and the shadow rays in turn (a second inlined copy
    # doubled the compile time when numba inlined it; LLVM would inline it twice): after a vertex with a
    # shadow ray pending, the next trip through the loop traces it (only up to the sampled emitter
    # point: t_max), adds its contribution if it hits nothing, and then resumes the path (or ends it)
    # from the saved direction.
    shadow = False
    alive = True
    t_max = np.inf  # the path's rays: any hit; a shadow ray: hits before the sampled point
    cr, cg, cb = 0.0, 0.0, 0.0  # the pending shadow ray's contribution if unoccluded
    ndx, ndy, ndz = 0.0, 0.0, 0.0  # the path's next direction while the shadow ray is traced
    px, py, pz = ox, oy, oz
    depth = np.int64(0)  # not a literal: sample_local is typed (and compiled) once
    while True:
        t, hit = intersect(ox, oy, oz, dx, dy, dz, spheres, plain, quads, eps, scratch, t_max)
        if shadow:
            if hit < 0:  # nothing before the sampled point
                lr += cr
                lg += cg
                lb += cb
            if not alive:
                break
            shadow = False
            t_max = np.inf
            dx, dy, dz = ndx, ndy, ndz
            continue
        if hit < 0:
            lr += br * background[0]
            lg += bg * background[1]
            lb += bb * background[2]
            break
        px = ox + t * dx
        py = oy + t * dy
        pz = oz + t * dz
        if hit < n_spheres:
            inv_r = spheres[10, hit]  # 1 / r, stored
            nx = (px - spheres[0, hit]) * inv_r
            ny = (py - spheres[1, hit]) * inv_r
            nz = (pz - spheres[2, hit]) * inv_r
            m = sphere_material[hit]
        else:
            q = hit - n_spheres
            nx, ny, nz = quads[9, q], quads[10, q], quads[11, q]
            m = quad_material[q]
        cos_in = dx * nx + dy * ny + dz * nz
        er, eg, eb = materials[m, 8], materials[m, 9], materials[m, 10]
        if er != 0.0 or eg != 0.0 or eb != 0.0:
            mis = 1.0
            if nee and not specular:  # BSDF-sampled hit of an emitter that NEE also samples
                p_light = light_pmf[hit] * emitter_pdf(
                    ox, oy, oz, hit, t, abs(cos_in), spheres, quads, kinds_sphere, kinds_cone, kinds_quad,
                    kinds_rectangle,
                )  # fmt: skip
                mis = power_heuristic(pdf_bsdf, p_light)
            lr += br * er * mis
            lg += bg * eg * mis
            lb += bb * eb * mis

        entering = cos_in < 0.0
        if not entering:  # face the normal towards the incoming ray
            nx, ny, nz, cos_in = -nx, -ny, -nz, -cos_in
        kind = np.int64(materials[m, 0])
        if kind == DIFFUSE or kind == TRANSLUCENT:
            full = kind == TRANSLUCENT
            if materials[m, 1] == 0.0 and materials[m, 2] == 0.0 and materials[m, 3] == 0.0:
                if not full or (materials[m, 4] == 0.0 and materials[m, 5] == 0.0 and materials[m, 6] == 0.0):
                    break  # black: absorbed, whatever the direction
            t_row, b_row = frame_rows(nx, ny, nz)
            if nee and depth + 1 < max_depth:  # next-event estimation: one emitter, one shadow ray
                ok, wx, wy, wz, lx, ly, lz, dist, p_light, fr, fg, fb, lm, state = _light_sample(
                    px, py, pz, nx, ny, nz, t_row, b_row, full, m, lights, light_pmf, materials, sphere_material,
                    quad_material, spheres, quads, state, kinds_sphere, kinds_cone, kinds_quad, kinds_rectangle,
                )  # fmt: skip
                if ok:
                    p_b = bsdf_pdf(fixed, cosine, code, full, lx, ly, lz)
                    g = abs(lz) * _INV_PI * power_heuristic(p_light, p_b) / p_light
                    cr = br * fr * materials[lm, 8] * g
                    cg = bg * fg * materials[lm, 9] * g
                    cb = bb * fb * materials[lm, 10] * g
                    shadow = cr != 0.0 or cg != 0.0 or cb != 0.0
                    if shadow:  # the sampled point itself is not an occluder
                        t_max = dist * (1.0 - _SHADOW_TOLERANCE) - eps
                    ndx, ndy, ndz = wx, wy, wz  # swapped with the path's direction below
            x, y, z, weight, pdf_bsdf, state = sample_local(sampler, fixed, cosine, code, full, key, s, depth, state)
            if z >= 0.0:
                br *= materials[m, 1] * weight
                bg *= materials[m, 2] * weight
                bb *= materials[m, 3] * weight
            else:
                br *= materials[m, 4] * weight
                bg *= materials[m, 5] * weight
                bb *= materials[m, 6] * weight
            dx, dy, dz = rows_to_world(x, y, z, t_row, b_row, nx, ny, nz)
            specular = False
        else:  # MIRROR or DIELECTRIC
            dx, dy, dz, state = _specular_direction(
                kind, dx, dy, dz, nx, ny, nz, cos_in, entering, materials[m, 7], state
            )
            br *= materials[m, 1]
            bg *= materials[m, 2]
            bb *= materials[m, 3]
            specular = True

        if depth + 1 >= rr_depth:
            survive = min(max(br, bg, bb), _RR_CAP)
            state, bits = next_u64(state)
            if u01(bits) >= survive:
                alive = False
            else:
                inv_q = 1.0 / survive
                br *= inv_q
                bg *= inv_q
                bb *= inv_q
        elif br == 0.0 and bg == 0.0 and bb == 0.0:
            alive = False
        depth += 1
        if depth >= max_depth:
            alive = False
        ox, oy, oz = px, py, pz
        if shadow:  # trace the shadow ray first; the path's direction waits in nd
            dx, ndx = ndx, dx
            dy, ndy = ndy, dy
            dz, ndz = ndz, dz
        elif not alive:
            break
    return lr, lg, lb


@njit(**_PASS_KERNEL_OPTIONS)  # scratch comes from the caller
def _render_rows(
    spheres, sphere_material, quads, quad_material, materials, lights, light_pmf, camera, background, eps,
    rr_depth, max_depth, integrator, sampler, code, pixel_filter, seed, sample_start, sample_count, rows, accum,
    scratch, kinds_sphere, kinds_cone, kinds_quad, kinds_rectangle,
):  # fmt: skip  # pragma: no cover - compiled by numba
    """The serial kernel: it renders the rows it is given (every estimator, sampler, map and filter).

    Compiled once per set of the scene's emitter kinds (:func:`light_kinds`: True or None each), so
    that the light sampling of kinds the scene does not have is not compiled."""
    height = accum.shape[0]
    width = accum.shape[1]
    plain = plain_spheres(spheres)
    fixed = fixed_sampler(sampler)
    cosine = is_cosine(sampler)
    for i in range(rows.shape[0]):
        row = rows[i]
        for col in range(width):
            key = pixel_key(seed, row * width + col)
            sr, sg, sb = 0.0, 0.0, 0.0
            for s in range(sample_start, sample_start + sample_count):
                lr, lg, lb = radiance(
                    spheres, sphere_material, quads, quad_material, materials, lights, light_pmf, camera,
                    background, eps, rr_depth, max_depth, integrator, sampler, fixed, cosine, code, pixel_filter,
                    key, s,
                    row, col, width, height, scratch, plain, kinds_sphere, kinds_cone, kinds_quad, kinds_rectangle,
                )  # fmt: skip
                sr += lr
                sg += lg
                sb += lb
            accum[row, col, 0] += sr
            accum[row, col, 1] += sg
            accum[row, col, 2] += sb


def render_pass(
    spheres, sphere_material, quads, quad_material, materials, lights, light_pmf, camera, background, eps,
    rr_depth, max_depth, integrator, sampler, code, pixel_filter, seed, sample_start, sample_count, rows, accum,
):  # fmt: skip
    """Add samples sample_start .. sample_start + sample_count - 1 of every pixel into *accum* (H, W, 3).

    Rows are split into one stretch of *rows* per thread (``symsphere._threads.run_kernel``);
    every pixel is done by one thread and its random numbers depend only on (seed, pixel,
    sample), so the sum does not depend on the number of threads or passes.
    """
    prepare_kernels()
    kinds = light_kinds(spheres, sphere_material, quads, quad_material, materials)
    # a cold cache: in two processes (this one's parts for the scene's emitter kinds)
    compile_ahead(_render_rows, __name__, COMPILE_HERE, COMPILE_THERE, parts=kernel_parts(kinds))
    parts = max(1, min(get_num_threads(), len(rows)))

    def arguments(index):
        lo, hi = len(rows) * index // parts, len(rows) * (index + 1) // parts
        return (
            spheres, sphere_material, quads, quad_material, materials, lights, light_pmf, camera, background, eps,
            rr_depth, max_depth, int(integrator), int(sampler), int(code), int(pixel_filter), seed, sample_start,
            sample_count, rows[lo:hi], accum,
            np.empty(max(spheres.shape[1], quads.shape[1], 1)),  # intersect's scratch: one per part
            *kinds,
        )  # fmt: skip

    run_kernel(_render_rows, arguments, parts)


# The kernel's parts that numba compiles on their own, split in two groups of about equal compile
# time (measured: docs/results/cold-start.md) for symsphere._compile_ahead
COMPILE_HERE = ("_light_sample", "intersect", "emitter_pdf", "_film_offset")
COMPILE_THERE = ("sample_local", "bsdf_pdf", "_specular_direction")


def kernel_is_cached() -> bool:
    """Whether numba's disk cache holds the renderer's kernel (for its current source)."""
    return is_cached(_render_rows)


def kernel_parts(kinds: tuple[bool | None, ...] = (None,) * 4) -> dict[str, tuple[Any, tuple[Any, ...]]]:
    """The kernel's cached parts, each with the argument types :func:`_render_rows` calls it with.

    What :func:`symsphere._compile_ahead.compile_ahead` compiles in two processes on a cold cache
    (tested: a cold render compiles each part for exactly these types, and only them), for a scene
    with the emitter *kinds* (:func:`light_kinds`; the second process's parts do not depend on them).
    """
    f, i, u, b = types.float64, types.int64, types.uint64, types.boolean
    k = tuple(types.none if kind is None else b for kind in kinds)
    f1, f2, i1 = types.Array(f, 1, "C"), types.Array(f, 2, "C"), types.Array(i, 1, "C")
    row = types.UniTuple(f, 3)
    return {
        "_light_sample": (_light_sample, (f, f, f, f, f, f, row, row, b, i, f2, f1, f2, i1, i1, f2, f2, u, *k)),
        "intersect": (intersect, (f, f, f, f, f, f, f2, i, f2, f, f1, f)),
        "emitter_pdf": (emitter_pdf, (f, f, f, i, f, f, f2, f2, *k)),
        "_film_offset": (_film_offset, (i, u)),
        "sample_local": (sample_local, (i, i, b, i, b, u, i, i, u)),
        "bsdf_pdf": (bsdf_pdf, (i, b, i, b, f, f, f)),
        "_specular_direction": (_specular_direction, (i, f, f, f, f, f, f, f, b, f, u)),
    }


_ready = False


def prepare_kernels() -> None:
    """Before the first kernel of this module runs: drop a stale disk cache, start the threads.

    Nothing happens at import.  The dependencies of the cached kernels are derived from this
    module's imports (``_numba_cache.kernel_dependencies``); the threads start with passive
    OpenMP waiting (``_threads.start_threads``).
    """
    global _ready
    if not _ready:
        invalidate_if_changed(_render_rows)  # the module's cache directory
        invalidate_if_changed(sample_emitter)  # the emitters' own cached functions (they inline _random, frames)
        invalidate_if_changed(sample_local)  # the direction sampling's own (it inlines the maps, _random)
        start_threads()
        _ready = True


route_compiles(globals())  # the first compile of each numba function here: interruptible (_threads)
