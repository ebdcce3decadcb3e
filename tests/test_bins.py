"""Tests of symsphere.bins: the equal-area bins and the quadrature of densities over them.

The reference densities are written in closed form (as in tests/test_stats.py,
whose chi-square tests use the same ones), and per-bin integrals are checked
against antiderivatives.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from references import LINEAR_NORM, cmax, cosine_pdf, linear_triangle_pdf, pole_pdf
from scipy import optimize

from symsphere import bins, stats
from symsphere.bins import bin_probabilities, equal_area_bins
from symsphere.stats import uniform_pdf

INV_SQRT3 = 1.0 / math.sqrt(3.0)


# ---------------------------------------------------------------------------
# Reference densities
# ---------------------------------------------------------------------------


# ---- exact per-bin integrals on T0 from antiderivatives in phi ----------------


def _crossing(c, a, b):
    """phi in [a, b] with cmax(phi) = c, if cmax - c changes sign there."""
    fa, fb = cmax(a) - c, cmax(b) - c
    if fa * fb < 0:
        return optimize.brentq(lambda p: cmax(p) - c, a, b, xtol=1e-15, rtol=1e-15)
    return None


def exact_triangle_bins(bins, kind):
    """Per-bin integrals over bin & T0 of: 'uniform' (12/pi), 'linear', 'pole'.

    Inner integrals in c over [lo, c1] with lo = c0 or cmax(phi):
      uniform: 12/pi (c1 - lo);  int cmax dphi = asin(sin(phi)/sqrt 2)
      linear:  K (c1^2 - lo^2)/2;  int cmax^2 dphi = phi - atan(tan(phi)/sqrt 2)/sqrt 2
      pole:    4 cos(phi)/pi (t(lo) - t(c1)), t(c) = sqrt(1-c^2)/c, t(cmax) = 1/cos(phi)
    """
    phi_e = np.linspace(0, np.pi / 4, bins[0] + 1)
    cos_e = np.linspace(INV_SQRT3, 1, bins[1] + 1)
    out = np.zeros(bins)
    s2 = math.sqrt(2)

    def t(c):
        return math.sqrt(1 - c * c) / c

    for i in range(bins[0]):
        for j in range(bins[1]):
            a, b = phi_e[i], phi_e[i + 1]
            c0, c1 = cos_e[j], cos_e[j + 1]
            pts = sorted({a, b} | {p for p in (_crossing(c0, a, b), _crossing(c1, a, b)) if p})
            total = 0.0
            for p, q in zip(pts[:-1], pts[1:], strict=False):
                m = cmax(0.5 * (p + q))
                if m >= c1:
                    continue  # piece entirely outside T0
                if m <= c0:  # full rectangle piece
                    if kind == "uniform":
                        total += 12 / np.pi * (c1 - c0) * (q - p)
                    elif kind == "linear":
                        total += LINEAR_NORM * (c1**2 - c0**2) / 2 * (q - p)
                    else:
                        total += 4 / np.pi * (t(c0) - t(c1)) * (math.sin(q) - math.sin(p))
                else:  # lower limit is the boundary cmax(phi)
                    if kind == "uniform":

                        def F(x):
                            return c1 * x - math.asin(math.sin(x) / s2)

                        total += 12 / np.pi * (F(q) - F(p))
                    elif kind == "linear":

                        def F(x):
                            return (c1**2 * x - x + math.atan(math.tan(x) / s2) / s2) / 2

                        total += LINEAR_NORM * (F(q) - F(p))
                    else:
                        total += 4 / np.pi * ((q - p) - t(c1) * (math.sin(q) - math.sin(p)))
            out[i, j] = total
    return out


# ---------------------------------------------------------------------------
# Quadrature accuracy
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("domain", ["sphere", "hemisphere"])
def test_uniform_bins_have_equal_solid_angle(domain):
    bins = (12, 6)
    p = bin_probabilities(uniform_pdf(domain), domain, bins)
    np.testing.assert_allclose(p, 1 / (12 * 6), rtol=1e-12)


@pytest.mark.parametrize("bins", [(4, 2), (32, 16), (64, 32)])
def test_cosine_integral_per_bin(bins):
    # int_bin cos(theta)/pi d(omega) = dphi (c1^2 - c0^2) / (2 pi)
    phi_e, cos_e = equal_area_bins("hemisphere", bins)
    exact = np.outer(np.diff(phi_e), np.diff(cos_e**2)) / (2 * np.pi)
    p = bin_probabilities(cosine_pdf, "hemisphere", bins)
    np.testing.assert_allclose(p, exact, rtol=1e-12, atol=0)
    assert abs(p.sum() - 1) < 1e-12


@pytest.mark.parametrize(
    "kind,pdf", [("uniform", uniform_pdf("triangle")), ("linear", linear_triangle_pdf), ("pole", pole_pdf)]
)
@pytest.mark.parametrize("bins", [(5, 7), (16, 16), (31, 31), (64, 64)])
def test_triangle_bins_match_antiderivatives(kind, pdf, bins):
    """Bins cut by the T0 boundary, and the pole bins, are integrated to 1e-6 relative."""
    exact = exact_triangle_bins(bins, kind)
    p = bin_probabilities(pdf, "triangle", bins)
    assert np.all(p[exact == 0] == 0)  # bins entirely outside T0 are exactly 0
    nz = exact > 0
    rel = np.abs(p[nz] - exact[nz]) / exact[nz]
    assert rel.max() < 1e-6, (kind, bins, rel.max())
    assert abs(p.sum() - 1) < 1e-9
    assert abs(exact.sum() - 1) < 1e-12  # the reference itself is normalised


def test_pole_substitution_matters():
    """The 1/sin(theta) pole density is integrated to 1e-6 only thanks to u-substitution.

    Check the top row of bins against the antiderivative, at a low order where a
    plain rule in cos(theta) would be visibly wrong (about 1e-3 relative).
    """
    bins = (4, 4)
    exact = exact_triangle_bins(bins, "pole")
    p = bin_probabilities(pole_pdf, "triangle", bins, quadrature_order=4)
    rel = np.abs(p[:, -1] - exact[:, -1]) / exact[:, -1]
    assert rel.max() < 1e-6
    # A plain Gauss-Legendre rule in cos theta on the same top row, for contrast.
    x, w = np.polynomial.legendre.leggauss(4)
    phi_e, cos_e = equal_area_bins("triangle", bins)
    c0, c1 = cos_e[-2], cos_e[-1]
    c = (c0 + c1) / 2 + (c1 - c0) / 2 * x
    plain = []
    for i in range(bins[0]):
        ph = (phi_e[i] + phi_e[i + 1]) / 2 + (phi_e[i + 1] - phi_e[i]) / 2 * x
        P, C = np.meshgrid(ph, c, indexing="ij")
        s = np.sqrt(1 - C**2)
        d = np.stack([s * np.cos(P), s * np.sin(P), C], axis=-1).reshape(-1, 3)
        W = np.outer(w * (phi_e[i + 1] - phi_e[i]) / 2, w * (c1 - c0) / 2).ravel()
        plain.append(np.sum(pole_pdf(d) * W))
    plain_rel = np.abs(np.array(plain) - exact[:, -1]) / exact[:, -1]
    assert plain_rel.max() > 1e-3


def test_pole_density_normalised():
    # (16, 16) and (64, 64): test_triangle_bins_match_antiderivatives checks the pole density's sum there, to 1e-9
    assert abs(bin_probabilities(pole_pdf, "triangle", (4, 4)).sum() - 1) < 1e-6


# ---------------------------------------------------------------------------
# Edges, and the names stats re-exports
# ---------------------------------------------------------------------------


def test_the_bins_have_one_home():
    # stats uses the bins but does not list them: their one public home is symsphere.bins
    assert not set(bins.__all__) & set(stats.__all__)


def test_equal_area_bins_edges():
    phi, cos = equal_area_bins("triangle", (4, 3))
    np.testing.assert_allclose(phi, np.linspace(0, np.pi / 4, 5))
    np.testing.assert_allclose(cos, np.linspace(INV_SQRT3, 1, 4))
    phi, cos = equal_area_bins("sphere", (6, 3))
    assert phi[0] == -np.pi and phi[-1] == np.pi and cos[0] == -1 and cos[-1] == 1


# ---------------------------------------------------------------------------
# Adaptive quadrature
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("bins", [(8, 4), (18, 9), (64, 32)])
def test_adaptive_quadrature_handles_corner_singularities(bins):
    """The paper maps' sphere densities have 1/r points on the axes, with kinks
    along the symmetry planes through them; the adaptive rule still integrates
    them to 1 within 1e-6, whether the axes fall on bin corners or inside bins."""
    from symsphere import sphere_pdf

    for method in ("paper1", "paper2"):
        total = bin_probabilities(lambda d: sphere_pdf(d, method), "sphere", bins).sum()
        assert total == pytest.approx(1.0, abs=1e-6)
