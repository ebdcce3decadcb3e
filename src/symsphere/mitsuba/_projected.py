"""Sampling a triangle light by projected solid angle, in Dr.Jit: the twin of
:mod:`symsphere.warps._projected_triangle` (numpy and numba), for ``symsphere_path``.

``square_to_projected_triangle(a, b, c, n, u) -> (d, pdf)``, ``square_to_projected_triangle_pdf(a, b, c,
n, d) -> pdf`` and ``projected_solid_angle(a, b, c, n) -> E``: *a*, *b*, *c* are the vectors from the
shading point to the triangle's vertices (``mi.Vector3f`` or ``mi.Vector3d``, any length), *n* the unit
shading normal, *u* a point of the square; d is a unit vector with density ``pdf = max(0, n.d) / E`` per
unit solid angle, 0 when the triangle has no part above the horizon (below it, degenerate, seen edge-on):
then d is n and nothing is sampled.  Every lane has its own triangle.  **Each function computes in the
precision of a** (float32 for ``mi.Vector3f``, float64 for ``mi.Vector3d``; n, u and d are converted to
it) and returns that precision.  The code is traceable: the branches of the numba original are
``dr.select``, its clipping writes at most four vertices by their rank, its sort is a network, its root
finder a ``dr.while_loop``.

The algorithm (see the numpy module): project onto the tangent disk, where the density is uniform in
area; each ray from the origin of azimuth phi meets the projection in [r_lo, r_hi], each bound from one
edge (``rho^2 = m_z^2 / (m_z^2 + k^2)``) or the horizon; the CDF of phi is a sum of elliptical sectors
(closed form), inverted by a bracketed Halley iteration; then r^2 is uniform in [r_lo^2, r_hi^2].  The
azimuths enter as unit vectors of the tangent plane (a piece's ends are its vertices' directions, its
middle the bisector; the iterate is the start rotated by x), so the setup evaluates no sine or cosine and
each step one sincos and two atan2.  The start is the inverse of a quadratic CDF with the piece's slopes
at its ends (exact where the width of the projection is linear in phi, and a square root where a piece
starts at a vertex, whose width starts at 0); Halley's step (the slope's derivative is rational in the
azimuth's vector), Newton's where it leaves the bracket, bisection where that does; a lane stops once
the CDF's residual is at its rounding level: 2.6 steps per lane on average in float32, 3.5 in float64
(``benchmarks/projected_cost.py``'s triangles).

What float32 loses (tests/mitsuba/test_projected.py): E and the CDF are sums that cancel for a triangle
thin in the projection (near the horizon, or seen nearly edge-on: terms large against their sum), so
they carry the terms' rounding, eps32 times their sum.  In float32, E is the projection's flat
(shoelace) area, which does not cancel, plus the arcs' segments (Lambert's terms times gamma / sin gamma
- 1, ~ gamma^2 / 6 of them): within 1.1e-4 relative of float64 on the tests' random triangles, where
Lambert's sum as such lost 1.6e-3.  The CDF's sector differences move a sample along the azimuth by up to
5e-4 rad there (a jitter at the CDF's rounding level, in the thinnest
projections; Mitsuba's chi^2 test passes in both precisions); the pdf is that of the direction returned, so the estimator's variance
stays at rounding level.  A triangle whose E is within 1e-6 of the sum of Lambert's terms (float64:
1e-10) is rounding noise and counts as empty.

``emitter_sampling='cosine'`` (:func:`cosine_table_sample`) takes the light table's cheap choice and
samples inside the chosen triangle near the cosine: by this map only where the triangle is large as seen
from the point (:data:`HUGE_ABOVE`), else by Arvo's map warped bilinearly by the cosine at the vertices
(:func:`square_to_cosine_spherical_triangle`), or by area where small.
"""

from __future__ import annotations

import math
from typing import Any

import drjit as dr
import mitsuba as mi

from ._light_rows import pick, small_triangle
from ._warps import square_to_spherical_triangle

