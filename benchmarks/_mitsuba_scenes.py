"""The scenes of ``bench_render.py equal-time``: the second scene (``gap``) and their Mitsuba 3 versions.

``gap_room()``
    A room lit through a gap: a closed box split by a partition with a 1.0-wide
    floor-to-ceiling gap at one side; the only light is a panel on the ceiling
    of the back compartment, which the camera (in the front compartment) does
    not see.  What the camera sees is lit almost entirely indirectly: direct
    light reaches the front compartment only through the gap, on a strip of
    the floor and of the right wall.  Next-event estimation finds the light
    from very few visible points, so the indirect light (the diffuse
    direction sampling) dominates the noise.

``mitsuba_dict(scene, width, height, spp)``
    A ``mitsuba.load_dict`` dictionary of a symsphere :class:`~symsphere.render.Scene`
    with Mitsuba's ``path`` integrator (``max_depth`` and ``rr_depth`` from the
    scene: both renderers count vertices the same way and apply Russian
    roulette after the throughput update at vertex ``rr_depth - 1`` with
    survival ``min(max(throughput), 0.95)``; Mitsuba multiplies by eta^2,
    which matters only inside glass), variant ``llvm_ad_rgb`` (float32):

    - quads -> ``rectangle`` shapes (the same parallelogram);
    - spheres of radius >= 1e4 (smallpt's walls) -> rectangles on their
      tangent plane facing the camera (x = 1, x = 99, z = 0, z = 170, y = 0,
      y = 81.6 for ``cornell``), spanning the box the six planes bound (1 unit
      of overlap at the edges);
    - a sphere with a ``clip`` half-space (``symsphere.render.HalfSpace``, where
      the renderer has it) -> the cap it keeps, as a triangle mesh (24 rings x
      96 segments);
    - otherwise, a sphere whose centre is beyond one of those planes
      (``cornell``'s light: radius 600, centre (50, 681.6 - .27, 81.6)) -> the
      cap of it on the room side of the plane, as a triangle mesh (24 rings x
      96 segments; the cap's radius is 18.0, its height 0.27), and the zone
      of the sphere up to 20 units beyond the plane as a second emitting mesh
      with ``sampling_weight = 0`` (never chosen for emitter sampling, hit
      only by BSDF samples): the rays of smallpt's top image row start on the
      near plane up to 0.35 above the ceiling and see that part of the light
      sphere (without it, Mitsuba's top row is black and its image mean 14 %
      lower); from inside the room it is hidden by the ceiling;
    - other spheres -> ``sphere`` shapes;
    - diffuse -> ``twosided`` ``diffuse`` (ours reflects on either side);
      mirror -> ``conductor`` with ``material = 'none'`` (a perfect mirror)
      times the reflectance; dielectric -> ``dielectric`` (exact Fresnel, as
      ours) with the tint as both specular reflectance and transmittance;
      emission -> an ``area`` emitter (one-sided in Mitsuba, two-sided in
      ours: every emitter here faces the room, its back is never seen);
    - the camera: ``perspective``, the same position, direction, up and
      vertical fov; ``near_clip`` = the camera's ``near`` (both start rays on
      the plane at that distance along the view direction: smallpt's 140);
      ``hdrfilm`` with a ``box`` filter (a sample counts only for its own
      pixel, as ours); ``independent`` sampler.

Translucent (Lambertian transmission) materials have no Mitsuba 3 plugin and
are refused.
"""

from __future__ import annotations

import math
import os
import tempfile

import numpy as np

from symsphere.render import Camera, Quad, Scene, Sphere, dielectric, diffuse

__all__ = ["gap_room", "mitsuba_dict", "HUGE_RADIUS"]

HUGE_RADIUS = 1e4  # spheres at least this large are walls: a plane for Mitsuba's float32
BAND = 20.0  # how far beyond its wall a clipped sphere is kept (smallpt's top image row starts outside)


