"""The convergence study: every sampler, point set and integrand, written up as a report.

``run_study`` measures, for every sampler x point set x integrand of a
:class:`StudyConfig`:

- the root-mean-square error of the estimate over independent repetitions
  for n = 48 * 2**k evaluations, k = ``k_min ... k_max``;
- the convergence slope, by least squares of log RMSE against log n, with
  its standard error;
- the efficiency 1 / (MSE * seconds) at the largest n, seconds being the
  median wall time of one estimate (sampling and evaluation);

and, for the point sets and samplers themselves,

- the spherical-cap L2 discrepancy of every point set on the sphere, exact,
  through Stolarsky's invariance principle (:func:`cap_discrepancy`), both
  with equal weights and with the estimator's weights 1 / (N 4 pi pdf);
- chi-square p-values of every random sampler against the uniform density
  and against its own density (:func:`symsphere.stats.chi2_test`, one
  direction per orbit for the orbit samplers);
- density maps (Mollweide) and warp pictures of the maps.

The results go to a folder: ``report.md`` (and ``report.html``), the CSV
tables ``convergence.csv``, ``summary.csv``, ``discrepancy.csv``,
``chi2.csv`` and PNG figures.  The folder appears only when complete
(:func:`symsphere._io.atomic_directory`).

Estimators
----------
The symmetric scheme (sampler ``symsphere_<method>``) is estimated by
:func:`symsphere.integrate`, its own estimator (the mean of f over each orbit,
weighted by 1 / pdf of the scheme), with ``replicates=1``: one repetition is
one call with a fresh seed (fresh random points, jitter or scrambling).  A
peer sampler gives ``mean(f / pdf)`` over its n directions.

Sizes
-----
n = 48 * 2**k for every sampler, except the scheme with stratified points,
which needs a square number of base points (n/48 on the sphere, n/24 on the
hemisphere): there n is the nearest such size, ``48 * round(sqrt(2**k))**2``
(for odd k; even k are exact), and the tables give the n actually used.
For Sobol' points of the peers, n = 3 * 2**(k + 4) is not a power of 2: the
first n points of the sequence are the union of two scrambled (0, m, 2)-nets
(of 2**(k+5) and 2**(k+4) points), so the balance holds piecewise and the
warning scipy gives is silenced.

Command line: ``symsphere study --out study-report`` (the full study) or
``symsphere study --config small`` (the one CI runs); see
:func:`add_study_parser`.
"""

from __future__ import annotations

import dataclasses
import html
import math
import os
import re
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numba
import numpy as np

from ._io import atomic_directory
from .maps import METHODS
from .points import POINT_SETS

__all__ = [
    "StudyConfig",
    "run_study",
    "add_study_parser",
    "run_study_command",
    "cap_discrepancy",
    "cap_discrepancy_squared",
    "rmse",
    "fit_slope",
    "SlopeFit",
    "markdown_to_html",
    "study_files",
    "CONFIGS",
]

ROUNDING_LEVEL = 1e-13
"""An RMSE at most this times max(1, |exact|) is rounding noise: flagged, and left out of slope fits."""

LOG_FLOOR = 1e-300
"""log(0) guard of the slope fit."""

FAMILY_SIGNIFICANCE = 0.01
"""Chance that any chi-square test of the study rejects an exactly conforming sampler (Sidak)."""

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
_BASELINE = {"sphere": ("classic", "random"), "hemisphere": ("classic_hemisphere", "random")}

# The maps that get a warp picture: name -> (domain of the picture, how to build it).
_WARP_MAPS = ("equal_area", "paper1", "paper2", "arvo", "classic", "octahedral", "cosine")


