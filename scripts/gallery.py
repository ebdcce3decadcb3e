"""The docs' gallery (docs/results/gallery.md), drawn from the library: ``make gallery``.

    python scripts/gallery.py [--out docs/images/gallery] [--small]

Writes into the folder (created if missing; each file replaced whole):

- ``triangles.png``: the 48 triangles of the sphere (colour: the index k that ``symsphere.fold``
  returns) in the equal-area coordinates (phi, cos theta), with the orbit of one base point of T0;
- ``orbit.png``: an orbit on the sphere in 3-D beside the triangles it visits, the front page's picture;
- ``warp_<name>.png`` for every warp of ``symsphere.warps.WARPS`` onto the sphere, the hemisphere,
  T0 or the wedge: its points (from a scrambled Sobol' set) beside its density relative to uniform;
- ``convergence_integrate.png``: RMSE of ``symsphere.integrate`` on exp(w . a) against n, for random,
  Sobol' and interlaced Sobol' base points and i.i.d. sampling, from fresh runs with fixed seeds;
- ``convergence_render.png``: RMSE against spp of the renderer's samplers, replotted from
  ``docs/images/render_convergence.json`` (written by ``python benchmarks/bench_render.py``);
- ``renders.png``: the Cornell box as each sampler rendered it, side by side (from docs/images).

``--small`` draws fewer points, smaller sizes and fewer repetitions (the test, tests/test_gallery.py,
runs it so, into a temporary folder).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import symsphere as ss
from symsphere.warps import WARPS

ROOT = Path(__file__).resolve().parent.parent
IMAGES = ROOT / "docs" / "images"
RENDERS = ("symmetric_sobol", "symmetric", "equal_area", "paper1", "cosine", "reference")
BASE_POINT = np.array([0.35, 0.2, 0.915])  # inside T0 = {z >= x >= y >= 0}


def _save(figure: plt.Figure, path: Path) -> None:
    # Whole or not at all: a reader of the folder never sees half a PNG.
    fd, tmp = tempfile.mkstemp(suffix=".png", dir=path.parent)
    os.close(fd)
    try:
        figure.savefig(tmp, dpi=100, bbox_inches="tight")
        os.replace(tmp, path)
    finally:
        plt.close(figure)
        if os.path.exists(tmp):
            os.unlink(tmp)


def _equal_area(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return np.arctan2(d[:, 1], d[:, 0]), d[:, 2]


# (phi, cos theta) ranges that hold each domain: T0 = {z >= x >= y >= 0}, the wedge 0 <= phi <= pi/4.
RANGES = {
    "sphere": ((-np.pi, np.pi), (-1.0, 1.0)),
    "hemisphere": ((-np.pi, np.pi), (0.0, 1.0)),
    "triangle": ((0.0, np.pi / 4), (1 / np.sqrt(3), 1.0)),
    "wedge": ((0.0, np.pi / 4), (0.0, 1.0)),
}
# the uniform density of each domain, in solid angle: 1 / its area
UNIFORM = {"sphere": 1 / (4 * np.pi), "hemisphere": 1 / (2 * np.pi), "triangle": 12 / np.pi, "wedge": 4 / np.pi}


def _grid(n: int, domain: str = "sphere") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Directions at the centres of an n x n grid of (phi, cos theta) over the domain's range: equal-area cells."""
    (phi0, phi1), (z0, z1) = RANGES[domain]
    phi = phi0 + (np.arange(n) + 0.5) / n * (phi1 - phi0)
    z = z0 + (np.arange(n) + 0.5) / n * (z1 - z0)
    P, Z = np.meshgrid(phi, z)
    r = np.sqrt(1 - Z**2)
    return P, Z, np.stack([r * np.cos(P), r * np.sin(P), Z], axis=-1).reshape(-1, 3)


def triangles(out: Path, n: int) -> None:
    P, Z, d = _grid(n)
    k, _ = ss.fold(d)
    figure, axes = plt.subplots(figsize=(9, 4.2), layout="constrained")
    axes.pcolormesh(P, Z, k.reshape(P.shape), cmap="tab20", shading="auto")
    phi, z = _equal_area(ss.orbit(BASE_POINT))
    axes.scatter(phi, z, s=18, c="black", label="the orbit of one point of T0 (48 directions)")
    axes.set(xlabel="φ", ylabel="cos θ", title="the 48 triangles (colour: k of symsphere.fold) and one orbit")
    axes.legend(loc="lower right", fontsize=8)
    _save(figure, out / "triangles.png")


def orbit_3d(out: Path) -> None:
    figure = plt.figure(figsize=(10, 3.6), layout="constrained")
    axes = figure.add_subplot(1, 3, 1, projection="3d")
    u, v = np.mgrid[0 : 2 * np.pi : 60j, 0 : np.pi : 30j]
    axes.plot_wireframe(np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v), color="0.85", linewidth=0.4)
    t = np.linspace(0, 2 * np.pi, 200)
    for plane in ("xy", "xz", "yz"):  # the coordinate and bisector planes cut the sphere into 48 triangles
        c, s = np.cos(t), np.sin(t)
        circle = {"xy": (c, s, 0 * t), "xz": (c, 0 * t, s), "yz": (0 * t, c, s)}[plane]
        axes.plot(*circle, color="0.4", linewidth=0.8)
    for a, b in ((0, 1), (0, 2), (1, 2)):
        for sign in (1, -1):
            axis = np.zeros((3, 3))
            axis[a, a], axis[b, a] = 1 / np.sqrt(2), sign / np.sqrt(2)
            third = 3 - a - b
            circle = np.outer(np.cos(t), axis[:, a]) + np.outer(np.sin(t), np.eye(3)[third])
            axes.plot(*circle.T, color="0.6", linewidth=0.5)
    orbit = ss.orbit(BASE_POINT)
    axes.scatter(*orbit.T, c=np.arange(48), cmap="viridis", s=22, depthshade=False)
    axes.set_axis_off()
    axes.set_box_aspect((1, 1, 1), zoom=1.5)
    axes.set_title("one point, its 48 mirror images", fontsize=10)
    flat = figure.add_subplot(1, 3, (2, 3))
    P, Z, d = _grid(200)
    k, _ = ss.fold(d)
    flat.pcolormesh(P, Z, k.reshape(P.shape), cmap="tab20", shading="auto", alpha=0.6)
    phi, z = _equal_area(orbit)
    flat.scatter(phi, z, c=np.arange(48), cmap="viridis", s=22)
    flat.set(xlabel="φ", ylabel="cos θ", title="the 48 triangles (equal-area map), one image in each")
    _save(figure, out / "orbit.png")


