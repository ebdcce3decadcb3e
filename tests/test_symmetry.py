"""Tables 1 and 2 entry by entry, orbit/fold round trips, the tie rule."""

import numpy as np
import pytest

from symsphere import HEMISPHERE_MAPS, SPHERE_MAPS, fold, orbit

# The paper's Table 2, transcribed as printed: rows P0..P5 then barred P0..P5,
# columns P, P', P'', P'''.  Table 1 is its first six rows.
TABLE_2 = """
x,y,z   -x,y,z   -x,-y,z   x,-y,z
y,x,z   -y,x,z   -y,-x,z   y,-x,z
z,y,x   -z,y,x   -z,-y,x   z,-y,x
z,x,y   -z,x,y   -z,-x,y   z,-x,y
x,z,y   -x,z,y   -x,-z,y   x,-z,y
y,z,x   -y,z,x   -y,-z,x   y,-z,x
x,y,-z  -x,y,-z  -x,-y,-z  x,-y,-z
y,x,-z  -y,x,-z  -y,-x,-z  y,-x,-z
z,y,-x  -z,y,-x  -z,-y,-x  z,-y,-x
z,x,-y  -z,x,-y  -z,-x,-y  z,-x,-y
x,z,-y  -x,z,-y  -x,-z,-y  x,-z,-y
y,z,-x  -y,z,-x  -y,-z,-x  y,-z,-x
"""
ENTRIES = [entry for row in TABLE_2.split("\n") if row for entry in row.split()]
POINT = {"x": 0.31, "y": 0.17, "z": 0.93}


def _evaluate(entry):
    return [(-POINT[c[1]] if c.startswith("-") else POINT[c]) for c in entry.split(",")]


@pytest.mark.parametrize("k", range(48))
def test_table_entry(k):
    p = np.array([POINT["x"], POINT["y"], POINT["z"]])
    expected = _evaluate(ENTRIES[k])
    assert orbit(p)[k].tolist() == expected
    assert (p @ SPHERE_MAPS[k]).tolist() == expected
    if k < 24:
        assert orbit(p, "hemisphere")[k].tolist() == expected


def test_examples_from_the_issue():
    p = np.array([1.0, 2.0, 3.0])
    assert orbit(p)[1].tolist() == [-1, 2, 3]
    assert orbit(p)[13].tolist() == [-3, 1, 2]
    assert orbit(p)[24].tolist() == [1, 2, -3]


def test_paper_composition_example():
    # Section 2: P0 * (swap x,z) * (swap y,z) = P3 = (z0, x0, y0).
    swap_xz = np.array([[0, 0, 1], [0, 1, 0], [1, 0, 0]])
    swap_yz = np.array([[1, 0, 0], [0, 0, 1], [0, 1, 0]])
    assert np.array_equal(swap_xz @ swap_yz, SPHERE_MAPS[12])


def test_maps_are_distinct_signed_permutations():
    assert SPHERE_MAPS.shape == (48, 3, 3) and HEMISPHERE_MAPS.shape == (24, 3, 3)
    assert np.array_equal(HEMISPHERE_MAPS, SPHERE_MAPS[:24])
    assert np.issubdtype(SPHERE_MAPS.dtype, np.integer)
    for m in SPHERE_MAPS:
        assert np.array_equal(m @ m.T, np.eye(3))
        assert sorted(np.abs(m).sum(axis=0)) == [1, 1, 1]
    assert len({m.tobytes() for m in SPHERE_MAPS}) == 48
    # the group of all signed permutations has exactly 48 elements: these are all of them
    # the hemisphere maps keep z >= 0 on T0
    t0 = np.array([0.31, 0.17, 0.93])
    assert np.all(orbit(t0, "hemisphere")[:, 2] > 0)
    assert np.all(orbit(t0)[24:, 2] < 0)


