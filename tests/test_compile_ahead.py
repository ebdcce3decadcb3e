"""symsphere._compile_ahead: a kernel's parts compiled in a second process on a cold cache."""

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from symsphere._testing import compile_ahead as C

TOY = """
from numba import njit, types


@njit(cache=True)
def first(x):
    return x + 1.0


@njit(cache=True)
def second(x):
    return 2.0 * x


@njit(cache=True)
def kernel(x):
    return first(x) + second(x)


def kernel_parts():
    return {"first": (first, (types.float64,)), "second": (second, (types.float64,))}


def warm():
    kernel(1.0)


def spawn_and_wait():  # a job that starts a process of its own (as a cold render does), then blocks
    import os, signal, subprocess, sys

    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(120)"])
    with open(os.environ["TOY_CHILD_PID"] + ".tmp", "w") as f:
        f.write(str(child.pid))
    os.replace(os.environ["TOY_CHILD_PID"] + ".tmp", os.environ["TOY_CHILD_PID"])
    signal.pause()
"""

two_cpus = pytest.mark.skipif(C._cpus() < 2, reason="compile_ahead needs two CPUs (it does nothing on one)")


@pytest.fixture
def toy(tmp_path, monkeypatch):
    # A module of its own (a fresh file: numba caches it next to its source, or under NUMBA_CACHE_DIR by
    # its path), importable by this process and by the second one (PYTHONPATH).
    name = f"toy_parts_{os.getpid()}_{abs(hash(str(tmp_path))) % 10**8}"
    (tmp_path / f"{name}.py").write_text(textwrap.dedent(TOY))
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(tmp_path), os.environ.get("PYTHONPATH")])))
    import importlib

    module = importlib.import_module(name)
    yield module
    sys.modules.pop(name, None)


@two_cpus
def test_the_second_process_fills_the_cache_with_its_parts_and_this_one_compiles_the_others(toy):
    assert not C.is_cached(toy.kernel) and not C.is_cached(toy.second)
    C.compile_ahead(toy.kernel, toy.__name__, ["first"], ["second"])
    assert C.is_cached(toy.second)  # written by the second process: this one never compiled it
    assert toy.second.signatures == [] and len(toy.first.signatures) == 1
    assert toy.kernel(1.0) == 4.0
    assert toy.second.stats.cache_hits  # the kernel's compile loaded it from the disk cache
    assert not C.is_cached(toy.kernel) or toy.kernel.stats.cache_misses  # the kernel compiled here


@two_cpus
def test_a_failing_second_process_changes_nothing_but_time(toy):
    C.compile_ahead(toy.kernel, toy.__name__, ["first"], ["no_such_part"])  # the helper exits with KeyError
    assert len(toy.first.signatures) == 1 and not C.is_cached(toy.second)
    assert toy.kernel(1.0) == 4.0  # compiles what is missing itself


@two_cpus
def test_a_second_process_past_its_timeout_is_killed(toy, monkeypatch):
    started = []
    real = subprocess.Popen

    def popen(*args, **kwargs):
        helper = real([sys.executable, "-c", "import time; time.sleep(60)"], **kwargs)
        started.append(helper)
        return helper

    monkeypatch.setattr(subprocess, "Popen", popen)
    C.compile_ahead(toy.kernel, toy.__name__, ["first"], ["second"], timeout=0.5)
    assert started and started[0].returncode is not None  # killed and reaped, not left running
    assert toy.kernel(1.0) == 4.0


def test_nothing_happens_for_a_cached_kernel_or_on_one_cpu(toy, monkeypatch):
    calls = []
    monkeypatch.setattr(subprocess, "Popen", lambda *a, **k: calls.append(a))
    monkeypatch.setattr(C, "_cpus", lambda: 1)
    C.compile_ahead(toy.kernel, toy.__name__, ["first"], ["second"])
    assert calls == [] and toy.first.signatures == []
    monkeypatch.setattr(C, "_cpus", lambda: 2)
    toy.kernel(1.0)  # now in the cache
    C.compile_ahead(toy.kernel, toy.__name__, ["first"], ["second"])
    assert calls == []


def test_is_cached_is_false_for_an_uncached_dispatcher():
    from numba import njit

    @njit
    def f(x):
        return x

    assert not C.is_cached(f) and not C.is_cached(len)


# --- a whole job in the background (start_in_background, finish: symsphere demo's render) -------------


@two_cpus
def test_a_background_job_fills_the_cache_and_this_process_loads_it(toy):
    helper = C.start_in_background(toy.__name__, "warm")
    assert helper is not None
    C.finish(helper, 120.0)
    assert helper.returncode == 0 and C.is_cached(toy.kernel)
    assert toy.kernel(1.0) == 4.0
    assert toy.kernel.stats.cache_hits and not toy.kernel.stats.cache_misses  # loaded, not compiled here


@two_cpus
def test_a_failing_or_endless_background_job_is_reaped(toy):
    failing = C.start_in_background(toy.__name__, "no_such_function")
    C.finish(failing, 120.0)
    assert failing.returncode not in (0, None)  # AttributeError in the second process, nothing here
    endless = C.start_in_background("signal", "pause")  # blocks until a signal
    C.finish(endless, 0.5)
    assert endless.returncode is not None  # killed and reaped, not left running
    assert toy.kernel(1.0) == 4.0


def test_no_background_job_on_one_cpu(toy, monkeypatch):
    monkeypatch.setattr(C, "_cpus", lambda: 1)
    assert C.start_in_background(toy.__name__, "warm") is None


@two_cpus
@pytest.mark.skipif(not hasattr(os, "killpg"), reason="process groups are POSIX")
def test_stopping_a_background_job_stops_the_processes_it_started(toy, tmp_path, monkeypatch):
    import time

    marker = tmp_path / "child.pid"
    monkeypatch.setenv("TOY_CHILD_PID", str(marker))
    helper = C.start_in_background(toy.__name__, "spawn_and_wait")
    deadline = time.monotonic() + 60
    while not marker.exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    child = int(marker.read_text())
    C.finish(helper, 0.0)
    assert helper.returncode is not None
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            os.kill(child, 0)
        except ProcessLookupError:
            break  # gone (killed with its group, and reaped)
        if Path("/proc/self/stat").exists():  # Linux: a zombie (killed, not yet reaped) is gone too
            try:
                state = Path(f"/proc/{child}/stat").read_text().rsplit(")", 1)[1].split()[0]
            except OSError:
                break  # gone between the two looks
            if state == "Z":
                break
        time.sleep(0.05)
    else:
        pytest.fail(f"the job's own process {child} outlived the job")
