"""Coverage of integrate(method='auto')'s intervals: 1000 seeded runs on each of five integrands.

For each integrand (smooth, peaked, discontinuous, and two on the hemisphere, where the rotated rules
are folded) it runs ``integrate(f, rtol=..., method='auto', rng=seed, n_max=N_MAX)`` for seeds
0 ... runs - 1 and counts, against the closed form:

- the runs whose returned interval (at its stated 95 %) contains the true value;
- the largest |estimate - true| / standard error over the runs (the target: at most 5);
- the family of the answer, the runs that converged, the median of the evaluations, and how many
  answering stages a run took (a first answering stage that misses the tolerance is followed by a
  larger fresh one, and only the last is returned).

Then, for the rules and sizes that answer most often, the coverage of one stage at a fixed size with 8,
32, 64 and 128 randomisations, as in a pilot stage and the three kinds of answering stage (``integrate(f, n=R * size, replicates=R,
method=family)``, the same seeds): what the rule's own t-interval does before any choice or stopping rule.

A calibrated 95 % interval covers in Binomial(runs, 0.95) of the runs: 950 of 1000 with a standard
deviation of 6.9.  Counts, not times: the machine's load does not change them.

    python benchmarks/bench_auto_coverage.py [--runs 1000] [--only exp,cap] [--json PATH]

``--tails`` instead estimates P(|error| > 5 standard errors) of one stage of R randomisations of the
small folded rules and of the rules that answer with 32 randomisations on these integrands (TAILS) by
resampling: 40 000 rotations of the rule (symsphere._families), then
200 000 draws of R of them with replacement, the error against the population's mean; and the same with
the variance pooled with 8 more draws (a pilot stage of the same rule, as ``integrate`` pools it).

    python benchmarks/bench_auto_coverage.py --tails
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import run_header

import symsphere
from symsphere.integrands import INTEGRANDS

RTOL = {"exp": 1e-2, "phong": 1e-2, "cap": 5e-2, "exp_hemisphere": 1e-2, "cosine": 1e-2}
"""A run costs at most some 10^4 evaluations (the discontinuous cap's, at a looser tolerance, some 10^4)."""
N_MAX = 48 * 2**14
TAILS = (
    ("exp_hemisphere", "lebedev", 14), ("cosine", "lebedev", 26), ("exp", "lebedev", 6), ("exp", "lebedev", 14),
    ("phong", "lebedev", 110), ("cosine", "lebedev", 50), ("cosine", "lebedev", 110), ("cosine", "fibonacci", 128),
)  # fmt: skip
FIXED = (
    ("exp", "lebedev", 6), ("exp", "lebedev", 14), ("exp_hemisphere", "lebedev", 14), ("cosine", "lebedev", 26),
    ("cap", "lebedev", 50), ("phong", "lebedev", 110), ("cosine", "lebedev", 110),
)  # fmt: skip
FIXED_REPLICATES = (8, 32, 64, 128)


def measure(name: str, runs: int) -> dict:
    f = INTEGRANDS[name]
    covered = converged = 0
    worst, worst_seed = 0.0, -1
    families: Counter = Counter()
    answers: Counter = Counter()
    evaluations = []
    start = time.process_time()
    for seed in range(runs):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # not converged: counted below
            result = symsphere.integrate(f, domain=f.domain, rtol=RTOL[name], method="auto", rng=seed, n_max=N_MAX)
        low, high = result.confidence_interval
        covered += bool(low <= f.exact <= high)
        converged += result.converged
        deviation = abs(result.integral - f.exact) / result.standard_error if result.standard_error > 0 else 0.0
        if deviation > worst:
            worst, worst_seed = float(deviation), seed
        families[result.method] += 1
        answers[sum(h["reason"].startswith("answer") for h in result.history)] += 1
        evaluations.append(result.n_evaluations)
    return dict(
        integrand=name,
        domain=f.domain,
        rtol=RTOL[name],
        runs=runs,
        covered=covered,
        converged=converged,
        largest_error_in_standard_errors=worst,
        its_seed=worst_seed,
        families=dict(families),
        answering_stages=dict(sorted(answers.items())),
        median_evaluations=float(np.median(evaluations)),
        cpu_seconds=time.process_time() - start,
    )


def fixed(name: str, method: str, size: int, replicates: int, runs: int) -> dict:
    f = INTEGRANDS[name]
    covered, worst = 0, 0.0
    for seed in range(runs):
        n = replicates * size
        result = symsphere.integrate(f, domain=f.domain, n=n, method=method, replicates=replicates, rng=seed)
        low, high = result.confidence_interval
        covered += bool(low <= f.exact <= high)
        if result.standard_error > 0:
            worst = max(worst, float(abs(result.integral - f.exact) / result.standard_error))
    return dict(integrand=name, method=method, size=size, replicates=replicates, runs=runs, covered=covered,
                largest_error_in_standard_errors=worst)  # fmt: skip


def tails(name: str, method: str, size: int) -> None:
    from symsphere._families import Rotated, haar_rotations

    f = INTEGRANDS[name]
    rule = Rotated(method, f, f.domain, np.array([0.0, 0.0, 1.0]), np.random.SeedSequence(5), 2, 2)
    population = np.array([rule._rule(r, size)[0] for r in haar_rotations(40_000, np.random.SeedSequence(7))])
    rng = np.random.default_rng(1)
    for replicates in (8, 32, 64, 128):
        beyond = pooled = 0
        for _ in range(20):
            draws = population[rng.integers(0, len(population), size=(10_000, replicates + 8))]
            fresh, pilot = draws[:, :replicates], draws[:, replicates:]
            error = np.abs(fresh.mean(axis=1) - population.mean())
            beyond += int(np.sum(error > 5 * fresh.std(axis=1, ddof=1) / np.sqrt(replicates)))
            # the variance pooled with 8 independent pilot randomisations of the same rule (the mean fresh's own)
            variance = ((replicates - 1) * fresh.var(axis=1, ddof=1) + 7 * pilot.var(axis=1, ddof=1)) / (replicates + 6)
            pooled += int(np.sum(error > 5 * np.sqrt(variance / replicates)))
        print(
            f"{name}: {method} {size}, {replicates} randomisations: P(> 5 SE) {beyond / 200_000:.2g}, "
            f"variance pooled with a pilot of 8: {pooled / 200_000:.2g}",
            flush=True,
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--only", default=None, help="comma-separated integrand names")
    parser.add_argument("--json", type=Path, default=None)
    parser.add_argument("--tails", action="store_true", help="P(> 5 SE) of single stages, by resampling")
    args = parser.parse_args()
    if args.tails:
        for case in TAILS:
            tails(*case)
        return
    names = [name for name in RTOL if args.only is None or name in args.only.split(",")]
    rows = []
    print("| integrand (rtol) | covers (of runs) | largest error / SE | family of the answer | answering stages |")
    print("|---|---:|---:|---|---|")
    for name in names:
        row = measure(name, args.runs)
        rows.append(row)
        families = ", ".join(f"{family[0].upper()} {count}" for family, count in sorted(row["families"].items()))
        stages = ", ".join(f"{k}: {v}" for k, v in row["answering_stages"].items())
        print(
            f"| `{name}` ({row['rtol']:g}) | {row['covered']} of {row['runs']} | "
            f"{row['largest_error_in_standard_errors']:.2f} | {families} | {stages} |",
            flush=True,
        )
    print("\n| integrand: rule | " + " | ".join(f"{r}: covers | largest error / SE" for r in FIXED_REPLICATES) + " |")
    print("|---|" + "---:|---:|" * len(FIXED_REPLICATES))
    fixed_rows = []
    for name, method, size in FIXED:
        if name not in names:
            continue
        pair = [fixed(name, method, size, replicates, args.runs) for replicates in FIXED_REPLICATES]
        fixed_rows += pair
        cells = " | ".join(f"{r['covered']} of {r['runs']} | {r['largest_error_in_standard_errors']:.2f}" for r in pair)
        print(f"| `{name}`: {method} {size} | {cells} |", flush=True)
    if args.json:
        args.json.write_text(
            json.dumps(
                dict(
                    **run_header(),
                    n_max=N_MAX,
                    rows=rows,
                    fixed=fixed_rows,
                ),
                indent=1,
            )
        )


if __name__ == "__main__":
    main()
