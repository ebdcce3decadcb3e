"""symsphere.io: files appear whole or not at all; directions round-trip through .npy and .csv."""

import os

import numpy as np
import pytest

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
