"""The scheme on real scenes, inside Mitsuba 3: symsphere_path against Mitsuba's path and its samplers.

    .venv/bin/python benchmarks/bench_mitsuba.py speed            # paths/s ratios (interleaved rounds)
    .venv/bin/python benchmarks/bench_mitsuba.py quality          # relMSE and FLIP at equal spp and equal time
    .venv/bin/python benchmarks/bench_mitsuba.py lengths          # mean vertices per camera path
    .venv/bin/python benchmarks/bench_mitsuba.py all --json results/mitsuba.json

Scenes: the shipped Mitsuba scene files (symsphere.mitsuba.SCENES), at --width x --height (256 x 256),
variant llvm_ad_rgb.

speed
    Every case renders --spp samples per pixel (a multiple of 24) in turn for --rounds rounds after a
    warm-up render (the JIT compile, reported separately as the first render's excess over the
    median); reported: the median seconds and paths/s, and the ratio of the medians to Mitsuba's
    ``path`` with the ``independent`` sampler, measured in the same rounds (targets: >= 0.95 for
    strategies bsdf and cosine, >= 0.9 for the symmetric ones).  ``--max-depth 3`` (two bounces, before
    the roulette starts) compares the cost per vertex: paths of nearly the same length in every case.
lengths
    Mean vertices per camera path of every strategy (surface hits, the camera's included), from an
    instrumented copy of ``symsphere_path`` whose ``_trace`` returns the path's depth instead of its
    radiance (written to a temporary module; the estimator is otherwise the shipped one): a strategy
    whose directions make longer paths does more work per path, which paths/s counts against it.
speed and lengths also run ``uniform warp``: symsphere_path with strategy ``symmetric`` whose direction
    at Lambertian vertices is Mitsuba's own ``mi.warp.square_to_uniform_hemisphere`` of an i.i.d. point
    per sample (hashed as the random strategies' points; a rewritten copy registered here only, as for
    lengths): uniform directions without the scheme, so that its ratio to ``symmetric`` · random tells
    the scheme's cost from that of uniform sampling.
report
    Markdown tables of a quality run's --json file: relMSE and FLIP at equal spp and relMSE·spp (equal
    work: Mitsuba's samplers round the spp up), and the efficiency 1/(relMSE·seconds) at the last budget
    with the seconds actually taken, each also as a ratio to the best of Mitsuba's samplers.
quality
    A converged reference per scene (Mitsuba's ``path``, ``independent``, --ref-spp, in two independent
    halves whose difference estimates the reference's own relMSE, which is subtracted).  Every case
    renders at --equal-spp and at equal wall-clock budgets (--budgets seconds: the spp is the budget
    times the case's measured paths/s, rounded down to a multiple of 24, at least 24; Mitsuba's
    stratified, orthogonal and ldsampler round it further to their sizes; the seconds actually taken
    are reported).  Metrics: relMSE = mean over pixels and channels of (x - ref)^2 / (ref^2 + 0.01),
    as bench_render.py, and FLIP (flip-evaluator, LDR, on the tone-mapped images), each the mean over
    --seeds seeds.  Cases: symsphere_path with every strategy (random and Sobol' base points), its
    symmetric_cosine with Sobol' points and the scene's sampler set to multijitter or ldsampler (which
    then supplies every other dimension of the path), and Mitsuba's path with independent, stratified,
    multijitter, orthogonal and ldsampler.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import cpu_name, cpu_snapshot, others_cpu

OURS = [
    ("bsdf", "random"),
    ("cosine", "random"),
    ("cosine", "sobol"),
    ("symmetric", "random"),
    ("symmetric", "sobol"),
    ("symmetric_cosine", "random"),
    ("symmetric_cosine", "sobol"),
]
MITSUBA_SAMPLERS = ["independent", "stratified", "multijitter", "orthogonal", "ldsampler"]
# quality: the scheme with one of Mitsuba's QMC samplers for every other dimension of the path (pixel
# position, light sample, the BSDF samples at other vertices, roulette): the scene's sampler supplies them
OURS_WITH_QMC = [("symmetric_cosine", "sobol", "multijitter"), ("symmetric_cosine", "sobol", "ldsampler")]
MAX_DEPTH, RR_DEPTH = 8, 5  # the shipped scenes' integrator


class Case:
    def __init__(self, mi, name, kind, strategy=None, points=None, sampler="independent", max_depth=MAX_DEPTH,
                 integrator="symsphere_path", label=None):  # fmt: skip
        self.mi, self.scene_name, self.kind = mi, name, kind
        self.strategy, self.points, self.sampler = strategy, points, sampler
        # --only's name of the case: strategy:points[+sampler] or mitsuba:sampler
        self.token = (f"{strategy}:{points}" + (f"+{sampler}" if sampler != "independent" else "")
                      if kind == "ours" else f"mitsuba:{sampler}")  # fmt: skip
        if kind == "ours":
            self.label = label or (
                f"symsphere_path {strategy}"
                + (f" · {points}" if strategy.startswith("symmetric") or points == "sobol" else "")
            )
            if sampler != "independent":
                self.label += f" + {sampler}"
            # Mitsuba's own light sampling (area): this bench measures the strategies, not the light table
            self.integrator = mi.load_dict({"type": integrator, "strategy": strategy, "points": points,
                                            "max_depth": max_depth, "rr_depth": RR_DEPTH,
                                            "emitter_sampling": "area"})  # fmt: skip
        else:
            self.label = f"Mitsuba path · {sampler}"
            self.integrator = mi.load_dict({"type": "path", "max_depth": max_depth, "rr_depth": RR_DEPTH})
        self.scenes = {}

    def scene(self, width, height):
        key = (width, height)
        if key not in self.scenes:
            import symsphere.mitsuba as sm

            self.scenes[key] = self.mi.load_file(str(sm.scene_path(self.scene_name)), width=width, height=height,
                                                 sampler=self.sampler)  # fmt: skip
        return self.scenes[key]

    def render(self, width, height, spp, seed):
        scene = self.scene(width, height)
        if self.kind == "ours":  # symsphere_path renders with a clone of the scene's sampler, rounded as it rounds
            import symsphere.mitsuba as sm

            group = sm.GROUP_SIZES[self.strategy]
            while (rounded := self.mi.load_dict({"type": self.sampler, "sample_count": spp}).sample_count()) % group:
                spp += group  # the sampler's rounding must keep whole groups
        start = time.perf_counter()
        image = self.mi.render(scene, integrator=self.integrator, spp=spp, seed=seed)
        image = np.array(image, dtype=np.float64)[..., :3]  # np.array waits for the kernel
        seconds = time.perf_counter() - start
        actual = scene.sensors()[0].sampler().sample_count() if self.kind == "mitsuba" else rounded
        return image, seconds, actual


def _setup():
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    import symsphere.mitsuba  # noqa: F401  (registers symsphere_path)

    return mi


UNIFORM_WARP = "uniform warp (Mitsuba's, no scheme)"


def speed(args, mi, folder):
    import symsphere.mitsuba as sm

    _rewritten_integrator(folder, "symsphere_path_uniform", _UNIFORM_WARP)
    rows = []
    for name in args.scenes:
        depth = args.max_depth
        uniform = Case(mi, name, "ours", "symmetric", "random", max_depth=depth, integrator="symsphere_path_uniform",
                       label=UNIFORM_WARP)  # fmt: skip
        uniform.token = "uniform_warp"
        cases = [Case(mi, name, "mitsuba", max_depth=depth)] + [
            Case(mi, name, "ours", s, p, max_depth=depth) for s, p in OURS
        ] + [uniform]  # fmt: skip
        cases = cases[:1] + [c for c in cases[1:] if not args.only or c.token in args.only]  # path: the base
        first = {}
        for case in cases:
            first[case.label] = case.render(args.width, args.height, args.spp, 0)[1]
        times = {case.label: [] for case in cases}
        before, t0 = cpu_snapshot(), time.perf_counter()
        for r in range(args.rounds):
            order = cases if r % 2 == 0 else cases[::-1]  # interleaved, alternating order
            for case in order:
                times[case.label].append(case.render(args.width, args.height, args.spp, r + 1)[1])
        load = others_cpu(before, cpu_snapshot(), time.perf_counter() - t0)
        base = statistics.median(times[cases[0].label])
        paths = args.width * args.height * args.spp
        for case in cases:
            median = statistics.median(times[case.label])
            rows.append({"scene": name, "case": case.label, "median_s": median, "paths_per_s": paths / median,
                         "ratio_to_path": base / median, "compile_s": max(first[case.label] - median, 0.0),
                         "others_cpu_share": None if load is None else load["share_of_all_cpus"]})  # fmt: skip
        share = "?" if load is None else f"{load['share_of_all_cpus']:.0%}"
        print(f"{name} (max_depth {depth}): others' CPU share {share}", flush=True)
        for row in rows[-len(cases) :]:
            print(f"  {row['case']:<40} {row['median_s']:.3f} s  {row['paths_per_s'] / 1e6:.2f} Mpaths/s  "
                  f"x{row['ratio_to_path']:.3f}  compile +{row['compile_s']:.1f} s", flush=True)  # fmt: skip
    assert set(args.scenes) <= set(sm.SCENES)
    return rows


# Edits of symsphere_path's source for the instrumented copies (each old text must occur once)
_DEPTH_RETURN = (
    ("return dr.select(valid_ray, result, 0.0), valid_ray", "return mi.Spectrum(mi.Float(depth)), mi.Bool(True)"),
)
_UNIFORM_WARP = (
    (
        """        bx, by, bz = triangle_point(u, v, self.method)
        density = triangle_density(bx, by, bz, self.method)
        x, y, z = orbit_member(bx, by, bz, member, members=24)
        return mi.Vector3f(x, y, z), density / n""",
        """        hs = _random.mix64(h ^ ((mi.UInt64(s) + 1) * _random.GOLDEN))  # one point per sample
        point = mi.Point2f(_random.u01(_random.mix64(hs ^ _BASE_U)), _random.u01(_random.mix64(hs ^ _BASE_V)))
        wo = mi.warp.square_to_uniform_hemisphere(point)
        return wo, mi.warp.square_to_uniform_hemisphere_pdf(wo)""",
    ),
)


def _rewritten_integrator(folder, name, edits):
    """Register *name*: a copy of symsphere_path's module with *edits* (see lengths and UNIFORM_WARP)."""
    import importlib
    import inspect

    import symsphere.mitsuba as sm

    source = Path(inspect.getsourcefile(sm.integrator_class())).read_text(encoding="utf-8")
    register = ('mi.register_integrator("symsphere_path"', f'mi.register_integrator("{name}"')
    for old, new in (*edits, register):  # each exactly once
        if source.count(old) != 1:
            raise RuntimeError(f"symsphere_path's source changed: {old!r} not found once; update bench_mitsuba.py")
        source = source.replace(old, new)
    for old, new in (("from ..", "from symsphere."), ("from . import", "from symsphere.mitsuba import"),
                     ("from ._", "from symsphere.mitsuba._")):  # fmt: skip
        source = source.replace(old, new)  # the relative imports, wherever they are
    (Path(folder) / f"{name}.py").write_text(source, encoding="utf-8")
    if str(folder) not in sys.path:
        sys.path.insert(0, str(folder))
    importlib.import_module(name).register()


