"""The scheme's maps in Dr.Jit: T0 maps, orbit member and fold, the square warps, the cosine wedge.

Each function restates one numpy function of the library with Dr.Jit operations, so that it
runs in every Mitsuba variant: on ``mi.Float`` / ``mi.Point2f`` / ``mi.Vector3f`` of a JIT
variant (``llvm_*``, ``cuda_*``: traced into the caller's kernel) and on Python floats in a
``scalar_*`` variant.  The numpy function each one mirrors is named in its docstring; the tests
(tests/mitsuba/test_warps.py) compare them to float32 rounding and run Mitsuba's own chi^2 test.

The triples are named as in Mitsuba's ``warp.h``: ``square_to_X``, ``square_to_X_pdf``,
``X_to_square``.  ``method`` is a Python string (a trace-time constant), one of
:data:`symsphere.warps.METHODS`.  Like the numpy originals these trust their inputs: ``uv`` in
[0, 1]^2, unit directions; outputs are clamped into their domain, so u, v in {0, 1} give no NaN.
"""

from __future__ import annotations

import math
from typing import Any

import drjit as dr
import mitsuba as mi
import numpy as np

from .._typing import Domain
from .._validation import check_choice
from ..symmetry import FOLD_TABLE, SIGNS, SOURCES, orbit_size
from ..warps import METHODS, strip_order

__all__ = [
    "square_to_triangle",
    "square_to_triangle_pdf",
    "triangle_to_square",
    "orbit_member",
    "fold",
    "square_to_sphere",
    "square_to_sphere_pdf",
    "sphere_to_square",
    "square_to_hemisphere",
    "square_to_hemisphere_pdf",
    "hemisphere_to_square",
    "square_to_cosine_wedge",
    "square_to_cosine_wedge_pdf",
    "cosine_wedge_to_square",
]  # the maps that symsphere.mitsuba re-exports; the package's integrator imports the point helpers by name

_SQRT2 = math.sqrt(2.0)
_PI = math.pi


# --- elementwise pieces (x, y, z as separate Floats) ------------------------------------------


def _clip(x: Any, lo: float, hi: float) -> Any:
    return dr.minimum(dr.maximum(x, lo), hi)


def _clamped_into_t0(x: Any, y: Any, z: Any) -> tuple[Any, Any, Any]:
    # maps._clamped_into_t0
    x = dr.minimum(x, z)
    return x, dr.minimum(dr.maximum(y, 0.0), x), z


def _in_triangle(x: Any, y: Any, z: Any) -> Any:
    return (z >= x) & (x >= y) & (y >= 0.0)


def _one_minus_cos_theta_max(cos_phi: Any) -> Any:
    # maps._one_minus_cos_theta_max: 1 - c / sqrt(1 + c^2) = 1 / (r (r + c)) without cancellation
    r = dr.sqrt(1.0 + cos_phi * cos_phi)
    return dr.rcp(r * (r + cos_phi))


def _equal_area_point(u: Any, v: Any) -> tuple[Any, Any, Any]:
    # maps._equal_area_point (Arvo's triangle sampling on T0), with Dr.Jit's sine for maps._sin_small
    sin_s = dr.sin(u * (_PI / 12))
    a = _SQRT2 * sin_s
    b = _SQRT2 * dr.sqrt(dr.maximum(1.0 - sin_s * sin_s, 0.0)) - 1.0
    inv_norm = dr.rsqrt(a * a + b * b)
    cos_phi, sin_phi = b * inv_norm, a * inv_norm
    w = v * _one_minus_cos_theta_max(cos_phi)
    sin_theta = dr.sqrt(dr.maximum(w * (2.0 - w), 0.0))
    return _clamped_into_t0(sin_theta * cos_phi, sin_theta * sin_phi, 1.0 - w)


def _equal_area_inverse(x: Any, y: Any, z: Any) -> tuple[Any, Any]:
    # maps._equal_area_inverse
    phi = _clip(dr.atan2(y, x), 0.0, _PI / 4)
    u = _clip((phi - dr.asin(dr.sin(phi) / _SQRT2)) * (12 / _PI), 0.0, 1.0)
    one_minus_cos = (x * x + y * y) / (1.0 + z)
    v = _clip(one_minus_cos / _one_minus_cos_theta_max(dr.cos(phi)), 0.0, 1.0)
    return u, v


