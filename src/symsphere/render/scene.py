"""Scenes as plain data: camera, materials, spheres and parallelograms; file loading; built-in scenes.

A :class:`Scene` is validated when it is made (from Python or from a file);
:meth:`Scene.arrays` packs it into the float64/int64 arrays the numba kernels
take.  Errors name the field, e.g. ``scene file 'x.toml': spheres[2].radius
must be positive, got -1.0``.

File format (TOML or JSON, the same structure; see ``docs/rendering.md``)::

    name = "example"                       # optional (default: the file name)

    [camera]
    position = [0, 1, 5]
    direction = [0, 0, -1]                 # or look_at = [x, y, z]
    up = [0, 1, 0]                         # optional, default [0, 1, 0]
    fov = 40                               # vertical field of view, degrees
    near = 0                               # optional: rays start this far along `direction`

    [settings]                             # optional
    background = [0, 0, 0]                 # radiance of escaping rays
    epsilon = 1e-6                         # ray offset; default 1e-6 * max(1, |camera.position|)
    rr_depth = 5                           # Russian roulette from this vertex on
    max_depth = 1024

    [materials.white]                      # type: diffuse | translucent | mirror | dielectric
    type = "diffuse"
    albedo = 0.75                          # a number or [r, g, b], in [0, 1]
    emission = [0, 0, 0]                   # optional on every type, >= 0

    [[spheres]]
    center = [0, 1, 0]
    radius = 1
    material = "white"
    clip = { point = [0, 1.5, 0], normal = [0, 1, 0] }   # optional: keep only the part on the normal's side

    [[quads]]                              # parallelogram corner + s edge1 + t edge2, s, t in [0, 1]
    corner = [-5, 0, -5]
    edge1 = [10, 0, 0]
    edge2 = [0, 0, 10]
    material = "white"

A sphere with ``clip`` is the sphere intersected with the closed half-space
``{p : normal . (p - point) >= 0}`` (an open spherical cap, seen from both
sides); next-event estimation samples such a sphere by area on the cap.

Material parameters: ``diffuse``: albedo; ``translucent``: reflectance,
transmittance (reflectance + transmittance <= 1 per channel); ``mirror``:
reflectance; ``dielectric``: ior (> 0), tint.  Colours are in [0, 1].
"""

from __future__ import annotations

import json
import math
import os
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping

import numpy as np
import numpy.typing as npt

from . import _integrator as _k

__all__ = [
    "MATERIAL_KINDS",
    "SCENES",
    "Camera",
    "HalfSpace",
    "Material",
    "Quad",
    "Scene",
    "SceneError",
    "Sphere",
    "cornell",
    "dielectric",
    "diffuse",
    "furnace",
    "get_scene",
    "load_scene",
    "mirror",
    "scene_from_dict",
    "translucent",
    "translucent_scene",
]

MATERIAL_KINDS = ("diffuse", "translucent", "mirror", "dielectric")
_KIND_CODES = {"diffuse": _k.DIFFUSE, "translucent": _k.TRANSLUCENT, "mirror": _k.MIRROR, "dielectric": _k.DIELECTRIC}
# The parameters each kind takes, in a file: (file key, attribute, default)
_KIND_KEYS = {
    "diffuse": (("albedo", "color", None),),
    "translucent": (("reflectance", "color", None), ("transmittance", "transmittance", None)),
    "mirror": (("reflectance", "color", 1.0),),
    "dielectric": (("ior", "ior", 1.5), ("tint", "color", 1.0)),
}
_BLACK = (0.0, 0.0, 0.0)


class SceneError(ValueError):
    """A scene (from Python or a file) is invalid; the message names the field.

    Examples
    --------
    >>> from symsphere.render import Camera, Scene, SceneError, Sphere, diffuse
    >>> try:
    ...     Scene("s", Camera((0, 0, 5), (0, 0, -1), 40), {"m": diffuse(0.5)}, (Sphere((0, 0, 0), -1, "m"),))
    ... except SceneError as error:
    ...     print(error)
    scene 's': spheres[0].radius must be positive, got -1.0
    """


# --- the data -----------------------------------------------------------------


@dataclass(frozen=True)
class Material:
    """A surface material (made with :func:`diffuse`, :func:`translucent`, :func:`mirror`, :func:`dielectric`).

    Attributes
    ----------
    kind : {'diffuse', 'translucent', 'mirror', 'dielectric'}
    color : tuple of 3 floats
        Albedo (diffuse), reflectance (translucent, mirror) or tint (dielectric).
    transmittance : tuple of 3 floats
        Translucent only.
    ior : float
        Dielectric only (inside / outside).
    emission : tuple of 3 floats
        Emitted radiance (two-sided), any kind.

    Examples
    --------
    >>> from symsphere.render import Material
    >>> Material("diffuse", (0.5, 0.5, 0.5)).kind
    'diffuse'
    """

    kind: str
    color: tuple = (0.0, 0.0, 0.0)
    transmittance: tuple = (0.0, 0.0, 0.0)
    ior: float = 1.5
    emission: tuple = (0.0, 0.0, 0.0)


