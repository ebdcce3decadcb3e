"""Dask scale-out: bit-identical to the single-process results, any chunking, a killed worker.

A Dask worker killed *while it is inside a task* (not after a sleep): it dies, the nanny replaces it,
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
import warnings

import numpy as np
import pytest
from numba import njit
from references import scaled_for_load

import symsphere
from symsphere.points import BLOCK

distributed = pytest.importorskip("distributed")
from symsphere import distributed as ss_distributed  # noqa: E402

A = np.array([0.7, -0.4, 0.5])

# Local Dask clusters (worker processes): on one xdist worker, one at a time (Makefile: --dist loadgroup).
pytestmark = pytest.mark.xdist_group("dask")


def test_the_cluster_tests_run_on_one_xdist_worker(request):
    """--dist loadgroup (Makefile) keeps this module's local clusters on one worker, one at a time."""
    if not getattr(request.config.option, "loadgroup", False):
        pytest.skip("not run by pytest-xdist with --dist loadgroup")
    # xdist marks a grouped test's node id with its group; pytest 9.2's structured ids lost the mark and the
    # groups were silently ignored (pytest-dev/pytest-xdist#1386): pyproject pins pytest < 9.2
    assert request.node.nodeid.endswith("@dask"), request.node.nodeid


def exp_dot(w):
    return np.exp(w @ A)


def slow_exp_dot(w):
    time.sleep(0.15)  # long enough to kill a worker in the middle of the run
    return np.exp(w @ A)


@pytest.fixture
def client(dask_client):
    return dask_client  # the session's cluster of 2 workers (tests/conftest.py)


def _same(a, b):
    return np.array_equal(a.integral, b.integral) and np.array_equal(a.standard_error, b.standard_error)


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(n=48 * BLOCK * 5 + 48 * 17, rng=1),
        dict(n=48 * 8 * 2**12, points="sobol", rng=2),
        dict(n=48 * 8 * 48**2, points="stratified", rng=3, method="paper1"),
        dict(n=24 * BLOCK * 3, domain="hemisphere", normal=[0.2, 0.3, -0.9], rng=4, method="paper2"),
    ],
)
def test_integrate_equals_single_process(client, kwargs):
    single = symsphere.integrate(exp_dot, **kwargs)
    for chunk_blocks in (1, 2, 7):
        assert _same(ss_distributed.integrate(exp_dot, client=client, chunk_blocks=chunk_blocks, **kwargs), single)


def _same_run(a, b):
    return _same(a, b) and (a.n_evaluations, a.n_stages, a.converged, a.tolerance, a.confidence_interval) == (
        b.n_evaluations,
        b.n_stages,
        b.converged,
        b.tolerance,
        b.confidence_interval,
    )


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(rtol=3e-5, rng=1),  # random: the n**-0.5 jump, several blocks per stage
        dict(rtol=1e-7, points="sobol", replicates=4, rng=2),  # doubling, blocks reused
        # a new grid per stage: 5 stages to n_max (unbounded, the rule ran to 4e8 points: ~40 s a run)
        dict(rtol=1e-5, points="stratified", replicates=2, rng=3, method="paper1", n_max=48 * 2**18),
        dict(atol=1e-9, n_max=48 * 2**13, domain="hemisphere", normal=[0.2, 0.3, -0.9], rng=4),  # n_max: warns
    ],
)
def test_integrate_to_tolerance_equals_single_process(client, kwargs):
    """Each stage's new blocks as tasks: bit for bit the in-process tolerance run (stages, n, interval)."""
    with warnings.catch_warnings(record=True) as single_warnings:
        warnings.simplefilter("always")
        single = symsphere.integrate(exp_dot, **kwargs)
    assert single.n_stages > 1
    for chunk_blocks in (1, 3):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            result = ss_distributed.integrate(exp_dot, client=client, chunk_blocks=chunk_blocks, **kwargs)
        assert _same_run(result, single)
        assert [str(w.message) for w in caught if "tolerance" in str(w.message)] == [
            str(w.message) for w in single_warnings if "tolerance" in str(w.message)
        ]


@njit
def exp_xyz(x, y, z):
    return np.exp(0.7 * x - 0.4 * y + 0.5 * z)


@pytest.mark.slow
def test_tolerance_ships_a_compiled_integrand(client):
    """A numba f(x, y, z) cannot run on the numpy path: equal bits mean the workers ran it fused."""
    from symsphere.integrands import INTEGRANDS

    for f in (exp_xyz, INTEGRANDS["exp"]):
        kwargs = dict(rtol=1e-5, points="sobol", rng=5)
        single = symsphere.integrate(f, **kwargs)
        assert _same_run(ss_distributed.integrate(f, client=client, chunk_blocks=2, **kwargs), single)


def test_dask_array_equals_sample_sphere(client):
    n = 48 * (2 * BLOCK + 100)
    expected = symsphere.sample_sphere(n, rng=5, dtype=np.float32)
    for chunks in (48 * BLOCK, 2 * 48 * BLOCK):
        array = ss_distributed.sample_sphere(n, chunks=chunks, rng=5, dtype=np.float32)
        assert np.array_equal(client.compute(array).result(), expected)
    hemi = ss_distributed.sample_hemisphere(24 * 3 * BLOCK, chunks=24 * BLOCK, normal=[1, 1, 0], points="halton", rng=6)
    assert np.array_equal(
        client.compute(hemi).result(),
        symsphere.sample_hemisphere(24 * 3 * BLOCK, normal=[1, 1, 0], points="halton", rng=6),
    )


