"""The study's report: ``report.md``, computed from the measurements, and ``report.html`` from it.

Every sentence of "What the measurements say" is computed from the results, never assumed.  The
HTML is the Markdown converted by the ``markdown`` package (Python-Markdown, with its ``tables`` and
``fenced_code`` extensions), in a small self-contained page.
"""

from __future__ import annotations

import html
import math
import os
from collections.abc import Iterable

import numba

from ... import __version__
from ..._typing import Domain
from ...integrands import INTEGRANDS
from ...symmetry import orbit_size
from .._format import format_p
from .config import BASELINE, CONFIGS, FAMILY_SIGNIFICANCE, ROUNDING_LEVEL, StudyConfig, domains
from .figures import density_samplers, warp_maps
from .results import CHI2_COLUMNS, CONVERGENCE_COLUMNS, DISCREPANCY_COLUMNS, SUMMARY_COLUMNS, Results, Row
from .samplers import Sampler, all_samplers, samplers

__all__ = ["report_html", "report_markdown"]

_Label = tuple[str, str]  # (sampler name, points)
_Comparison = tuple[_Label, _Label, str, dict[str, "float | None"]]


def _g(x: float | None, digits: int = 3) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    if isinstance(x, float) and math.isinf(x):
        return "∞"
    return f"{x:.{digits}g}"


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
    return _g(row["relative_efficiency"])


def _lookup(rows: list[Row], **match: object) -> Row | None:
    for row in rows:
        if all(row[k] == v for k, v in match.items()):
            return row
    return None


def _row(rows: list[Row], **match: object) -> Row:
    """The row of *rows* that matches (the caller knows there is one)."""
    row = _lookup(rows, **match)
    if row is None:  # pragma: no cover - a bug, not a user error
        raise LookupError(f"no row with {match}")
    return row


def _mse_ratio(results: Results, integrand: str, a: _Label, b: _Label) -> float | None:
    """MSE of b over MSE of a at the largest n (above 1: a is more accurate); None if a sampler is missing.

    inf if a alone is exact (rounding level), 0 if b alone is, NaN if both are.
    """
    ra = _lookup(results.summary, integrand=integrand, sampler=a[0], points=a[1])
    rb = _lookup(results.summary, integrand=integrand, sampler=b[0], points=b[1])
    if ra is None or rb is None:
        return None
    a_exact = ra["status"] == "exact" or ra["rmse_at_n_max"] == 0
    b_exact = rb["status"] == "exact" or rb["rmse_at_n_max"] == 0
    if a_exact and b_exact:
        return math.nan
    if a_exact:
        return math.inf
    if b_exact:
        return 0.0
    ratio: float = (rb["rmse_at_n_max"] / ra["rmse_at_n_max"]) ** 2
    return ratio


_COMPARISONS = (
    # (A, B, what it measures); A and B are (sampler, points)
    (("symsphere_equal_area", "random"), ("classic", "random"), "orbits of 48 vs i.i.d. (same uniform density)"),
    (("symsphere_equal_area", "random"), ("arvo", "random"), "closed form vs Arvo's map: same distribution, expect 1"),
    (("symsphere_equal_area", "random"), ("symsphere_paper1", "random"), "the paper's map 1: variance penalty"),
    (("symsphere_equal_area", "random"), ("symsphere_paper2", "random"), "the paper's map 2: variance penalty"),
    (("symsphere_equal_area", "stratified"), ("symsphere_equal_area", "random"), "stratified vs random base points"),
    (("symsphere_equal_area", "sobol"), ("symsphere_paper1", "sobol"), "QMC: paper map 1 vs equal_area"),
    (("symsphere_equal_area", "sobol"), ("symsphere_paper2", "sobol"), "QMC: paper map 2 vs equal_area"),
    (("symsphere_equal_area", "sobol"), ("classic", "sobol"), "QMC with orbits vs Sobol' on the classic map"),
    (("symsphere_equal_area", "sobol"), ("octahedral", "sobol"), "QMC with orbits vs Sobol' on the octahedral map"),
    (("symsphere_equal_area", "sobol"), ("fibonacci_rotated", "random"), "QMC with orbits vs rotated Fibonacci"),
    (
        ("symsphere_equal_area", "sobol_interlaced2"),
        ("symsphere_equal_area", "sobol"),
        "order-2 interlaced vs plain Sobol' base points",
    ),
    (
        ("symsphere_equal_area", "sobol_interlaced3"),
        ("symsphere_equal_area", "sobol"),
        "order-3 interlaced vs plain Sobol' base points",
    ),
    (
        ("symsphere_equal_area", "sobol_interlaced2"),
        ("octahedral", "sobol_interlaced2"),
        "order-2 points: orbits vs Clarberg's octahedral map",
    ),
    (
        ("symsphere_equal_area", "sobol_interlaced2"),
        ("fibonacci_rotated", "random"),
        "order-2 QMC with orbits vs rotated Fibonacci",
    ),
    (
        ("symsphere_equal_area", "sobol_interlaced2"),
        ("lebedev_rotated", "random"),
        "order-2 QMC with orbits vs rotated Lebedev (131)",
    ),
    (("symsphere_equal_area", "random"), ("classic_hemisphere", "random"), "hemisphere: orbits of 24 vs i.i.d."),
    (("symsphere_equal_area", "random"), ("cosine", "random"), "hemisphere: uniform orbits vs cosine-weighted i.i.d."),
    (("symsphere_equal_area", "sobol"), ("classic_hemisphere", "sobol"), "hemisphere QMC: orbits vs classic map"),
    (("symsphere_equal_area", "sobol"), ("cosine", "sobol"), "hemisphere QMC: orbits vs cosine-weighted Sobol'"),
)


