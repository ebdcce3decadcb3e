"""``symsphere render --scene FILE.xml``: a Mitsuba 3 scene file rendered with ``symsphere_path``.

The scene's own integrator sets ``max_depth``, ``rr_depth`` and ``hide_emitters`` (Mitsuba's ``path``
defaults where it is not a path tracer); the direction sampling at Lambertian vertices comes from
``--strategy`` and ``--points`` (the words of :mod:`symsphere._strategies`; :data:`SAMPLER_STRATEGIES`
maps the deprecated ``--sampler`` onto them).  The image has the file's resolution and the file's sample
count unless ``--width``, ``--height`` or ``--spp`` ask otherwise; width and height reach the file as its
parameters ``width`` and ``height`` (``<default name="width" .../>``, as the shipped scenes declare them):
a file whose film has a fixed size refuses them.  Given only one of the two, the other keeps the file's
aspect ratio.

Before Mitsuba sees the file it is read as XML here: anything but a regular file, and elements nested
deeper than :data:`MAX_NESTING` (or BSDFs nested deeper than :data:`MAX_BSDF_NESTING`: Mitsuba's loader
takes time and memory exponential in nested ``twosided`` BSDFs, and overflows its stack on deep nests),
are refused in one line naming the file.  A scene without a sensor, with an empty film, a film larger
than memory allows, or a non-finite parameter (an emitter's radiance of NaN or 1e39) is refused after
loading, before any rendering.

The samples are rendered in passes of about :data:`PASS_PATHS` paths (whole groups of the strategy,
each pass with its own seed, accumulated here), every Mitsuba call waited for in a second thread
(:func:`symsphere.apps._process.wait_interruptibly`): Ctrl-C or SIGTERM stops the render within a
fraction of a second, and nothing is written.  The image is the mean of the passes' developed films
(linear RGB), written as PNG, PFM, NPY and EXR, all or none.
"""

from __future__ import annotations

import functools
import re
import time
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path
from typing import Any
from xml.parsers import expat

import numpy as np

from .._signals import deferred as deferred_signals
from .._strategies import SAMPLING_STRATEGIES, words
from .._validation import MAX_PATHS, check_count, memory_pixel_limit, read_regular_file
from ..render._exr_threads import exr_threads
from ._process import wait_interruptibly

__all__ = [
    "DEFAULT_VARIANT",
    "MAX_BSDF_NESTING",
    "MAX_NESTING",
    "PASS_PATHS",
    "SAMPLER_STRATEGIES",
    "check_scene_file",
    "plan_passes",
    "render_scene_file",
    "select_variant",
]

SAMPLER_STRATEGIES = {
    "bsdf": ("bsdf", "random"),
    "cosine": ("cosine", "random"),
    "symmetric": ("symmetric", "random"),
    "symmetric_cosine": ("symmetric_cosine", "random"),
    "symmetric_cosine_sobol": ("symmetric_cosine", "sobol"),
    "symmetric_sobol": ("symmetric", "sobol"),
}
"""dict: the deprecated ``--sampler`` (one release) -> (strategy, points) of ``symsphere_path`` for a Mitsuba
scene file (sorted by name)."""

DEFAULT_VARIANT = "llvm_ad_rgb"
"""The Mitsuba variant of ``--variant``'s default: Dr.Jit's LLVM back end, RGB, on every machine."""

MAX_NESTING = 64
"""Deepest nesting of XML elements accepted in a scene file (Mitsuba's own scenes need about 8)."""

MAX_BSDF_NESTING = 8
"""Deepest nesting of ``<bsdf>`` inside ``<bsdf>`` (a blend of blends of twosided ...): Mitsuba's loader
doubles its time and memory with every nested ``twosided`` (measured: 16 levels 0.06 s, 24 levels 6.4 s)."""

PASS_PATHS = 2**22
"""Paths per pass (at least one group per pixel): about a second on two cores (docs/rendering.md)."""

BYTES_PER_PIXEL = 160
"""Memory a pixel of the film costs at most during a render: Mitsuba's block and developed image (float32,
up to 5 and 4 channels), the pass as float64 RGB, the sum, and the encoded outputs."""


