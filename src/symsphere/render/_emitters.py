"""Emitters for next-event estimation and MIS: sampling, densities, selection, the power heuristic.

Scalar numba functions, called by the path-tracing kernel of
:mod:`symsphere.render._integrator`: :func:`choose_light`, :func:`sample_emitter`,
:func:`emitter_pdf` and :func:`power_heuristic`.  Speed against compile time, measured
(docs/results/cold-start.md): the functions of the hot path that take the scene's
tables (these three, and the integrator's ``intersect``, NEE's light sample and the specular
directions) are numba functions of their own, typed and compiled once each (``INLINED``:
cached, no reference counting, ``forceinline``), which LLVM then inlines into the kernel.  As
plain calls, each call passes every array as its nine fields and, with numba's reference
counting, increments and decrements the array's counter atomically: 0.53-0.77x the paths/s;
inlined in numba's IR instead (``inline="always"``), the kernel kept its speed but typed every
inlined copy again: 21 instead of 8 CPU-seconds for a first render's kernel.  The kernel itself
is compiled without reference counting (``_nrt=False``: it allocates nothing); the helpers that
LLVM may or may not inline (the rectangle's and the cone's set-up) are ``TABLE_FUNCTION``s.
The tables are those of :meth:`symsphere.render.Scene.arrays`, column-wise:
spheres and quads, their rows as listed at ``SPHERE_COLUMNS`` and
``QUAD_COLUMNS`` in :mod:`symsphere.render._integrator`.

Emitters are sampled as pbrt-v4 and Mitsuba 3 do (:func:`sample_emitter`):
a full sphere seen from outside uniformly in the cone it subtends (pdf
``1 / (2 pi (1 - cos theta_max))``), from inside (or on it) by area; a
clipped sphere (a spherical cap) by area on the cap, uniform in height
(Archimedes: the area of a spherical zone is 2 pi r h); a rectangle seen
under a solid angle >= 1e-3 uniformly in solid angle (Urena et al. 2013);
any other parallelogram by area.  Area densities are converted to solid
angle, ``p_w = d^2 / (|cos_l| A)``.  :func:`emitter_pdf` makes the same case
analysis for a hit found by BSDF sampling.

The local frame (:func:`rows_to_world`, the scalar twin of :func:`symsphere.frames.to_world`, in
the frame of :func:`symsphere.frames.frame_rows`) is shared with the integrator, which imports it
from here; 1/(2 pi) is :data:`symsphere._constants.INV_2PI`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit
from numba.extending import register_jitable

from .._constants import INV_2PI, TWO_POW_M53
from .._random.hashes import next_u64, u01
from .._threads import route_compiles
from ..frames import frame_rows
from ..warps._spherical_rectangle import rectangle_frame, rectangle_point

__all__ = [
    "ALWAYS_COMPILED",
    "INLINED",
    "choose_light",
    "disk_point",
    "emitter_pdf",
    "light_kinds",
    "power_heuristic",
    "rows_to_world",
    "sample_emitter",
    "spherical_rectangle",
]

# The numba options of the scalar functions that take the scene's tables (here and in the integrator):
# compiled once each, cached, no reference counting of their array arguments (they allocate nothing),
# and the kernels' error model (a division by zero gives inf or NaN, as in numpy, not an exception).
TABLE_FUNCTION: dict[str, Any] = dict(_nrt=False, cache=True, error_model="numpy", nogil=True)
# ... and those of the hot path: the same, marked for LLVM to inline into the caller (its alwaysinline
# attribute; numba types and compiles each once, unlike numba-IR inlining, which types every copy again)
INLINED: dict[str, Any] = dict(TABLE_FUNCTION, forceinline=True)
_PI = math.pi
_MIN_RECTANGLE_SOLID_ANGLE = 1e-3  # below it a rectangle is sampled by area (pbrt-v4's threshold)
_ONE_MINUS_EPSILON = 1.0 - TWO_POW_M53
_S32 = np.uint64(32)
_M32 = np.uint64(0xFFFFFFFF)
_TWO_M31 = 2.0**-31


# --- the local frame ------------------------------------------------------------------


@register_jitable
def rows_to_world(lx, ly, lz, t, b, nx, ny, nz):
    """Local (x, y, z) to world coordinates in the frame (t, b, n) of the unit normal n (z along n), the
    scalar twin of :func:`symsphere.frames.to_world`: t, b are ``frames.frame_rows(nx, ny, nz)``."""
    return (
        lx * t[0] + ly * b[0] + lz * nx,
        lx * t[1] + ly * b[1] + lz * ny,
        lx * t[2] + ly * b[2] + lz * nz,
    )


# --- emitters ------------------------------------------------------------------------

LIGHT_KINDS = ("sphere", "cone", "quad", "rectangle")
"""The emitter kinds the renderer's kernel is specialised on (:func:`light_kinds`): any sphere, a full
(unclipped) sphere, which may be sampled by its cone, any quad, a rectangle, which may be sampled in
solid angle."""
ALWAYS_COMPILED = ("sphere", "quad")
"""Kinds whose code every kernel holds: a cap sampled by its height and a parallelogram by its area are
a few lines each, and with them compiled for every scene, scenes that differ only in these kinds share
one kernel (one compile in a process or a test run, not one per set of kinds).  The cone and the
rectangle in solid angle are most of the light sampling's compile time (docs/results/cold-start.md)."""


