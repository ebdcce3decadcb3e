"""Sampling a spherical triangle by projected solid angle about a normal n: forward, pdf, inverse.

The density is ``max(0, n.d) / E`` on the triangle, E its projected solid angle (Lambert's
``E = 1/2 sum gamma_i n.unit(v_i x v_i+1)`` over the part above the horizon): a Lambertian surface lit
by a uniform triangle light gets an estimate of its direct light with no variance.  Peters 2021
("BRDF importance sampling for polygonal lights", ACM TOG 40(4)) samples polygons so; this is an
exact equivalent derived here.

Nusselt's analogue: projecting the hemisphere about n onto its tangent disk turns cos(theta) d(omega)
into area, so the map is uniform in the area of the triangle's projection R.  A great circle with
normal m projects to half an ellipse centred at the origin; along the ray of azimuth phi the constraint
m.d >= 0 reads r <= rho or r >= rho with ``rho^2 = m_z^2 / (m_z^2 + k^2)``, ``k = m_x cos(phi) +
m_y sin(phi)`` (or holds for every r, or for none).  So every ray from the origin meets R in one segment
[r_lo, r_hi] (the horizon is r <= 1), and ``cos(theta) d(omega) = r dr dphi``: phi has density
``(r_hi^2 - r_lo^2) / 2``, then r^2 is uniform in [r_lo^2, r_hi^2] (v), in closed form.  Between the
azimuths of the clipped triangle's vertices (at most four: the triangle cut at the horizon) r_hi and
r_lo each come from one edge (or the horizon, or 0), and the area of the sector of an edge between two
azimuths is ``|m_z| / 2`` times the arc between its two points (a planar sector of the great circle,
projected): the CDF of phi is closed form piece by piece.  Its inverse is not (a sector difference of
two ellipses, Kepler-like), so u picks a piece by its area and phi is found in the piece by a bracketed
Newton iteration (bisection when a step leaves the bracket), run until the step is below 4 ulp of 2 pi
in float64: the forward map is exact to that.  The inverse is closed form (the sector areas at the
direction's azimuth).

The scalar functions (:func:`projected_triangle_setup`, :func:`projected_triangle_point`,
:func:`projected_triangle_uv`, :func:`projected_triangle_density`) are what numba compiles into kernels;
the numpy functions run them in a compiled loop, in float64 whatever the input dtype.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt
from numba import njit
from numba.extending import register_jitable

from .._threads import route_compiles
from .._typing import Float64Array, FloatArray
from .._validation import check_directions, check_triangle, check_unit_directions, check_uv
from .._validation.arrays import check_normal

__all__ = [
    "projected_solid_angle",
    "square_to_projected_triangle",
    "square_to_projected_triangle_pdf",
    "projected_triangle_to_square",
    "projected_triangle_setup",
    "projected_triangle_point",
    "projected_triangle_uv",
    "projected_triangle_density",
]

_TWO_PI = 2.0 * math.pi
_TOL = 4.0 * 2.220446049250313e-16 * _TWO_PI  # the root finder's step tolerance on phi
_MAX_STEPS = 100  # bisection alone needs 54 halvings of 2 pi to reach _TOL
# Lambert's sum cancels for a triangle seen nearly edge-on (terms ~ 1, E ~ their height^2): below this
# fraction of the terms' sum E is rounding noise, and the triangle is treated as having E = 0.
_CANCELLED = 1e-10

# Layout of the setup array (float64): the frame, the inward edge normals (local), the reference
# azimuth, the 5 piece boundaries (offsets from it), each piece's upper and lower constraint
# (0..2 an edge, 3 the horizon / none), the cumulative piece areas, the projected solid angle E.
_T1, _T2, _N, _M = 0, 3, 6, 9
_PHI0, _S, _HI, _LO, _C, _E = 18, 19, 24, 28, 32, 37
SETUP_SIZE = 38


@register_jitable
def _constraint(m: Any, i: int, cos_phi: float, sin_phi: float) -> tuple[float, float, float]:
    """(kind, m_z^2, k^2) of edge i along the ray of azimuth phi: kind 1 r <= rho, -1 r >= rho, 0 any r,
    2 no r; rho^2 = m_z^2 / (m_z^2 + k^2).  Bounds are compared by m_z^2 k'^2 against m_z'^2 k^2 (no
    rounding of rho^2 to 1 for an edge within 1e-8 of the horizon: its z^2 = k^2 / (m_z^2 + k^2))."""
    mz = m[_M + 3 * i + 2]
    k = m[_M + 3 * i] * cos_phi + m[_M + 3 * i + 1] * sin_phi
    den = mz * mz + k * k
    if mz > 0.0 and k < 0.0:
        return 1.0, mz * mz, k * k
    if mz < 0.0 and k > 0.0:
        return -1.0, mz * mz, k * k
    if mz >= 0.0 and k >= 0.0 and den > 0.0:
        return 0.0, 0.0, 1.0
    return 2.0, 0.0, 1.0


@register_jitable
def _bounds(s: Any, hi: int, lo: int, phi: float) -> tuple[float, float, float, float]:
    """(rho_hi^2, z_hi^2, rho_lo^2, z_lo^2) at azimuth phi for the piece's constraints."""
    c, sn = math.cos(phi), math.sin(phi)
    rh, zh, rl, zl = 1.0, 0.0, 0.0, 1.0
    if hi < 3:
        rh, zh = _crossing(s, hi, c, sn)
    if lo < 3:
        rl, zl = _crossing(s, lo, c, sn)
    return rh, zh, rl, zl


