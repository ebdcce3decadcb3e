"""What the convergence study measures, and how much: :class:`StudyConfig` and the named :data:`CONFIGS`."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..._typing import Domain
from ..._validation import short_repr
from ...integrands import INTEGRANDS
from ...peers import PEERS
from ...points import POINT_SETS
from ...symmetry import DOMAINS
from ...warps import METHODS

__all__ = [
    "BASELINE",
    "CONFIGS",
    "MAX_REPETITIONS",
    "FAMILY_SIGNIFICANCE",
    "ROUNDING_LEVEL",
    "StudyConfig",
    "WARP_MAPS",
    "domains",
    "resolve_config",
]

MAX_REPETITIONS = 2**20
"""Most repetitions per cell: a million integrations of every cell is already years of work at the
full configuration's size (32 repetitions take about 13 minutes on 2 cores)."""

ROUNDING_LEVEL = 1e-13
"""An RMSE at most this times max(1, |exact|) is rounding noise: flagged, and left out of slope fits."""

FAMILY_SIGNIFICANCE = 0.01
"""Chance that any chi-square test of the study rejects an exactly conforming sampler (Sidak)."""

BASELINE = {"sphere": ("classic", "random"), "hemisphere": ("classic_hemisphere", "random")}
"""The (peer, points) of each domain that the efficiency ratios are relative to."""

WARP_MAPS = ("equal_area", "paper1", "paper2", "arvo", "classic", "octahedral", "cosine")
"""The maps (of the scheme, or peers) that get a warp picture, when the configuration has them."""

_PEER_SPHERE = (
    ("classic", "random"),
    ("classic", "sobol"),
    ("gaussian", "random"),
    ("octahedral", "random"),
    ("octahedral", "sobol"),
    ("fibonacci_rotated", "random"),
    ("arvo", "random"),
)
_PEER_HEMISPHERE = (
    ("classic_hemisphere", "random"),
    ("classic_hemisphere", "sobol"),
    ("octahedral_hemisphere", "random"),
    ("octahedral_hemisphere", "sobol"),
    ("cosine", "random"),
    ("cosine", "sobol"),
)
_PEER_SPHERE_QMC = (
    ("classic", "random"),
    ("classic", "sobol"),
    ("octahedral", "sobol"),
    ("octahedral", "sobol_interlaced2"),
    ("fibonacci_rotated", "random"),
    ("lebedev", "random"),
    ("lebedev_rotated", "random"),
)
_CLASSIC_POINTS = ("random", "stratified", "sobol", "halton")
_FULL_INTEGRANDS = (
    "shifted_sh4_0",
    "shifted_cubic4",
    "shifted_sh2_1",
    "phong",
    "cap",
    "exp",
    "sphere_light",
    "quad_light",
)
_SMALL_INTEGRANDS = ("shifted_cubic4", "cap", "exp", "sphere_light")


