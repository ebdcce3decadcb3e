"""Peer samplers: the ways of sampling directions a user would pick instead.

Each peer is implemented here from its paper, with the conventions of
:func:`symsphere.sample_sphere`: ``rng=`` takes None, an int, a
``SeedSequence`` or a ``Generator``; ``dtype=`` is float64 or float32 (the
computation is in float64, cast at the end); outputs have shape (n, 3).
Densities are with respect to solid angle.  Where a peer is a map from the
unit square, the map is a :class:`symsphere.warps.Warp` (:attr:`Peer.warp`: ``square_to_X``,
``square_to_X_pdf`` and ``X_to_square`` of :mod:`symsphere.warps`), and its sampler takes quasi-Monte Carlo points
(``points=`` 'random', 'stratified', 'sobol', 'halton', 'sobol_interlaced2',
'sobol_interlaced3' or a ``scipy.stats.qmc.QMCEngine`` with ``d == 2``).

========================= =========== ===================================================
peer (key of `PEERS`)     domain      what
========================= =========== ===================================================
``classic``               sphere      z = 1 - 2u, phi = 2 pi v (Archimedes' hat-box map)
``classic_hemisphere``    hemisphere  z = u, phi = 2 pi v
``gaussian``              sphere      normalised standard normal vectors (random only)
``octahedral``            sphere      Clarberg's equal-area octahedral map (JGT 2008)
``octahedral_hemisphere`` hemisphere  its hemisphere variant (the square turned 45 deg)
``fibonacci``             sphere      spherical Fibonacci points (Keinert et al. 2015)
``fibonacci_rotated``     sphere      the same, under a uniformly random rotation
``arvo``                  sphere      Arvo (1995) on T0, then the 48 symmetric images
``lebedev``               sphere      Lebedev quadrature (scipy's rules, orders 3 to 131)
``lebedev_rotated``       sphere      the same, under uniformly random rotations
``cosine``                hemisphere  Shirley-Chiu concentric disk + Malley: cos(theta)/pi
========================= =========== ===================================================

Every map is exact and has no NaN or inf for u, v in {0, 1}, in float64 and
float32.

Arvo versus ``equal_area``: the same uniform distribution on T0, by a different map
(:func:`symsphere.warps.square_to_spherical_triangle` says how they relate).

The Lebedev rules are quadratures, not samplers: nodes with unequal weights
(:func:`lebedev_weights`, :attr:`Peer.rule_weights`; :meth:`Peer.estimate` uses them), in the
sizes of :data:`LEBEDEV_SIZES` only (:meth:`Peer.largest_n`).  A Lebedev rule is invariant under
the octahedral group: its nodes are whole orbits (of 6, 8, 12, 24 or 48 points) of the same 48
signed permutations of (x, y, z) as the symmetric scheme's, one weight per orbit, so it is itself a
sum over orbits of the same 48 maps, with the orbits and weights chosen to integrate polynomials
exactly up to the order.  Rotated by a uniformly random rotation it is unbiased for every
integrable f; ``n = r x 5810`` gives r independent rotations of the order-131 rule, whose spread
(replicates) gives the error bar.  Clarberg's octahedral map with scrambled Sobol' points
(LMS + digital shift, scipy's) is ``PEERS['octahedral'].sample(n, points='sobol')``, and with
interlaced (higher-order) Sobol' points ``points='sobol_interlaced2'``.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from ._fibonacci import fibonacci_point, fibonacci_points, sample_fibonacci
from ._lebedev import LEBEDEV_ORDERS, LEBEDEV_SIZES, lebedev_size, lebedev_weights, sample_lebedev
from ._typing import Domain, DTypeLike, Float64Array, FloatArray, PointsLike, RNGLike, Sampler
from ._validation import check_count, check_dtype, check_rng, short_repr
from .points import POINT_SETS, check_points, unit_square_points
from .symmetry import DOMAINS, orbit
from .warps import WARPS, Warp, square_to_uniform_sphere_pdf

__all__ = [
    "PEERS",
    "Peer",
    "get_peer",
    # samplers
    "sample_arvo",
    "sample_classic",
    "sample_classic_hemisphere",
    "sample_cosine",
    "sample_fibonacci",
    "sample_gaussian",
    "sample_lebedev",
    "lebedev_size",
    "lebedev_weights",
    "LEBEDEV_ORDERS",
    "LEBEDEV_SIZES",
    "sample_octahedral",
    "sample_octahedral_hemisphere",
    "fibonacci_point",
    "fibonacci_points",
]


@dataclass(frozen=True, kw_only=True)
class Peer:
    """A registered peer sampler, so that a study can loop over `PEERS`.

    A record of keyword fields; the defaults are a uniform sampler of the sphere with independent rows.
    A peer built on a map of the square is a record over its warp, :meth:`Peer.over`, which takes the
    sampler (:meth:`symsphere.warps.Warp.sample`), density, uniformity and reference from the warp.

    Attributes
    ----------
    name : str
        Key in `PEERS`.
    domain : {'sphere', 'hemisphere'}
        The hemisphere is about (0, 0, 1).
    sampler : callable
        ``sampler(n, *, points, rng, dtype)``; use :meth:`sample`.
    pdf : callable
        Density with respect to solid angle, ``pdf(d)`` for ``d`` of shape
        (..., 3) returns shape (...).  For ``fibonacci`` (deterministic) it is
        the density of its randomly rotated version, 1/(4 pi), so that
        ``mean(f / pdf)`` is the usual equal-weight rule.
    is_random : bool
        Whether the output depends on ``rng`` (False only for ``fibonacci``).
    is_map : bool
        Whether the peer is built on a map of the unit square (``warp is not None``), so that
        :meth:`sample` accepts every ``points=`` (quasi-Monte Carlo too).
    independent_rows : bool
        Whether the rows of one call are independent samples (False for the
        rotated Fibonacci set and for ``arvo``, whose rows come in orbits of
        48): a chi-square test needs independent rows.
    multiple : int
        ``n`` must be a multiple of this (48 for ``arvo``).
    orbit_size : int or None
        Rows per group of dependent rows: 1 if the rows are independent, 48 for
        ``arvo`` (one random point of T0 and its 48 images), None if no subset of
        rows is independent (the rotated Fibonacci set shares one rotation).
        A chi-square test takes one row per orbit.
    uniform : bool
        Whether the density is uniform on the domain (False for ``cosine``).
    warp : symsphere.warps.Warp or None
        The map of the unit square the peer is built on (None if it is not a map); for ``arvo``
        the map onto T0 (``WARPS['arvo_triangle']``, orbit size 48), followed by the 48 images.
    reference : str
        Where the method comes from.
    rule_weights : callable or None
        For a quadrature rule with unequal weights (the Lebedev rules): ``rule_weights(n)``, the
        weights of the n rows of :meth:`sample`, adding up to the domain's area; the estimate is
        ``sum(w f)`` instead of ``mean(f / pdf)`` (:meth:`estimate`).  None for equal weights 1/pdf.
    sizes : callable or None
        ``sizes(n)``: the largest count at most n that :meth:`sample` accepts, if not every multiple
        of ``multiple`` is (the Lebedev rules); see :meth:`largest_n`.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import PEERS
    >>> peer = PEERS["octahedral"]
    >>> peer.domain, peer.is_map, peer.uniform
    ('sphere', True, True)
    >>> d = peer.sample(4096, rng=1, points="sobol")
    >>> estimate = np.mean(np.exp(d[:, 0]) / peer.pdf(d))      # the integral of exp(x): 2 pi (e - 1/e)
    >>> bool(abs(estimate - 2 * np.pi * (np.e - 1 / np.e)) < 1e-3)
    True

    A study loops over the registry; the cosine peer's density cos(theta)/pi integrates
    cos(theta) with zero variance:

    >>> [name for name, p in PEERS.items() if p.domain == "hemisphere"]
    ['classic_hemisphere', 'octahedral_hemisphere', 'cosine']
    >>> cosine = PEERS["cosine"]
    >>> d = cosine.sample(1000, rng=2)
    >>> bool(np.allclose(d[:, 2] / cosine.pdf(d), np.pi))
    True
    """

    name: str
    sampler: Sampler
    domain: Domain = "sphere"
    pdf: Callable[[npt.ArrayLike], FloatArray] = square_to_uniform_sphere_pdf
    is_random: bool = True
    independent_rows: bool = True
    multiple: int = 1
    orbit_size: int | None = 1
    uniform: bool = True
    warp: Warp | None = None
    reference: str = ""
    rule_weights: Callable[[int], Float64Array] | None = None
    sizes: Callable[[int], int] | None = None

    @classmethod
    def over(cls, warp: Warp, *, name: str) -> Peer:
        """The peer that samples *warp*'s domain (the sphere or the hemisphere) by its map: the warp's facts.

        Its sampler is :meth:`symsphere.warps.Warp.sample`, its density, uniformity and reference the warp's.

        Examples
        --------
        >>> from symsphere.peers import PEERS, Peer
        >>> from symsphere.warps import WARPS
        >>> Peer.over(WARPS["octahedral_sphere"], name="octahedral") == PEERS["octahedral"]
        True
        """
        if warp.domain not in DOMAINS:
            raise ValueError(f"'warp' must map onto one of {list(DOMAINS)}; got {warp.name!r} onto {warp.domain!r}")
        domain: Domain = "sphere" if warp.domain == "sphere" else "hemisphere"
        return cls(
            name=name,
            sampler=warp.sample,
            domain=domain,
            pdf=warp.pdf,
            uniform=warp.uniform,
            warp=warp,
            reference=warp.reference,
        )

    @property
    def is_map(self) -> bool:
        """Whether the peer is built on a map of the unit square (:attr:`warp`), so that :meth:`sample`
        accepts every ``points=`` (quasi-Monte Carlo too).

        Examples
        --------
        >>> from symsphere.peers import PEERS
        >>> PEERS["octahedral"].is_map, PEERS["gaussian"].is_map
        (True, False)
        """
        return self.warp is not None

    @property
    def forward(self) -> Callable[[npt.ArrayLike], FloatArray] | None:
        """The map ``(m, 2) -> (m, 3)`` onto the peer's domain (the warp's validating ``square_to_X``).

        None if the peer is no map, or (``arvo``) its map is onto T0 and then the 48 images.

        Examples
        --------
        >>> from symsphere.peers import PEERS
        >>> PEERS["octahedral"].forward.__name__, PEERS["arvo"].forward
        ('square_to_octahedral_sphere', None)
        """
        return self.warp.forward if self.warp is not None and self.warp.domain == self.domain else None

    @property
    def inverse(self) -> Callable[[npt.ArrayLike], FloatArray] | None:
        """The inverse of :attr:`forward` (the warp's ``X_to_square``), or None with it."""
        return self.warp.inverse if self.warp is not None and self.warp.domain == self.domain else None

    def sample(
        self, n: int, rng: RNGLike = None, dtype: DTypeLike = np.float64, points: PointsLike = "random"
    ) -> FloatArray:
        """Draw ``n`` directions; ``points`` other than 'random' needs ``is_map``.

        Examples
        --------
        >>> from symsphere.peers import PEERS
        >>> PEERS["octahedral"].sample(4, rng=0, points="sobol").shape
        (4, 3)
        """
        if not self.is_map and not (isinstance(points, str) and points == "random"):
            raise ValueError(
                f"'points' must be 'random' for the peer {self.name!r}, which is not a map of "
                f"the unit square; got {points!r}"
            )
        return self.sampler(n, points=points, rng=rng, dtype=dtype)

    @property
    def point_sets(self) -> tuple[str, ...]:
        """The named base point sets :meth:`sample` accepts (all of ``POINT_SETS`` for a map, else 'random').

        Examples
        --------
        >>> from symsphere.peers import PEERS
        >>> PEERS["gaussian"].point_sets
        ('random',)
        """
        return POINT_SETS if self.is_map else ("random",)

    def largest_n(self, n: int) -> int:
        """The largest count at most *n* that :meth:`sample` accepts (n rounded down to ``multiple``, or a rule's size).

        Examples
        --------
        >>> from symsphere.peers import PEERS
        >>> PEERS["arvo"].largest_n(1000), PEERS["lebedev"].largest_n(1000), PEERS["classic"].largest_n(1000)
        (960, 974, 1000)
        """
        n = check_count(n, "n")
        if self.sizes is not None:
            return self.sizes(n)
        if n < self.multiple:
            raise ValueError(f"'n' must be at least {self.multiple} for the peer {self.name!r}, got {n}")
        return n - n % self.multiple

    def estimate(
        self, f: Callable[[Float64Array], npt.ArrayLike], n: int, rng: RNGLike = None, points: PointsLike = "random"
    ) -> float:
        """One estimate of the integral of f over the domain from n evaluations.

        ``sum(w f(d))`` for a quadrature rule (:attr:`rule_weights`), else ``mean(f(d) / pdf(d))``,
        with the directions where the pdf is 0 or infinite (probability 0) counted as 0.

        Examples
        --------
        >>> import numpy as np
        >>> from symsphere.peers import PEERS
        >>> f = lambda d: np.exp(d[:, 0])                        # integral 2 pi (e - 1/e)
        >>> exact = 2 * np.pi * (np.e - 1 / np.e)
        >>> bool(abs(PEERS["lebedev"].estimate(f, 50) - exact) < 1e-6)
        True
        >>> bool(abs(PEERS["octahedral"].estimate(f, 4096, rng=0, points="sobol") - exact) < 1e-3)
        True
        """
        d = self.sample(n, rng=rng, points=points)
        values = np.asarray(f(np.asarray(d, dtype=np.float64)), dtype=np.float64)
        if self.rule_weights is not None:
            return float(np.sum(self.rule_weights(len(d)) * values))
        pdf = np.asarray(self.pdf(d), dtype=np.float64)
        ok = (pdf > 0) & np.isfinite(pdf)
        return float(np.sum(np.divide(values, pdf, out=np.zeros_like(values), where=ok)) / len(d))


def get_peer(name: str) -> Peer:
    """The registered :class:`Peer` called *name*; ValueError naming 'peer' otherwise.

    Examples
    --------
    >>> from symsphere.peers import get_peer
    >>> get_peer("cosine").domain
    'hemisphere'
    """
    if not isinstance(name, str) or name not in PEERS:
        raise ValueError(f"'name' must be one of {sorted(PEERS)}; got {short_repr(name)}")
    return PEERS[name]


# =============================================================================
# Samplers
# =============================================================================


def sample_classic(
    n: int, *, points: PointsLike = "random", rng: RNGLike = None, dtype: DTypeLike = np.float64
) -> FloatArray:
    """Uniform directions on the sphere by z = 1 - 2u, phi = 2 pi v.

    The map of :func:`symsphere.warps.square_to_uniform_sphere` (pbrt-v4 ``SampleUniformSphere``,
    Mitsuba 3 ``square_to_uniform_sphere``) applied to points of the square.

    Parameters
    ----------
    n : int
        Number of directions, positive.
    points : str in symsphere.POINT_SETS or scipy.stats.qmc.QMCEngine
        The points of the unit square: 'random', 'stratified', 'sobol', 'halton',
        'sobol_interlaced2', 'sobol_interlaced3' (``'stratified'`` needs ``n`` to be a square).
    rng : None, int, numpy.random.SeedSequence or numpy.random.Generator
        Seeds the points (or their scrambling).
    dtype : {numpy.float64, numpy.float32}
        Of the result; the map is computed in float64.

    Returns
    -------
    ndarray, shape (n, 3)
        Row i is the image of point i of the square.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import sample_classic
    >>> d = sample_classic(1000, rng=1)
    >>> d.shape, bool(np.allclose(np.linalg.norm(d, axis=1), 1))
    ((1000, 3), True)
    """
    return WARPS["uniform_sphere"].sample(n, points=points, rng=rng, dtype=dtype)


def sample_classic_hemisphere(
    n: int, *, points: PointsLike = "random", rng: RNGLike = None, dtype: DTypeLike = np.float64
) -> FloatArray:
    """Uniform directions on the hemisphere z >= 0 by z = u, phi = 2 pi v.

    Parameters and returns as in :func:`sample_classic`.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import sample_classic_hemisphere
    >>> bool(np.all(sample_classic_hemisphere(100, rng=2)[:, 2] >= 0))
    True
    """
    return WARPS["uniform_hemisphere"].sample(n, points=points, rng=rng, dtype=dtype)


def sample_gaussian(n: int, *, rng: RNGLike = None, dtype: DTypeLike = np.float64) -> FloatArray:
    """Uniform directions on the sphere: normalised standard normal vectors.

    As ``scipy.stats.uniform_direction`` does (Muller 1959, Marsaglia 1972):
    the standard normal distribution in R^3 is rotation invariant, so its
    direction is uniform.  A zero vector (probability 0, but possible in
    floating point) is drawn again.  Arguments and result as for :func:`sample_classic`, without
    ``points`` (random only).

    Examples
    --------
    >>> from symsphere.peers import sample_gaussian
    >>> sample_gaussian(5, rng=0, dtype="float32").dtype
    dtype('float32')
    """
    n = check_count(n, "n")
    dtype = check_dtype(dtype)
    rng = check_rng(rng)
    g = rng.standard_normal((n, 3))
    norm = np.linalg.norm(g, axis=1)
    while np.any(norm == 0):  # pragma: no cover - probability ~ 0
        zero = norm == 0
        g[zero] = rng.standard_normal((int(zero.sum()), 3))
        norm = np.linalg.norm(g, axis=1)
    directions: FloatArray = (g / norm[:, None]).astype(dtype)
    return directions


def sample_octahedral(
    n: int, *, points: PointsLike = "random", rng: RNGLike = None, dtype: DTypeLike = np.float64
) -> FloatArray:
    """Uniform directions on the sphere by Clarberg's octahedral map.

    The map of :func:`symsphere.warps.square_to_octahedral_sphere`; parameters and returns as
    in :func:`sample_classic`.

    Examples
    --------
    >>> from symsphere.peers import sample_octahedral
    >>> sample_octahedral(256, points="sobol", rng=3).shape
    (256, 3)
    """
    return WARPS["octahedral_sphere"].sample(n, points=points, rng=rng, dtype=dtype)


def sample_octahedral_hemisphere(
    n: int, *, points: PointsLike = "random", rng: RNGLike = None, dtype: DTypeLike = np.float64
) -> FloatArray:
    """Uniform directions on the hemisphere z >= 0 by Clarberg's hemisphere map.

    The map of :func:`symsphere.warps.square_to_octahedral_hemisphere`; parameters and returns
    as in :func:`sample_classic`.

    Examples
    --------
    >>> from symsphere.peers import sample_octahedral_hemisphere
    >>> d = sample_octahedral_hemisphere(4096, points="sobol", rng=4)
    >>> round(float(d[:, 2].mean()), 3)      # E[cos theta] = 1/2 for uniform directions
    0.5
    """
    return WARPS["octahedral_hemisphere"].sample(n, points=points, rng=rng, dtype=dtype)


def sample_cosine(
    n: int, *, points: PointsLike = "random", rng: RNGLike = None, dtype: DTypeLike = np.float64
) -> FloatArray:
    """Cosine-weighted directions on the hemisphere z >= 0 (pdf cos(theta)/pi).

    Shirley & Chiu's concentric map onto the disk, lifted to the hemisphere
    by Malley's method: :func:`symsphere.warps.square_to_cosine_hemisphere`.  Parameters and
    returns as in :func:`sample_classic`.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import sample_cosine
    >>> d = sample_cosine(20000, rng=5)
    >>> round(float(d[:, 2].mean()), 2)      # E[cos theta] = 2/3
    0.67
    """
    return WARPS["cosine_hemisphere"].sample(n, points=points, rng=rng, dtype=dtype)


def sample_arvo(
    n: int, *, points: PointsLike = "random", rng: RNGLike = None, dtype: DTypeLike = np.float64
) -> FloatArray:
    """Uniform directions on the sphere: Arvo's triangle sampling on T0, then symmetry.

    ``n / 48`` points of the unit square are mapped onto T0 by Arvo's
    algorithm for a general spherical triangle (:func:`symsphere.warps.square_to_arvo_triangle`:
    ``T0_VERTICES`` in the order A = (0, 0, 1), B = (1, 0, 1)/sqrt 2,
    C = (1, 1, 1)/sqrt 3), and each is replaced by its 48 images
    (:func:`symsphere.orbit`), as :func:`symsphere.sample_sphere` does.

    Parameters
    ----------
    n : int
        A positive multiple of 48.
    points, rng, dtype
        As in :func:`sample_classic` (``'stratified'`` needs ``n/48`` to be a square).

    Returns
    -------
    ndarray, shape (n, 3)
        Row ``48 i + k`` is ``orbit(base_i)[k]``.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.peers import sample_arvo
    >>> d = sample_arvo(96, rng=6)
    >>> d.shape, bool(np.allclose(d[:48].sum(axis=0), 0))
    ((96, 3), True)
    """
    n = check_count(n, "n", multiple=48)
    dtype = check_dtype(dtype)
    check_points(points)
    uv = unit_square_points(n // 48, points, rng, per_point=48)
    return orbit(WARPS["arvo_triangle"].forward(uv)).reshape(n, 3).astype(dtype)


# =============================================================================
# Registry
# =============================================================================


def _random_only(sampler: Callable[..., FloatArray], **options: Any) -> Sampler:
    """*sampler* (no ``points=``: it is no map of the square) with *options*, as a peer's sampler."""

    def wrapped(
        n: int, *, points: PointsLike = "random", rng: RNGLike = None, dtype: DTypeLike = np.float64
    ) -> FloatArray:
        return sampler(n, rng=rng, dtype=dtype, **options)

    return wrapped


def _point_set(name: str, sample: Callable[..., FloatArray], *, rotated: bool, reference: str, **fields: Any) -> Peer:
    """The peer of a point set of the sphere (Fibonacci, Lebedev), rotated at random or not: its rows
    are one set (under one rotation), so no subset of them is independent; unrotated it is fixed."""
    return Peer(
        name=name,
        sampler=_random_only(sample, randomize=rotated),
        is_random=rotated,
        independent_rows=False,
        orbit_size=None,
        reference=reference,
        **fields,
    )


def _build_peers() -> dict[str, Peer]:
    lebedev = "Lebedev & Laikov 1999; scipy.integrate.lebedev_rule (orders 3-131, 6-5810 points)"
    peers = [
        Peer.over(WARPS["uniform_sphere"], name="classic"),
        Peer.over(WARPS["uniform_hemisphere"], name="classic_hemisphere"),
        Peer(
            name="gaussian",
            sampler=_random_only(sample_gaussian),
            reference="Muller (1959), Marsaglia (1972); scipy.stats.uniform_direction",
        ),
        Peer.over(WARPS["octahedral_sphere"], name="octahedral"),
        Peer.over(WARPS["octahedral_hemisphere"], name="octahedral_hemisphere"),
        _point_set(
            "fibonacci",
            sample_fibonacci,
            rotated=False,
            reference="Keinert et al., Spherical Fibonacci Mapping, SIGGRAPH Asia 2015",
        ),
        _point_set(
            "fibonacci_rotated",
            sample_fibonacci,
            rotated=True,
            reference="Keinert et al. 2015, under a uniformly random rotation",
        ),
        Peer(  # a map onto T0, then the 48 images: a uniform density on the sphere
            name="arvo",
            sampler=sample_arvo,
            independent_rows=False,
            multiple=WARPS["arvo_triangle"].orbit_size,
            orbit_size=WARPS["arvo_triangle"].orbit_size,
            warp=WARPS["arvo_triangle"],
            reference=WARPS["arvo_triangle"].reference + "; on T0, then 48 images",
        ),
        _point_set(
            "lebedev",
            sample_lebedev,
            rotated=False,
            reference=lebedev,
            rule_weights=lebedev_weights,
            sizes=lebedev_size,
        ),
        _point_set(
            "lebedev_rotated",
            sample_lebedev,
            rotated=True,
            reference="Lebedev rules under uniformly random rotations; r x 5810 points: r rotations",
            rule_weights=functools.partial(lebedev_weights, randomize=True),
            sizes=functools.partial(lebedev_size, randomize=True),
        ),
        Peer.over(WARPS["cosine_hemisphere"], name="cosine"),
    ]
    return {peer.name: peer for peer in peers}


PEERS = _build_peers()
"""dict name -> :class:`Peer`, in the order of the module docstring's table."""
