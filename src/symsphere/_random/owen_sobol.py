"""Owen-scrambled Sobol' points (2D and interlaced) as ``register_jitable`` scalar functions on ``uint64``.

The renderer's kernels (:mod:`symsphere.render`) inline them; the Dr.Jit form in
:mod:`symsphere.mitsuba._random` imports the constants (:data:`LAINE_KARRAS`, :data:`MASK32`) from here.
All constants are ``np.uint64`` globals: numba turns ``uint64 + int64`` into float64, so a bare integer
literal would silently break the arithmetic.

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

Interlaced (higher-order) Sobol'
--------------------------------
:func:`owen_sobol_interlaced` is the renderer's form of the library's point
sets ``'sobol_interlaced2'`` and ``'sobol_interlaced3'`` (:mod:`symsphere.points`;
Dick 2011): the first 2 x factor Sobol' dimensions, with scipy's direction numbers
(Joe & Kuo 2008; dimensions 0 and 1 are the two above), each Owen-scrambled as
above with its own seed after one shared index shuffle, and then interlaced digit
by digit, *factor* coordinates at a time, exactly as
:func:`symsphere.points.interlace_digits` (the leading ``53 // factor`` digits of
each, the centre of the cell).  Its tables are in the same bit-reversed form.
"""

from __future__ import annotations

import numpy as np
from numba.extending import register_jitable

from .splitmix import GOLDEN, MIX1, MIX2, ODD, mix64

__all__ = [
    "LAINE_KARRAS",
    "MASK32",
    "reverse_bits32",
    "nested_uniform_scramble",
    "sobol2",
    "owen_sobol2",
    "sobol_coordinate",
    "interlace_fractions",
    "owen_sobol_interlaced",
]

_S32 = np.uint64(32)
_ONE = np.uint64(1)
MASK32 = 0xFFFFFFFF
"""The low 32 bits (the fractions here are 32-bit)."""
_M32 = np.uint64(MASK32)
_TWO_M32 = 2.0**-32
_TWO_M52 = 2.0**-52
_TWO_M51 = 2.0**-51

LAINE_KARRAS = (0x6C50B47C, 0xB82F1E52, 0xC7AFE638, 0x8D22F6E6)
"""The Laine–Karras permutation's multipliers (Burley 2020, listing 2): all even."""
_LK0, _LK1, _LK2, _LK3 = (np.uint64(c) for c in LAINE_KARRAS)


def _pascal_direction_numbers():
    v = np.zeros(32, dtype=np.uint64)
    v[0] = 1 << 31
    for i in range(1, 32):
        v[i] = v[i - 1] ^ (v[i - 1] >> np.uint64(1))
    return v


_SOBOL2 = _pascal_direction_numbers()
_SOBOL2.setflags(write=False)

# Joe & Kuo, "Constructing Sobol' sequences with better two-dimensional projections", SIAM J. Sci.
# Comput. 30 (2008) 2635-2654, file new-joe-kuo-6.21201 (the direction numbers of scipy.stats.qmc.Sobol):
# (degree s, coefficients a, initial m_1 ... m_s) of its dimensions 3 ... 6, which are the Sobol'
# dimensions 2 ... 5 counted from 0 (0: van der Corput, 1: the Pascal dimension above).  A test derives
# all 6 x 32 direction numbers from scipy's unscrambled points.
_JOE_KUO = ((2, 1, (1, 3)), (3, 1, (1, 3, 1)), (3, 2, (1, 1, 1)), (4, 1, (1, 1, 3, 3)))


def _sobol_direction_numbers():
    v = np.zeros((6, 32), dtype=np.uint64)
    v[0] = [1 << (31 - k) for k in range(32)]
    v[1] = _SOBOL2
    for d, (degree, a, initial) in enumerate(_JOE_KUO, start=2):
        m = list(initial)  # m_k = m_{k-s} ^ (m_{k-s} << s) ^ xor_j a_j (m_{k-j} << j), a_j bit s-1-j of a
        for k in range(degree, 32):
            new = m[k - degree] ^ (m[k - degree] << degree)
            for j in range(1, degree):
                if (a >> (degree - 1 - j)) & 1:
                    new ^= m[k - j] << j
            m.append(new)
        v[d] = [m[k] << (31 - k) for k in range(32)]  # v_k = m_k / 2^(k+1), as a 32-bit fraction
    v.setflags(write=False)
    return v


_SOBOL6 = _sobol_direction_numbers()


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
    h1 = mix64(key ^ GOLDEN)
    h2 = mix64(key ^ MIX1)
    i = _reverse_fast(_laine_karras(_reverse_fast(np.uint64(index) & _M32), h1 & _M32))
    y_reversed = (
        _YREV[0, i & _B255] ^ _YREV[1, (i >> _S8) & _B255] ^ _YREV[2, (i >> _S16) & _B255] ^ _YREV[3, i >> _S24]
    )
    x = _reverse_fast(_laine_karras(i, h1 >> _S32))  # vdC(i) = reverse(i), so its scramble is reverse(LK(i))
    y = _reverse_fast(_laine_karras(y_reversed, h2 & _M32))
    return np.float64(x) * _TWO_M32, np.float64(y) * _TWO_M32


@register_jitable
def sobol_coordinate(index, dim):
    """Coordinate *dim* (0 ... 5) of the unscrambled Sobol' point *index* (< 2**32), a 32-bit fraction.

    The reference (a loop over the bits of the index), natural order: point i
    is the xor of the direction numbers of the set bits of i (scipy's points
    are in Gray-code order: its point n is this point n ^ (n >> 1)).
    """
    value = np.uint64(0)
    index = np.uint64(index)
    i = 0
    while index != 0:
        if index & _ONE:
            value = value ^ _SOBOL6[dim, i]
        index = index >> _ONE
        i += 1
    return value


