"""Urena, Fajardo & King's map onto a spherical rectangle, in Dr.Jit: the twin of
:mod:`symsphere.warps._spherical_rectangle` (numpy and numba).

The triple in Mitsuba's ``warp.h`` form, with the numpy functions' parameters in their order, and the
solid angle: ``square_to_spherical_rectangle(sample, corner, edge1, edge2) -> d``,
``square_to_spherical_rectangle_pdf(v, corner, edge1, edge2) -> pdf``,
``spherical_rectangle_to_square(v, corner, edge1, edge2) -> uv`` and
``spherical_rectangle_solid_angle(corner, edge1, edge2) -> S``.  The rectangle is
``corner + s edge1 + t edge2`` (s, t in [0, 1]; the edges orthogonal, as the numpy form requires and this
one trusts), seen from the origin: *corner* is the vector from the viewer (the shading point) to a
corner.  Every lane has its own rectangle.  The direction is uniform in solid angle: pdf = 1/S towards
the rectangle, 0 elsewhere.  **Each function computes in the precision of corner** (``mi.Vector3f``:
float32, ``mi.Vector3d``: float64; the other arguments are converted to it) and returns that precision;
JIT variants (``llvm_*``, ``cuda_*``).

The formulas are :func:`symsphere.warps.rectangle_frame` and :func:`symsphere.warps.rectangle_point`,
with these changes for float32 (all but the last also run in float64):

- the coordinates in the edges' frame are divided by the largest of them (solid angle and direction do
  not change), so that products of up to eight coordinates neither overflow (float32's 3e38 is reached
  by a rectangle 5e4 away) nor underflow; edge2 is made orthogonal to edge1 (to rounding it is trusted
  to be), so that the pdf's projection agrees with the map's frame;
- the solid angle is rectangle_frame's product of complex numbers or the two triangles by Van Oosterom &
  Strackee, whichever has the smaller bound on its rounding (:func:`_solid_angle`): the product loses eps
  times (offset / size)^2 for a small rectangle far off the axis (7.7e-2 relative at 4e-8 sr in float32),
  the triangles lose where the foot of the viewer lies near one of their edges and the viewer near the
  plane;
- b0 + b1 (Urena's n0.z + n2.z), h1 - h0 (the elevation sines of the segment's ends) and k's imaginary part
  are differences of nearly equal numbers for a small rectangle off the axis: formed as the difference of
  the squares over the sum (``y1/r1 - y0/r0 = d2 (y1 - y0)(y1 + y0) / (r0 r1 (y1 r0 + y0 r1))``, y0, y1 of
  one sign); nu = cos(au) b0 - b1 as ``2 sin^2(delta/2) b0 - (b0 + b1)``, delta = au - pi;
- float32 only: one Newton step on S([x0, xu] x [y0, y1]) = u S after Urena's closed form for xu, which
  carries eps32 (x / z0)^2 into u for a rectangle seen at a grazing angle (6e-3 at x = 100 z0; 1.9e-5
  after the step), unless the step is below its own rounding.

What float32 still loses (tests/mitsuba/test_rectangle.py, against the numpy float64 map on the same
float32 inputs; bounds and measurements in its FLOAT32): the solid angle within 7.6e-7 relative (1e-7 sr
included), the sample's place in the square within ~1e-6 for rectangles of ordinary size and distance,
but a few eps32 |corner| / width for a small one far off the axis (4e-4 at 4e-8 sr, 0.86 away for a 3.2e-4
wide square: the corner's coordinates in the edges' frame are rounded to float32); a direction moves by
that times the map's stretch (<= 4.1e-6 rad in the ordinary cases tested, 0.13 rad at the horizon of a rectangle of
nearly a hemisphere, where a float32 rounding of uv is a large angle).  The sample's point is clamped
into the rectangle, so a lost digit moves it inside the rectangle, never out of it, and the pdf stays
1/S (the pdf counts directions within rounding of an edge as inside).  A rectangle whose solid angle is
not positive and finite (seen edge-on, the viewer in its plane or within 32 eps of it relative to the
largest coordinate, zero or non-finite edges) is degenerate: S and the pdf are 0, the direction is the
unit vector towards its centre (else its normal, else +z), the inverse (0, 0).
"""

