"""The study's samplers: the symmetric scheme (one per map and point set) and the peers, behind one interface.

A :class:`Sampler` is a ``strategy`` x ``points`` x ``method``, the words of the renderers
(:mod:`symsphere._strategies`): the strategy ``symmetric`` (the scheme, with a map ``method``) or a peer
of :data:`symsphere.peers.PEERS` by name.  It draws directions, evaluates its density and gives one
estimate of an integral; the facts the study needs about it (rows per orbit, the multiple n must be,
whether it is uniform) are read from :class:`symsphere.peers.Peer` fields for a peer and from the map
and the domain for the scheme.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import cast

import numpy as np
import numpy.typing as npt

from ... import hemisphere_pdf, integrate, sample_hemisphere, sample_sphere, sphere_pdf
from ..._compiled_peers import COMPILED_PEERS, compiled_sample
from ..._strategies import SAMPLING_STRATEGIES
from ..._typing import Domain, FloatArray, MapMethod, PointSet, RNGLike
from ...peers import PEERS, Peer
from ...symmetry import orbit_size
from ...warps import triangle_warp
from .config import StudyConfig, domains

__all__ = ["Sampler", "all_samplers", "samplers", "weighted"]

SCHEME_PREFIX = "symsphere_"
"""Names of the scheme's samplers in the report: ``symsphere_<map>``."""

SCHEME = SAMPLING_STRATEGIES["symmetric"].name
"""The scheme's strategy: ``'symmetric'`` (the registry's word; the peers' strategies are their names)."""


