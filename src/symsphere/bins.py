"""Equal-area bins on the sphere, the hemisphere and T0, and a density's integrals over them.

The chi-square test of :mod:`symsphere.stats` histograms direction samples on
these bins and compares the counts with the bins' probabilities under the
claimed density.  Three domains are supported.  Each is a rectangle in the
coordinates (phi, cos theta), with phi = atan2(y, x) and cos theta = z:

========== ====================== ==========================
domain     phi                    cos theta
========== ====================== ==========================
sphere     [-pi, pi)              [-1, 1]
hemisphere [-pi, pi)              [0, 1]
triangle   [0, pi/4]              [1/sqrt 3, 1]
========== ====================== ==========================

The ``'triangle'`` rectangle is the bounding rectangle of the fundamental
spherical triangle T0 = {z >= x >= y >= 0} (area pi/12), which in these
coordinates is phi in [0, pi/4], cos theta >= cos theta_max(phi) with
cos theta_max(phi) = cos phi / sqrt(1 + cos^2 phi).  Since d(omega) =
d(phi) d(cos theta), a regular grid in (phi, cos theta) has bins of equal
solid angle.
"""

from __future__ import annotations

import math

import numpy as np

from ._typing import ChiDomain, Density, Float64Array
from ._validation import MAX_QUADRATURE_ORDER, check_bins, check_choice, check_count, check_pdf

__all__ = ["bin_probabilities", "equal_area_bins"]

_DOMAINS: tuple[ChiDomain, ...] = ("sphere", "hemisphere", "triangle")

# (phi_min, phi_max, cos_min, cos_max) of each domain's rectangle.
_RECTANGLES = {
    "sphere": (-math.pi, math.pi, -1.0, 1.0),
    "hemisphere": (-math.pi, math.pi, 0.0, 1.0),
    "triangle": (0.0, math.pi / 4, 1.0 / math.sqrt(3.0), 1.0),
}

# Adaptive quadrature: a bin's rule is refined by quartering while it changes the
# bin's probability by more than _REFINE_TOL, at most _REFINE_LEVELS times.
_REFINE_TOL = 1e-9
_REFINE_LEVELS = 12


def bin_probabilities(
    pdf: Density,
    domain: ChiDomain = "sphere",
    bins: tuple[int, int] = (32, 16),
    *,
    quadrature_order: int = 12,
) -> Float64Array:
    """Integrals of a density over the equal-area bins of a domain.

    Parameters
    ----------
    pdf : callable
        Density with respect to solid angle, as for :func:`symsphere.stats.chi2_test`.
    domain : {'sphere', 'hemisphere', 'triangle'}, optional
        Default is 'sphere'.
    bins : tuple of two int, optional
        ``(n_phi, n_cos)``.  Default is (32, 16).
    quadrature_order : int, optional
        Gauss-Legendre points per axis (and per piece, see Notes).  Default 12.

    Returns
    -------
    ndarray, shape bins
        ``P[i, j]`` is the integral of `pdf` over the bin
        ``phi_edges[i:i+2] x cos_edges[j:j+2]`` of :func:`equal_area_bins`.

    Notes
    -----
    With d(omega) = d(phi) d(cos theta), each bin's integral is computed by a
    tensor Gauss-Legendre rule in phi and in a variable u that makes the
    integrand smooth at the nearer pole: on bins whose centre has
    cos theta >= 0, ``cos theta = 1 - u**2`` (so ``d cos theta = 2 u du`` and
    ``sin theta = u sqrt(2 - u**2)``), on the others ``cos theta = -1 + u**2``.
    A density with a ``1/sin theta`` singularity at a pole thus becomes
    bounded and smooth in u, and is integrated to near machine precision.

    For ``domain='triangle'`` the pdf is taken to vanish outside T0, whose
    lower boundary cos theta_max(phi) = cos phi / sqrt(1 + cos^2 phi) cuts
    through the bins.  The inner (u) rule is therefore applied, at each
    phi node, on ``cos theta in [max(c0, cos theta_max(phi)), c1]`` only, and
    the phi interval of each bin is split where cos theta_max(phi) crosses
    c0 and c1 (there ``phi = atan2(sqrt(1 - 2 c**2), c)``), so that on each
    of the up to three pieces the inner integral is a smooth function of
    phi.  No discontinuity is then integrated over, and the per-bin
    integrals of the uniform density, or of any density smooth on T0 (also
    with a 1/sin theta pole), are accurate to about 1e-12 relative with the
    default order; on 64 x 64 bins the worst bin, a sliver of T0 with 5e-8
    of its area, is within 6e-9 relative, and the total is 1 within 1e-15.

    The rule is adaptive: each bin's value is compared with the sum of the
    same rule on its four quarters, and bins where they differ by more than
    1e-9 are quartered again (at most 12 times).  Densities with a kink or
    an integrable point singularity inside or on the corner of a bin, such
    as the paper maps' sphere densities at the axes, are thereby integrated
    to about 1e-7 in total.

    Examples
    --------
    >>> from symsphere.bins import bin_probabilities
    >>> from symsphere.stats import uniform_pdf
    >>> p = bin_probabilities(uniform_pdf("triangle"), "triangle", (8, 8))
    >>> p.shape, round(float(p.sum()), 12)
    ((8, 8), 1.0)
    """
    pdf = check_pdf(pdf)
    domain = check_choice(domain, "domain", _DOMAINS)
    shape = check_bins(bins)
    quadrature_order = check_count(quadrature_order, "quadrature_order", maximum=MAX_QUADRATURE_ORDER)
    return _bin_probabilities(pdf, domain, shape, quadrature_order)


