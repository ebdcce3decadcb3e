"""What the warps' modules share: the checked entry points, the elementwise decorator, the numba-aware branch.

Private module; its names are public within the package only.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable
from typing import Any, TypeVar, cast

import numpy as np
import numpy.typing as npt
from numba.extending import overload, register_jitable

from .._typing import Float64Array, FloatArray
from .._validation import check_real_arrays, check_unit_directions, check_uv

__all__ = [
    "checked_forward",
    "checked_inverse",
    "elementwise",
    "formula",
    "on_rows",
    "pick",
    "unit_square_args",
    "wrap_unit",
]

F = TypeVar("F", bound=Callable[..., Any])


def unit_square_args(u: Any, v: Any) -> list[Any]:
    """*u*, *v* as finite float64 in [0, 1] that broadcast together, else ValueError naming 'u' or 'v'."""
    return check_real_arrays((u, "u"), (v, "v"), unit_interval=True)


def elementwise(check: Callable[..., Any] = unit_square_args) -> Callable[[F], F]:
    """Give a scalar formula, written once, its checked Python form and its numba form.

    The decorated function is the formula: numpy ufuncs and :func:`pick` only, so that it runs on float64 arrays
    (numpy) and on scalars (numba); or a scalar formula in plain ``math`` whose *check* returns floats (the
    spherical rectangle's). The name it is bound to becomes the public function: called from Python it first
    passes its arguments through *check* (which returns them converted, or raises naming them; arguments given
    by name are bound to the formula's signature first) and then runs the formula; inside a numba kernel it *is*
    the formula, unchecked (an ``overload``). The bare formula itself, :func:`formula` of the public function,
    is ``register_jitable``: other formulas call it in numba and numpy alike, and the array maps
    (``square_to_X``) apply it to trusted rows (:func:`on_rows`). Mitsuba's ``warp.h`` and pbrt-v4's
    ``sampling.h`` write each map once as a small pure function; this is that, with the two entry points numpy
    and numba need.
    """

    def decorate(bare: F) -> F:
        register_jitable(bare)
        signature = inspect.signature(bare)

        @functools.wraps(bare)
        def checked(*args: Any, **kwargs: Any) -> Any:
            if kwargs:  # by name, as the formula's signature allows (its TypeError for an unknown name)
                args = signature.bind(*args, **kwargs).args
            return bare(*check(*args))

        overload(checked, jit_options={}, inline="never", strict=False)(lambda *args: bare)
        _FORMULAS[checked] = bare
        return checked  # type: ignore[return-value]  # functools.wraps keeps bare's signature and doc

    return decorate


_FORMULAS: dict[Callable[..., Any], Callable[..., Any]] = {}


def formula(public: F) -> F:
    """The bare formula of an :func:`elementwise` function (unchecked; ``register_jitable`` for numba)."""
    return cast(F, _FORMULAS[public])


def on_rows(point: Callable[..., Any]) -> Callable[[Float64Array], Float64Array]:
    """The array map of an elementwise formula ``point(u, v)``: float64 rows (..., 2) to (..., k), unchecked."""
    bare = _FORMULAS.get(point, point)

    def rows(uv: Float64Array) -> Float64Array:
        return np.stack(bare(uv[..., 0], uv[..., 1]), axis=-1)

    return rows


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
