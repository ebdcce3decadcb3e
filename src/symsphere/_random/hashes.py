"""Counter-based random numbers: SplitMix64 streams keyed by pixel and sample, as ``register_jitable``
scalar functions on ``uint64`` (the renderer's kernels inline them; :mod:`symsphere.mitsuba._random`
is their Dr.Jit form, checked bit for bit against these).

No generator state is shared between pixels or samples: the stream of sample *s* of pixel *p* starts
at ``path_state(pixel_key(seed, p), s)`` and advances by SplitMix64's increment
(:mod:`symsphere._random.splitmix`: Steele, Lea & Flood 2014; finaliser variant 13 of Stafford).  An
image is therefore a pure function of the seed, whatever the number of threads and however the
samples are split into passes.  All constants are ``np.uint64`` globals: numba turns
``uint64 + int64`` into float64, so a bare integer literal would silently break the arithmetic.
"""

from __future__ import annotations

import numpy as np
from numba.extending import register_jitable

from .._constants import TWO_POW_M53
from .splitmix import GOLDEN, ODD, mix64

__all__ = ["next_u64", "u01", "below", "pixel_key", "path_state"]

_S11 = np.uint64(11)
_S32 = np.uint64(32)
_ONE = np.uint64(1)


@register_jitable
def next_u64(state):
    """Advance a splitmix64 stream: returns (new state, 64 random bits)."""
    state = state + GOLDEN
    return state, mix64(state)


@register_jitable
def u01(bits):
    """A uint64 to a double in [0, 1) (its top 53 bits)."""
    return np.float64(bits >> _S11) * TWO_POW_M53


@register_jitable
def below(bits, n):
    """A uint64 to an integer in 0..n-1 (Lemire's multiply-shift on the top 32 bits; n < 2**32)."""
    return np.int64(((bits >> _S32) * np.uint64(n)) >> _S32)


@register_jitable
def pixel_key(seed, pixel):
    """The key of one pixel: every random decision in the pixel derives from it."""
    return mix64(mix64(seed + GOLDEN) ^ (np.uint64(pixel) * GOLDEN + _ONE))


@register_jitable
def path_state(key, sample):
    """Initial splitmix64 state of sample *sample* of the pixel with key *key*."""
    return mix64(key ^ ((np.uint64(sample) + _ONE) * ODD))
