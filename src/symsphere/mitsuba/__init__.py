"""symsphere.mitsuba: the scheme inside Mitsuba 3 (optional extra ``mitsuba``).

- The maps in Dr.Jit (:mod:`symsphere.mitsuba` re-exports them): the T0 maps
  (``square_to_triangle``, ``square_to_triangle_pdf``, ``triangle_to_square``), the orbit
  member and the fold, the whole-sphere/hemisphere bijection of :mod:`symsphere.warps`
  and the cosine wedge map, in Mitsuba's ``warp.h`` form; they run in every variant.  Urena et al.'s
  spherical rectangle (``square_to_spherical_rectangle``, ``…_pdf``, ``spherical_rectangle_to_square``,
  ``spherical_rectangle_solid_angle``; JIT variants, float32 or float64).
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

from . import _rectangle, _warps
from ._integrator import GROUP_SIZES, POINTS, STRATEGIES, integrator_class, on_variant_change, register
from ._rectangle import *  # noqa: F403  (Urena's spherical rectangle in Dr.Jit: _rectangle.__all__)
from ._scenes import SCENES, scene_path
from ._warps import *  # noqa: F403  (the maps in Dr.Jit, listed once: in _warps.__all__)

__all__ = [
    "integrator_class",
    "register",
    "SCENES",
    "scene_path",
    "STRATEGIES",
    "POINTS",
    "GROUP_SIZES",
]
__all__ += _warps.__all__ + _rectangle.__all__

if _mitsuba.variant() is not None:
    register()
_mitsuba.detail.add_variant_callback(on_variant_change)  # and for every variant set later
