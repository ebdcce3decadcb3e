"""Tests of symsphere.render call its numba kernels directly: check the kernels' disk cache first, as
the renderer does before its first kernel (nothing happens at import)."""

import pytest

from symsphere.render import _integrator


@pytest.fixture(autouse=True, scope="session")
def _kernels_prepared():
    _integrator.prepare_kernels()
