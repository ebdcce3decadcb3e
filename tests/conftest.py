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
