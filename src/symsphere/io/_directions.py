"""Direction files: an (n, 3) array of unit vectors written to ``.npy`` or ``.csv``, atomically
(:mod:`symsphere.io._atomic`), whole or produced block by block.

Large outputs are written with ordinary writes (no memory map), their space reserved first where the
file system allows (``os.posix_fallocate``), so a full disk is an ``OSError`` (``ENOSPC``) at the
start, never a ``SIGBUS`` part-way, and memory stays at one block.
"""

from __future__ import annotations

import errno
import os
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any

import numba
import numpy as np
import numpy.typing as npt

from .._threads import route_compiles
from .._typing import FloatArray
from .._validation import (
    UNIT_TOLERANCE,
    check_callable,
    check_count,
    check_dtype,
    check_file_suffix,
    check_unit_directions,
    short_repr,
    unit_bounds,
)
from ._atomic import atomic_path

__all__ = ["DIRECTION_SUFFIXES", "check_suffix", "save_directions", "stream_directions"]

DIRECTION_SUFFIXES = (".npy", ".csv")
"""tuple of str: the file suffixes (lower case; matched case-insensitively) :func:`save_directions` writes."""

_CSV_FORMATS = {np.dtype(np.float64): "%.17g", np.dtype(np.float32): "%.9g"}  # shortest exact round trip


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
        If the suffix is neither ``.npy`` nor ``.csv``, or *directions* is not an (n, 3)
        array, n >= 1, of unit vectors (norm 1 within 10**-3; no NaN, inf or zero rows).
    OSError
        If *path* (through symbolic links) is a directory, a device, a FIFO or a socket:
        only regular files are replaced (see :func:`atomic_paths`).
    TypeError
        If *path* is not a file name or *directions* not an array of real numbers.

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
    check_suffix(path, name)
    directions = check_unit_directions(directions, "directions")  # a zero or non-unit row is no direction
    if directions.dtype not in (np.float32, np.float64):  # float16 and other floats: written as float64
        directions = directions.astype(np.float64)
    if directions.ndim != 2 or len(directions) == 0:
        raise ValueError(f"'directions' must have shape (n, 3) with n >= 1; got {directions.shape}")
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
    if not isinstance(name, str):
        raise TypeError(f"'name' must be a str; got {type(name).__name__} {short_repr(name)}")
    return check_file_suffix(path, DIRECTION_SUFFIXES, name)


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
        ``blocks(None)`` returns an iterable of consecutive (m, 3) blocks (the argument
        is the ``out=`` of :func:`symsphere.iter_sphere`: None, so that each block is a
        fresh array and memory stays at one block).
    name : str, optional
        How error messages call *path*.
    progress : callable, optional
        Called with the length of each block once it is written.

    Raises
    ------
    OSError
        If the file cannot be written; for ``.npy`` a full disk is found before any
        block is computed (the file's space is reserved first where the file system
        supports it), else at the write that fails.  No file is left behind.
    ValueError, TypeError
        For a bad argument (named), or if *blocks* gives other than (m, 3) arrays
        of *n* directions in all (then, too, no file is left behind).

    Notes
    -----
    The file appears only when complete: an interrupted or failed run leaves
    no file under *path* (see :func:`atomic_path`).  The blocks are written with
    ordinary writes, and the pages written are dropped from the page cache as
    they reach the disk, so resident memory stays at about one block for any *n*.

    Examples
    --------
    With :func:`symsphere.iter_sphere` (memory stays at one block, for any *n*):

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
    n = check_count(n, "n")
    dtype = check_dtype(dtype)
    check_callable(blocks, "blocks")
    check_callable(progress, "progress", optional=True)
    written = 0
    with atomic_path(Path(path)) as temporary:
        if suffix == ".npy":
            file_dtype = dtype.newbyteorder("<")
            with open(temporary, "wb") as handle:
                header = {"descr": np.lib.format.dtype_to_descr(file_dtype), "fortran_order": False, "shape": (n, 3)}
                np.lib.format.write_array_header_1_0(handle, header)
                handle.flush()
                _reserve(handle.fileno(), handle.tell() + n * 3 * file_dtype.itemsize)
                pages = _PageDropper(handle.fileno())
                for block in _iterate(blocks):
                    data = _checked_block(block, file_dtype, n - written)
                    handle.write(data.data.cast("B"))
                    written += len(data)
                    pages.written(handle)
                    if progress is not None:
                        progress(len(data))
        else:
            fmt = _CSV_FORMATS.get(dtype, "%.17g")
            with open(temporary, "w", encoding="ascii", newline="\n") as handle:
                handle.write("x,y,z\n")
                for block in _iterate(blocks):
                    block = _checked_block(block, dtype, n - written)
                    np.savetxt(handle, block, fmt=fmt, delimiter=",")
                    written += len(block)
                    if progress is not None:
                        progress(len(block))
        if written != n:
            raise ValueError(f"'blocks' must give n={n} directions in all; got {written}")


