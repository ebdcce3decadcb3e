"""Keep numba's on-disk cache honest about the modules a kernel inlines.

numba invalidates a cached kernel only when the file that *defines* it changes.
Our kernels inline functions from other files (the maps, the generated orbit
stores, the random-number helpers), so an edit there would leave a stale kernel
in the cache.  :func:`invalidate_if_changed` keeps a digest of those files next
to the cache and removes the kernel module's cache entries when it changes.
"""

from __future__ import annotations

import contextlib
import hashlib
from pathlib import Path

__all__ = ["invalidate_if_changed"]


def invalidate_if_changed(dispatcher, dependencies):
    """Drop the numba cache of *dispatcher*'s module if that module or a dependency changed.

    Call it after the module's kernels are defined and before any is called (numba
    reads its cache at the first call).

    Parameters
    ----------
    dispatcher : numba dispatcher
        One ``cache=True`` kernel of the module; its cache directory is the module's
        (next to the source, or under ``NUMBA_CACHE_DIR`` or numba's user-wide cache).
    dependencies : iterable of str
        Source files whose functions the module's kernels inline.
    """
    module = Path(dispatcher.py_func.__code__.co_filename)
    cache = getattr(dispatcher, "_cache", None)
    cache_path = getattr(cache, "_cache_path", None)  # numba's own choice of directory
    if cache_path is None:
        return
    cache_dir = Path(cache_path)
    digest = hashlib.sha256()
    for path in (module, *map(Path, dependencies)):
        digest.update(path.read_bytes())
    stamp = cache_dir / f"{module.stem}.deps-sha256"
    with contextlib.suppress(OSError):  # a read-only location: numba then caches elsewhere or not at all
        if stamp.is_file() and stamp.read_text() == digest.hexdigest():
            return
        for entry in cache_dir.glob(f"{module.stem}.*.nb[ic]"):
            entry.unlink()
        cache_dir.mkdir(parents=True, exist_ok=True)
        stamp.write_text(digest.hexdigest())
