"""One line on stderr while numba compiles a kernel for the first time (a new install's first run).

numba broadcasts a ``"numba:compile"`` event only when it really compiles (a kernel
loaded from its on-disk cache broadcasts none: ``numba.core.event``), so the line
appears on the first run after an install, or after an upgrade, and never when the
cache is warm.  It is printed once, and only if a compilation is still running after
*delay* seconds, so that short compilations stay silent.
"""

from __future__ import annotations

import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, TextIO

from numba.core import event

__all__ = ["compile_notice"]


class _Notice(event.Listener):
    def __init__(self, line: str, stream: TextIO, delay: float) -> None:
        self._line, self._stream, self._delay = line, stream, delay
        self._lock = threading.Lock()
        self._depth = 0
        self._timer: threading.Timer | None = None
        self.said = False

    def _say(self) -> None:
        with self._lock:
            if self.said or self._depth == 0:
                return
            self.said = True
        print(self._line, file=self._stream, flush=True)

    def on_start(self, event: Any) -> None:
        with self._lock:
            self._depth += 1
            if self._depth == 1 and not self.said:
                self._timer = threading.Timer(self._delay, self._say)
                self._timer.daemon = True
                self._timer.start()

    def on_end(self, event: Any) -> None:
        with self._lock:
            self._depth -= 1
            if self._depth == 0 and self._timer is not None:
                self._timer.cancel()
                self._timer = None

    def close(self) -> None:
        with self._lock:
            self._depth = 0
            if self._timer is not None:
                self._timer.cancel()
                self._timer = None


@contextmanager
def compile_notice(prog: str, stream: TextIO | None = None, delay: float = 0.5) -> Iterator[None]:
    """Within the block, say once on *stream* (default stderr) that kernels are compiling, if one takes > *delay* s.

    Examples
    --------
    >>> import io
    >>> from numba import njit
    >>> from symsphere.apps._notices import compile_notice
    >>> stream = io.StringIO()
    >>> with compile_notice("demo", stream, delay=0.0):
    ...     _ = njit(lambda x: x + 1)(1)
    >>> "compiling" in stream.getvalue()
    True
    """
    line = f"{prog}: compiling numba kernels - first run after install, cached for next time ..."
    notice = _Notice(line, sys.stderr if stream is None else stream, delay)
    event.register("numba:compile", notice)  # type: ignore[no-untyped-call]  # numba is untyped
    try:
        yield
    finally:
        event.unregister("numba:compile", notice)  # type: ignore[no-untyped-call]
        notice.close()
