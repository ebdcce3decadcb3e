"""``method='auto'`` of :func:`symsphere.integrate`: it picks a rule family by a pilot on f itself.

The families (the scheme's orbits, rotated Lebedev rules, rotated spherical Fibonacci sets) are in
:mod:`symsphere._families`.  With ``atol`` or ``rtol``, ``'auto'`` and a named family (``'lebedev'``,
``'fibonacci'``: the same run with one family) run two kinds of stages:

- *pilot* stages (``replicates`` randomisations, default 8) that never answer: every family climbs its
  own ladder (the scheme's stages nested, the rotated rules' fresh), the one whose total after its next
  stage is smallest first (Lebedev's counted at half).  They grow so, balanced, until an answering
  stage is predicted to meet the tolerance: no family grows alone on a prediction from small stages
  (a Lebedev rule's sudden convergence once its order passes f's bandwidth, Fibonacci's on a sharp
  lobe, are invisible to it); before an answering stage every family, its own too, *explores* while
  its total stays below EXPLORE of it;
- *answering* stages: ANSWER_FACTOR times as many randomisations (default 128), all drawn afresh --
  new rotations or new base points, nothing reused -- at the size predicted (from the stages before:
  the spread of one randomisation extrapolated along the family's ladder) to meet the tolerance with
  the fewest evaluations, once one is predicted within JUMP times everything spent before (a stage
  whose estimate is DISAGREE standard errors or more from the estimate with the most evaluations
  behind it predicts with the spread its distance implies: a small rule that misses a sharp lobe
  measures a tiny spread around a wrong mean); or
  MID_FACTOR times as many (default 64), also sized to the tolerance, at a rule of MID_RULE points or
  more measured or the next size, on a fast decay (its spread like size**MID_SLOPE or faster), if cheaper; or
  FEW_FACTOR times as many (default 32) where a rule already measured is *far* inside the tolerance
  (FAR of it: a rule exact to rounding, or converging fast), if cheaper.  Its mean is its own; its
  variance is pooled with a pilot stage's of the same rule and size if one ran (independent draws of
  the same distribution: the pooled variance is independent of the fresh mean), and its Student-t
  interval (the pooled degrees of freedom) at ``confidence_level`` is returned if its half-width meets
  the tolerance; if not, its spread joins the predictions, and the next answering stage, again fresh,
  costs more than every one before it.

This is Stein's two-stage procedure: the answer's size is fixed before its values are seen, so its
interval covers at the stated level, conditioned only on its own half-width meeting the tolerance --
which, at a size predicted to meet it, is nearly always so (measured: docs/results/integration.md).
128 randomisations make the t-interval's tails light even for the skewed estimates of a small folded
rule (Student's t with 127 degrees of freedom exceeds 5 with probability 2e-6, with 7, 1.6e-3); 64
on rules of 50 points or more (|t_63| > 5: 5e-6; resampled, the folded rules' P(> 5 SE) at most 8e-5); 32
where the estimates are nearly normal (|t_31| > 5: 2e-5), which the rules far inside the
tolerance were on the measured integrands (resampled: docs/results/integration.md).  ``n_max`` bounds
the evaluations of all stages of all families, which is what ``n_evaluations`` counts.  ``result.history`` lists every stage: family,
evaluations, estimate, standard error, half-width, tolerance, level, and why it ran.
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
from ._integration import DEFAULT_REPLICATES, Integrand, IntegrationResult, Request
from ._lebedev import LEBEDEV_SIZES
from ._typing import Domain
from ._validation import check_choice, check_count, check_nonnegative, check_normal, check_rng, check_rtol, short_repr
from .points import check_points
from .symmetry import DOMAINS, orbit_size

# haar_rotations: the tests reach it here (symsphere._testing.auto)
__all__ = ["RULE_METHODS", "haar_rotations", "integrate_rules"]

RULE_METHODS: tuple[str, ...] = ("auto", "fibonacci", "lebedev")
"""The ``method=`` values this module runs (the scheme's maps run in :mod:`symsphere._integration`)."""
AUTO_POINTS = "sobol_interlaced3"
PILOT_STAGES = 2
ANSWER_FACTOR = 16
"""An answering stage has this many times the pilot's randomisations (default 16 x 8 = 128)."""
AIM = 0.75
"""An answering stage is sized for a predicted half-width of AIM x the tolerance: so that it meets the
tolerance nearly always, and the condition that it does hardly selects its spread."""
FEW_FACTOR = 4
"""An answering stage far inside the tolerance has this many times the pilot's randomisations (4 x 8 = 32)."""
FAR = 0.01
"""... far inside: its predicted half-width with FEW_FACTOR x the pilot's randomisations is FAR x the
tolerance or less, from the spread measured at that rule (never extrapolated: a rule predicted exact
to rounding would answer with an interval of rounding noise around a rounding bias of a few ulps).
Such a rule is exact to rounding or converging fast, its estimates over rotations nearly normal
(resampled; the small folded rules, skewed, are nowhere near so far inside)."""
MID_FACTOR = 8
"""An answering stage sized to the tolerance (AIM) has this many times the pilot's randomisations (8 x 8 = 64)
where cheaper than ANSWER_FACTOR x: on a spread falling like size**MID_SLOPE or faster, R randomisations
reach a half-width h with some R**(1 - 1/(2p)) evaluations (p = -slope), so fewer randomisations of a
larger rule cost less; only at a rule of MID_RULE points or more (the small folded rules are skewed:
with 64 their t-intervals had runs 5.9 standard errors off) and at a size measured or the next of the
ladder (a prediction further out, from 8 randomisations, is often optimistic: a miss then selects the
stages whose spread happened to be small)."""
MID_RULE = 50
MID_SLOPE = -1.0
EXPLORE = 0.125
SELF_EXPLORE = True
"""The leader explores its own ladder too (benchmarks/bench_integrate_auto.py runs a family alone both ways)."""
JUMP = 4 * ANSWER_FACTOR
"""An answering stage costs at most this multiple of every evaluation before it: a prediction from small
stages may be far off (the totals then grow geometrically); 4 for that, times its more replicates."""
SPECTRAL_MARGIN = 0.8
"""A Lebedev rule converging spectrally: the fitted decay per unit of sqrt(size), times this (slower)."""
DISAGREE = 4.0
"""A stage whose estimate is more than DISAGREE combined standard errors from the reference (the estimate
with the most evaluations behind it, of any family) missed part of f -- a small rule that never hits a
sharp lobe reports a tiny spread around a wrong mean --: its spread is not used below the one its
distance implies (distance x sqrt(randomisations)) in predicting an answering stage."""
SHARE = {"lebedev": 2.0}
"""Balanced stages give a family this multiple of the others' total: Lebedev's small rules are cheap, and
exact on band-limited f once the order passes the degree, which no small stage can predict."""


@dataclasses.dataclass(frozen=True)
class Jump:
    """The answering stage a family would run: ladder index (-1: none affordable), evaluations,
    predicted half-width, and whether that meets the tolerance."""

    k: int = -1
    cost: int = 0
    half_width: float = math.inf
    meets: bool = False
    replicates: int = 0  # 0: the family's answer_replicates


def integrate_rules(request: Request) -> IntegrationResult:
    """:func:`symsphere.integrate` for ``method`` in :data:`RULE_METHODS`."""
    f, n, points, rng, atol, rtol, n_max = (
        request.f, request.n, request.points, request.rng, request.atol, request.rtol, request.n_max
    )  # fmt: skip
    confidence_level = request.confidence_level
    if not callable(f):
        raise TypeError(f"'f' must be callable, taking an (m, 3) array of directions; got {type(f).__name__}")
    method = check_choice(request.method, "method", RULE_METHODS)
    domain = check_choice(request.domain, "domain", DOMAINS)
    unit_normal = check_normal(request.normal)
    if unit_normal is not None and domain != "hemisphere":
        raise ValueError("'normal' is only valid with domain='hemisphere'")
    if not (isinstance(confidence_level, float | int) and 0 < confidence_level < 1):
        raise ValueError(f"'confidence_level' must be in (0, 1), got {short_repr(confidence_level)}")
    replicates = DEFAULT_REPLICATES if request.replicates is None else check_count(request.replicates, "replicates")
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
    answer = ANSWER_FACTOR * replicates

    def rotated(name: str) -> Rotated:
        return Rotated(name, numpy_f, domain, fold_normal, seeds[name], replicates, answer)

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
        scheme = Scheme(f, domain, scheme_points, request.normal, seeds["equal_area"], replicates, n_max, answer)
        families: list[Family] = [scheme, rotated("fibonacci"), rotated("lebedev")]
    else:
        families = [rotated(method)]
    return _run(families, domain, float(confidence_level), atol_value, rtol_value, n_max)


def _balanced(family: Family) -> float:
    """The family's total after its next stage, over its share: the balanced order of the pilot."""
    return (family.spent + family.sizes()[0][1]) / SHARE.get(family.name, 1.0)


def _history_row(
    name: str,
    stage: Stage,
    spent: int,
    result: IntegrationResult,
    half_width: npt.NDArray[np.float64],
    reason: str,
) -> dict[str, Any]:
    """One entry of ``result.history``: a stage of family *name* and why it ran."""
    return dict(
        method=name,
        size=stage.size,
        replicates=stage.replicates,
        evaluations=stage.cost,
        total_evaluations=spent,
        integral=result.integral,
        standard_error=result.standard_error,
        half_width=float(np.max(half_width)),
        tolerance=result.tolerance,
        level=result.confidence_level,
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


def _honest_spread(stage: Stage, reference: tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]] | None) -> float:
    """The stage's spread of one randomisation, at least what its distance from *reference* (estimate,
    standard error; per component of f) implies where that distance is more than DISAGREE combined
    standard errors."""
    if reference is None:
        return stage.spread
    distance = np.abs(stage.integral - reference[0])
    apart = distance > DISAGREE * np.hypot(stage.standard_error, reference[1])
    if not np.any(apart):
        return stage.spread
    implied = np.sqrt(distance[apart] ** 2 - reference[1][apart] ** 2) * math.sqrt(stage.replicates)
    return max(stage.spread, float(np.max(implied)))


