"""The registry of warps: :data:`WARPS`, filled by each warp's module with :func:`register`, and :func:`get_warp`.

A warp's module states its :class:`Warp` records beside the functions they describe and ends with
``register(Warp(name=..., ...), ...)``; importing the module (one line in ``warps/__init__.py``) puts them
into :data:`WARPS`, in the order of the imports there.
"""

from __future__ import annotations

import sys

from .._validation import short_repr
from ._record import Warp

__all__ = ["WARPS", "get_warp", "register", "namespace"]

WARPS: dict[str, Warp] = {}
"""dict name -> :class:`Warp`: every map of the unit square in :mod:`symsphere.warps`.

The maps onto T0 are keyed by their ``method=`` name (``'equal_area'``, ``'paper1'``, ``'paper2'``,
:data:`METHODS`), the scheme's bijections by domain and method (``'sphere_equal_area'``, ...,
``'hemisphere_paper2'``).  Arvo's map onto a general spherical triangle takes the vertices as
arguments; ``'arvo_triangle'`` is it on T0."""

# The modules of the package that hold no warp: their names are for the package only.
_SHARED = ("_common", "_record", "_registry")


def register(*warps: Warp) -> None:
    """Add *warps* to :data:`WARPS` (each name once: a second record of a name is an error)."""
    for warp in warps:
        if warp.name in WARPS:
            raise ValueError(f"a warp called {warp.name!r} is registered already")
        WARPS[warp.name] = warp


def namespace(package: str) -> list[str]:
    """Every name in the ``__all__`` of *package*'s warp modules (not the shared ones), in the order of their imports."""
    names: list[str] = []
    for name, module in list(sys.modules.items()):
        parent, _, leaf = name.rpartition(".")
        if parent == package and leaf not in _SHARED:
            names += getattr(module, "__all__", [])
    return names


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