def check_scene_file(path: str | Path) -> Path:
    """*path* as a Path if it is a regular file of well-formed, shallowly nested XML; else ValueError naming it.

    Read here, before Mitsuba sees it: a directory, a FIFO, a device (a link to ``/dev/zero``) or a
    missing file is named for what it is; a nest deeper than :data:`MAX_NESTING` elements or
    :data:`MAX_BSDF_NESTING` BSDFs is refused with its line.
    """
    path = Path(path)
    where = f"--scene {str(path)!r}"
    try:
        data = read_regular_file(path, where)
    except FileNotFoundError:
        raise ValueError(f"{where}: no such file") from None
    except OSError as error:
        raise ValueError(f"{where}: cannot be read ({error.strerror or error})") from None
    where = f"scene file {str(path)!r}"
    parser = expat.ParserCreate()
    depth = [0, 0]  # elements, <bsdf> elements

    def start(tag: str, attributes: dict[str, str]) -> None:
        depth[0] += 1
        depth[1] += tag == "bsdf"
        for what, level, limit in (
            ("elements", depth[0], MAX_NESTING),
            ("<bsdf> elements", depth[1], MAX_BSDF_NESTING),
        ):
            if level > limit:
                raise ValueError(
                    f"{where}: {what} are nested more than {limit} deep (line {parser.CurrentLineNumber}); at most "
                    f"{limit} levels are accepted (Mitsuba's loader needs time and memory exponential in the nesting)"
                )

    def end(tag: str) -> None:
        depth[0] -= 1
        depth[1] -= tag == "bsdf"

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(data, True)
    except expat.ExpatError as error:
        raise ValueError(
            f"{where}: not well-formed XML ({expat.errors.messages[error.code]}, line {error.lineno})"
        ) from None
    return path


def _defaults(path: Path) -> dict[str, str]:
    """The file's ``<default name=... value=...>`` parameters (already checked well-formed)."""
    root = ET.parse(path).getroot()
    return {element.get("name", ""): element.get("value", "") for element in root.iter("default")}


def _film_size(path: Path, defaults: dict[str, str]) -> tuple[int, int] | None:
    """The film's width and height as the file gives them (parameters resolved), or None if not stated."""
    for film in ET.parse(path).getroot().iter("film"):
        size = {}
        for element in film.findall("integer"):
            value = element.get("value", "")
            if value.startswith("$"):
                value = defaults.get(value[1:], "")
            if element.get("name") in ("width", "height") and value.isdigit():
                size[element.get("name")] = int(value)
        return size.get("width", 768), size.get("height", 576)  # Mitsuba's hdrfilm defaults
    return None


def select_variant(variant: str, where: str = "") -> Any:
    """Set Mitsuba's *variant* (and register ``symsphere_path`` there); return the ``mitsuba`` module.

    ValueError naming ``--variant`` (one line) for a Mitsuba that is missing, a variant it does not
    offer (the message lists those it does, sorted), or a CUDA variant on a machine without a CUDA device.
    """
    with deferred_signals():  # a signal inside nanobind's module initialisation aborts the process
        return _select_variant(variant, where)


def _select_variant(variant: str, where: str) -> Any:
    try:
        import drjit as dr
        import mitsuba as mi
    except ImportError as error:
        raise ValueError(
            f"{where}Mitsuba scene files need Mitsuba 3: pip install 'symsphere[mitsuba]' ({error})"
        ) from None
    offered = sorted(mi.variants())
    if variant not in offered:
        raise ValueError(f"--variant {variant!r} is not a variant of this Mitsuba; use one of {offered}")
    if variant.startswith("cuda_") and not dr.has_backend(dr.JitBackend.CUDA):
        llvm = [v for v in offered if v.startswith("llvm_")]
        raise ValueError(f"--variant {variant!r} needs a CUDA device and none was found; use one of {llvm}")
    if mi.variant() != variant:
        mi.set_variant(variant)
    import symsphere.mitsuba  # noqa: F401  (registers symsphere_path in every variant set from now on)

    return mi