from __future__ import annotations

import math
from typing import Any

import drjit as dr
import mitsuba as mi

__all__ = [
    "spherical_rectangle_solid_angle",
    "square_to_spherical_rectangle",
    "square_to_spherical_rectangle_pdf",
    "spherical_rectangle_to_square",
]

_PI = math.pi

Vec = tuple[Any, Any, Any]


def _dot(p: Vec, q: Vec) -> Any:
    return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]


def _cross(p: Vec, q: Vec) -> Vec:
    return (p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0])


def _safe(x: Any) -> Any:
    return dr.select(x > 0.0, x, 1.0)


def _clip(x: Any, lo: Any, hi: Any) -> Any:
    return dr.minimum(dr.maximum(x, lo), hi)


def _sine_difference(y0: Any, y1: Any, dy: Any, d2: Any) -> Any:
    """y1 / r1 - y0 / r0 with r = sqrt(d2 + y^2) and dy = y1 - y0 >= 0, to its relative precision.

    Of one sign, the two sines nearly cancel for a small dy: then it is d2 dy (y1 + y0) / (r0 r1 (y1 r0 + y0 r1))
    (the difference of their squares over their sum); of opposite signs, the plain difference adds magnitudes.
    """
    r0, r1 = dr.sqrt(d2 + y0 * y0), dr.sqrt(d2 + y1 * y1)
    plain = y1 / _safe(r1) - y0 / _safe(r0)
    den = r0 * r1 * (y1 * r0 + y0 * r1)
    factored = d2 * dy * (y1 + y0) / dr.select(den != 0.0, den, 1.0)
    return dr.select((y0 * y1 > 0.0) & (den != 0.0), factored, plain)


def _solid_angle(x0: Any, y0: Any, a: Any, x1: Any, y1: Any, w: Any, h: Any) -> Any:
    """S of the rectangle [x0, x1] x [y0, y1] (w = x1 - x0, h = y1 - y0) in the plane at distance a > 0.

    Two exact forms, each with a bound on its rounding, and the one whose bound is smaller:
    rectangle_frame's product of four complex numbers (its argument taken in [0, 2 pi) when the foot of
    the viewer is inside: rectangle_frame's pi + atan2(-im, -re) carries pi's rounding into a small S),
    which for a small rectangle far off the axis carries eps times the offset over the size, squared; and
    the triangles (00, 10, 11) and (00, 11, 01) by Van Oosterom & Strackee, whose triple product is a w h
    for both, exact to rounding, and whose denominators cancel when the foot lies near one of their edges
    (within a, the viewer near the plane).
    """
    z2 = a * a
    r00, r10 = dr.sqrt(x0 * x0 + y0 * y0 + z2), dr.sqrt(x1 * x1 + y0 * y0 + z2)
    r01, r11 = dr.sqrt(x0 * x0 + y1 * y1 + z2), dr.sqrt(x1 * x1 + y1 * y1 + z2)
    triple = a * w * h
    d00_10, d00_11, d00_01 = x0 * x1 + y0 * y0 + z2, x0 * x1 + y0 * y1 + z2, x0 * x0 + y0 * y1 + z2
    d10_11, d11_01 = x1 * x1 + y0 * y1 + z2, x0 * x1 + y1 * y1 + z2
    den1 = r00 * r10 * r11 + d00_10 * r11 + d00_11 * r10 + d10_11 * r00
    den2 = r00 * r11 * r01 + d00_11 * r01 + d00_01 * r11 + d11_01 * r00
    size1 = r00 * r10 * r11 + dr.abs(d00_10) * r11 + dr.abs(d00_11) * r10 + dr.abs(d10_11) * r00
    size2 = r00 * r11 * r01 + dr.abs(d00_11) * r01 + dr.abs(d00_01) * r11 + dr.abs(d11_01) * r00
    triangles = 2.0 * (dr.atan2(triple, den1) + dr.atan2(triple, den2))
    # atan2(t, d) moves by (|t| err(d) + |d| err(t)) / (t^2 + d^2), err(d) ~ eps size, err(t) ~ eps |t|
    rounding_triangles = 2.0 * triple * (size1 + dr.abs(den1)) / _safe(triple * triple + den1 * den1)
    rounding_triangles += 2.0 * triple * (size2 + dr.abs(den2)) / _safe(triple * triple + den2 * den2)
    c00, c10, c01, c11 = a * r00, a * r10, a * r01, a * r11  # e^{i A_xy} is proportional to c_xy + i x y
    s00, s10, s01, s11 = x0 * y0, x1 * y0, x0 * y1, x1 * y1
    re1, im1 = c11 * c10 + s11 * s10, s11 * c10 - c11 * s10  # A11 - A10
    re0, im0 = c00 * c01 + s00 * s01, s00 * c01 - c00 * s01  # A00 - A01
    re, im = re1 * re0 - im1 * im0, re1 * im0 + im1 * re0
    size1 = dr.abs(c11 * c10) + dr.abs(s11 * s10) + dr.abs(s11 * c10) + dr.abs(c11 * s10)
    size0 = dr.abs(c00 * c01) + dr.abs(s00 * s01) + dr.abs(s00 * c01) + dr.abs(c00 * s01)
    rounding_product = size1 * size0 * (dr.abs(re) + dr.abs(im)) / _safe(re * re + im * im)
    foot_inside = (x0 < 0.0) & (x1 > 0.0) & (y0 < 0.0) & (y1 > 0.0)
    angle = dr.atan2(im, re)
    product = dr.select(foot_inside, angle + dr.select(im < 0.0, 2.0 * _PI, 0.0 * im), dr.maximum(angle, 0.0))
    return dr.select(rounding_product <= rounding_triangles, product, triangles)


