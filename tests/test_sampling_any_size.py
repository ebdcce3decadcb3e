"""Any size: sample_sphere(n) and sample_hemisphere(n) for every positive n.

Whole orbits first, the last orbit cut short (from a random member on).  The statistical test uses significance 0.01 with a Sidak
correction over the CHI2_TESTS tests of this file (one per row of a cut orbit: 47 on the sphere, 23 on
the hemisphere); the reference density is ``uniform_pdf``, a constant, independent of the maps.
"""

import warnings

import numpy as np
import pytest

from symsphere import fold, iter_sphere, sample_hemisphere, sample_sphere
from symsphere._testing import kernels
from symsphere.frames import frame
from symsphere.points import BasePoints
from symsphere.stats import chi2_test, uniform_pdf

SIGNIFICANCE = 0.01
CHI2_TESTS = 47 + 23
CALLS = 3000  # independent cut orbits per row


@pytest.mark.parametrize("n", [1, 5, 47, 49, 95, 100, 1000])
@pytest.mark.parametrize("points", ["random", "sobol", "halton"])
def test_sphere_any_n_is_a_prefix_of_whole_orbits(n, points):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # Sobol' balance
        d = sample_sphere(n, points=points, rng=3)
        whole = sample_sphere(48 * -(-n // 48), points=points, rng=3)
    assert d.shape == (n, 3) and d.dtype == np.float64
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0)
    _check_cut(d, whole, 48)


def _check_cut(d, whole, count):
    """The same base points: the whole orbits unchanged, then distinct members of the next orbit."""
    n = len(d)
    full = n - n % count
    assert np.array_equal(d[:full], whole[:full])
    cut, orbit = d[full:], whole[full : full + count]
    matches = np.all(cut[:, None, :] == orbit[None, :, :], axis=-1)  # (rows of the cut, members)
    assert np.all(matches.sum(axis=1) >= 1)  # every row is a member of that orbit ...
    assert len(set(np.argmax(matches, axis=1).tolist())) == len(cut)  # ... and no member twice


@pytest.mark.parametrize("n", [1, 7, 23, 25, 50])
def test_hemisphere_any_n(n):
    normal = [0.0, 0.6, 0.8]
    d = sample_hemisphere(n, normal=normal, rng=4)
    assert d.shape == (n, 3)
    _check_cut(d, sample_hemisphere(24 * -(-n // 24), normal=normal, rng=4), 24)
    assert np.all(d @ np.array(normal) >= -1e-12)


@pytest.mark.parametrize("n", [101, 48 * 400 + 5])
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_out_and_dtype_for_any_n(dtype, n):
    out = np.full((n, 3), np.nan, dtype=dtype)
    assert sample_sphere(n, rng=5, dtype=dtype, out=out) is out
    fresh = sample_sphere(n, rng=5, dtype=dtype)
    assert np.array_equal(out, fresh) and fresh.base is None  # a fresh array of n rows, not a view of more
    assert np.all(np.isfinite(out))
    with pytest.raises(ValueError, match="'out' must have shape"):
        sample_sphere(101, out=np.empty((96, 3), dtype=dtype), dtype=dtype)


@pytest.mark.parametrize("count, normal", [(48, None), (24, None), (24, (0.3, -0.5, -0.8))])
@pytest.mark.parametrize("rest, offset", [(1, 0), (5, 3), (5, -2), (-1, 7)])
def test_cut_orbit_is_made_in_the_kernel_call(count, normal, rest, offset):
    # The kernels cut the last orbit themselves (one call, no copy): the rows are those of the whole
    # orbits, then members (offset + i) % count of the last one, bit for bit, whatever the number of parts.
    rest, offset = rest % count, offset % count
    m = 40  # points: more than one batch of the kernels per part
    basis = None if normal is None else frame(np.array(normal) / np.linalg.norm(normal))
    source = BasePoints("random", 11, total=m + 3)
    members = (m - 1) * count + (offset + np.arange(rest)) % count
    for dtype in (np.float64, np.float32):
        whole = kernels.fill_random_orbits(
            source.seed_words, 3, m, "equal_area", count, basis, np.empty((m * count, 3), dtype)
        )
        expected = np.concatenate([whole[: (m - 1) * count], whole[members]])
        for parts in (1, 2, 3, 7):
            got = np.full(((m - 1) * count + rest, 3), np.nan, dtype)
            kernels.fill_random_orbits(
                source.seed_words, 3, m, "equal_area", count, basis, got, parts=parts, offset=offset
            )
            assert np.array_equal(got, expected)
            got[:] = np.nan
            kernels.fill_orbits(source.take(3, m + 3), "equal_area", count, basis, got, parts=parts, offset=offset)
            assert np.array_equal(got, expected)


def test_stratified_needs_a_square_number_of_orbits():
    assert sample_sphere(48 * 15 + 1, points="stratified", rng=0).shape == (721, 3)  # 16 orbits, a square
    with pytest.raises(ValueError):
        sample_sphere(48 * 16 + 1, points="stratified", rng=0)  # 17 orbits


def test_bad_n_still_rejected():
    for n, error in [(0, ValueError), (-48, ValueError), (4.5, TypeError), (True, TypeError)]:
        with pytest.raises(error, match="'n'"):
            sample_sphere(n)
    with pytest.raises(ValueError, match="not a multiple of 48"):
        iter_sphere(100)  # the streaming samplers stay in whole orbits


def test_sobol_warning_is_attributed_to_the_caller():
    # the balance warning pointed at a line of symsphere/sampling.py.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sample_sphere(48 * 6, points="sobol", rng=0)
    assert [w.filename for w in caught if "power of 2" in str(w.message)] == [__file__]


@pytest.mark.slow
@pytest.mark.statistical
@pytest.mark.parametrize("count", [48, 24])
def test_every_row_of_a_cut_orbit_is_uniform(count):
    # n = count - 1: no whole orbit, one orbit cut to count - 1 members from a random offset.  CALLS independent runs
    # give, for each row, CALLS independent directions; each row is tested on its own.  (Row k of a whole
    # orbit lies in triangle k: the cut orbit's rows are uniform only because its members are random.)
    sampler, domain = (sample_sphere, "sphere") if count == 48 else (sample_hemisphere, "hemisphere")
    rows = np.stack([sampler(count - 1, rng=seed) for seed in range(CALLS)], axis=1)  # (row, run, 3)
    for row, directions in enumerate(rows):
        result = chi2_test(directions, uniform_pdf(domain), domain, significance=SIGNIFICANCE, test_count=CHI2_TESTS)
        assert result.passed, f"row {row}: {result}"


def test_cut_orbit_members_are_random():
    # Row k of a whole orbit is always in triangle k; the rows of a cut orbit are not tied to a triangle.
    triangles = np.array([fold(sample_sphere(5, rng=seed))[0] for seed in range(200)])  # (run, row)
    assert all(len(np.unique(triangles[:, row])) > 30 for row in range(5))
    assert all(len(set(run)) == 5 for run in triangles.tolist())