def diffuse(albedo: npt.ArrayLike, emission: npt.ArrayLike = 0.0) -> Material:
    """Lambertian reflection with *albedo* (a number or RGB), optionally emitting.

    Examples
    --------
    >>> from symsphere.render import diffuse
    >>> diffuse(0.5, emission=[1, 2, 3]).emission
    (1.0, 2.0, 3.0)
    """
    return Material("diffuse", _rgb(albedo, "albedo"), emission=_rgb(emission, "emission"))


def translucent(reflectance: npt.ArrayLike, transmittance: npt.ArrayLike, emission: npt.ArrayLike = 0.0) -> Material:
    """Lambertian reflection and transmission (sampled over the whole sphere).

    Examples
    --------
    >>> from symsphere.render import translucent
    >>> translucent(0.2, [0.5, 0.4, 0.3]).transmittance
    (0.5, 0.4, 0.3)
    """
    return Material(
        "translucent",
        _rgb(reflectance, "reflectance"),
        _rgb(transmittance, "transmittance"),
        emission=_rgb(emission, "emission"),
    )


def mirror(reflectance: npt.ArrayLike = 1.0) -> Material:
    """A perfect mirror.

    Examples
    --------
    >>> from symsphere.render import mirror
    >>> mirror(0.9).color
    (0.9, 0.9, 0.9)
    """
    return Material("mirror", _rgb(reflectance, "reflectance"))


def dielectric(ior: float = 1.5, tint: npt.ArrayLike = 1.0) -> Material:
    """A smooth dielectric interface (exact Fresnel) with index of refraction *ior* inside.

    Examples
    --------
    >>> from symsphere.render import dielectric
    >>> dielectric(1.33).ior
    1.33
    """
    return Material("dielectric", _rgb(tint, "tint"), ior=ior)


@dataclass(frozen=True)
class HalfSpace:
    """The closed half-space ``{p : normal . (p - point) >= 0}`` (*normal* need not be unit).

    Examples
    --------
    >>> from symsphere.render import HalfSpace
    >>> HalfSpace((0, 81.6, 0), (0, -1, 0)).normal
    (0, -1, 0)
    """

    point: tuple
    normal: tuple


@dataclass(frozen=True)
class Sphere:
    """A sphere; with *clip*, only its part inside that :class:`HalfSpace` (a spherical cap).

    Examples
    --------
    >>> from symsphere.render import HalfSpace, Sphere
    >>> cap = Sphere((0, 10, 0), 10, "lamp", clip=HalfSpace((0, 1, 0), (0, -1, 0)))
    >>> cap.radius
    10
    """

    center: tuple
    radius: float
    material: str
    clip: HalfSpace | None = None


@dataclass(frozen=True)
class Quad:
    """The parallelogram ``corner + s * edge1 + t * edge2``, s, t in [0, 1]; normal along edge1 x edge2.

    Examples
    --------
    >>> from symsphere.render import Quad
    >>> Quad((0, 0, 0), (1, 0, 0), (0, 1, 0), "lamp").edge2
    (0, 1, 0)
    """

    corner: tuple
    edge1: tuple
    edge2: tuple
    material: str


@dataclass(frozen=True)
class Camera:
    """A pinhole camera.

    Attributes
    ----------
    position, direction : tuple of 3 floats
        Eye and viewing direction (any length).
    fov : float
        Vertical field of view, degrees.
    up : tuple of 3 floats
        The image's up direction (need not be orthogonal to *direction*).
    near : float
        Rays start on the plane at this distance along *direction* (smallpt's 140).

    Examples
    --------
    >>> from symsphere.render import Camera
    >>> Camera((0, 1, 5), (0, 0, -1), 40).up
    (0.0, 1.0, 0.0)
    """

    position: tuple
    direction: tuple
    fov: float
    up: tuple = (0.0, 1.0, 0.0)
    near: float = 0.0