__all__ = ["HUGE_ABOVE", "choose_projected", "cosine_table_sample", "projected_solid_angle", "square_to_cosine_spherical_triangle",
           "square_to_projected_triangle", "square_to_projected_triangle_pdf"]  # fmt: skip

_TWO_PI = 2.0 * math.pi
_EPS = {False: 2.0**-23, True: 2.0**-52}  # float32, float64 epsilon
_MAX_STEPS = {False: 40, True: 100}  # bisection alone needs 26 (float32), 54 (float64) halvings of 2 pi
_CANCELLED = {False: 1e-6, True: 1e-10}  # E below this fraction of Lambert's terms is rounding noise
_SMALLEST = {False: 1e-30, True: 1e-300}  # and below this (absolute): so that 1 / E is finite
_PLANE = {False: 2.0**-24, True: 1e-12}  # the pdf's slack at each edge's plane


def _cross(p: tuple[Any, Any, Any], q: tuple[Any, Any, Any]) -> tuple[Any, Any, Any]:
    return (p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0])


def _dot(p: tuple[Any, Any, Any], q: tuple[Any, Any, Any]) -> Any:
    return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]


def _select3(mask: Any, p: tuple[Any, Any, Any], q: tuple[Any, Any, Any]) -> tuple[Any, Any, Any]:
    return (dr.select(mask, p[0], q[0]), dr.select(mask, p[1], q[1]), dr.select(mask, p[2], q[2]))


def _safe(x: Any) -> Any:
    return dr.select(x > 0.0, x, 1.0)


def _is64(a: Any) -> bool:
    return bool(dr.type_v(a) == dr.VarType.Float64)