def _jump(
    family: Family,
    tolerance: float,
    level: float,
    budget: int,
    floor: int,
    reference: tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]] | None = None,
) -> Jump:
    """The smallest answering stage of *family* costing more than *floor* predicted to meet *tolerance*
    within *budget*; else the largest affordable one (``Jump()`` if none is).

    The spread of one randomisation is taken where a stage measured it (the one with the most
    randomisations) and extrapolated beyond the largest: along a power of the size, the slower of the
    rates through the last two and the last three (at least n**-0.5; exactly n**-0.5 for copies of the
    largest Lebedev rule), or for a Lebedev rule converging faster than n**-2 as exp(-b sqrt(size)).
    """
    seen: dict[int, tuple[int, float]] = {}  # size -> (randomisations behind it, spread of one)
    for stage in (*family.stages, *family.chosen):
        if stage.size not in seen or stage.replicates >= seen[stage.size][0]:
            seen[stage.size] = (stage.replicates, _honest_spread(stage, reference))
    largest = max(seen)
    spread = seen[largest][1]
    slope, spectral = -0.5, 0.0
    known = [(size, e) for size, (_, e) in sorted(seen.items()) if e > 0][-3:]
    if len(known) >= 2:
        x, y = np.log([z for z, _ in known]), np.log([e for _, e in known])
        local = float((y[-1] - y[-2]) / (x[-1] - x[-2]))
        fit = float(np.polyfit(x, y, 1)[0]) if len(known) == 3 else local
        slope = min(-0.5, fit)
        if family.name == "lebedev" and local <= -2:  # converging like exp(-b order), order ~ sqrt(size)
            root = np.sqrt([known[-2][0], known[-1][0]])
            spectral = SPECTRAL_MARGIN * float((y[-2] - y[-1]) / (root[1] - root[0]))
    copies_from = LEBEDEV_SIZES[-1] if family.name == "lebedev" else math.inf
    # 0: the family's answer_replicates; fewer where allowed (see FEW_FACTOR, MID_FACTOR)
    options = [0] + [
        factor * family.replicates
        for factor in (FEW_FACTOR, MID_FACTOR)
        if family.answer_replicates > factor * family.replicates
    ]
    best = dict.fromkeys(options, Jump())
    # the decay fitted over every size measured, not the last three (8 randomisations of a discontinuous f can
    # fall 4x in a step, a sharp lobe's suddenly converge): fewer randomisations only where it is fast, and at the
    # next size predicted with it if it is the slower
    measured = np.log([(size, e) for size, (_, e) in sorted(seen.items()) if e > 0]).reshape(-1, 2)
    overall = float(np.polyfit(measured[:, 0], measured[:, 1], 1)[0]) if len(measured) >= 3 else 0.0
    next_size = math.inf  # the first size of the ladder beyond the largest measured
    for k in range(64):
        size, cost = family.ladder(k)
        next_size = size if size > largest and next_size == math.inf else next_size
        costs = {r: family.ladder(k, r)[1] for r in options}
        if cost <= floor or (size < largest and size not in seen):
            continue
        if min(costs.values()) > budget:
            break
        rule = min(size, copies_from)
        if size in seen:
            predicted = seen[size][1]
        elif rule <= largest:
            predicted = spread
        elif spectral > 0:
            predicted = spread * math.exp(-spectral * (math.sqrt(rule) - math.sqrt(largest)))
        else:
            predicted = spread * (rule / largest) ** slope
        if size not in seen and size > rule:
            predicted *= (size / max(rule, largest)) ** -0.5
        for r in options:
            if best[r].meets or not floor < costs[r] <= budget:
                continue
            slower = (
                predicted
                if rule <= largest or r != MID_FACTOR * family.replicates
                else spread * (size / largest) ** overall
            )
            half_width = (
                t_quantile(family.answer_units(size, r), level)
                * max(predicted, slower)
                / math.sqrt(r or family.answer_replicates)
            )
            if r == 0:
                meets = half_width <= AIM * tolerance
            elif r == FEW_FACTOR * family.replicates:  # far inside, at a rule measured
                meets = half_width <= FAR * tolerance and rule <= largest
            else:  # near the tolerance: a rule measured or the next, on a fast decay
                meets = (
                    half_width <= AIM * tolerance and rule >= MID_RULE and size <= next_size and overall <= MID_SLOPE
                )
            best[r] = Jump(k, costs[r], half_width, meets, r)
        met = [j.cost for j in best.values() if j.meets]
        if met and min(costs.values()) >= min(met):
            break
    meeting = [j for j in best.values() if j.meets]
    return min(meeting, key=lambda j: j.cost) if meeting else best[0]


