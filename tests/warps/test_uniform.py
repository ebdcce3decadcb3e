"""The hat-box maps (square_to_uniform_sphere, square_to_uniform_hemisphere): corners, densities, errors.

The contract every warp keeps (round trips, Jacobian, normalisation, chi-square, numba = numpy) is in
test_registry.py.
"""

import numpy as np
import pytest
from references import ELEMENTARY_ULPS, EPS64

from symsphere.warps import (
    square_to_uniform_hemisphere,
    square_to_uniform_hemisphere_pdf,
    square_to_uniform_sphere,
    square_to_uniform_sphere_pdf,
    uniform_hemisphere_point,
    uniform_hemisphere_to_square,
    uniform_sphere_point,
    uniform_sphere_to_square,
)


def test_corners():
    # The corners map through numpy's sin, cos of multiples of pi/2 (e.g. sin((pi/2)_64) = 1 - 2e-33): exact
    # values, but an implementation within E = ELEMENTARY_ULPS ulps (tests/references.py) may return 1 - E ulp,
    # and the products round once more: (E + 1) eps on unit vectors.
    corner = (ELEMENTARY_ULPS + 1) * EPS64
    np.testing.assert_allclose(square_to_uniform_sphere([[0, 0], [1, 0.3]]), [[0, 0, 1], [0, 0, -1]], atol=corner)
    np.testing.assert_allclose(
        square_to_uniform_hemisphere([[1, 0.3], [0, 0], [0, 0.5]]), [[0, 0, 1], [1, 0, 0], [-1, 0, 0]], atol=corner
    )


def test_height_is_linear_in_u():
    # Archimedes: z = 1 - 2u on the sphere, z = u on the hemisphere, whatever v.
    u = np.linspace(0, 1, 11)
    uv = np.column_stack([u, np.full_like(u, 0.37)])
    np.testing.assert_allclose(square_to_uniform_sphere(uv)[:, 2], 1 - 2 * u, rtol=0, atol=1e-15)
    np.testing.assert_allclose(square_to_uniform_hemisphere(uv)[:, 2], u, rtol=0, atol=1e-15)


def test_densities():
    d = np.array([[0.0, 0.6, 0.8], [0.0, 0.6, -0.8]])
    np.testing.assert_array_equal(square_to_uniform_sphere_pdf(d), [1 / (4 * np.pi)] * 2)
    np.testing.assert_array_equal(square_to_uniform_hemisphere_pdf(d), [1 / (2 * np.pi), 0.0])


def test_elementwise_is_the_array_map():
    uv = np.random.default_rng(1).random((50, 2))
    np.testing.assert_array_equal(np.stack(uniform_sphere_point(uv[:, 0], uv[:, 1]), -1), square_to_uniform_sphere(uv))
    np.testing.assert_array_equal(
        np.stack(uniform_hemisphere_point(uv[:, 0], uv[:, 1]), -1), square_to_uniform_hemisphere(uv)
    )


def test_inverse_at_the_poles_gives_v_zero():
    np.testing.assert_array_equal(uniform_sphere_to_square([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]), [[0, 0], [1, 0]])
    np.testing.assert_array_equal(uniform_hemisphere_to_square([0.0, 0.0, 1.0]), [1.0, 0.0])


@pytest.mark.parametrize(
    "call, error, word",
    [
        (lambda: square_to_uniform_sphere([1.5, 0.2]), ValueError, "'uv'"),
        (lambda: uniform_sphere_to_square([1.0, 0.0]), ValueError, "'d'"),
        (lambda: square_to_uniform_sphere_pdf([[1, 2]]), ValueError, "'d'"),
        (lambda: uniform_hemisphere_to_square([0.0, 0.6, -0.8]), ValueError, "'d'"),
        (lambda: uniform_sphere_point(0.5, np.nan), ValueError, "'v'"),
    ],
)
def test_bad_input(call, error, word):
    with pytest.raises(error, match=word):
        call()