def _comparison_rows(results: Results) -> tuple[list[_Comparison], list[str]]:
    config = results.config
    rows: list[_Comparison] = []
    for a, b, what in _COMPARISONS:
        ratios: dict[str, float | None] = {}
        for g in config.integrands:
            ratios[g] = _mse_ratio(results, g, a, b)
        if all(v is None for v in ratios.values()):
            continue
        rows.append((a, b, what, ratios))
    return rows, [g for g in config.integrands if INTEGRANDS[g]]


def _range_text(ratios: Iterable[float | None]) -> str:
    values = [v for v in ratios if v is not None and math.isfinite(v) and v > 0]
    if not values:
        return "–"
    low, high = min(values), max(values)
    geometric = math.exp(sum(math.log(v) for v in values) / len(values))
    if len(values) == 1:
        return f"{_g(low)}"
    return f"{_g(low)} to {_g(high)} (geometric mean {_g(geometric)})"


def _complete(ratios: dict[str, float | None]) -> dict[str, float] | None:
    """*ratios*, or None if a sampler is missing for one of them."""
    if any(v is None for v in ratios.values()):
        return None
    return {g: v for g, v in ratios.items() if v is not None}


def _findings(results: Results) -> list[str]:
    """Sentences computed from the measurements (never assumed)."""
    config = results.config
    by_label: dict[_Label, Sampler] = {(s.name, s.points): s for s in all_samplers(config)}
    out: list[str] = []
    sphere = [g for g in config.integrands if INTEGRANDS[g].domain == "sphere"]
    hemisphere = [g for g in config.integrands if INTEGRANDS[g].domain == "hemisphere"]

    def ratios(a: _Label, b: _Label, names: list[str]) -> dict[str, float] | None:
        return _complete({g: _mse_ratio(results, g, a, b) for g in names})

    ea, ea_sobol = ("symsphere_equal_area", "random"), ("symsphere_equal_area", "sobol")
    domain: Domain
    for domain, names in (("sphere", sphere), ("hemisphere", hemisphere)):
        baseline = BASELINE[domain]
        count = orbit_size(domain)
        r = ratios(ea, baseline, names)
        if not names or r is None:
            continue
        exact = [g for g, v in r.items() if math.isinf(v)]
        finite = {g: v for g, v in r.items() if math.isfinite(v)}
        sentence = (
            f"**Orbits of {count}, random points ({domain}).** At the largest n, the MSE of "
            f"{'/'.join(baseline)} (i.i.d.) over that of equal_area with orbits is "
            + (
                f"{_range_text(finite.values())} ({', '.join(f'{g}: {_g(v)}' for g, v in finite.items())})"
                if finite
                else "infinite"
            )
        )
        if exact:
            sentence += f"; the scheme is exact (rounding level) on {', '.join(exact)}"
        invariant = [g for g in finite if INTEGRANDS[g].invariant]
        if invariant:
            sentence += (
                f". On the O_h-invariant {', '.join(invariant)} the orbit average is f itself, so the {count} "
                f"evaluations of an orbit are worth one independent sample: about 1/{count} = {1 / count:.3f} "
                "is expected there"
            )
        out.append(sentence + ".")
    for method in ("paper1", "paper2"):
        for points in ("random", "sobol"):
            names = sphere + hemisphere
            r = ratios(("symsphere_equal_area", points), (f"symsphere_{method}", points), names)
            if names and r is not None:
                finite_values = [v for v in r.values() if math.isfinite(v)]
                if not finite_values:
                    continue
                out.append(
                    f"**The paper's {method} map, {points} points.** Weighted by 1/pdf (unbiased), its MSE is "
                    f"{_range_text(finite_values)} times that of equal_area at the largest n "
                    f"({', '.join(f'{g}: {_g(v)}' for g, v in r.items())})."
                )
    for peer in ("classic", "octahedral"):
        r = ratios(ea_sobol, (peer, "sobol"), sphere)
        if sphere and r is not None:
            finite_values = [v for v in r.values() if math.isfinite(v)]
            if finite_values:
                out.append(
                    f"**QMC: orbits of scrambled Sobol' points vs Sobol' on the {peer} map.** MSE ratio "
                    f"({peer}/equal_area) at the largest n: {_range_text(finite_values)} "
                    f"({', '.join(f'{g}: {_g(v)}' for g, v in r.items())})."
                )
    slopes: list[str] = []
    for name, points in (
        ea,
        ea_sobol,
        ("classic", "random"),
        ("classic", "sobol"),
        ("octahedral", "sobol"),
        ("fibonacci_rotated", "random"),
    ):
        rows = [
            row
            for row in results.summary
            if row["sampler"] == name
            and row["points"] == points
            and row["integrand"] in sphere
            and row["status"] != "exact"
        ]
        if rows:
            slopes.append(f"{name}/{points}: " + ", ".join(f"{row['integrand']} {row['slope']:.2f}" for row in rows))
    if slopes:
        out.append(
            "**Convergence slopes** (log RMSE vs log n on the sphere; cells at rounding level left out): "
            + "; ".join(slopes)
            + "."
        )
    fits = {(f["sampler"], f["points"]): f for f in results.discrepancy_fits}
    parts: list[str] = []
    for key in (
        ea,
        ea_sobol,
        ("symsphere_paper1", "random"),
        ("symsphere_paper1", "sobol"),
        ("symsphere_paper2", "sobol"),
        ("classic", "sobol"),
        ("octahedral", "sobol"),
        ("fibonacci_rotated", "random"),
        ("classic", "random"),
    ):
        f = fits.get(key)
        if f is None or f["fit"] is None:
            continue
        text = f"{key[0]}/{key[1]} {f['fit'].slope:.2f}"
        if not by_label[key].uniform:
            text += f" (with weights 1/pdf: {f['weighted_fit'].slope:.2f})"
        parts.append(text)
    if parts:
        out.append(
            "**Cap discrepancy** (slope of D against N; i.i.d. points give -0.5, the best possible order is "
            "-0.75): " + "; ".join(parts) + "."
        )
    failed_uniform = sorted(
        {f"{r['sampler']} ({r['domain']})" for r in results.chi2 if r["reference"] == "uniform" and not r["passed"]}
    )
    passed_own = sorted(
        {f"{r['sampler']} ({r['domain']})" for r in results.chi2 if r["reference"] == "own pdf" and r["passed"]}
    )
    failed_own = sorted(
        {f"{r['sampler']} ({r['domain']})" for r in results.chi2 if r["reference"] == "own pdf" and not r["passed"]}
    )
    if results.chi2:
        sentence = "**χ².** Fail against the uniform density: " + (", ".join(failed_uniform) or "none")
        sentence += "; pass against their own pdf: " + (", ".join(passed_own) or "none")
        if failed_own:
            sentence += "; fail against their own pdf: " + ", ".join(failed_own)
        out.append(sentence + ".")
    return out


