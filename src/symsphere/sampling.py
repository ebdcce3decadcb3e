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

The engine: :class:`Scheme` holds the arguments, checked once, and a position in the stream of base
points (``random``, ``reset``, ``fast_forward``, ``blocks``, ``pdf``), as scipy's ``QMCEngine``; each
function below is one call on a fresh :class:`Scheme`.
"""

from __future__ import annotations

import copy
from collections.abc import Iterator
from typing import Any

import numpy as np
import numpy.typing as npt

from . import _blocks, _kernels, frames
from ._typing import Domain, DTypeLike, FloatArray, MapMethod, PointsLike, RNGLike
from ._validation import (
    check_choice,
    check_count,
    check_dtype,
    check_normal,
    check_out,
    check_rng_seed,
    check_unit_directions,
    machine_memory,
)
from .points import check_points
from .symmetry import DOMAINS, orbit_size
from .warps import triangle_warp
from .warps._scheme import scheme_pdf

__all__ = [
    "Scheme", "sample_sphere", "sample_hemisphere", "iter_sphere", "iter_hemisphere", "sphere_pdf",
    "hemisphere_pdf",
]  # fmt: skip

DEFAULT_CHUNK = orbit_size("sphere") * 2**16
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
    return Scheme("sphere", method=method, points=points, dtype=dtype, rng=rng).random(n, out=out)


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
    return Scheme("hemisphere", method=method, points=points, normal=normal, dtype=dtype, rng=rng).random(n, out=out)


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
    return Scheme("sphere", method=method, points=points, dtype=dtype, rng=rng).blocks(n_total, chunk, out=out)


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
    scheme = Scheme("hemisphere", method=method, points=points, normal=normal, dtype=dtype, rng=rng)
    return scheme.blocks(n_total, chunk, out=out)


def sphere_pdf(d: npt.ArrayLike, method: MapMethod = "equal_area") -> FloatArray:
    """Density (solid angle) of each direction that :func:`sample_sphere` returns.

    Parameters
    ----------
    d : array_like, shape (..., 3)
        Unit directions (any: the sampler reaches every direction), float64 or float32.
    method : {'equal_area', 'paper1', 'paper2'}
        The map that :func:`sample_sphere` was given.

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
    return Scheme("sphere", method=method, rng=0).pdf(d)


def hemisphere_pdf(
    d: npt.ArrayLike, method: MapMethod = "equal_area", normal: npt.ArrayLike | None = None
) -> FloatArray:
    """Density (solid angle) of each direction that :func:`sample_hemisphere` returns.

    Parameters
    ----------
    d : array_like, shape (..., 3)
        Unit directions.
    method : {'equal_area', 'paper1', 'paper2'}
        The map that :func:`sample_hemisphere` was given.
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
    return Scheme("hemisphere", method=method, normal=normal, rng=0).pdf(d)


class Scheme:
    """The symmetric sampling scheme as an engine: arguments checked once, a stream drawn on demand.

    As ``scipy.stats.qmc.QMCEngine``: the engine holds a position in its stream of base points of
    T0; :meth:`random` returns the orbits of the next ones and moves on, :meth:`reset` goes back to
    the start, :meth:`fast_forward` skips.  :func:`sample_sphere`, :func:`sample_hemisphere`,
    :func:`iter_sphere`, :func:`iter_hemisphere`, :func:`sphere_pdf` and :func:`hemisphere_pdf` are
    one call on a fresh engine each, with the same output bit for bit.

    Parameters
    ----------
    domain : {'hemisphere', 'sphere'}
        The sphere (orbits of :func:`symsphere.symmetry.orbit_size` = 48 directions) or the
        hemisphere (24).
    method : {'equal_area', 'paper1', 'paper2'}
        Map from the unit square onto T0, as in :func:`sample_sphere`.
    points : {'random', 'stratified', 'sobol', 'halton', 'sobol_interlaced2', 'sobol_interlaced3'} \
