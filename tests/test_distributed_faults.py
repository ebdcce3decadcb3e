"""A Dask worker killed *while it is inside a task* (not after a sleep): it dies, the nanny replaces it,
the lost tasks are rerun, and the results are bit-identical to an undisturbed run.

The task announces that it has started by creating a file (atomically, ``O_EXCL``: only the first task
to start does) holding its worker's process id, and then waits until it is killed (or released by the
test, should the test fail first); the test kills exactly that process with SIGKILL.  A rerun finds the
file and does not wait.

Under load (a shared CI machine: the workers start, import and compile slowly) the waits scale with the
load average, and the workers compile their kernels before the run, so that the first task starts soon
and stays inside the task until the kill: what is checked does not depend on timing.
"""

from __future__ import annotations

import os
import signal
import threading
import time

import numpy as np
import pytest

import symsphere
from symsphere.points import BLOCK

pytest.importorskip("distributed")
from symsphere import distributed as ss_distributed

A = np.array([0.7, -0.4, 0.5])

# Local Dask clusters (worker processes): on one xdist worker, one at a time (Makefile: --dist loadgroup).
pytestmark = pytest.mark.xdist_group("dask")


def _scaled(seconds):
    """*seconds* stretched by how overloaded the machine is (1-minute load average per core, at least 1)."""
    return seconds * max(1.0, os.getloadavg()[0] / (os.cpu_count() or 1))


def _announcing(marker):
    """A function for the workers (a closure: cloudpickle sends it by value) that the first caller
    announces in *marker* and then blocks in until it is killed, or until the test creates
    ``marker + '.release'`` (a failing test), or for 15 minutes; later callers pass straight through."""
    release = marker + ".release"

    def announce_and_wait():
        try:
            descriptor = os.open(marker, os.O_WRONLY | os.O_CREAT | os.O_EXCL)
        except FileExistsError:
            return
        os.write(descriptor, str(os.getpid()).encode())
        os.close(descriptor)
        deadline = time.monotonic() + 900
        while time.monotonic() < deadline and not os.path.exists(release):  # killed in here
            time.sleep(0.01)

    return announce_and_wait


def _warm_up():
    """Import and compile (or load from the cache) the kernels the tasks use, in a worker."""
    import symsphere

    for dtype in (np.float32, np.float64):
        symsphere.sample_sphere(48, rng=1, dtype=dtype)
    symsphere.integrate(lambda d: d[:, 0], n=48, rng=1)
    return os.getpid()


def _wait_for_pid(marker, runner, outcome, timeout=180.0):
    started = time.monotonic()
    timeout = _scaled(timeout)
    deadline = started + timeout
    while time.monotonic() < deadline:
        if not runner.is_alive():
            raise AssertionError(f"the run ended before a task announced itself: {outcome}")
        try:
            text = open(marker).read()
        except FileNotFoundError:
            text = ""
        if text:
            return int(text)
        time.sleep(0.01)
    raise AssertionError(
        f"no task started within {timeout:.0f} s (load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)"
    )


def _worker_pids(client):
    return set(client.run(os.getpid).values())


def _run_while_killing(client, marker, work):
    """Run work() in a thread; kill the worker that announces itself in *marker*; return work()'s result."""
    outcome = {}

    def target():
        try:
            outcome["result"] = work()
        except BaseException as exc:  # handed to the test thread
            outcome["error"] = exc

    before = _worker_pids(client)
    runner = threading.Thread(target=target, daemon=True)
    runner.start()
    try:
        pid = _wait_for_pid(marker, runner, outcome)
        assert pid in before  # a worker process, inside a task
        os.kill(pid, signal.SIGKILL)
    finally:
        open(f"{marker}.release", "w").close()  # no task waits any longer (a rerun would not wait anyway)
    runner.join(timeout=_scaled(300))
    assert not runner.is_alive()
    if "error" in outcome:
        raise outcome["error"]
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)  # it died
    deadline = time.monotonic() + _scaled(120)
    while len(_worker_pids(client)) < len(before) and time.monotonic() < deadline:
        time.sleep(0.1)
    after = _worker_pids(client)
    assert len(after) == len(before) and pid not in after  # replaced by a new process
    return outcome["result"]


@pytest.fixture
def client():
    client = ss_distributed.local_client(2)
    client.run(_warm_up)  # every worker compiles before the run: the first task starts soon
    yield client
    ss_distributed.close_client(client)


@pytest.mark.slow
def test_worker_killed_inside_an_integrate_task(client, tmp_path):
    wait = _announcing(str(tmp_path / "started"))

    def f(d):
        wait()
        return np.exp(d @ A)

    kwargs = dict(n=48 * BLOCK * 6, rng=11)
    result = _run_while_killing(
        client, tmp_path / "started", lambda: ss_distributed.integrate(f, client=client, chunk_blocks=1, **kwargs)
    )
    undisturbed = symsphere.integrate(lambda d: np.exp(d @ A), **kwargs)
    assert np.array_equal(result.integral, undisturbed.integral)
    assert np.array_equal(result.standard_error, undisturbed.standard_error)


@pytest.mark.slow
def test_worker_killed_inside_a_sample_sphere_task(client, tmp_path):
    wait = _announcing(str(tmp_path / "started"))

    def announce(block):
        if block.size:  # not dask's probe with an empty array, in this process
            wait()
        return block

    n = 48 * BLOCK * 4
    array = ss_distributed.sample_sphere(n, chunks=48 * BLOCK, rng=12, dtype=np.float32)
    # The announcing step runs on each chunk; dask fuses it into the chunk's task, so the kill lands inside
    # the task that computed (or holds) the directions, which must be computed again.
    watched = array.map_blocks(announce, dtype=array.dtype, meta=np.empty((0, 3), dtype=array.dtype))
    result = _run_while_killing(client, tmp_path / "started", lambda: client.compute(watched).result())
    assert np.array_equal(result, symsphere.sample_sphere(n, rng=12, dtype=np.float32))
    assert np.array_equal(client.compute(array).result(), result)


def _exits_the_worker(directions):
    os._exit(3)  # the integrand ends its process: a crash, the OOM killer, a library calling exit()


def test_a_worker_dying_inside_f_is_a_clear_error():
    # Dask reported "FutureCancelledError: ... cancelled for reason: already forgotten" (the plan scattered
    # to the dead worker went with it), naming neither the cause nor f.
    client = ss_distributed.local_client(1)
    try:
        with pytest.raises(RuntimeError, match=r"^a Dask worker's process ended while evaluating 'f' \(os._exit"):
            ss_distributed.integrate(_exits_the_worker, n=48 * 64, rng=1, client=client)
    finally:
        ss_distributed.close_client(client)