# =============================================================================
# Configuration
# =============================================================================


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
        Base point sets of the scheme (:data:`symsphere.POINT_SETS`).
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
    """

    name: str = "custom"
    k_min: int = 2
    k_max: int = 14
    repetitions: int = 32
    integrands: tuple = _FULL_INTEGRANDS
    scheme_methods: tuple = METHODS
    scheme_points: tuple = POINT_SETS
    sphere_peers: tuple = _PEER_SPHERE
    hemisphere_peers: tuple = _PEER_HEMISPHERE
    discrepancy_k_max: int = 8
    discrepancy_repetitions: int = 8
    chi2_samples: int = 2**16
    density_samples: int = 48 * 2**15
    warp_samples: int = 2**17

    def __post_init__(self):
        from .integrands import INTEGRANDS
        from .peers import PEERS

        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"'name' must be a non-empty string, got {self.name!r}")
        for name in ("k_min", "k_max", "repetitions", "discrepancy_k_max", "discrepancy_repetitions",
                     "chi2_samples", "density_samples", "warp_samples"):
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
        if self.repetitions < 2:
            raise ValueError(f"'repetitions' must be >= 2 (an RMSE needs repeated estimates), got {self.repetitions}")
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

        def names(field_name, allowed):
            value = getattr(self, field_name)
            if isinstance(value, str) or not isinstance(value, (tuple, list)) or not value:
                raise ValueError(f"'{field_name}' must be a non-empty tuple of names, got {value!r}")
            for item in value:
                if item not in allowed:
                    raise ValueError(
                        f"'{field_name}' has {item!r}, which is not one of {', '.join(sorted(allowed))}"
                    )
            if len(set(value)) != len(value):
                raise ValueError(f"'{field_name}' has duplicates: {value!r}")
            object.__setattr__(self, field_name, tuple(value))

        names("integrands", tuple(INTEGRANDS))
        names("scheme_methods", METHODS)
        names("scheme_points", POINT_SETS)

        def pairs(field_name, domain):
            value = getattr(self, field_name)
            if isinstance(value, str) or not isinstance(value, (tuple, list)):
                raise ValueError(f"'{field_name}' must be a tuple of (peer, points) pairs, got {value!r}")
            out = []
            for item in value:
                if not (isinstance(item, (tuple, list)) and len(item) == 2):
                    raise ValueError(f"'{field_name}' must hold (peer, points) pairs, got {item!r}")
                peer, points = item
                if peer not in PEERS or PEERS[peer].domain != domain:
                    allowed = ", ".join(p.name for p in PEERS.values() if p.domain == domain)
                    raise ValueError(f"'{field_name}' has peer {peer!r}; peers of the {domain}: {allowed}")
                if points not in POINT_SETS or (points != "random" and not PEERS[peer].is_map):
                    raise ValueError(
                        f"'{field_name}' has points {points!r} for {peer!r}; "
                        + ("use 'random'" if not PEERS[peer].is_map else f"use one of {', '.join(POINT_SETS)}")
                    )
                out.append((peer, points))
            if len(set(out)) != len(out):
                raise ValueError(f"'{field_name}' has duplicates: {value!r}")
            object.__setattr__(self, field_name, tuple(out))

        pairs("sphere_peers", "sphere")
        pairs("hemisphere_peers", "hemisphere")
        domains = {INTEGRANDS[g].domain for g in self.integrands}
        for domain in domains:
            baseline = _BASELINE[domain]
            peers = self.sphere_peers if domain == "sphere" else self.hemisphere_peers
            if baseline not in peers:
                raise ValueError(
                    f"'{domain}_peers' must include the baseline {baseline} of the efficiency ratios, "
                    f"since the integrands include the {domain}"
                )

    @property
    def ks(self):
        return tuple(range(self.k_min, self.k_max + 1))

    @property
    def discrepancy_ks(self):
        return tuple(range(self.k_min, self.discrepancy_k_max + 1))

    def replace(self, **changes):
        """A copy with *changes* (validated again)."""
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
}
"""The named configurations: ``'full'`` (the documented study) and ``'small'`` (CI)."""


def _resolve_config(config):
    if isinstance(config, StudyConfig):
        return config
    if isinstance(config, str) and config in CONFIGS:
        return CONFIGS[config]
    raise ValueError(f"'config' must be one of {', '.join(repr(c) for c in CONFIGS)} or a StudyConfig, got {config!r}")


# =============================================================================
# Samplers
# =============================================================================


@dataclass(frozen=True)
class _Sampler:
    name: str  # 'symsphere_<method>' or the peer's name
    points: str
    domain: str
    method: str | None = None  # the scheme's map
    peer: str | None = None

    @property
    def label(self):
        return f"{self.name}/{self.points}"

    @property
    def is_scheme(self):
        return self.method is not None

    def n_for(self, k):
        """Evaluations actually used for the size 48 * 2**k (the stratified scheme rounds)."""
        n = 48 * 2**k
        if self.is_scheme and self.points == "stratified":
            count = 48 if self.domain == "sphere" else 24
            side = max(1, round(math.sqrt(n // count)))
            return count * side * side
        return n

    def estimate(self, f, n, rng):
        """One estimate of the integral of f from n evaluations."""
        if self.is_scheme:
            from .integrate import integrate

            replicates = None if self.points == "random" else 1
            result = integrate(f, domain=self.domain, n=n, method=self.method, points=self.points, rng=rng,
                               replicates=replicates)
            return float(result.integral)
        from .peers import PEERS

        peer = PEERS[self.peer]
        d = peer.sample(n, rng=rng, points=self.points)
        return float(np.mean(_weighted(f(d), peer.pdf(d))))

    def sample(self, n, rng):
        """n directions (for the scheme: n/48 or n/24 whole orbits)."""
        from .peers import PEERS
        from .sampling import sample_hemisphere, sample_sphere

        if self.is_scheme:
            sample = sample_sphere if self.domain == "sphere" else sample_hemisphere
            return sample(n, method=self.method, points=self.points, rng=rng)
        return PEERS[self.peer].sample(n, rng=rng, points=self.points)

    def pdf(self, d):
        from .peers import PEERS
        from .sampling import hemisphere_pdf, sphere_pdf

        if self.is_scheme:
            return sphere_pdf(d, self.method) if self.domain == "sphere" else hemisphere_pdf(d, self.method)
        return PEERS[self.peer].pdf(d)

    @property
    def orbit_size(self):
        """Rows per orbit (1 if the rows are independent; None if they are never independent)."""
        if self.is_scheme:
            return 48 if self.domain == "sphere" else 24
        if self.peer == "arvo":
            return 48
        if self.peer.startswith("fibonacci"):
            return None
        return 1

    @property
    def uniform(self):
        from .maps import get_map

        if self.is_scheme:
            return get_map(self.method).uniform
        return self.peer != "cosine"


def _weighted(values, pdf):
    """values / pdf, and 0 where the pdf is 0 or infinite.

    Samplers put directions there with probability 0 (the paper maps' density is infinite on the
    axes, where the weight 1/pdf tends to 0; the cosine density vanishes on the horizon).
    """
    values = np.asarray(values, dtype=np.float64)
    pdf = np.asarray(pdf, dtype=np.float64)
    ok = (pdf > 0) & np.isfinite(pdf)
    out = np.zeros(np.broadcast_shapes(values.shape, pdf.shape))
    np.divide(values, pdf, out=out, where=ok)
    return out


def _samplers(config, domain):
    scheme = [
        _Sampler(f"symsphere_{method}", points, domain, method=method)
        for method in config.scheme_methods
        for points in config.scheme_points
    ]
    peers = config.sphere_peers if domain == "sphere" else config.hemisphere_peers
    return scheme + [_Sampler(peer, points, domain, peer=peer) for peer, points in peers]


def _all_samplers(config):
    domains = _domains(config)
    return [s for domain in domains for s in _samplers(config, domain)]


def _domains(config):
    from .integrands import INTEGRANDS

    present = {INTEGRANDS[g].domain for g in config.integrands}
    return [d for d in ("sphere", "hemisphere") if d in present]


# =============================================================================
# Statistics: RMSE, slope, discrepancy
# =============================================================================


def rmse(estimates, exact):
    """Root-mean-square error of *estimates* (last axis: repetitions) about *exact*.

    Examples
    --------
    >>> from symsphere.study import rmse
    >>> float(rmse([1.0, 3.0], 2.0))
    1.0
    """
    estimates = np.asarray(estimates, dtype=np.float64)
    if estimates.shape[-1] < 1:
        raise ValueError("'estimates' must hold at least one repetition")
    return np.sqrt(np.mean((estimates - exact) ** 2, axis=-1))


@dataclass(frozen=True)
class SlopeFit:
    """Least-squares fit log(rmse) = intercept + slope * log(n).

    ``standard_error`` is the usual OLS standard error of the slope (NaN with
    fewer than three points); ``points`` is the number of points used.
    """

    slope: float
    standard_error: float
    intercept: float
    points: int


def fit_slope(n, values, *, floor=LOG_FLOOR):
    """Fit the convergence slope of *values* (e.g. RMSE) against *n* on log-log axes.

    Values below *floor* (an exact zero) are raised to it, so the log is finite.

    Examples
    --------
    >>> from symsphere.study import fit_slope
    >>> fit = fit_slope([100, 400, 1600], [0.1, 0.05, 0.025])
    >>> round(fit.slope, 12), round(fit.standard_error, 12)
    (-0.5, 0.0)
    """
    x = np.log(np.asarray(n, dtype=np.float64))
    v = np.asarray(values, dtype=np.float64)
    if x.shape != v.shape or x.ndim != 1:
        raise ValueError(f"'n' and 'values' must be 1-D of the same length, got {x.shape} and {v.shape}")
    if len(x) < 2:
        return SlopeFit(math.nan, math.nan, math.nan, len(x))
    y = np.log(np.maximum(v, floor))
    xm, ym = x.mean(), y.mean()
    sxx = float(np.sum((x - xm) ** 2))
    if sxx == 0:
        raise ValueError("'n' must hold at least two distinct values")
    slope = float(np.sum((x - xm) * (y - ym)) / sxx)
    intercept = float(ym - slope * xm)
    if len(x) > 2:
        residual = y - (intercept + slope * x)
        se = math.sqrt(float(np.sum(residual**2)) / (len(x) - 2) / sxx)
    else:
        se = math.nan
    return SlopeFit(slope, se, intercept, len(x))


def cap_discrepancy_squared(points, weights=None):
    """Squared spherical-cap L2 discrepancy of points on S², exact, by Stolarsky's invariance principle.

    With the caps C(x, t) = {y : x.y >= t} and sigma the normalised surface
    measure (sigma(C(x, t)) = (1 - t)/2),

        D^2 = integral over t in [-1, 1] and x in S^2 of
              (sum_i w_i 1[x_i in C(x, t)] - sigma(C(x, t)))^2 dsigma(x) dt.

    Stolarsky's invariance principle (Stolarsky 1973; Brauchart & Dick, Proc.
    AMS 141 (2013) 2085-2096, with C_2 = 1/4 on S^2) turns it into a sum of
    distances: the kernel integral of the product of two cap indicators is
    1 - |y - z|/4, so

        D^2 = (sum w)^2 - (1/4) sum_{i,j} w_i w_j |x_i - x_j| - (4/3) sum w + 2/3,

    which for equal weights w_i = 1/N is the classical
    D^2 = 1/3 - (1/(4 N^2)) sum_{i,j} |x_i - x_j|.  For N independent uniform
    points E D^2 = 1/(3N) (since E|x - y| = 4/3).  D is also the worst-case
    error of the rule sum_i w_i f(x_i) for the mean of f over the sphere in
    the Sobolev space H^(3/2)(S^2) with reproducing kernel 1 - |x - y|/4.

    Parameters
    ----------
    points : array_like, shape (N, 3)
        Unit vectors (normalised here).
    weights : array_like, shape (N,), optional
        Default 1/N each.  For an importance-sampling rule use 1/(N 4 pi pdf(x_i)).

    Returns
    -------
    float
        D^2 (exact up to rounding; the O(N^2) sum runs in parallel, rows paired
        for balance, without storing the distance matrix).

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.study import cap_discrepancy_squared
    >>> octahedron = np.vstack([np.eye(3), -np.eye(3)])
    >>> round(cap_discrepancy_squared(octahedron), 12)      # 1/3 - (24 sqrt 2 + 6 * 2)/(4 * 36)
    0.014297739604
    """
    x = np.asarray(points, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != 3 or len(x) == 0:
        raise ValueError(f"'points' must have shape (N, 3) with N >= 1, got {x.shape}")
    norm = np.linalg.norm(x, axis=1)
    if not np.all(np.isfinite(x)) or np.any(norm == 0):
        raise ValueError("'points' must be finite and non-zero")
    x = np.ascontiguousarray(x / norm[:, None])
    n = len(x)
    if weights is None:
        w = np.full(n, 1.0 / n)
    else:
        w = np.ascontiguousarray(np.asarray(weights, dtype=np.float64))
        if w.shape != (n,) or not np.all(np.isfinite(w)):
            raise ValueError(f"'weights' must be finite with shape ({n},), got {w.shape}")
    total = float(np.sum(w))
    pair_sum = _weighted_distance_sum(x, w)
    return total * total - 0.25 * pair_sum - (4.0 / 3.0) * total + 2.0 / 3.0


def cap_discrepancy(points, weights=None):
    """Spherical-cap L2 discrepancy: the square root of :func:`cap_discrepancy_squared` (clipped at 0).

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.study import cap_discrepancy
    >>> round(cap_discrepancy(np.vstack([np.eye(3), -np.eye(3)])), 6)
    0.119573
    """
    return math.sqrt(max(cap_discrepancy_squared(points, weights), 0.0))


# =============================================================================
# The study
# =============================================================================


@dataclass
class _Results:
    config: StudyConfig
    seed: int
    convergence: list = field(default_factory=list)
    summary: list = field(default_factory=list)
    discrepancy: list = field(default_factory=list)
    discrepancy_fits: list = field(default_factory=list)
    chi2: list = field(default_factory=list)
    stage_seconds: dict = field(default_factory=dict)
    warp_chi2: dict = field(default_factory=dict)


def study_files(config="full"):
    """The names of the files :func:`run_study` writes for *config*, in a stable order."""
    config = _resolve_config(config)
    files = ["report.md", "report.html", "convergence.csv", "summary.csv", "discrepancy.csv", "chi2.csv"]
    files += [f"convergence_{g}.png" for g in config.integrands]
    if "sphere" in _domains(config):
        files.append("discrepancy.png")
    files += [f"density_{s.name}.png" for s in _density_samplers(config)]
    files += [f"warp_{m}.png" for m in _warp_maps(config)]
    return files


def _replaceable():
    """Every name a study of any configuration can write: an earlier study's folder may be replaced."""
    from .integrands import INTEGRANDS
    from .peers import PEERS

    names = {"report.md", "report.html", "convergence.csv", "summary.csv", "discrepancy.csv", "chi2.csv",
             "discrepancy.png"}
    names |= {f"convergence_{g}.png" for g in INTEGRANDS}
    names |= {f"density_symsphere_{m}.png" for m in METHODS} | {f"density_{p}.png" for p in PEERS}
    names |= {f"warp_{m}.png" for m in _WARP_MAPS}
    return names


