"""symsphere.points: base points of the unit square, addressed by index.

References are independent of the code under test: numpy's own PCG64 stream for random points,
scipy's own engines for Sobol' and Halton, and the definition of a jittered grid for stratified points.
"""

import numpy as np
import pytest
from scipy.stats import qmc

from symsphere.points import BLOCK, POINT_SETS, BasePoints, check_points, unit_square_points


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
