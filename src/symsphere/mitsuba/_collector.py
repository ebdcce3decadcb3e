"""Python's cyclic garbage collector off while ``symsphere_path`` traces a render (a Dr.Jit 1.5 workaround).

Dr.Jit 1.5's LLVM backend names a callable by the hash of its body, but keeps the callables of calls with one
instance apart from those of calls with more (``GlobalType`` in drjit-core's ``globals_map``): a kernel in which
one method body is traced into a call while its class has one live instance and into another while it has more
(an emitter of an earlier scene not yet freed) defines that function twice, and ``jit_llvm_compile`` aborts the
process ("invalid redefinition of function 'func_...'").  The collector freeing an earlier scene between two
such calls of one render does that (after many renders in one process, with a scene of one emitter); with it
off while a render traces, the instances stay put.  Mitsuba's own ``prb`` and ``path`` abort the same way.
"""

from __future__ import annotations

import functools
import gc
import threading
from collections.abc import Callable
from typing import Any

__all__ = ["TRACING", "collector_paused"]

# the methods that trace a render's kernels: Mitsuba's render, render_forward and render_backward (each traces
# sample() and, the last two, a second pass of it into the same kernel), and sample() (called by aov, moment)
TRACING = ("render", "render_forward", "render_backward", "sample")
_PAUSE: list[Any] = [0, False]  # [paused methods running, whether the collector was on before the first]
_PAUSE_LOCK = threading.Lock()


def collector_paused(method: Callable[..., Any]) -> Callable[..., Any]:
    """*method* with Python's cyclic garbage collector off while it runs (this module's docstring says why)."""

    @functools.wraps(method)
    def paused(*args: Any, **kwargs: Any) -> Any:
        with _PAUSE_LOCK:  # nested calls and other threads' renders: on again after the last one only
            if not _PAUSE[0]:
                _PAUSE[1] = gc.isenabled()  # off already: the caller's choice, kept
                gc.disable()
            _PAUSE[0] += 1
        try:
            return method(*args, **kwargs)
        finally:
            with _PAUSE_LOCK:
                _PAUSE[0] -= 1
                if not _PAUSE[0] and _PAUSE[1]:
                    gc.enable()

    return paused
