"""A NaN/inf scan of the Dr.Jit spherical rectangle (symsphere.mitsuba), float64 and float32.

    .venv/bin/python benchmarks/scan_spherical_rectangle_drjit.py --batches 100 --samples 1000000

For each precision, --batches batches of --samples lanes, each lane its own rectangle from the adversarial
generator of tests/mitsuba/test_rectangle.py (a seventh each: random; tiny, 1e-7 sr and below; nearly a
hemisphere; edge-on or within rounding of the plane; grazing; the viewer at a corner or on an edge;
slivers), 10 % of the points on the square's corners and edges: the test's 10^6-sample check, repeated.
Counted: non-finite or non-unit directions, solid angles outside [0, 2 pi], non-finite pdfs, lanes whose
own direction gets pdf 0 although S > 0, pdfs other than 1/S there, inverses outside [0, 1]^2; and the
degenerate lanes (S = 0).
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _scan import timed, write


def _generator():
    path = Path(__file__).resolve().parent.parent / "tests" / "mitsuba" / "test_rectangle.py"
    spec = importlib.util.spec_from_file_location("_test_rectangle", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.adversarial_samples


def scan(mi, sm, f64, batches, samples, seed):
    adversarial_samples = _generator()
    keys = ("samples", "degenerate", "nonfinite", "nonunit", "bad_solid_angle", "bad_pdf", "missed", "pdf_not_1_over_S")
    counts = dict.fromkeys(keys + ("bad_inverse",), 0)
    for batch in range(batches):
        rng = np.random.default_rng((seed, int(f64), batch))
        got, s, pdf, back = adversarial_samples(mi, sm, f64, samples, rng)
        valid = s > 0
        finite = np.all(np.isfinite(got), axis=1)
        counts["samples"] += samples
        counts["degenerate"] += int(np.sum(~valid))
        counts["nonfinite"] += int(np.sum(~finite))
        counts["nonunit"] += int(np.sum(finite & (np.abs(np.linalg.norm(got, axis=1) - 1) > 1e-5)))
        counts["bad_solid_angle"] += int(np.sum(~((s >= 0) & (s <= float(np.float32(2 * np.pi))))))
        counts["bad_pdf"] += int(np.sum(~np.isfinite(pdf) | (~valid & (pdf != 0))))
        counts["missed"] += int(np.sum(valid & (pdf == 0)))
        counts["pdf_not_1_over_S"] += int(np.sum(valid & (pdf > 0) & (np.abs(pdf * s - 1) > 1e-6)))
        counts["bad_inverse"] += int(np.sum(~np.all(np.isfinite(back) & (back >= 0) & (back <= 1), axis=1)))
    return counts


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--batches", type=int, default=100)
    parser.add_argument("--samples", type=int, default=1_000_000)
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--json", metavar="FILE")
    args = parser.parse_args(argv)
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    import symsphere.mitsuba as sm

    record = {"args": vars(args)}
    for f64 in (True, False):
        timed(record, "float64" if f64 else "float32", lambda: scan(mi, sm, f64, args.batches, args.samples, args.seed))
    write(args.json, record)


if __name__ == "__main__":
    main()
