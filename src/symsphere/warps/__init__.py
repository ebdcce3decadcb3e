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
``square_to_projected_triangle``    triangle     cos(theta) / E about a normal on any spherical triangle
                                                 (projected solid angle E: ``projected_solid_angle``)
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

from ._concentric import (
    concentric_disk_point,
    concentric_disk_to_square,
    cosine_hemisphere_point,
    cosine_hemisphere_to_square,
    square_to_concentric_disk,
    square_to_concentric_disk_pdf,
    square_to_cosine_hemisphere,
    square_to_cosine_hemisphere_pdf,
)
from ._octahedral import (
    octahedral_hemisphere_to_square,
    octahedral_sphere_point,
    octahedral_sphere_to_square,
    square_to_octahedral_hemisphere,
    square_to_octahedral_hemisphere_pdf,
    square_to_octahedral_sphere,
    square_to_octahedral_sphere_pdf,
)
from ._projected_triangle import (
    projected_solid_angle,
    projected_triangle_density,
    projected_triangle_point,
    projected_triangle_setup,
    projected_triangle_to_square,
    projected_triangle_uv,
    square_to_projected_triangle,
    square_to_projected_triangle_pdf,
)
from ._record import Warp
from ._registry import WARPS, get_warp
from ._scheme import (
    hemisphere_to_square,
    sphere_to_square,
    square_to_hemisphere,
    square_to_hemisphere_pdf,
    square_to_sphere,
    square_to_sphere_pdf,
    strip_order,
)
from ._spherical_rectangle import (
    rectangle_frame,
    rectangle_point,
    spherical_rectangle_to_square,
    square_to_spherical_rectangle,
    square_to_spherical_rectangle_pdf,
)
from ._spherical_triangle import (
    T0_VERTICES,
    arvo_triangle_to_square,
    spherical_triangle_to_square,
    square_to_arvo_triangle,
    square_to_arvo_triangle_pdf,
    square_to_spherical_triangle,
    square_to_spherical_triangle_pdf,
)
from ._triangle import (
    METHODS,
    TRIANGLE_WARPS,
    square_to_triangle,
    square_to_triangle_pdf,
    triangle_to_square,
    triangle_warp,
)
from ._uniform import (
    square_to_uniform_hemisphere,
    square_to_uniform_hemisphere_pdf,
    square_to_uniform_sphere,
    square_to_uniform_sphere_pdf,
    uniform_hemisphere_point,
    uniform_hemisphere_to_square,
    uniform_sphere_point,
    uniform_sphere_to_square,
)
from ._wedge import (
    WEDGE_MAPS,
    cosine_wedge_density,
    cosine_wedge_point,
    cosine_wedge_to_square,
    cosine_wedge_uv,
    square_to_cosine_wedge,
    square_to_cosine_wedge_pdf,
)

__all__ = [
    # the record and the registry
    "Warp",
    "WARPS",
    "get_warp",
    # T0: the scheme's maps
    "METHODS",
    "TRIANGLE_WARPS",
    "triangle_warp",
    "square_to_triangle",
    "square_to_triangle_pdf",
    "triangle_to_square",
    # the scheme as one bijection
    "square_to_sphere",
    "square_to_sphere_pdf",
    "sphere_to_square",
    "square_to_hemisphere",
    "square_to_hemisphere_pdf",
    "hemisphere_to_square",
    "strip_order",
    # the cosine wedge
    "WEDGE_MAPS",
    "square_to_cosine_wedge",
    "square_to_cosine_wedge_pdf",
    "cosine_wedge_to_square",
    "cosine_wedge_point",
    "cosine_wedge_density",
    "cosine_wedge_uv",
    # hat-box
    "square_to_uniform_sphere",
    "square_to_uniform_sphere_pdf",
    "uniform_sphere_to_square",
    "uniform_sphere_point",
    "square_to_uniform_hemisphere",
    "square_to_uniform_hemisphere_pdf",
    "uniform_hemisphere_to_square",
    "uniform_hemisphere_point",
    # octahedral
    "square_to_octahedral_sphere",
    "square_to_octahedral_sphere_pdf",
    "octahedral_sphere_to_square",
    "octahedral_sphere_point",
    "square_to_octahedral_hemisphere",
    "square_to_octahedral_hemisphere_pdf",
    "octahedral_hemisphere_to_square",
    # concentric disk and cosine hemisphere
    "square_to_concentric_disk",
    "square_to_concentric_disk_pdf",
    "concentric_disk_to_square",
    "concentric_disk_point",
    "square_to_cosine_hemisphere",
    "square_to_cosine_hemisphere_pdf",
    "cosine_hemisphere_to_square",
    "cosine_hemisphere_point",
    # Arvo's spherical triangles
    "T0_VERTICES",
    "square_to_spherical_triangle",
    "square_to_spherical_triangle_pdf",
    "spherical_triangle_to_square",
    "square_to_spherical_rectangle",
    "square_to_spherical_rectangle_pdf",
    "spherical_rectangle_to_square",
    "rectangle_frame",
    "rectangle_point",
    "square_to_arvo_triangle",
    "square_to_arvo_triangle_pdf",
    "arvo_triangle_to_square",
    # a spherical triangle by projected solid angle
    "projected_solid_angle",
    "square_to_projected_triangle",
    "square_to_projected_triangle_pdf",
    "projected_triangle_to_square",
    "projected_triangle_setup",
    "projected_triangle_point",
    "projected_triangle_uv",
    "projected_triangle_density",
]
