"""Seconds of the public densities, of bin probabilities of a density and of a small demo: a before/after probe.

Written for ``compare_revisions.py --same-script`` (it uses only public functions that every revision
since the cold-start work has): ``sphere_pdf`` and ``hemisphere_pdf`` of every map on 786 432 directions
(the validation of the directions included, as a user calls them), ``bin_probabilities`` of
``sphere_pdf(method='paper1')`` on 32 x 16 (phi, cos theta) bins, and a warm
``run_demo(n=480)`` (whose chi-square tests integrate the maps' densities over their bins).  Each is the
median of --repeats runs after one untimed run.

Usage::

    python benchmarks/density_rate.py --json out.json
    python benchmarks/compare_revisions.py --base 901af64 --same-script --keys . -- benchmarks/density_rate.py
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

import symsphere as ss
from symsphere.apps.demo import run_demo
from symsphere.bins import bin_probabilities


def _median_seconds(call, repeats):
    call()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", type=Path, help="write the numbers here")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    d = ss.sample_sphere(48 * 2**14, rng=1)  # 786432 directions
    upper = np.abs(d)
    out: dict[str, float] = {}
    for method in ss.METHODS:
        out[f"sphere_pdf {method}"] = _median_seconds(lambda m=method: ss.sphere_pdf(d, method=m), args.repeats)
        out[f"hemisphere_pdf {method}"] = _median_seconds(
            lambda m=method: ss.hemisphere_pdf(upper, method=m), args.repeats
        )
    out["bin_probabilities of sphere_pdf paper1"] = _median_seconds(
        lambda: bin_probabilities(lambda w: ss.sphere_pdf(w, method="paper1"), "sphere", (32, 16)), args.repeats
    )
    with tempfile.TemporaryDirectory() as folder:
        out["run_demo(n=480)"] = _median_seconds(
            lambda: run_demo(Path(folder) / "demo", n=480, progress=False), max(args.repeats // 2, 1)
        )
    for key, value in out.items():
        print(f"{key:<45} {value:.4f} s")
    if args.json:
        args.json.write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
