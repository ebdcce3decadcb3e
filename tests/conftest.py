"""Fixtures shared by test files of several modules."""

import os
import signal
import sys

import pytest


@pytest.fixture(scope="session", autouse=True)
def _drjit_pool_per_worker():
    """Under pytest-xdist, each worker's Dr.Jit pool gets its share of the CPUs (at least one), as the Makefile
    gives OpenBLAS one thread: a full pool in every worker puts more threads than CPUs on the Mitsuba tests,
    which then take more CPU time for the same work (docs/results/test-times.md).  Dr.Jit is imported by the
    Mitsuba tests' probes at collection; a worker that did not import it is left alone.  A file run alone
    keeps Dr.Jit's default."""
    workers = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))
    drjit = sys.modules.get("drjit")
    if workers > 1 and drjit is not None:
        drjit.set_thread_count(max(1, len(os.sched_getaffinity(0)) // workers))
    yield


@pytest.fixture
def python_sigint_handler():
    """Python's own SIGINT handler (KeyboardInterrupt) for a test that signals itself: a pytest-xdist
    worker runs with another."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


@pytest.fixture(scope="session")
def dask_client():
    """A local Dask cluster of 2 single-threaded worker processes, for the tests that need a cluster to run on
    but not a new one (those that check starting, failing or closing one start their own).  A test that kills
    a worker waits for the nanny to replace it.  Mark the test ``xdist_group("dask")``: the cluster tests then
    run on one pytest-xdist worker, which starts this cluster once (Makefile: --dist loadgroup)."""
    pytest.importorskip("distributed")
    from symsphere import distributed

    client = distributed.local_client(2)
    yield client
    distributed.close_client(client)