def gap_room() -> Scene:
    """A room lit through a gap in a partition (see the module docstring); 6 x 3 x 8, camera looking at -z.

    The light (4.5 x 1.8, radiance 20) is on the ceiling of the back compartment (z < 2.5); the gap
    is x in [5, 6] of the partition z = 2.5; a diffuse ball and a glass ball stand in the front.
    """
    materials = {
        "white": diffuse(0.75),
        "red": diffuse((0.7, 0.2, 0.15)),
        "green": diffuse((0.2, 0.55, 0.25)),
        "ball": diffuse((0.8, 0.6, 0.3)),
        "glass": dielectric(1.5, 0.999),
        "light": diffuse(0.0, emission=20.0),
    }
    W, H, D, P, G = 6.0, 3.0, 8.0, 2.5, 1.0  # width (x), height (y), depth (z), partition at z = P, gap width
    quads = (
        Quad((0, 0, 0), (0, 0, D), (W, 0, 0), "white"),  # floor, normal +y
        Quad((0, H, 0), (W, 0, 0), (0, 0, D), "white"),  # ceiling, normal -y
        Quad((0, 0, 0), (0, H, 0), (0, 0, D), "red"),  # left wall x = 0, normal +x
        Quad((W, 0, 0), (0, 0, D), (0, H, 0), "green"),  # right wall x = W, normal -x
        Quad((0, 0, 0), (W, 0, 0), (0, H, 0), "white"),  # back wall z = 0, normal +z
        Quad((0, 0, D), (0, H, 0), (W, 0, 0), "white"),  # front wall z = D (behind the camera), normal -z
        Quad((0, 0, P), (W - G, 0, 0), (0, H, 0), "white"),  # the partition, gap at x in [W - G, W]
        Quad((1.0, H - 1e-3, 0.4), (4.5, 0, 0), (0, 0, 1.8), "light"),  # ceiling panel behind it, normal -y
    )
    spheres = (
        Sphere((1.9, 0.7, 4.6), 0.7, "ball"),
        Sphere((4.2, 0.55, 5.6), 0.55, "glass"),
    )
    camera = Camera((3.0, 1.6, 7.9), (0.0, -0.12, -1.0), 62.0)
    return Scene("gap", camera, materials, spheres, quads)


# --- Mitsuba 3 ------------------------------------------------------------------------------------


def _rgb(value):
    return {"type": "rgb", "value": [float(c) for c in value]}


def _bsdf(material):
    kind = material.kind
    if kind == "diffuse":
        return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": _rgb(material.color)}}
    if kind == "mirror":
        return {"type": "conductor", "material": "none", "specular_reflectance": _rgb(material.color)}
    if kind == "dielectric":
        return {
            "type": "dielectric",
            "int_ior": float(material.ior),
            "ext_ior": 1.0,
            "specular_reflectance": _rgb(material.color),
            "specular_transmittance": _rgb(material.color),
        }
    raise ValueError(f"Mitsuba 3 has no plugin for symsphere's {kind!r} material")


def _shape_extras(material):
    extras = {"bsdf": _bsdf(material)}
    if any(c > 0 for c in material.emission):
        extras["emitter"] = {"type": "area", "radiance": _rgb(material.emission)}
    return extras


def _matrix(columns):
    """A 4x4 affine matrix from its first three columns and translation."""
    m = np.eye(4)
    for j, column in enumerate(columns):
        m[:3, j] = column
    return m


def _rectangle(corner, edge1, edge2):
    """to_world of Mitsuba's rectangle ([-1, 1]^2 at z = 0, normal +z) onto corner + s e1 + t e2."""
    corner, edge1, edge2 = (np.asarray(v, dtype=np.float64) for v in (corner, edge1, edge2))
    normal = np.cross(edge1, edge2)
    return _matrix([edge1 / 2, edge2 / 2, normal / np.linalg.norm(normal), corner + (edge1 + edge2) / 2])


