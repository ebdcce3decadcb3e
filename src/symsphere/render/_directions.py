"""Direction sampling at the renderer's diffuse vertices: the strategies' numba form, one direction at a time.

:func:`sample_local` draws a direction about the local pole (0, 0, 1) by one of the strategies of
:data:`symsphere.render.STRATEGIES` with its base points, and :func:`bsdf_pdf` is its density
(what multiple importance sampling needs); the path estimator (:mod:`symsphere.render._integrator`)
calls them at every diffuse and translucent vertex, inlined by LLVM into its kernel.  They go
through scalar library functions -- the maps and the orbit (``triangle_point``,
``triangle_density``, ``orbit_member`` of :mod:`symsphere._kernels`), the classic uniform and cosine
maps (``uniform_hemisphere_point`` etc. of :mod:`symsphere.warps`) and the cosine-weighted wedge
map (:func:`symsphere.warps.cosine_wedge_point`) -- so no formula is restated.  The ``symsphere_path``
plugin draws the same directions in Dr.Jit from the same keys and tags (:data:`symsphere._constants.BASE_U`).

Kernel codes
------------
One code per (strategy, points) pair that the renderer takes (``symsphere.render.renderer`` maps
the words to them).  ``UNIFORM`` (strategy ``uniform``) classic uniform directions
(``warps.uniform_hemisphere_point``, ``uniform_sphere_point``); ``COSINE`` (``cosine``) Shirley-Chiu
concentric disk + Malley (``warps.cosine_hemisphere_point``; the full sphere: a side with probability
1/2); ``ORBIT`` (``orbit``) a random base point mapped onto T0 and a uniformly random orbit member,
i.i.d.; ``SYMMETRIC`` (``symmetric``, points ``random``) the paper's pattern inside a pixel with
random base points; ``SYMMETRIC_SOBOL`` (points ``sobol``) the same with Owen-scrambled Sobol' base
points; ``SYMMETRIC_COSINE`` and ``SYMMETRIC_COSINE_SOBOL`` (``symmetric_cosine``) the same pattern
with the 8 signed permutations that keep z (16 with the side through transmission) and a
cosine-weighted map onto the wedge 0 <= phi <= pi/4; ``SYMMETRIC_SOBOL_INTERLACED2/3`` and
``SYMMETRIC_COSINE_SOBOL_INTERLACED2/3`` (points ``sobol_interlaced2/3``) the two patterns with
interlaced (higher-order) scrambled Sobol' base points.  See :func:`sample_local` for the exact
mapping of (sample, vertex) to (group, member, base point).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numba.extending import register_jitable

from .._constants import BASE_U, BASE_V, INV_2PI, INV_4PI, INV_PI
from .._kernels import orbit_member, triangle_density, triangle_point
from .._random.hashes import below, next_u64, u01
from .._random.owen_sobol import owen_sobol2, owen_sobol_interlaced
from .._random.splitmix import GOLDEN, ODD, mix64
from .._threads import route_compiles
from ..warps import cosine_hemisphere_point, cosine_wedge_point, uniform_hemisphere_point, uniform_sphere_point
from ._emitters import INLINED

__all__ = [
    "UNIFORM", "COSINE", "ORBIT", "SYMMETRIC", "SYMMETRIC_SOBOL", "SYMMETRIC_COSINE", "SYMMETRIC_COSINE_SOBOL",
    "SYMMETRIC_SOBOL_INTERLACED2", "SYMMETRIC_SOBOL_INTERLACED3", "SYMMETRIC_COSINE_SOBOL_INTERLACED2",
    "SYMMETRIC_COSINE_SOBOL_INTERLACED3", "fixed_sampler", "is_cosine", "sample_local", "bsdf_pdf",
]  # fmt: skip

UNIFORM, COSINE, ORBIT, SYMMETRIC, SYMMETRIC_SOBOL, SYMMETRIC_COSINE, SYMMETRIC_COSINE_SOBOL = range(7)
SYMMETRIC_SOBOL_INTERLACED2, SYMMETRIC_SOBOL_INTERLACED3 = 7, 8
SYMMETRIC_COSINE_SOBOL_INTERLACED2, SYMMETRIC_COSINE_SOBOL_INTERLACED3 = 9, 10

_INV_PI, _INV_4PI = INV_PI, INV_4PI  # the kernels' spelling
_BASE_U = np.uint64(BASE_U)  # distinct tags that split a group key into u and v
_BASE_V = np.uint64(BASE_V)
_GOLDEN, _ODD = GOLDEN, ODD  # SplitMix64's constants (symsphere._random.splitmix), as the kernels name them
_ONE = np.uint64(1)


@register_jitable
def fixed_sampler(sampler):
    """*sampler* if it is UNIFORM, COSINE or ORBIT, else -1: a symmetric sampler (its base-point source,
    random, Sobol' or interlaced, is then read from *sampler* itself)."""
    if sampler == UNIFORM or sampler == COSINE or sampler == ORBIT:
        return sampler
    return -1


@register_jitable
def is_cosine(sampler):
    """The symmetric cosine samplers and the i.i.d. cosine sampler: pdf cos / pi (sphere |cos| / (2 pi))."""
    return (
        sampler == COSINE or sampler == SYMMETRIC_COSINE or sampler == SYMMETRIC_COSINE_SOBOL
        or sampler == SYMMETRIC_COSINE_SOBOL_INTERLACED2 or sampler == SYMMETRIC_COSINE_SOBOL_INTERLACED3
    )  # fmt: skip


@njit(**INLINED)
def sample_local(sampler, fixed, cosine, code, full, key, s, depth, state):
    """A direction about the local pole (0, 0, 1), its weight ``|cos| / (pi pdf)`` and its pdf.

    Parameters
    ----------
    sampler, code : int
        Sampler code and map code (``METHOD_CODES``; used by the orbit samplers).
    fixed, cosine : int, bool
        ``fixed_sampler(sampler)`` and ``is_cosine(sampler)``, computed once per kernel call: the
        sampler family; *sampler* itself then only chooses the symmetric samplers' base-point source.
    full : bool
        Sample the whole sphere (Lambertian transmission) rather than the
        upper hemisphere.
    key : uint64
        The pixel's key (:func:`~symsphere._random.hashes.pixel_key`).
    s, depth : int
        Sample index within the pixel, vertex index along the path (0 = first hit).
    state : uint64
        The path's random stream.

    Returns
    -------
    (x, y, z, weight, pdf, state)
        For a BSDF ``f = c / pi`` the throughput factor is ``c * weight``;
        pdf (solid angle) is what :func:`bsdf_pdf` returns for (x, y, z): the
        marginal density of one sample, the one MIS needs.

    Notes
    -----
    With n = 24 (hemisphere) or 48 (sphere), the symmetric samplers put
    sample s in group ``g = s // n``.  At vertex *depth* the group shares one
    base point B(g, depth) (``SYMMETRIC``: two hashes of (pixel, depth, n,
    g); ``SYMMETRIC_SOBOL``: point g of the Owen-scrambled, index-shuffled
    Sobol' sequence seeded by (pixel, depth, n); ``..._INTERLACED2/3``: point g
    of the interlaced one, :func:`~symsphere._random.owen_sobol.owen_sobol_interlaced`)
    and one offset o(g, depth)
    uniform in 0..n-1 (a third hash), and sample s takes orbit member
    ``(s mod n + o) mod n``.  The n
    samples of a complete group take all n members of B in turn; each sample
    on its own gets a uniform member of a fresh, independent base point at
    every vertex, so each path has exactly the distribution of the i.i.d.
    ``ORBIT`` sampler (unbiased sample by sample, for any spp).  Without the
    offset a sample would keep member s mod n at every vertex, confined to
    one triangle of every local frame: biased.

    ``SYMMETRIC_COSINE`` and ``SYMMETRIC_COSINE_SOBOL`` do the same with
    n = 8 members, the signed permutations (x, y, z) -> (+-x, +-y, z),
    (+-y, +-x, z) (``orbit_member`` 0..7), which keep z and hence the cosine
    density; through transmission n = 16, members 8..15 being the same maps
    followed by z -> -z (``orbit_member`` 24..31).  The base point is the
    cosine-weighted map onto the wedge 0 <= phi <= pi/4
    (:func:`symsphere.warps.cosine_wedge_point`), whose
    8 images tile the hemisphere: each sample is cosine-distributed.
    """
    if fixed == UNIFORM:
        state, b1 = next_u64(state)
        state, b2 = next_u64(state)
        if full:
            x, y, z = uniform_sphere_point(u01(b1), u01(b2))
            return x, y, z, 4.0 * abs(z), _INV_4PI, state
        x, y, z = uniform_hemisphere_point(u01(b1), u01(b2))
        return x, y, z, 2.0 * z, INV_2PI, state
    if fixed == COSINE:
        state, b1 = next_u64(state)
        state, b2 = next_u64(state)
        x, y, z = cosine_hemisphere_point(u01(b1), u01(b2))
        if full:
            state, b3 = next_u64(state)
            if b3 >> np.uint64(63):
                z = -z
            return x, y, z, 2.0, abs(z) * INV_2PI, state
        return x, y, z, 1.0, z * _INV_PI, state
    if cosine:
        n = 16 if full else 8
    else:
        n = 48 if full else 24
    if fixed == ORBIT:
        state, b1 = next_u64(state)
        state, b2 = next_u64(state)
        state, b3 = next_u64(state)
        u = u01(b1)
        v = u01(b2)
        member = below(b3, n)
    else:
        if cosine:  # literal divisors: no integer division instruction
            group = s // 16 if full else s // 8
        else:
            group = s // 48 if full else s // 24
        vertex_key = mix64(key ^ (np.uint64(depth) * _GOLDEN + np.uint64(n)))  # (pixel, vertex, orbit size)
        h = mix64(vertex_key ^ ((np.uint64(group) + _ONE) * _ODD))  # ... and group
        member = s - n * group + below(h, n)  # (s mod n + offset) mod n, both terms < n
        if member >= n:
            member -= n
        if sampler == SYMMETRIC or sampler == SYMMETRIC_COSINE:
            u = u01(mix64(h ^ _BASE_U))
            v = u01(mix64(h ^ _BASE_V))
        elif sampler == SYMMETRIC_SOBOL or sampler == SYMMETRIC_COSINE_SOBOL:
            u, v = owen_sobol2(group, vertex_key)  # point `group` of the sequence scrambled for this (pixel, vertex, n)
        else:  # the same, interlaced
            factor = 2 if sampler == SYMMETRIC_SOBOL_INTERLACED2 or sampler == SYMMETRIC_COSINE_SOBOL_INTERLACED2 else 3
            u, v = owen_sobol_interlaced(group, vertex_key, factor)
    if cosine:
        bx, by, bz = cosine_wedge_point(u, v)
        x, y, z = orbit_member(bx, by, bz, member if member < 8 else member + 16)  # 8..15 -> 24..31: z -> -z
        if full:
            return x, y, z, 2.0, abs(z) * INV_2PI, state
        return x, y, z, 1.0, z * _INV_PI, state
    bx, by, bz = triangle_point(u, v, code)
    density = triangle_density(bx, by, bz, code)
    x, y, z = orbit_member(bx, by, bz, member)
    if density > 0.0:
        weight = abs(z) * n * _INV_PI / density  # density = +inf at the paper maps' vertex: weight 0
    else:
        weight = 0.0  # unreachable: triangle_point clamps into T0, where the density is positive
    return x, y, z, weight, density / n, state


@njit(**INLINED)
def bsdf_pdf(fixed, cosine, code, full, x, y, z):
    """The solid-angle density with which *sampler* draws the local unit direction (x, y, z).

    The marginal density of one sample (what :func:`sample_local` returns as
    pdf): 1/(2 pi) (sphere 1/(4 pi)) for ``UNIFORM``; z / pi (sphere
    |z| / (2 pi)) for ``COSINE`` and the symmetric cosine samplers;
    ``triangle_density(fold(x, y, z)) / n`` for the orbit samplers, fold =
    sorting |x|, |y|, |z| into T0 = {z >= x >= y >= 0}.  Hemisphere samplers:
    only for z >= 0.
    """
    if fixed == UNIFORM:
        return _INV_4PI if full else INV_2PI
    if cosine:
        return abs(z) * INV_2PI if full else z * _INV_PI
    a, b, c = abs(x), abs(y), abs(z)  # a three-element sorting network: a >= b >= c
    if a < b:
        a, b = b, a
    if b < c:
        b, c = c, b
    if a < b:
        a, b = b, a
    return triangle_density(b, c, a, code) / (48 if full else 24)


route_compiles(globals())  # the first compile of each numba function here: interruptible (_threads)
