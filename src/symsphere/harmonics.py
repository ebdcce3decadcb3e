"""Real spherical harmonics and polynomials on the sphere, with exact integrals.

Building blocks of the test integrands of :mod:`symsphere.integrands` (from
where they are importable too), public so that a study can make more:

- :func:`real_sh`, :func:`real_sh_basis`: real orthonormal spherical
  harmonics (any degree; the suite uses l <= 8), from the associated
  Legendre recurrence; :func:`sh_polynomial` gives the same functions as
  polynomials in x, y, z.
- :func:`monomial_integral`, :func:`polynomial_integral`: exact moments
  of x^a y^b z^c over the sphere and the upper hemisphere;
  :func:`evaluate_polynomial` evaluates a polynomial at points.
- :func:`cubic_harmonic`: the O_h-invariant harmonic polynomials of degree
  4, 6 and 8.

A polynomial is a dict ``{(a, b, c): coefficient}`` of the monomials
x^a y^b z^c.  See ``docs/explanation/when-orbits-help.md`` for the derivations.
"""

from __future__ import annotations

import itertools
import math
import numbers
from fractions import Fraction
from typing import Literal

import numpy as np
import numpy.typing as npt

from ._typing import Domain, Float64Array, Polynomial
from ._validation import (
    check_choice,
    check_coeffs,
    check_directions,
    check_exponents,
    check_lm,
    check_unit_directions,
    short_repr,
)

__all__ = [
    "real_sh",
    "real_sh_basis",
    "sh_polynomial",
    "monomial_integral",
    "polynomial_integral",
    "evaluate_polynomial",
    "cubic_harmonic",
]

_DOMAINS: tuple[Domain, ...] = ("sphere", "hemisphere")


# =============================================================================
# Spherical harmonics
# =============================================================================


def real_sh(l: int, m: int, d: npt.ArrayLike) -> Float64Array:
    """Real orthonormal spherical harmonic Y_lm at unit directions.

    ``Y_l0 = K_l0 P_l(z)``, ``Y_lm = sqrt 2 K_lm P_l^m(z) cos(m phi)`` for m > 0 and
    ``sqrt 2 K_l|m| P_l^|m|(z) sin(|m| phi)`` for m < 0, with
    ``K_lm = sqrt((2l + 1)/(4 pi) (l - m)!/(l + m)!)`` and the associated
    Legendre functions *without* the Condon-Shortley phase (graphics'
    convention; the sign does not affect orthonormality).  It is evaluated without angles: ``P_l^m(z) cos(m phi) = Q_l^m(z) Re (x + i y)^m``
    for unit vectors, where ``Q_m^m = (2m - 1)!!``, ``Q_{m+1}^m = (2m + 1) z Q_m^m``
    and ``(l - m) Q_l^m = (2l - 1) z Q_{l-1}^m - (l + m - 1) Q_{l-2}^m``.

    Parameters
    ----------
    l : int
        Degree, >= 0.
    m : int
        Order, -l <= m <= l.
    d : array_like, shape (..., 3)
        Unit directions.

    Returns
    -------
    ndarray, shape (...)
        ``Y_lm(d)`` for each direction.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.harmonics import real_sh
    >>> round(float(real_sh(0, 0, [0.0, 0.0, 1.0]) * np.sqrt(4 * np.pi)), 14)
    1.0
    >>> round(float(real_sh(1, 1, [1.0, 0.0, 0.0]) ** 2 * 4 * np.pi / 3), 14)   # Y_11 = sqrt(3/(4 pi)) x
    1.0
    """
    l, m = check_lm(l, m)
    d = check_unit_directions(d, "d").astype(np.float64)
    return _sh(l, m, d[..., 0], d[..., 1], d[..., 2])


