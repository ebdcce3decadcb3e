"""The study's report: ``report.md``, computed from the measurements, and ``report.html`` from it.

Every sentence of "What the measurements say" is computed from the results, never assumed.  The
HTML is the Markdown converted by the ``markdown`` package (Python-Markdown, with its ``tables`` and
``fenced_code`` extensions), in a small self-contained page.
"""

from __future__ import annotations

import html
import math
import os

import numba

from ... import __version__
from ...integrands import INTEGRANDS
from .._format import format_p
from .config import BASELINE, CONFIGS, FAMILY_SIGNIFICANCE, ROUNDING_LEVEL, StudyConfig, domains
from .figures import density_samplers, warp_maps
from .findings import best_randomized, comparison_rows, find_row, findings, lebedev_text, short_number
from .results import CHI2_COLUMNS, CONVERGENCE_COLUMNS, DISCREPANCY_COLUMNS, SUMMARY_COLUMNS, Results, Row
from .samplers import Sampler, all_samplers, samplers

__all__ = ["report_html", "report_markdown"]


def _slope_text(row: Row) -> str:
    if row["status"] == "exact":
        return "exact"
    if math.isnan(row["slope"]):
        return "–"
    return f"{row['slope']:.2f} ± {row['slope_se']:.2f}"


def _efficiency_text(row: Row) -> str:
    if row["status"] == "exact":
        return "∞ (exact)"
    if math.isinf(row["efficiency"]):
        return "∞ (rounding level)"
    return short_number(row["relative_efficiency"])