@register_jitable
def _crossing(s: Any, i: int, cos_phi: float, sin_phi: float) -> tuple[float, float]:
    """(rho^2, z^2) where edge i's great circle crosses the ray of azimuth phi, whatever the side (at a
    piece's ends the bound may meet the horizon, k = 0, and must run on continuously)."""
    mz = s[_M + 3 * i + 2]
    k = s[_M + 3 * i] * cos_phi + s[_M + 3 * i + 1] * sin_phi
    den = mz * mz + k * k
    if not den > 0.0:
        return 0.0, 1.0
    return mz * mz / den, k * k / den


@register_jitable
def _sector(s: Any, i: int, phi_a: float, phi_b: float) -> float:
    """Area of the projection of edge i's great circle's sector between azimuths phi_a <= phi_b (i = 3:
    the horizon): |m_z| / 2 times the arc between its two points there."""
    if i >= 3:
        return 0.5 * (phi_b - phi_a)
    mx, my, mz = s[_M + 3 * i], s[_M + 3 * i + 1], s[_M + 3 * i + 2]
    az = abs(mz)
    ca, sa, cb, sb = math.cos(phi_a), math.sin(phi_a), math.cos(phi_b), math.sin(phi_b)
    ka, kb = abs(mx * ca + my * sa), abs(mx * cb + my * sb)
    # w = (|m_z| cos phi, |m_z| sin phi, |k|) lies on the circle at azimuth phi (up to its length)
    ax, ay, bx, by = az * ca, az * sa, az * cb, az * sb
    cx = ay * kb - ka * by
    cy = ka * bx - ax * kb
    cz = ax * by - ay * bx
    dot = ax * bx + ay * by + ka * kb
    area: float = 0.5 * az * math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), dot)
    return area


@register_jitable
def _piece_area(s: Any, j: int, delta: float) -> float:
    """Area of piece j between its start and the offset delta (the piece's CDF, unnormalised)."""
    hi, lo = int(s[_HI + j]), int(s[_LO + j])
    phi_a = s[_PHI0] + s[_S + j]
    phi = s[_PHI0] + delta
    area = _sector(s, hi, phi_a, phi)
    if lo < 3:
        area -= _sector(s, lo, phi_a, phi)
    return area


