"""symsphere._threads: numba's threads wait passively; importing and sampling leave os.environ alone."""

import os
import signal
import subprocess
import sys
import threading
from pathlib import Path

import numba
import numpy as np
import pytest

import symsphere

PROBE = """
import os, json
before = dict(os.environ)
import symsphere
after_import = dict(os.environ)
symsphere.sample_sphere(48)
after_sampling = dict(os.environ)
print(json.dumps([after_import == before, after_sampling == before, os.environ.get("OMP_WAIT_POLICY")]))
"""


@pytest.mark.parametrize("preset", [None, "active"])
def test_threads_wait_passively_unless_the_user_says_otherwise_and_environ_is_untouched(preset):
    # Spinning OpenMP threads starve numpy's BLAS threads (docs/explanation/design.md, "Threads"): the kernels start
    # numba's threads with OMP_WAIT_POLICY=passive unless the user set it, and put os.environ back.
    env = {k: v for k, v in os.environ.items() if k != "OMP_WAIT_POLICY"}
    env["OMP_DISPLAY_ENV"] = "true"  # libgomp prints the settings it took, when it is loaded
    if preset:
        env["OMP_WAIT_POLICY"] = preset
    result = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    import json

    unchanged_by_import, unchanged_by_sampling, policy = json.loads(result.stdout.splitlines()[-1])
    assert unchanged_by_import and unchanged_by_sampling
    assert policy == preset
    if numba.config.THREADING_LAYER in ("default", "omp") and "OPENMP DISPLAY ENVIRONMENT" in result.stderr:
        assert f"OMP_WAIT_POLICY = '{(preset or 'passive').upper()}'" in result.stderr


COMPILE_THREADS = """
import json, threading
from numba.core import event
import symsphere

threads = set()


class Listener(event.Listener):
    def on_start(self, e):
        threads.add(threading.current_thread() is threading.main_thread())

    def on_end(self, e):
        pass


with event.install_listener("numba:compile", Listener()):
    symsphere.sample_sphere(48 * 4096, rng=1)  # the parts run on two threads
    symsphere.sample_hemisphere(24 * 4096, normal=[0, 1, 0], dtype="float32", rng=1)
print(json.dumps(sorted(threads)))
"""