def lengths(args, mi, folder):
    rows = []
    _rewritten_integrator(folder, "symsphere_path_depth", _DEPTH_RETURN)
    _rewritten_integrator(folder, "symsphere_path_uniform_depth", _DEPTH_RETURN + _UNIFORM_WARP)
    for name in args.scenes:
        cases = [
            Case(mi, name, "ours", s, p, max_depth=args.max_depth, integrator="symsphere_path_depth") for s, p in OURS
        ] + [Case(mi, name, "ours", "symmetric", "random", max_depth=args.max_depth,
                  integrator="symsphere_path_uniform_depth", label=UNIFORM_WARP)]  # fmt: skip
        for case in cases:
            image = case.render(args.width, args.height, args.spp, 1)[0]
            rows.append({"scene": name, "case": case.label, "vertices_per_path": float(image[..., 0].mean())})
        base = rows[-len(cases)]["vertices_per_path"]
        print(f"{name} (max_depth {args.max_depth}): mean vertices per camera path", flush=True)
        for row in rows[-len(cases) :]:
            row["ratio_to_bsdf"] = row["vertices_per_path"] / base
            print(f"  {row['case']:<40} {row['vertices_per_path']:.4f}  x{row['ratio_to_bsdf']:.4f}", flush=True)
    return rows


