"""The cosine-weighted map of the unit square onto the wedge 0 <= phi <= pi/4 of the hemisphere.

Stand-in until :mod:`symsphere.wedge` lands: Malley's method restricted to the
wedge, polar coordinates on the disk sector of angle pi/4: ``r^2 = u`` (area
uniform in the sector), ``phi = (pi / 4) v``, lifted to ``z = sqrt(1 - r^2)``.
The density is ``8 cos(theta) / pi`` on the wedge, so a uniformly random image
under the 8 signed permutations that keep z is cosine-distributed on the
hemisphere (pdf ``cos(theta) / pi``).
"""

from __future__ import annotations

import math

from numba.extending import register_jitable

__all__ = ["wedge_point"]


@register_jitable
def wedge_point(u, v):
    """(x, y, z) on the wedge 0 <= phi <= pi/4 of the upper hemisphere; density 8 cos(theta) / pi."""
    r = math.sqrt(u)
    phi = (0.25 * math.pi) * v
    return r * math.cos(phi), r * math.sin(phi), math.sqrt(max(0.0, 1.0 - u))