def light_kinds(
    spheres: Any, sphere_material: Any, quads: Any, quad_material: Any, materials: Any
) -> tuple[bool | None, ...]:
    """For each of :data:`LIGHT_KINDS`: True if the kernel is compiled for it, else None: always for the
    kinds of :data:`ALWAYS_COMPILED`, and for the others if the scene has an emitter of that kind.

    The tables are those of :meth:`symsphere.render.Scene.arrays`; an emitter is an object whose
    material emits (what the kernel tests before it asks :func:`emitter_pdf`).  A kernel called with
    None for a kind does not compile its code (numba prunes a branch on an argument that is None).
    """
    emits = np.any(np.asarray(materials)[:, 8:11] != 0.0, axis=1)
    sphere_lights = emits[np.asarray(sphere_material, dtype=np.int64)]
    quad_lights = emits[np.asarray(quad_material, dtype=np.int64)]
    full = np.asarray(spheres)[8] == -np.inf
    rectangle = np.asarray(quads)[25] != 0.0
    found = {
        "sphere": bool(sphere_lights.any()),
        "cone": bool((sphere_lights & full).any()),
        "quad": bool(quad_lights.any()),
        "rectangle": bool((quad_lights & rectangle).any()),
    }
    return tuple(True if found[kind] or kind in ALWAYS_COMPILED else None for kind in LIGHT_KINDS)


@njit(**TABLE_FUNCTION)
def _sphere_cone(px, py, pz, i, spheres):
    """(e = c - p, |e|^2, p outside the sphere): whether a full sphere is sampled by its cone from p.

    One expression, used by :func:`sample_emitter` and :func:`emitter_pdf`
    alike, so that both make the same choice for the same point (a point on
    the sphere may round either way; both choices are valid there).
    """
    ex = spheres[0, i] - px
    ey = spheres[1, i] - py
    ez = spheres[2, i] - pz
    d2 = ex * ex + ey * ey + ez * ez
    return ex, ey, ez, d2, d2 > spheres[4, i] and spheres[8, i] == -np.inf


