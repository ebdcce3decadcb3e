"""Rule families of :func:`symsphere.integrate` and ``method='auto'``, which picks one by a pilot on f itself.

Three families of randomised rules, each unbiased for every integrable f, with a standard error from
R independent randomisations (*replicates*, default 8; Student's t with R - 1 degrees of freedom):

- ``'equal_area'``: the scheme's orbits (as without ``method='auto'``); within ``'auto'`` its base points
  are ``'sobol_interlaced3'`` (higher-order scrambled Sobol'), unless ``points=`` says otherwise.  Stage
  k has 2**k orbits per replicate; the points are nested, so a stage only adds the new blocks.
- ``'lebedev'``: scipy's Lebedev rules of increasing order (:data:`LEBEDEV_LADDER` points), each
  replicate the rule under an independent uniform (Haar) rotation
  (``scipy.spatial.transform.Rotation.random``); past the largest rule (order 131, 5810 points) a
  replicate is the mean of 2, 4, 8, ... independently rotated copies (the earlier copies reused).
- ``'fibonacci'``: the spherical Fibonacci set of 16 * 2**k points, each replicate under an
  independent Haar rotation.

Hemispheres: the scheme has its own 24-image orbits about the normal.  A rotated sphere rule is
mapped onto the hemisphere by *folding*: a node below the plane is reflected into it
(``w - 2 (w . n) n``).  Reflection preserves the uniform measure, so a uniformly distributed node
folds to a uniformly distributed direction on the hemisphere, and ``(1/2) sum w_i f(fold(x_i))`` is
unbiased for the hemisphere integral.  Folding keeps f continuous (restricting f by an indicator
would make it discontinuous at the horizon and ruin the rule's order); the folded integrand has a
kink at the horizon where f's derivative along the normal is not zero there, so a high-order rule
converges more slowly on the hemisphere than on the sphere.

``'auto'`` (needs ``atol`` or ``rtol``): every family runs two pilot stages, the cheapest pending stage
first, and the integration stops as soon as any stage meets the tolerance.  After the pilot, the
family whose predicted remaining cost is smallest runs its next stage; the prediction extrapolates
the standard error from the family's last two stages (its measured rate, at least n**-0.5;
exactly n**-0.5 for the Lebedev copies) along the family's stage sizes.  The choice is made again
after every stage.  Every interval the run looks at spends part of the error probability
``alpha = 1 - confidence_level``: each of the F families gets alpha / F, and its stage j is at level
``1 - alpha / (F j (j + 1))`` (F = 1 for a named family: the scheme's rule).  These add up to alpha over
all stages of all families, so the interval returned covers with probability at least
``confidence_level`` (a union bound) whichever stage of whichever family it is.
``n_max`` bounds the evaluations of all stages of all families (pilot and discarded stages
included), which is what ``n_evaluations`` counts.  ``result.history`` lists every stage: family,
evaluations, estimate, standard error, half-width, tolerance, and why it ran.
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

from ._fused import compiled_integrand, vectorised
from ._integration import (
    DEFAULT_REPLICATES,
    Integrand,
    IntegrationResult,
    Plan,
    check_sums,
    compute_here,
    evaluate,
    plan,
    stage_result,
)
from ._lebedev import LEBEDEV_SIZES, lebedev_weights, sample_lebedev
from ._typing import Domain, Float64Array, PointsLike, RNGLike
from ._validation import check_choice, check_count, check_nonnegative, check_normal, check_rng, check_rtol, short_repr
from .peers import fibonacci_points
from .points import BLOCK, check_points
from .symmetry import DOMAINS, orbit_size

__all__ = ["FAMILIES", "RULE_METHODS", "LEBEDEV_LADDER", "haar_rotations", "integrate_rules"]

FAMILIES: tuple[str, ...] = ("equal_area", "fibonacci", "lebedev")
"""The families ``method='auto'`` chooses from (``'equal_area'``: the scheme)."""
RULE_METHODS: tuple[str, ...] = ("auto", "fibonacci", "lebedev")
"""The ``method=`` values this module runs (the scheme's maps run in :mod:`symsphere._integration`)."""
LEBEDEV_LADDER: tuple[int, ...] = (6, 14, 26, 50, 110, 230, 434, 974, 2030, 3890, 5810)
"""Points of the Lebedev rules of the stages (about doubling), then copies of the 5810-point rule."""
FIBONACCI_FIRST = 16
AUTO_POINTS = "sobol_interlaced3"
PILOT_STAGES = 2
EXPLORE = 0.25
SHARE = {"lebedev": 2.0}
"""Balanced stages give a family this multiple of the others' total: Lebedev's small rules are cheap, and
exact on band-limited f once the order passes the degree, which no small stage can predict."""
_CHUNK = 1 << 16  # rows evaluated at a time: bounded memory


@dataclasses.dataclass
class _Stage:
    size: int  # points of one replicate's rule (scheme: directions per replicate)
    cost: int  # new evaluations
    integral: Float64Array
    standard_error: Float64Array
    units: int
    tied: bool = False  # every replicate gave the same value although f varies: the spread says nothing


class _Family:
    """One rule family's stages; subclasses say what a stage is."""

    name = ""
    points_name = "haar_rotations"

    def __init__(self, replicates: int) -> None:
        self.replicates = replicates
        self.stages: list[_Stage] = []
        self.spent = 0

    def sizes(self) -> list[tuple[int, int]]:
        """(size, cost) of every stage from the next one on, as far as the ladder goes (lazily bounded)."""
        raise NotImplementedError

    def run_next(self) -> _Stage:
        raise NotImplementedError


class _Rotated(_Family):
    """Lebedev or Fibonacci: replicate r of a stage is the rule under Haar rotation(s) of its own."""

    def __init__(self, name: str, numpy_f: Integrand, domain: str, normal: Float64Array, seed: Any, replicates: int):
        super().__init__(replicates)
        self.name = name
        self.f = numpy_f
        self.normal = normal if domain == "hemisphere" else None
        self.seed = seed
        self.copies: list[list[Float64Array]] = [[] for _ in range(replicates)]  # Lebedev copies, reused
        self.copy_seeds: list[np.random.SeedSequence] | None = None
        self.varies = False  # f took two different values somewhere

    def _size(self, k: int) -> tuple[int, int]:
        """(points per replicate, copies) of stage k (0-based)."""
        if self.name == "fibonacci":
            return FIBONACCI_FIRST << k, 1
        if k < len(LEBEDEV_LADDER):
            return LEBEDEV_LADDER[k], 1
        return LEBEDEV_SIZES[-1], 2 ** (k - len(LEBEDEV_LADDER) + 1)

    def sizes(self) -> list[tuple[int, int]]:
        out = []
        for k in range(len(self.stages), len(self.stages) + 64):
            size, copies = self._size(k)
            out.append((size * copies, self.replicates * size * self._new_copies(k)))
        return out

    def _new_copies(self, k: int) -> int:
        """Copies stage k draws: the first copies stage draws 2, each later one as many as it reuses."""
        copies = self._size(k)[1]
        return copies if copies <= 2 else copies // 2

    def run_next(self) -> _Stage:
        return self.run_stage(len(self.stages))

    def run_stage(self, k: int) -> _Stage:
        """Stage k (0-based); copies stages reuse the copies drawn so far."""
        size, copies = self._size(k)
        stage_seed = self.seed.spawn(1)[0]
        if copies == 1:
            rotations = haar_rotations(self.replicates, stage_seed)
            estimates = np.stack([self._rule(rotation, size) for rotation in rotations])
            cost = self.replicates * size
        else:
            if self.copy_seeds is None:  # one stream of copies per replicate: later stages extend it
                self.copy_seeds = stage_seed.spawn(self.replicates)
            cost = 0
            for r, copy_seed in enumerate(self.copy_seeds):
                while len(self.copies[r]) < copies:
                    (rotation,) = haar_rotations(1, copy_seed.spawn(1)[0])
                    self.copies[r].append(self._rule(rotation, size))
                    cost += size
            estimates = np.stack([np.mean(self.copies[r][:copies], axis=0) for r in range(self.replicates)])
        integral = estimates.mean(axis=0)
        with np.errstate(over="ignore", invalid="ignore"):
            variance = estimates.var(axis=0, ddof=1)
        if not (np.all(np.isfinite(integral)) and np.all(np.isfinite(variance))):
            raise ValueError(
                f"'f' returned values whose sum (or its variance) overflows float64 (integral {integral[0]:.3g}); "
                "scale f down"
            )
        tied = self.varies and bool(np.all(variance == 0))  # e.g. the same count of points in a cap every time
        stage = _Stage(size * copies, cost, integral, np.sqrt(variance / self.replicates), self.replicates, tied)
        self.stages.append(stage)
        return stage

    def _rule(self, rotation: Float64Array, size: int) -> Float64Array:
        """sum w_i f(R x_i) over the rule of *size* points (folded onto the hemisphere about the normal),
        in chunks: a Fibonacci set's points are made chunk by chunk (bounded memory for any size)."""
        half = 1.0 if self.normal is None else 0.5  # folded: (1/2) sum w f(fold(x))
        total: Float64Array | None = None
        for start in range(0, size, _CHUNK):
            stop = min(start + _CHUNK, size)
            if self.name == "fibonacci":
                nodes, weights = fibonacci_points(size, start=start, stop=stop), np.full(stop - start, 4 * np.pi / size)
            else:
                nodes = np.asarray(sample_lebedev(size), dtype=np.float64)[start:stop]
                weights = lebedev_weights(size)[start:stop]
            weights = weights * half
            directions = nodes @ rotation.T
            if self.normal is not None:
                below = np.minimum(directions @ self.normal, 0.0)
                directions = directions - 2 * below[:, None] * self.normal
            values = evaluate(self.f, directions)
            self.varies = self.varies or bool(np.any(values != values[:1]))
            with np.errstate(over="ignore", invalid="ignore"):
                part = weights @ values
                total = part if total is None else total + part
            if not np.all(np.isfinite(total)):
                check_sums(values, directions)
        assert total is not None
        return total


class _Scheme(_Family):
    """The scheme's orbits: stage k has 2**k orbits per replicate (orbits as units for random points)."""

    name = "equal_area"

    def __init__(
        self, f: Integrand, domain: str, points: PointsLike, normal: Any, seed: Any, replicates: int, n_max: int
    ):
        units = 1 if points == "random" else replicates
        super().__init__(units)
        self.count = orbit_size(cast(Domain, domain))
        self.first = 16 if points == "random" else 1  # orbits (per replicate) of the first stage
        orbits = self.first
        while self.count * units * orbits * 2 <= n_max:
            orbits *= 2
        self.largest: Plan = plan(
            f,
            domain,
            self.count * units * orbits,
            "equal_area",
            points,
            normal,
            seed,
            None if units == 1 else units,
            0.95,
        )
        self.points_name = self.largest.points_name
        self.kept: dict[tuple[int, int], Any] = {}

    def sizes(self) -> list[tuple[int, int]]:
        out = []
        for k in range(len(self.stages), len(self.stages) + 64):
            orbits = self.first << k
            if orbits > self.largest.orbits_per_replicate:
                break
            new = orbits - (orbits // 2 if k > 0 else 0)
            out.append((self.count * orbits, self.count * self.replicates * new))
        return out

    def run_next(self) -> _Stage:
        k = len(self.stages)
        orbits = self.first << k
        work = dataclasses.replace(self.largest, orbits_per_replicate=orbits, blocks_per_replicate=-(-orbits // BLOCK))
        result = stage_result(work, self.kept, k + 1, 0.0, 0.0, compute_here)
        cost = self.count * self.replicates * (orbits - (orbits // 2 if k > 0 else 0))
        stage = _Stage(
            self.count * orbits,
            cost,
            np.atleast_1d(np.asarray(result.integral, dtype=np.float64)),
            np.atleast_1d(np.asarray(result.standard_error, dtype=np.float64)),
            result.n_units,
        )
        self.stages.append(stage)
        return stage


def haar_rotations(count: int, seed: np.random.SeedSequence) -> Float64Array:
    """*count* independent uniformly (Haar) distributed rotation matrices, (count, 3, 3), from *seed*."""
    from scipy.spatial.transform import Rotation  # function-level: scipy.spatial costs ~0.3 s at import

    matrices: Float64Array = Rotation.random(count, rng=np.random.default_rng(seed)).as_matrix().reshape(count, 3, 3)
    return matrices


def _t(units: int, level: float) -> float:
    from scipy import special  # not at import, as in symsphere._integration

    return float(special.stdtrit(units - 1, 0.5 + level / 2)) if units > 1 else math.inf


def _predict(family: _Family, tolerance: float, level: float, budget: int) -> tuple[float, float]:
    """(predicted new evaluations until the half-width meets *tolerance*, or inf; predicted half-width
    after spending at most *budget*), extrapolating the standard error along the family's stage sizes."""
    last = family.stages[-1]
    se = float(np.max(last.standard_error))
    slope = -0.5
    recent = [(st.size, float(np.max(st.standard_error))) for st in family.stages[-3:]]
    if len(recent) >= 2 and all(e > 0 for _, e in recent) and recent[0][0] != recent[-1][0]:
        x, y = np.log([z for z, _ in recent]), np.log([e for _, e in recent])  # least squares: less noise
        slope = min(-0.5, float(np.polyfit(x, y, 1)[0]))
    t = _t(last.units, level)
    cost, half_width = 0, t * se
    for size, stage_cost in family.sizes():
        if cost + stage_cost > budget:
            break
        cost += stage_cost
        rate = -0.5 if isinstance(family, _Rotated) and family.name == "lebedev" and size > LEBEDEV_SIZES[-1] else slope
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

    def rotated(name: str) -> _Rotated:
        return _Rotated(name, numpy_f, domain, fold_normal, seeds[name], replicates)

    if not to_tolerance:
        if method == "auto":
            raise ValueError("method='auto' chooses by the tolerance: give 'atol' or 'rtol' (or name a method)")
        if n_max is not None:
            raise ValueError("'n_max' is only valid with 'atol' or 'rtol'")
        if n is None:
            raise TypeError("integrate() missing required keyword argument 'n' (or give 'atol' or 'rtol')")
        return _fixed(rotated(method), check_count(n, "n", multiple=replicates), domain, confidence_level)
    if n is not None:
        raise ValueError(
            f"'n' with a tolerance is the scheme's first stage; method={method!r} starts at its smallest rule"
        )
    n_max = count * 2**24 if n_max is None else check_count(n_max, "n_max")
    if method == "auto":
        families: list[_Family] = [
            _Scheme(f, domain, scheme_points, normal, seeds["equal_area"], replicates, n_max),
            rotated("fibonacci"),
            rotated("lebedev"),
        ]
    else:
        families = [rotated(method)]
    return _race(families, domain, confidence_level, atol_value, rtol_value, n_max)


def _fixed(family: _Rotated, n: int, domain: str, level: float) -> IntegrationResult:
    """One stage of a rotated rule with n evaluations in all: n / replicates points per replicate."""
    per = n // family.replicates
    for k in range(64):
        size, copies = family._size(k)
        if size * copies == per:
            return _result(family, family.run_stage(k), level, n, domain)
        if size * copies > per:
            break
    valid = sorted({family._size(k)[0] * family._size(k)[1] * family.replicates for k in range(14)})
    raise ValueError(
        f"'n'={n} is not a stage of method={family.name!r} with {family.replicates} replicates; "
        f"use one of {valid[:14]} ..."
    )


def _result(family: _Family, stage: _Stage, level: float, evaluations: int, domain: str) -> IntegrationResult:
    t = _t(stage.units, level)
    squeeze = (lambda a: float(a[0])) if stage.integral.shape == (1,) else (lambda a: a)
    return IntegrationResult(
        integral=squeeze(stage.integral),
        standard_error=squeeze(stage.standard_error),
        confidence_interval=(
            squeeze(stage.integral - t * stage.standard_error),
            squeeze(stage.integral + t * stage.standard_error),
        ),
        confidence_level=level,
        n_evaluations=evaluations,
        n_units=stage.units,
        unit="orbit" if stage.units > 1 and isinstance(family, _Scheme) and family.replicates == 1 else "replicate",
        domain=domain,
        method=family.name,
        points=family.points_name,
    )


def _balanced(family: _Family) -> float:
    """The family's total after its next stage, over its share: the balanced order of the pilot."""
    return (family.spent + family.sizes()[0][1]) / SHARE.get(family.name, 1.0)


def _race(
    families: Sequence[_Family], domain: str, confidence_level: float, atol: float, rtol: float, n_max: int
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
        choice: _Family | None = None
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
        result = _result(choice, stage, level, spent, domain)
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
        history.append(
            dict(
                method=choice.name,
                size=stage.size,
                evaluations=stage.cost,
                total_evaluations=spent,
                integral=result.integral,
                standard_error=result.standard_error,
                half_width=float(np.max(half_width)),
                tolerance=result.tolerance,
                level=level,
                reason=reason,
            )
        )
        if converged:
            return dataclasses.replace(result, history=tuple(history))
    if result is None:
        raise ValueError(f"'n_max'={n_max} is smaller than the first stage of every family")
    best = min(
        latest.values(), key=lambda r: float(np.max(np.subtract(r.confidence_interval[1], r.confidence_interval[0])))
    )
    best = dataclasses.replace(best, n_evaluations=spent, n_stages=check, history=tuple(history))
    low, high = best.confidence_interval
    warnings.warn(
        f"integrate: the tolerance {best.tolerance:.3g} was not reached by n_max={n_max}: the best interval "
        f"({best.method}, {100 * best.confidence_level:.4g}%) has half-width {np.max(np.subtract(high, low)) / 2:.3g}",
        UserWarning,
        stacklevel=4,
    )
    return best
