"""``symsphere_path`` with Owen-scrambled Sobol' cosine directions (``strategy='cosine'``, ``points='sobol'``)
and the light table (``emitter_sampling`` ``'solid_angle'`` or ``'cosine'``): unbiased.

The block test of tests/mitsuba/test_lights.py: the mean image of SEEDS renders against Mitsuba's own ``path``
(the independent reference), 4 x 4 blocks of the mean of R, G, B, Welch's t-test, two-sided, significance 0.01
for the family with a Sidak correction over every block of every case.  The scenes: a rectangle light and a
24-triangle disk light near the floor of the textured scene (a tiny table; an exact table), max_depth 3 (the
Sobol' directions at two vertices, the table at the second).
"""

from __future__ import annotations

import numpy as np
import pytest
from mitsuba_scenes import scene_dict
from scipy import stats

SIZE, SPP, SEEDS, BLOCK = 16, 32, 12, 4
ALPHA = 0.01
CASES = [(scene, sampling) for scene in ("near_rect", "near_disk") for sampling in ("solid_angle", "cosine")]
TESTS = len(CASES) * (SIZE // BLOCK) ** 2


def _scene(mi, name, tmp_path):
    scene = scene_dict(mi, "textured", SIZE)
    for key in ("light", "sky", "ball", "glass"):
        del scene[key]
    radiance = {"type": "area", "radiance": {"type": "rgb", "value": [6, 6, 5]}}
    if name == "near_rect":  # 0.5 above the floor, facing it
        T = mi.ScalarTransform4f
        to_world = T().translate([0, 0.5, 0]).rotate([1, 0, 0], 90).scale(0.6)
        scene["light"] = {"type": "rectangle", "to_world": to_world, "emitter": radiance}
    else:  # a disk of 24 triangles (radius 0.8) 0.4 above the floor, facing down
        segments, radius, height = 24, 0.8, 0.4
        phi = 2 * np.pi * np.arange(segments) / segments
        lines = [f"v 0 {height} 0\n"] + [f"v {radius * np.cos(p)} {height} {radius * np.sin(p)}\n" for p in phi]
        lines += [f"f 1 {k + 2} {(k + 1) % segments + 2}\n" for k in range(segments)]  # normal -y
        path = tmp_path / "disk24.obj"
        path.write_text("".join(lines), encoding="utf-8")
        scene["light"] = {"type": "obj", "filename": str(path), "emitter": radiance}
    return mi.load_dict(scene)


def _blocks(mi, scene, integrator):
    images = np.stack(
        [np.array(mi.render(scene, integrator=integrator, spp=SPP, seed=seed))[..., :3] for seed in range(SEEDS)]
    )
    lum = images.mean(axis=-1).reshape(SEEDS, SIZE // BLOCK, BLOCK, SIZE // BLOCK, BLOCK)
    return lum.mean(axis=(2, 4)).reshape(SEEDS, -1)


@pytest.mark.statistical
@pytest.mark.parametrize(("scene_name", "sampling"), CASES)
def test_sobol_cosine_directions_with_the_light_table_agree_with_mitsubas_path(llvm, tmp_path, scene_name, sampling):
    mi = llvm
    import symsphere.mitsuba  # noqa: F401

    scene = _scene(mi, scene_name, tmp_path)
    depth = {"max_depth": 3, "rr_depth": 2}
    ref = _blocks(mi, scene, mi.load_dict({"type": "path", **depth}))
    spec = {"type": "symsphere_path", "strategy": "cosine", "points": "sobol", "emitter_sampling": sampling}
    ours = _blocks(mi, scene, mi.load_dict({**spec, **depth}))
    assert np.all(np.isfinite(ours)) and ours.mean() > 0.0
    pvalue = stats.ttest_ind(ours, ref, axis=0, equal_var=False).pvalue
    assert np.min(pvalue) > 1.0 - (1.0 - ALPHA) ** (1.0 / TESTS), (np.min(pvalue), ours.mean(0), ref.mean(0))
