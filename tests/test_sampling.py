"""The scheme: layout of the orbits, point sets, determinism, dtypes, out=, normals, pdfs, bad input.

Any size: sample_sphere(n) and sample_hemisphere(n) for every positive n.

Whole orbits first, the last orbit cut short (from a random member on).  The statistical test uses significance 0.01 with a Sidak
correction over the CHI2_TESTS tests of this file (one per row of a cut orbit: 47 on the sphere, 23 on
the hemisphere); the reference density is ``uniform_pdf``, a constant, independent of the maps.

The sampling engine ``symsphere.Scheme``: its stream, reset, fast_forward, blocks, pdf, out=/dtype=, errors.

The functions of :mod:`symsphere.sampling` are one call on a fresh engine each; their outputs are
pinned bit for bit by tests/test_public_outputs.py, so here the engine is compared with them and
with itself (a stream split into calls against the same stream in one call).
"""

import time
import warnings

import numpy as np
import pytest
from references import scaled_for_load
from scipy.stats import qmc

import symsphere
from symsphere import (
    METHODS,
    Scheme,
    fold,
    harmonics,
    hemisphere_pdf,
    iter_hemisphere,
    iter_sphere,
    orbit,
    sample_hemisphere,
    sample_sphere,
    sphere_pdf,
    square_to_triangle_pdf,
    symmetry,
    triangle_to_square,
    warps,
)
from symsphere._testing import kernels
from symsphere.frames import frame
from symsphere.points import BasePoints
from symsphere.stats import chi2_test, uniform_pdf
from symsphere.symmetry import orbit_size

SAMPLERS = [(sample_sphere, 48, "sphere"), (sample_hemisphere, 24, "hemisphere")]


@pytest.mark.parametrize("sampler, count, domain", SAMPLERS)
@pytest.mark.parametrize("method", METHODS)
def test_rows_are_orbits_in_table_order(sampler, count, domain, method):
    d = sampler(count * 50, method=method, rng=3)
    groups = d.reshape(50, count, 3)
    k, base = fold(d, domain)
    base = base.reshape(50, count, 3)
    assert np.all(base == base[:, :1])  # one base point per group
    assert np.all(k.reshape(50, count) == np.arange(count))
    assert np.array_equal(orbit(base[:, 0], domain), groups)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1, atol=1e-15)


@pytest.mark.parametrize("points", ["random", "stratified", "sobol", "halton"])
@pytest.mark.parametrize("sampler, count, domain", SAMPLERS)
def test_same_seed_same_output(points, sampler, count, domain):
    n = count * 64
    a = sampler(n, points=points, rng=12345)
    assert np.array_equal(a, sampler(n, points=points, rng=12345))
    assert np.array_equal(a, sampler(n, points=points, rng=np.random.SeedSequence(12345)))
    assert np.array_equal(a, sampler(n, points=points, rng=np.random.default_rng(12345)))
    assert not np.array_equal(a, sampler(n, points=points, rng=12346))


def test_rng_none_gives_fresh_samples():
    assert not np.array_equal(sample_sphere(48), sample_sphere(48))


def test_stratified_one_point_per_cell():
    side = 16
    d = sample_sphere(48 * side * side, points="stratified", rng=7)
    uv = triangle_to_square(fold(d[::48])[1])
    cells = np.floor(uv * side).astype(int)
    assert len({(i, j) for i, j in cells}) == side * side


def test_stratified_needs_square_base_count():
    with pytest.raises(ValueError, match=r"square number of base points; n=480 gives 10 .*use n=432 or n=768"):
        sample_sphere(480, points="stratified")
    with pytest.raises(ValueError, match=r"n=72 gives 3 \(n/24\); use n=24 or n=96"):
        sample_hemisphere(72, points="stratified")
    # Any size: the message quotes the n the user passed, not the whole orbits' n it was rounded up to
    # (sample_sphere(50) used to say "n=96 gives 2 (n/48)").
    with pytest.raises(ValueError, match=r"; n=50 gives 2 \(ceil\(n/48\)\); use n=48 or n=192$"):
        sample_sphere(50, points="stratified")
    with pytest.raises(ValueError, match=r"; n=50 gives 3 \(ceil\(n/24\)\); use n=24 or n=96$"):
        sample_hemisphere(50, points="stratified")