def _paper1_point(u: Any, v: Any) -> tuple[Any, Any, Any]:
    # maps._paper1_point: phi = u pi/4, theta = arctan(v / cos phi)
    phi = u * (_PI / 4)
    sin_p, cos_p = dr.sincos(phi)
    sin_t, cos_t = dr.sincos(dr.atan(v / cos_p))
    return _clamped_into_t0(cos_p * sin_t, sin_p * sin_t, cos_t)


def _paper2_point(u: Any, v: Any) -> tuple[Any, Any, Any]:
    # maps._paper2_point: phi = u pi/4, theta = v pi/4, P = N'_x x N'_y / |N'_x x N'_y|
    sin_p, cos_p = dr.sincos(u * (_PI / 4))
    sin_t, cos_t = dr.sincos(v * (_PI / 4))
    inv_norm = dr.rsqrt(sin_t * sin_t + cos_t * cos_t * cos_p * cos_p)
    return _clamped_into_t0(sin_t * cos_p * inv_norm, sin_t * sin_p * inv_norm, cos_t * cos_p * inv_norm)


def _vertex_singular_density(x: Any, y: Any, inside: Any, constant: float, smooth_factor: Any) -> Any:
    # maps._vertex_singular_density: constant x / (smooth_factor (x^2 + y^2)) on T0, +inf at the vertex
    r = dr.sqrt(x * x + y * y)
    at_vertex = r == 0.0
    cos_phi = dr.select(at_vertex, 1.0, x / dr.select(at_vertex, 1.0, r))
    value = dr.select(at_vertex, math.inf, constant * cos_phi / (smooth_factor * dr.select(at_vertex, 1.0, r)))
    return dr.select(inside, value, 0.0)


def _azimuth_u(x: Any, y: Any) -> Any:
    # maps._azimuth_to_u
    return _clip(dr.atan2(y, x) * (4 / _PI), 0.0, 1.0)


def triangle_point(u: Any, v: Any, method: str = "equal_area") -> tuple[Any, Any, Any]:
    """Elementwise forward map of the square onto T0 (x, y, z): ``Warp.point`` of :func:`symsphere.warps.triangle_warp`."""
    if method == "equal_area":
        return _equal_area_point(u, v)
    if method == "paper1":
        return _paper1_point(u, v)
    return _paper2_point(u, v)


def triangle_density(x: Any, y: Any, z: Any, method: str = "equal_area") -> Any:
    """Elementwise solid-angle density on T0: ``Warp.density`` of :func:`symsphere.warps.triangle_warp` (0 outside)."""
    inside = _in_triangle(x, y, z)
    if method == "equal_area":
        return dr.select(inside, 12 / _PI, 0.0)
    if method == "paper1":  # maps._paper1_density: 4 x / (pi z^2 (x^2 + y^2))
        return _vertex_singular_density(x, y, inside, 4.0, _PI * z * z)
    return _vertex_singular_density(x, y, inside, 16.0, _PI**2 * (x * x + z * z))  # maps._paper2_density


def _triangle_uv(x: Any, y: Any, z: Any, method: str) -> tuple[Any, Any]:
    if method == "equal_area":
        return _equal_area_inverse(x, y, z)
    if method == "paper1":  # maps._paper1_inverse
        return _azimuth_u(x, y), _clip(x / z, 0.0, 1.0)
    return _azimuth_u(x, y), _clip(dr.atan2(x, z) * (4 / _PI), 0.0, 1.0)  # maps._paper2_inverse


def cosine_wedge_point(u: Any, v: Any) -> tuple[Any, Any, Any]:
    """Elementwise cosine-weighted map onto the wedge W: :func:`symsphere.warps.cosine_wedge_point`."""
    r = dr.sqrt(u)
    sin_p, cos_p = dr.sincos(v * (_PI / 4))
    x = r * cos_p
    y = dr.minimum(dr.maximum(r * sin_p, 0.0), x)
    return x, y, dr.sqrt(dr.maximum(1.0 - u, 0.0))


