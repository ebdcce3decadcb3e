"""Running the study: the convergence, discrepancy and chi-square stages, and the output folder.

:func:`run_study` runs the stages in turn, then writes the CSV tables, the figures
(:mod:`.figures`) and the report (:mod:`.report`) into a folder that appears only when complete
(:func:`symsphere.io.atomic_directory`).
"""

from __future__ import annotations

import csv
import math
import os
import time
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Literal, cast

import numpy as np

from ..._typing import FloatArray
from ..._validation import check_seed
from ...integrands import INTEGRANDS, Integrand
from ...io import atomic_directory
from ...peers import PEERS
from ...quality import LOG_FLOOR, SlopeFit, cap_discrepancy_squared, fit_slope, rmse
from ...warps import METHODS
from .config import BASELINE, FAMILY_SIGNIFICANCE, ROUNDING_LEVEL, WARP_MAPS, StudyConfig, domains, resolve_config
from .figures import density_samplers, warp_maps, write_figures
from .report import report_html, report_markdown
from .results import (
    CHI2_COLUMNS,
    CONVERGENCE_COLUMNS,
    DISCREPANCY_COLUMNS,
    SUMMARY_COLUMNS,
    Progress,
    Results,
    Row,
    key,
)
from .samplers import Sampler, samplers, weighted

__all__ = ["chi2_tests", "run_study", "study_files"]


def study_files(config: str | StudyConfig = "full") -> list[str]:
    """The names of the files :func:`run_study` writes for *config*, in a stable order.

    Examples
    --------
    >>> from symsphere.apps.study import study_files
    >>> study_files("small")[:3]
    ['report.md', 'report.html', 'convergence.csv']
    """
    config = resolve_config(config)
    files = ["report.md", "report.html", "convergence.csv", "summary.csv", "discrepancy.csv", "chi2.csv"]
    files += [f"convergence_{g}.png" for g in config.integrands]
    if "sphere" in domains(config):
        files.append("discrepancy.png")
    files += [f"density_{s.name}.png" for s in density_samplers(config)]
    files += [f"warp_{m}.png" for m in warp_maps(config)]
    return files


def _replaceable() -> set[str]:
    """Every name a study of any configuration can write: an earlier study's folder may be replaced."""
    names = {
        "report.md",
        "report.html",
        "convergence.csv",
        "summary.csv",
        "discrepancy.csv",
        "chi2.csv",
        "discrepancy.png",
    }
    names |= {f"convergence_{g}.png" for g in INTEGRANDS}
    names |= {f"density_symsphere_{m}.png" for m in METHODS} | {f"density_{p}.png" for p in PEERS}
    names |= {f"warp_{m}.png" for m in WARP_MAPS}
    return names