def run_study(out_dir="study-report", *, config="full", seed=0, progress=True) -> Path:
    """Run the convergence study and write its folder (report, CSV tables, figures).

    Parameters
    ----------
    out_dir : str or os.PathLike
        The folder to write.  It is built next to its final place and renamed
        into it only when complete.  An existing folder is replaced only if it
        is empty or holds nothing but files an earlier study writes;
        otherwise ``FileExistsError`` is raised before any work.
    config : {'full', 'small'} or StudyConfig
        ``'full'`` is the documented study (about 13 minutes on 2 cores);
        ``'small'`` is the quick end-to-end run of CI (well under a minute).
    seed : int
        Non-negative; seeds every random choice (same seed, same numbers;
        the timings vary).
    progress : bool
        Show a progress bar (tqdm, on stderr, only if it is a terminal).

    Returns
    -------
    pathlib.Path
        The path of ``report.md`` in *out_dir*.

    Examples
    --------
    >>> from symsphere.study import run_study
    >>> report = run_study("/tmp/study-small", config="small", progress=False)  # doctest: +SKIP
    """
    from tqdm.auto import tqdm

    from .demo import _check_seed

    config = _resolve_config(config)
    seed = _check_seed(seed)
    results = _Results(config, seed)
    cells = _convergence_cells(config)
    discrepancy_cells = _discrepancy_cells(config)
    chi2_tests = _chi2_tests(config)
    files = study_files(config)
    figures = [f for f in files if f.endswith(".png")]
    total = len(cells) * len(config.ks) + len(discrepancy_cells) + len(chi2_tests) + len(figures)
    started = time.perf_counter()
    with atomic_directory(out_dir, replaceable=_replaceable()) as build_dir, warnings.catch_warnings():
        # The peers' Sobol' sizes 3 * 2**m are deliberate (see the module docstring).
        warnings.filterwarnings("ignore", message="The balance properties of Sobol")
        bar_format = "{l_bar}{bar}| {n:.0f}/{total_fmt} cells [{elapsed}<{remaining}{postfix}]"
        with tqdm(total=total, desc="study", disable=True if not progress else None, dynamic_ncols=True,
                  bar_format=bar_format) as bar:
            clock = time.perf_counter()
            _run_convergence(results, cells, bar)
            results.stage_seconds["convergence"] = time.perf_counter() - clock
            clock = time.perf_counter()
            _run_discrepancy(results, discrepancy_cells, bar)
            results.stage_seconds["discrepancy"] = time.perf_counter() - clock
            clock = time.perf_counter()
            _run_chi2(results, chi2_tests, bar)
            results.stage_seconds["chi2"] = time.perf_counter() - clock
            clock = time.perf_counter()
            _write_figures(results, build_dir, bar)
            results.stage_seconds["figures"] = time.perf_counter() - clock
        _write_csv(build_dir / "convergence.csv", results.convergence, _CONVERGENCE_COLUMNS)
        _write_csv(build_dir / "summary.csv", results.summary, _SUMMARY_COLUMNS)
        _write_csv(build_dir / "discrepancy.csv", results.discrepancy, _DISCREPANCY_COLUMNS)
        _write_csv(build_dir / "chi2.csv", results.chi2, _CHI2_COLUMNS)
        results.stage_seconds["total"] = time.perf_counter() - started
        text = _report(results)
        (build_dir / "report.md").write_text(text, encoding="utf-8")
        (build_dir / "report.html").write_text(
            markdown_to_html(text, title=f"symsphere study ({config.name})"), encoding="utf-8"
        )
        missing = [f for f in files if not (build_dir / f).exists()]
        if missing:  # pragma: no cover - a bug, not a user error
            raise RuntimeError(f"the study did not write {missing}")
    return Path(out_dir) / "report.md"


def _key(text):
    """A stable non-negative integer for a name (part of a SeedSequence spawn key)."""
    import zlib

    return zlib.crc32(text.encode("utf-8"))


def _seed(results, *key):
    return np.random.SeedSequence(results.seed, spawn_key=tuple(int(k) for k in key))


# --- convergence -----------------------------------------------------------------

_CONVERGENCE_COLUMNS = (
    "integrand", "domain", "sampler", "points", "k", "n", "repetitions", "rmse", "relative_rmse",
    "mean_error", "mean_error_se", "mean_seconds", "median_seconds", "rounding_level",
)
_SUMMARY_COLUMNS = (
    "integrand", "domain", "sampler", "points", "status", "slope", "slope_se", "fit_points", "n_max",
    "rmse_at_n_max", "relative_rmse_at_n_max", "median_seconds_at_n_max", "efficiency",
    "relative_efficiency", "baseline",
)


def _convergence_cells(config):
    from .integrands import INTEGRANDS

    cells = []
    for g in config.integrands:
        integrand = INTEGRANDS[g]
        for sampler in _samplers(config, integrand.domain):
            cells.append((integrand, sampler))
    return cells


def _run_convergence(results, cells, bar):
    """RMSE and timings.  The samplers of one integrand are interleaved (for each n and repetition, one
    estimate of every sampler in turn), so that a change of the machine's load between cells biases
    no sampler's timing against another's."""
    config = results.config
    groups = {}
    for integrand, sampler in cells:
        groups.setdefault(integrand.name, (integrand, []))[1].append(sampler)
    step = 1.0 / config.repetitions
    for integrand, samplers in groups.values():
        bar.set_postfix_str(f"{integrand.name}: warm-up", refresh=False)
        for sampler in samplers:  # numba kernels, scipy engines: not timed
            sampler.estimate(integrand.f, sampler.n_for(config.k_min), _seed(results, 9, _key(sampler.label)))
        rows = {sampler: [] for sampler in samplers}
        for k in config.ks:
            estimates = {sampler: np.empty(config.repetitions) for sampler in samplers}
            seconds = {sampler: np.empty(config.repetitions) for sampler in samplers}
            for r in range(config.repetitions):
                bar.set_postfix_str(f"{integrand.name}: n = 48*2^{k}, repetition {r + 1}", refresh=False)
                for sampler in samplers:
                    rng = _seed(results, 0, _key(sampler.label), _key(integrand.name), k, r)
                    n = sampler.n_for(k)
                    clock = time.perf_counter()
                    estimates[sampler][r] = sampler.estimate(integrand.f, n, rng)
                    seconds[sampler][r] = time.perf_counter() - clock
                    bar.update(step)
            for sampler in samplers:
                rows[sampler].append(_convergence_row(integrand, sampler, k, estimates[sampler], seconds[sampler]))
        for sampler in samplers:
            results.convergence.extend(rows[sampler])
    _summarise(results)


def _convergence_row(integrand, sampler, k, estimates, seconds):
    error = float(rmse(estimates, integrand.exact))
    repetitions = len(estimates)
    return {
        "integrand": integrand.name, "domain": integrand.domain, "sampler": sampler.name,
        "points": sampler.points, "k": k, "n": sampler.n_for(k), "repetitions": repetitions,
        "rmse": error,
        "relative_rmse": error / abs(integrand.exact) if integrand.exact != 0 else math.nan,
        "mean_error": float(np.mean(estimates - integrand.exact)),
        "mean_error_se": float(np.std(estimates, ddof=1) / math.sqrt(repetitions)),
        "mean_seconds": float(np.mean(seconds)), "median_seconds": float(np.median(seconds)),
        "rounding_level": bool(error <= ROUNDING_LEVEL * max(1.0, abs(integrand.exact))),
    }


def _summarise(results):
    by_cell = {}
    for row in results.convergence:
        by_cell.setdefault((row["integrand"], row["sampler"], row["points"]), []).append(row)
    summary = []
    for (g, name, points), rows in by_cell.items():
        fit_rows = [r for r in rows if not r["rounding_level"]]
        if len(fit_rows) >= 3:
            fit = fit_slope([r["n"] for r in fit_rows], [r["rmse"] for r in fit_rows])
        else:
            fit = SlopeFit(math.nan, math.nan, math.nan, len(fit_rows))
        if not fit_rows:
            status = "exact"
        elif len(fit_rows) < len(rows):
            status = "partly at rounding level"
        else:
            status = "ok"
        last = rows[-1]
        mse = last["rmse"] ** 2
        if last["rounding_level"]:
            efficiency = math.inf
        else:
            efficiency = 1.0 / (max(mse, LOG_FLOOR) * last["median_seconds"])
        summary.append({
            "integrand": g, "domain": last["domain"], "sampler": name, "points": points, "status": status,
            "slope": fit.slope, "slope_se": fit.standard_error, "fit_points": fit.points, "n_max": last["n"],
            "rmse_at_n_max": last["rmse"], "relative_rmse_at_n_max": last["relative_rmse"],
            "median_seconds_at_n_max": last["median_seconds"], "efficiency": efficiency,
        })
    for row in summary:
        baseline = _BASELINE[row["domain"]]
        reference = next(
            (r for r in summary if r["integrand"] == row["integrand"] and (r["sampler"], r["points"]) == baseline),
            None,
        )
        row["baseline"] = "/".join(baseline)
        if reference is None or not math.isfinite(reference["efficiency"]):
            row["relative_efficiency"] = math.nan
        else:
            row["relative_efficiency"] = row["efficiency"] / reference["efficiency"]
    results.summary = summary


# --- discrepancy -------------------------------------------------------------------

_DISCREPANCY_COLUMNS = (
    "sampler", "points", "k", "n", "repetitions", "discrepancy_rms", "discrepancy_min", "discrepancy_max",
    "weighted_discrepancy_rms", "random_expectation",
)


def _discrepancy_cells(config):
    if "sphere" not in _domains(config):
        return []
    return [(s, k) for s in _samplers(config, "sphere") for k in config.discrepancy_ks]


def _run_discrepancy(results, cells, bar):
    config = results.config
    for sampler, k in cells:
        bar.set_postfix_str(f"discrepancy: {sampler.label}, N = {sampler.n_for(k)}", refresh=False)
        n = sampler.n_for(k)
        plain, weighted = [], []
        for r in range(config.discrepancy_repetitions):
            x = sampler.sample(n, _seed(results, 1, _key(sampler.label), k, r))
            plain.append(max(cap_discrepancy_squared(x), 0.0))
            if sampler.uniform:
                weighted.append(plain[-1])
            else:
                w = _weighted(np.ones(n), n * 4 * math.pi * sampler.pdf(x))
                weighted.append(max(cap_discrepancy_squared(x, w), 0.0))
        plain, weighted = np.array(plain), np.array(weighted)
        results.discrepancy.append({
            "sampler": sampler.name, "points": sampler.points, "k": k, "n": n,
            "repetitions": config.discrepancy_repetitions,
            "discrepancy_rms": float(np.sqrt(plain.mean())),
            "discrepancy_min": float(np.sqrt(plain.min())), "discrepancy_max": float(np.sqrt(plain.max())),
            "weighted_discrepancy_rms": float(np.sqrt(weighted.mean())),
            "random_expectation": math.sqrt(1.0 / (3.0 * n)),
        })
        bar.update(1)
    fits = []
    groups = {}
    for row in results.discrepancy:
        groups.setdefault((row["sampler"], row["points"]), []).append(row)
    for (name, points), rows in groups.items():
        ns = [r["n"] for r in rows]
        fits.append({
            "sampler": name, "points": points,
            "fit": fit_slope(ns, [r["discrepancy_rms"] for r in rows]) if len(rows) >= 2 else None,
            "weighted_fit": fit_slope(ns, [r["weighted_discrepancy_rms"] for r in rows]) if len(rows) >= 2 else None,
        })
    results.discrepancy_fits = fits