def _best_randomized(results: Results) -> list[str]:
    """Per integrand: the most accurate randomized sampler at the largest n, and the most efficient one.

    Randomized: every sampler whose estimate is random (the deterministic Fibonacci and Lebedev rules
    excepted).  Ties at rounding level are all named.
    """
    config = results.config
    labels = {(s.name, s.points): s for s in all_samplers(config)}
    out = []
    for g in config.integrands:
        rows = [r for r in results.summary if r["integrand"] == g and labels[(r["sampler"], r["points"])].is_random]
        if len(rows) < 2:
            continue

        def label(r: Row) -> str:
            return f"{r['sampler']}/{r['points']}"

        exact = [r for r in rows if r["status"] == "exact" or not math.isfinite(r["efficiency"])]
        rest = [r for r in rows if r not in exact]
        text = f"`{g}`: " + (
            f"at rounding level with {', '.join(label(r) for r in exact)}; among the others, " if exact else ""
        )
        if len(rest) < 2:
            out.append(text.removesuffix("; among the others, "))
            continue
        by_mse = sorted(rest, key=lambda r: r["rmse_at_n_max"])
        by_time = sorted(rest, key=lambda r: -r["efficiency"])
        mse_ratio = (by_mse[1]["rmse_at_n_max"] / by_mse[0]["rmse_at_n_max"]) ** 2
        time_ratio = by_time[0]["efficiency"] / by_time[1]["efficiency"]
        out.append(
            text + f"at equal n {label(by_mse[0])} (MSE {_g(mse_ratio)}x below {label(by_mse[1])}); "
            f"at equal time {label(by_time[0])} ({_g(time_ratio)}x the efficiency of {label(by_time[1])})"
        )
    return out