@njit(**TABLE_FUNCTION)
def spherical_rectangle(px, py, pz, j, quads):
    """The rectangle j seen from p: :func:`symsphere.warps._spherical_rectangle.rectangle_frame` (Urena,
    Fajardo & King 2013) of its corner in the frame (x, y, z) of its edges e, f and its normal e x f,
    relative to p.  Returns (S, x0, y0, z0, x1, y1, zsign, b0, b1, cos k, sin k); S = 0 when p is in
    the rectangle's plane."""
    ex, ey, ez = quads[17, j], quads[18, j], quads[19, j]
    fx, fy, fz = quads[20, j], quads[21, j], quads[22, j]
    gx, gy, gz = quads[9, j], quads[10, j], quads[11, j]  # the unit normal: e x f for a rectangle
    dx = quads[0, j] - px
    dy = quads[1, j] - py
    dz = quads[2, j] - pz
    x0 = dx * ex + dy * ey + dz * ez
    y0 = dx * fx + dy * fy + dz * fz
    z0 = dx * gx + dy * gy + dz * gz
    return rectangle_frame(x0, y0, z0, quads[23, j], quads[24, j])


@register_jitable
def disk_point(state):
    """A uniform point (x, y) of the unit disk and r^2 = x^2 + y^2 > 0: rejection from the square.

    One 64-bit draw per trial, 32 bits per coordinate; accepted with
    probability pi/4.  (x, y) / r is a uniform direction and r^2 is uniform
    on (0, 1], independent of it, so one point gives a height and an azimuth
    without a sine or a cosine (measured: cos + sin cost ~35 ns here).
    """
    while True:
        state, bits = next_u64(state)
        x = np.float64(bits >> _S32) * _TWO_M31 - 1.0
        y = np.float64(bits & _M32) * _TWO_M31 - 1.0
        r2 = x * x + y * y
        if r2 <= 1.0 and r2 > 0.0:
            return x, y, r2, state


