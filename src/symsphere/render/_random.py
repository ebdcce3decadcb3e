"""Counter-based random numbers and Owen-scrambled Sobol' points for the render kernels.

Everything here is a ``register_jitable`` scalar function on ``uint64``
integers, so that the kernels in :mod:`symsphere.render._integrator` inline
it.  All constants are ``np.uint64`` globals: numba turns ``uint64 + int64``
into float64, so a bare integer literal would silently break the arithmetic.

Random numbers
--------------
No generator state is shared between pixels or samples: the stream of sample
*s* of pixel *p* starts at ``path_state(pixel_key(seed, p), s)`` and advances
by the splitmix64 increment (Steele, Lea & Flood 2014; finaliser variant 13 of
Stafford).  An image is therefore a pure function of the seed, whatever the
number of threads and however the samples are split into passes.

Owen-scrambled Sobol'
---------------------
Burley, "Practical Hash-based Owen Scrambling", JCGT 9(4), 2020.  The 2D
Sobol' sequence is its first two dimensions: the van der Corput sequence
(the bit reversal of the index) and the dimension whose generator matrix is
Pascal's triangle mod 2 (direction numbers ``v_i = v_{i-1} ^ (v_{i-1} >> 1)``).
A nested uniform scramble of a 32-bit fraction is approximated, as in the
paper, by reversing the bits, applying the Laine–Karras permutation (an
addition of the seed and four xor-multiplications by even constants: output
bit i depends on input bits 0..i only, bijectively) and reversing back, so
that each bit of the fraction is flipped by a hash of the bits above it.
Such a scramble maps every (0, m, 2)-net in base 2 onto a (0, m, 2)-net.
For padding, the sample *index* is shuffled by the same nested scramble
(with its own seed) before the Sobol' point is taken: the first 2^m indices
go to the 2^m indices of one aligned block, which is again a net.
"""

from __future__ import annotations

import numpy as np
from numba.extending import register_jitable

__all__ = [
    "mix64",
    "next_u64",
    "u01",
    "below",
    "pixel_key",
    "path_state",
    "reverse_bits32",
    "nested_uniform_scramble",
    "sobol2",
    "owen_sobol2",
]

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)
_ODD = np.uint64(0xD6E8FEB86659FD93)  # any odd constant: keys the sample index into the stream
_S30 = np.uint64(30)
_S27 = np.uint64(27)
_S31 = np.uint64(31)
_S11 = np.uint64(11)
_S32 = np.uint64(32)
_ONE = np.uint64(1)
_M32 = np.uint64(0xFFFFFFFF)
_TWO_M53 = 2.0**-53
_TWO_M32 = 2.0**-32

# Laine–Karras permutation constants (Burley 2020, listing 2): all even.
_LK = np.array([0x6C50B47C, 0xB82F1E52, 0xC7AFE638, 0x8D22F6E6], dtype=np.uint64)
_LK0, _LK1, _LK2, _LK3 = (np.uint64(c) for c in _LK)


def _pascal_direction_numbers():
    v = np.zeros(32, dtype=np.uint64)
    v[0] = 1 << 31
    for i in range(1, 32):
        v[i] = v[i - 1] ^ (v[i - 1] >> np.uint64(1))
    return v


_SOBOL2 = _pascal_direction_numbers()
_SOBOL2.setflags(write=False)


@register_jitable
def mix64(z):
    """splitmix64's finaliser: a bijective avalanche of a uint64."""
    z = (z ^ (z >> _S30)) * _MIX1
    z = (z ^ (z >> _S27)) * _MIX2
    return z ^ (z >> _S31)


@register_jitable
def next_u64(state):
    """Advance a splitmix64 stream: returns (new state, 64 random bits)."""
    state = state + _GOLDEN
    return state, mix64(state)


@register_jitable
def u01(bits):
    """A uint64 to a double in [0, 1) (its top 53 bits)."""
    return np.float64(bits >> _S11) * _TWO_M53


@register_jitable
def below(bits, n):
    """A uint64 to an integer in 0..n-1 (Lemire's multiply-shift on the top 32 bits; n < 2**32)."""
    return np.int64(((bits >> _S32) * np.uint64(n)) >> _S32)


@register_jitable
def pixel_key(seed, pixel):
    """The key of one pixel: every random decision in the pixel derives from it."""
    return mix64(mix64(seed + _GOLDEN) ^ (np.uint64(pixel) * _GOLDEN + _ONE))


@register_jitable
def path_state(key, sample):
    """Initial splitmix64 state of sample *sample* of the pixel with key *key*."""
    return mix64(key ^ ((np.uint64(sample) + _ONE) * _ODD))


