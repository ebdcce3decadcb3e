"""The scheme: layout of the orbits, point sets, determinism, dtypes, out=, normals, pdfs, bad input."""

import time
import warnings

import numpy as np
import pytest
from references import scaled_for_load
from scipy.stats import qmc

import symsphere
from symsphere import (
    METHODS,
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
from symsphere.frames import frame

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