def _iterate(blocks: Callable[[FloatArray | None], Iterable[FloatArray]]) -> Iterator[Any]:
    produced = blocks(None)
    if not hasattr(produced, "__iter__"):
        raise TypeError(f"'blocks' must return an iterable of (m, 3) arrays; got {type(produced).__name__}")
    yield from produced


def _checked_block(block: Any, dtype: np.dtype[Any], room: int) -> Any:
    """One block as a C-contiguous (m, 3) array of *dtype*; ValueError/TypeError naming 'blocks'."""
    try:
        data = np.asarray(block)
    except (TypeError, ValueError):
        data = np.asarray(None)
    if data.dtype.kind not in "biuf":
        raise TypeError(f"'blocks' must give arrays of real numbers of shape (m, 3); got {short_repr(block)}")
    data = np.ascontiguousarray(data, dtype=dtype)
    if data.ndim != 2 or data.shape[1] != 3 or len(data) > room:
        raise ValueError(
            f"'blocks' must give (m, 3) arrays of n directions in all; got one of shape {data.shape}"
            f" with {room} directions left"
        )
    bad = _first_non_unit_row(data, *unit_bounds(UNIT_TOLERANCE)) if len(data) else -1
    if bad >= 0:
        raise ValueError(
            f"'blocks' must give unit vectors (no NaN, inf, zero or non-unit rows); got {data[bad].tolist()}"
        )
    return data


@numba.njit(cache=True)
def _first_non_unit_row(data: Any, lo: float, hi: float) -> int:  # pragma: no cover - compiled
    """The first row whose squared norm is not within [lo, hi] (NaN and inf never are), or -1: the test of
    :func:`symsphere._validation.off_unit`, compiled.

    One pass in float64, a few ms for a chunk of 3 * 2**20 rows (numpy's einsum took 0.1 s: longer than
    computing the directions).
    """
    for i in range(data.shape[0]):
        x, y, z = float(data[i, 0]), float(data[i, 1]), float(data[i, 2])
        if not lo <= x * x + y * y + z * z <= hi:
            return i
    return -1


def _reserve(descriptor: int, size: int) -> None:
    """Allocate *size* bytes of the file now, so that a full disk fails here (ENOSPC), not part-way."""
    if not hasattr(os, "posix_fallocate"):
        return
    try:
        os.posix_fallocate(descriptor, 0, size)
    except OSError as exc:
        if exc.errno in (errno.EINVAL, errno.EOPNOTSUPP, errno.ENOSYS):  # not supported here: write as we go
            return
        raise


class _PageDropper:
    """Every STRIDE bytes written: flush them to disk and drop them from the page cache.

    Written pages stay in the page cache, dirty, until the kernel writes them back; a
    cgroup's memory limit counts them.  Writing back and dropping as we go keeps the
    memory of a long run flat (and costs no extra disk writes: the final fsync would
    write them anyway).
    """

    STRIDE = 256 * 2**20

    def __init__(self, descriptor: int) -> None:
        self.descriptor = descriptor
        self.dropped = 0

    def written(self, handle: Any) -> None:
        position = handle.tell()
        if position - self.dropped < self.STRIDE or not hasattr(os, "posix_fadvise"):
            return
        handle.flush()
        os.fdatasync(self.descriptor)
        os.posix_fadvise(self.descriptor, self.dropped, position - self.dropped, os.POSIX_FADV_DONTNEED)
        self.dropped = position


route_compiles(globals())  # the first compile of each numba function here: interruptible (_threads)
