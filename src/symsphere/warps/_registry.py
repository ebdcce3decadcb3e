"""Every warp of the package as a :class:`Warp` record: :data:`WARPS` and :func:`get_warp`."""

from __future__ import annotations

import numpy.typing as npt

from .._typing import FloatArray, MapMethod
from .._validation import short_repr
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
from ._record import Warp
from ._scheme import (
    hemisphere_to_square,
    sphere_to_square,
    square_to_hemisphere,
    square_to_hemisphere_pdf,
    square_to_sphere,
    square_to_sphere_pdf,
)
from ._spherical_triangle import arvo_triangle_to_square, square_to_arvo_triangle, square_to_arvo_triangle_pdf
from ._triangle import METHODS, TRIANGLE_WARPS
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
    cosine_wedge_density,
    cosine_wedge_point,
    cosine_wedge_to_square,
    square_to_cosine_wedge,
    square_to_cosine_wedge_pdf,
)

__all__ = ["WARPS", "get_warp"]


def _scheme_warps(method: MapMethod) -> list[Warp]:
    """The whole-sphere and hemisphere bijections through the scheme's triangles, by *method*."""

    def sphere(uv: npt.ArrayLike) -> FloatArray:
        return square_to_sphere(uv, method)

    def sphere_pdf(d: npt.ArrayLike) -> FloatArray:
        return square_to_sphere_pdf(d, method)

    def sphere_inverse(d: npt.ArrayLike) -> FloatArray:
        return sphere_to_square(d, method)

    def hemisphere(uv: npt.ArrayLike) -> FloatArray:
        return square_to_hemisphere(uv, method)

    def hemisphere_pdf(d: npt.ArrayLike) -> FloatArray:
        return square_to_hemisphere_pdf(d, method)

    def hemisphere_inverse(d: npt.ArrayLike) -> FloatArray:
        return hemisphere_to_square(d, method)

    uniform = method == "equal_area"
    reference = f"the scheme's triangles as strips of the square, each by {method!r}"
    return [
        Warp(f"sphere_{method}", "sphere", uniform, 1, sphere, sphere_pdf, sphere_inverse, reference=reference),
        Warp(
            f"hemisphere_{method}",
            "hemisphere",
            uniform,
            1,
            hemisphere,
            hemisphere_pdf,
            hemisphere_inverse,
            reference=reference,
        ),
    ]


_ALL = [
    *TRIANGLE_WARPS.values(),
    Warp(
        "arvo_triangle",
        "triangle",
        True,
        48,
        square_to_arvo_triangle,
        square_to_arvo_triangle_pdf,
        arvo_triangle_to_square,
        reference="Arvo, Stratified sampling of spherical triangles, SIGGRAPH 1995",
    ),
    *(warp for method in METHODS for warp in _scheme_warps(method)),
    Warp(
        "cosine_wedge",
        "wedge",
        False,
        8,
        square_to_cosine_wedge,
        square_to_cosine_wedge_pdf,
        cosine_wedge_to_square,
        point=cosine_wedge_point,
        density=cosine_wedge_density,
        reference="Malley's method on the disk sector 0 <= phi <= pi/4",
    ),
    Warp(
        "uniform_sphere",
        "sphere",
        True,
        1,
        square_to_uniform_sphere,
        square_to_uniform_sphere_pdf,
        uniform_sphere_to_square,
        point=uniform_sphere_point,
        reference="Archimedes' hat-box map; pbrt-v4 SampleUniformSphere, Mitsuba 3 square_to_uniform_sphere",
    ),
    Warp(
        "uniform_hemisphere",
        "hemisphere",
        True,
        1,
        square_to_uniform_hemisphere,
        square_to_uniform_hemisphere_pdf,
        uniform_hemisphere_to_square,
        point=uniform_hemisphere_point,
        reference="pbrt-v4 SampleUniformHemisphere",
    ),
    Warp(
        "octahedral_sphere",
        "sphere",
        True,
        1,
        square_to_octahedral_sphere,
        square_to_octahedral_sphere_pdf,
        octahedral_sphere_to_square,
        point=octahedral_sphere_point,
        reference="Clarberg, Fast equal-area mapping of the (hemi)sphere using SIMD, JGT 2008",
    ),
    Warp(
        "octahedral_hemisphere",
        "hemisphere",
        True,
        1,
        square_to_octahedral_hemisphere,
        square_to_octahedral_hemisphere_pdf,
        octahedral_hemisphere_to_square,
        reference="Clarberg, JGT 2008 (hemisphere variant)",
    ),
    Warp(
        "concentric_disk",
        "disk",
        True,
        1,
        square_to_concentric_disk,
        square_to_concentric_disk_pdf,
        concentric_disk_to_square,
        point=concentric_disk_point,
        reference="Shirley & Chiu 1997",
    ),
    Warp(
        "cosine_hemisphere",
        "hemisphere",
        False,
        1,
        square_to_cosine_hemisphere,
        square_to_cosine_hemisphere_pdf,
        cosine_hemisphere_to_square,
        point=cosine_hemisphere_point,
        reference="Shirley & Chiu 1997 (concentric map) + Malley's method; pbrt-v4 SampleCosineHemisphere",
    ),
]
WARPS: dict[str, Warp] = {warp.name: warp for warp in _ALL}
"""dict name -> :class:`Warp`: every map of the unit square in :mod:`symsphere.warps`.

The maps onto T0 are keyed by their ``method=`` name (``'equal_area'``, ``'paper1'``, ``'paper2'``,
:data:`METHODS`), the scheme's bijections by domain and method (``'sphere_equal_area'``, ...,
``'hemisphere_paper2'``).  Arvo's map onto a general spherical triangle takes the vertices as
arguments; ``'arvo_triangle'`` is it on T0."""


def get_warp(name: str) -> Warp:
    """The registered :class:`Warp` called *name*; ValueError naming 'name' otherwise.

    Examples
    --------
    >>> from symsphere.warps import get_warp
    >>> w = get_warp("cosine_wedge")
    >>> w.domain, w.uniform, w.orbit_size
    ('wedge', False, 8)
    """
    if not isinstance(name, str) or name not in WARPS:
        raise ValueError(f"'name' must be one of {sorted(WARPS)}; got {short_repr(name)}")
    return WARPS[name]
