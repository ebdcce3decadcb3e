"""Compile a kernel's parts in two processes when numba's disk cache is cold.

numba compiles in one thread.  A kernel built from cached numba functions that LLVM
inlines into it (the renderer's: ``symsphere.render._emitters.INLINED``) compiles those
parts one after another on its first run.  :func:`compile_ahead` compiles one group of
parts in a second Python process, into the disk cache, while this process compiles the
other group; numba looks in the cache before it compiles a function, so the kernel's own
compile then loads the second group from there.  What is loaded is what this process
would have compiled (numba caches a function's machine code with its LLVM bitcode, which
is what LLVM inlines), so the kernel is the same; the tests compare images bit for bit.

Nothing happens when the kernel is in the cache already (every run after the first), on
one core, or with caching off.  The second process is only a speed-up: if it fails, is
killed or takes longer than *timeout*, this process compiles what is missing itself.
Nothing happens at import.

:func:`start_in_background` is the same idea for a whole job: a second process runs a
function that fills the cache (the renderer's :func:`symsphere.render.renderer.warm_up`)
while this one does other work, and :func:`finish` waits for it before the work that
needs the cache (``symsphere demo`` renders last).
"""

from __future__ import annotations

import importlib
import os
import signal
import subprocess
import sys
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from ._threads import compile_interruptibly

__all__ = ["cached_signatures", "compile_ahead", "finish", "is_cached", "start_in_background"]

Parts = Mapping[str, tuple[Any, tuple[Any, ...]]]
"""name -> (numba dispatcher with ``cache=True``, its argument types)."""


def is_cached(dispatcher: Any) -> bool:
    """Whether numba's disk cache holds an entry of *dispatcher* for its current source (any signature).

    False if it is not cached at all (``cache=False``, or no writable cache location).
    """
    return bool(_index(dispatcher))


def cached_signatures(dispatcher: Any) -> list[str]:
    """The argument types (as text, sorted) of *dispatcher*'s entries in numba's disk cache for its current
    source: what a process that calls it would load (a part compiled for other types shows here too)."""
    return sorted(str(key[0]) for key in _index(dispatcher))


def _index(dispatcher: Any) -> dict[Any, Any]:
    """numba's cache index of *dispatcher*: {(argument types, target, code hashes): entry}, {} if none."""
    index = getattr(getattr(dispatcher, "_cache", None), "_cache_file", None)
    if index is None:
        return {}
    try:
        return dict(index._load_index())  # {} when missing, or stale (another source stamp)
    except (OSError, EOFError, ValueError):
        return {}


def compile_ahead(
    kernel: Any,
    module: str,
    here: Sequence[str],
    there: Sequence[str],
    timeout: float = 300.0,
    parts: Parts | None = None,
) -> None:
    """Before *kernel*'s first compile on a cold cache: its parts *there* in a second process, *here* in this one.

    Parameters
    ----------
    kernel : numba dispatcher
        The kernel that calls the parts; nothing is done if it is cached already.
    module : str
        The module whose ``kernel_parts()`` returns the parts (:data:`Parts`); the second
        process imports it.
    here, there : sequence of str
        Names of the parts compiled in this process and in the second one.
    timeout : float
        Seconds to wait for the second process after this one's parts are done.
    parts : Parts, optional
        The parts compiled here, if not the module's ``kernel_parts()`` (for a kernel specialised
        on its arguments: the types this call needs; the second process takes the module's).
    """
    if len(there) == 0 or is_cached(kernel) or _cpus() < 2:
        return
    helper = _start(module, *there)
    if helper is None:
        return  # no second process: this one compiles everything, as without this module
    try:
        _compile_parts(module, here, compile_interruptibly, parts)
    except BaseException:  # an error or Ctrl-C here: stop the second process at once
        finish(helper, 0.0)
        raise
    finish(helper, timeout)  # the kernel's compile then loads what is cached and compiles the rest


def start_in_background(module: str, function: str) -> subprocess.Popen[bytes] | None:
    """Run ``module.function()`` (no arguments) in a second Python process, to fill the disk cache.

    Returns the process, for :func:`finish`; None (nothing started) on one core or if no
    process can start.  Its output is discarded, and its failure only means that this
    process compiles what it needs itself.
    """
    if _cpus() < 2:
        return None
    return _start("--call", module, function, own_group=True)  # with any process it starts (finish)


def finish(helper: subprocess.Popen[bytes], timeout: float = 300.0) -> None:
    """Wait up to *timeout* seconds for a second process, then stop it if it still runs.

    A job of :func:`start_in_background` is stopped with the processes it started (its own
    process group: a cold render starts a second compiling process of its own).
    """
    try:
        helper.wait(timeout)
    except subprocess.TimeoutExpired:
        pass
    finally:
        if helper.poll() is None:
            group = getattr(os, "killpg", None) is not None and _leads_group(helper.pid)
            if group:
                os.killpg(helper.pid, signal.SIGKILL)
            else:
                helper.kill()
            helper.wait()


def _leads_group(pid: int) -> bool:
    try:
        return os.getpgid(pid) == pid
    except OSError:
        return False


def _start(*arguments: str, own_group: bool = False) -> subprocess.Popen[bytes] | None:
    """``python -m symsphere._compile_ahead ARGUMENTS`` with this very package first on the path; with
    *own_group*, in a new session (its own process group, which Ctrl-C in the terminal does not reach:
    the caller stops it)."""
    package = Path(__file__).resolve().parents[1]
    environment = dict(os.environ)
    environment["PYTHONPATH"] = os.pathsep.join(filter(None, [str(package), environment.get("PYTHONPATH")]))
    try:
        return subprocess.Popen(
            [sys.executable, "-m", __name__, *arguments],
            env=environment,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=own_group and os.name == "posix",
        )
    except OSError:
        return None


def _cpus() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _compile_parts(
    module: str, names: Sequence[str], compile: Callable[[Any, tuple[Any, ...]], None], parts: Parts | None = None
) -> None:
    found: Parts = importlib.import_module(module).kernel_parts() if parts is None else parts
    for name in names:
        dispatcher, signature = found[name]
        compile(dispatcher, signature)


def _main(argv: Sequence[str]) -> int:
    """``python -m symsphere._compile_ahead MODULE NAME...``: compile those parts into the disk cache;
    ``... --call MODULE FUNCTION``: run ``MODULE.FUNCTION()``."""
    if argv[0] == "--call":
        getattr(importlib.import_module(argv[1]), argv[2])()
        return 0
    module, *names = argv
    _compile_parts(module, names, lambda dispatcher, signature: dispatcher.compile(signature))
    return 0


if __name__ == "__main__":
    sys.exit(_main(sys.argv[1:]))
