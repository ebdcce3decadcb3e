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

import numpy as np

from ._validation import check_count
from .integrate import _block_partial, _finish, _plan
from .points import BLOCK
from .sampling import _fill_range, _prepare

__all__ = ["sample_sphere", "sample_hemisphere", "integrate", "render", "connect", "local_client", "close_client"]

DEFAULT_CHUNK_BLOCKS = 16
"""Blocks per task: 16 * 4096 orbits = 3 145 728 sphere directions (75 MB in float64)."""


def sample_sphere(n, *, chunks=48 * BLOCK * DEFAULT_CHUNK_BLOCKS, method="equal_area", points="random", rng=None, dtype=np.float64):
    """A dask array of the directions of :func:`symsphere.sample_sphere`.

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
    return _dask_directions(n, chunks, 48, None, method, points, rng, dtype)


def sample_hemisphere(
    n, *, chunks=24 * BLOCK * DEFAULT_CHUNK_BLOCKS, normal=None, method="equal_area", points="random", rng=None, dtype=np.float64
):
    """A dask array of the directions of :func:`symsphere.sample_hemisphere` (see :func:`sample_sphere`)."""
    from ._validation import check_normal

    return _dask_directions(n, chunks, 24, check_normal(normal), method, points, rng, dtype)


def integrate(f, *, client=None, chunk_blocks=DEFAULT_CHUNK_BLOCKS, progress=False, **kwargs):
    """:func:`symsphere.integrate` on a Dask cluster, with the identical result.

    Parameters
    ----------
    f : callable
        The integrand; it is pickled (cloudpickle) to the workers.
    client : distributed.Client, optional
        Default: a ``LocalCluster`` with one single-threaded worker per core,
        started for this call and closed after it.
    chunk_blocks : int
        Blocks of ``symsphere.points.BLOCK`` orbits per task.
    progress : bool
        Show a progress bar over the tasks as they complete.
    **kwargs
        As for :func:`symsphere.integrate` (domain, n, method, points, normal,
        rng, replicates, confidence_level).

    Returns
    -------
    symsphere.IntegrationResult
        Equal, bit for bit, to ``symsphere.integrate(f, **kwargs)``.
    """
    from distributed import as_completed

    plan = _plan(f, **_integrate_arguments(kwargs))
    chunk_blocks = check_count(chunk_blocks, "chunk_blocks")
    tasks = [
        (replicate, first, min(first + chunk_blocks, plan.blocks_per_replicate))
        for replicate in range(plan.replicates)
        for first in range(0, plan.blocks_per_replicate, chunk_blocks)
    ]
    with _client_or_local(client) as active:
        plan_future = active.scatter(plan, broadcast=True, hash=False)  # a fresh key: no clash with a release in flight
        futures = [active.submit(_partials_task, plan_future, *task, pure=False) for task in tasks]
        index_of = {future.key: index for index, future in enumerate(futures)}
        results = {}
        for future in _progress(as_completed(futures), len(futures), progress, "integrating"):
            results[index_of[future.key]] = future.result()
    partials = [[] for _ in range(plan.replicates)]
    for index, (replicate, _, _) in enumerate(tasks):
        partials[replicate].extend(results[index])
    return _finish(plan, partials)


def render(
    scene="cornell",
    *,
    client=None,
    passes_per_task=1,
    progress=False,
    width=256,
    height=192,
    spp=96,
    sampler="symmetric_sobol",
    method=None,
    pixel_filter="box",
    seed=None,
):
    """:func:`symsphere.render.render` with its sample passes on a Dask cluster, the identical image.

    The renderer sums every pass of samples from zero and adds the passes in order;
    here the passes are rendered on the workers (*passes_per_task* per task) and
    added in the same order on the client, so the image equals the single-process
    one bit for bit.  ``seconds`` of the result is the wall time of the whole run,
    ``startup_seconds`` 0 and ``threads`` the number of workers.
    """
    from distributed import as_completed

    from .render.renderer import plan_passes as _render_plan

    plan = _render_plan(scene, width, height, spp, sampler, method, pixel_filter, seed)
    passes_per_task = check_count(passes_per_task, "passes_per_task")
    tasks = [(first, min(first + passes_per_task, plan.passes)) for first in range(0, plan.passes, passes_per_task)]
    with _client_or_local(client) as active:
        start = time.perf_counter()
        plan_future = active.scatter(plan, broadcast=True, hash=False)
        futures = [active.submit(_render_task, plan_future, *task, pure=False) for task in tasks]
        index_of = {future.key: index for index, future in enumerate(futures)}
        results = {}
        for future in _progress(as_completed(futures), len(futures), progress, f"rendering {plan.scene.name}"):
            results[index_of[future.key]] = future.result()
        workers = len(active.scheduler_info()["workers"])
    accum = np.zeros((plan.height, plan.width, 3))
    for index in range(len(tasks)):
        for image in results[index]:
            accum += image
    return plan.result(accum, time.perf_counter() - start, 0.0, workers)


def connect(address, *, timeout=10):
    """A ``distributed.Client`` for the scheduler at *address*, or a clear error within *timeout* seconds."""
    from distributed import Client

    try:
        return Client(address, timeout=timeout)
    except (OSError, TimeoutError) as exc:
        raise ConnectionError(
            f"could not reach the Dask scheduler at {address!r} within {timeout} s "
            f"({type(exc).__name__}: {exc}); start one with 'dask scheduler' and workers with "
            f"'dask worker {address}'"
        ) from exc


def local_client(workers=None):
    """A ``LocalCluster`` client: *workers* single-threaded worker processes (default: one per core)."""
    from distributed import Client, LocalCluster

    workers = (os.cpu_count() or 1) if workers is None else check_count(workers, "workers")
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
    return Client(cluster)


def close_client(client):
    """Close *client*, and its cluster too if it runs one of its own (as :func:`local_client`'s does)."""
    cluster = getattr(client, "cluster", None)  # None for a client of a remote scheduler
    client.close()
    if cluster is not None:
        cluster.close()


# --- private ---------------------------------------------------------------------


def _integrate_arguments(kwargs):
    allowed = {"domain", "n", "method", "points", "normal", "rng", "replicates", "confidence_level"}
    unknown = sorted(set(kwargs) - allowed)
    if unknown:
        raise TypeError(f"integrate() got unexpected keyword arguments {unknown}; allowed: {sorted(allowed)}")
    defaults = dict(domain="sphere", method="equal_area", points="random", normal=None, rng=None, replicates=None)
    defaults["confidence_level"] = 0.95
    if "n" not in kwargs:
        raise TypeError("integrate() missing required keyword argument 'n'")
    return {**defaults, **kwargs}


def _partials_task(plan, replicate, first, stop):
    _single_threaded_kernels()
    # A private copy of the point sources: QMC engines are stateful, and tasks may share a process.
    plan = dataclasses.replace(plan, sources=tuple(copy.deepcopy(source) for source in plan.sources))
    return [_block_partial(plan, replicate, block) for block in range(first, stop)]


def _render_task(plan, first_pass, stop_pass):
    from .render.renderer import render_passes

    _single_threaded_kernels()
    return render_passes(plan, first_pass, stop_pass)


def _directions_task(source, method, count, basis, dtype, start, stop):
    _single_threaded_kernels()
    source = copy.deepcopy(source)  # QMC engines are stateful, and tasks may share a process
    out = np.empty(((stop - start) * count, 3), dtype=dtype)
    return _fill_range(source, start, stop, method, count, basis, out)


def _single_threaded_kernels():
    # Workers are one per core: numba's own threads would oversubscribe the cores.
    from distributed import get_worker

    with contextlib.suppress(ValueError):
        get_worker()
        import numba

        numba.set_num_threads(1)


def _dask_directions(n, chunks, count, normal, method, points, rng, dtype):
    import dask
    import dask.array as da

    n, dtype, method, source, basis = _prepare(n, count, normal, method, points, rng, dtype)
    chunks = check_count(chunks, "chunks", multiple=count * BLOCK)
    per_chunk = chunks // count
    total = n // count
    pieces = []
    for start in range(0, total, per_chunk):
        stop = min(start + per_chunk, total)
        task = dask.delayed(_directions_task, pure=True)(source, method, count, basis, dtype, start, stop)
        pieces.append(da.from_delayed(task, shape=((stop - start) * count, 3), dtype=dtype))
    return da.concatenate(pieces, axis=0)


@contextlib.contextmanager
def _client_or_local(client):
    if client is not None:
        yield client
        return
    owned = local_client()
    try:
        yield owned
    finally:
        close_client(owned)


def _progress(iterable, total, enabled, description):
    if not enabled:
        return iterable
    from tqdm.auto import tqdm

    return tqdm(iterable, total=total, desc=description, unit="task")