def _wall_planes(scene):
    """(axis, coordinate, inward sign, sphere) of every huge sphere: its tangent plane nearest the camera.

    The room is inside every wall sphere (smallpt's walls bound it from the inside): the inward
    normal of the plane points towards the sphere's centre.
    """
    eye = np.array(scene.camera.position)
    planes = []
    for sphere in scene.spheres:
        if sphere.radius < HUGE_RADIUS:
            continue
        offset = eye - np.array(sphere.center)
        axis = int(np.argmax(np.abs(offset)))
        sign = math.copysign(1.0, offset[axis])
        planes.append((axis, sphere.center[axis] + sign * sphere.radius, -sign, sphere))
    return planes


def _zone_mesh(center, radius, pole, theta0, theta1, rings, segments=96):
    """Vertices and faces of the zone theta0 <= theta <= theta1 of a sphere, theta measured from the
    unit direction *pole* (a cap when theta0 = 0).  Faces are wound so that their normals point out
    of the sphere."""
    center, pole = np.asarray(center, dtype=np.float64), np.asarray(pole, dtype=np.float64)
    helper = np.eye(3)[int(np.argmin(np.abs(pole)))]
    t = np.cross(pole, helper)
    t /= np.linalg.norm(t)
    b = np.cross(pole, t)
    vertices = []
    first = 1 if theta0 == 0 else 0
    if first:
        vertices.append(center + radius * pole)
    for i in range(first, rings + 1):
        theta = theta0 + (theta1 - theta0) * i / rings
        for j in range(segments):
            phi = 2 * math.pi * j / segments
            vertices.append(
                center + radius * (math.cos(theta) * pole + math.sin(theta) * (math.cos(phi) * t + math.sin(phi) * b))
            )
    vertices = np.array(vertices)

    def ring(i, j):
        return first + (i - first) * segments + (j % segments)

    faces = []
    if first:
        faces += [(0, ring(1, j), ring(1, j + 1)) for j in range(segments)]
    for i in range(first, rings):
        for j in range(segments):
            a, b_, c, d = ring(i, j), ring(i, j + 1), ring(i + 1, j), ring(i + 1, j + 1)
            faces += [(a, c, d), (a, d, b_)]
    faces = np.array(faces)
    v0, v1, v2 = (vertices[faces[:, k]] for k in range(3))
    outward = np.einsum("ij,ij->i", np.cross(v1 - v0, v2 - v0), (v0 + v1 + v2) / 3 - center) > 0
    faces[~outward] = faces[~outward][:, ::-1]
    return vertices, faces


def _write_obj(path, vertices, faces):
    with open(path, "w", encoding="ascii") as handle:
        handle.writelines(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in vertices)
        handle.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces)


