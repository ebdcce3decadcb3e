"""symsphere._compiled_peers: the compiled peer samplers (the study's timings use them) reproduce the library's peers.

The reference is the library's numpy implementation (symsphere.peers), itself tested against its
papers in tests/test_peers.py: same base points, same rotations, same directions to rounding.
"""

import numpy as np
import pytest
from references import ELEMENTARY_ULPS, GAMMA3, assert_within_eps

from symsphere._testing import compiled_peers
from symsphere.peers import PEERS

# How far a compiled peer (numba: libm's sin, cos) may be from the numpy peer (numpy's SIMD sin, cos),
# absolutely (unit vectors), in eps: the error model of tests/references.py, E = ELEMENTARY_ULPS.
# classic: phi = 2 pi v and r the same bits, x = r cos(phi), y = r sin(phi): E + 1/2 per path, so 2E + 1;
# octahedral: the angle (pi/2) p / r the same bits, one sine times sin(theta): 2E + 1;
# fibonacci_rotated: as classic, then the same rotation summed in another order (numpy's matmul,
# perhaps with FMA, the kernel's sum): |R d| = |d| plus a 3-term dot product per path, 2 GAMMA3;
# lebedev_rotated: the same nodes and rotations, only the two dot products: 2 GAMMA3.
_E = ELEMENTARY_ULPS
PEER_EPS = {
    "classic": 2 * _E + 1,
    "octahedral": 2 * _E + 1,
    "fibonacci_rotated": 2 * _E + 1 + 2 * GAMMA3,
    "lebedev_rotated": 2 * GAMMA3,
}


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
        got = compiled_peers.compiled_sample(peer, n, seed, points)
        assert got.shape == (n, 3) and got.dtype == np.float64
        assert_within_eps(got, expected, PEER_EPS[name], scale=1)


def test_compiled_sample_rejects_other_peers():
    assert "gaussian" not in compiled_peers.COMPILED_PEERS
    with pytest.raises(ValueError, match="'peer'"):
        compiled_peers.compiled_sample(PEERS["gaussian"], 10, 0)


def test_compiled_peers_are_uniform_on_the_sphere():
    # The study weights the compiled peers' directions by 4 pi (no pdf evaluated): that needs these facts.
    for name in compiled_peers.COMPILED_PEERS:
        assert PEERS[name].domain == "sphere" and PEERS[name].uniform, name


def test_study_estimate_of_a_compiled_peer_is_the_peers_estimate():
    from symsphere.apps.study.samplers import Sampler

    f = lambda d: np.exp(d @ np.array([0.3, -0.5, 0.6]))  # noqa: E731
    for name, points, n in (
        ("octahedral", "sobol_interlaced2", 1024),
        ("fibonacci_rotated", "random", 1000),
        ("lebedev_rotated", "random", 2 * 5810),
    ):
        sampler = Sampler.of_peer(PEERS[name], points)
        # The same f (numpy's exp) on directions PEER_EPS apart: |a| PEER_EPS <= 10 eps per term,
        # plus the two means' rounding (pairwise sums: about log2(n) / 2 eps each): < 45 eps = 1e-14.
        assert np.isclose(
            sampler.estimate(f, n, 3), PEERS[name].estimate(f, n, rng=3, points=points), rtol=1e-14, atol=0
        )
