"""Scene files: a :class:`~symsphere.render.Scene` from TOML or JSON (:func:`load_scene`), or from
their parsed structure (:func:`scene_from_dict`).

Errors name the file and the field, e.g. ``scene file 'x.toml': spheres[2].radius
must be positive, got -1.0`` (:class:`~symsphere.render.SceneError`, a ``ValueError``).

File format (TOML or JSON, the same structure; see ``docs/reference/renderer.md``)::

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
import os
import tomllib
from collections.abc import Collection, Iterable, Mapping
from typing import Any

from .._validation import check_path, read_regular_file, short_repr
from ._scene_checks import BLACK, SceneError, vector
from .scene import MATERIAL_KINDS, Camera, HalfSpace, Material, Quad, Scene, Sphere

__all__ = ["MAX_SCENE_BYTES", "load_scene", "scene_from_dict"]

MAX_SCENE_BYTES = 16 * 2**20
"""Largest scene file :func:`load_scene` reads (16 MiB); a scene is a short text."""

# The parameters each kind takes, in a file: (file key, attribute, default)
_KIND_KEYS = {
    "diffuse": (("albedo", "color", None),),
    "translucent": (("reflectance", "color", None), ("transmittance", "transmittance", None)),
    "mirror": (("reflectance", "color", 1.0),),
    "dielectric": (("ior", "ior", 1.5), ("tint", "color", 1.0)),
}
_TOP_KEYS = {"name", "camera", "settings", "materials", "spheres", "quads"}
_CAMERA_KEYS = {"position", "direction", "look_at", "up", "fov", "near"}
_SETTINGS_KEYS = {"background", "epsilon", "rr_depth", "max_depth"}
_SPHERE_KEYS = {"center", "radius", "material", "clip"}
_CLIP_KEYS = {"point", "normal"}
_QUAD_KEYS = {"corner", "edge1", "edge2", "material"}


def load_scene(path: str | os.PathLike[str]) -> Scene:
    r"""Read a scene from a ``.toml`` or ``.json`` file (format: this module's docstring, docs/reference/renderer.md).

    Raises
    ------
    FileNotFoundError
        If *path* does not exist.
    ValueError
        (:class:`~symsphere.render.SceneError`) If *path* is not a regular file (a FIFO, a
        device such as ``/dev/zero``, a directory: refused by what it is before it is opened).
    ValueError
        (:class:`~symsphere.render.SceneError`) If the file is not valid TOML/JSON
        (or is larger than :data:`MAX_SCENE_BYTES`, or nested too deeply) or not a
        valid scene; the message is ``scene file '<path>': <field> ...``.

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
    path = check_path(path, "path")
    where = f"scene file {str(path)!r}"
    suffix = path.suffix.lower()
    if suffix not in (".toml", ".json"):
        raise ValueError(f"{where}: the suffix must be .toml or .json, got {path.suffix!r}")
    try:  # a FIFO, a device: refused by what it is, before it is opened (a FIFO would block)
        raw = read_regular_file(path, where, MAX_SCENE_BYTES)
    except ValueError as exc:
        raise SceneError(str(exc)) from None
    if len(raw) > MAX_SCENE_BYTES:
        raise SceneError(f"{where}: larger than {MAX_SCENE_BYTES // 2**20} MiB; a scene file is a short text")
    try:
        data = tomllib.loads(raw.decode("utf-8")) if suffix == ".toml" else json.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise SceneError(f"{where}: not UTF-8 text ({exc})") from None
    except RecursionError:  # arrays or tables nested thousands deep: the parsers recurse
        raise SceneError(f"{where}: nested too deeply to be a scene") from None
    except ValueError as exc:  # TOMLDecodeError, JSONDecodeError, and integers beyond the digit limit
        raise SceneError(f"{where}: not valid {suffix[1:].upper()}: {exc}") from None
    return scene_from_dict(data, source=str(path), default_name=path.stem)


def scene_from_dict(data: Mapping[str, Any], *, source: str | None = None, default_name: str = "scene") -> Scene:
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
    if source is not None and not isinstance(source, str):
        raise TypeError(f"'source' must be a str or None, got {short_repr(source)}")
    if not isinstance(default_name, str) or not default_name:
        raise TypeError(f"'default_name' must be a non-empty str, got {short_repr(default_name)}")
    where = f"scene file {source!r}" if source else "scene"
    try:
        try:
            return _from_dict(data, source, default_name)
        except RecursionError:  # a value nested thousands deep (its repr recurses)
            raise SceneError("a value is nested too deeply") from None
    except SceneError as exc:
        message = str(exc)
        raise SceneError(message if message.startswith(where) else f"{where}: {message}") from None


def _from_dict(data: Any, source: str | None, default_name: str) -> Scene:
    table = _table(data, "the top level", _TOP_KEYS)
    for key in ("camera", "materials"):
        if key not in table:
            raise SceneError(f"missing [{key}]")
    camera_table = _table(table["camera"], "camera", _CAMERA_KEYS)
    for key in ("position", "fov"):
        if key not in camera_table:
            raise SceneError(f"camera.{key} is missing")
    position = vector(camera_table["position"], "camera.position")
    if ("direction" in camera_table) == ("look_at" in camera_table):
        raise SceneError("camera needs exactly one of direction and look_at")
    if "direction" in camera_table:
        direction = vector(camera_table["direction"], "camera.direction")
    else:
        target = vector(camera_table["look_at"], "camera.look_at")
        direction = tuple(t - p for t, p in zip(target, position, strict=False))
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
        background=settings.get("background", BLACK),
        epsilon=settings.get("epsilon"),
        rr_depth=settings.get("rr_depth", 5),
        max_depth=settings.get("max_depth", 1024),
        source=source,
    )


def _material_from_dict(value: Any, where: str) -> Material:
    if not isinstance(value, Mapping):
        raise SceneError(f"{where} must be a table, got {short_repr(value)}")
    kind = value.get("type")
    if kind not in MATERIAL_KINDS:
        raise SceneError(f"{where}.type must be one of {', '.join(MATERIAL_KINDS)}; got {short_repr(kind)}")
    parameters = _KIND_KEYS[kind]
    allowed = {"type", "emission"} | {key for key, _, _ in parameters}
    _table(value, where, allowed)
    fields = {"emission": value.get("emission", 0.0)}
    for key, attribute, default in parameters:
        if key not in value and default is None:
            raise SceneError(f"{where}.{key} is missing (a {kind} material needs {_join(k for k, _, _ in parameters)})")
        fields[attribute] = value.get(key, default)
    return Material(kind, **fields)


def _table(
    value: Any, where: str, allowed: Collection[str] | None, required: Collection[str] = ()
) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise SceneError(f"{where} must be a table, got {type(value).__name__}")
    if allowed is not None:
        unknown = sorted(set(value) - set(allowed))
        if unknown:
            raise SceneError(f"unknown key {short_repr(unknown[0])} in {where}; allowed: {_join(sorted(allowed))}")
    missing = sorted(set(required) - set(value))
    if missing:
        raise SceneError(f"{where}.{missing[0]} is missing")
    return value


def _list(value: Any, where: str) -> list[Any]:
    if not isinstance(value, list):
        raise SceneError(f"{where} must be a list (TOML: [[{where}]] tables), got {type(value).__name__}")
    return value


def _join(words: Iterable[str]) -> str:
    return ", ".join(words)