@register_jitable
def projected_triangle_setup(verts: Any, normal: Any) -> Any:
    """The constants of the map for the triangle *verts* (3, 3) (directions, any length) about the
    unit *normal*: a float64 array of SETUP_SIZE; its last entry is E (0 for a triangle with no part
    above the horizon, degenerate or seen edge-on: such a triangle has no sample and density 0).

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.warps import projected_triangle_setup
    >>> verts = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]])   # an octant: E = pi / 4
    >>> bool(np.isclose(projected_triangle_setup(verts, np.array([0, 0, 1.0]))[-1], np.pi / 4))
    True
    """
    s = np.zeros(SETUP_SIZE)
    nx, ny, nz = normal[0], normal[1], normal[2]
    # Duff et al. 2017's orthonormal basis (Mitsuba's coordinate_system): (t1, t2, n) right-handed
    sign = 1.0 if nz >= 0.0 else -1.0
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    s[0], s[1], s[2] = 1.0 + sign * nx * nx * a, sign * b, -sign * nx
    s[3], s[4], s[5] = b, sign + ny * ny * a, -ny
    s[6], s[7], s[8] = nx, ny, nz
    v = np.empty((3, 3))
    for i in range(3):
        x = verts[i, 0] * s[0] + verts[i, 1] * s[1] + verts[i, 2] * s[2]
        y = verts[i, 0] * s[3] + verts[i, 1] * s[4] + verts[i, 2] * s[5]
        z = verts[i, 0] * nx + verts[i, 1] * ny + verts[i, 2] * nz
        length = math.sqrt(x * x + y * y + z * z)
        if not length > 0.0:
            return s
        v[i, 0], v[i, 1], v[i, 2] = x / length, y / length, z / length
    triple = (
        v[0, 0] * (v[1, 1] * v[2, 2] - v[1, 2] * v[2, 1])
        - v[0, 1] * (v[1, 0] * v[2, 2] - v[1, 2] * v[2, 0])
        + v[0, 2] * (v[1, 0] * v[2, 1] - v[1, 1] * v[2, 0])
    )
    if not (triple != 0.0 and math.isfinite(triple)):
        return s
    if triple < 0.0:  # counter-clockwise seen from outside: the interior on the left of each edge
        for k in range(3):
            v[1, k], v[2, k] = v[2, k], v[1, k]
    for i in range(3):
        p, q = v[i], v[(i + 1) % 3]
        # p x (q - p) = p x q, accurate for close vertices (q - p exact-ish)
        dx, dy, dz = q[0] - p[0], q[1] - p[1], q[2] - p[2]
        mx, my, mz = p[1] * dz - p[2] * dy, p[2] * dx - p[0] * dz, p[0] * dy - p[1] * dx
        length = math.sqrt(mx * mx + my * my + mz * mz)
        if not length > 0.0:
            return s
        s[_M + 3 * i], s[_M + 3 * i + 1], s[_M + 3 * i + 2] = mx / length, my / length, mz / length
    # the part above the horizon: Sutherland-Hodgman against z >= 0 (at most 4 vertices)
    poly = np.zeros((4, 3))
    count = 0
    for i in range(3):
        p, q = v[i], v[(i + 1) % 3]
        if p[2] >= 0.0:
            poly[count, 0], poly[count, 1], poly[count, 2] = p[0], p[1], p[2]
            count += 1
        if (p[2] >= 0.0) != (q[2] >= 0.0):  # the crossing (p_z q - q_z p) / (p_z - q_z): on the arc, z = 0
            x, y = p[2] * q[0] - q[2] * p[0], p[2] * q[1] - q[2] * p[1]
            length = math.copysign(math.sqrt(x * x + y * y), p[2] - q[2])
            poly[count, 0], poly[count, 1], poly[count, 2] = x / length, y / length, 0.0
            count += 1
    if count < 3:
        return s
    # Lambert: E = 1/2 sum gamma_e n.unit(p x q) over the clipped polygon's edges
    e, scale = 0.0, 0.0
    for k in range(count):
        p, q = poly[k], poly[(k + 1) % count]
        dx, dy, dz = q[0] - p[0], q[1] - p[1], q[2] - p[2]
        cx, cy, cz = p[1] * dz - p[2] * dy, p[2] * dx - p[0] * dz, p[0] * dy - p[1] * dx
        sin_g = math.sqrt(cx * cx + cy * cy + cz * cz)
        if sin_g > 0.0:
            term = 0.5 * math.atan2(sin_g, p[0] * q[0] + p[1] * q[1] + p[2] * q[2]) * cz / sin_g
            e += term
            scale += abs(term)
    if not e > _CANCELLED * scale:  # E within its rounding error of 0: an edge-on triangle, nothing to sample
        return s
    # the pieces: azimuth offsets of the clipped vertices from the first one's, sorted
    phi0 = math.atan2(poly[0, 1], poly[0, 0])
    s[_PHI0] = phi0
    bounds = np.full(5, _TWO_PI)
    for k in range(count):
        d = math.atan2(poly[k, 1], poly[k, 0]) - phi0
        if d < 0.0:
            d += _TWO_PI
        bounds[k] = min(d, _TWO_PI)
    bounds[0] = 0.0
    bounds[:4] = np.sort(bounds[:4])
    cumulative = 0.0
    for j in range(4):
        a_, b_ = bounds[j], bounds[j + 1]
        s[_S + j] = a_
        mid = phi0 + 0.5 * (a_ + b_)
        cm, sm = math.cos(mid), math.sin(mid)
        # the bounds as (m_z^2, k^2): the horizon (1, 0), no lower bound (0, 1)
        hi, lo, mh, kh, ml, kl, empty = 3, 3, 1.0, 0.0, 0.0, 1.0, False
        for i in range(3):
            kind, mz2, k2 = _constraint(s, i, cm, sm)
            if kind == 1.0 and mz2 * kh < mh * k2:
                hi, mh, kh = i, mz2, k2
            elif kind == -1.0 and mz2 * kl > ml * k2:
                lo, ml, kl = i, mz2, k2
            elif kind == 2.0:
                empty = True
        s[_HI + j], s[_LO + j] = hi, lo
        s[_C + j] = cumulative
        if not empty and mh * kl > ml * kh and b_ > a_:
            cumulative += max(_piece_area(s, j, b_), 0.0)
    s[_S + 4] = _TWO_PI
    s[_C + 4] = cumulative
    s[_E] = e if e > 0.0 and cumulative > 0.0 else 0.0
    return s