def test_orbit_shapes_and_broadcasting():
    p = np.random.default_rng(0).random((4, 5, 3))
    assert orbit(p).shape == (4, 5, 48, 3)
    assert orbit(p, "hemisphere").shape == (4, 5, 24, 3)
    assert np.array_equal(orbit(p)[2, 3], orbit(p[2, 3]))
    assert orbit(p.astype(np.float32)).dtype == np.float32


def test_orbit_of_interior_point_covers_each_triangle_once():
    base = np.array([0.31, 0.17, 0.93])
    images = orbit(base)
    ks, bases = fold(images)
    assert ks.tolist() == list(range(48))
    assert np.array_equal(bases, np.broadcast_to(base, (48, 3)))


@pytest.mark.parametrize("domain", ["sphere", "hemisphere"])
def test_fold_round_trip_random(domain):
    d = np.random.default_rng(1).normal(size=(10_000, 3))
    if domain == "hemisphere":
        d[:, 2] = np.abs(d[:, 2])
    k, base = fold(d, domain)
    z, x, y = base[:, 2], base[:, 0], base[:, 1]
    assert np.all((z >= x) & (x >= y) & (y >= 0))
    assert np.all(orbit(base, domain)[np.arange(len(d)), k] == d)
    assert k.max() < (48 if domain == "sphere" else 24)


def test_fold_ties_take_lowest_index():
    # Boundary directions: zero coordinates, equal absolute values, the axes, the equator.
    values = [-1.0, -0.5, 0.0, 0.5, 1.0]
    grid = np.array(np.meshgrid(values, values, values, indexing="ij")).reshape(3, -1).T
    k, base = fold(grid)
    images = orbit(base)
    for i, d in enumerate(grid):
        matching = [j for j in range(48) if np.all(images[i, j] == d)]
        assert k[i] == min(matching)
    equator = np.array([[0.6, -0.8, 0.0], [0.0, 0.0, 0.0]])
    assert np.all(fold(equator)[0] < 24)


def test_fold_keeps_negative_zero_consistent():
    k, base = fold(np.array([-0.0, 0.6, 0.8]))
    assert np.all(orbit(base)[k] == [0.0, 0.6, 0.8])


def test_hemisphere_fold_rejects_lower_half():
    with pytest.raises(ValueError, match="'d' must have z >= 0"):
        fold([0.1, 0.2, -0.3], "hemisphere")


@pytest.mark.parametrize(
    "call, error, match",
    [
        (lambda: orbit([1.0, 2.0]), ValueError, "'p' must have shape"),
        (lambda: orbit([1.0, np.nan, 0.0]), ValueError, "'p' must be finite"),
        (lambda: orbit([1.0, 2.0, 3.0], "torus"), ValueError, "'torus' is not a valid domain"),
        (lambda: fold("abc"), TypeError, "'d'"),
        (lambda: fold([[1, 2, 3, 4]]), ValueError, "'d' must have shape"),
        (lambda: fold([1.0, 2.0, 3.0], domain=3), ValueError, "valid domain"),
    ],
)
def test_bad_input(call, error, match):
    with pytest.raises(error, match=match):
        call()


def test_base_point_is_the_sorted_absolute_coordinates():
    # base_point (fold's base, and the densities' preimage in T0) selects by a min/max network; the
    # independent reference sorts. Ties, zeros, -0.0, and float32 kept as float32.
    from symsphere.symmetry import base_point

    rng = np.random.default_rng(7)
    values = np.array([-1.0, -0.5, -0.0, 0.0, 0.5, 1.0])
    grid = np.array(np.meshgrid(values, values, values, indexing="ij")).reshape(3, -1).T
    for d in (rng.normal(size=(5_000, 3)), grid, rng.normal(size=(7, 4, 3)).astype(np.float32)):
        expected = np.sort(np.abs(d), axis=-1)[..., [1, 0, 2]]
        got = base_point(d)
        assert got.dtype == d.dtype and got.shape == d.shape
        np.testing.assert_array_equal(got, expected)
        assert not np.any(np.signbit(got))
