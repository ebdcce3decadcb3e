"""symsphere.render._directions: the renderer's direction sampling at diffuse vertices and its densities.

Through the test kernels of ``render/_probes.py`` (the very functions the path tracer inlines): the
symmetric groups take every orbit member (or wedge image) of one base point, members are shuffled
between vertices, every strategy's weights and pdfs equal their closed forms (the orbit's from
``warps.square_to_triangle_pdf``, the fold from ``symmetry.fold``: independent of the kernel), and
``bsdf_pdf`` integrates to one.  Statistical checks use fixed seeds and a Sidak correction so that a
correct sampler fails the family with probability FAMILY_SIGNIFICANCE = 0.01.
"""

import math

import numpy as np
import pytest
from scipy import stats

from symsphere._testing import kernels
from symsphere._testing import render_directions as D
from symsphere._testing import render_probes as P
from symsphere.symmetry import fold, orbit
from symsphere.warps import WEDGE_MAPS, square_to_triangle_pdf

METHOD_CODES = kernels.METHOD_CODES
FAMILY_SIGNIFICANCE = 0.01


def _sidak(tests, family=FAMILY_SIGNIFICANCE):
    """Per-test significance so that `tests` independent tests fail with probability `family` together."""
    return 1 - (1 - family) ** (1 / tests)


# --- the samplers ----------------------------------------------------------------

_ORBIT_SAMPLERS = [
    ("symmetric", D.SYMMETRIC), ("symmetric_sobol", D.SYMMETRIC_SOBOL),
    ("symmetric_sobol_interlaced2", D.SYMMETRIC_SOBOL_INTERLACED2),
    ("symmetric_sobol_interlaced3", D.SYMMETRIC_SOBOL_INTERLACED3),
]  # fmt: skip


@pytest.mark.parametrize("full, n", [(False, 24), (True, 48)])
@pytest.mark.parametrize("name, sampler", _ORBIT_SAMPLERS)
@pytest.mark.parametrize("method", ["equal_area", "paper1"])
def test_symmetric_groups_take_every_orbit_member_of_one_base(name, sampler, method, full, n):
    code = METHOD_CODES[method]
    groups = 3
    for depth in (0, 1, 5):
        out = P.pattern_directions(sampler, code, full, np.uint64(7), 1234, depth, groups * n)
        bases = []
        for g in range(groups):
            block = out[g * n : (g + 1) * n, :3]
            members, base = fold(block, domain="sphere")
            # one base point for the whole group...
            np.testing.assert_allclose(base, np.broadcast_to(base[0], base.shape), rtol=0, atol=1e-15)
            # ...and every member of its orbit exactly once (hemisphere: the 24 upper ones)
            assert sorted(members.tolist()) == list(range(n))
            np.testing.assert_array_equal(block[np.argsort(members)], orbit(base[0], domain="sphere")[:n])
            # weight = |cos| / (pi pdf), pdf = triangle pdf / n
            pdf = square_to_triangle_pdf(base[0], method) / n
            np.testing.assert_allclose(out[g * n : (g + 1) * n, 3], np.abs(block[:, 2]) / (np.pi * pdf), rtol=1e-12)
            bases.append(base[0])
        assert len({tuple(b) for b in bases}) == groups  # a fresh base point per group


def test_symmetric_members_are_shuffled_between_vertices():
    """Sample s must not keep member s mod 24 at every vertex (that would confine it to one triangle)."""
    members = []
    for depth in range(6):
        out = P.pattern_directions(D.SYMMETRIC, 0, False, np.uint64(3), 99, depth, 24)
        members.append(fold(out[:, :3], domain="sphere")[0])
    assert len({tuple(m) for m in members}) > 1


_INTERLACED_CODES = [
    D.SYMMETRIC_SOBOL_INTERLACED2, D.SYMMETRIC_SOBOL_INTERLACED3,
    D.SYMMETRIC_COSINE_SOBOL_INTERLACED2, D.SYMMETRIC_COSINE_SOBOL_INTERLACED3,
]  # fmt: skip
_ALL_CODES = [
    D.UNIFORM, D.COSINE, D.ORBIT, D.SYMMETRIC, D.SYMMETRIC_SOBOL, D.SYMMETRIC_COSINE, D.SYMMETRIC_COSINE_SOBOL,
    *_INTERLACED_CODES,
]  # fmt: skip
_COSINE_CODES = (
    D.COSINE, D.SYMMETRIC_COSINE, D.SYMMETRIC_COSINE_SOBOL, D.SYMMETRIC_COSINE_SOBOL_INTERLACED2,
    D.SYMMETRIC_COSINE_SOBOL_INTERLACED3,
)  # fmt: skip


