"""symsphere.render.scene, scene_files, scenes: smallpt's Cornell box, clipped spheres, the emitter tables, scene files,
validation; every name still importable from symsphere.render.scene."""

import dataclasses
import json
import math

import numpy as np
import pytest

from symsphere._testing import render_probes as P
from symsphere.render import (
    Camera,
    HalfSpace,
    Quad,
    Scene,
    SceneError,
    Sphere,
    cornell,
    diffuse,
    furnace,
    load_scene,
    render,
    translucent_scene,
)

# --- smallpt's scene, pinned ------------------------------------------------------

SMALLPT = [  # radius, centre, emission, colour, material: smallpt.cpp as published
    (1e5, (1e5 + 1, 40.8, 81.6), 0, (0.75, 0.25, 0.25), "diffuse"),
    (1e5, (-1e5 + 99, 40.8, 81.6), 0, (0.25, 0.25, 0.75), "diffuse"),
    (1e5, (50, 40.8, 1e5), 0, (0.75, 0.75, 0.75), "diffuse"),
    (1e5, (50, 40.8, -1e5 + 170), 0, (0, 0, 0), "diffuse"),
    (1e5, (50, 1e5, 81.6), 0, (0.75, 0.75, 0.75), "diffuse"),
    (1e5, (50, -1e5 + 81.6, 81.6), 0, (0.75, 0.75, 0.75), "diffuse"),
    (16.5, (27, 16.5, 47), 0, (0.999, 0.999, 0.999), "mirror"),
    (16.5, (73, 16.5, 78), 0, (0.999, 0.999, 0.999), "dielectric"),
    (600, (50, 681.6 - 0.27, 81.6), 12, (0, 0, 0), "diffuse"),
]


def test_cornell_is_smallpt_as_published():
    scene = cornell()
    assert len(scene.spheres) == 9 and not scene.quads
    assert [s.clip for s in scene.spheres[:8]] == [None] * 8
    # the light: smallpt's sphere, clipped to its part below the ceiling plane y = 81.6 (see below)
    assert scene.spheres[8].clip == HalfSpace((50.0, 81.6, 81.6), (0.0, -1.0, 0.0))
    for sphere, (radius, center, emission, color, kind) in zip(scene.spheres, SMALLPT, strict=False):
        material = scene.materials[sphere.material]
        assert sphere.radius == radius
        assert sphere.center == tuple(float(c) for c in center)
        assert material.emission == (emission,) * 3
        assert material.color == tuple(float(c) for c in color)
        assert material.kind == kind
    assert scene.materials["glass"].ior == 1.5
    assert scene.camera.position == (50, 52, 295.6) and scene.camera.near == 140
    assert scene.ray_epsilon == 1e-4
    # smallpt: cx = (w * .5135 / h, 0, 0), cy = (cx x d).norm() * .5135, d = (0, -0.042612, -1).norm()
    w, h = 256, 192
    cam = scene.camera_array(w, h)
    d = np.array([0, -0.042612, -1]) / np.linalg.norm([0, -0.042612, -1])
    np.testing.assert_allclose(cam[3:6], d, rtol=0, atol=1e-16)
    np.testing.assert_allclose(cam[6:9], [w * 0.5135 / h, 0, 0], rtol=1e-15, atol=0)
    cy = np.cross([1.0, 0, 0], d)
    np.testing.assert_allclose(cam[9:12], cy / np.linalg.norm(cy) * 0.5135, rtol=1e-14, atol=1e-16)


def _unclipped_cornell():
    scene = cornell()
    spheres = (*scene.spheres[:8], dataclasses.replace(scene.spheres[8], clip=None))
    return dataclasses.replace(scene, spheres=spheres)


def _inside_room(rng, count):
    """Uniform points inside smallpt's room (inside all six 1e5-radius walls), outside the light sphere."""
    points = np.column_stack(
        [rng.uniform(1, 99, 3 * count), rng.uniform(0, 81.6, 3 * count), rng.uniform(0, 170, 3 * count)]
    )
    keep = np.ones(len(points), dtype=bool)
    for radius, center, *_ in SMALLPT[:6]:
        keep &= np.sum((points - np.array(center)) ** 2, axis=1) < radius**2  # the walls are slightly curved
    light = np.array([50, 681.6 - 0.27, 81.6])
    keep &= np.sum((points - light) ** 2, axis=1) > 600.0**2  # the light's cap dips 0.27 into the room
    assert keep.sum() >= count
    return points[keep][:count]


