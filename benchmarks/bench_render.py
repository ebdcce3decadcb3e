"""Renderer benchmarks: paths per second on smallpt's Cornell box, cache start-up, and convergence.

Usage (from the repository root, package installed)::

    python benchmarks/bench_render.py speed                    # paths/s per sampler, 256x192, start-up time
    python benchmarks/bench_render.py speed --spp 96 --repeats 5
    python benchmarks/bench_render.py convergence              # RMSE vs spp, efficiency, images -> docs/
    python benchmarks/bench_render.py validation               # furnace and z-test tables (as the tests)
    python benchmarks/bench_render.py equal-time               # every strategy vs Mitsuba 3 at equal spp and time
    python benchmarks/bench_render.py paths-vs-mitsuba         # paths/s, ours (cosine, both integrators) vs Mitsuba 3
    python benchmarks/bench_render.py equal-time --budgets 0.2 0.4 --equal-spp 8 --reference-spp 256 \\
        --mitsuba-reference-spp 128 --width 64 --height 48 --seeds 1 --no-images   # a quick check
    python benchmarks/bench_render.py equal-time --no-mitsuba --integrators path --baseline symmetric_sobol \\
        --samplers symmetric_sobol symmetric_sobol_interlaced2 symmetric_sobol_interlaced3   # base points only

``speed``
    Every sampler renders ``cornell`` at 256 x 192 with ``--spp`` samples per
    pixel, ``--repeats`` times, taking turns round by round so that all see
    the same machine load.  Reported: the median wall time, paths per second
    (width * height * spp / wall seconds, after compilation) with all
    threads and with one thread (on an otherwise idle machine all threads ~=
    cores x one thread; with other load, the one-thread figure is the
    steadier).  Then the start-up of a *second*
    process: ``symsphere render`` on a 16 x 12 image, run twice; the second
    run finds the kernel in numba's cache.
``convergence``
    A high-spp reference of ``cornell`` at 128 x 96 (``--reference-spp``,
    cosine sampler), then every sampler at spp = 24 * 2^k: RMSE against the
    reference (minus the reference's own noise, estimated from two
    independent halves), the time per path on one thread (interleaved
    rounds; one thread so that other load on the machine matters less), and
    the efficiency 1 / (MSE * time).  Writes ``docs/images/render_convergence.png``,
    ``docs/images/render_cornell_<sampler>.png`` (all at the same spp),
    ``docs/images/render_translucent_<sampler>.png`` and prints Markdown tables for
    docs/results/render-convergence.md.
``paths-vs-mitsuba``
    Paths per second only: ours (``--samplers``, default cosine, with each
    integrator) and Mitsuba 3's ``path`` on ``--scenes`` at ``--spp``, taking
    turns for ``--rounds`` rounds after a warm-up; the medians, their range and
    the ratio to Mitsuba's median, with the load average and the CPU share of
    other processes (a quick check on a busy machine; ``--json`` keeps every
    measurement).
``equal-time``
    Every strategy -- each sampler in ``SAMPLERS`` x ``integrator`` in
    {"path", "bsdf"} (when ``render`` takes an ``integrator``; else today's
    BSDF-sampling estimator) -- and Mitsuba 3's ``path`` integrator
    (``llvm_ad_rgb``, the same threads) on ``cornell`` and on ``gap`` (a room
    lit through a gap, indirect light dominating; benchmarks/_mitsuba_scenes.py,
    which also builds the Mitsuba scenes), at ``--width`` x ``--height``.  Each
    renderer is compared with a converged reference of its own (ours:
    ``--reference-spp`` with the cosine sampler and the default integrator;
    Mitsuba: ``--mitsuba-reference-spp`` of ``path``; each the mean of two
    independent halves, whose difference estimates the reference's own error,
    which is subtracted from relMSE).  Metrics: relMSE = mean over pixels and
    channels of (x - ref)^2 / (ref^2 + 0.01), and LDR FLIP (flip-evaluator) of
    the tone-mapped sRGB images (``symsphere.render.tonemap``, exposure 1)
    against the reference's, both the mean over ``--seeds`` seeds; efficiency
    1 / (relMSE x seconds).  First every strategy renders ``--equal-spp``
    (interleaved, all seeds): the equal-spp table and each strategy's paths/s;
    then, for each budget of ``--budgets`` seconds, every strategy renders the
    spp that its measured paths/s fit into the budget (the actual seconds are
    reported).  Our time is ``RenderResult.seconds`` (compilation excluded);
    Mitsuba's is the wall time of ``mi.render`` up to the image in numpy,
    after a warm-up render with the same spp (its JIT compilation excluded;
    Mitsuba renders of more than 64 spp are split into passes).  Writes
    ``docs/images/equal_time_<scene>.png`` (the images at the largest budget,
    seed 1) and a JSON file in ``benchmarks/results/`` with every number and
    the Markdown tables, which are also printed.  ``--integrators`` restricts the
    integrators; the closing table compares every other symmetric sampler with
    ``--baseline`` (default ``cosine``), seed by seed.
"""

from __future__ import annotations

import argparse
import datetime
import inspect
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numba
import numpy as np

from symsphere.render import SAMPLERS, save_png, tonemap
from symsphere.render import render as _render

# The integrator of the speed, convergence and validation subcommands (their --integrator); equal-time
# compares both and passes it itself.
_INTEGRATOR = {"integrator": "bsdf"}


def render(*args, **kwargs):
    """symsphere.render.render with the subcommand's integrator unless one is given."""
    return _render(*args, **{**_INTEGRATOR, **kwargs})


sys.path.insert(0, str(Path(__file__).resolve().parent))  # benchmarks/: _machine, _mitsuba_scenes, bench_sample
from _machine import cpu_name, cpu_snapshot, others_cpu  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent


