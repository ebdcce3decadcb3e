"""The study's compiled peer samplers (symsphere.apps.study._compiled) reproduce the library's peers.

The reference is the library's numpy implementation (symsphere.peers), itself tested against its
papers in tests/test_peers.py: same base points, same rotations, same directions to rounding.
"""

import numpy as np
import pytest

from symsphere.apps.study._compiled import COMPILED_PEERS, compiled_sample
from symsphere.peers import PEERS


@pytest.mark.parametrize(
    "name, points, n",
    [
        ("classic", "random", 1000),
        ("classic", "sobol", 1024),
        ("octahedral", "random", 1000),
        ("octahedral", "sobol", 1024),
        ("octahedral", "sobol_interlaced2", 1024),
        ("octahedral", "sobol_interlaced3", 1024),
        ("fibonacci_rotated", "random", 999),
        ("lebedev_rotated", "random", 3 * 5810),
        ("lebedev_rotated", "random", 974),
    ],
)
def test_compiled_sample_is_the_peers_sample(name, points, n):
    peer = PEERS[name]
    for seed in (0, np.random.SeedSequence(5)):
        expected = peer.sample(n, rng=seed, points=points)
        got = compiled_sample(peer, n, seed, points)
        assert got.shape == (n, 3) and got.dtype == np.float64
        np.testing.assert_allclose(got, expected, rtol=0, atol=4e-16)


def test_octahedral_edges_and_corners():
    # The square's edges and corners, where the map folds: the same directions as the library's map.
    values = np.array([0.0, 1e-300, 0.25, 0.5, 0.75, 1 - 1e-16])
    uv = np.array([[a, b] for a in values for b in values])
    from symsphere.apps.study._compiled import _octahedral

    out = np.empty((len(uv), 3))
    _octahedral(uv, out)
    np.testing.assert_allclose(out, PEERS["octahedral"].forward(uv), rtol=0, atol=4e-16)


def test_compiled_sample_rejects_other_peers():
    assert "gaussian" not in COMPILED_PEERS
    with pytest.raises(ValueError, match="'peer'"):
        compiled_sample(PEERS["gaussian"], 10, 0)


def test_compiled_peers_are_uniform_on_the_sphere():
    # The study weights the compiled peers' directions by 4 pi (no pdf evaluated): that needs these facts.
    for name in COMPILED_PEERS:
        assert PEERS[name].domain == "sphere" and PEERS[name].uniform, name


def test_study_estimate_of_a_compiled_peer_is_the_peers_estimate():
    from symsphere.apps.study.samplers import Sampler

    f = lambda d: np.exp(d @ np.array([0.3, -0.5, 0.6]))  # noqa: E731
    for name, points, n in (("octahedral", "sobol_interlaced2", 1024), ("fibonacci_rotated", "random", 1000),
                            ("lebedev_rotated", "random", 2 * 5810)):
        sampler = Sampler.of_peer(PEERS[name], points)
        assert np.isclose(sampler.estimate(f, n, 3), PEERS[name].estimate(f, n, rng=3, points=points),
                          rtol=1e-14, atol=0)
