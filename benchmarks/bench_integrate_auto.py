"""integrate(method='auto') against each rule family alone: evaluations to reach rtol 1e-3, 1e-6, 1e-9.

For every integrand of the suite with a nonzero integral (a relative tolerance of an integral that is
0 cannot be met) and three integrands the tests do not use -- a sharp lobe exp(500 (w . mu - 1)), the
indicator of a spherical quadrilateral (a polygon light, discontinuous) and the product
Y_40,5 * Y_40,5 of real spherical harmonics of degree 40 (integral 1) -- and each rtol, it runs

- ``auto``: ``integrate(f, rtol=..., method='auto')`` (every evaluation counted: the pilot and every
  stage of every family);
- each family alone, with the same stage sizes as in ``auto``: ``method='lebedev'``, ``'fibonacci'``, and
  the scheme ``method='equal_area', points='sobol_interlaced3'`` from 1 orbit per replicate (``n`` = 48 x 8,
  hemisphere 24 x 8).  A rotated family alone runs twice, with its own next pilot stage explored before an
  answering stage (as within ``auto``) and without (``symsphere._auto.SELF_EXPLORE = False``: the answer
  as soon as one is predicted), and counts the fewer evaluations of the two that converged: the
  cheaper honest way of the family alone, whichever it is on this f;

all with ``rng=SEED`` and one ``n_max``.  A run that does not converge counts as not reached.  The
ratio is auto's evaluations over the fewest of the families that reached the tolerance (the best family
in hindsight); where a family reached it and auto did not (its pilot and exploration pushed it past
``n_max``), auto runs again with 4 x ``n_max`` (``auto_4x_n_max``) and the ratio is that run's.  Counts,
not times: the machine's load does not matter.

    python benchmarks/bench_integrate_auto.py [--n-max 6291456] [--seed 1] [--json PATH]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import run_header

import symsphere
from symsphere import _auto
from symsphere.harmonics import real_sh
from symsphere.integrands import INTEGRANDS

RTOLS = (1e-3, 1e-6, 1e-9)
FAMILIES = ("equal_area", "fibonacci", "lebedev")


class Unseen:
    """An integrand the tests do not use: a numpy f with its exact integral over the sphere."""

    domain = "sphere"

    def __init__(self, name, f, exact):
        self.name, self.f, self.exact = name, f, exact

    def __call__(self, w):
        return self.f(np.asarray(w, dtype=np.float64))


def _unit(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


MU = _unit([0.2, -0.5, 0.8])
KAPPA = 500.0
QUAD = [_unit(v) for v in ([0.3, 0.1, 1.0], [-0.2, 0.35, 1.0], [-0.3, -0.1, 1.0], [0.25, -0.3, 1.0])]


def _solid_angle(a, b, c):  # Van Oosterom & Strackee (1983)
    return 2 * math.atan2(abs(np.dot(a, np.cross(b, c))), 1 + a @ b + b @ c + c @ a)


def _inside_quad(w):
    inside = np.ones(len(w), dtype=bool)
    for i in range(4):
        inside &= w @ np.cross(QUAD[i], QUAD[(i + 1) % 4]) >= 0  # counter-clockwise seen from outside
    return inside.astype(np.float64)


UNSEEN = [
    Unseen("sharp_lobe", lambda w: np.exp(KAPPA * (w @ MU - 1)), 2 * np.pi * -np.expm1(-2 * KAPPA) / KAPPA),
    Unseen("polygon_light", _inside_quad, _solid_angle(*QUAD[:3]) + _solid_angle(QUAD[0], QUAD[2], QUAD[3])),
    Unseen("sh40_product", lambda w: real_sh(40, 5, w) ** 2, 1.0),
]


def run_alone(f, domain, rtol, method, seed, n_max):
    """A family alone; a rotated one both ways (see above), the fewer evaluations of those that converged."""
    if method == "equal_area":
        return run(f, domain, rtol, method, seed, n_max)
    both = []
    for explores in (True, False):
        _auto.SELF_EXPLORE = explores
        try:
            both.append(dict(run(f, domain, rtol, method, seed, n_max), leader_explores=explores))
        finally:
            _auto.SELF_EXPLORE = True
    return min(both, key=lambda r: (not r["converged"], r["evaluations"]))


def run(f, domain, rtol, method, seed, n_max):
    kwargs = dict(domain=domain, rtol=rtol, rng=seed, n_max=n_max, method=method)
    if method == "equal_area":
        kwargs.update(points="sobol_interlaced3", n=(48 if domain == "sphere" else 24) * 8)
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # not converged: recorded below
        result = symsphere.integrate(f, **kwargs)
    return dict(
        evaluations=result.n_evaluations,
        converged=result.converged,
        chosen=result.method,
        error=float(abs(result.integral - f.exact)),
        seconds=time.perf_counter() - start,
    )


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n-max", type=int, default=48 * 2**17)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--json", type=Path, default=None)
    parser.add_argument("--only", default=None, help="comma-separated integrand names")
    args = parser.parse_args()
    integrands = [(name, f) for name, f in INTEGRANDS.items() if f.exact != 0] + [(u.name, u) for u in UNSEEN]
    if args.only:
        integrands = [(name, f) for name, f in integrands if name in args.only.split(",")]
    rows = []
    for name, f in integrands:
        for rtol in RTOLS:
            cell = dict(auto=run(f, f.domain, rtol, "auto", args.seed, args.n_max))
            cell.update({m: run_alone(f, f.domain, rtol, m, args.seed, args.n_max) for m in FAMILIES})
            reached = {m: cell[m]["evaluations"] for m in FAMILIES if cell[m]["converged"]}
            best = min(reached, key=reached.get) if reached else None
            auto = cell["auto"]
            ratio = auto["evaluations"] / reached[best] if best and auto["converged"] else None
            if best and not auto["converged"]:  # the best family alone fit n_max, auto's overhead did not
                cell["auto_4x_n_max"] = run(f, f.domain, rtol, "auto", args.seed, 4 * args.n_max)
                if cell["auto_4x_n_max"]["converged"]:
                    ratio = cell["auto_4x_n_max"]["evaluations"] / reached[best]
            row = dict(integrand=name, domain=f.domain, rtol=rtol, best=best, ratio=ratio, runs=cell)
            rows.append(row)
            shown = "  ".join(
                f"{m} {cell[m]['evaluations'] if cell[m]['converged'] else '-'}" for m in ("auto", *FAMILIES)
            )
            print(f"{name:26s} {rtol:7.0e}  {shown}  chose {auto['chosen']}  best {best}  ratio "
                  f"{'-' if ratio is None else f'{ratio:.2f}'}", flush=True)  # fmt: skip
    ratios = [r["ratio"] for r in rows if r["ratio"] is not None]
    missed = [r for r in rows if r["best"] and r["ratio"] is None]
    summary = dict(
        cells=len(rows),
        cells_some_family_reached=sum(1 for r in rows if r["best"]),
        auto_missed_where_a_family_reached=len(missed),
        auto_needed_4x_n_max=sum(1 for r in rows if "auto_4x_n_max" in r["runs"]),
        within_2x=sum(1 for x in ratios if x <= 2),
        median_ratio=float(np.median(ratios)) if ratios else None,
        max_ratio=max(ratios) if ratios else None,
    )
    print(json.dumps(summary))
    if args.json:
        args.json.write_text(
            json.dumps(
                dict(
                    **run_header(),
                    n_max=args.n_max,
                    seed=args.seed,
                    summary=summary,
                    rows=rows,
                ),
                indent=1,
            )
        )


if __name__ == "__main__":
    main()
