"""numpy's PCG64 (O'Neill 2014: a 128-bit LCG with the XSL-RR output) in numba, for the kernels that
draw their base points themselves (:mod:`symsphere._kernels`, :mod:`symsphere._fused`).

numba can call a numpy ``Generator`` itself, but through the bit generator's function pointer:
measured 3x slower than this inlined step.  Bit for bit numpy's ``Generator(PCG64).random()``:
tests/_random/test_pcg64.py checks the seeding, the jump and the draws against numpy's own stream.
A part of a kernel starts from the state :func:`pcg64_state` gives (Python's integers seed, numpy's
``PCG64.advance`` jumps) and only steps it with :func:`pcg64_random`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt
from llvmlite import ir
from numba import types
from numba.extending import intrinsic, register_jitable

from .._constants import TWO_POW_M53

__all__ = ["pcg64_random", "pcg64_advanced", "pcg64_seeded", "pcg64_state", "pcg64_integers63"]

_PCG64_MULTIPLIER = 0x2360ED051FC65DA44385DF649FCCF645
_MUL_HI = np.uint64(_PCG64_MULTIPLIER >> 64)
_MUL_LO = np.uint64(_PCG64_MULTIPLIER & (2**64 - 1))
_U0, _U1, _U11, _U58, _U63, _U64 = (np.uint64(k) for k in (0, 1, 11, 58, 63, 64))
_MASK64 = 2**64 - 1
_MASK128 = 2**128 - 1
_Words = Sequence[int] | npt.NDArray[np.unsignedinteger[Any]]  # a SeedSequence's 4 uint64 words


@intrinsic
def _mul_high(typingctx, a, b):
    """The high 64 bits of the 128-bit product of two uint64 (one machine instruction)."""

    def codegen(context, builder, signature, args):
        wide = ir.IntType(128)
        product = builder.mul(builder.zext(args[0], wide), builder.zext(args[1], wide))
        return builder.trunc(builder.lshr(product, ir.Constant(wide, 64)), ir.IntType(64))

    return types.uint64(types.uint64, types.uint64), codegen


@register_jitable
def _mul128(a_hi, a_lo, b_hi, b_lo):
    """(a * b) mod 2**128 of 128-bit numbers given as (high, low) uint64 halves."""
    return _mul_high(a_lo, b_lo) + a_hi * b_lo + a_lo * b_hi, a_lo * b_lo  # type: ignore[call-arg]  # an intrinsic


@register_jitable
def _add128(a_hi, a_lo, b_hi, b_lo):
    """(a + b) mod 2**128."""
    lo = a_lo + b_lo
    return a_hi + b_hi + (_U1 if lo < a_lo else _U0), lo


@register_jitable
def _pcg64_step(stream):
    """state = M state + inc (mod 2**128); returns the new state (high, low)."""
    hi, lo = _mul128(stream[0], stream[1], _MUL_HI, _MUL_LO)
    hi, lo = _add128(hi, lo, stream[2], stream[3])
    stream[0], stream[1] = hi, lo
    return hi, lo


@register_jitable
def pcg64_random(stream):
    """Next ``Generator.random()`` of the PCG64 *stream* (uint64[4]: state hi, lo; inc hi, lo)."""
    hi, lo = _pcg64_step(stream)
    mixed = hi ^ lo
    rotation = hi >> _U58
    bits = (mixed >> rotation) | (mixed << ((_U64 - rotation) & _U63))
    return np.float64(bits >> _U11) * TWO_POW_M53  # numpy's next_double: 53 bits


@register_jitable
def pcg64_seeded(words):
    """The stream of numpy's ``PCG64(seed_sequence)``, from ``seed_sequence.generate_state(4,
    np.uint64)`` (O'Neill's ``pcg_setseq_128_srandom_r``, as numpy seeds it)."""
    stream = np.zeros(4, dtype=np.uint64)
    stream[2] = (words[2] << _U1) | (words[3] >> _U63)  # inc = (initseq << 1) | 1
    stream[3] = (words[3] << _U1) | _U1
    _pcg64_step(stream)
    stream[0], stream[1] = _add128(stream[0], stream[1], words[0], words[1])
    _pcg64_step(stream)
    return stream


@register_jitable
def pcg64_advanced(start, draws):
    """The PCG64 stream *start* after *draws* draws, as numpy's ``PCG64.advance`` (a new array).

    Jump-ahead of an LCG in O(log draws) steps (Brown, "Random number generation with
    arbitrary strides", 1994; O'Neill's ``pcg_advance_lcg_128``): x -> M x + c applied
    *draws* times is x -> A x + C, built from the binary digits of *draws*.
    """
    mult_hi, mult_lo = _MUL_HI, _MUL_LO
    plus_hi, plus_lo = start[2], start[3]
    acc_mult_hi, acc_mult_lo = _U0, _U1
    acc_plus_hi, acc_plus_lo = _U0, _U0
    remaining = np.uint64(draws)
    while remaining > _U0:
        if remaining & _U1:
            acc_mult_hi, acc_mult_lo = _mul128(acc_mult_hi, acc_mult_lo, mult_hi, mult_lo)
            acc_plus_hi, acc_plus_lo = _mul128(acc_plus_hi, acc_plus_lo, mult_hi, mult_lo)
            acc_plus_hi, acc_plus_lo = _add128(acc_plus_hi, acc_plus_lo, plus_hi, plus_lo)
        next_hi, next_lo = _add128(mult_hi, mult_lo, _U0, _U1)
        plus_hi, plus_lo = _mul128(next_hi, next_lo, plus_hi, plus_lo)
        mult_hi, mult_lo = _mul128(mult_hi, mult_lo, mult_hi, mult_lo)
        remaining = remaining >> _U1
    stream = start.copy()
    stream[0], stream[1] = _mul128(acc_mult_hi, acc_mult_lo, start[0], start[1])
    stream[0], stream[1] = _add128(stream[0], stream[1], acc_plus_hi, acc_plus_lo)
    return stream


def pcg64_state(seed_words: _Words, draws: int) -> npt.NDArray[np.uint64]:
    """The stream (uint64[4]: state hi, lo; inc hi, lo) of numpy's ``PCG64(seed_sequence)`` after
    *draws* draws, with *seed_words* = ``seed_sequence.generate_state(4, np.uint64)``.

    Python's integers do it all (a kernel's part starts from this state and only steps, so the kernels
    compile neither): the seeding as numpy does it, then the jump as ``PCG64.advance``.  One numpy
    call: after a large write, each numpy call costs 10-30 us more (its code has left the caches), and
    a numpy ``PCG64`` took five.
    """
    state, increment = _seeded(seed_words)
    s = _jumped(state, increment, int(draws))
    return np.array([s >> 64, s & _MASK64, increment >> 64, increment & _MASK64], dtype=np.uint64)


def pcg64_integers63(seed_words: _Words, count: int) -> tuple[int, ...]:
    """``Generator(PCG64(seed_sequence)).integers(0, 2**63, size=count, dtype=np.int64)`` as Python ints,
    *seed_words* = ``seed_sequence.generate_state(4, np.uint64)``, without making the Generator.

    numpy draws integers below 2**63 by Lemire's method, which for a power-of-2 range is the top bits of
    one draw and never rejects: each is ``next_uint64() >> 1`` (tested against numpy).
    """
    state, increment = _seeded(seed_words)
    draws = []
    for _ in range(count):
        state = (state * _PCG64_MULTIPLIER + increment) & _MASK128
        hi, lo = state >> 64, state & _MASK64
        mixed, rotation = hi ^ lo, hi >> 58  # XSL-RR: the high half's top 6 bits rotate the xor
        draws.append(((mixed >> rotation) | (mixed << (64 - rotation))) & _MASK64)
    return tuple(d >> 1 for d in draws)


def _seeded(seed_words: _Words) -> tuple[int, int]:
    """The (state, increment) of numpy's ``PCG64`` seeded with *seed_words* (O'Neill's
    ``pcg_setseq_128_srandom_r``, as numpy seeds it: two steps of the LCG)."""
    w0, w1, w2, w3 = (int(w) for w in seed_words)
    increment = (((w2 << 64) | w3) << 1 | 1) & _MASK128
    state = increment  # one step from state 0
    state = (state + ((w0 << 64) | w1)) & _MASK128
    state = (state * _PCG64_MULTIPLIER + increment) & _MASK128
    return state, increment


def _jumped(state: int, increment: int, draws: int) -> int:
    """*state* after *draws* steps x -> M x + inc (mod 2**128): M^d x + inc (M^d - 1) / (M - 1).

    The geometric sum is exact from M^d modulo (M - 1) 2**128 (M - 1 divides M^d - 1), so Python's
    three-argument ``pow`` does the jump: the same state as numpy's ``PCG64.advance`` (tested).
    """
    m = _PCG64_MULTIPLIER
    geometric = (pow(m, draws, (m - 1) << 128) - 1) // (m - 1)
    return (pow(m, draws, 1 << 128) * state + geometric * increment) & _MASK128
