"""Differentiable ``symsphere_path``: its gradients against Mitsuba's ``prb`` and against finite differences.

Two parameters of a 16 x 16 Cornell box (Mitsuba's, one-sided diffuse walls, a rectangle light): the
white walls' reflectance (a BSDF parameter: the path replay's relative BSDF derivative) and the light's
radiance (an emitter parameter: emission and next-event estimation).  The quantity is the derivative of
the image mean with respect to the parameter scaled in all three channels (the sum of its RGB
gradient), by ``mi.render`` + ``dr.backward`` (reverse mode) and by ``dr.forward`` (forward mode).

Statistics (fixed seeds): each case is K independent renders (seeds); Welch's t-test of its mean against
the reference's (``prb``'s gradients; central finite differences of Mitsuba's ``path`` images with common
random numbers and no Russian roulette, so that the difference is smooth), two-sided, family-wise
significance 0.01 with a Sidak correction over all the comparisons of this file (GRADIENT_TESTS).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

CASES = [
    {"strategy": "bsdf"},
    {"strategy": "cosine", "points": "sobol"},
    {"strategy": "symmetric"},
    {"strategy": "symmetric", "points": "sobol"},
    {"strategy": "symmetric_cosine"},
]
PARAMETERS = {"reflectance": "white.reflectance.value", "radiance": "light.emitter.radiance.value"}
STEPS = {"reflectance": 0.02, "radiance": 0.5}  # added to R, G and B (reflectance ~0.7, radiance ~17)
SIZE, SPP, SEEDS = 16, 24, 12
ALPHA = 0.01
# prb comparisons (cases x parameters), finite differences (2 parameters)
GRADIENT_TESTS = len(CASES) * len(PARAMETERS) + len(PARAMETERS)
THRESHOLD = 1.0 - (1.0 - ALPHA) ** (1.0 / GRADIENT_TESTS)
DEPTH = {"max_depth": 6, "rr_depth": 5}


def _ids(case):
    return "-".join(str(v) for v in case.values())


def _scene(mi):
    scene = mi.cornell_box()
    scene["sensor"]["film"] = {"type": "hdrfilm", "width": SIZE, "height": SIZE, "rfilter": {"type": "box"}}
    scene["sensor"]["sampler"] = {"type": "independent"}
    return mi.load_dict(scene)


def _gradient(mi, scene, integrator, key, seed, spp=SPP):
    """d mean(image) / d (parameter scaled in R, G and B alike), reverse mode through mi.render."""
    import drjit as dr

    params = mi.traverse(scene)
    dr.enable_grad(params[key])
    params.update()
    image = mi.render(scene, params=params, integrator=integrator, spp=spp, seed=seed, seed_grad=seed + 1000)
    dr.backward(dr.mean(image, axis=None))
    grad = float(np.sum(np.array(dr.grad(params[key]))))
    dr.disable_grad(params[key])
    params.update()
    return grad


def _gradients(mi, scene, integrator, key, seeds=SEEDS):
    return np.array([_gradient(mi, scene, integrator, key, seed) for seed in range(seeds)])


_PRB: dict[str, np.ndarray] = {}


def _welch_p(a, b):
    return float(stats.ttest_ind(a, b, equal_var=False).pvalue)


@pytest.mark.statistical
@pytest.mark.parametrize("parameter", sorted(PARAMETERS))
@pytest.mark.parametrize("case", CASES, ids=_ids)
def test_gradient_agrees_with_prb(llvm, parameter, case):
    mi = llvm
    import symsphere.mitsuba  # noqa: F401

    scene = _scene(mi)
    key = PARAMETERS[parameter]
    if parameter not in _PRB:
        _PRB[parameter] = _gradients(mi, scene, mi.load_dict({"type": "prb", **DEPTH}), key)
    ours = _gradients(mi, scene, mi.load_dict({"type": "symsphere_path", **case, **DEPTH}), key)
    assert np.all(np.isfinite(ours)) and np.all(ours > 0)
    p = _welch_p(ours, _PRB[parameter])
    assert p > THRESHOLD, (p, ours.mean(), _PRB[parameter].mean())


@pytest.mark.statistical
@pytest.mark.parametrize("parameter", sorted(PARAMETERS))
def test_gradient_agrees_with_finite_differences(llvm, parameter):
    """Central differences of Mitsuba's path (an independent estimator) at +-h, the same seed on both sides;
    no Russian roulette (rr_depth > max_depth): the two sides trace the same paths, so the difference of
    their images is a smooth function of the parameter (exact for the radiance, where the image is linear)."""
    mi = llvm
    import symsphere.mitsuba  # noqa: F401

    scene = _scene(mi)
    key = PARAMETERS[parameter]
    depth = {"max_depth": 6, "rr_depth": 100}
    params = mi.traverse(scene)
    base = type(params[key])(params[key])
    h = STEPS[parameter]
    path = mi.load_dict({"type": "path", **depth})
    diffs = []
    for seed in range(SEEDS):
        means = []
        for sign in (1.0, -1.0):
            params[key] = base + sign * h
            params.update()
            means.append(float(np.mean(np.array(mi.render(scene, integrator=path, spp=SPP, seed=seed)))))
        diffs.append((means[0] - means[1]) / (2 * h))
    params[key] = base
    params.update()
    ours = _gradients(mi, scene, mi.load_dict({"type": "symsphere_path", **depth}), key)
    p = _welch_p(ours, np.array(diffs))
    assert p > THRESHOLD, (p, ours.mean(), np.mean(diffs))


@pytest.mark.parametrize("case", [CASES[0], CASES[2]], ids=_ids)
def test_forward_mode_equals_reverse_mode(llvm, case):
    """Forward mode (RBIntegrator.render_forward: the gradient image) and reverse mode replay the same paths
    at the same seed: the image mean of the one is the other's gradient, up to float32 summation order."""
    mi = llvm
    import drjit as dr

    import symsphere.mitsuba  # noqa: F401

    scene = _scene(mi)
    integrator = mi.load_dict({"type": "symsphere_path", **case, **DEPTH})
    key = PARAMETERS["reflectance"]
    reverse = _gradient(mi, scene, integrator, key, seed=3)
    params = mi.traverse(scene)
    dr.enable_grad(params[key])
    params.update()
    dr.set_grad(params[key], 1.0)
    image = mi.render(scene, params=params, integrator=integrator, spp=SPP, seed=3, seed_grad=1003)
    dr.forward_to(image)
    forward = float(np.mean(np.array(dr.grad(image))))
    dr.disable_grad(params[key])
    params.update()
    assert reverse > 0 and abs(forward - reverse) <= 1e-4 * reverse, (forward, reverse)
