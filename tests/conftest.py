"""Fixtures shared by test files of several modules."""

import signal

import pytest


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
