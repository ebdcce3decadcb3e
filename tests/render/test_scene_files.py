"""symsphere.render.scene_files: the TOML/JSON scene format (load_scene, scene_from_dict), its errors naming the field."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from symsphere.render import (
    HalfSpace,
    load_scene,
    render,
)

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


def test_the_documented_scene_file_loads_and_renders(tmp_path):
    import pathlib
    import re

    doc = pathlib.Path(__file__).resolve().parents[2] / "docs" / "reference" / "renderer.md"
    if not doc.exists():
        pytest.skip("docs/reference/renderer.md not present")
    block = re.search(r"```toml\n(.*?)```", doc.read_text(encoding="utf-8"), re.S).group(1)
    path = tmp_path / "example.toml"
    path.write_text(block)
    scene = load_scene(path)
    assert scene.name == "example" and {m.kind for m in scene.materials.values()} == {
        "diffuse", "translucent", "mirror", "dielectric",
    }  # fmt: skip
    assert any(s.clip is not None for s in scene.spheres)
    assert render(str(path), width=16, height=12, spp=24, seed=0).image.mean() > 0


# --- files too large, FIFOs and devices refused at once ------------------------------------------------------------


def test_scene_file_too_large_is_refused(tmp_path):
    from symsphere.render import SceneError, load_scene
    from symsphere.render.scene_files import MAX_SCENE_BYTES

    path = tmp_path / "big.json"
    path.write_text(json.dumps({"name": "x" * (MAX_SCENE_BYTES + 10)}))
    with pytest.raises(SceneError, match="larger than"):
        load_scene(path)


def test_load_scene_on_a_fifo_or_device_fails_at_once(tmp_path):
    os.mkfifo(tmp_path / "f.json")
    (tmp_path / "z.json").symlink_to("/dev/zero")
    (tmp_path / "u.toml").symlink_to("/dev/urandom")
    code = (
        "import sys\nfrom symsphere.render import load_scene, load_pfm\n"
        "for name in sys.argv[1:]:\n"
        "    try:\n"
        "        (load_pfm if name.endswith('.pfm') else load_scene)(name)\n"
        "    except ValueError as exc:\n"
        "        print(exc)\n"
    )
    os.mkfifo(tmp_path / "p.pfm")
    names = [str(tmp_path / n) for n in ("f.json", "z.json", "u.toml", "p.pfm")]
    run = subprocess.run([sys.executable, "-c", code, *names], capture_output=True, text=True, timeout=60)
    lines = run.stdout.splitlines()
    assert run.returncode == 0 and len(lines) == 4, (run.stdout, run.stderr)
    assert "is a FIFO (named pipe), not a regular file" in lines[0]
    assert "is a character device, not a regular file" in lines[1] and "character device" in lines[2]
    assert "FIFO" in lines[3]
