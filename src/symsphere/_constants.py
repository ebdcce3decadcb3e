"""Numbers the package states once, each with where it comes from.

Every value is the correctly rounded float64 of its expression (or the exact integer), so a module
that used to spell it out gets the same bits by importing it: ``1.0 / (4.0 * math.pi)`` and
``0.25 / math.pi`` round alike (multiplying pi by a power of 2 is exact).

Examples
--------
>>> import math
>>> from symsphere._constants import GOLDEN_BITS, INV_4PI, SPHERE_AREA, T0_DENSITY
>>> INV_4PI == 0.25 / math.pi, T0_DENSITY * SPHERE_AREA / 48 == 1.0
(True, True)
>>> hex(GOLDEN_BITS)
'0x9e3779b97f4a7c15'
"""

from __future__ import annotations

import math

__all__ = [
    "INV_PI", "INV_2PI", "INV_4PI", "SPHERE_AREA", "HEMISPHERE_AREA", "T0_DENSITY", "GOLDEN_BITS",
    "TWO_POW_M53", "BASE_U", "BASE_V",
]  # fmt: skip

INV_PI = 1.0 / math.pi
"""1/pi: the cosine-weighted hemisphere's density at the pole, a Lambertian BSDF's albedo factor."""

INV_2PI = 1.0 / (2.0 * math.pi)
"""1/(2 pi): the uniform density on the hemisphere."""

INV_4PI = 1.0 / (4.0 * math.pi)
"""1/(4 pi): the uniform density on the sphere."""

SPHERE_AREA = 4.0 * math.pi
"""The sphere's solid angle, 4 pi."""

HEMISPHERE_AREA = 2.0 * math.pi
"""The hemisphere's solid angle, 2 pi."""

T0_DENSITY = 12.0 / math.pi
"""12/pi: the uniform density on the fundamental triangle T0, one 48th of the sphere (area pi/12)."""

GOLDEN_BITS = (math.isqrt(5 << 128) - (1 << 64)) >> 1
"""floor(2**64 / phi) = floor(2**64 (sqrt(5) - 1) / 2), an odd int (0x9E3779B97F4A7C15): SplitMix64's
increment and the Fibonacci lattice's fraction, in 64 bits."""

TWO_POW_M53 = 2.0**-53
"""2**-53: numpy's ``next_double`` step (a double in [0, 1) from the top 53 bits of a uint64)."""

BASE_U = 0x2545F4914F6CDD1D
"""The tag that derives a group's base-point coordinate u from its key (``mix64(key ^ BASE_U)``): the
symmetric strategies with random points, in the numba renderer and in ``symsphere_path`` alike (the same
directions from the same key)."""

BASE_V = 0x5851F42D4C957F2D
"""The tag of the coordinate v, as :data:`BASE_U` (distinct tags: u and v independent)."""

assert GOLDEN_BITS == 0x9E3779B97F4A7C15
