"""Two threads in Dr.Jit's pool while Mitsuba 3 reads or writes OpenEXR.

Mitsuba's ``Bitmap`` encodes and decodes ``.exr`` on Dr.Jit's thread pool, and with one thread in it
(a one-CPU machine, ``taskset -c 0``, ``dr.set_thread_count(1)``, ``symsphere render --threads 1``) it
waits forever on OpenEXR's semaphore: writing an ``.exr`` and loading a scene file whose textures or
environment maps are ``.exr`` files (Mitsuba 3.9.1; tests/apps/test_mitsuba_render.py runs both with
one thread).  :func:`exr_threads` gives the pool a second thread for the block and puts its size back
after; a pool of two or more is left alone.  Only the pool's size changes, not what is computed.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

__all__ = ["exr_threads"]

_NEEDED = 2  # threads OpenEXR's codec needs in the pool: it waits on a worker besides the caller


@contextlib.contextmanager
def exr_threads() -> Iterator[None]:
    """Within the block Dr.Jit's pool has at least two threads (Mitsuba's OpenEXR codec needs them)."""
    import drjit as dr  # function-level: only Mitsuba's image and scene input and output get here

    previous = int(dr.thread_count())
    if previous >= _NEEDED:
        yield
        return
    dr.set_thread_count(_NEEDED)
    try:
        yield
    finally:
        dr.set_thread_count(previous)
