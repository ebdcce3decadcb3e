"""The convergence study (symsphere.apps.study): its configuration, its command and an end-to-end run.

Its statistics (RMSE, slope fit, cap discrepancy) are library code, tested in tests/test_quality.py.
"""

import argparse
import csv
import math

import pytest

from symsphere.apps.study import CONFIGS, StudyConfig, add_study_parser, run_study, study_files
from symsphere.apps.study.config import domains
from symsphere.apps.study.report import report_html
from symsphere.apps.study.run import chi2_tests
from symsphere.apps.study.samplers import all_samplers
from symsphere.apps.study.samplers import samplers as domain_samplers
from symsphere.integrands import INTEGRANDS

# --- configuration ------------------------------------------------------------------------


@pytest.mark.parametrize(
    "changes, field",
    [
        (dict(repetitions=1), "repetitions"),
        (dict(repetitions=2.5), "repetitions"),
        (dict(k_min=-1), "k_min"),
        (dict(k_min="2"), "k_min"),
        (dict(k_min=5, k_max=6), "k_max"),
        (dict(k_max=21), "k_max"),
        (dict(integrands=("exp", "no_such_integrand")), "integrands"),
        (dict(integrands=()), "integrands"),
        (dict(integrands="exp"), "integrands"),
        (dict(scheme_methods=("equal_area", "equal_area")), "scheme_methods"),
        (dict(scheme_points=("random", "lattice")), "scheme_points"),
        (dict(sphere_peers=(("cosine", "random"),)), "sphere_peers"),
        (dict(sphere_peers=(("classic", "random"), ("gaussian", "sobol"))), "sphere_peers"),
        (dict(sphere_peers=(("octahedral", "random"),)), "sphere_peers"),  # the baseline is missing
        (dict(hemisphere_peers=(("classic", "random"),)), "hemisphere_peers"),
        (dict(discrepancy_k_max=10), "discrepancy_k_max"),
        (dict(discrepancy_repetitions=0), "discrepancy_repetitions"),
        (dict(chi2_samples=10), "chi2_samples"),
        (dict(density_samples=4801), "density_samples"),
        (dict(warp_samples=5), "warp_samples"),
        (dict(name=""), "name"),
    ],
)
def test_bad_config_values_name_the_field(changes, field):
    with pytest.raises(ValueError, match=f"'{field}'"):
        CONFIGS["small"].replace(**changes)


def test_bad_run_arguments(tmp_path):
    with pytest.raises(ValueError, match="'config'"):
        run_study(tmp_path / "out", config="medium", progress=False)
    with pytest.raises(ValueError, match="'seed'"):
        run_study(tmp_path / "out", config="small", seed=-1, progress=False)
    assert list(tmp_path.iterdir()) == []


def test_sizes_are_valid_for_every_sampler():
    config = CONFIGS["full"]
    for sampler in all_samplers(config):
        for k in config.ks:
            n = sampler.n_for(k)
            assert 0.8 < n / (48 * 2**k) < 1.25
            if sampler.is_scheme and sampler.points == "stratified":
                base = n // (48 if sampler.domain == "sphere" else 24)
                assert math.isqrt(base) ** 2 == base
            else:
                assert n == 48 * 2**k


def test_qmc_config_sizes_and_samplers():
    # The Lebedev peers use their largest rule within the budget n = 48 * 2**k (r x 5810 when rotated);
    # every other sampler of the 'qmc' configuration uses n itself.
    from symsphere.peers import LEBEDEV_SIZES

    config = CONFIGS["qmc"]
    labels = {s.label for s in all_samplers(config)}
    assert {
        "symsphere_equal_area/sobol_interlaced2",
        "symsphere_equal_area/sobol_interlaced3",
        "octahedral/sobol_interlaced2",
        "lebedev/random",
        "lebedev_rotated/random",
        "fibonacci_rotated/random",
    } <= labels
    for sampler in all_samplers(config):
        for k in config.ks:
            budget, n = 48 * 2**k, sampler.n_for(k)
            if sampler.name == "lebedev":
                assert n == max(size for size in LEBEDEV_SIZES if size <= budget)
            elif sampler.name == "lebedev_rotated" and budget >= 2 * 5810:
                assert n == budget - budget % 5810
            elif sampler.name == "lebedev_rotated":
                assert n in LEBEDEV_SIZES and n <= budget
            else:
                assert n == budget
    assert [s.is_random for s in all_samplers(config) if s.name.startswith("lebedev")] == [False, True]
    assert chi2_tests(config) == [t for t in chi2_tests(config) if not t[0].name.startswith("lebedev")]