@pytest.mark.parametrize("full", [False, True])
@pytest.mark.parametrize("sampler", _ALL_CODES)
def test_sampled_directions_weights_and_pdfs(sampler, full):
    """Weights |cos| / (pi pdf) and pdfs of every sampler against their closed forms (orbit: warps.square_to_triangle_pdf)."""
    code = METHOD_CODES["paper1"]
    out = P.pattern_directions(sampler, code, full, np.uint64(11), 5, 2, 480)
    directions, weights, pdfs = out[:, :3], out[:, 3], out[:, 4]
    np.testing.assert_allclose(np.linalg.norm(directions, axis=1), 1.0, rtol=0, atol=1e-14)
    if not full:
        assert np.all(directions[:, 2] >= 0)
    else:
        assert np.any(directions[:, 2] < 0)
    z = np.abs(directions[:, 2])
    if sampler in _COSINE_CODES:
        expected_weight, expected_pdf = np.full_like(z, 2.0 if full else 1.0), z / ((2 if full else 1) * np.pi)
    elif sampler == D.UNIFORM:
        expected_weight, expected_pdf = (4.0 if full else 2.0) * z, np.full_like(z, 1 / ((4 if full else 2) * np.pi))
    else:
        _, base = fold(directions, domain="sphere")
        expected_pdf = square_to_triangle_pdf(base, "paper1") / (48 if full else 24)
        expected_weight = z / (np.pi * expected_pdf)
    np.testing.assert_allclose(weights, expected_weight, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(pdfs, expected_pdf, rtol=1e-12, atol=1e-15)
    # bsdf_pdf, which MIS evaluates at light-sampled directions, is the same density
    np.testing.assert_allclose(P.bsdf_pdfs(sampler, code, full, directions), expected_pdf, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("full, n", [(False, 8), (True, 16)])
@pytest.mark.parametrize(
    "sampler",
    [
        D.SYMMETRIC_COSINE,
        D.SYMMETRIC_COSINE_SOBOL,
        D.SYMMETRIC_COSINE_SOBOL_INTERLACED2,
        D.SYMMETRIC_COSINE_SOBOL_INTERLACED3,
    ],
)
def test_symmetric_cosine_groups_take_the_images_of_one_wedge_point(sampler, full, n):
    """Groups of 8 (16) samples: the 8 z-keeping signed permutations (x {z, -z}) of one cosine wedge point."""
    groups = 4
    for depth in (0, 3):
        out = P.pattern_directions(sampler, 0, full, np.uint64(5), 77, depth, groups * n)
        bases = []
        for g in range(groups):
            block = out[g * n : (g + 1) * n, :3]
            ax, ay = np.abs(block[:, 0]), np.abs(block[:, 1])
            base = np.column_stack([np.maximum(ax, ay), np.minimum(ax, ay), np.abs(block[:, 2])])
            np.testing.assert_array_equal(base, np.broadcast_to(base[0], base.shape))
            images = base[0] @ WEDGE_MAPS  # (8, 3)
            if full:
                images = np.vstack([images, images * [1, 1, -1]])
            assert sorted(map(tuple, block)) == sorted(map(tuple, images))  # every image once
            bases.append(tuple(base[0]))
        assert len(set(bases)) == groups


def test_paper_map_weights_use_their_density():
    out = P.pattern_directions(D.ORBIT, METHOD_CODES["paper2"], False, np.uint64(1), 0, 0, 240)
    _, base = fold(out[:, :3], domain="sphere")
    expected = np.abs(out[:, 2]) * 24 / (np.pi * square_to_triangle_pdf(base, "paper2"))
    np.testing.assert_allclose(out[:, 3], expected, rtol=1e-12)


def test_bsdf_pdfs_integrate_to_one():
    """Monte Carlo over uniform directions: the integral of bsdf_pdf over its domain is 1 (equal-area orbit, classic)."""
    rng = np.random.default_rng(4)
    directions = rng.normal(size=(400_000, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    cases = [(s, full) for s in (D.UNIFORM, D.COSINE, D.ORBIT, D.SYMMETRIC_COSINE) for full in (False, True)]
    critical = stats.norm.isf(_sidak(len(cases)) / 2)
    for sampler, full in cases:
        d = directions if full else np.column_stack([directions[:, 0], directions[:, 1], np.abs(directions[:, 2])])
        values = P.bsdf_pdfs(sampler, METHOD_CODES["equal_area"], full, d) * (4 * np.pi if full else 2 * np.pi)
        error = values.std(ddof=1) / math.sqrt(values.size)
        assert abs(values.mean() - 1) < critical * max(error, 1e-12), (sampler, full, values.mean(), error)
