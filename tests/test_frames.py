"""symsphere.frames: Duff et al.'s frame about a normal (frame, frame_rows) and the changes of basis
(to_world, to_local).  The frame's use by the samplers is tested in test_sampling.py; its validation
under random inputs in test_properties.py."""

import math

import numpy as np
import pytest
from numba import njit
from references import raises_naming

from symsphere import frames
from symsphere.frames import frame, frame_rows, to_local, to_world

RNG = np.random.default_rng(7)
NORMALS = np.concatenate(
    [
        [[0, 0, 1], [0, 0, -1], [1, 0, 0], [0, 1, 0], [1e-300, 0, 1], [0, 1e-300, -1]],
        RNG.normal(size=(200, 3)),
        [[1e-9, 1e-9, -1.0], [0.6, 0.8, 0.0], [0.6, 0.8, -0.0]],
    ]
)
NORMALS = NORMALS / np.linalg.norm(NORMALS, axis=1, keepdims=True)
EPS = np.finfo(np.float64).eps


def test_frame_is_a_right_handed_orthonormal_basis_with_n_last():
    for n in NORMALS:
        basis = frame(n)
        # Duff et al.'s formula: exact rational expressions of n; orthonormal to a few eps for unit n.
        assert np.max(np.abs(basis @ basis.T - np.eye(3))) <= 8 * EPS
        assert abs(np.linalg.det(basis) - 1.0) <= 8 * EPS
        np.testing.assert_array_equal(basis[2], n)


def test_the_poles_are_exact():
    np.testing.assert_array_equal(frame([0.0, 0.0, 1.0]), np.eye(3))
    np.testing.assert_array_equal(np.abs(frame([0.0, 0.0, -1.0])), np.eye(3))


def test_frame_rows_is_the_frame_and_numba_computes_the_same_bits():
    # The formula has no elementary function (only + - * / and copysign) and the kernels compile
    # without fastmath, so numba's code and Python's give the same bits (no error bound needed).
    @njit
    def rows(normals, out):
        for i in range(normals.shape[0]):
            t, b = frame_rows(normals[i, 0], normals[i, 1], normals[i, 2])
            out[i, 0, 0], out[i, 0, 1], out[i, 0, 2] = t
            out[i, 1, 0], out[i, 1, 1], out[i, 1, 2] = b

    compiled = np.empty((len(NORMALS), 2, 3))
    rows(NORMALS, compiled)
    for n, got in zip(NORMALS, compiled, strict=True):
        t, b = frame_rows(*map(float, n))
        np.testing.assert_array_equal(np.array([t, b]), frame(n)[:2])
        np.testing.assert_array_equal(got, frame(n)[:2])


def test_to_world_and_to_local_are_inverse():
    basis = frame(NORMALS[7])
    local = RNG.normal(size=(50, 3))
    world = to_world(local, basis)
    np.testing.assert_allclose(world, local @ basis, rtol=0, atol=0)
    np.testing.assert_allclose(to_local(world, basis), local, rtol=0, atol=16 * EPS * np.max(np.abs(local)))
    np.testing.assert_array_equal(to_world(np.array([0.0, 0.0, 1.0]), basis), basis[2])


@pytest.mark.parametrize(
    "call, error, name",
    [
        (lambda: frame(None), TypeError, "'normal'"),
        (lambda: frame([0.0, 0.0]), ValueError, "'normal'"),
        (lambda: frame([0.0, 0.0, 2.0]), ValueError, "'normal'"),
        (lambda: frame([np.nan, 0.0, 1.0]), ValueError, "'normal'"),
        (lambda: frame_rows("x", 0.0, 1.0), TypeError, "'nx'"),
        (lambda: frame_rows(0.0, np.inf, 1.0), ValueError, "'ny'"),
        (lambda: frame_rows(0.0, 0.0, 0.5), ValueError, "unit vector"),
        (lambda: to_world(np.ones((2, 3)), np.ones((3, 3))), ValueError, "'basis'"),
        (lambda: to_local(np.ones((2, 2)), np.eye(3)), ValueError, "'world'"),
    ],
)
def test_bad_arguments_name_themselves(call, error, name):
    with pytest.raises(error, match=name):
        call()


# --- wrong types and values name the argument ----------------------------------------------------------------------


@pytest.mark.parametrize(
    "call, error, named",
    [
        (lambda: frames.to_local(np.ones((1, 3)), None), TypeError, "'basis'"),
        (lambda: frames.to_world("abc", np.eye(3)), TypeError, "'local'"),
        (lambda: frames.to_world(np.ones((1, 3)), "xyz"), TypeError, "'basis'"),
        (lambda: frames.frame([math.nan, 0, 1]), ValueError, "'normal'"),
        (lambda: frames.frame([0, 0, 2.0]), ValueError, "'normal'"),
        (lambda: frames.frame_rows(math.inf, 0, 1), ValueError, "'nx'"),
        (lambda: frames.frame_rows(None, 0, 1), TypeError, "'nx'"),
    ],
)  # fmt: skip
def test_wrong_types_and_values_name_the_argument(call, error, named):
    raises_naming(call, error, named)