@register_jitable
def _spread(d, factor):
    # The bits of d (< 2^32 for factor 2, < 2^21 for 3) spread out: bit b -> bit factor * b (Morton codes).
    if factor == 2:
        d = (d | (d << _S16)) & np.uint64(0x0000FFFF0000FFFF)
        d = (d | (d << _S8)) & np.uint64(0x00FF00FF00FF00FF)
        d = (d | (d << np.uint64(4))) & np.uint64(0x0F0F0F0F0F0F0F0F)
        d = (d | (d << np.uint64(2))) & np.uint64(0x3333333333333333)
        return (d | (d << _ONE)) & np.uint64(0x5555555555555555)
    d = (d | (d << _S32)) & np.uint64(0x001F00000000FFFF)
    d = (d | (d << _S16)) & np.uint64(0x001F0000FF0000FF)
    d = (d | (d << _S8)) & np.uint64(0x100F00F00F00F00F)
    d = (d | (d << np.uint64(4))) & np.uint64(0x10C30C30C30C30C3)
    return (d | (d << np.uint64(2))) & np.uint64(0x1249249249249249)


@register_jitable
def interlace_fractions(a, b, c, factor):
    """Interlace the digits of the 32-bit fractions a, b (factor 2) or a, b, c (factor 3) into a double.

    As :func:`symsphere.points.interlace_digits`: digit k of the result is digit
    ceil(k / factor) of source (k - 1) mod factor, from the leading 26 (factor 2)
    or 17 (factor 3) digits of each; the result is the centre of its cell of side
    2^-52 or 2^-51, in (0, 1).  (c is ignored for factor 2.)
    """
    if factor == 2:  # the leading 26 digits of each
        s = np.uint64(6)
        return (np.float64((_spread(a >> s, 2) << _ONE) | _spread(b >> s, 2)) + 0.5) * _TWO_M52
    s = np.uint64(15)  # the leading 17 digits of each
    value = (_spread(a >> s, 3) << np.uint64(2)) | (_spread(b >> s, 3) << _ONE) | _spread(c >> s, 3)
    return (np.float64(value) + 0.5) * _TWO_M51


@register_jitable
def _scrambled_coordinate(i, dim, seed):
    """Coordinate *dim* of Sobol' point i, nested-uniform scrambled with *seed*: reverse(LK(reverse(x)))."""
    r = (
        _SOBOL6_REV[dim, 0, i & _B255]
        ^ _SOBOL6_REV[dim, 1, (i >> _S8) & _B255]
        ^ _SOBOL6_REV[dim, 2, (i >> _S16) & _B255]
        ^ _SOBOL6_REV[dim, 3, i >> _S24]
    )  # reverse(x) = xor of reverse(v_j) over the set bits j of i
    return _reverse_fast(_laine_karras(r, seed))


@register_jitable
def owen_sobol_interlaced(index, key, factor):
    """Point *index* of the Owen-scrambled, index-shuffled, interlaced Sobol' sequence with 64-bit *key*.

    *factor* 2 or 3: Sobol' dimensions 0 ... 3 or 0 ... 5.  Returns two
    doubles in (0, 1).  Seeds (32 bits each, from *key*): one shuffles the
    index, one scrambles each dimension.  Equal to::

        i = nested_uniform_scramble(index, s)
        x_d = nested_uniform_scramble(sobol_coordinate(i, d), s_d)     d = 0 ... 2 factor - 1
        interlace_fractions(x_0, ..., x_{factor-1}), interlace_fractions(x_factor, ...)

    (pinned by a test), with the dimensions' xor over the bits of i done by byte tables.
    """
    h1 = mix64(key ^ GOLDEN)
    h2 = mix64(key ^ MIX1)
    h3 = mix64(key ^ MIX2)
    i = _reverse_fast(_laine_karras(_reverse_fast(np.uint64(index) & _M32), h1 & _M32))
    x0 = _scrambled_coordinate(i, 0, h1 >> _S32)
    x1 = _scrambled_coordinate(i, 1, h2 & _M32)
    x2 = _scrambled_coordinate(i, 2, h2 >> _S32)
    x3 = _scrambled_coordinate(i, 3, h3 & _M32)
    if factor == 2:
        return interlace_fractions(x0, x1, x1, 2), interlace_fractions(x2, x3, x3, 2)
    h4 = mix64(key ^ ODD)
    x4 = _scrambled_coordinate(i, 4, h3 >> _S32)
    x5 = _scrambled_coordinate(i, 5, h4 & _M32)
    return interlace_fractions(x0, x1, x2, 3), interlace_fractions(x3, x4, x5, 3)


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
    sobol6_rev = np.zeros((6, 4, 256), dtype=np.uint64)
    for dim in range(6):
        w = [reverse(int(_SOBOL6[dim, j]), 32) for j in range(32)]
        for byte in range(4):
            for bit in range(8):  # entries with highest set bit `bit` from the smaller ones: 256 xors
                step = 1 << bit
                sobol6_rev[dim, byte, step : 2 * step] = sobol6_rev[dim, byte, :step] ^ np.uint64(w[8 * byte + bit])
    rev8.setflags(write=False)
    yrev.setflags(write=False)
    sobol6_rev.setflags(write=False)
    return rev8, yrev, sobol6_rev


_REV8, _YREV, _SOBOL6_REV = _tables()
_B255 = np.uint64(255)
_S8 = np.uint64(8)
_S16 = np.uint64(16)
_S24 = np.uint64(24)