# --- chi-square ----------------------------------------------------------------------

_CHI2_COLUMNS = (
    "sampler", "points", "domain", "reference", "n_samples", "statistic", "dof", "p_value", "threshold", "passed",
)


def _chi2_tests(config):
    tests = []
    for domain in _domains(config):
        for sampler in _samplers(config, domain):
            if sampler.points != "random" or sampler.orbit_size is None:
                continue
            tests.append((sampler, "uniform"))
            if not sampler.uniform:
                tests.append((sampler, "own"))
    return tests


def _run_chi2(results, tests, bar):
    from .stats import chi2_test, one_per_orbit, uniform_pdf

    config = results.config
    samples = {}
    for sampler, reference in tests:
        bar.set_postfix_str(f"chi2: {sampler.label} ({sampler.domain}) vs {reference}", refresh=False)
        if sampler not in samples:
            size = sampler.orbit_size
            d = sampler.sample(config.chi2_samples * size, _seed(results, 2, _key(sampler.label), _key(sampler.domain)))
            if size > 1:
                d = one_per_orbit(d, size, _seed(results, 3, _key(sampler.label), _key(sampler.domain)))
            samples[sampler] = d
        pdf = uniform_pdf(sampler.domain) if reference == "uniform" else sampler.pdf
        result = chi2_test(samples[sampler], pdf, sampler.domain, significance=FAMILY_SIGNIFICANCE,
                           test_count=len(tests))
        results.chi2.append({
            "sampler": sampler.name, "points": sampler.points, "domain": sampler.domain,
            "reference": reference if reference == "uniform" else "own pdf",
            "n_samples": len(samples[sampler]), "statistic": result.statistic, "dof": result.dof,
            "p_value": result.p_value, "threshold": result.threshold, "passed": result.passed,
        })
        bar.update(1)


# --- CSV ------------------------------------------------------------------------------


