"""SplitMix64 (Steele, Lea & Flood 2014): its golden-ratio increment and its finaliser, defined once.

``GOLDEN`` = floor(2**64 / phi) (odd), the stream's increment; ``MIX1``, ``MIX2`` the finaliser's
multipliers (variant 13 of Stafford's mixers); ``ODD``, an odd constant that keys a sample index into a
stream.  All are ``np.uint64`` (numba types them as uint64; ``int()`` gives the Python int).
:func:`mix64` is the finaliser, a bijective avalanche of a uint64: compiled by numba into the kernels
(``register_jitable``), and callable from Python on an ``np.uint64`` (:func:`mix64_int` for a Python
int).  The Dr.Jit port (``symsphere.mitsuba._random``) writes the finaliser on Dr.Jit arrays with
these constants, imported from here.
"""

from __future__ import annotations

import numpy as np
from numba.extending import register_jitable

from .._constants import GOLDEN_BITS

__all__ = ["GOLDEN", "MIX1", "MIX2", "ODD", "mix64", "mix64_int"]

GOLDEN = np.uint64(GOLDEN_BITS)
MIX1 = np.uint64(0xBF58476D1CE4E5B9)
MIX2 = np.uint64(0x94D049BB133111EB)
ODD = np.uint64(0xD6E8FEB86659FD93)
_S27, _S30, _S31 = np.uint64(27), np.uint64(30), np.uint64(31)


@register_jitable
def mix64(z):  # typed by numba (uint64 -> uint64)
    """SplitMix64's finaliser of a uint64 (wrap-around multiplication)."""
    z = (z ^ (z >> _S30)) * MIX1
    z = (z ^ (z >> _S27)) * MIX2
    return z ^ (z >> _S31)


def mix64_int(key: int) -> int:
    """:func:`mix64` of a Python int in ``[0, 2**64)``, as a Python int.

    Examples
    --------
    >>> from symsphere._random.splitmix import mix64_int
    >>> hex(mix64_int(0x9E3779B97F4A7C15))  # SplitMix64's first output for seed 0
    '0xe220a8397b1dcdaf'
    """
    with np.errstate(over="ignore"):  # the multiplications wrap around 2**64 by definition
        return int(mix64(np.uint64(key)))