@dataclass(frozen=True)
class Scene:
    """A scene: camera, named materials, spheres, quads and settings (validated on creation).

    Raises :class:`SceneError` naming the first invalid field.

    Examples
    --------
    >>> from symsphere.render import Camera, Scene, Sphere, diffuse, render
    >>> lamp = {"lamp": diffuse(0.0, emission=1.0)}
    >>> scene = Scene("ball", Camera((0, 0, 4), (0, 0, -1), 40), lamp, (Sphere((0, 0, 0), 1, "lamp"),))
    >>> float(render(scene, width=8, height=6, spp=2, seed=0).image[3, 4, 0])   # the centre sees the lamp
    1.0
    """

    name: str
    camera: Camera
    materials: Mapping[str, Material]
    spheres: tuple = ()
    quads: tuple = ()
    background: tuple = (0.0, 0.0, 0.0)
    epsilon: float | None = None
    rr_depth: int = 5
    max_depth: int = 1024
    source: str | None = field(default=None, compare=False, repr=False)

    def __post_init__(self):
        where = f"scene file {self.source!r}" if self.source else f"scene {self.name!r}"
        try:
            _normalise(self)
        except SceneError as exc:
            raise SceneError(f"{where}: {exc}") from None

    @property
    def ray_epsilon(self) -> float:
        """The ray offset used: *epsilon*, or 1e-6 * max(1, |camera.position|)."""
        if self.epsilon is not None:
            return self.epsilon
        return 1e-6 * max(1.0, math.sqrt(sum(c * c for c in self.camera.position)))

    def arrays(self, width: int, height: int) -> dict:
        """The scene packed for the kernels (float64 / int64 arrays), for an image of width x height.

        Objects are numbered as the kernels see them: the unclipped spheres
        in scene order, then the clipped ones, then the quads.
        """
        names = list(self.materials)
        index = {name: i for i, name in enumerate(names)}
        materials = np.zeros((len(names), _k.MATERIAL_COLUMNS))
        for i, name in enumerate(names):
            m = self.materials[name]
            materials[i] = [_KIND_CODES[m.kind], *m.color, *m.transmittance, m.ior, *m.emission]
        # unclipped spheres first (the kernels test them in their own loop), each group in scene order
        ordered = [s for s in self.spheres if s.clip is None] + [s for s in self.spheres if s.clip is not None]
        spheres = np.zeros((len(ordered), _k.SPHERE_COLUMNS))
        areas = []
        for i, s in enumerate(ordered):
            axis, offset, cap_height = _clip_table(s)
            spheres[i] = [*s.center, s.radius, s.radius * s.radius, *axis, offset, cap_height, 1.0 / s.radius]
            areas.append(2 * math.pi * s.radius * cap_height)  # Archimedes: the area of a cap is 2 pi r h
        quads = np.zeros((len(self.quads), _k.QUAD_COLUMNS))
        for i, q in enumerate(self.quads):
            p0, e1, e2 = (np.array(v, dtype=np.float64) for v in (q.corner, q.edge1, q.edge2))
            normal_raw = np.cross(e1, e2)
            squared = float(normal_raw @ normal_raw)
            normal = normal_raw / math.sqrt(squared)
            l1, l2 = math.sqrt(float(e1 @ e1)), math.sqrt(float(e2 @ e2))
            rectangle = abs(float(e1 @ e2)) <= 1e-12 * l1 * l2  # sampled by solid angle (Urena et al. 2013)
            quads[i] = [
                *p0, *e1, *e2, *normal, *(normal_raw / squared), float(normal @ p0), math.sqrt(squared),
                *(e1 / l1), *(e2 / l2), l1, l2, float(rectangle),
            ]  # fmt: skip
            areas.append(math.sqrt(squared))
        lights, light_pmf = _light_tables(
            [materials[index[o.material], 8:11] for o in (*ordered, *self.quads)], areas
        )
        return dict(
            spheres=np.ascontiguousarray(spheres.T),  # structure of arrays: the kernels vectorise over objects
            sphere_material=np.array([index[s.material] for s in ordered], dtype=np.int64),
            quads=np.ascontiguousarray(quads.T),
            quad_material=np.array([index[q.material] for q in self.quads], dtype=np.int64),
            materials=materials,
            lights=lights,
            light_pmf=light_pmf,
            camera=self.camera_array(width, height),
            background=np.array(self.background, dtype=np.float64),
            eps=float(self.ray_epsilon),
            rr_depth=int(self.rr_depth),
            max_depth=int(self.max_depth),
        )

    def camera_array(self, width: int, height: int) -> np.ndarray:
        """position, forward (unit), right and up spanning the image plane at distance 1, near.

        A pixel position (sx, sy) in [-0.5, 0.5]^2 (sy up) looks along
        ``forward + sx * right + sy * up``.
        """
        cam = self.camera
        forward = _unit(cam.direction)
        right = _unit(np.cross(forward, np.array(cam.up, dtype=np.float64)))
        up = _unit(np.cross(right, forward))
        height_at_1 = 2 * math.tan(math.radians(cam.fov) / 2)  # the image plane at distance 1 is this high
        return np.array(
            [*cam.position, *forward, *(right * (height_at_1 * width / height)), *(up * height_at_1), cam.near],
            dtype=np.float64,
        )


def _clip_table(sphere):
    """Kernel rows of a sphere's clip: unit axis a into the kept side, offset d (keep a . p >= d), cap height.

    The kept cap is {p on the sphere : a . (p - c) >= d - a . c}; its height
    along a is ``r - max(d - a . c, -r)`` (2 r for an unclipped sphere, whose
    axis is 0 and offset -inf, so that the intersection test keeps every point).
    """
    if sphere.clip is None:
        return (0.0, 0.0, 0.0), -math.inf, 2.0 * sphere.radius
    axis = _unit(sphere.clip.normal)
    offset = float(axis @ np.array(sphere.clip.point, dtype=np.float64))
    lowest = offset - float(axis @ np.array(sphere.center, dtype=np.float64))
    return tuple(float(c) for c in axis), offset, sphere.radius - max(lowest, -sphere.radius)


