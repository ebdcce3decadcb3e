"""Light sampling by solid angle in Mitsuba 3: symsphere_path's emitter_sampling against Mitsuba's path.

    .venv/bin/python benchmarks/bench_mitsuba_lights.py --json benchmarks/results/mitsuba_lights.json

Scenes: benchmarks/_mitsuba_light_scenes.py (--scenes), at --width x --height, variant llvm_ad_rgb, for
each --depths (max_depth 2: direct light only; 8: full paths; rr_depth 5).

--samplers adds, per Mitsuba sampler named (e.g. ldsampler, multijitter), Mitsuba's ``path`` and
``symsphere_path`` (``bsdf`` with ``solid_angle`` and with ``cosine``) with the scene's sampler set to it
(labels `` + NAME``), so that the best of each side can be compared; efficiency ratios stay relative to
``path`` with ``independent``.

Per scene and depth: a reference (Mitsuba's ``path``, ``independent``, --ref-spp in two independent
halves), then --rounds interleaved rounds (alternating order) in which every case renders --spp samples per
pixel with a new seed.  relMSE = mean over pixels and channels of (x - ref)^2 / (ref^2 + 0.01) (as
bench_mitsuba.py), the mean over the rounds; seconds = the median over the rounds.  The reference's own
noise adds its variance to every case's squared error (x and ref are independent and unbiased), which
would compress the ratios towards 1: the relMSE reported is bias-corrected, the raw one minus the
reference's own relMSE, estimated from the halves a, b as the mean of ((a - b) / 2)^2 / (ref^2 + 0.01)
(the variance of (a - b) / 2 is that of ref = (a + b) / 2); the raw value is recorded too.  A sampler that
takes another sample count than --spp (multijitter: 35 for 32, stratified 36, ldsampler 64) renders that
count: its relMSE and seconds are scaled to --spp (relMSE x taken / spp, seconds x spp / taken: Monte
Carlo's 1/spp, exact for independent samples, a slight flattery of a QMC sampler that converges faster),
so that "at equal spp" holds; the efficiency, their product, does not depend on the scaling.  Efficiency = 1 / (relMSE x seconds),
which is the equal-time comparison (relMSE is inversely proportional to spp); reported as a ratio to
Mitsuba's path in the same rounds, with the ratio of relMSE at equal spp and of paths/s.  The machine may
be shared: the others' CPU share during the rounds is recorded, and each render's CPU time (this
process's, Dr.Jit's threads included) is recorded beside its wall-clock seconds, with the ratios it gives
(steadier than seconds on a loaded machine; on an idle one the two agree up to the threads' idling).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import cpu_snapshot, others_cpu, run_header
from _mitsuba_light_scenes import LIGHT_SCENES, light_scene

CASES = [  # (label, integrator dict)
    ("Mitsuba path", {"type": "path"}),
    ("symsphere_path bsdf · area", {"type": "symsphere_path", "strategy": "bsdf", "emitter_sampling": "area"}),
    ("symsphere_path bsdf · solid_angle", {"type": "symsphere_path", "strategy": "bsdf", "emitter_sampling": "solid_angle"}),
    ("symsphere_path symmetric_cosine sobol · solid_angle",
     {"type": "symsphere_path", "strategy": "symmetric_cosine", "points": "sobol", "emitter_sampling": "solid_angle"}),
]  # fmt: skip
PROJECTED = [  # --projected: by projected solid angle at Lambertian vertices (a root finder; slow with full paths)
    ("symsphere_path bsdf · projected", {"type": "symsphere_path", "strategy": "bsdf", "emitter_sampling": "projected"}),
]  # fmt: skip
COSINE = [  # after the others (the images' order): near the cosine at Lambertian vertices, at solid_angle's cost
    ("symsphere_path bsdf · cosine", {"type": "symsphere_path", "strategy": "bsdf", "emitter_sampling": "cosine"}),
    ("symsphere_path symmetric_cosine sobol · cosine",
     {"type": "symsphere_path", "strategy": "symmetric_cosine", "points": "sobol", "emitter_sampling": "cosine"}),
]  # fmt: skip
QMC = [  # after the others (the images' order): Owen-scrambled Sobol' cosine directions at Lambertian vertices
    ("symsphere_path cosine sobol · solid_angle",
     {"type": "symsphere_path", "strategy": "cosine", "points": "sobol", "emitter_sampling": "solid_angle"}),
    ("symsphere_path cosine sobol · cosine",
     {"type": "symsphere_path", "strategy": "cosine", "points": "sobol", "emitter_sampling": "cosine"}),
]  # fmt: skip
WITH_SAMPLER = CASES[0], CASES[2], COSINE[0]  # --samplers: these with the scene's sampler set to a better one


def rel_mse(image, reference):
    """The relMSE of *image* against *reference*: the mean of (x - ref)^2 / (ref^2 + 0.01)."""
    return float(np.mean((image - reference) ** 2 / (reference**2 + 0.01)))


def reference(a, b):
    """(ref, its own relMSE) from two independent half-references *a*, *b*: ref = (a + b) / 2, and the
    estimate of the relMSE its own noise adds to every image's, rel_mse((a - b) / 2 + ref, ref)."""
    ref = 0.5 * (a + b)
    return ref, rel_mse(ref + 0.5 * (a - b), ref)


