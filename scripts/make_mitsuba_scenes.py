"""Write the Mitsuba 3 scene files shipped in src/symsphere/mitsuba/scenes (XML + OBJ + PNG).

    .venv/bin/python scripts/make_mitsuba_scenes.py        # rewrites the folder; commit the result

Every file is loadable by plain Mitsuba 3 (``mi.load_file``; integrator ``path``), with the parameters
``width``, ``height`` (default 256), ``spp`` (48) and ``sampler`` (Mitsuba's sampler plugin, default
``independent``): ``mi.load_file(f, width=64, sampler="ldsampler")``, ``mitsuba -D spp=96``; ``symsphere render
--scene FILE.xml`` and benchmarks/bench_mitsuba.py render them with ``symsphere_path`` instead.

cornell_box
    The original Cornell box as triangle meshes, from Cornell's published measurements ("Cornell Box
    Data", Cornell University Program of Computer Graphics, https://www.graphics.cornell.edu/online/box/data.html):
    the room's, the light's and the two blocks' vertices in millimetres, the camera at (278, 273, -800)
    looking along +z with a 35 mm focal length and a 25 mm x 25 mm film (fov 2 atan(12.5/35) = 39.3
    degrees).  The measured reflectances and emission are spectra; the RGB values here are those of
    Mitsuba's own ``mi.cornell_box()`` (its RGB rendition of the same box).  All surfaces are one-sided
    ``diffuse`` facing the room, as measured.
veach_mis
    Veach-style MIS scene (Veach & Guibas 1995, fig. 8; our own geometry): four conductor plates of
    increasing roughness (GGX alpha 0.01, 0.04, 0.12, 0.3), lit by four spherical lights of increasing
    radius (0.03 ... 0.9, equal power), over a diffuse floor and back wall (two-sided).
door_room
    A room lit indirectly: the only light is a ceiling panel in a second room behind a wall, seen
    through a door standing ajar (a door leaf at 25 degrees in a 0.9-wide opening); two-sided diffuse.
textured
    A checkerboard floor (procedural ``checkerboard``), a wall with a bitmap texture (stripes.png,
    written here), a rough-plastic sphere and a textured diffuse sphere under a rectangle light and a dim sky.
smallpt_cornell, gap
    symsphere's own ``cornell`` (smallpt's box) and ``gap`` (benchmarks/_mitsuba_scenes.gap_room)
    scenes, exported with benchmarks/_mitsuba_scenes.mitsuba_dict as bench_render.py compares them.
"""

from __future__ import annotations

import math
import os
import shutil
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "src" / "symsphere" / "mitsuba" / "scenes"
WIDTH = HEIGHT = 256
SPP = 48

# --- a small dictionary -> Mitsuba XML writer ------------------------------------------------------

_SHAPES = {"rectangle", "sphere", "obj", "cube", "disk", "ply"}
_EMITTERS = {"constant", "envmap", "point", "directional"}
_CHILD_TAGS = {"sensor", "film", "sampler", "rfilter", "integrator", "bsdf", "emitter"}


def _tag_of(key: str, value: dict) -> str:
    if key in _CHILD_TAGS:
        return key
    kind = value["type"]
    if kind in _SHAPES:
        return "shape"
    if kind in _EMITTERS:
        return "emitter"
    if kind in ("checkerboard", "bitmap"):
        return "texture"
    if kind in ("path", "symsphere_path"):
        return "integrator"
    return "bsdf"


def _fmt(x: float) -> str:
    return f"{float(x):.9g}"


