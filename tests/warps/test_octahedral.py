"""Clarberg's octahedral maps (square_to_octahedral_sphere, square_to_octahedral_hemisphere).

The contract every warp keeps is in test_registry.py.
"""

import numpy as np
import pytest
from references import ELEMENTARY_ULPS, EPS64

from symsphere.warps import (
    octahedral_hemisphere_to_square,
    octahedral_sphere_point,
    square_to_octahedral_hemisphere,
    square_to_octahedral_hemisphere_pdf,
    square_to_octahedral_sphere,
    square_to_octahedral_sphere_pdf,
)


def test_corners():
    # As in test_uniform.py: (E + 1) eps on unit vectors.
    corner = (ELEMENTARY_ULPS + 1) * EPS64
    np.testing.assert_allclose(
        square_to_octahedral_sphere([[0.5, 0.5], [0, 0], [1, 1], [0, 1], [1, 0]]),
        [[0, 0, 1]] + [[0, 0, -1]] * 4,
        atol=corner,
    )
    np.testing.assert_allclose(
        square_to_octahedral_sphere([[1, 0.5], [0.5, 1], [0, 0.5], [0.5, 0]]),
        [[1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0]],
        atol=corner,
    )
    np.testing.assert_allclose(
        square_to_octahedral_hemisphere([[0.5, 0.5], [1, 1], [0, 1], [0, 0], [1, 0]]),
        [[0, 0, 1], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0]],
        atol=corner,
    )


def _jacobian(forward, uv, h=1e-6):
    du, dv = np.array([h, 0.0]), np.array([0.0, h])
    fu = (forward(uv + du) - forward(uv - du)) / (2 * h)
    fv = (forward(uv + dv) - forward(uv - dv)) / (2 * h)
    return np.linalg.norm(np.cross(fu, fv), axis=-1)


def test_octahedral_density_is_uniform():
    # Clarberg's map is equal-area: |J| = 4 pi everywhere (the sphere has area 4 pi), away from its kinks
    # (u, v = 1/2, |a| + |b| = 1, |a| = |b| with (a, b) = 2 (u, v) - 1).
    uv = 1e-3 + (1 - 2e-3) * np.random.default_rng(5).random((20_000, 2))
    a, b = 2 * uv[:, 0] - 1, 2 * uv[:, 1] - 1
    ok = (np.abs(a) > 1e-3) & (np.abs(b) > 1e-3) & (np.abs(np.abs(a) + np.abs(b) - 1) > 1e-3)
    uv = uv[ok & (np.abs(np.abs(a) - np.abs(b)) > 1e-3)][:5000]
    np.testing.assert_allclose(_jacobian(square_to_octahedral_sphere, uv), 4 * np.pi, rtol=2e-7)
    np.testing.assert_allclose(_jacobian(square_to_octahedral_hemisphere, uv), 2 * np.pi, rtol=2e-7)


def test_densities():
    d = np.array([[0.0, 0.6, 0.8], [0.0, 0.6, -0.8]])
    np.testing.assert_array_equal(square_to_octahedral_sphere_pdf(d), [1 / (4 * np.pi)] * 2)
    np.testing.assert_array_equal(square_to_octahedral_hemisphere_pdf(d), [1 / (2 * np.pi), 0.0])


def test_elementwise_is_the_array_map():
    uv = np.concatenate([np.random.default_rng(1).random((50, 2)), [[0, 0], [1, 1], [0.5, 0.5], [0.25, 0.75]]])
    np.testing.assert_array_equal(
        np.stack(octahedral_sphere_point(uv[:, 0], uv[:, 1]), -1), square_to_octahedral_sphere(uv)
    )


@pytest.mark.parametrize(
    "call, error, word",
    [
        (lambda: square_to_octahedral_sphere([[0.5, np.nan]]), ValueError, "'uv'"),
        (lambda: octahedral_hemisphere_to_square([0.0, 0.6, -0.8]), ValueError, "'d'"),
        (lambda: square_to_octahedral_hemisphere_pdf([0.0, 1.0]), ValueError, "'d'"),
        (lambda: octahedral_sphere_point(1.5, 0.5), ValueError, "'u'"),
    ],
)
def test_bad_input(call, error, word):
    with pytest.raises(error, match=word):
        call()


def test_compiled_formula_at_the_edges_and_corners():
    # The square's edges and corners, where the map folds: the formula numba compiles (the study's
    # compiled octahedral peer runs it) gives the numpy map's directions there, within the error model's
    # bound for one sine and one cosine of the same angle times the same factor (2E + 1 eps, absolute).
    from numba import njit

    @njit
    def compiled(uv, out):
        for i in range(uv.shape[0]):
            out[i, 0], out[i, 1], out[i, 2] = octahedral_sphere_point(uv[i, 0], uv[i, 1])

    values = np.array([0.0, 1e-300, 0.25, 0.5, 0.75, 1 - 1e-16, 1.0])
    uv = np.array([[a, b] for a in values for b in values])
    out = np.empty((len(uv), 3))
    compiled(uv, out)
    assert np.all(np.isfinite(out))
    assert np.max(np.abs(out - square_to_octahedral_sphere(uv))) <= (2 * ELEMENTARY_ULPS + 1) * EPS64
