"""symsphere.io: files appear whole or not at all; directions round-trip through .npy and .csv."""

import errno
import os
import shutil
import stat
import sys

import numpy as np
import pytest
from references import inject_sigint

import symsphere
from symsphere import io
from symsphere.io import atomic_directory, atomic_path, save_directions, stream_directions


def _leftovers(directory):
    """Everything in *directory*: after a failure it must be empty (no target, no temporary)."""
    return sorted(p.name for p in directory.iterdir())


def _blocks_failing_after_one(exception):
    def blocks(out):
        first = np.tile([0.0, 0.0, 1.0], (48, 1))  # unit vectors: zero rows are refused
        if out is not None:
            out[:48] = first
            first = out[:48]
        yield first  # some bytes reach the temporary first
        raise exception

    return blocks


@pytest.mark.parametrize("suffix", [".npy", ".csv"])
def test_failed_write_leaves_no_file(tmp_path, suffix):
    out = tmp_path / f"d{suffix}"
    with pytest.raises(OSError, match="No space"):
        stream_directions(out, 96, np.float64, _blocks_failing_after_one(OSError(28, "No space left on device")))
    assert _leftovers(tmp_path) == []


def test_atomic_path_keeps_target_on_any_exception(tmp_path):
    out = tmp_path / "f.txt"
    with pytest.raises(ZeroDivisionError):
        with atomic_path(out) as temporary:
            temporary.write_text("half")
            _ = 1 / 0
    assert _leftovers(tmp_path) == []
    with atomic_path(out) as temporary:
        temporary.write_text("whole")
        if hasattr(os, "O_TMPFILE"):  # Linux: an unnamed file until the commit, nothing to leave behind
            assert _leftovers(tmp_path) == []
        else:
            assert temporary.parent == tmp_path and temporary.name.startswith(".")
    assert out.read_text() == "whole" and _leftovers(tmp_path) == ["f.txt"]


def test_atomic_path_gives_the_usual_permissions(tmp_path):
    umask = os.umask(0o022)
    os.umask(umask)
    out = tmp_path / "f.txt"
    with atomic_path(out) as temporary:
        temporary.write_text("x")
    assert out.stat().st_mode & 0o777 == 0o666 & ~umask


def test_save_directions_names_the_argument():
    with pytest.raises(ValueError, match="'--out' must end in one of .npy, .csv"):
        save_directions("d.json", np.zeros((48, 3)), name="--out")
    with pytest.raises(ValueError, match="'path'"):
        save_directions("d.json", np.zeros((48, 3)))


def test_atomic_directory_refuses_to_replace_foreign_files(tmp_path):
    target = tmp_path / "out"
    target.mkdir()
    (target / "thesis.tex").write_text("precious")
    with pytest.raises(FileExistsError, match="thesis.tex"):
        with atomic_directory(target, replaceable={"report.md"}):
            pytest.fail("must refuse before yielding")
    assert (target / "thesis.tex").read_text() == "precious"
    assert _leftovers(tmp_path) == ["out"]


def test_atomic_directory_cleans_up_after_failure(tmp_path):
    target = tmp_path / "out"
    target.mkdir()
    (target / "report.md").write_text("old")
    with pytest.raises(KeyboardInterrupt):
        with atomic_directory(target, replaceable={"report.md"}) as build:
            (build / "report.md").write_text("new")
            raise KeyboardInterrupt
    assert (target / "report.md").read_text() == "old"
    assert _leftovers(tmp_path) == ["out"]


# --- writes that are whole or absent: no memory map, space reserved first, sets of files, special files refused, a signal or a kill leaves nothing ---


def _listing(directory):
    return sorted(p.name for p in directory.iterdir())


def _write_set(paths, texts):
    with io.atomic_paths(paths) as temporaries:
        for temporary, text in zip(temporaries, texts, strict=False):
            temporary.write_text(text)


