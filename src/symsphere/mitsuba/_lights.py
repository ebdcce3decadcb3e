"""Light sampling by solid angle for ``symsphere_path`` (``emitter_sampling='solid_angle'``).

Mitsuba 3 samples a ``rectangle`` or triangle-mesh area emitter by area and converts the density to
solid angle, so a point near a large light gets wildly varying weights ``d^2 / cos``.  Here every
triangle of those emitters (a rectangle is two) is a row of a table (:class:`LightTable`), and at a
shading point p:

1. one triangle is chosen with probability proportional to an estimate of its contribution,
   ``w_i = Omega_i(p) L_e``: its solid angle seen from p (Van Oosterom & Strackee) times a scalar
   radiance of its emitter (the mean of its RGB radiance, of the texture's mean for a textured one),
   0 when p is behind the triangle (area emitters are one-sided).  For up to :data:`EXACT_MAX`
   triangles every w_i is evaluated (the loop is unrolled into the kernel, the triangles are
   constants of it); above that, the triangle is chosen by its power ``area L_e`` (a
   ``mi.DiscreteDistribution``), which is what Mitsuba does, and only the map below is gained: no
   light hierarchy yet;
2. a direction is drawn uniformly in the chosen triangle's solid angle with Arvo's map
   (:func:`symsphere.mitsuba._warps.square_to_spherical_triangle`, float64 inside the kernel);
3. the point q where the direction meets the triangle's plane is shadow-tested as Mitsuba tests its
   own samples (a shortened ray to q), and the emitter's ``eval_direction`` gives the radiance there
   (texture coordinates interpolated from the triangle's vertices; the one-sided test).

The density of the direction is ``P(i) / Omega_i``, which with exact selection is ``L_e / W`` (W the
sum of the w_i), the same for every triangle of an emitter.  A BSDF-sampled ray that hits such an
emitter gets this same density at its previous vertex (:meth:`LightTable.pdf_direction`, for MIS).

Every other emitter (sphere, disk, point, spot, directional, environment, constant) keeps Mitsuba's
own sampling: with probability ``P_other`` (the Mitsuba selection probabilities of those emitters,
summed) one of them is chosen as Mitsuba would and samples itself; the table's triangles share the
rest.  Emitters Mitsuba never chooses (``sampling_weight`` 0) stay out of the table.
"""

from __future__ import annotations

from typing import Any

import drjit as dr
import mitsuba as mi
import numpy as np

from ._warps import spherical_triangle_solid_angle, square_to_spherical_triangle

__all__ = ["EMITTER_SAMPLINGS", "EXACT_MAX", "LightTable", "build"]

EMITTER_SAMPLINGS = ("area", "solid_angle")
"""The values of ``symsphere_path``'s ``emitter_sampling``, sorted."""
EXACT_MAX = 64
"""Up to this many emitter triangles, each is evaluated at every shading point to choose one."""
_NONE = 0xFFFFFFFF  # no table row: the shape is not one of the table's emitters


def _registry_ids(pointers: Any) -> Any:
    """The Dr.Jit registry ids (UInt32) of an array of Mitsuba object pointers."""
    return dr.reinterpret_array(mi.UInt32, pointers)


def _shape_id(shape: Any) -> int:
    return int(_registry_ids(mi.ShapePtr(shape))[0])


def _radiance(emitter: Any) -> float:
    """A scalar radiance of an area emitter: the mean of its RGB value (of the texture's mean), else 1."""
    params = mi.traverse(emitter)
    for key in ("radiance.value", "radiance.data"):
        if key in params:
            value = np.asarray(params[key], dtype=np.float64)
            if value.size and np.all(np.isfinite(value)):
                return float(np.mean(np.maximum(value, 0.0)))
    return 1.0


