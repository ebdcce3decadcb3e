"""Sampling a triangle light by projected solid angle, in Dr.Jit: the twin of
:mod:`symsphere.warps._projected_triangle` (numpy and numba), for ``symsphere_path``.

``square_to_projected_triangle(a, b, c, n, u) -> (d, pdf)``, ``square_to_projected_triangle_pdf(a, b, c,
n, d) -> pdf`` and ``projected_solid_angle(a, b, c, n) -> E``: *a*, *b*, *c* are the vectors from the
shading point to the triangle's vertices (``mi.Vector3f`` or ``mi.Vector3d``, any length), *n* the unit
shading normal, *u* an ``mi.Point2f``; d is a unit ``mi.Vector3f`` with density ``pdf = max(0, n.d) / E``
per unit solid angle (``mi.Float``), 0 when the triangle has no part above the horizon (below it,
degenerate, seen edge-on): then d is n and nothing is sampled.  Every lane has its own triangle; the
computation is float64 inside (as Arvo's map in :mod:`._warps`: in float32 the sector differences of a
small triangle cancel) and traceable: the branches of the numba original are ``dr.select``, its clipping
writes at most four vertices by their rank, its sort is a network, its root finder a ``dr.while_loop``.

The algorithm (see the numpy module): project onto the tangent disk, where the density is uniform in
area; each ray from the origin of azimuth phi meets the projection in [r_lo, r_hi], each bound from one
edge (``rho^2 = m_z^2 / (m_z^2 + k^2)``) or the horizon; the CDF of phi is a sum of elliptical sectors
(closed form), inverted by a bracketed Newton iteration; then r^2 is uniform in [r_lo^2, r_hi^2].
"""

from __future__ import annotations

import math
from typing import Any

import drjit as dr
import mitsuba as mi

__all__ = ["projected_solid_angle", "square_to_projected_triangle", "square_to_projected_triangle_pdf"]

_TWO_PI = 2.0 * math.pi
_TOL = 4.0 * 2.220446049250313e-16 * _TWO_PI  # the root finder's step tolerance on phi (as the numpy form)
_MAX_STEPS = 100
_CANCELLED = 1e-10  # as the numpy form: E below this fraction of Lambert's terms is rounding noise


def _cross(p: tuple[Any, Any, Any], q: tuple[Any, Any, Any]) -> tuple[Any, Any, Any]:
    return (p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0])


def _dot(p: tuple[Any, Any, Any], q: tuple[Any, Any, Any]) -> Any:
    return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]


def _select3(mask: Any, p: tuple[Any, Any, Any], q: tuple[Any, Any, Any]) -> tuple[Any, Any, Any]:
    return (dr.select(mask, p[0], q[0]), dr.select(mask, p[1], q[1]), dr.select(mask, p[2], q[2]))


def _safe(x: Any) -> Any:
    return dr.select(x > 0.0, x, 1.0)