def test_npy_is_written_without_a_memory_map(tmp_path, monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("a memory map turns ENOSPC into SIGBUS")

    monkeypatch.setattr(np.lib.format, "open_memmap", refuse)
    monkeypatch.setattr(np, "memmap", refuse)
    path = tmp_path / "d.npy"
    n = 48 * 300
    io.stream_directions(
        path, n, np.float32, lambda out: symsphere.iter_sphere(n, chunk=48 * 64, rng=3, dtype=np.float32)
    )
    np.testing.assert_array_equal(np.load(path), symsphere.sample_sphere(n, rng=3, dtype=np.float32))


def test_space_is_reserved_before_any_block_is_computed(tmp_path, monkeypatch):
    computed = []

    def fallocate(fd, offset, length):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    def blocks(out):
        computed.append(True)
        yield np.zeros((48, 3))

    monkeypatch.setattr(os, "posix_fallocate", fallocate, raising=False)
    with pytest.raises(OSError, match="No space left"):
        io.stream_directions(tmp_path / "d.npy", 48, np.float64, blocks)
    assert computed == [] and _listing(tmp_path) == []


def test_atomic_paths_failure_while_writing_changes_nothing(tmp_path):
    paths = [tmp_path / name for name in ("a.png", "a.pfm", "a.npy")]
    _write_set(paths, ["old png", "old pfm", "old npy"])
    with pytest.raises(KeyboardInterrupt):
        with io.atomic_paths(paths) as temporaries:
            temporaries[0].write_text("new png")
            raise KeyboardInterrupt
    assert [p.read_text() for p in paths] == ["old png", "old pfm", "old npy"]
    assert _listing(tmp_path) == ["a.npy", "a.pfm", "a.png"]


def test_atomic_paths_failed_rename_restores_the_old_set(tmp_path, monkeypatch):
    paths = [tmp_path / name for name in ("a.png", "a.pfm", "a.npy")]
    _write_set(paths[:2], ["old png", "old pfm"])  # a.npy did not exist before
    real_replace = os.replace
    calls = []

    def failing_replace(source, target):
        calls.append(target)
        if len(calls) == 3:  # the third rename (a.npy) fails: disk error, signal, ...
            raise OSError(errno.EIO, "I/O error", str(target))
        return real_replace(source, target)

    monkeypatch.setattr(os, "replace", failing_replace)
    with pytest.raises(OSError, match="I/O error"):
        _write_set(paths, ["new png", "new pfm", "new npy"])
    monkeypatch.setattr(os, "replace", real_replace)
    assert [p.read_text() for p in paths[:2]] == ["old png", "old pfm"]
    assert _listing(tmp_path) == ["a.pfm", "a.png"]


def test_library_writers_refuse_a_fifo_and_leave_nothing(tmp_path):
    from symsphere.render import save_image_set

    os.mkfifo(tmp_path / "x.npy")
    os.symlink("x.npy", tmp_path / "y.pfm")
    with pytest.raises(OSError, match="FIFO"):
        io.save_directions(tmp_path / "x.npy", np.array([[0.0, 0.0, 1.0]]))
    with pytest.raises(OSError, match="FIFO"):
        save_image_set([tmp_path / "y.png", tmp_path / "y.pfm"], np.zeros((2, 2, 3)))
    with pytest.raises(OSError, match="FIFO"), io.atomic_path(tmp_path / "x.npy"):
        pass
    assert stat.S_ISFIFO(os.lstat(tmp_path / "x.npy").st_mode)
    assert _listing(tmp_path) == ["x.npy", "y.pfm"]  # no temporary, no y.png


@pytest.mark.usefixtures("python_sigint_handler")
def test_sigint_just_after_the_temporary_is_created_leaves_nothing(tmp_path, monkeypatch):
    # The window between the temporary's creation (os.open) and its entry in the list of files to
    # remove: a SIGINT there (found by test_late_sigint_at_many_times on a loaded machine) is deferred
    # until the file is listed, so the rollback removes it.
    import fcntl

    from symsphere.io import atomic_path

    out = tmp_path / "d.npy"
    out.write_bytes(b"old")
    if hasattr(os, "O_TMPFILE"):  # Linux: the temporary is the unnamed file of the first os.open
        inject_sigint(monkeypatch, os, "open", 1)
    else:
        inject_sigint(monkeypatch, fcntl, "flock", 1)  # right after the temporary's os.open
    with pytest.raises(KeyboardInterrupt):
        with atomic_path(out) as tmp:
            tmp.write_bytes(b"new")
    monkeypatch.undo()
    assert _listing(tmp_path) == ["d.npy"] and out.read_bytes() == b"old"


def test_a_killed_demo_or_study_directory_is_removed_by_the_next_write(tmp_path):
    target = tmp_path / "report"
    left = tmp_path / ".report.4194305-89abcdef.tmp"  # a pid beyond the kernel's maximum: no such process
    left.mkdir()
    (left / "figure.png").write_bytes(b"partial")
    with pytest.warns(UserWarning, match=r"removed 1 temporary that a killed run left beside report"):
        with io.atomic_directory(target) as build:
            (build / "report.md").write_text("# done")
    assert _listing(tmp_path) == ["report"]


def test_writers_refuse_rows_that_are_not_directions(tmp_path):
    for rows in (np.zeros((2, 3)), np.array([[0.0, 0.0, 2.0]])):
        with pytest.raises(ValueError, match="'directions'"):
            io.save_directions(tmp_path / "d.npy", rows)
    with pytest.raises(ValueError, match="'blocks'"):
        io.stream_directions(tmp_path / "d.npy", 48, np.float64, lambda out: [np.full((48, 3), np.nan)])
    with pytest.raises(ValueError, match="'blocks'"):
        io.stream_directions(tmp_path / "d.csv", 48, np.float32, lambda out: [np.zeros((48, 3))])
    assert _listing(tmp_path) == []


@pytest.mark.skipif(sys.platform != "linux", reason="renameat2(RENAME_EXCHANGE) is Linux's")
def test_replacing_a_directory_exchanges_it_in_one_step(tmp_path, monkeypatch):
    # A process killed between "rename the old directory aside" and "rename the new one in" left no
    # directory at all: on Linux the two are exchanged atomically, the target is never absent.
    out = tmp_path / "report"
    with atomic_directory(out, replaceable={"a"}) as build:
        (build / "a").write_text("old")
    moves, real_replace = [], os.replace
    monkeypatch.setattr(os, "replace", lambda source, target: moves.append(source) or real_replace(source, target))
    seen, real_rmtree = [], shutil.rmtree

    def rmtree(path, *args, **kwargs):  # when the old directory is deleted, the new one is in place
        seen.append((out / "a").read_text())
        return real_rmtree(path, *args, **kwargs)

    monkeypatch.setattr(shutil, "rmtree", rmtree)
    with atomic_directory(out, replaceable={"a"}) as build:
        (build / "a").write_text("new")
    assert moves == [] and seen == ["new"] and (out / "a").read_text() == "new"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report"]
