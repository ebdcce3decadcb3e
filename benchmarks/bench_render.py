"""Renderer benchmarks: paths per second on smallpt's Cornell box, cache start-up, and convergence.

Usage (from the repository root, package installed)::

    python benchmarks/bench_render.py speed                    # paths/s per sampler, 256x192, start-up time
    python benchmarks/bench_render.py speed --spp 96 --repeats 5
    python benchmarks/bench_render.py convergence              # RMSE vs spp, efficiency, images -> docs/
    python benchmarks/bench_render.py validation               # furnace and z-test tables (as the tests)

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
    docs/rendering.md.
"""

from __future__ import annotations

import argparse
import json
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

from symsphere.render import SAMPLERS, render, save_png

ROOT = Path(__file__).resolve().parent.parent


def _timed_rounds(width, height, spp, repeats, threads):
    """Median render seconds per sampler, all samplers taking turns in every round."""
    seconds = {s: [] for s in SAMPLERS}
    for round_ in range(repeats):
        for sampler in SAMPLERS:
            result = render("cornell", width=width, height=height, spp=spp, sampler=sampler, seed=round_, threads=threads)
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
    """The numbers behind tests/test_render_stats.py, as Markdown tables (same scenes, sizes and seeds)."""
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
                print(f"| `{sampler}` | {kind} | {rho} | {exact:.4f} | {mean:.4f} ± {se:.4f} | {(mean - exact) / se:+.2f} |")
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


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    verbs = parser.add_subparsers(dest="verb", required=True)
    p = verbs.add_parser("speed")
    p.add_argument("--width", type=int, default=256)
    p.add_argument("--height", type=int, default=192)
    p.add_argument("--spp", type=int, default=48)
    p.add_argument("--repeats", type=int, default=3)
    p.set_defaults(run=speed)
    c = verbs.add_parser("convergence")
    c.add_argument("--width", type=int, default=128)
    c.add_argument("--height", type=int, default=96)
    c.add_argument("--reference-spp", type=int, default=2**14)
    c.add_argument("--levels", type=int, default=6, help="spp = 24 * 2^k, k < levels")
    c.add_argument("--replicates", type=int, default=3)
    c.add_argument("--image-spp", type=int, default=96, help="spp of the side-by-side images")
    c.add_argument(
        "--replot", action="store_true", help="redraw the figure and tables from docs/images/render_convergence.json"
    )
    c.set_defaults(run=convergence)
    v = verbs.add_parser("validation")
    v.set_defaults(run=validation)
    args = parser.parse_args()
    args.run(args)


if __name__ == "__main__":
    main()
