"""Dask scale-out: bit-identical to the single-process results, any chunking, a killed worker."""

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


@pytest.fixture(scope="module")
def client():
    client = ss_distributed.local_client(2)
    yield client
    ss_distributed.close_client(client)


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
    assert _same(result, symsphere.integrate(slow_exp_dot, **kwargs)) and _same(result, expected)
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

    options = dict(width=64, height=48, spp=200, sampler="symmetric_sobol", seed=3)
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
