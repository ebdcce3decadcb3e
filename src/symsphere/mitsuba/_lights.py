"""Light sampling by solid angle for ``symsphere_path`` (``emitter_sampling='solid_angle'``; ``'projected'``
and ``'cosine'``: at Lambertian vertices by projected solid angle, see :meth:`LightTable.sample_direction`
and :func:`._projected.cosine_table_sample`).

Mitsuba 3 samples a ``rectangle`` or triangle-mesh area emitter by area and converts the density to
solid angle, so a point near a large light gets wildly varying weights ``d^2 / cos``.  Here every
triangle of those emitters (a rectangle is two) is a row of a table (:class:`LightTable`), and at a
shading point p:

1. one triangle is chosen with probability proportional to an estimate of its contribution,
   ``w_i = Omega_i(p) L_e c_i`` (:func:`._light_rows.triangle_weight`): its solid angle seen from p (Van
   Oosterom & Strackee) times a scalar radiance of its emitter (the mean of its RGB value or texture)
   times the receiver's cosine c_i, ``|n.v|`` summed over the unit vectors v from p to the vertices (n the
   geometric normal at p; unsigned: 0 only for a triangle in p's tangent plane), 0 behind the triangle
   (area emitters are one-sided).  Up to :data:`EXACT_MAX` triangles every w_i is evaluated (unrolled,
   the triangles constants of the kernel; float32 sums: u has 24 bits), but where every run of
   :data:`CLUSTER_ROWS` of an emitter's triangles (in a spatial order) is small as seen from p
   (:data:`CLUSTER_BELOW`) a run by its importance and its triangle by power, no w_i evaluated.  Above,
   through a tree of fixed
   depth over a spatial order (:func:`._light_rows.tree_spans`): at most :data:`TREE_TOP` runs at the top
   (constants), each of :data:`FANOUT` runs of the level below (gathered), down to leaves of
   :data:`TREE_LEAF` triangles; a run is chosen by an importance ``power cos cos_r / d^2`` of its bounds
   (:class:`._light_rows.Group`, as pbrt-v4's ``LightBounds::Importance``: 0 only where none of its triangles faces p;
   below the top with the top run's normal bound), a triangle of the leaf by the same importance of its centroid
   and power (:meth:`._light_choice.Choice._member_weights`); but where the chosen top
   run is small as seen from p (:data:`TOP_BELOW`) its triangle by power (an alias table), skipping the levels
   below (the choice: :class:`._light_choice.Choice`, the table's base);
2. a direction uniform in the chosen triangle's solid angle (Arvo's map,
   :func:`symsphere.mitsuba._warps.square_to_spherical_triangle`, in float32 as Mitsuba's own sampling),
   but where the triangle is small as seen from p (:data:`AREA_BELOW`) a point uniform in its area,
   density ``d^2 / (A |cos|)``; a table of at most :data:`TINY_MAX` triangles small as seen from p
   (:data:`TINY_BELOW`) chooses by power and samples by area (for one emitter's triangles: that emitter's
   own sampling by area, the same density);
3. the point q where the direction meets the triangle's plane is shadow-tested as Mitsuba tests its
   own samples, and the emitter's ``eval_direction`` gives the radiance there.

Each of these rules is deterministic in p and gives every triangle facing p a positive probability, so
the estimate is unbiased.  The density is ``P(i) / Omega_i`` (by area ``P(i) d^2 / (A |cos|)``;
:meth:`LightTable.pdf_direction`, which no hit needs: ``symsphere_path`` samples so at diffuse vertices
only, where a BSDF-sampled ray that hits such an emitter counts 0; elsewhere :meth:`sample_direction`
samples every emitter as ``scene.sample_emitter_direction`` does).  Every other emitter (sphere, disk,
point, spot, directional, environment, constant) keeps Mitsuba's own sampling: with probability
``P_other`` (their Mitsuba selection probabilities, summed) one of them is chosen as Mitsuba would; the
table's triangles share the rest.  Emitters Mitsuba never chooses (``sampling_weight`` 0) stay out.
"""

from __future__ import annotations

from typing import Any

import drjit as dr
import mitsuba as mi
import numpy as np

from ._light_choice import (
    CLUSTER_BELOW,
    CLUSTER_ROWS,
    EXACT_MAX,
    FANOUT,
    TOP_BELOW,
    TREE_LEAF,
    TREE_SOFT,
    TREE_TOP,
    Choice,
)
from ._light_rows import (
    alias_pick,
    alias_rows,
    area_direction,
    branch,
    column,
    pick,
    registry_ids,
    scalar_radiance,
    shape_id,
    share,
    small_sphere,
    small_triangle,
    spatial_order,
    tree_order,
    triangles,
    uniform_rgb,
)
from ._projected import choose_projected, cosine_table_sample, square_to_projected_triangle
from ._warps import square_to_spherical_triangle, unit_spherical_triangle_solid_angle

