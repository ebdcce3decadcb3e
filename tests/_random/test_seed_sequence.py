"""The seed words of numpy's SeedSequence, in Python's integers, equal numpy's own."""

import random

import numpy as np
import pytest

from symsphere._testing import seed_sequence


def _cases():
    fixed = [(0, ()), (1, ()), (2**32 - 1, ()), (2**32, ()), (2**64 - 1, ()), (2**200 + 7, ()),
             ((1, 2, 3, 4), (0,)), ((0, 0, 0, 0), (1,)), ((5,), (0,)), (7, (3, 4)), ((2**63 - 1,) * 4, (2,))]  # fmt: skip
    draw = random.Random(5)  # fixed seed: the same cases every run
    for _ in range(200):
        size = draw.randrange(0, 6)
        bits = [1, 31, 32, 33, 63, 64, 65]
        entropy = (
            tuple(draw.randrange(0, 2 ** draw.choice(bits)) for _ in range(size))
            if size
            else draw.randrange(0, 2 ** draw.choice([1, 32, 63, 128]))
        )
        spawn_key = tuple(draw.randrange(0, 2 ** draw.choice([1, 32, 40])) for _ in range(draw.randrange(0, 3)))
        fixed.append((entropy, spawn_key))
    return fixed


@pytest.mark.parametrize("count", [1, 4, 5])
def test_seed_words_equal_numpys_seed_sequence(count):
    for entropy, spawn_key in _cases():
        expected = np.random.SeedSequence(entropy, spawn_key=spawn_key).generate_state(count, np.uint64)
        got = seed_sequence.seed_words(entropy, spawn_key, count)
        assert got == tuple(int(w) for w in expected), (entropy, spawn_key)