def test_kernels_compile_in_the_calling_thread_never_on_the_pool(tmp_path):
    # A Ctrl-C during a first run's compile raises KeyboardInterrupt in the main thread only: had a pool
    # thread been compiling the same kernel, it could be left with a half-built library (seen as "no
    # compiled object yet" errors and a hung process).  So run_kernel compiles before the parts start,
    # and the library's kernels go through it (the two tests below); here, end to end, every compile of
    # a first sampling run (empty cache, two parts) is reported by numba in the main thread.
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path), NUMBA_NUM_THREADS="2")
    result = subprocess.run(
        [sys.executable, "-c", COMPILE_THREADS], env=env, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    import json

    assert json.loads(result.stdout.splitlines()[-1]) == [True]  # compiles happened, all in the main thread


class _ProbeKernel:
    """A dispatcher stand-in: records where it is compiled, and refuses a call before it is."""

    def __init__(self):
        self.compiled_in = []
        self.calls = []

    def compile(self, signature):
        self.compiled_in.append((threading.current_thread() is threading.main_thread(), signature))

    def __call__(self, *args):
        assert self.compiled_in, "a part ran before the kernel was compiled"
        self.calls.append(args)


def test_run_kernel_compiles_in_the_calling_thread_before_any_part():
    from numba import types

    from symsphere._testing import threads

    kernel = _ProbeKernel()
    values = np.zeros(4)
    threads.run_kernel(kernel, lambda index: (values, index), 3)
    assert kernel.compiled_in == [(True, (types.float64[::1], types.int64))]
    assert sorted(index for _, index in kernel.calls) == [0, 1, 2]


def test_run_kernel_checks_the_compile_once_per_argument_types():
    # A launch with arguments of types seen before skips the compile check (numba.typeof of every
    # argument); new types are compiled again, in the calling thread; arguments without a faithful
    # fingerprint (an unaligned array, a dispatcher) are checked at every launch.
    import numba
    from numba import types

    from symsphere._testing import threads

    kernel = _ProbeKernel()
    values = np.zeros(4)
    threads.run_kernel(kernel, lambda index: (values, index), 2)
    threads.run_kernel(kernel, lambda index: (np.ones(4), index + 7), 2)  # the same types
    assert kernel.compiled_in == [(True, (types.float64[::1], types.int64))]
    threads.run_kernel(kernel, lambda index: (values.astype(np.float32), index), 2)
    threads.run_kernel(kernel, lambda index: (values[::2], index), 2)
    assert kernel.compiled_in[1:] == [
        (True, (types.float32[::1], types.int64)),
        (True, (types.float64[:], types.int64)),
    ]
    unaligned = np.frombuffer(bytearray(33), dtype=np.uint8)[1:].view(np.float64)
    assert not unaligned.flags.aligned
    function = numba.njit(lambda x: x)
    big = 2**63  # numba: uint64, though its fingerprint is that of an int64
    for value in (unaligned, unaligned, function, function, big, big, (1, big), (1, big)):
        threads.run_kernel(kernel, lambda index, value=value: (value, index), 2)
    assert len(kernel.compiled_in) == 3 + 8
    assert kernel.compiled_in[7] == (True, (types.uint64, types.int64))
    assert len(kernel.calls) == 2 * 12


def test_the_library_runs_its_kernels_through_run_kernel():
    # run_parts with a kernel inside the task would let a pool thread compile it
    source = Path(symsphere.__file__).parent
    callers = [p.relative_to(source) for p in source.rglob("*.py") if "run_parts(" in p.read_text(encoding="utf-8")]
    assert callers == [Path("_threads.py")], callers


def test_run_kernel_compiles_once_for_the_parts_signature():
    from numba import njit

    from symsphere._testing import threads

    @njit(nogil=True)
    def add_one(values, lo, hi):  # pragma: no cover - compiled by numba
        for i in range(lo, hi):
            values[i] += 1.0

    values = np.zeros(10)
    threads.run_kernel(add_one, lambda index: (values, 5 * index, 5 * index + 5), 2)
    assert np.array_equal(values, np.ones(10))
    assert len(add_one.signatures) == 1  # the signature run_kernel compiled is the one the parts call


class _SwallowingKernel(_ProbeKernel):
    """Compiles as numba did when a SIGINT came during one of its LLVM callbacks: the interrupt is lost
    inside the callback (C code swallows Python exceptions) and the compile fails afterwards."""

    def __init__(self, fail):
        super().__init__()
        self.fail = fail

    def compile(self, signature):
        try:
            signal.raise_signal(signal.SIGINT)  # KeyboardInterrupt, raised inside the "callback" ...
        except KeyboardInterrupt:
            pass  # ... and lost there
        if self.fail:
            raise RuntimeError("no compiled object yet for <Library 'fill'>")
        super().compile(signature)


@pytest.mark.usefixtures("python_sigint_handler")  # Python's own handler, whatever the worker's
@pytest.mark.parametrize("fail", [True, False], ids=["compile-failed", "compile-finished"])
def test_a_sigint_lost_inside_the_compile_still_interrupts(fail):
    from symsphere._testing import threads

    kernel = _SwallowingKernel(fail)
    with pytest.raises(KeyboardInterrupt):
        threads.run_kernel(kernel, lambda index: (np.zeros(2), index), 2)
    assert kernel.calls == []  # no part ran
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # the handler is back


def _package_dispatchers():
    """Every numba function the package defines, found in its modules' namespaces (one level of containers
    too), with where it was found."""
    import importlib
    import pkgutil

    from numba.core.dispatcher import Dispatcher

    found = {}
    for info in pkgutil.walk_packages(symsphere.__path__, "symsphere."):
        if ".mitsuba" in info.name or info.name.endswith("__main__"):  # Dr.Jit, not numba; the entry point
            continue
        module = importlib.import_module(info.name)
        for name, value in vars(module).items():
            items = (
                value.values() if isinstance(value, dict) else value if isinstance(value, (tuple, list)) else [value]
            )
            for item in items:
                if isinstance(item, Dispatcher) and item.py_func.__module__.startswith("symsphere."):
                    found.setdefault(id(item), (item, f"{info.name}.{name}"))
    return list(found.values())


def test_every_numba_function_of_the_package_compiles_on_the_interruptible_path():
    from symsphere._testing import threads

    dispatchers = _package_dispatchers()
    assert len(dispatchers) >= 30  # the kernels, the validation, the renderer's parts ...
    unrouted = sorted(where for dispatcher, where in dispatchers if not getattr(dispatcher, threads.ROUTED, False))
    assert not unrouted, f"add route_compiles(globals()) to the modules of {unrouted}"


@pytest.mark.usefixtures("python_sigint_handler")  # Python's own handler, whatever the worker's
@pytest.mark.parametrize("fail", [True, False], ids=["compile-failed", "compile-finished"])
def test_a_sigint_lost_in_the_first_compile_of_a_routed_function_still_interrupts(fail):
    # The validation kernel of symsphere.io compiled at its first call, not in run_kernel: a Ctrl-C lost
    # in numba's LLVM callback ended as "RuntimeError: no compiled object yet" (exit 1, seen once).
    from numba import njit

    from symsphere._testing import threads

    @njit
    def twice(x):  # pragma: no cover - compiled by numba
        return 2 * x

    real = twice._compile_for_args

    def swallowing(*args, **kws):  # as numba's compile when the SIGINT came inside an LLVM callback
        try:
            signal.raise_signal(signal.SIGINT)
        except KeyboardInterrupt:
            pass
        if fail:
            raise RuntimeError("no compiled object yet for <Library '_first_non_unit_row'>")
        return real(*args, **kws)

    twice._compile_for_args = swallowing
    threads.route(twice)
    with pytest.raises(KeyboardInterrupt):
        twice(21)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # the handler is back

    @njit
    def thrice(x):  # pragma: no cover - compiled by numba
        return 3 * x

    assert threads.route(threads.route(thrice)) is thrice and thrice(14) == 42  # idempotent; no signal, no change