class _Setup:
    """The per-lane constants: frame, inward edge normals, clipped polygon, E, the four pieces."""

    def __init__(self, a: Any, b: Any, c: Any, n: Any, edges: bool, pieces: bool) -> None:
        self.is64 = is64 = _is64(a)
        f: Any = mi.Float64 if is64 else mi.Float
        self.f = f
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
            length2 = x * x + y * y + z * z
            valid &= length2 > 0.0
            inv = dr.rsqrt(_safe(length2))
            v.append((x * inv, y * inv, z * inv))
        triple = _dot(v[0], _cross(v[1], v[2]))
        valid &= (triple != 0.0) & dr.isfinite(triple)
        flip = triple < 0.0
        v[1], v[2] = _select3(flip, v[2], v[1]), _select3(flip, v[1], v[2])
        self.m = []
        for i in range(3 if edges or pieces else 0):  # E alone needs no edge normals
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
        # Lambert over the clipped polygon's edges (edge k from slot k to slot k + 1, the last back to 0),
        # 1/2 sum gamma_k (p_k x q_k)_z / sin gamma_k.  In float32 its terms' rounding (eps32 times their sum,
        # which is large against E for a triangle thin in the projection) is most of E's error; there it is
        # the flat part, 1/2 sum (p_k x q_k)_z (the projected polygon's shoelace area, by its diagonals: no
        # cancellation), plus 1/2 sum (p_k x q_k)_z (gamma_k / sin gamma_k - 1), terms ~ gamma^2 / 6 smaller.
        e, scale = f(0.0), f(0.0)
        if not is64:
            q3 = _select3(count == 4, poly[3], poly[0])
            d0, d1 = (poly[2][0] - poly[0][0], poly[2][1] - poly[0][1]), (q3[0] - poly[1][0], q3[1] - poly[1][1])
            e = 0.5 * (d0[0] * d1[1] - d0[1] * d1[0])
        for k in range(4):
            p = poly[k]
            q = _select3(count == k + 1, poly[0], poly[(k + 1) % 4])
            cr = _cross(p, (q[0] - p[0], q[1] - p[1], q[2] - p[2]))
            sin_g = dr.sqrt(_dot(cr, cr))
            gamma = dr.atan2(sin_g, _dot(p, q))
            ok = (k < count) & (sin_g > 0.0)
            inv_sin = 1.0 / _safe(sin_g)
            term = 0.5 * gamma * cr[2] * inv_sin
            if is64:
                e += dr.select(ok, term, 0.0)
            else:
                g2 = gamma * gamma  # gamma / sin gamma - 1 by its series below 0.5 (to 1e-6 of itself)
                excess = dr.select(
                    gamma < 0.5,
                    g2 * (1.0 / 6.0 + g2 * (7.0 / 360.0 + g2 * (31.0 / 15120.0))),
                    (gamma - sin_g) * inv_sin,
                )
                e += dr.select(ok, 0.5 * cr[2] * excess, 0.0)
            scale += dr.select(ok, dr.abs(term), 0.0)
        # E within its rounding error of 0 (seen edge-on): nothing to sample
        valid &= (e > _CANCELLED[is64] * scale) & (e > _SMALLEST[is64])
        self.e = dr.select(valid, e, 0.0)
        self.valid = valid
        if pieces:
            self._pieces()

    def _pieces(self) -> None:
        f = self.f
        poly, count = self.poly, self.count
        # each slot's azimuth as a unit vector of the tangent plane ((1, 0) at the pole, as atan2(0, 0))
        # and its sort key, a pseudo-angle from slot 0's in [0, 4) (monotone in the angle, no atan2)
        dirs = []
        for k in range(4):
            x, y = poly[k][0], poly[k][1]
            r = dr.sqrt(x * x + y * y)
            inv = 1.0 / _safe(r)
            dirs.append((dr.select(r > 0.0, x * inv, 1.0), y * inv))
        s = [f(0.0)]
        e0 = dirs[0]
        for k in range(1, 4):
            cs, sn = e0[0] * dirs[k][0] + e0[1] * dirs[k][1], e0[0] * dirs[k][1] - e0[1] * dirs[k][0]
            ac, asn = dr.abs(cs), dr.abs(sn)
            t = asn / _safe(ac + asn)  # in [0, 1] within the quadrant
            key = dr.select(sn >= 0.0, dr.select(cs >= 0.0, t, 2.0 - t), dr.select(cs < 0.0, 2.0 + t, 4.0 - t))
            unused = k >= count
            s.append(dr.select(unused, 4.0, dr.minimum(key, 4.0)))
            dirs[k] = (dr.select(unused, e0[0], dirs[k][0]), dr.select(unused, e0[1], dirs[k][1]))
        for i, j in ((0, 1), (2, 3), (0, 2), (1, 3), (1, 2)):  # a sorting network, the directions along
            swap = s[j] < s[i]
            s[i], s[j] = dr.select(swap, s[j], s[i]), dr.select(swap, s[i], s[j])
            di, dj = dirs[i], dirs[j]
            dirs[i] = (dr.select(swap, dj[0], di[0]), dr.select(swap, dj[1], di[1]))
            dirs[j] = (dr.select(swap, di[0], dj[0]), dr.select(swap, di[1], dj[1]))
        s.append(f(4.0))
        dirs.append(e0)
        self.s, self.dirs = s, dirs
        # each piece's upper bound (an edge's normal; (0, 0, 1) is the horizon) and lower bound (an edge's
        # normal, lo_none where none), and the cumulative areas
        self.hi: list[tuple[Any, Any, Any]] = []
        self.lo: list[tuple[Any, Any, Any]] = []
        self.lo_none: list[Any] = []
        self.c = [f(0.0)]
        for j in range(4):
            ea, eb = dirs[j], dirs[j + 1]
            # the bisector of the piece (unnormalised, any width below 2 pi): rot90(ea - eb)
            cm, sm = eb[1] - ea[1], ea[0] - eb[0]
            hi = (f(0.0), f(0.0), f(1.0))
            lo = (f(0.0), f(0.0), f(0.0))
            # the bounds as (m_z^2, k^2), compared by cross products (rho^2 = m_z^2 / (m_z^2 + k^2) rounds to
            # 1 for an edge within 1e-8 of the horizon): the horizon (1, 0), no lower bound (0, 1)
            mh, kh, ml, kl = f(1.0), f(0.0), f(0.0), f(1.0)
            lo_none = dr.full(mi.Bool, True, dr.width(cm))
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
            area = _sector(_arc_point(ea, hi), eb, hi) - dr.select(lo_none, 0.0, _sector(_arc_point(ea, lo), eb, lo))
            self.c.append(self.c[j] + dr.select(nonempty, dr.maximum(area, 0.0), 0.0))

    def to_world(self, x: Any, y: Any, z: Any) -> tuple[Any, Any, Any]:
        return (
            x * self.t1[0] + y * self.t2[0] + z * self.n[0],
            x * self.t1[1] + y * self.t2[1] + z * self.n[1],
            x * self.t1[2] + y * self.t2[2] + z * self.n[2],
        )


