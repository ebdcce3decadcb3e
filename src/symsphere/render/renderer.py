"""``render``: path-trace a scene with a chosen direction sampler, on all cores."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numba
import numpy as np

from .._kernels import METHOD_CODES
from . import _integrator as _k
from .image import save_npy, save_pfm, save_png
from .scene import get_scene

__all__ = ["SAMPLERS", "SYMMETRIC_SAMPLERS", "FILTERS", "RenderResult", "render", "write_outputs"]

SAMPLERS = ("symmetric", "symmetric_sobol", "equal_area", "paper1", "paper2", "uniform", "cosine")
"""Direction samplers at diffuse vertices (see docs/rendering.md):

``symmetric``        the paper's scheme inside a pixel: groups of 24 (48 through
                     transmission) samples share a random base point per vertex and
                     take its orbit members in turn;
``symmetric_sobol``  the same with base points from a per-pixel, per-vertex
                     Owen-scrambled 2D Sobol' sequence (Burley 2020);
``equal_area``, ``paper1``, ``paper2``
                     i.i.d.: a random base point mapped onto T0 by that map and a
                     uniformly random orbit member, weighted by 1/pdf;
``uniform``          classic independent uniform directions;
``cosine``           cosine-weighted (Shirley–Chiu concentric disk + Malley).
"""

SYMMETRIC_SAMPLERS = ("symmetric", "symmetric_sobol")
FILTERS = ("box", "tent")
_SAMPLER_CODES = {
    "symmetric": _k.SYMMETRIC,
    "symmetric_sobol": _k.SYMMETRIC_SOBOL,
    "equal_area": _k.ORBIT,
    "paper1": _k.ORBIT,
    "paper2": _k.ORBIT,
    "uniform": _k.UNIFORM,
    "cosine": _k.COSINE,
}
_PATHS_PER_PASS = 200_000  # progress granularity: a kernel call per ~0.1 s


@dataclass(frozen=True)
class RenderResult:
    """A rendered image and how it was made.

    image : (height, width, 3) float64, mean linear radiance per pixel (unclamped)
    seconds : wall time of the path tracing (after compilation / cache load)
    startup_seconds : time to compile the kernel or load it from numba's cache
    paths : width * height * spp camera paths;  paths_per_second = paths / seconds
    """

    image: np.ndarray = field(repr=False)
    scene: str
    width: int
    height: int
    spp: int
    sampler: str
    method: str | None
    pixel_filter: str
    seed: int
    seconds: float
    startup_seconds: float
    paths: int
    threads: int

    @property
    def paths_per_second(self) -> float:
        return self.paths / self.seconds if self.seconds > 0 else math.inf


def render(
    scene="cornell",
    *,
    width=256,
    height=192,
    spp=96,
    sampler="symmetric_sobol",
    method=None,
    pixel_filter="box",
    seed=None,
    threads=None,
    progress=False,
) -> RenderResult:
    """Path-trace *scene* and return the mean radiance per pixel.

    Parameters
    ----------
    scene : Scene, str or os.PathLike
        A :class:`~symsphere.render.Scene`, a built-in scene name (``'cornell'``,
        ``'furnace'``, ``'translucent'``) or a ``.toml``/``.json`` scene file.
    width, height, spp : int
        Image size and samples (camera paths) per pixel.  The symmetric
        samplers form complete orbits when spp is a multiple of 24 (48 if the
        scene has translucent materials); any spp is unbiased.
    sampler : str
        One of :data:`SAMPLERS`.
    method : {'equal_area', 'paper1', 'paper2'}, optional
        The map from the square onto T0 for the symmetric samplers (default
        ``'equal_area'``).  The other samplers do not take it.
    pixel_filter : {'box', 'tent'}
        ``'box'``: uniform within the pixel; ``'tent'``: smallpt's (a random
        2 x 2 subpixel, a tent of radius one subpixel).
    seed : int, optional
        Non-negative; the same seed gives the same image for any thread count.
        Default: fresh entropy (returned in the result).
    threads : int, optional
        numba threads (default: all).
    progress : bool
        Show a progress bar (tqdm, on stderr, only on a terminal).

    Returns
    -------
    RenderResult
    """
    plan = _plan(scene, width, height, spp, sampler, method, pixel_filter, seed)
    if threads is not None:
        threads = _positive_int(threads, "threads")
        if threads > numba.config.NUMBA_NUM_THREADS:
            raise ValueError(f"'threads' must be at most {numba.config.NUMBA_NUM_THREADS}, got {threads}")

    accum = np.zeros((plan.height, plan.width, 3))
    previous_threads = numba.get_num_threads()
    if threads is not None:
        numba.set_num_threads(threads)
    try:
        start = time.perf_counter()
        _render_pass_into(plan, 0, 0, accum)  # compile, or load from numba's cache
        startup = time.perf_counter() - start
        from tqdm.auto import tqdm

        with tqdm(total=plan.spp, unit="spp", desc=f"rendering {plan.scene.name}", disable=None if progress else True) as bar:
            start = time.perf_counter()
            for index in range(plan.passes):
                # Each pass is summed on its own and then added, so that a cluster that renders
                # passes on workers (symsphere.distributed.render) gets the identical image.
                accum += render_passes(plan, index, index + 1)[0]
                bar.update(plan.pass_range(index)[1])
            seconds = time.perf_counter() - start
        used_threads = numba.get_num_threads()
    finally:
        if threads is not None:
            numba.set_num_threads(previous_threads)
    return plan.result(accum, seconds, startup, used_threads)


@dataclass(frozen=True)
class _RenderPlan:
    """A validated render: everything a pass needs (picklable, for Dask workers)."""

    scene: object
    width: int
    height: int
    spp: int
    sampler: str
    method: str | None
    pixel_filter: str
    seed: int
    arguments: tuple = field(repr=False)  # the kernel's scene and sampler arguments
    per_pass: int

    @property
    def passes(self) -> int:
        return -(-self.spp // self.per_pass)

    def pass_range(self, index):
        first = index * self.per_pass
        return first, min(self.per_pass, self.spp - first)

    def result(self, accum, seconds, startup, threads):
        return RenderResult(
            image=accum / self.spp,
            scene=self.scene.name,
            width=self.width,
            height=self.height,
            spp=self.spp,
            sampler=self.sampler,
            method=self.method,
            pixel_filter=self.pixel_filter,
            seed=self.seed,
            seconds=seconds,
            startup_seconds=startup,
            paths=self.width * self.height * self.spp,
            threads=threads,
        )


def _plan(scene, width, height, spp, sampler, method, pixel_filter, seed):
    scene = get_scene(scene)
    width = _positive_int(width, "width")
    height = _positive_int(height, "height")
    spp = _positive_int(spp, "spp")
    if sampler not in SAMPLERS:
        raise ValueError(f"'sampler' must be one of {', '.join(SAMPLERS)}; got {sampler!r}")
    if method is not None and sampler not in SYMMETRIC_SAMPLERS:
        raise ValueError(
            f"'method' applies only to the samplers {', '.join(SYMMETRIC_SAMPLERS)}; "
            f"for {sampler!r} leave it out (the i.i.d. orbit samplers are named after their map)"
        )
    if sampler in SYMMETRIC_SAMPLERS:
        method = "equal_area" if method is None else method
        if method not in METHOD_CODES:
            raise ValueError(f"'method' must be one of {', '.join(METHOD_CODES)}; got {method!r}")
        code = METHOD_CODES[method]
    else:
        code = METHOD_CODES.get(sampler, 0)
    if pixel_filter not in FILTERS:
        raise ValueError(f"'pixel_filter' must be one of {', '.join(FILTERS)}; got {pixel_filter!r}")
    if seed is None:
        seed = int(np.random.SeedSequence().entropy)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"'seed' must be a non-negative integer, got {seed!r}")
    seed = int(seed)
    a = scene.arrays(width, height)
    key = np.random.SeedSequence(seed).generate_state(1, dtype=np.uint64)[0]
    arguments = (
        a["spheres"], a["sphere_material"], a["quads"], a["quad_material"], a["materials"], a["camera"],
        a["background"], a["eps"], a["rr_depth"], a["max_depth"], _SAMPLER_CODES[sampler], code,
        FILTERS.index(pixel_filter), key,
    )  # fmt: skip
    return _RenderPlan(
        scene=scene,
        width=width,
        height=height,
        spp=spp,
        sampler=sampler,
        method=method if sampler in SYMMETRIC_SAMPLERS else None,
        pixel_filter=pixel_filter,
        seed=seed,
        arguments=arguments,
        per_pass=max(1, min(spp, _PATHS_PER_PASS // (width * height))),
    )


def render_passes(plan, first_pass, stop_pass):
    """The images (sums, not means) of passes ``first_pass .. stop_pass - 1``, each summed from zero."""
    images = []
    for index in range(first_pass, stop_pass):
        image = np.zeros((plan.height, plan.width, 3))
        _render_pass_into(plan, *plan.pass_range(index), image)
        images.append(image)
    return images


def _render_pass_into(plan, first, count, image):
    rows = np.arange(plan.height, dtype=np.int64)
    with numba.parallel_chunksize(1):  # rows differ in cost: hand them out one at a time
        _k.render_pass(*plan.arguments, first, count, rows, image)


def write_outputs(result: RenderResult, out, exposure=1.0) -> list[Path]:
    """Write ``out`` (.png, tone-mapped) and, next to it, the HDR image as ``.pfm`` and ``.npy``.

    *out* may end in .png, .pfm or .npy; all three files are written with the
    same stem, each atomically.  Returns their paths (PNG, PFM, NPY).
    """
    out = Path(out)
    if out.suffix.lower() not in (".png", ".pfm", ".npy"):
        raise ValueError(f"'--out' must end in .png, .pfm or .npy, got {str(out)!r}")
    png, pfm, npy = (out.with_suffix(s) for s in (".png", ".pfm", ".npy"))
    save_png(png, result.image, exposure)
    save_pfm(pfm, result.image)
    save_npy(npy, result.image)
    return [png, pfm, npy]


def _positive_int(value, name) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"'{name}' must be a positive integer, got {value!r}")
    return int(value)

