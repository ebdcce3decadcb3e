"""numpy's ``SeedSequence(entropy, spawn_key=...).generate_state(n, np.uint64)`` in Python's integers.

Every sampling call turns its seed into a stream's seed words this way, twice (the root seed, then the
stream's).  numpy's ``SeedSequence`` does it in a dozen numpy calls, each 10-30 us after a large write
has left numpy's code out of the caches; here it is a few hundred operations on Python ints.  O'Neill's
``seed_seq`` hash, as numpy implements it (pool of 4 words of 32 bits): tests/_random/test_seed_sequence.py
checks it against numpy's own for ints, tuples of ints and spawn keys.
"""

from __future__ import annotations

__all__ = ["seed_words"]

_POOL_SIZE = 4
_INIT_A, _MULT_A = 0x43B0D7E5, 0x931E8875
_INIT_B, _MULT_B = 0x8B51F9DD, 0x58F38DED
_MIX_MULT_L, _MIX_MULT_R = 0xCA01F9DD, 0x4973F715
_MASK32 = 0xFFFFFFFF


def seed_words(entropy: int | tuple[int, ...], spawn_key: tuple[int, ...] = (), count: int = 4) -> tuple[int, ...]:
    """``SeedSequence(entropy, spawn_key=spawn_key).generate_state(count, np.uint64)`` as Python ints.

    *entropy* a non-negative int or a tuple of them, *spawn_key* a tuple of non-negative ints (the
    caller checks both).
    """
    words = _uint32_words(entropy)
    spawn = _uint32_words(spawn_key)
    if spawn and len(words) < _POOL_SIZE:
        words += [0] * (_POOL_SIZE - len(words))
    pool = _mixed_pool(words + spawn)
    # generate_state: the pool cycled through a second hash, two 32-bit words per uint64 (low first).
    hash_const = _INIT_B
    state = []
    for i in range(2 * count):
        value = pool[i % _POOL_SIZE] ^ hash_const
        hash_const = (hash_const * _MULT_B) & _MASK32
        value = (value * hash_const) & _MASK32
        state.append(value ^ (value >> 16))
    return tuple(state[2 * i] | state[2 * i + 1] << 32 for i in range(count))


def _uint32_words(value: int | tuple[int, ...]) -> list[int]:
    """numpy's ``_coerce_to_uint32_array``: an int as its 32-bit words, low first (0 as one word); a tuple
    as its items' words, concatenated."""
    if isinstance(value, tuple):
        return [word for item in value for word in _uint32_words(item)]
    n = int(value)
    words = [] if n else [0]
    while n:
        words.append(n & _MASK32)
        n >>= 32
    return words


def _mixed_pool(entropy: list[int]) -> list[int]:
    """numpy's ``SeedSequence.mix_entropy`` of the assembled *entropy* words into a pool of 4."""
    hash_const = _INIT_A

    def hashmix(value: int) -> int:
        nonlocal hash_const
        value ^= hash_const
        hash_const = (hash_const * _MULT_A) & _MASK32
        value = (value * hash_const) & _MASK32
        return value ^ (value >> 16)

    def mix(x: int, y: int) -> int:
        result = (_MIX_MULT_L * x - _MIX_MULT_R * y) & _MASK32
        return result ^ (result >> 16)

    pool = [hashmix(entropy[i] if i < len(entropy) else 0) for i in range(_POOL_SIZE)]
    for src in range(_POOL_SIZE):
        for dst in range(_POOL_SIZE):
            if src != dst:
                pool[dst] = mix(pool[dst], hashmix(pool[src]))
    for src in range(_POOL_SIZE, len(entropy)):
        for dst in range(_POOL_SIZE):
            pool[dst] = mix(pool[dst], hashmix(entropy[src]))
    return pool
