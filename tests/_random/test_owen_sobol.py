"""symsphere._random.owen_sobol: the 2D Sobol' sequence, bit reversal, hash-based Owen scrambling and interlacing."""

import numpy as np
import pytest
from references import net_t_value

from symsphere._testing import owen_sobol, splitmix
from symsphere._testing import render_probes as P

nested_uniform_scramble, reverse_bits32, sobol2 = (
    owen_sobol.nested_uniform_scramble,
    owen_sobol.reverse_bits32,
    owen_sobol.sobol2,
)
mix64 = splitmix.mix64


def test_sobol2_first_points():
    points = [tuple(int(c) / 2**32 for c in sobol2(np.uint64(i))) for i in range(4)]
    assert points == [(0, 0), (0.5, 0.5), (0.25, 0.75), (0.75, 0.25)]


def test_reverse_bits():
    for x in (0, 1, 2, 0x80000000, 0x12345678, 0xFFFFFFFF):
        assert int(reverse_bits32(np.uint64(x))) == int(format(x, "032b")[::-1], 2)


def test_owen_sobol_equals_its_definition():
    """The fast bit-reversed form equals scramble(sobol2(scramble(index))) (Burley 2020, listing 3)."""
    from numba import njit

    @njit
    def definition(index, key):  # njit: the uint64 products wrap silently, as in the kernels
        m32 = np.uint64(0xFFFFFFFF)
        h1, h2 = mix64(key ^ splitmix.GOLDEN), mix64(key ^ splitmix.MIX1)
        x, y = sobol2(nested_uniform_scramble(np.uint64(index), h1 & m32))
        return nested_uniform_scramble(x, h1 >> np.uint64(32)), nested_uniform_scramble(y, h2 & m32)

    for key in (np.uint64(1), np.uint64(0xDEADBEEF12345)):
        points = P.sobol_points(512, key)
        for i in range(0, 512, 7):
            x, y = definition(i, key)
            assert tuple(points[i]) == (int(x) / 2**32, int(y) / 2**32)


@pytest.mark.parametrize("key", [0, 1, 2**63 + 12345, 987654321])
def test_owen_sobol_prefixes_are_nets(key):
    """The first 2^k points of one scramble form a (0, k, 2)-net: every dyadic box of area 2^-k holds one."""
    points = P.sobol_points(2**10, np.uint64(key))
    assert np.all((points >= 0) & (points < 1))
    for k in range(11):
        prefix = points[: 2**k]
        for a in range(k + 1):
            cells = np.floor(prefix[:, 0] * 2**a).astype(np.int64) * 2 ** (k - a) + np.floor(
                prefix[:, 1] * 2 ** (k - a)
            ).astype(np.int64)
            assert np.array_equal(np.sort(cells), np.arange(2**k)), (k, a)


def test_owen_scrambles_differ_between_keys():
    a, b = P.sobol_points(64, np.uint64(1)), P.sobol_points(64, np.uint64(2))
    assert not np.any(np.all(a == b, axis=1))


# --- interlaced (higher-order) Sobol' points --------------------------------------------------------


def _gray(n):
    return n ^ (n >> 1)


def test_sobol_direction_numbers_are_scipys():
    """Direction number k of dimension d is scipy's unscrambled point with Gray code 2^k (index 2^(k+1) - 1).

    scipy's fast_forward steps through every point (O(n)): reaching index 2^32 - 1 for k = 31 took 100 s of
    the suite.  So the public points are read for k <= 22 (index < 2^23, 0.1 s), and the table they come from
    (scipy's engine._sv, a private attribute: checked against those public points first) for all 32; if a
    scipy release drops _sv, every k is read from the public points again (slow, but the same test).
    """
    from scipy.stats import qmc

    sobol_coordinate = owen_sobol.sobol_coordinate

    engine = qmc.Sobol(d=6, scramble=False, bits=32)

    def public(k):
        engine.reset()
        engine.fast_forward(2 ** (k + 1) - 1)
        return [int(e) for e in (engine.random(1)[0] * 2.0**32).astype(np.uint64)]

    table = getattr(engine, "_sv", None)
    usable = table is not None and np.shape(table) == (6, 32)
    for k in range(32):
        if k <= 22 or not usable:
            expected = public(k)
            if usable:
                assert [int(table[d, k]) for d in range(6)] == expected, ("scipy's _sv is not its points", k)
        else:
            expected = [int(table[d, k]) for d in range(6)]
        got = [int(sobol_coordinate(np.uint64(2**k), np.int64(d))) for d in range(6)]
        assert got == expected, k


@pytest.mark.parametrize("factor", [2, 3])
def test_unscrambled_interlaced_points_are_the_librarys(factor):
    """Unscrambled, the kernel's points are points.interlace_digits of scipy's Sobol' points, bit for bit.

    scipy's point n is the natural-order point n ^ (n >> 1) (Gray code); interlace_digits keeps the leading
    26 (17) digits of each of scipy's 30, which the kernel's 32-bit coordinates share.
    """
    from scipy.stats import qmc

    from symsphere.points import interlace_digits

    count = 2**12
    n = np.arange(count)
    mine = P.interlaced_points(count, np.uint64(0), factor, False)
    reference = interlace_digits(qmc.Sobol(d=2 * factor, scramble=False).random(count), factor)
    np.testing.assert_array_equal(mine[_gray(n)], reference)


