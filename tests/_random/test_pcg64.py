"""symsphere._random.pcg64: numpy's PCG64 in numba (seeding, jump ahead, step) against numpy's own stream."""

import numpy as np
import pytest
from numba import njit

from symsphere._testing import pcg64
from symsphere.points import BLOCK, BasePoints


def test_random_points_are_numpys_pcg64_stream():
    # Independent reference: numpy's own PCG64 stream from the documented seed, drawn in one go.
    source = BasePoints("random", 8, total=3 * BLOCK)
    seed = np.random.SeedSequence(source.root_entropy, spawn_key=(0,))
    expected = np.random.Generator(np.random.PCG64(seed)).random((3 * BLOCK, 2))
    assert np.array_equal(source.take(0, 3 * BLOCK), expected)
    assert np.array_equal(source.take(BLOCK + 3, BLOCK + 9), expected[BLOCK + 3 : BLOCK + 9])
    assert np.array_equal(source.take(np.int64(7), np.int32(9)), expected[7:9])  # numpy integers too

    # The kernels' own PCG64 (seeding, jump, step) continues numpy's stream from any index.
    @njit
    def draw(words, index, k):
        stream = pcg64.pcg64_advanced(pcg64.pcg64_seeded(words), 2 * index)
        return [pcg64.pcg64_random(stream) for _ in range(k)]

    assert np.array_equal(draw(source.seed_words, 101, 2 * 400), expected[101:501].ravel())
    assert BasePoints("sobol", 8, total=16).seed_words is None


def _numpy_state(bit_generator):
    state = bit_generator.state["state"]
    return state["state"], state["inc"]


def _as_int128(stream):
    return int(stream[0]) << 64 | int(stream[1]), int(stream[2]) << 64 | int(stream[3])


@pytest.mark.parametrize("seed", range(5))
def test_pcg64_seeding_and_jump_ahead_equal_numpys(seed):
    rng = np.random.default_rng(seed)
    sequence = np.random.SeedSequence(rng.integers(0, 2**63, size=4).tolist(), spawn_key=(0,))
    words = sequence.generate_state(4, np.uint64)
    start = njit(pcg64.pcg64_seeded)(words)
    assert _as_int128(start) == _numpy_state(np.random.PCG64(sequence))
    jump = njit(pcg64.pcg64_advanced)
    for draws in [0, 1, 2, 3, 2**32 + 5, 2**62 + 999, 2**63 - 1, *rng.integers(0, 2**63, size=20)]:
        bit_generator = np.random.PCG64(sequence)
        bit_generator.advance(int(draws))
        assert _as_int128(jump(start, np.uint64(draws))) == _numpy_state(bit_generator)
        # The kernels' parts start from pcg64_state (Python's integers seed and jump).
        assert _as_int128(pcg64.pcg64_state(words, int(draws))) == _numpy_state(bit_generator)


@pytest.mark.parametrize("seed", [0, 1, 2**40 + 3])
def test_pcg64_integers63_equal_numpys_integers(seed):
    sequence = np.random.SeedSequence(seed)
    expected = np.random.Generator(np.random.PCG64(sequence)).integers(0, 2**63, size=6, dtype=np.int64)
    assert pcg64.pcg64_integers63(sequence.generate_state(4, np.uint64), 6) == tuple(int(e) for e in expected)
