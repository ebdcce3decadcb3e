"""A NaN/inf scan of Arvo's map on random and adversarial spherical triangles, float32 and float64.

    .venv/bin/python benchmarks/scan_spherical_triangle.py --triangles 10000 --samples 10000

For each dtype, --triangles triangles (a fifth each: random vertices on the sphere; tiny, 10^-U(2, 4.5)
rad across; slivers whose third vertex lies 10^-U(3, 8) off the arc between the other two; nearly a
hemisphere, three vertices 10^-U(1, 4.5) above a great circle; needles, one edge 10^-U(3, 7) long), each
with --samples points of the square (uniform, with the edge values 0, 1e-300, 1 - 1e-16, 1 mixed in).
Counted: non-finite or non-unit directions, directions outside the triangle (float64 only: a float32
direction may leave a triangle narrower than its ulp), non-finite or out-of-range inverses, non-finite
densities; triangles below 1e-12 sr are refused by the map (ValueError), counted apart and replaced.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _scan import timed, write

from symsphere.warps import spherical_triangle_to_square, square_to_spherical_triangle, square_to_spherical_triangle_pdf

KINDS = ("random", "tiny", "sliver", "hemisphere", "needle")


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _triangle(kind, rng):
    g = _unit(rng.standard_normal((3, 3)))
    if kind == "random":
        return g
    centre = g[0]
    t = _unit(np.cross(centre, g[1]))
    b = np.cross(centre, t)
    if kind == "tiny":
        s = 10 ** -rng.uniform(2, 4.5)
        angles = rng.uniform(0, 2 * np.pi, 3)
        return _unit(centre + s * (np.cos(angles)[:, None] * t + np.sin(angles)[:, None] * b))
    if kind == "sliver":
        a, c = g[0], g[1]
        m = _unit(rng.uniform(0.05, 0.95) * a + (1 - rng.uniform(0.05, 0.95)) * c)
        off = 10 ** -rng.uniform(3, 8) * _unit(np.cross(a, c))
        tri = np.array([a, c, _unit(m + off)])
        return tri[rng.permutation(3)]
    if kind == "hemisphere":
        z = 10 ** -rng.uniform(1, 4.5)
        phi = rng.uniform(0, 2 * np.pi) + np.array([0, 2 * np.pi / 3, 4 * np.pi / 3]) + rng.uniform(-0.3, 0.3, 3)
        return _unit(np.cos(phi)[:, None] * t + np.sin(phi)[:, None] * b + z * centre)
    s = 10 ** -rng.uniform(3, 7)  # needle: one edge of length s, the third vertex far away
    return np.array([centre, _unit(centre + s * t), g[2]])


def scan(dtype, triangles, samples, seed):
    rng = np.random.default_rng(seed)
    counts = dict.fromkeys(("samples", "refused", "nonfinite", "nonunit", "outside", "bad_inverse", "bad_pdf"), 0)
    edge = np.array([0.0, 1e-300, 1 - 1e-16, 1.0])
    for i in range(triangles):
        uv = rng.random((samples, 2))
        uv[: samples // 50] = rng.choice(edge, size=(samples // 50, 2))
        uv = uv.astype(dtype)
        while True:  # a triangle below 1e-12 sr is refused: counted, and another of the kind drawn
            tri = _triangle(KINDS[i % len(KINDS)], rng)
            try:
                d = square_to_spherical_triangle(uv, *tri)
                break
            except ValueError:
                counts["refused"] += 1
        counts["samples"] += samples
        finite = np.all(np.isfinite(d), axis=1)
        counts["nonfinite"] += int(np.sum(~finite))
        d64 = d.astype(np.float64)
        counts["nonunit"] += int(np.sum(np.abs(np.linalg.norm(d64, axis=1) - 1) > 4 * np.finfo(dtype).eps))
        pdf = square_to_spherical_triangle_pdf(d, *tri)
        counts["bad_pdf"] += int(np.sum(~np.isfinite(pdf)))
        if dtype == np.float64:
            counts["outside"] += int(np.sum(pdf[samples // 50 :] == 0))  # the random part (edges may round out)
        back = spherical_triangle_to_square(d, *tri)
        counts["bad_inverse"] += int(np.sum(~np.all(np.isfinite(back) & (back >= 0) & (back <= 1), axis=1)))
    return counts


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--triangles", type=int, default=10_000)
    parser.add_argument("--samples", type=int, default=10_000)
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--json", metavar="FILE")
    args = parser.parse_args(argv)
    record = {"args": vars(args)}
    for dtype in (np.float64, np.float32):
        timed(record, np.dtype(dtype).name, lambda: scan(dtype, args.triangles, args.samples, args.seed))
    write(args.json, record)


if __name__ == "__main__":
    main()
