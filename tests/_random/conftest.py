"""The Owen-Sobol' tests call the renderer's probe kernels (``render._probes``): check the kernels' disk
cache first, as the renderer does before its first kernel (nothing happens at import)."""

import pytest

from symsphere._testing import render_probes as _probes


@pytest.fixture(autouse=True, scope="session")
def _kernels_prepared():
    _probes.prepare_kernels()
