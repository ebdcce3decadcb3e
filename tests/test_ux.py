"""First contact with the command line and the package: optional extras, error bars, warnings, help
and choices, the lazy modules, the docs' citations, notebook reprs.

The demo's first contact is in test_demo.py, the wheel's (extras, metadata, a bare install) in
tests/test_packaging.py.
"""

import importlib.metadata
import re
import subprocess
import sys

import numpy as np
import pytest

import symsphere as ss
from symsphere.apps.cli import main
from symsphere.integrands import INTEGRANDS
from symsphere.points import POINT_SETS
from symsphere.warps import METHODS


def _one_clean_line(err):
    # The one line that says numba is compiling (a first run with an empty cache) is not a message of the verb.
    lines = [line for line in err.splitlines() if line.strip() and "compiling numba kernels" not in line]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


# --- optional extras: --workers without the distributed extra -------------------------------------


@pytest.mark.parametrize("verb", [["integrate", "--integrand", "exp", "--n", "4800"], ["render", "--spp", "24"]])
@pytest.mark.parametrize("option", [["--workers", "2"], ["--scheduler", "tcp://127.0.0.1:1"]])
def test_cluster_options_without_dask_name_the_extra(monkeypatch, capsys, tmp_path, verb, option):
    # As after `pip install symsphere` (no extras): importing dask or distributed fails.
    for name in ("dask", "distributed"):
        monkeypatch.setitem(sys.modules, name, None)
    monkeypatch.delitem(sys.modules, "symsphere.distributed", raising=False)  # imported afresh: it needs dask
    if "distributed" in vars(ss):
        monkeypatch.delattr(ss, "distributed")
    out = ["--out", str(tmp_path / "r.png")] if verb[0] == "render" else []
    assert main([*verb, *option, *out]) == 2
    line = _one_clean_line(capsys.readouterr().err)
    assert line.endswith("pip install 'symsphere[distributed]'") and option[0] in line


def test_cluster_options_say_they_need_the_extra(capsys):
    assert main(["integrate", "--help"]) == 0
    assert "symsphere[distributed]" in capsys.readouterr().out


# --- error bars: none rather than '± nan' ----------------------------------------------------------


