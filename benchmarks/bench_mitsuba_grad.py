"""Gradient variance of ``symsphere_path`` against Mitsuba's ``prb``, at equal spp and at equal time.

    .venv/bin/python benchmarks/bench_mitsuba_grad.py --json results/mitsuba_grad.json
    .venv/bin/python benchmarks/bench_mitsuba_grad.py --scene textured --json results/mitsuba_grad_textured.json

Scenes (--scene): ``cornell``, Mitsuba's Cornell box (``mi.cornell_box()``: one-sided diffuse walls, a
rectangle light), with two parameters: the white walls' reflectance (a BSDF parameter) and the light's
radiance (an emitter parameter); ``textured`` (tests/mitsuba's: a two-sided diffuse checkerboard floor
and wall, a rough-plastic sphere, a glass sphere, a rectangle light, a constant sky), with a checker
colour (a texture) and the sky's radiance.  Each parameter is scaled in R, G and B alike.  At --width x
--height (64 x 64), --spp (24) samples per pixel, ``max_depth`` 6, ``rr_depth`` 5, variant llvm_ad_rgb.
Two estimators per integrator and parameter, over --seeds seeds (independent renders: seed s,
seed_grad s + 10^6):

reverse
    The scalar gradient of the image mean (``mi.render`` + ``dr.backward``; the sum of the parameter's RGB
    gradient): what an optimiser of a loss summed over the image sees.  Its variance over seeds.
forward
    The gradient image (``render_forward`` with a unit tangent in R, G and B): the mean over pixels and
    channels of each pixel's variance over seeds (the noise of the derivative per pixel).

Times: seconds per reverse-mode gradient (render and backward) and per gradient image, the median of
--seeds rounds, every integrator in turn in each round (interleaved), after a warm-up (the JIT compile).
Efficiency relative to prb at equal time: (variance x seconds of prb) / (variance x seconds), above 1
where the case needs less time than prb for the same gradient variance.  The standard error of a
variance ratio from --seeds samples is about sqrt(2 / (seeds - 1)) each way (chi-square), ~25 % at 32.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import cpu_name, cpu_snapshot, others_cpu

# Mitsuba's own light sampling (area): this bench measures the strategies' gradients against prb's
AREA = {"emitter_sampling": "area"}
CASES = [
    ("prb", {"type": "prb"}),
    ("bsdf", {"type": "symsphere_path", **AREA, "strategy": "bsdf"}),
    ("cosine · sobol", {"type": "symsphere_path", **AREA, "strategy": "cosine", "points": "sobol"}),
    ("symmetric · random", {"type": "symsphere_path", **AREA, "strategy": "symmetric"}),
    ("symmetric · sobol", {"type": "symsphere_path", **AREA, "strategy": "symmetric", "points": "sobol"}),
    ("symmetric_cosine · random", {"type": "symsphere_path", **AREA, "strategy": "symmetric_cosine"}),
    ("symmetric_cosine · sobol", {"type": "symsphere_path", **AREA, "strategy": "symmetric_cosine", "points": "sobol"}),
]
PARAMETERS = {
    "cornell": {"reflectance": "white.reflectance.value", "radiance": "light.emitter.radiance.value"},
    "textured": {"checker": "floor.bsdf.brdf_0.reflectance.color0.value", "sky": "sky.radiance.value"},
}
DEPTH = {"max_depth": 6, "rr_depth": 5}


def _scene(mi, name, width, height):
    film = {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"}}
    if name == "cornell":
        scene = mi.cornell_box()
        scene["sensor"]["film"] = film
        scene["sensor"]["sampler"] = {"type": "independent"}
        return mi.load_dict(scene)
    T = mi.ScalarTransform4f
    white = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.7, 0.7, 0.7]}}}
    checker = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {
        "type": "checkerboard", "color0": {"type": "rgb", "value": [0.8, 0.2, 0.1]},
        "color1": {"type": "rgb", "value": [0.1, 0.3, 0.8]}, "to_uv": T().scale([4, 4, 1])}}}  # fmt: skip
    plastic = {"type": "roughplastic", "alpha": 0.2, "diffuse_reflectance": {"type": "rgb", "value": [0.2, 0.6, 0.3]}}
    return mi.load_dict({
        "type": "scene",
        "sensor": {"type": "perspective", "fov": 50, "film": film, "sampler": {"type": "independent"},
                   "to_world": T().look_at(origin=[0, 1.2, 4.5], target=[0, 0.6, 0], up=[0, 1, 0])},
        "floor": {"type": "rectangle", "to_world": T().rotate([1, 0, 0], -90).scale(3), "bsdf": checker},
        "wall": {"type": "rectangle", "to_world": T().translate([0, 1.5, -1.5]).scale(3), "bsdf": white},
        "ball": {"type": "sphere", "center": [-0.7, 0.5, 0.2], "radius": 0.5, "bsdf": plastic},
        "glass": {"type": "sphere", "center": [0.8, 0.4, 0.6], "radius": 0.4, "bsdf": {"type": "dielectric"}},
        "light": {"type": "rectangle", "to_world": T().translate([0.5, 2.8, 0.5]).rotate([1, 0, 0], 90).scale(0.6),
                  "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [12, 11, 10]}}},
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [0.3, 0.35, 0.4]}},
    })  # fmt: skip


def _reverse(mi, dr, scene, integrator, key, seed, spp):
    params = mi.traverse(scene)
    dr.enable_grad(params[key])
    params.update()
    start = time.perf_counter()
    image = mi.render(scene, params=params, integrator=integrator, spp=spp, seed=seed, seed_grad=seed + 10**6)
    dr.backward(dr.mean(image, axis=None))
    grad = float(np.sum(np.array(dr.grad(params[key]))))
    seconds = time.perf_counter() - start
    dr.disable_grad(params[key])
    params.update()
    return grad, seconds


def _forward(mi, dr, scene, integrator, key, seed, spp):
    params = mi.traverse(scene)
    dr.enable_grad(params[key])
    params.update()
    dr.set_grad(params[key], 1.0)
    start = time.perf_counter()
    image = np.array(integrator.render_forward(scene, params, seed=seed + 10**6, spp=spp))
    seconds = time.perf_counter() - start
    dr.disable_grad(params[key])
    params.update()
    return image, seconds


def run(args):
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    import symsphere.mitsuba  # noqa: F401  (registers symsphere_path)

    scene = _scene(mi, args.scene, args.width, args.height)
    integrators = {name: mi.load_dict({**spec, **DEPTH}) for name, spec in CASES}
    rows = []
    snapshot = cpu_snapshot()
    wall = time.perf_counter()
    for parameter, key in PARAMETERS[args.scene].items():
        for integrator in integrators.values():  # warm-up: the JIT compile of each kernel
            _reverse(mi, dr, scene, integrator, key, 0, args.spp)
            _forward(mi, dr, scene, integrator, key, 0, args.spp)
        grads = {name: [] for name in integrators}
        images = {name: [] for name in integrators}
        t_rev = {name: [] for name in integrators}
        t_fwd = {name: [] for name in integrators}
        for seed in range(1, args.seeds + 1):
            for name, integrator in integrators.items():  # interleaved: every case in each round
                g, t = _reverse(mi, dr, scene, integrator, key, seed, args.spp)
                grads[name].append(g)
                t_rev[name].append(t)
                image, t = _forward(mi, dr, scene, integrator, key, seed, args.spp)
                images[name].append(image)
                t_fwd[name].append(t)
        for name in integrators:
            g = np.array(grads[name])
            stack = np.stack(images[name])
            rows.append({
                "parameter": parameter, "case": name,
                "reverse_mean": float(g.mean()), "reverse_var": float(g.var(ddof=1)),
                "reverse_seconds": statistics.median(t_rev[name]),
                "forward_image_mean": float(stack.mean()),
                "forward_pixel_var": float(stack.var(axis=0, ddof=1).mean()),
                "forward_seconds": statistics.median(t_fwd[name]),
            })  # fmt: skip
        prb = next(r for r in rows if r["parameter"] == parameter and r["case"] == "prb")
        for row in rows:
            if row["parameter"] == parameter:
                for mode, var, sec in (("reverse", "reverse_var", "reverse_seconds"),
                                       ("forward", "forward_pixel_var", "forward_seconds")):  # fmt: skip
                    row[f"{mode}_var_ratio"] = row[var] / prb[var]
                    row[f"{mode}_time_ratio"] = row[sec] / prb[sec]
                    row[f"{mode}_efficiency_vs_prb"] = (prb[var] * prb[sec]) / (row[var] * row[sec])
    return {
        "command": " ".join(["benchmarks/bench_mitsuba_grad.py", *sys.argv[1:]]),
        "machine": cpu_name(),
        "others_cpu": others_cpu(snapshot, cpu_snapshot(), time.perf_counter() - wall),
        "scene": args.scene, "width": args.width, "height": args.height, "spp": args.spp, "seeds": args.seeds,
        "variant": "llvm_ad_rgb", "mitsuba": mi.__version__, "rows": rows,
    }  # fmt: skip


def report(result):
    print(
        f"{result['machine']}; {result.get('scene', 'cornell')} {result['width']}x{result['height']}, {result['spp']} spp, {result['seeds']} seeds"
    )
    print(
        f"{'parameter':12} {'case':26} {'rev var/prb':>11} {'time/prb':>8} {'eff':>6}  {'fwd var/prb':>11} {'time/prb':>8} {'eff':>6}"
    )
    for r in result["rows"]:
        print(
            f"{r['parameter']:12} {r['case']:26} {r['reverse_var_ratio']:11.2f} {r['reverse_time_ratio']:8.2f} "
            f"{r['reverse_efficiency_vs_prb']:6.2f}  {r['forward_var_ratio']:11.2f} {r['forward_time_ratio']:8.2f} "
            f"{r['forward_efficiency_vs_prb']:6.2f}"
        )


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scene", choices=sorted(PARAMETERS), default="cornell")
    parser.add_argument("--width", type=int, default=64)
    parser.add_argument("--height", type=int, default=64)
    parser.add_argument("--spp", type=int, default=24)
    parser.add_argument("--seeds", type=int, default=32)
    parser.add_argument("--json", help="write the result here (relative to benchmarks/)")
    args = parser.parse_args(argv)
    result = run(args)
    report(result)
    if args.json:
        path = Path(__file__).resolve().parent / args.json
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