__all__ = ["AREA_BELOW", "CLUSTER_BELOW", "CLUSTER_ROWS", "EMITTER_SAMPLINGS", "EXACT_MAX", "FANOUT", "LightTable", "SELECT_MAX", "TINY_BELOW", "TINY_MAX",
           "TREE_LEAF", "TOP_BELOW", "TREE_SOFT", "TREE_TOP", "alias_pick", "alias_rows", "build"]  # fmt: skip

EMITTER_SAMPLINGS = ("area", "cosine", "projected", "solid_angle")
"""The values of ``symsphere_path``'s ``emitter_sampling``, sorted."""
AREA_BELOW = 0.3
"""A chosen triangle whose bounding radius (about its centroid) is below this times the centroid's distance
from p is sampled by area, not by Arvo's map (0: never).  Measured: 0.6 lost 20 % under the disk."""
TINY_MAX = 2
"""A table of at most this many triangles: where its bounding radius is below :data:`TINY_BELOW` times
its centre's distance from p, a triangle is chosen by its power and sampled by area."""
TINY_BELOW = 0.45
SELECT_MAX = 4
"""A table of at most this many rows selects a chosen row's vertices, normal, RGB radiance and emitter from
constants instead of gathering them (measured: 2 and 4 rows 2.3-2.6 % more paths/s with full paths, 26 rows
the same paths/s as the gathers)."""
_NONE = 0xFFFFFFFF  # no table row: the shape is not one of the table's emitters


