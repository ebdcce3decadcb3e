"""The rows of ``symsphere_path``'s light table (:mod:`._lights`): the emitter triangles of a scene's
``rectangle`` and mesh area emitters, their radiance, their spatial order and groups (the first level of
the choice above :data:`._lights.EXACT_MAX` triangles), and a branch that carries a direction sample."""

from __future__ import annotations

from typing import Any

import drjit as dr
import mitsuba as mi
import numpy as np

__all__ = ["REACH", "alias_pick", "read", "alias_rows", "area_direction", "branch", "column", "importance", "pick", "scalar_radiance", "share",
           "registry_ids", "shape_id", "small_sphere", "small_triangle", "spatial_order", "tree_order", "tree_spans", "triangle_weight",
           "triangles", "uniform_rgb", "unit_clip", "weight_sum", "Group", "Level"]  # fmt: skip


def registry_ids(pointers: Any) -> Any:
    """The Dr.Jit registry ids (UInt32) of an array of Mitsuba object pointers."""
    return dr.reinterpret_array(mi.UInt32, pointers)


def shape_id(shape: Any) -> int:
    return int(registry_ids(mi.ShapePtr(shape))[0])


_READ: dict[tuple[int, ...], tuple[Any, np.ndarray]] = {}


def _variables(value: Any) -> tuple[int, ...] | None:
    """The Dr.Jit variables that hold *value* (a JIT array, nested, or a tensor); None otherwise."""
    if dr.is_tensor_v(value):
        value = value.array
    if not dr.is_jit_v(value):
        return None
    if dr.depth_v(value) == 1:
        return (value.index,) if value.index else None
    ids: list[int] = []
    for part in value:
        inner = _variables(part)
        if inner is None:
            return None
        ids += inner
    return tuple(ids)


def read(value: Any) -> np.ndarray:
    """``np.asarray(value, dtype=np.float64)``, read once per Dr.Jit variable: an emitter's radiance and a
    rectangle's transform are literals, and reading one inside a render evaluated the render's scheduled
    variables in a kernel of their own (3-4 % of the wall washer's CPU time at 128 x 128, 32 spp).  A
    parameter set anew (``mi.traverse``) is a new variable; the value read keeps its variables alive, so that
    their numbers are not reused while it is kept."""
    ids = _variables(value)
    if ids is None:
        return np.asarray(value, dtype=np.float64)
    if ids not in _READ:
        while len(_READ) >= 64:
            _READ.pop(next(iter(_READ)))
        _READ[ids] = (value, np.asarray(value, dtype=np.float64))
    return _READ[ids][1].copy()


def scalar_radiance(emitter: Any) -> float:
    """A scalar radiance of an area emitter: the mean of its RGB value (of the texture's mean), else 1."""
    params = mi.traverse(emitter)
    for key in ("radiance.value", "radiance.data"):
        if key in params:
            value = read(params[key])
            if value.size and np.all(np.isfinite(value)):
                return float(np.mean(np.maximum(value, 0.0)))
    return 1.0


def uniform_rgb(emitter: Any) -> np.ndarray | None:
    """The radiance of an area emitter whose radiance is one RGB value, in an RGB variant (what its
    ``eval_direction`` returns on its front side); None otherwise (a texture, a spectrum)."""
    params = mi.traverse(emitter)
    if not mi.is_rgb or "radiance.value" not in params or "radiance.data" in params:
        return None
    value = read(params["radiance.value"]).astype(np.float32).ravel()
    return value if value.size == 3 else None


def triangles(shape: Any) -> tuple[np.ndarray, np.ndarray] | None:
    """The triangles (n, 3, 3) of a rectangle or mesh, in the orientation of its emitting side, and their
    vertices' texture coordinates (n, 3, 2); None for other shapes."""
    name = shape.class_name()
    if name == "Rectangle":
        m = read(mi.traverse(shape)["to_world"].matrix).reshape(4, 4)
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


def _facing(tris: np.ndarray) -> np.ndarray:
    """Each triangle's class: the axis its normal is closest to, 2 * axis, + 1 where the normal points down it."""
    normal = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    axis = np.argmax(np.abs(normal), axis=1)
    facing: np.ndarray = 2 * axis + (normal[np.arange(len(normal)), axis] < 0)
    return facing