def _lebedev_text(results: Results) -> list[str]:
    """Per integrand: the deterministic Lebedev rule's error at its largest size against the best randomized
    sampler at the same budget, and the n that sampler needs to match it."""
    config = results.config
    labels = {(s.name, s.points): s for s in all_samplers(config)}
    rule = next((s for s in all_samplers(config) if s.name == "lebedev"), None)
    if rule is None:
        return []
    k = next((k for k in config.ks if rule.n_for(k) == rule.n_for(config.ks[-1])), config.ks[-1])
    out = []
    for g in config.integrands:
        lebedev = _lookup(results.convergence, integrand=g, sampler="lebedev", points=rule.points, k=k)
        if lebedev is None:
            continue
        rows = [
            r
            for r in results.convergence
            if r["integrand"] == g and r["k"] == k and labels[(r["sampler"], r["points"])].is_random
        ]
        if not rows:
            continue
        best = min(rows, key=lambda r: r["rmse"])
        error = abs(lebedev["mean_error"])
        if lebedev["rounding_level"]:
            out.append(f"`{g}`: Lebedev at rounding level (n = {lebedev['n']})")
            continue
        series = [
            r
            for r in results.convergence
            if r["integrand"] == g and r["sampler"] == best["sampler"] and r["points"] == best["points"]
        ]
        match = next((r["n"] for r in series if r["rmse"] <= error), None)
        needs = f"reaches it at n = {match}" if match is not None else f"does not reach it by n = {series[-1]['n']}"
        out.append(
            f"`{g}`: Lebedev {_g(error)} (n = {lebedev['n']}); best randomized at n = {best['n']}: "
            f"{best['sampler']}/{best['points']} {_g(best['rmse'])}, which {needs}"
        )
    return out


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
        lines += [
            f"**{domain}** (1/(MSE·seconds) over that of `{baseline}`; above 1: better):",
            "",
            "| sampler | " + " | ".join(f"`{g}`" for g in names) + " |",
            "|---|" + "---:|" * len(names),
        ]
        for sampler in samplers(config, domain):
            cells = [
                _efficiency_text(_row(results.summary, integrand=g, sampler=sampler.name, points=sampler.points))
                for g in names
            ]
            lines.append(f"| {sampler.label} | " + " | ".join(cells) + " |")
        lines += [
            "",
            f"**{domain}: convergence slopes** (log RMSE vs log n; ± standard error):",
            "",
            "| sampler | " + " | ".join(f"`{g}`" for g in names) + " |",
            "|---|" + "---:|" * len(names),
        ]
        for sampler in samplers(config, domain):
            cells = [
                _slope_text(_row(results.summary, integrand=g, sampler=sampler.name, points=sampler.points))
                for g in names
            ]
            lines.append(f"| {sampler.label} | " + " | ".join(cells) + " |")
        lines.append("")

    comparisons, names = _comparison_rows(results)
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
            cells = ["" if ratios[g] is None else _g(ratios[g]) for g in names]
            lines.append(f"| {'/'.join(a)} | {'/'.join(b)} | {what} | " + " | ".join(cells) + " |")
        lines.append("")

    lines += ["## What the measurements say", ""]
    lines += [f"- {sentence}" for sentence in _findings(results)]
    best = _best_randomized(results)
    if best:
        lines.append(
            "- **The most accurate randomized method** (largest n; equal time: efficiency 1/(MSE·seconds)): "
            + "; ".join(best)
            + "."
        )
    lebedev = _lebedev_text(results)
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
            last = _row(results.convergence, integrand=g, sampler=row["sampler"], points=row["points"], n=row["n_max"])
            lines.append(
                f"| {row['sampler']} | {row['points']} | {row['n_max']} | {_g(row['relative_rmse_at_n_max'])} | "
                f"{_g(last['mean_error'])} ± {_g(last['mean_error_se'], 2)} | {_slope_text(row)} | "
                f"{_g(row['median_seconds_at_n_max'])} | {_g(row['efficiency'])} | {_efficiency_text(row)} | "
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
            "| i.i.d. expectation √(1/(3N)) | " + " | ".join(_g(math.sqrt(1 / (3 * n))) for n in ns) + " | -0.50 |",
        ]
        for (name, points), f in fits.items():
            rows = [r for r in results.discrepancy if r["sampler"] == name and r["points"] == points]
            cells = [_g(r["discrepancy_rms"]) for r in rows]
            slope = f"{f['fit'].slope:.2f}" if f["fit"] is not None else "–"
            lines.append(f"| {name}/{points} | " + " | ".join(cells) + f" | {slope} |")
            if not by_label[(name, points)].uniform or by_label[(name, points)].is_rule:
                cells = [_g(r["weighted_discrepancy_rms"]) for r in rows]
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
                f"{_g(row['statistic'], 6)} | {row['dof']} | {format_p(row['p_value'])} | "
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