class _Frame:
    """The rectangle in the frame of its edges, scaled: :func:`symsphere.warps.rectangle_frame` per lane."""

    def __init__(self, corner: Any, edge1: Any, edge2: Any) -> None:
        is64 = bool(dr.type_v(corner.x) == dr.VarType.Float64)
        f: Any = mi.Float64 if is64 else mi.Float
        self.f, self.is64 = f, is64
        c = (f(corner.x), f(corner.y), f(corner.z))
        p1, p2 = (f(edge1.x), f(edge1.y), f(edge1.z)), (f(edge2.x), f(edge2.y), f(edge2.z))
        w = dr.sqrt(_dot(p1, p1))
        e = tuple(x / _safe(w) for x in p1)
        # edge2 made orthogonal to edge1 (Gram-Schmidt; the edges are trusted to be so, but a float32
        # rectangle is only to its rounding): the directions the map builds from this frame and the ones
        # the pdf projects onto it then agree to rounding
        along = _dot(e, p2)
        q = tuple(p2[i] - along * e[i] for i in range(3))
        h = dr.sqrt(_dot(q, q))
        g_ = tuple(x / _safe(h) for x in q)
        n = _cross(e, g_)
        self.axes = (e, g_, n)
        x0, y0, z0 = _dot(e, c), _dot(g_, c), _dot(n, c)
        zsign = dr.select(z0 > 0.0, f(-1.0), f(1.0))  # the rectangle put at z0 < 0, as rectangle_frame
        z0 = -dr.abs(z0)
        x1, y1 = x0 + w, y0 + h
        scale = dr.maximum(dr.maximum(dr.maximum(dr.abs(x0), dr.abs(x1)), dr.maximum(dr.abs(y0), dr.abs(y1))), -z0)
        inv = 1.0 / _safe(scale)
        x0, y0, z0, x1, y1, w, h = (v * inv for v in (x0, y0, z0, x1, y1, w, h))
        a = -z0
        z2 = z0 * z0
        r00, r01 = dr.sqrt(x0 * x0 + y0 * y0 + z2), dr.sqrt(x0 * x0 + y1 * y1 + z2)
        s = _solid_angle(x0, y0, a, x1, y1, w, h)
        # Seen within rounding of edge-on (a below 32 eps of the largest coordinate, 1 after scaling): the
        # plane's offset is below the rounding of the frame itself, whose directions could not then be told
        # to hit the rectangle or not: degenerate, as a rectangle exactly edge-on.
        self.eps = eps = 2.0**-52 if is64 else 2.0**-23
        finite = dr.isfinite(s) & dr.isfinite(scale) & (w > 0.0) & (h > 0.0) & (a > 32.0 * eps)
        self.valid = finite & (s > 0.0)
        self.solid_angle = dr.select(self.valid, s, 0.0)
        # e^{ik'} with k' = A00 - A01 (rectangle_frame's k = pi - k'), proportional to
        # (a r00 + i x0 y0)(a r01 - i x0 y1) = a^2 r00 r01 + x0^2 y0 y1 + i a x0 (y0 r01 - y1 r00), where
        # y0 r01 - y1 r00 = -(x0^2 + a^2) h (y0 + y1) / (y0 r01 + y1 r00) for y0, y1 of one sign
        re2 = a * a * r00 * r01 + x0 * x0 * (y0 * y1)
        plain = y0 * r01 - y1 * r00
        sum_ = y0 * r01 + y1 * r00
        factored = -(x0 * x0 + z2) * h * (y0 + y1) / dr.select(sum_ != 0.0, sum_, 1.0)
        im2 = a * x0 * dr.select((y0 * y1 > 0.0) & (sum_ != 0.0), factored, plain)
        norm2 = dr.sqrt(re2 * re2 + im2 * im2)
        self.ck, self.sk = -re2 / _safe(norm2), im2 / _safe(norm2)
        y02, y12 = y0 * y0, y1 * y1
        self.b0 = -y0 / _safe(dr.sqrt(y02 + z2))
        self.b1 = y1 / _safe(dr.sqrt(y12 + z2))
        self.b_sum = _sine_difference(y0, y1, h, z2)  # b0 + b1
        self.x0, self.y0, self.z0, self.x1, self.y1, self.h = x0, y0, z0, x1, y1, h
        self.z2, self.zsign, self.scale, self.corner = z2, zsign, scale, c
        self.centre = tuple(c[i] + 0.5 * (p1[i] + p2[i]) for i in range(3))

    def world(self, x: Any, y: Any, z: Any) -> Vec:
        """The frame's (x, y, z) (z already unflipped) in the viewer's coordinates."""
        e, g_, n = self.axes
        return (
            x * e[0] + y * g_[0] + z * n[0],
            x * e[1] + y * g_[1] + z * n[1],
            x * e[2] + y * g_[2] + z * n[2],
        )

    def hit(self, v: Any) -> tuple[Any, Any, Any]:
        """(x, y, inside): where the ray along v meets the plane (scaled frame), and whether in the rectangle.

        Within rounding of an edge counts as inside: x = z0 v_x / v_z carries about 2 eps |t| (1 + |x| / a)
        (v_z formed from v's components; t the distance), so that the map's own directions on the edges (u or
        v in {0, 1}) have pdf 1/S.  The slack grows as v_z shrinks; no ray that meets the rectangle is longer
        than sqrt(3) (every coordinate is at most 1 after scaling), so longer ones are outside whatever it is.
        """
        f = self.f
        d = (f(v.x), f(v.y), f(v.z))
        e, g_, n = self.axes
        length = dr.sqrt(_dot(d, d))
        dz = _dot(n, d) * self.zsign
        t = self.z0 / dr.select(dz < 0.0, dz, -1.0)
        x, y = t * _dot(e, d), t * _dot(g_, d)
        tol = 8.0 * self.eps * t * length * (1.0 + (dr.abs(x) + dr.abs(y)) / -self.z0)
        inside = self.valid & (dz < 0.0) & (t * length <= 2.0)
        inside &= (x >= self.x0 - tol) & (x <= self.x1 + tol) & (y >= self.y0 - tol) & (y <= self.y1 + tol)
        x, y = _clip(x, self.x0, self.x1), _clip(y, self.y0, self.y1)
        return dr.select(inside, x, self.x0), dr.select(inside, y, self.y0), inside


