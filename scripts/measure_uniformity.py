"""Measure how far each T0 map is from uniform: the numbers quoted in the README.

Draws N points of the unit square, maps them onto T0 with each method and
counts them in 20 x 20 cells of equal area: the cells are the images of the
unit square's 20 x 20 grid under the ``equal_area`` map, which is exactly
area-preserving (its uniformity is tested against independent (phi, cos theta)
bins in tests/test_uniformity.py).  A uniform map puts 1x the mean count in
each cell, up to noise; the table shows the smallest and largest ratio, the
chi^2 test of ``symsphere.stats`` against the uniform density on T0, and the
range of the exact density relative to uniform, 12/pi.

    python scripts/measure_uniformity.py [--n 10000000] [--seed 0]
"""

import argparse

import numpy as np

import symsphere
from symsphere.stats import chi2_test, uniform_pdf

CELLS = 20


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=10**7, help="points per method (default 1e7)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    print(f"N = {args.n:.3g} points per method, seed {args.seed}, {CELLS}x{CELLS} equal-area cells of T0\n")
    print("| method | min count / uniform | max count / uniform | chi² p-value vs uniform | density / (12/π) on T0 |")
    print("|---|---|---|---|---|")
    for method in symsphere.METHODS:
        rng = np.random.default_rng(args.seed)
        p = symsphere.square_to_triangle(rng.random((args.n, 2)), method)
        cell = np.minimum((symsphere.triangle_to_square(p, "equal_area") * CELLS).astype(int), CELLS - 1)
        ratio = np.bincount(cell[:, 0] * CELLS + cell[:, 1], minlength=CELLS**2) / (args.n / CELLS**2)
        result = chi2_test(p, uniform_pdf("triangle"), "triangle")
        density = symsphere.square_to_triangle_pdf(p, method) / (12 / np.pi)
        print(
            f"| {method} | {ratio.min():.2f} | {ratio.max():.2f} | {result.p_value:.3g} "
            f"| {density.min():.2f} – {density.max():.3g} (unbounded at (0,0,1)) |"
            if method != "equal_area"
            else f"| {method} | {ratio.min():.2f} | {ratio.max():.2f} | {result.p_value:.3g} | 1 |"
        )


if __name__ == "__main__":
    main()