@dataclass(frozen=True)
class StudyConfig:
    """What :func:`run_study` measures, and how much.

    Attributes
    ----------
    name : str
        Shown in the report.
    k_min, k_max : int
        n = 48 * 2**k evaluations for k = k_min ... k_max (0 <= k_min, k_max - k_min >= 2).
    repetitions : int
        Independent repetitions per (sampler, points, integrand, n), >= 2.
    integrands : tuple of str
        Names in :data:`symsphere.integrands.INTEGRANDS`.
    scheme_methods : tuple of str
        Maps of the symmetric scheme (:data:`symsphere.METHODS`).
    scheme_points : tuple of str
        Base point sets of the scheme (:data:`symsphere.POINT_SETS`); by default the four of the
        original study (random, stratified, sobol, halton), without the interlaced Sobol' sets.
    sphere_peers, hemisphere_peers : tuple of (str, str)
        ``(peer, points)`` pairs from :data:`symsphere.peers.PEERS` of that domain.
    discrepancy_k_max : int
        Cap discrepancy for N = 48 * 2**k, k = k_min ... discrepancy_k_max (N <= 48 * 2**9).
    discrepancy_repetitions : int
        Independent point sets per (sampler, points, N), >= 1.
    chi2_samples : int
        Independent directions per chi-square test (>= 1000).
    density_samples : int
        Directions per density map, a multiple of 48 (>= 4800).
    warp_samples : int
        Points of the unit square per warp histogram (>= 1000).

    Examples
    --------
    A configuration is validated when it is made; pass it to :func:`run_study` as ``config=``.

    >>> from symsphere.apps.study import CONFIGS, StudyConfig
    >>> config = StudyConfig(name="exp", k_max=8, repetitions=8, integrands=("exp",),
    ...                      scheme_points=("random", "sobol"))
    >>> config.ks                                   # n = 48 * 2**k
    (2, 3, 4, 5, 6, 7, 8)
    >>> config.replace(k_max=10, repetitions=16).ks[-1]
    10
    >>> CONFIGS["small"].replace(name="smaller", k_max=4).k_max
    4
    >>> config.replace(repetitions=1)
    Traceback (most recent call last):
        ...
    ValueError: 'repetitions' must be in [2, 1048576] (an RMSE needs repeated estimates; each is an integration of every cell), got 1
    """

    name: str = "custom"
    k_min: int = 2
    k_max: int = 14
    repetitions: int = 32
    integrands: tuple[str, ...] = _FULL_INTEGRANDS
    scheme_methods: tuple[str, ...] = METHODS
    scheme_points: tuple[str, ...] = _CLASSIC_POINTS
    sphere_peers: tuple[tuple[str, str], ...] = _PEER_SPHERE
    hemisphere_peers: tuple[tuple[str, str], ...] = _PEER_HEMISPHERE
    discrepancy_k_max: int = 8
    discrepancy_repetitions: int = 8
    chi2_samples: int = 2**16
    density_samples: int = 48 * 2**15
    warp_samples: int = 2**17

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"'name' must be a non-empty string, got {self.name!r}")
        for name in (
            "k_min",
            "k_max",
            "repetitions",
            "discrepancy_k_max",
            "discrepancy_repetitions",
            "chi2_samples",
            "density_samples",
            "warp_samples",
        ):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                raise ValueError(f"'{name}' must be an integer, got {value!r}")
            object.__setattr__(self, name, int(value))
        if not 0 <= self.k_min:
            raise ValueError(f"'k_min' must be >= 0, got {self.k_min}")
        if not self.k_max - self.k_min >= 2 or self.k_max > 20:
            raise ValueError(
                f"'k_max' must be at least k_min + 2 (three sizes for a slope) and at most 20, got {self.k_max}"
            )
        if not 2 <= self.repetitions <= MAX_REPETITIONS:
            raise ValueError(
                f"'repetitions' must be in [2, {MAX_REPETITIONS}] (an RMSE needs repeated estimates; each is an "
                f"integration of every cell), got {short_repr(self.repetitions)}"
            )
        if not self.k_min <= self.discrepancy_k_max <= 9:
            raise ValueError(
                f"'discrepancy_k_max' must be in [k_min, 9] (the O(N^2) sum; 48 * 2**9 = 24576), "
                f"got {self.discrepancy_k_max}"
            )
        if self.discrepancy_repetitions < 1:
            raise ValueError(f"'discrepancy_repetitions' must be >= 1, got {self.discrepancy_repetitions}")
        if self.chi2_samples < 1000:
            raise ValueError(f"'chi2_samples' must be >= 1000, got {self.chi2_samples}")
        if self.density_samples < 4800 or self.density_samples % 48:
            raise ValueError(f"'density_samples' must be a multiple of 48, >= 4800, got {self.density_samples}")
        if self.warp_samples < 1000:
            raise ValueError(f"'warp_samples' must be >= 1000, got {self.warp_samples}")

        def names(field_name: str, allowed: tuple[str, ...]) -> None:
            value = getattr(self, field_name)
            if isinstance(value, str) or not isinstance(value, (tuple, list)) or not value:
                raise ValueError(f"'{field_name}' must be a non-empty tuple of names, got {value!r}")
            for item in value:
                if item not in allowed:
                    raise ValueError(f"'{field_name}' has {item!r}, which is not one of {', '.join(sorted(allowed))}")
            if len(set(value)) != len(value):
                raise ValueError(f"'{field_name}' has duplicates: {value!r}")
            object.__setattr__(self, field_name, tuple(value))

        names("integrands", tuple(INTEGRANDS))
        names("scheme_methods", METHODS)
        names("scheme_points", POINT_SETS)

        def pairs(field_name: str, domain: str) -> None:
            value = getattr(self, field_name)
            if isinstance(value, str) or not isinstance(value, (tuple, list)):
                raise ValueError(f"'{field_name}' must be a tuple of (peer, points) pairs, got {value!r}")
            out: list[tuple[str, str]] = []
            for item in value:
                if not (isinstance(item, (tuple, list)) and len(item) == 2):
                    raise ValueError(f"'{field_name}' must hold (peer, points) pairs, got {item!r}")
                peer, points = item
                if peer not in PEERS or PEERS[peer].domain != domain:
                    allowed = ", ".join(p.name for p in PEERS.values() if p.domain == domain)
                    raise ValueError(f"'{field_name}' has peer {peer!r}; peers of the {domain}: {allowed}")
                point_sets = PEERS[peer].point_sets
                if points not in point_sets:
                    raise ValueError(
                        f"'{field_name}' has points {points!r} for {peer!r}; "
                        + ("use 'random'" if point_sets == ("random",) else f"use one of {', '.join(point_sets)}")
                    )
                out.append((peer, points))
            if len(set(out)) != len(out):
                raise ValueError(f"'{field_name}' has duplicates: {value!r}")
            object.__setattr__(self, field_name, tuple(out))

        pairs("sphere_peers", "sphere")
        pairs("hemisphere_peers", "hemisphere")
        present = {INTEGRANDS[g].domain for g in self.integrands}
        for domain in present:
            baseline = BASELINE[domain]
            peers = self.sphere_peers if domain == "sphere" else self.hemisphere_peers
            if baseline not in peers:
                raise ValueError(
                    f"'{domain}_peers' must include the baseline {baseline} of the efficiency ratios, "
                    f"since the integrands include the {domain}"
                )

    @property
    def ks(self) -> tuple[int, ...]:
        """The size exponents k_min ... k_max of the convergence runs (n = 48 * 2**k)."""
        return tuple(range(self.k_min, self.k_max + 1))

    @property
    def discrepancy_ks(self) -> tuple[int, ...]:
        """The size exponents k_min ... discrepancy_k_max of the discrepancy runs."""
        return tuple(range(self.k_min, self.discrepancy_k_max + 1))

    def replace(self, **changes: Any) -> StudyConfig:
        """A copy with *changes* (validated again).

        Examples
        --------
        >>> from symsphere.apps.study import CONFIGS
        >>> CONFIGS["small"].replace(repetitions=8).repetitions
        8
        """
        return dataclasses.replace(self, **changes)