def _arc_point(e: tuple[Any, Any], m: tuple[Any, Any, Any]) -> tuple[Any, Any, Any]:
    """The point (unnormalised) of the great circle m in the azimuth of the unit vector e (m_z != 0; the
    horizon's is e itself)."""
    az = dr.abs(m[2])
    return (az * e[0], az * e[1], dr.abs(m[0] * e[0] + m[1] * e[1]))


def _sector(wa: tuple[Any, Any, Any], eb: tuple[Any, Any], m: tuple[Any, Any, Any]) -> Any:
    """Area of the projection of the great circle m's sector from its point wa (:func:`_arc_point`) to the
    azimuth eb (at most pi wide here): |m_z| / 2 times the arc between its points there."""
    wb = _arc_point(eb, m)
    cr = _cross(wa, wb)
    return 0.5 * dr.abs(m[2]) * dr.atan2(dr.sqrt(_dot(cr, cr)), _dot(wa, wb))


def _bounds(e: tuple[Any, Any], hi: Any, lo: Any, lo_none: Any) -> tuple[Any, Any, Any, Any]:
    """(rho_hi^2, z_hi^2, rho_lo^2, z_lo^2) in the azimuth of the unit vector e."""
    out = []
    for m in (hi, lo):
        mz, k = m[2], m[0] * e[0] + m[1] * e[1]
        inv = 1.0 / _safe(mz * mz + k * k)
        out += [mz * mz * inv, k * k * inv]
    return out[0], out[1], dr.select(lo_none, 0.0, out[2]), dr.select(lo_none, 1.0, out[3])


def _width(e: tuple[Any, Any], hi: Any, lo: Any, lo_none: Any) -> tuple[Any, Any]:
    """The CDF's slope (rho_hi^2 - rho_lo^2) / 2 in the azimuth of the unit vector e, and its derivative by
    the azimuth (d rho^2 = -2 rho^2 k k' / (m_z^2 + k^2), k' = m . e_perp)."""
    out = []
    for m in (hi, lo):
        mz2, k, dk = m[2] * m[2], m[0] * e[0] + m[1] * e[1], m[1] * e[0] - m[0] * e[1]
        inv = 1.0 / _safe(mz2 + k * k)
        rho2 = mz2 * inv
        out += [rho2, -2.0 * rho2 * k * dk * inv]
    return 0.5 * (out[0] - dr.select(lo_none, 0.0, out[2])), 0.5 * (out[1] - dr.select(lo_none, 0.0, out[3]))


def _pick(index: Any, values: list[Any]) -> Any:
    out = values[0]
    for j in range(1, len(values)):
        out = dr.select(index == j, values[j], out)
    return out


def _pick_n(index: Any, values: list[tuple[Any, ...]]) -> tuple[Any, ...]:
    return tuple(_pick(index, [v[i] for v in values]) for i in range(len(values[0])))


def projected_solid_angle(a: Any, b: Any, c: Any, n: Any) -> Any:
    """The projected solid angle E of the triangle (vectors a, b, c from the shading point) about the unit
    normal n, in a's precision: Lambert's formula over its part above the horizon; 0 when there is none
    (``symsphere.warps.projected_solid_angle`` restated)."""
    return _Setup(a, b, c, n, edges=False, pieces=False).e


