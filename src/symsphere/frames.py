"""An orthonormal frame about a normal, to carry the hemisphere (0, 0, 1) onto it.

The frame is Duff et al., "Building an Orthonormal Basis, Revisited" (JCGT 6(1),
2017): branch-free, exact for n = (0, 0, +-1), and continuous in n everywhere
except across the plane n_z = 0, where the sign branch flips (no frame field on
the sphere can be continuous everywhere).  For n = (0, 0, 1) it is the identity.

:func:`frame_rows` is the formula, a scalar function that numba compiles
(``register_jitable``): the path tracer's kernels call it, and :func:`frame`
is it for one numpy normal.
"""

from __future__ import annotations

import math

import numpy as np
from numba.extending import register_jitable

__all__ = ["frame", "frame_rows", "to_world", "to_local"]


@register_jitable
def frame_rows(nx, ny, nz):
    """The first two rows t, b of the frame about the unit normal (nx, ny, nz) (Duff et al. 2017, listing 3).

    Scalar and numba-compilable; the third row is n itself.

    Examples
    --------
    >>> from symsphere.frames import frame_rows
    >>> frame_rows(0.0, 0.0, 1.0)
    ((1.0, -0.0, -0.0), (-0.0, 1.0, -0.0))
    """
    sign = math.copysign(1.0, nz)
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    return (1.0 + sign * nx * nx * a, sign * b, -sign * nx), (b, sign + ny * ny * a, -ny)


def frame(normal):
    """Rows (t, b, n) of a right-handed orthonormal frame with third axis *normal*.

    *normal* must be a unit float64 3-vector (validate with
    ``symsphere._validation.check_normal``).
    """
    nx, ny, nz = (float(c) for c in normal)
    t, b = frame_rows(nx, ny, nz)
    return np.array([t, b, (nx, ny, nz)])


def to_world(local, basis):
    """Local coordinates (..., 3) to world directions: ``local @ basis``."""
    return local @ basis


def to_local(world, basis):
    """World directions (..., 3) to local coordinates: ``world @ basis.T``."""
    return world @ basis.T
