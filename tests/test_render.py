"""The renderer: scenes, samplers, Sobol' nets, determinism, image I/O and the ``render`` verb.

The statistical tests (furnace, unbiasedness against a reference) are in
``test_render_stats.py``.
"""

import json
import math

import numba
import numpy as np
import pytest

from symsphere import frames
from symsphere._kernels import METHOD_CODES
from symsphere.cli import main
from symsphere.maps import triangle_pdf
from symsphere.render import (
    SAMPLERS,
    Camera,
    Quad,
    Scene,
    SceneError,
    Sphere,
    cornell,
    diffuse,
    furnace,
    load_pfm,
    load_scene,
    render,
    save_npy,
    save_pfm,
    save_png,
    tonemap,
    translucent_scene,
)
from symsphere.render import _integrator as K
from symsphere.render._random import nested_uniform_scramble, reverse_bits32, sobol2
from symsphere.symmetry import fold, orbit

# --- the frame ------------------------------------------------------------------


def test_scalar_frame_equals_frames_frame():
    rng = np.random.default_rng(0)
    normals = rng.normal(size=(200, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.vstack([normals, [[0, 0, 1], [0, 0, -1], [1, 0, 0], [0, -1, 0], [0.6, 0, -0.8]]])
    for n in normals:
        np.testing.assert_array_equal(K.frame_matrix(*n), frames.frame(n))


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
    for sphere, (radius, center, emission, color, kind) in zip(scene.spheres, SMALLPT):
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


def test_cornell_renders_like_smallpt():
    """Cheap sanity: the light is the brightest thing, the left wall red, the right wall blue."""
    image = render("cornell", width=32, height=24, spp=48, seed=5).image
    assert np.all(np.isfinite(image)) and image.min() >= 0
    left, right = image[8:16, 1:4].mean(axis=(0, 1)), image[8:16, -4:-1].mean(axis=(0, 1))
    assert left[0] > 1.5 * left[2] and right[2] > 1.5 * right[0]
    row, col = np.unravel_index(np.argmax(image[..., 0]), image.shape[:2])
    assert 2 <= row <= 4 and 12 <= col <= 20 and image[row, col, 0] > 6  # the light (radiance 12) in the ceiling


# --- Owen-scrambled Sobol' ---------------------------------------------------------


def test_sobol2_first_points():
    points = [tuple(int(c) / 2**32 for c in sobol2(np.uint64(i))) for i in range(4)]
    assert points == [(0, 0), (0.5, 0.5), (0.25, 0.75), (0.75, 0.25)]


def test_reverse_bits():
    for x in (0, 1, 2, 0x80000000, 0x12345678, 0xFFFFFFFF):
        assert int(reverse_bits32(np.uint64(x))) == int(format(x, "032b")[::-1], 2)


def test_owen_sobol_equals_its_definition():
    """The fast bit-reversed form equals scramble(sobol2(scramble(index))) (Burley 2020, listing 3)."""
    from numba import njit

    from symsphere.render._random import _GOLDEN, _MIX1, mix64

    @njit
    def definition(index, key):  # njit: the uint64 products wrap silently, as in the kernels
        m32 = np.uint64(0xFFFFFFFF)
        h1, h2 = mix64(key ^ _GOLDEN), mix64(key ^ _MIX1)
        x, y = sobol2(nested_uniform_scramble(np.uint64(index), h1 & m32))
        return nested_uniform_scramble(x, h1 >> np.uint64(32)), nested_uniform_scramble(y, h2 & m32)

    for key in (np.uint64(1), np.uint64(0xDEADBEEF12345)):
        points = K.sobol_points(512, key)
        for i in range(0, 512, 7):
            x, y = definition(i, key)
            assert tuple(points[i]) == (int(x) / 2**32, int(y) / 2**32)


@pytest.mark.parametrize("key", [0, 1, 2**63 + 12345, 987654321])
def test_owen_sobol_prefixes_are_nets(key):
    """The first 2^k points of one scramble form a (0, k, 2)-net: every dyadic box of area 2^-k holds one."""
    points = K.sobol_points(2**10, np.uint64(key))
    assert np.all((points >= 0) & (points < 1))
    for k in range(11):
        prefix = points[: 2**k]
        for a in range(k + 1):
            cells = np.floor(prefix[:, 0] * 2**a).astype(np.int64) * 2 ** (k - a) + np.floor(
                prefix[:, 1] * 2 ** (k - a)
            ).astype(np.int64)
            assert np.array_equal(np.sort(cells), np.arange(2**k)), (k, a)


def test_owen_scrambles_differ_between_keys():
    a, b = K.sobol_points(64, np.uint64(1)), K.sobol_points(64, np.uint64(2))
    assert not np.any(np.all(a == b, axis=1))


# --- the samplers ----------------------------------------------------------------

_ORBIT_SAMPLERS = [("symmetric", K.SYMMETRIC), ("symmetric_sobol", K.SYMMETRIC_SOBOL)]


@pytest.mark.parametrize("full, n", [(False, 24), (True, 48)])
@pytest.mark.parametrize("name, sampler", _ORBIT_SAMPLERS)
@pytest.mark.parametrize("method", ["equal_area", "paper1"])
def test_symmetric_groups_take_every_orbit_member_of_one_base(name, sampler, method, full, n):
    code = METHOD_CODES[method]
    groups = 3
    for depth in (0, 1, 5):
        out = K.pattern_directions(sampler, code, full, np.uint64(7), 1234, depth, groups * n)
        bases = []
        for g in range(groups):
            block = out[g * n : (g + 1) * n, :3]
            members, base = fold(block, domain="sphere")
            # one base point for the whole group...
            np.testing.assert_allclose(base, np.broadcast_to(base[0], base.shape), rtol=0, atol=1e-15)
            # ...and every member of its orbit exactly once (hemisphere: the 24 upper ones)
            assert sorted(members.tolist()) == list(range(n))
            np.testing.assert_array_equal(block[np.argsort(members)], orbit(base[0], domain="sphere")[:n])
            # weight = |cos| / (pi pdf), pdf = triangle pdf / n
            pdf = triangle_pdf(base[0], method) / n
            np.testing.assert_allclose(out[g * n : (g + 1) * n, 3], np.abs(block[:, 2]) / (np.pi * pdf), rtol=1e-12)
            bases.append(base[0])
        assert len({tuple(b) for b in bases}) == groups  # a fresh base point per group


def test_symmetric_members_are_shuffled_between_vertices():
    """Sample s must not keep member s mod 24 at every vertex (that would confine it to one triangle)."""
    members = []
    for depth in range(6):
        out = K.pattern_directions(K.SYMMETRIC, 0, False, np.uint64(3), 99, depth, 24)
        members.append(fold(out[:, :3], domain="sphere")[0])
    assert len({tuple(m) for m in members}) > 1


@pytest.mark.parametrize("full", [False, True])
@pytest.mark.parametrize("sampler", [K.UNIFORM, K.COSINE, K.ORBIT, K.SYMMETRIC, K.SYMMETRIC_SOBOL])
def test_sampled_directions_and_weights(sampler, full):
    out = K.pattern_directions(sampler, 0, full, np.uint64(11), 5, 2, 480)
    directions, weights = out[:, :3], out[:, 3]
    np.testing.assert_allclose(np.linalg.norm(directions, axis=1), 1.0, rtol=0, atol=1e-14)
    if not full:
        assert np.all(directions[:, 2] >= 0)
    else:
        assert np.any(directions[:, 2] < 0)
    z = np.abs(directions[:, 2])
    expected = {K.COSINE: np.full_like(z, 2.0 if full else 1.0)}.get(sampler, (4.0 if full else 2.0) * z)
    np.testing.assert_allclose(weights, expected, rtol=1e-12, atol=1e-15)


def test_paper_map_weights_use_their_density():
    out = K.pattern_directions(K.ORBIT, METHOD_CODES["paper2"], False, np.uint64(1), 0, 0, 240)
    _, base = fold(out[:, :3], domain="sphere")
    expected = np.abs(out[:, 2]) * 24 / (np.pi * triangle_pdf(base, "paper2"))
    np.testing.assert_allclose(out[:, 3], expected, rtol=1e-12)


# --- determinism -------------------------------------------------------------------


@pytest.mark.parametrize("sampler", ["symmetric_sobol", "equal_area"])
def test_same_seed_same_image_for_any_thread_count(sampler):
    previous = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = render("cornell", width=24, height=16, spp=30, sampler=sampler, seed=42).image
        numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
        two = render("cornell", width=24, height=16, spp=30, sampler=sampler, seed=42).image
    finally:
        numba.set_num_threads(previous)
    np.testing.assert_array_equal(one, two)
    other = render("cornell", width=24, height=16, spp=30, sampler=sampler, seed=43).image
    assert not np.array_equal(one, other)


def test_the_image_does_not_depend_on_how_samples_are_split_into_passes():
    scene = cornell()
    arrays = scene.arrays(16, 12)
    rows = np.arange(12, dtype=np.int64)

    def run(splits):
        accum = np.zeros((12, 16, 3))
        first = 0
        for count in splits:
            K.render_pass(
                arrays["spheres"], arrays["sphere_material"], arrays["quads"], arrays["quad_material"],
                arrays["materials"], arrays["camera"], arrays["background"], arrays["eps"], arrays["rr_depth"],
                arrays["max_depth"], K.SYMMETRIC, 0, K.BOX, np.uint64(9), first, count, rows[::-1].copy(), accum,
            )  # fmt: skip
            first += count
        return accum

    a, b = run([48]), run([5, 19, 24])
    np.testing.assert_allclose(a, b, rtol=1e-13)  # same samples; only the summation order differs


def test_render_result_fields():
    result = render("furnace", width=8, height=6, spp=24, sampler="symmetric_sobol", method="paper2", seed=1)
    assert result.image.shape == (6, 8, 3) and result.image.dtype == np.float64
    assert result.paths == 8 * 6 * 24 and result.paths_per_second > 0
    assert (result.sampler, result.method, result.pixel_filter, result.seed) == ("symmetric_sobol", "paper2", "box", 1)
    assert render("furnace", width=4, height=4, spp=1, sampler="cosine", seed=1).method is None
    tent = render("cornell", width=8, height=6, spp=4, pixel_filter="tent", seed=1)
    assert tent.pixel_filter == "tent" and np.all(np.isfinite(tent.image))


@pytest.mark.parametrize(
    "kwargs, named",
    [
        (dict(sampler="nope"), "sampler"),
        (dict(sampler="cosine", method="paper1"), "method"),
        (dict(method="nope"), "method"),
        (dict(width=0), "width"),
        (dict(spp=2.5), "spp"),
        (dict(seed=-1), "seed"),
        (dict(pixel_filter="gauss"), "pixel_filter"),
        (dict(scene="nope"), "scene"),
        (dict(threads=0), "threads"),
    ],
)
def test_render_rejects_bad_arguments(kwargs, named):
    arguments = dict(scene="cornell", width=4, height=4, spp=1, seed=0) | kwargs
    with pytest.raises(ValueError, match=named):
        render(**arguments)


# --- image I/O -------------------------------------------------------------------


def test_pfm_round_trip(tmp_path):
    rng = np.random.default_rng(1)
    image = rng.random((5, 7, 3)) * 10
    path = save_pfm(tmp_path / "x.pfm", image)
    raw = path.read_bytes()
    assert raw.startswith(b"PF\n7 5\n-1.0\n") and len(raw) == len(b"PF\n7 5\n-1.0\n") + 5 * 7 * 3 * 4
    np.testing.assert_array_equal(load_pfm(path), image.astype(np.float32))
    # bottom row first, little-endian
    first = np.frombuffer(raw[len(b"PF\n7 5\n-1.0\n") :][:12], dtype="<f4")
    np.testing.assert_array_equal(first, image[-1, 0].astype(np.float32))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.pfm"]  # no temporaries left


def test_pfm_reader_rejects_garbage(tmp_path):
    bad = tmp_path / "bad.pfm"
    bad.write_bytes(b"P6\n1 1\n255\n\x00\x00\x00")
    with pytest.raises(ValueError, match="not a PFM"):
        load_pfm(bad)
    bad.write_bytes(b"PF\n2 2\n-1.0\n" + b"\x00" * 8)
    with pytest.raises(ValueError, match="truncated"):
        load_pfm(bad)


def test_npy_and_png(tmp_path):
    from matplotlib.image import imread

    image = np.zeros((2, 3, 3))
    image[0, 0] = 1.0
    image[0, 1] = 0.5
    image[1, 2] = 7.0  # clamped
    np.testing.assert_array_equal(np.load(save_npy(tmp_path / "x.npy", image)), image)
    pixels = imread(save_png(tmp_path / "x.png", image))
    assert pixels.shape[:2] == (2, 3)
    np.testing.assert_array_equal(np.rint(pixels[..., :3] * 255).astype(int), tonemap(image).astype(int))
    assert tonemap(image)[0, 0].tolist() == [255] * 3 and tonemap(image)[1, 0].tolist() == [0] * 3
    assert tonemap(image)[0, 1, 0] == round(255 * (1.055 * 0.5 ** (1 / 2.4) - 0.055))  # 188
    assert tonemap(image, exposure=0.25)[0, 0, 0] == round(255 * (1.055 * 0.25 ** (1 / 2.4) - 0.055))


# --- scene files -----------------------------------------------------------------

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
    assert scene.name == "box" and len(scene.spheres) == 2 and len(scene.quads) == 3
    assert scene.camera.direction == (0, 0, -4) and scene.background == (0.1,) * 3 and scene.rr_depth == 4
    assert scene.materials["sheet"].transmittance == (0.5,) * 3 and scene.materials["chrome"].color == (1.0,) * 3
    image = render(str(toml_path), width=16, height=12, spp=48, seed=0).image
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


# --- the render verb ----------------------------------------------------------------


def test_render_verb_writes_png_pfm_npy(tmp_path, capsys):
    out = tmp_path / "img.png"
    arguments = ["render", "--scene", "cornell", "--width", "16", "--height", "12", "--spp", "24"]
    status = main([*arguments, "--sampler", "symmetric_sobol", "--seed", "3", "--no-progress", "--out", str(out)])
    assert status == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["img.npy", "img.pfm", "img.png"]
    expected = render("cornell", width=16, height=12, spp=24, sampler="symmetric_sobol", seed=3).image
    np.testing.assert_array_equal(np.load(tmp_path / "img.npy"), expected)
    np.testing.assert_array_equal(load_pfm(tmp_path / "img.pfm"), expected.astype(np.float32))
    assert (tmp_path / "img.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    closing = capsys.readouterr().out.strip().splitlines()
    assert len(closing) == 1 and "Mpaths/s" in closing[0] and " s = " in closing[0] and str(out) in closing[0]


@pytest.mark.parametrize(
    "arguments, named",
    [
        (["--sampler", "nope"], "--sampler"),
        (["--spp", "0"], "--spp"),
        (["--seed", "-2"], "--seed"),
        (["--out", "x.jpg"], "--out"),
        (["--scene", "nope"], "scene"),
        (["--sampler", "uniform", "--method", "paper1"], "method"),
        (["--exposure", "0"], "--exposure"),
    ],
)
def test_render_verb_rejects_bad_arguments(tmp_path, capsys, arguments, named):
    base = ["render", "--width", "4", "--height", "4", "--spp", "1", "--no-progress"]
    if "--out" not in arguments:
        base += ["--out", str(tmp_path / "x.png")]
    assert main([*base, *arguments]) == 2
    err = capsys.readouterr().err
    assert named in err
    assert not any(p.suffix in (".png", ".pfm", ".npy") for p in tmp_path.iterdir())


def test_render_verb_names_a_bad_scene_file(tmp_path, capsys):
    path = tmp_path / "s.toml"
    path.write_text(GOOD_TOML.replace("radius = 0.5", "radius = -0.5", 1))
    assert main(["render", "--scene", str(path), "--out", str(tmp_path / "x.png"), "--no-progress"]) == 2
    assert f"scene file {str(path)!r}: spheres[0].radius must be positive" in capsys.readouterr().err
    missing = tmp_path / "missing.toml"
    assert main(["render", "--scene", str(missing), "--out", str(tmp_path / "x.png"), "--no-progress"]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_samplers_listed():
    assert set(SAMPLERS) == {"symmetric", "symmetric_sobol", "equal_area", "paper1", "paper2", "uniform", "cosine"}
    assert math.isclose(2 * math.tan(math.radians(cornell().camera.fov) / 2), 0.5135, rel_tol=1e-15)


def test_the_documented_scene_file_loads_and_renders(tmp_path):
    import pathlib
    import re

    doc = pathlib.Path(__file__).resolve().parent.parent / "docs" / "rendering.md"
    if not doc.exists():
        pytest.skip("docs/rendering.md not present")
    block = re.search(r"```toml\n(.*?)```", doc.read_text(encoding="utf-8"), re.S).group(1)
    path = tmp_path / "example.toml"
    path.write_text(block)
    scene = load_scene(path)
    assert scene.name == "example" and {m.kind for m in scene.materials.values()} == {
        "diffuse", "translucent", "mirror", "dielectric",
    }  # fmt: skip
    assert render(str(path), width=16, height=12, spp=24, seed=0).image.mean() > 0