def _vector(f: Any, p: Vec) -> Any:
    return (mi.Vector3d if f is mi.Float64 else mi.Vector3f)(*p)


def spherical_rectangle_solid_angle(corner: Any, edge1: Any, edge2: Any) -> Any:
    """The solid angle S of the rectangle ``corner + s edge1 + t edge2`` seen from the origin (0 if degenerate).

    :func:`symsphere.warps.rectangle_frame`'s S, in the precision of *corner*; S is in [0, 2 pi).
    """
    return _Frame(corner, edge1, edge2).solid_angle


def square_to_spherical_rectangle(sample: Any, corner: Any, edge1: Any, edge2: Any) -> Any:
    """Urena's map of the square onto the rectangle seen from the origin: :func:`symsphere.warps.square_to_spherical_rectangle`.

    u = 0 is the edge through *corner* along *edge2*, v = 0 the edge through it along *edge1*.  A unit
    vector in the precision of *corner*, with density 1/S (:func:`spherical_rectangle_solid_angle`).
    """
    fr = _Frame(corner, edge1, edge2)
    f = fr.f
    u, v = _clip(f(sample[0]), 0.0, 1.0), _clip(f(sample[1]), 0.0, 1.0)
    x0, y0, z0, x1, y1, z2, b0 = fr.x0, fr.y0, fr.z0, fr.x1, fr.y1, fr.z2, fr.b0
    # rectangle_point: au = u S + k; with delta = au - pi, cos(au) = -1 + 2 sin^2(delta/2) and
    # sin(au) = -sin(delta), delta = u S - k' (k' = pi - k, e^{ik'} = -(ck - i sk))
    ss, cs = dr.sincos(u * fr.solid_angle)
    kc, ks = -fr.ck, fr.sk  # cos k', sin k'
    sin_delta = ss * kc - cs * ks
    cos_delta = cs * kc + ss * ks
    sin_half2 = 0.5 * dr.maximum(1.0 - cos_delta, 0.0)
    sin_half2 = dr.select(cos_delta > 0.0, 0.25 * sin_delta * sin_delta / _safe(0.5 * (1.0 + cos_delta)), sin_half2)
    sa = -sin_delta
    nu = 2.0 * sin_half2 * b0 - fr.b_sum
    den = nu * nu - z2 / (y0 * y0 + z2) * (sa * sa)
    tiny = 1e-300 if fr.is64 else 1e-37
    xu = -z0 * dr.mulsign(sa, nu) / dr.sqrt(dr.maximum(den, tiny))
    xu = _clip(xu, x0, x1)
    if not fr.is64:
        # One Newton step on S([x0, xu] x [y0, y1]) = u S, whose solid angle keeps its relative precision
        # (dS/dx = a (h1 - h0) / (x^2 + a^2)): Urena's closed form carries eps32 times the offset over the
        # width (the rotation by k) and, seen at a grazing angle, eps32 (x / a)^2 into u; after the step,
        # a few eps32.  Float64 keeps the closed form (1e-9 of the numpy map without it).
        a = -z0
        width = xu - x0
        d2 = xu * xu + z2
        slope = a * _sine_difference(y0, y1, fr.h, d2) / d2
        part = _solid_angle(x0, y0, a, xu, y1, width, fr.h)
        step = (part - u * fr.solid_angle) / dr.select(slope > 0.0, slope, dr.inf)
        # the step's own error, the rounding of the two solid angles over the slope: a step below it (where
        # the slope is small against S, as at the far edges of a rectangle of nearly a hemisphere) is noise
        noise = 4.0 * fr.eps * (part + u * fr.solid_angle) / dr.select(slope > 0.0, slope, 1.0)
        xu = _clip(dr.select(dr.abs(step) > noise, xu - step, xu), x0, x1)
    d2 = xu * xu + z2
    # the segment x = xu from y0 to y1, uniform in h = y / sqrt(d2 + y^2): h = h0 + v (h1 - h0)
    r0 = dr.sqrt(d2 + y0 * y0)
    h0 = y0 / r0
    hv = h0 + v * _sine_difference(y0, y1, fr.h, d2)
    one_minus = (1.0 - hv) * (1.0 + hv)
    yv = dr.select(one_minus > 0.0, hv * dr.sqrt(d2 / _safe(one_minus)), dr.select(hv > 0.0, y1, y0))
    yv = _clip(yv, y0, y1)
    inv = dr.rsqrt(d2 + yv * yv)
    d = fr.world(xu * inv, yv * inv, z0 * fr.zsign * inv)
    # the degenerate rectangle's direction: towards its centre (its normal if the viewer is there)
    big = dr.maximum(dr.maximum(dr.abs(fr.centre[0]), dr.abs(fr.centre[1])), dr.abs(fr.centre[2]))
    centre = tuple(x / _safe(big) for x in fr.centre)  # scaled first: its squared length may overflow
    length2 = _dot(centre, centre)
    inv_c = dr.rsqrt(_safe(length2))
    usable = (length2 > 0.0) & dr.isfinite(length2)
    n = fr.axes[2]
    n_ok = dr.isfinite(n[0]) & dr.isfinite(n[1]) & dr.isfinite(n[2]) & (_dot(n, n) > 0.5)
    last = (dr.select(n_ok, n[0], 0.0), dr.select(n_ok, n[1], 0.0), dr.select(n_ok, n[2], 1.0))
    fallback = tuple(dr.select(usable, centre[i] * inv_c, last[i]) for i in range(3))
    ok = fr.valid & dr.isfinite(d[0]) & dr.isfinite(d[1]) & dr.isfinite(d[2])
    return _vector(f, tuple(dr.select(ok, d[i], fallback[i]) for i in range(3)))