def _pooled(family: Family, fresh: Stage) -> Stage:
    """*fresh* with its variance pooled with a pilot stage's of the same rule and size, if there is one.

    The mean stays fresh's own (the pilot chose the rule: its mean must not answer).  The pilot's
    randomisations are independent draws of the same distribution as fresh's, so the pooled variance is
    independent of fresh's mean and Student's t applies with the pooled degrees of freedom under
    normality; on skewed estimates the pilot's share also weakens the dependence of the variance on
    the mean that makes the t-interval's tails heavy (resampled: docs/results/integration.md)."""
    pilot = [s for s in family.stages if s.size == fresh.size and s.units == s.replicates]
    if not pilot or fresh.units != fresh.replicates:  # random points: orbits are the units, not replicates
        return fresh
    other = pilot[0]
    r, q = fresh.replicates, other.replicates
    variance = ((r - 1) * fresh.standard_error**2 * r + (q - 1) * other.standard_error**2 * q) / (r + q - 2)
    return dataclasses.replace(fresh, standard_error=np.sqrt(variance / r), units=r + q - 1)


def _run(
    families: Sequence[Family], domain: str, confidence_level: float, atol: float, rtol: float, n_max: int
) -> IntegrationResult:
    """Pilot stages, then fresh answering stages of the family predicted to meet the tolerance with the
    fewest evaluations (the others exploring on the side), until one answers or n_max."""
    spent, floor = 0, 0  # floor: an answering stage costs more than every one before it
    history: list[dict[str, Any]] = []
    latest: dict[str, tuple[IntegrationResult, int]] = {}  # each family's estimate with the most evaluations behind it

    def look(family: Family, stage: Stage, answering: bool, reason: str) -> IntegrationResult:
        nonlocal spent
        family.spent += stage.cost
        spent += stage.cost
        result = as_result(family, stage, confidence_level, spent, domain)
        low, high = result.confidence_interval
        half_width = (np.asarray(high) - np.asarray(low)) / 2
        tolerance_now = np.maximum(atol, rtol * np.abs(np.asarray(result.integral)))
        # A tolerance of 0 (rtol alone, an estimate of exactly 0: every replicate missed f's support) is never met.
        # Nor is one whose replicates all tied while f varies (a discontinuous f on an even point set), or
        # all tied while some stage (of any family) had a spread: the scheme's too.
        spread = bool(np.any(stage.standard_error > 0))
        tied = stage.tied or (not spread and any(np.any(h["standard_error"]) for h in history))
        valid = bool(np.all(tolerance_now > 0) and not tied)
        converged = answering and valid and bool(np.all(half_width <= tolerance_now))
        result = dataclasses.replace(
            result, tolerance=float(np.min(tolerance_now)), n_stages=len(history) + 1, converged=converged
        )
        behind = stage.size * stage.replicates
        if family.name not in latest or behind >= latest[family.name][1]:
            latest[family.name] = (result, behind)
        history.append(_history_row(family.name, stage, spent, result, half_width, reason))
        return result

    def answer(family: Family, jump: Jump, reason: str) -> IntegrationResult:
        nonlocal floor
        stage = _pooled(family, family.fresh(jump.k, jump.replicates))
        family.chosen.append(stage)
        floor = jump.cost
        return look(family, stage, True, reason)

    while True:
        budget = n_max - spent
        affordable = [fam for fam in families if fam.sizes() and fam.sizes()[0][1] <= budget]
        jumps: dict[str, Jump] = {}
        if latest:
            # the tolerance from the estimate with the most evaluations behind it (a small rule can miss
            # a peak and report a tiny integral with a tiny error)
            best = max(latest.values(), key=lambda pair: pair[1])[0]
            tolerance = float(np.min(np.maximum(atol, rtol * np.abs(best.integral))))
            cap = min(budget, max(JUMP * spent, 1))
            reference = (np.atleast_1d(np.asarray(best.integral)), np.atleast_1d(np.asarray(best.standard_error)))
            jumps = {
                fam.name: _jump(fam, tolerance, confidence_level, cap, floor, reference)
                for fam in families
                if len(fam.stages) + len(fam.chosen) >= PILOT_STAGES
            }
        said = ", ".join(f"{name} {j.cost if j.meets else 'none'}" for name, j in jumps.items())
        meeting = [fam for fam in families if fam.name in jumps and jumps[fam.name].meets]
        # else (for the last answer at n_max) the one whose largest affordable answering stage has the smallest
        # half-width per evaluation
        growing = [fam for fam in families if jumps.get(fam.name, Jump()).k >= 0]
        leader = (
            min(meeting, key=lambda fam: jumps[fam.name].cost)
            if meeting
            else min(growing, key=lambda fam: jumps[fam.name].half_width * math.sqrt(jumps[fam.name].cost))
            if growing
            else None
        )
        # before an answering stage every family continues its own ladder, the leader too (a cheap measurement)
        horizon = EXPLORE * jumps[leader.name].cost if leader is not None and meeting else 0
        explore = [
            fam
            for fam in affordable
            if (fam is not leader or SELF_EXPLORE) and fam.spent + fam.sizes()[0][1] <= horizon
        ]
        if explore:
            reason = f"exploring: its total stays below {EXPLORE} of the leader's answering stage; predicted: {said}"
            result = look(min(explore, key=_balanced), min(explore, key=_balanced).run_next(), False, reason)
        elif meeting and leader is not None:
            reason = f"answer: a fresh stage predicted to meet the tolerance with the fewest evaluations: {said}"
            result = answer(leader, jumps[leader.name], reason)
        elif affordable:
            # no answering stage predicted to meet the tolerance: every family grows, balanced (no one grows alone:
            # a decay that sets in late -- Lebedev past f's bandwidth, Fibonacci on a sharp lobe -- is not predicted)
            choice = min(affordable, key=_balanced)
            reason = f"pilot: the smallest total after the stage; none predicted to meet the tolerance within {JUMP} x the total; {said}"
            result = look(choice, choice.run_next(), False, reason)
        elif leader is not None:
            result = answer(leader, jumps[leader.name], "answer: the largest affordable fresh stage (n_max)")
        else:
            break
        if result.converged:
            return dataclasses.replace(result, history=tuple(history))
    if not latest:
        raise ValueError(f"'n_max'={n_max} is smaller than the first stage of every family")
    return _not_reached([pair[0] for pair in latest.values()], spent, history, n_max)
