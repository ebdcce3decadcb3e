"""The library's threads: the parts of a sampling kernel on a pool of Python threads, and how
numba's own (OpenMP) worker threads wait: passively, unless the user chose otherwise.

:func:`run_parts` runs the parts of a kernel call, the first in the calling thread and the
others on a pool of ``numba.config.NUMBA_NUM_THREADS - 1`` threads, made at the first call
with more than one part (nothing at import) and made again in a forked child.  The kernels
are serial numba functions that release the GIL (``nogil=True``), so the parts run at once;
a serial kernel compiles in well under half the time of the same loop in a numba ``prange``
(docs/benchmarks.md).  The number of parts of a call is ``numba.get_num_threads()`` (so
``numba.set_num_threads`` and ``NUMBA_NUM_THREADS`` apply); results never depend on it.

numba's OpenMP threads (GNU libgomp) busy-wait for a while after each parallel
kernel.  With as many threads as cores, they then hold the cores that numpy's
BLAS threads need, and the next kernel waits for the spinning BLAS threads in
turn: measured on 2 cores, ``integrate(lambda w: w @ a)`` took 128 ms instead of
5.6 ms, and a loop of ``sample_sphere`` and ``d @ a`` ~30x longer.  Passive waiting
costs the kernels nothing measurable (docs/design.md, "Threads").

libgomp reads ``OMP_WAIT_POLICY`` once, when it is loaded, i.e. when numba
starts its threads.  :func:`start_threads` starts them with the variable set to
``passive`` (unless the user has set it) and puts ``os.environ`` back as it was,
so that child processes inherit nothing.  The kernels call it before their first
run; nothing happens at import.  If another library has loaded libgomp before,
the setting has no effect (as with any OpenMP setting).
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor, wait

import numba

__all__ = ["WAIT_POLICY", "start_threads", "run_parts"]

WAIT_POLICY = "passive"
"""The ``OMP_WAIT_POLICY`` numba's threads start with when the user has not set one."""

_lock = threading.Lock()
_started = False


def start_threads() -> None:
    """Start numba's thread pool with passive OpenMP waiting; ``os.environ`` is left as it was.

    Idempotent and cheap after the first call.  A user's ``OMP_WAIT_POLICY`` is kept.
    """
    global _started
    if _started:
        return
    with _lock:
        if _started:
            return
        if "OMP_WAIT_POLICY" in os.environ:
            numba.get_num_threads()  # launches the threads
        else:
            os.environ["OMP_WAIT_POLICY"] = WAIT_POLICY
            try:
                numba.get_num_threads()  # launches the threads: libgomp reads its environment now
            finally:
                del os.environ["OMP_WAIT_POLICY"]
        _started = True


_pool_lock = threading.Lock()
_pool: ThreadPoolExecutor | None = None
_pool_pid = 0


def _executor() -> ThreadPoolExecutor:
    """The pool (made at the first use, and again in a forked child, which has none of its threads)."""
    global _pool, _pool_pid
    with _pool_lock:
        if _pool is None or _pool_pid != os.getpid():
            workers = max(1, int(numba.config.NUMBA_NUM_THREADS) - 1)  # type: ignore[attr-defined]  # set at import by numba
            _pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="symsphere")
            _pool_pid = os.getpid()
        return _pool


def run_parts(task: Callable[[int], None], count: int) -> None:
    """Run ``task(0), ..., task(count - 1)`` at once: part 0 in the calling thread, the others on the pool.

    Returns when every part has finished, also if one raised (the parts write into arrays the
    caller owns); the first exception is then raised again.
    """
    if count <= 1:
        task(0)
        return
    futures: list[Future[None]] = [_executor().submit(task, index) for index in range(1, count)]
    try:
        task(0)
    finally:
        wait(futures)
    for future in futures:
        future.result()