def _triangles(shape: Any) -> tuple[np.ndarray, np.ndarray] | None:
    """The triangles (n, 3, 3) of a rectangle or mesh, in the orientation of its emitting side, and their
    vertices' texture coordinates (n, 3, 2); None for other shapes."""
    name = shape.class_name()
    if name == "Rectangle":
        m = np.asarray(mi.traverse(shape)["to_world"].matrix, dtype=np.float64).reshape(4, 4)
        local = ((-1, -1), (1, -1), (1, 1), (-1, 1))
        corners = [(m @ np.array([x, y, 0.0, 1.0]))[:3] for x, y in local]
        # Mitsuba's rectangle: uv = ((x + 1) / 2, (y + 1) / 2); the first triangle is uv.y <= uv.x
        uv = [((x + 1) / 2, (y + 1) / 2) for x, y in local]
        tris = np.array([[corners[0], corners[1], corners[2]], [corners[0], corners[2], corners[3]]])
        uvs = np.array([[uv[0], uv[1], uv[2]], [uv[0], uv[2], uv[3]]], dtype=np.float64)
    elif shape.is_mesh():
        vertices = np.asarray(shape.vertex_positions_buffer(), dtype=np.float64).reshape(-1, 3)
        faces = np.asarray(shape.faces_buffer(), dtype=np.int64).reshape(-1, 3)
        tris = vertices[faces]
        texcoords = np.asarray(shape.vertex_texcoords_buffer(), dtype=np.float64)
        uvs = texcoords.reshape(-1, 2)[faces] if texcoords.size else np.zeros((len(faces), 3, 2))
    else:
        return None
    if shape.has_flipped_normals():
        tris, uvs = tris[:, [0, 2, 1]], uvs[:, [0, 2, 1]]
    return tris, uvs


