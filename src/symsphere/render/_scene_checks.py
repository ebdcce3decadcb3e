"""Checks of the values in a scene, shared by :mod:`symsphere.render.scene` and
:mod:`symsphere.render.scene_files`: numbers, integers, 3-vectors, colours and lists.

Each check returns the value converted to plain Python floats / ints / tuples,
or raises :class:`SceneError` with a message that names the field (*where*).
:class:`SceneError` is defined here, below both of its users, and is public as
``symsphere.render.SceneError`` (and in :mod:`symsphere.render.scene`).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from typing import Any

import numpy as np

from .._validation import real_number, short_repr

__all__ = ["BLACK", "MAX_DEPTH", "MAX_MAGNITUDE", "SceneError", "color", "integer", "number", "sequence", "vector"]

BLACK: tuple[float, float, float] = (0.0, 0.0, 0.0)
"""The colour (0, 0, 0): no emission, no background."""

MAX_MAGNITUDE = 1e30
"""Largest absolute value of a number in a scene (coordinates, radii, emission, ...): products of a few of
them (areas, light powers, squared distances) stay finite in float64, so an image is never inf."""

MAX_DEPTH = 1_000_000
"""Largest path depth (``settings.max_depth``, ``settings.rr_depth``): the kernels count in int64, and a
deeper path carries no measurable energy."""


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


def sequence(value: Any, where: str) -> list[Any]:
    """*value* (any iterable but a string or a mapping) as a list.

    Examples
    --------
    >>> from symsphere.render._scene_checks import sequence
    >>> sequence((1, 2), "spheres")
    [1, 2]
    """
    if isinstance(value, (str, bytes, Mapping)) or not hasattr(value, "__iter__"):
        raise SceneError(f"{where} must be a list, got {type(value).__name__}")
    return list(value)


def number(value: Any, where: str) -> float:
    """*value*, a finite real number (not a bool), as a float.

    Examples
    --------
    >>> from symsphere.render._scene_checks import number
    >>> number(2, "camera.fov")
    2.0
    >>> number(float("nan"), "camera.fov")
    Traceback (most recent call last):
    ...
    symsphere.render._scene_checks.SceneError: camera.fov must be finite, got nan
    """
    result = real_number(value)  # the library's number rule (symsphere._validation)
    if result is None:
        raise SceneError(f"{where} must be a number, got {short_repr(value)}")
    if math.isinf(result) and isinstance(value, numbers.Integral):  # an int beyond float64
        raise SceneError(f"{where} must be at most {MAX_MAGNITUDE:g} in magnitude, got {short_repr(value)}")
    if not math.isfinite(result):
        raise SceneError(f"{where} must be finite, got {result!r}")
    if abs(result) > MAX_MAGNITUDE:
        raise SceneError(f"{where} must be at most {MAX_MAGNITUDE:g} in magnitude, got {result!r}")
    return result


def integer(value: Any, where: str, minimum: int, maximum: int = MAX_DEPTH) -> int:
    """*value*, an integer (not a bool) in [*minimum*, *maximum*], as an int.

    Examples
    --------
    >>> from symsphere.render._scene_checks import integer
    >>> integer(5, "settings.rr_depth", 1)
    5
    """
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise SceneError(f"{where} must be an integer, got {short_repr(value)}")
    if value < minimum:
        raise SceneError(f"{where} must be >= {minimum}, got {short_repr(value)}")
    if value > maximum:
        raise SceneError(f"{where} must be at most {maximum}, got {short_repr(value)}")
    return int(value)


def _length(value: Any) -> int | None:
    """len(value), or None for what has no length (a number, a 0-d array)."""
    try:
        return len(value)
    except TypeError:
        return None


def vector(value: Any, where: str) -> tuple[float, ...]:
    """*value*, 3 finite numbers, as a tuple of floats.

    Examples
    --------
    >>> from symsphere.render._scene_checks import vector
    >>> vector([0, 1, 5], "camera.position")
    (0.0, 1.0, 5.0)
    """
    if isinstance(value, (str, bytes, Mapping)) or _length(value) != 3:
        raise SceneError(f"{where} must be 3 numbers [x, y, z], got {short_repr(value)}")
    return tuple(number(c, f"{where}[{i}]") for i, c in enumerate(value))


def color(value: Any, where: str, upper: float | None) -> tuple[float, ...]:
    """*value*, a number (grey) or 3 numbers [r, g, b] in [0, upper] (``upper=None``: >= 0), as 3 floats.

    Examples
    --------
    >>> from symsphere.render._scene_checks import color
    >>> color(0.5, "materials.white.albedo", upper=1.0)
    (0.5, 0.5, 0.5)
    """
    if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool):
        value = (value, value, value)
    elif isinstance(value, (str, bytes, Mapping)) or _length(value) != 3:
        raise SceneError(f"{where} must be a number or 3 numbers [r, g, b], got {short_repr(value)}")
    rgb = tuple(number(c, where) for c in value)
    for c in rgb:
        if c < 0 or (upper is not None and c > upper):
            allowed = f"in [0, {upper:g}]" if upper is not None else ">= 0"
            raise SceneError(f"{where} must be {allowed}, got {list(rgb)}")
    return rgb
