"""Point sets on the unit square: the inputs of the maps.

- ``'random'``: independent uniform points;
- ``'stratified'``: a jittered sqrt(m) x sqrt(m) grid, one point per cell (m must be a square);
- ``'sobol'``: scrambled Sobol' points (``scipy.stats.qmc.Sobol``); a warning, as scipy
  gives, when m is not a power of 2, since the balance properties need it;
- ``'halton'``: scrambled Halton points (``scipy.stats.qmc.Halton``);
- any ``scipy.stats.qmc.QMCEngine`` with ``d == 2``, used from its current state (which advances).

Points are addressed by index, so that any stretch ``[start, stop)`` can be made on
its own and every chunking of a run gives the same points (:class:`BasePoints`).
Random points are one stream of numpy's ``PCG64`` seeded by
``SeedSequence(root_entropy, spawn_key=(0,))``: point ``i`` is ``(u, v)`` = draws
``2i`` and ``2i + 1`` of ``Generator.random``, and a stretch starting at ``i`` is
reached by ``PCG64.advance(2 i)`` (a jump of O(log i) steps), so the numbers depend
on the root seed and the index only, not on how the run is split into chunks,
threads or workers.  QMC points are consecutive segments of one scrambled sequence
(``fast_forward``).  :data:`BLOCK` is the unit in which the integrator and the
distributed code cut their work.
"""

from __future__ import annotations

import math
import warnings
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from ._typing import Float64Array, PointSet, PointsLike, RNGLike
from ._validation import check_choice, check_count, check_rng, check_sobol_size

if TYPE_CHECKING:
    from scipy.stats.qmc import QMCEngine

__all__ = ["POINT_SETS", "BLOCK", "BasePoints", "unit_square_points", "check_points"]

POINT_SETS: tuple[PointSet, ...] = ("random", "stratified", "sobol", "halton")
"""tuple of str: the named point sets of the unit square, the choices of ``points=``.

They are described in the module docstring; ``points=`` also takes a ``scipy.stats.qmc.QMCEngine``
with ``d == 2`` (see :func:`check_points`)."""

BLOCK = 4096
"""Base points per unit of work of the integrator and of :mod:`symsphere.distributed`."""

_STREAM_KEY, _SCRAMBLE_KEY = 0, 1  # spawn-key namespaces of the root SeedSequence
_SOBOL_WARNING = "The balance properties of Sobol' points require n to be a power of 2."


def unit_square_points(
    m: int, points: PointsLike = "random", rng: RNGLike = None, *, per_point: int = 1
) -> Float64Array:
    """Draw *m* points of the unit square.

    Parameters
    ----------
    m : int
        Number of points.
    points : {'random', 'stratified', 'sobol', 'halton'} or scipy.stats.qmc.QMCEngine
        The point set; an engine must have ``d == 2``.
    rng : None, int, numpy.random.SeedSequence or numpy.random.Generator
        Randomness for the random points, the jitter, or the scrambling.
    per_point : int
        How many outputs the caller makes from each point (48 or 24); only
        used to phrase errors in terms of the caller's ``n``.

    Returns
    -------
    ndarray, shape (m, 2), float64

    Examples
    --------
    >>> from symsphere.points import unit_square_points
    >>> unit_square_points(4, "stratified", rng=0).shape
    (4, 2)
    """
    m = check_count(m, "m")
    return BasePoints(points, rng, m, per_point=per_point).take(0, m)