# --- the command line ----------------------------------------------------------------------


def _parser():
    parser = argparse.ArgumentParser(prog="symsphere")
    add_study_parser(parser.add_subparsers(dest="verb"))
    return parser


def test_study_help(capsys):
    with pytest.raises(SystemExit) as exit_info:
        _parser().parse_args(["study", "--help"])
    assert exit_info.value.code == 0
    text = capsys.readouterr().out
    for option in ("--out", "--config", "--seed", "--repetitions", "--k-max", "--no-progress"):
        assert option in text


@pytest.mark.parametrize(
    "arguments, option",
    [(["--seed", "-1"], "--seed"), (["--repetitions", "1"], "--repetitions"), (["--k-max", "3"], "--k-max")],
)
def test_study_command_rejects_bad_options(tmp_path, arguments, option):
    args = _parser().parse_args(["study", "--config", "small", "--out", str(tmp_path / "r"), *arguments])
    with pytest.raises(ValueError, match=option):
        args.handler(args)
    assert list(tmp_path.iterdir()) == []


def test_study_command_names_a_missing_parent_directory(tmp_path):
    out = tmp_path / "missing" / "study"
    args = _parser().parse_args(["study", "--config", "small", "--out", str(out)])
    with pytest.raises(OSError, match="missing"):
        args.handler(args)
    assert list(tmp_path.iterdir()) == []


# --- end to end --------------------------------------------------------------------------------


def _read_csv(path):
    with open(path, newline="", encoding="utf-8") as handle:
        reader = csv.DictReader(handle)
        return reader.fieldnames, list(reader)


@pytest.mark.slow
def test_small_study_end_to_end(tmp_path, capsys):
    out = tmp_path / "study"
    args = _parser().parse_args(["study", "--config", "small", "--out", str(out), "--no-progress", "--seed", "3"])
    assert args.handler(args) == 0
    assert "report.md" in capsys.readouterr().out
    config = CONFIGS["small"]
    assert sorted(p.name for p in out.iterdir()) == sorted(study_files(config))
    assert [p.name for p in tmp_path.iterdir()] == ["study"]  # no temporary left behind

    samplers = {domain: domain_samplers(config, domain) for domain in domains(config)}
    fields, rows = _read_csv(out / "convergence.csv")
    assert fields[:8] == ["integrand", "domain", "sampler", "points", "k", "n", "repetitions", "rmse"]
    for column in ("mean_error", "mean_seconds"):
        assert column in fields
    expected_rows = sum(len(samplers[INTEGRANDS[g].domain]) * len(config.ks) for g in config.integrands)
    assert len(rows) == expected_rows
    for row in rows:
        assert float(row["rmse"]) >= 0 and math.isfinite(float(row["rmse"]))
        assert float(row["mean_seconds"]) > 0 and int(row["repetitions"]) == config.repetitions
    # Unbiased and convergent: the QMC scheme on exp at the largest n.
    best = [
        r
        for r in rows
        if r["integrand"] == "exp"
        and r["sampler"] == "symsphere_equal_area"
        and r["points"] == "sobol"
        and int(r["k"]) == config.k_max
    ]
    assert float(best[0]["relative_rmse"]) < 1e-3

    fields, summary = _read_csv(out / "summary.csv")
    for column in ("slope", "slope_se", "efficiency", "relative_efficiency", "status"):
        assert column in fields
    assert len(summary) == expected_rows // len(config.ks)
    baseline = [r for r in summary if r["sampler"] == "classic" and r["points"] == "random"]
    assert all(float(r["relative_efficiency"]) == 1.0 for r in baseline)

    fields, discrepancy = _read_csv(out / "discrepancy.csv")
    assert {"sampler", "points", "n", "discrepancy_rms", "weighted_discrepancy_rms"} <= set(fields)
    assert len(discrepancy) == len(samplers["sphere"]) * len(config.discrepancy_ks)
    assert all(0 < float(r["discrepancy_rms"]) < 1 for r in discrepancy)

    fields, chi2 = _read_csv(out / "chi2.csv")
    assert {"sampler", "domain", "reference", "p_value", "passed"} <= set(fields)
    assert len(chi2) == len(chi2_tests(config))
    paper_own = [r for r in chi2 if r["sampler"].startswith("symsphere_paper") and r["reference"] == "own pdf"]
    assert paper_own and all(0 <= float(r["p_value"]) <= 1 for r in paper_own)

    report = (out / "report.md").read_text(encoding="utf-8")
    for sampler in all_samplers(config):
        assert sampler.name in report and sampler.label in report
    for g in config.integrands:
        assert f"`{g}`" in report and repr(INTEGRANDS[g].exact) in report
    for name in study_files(config):
        if name.endswith(".png"):
            assert f"({name})" in report
            assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    page = (out / "report.html").read_text(encoding="utf-8")
    assert page.startswith("<!DOCTYPE html>") and "<table>" in page and 'src="discrepancy.png"' in page


