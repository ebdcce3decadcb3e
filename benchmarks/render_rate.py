"""Paths per second of the renderer on smallpt's Cornell box, per sampler: a before/after probe.

Written for ``compare_revisions.py --same-script`` (it uses only ``symsphere.render.render`` and
``cornell``, which every revision has): each sampler renders 128 x 96 pixels at 48 spp, twice, after
an untimed small render that loads (or compiles) its kernel; reported is the better of the two, as
M paths per second of process CPU time on one thread (``threads=1``: the kernel's own speed, less
sensitive to a shared machine's load) and of wall time on all threads.

Usage::

    python benchmarks/render_rate.py --json out.json
    python benchmarks/compare_revisions.py --base db6d760 --rate --same-script --keys . -- benchmarks/render_rate.py
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from symsphere.render import cornell, render

SAMPLERS = ("cosine", "symmetric_sobol", "symmetric_cosine")
WIDTH, HEIGHT, SPP = 128, 96, 48


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", type=Path, help="write the numbers here")
    parser.add_argument("--samplers", nargs="+", default=list(SAMPLERS))
    args = parser.parse_args(argv)
    for sampler in args.samplers:  # untimed: load or compile the kernel
        render(cornell(), width=16, height=12, spp=24, sampler=sampler, progress=False, seed=1)
    out: dict[str, float] = {}
    for sampler in args.samplers:
        for threads, clock, label in ((1, time.process_time, "1 thread, CPU"), (None, time.perf_counter, "wall")):
            best = 0.0
            for _ in range(2):
                start = clock()
                render(cornell(), width=WIDTH, height=HEIGHT, spp=SPP, sampler=sampler, seed=2, threads=threads)
                best = max(best, WIDTH * HEIGHT * SPP / (clock() - start) / 1e6)
            out[f"{sampler}, {label}"] = round(best, 4)
    print(json.dumps(out, indent=1))
    if args.json:
        args.json.write_text(json.dumps(out))


if __name__ == "__main__":
    main()