class LightTable:
    """The emitter triangles of a scene and their selection (see the module docstring)."""

    def __init__(self, scene: Any) -> None:
        emitters = scene.emitters()
        pmf = [float(scene.pdf_emitter(mi.UInt32(i))[0]) for i in range(len(emitters))]
        rows: list[np.ndarray] = []
        uv_rows: list[np.ndarray] = []
        emitter_rows: list[int] = []
        radiance: list[float] = []
        shape_rows: dict[int, tuple[int, bool]] = {}  # shape id -> (first row, is a rectangle)
        in_table = [False] * len(emitters)
        emitter_index = {int(k): i for i, k in enumerate(_registry_ids(scene.emitters_dr()))}
        for shape in scene.shapes():
            emitter = shape.emitter()
            if emitter is None:
                continue
            index = emitter_index.get(int(_registry_ids(mi.EmitterPtr(emitter))[0]))
            if index is None or pmf[index] <= 0.0:
                continue
            found = _triangles(shape)
            if found is None or len(found[0]) == 0:
                continue
            tris, uvs = found
            in_table[index] = True
            shape_rows[_shape_id(shape)] = (sum(len(r) for r in rows), shape.class_name() == "Rectangle")
            rows.append(tris)
            uv_rows.append(uvs)
            emitter_rows += [index] * len(tris)
            radiance += [_radiance(emitter)] * len(tris)
        self.count = sum(len(r) for r in rows)
        self.p_other = float(sum(p for p, t in zip(pmf, in_table, strict=True) if not t))
        self.p_table = 1.0 - self.p_other if self.count else 0.0
        if not self.count:
            return
        tris = np.concatenate(rows)
        normal = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
        area = 0.5 * np.linalg.norm(normal, axis=1)
        lum = np.asarray(radiance)
        lum = np.where(area > 0.0, lum, 0.0)  # a degenerate triangle is never chosen
        self.tris, self.normal, self.lum, self.exact = tris, normal, lum, self.count <= EXACT_MAX
        self._columns = [mi.Float64(np.ascontiguousarray(tris[:, k, j])) for k in range(3) for j in range(3)]
        self._normal = [mi.Float64(np.ascontiguousarray(normal[:, j])) for j in range(3)]
        self._lum = mi.Float64(lum)
        uvs = np.concatenate(uv_rows)
        self._uv = [mi.Float(np.ascontiguousarray(uvs[:, k, j])) for k in range(3) for j in range(2)]
        self._emitter = mi.UInt32(np.asarray(emitter_rows, dtype=np.uint32))
        size = max(shape_rows) + 1
        first, rect = np.full(size, _NONE, dtype=np.uint32), np.zeros(size, dtype=np.uint32)
        for ident, (row, is_rect) in shape_rows.items():
            first[ident], rect[ident] = row, int(is_rect)
        self._first, self._rect = mi.UInt32(first), mi.UInt32(rect)
        if not self.exact:
            self._power = mi.DiscreteDistribution(mi.Float(area * lum))
        others = [p if not t else 0.0 for p, t in zip(pmf, in_table, strict=True)]
        self._other = mi.DiscreteDistribution(mi.Float(others)) if self.p_other > 0.0 else None

    # --- per-point weights ---------------------------------------------------------------------

    def _vertices(self, row: Any, active: Any) -> tuple[Any, Any, Any, Any]:
        c = [dr.gather(mi.Float64, col, row, active) for col in self._columns]
        n = [dr.gather(mi.Float64, col, row, active) for col in self._normal]
        return (
            mi.Vector3d(c[0], c[1], c[2]),
            mi.Vector3d(c[3], c[4], c[5]),
            mi.Vector3d(c[6], c[7], c[8]),
            mi.Vector3d(*n),
        )

    @staticmethod
    def _weight(p: Any, a: Any, b: Any, c: Any, n: Any, lum: Any) -> Any:
        """``Omega(p) L_e``, 0 behind the triangle (float64)."""
        front = dr.dot(p - a, n) > 0.0
        omega = spherical_triangle_solid_angle(a - p, b - p, c - p)
        return dr.select(front & (omega > 0.0), omega * lum, 0.0)

    def _exact_weights(self, p: Any) -> list[Any]:
        """w_i at p for every row (None for a degenerate one): the triangles are constants of the kernel."""
        weights: list[Any] = []
        for tri, normal, lum in zip(self.tris, self.normal, self.lum, strict=True):
            if lum > 0.0:
                a, b, c = (mi.ScalarVector3d(*vertex) for vertex in tri)
                weights.append(self._weight(p, a, b, c, mi.ScalarVector3d(*normal), float(lum)))
            else:
                weights.append(None)
        return weights

    # --- sampling (next-event estimation) ------------------------------------------------------------

    def sample_direction(self, scene: Any, si: Any, sample: Any, active: Any) -> tuple[Any, Any]:
        """Like ``scene.sample_emitter_direction(si, sample, True, active)``: (ds, radiance / pdf), with
        ``ds.d``, ``ds.pdf`` (solid angle, selection included) and ``ds.delta`` set; visibility tested."""
        u = mi.Float(sample.x)
        ds = dr.zeros(mi.DirectionSample3f)
        weight = dr.zeros(mi.Spectrum)
        ours = active & (u < self.p_table)
        if self._other is not None:  # Mitsuba's own emitters: chosen by their Mitsuba probabilities
            other = active & ~ours
            u_other: Any = dr.clip((u - self.p_table) / self.p_other, 0.0, 1.0 - 2.0**-24)
            index, u_other, _ = self._other.sample_reuse_pmf(u_other, other)
            emitter = dr.gather(mi.EmitterPtr, scene.emitters_dr(), index, other)
            ds_o, w_o = emitter.sample_direction(si, mi.Point2f(u_other, sample.y), other)
            other &= ds_o.pdf != 0.0
            visible = ~scene.ray_test(si.spawn_ray_to(ds_o.p), other)
            ds_o.pdf *= self.p_other * self._other.eval_pmf_normalized(index, other)
            w_o = dr.select(other & visible, w_o / (self.p_other * self._other.eval_pmf_normalized(index, other)), 0.0)
            ds = dr.select(other, ds_o, ds)
            weight = dr.select(other, w_o, weight)
        if self.count:
            d, pdf, value = self._sample_table(scene, si, u / self.p_table, sample.y, ours)
            ds.d = dr.select(ours, d, ds.d)
            ds.pdf = dr.select(ours, pdf, ds.pdf)
            ds.delta = dr.select(ours, False, ds.delta)
            weight = dr.select(ours, value, weight)
        return ds, weight

    def _sample_table(self, scene: Any, si: Any, u: Any, v: Any, active: Any) -> tuple[Any, Any, Any]:
        p = mi.Vector3d(si.p)
        u = mi.Float64(u)
        if self.exact:
            weights = self._exact_weights(p)
            total = mi.Float64(0.0)
            for w in weights:
                if w is not None:
                    total += w
            target = u * total
            row: Any = mi.UInt32(0)
            before = mi.Float64(0.0)
            chosen = mi.Float64(0.0)
            acc = mi.Float64(0.0)
            for i, w in enumerate(weights):
                if w is None:
                    continue
                take = (acc <= target) & (w > 0.0)
                row = dr.select(take, i, row)
                before = dr.select(take, acc, before)
                chosen = dr.select(take, w, chosen)
                acc += w
            active = active & (total > 0.0) & (chosen > 0.0)
            u_map = dr.clip((target - before) / dr.select(chosen > 0.0, chosen, 1.0), 0.0, 1.0)
            a, b, c, n = self._vertices(row, active)
            lum = dr.gather(mi.Float64, self._lum, row, active)
            direction, omega = square_to_spherical_triangle((u_map, mi.Float64(v)), a - p, b - p, c - p)
            pdf = self.p_table * lum / dr.select(total > 0.0, total, 1.0)
        else:
            row, u_map, pmf = self._power.sample_reuse_pmf(mi.Float(u), active)  # type: ignore[arg-type]
            a, b, c, n = self._vertices(row, active)
            direction, omega = square_to_spherical_triangle((mi.Float64(u_map), mi.Float64(v)), a - p, b - p, c - p)
            active &= (dr.dot(p - a, n) > 0.0) & (omega > 0.0)
            pdf = self.p_table * mi.Float64(pmf) / dr.select(omega > 0.0, omega, 1.0)
        active &= omega > 0.0
        d = mi.Vector3f(dr.normalize(direction))
        # The point q where d meets the triangle's plane: shadow-tested as Mitsuba tests its own samples
        # (a ray to q, shortened; a coplanar surface, as the Cornell box's ceiling around its light, does
        # not occlude), and the emitter evaluated there (texture coordinates interpolated).
        dd = mi.Vector3d(d)
        cos_n = dr.dot(dd, n)
        t_plane = dr.dot(a - p, n) / dr.select(cos_n != 0.0, cos_n, 1.0)
        q = p + t_plane * dd
        n2 = dr.squared_norm(n)
        n2 = dr.select(n2 > 0.0, n2, 1.0)
        lb = mi.Float(dr.dot(dr.cross(q - a, c - a), n) / n2)
        lc = mi.Float(dr.dot(dr.cross(b - a, q - a), n) / n2)
        uv = [dr.gather(mi.Float, col, row, active) for col in self._uv]
        ds: Any = dr.zeros(mi.DirectionSample3f)
        ds.p = mi.Point3f(q)
        ds.n = mi.Normal3f(dr.normalize(n))
        ds.uv = mi.Point2f(
            uv[0] + lb * (uv[2] - uv[0]) + lc * (uv[4] - uv[0]), uv[1] + lb * (uv[3] - uv[1]) + lc * (uv[5] - uv[1])
        )
        ds.d = d
        ds.dist = mi.Float(t_plane)
        ds.emitter = dr.gather(
            mi.EmitterPtr, scene.emitters_dr(), dr.gather(mi.UInt32, self._emitter, row, active), active
        )
        active &= t_plane > 0.0
        active &= ~scene.ray_test(si.spawn_ray_to(ds.p), active)
        radiance: Any = ds.emitter.eval_direction(si, ds, active)
        pdf_f = mi.Float(pdf)
        value = dr.select(active & (pdf_f > 0.0), radiance / dr.select(pdf_f > 0.0, pdf_f, 1.0), 0.0)
        return d, dr.select(active, pdf_f, 0.0), value

    # --- the density of a hit (MIS) ----------------------------------------------------------------

    def pdf_direction(self, scene: Any, prev_si: Any, si: Any, ds: Any, active: Any) -> Any:
        """Like ``scene.pdf_emitter_direction(prev_si, ds, active)`` for the emitter hit at *si*."""
        mitsuba_pdf = scene.pdf_emitter_direction(prev_si, ds, active)
        if not self.count:
            return mitsuba_pdf
        ident = _registry_ids(si.shape)
        valid = active & si.is_valid() & (ident < dr.width(self._first))
        first = dr.gather(mi.UInt32, self._first, ident, valid)
        ours = valid & (first != _NONE)
        rect = dr.gather(mi.UInt32, self._rect, ident, ours) != 0
        row = first + dr.select(rect, dr.select(si.uv.y > si.uv.x, 1, 0), si.prim_index)
        p = mi.Vector3d(prev_si.p)
        a, b, c, n = self._vertices(row, ours)
        if self.exact:
            total = mi.Float64(0.0)
            for w in self._exact_weights(p):
                if w is not None:
                    total += w
            lum = dr.gather(mi.Float64, self._lum, row, ours)
            front = dr.dot(p - a, n) > 0.0
            pdf = dr.select(front & (total > 0.0), lum / dr.select(total > 0.0, total, 1.0), 0.0)
        else:
            omega = spherical_triangle_solid_angle(a - p, b - p, c - p)
            pmf = mi.Float64(self._power.eval_pmf_normalized(row, ours))
            front = dr.dot(p - a, n) > 0.0
            pdf = dr.select(front & (omega > 0.0), pmf / dr.select(omega > 0.0, omega, 1.0), 0.0)
        return dr.select(ours, mi.Float(pdf) * self.p_table, mitsuba_pdf)


def build(scene: Any, emitter_sampling: str) -> LightTable | None:
    """The light table of *scene* for ``emitter_sampling`` ('area': None, Mitsuba samples its emitters)."""
    if emitter_sampling == "area":
        return None
    table = LightTable(scene)
    return table if table.count else None
