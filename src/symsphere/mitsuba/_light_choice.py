"""The choice of a light triangle at a shading point: :class:`Choice`, the base of
:class:`._lights.LightTable` (its rows' vertices, the weights and the tree; see :mod:`._lights`).

Up to :data:`EXACT_MAX` triangles every weight ``Omega_i(p) L_e c_i`` is evaluated
(:func:`._light_rows.triangle_weight`), unless (more than :data:`CLUSTER_ROWS` triangles) every group of at
most :data:`CLUSTER_ROWS` of an emitter's triangles is small as seen from p (:data:`CLUSTER_BELOW`): then a
group by its importance (:class:`._light_rows.Group`) and its triangle by power.  Above, a tree of fixed
depth (:func:`._light_rows.tree_spans`) over compact runs (:func:`._light_rows.tree_order`): a top run by its
importance, by power below it where it is small as seen from p (:data:`TOP_BELOW`), else through the levels
below to a leaf and a triangle of it by its importance as a group of one, every node and triangle below a
top run taking the run's normal bound (:meth:`Choice._cone`: fewer gathers, the descent's cost on Zen 4).
:meth:`Choice.probability` is the probability of a row under the same rules (each deterministic in p, every
triangle facing p kept choosable)."""

from __future__ import annotations

from typing import Any

import drjit as dr
import mitsuba as mi
import numpy as np

from ._light_rows import (
    REACH,
    Group,
    Level,
    alias_pick,
    alias_rows,
    column,
    importance,
    pick,
    share,
    small_sphere,
    tree_spans,
    triangle_weight,
    weight_sum,
)

__all__ = [
    "CLUSTER_BELOW",
    "CLUSTER_ROWS",
    "EXACT_MAX",
    "FANOUT",
    "TOP_BELOW",
    "TREE_LEAF",
    "TREE_SOFT",
    "TREE_TOP",
    "Choice",
]

EXACT_MAX = 64
"""Up to this many emitter triangles, each is evaluated at every shading point to choose one; above,
a triangle is chosen through a tree (TREE_LEAF, FANOUT, TREE_TOP)."""
TREE_LEAF, FANOUT, TREE_TOP = 8, 4, 40
"""Above EXACT_MAX: a tree over the spatial order, leaves of TREE_LEAF triangles under levels of FANOUT
nodes, at most TREE_TOP nodes at the top."""
TOP_BELOW = 0.25
"""Where the top run chosen at p is small as seen from p (its bounding radius below this times its centre's
distance), its triangle is chosen by power (an alias table), not through the levels below (0: never)."""
TREE_SOFT = 0.1
"""The tree's runs are weighed with the distance ``sqrt(d^2 + TREE_SOFT r^2)`` (:class:`._light_rows.Group`)."""
CLUSTER_BELOW = 0.4
"""From CLUSTER_ROWS + 1 up to EXACT_MAX triangles (fewer: the test costs what the weights it skips do,
docs/results/light-selection-cost.md): where every group of an emitter's triangles (CLUSTER_ROWS) is
small as seen from p (its bounding radius below this times its centre's distance), a group is chosen by its
importance (:class:`._light_rows.Group`) and its triangle by power (an alias table), without the triangles'
weights (0: never)."""


CLUSTER_ROWS = 8
"""CLUSTER_BELOW's groups: runs of at most this many rows of one emitter (in a spatial order), so that a large
emitter is small as seen from p in parts, and the choice among them follows the light's falloff over it."""


_BUILT: dict[tuple[Any, ...], dict[str, Any]] = {}
_BUILT_MAX = 4  # the choices kept (of the last scenes rendered)


