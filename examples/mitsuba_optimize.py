"""Inverse rendering with ``symsphere_path``: recover a wall's reflectance from a target image.

    pip install -e ".[mitsuba]"
    python examples/mitsuba_optimize.py

Mitsuba's Cornell box: the target image is rendered with the red wall's true reflectance; the
optimisation starts from a grey wall and minimises the mean squared difference to the target with
Adam, every gradient by ``mi.render`` + ``dr.backward`` through ``symsphere_path`` (path replay, here
with the ``symmetric_cosine`` strategy), a new seed at every step.  ``optimize()`` returns the
reflectance error (the largest over R, G, B) at the start and the end: the measure of convergence, since
the loss soon reaches the noise floor of the two Monte Carlo images.  tests/mitsuba/test_integrator.py runs
it small.
"""

from __future__ import annotations

from typing import Any

KEY = "red.reflectance.value"


def optimize(size: int = 48, spp: int = 24, iterations: int = 60, seed: int = 0, strategy: str = "symmetric_cosine",
             learning_rate: float = 0.05, verbose: bool = False) -> dict[str, Any]:  # fmt: skip
    import drjit as dr
    import mitsuba as mi

    if mi.variant() is None or not mi.variant().startswith(("llvm_ad", "cuda_ad")):
        mi.set_variant("llvm_ad_rgb")
    import symsphere.mitsuba  # noqa: F401  (registers symsphere_path)

    spec = mi.cornell_box()
    spec["sensor"]["film"]["width"] = spec["sensor"]["film"]["height"] = size
    scene = mi.load_dict(spec)
    integrator = mi.load_dict({"type": "symsphere_path", "strategy": strategy, "max_depth": 6})
    params = mi.traverse(scene)
    true = mi.Color3f(params[KEY])
    target = mi.render(scene, integrator=integrator, spp=8 * spp, seed=10**6 + seed)

    params[KEY] = mi.Color3f(0.5, 0.5, 0.5)  # the starting guess: a grey wall
    params.update()
    optimizer = mi.ad.Adam(lr=learning_rate)
    optimizer[KEY] = params[KEY]
    params.update(optimizer)

    def error() -> float:
        return float(dr.max(dr.abs(params[KEY] - true))[0])

    losses, errors = [], [error()]
    for step in range(iterations):
        image = mi.render(scene, params, integrator=integrator, spp=spp, seed=seed * iterations + step)
        loss = dr.mean(dr.square(image - target), axis=None)
        dr.backward(loss)
        optimizer.step()
        optimizer[KEY] = dr.clip(optimizer[KEY], 0.0, 1.0)
        params.update(optimizer)
        losses.append(float(loss.array[0]))
        errors.append(error())
        if verbose and (step % 10 == 0 or step == iterations - 1):
            print(f"step {step:3d}: loss {losses[-1]:.3e}, reflectance {params[KEY]}, error {errors[-1]:.3f}")
    return {
        "true": [float(v[0]) for v in true],
        "recovered": [float(v[0]) for v in params[KEY]],
        "error_start": errors[0],
        "error_final": errors[-1],
        "losses": losses,
    }


if __name__ == "__main__":
    result = optimize(verbose=True)
    print("symsphere_path recovered", result["recovered"], "true", result["true"])
    print("error", round(result["error_start"], 3), "->", round(result["error_final"], 3),
          result["error_final"] < 0.25 * result["error_start"])  # fmt: skip