def _light_tables(emissions, areas):
    """Emitters chosen by power: (2, L) rows object index, cumulative probability; and the pmf per object.

    Power of an emitter = mean emitted radiance over RGB x area (x pi, x 2
    sides: common factors).  Objects are numbered spheres first, then quads.
    """
    power = np.array([float(np.mean(e)) * a for e, a in zip(emissions, areas)], dtype=np.float64)
    emitters = np.flatnonzero(power > 0)
    pmf = np.zeros(len(power))
    if emitters.size:
        pmf[emitters] = power[emitters] / power[emitters].sum()
    cdf = np.cumsum(pmf[emitters])
    if cdf.size:
        cdf[-1] = 1.0  # no rounding gap at the top: u < 1 always selects an emitter
    lights = np.ascontiguousarray(np.stack([emitters.astype(np.float64), cdf]))
    return lights, pmf


# --- validation -----------------------------------------------------------------


def _normalise(scene: Scene) -> None:
    """Convert every field to plain floats / tuples in place and check it; SceneError names the field."""
    put = object.__setattr__
    if not isinstance(scene.name, str) or not scene.name:
        raise SceneError(f"name must be a non-empty string, got {scene.name!r}")
    if not isinstance(scene.camera, Camera):
        raise SceneError(f"camera must be a Camera, got {type(scene.camera).__name__}")
    put(scene, "camera", _check_camera(scene.camera))
    if not isinstance(scene.materials, Mapping) or not scene.materials:
        raise SceneError("materials must be a non-empty mapping of names to materials")
    materials = {}
    for name, material in scene.materials.items():
        if not isinstance(name, str) or not name:
            raise SceneError(f"material names must be non-empty strings, got {name!r}")
        materials[name] = _check_material(material, f"materials.{name}")
    put(scene, "materials", materials)
    spheres = []
    for i, sphere in enumerate(_sequence(scene.spheres, "spheres")):
        where = f"spheres[{i}]"
        if not isinstance(sphere, Sphere):
            raise SceneError(f"{where} must be a Sphere, got {type(sphere).__name__}")
        radius = _number(sphere.radius, f"{where}.radius")
        if not radius > 0:
            raise SceneError(f"{where}.radius must be positive, got {radius!r}")
        material = _material_name(sphere.material, materials, f"{where}.material")
        center = _vector(sphere.center, f"{where}.center")
        clip = _check_clip(sphere.clip, center, radius, f"{where}.clip")
        spheres.append(Sphere(center, radius, material, clip))
    put(scene, "spheres", tuple(spheres))
    quads = []
    for i, quad in enumerate(_sequence(scene.quads, "quads")):
        where = f"quads[{i}]"
        if not isinstance(quad, Quad):
            raise SceneError(f"{where} must be a Quad, got {type(quad).__name__}")
        corner = _vector(quad.corner, f"{where}.corner")
        edge1 = _vector(quad.edge1, f"{where}.edge1")
        edge2 = _vector(quad.edge2, f"{where}.edge2")
        normal = np.cross(edge1, edge2)
        if not float(normal @ normal) > 0 or not np.all(np.isfinite(normal)):
            raise SceneError(f"{where}: edge1 and edge2 must be non-zero and not parallel")
        material = _material_name(quad.material, materials, f"{where}.material")
        quads.append(Quad(corner, edge1, edge2, material))
    put(scene, "quads", tuple(quads))
    if not spheres and not quads:
        raise SceneError("needs at least one sphere or quad")
    put(scene, "background", _color(scene.background, "settings.background", upper=None))
    if scene.epsilon is not None:
        epsilon = _number(scene.epsilon, "settings.epsilon")
        if not epsilon > 0:
            raise SceneError(f"settings.epsilon must be positive, got {epsilon!r}")
        put(scene, "epsilon", epsilon)
    put(scene, "rr_depth", _integer(scene.rr_depth, "settings.rr_depth", 1))
    put(scene, "max_depth", _integer(scene.max_depth, "settings.max_depth", 1))


def _check_camera(cam: Camera) -> Camera:
    position = _vector(cam.position, "camera.position")
    direction = _vector(cam.direction, "camera.direction")
    if not float(np.dot(direction, direction)) > 0:
        raise SceneError("camera.direction must be non-zero")
    up = _vector(cam.up, "camera.up")
    cross = np.cross(_unit(direction), up)
    if not float(cross @ cross) > 1e-24:
        raise SceneError("camera.up must be non-zero and not parallel to camera.direction")
    fov = _number(cam.fov, "camera.fov")
    if not 0 < fov < 180:
        raise SceneError(f"camera.fov must be in (0, 180) degrees, got {fov!r}")
    near = _number(cam.near, "camera.near")
    if not near >= 0:
        raise SceneError(f"camera.near must be >= 0, got {near!r}")
    return Camera(position, direction, fov, up, near)


