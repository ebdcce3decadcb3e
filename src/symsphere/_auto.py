"""``method='auto'`` of :func:`symsphere.integrate`: it picks a rule family by a pilot on f itself.

The families (the scheme's orbits, rotated Lebedev rules, rotated spherical Fibonacci sets) are in
:mod:`symsphere._families`.

``'auto'`` (needs ``atol`` or ``rtol``) runs three kinds of stages:

- *pilot*: the family whose total after its next stage is smallest (Lebedev's counted at half) runs
  its next stage on its own ladder (the scheme's nested, the rotated rules' fresh);
- *chosen*: once a family has two stages, its standard error is extrapolated to each larger stage of
  its ladder (a power of the size fitted to its last stages, at least n**-0.5; for a Lebedev rule
  converging faster than n**-2, exp(-b sqrt(size)), its order growing like sqrt(size)); the family
  whose smallest stage predicted to meet the tolerance costs least (at most JUMP times everything
  spent before) runs that stage *afresh* -- new rotations or new base points, nothing reused;
- *exploring*: before each chosen stage, every other family continues its pilot ladder while its
  total stays below EXPLORE of that stage (a Lebedev rule's sudden convergence once its order passes
  f's bandwidth is invisible to a prediction from small stages).

A chosen stage answers when it meets the tolerance; a pilot or exploring stage never (it ran to choose,
and one that meets the tolerance may owe it to a spread that happened to be small): one that meets
PILOT_STRICT of it is repeated afresh, and the repetition is a chosen stage.  A chosen stage's replicates are independent randomisations of its family
only, drawn after the choice and the size were fixed from earlier stages.  Every interval the run looks
at spends part of ``alpha = 1 - confidence_level``: the c-th pilot or exploring stage
``(alpha / 2) / (c (c + 1))``, the i-th chosen stage ``(alpha / 2) / (i (i + 1))``; these add up to at
most alpha, so the interval returned covers with probability at least ``confidence_level`` (a union
bound) whichever stage it is.  A named family runs its own ladder alone (stage j at level
``1 - alpha / (j (j + 1))``).  ``n_max`` bounds the evaluations of all stages of all families (pilot
and discarded stages included), which is what ``n_evaluations`` counts.  ``result.history`` lists every
stage: family, evaluations, estimate, standard error, half-width, tolerance, level, and why it ran.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Sequence
from typing import Any, cast

import numpy as np
import numpy.typing as npt
from numba.extending import is_jitted

from ._families import (
    FAMILIES,
    Family,
    Rotated,
    Scheme,
    Stage,
    as_result,
    fixed_stage,
    haar_rotations,
    t_quantile,
)
from ._fused import compiled_integrand, vectorised
from ._integration import DEFAULT_REPLICATES, Integrand, IntegrationResult
from ._lebedev import LEBEDEV_SIZES
from ._typing import Domain, PointsLike, RNGLike
from ._validation import check_choice, check_count, check_nonnegative, check_normal, check_rng, check_rtol, short_repr
from .points import check_points
from .symmetry import DOMAINS, orbit_size

# haar_rotations: the tests reach it here (symsphere._testing.auto)
__all__ = ["RULE_METHODS", "haar_rotations", "integrate_rules"]

RULE_METHODS: tuple[str, ...] = ("auto", "fibonacci", "lebedev")
"""The ``method=`` values this module runs (the scheme's maps run in :mod:`symsphere._integration`)."""
AUTO_POINTS = "sobol_interlaced3"
PILOT_STAGES = 2
PILOT_ALPHA = 0.5
"""'auto': the share of alpha for the pilot's and the exploring stages; the rest is for the chosen fresh stages."""
EXPLORE = 0.25
PILOT_STRICT = 0.1
JUMP = 4
"""'auto': a fresh stage costs at most this multiple of every evaluation before it (a prediction from small
stages may be far off; the totals then grow geometrically)."""
SLOPE_MARGIN = 0.0
"""'auto' predicts with the fitted rate of decay slowed by this much: about one standard deviation of a
slope fitted to standard errors of 8 replicates over a factor 4 in size (an upper bound on the cost)."""
SPECTRAL_MARGIN = 0.8
"""The same for a Lebedev rule converging spectrally: the fitted decay per unit of sqrt(size), times this."""
SHARE = {"lebedev": 2.0}
"""Balanced stages give a family this multiple of the others' total: Lebedev's small rules are cheap, and
exact on band-limited f once the order passes the degree, which no small stage can predict."""


def _predict(family: Family, tolerance: float, level: float, budget: int) -> tuple[float, float]:
    """(predicted new evaluations until the half-width meets *tolerance*, or inf; predicted half-width
    after spending at most *budget*), extrapolating the standard error along the family's stage sizes."""
    last = family.stages[-1]
    se = float(np.max(last.standard_error))
    slope = -0.5
    recent = [(st.size, float(np.max(st.standard_error))) for st in family.stages[-3:]]
    if len(recent) >= 2 and all(e > 0 for _, e in recent) and recent[0][0] != recent[-1][0]:
        x, y = np.log([z for z, _ in recent]), np.log([e for _, e in recent])  # least squares: less noise
        slope = min(-0.5, float(np.polyfit(x, y, 1)[0]))
    t = t_quantile(last.units, level)
    cost, half_width = 0, t * se
    for size, stage_cost in family.sizes():
        if cost + stage_cost > budget:
            break
        cost += stage_cost
        rate = -0.5 if isinstance(family, Rotated) and family.name == "lebedev" and size > LEBEDEV_SIZES[-1] else slope
        half_width = t * se * (size / last.size) ** rate
        if half_width <= tolerance:
            return float(cost), half_width
    return math.inf, half_width


def integrate_rules(
    f: Integrand,
    domain: str,
    n: int | None,
    method: str,
    points: PointsLike | None,
    normal: npt.ArrayLike | None,
    rng: RNGLike,
    replicates: int | None,
    confidence_level: float,
    atol: float | None,
    rtol: float | None,
    n_max: int | None,
) -> IntegrationResult:
    """:func:`symsphere.integrate` for ``method`` in :data:`RULE_METHODS`."""
    if not callable(f):
        raise TypeError(f"'f' must be callable, taking an (m, 3) array of directions; got {type(f).__name__}")
    method = check_choice(method, "method", RULE_METHODS)
    domain = check_choice(domain, "domain", DOMAINS)
    unit_normal = check_normal(normal)
    if unit_normal is not None and domain != "hemisphere":
        raise ValueError("'normal' is only valid with domain='hemisphere'")
    if not (isinstance(confidence_level, float | int) and 0 < confidence_level < 1):
        raise ValueError(f"'confidence_level' must be in (0, 1), got {short_repr(confidence_level)}")
    replicates = DEFAULT_REPLICATES if replicates is None else check_count(replicates, "replicates")
    if replicates < 2:
        raise ValueError(
            f"'replicates' must be at least 2 with method={method!r} (an error estimate), got {replicates}"
        )
    if method != "auto" and points is not None:
        raise ValueError(f"'points' is only valid with the scheme's maps and 'auto', not with method={method!r}")
    scheme_points = AUTO_POINTS if points is None else points
    if method == "auto" and (check_points(scheme_points) is not None or scheme_points == "stratified"):
        raise ValueError(
            "'points' with method='auto' must be nested and randomised: one of 'halton', 'random', 'sobol', "
            f"'sobol_interlaced2', 'sobol_interlaced3'; got {short_repr(scheme_points)}"
        )
    count = orbit_size(cast(Domain, domain))
    to_tolerance = atol is not None or rtol is not None
    atol_value = 0.0 if atol is None else check_nonnegative(atol, "atol")
    rtol_value = 0.0 if rtol is None else check_rtol(rtol, "rtol")
    if to_tolerance and atol_value == 0 and rtol_value == 0:
        raise ValueError("'atol' or 'rtol' must be positive")
    compiled = compiled_integrand(f)
    # a numba function is called row by row in a compiled loop; a suite integrand has its own numpy f
    numpy_f: Integrand = vectorised(compiled) if compiled is not None and is_jitted(f) else f
    root = np.random.SeedSequence(check_rng(rng).integers(0, 2**63, size=4, dtype=np.int64).tolist())
    seeds = dict(zip(FAMILIES, root.spawn(len(FAMILIES)), strict=True))
    fold_normal = np.array([0.0, 0.0, 1.0]) if unit_normal is None else unit_normal

    def rotated(name: str) -> Rotated:
        return Rotated(name, numpy_f, domain, fold_normal, seeds[name], replicates)

    if not to_tolerance:
        if method == "auto":
            raise ValueError("method='auto' chooses by the tolerance: give 'atol' or 'rtol' (or name a method)")
        if n_max is not None:
            raise ValueError("'n_max' is only valid with 'atol' or 'rtol'")
        if n is None:
            raise TypeError("integrate() missing required keyword argument 'n' (or give 'atol' or 'rtol')")
        return fixed_stage(rotated(method), check_count(n, "n", multiple=replicates), domain, confidence_level)
    if n is not None:
        raise ValueError(
            f"'n' with a tolerance is the scheme's first stage; method={method!r} starts at its smallest rule"
        )
    n_max = count * 2**24 if n_max is None else check_count(n_max, "n_max")
    if method == "auto":
        families: list[Family] = [
            Scheme(f, domain, scheme_points, normal, seeds["equal_area"], replicates, n_max),
            rotated("fibonacci"),
            rotated("lebedev"),
        ]
        return _auto(families, domain, confidence_level, atol_value, rtol_value, n_max)
    return _race([rotated(method)], domain, confidence_level, atol_value, rtol_value, n_max)


def _balanced(family: Family) -> float:
    """The family's total after its next stage, over its share: the balanced order of the pilot."""
    return (family.spent + family.sizes()[0][1]) / SHARE.get(family.name, 1.0)


def _race(
    families: Sequence[Family], domain: str, confidence_level: float, atol: float, rtol: float, n_max: int
) -> IntegrationResult:
    """Run stages (pilot, then the predicted cheapest family) until one meets the tolerance or n_max."""
    alpha = 1.0 - confidence_level
    spent, check = 0, 0
    history: list[dict[str, Any]] = []
    latest: dict[str, IntegrationResult] = {}
    result: IntegrationResult | None = None
    while True:
        share = alpha / len(families)  # each family's share of alpha, spent over its own stages
        pending = [fam for fam in families if len(fam.stages) < PILOT_STAGES and fam.sizes()]
        budget = n_max - spent
        choice: Family | None = None
        if pending:  # balanced: the family whose total after its next stage is smallest
            running = [fam for fam in families if fam.sizes()]
            choice = min(running, key=_balanced)
            reason = f"pilot ({PILOT_STAGES} stages of every family): the smallest total after the stage"
            if choice.sizes()[0][1] > budget:
                choice = None
        else:
            # the tolerance from the estimate with the most evaluations behind it (a small rule can miss
            # a peak and report a tiny integral with a tiny error)
            best = latest[max(families, key=lambda fam: fam.spent if fam.name in latest else -1).name]
            tolerance = float(np.min(np.maximum(atol, rtol * np.abs(best.integral))))
            predictions = {
                fam.name: _predict(
                    fam, tolerance, 1.0 - share / ((len(fam.stages) + 1) * (len(fam.stages) + 2)), budget
                )
                for fam in families
            }
            finite = [fam for fam in families if math.isfinite(predictions[fam.name][0])]
            if finite:
                choice = min(finite, key=lambda fam: predictions[fam.name][0])
                reason = "predicted to meet the tolerance with the fewest new evaluations: " + ", ".join(
                    f"{name} {p[0]:.3g}" for name, p in predictions.items()
                )
                # A prediction from small stages can be wrong (a Lebedev rule converges only once its order
                # passes f's bandwidth): another family keeps running while its total stays below
                # EXPLORE of the leader's total, which costs at most 2 * EXPLORE of that.
                horizon = EXPLORE * (choice.spent + choice.sizes()[0][1])
                explore = [
                    fam
                    for fam in families
                    if fam is not choice and fam.sizes() and fam.spent + fam.sizes()[0][1] <= horizon
                ]
                if explore:
                    choice = min(explore, key=_balanced)
                    reason = f"exploring: its total stays below {EXPLORE} of the leader's total; " + reason
            else:
                affordable = [fam for fam in families if fam.sizes() and fam.sizes()[0][1] <= budget]
                choice = min(affordable, key=_balanced) if affordable else None
                reason = (
                    "no family is predicted to meet the tolerance within n_max: balanced, the smallest total "
                    "after the stage"
                )
        if choice is None:
            break
        stage = choice.run_next()
        choice.spent += stage.cost
        spent += stage.cost
        check += 1
        level = 1.0 - share / (len(choice.stages) * (len(choice.stages) + 1))
        result = as_result(choice, stage, level, spent, domain)
        low, high = result.confidence_interval
        half_width = (np.asarray(high) - np.asarray(low)) / 2
        tolerance_now = np.maximum(atol, rtol * np.abs(np.asarray(result.integral)))
        # A tolerance of 0 (rtol alone, an estimate of exactly 0: every replicate missed f's support) is never met.
        # Nor is one whose replicates all tied while f varies (a discontinuous f on an even point set).
        converged = bool(np.all(half_width <= tolerance_now) and np.all(tolerance_now > 0) and not stage.tied)
        result = dataclasses.replace(
            result, tolerance=float(np.min(tolerance_now)), n_stages=check, converged=converged
        )
        latest[choice.name] = result
        history.append(_history_row(choice.name, stage.size, stage.cost, spent, result, half_width, level, reason))
        if converged:
            return dataclasses.replace(result, history=tuple(history))
    if result is None:
        raise ValueError(f"'n_max'={n_max} is smaller than the first stage of every family")
    return _not_reached(list(latest.values()), spent, history, n_max)


def _history_row(
    name: str,
    size: int,
    cost: int,
    spent: int,
    result: IntegrationResult,
    half_width: npt.NDArray[np.float64],
    level: float,
    reason: str,
) -> dict[str, Any]:
    """One entry of ``result.history``: a stage of family *name* and why it ran."""
    return dict(
        method=name,
        size=size,
        evaluations=cost,
        total_evaluations=spent,
        integral=result.integral,
        standard_error=result.standard_error,
        half_width=float(np.max(half_width)),
        tolerance=result.tolerance,
        level=level,
        reason=reason,
    )


def _not_reached(
    results: Sequence[IntegrationResult], spent: int, history: list[dict[str, Any]], n_max: int
) -> IntegrationResult:
    """The narrowest interval of *results*, with a warning naming the tolerance and what was reached."""
    best = min(results, key=lambda r: float(np.max(np.subtract(r.confidence_interval[1], r.confidence_interval[0]))))
    best = dataclasses.replace(best, n_evaluations=spent, n_stages=len(history), history=tuple(history))
    low, high = best.confidence_interval
    warnings.warn(
        f"integrate: the tolerance {best.tolerance:.3g} was not reached by n_max={n_max}: the best interval "
        f"({best.method}, {100 * best.confidence_level:.4g}%) has half-width {np.max(np.subtract(high, low)) / 2:.3g}",
        UserWarning,
        stacklevel=5,
    )
    return best


def _jump(family: Family, tolerance: float, t: float, budget: int) -> tuple[int, int, float, bool]:
    """(stage, evaluations, predicted half-width, whether it meets *tolerance*) of the smallest fresh stage,
    larger than any run, predicted to meet the tolerance within *budget*; else the largest affordable one
    (evaluations 0 and half-width inf if none is).  The standard error is extrapolated from the family's
    largest stages along a power of the size: the slower of the rates through the last two and the last
    three (at least n**-0.5; exactly n**-0.5 for copies of the largest Lebedev rule) -- an upper bound on
    the cost, since one stage too large costs about what the family alone spends on its way there, one too
    small a further stage."""
    seen: dict[int, float] = {}
    for stage in (*family.stages, *family.chosen):
        seen[stage.size] = float(np.max(stage.standard_error))
    largest = max(seen)
    se = seen[largest]
    slope, spectral = -0.5, 0.0
    known = [(size, e) for size, e in sorted(seen.items()) if e > 0][-3:]
    if len(known) >= 2:
        x, y = np.log([z for z, _ in known]), np.log([e for _, e in known])
        local = float((y[-1] - y[-2]) / (x[-1] - x[-2]))
        fit = float(np.polyfit(x, y, 1)[0]) if len(known) == 3 else local
        slope = min(-0.5, fit + SLOPE_MARGIN)
        if family.name == "lebedev" and local <= -2:  # converging like exp(-b order), order ~ sqrt(size)
            root = np.sqrt([known[-2][0], known[-1][0]])
            spectral = SPECTRAL_MARGIN * float((y[-2] - y[-1]) / (root[1] - root[0]))
    copies_from = LEBEDEV_SIZES[-1] if family.name == "lebedev" else math.inf
    found: tuple[int, int, float, bool] = (-1, 0, math.inf, False)
    for k in range(64):
        size, cost = family.ladder(k)
        if size <= largest:
            continue
        if cost > budget:
            break
        if se == 0:  # no spread at the largest stage (a tie on a varying f): the next stage decides
            return k, cost, 0.0, True
        rule = min(size, copies_from)
        if rule <= largest:
            predicted = se
        elif spectral > 0:
            predicted = se * math.exp(-spectral * (math.sqrt(rule) - math.sqrt(largest)))
        else:
            predicted = se * (rule / largest) ** slope
        predicted *= (size / max(rule, largest)) ** -0.5 if size > rule else 1.0
        found = (k, cost, t * predicted, t * predicted <= tolerance)
        if found[3]:
            break
    return found


def _auto(
    families: Sequence[Family], domain: str, confidence_level: float, atol: float, rtol: float, n_max: int
) -> IntegrationResult:
    """The pilot (every family's first stages, cheapest total first), then fresh stages of the family
    predicted to meet the tolerance with the fewest evaluations, the others exploring on the side."""
    alpha = 1.0 - confidence_level
    spent = 0
    looks = {"pilot": 0, "chosen": 0}
    history: list[dict[str, Any]] = []
    latest: dict[str, tuple[IntegrationResult, int]] = {}  # each family's estimate with the most evaluations behind it
    result: IntegrationResult | None = None
    confirm: list[tuple[Family, int]] = []  # a pilot stage that met PILOT_STRICT of the tolerance

    def level(part: str, look: int) -> float:
        share = PILOT_ALPHA if part == "pilot" else 1.0 - PILOT_ALPHA
        return 1.0 - alpha * share / (look * (look + 1))

    def look(family: Family, stage: Stage, part: str, reason: str) -> IntegrationResult:
        nonlocal spent
        family.spent += stage.cost
        spent += stage.cost
        looks[part] += 1
        result = as_result(family, stage, level(part, looks[part]), spent, domain)
        low, high = result.confidence_interval
        half_width = (np.asarray(high) - np.asarray(low)) / 2
        tolerance_now = np.maximum(atol, rtol * np.abs(np.asarray(result.integral)))
        # A tolerance of 0 (rtol alone, an estimate of exactly 0: every replicate missed f's support) is never met.
        # Nor is one whose replicates all tied while f varies (a discontinuous f on an even point set).
        # replicates that all tie while some stage (of any family) had a spread: the scheme's too
        spread = bool(np.any(stage.standard_error > 0))
        tied = stage.tied or (not spread and any(np.any(h["standard_error"]) for h in history))
        valid = bool(np.all(tolerance_now > 0) and not tied)
        converged = valid and bool(np.all(half_width <= tolerance_now)) and part == "chosen"
        # A pilot stage never answers: it would be returned because its spread happened to be small (a stage
        # of 6 Lebedev points answering rtol 1e-2 covers in 91% of runs instead of 95%).  One that meets
        # PILOT_STRICT of the tolerance is repeated afresh, and the repetition answers.
        if part == "pilot" and valid and bool(np.all(half_width <= PILOT_STRICT * tolerance_now)):
            confirm.append((family, len(family.stages) - 1))
        result = dataclasses.replace(
            result, tolerance=float(np.min(tolerance_now)), n_stages=len(history) + 1, converged=converged
        )
        behind = stage.size * family.replicates
        if family.name not in latest or behind >= latest[family.name][1]:
            latest[family.name] = (result, behind)
        history.append(
            _history_row(
                family.name, stage.size, stage.cost, spent, result, half_width, result.confidence_level, reason
            )
        )
        return result

    def step(family: Family, reason: str) -> IntegrationResult:
        return look(family, family.run_next(), "pilot", reason)

    while True:
        budget = n_max - spent
        affordable = [fam for fam in families if fam.sizes() and fam.sizes()[0][1] <= budget]
        if confirm:
            family, k = confirm.pop()
            confirm.clear()
            if family.ladder(k)[1] <= budget:
                stage = family.fresh(k)
                family.chosen.append(stage)
                reason = f"confirming: a pilot stage met {PILOT_STRICT} of the tolerance; this fresh repetition answers"
                result = look(family, stage, "chosen", reason)
                if result.converged:
                    break
                continue
        best = max(latest.values(), key=lambda pair: pair[1])[0] if latest else None
        jumps: dict[str, tuple[int, int, float, bool]] = {}
        if best is not None:
            tolerance = float(np.min(np.maximum(atol, rtol * np.abs(best.integral))))
            units = min(fam.replicates for fam in families)
            t = t_quantile(units, level("chosen", looks["chosen"] + 1))
            cap = max(JUMP * spent, 1)  # a fresh stage costs at most JUMP times everything so far
            jumps = {
                fam.name: _jump(fam, tolerance, t, min(budget, cap))
                for fam in families
                if len(fam.stages) + len(fam.chosen) >= PILOT_STAGES
            }
        leaders = [fam for fam in families if jumps.get(fam.name, (-1,))[0] >= 0]
        said = ", ".join(f"{name} {j[1] if j[3] else 'none'}" for name, j in jumps.items())
        if leaders:
            # the one predicted to meet the tolerance with the fewest evaluations, else (all capped) the
            # smallest predicted half-width per evaluation
            choice = min(
                leaders,
                key=lambda fam: (
                    not jumps[fam.name][3],
                    jumps[fam.name][1] if jumps[fam.name][3] else jumps[fam.name][2] * math.sqrt(jumps[fam.name][1]),
                ),
            )
            k, cost, _, _ = jumps[choice.name]
            # A prediction from small stages can be wrong (a Lebedev rule converges only once its order passes
            # f's bandwidth): before a fresh stage of the leader, every other family continues its own stages
            # while its total stays below EXPLORE of that stage.
            explore = [
                fam for fam in affordable if fam is not choice and fam.spent + fam.sizes()[0][1] <= EXPLORE * cost
            ]
            if explore:
                result = step(
                    min(explore, key=_balanced),
                    f"exploring: its total stays below {EXPLORE} of the leader's next stage; predicted fresh stages: "
                    + said,
                )
            else:
                reason = (
                    f"chosen: its fresh stage is predicted to meet the tolerance with the fewest evaluations: {said}"
                )
                stage = choice.fresh(k)
                choice.chosen.append(stage)
                result = look(choice, stage, "chosen", reason)
        elif affordable:
            result = step(min(affordable, key=_balanced), "pilot: the smallest total after the stage")
        else:
            break
        if result.converged:
            break
    if result is not None and result.converged:
        return dataclasses.replace(result, history=tuple(history))
    if not latest:
        raise ValueError(f"'n_max'={n_max} is smaller than the first stage of every family")
    return _not_reached([pair[0] for pair in latest.values()], spent, history, n_max)
