"""Scale-out on a Dask cluster, with results independent of the cluster.

Work is cut at the block boundaries of :mod:`symsphere.points` (``BLOCK`` base
points; random block ``b`` is the stretch of one PCG64 stream from draw
``2 b BLOCK`` on, QMC blocks are consecutive segments of one scrambled sequence).  Every task computes whole blocks exactly
as a single process would, and the client combines the blocks in block order,
so the results are **bit-identical** to :func:`symsphere.sample_sphere` and
:func:`symsphere.integrate` with the same arguments, whatever the number of
workers or the chunk size (a multiple of the block), and also when a worker
dies and its tasks are rerun (tasks are pure).

Clusters: ``client=None`` starts a ``LocalCluster`` with one single-threaded
worker process per core; pass a ``distributed.Client`` (or, on the command line,
``--scheduler ADDRESS``) to use an existing cluster::

    dask scheduler                         # on the head node; prints tcp://HOST:8786
    dask worker tcp://HOST:8786 --nthreads 1 --nworkers 4   # on every machine
    symsphere integrate --integrand exp_dot --n 4800000000 --scheduler tcp://HOST:8786

Needs the optional extra ``symsphere[distributed]`` (dask, distributed).
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import os
import time
from collections.abc import Callable, Iterable, Sequence
from typing import TYPE_CHECKING, Any, Literal, TypeVar

import numpy as np
import numpy.typing as npt

from . import frames
from ._blocks import base_points, empty_rows
from ._clients import client_or_local, close_client, connect, local_client
from ._integration import (
    Integrand,
    IntegrationResult,
    Partial,
    Plan,
    Request,
    block_partials,
    finish,
    plan,
    to_tolerance,
)
from ._kernels import Plan as KernelPlan
from ._kernels import fill
from ._threads import start_threads
from ._typing import DTypeLike, Float64Array, FloatArray, MapMethod, PointsLike, RNGLike
from ._validation import (
    check_bool,
    check_client,
    check_count,
    check_dtype,
    check_normal,
    check_tasks,
)
from .points import BLOCK, BasePoints
from .symmetry import orbit_size
from .warps import triangle_warp

if TYPE_CHECKING:  # not at import: dask and the renderer load only when used
    import dask.array as da
    from distributed import Client, Future

    from .render.renderer import RenderPlan, RenderResult
    from .render.scene import Scene

_T = TypeVar("_T")

__all__ = ["sample_sphere", "sample_hemisphere", "integrate", "render", "connect", "local_client", "close_client"]

DEFAULT_CHUNK_BLOCKS = 16
"""Blocks per task: 16 * 4096 orbits = 3 145 728 sphere directions (75 MB in float64)."""


def sample_sphere(
    n: int,
    *,
    chunks: int = 48 * BLOCK * DEFAULT_CHUNK_BLOCKS,
    method: MapMethod = "equal_area",
    points: PointsLike = "random",
    rng: RNGLike = None,
    dtype: DTypeLike = np.float64,
) -> da.Array:
    """A dask array of the directions of :func:`symsphere.sample_sphere`.

    Each chunk is one task: the kernel of :func:`symsphere.sample_sphere` on the chunk's orbits,
    whose base points it takes by index from the same stream.

    Parameters
    ----------
    n : int
        A positive multiple of 48.
    chunks : int
        Rows per chunk: a multiple of ``48 * symsphere.points.BLOCK`` (196 608).
    method, points, rng, dtype
        As in :func:`symsphere.sample_sphere`; the computed array equals its
        result bit for bit.

    Returns
    -------
    dask.array.Array, shape (n, 3)
        Lazy: blocks of *chunks* rows (the last may be shorter), in *dtype*.

    Examples
    --------
    >>> import numpy as np, symsphere
    >>> from symsphere import distributed
    >>> d = distributed.sample_sphere(48 * 5000, chunks=48 * 4096, rng=3)
    >>> d.chunks[0]
    (196608, 43392)
    >>> bool(np.array_equal(d.compute(scheduler="threads"), symsphere.sample_sphere(48 * 5000, rng=3)))
    True
    """
    return _dask_directions(n, chunks, orbit_size("sphere"), None, method, points, rng, dtype)


def sample_hemisphere(
    n: int,
    *,
    chunks: int = 24 * BLOCK * DEFAULT_CHUNK_BLOCKS,
    normal: npt.ArrayLike | None = None,
    method: MapMethod = "equal_area",
    points: PointsLike = "random",
    rng: RNGLike = None,
    dtype: DTypeLike = np.float64,
) -> da.Array:
    """A dask array of the directions of :func:`symsphere.sample_hemisphere` (see :func:`sample_sphere`).

    Parameters
    ----------
    n, chunks : int
        As for :func:`sample_sphere`, with 24 for 48: *n* a positive multiple of 24, rows per chunk
        a multiple of ``24 * symsphere.points.BLOCK`` (98 304).
    normal, method, points, rng, dtype
        As in :func:`symsphere.sample_hemisphere`; the computed array equals its
        result bit for bit.

    Returns
    -------
    dask.array.Array, shape (n, 3)
        Lazy, in chunks of rows as for :func:`sample_sphere`.

    Examples
    --------
    Any Dask scheduler computes it (``client.compute(d)`` on a cluster); here, threads:

    >>> import numpy as np, symsphere
    >>> from symsphere import distributed
    >>> d = distributed.sample_hemisphere(24 * 5000, chunks=24 * 4096, normal=[0, 1, 0], rng=3)
    >>> d.shape, d.chunks[0]
    ((120000, 3), (98304, 21696))
    >>> local = symsphere.sample_hemisphere(24 * 5000, normal=[0, 1, 0], rng=3)
    >>> bool(np.array_equal(d.compute(scheduler="threads"), local))
    True
    """
    return _dask_directions(n, chunks, orbit_size("hemisphere"), check_normal(normal), method, points, rng, dtype)


def integrate(
    f: Integrand,
    *,
    client: Client | None = None,
    chunk_blocks: int = DEFAULT_CHUNK_BLOCKS,
    progress: bool = False,
    **kwargs: Any,
) -> IntegrationResult:
    """:func:`symsphere.integrate` on a Dask cluster, with the identical result.

    Parameters
    ----------
    f : callable
        The integrand; it is pickled (cloudpickle) to the workers.  A compiled f
        (numba, or a suite integrand) runs fused there too, compiled once per worker.
    client : distributed.Client, optional
        Default: a ``LocalCluster`` with one single-threaded worker per core,
        started for this call and closed after it.
    chunk_blocks : int
        Blocks of ``symsphere.points.BLOCK`` orbits per task.
    progress : bool
        Show a progress bar over the tasks as they complete.
    **kwargs
        As for :func:`symsphere.integrate` (domain, n, method, points, normal,
        rng, replicates, confidence_level, atol, rtol, n_max).  With ``atol``/``rtol`` the
        stages run one after the other, each stage's new blocks as tasks; the blocks summed
        in earlier stages are kept on the client and reused, as in one process.

    Returns
    -------
    symsphere.IntegrationResult
        Equal, bit for bit, to ``symsphere.integrate(f, **kwargs)`` (to a tolerance too: the same
        stages, the same n, the same interval).

    Examples
    --------
    >>> import numpy as np, symsphere
    >>> from symsphere.distributed import close_client, integrate, local_client
    >>> client = local_client(1)
    >>> f = lambda d: np.exp(d @ [0.7, -0.4, 0.5])
    >>> result = integrate(f, client=client, n=48 * 4, rng=1)
    >>> result == symsphere.integrate(f, n=48 * 4, rng=1)          # bit for bit
    True

    To a tolerance, with a compiled integrand (fused on the workers too):

    >>> from symsphere.integrands import INTEGRANDS
    >>> result = integrate(INTEGRANDS["exp"], client=client, rtol=1e-4, rng=2)
    >>> result == symsphere.integrate(INTEGRANDS["exp"], rtol=1e-4, rng=2)
    True
    >>> result.converged, result.n_stages
    (True, 2)
    >>> close_client(client)
    """
    from distributed import as_completed

    arguments = _integrate_arguments(kwargs)
    chunk_blocks = check_count(chunk_blocks, "chunk_blocks")
    if {"atol", "rtol", "n_max"} & set(arguments):
        tolerance = {k: arguments.pop(k, None) for k in ("atol", "rtol", "n_max")}
        n = arguments.pop("n", None)
        with contextlib.ExitStack() as stack:
            clients: list[Client] = []  # opened at the first stage, after the arguments are checked

            def compute(work: Plan, requests: Sequence[tuple[int, int, int]]) -> list[list[Partial]]:
                if not clients:
                    check_client(client)
                    clients.append(stack.enter_context(client_or_local(client)))
                return _compute_on(clients[0], work, requests, chunk_blocks, progress, as_completed)

            return to_tolerance(Request(f, n=n, **arguments, **tolerance), compute=compute)
    work = plan(f, **arguments)
    requests = [(replicate, 0, work.blocks_per_replicate) for replicate in range(work.replicates)]
    check_tasks(
        work.replicates * -(-work.blocks_per_replicate // chunk_blocks),
        "chunk_blocks",
        f"{work.replicates} replicates of {work.blocks_per_replicate} blocks in tasks of {chunk_blocks}",
    )
    check_bool(progress, "progress")
    check_client(client)  # after the arguments of the run, before any work
    with client_or_local(client) as active:
        partials = _compute_on(active, work, requests, chunk_blocks, progress, as_completed)
    return finish(work, partials)


def _compute_on(
    active: Client,
    work: Plan,
    requests: Sequence[tuple[int, int, int]],
    chunk_blocks: int,
    progress: bool,
    as_completed: Callable[[list[Future[Any]]], Iterable[Future[Any]]],
) -> list[list[Partial]]:
    """The partials of each (replicate, first, stop) request, as tasks of at most chunk_blocks blocks."""
    tasks = [
        (index, replicate, first, min(first + chunk_blocks, stop))
        for index, (replicate, start, stop) in enumerate(requests)
        for first in range(start, stop, chunk_blocks)
    ]
    check_tasks(len(tasks), "chunk_blocks", f"{len(requests)} replicates' blocks in tasks of {chunk_blocks}")
    partials: list[list[Partial]] = [[] for _ in requests]
    if not tasks:
        return partials
    plan_future = active.scatter(work, broadcast=True, hash=False)  # a fresh key: no clash with a release in flight
    futures = [active.submit(_partials_task, plan_future, *task[1:], pure=False) for task in tasks]
    index_of = {future.key: index for index, future in enumerate(futures)}
    results: dict[int, list[Partial]] = {}
    for future in _progress(as_completed(futures), len(futures), progress, "integrating"):
        results[index_of[future.key]] = _result(future, "evaluating 'f'")
    for number, task in enumerate(tasks):  # in task order: block order within each request
        partials[task[0]].extend(results[number])
    return partials


def _result(future: Future[Any], doing: str) -> Any:
    """``future.result()``; a task lost with its worker's process (``os._exit``, a crash, the OOM killer) raises
    a RuntimeError saying so: Dask reports it as "cancelled ... already forgotten" (the data scattered to the
    worker went with it) or ``KilledWorker``, naming neither the cause nor the task's work."""
    from distributed.client import FutureCancelledError
    from distributed.scheduler import KilledWorker

    try:
        return future.result()
    except (FutureCancelledError, KilledWorker) as error:
        raise RuntimeError(
            f"a Dask worker's process ended while {doing} (os._exit, a crash or memory exhausted inside the "
            f"task), and its task could not be finished: {type(error).__name__}: {error}"
        ) from None