def square_to_spherical_rectangle_pdf(v: Any, corner: Any, edge1: Any, edge2: Any) -> Any:
    """Density of :func:`square_to_spherical_rectangle`: 1/S towards the rectangle, 0 elsewhere (and when
    it is degenerate): :func:`symsphere.warps.square_to_spherical_rectangle_pdf`."""
    fr = _Frame(corner, edge1, edge2)
    inside = fr.hit(v)[2]
    return dr.select(inside, 1.0 / _safe(fr.solid_angle), 0.0)


def spherical_rectangle_to_square(v: Any, corner: Any, edge1: Any, edge2: Any) -> Any:
    """Inverse of :func:`square_to_spherical_rectangle` (directions that miss the rectangle: clipped to its
    corner's (0, 0)): :func:`symsphere.warps.spherical_rectangle_to_square`.

    u = S([x0, x] x [y0, y1]) / S (the sub-rectangle's solid angle, by the same formula), and
    v = (h - h0) / (h1 - h0), both differences formed as :func:`square_to_spherical_rectangle` forms them.
    """
    fr = _Frame(corner, edge1, edge2)
    x, y, inside = fr.hit(v)
    x0, y0, z0, y1, z2 = fr.x0, fr.y0, fr.z0, fr.y1, fr.z2
    width = dr.maximum(x - x0, 0.0)
    u = _solid_angle(x0, y0, -z0, x0 + width, y1, width, fr.h) / _safe(fr.solid_angle)
    d2 = x * x + z2
    span = _sine_difference(y0, y1, fr.h, d2)
    part = _sine_difference(y0, y, dr.maximum(y - y0, 0.0), d2)
    vv = dr.select(span > 0.0, part / _safe(span), 0.0)
    u, vv = dr.select(inside, _clip(u, 0.0, 1.0), 0.0), dr.select(inside, _clip(vv, 0.0, 1.0), 0.0)
    return (mi.Point2d if fr.is64 else mi.Point2f)(u, vv)
