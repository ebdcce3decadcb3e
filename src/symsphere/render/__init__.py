"""symsphere.render: Monte Carlo and quasi-Monte Carlo solution of the rendering equation.

A path tracer (numba, all cores) with two estimators -- ``integrator="path"``
(next-event estimation and BSDF sampling combined by multiple importance
sampling, the default) and ``integrator="bsdf"`` (BSDF sampling only,
smallpt's) -- whose direction sampling at diffuse vertices is ``strategy`` x
``points`` x ``method`` (the words of the Mitsuba plugin ``symsphere_path``): the
paper's symmetric scheme (``symmetric``: orbits of 24 directions on the hemisphere,
48 on the sphere for Lambertian transmission) with random, Owen-scrambled Sobol' or
interlaced (higher-order) scrambled Sobol' base points, i.i.d. orbit members
(``orbit``) of each map, the classic ``uniform`` and ``cosine``-weighted references,
and ``symmetric_cosine`` (the 8 signed permutations that keep z).  Every integrator
and way of sampling is unbiased and converges to the same image.

>>> from symsphere.render import render, write_outputs
>>> result = render("cornell", width=64, height=48, spp=24, seed=1)   # doctest: +SKIP
>>> write_outputs(result, "cornell.png")                              # doctest: +SKIP

See docs/explanation/renderer.md and docs/reference/renderer.md.
"""

from .image import linear_to_srgb, load_pfm, save_image, save_image_set, save_npy, save_pfm, save_png, tonemap
from .renderer import (
    FILTERS,
    INTEGRATORS,
    SAMPLERS,
    STRATEGIES,
    SYMMETRIC_SAMPLERS,
    RenderPlan,
    RenderResult,
    RenderSettings,
    plan_passes,
    render,
    render_passes,
    write_outputs,
)
from .scene import (
    MATERIAL_KINDS,
    Camera,
    HalfSpace,
    Material,
    Quad,
    Scene,
    SceneError,
    Sphere,
    dielectric,
    diffuse,
    mirror,
    translucent,
)
from .scene_files import load_scene, scene_from_dict
from .scenes import SCENES, cornell, furnace, get_scene, translucent_scene

__all__ = [
    "FILTERS",
    "INTEGRATORS",
    "MATERIAL_KINDS",
    "SAMPLERS",
    "SCENES",
    "STRATEGIES",
    "SYMMETRIC_SAMPLERS",
    "Camera",
    "HalfSpace",
    "Material",
    "Quad",
    "RenderPlan",
    "RenderResult",
    "RenderSettings",
    "Scene",
    "SceneError",
    "Sphere",
    "cornell",
    "dielectric",
    "diffuse",
    "furnace",
    "get_scene",
    "linear_to_srgb",
    "load_pfm",
    "load_scene",
    "mirror",
    "plan_passes",
    "render",
    "render_passes",
    "save_image",
    "save_image_set",
    "save_npy",
    "save_pfm",
    "save_png",
    "scene_from_dict",
    "tonemap",
    "translucent",
    "translucent_scene",
    "write_outputs",
]
