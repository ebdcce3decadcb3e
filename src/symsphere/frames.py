"""An orthonormal frame about a normal, to carry the hemisphere (0, 0, 1) onto it.

The frame is Duff et al., "Building an Orthonormal Basis, Revisited" (JCGT 6(1),
2017): branch-free, exact for n = (0, 0, +-1), and continuous in n everywhere
except across the plane n_z = 0, where the sign branch flips (no frame field on
the sphere can be continuous everywhere).  For n = (0, 0, 1) it is the identity.

:func:`frame_rows` is the formula for one unit normal given as three numbers; the
path tracer's numba kernels call it too (inside them it is the trusting scalar formula,
through ``numba.extending.overload``; called from Python it validates its arguments as
:func:`frame` does).  :func:`frame` is it for one numpy normal.
"""

from __future__ import annotations

import math
import numbers
from typing import Any

import numpy as np
import numpy.typing as npt
from numba.extending import overload

from ._typing import Float64Array, FloatArray
from ._validation import UNIT_TOLERANCE, as_float_array, check_dimensions, check_directions, short_repr

__all__ = ["frame", "frame_rows", "to_world", "to_local"]


def _rows(nx: float, ny: float, nz: float) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    # Duff et al. 2017, listing 3: numba compiles this inside the kernels (see the overload below).
    sign = math.copysign(1.0, nz)
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    return (1.0 + sign * nx * nx * a, sign * b, -sign * nx), (b, sign + ny * ny * a, -ny)


def frame_rows(nx: float, ny: float, nz: float) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """The first two rows t, b of the frame about the unit normal (nx, ny, nz) (Duff et al. 2017, listing 3).

    Scalar; the third row is n itself.  Inside a numba kernel it compiles to the bare formula
    (the kernels pass unit normals); from Python the three numbers are checked first.

    Parameters
    ----------
    nx, ny, nz : float
        A unit vector (norm 1 within 10**-3), finite real numbers.

    Returns
    -------
    t, b : tuple of 3 floats each

    Raises
    ------
    TypeError
        If a component is not a real number (it names 'nx', 'ny' or 'nz').
    ValueError
        If a component is NaN or inf, or the vector is not a unit vector.

    Examples
    --------
    >>> from symsphere.frames import frame_rows
    >>> frame_rows(0.0, 0.0, 1.0)
    ((1.0, -0.0, -0.0), (-0.0, 1.0, -0.0))
    """
    values: list[float] = []
    for value, name in ((nx, "nx"), (ny, "ny"), (nz, "nz")):
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
            raise TypeError(f"'{name}' must be a real number; got {type(value).__name__} {short_repr(value)}")
        try:
            number = float(value)
        except OverflowError:  # an int beyond float64
            number = math.inf
        if not math.isfinite(number):
            raise ValueError(f"'{name}' must be finite; got {short_repr(value)}")
        values.append(number)
    _check_unit(values, "'nx', 'ny', 'nz'")
    return _rows(*values)


@overload(frame_rows, jit_options={}, inline="never", strict=False)
def _frame_rows_in_kernels(
    nx: Any, ny: Any, nz: Any
) -> Any:  # numba: the formula, trusting its (unit, finite) arguments
    return _rows


def _check_unit(vector: list[float], names: str) -> None:
    """ValueError naming *names* unless the 3 finite floats *vector* have norm 1 within UNIT_TOLERANCE.

    In Python floats: a sampler about a normal calls it after writing its last output, which leaves
    numpy's code out of the caches (each numpy call then costs ~10-30 us; docs/results/write-limit.md)."""
    scale = max(abs(c) for c in vector)
    norm = scale * math.sqrt(sum((c / scale) * (c / scale) for c in vector)) if scale > 0 else 0.0
    if abs(norm - 1.0) > UNIT_TOLERANCE:
        raise ValueError(f"{names} must be a unit vector (norm 1 within {UNIT_TOLERANCE:g}); got a norm of {norm:.6g}")


def _check_basis(basis: object) -> FloatArray:
    """*basis* as a finite (3, 3) float array with orthonormal rows (within UNIT_TOLERANCE); errors name 'basis'."""
    if basis is None:
        raise TypeError("'basis' must be a (3, 3) array with orthonormal rows (from frame()); got None")
    arr = as_float_array(basis, "basis")
    if arr.shape != (3, 3):
        raise ValueError(f"'basis' must have shape (3, 3); got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"'basis' must be finite (no NaN or inf); got {short_repr(arr)}")
    wide = arr.astype(np.float64)
    with np.errstate(over="ignore", invalid="ignore"):  # huge entries: not orthonormal, said below
        gram = wide @ wide.T
    if not np.all(np.abs(gram - np.eye(3)) <= 2 * UNIT_TOLERANCE):
        raise ValueError("'basis' must have orthonormal rows (a frame from frame()); B @ B.T is not the identity")
    return arr


def frame(normal: npt.ArrayLike) -> Float64Array:
    """Rows (t, b, n) of a right-handed orthonormal frame with third axis *normal*.

    Parameters
    ----------
    normal : array_like, shape (3,)
        A unit vector (norm 1 within 10**-3; it is not normalised here: the samplers
        normalise theirs first).  NaN, inf, a zero or a non-unit vector is a ValueError.

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
    if normal is None:
        raise TypeError("'normal' must be a unit 3-vector; got None")
    arr = as_float_array(normal, "normal")
    if arr.shape != (3,):
        raise ValueError(f"'normal' must be a 3-vector; got shape {arr.shape}")
    nx, ny, nz = values = arr.astype(np.float64).tolist()
    if not all(math.isfinite(c) for c in values):
        raise ValueError(f"'normal' must be finite (no NaN or inf); got {short_repr(normal)}")
    _check_unit(values, "'normal'")
    t, b = _rows(nx, ny, nz)
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
        The same directions in world coordinates (numpy's result type of the two inputs;
        integers count as float64).

    Raises
    ------
    TypeError, ValueError
        Naming 'local' or 'basis': not real numbers, NaN or inf, a wrong shape, or rows of
        *basis* that are not orthonormal (within 10**-3).

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
    return _checked(local, "local") @ _check_basis(basis)


def _checked(vectors: object, name: str) -> FloatArray:
    arr = check_directions(vectors, name)  # real, finite, shape (..., 3)
    check_dimensions(arr, name)
    return arr


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
    return _checked(world, "world") @ _check_basis(basis).T
