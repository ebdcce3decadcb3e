"""Compiled samplers of the peers, so that the study's timings compare methods, not implementations.

The scheme's directions come from symsphere's numba kernels (parallel over all threads); the library's
peers (:mod:`symsphere.peers`) are vectorised numpy, one thread.  Here the peers the study times get
numba kernels too, parallel in the same way: the same base points (the library's
:class:`~symsphere.points.BasePoints`, i.e. numpy's PCG64 or scipy's Sobol' engine), the same random
rotations (scipy's ``Rotation.random`` from the same generator), and each map's formula restated
for one point at a time.  :func:`compiled_sample` returns what ``peer.sample`` returns, to rounding
(tested in ``tests/apps/test_study_compiled.py``), for the peers of :data:`COMPILED_PEERS`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange
from scipy.spatial.transform import Rotation

from ..._threads import start_threads
from ..._validation import check_rng
from ...peers import Peer, lebedev_size, sample_lebedev
from ...points import BasePoints
from ...warps import uniform_sphere_point

__all__ = ["COMPILED_PEERS", "compiled_sample"]

COMPILED_PEERS = ("classic", "octahedral", "fibonacci_rotated", "lebedev_rotated")
"""The peers whose sampling :func:`compiled_sample` compiles."""

_OPTIONS = dict(cache=True, parallel=True, nogil=True, error_model="numpy")
# floor(2^64 (Phi - 1)), as symsphere.peers computes it (the integer square root of 5 * 2^128).
_GOLDEN_FRACTION_BITS = np.uint64((math.isqrt(5 << 128) - (1 << 64)) >> 1)


@njit(**_OPTIONS)
def _classic(uv, out):
    for i in prange(uv.shape[0]):
        x, y, z = uniform_sphere_point(uv[i, 0], uv[i, 1])
        out[i, 0], out[i, 1], out[i, 2] = x, y, z


@njit(**_OPTIONS)
def _octahedral(uv, out):
    # Clarberg (2008), as symsphere.warps._octahedral_sphere: the diamond |a| + |b| <= 1 is the upper
    # hemisphere; 1 - |z| = r^2 with the L1 radius r; the azimuth is linear along the octant's edge.
    half_pi = 0.5 * np.pi
    for i in prange(uv.shape[0]):
        a = 2.0 * uv[i, 0] - 1.0
        b = 2.0 * uv[i, 1] - 1.0
        aa, ab = abs(a), abs(b)
        upper = aa + ab <= 1.0
        p = aa if upper else 1.0 - ab
        q = ab if upper else 1.0 - aa
        r = p + q
        safe = r if r > 0 else 1.0
        sin_theta = r * math.sqrt(max(2.0 - r * r, 0.0))
        out[i, 0] = math.copysign(sin_theta * math.sin(half_pi * p / safe), a)
        out[i, 1] = math.copysign(sin_theta * math.sin(half_pi * q / safe), b)
        out[i, 2] = 1.0 - r * r if upper else r * r - 1.0


@njit(**_OPTIONS)
def _fibonacci_rotated(rotation, out):
    # Keinert et al. (2015), as symsphere.peers.fibonacci_points, then the rotation.
    n = out.shape[0]
    for i in prange(n):
        odd = 2.0 * i + 1.0
        z = 1.0 - odd / n
        sin_theta = math.sqrt(odd * (2.0 * n - odd)) / n
        bits = np.uint64(i) * _GOLDEN_FRACTION_BITS  # wraps mod 2^64, exactly
        phi = 2.0 * np.pi * (float(bits >> np.uint64(11)) * 2.0**-53)
        x, y = sin_theta * math.cos(phi), sin_theta * math.sin(phi)
        for k in range(3):
            out[i, k] = rotation[k, 0] * x + rotation[k, 1] * y + rotation[k, 2] * z


@njit(**_OPTIONS)
def _rotated_copies(nodes, rotations, out):
    m = nodes.shape[0]
    for c in prange(rotations.shape[0]):
        for i in range(m):
            x, y, z = nodes[i, 0], nodes[i, 1], nodes[i, 2]
            for k in range(3):
                out[c * m + i, k] = rotations[c, k, 0] * x + rotations[c, k, 1] * y + rotations[c, k, 2] * z


def compiled_sample(peer: Peer, n: int, rng, points: str = "random") -> np.ndarray:
    """``peer.sample(n, rng=rng, points=points)`` (float64), computed by a compiled, parallel kernel.

    Parameters
    ----------
    peer : symsphere.peers.Peer
        One of :data:`COMPILED_PEERS`.
    n : int
    rng : None, int, numpy.random.SeedSequence or numpy.random.Generator
    points : str
        A named point set (the maps) or 'random'.

    Returns
    -------
    ndarray, shape (n, 3), float64

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.apps.study._compiled import compiled_sample
    >>> from symsphere.peers import PEERS
    >>> peer = PEERS["octahedral"]
    >>> bool(np.allclose(compiled_sample(peer, 512, 3, "sobol"), peer.sample(512, rng=3, points="sobol"),
    ...                  rtol=0, atol=1e-15))
    True
    """
    start_threads()  # numba's threads wait passively, as the scheme's kernels' do
    out = np.empty((n, 3))
    if peer.name in ("classic", "octahedral"):
        uv = BasePoints(points, rng, n).take(0, n)
        (_classic if peer.name == "classic" else _octahedral)(uv, out)
    elif peer.name == "fibonacci_rotated":
        _fibonacci_rotated(np.ascontiguousarray(Rotation.random(rng=check_rng(rng)).as_matrix()), out)
    elif peer.name == "lebedev_rotated":
        size = 5810 if n % 5810 == 0 else lebedev_size(n)
        if size != 5810:  # a single small rule: not worth a kernel
            return sample_lebedev(n, randomize=True, rng=rng)
        rotations = np.ascontiguousarray(Rotation.random(n // size, rng=check_rng(rng)).as_matrix())
        _rotated_copies(sample_lebedev(size), rotations, out)
    else:
        raise ValueError(f"'peer' must be one of {COMPILED_PEERS}, got {peer.name!r}")
    return out