def run_study(
    out_dir: str | os.PathLike[str] = "study-report",
    *,
    config: str | StudyConfig = "full",
    seed: int = 0,
    progress: bool = True,
) -> Path:
    """Run the convergence study and write its folder (report, CSV tables, figures).

    Parameters
    ----------
    out_dir : str or os.PathLike
        The folder to write.  It is built next to its final place and renamed
        into it only when complete.  An existing folder is replaced only if it
        is empty or holds nothing but files an earlier study writes;
        otherwise ``FileExistsError`` is raised before any work.
    config : {'full', 'small', 'qmc'} or StudyConfig
        ``'full'`` is the documented study (about 13 minutes on 2 cores);
        ``'small'`` is the quick end-to-end run of CI (well under a minute);
        ``'qmc'`` compares interlaced Sobol' base points with Lebedev and the rotated
        Fibonacci set on the sphere (about 15 minutes on 2 cores).
    seed : int
        Non-negative; seeds every random choice (same seed, same numbers;
        the timings vary).
    progress : bool
        Show a progress bar (tqdm, on stderr, only if it is a terminal).

    Returns
    -------
    pathlib.Path
        The path of ``report.md`` in *out_dir*.

    Examples
    --------
    >>> from symsphere.apps.study import run_study
    >>> report = run_study("/tmp/study-small", config="small", progress=False)  # doctest: +SKIP
    """
    from tqdm.auto import tqdm  # function-level: ~60 ms, not needed to build the CLI's parser

    config = resolve_config(config)
    seed = check_seed(seed)
    results = Results(config, seed)
    cells = _convergence_cells(config)
    discrepancy_cells = _discrepancy_cells(config)
    tests = chi2_tests(config)
    files = study_files(config)
    figures = [f for f in files if f.endswith(".png")]
    total = len(cells) * len(config.ks) + len(discrepancy_cells) + len(tests) + len(figures)
    started = time.perf_counter()
    with atomic_directory(out_dir, replaceable=_replaceable()) as build_dir, warnings.catch_warnings():
        # The peers' Sobol' sizes 3 * 2**m are deliberate (see the module docstring).
        warnings.filterwarnings("ignore", message="The balance properties of Sobol")
        bar_format = "{l_bar}{bar}| {n:.0f}/{total_fmt} cells [{elapsed}<{remaining}{postfix}]"
        with tqdm(
            total=total, desc="study", disable=True if not progress else None, dynamic_ncols=True, bar_format=bar_format
        ) as bar:
            stages: tuple[tuple[str, Callable[[], object]], ...] = (
                ("convergence", lambda: _run_convergence(results, cells, bar)),
                ("discrepancy", lambda: _run_discrepancy(results, discrepancy_cells, bar)),
                ("chi2", lambda: _run_chi2(results, tests, bar)),
                ("figures", lambda: write_figures(results, build_dir, bar)),
            )
            for stage, work in stages:
                clock = time.perf_counter()
                work()
                results.stage_seconds[stage] = time.perf_counter() - clock
        _write_csv(build_dir / "convergence.csv", results.convergence, CONVERGENCE_COLUMNS)
        _write_csv(build_dir / "summary.csv", results.summary, SUMMARY_COLUMNS)
        _write_csv(build_dir / "discrepancy.csv", results.discrepancy, DISCREPANCY_COLUMNS)
        _write_csv(build_dir / "chi2.csv", results.chi2, CHI2_COLUMNS)
        results.stage_seconds["total"] = time.perf_counter() - started
        text = report_markdown(results)
        (build_dir / "report.md").write_text(text, encoding="utf-8")
        (build_dir / "report.html").write_text(
            report_html(text, title=f"symsphere study ({config.name})"), encoding="utf-8"
        )
        missing = [f for f in files if not (build_dir / f).exists()]
        if missing:  # pragma: no cover - a bug, not a user error
            raise RuntimeError(f"the study did not write {missing}")
    return Path(out_dir) / "report.md"


# --- convergence -----------------------------------------------------------------


def _convergence_cells(config: StudyConfig) -> list[tuple[Integrand, Sampler]]:
    cells = []
    for g in config.integrands:
        integrand = INTEGRANDS[g]
        for sampler in samplers(config, integrand.domain):
            cells.append((integrand, sampler))
    return cells


def _run_convergence(results: Results, cells: list[tuple[Integrand, Sampler]], bar: Progress) -> None:
    """RMSE and timings.  The samplers of one integrand are interleaved (for each n and repetition, one
    estimate of every sampler in turn), so that a change of the machine's load between cells biases
    no sampler's timing against another's."""
    config = results.config
    groups: dict[str, tuple[Integrand, list[Sampler]]] = {}
    for integrand, sampler in cells:
        groups.setdefault(integrand.name, (integrand, []))[1].append(sampler)
    step = 1.0 / config.repetitions
    for integrand, group in groups.values():
        bar.set_postfix_str(f"{integrand.name}: warm-up", refresh=False)
        for sampler in group:  # numba kernels, scipy engines: not timed
            sampler.estimate(integrand.f, sampler.n_for(config.k_min), results.seed_sequence(9, key(sampler.label)))
        rows: dict[Sampler, list[Row]] = {sampler: [] for sampler in group}
        for k in config.ks:
            estimates = {sampler: np.empty(config.repetitions) for sampler in group}
            seconds = {sampler: np.empty(config.repetitions) for sampler in group}
            for r in range(config.repetitions):
                bar.set_postfix_str(f"{integrand.name}: n = 48*2^{k}, repetition {r + 1}", refresh=False)
                for sampler in group:
                    rng = results.seed_sequence(0, key(sampler.label), key(integrand.name), k, r)
                    n = sampler.n_for(k)
                    clock = time.perf_counter()
                    estimates[sampler][r] = sampler.estimate(integrand.f, n, rng)
                    seconds[sampler][r] = time.perf_counter() - clock
                    bar.update(step)
            for sampler in group:
                rows[sampler].append(_convergence_row(integrand, sampler, k, estimates[sampler], seconds[sampler]))
        for sampler in group:
            results.convergence.extend(rows[sampler])
    _summarise(results)


