"""The integrator's machinery: a plan fixed before any work, partial sums per block, their reduction.

:func:`symsphere.integrate` runs it in one process; :func:`symsphere.distributed.integrate`
runs the same blocks as Dask tasks.  Block partials are (orbits, sum, sum of
squared deviations) and are combined in block order (Chan et al.'s pairwise
update), so the result does not depend on how the work is split.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np
import numpy.typing as npt

from . import frames
from ._blocks import empty_rows, warn_at_caller
from ._constants import HEMISPHERE_AREA, SPHERE_AREA
from ._fused import Compiled, NonFiniteBlock, compiled_integrand, fused_partials, vectorised
from ._kernels import Plan as KernelPlan
from ._kernels import fill, fill_orbits
from ._typing import Domain, Float64Array, MapMethod, PointsLike, RNGLike
from ._validation import (
    check_choice,
    check_count,
    check_nonnegative,
    check_normal,
    check_real_values,
    check_rng,
    check_rtol,
    memory_count_limit,
    short_repr,
)
from .points import BLOCK, BasePoints, check_points
from .symmetry import DOMAINS, orbit_size
from .warps import triangle_warp

Integrand = Callable[[Float64Array], npt.ArrayLike]
"""What ``f`` is: directions (m, 3) to values (m,) or (m, k)."""
Partial = tuple[int, Float64Array, Float64Array]
"""A block's (orbits, sum of orbit estimates, sum of squared deviations from their mean)."""
PARTIAL_BYTES = 512
"""Memory a block's partial takes until the reduction: 312 bytes measured (a tuple of an int and two
one-element arrays, tracemalloc, one component), ~150 more where a tolerance run also keeps it by index;
rounded up.  Every block's partial is held until the end, so this, not the evaluation (a block at a time),
is what bounds n by the machine's memory."""
Compute = Callable[["Plan", Sequence[tuple[int, int, int]]], list[list[Partial]]]
"""Sums blocks: (plan, [(replicate, first block, stop block), ...]) -> one list of partials per request."""

__all__ = [
    "DEFAULT_REPLICATES",
    "IntegrationResult",
    "Plan",
    "plan",
    "block_partial",
    "block_partials",
    "evaluate",
    "combine",
    "finish",
    "Compute",
    "compute_here",
    "Request",
    "to_tolerance",
    "stage_result",
    "check_sums",
]

DEFAULT_REPLICATES = 8


