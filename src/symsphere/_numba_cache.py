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
import os
from pathlib import Path

__all__ = ["invalidate_if_changed"]


def invalidate_if_changed(module_file, dependencies):
    """Drop the numba cache of *module_file* if *module_file* or a dependency changed.

    Parameters
    ----------
    module_file : str
        ``__file__`` of the module that defines the cached kernels.
    dependencies : iterable of str
        Source files whose functions those kernels inline.
    """
    module = Path(module_file)
    cache_dir = Path(os.environ["NUMBA_CACHE_DIR"]) if os.environ.get("NUMBA_CACHE_DIR") else module.parent / "__pycache__"
    digest = hashlib.sha256()
    for path in (module, *map(Path, dependencies)):
        digest.update(path.read_bytes())
    stamp = cache_dir / f"{module.stem}.deps-sha256"
    with contextlib.suppress(OSError):  # a read-only install: numba then caches elsewhere or not at all
        if stamp.is_file() and stamp.read_text() == digest.hexdigest():
            return
        for entry in cache_dir.glob(f"{module.stem}.*.nb[ic]"):
            entry.unlink()
        cache_dir.mkdir(parents=True, exist_ok=True)
        stamp.write_text(digest.hexdigest())