def test_every_ray_from_inside_the_room_hits_what_it_hits_in_smallpt():
    """The clipped light changes nothing for rays that start in the room: same object, same distance, bit for bit.

    500 000 rays: random origins in the room, random directions, and 100 000
    aimed at random points of the light's visible cap and its rim.
    """
    rng = np.random.default_rng(2026)
    origins = _inside_room(rng, 500_000)
    directions = rng.normal(size=origins.shape)
    cap = np.column_stack([rng.uniform(30, 70, 100_000), np.full(100_000, 81.45), rng.uniform(60, 100, 100_000)])
    directions[:100_000] = cap - origins[:100_000]
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    hits = []
    for scene in (_unclipped_cornell(), cornell()):
        a = scene.arrays(4, 4)
        hits.append(P.first_hits(origins, directions, a["spheres"], a["quads"], a["eps"]))
    np.testing.assert_array_equal(hits[0][1], hits[1][1])
    np.testing.assert_array_equal(hits[0][0], hits[1][0])
    assert np.sum(hits[1][1] == 8) > 30_000  # the light is among the hits


def test_bsdf_image_of_old_and_new_cornell_differs_only_where_rays_start_above_the_ceiling():
    """Same seed, BSDF integrator: identical pixels below the top row (smallpt starts some top-row rays above the ceiling)."""
    old = render(_unclipped_cornell(), width=32, height=24, spp=24, seed=3, integrator="bsdf").image
    new = render(cornell(), width=32, height=24, spp=24, seed=3, integrator="bsdf").image
    np.testing.assert_array_equal(old[1:], new[1:])
    # the top row: rays from camera + 140 d reach y > 81.6 only for d_y > 29.6 / 140 (the top 0.54 % of the image)
    camera = cornell().camera_array(32, 24)
    assert camera[4] + 0.5 * camera[10] > (81.6 - 52) / 140 > camera[4] + (0.5 - 1 / 24) * camera[10]


def test_clipped_sphere_table_and_light_tables():
    a = cornell().arrays(8, 6)
    light = a["spheres"][:, 8]
    np.testing.assert_allclose(light[5:8], [0, -1, 0])
    assert light[8] == -81.6 and math.isclose(light[9], 0.27, rel_tol=1e-9)  # keep -y >= -81.6; cap height 0.27
    assert np.all(a["spheres"][8, :8] == -np.inf) and np.all(a["spheres"][9, :8] == 2 * a["spheres"][3, :8])
    np.testing.assert_array_equal(a["lights"], [[8.0], [1.0]])
    np.testing.assert_array_equal(a["light_pmf"], [0] * 8 + [1])
    # translucent scene: two quad emitters chosen by power = mean radiance x area
    t = translucent_scene()
    b = t.arrays(8, 6)
    power = np.array([4.0 * 5.6 * 2.4, 0.8 * 6.0 * 4.0])
    np.testing.assert_allclose(b["light_pmf"][[3, 5]], power / power.sum(), rtol=1e-12)  # quads 2 and 4 (+1 sphere)
    np.testing.assert_allclose(b["lights"], [[3, 5], [power[0] / power.sum(), 1.0]], rtol=1e-12)
    assert b["light_pmf"].sum() == pytest.approx(1.0)
    np.testing.assert_allclose(b["quads"][16], [16 * 16, 16 * 8, 5.6 * 2.4, math.hypot(2.2, 0.3) * 2.3, 24], rtol=1e-12)


def test_clip_validation():
    camera = Camera((0, 0, 5), (0, 0, -1), 40)
    with pytest.raises(SceneError, match=r"spheres\[0\].clip keeps nothing of the sphere"):
        Scene("s", camera, {"m": diffuse(0.5)}, (Sphere((0, 0, 0), 1.0, "m", HalfSpace((0, 2, 0), (0, 1, 0))),))
    with pytest.raises(SceneError, match=r"spheres\[0\].clip.normal must be non-zero"):
        Scene("s", camera, {"m": diffuse(0.5)}, (Sphere((0, 0, 0), 1.0, "m", HalfSpace((0, 0, 0), (0, 0, 0))),))
    with pytest.raises(SceneError, match=r"spheres\[0\].clip must be a HalfSpace"):
        Scene("s", camera, {"m": diffuse(0.5)}, (Sphere((0, 0, 0), 1.0, "m", ((0, 0, 0), (0, 1, 0))),))
    whole = Scene("s", camera, {"m": diffuse(0.5)}, (Sphere((0, 0, 0), 1.0, "m", HalfSpace((0, -3, 0), (0, 1, 0))),))
    assert whole.arrays(4, 4)["spheres"][9, 0] == 2.0  # a plane below the sphere keeps all of it