def equal_area_bins(
    domain: ChiDomain = "sphere", bins: tuple[int, int] = (32, 16)
) -> tuple[Float64Array, Float64Array]:
    """Edges of the regular (phi, cos theta) grid of a domain's rectangle.

    Parameters
    ----------
    domain : {'sphere', 'hemisphere', 'triangle'}, optional
        Default is 'sphere'.
    bins : tuple of two int, optional
        ``(n_phi, n_cos)``.  Default is (32, 16).

    Returns
    -------
    phi_edges : ndarray, shape (n_phi + 1,)
    cos_edges : ndarray, shape (n_cos + 1,)
        Every bin has solid angle ``dphi * dcos``; for the triangle only the
        part of a bin inside T0 belongs to the domain.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.bins import equal_area_bins
    >>> phi, cos = equal_area_bins("hemisphere", (4, 2))
    >>> phi / np.pi
    array([-1. , -0.5,  0. ,  0.5,  1. ])
    >>> cos
    array([0. , 0.5, 1. ])
    """
    domain = check_choice(domain, "domain", _DOMAINS)
    shape = check_bins(bins)
    return _edges(domain, shape)


# ---------------------------------------------------------------------------
# Private helpers
# ---------------------------------------------------------------------------


def _edges(domain: str, shape: tuple[int, int]) -> tuple[Float64Array, Float64Array]:
    p0, p1, c0, c1 = _RECTANGLES[domain]
    return np.linspace(p0, p1, shape[0] + 1), np.linspace(c0, c1, shape[1] + 1)


def _cos_theta_max(phi: Float64Array) -> Float64Array:
    """Lower boundary of T0 in cos theta: cos phi / sqrt(1 + cos^2 phi)."""
    c = np.cos(phi)
    return c / np.sqrt(1.0 + c * c)


def _phi_crossing(c: Float64Array) -> Float64Array:
    """The phi at which cos theta_max(phi) = c (decreasing in c).

    Valid for c in [1/sqrt 3, 1]: 0 for c >= 1/sqrt 2, pi/4 at c = 1/sqrt 3.
    Smaller c give phi > pi/4, which callers clip.
    """
    return np.arctan2(np.sqrt(np.maximum(1.0 - 2.0 * c * c, 0.0)), c)


def _bin_probabilities(pdf: Density, domain: str, shape: tuple[int, int], order: int) -> Float64Array:
    """Adaptive quadrature of `pdf` over all bins (see bin_probabilities).

    Each rectangle's rule is checked against the sum of the same rule on its
    four quarters; rectangles where the two differ by more than
    ``_REFINE_TOL`` are split and checked again, up to ``_REFINE_LEVELS``
    times.  Smooth bins stop at once; bins with a kink or an integrable
    singularity inside (the paper maps' 1/r points on the sphere sit at bin
    corners, with kinks along the symmetry planes through them) are refined
    where needed.
    """
    phi_edges, cos_edges = _edges(domain, shape)
    pa, ca = np.meshgrid(phi_edges[:-1], cos_edges[:-1], indexing="ij")
    pb, cb = np.meshgrid(phi_edges[1:], cos_edges[1:], indexing="ij")
    rects = np.stack([a.ravel() for a in (pa, pb, ca, cb)], axis=1)  # (B, 4)
    owner = np.arange(len(rects))
    values = _rectangle_integrals(pdf, domain, rects, order)
    prob = np.zeros(len(rects))
    for level in range(_REFINE_LEVELS + 1):
        pm, cm = 0.5 * (rects[:, 0] + rects[:, 1]), 0.5 * (rects[:, 2] + rects[:, 3])
        quarters = np.stack(
            [
                np.stack([rects[:, 0], pm, rects[:, 2], cm], axis=1),
                np.stack([pm, rects[:, 1], rects[:, 2], cm], axis=1),
                np.stack([rects[:, 0], pm, cm, rects[:, 3]], axis=1),
                np.stack([pm, rects[:, 1], cm, rects[:, 3]], axis=1),
            ],
            axis=1,
        )  # (R, 4, 4)
        quarter_values = _rectangle_integrals(pdf, domain, quarters.reshape(-1, 4), order).reshape(-1, 4)
        refined = quarter_values.sum(axis=1)
        done = np.abs(refined - values) <= _REFINE_TOL
        if level == _REFINE_LEVELS:
            done[:] = True
        np.add.at(prob, owner[done], refined[done])
        todo = ~done
        rects = quarters[todo].reshape(-1, 4)
        values = quarter_values[todo].ravel()
        owner = np.repeat(owner[todo], 4)
        if not len(rects):
            break
    return prob.reshape(shape)


