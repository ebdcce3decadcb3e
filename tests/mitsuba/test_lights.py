"""``symsphere_path``'s ``emitter_sampling='solid_angle'``: its density, its MIS, that it is unbiased.

Statistical tests (fixed seeds): the block test compares the mean image with Mitsuba's own ``path`` (the
independent reference), K independent renders each, block by block (4 x 4 pixels, the mean of R, G, B):
Welch's t-test, two-sided, significance 0.01 for the family with a Sidak correction over the
UNBIASED_TESTS blocks.  The furnace tests are z-tests of an image mean against the closed form at 0.01,
Sidak-corrected over the FURNACE_TESTS.  The normalisation test is a z-test of a Monte Carlo integral of
the density over the sphere (uniform directions from numpy, not from the code under test) against 1.
"""

from __future__ import annotations

import numpy as np
import pytest
from mitsuba_scenes import scene_dict
from scipy import stats

SIZE, SPP, SEEDS = 16, 32, 12
ALPHA = 0.01
SCENES = ("cornell", "textured", "mesh_light")
# (scene, max_depth): full paths in each scene; direct light only in the Cornell box, where every BSDF is
# diffuse and every emitter in the table, so that no ray towards a last vertex is traced
# (scene, max_depth, emitter_sampling); projected: Lambertian vertices by projected solid angle (every one in
# the Cornell box, some in the textured scene and the mesh-light scene)
UNBIASED_CASES = [(name, 6, "solid_angle") for name in SCENES] + [("cornell", 2, "solid_angle")]
UNBIASED_CASES += [("cornell", 2, "projected"), ("textured", 6, "projected"), ("mesh_light", 3, "projected")]
# where the map switches inside the image between Arvo's and sampling by area (a tiny table far from or near
# p; a disk's triangles small or not as seen from p): test_area_sampling_switches_inside_these_images
UNBIASED_CASES += [("near_rect", 3, "solid_angle"), ("near_disk", 3, "solid_angle")]
# the rectangle under a sky (Mitsuba's first emitter): where the rectangle is small as seen from p it samples
# itself, chosen as Mitsuba chooses with u moved onto its interval; near it the table (u < p_table)
UNBIASED_CASES += [("near_rect_sky", 3, "solid_angle")]
# a light of 320 triangles: a tree with a level between its top and its leaves (42 leaves > TREE_TOP)
UNBIASED_CASES += [("tree_light", 3, "solid_angle")]
# 24 + 12 triangles, each weighed, but by power where all runs of their rows are small as seen from p
UNBIASED_CASES += [("exact_light", 3, "solid_angle")]
UNBIASED_TESTS = len(UNBIASED_CASES) * (SIZE // 4) ** 2
FURNACE_TESTS = 6
BLOCK = 4


def _sidak(alpha, count):
    return 1.0 - (1.0 - alpha) ** (1.0 / count)


def _blocks(images):
    k = images.shape[0]
    lum = images.mean(axis=-1).reshape(k, SIZE // BLOCK, BLOCK, SIZE // BLOCK, BLOCK)
    return lum.mean(axis=(2, 4)).reshape(k, -1)


def _obj_box(path, n, inward=True):
    """The six faces of the box [-1, 1]^3, each cut into n x n squares (2 n^2 triangles), facing inward."""
    vertices, faces = [], []
    for axis in range(3):
        for side in (-1.0, 1.0):
            u_axis, v_axis = (axis + 1) % 3, (axis + 2) % 3
            base = len(vertices)
            for i in range(n + 1):
                for j in range(n + 1):
                    p = [0.0, 0.0, 0.0]
                    p[axis], p[u_axis], p[v_axis] = side, -1 + 2 * i / n, -1 + 2 * j / n
                    vertices.append(p)
            for i in range(n):
                for j in range(n):
                    a, b = base + i * (n + 1) + j, base + (i + 1) * (n + 1) + j
                    quad = (a, b, b + 1, a + 1)  # normal +axis for these (u, v) orders
                    flip = (side > 0) == inward
                    tri1, tri2 = (quad[0], quad[1], quad[2]), (quad[0], quad[2], quad[3])
                    faces += [t[::-1] if flip else t for t in (tri1, tri2)]
    with open(path, "w") as f:
        f.writelines(f"v {x} {y} {z}\n" for x, y, z in vertices)
        f.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces)
    return path


def _disk_obj(path, segments, radius=0.5, height=1.2, x0=0.0):
    """A disk light of *segments* triangles about (x0, height, 0), facing down (-y)."""
    lines = [f"v {x0} {height} 0\n"]
    for k in range(segments):
        phi = 2 * np.pi * k / segments
        lines.append(f"v {x0 + radius * np.cos(phi)} {height} {radius * np.sin(phi)}\n")
    for k in range(segments):
        lines.append(f"f 1 {k + 2} {(k + 1) % segments + 2}\n")  # counter-clockwise from below: normal -y
    with open(path, "w") as f:
        f.writelines(lines)
    return path


def _scene(mi, name, tmp_path, bare=False):
    if name not in ("mesh_light", "tree_light", "exact_light", "near_rect", "near_disk", "near_rect_sky"):
        return mi.load_dict(scene_dict(mi, name, SIZE))
    scene = scene_dict(mi, "textured", SIZE)
    del scene["light"]
    if name != "near_rect_sky":
        del scene["sky"]
    if name.startswith("near_rect"):  # one rectangle (a tiny table) 0.5 above the floor, facing it
        del scene["ball"], scene["glass"]
        T = mi.ScalarTransform4f
        scene["light"] = {"type": "rectangle", "to_world": T().translate([0, 0.5, 0]).rotate([1, 0, 0], 90).scale(0.6),
                          "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [6, 6, 5]}}}  # fmt: skip
        return mi.load_dict(scene)
    if name == "near_disk":  # a 24-triangle disk 0.4 above the floor
        del scene["ball"], scene["glass"]
        scene["light"] = {"type": "obj", "filename": str(_disk_obj(tmp_path / "disk24.obj", 24, radius=0.8, height=0.4)),
                          "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [6, 6, 5]}}}  # fmt: skip
        return mi.load_dict(scene)
    if bare:  # the lights and the floor only: nothing between a point above the floor and the lights
        del scene["ball"], scene["glass"], scene["wall"]
    # > EXACT_MAX: a tree (leaves under its top; 320: a level between); exact_light: 24 + 12, each weighed
    segments = {"tree_light": 320, "exact_light": 24}.get(name, 80)
    scene["light"] = {
        "type": "obj",
        "filename": str(_disk_obj(tmp_path / "disk.obj", segments)),
        "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [6, 6, 5]}},
    }
    scene["panel"] = {
        "type": "obj",
        "filename": str(_disk_obj(tmp_path / "panel.obj", 12, radius=0.4, height=2.0, x0=-2.0)),
        "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [3, 2, 2]}},
    }
    return mi.load_dict(scene)


def test_unknown_emitter_sampling_names_the_parameter_and_the_values(llvm):
    mi = llvm
    import symsphere.mitsuba  # noqa: F401

    with pytest.raises(RuntimeError) as info:
        mi.load_dict({"type": "symsphere_path", "emitter_sampling": "solid"})
    last = str(info.value).strip().splitlines()[-1]
    assert last.startswith("ValueError: ") and "'solid' is not a valid emitter_sampling" in last
    assert "use one of {'area', 'cosine', 'projected', 'solid_angle'}" in last


def test_the_density_of_a_hit_is_the_density_it_was_sampled_with(llvm, tmp_path):
    """The table's pair: for directions sampled at random shading points, the density ``pdf_direction``
    gives the emitter hit (selection probability x solid-angle density) equals the sampled one."""
    mi = llvm
    import drjit as dr

    from symsphere._testing import mitsuba_lights as lights

    for name in (*SCENES, "near_rect", "near_disk", "tree_light", "exact_light"):  # near_*: both maps
        scene = _scene(mi, name, tmp_path)
        table = lights.LightTable(scene)
        rng = np.random.default_rng(5)
        n = 4000
        origin = mi.Point3f(*(rng.uniform(-1.2, 1.2, n) for _ in range(2)), rng.uniform(-1.2, 1.2, n))
        origin.y = mi.Float(rng.uniform(0.05, 1.0, n))  # above the floor, below the lights
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.p = origin
        si.n = mi.Normal3f(0, 1, 0)
        si.sh_frame = mi.Frame3f(si.n)
        ds, weight, _ = table.sample_direction(scene, si, mi.Point2f(rng.random(n), rng.random(n)), mi.Bool(True))
        hit = scene.ray_intersect(mi.Ray3f(si.p, ds.d))  # from p itself: the points are on no surface
        # (the Cornell box's light is coplanar with its ceiling: a traced ray may hit either)
        lit = (dr.max(weight) > 0).numpy() & (hit.shape.emitter() != None).numpy()  # noqa: E711 - Dr.Jit
        assert lit.sum() > n // 10, name
        hit_ds = mi.DirectionSample3f(scene, si=hit, ref=si)
        pdf = table.pdf_direction(scene, si, hit, hit_ds, mi.Bool(True)).numpy()
        np.testing.assert_allclose(pdf[lit], ds.pdf.numpy()[lit], rtol=2e-3, err_msg=name)


def test_projected_direct_light_of_one_polygon_light_has_no_variance(llvm):
    """With ``projected``, the direct light at an unoccluded Lambertian point lit by one polygon light (a
    rectangle: two triangles, chosen by projected solid angle, then sampled by it) has a relative standard
    deviation <= 1e-3 per sample (the estimator is constant up to rounding), at points near and far."""
    mi = llvm
    import drjit as dr

    from symsphere._testing import mitsuba_lights as lights

    T = mi.ScalarTransform4f
    scene = mi.load_dict({
        "type": "scene",
        "light": {"type": "rectangle", "to_world": T().translate([0.3, 1.0, -0.2]).rotate([1, 0, 0], 70).scale([0.8, 0.5, 1]),
                  "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [4, 4, 4]}}},
    })  # fmt: skip
    table = lights.LightTable(scene, projected=True)
    rng = np.random.default_rng(15)
    n = 4000
    for x, z in ((0.0, 0.0), (0.9, -1.5), (-2.0, 1.0)):
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.p = mi.Point3f(x, 0.0, z)
        si.n = mi.Normal3f(0, 1, 0)
        si.sh_frame = mi.Frame3f(si.n)
        si.wi = mi.Vector3f(0, 0, 1)
        sample = mi.Point2f(rng.random(n), rng.random(n))
        ds, weight, _ = table.sample_direction(scene, si, sample, mi.Bool(True), cos=mi.Bool(True), only=True)
        value = (weight.x * dr.maximum(ds.d.y, 0.0)).numpy()  # L cos / pdf
        assert np.all(value > 0), (x, z)
        assert value.std() / value.mean() <= 1e-3, (x, z, value.std() / value.mean())


def _sphere_obj(path, rings=10, segments=16):
    """A UV sphere of radius 1 about the origin (2 rings x segments triangles, those at the poles
    degenerate), facing outward."""
    vertices = [
        (np.sin(t) * np.cos(f), np.cos(t), np.sin(t) * np.sin(f))
        for t in np.linspace(0, np.pi, rings + 1)
        for f in 2 * np.pi * np.arange(segments) / segments
    ]
    faces = []
    for i in range(rings):
        for j in range(segments):
            a, b = i * segments + j, i * segments + (j + 1) % segments
            c, d = a + segments, b + segments
            faces += [(a, b, c), (b, d, c)]
    with open(path, "w") as f:
        f.writelines(f"v {x} {y} {z}\n" for x, y, z in vertices)
        f.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces)
    return path


def test_every_triangle_facing_a_point_can_be_chosen_there(llvm, tmp_path):
    """Light sampling alone at diffuse vertices counts a triangle only through its choice: in a tree
    (320 triangles of a sphere facing outward, chosen through the tree: nodes whose normals differ), every triangle that a
    point outside sees from its front (by more than float32's rounding: some of them at grazing angles near
    the silhouette, from afar) has a choice probability > 0, with and without a receiver's normal (random:
    its cosine weights the choice, but is 0 for no triangle that could light the point)."""
    mi = llvm

    from symsphere._testing import mitsuba_lights as lights

    scene = mi.load_dict({
        "type": "scene",
        "ball": {"type": "obj", "filename": str(_sphere_obj(tmp_path / "sphere.obj")),
                 "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [1, 1, 1]}}},
    })  # fmt: skip
    table = lights.LightTable(scene)
    assert table.mode == "tree"
    rng = np.random.default_rng(14)
    g = rng.standard_normal((300, 3))
    points = g / np.linalg.norm(g, axis=1, keepdims=True) * rng.uniform(1.5, 6.0, (300, 1))
    rows = np.arange(table.count)
    p = np.repeat(points, table.count, axis=0)
    row = np.tile(rows, len(points))
    tris, normal = table.tris[row], table.normal[row]
    unit = normal / np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
    height = np.einsum("ij,ij->i", p - tris[:, 0], unit)
    # the pole's triangles have areas of 1e-17: their normals are rounding noise, their light nothing
    area = 0.5 * np.linalg.norm(normal, axis=1)
    facing = (height > 1e-4) & (table.lum[row] > 0) & (area > 1e-12)
    point = mi.Vector3f(*(mi.Float(p[:, k]) for k in range(3)))
    g = np.repeat(rng.standard_normal((len(points), 3)), table.count, axis=0)
    normal = mi.Vector3f(*(mi.Float(g[:, k] / np.linalg.norm(g, axis=1)) for k in range(3)))
    assert facing.sum() > 1000
    for receiver in (None, normal):  # without and with the receiver's cosine in the weights
        probability = table.probability(point, mi.UInt32(row), mi.Bool(True), receiver).numpy()
        assert np.all(probability[facing] > 0), np.flatnonzero(facing & (probability <= 0))[:5]


def test_choice_probabilities_sum_to_one_over_the_triangles(llvm, tmp_path):
    """Brute force: at random points with random receiver normals, the probabilities with which the table
    chooses each of its triangles (the exact choice of the Cornell box's 2 and of the 36 of a disk and a
    panel, by power where all their runs are small as seen from p, the tree of the mesh-light scene's 92: leaves
    under its top, and of the tree-light scene's 332: a level between) sum to 1 wherever a triangle faces
    the point, and a sampled row's probability is the one computed for it."""
    mi = llvm
    import drjit as dr

    from symsphere._testing import mitsuba_lights as lights

    rng = np.random.default_rng(21)
    for name, mode in (("cornell", "exact"), ("exact_light", "exact"), ("mesh_light", "tree"), ("tree_light", "tree")):
        table = lights.LightTable(_scene(mi, name, tmp_path))
        assert table.mode == mode
        m = 64
        p = np.column_stack([rng.uniform(-1.0, 1.0, m), rng.uniform(0.05, 1.0, m), rng.uniform(-1.0, 1.0, m)])
        g = rng.standard_normal((m, 3))
        n = g / np.linalg.norm(g, axis=1, keepdims=True)
        rows = np.arange(table.count)
        pp, nn, row = np.repeat(p, table.count, axis=0), np.repeat(n, table.count, axis=0), np.tile(rows, m)
        point = mi.Vector3f(*(mi.Float(pp[:, k]) for k in range(3)))
        normal = mi.Vector3f(*(mi.Float(nn[:, k]) for k in range(3)))
        probability = table.probability(point, mi.UInt32(row), mi.Bool(True), normal).numpy()
        sums = probability.reshape(m, table.count).sum(axis=1)
        assert np.all(probability >= 0.0)
        assert np.sum(sums > 0) > m // 2, name
        np.testing.assert_allclose(sums[sums > 0], 1.0, rtol=1e-5, err_msg=name)
        # the sampled row's probability is the computed one
        point1 = mi.Vector3f(*(mi.Float(p[:, k]) for k in range(3)))
        normal1 = mi.Vector3f(*(mi.Float(n[:, k]) for k in range(3)))
        chosen, chosen_p, _ = table.choose(point1, mi.Float64(rng.random(m)), mi.Bool(True), normal1)
        again = table.probability(point1, chosen, mi.Bool(True), normal1)
        dr.eval(chosen_p, again)
        lit = chosen_p.numpy() > 0
        assert lit.sum() > m // 2, name
        np.testing.assert_allclose(again.numpy()[lit], chosen_p.numpy()[lit], rtol=1e-6, err_msg=name)
        if mode == "tree":  # both rules below the top: by power where the chosen top run is small, else the levels
            far = table._top_far(point1, chosen // table.spans[0], mi.Bool(True)).numpy()[lit]
        if name == "exact_light":  # both rules: by power where every emitter is small as seen from p, else weighed
            far = table._clusters_far(point1).numpy()[lit]
        if name != "cornell":
            assert 0.1 < far.mean() < 0.9, (name, far.mean())


@pytest.mark.statistical
def test_alias_tables_choose_rows_by_their_share(llvm):
    """A top run small as seen from p chooses its triangle by power through an alias table: the rows'
    frequencies (Dr.Jit, 400 000 draws over runs of 8, a short last run and a zero weight) against their
    shares of the run's weight (chi-square, significance 0.01); a row of weight 0 is never drawn."""
    mi = llvm
    from symsphere._testing import mitsuba_lights as lights

    weights = np.array([1.0, 5.0, 0.0, 2.0, 0.5, 3.0, 1.0, 7.5, 4.0, 0.0, 1.0, 2.0, 9.0])
    keep, alias, shares = lights.alias_rows(weights, 8)
    np.testing.assert_allclose(
        shares, np.concatenate([weights[:8] / weights[:8].sum(), weights[8:] / weights[8:].sum()])
    )
    n, rng = 400_000, np.random.default_rng(8)
    run = rng.integers(0, 2, n)
    start, count = run * 8, np.where(run == 0, 8, 5)
    row, reused = lights.alias_pick(
        mi.Float(keep.astype(np.float32)),
        mi.UInt32(alias),
        mi.UInt32(start),
        mi.UInt32(count),
        mi.Float64(rng.random(n)),
        mi.Bool(True),
    )
    row, reused = row.numpy(), reused.numpy()
    assert np.all((row >= start) & (row < start + count)) and np.all(weights[row] > 0.0)
    observed = np.bincount(row, minlength=len(weights))
    expected = shares * np.bincount(run, minlength=2)[np.arange(len(weights)) // 8]
    used = expected > 0
    # two runs: one constraint more than chisquare's default (ddof=1)
    assert stats.chisquare(observed[used], expected[used], ddof=1).pvalue > ALPHA
    assert 0.0 <= reused.min() and reused.max() <= 1.0 and abs(reused.mean() - 0.5) < 0.01
    # runs given by their starts (an exact table's emitters): each row's share and alias within its own run
    keep, alias, shares = lights.alias_rows(weights, [0, 3, 8])
    run = np.searchsorted([3, 8], np.arange(len(weights)), side="right")
    sums = np.bincount(run, weights)
    np.testing.assert_allclose(shares, weights / sums[run])
    assert np.all(run[alias] == run) and np.all(keep[weights == 0.0] == 0.0)


# (scene, point): the mesh-light scene (two emitters, one chosen through the tree, one exactly; most
# triangles sampled by area there), near_rect near its light (Arvo's map) and far (by power and area),
# near_disk where some of its triangles are sampled by area and some by Arvo's map, exact_light where every run of
# its emitters' rows is small as seen from p (a run by its importance, its triangle by power)
DENSITY_CASES = [("mesh_light", (0.1, 0.3, -0.2)), ("near_rect", (0.2, 0.1, 0.1)), ("near_rect", (1.8, 0.1, 1.2)),
                 ("near_disk", (1.4, 0.1, 0.6)), ("tree_light", (0.3, 0.2, 0.4)), ("exact_light", (1.0, 0.1, 0.8))]  # fmt: skip


@pytest.mark.statistical
@pytest.mark.parametrize(("scene_name", "point"), DENSITY_CASES)
def test_the_density_integrates_to_one(llvm, tmp_path, scene_name, point):
    """The density of the table's directions over the sphere, by Monte Carlo with numpy's uniform directions,
    is 1 at a point below the lights (z-test, Sidak over the DENSITY_CASES)."""
    mi = llvm
    import drjit as dr

    from symsphere._testing import mitsuba_lights as lights

    scene = _scene(mi, scene_name, tmp_path, bare=True)
    table = lights.LightTable(scene)
    n = 400_000
    g = np.random.default_rng(6).standard_normal((n, 3))
    d = g / np.linalg.norm(g, axis=1, keepdims=True)
    prev = dr.zeros(mi.SurfaceInteraction3f, n)
    prev.p = mi.Point3f(*point)
    prev.n = mi.Normal3f(0, 1, 0)
    hit = scene.ray_intersect(mi.Ray3f(prev.p, mi.Vector3f(d[:, 0], d[:, 1], d[:, 2])))
    ds = mi.DirectionSample3f(scene, si=hit, ref=prev)
    on_light = (hit.shape.emitter() != None).numpy()  # noqa: E711 - a Dr.Jit comparison
    pdf = np.where(on_light, table.pdf_direction(scene, prev, hit, ds, mi.Bool(True)).numpy(), 0.0)
    values = 4 * np.pi * pdf
    z = (values.mean() - 1.0) / (values.std(ddof=1) / np.sqrt(n))
    assert abs(z) < stats.norm.isf(_sidak(ALPHA, len(DENSITY_CASES)) / 2), (values.mean(), z)


def _renders(mi, scene, integrator):
    return np.stack(
        [np.array(mi.render(scene, integrator=integrator, spp=SPP, seed=seed))[..., :3] for seed in range(SEEDS)]
    )


_REFERENCE: dict[tuple[str, int], np.ndarray] = {}  # (scene, max_depth): Mitsuba path's blocks


@pytest.mark.xdist_group("lights_path_references")  # one worker: the references shared
@pytest.mark.statistical
@pytest.mark.parametrize(("scene_name", "max_depth", "sampling"), UNBIASED_CASES)
def test_mean_image_agrees_with_mitsubas_path(llvm, scene_name, max_depth, sampling, tmp_path):
    mi = llvm
    import symsphere.mitsuba  # noqa: F401

    scene = _scene(mi, scene_name, tmp_path)
    depth = {"max_depth": max_depth, "rr_depth": 3}
    if (scene_name, max_depth) not in _REFERENCE:  # two cases (solid_angle, projected) share a scene and depth
        _REFERENCE[scene_name, max_depth] = _blocks(_renders(mi, scene, mi.load_dict({"type": "path", **depth})))
    ref = _REFERENCE[scene_name, max_depth]
    integrator = mi.load_dict({"type": "symsphere_path", "strategy": "bsdf", "emitter_sampling": sampling, **depth})
    ours = _blocks(_renders(mi, scene, integrator))
    assert np.all(np.isfinite(ours))
    result = stats.ttest_ind(ours, ref, axis=0, equal_var=False)
    assert np.min(result.pvalue) > _sidak(ALPHA, UNBIASED_TESTS), (np.min(result.pvalue), ours.mean(0), ref.mean(0))


# 12 triangles (exact choice), 108 (a tree: leaves under its top), 4332 (a tree, two levels between); and 12 with a perfect mirror ball inside,
# which leaves the radiance at 2 but makes the scene not all diffuse (Mitsuba's sampling and MIS at the
# ball's vertices, with no smooth part: its BSDF hits count in full)
# projected: by projected solid angle at every vertex (12 triangles, exact choice), or at the diffuse ones
# (the mirror ball: both techniques in one kernel)
FURNACE_CASES = [(1, False, "solid_angle"), (3, False, "solid_angle"), (19, False, "solid_angle")]
FURNACE_CASES += [(1, True, "solid_angle"), (1, False, "projected"), (1, True, "projected")]


@pytest.mark.statistical
@pytest.mark.parametrize(("per_side", "mirror", "sampling"), FURNACE_CASES)
def test_emitting_box_furnace(llvm, tmp_path, per_side, mirror, sampling):
    """Inside a closed box whose walls emit radiance 1 inward and reflect diffusely with albedo 1/2, the
    radiance is 1 / (1 - 1/2) = 2 everywhere."""
    mi = llvm
    import symsphere.mitsuba  # noqa: F401

    T = mi.ScalarTransform4f
    scene = mi.load_dict({
        "type": "scene",
        "sensor": {"type": "perspective", "fov": 60, "to_world": T().look_at(origin=[0.2, -0.3, 0.5], target=[-1, 0.2, -1], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": SIZE, "height": SIZE, "rfilter": {"type": "box"}}},
        "box": {"type": "obj", "filename": str(_obj_box(tmp_path / "box.obj", per_side)),
                "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.5, 0.5, 0.5]}},
                "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [1, 1, 1]}}},
    } | ({"mirror": {"type": "sphere", "center": [-0.3, 0.1, -0.4], "radius": 0.35,
                     "bsdf": {"type": "conductor", "material": "none"}}} if mirror else {}))  # fmt: skip
    integrator = mi.load_dict({"type": "symsphere_path", "strategy": "bsdf", "emitter_sampling": sampling,
                               "max_depth": -1, "rr_depth": 5})  # fmt: skip
    images = np.stack([np.array(mi.render(scene, integrator=integrator, spp=SPP, seed=s))[..., :3] for s in range(4)])
    values = images.mean(axis=-1).ravel()
    z = (values.mean() - 2.0) / (values.std(ddof=1) / np.sqrt(values.size))
    assert abs(z) < stats.norm.isf(_sidak(ALPHA, FURNACE_TESTS) / 2), (values.mean(), z)


DEGENERATE = "f 1 1 2\nf 1 5 3\n"  # a repeated vertex, a collinear one


DEGENERATE_FACES = ["f 1 3 2\nf 1 4 3\n" + DEGENERATE, "f 1 3 2\nf 1 5 3\n", "f 1 3 2\nf 1 4 3\n" + DEGENERATE * 40]


@pytest.mark.parametrize("faces", DEGENERATE_FACES, ids=["exact", "tiny", "tree"])
def test_degenerate_emitter_triangles_contribute_nothing(llvm, tmp_path, faces):
    """A mesh light with zero-area triangles and one seen edge-on: finite images, the same mean as Mitsuba's.
    Two faces down, a repeated vertex, a collinear one; a face and a collinear one (a tiny table, chosen
    from by power and sampled by area far from it); two faces among 80 degenerate ones (the tree)."""
    mi = llvm
    import symsphere.mitsuba  # noqa: F401

    path = tmp_path / "bad.obj"
    path.write_text("v -0.5 1.5 -0.5\nv 0.5 1.5 -0.5\nv 0.5 1.5 0.5\nv -0.5 1.5 0.5\nv 0 1.5 0\n" + faces)
    scene = scene_dict(mi, "textured", SIZE)
    del scene["light"], scene["sky"]
    scene["light"] = {
        "type": "obj",
        "filename": str(path),
        "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [5, 5, 5]}},
    }
    scene = mi.load_dict(scene)
    from symsphere._testing import mitsuba_lights as lights

    assert lights.LightTable(scene).count == faces.count("f")
    integrator = mi.load_dict(
        {"type": "symsphere_path", "strategy": "bsdf", "emitter_sampling": "solid_angle", "max_depth": 2}
    )
    image = np.array(mi.render(scene, integrator=integrator, spp=16, seed=1))
    assert np.all(np.isfinite(image)) and image.mean() > 0


def _area_fraction(mi, scene, table, lights):
    """The fraction of the primary hits (a 32 x 32 grid of camera rays) where the table samples by area:
    the criteria restated in numpy (a tiny table's bounding sphere; else each triangle's, averaged)."""
    sensor = scene.sensors()[0]
    xs, ys = np.meshgrid((np.arange(32) + 0.5) / 32, (np.arange(32) + 0.5) / 32)
    ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(xs.ravel(), ys.ravel()), mi.Point2f(0.5, 0.5))
    si = scene.ray_intersect(ray)
    p = np.asarray(si.p.numpy()).reshape(-1, 3)[si.is_valid().numpy()]
    tris = table.tris
    if table.count <= lights.TINY_MAX:
        centre = tris.reshape(-1, 3).mean(axis=0)
        radius = np.linalg.norm(tris - centre, axis=2).max()
        return float(np.mean(radius < lights.TINY_BELOW * np.linalg.norm(p - centre, axis=1)))
    centre = tris.mean(axis=1)
    radius = np.linalg.norm(tris - centre[:, None], axis=2).max(axis=1)
    return float(np.mean(radius < lights.AREA_BELOW * np.linalg.norm(p[:, None] - centre, axis=2)))


def test_area_sampling_switches_inside_these_images(llvm, tmp_path):
    """The block tests' near_rect and near_disk scenes use both maps, each in at least a tenth of the image."""
    mi = llvm
    from symsphere._testing import mitsuba_lights as lights

    for name in ("near_rect", "near_disk"):
        scene = _scene(mi, name, tmp_path)
        fraction = _area_fraction(mi, scene, lights.LightTable(scene), lights)
        assert 0.1 < fraction < 0.9, (name, fraction)


def test_drjit_spherical_triangle_equals_numpy(llvm):
    """The Dr.Jit form of Arvo's map (float64 inside the kernel, with sin(A' - alpha) and sin(A'/2 - alpha)
    by the addition theorems) against the numpy one, on ordinary and adversarial triangles whose vertex
    vectors are scaled by 2.5 (the Dr.Jit form normalises them itself).  Bound: 1e-9 in direction (measured <= 7e-10 on the 1e-7 sr slivers,
    1e-14 on the rest; the vertices' differences are formed and normalised differently)."""
    mi = llvm
    from symsphere._testing import mitsuba_warps

    rng = np.random.default_rng(12)
    uv = rng.random((2000, 2))
    triangles = [
        [[0.1, -0.3, 0.95], [0.9, 0.4, -0.2], [-0.6, 0.7, 0.3]],
        _sliver_vertices(1e-7),
        _sliver_vertices(1e-5),
        [[np.cos(p), np.sin(p), 3e-4] for p in (0.0, 2 * np.pi / 3, 4 * np.pi / 3)],
        [[1, 0, 0], [-0.2, 1, 0], [-0.2, 1, 1e-6]],
    ]
    from symsphere.warps import square_to_spherical_triangle

    for tri in triangles:
        tri = np.array(tri, dtype=np.float64)
        tri /= np.linalg.norm(tri, axis=1, keepdims=True)
        scale = 2.5
        corners = [mi.Vector3d(*(mi.Float64(np.full(len(uv), x * scale)) for x in v)) for v in tri]
        d, area = mitsuba_warps.square_to_spherical_triangle((mi.Float64(uv[:, 0]), mi.Float64(uv[:, 1])), *corners)
        got = np.stack([d.x.numpy(), d.y.numpy(), d.z.numpy()], axis=1)
        assert np.all(np.isfinite(got)) and np.all(area.numpy() > 0)
        np.testing.assert_allclose(got, square_to_spherical_triangle(uv, *tri), rtol=0, atol=1e-9)


def test_drjit_spherical_triangle_in_float32(llvm):
    """The map as ``solid_angle`` runs it, in float32 (vertices relative to the shading point), against the
    numpy map in float64: a 1.6 x 1.0 light half seen from 0.15 away (1.76 sr), a Cornell-like light
    (0.02 sr), lights of 5e-5 and 5e-7 sr 10 away and one far from the origin.  Bounds: 1e-5 in direction
    (measured <= 2.5e-6, on the 1.76 sr one) and in relative solid angle (measured <= 8.3e-7; 1.7e-5 on the
    5e-7 sr one, bounded by 1e-4)."""
    mi = llvm
    from symsphere._testing import mitsuba_warps
    from symsphere.warps import square_to_spherical_triangle

    uv = np.random.default_rng(13).random((20000, 2))
    cases = [  # (vertices, shading point, bound on the solid angle's relative error)
        ([[0, 0, 0.15], [1.6, 0, 0.15], [1.6, 1.0, 0.15]], [0.3, 0.2, 0.0], 1e-5),
        ([[-0.24, 1.98, -0.22], [0.23, 1.98, -0.22], [0.23, 1.98, 0.16]], [0.1, 0.0, 0.3], 1e-5),
        ([[0, 0, 10], [0.1, 0, 10], [0, 0.1, 10]], [0.3, 0.2, 0.0], 1e-5),
        ([[0, 0, 10], [0.01, 0, 10], [0, 0.01, 10]], [0.3, 0.2, 0.0], 1e-4),
        ([[100, 100, 3], [100.5, 100, 3], [100, 100.5, 3]], [99.0, 99.0, 0.0], 1e-5),
    ]
    for tri, p, bound in cases:
        tri, p = np.array(tri, dtype=np.float64), np.array(p, dtype=np.float64)
        point = mi.Vector3f(*(float(x) for x in p))
        corners = [mi.Vector3f(*(mi.Float(np.full(len(uv), x, dtype=np.float32)) for x in v)) - point for v in tri]
        d, area = mitsuba_warps.square_to_spherical_triangle((mi.Float(uv[:, 0]), mi.Float(uv[:, 1])), *corners)
        got = np.stack([d.x.numpy(), d.y.numpy(), d.z.numpy()], axis=1).astype(np.float64)
        rel = tri - p
        unit = rel / np.linalg.norm(rel, axis=1, keepdims=True)
        want = square_to_spherical_triangle(uv, *unit)
        assert np.all(np.isfinite(got))
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-5)
        a, b, c = unit
        omega = 2 * np.arctan2(abs(np.dot(a, np.cross(b, c))), 1 + a @ b + b @ c + c @ a)
        np.testing.assert_allclose(area.numpy(), omega, rtol=bound)


def _sliver_vertices(height):
    a, b = np.array([1.0, 0.0, 0.2]), np.array([0.0, 1.0, 0.2])
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    m = (a + b) / 2 + height * np.array([0.0, 0.0, 1.0])
    return [a, b, m / np.linalg.norm(m)]


def test_a_scene_without_rectangle_or_mesh_lights_renders_as_with_area(llvm):
    """Sphere lights and a sky only: no light table, Mitsuba samples every emitter; the same image, bit for bit."""
    mi = llvm
    import symsphere.mitsuba  # noqa: F401

    scene = scene_dict(mi, "textured", SIZE)
    del scene["light"]
    lamp = {"type": "area", "radiance": {"type": "rgb", "value": [20, 20, 20]}}
    scene["lamp"] = {"type": "sphere", "center": [0.5, 2.5, 0.5], "radius": 0.2, "emitter": lamp}
    scene = mi.load_dict(scene)
    images = [
        np.array(mi.render(scene, integrator=mi.load_dict({"type": "symsphere_path", "strategy": "bsdf",
                 "emitter_sampling": sampling, "max_depth": 4}), spp=8, seed=3))
        for sampling in ("area", "solid_angle")
    ]  # fmt: skip
    np.testing.assert_array_equal(images[0], images[1])


def test_glossy_vertices_sample_emitters_as_mitsubas_path(llvm):
    """At a vertex whose BSDF is not diffuse only, every emitter is sampled as Mitsuba's ``path`` samples it
    (and MIS takes Mitsuba's densities): a scene whose every BSDF is glossy or smooth renders as ``path``,
    bit for bit, with one emitter (the rectangle light: Mitsuba's fast path) and with two (and a sky)."""
    mi = llvm
    import symsphere.mitsuba  # noqa: F401

    for sky in (False, True):
        scene = scene_dict(mi, "textured", SIZE)
        for name in ("floor", "wall"):
            scene[name]["bsdf"] = {"type": "roughplastic", "alpha": 0.3}
        if not sky:
            del scene["sky"]
        scene = mi.load_dict(scene)
        images = [
            np.array(mi.render(scene, integrator=mi.load_dict(spec | {"max_depth": 5}), spp=16, seed=3))
            for spec in ({"type": "path"}, {"type": "symsphere_path", "strategy": "bsdf", "emitter_sampling": "solid_angle"})
        ]  # fmt: skip
        assert images[0].mean() > 0
        np.testing.assert_array_equal(images[0], images[1])


def test_a_one_triangle_light_renders_again_from_the_kernel_cache(llvm, tmp_path):
    """The table is built at each render: a second render of a one-triangle light compiles no kernel
    (a gather from a one-entry column missed Dr.Jit's kernel cache: 0.30 s per 64 x 64 render)."""
    mi = llvm
    path = tmp_path / "one.obj"
    path.write_text("v -0.5 1.5 -0.5\nv 0.5 1.5 -0.5\nv 0.5 1.5 0.5\nf 1 3 2\n")
    scene = scene_dict(mi, "textured", 16)
    del scene["light"], scene["sky"]
    emitter = {"type": "area", "radiance": {"type": "rgb", "value": [5, 5, 5]}}
    scene["light"] = {"type": "obj", "filename": str(path), "emitter": emitter}
    _assert_renders_again_from_the_kernel_cache(mi, mi.load_dict(scene), 2)


@pytest.mark.parametrize("scene_name", ["tree_light", "textured", "exact_light"])
def test_the_tree_and_a_tiny_table_render_again_from_the_kernel_cache(llvm, tmp_path, scene_name):
    """The same with the tree's alias tables (a second render's columns are new arrays), with a tiny
    table whose emitter samples itself where it is small, and with an exact table's emitters' alias tables."""
    _assert_renders_again_from_the_kernel_cache(llvm, _scene(llvm, scene_name, tmp_path), 3)


def _assert_renders_again_from_the_kernel_cache(mi, scene, max_depth):
    import drjit as dr

    import symsphere.mitsuba  # noqa: F401

    integrator = mi.load_dict(
        {"type": "symsphere_path", "strategy": "bsdf", "emitter_sampling": "solid_angle", "max_depth": max_depth}
    )
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        np.array(mi.render(scene, integrator=integrator, spp=1, seed=0))
        dr.kernel_history()
        np.array(mi.render(scene, integrator=integrator, spp=1, seed=1))
        compiled = [k for k in dr.kernel_history() if k["type"] == dr.KernelType.JIT]
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    assert compiled and all(k["cache_hit"] for k in compiled), compiled


def _domed_grid(nx, nz, size, dome):
    """The triangles (2 nx nz, 3, 3) of an nx x nz grid of quads over size = (sx, sz), its middle raised by
    *dome*, facing down (-y): the shape of the benchmarks' 1024-triangle light."""
    a, b = np.meshgrid(np.arange(nx + 1) / nx - 0.5, np.arange(nz + 1) / nz - 0.5, indexing="ij")
    v = np.stack([a * size[0], dome * (1 - 4 * a * a) * (1 - 4 * b * b), b * size[1]], axis=-1)
    v00, v10, v01, v11 = v[:-1, :-1], v[1:, :-1], v[:-1, 1:], v[1:, 1:]
    quads = np.stack([np.stack([v00, v10, v11], axis=-2), np.stack([v00, v11, v01], axis=-2)], axis=2)
    return quads.reshape(-1, 3, 3)


def test_the_trees_runs_are_compact(llvm):
    """The tree's order (``tree_order``): on a slightly domed 32 x 16 grid of quads over 2 x 1 (1024
    triangles, quads of 1/16), every aligned run of 32 rows (a top run) is no larger than a 4 x 4 patch of
    quads (bounding radius about the mean of its centroids within 1.1 x the patch's half-diagonal) and
    every run of 8 (a node below it, a leaf) no larger than a 2 x 2 patch; the order is a permutation,
    also of triangles that face several ways.  (The Morton curve of before, the centroids scaled to the
    unit cube, ran along the dome's 0.05 as along the width: runs of 32 with radii up to 0.92.)"""
    from symsphere._testing import mitsuba_lights as lights

    tris = _domed_grid(32, 16, (2.0, 1.0), 0.05)
    order = lights.tree_order(tris)
    np.testing.assert_array_equal(np.sort(order), np.arange(len(tris)))
    for span, quads in ((32, 4), (8, 2)):
        runs = tris[order].reshape(-1, span, 3, 3)
        centre = runs.mean(axis=2).mean(axis=1)
        radius = np.linalg.norm(runs - centre[:, None, None], axis=-1).max(axis=(1, 2))
        assert radius.max() < 1.1 * quads / 16 * np.sqrt(0.5), (span, radius.max())
    rng = np.random.default_rng(5)
    soup = np.concatenate([tris[:100], tris[:60, ::-1], rng.standard_normal((77, 3, 3))])
    np.testing.assert_array_equal(np.sort(lights.tree_order(soup)), np.arange(len(soup)))


def test_a_table_of_the_same_lights_shares_its_choice_and_a_changed_one_does_not(llvm, tmp_path):
    """The choice (groups, levels, alias tables) is built once per content: a second table of the same scene
    shares it; after the light's radiance or its vertices change (``mi.traverse``) the table is built anew and
    follows the change."""
    mi = llvm
    from symsphere._testing import mitsuba_lights as lights

    scene = _scene(mi, "tree_light", tmp_path)  # a 320-triangle disk at height 1.2 (radiance 6, 6, 5), a panel
    first = lights.LightTable(scene)
    again = lights.LightTable(scene)
    assert again._top is first._top and again.groups is first.groups
    params = mi.traverse(scene)
    params["light.emitter.radiance.value"] = mi.Color3f(12.0, 12.0, 10.0)
    params.update()
    brighter = lights.LightTable(scene)
    assert brighter._top is not first._top
    np.testing.assert_allclose(np.unique(first.lum), [7 / 3, 17 / 3], rtol=1e-6)
    np.testing.assert_allclose(np.unique(brighter.lum), [7 / 3, 34 / 3], rtol=1e-6)
    np.testing.assert_allclose(sum(g.power for g in brighter.groups), np.sum(brighter.area * brighter.lum), rtol=1e-9)
    positions = np.array(params["light.vertex_positions"]).reshape(-1, 3)
    positions[:, 1] -= 0.1  # the disk 0.1 lower
    params["light.vertex_positions"] = mi.Float(positions.ravel())
    params.update()
    lower = lights.LightTable(scene)
    assert lower._top is not brighter._top
    assert (
        np.sum(np.isclose(lower.tris[..., 1], 1.1, atol=1e-6))
        == np.sum(np.isclose(first.tris[..., 1], 1.2, atol=1e-6))
        == 960
    )


# ``symsphere_path`` with Owen-scrambled Sobol' cosine directions (``strategy='cosine'``, ``points='sobol'``)
# and the light table (``emitter_sampling`` ``'solid_angle'`` or ``'cosine'``): unbiased.
#
# The block test of test_mean_image_agrees_with_mitsubas_path: the mean image of QMC_SEEDS renders against Mitsuba's own ``path``
# (the independent reference), 4 x 4 blocks of the mean of R, G, B, Welch's t-test, two-sided, significance 0.01
# for the family with a Sidak correction over every block of every case.  The scenes: a rectangle light and a
# 24-triangle disk light near the floor of the textured scene (a tiny table; an exact table), max_depth 3 (the
# Sobol' directions at two vertices, the table at the second).
QMC_SIZE, QMC_SPP, QMC_SEEDS, QMC_BLOCK = 16, 32, 12, 4
QMC_CASES = [(scene, sampling) for scene in ("near_rect", "near_disk") for sampling in ("solid_angle", "cosine")]
QMC_TESTS = len(QMC_CASES) * (QMC_SIZE // QMC_BLOCK) ** 2


def _qmc_scene(mi, name, tmp_path):
    scene = scene_dict(mi, "textured", QMC_SIZE)
    for key in ("light", "sky", "ball", "glass"):
        del scene[key]
    radiance = {"type": "area", "radiance": {"type": "rgb", "value": [6, 6, 5]}}
    if name == "near_rect":  # 0.5 above the floor, facing it
        T = mi.ScalarTransform4f
        to_world = T().translate([0, 0.5, 0]).rotate([1, 0, 0], 90).scale(0.6)
        scene["light"] = {"type": "rectangle", "to_world": to_world, "emitter": radiance}
    else:  # a disk of 24 triangles (radius 0.8) 0.4 above the floor, facing down
        segments, radius, height = 24, 0.8, 0.4
        phi = 2 * np.pi * np.arange(segments) / segments
        lines = [f"v 0 {height} 0\n"] + [f"v {radius * np.cos(p)} {height} {radius * np.sin(p)}\n" for p in phi]
        lines += [f"f 1 {k + 2} {(k + 1) % segments + 2}\n" for k in range(segments)]  # normal -y
        path = tmp_path / "disk24.obj"
        path.write_text("".join(lines), encoding="utf-8")
        scene["light"] = {"type": "obj", "filename": str(path), "emitter": radiance}
    return mi.load_dict(scene)


def _qmc_blocks(mi, scene, integrator):
    images = np.stack(
        [
            np.array(mi.render(scene, integrator=integrator, spp=QMC_SPP, seed=seed))[..., :3]
            for seed in range(QMC_SEEDS)
        ]
    )
    lum = images.mean(axis=-1).reshape(QMC_SEEDS, QMC_SIZE // QMC_BLOCK, QMC_BLOCK, QMC_SIZE // QMC_BLOCK, QMC_BLOCK)
    return lum.mean(axis=(2, 4)).reshape(QMC_SEEDS, -1)


_QMC_REFERENCE: dict[str, np.ndarray] = {}  # scene: Mitsuba path's blocks


@pytest.mark.xdist_group("qmc_path_references")  # one worker: the references shared
@pytest.mark.statistical
@pytest.mark.parametrize(("scene_name", "sampling"), QMC_CASES)
def test_sobol_cosine_directions_with_the_light_table_agree_with_mitsubas_path(llvm, tmp_path, scene_name, sampling):
    mi = llvm
    import symsphere.mitsuba  # noqa: F401

    scene = _qmc_scene(mi, scene_name, tmp_path)
    depth = {"max_depth": 3, "rr_depth": 2}
    if scene_name not in _QMC_REFERENCE:  # the two samplings of a scene share its reference
        _QMC_REFERENCE[scene_name] = _qmc_blocks(mi, scene, mi.load_dict({"type": "path", **depth}))
    ref = _QMC_REFERENCE[scene_name]
    spec = {"type": "symsphere_path", "strategy": "cosine", "points": "sobol", "emitter_sampling": sampling}
    ours = _qmc_blocks(mi, scene, mi.load_dict({**spec, **depth}))
    assert np.all(np.isfinite(ours)) and ours.mean() > 0.0
    pvalue = stats.ttest_ind(ours, ref, axis=0, equal_var=False).pvalue
    assert np.min(pvalue) > 1.0 - (1.0 - ALPHA) ** (1.0 / QMC_TESTS), (np.min(pvalue), ours.mean(0), ref.mean(0))
