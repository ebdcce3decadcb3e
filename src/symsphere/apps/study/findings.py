"""The sentences of the study's report that are computed from the measurements ("What the measurements
say"): comparisons of mean squared errors, the best randomised sampler, the Lebedev rule's reach.
Nothing here is assumed; :mod:`symsphere.apps.study.report` puts them into ``report.md``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

from ..._typing import Domain
from ...integrands import INTEGRANDS
from ...symmetry import orbit_size
from .config import BASELINE
from .results import Results, Row
from .samplers import Sampler, all_samplers

__all__ = ["Comparison", "best_randomized", "comparison_rows", "findings", "lebedev_text", "find_row", "short_number"]

_Label = tuple[str, str]  # (sampler name, points)
Comparison = tuple[_Label, _Label, str, dict[str, "float | None"]]


def short_number(x: float | None, digits: int = 3) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    if isinstance(x, float) and math.isinf(x):
        return "∞"
    return f"{x:.{digits}g}"


def _lookup(rows: list[Row], **match: object) -> Row | None:
    for row in rows:
        if all(row[k] == v for k, v in match.items()):
            return row
    return None


def find_row(rows: list[Row], **match: object) -> Row:
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


def comparison_rows(results: Results) -> tuple[list[Comparison], list[str]]:
    config = results.config
    rows: list[Comparison] = []
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
        return f"{short_number(low)}"
    return f"{short_number(low)} to {short_number(high)} (geometric mean {short_number(geometric)})"


def _complete(ratios: dict[str, float | None]) -> dict[str, float] | None:
    """*ratios*, or None if a sampler is missing for one of them."""
    if any(v is None for v in ratios.values()):
        return None
    return {g: v for g, v in ratios.items() if v is not None}


def findings(results: Results) -> list[str]:
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
                f"{_range_text(finite.values())} ({', '.join(f'{g}: {short_number(v)}' for g, v in finite.items())})"
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
                    f"({', '.join(f'{g}: {short_number(v)}' for g, v in r.items())})."
                )
    for peer in ("classic", "octahedral"):
        r = ratios(ea_sobol, (peer, "sobol"), sphere)
        if sphere and r is not None:
            finite_values = [v for v in r.values() if math.isfinite(v)]
            if finite_values:
                out.append(
                    f"**QMC: orbits of scrambled Sobol' points vs Sobol' on the {peer} map.** MSE ratio "
                    f"({peer}/equal_area) at the largest n: {_range_text(finite_values)} "
                    f"({', '.join(f'{g}: {short_number(v)}' for g, v in r.items())})."
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


def best_randomized(results: Results) -> list[str]:
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
            text + f"at equal n {label(by_mse[0])} (MSE {short_number(mse_ratio)}x below {label(by_mse[1])}); "
            f"at equal time {label(by_time[0])} ({short_number(time_ratio)}x the efficiency of {label(by_time[1])})"
        )
    return out


def lebedev_text(results: Results) -> list[str]:
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
            f"`{g}`: Lebedev {short_number(error)} (n = {lebedev['n']}); best randomized at n = {best['n']}: "
            f"{best['sampler']}/{best['points']} {short_number(best['rmse'])}, which {needs}"
        )
    return out
