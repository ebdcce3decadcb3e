"""A NaN/inf scan of the projected-solid-angle map of a triangle, numpy (float64, float32) and Dr.Jit.

    .venv/bin/python benchmarks/scan_projected_triangle.py --triangles 10000 --samples 10000

Triangles (an eighth each): random vertices on the sphere; tiny, 10^-U(2, 4.5) rad across; slivers whose
third vertex lies 10^-U(3, 8) off the arc between the other two; nearly a hemisphere (three vertices
10^-U(1, 4.5) above a great circle); needles (one edge 10^-U(3, 7) long); cut by the horizon (vertices
within 0.3 of it on both sides); grazing (one vertex 10^-U(1, 8) above the horizon, the others below);
edge-on (all three within 10^-U(4, 9) of the horizon, either side).  The normal is random for the first
five kinds, and the triangle is placed about it for the last three.  Each triangle gets --samples points of
the square (uniform, with 0, 1e-300, 1 - 1e-16, 1 mixed in).

numpy (``square_to_projected_triangle``, float64 and float32 outputs): counted are non-finite or non-unit
directions, directions below the horizon or outside the triangle (float64; the random part of the
square), non-finite or out-of-range inverses, non-finite densities; a triangle refused by the map
(ValueError: below 1e-12 sr, or nothing above the horizon) is counted and another drawn.  Dr.Jit
(``symsphere.mitsuba._projected``, llvm_ad_rgb, one triangle per lane, with --drjit-samples per
triangle; --drjit-precision: float32 in, out and inside, float64 likewise, or both): non-finite or
non-unit directions, non-finite or negative densities, directions below the horizon where the density
is positive, and the distance of each direction from the numpy float64 map's on the same float32 inputs (max and quantiles; the refused triangles must give pdf 0).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _scan import timed, write

from symsphere.warps import (
    projected_triangle_to_square,
    square_to_projected_triangle,
    square_to_projected_triangle_pdf,
)

KINDS = ("random", "tiny", "sliver", "hemisphere", "needle", "straddling", "grazing", "edge_on")


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _triangle(kind, rng):
    """(vertices (3, 3), normal (3,))."""
    g = _unit(rng.standard_normal((3, 3)))
    n = _unit(rng.standard_normal(3))
    centre = g[0]
    t = _unit(np.cross(centre, g[1]))
    b = np.cross(centre, t)
    if kind == "random":
        return g, n
    if kind == "tiny":
        s = 10 ** -rng.uniform(2, 4.5)
        angles = rng.uniform(0, 2 * np.pi, 3)
        return _unit(centre + s * (np.cos(angles)[:, None] * t + np.sin(angles)[:, None] * b)), n
    if kind == "sliver":
        a, c = g[0], g[1]
        m = _unit(rng.uniform(0.05, 0.95) * a + (1 - rng.uniform(0.05, 0.95)) * c)
        off = 10 ** -rng.uniform(3, 8) * _unit(np.cross(a, c))
        tri = np.array([a, c, _unit(m + off)])
        return tri[rng.permutation(3)], n
    if kind == "hemisphere":
        z = 10 ** -rng.uniform(1, 4.5)
        phi = rng.uniform(0, 2 * np.pi) + np.array([0, 2 * np.pi / 3, 4 * np.pi / 3]) + rng.uniform(-0.3, 0.3, 3)
        return _unit(np.cos(phi)[:, None] * t + np.sin(phi)[:, None] * b + z * centre), n
    if kind == "needle":
        s = 10 ** -rng.uniform(3, 7)
        return np.array([centre, _unit(centre + s * t), g[2]]), n
    # about the normal: local (x, y) on the horizon circle, z the height
    phi = rng.uniform(0, 2 * np.pi, 3)
    if kind == "straddling":
        z = rng.uniform(-0.3, 0.3, 3)
        z[0], z[1] = abs(z[0]), -abs(z[1])
    elif kind == "grazing":
        z = -rng.uniform(0.01, 0.5, 3)
        z[0] = 10 ** -rng.uniform(1, 8)
    else:  # edge-on
        z = 10 ** -rng.uniform(4, 9, 3) * rng.choice([-1.0, 1.0], 3)
    local = np.column_stack([np.cos(phi), np.sin(phi), z])
    tt = _unit(np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0]))
    bb = np.cross(n, tt)
    return _unit(local @ np.array([tt, bb, n])), n


def _draw(kind, rng, uv):
    """A triangle the numpy map accepts and its directions, and how many were refused before it."""
    refused = 0
    while True:
        tri, n = _triangle(kind, rng)
        try:
            return tri, n, square_to_projected_triangle(uv, *tri, n), refused
        except ValueError:
            refused += 1


def scan_numpy(dtype, triangles, samples, seed):
    rng = np.random.default_rng(seed)
    keys = ("samples", "refused", "nonfinite", "nonunit", "below", "outside", "bad_inverse", "bad_pdf")
    counts = dict.fromkeys(keys, 0)
    edge = np.array([0.0, 1e-300, 1 - 1e-16, 1.0])
    for i in range(triangles):
        uv = rng.random((samples, 2))
        uv[: samples // 50] = rng.choice(edge, size=(samples // 50, 2))
        uv = uv.astype(dtype)
        tri, n, d, refused = _draw(KINDS[i % len(KINDS)], rng, uv)
        counts["refused"] += refused
        counts["samples"] += samples
        counts["nonfinite"] += int(np.sum(~np.all(np.isfinite(d), axis=1)))
        d64 = d.astype(np.float64)
        counts["nonunit"] += int(np.sum(np.abs(np.linalg.norm(d64, axis=1) - 1) > 4 * np.finfo(dtype).eps))
        pdf = square_to_projected_triangle_pdf(d, *tri, n)
        counts["bad_pdf"] += int(np.sum(~np.isfinite(pdf) | (pdf < 0)))
        if dtype == np.float64:
            counts["below"] += int(np.sum(d64 @ n < -1e-15))
            # the random part (edges may round out), above the horizon (on it the density is 0 anyway)
            counts["outside"] += int(np.sum(((pdf == 0) & (d64 @ n > 1e-15))[samples // 50 :]))
        back = projected_triangle_to_square(d, *tri, n)
        counts["bad_inverse"] += int(np.sum(~np.all(np.isfinite(back) & (back >= 0) & (back <= 1), axis=1)))
    return counts


def scan_drjit(triangles, samples, seed, batch=1000, precision="f32"):
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    from symsphere._testing import mitsuba_projected as mp

    rng = np.random.default_rng(seed)
    counts = dict.fromkeys(("samples", "nonfinite", "nonunit", "bad_pdf", "below", "refused_nonzero_pdf"), 0)
    errors, worst = [], {}
    for start in range(0, triangles, batch):
        count = min(batch, triangles - start)
        tris, normals, refs, accepted, kinds = [], [], [], [], []
        uv = rng.random((count * samples, 2)).astype(np.float32)
        uv[:: max(samples // 20, 1)] = rng.choice(
            np.array([0.0, 1.0], dtype=np.float32), size=(len(uv[:: max(samples // 20, 1)]), 2)
        )
        for k in range(count):
            tri, n = _triangle(KINDS[(start + k) % len(KINDS)], rng)
            kinds.append((start + k) % len(KINDS))
            tri32, n32 = tri.astype(np.float32), n.astype(np.float32)
            part = uv[k * samples : (k + 1) * samples].astype(np.float64)
            try:
                refs.append(square_to_projected_triangle(part, *tri32.astype(np.float64), n32.astype(np.float64)))
                accepted.append(True)
            except ValueError:  # no part above the horizon, or below 1e-12 sr: Dr.Jit must give pdf 0 (or tiny)
                refs.append(np.full((samples, 3), np.nan))
                accepted.append(False)
            tris.append(np.broadcast_to(tri32, (samples, 3, 3)))
            normals.append(np.broadcast_to(n32, (samples, 3)))
        tri = np.concatenate(tris)
        n = np.concatenate(normals)
        vector, point, dtype = (
            (mi.Vector3d, mi.Point2d, np.float64) if precision == "f64" else (mi.Vector3f, mi.Point2f, np.float32)
        )
        args = [vector(*(tri[:, i, j].astype(dtype) for j in range(3))) for i in range(3)]
        args.append(vector(*(n[:, j].astype(dtype) for j in range(3))))
        d, pdf = mp.square_to_projected_triangle(*args, point(*(uv[:, j].astype(dtype) for j in range(2))))
        dr.eval(d, pdf)
        got = np.stack([np.asarray(d.x), np.asarray(d.y), np.asarray(d.z)], axis=1).astype(np.float64)
        pdf = np.asarray(pdf, dtype=np.float64)
        counts["samples"] += len(uv)
        counts["nonfinite"] += int(np.sum(~np.all(np.isfinite(got), axis=1)))
        counts["nonunit"] += int(np.sum(np.abs(np.linalg.norm(got, axis=1) - 1) > 1e-6))
        counts["bad_pdf"] += int(np.sum(~np.isfinite(pdf) | (pdf < 0)))
        cos = np.sum(got * n.astype(np.float64), axis=1) / np.linalg.norm(n.astype(np.float64), axis=1)
        counts["below"] += int(np.sum((pdf > 0) & (cos < -1e-6)))
        ref = np.concatenate(refs)
        ok = np.repeat(np.array(accepted), samples)
        counts["refused_nonzero_pdf"] += int(np.sum(~ok & (pdf > 0)))
        both = ok & (pdf > 0)
        error = np.linalg.norm(got - ref, axis=1)
        errors.append(error[both])
        kind = np.repeat(np.array(kinds), samples)
        for index, name in enumerate(KINDS):
            mine = both & (kind == index)
            if mine.any():
                worst[name] = max(worst.get(name, 0.0), float(error[mine].max()))
    err = np.concatenate(errors)
    counts["direction_error_vs_float64_max_by_kind"] = worst
    counts["direction_error_vs_float64"] = {
        "max": float(err.max()),
        "p99.99": float(np.quantile(err, 0.9999)),
        "p99": float(np.quantile(err, 0.99)),
        "median": float(np.median(err)),
    }
    return counts


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--triangles", type=int, default=10_000)
    parser.add_argument("--samples", type=int, default=10_000)
    parser.add_argument("--float32-triangles", type=int, default=None, help="default: --triangles")
    parser.add_argument("--drjit-triangles", type=int, default=10_000)
    parser.add_argument("--drjit-samples", type=int, default=1000)
    parser.add_argument(
        "--drjit-precision",
        choices=("f32", "f64", "both"),
        default="both",
        help="the Dr.Jit map's inputs (and so its arithmetic)",
    )
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--json", metavar="FILE")
    args = parser.parse_args(argv)
    record = {"args": vars(args)}
    for dtype in (np.float64, np.float32):
        triangles = args.triangles if dtype == np.float64 or args.float32_triangles is None else args.float32_triangles
        timed(record, np.dtype(dtype).name, lambda: scan_numpy(dtype, triangles, args.samples, args.seed))
    for precision in ("f32", "f64") if args.drjit_triangles else ():
        if args.drjit_precision not in (precision, "both"):
            continue
        name = "drjit_float32" if precision == "f32" else "drjit_float64"
        timed(
            record,
            name,
            lambda: scan_drjit(args.drjit_triangles, args.drjit_samples, args.seed + 1, precision=precision),
        )
    write(args.json, record)


if __name__ == "__main__":
    main()
