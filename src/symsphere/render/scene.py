"""Scenes as plain data: camera, materials, spheres and parallelograms, validated; the kernels' tables.

A :class:`Scene` is validated when it is made (from Python or from a file);
:meth:`Scene.arrays` packs it into the float64/int64 arrays the numba kernels
take.  Errors name the field, e.g. ``scene file 'x.toml': spheres[2].radius
must be positive, got -1.0``.

A sphere with a ``clip`` (:class:`HalfSpace`) is the sphere intersected with the
closed half-space ``{p : normal . (p - point) >= 0}`` (an open spherical cap,
seen from both sides); next-event estimation samples such a sphere by area on
the cap.

Scene files (TOML, JSON) are read by :mod:`symsphere.render.scene_files`
(:func:`load_scene`, :func:`scene_from_dict`), the built-in scenes are in
:mod:`symsphere.render.scenes` (:data:`SCENES`, :func:`get_scene`, :func:`cornell`,
:func:`furnace`, :func:`translucent_scene`); both import this module.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import TypedDict, TypeVar

import numpy as np
import numpy.typing as npt

from .._typing import Float64Array, IntArray
from .._validation import short_repr
from ..frames import frame_rows
from . import _integrator as _k
from ._scene_checks import BLACK, SceneError, color, integer, number, sequence, vector

__all__ = [
    "MATERIAL_KINDS",
    "Camera",
    "HalfSpace",
    "Material",
    "Quad",
    "Scene",
    "SceneError",
    "Sphere",
    "dielectric",
    "diffuse",
    "mirror",
    "translucent",
]

MATERIAL_KINDS = ("diffuse", "translucent", "mirror", "dielectric")
"""The materials of the scene format: Lambertian reflection, Lambertian reflection and transmission, mirror, glass."""
_KIND_CODES = {"diffuse": _k.DIFFUSE, "translucent": _k.TRANSLUCENT, "mirror": _k.MIRROR, "dielectric": _k.DIELECTRIC}
_Member = TypeVar("_Member")


# --- the data -----------------------------------------------------------------


class _SceneArrays(TypedDict):
    """:meth:`Scene.arrays`: the scene packed for the kernels."""

    spheres: Float64Array
    sphere_material: IntArray
    quads: Float64Array
    quad_material: IntArray
    materials: Float64Array
    lights: Float64Array
    light_pmf: Float64Array
    camera: Float64Array
    background: Float64Array
    eps: float
    rr_depth: int
    max_depth: int


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
    color: tuple[float, ...] = (0.0, 0.0, 0.0)
    transmittance: tuple[float, ...] = (0.0, 0.0, 0.0)
    ior: float = 1.5
    emission: tuple[float, ...] = (0.0, 0.0, 0.0)


def diffuse(albedo: npt.ArrayLike, emission: npt.ArrayLike = 0.0) -> Material:
    """Lambertian reflection with *albedo* (a number or RGB), optionally emitting.

    Examples
    --------
    >>> from symsphere.render import diffuse
    >>> diffuse(0.5, emission=[1, 2, 3]).emission
    (1.0, 2.0, 3.0)
    """
    return Material("diffuse", _rgb(albedo, "'albedo'"), emission=_rgb(emission, "'emission'"))


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
        _rgb(reflectance, "'reflectance'"),
        _rgb(transmittance, "'transmittance'"),
        emission=_rgb(emission, "'emission'"),
    )


def mirror(reflectance: npt.ArrayLike = 1.0) -> Material:
    """A perfect mirror.

    Examples
    --------
    >>> from symsphere.render import mirror
    >>> mirror(0.9).color
    (0.9, 0.9, 0.9)
    """
    return Material("mirror", _rgb(reflectance, "'reflectance'"))


def dielectric(ior: float = 1.5, tint: npt.ArrayLike = 1.0) -> Material:
    """A smooth dielectric interface (exact Fresnel) with index of refraction *ior* inside.

    Examples
    --------
    >>> from symsphere.render import dielectric
    >>> dielectric(1.33).ior
    1.33
    """
    try:
        index = number(ior, "'ior'")
    except SceneError as exc:
        raise ValueError(str(exc)) from None
    if not index > 0:
        raise ValueError(f"'ior' must be positive, got {index!r}")
    return Material("dielectric", _rgb(tint, "'tint'"), ior=index)


@dataclass(frozen=True)
class HalfSpace:
    """The closed half-space ``{p : dot(normal, p - point) >= 0}`` (*normal* need not be unit).

    Examples
    --------
    >>> from symsphere.render import HalfSpace
    >>> HalfSpace((0, 81.6, 0), (0, -1, 0)).normal
    (0, -1, 0)
    """

    point: tuple[float, ...]
    normal: tuple[float, ...]


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

    center: tuple[float, ...]
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

    corner: tuple[float, ...]
    edge1: tuple[float, ...]
    edge2: tuple[float, ...]
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

    position: tuple[float, ...]
    direction: tuple[float, ...]
    fov: float
    up: tuple[float, ...] = (0.0, 1.0, 0.0)
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
    spheres: tuple[Sphere, ...] = ()
    quads: tuple[Quad, ...] = ()
    background: tuple[float, ...] = (0.0, 0.0, 0.0)
    epsilon: float | None = None
    rr_depth: int = 5
    max_depth: int = 1024
    source: str | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        where = f"scene file {self.source!r}" if self.source else f"scene {short_repr(self.name)}"
        try:
            _normalise(self)
        except SceneError as exc:
            raise SceneError(f"{where}: {exc}") from None

    @property
    def ray_epsilon(self) -> float:
        """The ray offset used: *epsilon*, or ``1e-6 * max(1, |camera.position|)``."""
        if self.epsilon is not None:
            return self.epsilon
        return 1e-6 * max(1.0, math.sqrt(sum(c * c for c in self.camera.position)))

    def arrays(self, width: int, height: int) -> _SceneArrays:
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
        areas: list[float] = []
        for i, s in enumerate(ordered):
            axis, offset, cap_height = _clip_table(s)
            t_row, b_row = frame_rows(*axis)  # the sampling frame of the cap (t, b, axis), once per render
            spheres[i] = [
                *s.center, s.radius, s.radius * s.radius, *axis, offset, cap_height, 1.0 / s.radius, *t_row, *b_row,
            ]  # fmt: skip
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
        objects: tuple[Sphere | Quad, ...] = (*ordered, *self.quads)
        lights, light_pmf = _light_tables([materials[index[o.material], 8:11] for o in objects], areas)
        return _SceneArrays(
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

    def camera_array(self, width: int, height: int) -> Float64Array:
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


def _clip_table(sphere: Sphere) -> tuple[tuple[float, ...], float, float]:
    """Kernel rows of a sphere's clip: unit axis a into the kept side, offset d (keep a . p >= d), cap height.

    The kept cap is {p on the sphere : a . (p - c) >= d - a . c}; its height
    along a is ``r - max(d - a . c, -r)`` (2 r for an unclipped sphere, whose
    offset is -inf, so that the intersection test keeps every point, and whose
    axis, used only to sample it by area, is +z).
    """
    if sphere.clip is None:
        return (0.0, 0.0, 1.0), -math.inf, 2.0 * sphere.radius
    axis = _unit(sphere.clip.normal)
    offset = float(axis @ np.array(sphere.clip.point, dtype=np.float64))
    lowest = offset - float(axis @ np.array(sphere.center, dtype=np.float64))
    return tuple(float(c) for c in axis), offset, sphere.radius - max(lowest, -sphere.radius)


def _light_tables(emissions: list[Float64Array], areas: list[float]) -> tuple[Float64Array, Float64Array]:
    """Emitters chosen by power: (2, L) rows object index, cumulative probability; and the pmf per object.

    Power of an emitter = mean emitted radiance over RGB x area (x pi, x 2
    sides: common factors).  Objects are numbered spheres first, then quads.
    """
    power = np.array([float(np.mean(e)) * a for e, a in zip(emissions, areas, strict=False)], dtype=np.float64)
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
        raise SceneError(f"name must be a non-empty string, got {short_repr(scene.name)}")
    if not isinstance(scene.camera, Camera):
        raise SceneError(f"camera must be a Camera, got {type(scene.camera).__name__}")
    put(scene, "camera", _check_camera(scene.camera))
    if not isinstance(scene.materials, Mapping) or not scene.materials:
        raise SceneError("materials must be a non-empty mapping of names to materials")
    materials: dict[str, Material] = {}
    for name, material in scene.materials.items():
        if not isinstance(name, str) or not name:
            raise SceneError(f"material names must be non-empty strings, got {short_repr(name)}")
        materials[name] = _check_material(material, f"materials.{name}")
    put(scene, "materials", materials)
    spheres = []
    for where, sphere in _members(scene.spheres, "spheres", Sphere):
        radius = number(sphere.radius, f"{where}.radius")
        if not radius > 0:
            raise SceneError(f"{where}.radius must be positive, got {radius!r}")
        material_name = _material_name(sphere.material, materials, f"{where}.material")
        center = vector(sphere.center, f"{where}.center")
        clip = _check_clip(sphere.clip, center, radius, f"{where}.clip")
        spheres.append(Sphere(center, radius, material_name, clip))
    put(scene, "spheres", tuple(spheres))
    quads = []
    for where, quad in _members(scene.quads, "quads", Quad):
        corner = vector(quad.corner, f"{where}.corner")
        edge1 = vector(quad.edge1, f"{where}.edge1")
        edge2 = vector(quad.edge2, f"{where}.edge2")
        normal = np.cross(edge1, edge2)
        if not float(normal @ normal) > 0 or not np.all(np.isfinite(normal)):
            raise SceneError(f"{where}: edge1 and edge2 must be non-zero and not parallel")
        material_name = _material_name(quad.material, materials, f"{where}.material")
        quads.append(Quad(corner, edge1, edge2, material_name))
    put(scene, "quads", tuple(quads))
    if not spheres and not quads:
        raise SceneError("needs at least one sphere or quad")
    put(scene, "background", color(scene.background, "settings.background", upper=None))
    if scene.epsilon is not None:
        epsilon = number(scene.epsilon, "settings.epsilon")
        if not epsilon > 0:
            raise SceneError(f"settings.epsilon must be positive, got {epsilon!r}")
        put(scene, "epsilon", epsilon)
    put(scene, "rr_depth", integer(scene.rr_depth, "settings.rr_depth", 1))
    put(scene, "max_depth", integer(scene.max_depth, "settings.max_depth", 1))


def _members(values: object, name: str, kind: type[_Member]) -> Iterator[tuple[str, _Member]]:
    """(where, member) for each member of the sequence field *name*, each checked to be a *kind*."""
    for i, value in enumerate(sequence(values, name)):
        where = f"{name}[{i}]"
        if not isinstance(value, kind):
            raise SceneError(f"{where} must be a {kind.__name__}, got {type(value).__name__}")
        yield where, value


def _check_camera(cam: Camera) -> Camera:
    position = vector(cam.position, "camera.position")
    direction = vector(cam.direction, "camera.direction")
    if not float(np.dot(direction, direction)) > 0:
        raise SceneError("camera.direction must be non-zero")
    up = vector(cam.up, "camera.up")
    cross = np.cross(_unit(direction), up)
    if not float(cross @ cross) > 1e-24:
        raise SceneError("camera.up must be non-zero and not parallel to camera.direction")
    fov = number(cam.fov, "camera.fov")
    if not 0 < fov < 180:
        raise SceneError(f"camera.fov must be in (0, 180) degrees, got {fov!r}")
    near = number(cam.near, "camera.near")
    if not near >= 0:
        raise SceneError(f"camera.near must be >= 0, got {near!r}")
    return Camera(position, direction, fov, up, near)


def _check_clip(clip: object, center: tuple[float, ...], radius: float, where: str) -> HalfSpace | None:
    if clip is None:
        return None
    if not isinstance(clip, HalfSpace):
        raise SceneError(f"{where} must be a HalfSpace, got {type(clip).__name__}")
    point = vector(clip.point, f"{where}.point")
    normal = vector(clip.normal, f"{where}.normal")
    if not float(np.dot(normal, normal)) > 0:
        raise SceneError(f"{where}.normal must be non-zero")
    axis = _unit(normal)
    lowest = float(axis @ (np.array(point) - np.array(center)))  # the cap keeps a . (p - c) >= lowest
    if not lowest < radius * (1 - 1e-12):
        raise SceneError(
            f"{where} keeps nothing of the sphere (the plane is {lowest - radius:g} beyond it): "
            "move its point or turn its normal"
        )
    return HalfSpace(point, normal)


def _check_material(material: object, where: str) -> Material:
    if not isinstance(material, Material):
        raise SceneError(f"{where} must be a Material, got {type(material).__name__}")
    if not isinstance(material.kind, str) or material.kind not in MATERIAL_KINDS:
        raise SceneError(f"{where}.type must be one of {', '.join(MATERIAL_KINDS)}; got {short_repr(material.kind)}")
    color_name = {"diffuse": "albedo", "dielectric": "tint"}.get(material.kind, "reflectance")
    rgb = color(material.color, f"{where}.{color_name}", upper=1.0)
    transmittance = color(material.transmittance, f"{where}.transmittance", upper=1.0)
    if material.kind == "translucent" and any(r + t > 1.0 for r, t in zip(rgb, transmittance, strict=False)):
        raise SceneError(f"{where}: reflectance + transmittance must be <= 1 in every channel (energy conservation)")
    if material.kind != "translucent":
        transmittance = BLACK
    ior = number(material.ior, f"{where}.ior")
    if not ior > 0:
        raise SceneError(f"{where}.ior must be positive, got {ior!r}")
    emission = color(material.emission, f"{where}.emission", upper=None)
    return Material(material.kind, rgb, transmittance, ior, emission)


def _rgb(value: npt.ArrayLike, where: str) -> tuple[float, ...]:
    try:
        return color(value, where, upper=None)
    except SceneError as exc:
        raise ValueError(str(exc)) from None


def _material_name(name: object, materials: Mapping[str, Material], where: str) -> str:
    if not isinstance(name, str):
        raise SceneError(f"{where} must be the name of a material, got {short_repr(name)}")
    if name not in materials:
        known = ", ".join(sorted(materials))
        raise SceneError(f"{where} names an unknown material {short_repr(name)}; defined: {known}")
    return name


def _unit(v: npt.ArrayLike) -> Float64Array:
    a = np.asarray(v, dtype=np.float64)
    unit: Float64Array = a / math.sqrt(float(a @ a))
    return unit