def _csv_value(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    return str(value)


def _write_csv(path, rows, columns):
    import csv

    with open(path, "w", encoding="utf-8", newline="") as handle:
        writer = csv.writer(handle, lineterminator="\n")
        writer.writerow(columns)
        for row in rows:
            writer.writerow([_csv_value(row[c]) for c in columns])
# --- figures ----------------------------------------------------------------------------

_METHOD_COLOURS = {"equal_area": "#1f77b4", "paper1": "#ff7f0e", "paper2": "#d62728"}
_PEER_COLOURS = {
    "classic": "#2ca02c", "classic_hemisphere": "#2ca02c", "gaussian": "#9467bd", "octahedral": "#8c564b",
    "octahedral_hemisphere": "#8c564b", "fibonacci_rotated": "#e377c2", "fibonacci": "#e377c2",
    "arvo": "#bcbd22", "cosine": "#17becf",
}
_POINT_STYLES = {
    "random": ("-", "o"), "stratified": ("--", "s"), "sobol": ("-.", "^"), "halton": (":", "v"),
}


def _density_samplers(config):
    """One sampler per name with random points (the sphere's scheme, and every peer)."""
    seen, out = set(), []
    for sampler in _all_samplers(config):
        if sampler.points == "random" and sampler.name not in seen:
            seen.add(sampler.name)
            out.append(sampler)
    return out


def _warp_maps(config):
    peers = {p for p, _ in config.sphere_peers + config.hemisphere_peers}
    out = []
    for name in _WARP_MAPS:
        if name in METHODS:
            if name in config.scheme_methods:
                out.append(name)
        elif name in peers:
            out.append(name)
    return out


def _figure(size):
    # The object-oriented API with an Agg canvas: no pyplot state, no GUI backend (as symsphere.demo).
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(figure)
    return figure


def _write_figures(results, build_dir, bar):
    config = results.config
    from .integrands import INTEGRANDS

    for g in config.integrands:
        bar.set_postfix_str(f"figure: convergence {g}", refresh=False)
        _convergence_figure(build_dir / f"convergence_{g}.png", results, INTEGRANDS[g])
        bar.update(1)
    if "sphere" in _domains(config):
        bar.set_postfix_str("figure: discrepancy", refresh=False)
        _discrepancy_figure(build_dir / "discrepancy.png", results)
        bar.update(1)
    for sampler in _density_samplers(config):
        bar.set_postfix_str(f"figure: density {sampler.name}", refresh=False)
        _density_figure(build_dir / f"density_{sampler.name}.png", results, sampler)
        bar.update(1)
    for name in _warp_maps(config):
        bar.set_postfix_str(f"figure: warp {name}", refresh=False)
        _warp_figure(build_dir / f"warp_{name}.png", results, name)
        bar.update(1)


def _style(name, points, method=None):
    colour = _METHOD_COLOURS[method] if method else _PEER_COLOURS.get(name, "#7f7f7f")
    line, marker = _POINT_STYLES[points]
    return dict(color=colour, linestyle=line, marker=marker, markersize=3.5, linewidth=1.2)


def _convergence_figure(path, results, integrand):
    rows = [r for r in results.convergence if r["integrand"] == integrand.name]
    relative = integrand.exact != 0
    key = "relative_rmse" if relative else "rmse"
    floor = 1e-17
    series = {}
    for r in rows:
        series.setdefault((r["sampler"], r["points"]), []).append(r)
    summary = {(r["sampler"], r["points"]): r for r in results.summary if r["integrand"] == integrand.name}
    figure = _figure((12.5, 5.0))
    left, right = figure.subplots(1, 2, sharey=True)
    values = [max(r[key], floor) for r in rows]
    for (name, points), data in series.items():
        method = name[len("symsphere_"):] if name.startswith("symsphere_") else None
        n = np.array([r["n"] for r in data], dtype=float)
        y = np.array([max(r[key], floor) for r in data])
        fit = summary[(name, points)]
        slope = "exact" if fit["status"] == "exact" else f"{fit['slope']:.2f}"
        label = f"{name.replace('symsphere_', '') if method else name}/{points} ({slope})"
        axes = left if method else right
        axes.loglog(n, y, label=label, **_style(name, points, method))
        if method == "equal_area" and points in ("random", "sobol"):
            right.loglog(n, y, color="0.6", linestyle=_POINT_STYLES[points][0], linewidth=2.5, alpha=0.6,
                         label=f"equal_area/{points} ({slope})", zorder=0)
    n_all = np.array(sorted({r["n"] for r in rows}), dtype=float)
    top = max(values)
    for axes in (left, right):
        for power, text in ((0.5, "n^-1/2"), (1.0, "n^-1"), (1.5, "n^-3/2")):
            guide = top * (n_all / n_all[0]) ** (-power)
            axes.loglog(n_all, guide, color="0.3", linewidth=0.6, linestyle=(0, (1, 3)))
            axes.annotate(text, (n_all[-1], guide[-1]), fontsize=7, color="0.3", xytext=(2, 0),
                          textcoords="offset points", va="center")
        axes.set_xlabel("n (evaluations of f)")
        axes.grid(True, which="major", linewidth=0.3)
        axes.legend(fontsize=6.5, ncol=2 if axes is left else 1, loc="lower left")
    left.set_ylabel(("relative " if relative else "") + f"RMSE over {results.config.repetitions} repetitions")
    left.set_title("the symmetric scheme (map/points, fitted slope)", fontsize=9)
    right.set_title("peers (grey: equal_area/random and /sobol)", fontsize=9)
    figure.suptitle(f"{integrand.name} on the {integrand.domain}: exact {integrand.exact:.12g}", fontsize=10)
    figure.savefig(path, dpi=90)


def _discrepancy_figure(path, results):
    figure = _figure((16.5, 6.2))
    scheme, weighted_axes, peers = figure.subplots(1, 3, sharey=True)
    groups = {}
    for row in results.discrepancy:
        groups.setdefault((row["sampler"], row["points"]), []).append(row)
    fits = {(f["sampler"], f["points"]): f for f in results.discrepancy_fits}
    for (name, points), rows in groups.items():
        method = name[len("symsphere_"):] if name.startswith("symsphere_") else None
        n = np.array([r["n"] for r in rows], dtype=float)
        fit = fits[(name, points)]["fit"]
        slope = f" ({fit.slope:.2f})" if fit is not None else ""
        label = f"{method or name}/{points}{slope}"
        axes = scheme if method else peers
        axes.loglog(n, [r["discrepancy_rms"] for r in rows], label=label, **_style(name, points, method))
        if method:
            weighted = fits[(name, points)]["weighted_fit"]
            wslope = f" ({weighted.slope:.2f})" if weighted is not None else ""
            weighted_axes.loglog(n, [r["weighted_discrepancy_rms"] for r in rows], label=f"{method}/{points}{wslope}",
                                 **_style(name, points, method))
    n_all = np.array(sorted({r["n"] for r in results.discrepancy}), dtype=float)
    for axes in (scheme, weighted_axes, peers):
        axes.loglog(n_all, np.sqrt(1.0 / (3.0 * n_all)), color="k", linewidth=1.0, linestyle=(0, (4, 2)),
                    label="√(1/(3N)): i.i.d. uniform")
        first = math.sqrt(1.0 / (3.0 * n_all[0])) / 3
        axes.loglog(n_all, first * (n_all / n_all[0]) ** -0.75, color="0.4", linewidth=0.7,
                    linestyle=(0, (1, 2)), label="N^-3/4 (the optimal order)")
        axes.set_xlabel("N (points)")
        axes.grid(True, linewidth=0.3)
        axes.legend(fontsize=6.5, ncol=2 if axes is not peers else 1, loc="upper center",
                    bbox_to_anchor=(0.5, -0.13))
    scheme.set_ylabel(f"cap L2 discrepancy D (rms over {results.config.discrepancy_repetitions} sets)")
    scheme.set_title("the scheme: all N directions, equal weights 1/N", fontsize=9)
    weighted_axes.set_title("the scheme with the estimator's weights 1/(N 4π pdf)", fontsize=9)
    peers.set_title("peers (equal weights)", fontsize=9)
    figure.suptitle("Spherical-cap L2 discrepancy, exact by Stolarsky's invariance principle (fitted slope)",
                    fontsize=10)
    figure.savefig(path, dpi=80)


def _density_figure(path, results, sampler):
    from matplotlib.colors import LogNorm

    n = results.config.density_samples
    if sampler.peer == "arvo" or sampler.is_scheme:
        n -= n % 48
    d = sampler.sample(n, _seed(results, 4, _key(sampler.label)))
    hemisphere = sampler.domain == "hemisphere"
    n_phi, n_cos = 72, 18 if hemisphere else 36
    phi_edges = np.linspace(-math.pi, math.pi, n_phi + 1)
    cos_edges = np.linspace(0.0 if hemisphere else -1.0, 1.0, n_cos + 1)
    phi = np.arctan2(d[:, 1], d[:, 0])
    counts, _, _ = np.histogram2d(phi, np.clip(d[:, 2], -1.0, 1.0), bins=(phi_edges, cos_edges))
    ratio = counts / (len(d) / (n_phi * n_cos))
    ratio = np.clip(ratio, 1 / 8, 8)
    figure = _figure((6.4, 3.6))
    axes = figure.add_subplot(projection="mollweide")
    mesh = axes.pcolormesh(phi_edges, np.arcsin(cos_edges), ratio.T, cmap="RdBu_r",
                           norm=LogNorm(vmin=0.25, vmax=4.0), shading="flat", rasterized=True)
    axes.grid(True, linewidth=0.3)
    axes.set_xticklabels([])
    axes.tick_params(labelsize=6)
    figure.colorbar(mesh, ax=axes, shrink=0.7, label="density / uniform", ticks=[0.25, 0.5, 1, 2, 4],
                    format="%g")
    low, high = float(ratio.min()), float(ratio.max())
    axes.set_title(
        f"{sampler.name} (random points): {len(d)} directions\nin {n_phi}×{n_cos} equal-area bins, "
        f"density/uniform from {low:.2f} to {high:.2f}",
        fontsize=8,
    )
    figure.savefig(path, dpi=90)


def _warp_setup(name):
    """(domain, forward uv -> d, pdf, title) of a map that gets a warp picture."""
    from . import peers
    from .maps import square_to_triangle, triangle_pdf

    if name in METHODS:
        return ("triangle", lambda uv: square_to_triangle(uv, name), lambda p: triangle_pdf(p, name),
                f"{name}: unit square -> T0")
    if name == "arvo":
        vertices = peers.T0_VERTICES
        return ("triangle", lambda uv: peers.square_to_spherical_triangle(uv, *vertices),
                lambda p: peers.spherical_triangle_pdf(p, *vertices), "arvo: unit square -> T0 (Arvo 1995)")
    if name == "classic":
        return ("sphere", peers.square_to_uniform_sphere, peers.uniform_sphere_pdf,
                "classic: unit square -> sphere (z = 1 - 2u, φ = 2πv)")
    if name == "octahedral":
        return ("sphere", peers.square_to_octahedral_sphere, peers.uniform_sphere_pdf,
                "octahedral: unit square -> sphere (Clarberg 2008)")
    if name == "cosine":
        return ("hemisphere", peers.square_to_cosine_hemisphere, peers.cosine_hemisphere_pdf,
                "cosine: unit square -> hemisphere (concentric disk + Malley)")
    raise ValueError(f"no warp picture for {name!r}")  # pragma: no cover


def _phi_cos(d):
    return np.arctan2(d[..., 1], d[..., 0]), np.clip(d[..., 2], -1.0, 1.0)


def _broken(phi, cos):
    """Insert NaN where a curve jumps across phi = +-pi, so that it is not drawn across the picture."""
    jumps = np.nonzero(np.abs(np.diff(phi)) > math.pi)[0]
    return np.insert(phi, jumps + 1, np.nan), np.insert(cos, jumps + 1, np.nan)


def _warp_figure(path, results, name):
    from matplotlib.colors import LogNorm

    from .stats import bin_probabilities, chi2_test, equal_area_bins, uniform_pdf

    domain, forward, pdf, title = _warp_setup(name)
    bins = {"triangle": (20, 20), "sphere": (48, 24), "hemisphere": (48, 12)}[domain]
    figure = _figure((16.5, 4.2))
    grid, cloud, observed_axes, expected_axes = figure.subplots(1, 4)
    # (1) The grid lines of the unit square, warped.
    t = np.linspace(0.0, 1.0, 401)
    for value in np.linspace(0.0, 1.0, 11):
        for which, colour in ((0, "#1f77b4"), (1, "#d62728")):
            uv = np.stack([np.full_like(t, value), t] if which == 0 else [t, np.full_like(t, value)], axis=-1)
            phi, cos = _phi_cos(forward(uv))
            if domain != "triangle":
                phi, cos = _broken(phi, cos)
            grid.plot(np.degrees(phi), cos, color=colour, linewidth=0.7)
    grid.set_title("grid of the square (blue: u = const, red: v = const)", fontsize=8)
    # (2) A point cloud, coloured by u.
    rng = np.random.default_rng(_seed(results, 5, _key(name)))
    uv = rng.random((4096, 2))
    phi, cos = _phi_cos(forward(uv))
    cloud.scatter(np.degrees(phi), cos, c=uv[:, 0], s=1.0, cmap="viridis", linewidths=0, rasterized=True)
    cloud.set_title("4096 random points (colour: u)", fontsize=8)
    # (3), (4) Histogram of the map's points and its pdf integrated over the same bins, both / uniform.
    samples = forward(rng.random((results.config.warp_samples, 2)))
    result = chi2_test(samples, pdf, domain, bins=bins)
    uniform = len(samples) * bin_probabilities(uniform_pdf(domain), domain, bins)
    full = uniform.max()
    with np.errstate(divide="ignore", invalid="ignore"):
        observed = np.where(uniform > 0.3 * full, result.observed / np.where(uniform > 0, uniform, 1), np.nan)
        expected = np.where(uniform > 0.3 * full, result.expected / np.where(uniform > 0, uniform, 1), np.nan)
    phi_edges, cos_edges = equal_area_bins(domain, bins)
    norm = LogNorm(vmin=0.25, vmax=4.0)
    clipped = lambda a: np.clip(a, 1 / 8, 8)  # noqa: E731
    observed_axes.pcolormesh(np.degrees(phi_edges), cos_edges, clipped(observed).T, cmap="RdBu_r", norm=norm)
    mesh = expected_axes.pcolormesh(np.degrees(phi_edges), cos_edges, clipped(expected).T, cmap="RdBu_r", norm=norm)
    results.warp_chi2[name] = result.p_value
    observed_axes.set_title(
        f"histogram of {len(samples)} points / uniform (χ² vs own pdf: p = {_format_p(result.p_value)})", fontsize=8
    )
    expected_axes.set_title("pdf integrated over the bins / uniform", fontsize=8)
    for axes in (grid, cloud, observed_axes, expected_axes):
        if domain == "triangle":
            phi = np.linspace(0.0, math.pi / 4, 200)
            axes.plot(np.degrees(phi), np.cos(phi) / np.sqrt(1 + np.cos(phi) ** 2), color="k", linewidth=0.8)
            axes.set_xlim(0, 45)
            axes.set_ylim(1 / math.sqrt(3), 1.0)
        else:
            axes.set_xlim(-180, 180)
            axes.set_ylim(0.0 if domain == "hemisphere" else -1.0, 1.0)
        axes.set_xlabel("φ (degrees)")
        axes.tick_params(labelsize=7)
    grid.set_ylabel("cos θ (equal-area coordinates)")
    figure.colorbar(mesh, ax=[observed_axes, expected_axes], shrink=0.85, label="/ uniform",
                    ticks=[0.25, 0.5, 1, 2, 4], format="%g")
    figure.suptitle(f"warp of {title}", fontsize=10)
    figure.savefig(path, dpi=80)


def _format_p(p):
    from .demo import _format_p as format_p

    return format_p(p)


# --- report -------------------------------------------------------------------------------


def _g(x, digits=3):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    if isinstance(x, float) and math.isinf(x):
        return "∞"
    return f"{x:.{digits}g}"


def _slope_text(row):
    if row["status"] == "exact":
        return "exact"
    if math.isnan(row["slope"]):
        return "–"
    return f"{row['slope']:.2f} ± {row['slope_se']:.2f}"


def _efficiency_text(row):
    if row["status"] == "exact":
        return "∞ (exact)"
    if math.isinf(row["efficiency"]):
        return "∞ (rounding level)"
    return _g(row["relative_efficiency"])


def _lookup(rows, **match):
    for row in rows:
        if all(row[k] == v for k, v in match.items()):
            return row
    return None


def _mse_ratio(results, integrand, a, b):
    """MSE of b over MSE of a at the largest n (above 1: a is more accurate); None if a sampler is missing.

    inf if a alone is exact (rounding level), 0 if b alone is, NaN if both are.
    """
    ra = _lookup(results.summary, integrand=integrand, sampler=a[0], points=a[1])
    rb = _lookup(results.summary, integrand=integrand, sampler=b[0], points=b[1])
    if ra is None or rb is None:
        return None
    a_exact = ra["status"] == "exact" or ra["rmse_at_n_max"] == 0
    b_exact = rb["status"] == "exact" or rb["rmse_at_n_max"] == 0
    if a_exact and b_exact:
        return math.nan
    if a_exact:
        return math.inf
    if b_exact:
        return 0.0
    return (rb["rmse_at_n_max"] / ra["rmse_at_n_max"]) ** 2


_COMPARISONS = (
    # (A, B, what it measures); A and B are (sampler, points)
    (("symsphere_equal_area", "random"), ("classic", "random"), "orbits of 48 vs i.i.d. (same uniform density)"),
    (("symsphere_equal_area", "random"), ("arvo", "random"), "closed form vs Arvo's map: same distribution, expect 1"),
    (("symsphere_equal_area", "random"), ("symsphere_paper1", "random"), "the paper's map 1: variance penalty"),
    (("symsphere_equal_area", "random"), ("symsphere_paper2", "random"), "the paper's map 2: variance penalty"),
    (("symsphere_equal_area", "stratified"), ("symsphere_equal_area", "random"), "stratified vs random base points"),
    (("symsphere_equal_area", "sobol"), ("symsphere_paper1", "sobol"), "QMC: paper map 1 vs equal_area"),
    (("symsphere_equal_area", "sobol"), ("symsphere_paper2", "sobol"), "QMC: paper map 2 vs equal_area"),
    (("symsphere_equal_area", "sobol"), ("classic", "sobol"), "QMC with orbits vs Sobol' on the classic map"),
    (("symsphere_equal_area", "sobol"), ("octahedral", "sobol"), "QMC with orbits vs Sobol' on the octahedral map"),
    (("symsphere_equal_area", "sobol"), ("fibonacci_rotated", "random"), "QMC with orbits vs rotated Fibonacci"),
    (("symsphere_equal_area", "random"), ("classic_hemisphere", "random"), "hemisphere: orbits of 24 vs i.i.d."),
    (("symsphere_equal_area", "random"), ("cosine", "random"), "hemisphere: uniform orbits vs cosine-weighted i.i.d."),
    (("symsphere_equal_area", "sobol"), ("classic_hemisphere", "sobol"), "hemisphere QMC: orbits vs classic map"),
    (("symsphere_equal_area", "sobol"), ("cosine", "sobol"), "hemisphere QMC: orbits vs cosine-weighted Sobol'"),
)


def _comparison_rows(results):
    config = results.config
    from .integrands import INTEGRANDS

    rows = []
    for a, b, what in _COMPARISONS:
        ratios = {}
        for g in config.integrands:
            ratios[g] = _mse_ratio(results, g, a, b)
        if all(v is None for v in ratios.values()):
            continue
        rows.append((a, b, what, ratios))
    return rows, [g for g in config.integrands if INTEGRANDS[g]]


def _range_text(values):
    values = [v for v in values if v is not None and math.isfinite(v) and v > 0]
    if not values:
        return "–"
    low, high = min(values), max(values)
    geometric = math.exp(sum(math.log(v) for v in values) / len(values))
    if len(values) == 1:
        return f"{_g(low)}"
    return f"{_g(low)} to {_g(high)} (geometric mean {_g(geometric)})"


def _findings(results):
    """Sentences computed from the measurements (never assumed)."""
    from .integrands import INTEGRANDS

    config = results.config
    out = []
    sphere = [g for g in config.integrands if INTEGRANDS[g].domain == "sphere"]
    hemisphere = [g for g in config.integrands if INTEGRANDS[g].domain == "hemisphere"]

    def ratios(a, b, names):
        return {g: _mse_ratio(results, g, a, b) for g in names}

    ea, ea_sobol = ("symsphere_equal_area", "random"), ("symsphere_equal_area", "sobol")
    for domain, names in (("sphere", sphere), ("hemisphere", hemisphere)):
        baseline = _BASELINE[domain]
        count = 48 if domain == "sphere" else 24
        r = ratios(ea, baseline, names)
        if not names or any(v is None for v in r.values()):
            continue
        exact = [g for g, v in r.items() if math.isinf(v)]
        finite = {g: v for g, v in r.items() if math.isfinite(v)}
        sentence = (
            f"**Orbits of {count}, random points ({domain}).** At the largest n, the MSE of "
            f"{'/'.join(baseline)} (i.i.d.) over that of equal_area with orbits is "
            + (f"{_range_text(finite.values())} ({', '.join(f'{g}: {_g(v)}' for g, v in finite.items())})"
               if finite else "infinite")
        )
        if exact:
            sentence += f"; the scheme is exact (rounding level) on {', '.join(exact)}"
        invariant = [g for g in finite if INTEGRANDS[g].invariant]
        if invariant:
            sentence += (
                f". On the O_h-invariant {', '.join(invariant)} the orbit average is f itself, so the {count} "
                f"evaluations of an orbit are worth one independent sample: about 1/{count} = {1 / count:.3f} "
                "is expected there"
            )
        out.append(sentence + ".")
    for method in ("paper1", "paper2"):
        for points in ("random", "sobol"):
            names = sphere + hemisphere
            r = ratios(("symsphere_equal_area", points), (f"symsphere_{method}", points), names)
            if names and all(v is not None for v in r.values()):
                finite = [v for v in r.values() if math.isfinite(v)]
                if not finite:
                    continue
                out.append(
                    f"**The paper's {method} map, {points} points.** Weighted by 1/pdf (unbiased), its MSE is "
                    f"{_range_text(finite)} times that of equal_area at the largest n "
                    f"({', '.join(f'{g}: {_g(v)}' for g, v in r.items())})."
                )
    for peer in ("classic", "octahedral"):
        r = ratios(ea_sobol, (peer, "sobol"), sphere)
        if sphere and all(v is not None for v in r.values()):
            finite = [v for v in r.values() if math.isfinite(v)]
            if finite:
                out.append(
                    f"**QMC: orbits of scrambled Sobol' points vs Sobol' on the {peer} map.** MSE ratio "
                    f"({peer}/equal_area) at the largest n: {_range_text(finite)} "
                    f"({', '.join(f'{g}: {_g(v)}' for g, v in r.items())})."
                )
    slopes = []
    for name, points in (ea, ea_sobol, ("classic", "random"), ("classic", "sobol"), ("octahedral", "sobol"),
                         ("fibonacci_rotated", "random")):
        rows = [row for row in results.summary if row["sampler"] == name and row["points"] == points
                and row["integrand"] in sphere and row["status"] != "exact"]
        if rows:
            slopes.append(f"{name}/{points}: " + ", ".join(f"{row['integrand']} {row['slope']:.2f}" for row in rows))
    if slopes:
        out.append(
            "**Convergence slopes** (log RMSE vs log n on the sphere; cells at rounding level left out): "
            + "; ".join(slopes) + "."
        )
    fits = {(f["sampler"], f["points"]): f for f in results.discrepancy_fits}
    parts = []
    for key in (ea, ea_sobol, ("symsphere_paper1", "random"), ("symsphere_paper1", "sobol"),
                ("symsphere_paper2", "sobol"), ("classic", "sobol"), ("octahedral", "sobol"),
                ("fibonacci_rotated", "random"), ("classic", "random")):
        f = fits.get(key)
        if f is None or f["fit"] is None:
            continue
        text = f"{key[0]}/{key[1]} {f['fit'].slope:.2f}"
        if key[0] in ("symsphere_paper1", "symsphere_paper2"):
            text += f" (with weights 1/pdf: {f['weighted_fit'].slope:.2f})"
        parts.append(text)
    if parts:
        out.append(
            "**Cap discrepancy** (slope of D against N; i.i.d. points give -0.5, the best possible order is "
            "-0.75): " + "; ".join(parts) + "."
        )
    failed_uniform = sorted({f"{r['sampler']} ({r['domain']})" for r in results.chi2
                             if r["reference"] == "uniform" and not r["passed"]})
    passed_own = sorted({f"{r['sampler']} ({r['domain']})" for r in results.chi2
                         if r["reference"] == "own pdf" and r["passed"]})
    failed_own = sorted({f"{r['sampler']} ({r['domain']})" for r in results.chi2
                         if r["reference"] == "own pdf" and not r["passed"]})
    if results.chi2:
        sentence = "**χ².** Fail against the uniform density: " + (", ".join(failed_uniform) or "none")
        sentence += "; pass against their own pdf: " + (", ".join(passed_own) or "none")
        if failed_own:
            sentence += "; fail against their own pdf: " + ", ".join(failed_own)
        out.append(sentence + ".")
    return out


def _report(results):
    from . import __version__
    from .integrands import INTEGRANDS

    config = results.config
    ks = config.ks
    lines = [
        "# symsphere study: the symmetric scheme and its peers, measured",
        "",
        f"symsphere {__version__}; configuration **{config.name}**; seed {results.seed}; "
        f"{os.cpu_count()} CPUs (numba threads: {numba.get_num_threads()}); run time "
        f"{results.stage_seconds.get('total', math.nan):.0f} s (convergence "
        f"{results.stage_seconds.get('convergence', math.nan):.0f} s, discrepancy "
        f"{results.stage_seconds.get('discrepancy', math.nan):.0f} s, χ² "
        f"{results.stage_seconds.get('chi2', math.nan):.0f} s, figures "
        f"{results.stage_seconds.get('figures', math.nan):.0f} s).",
        "",
        "## What is measured",
        "",
        f"- **RMSE** of the estimate over {config.repetitions} independent repetitions (fresh random points, "
        f"jitter, scrambling or rotation each time) for n = 48·2^k evaluations of f, k = {ks[0]}…{ks[-1]} "
        f"(n = {48 * 2**ks[0]} … {48 * 2**ks[-1]}). The scheme with stratified points needs a square number of "
        "base points; for odd k it uses the nearest such n (the tables give the n used).",
        "- **Slope**: least squares of log RMSE against log n over all sizes (± its standard error). "
        f"RMSEs at rounding level (≤ {ROUNDING_LEVEL:g}·max(1, |exact|)) are flagged and left out; a cell "
        "that is at rounding level at every n is *exact*.",
        "- **Efficiency** 1/(MSE × seconds) at the largest n, seconds = median wall time of one estimate "
        "(sampling and evaluation), relative to the baseline i.i.d. sampler (classic on the sphere, "
        "classic_hemisphere on the hemisphere): above 1 is better than the baseline.",
        "- **Estimators**: the scheme (`symsphere_<map>`) is `symsphere.integrate` (orbit mean weighted by "
        "1/pdf, so the paper's maps are unbiased), one call with `replicates=1` per repetition; a peer gives "
        "mean(f/pdf).",
        f"- **Spherical-cap L2 discrepancy** of each point set on the sphere (all N directions, orbits "
        f"included), exact by Stolarsky's invariance principle, D² = 1/3 − (1/(4N²)) Σ|x_i − x_j|, rms over "
        f"{config.discrepancy_repetitions} sets, N = 48·2^k up to {48 * 2**config.discrepancy_k_max}. For the "
        "paper's maps also with the estimator's weights 1/(N·4π·pdf) (the worst-case error of the weighted rule "
        "in H^{3/2}(S²) with kernel 1 − |x − y|/4).",
        f"- **χ²** (`symsphere.stats.chi2_test`) of each random sampler, {config.chi2_samples} independent "
        "directions (one per orbit for orbit samplers), against the uniform density and, for the non-uniform "
        f"samplers, against their own pdf; Šidák-corrected over the {len(results.chi2)} tests at family level "
        f"{FAMILY_SIGNIFICANCE}.",
        "",
        "## Integrands",
        "",
        "| integrand | domain | exact | smooth | O_h-invariant | orbit average exact | description |",
        "|---|---|---:|---|---|---|---|",
    ]
    for g in config.integrands:
        it = INTEGRANDS[g]
        description = it.description.replace("|", "\\|")  # a literal | inside a table cell
        lines.append(
            f"| `{g}` | {it.domain} | {it.exact!r} | {_yes(it.smooth)} | {_yes(it.invariant)} | "
            f"{_yes(it.orbit_exact)} | {description} |"
        )
    lines += ["", "## Samplers", "", "| sampler | points | domain | what |", "|---|---|---|---|"]
    for sampler in _all_samplers(config):
        lines.append(f"| `{sampler.name}` | {sampler.points} | {sampler.domain} | {_sampler_note(sampler)} |")

    lines += ["", "## Headline: efficiency relative to the baseline, at the largest n", ""]
    for domain in _domains(config):
        names = [g for g in config.integrands if INTEGRANDS[g].domain == domain]
        baseline = "/".join(_BASELINE[domain])
        lines += [
            f"**{domain}** (1/(MSE·seconds) over that of `{baseline}`; above 1: better):",
            "",
            "| sampler | " + " | ".join(f"`{g}`" for g in names) + " |",
            "|---|" + "---:|" * len(names),
        ]
        for sampler in _samplers(config, domain):
            cells = [_efficiency_text(_lookup(results.summary, integrand=g, sampler=sampler.name,
                                              points=sampler.points)) for g in names]
            lines.append(f"| {sampler.label} | " + " | ".join(cells) + " |")
        lines += [
            "",
            f"**{domain}: convergence slopes** (log RMSE vs log n; ± standard error):",
            "",
            "| sampler | " + " | ".join(f"`{g}`" for g in names) + " |",
            "|---|" + "---:|" * len(names),
        ]
        for sampler in _samplers(config, domain):
            cells = [_slope_text(_lookup(results.summary, integrand=g, sampler=sampler.name,
                                         points=sampler.points)) for g in names]
            lines.append(f"| {sampler.label} | " + " | ".join(cells) + " |")
        lines.append("")

    comparisons, names = _comparison_rows(results)
    if comparisons:
        lines += [
            "## Comparisons: MSE(B) / MSE(A) at the largest n",
            "",
            "Above 1: A is more accurate at the same n (for random points, B needs about this many times "
            "as many evaluations). ∞: A alone is at rounding level; 0: B alone is; –: both are. Blank: the "
            "comparison does not apply to that integrand's domain.",
            "",
            "| A | B | what | " + " | ".join(f"`{g}`" for g in names) + " |",
            "|---|---|---|" + "---:|" * len(names),
        ]
        for a, b, what, ratios in comparisons:
            cells = ["" if ratios[g] is None else _g(ratios[g]) for g in names]
            lines.append(f"| {'/'.join(a)} | {'/'.join(b)} | {what} | " + " | ".join(cells) + " |")
        lines.append("")

    lines += ["## What the measurements say", ""]
    lines += [f"- {sentence}" for sentence in _findings(results)]
    lines += ["", "## Convergence", ""]
    for g in config.integrands:
        it = INTEGRANDS[g]
        lines += [
            f"### `{g}` ({it.domain}, exact {it.exact!r})",
            "",
            f"![convergence of {g}](convergence_{g}.png)",
            "",
            "| sampler | points | n max | relative RMSE | mean error | slope | seconds | efficiency | relative "
            "| status |",
            "|---|---|---:|---:|---:|---:|---:|---:|---:|---|",
        ]
        for row in results.summary:
            if row["integrand"] != g:
                continue
            last = _lookup(results.convergence, integrand=g, sampler=row["sampler"], points=row["points"],
                           n=row["n_max"])
            lines.append(
                f"| {row['sampler']} | {row['points']} | {row['n_max']} | {_g(row['relative_rmse_at_n_max'])} | "
                f"{_g(last['mean_error'])} ± {_g(last['mean_error_se'], 2)} | {_slope_text(row)} | "
                f"{_g(row['median_seconds_at_n_max'])} | {_g(row['efficiency'])} | {_efficiency_text(row)} | "
                f"{row['status']} |"
            )
        lines.append("")

    if results.discrepancy:
        ns = sorted({r["n"] for r in results.discrepancy if r["sampler"] == "classic"} or
                    {r["n"] for r in results.discrepancy})
        fits = {(f["sampler"], f["points"]): f for f in results.discrepancy_fits}
        lines += [
            "## Spherical-cap L2 discrepancy",
            "",
            "![discrepancy](discrepancy.png)",
            "",
            "rms of D over the sets; i.i.d. uniform points have E D² = 1/(3N). Rows *weights 1/pdf*: the "
            "paper's maps with the estimator's weights.",
            "",
            "| point set | " + " | ".join(f"N = {n}" for n in ns) + " | slope |",
            "|---|" + "---:|" * (len(ns) + 1),
            "| i.i.d. expectation √(1/(3N)) | " + " | ".join(_g(math.sqrt(1 / (3 * n))) for n in ns) + " | -0.50 |",
        ]
        for (name, points), f in fits.items():
            rows = [r for r in results.discrepancy if r["sampler"] == name and r["points"] == points]
            cells = [_g(r["discrepancy_rms"]) for r in rows]
            slope = f"{f['fit'].slope:.2f}" if f["fit"] is not None else "–"
            lines.append(f"| {name}/{points} | " + " | ".join(cells) + f" | {slope} |")
            if not _is_uniform(name):
                cells = [_g(r["weighted_discrepancy_rms"]) for r in rows]
                slope = f"{f['weighted_fit'].slope:.2f}" if f["weighted_fit"] is not None else "–"
                lines.append(f"| {name}/{points}, weights 1/pdf | " + " | ".join(cells) + f" | {slope} |")
        lines.append("")

    if results.chi2:
        lines += [
            "## χ² tests",
            "",
            f"Šidák threshold {results.chi2[0]['threshold']:.3g} per test ({len(results.chi2)} tests, family "
            f"level {FAMILY_SIGNIFICANCE}). Stratified and QMC point sets are not tested: their points are not "
            "independent. Nor is fibonacci_rotated (one rotation per set).",
            "",
            "| sampler | domain | reference | samples | χ² | dof | p-value | result |",
            "|---|---|---|---:|---:|---:|---:|---|",
        ]
        for row in results.chi2:
            lines.append(
                f"| {row['sampler']} | {row['domain']} | {row['reference']} | {row['n_samples']} | "
                f"{_g(row['statistic'], 6)} | {row['dof']} | {_format_p(row['p_value'])} | "
                f"{'pass' if row['passed'] else '**FAIL**'} |"
            )
        lines.append("")

    lines += [
        "## Density maps",
        "",
        "Histograms of each sampler's directions (random points) in equal-area (φ, cos θ) bins, relative to "
        "the uniform density, in a Mollweide projection (log colour scale 1/4 … 4, white = 1).",
        "",
    ]
    for sampler in _density_samplers(config):
        lines += [f"![density of {sampler.name}](density_{sampler.name}.png)", ""]
    lines += [
        "## Warp pictures",
        "",
        "In the manner of Nori's warptest: the grid lines of the unit square carried by the map, a point cloud, "
        "and a histogram of the map's points beside its pdf integrated over the same bins (both relative to "
        "uniform), in the equal-area coordinates (φ, cos θ) — T0 is the region under the curve "
        "cos θ = cos φ/√(1 + cos²φ).",
        "",
    ]
    for name in _warp_maps(config):
        p_value = results.warp_chi2.get(name, math.nan)
        lines += [
            f"![warp of {name}](warp_{name}.png)",
            "",
            f"`{name}`: χ² of {config.warp_samples} points of the map against its own pdf, p = {_format_p(p_value)}.",
            "",
        ]
    lines += [
        "## Files",
        "",
        "- `convergence.csv`: one row per (integrand, sampler, points, n): " + ", ".join(_CONVERGENCE_COLUMNS) + ".",
        "- `summary.csv`: one row per (integrand, sampler, points): " + ", ".join(_SUMMARY_COLUMNS) + ".",
        "- `discrepancy.csv`: one row per (sampler, points, N): " + ", ".join(_DISCREPANCY_COLUMNS) + ".",
        "- `chi2.csv`: one row per test: " + ", ".join(_CHI2_COLUMNS) + ".",
        "",
        f"Reproduce: {_reproduce(config, results.seed)}",
        "",
    ]
    return "\n".join(lines)


def _reproduce(config, seed):
    base = CONFIGS.get(config.name.split(" ")[0])
    if base is not None:
        command = f"symsphere study --config {base.name} --seed {seed}"
        if config.repetitions != base.repetitions:
            command += f" --repetitions {config.repetitions}"
        if config.k_max != base.k_max:
            command += f" --k-max {config.k_max}"
        if config == base.replace(name=config.name, repetitions=config.repetitions, k_max=config.k_max):
            return f"`{command}`."
    return "a custom configuration: `symsphere.study.run_study(config=StudyConfig(...))` with the values above."


def _is_uniform(name):
    if name.startswith("symsphere_"):
        from .maps import get_map

        return get_map(name[len("symsphere_"):]).uniform
    return name != "cosine"


def _yes(flag):
    return "yes" if flag else "no"


def _sampler_note(sampler):
    from .peers import PEERS

    if sampler.is_scheme:
        count = 48 if sampler.domain == "sphere" else 24
        note = f"the scheme: `{sampler.method}` map onto T0, orbits of {count}, `integrate()`"
        if sampler.method != "equal_area":
            note += " (the paper's map as printed, weighted by 1/pdf)"
        return note
    peer = PEERS[sampler.peer]
    note = peer.reference.split(";")[0]
    if sampler.peer == "fibonacci_rotated":
        note += " (a new random rotation per repetition)"
    return note


# =============================================================================
# Markdown -> HTML (headings, paragraphs, lists, tables, images, code)
# =============================================================================


def markdown_to_html(text, title="report"):
    r"""A minimal Markdown to HTML conversion, enough for the study's report.

    Handles ATX headings, paragraphs, ``-`` lists, pipe tables (with ``---:``
    right alignment), fenced code blocks, images, links, ``code``, **bold**
    and *emphasis*.  Everything else is escaped text.

    Examples
    --------
    >>> from symsphere.study import markdown_to_html
    >>> page = markdown_to_html("# Title\n\n| a | b |\n|---|---:|\n| 1 | **2** |\n")
    >>> "<h1>Title</h1>" in page and '<td style="text-align:right"><strong>2</strong></td>' in page
    True
    """
    out = []
    lines = text.splitlines()
    i = 0
    paragraph = []

    def flush():
        if paragraph:
            out.append("<p>" + _inline(" ".join(paragraph)) + "</p>")
            paragraph.clear()

    while i < len(lines):
        line = lines[i]
        stripped = line.strip()
        if stripped.startswith("```"):
            flush()
            i += 1
            code = []
            while i < len(lines) and not lines[i].strip().startswith("```"):
                code.append(html.escape(lines[i]))
                i += 1
            out.append("<pre><code>" + "\n".join(code) + "</code></pre>")
        elif re.match(r"#{1,6} ", stripped):
            flush()
            level = len(stripped) - len(stripped.lstrip("#"))
            out.append(f"<h{level}>{_inline(stripped[level:].strip())}</h{level}>")
        elif stripped.startswith("|"):
            flush()
            block = []
            while i < len(lines) and lines[i].strip().startswith("|"):
                block.append(lines[i].strip())
                i += 1
            out.append(_table(block))
            continue
        elif stripped.startswith("- "):
            flush()
            out.append("<ul>")
            while i < len(lines) and lines[i].strip().startswith("- "):
                out.append("<li>" + _inline(lines[i].strip()[2:]) + "</li>")
                i += 1
            out.append("</ul>")
            continue
        elif not stripped:
            flush()
        else:
            paragraph.append(stripped)
        i += 1
    flush()
    style = (
        "body{font-family:sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;line-height:1.4}"
        "table{border-collapse:collapse;margin:1em 0;font-size:0.85em}"
        "th,td{border:1px solid #ccc;padding:0.2em 0.5em}th{background:#f0f0f0}"
        "img{max-width:100%}code{background:#f4f4f4;padding:0 0.2em}"
    )
    return (
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
        f"<title>{html.escape(title)}</title>\n<style>{style}</style>\n</head>\n<body>\n"
        + "\n".join(out)
        + "\n</body>\n</html>\n"
    )


def _cells(row):
    row = row.strip()
    row = row[1:] if row.startswith("|") else row
    row = row[:-1] if row.endswith("|") and not row.endswith("\\|") else row
    return [c.strip().replace("\\|", "|") for c in re.split(r"(?<!\\)\|", row)]


def _table(block):
    header = _cells(block[0])
    align = [""] * len(header)
    body = block[1:]
    if body and re.fullmatch(r"\|?(\s*:?-+:?\s*\|)*\s*:?-+:?\s*\|?", body[0]):
        for k, spec in enumerate(_cells(body[0])[: len(header)]):
            if spec.endswith(":") and spec.startswith(":"):
                align[k] = ' style="text-align:center"'
            elif spec.endswith(":"):
                align[k] = ' style="text-align:right"'
        body = body[1:]
    rows = ["<table>", "<tr>" + "".join(f"<th{a}>{_inline(c)}</th>" for c, a in zip(header, align)) + "</tr>"]
    for row in body:
        cells = _cells(row)
        rows.append("<tr>" + "".join(f"<td{a}>{_inline(c)}</td>" for c, a in zip(cells, align)) + "</tr>")
    rows.append("</table>")
    return "\n".join(rows)


def _inline(text):
    codes = []

    def keep(match):
        codes.append("<code>" + html.escape(match.group(1)) + "</code>")
        return f"\x00{len(codes) - 1}\x00"

    text = re.sub(r"`([^`]+)`", keep, text)
    text = html.escape(text, quote=False)
    text = re.sub(r"!\[([^\]]*)\]\(([^)\s]+)\)",
                  lambda m: f'<img src="{html.escape(m.group(2))}" alt="{html.escape(m.group(1))}">', text)
    text = re.sub(r"\[([^\]]+)\]\(([^)\s]+)\)", lambda m: f'<a href="{html.escape(m.group(2))}">{m.group(1)}</a>', text)
    text = re.sub(r"\*\*(.+?)\*\*", r"<strong>\1</strong>", text)
    text = re.sub(r"(?<![\w*])\*(?!\s)(.+?)(?<!\s)\*(?![\w*])", r"<em>\1</em>", text)
    return re.sub("\x00(\\d+)\x00", lambda m: codes[int(m.group(1))], text)


# =============================================================================
# Command line (wired into symsphere.cli by ``add_study_parser``)
# =============================================================================


def add_study_parser(subparsers):
    """Add the ``study`` verb to the ``symsphere`` command's sub-parsers.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        What ``ArgumentParser.add_subparsers()`` returned.

    Returns
    -------
    argparse.ArgumentParser
        The ``study`` parser; its default ``handler`` is :func:`run_study_command`.
    """
    study = subparsers.add_parser(
        "study",
        help="convergence study of every sampler, point set and integrand, written up as a report",
        description=(
            "Measure, for every sampler x point set x integrand, the RMSE over independent repetitions "
            "for n = 48*2^k, the convergence slope and the efficiency 1/(MSE x seconds); the spherical-cap "
            "L2 discrepancy of every point set (exact, by Stolarsky's invariance principle); chi-square "
            "p-values of the random samplers; and write report.md, report.html, CSV tables and PNG figures "
            "into DIR.  --config full (the default) takes about 13 minutes on 2 cores; --config small, "
            "well under a minute.  An existing DIR is replaced only if it holds nothing but an earlier "
            "study's output."
        ),
    )
    study.add_argument("--out", default="study-report", metavar="DIR", help="output directory (default: %(default)s)")
    study.add_argument("--config", choices=tuple(CONFIGS), default="full", help="default: %(default)s")
    study.add_argument("--seed", type=int, default=0, help="non-negative integer (default: %(default)s)")
    study.add_argument(
        "--repetitions", type=int, default=None,
        help="independent repetitions per cell, >= 2 (default: 32 for full, 4 for small)",
    )
    study.add_argument(
        "--k-max", type=int, default=None, dest="k_max", metavar="K",
        help="largest size n = 48*2^K (default: 14 for full, 6 for small)",
    )
    study.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    study.set_defaults(handler=run_study_command)
    return study


def run_study_command(args) -> int:
    """Handler of ``symsphere study``: run :func:`run_study` with the parsed *args*; return 0.

    Invalid values raise ValueError naming the option (the ``symsphere`` command turns it into exit
    status 2); an unwritable output raises OSError (exit status 1).
    """
    if args.seed is None or args.seed < 0:
        raise ValueError(f"--seed must be a non-negative integer, got {args.seed}")
    config = CONFIGS[args.config]
    changes = {}
    if args.repetitions is not None:
        if args.repetitions < 2:
            raise ValueError(f"--repetitions must be >= 2, got {args.repetitions}")
        changes["repetitions"] = args.repetitions
    if args.k_max is not None:
        if args.k_max < config.k_min + 2 or args.k_max > 20:
            raise ValueError(f"--k-max must be in [{config.k_min + 2}, 20], got {args.k_max}")
        changes["k_max"] = args.k_max
    if changes:
        config = config.replace(name=f"{config.name} (" + ", ".join(f"{k}={v}" for k, v in changes.items()) + ")",
                                **changes)
    parent = Path(args.out).absolute().parent
    if not parent.is_dir():  # name the user's path, not the temporary folder next to it
        import errno

        raise OSError(errno.ENOENT, "no such directory", str(parent))
    start = time.perf_counter()
    report = run_study(args.out, config=config, seed=args.seed, progress=not args.no_progress)
    print(f"report: {report}  (and report.html, CSV tables and figures in {report.parent}; "
          f"{time.perf_counter() - start:.1f} s)")
    return 0


@numba.njit(cache=True)
def _row_distance_sum(x, w, i):  # pragma: no cover - compiled
    """w_i * sum over j > i of w_j |x_i - x_j|."""
    xi, yi, zi = x[i, 0], x[i, 1], x[i, 2]
    row = 0.0
    for j in range(i + 1, x.shape[0]):
        dx, dy, dz = xi - x[j, 0], yi - x[j, 1], zi - x[j, 2]
        row += w[j] * math.sqrt(dx * dx + dy * dy + dz * dz)
    return w[i] * row


@numba.njit(parallel=True, cache=True)
def _weighted_distance_sum(x, w):  # pragma: no cover - compiled
    """sum over i != j of w_i w_j |x_i - x_j|: rows r and N-1-r share a task, so the tasks are equal."""
    n = x.shape[0]
    total = 0.0
    for r in numba.prange((n + 1) // 2):
        other = n - 1 - r
        acc = _row_distance_sum(x, w, r)
        if other != r:
            acc += _row_distance_sum(x, w, other)
        total += acc
    return 2.0 * total