def _add(parent: ET.Element, key: str, value) -> None:
    import mitsuba as mi

    if isinstance(value, dict):
        if value.get("type") == "rgb":
            ET.SubElement(parent, "rgb", name=key, value=", ".join(_fmt(c) for c in value["value"]))
            return
        kind = "$sampler" if key == "sampler" else value["type"]  # the sampler is a parameter (bench_mitsuba.py)
        element = ET.SubElement(parent, _tag_of(key, value), type=kind)
        if parent.tag == "scene":
            element.set("id", key)
        elif element.tag == "texture" or (parent.tag == "bsdf" and element.tag == "bsdf" and key != "bsdf"):
            element.set("name", key)
        for k, v in value.items():
            if k != "type":
                _add(element, k, v)
    elif isinstance(value, mi.ScalarTransform4f):
        transform = ET.SubElement(parent, "transform", name=key)
        m = np.array(value.matrix, dtype=np.float64)
        ET.SubElement(transform, "matrix", value=" ".join(_fmt(c) for c in m.ravel()))
    elif isinstance(value, bool):
        ET.SubElement(parent, "boolean", name=key, value="true" if value else "false")
    elif isinstance(value, int):
        ET.SubElement(parent, "integer", name=key, value=str(value))
    elif isinstance(value, float):
        ET.SubElement(parent, "float", name=key, value=_fmt(value))
    elif isinstance(value, str) and value.startswith("$"):  # a parameter with a <default> (mitsuba -D)
        ET.SubElement(parent, "integer", name=key, value=value)
    elif isinstance(value, str):
        ET.SubElement(parent, "string", name=key, value=value)
    elif isinstance(value, (list, tuple)) and len(value) == 3:
        ET.SubElement(parent, "point", name=key, x=_fmt(value[0]), y=_fmt(value[1]), z=_fmt(value[2]))
    else:
        raise TypeError(f"cannot write {key!r} = {value!r}")


def write_xml(path: Path, scene: dict, comment: str) -> None:
    root = ET.Element("scene", version="3.0.0")
    for name, default in (("width", WIDTH), ("height", HEIGHT), ("spp", SPP), ("sampler", "independent")):
        ET.SubElement(root, "default", name=name, value=str(default))
    _parametrise(scene)
    for key, value in scene.items():
        if key != "type":
            _add(root, key, value)
    ET.indent(root)
    text = f"<!-- {comment} Written by scripts/make_mitsuba_scenes.py (symsphere). -->\n" + ET.tostring(
        root, encoding="unicode"
    )
    path.write_text(text + "\n", encoding="utf-8")


def _parametrise(scene: dict) -> None:
    """The film size and the sampler's sample count become the parameters $width, $height, $spp."""
    sensor = scene["sensor"]
    sensor["film"]["width"], sensor["film"]["height"] = "$width", "$height"
    sensor["sampler"]["sample_count"] = "$spp"


def write_obj(path: Path, quads: list) -> None:
    """Planar quads (4 vertices each, in order) as an OBJ of two triangles per quad."""
    lines = []
    for q, quad in enumerate(quads):
        lines += [f"v {_fmt(x)} {_fmt(y)} {_fmt(z)}" for x, y, z in quad]
        b = 4 * q + 1
        lines += [f"f {b} {b + 1} {b + 2}", f"f {b} {b + 2} {b + 3}"]
    path.write_text("\n".join(lines) + "\n", encoding="ascii")


def _rgb(*c):
    return {"type": "rgb", "value": list(c) if len(c) == 3 else [c[0]] * 3}


def _diffuse(c, twosided=True, texture=None):
    bsdf = {"type": "diffuse", "reflectance": texture if texture is not None else _rgb(*c)}
    return {"type": "twosided", "bsdf": bsdf} if twosided else bsdf


def _film():
    return {"type": "hdrfilm", "width": WIDTH, "height": HEIGHT, "rfilter": {"type": "box"},
            "pixel_format": "rgb", "component_format": "float32"}  # fmt: skip


def _sensor(mi, origin, target, fov, up=(0, 1, 0)):
    T = mi.ScalarTransform4f
    return {"type": "perspective", "fov": float(fov), "fov_axis": "x",
            "to_world": T().look_at(origin=list(origin), target=list(target), up=list(up)),
            "film": _film(), "sampler": {"type": "independent", "sample_count": SPP}}  # fmt: skip


def _integrator():
    return {"type": "path", "max_depth": 8, "rr_depth": 5}


# --- the scenes --------------------------------------------------------------------------------------