@dataclass(frozen=True)
class IntegrationResult:
    """Outcome of :func:`integrate`.

    Attributes
    ----------
    integral : float or ndarray
        The estimate (shape (k,) for an integrand with k components).
    standard_error : float or ndarray
        Its estimated standard deviation (NaN when it cannot be estimated).
    confidence_interval : tuple of (float or ndarray)
        ``integral -+ t * standard_error`` with Student's t at
        ``confidence_level`` and ``n_units - 1`` degrees of freedom.
    confidence_level : float
    n_evaluations : int
        Directions at which f was evaluated.
    n_units : int
        Independent units behind the standard error: orbits or replicates.
    unit : str
        ``'orbit'``, ``'replicate'`` or ``'run'``.
    domain : str
        ``'sphere'`` or ``'hemisphere'``.
    method : str
        The map onto T0 (``'equal_area'``, ``'paper1'`` or ``'paper2'``), or the rule family
        (``'lebedev'``, ``'fibonacci'``); with ``method='auto'`` the family it chose.
    points : str
        The base points: ``'random'``, ``'stratified'``, ``'sobol'``, ``'halton'``, ``'sobol_interlaced2'``,
        ``'sobol_interlaced3'``, the class name of the ``QMCEngine`` given, or ``'haar_rotations'``
        (a rotated rule family).
    tolerance : float or None
        With ``atol``/``rtol``: the target ``max(atol, rtol * |integral|)`` the interval's
        half-width was compared with (None for a fixed n).
    n_stages : int
        With ``atol``/``rtol``: the doublings run (the interval is that stage's, at level
        ``1 - (1 - requested level) / (n_stages (n_stages + 1))``; with a rule family, the stages
        run, and the level is the one requested); 1 for a fixed n.
    converged : bool
        Whether the half-width reached the tolerance (always True for a fixed n).
    history : tuple of dict
        With ``method`` ``'auto'``, ``'lebedev'`` or ``'fibonacci'`` to a tolerance: one dict per stage
        run, in order: ``method`` (the family), ``size`` (points per replicate), ``replicates``,
        ``evaluations`` (new),
        ``total_evaluations``, ``integral``, ``standard_error``, ``half_width``, ``tolerance``, ``level``
        and ``reason`` (why this family ran this stage: the pilot, exploring, or an answer,
        with the predicted costs of all families).  Empty otherwise.

    Examples
    --------
    >>> import numpy as np
    >>> from symsphere import integrate
    >>> f = lambda w: np.stack([np.exp(w[:, 0]), w[:, 2] ** 2], axis=1)   # two integrands at once
    >>> result = integrate(f, n=48 * 1024, rng=0)
    >>> result.integral.shape, result.unit, result.n_units, result.n_evaluations
    ((2,), 'orbit', 1024, 49152)
    >>> low, high = result.confidence_interval
    >>> bool(low[0] < 2 * np.pi * (np.e - 1 / np.e) < high[0])
    True
    >>> bool(result.standard_error[1] < 1e-12)     # the orbit average of z**2 is exactly 1/3
    True
    >>> result = integrate(lambda w: np.exp(w[:, 0]), n=48 * 1024, points="sobol", rng=0)
    >>> result.unit, result.n_units, result.points      # 8 scramblings of the Sobol' points
    ('replicate', 8, 'sobol')
    """

    integral: float | Float64Array
    standard_error: float | Float64Array
    confidence_interval: tuple[float | Float64Array, float | Float64Array]
    confidence_level: float
    n_evaluations: int
    n_units: int
    unit: str
    domain: str
    method: str
    points: str = field(repr=False)
    tolerance: float | None = field(default=None, repr=False)
    n_stages: int = field(default=1, repr=False)
    converged: bool = field(default=True, repr=False)
    history: tuple[dict[str, Any], ...] = field(default=(), repr=False, compare=False)

    def __str__(self) -> str:
        low, high = self.confidence_interval
        source = f"from {self.n_evaluations} evaluations, {self.n_units} independent {self.unit}s "
        source += f"({self.domain}, {self.method}, {self.points})"
        if np.all(np.isnan(self.standard_error)):  # say why, and what to pass instead
            text = f"integral = {self.integral} {source}; {self._no_error_bar()}"
        else:
            text = (
                f"integral = {self.integral} ± {self.standard_error} (standard error; "
                f"{100 * self.confidence_level:.4g}% interval [{low}, {high}]) {source}"
            )
        if self.tolerance is not None:
            state = "reached" if self.converged else "NOT reached"
            text += f"; tolerance {self.tolerance:.3g} {state} after {self.n_stages} stages"
        return text

    def _no_error_bar(self) -> str:
        if self.unit == "run":
            why = "a QMCEngine is one deterministic run; pass points='sobol' (or 'halton') for scrambled replicates"
        elif self.unit == "replicate":
            why = "one replicate has no spread to measure; pass replicates >= 2 (default 8)"
        else:
            why = "one orbit has no spread to measure; pass a larger n"
        return f"no error bar: {why}"

    def _repr_html_(self) -> str:
        """A small table for Jupyter (one column per component of a vector integrand)."""
        from html import escape

        def cells(value: Any, fmt: str = ".10g") -> str:
            return "".join(f"<td>{v:{fmt}}</td>" for v in np.atleast_1d(value))

        low, high = self.confidence_interval
        rows = [("integral", cells(self.integral))]
        if np.all(np.isnan(self.standard_error)):
            rows.append(("standard error", f"<td colspan=99>{escape(self._no_error_bar())}</td>"))
        else:
            rows += [("standard error", cells(self.standard_error, ".3g")),
                     (f"{self.confidence_level:.0%} interval", "".join(
                         f"<td>[{a:.10g}, {b:.10g}]</td>" for a, b in zip(np.atleast_1d(low), np.atleast_1d(high), strict=False)))]  # fmt: skip
        body = "".join(f"<tr><th style='text-align:left'>{k}</th>{v}</tr>" for k, v in rows)
        caption = (f"{self.n_evaluations} evaluations, {self.n_units} independent {self.unit}s "
                   f"({self.domain}, {self.method}, {escape(self.points)})")  # fmt: skip
        return f"<table><caption>{caption}</caption>{body}</table>"