def _initial(tau: Any, area: Any, width: Any, d0: Any, d1: Any) -> Any:
    """The start of the root finder in [0, width]: the inverse of the quadratic CDF with the slopes d0, d1
    at the piece's ends, scaled to its area (a = 2 d0 / (d0 + d1), y = a t + (1 - a) t^2)."""
    y = dr.clip(tau / _safe(area), 0.0, 1.0)
    sum_d = d0 + d1
    a = dr.select(sum_d > 0.0, 2.0 * d0 / _safe(sum_d), 1.0)
    root = dr.sqrt(dr.maximum(a * a + 4.0 * (1.0 - a) * y, 0.0))
    t = 2.0 * y / _safe(a + root)  # the stable root of (1 - a) t^2 + a t - y = 0
    return width * dr.clip(t, 0.0, 1.0)


def square_to_projected_triangle(a: Any, b: Any, c: Any, n: Any, u: Any) -> tuple[Any, Any]:
    """(d, pdf): a direction with density ``max(0, n.d) / E`` on the triangle and that density, in a's
    precision (d = n and pdf = 0 when E = 0); ``symsphere.warps.square_to_projected_triangle`` restated
    lane by lane."""
    st = _Setup(a, b, c, n, edges=True, pieces=True)
    f, is64 = st.f, st.is64
    eps = _EPS[is64]
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
    ea, eb = _pick_n(j, st.dirs[:4]), _pick_n(j, st.dirs[1:])
    hi, lo, lo_none = _pick_n(j, st.hi), _pick_n(j, st.lo), _pick(j, st.lo_none)
    wa_hi, wa_lo = _arc_point(ea, hi), _arc_point(ea, lo)
    # the piece's width in radians (below 2 pi; a non-empty piece is at most pi wide)
    width = dr.atan2(ea[0] * eb[1] - ea[1] * eb[0], ea[0] * eb[0] + ea[1] * eb[1])
    width = dr.select(width < 0.0, width + _TWO_PI, width)
    width = dr.select(s1 > s0, width, 0.0)
    rh, _, rl, _ = _bounds(ea, hi, lo, lo_none)
    rh1, _, rl1, _ = _bounds(eb, hi, lo, lo_none)
    x = _initial(tau, area, width, 0.5 * (rh - rl), 0.5 * (rh1 - rl1))
    tol = 4.0 * eps * _TWO_PI

    def rotated(x: Any) -> tuple[Any, Any]:
        sx, cx = dr.sincos(x)
        return (ea[0] * cx - ea[1] * sx, ea[1] * cx + ea[0] * sx)

    def cond(x: Any, lo_b: Any, hi_b: Any, step: Any, done: Any) -> Any:
        return ~done & (step < _MAX_STEPS[is64])

    def body(x: Any, lo_b: Any, hi_b: Any, step: Any, done: Any) -> tuple[Any, Any, Any, Any, Any]:
        e = rotated(x)
        upper = _sector(wa_hi, e, hi)
        lower = dr.select(lo_none, 0.0, _sector(wa_lo, e, lo))
        g = upper - lower - tau
        settled = dr.abs(g) <= 1.0 * eps * (upper + lower + tau)  # the residual is rounding noise
        hi_b = dr.select(g > 0.0, x, hi_b)
        lo_b = dr.select(g < 0.0, x, lo_b)
        slope, curve = _width(e, hi, lo, lo_none)
        newton = x - g / _safe(slope)
        # Halley's step (cubic convergence), Newton's where it leaves the bracket
        den = 2.0 * slope * slope - g * curve
        xn = x - 2.0 * g * slope / _safe(den)
        xn = dr.select((den > 0.0) & (xn > lo_b) & (xn < hi_b), xn, newton)
        bisect = ~(slope > 0.0) | (xn <= lo_b) | (xn >= hi_b)
        # settled: the Newton step if it stays in the bracket, else x (a bisection would leave the root)
        xn = dr.select(bisect, dr.select(settled, x, 0.5 * (lo_b + hi_b)), xn)
        done = settled | (dr.abs(xn - x) <= tol) | (hi_b - lo_b <= tol)
        return xn, lo_b, hi_b, step + 1, done

    x, _, _, _, _ = dr.while_loop(
        state=(x, f(0.0), f(width), mi.UInt32(0), ~st.valid | ~(area > 0.0)), cond=cond, body=body
    )
    e = rotated(x)
    rh, zh, rl, zl = _bounds(e, hi, lo, lo_none)
    v = f(u.y)
    r2 = dr.maximum(rl + v * (rh - rl), 0.0)
    z2 = dr.maximum(zl - v * (zl - zh), 0.0)
    r, z = dr.sqrt(r2), dr.sqrt(z2)
    inv = 1.0 / _safe(dr.sqrt(r2 + z2))
    lz = z * inv
    ok = st.valid & (total > 0.0)
    d = _select3(ok, st.to_world(r * e[0] * inv, r * e[1] * inv, lz), st.n)
    pdf = dr.select(ok, lz / _safe(st.e), 0.0)
    vector = mi.Vector3d if is64 else mi.Vector3f
    return vector(*d), pdf


