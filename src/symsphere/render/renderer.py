"""``render``: path-trace a scene with a chosen integrator and direction sampling, on all cores.

The direction at a diffuse vertex is chosen by the words of :mod:`symsphere._strategies` (those of the
Mitsuba plugin): ``strategy`` (:data:`STRATEGIES`), ``points`` (its base points) and ``method`` (the map
onto T0).  The earlier one-word ``sampler=`` names (:data:`SAMPLERS`) still work, with a
DeprecationWarning naming the words.
"""

from __future__ import annotations

import math
import os
import time
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, Literal, cast

import numba
import numpy as np

from .._kernels import METHOD_CODES
from .._strategies import SAMPLER_SPELLINGS, legacy_sampler, resolve, words
from .._typing import Float64Array, MapMethod
from .._validation import (
    MAX_PATHS,
    MAX_PIXELS,
    check_bool,
    check_count,
    check_file_suffix,
    check_index,
    check_seed,
    check_size,
    memory_pixel_limit,
    short_repr,
)
from . import _directions as _d
from . import _integrator as _k
from .image import IMAGE_SUFFIXES, save_image_set
from .scene import Scene
from .scenes import get_scene

__all__ = [
    "FILTERS",
    "INTEGRATORS",
    "SAMPLERS",
    "STRATEGIES",
    "SYMMETRIC_SAMPLERS",
    "RenderPlan",
    "RenderResult",
    "RenderSettings",
    "plan_passes",
    "render",
    "render_passes",
    "write_outputs",
]

BYTES_PER_PIXEL = 160
"""Memory a pixel of an image costs during a render, with room to spare over the ~147 bytes an audit measured
(the sum, a pass and the mean in float64 RGB, the filter weights, the encoded outputs); images whose
pixels would not fit in the machine's memory are refused before any allocation."""

STRATEGIES = words("render")
"""The direction sampling at diffuse vertices (``strategy=``; the registry
:data:`symsphere._strategies.SAMPLING_STRATEGIES`; see docs/reference/renderer.md):

``symmetric``         the paper's scheme inside a pixel: groups of 24 (48 through
                      transmission) samples share a base point per vertex, mapped
                      onto T0 by ``method``, and take its orbit members in turn;
``symmetric_cosine``  cosine-weighted symmetric sampling: groups of 8 (16 through
                      transmission) samples share a base point of a cosine-weighted
                      map onto the wedge 0 <= phi <= pi/4 and take its images under
                      the 8 signed permutations that keep z (x {z, -z}) in turn;
``orbit``             i.i.d.: a random base point mapped onto T0 by ``method`` and a
                      uniformly random orbit member, weighted by 1/pdf;
``uniform``           classic independent uniform directions;
``cosine``            cosine-weighted (Shirley–Chiu concentric disk + Malley).

Base points (``points=``) of the two symmetric strategies: ``'sobol'`` (the
default: a per-pixel, per-vertex Owen-scrambled 2D Sobol' sequence, Burley 2020),
``'random'`` (hashes), ``'sobol_interlaced2'``, ``'sobol_interlaced3'`` (4 or 6
Sobol' dimensions, each Owen-scrambled, interlaced digit by digit into 2:
higher-order digital nets, Dick 2011, as the point sets of :mod:`symsphere.points`);
the i.i.d. strategies take ``'random'`` only.
"""

SAMPLERS = tuple(SAMPLER_SPELLINGS)
"""The deprecated ``sampler=`` names (one release): each is a (strategy, points, method) of
:data:`symsphere._strategies.SAMPLER_SPELLINGS`, e.g. ``'symmetric_cosine_sobol'`` is
``strategy='symmetric_cosine', points='sobol'`` and ``'paper1'`` is ``strategy='orbit', method='paper1'``."""

INTEGRATORS = ("path", "bsdf")
"""``path``: next-event estimation + BSDF sampling, combined by MIS (power heuristic);
``bsdf``: BSDF sampling only (smallpt's estimator)."""

