"""Compiled samplers of the peers, so that timings (the convergence study's) compare methods, not implementations.

The scheme's directions come from symsphere's numba kernels (parallel over all threads); the library's
peers (:mod:`symsphere.peers`) are vectorised numpy, one thread.  Here the peers the study times get
numba kernels too, parallel in the same way: the same base points (the library's
:class:`~symsphere.points.BasePoints`, i.e. numpy's PCG64 or scipy's Sobol' engine), the same random
rotations (scipy's ``Rotation.random`` from the same generator), and each map's own elementwise
formula (:func:`symsphere.warps.octahedral_sphere_point`, :func:`symsphere.peers.fibonacci_point`, ...),
compiled for one point at a time.  :func:`compiled_sample` returns what ``peer.sample`` returns, to rounding
(tested in ``tests/test_compiled_peers.py``), for the peers of :data:`COMPILED_PEERS`.
"""

from __future__ import annotations

from typing import Literal, TypedDict

import numpy as np
from numba import njit, prange

from ._threads import route_compiles, start_threads
from ._typing import Float64Array, FloatArray, PointSet, RNGLike
from ._validation import check_rng
from .peers import Peer, fibonacci_point, lebedev_size, sample_lebedev
from .points import BasePoints
from .warps import octahedral_sphere_point, uniform_sphere_point

__all__ = ["COMPILED_PEERS", "compiled_sample"]

COMPILED_PEERS = ("classic", "octahedral", "fibonacci_rotated", "lebedev_rotated")
"""The peers whose sampling :func:`compiled_sample` compiles."""


class _JitOptions(TypedDict):
    cache: bool
    parallel: bool
    nogil: bool
    error_model: Literal["python", "numpy"]


_OPTIONS: _JitOptions = {"cache": True, "parallel": True, "nogil": True, "error_model": "numpy"}


@njit(**_OPTIONS)
def _classic(uv: Float64Array, out: Float64Array) -> None:
    for i in prange(uv.shape[0]):
        x, y, z = uniform_sphere_point(uv[i, 0], uv[i, 1])
        out[i, 0], out[i, 1], out[i, 2] = x, y, z


@njit(**_OPTIONS)
def _octahedral(uv: Float64Array, out: Float64Array) -> None:
    for i in prange(uv.shape[0]):
        x, y, z = octahedral_sphere_point(uv[i, 0], uv[i, 1])
        out[i, 0], out[i, 1], out[i, 2] = x, y, z


@njit(**_OPTIONS)
def _fibonacci_rotated(rotation: Float64Array, out: Float64Array) -> None:
    n = out.shape[0]
    for i in prange(n):
        x, y, z = fibonacci_point(i, n)
        for k in range(3):
            out[i, k] = rotation[k, 0] * x + rotation[k, 1] * y + rotation[k, 2] * z


@njit(**_OPTIONS)
def _rotated_copies(nodes: FloatArray, rotations: Float64Array, out: Float64Array) -> None:
    m = nodes.shape[0]
    for c in prange(rotations.shape[0]):
        for i in range(m):
            x, y, z = nodes[i, 0], nodes[i, 1], nodes[i, 2]
            for k in range(3):
                out[c * m + i, k] = rotations[c, k, 0] * x + rotations[c, k, 1] * y + rotations[c, k, 2] * z


def compiled_sample(peer: Peer, n: int, rng: RNGLike, points: PointSet = "random") -> FloatArray:
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
    >>> from symsphere._compiled_peers import compiled_sample
    >>> from symsphere.peers import PEERS
    >>> peer = PEERS["octahedral"]
    >>> bool(np.allclose(compiled_sample(peer, 512, 3, "sobol"), peer.sample(512, rng=3, points="sobol"),
    ...                  rtol=0, atol=1e-15))
    True
    """
    from scipy.spatial.transform import Rotation  # function-level: scipy.spatial adds ~0.3 s to every CLI start

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


route_compiles(globals())  # the first compile of each numba function here: interruptible (_threads)
