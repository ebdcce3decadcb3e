"""The randomised rule families of :func:`symsphere.integrate` (``method='auto'`` chooses among them).

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

Each family runs *stages*: :class:`Stage` records one stage's estimate and standard error.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, cast

import numpy as np

from ._integration import Integrand, IntegrationResult, Plan, check_sums, compute_here, evaluate, plan, stage_result
from ._lebedev import LEBEDEV_SIZES, lebedev_weights, sample_lebedev
from ._typing import Domain, Float64Array, PointsLike
from .peers import fibonacci_points
from .points import BLOCK
from .symmetry import orbit_size

__all__ = [
    "FAMILIES", "LEBEDEV_LADDER", "Family", "Rotated", "Scheme", "Stage", "as_result", "fixed_stage",
    "haar_rotations", "t_quantile",
]  # fmt: skip

FAMILIES: tuple[str, ...] = ("equal_area", "fibonacci", "lebedev")
"""The families ``method='auto'`` chooses from (``'equal_area'``: the scheme)."""
LEBEDEV_LADDER: tuple[int, ...] = (6, 14, 26, 50, 110, 230, 434, 974, 2030, 3890, 5810)
"""Points of the Lebedev rules of the stages (about doubling), then copies of the 5810-point rule."""
FIBONACCI_FIRST = 16
_CHUNK = 1 << 16  # rows evaluated at a time: bounded memory


@dataclasses.dataclass
class Stage:
    size: int  # points of one replicate's rule (scheme: directions per replicate)
    cost: int  # new evaluations
    integral: Float64Array
    standard_error: Float64Array
    units: int
    replicates: int  # independent randomisations of the whole stage (1 for the scheme's random points)
    tied: bool = False  # every replicate gave the same value although f varies: the spread says nothing

    @property
    def spread(self) -> float:
        """The standard deviation of one replicate's estimate (the largest over f's components)."""
        return float(np.max(self.standard_error)) * math.sqrt(self.replicates)


class Family:
    """One rule family's stages; subclasses say what a stage is."""

    name = ""
    points_name = "haar_rotations"

    def __init__(self, replicates: int, answer_replicates: int) -> None:
        self.replicates = replicates  # of the pilot's and the exploring stages
        self.answer_replicates = answer_replicates  # of a fresh stage (:meth:`ladder`, :meth:`fresh`)
        self.stages: list[Stage] = []
        self.chosen: list[Stage] = []  # fresh stages run to answer
        self.spent = 0

    def sizes(self) -> list[tuple[int, int]]:
        """(size, cost) of every stage from the next one on, as far as the ladder goes (lazily bounded)."""
        raise NotImplementedError

    def run_next(self) -> Stage:
        raise NotImplementedError

    def ladder(self, k: int, replicates: int = 0) -> tuple[int, int]:
        """(size, evaluations) of stage k run afresh, with *replicates* (0: :attr:`answer_replicates`)."""
        raise NotImplementedError

    def fresh(self, k: int, replicates: int = 0) -> Stage:
        """Stage k from *replicates* randomisations of its own (0: :attr:`answer_replicates`), independent of
        every stage before."""
        raise NotImplementedError

    def answer_units(self, size: int, replicates: int = 0) -> int:
        """The independent units (the degrees of freedom + 1) of a fresh stage of *size*."""
        return replicates or self.answer_replicates


class Rotated(Family):
    """Lebedev or Fibonacci: replicate r of a stage is the rule under Haar rotation(s) of its own."""

    def __init__(
        self, name: str, numpy_f: Integrand, domain: str, normal: Float64Array, seed: Any, replicates: int, answer: int
    ):
        super().__init__(replicates, answer)
        self.name = name
        self.f = numpy_f
        self.normal = normal if domain == "hemisphere" else None
        self.seed = seed
        self.copies: list[list[Float64Array]] = [[] for _ in range(replicates)]  # Lebedev copies, reused
        self.copy_seeds: list[np.random.SeedSequence] | None = None
        self.varies = False  # f took two different values somewhere
        self._sizes: tuple[int, list[tuple[int, int]]] = (-1, [])  # (stages run, sizes()): asked many times a stage

    def shape(self, k: int) -> tuple[int, int]:
        """(points per replicate, copies) of stage k (0-based)."""
        if self.name == "fibonacci":
            return FIBONACCI_FIRST << k, 1
        if k < len(LEBEDEV_LADDER):
            return LEBEDEV_LADDER[k], 1
        return LEBEDEV_SIZES[-1], 2 ** (k - len(LEBEDEV_LADDER) + 1)

    def sizes(self) -> list[tuple[int, int]]:
        if self._sizes[0] != len(self.stages):  # the ladder depends only on the stages run
            out = []
            for k in range(len(self.stages), len(self.stages) + 64):
                size, copies = self.shape(k)
                out.append((size * copies, self.replicates * size * self._new_copies(k)))
            self._sizes = (len(self.stages), out)
        return self._sizes[1]

    def _new_copies(self, k: int) -> int:
        """Copies stage k draws: the first copies stage draws 2, each later one as many as it reuses."""
        copies = self.shape(k)[1]
        return copies if copies <= 2 else copies // 2

    def run_next(self) -> Stage:
        return self.run_stage(len(self.stages))

    def ladder(self, k: int, replicates: int = 0) -> tuple[int, int]:
        """(size, evaluations) of stage k run afresh: every copy drawn."""
        size, copies = self.shape(k)
        return size * copies, (replicates or self.answer_replicates) * size * copies

    def fresh(self, k: int, replicates: int = 0) -> Stage:
        """Stage k from rotations of its own (a child of this family's seed), nothing reused."""
        domain, normal = ("sphere", np.zeros(3)) if self.normal is None else ("hemisphere", self.normal)
        answer = replicates or self.answer_replicates
        other = Rotated(self.name, self.f, domain, normal, self.seed.spawn(1)[0], answer, answer)
        stage = other.run_stage(k)
        self.varies = self.varies or other.varies
        return stage

    def run_stage(self, k: int) -> Stage:
        """Stage k (0-based); copies stages reuse the copies drawn so far."""
        size, copies = self.shape(k)
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
        se = np.sqrt(variance / self.replicates)
        stage = Stage(size * copies, cost, integral, se, self.replicates, self.replicates, tied)
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