def report_markdown(results: Results) -> str:
    """The text of ``report.md`` for the measurements of a finished study.

    Parameters
    ----------
    results : Results
        Every stage run (convergence, discrepancy, chi-square, figures), ``stage_seconds`` filled in.

    Returns
    -------
    str
        Markdown: what was measured, the tables, the findings computed from them, the figures, the
        files and how to reproduce the run.
    """
    config = results.config
    by_label = {(s.name, s.points): s for s in all_samplers(config)}
    ks = config.ks
    lines = [
        "# symsphere study: the symmetric scheme and its peers, measured",
        "",
        f"symsphere {__version__}; configuration **{config.name}**; seed {results.seed}; "
        f"{os.cpu_count()} CPUs (numba threads: {numba.get_num_threads()}); run time "
        f"{results.stage_seconds.get('total', math.nan):.0f} s (convergence "
        f"{results.stage_seconds.get('convergence', math.nan):.0f} s, discrepancy "
        f"{results.stage_seconds.get('discrepancy', math.nan):.0f} s, χ² "
        f"{results.stage_seconds.get('chi2', math.nan):.0f} s, figures "
        f"{results.stage_seconds.get('figures', math.nan):.0f} s).",
        "",
        "## What is measured",
        "",
        f"- **RMSE** of the estimate over {config.repetitions} independent repetitions (fresh random points, "
        f"jitter, scrambling or rotation each time) for n = 48·2^k evaluations of f, k = {ks[0]}…{ks[-1]} "
        f"(n = {48 * 2 ** ks[0]} … {48 * 2 ** ks[-1]}). The scheme with stratified points needs a square number of "
        "base points; for odd k it uses the nearest such n (the tables give the n used).",
        "- **Slope**: least squares of log RMSE against log n over all sizes (± its standard error). "
        f"RMSEs at rounding level (≤ {ROUNDING_LEVEL:g}·max(1, |exact|)) are flagged and left out; a cell "
        "that is at rounding level at every n is *exact*.",
        "- **Efficiency** 1/(MSE × seconds) at the largest n, seconds = median wall time of one estimate "
        "(sampling and evaluation), relative to the baseline i.i.d. sampler (classic on the sphere, "
        "classic_hemisphere on the hemisphere): above 1 is better than the baseline. **What is compiled:** the "
        "scheme's directions come from symsphere's numba kernels, parallel over all threads; so do those of the "
        "peers marked *compiled* in the table of samplers (numba kernels of their maps, Fibonacci points and "
        "rotations, parallel alike, from the same base points: numpy's PCG64 stream or scipy's Sobol' engine, "
        "interlaced by a numba kernel); the other peers' come from vectorised numpy. f is the same numpy "
        "function for all, called on blocks of 4096 orbits by the scheme and once on all n directions by a peer.",
        "- **Estimators**: the scheme (`symsphere_<map>`) is `symsphere.integrate` (orbit mean weighted by "
        "1/pdf, so the paper's maps are unbiased), one call with `replicates=1` per repetition; a peer gives "
        "mean(f/pdf).",
        f"- **Spherical-cap L2 discrepancy** of each point set on the sphere (all N directions, orbits "
        f"included), exact by Stolarsky's invariance principle, D² = 1/3 − (1/(4N²)) Σ|x_i − x_j|, rms over "
        f"{config.discrepancy_repetitions} sets, N = 48·2^k up to {48 * 2**config.discrepancy_k_max}. For the "
        "paper's maps also with the estimator's weights 1/(N·4π·pdf) (the worst-case error of the weighted rule "
        "in H^{3/2}(S²) with kernel 1 − |x − y|/4).",
        f"- **χ²** (`symsphere.stats.chi2_test`) of each random sampler, {config.chi2_samples} independent "
        "directions (one per orbit for orbit samplers), against the uniform density and, for the non-uniform "
        f"samplers, against their own pdf; Šidák-corrected over the {len(results.chi2)} tests at family level "
        f"{FAMILY_SIGNIFICANCE}.",
        "",
        "## Integrands",
        "",
        "| integrand | domain | exact | smooth | O_h-invariant | orbit average exact | description |",
        "|---|---|---:|---|---|---|---|",
    ]
    for g in config.integrands:
        it = INTEGRANDS[g]
        description = it.description.replace("|", "\\|")  # a literal | inside a table cell
        lines.append(
            f"| `{g}` | {it.domain} | {it.exact!r} | {_yes(it.smooth)} | {_yes(it.invariant)} | "
            f"{_yes(it.orbit_exact)} | {description} |"
        )
    lines += ["", "## Samplers", "", "| sampler | points | domain | what |", "|---|---|---|---|"]
    for sampler in all_samplers(config):
        lines.append(f"| `{sampler.name}` | {sampler.points} | {sampler.domain} | {_sampler_note(sampler)} |")

    lines += ["", "## Headline: efficiency relative to the baseline, at the largest n", ""]
    for domain in domains(config):
        names = [g for g in config.integrands if INTEGRANDS[g].domain == domain]
        baseline = "/".join(BASELINE[domain])
        for title, cell in (
            (f"**{domain}** (1/(MSE·seconds) over that of `{baseline}`; above 1: better):", _efficiency_text),
            (f"**{domain}: convergence slopes** (log RMSE vs log n; ± standard error):", _slope_text),
        ):
            lines += [title, "", "| sampler | " + " | ".join(f"`{g}`" for g in names) + " |"]
            lines.append("|---|" + "---:|" * len(names))
            for sampler in samplers(config, domain):
                rows = [
                    find_row(results.summary, integrand=g, sampler=sampler.name, points=sampler.points) for g in names
                ]
                lines.append(f"| {sampler.label} | " + " | ".join(cell(row) for row in rows) + " |")
            lines.append("")

    comparisons, names = comparison_rows(results)
    if comparisons:
        lines += [
            "## Comparisons: MSE(B) / MSE(A) at the largest n",
            "",
            "Above 1: A is more accurate at the same n (for random points, B needs about this many times "
            "as many evaluations). ∞: A alone is at rounding level; 0: B alone is; –: both are. Blank: the "
            "comparison does not apply to that integrand's domain.",
            "",
            "| A | B | what | " + " | ".join(f"`{g}`" for g in names) + " |",
            "|---|---|---|" + "---:|" * len(names),
        ]
        for a, b, what, ratios in comparisons:
            cells = ["" if ratios[g] is None else short_number(ratios[g]) for g in names]
            lines.append(f"| {'/'.join(a)} | {'/'.join(b)} | {what} | " + " | ".join(cells) + " |")
        lines.append("")

    lines += ["## What the measurements say", ""]
    lines += [f"- {sentence}" for sentence in findings(results)]
    best = best_randomized(results)
    if best:
        lines.append(
            "- **The most accurate randomized method** (largest n; equal time: efficiency 1/(MSE·seconds)): "
            + "; ".join(best)
            + "."
        )
    lebedev = lebedev_text(results)
    if lebedev:
        lines.append(
            "- **Lebedev (deterministic, exact to degree 131 at 5810 points) against the best randomized "
            "method at the same budget** (absolute errors): " + "; ".join(lebedev) + "."
        )
    lines += ["", "## Convergence", ""]
    for g in config.integrands:
        it = INTEGRANDS[g]
        lines += [
            f"### `{g}` ({it.domain}, exact {it.exact!r})",
            "",
            f"![convergence of {g}](convergence_{g}.png)",
            "",
            "| sampler | points | n max | relative RMSE | mean error | slope | seconds | efficiency | relative "
            "| status |",
            "|---|---|---:|---:|---:|---:|---:|---:|---:|---|",
        ]
        for row in results.summary:
            if row["integrand"] != g:
                continue
            last = find_row(
                results.convergence, integrand=g, sampler=row["sampler"], points=row["points"], n=row["n_max"]
            )
            lines.append(
                f"| {row['sampler']} | {row['points']} | {row['n_max']} | {short_number(row['relative_rmse_at_n_max'])} | "
                f"{short_number(last['mean_error'])} ± {short_number(last['mean_error_se'], 2)} | {_slope_text(row)} | "
                f"{short_number(row['median_seconds_at_n_max'])} | {short_number(row['efficiency'])} | {_efficiency_text(row)} | "
                f"{row['status']} |"
            )
        lines.append("")

    if results.discrepancy:
        baseline = BASELINE["sphere"][0]  # exactly 48 * 2**k points, unlike the stratified scheme
        ns = sorted(
            {r["n"] for r in results.discrepancy if r["sampler"] == baseline} or {r["n"] for r in results.discrepancy}
        )
        fits = {(f["sampler"], f["points"]): f for f in results.discrepancy_fits}
        lines += [
            "## Spherical-cap L2 discrepancy",
            "",
            "![discrepancy](discrepancy.png)",
            "",
            "rms of D over the sets; i.i.d. uniform points have E D² = 1/(3N). Rows *weights 1/pdf*: the "
            "paper's maps with the estimator's weights; *the rule's weights*: a Lebedev rule with its own "
            "weights, at its largest size within N (the columns give the budget N).",
            "",
            "| point set | " + " | ".join(f"N = {n}" for n in ns) + " | slope |",
            "|---|" + "---:|" * (len(ns) + 1),
            "| i.i.d. expectation √(1/(3N)) | "
            + " | ".join(short_number(math.sqrt(1 / (3 * n))) for n in ns)
            + " | -0.50 |",
        ]
        for (name, points), f in fits.items():
            rows = [r for r in results.discrepancy if r["sampler"] == name and r["points"] == points]
            cells = [short_number(r["discrepancy_rms"]) for r in rows]
            slope = f"{f['fit'].slope:.2f}" if f["fit"] is not None else "–"
            lines.append(f"| {name}/{points} | " + " | ".join(cells) + f" | {slope} |")
            if not by_label[(name, points)].uniform or by_label[(name, points)].is_rule:
                cells = [short_number(r["weighted_discrepancy_rms"]) for r in rows]
                slope = f"{f['weighted_fit'].slope:.2f}" if f["weighted_fit"] is not None else "–"
                weights = "the rule's weights" if by_label[(name, points)].is_rule else "weights 1/pdf"
                lines.append(f"| {name}/{points}, {weights} | " + " | ".join(cells) + f" | {slope} |")
        lines.append("")

    if results.chi2:
        lines += [
            "## χ² tests",
            "",
            f"Šidák threshold {results.chi2[0]['threshold']:.3g} per test ({len(results.chi2)} tests, family "
            f"level {FAMILY_SIGNIFICANCE}). Stratified and QMC point sets are not tested: their points are not "
            "independent. Nor is fibonacci_rotated (one rotation per set).",
            "",
            "| sampler | domain | reference | samples | χ² | dof | p-value | result |",
            "|---|---|---|---:|---:|---:|---:|---|",
        ]
        for row in results.chi2:
            lines.append(
                f"| {row['sampler']} | {row['domain']} | {row['reference']} | {row['n_samples']} | "
                f"{short_number(row['statistic'], 6)} | {row['dof']} | {format_p(row['p_value'])} | "
                f"{'pass' if row['passed'] else '**FAIL**'} |"
            )
        lines.append("")

    lines += [
        "## Density maps",
        "",
        "Histograms of each sampler's directions (random points) in equal-area (φ, cos θ) bins, relative to "
        "the uniform density, in a Mollweide projection (log colour scale 1/4 … 4, white = 1).",
        "",
    ]
    for sampler in density_samplers(config):
        lines += [f"![density of {sampler.name}](density_{sampler.name}.png)", ""]
    lines += [
        "## Warp pictures",
        "",
        "In the manner of Nori's warptest: the grid lines of the unit square carried by the map, a point cloud, "
        "and a histogram of the map's points beside its pdf integrated over the same bins (both relative to "
        "uniform), in the equal-area coordinates (φ, cos θ) — T0 is the region under the curve "
        "cos θ = cos φ/√(1 + cos²φ).",
        "",
    ]
    for name in warp_maps(config):
        p_value = results.warp_chi2.get(name, math.nan)
        lines += [
            f"![warp of {name}](warp_{name}.png)",
            "",
            f"`{name}`: χ² of {config.warp_samples} points of the map against its own pdf, p = {format_p(p_value)}.",
            "",
        ]
    lines += [
        "## Files",
        "",
        "- `convergence.csv`: one row per (integrand, sampler, points, n): " + ", ".join(CONVERGENCE_COLUMNS) + ".",
        "- `summary.csv`: one row per (integrand, sampler, points): " + ", ".join(SUMMARY_COLUMNS) + ".",
        "- `discrepancy.csv`: one row per (sampler, points, N): " + ", ".join(DISCREPANCY_COLUMNS) + ".",
        "- `chi2.csv`: one row per test: " + ", ".join(CHI2_COLUMNS) + ".",
        "",
        f"Reproduce: {_reproduce(config, results.seed)}",
        "",
    ]
    return "\n".join(lines)


