"""The Mitsuba 3 scene files shipped with symsphere (src/symsphere/mitsuba/scenes, package data).

Written by scripts/make_mitsuba_scenes.py, which describes each; loadable by plain Mitsuba 3 with
the parameters ``width``, ``height`` and ``spp`` (``mi.load_file(scene_path("veach_mis"), spp=96)``).
"""

from __future__ import annotations

from pathlib import Path

from .._validation import check_choice

__all__ = ["SCENES", "scene_path"]

SCENES = ("cornell_box", "veach_mis", "door_room", "textured", "smallpt_cornell", "gap")
"""tuple of str: the shipped scenes (docs/reference/mitsuba-plugin.md shows them)."""

_FOLDER = Path(__file__).resolve().parent / "scenes"


def scene_path(name: str) -> Path:
    """The XML file of the shipped scene *name* (one of :data:`SCENES`).

    >>> scene_path("cornell_box").name
    'cornell_box.xml'
    """
    return _FOLDER / f"{check_choice(name, 'name', SCENES)}.xml"