def _timed_rounds(width, height, spp, repeats, threads):
    """Median render seconds per sampler, all samplers taking turns in every round."""
    seconds = {s: [] for s in SAMPLERS}
    for round_ in range(repeats):
        for sampler in SAMPLERS:
            result = render(
                "cornell", width=width, height=height, spp=spp, sampler=sampler, seed=round_, threads=threads
            )
            seconds[sampler].append(result.seconds)
    return {s: statistics.median(v) for s, v in seconds.items()}, {s: min(v) for s, v in seconds.items()}


def speed(args):
    width, height = args.width, args.height
    for sampler in SAMPLERS:  # compile or load every variant first
        render("cornell", width=8, height=8, spp=1, sampler=sampler, seed=0)
    load_before = os.getloadavg()
    median_all, best_all = _timed_rounds(width, height, args.spp, args.repeats, None)
    median_one, best_one = _timed_rounds(width, height, args.spp, args.repeats, 1)
    load_after = os.getloadavg()
    paths = width * height * args.spp
    print(
        f"cornell {width}x{height}, {args.spp} spp = {paths} paths per render, {args.repeats} rounds; "
        f"{numba.config.NUMBA_NUM_THREADS} threads ({numba.threading_layer()}), {os.cpu_count()} CPUs, "
        f"{platform.processor() or platform.machine()}, Python {platform.python_version()}, numba {numba.__version__}; "
        f"load average before {load_before[0]:.2f}, after {load_after[0]:.2f}"
    )
    print()
    print("| sampler | Mpaths/s, all threads (median) | best | Mpaths/s, 1 thread (median) | best |")
    print("|---|---:|---:|---:|---:|")
    for sampler in SAMPLERS:
        print(
            f"| `{sampler}` | {paths / median_all[sampler] / 1e6:.2f} | {paths / best_all[sampler] / 1e6:.2f} "
            f"| {paths / median_one[sampler] / 1e6:.2f} | {paths / best_one[sampler] / 1e6:.2f} |"
        )
    print()
    command = [
        sys.executable, "-m", "symsphere", "render", "--scene", "cornell", "--width", "16", "--height", "12",
        "--spp", "1", "--seed", "0", "--no-progress",
    ]  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        for attempt in ("first", "second"):
            start = time.perf_counter()
            subprocess.run([*command, "--out", os.path.join(tmp, "x.png")], check=True, capture_output=True)
            print(f"{attempt} `symsphere render` process (16x12, 1 spp), wall: {time.perf_counter() - start:.2f} s")


def convergence(args):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    width, height = args.width, args.height
    images_dir = ROOT / "docs" / "images"
    images_dir.mkdir(parents=True, exist_ok=True)
    half = args.reference_spp // 2
    if not args.replot:
        print(f"reference: cosine, {args.reference_spp} spp at {width}x{height} ...", file=sys.stderr)
        ref_a = render("cornell", width=width, height=height, spp=half, sampler="cosine", seed=10_001)
        ref_b = render("cornell", width=width, height=height, spp=half, sampler="cosine", seed=10_002)
        reference = 0.5 * (ref_a.image + ref_b.image)
        # Var(reference) per pixel ~ ((a - b) / 2)^2: the reference's own contribution to the measured MSE.
        reference_mse = float(np.mean(((ref_a.image - ref_b.image) / 2) ** 2))
    else:
        reference_mse = json.loads((images_dir / "render_convergence.json").read_text())["reference_mse"]

    spps = [24 * 2**k for k in range(args.levels)]
    rmse = {s: [] for s in SAMPLERS}
    results = images_dir / "render_convergence.json"  # raw numbers, to replot with --replot
    if args.replot:
        saved = json.loads(results.read_text())
        spps, rmse, per_path = saved["spp"], saved["rmse"], saved["seconds_per_path"]
    for sampler in SAMPLERS if not args.replot else ():
        for spp in spps:
            errors = []
            for rep in range(args.replicates):
                result = render("cornell", width=width, height=height, spp=spp, sampler=sampler, seed=1000 * rep + spp)
                errors.append(float(np.mean((result.image - reference) ** 2)) - reference_mse)
                if spp == args.image_spp and rep == 0:
                    save_png(images_dir / f"render_cornell_{sampler}.png", result.image)
            rmse[sampler].append(float(np.sqrt(max(np.mean(errors), 0.0))))
            print(f"{sampler} {spp} spp: RMSE {rmse[sampler][-1]:.4f}", file=sys.stderr)
    if not args.replot:
        save_png(images_dir / "render_cornell_reference.png", reference)
        # Time per path on one thread (robust to other load on the machine), samplers interleaved.
        per_path = {s: t / (width * height * 96) for s, t in _timed_rounds(width, height, 96, 3, 1)[0].items()}
        for name, sampler in (("translucent", "symmetric"), ("translucent", "cosine")):
            image = render(name, width=width, height=height, spp=args.image_spp, sampler=sampler, seed=1).image
            save_png(images_dir / f"render_{name}_{sampler}.png", image)
        saved = dict(spp=spps, rmse=rmse, seconds_per_path=per_path, reference_mse=reference_mse)
        results.write_text(json.dumps(saved, indent=1))
    seconds = {s: [per_path[s] * width * height * spp for spp in spps] for s in SAMPLERS}

    figure = Figure(figsize=(10, 4.2), layout="constrained")
    FigureCanvasAgg(figure)
    left, right = figure.subplots(1, 2)
    for sampler in SAMPLERS:
        left.loglog(spps, rmse[sampler], "o-", label=sampler, ms=3)
        right.loglog(seconds[sampler], rmse[sampler], "o-", label=sampler, ms=3)
    slope = np.array(spps, dtype=float)
    left.loglog(slope, rmse["cosine"][0] * np.sqrt(spps[0] / slope), "k:", lw=0.8, label="∝ spp^-1/2")
    left.set_xticks(spps, [str(v) for v in spps], minor=False)
    left.set_xticks([], minor=True)
    left.set_xlabel("samples per pixel")
    left.set_ylabel("RMSE vs reference (linear radiance)")
    left.set_title(f"cornell {width}x{height}: RMSE vs spp")
    right.set_xlabel("render seconds (one thread)")
    right.set_title("RMSE vs time (equal time: read across)")
    for axes in (left, right):
        axes.grid(True, which="both", lw=0.3)
    left.legend(fontsize=7)
    figure.savefig(images_dir / "render_convergence.png", dpi=100)

    print(f"reference: {args.reference_spp} spp cosine; its own MSE {reference_mse:.3g} subtracted\n")
    print("| sampler | " + " | ".join(f"{s} spp" for s in spps) + " |")
    print("|---|" + "---:|" * len(spps))
    for sampler in SAMPLERS:
        print(f"| `{sampler}` | " + " | ".join(f"{v:.4f}" for v in rmse[sampler]) + " |")
    print()
    last = -1
    base = 1.0 / (rmse["uniform"][last] ** 2 * seconds["uniform"][last])
    print(
        f"| sampler | RMSE at {spps[last]} spp | µs per path (1 thread) | one-thread seconds at {spps[last]} spp "
        "| efficiency 1/(MSE·time) relative to `uniform` |"
    )
    print("|---|---:|---:|---:|---:|")
    for sampler in SAMPLERS:
        efficiency = 1.0 / (rmse[sampler][last] ** 2 * seconds[sampler][last])
        print(
            f"| `{sampler}` | {rmse[sampler][last]:.4f} | {per_path[sampler] * 1e6:.3f} | {seconds[sampler][last]:.1f} "
            f"| {efficiency / base:.2f} |"
        )