def render(
    scene: Scene | str | os.PathLike[str] = "cornell",
    *,
    client: Client | None = None,
    passes_per_task: int = 1,
    progress: bool = False,
    width: int = 256,
    height: int = 192,
    spp: int = 96,
    strategy: str = "symmetric",
    points: str | None = None,
    method: str | None = None,
    pixel_filter: str = "box",
    seed: int | None = None,
    integrator: Literal["path", "bsdf"] = "path",
    sampler: str | None = None,
) -> RenderResult:
    """:func:`symsphere.render.render` with its sample passes on a Dask cluster, the identical image.

    The renderer sums every pass of samples from zero and adds the passes in order;
    here the passes are rendered on the workers (*passes_per_task* per task) and
    added in the same order on the client, so the image equals the single-process
    one bit for bit.  ``seconds`` of the result is the wall time of the whole run,
    ``startup_seconds`` 0 and ``threads`` the number of workers.

    Parameters
    ----------
    scene, width, height, spp, strategy, points, method, pixel_filter, seed, integrator
        As in :func:`symsphere.render.render`.
    sampler : str, optional
        Deprecated, as in :func:`symsphere.render.render`.
    client : distributed.Client, optional
        Default: a ``LocalCluster`` with one single-threaded worker per core,
        started for this call and closed after it.
    passes_per_task : int
        Sample passes per task.
    progress : bool
        Show a progress bar over the tasks as they complete.

    Returns
    -------
    symsphere.render.RenderResult

    Examples
    --------
    >>> from symsphere.distributed import close_client, local_client, render
    >>> client = local_client(1)
    >>> result = render("cornell", client=client, width=16, height=12, spp=24, seed=1)
    >>> result.image.shape, result.paths, result.threads
    ((12, 16, 3), 4608, 1)
    >>> close_client(client)
    """
    from distributed import as_completed

    from ._strategies import resolve
    from .render.renderer import plan_passes

    strategy, points, method = resolve(sampler, strategy, points, method, "render", stacklevel=2)
    plan = plan_passes(
        scene, width, height, spp, method=method, pixel_filter=pixel_filter, seed=seed, integrator=integrator,
        strategy=strategy, points=points,
    )  # fmt: skip
    passes_per_task = check_count(passes_per_task, "passes_per_task")
    check_tasks(-(-plan.passes // passes_per_task), "passes_per_task", f"{plan.passes} passes")
    check_bool(progress, "progress")
    check_client(client)
    tasks = [(first, min(first + passes_per_task, plan.passes)) for first in range(0, plan.passes, passes_per_task)]
    with client_or_local(client) as active:
        start = time.perf_counter()
        plan_future = active.scatter(plan, broadcast=True, hash=False)
        futures = [active.submit(_render_task, plan_future, *task, pure=False) for task in tasks]
        index_of = {future.key: index for index, future in enumerate(futures)}
        results: dict[int, list[Float64Array]] = {}
        for future in _progress(as_completed(futures), len(futures), progress, f"rendering {plan.scene.name}"):
            results[index_of[future.key]] = _result(future, f"rendering {plan.scene.name!r}")
        workers = len(active.scheduler_info()["workers"])
    accum = np.zeros((plan.height, plan.width, 3))
    for index in range(len(tasks)):
        for image in results[index]:
            accum += image
    return plan.result(accum, time.perf_counter() - start, 0.0, workers)


# --- private ---------------------------------------------------------------------


def _integrate_arguments(kwargs: dict[str, Any]) -> dict[str, Any]:
    allowed = {
        "domain",
        "n",
        "method",
        "points",
        "normal",
        "rng",
        "replicates",
        "confidence_level",
        "atol",
        "rtol",
        "n_max",
    }
    unknown = sorted(set(kwargs) - allowed)
    if unknown:
        raise TypeError(f"integrate() got unexpected keyword arguments {unknown}; allowed: {sorted(allowed)}")
    if kwargs.get("method") in ("auto", "fibonacci", "lebedev"):
        # Only the scheme's orbits are split into tasks; a rotated Lebedev or Fibonacci stage is one rule per
        # replicate, evaluated in this process, so 'auto' here would distribute at most one of its families.
        raise ValueError(
            f"method={kwargs['method']!r} runs in one process: use symsphere.integrate(f, method="
            f"{kwargs['method']!r}, ...); distributed.integrate distributes the scheme's maps, one of "
            "{'equal_area', 'paper1', 'paper2'}"
        )
    defaults: dict[str, Any] = dict(
        domain="sphere", method="equal_area", points="random", normal=None, rng=None, replicates=None
    )
    defaults["confidence_level"] = 0.95
    tolerance = {k: v for k, v in kwargs.items() if k in ("atol", "rtol", "n_max") and v is not None}
    kwargs = {k: v for k, v in kwargs.items() if k not in ("atol", "rtol", "n_max")}
    if "n_max" in tolerance and not ({"atol", "rtol"} & set(tolerance)):
        raise ValueError("'n_max' is only valid with 'atol' or 'rtol'")
    if "n" not in kwargs and not tolerance:
        raise TypeError("integrate() missing required keyword argument 'n' (or give 'atol' or 'rtol')")
    return {**defaults, **kwargs, **tolerance}


def _partials_task(work: Plan, replicate: int, first: int, stop: int) -> list[Partial]:
    _single_threaded_kernels()
    # A private copy of the point sources: QMC engines are stateful, and tasks may share a process.
    work = dataclasses.replace(work, sources=tuple(copy.deepcopy(source) for source in work.sources))
    return block_partials(work, replicate, first, stop)  # a compiled f: one fused kernel call


def _render_task(plan: RenderPlan, first_pass: int, stop_pass: int) -> list[Float64Array]:
    from .render.renderer import render_passes

    _single_threaded_kernels()
    return render_passes(plan, first_pass, stop_pass)


def _directions_task(
    source: BasePoints,
    method: MapMethod,
    count: int,
    basis: Float64Array | None,
    dtype: np.dtype[np.floating[Any]],
    start: int,
    stop: int,
) -> FloatArray:
    _single_threaded_kernels()
    source = copy.deepcopy(source)  # QMC engines are stateful, and tasks may share a process
    out = empty_rows((stop - start) * count, dtype)
    return fill(KernelPlan(source, method, count, basis), start, stop, out)


def _single_threaded_kernels() -> None:
    # Workers are one per core: numba's own threads would oversubscribe the cores.
    from distributed import get_worker

    with contextlib.suppress(ValueError):
        get_worker()
        import numba

        start_threads()  # before set_num_threads launches them: passive waiting, as in the client
        numba.set_num_threads(1)


def _dask_directions(
    n: int,
    chunks: int,
    count: int,
    normal: Float64Array | None,
    method: MapMethod,
    points: PointsLike,
    rng: RNGLike,
    dtype: DTypeLike,
) -> da.Array:
    import dask.array as da
    from dask.delayed import delayed

    n = check_count(n, "n", multiple=count)
    dtype = check_dtype(dtype)
    triangle_warp(method)
    source = base_points(points, rng, n // count, count, n)
    basis = None if normal is None else frames.frame(normal)
    chunks = check_count(chunks, "chunks", multiple=count * BLOCK)
    per_chunk = chunks // count
    total = n // count
    check_tasks(-(-total // per_chunk), "chunks", f"'n'={n} in chunks of {chunks}")
    pieces = []
    for start in range(0, total, per_chunk):
        stop = min(start + per_chunk, total)
        task = delayed(_directions_task, pure=True)(source, method, count, basis, dtype, start, stop)
        pieces.append(da.from_delayed(task, shape=((stop - start) * count, 3), dtype=dtype))
    directions: da.Array = da.concatenate(pieces, axis=0)
    return directions


def _progress(iterable: Iterable[_T], total: int, enabled: bool, description: str) -> Iterable[_T]:
    if not enabled:
        return iterable
    from tqdm.auto import tqdm

    bar: Iterable[_T] = tqdm(iterable, total=total, desc=description, unit="task")
    return bar