@njit(**INLINED)
def sample_emitter(px, py, pz, obj, state, spheres, quads, kinds_sphere, kinds_cone, kinds_quad, kinds_rectangle):
    """Sample the emitter *obj* as seen from the point p: (wx, wy, wz, distance, pdf, ok, state).

    w is a unit direction, pdf its solid-angle density (without the emitter's
    selection probability), distance that of the sampled point (for a cone,
    where a direction is sampled, the nearer intersection with the sphere), so
    that the point is visible when nothing is hit before it.  ``ok`` is False for a degenerate sample (zero distance or a
    grazing point), which contributes nothing.  *state* is the path's stream.

    - a full sphere seen from outside: uniform in the cone it subtends
      (pbrt-v4 ``Sphere::Sample(ctx, u)``, Mitsuba 3 ``Sphere::sample_direction``):
      ``sin^2 theta_max = r^2 / |c - p|^2``, ``1 - cos theta = u (1 - cos theta_max)``,
      ``1 - cos theta_max = sin^2 theta_max / (1 + cos theta_max)`` (no cancellation
      for small cones), pdf ``1 / (2 pi (1 - cos theta_max))``;
    - a full sphere seen from inside or on it, and a clipped sphere: by area on
      the cap of height h about the axis a (h = 2 r: the whole sphere), uniform
      in height by Archimedes' hat-box theorem: ``w = u h`` below the pole
      c + r a, ring radius ``sqrt(w (2 r - w))``, uniform azimuth; area
      ``2 pi r h``;
    - a rectangle (a parallelogram with orthogonal edges) seen under a solid
      angle S >= 1e-3: uniformly in S (:func:`spherical_rectangle`; Urena et
      al. 2013, section 4), pdf ``1 / S``;
    - any other parallelogram: ``corner + u edge1 + v edge2``, area ``|edge1 x edge2|``.

    For the sphere cases u and the azimuth come from one uniform disk point
    (:func:`disk_point`): u = r^2, (cos, sin) = (x, y) / r, so that e.g. the
    ring point is ``(x, y) sqrt(h (2 r - w))``.  Area densities become
    solid-angle ones as ``|q - p|^2 / (|cos_l| area)``, cos_l between w and the
    emitter's normal at q.

    *kinds_sphere*, *kinds_cone*, *kinds_quad*, *kinds_rectangle* (:data:`LIGHT_KINDS`) are each None
    when the scene has no emitter of that kind, and then numba prunes its branch before typing it:
    the code for absent kinds is never compiled (its cost: docs/results/cold-start.md).
    """
    n_spheres = spheres.shape[1]
    if obj < n_spheres:
        if kinds_sphere is None:
            return 0.0, 0.0, 1.0, 0.0, 0.0, False, state  # (not an emitter of the scene: never reached)
        r = spheres[3, obj]
        x, y, u, state = disk_point(state)
        if kinds_cone is not None and spheres[8, obj] == -np.inf:  # a full sphere: by its cone from outside
            ex, ey, ez, d2, cone = _sphere_cone(px, py, pz, obj, spheres)
            if cone:
                sin2 = spheres[4, obj] / d2
                cos_max = math.sqrt(max(0.0, 1.0 - sin2))
                one_minus_cos_max = sin2 / (1.0 + cos_max)
                w = u * one_minus_cos_max  # 1 - cos theta
                scale = math.sqrt(max(0.0, one_minus_cos_max * (2.0 - w)))  # sin theta / sqrt(u)
                inv = 1.0 / math.sqrt(d2)
                ax, ay, az = ex * inv, ey * inv, ez * inv  # the cone's axis
                t_row, b_row = frame_rows(ax, ay, az)
                wx, wy, wz = rows_to_world(x * scale, y * scale, 1.0 - w, t_row, b_row, ax, ay, az)
                # the distance to the sphere along w: the nearer root of |p + t w - c|^2 = r^2
                b = ex * wx + ey * wy + ez * wz
                dist = b - math.sqrt(max(0.0, b * b - (d2 - spheres[4, obj])))
                return wx, wy, wz, dist, INV_2PI / one_minus_cos_max, one_minus_cos_max > 0.0 and dist > 0.0, state
        height = spheres[9, obj]
        w = u * height  # depth below the pole c + r a
        scale = math.sqrt(max(0.0, height * (2.0 * r - w)))  # ring radius / sqrt(u)
        lx, ly, lz = x * scale, y * scale, r - w  # q - c in the frame (t, b, a) of the cap's axis a (stored)
        ox = lx * spheres[11, obj] + ly * spheres[14, obj] + lz * spheres[5, obj]
        oy = lx * spheres[12, obj] + ly * spheres[15, obj] + lz * spheres[6, obj]
        oz = lx * spheres[13, obj] + ly * spheres[16, obj] + lz * spheres[7, obj]
        dx = spheres[0, obj] + ox - px  # q - p
        dy = spheres[1, obj] + oy - py
        dz = spheres[2, obj] + oz - pz
        dist2 = dx * dx + dy * dy + dz * dz
        dist = math.sqrt(dist2)
        proj = abs(dx * ox + dy * oy + dz * oz)  # |(q - p) . (q - c)| = dist r |cos_l|: no normal, no division
        inv = 1.0 / dist
        pdf = dist2 * dist / (proj * (2.0 * _PI * height))  # d^2 / (|cos_l| 2 pi r h)
        return dx * inv, dy * inv, dz * inv, dist, pdf, proj > 0.0 and dist > 0.0, state
    else:
        if kinds_quad is None:
            return 0.0, 0.0, 1.0, 0.0, 0.0, False, state  # (not an emitter of the scene: never reached)
        j = obj - n_spheres
        state, b1 = next_u64(state)
        state, b2 = next_u64(state)
        u = u01(b1)
        v = u01(b2)
        if kinds_rectangle is not None and quads[25, j] != 0.0:
            solid_angle, x0, y0, z0, x1, y1, zsign, b0, b1_, ck, sk = spherical_rectangle(px, py, pz, j, quads)
            if solid_angle >= _MIN_RECTANGLE_SOLID_ANGLE:  # uniform in solid angle (Urena et al. 2013, sec. 4)
                xu, yv, dist2 = rectangle_point(u, v, solid_angle, x0, y0, z0, x1, y1, b0, b1_, ck, sk)
                lz = z0 * zsign  # back to the frame of the edges
                wx = xu * quads[17, j] + yv * quads[20, j] + lz * quads[9, j]  # the normal is e x f
                wy = xu * quads[18, j] + yv * quads[21, j] + lz * quads[10, j]
                wz = xu * quads[19, j] + yv * quads[22, j] + lz * quads[11, j]
                dist = math.sqrt(dist2)
                if not dist > 0.0:
                    return 0.0, 0.0, 1.0, 0.0, 0.0, False, state
                inv = 1.0 / dist
                return wx * inv, wy * inv, wz * inv, dist, 1.0 / solid_angle, True, state
        qx = quads[0, j] + u * quads[3, j] + v * quads[6, j]
        qy = quads[1, j] + u * quads[4, j] + v * quads[7, j]
        qz = quads[2, j] + u * quads[5, j] + v * quads[8, j]
        nx, ny, nz = quads[9, j], quads[10, j], quads[11, j]
        area = quads[16, j]
    dx = qx - px
    dy = qy - py
    dz = qz - pz
    dist2 = dx * dx + dy * dy + dz * dz
    dist = math.sqrt(dist2)
    if not dist > 0.0:
        return 0.0, 0.0, 1.0, 0.0, 0.0, False, state
    inv = 1.0 / dist
    dx *= inv
    dy *= inv
    dz *= inv
    cos_l = abs(dx * nx + dy * ny + dz * nz)
    if not cos_l > 0.0:
        return dx, dy, dz, dist, 0.0, False, state
    return dx, dy, dz, dist, dist2 / (cos_l * area), True, state