@register_jitable
def _local(s: Any, x: float, y: float, z: float) -> tuple[float, float, float]:
    return (
        x * s[0] + y * s[1] + z * s[2],
        x * s[3] + y * s[4] + z * s[5],
        x * s[6] + y * s[7] + z * s[8],
    )


@register_jitable
def projected_triangle_point(u: float, v: float, s: Any) -> tuple[float, float, float, float]:
    """The direction (x, y, z) for (u, v) and its density cos(theta) / E (setup *s* of
    :func:`projected_triangle_setup`); (n, 0) when E = 0.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.warps import projected_triangle_point, projected_triangle_setup
    >>> s = projected_triangle_setup(np.eye(3), np.array([0, 0, 1.0]))
    >>> x, y, z, pdf = projected_triangle_point(0.3, 0.7, s)
    >>> bool(np.isclose(pdf, z / (np.pi / 4))), bool(min(x, y, z) >= 0)
    (True, True)
    """
    total = s[_C + 4]
    if not s[_E] > 0.0:
        return s[6], s[7], s[8], 0.0
    target = u * total
    j = 3
    while j > 0 and not s[_C + j + 1] > s[_C + j]:
        j -= 1  # the last non-empty piece
    for jj in range(3, -1, -1):
        if s[_C + jj + 1] > s[_C + jj] and target <= s[_C + jj + 1]:
            j = jj
    area = s[_C + j + 1] - s[_C + j]
    tau = min(max(target - s[_C + j], 0.0), area)
    lo_b, hi_b = s[_S + j], s[_S + j + 1]
    hi, lo = int(s[_HI + j]), int(s[_LO + j])
    x = lo_b + (hi_b - lo_b) * (tau / area)
    for _ in range(_MAX_STEPS):
        g = _piece_area(s, j, x) - tau
        if g == 0.0:
            break
        if g > 0.0:
            hi_b = x
        else:
            lo_b = x
        rh, _, rl, _ = _bounds(s, hi, lo, s[_PHI0] + x)
        slope = 0.5 * (rh - rl)
        step_ok = slope > 0.0
        xn = x - g / slope if step_ok else x
        if not (step_ok and lo_b < xn < hi_b):
            xn = 0.5 * (lo_b + hi_b)
        done = abs(xn - x) <= _TOL or hi_b - lo_b <= _TOL
        x = xn
        if done:
            break
    phi = s[_PHI0] + x
    rh, zh, rl, zl = _bounds(s, hi, lo, phi)
    r2 = max(rl + v * (rh - rl), 0.0)
    z2 = max(zl - v * (zl - zh), 0.0)
    r, z = math.sqrt(r2), math.sqrt(z2)
    inv = 1.0 / math.sqrt(r2 + z2)
    lx, ly, lz = r * math.cos(phi) * inv, r * math.sin(phi) * inv, z * inv
    return (
        lx * s[0] + ly * s[3] + lz * s[6],
        lx * s[1] + ly * s[4] + lz * s[7],
        lx * s[2] + ly * s[5] + lz * s[8],
        lz / s[_E],
    )