def plan_passes(spp: int, pixels: int, group: int) -> list[int]:
    """The samples per pixel of each pass: whole groups, about :data:`PASS_PATHS` paths a pass, *spp* in all.

    An *spp* that is not a multiple of *group* is one pass (the integrator rounds it or says why not).

    Examples
    --------
    >>> from symsphere.apps.mitsuba_render import plan_passes
    >>> plan_passes(4800, 256 * 192, 24)[:2], len(plan_passes(4800, 256 * 192, 24))
    ([72, 72], 67)
    >>> plan_passes(48, 8000 * 8000, 24)
    [24, 24]
    """
    if spp % group:
        return [spp]
    per = max(group, (PASS_PATHS // (pixels * group)) * group)
    passes = [per] * (spp // per)
    if spp % per:
        passes.append(spp % per)
    return passes


def _pass_seed(seed: int, index: int) -> int:
    """The seed of pass *index*: *seed* itself for the first, then independent 32-bit streams."""
    if index == 0:
        return seed
    return int(np.random.SeedSequence([seed, index]).generate_state(1)[0])


def _last_line(error: BaseException) -> str:
    """The last line of Mitsuba's message, with the list that follows it ("Found unused parameters:",
    then one "- $spp=4" a line) joined on: the list alone named no reason."""
    lines: list[str] = []
    for line in (line.strip() for line in str(error).strip().splitlines()):
        if line.startswith("- ") and lines:
            lines[-1] += (" " if lines[-1].endswith(":") else ", ") + line[2:]
        elif line:
            lines.append(line)
    return lines[-1] if lines else type(error).__name__


def _check_finite_parameters(mi: Any, scene: Any, where: str) -> None:
    """ValueError naming the first scene parameter (an emitter's radiance, a reflectance) that is not finite."""
    parameters = mi.traverse(scene)
    for key in parameters.keys():
        try:
            values = np.asarray(parameters[key], dtype=np.float64)
        except (TypeError, ValueError, RuntimeError):
            continue  # not numbers (a bitmap's path, a nested object)
        if values.size and not np.isfinite(values).all():
            bad = values[~np.isfinite(values)].ravel()[0]
            raise ValueError(
                f"{where}: parameter {key!r} is {bad} (beyond float32's 3.4e38 or not a number); "
                "every radiance, reflectance and transform must be finite"
            )


def render_scene_file(
    path: str | Path,
    *,
    width: int | None,
    height: int | None,
    spp: int | None,
    strategy: str,
    points: str,
    method: str | None,
    seed: int,
    variant: str = DEFAULT_VARIANT,
    threads: int | None = None,
    check_duration: Callable[[float, str], None] | None = None,
    progress: bool = False,
    between_passes: Callable[[], None] | None = None,
    report: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """Render the Mitsuba scene file *path*; returns the image and what the CLI reports.

    Raises ValueError (one line, naming the file or the option) for a missing Mitsuba, a strategy and
    points that ``symsphere_path`` does not take, an unknown variant, a file that is not a regular file or nests too deep, a file Mitsuba cannot load (with
    Mitsuba's reason), a scene that cannot render (no sensor, an empty or too large film, a non-finite
    parameter), an spp the strategy cannot use, or an image with non-finite pixels.  *check_duration*
    is called with the estimated seconds before the render (at the fastest rate) and again after the
    first pass (at the measured rate); *between_passes* after every pass (the CLI raises a pending
    signal there); *report* with a line to show when the render will take more than a minute.
    """
    if strategy not in words("plugin"):
        raise ValueError(f"--strategy {strategy!r} is not available for Mitsuba scenes; use one of {words('plugin')}")
    if points not in SAMPLING_STRATEGIES[strategy].plugin_points:
        allowed = SAMPLING_STRATEGIES[strategy].plugin_points
        raise ValueError(f"--points {points!r} does not apply to --strategy {strategy} here; use one of {allowed}")
    path = check_scene_file(path)
    where = f"scene file {str(path)!r}"
    for name, value in (("--width", width), ("--height", height), ("--spp", spp), ("--threads", threads)):
        if value is not None:
            check_count(value, name)
    defaults = _defaults(path)
    params: dict[str, int] = {}
    if width is not None or height is not None:
        missing = [name for name in ("width", "height") if name not in defaults]
        if missing:
            raise ValueError(
                f'--width/--height: {where} fixes its film\'s size (no <default name="{missing[0]}">); drop '
                "--width and --height to render at the file's resolution, or declare the parameters in the file"
            )
        file_size = _film_size(path, defaults)
        if file_size is not None and (width is None or height is None):  # keep the file's aspect ratio
            fw, fh = file_size
            width = width if width is not None else max(1, round(height * fw / fh))  # type: ignore[operator]
            height = height if height is not None else max(1, round(width * fh / fw))
        params.update(width=width, height=height)  # type: ignore[arg-type]
    if spp is not None and "spp" in defaults:
        params["spp"] = spp
    mi = select_variant(variant, f"--scene {str(path)!r}: ")
    import drjit as dr

    previous = dr.thread_count()
    if threads is not None:
        dr.set_thread_count(threads)
    try:
        return _render(mi, path, params, spp, (strategy, points), method, seed, variant, check_duration, progress,
                       between_passes, report)  # fmt: skip
    finally:  # the process's Dr.Jit pool as it was
        if threads is not None:
            dr.set_thread_count(previous)


def _render(
    mi: Any,
    path: Path,
    params: dict[str, int],
    spp: int | None,
    sampling: tuple[str, str],
    method: str | None,
    seed: int,
    variant: str,
    check_duration: Callable[[float, str], None] | None,
    progress: bool,
    between_passes: Callable[[], None] | None,
    report: Callable[[str], None] | None,
) -> dict[str, Any]:
    import drjit as dr

    where = f"scene file {str(path)!r}"
    try:
        with exr_threads():  # the scene's .exr textures: Mitsuba's OpenEXR reader hangs with one thread
            scene = wait_interruptibly(lambda: mi.load_file(str(path), **params))
    except Exception as error:
        raise ValueError(f"{where}: {_last_line(error)}") from None
    if not scene.sensors():
        raise ValueError(f"{where} has no <sensor>: there is no camera to render from")
    sensor = scene.sensors()[0]
    film = sensor.film()
    w, h = (int(c) for c in film.crop_size())
    if w * h == 0:
        raise ValueError(f"{where}: its film is {w} x {h} pixels; give it a positive width and height")
    limit = memory_pixel_limit(BYTES_PER_PIXEL)
    if w * h > limit:
        raise ValueError(
            f"{where}: its film of {w} x {h} = {w * h} pixels needs more memory than this machine has "
            f"(about {BYTES_PER_PIXEL} bytes a pixel); at most {limit} pixels are supported here"
        )
    if spp is None:
        spp = int(sensor.sampler().sample_count())
    if spp > MAX_PATHS // (w * h) or w * h * spp > 2**62:
        raise ValueError(f"--spp {spp} is too large for {w} x {h} pixels: at most {MAX_PATHS // (w * h)}")
    _check_finite_parameters(mi, scene, where)
    if check_duration is not None:
        check_duration(w * h * spp / (1e7 * max(1, dr.thread_count())), f"{w * h * spp} paths ({w} x {h} x {spp} spp)")
    own = str(scene.integrator()) if scene.integrator() is not None else ""
    depth: dict[str, Any] = {}
    for key in ("max_depth", "rr_depth"):
        match = re.search(rf"{key}\s*=\s*(-?\d+)", own)
        if match:
            value = int(match.group(1))
            depth[key] = -1 if key == "max_depth" and value >= 2**32 - 1 else value
    if re.search(r"hide_emitters\s*=\s*(1|true)", own):
        depth["hide_emitters"] = True
    strategy, points = sampling
    options = {"type": "symsphere_path", "strategy": strategy, "points": points, **depth}
    if method is not None:
        options["method"] = method
    level = mi.log_level()
    mi.set_log_level(mi.LogLevel.Error)  # the plugin's refusal of a scalar variant is the one line to show
    try:
        with deferred_signals():  # Python's __init__ of the plugin runs inside Mitsuba's C++ constructor
            integrator = mi.load_dict(options)
    except Exception as error:
        raise ValueError(f"--variant {variant!r}: {_last_line(error).removeprefix('ValueError: ')}") from None
    finally:
        mi.set_log_level(level)
    group = int(getattr(integrator, "group_size", 1))
    if w * h * group > 2**32:  # one pass is at least one group a pixel, in one Dr.Jit wavefront of 32-bit indices
        raise ValueError(f"{where}: its film of {w} x {h} pixels is too large: at most {2**32 // group} pixels")
    passes = plan_passes(spp, w * h, group)
    if report is not None and w * h * spp / (1e7 * max(1, dr.thread_count())) > 60:
        report(f"{w * h * spp} paths in {len(passes)} passes; an estimate follows the first pass; Ctrl-C stops")
    total = np.zeros((h, w, 3), dtype=np.float64)
    start = time.perf_counter()
    from tqdm.auto import tqdm  # function-level: only the render verb shows this bar

    with tqdm(total=spp, unit="spp", disable=None if progress else True, desc="rendering", leave=False) as bar:
        for index, count in enumerate(passes):
            pass_seed = _pass_seed(seed, index)
            try:
                image = wait_interruptibly(functools.partial(_render_pass, integrator, scene, pass_seed, count))
            except ValueError as error:
                raise ValueError(f"--spp: {_last_line(error)}") from None
            except RuntimeError as error:
                raise ValueError(f"{where}: Mitsuba could not render it: {_last_line(error)}") from None
            total += _rgb(image) * count
            bar.update(count)
            if between_passes is not None:
                between_passes()
            if index == 0 and len(passes) > 1:
                _estimate(time.perf_counter() - start, passes, w * h, check_duration, report)
    seconds = time.perf_counter() - start
    image = total / spp
    bad = int(np.count_nonzero(~np.isfinite(image).all(axis=-1)))
    if bad:
        raise ValueError(
            f"{where}: the render has {bad} of {w * h} pixels that are not finite (NaN or inf); nothing was "
            "written (a radiance beyond float32's range, or a degenerate shape?)"
        )
    return {"image": image, "width": w, "height": h, "spp": spp, "seconds": seconds, "variant": variant,
            "strategy": strategy, "points": points, "integrator": integrator, "paths": w * h * spp,
            "passes": len(passes), "threads": int(dr.thread_count())}  # fmt: skip


def _render_pass(integrator: Any, scene: Any, seed: int, spp: int) -> np.ndarray[Any, Any]:
    return np.array(integrator.render(scene, seed=seed, spp=spp), dtype=np.float64)


def _rgb(image: np.ndarray[Any, Any]) -> np.ndarray[Any, Any]:
    """The developed film as (h, w, 3) RGB: alpha dropped, a monochrome film repeated."""
    if image.ndim == 2:
        image = image[..., None]
    if image.shape[-1] < 3:
        return np.repeat(image[..., :1], 3, axis=-1)
    return image[..., :3]


def _estimate(
    first: float,
    passes: list[int],
    pixels: int,
    check_duration: Callable[[float, str], None] | None,
    report: Callable[[str], None] | None,
) -> None:
    """After the first pass: the time the rest will take, at its rate (compilation included: an overestimate)."""
    done, total = passes[0], sum(passes)
    rate = pixels * done / max(first, 1e-9)
    remaining = pixels * (total - done) / rate
    what = f"{pixels * total} paths at {rate / 1e6:.3g} Mpaths/s"
    if check_duration is not None:
        check_duration(remaining, what)
    if report is not None and remaining > 60:
        minutes = remaining / 60
        shown = f"{minutes:.3g} minutes" if minutes < 120 else f"{minutes / 60:.3g} hours"
        report(f"{what} in {len(passes)} passes: about {shown} to go; Ctrl-C stops")