def mitsuba_dict(scene: Scene, width: int, height: int, spp: int, *, workdir=None) -> dict:
    """The ``mitsuba.load_dict`` dictionary of *scene* (see the module docstring); call after ``mi.set_variant``.

    Mesh files (the light caps) are written to *workdir* (default: a new
    temporary directory); they must exist until ``load_dict`` has run.
    """
    import mitsuba as mi

    T = mi.ScalarTransform4f
    cam = scene.camera
    eye = np.array(cam.position, dtype=np.float64)
    target = eye + np.array(cam.direction, dtype=np.float64) / np.linalg.norm(cam.direction)
    result = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": int(scene.max_depth), "rr_depth": int(scene.rr_depth)},
        "sensor": {
            "type": "perspective",
            "fov": float(cam.fov),
            "fov_axis": "y",
            "near_clip": float(cam.near) if cam.near > 0 else 1e-3,
            "far_clip": 1e6,
            "to_world": T().look_at(origin=eye.tolist(), target=target.tolist(), up=list(cam.up)),
            "film": {
                "type": "hdrfilm",
                "width": int(width),
                "height": int(height),
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
                "component_format": "float32",
            },
            "sampler": {"type": "independent", "sample_count": int(spp)},
        },
    }
    materials = scene.materials
    planes = _wall_planes(scene)
    if planes:
        box = np.array([[-np.inf, np.inf]] * 3)
        for axis, coordinate, sign, _ in planes:
            box[axis, 0 if sign > 0 else 1] = coordinate
        if not np.all(np.isfinite(box)):
            raise ValueError("huge spheres are converted only when six of them bound a box (smallpt's walls)")
        for k, (axis, coordinate, sign, sphere) in enumerate(planes):
            u, v = [a for a in range(3) if a != axis]
            corner = np.zeros(3)
            corner[axis] = coordinate
            corner[u], corner[v] = box[u, 0] - 1, box[v, 0] - 1
            e1, e2 = np.zeros(3), np.zeros(3)
            e1[u] = box[u, 1] - box[u, 0] + 2
            e2[v] = box[v, 1] - box[v, 0] + 2
            if np.cross(e1, e2)[axis] * sign < 0:  # normal into the room
                e1, e2 = e2, e1
            result[f"wall{k}"] = {"type": "rectangle", "to_world": T(_rectangle(corner, e1, e2).tolist()),
                                  **_shape_extras(materials[sphere.material])}  # fmt: skip
    workdir = workdir or tempfile.mkdtemp(prefix="symsphere-mitsuba-")
    for k, sphere in enumerate(scene.spheres):
        if sphere.radius >= HUGE_RADIUS:
            continue
        material = materials[sphere.material]
        beyond = [
            (axis, coordinate)
            for axis, coordinate, sign, _ in planes
            if (sphere.center[axis] - coordinate) * sign < 0  # centre beyond the plane, outside the room
        ]
        parts = {}  # name -> (pole, theta0, theta1, rings, emitter sampling weight)
        clip = getattr(sphere, "clip", None)  # symsphere.render.HalfSpace, on a branch with clipped spheres
        if clip is not None:  # keep n . (p - q) >= 0: the cap about n of the sphere
            n = np.asarray(clip.normal, dtype=np.float64) / np.linalg.norm(clip.normal)
            lowest = float(n @ (np.asarray(clip.point, dtype=np.float64) - np.asarray(sphere.center)))
            parts["cap"] = (n, 0.0, math.acos(min(max(lowest / sphere.radius, -1.0), 1.0)), 24, 1.0)
        elif beyond:
            if len(beyond) > 1:
                raise ValueError(f"sphere {k} lies beyond more than one wall")
            axis, coordinate = beyond[0]
            n = np.zeros(3)
            n[axis] = math.copysign(1.0, coordinate - sphere.center[axis])  # from the centre to the room
            depth = abs(coordinate - sphere.center[axis])
            theta_cap = math.acos(min(depth / sphere.radius, 1.0))
            theta_band = math.acos(min(max((depth - BAND) / sphere.radius, -1.0), 1.0))
            parts["cap"] = (n, 0.0, theta_cap, 24, 1.0)
            parts["band"] = (n, theta_cap, theta_band, 32, 0.0)
        for part, (pole, theta0, theta1, rings, weight) in parts.items():
            vertices, faces = _zone_mesh(sphere.center, sphere.radius, pole, theta0, theta1, rings)
            path = os.path.join(workdir, f"sphere{k}_{part}.obj")
            _write_obj(path, vertices, faces)
            shape = {"type": "obj", "filename": path, "face_normals": True, **_shape_extras(material)}
            if "emitter" in shape:
                shape["emitter"] = dict(shape["emitter"], sampling_weight=weight)
            result[f"sphere{k}_{part}"] = shape
        if not parts:
            result[f"sphere{k}"] = {
                "type": "sphere",
                "center": [float(c) for c in sphere.center],
                "radius": float(sphere.radius),
                **_shape_extras(material),
            }
    for k, quad in enumerate(scene.quads):
        result[f"quad{k}"] = {"type": "rectangle", "to_world": T(_rectangle(quad.corner, quad.edge1, quad.edge2).tolist()),
                              **_shape_extras(materials[quad.material])}  # fmt: skip
    return result