class Choice:
    """The rows (triangles, their normals and radiances) and the choice of one at a point p."""

    def __init__(self, tris: np.ndarray, lum: np.ndarray, starts: list[int]) -> None:
        """*tris* (n, 3, 3) in the table's order, *lum* their scalar radiances, *starts* the first row of
        each emitter (rows of an emitter are consecutive up to EXACT_MAX).  Built once per content (and
        rules): ``symsphere_path`` builds its table at every render, and the tree's groups took 13 ms of a
        1024-triangle light's (3 % of a 128 x 128, 32 spp render with full paths); a scene whose emitters
        move or change gets a new one."""
        key = (mi.variant(), tris.shape, tris.tobytes(), np.asarray(lum, dtype=np.float64).tobytes(), tuple(starts),
               EXACT_MAX, TREE_LEAF, FANOUT, TREE_TOP, TREE_SOFT, CLUSTER_BELOW, CLUSTER_ROWS, REACH)  # fmt: skip
        built = _BUILT.get(key)
        if built is None:
            blank = Choice.__new__(Choice)
            blank._build(tris, lum, starts)
            built = _BUILT[key] = vars(blank)
            while len(_BUILT) > _BUILT_MAX:  # the oldest first
                _BUILT.pop(next(iter(_BUILT)))
        vars(self).update(built)  # read only: shared by the tables of one content

    def _build(self, tris: np.ndarray, lum: np.ndarray, starts: list[int]) -> None:
        self.count = count = len(tris)
        normal = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
        self.area = area = 0.5 * np.linalg.norm(normal, axis=1)
        lum = np.where(area > 0.0, lum, 0.0)  # a degenerate triangle is never chosen
        self.tris, self.normal, self.lum = tris, normal, lum
        self._columns32 = [column(tris[:, k, j]) for k in range(3) for j in range(3)]
        self._normal32 = [column(normal[:, j]) for j in range(3)]
        self._lum32 = column(lum)
        centroid = tris.mean(axis=1)
        self._centroid = [column(centroid[:, j]) for j in range(3)]
        self._power32 = column(area * lum)
        tri_radius = np.max(np.linalg.norm(tris - centroid[:, None], axis=2), axis=1)
        # the levels: one triangle each up to EXACT_MAX, else runs of the spatial order (tree_spans)
        self.spans = tree_spans(count, EXACT_MAX, TREE_LEAF, FANOUT, TREE_TOP)
        self.group_size = self.spans[-1]  # the rows of a leaf (of the last level)
        self.mode = "exact" if count <= EXACT_MAX else "tree"

        def runs(span: int) -> list[Group]:
            return [Group(tris, normal, area, lum, k, min(k + span, count)) for k in range(0, count, span)]

        self.groups = groups = runs(self.spans[0])
        self._levels = [Level(runs(span), TREE_SOFT) for span in self.spans[1:]]  # gathered: the nodes below the top
        self._fanouts = [a // b for a, b in zip(self.spans, self.spans[1:], strict=False)]
        self._top = Level(groups, TREE_SOFT)  # the top level gathered: the density of a chosen row
        if self.mode == "tree":  # a leaf's members: the largest member's radius, a bound of float32's rounding
            self._leaf_radius = column(np.maximum.reduceat(tri_radius, np.arange(0, count, self.group_size)))
            self._member_slack = 1e-5 * float(np.max(tri_radius + np.linalg.norm(centroid, axis=1)))
        # small as seen from p: a tree's top run, or every group of an exact table, chooses by power (choose)
        self._clusters: list[Group] | None = None
        if self.mode == "tree":
            keep, alias, shares = alias_rows(area * lum, self.spans[0])
        elif count > CLUSTER_ROWS and CLUSTER_BELOW > 0.0:  # fewer rows: their weights cost what the test does
            # runs of at most CLUSTER_ROWS rows of an emitter (the table orders each emitter's rows spatially)
            starts = [k for a, b in zip(starts, [*starts[1:], count], strict=True) for k in range(a, b, CLUSTER_ROWS)]
            sizes = np.diff([*starts, count])
            self._clusters = [Group(tris, normal, area, lum, a, a + k) for a, k in zip(starts, sizes, strict=True)]
            keep, alias, shares = alias_rows(area * lum, starts)
            self._cluster_start = column(np.asarray(starts, dtype=np.uint32), mi.UInt32)
            self._cluster_size = column(sizes.astype(np.uint32), mi.UInt32)
            self._cluster_of = column(np.repeat(np.arange(len(starts)), sizes).astype(np.uint32), mi.UInt32)
        if self.mode == "tree" or self._clusters is not None:
            self._keep, self._alias = column(keep.astype(np.float32)), column(alias, mi.UInt32)
            self._share = column(shares.astype(np.float32))

    def luminance(self, row: Any, active: Any) -> Any:
        """The scalar radiance of the rows *row* (float32)."""
        return dr.gather(mi.Float, self._lum32, row, active)

    def vertices(self, row: Any, active: Any) -> tuple[Any, Any, Any, Any]:
        c = [dr.gather(mi.Float, col, row, active) for col in self._columns32]
        n = [dr.gather(mi.Float, col, row, active) for col in self._normal32]
        return (
            mi.Vector3f(c[0], c[1], c[2]),
            mi.Vector3f(c[3], c[4], c[5]),
            mi.Vector3f(c[6], c[7], c[8]),
            mi.Vector3f(*n),
        )

    def _group_weights(self, p: Any, n: Any = None) -> list[Any]:
        """The top level's weights at p (float32; None for a group that is never chosen): a triangle's
        exact weight, or a group's importance (see :class:`Group`)."""
        weights: list[Any] = []
        for g in self.groups:
            if g.power <= 0.0:
                weights.append(None)
            elif g.stop - g.start == 1:
                a, b, c = (mi.ScalarVector3f(*vertex) for vertex in self.tris[g.start])
                weights.append(
                    triangle_weight(p, a, b, c, mi.ScalarVector3f(*self.normal[g.start]), float(self.lum[g.start]), n)
                )
            else:
                weights.append(g.importance(p, TREE_SOFT, n))
        return weights

    def _cone(self, node: Any, active: Any) -> list[Any]:
        """The top run *node*'s normal bound (its axis and spread, :class:`._light_rows.Group`), which every
        node and triangle below it takes for its own (a looser bound: 4 gathers instead of 4 per node and 3
        per triangle)."""
        return [dr.gather(mi.Float, self._top.fields[k], node, active) for k in (4, 5, 6, 7)]

    def _member_weights(self, p: Any, start: Any, active: Any, receiver: Any = None, cone: Any = None) -> list[Any]:
        """The weights at p of the rows [start, start + group_size) of a leaf, slot by slot: each triangle's
        importance as a group of its own (:func:`._light_rows.importance`: its centroid and power, the leaf's
        largest triangle radius, the normal bound *cone* of its top run, :meth:`_cone`, and for the offset
        only float32's rounding: a flat triangle's points lie in its plane): 4 gathers per triangle where a
        proxy of its exact weight took 7 (gathers are most of the descent's cost on an AMD Zen 4); 0 only where
        the triangle does not face p."""
        radius = dr.gather(mi.Float, self._leaf_radius, start // self.group_size, active)
        reach = REACH * radius
        weights = []
        for k in range(self.group_size):
            row = start + k
            ok = active & (row < self.count)
            g = [dr.gather(mi.Float, col, row, ok) for col in self._centroid]
            power = dr.gather(mi.Float, self._power32, row, ok)
            fields = [*g, radius, *cone, mi.Float(self._member_slack), power, reach]
            weights.append(dr.select(ok, importance(p, fields, TREE_SOFT, receiver), 0.0))
        return weights

    def descend(self, p: Any, u: Any, active: Any, n: Any = None, top: Any = None) -> tuple[Any, Any, Any]:
        """(node of the last level: the row in exact mode, else a leaf; its probability; u reused): a node
        of the top by its weight (*top*: already chosen), then a child of it by its importance, level by level."""
        return self._descend(p, u, active, n, top)[:3]

    def _descend(self, p: Any, u: Any, active: Any, n: Any = None, top: Any = None) -> tuple[Any, Any, Any, Any]:
        """:meth:`descend` and the normal bound of the top run chosen (:meth:`_cone`; None in exact mode)."""
        node, probability, u = pick(self._group_weights(p, n), u) if top is None else top
        cone = self._cone(node, active & (probability > 0.0)) if self.mode == "tree" else None
        for level, fanout in zip(self._levels, self._fanouts, strict=True):
            first = node * fanout
            slot, fraction, u = pick(level.weights(p, first, fanout, active & (probability > 0.0), n, cone), u)
            probability *= fraction
            node = first + slot
        return node, probability, u, cone

    def _clusters_far(self, p: Any) -> Any:
        """The lanes where every group (:data:`CLUSTER_ROWS`) is small as seen from p (:data:`CLUSTER_BELOW`): a test
        of constants, before any triangle's weight."""
        far = mi.Bool(True)
        for g in self._clusters or []:
            if g.power > 0.0:
                far &= small_sphere(p, mi.ScalarVector3f(*g.centre), g.radius, CLUSTER_BELOW)
        return far

    def _cluster_weights(self, p: Any, n: Any) -> list[Any]:  # the emitters' importances at p (exact mode)
        return [g.importance(p, TREE_SOFT, n) if g.power > 0.0 else None for g in self._clusters or []]

    def _top_far(self, p: Any, node: Any, active: Any) -> Any:
        """The lanes where the top run *node* is small as seen from p (:data:`TOP_BELOW`)."""
        centre = mi.Vector3f(*(dr.gather(mi.Float, self._top.fields[k], node, active) for k in range(3)))
        return active & small_sphere(p, centre, dr.gather(mi.Float, self._top.fields[3], node, active), TOP_BELOW)

    def choose(self, p: Any, u: Any, active: Any, n: Any = None) -> tuple[Any, Any, Any]:
        """(row, its probability at p, u reused) for the point p (mi.Vector3f) and u (mi.Float64).  Exact: each
        triangle by its weight, but where every group of an emitter's triangles is small as seen from p
        (:meth:`_clusters_far`) a group by its importance and its triangle by power.  Tree: a top run by its importance, then, where
        it is small as seen from p, its triangle by power, else a leaf through the levels below and its
        triangle by the members' weights.  The weights in a branch that a packet of lanes all small skips."""
        if self.mode == "exact" and self._clusters is None:
            return self.descend(p, u, active, n)
        if self.mode == "exact":
            far = active & self._clusters_far(p)
            cluster, fraction, u_c = pick(self._cluster_weights(p, n), u)
            start = dr.gather(mi.UInt32, self._cluster_start, cluster, far)
            size = dr.gather(mi.UInt32, self._cluster_size, cluster, far)
            row, u_far = alias_pick(self._keep, self._alias, start, size, u_c, far)
            by_power = (row, fraction * mi.Float64(dr.gather(mi.Float, self._share, row, far)), u_far)

            def exact(*_: Any) -> tuple[Any, Any, Any]:
                return self.descend(p, u, active, n)

            return dr.if_stmt(args=by_power, cond=active & ~far, true_fn=exact, false_fn=lambda *power: power)
        node, probability, u = pick(self._group_weights(p, n), u)
        ok = active & (probability > 0.0)
        far = self._top_far(p, node, ok)
        span = self.spans[0]
        row, u_far = alias_pick(
            self._keep, self._alias, node * span, dr.minimum(span, self.count - node * span), u, far
        )
        by_power = (row, probability * mi.Float64(dr.gather(mi.Float, self._share, row, far)), u_far)

        def below(*_: Any) -> tuple[Any, Any, Any]:
            leaf, leaf_p, u_leaf, cone = self._descend(p, u, ok, n, (node, probability, u))
            start = leaf * self.group_size
            slot, fraction, u_leaf = pick(self._member_weights(p, start, ok & (leaf_p > 0.0), n, cone), u_leaf)
            return start + slot, leaf_p * fraction, u_leaf

        return dr.if_stmt(args=by_power, cond=ok & ~far, true_fn=below, false_fn=lambda *power: power)

    def _first_level_weight(self, p: Any, row: Any, active: Any, n: Any = None) -> Any:
        """The top level's weight at p of the group (exact: the triangle) that holds *row*, from gathered
        values: the bits of :meth:`_group_weights`' entry."""
        if self.mode == "exact":
            c = [dr.gather(mi.Float, col, row, active) for col in self._columns32]
            tn = mi.Vector3f(*(dr.gather(mi.Float, col, row, active) for col in self._normal32))
            lum = dr.gather(mi.Float, self._lum32, row, active)
            a, b, cc = mi.Vector3f(c[0], c[1], c[2]), mi.Vector3f(c[3], c[4], c[5]), mi.Vector3f(c[6], c[7], c[8])
            return dr.select(lum > 0.0, triangle_weight(p, a, b, cc, tn, lum, n), 0.0)
        return self._top.weight(p, row // self.spans[0], active, n)

    def probability(self, p: Any, row: Any, active: Any, n: Any = None) -> Any:
        """The probability with which :meth:`choose` at p picks *row*: the product of its shares, level by level."""
        total = mi.Float64(weight_sum(self._group_weights(p, n)))
        mine = mi.Float64(self._first_level_weight(p, row, active, n))
        probability = dr.select(total > 0.0, mine / dr.select(total > 0.0, total, 1.0), 0.0)
        if self.mode == "exact" and self._clusters is None:
            return probability
        if self.mode == "exact":
            far = active & self._clusters_far(p)
            cluster = share(self._cluster_weights(p, n), dr.gather(mi.UInt32, self._cluster_of, row, far))
            return dr.select(far, cluster * mi.Float64(dr.gather(mi.Float, self._share, row, far)), probability)
        far = self._top_far(p, row // self.spans[0], active)
        by_power = probability * mi.Float64(dr.gather(mi.Float, self._share, row, far))
        cone = self._cone(row // self.spans[0], active)
        for level, fanout, span in zip(self._levels, self._fanouts, self.spans[1:], strict=True):
            node = row // span
            first = node // fanout * fanout
            probability *= share(level.weights(p, first, fanout, active, n, cone), node - first)
        start = row // self.group_size * self.group_size
        members = self._member_weights(p, start, active, n, cone)
        return dr.select(far, by_power, probability * share(members, row - start))
