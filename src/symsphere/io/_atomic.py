"""Atomic file output: files (or a directory) appear under their final names only once complete.

The files of one run appear *as a set* (:func:`atomic_paths`): every file is
written under a hidden temporary name in its target's directory and flushed to disk,
and only then are all of them renamed over their targets (``os.replace``, atomic
within one file system).  On any exception, ``KeyboardInterrupt`` (and, in the
command line, SIGTERM) included, the temporaries are removed and the targets are
left as they were; if a rename fails part-way, the targets already replaced are
restored from their previous versions.  The renames run with the signals deferred
(:func:`symsphere._signals.deferred`).

A target that is a symbolic link is written through: the file it points to is
replaced and the link is kept.  Only regular files (or names that do not exist yet)
are replaced: a target that is, or links to, a directory, a character or block
device, a FIFO or a socket is refused with an ``OSError`` naming it, before any
temporary is made (``/dev/null`` is never renamed over, nor a FIFO blocked on).
On Linux a file's temporary is an unnamed file (``O_TMPFILE``) until the commit, so a
killed run (SIGKILL, the OOM killer) leaves nothing; temporary directories, and files
elsewhere, carry their process id, and the next write to the same target removes those
of processes that no longer exist, with a warning (:func:`remove_stale_temporaries`).
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import re
import secrets
import shutil
import stat
import time
import warnings
from collections.abc import Collection, Iterable, Iterator
from pathlib import Path

from .._signals import deferred as signals_deferred
from .._validation import (
    TEMPORARY_KINDS,
    check_file_names,
    check_output_path,
    check_path,
    check_paths,
    file_kind,
)

__all__ = ["STALE_SECONDS", "atomic_path", "atomic_paths", "atomic_directory", "remove_stale_temporaries"]


def _temporary_name(target: Path, kind: str) -> Path:
    # Hidden, in the target's directory (so the rename stays on one file system), recognisable if a hard
    # crash (SIGKILL, power loss) ever leaves one behind, and naming its process: the next run removes it
    # as soon as that process no longer exists (remove_stale_temporaries).
    return target.with_name(f".{target.name}.{os.getpid()}-{secrets.token_hex(4)}.{kind}")


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a fresh temporary file path that replaces *path* on success.

    Parameters
    ----------
    path : str or os.PathLike
        The final file.  Its directory must exist.  If it is a symbolic link, the
        file it points to is replaced and the link kept.

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
    and the exception propagates; *path* is untouched.  :func:`atomic_paths`
    does the same for several files at once.

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
    with _atomic_paths([check_path(path, "path")], "path") as (temporary,):
        yield temporary


@contextlib.contextmanager
def atomic_paths(paths: Iterable[str | os.PathLike[str]]) -> Iterator[list[Path]]:
    """Yield fresh temporary file paths that replace *paths* together on success: all or none.

    Parameters
    ----------
    paths : iterable of str or os.PathLike
        The final files (distinct; their directories must exist).  Symbolic links are
        written through, as in :func:`atomic_path`.

    Yields
    ------
    list of pathlib.Path
        One empty temporary file per path, in the same order, each in its target's directory.

    Notes
    -----
    Every path, followed through symbolic links, must be absent or a regular file;
    anything else (a directory, a device, a FIFO, a socket) is an ``OSError`` naming
    it before any temporary is made.  On normal exit every temporary is flushed to
    disk, and then all are renamed over their targets.  A SIGINT, SIGTERM or SIGHUP
    that arrives once the renames have begun is held back and delivered when they
    are done (Ctrl-C then raises ``KeyboardInterrupt`` with the files complete); one
    that arrives before rolls everything back.
    If a rename fails, the targets already replaced get their previous contents back
    (or are removed if they did not exist), so that either all files are new or all
    are as before.  On any exception all temporaries are removed and the exception
    propagates.

    Examples
    --------
    >>> import os, tempfile
    >>> from symsphere.io import atomic_paths
    >>> folder = tempfile.mkdtemp()
    >>> targets = [os.path.join(folder, name) for name in ("a.txt", "b.txt")]
    >>> with atomic_paths(targets) as (a, b):
    ...     _ = a.write_text("first")
    ...     _ = b.write_text("second")
    >>> sorted(os.listdir(folder))
    ['a.txt', 'b.txt']
    >>> try:
    ...     with atomic_paths(targets) as (a, b):
    ...         _ = a.write_text("new")
    ...         raise OSError("disk full")
    ... except OSError:
    ...     pass
    >>> open(targets[0]).read(), sorted(os.listdir(folder))        # nothing changed, nothing left over
    ('first', ['a.txt', 'b.txt'])
    """
    with _atomic_paths(check_paths(paths), "paths") as temporaries:
        yield temporaries


@contextlib.contextmanager
def _atomic_paths(paths: list[Path], name: str) -> Iterator[list[Path]]:
    for path in paths:  # absent or a regular file (through symbolic links), in an existing directory
        check_output_path(path, name, probe=False)
    targets = [Path(os.path.realpath(path)) for path in paths]  # through symbolic links
    if len(set(targets)) != len(targets):
        raise ValueError(f"'{name}' must name distinct files; got {[str(t) for t in targets]}")
    temporaries: list[Path] = []
    locks: list[int] = []
    try:
        for path, target in zip(paths, targets, strict=False):
            remove_stale_temporaries(target)
            # A SIGINT between the file's creation and its entry in the list would leave it behind:
            # the signals wait until it is listed (and then removed with the others below).
            with signals_deferred():
                try:
                    temporary, lock = _create_temporary(target)
                except OSError as exc:  # name the user's file, not the temporary
                    raise OSError(exc.errno, exc.strerror, str(path)) from None
                temporaries.append(temporary)
                locks.append(lock)
        yield list(temporaries)
        for path, lock in zip(paths, locks, strict=False):
            try:
                os.fsync(lock)  # the data is on disk before the name points at it (any descriptor of the file)
            except OSError as exc:
                raise OSError(exc.errno, exc.strerror, str(path)) from None
        with signals_deferred():
            for index, (target, path, lock) in enumerate(zip(targets, paths, locks, strict=False)):
                if _is_unnamed(temporaries[index]):  # now it gets a name, for the rename
                    try:
                        temporaries[index] = _link_unnamed(lock, target)
                    except OSError as exc:
                        raise OSError(exc.errno, exc.strerror, str(path)) from None
            _replace_all(temporaries, targets, paths)
    except BaseException:
        for temporary in temporaries:
            if not _is_unnamed(temporary):  # an unnamed file goes with its last descriptor
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(temporary)
        raise
    finally:
        for lock in locks:
            os.close(lock)


STALE_SECONDS = 60.0
"""How long a hidden temporary of ours whose process cannot be told dead must have been left unchanged, and
unlocked, before a later write to the same target removes it (see :func:`remove_stale_temporaries`)."""


def remove_stale_temporaries(path: str | os.PathLike[str]) -> list[Path]:
    """Remove the temporaries that an earlier, killed write to *path* left beside it; return them.

    Parameters
    ----------
    path : str or os.PathLike
        A target of :func:`atomic_path`, :func:`atomic_paths` or :func:`atomic_directory` (followed
        through symbolic links).

    Returns
    -------
    list of pathlib.Path
        The files and directories removed.  When there are any, a ``UserWarning`` says so (the
        command line shows it as a note).

    Notes
    -----
    Only an uncatchable end (SIGKILL, the OOM killer, power loss) leaves a temporary behind, and on
    Linux a file's temporary has no name until its last instant (``O_TMPFILE``), so what is left is a
    temporary directory, a file of a system without unnamed files, or one caught in the instant of
    its renaming.  An entry is removed only if all of these hold: its name is exactly
    ``.NAME.<pid>-<8 hex digits>.tmp`` (or ``.old``, ``.probe``; or the older ``.NAME.<8 hex>.tmp``)
    for this target's NAME; it is a regular file or a directory owned by this user; no process holds
    its lock (a writer holds an exclusive ``flock`` on its temporary for as long as it writes, so a
    running write's file is never taken); and either the process *pid* no longer exists or the entry
    has not changed for :data:`STALE_SECONDS`.  Every write through this module calls it first, so the
    next run over the same output cleans up at once.

    Examples
    --------
    >>> import os, tempfile, warnings
    >>> from symsphere.io import remove_stale_temporaries
    >>> folder = tempfile.mkdtemp()
    >>> left = os.path.join(folder, ".out.npy.0123abcd.tmp")
    >>> _ = open(left, "w").write("a killed run's partial output")
    >>> os.utime(left, (0, 0))                      # unchanged since 1970
    >>> with warnings.catch_warnings(record=True):
    ...     [p.name for p in remove_stale_temporaries(os.path.join(folder, "out.npy"))]
    ['.out.npy.0123abcd.tmp']
    """
    target = Path(os.path.realpath(check_path(path, "path")))
    pattern = re.compile(rf"\.{re.escape(target.name)}\.(?:([0-9]+)-)?[0-9a-f]{{8}}\.(?:{'|'.join(TEMPORARY_KINDS)})")
    removed: list[Path] = []
    try:
        entries = os.scandir(target.parent)
    except OSError:  # no directory, no permission: the write itself will say so
        return removed
    now = time.time()
    with entries:
        for entry in entries:
            match = pattern.fullmatch(entry.name)
            if match is None:
                continue
            candidate = Path(entry.path)
            try:
                info = entry.stat(follow_symlinks=False)
            except OSError:
                continue
            kind_ok = stat.S_ISREG(info.st_mode) or stat.S_ISDIR(info.st_mode)
            dead = match.group(1) is not None and not _process_exists(int(match.group(1)))
            if not kind_ok or info.st_uid != os.geteuid() or not (dead or now - info.st_mtime >= STALE_SECONDS):
                continue
            if _remove_unlocked(candidate, stat.S_ISDIR(info.st_mode)):
                removed.append(candidate)
    if removed:
        shown = ", ".join(p.name for p in removed[:3]) + (", ..." if len(removed) > 3 else "")
        warnings.warn(
            f"removed {len(removed)} temporar{'y' if len(removed) == 1 else 'ies'} that a killed run left "
            f"beside {target.name} ({shown})",
            UserWarning,
            stacklevel=2,
        )
    return removed


def _process_exists(pid: int) -> bool:
    """Whether a process *pid* exists here (another user's counts; pid 0 and ours are never stale)."""
    if pid <= 0 or pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # EPERM: it exists, as another user's; anything else: assume it does
        return True
    return True


def _remove_unlocked(candidate: Path, directory: bool) -> bool:
    """Remove *candidate* if no process holds its lock; whether it was removed."""
    try:
        descriptor = os.open(candidate, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    except OSError:
        return False
    try:
        fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)  # held by a live writer: not stale
        if directory:
            shutil.rmtree(candidate)
        else:
            os.unlink(candidate)
    except OSError:
        return False
    finally:
        os.close(descriptor)
    return True


_UNNAMED = Path("/proc/self/fd")


def _is_unnamed(temporary: Path) -> bool:
    return temporary.parent == _UNNAMED


def _create_temporary(target: Path) -> tuple[Path, int]:
    """A new empty temporary for *target*, and a descriptor of it holding its lock (close it when done).

    On Linux it is an unnamed file in the target's directory (``O_TMPFILE``), reached by the name
    ``/proc/self/fd/N`` while it is written and linked under a hidden name only at commit: a process killed
    before (SIGKILL, the OOM killer) leaves nothing.  Elsewhere, or on a file system without unnamed
    files, it is the hidden file ``.NAME.<pid>-<8 hex>.tmp`` beside the target.
    """
    unnamed = getattr(os, "O_TMPFILE", 0)
    if unnamed and _UNNAMED.is_dir():
        try:
            descriptor = os.open(target.parent, unnamed | os.O_RDWR, 0o666)  # the umask applies, as to a name
        except OSError as exc:
            if exc.errno not in (errno.EOPNOTSUPP, errno.EISDIR, errno.EINVAL, errno.ENOENT):
                raise
        else:
            return _UNNAMED / str(descriptor), descriptor
    while True:
        temporary = _temporary_name(target, "tmp")
        try:
            # O_EXCL: never clobber an existing file; mode 0o666 lets the umask decide, unlike mkstemp's 0o600.
            descriptor = os.open(temporary, os.O_RDWR | os.O_CREAT | os.O_EXCL, 0o666)
        except FileExistsError:
            continue
        with contextlib.suppress(OSError):  # a file system without flock: only the age protects it
            fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
        return temporary, descriptor


def _link_unnamed(descriptor: int, target: Path) -> Path:
    """Give the unnamed file of *descriptor* a hidden name beside *target* (``linkat`` through /proc)."""
    # linkat(..., AT_SYMLINK_FOLLOW) through the magic link; os.link calls linkat (not link, which would
    # try to link the /proc entry itself: EXDEV) only when it is given a directory descriptor.
    folder = os.open(_UNNAMED, os.O_RDONLY | os.O_DIRECTORY)
    try:
        while True:
            name = _temporary_name(target, "tmp")
            try:
                os.link(str(descriptor), name, src_dir_fd=folder, follow_symlinks=True)
            except FileExistsError:
                continue
            break
    finally:
        os.close(folder)
    with contextlib.suppress(OSError):
        fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
    return name


def _check_still_replaceable(target: Path, path: Path) -> None:
    """Just before the rename: *target* is still absent or a regular file (not swapped for a device)."""
    try:
        mode = os.lstat(target).st_mode
    except FileNotFoundError:
        return
    if not stat.S_ISREG(mode):
        raise OSError(errno.EINVAL, f"became {file_kind(mode)} while it was being written; not replaced", str(path))


def _replace_all(temporaries: list[Path], targets: list[Path], paths: list[Path]) -> None:
    """Rename every temporary over its target; on a failure, put back what was there."""
    if len(targets) == 1:  # one rename is atomic by itself
        _check_still_replaceable(targets[0], paths[0])
        os.replace(temporaries[0], targets[0])
        return
    backups: list[Path | None] = []
    done = 0
    try:
        for target, path in zip(
            targets, paths, strict=False
        ):  # keep the previous versions under a second name (a hard link)
            _check_still_replaceable(target, path)
            backup = None
            if target.exists():
                backup = _temporary_name(target, "old")
                try:
                    os.link(target, backup)
                except OSError:  # a file system without hard links: a copy
                    shutil.copyfile(target, backup)
            backups.append(backup)
        for temporary, target in zip(temporaries, targets, strict=False):
            os.replace(temporary, target)
            done += 1
    except BaseException:
        for target, backup in zip(targets[:done], backups, strict=False):
            with contextlib.suppress(OSError):
                if backup is None:
                    os.unlink(target)
                else:
                    os.replace(backup, target)
        raise
    finally:
        for backup in backups:
            if backup is not None:
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(backup)


@contextlib.contextmanager
def atomic_directory(path: str | os.PathLike[str], *, replaceable: Collection[str] | None = None) -> Iterator[Path]:
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
    A directory cannot be renamed over a non-empty one.  On Linux the new
    directory and an existing *path* are exchanged in one step
    (``renameat2(RENAME_EXCHANGE)``) and the old one deleted: *path* is always
    the old or the new directory, also for a process killed at any moment.
    Elsewhere *path* is first renamed aside, the new one renamed in, and the
    old one deleted: in the instant between the two renames *path* does not exist.

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
    target = check_path(path, "path")
    allowed = check_file_names(replaceable, "replaceable")
    _check_replaceable(target, allowed)
    remove_stale_temporaries(target)
    temporary = _temporary_name(target, "tmp")
    temporary.mkdir()
    lock = os.open(temporary, os.O_RDONLY)
    with contextlib.suppress(OSError):  # held while the directory is built: a live run's is never removed
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    try:
        yield temporary
        _check_replaceable(target, allowed)  # it may have appeared or changed meanwhile
        if target.exists() and _exchange(temporary, target):
            shutil.rmtree(temporary, ignore_errors=True)  # the old directory now; if killed first, a stale one
        elif target.exists():
            aside = _temporary_name(target, "old")
            os.replace(target, aside)
            os.replace(temporary, target)
            shutil.rmtree(aside, ignore_errors=True)
        else:
            os.replace(temporary, target)
    except BaseException:
        shutil.rmtree(temporary, ignore_errors=True)
        raise
    finally:
        os.close(lock)


def _exchange(first: Path, second: Path) -> bool:
    """Swap two paths atomically (Linux ``renameat2(..., RENAME_EXCHANGE)``); False where it is not available."""
    import ctypes

    function = getattr(ctypes.CDLL(None, use_errno=True), "renameat2", None)
    if function is None:  # not glibc >= 2.28 (or not Linux)
        return False
    function.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    if function(-100, os.fsencode(first), -100, os.fsencode(second), 2) == 0:  # AT_FDCWD, RENAME_EXCHANGE
        return True
    code = ctypes.get_errno()
    if code in (errno.ENOSYS, errno.EINVAL, errno.EOPNOTSUPP):  # an old kernel or a file system without it
        return False
    raise OSError(code, os.strerror(code), str(second))


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