def _rectangle_integrals(pdf: Density, domain: str, rects: Float64Array, order: int) -> Float64Array:
    """Tensor Gauss-Legendre integrals of `pdf` over rectangles (phi0, phi1, cos0, cos1)."""
    x, w = np.polynomial.legendre.leggauss(order)
    pa, pb, ca, cb = rects.T  # (B,)

    if domain == "triangle":
        # Split phi where the boundary crosses cb and ca (crossing(cb) <= crossing(ca)).
        b1 = np.clip(_phi_crossing(cb), pa, pb)
        b2 = np.clip(_phi_crossing(ca), b1, pb)
        breaks = np.stack([pa, b1, b2, pb], axis=1)
    else:
        breaks = np.stack([pa, pb], axis=1)
    lo, hi = breaks[:, :-1], breaks[:, 1:]  # (B, P)
    half = 0.5 * (hi - lo)
    phi = (0.5 * (hi + lo))[..., None] + half[..., None] * x  # (B, P, q)
    w_phi = half[..., None] * w

    c_lo = np.broadcast_to(ca[:, None, None], phi.shape)
    c_hi = np.broadcast_to(cb[:, None, None], phi.shape)
    if domain == "triangle":
        c_lo = np.minimum(np.maximum(c_lo, _cos_theta_max(phi)), c_hi)

    north = ((ca + cb) >= 0)[:, None, None]
    u_lo = np.where(north, np.sqrt(1.0 - c_hi), np.sqrt(1.0 + c_lo))
    u_hi = np.where(north, np.sqrt(1.0 - c_lo), np.sqrt(1.0 + c_hi))
    u_half = 0.5 * (u_hi - u_lo)
    u = (0.5 * (u_hi + u_lo))[..., None] + u_half[..., None] * x  # (B, P, q, q)
    weight = (w_phi * u_half)[..., None] * w * (2.0 * u)

    usq = u * u
    cos = np.where(north[..., None], 1.0 - usq, usq - 1.0)
    sin = u * np.sqrt(np.maximum(2.0 - usq, 0.0))
    phi4 = phi[..., None]
    nodes = np.stack(np.broadcast_arrays(sin * np.cos(phi4), sin * np.sin(phi4), cos), axis=-1).reshape(-1, 3)

    values = _evaluate_pdf(pdf, nodes)
    integrals: Float64Array = (values.reshape(weight.shape) * weight).sum(axis=(1, 2, 3))
    return integrals


def _endpoint_graded_rule(order: int) -> tuple[Float64Array, Float64Array]:
    """Gauss-Legendre on [-1, 1] after Sidi's sin^2 transformation.

    t -> t - sin(2 pi t) / (2 pi) on [0, 1] has a derivative 1 - cos(2 pi t)
    that vanishes quadratically at both ends, so nodes crowd towards the bin
    edges.  A density with an integrable singularity on a bin edge or corner
    (1/r at an axis, as the paper maps have on the sphere) becomes bounded and
    is integrated accurately; smooth densities still converge spectrally.
    """
    x, w = np.polynomial.legendre.leggauss(order)
    t = 0.5 * (x + 1.0)
    graded = t - np.sin(2.0 * np.pi * t) / (2.0 * np.pi)
    return 2.0 * graded - 1.0, w * (1.0 - np.cos(2.0 * np.pi * t))


def _evaluate_pdf(pdf: Density, nodes: Float64Array) -> Float64Array:
    m = nodes.shape[0]
    out = pdf(nodes)
    try:
        values = np.asarray(out, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"'pdf' must return an array of real numbers, got {type(out).__name__}") from exc
    if values.ndim == 0:
        values = np.full(m, float(values))
    if values.shape != (m,):
        raise ValueError(f"'pdf' must return shape (m,) = ({m},) for directions of shape ({m}, 3), got {values.shape}")
    bad = ~np.isfinite(values)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise ValueError(
            f"'pdf' returned non-finite values at {int(bad.sum())} of {m} quadrature "
            f"nodes, e.g. {values[k]} at direction {nodes[k].tolist()}"
        )
    neg = values < 0
    if np.any(neg):
        k = int(np.argmax(neg))
        raise ValueError(
            f"'pdf' returned negative densities at {int(neg.sum())} of {m} quadrature "
            f"nodes, e.g. {values[k]} at direction {nodes[k].tolist()}"
        )
    return values
