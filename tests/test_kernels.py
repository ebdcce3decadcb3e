"""The numba kernels against the numpy reference path; streaming; the specialised kernels."""

import mmap

import numpy as np
import pytest
from numba import njit
from references import ELEMENTARY_ULPS, EPS32, EPS64, GAMMA3, assert_within_eps

from symsphere import METHODS, iter_hemisphere, iter_sphere, sample_hemisphere, sample_sphere
from symsphere._testing import blocks, kernels
from symsphere.frames import frame
from symsphere.points import BLOCK, BasePoints
from symsphere.symmetry import SPHERE_MAPS

reference_orbits = blocks.reference_orbits

# One worker runs the file (Makefile: --dist loadgroup): its cases compile the sampling kernel's variants
# (method, count, frame, dtype, point set), most of them shared by several cases; split over two workers,
# both compiled some of them.
pytestmark = pytest.mark.xdist_group("sampling_kernels")

# How far the kernels' map may be from the numpy path's, relative to each component, in EPS64
# (the error model of tests/references.py; E = ELEMENTARY_ULPS per elementary function, 1/2 per
# rounding, first order).  The kernel calls libm, numpy its SIMD loops:
# - equal_area: no elementary function (its sine is a polynomial), only +, -, *, /, sqrt in the
#   same order on both paths: the same bits;
# - paper1: phi = u pi/4 (same bits), cos(phi) E, w = v / cos(phi) E + 1/2, theta = atan(w) (condition
#   number <= 1) 2E + 1/2, sin(theta) (condition <= 1) 3E + 1/2, cos(theta) (condition theta tan(theta)
#   <= 1.35 for theta <= atan(sqrt 2)) 3.7E + 0.7; x = cos(phi) sin(theta) and the others 4E + 1 per
#   path, so the paths differ by 8E + 2;
# - paper2: sin(theta), cos(theta), cos(phi) E each; the norm sqrt(s^2 + c^2 cp^2) 2E + 3/2; each
#   component (a product over the norm) 4E + 5/2 per path: 8E + 5.
# The clamps into T0 are 1-Lipschitz; the orbit stores (signed permutations) are exact.
_E = ELEMENTARY_ULPS
MAP_EPS = {"equal_area": 0, "paper1": 8 * _E + 2, "paper2": 8 * _E + 5}


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("count, normal", [(48, None), (24, None), (24, (0.3, -0.5, -0.8))])
def test_kernel_matches_numpy_reference(method, count, normal):
    uv = np.random.default_rng(0).random((5000, 2))
    uv[:4] = [[0, 0], [0, 1], [1, 0], [1, 1]]
    basis = None if normal is None else frame(np.array(normal) / np.linalg.norm(normal))
    reference = reference_orbits(uv, method, count, basis)
    for dtype in (np.float64, np.float32):
        out = np.empty((len(uv) * count, 3), dtype)
        kernels.fill_orbits(uv, method, count, basis, out)
        # Unit vectors, so absolute bounds in EPS64: the map's MAP_EPS; a frame rotates that
        # difference (|R d| = |d|) and adds a 3-term dot product per path, numpy's `local @ basis`
        # (BLAS, perhaps with FMA) and the kernel's sum: 2 GAMMA3.  float32: the kernel maps in
        # float64 and rounds once, like reference.astype(float32): the float64 bound, plus one
        # float32 rounding that may go the other way (ulp <= EPS32 / 2 below 1) where they differ.
        k64 = MAP_EPS[method] + (0 if basis is None else 2 * GAMMA3)
        if dtype == np.float64:
            assert_within_eps(out, reference, k64, scale=1)
        else:
            k32 = 0.0 if k64 == 0 else k64 * EPS64 / EPS32 + 1 / 2
            assert_within_eps(out, reference.astype(dtype), k32, scale=1, eps=EPS32)
        assert np.all(np.isfinite(out))


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("count, normal", [(48, None), (24, None), (24, (0.3, -0.5, -0.8))])
@pytest.mark.parametrize("m, parts", [(1, 1), (15, 7), (17, 2), (1000, 3), (4099, 2), (4099, 7)])
def test_random_kernel_draws_the_same_points_as_take(method, count, normal, m, parts):
    # The fused kernel draws u, v itself, part by part; it must equal the points of take()
    # put through the uv kernel, bit for bit, whatever the number of parts.
    basis = None if normal is None else frame(np.array(normal) / np.linalg.norm(normal))
    source = BasePoints("random", 21, total=m + 5)
    for dtype in (np.float64, np.float32):
        expected = kernels.fill_orbits(source.take(5, m + 5), method, count, basis, np.empty((m * count, 3), dtype))
        got = np.full((m * count, 3), np.nan, dtype)
        kernels.fill_orbits(kernels.RandomPoints(source.seed_words, 5, m), method, count, basis, got, parts=parts)
        assert np.array_equal(got, expected)


