"""The paper's parallel sampling scheme: one point of T0, 48 (24) directions.

``n / 48`` base points are drawn in T0 by a map from the unit square; each is
replaced by its orbit under the 48 signed permutations of Table 2 (the
hemisphere: 24, Table 1).  Rows ``48 i ... 48 i + 47`` of the output are the
orbit of base point ``i``, in table order, so row ``48 i + k`` lies in
triangle k.  If the map is uniform on T0, each whole orbit is uniform as a set
(a row chosen at random from it is uniform on the sphere, and the mean of f over
it is unbiased); the rows of one orbit are not independent.

Any size: :func:`sample_sphere` and :func:`sample_hemisphere` take any positive
``n``, as ``numpy.random.Generator.random`` does.  The first ``n // 48``
(``n // 24``) orbits are whole; the last ``n % 48`` rows are members of one
more orbit: members ``s, s + 1, ...`` (mod 48) in table order from an offset s
drawn uniformly from the seed, independently of the base point.  Each of those
rows is the image of a uniform base point under a symmetry chosen uniformly, so it is uniform on the sphere, and the mean of f over all n rows is
an unbiased estimate of its mean over the sphere.  For random base points the
whole orbits are the rows of ``sample_sphere(48 * (n // 48))`` with the same
seed; multiples of 48 take exactly the path they always took.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
import numpy.typing as npt

from . import _blocks, frames
from ._typing import DTypeLike, Float64Array, FloatArray, MapMethod, PointsLike, RNGLike
from ._validation import check_count, check_normal, check_out, check_unit_directions, machine_memory
from .warps._scheme import scheme_pdf

__all__ = ["sample_sphere", "sample_hemisphere", "iter_sphere", "iter_hemisphere", "sphere_pdf", "hemisphere_pdf"]

DEFAULT_CHUNK = 48 * 2**16
"""Directions per block of :func:`iter_sphere` (3 145 728: 75 MB in float64)."""


def sample_sphere(
    n: int,
    *,
    method: MapMethod = "equal_area",
    points: PointsLike = "random",
    rng: RNGLike = None,
    dtype: DTypeLike = np.float64,
    out: FloatArray | None = None,
) -> FloatArray:
    """Directions on the unit sphere by the 48-fold symmetric scheme.

    Parameters
    ----------
    n : int
        Number of directions, any positive integer.  Multiples of 48 are whole
        orbits; otherwise the last orbit is cut short to ``n % 48`` of its members,
        from a random offset (see the module docstring: each of them is uniform).
    method : {'equal_area', 'paper1', 'paper2'}
        Map from the unit square onto T0.  Only ``'equal_area'`` gives uniform
        directions; the paper's maps have density :func:`sphere_pdf`.
    points : {'random', 'stratified', 'sobol', 'halton'} or scipy.stats.qmc.QMCEngine
        The ``ceil(n/48)`` base points of the unit square (``'stratified'`` needs
        their number to be a square; ``'sobol'`` warns unless it is a power of 2).
    rng : None, int, numpy.random.SeedSequence or numpy.random.Generator
        Seeds the points (or their scrambling).  The same seed gives the same output.
    dtype : {numpy.float64, numpy.float32}
    out : ndarray, optional
        Output array of shape (n, 3) and the given dtype, C-contiguous.

    Returns
    -------
    ndarray, shape (n, 3)
        Row ``48 i + k`` is ``orbit(base_i)[k]``; the rows of a cut last orbit are
        members ``(s + j) % 48`` of ``orbit(base_i)``, s random.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere import sample_sphere
    >>> d = sample_sphere(96, rng=1)
    >>> d.shape
    (96, 3)
    >>> bool(np.allclose(np.linalg.norm(d, axis=1), 1.0))
    True
    >>> bool(np.allclose(d[:48].mean(axis=0), 0.0))   # an orbit is symmetric about 0
    True
    >>> e = sample_sphere(100, rng=1)                  # any n: 2 whole orbits and 4 members of a third
    >>> e.shape, bool(np.array_equal(e[:96], d))
    ((100, 3), True)
    """
    return _sample(n, 48, None, method, points, rng, dtype, out)


def sample_hemisphere(
    n: int,
    *,
    normal: npt.ArrayLike | None = None,
    method: MapMethod = "equal_area",
    points: PointsLike = "random",
    rng: RNGLike = None,
    dtype: DTypeLike = np.float64,
    out: FloatArray | None = None,
) -> FloatArray:
    """Directions on the unit hemisphere by the 24-fold symmetric scheme.

    Parameters
    ----------
    n : int
        Number of directions, any positive integer; multiples of 24 are whole
        orbits, otherwise the last orbit is cut short to random members (each uniform).
    normal : array_like of 3 floats, optional
        Pole of the hemisphere (normalised; default (0, 0, 1)).  The
        hemisphere about (0, 0, 1) is carried onto it by the frame of
        :func:`symsphere.frames.frame` (Duff et al. 2017).
    method, points, rng, dtype, out
        As in :func:`sample_sphere`.

    Returns
    -------
    ndarray, shape (n, 3)
        Row ``24 i + k`` is ``orbit(base_i, 'hemisphere')[k]``, rotated onto *normal*.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere import sample_hemisphere
    >>> d = sample_hemisphere(48, normal=[1.0, 0.0, 0.0], rng=2)
    >>> bool(np.all(d[:, 0] >= 0))
    True
    >>> sample_hemisphere(7, rng=2).shape              # any n
    (7, 3)
    """
    normal = check_normal(normal)
    return _sample(n, 24, normal, method, points, rng, dtype, out)


def iter_sphere(
    n_total: int,
    *,
    chunk: int = DEFAULT_CHUNK,
    method: MapMethod = "equal_area",
    points: PointsLike = "random",
    rng: RNGLike = None,
    dtype: DTypeLike = np.float64,
    out: FloatArray | None = None,
) -> Iterator[FloatArray]:
    """Directions of :func:`sample_sphere` in blocks, for runs larger than memory.

    Parameters
    ----------
    n_total : int
        Directions in all, a positive multiple of 48.
    chunk : int
        Directions per block (a multiple of 48; the last block may be shorter).
    method, points, rng, dtype
        As in :func:`sample_sphere`.
    out : ndarray, optional
        An (n_total, 3) array of the given dtype (a ``numpy.memmap`` too): each
        block is written into its rows and yielded as a view of them, so a run
        can fill a file larger than memory.

    Returns
    -------
    iterator of ndarray, shape (m, 3)
        Consecutive blocks; concatenated, they equal ``sample_sphere(n_total, ...)``
        with the same arguments.  The arguments are checked at the call, not at the
        first block.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere import iter_sphere, sample_sphere
    >>> blocks = list(iter_sphere(48 * 1000, chunk=48 * 300, rng=5))
    >>> [len(b) for b in blocks]
    [14400, 14400, 14400, 4800]
    >>> bool(np.array_equal(np.concatenate(blocks), sample_sphere(48 * 1000, rng=5)))
    True
    """
    return _iterate(n_total, chunk, 48, None, method, points, rng, dtype, out)


def iter_hemisphere(
    n_total: int,
    *,
    chunk: int = DEFAULT_CHUNK // 2,
    normal: npt.ArrayLike | None = None,
    method: MapMethod = "equal_area",
    points: PointsLike = "random",
    rng: RNGLike = None,
    dtype: DTypeLike = np.float64,
    out: FloatArray | None = None,
) -> Iterator[FloatArray]:
    """Directions of :func:`sample_hemisphere` in blocks, for runs larger than memory.

    Parameters
    ----------
    n_total : int
        Directions in all, a positive multiple of 24.
    chunk : int
        Directions per block (a multiple of 24; the last block may be shorter).
    normal, method, points, rng, dtype
        As in :func:`sample_hemisphere`.
    out : ndarray, optional
        An (n_total, 3) array of the given dtype (a ``numpy.memmap`` too), filled block by
        block as in :func:`iter_sphere`.

    Returns
    -------
    iterator of ndarray, shape (m, 3)
        Consecutive blocks; concatenated, they equal ``sample_hemisphere(n_total, ...)``
        with the same arguments.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere import iter_hemisphere, sample_hemisphere
    >>> blocks = iter_hemisphere(24 * 100, chunk=24 * 64, normal=[1, 0, 0], rng=5)
    >>> bool(np.array_equal(np.concatenate(list(blocks)), sample_hemisphere(2400, normal=[1, 0, 0], rng=5)))
    True
    """
    normal = check_normal(normal)
    return _iterate(n_total, chunk, 24, normal, method, points, rng, dtype, out)


def sphere_pdf(d: npt.ArrayLike, method: MapMethod = "equal_area") -> FloatArray:
    """Density (solid angle) of each direction that :func:`sample_sphere` returns.

    Parameters
    ----------
    d : array_like, shape (..., 3)
        Unit directions.
    method : {'equal_area', 'paper1', 'paper2'}

    Returns
    -------
    ndarray, shape (...)
        ``square_to_triangle_pdf(base, method) / 48`` where ``base`` is the fold of *d*
        into T0: ``1/(4 pi)`` for ``'equal_area'``.  The paper's maps diverge
        (``inf``) at the six images of the vertex (0, 0, 1): the axes.

    See Also
    --------
    symsphere.warps.square_to_sphere_pdf : the same function (one implementation) under the
        warp's name: the sampler's orbits have the warp's density.

    Examples
    --------
    >>> from symsphere import sphere_pdf
    >>> float(sphere_pdf([0.0, 0.6, -0.8])) * 4 * 3.141592653589793
    1.0
    """
    d = check_unit_directions(d, "d")
    return scheme_pdf(d.astype(np.float64), method, 48, d.dtype)


def hemisphere_pdf(
    d: npt.ArrayLike, method: MapMethod = "equal_area", normal: npt.ArrayLike | None = None
) -> FloatArray:
    """Density (solid angle) of each direction that :func:`sample_hemisphere` returns.

    Parameters
    ----------
    d : array_like, shape (..., 3)
        Unit directions.
    method : {'equal_area', 'paper1', 'paper2'}
    normal : array_like of 3 floats, optional
        Pole of the hemisphere (default (0, 0, 1)).

    Returns
    -------
    ndarray, shape (...)
        ``square_to_triangle_pdf(base, method) / 24`` on the closed hemisphere about *normal*,
        0 below it.  Directions within 16 ulps (of *d*'s dtype) of the plane count as on
        it, so that every direction :func:`sample_hemisphere` returns has a positive density.

    See Also
    --------
    symsphere.warps.square_to_hemisphere_pdf : the same density about the pole (0, 0, 1), of the
        warp; this adds the sampler's *normal* and argument checks.

    Examples
    --------
    >>> from symsphere import hemisphere_pdf
    >>> hemisphere_pdf([[0.0, 0.6, 0.8], [0.0, 0.6, -0.8]]) * 2 * 3.141592653589793
    array([1., 0.])
    """
    d = check_unit_directions(d, "d")
    normal = check_normal(normal)
    local: FloatArray = d.astype(np.float64)
    if normal is not None:
        local = frames.to_local(local, frames.frame(normal))
    return scheme_pdf(local, method, 24, d.dtype)


# --- private ------------------------------------------------------------------


def _sample(
    n: int,
    count: int,
    normal: Float64Array | None,
    method: MapMethod,
    points: PointsLike,
    rng: RNGLike,
    dtype: DTypeLike,
    out: FloatArray | None,
) -> FloatArray:
    n, dtype, method, source, basis = _blocks.prepare(n, count, normal, method, points, rng, dtype, any_size=True)
    if out is None:
        out = _allocate(n, np.dtype(dtype))
    else:
        check_out(out, (n, 3), dtype)
    return _blocks.fill_rows(source, 0, method, count, basis, out)


def _allocate(n: int, dtype: np.dtype[Any]) -> FloatArray:
    """An empty (n, 3) array; ValueError naming 'n' if it cannot fit in the machine's memory (numpy's
    MemoryError named neither the argument nor what to do)."""
    need = 3 * n * dtype.itemsize
    memory = machine_memory()
    hint = "stream them with iter_sphere / iter_hemisphere (chunk=...) or symsphere.io.stream_directions"
    if memory is not None and need > memory:
        raise ValueError(
            f"'n'={n} directions need {need / 2**30:.3g} GiB as {dtype} but this machine has "
            f"{memory / 2**30:.3g} GiB; {hint}, or pass a smaller n"
        )
    try:
        return np.empty((n, 3), dtype=dtype)
    except MemoryError:
        raise ValueError(
            f"'n'={n} directions ({need / 2**30:.3g} GiB as {dtype}) do not fit in free memory; {hint}"
        ) from None


def _iterate(
    n_total: int,
    chunk: int,
    count: int,
    normal: Float64Array | None,
    method: MapMethod,
    points: PointsLike,
    rng: RNGLike,
    dtype: DTypeLike,
    out: FloatArray | None,
) -> Iterator[FloatArray]:
    # Validate now, not at the first next(): a generator function would defer the errors.
    n_total, dtype, method, source, basis = _blocks.prepare(
        n_total, count, normal, method, points, rng, dtype, name="n_total"
    )
    per_chunk = check_count(chunk, "chunk", multiple=count) // count
    total = n_total // count
    if out is not None:
        check_out(out, (n_total, 3), dtype)

    def blocks() -> Iterator[FloatArray]:
        for start in range(0, total, per_chunk):
            stop = min(start + per_chunk, total)
            if out is None:
                block = np.empty(((stop - start) * count, 3), dtype=dtype)
            else:
                block = out[start * count : stop * count]
            yield _blocks.fill_range(source, start, stop, method, count, basis, block)

    return blocks()
