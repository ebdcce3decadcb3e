"""symsphere.render._random: the 2D Sobol' sequence, bit reversal and hash-based Owen scrambling."""

import numpy as np
import pytest

from symsphere.render import _integrator as K
from symsphere.render._random import nested_uniform_scramble, reverse_bits32, sobol2



def test_sobol2_first_points():
    points = [tuple(int(c) / 2**32 for c in sobol2(np.uint64(i))) for i in range(4)]
    assert points == [(0, 0), (0.5, 0.5), (0.25, 0.75), (0.75, 0.25)]


def test_reverse_bits():
    for x in (0, 1, 2, 0x80000000, 0x12345678, 0xFFFFFFFF):
        assert int(reverse_bits32(np.uint64(x))) == int(format(x, "032b")[::-1], 2)


def test_owen_sobol_equals_its_definition():
    """The fast bit-reversed form equals scramble(sobol2(scramble(index))) (Burley 2020, listing 3)."""
    from numba import njit

    from symsphere.render._random import _GOLDEN, _MIX1, mix64

    @njit
    def definition(index, key):  # njit: the uint64 products wrap silently, as in the kernels
        m32 = np.uint64(0xFFFFFFFF)
        h1, h2 = mix64(key ^ _GOLDEN), mix64(key ^ _MIX1)
        x, y = sobol2(nested_uniform_scramble(np.uint64(index), h1 & m32))
        return nested_uniform_scramble(x, h1 >> np.uint64(32)), nested_uniform_scramble(y, h2 & m32)

    for key in (np.uint64(1), np.uint64(0xDEADBEEF12345)):
        points = K.sobol_points(512, key)
        for i in range(0, 512, 7):
            x, y = definition(i, key)
            assert tuple(points[i]) == (int(x) / 2**32, int(y) / 2**32)


@pytest.mark.parametrize("key", [0, 1, 2**63 + 12345, 987654321])
def test_owen_sobol_prefixes_are_nets(key):
    """The first 2^k points of one scramble form a (0, k, 2)-net: every dyadic box of area 2^-k holds one."""
    points = K.sobol_points(2**10, np.uint64(key))
    assert np.all((points >= 0) & (points < 1))
    for k in range(11):
        prefix = points[: 2**k]
        for a in range(k + 1):
            cells = np.floor(prefix[:, 0] * 2**a).astype(np.int64) * 2 ** (k - a) + np.floor(
                prefix[:, 1] * 2 ** (k - a)
            ).astype(np.int64)
            assert np.array_equal(np.sort(cells), np.arange(2**k)), (k, a)


def test_owen_scrambles_differ_between_keys():
    a, b = K.sobol_points(64, np.uint64(1)), K.sobol_points(64, np.uint64(2))
    assert not np.any(np.all(a == b, axis=1))


