"""What the warps' modules share: the checked entry points and the numba-aware branch.

Private module; its names are public within the package only.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import numpy.typing as npt
from numba.extending import overload

from .._typing import Float64Array, FloatArray
from .._validation import check_unit_directions, check_uv

__all__ = ["checked_forward", "checked_inverse", "pick", "wrap_unit"]


def checked_forward(forward: Callable[[Float64Array], Float64Array], uv: npt.ArrayLike) -> FloatArray:
    """Check *uv* (points of [0, 1]^2), apply *forward* in float64, return in *uv*'s dtype."""
    uv = check_uv(uv)
    return forward(uv.astype(np.float64)).astype(uv.dtype, copy=False)


def checked_inverse(
    inverse: Callable[[Float64Array], Float64Array], d: npt.ArrayLike, hemisphere: bool = False
) -> FloatArray:
    """Check *d* (unit directions; z >= 0 with *hemisphere*), apply *inverse* in float64."""
    d = check_unit_directions(d, "d")  # a zero or non-unit vector would map to NaN or a wrong point
    d64 = d.astype(np.float64)
    if hemisphere and np.any(d64[..., 2] < -1e-12):
        raise ValueError("'d' must have z >= 0 (directions of the hemisphere about (0, 0, 1))")
    return inverse(d64).astype(d.dtype, copy=False)


def wrap_unit(t: Float64Array) -> Float64Array:
    """Fold t into [0, 1): -0.25 -> 0.75, and 1 - tiny rounding to 1 -> 0."""
    t = np.where(t < 0, t + 1.0, t)
    return np.where(t >= 1.0, 0.0, t)


def pick(condition: Any, a: Any, b: Any) -> Any:
    """``np.where(condition, a, b)``; in numba code, ``a if condition else b`` (scalars)."""
    return np.where(condition, a, b)


@overload(pick)
def _pick_scalar(condition: Any, a: Any, b: Any) -> Any:
    def impl(condition: Any, a: Any, b: Any) -> Any:
        return a if condition else b

    return impl
