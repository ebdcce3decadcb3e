"""The BSDFs of a Mitsuba scene as :mod:`symsphere.mitsuba._integrator` classifies them: Lambertian (the
strategies replace their samples), diffuse only (light sampling alone for the light table's emitters)."""

from __future__ import annotations

import re
from typing import Any

import drjit as dr
import mitsuba as mi

__all__ = ["all_diffuse", "all_lambertian", "bsdf_ids", "diffuse_only", "lambertian_codes"]


def bsdf_ids(bsdfs: Any) -> Any:
    """The Dr.Jit registry ids (UInt32) of a ``BSDFPtr`` array: the keys of the Lambertian table."""
    return dr.reinterpret_array(mi.UInt32, bsdfs)


_BRDF_LINE = re.compile(r"^  brdf\[(\d)\] = (\w+)\[", re.MULTILINE)


def lambertian_codes(bsdf: Any) -> int:
    """1 for Mitsuba's ``diffuse``, 2 for a ``twosided`` whose both sides are ``diffuse``, else 0."""
    name = bsdf.class_name()
    if name == "SmoothDiffuse":
        return 1
    if name == "TwoSidedBRDF":
        nested = dict(_BRDF_LINE.findall(str(bsdf)))
        if nested.get("0") == "SmoothDiffuse" and nested.get("1") == "SmoothDiffuse":
            return 2
    return 0


def diffuse_only(flags: Any) -> Any:
    """The lanes whose BSDF is diffuse only (no glossy or delta component): light sampling alone there."""
    return (
        mi.has_flag(flags, mi.BSDFFlags.Diffuse)
        & ~mi.has_flag(flags, mi.BSDFFlags.Glossy)
        & ~mi.has_flag(flags, mi.BSDFFlags.Delta)
    )


def all_diffuse(scene: Any) -> bool:
    """Whether every BSDF of *scene* is diffuse only (a trace-time constant)."""
    for shape in scene.shapes():
        bsdf = shape.bsdf()
        if bsdf is None:
            continue
        flags = int(bsdf.flags())
        if not flags & int(mi.BSDFFlags.Diffuse) or flags & int(mi.BSDFFlags.Glossy | mi.BSDFFlags.Delta):
            return False
    return True


def all_lambertian(scene: Any) -> bool:
    """Whether every BSDF of *scene* is Lambertian (:func:`lambertian_codes`; a trace-time constant)."""
    return all(shape.bsdf() is None or lambertian_codes(shape.bsdf()) for shape in scene.shapes())
