"""Atomic file output for the command line, the renderer and the demo, and direction files.

Files (or a directory) appear under their final names only once they are complete, and the files of
one run appear *as a set* (:func:`atomic_paths`, :func:`atomic_path`, :func:`atomic_directory`;
:func:`remove_stale_temporaries` clears what a killed run left): ``symsphere.io._atomic``.
:func:`save_directions` and :func:`stream_directions` write directions to ``.npy`` or ``.csv``
through them: ``symsphere.io._directions``.  This namespace is the public one.
"""

from __future__ import annotations

from ._atomic import atomic_directory, atomic_path, atomic_paths, remove_stale_temporaries
from ._directions import DIRECTION_SUFFIXES, check_suffix, save_directions, stream_directions

__all__ = [
    "DIRECTION_SUFFIXES",
    "atomic_path",
    "atomic_paths",
    "atomic_directory",
    "check_suffix",
    "remove_stale_temporaries",
    "save_directions",
    "stream_directions",
]
