"""The library's threads: the parts of a sampling kernel on a pool of Python threads, and how
numba's own (OpenMP) worker threads wait: passively, unless the user chose otherwise.

:func:`run_kernel` compiles a kernel in the calling thread and then runs the parts of its call with
:func:`run_parts`: the first in the calling thread and the others on a pool of
``numba.config.NUMBA_NUM_THREADS - 1`` threads, made at the first call with more than one part
(nothing at import) and made again in a forked child.  The kernels are serial numba functions that
release the GIL (``nogil=True``), so the parts run at once; a serial kernel compiles in well under
half the time of the same loop in a numba ``prange`` (docs/results/cold-start.md).  The number of parts of a
call is ``numba.get_num_threads()`` (so ``numba.set_num_threads`` and ``NUMBA_NUM_THREADS`` apply);
results never depend on it.

numba's OpenMP threads (GNU libgomp) busy-wait for a while after each parallel
kernel.  With as many threads as cores, they then hold the cores that numpy's
BLAS threads need, and the next kernel waits for the spinning BLAS threads in
turn: measured on 2 cores, ``integrate(lambda w: w @ a)`` took 128 ms instead of
5.6 ms, and a loop of ``sample_sphere`` and ``d @ a`` ~30x longer.  Passive waiting
costs the kernels nothing measurable (docs/explanation/design.md, "Threads").

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
import weakref
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor, wait
from typing import Any, cast

import numba
import numpy as np
from numba.core.dispatcher import Dispatcher

from ._signals import kept as signals_kept

__all__ = [
    "ROUTED",
    "WAIT_POLICY",
    "compile_interruptibly",
    "route",
    "route_compiles",
    "run_kernel",
    "run_parts",
    "start_threads",
]

_typeof = cast(Callable[[Any], Any], numba.typeof)  # the type numba dispatches a value on (numba: untyped)
try:  # the C fingerprint by which numba's dispatcher resolves argument types (private to numba; in 0.68)
    from numba._dispatcher import compute_fingerprint as _compute_fingerprint
except ImportError:  # pragma: no cover - numba 0.68 has it
    _compute_fingerprint = None  # type: ignore[assignment]  # numba without it: every launch checked by types

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


def run_kernel(kernel: Any, arguments: Callable[[int], tuple[Any, ...]], count: int) -> None:
    """``kernel(*arguments(i))`` for i in 0..count-1 at once (:func:`run_parts`), compiled first, here.

    The numba dispatcher *kernel* is compiled (or loaded from numba's cache) for the arguments of
    part 0 in the calling thread before any part starts, so that no pool thread ever compiles: a
    KeyboardInterrupt in the middle of a compile (a first run's Ctrl-C) then ends only the calling
    thread's work, never leaves a pool thread with a half-built library (measured before: "no
    compiled object yet" errors and a hung process).  The check is made once per kernel and argument
    types in a process (remembered by numba's type fingerprints of the arguments), not at every launch.
    """
    first = arguments(0)
    key = _fingerprints(first)
    with _compiled_lock:
        known = key is not None and key in _compiled.get(kernel, ())
    if not known:
        compile_interruptibly(kernel, tuple(_typeof(value) for value in first))
        if key is not None:
            with _compiled_lock:
                _compiled.setdefault(kernel, set()).add(key)
    run_parts(lambda index: kernel(*(first if index == 0 else arguments(index))), count)


# The argument fingerprints each kernel has been compiled (or loaded) for in this process: a call with
# known ones skips numba.typeof and the compile check (~0.35 ms a call, 7-20 arguments; measured with
# cProfile on the Intel host: 15 % of an integrate() of 6144 Sobol' points, which launches 8 kernels).
_compiled_lock = threading.Lock()
_compiled: weakref.WeakKeyDictionary[Any, set[tuple[bytes, ...]]] = weakref.WeakKeyDictionary()


def _fingerprints(values: tuple[Any, ...]) -> tuple[bytes, ...] | None:
    """numba's type fingerprints of *values*, or None where a fingerprint would not tell numba's type
    (then the kernel is checked by its types at every launch, as before).

    A fingerprint has no size for a Python int (numba types one from 2**63 on as uint64), no
    alignment for an array, and none at all for a dispatcher; such values, tuples of them and arrays
    of other than plain numbers give None.
    """
    if _compute_fingerprint is None or not all(_faithful(value) for value in values):
        return None
    try:
        return tuple(_compute_fingerprint(value) for value in values)
    except (NotImplementedError, TypeError, ValueError):
        return None


def _faithful(value: Any) -> bool:
    """Whether numba's fingerprint of *value* determines its numba type."""
    if isinstance(value, np.ndarray):
        return bool(value.flags.aligned) and value.dtype.kind in "biufc"
    if isinstance(value, int) and not isinstance(value, bool):
        return -(2**63) <= value < 2**63
    if isinstance(value, tuple):
        return all(_faithful(item) for item in value)
    return True


def compile_interruptibly(kernel: Any, signature: tuple[Any, ...]) -> None:
    """``kernel.compile(signature)``, with a signal during it always ending as its exception.

    numba runs some of its compile steps as callbacks from LLVM's C code, which swallow Python
    exceptions: a KeyboardInterrupt raised there is lost and the compile fails later with
    ``RuntimeError: no compiled object yet`` (measured: 1 of ~10 first runs interrupted ~1 s into the
    compile).  So while it compiles in the main thread, SIGINT (and SIGTERM, SIGHUP where a Python
    handler is set, as the command line sets one) is also recorded, and a recorded signal is raised
    again (through its handler) if the compile did not raise it itself.  :func:`route_compiles` puts
    the first compile of every other call of the package's numba functions on the same path.
    """
    with signals_kept():  # a no-op outside the main thread
        kernel.compile(signature)


ROUTED = "_symsphere_routed"
"""The attribute :func:`route_compiles` sets on each numba dispatcher it has routed (the tests check it)."""


def route_compiles(namespace: dict[str, Any]) -> None:
    """Put the first compile of every numba function defined in the module of *namespace* (its
    ``globals()``) on the interruptible path of :func:`compile_interruptibly`.

    numba compiles a function at its first call with new argument types, through the dispatcher's
    ``_compile_for_args`` (called from numba's C dispatcher, looked up on the instance); each of this
    module's dispatchers gets a wrapper there that keeps a signal arriving during the compile (a
    validation kernel's compile interrupted by Ctrl-C ended as "no compiled object yet", exit 1).
    Calls with known types never reach it: nothing changes on the hot path.  Every module of the
    package that defines numba functions calls this as its last line.
    """
    module = namespace.get("__name__")
    for value in list(namespace.values()):
        if isinstance(value, Dispatcher) and getattr(value.py_func, "__module__", None) == module:
            route(value)


def route(dispatcher: Any) -> Any:
    """Route *dispatcher*'s compiles on first calls through the interruptible path (idempotent); return it."""
    if getattr(dispatcher, ROUTED, False):
        return dispatcher
    original = dispatcher._compile_for_args

    def compile_for_args(*args: Any, **kws: Any) -> Any:
        with signals_kept():  # a no-op outside the main thread
            return original(*args, **kws)

    dispatcher._compile_for_args = compile_for_args
    setattr(dispatcher, ROUTED, True)
    return dispatcher