def test_sobol_size_error_quotes_the_users_n():
    # 2**30 Sobol' points at most: n = 48 * 2**30 + 1 needs one more (ceil(n/48)); the message says so with n as given.
    n = 48 * 2**30 + 1
    with pytest.raises(ValueError, match=rf"^'n'={n} needs {2**30 + 1} Sobol' points \(ceil\(n/48\)\) but"):
        sample_sphere(n, points="sobol")
    with pytest.raises(ValueError, match=rf"^'n'={48 * 2**31} needs {2**31} Sobol' points \(n/48\) but"):
        sample_sphere(48 * 2**31, points="sobol")


def test_sobol_warns_unless_power_of_two():
    with pytest.warns(UserWarning, match="power of 2"):
        sample_sphere(48 * 6, points="sobol", rng=0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sample_sphere(48 * 8, points="sobol", rng=0)


def test_sobol_base_points_are_a_scrambled_sobol_net():
    # 2^k scrambled Sobol' points form a (0, k, 2)-net in base 2: every dyadic box of
    # area 2^-k, of any shape, holds exactly one point.  Unscrambled, the first point is 0.
    k = 10
    d = sample_sphere(48 * 2**k, points="sobol", rng=5)
    uv = triangle_to_square(fold(d[::48])[1])
    for a in range(k + 1):
        cells = np.floor(uv[:, 0] * 2**a).astype(int) * 2 ** (k - a) + np.floor(uv[:, 1] * 2 ** (k - a)).astype(int)
        assert np.array_equal(np.sort(cells), np.arange(2**k)), a
    assert np.all(uv[0] > 0)
    assert not np.array_equal(d, sample_sphere(48 * 2**k, points="sobol", rng=6))


def test_any_qmc_engine():
    engine = qmc.Halton(d=2, scramble=False)
    d = sample_hemisphere(24 * 5, points=engine)
    uv = triangle_to_square(fold(d[::24], "hemisphere")[1])
    np.testing.assert_allclose(uv, qmc.Halton(d=2, scramble=False).random(5), atol=1e-12)
    with pytest.raises(ValueError, match="'points' engine must have d=2"):
        sample_sphere(48, points=qmc.Sobol(d=3))


@pytest.mark.parametrize("sampler, count, domain", SAMPLERS)
def test_float32_and_out(sampler, count, domain):
    n = count * 100
    d64 = sampler(n, rng=9)
    d32 = sampler(n, rng=9, dtype=np.float32)
    assert d32.dtype == np.float32 and np.all(np.isfinite(d32))
    np.testing.assert_allclose(d32, d64, atol=1e-7)
    out = np.empty((n, 3), np.float32)
    result = sampler(n, rng=9, dtype=np.float32, out=out)
    assert result is out and np.array_equal(out, d32)
    out64 = np.full((n, 3), np.nan)
    assert sampler(n, rng=9, out=out64) is out64 and np.array_equal(out64, d64)


def test_normal_none_is_z_axis_and_frame_is_orthonormal():
    assert np.array_equal(sample_hemisphere(240, rng=1), sample_hemisphere(240, rng=1, normal=[0, 0, 1]))
    rng = np.random.default_rng(0)
    for n in list(rng.normal(size=(50, 3))) + [np.array([0, 0, -1.0]), np.array([1.0, 0, 0])]:
        n = n / np.linalg.norm(n)
        basis = frame(n)
        np.testing.assert_allclose(basis @ basis.T, np.eye(3), atol=1e-14)
        np.testing.assert_allclose(basis[2], n, atol=0)
        assert np.linalg.det(basis) == pytest.approx(1.0)


@pytest.mark.parametrize("method", METHODS)
def test_hemisphere_about_normal(method):
    normal = np.array([0.3, -0.5, -0.8])
    unit = normal / np.linalg.norm(normal)
    d = sample_hemisphere(24 * 200, normal=normal, method=method, rng=4)
    assert np.all(d @ unit >= -1e-15)
    # the same points as about z, rotated: the local coordinates are the un-rotated sample
    local = d @ frame(unit).T
    np.testing.assert_allclose(local, sample_hemisphere(24 * 200, method=method, rng=4), atol=1e-15)
    np.testing.assert_allclose(hemisphere_pdf(d, method, normal=normal), hemisphere_pdf(local, method), rtol=1e-12)
    assert np.all(hemisphere_pdf(-d[d @ unit > 1e-9], method, normal=normal) == 0)


@pytest.mark.parametrize("method", METHODS)
def test_scheme_pdf_is_triangle_pdf_over_count(method):
    d = sample_sphere(48 * 100, method=method, rng=8)
    _, base = fold(d)
    np.testing.assert_array_equal(sphere_pdf(d, method), square_to_triangle_pdf(base, method) / 48)
    h = sample_hemisphere(24 * 100, method=method, rng=8)
    np.testing.assert_array_equal(
        hemisphere_pdf(h, method), square_to_triangle_pdf(fold(h, "hemisphere")[1], method) / 24
    )
    if method == "equal_area":
        np.testing.assert_allclose(sphere_pdf(d, method), 1 / (4 * np.pi), rtol=1e-15)
        np.testing.assert_allclose(hemisphere_pdf(h, method), 1 / (2 * np.pi), rtol=1e-15)
    else:  # diverges on the axes, the images of the vertex (0, 0, 1)
        assert np.all(np.isinf(sphere_pdf(np.eye(3), method)))


@pytest.mark.parametrize("sampler", [sample_sphere, sample_hemisphere])
@pytest.mark.parametrize(
    "kwargs, error, match",
    [
        ({"n": 0}, ValueError, r"'n' must be positive"),
        ({"n": -48}, ValueError, r"'n' must be positive"),
        ({"n": 48.0}, TypeError, r"'n' must be an integer"),
        ({"n": True}, TypeError, r"'n' must be an integer"),
        ({"n": "48"}, TypeError, r"'n' must be an integer"),
        (
            {"method": "uniform"},
            ValueError,
            r"'uniform' is not a valid method; use one of \{'equal_area', 'paper1', 'paper2'\}",
        ),
        ({"points": "lattice"}, ValueError, r"'lattice' is not a valid points; use one of"),
        ({"points": 3}, TypeError, r"'points' must be one of"),
        ({"rng": 1.5}, TypeError, r"'rng' must be None, an int, a numpy SeedSequence or a numpy Generator"),
        ({"rng": -1}, ValueError, r"'rng' must be a non-negative integer seed"),
        ({"dtype": np.float16}, TypeError, r"'dtype' must be float32 or float64, got float16"),
        ({"dtype": int}, TypeError, r"'dtype' must be float32 or float64"),
        ({"dtype": "banana"}, TypeError, r"'dtype' must be float32 or float64"),
        ({"out": np.empty((10, 3))}, ValueError, r"'out' must have shape"),
        ({"out": np.empty((96, 3), np.float32)}, TypeError, r"'out' has dtype float32 but dtype=float64"),
        ({"out": np.empty((3, 96)).T}, ValueError, r"'out' must be C-contiguous"),
        ({"out": [[0.0] * 3] * 96}, TypeError, r"'out' must be a numpy array"),
    ],
)
def test_bad_input(sampler, kwargs, error, match):
    kwargs = {"n": 96, **kwargs}  # 96 is valid for both samplers
    with pytest.raises(error, match=match):
        sampler(**kwargs)


def test_n_not_multiple_names_nearest_sizes():
    # The streaming samplers work in whole orbits (sample_sphere and sample_hemisphere take any n).
    with pytest.raises(
        ValueError, match=r"'n_total'=100 is not a multiple of 48; the nearest valid sizes are 96 or 144"
    ):
        iter_sphere(100)
    with pytest.raises(ValueError, match=r"'n_total'=10 is not a multiple of 24; the nearest valid sizes are 24"):
        iter_hemisphere(10)


@pytest.mark.parametrize("normal", [[0, 0, 0], [np.nan, 0, 1], [0, 1], [[0, 0, 1]], "up"])
def test_bad_normal(normal):
    with pytest.raises((ValueError, TypeError), match="'normal'"):
        sample_hemisphere(24, normal=normal)
    with pytest.raises((ValueError, TypeError), match="'normal'"):
        hemisphere_pdf([0, 0, 1.0], normal=normal)


def test_pdf_bad_input():
    with pytest.raises(ValueError, match="'d' must have shape"):
        sphere_pdf([1.0, 0.0])
    with pytest.raises(ValueError, match="'d' must be finite"):
        hemisphere_pdf([np.nan, 0.0, 1.0])
    with pytest.raises(ValueError, match="not a valid method"):
        sphere_pdf([0, 0, 1.0], method="paper3")


def test_an_array_larger_than_memory_is_a_value_error_naming_n(monkeypatch):
    import symsphere.sampling

    monkeypatch.setattr(symsphere.sampling, "machine_memory", lambda: 2**30)  # a 1 GiB machine
    with pytest.raises(ValueError, match=r"^'n'=50331648 directions need 1.12 GiB as float64 .* iter_sphere"):
        sample_sphere(48 * 2**20)  # 1.2e9 bytes: numpy raised MemoryError, naming neither n nor a remedy
    with pytest.raises(ValueError, match=r"^'n'=103079215104 directions need"):
        sample_sphere(48 * 2**31)
    assert sample_sphere(48 * 2**10, rng=1).shape == (48 * 2**10, 3)  # what fits is sampled as before


# --- hostile and extreme input: rows on the hemisphere, Sobol' lengths, absurd sizes, the documented exception types, extreme normals, non-unit vectors ---


def _fails_fast(call, error, match, seconds=5.0):
    start = time.monotonic()
    with pytest.raises(error, match=match):
        call()
    assert time.monotonic() - start < scaled_for_load(seconds)  # instead of allocating or computing for minutes


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_rotated_hemisphere_rows_have_positive_pdf(dtype):
    from scipy.stats import qmc

    normal = [0.3, -0.5, 0.8]
    d = symsphere.sample_hemisphere(96, normal=normal, points=qmc.Sobol(2, scramble=False), dtype=dtype)
    assert np.all(symsphere.hemisphere_pdf(d, normal=normal) > 0)
    rng = np.random.default_rng(12)
    for seed in range(40):  # the random float32 scan found 357 such rows
        normal = rng.normal(size=3)
        d = symsphere.sample_hemisphere(24 * 512, normal=normal, rng=seed, dtype=dtype)
        assert np.all(symsphere.hemisphere_pdf(d, normal=normal) > 0)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_rotated_hemisphere_rows_are_not_below_the_plane(dtype):
    from scipy.stats import qmc

    cases = [
        (
            [0.3, -0.5, 0.8],
            symsphere.sample_hemisphere(96, normal=[0.3, -0.5, 0.8], points=qmc.Sobol(2, scramble=False), dtype=dtype),
        )
    ]
    rng = np.random.default_rng(22)
    for seed in range(40):
        normal = rng.normal(size=3)
        cases.append((normal, symsphere.sample_hemisphere(24 * 512, normal=normal, rng=seed, dtype=dtype)))
    for normal, d in cases:
        normal = np.asarray(normal)
        assert np.all(d.astype(np.float64) @ normal >= 0)  # the check, in float64
        assert np.all(d @ normal.astype(dtype) >= 0)  # and in the rows' own dtype
        unit = normal / np.linalg.norm(normal)
        assert np.all(d.astype(np.float64) @ unit >= 0) and np.all(d @ unit.astype(dtype) >= 0)
    block = next(iter(symsphere.iter_hemisphere(24 * 64, chunk=24 * 32, normal=[0.3, -0.5, 0.8],
                                                points=qmc.Sobol(2, scramble=False), dtype=dtype)))  # fmt: skip
    assert np.all(block.astype(np.float64) @ np.array([0.3, -0.5, 0.8]) >= 0)


def test_sobol_beyond_its_length_is_rejected_at_the_call():
    with pytest.raises(ValueError, match=r"'n'=103079215104 needs 2147483648 Sobol' points"):
        symsphere.iter_sphere(48 * 2**31, points="sobol")
    with pytest.raises(ValueError, match="Sobol'"):
        symsphere.integrate(lambda d: d[:, 2], n=48 * 8 * 2**31, points="sobol")
    from scipy.stats import qmc

    engine = qmc.Sobol(2, scramble=False)
    engine.fast_forward(2**30 - 4)
    with pytest.raises(ValueError, match="after the engine's 1073741820"):
        symsphere.sample_sphere(48 * 8, points=engine)


def test_absurd_sizes_fail_fast_naming_the_argument():
    from symsphere.render import render

    _fails_fast(lambda: symsphere.sample_sphere(48 * 2**64), ValueError, r"'n'=.* is too large")
    _fails_fast(lambda: symsphere.integrate(lambda d: d[:, 0], n=48 * 2**64), ValueError, "'n'")
    _fails_fast(lambda: symsphere.iter_sphere(48 * 2**64), ValueError, "'n_total'")
    _fails_fast(lambda: render("cornell", spp=10**15), ValueError, r"'spp'=1000000000000000 is too large")
    _fails_fast(lambda: harmonics.sh_polynomial(10**5, 0), ValueError, "'l'")
    _fails_fast(lambda: harmonics.monomial_integral(10**7, 0, 0), ValueError, r"'a \+ b \+ c'")
    _fails_fast(lambda: harmonics.real_sh_basis(10**6, [0, 0, 1]), ValueError, "'lmax'")


def test_exception_types():
    deep = np.zeros((1,) * 33 + (3,))
    for call in (
        lambda: symmetry.fold(deep),
        lambda: symsphere.sphere_pdf(deep),
        lambda: symsphere.hemisphere_pdf(deep),
    ):
        with pytest.raises(ValueError, match="'d' has 34 dimensions"):
            call()
    with pytest.raises(ValueError, match="'l'"):
        harmonics.real_sh(10**5, 0, [0.0, 0.0, 1.0])
    from symsphere.render import Camera, Scene, SceneError, Sphere, diffuse, write_outputs

    with pytest.raises(TypeError, match="'result'"):
        write_outputs(None, "x.png")
    with pytest.raises(SceneError, match="max_depth must be at most"):
        Scene("s", Camera((0, 0, 5), (0, 0, -1), 40), {"m": diffuse(0.5, 1.0)}, (Sphere((0, 0, 0), 1, "m"),),
              max_depth=10**30)  # fmt: skip


@pytest.mark.parametrize("scale", [1e200, 1e-170, 1e-320])
def test_extreme_normals_are_accepted_without_warning(scale):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        d = symsphere.sample_hemisphere(48, normal=[scale, 0.0, 0.0], rng=4)
        density = symsphere.hemisphere_pdf(d, normal=[scale, 0.0, 0.0])
    np.testing.assert_array_equal(d, symsphere.sample_hemisphere(48, normal=[1.0, 0.0, 0.0], rng=4))
    assert np.all(density > 0)


def test_zero_and_non_unit_vectors_are_rejected():

    for call in (
        lambda: warps.square_to_cosine_hemisphere_pdf([0.0, 0.0, 0.0]),
        lambda: warps.spherical_triangle_to_square([0.0, 0.0, 0.0], *warps.T0_VERTICES),
        lambda: symsphere.triangle_to_square([0.0, 0.0, 0.0], "paper1"),
        lambda: symsphere.sphere_pdf([0.0, 0.0, 2.0], "paper1"),
        lambda: symsphere.hemisphere_pdf([0.0, 0.0, 0.5]),
    ):
        with pytest.raises(ValueError, match="unit vectors"):
            call()


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
    assert np.array_equal(out, fresh) and fresh.base.nbytes - fresh.nbytes == 64  # n rows and a line, no more
    assert np.all(np.isfinite(out))
    with pytest.raises(ValueError, match="'out' must have shape"):
        sample_sphere(101, out=np.empty((96, 3), dtype=dtype), dtype=dtype)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_a_fresh_output_starts_a_line_and_a_large_one_a_huge_page(dtype):
    # The kernels store in 64-byte vectors, and numpy asks for 2 MiB pages from 4 MiB on, where numpy's
    # own arrays start 16 bytes into a line: a fresh output (and a block of iter_*) starts on both, a
    # view of an allocation of its own, one alignment larger.
    large = 2**22 // (3 * np.dtype(dtype).itemsize) + 1
    for n, align in ((101, 64), (large, 2**21)):
        fresh = sample_hemisphere(n, rng=5, normal=(1.0, 1.0, 1.0), dtype=dtype)
        assert fresh.shape == (n, 3) and fresh.flags.c_contiguous and fresh.flags.writeable
        assert fresh.ctypes.data % align == 0
        assert fresh.base.flags.owndata and fresh.base.nbytes - fresh.nbytes == align
    blocks = list(iter_hemisphere(24 * 40, chunk=24 * 16, dtype=dtype, rng=5))
    assert all(b.ctypes.data % 64 == 0 and b.base.nbytes - b.nbytes == 64 for b in blocks)


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
        random_points = kernels.RandomPoints(source.seed_words, 3, m)
        whole = kernels.fill_orbits(random_points, "equal_area", count, basis, np.empty((m * count, 3), dtype))
        expected = np.concatenate([whole[: (m - 1) * count], whole[members]])
        for parts in (1, 2, 3, 7):
            got = np.full(((m - 1) * count + rest, 3), np.nan, dtype)
            kernels.fill_orbits(random_points, "equal_area", count, basis, got, parts=parts, offset=offset)
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


DOMAINS = ["sphere", "hemisphere"]
STREAMS = ["random", "sobol", "halton", "sobol_interlaced2", "sobol_interlaced3"]


def _one_call(domain, n, **kwargs):
    sampler = sample_sphere if domain == "sphere" else sample_hemisphere
    return sampler(n, **kwargs)


@pytest.mark.parametrize("domain", DOMAINS)
@pytest.mark.parametrize("points", STREAMS)
def test_the_stream_continues_across_calls(domain, points):
    count = orbit_size(domain)
    a, b = 4 * count, 3 * count + 5  # a a multiple of the orbit size, b any
    scheme = Scheme(domain, points=points, rng=11)
    split = np.concatenate([scheme.random(a), scheme.random(b)])
    assert np.array_equal(split, Scheme(domain, points=points, rng=11).random(a + b))
    assert np.array_equal(split, _one_call(domain, a + b, points=points, rng=11))


@pytest.mark.parametrize("domain", DOMAINS)
def test_a_cut_orbit_uses_up_its_base_point(domain):
    count = orbit_size(domain)
    scheme = Scheme(domain, rng=4)
    first = scheme.random(count + 1)  # one whole orbit and one member of the second
    after = scheme.random(count)
    whole = Scheme(domain, rng=4).random(3 * count)
    assert np.array_equal(first[:count], whole[:count])
    assert np.array_equal(after, whole[2 * count :])


@pytest.mark.parametrize("domain", DOMAINS)
@pytest.mark.parametrize("points", ["random", "sobol", "stratified"])
def test_reset_starts_the_stream_again(domain, points):
    count = orbit_size(domain)
    scheme = Scheme(domain, points=points, rng=2)
    first = scheme.random(16 * count)
    assert np.array_equal(scheme.reset().random(16 * count), first)
    assert np.array_equal(first, _one_call(domain, 16 * count, points=points, rng=2))


def test_stratified_points_are_one_grid_per_call():
    scheme = Scheme(points="stratified", rng=0)
    scheme.random(48 * 4)
    with pytest.raises(ValueError, match="reset"):
        scheme.random(48 * 4)
    with pytest.raises(ValueError, match="stratified"):
        scheme.fast_forward(48)


@pytest.mark.parametrize("domain", DOMAINS)
@pytest.mark.parametrize("points", ["random", "halton"])
def test_fast_forward_skips_whole_orbits(domain, points):
    count = orbit_size(domain)
    scheme = Scheme(domain, points=points, rng=9).fast_forward(5 * count)
    assert np.array_equal(
        scheme.random(2 * count + 3), Scheme(domain, points=points, rng=9).random(7 * count + 3)[5 * count :]
    )
    assert np.array_equal(Scheme(domain, rng=9).fast_forward(0).random(count), Scheme(domain, rng=9).random(count))


@pytest.mark.parametrize("domain", DOMAINS)
def test_blocks_are_the_stream_in_pieces(domain):
    count = orbit_size(domain)
    scheme = Scheme(domain, rng=6)
    scheme.random(count)
    pieces = list(scheme.blocks(10 * count, chunk=3 * count))
    assert [len(p) for p in pieces] == [3 * count] * 3 + [count]
    following = scheme.random(count)  # the blocks moved the stream past their rows at the call
    whole = Scheme(domain, rng=6).random(12 * count)
    assert np.array_equal(np.concatenate(pieces), whole[count : 11 * count])
    assert np.array_equal(following, whole[11 * count :])


def test_blocks_fill_out_and_match_iter_sphere():
    out = np.empty((48 * 20, 3), np.float32)
    pieces = list(Scheme(dtype=np.float32, rng=1).blocks(48 * 20, 48 * 8, out=out))
    assert all(np.shares_memory(p, out) for p in pieces)
    assert np.array_equal(out, np.concatenate(list(iter_sphere(48 * 20, chunk=48 * 8, dtype=np.float32, rng=1))))


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_out_and_dtype_as_generator_random(dtype):
    scheme = Scheme("hemisphere", normal=[1.0, 2.0, -2.0], dtype=dtype, rng=5)
    out = np.empty((100, 3), dtype)
    assert scheme.random(100, out=out) is out
    assert np.array_equal(out, sample_hemisphere(100, normal=[1.0, 2.0, -2.0], dtype=dtype, rng=5))
    assert scheme.random(7).dtype == dtype
    other = np.float64 if dtype == np.float32 else np.float32
    with pytest.raises(TypeError, match="'out'"):
        scheme.random(10, out=np.empty((10, 3), other))
    with pytest.raises(ValueError, match="'out'"):
        scheme.random(10, out=np.empty((11, 3), dtype))
    with pytest.raises(ValueError, match="'out'"):
        scheme.random(10, out=np.empty((3, 10), dtype).T)


def test_a_generator_advances_as_one_sampling_call_advances_it():
    for points in ("random", "sobol"):
        g1, g2 = np.random.default_rng(3), np.random.default_rng(3)
        scheme = Scheme(points=points, rng=g1)
        first = sample_sphere(96, points=points, rng=g2)
        assert g1.random() == g2.random()  # the same draw, at construction
        assert np.array_equal(scheme.random(96), first)


ENGINES = [
    lambda: qmc.Sobol(d=2, rng=np.random.default_rng(1)),
    lambda: qmc.Halton(d=2, rng=np.random.default_rng(1)),
    lambda: qmc.LatinHypercube(d=2, rng=np.random.default_rng(1)),
    lambda: qmc.PoissonDisk(d=2, radius=0.05, rng=np.random.default_rng(1)),
]


@pytest.mark.parametrize("make", ENGINES, ids=["Sobol", "Halton", "LatinHypercube", "PoissonDisk"])
def test_every_qmc_engine_as_points(make):
    got = Scheme(points=make(), rng=0).random(48 * 8)
    assert np.array_equal(got, sample_sphere(48 * 8, points=make(), rng=0))
    np.testing.assert_allclose(np.linalg.norm(got, axis=1), 1.0, atol=1e-15)


@pytest.mark.filterwarnings("ignore:The balance properties of Sobol")
@pytest.mark.parametrize("make", ENGINES[:2], ids=["Sobol", "Halton"])
def test_a_sequence_engine_continues_from_where_the_user_left_it(make):
    engine = make()
    engine.random(5)  # the engine's own position is the stream's start
    scheme = Scheme(points=engine, rng=0)
    split = np.concatenate([scheme.random(48 * 4), scheme.random(48 * 3)])
    reference = make()
    reference.random(5)
    assert np.array_equal(split, sample_sphere(48 * 7, points=reference, rng=0))


@pytest.mark.parametrize("method", ["equal_area", "paper1", "paper2"])
def test_pdf_is_the_functions_pdf(method):
    d = sample_sphere(480, rng=8)
    assert np.array_equal(Scheme(method=method).pdf(d), sphere_pdf(d, method))
    normal = [0.3, -1.0, 0.2]
    e = sample_hemisphere(480, normal=normal, dtype=np.float32, rng=8)
    got = Scheme("hemisphere", method=method, normal=normal).pdf(e)
    assert got.dtype == np.float32
    assert np.array_equal(got, hemisphere_pdf(e, method, normal))


@pytest.mark.parametrize(
    "kwargs, error, named",
    [
        ({"domain": "torus"}, ValueError, "domain"),
        ({"method": "polar"}, ValueError, "polar"),
        ({"points": "grid"}, ValueError, "grid"),
        ({"normal": [0, 0, 1]}, ValueError, "'normal'"),
        ({"domain": "hemisphere", "normal": [0, 0, 0]}, ValueError, "'normal'"),
        ({"dtype": np.int32}, TypeError, "'dtype'"),
        ({"rng": "seed"}, TypeError, "'rng'"),
        ({"rng": -1}, ValueError, "'rng'"),
    ],
)
def test_bad_arguments_are_named_at_construction(kwargs, error, named):
    with pytest.raises(error, match=named):
        Scheme(**kwargs)


def test_bad_counts_are_named():
    scheme = Scheme("hemisphere", rng=0)
    with pytest.raises(ValueError, match="'n'"):
        scheme.random(0)
    with pytest.raises(TypeError, match="'n'"):
        scheme.random(2.5)
    with pytest.raises(ValueError, match="'n'"):
        scheme.fast_forward(25)
    with pytest.raises(ValueError, match="'n_total'"):
        scheme.blocks(25)
    with pytest.raises(ValueError, match="'chunk'"):
        scheme.blocks(48, chunk=25)
    assert np.array_equal(scheme.random(24), Scheme("hemisphere", rng=0).random(24))  # errors moved nothing


def test_the_domain_message_lists_the_choices_sorted():
    with pytest.raises(ValueError, match=r"use one of \{'hemisphere', 'sphere'\}"):
        Scheme("torus")


def test_repr_names_the_configuration_and_position():
    scheme = Scheme("hemisphere", normal=[0, 0, 2], dtype=np.float32, rng=0)
    scheme.random(48)
    assert repr(scheme) == (
        "Scheme('hemisphere', method='equal_area', points='random', normal=[0.0, 0.0, 1.0], dtype=float32, position=2)"
    )
