"""Point sets on the unit square: the inputs of the maps.

- ``'random'``: independent uniform points;
- ``'stratified'``: a jittered sqrt(m) x sqrt(m) grid, one point per cell (m must be a square);
- ``'sobol'``: scrambled Sobol' points (``scipy.stats.qmc.Sobol``); a warning, as scipy
  gives, when m is not a power of 2, since the balance properties need it;
- ``'halton'``: scrambled Halton points (``scipy.stats.qmc.Halton``);
- ``'sobol_interlaced2'``, ``'sobol_interlaced3'``: higher-order scrambled digital nets (Dick,
  "Higher order scrambled digital nets achieve the optimal rate of the root mean square error for
  smooth integrands", Ann. Statist. 39 (2011) 1372-1398): scrambled Sobol' points of dimension
  2 x 2 or 2 x 3 (``scipy.stats.qmc.Sobol``, LMS + digital shift, as ``'sobol'``), whose coordinates
  are then interlaced digit by digit, 2 or 3 at a time (:func:`interlace_digits`); the interlacing
  factor is the order of smoothness the net exploits, and is the number in the name.  A smooth
  integrand's RMSE decreases up to about n^(-factor - 1/2) instead of Sobol's n^(-3/2);
  the same power-of-2 warning as ``'sobol'``;
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

import numbers
import warnings
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt
from numba import njit, prange

from ._random.pcg64 import pcg64_integers63
from ._random.seed_sequence import seed_words
from ._threads import route_compiles, start_threads
from ._typing import Float64Array, PointSet, PointsLike, RNGLike
from ._validation import (
    MAX_COUNT,
    as_float_array,
    check_count,
    check_point_set,
    check_rng_seed,
    check_size,
    check_sobol_size,
    check_square_count,
    short_repr,
)

if TYPE_CHECKING:
    from scipy.stats.qmc import QMCEngine

__all__ = ["POINT_SETS", "BLOCK", "BasePoints", "interlace_digits", "unit_square_points", "check_points"]

POINT_SETS: tuple[PointSet, ...] = ("random", "stratified", "sobol", "halton", "sobol_interlaced2", "sobol_interlaced3")
"""tuple of str: the named point sets of the unit square, the choices of ``points=``.

They are described in the module docstring; ``points=`` also takes a ``scipy.stats.qmc.QMCEngine``
with ``d == 2`` (see :func:`check_points`)."""

BLOCK = 4096
"""Base points per unit of work of the integrator and of :mod:`symsphere.distributed`."""

_STREAM_KEY, _SCRAMBLE_KEY = 0, 1  # spawn-key namespaces of the root SeedSequence
_INTERLACED = {"sobol_interlaced2": 2, "sobol_interlaced3": 3}  # name -> interlacing factor
_SOBOL_BITS = 30  # scipy's Sobol' default: every coordinate is a multiple of 2**-30
_SOBOL_WARNING = "The balance properties of Sobol' points require n to be a power of 2."


def unit_square_points(
    m: int, points: PointsLike = "random", rng: RNGLike = None, *, per_point: int = 1
) -> Float64Array:
    """Draw *m* points of the unit square.

    Parameters
    ----------
    m : int
        Number of points.
    points : {'random', 'stratified', 'sobol', 'halton', 'sobol_interlaced2', 'sobol_interlaced3'} \
or scipy.stats.qmc.QMCEngine
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
    points : {'random', 'stratified', 'sobol', 'halton', 'sobol_interlaced2', 'sobol_interlaced3'} \
