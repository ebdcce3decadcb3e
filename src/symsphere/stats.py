"""Chi-square goodness-of-fit tests for samplers of directions.

A sampler of unit directions is tested against the density it claims to
have, in the manner of Mitsuba 3's ``ChiSquareTest``: the samples are
histogrammed on a grid of bins, the expected count of every bin is obtained
by integrating the density over the bin numerically, bins with a small
expected count are pooled, and Pearson's chi-square statistic is compared
with the chi-square distribution.

The domains are the sphere, the hemisphere z >= 0 and the fundamental
triangle T0 = {z >= x >= y >= 0}; the equal-area bins in (phi, cos theta)
and the quadrature of the density over them are in :mod:`symsphere.bins`
(:func:`~symsphere.bins.bin_probabilities`, :func:`~symsphere.bins.equal_area_bins`).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
import numpy.typing as npt
from scipy import stats as _scipy_stats

from ._constants import INV_2PI, INV_4PI, T0_DENSITY
from ._typing import ChiDomain, Density, Float64Array, FloatArray, IntArray, RNGLike
from ._validation import (
    MAX_QUADRATURE_ORDER,
    check_bins,
    check_choice,
    check_count,
    check_directions,
    check_open_unit,
    check_pdf,
    check_positive_real,
    check_rng,
    check_samples,
    off_unit,
    short_repr,
)
from .bins import bin_probabilities, equal_area_bins

__all__ = [
    "Chi2Result",
    "chi2_test",
    "one_per_orbit",
    "uniform_pdf",
]

_DOMAINS: tuple[ChiDomain, ...] = ("sphere", "hemisphere", "triangle")

# |integral - 1| above this fails the test: the expected counts would be wrong.
_INTEGRAL_TOL = 1e-3
# | |d| - 1 | above this marks a sample as not a unit vector (a failing sampler).
_NORM_TOL = 1e-4
# Samples this far outside the domain (in units of the samples' machine
# epsilon) are still counted, in the nearest bin: rounding, not a bug.
_BOUNDARY_ULPS = 64
# Tolerance of uniform_pdf('triangle') for nodes on an edge of T0.
_EDGE_TOL = 1e-12
# Default bin grid: about this many expected samples per bin, and limits on r.
_TARGET_PER_BIN = 100
_MIN_RES, _MAX_RES = 4, 64


@dataclass(frozen=True, eq=False)
class Chi2Result:
    """Outcome of :func:`chi2_test`.

    Attributes
    ----------
    statistic : float
        Pearson's chi-square statistic over the cells (``inf`` if the test
        failed before it could be computed, see `message`).
    dof : int
        Degrees of freedom, the number of cells after pooling minus one.
    p_value : float
        ``scipy.stats.chi2.sf(statistic, dof)``; 0 for a hard failure
        (samples outside the domain or in bins of zero expected count).
    threshold : float
        The Sidak-corrected significance level
        ``1 - (1 - significance)**(1 / test_count)``.
    passed : bool
        True iff there was no hard failure, the pdf integrates to 1 within
        1e-3 and ``p_value >= threshold``.
    observed : ndarray of int64, shape bins
        Sample counts per bin, indexed ``[i_phi, i_cos]``.  Samples outside
        the domain are not counted.
    expected : ndarray of float64, shape bins
        ``n * integral of pdf over the bin`` per bin.
    integral : float
        Integral of the pdf over the whole domain (should be 1).
    message : str
        Human-readable verdict, naming the reason of a failure.
    ratio_range : tuple of float
        Smallest and largest ``observed / expected`` over the bins whose
        expected count is at least `min_expected` (NaN if there are none).
    domain : str
        The domain tested.
    n_samples : int
        Number of samples given, including any outside the domain.

    Examples
    --------
    >>> import symsphere
    >>> from symsphere.stats import chi2_test, one_per_orbit, uniform_pdf
    >>> d = one_per_orbit(symsphere.sample_sphere(48 * 5000, rng=1), 48, rng=2)
    >>> res = chi2_test(d, uniform_pdf("sphere"))
    >>> res.passed, res.dof, res.observed.shape, int(res.observed.sum())
    (True, 31, (8, 4), 5000)
    >>> bool(res.p_value >= res.threshold), round(res.integral, 9)
    (True, 1.0)
    >>> print(str(res).splitlines()[0])                      # str(res) is a short report
    chi2 test on the sphere: PASSED
    """

    statistic: float
    dof: int
    p_value: float
    threshold: float
    passed: bool
    observed: IntArray
    expected: Float64Array
    integral: float
    message: str
    ratio_range: tuple[float, float]
    domain: ChiDomain
    n_samples: int

    def __str__(self) -> str:
        n_phi, n_cos = self.observed.shape
        lo, hi = self.ratio_range
        lines = [
            f"chi2 test on the {self.domain}: {'PASSED' if self.passed else 'FAILED'}",
            f"  {self.n_samples} samples in {n_phi} x {n_cos} bins (phi x cos theta), {self.dof} degrees of freedom",
            f"  statistic {self.statistic:.6g}, p-value {self.p_value:.4g}, threshold {self.threshold:.4g}",
            f"  pdf integral over the domain {self.integral:.10f}",
            f"  observed/expected per bin {lo:.3g} - {hi:.3g}",
            f"  {self.message}",
        ]
        return "\n".join(lines)

    def _repr_html_(self) -> str:
        """A small table for Jupyter: the verdict, the statistic, the p-value against its threshold."""
        from html import escape

        n_phi, n_cos = self.observed.shape
        rows = [
            ("result", "PASSED" if self.passed else "FAILED"),
            ("samples", f"{self.n_samples} in {n_phi} &times; {n_cos} bins (&phi; &times; cos &theta;)"),
            ("&chi;&sup2; / dof", f"{self.statistic:.6g} / {self.dof}"),
            ("p-value", f"{self.p_value:.4g} (passes if &ge; {self.threshold:.4g})"),
            ("observed / expected", "{:.3g} &ndash; {:.3g} per bin".format(*self.ratio_range)),
            ("pdf integral", f"{self.integral:.10f}"),
        ]
        body = "".join(
            f"<tr><th style='text-align:left'>{k}</th><td style='text-align:left'>{v}</td></tr>" for k, v in rows
        )
        return f"<table><caption>&chi;&sup2; test on the {escape(self.domain)}: {escape(self.message)}</caption>{body}</table>"


def chi2_test(
    samples: npt.ArrayLike,
    pdf: Density,
    domain: ChiDomain = "sphere",
    *,
    bins: tuple[int, int] | None = None,
    significance: float = 0.01,
    test_count: int = 1,
    min_expected: float = 5.0,
    quadrature_order: int = 12,
) -> Chi2Result:
    """Pearson chi-square test of direction samples against a density.

    The samples are histogrammed on the equal-area grid of
    :func:`equal_area_bins`, the expected count of each bin is ``n`` times
    the integral of `pdf` over it (see :func:`bin_probabilities`), and
    Pearson's statistic is computed over the cells that remain after pooling
    the bins whose expected count is below `min_expected` into a single cell
    (if that cell's expected count is still below `min_expected`, the cells
    with the smallest expected counts are added to it until it is not).
    Bins whose expected count is exactly 0 are not cells; a sample in one
    fails the test.

    Parameters
    ----------
    samples : array_like, shape (n, 3)
        Unit directions (float32 or float64; integers are converted).
    pdf : callable
        ``pdf(d)`` takes a float64 array of shape (m, 3) of unit directions
        and returns their densities with respect to solid angle, shape (m,)
        (a scalar is broadcast).  It may be 0 outside its support.  It is
        evaluated only at interior Gauss-Legendre nodes, never exactly on a
        pole or on a bin edge, so isolated infinities there are harmless;
        non-finite or negative values at the nodes raise ValueError.  For
        ``domain='triangle'`` the pdf is assumed to vanish outside T0 and
        is evaluated only inside it.
    domain : {'sphere', 'hemisphere', 'triangle'}, optional
        The domain the samples should cover (see the module docstring).
        Default is 'sphere'.
    bins : tuple of two int, optional
        ``(n_phi, n_cos)``.  The default is ``(2 r, r)`` for the sphere and
        hemisphere, with ``r = clip(floor(sqrt(n / 200)), 4, 64)``, and
        ``(r, r)`` with ``r = clip(floor(sqrt(n / 100)), 4, 64)`` for the
        triangle: about 100 expected samples per bin.
    significance : float, optional
        Significance level of one test, in (0, 1).  Default is 0.01.
    test_count : int, optional
        Number of tests run together; the level is Sidak-corrected to
        ``1 - (1 - significance)**(1 / test_count)`` so that the chance of
        any false rejection among them is `significance`.  Default is 1.
    min_expected : float, optional
        Bins with a smaller positive expected count are pooled.  Default 5.
    quadrature_order : int, optional
        Gauss-Legendre points per axis and bin.  Default is 12.

    Returns
    -------
    Chi2Result
        The statistic, p-value, verdict, histograms and a message.  A
        sampler that puts samples outside the domain, or samples that are
        not unit vectors, gives ``passed=False`` and ``p_value=0`` rather
        than an exception.

    Raises
    ------
    TypeError
        If `pdf` is not callable, or an argument has the wrong type.
    ValueError
        If an argument has an invalid value, or `pdf` returns a wrong shape,
        non-finite or negative values at the quadrature nodes.

    See Also
    --------
    bin_probabilities : the per-bin integrals of the pdf.
    uniform_pdf : reference densities of the uniform distributions.

    Notes
    -----
    The test passes iff ``p_value >= threshold``, the pdf integrates to 1
    within 1e-3 over the domain (otherwise the expected counts would be
    wrong, whatever the sampler) and no sample is outside the domain.

    Sample coordinates are ``phi = atan2(y, x)``, with phi = pi wrapped to
    -pi, and ``cos theta = z`` of the normalised sample, clipped to [-1, 1];
    cos theta = 1 and, for the triangle, phi = pi/4 fall in the last bin.
    Samples within 64 machine epsilons (of the samples' dtype) outside the
    domain are counted in the nearest bin; samples farther out, or whose
    norm differs from 1 by more than 1e-4, fail the test.  For the triangle
    the domain is T0 itself, tested with the inequalities z >= x >= y >= 0,
    not only its bounding rectangle.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.stats import chi2_test, uniform_pdf
    >>> rng = np.random.default_rng(12345)
    >>> d = rng.standard_normal((20000, 3))
    >>> d /= np.linalg.norm(d, axis=1, keepdims=True)
    >>> res = chi2_test(d, uniform_pdf("sphere"))
    >>> res.passed, res.observed.shape
    (True, (20, 10))
    >>> abs(res.integral - 1) < 1e-12
    True

    A sampler that is not uniform is rejected:

    >>> d[:, 0] *= 1.5
    >>> d /= np.linalg.norm(d, axis=1, keepdims=True)
    >>> res = chi2_test(d, uniform_pdf("sphere"))
    >>> res.passed, res.p_value < 1e-10
    (False, True)
    """
    domain = check_choice(domain, "domain", _DOMAINS)
    d = check_samples(samples)
    boundary_tol = _BOUNDARY_ULPS * float(np.finfo(d.dtype).eps)
    pdf = check_pdf(pdf)
    significance = check_open_unit(significance, "significance")
    test_count = check_count(test_count, "test_count")
    min_expected = check_positive_real(min_expected, "min_expected")
    quadrature_order = check_count(quadrature_order, "quadrature_order", maximum=MAX_QUADRATURE_ORDER)
    n = d.shape[0]
    shape = _default_bins(domain, n) if bins is None else check_bins(bins)
    threshold = _sidak(significance, test_count)

    prob = bin_probabilities(pdf, domain, shape, quadrature_order=quadrature_order)
    integral = math.fsum(prob.ravel().tolist())
    expected = n * prob
    observed, problems = _histogram(d, domain, shape, boundary_tol)

    zero = (expected <= 0) & (observed > 0)
    hard_failure = bool(problems)
    if np.any(zero):
        i, j = np.argwhere(zero)[0]
        problems.append(
            f"{int(observed[zero].sum())} samples fall in {int(zero.sum())} bins where "
            f"the pdf integrates to 0 (expected count 0), e.g. bin ({i}, {j}) with "
            f"phi in {_interval(domain, shape, 0, i)} and cos theta in "
            f"{_interval(domain, shape, 1, j)}: the sampler puts samples where the pdf "
            "has no support"
        )
        hard_failure = True

    statistic, dof, ncells_note = _pearson(observed, expected, min_expected)
    if hard_failure:
        statistic, p_value = math.inf, 0.0
    elif dof < 1:
        p_value = math.nan
        problems.append(
            f"only {dof + 1} cell(s) have an expected count >= min_expected="
            f"{min_expected:g} after pooling, so there is nothing to test; use more "
            "samples or fewer bins"
        )
    else:
        p_value = float(_scipy_stats.chi2.sf(statistic, dof))

    if abs(integral - 1.0) > _INTEGRAL_TOL:
        problems.append(
            f"the pdf integrates to {integral:.9g} over the {domain}, not 1 "
            f"(tolerance {_INTEGRAL_TOL:g}), so the expected counts are wrong; the pdf "
            "must be a density with respect to solid angle, normalised over the domain"
        )

    passed = not problems and p_value >= threshold
    level = (
        f"the Sidak-corrected level for {test_count} tests at significance {significance:g}"
        if test_count > 1
        else f"significance {significance:g}"
    )
    if problems:
        message = "rejected: " + "; ".join(problems)
    elif passed:
        message = f"accepted: p-value {p_value:.4g} >= {threshold:.4g}, {level}{ncells_note}"
    else:
        message = (
            f"rejected: p-value {p_value:.4g} < {threshold:.4g}, {level}; the samples do "
            f"not follow the pdf{ncells_note}"
        )

    large = expected >= min_expected
    if np.any(large):
        ratio = observed[large] / expected[large]
        ratio_range = (float(ratio.min()), float(ratio.max()))
    else:
        ratio_range = (math.nan, math.nan)

    observed.setflags(write=False)
    expected.setflags(write=False)
    return Chi2Result(
        statistic=float(statistic),
        dof=int(dof),
        p_value=float(p_value),
        threshold=threshold,
        passed=bool(passed),
        observed=observed,
        expected=expected,
        integral=float(integral),
        message=message,
        ratio_range=ratio_range,
        domain=domain,
        n_samples=int(n),
    )


def uniform_pdf(domain: ChiDomain = "sphere") -> Callable[[npt.ArrayLike], Float64Array]:
    """The uniform density on a domain, as a callable for :func:`chi2_test`.

    Parameters
    ----------
    domain : {'sphere', 'hemisphere', 'triangle'}, optional
        Default is 'sphere'.

    Returns
    -------
    callable
        ``f(d)`` for an array of shape (..., 3) returns shape (...,):
        ``1 / (4 pi)`` on the sphere; ``1 / (2 pi)`` where ``z >= 0`` and 0
        elsewhere for the hemisphere; ``12 / pi`` where ``z >= x >= y >= 0``
        (each inequality with a tolerance of 1e-12, so that points on an
        edge count as inside) and 0 elsewhere for the triangle.  The
        triangle's density uses only these inequalities, not the
        (phi, cos theta) description of T0, so it is an independent
        reference for the quadrature.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.stats import uniform_pdf
    >>> f = uniform_pdf("triangle")
    >>> f(np.array([[0.1, 0.05, 0.99], [0.0, 0.0, -1.0]])) * np.pi
    array([12.,  0.])
    """
    domain = check_choice(domain, "domain", _DOMAINS)
    if domain == "sphere":
        value = INV_4PI

        def uniform_sphere_pdf(d: npt.ArrayLike) -> Float64Array:
            d = check_directions(d, "d")
            return np.full(d.shape[:-1], value)

        return uniform_sphere_pdf
    if domain == "hemisphere":
        value = INV_2PI

        def uniform_hemisphere_pdf(d: npt.ArrayLike) -> Float64Array:
            d = check_directions(d, "d")
            return np.where(d[..., 2] >= 0, value, 0.0)

        return uniform_hemisphere_pdf

    value = T0_DENSITY

    def uniform_triangle_pdf(d: npt.ArrayLike) -> Float64Array:
        d = check_directions(d, "d")
        x, y, z = d[..., 0], d[..., 1], d[..., 2]
        inside = (z - x >= -_EDGE_TOL) & (x - y >= -_EDGE_TOL) & (y >= -_EDGE_TOL)
        return np.where(inside, value, 0.0)

    return uniform_triangle_pdf


def one_per_orbit(directions: npt.ArrayLike, orbit_size: Literal[48, 24], rng: RNGLike = None) -> FloatArray:
    """One randomly chosen row of each orbit: independent directions.

    The 48 (hemisphere: 24) rows of an orbit of :func:`symsphere.sample_sphere`
    are mirror images of one another, not independent samples, and a chi-square
    test on all of them gives meaningless p-values (symmetric bins get equal
    counts).  One member per orbit, chosen independently of the base point,
    gives independent directions with the scheme's marginal density.

    Parameters
    ----------
    directions : array_like, shape (m * orbit_size, 3)
        Consecutive orbits, as the samplers return them.
    orbit_size : {48, 24}
        Rows per orbit.
    rng : None, int, numpy.random.SeedSequence or numpy.random.Generator
        Chooses the members.

    Returns
    -------
    ndarray, shape (m, 3)
        Row i is a member of orbit i (rows ``orbit_size * i`` to ``orbit_size * (i + 1) - 1``).

    Examples
    --------
    >>> from symsphere import sample_sphere
    >>> from symsphere.stats import chi2_test, one_per_orbit, uniform_pdf
    >>> d = one_per_orbit(sample_sphere(48 * 20_000, rng=1), 48, rng=2)
    >>> chi2_test(d, uniform_pdf("sphere"), "sphere").passed
    True
    """
    directions = check_directions(directions, "directions")
    if isinstance(orbit_size, bool) or not isinstance(orbit_size, numbers.Integral) or orbit_size not in (48, 24):
        raise ValueError(f"'orbit_size' must be 48 (sphere) or 24 (hemisphere), got {short_repr(orbit_size)}")
    if directions.ndim != 2 or len(directions) % orbit_size:
        raise ValueError(f"'directions' must have shape (m * {orbit_size}, 3), got {directions.shape}")
    orbits = directions.reshape(-1, orbit_size, 3)
    members = check_rng(rng).integers(orbit_size, size=len(orbits))
    return orbits[np.arange(len(orbits)), members]


# ---------------------------------------------------------------------------
# Private helpers
# ---------------------------------------------------------------------------


def _to_phi_cos(d: Float64Array) -> tuple[Float64Array, Float64Array]:
    """(phi, cos theta) of unit vectors, phi in [-pi, pi) and cos theta in [-1, 1]."""
    phi = np.arctan2(d[..., 1], d[..., 0])
    phi = np.where(phi >= np.pi, -np.pi, phi)
    cos = np.clip(d[..., 2], -1.0, 1.0)
    return phi, cos


def _interval(domain: ChiDomain, shape: tuple[int, int], axis: int, k: int) -> str:
    e = equal_area_bins(domain, shape)[axis]
    return f"[{e[k]:.6g}, {e[k + 1]:.6g}]"


def _default_bins(domain: ChiDomain, n: int) -> tuple[int, int]:
    per_phi_bin = 2 if domain != "triangle" else 1
    r = int(np.clip(math.isqrt(n // (per_phi_bin * _TARGET_PER_BIN)), _MIN_RES, _MAX_RES))
    if domain != "triangle":
        # An even r puts the axes (phi = 0, +-pi/2, pi; cos theta = 0) on bin edges, so that
        # densities singular there, like the paper maps' on the sphere, are not split by a bin.
        r -= r % 2
    return (per_phi_bin * r, r)


def _sidak(significance: float, test_count: int) -> float:
    return float(-math.expm1(math.log1p(-significance) / test_count))


def _histogram(
    d: FloatArray, domain: ChiDomain, shape: tuple[int, int], boundary_tol: float
) -> tuple[IntArray, list[str]]:
    """Counts per bin and a list of problems (samples that are not in the domain)."""
    problems = []
    d64 = d.astype(np.float64)
    norm = np.linalg.norm(d64, axis=1)
    bad_norm = off_unit(d64, _NORM_TOL)
    v = np.divide(d64, norm[:, None], out=np.zeros_like(d64), where=norm[:, None] > 0)
    x, y, z = v[:, 0], v[:, 1], v[:, 2]
    if domain == "sphere":
        outside = np.zeros(len(v), dtype=bool)
        where = ""
    elif domain == "hemisphere":
        outside = z < -boundary_tol
        where = "the hemisphere (z < 0)"
    else:
        outside = (z - x < -boundary_tol) | (x - y < -boundary_tol) | (y < -boundary_tol)
        where = "the triangle T0 = {z >= x >= y >= 0}"
    outside &= ~bad_norm
    n = len(v)
    if np.any(bad_norm):
        k = int(np.argmax(bad_norm))
        problems.append(
            f"{int(bad_norm.sum())} of {n} samples are not unit vectors "
            f"(| |d| - 1 | > {_NORM_TOL:g}), e.g. sample {k} = {d64[k].tolist()}"
        )
    if np.any(outside):
        k = int(np.argmax(outside))
        problems.append(f"{int(outside.sum())} of {n} samples lie outside {where}, e.g. sample {k} = {d64[k].tolist()}")

    phi, cos = _to_phi_cos(v[~(bad_norm | outside)])
    phi_edges, cos_edges = equal_area_bins(domain, (1, 1))  # the domain's rectangle
    p0, p1, c0, c1 = float(phi_edges[0]), float(phi_edges[1]), float(cos_edges[0]), float(cos_edges[1])
    i = np.floor((phi - p0) * (shape[0] / (p1 - p0)))
    j = np.floor((cos - c0) * (shape[1] / (c1 - c0)))
    i = np.clip(i, 0, shape[0] - 1).astype(np.int64)
    j = np.clip(j, 0, shape[1] - 1).astype(np.int64)
    counts = np.bincount(i * shape[1] + j, minlength=shape[0] * shape[1])
    return counts.astype(np.int64).reshape(shape), problems


def _pearson(observed: IntArray, expected: Float64Array, min_expected: float) -> tuple[float, int, str]:
    """Pearson's statistic with pooling of small cells; returns (stat, dof, note)."""
    o = observed.ravel().astype(np.float64)
    e = expected.ravel()
    positive = e > 0
    small = positive & (e < min_expected)
    large_idx = np.flatnonzero(positive & ~small)
    large_idx = large_idx[np.argsort(e[large_idx], kind="stable")]
    pooled_o, pooled_e = float(o[small].sum()), float(e[small].sum())
    n_pooled = int(small.sum())
    start = 0
    if n_pooled:
        # Grow the pooled cell with the smallest large cells until it is large enough.
        while pooled_e < min_expected and start < len(large_idx):
            k = large_idx[start]
            pooled_o += o[k]
            pooled_e += e[k]
            n_pooled += 1
            start += 1
    keep = large_idx[start:]
    stat = float(np.sum((o[keep] - e[keep]) ** 2 / e[keep]))
    cells = len(keep)
    if n_pooled:
        stat += (pooled_o - pooled_e) ** 2 / pooled_e
        cells += 1
    note = f" ({n_pooled} bins pooled into one cell)" if n_pooled > 1 else ""
    return stat, cells - 1, note
