"""Counter-based random numbers and Owen-scrambled Sobol' points in Dr.Jit, for ``symsphere_path``.

The Dr.Jit form of :mod:`symsphere._random.hashes` and :mod:`symsphere._random.owen_sobol`, for JIT variants (``mi.UInt64`` / ``mi.UInt32``
arrays; wrap-around arithmetic): splitmix64's finaliser :func:`mix64` (Steele, Lea & Flood 2014),
the per-pixel key :func:`pixel_key`, Lemire's :func:`below`, and the point ``index`` of the
Owen-scrambled, index-shuffled 2D Sobol' sequence :func:`owen_sobol2` (Burley 2020: reverse the
bits, Laine-Karras permutation, reverse back), in the reference form the renderer's table-driven
version is pinned to::

    i = nested_uniform_scramble(index, s0);  x, y = sobol2(i)
    nested_uniform_scramble(x, s1), nested_uniform_scramble(y, s2)

with the seeds s0, s1, s2 taken from the 64-bit key as the renderer takes them.  The constants are
imported from :mod:`symsphere._random`; tests/mitsuba/test_integrator.py checks these functions bit
for bit against the numba forms there.  Floats are the top 24 bits (float32 has 24), in [0, 1).
"""

from __future__ import annotations

from typing import Any

import mitsuba as mi

from .._random import splitmix
from .._random.owen_sobol import LAINE_KARRAS, MASK32

__all__ = ["GOLDEN", "ODD", "mix64", "pixel_key", "below", "u01", "owen_sobol2", "fraction"]

GOLDEN, ODD = int(splitmix.GOLDEN), int(splitmix.ODD)  # SplitMix64's constants, as Python ints
_MIX1, _MIX2 = int(splitmix.MIX1), int(splitmix.MIX2)


# The second Sobol' dimension (direction numbers v_j = v_{j-1} ^ (v_{j-1} >> 1), v_0 = 2^31: bit 31 - k of v_j
# is C(j, k) mod 2, which by Lucas' theorem is 1 iff k is a bit-subset of j).  So the bit-reversed
# coordinate has bit k = the xor of the index's bits j over the supersets j of k: a superset transform
# over the 5-bit positions, one shift-and-xor per position bit (15 operations instead of 32 terms).
_SUPERSET_STEPS = ((1, 0x55555555), (2, 0x33333333), (4, 0x0F0F0F0F), (8, 0x00FF00FF), (16, 0x0000FFFF))


def mix64(z: Any) -> Any:
    """splitmix64's finaliser (``symsphere._random.splitmix.mix64``) on a UInt64 array."""
    z = (z ^ (z >> 30)) * _MIX1
    z = (z ^ (z >> 27)) * _MIX2
    return z ^ (z >> 31)


def pixel_key(seed: Any, pixel: Any) -> Any:
    """``_random.hashes.pixel_key``: the key of one pixel (UInt64)."""
    seed = mi.UInt64(seed)
    return mix64(mix64(seed + GOLDEN) ^ (mi.UInt64(pixel) * GOLDEN + 1))


def below(bits: Any, n: int) -> Any:
    """``_random.hashes.below``: a UInt64 to a UInt32 in 0..n-1 (multiply-shift on the top 32 bits)."""
    return mi.UInt32(((bits >> 32) * n) >> 32)


def u01(bits: Any) -> Any:
    """A UInt64 to a Float in [0, 1): its top 24 bits."""
    return mi.Float(mi.UInt32(bits >> 40)) * (2.0**-24)


def _reverse32(x: Any) -> Any:
    x = ((x >> 1) & 0x55555555) | ((x & 0x55555555) << 1)
    x = ((x >> 2) & 0x33333333) | ((x & 0x33333333) << 2)
    x = ((x >> 4) & 0x0F0F0F0F) | ((x & 0x0F0F0F0F) << 4)
    x = ((x >> 8) & 0x00FF00FF) | ((x & 0x00FF00FF) << 8)
    return (x >> 16) | (x << 16)


def _laine_karras(x: Any, seed: Any) -> Any:
    x = x + seed
    for c in LAINE_KARRAS:
        x = x ^ (x * c)
    return x


def _scramble(x: Any, seed: Any) -> Any:
    """``_random.owen_sobol.nested_uniform_scramble`` of a UInt32 fraction."""
    return _reverse32(_laine_karras(_reverse32(x), seed))


def owen_sobol2(index: Any, key: Any) -> tuple[Any, Any]:
    """Point *index* (UInt32) of the Owen-scrambled, index-shuffled 2D Sobol' sequence of the UInt64 *key*.

    Returns the two UInt32 fractions (``_random.owen_sobol.owen_sobol2`` returns them divided by 2^32).
    The reference form's bit reversals cancel in pairs: with ``i`` the shuffled index, the first
    coordinate (van der Corput, ``reverse(i)``) scrambled is ``reverse(laine_karras(i, s1))``; the
    second, ``reverse(laine_karras(superset(i), s2))`` (``_SUPERSET_STEPS``).
    """
    h1 = mix64(key ^ GOLDEN)
    h2 = mix64(key ^ _MIX1)
    i = _scramble(mi.UInt32(index), mi.UInt32(h1 & MASK32))
    r = i
    for shift, mask in _SUPERSET_STEPS:
        r = r ^ ((r >> shift) & mask)
    x = _reverse32(_laine_karras(i, mi.UInt32(h1 >> 32)))
    y = _reverse32(_laine_karras(r, mi.UInt32(h2 & MASK32)))
    return x, y


def fraction(bits32: Any) -> Any:
    """A UInt32 fraction to a Float in [0, 1): its top 24 bits."""
    return mi.Float(bits32 >> 8) * (2.0**-24)