or scipy.stats.qmc.QMCEngine
        The base points.  ``'stratified'`` is one grid of the size of a call: its engine draws
        once (then :meth:`reset`); the others are streams.
    normal : array_like of 3 floats, optional
        Pole of the hemisphere (``domain='hemisphere'`` only; default (0, 0, 1)).
    dtype : {numpy.float64, numpy.float32}
        Of the directions :meth:`random` returns.
    rng : None, int, numpy.random.SeedSequence or numpy.random.Generator
        Seeds the stream, once, here: a Generator advances now, by the same draw whatever the
        engine later produces.

    Attributes
    ----------
    domain : {'hemisphere', 'sphere'}
    orbit_size : int
        48 or 24: directions per base point.
    method : str
    points : str or scipy.stats.qmc.QMCEngine
    normal : ndarray of 3 floats or None
        The unit normal (normalised from the argument).
    dtype : numpy.dtype

    Notes
    -----
    The stream is one of base points: ``random(n)`` takes ``ceil(n / orbit_size)`` of them.  If
    *n* is a multiple of the orbit size they are all whole orbits, so ``random(a)`` then
    ``random(b)`` equals ``random(a + b)`` bit for bit whenever *a* is a multiple of the orbit size
    (any *b*).  Otherwise the last orbit of ``random(a)`` is cut to ``a % orbit_size`` random members
    (each uniform) and its base point is used up: the next call starts at the next orbit.
    :meth:`fast_forward` therefore counts whole orbits: *n* a multiple of the orbit size.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere import Scheme, sample_sphere
    >>> scheme = Scheme("sphere", rng=7)
    >>> a = scheme.random(96)
    >>> b = scheme.random(100)                   # continues the stream
    >>> bool(np.array_equal(np.concatenate([a, b]), sample_sphere(196, rng=7)))
    True
    >>> _ = scheme.reset().fast_forward(96)       # back to the start, skip two orbits
    >>> bool(np.array_equal(scheme.random(100), b))
    True
    >>> h = Scheme("hemisphere", normal=[0, 1, 0], dtype=np.float32, rng=1)
    >>> d = h.random(24)
    >>> d.dtype, bool(np.all(d[:, 1] >= 0))
    (dtype('float32'), True)
    >>> float(h.pdf([0.0, 1.0, 0.0]) * 2 * np.pi)
    1.0
    """

    def __init__(
        self,
        domain: Domain = "sphere",
        *,
        method: MapMethod = "equal_area",
        points: PointsLike = "random",
        normal: npt.ArrayLike | None = None,
        dtype: DTypeLike = np.float64,
        rng: RNGLike = None,
    ) -> None:
        self.domain: Domain = check_choice(domain, "domain", sorted(DOMAINS))
        self.orbit_size = orbit_size(self.domain)
        self.normal = check_normal(normal)
        if self.normal is not None and self.domain != "hemisphere":
            raise ValueError("'normal' is for domain='hemisphere' only; leave it None for the sphere")
        self.dtype: np.dtype[Any] = check_dtype(dtype)
        triangle_warp(method)  # raises for an unknown map, naming the choices
        self.method: MapMethod = method
        engine = check_points(points)
        self.points: PointsLike = points
        self._basis = None if self.normal is None else frames.frame(self.normal)
        # An engine of the user's is drawn from by position: each call puts it back where it was.
        self._engine_start = 0 if engine is None else engine.num_generated
        seed = check_rng_seed(rng)
        if isinstance(seed, np.random.Generator):
            # The user's: keep its state for the sources, and advance it once by the draw a source makes.
            self._seed: np.random.Generator | np.random.SeedSequence | int = copy.deepcopy(seed)
            seed.integers(0, 2**63, size=4, dtype=np.int64)
        else:
            self._seed = seed  # an int or SeedSequence: every source drawn from it starts the same stream
        self._random_plan: _kernels.Plan | None = None
        self._position = 0

    def random(self, n: int, out: FloatArray | None = None) -> FloatArray:
        """The next *n* directions of the stream, shape (n, 3), as :func:`sample_sphere` orders them.

        Parameters
        ----------
        n : int
            Any positive number: ``n // orbit_size`` whole orbits, then ``n % orbit_size`` members of
            one more (see the class's Notes).
        out : ndarray, optional
            Output array of shape (n, 3) and the engine's dtype, C-contiguous (as
            ``numpy.random.Generator.random``).

        Returns
        -------
        ndarray, shape (n, 3)
            *out* if given.
        """
        n = check_count(n, "n")
        count = self.orbit_size
        m = -(-n // count)
        plan = self._plan(self._position + m, n)
        if out is None:
            out = _allocate(n, self.dtype)
        else:
            check_out(out, (n, 3), self.dtype)
        start = self._position
        whole, rest = divmod(n, count)
        offset = _blocks.cut_offset(plan.source, start + whole, count) if rest else 0
        _kernels.fill(plan, start, start + m, out, offset)
        self._position += m
        return out

    def blocks(self, n_total: int, chunk: int | None = None, *, out: FloatArray | None = None) -> Iterator[FloatArray]:
        """The next *n_total* directions in blocks of *chunk* (as :func:`iter_sphere`).

        Parameters
        ----------
        n_total : int
            A positive multiple of the orbit size.
        chunk : int, optional
            Directions per block, a multiple of the orbit size (default ``orbit_size * 2**16``); the
            last block may be shorter.
        out : ndarray, optional
            An (n_total, 3) array of the engine's dtype (a ``numpy.memmap`` too), filled block by block.

        Returns
        -------
        iterator of ndarray, shape (m, 3)
            Concatenated, the blocks equal ``random(n_total)`` at the same position.  The arguments
            are checked, and the stream moved past the *n_total* directions, at the call.

        Examples
        --------
        >>> import numpy as np
        >>> from symsphere import Scheme
        >>> blocks = Scheme("hemisphere", rng=3).blocks(24 * 10, chunk=24 * 4)
        >>> [len(b) for b in blocks]
        [96, 96, 48]
        """
        count = self.orbit_size
        n_total = check_count(n_total, "n_total", multiple=count)
        total = n_total // count
        plan = self._plan(self._position + total, n_total)
        per_chunk = check_count(count * 2**16 if chunk is None else chunk, "chunk", multiple=count) // count
        if out is not None:
            check_out(out, (n_total, 3), self.dtype)
        first = self._position
        self._position += total

        def blocks() -> Iterator[FloatArray]:
            for start in range(0, total, per_chunk):
                stop = min(start + per_chunk, total)
                if out is None:
                    block = _blocks.empty_rows((stop - start) * count, self.dtype)
                else:
                    block = out[start * count : stop * count]
                yield _kernels.fill(plan, first + start, first + stop, block)

        return blocks()

    def reset(self) -> Scheme:
        """Go back to the start of the stream; returns the engine."""
        self._position = 0
        return self

    def fast_forward(self, n: int) -> Scheme:
        """Skip the next *n* directions (a multiple of the orbit size: whole orbits); returns the engine."""
        if isinstance(n, (int, np.integer)) and not isinstance(n, bool) and n == 0:
            return self
        n = check_count(n, "n", multiple=self.orbit_size)
        if self.points == "stratified":
            raise ValueError("points='stratified' is one grid of the size of a call; it cannot be fast-forwarded")
        self._position += n // self.orbit_size
        return self

    def pdf(self, d: npt.ArrayLike) -> FloatArray:
        """Density (solid angle) of the directions *d* (shape (..., 3)): :func:`sphere_pdf` /
        :func:`hemisphere_pdf` of the engine's map and normal, in *d*'s dtype."""
        d = check_unit_directions(d, "d")
        local: FloatArray = d.astype(np.float64)
        if self._basis is not None:
            local = frames.to_local(local, self._basis)
        return scheme_pdf(local, self.method, self.orbit_size, d.dtype)

    def __repr__(self) -> str:
        normal = "" if self.normal is None else f", normal={self.normal.tolist()}"
        return (
            f"Scheme({self.domain!r}, method={self.method!r}, points={self.points!r}{normal}, "
            f"dtype={self.dtype.name}, position={self._position})"
        )

    def _plan(self, total: int, n: int) -> _kernels.Plan:
        """The plan of a call that ends at base point *total* (its caller's count is *n*)."""
        if isinstance(self.points, str) and self.points == "random":
            # One stream, however long: its source does not depend on the run's size.
            if self._random_plan is None:
                source = _blocks.base_points("random", self._seed, 1, self.orbit_size)
                self._random_plan = _kernels.Plan(source, self.method, self.orbit_size, self._basis)
            return self._random_plan
        if isinstance(self.points, str) and self.points == "stratified" and self._position:
            raise ValueError("points='stratified' is one grid of the size of a call; call reset() before drawing again")
        engine = check_points(self.points)
        if engine is not None and engine.num_generated != self._engine_start:
            engine.reset()
            if self._engine_start:  # scipy's Sobol.fast_forward(0) raises
                engine.fast_forward(self._engine_start)
        # The caller's n quoted in errors of a first draw; later ones are phrased in the stream's total.
        source = _blocks.base_points(
            self.points, copy.deepcopy(self._seed), total, self.orbit_size, None if self._position else n
        )
        return _kernels.Plan(source, self.method, self.orbit_size, self._basis)


def _allocate(n: int, dtype: np.dtype[Any]) -> FloatArray:
    """An empty (n, 3) array (:func:`symsphere._blocks.empty_rows`: on cache lines, a view of an allocation
    of its own); ValueError naming 'n' if it cannot fit in the machine's memory (numpy's MemoryError named
    neither the argument nor what to do)."""
    need = 3 * n * dtype.itemsize
    memory = machine_memory()
    hint = "stream them with iter_sphere / iter_hemisphere (chunk=...) or symsphere.io.stream_directions"
    if memory is not None and need > memory:
        raise ValueError(
            f"'n'={n} directions need {need / 2**30:.3g} GiB as {dtype} but this machine has "
            f"{memory / 2**30:.3g} GiB; {hint}, or pass a smaller n"
        )
    try:
        return _blocks.empty_rows(n, dtype)
    except MemoryError:
        raise ValueError(
            f"'n'={n} directions ({need / 2**30:.3g} GiB as {dtype}) do not fit in free memory; {hint}"
        ) from None
