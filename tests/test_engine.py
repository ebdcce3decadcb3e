"""The sampling engine ``symsphere.Scheme``: its stream, reset, fast_forward, blocks, pdf, out=/dtype=, errors.

The functions of :mod:`symsphere.sampling` are one call on a fresh engine each; their outputs are
pinned bit for bit by tests/test_public_outputs.py, so here the engine is compared with them and
with itself (a stream split into calls against the same stream in one call).
"""

import numpy as np
import pytest
from scipy.stats import qmc

from symsphere import Scheme, hemisphere_pdf, iter_sphere, sample_hemisphere, sample_sphere, sphere_pdf
from symsphere.symmetry import orbit_size

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