GOOD_TOML = """
name = "box"

[camera]
position = [0, 1, 4]
look_at = [0, 1, 0]
fov = 40

[settings]
background = [0.1, 0.1, 0.1]
rr_depth = 4

[materials.white]
type = "diffuse"
albedo = 0.7

[materials.lamp]
type = "diffuse"
albedo = 0
emission = [4, 4, 3]

[materials.sheet]
type = "translucent"
reflectance = [0.2, 0.2, 0.2]
transmittance = 0.5

[materials.glass]
type = "dielectric"
ior = 1.33

[materials.chrome]
type = "mirror"

[[spheres]]
center = [0, 1, 0]
radius = 0.5
material = "glass"

[[spheres]]
center = [1, 0.5, 0]
radius = 0.5
material = "chrome"

[[spheres]]
center = [0, 13, 0]
radius = 10
material = "lamp"
clip = { point = [0, 3.5, 0], normal = [0, -1, 0] }

[[quads]]
corner = [-5, 0, -5]
edge1 = [0, 0, 10]
edge2 = [10, 0, 0]
material = "white"

[[quads]]
corner = [-1, 3, -1]
edge1 = [2, 0, 0]
edge2 = [0, 0, 2]
material = "lamp"

[[quads]]
corner = [-2, 0, -1]
edge1 = [1, 0, 0]
edge2 = [0, 2, 0]
material = "sheet"
"""


def _toml_to_json(text):
    import tomllib

    return json.dumps(tomllib.loads(text))


def test_scene_files_load_and_render(tmp_path):
    toml_path = tmp_path / "box.toml"
    toml_path.write_text(GOOD_TOML)
    json_path = tmp_path / "box.json"
    json_path.write_text(_toml_to_json(GOOD_TOML))
    scene = load_scene(toml_path)
    assert scene == load_scene(json_path)
    assert scene.name == "box" and len(scene.spheres) == 3 and len(scene.quads) == 3
    assert scene.spheres[2].clip == HalfSpace((0.0, 3.5, 0.0), (0.0, -1.0, 0.0))
    assert scene.camera.direction == (0, 0, -4) and scene.background == (0.1,) * 3 and scene.rr_depth == 4
    assert scene.materials["sheet"].transmittance == (0.5,) * 3 and scene.materials["chrome"].color == (1.0,) * 3
    for integrator in ("path", "bsdf"):
        image = render(str(toml_path), width=16, height=12, spp=48, seed=0, integrator=integrator).image
        assert np.all(np.isfinite(image)) and image.max() > 0


def _bad(text, old, new):
    assert old in text
    return text.replace(old, new, 1)


BAD_FILES = [
    (_bad(GOOD_TOML, "radius = 0.5\nmaterial = \"chrome\"", "radius = -1\nmaterial = \"chrome\""),
     "spheres[1].radius must be positive"),
    (_bad(GOOD_TOML, "radius = 0.5", "radius = \"big\""), "spheres[0].radius must be a number"),
    (_bad(GOOD_TOML, "radius = 0.5", "radios = 0.5"), "unknown key 'radios' in spheres[0]"),
    (_bad(GOOD_TOML, "material = \"glass\"", "material = \"gold\""), "spheres[0].material names an unknown material"),
    (_bad(GOOD_TOML, "center = [0, 1, 0]", "center = [0, 1]"), "spheres[0].center must be 3 numbers"),
    (_bad(GOOD_TOML, "albedo = 0.7", "albedo = 1.7"), "materials.white.albedo must be in [0, 1]"),
    (_bad(GOOD_TOML, "transmittance = 0.5", "transmittance = 0.9"), "reflectance + transmittance must be <= 1"),
    (_bad(GOOD_TOML, "type = \"mirror\"", "type = \"gold\""), "materials.chrome.type must be one of"),
    (_bad(GOOD_TOML, "fov = 40", "fov = 200"), "camera.fov must be in (0, 180)"),
    (_bad(GOOD_TOML, "fov = 40", ""), "camera.fov is missing"),
    (_bad(GOOD_TOML, "look_at = [0, 1, 0]", "look_at = [0, 1, 4]"), "camera.look_at must differ"),
    (_bad(GOOD_TOML, "edge2 = [0, 2, 0]", "edge2 = [2, 0, 0]"), "quads[2]: edge1 and edge2 must be non-zero and not parallel"),
    (_bad(GOOD_TOML, "[camera]", "[kamera]"), "unknown key 'kamera' in the top level"),
    (_bad(GOOD_TOML, "ior = 1.33", "ior = -1"), "materials.glass.ior must be positive"),
    (_bad(GOOD_TOML, "emission = [4, 4, 3]", "emission = [4, -4, 3]"), "materials.lamp.emission must be >= 0"),
    (_bad(GOOD_TOML, "rr_depth = 4", "rr_depth = 0"), "settings.rr_depth must be >= 1"),
    (_bad(GOOD_TOML, "[materials.white]\ntype = \"diffuse\"\nalbedo = 0.7", "[materials.white]\ntype = \"diffuse\""),
     "materials.white.albedo is missing"),
    ("name = [", "not valid TOML"),
    (_bad(GOOD_TOML, "clip = { point", "clip = { pointe"), "unknown key 'pointe' in spheres[2].clip"),
    (_bad(GOOD_TOML, "clip = { point = [0, 3.5, 0], ", "clip = { "), "spheres[2].clip.point is missing"),
    (_bad(GOOD_TOML, "point = [0, 3.5, 0]", "point = [0, 2, 0]"), "spheres[2].clip keeps nothing of the sphere"),
    (_bad(GOOD_TOML, "normal = [0, -1, 0]", "normal = [0, 0, 0]"), "spheres[2].clip.normal must be non-zero"),
    (_bad(GOOD_TOML, "normal = [0, -1, 0]", "normal = [0, -1]"), "spheres[2].clip.normal must be 3 numbers"),
    (_bad(GOOD_TOML, "clip = { point = [0, 3.5, 0], normal = [0, -1, 0] }", "clip = 3"), "spheres[2].clip must be a table"),
]  # fmt: skip