def _check_clip(clip, center, radius, where) -> HalfSpace | None:
    if clip is None:
        return None
    if not isinstance(clip, HalfSpace):
        raise SceneError(f"{where} must be a HalfSpace, got {type(clip).__name__}")
    point = _vector(clip.point, f"{where}.point")
    normal = _vector(clip.normal, f"{where}.normal")
    if not float(np.dot(normal, normal)) > 0:
        raise SceneError(f"{where}.normal must be non-zero")
    axis = _unit(normal)
    lowest = float(axis @ (np.array(point) - np.array(center)))  # the cap keeps a . (p - c) >= lowest
    if not lowest < radius * (1 - 1e-12):
        raise SceneError(f"{where} keeps nothing of the sphere (the plane is {lowest - radius:g} beyond it)")
    return HalfSpace(point, normal)


def _check_material(material, where) -> Material:
    if not isinstance(material, Material):
        raise SceneError(f"{where} must be a Material, got {type(material).__name__}")
    if material.kind not in MATERIAL_KINDS:
        raise SceneError(f"{where}.type must be one of {', '.join(MATERIAL_KINDS)}; got {material.kind!r}")
    color_name = {"diffuse": "albedo", "dielectric": "tint"}.get(material.kind, "reflectance")
    color = _color(material.color, f"{where}.{color_name}", upper=1.0)
    transmittance = _color(material.transmittance, f"{where}.transmittance", upper=1.0)
    if material.kind == "translucent" and any(r + t > 1.0 for r, t in zip(color, transmittance)):
        raise SceneError(f"{where}: reflectance + transmittance must be <= 1 in every channel (energy conservation)")
    if material.kind != "translucent":
        transmittance = _BLACK
    ior = _number(material.ior, f"{where}.ior")
    if not ior > 0:
        raise SceneError(f"{where}.ior must be positive, got {ior!r}")
    emission = _color(material.emission, f"{where}.emission", upper=None)
    return Material(material.kind, color, transmittance, ior, emission)


def _sequence(value, where):
    if isinstance(value, (str, bytes, Mapping)) or not hasattr(value, "__iter__"):
        raise SceneError(f"{where} must be a list, got {type(value).__name__}")
    return list(value)


def _number(value, where) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise SceneError(f"{where} must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise SceneError(f"{where} must be finite, got {value!r}")
    return value


def _integer(value, where, minimum) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise SceneError(f"{where} must be an integer, got {value!r}")
    if value < minimum:
        raise SceneError(f"{where} must be >= {minimum}, got {value!r}")
    return int(value)


def _vector(value, where) -> tuple:
    if isinstance(value, (str, bytes, Mapping)) or not hasattr(value, "__len__") or len(value) != 3:
        raise SceneError(f"{where} must be 3 numbers [x, y, z], got {value!r}")
    return tuple(_number(c, f"{where}[{i}]") for i, c in enumerate(value))


def _color(value, where, upper) -> tuple:
    if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool):
        value = (value, value, value)
    elif isinstance(value, (str, bytes, Mapping)) or not hasattr(value, "__len__") or len(value) != 3:
        raise SceneError(f"{where} must be a number or 3 numbers [r, g, b], got {value!r}")
    rgb = tuple(_number(c, where) for c in value)
    for c in rgb:
        if c < 0 or (upper is not None and c > upper):
            allowed = f"in [0, {upper:g}]" if upper is not None else ">= 0"
            raise SceneError(f"{where} must be {allowed}, got {list(rgb)}")
    return rgb


def _rgb(value, where):
    try:
        return _color(value, where, upper=None)
    except SceneError as exc:
        raise ValueError(str(exc)) from None


def _material_name(name, materials, where) -> str:
    if not isinstance(name, str):
        raise SceneError(f"{where} must be the name of a material, got {name!r}")
    if name not in materials:
        known = ", ".join(sorted(materials))
        raise SceneError(f"{where} names an unknown material {name!r}; defined: {known}")
    return name


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return v / math.sqrt(float(v @ v))


# --- files --------------------------------------------------------------------

_TOP_KEYS = {"name", "camera", "settings", "materials", "spheres", "quads"}
_CAMERA_KEYS = {"position", "direction", "look_at", "up", "fov", "near"}
_SETTINGS_KEYS = {"background", "epsilon", "rr_depth", "max_depth"}
_SPHERE_KEYS = {"center", "radius", "material", "clip"}
_CLIP_KEYS = {"point", "normal"}
_QUAD_KEYS = {"corner", "edge1", "edge2", "material"}


