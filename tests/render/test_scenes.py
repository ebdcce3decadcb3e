"""symsphere.render.scenes: the built-in scenes; smallpt's Cornell box pinned to smallpt.cpp as published."""

import dataclasses

import numpy as np

from symsphere._testing import render_probes as P
from symsphere.render import (
    HalfSpace,
    cornell,
    render,
)

SMALLPT = [  # radius, centre, emission, colour, material: smallpt.cpp as published
    (1e5, (1e5 + 1, 40.8, 81.6), 0, (0.75, 0.25, 0.25), "diffuse"),
    (1e5, (-1e5 + 99, 40.8, 81.6), 0, (0.25, 0.25, 0.75), "diffuse"),
    (1e5, (50, 40.8, 1e5), 0, (0.75, 0.75, 0.75), "diffuse"),
    (1e5, (50, 40.8, -1e5 + 170), 0, (0, 0, 0), "diffuse"),
    (1e5, (50, 1e5, 81.6), 0, (0.75, 0.75, 0.75), "diffuse"),
    (1e5, (50, -1e5 + 81.6, 81.6), 0, (0.75, 0.75, 0.75), "diffuse"),
    (16.5, (27, 16.5, 47), 0, (0.999, 0.999, 0.999), "mirror"),
    (16.5, (73, 16.5, 78), 0, (0.999, 0.999, 0.999), "dielectric"),
    (600, (50, 681.6 - 0.27, 81.6), 12, (0, 0, 0), "diffuse"),
]


def test_cornell_is_smallpt_as_published():
    scene = cornell()
    assert len(scene.spheres) == 9 and not scene.quads
    assert [s.clip for s in scene.spheres[:8]] == [None] * 8
    # the light: smallpt's sphere, clipped to its part below the ceiling plane y = 81.6 (see below)
    assert scene.spheres[8].clip == HalfSpace((50.0, 81.6, 81.6), (0.0, -1.0, 0.0))
    for sphere, (radius, center, emission, color, kind) in zip(scene.spheres, SMALLPT, strict=False):
        material = scene.materials[sphere.material]
        assert sphere.radius == radius
        assert sphere.center == tuple(float(c) for c in center)
        assert material.emission == (emission,) * 3
        assert material.color == tuple(float(c) for c in color)
        assert material.kind == kind
    assert scene.materials["glass"].ior == 1.5
    assert scene.camera.position == (50, 52, 295.6) and scene.camera.near == 140
    assert scene.ray_epsilon == 1e-4
    # smallpt: cx = (w * .5135 / h, 0, 0), cy = (cx x d).norm() * .5135, d = (0, -0.042612, -1).norm()
    w, h = 256, 192
    cam = scene.camera_array(w, h)
    d = np.array([0, -0.042612, -1]) / np.linalg.norm([0, -0.042612, -1])
    np.testing.assert_allclose(cam[3:6], d, rtol=0, atol=1e-16)
    np.testing.assert_allclose(cam[6:9], [w * 0.5135 / h, 0, 0], rtol=1e-15, atol=0)
    cy = np.cross([1.0, 0, 0], d)
    np.testing.assert_allclose(cam[9:12], cy / np.linalg.norm(cy) * 0.5135, rtol=1e-14, atol=1e-16)


def _unclipped_cornell():
    scene = cornell()
    spheres = (*scene.spheres[:8], dataclasses.replace(scene.spheres[8], clip=None))
    return dataclasses.replace(scene, spheres=spheres)


def _inside_room(rng, count):
    """Uniform points inside smallpt's room (inside all six 1e5-radius walls), outside the light sphere."""
    points = np.column_stack(
        [rng.uniform(1, 99, 3 * count), rng.uniform(0, 81.6, 3 * count), rng.uniform(0, 170, 3 * count)]
    )
    keep = np.ones(len(points), dtype=bool)
    for radius, center, *_ in SMALLPT[:6]:
        keep &= np.sum((points - np.array(center)) ** 2, axis=1) < radius**2  # the walls are slightly curved
    light = np.array([50, 681.6 - 0.27, 81.6])
    keep &= np.sum((points - light) ** 2, axis=1) > 600.0**2  # the light's cap dips 0.27 into the room
    assert keep.sum() >= count
    return points[keep][:count]


def test_every_ray_from_inside_the_room_hits_what_it_hits_in_smallpt():
    """The clipped light changes nothing for rays that start in the room: same object, same distance, bit for bit.

    500 000 rays: random origins in the room, random directions, and 100 000
    aimed at random points of the light's visible cap and its rim.
    """
    rng = np.random.default_rng(2026)
    origins = _inside_room(rng, 500_000)
    directions = rng.normal(size=origins.shape)
    cap = np.column_stack([rng.uniform(30, 70, 100_000), np.full(100_000, 81.45), rng.uniform(60, 100, 100_000)])
    directions[:100_000] = cap - origins[:100_000]
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    hits = []
    for scene in (_unclipped_cornell(), cornell()):
        a = scene.arrays(4, 4)
        hits.append(P.first_hits(origins, directions, a["spheres"], a["quads"], a["eps"]))
    np.testing.assert_array_equal(hits[0][1], hits[1][1])
    np.testing.assert_array_equal(hits[0][0], hits[1][0])
    assert np.sum(hits[1][1] == 8) > 30_000  # the light is among the hits


def test_bsdf_image_of_old_and_new_cornell_differs_only_where_rays_start_above_the_ceiling():
    """Same seed, BSDF integrator: identical pixels below the top row (smallpt starts some top-row rays above the ceiling)."""
    old = render(_unclipped_cornell(), width=32, height=24, spp=24, seed=3, integrator="bsdf").image
    new = render(cornell(), width=32, height=24, spp=24, seed=3, integrator="bsdf").image
    np.testing.assert_array_equal(old[1:], new[1:])
    # the top row: rays from camera + 140 d reach y > 81.6 only for d_y > 29.6 / 140 (the top 0.54 % of the image)
    camera = cornell().camera_array(32, 24)
    assert camera[4] + 0.5 * camera[10] > (81.6 - 52) / 140 > camera[4] + (0.5 - 1 / 24) * camera[10]
