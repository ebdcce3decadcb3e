"""examples/: every walkthrough runs as written (a notebook-style tour that the suite runs)."""

import runpy
from pathlib import Path

import pytest

# the Mitsuba examples need the extra mitsuba: tests/mitsuba runs them (small, skipped without Mitsuba)
EXAMPLES = sorted(
    p for p in (Path(__file__).resolve().parents[1] / "examples").glob("*.py") if not p.name.startswith("mitsuba_")
)


def test_there_are_examples():
    assert EXAMPLES


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_example_runs(path, capsys):
    runpy.run_path(str(path), run_name="__main__")
    out = capsys.readouterr().out
    assert "symsphere" in out and "False" not in out  # every check the walkthrough prints is True
