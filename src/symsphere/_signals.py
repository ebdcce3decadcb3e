"""Signals, in one place: which ones end a run, and the two ways the package holds them back.

Python runs signal handlers in the main thread, between bytecodes, whichever thread the signal reached
(numba's and tqdm's threads included).  Two stretches of work must not be cut there:

- :func:`deferred`: code a Python exception must not cross (the renames that put a run's outputs in
  place, :mod:`symsphere.io`; importing Mitsuba, whose module initialisation runs Python inside C++).
  The signals are recorded, not handled, and go to their handlers once the block is over, also after an
  error in it (the signal is then what ended the run);
- :func:`kept`: a numba compile, which can swallow the exception a handler raises (it ended as "no
  compiled object yet").  The signals are handled as usual and also recorded; if the block then ends
  without the handler's exception, the handler runs again (:mod:`symsphere._threads`).

The command line's handlers (``symsphere.apps._process``: SIGINT as ``KeyboardInterrupt``, SIGTERM and
SIGHUP as its ``Terminated``) are what both hand the signals to.  Outside the main thread no handler runs,
so both are no-ops there.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from typing import Any

__all__ = ["INTERRUPTS", "deferred", "kept"]

INTERRUPTS = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))
"""The signals that end a run (those this platform has): SIGINT, SIGTERM, SIGHUP."""


@contextlib.contextmanager
def deferred() -> Iterator[None]:
    """Within the block (main thread): :data:`INTERRUPTS` are recorded, not handled; after it, each
    arrived one goes once to the handler it had (``KeyboardInterrupt`` for Python's default SIGINT
    handler; re-raised for the default action, which ends the process)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    arrived: list[int] = []
    previous = {signum: signal.signal(signum, lambda signum, frame: arrived.append(signum)) for signum in INTERRUPTS}
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        for signum in dict.fromkeys(arrived):  # also after an error in the block: the signal is what ended it
            handler = previous[signum]
            if callable(handler):
                handler(signum, None)
            elif handler == signal.SIG_DFL:
                signal.raise_signal(signum)


@contextlib.contextmanager
def kept() -> Iterator[None]:
    """Within the block (main thread): a signal with a Python handler is recorded as well as handled; if
    the block then raises anything but the handler's exception, or nothing, the handler runs again."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {signum: signal.getsignal(signum) for signum in INTERRUPTS}
    handlers = {signum: handler for signum, handler in previous.items() if callable(handler)}
    arrived: list[int] = []

    def record(signum: int, frame: Any) -> None:
        arrived.append(signum)
        handlers[signum](signum, frame)

    for signum in handlers:
        signal.signal(signum, record)
    try:
        yield
    except BaseException as error:
        for signum in handlers:
            signal.signal(signum, previous[signum])
        if arrived and not isinstance(error, KeyboardInterrupt):
            handlers[arrived[0]](arrived[0], None)  # the interrupt the block lost, instead of its error
        raise
    finally:
        for signum in handlers:
            signal.signal(signum, previous[signum])
    if arrived:
        handlers[arrived[0]](arrived[0], None)
