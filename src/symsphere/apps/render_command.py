"""``symsphere render``: the verb's parser and handlers, for the numba path tracer and Mitsuba 3 scene files.

``symsphere render --help`` lists the options of the built-in, ``.toml`` and ``.json`` scenes;
``symsphere render --scene FILE.xml --help`` those of a Mitsuba 3 scene file (rendered with
``symsphere_path``, see :mod:`symsphere.apps.mitsuba_render`).  Every option is either honoured or refused
in one line for each kind of scene; choices are listed in a stable order.  The direction sampling is
``--strategy`` x ``--points`` x ``--method``, the words of both renderers (:mod:`symsphere._strategies`);
the earlier ``--sampler`` still works for one release, with a line on stderr naming the new options.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import cast

import numpy as np

from .._strategies import SAMPLER_SPELLINGS, SAMPLING_STRATEGIES, from_sampler, words
from .._validation import (
    MAX_PATHS,
    check_count,
    check_output_path,
    check_seed,
    check_size,
    file_kind,
    memory_pixel_limit,
)
from ..warps import METHODS
from ._process import (
    FASTEST_PATHS_PER_THREAD,
    UsageError,
    add_allow_long,
    add_run_options,
    check_duration,
    check_pending,
    close_client,
    cluster_client,
    distributed_module,
)

__all__ = ["add_render_parser", "is_mitsuba_scene"]

BYTES_PER_PIXEL = 160  # as symsphere.render.renderer.BYTES_PER_PIXEL (not imported: ~0.3 s)

_NUMBA_SUFFIXES = (".png", ".pfm", ".npy")
_MITSUBA_SUFFIXES = (".png", ".pfm", ".npy", ".exr")


def is_mitsuba_scene(argv: Sequence[str]) -> bool:
    """Whether *argv* is a ``render`` of a Mitsuba scene file (``--scene X.xml``): its help and choices differ."""
    words = list(argv)
    if "render" not in words:
        return False
    for index, word in enumerate(words):
        value = None
        if word == "--scene" and index + 1 < len(words):
            value = words[index + 1]
        elif word.startswith("--scene="):
            value = word.split("=", 1)[1]
        if value is not None and value.lower().endswith(".xml"):
            return True
    return False


def add_render_parser(verbs: argparse._SubParsersAction[argparse.ArgumentParser], *, mitsuba: bool = False) -> None:
    """Add the ``render`` verb; with *mitsuba*, its options for a Mitsuba scene file (``--scene X.xml``)."""
    if mitsuba:
        _add_mitsuba_parser(verbs)
        return
    render = verbs.add_parser(
        "render",
        help="path-trace a scene (built-in, .toml/.json, or Mitsuba 3 .xml) with a chosen direction sampler",
        description=(
            "Path-trace a built-in scene (cornell: smallpt's Cornell box; furnace; translucent) or a "
            ".toml/.json scene file, sampling directions at diffuse vertices by STRATEGY and its POINTS, on all cores.  "
            "Writes the tone-mapped sRGB image to --out (.png) and the linear HDR mean radiance next to "
            "it (.pfm and .npy, same stem).  Every file appears only when complete."
        ),
    )
    render.add_argument("--scene", default="cornell", help="cornell, furnace, translucent, a .toml/.json file, or a "
                        "Mitsuba 3 .xml file ('symsphere render --scene FILE.xml --help' lists its options); "
                        "furnace prints its mean radiance against the exact value (default: %(default)s)")  # fmt: skip
    render.add_argument("--width", type=int, default=None, help="default: 256")
    render.add_argument("--height", type=int, default=None, help="default: 192")
    render.add_argument(
        "--spp", type=int, default=None,
        help="samples (camera paths) per pixel; the symmetric strategy forms whole orbits for multiples of 24 "
        "(48 with translucent materials) (default: 96)",
    )  # fmt: skip
    _add_sampling_options(render, "render")
    render.add_argument(
        "--integrator", choices=("path", "bsdf"), default="path",
        help="path: next-event estimation and BSDF sampling combined by multiple importance sampling; "
        "bsdf: BSDF sampling only, smallpt's estimator (default: %(default)s)",
    )  # fmt: skip
    render.add_argument("--filter", choices=("box", "tent"), default=None, help="pixel filter (default: box)")
    render.add_argument("--seed", type=int, default=None, help="non-negative integer; default: fresh entropy")
    render.add_argument(
        "--exposure", type=float, default=None,
        help="PNG only: scale before tone mapping (default: 1; furnace: 0.5 / exact radiance, a mid-grey)",
    )  # fmt: skip
    render.add_argument("--threads", type=int, default=None, help="numba threads (default: all cores)")
    render.add_argument("--out", default="render.png", metavar="FILE.png",
                        help="writes FILE.png, FILE.pfm and FILE.npy; may end in .pfm or .npy (default: %(default)s)")  # fmt: skip
    render.add_argument("--variant", default=None, help=argparse.SUPPRESS)  # Mitsuba scene files only: refused
    render.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    add_run_options(render, _run_render)


def _add_mitsuba_parser(verbs: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    from .mitsuba_render import DEFAULT_VARIANT

    render = verbs.add_parser(
        "render",
        help="path-trace a scene with a chosen direction sampler",
        description=(
            "Render a Mitsuba 3 scene file with the integrator symsphere_path (needs the extra 'mitsuba'): "
            "the file's sensor, film, emitters and BSDFs, its integrator's max_depth, rr_depth and "
            "hide_emitters, and the directions of STRATEGY at diffuse vertices.  Writes the tone-mapped sRGB image "
            "to --out (.png) and the linear HDR mean radiance next to it (.pfm, .npy and .exr, same stem).  "
            "Every file appears only when complete; Ctrl-C stops the render within a second."
        ),
    )
    render.add_argument("--scene", required=True, metavar="FILE.xml", help="the Mitsuba 3 scene file")
    render.add_argument(
        "--width", type=int, default=None,
        help="image width (default: the file's; given alone, the height keeps the file's aspect ratio; "
        "the file must declare <default name=\"width\">)",
    )  # fmt: skip
    render.add_argument("--height", type=int, default=None, help="image height (default: the file's; as --width)")
    render.add_argument(
        "--spp", type=int, default=None,
        help="samples per pixel, rendered in passes of about 4 million paths (default: the file's sampler's)",
    )  # fmt: skip
    _add_sampling_options(render, "plugin")
    render.add_argument(
        "--variant", default=DEFAULT_VARIANT,
        help="Mitsuba variant: an llvm_ad_* variant (rgb, mono, spectral), cuda_ad_* where a CUDA device "
        "is present (default: %(default)s)",
    )  # fmt: skip
    render.add_argument("--seed", type=int, default=None, help="non-negative integer; default: fresh entropy")
    render.add_argument("--exposure", type=float, default=None, help="PNG only: scale before tone mapping (default: 1)")
    render.add_argument("--threads", type=int, default=None, help="Dr.Jit's threads (default: all cores)")
    render.add_argument("--out", default="render.png", metavar="FILE.png",
                        help="writes FILE.png, FILE.pfm, FILE.npy and FILE.exr; may end in any of those "
                        "(default: %(default)s)")  # fmt: skip
    render.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    add_allow_long(render)
    # Options of the numba renderer that a Mitsuba scene cannot honour: accepted here so that each is
    # refused in one line with the reason (not argparse's "unrecognized arguments"), and not listed.
    render.add_argument("--integrator", default=None, help=argparse.SUPPRESS)
    render.add_argument("--filter", default=None, help=argparse.SUPPRESS)
    render.add_argument("--workers", default=None, help=argparse.SUPPRESS)
    render.add_argument("--scheduler", default=None, help=argparse.SUPPRESS)
    render.add_argument("--timeout", default=None, help=argparse.SUPPRESS)
    render.set_defaults(handler=_run_render)


# --strategy, --points, --sampler (deprecated), --method: the help of each, for the numba renderer and the plugin
_SAMPLING_HELP = {
    "render": (
        "direction sampling at diffuse vertices: the paper's scheme inside a pixel (symmetric: orbits of 24 on T0; "
        "symmetric_cosine: 8 images of a cosine-weighted base point), i.i.d. orbit members (orbit), or the classic "
        "uniform and cosine references (default: symmetric)",
        "the strategy's base points: sobol (Owen-scrambled Sobol', the default of the symmetric strategies), random "
        "(the default, and the only choice, of the others), sobol_interlaced2 or sobol_interlaced3 (higher-order "
        "nets, symmetric strategies)",
        "map onto the triangle for the strategies symmetric and orbit (default: equal_area)",
    ),
    "plugin": (
        "direction sampling at Lambertian vertices, symsphere_path's strategy; bsdf is Mitsuba's own sampling "
        "(default: symmetric)",
        "the strategy's base points, symsphere_path's points: sobol (the default of the symmetric strategies) or "
        "random (the default of the others; bsdf takes the file's sampler's points)",
        "map onto the triangle for the strategy symmetric (default: equal_area)",
    ),
}


def _add_sampling_options(render: argparse.ArgumentParser, program: str) -> None:
    """The options of the direction sampling, in the words of :mod:`symsphere._strategies`."""
    if program == "render":
        old = tuple(SAMPLER_SPELLINGS)
    else:
        from .mitsuba_render import SAMPLER_STRATEGIES  # (the registry's words: no Mitsuba import)

        old = tuple(SAMPLER_STRATEGIES)
    strategy, points, method = _SAMPLING_HELP[program]
    render.add_argument("--strategy", choices=words(program), default=None, help=strategy)
    render.add_argument("--points", choices=_points(program), default=None, help=points)
    render.add_argument("--method", choices=METHODS, default=None, help=method)
    deprecated = "deprecated (one release): the earlier one-word spelling of --strategy and --points"
    render.add_argument("--sampler", choices=old, default=None, help=deprecated)


def _points(program: str) -> tuple[str, ...]:
    """The base points some strategy of *program* takes, sorted."""
    records = SAMPLING_STRATEGIES.values()
    return tuple(sorted({p for s in records for p in (s.render_points if program == "render" else s.plugin_points)}))


def _sampling(args: argparse.Namespace, program: str) -> tuple[str, str, str | None]:
    """(strategy, points, method) of the command line: the words, or the deprecated ``--sampler`` (with a
    line on stderr naming the words); a combination one renderer does not take is refused naming options."""
    strategy, points, method = args.strategy, args.points, args.method
    if args.sampler is not None:
        if strategy is not None or points is not None:
            raise UsageError("--sampler is the deprecated spelling of --strategy and --points; give one or the other")
        if program == "render":
            strategy, points, method, _ = from_sampler(args.sampler, method)
        else:
            from .mitsuba_render import SAMPLER_STRATEGIES

            strategy, points = SAMPLER_STRATEGIES[args.sampler]
        new = f"--strategy {strategy} --points {points}" + (
            f" --method {method}" if method is not None and args.method is None else ""
        )
        print(f"symsphere render: --sampler is deprecated; use {new}", file=sys.stderr)
    record = SAMPLING_STRATEGIES[strategy or "symmetric"]
    allowed = record.render_points if program == "render" else record.plugin_points
    if points is None:  # the renderer's default where this one takes it: Sobol' for the symmetric strategies
        points = (
            record.render_points[0] if record.render_points[:1] and record.render_points[0] in allowed else allowed[0]
        )
    if points not in allowed:
        raise UsageError(
            f"--points {points} does not apply to --strategy {record.name}; use one of {', '.join(allowed)}"
        )
    if program == "render" and args.method is not None and not record.takes_method:
        takers = " and ".join(name for name in words("render") if SAMPLING_STRATEGIES[name].takes_method)
        raise UsageError(f"--method applies only to --strategy {takers}; drop it for --strategy {record.name}")
    return record.name, points, method


def _run_render(args: argparse.Namespace) -> int:
    if Path(args.scene).suffix.lower() == ".xml":  # a Mitsuba 3 scene file: rendered with symsphere_path
        return _run_mitsuba_render(args)
    from ..render import render, write_outputs  # function-level: ~0.3 s, only for this verb

    if args.variant is not None:
        raise UsageError("--variant applies to Mitsuba 3 scene files (--scene FILE.xml) only; drop it")
    out = _check_out(args.out, _NUMBA_SUFFIXES)
    outputs = [out.with_suffix(s) for s in _NUMBA_SUFFIXES]  # what write_outputs writes
    for path in outputs:  # before the render, not after minutes of work; errors name the path (OSError)
        check_output_path(path, "--out")
    if args.seed is not None:
        check_seed(args.seed, "--seed")
    furnace_exact = _furnace_radiance() if args.scene == "furnace" else None
    args.exposure = _exposure(args.exposure, furnace_exact)
    args.width = 256 if args.width is None else args.width
    args.height = 192 if args.height is None else args.height
    args.spp = 96 if args.spp is None else args.spp
    args.filter = "box" if args.filter is None else args.filter
    scene_file = Path(args.scene)
    if scene_file.suffix.lower() in (".toml", ".json"):
        if not scene_file.exists():
            raise UsageError(f"--scene: file {args.scene!r} does not exist")
        if not scene_file.is_file():  # a FIFO would block the reader, /dev/zero never ends
            raise UsageError(f"--scene: {args.scene!r} is {file_kind(os.stat(scene_file).st_mode)}, not a regular file")
    for name in ("width", "height", "spp", "threads"):  # render() checks them too, naming 'spp' not '--spp'
        if getattr(args, name) is not None:
            check_count(getattr(args, name), f"--{name}")
    pixels = args.width * args.height  # before any allocation; render() checks the same, without the '--'
    limit = memory_pixel_limit(BYTES_PER_PIXEL)
    check_size(pixels, "--width * --height", limit, f"({args.width} x {args.height} pixels){_on_this_machine(limit)}")
    check_size(args.spp, "--spp", MAX_PATHS // pixels, f"for {args.width} x {args.height} pixels (int64 path indices)")
    if args.scheduler is None:  # on a remote cluster the number of threads is not known here
        threads = (args.threads or os.cpu_count() or 1) * (args.workers or 1)
        check_duration(
            pixels * args.spp / (FASTEST_PATHS_PER_THREAD * threads),
            f"{pixels * args.spp} paths (--width x --height x --spp on {threads} threads)",
            args,
        )
    strategy, points, method = _sampling(args, "render")
    options = dict(
        width=args.width,
        height=args.height,
        spp=args.spp,
        strategy=strategy,
        points=points,
        integrator=args.integrator,
        method=method,
        pixel_filter=args.filter,
        seed=args.seed,
        progress=not args.no_progress,
    )
    client = cluster_client(args)
    try:
        if client is None:
            result = render(args.scene, threads=args.threads, **options)
        else:
            result = distributed_module().render(args.scene, client=client, **options)
    finally:
        close_client(client)
    check_pending(args)  # an interrupt lost while the kernels compiled: nothing is written
    args.outputs.watch(outputs)
    paths = write_outputs(result, out, exposure=args.exposure)  # all three files or none; errors name the file
    args.outputs.done = True
    method = f", method {result.method}" if result.method else ""
    if client is None:
        where = f"on {result.threads} threads (+{result.startup_seconds:.2f} s compile/load)"
    else:
        where = f"in all, on a Dask cluster of {result.threads} workers (wall time, compilation included)"
    print(
        f"rendered {result.scene} {result.width}x{result.height} at {result.spp} spp, {result.integrator} integrator, "
        f"strategy {result.strategy}, points {result.points}{method}, "
        f"seed {result.seed}: {result.paths} paths in {result.seconds:.2f} s = "
        f"{result.paths_per_second / 1e6:.2f} Mpaths/s {where}; wrote {', '.join(str(p) for p in paths)}"
    )
    if furnace_exact is not None:
        mean = float(result.image.mean())
        spread = float(result.image.mean(axis=2).std(ddof=1) / math.sqrt(result.width * result.height))
        print(
            f"furnace: mean radiance {mean:.6g} ± {spread:.2g} (standard error over pixels), exact {furnace_exact:g} "
            f"= emission / (1 - albedo); relative error {mean / furnace_exact - 1:+.2e}; PNG at exposure "
            f"{args.exposure:g} (exact = mid-grey)"
        )
    return 0


def _run_mitsuba_render(args: argparse.Namespace) -> int:
    from ..render import save_image_set
    from .mitsuba_render import render_scene_file  # function-level: imports Mitsuba

    for option, value in (("--integrator", args.integrator), ("--filter", args.filter)):
        if value is not None and not (option == "--integrator" and value == "path"):
            reason = (
                "the path tracer of symsphere_path (NEE and MIS) is the only one" if option == "--integrator"
                else "the pixel filter is the file's <rfilter> (edit the file to change it)"
            )  # fmt: skip
            raise UsageError(f"{option} does not apply to Mitsuba scene files: {reason}; drop {option}")
    for option in ("--workers", "--scheduler", "--timeout"):
        if getattr(args, option[2:]) is not None:
            raise UsageError(
                f"{option} does not apply to Mitsuba scene files: they render in this process, on all cores "
                "(set --threads to use fewer); drop it"
            )
    out = _check_out(args.out, _MITSUBA_SUFFIXES)
    outputs = [out.with_suffix(s) for s in _MITSUBA_SUFFIXES]
    for path in outputs:  # before the render; errors name the path (OSError)
        check_output_path(path, "--out")
    args.exposure = _exposure(args.exposure, None)
    seed = check_seed(args.seed, "--seed") if args.seed is not None else None
    if seed is None:
        seed = int(cast(int, np.random.SeedSequence().entropy) % 2**32)
    elif seed >= 2**32:  # Dr.Jit's samplers take 32-bit seeds
        raise UsageError(f"--seed must be below 2**32 for Mitsuba scene files, got {seed}")

    def long_work(seconds: float, what: str) -> None:
        check_duration(seconds, what, args)

    def say(line: str) -> None:
        print(f"symsphere render: {line}", file=sys.stderr)

    strategy, points, method = _sampling(args, "plugin")
    r = render_scene_file(
        args.scene, width=args.width, height=args.height, spp=args.spp, strategy=strategy, points=points, method=method,
        seed=seed, variant=args.variant, threads=args.threads, check_duration=long_work,
        progress=not args.no_progress, between_passes=lambda: check_pending(args), report=say,
    )  # fmt: skip
    check_pending(args)
    args.outputs.watch(outputs)
    paths = save_image_set(outputs, r["image"], args.exposure)  # all four or none; errors name the file
    args.outputs.done = True
    print(
        f"rendered {args.scene} {r['width']}x{r['height']} at {r['spp']} spp with Mitsuba 3 ({r['variant']}, "
        f"{r['threads']} threads), symsphere_path strategy {r['strategy']}, points {r['points']}, seed {seed}: "
        f"{r['paths']} paths in {r['passes']} pass{'es' if r['passes'] > 1 else ''}, {r['seconds']:.2f} s = "
        f"{r['paths'] / r['seconds'] / 1e6:.2f} Mpaths/s (JIT compile included); "
        f"wrote {', '.join(str(p) for p in paths)}"
    )
    return 0


def _check_out(out: str, suffixes: tuple[str, ...]) -> Path:
    path = Path(out)
    if path.suffix.lower() not in suffixes:
        extra = "; .exr is written for Mitsuba 3 scene files" if ".exr" not in suffixes else ""
        raise UsageError(f"--out must end in {', '.join(suffixes[:-1])} or {suffixes[-1]}, got {out!r}{extra}")
    return path


def _exposure(exposure: float | None, furnace_exact: float | None) -> float:
    if exposure is None:  # the furnace's uniform radiance 2 would clip to pure white
        exposure = 1.0 if furnace_exact is None else 0.5 / furnace_exact
    if not (math.isfinite(exposure) and exposure > 0):  # checked by save_png too, but after the render
        raise UsageError(f"--exposure must be a positive finite number, got {exposure}")
    return exposure


def _on_this_machine(limit: int) -> str:
    from .._validation import MAX_PIXELS

    return "" if limit == MAX_PIXELS else f" on this machine's memory (~{BYTES_PER_PIXEL} bytes a pixel)"


def _furnace_radiance() -> float:
    """The exact radiance of the built-in furnace scene: emission / (1 - albedo), from its defaults."""
    import inspect

    from ..render import furnace

    defaults = inspect.signature(furnace).parameters
    return float(defaults["emission"].default) / (1 - float(defaults["albedo"].default))
