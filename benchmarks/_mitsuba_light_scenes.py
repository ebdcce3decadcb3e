"""The scenes of ``bench_mitsuba_lights.py``: where a light's solid angle matters, and where it must not lose.

Each is a ``mitsuba.load_dict`` dictionary (``light_scene(name, width, height, workdir)``), box filter,
``independent`` sampler, two-sided ``diffuse`` surfaces unless said otherwise:

``cornell``
    The shipped Cornell box (``cornell_box.xml``): a small 2-triangle light on the ceiling.
``wall_wash``
    A 4 x 3 x 4 room; a 1.6 x 1.0 ``rectangle`` light 0.15 in front of the back wall, facing it (a wall
    washer), and a small ceiling panel; the camera sees the washed wall.
``disk_near_floor``
    A 24-triangle disk light (radius 0.5) 0.2 above the floor, facing down, in the same room, and the
    small ceiling panel.
``mesh_1024``
    A 1024-triangle light (a 32 x 16 grid of quads over 2.0 x 1.0, slightly domed) 0.3 above the floor,
    facing down, and the ceiling panel: above :data:`symsphere.mitsuba._lights.EXACT_MAX` triangles.
``textured``
    The shipped textured scene (a rectangle light, a constant sky: a mixed emitter set).
``veach_mis``
    The shipped Veach MIS scene: sphere lights only, which ``solid_angle`` leaves to Mitsuba.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["LIGHT_SCENES", "light_scene"]

LIGHT_SCENES = ("cornell", "wall_wash", "disk_near_floor", "mesh_1024", "textured", "veach_mis")
_SHIPPED = {"cornell": "cornell_box", "textured": "textured", "veach_mis": "veach_mis"}


def _diffuse(rgb):
    return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(rgb)}}}


def _emitter(rgb):
    return {"type": "area", "radiance": {"type": "rgb", "value": list(rgb)}}


def _write_obj(path, vertices, faces):
    with open(path, "w", encoding="utf-8") as f:
        f.writelines(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in vertices)
        f.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces)
    return str(path)


def _disk(segments, radius, center):
    """A disk of *segments* triangles about *center* in the plane y = center.y, facing down (-y)."""
    cx, cy, cz = center
    vertices = [(cx, cy, cz)] + [
        (cx + radius * np.cos(p), cy, cz + radius * np.sin(p)) for p in 2 * np.pi * np.arange(segments) / segments
    ]
    faces = [(0, k + 1, (k + 1) % segments + 1) for k in range(segments)]  # counter-clockwise from below
    return vertices, faces


def _grid(nx, nz, size, center, dome=0.05):
    """An nx x nz grid of quads (2 nx nz triangles) over size = (sx, sz) about *center*, facing down,
    its middle raised by *dome* (so the triangles are not all coplanar)."""
    cx, cy, cz = center
    sx, sz = size
    vertices = []
    for i in range(nx + 1):
        for j in range(nz + 1):
            a, b = i / nx - 0.5, j / nz - 0.5
            vertices.append((cx + a * sx, cy + dome * (1 - 4 * a * a) * (1 - 4 * b * b), cz + b * sz))
    faces = []
    for i in range(nx):
        for j in range(nz):
            v00, v10, v01, v11 = (
                i * (nz + 1) + j,
                (i + 1) * (nz + 1) + j,
                i * (nz + 1) + j + 1,
                (i + 1) * (nz + 1) + j + 1,
            )
            faces += [(v00, v10, v11), (v00, v11, v01)]  # normal -y for this winding
    return vertices, faces


def _room(mi, width, height, camera_origin, camera_target, sampler="independent"):
    T = mi.ScalarTransform4f
    return {
        "type": "scene",
        "sensor": {
            "type": "perspective",
            "fov": 60,
            "to_world": T().look_at(origin=camera_origin, target=camera_target, up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"}},
            "sampler": {"type": sampler},
        },
        # x in [-2, 2], y in [0, 3], z in [-2, 2]; Mitsuba's rectangle is [-1, 1]^2 in z = 0, normal +z
        "floor": {"type": "rectangle", "to_world": T().rotate([1, 0, 0], -90).scale([2, 2, 1]), "bsdf": _diffuse((0.7, 0.7, 0.7))},
        "ceiling": {"type": "rectangle", "to_world": T().translate([0, 3, 0]).rotate([1, 0, 0], 90).scale([2, 2, 1]),
                    "bsdf": _diffuse((0.75, 0.75, 0.75))},
        "back": {"type": "rectangle", "to_world": T().translate([0, 1.5, -2]).scale([2, 1.5, 1]), "bsdf": _diffuse((0.7, 0.7, 0.65))},
        "left": {"type": "rectangle", "to_world": T().translate([-2, 1.5, 0]).rotate([0, 1, 0], 90).scale([2, 1.5, 1]),
                 "bsdf": _diffuse((0.65, 0.2, 0.15))},
        "right": {"type": "rectangle", "to_world": T().translate([2, 1.5, 0]).rotate([0, 1, 0], -90).scale([2, 1.5, 1]),
                  "bsdf": _diffuse((0.2, 0.5, 0.25))},
        "panel": {"type": "rectangle", "to_world": T().translate([1.2, 2.999, 1.0]).rotate([1, 0, 0], 90).scale([0.15, 0.15, 1]),
                  "emitter": _emitter((15, 14, 12))},
        "ball": {"type": "sphere", "center": [0.9, 0.45, 0.3], "radius": 0.45, "bsdf": _diffuse((0.8, 0.6, 0.3))},
    }  # fmt: skip


def light_scene(mi, name, width, height, workdir, sampler="independent"):
    """The loaded scene *name* at width x height, its sensor's sampler *sampler* (a Mitsuba sampler's name)."""
    if name in _SHIPPED:
        import symsphere.mitsuba as sm

        return mi.load_file(str(sm.scene_path(_SHIPPED[name])), width=width, height=height, sampler=sampler)
    T = mi.ScalarTransform4f
    workdir = Path(workdir)
    if name == "wall_wash":
        scene = _room(mi, width, height, [0, 1.5, 3.8], [0, 1.4, -2], sampler)
        # 0.15 in front of the back wall, facing it (-z): Mitsuba's rectangle faces +z, so turn it round
        scene["washer"] = {"type": "rectangle", "to_world": T().translate([0, 1.8, -1.85]).rotate([0, 1, 0], 180).scale([0.8, 0.5, 1]),
                           "emitter": _emitter((10, 9.5, 8.5))}  # fmt: skip
    elif name == "disk_near_floor":
        scene = _room(mi, width, height, [0, 1.6, 3.8], [0, 0.3, -1], sampler)
        vertices, faces = _disk(24, 0.5, (-0.6, 0.2, -0.5))
        scene["disk"] = {"type": "obj", "filename": _write_obj(workdir / "disk24.obj", vertices, faces),
                         "emitter": _emitter((8, 7.5, 7))}  # fmt: skip
    elif name == "mesh_1024":
        scene = _room(mi, width, height, [0, 1.6, 3.8], [0, 0.3, -1], sampler)
        vertices, faces = _grid(32, 16, (2.0, 1.0), (-0.4, 0.3, -0.8))
        scene["strip"] = {"type": "obj", "filename": _write_obj(workdir / "grid1024.obj", vertices, faces),
                          "emitter": _emitter((4, 3.8, 3.5))}  # fmt: skip
    else:
        raise ValueError(f"{name!r} is not a light scene; use one of {sorted(LIGHT_SCENES)}")
    return mi.load_dict(scene)
