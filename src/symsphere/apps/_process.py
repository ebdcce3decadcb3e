"""The ``symsphere`` command as a process: signals, exit statuses, one-line errors, time estimates, clusters.

Every verb runs inside :func:`signals_as_interrupts`: SIGINT raises ``KeyboardInterrupt`` and SIGTERM,
SIGHUP :class:`Terminated` in the main thread, so that the same clean-up runs for each (the outputs'
temporaries are removed, nothing is written) and the command exits 130, 143 or 129.  :class:`Outputs`
tells a signal that arrived once the outputs were in place (then the run is a success).  Work that runs
outside Python (a Mitsuba render) is waited for by :func:`wait_interruptibly`, so that a signal is
handled within a fraction of a second there too.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from types import FrameType
from typing import Any, NoReturn, TypeVar

from .._signals import INTERRUPTS

__all__ = [
    "CLEAN_EXIT_SIGNALS",
    "DISTRIBUTED_EXTRA",
    "FASTEST_DIRECTIONS_PER_SECOND",
    "FASTEST_EVALUATIONS_PER_SECOND",
    "FASTEST_PATHS_PER_THREAD",
    "LONG_SECONDS",
    "Outputs",
    "Terminated",
    "UsageError",
    "abandoned_work",
    "add_allow_long",
    "add_cluster_options",
    "add_run_options",
    "check_duration",
    "check_pending",
    "close_client",
    "cluster_client",
    "describe_os_error",
    "distributed_module",
    "duration",
    "exit_now",
    "ignore_signals",
    "one_line",
    "raise_terminated",
    "signals_as_interrupts",
    "wait_interruptibly",
]

DISTRIBUTED_EXTRA = "symsphere[distributed]"
_T = TypeVar("_T")


class UsageError(Exception):
    """An invalid combination of arguments that argparse cannot express."""


class Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP, raised in the main thread like Ctrl-C, so that the same clean-up runs."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum


CLEAN_EXIT_SIGNALS = tuple(signum for signum in INTERRUPTS if signum != signal.SIGINT)
"""SIGTERM and SIGHUP (where the platform has them): raised as :class:`Terminated`."""


def raise_terminated(signum: int, frame: FrameType | None) -> NoReturn:
    if signum == signal.SIGINT:
        raise KeyboardInterrupt
    raise Terminated(signum)


class Outputs:
    """The files (or directory) a verb writes, and whether they are in place: a late signal then ends in success."""

    def __init__(self) -> None:
        self.paths: list[Path] = []
        self.before: list[tuple[int, int] | None] = []
        self.done = False

    def watch(self, paths: Sequence[str | os.PathLike[str]]) -> None:
        """Call just before the write: remember what is at *paths* now (followed through symbolic links)."""
        self.paths = [Path(p) for p in paths]
        self.before = [_identity(p) for p in self.paths]

    def complete(self) -> bool:
        """Whether the write has put every file in place (each name now points at a new file)."""
        if self.done:
            return True
        after = [_identity(p) for p in self.paths]
        return bool(self.paths) and all(a is not None and a != b for a, b in zip(after, self.before, strict=False))


def _identity(path: Path) -> tuple[int, int] | None:
    try:
        info = os.stat(path)
    except OSError:
        return None
    return info.st_dev, info.st_ino


LONG_SECONDS = 86400.0  # work estimated beyond a day needs --allow-long
FASTEST_DIRECTIONS_PER_SECOND = 1e9  # sample: 40x the 2.3e7/s measured to a file (docs/reliability.md)
FASTEST_EVALUATIONS_PER_SECOND = 1e9  # integrate: 17x the 59 M/s measured (docs/integration.md); then a pilot
FASTEST_PATHS_PER_THREAD = 1e7  # render: 4x the best 2.5 Mpaths/s per thread measured (docs/rendering.md)


def check_duration(seconds: float, what: str, args: argparse.Namespace) -> None:
    """Refuse work estimated beyond a day unless --allow-long was given (a usage error, before any work)."""
    if seconds > LONG_SECONDS and not args.allow_long:
        raise UsageError(f"{what} is estimated to take at least {duration(seconds)}; add --allow-long to run it anyway")


def add_allow_long(verb: argparse.ArgumentParser) -> None:
    verb.add_argument(
        "--allow-long", action="store_true",
        help="run even if the work is estimated to take more than a day (refused otherwise, before any work)",
    )  # fmt: skip


@contextlib.contextmanager
def signals_as_interrupts(pending: list[int]) -> Iterator[None]:
    """While the command runs, SIGINT raises KeyboardInterrupt and SIGTERM, SIGHUP Terminated (the main
    thread only: signal's rule), and every signal is also recorded in *pending*.

    Python runs a handler at any bytecode, also inside a callback from C (numba's compiler calls back into
    Python through ctypes), where the exception is printed as "Exception ignored" and dropped: the run went
    on and exited 0 with a traceback.  Such a lost interrupt stays in *pending*; :func:`check_pending` raises
    it again at the next safe point (each block written, the end of a render), and the unraisable-exception
    hook stays quiet about it.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, frame: FrameType | None) -> None:
        pending.append(signum)
        raise_terminated(signum, frame)

    def unraisable(report: sys.UnraisableHookArgs, previous_hook: Callable[..., object] = sys.unraisablehook) -> None:
        if not (isinstance(report.exc_type, type) and issubclass(report.exc_type, KeyboardInterrupt)):
            previous_hook(report)

    previous = {signum: signal.signal(signum, handler) for signum in INTERRUPTS}
    previous_hook, sys.unraisablehook = sys.unraisablehook, unraisable
    try:
        yield
    finally:
        sys.unraisablehook = previous_hook
        for signum, old in previous.items():
            signal.signal(signum, old)