def _reproduce(config: StudyConfig, seed: int) -> str:
    base = CONFIGS.get(config.name.split(" ")[0])
    if base is not None:
        command = f"symsphere study --config {base.name} --seed {seed}"
        if config.repetitions != base.repetitions:
            command += f" --repetitions {config.repetitions}"
        if config.k_max != base.k_max:
            command += f" --k-max {config.k_max}"
        if config == base.replace(name=config.name, repetitions=config.repetitions, k_max=config.k_max):
            return f"`{command}`."
    return "a custom configuration: `symsphere.apps.study.run_study(config=StudyConfig(...))` with the values above."


def _yes(flag: bool) -> str:
    return "yes" if flag else "no"


def _sampler_note(sampler: Sampler) -> str:
    if sampler.is_scheme:
        note = f"the scheme: `{sampler.method}` map onto T0, orbits of {sampler.orbit_size}, `integrate()`"
        if not sampler.uniform:
            note += " (the paper's map as printed, weighted by 1/pdf)"
        return note
    peer = sampler.peer
    assert peer is not None  # not the scheme
    note = peer.reference.split(";")[0] + ("; *compiled*" if sampler.is_compiled else "; numpy")
    if peer.is_random and peer.orbit_size is None:  # one random choice for all rows: the rotation
        note += " (a new random rotation per repetition)"
    return note