class Scheme(Family):
    """The scheme's orbits: stage k has 2**k orbits per replicate (orbits as units for random points)."""

    name = "equal_area"

    def __init__(
        self,
        f: Integrand,
        domain: str,
        points: PointsLike,
        normal: Any,
        seed: Any,
        replicates: int,
        n_max: int,
        answer: int,
        first: int | None = None,
    ):
        units = 1 if points == "random" else replicates
        super().__init__(units, 1 if points == "random" else answer)
        self.args = (f, domain, points, normal, seed, n_max, answer)
        self.count = orbit_size(cast(Domain, domain))
        self.base = 16 if points == "random" else 1  # orbits (per replicate) of the first stage
        self.first = self.base if first is None else first
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

    def ladder(self, k: int, replicates: int = 0) -> tuple[int, int]:
        """(size, evaluations) of stage k (counted from the first stage of 1 or 16 orbits) run afresh."""
        orbits = self.base << k
        if orbits > self.largest.orbits_per_replicate:
            return self.count * orbits, 2**62  # beyond the plan for n_max: never affordable
        return self.count * orbits, self.count * self._answering(replicates) * orbits

    def _answering(self, replicates: int) -> int:
        """Random points have one replicate (orbits as units): *replicates* does not apply."""
        return 1 if self.answer_replicates == 1 else replicates or self.answer_replicates

    def fresh(self, k: int, replicates: int = 0) -> Stage:
        """Stage k from base points of their own (a child of this family's seed), nothing reused."""
        f, domain, points, normal, seed, n_max, answer = self.args
        answer = self._answering(replicates)
        other = Scheme(f, domain, points, normal, seed.spawn(1)[0], answer, n_max, answer, first=self.base << k)
        return other.run_next()

    def answer_units(self, size: int, replicates: int = 0) -> int:
        """Random points: the orbits of the stage; else its replicates."""
        return size // self.count if self.answer_replicates == 1 else self._answering(replicates)

    def sizes(self) -> list[tuple[int, int]]:
        out = []
        for k in range(len(self.stages), len(self.stages) + 64):
            orbits = self.first << k
            if orbits > self.largest.orbits_per_replicate:
                break
            new = orbits - (orbits // 2 if k > 0 else 0)
            out.append((self.count * orbits, self.count * self.replicates * new))
        return out

    def run_next(self) -> Stage:
        k = len(self.stages)
        orbits = self.first << k
        work = dataclasses.replace(self.largest, orbits_per_replicate=orbits, blocks_per_replicate=-(-orbits // BLOCK))
        result = stage_result(work, self.kept, k + 1, 0.0, 0.0, compute_here)
        cost = self.count * self.replicates * (orbits - (orbits // 2 if k > 0 else 0))
        stage = Stage(
            self.count * orbits,
            cost,
            np.atleast_1d(np.asarray(result.integral, dtype=np.float64)),
            np.atleast_1d(np.asarray(result.standard_error, dtype=np.float64)),
            result.n_units,
            self.replicates,
        )
        self.stages.append(stage)
        return stage


def haar_rotations(count: int, seed: np.random.SeedSequence) -> Float64Array:
    """*count* independent uniformly (Haar) distributed rotation matrices, (count, 3, 3), from *seed*."""
    from scipy.spatial.transform import Rotation  # function-level: scipy.spatial costs ~0.3 s at import

    matrices: Float64Array = Rotation.random(count, rng=np.random.default_rng(seed)).as_matrix().reshape(count, 3, 3)
    return matrices


def t_quantile(units: int, level: float) -> float:
    """Student's t quantile of two-sided *level* with units - 1 degrees of freedom (inf for one unit)."""
    from scipy import special  # not at import, as in symsphere._integration

    return float(special.stdtrit(units - 1, 0.5 + level / 2)) if units > 1 else math.inf


def fixed_stage(family: Rotated, n: int, domain: str, level: float) -> IntegrationResult:
    """One stage of a rotated rule with n evaluations in all: n / replicates points per replicate."""
    per = n // family.replicates
    for k in range(64):
        size, copies = family.shape(k)
        if size * copies == per:
            return as_result(family, family.run_stage(k), level, n, domain)
        if size * copies > per:
            break
    valid = sorted({family.shape(k)[0] * family.shape(k)[1] * family.replicates for k in range(14)})
    raise ValueError(
        f"'n'={n} is not a stage of method={family.name!r} with {family.replicates} replicates; "
        f"use one of {valid[:14]} ..."
    )


def as_result(family: Family, stage: Stage, level: float, evaluations: int, domain: str) -> IntegrationResult:
    """*stage* of *family* as a result: its Student-t interval at *level*."""
    t = t_quantile(stage.units, level)
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
        unit="orbit" if stage.units > 1 and isinstance(family, Scheme) and family.replicates == 1 else "replicate",
        domain=domain,
        method=family.name,
        points=family.points_name,
    )
