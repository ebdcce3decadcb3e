"""The built-in scenes: smallpt's Cornell box, the white furnace and a translucent scene, by name.

:data:`SCENES` maps the names to the functions that make them; :func:`get_scene`
takes a :class:`~symsphere.render.Scene`, a built-in name or a scene file
(:func:`~symsphere.render.load_scene`), as :func:`~symsphere.render.render` does.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

from .._validation import check_bool, check_real
from ._scene_checks import BLACK, MAX_MAGNITUDE
from .scene import Camera, HalfSpace, Material, Quad, Scene, Sphere, dielectric, diffuse, mirror, translucent
from .scene_files import load_scene

__all__ = ["SCENES", "cornell", "furnace", "get_scene", "translucent_scene"]


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
    see docs/reference/renderer.md) can tell the difference.  Next-event estimation
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
    >>> image = render(furnace(albedo=0.5, emission=1.0), width=8, height=8, spp=16, strategy="cosine", seed=1).image
    >>> bool(abs(image.mean() - 2.0) < 0.1)   # Le / (1 - rho) = 2
    True
    """
    rho = check_real(albedo, "albedo")
    if not 0 <= rho < 1:
        raise ValueError(f"'albedo' must be in [0, 1), got {albedo!r}")
    emission = check_real(emission, "emission")
    if not 0 <= emission <= MAX_MAGNITUDE:
        raise ValueError(f"'emission' must be in [0, {MAX_MAGNITUDE:g}], got {emission!r}")
    translucent = check_bool(translucent, "translucent")
    radiance = emission / (1 - rho)
    camera = Camera((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 90.0)
    if translucent:
        material = Material("translucent", (rho / 2,) * 3, (rho / 2,) * 3, emission=(float(emission),) * 3)
        background = (radiance,) * 3
    else:
        material = diffuse(rho, emission=emission)
        background = BLACK
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


def get_scene(scene: Scene | str | os.PathLike[str]) -> Scene:
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
