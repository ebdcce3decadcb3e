"""The convergence study: its statistics, the cap discrepancy, its configuration and an end-to-end run."""

import argparse
import csv
import math

import numpy as np
import pytest

from symsphere.integrands import INTEGRANDS
from symsphere.study import (
    CONFIGS,
    StudyConfig,
    _all_samplers,
    _chi2_tests,
    _domains,
    _samplers,
    add_study_parser,
    cap_discrepancy,
    cap_discrepancy_squared,
    fit_slope,
    markdown_to_html,
    rmse,
    run_study,
    study_files,
)


def _unit(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _rotation(angle_xyz):
    """A rotation matrix from three angles (independent of symsphere and scipy)."""
    a, b, c = angle_xyz
    rx = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
    rz = np.array([[math.cos(c), -math.sin(c), 0], [math.sin(c), math.cos(c), 0], [0, 0, 1]])
    return rz @ ry @ rx


# --- cap discrepancy -----------------------------------------------------------------


def _brute_force_cap_discrepancy_squared(points, weights=None, n_z=200, n_phi=400):
    """D² = ∫_{-1}^{1} ∫_{S²} (Σ w_i 1[x_i·c ≥ t] − (1 − t)/2)² dσ(c) dt, straight from the definition.

    For a fixed cap centre c the integrand is piecewise quadratic in t (the count changes at
    t = x_i·c), so the t-integral is exact: with g(t) = W − 1/2 + t/2 on an interval where the
    weight inside is W, ∫ g² dt = (2/3)(g(b)³ − g(a)³).  The centres c are integrated by
    Gauss–Legendre in z times the midpoint rule in φ; the integrand is continuous in c with kinks,
    so the rule converges like h².
    """
    x = _unit(points)
    n = len(x)
    w = np.full(n, 1.0 / n) if weights is None else np.asarray(weights, dtype=np.float64)
    z, gauss = np.polynomial.legendre.leggauss(n_z)
    phi = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    zz, pp = np.meshgrid(z, phi, indexing="ij")
    r = np.sqrt(1 - zz**2)
    centres = np.stack([r * np.cos(pp), r * np.sin(pp), zz], axis=-1).reshape(-1, 3)
    quadrature = (gauss[:, None] * np.full(n_phi, 2 * np.pi / n_phi)[None, :]).reshape(-1) / (4 * np.pi)
    total = 0.0
    for start in range(0, len(centres), 20000):
        c = centres[start : start + 20000]
        s = c @ x.T
        order = np.argsort(s, axis=1)
        s_sorted = np.take_along_axis(s, order, axis=1)
        w_sorted = w[order]
        # tail[:, k]: weight of the points with sorted index >= k, i.e. inside the cap for t in (b_k, b_k+1)
        tail = np.concatenate([np.cumsum(w_sorted[:, ::-1], axis=1)[:, ::-1], np.zeros((len(c), 1))], axis=1)
        edges = np.concatenate([-np.ones((len(c), 1)), np.clip(s_sorted, -1, 1), np.ones((len(c), 1))], axis=1)
        low = tail - 0.5 + edges[:, :-1] / 2
        high = tail - 0.5 + edges[:, 1:] / 2
        total += quadrature[start : start + 20000] @ ((2.0 / 3.0) * (high**3 - low**3)).sum(axis=1)
    return total


def test_stolarsky_matches_the_definition_for_the_octahedron():
    octahedron = np.vstack([np.eye(3), -np.eye(3)]) @ _rotation((0.3, 0.7, 1.1)).T
    exact = 1 / 3 - (24 * math.sqrt(2) + 12) / (4 * 36)  # 4 neighbours at sqrt 2 and one at 2, per point
    assert cap_discrepancy_squared(octahedron) == pytest.approx(exact, rel=1e-13)
    # Measured: the quadrature agrees to ~1e-6 relative; the tolerance leaves room.
    assert _brute_force_cap_discrepancy_squared(octahedron) == pytest.approx(exact, rel=2e-5)


@pytest.mark.parametrize("weighted", [False, True])
def test_stolarsky_matches_the_definition_for_random_points(weighted):
    rng = np.random.default_rng(20)
    x = _unit(rng.standard_normal((20, 3)))
    w = rng.uniform(0.5, 1.5, 20) / 20 if weighted else None  # weights need not sum to 1
    brute = _brute_force_cap_discrepancy_squared(x, w)
    assert cap_discrepancy_squared(x, w) == pytest.approx(brute, rel=2e-5)  # measured: 2e-7


def test_discrepancy_is_rotation_invariant_and_agrees_with_dense_distances():
    rng = np.random.default_rng(3)
    x = _unit(rng.standard_normal((301, 3)))  # odd N: the paired rows of the kernel meet in the middle
    w = rng.random(301)
    dense = np.linalg.norm(x[:, None, :] - x[None, :, :], axis=-1)
    expected = w.sum() ** 2 - 0.25 * (w @ dense @ w) - 4 / 3 * w.sum() + 2 / 3
    assert cap_discrepancy_squared(x, w) == pytest.approx(expected, rel=1e-12)
    rotated = x @ _rotation((1.0, -0.4, 2.2)).T
    assert cap_discrepancy_squared(rotated, w) == pytest.approx(expected, rel=1e-10)
    assert cap_discrepancy(x) == pytest.approx(math.sqrt(cap_discrepancy_squared(x)))


def test_expected_discrepancy_of_iid_uniform_points_is_one_over_3n():
    # E|x - y| = 4/3 for independent uniform x, y on S², and the N diagonal terms vanish, so
    # E D² = 1/3 - (1/(4N²)) N(N - 1) 4/3 = 1/(3N).
    rng = np.random.default_rng(11)
    n, sets = 50, 400
    values = np.array([cap_discrepancy_squared(_unit(rng.standard_normal((n, 3)))) for _ in range(sets)])
    standard_error = values.std(ddof=1) / math.sqrt(sets)
    assert abs(values.mean() - 1 / (3 * n)) < 4 * standard_error


def test_expected_weighted_discrepancy_of_importance_samples():
    # x_i i.i.d. with density p = (1 + z/2)/(4 pi), weights w_i = 1/(N 4 pi p(x_i)): E sum w = 1,
    # E sum_{i != j} w_i w_j |x_i - x_j| = (1 - 1/N) 4/3 and Var(sum w) = (E_sigma[1/(1 + z/2)] - 1)/N
    # = (ln 3 - 1)/N, so E D_w² = (ln 3 - 1)/N + 1/(3N).
    rng = np.random.default_rng(12)
    n, sets = 40, 400
    values = []
    for _ in range(sets):
        x = np.empty((0, 3))
        while len(x) < n:  # rejection sampling from the uniform density
            candidates = _unit(rng.standard_normal((2 * n, 3)))
            keep = rng.random(2 * n) < (1 + candidates[:, 2] / 2) / 1.5
            x = np.vstack([x, candidates[keep]])
        x = x[:n]
        values.append(cap_discrepancy_squared(x, 1 / (n * (1 + x[:, 2] / 2))))
    values = np.array(values)
    expected = (math.log(3) - 1) / n + 1 / (3 * n)
    assert abs(values.mean() - expected) < 4 * values.std(ddof=1) / math.sqrt(sets)


def test_discrepancy_rejects_bad_input():
    with pytest.raises(ValueError, match="points"):
        cap_discrepancy_squared(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="points"):
        cap_discrepancy_squared(np.zeros((4, 3)))
    with pytest.raises(ValueError, match="weights"):
        cap_discrepancy_squared(np.eye(3), [1.0, 2.0])


# --- RMSE and slope --------------------------------------------------------------------


def test_rmse_of_synthetic_errors():
    errors = np.array([0.3, -0.4, 0.0, 1.2])
    assert rmse(2.5 + errors, 2.5) == pytest.approx(math.sqrt(np.mean(errors**2)), rel=1e-15)
    table = np.array([[1.0, 3.0], [2.0, 2.0]])
    np.testing.assert_allclose(rmse(table, 2.0), [1.0, 0.0])


def test_fit_slope_recovers_a_known_slope():
    n = 48 * 2 ** np.arange(2, 15)
    fit = fit_slope(n, 3.0 * n**-0.73)
    assert fit.slope == pytest.approx(-0.73, abs=1e-12)
    assert fit.intercept == pytest.approx(math.log(3.0), abs=1e-9)
    assert fit.standard_error < 1e-12 and fit.points == len(n)


def test_fit_slope_standard_error_is_calibrated():
    rng = np.random.default_rng(5)
    n = 48 * 2 ** np.arange(2, 15)
    z = []
    for _ in range(300):
        fit = fit_slope(n, n**-1.0 * np.exp(0.3 * rng.standard_normal(len(n))))
        z.append((fit.slope + 1.0) / fit.standard_error)
    z = np.array(z)
    # (slope - true) / se is Student t with 11 degrees of freedom: mean 0, variance 11/9.
    assert abs(z.mean()) < 4 * math.sqrt(11 / 9 / len(z))
    assert 0.8 < z.var() / (11 / 9) < 1.25


def test_fit_slope_floors_zeros_without_warnings():
    fit = fit_slope([10, 100, 1000], [1e-3, 0.0, 1e-5])  # RuntimeWarnings are errors in this suite
    assert math.isfinite(fit.slope)
    assert math.isnan(fit_slope([10, 100], [1.0, 0.1]).standard_error)
    with pytest.raises(ValueError, match="distinct"):
        fit_slope([10, 10, 10], [1.0, 2.0, 3.0])


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
    for sampler in _all_samplers(config):
        for k in config.ks:
            n = sampler.n_for(k)
            assert 0.8 < n / (48 * 2**k) < 1.25
            if sampler.is_scheme and sampler.points == "stratified":
                base = n // (48 if sampler.domain == "sphere" else 24)
                assert math.isqrt(base) ** 2 == base
            else:
                assert n == 48 * 2**k


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

    samplers = {domain: _samplers(config, domain) for domain in _domains(config)}
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
    best = [r for r in rows if r["integrand"] == "exp" and r["sampler"] == "symsphere_equal_area"
            and r["points"] == "sobol" and int(r["k"]) == config.k_max]
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
    assert len(chi2) == len(_chi2_tests(config))
    paper_own = [r for r in chi2 if r["sampler"].startswith("symsphere_paper") and r["reference"] == "own pdf"]
    assert paper_own and all(0 <= float(r["p_value"]) <= 1 for r in paper_own)

    report = (out / "report.md").read_text(encoding="utf-8")
    for sampler in _all_samplers(config):
        assert sampler.name in report and sampler.label in report
    for g in config.integrands:
        assert f"`{g}`" in report and repr(INTEGRANDS[g].exact) in report
    for name in study_files(config):
        if name.endswith(".png"):
            assert f"({name})" in report
            assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    page = (out / "report.html").read_text(encoding="utf-8")
    assert page.startswith("<!DOCTYPE html>") and "<table>" in page and 'src="discrepancy.png"' in page


def test_tiny_study_flags_exact_cells_and_replaces_its_own_folder(tmp_path):
    # shifted_sh2_1 = 1 + Y_21 is integrated exactly by every orbit: RMSE at rounding level.
    config = StudyConfig(
        name="tiny", k_min=1, k_max=3, repetitions=2, integrands=("shifted_sh2_1",),
        scheme_methods=("equal_area",), scheme_points=("random",), sphere_peers=(("classic", "random"),),
        hemisphere_peers=(), discrepancy_k_max=1, discrepancy_repetitions=1, chi2_samples=1000,
        density_samples=4800, warp_samples=1000,
    )
    out = tmp_path / "tiny"
    run_study(out, config=config, progress=False)
    run_study(out, config=config, progress=False)  # an earlier study's folder is replaced
    _, summary = _read_csv(out / "summary.csv")
    by_sampler = {r["sampler"]: r for r in summary}
    assert by_sampler["symsphere_equal_area"]["status"] == "exact"
    assert by_sampler["symsphere_equal_area"]["efficiency"] == "inf"
    assert by_sampler["classic"]["status"] == "ok" and math.isfinite(float(by_sampler["classic"]["slope"]))
    _, rows = _read_csv(out / "convergence.csv")
    assert all(r["rounding_level"] == "true" for r in rows if r["sampler"] == "symsphere_equal_area")
    assert "∞ (exact)" in (out / "report.md").read_text(encoding="utf-8")

    (out / "notes.txt").write_text("mine")
    with pytest.raises(FileExistsError, match="notes.txt"):
        run_study(out, config=config, progress=False)
    assert (out / "notes.txt").read_text() == "mine"


def test_markdown_to_html_escapes_and_converts():
    page = markdown_to_html("## A <b> & `x<y`\n\n- item **bold**\n\n![plot](a.png)\n\ntext *em* [link](b.html)\n")
    assert "<h2>A &lt;b&gt; &amp; <code>x&lt;y</code></h2>" in page
    assert "<li>item <strong>bold</strong></li>" in page
    assert '<img src="a.png" alt="plot">' in page
    assert "<em>em</em>" in page and '<a href="b.html">link</a>' in page