def spatial_order(tris: np.ndarray) -> np.ndarray:
    """An order of the triangles by the axis their normal is closest to (and its sign), then along a
    Morton curve of their centroids: runs of it are compact, similarly oriented groups."""
    facing, centroid = _facing(tris), tris.mean(axis=1)
    lo, hi = centroid.min(axis=0), centroid.max(axis=0)
    cells = ((centroid - lo) / np.where(hi > lo, hi - lo, 1.0) * 1023).astype(np.int64)
    code = np.zeros(len(tris), dtype=np.int64)
    for bit in range(10):
        for k in range(3):
            code |= ((cells[:, k] >> bit) & 1) << (3 * bit + k)
    return np.lexsort((code, facing))


def tree_order(tris: np.ndarray) -> np.ndarray:
    """The tree's order (:func:`tree_spans`): by the axis their normal is closest to (and its sign), then
    a bounding-volume split: the centroids sorted along their longest extent, the first 2^k (the least
    power of two >= half) split off and both parts split again.  Every aligned run of 2^j rows inside a
    part is then one of its halves' halves, compact in every axis: a Morton curve of the centroids scaled
    to the unit cube (:func:`spatial_order`) ran through the dome of a nearly flat light as through its
    width, which left runs of 32 triangles with radii up to 4x their size (their importance a poor
    estimate of their light)."""
    facing, centroid = _facing(tris), tris.mean(axis=1)
    order: list[np.ndarray] = []
    stack = [np.flatnonzero(facing == f) for f in np.unique(facing)[::-1]]
    while stack:  # depth first, the first part first
        rows = stack.pop()
        if len(rows) <= 2:
            order.append(rows)
            continue
        c = centroid[rows]
        rows = rows[np.argsort(c[:, np.argmax(np.ptp(c, axis=0))], kind="stable")]
        half = 1 << int(np.ceil(np.log2(len(rows) / 2)))
        stack += [rows[half:], rows[:half]]
    return np.concatenate(order)


REACH = 0.1
"""The receiver's cosine bound of a group takes ``REACH r`` for r (see :class:`Group`)."""


class Group:
    """A run of rows [start, stop) (a node of the choice, :func:`tree_spans`) and the constants of its
    importance at a point p: ``power cos cos_r / D^2``, D = ``sqrt(d^2 + k r^2)`` (k: :data:`._lights.TREE_SOFT`;
    ``max(d, r)`` gave the near runs too little), d = |p - centre|, r the radius of its bounding sphere about
    the centre; cos = ``((p - centre).axis + h + s D) / D`` clipped to [0, 1]
    (axis the mean normal; s the largest distance between a member's unit normal and it, plus 1e-5 for
    float32's rounding; h the largest ``(centre - a_t).n_t`` over the members t, a_t a vertex and n_t the
    unit normal: 0 for a flat group, where r, before, made the bound loose near the light's plane), 1 when
    the normals spread over more than 60 degrees (axis 0, s = 1, h = r); cos_r (given a receiver normal
    n at p) ``(|(p - centre).n| + REACH r) / D`` clipped to [0, 1], an estimate of the receiver's
    cosine (r itself, a bound, weighed the far groups near p's horizon too much).  It is 0 only where no
    member faces p: for x in a member t, (p - x).n_t = (p - centre).n_t + (centre - a_t).n_t <=
    (p - centre).axis + d s + h, and D >= d.  (Light sampling alone at diffuse vertices needs this: a triangle never
    chosen there would be lost.)"""

    def __init__(self, tris: np.ndarray, normal: np.ndarray, area: np.ndarray, lum: np.ndarray, start: int, stop: int):
        self.start, self.stop = start, stop
        weights = area[start:stop] * lum[start:stop]
        self.power = float(weights.sum())
        centroid = tris[start:stop].mean(axis=1)
        self.centre = centroid.mean(axis=0)
        self.radius = float(np.max(np.linalg.norm(tris[start:stop] - self.centre, axis=2)))
        unit = normal[start:stop] / np.maximum(np.linalg.norm(normal[start:stop], axis=1, keepdims=True), 1e-300)
        mean = (unit * area[start:stop, None]).sum(axis=0)
        mean /= max(float(np.linalg.norm(mean)), 1e-300)
        self.axis = mean if np.all(unit @ mean > 0.5) else None
        spread = float(np.max(np.linalg.norm(unit - mean, axis=1))) + 1e-5
        # float32's rounding of p - centre and of the vertices: 1e-5 of the group's scale
        slack = 1e-5 * (self.radius + float(np.linalg.norm(self.centre)))
        offset = float(np.max(np.einsum("ij,ij->i", self.centre - tris[start:stop, 0], unit))) + slack
        axis = np.zeros(3) if self.axis is None else self.axis
        spread, offset = (1.0, self.radius) if self.axis is None else (spread, offset)
        # the importance's constants, in this order (a Level gathers the same)
        self.fields = (*self.centre, self.radius, *axis, spread, offset, self.power, REACH * self.radius)

    def importance(self, p: Any, soft: float, n: Any = None) -> Any:
        return importance(p, [mi.Float(x) for x in self.fields], soft, n)