def check_pending(args: argparse.Namespace) -> None:
    """Raise a signal that arrived but whose exception was lost (see signals_as_interrupts)."""
    if args.pending:
        raise_terminated(args.pending[0], None)


def add_run_options(verb: argparse.ArgumentParser, handler: Callable[[argparse.Namespace], int]) -> None:
    """Finish a verb whose work may be long or distributed: --allow-long, the cluster options, its handler."""
    add_allow_long(verb)
    add_cluster_options(verb)
    verb.set_defaults(handler=handler)


def add_cluster_options(verb: argparse.ArgumentParser) -> None:
    cluster = verb.add_mutually_exclusive_group()
    cluster.add_argument(
        "--workers", type=int, default=None, metavar="N",
        help=f"run on a local Dask cluster of N worker processes (needs {DISTRIBUTED_EXTRA})",
    )  # fmt: skip
    cluster.add_argument(
        "--scheduler", default=None, metavar="ADDRESS",
        help=f"run on the Dask cluster at ADDRESS (tcp://host:8786; needs {DISTRIBUTED_EXTRA})",
    )  # fmt: skip
    verb.add_argument(
        "--timeout", type=float, default=10.0, help="seconds to wait for the scheduler (default: %(default)s)"
    )


def cluster_client(args: argparse.Namespace) -> Any:  # a dask.distributed Client, or None
    """A Dask client for --workers / --scheduler, or None to run in this process."""
    if args.workers is None and args.scheduler is None:
        return None
    if not (math.isfinite(args.timeout) and args.timeout > 0):
        raise UsageError(f"--timeout must be a positive number of seconds, got {args.timeout}")
    option = "--workers" if args.scheduler is None else "--scheduler"
    try:  # the optional extra: say so, not with a traceback from deep inside symsphere.distributed
        import importlib

        for name in ("dask", "distributed"):
            importlib.import_module(name)  # function-level: dask is slow to import and optional
    except ModuleNotFoundError:
        raise UsageError(
            f"{option} needs Dask, which is not installed; install it with: pip install '{DISTRIBUTED_EXTRA}'"
        ) from None
    distributed = distributed_module()
    if args.scheduler is not None:
        return distributed.connect(args.scheduler, timeout=args.timeout)
    if args.workers < 1:
        raise UsageError(f"--workers must be a positive integer, got {args.workers}")
    return distributed.local_client(args.workers)


def close_client(client: Any) -> None:
    if client is not None:
        distributed_module().close_client(client)


def distributed_module() -> Any:  # Any while symsphere.distributed is not annotated (its mypy override)
    from .. import distributed  # function-level: dask is slow to import and optional

    return distributed


def exit_now(status: int, argv: Sequence[str] | None) -> int:
    """Run as the program (no *argv*) after an interrupt: exit with *status* now.  The interpreter's own
    exit could still die by the signal (the audit once saw exit -2 after this line was printed, an
    interrupt having been dropped inside a numba callback); everything of ours is already cleaned up."""
    if argv is None:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(status)
    return status


def ignore_signals() -> None:
    for signum in INTERRUPTS:
        signal.signal(signum, signal.SIG_IGN)


def one_line(exc: object) -> str:
    text = " ".join(str(exc).split())
    return text if len(text) <= 500 else text[:480] + " ..."


def duration(seconds: float) -> str:
    for unit, size in (("days", 86400.0), ("hours", 3600.0), ("minutes", 60.0)):
        if seconds >= 2 * size:
            return f"{seconds / size:.3g} {unit}"
    return f"{seconds:.3g} s"


def describe_os_error(exc: OSError) -> str:
    if exc.filename is not None and exc.strerror:
        return f"cannot write {exc.filename!s}: {exc.strerror}"
    return str(exc)


def wait_interruptibly(work: Callable[[], _T], poll: float = 0.05) -> _T:
    """``work()`` in a second (daemon) thread while this one waits, waking every *poll* seconds.

    Mitsuba's loader and Dr.Jit's kernel launches run in C++ with the GIL released, and a Python signal
    handler runs only when the main thread executes bytecode: waited for here, a SIGINT or SIGTERM raises
    in this thread within *poll* seconds, where the call itself would have ignored it to its end.  The
    abandoned call finishes in its thread (or dies with the process: the command exits at once after an
    interrupt); its result is dropped.  An exception of *work* is raised here.
    """
    if threading.current_thread() is not threading.main_thread():
        return work()
    outcome: list[Any] = []

    def run() -> None:
        try:
            outcome.append((True, work()))
        except BaseException as error:  # handed to the waiting thread
            outcome.append((False, error))

    thread = threading.Thread(target=run, name=_WAIT_THREAD, daemon=True)
    thread.start()
    while thread.is_alive():
        thread.join(poll)
    ok, value = outcome[0]
    if not ok:
        raise value
    return value  # type: ignore[no-any-return]


_WAIT_THREAD = "symsphere-wait"


def abandoned_work() -> bool:
    """Whether a call of :func:`wait_interruptibly` is still running in its thread (abandoned on a signal)."""
    return any(thread.name == _WAIT_THREAD and thread.is_alive() for thread in threading.enumerate())
