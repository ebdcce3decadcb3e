"""symsphere.points: base points of the unit square, addressed by index.

References are independent of the code under test: numpy's own PCG64 stream for random points,
scipy's own engines for Sobol' and Halton, and the definition of a jittered grid for stratified points.
"""

import numpy as np
import pytest
from references import net_t_value
from scipy.stats import qmc

from symsphere import points
from symsphere.points import BLOCK, POINT_SETS, BasePoints, check_points, interlace_digits, unit_square_points


def test_random_points_are_numpys_pcg64_stream():
    # Point i is draws 2i, 2i + 1 of Generator(PCG64(SeedSequence(root, spawn_key=(0,)))).random().
    source = BasePoints("random", 11, total=1000)
    stream = np.random.Generator(np.random.PCG64(np.random.SeedSequence(source.root_entropy, spawn_key=(0,))))
    assert np.array_equal(source.take(0, 1000), stream.random((1000, 2)))


def test_stratified_points_jitter_every_cell_once():
    side = 16
    uv = unit_square_points(side * side, "stratified", rng=3)
    cells = np.floor(uv * side).astype(int)
    assert len({(int(a), int(b)) for a, b in cells}) == side * side  # one point per cell of the grid
    assert np.all((uv >= 0) & (uv < 1))


@pytest.mark.parametrize("name, engine", [("sobol", qmc.Sobol), ("halton", qmc.Halton)])
def test_engine_points_are_a_scrambled_scipy_sequence(name, engine):
    uv = unit_square_points(256, name, rng=5)
    assert uv.shape == (256, 2) and np.all((uv >= 0) & (uv < 1))
    if name == "sobol":  # a scrambled (0, 8, 2)-net in base 2: every elementary interval of area 1/256 holds one point
        for k in range(9):
            cells = np.floor(uv[:, 0] * 2**k).astype(int) * 2 ** (8 - k) + np.floor(uv[:, 1] * 2 ** (8 - k)).astype(int)
            assert len(set(cells.tolist())) == 256
    given = engine(d=2, scramble=False)
    assert np.array_equal(unit_square_points(8, given), engine(d=2, scramble=False).random(8))


def test_check_points_accepts_the_named_sets_and_2d_engines():
    for name in POINT_SETS:
        assert check_points(name) is None
    engine = qmc.Sobol(d=2, seed=1)
    assert check_points(engine) is engine
    with pytest.raises(ValueError, match="'points'.*d=2"):
        check_points(qmc.Sobol(d=3, seed=1))
    with pytest.raises(ValueError, match="'lattice' is not a valid points; use one of"):
        check_points("lattice")
    with pytest.raises(TypeError, match="'points'"):
        check_points(4)


@pytest.mark.parametrize("points", ["sobol", "halton"])
def test_base_points_of_an_engine_taken_twice(points):
    source = BasePoints(points, 4, total=4096)
    first = source.take(0, 4096)
    assert np.array_equal(source.take(0, 4096), first)  # from the start again (scipy: fast_forward(0) raises)
    assert np.array_equal(source.take(100, 200), first[100:200])


def test_base_points_any_stretch():
    source = BasePoints("random", 4, total=3 * BLOCK)
    whole = source.take(0, 3 * BLOCK)
    for start, stop in [(0, 1), (BLOCK - 1, BLOCK + 1), (5, 2 * BLOCK + 7), (3 * BLOCK, 3 * BLOCK)]:
        assert np.array_equal(BasePoints("random", 4, total=3 * BLOCK).take(start, stop), whole[start:stop])
        assert np.array_equal(source.take(start, stop), whole[start:stop])
    with pytest.raises(ValueError, match="'start'"):
        source.take(2, 1)


# --- interlaced Sobol' points (higher-order digital nets) -----------------------------------------


@pytest.mark.parametrize("factor", [2, 3])
def test_interlaced_sobol_is_a_digital_net(factor):
    # Interlacing maps a (t, m, 2 factor)-net to a (t, m, 2)-net: the interlaced box with depths (k1, k2)
    # is the box of the source net with depths ceil((k_j - r)/factor), r = 0 ... factor - 1, whose
    # depths add up to k1 + k2.  Reference: the t of scipy's unscrambled Sobol' points of dimension
    # 2 factor, found by brute force; the interlaced points, unscrambled (interlace_digits of those
    # points) and scrambled (BasePoints), must be nets with that t or better (measured: 2, 2, 2, 1).
    name = f"sobol_interlaced{factor}"
    for m in (6, 9):
        source = qmc.Sobol(d=2 * factor, scramble=False).random(2**m)
        t_source = net_t_value(source, m)
        assert t_source <= 4  # measured t = 2, 3 (dimension 4) and 3, 4 (dimension 6) at m = 6, 9
        assert net_t_value(interlace_digits(source, factor), m) <= t_source
        for seed in (0, 1):
            scrambled = BasePoints(name, seed, total=2**m).take(0, 2**m)
            assert scrambled.shape == (2**m, 2) and np.all((scrambled > 0) & (scrambled < 1))
            assert net_t_value(scrambled, m) <= t_source


def test_interlace_digits_by_definition():
    # Digit by digit, from the definition (Python integers), on random inputs.
    rng = np.random.default_rng(8)
    for factor in (1, 2, 3, 5):
        bits = 53 // factor
        x = rng.random((20, 2 * factor))
        expected = np.empty((20, 2))
        for i, row in enumerate(x):
            for j in range(2):
                sources = [int(np.floor(row[j * factor + k] * 2.0**bits)) for k in range(factor)]
                value = 0
                for b in range(bits):
                    for k in range(factor):
                        value = (value << 1) | ((sources[k] >> (bits - 1 - b)) & 1)
                expected[i, j] = (value + 0.5) / 2.0 ** (factor * bits)
        assert np.array_equal(interlace_digits(x, factor), expected)
    with pytest.raises(ValueError, match="'factor'"):
        interlace_digits(x, 0)
    with pytest.raises(ValueError, match="'x'"):
        interlace_digits(np.zeros((3, 5)), 2)
    with pytest.raises(ValueError, match="'x'"):
        interlace_digits(np.ones((3, 4)), 2)


