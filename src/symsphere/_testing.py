"""The tests' one door into the library's internals (docs/explanation/testing.md).

Tests use the public API; where a test must reach a private module (a kernel's parts, the probes
that compile the renderer's scalar functions, the stale-cache guard), it imports it from here and
nowhere else: ``from symsphere._testing import kernels``.  ``tests/test_architecture.py`` checks that
no test imports a private module or name otherwise.  The Mitsuba port's modules load on first use
(they import Mitsuba 3).  Nothing in the library imports this module.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from . import _auto as auto
from . import _blocks as blocks
from . import _compile_ahead as compile_ahead
from . import _compiled_peers as compiled_peers
from . import _fused as fused
from . import _integrand_kernels as integrand_kernels
from . import _kernels as kernels
from . import _numba_cache as numba_cache
from . import _strategies as strategies
from . import _threads as threads
from . import _validation as validation
from ._random import hashes, owen_sobol, pcg64, seed_sequence, splitmix
from .render import _directions as render_directions
from .render import _emitters as render_emitters
from .render import _exr_threads as exr_threads
from .render import _integrator as render_integrator
from .render import _probes as render_probes
from .warps import _triangle as warps_triangle

__all__ = [
    "auto",
    "blocks",
    "compile_ahead",
    "compiled_peers",
    "exr_threads",
    "fused",
    "hashes",
    "integrand_kernels",
    "kernels",
    "numba_cache",
    "owen_sobol",
    "pcg64",
    "seed_sequence",
    "splitmix",
    "strategies",
    "threads",
    "validation",
    "render_directions",
    "render_emitters",
    "render_integrator",
    "render_probes",
    "warps_triangle",
]  # and, on first use (module __getattr__), mitsuba_integrator, mitsuba_lights, mitsuba_projected, mitsuba_random,
# mitsuba_warps

_LAZY = {
    "mitsuba_integrator": "symsphere.mitsuba._integrator",
    "mitsuba_lights": "symsphere.mitsuba._lights",
    "mitsuba_projected": "symsphere.mitsuba._projected",
    "mitsuba_random": "symsphere.mitsuba._random",
    "mitsuba_warps": "symsphere.mitsuba._warps",
}


def __getattr__(name: str) -> ModuleType:
    if name in _LAZY:
        return importlib.import_module(_LAZY[name])
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
