"""Independent reference densities and quadratures shared by several test files.

Written from their formulas here, not with the code under test.  (tests/ is on pytest's
``pythonpath``: ``from references import ...``.)
"""

import math

import numpy as np

# Linear density on T0: z / int_T0 z d(omega), with int_T0 z = atan(1/sqrt 2) / (2 sqrt 2).
LINEAR_NORM = 2 * math.sqrt(2) / math.atan(1 / math.sqrt(2))


def frame(axis):
    axis = np.asarray(axis, dtype=np.float64)
    axis = axis / np.linalg.norm(axis)
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    t = np.cross(axis, helper)
    t /= np.linalg.norm(t)
    return t, np.cross(axis, t), axis


def cap_rule(axis, cos_lo, cos_hi, n_cos, n_psi):
    """Nodes and weights for the region cos_lo <= w.axis <= cos_hi (GL in cos t x trapezoid in psi)."""
    x, w = np.polynomial.legendre.leggauss(n_cos)
    cos = 0.5 * (cos_hi - cos_lo) * x + 0.5 * (cos_hi + cos_lo)
    wc = 0.5 * (cos_hi - cos_lo) * w
    psi = 2 * np.pi * np.arange(n_psi) / n_psi
    c, p = np.meshgrid(cos, psi, indexing="ij")
    s = np.sqrt(np.maximum(0.0, (1 - c) * (1 + c)))
    t, b, n = frame(axis)
    d = (s * np.cos(p))[..., None] * t + (s * np.sin(p))[..., None] * b + c[..., None] * n
    weights = wc[:, None] * np.full(n_psi, 2 * np.pi / n_psi)
    return d.reshape(-1, 3), weights.ravel()


def in_t0(d):
    x, y, z = d[:, 0], d[:, 1], d[:, 2]
    return (z >= x) & (x >= y) & (y >= 0)


def cosine_pdf(d):
    return np.maximum(d[:, 2], 0) / np.pi


def pole_pdf(d):
    """Density of pole_sampler: 4 x / (pi z^2 (x^2 + y^2)) on T0 (1/sin(theta) at the pole)."""
    x, y, z = d[:, 0], d[:, 1], d[:, 2]
    r2 = x * x + y * y
    inside = in_t0(d) & (r2 > 0)
    safe_r2 = np.where(inside, r2, 1.0)
    safe_z = np.where(inside, z, 1.0)
    return np.where(inside, 4 * x / (np.pi * safe_z**2 * safe_r2), 0.0)


def linear_triangle_pdf(d):
    return np.where(in_t0(d), LINEAR_NORM * d[:, 2], 0.0)


def cmax(phi):
    return np.cos(phi) / np.sqrt(1 + np.cos(phi) ** 2)


def net_t_value(x, m):
    """The smallest t such that every elementary dyadic box of volume 2^-(m - t) holds 2^t of the 2^m points.

    Brute force over every split of the m - t digits among the coordinates: the definition of a
    (t, m, s)-net in base 2, independent of how the points were made.
    """
    n, s = x.shape
    assert n == 2**m
    cells = np.floor(x * 2.0**m).astype(np.int64)  # the leading m digits of each coordinate

    def splits(total, parts):
        if parts == 1:
            yield (total,)
            return
        for first in range(total + 1):
            for rest in splits(total - first, parts - 1):
                yield (first,) + rest

    def box_index(depths):
        index = np.zeros(n, dtype=np.int64)
        for j, k in enumerate(depths):
            index = (index << k) | (cells[:, j] >> (m - k))
        return index

    for t in range(m + 1):
        if all(np.all(np.bincount(box_index(d), minlength=2 ** (m - t)) == 2**t) for d in splits(m - t, s)):
            return t
    raise AssertionError("unreachable: t = m always holds")
