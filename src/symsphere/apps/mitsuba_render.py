"""``symsphere render --scene FILE.xml``: a Mitsuba 3 scene file rendered with ``symsphere_path``.

The scene's own integrator sets ``max_depth``, ``rr_depth`` and ``hide_emitters`` (Mitsuba's ``path``
defaults where it is not a path tracer); the direction sampling at Lambertian vertices comes from
``--sampler`` (:data:`SAMPLER_STRATEGIES`).  Width, height and spp are passed to the file as the
parameters ``width``, ``height``, ``spp`` where it declares them (``<default name="width" .../>``, as the
shipped scenes do), else the file's film and sampler are kept (spp: ``--spp`` always).  The image is
Mitsuba's developed film (linear RGB), written as PNG, PFM and NPY, all or none.
"""

from __future__ import annotations

import re
import time
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["SAMPLER_STRATEGIES", "render_scene_file"]

SAMPLER_STRATEGIES = {
    "bsdf": ("bsdf", "random"),
    "cosine": ("cosine", "random"),
    "symmetric": ("symmetric", "random"),
    "symmetric_sobol": ("symmetric", "sobol"),
    "symmetric_cosine": ("symmetric_cosine", "random"),
    "symmetric_cosine_sobol": ("symmetric_cosine", "sobol"),
}
"""dict: ``--sampler`` -> (strategy, points) of ``symsphere_path`` for a Mitsuba scene file."""

VARIANT = "llvm_ad_rgb"


def _declared_parameters(path: Path) -> set[str]:
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError):
        return set()  # Mitsuba's loader reports the problem
    return {element.get("name", "") for element in root.iter("default")}


def _last_line(error: BaseException) -> str:
    lines = [line.strip() for line in str(error).strip().splitlines() if line.strip()]
    return lines[-1] if lines else type(error).__name__


def render_scene_file(path: str | Path, *, width: int | None, height: int | None, spp: int, sampler: str,
                      method: str | None, seed: int) -> dict[str, Any]:  # fmt: skip
    """Render the Mitsuba scene file *path*; returns the image and what the CLI reports.

    Raises ValueError (one line, naming the file or the option) for a missing Mitsuba, an unknown
    sampler, a file Mitsuba cannot load (with Mitsuba's reason) or an spp the strategy cannot use.
    """
    path = Path(path)
    if sampler not in SAMPLER_STRATEGIES:
        raise ValueError(
            f"--sampler {sampler!r} is not available for Mitsuba scenes; use one of {set(SAMPLER_STRATEGIES)}"
        )
    if not path.is_file():
        raise ValueError(f"--scene: file {str(path)!r} does not exist")
    try:
        import mitsuba as mi
    except ImportError as error:
        raise ValueError(
            f"--scene {str(path)!r}: Mitsuba scene files need Mitsuba 3: pip install 'symsphere[mitsuba]' ({error})"
        ) from None
    if mi.variant() != VARIANT:
        mi.set_variant(VARIANT)
    import symsphere.mitsuba  # noqa: F401  (registers symsphere_path)

    declared = _declared_parameters(path)
    params = {k: v for k, v in (("width", width), ("height", height), ("spp", spp)) if k in declared and v is not None}
    try:
        scene = mi.load_file(str(path), **params)  # type: ignore[arg-type]  # the stub knows only update_scene: bool
    except Exception as error:
        raise ValueError(f"scene file {str(path)!r}: {_last_line(error)}") from None
    own = str(scene.integrator()) if scene.integrator() is not None else ""
    depth = {}
    for key in ("max_depth", "rr_depth"):
        match = re.search(rf"{key}\s*=\s*(-?\d+)", own)
        if match:
            value = int(match.group(1))
            depth[key] = -1 if key == "max_depth" and value >= 2**32 - 1 else value
    if re.search(r"hide_emitters\s*=\s*(1|true)", own):
        depth["hide_emitters"] = True
    strategy, points = SAMPLER_STRATEGIES[sampler]
    options = {"type": "symsphere_path", "strategy": strategy, "points": points, **depth}
    if method is not None:
        options["method"] = method
    try:
        integrator = mi.load_dict(options)
    except Exception as error:
        raise ValueError(_last_line(error).removeprefix("ValueError: ")) from None
    film = scene.sensors()[0].film()
    w, h = (int(c) for c in film.crop_size())
    start = time.perf_counter()
    try:
        image = integrator.render(scene, seed=seed, spp=spp)
        image = np.array(image, dtype=np.float64)
    except ValueError as error:
        raise ValueError(f"--spp: {error}") from None
    seconds = time.perf_counter() - start
    return {"image": image[..., :3], "width": w, "height": h, "spp": spp, "seconds": seconds, "variant": VARIANT,
            "strategy": strategy, "points": points, "integrator": integrator, "paths": w * h * spp}  # fmt: skip