@pytest.mark.parametrize("text, message", BAD_FILES)
def test_bad_scene_files_name_the_field(tmp_path, text, message):
    path = tmp_path / "x.toml"
    path.write_text(text)
    with pytest.raises(ValueError) as info:
        load_scene(path)
    assert str(info.value).startswith(f"scene file {str(path)!r}: ")
    assert message in str(info.value)


def test_bad_json_and_suffix(tmp_path):
    path = tmp_path / "x.json"
    path.write_text("{")
    with pytest.raises(ValueError, match="not valid JSON"):
        load_scene(path)
    other = tmp_path / "x.yaml"
    other.write_text("")
    with pytest.raises(ValueError, match="suffix must be .toml or .json"):
        load_scene(other)


def test_scenes_made_in_python_are_validated():
    camera = Camera((0, 0, 5), (0, 0, -1), 40)
    with pytest.raises(SceneError, match=r"scene 's': spheres\[0\].radius must be positive"):
        Scene("s", camera, {"m": diffuse(0.5)}, (Sphere((0, 0, 0), 0.0, "m"),))
    with pytest.raises(SceneError, match="quads.0..material names an unknown material 'x'"):
        Scene("s", camera, {"m": diffuse(0.5)}, (), (Quad((0, 0, 0), (1, 0, 0), (0, 1, 0), "x"),))
    with pytest.raises(SceneError, match="at least one sphere or quad"):
        Scene("s", camera, {"m": diffuse(0.5)})
    with pytest.raises(ValueError, match="albedo"):
        furnace(albedo=1.0)
    assert translucent_scene().materials["ball"].kind == "translucent"


def test_the_documented_scene_file_loads_and_renders(tmp_path):
    import pathlib
    import re

    doc = pathlib.Path(__file__).resolve().parents[2] / "docs" / "rendering.md"
    if not doc.exists():
        pytest.skip("docs/rendering.md not present")
    block = re.search(r"```toml\n(.*?)```", doc.read_text(encoding="utf-8"), re.S).group(1)
    path = tmp_path / "example.toml"
    path.write_text(block)
    scene = load_scene(path)
    assert scene.name == "example" and {m.kind for m in scene.materials.values()} == {
        "diffuse", "translucent", "mirror", "dielectric",
    }  # fmt: skip
    assert any(s.clip is not None for s in scene.spheres)
    assert render(str(path), width=16, height=12, spp=24, seed=0).image.mean() > 0


def test_scene_names_have_one_home_each():
    # The scene files and the built-in scenes have their own modules, which import symsphere.render.scene
    # (and not the other way round); the package namespace gathers them.  SceneError pickles.
    import pickle

    import symsphere.render as render_package
    from symsphere.render import scene, scene_files, scenes

    for module in (scene, scene_files, scenes):
        for name in module.__all__:
            assert getattr(module, name) is getattr(render_package, name, getattr(module, name)), name
    assert not {"load_scene", "scene_from_dict"} & set(dir(scene)) and not {"SCENES", "get_scene"} & set(dir(scene))
    with pytest.raises(AttributeError, match="no attribute 'get_scene'"):
        scene.get_scene  # noqa: B018
    error_class = render_package.SceneError
    assert type(pickle.loads(pickle.dumps(error_class("x")))) is error_class