def importance(p: Any, fields: list[Any], soft: float, n: Any = None) -> Any:
    """A group's importance at p (see :class:`Group`, *soft* its k) from its fields, float32 literals or
    gathered values alike: the same operations, so that both give the same bits."""
    cx, cy, cz, radius, ax, ay, az, spread, offset, power, reach = fields
    e = p - mi.Vector3f(cx, cy, cz)
    d2 = dr.squared_norm(e)
    q = d2 + soft * (radius * radius)
    inv = dr.rsqrt(q)
    d = q * inv  # >= |p - centre|: the bound below holds
    value = power * inv * inv
    value *= unit_clip((dr.dot(e, mi.Vector3f(ax, ay, az)) + offset + spread * d) * inv)
    if n is not None:  # the receiver's cosine, unsigned
        value *= unit_clip((dr.abs(dr.dot(e, n)) + reach) * inv)
    return dr.select(power > 0.0, value, 0.0)


def unit_clip(x: Any) -> Any:
    """``dr.clip(x, 0, 1)`` for finite x (bit for bit; NaN gives 0) by two comparisons: Dr.Jit's
    ``dr.maximum`` and ``dr.minimum`` are LLVM's NaN-propagating ``maximum`` and ``minimum``, six AVX-512
    instructions each, where a comparison and a select are one (vmaxps, vminps); the top of the light tree
    evaluates four per run at every vertex."""
    x = dr.select(x > 0.0, x, 0.0)
    return dr.select(x < 1.0, x, 1.0)