CONFIGS = {
    "full": StudyConfig(name="full"),
    "small": StudyConfig(
        name="small",
        k_min=2,
        k_max=6,
        repetitions=4,
        integrands=_SMALL_INTEGRANDS,
        discrepancy_k_max=5,
        discrepancy_repetitions=2,
        chi2_samples=2**12,
        density_samples=48 * 2**10,
        warp_samples=2**13,
    ),
    "qmc": StudyConfig(
        name="qmc",
        k_min=2,
        k_max=14,
        repetitions=32,
        integrands=_FULL_INTEGRANDS[:6],
        scheme_methods=("equal_area",),
        scheme_points=("random", "sobol", "sobol_interlaced2", "sobol_interlaced3"),
        sphere_peers=_PEER_SPHERE_QMC,
        discrepancy_k_max=8,
        discrepancy_repetitions=4,
        chi2_samples=2**14,
        density_samples=48 * 2**12,
        warp_samples=2**13,
    ),
}
"""The named configurations: ``'full'`` (the documented study), ``'small'`` (CI) and ``'qmc'`` (higher-order
QMC base points against the strongest peers, Lebedev and the rotated Fibonacci set, on the sphere)."""


def resolve_config(config: str | StudyConfig) -> StudyConfig:
    """*config* itself if a :class:`StudyConfig`, else the named one of :data:`CONFIGS`; ValueError otherwise."""
    if isinstance(config, StudyConfig):
        return config
    if isinstance(config, str) and config in CONFIGS:
        return CONFIGS[config]
    raise ValueError(f"'config' must be one of {', '.join(repr(c) for c in CONFIGS)} or a StudyConfig, got {config!r}")


def domains(config: StudyConfig) -> list[Domain]:
    """The domains of *config*'s integrands: ``'sphere'`` before ``'hemisphere'``."""
    present = {INTEGRANDS[g].domain for g in config.integrands}
    return [d for d in DOMAINS if d in present]