class _Setup:
    """The per-lane constants: frame, inward edge normals, clipped polygon, E, the four pieces."""

    def __init__(self, a: Any, b: Any, c: Any, n: Any, pieces: bool) -> None:
        f = mi.Float64
        nx, ny, nz = f(n.x), f(n.y), f(n.z)
        inv_n = 1.0 / dr.sqrt(nx * nx + ny * ny + nz * nz)  # a float32 unit normal is unit to its rounding only
        nx, ny, nz = nx * inv_n, ny * inv_n, nz * inv_n
        # Duff et al. 2017's basis, as the numpy form (the same map, lane by lane)
        sign = dr.select(nz >= 0.0, f(1.0), f(-1.0))
        ia = -1.0 / (sign + nz)
        ib = nx * ny * ia
        self.t1 = (1.0 + sign * nx * nx * ia, sign * ib, -sign * nx)
        self.t2 = (ib, sign + ny * ny * ia, -ny)
        self.n = (nx, ny, nz)
        valid = dr.full(mi.Bool, True, dr.width(nx))
        v = []
        for p in (a, b, c):
            w = (f(p.x), f(p.y), f(p.z))
            x, y, z = _dot(w, self.t1), _dot(w, self.t2), _dot(w, self.n)
            length = dr.sqrt(x * x + y * y + z * z)
            valid &= length > 0.0
            inv = 1.0 / _safe(length)
            v.append((x * inv, y * inv, z * inv))
        triple = _dot(v[0], _cross(v[1], v[2]))
        valid &= (triple != 0.0) & dr.isfinite(triple)
        flip = triple < 0.0
        v[1], v[2] = _select3(flip, v[2], v[1]), _select3(flip, v[1], v[2])
        self.m = []
        for i in range(3):
            p, q = v[i], v[(i + 1) % 3]
            mm = _cross(p, (q[0] - p[0], q[1] - p[1], q[2] - p[2]))
            length = dr.sqrt(_dot(mm, mm))
            valid &= length > 0.0
            inv = 1.0 / _safe(length)
            self.m.append((mm[0] * inv, mm[1] * inv, mm[2] * inv))
        # Sutherland-Hodgman against z >= 0: candidates vertex, crossing per edge; kept ones take
        # the slot of their rank (at most four are kept)
        zero = f(0.0)
        poly = [(zero, zero, zero) for _ in range(4)]
        count = mi.UInt32(0)
        for i in range(3):
            p, q = v[i], v[(i + 1) % 3]
            above_p, above_q = p[2] >= 0.0, q[2] >= 0.0
            x, y = p[2] * q[0] - q[2] * p[0], p[2] * q[1] - q[2] * p[1]
            inv = dr.select(above_p, 1.0, -1.0) / _safe(dr.sqrt(x * x + y * y))  # (p_z q - q_z p) / (p_z - q_z)
            crossing = (x * inv, y * inv, zero)
            for keep, point in ((above_p, p), (above_p != above_q, crossing)):
                for k in range(4):
                    poly[k] = _select3(keep & (count == k), point, poly[k])
                count += dr.select(keep, 1, 0)
        valid &= count >= 3
        self.poly, self.count = poly, count
        # Lambert over the clipped polygon's edges (edge k from slot k to slot k + 1, the last back to 0)
        e, scale = f(0.0), f(0.0)
        for k in range(4):
            p = poly[k]
            q = _select3(count == k + 1, poly[0], poly[(k + 1) % 4])
            cr = _cross(p, (q[0] - p[0], q[1] - p[1], q[2] - p[2]))
            sin_g = dr.sqrt(_dot(cr, cr))
            term = 0.5 * dr.atan2(sin_g, _dot(p, q)) * cr[2] / _safe(sin_g)
            term = dr.select((k < count) & (sin_g > 0.0), term, 0.0)
            e += term
            scale += dr.abs(term)
        valid &= e > _CANCELLED * scale  # E within its rounding error of 0 (seen edge-on): nothing to sample
        self.e = dr.select(valid, e, 0.0)
        self.valid = valid
        if pieces:
            self._pieces()

    def _pieces(self) -> None:
        f = mi.Float64
        poly, count = self.poly, self.count
        self.phi0 = dr.atan2(poly[0][1], poly[0][0])
        s = []
        for k in range(4):
            d = dr.atan2(poly[k][1], poly[k][0]) - self.phi0
            d = dr.select(d < 0.0, d + _TWO_PI, d)
            d = dr.minimum(d, _TWO_PI)
            s.append(dr.select(k < count, d, _TWO_PI) if k > 0 else f(0.0))
        for i, j in ((0, 1), (2, 3), (0, 2), (1, 3), (1, 2)):  # a sorting network
            s[i], s[j] = dr.minimum(s[i], s[j]), dr.maximum(s[i], s[j])
        s.append(f(_TWO_PI))
        self.s = s
        # each piece's upper bound (an edge's normal; (0, 0, 1) is the horizon) and lower bound (an edge's
        # normal, lo_none where none), and the cumulative areas
        self.hi: list[tuple[Any, Any, Any]] = []
        self.lo: list[tuple[Any, Any, Any]] = []
        self.lo_none: list[Any] = []
        self.c = [f(0.0)]
        for j in range(4):
            mid = self.phi0 + 0.5 * (s[j] + s[j + 1])
            sm, cm = dr.sincos(mid)
            hi = (f(0.0), f(0.0), f(1.0))
            lo = (f(0.0), f(0.0), f(0.0))
            # the bounds as (m_z^2, k^2), compared by cross products (rho^2 = m_z^2 / (m_z^2 + k^2) rounds to
            # 1 for an edge within 1e-8 of the horizon): the horizon (1, 0), no lower bound (0, 1)
            mh, kh, ml, kl = f(1.0), f(0.0), f(0.0), f(1.0)
            lo_none = dr.full(mi.Bool, True, dr.width(mid))
            empty = ~self.valid
            for m in self.m:
                mz, k = m[2], m[0] * cm + m[1] * sm
                mz2, k2 = mz * mz, k * k
                upper = (mz > 0.0) & (k < 0.0) & (mz2 * kh < mh * k2)
                lower = (mz < 0.0) & (k > 0.0) & (mz2 * kl > ml * k2)
                never = ~((mz > 0.0) & (k < 0.0)) & ~((mz < 0.0) & (k > 0.0)) & ~((mz >= 0.0) & (k >= 0.0))
                never |= (mz == 0.0) & (k == 0.0)
                hi, mh, kh = _select3(upper, m, hi), dr.select(upper, mz2, mh), dr.select(upper, k2, kh)
                lo, ml, kl = _select3(lower, m, lo), dr.select(lower, mz2, ml), dr.select(lower, k2, kl)
                lo_none &= ~lower
                empty |= never
            self.hi.append(hi)
            self.lo.append(lo)
            self.lo_none.append(lo_none)
            nonempty = ~empty & (mh * kl > ml * kh) & (s[j + 1] > s[j])
            area = _piece_area(self.phi0 + s[j], self.phi0 + s[j + 1], hi, lo, lo_none)
            self.c.append(self.c[j] + dr.select(nonempty, dr.maximum(area, 0.0), 0.0))

    def to_world(self, x: Any, y: Any, z: Any) -> Any:
        return mi.Vector3d(
            x * self.t1[0] + y * self.t2[0] + z * self.n[0],
            x * self.t1[1] + y * self.t2[1] + z * self.n[1],
            x * self.t1[2] + y * self.t2[2] + z * self.n[2],
        )


