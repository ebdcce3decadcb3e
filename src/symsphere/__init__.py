"""Exactly uniform, symmetric Monte Carlo and quasi-Monte Carlo sampling of directions.

The sphere is cut into 48 congruent orthogonal spherical triangles (the
hemisphere into 24) by the coordinate and bisector planes (Dimov, Penzov &
Stoilova, *Parallel Monte Carlo Sampling Scheme for Sphere and Hemisphere*).
One point of the fundamental triangle T0 = {z >= x >= y >= 0} gives 48 (24)
directions by signed coordinate permutations.  The paper's two maps from the
unit square onto T0 are shipped as printed, with their exact (non-uniform)
densities; the default map, ``'equal_area'``, is exactly uniform.

The names below are the package's everyday interface; each is documented in
its module (:mod:`symsphere.sampling`, :mod:`symsphere.integration`,
:mod:`symsphere.warps`, :mod:`symsphere.symmetry`, :mod:`symsphere.points`).
:mod:`symsphere.stats`, :mod:`symsphere.peers`, :mod:`symsphere.integrands`,
:mod:`symsphere.render` and the other library submodules of
``dir(symsphere)`` are imported on first use (``ss.render.render(...)`` works
without an import of its own); ``import symsphere`` itself stays cheap and
changes nothing in the process.

Examples
--------
>>> import numpy as np
>>> import symsphere as ss
>>> d = ss.sample_sphere(48 * 1000, rng=1)       # rows 48 i ... 48 i + 47: the orbit of one point
>>> d.shape
(48000, 3)
>>> k, base = ss.fold(d[13])                     # which triangle, and the preimage in T0
>>> bool(np.allclose(ss.orbit(base)[k], d[13]))
True
>>> p = ss.sample_sphere(48 * 10_000, method="paper1", rng=3)   # the paper's map: not uniform,
>>> f = lambda w: np.exp(w[:, 0])                               # but unbiased weighted by 1/pdf
>>> bool(abs(np.mean(f(p) / ss.sphere_pdf(p, "paper1")) - 2 * np.pi * (np.e - 1 / np.e)) < 0.1)
True
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .integration import IntegrationResult, integrate
from .points import POINT_SETS
from .sampling import Scheme, hemisphere_pdf, iter_hemisphere, iter_sphere, sample_hemisphere, sample_sphere, sphere_pdf
from .symmetry import HEMISPHERE_MAPS, SPHERE_MAPS, fold, orbit
from .warps import (
    METHODS,
    hemisphere_to_square,
    sphere_to_square,
    square_to_hemisphere,
    square_to_hemisphere_pdf,
    square_to_sphere,
    square_to_sphere_pdf,
    square_to_triangle,
    square_to_triangle_pdf,
    triangle_to_square,
)

__version__ = "0.2.0.dev0"

_SUBMODULES = (
    "bins", "distributed", "frames", "harmonics", "integrands", "io", "peers", "quality", "render",
    "stats",
)  # fmt: skip


if TYPE_CHECKING:
    from types import ModuleType


def __getattr__(name: str) -> ModuleType:
    # Submodules that need scipy.stats, scipy.integrate or dask are imported on first use
    # (PEP 562), so that ``import symsphere`` and a first sample stay fast.
    if name in _SUBMODULES:
        import importlib

        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    # The lazy submodules too, so that tab completion finds them before their first use.
    return sorted(set(globals()) | set(_SUBMODULES))


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
    "warps",
    "fold",
    "IntegrationResult",
    "Scheme",
    "hemisphere_pdf",
    "hemisphere_to_square",
    "integrate",
    "iter_hemisphere",
    "iter_sphere",
    "orbit",
    "sample_hemisphere",
    "sample_sphere",
    "sphere_pdf",
    "sphere_to_square",
    "square_to_hemisphere",
    "square_to_hemisphere_pdf",
    "square_to_sphere",
    "square_to_sphere_pdf",
    "square_to_triangle",
    "square_to_triangle_pdf",
    "triangle_to_square",
]