@dataclass(frozen=True)
class Sampler:
    """One sampler of the study: a strategy (the symmetric scheme with a map, or a peer) with its base points.

    Build it with :meth:`scheme` or :meth:`of_peer`.

    Attributes
    ----------
    strategy : str
        ``'symmetric'`` for the scheme, else the peer's name.
    points : str
        The base point set (:data:`symsphere.POINT_SETS`).
    domain : {'sphere', 'hemisphere'}
    method : str or None
        The scheme's map; None for a peer.
    peer : symsphere.peers.Peer or None
        None for the scheme.
    """

    strategy: str
    points: PointSet
    domain: Domain
    method: MapMethod | None = None
    peer: Peer | None = None

    @classmethod
    def scheme(cls, method: MapMethod, points: PointSet, domain: Domain) -> Sampler:
        """The symmetric scheme with the map *method* and base *points* on *domain*."""
        return cls(SCHEME, points, domain, method=method)

    @classmethod
    def of_peer(cls, peer: Peer, points: PointSet) -> Sampler:
        """The peer sampler *peer* with base *points*."""
        return cls(peer.name, points, peer.domain, peer=peer)

    @property
    def name(self) -> str:
        """The report's name: ``'symsphere_<method>'`` for the scheme, else the peer's name."""
        return f"{SCHEME_PREFIX}{self._method}" if self.is_scheme else self.strategy

    @property
    def _peer(self) -> Peer:
        """The peer of a peer sampler (the scheme has none)."""
        assert self.peer is not None, f"{self.name} is the scheme, not a peer"
        return self.peer

    @property
    def _method(self) -> MapMethod:
        """The map of the scheme (a peer has none)."""
        assert self.method is not None, f"{self.name} is a peer, not the scheme"
        return self.method

    @property
    def label(self) -> str:
        """``name/points``."""
        return f"{self.name}/{self.points}"

    @property
    def is_scheme(self) -> bool:
        """Whether this is the symmetric scheme (not a peer)."""
        return self.method is not None

    @property
    def orbit_size(self) -> int | None:
        """Rows per orbit (1 if the rows are independent; None if they are never independent)."""
        return orbit_size(self.domain) if self.is_scheme else self._peer.orbit_size

    @property
    def multiple(self) -> int:
        """n must be a multiple of this."""
        return orbit_size(self.domain) if self.is_scheme else self._peer.multiple

    @property
    def uniform(self) -> bool:
        """Whether the density is uniform on the domain."""
        return triangle_warp(self._method).uniform if self.is_scheme else self._peer.uniform

    @property
    def is_rule(self) -> bool:
        """Whether this is a quadrature rule with unequal weights (the Lebedev peers)."""
        return not self.is_scheme and self._peer.rule_weights is not None

    @property
    def is_random(self) -> bool:
        """Whether the estimate is random (False only for the deterministic peers: Fibonacci, Lebedev)."""
        return self.is_scheme or self._peer.is_random

    def rule_weights(self, n: int) -> FloatArray:
        """The weights of a rule's n directions, normalised to add up to 1 (for the discrepancy)."""
        weights = self._peer.rule_weights
        assert weights is not None, f"{self.name} is not a rule"
        w = weights(n)
        normalised: FloatArray = w / w.sum()
        return normalised

    def n_for(self, k: int) -> int:
        """Evaluations actually used for the size 48 * 2**k (the stratified scheme rounds; a Lebedev rule
        takes its largest size at most n)."""
        n = 48 * 2**k
        if self.is_scheme and self.points == "stratified":
            count = orbit_size(self.domain)
            side = max(1, round(math.sqrt(n // count)))
            return count * side * side
        return n if self.is_scheme else self._peer.largest_n(n)

    def estimate(self, f: Callable[[FloatArray], FloatArray], n: int, rng: RNGLike) -> float:
        """One estimate of the integral of f from n evaluations.

        The scheme: :func:`symsphere.integrate` with ``replicates=1`` (None for random points); a peer:
        :meth:`symsphere.peers.Peer.estimate`, ``mean(f / pdf)`` over its n directions (a rule:
        ``sum(w f)``), the directions from a compiled kernel (:mod:`symsphere._compiled_peers`) for the peers of
        ``COMPILED_PEERS``.
        """
        if self.is_scheme:
            replicates = None if self.points == "random" else 1
            result = integrate(
                f, domain=self.domain, n=n, method=self._method, points=self.points, rng=rng, replicates=replicates
            )
            return float(result.integral)
        peer = self._peer
        if peer.name not in COMPILED_PEERS:
            return peer.estimate(f, n, rng=rng, points=self.points)
        d = compiled_sample(peer, n, rng, self.points)
        if peer.rule_weights is not None:  # self.is_rule
            return float(np.sum(peer.rule_weights(n) * f(d)))
        # These peers are uniform on the sphere (tested in tests/test_compiled_peers.py): weight 4 pi, as
        # the scheme's estimator, which evaluates no pdf for a uniform map either.
        return float(4 * np.pi * np.mean(f(d)))

    def sample(self, n: int, rng: RNGLike) -> FloatArray:
        """n directions (for the scheme: n/48 or n/24 whole orbits)."""
        if self.is_scheme:
            sample = sample_sphere if self.domain == "sphere" else sample_hemisphere
            return sample(n, method=self._method, points=self.points, rng=rng)
        if self._peer.name in COMPILED_PEERS:
            return compiled_sample(self._peer, n, rng, self.points)
        return self._peer.sample(n, rng=rng, points=self.points)

    @property
    def is_compiled(self) -> bool:
        """Whether the directions come from a compiled kernel (the scheme, and the peers of COMPILED_PEERS)."""
        return self.is_scheme or self._peer.name in COMPILED_PEERS

    def pdf(self, d: npt.ArrayLike) -> FloatArray:
        """The density of the directions *d* with respect to solid angle."""
        if self.is_scheme:
            return sphere_pdf(d, self._method) if self.domain == "sphere" else hemisphere_pdf(d, self._method)
        return self._peer.pdf(d)


def weighted(values: npt.ArrayLike, pdf: npt.ArrayLike) -> FloatArray:
    """values / pdf, and 0 where the pdf is 0 or infinite.

    Samplers put directions there with probability 0 (the paper maps' density is infinite on the
    axes, where the weight 1/pdf tends to 0; the cosine density vanishes on the horizon).

    Examples
    --------
    >>> from symsphere.apps.study.samplers import weighted
    >>> weighted([1.0, 1.0, 1.0], [2.0, 0.0, float("inf")]).tolist()
    [0.5, 0.0, 0.0]
    """
    values = np.asarray(values, dtype=np.float64)
    pdf = np.asarray(pdf, dtype=np.float64)
    ok = (pdf > 0) & np.isfinite(pdf)
    out = np.zeros(np.broadcast_shapes(values.shape, pdf.shape))
    np.divide(values, pdf, out=out, where=ok)
    return out


def samplers(config: StudyConfig, domain: Domain) -> list[Sampler]:
    """The samplers of *config* on *domain*: the scheme (every map x point set), then the peers."""
    # StudyConfig checked its names against METHODS and POINT_SETS
    scheme = [
        Sampler.scheme(cast(MapMethod, method), cast(PointSet, points), domain)
        for method in config.scheme_methods
        for points in config.scheme_points
    ]
    peers = config.sphere_peers if domain == "sphere" else config.hemisphere_peers
    return scheme + [Sampler.of_peer(PEERS[peer], cast(PointSet, points)) for peer, points in peers]


def all_samplers(config: StudyConfig) -> list[Sampler]:
    """The samplers of every domain of *config*."""
    return [s for domain in domains(config) for s in samplers(config, domain)]