def load_scene(path: str | os.PathLike) -> Scene:
    r"""Read a scene from a ``.toml`` or ``.json`` file (format: module docstring, docs/rendering.md).

    Raises
    ------
    FileNotFoundError
        If *path* does not exist.
    ValueError
        If the file is not valid TOML/JSON or not a valid scene; the message
        is ``scene file '<path>': <field> ...``.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from symsphere.render import load_scene
    >>> text = 'camera = {position = [0, 0, 4], look_at = [0, 0, 0], fov = 40}\n'
    >>> text += 'materials.lamp = {type = "diffuse", albedo = 0, emission = 1}\n'
    >>> text += 'spheres = [{center = [0, 0, 0], radius = 1, material = "lamp"}]\n'
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = pathlib.Path(folder) / "ball.toml"
    ...     _ = path.write_text(text)
    ...     load_scene(path).name
    'ball'
    """
    path = Path(path)
    where = f"scene file {str(path)!r}"
    suffix = path.suffix.lower()
    if suffix not in (".toml", ".json"):
        raise ValueError(f"{where}: the suffix must be .toml or .json, got {path.suffix!r}")
    raw = path.read_bytes()
    try:
        data = tomllib.loads(raw.decode("utf-8")) if suffix == ".toml" else json.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise ValueError(f"{where}: not UTF-8 text ({exc})") from None
    except (tomllib.TOMLDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{where}: not valid {suffix[1:].upper()}: {exc}") from None
    return scene_from_dict(data, source=str(path), default_name=path.stem)


def scene_from_dict(data: Mapping, *, source: str | None = None, default_name: str = "scene") -> Scene:
    """A :class:`Scene` from the parsed structure of a scene file.

    Examples
    --------
    >>> from symsphere.render import scene_from_dict
    >>> scene = scene_from_dict({
    ...     "camera": {"position": [0, 0, 4], "direction": [0, 0, -1], "fov": 40},
    ...     "materials": {"lamp": {"type": "diffuse", "albedo": 0, "emission": 1}},
    ...     "spheres": [{"center": [0, 0, 0], "radius": 1, "material": "lamp",
    ...                  "clip": {"point": [0, 0, 0], "normal": [0, 0, 1]}}],
    ... })
    >>> scene.spheres[0].clip.normal
    (0.0, 0.0, 1.0)
    """
    where = f"scene file {source!r}" if source else "scene"
    try:
        return _from_dict(data, source, default_name)
    except SceneError as exc:
        message = str(exc)
        raise SceneError(message if message.startswith(where) else f"{where}: {message}") from None


def _from_dict(data, source, default_name) -> Scene:
    table = _table(data, "the top level", _TOP_KEYS)
    for key in ("camera", "materials"):
        if key not in table:
            raise SceneError(f"missing [{key}]")
    camera_table = _table(table["camera"], "camera", _CAMERA_KEYS)
    for key in ("position", "fov"):
        if key not in camera_table:
            raise SceneError(f"camera.{key} is missing")
    position = _vector(camera_table["position"], "camera.position")
    if ("direction" in camera_table) == ("look_at" in camera_table):
        raise SceneError("camera needs exactly one of direction and look_at")
    if "direction" in camera_table:
        direction = _vector(camera_table["direction"], "camera.direction")
    else:
        target = _vector(camera_table["look_at"], "camera.look_at")
        direction = tuple(t - p for t, p in zip(target, position))
        if not any(direction):
            raise SceneError("camera.look_at must differ from camera.position")
    camera = Camera(
        position, direction, camera_table["fov"], camera_table.get("up", (0.0, 1.0, 0.0)), camera_table.get("near", 0.0)
    )
    settings = _table(table.get("settings", {}), "settings", _SETTINGS_KEYS)
    materials_table = _table(table["materials"], "materials", None)
    materials = {name: _material_from_dict(value, f"materials.{name}") for name, value in materials_table.items()}
    spheres = []
    for i, value in enumerate(_list(table.get("spheres", []), "spheres")):
        entry = _table(value, f"spheres[{i}]", _SPHERE_KEYS, required=_SPHERE_KEYS - {"clip"})
        clip = None
        if "clip" in entry:
            clip_table = _table(entry["clip"], f"spheres[{i}].clip", _CLIP_KEYS, required=_CLIP_KEYS)
            clip = HalfSpace(clip_table["point"], clip_table["normal"])
        spheres.append(Sphere(entry["center"], entry["radius"], entry["material"], clip))
    quads = []
    for i, value in enumerate(_list(table.get("quads", []), "quads")):
        entry = _table(value, f"quads[{i}]", _QUAD_KEYS, required=_QUAD_KEYS)
        quads.append(Quad(entry["corner"], entry["edge1"], entry["edge2"], entry["material"]))
    name = table.get("name", default_name)
    return Scene(
        name=name,
        camera=camera,
        materials=materials,
        spheres=tuple(spheres),
        quads=tuple(quads),
        background=settings.get("background", _BLACK),
        epsilon=settings.get("epsilon"),
        rr_depth=settings.get("rr_depth", 5),
        max_depth=settings.get("max_depth", 1024),
        source=source,
    )


def _material_from_dict(value, where) -> Material:
    if not isinstance(value, Mapping):
        raise SceneError(f"{where} must be a table, got {value!r}")
    kind = value.get("type")
    if kind not in MATERIAL_KINDS:
        raise SceneError(f"{where}.type must be one of {', '.join(MATERIAL_KINDS)}; got {kind!r}")
    parameters = _KIND_KEYS[kind]
    allowed = {"type", "emission"} | {key for key, _, _ in parameters}
    _table(value, where, allowed)
    fields = {"emission": value.get("emission", 0.0)}
    for key, attribute, default in parameters:
        if key not in value and default is None:
            raise SceneError(f"{where}.{key} is missing (a {kind} material needs {_join(k for k, _, _ in parameters)})")
        fields[attribute] = value.get(key, default)
    return Material(kind, **fields)


def _table(value, where, allowed, required=()):
    if not isinstance(value, Mapping):
        raise SceneError(f"{where} must be a table, got {type(value).__name__}")
    if allowed is not None:
        unknown = sorted(set(value) - set(allowed))
        if unknown:
            raise SceneError(f"unknown key {unknown[0]!r} in {where}; allowed: {_join(sorted(allowed))}")
    missing = sorted(set(required) - set(value))
    if missing:
        raise SceneError(f"{where}.{missing[0]} is missing")
    return value


def _list(value, where):
    if not isinstance(value, list):
        raise SceneError(f"{where} must be a list (TOML: [[{where}]] tables), got {type(value).__name__}")
    return value


def _join(words):
    return ", ".join(words)


# --- built-in scenes -------------------------------------------------------------


def cornell() -> Scene:
    """Kevin Beason's smallpt Cornell box, exactly as published (smallpt.cpp, 2008).

    Examples
    --------
    >>> from symsphere.render import cornell
    >>> scene = cornell()
    >>> len(scene.spheres), scene.spheres[8].clip.normal
    (9, (0.0, -1.0, 0.0))

    Nine spheres (radius, centre, emission, colour, material)::

        1e5   ( 1e5+1, 40.8, 81.6)   0       (.75,.25,.25)  diffuse   left
        1e5   (-1e5+99, 40.8, 81.6)  0       (.25,.25,.75)  diffuse   right
        1e5   (50, 40.8, 1e5)        0       (.75,.75,.75)  diffuse   back
        1e5   (50, 40.8, -1e5+170)   0       0              diffuse   front
        1e5   (50, 1e5, 81.6)        0       (.75,.75,.75)  diffuse   bottom
        1e5   (50, -1e5+81.6, 81.6)  0       (.75,.75,.75)  diffuse   top
        16.5  (27, 16.5, 47)         0       .999           mirror
        16.5  (73, 16.5, 78)         0       .999           glass (ior 1.5)
        600   (50, 681.6-.27, 81.6)  12      0              diffuse   light

    The light is described as the part of that sphere below the ceiling
    plane y = 81.6 (``clip``): a cap of height 0.27 and radius ~18, the only
    part of it that can be seen from inside the room.  Every ray that starts
    inside the room hits exactly what it hits in smallpt (tested); only the
    rays that smallpt starts above the ceiling (the top ~0.5 % of the image,
    see docs/rendering.md) can tell the difference.  Next-event estimation
    samples the light by area on the cap, where it can be seen.

    Camera at (50, 52, 295.6) looking along (0, -0.042612, -1), the image
    plane at distance 1 is 0.5135 high (vertical fov 2 atan(0.5135 / 2) =
    28.82 degrees) and 0.5135 * width / height wide, rays start on the plane
    140 units along the view direction; smallpt's ray epsilon 1e-4.
    Differences from smallpt's estimator (not its scene): exact Fresnel for
    the glass instead of Schlick's approximation, throughput-based Russian
    roulette, no clamping of pixel values.
    """
    materials = {
        "left": diffuse((0.75, 0.25, 0.25)),
        "right": diffuse((0.25, 0.25, 0.75)),
        "white": diffuse((0.75, 0.75, 0.75)),
        "black": diffuse(0.0),
        "mirror": mirror(0.999),
        "glass": dielectric(1.5, 0.999),
        "light": diffuse(0.0, emission=12.0),
    }
    spheres = (
        Sphere((1e5 + 1, 40.8, 81.6), 1e5, "left"),
        Sphere((-1e5 + 99, 40.8, 81.6), 1e5, "right"),
        Sphere((50, 40.8, 1e5), 1e5, "white"),
        Sphere((50, 40.8, -1e5 + 170), 1e5, "black"),
        Sphere((50, 1e5, 81.6), 1e5, "white"),
        Sphere((50, -1e5 + 81.6, 81.6), 1e5, "white"),
        Sphere((27, 16.5, 47), 16.5, "mirror"),
        Sphere((73, 16.5, 78), 16.5, "glass"),
        Sphere((50, 681.6 - 0.27, 81.6), 600, "light", clip=HalfSpace((50, 81.6, 81.6), (0, -1, 0))),
    )
    camera = Camera((50, 52, 295.6), (0, -0.042612, -1), math.degrees(2 * math.atan(0.5135 / 2)), near=140.0)
    return Scene("cornell", camera, materials, spheres, epsilon=1e-4)


def furnace(albedo: float = 0.5, emission: float = 1.0, translucent: bool = False) -> Scene:
    """The inside of a closed unit sphere of albedo rho emitting Le: radiance is exactly Le / (1 - rho).

    With ``translucent=True`` the sphere is a Lambertian reflector *and*
    transmitter (reflectance = transmittance = rho / 2, sampled over the
    whole sphere) and the background radiance is Le / (1 - rho): the field
    is again uniform, Le / (1 - rho) everywhere.

    Examples
    --------
    >>> from symsphere.render import furnace, render
    >>> image = render(furnace(albedo=0.5, emission=1.0), width=8, height=8, spp=16, sampler="cosine", seed=1).image
    >>> bool(abs(image.mean() - 2.0) < 0.1)   # Le / (1 - rho) = 2
    True
    """
    rho = float(albedo)
    if not 0 <= rho < 1:
        raise ValueError(f"'albedo' must be in [0, 1), got {albedo!r}")
    radiance = float(emission) / (1 - rho)
    camera = Camera((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 90.0)
    if translucent:
        material = Material("translucent", (rho / 2,) * 3, (rho / 2,) * 3, emission=(float(emission),) * 3)
        background = (radiance,) * 3
    else:
        material = diffuse(rho, emission=emission)
        background = _BLACK
    name = f"furnace (albedo {rho:g}, emission {float(emission):g}{', translucent' if translucent else ''})"
    return Scene(name, camera, {"shell": material}, (Sphere((0.0, 0.0, 0.0), 1.0, "shell"),), background=background)


def translucent_scene() -> Scene:
    """A translucent sheet and a translucent ball in front of a light panel, on a diffuse floor.

    The panel behind them is the main light: what the camera sees of the
    sheet and the ball is mostly light transmitted through them (Lambertian
    transmission, sampled over the whole sphere: the paper's transparent-object
    case).  A weak panel overhead lights their fronts.

    Examples
    --------
    >>> from symsphere.render import translucent_scene
    >>> translucent_scene().materials["ball"].kind
    'translucent'
    """
    materials = {
        "floor": diffuse(0.5),
        "wall": diffuse(0.1),
        "backlight": diffuse(0.0, emission=4.0),
        "fill": diffuse(0.0, emission=0.8),
        "sheet": translucent((0.1, 0.1, 0.1), (0.2, 0.5, 0.8)),
        "ball": translucent((0.2, 0.12, 0.05), (0.75, 0.4, 0.12)),
    }
    quads = (
        Quad((-8.0, 0.0, -8.0), (0.0, 0.0, 16.0), (16.0, 0.0, 0.0), "floor"),
        Quad((-8.0, 0.0, -5.0), (16.0, 0.0, 0.0), (0.0, 8.0, 0.0), "wall"),
        Quad((-2.8, 0.3, -3.0), (5.6, 0.0, 0.0), (0.0, 2.4, 0.0), "backlight"),
        Quad((-2.4, 0.0, -1.4), (2.2, 0.0, -0.3), (0.0, 2.3, 0.0), "sheet"),
        Quad((-3.0, 4.5, -2.0), (6.0, 0.0, 0.0), (0.0, 0.0, 4.0), "fill"),
    )
    spheres = (Sphere((1.2, 0.9, -1.4), 0.9, "ball"),)
    camera = Camera((0.0, 1.4, 5.0), (0.0, -0.05, -1.0), 40.0)
    return Scene("translucent", camera, materials, spheres, quads)


SCENES = {"cornell": cornell, "furnace": furnace, "translucent": translucent_scene}
"""Built-in scenes by name: functions returning a :class:`Scene`."""


def get_scene(scene: Scene | str | os.PathLike) -> Scene:
    """A :class:`Scene`, the built-in scene of that name, or the scene in that ``.toml``/``.json`` file.

    Examples
    --------
    >>> from symsphere.render import get_scene
    >>> get_scene("cornell").name
    'cornell'
    """
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, os.PathLike) or (isinstance(scene, str) and scene not in SCENES):
        if isinstance(scene, str) and Path(scene).suffix.lower() not in (".toml", ".json"):
            raise ValueError(f"'scene' must be one of {', '.join(SCENES)} or a .toml/.json file, got {scene!r}")
        return load_scene(scene)
    if isinstance(scene, str):
        return SCENES[scene]()
    raise TypeError(f"'scene' must be a Scene, a built-in scene name or a file path, got {type(scene).__name__}")

