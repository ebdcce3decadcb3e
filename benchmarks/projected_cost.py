"""Per-sample cost of the Dr.Jit projected-solid-angle map against Arvo's solid-angle map, in one process.

    .venv/bin/python benchmarks/projected_cost.py --json benchmarks/results/FILE.json

llvm_ad_rgb.  Every lane has its own triangle (random vertices about a random unit normal, most of them
above the horizon, some cut by it: what a shading point sees of a light's triangles) and its own point of
the square.  Cases, each in the precision of its inputs (``f32``: ``mi.Vector3f``, ``f64``:
``mi.Vector3d``):

* ``arvo``    -- ``symsphere.mitsuba._warps.square_to_spherical_triangle`` (the solid-angle map);
* ``E``       -- ``symsphere.mitsuba._projected.projected_solid_angle`` alone (what choosing a triangle
                 evaluates for each triangle);
* ``sample``  -- ``square_to_projected_triangle`` alone;
* ``projected`` -- ``projected_solid_angle`` + ``square_to_projected_triangle`` in one kernel (choosing
                 one triangle and sampling it).

A case's per-sample cost is (t(N) - t(n)) / (N - n) for a launch of N = --lanes and of n = --small lanes
(the difference removes the tracing and launch overhead, which a render pays once per kernel), in wall
time and in this process's CPU time (Dr.Jit runs --threads worker threads, default 1, so that CPU time
is the kernel's work, less disturbed by other processes on a shared machine); each round times every
case once, in turn, and the medians over --rounds rounds are reported, with each case's ratio to
``arvo`` in the same precision.  Ratios of the same run only.
"""

from __future__ import annotations

import argparse
import datetime
import json
import statistics
import time

import numpy as np
from _machine import cpu_name, cpu_snapshot, others_cpu

CASES = ("arvo", "E", "sample", "projected")
PRECISIONS = ("f32", "f64")


def _triangles(rng, count):
    """(vertices (count, 3, 3), normals (count, 3), uv (count, 2)): triangles about 1 away from a point."""
    n = rng.standard_normal((count, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    centre = rng.standard_normal((count, 3)) + 1.5 * n
    centre *= rng.uniform(0.3, 3.0, (count, 1)) / np.linalg.norm(centre, axis=1, keepdims=True)
    tri = centre[:, None, :] + rng.uniform(0.05, 1.5, (count, 1, 1)) * rng.standard_normal((count, 3, 3))
    return tri, n, rng.random((count, 2))


def _inputs(mi, dr, tri, n, uv, precision):
    vector, real = (mi.Vector3f, mi.Float) if precision == "f32" else (mi.Vector3d, mi.Float64)
    dtype = np.float32 if precision == "f32" else np.float64
    args = [vector(*(np.ascontiguousarray(tri[:, i, j], dtype=dtype) for j in range(3))) for i in range(3)]
    args.append(vector(*(np.ascontiguousarray(n[:, j], dtype=dtype) for j in range(3))))
    sample = (real(uv[:, 0].astype(dtype)), real(uv[:, 1].astype(dtype)))
    dr.eval(args, sample)
    return args, sample


def _run(mi, dr, case, args, sample):
    from symsphere.mitsuba import _projected, _warps

    a, b, c, n = args
    if case == "arvo":
        out = _warps.square_to_spherical_triangle(sample, a, b, c)
    elif case == "E":
        out = _projected.projected_solid_angle(a, b, c, n)
    else:
        point = mi.Point2f(mi.Float(sample[0]), mi.Float(sample[1]))
        if type(a.x) is mi.Float64:
            point = mi.Point2d(sample[0], sample[1])
        out = _projected.square_to_projected_triangle(a, b, c, n, point)
        if case == "projected":
            out = (*out, _projected.projected_solid_angle(a, b, c, n))
    dr.eval(out)
    dr.sync_thread()


def _time(mi, dr, case, inputs):
    """(wall, CPU) seconds of one launch (the CPU time of every thread of this process)."""
    t0, c0 = time.perf_counter(), time.process_time()
    _run(mi, dr, case, *inputs)
    return time.perf_counter() - t0, time.process_time() - c0


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--lanes", type=int, default=1 << 21)
    parser.add_argument("--small", type=int, default=1 << 10)
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--threads", type=int, default=1, help="Dr.Jit's worker threads (default 1)")
    parser.add_argument("--json", metavar="FILE")
    args = parser.parse_args(argv)

    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    dr.set_thread_count(args.threads)
    rng = np.random.default_rng(args.seed)
    tri, n, uv = _triangles(rng, args.lanes)
    inputs = {
        (p, size): _inputs(mi, dr, tri[:size], n[:size], uv[:size], p)
        for p in PRECISIONS
        for size in (args.lanes, args.small)
    }
    for p in PRECISIONS:  # compile every kernel once, untimed
        for case in CASES:
            for size in (args.lanes, args.small):
                _run(mi, dr, case, *inputs[(p, size)])
    per_sample = {(p, case): [] for p in PRECISIONS for case in CASES}
    per_sample_cpu = {(p, case): [] for p in PRECISIONS for case in CASES}
    before, t0 = cpu_snapshot(), time.perf_counter()
    for _ in range(args.rounds):
        for p in PRECISIONS:
            for case in CASES:
                big = _time(mi, dr, case, inputs[(p, args.lanes)])
                small = _time(mi, dr, case, inputs[(p, args.small)])
                per_sample[(p, case)].append((big[0] - small[0]) / (args.lanes - args.small))
                per_sample_cpu[(p, case)].append((big[1] - small[1]) / (args.lanes - args.small))
    load = others_cpu(before, cpu_snapshot(), time.perf_counter() - t0)
    rows = []
    for p in PRECISIONS:
        arvo = statistics.median(per_sample[(p, "arvo")])
        arvo_cpu = statistics.median(per_sample_cpu[(p, "arvo")])
        for case in CASES:
            ns = statistics.median(per_sample[(p, case)])
            cpu = statistics.median(per_sample_cpu[(p, case)])
            rows.append({
                "precision": p, "case": case, "ns_per_sample": 1e9 * ns, "vs_arvo": ns / arvo,
                "cpu_ns_per_sample": 1e9 * cpu, "cpu_vs_arvo": cpu / arvo_cpu,
            })  # fmt: skip
            print(
                f"{p} {case:10s} {1e9 * ns:8.1f} ns/sample  {ns / arvo:6.2f}x arvo   CPU {1e9 * cpu:8.1f} ns  {cpu / arvo_cpu:6.2f}x"
            )
    if load is not None:
        print(f"others' CPU share while timing: {load['share_of_all_cpus']:.0%}")
    if args.json:
        record = {
            "command": "python benchmarks/projected_cost.py " + " ".join(argv or __import__("sys").argv[1:]),
            "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
            "cpu": cpu_name(),
            "lanes": args.lanes,
            "small": args.small,
            "rounds": args.rounds,
            "threads": args.threads,
            "others_cpu_share": None if load is None else load["share_of_all_cpus"],
            "rows": rows,
        }
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(record, f, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