or scipy.stats.qmc.QMCEngine
    rng : None, int, numpy.random.SeedSequence or numpy.random.Generator
        Consumed once, at construction, to fix the root seed (a Generator
        advances; the same int, SeedSequence or freshly seeded Generator gives
        the same points).
    total : int
        Number of points in the run (the grid size for ``'stratified'``, the
        count checked for Sobol' balance).
    per_point : int
        Outputs per point (48 or 24), only to phrase errors in terms of ``n``.
    n : int, optional
        The caller's number of outputs (``total = ceil(n / per_point)``), only for the
        errors, which quote it as given; default ``total * per_point``.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.points import BasePoints
    >>> source = BasePoints("random", 7, total=10_000)
    >>> whole = source.take(0, 10_000)
    >>> bool(np.array_equal(whole[5000:6000], BasePoints("random", 7, total=10_000).take(5000, 6000)))
    True
    """

    def __init__(
        self, points: PointsLike, rng: RNGLike, total: int, *, per_point: int = 1, n: int | None = None
    ) -> None:
        self.total = check_count(total, "total")
        per_point = check_count(per_point, "per_point")  # every point set: a positive integer
        check_size(self.total * per_point, "total * per_point", MAX_COUNT, "(the caller's n)")
        self._engine = check_points(points)
        # n: the caller's count (ceil(n / per_point) = total), for the messages; default total * per_point.
        check_sobol_size(points, self.total, per_point, n=n)  # at the call, not when the last chunk is drawn
        self._kind: str = "engine" if self._engine is not None else points
        self._side: int | None = None
        self.root_entropy = _root_entropy(rng)
        if self._kind == "stratified":
            self._side = check_square_count(self.total, per_point, n)
        elif self._kind in ("sobol", "halton") or self._kind in _INTERLACED:
            from scipy.stats import qmc  # imported when needed: scipy.stats costs 0.3 s at start-up

            engine_class = qmc.Halton if self._kind == "halton" else qmc.Sobol
            scramble_seed = np.random.SeedSequence(self.root_entropy, spawn_key=(_SCRAMBLE_KEY,))
            # An interlaced set scrambles 2 x factor Sobol' coordinates, then interlaces them (take()).
            self._engine = engine_class(
                d=2 * _INTERLACED.get(self._kind, 1), scramble=True, rng=np.random.default_rng(scramble_seed)
            )
        # The random stream's seed, for the kernels (below).
        self.seed_words: npt.NDArray[np.unsignedinteger[Any]] | None = None
        if self._engine is not None:
            self._offset = self._engine.num_generated
            if type(self._engine).__name__ == "Sobol" and self.total & (self.total - 1):
                warnings.warn(_SOBOL_WARNING, UserWarning, stacklevel=3)
        else:
            # What numpy's PCG64 takes from SeedSequence(root_entropy, spawn_key=(_STREAM_KEY,))
            # (uint64[4]): the kernels seed their own copy of the stream from it (pcg64_seeded).
            self.seed_words = np.array(seed_words(self.root_entropy, (_STREAM_KEY,)), dtype=np.uint64)
            self._stream_start: Any = None  # numpy's PCG64 state at point 0, made when take() needs it

    @property
    def kind(self) -> str:
        """The name of the point set (one of :data:`POINT_SETS`), or ``'engine'``."""
        return self._kind

    def take(self, start: int, stop: int) -> Float64Array:
        """Points ``start ... stop - 1`` of the run, shape (stop - start, 2), float64."""
        for name, value in (("start", start), ("stop", stop)):
            if isinstance(value, bool) or not isinstance(value, numbers.Integral):
                raise TypeError(f"'{name}' must be an integer index; got {type(value).__name__} {short_repr(value)}")
        start, stop = int(start), int(stop)
        if not 0 <= start <= stop <= self.total:
            raise ValueError(f"'start'={start} and 'stop'={stop} must satisfy 0 <= start <= stop <= {self.total}")
        if self._engine is not None:
            raw = self._take_engine(start, stop)
            factor = _INTERLACED.get(self._kind)
            return raw if factor is None else interlace_digits(raw, factor)
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
            stream_seed = np.random.SeedSequence(self.root_entropy, spawn_key=(_STREAM_KEY,))
            self._stream_start = np.random.PCG64(stream_seed).state
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


def _root_entropy(rng: RNGLike) -> tuple[int, ...]:
    """``check_rng(rng).integers(0, 2**63, size=4, dtype=np.int64)`` as Python ints.  From an int, None or a
    SeedSequence the same four numbers without a Generator: its PCG64 drawn (and an int's SeedSequence hashed)
    in Python's integers."""
    seed = check_rng_seed(rng)
    if isinstance(seed, np.random.Generator):
        return tuple(int(e) for e in seed.integers(0, 2**63, size=4, dtype=np.int64))
    words = seed.generate_state(4, np.uint64) if isinstance(seed, np.random.SeedSequence) else seed_words(seed)
    return pcg64_integers63(words, 4)


def interlace_digits(x: npt.ArrayLike, factor: int) -> Float64Array:
    """Interlace the binary digits of groups of *factor* coordinates (Dick's digit interlacing).

    Row ``x`` of dimension ``s * factor`` becomes a row ``y`` of dimension ``s``: coordinate j of
    ``y`` takes its digits in turn from coordinates ``j*factor, ..., j*factor + factor - 1`` of
    ``x``: with ``x_k = 0.a_k1 a_k2 ...`` in base 2, ``y_j = 0.a_1,1 a_2,1 ... a_f,1 a_1,2 a_2,2 ...``
    (k = j*factor + 1 ... j*factor + f).  Applied to a digital (t, m, s*factor)-net (Sobol'
    points, scrambled or not) it gives an order-*factor* digital net of dimension s (Dick 2008,
    2011), which integrates functions with *factor* square-integrable mixed derivatives with
    error up to O(n^-factor (log n)^(s factor)), and, scrambled first, with RMSE
    O(n^(-factor - 1/2 + eps)).  Its elementary intervals of volume 2^-(m - t) still hold
    2^t points each: it is an ordinary digital (t, m, s)-net too.

    Each coordinate of ``y`` is made of the leading ``53 // factor`` digits of its *factor*
    sources (26 or 17 for factors 2 and 3; a float64 holds 53), and is the centre of its cell
    of side 2^-(factor (53 // factor)): never 0 or 1, and exactly uniform in mean if each source
    digit is (as after scipy's digital shift).

    Parameters
    ----------
    x : array_like, shape (m, s * factor)
        Points of the unit cube, in [0, 1); digits beyond the 53rd are ignored.
    factor : int
        The interlacing factor (the order of the net), 1 ... 8.

    Returns
    -------
    ndarray, shape (m, s), float64

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.points import interlace_digits
    >>> y = interlace_digits([[0.5, 0.25, 0.75, 0.0]], 2)   # 0.1|0.01 -> 0.1001; 0.11|0.00 -> 0.1010
    >>> y.round(6)
    array([[0.5625, 0.625 ]])
    """
    factor = check_count(factor, "factor", maximum=8)
    x = as_float_array(x, "x").astype(np.float64, copy=False)
    if x.ndim != 2 or x.shape[1] % factor or x.shape[1] == 0:
        raise ValueError(f"'x' must have shape (m, s * factor) with factor={factor}, got {x.shape}")
    if np.any(~((x >= 0) & (x < 1))):
        raise ValueError("'x' must lie in [0, 1)")
    out = np.empty((x.shape[0], x.shape[1] // factor))
    start_threads()  # numba's threads wait passively (symsphere._threads)
    _interlace(x, factor, 53 // factor, out)
    return out


@njit(cache=True, nogil=True)
def _spread(d, factor, bits):  # type: ignore[no-untyped-def]
    # Digit b of d (from the top, 1-based) -> bit factor * bits - 1 - (b - 1) factor of the result.
    if factor == 2:  # 26 bits: the "magic numbers" of Morton codes
        d = (d | (d << np.uint64(16))) & np.uint64(0x0000FFFF0000FFFF)
        d = (d | (d << np.uint64(8))) & np.uint64(0x00FF00FF00FF00FF)
        d = (d | (d << np.uint64(4))) & np.uint64(0x0F0F0F0F0F0F0F0F)
        d = (d | (d << np.uint64(2))) & np.uint64(0x3333333333333333)
        return (d | (d << np.uint64(1))) & np.uint64(0x5555555555555555)
    if factor == 3:  # 17 bits
        d = (d | (d << np.uint64(32))) & np.uint64(0x001F00000000FFFF)
        d = (d | (d << np.uint64(16))) & np.uint64(0x001F0000FF0000FF)
        d = (d | (d << np.uint64(8))) & np.uint64(0x100F00F00F00F00F)
        d = (d | (d << np.uint64(4))) & np.uint64(0x10C30C30C30C30C3)
        return (d | (d << np.uint64(2))) & np.uint64(0x1249249249249249)
    value = np.uint64(0)
    for b in range(bits):
        value |= ((d >> np.uint64(b)) & np.uint64(1)) << np.uint64(b * factor)
    return value


@njit(cache=True, parallel=True, nogil=True)
def _interlace(x, factor, bits, out):  # type: ignore[no-untyped-def]
    # Output digit (b - 1) factor + k + 1 is digit b of source k (from the top); the output is the
    # centre of its cell of side 2^-(factor bits).
    scale = 2.0**bits
    cell = 2.0 ** -(factor * bits)
    for i in prange(x.shape[0]):
        for j in range(out.shape[1]):
            value = np.uint64(0)
            for k in range(factor):
                digits = np.uint64(x[i, j * factor + k] * scale)  # the leading `bits` digits, exactly
                value |= _spread(digits, factor, bits) << np.uint64(factor - 1 - k)
            out[i, j] = (float(value) + 0.5) * cell


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
    ValueError: 'grid' is not a valid points; use one of {'random', 'stratified', 'sobol', 'halton', \
'sobol_interlaced2', 'sobol_interlaced3'}
    """
    return check_point_set(points, POINT_SETS)


route_compiles(globals())  # the first compile of each numba function here: interruptible (_threads)
