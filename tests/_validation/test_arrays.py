"""symsphere._validation.arrays: the unit-direction check every direction function calls at its boundary."""

from __future__ import annotations

import math

import numpy as np
import pytest


def test_unit_direction_check_tolerance_and_extreme_norms():
    # The check compares squared norms with (1 -+ tol)^2; the message reports the first bad vector's norm,
    # computed without overflow or underflow (the reference: math.hypot, exact to an ulp).

    from symsphere._testing import validation

    check_unit_directions, tol = validation.check_unit_directions, validation.UNIT_TOLERANCE
    ok = np.array([[0.0, 0.0, 1.0 + 0.9 * tol], [0.0, 1.0 - 0.9 * tol, 0.0], [0.6, 0.0, -0.8]])
    assert check_unit_directions(ok) is not None
    assert check_unit_directions(ok.astype(np.float32)).dtype == np.float32
    for bad in ([0.0, 0.0, 1.0 + 1.1 * tol], [1.0 - 1.1 * tol, 0.0, 0.0], [1e200, 1e200, 0.0], [1e-200, 0.0, 0.0]):
        rows = np.array([[0.0, 0.0, 1.0], bad, [0.0, 0.0, 2.0]])  # the first bad row is reported
        expected = math.hypot(*bad)
        with pytest.raises(ValueError, match="unit vectors") as info:
            check_unit_directions(rows)
        reported = float(str(info.value).rsplit("norm of ", 1)[1])
        assert reported == pytest.approx(expected, rel=1e-5), (bad, reported)