SYMMETRIC_SAMPLERS = ("symmetric", "symmetric_sobol", "symmetric_sobol_interlaced2", "symmetric_sobol_interlaced3")
"""The deprecated samplers that take a ``method`` (the map onto T0): ``strategy='symmetric'``."""
FILTERS = ("box", "tent")
"""Pixel filters: ``box`` (uniform in the pixel) and ``tent`` (smallpt's 2 x 2 subpixel tent)."""
_SAMPLING_CODES = {  # (strategy, points) -> the kernel's code (render/_directions.py)
    ("symmetric", "random"): _d.SYMMETRIC,
    ("symmetric", "sobol"): _d.SYMMETRIC_SOBOL,
    ("symmetric", "sobol_interlaced2"): _d.SYMMETRIC_SOBOL_INTERLACED2,
    ("symmetric", "sobol_interlaced3"): _d.SYMMETRIC_SOBOL_INTERLACED3,
    ("symmetric_cosine", "random"): _d.SYMMETRIC_COSINE,
    ("symmetric_cosine", "sobol"): _d.SYMMETRIC_COSINE_SOBOL,
    ("symmetric_cosine", "sobol_interlaced2"): _d.SYMMETRIC_COSINE_SOBOL_INTERLACED2,
    ("symmetric_cosine", "sobol_interlaced3"): _d.SYMMETRIC_COSINE_SOBOL_INTERLACED3,
    ("orbit", "random"): _d.ORBIT,
    ("uniform", "random"): _d.UNIFORM,
    ("cosine", "random"): _d.COSINE,
}
_INTEGRATOR_CODES = {"path": _k.PATH, "bsdf": _k.BSDF}
# The numba kernels' module is typed by numba, not mypy (pyproject.toml): its one entry point, typed here.
_render_pass: Callable[..., None] = _k.render_pass
_PATHS_PER_PASS = 200_000  # progress granularity: a kernel call per ~0.1 s


@dataclass(frozen=True, kw_only=True)
class RenderSettings:
    """What a render was asked for, checked: the fields :class:`RenderPlan` and :class:`RenderResult` share.

    Attributes
    ----------
    width, height, spp, strategy, points, method, pixel_filter, seed, integrator
        The arguments of :func:`render` (``points`` and ``method`` filled in with their defaults,
        ``method`` None for the strategies without one; ``seed`` the one used, drawn from fresh
        entropy if none was given).

    Examples
    --------
    >>> from symsphere.render import RenderSettings, plan_passes
    >>> plan = plan_passes("furnace", 4, 4, 3, strategy="cosine", seed=7)
    >>> plan.settings() == RenderSettings(width=4, height=4, spp=3, strategy="cosine", points="random",
    ...                                   method=None, pixel_filter="box", seed=7, integrator="path")
    True
    """

    width: int
    height: int
    spp: int
    strategy: str
    points: str
    method: str | None
    pixel_filter: str
    seed: int
    integrator: str = "path"

    def settings(self) -> RenderSettings:
        """These settings alone, as a :class:`RenderSettings` (from a plan or a result: equal for the same render)."""
        return RenderSettings(**{f.name: getattr(self, f.name) for f in fields(RenderSettings)})

    @property
    def sampler(self) -> str | None:
        """Deprecated: the one-word ``sampler=`` name of (strategy, points, method); use those."""
        warnings.warn(
            "'sampler' is deprecated; use 'strategy', 'points' and 'method'", DeprecationWarning, stacklevel=2
        )
        return legacy_sampler(self.strategy, self.points, self.method)


@dataclass(frozen=True, kw_only=True)
class RenderResult(RenderSettings):
    """A rendered image and how it was made.

    Attributes
    ----------
    image : ndarray, shape (height, width, 3)
        float64, mean linear radiance per pixel (unclamped).
    scene : str
        The scene's name.
    width, height, spp, strategy, points, method, pixel_filter, seed, integrator
        The arguments of :func:`render`: the fields of :class:`RenderSettings`
        (``method`` None for the strategies without one); ``result.settings()`` gives them alone.
    seconds : float
        Wall time of the path tracing (after compilation / cache load).
    startup_seconds : float
        Time to compile the kernel or load it from numba's cache.
    paths : int
        ``width * height * spp`` camera paths; ``paths_per_second = paths / seconds``.
    threads : int
        numba threads used.

    Examples
    --------
    >>> from symsphere.render import render
    >>> result = render("furnace", width=8, height=6, spp=8, strategy="cosine", seed=1)
    >>> result.image.shape, result.paths, result.integrator
    ((6, 8, 3), 384, 'path')
    """

    image: Float64Array = field(repr=False)
    scene: str
    seconds: float
    startup_seconds: float
    paths: int
    threads: int

    @property
    def paths_per_second(self) -> float:
        """Camera paths per second of wall time (``paths / seconds``)."""
        return self.paths / self.seconds if self.seconds > 0 else math.inf

    def _repr_png_(self) -> bytes:
        """The image as PNG bytes (tone-mapped sRGB at exposure 1, as ``save_png``): Jupyter shows it."""
        import io

        from matplotlib.image import imsave  # function-level: only when a notebook displays the result

        from .image import tonemap

        buffer = io.BytesIO()
        imsave(buffer, tonemap(self.image), format="png")
        return buffer.getvalue()