@pytest.mark.parametrize("name", ["sobol_interlaced2", "sobol_interlaced3"])
def test_interlaced_points_by_index(name):
    total = 4 * BLOCK
    whole = BasePoints(name, 6, total=total).take(0, total)
    for start, stop in [(0, 1), (BLOCK - 1, BLOCK + 1), (5, 2 * BLOCK + 7)]:
        assert np.array_equal(BasePoints(name, 6, total=total).take(start, stop), whole[start:stop])
    assert not np.array_equal(BasePoints(name, 7, total=total).take(0, 8), whole[:8])  # another scrambling
    with pytest.warns(UserWarning, match="power of 2"):
        BasePoints(name, 6, total=3 * BLOCK)


def test_interlaced_points_converge_faster_on_a_smooth_function():
    # f(u, v) = exp(u) cos(u + 2 v), exact integral over the square in closed form (complex exponentials).
    # RMSE over 32 scramblings at 2^12 points (seeded, so deterministic): measured 6.6e-6 for 'sobol',
    # 1.7e-7 and 2.4e-7 for the interlaced sets (slopes about -1.3 against -2.4 and -2.5 over 2^6 ... 2^14).
    exact = (((np.exp(1 + 1j) - 1) / (1 + 1j)) * ((np.exp(2j) - 1) / 2j)).real

    def rmse(name):
        errors = [
            np.mean(np.exp(uv[:, 0]) * np.cos(uv[:, 0] + 2 * uv[:, 1])) - exact
            for uv in (BasePoints(name, seed, total=2**12).take(0, 2**12) for seed in range(32))
        ]
        return np.sqrt(np.mean(np.square(errors)))

    plain = rmse("sobol")
    assert rmse("sobol_interlaced2") < plain / 10
    assert rmse("sobol_interlaced3") < plain / 10


@pytest.mark.slow
@pytest.mark.statistical
def test_interlaced_points_keep_the_scheme_unbiased():
    # The scheme with interlaced base points is unbiased: the mean of 200 independent estimates (seeds
    # 0 ... 199, each of 8 replicates at n = 48 * 64 * 8) against closed forms, a smooth and a
    # discontinuous integrand: exp(w . a) (4 pi sinh|a| / |a|) and the indicator of a cap (2 pi (1 - t)).
    # Student t test of the mean, family significance 1e-3, Sidak-corrected over the 4 tests.
    from scipy import stats

    import symsphere

    a, centre, t = np.array([0.3, -0.5, 0.6]), np.array([1.0, 2.0, 2.0]) / 3.0, 0.3
    cases = [
        (lambda w: np.exp(w @ a), 4 * np.pi * np.sinh(np.linalg.norm(a)) / np.linalg.norm(a)),
        (lambda w: (w @ centre > t).astype(np.float64), 2 * np.pi * (1 - t)),
    ]
    seeds, tests = 200, 4
    alpha = 1 - (1 - 1e-3) ** (1 / tests)
    threshold = stats.t.ppf(1 - alpha / 2, seeds - 1)
    for name in ("sobol_interlaced2", "sobol_interlaced3"):
        for f, exact in cases:
            estimates = np.array(
                [
                    symsphere.integrate(f, n=48 * 64 * 8, points=name, rng=seed, replicates=8).integral
                    for seed in range(seeds)
                ]
            )
            z = (estimates.mean() - exact) / (estimates.std(ddof=1) / np.sqrt(seeds))
            assert abs(z) < threshold, (name, exact, z)


@pytest.mark.parametrize("start", [1.5, None, "1"])
def test_take_names_a_start_or_stop_that_is_not_an_integer(start):
    points = BasePoints("random", 1, 64)
    with pytest.raises(TypeError, match=r"^'start' must be an integer index; got "):
        points.take(start=start, stop=8)
    with pytest.raises(TypeError, match=r"^'stop' must be an integer index; got "):
        points.take(start=0, stop=start)
    assert points.take(start=np.int64(1), stop=8).shape == (7, 2)


# --- per_point is checked for every point set ----------------------------------------------------------------------


@pytest.mark.parametrize("point_set", ["random", "sobol", "halton", "sobol_interlaced2", "sobol_interlaced3"])
def test_per_point_is_checked(point_set):
    with pytest.raises(TypeError, match="'per_point'"):
        points.unit_square_points(64, point_set, 1, per_point="x")
    for bad in (-1, 0):
        with pytest.raises(ValueError, match="'per_point'"):
            points.unit_square_points(64, point_set, 1, per_point=bad)
    with pytest.raises(ValueError, match="per_point"):
        points.unit_square_points(64, point_set, 1, per_point=2**60)
    assert points.unit_square_points(64, point_set, 1, per_point=48).shape == (64, 2)


@pytest.mark.parametrize("rng", [0, 5, np.int64(2**40), np.random.SeedSequence(9, spawn_key=(1,))])
def test_root_entropy_is_the_first_draw_of_default_rng(rng):
    # An int or SeedSequence seeds without a Generator: the same four numbers as the documented draw.
    expected = np.random.default_rng(rng).integers(0, 2**63, size=4, dtype=np.int64)
    assert BasePoints("random", rng, total=1).root_entropy == tuple(int(e) for e in expected)
    generator = np.random.default_rng(rng)
    assert BasePoints("random", generator, total=1).root_entropy == tuple(int(e) for e in expected)
