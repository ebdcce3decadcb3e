"""Shirley & Chiu's concentric disk and its lift, the cosine hemisphere (square_to_concentric_disk,
square_to_cosine_hemisphere).

The contract every warp keeps is in test_registry.py.
"""

import numpy as np
import pytest
from references import ELEMENTARY_ULPS, EPS64

from symsphere.warps import (
    concentric_disk_point,
    concentric_disk_to_square,
    cosine_hemisphere_point,
    cosine_hemisphere_to_square,
    square_to_concentric_disk,
    square_to_concentric_disk_pdf,
    square_to_cosine_hemisphere,
    square_to_cosine_hemisphere_pdf,
)


def test_corners():
    # As in test_uniform.py: (E + 1) eps on unit vectors.
    corner = (ELEMENTARY_ULPS + 1) * EPS64
    np.testing.assert_allclose(
        square_to_cosine_hemisphere([[0.5, 0.5], [1, 0.5], [0.5, 1], [0, 0.5]]),
        [[0, 0, 1], [1, 0, 0], [0, 1, 0], [-1, 0, 0]],
        atol=corner,
    )
    np.testing.assert_allclose(
        square_to_concentric_disk([[0.5, 0.5], [1, 0.5], [0.5, 1], [0, 0.5], [0.5, 0]]),
        [[0, 0], [1, 0], [0, 1], [-1, 0], [0, -1]],
        atol=corner,
    )


def test_concentric_squares_go_to_concentric_circles():
    # The square's ring max(|a|, |b|) = rho goes onto the circle of radius rho.
    rng = np.random.default_rng(2)
    rho, t = rng.random(1000), rng.uniform(-1, 1, 1000)
    side = rng.integers(4, size=1000)
    a = np.choose(side, [rho, -rho, rho * t, rho * t])
    b = np.choose(side, [rho * t, rho * t, rho, -rho])
    p = square_to_concentric_disk(np.column_stack([(a + 1) / 2, (b + 1) / 2]))
    np.testing.assert_allclose(np.hypot(p[:, 0], p[:, 1]), rho, rtol=0, atol=1e-15)


def test_densities():
    np.testing.assert_array_equal(square_to_concentric_disk_pdf([[0.0, 1.0], [0.8, 0.8]]), [1 / np.pi, 0.0])
    d = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.6, 0.0, -0.8]])
    np.testing.assert_allclose(square_to_cosine_hemisphere_pdf(d), [1 / np.pi, 0.8 / np.pi, 0.0], rtol=1e-15)


def test_cosine_is_the_lifted_disk():
    uv = np.random.default_rng(3).random((100, 2))
    d = square_to_cosine_hemisphere(uv)
    np.testing.assert_array_equal(d[:, :2], square_to_concentric_disk(uv))
    np.testing.assert_array_equal(cosine_hemisphere_to_square(d), concentric_disk_to_square(d[:, :2]))


def test_elementwise_is_the_array_map():
    uv = np.random.default_rng(1).random((50, 2))
    np.testing.assert_array_equal(
        np.stack(concentric_disk_point(uv[:, 0], uv[:, 1]), -1), square_to_concentric_disk(uv)
    )
    np.testing.assert_array_equal(
        np.stack(cosine_hemisphere_point(uv[:, 0], uv[:, 1]), -1), square_to_cosine_hemisphere(uv)
    )


@pytest.mark.parametrize(
    "call, error, word",
    [
        (lambda: square_to_cosine_hemisphere([0.5, 0.5, 0.5]), ValueError, "'uv'"),
        (lambda: square_to_concentric_disk("ab"), TypeError, "'uv'"),
        (lambda: cosine_hemisphere_to_square([[np.inf, 0, 1]]), ValueError, "'d'"),
        (lambda: concentric_disk_to_square([2.0, 0.0]), ValueError, "'p'"),
        (lambda: square_to_concentric_disk_pdf([0.0, 0.0, 1.0]), ValueError, "'p'"),
        (lambda: square_to_cosine_hemisphere_pdf([0.0, 0.0, 0.0]), ValueError, "'d'"),
    ],
)
def test_bad_input(call, error, word):
    with pytest.raises(error, match=word):
        call()