def test_tiny_study_flags_exact_cells_replaces_its_own_folder_and_keeps_texts_inside_the_figures(tmp_path, monkeypatch):
    # shifted_sh2_1 = 1 + Y_21 is integrated exactly by every orbit: RMSE at rounding level.
    config = StudyConfig(
        name="tiny",
        k_min=1,
        k_max=3,
        repetitions=2,
        integrands=("shifted_sh2_1",),
        scheme_methods=("equal_area",),
        scheme_points=("random",),
        sphere_peers=(("classic", "random"),),
        hemisphere_peers=(),
        discrepancy_k_max=1,
        discrepancy_repetitions=1,
        chi2_samples=1000,
        density_samples=4800,
        warp_samples=1000,
    )
    out = tmp_path / "tiny"
    run_study(out, config=config, progress=False)
    _, summary = _read_csv(out / "summary.csv")
    by_sampler = {r["sampler"]: r for r in summary}
    assert by_sampler["symsphere_equal_area"]["status"] == "exact"
    assert by_sampler["symsphere_equal_area"]["efficiency"] == "inf"
    assert by_sampler["classic"]["status"] == "ok" and math.isfinite(float(by_sampler["classic"]["slope"]))
    _, rows = _read_csv(out / "convergence.csv")
    assert all(r["rounding_level"] == "true" for r in rows if r["sampler"] == "symsphere_equal_area")
    assert "∞ (exact)" in (out / "report.md").read_text(encoding="utf-8")

    # An earlier study's folder is replaced, here by the same study of exp (fitted slopes, not exact), whose
    # figures keep every text (the slope guides' labels) inside the figure: drawn before each save, each
    # text's extent is checked against the figure's box (this was tests/test_ux.py's own tiny study).
    from matplotlib.figure import Figure

    outside = []
    savefig = Figure.savefig

    def checking_savefig(self, *args, **kwargs):
        self.canvas.draw()
        box = self.bbox
        for axes in self.axes:
            for text in axes.texts:
                extent = text.get_window_extent()
                if extent.x1 > box.x1 + 1 or extent.x0 < box.x0 - 1 or extent.y1 > box.y1 + 1 or extent.y0 < box.y0 - 1:
                    outside.append(text.get_text())
        return savefig(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", checking_savefig)
    config = config.replace(integrands=("exp",))
    run_study(out, config=config, progress=False)
    assert outside == []
    assert sorted(p.name for p in out.iterdir()) == sorted(study_files(config))  # none of the first study's left
    _, summary = _read_csv(out / "summary.csv")
    assert {r["integrand"] for r in summary} == {"exp"} and all(r["status"] == "ok" for r in summary)

    (out / "notes.txt").write_text("mine")
    with pytest.raises(FileExistsError, match="notes.txt"):
        run_study(out, config=config, progress=False)
    assert (out / "notes.txt").read_text() == "mine"


@pytest.mark.slow
def test_tiny_study_with_interlaced_points_and_lebedev(tmp_path):
    config = StudyConfig(
        name="tiny-qmc",
        k_min=1,
        k_max=3,
        repetitions=2,
        integrands=("exp",),
        scheme_methods=("equal_area",),
        scheme_points=("sobol", "sobol_interlaced2"),
        sphere_peers=(("classic", "random"), ("lebedev", "random"), ("lebedev_rotated", "random")),
        hemisphere_peers=(),
        discrepancy_k_max=2,
        discrepancy_repetitions=1,
        chi2_samples=1000,
        density_samples=4800,
        warp_samples=1000,
    )
    out = tmp_path / "tiny-qmc"
    run_study(out, config=config, progress=False)
    _, rows = _read_csv(out / "convergence.csv")
    lebedev = [r for r in rows if r["sampler"] == "lebedev"]
    assert [int(r["n"]) for r in lebedev] == [86, 170, 350]
    assert all(float(r["mean_error_se"]) == 0 for r in lebedev)  # deterministic: every repetition agrees
    assert {r["points"] for r in rows if r["sampler"] == "symsphere_equal_area"} == {"sobol", "sobol_interlaced2"}
    _, discrepancy = _read_csv(out / "discrepancy.csv")
    rule = [r for r in discrepancy if r["sampler"] == "lebedev"]
    assert [int(r["n"]) for r in rule] == [86, 170]
    assert all(float(r["weighted_discrepancy_rms"]) != float(r["discrepancy_rms"]) for r in rule)  # rule weights
    text = (out / "report.md").read_text(encoding="utf-8")
    assert "The most accurate randomized method" in text and "Lebedev (deterministic" in text
    assert "What is compiled" in text
    assert not (out / "density_lebedev.png").exists()


def test_report_html_converts_the_report_markdown():
    # The conversion is Python-Markdown's; this checks the features report.md uses, and the page around it.
    text = (
        "# Title\n\n## A & `x<y`\n\n- item **bold**\n\n![plot](a.png)\n\ntext *em* [link](b.html)\n\n"
        "| a | b |\n|---|---:|\n| c\\|d | 2 |\n"
    )
    page = report_html(text, title="t <1>")
    assert page.startswith("<!DOCTYPE html>") and page.rstrip().endswith("</html>")
    assert "<title>t &lt;1&gt;</title>" in page
    assert "<h2>A &amp; <code>x&lt;y</code></h2>" in page
    assert "<li>item <strong>bold</strong></li>" in page
    assert '<img alt="plot" src="a.png">' in page
    assert "<em>em</em>" in page and '<a href="b.html">link</a>' in page
    assert "<table>" in page and '<td style="text-align: right;">2</td>' in page


@pytest.mark.parametrize(
    "repetitions, words",
    [("1000000000", "--repetitions must be at most 1048576"), (str(2**70), "--repetitions must be at most 1048576"),
     ("100000", "is estimated to take at least")],
)  # fmt: skip
def test_absurd_repetitions_are_refused_before_any_work(tmp_path, repetitions, words):
    parser = argparse.ArgumentParser(prog="symsphere")
    add_study_parser(parser.add_subparsers(dest="verb"))
    from symsphere.apps.study import run_study_command

    args = parser.parse_args(["study", "--repetitions", repetitions, "--out", str(tmp_path / "r")])
    with pytest.raises(ValueError, match=words):
        run_study_command(args)
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ValueError, match=r"'repetitions' must be in \[2, 1048576\]"):
        CONFIGS["small"].replace(repetitions=2**70)