# Cornell's measurements (mm): each surface as its published vertex list.
CORNELL = {
    "floor": [[(552.8, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 559.2), (549.6, 0.0, 559.2)]],
    "light": [[(343.0, 548.8, 227.0), (343.0, 548.8, 332.0), (213.0, 548.8, 332.0), (213.0, 548.8, 227.0)]],
    "ceiling": [[(556.0, 548.8, 0.0), (556.0, 548.8, 559.2), (0.0, 548.8, 559.2), (0.0, 548.8, 0.0)]],
    "back_wall": [[(549.6, 0.0, 559.2), (0.0, 0.0, 559.2), (0.0, 548.8, 559.2), (556.0, 548.8, 559.2)]],
    "right_wall": [[(0.0, 0.0, 559.2), (0.0, 0.0, 0.0), (0.0, 548.8, 0.0), (0.0, 548.8, 559.2)]],
    "left_wall": [[(552.8, 0.0, 0.0), (549.6, 0.0, 559.2), (556.0, 548.8, 559.2), (556.0, 548.8, 0.0)]],
    "short_block": [
        [(130.0, 165.0, 65.0), (82.0, 165.0, 225.0), (240.0, 165.0, 272.0), (290.0, 165.0, 114.0)],
        [(290.0, 0.0, 114.0), (290.0, 165.0, 114.0), (240.0, 165.0, 272.0), (240.0, 0.0, 272.0)],
        [(130.0, 0.0, 65.0), (130.0, 165.0, 65.0), (290.0, 165.0, 114.0), (290.0, 0.0, 114.0)],
        [(82.0, 0.0, 225.0), (82.0, 165.0, 225.0), (130.0, 165.0, 65.0), (130.0, 0.0, 65.0)],
        [(240.0, 0.0, 272.0), (240.0, 165.0, 272.0), (82.0, 165.0, 225.0), (82.0, 0.0, 225.0)],
    ],
    "tall_block": [
        [(423.0, 330.0, 247.0), (265.0, 330.0, 296.0), (314.0, 330.0, 456.0), (472.0, 330.0, 406.0)],
        [(423.0, 0.0, 247.0), (423.0, 330.0, 247.0), (472.0, 330.0, 406.0), (472.0, 0.0, 406.0)],
        [(472.0, 0.0, 406.0), (472.0, 330.0, 406.0), (314.0, 330.0, 456.0), (314.0, 0.0, 456.0)],
        [(314.0, 0.0, 456.0), (314.0, 330.0, 456.0), (265.0, 330.0, 296.0), (265.0, 0.0, 296.0)],
        [(265.0, 0.0, 296.0), (265.0, 330.0, 296.0), (423.0, 330.0, 247.0), (423.0, 0.0, 247.0)],
    ],
}


def _facing(quads, inside_point):
    """Order each quad's vertices so that its normal (right-handed, OBJ winding) faces inside_point."""
    out = []
    for quad in quads:
        q = np.array(quad)
        n = np.cross(q[1] - q[0], q[2] - q[0])
        out.append(quad if n @ (np.asarray(inside_point) - q.mean(axis=0)) > 0 else quad[::-1])
    return out


def cornell_box(mi):
    ref = mi.cornell_box()  # its RGB reflectances and light radiance
    white, green, red = (ref[k]["reflectance"]["value"] for k in ("white", "green", "red"))
    radiance = ref["light"]["emitter"]["radiance"]["value"]
    centre = (278.0, 274.4, 279.6)
    scene = {"type": "scene", "integrator": _integrator(),
             "sensor": _sensor(mi, (278.0, 273.0, -800.0), (278.0, 273.0, 0.0), 2 * math.degrees(math.atan(12.5 / 35)))}  # fmt: skip
    colours = {"floor": white, "ceiling": white, "back_wall": white, "right_wall": green, "left_wall": red,
               "short_block": white, "tall_block": white, "light": [0.78, 0.78, 0.78]}  # fmt: skip
    for name, quads in CORNELL.items():
        if name.endswith("block"):  # outward normals: away from the block's centre
            c = np.array([v for q in quads for v in q]).mean(axis=0)
            quads = [q[::-1] for q in _facing(quads, c)]
        elif name == "light":
            quads = _facing(quads, (278.0, 0.0, 279.6))  # facing down
        else:
            quads = _facing(quads, centre)
        write_obj(OUT / f"cornell_box_{name}.obj", quads)
        shape = {
            "type": "obj",
            "filename": f"cornell_box_{name}.obj",
            "face_normals": True,
            "bsdf": _diffuse(colours[name], twosided=False),
        }
        if name == "light":
            shape["emitter"] = {"type": "area", "radiance": _rgb(*radiance)}
        scene[name] = shape
    return scene, "The original Cornell box from Cornell's published measurements (mm)."


