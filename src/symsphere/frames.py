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
import numpy.typing as npt
from numba.extending import register_jitable

from ._typing import Float64Array, FloatArray

__all__ = ["frame", "frame_rows", "to_world", "to_local"]


@register_jitable
def frame_rows(nx: float, ny: float, nz: float) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
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


def frame(normal: npt.ArrayLike) -> Float64Array:
    """Rows (t, b, n) of a right-handed orthonormal frame with third axis *normal*.

    Parameters
    ----------
    normal : array_like, shape (3,)
        A unit vector, trusted: not validated or normalised here (the samplers validate
        theirs with ``symsphere._validation.check_normal``).

    Returns
    -------
    ndarray, shape (3, 3), float64
        The basis: rows t, b and *normal*, orthonormal with determinant +1; the identity for
        ``normal = (0, 0, 1)``.  Use it with :func:`to_world` and :func:`to_local`.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.frames import frame
    >>> basis = frame([0.48, 0.6, 0.64])
    >>> basis[2]
    array([0.48, 0.6 , 0.64])
    >>> bool(np.allclose(basis @ basis.T, np.eye(3))), round(float(np.linalg.det(basis)), 12)
    (True, 1.0)
    """
    nx, ny, nz = (float(c) for c in np.asarray(normal, dtype=np.float64))
    t, b = frame_rows(nx, ny, nz)
    return np.array([t, b, (nx, ny, nz)])


def to_world(local: FloatArray, basis: Float64Array) -> FloatArray:
    """Local coordinates (..., 3) to world directions: ``local @ basis``.

    Parameters
    ----------
    local : ndarray, shape (..., 3)
        Coordinates in the frame: the hemisphere about (0, 0, 1) is the hemisphere about the
        frame's normal.
    basis : ndarray, shape (3, 3)
        A frame from :func:`frame` (any orthonormal rows).

    Returns
    -------
    ndarray, shape (..., 3)
        The same directions in world coordinates (numpy's result type of the two inputs).

    Examples
    --------
    >>> import numpy as np
    >>> import symsphere
    >>> from symsphere.frames import frame, to_world
    >>> normal = np.array([0.48, 0.6, 0.64])
    >>> to_world(np.array([0.0, 0.0, 1.0]), frame(normal))      # the pole goes to the normal
    array([0.48, 0.6 , 0.64])
    >>> d = to_world(symsphere.sample_hemisphere(24 * 4, rng=1), frame(normal))
    >>> bool(np.all(d @ normal >= 0))                           # the hemisphere about the normal
    True
    >>> bool(np.allclose(d, symsphere.sample_hemisphere(24 * 4, normal=normal, rng=1)))
    True
    """
    return local @ basis


def to_local(world: FloatArray, basis: Float64Array) -> FloatArray:
    """World directions (..., 3) to local coordinates: ``world @ basis.T``.

    The inverse of :func:`to_world` (the basis is orthonormal).

    Parameters
    ----------
    world : ndarray, shape (..., 3)
        Directions in world coordinates.
    basis : ndarray, shape (3, 3)
        A frame from :func:`frame` (any orthonormal rows).

    Returns
    -------
    ndarray, shape (..., 3)
        Their coordinates in the frame: the third is the cosine to the frame's normal.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.frames import frame, to_local, to_world
    >>> basis = frame([0.0, 1.0, 0.0])
    >>> to_local(np.array([0.0, 1.0, 0.0]), basis)             # the normal is the local pole
    array([0., 0., 1.])
    >>> w = np.array([[0.6, 0.0, 0.8], [0.0, -0.6, 0.8]])
    >>> bool(np.allclose(to_world(to_local(w, basis), basis), w))
    True
    """
    return world @ basis.T