def render(
    scene: Scene | str | os.PathLike[str] = "cornell",
    *,
    width: int = 256,
    height: int = 192,
    spp: int = 96,
    strategy: Literal["cosine", "orbit", "symmetric", "symmetric_cosine", "uniform"] = "symmetric",
    points: Literal["random", "sobol", "sobol_interlaced2", "sobol_interlaced3"] | None = None,
    method: Literal["equal_area", "paper1", "paper2"] | None = None,
    pixel_filter: Literal["box", "tent"] = "box",
    seed: int | None = None,
    threads: int | None = None,
    progress: bool = False,
    integrator: Literal["path", "bsdf"] = "path",
    sampler: str | None = None,
) -> RenderResult:  # fmt: skip
    """Path-trace *scene* and return the mean radiance per pixel.

    Parameters
    ----------
    scene : Scene, str or os.PathLike
        A :class:`~symsphere.render.Scene`, a built-in scene name (``'cornell'``,
        ``'furnace'``, ``'translucent'``) or a ``.toml``/``.json`` scene file.
    width, height, spp : int
        Image size and samples (camera paths) per pixel.  The strategy
        ``symmetric`` forms complete orbits when spp is a multiple of 24 (48 if the
        scene has translucent materials; 8 and 16 for ``symmetric_cosine``);
        any spp is unbiased.
    strategy : str
        One of :data:`STRATEGIES`: the direction sampling at diffuse vertices.
    points : str, optional
        The strategy's base points: ``'sobol'`` (the default of the two symmetric
        strategies), ``'random'`` (the default, and the only choice, of the others),
        ``'sobol_interlaced2'``, ``'sobol_interlaced3'`` (symmetric strategies).
    method : {'equal_area', 'paper1', 'paper2'}, optional
        The map from the square onto T0 for the strategies ``symmetric`` and
        ``orbit`` (default ``'equal_area'``).  The others do not take it.
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
    integrator : {'path', 'bsdf'}
        ``'path'``: next-event estimation and BSDF sampling combined by
        multiple importance sampling (power heuristic); ``'bsdf'``: BSDF
        sampling only (smallpt's estimator).  Both converge to the same image.
    sampler : str, optional
        Deprecated (one release): one of :data:`SAMPLERS`, the earlier one-word
        spelling of *strategy* and *points* (and of *method* for the i.i.d. orbit
        samplers); a DeprecationWarning names the new spelling.  Not with
        *strategy* or *points*.

    Returns
    -------
    RenderResult

    Examples
    --------
    >>> from symsphere.render import render
    >>> result = render("cornell", width=8, height=6, spp=8, seed=1)
    >>> result.image.shape, bool(result.image.max() > 0)
    ((6, 8, 3), True)
    >>> render("furnace", width=4, height=4, spp=4, seed=1, integrator="bsdf").integrator
    'bsdf'
    """
    chosen = resolve(sampler, strategy, points, method, "render", stacklevel=2)
    plan = plan_passes(
        scene, width, height, spp, method=chosen[2], pixel_filter=pixel_filter, seed=seed, integrator=integrator,
        strategy=chosen[0], points=chosen[1],
    )  # fmt: skip
    progress = check_bool(progress, "progress")
    if threads is not None:
        threads = check_count(threads, "threads")
        most = int(numba.config.NUMBA_NUM_THREADS)  # type: ignore[attr-defined]  # set at import by numba
        if threads > most:
            raise ValueError(f"'threads' must be at most {most}, got {threads}")

    accum = np.zeros((plan.height, plan.width, 3))
    _k.prepare_kernels()  # before numba starts its threads: passive OpenMP waiting, a fresh cache
    previous_threads = numba.get_num_threads()
    if threads is not None:
        numba.set_num_threads(threads)
    try:
        start = time.perf_counter()
        _render_pass_into(plan, 0, 0, accum)  # compile, or load from numba's cache
        startup = time.perf_counter() - start
        from tqdm.auto import tqdm

        with tqdm(
            total=plan.spp, unit="spp", desc=f"rendering {plan.scene.name}", disable=None if progress else True
        ) as bar:
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


