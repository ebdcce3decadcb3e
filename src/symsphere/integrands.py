"""Test integrands on the sphere and hemisphere with closed-form integrals.

A documented, reusable suite for studies of samplers: each :class:`Integrand`
has a callable ``f`` on unit directions, the exact integral of ``f`` with
respect to solid angle over its domain, and flags saying whether it is
smooth, invariant under the 48 symmetries of the scheme, and whether the
orbit average (the mean of ``f`` over the 48 or 24 images of a point of T0)
integrates it exactly.  ``INTEGRANDS`` maps names to integrands and
:func:`suite` selects them by domain.  See ``docs/reference/integrands.md`` and ``docs/explanation/when-orbits-help.md`` for the
derivations and for why the orbit average is exact where it is.

Building blocks, public so that a study can make more integrands:

- the spherical harmonics and polynomials of :mod:`symsphere.harmonics`
  (:func:`~symsphere.harmonics.real_sh`, :func:`~symsphere.harmonics.real_sh_basis`,
  :func:`~symsphere.harmonics.sh_polynomial`, :func:`~symsphere.harmonics.monomial_integral`,
  :func:`~symsphere.harmonics.polynomial_integral`,
  :func:`~symsphere.harmonics.evaluate_polynomial`, :func:`~symsphere.harmonics.cubic_harmonic`);
- :func:`lambert_irradiance`, :func:`sphere_light_irradiance`: the closed
  forms of irradiance from a polygonal and from a spherical light.
- :func:`orbit_average`: the mean of ``f`` over the orbit of a point.

Every registered integrand also has a ``kernel``: the same function of one direction
compiled by numba, ``kernel(x, y, z) -> float``: one of the formulas of
``symsphere._integrand_kernels`` with the integrand's parameters as constants of the compiled
code (polynomials as explicit monomials, ``exp`` as a polynomial instead of libm's).  Given an
integrand with a kernel, :func:`symsphere.integrate` evaluates it inside its
parallel kernel (``integrate(INTEGRANDS["exp"], ...)``), vectorised across base
points where the expression has no libm call.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from fractions import Fraction
from types import MappingProxyType
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from ._constants import HEMISPHERE_AREA, SPHERE_AREA
from ._integrand_kernels import CAP, EXP, PHONG, POLYGON_LIGHT, POLYNOMIAL, SPHERE_LIGHT, Z, integrand_kernel
from ._irradiance import lambert_irradiance, sphere_light_irradiance
from ._threads import route_compiles
from ._typing import BoolArray, Domain, Float64Array, FloatArray
from ._validation import (
    check_choice,
    check_real_values,
)
from .harmonics import (
    cubic_harmonic,
    evaluate_polynomial,
    polynomial_integral,
    real_sh,
    sh_polynomial,
)
from .symmetry import orbit, orbit_size

__all__ = [
    "INTEGRANDS",
    "Integrand",
    "suite",
    "lambert_irradiance",
    "sphere_light_irradiance",
    "orbit_average",
]

_DOMAINS: tuple[Domain, ...] = ("sphere", "hemisphere")
_AREA = {"sphere": SPHERE_AREA, "hemisphere": HEMISPHERE_AREA}


@dataclass(frozen=True, eq=False)
class Integrand:
    """A test integrand with its exact integral.

    Attributes
    ----------
    name : str
        Key in `INTEGRANDS`.
    domain : {'sphere', 'hemisphere'}
        The hemisphere is z >= 0, about (0, 0, 1).
    f : callable
        ``f(d)`` for unit directions of shape (m, 3) (or (..., 3)) returns
        shape (m,) (or (...)), float64.
    exact : float
        The integral of ``f`` over the domain with respect to solid angle.
    description : str
        What the integrand is and where `exact` comes from.
    smooth : bool
        Infinitely differentiable on the domain (True also for the Phong
        lobe, which is C^19), as opposed to discontinuous.
    invariant : bool
        Constant on every orbit: ``f(d @ M) == f(d)`` for the 48 maps of
        ``SPHERE_MAPS`` (hemisphere: the 24 images of any point of T0).
    orbit_exact : bool
        The orbit average integrates ``f`` exactly: ``area * mean(f(orbit(p)))
        == exact`` for every p, so the symmetric scheme has zero variance
        on it (see ``docs/explanation/when-orbits-help.md``).  Verified in the tests.
    params : mapping
        The parameters (directions, angles, vertices, ...), read-only.
    kernel : numba function or None
        ``kernel(x, y, z)``: f at one direction, compiled (numba ``@njit``); with it,
        :func:`symsphere.integrate` fuses f into its kernel.  None: numpy only.

    Examples
    --------
    >>> import numpy as np
    >>> import symsphere
    >>> from symsphere.integrands import INTEGRANDS, Integrand, orbit_average
    >>> g = INTEGRANDS["exp"]
    >>> g.domain, g.smooth, g.orbit_exact
    ('sphere', True, False)
    >>> result = symsphere.integrate(g.f, n=48 * 4096, rng=1)
    >>> bool(abs(result.integral - g.exact) < 1e-3)
    True
    >>> fused = symsphere.integrate(g, n=48 * 4096, rng=1)      # g.kernel inside the kernel
    >>> bool(np.isclose(fused.integral, result.integral, rtol=1e-13))
    True

    A new integrand: z^2 is not invariant, but its mean over the orbit of any point p is
    ``|p|^2 / 3``, so the symmetric scheme integrates it exactly:

    >>> z2 = Integrand("z2", "sphere", lambda d: np.asarray(d)[..., 2] ** 2, 4 * np.pi / 3,
    ...                "z^2; exact: 4 pi / 3", smooth=True, invariant=False, orbit_exact=True)
    >>> p = symsphere.square_to_triangle([0.3, 0.6])          # a point of T0
    >>> bool(np.isclose(4 * np.pi * orbit_average(z2, p), z2.exact))
    True
    """

    name: str
    domain: Domain
    f: Callable[[FloatArray], Float64Array]
    exact: float
    description: str
    smooth: bool
    invariant: bool
    orbit_exact: bool
    params: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    kernel: Any = field(default=None, repr=False)

    def __call__(self, d: FloatArray) -> Float64Array:
        """``self.f(d)``."""
        return self.f(d)


def suite(domain: Domain | None = None) -> list[Integrand]:
    """The registered integrands, optionally only those of one domain.

    Parameters
    ----------
    domain : {'sphere', 'hemisphere'}, optional
        Default: all.

    Returns
    -------
    list of Integrand
        In registration order.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.integrands import suite
    >>> from symsphere.peers import sample_octahedral
    >>> d = sample_octahedral(4096, points="sobol", rng=0)
    >>> errors = {g.name: abs(4 * np.pi * g.f(d).mean() - g.exact) for g in suite("sphere")}
    >>> bool(errors["exp"] < 1e-2)
    True
    """
    if domain is None:
        return list(INTEGRANDS.values())
    domain = check_choice(domain, "domain", _DOMAINS)
    return [g for g in INTEGRANDS.values() if g.domain == domain]


# =============================================================================
# Lights
# =============================================================================


def orbit_average(
    f: Callable[[FloatArray], npt.ArrayLike], p: npt.ArrayLike, domain: Domain = "sphere"
) -> Float64Array:
    """Mean of ``f`` over the 48 (hemisphere: 24) images of each point p.

    ``area * orbit_average(f, p)`` with p uniform on T0 is the symmetric
    scheme's estimate of the integral of f from one base point.

    Parameters
    ----------
    f : callable
        ``f(d)`` for directions of shape (m, 3).
    p : array_like, shape (..., 3)
        Base points, usually in T0 = {z >= x >= y >= 0} (for the hemisphere
        they must be, so that all images have z >= 0).
    domain : {'sphere', 'hemisphere'}
        The 48 images on the sphere or the 24 on the hemisphere.

    Returns
    -------
    ndarray, shape (...)
        The mean of ``f`` over the images of each point.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere.integrands import orbit_average
    >>> float(orbit_average(lambda d: d[:, 0] * d[:, 1], [0.3, 0.2, 0.9]))   # odd in x: averages to 0
    0.0
    """
    if not callable(f):
        raise TypeError(f"'f' must be callable, got {type(f).__name__}")
    count = orbit_size(domain)
    images = orbit(p, domain)
    raw = f(images.reshape(-1, 3))
    try:
        values = check_real_values(raw, "f")  # NaN, inf, complex: an error, not a silent mean
    except ValueError:
        norms = _safe_norms(images[..., 0, :])
        far = ~((norms > 1e-100) & (norms < 1e100))  # rows no direction is near: p is to blame, not only f
        if np.any(far):
            worst = float(norms[far].flat[0])
            raise ValueError(
                f"'f' returned non-finite values at the images of 'p', whose rows are far from unit directions "
                f"(a norm of {worst:.3g}); pass directions as 'p'"
            ) from None
        raise
    expected = (int(np.prod(images.shape[:-1])),)
    if values.shape != expected:
        raise ValueError(f"'f' must return one value per direction, shape {expected}, got {values.shape}")
    with np.errstate(over="ignore", invalid="ignore"):  # an overflow is handled below, naming f
        grouped = values.reshape(images.shape[:-2] + (count,))
        mean: Float64Array = grouped.mean(axis=-1)
        if not np.all(np.isfinite(mean)):  # each value divided first: finite values near 1e308 average finitely
            mean = (grouped / count).sum(axis=-1)
    if not np.all(np.isfinite(mean)):
        row = int(np.flatnonzero(~np.isfinite(mean.ravel()))[0])
        raise ValueError(
            f"'f' returned values whose sum overflows float64 (the images of base point {row}, the first "
            f"{images.reshape(-1, count, 3)[row, 0].tolist()}); scale f down"
        )
    return mean


def _safe_norms(p: FloatArray) -> Float64Array:
    """Euclidean norms of the rows of *p* without overflow (rows of 1e308 have norm 1.7e308, not inf)."""
    points = np.asarray(p, dtype=np.float64)
    scale = np.max(np.abs(points), axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        scaled = np.where(scale > 0, points / np.where(scale > 0, scale, 1.0), 0.0)
    norms: Float64Array = scale[..., 0] * np.sqrt(np.sum(scaled * scaled, axis=-1))
    return norms


# =============================================================================
# Private helpers
# =============================================================================


def _unit3(v: npt.ArrayLike) -> Float64Array:
    a = np.asarray(v, dtype=np.float64)
    unit: Float64Array = a / np.linalg.norm(a)
    return unit


def _frozen(**kwargs: Any) -> Mapping[str, Any]:
    return MappingProxyType(
        {
            k: (np.array(v, dtype=np.float64) if isinstance(v, (list, tuple, np.ndarray)) else v)
            for k, v in kwargs.items()
        }
    )


def _polynomial_kernel(coeffs: Mapping[tuple[int, int, int], float | Fraction], shift: float = 0.0) -> Any:
    """The kernel of ``shift + sum c x^a y^b z^c``, the terms in sorted order (zero terms left out)."""
    params = [float(shift)]
    for (a, b, c), coefficient in sorted(coeffs.items()):
        if coefficient:
            params += [float(coefficient), a, b, c]
    return integrand_kernel(POLYNOMIAL, tuple(params))


# The two hemisphere integrals without a closed form, by 1D quadrature (scipy.integrate.quad, relative
# tolerance 1e-13); tests/test_integrands.py derives the formulas and recomputes both, and checks them
# against a cubature rule of its own.  Tabulated here, as importing scipy.integrate and scipy.special
# would add ~0.5 s to every command-line start.
_PHONG_HEMISPHERE = 0.9999999999123943  # the Phong lobe of "phong" (r, n = 20) over z >= 0
_EXP_HEMISPHERE = 9.005741315448399  # exp(w . a), a = (0.7, -0.4, 0.5), over z >= 0


def _quad_kernel(vertices: npt.ArrayLike, radiance: float) -> Any:
    """The kernel of L max(z, 0) 1[w inside the polygon's cone] (the planes of _polygon_inside)."""
    v = np.asarray(vertices, dtype=np.float64)
    normals = np.cross(v, np.roll(v, -1, axis=0))
    normals = np.sign(v.mean(axis=0) @ normals[0]) * normals
    return integrand_kernel(POLYGON_LIGHT, (radiance, *normals.ravel().tolist()))


def _polygon_inside(vertices: npt.ArrayLike) -> Callable[[FloatArray], BoolArray]:
    """Vectorised test: does the ray along w pass through the convex polygon?

    For a convex polygon not containing the origin, the rays through it form
    the convex cone on the inner side of the planes through the origin and
    each edge: sigma * w . (v_i x v_i+1) >= 0 for all i, sigma the orientation.
    """
    v = np.asarray(vertices, dtype=np.float64)
    normals = np.cross(v, np.roll(v, -1, axis=0))
    sigma = np.sign(v.mean(axis=0) @ normals[0])
    normals = sigma * normals

    def inside(d: FloatArray) -> BoolArray:
        hit: BoolArray = np.all(d @ normals.T >= 0, axis=-1)
        return hit

    return inside


# =============================================================================
# The registry
# =============================================================================


def _sh_integrand(
    l: int, m: int, domain: Domain = "sphere", shift: float = 0.0, orbit_exact: bool = False
) -> Integrand:
    poly = sh_polynomial(l, m)
    exact = shift * _AREA[domain] + (0.0 if domain == "sphere" and l > 0 else polynomial_integral(poly, domain))
    label = f"Y_{l},{m}" if not shift else f"{shift:g} + Y_{l},{m}"
    base = f"sh{l}_{m}" if not shift else f"shifted_sh{l}_{m}"
    name = base if domain == "sphere" else f"{base}_hemisphere"
    how = "0 (orthogonal to Y_00)" if domain == "sphere" else "moment formula"
    return Integrand(
        name,
        domain,
        lambda d: shift + real_sh(l, m, d),
        exact,
        f"real spherical harmonic {label}; exact: {how}",
        True,
        False,
        orbit_exact,
        _frozen(l=l, m=m, shift=shift),
        _polynomial_kernel(poly, shift),
    )


def _cubic_integrand(degree: Literal[4, 6, 8], shift: float = 0.0) -> Integrand:
    coeffs: dict[tuple[int, int, int], float | Fraction]
    if degree == 4:  # the brief form x^4 + y^4 + z^4 - 3/5 = (2/5) * harmonic on the sphere
        coeffs = {(4, 0, 0): 1, (0, 4, 0): 1, (0, 0, 4): 1, (0, 0, 0): Fraction(-3, 5)}
        label = "x^4 + y^4 + z^4 - 3/5"
    else:
        coeffs = dict(cubic_harmonic(degree))
        label = f"the O_h-invariant harmonic polynomial of degree {degree}"
    if shift:
        coeffs = dict(coeffs)
        coeffs[(0, 0, 0)] = coeffs.get((0, 0, 0), 0.0) + shift
        label = f"{shift:g} + {label}"
    name = f"cubic{degree}" if not shift else f"shifted_cubic{degree}"
    return Integrand(
        name,
        "sphere",
        lambda d: evaluate_polynomial(coeffs, d),
        polynomial_integral(coeffs, "sphere"),
        f"cubic harmonic: {label}; invariant under the 48 maps; exact: moment formula",
        True,
        True,
        False,
        _frozen(degree=degree, shift=shift),
        _polynomial_kernel(coeffs),
    )


def _build_integrands() -> dict[str, Integrand]:
    out: list[Integrand] = []
    # (a) pure harmonics: exact 0.  orbit_exact: those with no O_h-invariant component
    # (odd l, l = 2, and odd under a sign change of x or y), see docs/explanation/when-orbits-help.md.
    for l, m, exact_orbit in [
        (1, -1, True),
        (1, 0, True),
        (2, 0, True),
        (2, 1, True),
        (2, -2, True),
        (3, -2, True),
        (3, 0, True),
        (4, 0, False),
        (4, -2, True),
        (5, 3, True),
        (6, 0, False),
        (6, 4, False),
        (7, -5, True),
        (8, 0, False),
        (8, -5, True),
    ]:
        out.append(_sh_integrand(l, m, orbit_exact=exact_orbit))
    # (b) invariant cubic harmonics and (c) shifted versions.
    out += [_cubic_integrand(4), _cubic_integrand(6), _cubic_integrand(8)]
    out += [_cubic_integrand(4, 1.0), _cubic_integrand(6, 1.0), _cubic_integrand(8, 1.0)]
    out += [
        _sh_integrand(2, 1, shift=1.0, orbit_exact=True),
        _sh_integrand(4, 0, shift=1.0),
        _sh_integrand(7, 2, shift=1.0, orbit_exact=True),
    ]

    # Phong lobe, n = 20, about an off-axis direction.
    r = _unit3([0.3, -0.2, 0.9])
    n = 20

    def phong(d: FloatArray, r: Float64Array = r, n: int = n) -> Float64Array:
        d = np.asarray(d, dtype=np.float64)
        return (n + 1) / (2 * math.pi) * np.maximum(d @ r, 0.0) ** n

    assert n == 20  # the kernel's formula: (t^4)^5
    phong_kernel = integrand_kernel(PHONG, ((n + 1) / (2 * math.pi), *r.tolist()))
    out.append(
        Integrand(
            "phong",
            "sphere",
            phong,
            1.0,
            "normalised Phong lobe 21/(2 pi) max(0, w.r)^20, r = (0.3, -0.2, 0.9)/|.|; exact: 1",
            True,
            False,
            False,
            _frozen(direction=r, exponent=n),
            phong_kernel,
        )
    )
    out.append(
        Integrand(
            "phong_hemisphere",
            "hemisphere",
            phong,
            _PHONG_HEMISPHERE,
            "the Phong lobe over z >= 0 (it crosses the horizon slightly: 1 - 8.8e-11); "
            "exact: 1D quadrature about r, to ~1e-15",
            True,
            False,
            False,
            _frozen(direction=r, exponent=n),
            phong_kernel,
        )
    )

    # Spherical cap indicator.
    c = _unit3([0.5, 0.3, 0.8])
    alpha = 0.4
    cos_alpha = math.cos(alpha)
    cap_area = 2 * math.pi * 2 * math.sin(alpha / 2) ** 2  # 2 pi (1 - cos alpha)

    def cap(d: FloatArray, c: Float64Array = c, cos_alpha: float = cos_alpha) -> Float64Array:
        return (np.asarray(d, dtype=np.float64) @ c >= cos_alpha).astype(np.float64)

    cap_kernel = integrand_kernel(CAP, (cos_alpha, *c.tolist()))
    for domain in _DOMAINS:
        out.append(
            Integrand(
                "cap" if domain == "sphere" else "cap_hemisphere",
                domain,
                cap,
                cap_area,
                "indicator of the cap w.c >= cos 0.4, c = (0.5, 0.3, 0.8)/|.| (inside the "
                "hemisphere); exact: 2 pi (1 - cos alpha)",
                False,
                False,
                False,
                _frozen(axis=c, cos_alpha=cos_alpha),
                cap_kernel,
            )
        )

    # exp(w . a): all components.
    a = np.array([0.7, -0.4, 0.5])
    norm_a = float(np.linalg.norm(a))

    def expo(d: FloatArray, a: Float64Array = a) -> Float64Array:
        return np.exp(np.asarray(d, dtype=np.float64) @ a)

    exp_kernel = integrand_kernel(EXP, tuple(a.tolist()))
    for name, domain, exact, description in (
        (
            "exp",
            "sphere",
            4 * math.pi * math.sinh(norm_a) / norm_a,
            "exp(w.a), a = (0.7, -0.4, 0.5); exact: 4 pi sinh|a| / |a|",
        ),
        (
            "exp_hemisphere",
            "hemisphere",
            _EXP_HEMISPHERE,
            "exp(w.a) over z >= 0; exact: 2 pi int_0^1 exp(a_z z) I0(|a_xy| sqrt(1 - z^2)) dz by quadrature, ~1e-15",
        ),
    ):
        out.append(Integrand(name, domain, expo, exact, description, True, False, False, _frozen(a=a), exp_kernel))

    # Hemisphere: cos theta and harmonics with the odd-c moment formula.
    out.append(
        Integrand(
            "cosine",
            "hemisphere",
            lambda d: np.asarray(d, dtype=np.float64)[..., 2],
            math.pi,
            "cos(theta) = z; exact: pi",
            True,
            False,
            False,
            _frozen(),
            integrand_kernel(Z, (0.0,)),
        )
    )
    out += [
        _sh_integrand(3, 0, "hemisphere"),
        _sh_integrand(5, 0, "hemisphere"),
        _sh_integrand(2, 1, "hemisphere", orbit_exact=True),
        _sh_integrand(4, 0, "hemisphere", shift=1.0),
    ]

    # Irradiance from a spherical light.
    light_c = _unit3([-0.4, 0.2, 1.0])
    radiance, distance, radius = 3.0, 5.0, 1.5
    cos_light = math.sqrt(distance**2 - radius**2) / distance

    def sphere_light(
        d: FloatArray, c: Float64Array = light_c, cos_light: float = cos_light, radiance: float = radiance
    ) -> Float64Array:
        d = np.asarray(d, dtype=np.float64)
        return radiance * np.maximum(d[..., 2], 0.0) * (d @ c >= cos_light)

    out.append(
        Integrand(
            "sphere_light",
            "hemisphere",
            sphere_light,
            sphere_light_irradiance(light_c, distance, radius, radiance),
            "irradiance L cos(theta) 1[w hits a sphere of radius 1.5 at distance 5 towards "
            "(-0.4, 0.2, 1)], L = 3; exact: pi L (R/D)^2 cos(beta)",
            False,
            False,
            False,
            _frozen(center=light_c, distance=distance, radius=radius, radiance=radiance, cos_alpha=cos_light),
            integrand_kernel(SPHERE_LIGHT, (radiance, cos_light, *light_c.tolist())),
        )
    )

    # Irradiance from a quad light (a parallelogram above the horizon), Lambert's formula.
    centre = np.array([0.4, -0.3, 2.0])
    e1, e2 = np.array([1.2, 0.0, 0.4]), np.array([0.0, 0.9, -0.3])
    quad = np.array(
        [centre - e1 / 2 - e2 / 2, centre + e1 / 2 - e2 / 2, centre + e1 / 2 + e2 / 2, centre - e1 / 2 + e2 / 2]
    )
    quad_radiance = 2.0
    inside = _polygon_inside(quad)

    def quad_light(
        d: FloatArray, inside: Callable[[FloatArray], BoolArray] = inside, radiance: float = quad_radiance
    ) -> Float64Array:
        d = np.asarray(d, dtype=np.float64)
        return radiance * np.maximum(d[..., 2], 0.0) * inside(d)

    out.append(
        Integrand(
            "quad_light",
            "hemisphere",
            quad_light,
            lambert_irradiance(quad, radiance=quad_radiance),
            "irradiance L cos(theta) 1[w passes through a parallelogram light], L = 2; exact: Lambert's formula",
            False,
            False,
            False,
            _frozen(vertices=quad, radiance=quad_radiance),
            _quad_kernel(quad, quad_radiance),
        )
    )
    return {g.name: g for g in out}


INTEGRANDS = _build_integrands()
"""dict name -> :class:`Integrand`."""


route_compiles(globals())  # the first compile of each numba function here: interruptible (_threads)