# --- orbit member and fold ------------------------------------------------------------------------

# orbit_member restates symmetry.SOURCES / SIGNS (``(p @ SPHERE_MAPS[k])[j] == SIGNS[k, j] p[SOURCES[k, j]]``)
# as selects, using their structure (k = 24 half + 4 i + j: the source coordinates depend on the row i, the
# first two signs on the column j, the third on the half), checked here on the tables themselves.
_K = np.arange(48)
assert np.array_equal(SOURCES, SOURCES[4 * ((_K % 24) // 4)])
assert np.array_equal(SIGNS[:, :2], SIGNS[_K % 4, :2])
assert np.array_equal(SIGNS[:, 2], SIGNS[24 * (_K >= 24), 2])
_ROW_SOURCES = [tuple(int(s) for s in SOURCES[4 * i]) for i in range(6)]
_COLUMN_SIGNS = [tuple(float(s) for s in SIGNS[j, :2]) for j in range(4)]


def _chain(index: Any, values: list[Any]) -> Any:
    """values[index] by a chain of selects (index a UInt32 array or an int)."""
    if isinstance(index, (int, np.integer)):
        return values[int(index)]
    result = values[-1]
    for i in range(len(values) - 2, -1, -1):
        result = dr.select(index == i, values[i], result)
    return result


def orbit_member(x: Any, y: Any, z: Any, k: Any, members: int = 48) -> tuple[Any, Any, Any]:
    """Image k (0..47) of (x, y, z): ``(x, y, z) @ SPHERE_MAPS[k]`` (:func:`symsphere.orbit`, one member).

    *members*: k is known to be below it (8: the z-keeping images, 24: the hemisphere's, 48: all), so
    that the selects of the images k cannot reach are not traced.
    """
    if members not in (8, 24, 48):
        raise ValueError(f"'members' must be 8, 24 or 48; got {members!r}")
    if isinstance(k, (int, np.integer)):
        if not 0 <= k < members:
            raise ValueError(f"'k' must be in 0..{members - 1}; got {k}")
        members = 48
    half = k >= 24
    if members == 48:
        rest = dr.select(half, k - 24, k) if not isinstance(k, (int, np.integer)) else (k - 24 if k >= 24 else k)
    else:
        rest = k
    row = rest // 4
    column = rest % 4
    base = (x, y, z)
    rows = 6 if members >= 24 else members // 4
    out = [_chain(row, [base[_ROW_SOURCES[i][c]] for i in range(rows)]) for c in range(3)]
    sx = _chain(column, [s[0] for s in _COLUMN_SIGNS])
    sy = _chain(column, [s[1] for s in _COLUMN_SIGNS])
    if members == 48:
        sz = dr.select(half, float(SIGNS[24, 2]), float(SIGNS[0, 2]))
        return sx * out[0], sy * out[1], sz * out[2]
    return sx * out[0], sy * out[1], float(SIGNS[0, 2]) * out[2]


def _sign(value: Any) -> Any:
    return dr.select(value > 0, 1, dr.select(value < 0, -1, 0))


def _weak_order(a: Any, b: Any) -> Any:
    return dr.select(a > b, 1, dr.select(a < b, -1, 0))


def _fold_key(x: Any, y: Any, z: Any) -> Any:
    """The sign pattern of d and the weak order of |d| as one key < 729: :func:`symsphere.symmetry.fold_key`."""
    ax, ay, az = dr.abs(x), dr.abs(y), dr.abs(z)
    key = 0
    for part in (_sign(x), _sign(y), _sign(z), _weak_order(ax, ay), _weak_order(ax, az), _weak_order(ay, az)):
        key = key * 3 + (part + 1)
    return key


# symmetry's table, as the UInt32 a gather reads (a key no vector has is never looked up).
_FOLD_TABLE = np.maximum(FOLD_TABLE, 0).astype(np.uint32)


def _lookup(table: np.ndarray, index: Any) -> Any:
    """table[index] for an int (scalar variants) or a UInt32 array (JIT variants: a gather)."""
    if isinstance(index, (int, np.integer)):
        return int(table[int(index)])
    index_type = type(index)
    uint = dr.uint32_array_t(index_type)
    return dr.gather(uint, uint(table.astype(np.uint32)), uint(index))


def _base(x: Any, y: Any, z: Any) -> tuple[Any, Any, Any]:
    """(middle, smallest, largest) of |d|: the preimage in T0 (symmetry._base), by a min/max network."""
    a, b, c = dr.abs(x), dr.abs(y), dr.abs(z)
    lo_ab, hi_ab = dr.minimum(a, b), dr.maximum(a, b)
    largest = dr.maximum(hi_ab, c)
    smallest = dr.minimum(lo_ab, c)
    middle = dr.maximum(lo_ab, dr.minimum(hi_ab, c))
    return middle, smallest, largest


def fold(d: Any) -> tuple[Any, Any]:
    """Sub-domain index k and preimage in T0 of directions: :func:`symsphere.fold`.

    Returns ``(k, base)`` with ``orbit_member(base, k) == d`` exactly (the lowest k on boundaries).
    """
    key = _fold_key(d.x, d.y, d.z)
    if not isinstance(key, int):
        key = dr.uint32_array_t(type(d.x))(key)
    return _lookup(_FOLD_TABLE, key), _vector(*_base(d.x, d.y, d.z))


# --- the public triples (Mitsuba's warp.h form) ------------------------------------------------------


def _vector(x: Any, y: Any, z: Any) -> Any:
    return mi.Vector3f(x, y, z)


def _method(method: str) -> str:
    return check_choice(method, "method", METHODS)


def square_to_triangle(sample: Any, method: str = "equal_area") -> Any:
    """Points of the unit square to directions in T0: :func:`symsphere.square_to_triangle`."""
    return _vector(*triangle_point(sample.x, sample.y, _method(method)))


def square_to_triangle_pdf(v: Any, method: str = "equal_area") -> Any:
    """Solid-angle density of :func:`square_to_triangle` (0 outside T0): :func:`symsphere.square_to_triangle_pdf`."""
    return triangle_density(v.x, v.y, v.z, _method(method))


def triangle_to_square(v: Any, method: str = "equal_area") -> Any:
    """Inverse of :func:`square_to_triangle`: :func:`symsphere.triangle_to_square`."""
    return mi.Point2f(*_triangle_uv(v.x, v.y, v.z, _method(method)))


def _strip_forward(sample: Any, method: str, domain: Domain) -> Any:
    # square_warps._forward: strip j = floor(count u) onto triangle strip_order[j], odd strips mirrored
    method = _method(method)
    count = orbit_size(domain)
    t = sample.x * count
    j_float = dr.minimum(dr.floor(t), count - 1)
    local = t - j_float
    if isinstance(t, float):
        j: Any = int(j_float)
        odd = j % 2 == 1
    else:
        j = dr.uint32_array_t(type(t))(j_float)
        odd = (j & 1) == 1
    local_u = _clip(dr.select(odd, 1.0 - local, local), 0.0, 1.0)
    bx, by, bz = triangle_point(local_u, sample.y, method)
    k = _lookup(strip_order(domain), j)
    return _vector(*orbit_member(bx, by, bz, k))


def _strip_pdf(v: Any, method: str, domain: Domain) -> Any:
    # sampling.sphere_pdf / hemisphere_pdf: square_to_triangle_pdf(fold(d)) / count, 0 below the equator
    bx, by, bz = _base(v.x, v.y, v.z)
    density = triangle_density(bx, by, bz, _method(method)) / orbit_size(domain)
    if domain == "hemisphere":
        density = dr.select(v.z >= 0.0, density, 0.0)
    return density


def _strip_inverse(v: Any, method: str, domain: Domain) -> Any:
    # square_warps._inverse: fold, invert the map, put u' back into the strip of triangle k
    method = _method(method)
    count = orbit_size(domain)
    k, base = fold(v)
    lu, lv = _triangle_uv(base.x, base.y, base.z, method)
    strips = np.argsort(strip_order(domain)).astype(np.uint32)
    j = _lookup(strips, k)
    lu = _clip(lu, 0.0, 1.0)
    odd = (j % 2 == 1) if isinstance(j, int) else ((j & 1) == 1)
    j_float = float(j) if isinstance(j, int) else type(v.x)(j)
    return mi.Point2f((j_float + dr.select(odd, 1.0 - lu, lu)) / count, lv)


def square_to_sphere(sample: Any, method: str = "equal_area") -> Any:
    """The whole-sphere bijection through the 48 triangles: :func:`symsphere.warps.square_to_sphere`."""
    return _strip_forward(sample, method, "sphere")


def square_to_sphere_pdf(v: Any, method: str = "equal_area") -> Any:
    """Density of :func:`square_to_sphere`: :func:`symsphere.warps.square_to_sphere_pdf`."""
    return _strip_pdf(v, method, "sphere")


def sphere_to_square(v: Any, method: str = "equal_area") -> Any:
    """Inverse of :func:`square_to_sphere`: :func:`symsphere.warps.sphere_to_square`."""
    return _strip_inverse(v, method, "sphere")


def square_to_hemisphere(sample: Any, method: str = "equal_area") -> Any:
    """The hemisphere bijection through the 24 triangles: :func:`symsphere.warps.square_to_hemisphere`."""
    return _strip_forward(sample, method, "hemisphere")


def square_to_hemisphere_pdf(v: Any, method: str = "equal_area") -> Any:
    """Density of :func:`square_to_hemisphere`: :func:`symsphere.warps.square_to_hemisphere_pdf`."""
    return _strip_pdf(v, method, "hemisphere")


def hemisphere_to_square(v: Any, method: str = "equal_area") -> Any:
    """Inverse of :func:`square_to_hemisphere`: :func:`symsphere.warps.hemisphere_to_square`."""
    return _strip_inverse(v, method, "hemisphere")


def square_to_cosine_wedge(sample: Any) -> Any:
    """Cosine-weighted map onto the wedge W: :func:`symsphere.warps.square_to_cosine_wedge`."""
    return _vector(*cosine_wedge_point(sample.x, sample.y))


def square_to_cosine_wedge_pdf(v: Any) -> Any:
    """``8 z / pi`` inside W = {x >= y >= 0, z >= 0}, else 0: :func:`symsphere.warps.square_to_cosine_wedge_pdf`."""
    inside = (v.x >= v.y) & (v.y >= 0.0) & (v.z >= 0.0)
    return dr.select(inside, (8 / _PI) * dr.maximum(v.z, 0.0), 0.0)


def cosine_wedge_to_square(v: Any) -> Any:
    """Inverse of :func:`square_to_cosine_wedge`: :func:`symsphere.warps.cosine_wedge_to_square`."""
    u = dr.minimum(v.x * v.x + v.y * v.y, 1.0)
    return mi.Point2f(u, _clip(dr.atan2(v.y, v.x) * (4 / _PI), 0.0, 1.0))


# --- Arvo's spherical triangle, in float64 ------------------------------------------------------


def spherical_triangle_solid_angle(a: Any, b: Any, c: Any) -> Any:
    """Solid angle of the triangle with vertices at a, b, c (vectors from the viewer, any length; float64).

    Van Oosterom & Strackee (1983), ``tan(E/2) = |a.(b x c)| / (|a||b||c| + (a.b)|c| + (a.c)|b| + (b.c)|a|)``;
    the Dr.Jit twin of ``symsphere.warps._spherical_triangle._triangle_area`` for unnormalised vertices.
    0 for a degenerate triangle (no NaN).
    """
    la, lb, lc = dr.norm(a), dr.norm(b), dr.norm(c)
    triple = dr.abs(dr.dot(a, dr.cross(b, c)))
    den = la * lb * lc + dr.dot(a, b) * lc + dr.dot(a, c) * lb + dr.dot(b, c) * la
    return 2.0 * dr.atan2(triple, den)


def unit_spherical_triangle_solid_angle(A: Any, B: Any, C: Any) -> Any:
    """The solid angle of the triangle of the unit vectors A, B, C, as :func:`square_to_spherical_triangle`
    computes it (the same operations: a density evaluated elsewhere matches the map's bit for bit)."""
    return 2.0 * dr.atan2(dr.abs(dr.dot(A, dr.cross(B, C))), 1.0 + dr.dot(A, B) + dr.dot(B, C) + dr.dot(C, A))


def square_to_spherical_triangle(sample: Any, a: Any, b: Any, c: Any) -> tuple[Any, Any]:
    """Arvo's map: ``symsphere.warps.square_to_spherical_triangle`` restated, (direction, solid angle).

    *a*, *b*, *c* are vectors from the viewer (``mi.Vector3d`` or ``mi.Vector3f``, any length, normalised
    here); *sample* two values of the same precision (converted).  It runs in the precision of *a*.  In
    float64 it is the numpy map to 1e-9.  In float32 (as ``symsphere_path``'s ``solid_angle`` runs it) the
    forms without cancellation (1 - cos as 2 sin^2, sin(A' - alpha) by the addition theorems) keep it
    within 2.5e-6 in direction of the float64 map on a 1.76 sr triangle seen from 0.15 away, and the solid
    angle within 1e-6 relative down to 5e-5 sr (1.7e-5 at 5e-7 sr; tests/mitsuba/test_lights.py); a naive
    float32 form lost 7e-4 in direction there.  Slivers narrower than float32's ulp may leave their
    triangle: a tiny triangle's light, a tiny error.
    The solid angle is 0 for a degenerate triangle; the direction is then finite but meaningless.
    """
    f64 = type(a.x)
    u, v = f64(sample[0]), f64(sample[1])
    A, B, C = dr.normalize(a), dr.normalize(b), dr.normalize(c)
    tb, tc = B - dr.dot(A, B) * A, C - dr.dot(A, C) * A
    # the angle alpha at A by its sine and cosine (no atan2), and one sincos of A'/2: sin(A' - alpha) and
    # sin(A'/2 - alpha) by the addition theorems (the numpy original evaluates each sine directly)
    inv_tt = 1.0 / dr.sqrt(dr.squared_norm(tb) * dr.squared_norm(tc))
    sin_a = dr.norm(dr.cross(tb, tc)) * inv_tt
    cos_a = dr.dot(tb, tc) * inv_tt
    cos_c = dr.dot(A, B)
    area = unit_spherical_triangle_solid_angle(A, B, C)
    half = 0.5 * u * area
    sin_half, cos_half = dr.sincos(half)
    sin_area_hat = 2.0 * sin_half * cos_half
    cos_area_hat = 1.0 - 2.0 * dr.square(sin_half)
    one_minus_cos_c = 0.5 * dr.squared_norm(A - B)
    sin_c = dr.norm(dr.cross(A, B))
    sin_diff = sin_area_hat * cos_a - cos_area_hat * sin_a  # sin(A' - alpha)
    sin_half_diff = sin_half * cos_a - cos_half * sin_a  # sin(A'/2 - alpha)
    denom = 2.0 * dr.square(sin_half) - sin_diff * sin_a * one_minus_cos_c
    denom = dr.select(denom > 0.0, denom, 1.0)  # 0 only for a degenerate triangle
    cos_b = 1.0 - (1.0 + cos_c) * 2.0 * dr.square(sin_half) / denom
    sin_b = 2.0 * sin_c * dr.abs(sin_half * sin_half_diff) / denom
    c_perp = dr.normalize(C - dr.dot(C, A) * A)
    c_hat = dr.normalize(cos_b * A + sin_b * c_perp)
    one_minus_cb = 0.5 * dr.squared_norm(c_hat - B)
    w = v * one_minus_cb
    sin_d = dr.sqrt(dr.maximum(w * (2.0 - w), 0.0))
    tangent = c_hat - dr.dot(c_hat, B) * B
    norm = dr.norm(tangent)
    tangent = tangent / dr.select(norm > 0.0, norm, 1.0)
    tangent = tangent - dr.dot(tangent, B) * B  # once more: C' may be nearly antipodal to B
    norm = dr.norm(tangent)
    tangent = tangent / dr.select(norm > 0.0, norm, 1.0)
    d = (1.0 - w) * B + sin_d * tangent
    ok = dr.isfinite(d.x) & dr.isfinite(d.y) & dr.isfinite(d.z) & (area > 0.0)
    return dr.select(ok, d, B), dr.select(ok, area, 0.0)