@register_jitable
def reverse_bits32(x):
    """Reverse the low 32 bits of x (the high bits must be 0)."""
    x = ((x >> np.uint64(1)) & np.uint64(0x55555555)) | ((x & np.uint64(0x55555555)) << np.uint64(1))
    x = ((x >> np.uint64(2)) & np.uint64(0x33333333)) | ((x & np.uint64(0x33333333)) << np.uint64(2))
    x = ((x >> np.uint64(4)) & np.uint64(0x0F0F0F0F)) | ((x & np.uint64(0x0F0F0F0F)) << np.uint64(4))
    x = ((x >> np.uint64(8)) & np.uint64(0x00FF00FF)) | ((x & np.uint64(0x00FF00FF)) << np.uint64(8))
    return ((x >> np.uint64(16)) | (x << np.uint64(16))) & _M32


@register_jitable
def _laine_karras(x, seed):
    x = (x + seed) & _M32
    x = x ^ ((x * _LK0) & _M32)
    x = x ^ ((x * _LK1) & _M32)
    x = x ^ ((x * _LK2) & _M32)
    return x ^ ((x * _LK3) & _M32)


@register_jitable
def nested_uniform_scramble(x, seed):
    """Hash-based nested uniform (Owen) scramble of a 32-bit fraction x / 2**32 (seed: 32 bits)."""
    return reverse_bits32(_laine_karras(reverse_bits32(x), seed))


@register_jitable
def sobol2(index):
    """The first two Sobol' dimensions at *index* (< 2**32), as 32-bit fractions."""
    x = reverse_bits32(index)
    y = np.uint64(0)
    i = 0
    while index != 0:
        if index & _ONE:
            y = y ^ _SOBOL2[i]
        index = index >> _ONE
        i += 1
    return x, y


@register_jitable
def _reverse_fast(x):
    """reverse_bits32 by byte table (the kernels' hot path; reverse_bits32 is the reference)."""
    return (
        (_REV8[x & _B255] << _S24)
        | (_REV8[(x >> _S8) & _B255] << _S16)
        | (_REV8[(x >> _S16) & _B255] << _S8)
        | _REV8[x >> _S24]
    )


@register_jitable
def owen_sobol2(index, key):
    """Point *index* of the Owen-scrambled, index-shuffled 2D Sobol' sequence with 64-bit *key*.

    Returns two doubles in [0, 1).  Three 32-bit seeds are taken from *key*:
    one shuffles the index, one scrambles each dimension.  Equal to::

        i = nested_uniform_scramble(index, s0)
        x, y = sobol2(i)
        nested_uniform_scramble(x, s1) / 2**32, nested_uniform_scramble(y, s2) / 2**32

    (pinned by a test), with table-driven bit reversals and reverse(y) as a
    table-driven xor over the bytes of i (reverse(y) = xor of reverse(v_j)
    over the set bits j of i), so that no loop over the bits remains.
    """
    h1 = mix64(key ^ _GOLDEN)
    h2 = mix64(key ^ _MIX1)
    i = _reverse_fast(_laine_karras(_reverse_fast(np.uint64(index) & _M32), h1 & _M32))
    y_reversed = _YREV[0, i & _B255] ^ _YREV[1, (i >> _S8) & _B255] ^ _YREV[2, (i >> _S16) & _B255] ^ _YREV[3, i >> _S24]
    x = _reverse_fast(_laine_karras(i, h1 >> _S32))  # vdC(i) = reverse(i), so its scramble is reverse(LK(i))
    y = _reverse_fast(_laine_karras(y_reversed, h2 & _M32))
    return np.float64(x) * _TWO_M32, np.float64(y) * _TWO_M32


def _tables():
    def reverse(x, bits):
        return int(format(x, f"0{bits}b")[::-1], 2)

    rev8 = np.array([reverse(b, 8) for b in range(256)], dtype=np.uint64)
    w = [reverse(int(_SOBOL2[j]), 32) for j in range(32)]  # reverse(v_j)
    yrev = np.zeros((4, 256), dtype=np.uint64)
    for byte in range(4):
        for value in range(256):
            acc = 0
            for bit in range(8):
                if value >> bit & 1:
                    acc ^= w[8 * byte + bit]
            yrev[byte, value] = acc
    rev8.setflags(write=False)
    yrev.setflags(write=False)
    return rev8, yrev


_REV8, _YREV = _tables()
_B255 = np.uint64(255)
_S8 = np.uint64(8)
_S16 = np.uint64(16)
_S24 = np.uint64(24)