def _sector(phi_a: Any, phi_b: Any, m: tuple[Any, Any, Any]) -> Any:
    """Area of the projection of the great circle m's sector between azimuths phi_a <= phi_b (the horizon
    is m = (0, 0, 1), at most pi wide here): |m_z| / 2 times the arc between its points there."""
    az = dr.abs(m[2])
    sa, ca = dr.sincos(phi_a)
    sb, cb = dr.sincos(phi_b)
    ka, kb = dr.abs(m[0] * ca + m[1] * sa), dr.abs(m[0] * cb + m[1] * sb)
    wa, wb = (az * ca, az * sa, ka), (az * cb, az * sb, kb)
    cr = _cross(wa, wb)
    return 0.5 * az * dr.atan2(dr.sqrt(_dot(cr, cr)), _dot(wa, wb))


def _piece_area(phi_a: Any, phi: Any, hi: Any, lo: Any, lo_none: Any) -> Any:
    return _sector(phi_a, phi, hi) - dr.select(lo_none, 0.0, _sector(phi_a, phi, lo))


def _bounds(phi: Any, hi: Any, lo: Any, lo_none: Any) -> tuple[Any, Any, Any, Any]:
    """(rho_hi^2, z_hi^2, rho_lo^2, z_lo^2) at azimuth phi."""
    sn, cs = dr.sincos(phi)
    out = []
    for m in (hi, lo):
        mz, k = m[2], m[0] * cs + m[1] * sn
        inv = 1.0 / _safe(mz * mz + k * k)
        out += [mz * mz * inv, k * k * inv]
    return out[0], out[1], dr.select(lo_none, 0.0, out[2]), dr.select(lo_none, 1.0, out[3])


def _pick(index: Any, values: list[Any]) -> Any:
    out = values[0]
    for j in range(1, len(values)):
        out = dr.select(index == j, values[j], out)
    return out


def _pick3(index: Any, values: list[tuple[Any, Any, Any]]) -> tuple[Any, Any, Any]:
    return (_pick(index, [v[0] for v in values]), _pick(index, [v[1] for v in values]),
            _pick(index, [v[2] for v in values]))  # fmt: skip


def projected_solid_angle(a: Any, b: Any, c: Any, n: Any) -> Any:
    """The projected solid angle E of the triangle (vectors a, b, c from the shading point) about the unit
    normal n, ``mi.Float``: Lambert's formula over its part above the horizon; 0 when there is none
    (``symsphere.warps.projected_solid_angle`` restated)."""
    return mi.Float(_Setup(a, b, c, n, pieces=False).e)