def validation(args):
    """The numbers behind tests/render/, as Markdown tables (same scenes, sizes and seeds)."""
    import math

    from scipy import stats

    from symsphere.render import furnace

    print("Furnace (32 x 32 pixels, 48 spp, Le = 0.7; mean ± standard error over pixels; z = (mean − exact) / se):\n")
    print("| sampler | scene | ρ | exact | mean ± se | z |")
    print("|---|---|---:|---:|---:|---:|")
    for sampler in SAMPLERS:
        for translucent in (False, True):
            for rho in (0.3, 0.6, (0.9 if translucent or sampler == "cosine" else 0.85)):
                scene = furnace(albedo=rho, emission=0.7, translucent=translucent)
                seed = round(1000 * rho) + translucent
                pixels = render(scene, width=32, height=32, spp=48, sampler=sampler, seed=seed).image[..., 0].ravel()
                mean, se = pixels.mean(), pixels.std(ddof=1) / math.sqrt(pixels.size)
                exact = 0.7 / (1 - rho)
                kind = "translucent" if translucent else "diffuse"
                print(
                    f"| `{sampler}` | {kind} | {rho} | {exact:.4f} | {mean:.4f} ± {se:.4f} | {(mean - exact) / se:+.2f} |"
                )
    print()
    width, height, block, replicates = 32, 24, 8, 8

    def block_stats(sampler, spp, seed0):
        images = np.stack(
            [render("cornell", width=width, height=height, spp=spp, sampler=sampler, seed=seed0 + r).image
             for r in range(replicates)]
        )  # fmt: skip
        mean, var = images.mean(axis=0), images.var(axis=0, ddof=1) / replicates
        shape = (height // block, block, width // block, block, 3)
        return mean.reshape(shape).mean(axis=(1, 3)), var.reshape(shape).sum(axis=(1, 3)) / block**4

    ref_mean, ref_var = block_stats("cosine", 512, 90_000)
    tests = len(SAMPLERS) * ref_mean.size
    critical = stats.norm.isf((1 - 0.99 ** (1 / tests)) / 2)
    print(f"Unbiasedness (cornell 32 x 24, 8 replicates x 48 spp vs 8 x 512 spp cosine; 8 x 8 blocks x 3 channels; "
          f"{tests} tests, Šidák critical |z| = {critical:.2f}):\n")  # fmt: skip
    print("| sampler | max \\|z\\| over 36 block-channels | mean z | rms z |")
    print("|---|---:|---:|---:|")
    for index, sampler in enumerate(SAMPLERS):
        mean, var = block_stats(sampler, 48, 1000 * (index + 1))
        z = (mean - ref_mean) / np.sqrt(var + ref_var)
        print(f"| `{sampler}` | {np.abs(z).max():.2f} | {z.mean():+.2f} | {np.sqrt((z**2).mean()):.2f} |")


# --- equal-time ------------------------------------------------------------------------------------

MITSUBA_PASS_SPP = 64  # Mitsuba renders of more spp are split into passes (its wavefront memory grows with spp)


def _integrator_choices():
    """(integrators to compare, the default): ("path", "bsdf") if ``render`` takes an integrator, else (None,)."""
    parameters = inspect.signature(_render).parameters
    if "integrator" not in parameters:
        return (None,), None
    import symsphere.render

    default = parameters["integrator"].default
    available = getattr(symsphere.render, "INTEGRATORS", ("path", "bsdf"))
    return tuple(sorted((i for i in ("path", "bsdf") if i in available), key=lambda name: name != default)), default


def _rel_mse(image, reference):
    return float(np.mean((image - reference) ** 2 / (reference**2 + 0.01)))


class _Reference:
    """A converged image from two independent halves; its own relMSE (to subtract) from their difference."""

    def __init__(self, half_a, half_b):
        self.image = 0.5 * (half_a + half_b)
        # Var(reference) per pixel ~ ((a - b) / 2)^2: what the reference adds to a measured relMSE.
        self.own_rel_mse = float(np.mean(((half_a - half_b) / 2) ** 2 / (self.image**2 + 0.01)))
        self.ldr = tonemap(self.image).astype(np.float32) / 255

    def metrics(self, image):
        import flip_evaluator

        ldr = tonemap(image).astype(np.float32) / 255
        flip = flip_evaluator.evaluate(self.ldr, ldr, "LDR", applyMagma=False)[1]
        return _rel_mse(image, self.image) - self.own_rel_mse, float(flip)


class _Ours:
    renderer = "symsphere"

    def __init__(self, scene, sampler, integrator, width, height, threads):
        self.scene, self.sampler, self.integrator = scene, sampler, integrator
        self.width, self.height, self.threads = width, height, threads
        self.label = f"`{sampler}`" + (f" · {integrator}" if integrator else " · bsdf")
        self.key = f"{sampler}/{integrator or 'bsdf'}"

    def render(self, spp, seed):
        extra = {} if self.integrator is None else {"integrator": self.integrator}
        result = render(self.scene, width=self.width, height=self.height, spp=spp, sampler=self.sampler, seed=seed,
                        threads=self.threads, **extra)  # fmt: skip
        return result.image, result.seconds

    def warm_up(self, spp):
        """Compile the kernel or load it from numba's cache (render() times only after that anyway)."""
        extra = {} if self.integrator is None else {"integrator": self.integrator}
        render(self.scene, width=8, height=8, spp=1, sampler=self.sampler, seed=0, threads=self.threads, **extra)


class _Mitsuba:
    """Mitsuba 3's ``path`` integrator on the converted scene (benchmarks/_mitsuba_scenes.py)."""

    renderer = "mitsuba"
    label = "Mitsuba 3 `path`"
    key = "mitsuba/path"

    def __init__(self, scene, width, height, threads):
        import drjit as dr
        import mitsuba as mi
        from _mitsuba_scenes import mitsuba_dict

        mi.set_variant("llvm_ad_rgb")
        dr.set_thread_count(threads)
        self.dr, self.mi = dr, mi
        with tempfile.TemporaryDirectory(prefix="symsphere-mitsuba-") as workdir:
            start = time.perf_counter()
            self.scene = mi.load_dict(mitsuba_dict(scene, width, height, 1, workdir=workdir))
            self.load_seconds = time.perf_counter() - start
        self.warm = {}  # pass spp -> seconds of the first (compiling) render
        self.version = f"mitsuba {mi.__version__}, drjit {dr.__version__}, llvm_ad_rgb, {dr.thread_count()} threads"

    def _pass(self, spp, seed):
        start = time.perf_counter()
        image = np.array(
            self.mi.render(self.scene, spp=spp, seed=self.dr.opaque(self.mi.UInt32, seed)), dtype=np.float64
        )
        return image, time.perf_counter() - start

    @staticmethod
    def _split(spp):
        passes = -(-spp // MITSUBA_PASS_SPP)
        return [spp // passes + (1 if k < spp % passes else 0) for k in range(passes)]

    def warm_up(self, spp):
        """Compile the kernels of every pass size *spp* needs (a render with an unused seed, not timed)."""
        for size in set(self._split(spp)):
            if size not in self.warm:
                self.warm[size] = self._pass(size, 2**31 - size)[1]

    def render(self, spp, seed):
        self.warm_up(spp)
        image, seconds = 0.0, 0.0
        sizes = self._split(spp)
        for k, size in enumerate(sizes):
            part, elapsed = self._pass(size, seed * 1009 + k)
            image = image + part * size
            seconds += elapsed
        return image / spp, seconds


def _mitsuba_status(no_mitsuba):
    if no_mitsuba:
        return False, "--no-mitsuba"
    try:
        from bench_sample import probe_mitsuba  # sets DRJIT_LIBLLVM_PATH, tries the variant in a subprocess
    except ImportError as error:
        return False, f"benchmarks/bench_sample.py cannot be imported: {error}"
    return probe_mitsuba()


def _reference(strategy, spp, seed):
    half = max(1, spp // 2)
    strategy.warm_up(half)
    a, seconds_a = strategy.render(half, seed)
    b, seconds_b = strategy.render(half, seed + 1)
    return _Reference(a, b), seconds_a + seconds_b


def _rotated(items, round_):
    k = round_ % len(items)
    return items[k:] + items[:k]


def _fmt(value, digits=3):
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "–"
    return f"{value:.{digits}g}" if abs(value) < 1e4 else f"{value:.3g}"


def _scene_for(name):
    from _mitsuba_scenes import gap_room

    from symsphere.render import get_scene

    return gap_room() if name == "gap" else get_scene(name)


def _equal_time_scene(name, args, integrators, default_integrator, mitsuba_ok, mitsuba_reason, images_dir):
    width, height, threads = args.width, args.height, args.threads
    scene = _scene_for(name)
    pixels = width * height
    samplers = args.samplers or list(SAMPLERS)
    ours = [_Ours(scene, s, i, width, height, threads) for s in samplers for i in integrators]
    strategies = list(ours)
    mitsuba, note = None, mitsuba_reason
    if mitsuba_ok:
        try:
            mitsuba = _Mitsuba(scene, width, height, threads)
            strategies.append(mitsuba)
            note = f"{mitsuba.version}; scene loaded in {mitsuba.load_seconds:.2f} s"
        except Exception as error:  # a scene Mitsuba cannot express (translucent), or a loading failure
            note = f"skipped: {type(error).__name__}: {error}"
    print(f"\n## {name} {width}x{height}: {len(strategies)} strategies; Mitsuba: {note}", file=sys.stderr)
    for strategy in ours:
        strategy.warm_up(1)

    # References, one per renderer.
    reference_ours = _Ours(scene, "cosine", default_integrator, width, height, threads)
    print(f"{name}: reference (ours): cosine, {args.reference_spp} spp ...", file=sys.stderr)
    ref = {"symsphere": _reference(reference_ours, args.reference_spp, 900_001)}
    if mitsuba is not None:
        print(f"{name}: reference (Mitsuba path): {args.mitsuba_reference_spp} spp ...", file=sys.stderr)
        ref["mitsuba"] = _reference(mitsuba, args.mitsuba_reference_spp, 900_001)
    references = {
        r: dict(spp=(args.reference_spp if r == "symsphere" else args.mitsuba_reference_spp), seconds=sec,
                own_rel_mse=reference.own_rel_mse)
        for r, (reference, sec) in ref.items()
    }  # fmt: skip
    if mitsuba is not None:  # are the two scenes the same? (their references' relMSE, minus both references' noise)
        a, b = ref["symsphere"][0], ref["mitsuba"][0]
        cross = float(np.mean((a.image - b.image) ** 2 / (a.image**2 + 0.01)))
        references["ours_vs_mitsuba_rel_mse"] = cross  # includes both references' noise (~ the two own_rel_mse)
        references["mean_radiance"] = dict(symsphere=a.image.mean(axis=(0, 1)).tolist(),
                                           mitsuba=b.image.mean(axis=(0, 1)).tolist())  # fmt: skip
        ratio = a.image.mean() / b.image.mean()
        references["mean_radiance_ratio"] = float(ratio)
        if abs(ratio - 1) > 0.03:
            print(f"WARNING {name}: the mean radiance of our reference is {ratio:.3f} x Mitsuba's: "
                  "the two renderers do not render the same scene", file=sys.stderr)  # fmt: skip

    seeds = list(range(1, args.seeds + 1))
    records = {s.key: dict(label=s.label, renderer=s.renderer, equal_spp=[], budgets={}) for s in strategies}
    for strategy in strategies:
        strategy.warm_up(args.equal_spp)
    load_before, cpu_before, wall_start = os.getloadavg(), cpu_snapshot(), time.perf_counter()
    # Equal spp (also each strategy's paths/s), interleaved.
    for round_, seed in enumerate(seeds):
        for strategy in _rotated(strategies, round_):
            image, seconds = strategy.render(args.equal_spp, seed)
            rel, flip = ref[strategy.renderer][0].metrics(image)
            records[strategy.key]["equal_spp"].append(
                dict(seed=seed, spp=args.equal_spp, seconds=seconds, rel_mse=rel, flip=flip)
            )
        print(f"{name}: equal spp, seed {seed} done", file=sys.stderr)
    for strategy in strategies:
        runs = records[strategy.key]["equal_spp"]
        records[strategy.key]["calibration_paths_per_second"] = statistics.median(
            pixels * r["spp"] / r["seconds"] for r in runs
        )
    # Equal time: the spp each strategy's paths/s fits into the budget.
    for strategy in strategies:
        pps = records[strategy.key]["calibration_paths_per_second"]
        for budget in args.budgets:
            spp = max(1, round(budget * pps / pixels))
            records[strategy.key]["budgets"][str(budget)] = dict(spp=spp, runs=[])
            strategy.warm_up(spp)
    keep = {}
    for round_, seed in enumerate(seeds):
        for budget in args.budgets:
            for strategy in _rotated(strategies, round_):
                entry = records[strategy.key]["budgets"][str(budget)]
                image, seconds = strategy.render(entry["spp"], 100 * seed + args.budgets.index(budget))
                rel, flip = ref[strategy.renderer][0].metrics(image)
                entry["runs"].append(dict(seed=seed, seconds=seconds, rel_mse=rel, flip=flip))
                if seed == seeds[0] and budget == args.budgets[-1]:
                    keep[strategy.key] = (image, entry["spp"], seconds, rel, flip)
            print(f"{name}: equal time {budget} s, seed {seed} done", file=sys.stderr)
    wall = time.perf_counter() - wall_start
    machine = dict(load_before=load_before[0], load_after=os.getloadavg()[0],
                   others_cpu=others_cpu(cpu_before, cpu_snapshot(), wall))  # fmt: skip

    # Summaries.
    for record in records.values():
        runs = record["equal_spp"]
        record["equal_spp_summary"] = _summary(runs, pixels * runs[0]["spp"])
        for entry in record["budgets"].values():
            entry.update(_summary(entry["runs"], pixels * entry["spp"]))
        all_runs = [(pixels * r["spp"], r["seconds"]) for r in runs] + [
            (pixels * e["spp"], r["seconds"]) for e in record["budgets"].values() for r in e["runs"]
        ]
        record["paths_per_second"] = statistics.median(p / s for p, s in all_runs)
    result = dict(scene=name, width=width, height=height, mitsuba=note, references=references, strategies=records,
                  machine=machine, seconds=wall)  # fmt: skip
    result["markdown"] = _equal_time_tables(result, args)
    print(result["markdown"])
    if not args.no_images:
        path = images_dir / f"equal_time_{name}.png"
        _contact_sheet(path, name, ref, keep, records, args.budgets[-1], width, height, references)
        result["image"] = str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else str(path)
    return result


def _summary(runs, paths):
    rel = statistics.fmean(r["rel_mse"] for r in runs)
    seconds = statistics.fmean(r["seconds"] for r in runs)
    spread = statistics.stdev(r["rel_mse"] for r in runs) / math.sqrt(len(runs)) if len(runs) > 1 else None
    return dict(
        rel_mse=rel,
        rel_mse_se=spread,
        flip=statistics.fmean(r["flip"] for r in runs),
        seconds=seconds,
        paths_per_second=paths / seconds,
        efficiency=1.0 / (rel * seconds) if rel > 0 else math.inf,
    )


def _equal_time_tables(result, args):
    records = result["strategies"]
    mitsuba = records.get("mitsuba/path")
    budgets = [str(b) for b in args.budgets]
    last = budgets[-1]
    lines = [
        f"**{result['scene']}** {result['width']}x{result['height']}; Mitsuba: {result['mitsuba']}.  "
        f"Load average {result['machine']['load_before']:.2f} before, {result['machine']['load_after']:.2f} after"
        + (f"; other processes used {result['machine']['others_cpu']['share_of_all_cpus']:.0%} of the CPUs"
           if result["machine"]["others_cpu"] else "") + ".",
        "",
        f"Equal spp ({args.equal_spp}), mean of {args.seeds} seeds:",
        "",
        "| strategy | Mpaths/s | seconds | relMSE | FLIP | efficiency 1/(relMSE·s) | × Mitsuba |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]  # fmt: skip
    for record in records.values():
        summary = record["equal_spp_summary"]
        ratio = summary["efficiency"] / mitsuba["equal_spp_summary"]["efficiency"] if mitsuba else None
        lines.append(
            f"| {record['label']} | {record['paths_per_second'] / 1e6:.2f} | {summary['seconds']:.3f} "
            f"| {_fmt(summary['rel_mse'])} | {summary['flip']:.4f} | {_fmt(summary['efficiency'])} | {_fmt(ratio, 2)} |"
        )
    lines += [
        "",
        f"Equal time (budgets {', '.join(budgets)} s; spp from each strategy's measured paths/s; mean of {args.seeds} "
        f"seeds): relMSE and FLIP at each budget, spp and actual seconds at {last} s, efficiency at {last} s:",
        "",
        "| strategy | " + " | ".join(f"relMSE {b} s" for b in budgets) + " | " + " | ".join(f"FLIP {b} s" for b in budgets)
        + f" | spp / s at {last} s | efficiency | × Mitsuba |",
        "|---|" + "---:|" * (2 * len(budgets) + 3),
    ]  # fmt: skip
    for record in records.values():
        entries = [record["budgets"][b] for b in budgets]
        ratio = entries[-1]["efficiency"] / mitsuba["budgets"][last]["efficiency"] if mitsuba else None
        lines.append(
            f"| {record['label']} | " + " | ".join(_fmt(e["rel_mse"]) for e in entries) + " | "
            + " | ".join(f"{e['flip']:.4f}" for e in entries)
            + f" | {entries[-1]['spp']} / {entries[-1]['seconds']:.2f} | {_fmt(entries[-1]['efficiency'])} | {_fmt(ratio, 2)} |"
        )  # fmt: skip
    refs = result["references"]
    lines += ["", "References: " + "; ".join(
        f"{r} {refs[r]['spp']} spp in {refs[r]['seconds']:.1f} s (own relMSE {refs[r]['own_rel_mse']:.2g}, subtracted)"
        for r in ("symsphere", "mitsuba") if r in refs
    ) + (f"; ours vs Mitsuba's reference: relMSE {refs['ours_vs_mitsuba_rel_mse']:.3g} (both references' noise "
         f"included), mean radiance ratio {refs['mean_radiance_ratio']:.4f}" if "ours_vs_mitsuba_rel_mse" in refs
         else "") + "."]  # fmt: skip
    return "\n".join(lines)


def _contact_sheet(path, name, ref, keep, records, budget, width, height, references):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    tiles = [(f"reference: ours, {references['symsphere']['spp']} spp", ref["symsphere"][0].image)]
    if "mitsuba" in ref:
        tiles.append((f"reference: Mitsuba, {references['mitsuba']['spp']} spp", ref["mitsuba"][0].image))
    for key in sorted(records, key=lambda k: records[k]["renderer"] != "mitsuba"):  # Mitsuba next to the references
        if key not in keep:
            continue
        image, spp, seconds, rel, flip = keep[key]
        label = records[key]["label"].replace("`", "")
        tiles.append((f"{label}\n{spp} spp, {seconds:.2f} s, relMSE {rel:.3g}, FLIP {flip:.3f}", image))
    columns = min(5, len(tiles))
    rows = -(-len(tiles) // columns)
    scale = 2.6 / width * 100
    figure = Figure(figsize=(columns * width * scale / 100, rows * (height * scale / 100 + 0.42)), layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.subplots(rows, columns, squeeze=False)
    for ax in axes.ravel():
        ax.axis("off")
    for ax, (title, image) in zip(axes.ravel(), tiles, strict=False):
        ax.imshow(tonemap(image), interpolation="nearest")
        ax.set_title(title, fontsize=6.5)
    figure.suptitle(f"{name}: every strategy at an equal time of {budget} s (seed 1), next to the references",
                    fontsize=9)  # fmt: skip
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=100)


def equal_time(args):
    integrators, default_integrator = _integrator_choices()
    if args.integrators:
        if integrators == (None,):
            raise SystemExit("--integrators: this render() has no integrator parameter")
        integrators = tuple(args.integrators)
        default_integrator = default_integrator if default_integrator in integrators else integrators[0]
    if args.samplers and args.baseline not in args.samplers:  # the closing table needs it
        args.samplers = [*args.samplers, args.baseline]
    mitsuba_ok, mitsuba_reason = _mitsuba_status(args.no_mitsuba)
    print(f"integrators: {integrators} (default {default_integrator}); samplers: {args.samplers or SAMPLERS}; "
          f"Mitsuba: {mitsuba_reason if mitsuba_ok else 'skipped: ' + mitsuba_reason}", file=sys.stderr)  # fmt: skip
    if not mitsuba_ok:
        mitsuba_reason = f"skipped: {mitsuba_reason}"
    if args.threads > numba.config.NUMBA_NUM_THREADS:
        raise SystemExit(f"--threads {args.threads} > numba's {numba.config.NUMBA_NUM_THREADS}")
    images_dir = Path(args.images_dir)
    header = dict(
        command=" ".join(["python", "benchmarks/bench_render.py", *sys.argv[1:]]),
        date=datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        machine=f"{os.cpu_count()} CPUs, {cpu_name()}, Python {platform.python_version()}, "
        f"numba {numba.__version__} ({args.threads} threads)",
        integrators=[i or "bsdf (render() has no integrator parameter)" for i in integrators],
        default_integrator=default_integrator,
        samplers=list(args.samplers or SAMPLERS),
        baseline=args.baseline,
        relmse="mean over pixels and channels of (x - ref)^2 / (ref^2 + 0.01), minus the reference's own (from its halves)",
        flip="LDR FLIP (flip-evaluator) of tonemap(image) (exposure 1, clip, sRGB, 8 bits) against tonemap(reference)",
        timing="ours: RenderResult.seconds (after compilation); Mitsuba: wall time of mi.render + conversion to numpy, "
        "after a warm-up render of the same pass size (JIT compilation excluded)",
        budgets=args.budgets,
        equal_spp=args.equal_spp,
        seeds=args.seeds,
        git=subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True, cwd=ROOT).stdout.strip(),
    )  # fmt: skip
    print(f"{header['machine']}; load average {os.getloadavg()[0]:.2f}\n")
    results = dict(header, scenes=[])
    out = Path(args.json) if args.json else ROOT / "benchmarks" / "results" / (
        f"{datetime.date.today().isoformat()}-bench_render-equal_time.json")  # fmt: skip
    for name in args.scenes:
        results["scenes"].append(
            _equal_time_scene(name, args, integrators, default_integrator, mitsuba_ok, mitsuba_reason, images_dir)
        )
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(results, indent=1))  # after every scene: a partial run leaves its numbers
    _equal_time_answer(results)
    _equal_time_targets(results)
    out.write_text(json.dumps(results, indent=1))
    print(f"\nwrote {out}", file=sys.stderr)


def _equal_time_answer(results):
    """Each symmetric sampler against the baseline (i.i.d. cosine sampling), with the default (NEE) integrator."""
    integrator = results["default_integrator"] or "bsdf"
    baseline = results.get("baseline", "cosine")
    base_key = f"{baseline}/{integrator}"
    budgets = [str(b) for b in results["budgets"]]
    lines = [
        f"Symmetric samplers against `{baseline}`, integrator `{integrator}`: relMSE ratio at {results['equal_spp']} "
        "spp (below 1: the symmetric sampler is better; ± from the seed-to-seed spread; paired: the mean over seeds "
        "of the per-seed ratio ± its standard error) and efficiency ratio at each budget (above 1: better at equal "
        "time):",
        "",
        f"| scene | sampler | relMSE / {baseline}'s, equal spp | paired | "
        + " | ".join(f"efficiency × {baseline}'s, {b} s" for b in budgets) + " |",
        "|---|---|---:|---:|" + "---:|" * len(budgets),
    ]  # fmt: skip
    for scene in results["scenes"]:
        records = scene["strategies"]
        if base_key not in records:
            continue
        base = records[base_key]
        for key, record in records.items():
            sampler = key.split("/")[0]
            if not key.endswith(f"/{integrator}") or not sampler.startswith("symmetric") or key == base_key:
                continue
            a, b = record["equal_spp_summary"], base["equal_spp_summary"]
            ratio = a["rel_mse"] / b["rel_mse"]
            error = ""
            if a["rel_mse_se"] is not None and b["rel_mse_se"] is not None:
                error = f" ± {ratio * math.hypot(a['rel_mse_se'] / a['rel_mse'], b['rel_mse_se'] / b['rel_mse']):.2f}"
            per_seed = [
                r["rel_mse"] / q["rel_mse"] for r, q in zip(record["equal_spp"], base["equal_spp"], strict=False)
            ]
            paired = f"{statistics.fmean(per_seed):.3f}"
            if len(per_seed) > 1:
                paired += f" ± {statistics.stdev(per_seed) / math.sqrt(len(per_seed)):.3f}"
            efficiency = [record["budgets"][x]["efficiency"] / base["budgets"][x]["efficiency"] for x in budgets]
            lines.append(f"| {scene['scene']} | `{sampler}` | {ratio:.2f}{error} | {paired} | "
                         + " | ".join(f"{e:.2f}" for e in efficiency) + " |")  # fmt: skip
    text = "\n".join(lines)
    results["answer_markdown"] = text
    print("\n" + text)


def _equal_time_targets(results):
    """The issue's targets on cornell: best efficiency >= 2x Mitsuba path; our paths/s with NEE >= 2.5x Mitsuba's."""
    lines = []
    for scene in results["scenes"]:
        records = scene["strategies"]
        mitsuba = records.get("mitsuba/path")
        if mitsuba is None:
            lines.append(f"{scene['scene']}: no Mitsuba run, targets not evaluated")
            continue
        last = str(results["budgets"][-1])
        ours = {k: r for k, r in records.items() if r["renderer"] == "symsphere"}
        best_key = max(ours, key=lambda k: ours[k]["budgets"][last]["efficiency"])
        eff_ratio = ours[best_key]["budgets"][last]["efficiency"] / mitsuba["budgets"][last]["efficiency"]
        nee = {k: r for k, r in ours.items() if k.endswith("/path")}
        speed = {k: r["paths_per_second"] / mitsuba["paths_per_second"] for k, r in nee.items()}
        scene["targets"] = dict(best_strategy=best_key, efficiency_ratio=eff_ratio, efficiency_target=2.0,
                                paths_per_second_ratio_nee=speed, paths_per_second_target=2.5)  # fmt: skip
        lines.append(
            f"{scene['scene']}: best strategy at {last} s {best_key}: efficiency {eff_ratio:.2f}x Mitsuba path "
            f"(target >= 2: {'met' if eff_ratio >= 2 else 'NOT met'}); paths/s with NEE vs Mitsuba: "
            + (", ".join(f"{k.split('/')[0]} {v:.2f}x" for k, v in speed.items()) +
               f" (target >= 2.5: {'met' if speed and min(speed.values()) >= 2.5 else 'NOT met by all'})"
               if speed else "no NEE integrator in this render() (target not evaluable)")
        )  # fmt: skip
    results["targets"] = lines
    print("\n" + "\n".join(f"- {line}" for line in lines))


def paths_vs_mitsuba(args):
    """Paths/s of ours (each sampler given, both integrators) and of Mitsuba 3 ``path``, interleaved: medians."""
    ok, reason = _mitsuba_status(args.no_mitsuba)
    integrators, _ = _integrator_choices()
    out = dict(command="python benchmarks/bench_render.py " + " ".join(sys.argv[1:]),
               date=datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
               machine=f"{os.cpu_count()} CPUs, {cpu_name()}, numba {numba.__version__} ({args.threads} threads)",
               spp=args.spp, rounds=args.rounds, scenes=[])  # fmt: skip
    for name in args.scenes:
        scene = _scene_for(name)
        strategies = [
            _Ours(scene, s, i, args.width, args.height, args.threads) for s in args.samplers for i in integrators
        ]
        if ok:
            strategies.append(_Mitsuba(scene, args.width, args.height, args.threads))
        for strategy in strategies:
            strategy.warm_up(args.spp)
        rates = {strategy.key: [] for strategy in strategies}
        before, start = cpu_snapshot(), time.perf_counter()
        load = os.getloadavg()[0]
        for round_ in range(args.rounds):
            for strategy in _rotated(strategies, round_):
                seconds = strategy.render(args.spp, 1000 + round_)[1]
                rates[strategy.key].append(args.width * args.height * args.spp / seconds)
        others = others_cpu(before, cpu_snapshot(), time.perf_counter() - start)
        medians = {k: statistics.median(v) for k, v in rates.items()}
        mitsuba = medians.get("mitsuba/path")
        share = "?" if others is None else f"{100 * others['share_of_all_cpus']:.0f}%"
        print(f"\n{name} {args.width}x{args.height}, {args.spp} spp, {args.rounds} interleaved rounds; load average "
              f"{load:.2f} before; other processes used {share} of the CPUs")  # fmt: skip
        print("| strategy | Mpaths/s (median) | min–max | × Mitsuba |\n|---|---:|---:|---:|")
        for key, values in rates.items():
            ratio = f"{medians[key] / mitsuba:.2f}" if mitsuba else "–"
            print(f"| {key} | {medians[key] / 1e6:.2f} | {min(values) / 1e6:.2f}–{max(values) / 1e6:.2f} | {ratio} |")
        out["scenes"].append(dict(scene=name, width=args.width, height=args.height, paths_per_second=rates,
                                  medians=medians, others_cpu=others, load_before=load,
                                  mitsuba=None if ok else reason))  # fmt: skip
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    verbs = parser.add_subparsers(dest="verb", required=True)
    p = verbs.add_parser("speed")
    p.add_argument("--width", type=int, default=256)
    p.add_argument("--height", type=int, default=192)
    p.add_argument("--spp", type=int, default=48)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument(
        "--integrator",
        choices=("path", "bsdf"),
        default="bsdf",
        help="bsdf (default) reproduces the tables of docs/results/render-convergence.md made before NEE",
    )
    p.set_defaults(run=speed)
    c = verbs.add_parser("convergence")
    c.add_argument("--width", type=int, default=128)
    c.add_argument("--height", type=int, default=96)
    c.add_argument("--reference-spp", type=int, default=2**14)
    c.add_argument("--levels", type=int, default=6, help="spp = 24 * 2^k, k < levels")
    c.add_argument("--replicates", type=int, default=3)
    c.add_argument("--image-spp", type=int, default=96, help="spp of the side-by-side images")
    c.add_argument(
        "--integrator",
        choices=("path", "bsdf"),
        default="bsdf",
        help="bsdf (default) reproduces the tables and images of docs/results/render-convergence.md made before NEE",
    )
    c.add_argument(
        "--replot", action="store_true", help="redraw the figure and tables from docs/images/render_convergence.json"
    )
    c.set_defaults(run=convergence)
    v = verbs.add_parser("validation")
    v.add_argument("--integrator", choices=("path", "bsdf"), default="bsdf")
    v.set_defaults(run=validation)
    e = verbs.add_parser("equal-time")
    e.add_argument("--scenes", nargs="+", default=["cornell", "gap"], help="built-in scenes or 'gap'")
    e.add_argument("--width", type=int, default=256)
    e.add_argument("--height", type=int, default=192)
    e.add_argument("--samplers", nargs="+", choices=SAMPLERS, help="default: all of SAMPLERS")
    e.add_argument("--integrators", nargs="+", choices=("path", "bsdf"), help="default: both")
    e.add_argument(
        "--baseline",
        choices=SAMPLERS,
        default="cosine",
        help="the closing table's reference sampler (default: %(default)s)",
    )
    e.add_argument("--budgets", nargs="+", type=float, default=[1.0, 2.0], help="seconds per render")
    e.add_argument("--equal-spp", type=int, default=24)
    e.add_argument("--seeds", type=int, default=3)
    e.add_argument("--reference-spp", type=int, default=1024, help="ours: cosine, the default integrator")
    e.add_argument("--mitsuba-reference-spp", type=int, default=512)
    e.add_argument("--threads", type=int, default=numba.config.NUMBA_NUM_THREADS, help="ours and Mitsuba's")
    e.add_argument("--no-mitsuba", action="store_true")
    e.add_argument("--no-images", action="store_true")
    e.add_argument("--images-dir", default=str(ROOT / "docs" / "images"))
    e.add_argument("--json", help="default: benchmarks/results/<date>-bench_render-equal_time.json")
    e.set_defaults(run=equal_time)
    q = verbs.add_parser("paths-vs-mitsuba", help="paths/s of ours and of Mitsuba 3 path, interleaved rounds")
    q.add_argument("--scenes", nargs="+", default=["cornell", "gap"])
    q.add_argument("--samplers", nargs="+", choices=SAMPLERS, default=["cosine"])
    q.add_argument("--width", type=int, default=256)
    q.add_argument("--height", type=int, default=192)
    q.add_argument("--spp", type=int, default=24)
    q.add_argument("--rounds", type=int, default=7)
    q.add_argument("--threads", type=int, default=numba.config.NUMBA_NUM_THREADS)
    q.add_argument("--no-mitsuba", action="store_true")
    q.add_argument("--json", help="write every measurement here")
    q.set_defaults(run=paths_vs_mitsuba)
    args = parser.parse_args()
    if getattr(args, "integrator", None):
        _INTEGRATOR["integrator"] = args.integrator
    args.run(args)


if __name__ == "__main__":
    main()