@dataclass(frozen=True, kw_only=True)
class RenderPlan(RenderSettings):
    """A validated render: everything a pass needs (picklable, for Dask workers).

    Made by :func:`plan_passes`; rendered pass by pass with :func:`render_passes`.

    Examples
    --------
    >>> from symsphere.render import plan_passes
    >>> plan = plan_passes("cornell", 8, 6, 10, strategy="cosine", seed=1)
    >>> plan.passes, plan.pass_range(0)
    (1, (0, 10))
    """

    scene: Scene
    arguments: tuple[Any, ...] = field(repr=False)  # the kernel's scene and sampling arguments: arrays and codes
    per_pass: int

    @property
    def passes(self) -> int:
        """The number of passes."""
        return -(-self.spp // self.per_pass)

    def pass_range(self, index: int) -> tuple[int, int]:
        """(first sample, sample count) of pass *index*."""
        first = index * self.per_pass
        return first, min(self.per_pass, self.spp - first)

    def result(self, accum: Float64Array, seconds: float, startup: float, threads: int) -> RenderResult:
        """The :class:`RenderResult` of the summed image *accum* (all passes)."""
        return RenderResult(
            **vars(self.settings()),
            image=accum / self.spp,
            scene=self.scene.name,
            seconds=seconds,
            startup_seconds=startup,
            paths=self.width * self.height * self.spp,
            threads=threads,
        )


def warm_up() -> None:
    """Load or compile the renderer's kernel: a 4 x 4 render of ``cornell`` on one thread (what
    :func:`compile_in_background` runs in its second process)."""
    render("cornell", width=4, height=4, spp=24, threads=1, seed=0)


@contextmanager
def compile_in_background(timeout: float = 300.0) -> Iterator[Callable[[], None]]:
    """On a cold numba cache, compile the renderer's kernel in a second process while the block runs.

    For a job that renders after other work (``symsphere demo``): the compile runs on the second
    core meanwhile; the block calls the function it gets before rendering, which waits up to
    *timeout* seconds for the compile, and the render then loads the kernel from the cache.
    Nothing is started when the kernel is cached already or on one core; if the second process
    fails, or numba cannot cache (no writable cache location), the render compiles the kernel
    itself.  Leaving the block stops the process, and any it started, if it still runs (an
    error, Ctrl-C).
    """
    from .._compile_ahead import finish, start_in_background

    helper = None if _k.kernel_is_cached() else start_in_background(__name__, "warm_up")

    def wait() -> None:
        if helper is not None:
            finish(helper, timeout)

    try:
        yield wait
    finally:
        if helper is not None:
            finish(helper, 0.0)


def plan_passes(
    scene: Scene | str | os.PathLike[str],
    width: int,
    height: int,
    spp: int,
    sampler: str | None = None,
    method: str | None = None,
    pixel_filter: str = "box",
    seed: int | None = None,
    integrator: Literal["path", "bsdf"] = "path",
    *,
    strategy: str = "symmetric",
    points: str | None = None,
) -> RenderPlan:
    """Validate the arguments of :func:`render` and split its samples into passes of ~2e5 paths.

    The arguments are :func:`render`'s; the fifth, *sampler*, is the deprecated one-word
    spelling of *strategy* and *points* (a DeprecationWarning names them).  Raises
    ValueError naming a bad argument.

    Examples
    --------
    >>> from symsphere.render import plan_passes, render_passes
    >>> plan = plan_passes("furnace", 4, 4, 3, strategy="cosine", seed=7, integrator="bsdf")
    >>> [image.shape for image in render_passes(plan, 0, plan.passes)]
    [(4, 4, 3)]
    """
    scene = get_scene(scene)
    width = check_count(width, "width")
    height = check_count(height, "height")
    spp = check_count(spp, "spp")
    # The image first (else 'spp'=1 was "too large ... at most 0"), then the paths, before any allocation.
    limit = memory_pixel_limit(BYTES_PER_PIXEL)
    memory = "" if limit == MAX_PIXELS else f" on this machine (~{BYTES_PER_PIXEL} bytes a pixel)"
    check_size(
        width * height, "width * height", limit, f"({width} x {height} pixels, held in memory in float64){memory}"
    )
    check_size(spp, "spp", MAX_PATHS // (width * height), f"for {width}x{height} pixels (paths are counted in int64)")
    strategy, points, method = resolve(sampler, strategy, points, method, "render", stacklevel=2)
    if not isinstance(integrator, str) or integrator not in INTEGRATORS:
        raise ValueError(f"'integrator' must be one of {', '.join(INTEGRATORS)}; got {short_repr(integrator)}")
    code = METHOD_CODES[cast(MapMethod, method)] if method is not None else 0
    if not isinstance(pixel_filter, str) or pixel_filter not in FILTERS:
        raise ValueError(f"'pixel_filter' must be one of {', '.join(FILTERS)}; got {short_repr(pixel_filter)}")
    if seed is None:
        seed = int(cast(int, np.random.SeedSequence().entropy))  # fresh entropy is an int
    seed = check_seed(seed)
    a = scene.arrays(width, height)
    key = np.random.SeedSequence(seed).generate_state(1, dtype=np.uint64)[0]
    arguments = (
        a["spheres"], a["sphere_material"], a["quads"], a["quad_material"], a["materials"], a["lights"],
        a["light_pmf"], a["camera"], a["background"], a["eps"], a["rr_depth"], a["max_depth"],
        _INTEGRATOR_CODES[integrator], _SAMPLING_CODES[strategy, points], code, FILTERS.index(pixel_filter), key,
    )  # fmt: skip
    return RenderPlan(
        scene=scene,
        width=width,
        height=height,
        spp=spp,
        strategy=strategy,
        points=points,
        method=method,
        pixel_filter=pixel_filter,
        seed=seed,
        arguments=arguments,
        per_pass=max(1, min(spp, _PATHS_PER_PASS // (width * height))),
        integrator=integrator,
    )


def render_passes(plan: RenderPlan, first_pass: int, stop_pass: int) -> list[Float64Array]:
    """The images (sums, not means) of passes ``first_pass`` to ``stop_pass - 1``, each summed from zero.

    Examples
    --------
    >>> from symsphere.render import plan_passes, render_passes
    >>> plan = plan_passes("furnace", 4, 4, 2, strategy="cosine", seed=7)
    >>> len(render_passes(plan, 0, 1))
    1
    """
    if not isinstance(plan, RenderPlan):
        raise TypeError(f"'plan' must be a RenderPlan (see plan_passes); got {type(plan).__name__}")
    first_pass = check_index(first_pass, "first_pass", 0, plan.passes)
    stop_pass = check_index(stop_pass, "stop_pass", first_pass, plan.passes)
    images = []
    for index in range(first_pass, stop_pass):
        image = np.zeros((plan.height, plan.width, 3))
        _render_pass_into(plan, *plan.pass_range(index), image)
        images.append(image)
    return images


def _render_pass_into(plan: RenderPlan, first: int, count: int, image: Float64Array) -> None:
    _k.prepare_kernels()
    rows = np.arange(plan.height, dtype=np.int64)
    _render_pass(*plan.arguments, first, count, rows, image)


def write_outputs(result: RenderResult, out: str | os.PathLike[str], exposure: float = 1.0) -> list[Path]:
    """Write ``out`` (.png, tone-mapped) and, next to it, the HDR image as ``.pfm`` and ``.npy``.

    *out* may end in .png, .pfm or .npy; all three files are written with the
    same stem, as one set: they appear together, complete, or none does (an error,
    a full disk or a signal leaves the previous files as they were).  Returns their
    paths (PNG, PFM, NPY).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from symsphere.render import render, write_outputs
    >>> result = render("furnace", width=4, height=4, spp=2, strategy="cosine", seed=1)
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     [p.name for p in write_outputs(result, pathlib.Path(folder) / "f.png")]
    ['f.png', 'f.pfm', 'f.npy']
    """
    if not isinstance(result, RenderResult):
        raise TypeError(f"'result' must be a RenderResult (from render()), got {type(result).__name__}")
    check_file_suffix(out, IMAGE_SUFFIXES[:3], "out")  # .exr is not among the three written
    out = Path(out)
    # One set: all three files appear together or none does (symsphere.io.atomic_paths).
    return save_image_set([out.with_suffix(s) for s in (".png", ".pfm", ".npy")], result.image, exposure)
