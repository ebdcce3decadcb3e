"""Files: names and suffixes, what an atomic write may replace, reading only regular files.

Part of :mod:`symsphere._validation` (import the validators from there).
"""

from __future__ import annotations

import errno
import os
import secrets
import stat
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import cast

from .._signals import deferred as signals_deferred
from .values import short_repr

__all__ = [
    "TEMPORARY_KINDS",
    "check_file_names",
    "check_file_suffix",
    "check_output_path",
    "check_path",
    "check_paths",
    "file_kind",
    "read_regular_file",
]


def check_path(path: object, name: str = "path") -> Path:
    """*path* (a str or os.PathLike naming a file) as a Path; TypeError or ValueError naming *name*.

    Bytes, integers (which ``open`` would take as a file descriptor: 0 is standard input) and other
    types are TypeErrors; an empty name or one with a NUL character is a ValueError.

    Examples
    --------
    >>> from symsphere._validation import check_path
    >>> check_path("out.npy")
    PosixPath('out.npy')
    >>> check_path(0)
    Traceback (most recent call last):
        ...
    TypeError: 'path' must be a str or os.PathLike file name; got int 0
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(
            f"'{name}' must be a str or os.PathLike file name; got {type(path).__name__} {short_repr(path)}"
        )
    text = os.fspath(path)
    if not isinstance(text, str):
        raise TypeError(
            f"'{name}' must be a str or os.PathLike file name; got {type(text).__name__} {short_repr(text)}"
        )
    if not text or "\0" in text:
        raise ValueError(f"'{name}' must be a non-empty file name without NUL characters; got {short_repr(text)}")
    return Path(text)


def check_file_suffix(path: object, allowed: Sequence[str], name: str = "path") -> str:
    """The lower-case suffix of the file name *path* (see :func:`check_path`) if it is one of *allowed*
    (lower case; matched case-insensitively), else ValueError naming *name* and what is allowed.

    Examples
    --------
    >>> from symsphere._validation import check_file_suffix
    >>> check_file_suffix("x.NPY", (".npy", ".csv"))
    '.npy'
    >>> check_file_suffix("x.jpg", (".png",), "out")
    Traceback (most recent call last):
        ...
    ValueError: 'out' must end in .png, got 'x.jpg'
    """
    suffix = check_path(path, name).suffix.lower()
    if suffix not in allowed:
        shown = allowed[0] if len(allowed) == 1 else "one of " + ", ".join(allowed)
        raise ValueError(f"'{name}' must end in {shown}, got {str(path)!r}")
    return suffix


# ---------------------------------------------------------------------------
# Output files: what may be written, checked before any work
# ---------------------------------------------------------------------------

TEMPORARY_KINDS = ("tmp", "old", "probe")
"""The last suffix of the hidden files an atomic write makes beside its target, ``.NAME.<pid>-<8 hex>.KIND``:
the temporary (``tmp``), the previous version kept during the renames of a set (``old``) and the
file that :func:`check_output_path` creates and removes at once (``probe``)."""

_KINDS = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISSOCK, "a socket"),
)


def file_kind(mode: int) -> str:
    """What a file of the ``st_mode`` *mode* is, in words: ``'a regular file'``, ``'a FIFO (named pipe)'``, ...

    Examples
    --------
    >>> import stat
    >>> from symsphere._validation import file_kind
    >>> file_kind(stat.S_IFCHR | 0o666)
    'a character device'
    """
    if stat.S_ISREG(mode):
        return "a regular file"
    for test, words in _KINDS:
        if test(mode):
            return words
    return "not a regular file"


def check_output_path(path: object, name: str = "path", *, probe: bool = True) -> Path:
    """*path* as a Path that an atomic write may replace, checked before any work is done.

    The target, followed through symbolic links, must be absent or a regular file (a device, a
    FIFO, a socket or a directory is never replaced, nor written into), and its directory must
    exist; with *probe*, a hidden file ``.NAME.<hex>.probe`` is created in it and removed at once,
    so that a directory that takes no new files (read-only, ``/proc``, no permission) fails now,
    not after minutes of work.  Errors name *path* as the user gave it: TypeError or ValueError
    for a bad name (see :func:`check_path`), else an ``OSError`` whose ``filename`` is *path*.

    Examples
    --------
    >>> from symsphere._validation import check_output_path
    >>> check_output_path("/dev/null")
    Traceback (most recent call last):
        ...
    OSError: [Errno 22] is a character device, not a regular file: only regular files are replaced: '/dev/null'
    """
    given = check_path(path, name)
    target = Path(os.path.realpath(given))  # through symbolic links, as the writer goes
    try:
        mode = os.stat(target).st_mode
    except (FileNotFoundError, NotADirectoryError):  # absent, or a "directory" that is a file: below
        mode = None
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror, str(given)) from None
    if mode is not None and stat.S_ISDIR(mode):
        raise IsADirectoryError(errno.EISDIR, "is a directory, not a file", str(given))
    if mode is not None and not stat.S_ISREG(mode):
        shown = f" ({target})" if str(target) != os.path.abspath(given) else ""  # reached through a link
        raise OSError(
            errno.EINVAL,
            f"is {file_kind(mode)}{shown}, not a regular file: only regular files are replaced",
            str(given),
        )
    folder = target.parent
    if not folder.exists():
        raise FileNotFoundError(errno.ENOENT, f"its directory {str(given.parent)!r} does not exist", str(given))
    if not folder.is_dir():
        raise NotADirectoryError(errno.ENOTDIR, f"{str(given.parent)!r} is not a directory", str(given))
    if probe:
        trial = folder / f".{target.name}.{secrets.token_hex(4)}.probe"
        with signals_deferred():  # a Ctrl-C between creating and removing it would leave the probe behind
            try:
                os.close(os.open(trial, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
            except OSError as exc:
                raise OSError(
                    exc.errno, f"cannot create a file in {str(folder)!r} ({exc.strerror})", str(given)
                ) from None
            os.unlink(trial)
    return given


def read_regular_file(path: Path, where: str, limit: int | None = None) -> bytes:
    """The bytes of the regular file *path* (at most *limit* + 1 of them), refusing anything else first.

    A FIFO would block the reader until a writer comes (forever, for a scene file), and ``/dev/zero`` or
    ``/dev/urandom`` never end: what *path* is (through symbolic links) is checked before it is opened,
    and again on the opened descriptor (opened without blocking), so that nothing is read from such a
    file.  *where* starts the messages (``"scene file 'x.json'"``).  FileNotFoundError if it does not
    exist, ValueError naming what it is otherwise.

    Examples
    --------
    >>> from pathlib import Path
    >>> from symsphere._validation import read_regular_file
    >>> read_regular_file(Path("/dev/zero"), "scene file '/dev/zero'")
    Traceback (most recent call last):
        ...
    ValueError: scene file '/dev/zero': is a character device, not a regular file
    """
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise FileNotFoundError(errno.ENOENT, os.strerror(errno.ENOENT), str(path)) from None
    if not stat.S_ISREG(mode):
        raise ValueError(f"{where}: is {file_kind(mode)}, not a regular file")
    descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK)  # swapped for a FIFO meanwhile: no wait
    with os.fdopen(descriptor, "rb") as handle:
        mode = os.fstat(descriptor).st_mode
        if not stat.S_ISREG(mode):
            raise ValueError(f"{where}: is {file_kind(mode)}, not a regular file")
        return handle.read() if limit is None else handle.read(limit + 1)


def check_paths(paths: object, name: str = "paths") -> list[Path]:
    """*paths* (an iterable of file names, not one name) as a list of Paths (see :func:`check_path`).

    Examples
    --------
    >>> from symsphere._validation import check_paths
    >>> check_paths(("a.png", "b.npy"))
    [PosixPath('a.png'), PosixPath('b.npy')]
    >>> check_paths("a.png")
    Traceback (most recent call last):
        ...
    TypeError: 'paths' must be an iterable of file names; got str 'a.png'
    """
    if isinstance(paths, (str, bytes, os.PathLike)) or not hasattr(paths, "__iter__"):
        raise TypeError(f"'{name}' must be an iterable of file names; got {type(paths).__name__} {short_repr(paths)}")
    return [check_path(path, name) for path in cast("Iterable[object]", paths)]


def check_file_names(names: object, name: str) -> set[str]:
    """*names* (None or a collection of str: names of files in a directory) as a set; TypeError naming *name*."""
    if names is None:
        return set()
    entries: list[object]
    try:
        if isinstance(names, (str, bytes)):
            raise TypeError
        entries = list(names)  # type: ignore[call-overload]
    except TypeError:
        entries = [None]
    if not all(isinstance(entry, str) for entry in entries):
        raise TypeError(f"'{name}' must be None or a collection of file names (str); got {short_repr(names)}")
    return {entry for entry in entries if isinstance(entry, str)}
