"""The integrand suite's compiled kernels: a few formulas, each a numba function of one direction.

A suite integrand's kernel is one of the formulas below (:data:`PHONG`, :data:`CAP`, ...)
with its constants: a *spec* ``(kind, params)``, an int and a tuple of floats.
:func:`integrand_kernel` makes ``kernel(x, y, z)`` as a closure over the spec; numba treats a
closure's cells as constants, so the branch of the formula is chosen before typing and the
constants are folded into the machine code (and a loop over them unrolled), as if written out.
:mod:`symsphere._fused` compiles the same spec into its fused kernel (a closure too), which numba
caches on disk by the cells' values.  No source is generated.

A polynomial (:data:`POLYNOMIAL`) is a chain of numba functions, one per term, each a closure over
its constants.  The arithmetic is the integrand's expression evaluated left to right: a polynomial
``shift + c1 x^a1 y^b1 z^c1 + ...`` as ``((shift + ((c1 x) x) ... ) + ...)``, a dot product
``w . a`` as ``(a0 x + a1 y) + a2 z``; ``exp`` is :func:`vexp`, a libm-free exp that LLVM can
vectorise.
"""

from __future__ import annotations

from typing import Any

from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic, register_jitable

from ._threads import route_compiles

__all__ = [
    "CAP",
    "EXP",
    "KINDS",
    "PHONG",
    "POLYGON_LIGHT",
    "POLYNOMIAL",
    "SPHERE_LIGHT",
    "Z",
    "evaluate",
    "integrand_kernel",
    "no_chain",
    "polynomial_chain",
    "value",
    "vexp",
]

POLYNOMIAL = 0
"""``shift + sum_i c_i x^a_i y^b_i z^c_i``; params ``(shift, c_1, a_1, b_1, c_1, c_2, ...)`` (exponents as floats)."""
PHONG = 1
"""``scale max(0, w . r)^20``; params ``(scale, r0, r1, r2)``."""
CAP = 2
"""``1[w . c >= cos_alpha]``; params ``(cos_alpha, c0, c1, c2)``."""
EXP = 3
"""``exp(w . a)`` (:func:`vexp`); params ``(a0, a1, a2)``."""
Z = 4
"""``z``; params ``(0.0,)`` (unused)."""
SPHERE_LIGHT = 5
"""``L max(z, 0) 1[w . c >= cos_light]``; params ``(L, cos_light, c0, c1, c2)``."""
POLYGON_LIGHT = 6
"""``L max(z, 0) 1[w . n_i >= 0 for every edge plane i]``; params ``(L, n_1, n_2, ...)`` (3 floats each)."""
KINDS = (POLYNOMIAL, PHONG, CAP, EXP, Z, SPHERE_LIGHT, POLYGON_LIGHT)


# --- a vectorisable exp -------------------------------------------------------------------


@intrinsic
def _float_bits(typingctx: Any, x: Any) -> Any:
    """The bits of a float64 as an int64 (a bitcast: no instruction)."""

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        return builder.bitcast(args[0], ir.IntType(64))

    return types.int64(types.float64), codegen


@intrinsic
def _bits_float(typingctx: Any, i: Any) -> Any:
    """The float64 whose bits are the int64 *i*."""

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        return builder.bitcast(args[0], ir.DoubleType())

    return types.float64(types.int64), codegen


_SHIFTER = 6755399441055744.0  # 1.5 * 2**52: adding it rounds to an integer kept in the low bits
_LN2_HI = 0.693145751953125  # ln 2 split for an exact k * ln2_hi (Cody & Waite)
_LN2_LO = 1.42860682030941723212e-6
_INV_LN2 = 1.4426950408889634


@njit(error_model="numpy", nogil=True)
def vexp(t: float) -> float:
    """exp(t) without a libm call, so that LLVM can vectorise loops around it.

    t = k ln 2 + r with |r| <= ln2 / 2 (Cody-Waite), exp(r) by its Taylor polynomial to r^13
    (remainder below 4e-18), 2^k put into the exponent bits.  Within 1 ulp of numpy's exp on
    [-708, 709] (tested); t is clamped to that range (no inf, no NaN for finite t).
    """
    t = min(max(t, -708.0), 709.0)
    shifted = t * _INV_LN2 + _SHIFTER
    k = shifted - _SHIFTER
    r = (t - k * _LN2_HI) - k * _LN2_LO
    p = 1.0 / 6227020800.0
    p = p * r + 1.0 / 479001600.0
    p = p * r + 1.0 / 39916800.0
    p = p * r + 1.0 / 3628800.0
    p = p * r + 1.0 / 362880.0
    p = p * r + 1.0 / 40320.0
    p = p * r + 1.0 / 5040.0
    p = p * r + 1.0 / 720.0
    p = p * r + 1.0 / 120.0
    p = p * r + 1.0 / 24.0
    p = p * r + 1.0 / 6.0
    p = p * r + 0.5
    p = p * r + 1.0
    p = p * r + 1.0
    # 2^k: k sits in the low bits of shifted (the intrinsics' Python signatures include numba's typing context)
    scale: float = _bits_float((_float_bits(shifted) + 1023) << 52)  # type: ignore[call-arg]
    return p * scale