def test_random_kernel_far_into_the_stream():
    first = 1_000_003
    source = BasePoints("random", 22, total=first + 333)
    expected = kernels.fill_orbits(source.take(first, first + 333), "equal_area", 48, None, np.empty((333 * 48, 3)))
    random_points = kernels.RandomPoints(source.seed_words, first, 333)
    got = kernels.fill_orbits(random_points, "equal_area", 48, None, np.empty((333 * 48, 3)))
    assert np.array_equal(got, expected)


def test_parts_cover_the_points_in_order():
    for m in [1, 15, 16, 17, 100, 4099]:
        for parts in [1, 2, 3, 7, 1000]:
            bounds = kernels.part_bounds(m, parts)
            assert bounds[0] == 0 and bounds[-1] == m and np.all(np.diff(bounds) > 0)
            assert np.all(bounds[1:-1] % 16 == 0) and len(bounds) - 1 == min(parts, -(-m // 16))


def test_kernel_exact_signs_and_permutations():
    # Without a frame the orbit stores are exact copies: compare against the tables.
    uv = np.random.default_rng(1).random((100, 2))
    out = kernels.fill_orbits(uv, "equal_area", 48, None, np.empty((4800, 3)))
    base = out[::48]
    assert np.array_equal(out.reshape(100, 48, 3), np.einsum("mi,kij->mkj", base, SPHERE_MAPS))


def test_scalar_helpers_match_numpy():
    @njit
    def evaluate(uv, code, k):
        out = np.empty((len(uv), 7))
        for i in range(len(uv)):
            x, y, z = kernels.triangle_point(uv[i, 0], uv[i, 1], code)
            a, b, c = kernels.orbit_member(x, y, z, k)
            out[i, 0], out[i, 1], out[i, 2] = x, y, z
            out[i, 3], out[i, 4], out[i, 5] = a, b, c
            out[i, 6] = kernels.triangle_density(x, y, z, code)
        return out

    from symsphere import square_to_triangle, square_to_triangle_pdf

    uv = np.random.default_rng(2).random((200, 2))
    for method, code in kernels.METHOD_CODES.items():
        for k in (0, 13, 47):
            got = evaluate(uv, code, k)
            p = square_to_triangle(uv, method)
            # the map: MAP_EPS relative to each component (see above)
            assert_within_eps(got[:, :3], p, MAP_EPS[method])
            np.testing.assert_allclose(got[:, 3:6], got[:, :3] @ SPHERE_MAPS[k], atol=0, rtol=0)
            # the density, from each path's own point: equal_area's is the constant 12/pi (same bits);
            # the paper maps' C x / (s (x^2 + y^2)), s = pi z^2 or pi^2 (x^2 + z^2), has condition
            # numbers summing to <= 5 in the components (MAP_EPS apart), and each path's evaluation
            # (hypot E, six roundings) adds E + 3: 5 MAP_EPS + 2E + 6.
            k_pdf = 0 if method == "equal_area" else 5 * MAP_EPS[method] + 2 * _E + 6
            assert_within_eps(got[:, 6], square_to_triangle_pdf(p, method), k_pdf)


@pytest.mark.parametrize("points", ["random", "stratified", "sobol", "halton"])
@pytest.mark.parametrize("chunk_orbits", [1, 7, BLOCK - 1, BLOCK + 3])
def test_iter_sphere_equals_one_shot(points, chunk_orbits):
    total = 96**2  # a square, for 'stratified'
    if points == "sobol":
        total = 2**13
    whole = sample_sphere(48 * total, points=points, rng=11)
    blocks = list(iter_sphere(48 * total, chunk=48 * chunk_orbits, points=points, rng=11))
    assert all(len(b) == 48 * chunk_orbits for b in blocks[:-1])
    assert np.array_equal(np.concatenate(blocks), whole)


def test_iter_hemisphere_equals_one_shot_with_normal_and_float32():
    args = dict(normal=[0.2, 0.9, -0.1], rng=3, dtype=np.float32, method="paper2")
    whole = sample_hemisphere(24 * 5000, **args)
    assert np.array_equal(np.concatenate(list(iter_hemisphere(24 * 5000, chunk=24 * 999, **args))), whole)


def test_iter_validates_eagerly():
    with pytest.raises(ValueError, match="'chunk'=50 is not a multiple of 48"):
        iter_sphere(480, chunk=50)
    with pytest.raises(ValueError, match="'n_total'=10 is not a multiple of 24"):
        iter_hemisphere(10)


def _dots_in_every_order(d, normal):
    """d . normal in d's dtype (normal rounded to it), summed in the three orders; and in float64."""
    n = np.asarray(normal, dtype=np.float64)
    a, b, c = (d[:, i] * n.astype(d.dtype)[i] for i in range(3))
    wide = d.astype(np.float64) @ n
    return [(a + b) + c, a + (b + c), (a + c) + b, wide]


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_store_keeps_rows_about_a_normal_on_or_above_the_plane(dtype):
    # Unscrambled Sobol' points include u = 0 and v = 0: base points on an edge of T0, whose images
    # lie on the equator, where rounding puts rows just below the plane.  With *above* the store moves
    # those rows, and only rows that close to the plane, by a few ulps; every row then has d . n >= 0
    # in its dtype, whichever order the sum is taken in, and in float64, for the normal as given or
    # scaled (the guarantee tests/test_sampling.py checks through the public functions).
    from scipy.stats import qmc

    uv = qmc.Sobol(2, scramble=False).random(512)
    eps = float(np.finfo(dtype).eps)
    found_below = False
    for normal in ([0.3, -0.5, 0.8], [1.0, 1.0, 1.0], [0.0, 0.0, 1.0], [-0.2, 0.9, 1e-9], [0.6, 0.0, -0.8]):
        basis = frame(np.array(normal) / np.linalg.norm(normal))
        unit = basis[2]
        raw = kernels.fill_orbits(uv, "equal_area", 24, basis, np.empty((512 * 24, 3), dtype))
        kept = kernels.fill_orbits(uv, "equal_area", 24, basis, np.empty((512 * 24, 3), dtype), above=True)
        found_below |= any(np.any(dot < 0) for dot in _dots_in_every_order(raw, unit))
        moved = ~np.all(raw == kept, axis=1)
        assert np.all(np.abs(raw[moved].astype(np.float64) @ unit) < 16 * eps)  # only rows at the plane
        assert np.max(np.abs(raw[moved].astype(np.float64) - kept[moved]), initial=0) <= 128 * eps
        assert np.allclose(np.linalg.norm(kept.astype(np.float64), axis=1), 1, atol=4 * eps, rtol=0)
        for scale in (1.0, 0.37, 3.1):
            assert all(np.all(dot >= 0) for dot in _dots_in_every_order(kept, scale * np.asarray(normal)))
            assert all(np.all(dot >= 0) for dot in _dots_in_every_order(kept, scale * unit))
        # The random kernel's store does the same.
        source = BasePoints("random", 4, total=300)
        expected = kernels.fill_orbits(source.take(0, 300), "equal_area", 24, basis, np.empty((7200, 3), dtype),
                                       above=True)  # fmt: skip
        got = kernels.fill_orbits(kernels.RandomPoints(source.seed_words, 0, 300), "equal_area", 24, basis,
                                  np.empty((7200, 3), dtype), parts=3, above=True)  # fmt: skip
        assert np.array_equal(got, expected)
    assert found_below  # the points put rows below the plane before the store's check: it was tested


_store_sphere, _store_hemisphere = kernels.store_sphere_orbit, kernels.store_hemisphere_orbit
_store_rotated = kernels.store_rotated_hemisphere


@njit
def _write_orbit(rows, i, x, y, z, weights):  # pragma: no cover - compiled by numba
    if weights.shape[1]:
        _store_rotated(x, y, z, rows, i, weights)
    elif rows.shape[1] == 3 * 48:
        _store_sphere(x, y, z, rows, i)
    else:
        _store_hemisphere(x, y, z, rows, i)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("count, normal", [(48, None), (24, None), (24, (0.3, -0.5, -0.8))])
def test_vector_stores_write_their_row_of_the_tables_and_nothing_else(dtype, count, normal):
    # The orbit stores (LLVM vectors) write row i, and only row i, of a C-contiguous array: exactly the
    # tables' images (p @ SPHERE_MAPS[k], rounded to the dtype: values that float32 does not hold, so the
    # rounding of -x must be -(rounding of x)), and about a normal (x w0 + y w1) + z w2 in float64 with
    # the weights of rotated_weights, by numpy's elementwise products and sums (no FMA), rounded once.
    p = np.array([0.1, 0.7, 0.3])
    if normal is None:
        weights = np.zeros((3, 0))
        expected = (p @ SPHERE_MAPS[:count]).reshape(-1)
    else:
        weights = kernels.rotated_weights(frame(np.array(normal) / np.linalg.norm(normal)), count)
        expected = (p[0] * weights[0] + p[1] * weights[1]) + p[2] * weights[2]
    rows = np.full((3, 3 * count), np.nan, dtype)
    _write_orbit(rows, 1, p[0], p[1], p[2], weights)
    assert np.array_equal(rows[1], expected.astype(dtype))
    assert np.isnan(rows[0]).all() and np.isnan(rows[2]).all()


_stream_rows, _store_fence = kernels.stream_rows, kernels.store_fence
_stage_on_lines = kernels._stage_on_lines


@njit
def _stage_placement(count, columns, dtype):  # pragma: no cover - compiled by numba
    stage = _stage_on_lines(count, columns, dtype)
    return stage.shape[0], stage.shape[1], stage.ctypes.data % 64


def test_weights_and_stage_start_cache_lines():
    # The rotated store loads the weights in 64-byte vectors, the orbit stores write the stage so:
    # each row of the weights starts a line, and so does the stage, whatever numba's allocator gives.
    weights = kernels.rotated_weights(frame(np.array([0.0, 0.6, 0.8])), 24)
    assert weights.shape == (3, 72) and weights.flags.c_contiguous
    assert [weights[r].ctypes.data % 64 for r in range(3)] == [0, 0, 0]
    for dtype in (np.float32, np.float64):
        for columns in (72, 144):
            for count in (32, 31, 0):
                assert _stage_placement(count, columns, dtype) == (count, columns, 0)


def test_rotated_weights_are_the_images_of_the_basis_and_kept_per_basis():
    # Block k of the weights is SPHERE_MAPS[k] @ basis (a signed permutation of the basis rows: exact,
    # signs of zeros included), for every basis asked for, also after more bases than are kept; a basis
    # asked for again gets the same values.
    rng = np.random.default_rng(7)
    normals = [rng.normal(size=3) for _ in range(20)] + [np.array([0.0, 0.0, 1.0]), np.array([0.0, -0.0, -1.0])]
    for normal in normals + normals[:3]:
        basis = frame(normal / np.linalg.norm(normal))
        for count in (24, 48):
            weights = kernels.rotated_weights(basis, count)
            for k in range(count):
                # row r of M_k @ basis without a sum (which would turn -0.0 into 0.0): its one nonzero
                expected = np.array(
                    [row[np.flatnonzero(row)[0]] * basis[np.flatnonzero(row)[0]] for row in SPHERE_MAPS[k]]
                )
                assert np.array_equal(weights[:, 3 * k : 3 * k + 3], expected)
                assert np.array_equal(np.signbit(weights[:, 3 * k : 3 * k + 3]), np.signbit(expected))


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("count, normal", [(48, None), (24, None), (24, (0.3, -0.5, -0.8))])
def test_streamed_kernels_write_the_same_rows(dtype, count, normal, monkeypatch):
    # The kernels that stage each batch of orbits and copy it out non-temporally write bit for bit the
    # rows of the plain stores: whole and cut orbits, several parts, outputs at several alignments.
    basis = None if normal is None else frame(np.array(normal) / np.linalg.norm(normal))
    uv = BasePoints("random", 9, total=301).take(0, 301)
    n = 300 * count + count // 3
    size = np.dtype(dtype).itemsize
    raw = np.empty(n * 3 * size + 64, np.uint8)
    results = {}
    for streamed in (False, True):
        monkeypatch.setattr(kernels, "stream_override", streamed)
        for shift in (0, 16, 3 * size):
            out = raw[shift : shift + n * 3 * size].view(dtype).reshape(n, 3)
            out[:] = np.nan
            kernels.fill_orbits(uv, "equal_area", count, basis, out, parts=3, offset=5, above=normal is not None)
            results[streamed, shift] = out.copy()
    for shift in (0, 16, 3 * size):
        assert np.array_equal(results[True, shift], results[False, shift])
        assert np.array_equal(results[False, shift], results[False, 0])


def test_outputs_are_streamed_only_when_large_and_already_in_memory(monkeypatch):
    # The rule: non-temporal stores for an output of at least STREAM_BYTES whose pages are mapped (a
    # buffer written before); plain ones for new memory (its pages are cleared by the kernel on the
    # first write), for a small output, and whatever the rule when overridden.  New memory from an
    # anonymous mapping: np.empty may be served from memory this process freed before (glibc raises
    # its mmap threshold after a free), whose pages are mapped, and streaming them is right.
    rows = kernels.STREAM_BYTES // 24 + 1
    fresh = np.frombuffer(mmap.mmap(-1, rows * 24), dtype=np.float64).reshape(rows, 3)
    assert not kernels._streams(fresh)
    fresh.fill(0.5)
    assert kernels._streams(fresh)
    assert not kernels._streams(np.ones((rows // 4, 3)))
    monkeypatch.setattr(kernels, "stream_override", False)
    assert not kernels._streams(fresh)
    monkeypatch.setattr(kernels, "stream_override", True)
    assert kernels._streams(np.empty((10, 3)))