def report_html(text: str, title: str = "report") -> str:
    r"""A self-contained HTML page of the Markdown *text* (the study's ``report.md``).

    The conversion is Python-Markdown's, with the ``tables`` and ``fenced_code`` extensions.

    Parameters
    ----------
    text : str
        Markdown.
    title : str, optional
        The page's ``<title>`` (escaped).

    Returns
    -------
    str
        ``<!DOCTYPE html>`` ... ``</html>``, with a small inline style sheet.

    Examples
    --------
    >>> from symsphere.apps.study.report import report_html
    >>> page = report_html("# Title\n\n| a | b |\n|---|---:|\n| 1 | **2** |\n", title="t")
    >>> "<h1>Title</h1>" in page and '<td style="text-align: right;"><strong>2</strong></td>' in page
    True
    """
    import markdown  # function-level: only a finished study needs it (~50 ms to import)

    body: str = markdown.markdown(text, extensions=["tables", "fenced_code"], output_format="html")
    style = (
        "body{font-family:sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;line-height:1.4}"
        "table{border-collapse:collapse;margin:1em 0;font-size:0.85em}"
        "th,td{border:1px solid #ccc;padding:0.2em 0.5em}th{background:#f0f0f0}"
        "img{max-width:100%}code{background:#f4f4f4;padding:0 0.2em}"
    )
    return (
        '<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        f"<title>{html.escape(title)}</title>\n<style>{style}</style>\n</head>\n<body>\n"
        + body
        + "\n</body>\n</html>\n"
    )