def real_sh_basis(lmax: int, d: npt.ArrayLike) -> Float64Array:
    """All real spherical harmonics of degree <= lmax: shape (..., (lmax + 1)^2).

    Column ``l^2 + l + m`` is :func:`real_sh` ``(l, m, d)``.

    Examples
    --------
    >>> from symsphere.harmonics import real_sh_basis
    >>> real_sh_basis(8, [[0.0, 0.6, 0.8]]).shape
    (1, 81)
    """
    lmax, _ = check_lm(lmax, 0, "lmax")
    d = check_unit_directions(d, "d").astype(np.float64)
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    cols = [_sh(l, m, x, y, z) for l in range(lmax + 1) for m in range(-l, l + 1)]
    return np.stack(cols, axis=-1)


def sh_polynomial(l: int, m: int) -> dict[tuple[int, int, int], float]:
    """Y_lm as a polynomial in x, y, z: a dict ``{(a, b, c): coefficient}``.

    The same function as :func:`real_sh` on the unit sphere, built from the
    coefficients of Q_l^m (exact rationals) and of Re/Im (x + i y)^m, for use
    with :func:`polynomial_integral` (e.g. over the hemisphere).

    Examples
    --------
    >>> from symsphere.harmonics import sh_polynomial
    >>> {k: round(v, 6) for k, v in sh_polynomial(2, -2).items()}    # sqrt(15/(4 pi)) x y
    {(1, 1, 0): 1.092548}
    """
    l, m = check_lm(l, m)
    am = abs(m)
    q = _legendre_q_coefficients(l, am)  # Fractions, index = power of z
    scale = _sh_norm(l, am) * (math.sqrt(2.0) if m else 1.0)
    coeffs: dict[tuple[int, int, int], float] = {}
    for k in range(am + 1):
        if (k % 2 == 0) != (m >= 0):  # Re: even powers of i y; Im: odd
            continue
        sign = (-1) ** (k // 2)
        for j, qj in enumerate(q):
            if qj:
                key = (am - k, k, j)
                coeffs[key] = coeffs.get(key, 0.0) + scale * sign * math.comb(am, k) * float(qj)
    return coeffs


# =============================================================================
# Moments and polynomials
# =============================================================================


def monomial_integral(a: int, b: int, c: int, domain: Domain = "sphere") -> float:
    """Exact integral of x^a y^b z^c over the unit sphere or the hemisphere z >= 0.

    Sphere: ``2 G((a+1)/2) G((b+1)/2) G((c+1)/2) / G((a+b+c+3)/2)`` (G = Gamma) if
    a, b, c are all even, else 0; for even exponents this is
    ``4 pi (a-1)!! (b-1)!! (c-1)!! / (a+b+c+1)!!``.

    Hemisphere z >= 0: 0 if a or b is odd (x -> -x maps the hemisphere onto
    itself); otherwise ``G((a+1)/2) G((b+1)/2) G((c+1)/2) / G((a+b+c+3)/2)`` for
    *every* c >= 0 -- half the sphere's value when c is even, and for odd c
    the same expression, ``pi (a-1)!! (b-1)!! / 2^((a+b)/2) * ((c-1)/2)! / ((a+b+c+1)/2)!``.
    (In spherical coordinates the phi integral is ``2 B((a+1)/2, (b+1)/2)`` and
    the theta integral over [0, pi/2] is ``B((a+b+2)/2, (c+1)/2) / 2``.)

    Parameters
    ----------
    a, b, c : int
        Non-negative exponents.
    domain : {'sphere', 'hemisphere'}

    Returns
    -------
    float
        A rational multiple of pi, rounded once.

    Examples
    --------
    >>> import math
    >>> from symsphere.harmonics import monomial_integral
    >>> monomial_integral(2, 0, 0) / math.pi, monomial_integral(0, 0, 1, "hemisphere") / math.pi
    (1.3333333333333333, 1.0)
    """
    return (
        float(_monomial_integral_over_pi(*check_exponents(a, b, c), check_choice(domain, "domain", _DOMAINS))) * math.pi
    )


def polynomial_integral(coeffs: Polynomial, domain: Domain = "sphere") -> float:
    """Exact integral of a polynomial ``{(a, b, c): coefficient}`` (see :func:`monomial_integral`).

    Coefficients may be floats, ints or ``fractions.Fraction``; the sum is
    formed exactly in rationals (times pi) and rounded once.

    Examples
    --------
    >>> import math
    >>> from symsphere.harmonics import polynomial_integral
    >>> from fractions import Fraction
    >>> polynomial_integral({(4, 0, 0): 1, (0, 4, 0): 1, (0, 0, 4): 1, (0, 0, 0): Fraction(-3, 5)})
    0.0
    >>> polynomial_integral({(2, 0, 2): 1}, "hemisphere") / math.pi     # 2/15
    0.13333333333333333
    """
    domain = check_choice(domain, "domain", _DOMAINS)
    # Summed exactly (a float coefficient is converted to the Fraction it equals), rounded once.
    total = sum(
        (
            Fraction(coef) * _monomial_integral_over_pi(*check_exponents(*key), domain)
            for key, coef in check_coeffs(coeffs).items()
        ),
        Fraction(0),
    )
    try:
        return float(total) * math.pi
    except OverflowError:
        raise ValueError("'coeffs' are too large: the integral overflows float64") from None


def evaluate_polynomial(coeffs: Polynomial, d: npt.ArrayLike) -> Float64Array:
    """Evaluate ``{(a, b, c): coefficient}`` at points of shape (..., 3).

    Examples
    --------
    >>> from symsphere.harmonics import evaluate_polynomial
    >>> float(evaluate_polynomial({(1, 1, 0): 2.0, (0, 0, 0): 1.0}, [0.5, 0.5, 0.7]))
    1.5
    """
    coeffs = check_coeffs(coeffs)
    d = check_directions(d, "d").astype(np.float64)
    with np.errstate(over="raise", invalid="raise"):
        try:
            return _poly_eval(coeffs, d)
        except FloatingPointError:
            raise ValueError("'d' is too large: the polynomial overflows float64 (use unit directions)") from None


def cubic_harmonic(degree: Literal[4, 6, 8]) -> dict[tuple[int, int, int], float]:
    """The O_h-invariant harmonic polynomial of degree 4, 6 or 8.

    The polynomials invariant under the 48 signed permutations form, on the
    sphere, one harmonic of each degree 0, 4, 6, 8 (and none of degree 2 or
    any odd degree; see ``docs/explanation/when-orbits-help.md``).  Their homogeneous harmonic
    representatives (Laplacian 0 in R^3, derived by matching coefficients):

    - degree 4: ``sum x^4 - 3 sum x^2 y^2``  (= (5/2)(x^4 + y^4 + z^4 - 3/5) on the sphere)
    - degree 6: ``sum x^6 - (15/2) sum_sym x^4 y^2 + 90 x^2 y^2 z^2``
    - degree 8: ``sum x^8 - 14 sum_sym x^6 y^2 + 35 sum x^4 y^4``

    where ``sum_sym x^4 y^2`` runs over the 6 ordered pairs of distinct axes.
    Being harmonic and homogeneous of degree l, each restricts to a degree-l
    spherical harmonic, so it integrates to 0 and is orthogonal to every
    lower degree.

    Returns
    -------
    dict
        ``{(a, b, c): coefficient}``.

    Examples
    --------
    >>> from symsphere.harmonics import cubic_harmonic, polynomial_integral
    >>> len(cubic_harmonic(6)), polynomial_integral(cubic_harmonic(8))
    (10, 0.0)
    """
    if isinstance(degree, bool) or not isinstance(degree, numbers.Integral) or degree not in (4, 6, 8):
        raise ValueError(f"'degree' must be 4, 6 or 8, got {short_repr(degree)}")
    terms = {
        4: (((4, 0, 0), 1.0), ((2, 2, 0), -3.0)),
        6: (((6, 0, 0), 1.0), ((4, 2, 0), -7.5), ((2, 2, 2), 90.0)),
        8: (((8, 0, 0), 1.0), ((6, 2, 0), -14.0), ((4, 4, 0), 35.0)),
    }[int(degree)]
    coeffs: dict[tuple[int, int, int], float] = {}
    for exps, coef in terms:
        for perm in _distinct_permutations(exps):
            coeffs[perm] = coef
    return coeffs


# =============================================================================
# Private helpers
# =============================================================================


def _double_factorial(k: int) -> int:
    return math.prod(range(k, 0, -2)) if k > 0 else 1


def _monomial_integral_over_pi(a: int, b: int, c: int, domain: str) -> Fraction:
    """The integral divided by pi, as an exact Fraction (see monomial_integral)."""
    if a % 2 or b % 2:
        return Fraction(0)
    if c % 2 == 0:
        sphere = Fraction(
            4 * _double_factorial(a - 1) * _double_factorial(b - 1) * _double_factorial(c - 1),
            _double_factorial(a + b + c + 1),
        )
        return sphere if domain == "sphere" else sphere / 2
    if domain == "sphere":
        return Fraction(0)
    # G((a+1)/2) G((b+1)/2) = pi (a-1)!! (b-1)!! / 2^((a+b)/2); G((c+1)/2) = ((c-1)/2)!;
    # G((a+b+c+3)/2) = ((a+b+c+1)/2)!  (a + b + c + 1 is even).
    return Fraction(
        _double_factorial(a - 1) * _double_factorial(b - 1) * math.factorial((c - 1) // 2),
        2 ** ((a + b) // 2) * math.factorial((a + b + c + 1) // 2),
    )


def _poly_eval(coeffs: Polynomial, d: Float64Array) -> Float64Array:
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    out = np.zeros(d.shape[:-1])
    for (a, b, c), coef in coeffs.items():
        out = out + float(coef) * x**a * y**b * z**c
    return out


def _distinct_permutations(exps: tuple[int, int, int]) -> list[tuple[int, ...]]:
    return sorted(set(itertools.permutations(exps)))


def _sh_norm(l: int, am: int) -> float:
    return math.sqrt((2 * l + 1) / (4 * math.pi) * math.factorial(l - am) / math.factorial(l + am))


def _assoc_q(l: int, am: int, z: Float64Array) -> Float64Array:
    """Q_l^m(z), with P_l^m = (1 - z^2)^(m/2) Q_l^m, no Condon-Shortley phase."""
    q_prev = np.full_like(z, float(_double_factorial(2 * am - 1)))  # Q_m^m
    if l == am:
        return q_prev
    q = (2 * am + 1) * z * q_prev  # Q_{m+1}^m
    for k in range(am + 2, l + 1):
        q, q_prev = ((2 * k - 1) * z * q - (k + am - 1) * q_prev) / (k - am), q
    return q


def _legendre_q_coefficients(l: int, am: int) -> list[Fraction]:
    """Coefficients (Fractions, by power of z) of Q_l^m, by the same recurrence."""
    q_prev = [Fraction(_double_factorial(2 * am - 1))]
    if l == am:
        return q_prev
    q = [Fraction(0), (2 * am + 1) * q_prev[0]]
    for k in range(am + 2, l + 1):
        zq = [Fraction(0)] + [(2 * k - 1) * c for c in q]
        prev = q_prev + [Fraction(0)] * (len(zq) - len(q_prev))
        q, q_prev = [(s - (k + am - 1) * t) / (k - am) for s, t in zip(zq, prev, strict=False)], q
    return q


def _sh(l: int, m: int, x: Float64Array, y: Float64Array, z: Float64Array) -> Float64Array:
    am = abs(m)
    value = _sh_norm(l, am) * _assoc_q(l, am, z)
    if m == 0:
        return value
    re, im = np.ones_like(x), np.zeros_like(x)  # (x + i y)^|m| by repeated multiplication
    for _ in range(am):
        re, im = re * x - im * y, re * y + im * x
    return math.sqrt(2.0) * value * (re if m > 0 else im)
