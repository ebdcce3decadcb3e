"""symsphere.render.scene: the scene data (Scene, Sphere, Quad, HalfSpace, materials), validated; the kernels' tables."""

import math

import numpy as np
import pytest

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
    translucent_scene,
)


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


# --- materials and emission validated at once ----------------------------------------------------------------------


def test_huge_emission_is_rejected_not_rendered_as_inf():
    from symsphere.render import SceneError, diffuse, scene_from_dict

    with pytest.raises(SceneError, match="emission must be at most"):
        scene_from_dict({
            "camera": {"position": [0, 0, 4], "direction": [0, 0, -1], "fov": 40},
            "materials": {"lamp": {"type": "diffuse", "albedo": 0, "emission": 1e308}},
            "spheres": [{"center": [0, 0, 0], "radius": 1, "material": "lamp"}],
        })  # fmt: skip
    assert diffuse(0.5, emission=1e30).emission == (1e30,) * 3


def test_dielectric_validates_at_once():
    from symsphere.render import dielectric

    for bad in (-1.0, float("nan"), "glass"):
        with pytest.raises(ValueError, match="ior"):
            dielectric(ior=bad)