def test_integrate_without_an_error_bar_says_why(capsys):
    args = ["integrate", "--integrand", "exp", "--n", "4800", "--points", "halton", "--replicates", "1", "--seed", "0"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "nan" not in out and "no error bar" in out and "--replicates 2" in out


def test_integration_result_without_an_error_bar_says_why():
    from scipy.stats import qmc

    result = ss.integrate(lambda w: np.exp(w[:, 0]), n=3072, points=qmc.Sobol(2, seed=1))
    assert np.isnan(result.standard_error)  # the value stays NaN, as documented; its text explains
    text = str(result)
    assert "nan" not in text and "no error bar" in text and "points='sobol'" in text
    assert "no error bar" in result._repr_html_()
    one = ss.integrate(lambda w: w[:, 0] ** 2, n=4800, points="stratified", replicates=1, rng=1)
    assert "pass replicates >= 2" in str(one)


# --- warnings: scipy's Sobol' balance warning on the CLI --------------------------------------------


@pytest.mark.parametrize("verb", [["sample", "--n", "480"], ["integrate", "--integrand", "exp", "--n", "4608"]])
def test_sobol_balance_warning_is_one_note_on_the_cli(tmp_path, verb):
    out = ["--out", str(tmp_path / "h.csv")] if verb[0] == "sample" else []
    run = subprocess.run(
        [sys.executable, "-W", "default", "-m", "symsphere", *verb, "--points", "sobol", "--seed", "0", *out],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    line = _one_clean_line(run.stderr)
    assert line.startswith(f"symsphere {verb[0]}: note: The balance properties of Sobol' points")
    assert "--n" in line and ".py" not in line and "UserWarning" not in line


# --- the docs cite files that exist -----------------------------------------------------------

_ROOT = __import__("pathlib").Path(__file__).resolve().parents[1]


@pytest.mark.parametrize(
    "page",
    ["README.md", *sorted(str(p.relative_to(_ROOT)) for p in (_ROOT / "docs").glob("*/*.md"))],
)
def test_docs_cite_only_files_that_exist(page):
    text = (_ROOT / page).read_text(encoding="utf-8")
    # Repository paths; not patterns (tests/test_<module>.py, render/{scene, ...}.py) nor build output.
    cited = set(
        re.findall(r"(?<![\w/.])((?:src|tests|docs|benchmarks|scripts|examples|\.ci)/[\w./-]*\w)(?![\w<{*])", text)
    )
    cited = {c for c in cited if not c.startswith("docs/_build")}
    cited |= set(re.findall(r"\]\(((?!https?:|#)[^)#\s]+)", text))  # Markdown links
    # and any `dir/file.ext` in backquotes (the old first line of design.md cited `shared/DESIGN.md`)
    cited |= set(re.findall(r"`([\w.-]+/[\w./-]*\.(?:md|py|toml|json|png|rst|txt))`", text))
    bases = [_ROOT, _ROOT / "docs", (_ROOT / page).parent, _ROOT / "src" / "symsphere", _ROOT / "tests"]
    generated = ("symsphere-demo/", "study-report/")  # what `make demo` and `symsphere study` write
    missing = [c for c in sorted(cited) if not (c.startswith(generated) or any((b / c).exists() for b in bases))]
    assert missing == []


# --- the lazy modules --------------------------------------------------------------------------------


def test_render_loads_lazily_and_dir_lists_it():
    # The library's lazy table names library modules only: the study is an application (symsphere.apps.study).
    code = (
        "import sys, symsphere as ss; "
        "assert not any(m in sys.modules for m in ('symsphere.render', 'symsphere.apps', 'scipy.stats', 'dask')); "
        "names = dir(ss); assert {'render', 'stats', 'distributed', 'peers'} <= set(names), names; "
        "assert 'study' not in names and not hasattr(ss, 'study'); "
        "assert ss.render.render.__module__ == 'symsphere.render.renderer'; "
        "assert 'symsphere.apps' not in sys.modules; print('ok')"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert run.stdout.strip() == "ok", run.stderr
    with pytest.raises(AttributeError, match="has no attribute 'nope'"):
        ss.nope  # noqa: B018


# --- help, choices and output of the verbs; the study's figure labels -------------------------------


def test_furnace_prints_mean_radiance_against_exact_and_is_not_white(tmp_path, capsys):
    png = tmp_path / "f.png"
    args = ["render", "--scene", "furnace", "--width", "8", "--height", "6", "--spp", "24", "--seed", "1"]
    assert main([*args, "--strategy", "cosine", "--out", str(png), "--no-progress"]) == 0
    out = capsys.readouterr().out
    match = re.search(r"furnace: mean radiance ([\d.]+) .* exact 2 ", out)
    assert match and abs(float(match.group(1)) - 2) < 0.1, out
    from matplotlib.image import imread

    pixels = imread(png)[..., :3]
    assert 0.6 < pixels.mean() < 0.85  # mid-grey in sRGB (0.5 linear is 188/255), not clipped to white


@pytest.mark.xdist_group("dask")  # a local Dask cluster: with the other cluster tests (Makefile: --dist loadgroup)
def test_render_on_a_cluster_reports_workers_not_threads(tmp_path, capsys):
    pytest.importorskip("distributed")
    args = ["render", "--width", "8", "--height", "6", "--spp", "24", "--seed", "1", "--workers", "1"]
    assert main([*args, "--out", str(tmp_path / "c.png"), "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "Dask cluster of 1 workers" in out and "threads" not in out


def test_every_verb_lists_its_choices(capsys):
    from symsphere.apps.study import CONFIGS
    from symsphere.render import SAMPLERS, SCENES, STRATEGIES

    expected = {
        "sample": [*METHODS, *POINT_SETS, "sphere", "hemisphere"],
        "integrate": [*INTEGRANDS, *METHODS, *POINT_SETS],
        "render": [*SCENES, *STRATEGIES, "sobol_interlaced2", *SAMPLERS, *METHODS],
        "study": list(CONFIGS),
        "demo": [*METHODS, "render.png"],
    }
    for verb, names in expected.items():
        assert main([verb, "--help"]) == 0
        text = " ".join(capsys.readouterr().out.split())
        assert [name for name in names if name not in text] == [], verb


def test_version_agrees_with_the_metadata(capsys):
    assert main(["--version"]) == 0
    assert (
        capsys.readouterr().out.strip()
        == f"symsphere {ss.__version__}"
        == f"symsphere {importlib.metadata.version('symsphere')}"
    )


def test_errors_end_with_what_to_do(capsys, tmp_path):
    cases = [
        (["sample", "--n", "100", "--out", str(tmp_path / "d.npy")], "the nearest valid sizes are 96 or 144"),
        (["sample", "--n", "48", "--normal", "0", "1", "0", "--out", str(tmp_path / "d.npy")], "drop --normal"),
        (["integrate", "--integrand", "nope", "--n", "48"], "use one of"),
    ]
    for args, ending in cases:
        assert main(args) == 2
        line = _one_clean_line(capsys.readouterr().err)
        assert ending in line, line


# The study's figures keep their texts (the slope guides' labels) inside: tests/apps/test_study.py, in its tiny
# study of exp.


# --- notebooks ------------------------------------------------------------------------------------------


def test_notebook_reprs():
    result = ss.integrate(lambda w: np.exp(w[:, 0]), n=4800, rng=1)
    html = result._repr_html_()
    assert html.startswith("<table>") and "standard error" in html and "interval" in html
    test = ss.stats.chi2_test(ss.stats.one_per_orbit(ss.sample_sphere(48 * 1000, rng=1), 48, rng=2),
                              ss.stats.uniform_pdf("sphere"))  # fmt: skip
    assert "PASSED" in test._repr_html_() and "<table>" in test._repr_html_()
    image = ss.render.render("furnace", width=4, height=3, spp=8, strategy="cosine", seed=1)
    assert image._repr_png_()[:8] == b"\x89PNG\r\n\x1a\n"