def square_to_projected_triangle_pdf(a: Any, b: Any, c: Any, n: Any, d: Any) -> Any:
    """The density ``max(0, n.d) / E`` at the unit direction d inside the triangle (each edge's plane within
    1e-12; float32 2^-24), 0 elsewhere and when E = 0, in a's precision;
    ``symsphere.warps.square_to_projected_triangle_pdf``."""
    st = _Setup(a, b, c, n, edges=True, pieces=False)
    f = st.f
    w = (f(d.x), f(d.y), f(d.z))
    lx, ly, lz = _dot(w, st.t1), _dot(w, st.t2), _dot(w, st.n)
    inside = st.valid & (lz > 0.0)
    for m in st.m:
        inside &= m[0] * lx + m[1] * ly + m[2] * lz >= -_PLANE[st.is64]
    length = dr.sqrt(lx * lx + ly * ly + lz * lz)
    return dr.select(inside, lz / _safe(length) / _safe(st.e), 0.0)


# --- emitter_sampling='cosine': the light table's choice, then a cosine-aware direction in the triangle ---

HUGE_ABOVE = 1.5
"""``emitter_sampling='cosine'``: a chosen triangle whose bounding radius (about its centroid) is at least
this times the centroid's distance is sampled by projected solid angle; a smaller one (down to the light
table's ``AREA_BELOW``, where it is sampled by area) by Arvo's map warped bilinearly by the cosine."""


def _sample_linear(u: Any, a: Any, b: Any) -> Any:
    """x in [0, 1) with density proportional to (1 - x) a + x b (a, b >= 0, not both 0), by u."""
    den = a + dr.sqrt(dr.maximum(dr.lerp(a * a, b * b, u), 0.0))
    return dr.minimum(u * (a + b) / _safe(den), 1.0 - 2.0**-24)


def square_to_cosine_spherical_triangle(a: Any, b: Any, c: Any, n: Any, u: Any) -> tuple[Any, Any]:
    """(d, 1 / density): Arvo's map of a point of the square drawn with the bilinear density whose corners
    are ``max(n.v, 0.01)`` at the vertices the map sends them to (B, B, A, C), so the density in solid angle
    is ``bilinear(u) / Omega`` (Hart et al. 2020; pbrt-v4's ``TriangleLight::SampleLi``): cheap (a few
    operations on top of the map), and near the cosine where it varies little over the triangle.  a, b, c
    from the shading point (float32), n the unit shading normal; 0 for a degenerate triangle."""
    cosines = [dr.dot(n, dr.normalize(v)) for v in (a, b, c)]
    wa, wb, wc = (dr.select(w > 0.01, w, 0.01) for w in cosines)  # 0.01 for NaN too (a vertex at p)
    y = _sample_linear(u[1], wb + wb, wa + wc)
    x = _sample_linear(u[0], dr.lerp(wb, wa, y), dr.lerp(wb, wc, y))
    square = 4.0 * ((1.0 - y) * wb + y * ((1.0 - x) * wa + x * wc)) / (wb + wb + wa + wc)
    d, omega = square_to_spherical_triangle((x, y), a, b, c)
    return dr.normalize(d), dr.select(omega > 0.0, omega / square, 0.0)


