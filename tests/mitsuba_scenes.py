"""The small Mitsuba scenes that several tests of symsphere_path render (tests/ is on pytest's pythonpath)."""

from __future__ import annotations

from typing import Any


def scene_dict(mi: Any, name: str, size: int) -> dict[str, Any]:
    """A *size* x *size* scene for ``mi.load_dict``: ``'cornell'`` (Mitsuba's Cornell box: one-sided
    diffuse walls, a rectangle light) or ``'textured'`` (a checker floor, a wall, a rough plastic and a
    glass sphere, a rectangle light and a constant sky)."""
    sensor_film = {"type": "hdrfilm", "width": size, "height": size, "rfilter": {"type": "box"}}
    if name == "cornell":  # Mitsuba's Cornell box: one-sided diffuse walls, a rectangle light
        scene = mi.cornell_box()
        scene["sensor"]["film"] = sensor_film
        scene["sensor"]["sampler"] = {"type": "independent"}
        return scene
    T = mi.ScalarTransform4f
    white = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.7, 0.7, 0.7]}}}
    checker = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {
        "type": "checkerboard", "color0": {"type": "rgb", "value": [0.8, 0.2, 0.1]}, "color1": {"type": "rgb", "value": [0.1, 0.3, 0.8]},
        "to_uv": T().scale([4, 4, 1])}}}  # fmt: skip
    return {
        "type": "scene",
        "sensor": {
            "type": "perspective",
            "fov": 50,
            "to_world": T().look_at(origin=[0, 1.2, 4.5], target=[0, 0.6, 0], up=[0, 1, 0]),
            "film": sensor_film,
            "sampler": {"type": "independent"},
        },  # fmt: skip
        "floor": {"type": "rectangle", "to_world": T().rotate([1, 0, 0], -90).scale(3), "bsdf": checker},
        "wall": {"type": "rectangle", "to_world": T().translate([0, 1.5, -1.5]).scale(3), "bsdf": white},
        "ball": {
            "type": "sphere",
            "center": [-0.7, 0.5, 0.2],
            "radius": 0.5,
            "bsdf": {
                "type": "roughplastic",
                "alpha": 0.2,
                "diffuse_reflectance": {"type": "rgb", "value": [0.2, 0.6, 0.3]},
            },
        },  # fmt: skip
        "glass": {"type": "sphere", "center": [0.8, 0.4, 0.6], "radius": 0.4, "bsdf": {"type": "dielectric"}},
        "light": {
            "type": "rectangle",
            "to_world": T().translate([0.5, 2.8, 0.5]).rotate([1, 0, 0], 90).scale(0.6),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [12, 11, 10]}},
        },  # fmt: skip
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [0.3, 0.35, 0.4]}},
    }