class LightTable(Choice):
    """The emitter triangles of a scene and their selection (see the module docstring)."""

    head: Any = None  # emitter_sampling='cosine': its choice and direction (_projected.cosine_table_sample)
    _own_below: float | None = None

    def __init__(self, scene: Any, projected: bool = False) -> None:
        self.projected = projected  # cosine-weighted sampling where sample_direction is given the lanes
        emitters = scene.emitters()
        pmf = [float(scene.pdf_emitter(mi.UInt32(i))[0]) for i in range(len(emitters))]
        rows: list[np.ndarray] = []
        uv_rows: list[np.ndarray] = []
        emitter_rows: list[int] = []
        radiance: list[float] = []
        rgb_rows: list[np.ndarray | None] = []
        shape_rows: dict[int, tuple[int, bool]] = {}  # shape id -> (first row, is a rectangle)
        in_table = [False] * len(emitters)
        starts: list[int] = []  # the first row of each shape
        # an emitter's index: its Python object is the list's (nanobind keeps one per C++ object); else by its
        # Dr.Jit registry id, whose array read inside a render ran the render's scheduled variables (3 %)
        emitter_index: dict[int, int] | None = None
        for shape in scene.shapes():
            emitter = shape.emitter()
            if emitter is None:
                continue
            index = next((i for i, e in enumerate(emitters) if e is emitter), None)
            if index is None:
                if emitter_index is None:
                    emitter_index = {int(k): i for i, k in enumerate(registry_ids(scene.emitters_dr()))}
                index = emitter_index.get(int(registry_ids(mi.EmitterPtr(emitter))[0]))
            if index is None or pmf[index] <= 0.0:
                continue
            found = triangles(shape)
            if found is None or len(found[0]) == 0:
                continue
            tris, uvs = found
            in_table[index] = True
            shape_rows[shape_id(shape)] = (sum(len(r) for r in rows), shape.class_name() == "Rectangle")
            rows.append(tris)
            uv_rows.append(uvs)
            emitter_rows += [index] * len(tris)
            starts.append(len(emitter_rows) - len(tris))
            radiance += [scalar_radiance(emitter)] * len(tris)
            rgb_rows.append(uniform_rgb(emitter))
            rgb_rows[-1:] = [rgb_rows[-1]] * len(tris)
        self.count = sum(len(r) for r in rows)
        # every emitter of the scene is in the table: a ray can find no other emission
        self.covers_all = all(in_table)
        self.p_other = float(sum(p for p, t in zip(pmf, in_table, strict=True) if not t))
        self.p_table = 1.0 - self.p_other if self.count else 0.0
        if not self.count:
            return
        tris = np.concatenate(rows)
        uvs = np.concatenate(uv_rows)
        lum = np.asarray(radiance)
        emitter_of = np.asarray(emitter_rows, dtype=np.uint32)
        # the spatial order: the tree's runs, an exact table's runs of CLUSTER_ROWS within each emitter
        order = _tree_order(tris) if self.count > EXACT_MAX else np.arange(self.count)
        if TINY_MAX < self.count <= EXACT_MAX:
            stops = [*starts[1:], self.count]
            order = np.concatenate([a + spatial_order(tris[a:b]) for a, b in zip(starts, stops, strict=True)])
        tris, uvs, lum, emitter_of = tris[order], uvs[order], lum[order], emitter_of[order]
        row_of = np.empty(self.count, dtype=np.uint32)
        row_of[order] = np.arange(self.count, dtype=np.uint32)  # table index (shape's first + prim) -> row
        Choice.__init__(self, tris, lum, starts)
        # every table emitter's radiance one RGB value: gathered, instead of a call of the emitter per sample
        self._rgb = None
        if all(rgb is not None for rgb in rgb_rows):
            rgb = np.asarray(rgb_rows, dtype=np.float32)[order]
            self._rgb = [column(rgb[:, j]) for j in range(3)]
            self._rgb_values = rgb
        self._uv = [column(uvs[:, k, j]) for k in range(3) for j in range(2)]
        self._emitter = column(emitter_of, mi.UInt32)
        self._emitter_values = emitter_of
        self._row_of = column(row_of, mi.UInt32)
        size = max(shape_rows) + 1
        first, rect = np.full(size, _NONE, dtype=np.uint32), np.zeros(size, dtype=np.uint32)
        for ident, (row, is_rect) in shape_rows.items():
            first[ident], rect[ident] = row, int(is_rect)
        self._first, self._rect = column(first, mi.UInt32), column(rect, mi.UInt32)
        # a tiny table (as the Cornell box's two triangles): where its bounding sphere is small as seen
        # from p, a triangle is chosen by its power (constants: no weight is evaluated)
        self._tiny = None
        self._own_emitter: int | None = None
        if self.count <= TINY_MAX:
            centre = tris.reshape(-1, 3).mean(axis=0)
            self._tiny = (mi.ScalarVector3f(*centre), float(np.max(np.linalg.norm(tris - centre, axis=2))))
            self._tiny_power = [float(w) if w > 0.0 else None for w in self.area * self.lum]
            # the planes of its triangles (unit normal, offset), in front of which they light
            normals = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
            lengths = np.linalg.norm(normals, axis=1)
            self._tiny_planes = [
                (mi.ScalarVector3f(*(nt / ln)), float(np.dot(nt / ln, t[0])))
                for nt, ln, t in zip(normals, lengths, tris, strict=True)
                if ln > 0.0
            ]
            # one emitter's triangles (a rectangle): its power shares are its area shares, so "by power, then
            # by area" is its own sampling by area (the same density), which far lanes may call instead
            if len(set(emitter_rows)) == 1:
                self._own_emitter = emitter_rows[0]
        # a table of one emitter: Mitsuba's CDF below it (its lanes' choice of another emitter is Mitsuba's
        # choice of a moved u: see _sample_own)
        self._own_below = float(sum(pmf[: emitter_rows[0]])) if len(set(emitter_rows)) == 1 else None

        others = [p if not t else 0.0 for p, t in zip(pmf, in_table, strict=True)]
        self._other = mi.DiscreteDistribution(mi.Float(others)) if self.p_other > 0.0 else None

    def vertices(self, row: Any, active: Any) -> tuple[Any, Any, Any, Any]:
        """:meth:`Choice.vertices`, but for a table of at most :data:`SELECT_MAX` rows selected from constants
        (no gathers: 2.5 % of the wall washer's time with full paths)."""
        if self.count > SELECT_MAX:
            return Choice.vertices(self, row, active)
        tris, normal = self.tris.astype(np.float32), self.normal.astype(np.float32)
        a, b, c = (
            mi.Vector3f(*(self._row_value(tris[:, k, j], None, row, active) for j in range(3))) for k in range(3)
        )
        return a, b, c, mi.Vector3f(*(self._row_value(normal[:, j], None, row, active) for j in range(3)))

    def _row_value(self, values: np.ndarray, col: Any, row: Any, active: Any) -> Any:
        """values[row] (*col*: the same values as a Dr.Jit array): gathered, or for a table of at most
        :data:`SELECT_MAX` rows selected from constants (0 outside *active*, as a gather)."""
        kind = mi.UInt32 if values.dtype == np.uint32 else mi.Float
        if self.count > SELECT_MAX:
            return dr.gather(kind, col, row, active)
        cast = int if kind is mi.UInt32 else float
        out: Any = kind(cast(values[0]))
        for i in range(1, len(values)):
            out = dr.select(row == i, cast(values[i]), out)
        return dr.select(active, out, 0)

    # --- sampling (next-event estimation) ------------------------------------------------------------

    def sample_direction(
        self, scene: Any, si: Any, sample: Any, active: Any, *, table: Any = None, cos: Any = None, only: bool = False
    ) -> tuple[Any, Any, Any]:
        """Like ``scene.sample_emitter_direction(si, sample, True, active)``: (ds, radiance / pdf, ours),
        with ``ds.d``, ``ds.pdf`` (solid angle, selection included) and ``ds.delta`` set; visibility
        tested.  *ours*: the lanes whose sample is the table's.  *table*: the lanes where the table
        samples (None: every lane); elsewhere Mitsuba's own emitter sampling, with the operations of
        ``scene.sample_emitter_direction`` (so its density there is ``scene.pdf_emitter_direction``'s).

        *cos* (``emitter_sampling='projected'``): the lanes (Lambertian vertices) where the table's
        triangle is chosen by its projected solid angle about the shading normal (on the side of si.wi)
        x radiance and the direction drawn by projected solid angle
        (:func:`symsphere.mitsuba._projected.square_to_projected_triangle`); their density is then not the
        one :meth:`pdf_direction` gives, so the caller weights their BSDF hits on the table's emitters 0
        (light sampling alone).  *only*: every lane is such a lane (the solid-angle technique is
        not traced)."""
        cosine, cosine_only = cos, only
        u = mi.Float(sample.x)
        ds = dr.zeros(mi.DirectionSample3f)
        weight = dr.zeros(mi.Spectrum)
        lanes = active if table is None else active & table
        ours = lanes & (u < self.p_table)
        mitsuba = None if table is None else active & ~table
        other = lanes & ~ours if self._other is not None else None
        own = mitsuba if other is None else (other if mitsuba is None else other | mitsuba)
        # a tiny table of one emitter, far from p: the table's "by power, then by area" is that emitter's own
        # sampling by area (the same density), so these lanes call it where emitters are called anyway (in
        # the branch of the others, or for a radiance not one RGB value; with neither the rows are faster)
        far = None
        if self._own_emitter is not None and not cosine_only and (own is not None or self._rgb is None):
            far = ours & self._far(mi.Vector3f(si.p))
            far = far if cosine is None else far & ~cosine
            own = far if own is None else own | far
        if own is not None:
            # one emitter's own sampling: outside the table's lanes any emitter, chosen as Mitsuba chooses
            # (scene.sample_emitter_direction); in them one of the emitters outside the table, by their
            # Mitsuba probabilities.  A branch: a packet of lanes with none of these skips it
            ds, weight = branch(own, lambda: self._sample_own(scene, si, sample, u, own, other, mitsuba, far))
        if self.count:
            near = ours if far is None else ours & ~far
            # the whole sample (point, normal, uv, emitter), so that the emitter can be evaluated at it
            # again (a differential mode re-attaches the radiance's derivative that way)
            ds_table, value = branch(
                near, lambda: self._sample_table(scene, si, u / self.p_table, sample.y, near, cosine, cosine_only)
            )
            ds = dr.select(near, ds_table, ds)
            weight = dr.select(near, value, weight)
        # one shadow ray for every kind of sample, as Mitsuba tests its own (a ray to the sampled point,
        # shortened; a coplanar surface, as the Cornell box's ceiling around its light, does not occlude).
        # An occluded sample has density 0: a differential mode re-attaches the emitter's derivative
        # wherever the density is not 0
        tested = active & (ds.pdf != 0.0)
        visible = tested & ~scene.ray_test(si.spawn_ray_to(ds.p), tested)
        ds.pdf = dr.select(visible, ds.pdf, 0.0)
        weight = dr.select(visible, weight, 0.0)
        return ds, weight, ours

    def _sample_own(
        self, scene: Any, si: Any, sample: Any, u: Any, own: Any, other: Any, mitsuba: Any, far: Any = None
    ) -> Any:
        """(ds, radiance / pdf) at the lanes *own*: :meth:`sample_direction`'s emitters that sample
        themselves (*other*: those outside the table, at the table's lanes; *mitsuba*: any, elsewhere;
        *far*: the table's lanes where its one emitter samples itself by area)."""
        if self._own_below is not None and len(scene.emitters()) > 1:
            # one emitter in the table: its lanes' choice (u < p_table: it, far; else the others by their Mitsuba
            # probabilities) is Mitsuba's choice of u moved, measure-preserving, so that [0, p_table) lands on its
            # interval: one scene.sample_emitter for every lane (2 % of the textured scene's time, full paths)
            below = self._own_below
            moved = dr.select(u < self.p_table, u + below, dr.select(u < self.p_table + below, u - self.p_table, u))
            at, inv, u_at = scene.sample_emitter(moved if mitsuba is None else dr.select(mitsuba, u, moved), own)
            return self._emit(scene, si, at, u_at, sample.y, scene.pdf_emitter(at, own), inv, own)
        index: Any = mi.UInt32(0)
        u_x: Any = u
        selection: Any = mi.Float(1.0)
        inverse: Any = mi.Float(1.0)
        if other is not None:
            distribution: Any = self._other  # not None where there are emitters outside the table
            u_other: Any = dr.clip((u - self.p_table) / self.p_other, 0.0, 1.0 - 2.0**-24)
            index, u_x, _ = distribution.sample_reuse_pmf(u_other, other)
            selection = self.p_other * distribution.eval_pmf_normalized(index, other)
            inverse = dr.rcp(selection)
        if mitsuba is not None and len(scene.emitters()) > 1:
            index_m, inverse_m, u_m = scene.sample_emitter(u, mitsuba)
            index = dr.select(mitsuba, index_m, index)
            u_x = dr.select(mitsuba, u_m, u_x)
            selection = dr.select(mitsuba, scene.pdf_emitter(index_m, mitsuba), selection)
            inverse = dr.select(mitsuba, inverse_m, inverse)
        elif mitsuba is not None:  # Mitsuba's single emitter samples itself without a choice
            u_x = dr.select(mitsuba, u, u_x)
            selection, inverse = dr.select(mitsuba, 1.0, selection), dr.select(mitsuba, 1.0, inverse)
        if far is not None:  # the table chosen with p_table, its emitter samples itself (by area)
            index = dr.select(far, self._own_emitter, index)
            u_x = dr.select(far, dr.minimum(u / self.p_table, 1.0 - 2.0**-24), u_x)
            selection, inverse = dr.select(far, self.p_table, selection), dr.select(far, 1.0 / self.p_table, inverse)
        return self._emit(scene, si, index, u_x, sample.y, selection, inverse, own)

    @staticmethod
    def _emit(scene: Any, si: Any, index: Any, u_x: Any, v: Any, selection: Any, inverse: Any, own: Any) -> Any:
        """The emitter *index*'s own sample at *si* (its selection probability and inverse given)."""
        emitter = dr.gather(mi.EmitterPtr, scene.emitters_dr(), index, own)
        ds, weight = emitter.sample_direction(si, mi.Point2f(u_x, v), own)
        own = own & (ds.pdf != 0.0)
        ds.pdf = dr.select(own, ds.pdf * selection, 0.0)
        return ds, dr.select(own, weight * inverse, 0.0)

    def _sample_table(
        self, scene: Any, si: Any, u: Any, v: Any, active: Any, cosine: Any, cosine_only: bool
    ) -> tuple[Any, Any]:
        p = mi.Vector3f(si.p)
        if self.head is not None:  # emitter_sampling='cosine' (symsphere.mitsuba._projected)
            row, ok, a, b, c, n, pdf, d = self.head(self, si, p, u, v, active, cosine)
        elif not cosine_only:  # by solid angle (a triangle small as seen from p: by area, see _small)
            row, ok, a, b, c, n, pdf, d = self.sample_triangle(p, u, v, active, mi.Vector3f(si.n))
        if cosine is not None and self.head is None:  # by projected solid angle
            mine = active & cosine
            normal = dr.mulsign(mi.Vector3f(si.sh_frame.n), si.wi.z)
            row_c, probability_c, u_c = choose_projected(self, p, normal, mi.Float64(u), mine, mi.Vector3f(si.n))
            ok_c = mine & (probability_c > 0.0)
            a_c, b_c, c_c, n_c = self.vertices(row_c, ok_c)
            d_c, pdf_c = square_to_projected_triangle(
                a_c - p, b_c - p, c_c - p, normal, mi.Point2f(mi.Float(u_c), mi.Float(v))
            )
            ok_c &= (dr.dot(p - a_c, n_c) > 0.0) & (pdf_c > 0.0)
            pdf_c = mi.Float(self.p_table * probability_c * mi.Float64(pdf_c))
            if cosine_only:
                row, ok, a, b, c, n, pdf, d = row_c, ok_c, a_c, b_c, c_c, n_c, pdf_c, d_c
            else:
                row, ok, pdf, d = (
                    dr.select(mine, row_c, row),
                    dr.select(mine, ok_c, ok),
                    dr.select(mine, pdf_c, pdf),
                    dr.select(mine, d_c, d),
                )
                a, b, c, n = (dr.select(mine, x_c, x) for x_c, x in ((a_c, a), (b_c, b), (c_c, c), (n_c, n)))
        active = ok
        # The point q where d meets the triangle's plane (shadow-tested by the caller), and the emitter
        # evaluated there (texture coordinates interpolated, where a radiance is not one value).
        cos_n = dr.dot(d, n)
        t_plane = dr.dot(a - p, n) / dr.select(cos_n != 0.0, cos_n, 1.0)
        q = p + t_plane * d
        ds: Any = dr.zeros(mi.DirectionSample3f)
        ds.p = mi.Point3f(q)
        ds.n = mi.Normal3f(dr.normalize(n))
        if self._rgb is None:
            n2 = dr.squared_norm(n)
            n2 = dr.select(n2 > 0.0, n2, 1.0)
            lb = dr.dot(dr.cross(q - a, c - a), n) / n2
            lc = dr.dot(dr.cross(b - a, q - a), n) / n2
            uv = [dr.gather(mi.Float, col, row, active) for col in self._uv]
            ds.uv = mi.Point2f(
                uv[0] + lb * (uv[2] - uv[0]) + lc * (uv[4] - uv[0]),
                uv[1] + lb * (uv[3] - uv[1]) + lc * (uv[5] - uv[1]),
            )
        ds.d = d
        ds.dist = t_plane
        ds.emitter = dr.gather(
            mi.EmitterPtr,
            scene.emitters_dr(),
            self._row_value(self._emitter_values, self._emitter, row, active),
            active,
        )
        active &= t_plane > 0.0
        if self._rgb is None:
            radiance: Any = ds.emitter.eval_direction(si, ds, active)
        else:  # the area emitter's eval_direction: its value on the front side (cos_n < 0), else 0
            lit = active & (cos_n < 0.0)
            radiance = mi.Spectrum(
                *(self._row_value(self._rgb_values[:, j], col, row, lit) for j, col in enumerate(self._rgb))
            )
            radiance = dr.select(lit, radiance, 0.0)
        value = dr.select(active & (pdf > 0.0), radiance / dr.select(pdf > 0.0, pdf, 1.0), 0.0)
        ds.pdf = dr.select(active, pdf, 0.0)
        ds.delta = mi.Bool(False)
        return ds, value

    def sample_triangle(self, p: Any, u: Any, v: Any, active: Any, n: Any, warp: Any = None) -> tuple[Any, ...]:
        """The table's sample at p (vectors mi.Vector3f; *n* the receiver's normal of the choice): (row, valid
        lanes, its vertices a, b, c and unnormalised normal, the density with the choice and p_table, the
        direction).  A triangle by :meth:`choose_near`, a direction in it by :meth:`_direction` (*warp*:
        its other maps)."""
        row, probability, u_map, far = self.choose_near(p, u, active, n)
        ok = active & (probability > 0.0)
        a, b, c, tn = self.vertices(row, ok)
        d, inv = self._direction(a - p, b - p, c - p, tn, (mi.Float(u_map), mi.Float(v)), ok, far, warp)
        ok &= (dr.dot(p - a, tn) > 0.0) & (inv > 0.0)
        pdf = mi.Float(self.p_table * probability / mi.Float64(dr.select(inv > 0.0, inv, 1.0)))
        return row, ok, a, b, c, tn, pdf, d

    def choose_near(self, p: Any, u: Any, active: Any, n: Any) -> tuple[Any, Any, Any, Any]:
        """(row, probability, u reused, :meth:`_far`'s lanes): :meth:`choose`, but by power where a tiny
        table is far from p."""
        far = self._far(p)
        if far is None:
            return (*self.choose(p, mi.Float64(u), active, n), None)
        # by power: constants, outside the branch (a branch's literal result, as the row of a table with one
        # triangle of power, failed Dr.Jit 1.5's LLVM backend: "does not dominate all uses")
        by_power = pick(self._tiny_weights(), mi.Float64(u))

        def by_weight(*_: Any) -> tuple[Any, Any, Any]:
            return self.choose(p, mi.Float64(u), active, n)

        chosen = dr.if_stmt(args=by_power, cond=active & ~far, true_fn=by_weight, false_fn=lambda *power: power)
        return (*chosen, far)

    def _far(self, p: Any) -> Any:
        """The lanes where a tiny table's bounding sphere is small as seen from p (radius below
        :data:`TINY_BELOW` times its centre's distance; None: not a tiny table)."""
        if self._tiny is None:
            return None
        return small_sphere(p, *self._tiny, TINY_BELOW)

    def hand_far_lanes(self, scene: Any = None) -> Any:
        """Give up the points where a tiny table is far from p (:meth:`_far`) or p is behind (or on) the
        plane of each of its triangles: returns a function of p giving those lanes (None: not a tiny table),
        and this table never samples there (its choice, density and sampling as for a table without the
        far rule).  ``symsphere_path`` samples those vertices as Mitsuba's ``path`` does, with its MIS,
        where no last ray is saved by light sampling alone (a scene not all diffuse, or with emitters
        outside the table): far, "by power, then by area" is Mitsuba's sampling of the emitter, so the
        table's technique differed only by the missing MIS (the textured scene: 0.984x ``path``'s relMSE,
        now its image bit for bit); behind, the table has nothing to sample (a vertex on the light itself,
        whose default BSDF is diffuse), yet its lanes ran the table's branch.  A deterministic rule of p:
        unbiased (each vertex's weights sum to 1).  With *scene*: where no diffuse-only surface of it has a
        point near the table and in front of it (bounding boxes, :meth:`_reached`), every lane (a constant:
        the table's code is not traced; in the textured scene 2-3 % of the time)."""
        tiny = self._tiny
        if tiny is None:
            return None
        planes = self._tiny_planes
        self._tiny, self._own_emitter = None, None
        margin = 1e-4 * tiny[1]
        if scene is not None and not self._reached(scene, tiny, planes, margin):
            return lambda p: mi.Bool(True)

        def lanes(p: Any) -> Any:
            mine = small_sphere(p, *tiny, TINY_BELOW)
            if planes:
                behind = mi.Bool(True)
                for normal, offset in planes:  # behind every triangle's plane (on it, as on the light itself)
                    behind &= dr.dot(p, normal) - offset <= margin
                mine |= behind
            return mine

        return lanes

    @staticmethod
    def _reached(scene: Any, tiny: Any, planes: Any, margin: float) -> bool:
        """Whether a shape whose BSDF may be diffuse only has a bounding box that reaches closer to the tiny
        table's centre than its far radius (:data:`TINY_BELOW`, with a slack) and a corner in front of one of
        its triangles' planes (more than *margin*): conservative, so that a lane near the table can occur
        only in a scene where this is True."""
        centre, radius = np.asarray(tiny[0], dtype=np.float64), float(tiny[1])
        reach = 1.001 * radius / TINY_BELOW
        bad = int(mi.BSDFFlags.Glossy | mi.BSDFFlags.Delta)
        for shape in scene.shapes():
            bsdf = shape.bsdf()
            flags = None if bsdf is None else int(bsdf.flags())
            if flags is not None and (not flags & int(mi.BSDFFlags.Diffuse) or flags & bad):
                continue
            box = shape.bbox()
            lo, hi = np.asarray(box.min, dtype=np.float64), np.asarray(box.max, dtype=np.float64)
            if np.sum(np.square(np.clip(centre, lo, hi) - centre)) > reach * reach:
                continue
            corners = np.array([[(lo, hi)[k >> j & 1][j] for j in range(3)] for k in range(8)])
            if any(np.max(corners @ np.asarray(n, dtype=np.float64)) - offset > margin for n, offset in planes):
                return True
        return False

    def _tiny_weights(self) -> list[Any]:  # a tiny table's triangles by power
        return [None if w is None else mi.Float(w) for w in self._tiny_power]

    def _small(self, a: Any, b: Any, c: Any, far: Any = None) -> Any:
        """The lanes sampled by area: *far*, or the triangle (vertices relative to p) small as seen from p
        (:func:`._light_rows.small_triangle` with :data:`AREA_BELOW`)."""
        small = small_triangle(a, b, c, AREA_BELOW)
        return small if far is None else small | far

    def _direction(
        self, a: Any, b: Any, c: Any, n: Any, uv: Any, active: Any, far: Any = None, warp: Any = None
    ) -> tuple[Any, Any]:
        """(unit direction, 1 / its solid-angle density) towards the triangle a, b, c (relative to p; n
        its unnormalised normal): by area where :meth:`_small` (:func:`._light_rows.area_direction`), else
        by Arvo's map (the solid angle) in a branch that a packet of lanes all small skips.  *warp*: other
        maps, ``warp(a, b, c, uv, lanes, d, inv) -> (d, inv, lanes left to Arvo's map)`` at the lanes not
        small (``emitter_sampling='cosine'``).  Each lane's density is its technique's; no MIS at the
        table's vertices: any deterministic criterion is unbiased."""

        def arvo(*_: Any) -> tuple[Any, Any]:
            direction, omega = square_to_spherical_triangle(uv, a, b, c)
            return dr.normalize(direction), omega

        small = self._small(a, b, c, far)
        by_area = area_direction(a, b, c, n, *uv)
        if warp is None:
            return dr.if_stmt(args=(), cond=active & ~small, true_fn=arvo, false_fn=lambda: by_area)
        d, inv, rest = warp(a, b, c, uv, active & ~small, *by_area)
        return dr.if_stmt(args=(d, inv), cond=rest, true_fn=arvo, false_fn=lambda *x: x)

    # --- the density of a hit (MIS) ----------------------------------------------------------------

    def holds(self, si: Any, active: Any) -> Any:
        """The lanes whose *si* lies on one of the table's emitters."""
        return self._first_rows(si, active)[2]

    def _first_rows(self, si: Any, active: Any) -> tuple[Any, Any, Any]:
        """(shape id, its first row, the lanes on a table emitter) of the shape hit at *si*."""
        ident = registry_ids(si.shape)
        valid = active & si.is_valid() & (ident < dr.width(self._first))
        first = dr.gather(mi.UInt32, self._first, ident, valid)
        return ident, first, valid & (first != _NONE)

    def pdf_direction(self, scene: Any, prev_si: Any, si: Any, ds: Any, active: Any) -> Any:
        """The density (solid angle) with which :meth:`sample_direction` (at its table's lanes, by solid
        angle) samples the emitter hit at *si* from *prev_si*: ``sample_direction``'s other half, as
        ``scene.pdf_emitter_direction`` is Mitsuba's.  ``symsphere_path`` needs it at no hit (the table
        samples only at diffuse vertices, whose BSDF hits on the table's emitters count 0); the tests
        check the sampling against it."""
        # Mitsuba's density for its own emitters (none when every emitter it may choose is in the table)
        ident, first, ours = self._first_rows(si, active)
        mitsuba_pdf = scene.pdf_emitter_direction(prev_si, ds, active & ~ours) if self.p_other > 0.0 else mi.Float(0.0)
        rect = dr.gather(mi.UInt32, self._rect, ident, ours) != 0
        index = first + dr.select(rect, dr.select(si.uv.y > si.uv.x, 1, 0), si.prim_index)
        row = dr.gather(mi.UInt32, self._row_of, index, ours)
        p = mi.Vector3f(prev_si.p)
        a, b, c, n = self.vertices(row, ours)
        # the map's own solid angle (the same operations on the same float32 values as in sampling)
        omega = unit_spherical_triangle_solid_angle(dr.normalize(a - p), dr.normalize(b - p), dr.normalize(c - p))
        front = (dr.dot(p - a, n) > 0.0) & (omega > 0.0)
        probability = self.probability(mi.Vector3f(prev_si.p), row, ours, mi.Vector3f(prev_si.n))
        pdf = dr.select(front, probability / dr.select(omega > 0.0, omega, 1.0), 0.0)
        far = self._far(p)
        if far is not None:
            probability = dr.select(far, share(self._tiny_weights(), row), probability)
        small = self._small(a - p, b - p, c - p, far)  # by area:
        dist = dr.norm(mi.Vector3f(si.p) - p)  # d^2 / (A |cos|) = 2 d^3 / |(a - p).n|
        height = dr.abs(dr.dot(a - p, n))
        by_area = mi.Float64(2.0 * dist * dist * dist / dr.select(height > 0.0, height, 1.0))
        pdf = dr.select(small, dr.select(front & (height > 0.0), probability * by_area, 0.0), pdf)
        return dr.select(ours, mi.Float(pdf) * self.p_table, mitsuba_pdf)


_ORDERS: dict[bytes, np.ndarray] = {}


def _tree_order(tris: np.ndarray) -> np.ndarray:
    """:func:`._light_rows.tree_order`, once per set of triangles (8 ms for 1026 triangles, at every render)."""
    key = tris.tobytes()
    if key not in _ORDERS:
        while len(_ORDERS) >= 4:
            _ORDERS.pop(next(iter(_ORDERS)))
        _ORDERS[key] = tree_order(tris)
    return _ORDERS[key]


def build(scene: Any, emitter_sampling: str) -> LightTable | None:
    """The light table of *scene* for ``emitter_sampling`` ('area': None, Mitsuba samples its emitters)."""
    if emitter_sampling == "area":
        return None
    table = LightTable(scene, projected=emitter_sampling in ("cosine", "projected"))
    table.head = cosine_table_sample if emitter_sampling == "cosine" else None
    return table if table.count else None