def test_killed_worker_gives_identical_result(client):
    kwargs = dict(n=48 * BLOCK * 24, rng=7)
    expected = symsphere.integrate(exp_dot, **kwargs)
    pids = list(client.run(os.getpid).values())
    assert len(pids) == 2

    def kill_one():
        time.sleep(1.0)
        os.kill(pids[0], signal.SIGKILL)

    killer = threading.Thread(target=kill_one)
    killer.start()
    start = time.perf_counter()
    result = ss_distributed.integrate(slow_exp_dot, client=client, chunk_blocks=1, **kwargs)
    killer.join()
    assert time.perf_counter() - start > 1.0  # the kill happened during the run
    assert _same(result, expected)  # slow_exp_dot's values are exp_dot's: the single-process run is the reference
    client.wait_for_workers(2, timeout=60)  # the nanny restarts the worker


def test_unreachable_scheduler_fails_fast():
    start = time.perf_counter()
    with pytest.raises(ConnectionError, match="could not reach the Dask scheduler at 'tcp://127.0.0.1:9'"):
        ss_distributed.connect("tcp://127.0.0.1:9", timeout=2)
    assert time.perf_counter() - start < scaled_for_load(15)


@pytest.mark.parametrize(
    "call, error, match",
    [
        (
            lambda: ss_distributed.sample_sphere(48 * 10, chunks=480),
            ValueError,
            "'chunks'=480 is not a multiple of 196608",
        ),
        (
            lambda: ss_distributed.integrate(exp_dot, client=object(), n=48, chunk_blocks=0),
            ValueError,
            "'chunk_blocks' must be positive",
        ),
        (
            lambda: ss_distributed.integrate(exp_dot, client=object(), n=48, colour="red"),
            TypeError,
            "unexpected keyword arguments",
        ),
        (
            lambda: ss_distributed.integrate(exp_dot, client=object()),
            TypeError,
            "missing required keyword argument 'n'",
        ),
        (
            lambda: ss_distributed.integrate(exp_dot, client=object(), n=48, n_max=96),
            ValueError,
            "'n_max' is only valid",
        ),
        (lambda: ss_distributed.integrate(exp_dot, client=object(), rtol=-1.0), ValueError, "'rtol' must be"),
    ],
)
def test_bad_input(call, error, match):
    with pytest.raises(error, match=match):
        call()


def test_render_on_cluster_equals_single_process(client):
    from symsphere.render import render
    from symsphere.render.renderer import plan_passes

    options = dict(width=64, height=48, spp=200, strategy="symmetric", points="sobol", seed=3)
    assert plan_passes("cornell", pixel_filter="box", method=None, **options).passes == 4
    single = render("cornell", **options).image
    for passes_per_task in (1, 3):
        clustered = ss_distributed.render("cornell", client=client, passes_per_task=passes_per_task, **options)
        assert np.array_equal(clustered.image, single)


# --- bad input: Sobol' lengths, graphs too large to build, exception types -----------------------------------------


def _fails_fast(call, error, match, seconds=5.0):
    start = time.monotonic()
    with pytest.raises(error, match=match):
        call()
    assert time.monotonic() - start < scaled_for_load(seconds)  # instead of allocating or computing for minutes


def test_sobol_beyond_its_length_is_rejected_by_distributed():
    distributed = pytest.importorskip("symsphere.distributed")
    pytest.importorskip("dask")
    with pytest.raises(ValueError, match="Sobol'"):
        distributed.sample_sphere(48 * 2**31, points="sobol")


def test_absurd_dask_graphs_fail_fast(monkeypatch):
    distributed = pytest.importorskip("symsphere.distributed")
    pytest.importorskip("dask")
    from symsphere._testing import validation

    # A machine whose memory holds the partial sums (a smaller one refuses n first, naming it)
    monkeypatch.setattr(validation.values, "machine_memory", lambda: 2**50)
    _fails_fast(lambda: distributed.sample_sphere(n=48 * 10**13), ValueError, "'chunks'", seconds=10)
    _fails_fast(
        lambda: distributed.integrate(lambda d: d[:, 0], n=48 * 10**13, client=None), ValueError, "'chunk_blocks'"
    )


def test_distributed_exception_types():
    distributed = pytest.importorskip("symsphere.distributed")
    pytest.importorskip("dask")
    with pytest.raises(TypeError, match="'client'"):
        distributed.close_client(None)
    with pytest.raises(TypeError, match="'client'"):
        distributed.integrate(lambda d: d[:, 0], client=5, n=48)
    with pytest.raises(TypeError, match="'timeout'"):
        distributed.connect("tcp://127.0.0.1:9", timeout="x")
    with pytest.raises(ValueError, match="'timeout'"):
        distributed.connect("tcp://127.0.0.1:9", timeout=float("nan"))


def test_connect_none_does_not_start_a_cluster():
    distributed = pytest.importorskip("symsphere.distributed")
    pytest.importorskip("dask")
    with pytest.raises(TypeError, match="'address'"):
        distributed.connect(None)


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
def warm_client(dask_client):
    """The session's cluster, every worker compiled (one of them is killed: the nanny replaces it, and the test
    waits for that, so the next test finds 2 workers again, the new one not yet compiled)."""
    dask_client.run(_warm_up)  # every worker compiles before the run: the first task starts soon
    return dask_client


@pytest.mark.slow
def test_worker_killed_inside_an_integrate_task(warm_client, tmp_path):
    client = warm_client
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
def test_worker_killed_inside_a_sample_sphere_task(warm_client, tmp_path):
    client = warm_client
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