@dataclass(frozen=True)
class Request:
    """The arguments of :func:`symsphere.integrate` as given (each is checked where it is used)."""

    f: Integrand
    domain: str = "sphere"
    n: int | None = None
    method: str = "equal_area"
    points: PointsLike | None = None
    normal: npt.ArrayLike | None = None
    rng: RNGLike = None
    replicates: int | None = None
    confidence_level: float = 0.95
    atol: float | None = None
    rtol: float | None = None
    n_max: int | None = None


@dataclass(frozen=True)
class Plan:
    """Everything a block needs, fixed before any work starts (and picklable)."""

    f: Integrand
    domain: str
    count: int
    method: MapMethod
    points: PointsLike
    points_name: str
    sources: tuple[BasePoints, ...]  # one per replicate
    orbits_per_replicate: int
    blocks_per_replicate: int
    replicates: int
    unit: str
    basis: Float64Array | None
    confidence_level: float
    compiled: Compiled | None = None  # (numba function, caller): the fused path of symsphere._fused


def plan(
    f: Integrand,
    domain: str,
    n: int,
    method: MapMethod,
    points: PointsLike | None,
    normal: npt.ArrayLike | None,
    rng: RNGLike,
    replicates: int | None,
    confidence_level: float,
) -> Plan:
    """Validate every argument of :func:`symsphere.integrate` and fix the run: sources, blocks, unit."""
    points = "random" if points is None else points  # integrate's default (distributed passes None on)
    if not callable(f):
        raise TypeError(f"'f' must be callable, taking an (m, 3) array of directions; got {type(f).__name__}")
    compiled = compiled_integrand(f)
    domain = check_choice(domain, "domain", DOMAINS)
    count = orbit_size(cast(Domain, domain))
    triangle_warp(method)
    engine = check_points(points)
    normal = check_normal(normal)
    if normal is not None and domain != "hemisphere":
        raise ValueError("'normal' is only valid with domain='hemisphere'")
    if not (isinstance(confidence_level, float | int) and 0 < confidence_level < 1):
        raise ValueError(f"'confidence_level' must be in (0, 1), got {short_repr(confidence_level)}")
    if engine is not None or points == "random":
        if not (replicates is None or (type(replicates) is int and replicates == 1)):
            kind = "a QMCEngine" if engine is not None else "points='random'"
            raise ValueError(f"'replicates' must be None or 1 with {kind}, got {short_repr(replicates)}")
        replicates = 1
    else:
        replicates = DEFAULT_REPLICATES if replicates is None else check_count(replicates, "replicates")
    if replicates > 1 and (n is None or (type(n) is int and 0 < n < count * replicates)):
        # the replicates, not n, are what cannot fit: each needs at least one orbit of its own
        raise ValueError(
            f"'n'={short_repr(n)} is not a multiple of {count * replicates}: 'replicates'={short_repr(replicates)} "
            f"needs 'n' >= {count * replicates} ({count} evaluations, one orbit, per replicate); pass a larger n "
            "or fewer replicates"
        )
    n = check_count(n, "n", multiple=count * replicates)
    check_partials_fit(n, count, replicates, "n")
    root = np.random.SeedSequence(check_rng(rng).integers(0, 2**63, size=4, dtype=np.int64).tolist())
    orbits = n // (count * replicates)
    with warnings.catch_warnings(record=True) as caught:  # e.g. scipy's Sobol' balance warning, once per replicate
        warnings.simplefilter("always")
        sources = tuple(
            BasePoints(points, np.random.default_rng(child), orbits, per_point=count * replicates)
            for child in root.spawn(replicates)
        )
    for message, category in dict.fromkeys((str(w.message), w.category) for w in caught):
        warn_at_caller(message, category)  # once, at the user's line
    unit = "run" if engine is not None else ("orbit" if points == "random" else "replicate")
    return Plan(
        f=f,
        domain=domain,
        count=count,
        method=method,
        points=points,
        points_name=points if isinstance(points, str) else type(points).__name__,
        sources=sources,
        orbits_per_replicate=orbits,
        blocks_per_replicate=-(-orbits // BLOCK),
        replicates=replicates,
        unit=unit,
        basis=None if normal is None else frames.frame(normal),
        confidence_level=float(confidence_level),
        compiled=compiled,
    )


def check_partials_fit(
    n: int, count: int, replicates: int, name: str, given: int | None = None, replicates_name: str = "replicates"
) -> None:
    """ValueError naming *name* (=*given*, default *n*) if the partials of *n* evaluations (one per block
    of BLOCK orbits of each replicate) cannot fit in the machine's memory (:data:`PARTIAL_BYTES` each);
    naming *replicates_name* if one block per replicate already cannot."""
    most_blocks = memory_count_limit(PARTIAL_BYTES)
    blocks = replicates * -(-n // (count * replicates * BLOCK))
    if most_blocks is None or blocks <= most_blocks:
        return
    if replicates > most_blocks:
        raise ValueError(
            f"{replicates_name!r}={replicates} is too large for this machine's memory: each replicate keeps a "
            f"partial sum per block (~{PARTIAL_BYTES} bytes) until the end; at most {most_blocks} here"
        )
    largest = (most_blocks // replicates) * BLOCK * count * replicates
    raise ValueError(
        f"{name!r}={n if given is None else given} is too large for this machine's memory: its {blocks} blocks of {BLOCK} orbits keep a "
        f"partial sum each (~{PARTIAL_BYTES} bytes) until the end, {blocks * PARTIAL_BYTES / 2**30:.3g} GiB of "
        f"{most_blocks * PARTIAL_BYTES / 2**30:.3g} GiB; at most {largest} here (or combine smaller runs)"
    )


def block_partials(plan: Plan, replicate: int, first: int, stop: int) -> list[Partial]:
    """The partials of blocks ``first ... stop - 1`` of a replicate (fused: in one parallel kernel call)."""
    if plan.compiled is not None:
        try:
            return fused_partials(
                plan.compiled,
                plan.sources[replicate],
                plan.orbits_per_replicate,
                first,
                stop,
                plan.method,
                plan.count,
                plan.basis,
                triangle_warp(plan.method).uniform,
            )
        except NonFiniteBlock as error:  # the numpy path on that block names the first offending direction
            numpy_plan = dataclasses.replace(plan, f=vectorised(plan.compiled), compiled=None)
            block_partial(numpy_plan, replicate, error.block)
            raise ValueError(str(error)) from None  # to rounding, the numpy path found nothing to name
    return [block_partial(plan, replicate, block) for block in range(first, stop)]


def block_partial(plan: Plan, replicate: int, block: int) -> Partial:
    """(orbits, sum of orbit estimates, sum of squared deviations from their mean) of one block."""
    if plan.compiled is not None:
        return block_partials(plan, replicate, block, block + 1)[0]
    start = block * BLOCK
    stop = min(start + BLOCK, plan.orbits_per_replicate)
    source = plan.sources[replicate]
    triangle_map = triangle_warp(plan.method)
    directions = empty_rows((stop - start) * plan.count, np.dtype(np.float64))
    if triangle_map.uniform:
        fill(
            KernelPlan(source, plan.method, plan.count, plan.basis), start, stop, directions
        )  # random: drawn in the kernel
        weight = np.full(stop - start, SPHERE_AREA if plan.domain == "sphere" else HEMISPHERE_AREA)
    else:
        uv = source.take(start, stop)  # the weights need the base points
        fill_orbits(uv, plan.method, plan.count, plan.basis, directions)
        # 1 / pdf of the scheme = count / pdf_T0(base), shared by the whole orbit
        with np.errstate(divide="ignore"):
            weight = plan.count / triangle_map.densities(triangle_map.points(uv))
    values = evaluate(plan.f, directions)
    with np.errstate(over="ignore", invalid="ignore"):  # an overflow is reported below, naming f
        estimates = values.reshape(stop - start, plan.count, -1).mean(axis=1) * weight[:, None]
        mean = estimates.mean(axis=0)
        partial = stop - start, estimates.sum(axis=0), ((estimates - mean) ** 2).sum(axis=0)
    if not (np.all(np.isfinite(partial[1])) and np.all(np.isfinite(partial[2]))):
        check_sums(values, directions)
    return partial


def evaluate(f: Integrand, directions: Float64Array) -> Float64Array:
    """f at *directions*, as an (m, k) float64 array.

    ValueError naming ``f`` and the first offending direction for a wrong shape, a non-finite value,
    or an exception raised by f (chained); TypeError for complex values.
    """
    m = len(directions)
    try:
        returned = f(directions)
    except Exception as error:  # the user's error, told once with where it happened; KeyboardInterrupt passes
        raise ValueError(
            f"'f' raised {type(error).__name__}: {error} (on {m} directions, the first {_direction(directions, 0)})"
        ) from error
    values = check_real_values(returned, "f", finite=False)  # complex: TypeError, not a dropped imaginary part
    if not (values.shape == (m,) or (values.ndim == 2 and values.shape[0] == m and values.shape[1] >= 1)):
        raise ValueError(
            f"'f' must return shape (m,) or (m, k) with k >= 1 for directions of shape ({m}, 3), got {values.shape} "
            f"(the first direction {_direction(directions, 0)})"
        )
    values = values.reshape(m, -1)
    if not np.all(np.isfinite(values)):
        row = int(np.flatnonzero(~np.all(np.isfinite(values), axis=1))[0])
        bad = values[row][~np.isfinite(values[row])][0]
        raise ValueError(
            f"'f' returned non-finite values ({bad} at direction {_direction(directions, row)}, the first)"
        )
    return values


def check_sums(values: Float64Array, directions: Float64Array) -> None:
    """ValueError naming ``f`` if finite *values* overflow float64 when summed (or their squares are)."""
    with np.errstate(over="ignore", invalid="ignore"):
        running = np.cumsum(values, axis=0)
        overflow = ~np.all(np.isfinite(running), axis=1)
    row = int(np.flatnonzero(overflow)[0]) if np.any(overflow) else int(np.argmax(np.max(np.abs(values), axis=1)))
    raise ValueError(
        f"'f' returned values whose sum (or its variance) overflows float64 (f = {np.max(np.abs(values[row])):.3g} "
        f"at direction {_direction(directions, row)}, the first where the running sum overflows); scale f down"
    )


def _direction(directions: Float64Array, row: int) -> str:
    return "[" + ", ".join(f"{float(c):.17g}" for c in directions[row]) + "]"


def combine(partials: Sequence[Partial]) -> Partial:
    """Chan et al.'s pairwise update of (count, sum, M2), in the given order."""
    count, total, m2 = partials[0]
    for n_b, sum_b, m2_b in partials[1:]:
        delta = sum_b / n_b - total / count
        m2 = m2 + m2_b + delta**2 * count * n_b / (count + n_b)
        count, total = count + n_b, total + sum_b
    return count, total, m2


def finish(plan: Plan, partials: Sequence[Sequence[Partial]]) -> IntegrationResult:
    """Reduce per-block partials (a list per replicate, in block order) to the result."""
    with np.errstate(over="ignore", invalid="ignore"):  # an overflow is reported below, naming f
        return _finish(plan, partials)


def _finish(plan: Plan, partials: Sequence[Sequence[Partial]]) -> IntegrationResult:
    per_replicate = [combine(blocks) for blocks in partials]
    if plan.unit == "orbit":
        count, total, m2 = per_replicate[0]
        integral = total / count
        units = count
        variance = m2 / (count - 1) if count > 1 else np.full_like(integral, np.nan)
    else:
        estimates = np.array([total / count for count, total, _ in per_replicate])
        integral = estimates.mean(axis=0)
        units = len(estimates)
        variance = estimates.var(axis=0, ddof=1) if units > 1 else np.full_like(integral, np.nan)
    if not (np.all(np.isfinite(integral)) and np.all(np.isfinite(variance) | np.isnan(variance) & (units < 2))):
        raise ValueError(  # the blocks were finite, their reduction is not: far-apart huge values
            f"'f' returned values whose sum (or its variance) overflows float64 (integral {np.ravel(integral)[0]:.3g}, "
            f"variance {np.ravel(variance)[0]:.3g}); scale f down"
        )
    standard_error = np.sqrt(variance / units)
    if units > 1:
        from scipy import special  # not at import; scipy.stats (whose t.ppf is this function) costs 2x more

        t = special.stdtrit(units - 1, 0.5 + plan.confidence_level / 2)
    else:
        t = np.nan
    squeeze = (lambda a: float(a[0])) if integral.shape == (1,) else (lambda a: a)
    return IntegrationResult(
        integral=squeeze(integral),
        standard_error=squeeze(standard_error),
        confidence_interval=(squeeze(integral - t * standard_error), squeeze(integral + t * standard_error)),
        confidence_level=plan.confidence_level,
        n_evaluations=plan.replicates * plan.orbits_per_replicate * plan.count,
        n_units=int(units),
        unit=plan.unit,
        domain=plan.domain,
        method=plan.method,
        points=plan.points_name,
    )


def compute_here(work: Plan, requests: Sequence[tuple[int, int, int]]) -> list[list[Partial]]:
    """The partials of each (replicate, first, stop) request, in this process."""
    return [block_partials(work, replicate, first, stop) for replicate, first, stop in requests]


def to_tolerance(request: Request, compute: Compute | None = None) -> IntegrationResult:
    """Double n, reusing the blocks already summed, until the half-width meets the tolerance.

    *compute* sums the new blocks of a stage: ``compute(plan, [(replicate, first, stop), ...])`` gives
    one list of partials per request (default: here, :func:`block_partials`;
    :func:`symsphere.distributed.integrate` passes one that runs them as Dask tasks).  The stages,
    the reuse and so the result do not depend on it.
    """
    f, domain, n, replicates, n_max = request.f, request.domain, request.n, request.replicates, request.n_max
    method, normal, rng = cast(MapMethod, request.method), request.normal, request.rng
    points = "random" if request.points is None else request.points  # integrate's default (distributed: None)
    confidence_level = request.confidence_level
    atol = 0.0 if request.atol is None else check_nonnegative(request.atol, "atol")
    rtol = 0.0 if request.rtol is None else check_rtol(request.rtol, "rtol")
    if atol == 0 and rtol == 0:
        raise ValueError("'atol' or 'rtol' must be positive")
    count = orbit_size(cast(Domain, check_choice(domain, "domain", DOMAINS)))
    if check_points(points) is not None:
        raise ValueError(
            "'atol' and 'rtol' need an error estimate, which a QMCEngine does not give "
            "(its replicates cannot be made independent); use points='sobol' or 'halton' (scrambled replicates)"
        )
    stratified = points == "stratified"
    if points != "random":
        replicates = DEFAULT_REPLICATES if replicates is None else check_count(replicates, "replicates")
        if replicates < 2:
            raise ValueError(
                f"'replicates' must be at least 2 with 'atol' or 'rtol' (an error estimate), got {replicates}"
            )
    unit = count * (replicates or 1)
    n = unit * (16**2 if stratified else 256) if n is None else check_count(n, "n", multiple=unit)
    n_max = count * 2**24 if n_max is None else check_count(n_max, "n_max", multiple=count)
    if n_max < n:
        raise ValueError(f"'n_max' must be at least n={n}, got {n_max}")
    growth = 4 if stratified else 2
    largest_n = n
    while largest_n * growth <= n_max:
        largest_n *= growth
    check_partials_fit(largest_n, count, replicates or 1, *(("n_max", n_max) if largest_n > n else ("n", n)))
    # One plan for the largest stage: its point sources address every stage's points by index.
    # 'stratified' grids are not nested (a finer grid is other points), so each stage plans anew.
    largest = plan(f, domain, largest_n, method, points, normal, rng, replicates, confidence_level)
    kept: dict[tuple[int, int], Partial] = {}  # (replicate, block) -> the partial of a whole block
    alpha = 1.0 - largest.confidence_level
    stage, n_stage = 1, n
    while True:
        level = 1.0 - alpha / (stage * (stage + 1))
        if stratified:
            work = plan(f, domain, n_stage, method, points, normal, rng, replicates, level)
            kept.clear()
        else:
            orbits = n_stage // unit
            work = dataclasses.replace(
                largest, orbits_per_replicate=orbits, blocks_per_replicate=-(-orbits // BLOCK), confidence_level=level
            )
        result = stage_result(work, kept, stage, atol, rtol, compute or compute_here)
        if result.converged or n_stage == largest_n:
            break
        factor = growth
        if points == "random":  # the error falls as n**-0.5 exactly: jump to the n predicted for the next level
            factor = max(2, _predicted_factor(result, alpha / ((stage + 1) * (stage + 2))))
        while n_stage * factor > largest_n:
            factor //= 2
        stage, n_stage = stage + 1, n_stage * factor
    if not result.converged:
        low, high = result.confidence_interval
        warnings.warn(
            f"integrate: the tolerance {result.tolerance:.3g} was not reached by n_max={n_max}: at n={n_stage} the "
            f"half-width of the {100 * result.confidence_level:.4g}% interval is {np.max((high - low) / 2):.3g}",
            UserWarning,  # as scipy's IntegrationWarning
            stacklevel=3,  # the caller of integrate
        )
    return result


def _predicted_factor(result: IntegrationResult, next_alpha: float) -> int:
    """The power of 2 by which n must grow for the next stage's half-width to meet the tolerance,
    if the standard error falls as n**-0.5 (random points: exactly, in expectation)."""
    from scipy import special  # not at import: the t quantile, as scipy.stats.t.ppf computes it

    assert result.tolerance is not None
    t = special.stdtrit(result.n_units - 1, 1 - next_alpha / 2)
    ratio = float(np.max(t * np.asarray(result.standard_error))) / result.tolerance if result.tolerance > 0 else np.inf
    if not np.isfinite(ratio):
        return 2
    return int(2 ** min(62, max(1, int(np.ceil(2 * np.log2(max(ratio, 1.0)))))))  # capped: n_max bounds it anyway


def stage_result(
    work: Plan, kept: dict[tuple[int, int], Partial], stage: int, atol: float, rtol: float, compute: Compute
) -> IntegrationResult:
    """The result at one stage: whole blocks from *kept*, the rest summed now (and whole ones kept)."""
    partials = []
    requests = []
    for replicate in range(work.replicates):
        reused = 0
        while (replicate, reused) in kept and reused < work.blocks_per_replicate:
            reused += 1
        requests.append((replicate, reused, work.blocks_per_replicate))
    for (replicate, reused, _), fresh in zip(requests, compute(work, requests), strict=False):
        for block, partial in enumerate(fresh, start=reused):
            if partial[0] == BLOCK:
                kept[(replicate, block)] = partial
        partials.append([kept[(replicate, b)] for b in range(reused)] + fresh)
    result = finish(work, partials)
    low, high = result.confidence_interval
    tolerance = np.maximum(atol, rtol * np.abs(result.integral))
    converged = bool(np.all((np.asarray(high) - np.asarray(low)) / 2 <= tolerance))
    return dataclasses.replace(result, tolerance=float(np.min(tolerance)), n_stages=stage, converged=converged)
