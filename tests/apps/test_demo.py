"""The demo (symsphere.apps.demo): ``symsphere demo`` and ``run_demo``."""

import contextlib
import io
import os
import re
import stat

import pytest
from references import one_line_error

import symsphere.apps.demo
from symsphere.apps.cli import main
from symsphere.apps.demo import DEMO_FILES, run_demo


def _leftovers(directory):
    """Everything in *directory*: after a failure it must be empty (no target, no temporary)."""
    return sorted(p.name for p in directory.iterdir())


DEMO_N = 48 * 2**11

# One xdist worker runs this module (Makefile: --dist loadgroup) and the demo run is a session fixture, so
# that it is made once: a worker may run other modules' tests between this module's (which ends a module
# fixture), and the two demo runs were the suite's two slowest set-ups.
pytestmark = pytest.mark.xdist_group("demo")


@pytest.fixture(scope="session")
def demo_run(tmp_path_factory):
    """(the output folder, what the run printed on stdout) of one demo run, made once for the session."""
    out = tmp_path_factory.mktemp("demo") / "symsphere-demo"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        assert main(["demo", "--out", str(out), "--n", str(DEMO_N), "--seed", "0", "--no-progress"]) == 0
    return out, printed.getvalue()


@pytest.fixture
def demo_dir(demo_run):
    return demo_run[0]


def test_demo_writes_report_and_figure(demo_dir):
    assert sorted(p.name for p in demo_dir.iterdir()) == ["figure.png", "render.png", "report.md"]
    assert (demo_dir / "figure.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert _leftovers(demo_dir.parent) == ["symsphere-demo"]  # no temporary directories


def test_demo_report_states_the_measured_verdicts(demo_dir):
    report = (demo_dir / "report.md").read_text(encoding="utf-8")
    assert "**equal_area passes** every test against the uniform density" in report
    assert "**paper1 fails** against the uniform density" in report
    assert "**paper2 fails** against the uniform density" in report
    rows = [line for line in report.splitlines() if line.startswith("| ") and "domain" not in line]
    assert len(rows) == 15  # 3 domains x 3 maps vs uniform, + 3 domains x 2 paper maps vs their own pdf
    equal_area = [row for row in rows if "| equal_area |" in row]
    assert len(equal_area) == 3 and all("| pass |" in row for row in equal_area)


def test_demo_replaces_its_own_output(demo_dir, capsys):
    before = (demo_dir / "report.md").read_text(encoding="utf-8")
    assert main(["demo", "--out", str(demo_dir), "--n", "4800", "--seed", "1", "--no-progress"]) == 0
    assert str(demo_dir / "report.md") in capsys.readouterr().out
    assert (demo_dir / "report.md").read_text(encoding="utf-8") != before
    assert _leftovers(demo_dir.parent) == ["symsphere-demo"]
    # Same seed, same n: the same report.
    assert main(["demo", "--out", str(demo_dir), "--n", str(DEMO_N), "--seed", "0", "--no-progress"]) == 0
    assert (demo_dir / "report.md").read_text(encoding="utf-8") == before


def test_demo_refuses_a_directory_with_other_files(tmp_path, capsys):
    (tmp_path / "notes.txt").write_text("keep me")
    assert main(["demo", "--out", str(tmp_path), "--n", "4800", "--no-progress"]) == 1
    assert "notes.txt" in capsys.readouterr().err
    assert _leftovers(tmp_path) == ["notes.txt"]


@pytest.mark.parametrize("arguments, named", [(["--n", "100"], "'n'"), (["--seed", "-2"], "'seed'")])
def test_demo_rejects_invalid_values(tmp_path, capsys, arguments, named):
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out), *arguments, "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "symsphere demo: error:" in err and named in err
    assert _leftovers(tmp_path) == []


# --- run_demo ---------------------------------------------------------------------


def _run_demo_capturing_figure_titles(monkeypatch, out, n):
    """run_demo(out, n), and the titles of the axes of the figure it saved (matplotlib's public API)."""
    from matplotlib.figure import Figure

    titles = []
    savefig = Figure.savefig

    def recording_savefig(self, *args, **kwargs):
        titles.extend(axes.get_title() for axes in self.axes)
        return savefig(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", recording_savefig)
    report = run_demo(out, n=n, seed=0, progress=False)
    return report, titles


def _scatter_directions(report, titles):
    """(directions the report says the scatter plots show, directions each scatter plot's title says)."""
    stated = re.search(r"(\d+) whole orbits? \((\d+) directions\)", report)
    shown = [int(m.group(1)) for t in titles if (m := re.search(r": (\d+) directions$", t))]
    return int(stated.group(2)), shown


def test_run_demo_writes_its_report_atomically(tmp_path, monkeypatch):
    out = tmp_path / "demo"
    report, titles = _run_demo_capturing_figure_titles(monkeypatch, out, 48 * 64)
    assert report == out / "report.md"
    assert sorted(p.name for p in out.iterdir()) == sorted(DEMO_FILES)
    assert _leftovers(tmp_path) == ["demo"]  # no temporary directory beside it
    text = report.read_text(encoding="utf-8")
    stated, shown = _scatter_directions(text, titles)
    assert shown == [stated] * 3  # 64 whole orbits, one scatter plot per map

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(symsphere.apps.demo, "sample_sphere", interrupted)
    with pytest.raises(KeyboardInterrupt):
        run_demo(out, n=48 * 64, seed=1, progress=False)
    assert report.read_text(encoding="utf-8") == text  # the earlier report, whole
    assert _leftovers(tmp_path) == ["demo"]


def test_figure_and_report_agree_on_the_scatter_directions_for_small_n(tmp_path, monkeypatch):
    # for n < 48 * 64 the report said 64 whole orbits (3072 directions) while the
    # scatter plots showed all n directions.
    report, titles = _run_demo_capturing_figure_titles(monkeypatch, tmp_path / "demo", 48)
    text = report.read_text(encoding="utf-8")
    stated, shown = _scatter_directions(text, titles)
    assert shown == [stated] * 3 == [48] * 3
    assert "1 whole orbit (48 directions)" in text and "render.png" in text


def test_demo_names_all_its_files_in_help_and_closing_line(demo_run, capsys):
    # render.png was mentioned neither in --help nor in the closing line.
    assert main(["demo", "--help"]) == 0
    assert "render.png" in capsys.readouterr().out
    closing = demo_run[1].strip().splitlines()[-1]  # the session's demo run (no second run for this)
    assert all(name in closing for name in DEMO_FILES)


# --- --out that is a FIFO ------------------------------------------------------------------------------------------


def _listing(directory):
    return sorted(p.name for p in directory.iterdir())


def test_demo_out_that_is_a_fifo_is_refused(tmp_path, capsys):
    os.mkfifo(tmp_path / "demo")
    assert main(["demo", "--n", "4800", "--out", str(tmp_path / "demo"), "--no-progress"]) != 0
    assert "demo" in one_line_error(capsys.readouterr().err)
    assert stat.S_ISFIFO(os.lstat(tmp_path / "demo").st_mode) and _listing(tmp_path) == ["demo"]