@register_jitable
def projected_triangle_uv(x: float, y: float, z: float, s: Any) -> tuple[float, float]:
    """Inverse of :func:`projected_triangle_point` at the unit direction (x, y, z) in the triangle.

    u is the area of the pieces before the direction's azimuth over E's sum of pieces, v the place of
    r^2 between r_lo^2 and r_hi^2 on its ray (from r^2 near the pole, from z^2 near the horizon).

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.warps import projected_triangle_point, projected_triangle_setup, projected_triangle_uv
    >>> s = projected_triangle_setup(np.eye(3), np.array([0, 0, 1.0]))
    >>> x, y, z, _ = projected_triangle_point(0.3, 0.7, s)
    >>> bool(np.allclose(projected_triangle_uv(x, y, z, s), (0.3, 0.7)))
    True
    """
    total = s[_C + 4]
    if not s[_E] > 0.0:
        return 0.0, 0.0
    lx, ly, lz = _local(s, x, y, z)
    length = math.sqrt(lx * lx + ly * ly + lz * lz)
    lx, ly, lz = lx / length, ly / length, lz / length
    delta = math.atan2(ly, lx) - s[_PHI0]
    if delta < 0.0:
        delta += _TWO_PI
    first, last = -1, -1
    for jj in range(4):
        if s[_C + jj + 1] > s[_C + jj]:
            last = jj
            if first < 0:
                first = jj
    end = s[_S + last + 1]
    if delta > end and _TWO_PI - delta < delta - end:
        delta = 0.0  # just before the reference azimuth: the start, not the end
    j = first
    for jj in range(4):
        if s[_C + jj + 1] > s[_C + jj] and delta >= s[_S + jj]:
            j = jj
    delta = min(max(delta, s[_S + j]), s[_S + j + 1])
    area = min(max(_piece_area(s, j, delta), 0.0), s[_C + j + 1] - s[_C + j])
    u = (s[_C + j] + area) / total
    hi, lo = int(s[_HI + j]), int(s[_LO + j])
    rh, zh, rl, zl = _bounds(s, hi, lo, s[_PHI0] + delta)
    r2 = lx * lx + ly * ly
    if r2 <= 0.5:
        num, den = r2 - rl, rh - rl
    else:
        num, den = zl - lz * lz, zl - zh
    v = num / den if den > 0.0 else 0.0
    return min(max(u, 0.0), 1.0), min(max(v, 0.0), 1.0)


