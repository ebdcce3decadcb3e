"""Keep numba's on-disk cache honest about the files a kernel inlines.

numba invalidates a cached kernel only when the file that *defines* it changes.
Our kernels inline functions from other files (the maps, the generated orbit
stores, the random-number helpers) and freeze other modules' tables into the
machine code, so an edit there would leave a stale kernel in the cache.
:func:`invalidate_if_changed` keeps a digest of those files next to the cache and
removes the kernel module's cache entries when it changes.  The files are not
listed by hand: :func:`kernel_dependencies` follows the kernel module's imports
within the package, transitively (a superset of what the kernels inline: an edit
anywhere in it costs one recompilation, never a stale kernel).

Nothing happens at import: the kernels' modules call :func:`invalidate_if_changed`
once, just before their first kernel runs (numba reads the cache at a kernel's
first call).
"""

from __future__ import annotations

import ast
import contextlib
import functools
import hashlib
from collections.abc import Iterable
from pathlib import Path
from typing import Any

__all__ = ["invalidate_if_changed", "kernel_dependencies"]


def _package_root(path: Path) -> Path:
    """The top package directory containing *path* (the highest folder with an ``__init__.py``)."""
    root = path.parent
    while (root.parent / "__init__.py").is_file():
        root = root.parent
    return root


def _imported_files(path: Path, root: Path) -> frozenset[Path]:
    """Files of the package under *root* that the module at *path* imports (relative or absolute)."""
    stat = path.stat()  # the parse is remembered while the file is unchanged (every render re-checks)
    return _parsed_imports(path, root, stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=256)
def _parsed_imports(path: Path, root: Path, mtime_ns: int, size: int) -> frozenset[Path]:
    """:func:`_imported_files` of one version of the file (*mtime_ns*, *size*: the cache key only)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    package = path.parent
    found: set[Path] = set()

    def add(folder: Path, dotted: str) -> None:
        target = folder.joinpath(*dotted.split(".")) if dotted else folder
        for candidate in (target.with_suffix(".py"), target / "__init__.py"):
            if candidate.is_file():
                found.add(candidate.resolve())

    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                folder = package
                for _ in range(node.level - 1):
                    folder = folder.parent
            elif node.module and node.module.split(".")[0] == root.name:
                folder, node_module = root.parent, node.module
                add(folder, node_module)
                for alias in node.names:
                    add(folder, f"{node_module}.{alias.name}")
                continue
            else:
                continue
            if node.module:
                add(folder, node.module)
            for alias in node.names:  # ``from . import maps`` imports a module
                add(folder, f"{node.module}.{alias.name}" if node.module else alias.name)
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == root.name:
                    add(root.parent, alias.name)
    return frozenset(f for f in found if root == f.parent or root in f.parents)


def kernel_dependencies(dispatcher: Any) -> list[Path]:
    """Source files of the package that the module defining *dispatcher* imports, transitively.

    Includes the module's own file.
    """
    function = getattr(dispatcher, "py_func", dispatcher)
    code = getattr(function, "__code__", None)
    if code is None:
        raise TypeError(
            f"'dispatcher' must be a numba dispatcher or a Python function, got {type(dispatcher).__name__}"
        )
    start = Path(code.co_filename).resolve()
    root = _package_root(start)
    files: set[Path] = set()
    pending = [start]
    while pending:
        path = pending.pop()
        if path in files:
            continue
        files.add(path)
        pending.extend(_imported_files(path, root) - files)
    return sorted(files)


def invalidate_if_changed(dispatcher: Any, dependencies: Iterable[str | Path] | None = None) -> None:
    """Drop the numba cache of *dispatcher*'s module if that module or a dependency changed.

    Call it before any cached kernel of the module is called (numba reads its
    cache at the first call).

    Parameters
    ----------
    dispatcher : numba dispatcher
        One ``cache=True`` kernel of the module; its cache directory is the module's
        (next to the source, or under ``NUMBA_CACHE_DIR`` or numba's user-wide cache).
    dependencies : iterable of str or Path, optional
        Source files whose functions the module's kernels inline; default
        :func:`kernel_dependencies` of *dispatcher*.
    """
    module = Path(dispatcher.py_func.__code__.co_filename)
    cache = getattr(dispatcher, "_cache", None)
    cache_path = getattr(cache, "_cache_path", None)  # numba's own choice of directory
    if cache_path is None:
        return
    if dependencies is None:
        dependencies = kernel_dependencies(dispatcher)
    cache_dir = Path(cache_path)
    digest = hashlib.sha256()
    for path in sorted({module.resolve(), *(Path(p).resolve() for p in dependencies)}):
        digest.update(path.read_bytes())
    stamp = cache_dir / f"{module.stem}.deps-sha256"
    with contextlib.suppress(OSError):  # a read-only location: numba then caches elsewhere or not at all
        if stamp.is_file() and stamp.read_text() == digest.hexdigest():
            return
        for entry in cache_dir.glob(f"{module.stem}.*.nb[ic]"):
            entry.unlink()
        cache_dir.mkdir(parents=True, exist_ok=True)
        stamp.write_text(digest.hexdigest())