def veach_mis(mi):
    T = mi.ScalarTransform4f
    scene = {"type": "scene", "integrator": _integrator(), "sensor": _sensor(mi, (0, 2.0, 15.0), (0, 1.2, 0), 40)}
    scene["floor"] = {
        "type": "rectangle",
        "to_world": T().translate([0, 0, 0]).rotate([1, 0, 0], -90).scale(20),
        "bsdf": _diffuse((0.4,)),
    }
    scene["back"] = {"type": "rectangle", "to_world": T().translate([0, 0, -6]).scale(20), "bsdf": _diffuse((0.4,))}
    eye, light_y, light_z = np.array([0, 2.0, 15.0]), 6.0, -3.0
    for k, alpha in enumerate((0.01, 0.04, 0.12, 0.3)):
        centre = np.array([0.0, 0.6 + 0.9 * k, 2.5 - 1.0 * k])
        to_eye = (eye - centre) / np.linalg.norm(eye - centre)
        to_light = np.array([0, light_y, light_z]) - centre
        to_light /= np.linalg.norm(to_light)
        normal = to_eye + to_light
        normal /= np.linalg.norm(normal)  # the plate reflects the lights towards the camera
        tangent = np.cross([1.0, 0, 0], normal)
        frame = np.eye(4)
        frame[:3, 0] = [4.0, 0, 0]
        frame[:3, 1] = 0.6 * tangent / np.linalg.norm(tangent)
        frame[:3, 2] = normal
        frame[:3, 3] = centre
        scene[f"plate{k}"] = {"type": "rectangle", "to_world": T(frame.tolist()),
                              "bsdf": {"type": "roughconductor", "material": "Al", "distribution": "ggx", "alpha": alpha}}  # fmt: skip
    for k, radius in enumerate((0.03, 0.1, 0.3, 0.9)):
        power = 4.0  # equal power: radiance ~ 1 / r^2
        scene[f"light{k}"] = {"type": "sphere", "center": [-3.75 + 2.5 * k, light_y, light_z], "radius": radius,
                              "emitter": {"type": "area", "radiance": _rgb(power / (radius * radius))}}  # fmt: skip
    scene["fill"] = {"type": "constant", "radiance": _rgb(0.02)}
    return (
        scene,
        "A Veach-style MIS scene: four plates of increasing roughness, four spherical lights of increasing size.",
    )


def door_room(mi):
    T = mi.ScalarTransform4f
    W, H, D, P, door, ajar = 5.0, 2.6, 8.0, 4.0, 0.9, math.radians(25)

    def rect(corner, e1, e2, bsdf, emitter=None):
        corner, e1, e2 = (np.asarray(v, dtype=np.float64) for v in (corner, e1, e2))
        n = np.cross(e1, e2)
        m = np.eye(4)
        m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = e1 / 2, e2 / 2, n / np.linalg.norm(n), corner + (e1 + e2) / 2
        shape = {"type": "rectangle", "to_world": T(m.tolist()), "bsdf": bsdf}
        if emitter:
            shape["emitter"] = emitter
        return shape

    white, warm = _diffuse((0.75,)), _diffuse((0.75, 0.6, 0.45))
    x0 = 3.2  # the door opening x in [x0, x0 + door] of the partition z = P
    scene = {
        "type": "scene",
        "integrator": _integrator(),
        "sensor": _sensor(mi, (1.2, 1.5, D - 0.2), (3.0, 1.0, P), 60),
    }
    scene |= {
        "floor": rect((0, 0, 0), (0, 0, D), (W, 0, 0), white),
        "ceiling": rect((0, H, 0), (W, 0, 0), (0, 0, D), white),
        "left": rect((0, 0, 0), (0, H, 0), (0, 0, D), _diffuse((0.7, 0.25, 0.2))),
        "right": rect((W, 0, 0), (0, 0, D), (0, H, 0), _diffuse((0.25, 0.45, 0.7))),
        "back": rect((0, 0, 0), (W, 0, 0), (0, H, 0), warm),
        "front": rect((0, 0, D), (0, H, 0), (W, 0, 0), white),
        "wall_a": rect((0, 0, P), (x0, 0, 0), (0, H, 0), white),
        "wall_b": rect((x0 + door, 0, P), (W - x0 - door, 0, 0), (0, H, 0), white),
        "lintel": rect((x0, 2.1, P), (door, 0, 0), (0, H - 2.1, 0), white),
        "door": rect(
            (x0 + door, 0, P),
            (-door * math.cos(ajar), 0, door * math.sin(ajar)),
            (0, 2.1, 0),
            _diffuse((0.5, 0.35, 0.2)),
        ),
        "light": rect((1.0, H - 1e-3, 1.0), (3.0, 0, 0), (0, 0, 2.0), white, {"type": "area", "radiance": _rgb(15.0)}),
    }
    return scene, "A room lit indirectly: the light is in a second room, seen through a door standing ajar."