def _rel_mse(image, reference):
    return float(np.mean((image - reference) ** 2 / (reference**2 + 0.01)))


def _ldr(image):
    from symsphere.render import tonemap

    return tonemap(image).astype(np.float32) / 255


def quality(args, mi):
    import flip_evaluator

    rows = []
    for name in args.scenes:
        ref_case = Case(mi, name, "mitsuba")
        half = max(args.ref_spp // 2 // 24 * 24, 24)
        a = ref_case.render(args.width, args.height, half, 1000)[0]
        b = ref_case.render(args.width, args.height, half, 2000)[0]
        ref = 0.5 * (a + b)
        own = float(np.mean(((a - b) / 2) ** 2 / (ref**2 + 0.01)))
        ref_ldr = _ldr(ref)
        strip = [ref]  # --images: the reference, then every case at the last budget, side by side
        cases = (
            [Case(mi, name, "ours", s, p) for s, p in OURS]
            + [Case(mi, name, "ours", s, p, sampler) for s, p, sampler in OURS_WITH_QMC]
            + [Case(mi, name, "mitsuba", sampler=s) for s in MITSUBA_SAMPLERS]
        )
        cases = [case for case in cases if not args.only or case.token in args.only]
        for case in cases:
            case.render(args.width, args.height, args.equal_spp, 0)  # compile
            results = {"equal_spp": []}
            rate = []
            for seed in range(1, args.seeds + 1):
                image, seconds, actual = case.render(args.width, args.height, args.equal_spp, seed)
                rate.append(args.width * args.height * actual / seconds)
                results["equal_spp"].append(
                    (
                        _rel_mse(image, ref) - own,
                        float(flip_evaluator.evaluate(ref_ldr, _ldr(image), "LDR", applyMagma=False)[1]),
                        actual,
                        seconds,
                    )
                )
            paths_per_s = statistics.median(rate)
            for budget in args.budgets:
                spp = max(int(budget * paths_per_s / (args.width * args.height)) // 24 * 24, 24)
                results[f"{budget:g}s"] = []
                for seed in range(1, args.seeds + 1):
                    image, seconds, actual = case.render(args.width, args.height, spp, 100 + seed)
                    results[f"{budget:g}s"].append(
                        (
                            _rel_mse(image, ref) - own,
                            float(flip_evaluator.evaluate(ref_ldr, _ldr(image), "LDR", applyMagma=False)[1]),
                            actual,
                            seconds,
                        )
                    )
            strip.append(image)
            row = {"scene": name, "case": case.label, "paths_per_s": paths_per_s, "reference_own_rel_mse": own}
            for key, values in results.items():
                row[key] = {"rel_mse": float(np.mean([v[0] for v in values])), "flip": float(np.mean([v[1] for v in values])),
                            "spp": values[0][2], "seconds": float(np.median([v[3] for v in values]))}  # fmt: skip
            rows.append(row)
            cells = "  ".join(f"{k}: relMSE {v['rel_mse']:.4g} FLIP {v['flip']:.4f} ({v['spp']} spp, {v['seconds']:.2f} s)"
                              for k, v in row.items() if isinstance(v, dict))  # fmt: skip
            print(f"{name} {case.label:<40} {cells}", flush=True)
        if args.images:
            from symsphere.render import save_png

            Path(args.images).mkdir(parents=True, exist_ok=True)
            save_png(Path(args.images) / f"{name}.png", np.concatenate(strip, axis=1))
    return rows


def report(record):
    """Markdown tables of a quality run: per scene, every case at equal spp and at the last budget."""
    lines = []
    rows = record.get("quality", [])
    budgets = (
        [k for k in rows[0] if k.endswith("s") and isinstance(rows[0][k], dict) and k != "equal_spp"] if rows else []
    )
    last = budgets[-1] if budgets else None
    for scene in dict.fromkeys(r["scene"] for r in rows):
        mine = [r for r in rows if r["scene"] == scene]
        work = {r["case"]: r["equal_spp"]["rel_mse"] * r["equal_spp"]["spp"] for r in mine}
        eff = {r["case"]: 1.0 / (r[last]["rel_mse"] * r[last]["seconds"]) for r in mine}
        best = max((c for c in eff if c.startswith("Mitsuba")), key=lambda c: eff[c])
        best_work = min((c for c in work if c.startswith("Mitsuba")), key=lambda c: work[c])
        lines += [f"**{scene}** (reference's own relMSE {mine[0]['reference_own_rel_mse']:.2g}, subtracted)", "",
                  f"| case | relMSE (spp) | FLIP | relMSE·spp | × best Mitsuba | at {last}: relMSE (spp, s) | FLIP | efficiency 1/(relMSE·s) | × best Mitsuba |",
                  "|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
        for r in mine:
            e, b = r["equal_spp"], r[last]
            lines.append(f"| {r['case']} | {e['rel_mse']:.4g} ({e['spp']}) | {e['flip']:.4f} | {work[r['case']]:.3g} | "
                         f"{work[best_work] / work[r['case']]:.2f} | {b['rel_mse']:.4g} ({b['spp']}, {b['seconds']:.2f}) | "
                         f"{b['flip']:.4f} | {eff[r['case']]:.3g} | {eff[r['case']] / eff[best]:.2f} |")  # fmt: skip
        lines += [
            "",
            f"(best Mitsuba sampler: at equal work {best_work.split(' · ')[-1]}, at {last} {best.split(' · ')[-1]})",
            "",
        ]
    return "\n".join(lines)


def main(argv=None):
    import symsphere.mitsuba as sm

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "what",
        choices=("speed", "quality", "lengths", "all", "report"),
        help="report: print the markdown tables of --json FILE",
    )
    parser.add_argument("--scenes", nargs="+", default=list(sm.SCENES), choices=sm.SCENES)
    parser.add_argument("--width", type=int, default=256)
    parser.add_argument("--height", type=int, default=256)
    parser.add_argument(
        "--spp", type=int, default=48, help="speed: spp per render, a multiple of 24 (default %(default)s)"
    )
    parser.add_argument(
        "--max-depth", type=int, default=MAX_DEPTH, help="speed, lengths: max_depth of every integrator (default 8)"
    )
    parser.add_argument("--rounds", type=int, default=5, help="speed: interleaved rounds (default %(default)s)")
    parser.add_argument("--ref-spp", type=int, default=2048, help="quality: reference spp (default %(default)s)")
    parser.add_argument("--equal-spp", type=int, default=48, help="quality: spp at equal spp (default %(default)s)")
    parser.add_argument(
        "--budgets", type=float, nargs="+", default=[1.0, 2.0, 4.0], help="quality: seconds (default 1 2 4)"
    )
    parser.add_argument("--seeds", type=int, default=2, help="quality: seeds per measurement (default %(default)s)")
    parser.add_argument("--only", nargs="+", metavar="CASE", help="speed, quality: only these cases, each "
                        "strategy:points[+sampler] (e.g. cosine:sobol, symmetric_cosine:sobol+ldsampler), "
                        "mitsuba:SAMPLER or uniform_warp; speed always runs its base, Mitsuba's path with "
                        "independent; quality always renders the reference and needs a mitsuba:SAMPLER case")  # fmt: skip
    parser.add_argument("--json", metavar="FILE", help="also write the results as JSON")
    parser.add_argument("--images", metavar="DIR", help="quality: write DIR/<scene>.png, the reference and every case "
                        "at the last budget side by side (in the order of the table)")  # fmt: skip
    args = parser.parse_args(argv)
    if args.spp % 24 or args.equal_spp % 24:
        parser.error("--spp and --equal-spp must be multiples of 24 (the symmetric strategies' group)")
    if args.only:
        known = {f"{s}:{p}" for s, p in OURS} | {f"{s}:{p}+{q}" for s, p, q in OURS_WITH_QMC}
        known |= {f"mitsuba:{q}" for q in MITSUBA_SAMPLERS} | {"uniform_warp"}
        if unknown := sorted(set(args.only) - known):
            parser.error(f"--only: {', '.join(unknown)} not a case; use some of {', '.join(sorted(known))}")
        if args.what in ("quality", "all") and not any(c.startswith("mitsuba:") for c in args.only):
            parser.error("--only: quality needs a mitsuba:SAMPLER case (its ratios are to Mitsuba's best sampler)")
    if args.what == "report":
        print(report(json.loads(Path(args.json).read_text(encoding="utf-8"))))
        return
    mi = _setup()
    record = {"cpu": cpu_name(), "cpus": os.cpu_count(), "load_before": os.getloadavg(), "args": vars(args),
              "mitsuba": mi.__version__}  # fmt: skip
    print(
        f"{record['cpu']}, {record['cpus']} CPUs, load {record['load_before'][0]:.2f}, Mitsuba {mi.__version__}",
        flush=True,
    )
    import tempfile

    with tempfile.TemporaryDirectory() as folder:  # the rewritten copies of symsphere_path (speed, lengths)
        if args.what in ("speed", "all"):
            record["speed"] = speed(args, mi, folder)
        if args.what in ("quality", "all"):
            record["quality"] = quality(args, mi)
        if args.what in ("lengths", "all"):
            record["lengths"] = lengths(args, mi, folder)
    if args.json:
        Path(args.json).write_text(json.dumps(record, indent=1) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