def _convergence_row(integrand: Integrand, sampler: Sampler, k: int, estimates: FloatArray, seconds: FloatArray) -> Row:
    error = float(rmse(estimates, integrand.exact))
    repetitions = len(estimates)
    return {
        "integrand": integrand.name,
        "domain": integrand.domain,
        "sampler": sampler.name,
        "points": sampler.points,
        "k": k,
        "n": sampler.n_for(k),
        "repetitions": repetitions,
        "rmse": error,
        "relative_rmse": error / abs(integrand.exact) if integrand.exact != 0 else math.nan,
        "mean_error": float(np.mean(estimates - integrand.exact)),
        "mean_error_se": float(np.std(estimates, ddof=1) / math.sqrt(repetitions)),
        "mean_seconds": float(np.mean(seconds)),
        "median_seconds": float(np.median(seconds)),
        "rounding_level": bool(error <= ROUNDING_LEVEL * max(1.0, abs(integrand.exact))),
    }


def _summarise(results: Results) -> None:
    by_cell: dict[tuple[str, str, str], list[Row]] = {}
    for row in results.convergence:
        by_cell.setdefault((row["integrand"], row["sampler"], row["points"]), []).append(row)
    summary: list[Row] = []
    for (g, name, points), rows in by_cell.items():
        fit_rows = [r for r in rows if not r["rounding_level"]]
        if len(fit_rows) >= 3:
            fit = fit_slope([r["n"] for r in fit_rows], [r["rmse"] for r in fit_rows])
        else:
            fit = SlopeFit(math.nan, math.nan, math.nan, len(fit_rows))
        if not fit_rows:
            status = "exact"
        elif len(fit_rows) < len(rows):
            status = "partly at rounding level"
        else:
            status = "ok"
        last = rows[-1]
        mse = last["rmse"] ** 2
        if last["rounding_level"]:
            efficiency = math.inf
        else:
            efficiency = 1.0 / (max(mse, LOG_FLOOR) * last["median_seconds"])
        summary.append(
            {
                "integrand": g,
                "domain": last["domain"],
                "sampler": name,
                "points": points,
                "status": status,
                "slope": fit.slope,
                "slope_se": fit.standard_error,
                "fit_points": fit.points,
                "n_max": last["n"],
                "rmse_at_n_max": last["rmse"],
                "relative_rmse_at_n_max": last["relative_rmse"],
                "median_seconds_at_n_max": last["median_seconds"],
                "efficiency": efficiency,
            }
        )
    for row in summary:
        baseline = BASELINE[row["domain"]]
        reference = next(
            (r for r in summary if r["integrand"] == row["integrand"] and (r["sampler"], r["points"]) == baseline),
            None,
        )
        row["baseline"] = "/".join(baseline)
        if reference is None or not math.isfinite(reference["efficiency"]):
            row["relative_efficiency"] = math.nan
        else:
            row["relative_efficiency"] = row["efficiency"] / reference["efficiency"]
    results.summary = summary


# --- discrepancy -------------------------------------------------------------------


def _discrepancy_cells(config: StudyConfig) -> list[tuple[Sampler, int]]:
    if "sphere" not in domains(config):
        return []
    return [(s, k) for s in samplers(config, "sphere") for k in config.discrepancy_ks]


