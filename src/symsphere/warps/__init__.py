"""Maps of the unit square: every warp of symsphere, each a triple forward / pdf / inverse.

One naming template for all, Mitsuba 3's ``core/warp.h``: ``square_to_X`` maps points of
[0, 1]^2 onto the domain, ``square_to_X_pdf`` is the density (with respect to solid angle;
area for the disk) and ``X_to_square`` the inverse.  Elementwise formulas that numba compiles
into the kernels are ``X_point(u, v)`` (and, for the wedge, ``cosine_wedge_density``,
``cosine_wedge_uv``).  Every warp is described by a :class:`Warp` record in :data:`WARPS`
(domain, uniform or not, orbit size).

=================================== ============ ============================================================
maps                                domain       what
=================================== ============ ============================================================
``square_to_triangle``              T0           the scheme's maps onto T0 = {z >= x >= y >= 0}:
                                                 ``method='equal_area'`` (exact, uniform), ``'paper1'``,
                                                 ``'paper2'`` (the paper's Algorithms 1 and 2, not uniform)
``square_to_sphere``,               sphere,      the scheme as one bijection of the square through its 48
``square_to_hemisphere``            hemisphere   (24) triangles, strip by strip
``square_to_cosine_wedge``          wedge        cosine-weighted onto W = {x >= y >= 0, z >= 0} (8 images)
``square_to_uniform_sphere``,       sphere,      z = 1 - 2u (z = u), phi = 2 pi v: Archimedes' hat-box map
``square_to_uniform_hemisphere``    hemisphere
``square_to_octahedral_sphere``,    sphere,      Clarberg's equal-area octahedral maps (JGT 2008)
``square_to_octahedral_hemisphere`` hemisphere
``square_to_concentric_disk``       disk         Shirley & Chiu (1997)
``square_to_cosine_hemisphere``     hemisphere   the concentric disk lifted by Malley's method: cos(theta)/pi
``square_to_spherical_triangle``    triangle     Arvo (1995) onto any spherical triangle;
                                                 ``square_to_arvo_triangle``: onto T0
``square_to_spherical_rectangle``   rectangle    Urena, Fajardo & King (2013) onto a rectangle seen from 0
=================================== ============ ============================================================

Every map is exact and has no NaN or inf for u, v in {0, 1}, in float64 and float32; results take
the floating dtype of the input.  The samplers built on them are in :mod:`symsphere.sampling` (the
scheme) and :mod:`symsphere.peers` (the peers).

Examples
--------
>>> import numpy as np
>>> from symsphere.warps import WARPS
>>> sorted(name for name, w in WARPS.items() if w.domain == "sphere" and w.uniform)
['octahedral_sphere', 'sphere_equal_area', 'uniform_sphere']
>>> w = WARPS["octahedral_sphere"]
>>> d = w.forward([[0.1, 0.8]])
>>> bool(np.allclose(w.inverse(d), [[0.1, 0.8]])), float(w.pdf(d)[0] * 4 * np.pi)
(True, 1.0)
"""

# isort: off
# Each module below holds maps and registers their Warp records; the order of these lines is the order of
# WARPS (and of the table above).  Adding a warp is its module and one line here.
from ._record import Warp
from ._registry import WARPS, get_warp
from ._registry import namespace as _namespace
from ._triangle import *  # noqa: F403
from ._spherical_triangle import *  # noqa: F403
from ._scheme import *  # noqa: F403
from ._wedge import *  # noqa: F403
from ._uniform import *  # noqa: F403
from ._octahedral import *  # noqa: F403
from ._concentric import *  # noqa: F403
from ._spherical_rectangle import *  # noqa: F403
# isort: on

__all__ = ["Warp", "WARPS", "get_warp", *_namespace(__name__)]  # each module's names are listed once, in its __all__
