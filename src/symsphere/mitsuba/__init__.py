"""symsphere.mitsuba: the scheme inside Mitsuba 3 (optional extra ``mitsuba``).

- The maps in Dr.Jit (:mod:`symsphere.mitsuba` re-exports them): the T0 maps
  (``square_to_triangle``, ``square_to_triangle_pdf``, ``triangle_to_square``), the orbit
  member and the fold, the whole-sphere/hemisphere bijection of :mod:`symsphere.warps`
  and the cosine wedge map, in Mitsuba's ``warp.h`` form; they run in every variant.
- The integrator ``symsphere_path`` (:func:`integrator_class`): Mitsuba's ``path`` estimator
  whose direction at Lambertian vertices comes from the chosen ``strategy``, differentiable as
  ``prb`` (path replay; docs/reference/mitsuba-plugin.md); registered with
  Mitsuba (:func:`register`) when this module is imported, for the variant set then and for
  every variant set later (a Mitsuba variant callback).
- The scene files shipped with the package (:func:`scene_path`, :data:`SCENES`).

``import symsphere`` never imports this module (nor Mitsuba).  See docs/reference/mitsuba-plugin.md.
"""

from __future__ import annotations

try:
    import drjit as _drjit  # noqa: F401
    import mitsuba as _mitsuba
except ImportError as _error:  # pragma: no cover - exercised without the extra
    raise ImportError(
        "symsphere.mitsuba needs Mitsuba 3 and Dr.Jit: pip install 'symsphere[mitsuba]' "
        "(Mitsuba's LLVM variants also need libLLVM >= 16, Debian: apt-get install libllvm19)"
    ) from _error

from ._integrator import GROUP_SIZES, POINTS, STRATEGIES, integrator_class, on_variant_change, register
from ._scenes import SCENES, scene_path
from ._warps import (
    cosine_wedge_to_square,
    fold,
    hemisphere_to_square,
    orbit_member,
    sphere_to_square,
    square_to_cosine_wedge,
    square_to_cosine_wedge_pdf,
    square_to_hemisphere,
    square_to_hemisphere_pdf,
    square_to_sphere,
    square_to_sphere_pdf,
    square_to_triangle,
    square_to_triangle_pdf,
    triangle_to_square,
)

__all__ = [
    "integrator_class",
    "register",
    "SCENES",
    "scene_path",
    "STRATEGIES",
    "POINTS",
    "GROUP_SIZES",
    "square_to_triangle",
    "square_to_triangle_pdf",
    "triangle_to_square",
    "orbit_member",
    "fold",
    "square_to_sphere",
    "square_to_sphere_pdf",
    "sphere_to_square",
    "square_to_hemisphere",
    "square_to_hemisphere_pdf",
    "hemisphere_to_square",
    "square_to_cosine_wedge",
    "square_to_cosine_wedge_pdf",
    "cosine_wedge_to_square",
]

if _mitsuba.variant() is not None:
    register()
_mitsuba.detail.add_variant_callback(on_variant_change)  # and for every variant set later
