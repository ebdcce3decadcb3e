"""An orthonormal frame about a normal, to carry the hemisphere (0, 0, 1) onto it.

The frame is Duff et al., "Building an Orthonormal Basis, Revisited" (JCGT 6(1),
2017): branch-free, exact for n = (0, 0, +-1), and continuous in n everywhere
except across the plane n_z = 0, where the sign branch flips (no frame field on
the sphere can be continuous everywhere).  For n = (0, 0, 1) it is the identity.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from ._typing import Float64Array, FloatArray

__all__ = ["frame", "to_world", "to_local"]


def frame(normal: npt.ArrayLike) -> Float64Array:
    """Rows (t, b, n) of a right-handed orthonormal frame with third axis *normal*.

    *normal* must be a unit float64 3-vector (validate with
    ``symsphere._validation.check_normal``).
    """
    nx, ny, nz = (float(c) for c in normal)
    sign = np.copysign(1.0, nz)
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    return np.array(
        [
            [1.0 + sign * nx * nx * a, sign * b, -sign * nx],
            [b, sign + ny * ny * a, -ny],
            [nx, ny, nz],
        ]
    )


def to_world(local: FloatArray, basis: Float64Array) -> FloatArray:
    """Local coordinates (..., 3) to world directions: ``local @ basis``."""
    return local @ basis


def to_local(world: FloatArray, basis: Float64Array) -> FloatArray:
    """World directions (..., 3) to local coordinates: ``world @ basis.T``."""
    return world @ basis.T
