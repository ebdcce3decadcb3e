"""Atomic file output for the command line and the demo.

A file (or directory) appears under its final name only once it is complete:
it is written under a hidden temporary name in the same directory and then
renamed over the target (``os.replace``, atomic on POSIX and Windows within
one file system).  On any exception, ``KeyboardInterrupt`` included, the
temporary is removed and the target is left as it was.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import shutil
from collections.abc import Callable, Collection, Iterable, Iterator
from pathlib import Path

import numpy as np
import numpy.typing as npt

from ._typing import FloatArray

__all__ = [
    "DIRECTION_SUFFIXES",
    "atomic_path",
    "atomic_directory",
    "check_suffix",
    "save_directions",
    "stream_directions",
]

DIRECTION_SUFFIXES = (".npy", ".csv")
"""tuple of str: the file suffixes (lower case; matched case-insensitively) :func:`save_directions` writes."""

_CSV_FORMATS = {np.dtype(np.float64): "%.17g", np.dtype(np.float32): "%.9g"}  # shortest exact round trip


def _temporary_name(target: Path, kind: str) -> Path:
    # Hidden, in the target's directory (so the rename stays on one file system),
    # and recognisable if a hard crash (SIGKILL, power loss) ever leaves one behind.
    return target.with_name(f".{target.name}.{secrets.token_hex(4)}.{kind}")


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a fresh temporary file path that replaces *path* on success.

    Parameters
    ----------
    path : str or os.PathLike
        The final file.  Its directory must exist.

    Yields
    ------
    pathlib.Path
        An empty file, created in the directory of *path* with the
        permissions a new file would get (``0o666`` minus the umask).  Write
        to it (by name, or open it again); do not rename it.

    Notes
    -----
    On normal exit the temporary is flushed to disk (``fsync``) and renamed
    over *path*.  On any exception (``KeyboardInterrupt`` too) it is removed
    and the exception propagates; *path* is untouched.

    Examples
    --------
    >>> import os, tempfile
    >>> from symsphere.io import atomic_path
    >>> target = os.path.join(tempfile.mkdtemp(), "out.txt")
    >>> with atomic_path(target) as tmp:
    ...     _ = tmp.write_text("done")
    >>> open(target).read()
    'done'
    """
    target = Path(path)
    while True:
        temporary = _temporary_name(target, "tmp")
        try:
            # O_EXCL: never clobber an existing file; mode 0o666 lets the umask decide, unlike mkstemp's 0o600.
            descriptor = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        except FileExistsError:
            continue
        os.close(descriptor)
        break
    try:
        yield temporary
        with open(temporary, "rb+") as handle:
            os.fsync(handle.fileno())  # the data is on disk before the name points at it
        os.replace(temporary, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temporary)
        raise


@contextlib.contextmanager
def atomic_directory(
    path: str | os.PathLike[str], *, replaceable: Collection[str] | None = None
) -> Iterator[Path]:
    """Yield a fresh temporary directory that replaces the directory *path* on success.

    Parameters
    ----------
    path : str or os.PathLike
        The final directory.  Its parent must exist.
    replaceable : collection of str, optional
        If *path* already exists it is replaced only if it is a directory
        holding nothing but entries with these names (an earlier run's
        output); anything else raises ``FileExistsError`` before any work is
        done, so that a mistyped ``--out`` cannot delete a user's files.
        ``None`` allows only an empty directory.

    Yields
    ------
    pathlib.Path
        An empty directory next to *path*.

    Notes
    -----
    A directory cannot be renamed over a non-empty one, so an existing
    *path* is first renamed aside, the new one renamed in, and the old one
    deleted.  Readers see either the old or the new directory, except in the
    instant between the two renames, when *path* does not exist.

    Examples
    --------
    >>> import os, tempfile
    >>> from symsphere.io import atomic_directory
    >>> out = os.path.join(tempfile.mkdtemp(), "report")
    >>> with atomic_directory(out) as tmp:
    ...     _ = (tmp / "report.md").write_text("# results")
    >>> os.listdir(out)
    ['report.md']

    A second run replaces the folder only if it holds nothing but files a run writes:

    >>> with atomic_directory(out, replaceable={"report.md"}) as tmp:
    ...     _ = (tmp / "report.md").write_text("# new results")
    >>> open(os.path.join(out, "report.md")).read()
    '# new results'
    >>> with atomic_directory(out) as tmp:
    ...     pass
    Traceback (most recent call last):
        ...
    FileExistsError: ... holds files this program did not write (report.md); refusing to replace it: ...
    """
    target = Path(path)
    allowed = set(replaceable or ())
    _check_replaceable(target, allowed)
    temporary = _temporary_name(target, "tmp")
    temporary.mkdir()
    try:
        yield temporary
        _check_replaceable(target, allowed)  # it may have appeared or changed meanwhile
        if target.exists():
            aside = _temporary_name(target, "old")
            os.replace(target, aside)
            os.replace(temporary, target)
            shutil.rmtree(aside, ignore_errors=True)
        else:
            os.replace(temporary, target)
    except BaseException:
        shutil.rmtree(temporary, ignore_errors=True)
        raise


def _check_replaceable(target: Path, allowed: set[str]) -> None:
    if not (target.exists() or target.is_symlink()):
        return
    if target.is_symlink() or not target.is_dir():
        raise FileExistsError(f"{str(target)!r} exists and is not a directory; choose another output directory")
    unexpected = sorted(entry.name for entry in target.iterdir() if entry.name not in allowed)
    if unexpected:
        shown = ", ".join(unexpected[:3]) + (", ..." if len(unexpected) > 3 else "")
        raise FileExistsError(
            f"{str(target)!r} exists and holds files this program did not write ({shown}); "
            "refusing to replace it: choose a new or empty output directory"
        )


