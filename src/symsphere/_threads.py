"""How numba's worker threads wait: passively, unless the user chose otherwise.

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

import numba

__all__ = ["WAIT_POLICY", "start_threads"]

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