def textured(mi):
    T = mi.ScalarTransform4f
    from symsphere.render import save_png

    v = np.linspace(0, 1, 256)
    stripes = 0.15 + 0.7 * (0.5 + 0.5 * np.sin(2 * np.pi * 12 * v))[None, :, None] * np.array([0.9, 0.8, 0.3])
    save_png(OUT / "textured_stripes.png", np.broadcast_to(stripes, (64, 256, 3)).copy())
    checker = {
        "type": "checkerboard",
        "color0": _rgb(0.8, 0.8, 0.75),
        "color1": _rgb(0.15, 0.15, 0.2),
        "to_uv": T().scale([8, 8, 1]),
    }
    bitmap = {"type": "bitmap", "filename": "textured_stripes.png", "to_uv": T().scale([2, 1, 1])}
    scene = {"type": "scene", "integrator": _integrator(), "sensor": _sensor(mi, (0, 1.5, 5.0), (0, 0.7, 0), 45)}
    scene |= {
        "floor": {
            "type": "rectangle",
            "to_world": T().rotate([1, 0, 0], -90).scale(4),
            "bsdf": _diffuse(None, texture=checker),
        },
        "wall": {
            "type": "rectangle",
            "to_world": T().translate([0, 2, -2]).scale([4, 2, 1]),
            "bsdf": _diffuse(None, texture=bitmap),
        },
        "plastic": {
            "type": "sphere",
            "center": [-0.8, 0.6, 0.0],
            "radius": 0.6,
            "bsdf": {"type": "roughplastic", "alpha": 0.15, "diffuse_reflectance": _rgb(0.2, 0.5, 0.25)},
        },  # fmt: skip
        "ball": {
            "type": "sphere",
            "center": [0.9, 0.45, 0.6],
            "radius": 0.45,
            "bsdf": _diffuse(None, texture=dict(checker, to_uv=T().scale([6, 3, 1]))),
        },
        "light": {
            "type": "rectangle",
            "to_world": T().translate([0.5, 3.5, 1.0]).rotate([1, 0, 0], 90).scale(0.8),
            "emitter": {"type": "area", "radiance": _rgb(14, 13, 11)},
        },  # fmt: skip
        "sky": {"type": "constant", "radiance": _rgb(0.15, 0.18, 0.22)},
    }
    return scene, "A textured scene: a checkerboard floor, a bitmap-textured wall, glossy and textured spheres."


def exported(mi, name):
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from _mitsuba_scenes import gap_room, mitsuba_dict

    from symsphere.render import cornell

    scene_obj = cornell() if name == "smallpt_cornell" else gap_room()
    workdir = OUT / f"_{name}_tmp"
    workdir.mkdir(exist_ok=True)
    d = mitsuba_dict(scene_obj, WIDTH, HEIGHT, SPP, workdir=str(workdir))
    for value in d.values():  # mesh files next to the XML, relative names
        if isinstance(value, dict) and value.get("type") == "obj":
            target = f"{name}_{Path(value['filename']).name}"
            shutil.move(value["filename"], OUT / target)
            value["filename"] = target
    workdir.rmdir()
    d["integrator"] = dict(d["integrator"])
    note = "smallpt's Cornell box" if name == "smallpt_cornell" else "the gap room (light through a gap)"
    return d, f"symsphere's {note}, exported by benchmarks/_mitsuba_scenes.mitsuba_dict."


def main() -> None:
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    if OUT.exists():
        for f in OUT.iterdir():
            if f.suffix in (".xml", ".obj", ".png"):
                f.unlink()
    OUT.mkdir(parents=True, exist_ok=True)
    makers = {"cornell_box": cornell_box, "veach_mis": veach_mis, "door_room": door_room, "textured": textured,
              "smallpt_cornell": lambda m: exported(m, "smallpt_cornell"), "gap": lambda m: exported(m, "gap")}  # fmt: skip
    for name, make in makers.items():
        scene, comment = make(mi)
        write_xml(OUT / f"{name}.xml", scene, comment)
        mi.load_file(str(OUT / f"{name}.xml"))  # loadable by plain Mitsuba
        print(f"wrote {os.path.relpath(OUT / (name + '.xml'), ROOT)}")


if __name__ == "__main__":
    main()