class BasePoints:
    """A reproducible, index-addressable source of *total* points of the unit square.

    Parameters
    ----------
    points : {'random', 'stratified', 'sobol', 'halton'} or scipy.stats.qmc.QMCEngine
    rng : None, int, numpy.random.SeedSequence or numpy.random.Generator
        Consumed once, at construction, to fix the root seed (a Generator
        advances; the same int, SeedSequence or freshly seeded Generator gives
        the same points).
    total : int
        Number of points in the run (the grid size for ``'stratified'``, the
        count checked for Sobol' balance).
    per_point : int
        Outputs per point (48 or 24), only to phrase errors in terms of ``n``.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.points import BasePoints
    >>> source = BasePoints("random", 7, total=10_000)
    >>> whole = source.take(0, 10_000)
    >>> bool(np.array_equal(whole[5000:6000], BasePoints("random", 7, total=10_000).take(5000, 6000)))
    True
    """

    def __init__(self, points: PointsLike, rng: RNGLike, total: int, *, per_point: int = 1) -> None:
        self.total = check_count(total, "total")
        self._engine = check_points(points)
        check_sobol_size(points, self.total, per_point)  # at the call, not when the last chunk is drawn
        self._kind: str = "engine" if self._engine is not None else points
        self._side: int | None = None
        entropy = check_rng(rng).integers(0, 2**63, size=4, dtype=np.int64)
        self.root_entropy = tuple(int(e) for e in entropy)
        if self._kind == "stratified":
            self._side = _square_side(self.total, per_point)
        elif self._kind in ("sobol", "halton"):
            from scipy.stats import qmc  # imported when needed: scipy.stats costs 0.3 s at start-up

            engine_class = qmc.Sobol if self._kind == "sobol" else qmc.Halton
            scramble_seed = np.random.SeedSequence(self.root_entropy, spawn_key=(_SCRAMBLE_KEY,))
            self._engine = engine_class(d=2, scramble=True, rng=np.random.default_rng(scramble_seed))
        # The random stream's seed, for the kernels (below).
        self.seed_words: npt.NDArray[np.unsignedinteger[Any]] | None = None
        if self._engine is not None:
            self._offset = self._engine.num_generated
            if type(self._engine).__name__ == "Sobol" and self.total & (self.total - 1):
                warnings.warn(_SOBOL_WARNING, UserWarning, stacklevel=3)
        else:
            self._stream_seed = np.random.SeedSequence(self.root_entropy, spawn_key=(_STREAM_KEY,))
            # What numpy's PCG64 takes from the SeedSequence (uint64[4]): the kernels seed their
            # own copy of the stream from it (symsphere._kernels.pcg64_seeded).
            self.seed_words = self._stream_seed.generate_state(4, np.uint64)
            self._stream_start: Any = None  # numpy's PCG64 state at point 0, made when take() needs it

    @property
    def kind(self) -> str:
        """``'random'``, ``'stratified'``, ``'sobol'``, ``'halton'`` or ``'engine'``."""
        return self._kind

    def take(self, start: int, stop: int) -> Float64Array:
        """Points ``start ... stop - 1`` of the run, shape (stop - start, 2), float64."""
        if not 0 <= start <= stop <= self.total:
            raise ValueError(f"'start'={start} and 'stop'={stop} must satisfy 0 <= start <= stop <= {self.total}")
        if self._engine is not None:
            return self._take_engine(start, stop)
        jitter = self._take_random(start, stop)
        if self._kind == "random":
            return jitter
        side = self._side
        assert side is not None  # set at construction for 'stratified', the only other kind
        cells = np.arange(start, stop)
        corner = np.stack([cells // side, cells % side], axis=-1)
        return (corner + jitter) / side

    def _generator_at(self, index: int) -> np.random.Generator:
        if self._stream_start is None:
            self._stream_start = np.random.PCG64(self._stream_seed).state
        bit_generator = np.random.PCG64(0)  # any seed (not None: that reads OS entropy); replaced next
        bit_generator.state = self._stream_start
        bit_generator.advance(2 * int(index))  # two draws per point; advance takes Python ints only
        return np.random.Generator(bit_generator)

    def _take_random(self, start: int, stop: int) -> Float64Array:
        return self._generator_at(start).random((stop - start, 2))

    def _take_engine(self, start: int, stop: int) -> Float64Array:
        engine = self._engine
        assert engine is not None  # take() calls this for engines only
        position = self._offset + start
        if engine.num_generated != position:
            engine.reset()
            if position:  # scipy's Sobol.fast_forward(0) raises (it computes n - 1)
                engine.fast_forward(position)
        with warnings.catch_warnings():
            # The balance warning is given once, for the whole run, at construction.
            warnings.filterwarnings("ignore", message="The balance properties of Sobol")
            return np.asarray(engine.random(stop - start), dtype=np.float64)


def check_points(points: object) -> QMCEngine | None:
    """Validate *points*; return the engine if it is a QMCEngine, else None.

    Parameters
    ----------
    points : object
        What a ``points=`` argument was given: a name in :data:`POINT_SETS` or a
        ``scipy.stats.qmc.QMCEngine`` with ``d == 2``.

    Returns
    -------
    scipy.stats.qmc.QMCEngine or None
        The engine itself (not copied: drawing from it advances it), or None for a name.

    Raises
    ------
    ValueError
        For an unknown name, or an engine whose dimension ``d`` is not 2.
    TypeError
        For anything else.

    Examples
    --------
    >>> from scipy.stats import qmc
    >>> from symsphere.points import check_points
    >>> check_points("sobol") is None
    True
    >>> engine = qmc.Halton(d=2, rng=1)
    >>> check_points(engine) is engine
    True
    >>> check_points("grid")
    Traceback (most recent call last):
        ...
    ValueError: 'grid' is not a valid points; use one of {'random', 'stratified', 'sobol', 'halton'}
    """
    if isinstance(points, str):
        check_choice(points, "points", POINT_SETS)
        return None
    from scipy.stats import qmc  # not at import: scipy.stats costs 0.3 s at start-up

    if isinstance(points, qmc.QMCEngine):
        if points.d != 2:
            raise ValueError(f"'points' engine must have d=2 (points of the unit square), got d={points.d}")
        return points
    raise TypeError(
        f"'points' must be one of {set(POINT_SETS)} or a scipy.stats.qmc.QMCEngine, got {type(points).__name__}"
    )


def _square_side(m: int, per_point: int) -> int:
    side = math.isqrt(m)
    if side * side != m:
        options = [c for c in (side * side, (side + 1) ** 2) if c > 0]
        if per_point > 1:
            sizes = " or ".join(f"n={per_point * c}" for c in options)
            got = f"n={per_point * m} gives {m} (n/{per_point})"
        else:
            sizes = " or ".join(str(c) for c in options)
            got = f"got {m}"
        raise ValueError(f"points='stratified' needs a square number of base points; {got}; use {sizes}")
    return side