def save_directions(path: str | os.PathLike[str], directions: npt.ArrayLike, *, name: str = "path") -> None:
    """Write an (n, 3) array of directions to ``.npy`` or ``.csv``, atomically.

    Parameters
    ----------
    path : str or os.PathLike
        Output file; the suffix (case-insensitive) chooses the format:
        ``.npy`` (``numpy.save`` format) or ``.csv`` (header ``x,y,z``, then one
        direction per line, with 17 significant digits for float64 and 9 for
        float32, which read back exactly).
    directions : ndarray, shape (n, 3)
    name : str, optional
        How error messages call *path* (the command line passes ``'--out'``).

    Raises
    ------
    ValueError
        If the suffix is neither ``.npy`` nor ``.csv``, or *directions* is not (n, 3).

    Examples
    --------
    >>> import os, tempfile
    >>> import numpy as np
    >>> from symsphere.io import save_directions
    >>> target = os.path.join(tempfile.mkdtemp(), "d.csv")
    >>> save_directions(target, np.array([[0.0, 0.6, 0.8]]))
    >>> print(open(target).read(), end="")
    x,y,z
    0,0.59999999999999998,0.80000000000000004
    """
    directions = np.asarray(directions)
    if directions.ndim != 2 or directions.shape[1] != 3:
        raise ValueError(f"directions must have shape (n, 3), got {directions.shape}")
    stream_directions(path, len(directions), directions.dtype, lambda out: [directions], name=name)


def check_suffix(path: str | os.PathLike[str], name: str = "path") -> str:
    """The lower-case suffix of *path*, if it is one of DIRECTION_SUFFIXES.

    Parameters
    ----------
    path : str or os.PathLike
        A file name for :func:`save_directions` or :func:`stream_directions`.
    name : str, optional
        How the error message calls *path* (the command line passes ``'--out'``).

    Returns
    -------
    str
        ``'.npy'`` or ``'.csv'`` (see :data:`DIRECTION_SUFFIXES`).

    Raises
    ------
    ValueError
        If the suffix is not one of :data:`DIRECTION_SUFFIXES`.

    Examples
    --------
    >>> from symsphere.io import check_suffix
    >>> check_suffix("directions.NPY")
    '.npy'
    >>> check_suffix("directions.txt", "--out")
    Traceback (most recent call last):
        ...
    ValueError: '--out' must end in one of .npy, .csv, got 'directions.txt'
    """
    suffix = Path(path).suffix.lower()
    if suffix not in DIRECTION_SUFFIXES:
        allowed = ", ".join(DIRECTION_SUFFIXES)
        raise ValueError(f"'{name}' must end in one of {allowed}, got {str(path)!r}")
    return suffix


def stream_directions(
    path: str | os.PathLike[str],
    n: int,
    dtype: npt.DTypeLike,
    blocks: Callable[[FloatArray | None], Iterable[FloatArray]],
    *,
    name: str = "path",
    progress: Callable[[int], object] | None = None,
) -> None:
    """Write *n* directions, produced block by block, to ``.npy`` or ``.csv``, atomically.

    Parameters
    ----------
    path : str or os.PathLike
        Output file, ``.npy`` or ``.csv`` (see :func:`save_directions`).
    n : int
        Number of directions in all.
    dtype : float32 or float64
    blocks : callable
        ``blocks(out)`` returns an iterable of consecutive (m, 3) blocks.  For
        ``.npy``, *out* is an (n, 3) memory map of the file's data and the blocks
        may be views of it (written in place, so memory stays at one block);
        for ``.csv``, *out* is None.
    name : str, optional
        How error messages call *path*.
    progress : callable, optional
        Called with the length of each block once it is written.

    Notes
    -----
    The file appears only when complete: an interrupted or failed run leaves
    no file under *path* (see :func:`atomic_path`).

    Examples
    --------
    With :func:`symsphere.iter_sphere`, which fills *out* in place when given one
    (memory stays at one block, for any *n*):

    >>> import os, tempfile
    >>> import numpy as np
    >>> import symsphere
    >>> from symsphere.io import stream_directions
    >>> path = os.path.join(tempfile.mkdtemp(), "d.npy")
    >>> n = 48 * 1000
    >>> blocks = lambda out: symsphere.iter_sphere(n, chunk=48 * 256, rng=1, out=out)
    >>> stream_directions(path, n, np.float64, blocks)
    >>> bool(np.array_equal(np.load(path), symsphere.sample_sphere(n, rng=1)))
    True
    """
    suffix = check_suffix(path, name)
    dtype = np.dtype(dtype)
    written = 0
    with atomic_path(Path(path)) as temporary:
        if suffix == ".npy":
            data = np.lib.format.open_memmap(temporary, mode="w+", dtype=dtype, shape=(n, 3))
            for block in blocks(data):
                if not np.shares_memory(block, data):
                    data[written : written + len(block)] = block
                written += len(block)
                if progress is not None:
                    progress(len(block))
            data.flush()
            del data
        else:
            fmt = _CSV_FORMATS.get(dtype, "%.17g")
            with open(temporary, "w", encoding="ascii", newline="\n") as handle:
                handle.write("x,y,z\n")
                for block in blocks(None):
                    np.savetxt(handle, block, fmt=fmt, delimiter=",")
                    written += len(block)
                    if progress is not None:
                        progress(len(block))
        if written != n:
            raise RuntimeError(f"expected {n} directions, got {written}")