def _taken_spp(scene, spp):
    """The sample count the scene's sampler renders when asked for *spp* (Mitsuba rounds some counts)."""
    sampler = scene.sensors()[0].sampler().clone()
    sampler.set_sample_count(spp)
    return int(sampler.sample_count())


def _render(mi, scene, integrator, spp, seed):
    start, cpu = time.perf_counter(), time.process_time()
    image = np.array(mi.render(scene, integrator=integrator, spp=spp, seed=seed), dtype=np.float64)[..., :3]
    return image, time.perf_counter() - start, time.process_time() - cpu


def run(args, mi, workdir):
    rows, images = [], {}
    for depth in args.depths:
        for name in args.scenes:
            scene = light_scene(mi, name, args.width, args.height, workdir)
            options = {"max_depth": depth, "rr_depth": 5}
            ref_integrator = mi.load_dict({"type": "path", **options})
            a = _render(mi, scene, ref_integrator, args.ref_spp // 2, 1000)[0]
            b = _render(mi, scene, ref_integrator, args.ref_spp // 2, 2000)[0]
            ref, own = reference(a, b)
            specs = [
                (label, spec, None) for label, spec in CASES + (PROJECTED if args.projected else []) + COSINE + QMC
            ]
            scenes = {None: scene}
            for sampler in args.samplers:
                scenes[sampler] = light_scene(mi, name, args.width, args.height, workdir, sampler)
                specs += [(f"{label} + {sampler}", spec, sampler) for label, spec in WITH_SAMPLER]
            cases = [(label, mi.load_dict({**spec, **options}), sampler) for label, spec, sampler in specs]
            taken = {sampler: _taken_spp(scenes[sampler], args.spp) for sampler in scenes}
            for _, integrator, sampler in cases:  # compile
                _render(mi, scenes[sampler], integrator, args.spp, 0)
            errors = {label: [] for label, *_ in cases}
            raw = {label: [] for label, *_ in cases}
            seconds = {label: [] for label, *_ in cases}
            cpu = {label: [] for label, *_ in cases}
            before, t0 = cpu_snapshot(), time.perf_counter()
            for r in range(args.rounds):
                for label, integrator, sampler in cases if r % 2 == 0 else cases[::-1]:
                    image, s, c = _render(mi, scenes[sampler], integrator, args.spp, r + 1)
                    scale = taken[sampler] / args.spp  # to --spp samples per pixel (see the module docstring)
                    raw[label].append(rel_mse(image, ref) * scale)
                    errors[label].append((rel_mse(image, ref) - own) * scale)
                    seconds[label].append(s / scale)
                    cpu[label].append(c / scale)
                    if r == args.rounds - 1:
                        images.setdefault((name, depth), [ref]).append(image)
            load = others_cpu(before, cpu_snapshot(), time.perf_counter() - t0)
            base = CASES[0][0]
            eff = {label: 1.0 / (np.mean(errors[label]) * statistics.median(seconds[label])) for label, *_ in cases}
            eff_cpu = {label: 1.0 / (np.mean(errors[label]) * statistics.median(cpu[label])) for label, *_ in cases}
            share = "?" if load is None else f"{load['share_of_all_cpus']:.0%}"
            print(
                f"{name}, max_depth {depth} (reference's own relMSE {own:.2g}; others' CPU share {share})", flush=True
            )
            for label, _, sampler in cases:
                row = {
                    "scene": name, "max_depth": depth, "case": label, "spp": args.spp, "sampler": sampler or "independent",
                    "spp_rendered": taken[sampler], "rel_mse_raw": float(np.mean(raw[label])),
                    "rel_mse_ratio_raw": float(np.mean(raw[base]) / np.mean(raw[label])),
                    "rel_mse": float(np.mean(errors[label])), "seconds": statistics.median(seconds[label]),
                    "efficiency": eff[label], "efficiency_ratio": eff[label] / eff[base],
                    "rel_mse_ratio": float(np.mean(errors[base]) / np.mean(errors[label])),
                    "speed_ratio": statistics.median(seconds[base]) / statistics.median(seconds[label]),
                    "cpu_seconds": statistics.median(cpu[label]),
                    "cpu_speed_ratio": statistics.median(cpu[base]) / statistics.median(cpu[label]),
                    "cpu_efficiency_ratio": eff_cpu[label] / eff_cpu[base],
                    "reference_own_rel_mse": own,
                    "others_cpu_share": None if load is None else load["share_of_all_cpus"],
                }  # fmt: skip
                rows.append(row)
                print(f"  {label:<52} relMSE {row['rel_mse']:.4g} (x{row['rel_mse_ratio']:.2f} lower; raw "
                      f"x{row['rel_mse_ratio_raw']:.2f})  "
                      f"{row['seconds']:.3f} s (speed x{row['speed_ratio']:.2f})  efficiency x{row['efficiency_ratio']:.2f}  "
                      f"CPU: speed x{row['cpu_speed_ratio']:.2f}, efficiency x{row['cpu_efficiency_ratio']:.2f}",
                      flush=True)  # fmt: skip
    return rows, images


def report(record):
    lines = [
        "| scene | max_depth | case | relMSE | × lower | s | paths/s × | efficiency × path | CPU: paths/s × | CPU: efficiency × |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in record["rows"]:
        cpu = f"{r['cpu_speed_ratio']:.2f} | {r['cpu_efficiency_ratio']:.2f}" if "cpu_speed_ratio" in r else "– | –"
        lines.append(f"| {r['scene']} | {r['max_depth']} | {r['case']} | {r['rel_mse']:.3g} | {r['rel_mse_ratio']:.2f} | "
                     f"{r['seconds']:.3f} | {r['speed_ratio']:.2f} | {r['efficiency_ratio']:.2f} | {cpu} |")  # fmt: skip
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenes", nargs="+", default=list(LIGHT_SCENES), choices=LIGHT_SCENES)
    parser.add_argument("--depths", type=int, nargs="+", default=[2, 8])
    parser.add_argument("--width", type=int, default=128)
    parser.add_argument("--height", type=int, default=128)
    parser.add_argument("--spp", type=int, default=16, help="spp per render, a multiple of 8 (default %(default)s)")
    parser.add_argument("--ref-spp", type=int, default=4096, help="reference spp (default %(default)s)")
    parser.add_argument("--rounds", type=int, default=5, help="interleaved rounds (default %(default)s)")
    parser.add_argument("--projected", action="store_true", help="add emitter_sampling='projected' (slow)")
    parser.add_argument("--samplers", nargs="*", default=[], metavar="NAME",
                        help="add path and symsphere_path (bsdf: solid_angle, cosine) with the scene's sampler set "
                        "to NAME (a Mitsuba sampler: ldsampler, multijitter, ...)")  # fmt: skip
    parser.add_argument("--json", metavar="FILE", help="write the results as JSON")
    parser.add_argument("--images", metavar="DIR", help="write DIR/<scene>_<depth>.png: the reference and every "
                        "case's last render side by side, in the order of the table")  # fmt: skip
    parser.add_argument("--report", metavar="FILE", help="print the markdown table of a --json FILE and exit")
    args = parser.parse_args(argv)
    if args.report:
        print(report(json.loads(Path(args.report).read_text(encoding="utf-8"))))
        return
    if args.spp % 8:
        parser.error("--spp must be a multiple of 8 (symmetric_cosine's group)")
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    import symsphere.mitsuba  # noqa: F401  (registers symsphere_path)

    # run_header: the command, date and measured sources (benchmarks/tables.py's verdict table and its stale note)
    record = {**run_header(), "cpus": os.cpu_count(), "load_before": os.getloadavg(), "args": vars(args),
              "mitsuba": mi.__version__}  # fmt: skip
    print(
        f"{record['cpu']}, {record['cpus']} CPUs, load {record['load_before'][0]:.2f}, Mitsuba {mi.__version__}",
        flush=True,
    )
    with tempfile.TemporaryDirectory() as workdir:
        record["rows"], images = run(args, mi, workdir)
    if args.json:
        Path(args.json).write_text(json.dumps(record, indent=1) + "\n", encoding="utf-8")
    if args.images:
        from symsphere.render import save_png

        Path(args.images).mkdir(parents=True, exist_ok=True)
        for (name, depth), strip in images.items():
            save_png(Path(args.images) / f"{name}_{depth}.png", np.concatenate(strip, axis=1))


if __name__ == "__main__":
    main()