def warps(out: Path, n_points: int, n_grid: int) -> list[str]:
    names = []
    uv = ss.points.unit_square_points(n_points, "sobol", rng=0)
    for name, warp in WARPS.items():
        if warp.domain == "disk":
            continue  # a map of the plane: no density on the sphere to show
        points = warp.forward(uv)
        P, Z, d = _grid(n_grid, warp.domain)
        density = warp.pdf(d).reshape(P.shape)
        uniform = UNIFORM[warp.domain]
        figure, (left, right) = plt.subplots(1, 2, figsize=(10, 3.6), layout="constrained")
        phi, z = _equal_area(points)
        left.scatter(phi, z, s=0.5, c="C0")
        left.set(xlabel="φ", ylabel="cos θ", title=f"{name}: {n_points} points of a Sobol' set")
        with np.errstate(divide="ignore"):
            shown = np.where(density > 0, density / uniform, np.nan)
        image = right.pcolormesh(P, Z, shown, cmap="magma", shading="auto", vmin=0, vmax=np.nanpercentile(shown, 99))
        figure.colorbar(image, ax=right, label="density / uniform")
        right.set(xlabel="φ", title=f"{name}: pdf relative to uniform on its domain")
        for axes in (left, right):
            axes.set_xlim(*RANGES[warp.domain][0])
            axes.set_ylim(*RANGES[warp.domain][1])
        _save(figure, out / f"warp_{name}.png")
        names.append(name)
    return names


def convergence_integrate(out: Path, k_max: int, repetitions: int) -> None:
    a = np.array([0.3, -0.5, 0.7])
    f = lambda w: np.exp(w @ a)  # noqa: E731
    exact = 4 * np.pi * np.sinh(np.linalg.norm(a)) / np.linalg.norm(a)
    sizes = [48 * 2**k for k in range(2, k_max + 1)]
    figure, axes = plt.subplots(figsize=(6, 4), layout="constrained")
    for points in ("random", "sobol", "sobol_interlaced3"):
        rmse = []
        for n in sizes:
            seeds = np.random.SeedSequence([n, len(points)]).spawn(repetitions)
            errors = [ss.integrate(f, n=n, points=points, rng=s, replicates=1).integral - exact for s in seeds]
            rmse.append(np.sqrt(np.mean(np.square(errors))) / exact)
        axes.loglog(sizes, rmse, "o-", label=f"scheme, {points}")
    rng = np.random.default_rng(1)
    iid = []
    for n in sizes:
        errors = []
        for _ in range(repetitions):
            z = 1 - 2 * rng.random(n)
            phi = 2 * np.pi * rng.random(n)
            r = np.sqrt(1 - z**2)
            d = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
            errors.append(4 * np.pi * np.mean(f(d)) - exact)
        iid.append(np.sqrt(np.mean(np.square(errors))) / exact)
    axes.loglog(sizes, iid, "s--", color="0.4", label="i.i.d. (z = 1 − 2u)")
    axes.set(xlabel="n (evaluations of f)", ylabel="relative RMSE", title=f"exp(ω·a), {repetitions} repetitions")
    axes.legend(fontsize=8)
    _save(figure, out / "convergence_integrate.png")


def convergence_render(out: Path) -> None:
    data = json.loads((IMAGES / "render_convergence.json").read_text(encoding="utf-8"))
    figure, axes = plt.subplots(figsize=(6, 4), layout="constrained")
    for sampler, rmse in data["rmse"].items():
        axes.loglog(data["spp"], rmse, "o-", label=sampler)
    axes.set(xlabel="samples per pixel", ylabel="RMSE against the reference", title="Cornell box, BSDF sampling")
    axes.legend(fontsize=8)
    _save(figure, out / "convergence_render.png")


def renders(out: Path) -> None:
    figure, axes = plt.subplots(1, len(RENDERS), figsize=(2.2 * len(RENDERS), 2.2), layout="constrained")
    for ax, name in zip(axes, RENDERS, strict=True):
        ax.imshow(plt.imread(IMAGES / f"render_cornell_{name}.png"))
        ax.set_title(name, fontsize=8)
        ax.set_axis_off()
    _save(figure, out / "renders.png")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=IMAGES / "gallery", help="folder (default docs/images/gallery)")
    parser.add_argument("--small", action="store_true", help="fewer points and repetitions (the test's run)")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    small = args.small
    triangles(args.out, 48 if small else 400)
    orbit_3d(args.out)
    names = warps(args.out, 512 if small else 4096, 32 if small else 200)
    convergence_integrate(args.out, 6 if small else 14, 4 if small else 16)
    convergence_render(args.out)
    renders(args.out)
    print(f"wrote the gallery into {args.out}: triangles, orbit, {len(names)} warps, convergence, renders")
    return 0


if __name__ == "__main__":
    sys.exit(main())
