"""The renderer's random streams (defined in :mod:`symsphere._random`), under the names
:mod:`symsphere.render._integrator` imports them by until it imports them from there itself."""

from __future__ import annotations

from .._random.hashes import below, next_u64, path_state, pixel_key, u01
from .._random.owen_sobol import owen_sobol2, owen_sobol_interlaced

__all__ = ["below", "next_u64", "path_state", "pixel_key", "u01", "owen_sobol2", "owen_sobol_interlaced"]