def square_to_projected_triangle(a: Any, b: Any, c: Any, n: Any, u: Any) -> tuple[Any, Any]:
    """(d, pdf): a direction with density ``max(0, n.d) / E`` on the triangle and that density (``mi.Float``;
    0 and d = n when E = 0); ``symsphere.warps.square_to_projected_triangle`` restated lane by lane."""
    f = mi.Float64
    st = _Setup(a, b, c, n, pieces=True)
    total = st.c[4]
    target = f(u.x) * total
    nonempty = [st.c[j + 1] > st.c[j] for j in range(4)]
    j = mi.UInt32(0)
    for jj in (1, 2, 3):  # the last non-empty piece
        j = dr.select(nonempty[jj], jj, j)
    for jj in (3, 2, 1, 0):  # the first non-empty piece whose end reaches the target
        j = dr.select(nonempty[jj] & (target <= st.c[jj + 1]), jj, j)
    c0, c1 = _pick(j, st.c[:4]), _pick(j, st.c[1:])
    area = c1 - c0
    tau = dr.minimum(dr.maximum(target - c0, 0.0), area)
    s0, s1 = _pick(j, st.s[:4]), _pick(j, st.s[1:])
    hi, lo, lo_none = _pick3(j, st.hi), _pick3(j, st.lo), _pick(j, st.lo_none)
    phi_a = st.phi0 + s0
    x = s0 + (s1 - s0) * (tau / _safe(area))

    def cond(x: Any, lo_b: Any, hi_b: Any, step: Any, done: Any) -> Any:
        return ~done & (step < _MAX_STEPS)

    def body(x: Any, lo_b: Any, hi_b: Any, step: Any, done: Any) -> tuple[Any, Any, Any, Any, Any]:
        g = _piece_area(phi_a, st.phi0 + x, hi, lo, lo_none) - tau
        hit = g == 0.0
        hi_b = dr.select(g > 0.0, x, hi_b)
        lo_b = dr.select(g < 0.0, x, lo_b)
        rh, _, rl, _ = _bounds(st.phi0 + x, hi, lo, lo_none)
        slope = 0.5 * (rh - rl)
        xn = x - g / _safe(slope)
        bisect = ~(slope > 0.0) | (xn <= lo_b) | (xn >= hi_b)
        xn = dr.select(bisect, 0.5 * (lo_b + hi_b), xn)
        xn = dr.select(hit, x, xn)
        done = hit | (dr.abs(xn - x) <= _TOL) | (hi_b - lo_b <= _TOL)
        return xn, lo_b, hi_b, step + 1, done

    x, _, _, _, _ = dr.while_loop(
        state=(x, f(s0), f(s1), mi.UInt32(0), ~st.valid | ~(area > 0.0)), cond=cond, body=body
    )
    phi = st.phi0 + x
    rh, zh, rl, zl = _bounds(phi, hi, lo, lo_none)
    v = f(u.y)
    r2 = dr.maximum(rl + v * (rh - rl), 0.0)
    z2 = dr.maximum(zl - v * (zl - zh), 0.0)
    r, z = dr.sqrt(r2), dr.sqrt(z2)
    inv = 1.0 / _safe(dr.sqrt(r2 + z2))
    sp, cp = dr.sincos(phi)
    lz = z * inv
    d = st.to_world(r * cp * inv, r * sp * inv, lz)
    ok = st.valid & (total > 0.0)
    pdf = dr.select(ok, lz / _safe(st.e), 0.0)
    return mi.Vector3f(dr.select(ok, d, mi.Vector3d(*st.n))), mi.Float(pdf)


def square_to_projected_triangle_pdf(a: Any, b: Any, c: Any, n: Any, d: Any) -> Any:
    """The density ``max(0, n.d) / E`` at the unit direction d inside the triangle (each edge's plane within
    1e-12), 0 elsewhere and when E = 0 (``mi.Float``); ``symsphere.warps.square_to_projected_triangle_pdf``."""
    f = mi.Float64
    st = _Setup(a, b, c, n, pieces=False)
    w = (f(d.x), f(d.y), f(d.z))
    lx, ly, lz = _dot(w, st.t1), _dot(w, st.t2), _dot(w, st.n)
    inside = st.valid & (lz > 0.0)
    for m in st.m:
        inside &= m[0] * lx + m[1] * ly + m[2] * lz >= -1e-12
    length = dr.sqrt(lx * lx + ly * ly + lz * lz)
    return mi.Float(dr.select(inside, lz / _safe(length) / _safe(st.e), 0.0))