def tree_spans(count: int, exact_max: int, leaf: int, fanout: int, top: int) -> list[int]:
    """The rows per node at each level of the choice, top first: [1] (every triangle weighed) up to
    *exact_max* rows; beyond, leaves of *leaf* rows under levels of *fanout* children each, until at most
    *top* nodes remain at the top."""
    if count <= exact_max:
        return [1]
    spans = [leaf]
    while -(-count // spans[0]) > top:
        spans.insert(0, spans[0] * fanout)
    return spans


def column(values: Any, kind: Any = None) -> Any:
    """A Dr.Jit array of a table column, padded to two entries (never gathered from: rows < count).
    A kernel gathering from a one-entry array is not found in Dr.Jit's kernel cache when the table is
    built again (each render): 0.30 s against 0.016 s per render of a one-triangle light (64 x 64, 4 spp)."""
    values = np.ascontiguousarray(values)
    if values.size == 1:
        values = np.concatenate([values, np.zeros(1, dtype=values.dtype)])
    return (kind or mi.Float)(values)


class Level:
    """The groups of one level (runs of the same span) as arrays of their fields: their importances at p
    from gathered values."""

    def __init__(self, groups: list[Group], soft: float) -> None:
        self.count, self.soft = len(groups), soft
        self.fields = [column(field) for field in np.array([g.fields for g in groups], dtype=np.float32).T]

    def weight(self, p: Any, node: Any, active: Any, n: Any = None) -> Any:
        """The importance at p of the group *node* (0 where not *active*)."""
        w = importance(p, [dr.gather(mi.Float, col, node, active) for col in self.fields], self.soft, n)
        return dr.select(active, w, 0.0)

    def weights(self, p: Any, first: Any, fanout: int, active: Any, n: Any = None, cone: Any = None) -> list[Any]:
        """The importances at p of the groups [first, first + fanout) (0 past the last one); with *cone* (the
        axis and spread of a group that holds them all) each takes that normal bound for its own, and its reach
        from its radius: 6 gathers instead of 11 (a looser bound: the axis's spread over more normals)."""
        if cone is None:
            return [self.weight(p, first + k, active & (first + k < self.count), n) for k in range(fanout)]
        weights = []
        for k in range(fanout):
            ok = active & (first + k < self.count)
            cx, cy, cz, radius, offset, power = (
                dr.gather(mi.Float, self.fields[j], first + k, ok) for j in (0, 1, 2, 3, 8, 9)
            )
            fields = [cx, cy, cz, radius, *cone, offset, power, REACH * radius]
            weights.append(dr.select(ok, importance(p, fields, self.soft, n), 0.0))
        return weights


def triangle_weight(p: Any, a: Any, b: Any, c: Any, n: Any, lum: Any, receiver: Any = None) -> Any:
    """``Omega(p) L_e`` in float32, 0 behind the triangle: a selection weight (its rounding only changes
    which triangle is chosen how often; the density divides by the map's solid angle)."""
    front = dr.dot(p - a, n) > 0.0
    a, b, c = a - p, b - p, c - p
    la, lb, lc = dr.norm(a), dr.norm(b), dr.norm(c)
    triple = dr.abs(dr.dot(a, dr.cross(b, c)))
    den = la * lb * lc + dr.dot(a, b) * lc + dr.dot(a, c) * lb + dr.dot(b, c) * la
    omega = 2.0 * dr.atan2(triple, den)
    value = omega * lum
    if receiver is not None:  # the receiver's unsigned cosine at the vertices (see :mod:`._lights`)
        cos = dr.abs(dr.dot(a, receiver)) / la + dr.abs(dr.dot(b, receiver)) / lb + dr.abs(dr.dot(c, receiver)) / lc
        value *= dr.select(dr.squared_norm(receiver) > 0.0, cos, 1.0)
    return dr.select(front & (omega > 0.0), value, 0.0)


def small_sphere(p: Any, centre: Any, radius: Any, tau: float) -> Any:
    """The lanes where the sphere (centre, radius) is small as seen from p: radius < tau |p - centre|."""
    return radius * radius < (tau * tau) * dr.squared_norm(p - centre)


def small_triangle(a: Any, b: Any, c: Any, tau: float) -> Any:
    """The lanes where the triangle a, b, c (vectors from p) is small as seen from p: its bounding radius
    about its centroid below tau times the centroid's distance."""
    centre = (a + b + c) * (1.0 / 3.0)
    r2 = dr.maximum(dr.maximum(dr.squared_norm(a - centre), dr.squared_norm(b - centre)), dr.squared_norm(c - centre))
    return r2 < (tau * tau) * dr.squared_norm(centre)


def area_direction(a: Any, b: Any, c: Any, n: Any, u: Any, v: Any) -> tuple[Any, Any]:
    """(unit direction, 1 / its solid-angle density) of a point uniform in the area of the triangle a, b, c
    (vectors from p; n its unnormalised normal): Mitsuba's ``square_to_uniform_triangle`` (barycentrics
    ``(1 - sqrt(1 - u), sqrt(1 - u) v)``), density ``d^2 / (A |cos|)`` = ``2 d^3 / |a.n|`` (A = |n| / 2,
    |cos| = |a.n| / (|n| d)).  0 (density infinite: never used) where p lies in the triangle's plane."""
    t = dr.safe_sqrt(1.0 - u)
    q = a + (1.0 - t) * (b - a) + (t * v) * (c - a)
    dist = dr.norm(q)
    positive = dist > 0.0
    extent = dr.select(positive, dr.abs(dr.dot(a, n)) / dr.select(positive, 2.0 * dist * dist * dist, 1.0), 0.0)
    return q / dr.select(positive, dist, 1.0), extent


def alias_rows(weights: np.ndarray, span: int | list[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Walker's alias tables of the runs [k, k + span) of *weights* (or of the runs that start at the rows
    *span*, a sorted list beginning with 0): per row the probability of keeping it, its alias (a row of
    the same run, absolute) and its share of its run's weight (float64).  A row of weight 0 is never kept
    and never an alias."""
    count = len(weights)
    keep, alias, shares = np.ones(count), np.arange(count, dtype=np.uint32), np.zeros(count)
    starts = list(range(0, count, span)) if isinstance(span, int) else list(span)
    for start, stop in zip(starts, [*starts[1:], count], strict=True):
        w = np.asarray(weights[start:stop], dtype=np.float64)
        if w.sum() <= 0.0:
            continue
        shares[start : start + len(w)] = w / w.sum()
        scaled = w / w.sum() * len(w)
        small, large = [i for i in range(len(w)) if scaled[i] < 1.0], [i for i in range(len(w)) if scaled[i] >= 1.0]
        while small and large:
            s, big = small.pop(), large.pop()
            keep[start + s], alias[start + s] = scaled[s], start + big
            scaled[big] -= 1.0 - scaled[s]
            (small if scaled[big] < 1.0 else large).append(big)
        zero = np.flatnonzero(w <= 0.0)  # left over by rounding: never kept
        keep[start + zero], alias[start + zero] = 0.0, start + int(np.argmax(w))
    return keep, alias, shares


def alias_pick(keep: Any, alias: Any, start: Any, count: Any, u: Any, active: Any) -> tuple[Any, Any]:
    """(row, u reused) of a row of the run [start, start + count) by its alias table (:func:`alias_rows`;
    one gather of a kept fraction, one of an alias)."""
    x = mi.Float(u) * mi.Float(count)
    slot = dr.minimum(mi.UInt32(x), count - 1)
    frac = x - mi.Float(slot)
    q = dr.gather(mi.Float, keep, start + slot, active)
    kept = frac < q
    row = dr.select(kept, start + slot, dr.gather(mi.UInt32, alias, start + slot, active & ~kept))
    reused = dr.select(kept, frac / dr.select(q > 0.0, q, 1.0), (frac - q) / dr.select(q < 1.0, 1.0 - q, 1.0))
    return row, mi.Float64(dr.clip(reused, 0.0, 1.0))


def weight_sum(weights: list[Any]) -> Any:
    """The sum of the weights (None: left out) in float32, in order: :func:`pick`'s total."""
    total = mi.Float(0.0)
    for w in weights:
        if w is not None:
            total += w
    return total


def pick(weights: list[Any], u: Any) -> tuple[Any, Any, Any]:
    """(index, its probability, u reused) of a choice proportional to *weights* by u: float32 sums (u
    itself has 24 bits: float64 sums would not make the frequencies closer to the weights); the
    probability its weight over the total in float64 (0 where the total is 0)."""
    total = weight_sum(weights)
    target = mi.Float(u) * total
    index: Any = mi.UInt32(0)
    before, chosen, acc = mi.Float(0.0), mi.Float(0.0), mi.Float(0.0)
    for i, w in enumerate(weights):
        if w is None:
            continue
        take = (acc <= target) & (w > 0.0)
        index = dr.select(take, i, index)
        before = dr.select(take, acc, before)
        chosen = dr.select(take, w, chosen)
        acc += w
    reused = dr.clip((target - before) / dr.select(chosen > 0.0, chosen, 1.0), 0.0, 1.0)
    mine, whole = mi.Float64(chosen), mi.Float64(total)
    return index, dr.select(whole > 0.0, mine / dr.select(whole > 0.0, whole, 1.0), 0.0), mi.Float64(reused)


def share(weights: list[Any], index: Any) -> Any:
    """weights[index] / sum(weights), summed as :func:`pick` sums them (0 if the sum is 0; float64)."""
    total, mine = mi.Float64(weight_sum(weights)), mi.Float64(0.0)
    for i, w in enumerate(weights):
        if w is not None:
            mine = dr.select(index == i, mi.Float64(w), mine)
    return dr.select(total > 0.0, mine / dr.select(total > 0.0, total, 1.0), 0.0)


_FIELDS = ("p", "n", "uv", "time", "pdf", "delta", "d", "dist", "emitter")


def branch(cond: Any, sample: Any) -> tuple[Any, Any]:
    """``sample()`` -> (DirectionSample3f, weight) in a Dr.Jit branch taken by the lanes *cond* (a packet
    of lanes with none skips it), zeros elsewhere.  The sample crosses the branch field by field, and
    ``delta`` as a number: (Dr.Jit 1.5's LLVM backend emitted a mask defined inside the branch where a
    structure's boolean field was selected after it: "Instruction does not dominate all uses")."""

    def taken() -> tuple[Any, ...]:
        ds, weight = sample()
        fields = [getattr(ds, f) for f in _FIELDS]
        fields[5] = dr.select(ds.delta, mi.Float(1.0), mi.Float(0.0))
        return (*fields, weight)

    def skipped() -> tuple[Any, ...]:
        ds = dr.zeros(mi.DirectionSample3f)
        fields = [getattr(ds, f) for f in _FIELDS]
        fields[5] = mi.Float(0.0)
        return (*fields, dr.zeros(mi.Spectrum))

    out = dr.if_stmt(args=(), cond=cond, true_fn=taken, false_fn=skipped)
    ds = dr.zeros(mi.DirectionSample3f)
    for f, value in zip(_FIELDS, out[:-1], strict=True):
        setattr(ds, f, value)
    ds.delta = out[5] != 0.0
    return ds, out[-1]
