"""SplitMix64 under its former module name, for :mod:`symsphere.render._integrator` (which imports it
from here until it imports :mod:`symsphere._random.splitmix`, the definition, itself)."""

from __future__ import annotations

from ._random.splitmix import GOLDEN, ODD, mix64

__all__ = ["GOLDEN", "ODD", "mix64"]