def test_interlace_fractions_is_interlace_digits():
    """On random 32-bit fractions: the kernel's interlacing equals the library's, bit for bit."""
    from numba import njit

    from symsphere.points import interlace_digits

    interlace_fractions = owen_sobol.interlace_fractions

    @njit
    def interlace(words, factor):
        out = np.empty(words.shape[0])
        for i in range(words.shape[0]):
            out[i] = interlace_fractions(words[i, 0], words[i, 1], words[i, factor - 1], factor)
        return out

    rng = np.random.default_rng(14)
    for factor in (2, 3):
        words = rng.integers(0, 2**32, size=(2000, factor), dtype=np.uint64)
        words[:4] = [[0] * factor, [2**32 - 1] * factor, [2**31] * factor, [1] * factor]
        np.testing.assert_array_equal(interlace(words, factor), interlace_digits(words / 2.0**32, factor)[:, 0])


def test_owen_sobol_interlaced_equals_its_definition():
    """The table-driven form equals: shuffle the index, scramble each Sobol' coordinate, interlace."""
    from numba import njit

    interlace_fractions, sobol_coordinate = owen_sobol.interlace_fractions, owen_sobol.sobol_coordinate

    @njit
    def definition(index, key, factor):
        m32, s32 = np.uint64(0xFFFFFFFF), np.uint64(32)
        h1, h2, h3, h4 = (
            mix64(key ^ splitmix.GOLDEN),
            mix64(key ^ splitmix.MIX1),
            mix64(key ^ splitmix.MIX2),
            mix64(key ^ splitmix.ODD),
        )
        seeds = (h1 >> s32, h2 & m32, h2 >> s32, h3 & m32, h3 >> s32, h4 & m32)
        i = nested_uniform_scramble(np.uint64(index), h1 & m32)
        x = [nested_uniform_scramble(sobol_coordinate(i, d), seeds[d]) for d in range(6)]
        if factor == 2:
            return interlace_fractions(x[0], x[1], x[1], 2), interlace_fractions(x[2], x[3], x[3], 2)
        return interlace_fractions(x[0], x[1], x[2], 3), interlace_fractions(x[3], x[4], x[5], 3)

    for factor in (2, 3):
        for key in (np.uint64(1), np.uint64(0xDEADBEEF12345)):
            points = P.interlaced_points(512, key, factor, True)
            for i in range(0, 512, 7):
                assert tuple(points[i]) == definition(i, key, factor), (factor, key, i)


@pytest.mark.parametrize("factor", [2, 3])
@pytest.mark.parametrize("key", [0, 1, 2**63 + 12345])
def test_owen_sobol_interlaced_prefixes_are_nets(factor, key):
    """The first 2^m points of one scramble are a (t, m, 2)-net with the t of the library's unscrambled points.

    Reference: the t of points.interlace_digits of scipy's unscrambled Sobol' points, found by brute
    force (no larger than the t of the 2 x factor dimensional source net: measured 2-3 and 3-4).  An
    Owen scramble maps each elementary box of the source onto one of the same shape, and the index
    shuffle picks an aligned block of the sequence (a digital shift of the first one), so every
    elementary box of the interlaced points holds exactly what it holds unscrambled: t is equal.
    """
    from scipy.stats import qmc

    from symsphere.points import interlace_digits

    points = P.interlaced_points(2**10, np.uint64(key), factor, True)
    assert np.all((points > 0) & (points < 1))
    for m in (4, 7, 10):
        source = qmc.Sobol(d=2 * factor, scramble=False).random(2**m)
        t_reference = net_t_value(interlace_digits(source, factor), m)
        assert t_reference <= min(net_t_value(source, m), 4)
        assert net_t_value(points[: 2**m], m) == t_reference, m


def test_owen_sobol_interlaced_first_point_is_uniform():
    """Over 4096 keys, point 0 of each scramble is uniform on the square (chi^2, 8 x 8 cells; Sidak over 2 factors)."""
    from scipy import stats

    for factor in (2, 3):
        first = np.array([P.interlaced_points(1, np.uint64(key), factor, True)[0] for key in range(4096)])
        counts = np.histogram2d(first[:, 0], first[:, 1], bins=8, range=[[0, 1], [0, 1]])[0].ravel()
        p = stats.chisquare(counts).pvalue
        assert p > 1 - (1 - 1e-3) ** 0.5, (factor, p)


def test_owen_sobol_interlaced_scrambles_differ_between_keys():
    for factor in (2, 3):
        a = P.interlaced_points(64, np.uint64(1), factor, True)
        b = P.interlaced_points(64, np.uint64(2), factor, True)
        assert not np.any(np.all(a == b, axis=1))