def choose_projected(table: Any, p: Any, normal: Any, u: Any, active: Any, n: Any = None) -> tuple[Any, Any, Any]:
    """``emitter_sampling='projected'``'s choice in *table* (a ``LightTable``): (row, its probability, u
    reused), as ``LightTable.choose``, with each triangle's weight its projected solid angle about
    *normal* x radiance (0 behind it: the levels above are ``choose``'s, whose estimates are 0 only where
    no member faces p)."""
    if table.mode == "exact":
        weights: list[Any] = []
        for row in range(table.count):
            if table.lum[row] <= 0.0:
                weights.append(None)
                continue
            a, b, c = (mi.ScalarVector3f(*vertex) for vertex in table.tris[row])
            front = dr.dot(p - a, mi.ScalarVector3f(*table.normal[row])) > 0.0
            e = projected_solid_angle(a - p, b - p, c - p, normal)
            weights.append(dr.select(front, e * float(table.lum[row]), 0.0))
        return pick(weights, u)
    leaf, probability, u = table.descend(p, u, active, n)
    start = leaf * table.group_size
    members = []
    for k in range(table.group_size):
        row = start + k
        ok = active & (row < table.count) & (probability > 0.0)
        a, b, c, n = table.vertices(row, ok)
        lum = table.luminance(row, ok)
        e = projected_solid_angle(a - p, b - p, c - p, normal)
        members.append(dr.select(ok & (dr.dot(p - a, n) > 0.0) & (lum > 0.0), e * lum, 0.0))
    slot, fraction, u = pick(members, u)
    probability *= fraction
    return start + slot, probability, u


def cosine_table_sample(table: Any, si: Any, p: Any, u: Any, v: Any, active: Any, cosine: Any) -> tuple[Any, ...]:
    """``emitter_sampling='cosine'``'s half of ``LightTable._sample_table``: (row, valid lanes, a, b, c,
    the triangle's normal, density, direction).  One choice for every lane, the table's (solid angle x
    radiance x the receiver's cosine, about the shading normal at the lanes *cosine*, Lambertian
    vertices; the geometric one elsewhere); then a direction in the chosen triangle: by area where it is
    small as seen from p (as ``solid_angle``), by Arvo's map at the other lanes, and at the lanes *cosine*
    by :func:`square_to_cosine_spherical_triangle`, or by projected solid angle
    (:func:`square_to_projected_triangle`) where the triangle is large (:data:`HUGE_ABOVE`).  Each in a
    branch that a packet of lanes without it skips.  No hit needs this density (the caller weights BSDF
    hits on the table's emitters 0 at these vertices), and each lane's technique is a deterministic
    function of p, so the estimate is unbiased."""
    normal = dr.mulsign(mi.Vector3f(si.sh_frame.n), si.wi.z)
    mine = active & cosine if cosine is not None else mi.Bool(False)

    def warp(ra: Any, rb: Any, rc: Any, uv: Any, lanes: Any, d: Any, inv: Any) -> tuple[Any, Any, Any]:
        huge = ~small_triangle(ra, rb, rc, HUGE_ABOVE)

        def warped(*_: Any) -> tuple[Any, Any]:
            return square_to_cosine_spherical_triangle(ra, rb, rc, normal, uv)

        def projected(*_: Any) -> tuple[Any, Any]:
            direction, pdf = square_to_projected_triangle(ra, rb, rc, normal, mi.Point2f(*uv))
            return direction, dr.select(pdf > 0.0, dr.rcp(_safe(pdf)), 0.0)

        for fn, where in ((warped, mine & ~huge), (projected, mine & huge)):
            d, inv = dr.if_stmt(args=(d, inv), cond=lanes & where, true_fn=fn, false_fn=lambda *x: x)
        return d, inv, lanes & ~mine

    sample: tuple[Any, ...] = table.sample_triangle(p, u, v, active, dr.select(mine, normal, mi.Vector3f(si.n)), warp)
    return sample
