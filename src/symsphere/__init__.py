"""symsphere: exactly uniform, symmetric Monte Carlo and quasi-Monte Carlo sampling of directions.

The sphere is cut into 48 congruent orthogonal spherical triangles (the
hemisphere into 24) by the coordinate and bisector planes (Dimov, Penzov &
Stoilova, *Parallel Monte Carlo Sampling Scheme for Sphere and Hemisphere*).
One point of the fundamental triangle T0 = {z >= x >= y >= 0} gives 48 (24)
directions by signed coordinate permutations.  The paper's two maps from the
unit square onto T0 are shipped as printed, with their exact (non-uniform)
densities; the default map, ``'equal_area'``, is exactly uniform.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .integrate import IntegrationResult, integrate
from .maps import METHODS, square_to_triangle, triangle_pdf, triangle_to_square
from .points import POINT_SETS
from .sampling import hemisphere_pdf, iter_hemisphere, iter_sphere, sample_hemisphere, sample_sphere, sphere_pdf
from .symmetry import HEMISPHERE_MAPS, SPHERE_MAPS, fold, orbit

__version__ = "0.1.0"

_SUBMODULES = ("bins", "distributed", "harmonics", "integrands", "peers", "stats", "wedge")


if TYPE_CHECKING:
    from types import ModuleType


def __getattr__(name: str) -> ModuleType:
    # Submodules that need scipy.stats, scipy.integrate or dask are imported on first use
    # (PEP 562), so that ``import symsphere`` and a first sample stay fast.
    if name in _SUBMODULES:
        import importlib

        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

__all__ = [
    "HEMISPHERE_MAPS",
    "METHODS",
    "POINT_SETS",
    "SPHERE_MAPS",
    "bins",
    "harmonics",
    "integrands",
    "peers",
    "stats",
    "wedge",
    "fold",
    "IntegrationResult",
    "hemisphere_pdf",
    "integrate",
    "iter_hemisphere",
    "iter_sphere",
    "orbit",
    "sample_hemisphere",
    "sample_sphere",
    "sphere_pdf",
    "square_to_triangle",
    "triangle_pdf",
    "triangle_to_square",
]