@njit(**INLINED)
def emitter_pdf(px, py, pz, obj, t, cos_l, spheres, quads, kinds_sphere, kinds_cone, kinds_quad, kinds_rectangle):
    """The solid-angle density with which :func:`sample_emitter` from p yields the hit of *obj* at distance t.

    *cos_l* is |cos| between the ray and the emitter's normal at the hit.
    The same case analysis as :func:`sample_emitter` (cone, cap, rectangle, parallelogram), and
    the same emitter kinds (None: absent from the scene, not compiled).
    """
    n_spheres = spheres.shape[1]
    if obj < n_spheres:
        if kinds_sphere is None:
            return 0.0  # (not an emitter of the scene: never reached)
        if kinds_cone is not None:
            _, _, _, d2, cone = _sphere_cone(px, py, pz, obj, spheres)
            if cone:
                sin2 = spheres[4, obj] / d2
                cos_max = math.sqrt(max(0.0, 1.0 - sin2))
                return INV_2PI * (1.0 + cos_max) / sin2
        area = 2.0 * _PI * spheres[3, obj] * spheres[9, obj]
    else:
        if kinds_quad is None:
            return 0.0  # (not an emitter of the scene: never reached)
        j = obj - n_spheres
        if kinds_rectangle is not None and quads[25, j] != 0.0:
            solid_angle = spherical_rectangle(px, py, pz, j, quads)[0]
            if solid_angle >= _MIN_RECTANGLE_SOLID_ANGLE:
                return 1.0 / solid_angle
        area = quads[16, j]
    if not cos_l > 0.0:
        return np.inf
    return t * t / (cos_l * area)


@njit(**INLINED)
def choose_light(lights, u):
    """Index (into the rows of *lights*) of the emitter whose cumulative probability interval holds u."""
    last = lights.shape[1] - 1
    j = 0
    while j < last and u >= lights[1, j]:
        j += 1
    return j


@register_jitable
def power_heuristic(pdf, other):
    """Veach's power heuristic (beta = 2) ``pdf^2 / (pdf^2 + other^2)``, as ``1 / (1 + (other / pdf)^2)``.

    The quotient form handles pdf = inf (weight 1; the paper maps' vertex,
    where the sample's throughput weight is 0 anyway) and other = 0.
    """
    if not pdf > 0.0:
        return 0.0
    ratio = other / pdf
    return 1.0 / (1.0 + ratio * ratio)


route_compiles(globals())  # the first compile of each numba function here: interruptible (_threads)