# --- the formulas ---------------------------------------------------------------------------


@njit(inline="always")
def evaluate(kind, params, x, y, z):  # typed by numba
    """The integrand *kind* with constants *params* at the direction (x, y, z).

    Inlined in numba's IR: with *kind* a constant of the caller, numba prunes the other formulas.
    """
    if kind == PHONG:
        m = max(0.0, params[1] * x + params[2] * y + params[3] * z)
        return params[0] * (m * m * m * m) ** 5
    if kind == CAP:
        return 1.0 if params[1] * x + params[2] * y + params[3] * z >= params[0] else 0.0
    if kind == EXP:
        return vexp(params[0] * x + params[1] * y + params[2] * z)
    if kind == Z:
        return z
    if kind == SPHERE_LIGHT:
        inside = params[2] * x + params[3] * y + params[4] * z >= params[1]
        return params[0] * max(z, 0.0) * (1.0 if inside else 0.0)
    # POLYGON_LIGHT
    inside = True
    for i in range(1, len(params), 3):
        if not params[i] * x + params[i + 1] * y + params[i + 2] * z >= 0.0:
            inside = False
    return params[0] * max(z, 0.0) * (1.0 if inside else 0.0)


def _with_term(previous: Any, c: float, a: int, b: int, e: int) -> Any:
    """``previous(x, y, z) + c x^a y^b z^e``; the exponents are cells (constants: the loops unroll)."""

    @register_jitable
    def polynomial(x, y, z):  # pragma: no cover - compiled by numba
        term = c
        for _ in range(a):
            term = term * x
        for _ in range(b):
            term = term * y
        for _ in range(e):
            term = term * z
        return previous(x, y, z) + term

    return polynomial


def polynomial_chain(params: tuple[float, ...]) -> Any:
    """The polynomial of *params* (:data:`POLYNOMIAL`) as a chain of ``register_jitable`` functions, one per
    term, which LLVM inlines into straight-line code, as if the sum were written out (one function looping
    over the terms is not unrolled: measured 4-5x slower on the suite's cubic8).  Plain closures over
    numbers: they pickle the same in every process, so numba's disk cache keys a kernel holding one."""
    shift = params[0]

    @register_jitable
    def constant(x, y, z):  # pragma: no cover - compiled by numba
        return shift

    chain = constant
    for i in range(1, len(params), 4):
        chain = _with_term(chain, params[i], int(params[i + 1]), int(params[i + 2]), int(params[i + 3]))
    return chain


@register_jitable
def no_chain(x, y, z):  # pragma: no cover - compiled by numba
    """The chain of a spec that is not a polynomial (never called)."""
    return 0.0


Spec = tuple[int, tuple[float, ...], Any]
"""(kind, params, the polynomial's chain or :func:`no_chain`)."""


def integrand_kernel(kind: int, params: tuple[float, ...]) -> Any:
    """``kernel(x, y, z)``, the formula *kind* with constants *params*, compiled by numba on first call.

    The spec ``(kind, params, chain)`` is kept as ``kernel.symsphere_spec`` (:mod:`symsphere._fused`
    compiles it into its disk-cached fused kernel).
    """
    if kind not in KINDS:
        raise ValueError(f"'kind' must be one of {KINDS}, got {kind!r}")
    params = tuple(float(p) for p in params)
    chain = polynomial_chain(params) if kind == POLYNOMIAL else no_chain

    @njit(error_model="numpy")
    def kernel(x, y, z):  # pragma: no cover - compiled by numba
        return value(kind, params, chain, x, y, z)

    # setattr: a numba Dispatcher has no such attribute for mypy.
    setattr(kernel, "symsphere_spec", (kind, params, chain))  # noqa: B010
    return kernel


@njit(inline="always")
def value(kind, params, chain, x, y, z):  # pragma: no cover - compiled by numba
    """The spec's integrand at (x, y, z): the polynomial's chain, or :func:`evaluate`; inlined in numba's
    IR, so that a constant *kind* prunes the other branch."""
    if kind == POLYNOMIAL:
        return chain(x, y, z)
    return evaluate(kind, params, x, y, z)


route_compiles(globals())  # the first compile of each numba function here: interruptible (_threads)