@register_jitable
def projected_triangle_density(x: float, y: float, z: float, s: Any) -> float:
    """max(0, n.d) / E for the direction d = (x, y, z) in the triangle (each edge's plane within 1e-12),
    0 elsewhere and when E = 0.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.warps import projected_triangle_density, projected_triangle_setup
    >>> s = projected_triangle_setup(np.eye(3), np.array([0, 0, 1.0]))   # an octant: E = pi / 4
    >>> bool(np.isclose(projected_triangle_density(0.0, 0.0, 1.0, s), 4 / np.pi))
    True
    >>> projected_triangle_density(0.0, 0.0, -1.0, s)
    0.0
    """
    if not s[_E] > 0.0:
        return 0.0
    lx, ly, lz = _local(s, x, y, z)
    if not lz > 0.0:
        return 0.0
    for i in range(3):
        if s[_M + 3 * i] * lx + s[_M + 3 * i + 1] * ly + s[_M + 3 * i + 2] * lz < -1e-12:
            return 0.0
    density: float = lz / math.sqrt(lx * lx + ly * ly + lz * lz) / s[_E]
    return density


# --- the numpy forms -----------------------------------------------------------------------------


@njit(cache=True, error_model="numpy")
def _setup_kernel(verts: Any, normal: Any) -> Any:  # pragma: no cover - compiled
    return projected_triangle_setup(verts, normal)


@njit(cache=True, error_model="numpy")
def _forward_kernel(uv: Any, s: Any, out: Any) -> None:  # pragma: no cover - compiled
    for i in range(uv.shape[0]):
        x, y, z, _ = projected_triangle_point(uv[i, 0], uv[i, 1], s)
        out[i, 0], out[i, 1], out[i, 2] = x, y, z


@njit(cache=True, error_model="numpy")
def _inverse_kernel(d: Any, s: Any, out: Any) -> None:  # pragma: no cover - compiled
    for i in range(d.shape[0]):
        u, v = projected_triangle_uv(d[i, 0], d[i, 1], d[i, 2], s)
        out[i, 0], out[i, 1] = u, v


@njit(cache=True, error_model="numpy")
def _density_kernel(d: Any, s: Any, out: Any) -> None:  # pragma: no cover - compiled
    for i in range(d.shape[0]):
        out[i] = projected_triangle_density(d[i, 0], d[i, 1], d[i, 2], s)


def _setup(a: npt.ArrayLike, b: npt.ArrayLike, c: npt.ArrayLike, n: npt.ArrayLike) -> Float64Array:
    verts = np.ascontiguousarray(check_triangle(a, b, c))
    if n is None:
        raise TypeError("'n' must be a 3-vector (the normal), got None")
    normal = check_normal(n, "n")
    setup: Float64Array = _setup_kernel(verts, np.ascontiguousarray(normal))
    return setup


def _checked_setup(a: npt.ArrayLike, b: npt.ArrayLike, c: npt.ArrayLike, n: npt.ArrayLike) -> Float64Array:
    s = _setup(a, b, c, n)
    if not s[_E] > 0.0:
        raise ValueError(
            "'a', 'b', 'c' must have a positive projected solid angle about 'n' "
            "(part of the triangle above the horizon of 'n', not seen edge-on)"
        )
    return s


def projected_solid_angle(a: npt.ArrayLike, b: npt.ArrayLike, c: npt.ArrayLike, n: npt.ArrayLike) -> float:
    """The projected solid angle E of the spherical triangle abc about the unit normal n.

    ``E = integral over the triangle of max(0, n.d) d(omega)``, by Lambert's formula
    ``1/2 sum gamma_i n.unit(v_i x v_i+1)`` over the part of the triangle above the horizon of n.
    The irradiance from a uniform triangle light of radiance L is L E.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.warps import projected_solid_angle
    >>> bool(np.isclose(projected_solid_angle([1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, 1]), np.pi / 4))
    True
    >>> projected_solid_angle([1, 0, -1], [0, 1, -1], [0, 0, -1], [0, 0, 1])   # below the horizon
    0.0
    """
    return float(_setup(a, b, c, n)[_E])