def _run_discrepancy(results: Results, cells: list[tuple[Sampler, int]], bar: Progress) -> None:
    config = results.config
    for sampler, k in cells:
        bar.set_postfix_str(f"discrepancy: {sampler.label}, N = {sampler.n_for(k)}", refresh=False)
        n = sampler.n_for(k)
        plain_list: list[float] = []
        weighted_list: list[float] = []
        for r in range(config.discrepancy_repetitions):
            x = sampler.sample(n, results.seed_sequence(1, key(sampler.label), k, r))
            plain_list.append(max(cap_discrepancy_squared(x), 0.0))
            if sampler.is_rule:  # the rule's own weights
                weighted_list.append(max(cap_discrepancy_squared(x, sampler.rule_weights(n)), 0.0))
            elif sampler.uniform:
                weighted_list.append(plain_list[-1])
            else:
                w = weighted(np.ones(n), n * 4 * math.pi * sampler.pdf(x))
                weighted_list.append(max(cap_discrepancy_squared(x, w), 0.0))
        plain, with_weights = np.array(plain_list), np.array(weighted_list)
        results.discrepancy.append(
            {
                "sampler": sampler.name,
                "points": sampler.points,
                "k": k,
                "n": n,
                "repetitions": config.discrepancy_repetitions,
                "discrepancy_rms": float(np.sqrt(plain.mean())),
                "discrepancy_min": float(np.sqrt(plain.min())),
                "discrepancy_max": float(np.sqrt(plain.max())),
                "weighted_discrepancy_rms": float(np.sqrt(with_weights.mean())),
                "random_expectation": math.sqrt(1.0 / (3.0 * n)),
            }
        )
        bar.update(1)
    fits: list[Row] = []
    groups: dict[tuple[str, str], list[Row]] = {}
    for row in results.discrepancy:
        groups.setdefault((row["sampler"], row["points"]), []).append(row)
    for (name, points), rows in groups.items():
        ns = [r["n"] for r in rows]
        fits.append(
            {
                "sampler": name,
                "points": points,
                "fit": fit_slope(ns, [r["discrepancy_rms"] for r in rows]) if len(rows) >= 2 else None,
                "weighted_fit": fit_slope(ns, [r["weighted_discrepancy_rms"] for r in rows])
                if len(rows) >= 2
                else None,
            }
        )
    results.discrepancy_fits = fits


# --- chi-square ----------------------------------------------------------------------


def chi2_tests(config: StudyConfig) -> list[tuple[Sampler, str]]:
    """The chi-square tests of *config*: (sampler, ``'uniform'`` or ``'own'``) for each random sampler.

    Samplers whose rows are never independent (``orbit_size`` None) are not tested; the non-uniform
    ones are tested against their own density too.
    """
    tests: list[tuple[Sampler, str]] = []
    for domain in domains(config):
        for sampler in samplers(config, domain):
            if sampler.points != "random" or sampler.orbit_size is None:
                continue
            tests.append((sampler, "uniform"))
            if not sampler.uniform:
                tests.append((sampler, "own"))
    return tests


def _run_chi2(results: Results, tests: list[tuple[Sampler, str]], bar: Progress) -> None:
    from ...stats import chi2_test, one_per_orbit, uniform_pdf  # function-level: scipy.stats takes ~1 s

    config = results.config
    samples: dict[Sampler, FloatArray] = {}
    for sampler, reference in tests:
        bar.set_postfix_str(f"chi2: {sampler.label} ({sampler.domain}) vs {reference}", refresh=False)
        if sampler not in samples:
            size = sampler.orbit_size
            assert size is not None  # chi2_tests leaves out the samplers whose rows are never independent
            d = sampler.sample(
                config.chi2_samples * size, results.seed_sequence(2, key(sampler.label), key(sampler.domain))
            )
            if size > 1:
                orbit = cast(Literal[48, 24], size)  # the scheme's orbits (a peer's rows are independent: 1)
                d = one_per_orbit(d, orbit, results.seed_sequence(3, key(sampler.label), key(sampler.domain)))
            samples[sampler] = d
        pdf = uniform_pdf(sampler.domain) if reference == "uniform" else sampler.pdf
        result = chi2_test(
            samples[sampler], pdf, sampler.domain, significance=FAMILY_SIGNIFICANCE, test_count=len(tests)
        )
        results.chi2.append(
            {
                "sampler": sampler.name,
                "points": sampler.points,
                "domain": sampler.domain,
                "reference": reference if reference == "uniform" else "own pdf",
                "n_samples": len(samples[sampler]),
                "statistic": result.statistic,
                "dof": result.dof,
                "p_value": result.p_value,
                "threshold": result.threshold,
                "passed": result.passed,
            }
        )
        bar.update(1)


# --- CSV ------------------------------------------------------------------------------


def _csv_value(value: object) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    return str(value)


def _write_csv(path: Path, rows: list[Row], columns: Sequence[str]) -> None:
    with open(path, "w", encoding="utf-8", newline="") as handle:
        writer = csv.writer(handle, lineterminator="\n")
        writer.writerow(columns)
        for row in rows:
            writer.writerow([_csv_value(row[c]) for c in columns])