def square_to_projected_triangle(
    uv: npt.ArrayLike, a: npt.ArrayLike, b: npt.ArrayLike, c: npt.ArrayLike, n: npt.ArrayLike
) -> FloatArray:
    """The map of the square onto the triangle abc with density max(0, n.d) / E (projected solid angle).

    Parameters
    ----------
    uv : array_like, shape (..., 2)
    a, b, c : array_like of 3 floats
        The vertices (directions; any length), a non-degenerate triangle (smaller than a hemisphere).
    n : array_like of 3 floats
        The normal (any length; normalised here).  Some of the triangle must lie above its horizon.

    Returns
    -------
    ndarray, shape (..., 3)
        Unit directions in the part of the triangle above the horizon, with density
        :func:`square_to_projected_triangle_pdf` (float64 inside; the input's dtype out).

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.warps import projected_solid_angle, square_to_projected_triangle, square_to_projected_triangle_pdf
    >>> tri = ([1, 0, 0.2], [0, 1, 0.2], [0.3, 0.3, 1.0])
    >>> d = square_to_projected_triangle([[0.2, 0.5], [0.9, 0.1]], *tri, [0, 0, 1])
    >>> bool(np.allclose(np.linalg.norm(d, axis=1), 1))
    True
    >>> e = projected_solid_angle(*tri, [0, 0, 1])
    >>> bool(np.allclose(square_to_projected_triangle_pdf(d, *tri, [0, 0, 1]), d[:, 2] / e))
    True
    """
    uv = check_uv(uv)
    s = _checked_setup(a, b, c, n)
    flat = np.ascontiguousarray(uv.reshape(-1, 2), dtype=np.float64)
    out = np.empty((flat.shape[0], 3))
    _forward_kernel(flat, s, out)
    return out.reshape(*uv.shape[:-1], 3).astype(uv.dtype, copy=False)


def square_to_projected_triangle_pdf(
    d: npt.ArrayLike, a: npt.ArrayLike, b: npt.ArrayLike, c: npt.ArrayLike, n: npt.ArrayLike
) -> Float64Array:
    """Density of :func:`square_to_projected_triangle`: max(0, n.d) / E in the triangle, 0 elsewhere
    (and everywhere when the triangle has no part above the horizon).

    Examples
    --------
    >>> from symsphere.warps import square_to_projected_triangle_pdf
    >>> tri = ([1, 0, 0], [0, 1, 0], [0, 0, 1])
    >>> square_to_projected_triangle_pdf([[0, 0, 1], [0, 0, -1]], *tri, [0, 0, 1]) * 3.141592653589793 / 4
    array([1., 0.])
    """
    d = check_directions(d, "d")
    s = _setup(a, b, c, n)
    flat = np.ascontiguousarray(d.reshape(-1, 3), dtype=np.float64)
    out = np.empty(flat.shape[0])
    _density_kernel(flat, s, out)
    return out.reshape(d.shape[:-1])


def projected_triangle_to_square(
    d: npt.ArrayLike, a: npt.ArrayLike, b: npt.ArrayLike, c: npt.ArrayLike, n: npt.ArrayLike
) -> FloatArray:
    """Inverse of :func:`square_to_projected_triangle` (directions outside the triangle: clipped).

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.warps import projected_triangle_to_square, square_to_projected_triangle
    >>> tri = ([1, 0, 0.2], [0, 1, 0.2], [0.3, 0.3, 1.0], [0.1, 0.2, 1.0])
    >>> uv = np.array([[0.3, 0.8]])
    >>> bool(np.allclose(projected_triangle_to_square(square_to_projected_triangle(uv, *tri), *tri), uv))
    True
    """
    d = check_unit_directions(d, "d")
    s = _checked_setup(a, b, c, n)
    flat = np.ascontiguousarray(d.reshape(-1, 3), dtype=np.float64)
    out = np.empty((flat.shape[0], 2))
    _inverse_kernel(flat, s, out)
    return out.reshape(*d.shape[:-1], 2).astype(d.dtype, copy=False)


route_compiles(globals())  # the first compile of each numba function here: interruptible (_threads)
