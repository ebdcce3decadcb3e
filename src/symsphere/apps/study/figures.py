"""The study's figures (matplotlib): convergence, discrepancy, density maps and warp pictures.

matplotlib is imported inside the functions that draw, so that importing the study (and building the
``symsphere`` command's parser) does not load it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from ..._typing import ChiDomain, FloatArray, MapMethod, PointSet
from ...integrands import INTEGRANDS, Integrand
from ...peers import PEERS
from ...warps import (
    METHODS,
    T0_VERTICES,
    square_to_spherical_triangle,
    square_to_spherical_triangle_pdf,
    square_to_triangle,
    square_to_triangle_pdf,
)
from .._format import format_p
from .config import WARP_MAPS, StudyConfig, domains
from .results import Progress, Results, key
from .samplers import Sampler, all_samplers

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["density_samplers", "warp_maps", "write_figures"]


_METHOD_COLOURS = {"equal_area": "#1f77b4", "paper1": "#ff7f0e", "paper2": "#d62728"}
_PEER_COLOURS = {
    "classic": "#2ca02c",
    "classic_hemisphere": "#2ca02c",
    "gaussian": "#9467bd",
    "octahedral": "#8c564b",
    "octahedral_hemisphere": "#8c564b",
    "fibonacci_rotated": "#e377c2",
    "fibonacci": "#e377c2",
    "arvo": "#bcbd22",
    "cosine": "#17becf",
    "lebedev": "#000000",
    "lebedev_rotated": "#7f7f7f",
}
_POINT_STYLES = {
    "random": ("-", "o"),
    "stratified": ("--", "s"),
    "sobol": ("-.", "^"),
    "halton": (":", "v"),
    "sobol_interlaced2": ((0, (5, 1, 1, 1)), "D"),
    "sobol_interlaced3": ((0, (3, 1, 1, 1, 1, 1)), "P"),
}


def density_samplers(config: StudyConfig) -> list[Sampler]:
    """The samplers that get a density map: one per name, with random points."""
    seen: set[str] = set()
    out: list[Sampler] = []
    for sampler in all_samplers(config):
        if sampler.points == "random" and sampler.name not in seen and not sampler.is_rule:
            seen.add(sampler.name)
            out.append(sampler)
    return out


def warp_maps(config: StudyConfig) -> list[str]:
    """The maps of :data:`~.config.WARP_MAPS` that *config* has (as a scheme map or a peer)."""
    peers = {p for p, _ in config.sphere_peers + config.hemisphere_peers}
    out: list[str] = []
    for name in WARP_MAPS:
        if name in METHODS:
            if name in config.scheme_methods:
                out.append(name)
        elif name in peers:
            out.append(name)
    return out


def _figure(size: tuple[float, float]) -> Figure:
    # The object-oriented API with an Agg canvas: no pyplot state, no GUI backend (as the demo).
    # Function-level: matplotlib loads only when a figure is drawn.
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(figure)
    return figure


def write_figures(results: Results, build_dir: Path, bar: Progress) -> None:
    """Draw every figure of :func:`~.run.study_files` into *build_dir*, advancing the progress *bar* by one each."""
    config = results.config
    by_label = {(s.name, s.points): s for s in all_samplers(config)}
    for g in config.integrands:
        bar.set_postfix_str(f"figure: convergence {g}", refresh=False)
        _convergence_figure(build_dir / f"convergence_{g}.png", results, INTEGRANDS[g], by_label)
        bar.update(1)
    if "sphere" in domains(config):
        bar.set_postfix_str("figure: discrepancy", refresh=False)
        _discrepancy_figure(build_dir / "discrepancy.png", results, by_label)
        bar.update(1)
    for sampler in density_samplers(config):
        bar.set_postfix_str(f"figure: density {sampler.name}", refresh=False)
        _density_figure(build_dir / f"density_{sampler.name}.png", results, sampler)
        bar.update(1)
    for name in warp_maps(config):
        bar.set_postfix_str(f"figure: warp {name}", refresh=False)
        _warp_figure(build_dir / f"warp_{name}.png", results, name)
        bar.update(1)


def _style(name: str, points: PointSet, method: MapMethod | None = None) -> dict[str, Any]:
    colour = _METHOD_COLOURS[method] if method else _PEER_COLOURS.get(name, "#7f7f7f")
    line, marker = _POINT_STYLES[points]
    return dict(color=colour, linestyle=line, marker=marker, markersize=3.5, linewidth=1.2)


def _convergence_figure(
    path: Path, results: Results, integrand: Integrand, by_label: dict[tuple[str, PointSet], Sampler]
) -> None:
    rows = [r for r in results.convergence if r["integrand"] == integrand.name]
    relative = integrand.exact != 0
    column = "relative_rmse" if relative else "rmse"
    floor = 1e-17
    series: dict[tuple[str, PointSet], list[dict[str, Any]]] = {}
    for r in rows:
        series.setdefault((r["sampler"], r["points"]), []).append(r)
    summary = {(r["sampler"], r["points"]): r for r in results.summary if r["integrand"] == integrand.name}
    figure = _figure((12.5, 5.0))
    left, right = figure.subplots(1, 2, sharey=True)
    values = [max(r[column], floor) for r in rows]
    for (name, points), data in series.items():
        method = by_label[(name, points)].method
        n = np.array([r["n"] for r in data], dtype=float)
        y = np.array([max(r[column], floor) for r in data])
        fit = summary[(name, points)]
        slope = "exact" if fit["status"] == "exact" else f"{fit['slope']:.2f}"
        label = f"{method or name}/{points} ({slope})"
        axes = left if method else right
        axes.loglog(n, y, label=label, **_style(name, points, method))
        if method == "equal_area" and points in ("random", "sobol"):
            right.loglog(
                n,
                y,
                color="0.6",
                linestyle=_POINT_STYLES[points][0],
                linewidth=2.5,
                alpha=0.6,
                label=f"equal_area/{points} ({slope})",
                zorder=0,
            )
    n_all = np.array(sorted({r["n"] for r in rows}), dtype=float)
    top = max(values)
    for axes in (left, right):
        for power, text in ((0.5, "n^-1/2"), (1.0, "n^-1"), (1.5, "n^-3/2")):
            guide = top * (n_all / n_all[0]) ** (-power)
            axes.loglog(n_all, guide, color="0.3", linewidth=0.6, linestyle=(0, (1, 3)))
            # Inside the axes, left of the guide's last point: to its right it was clipped at the figure's edge.
            axes.annotate(
                text,
                (n_all[-1], guide[-1]),
                fontsize=7,
                color="0.3",
                xytext=(-2, 2),
                textcoords="offset points",
                ha="right",
                va="bottom",
            )
        axes.set_xlabel("n (evaluations of f)")
        axes.grid(True, which="major", linewidth=0.3)
        axes.legend(fontsize=6.5, ncol=2 if axes is left else 1, loc="lower left")
    left.set_ylabel(("relative " if relative else "") + f"RMSE over {results.config.repetitions} repetitions")
    left.set_title("the symmetric scheme (map/points, fitted slope)", fontsize=9)
    right.set_title("peers (grey: equal_area/random and /sobol)", fontsize=9)
    figure.suptitle(f"{integrand.name} on the {integrand.domain}: exact {integrand.exact:.12g}", fontsize=10)
    figure.savefig(path, dpi=90)


def _discrepancy_figure(path: Path, results: Results, by_label: dict[tuple[str, PointSet], Sampler]) -> None:
    figure = _figure((16.5, 6.2))
    scheme, weighted_axes, peers = figure.subplots(1, 3, sharey=True)
    groups: dict[tuple[str, PointSet], list[dict[str, Any]]] = {}
    for row in results.discrepancy:
        groups.setdefault((row["sampler"], row["points"]), []).append(row)
    fits = {(f["sampler"], f["points"]): f for f in results.discrepancy_fits}
    for (name, points), rows in groups.items():
        method = by_label[(name, points)].method
        n = np.array([r["n"] for r in rows], dtype=float)
        fit = fits[(name, points)]["fit"]
        slope = f" ({fit.slope:.2f})" if fit is not None else ""
        label = f"{method or name}/{points}{slope}"
        axes = scheme if method else peers
        axes.loglog(n, [r["discrepancy_rms"] for r in rows], label=label, **_style(name, points, method))
        if method:
            weighted = fits[(name, points)]["weighted_fit"]
            wslope = f" ({weighted.slope:.2f})" if weighted is not None else ""
            weighted_axes.loglog(
                n,
                [r["weighted_discrepancy_rms"] for r in rows],
                label=f"{method}/{points}{wslope}",
                **_style(name, points, method),
            )
    n_all = np.array(sorted({r["n"] for r in results.discrepancy}), dtype=float)
    for axes in (scheme, weighted_axes, peers):
        axes.loglog(
            n_all,
            np.sqrt(1.0 / (3.0 * n_all)),
            color="k",
            linewidth=1.0,
            linestyle=(0, (4, 2)),
            label="√(1/(3N)): i.i.d. uniform",
        )
        first = math.sqrt(1.0 / (3.0 * n_all[0])) / 3
        axes.loglog(
            n_all,
            first * (n_all / n_all[0]) ** -0.75,
            color="0.4",
            linewidth=0.7,
            linestyle=(0, (1, 2)),
            label="N^-3/4 (the optimal order)",
        )
        axes.set_xlabel("N (points)")
        axes.grid(True, linewidth=0.3)
        axes.legend(fontsize=6.5, ncol=2 if axes is not peers else 1, loc="upper center", bbox_to_anchor=(0.5, -0.13))
    scheme.set_ylabel(f"cap L2 discrepancy D (rms over {results.config.discrepancy_repetitions} sets)")
    scheme.set_title("the scheme: all N directions, equal weights 1/N", fontsize=9)
    weighted_axes.set_title("the scheme with the estimator's weights 1/(N 4π pdf)", fontsize=9)
    peers.set_title("peers (equal weights)", fontsize=9)
    figure.suptitle(
        "Spherical-cap L2 discrepancy, exact by Stolarsky's invariance principle (fitted slope)", fontsize=10
    )
    figure.savefig(path, dpi=80)


def _density_figure(path: Path, results: Results, sampler: Sampler) -> None:
    from matplotlib.colors import LogNorm  # function-level: see _figure

    n = results.config.density_samples
    n -= n % sampler.multiple
    d = sampler.sample(n, results.seed_sequence(4, key(sampler.label)))
    hemisphere = sampler.domain == "hemisphere"
    n_phi, n_cos = 72, 18 if hemisphere else 36
    phi_edges = np.linspace(-math.pi, math.pi, n_phi + 1)
    cos_edges = np.linspace(0.0 if hemisphere else -1.0, 1.0, n_cos + 1)
    phi = np.arctan2(d[:, 1], d[:, 0])
    counts, _, _ = np.histogram2d(phi, np.clip(d[:, 2], -1.0, 1.0), bins=(phi_edges, cos_edges))
    ratio = counts / (len(d) / (n_phi * n_cos))
    ratio = np.clip(ratio, 1 / 8, 8)
    figure = _figure((6.4, 3.6))
    axes = figure.add_subplot(projection="mollweide")
    mesh = axes.pcolormesh(
        phi_edges,
        np.arcsin(cos_edges),
        ratio.T,
        cmap="RdBu_r",
        norm=LogNorm(vmin=0.25, vmax=4.0),
        shading="flat",
        rasterized=True,
    )
    axes.grid(True, linewidth=0.3)
    axes.set_xticklabels([])
    axes.tick_params(labelsize=6)
    figure.colorbar(mesh, ax=axes, shrink=0.7, label="density / uniform", ticks=[0.25, 0.5, 1, 2, 4], format="%g")
    low, high = float(ratio.min()), float(ratio.max())
    axes.set_title(
        f"{sampler.name} (random points): {len(d)} directions\nin {n_phi}×{n_cos} equal-area bins, "
        f"density/uniform from {low:.2f} to {high:.2f}",
        fontsize=8,
    )
    figure.savefig(path, dpi=90)


# What the title of a warp picture says about the map (a caption, not a fact the code relies on).
_WARP_CAPTIONS = {
    "arvo": "Arvo 1995",
    "classic": "z = 1 - 2u, φ = 2πv",
    "octahedral": "Clarberg 2008",
    "cosine": "concentric disk + Malley",
}


_Warp = tuple[ChiDomain, Callable[[FloatArray], FloatArray], Callable[[npt.ArrayLike], FloatArray], str]


def _warp_setup(name: str) -> _Warp:
    """(domain, forward uv -> d, pdf, title) of a map that gets a warp picture."""
    if name in METHODS:
        method: MapMethod = name  # narrowed by the test above, kept for the lambdas
        return (
            "triangle",
            lambda uv: square_to_triangle(uv, method),
            lambda p: square_to_triangle_pdf(p, method),
            f"{name}: unit square -> T0",
        )
    peer = PEERS[name]
    caption = f" ({_WARP_CAPTIONS[name]})" if name in _WARP_CAPTIONS else ""
    if peer.forward is not None:
        return (peer.domain, peer.forward, peer.pdf, f"{name}: unit square -> {peer.domain}{caption}")
    if peer.is_map and peer.orbit_size == 48:  # a map onto T0, then the 48 images (Peer.forward is None)
        return (
            "triangle",
            lambda uv: square_to_spherical_triangle(uv, *T0_VERTICES),
            lambda p: square_to_spherical_triangle_pdf(p, *T0_VERTICES),
            f"{name}: unit square -> T0{caption}",
        )
    raise ValueError(f"no warp picture for {name!r}")  # pragma: no cover


def _phi_cos(d: FloatArray) -> tuple[FloatArray, FloatArray]:
    return np.arctan2(d[..., 1], d[..., 0]), np.clip(d[..., 2], -1.0, 1.0)


def _broken(phi: FloatArray, cos: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Insert NaN where a curve jumps across phi = +-pi, so that it is not drawn across the picture."""
    jumps = np.nonzero(np.abs(np.diff(phi)) > math.pi)[0]
    return np.insert(phi, jumps + 1, np.nan), np.insert(cos, jumps + 1, np.nan)


def _warp_figure(path: Path, results: Results, name: str) -> None:
    from matplotlib.colors import LogNorm  # function-level: see _figure

    from ...bins import bin_probabilities, equal_area_bins
    from ...stats import chi2_test, uniform_pdf  # scipy.stats: ~1 s

    domain, forward, pdf, title = _warp_setup(name)
    bins = {"triangle": (20, 20), "sphere": (48, 24), "hemisphere": (48, 12)}[domain]
    figure = _figure((16.5, 4.2))
    grid, cloud, observed_axes, expected_axes = figure.subplots(1, 4)
    # (1) The grid lines of the unit square, warped.
    t = np.linspace(0.0, 1.0, 401)
    for value in np.linspace(0.0, 1.0, 11):
        for which, colour in ((0, "#1f77b4"), (1, "#d62728")):
            uv = np.stack([np.full_like(t, value), t] if which == 0 else [t, np.full_like(t, value)], axis=-1)
            phi, cos = _phi_cos(forward(uv))
            if domain != "triangle":
                phi, cos = _broken(phi, cos)
            grid.plot(np.degrees(phi), cos, color=colour, linewidth=0.7)
    grid.set_title("grid of the square (blue: u = const, red: v = const)", fontsize=8)
    # (2) A point cloud, coloured by u.
    rng = np.random.default_rng(results.seed_sequence(5, key(name)))
    uv = rng.random((4096, 2))
    phi, cos = _phi_cos(forward(uv))
    cloud.scatter(np.degrees(phi), cos, c=uv[:, 0], s=1.0, cmap="viridis", linewidths=0, rasterized=True)
    cloud.set_title("4096 random points (colour: u)", fontsize=8)
    # (3), (4) Histogram of the map's points and its pdf integrated over the same bins, both / uniform.
    samples = forward(rng.random((results.config.warp_samples, 2)))
    result = chi2_test(samples, pdf, domain, bins=bins)
    uniform = len(samples) * bin_probabilities(uniform_pdf(domain), domain, bins)
    full = uniform.max()
    with np.errstate(divide="ignore", invalid="ignore"):
        observed = np.where(uniform > 0.3 * full, result.observed / np.where(uniform > 0, uniform, 1), np.nan)
        expected = np.where(uniform > 0.3 * full, result.expected / np.where(uniform > 0, uniform, 1), np.nan)
    phi_edges, cos_edges = equal_area_bins(domain, bins)
    norm = LogNorm(vmin=0.25, vmax=4.0)

    def clipped(a: FloatArray) -> FloatArray:
        return np.clip(a, 1 / 8, 8)

    observed_axes.pcolormesh(np.degrees(phi_edges), cos_edges, clipped(observed).T, cmap="RdBu_r", norm=norm)
    mesh = expected_axes.pcolormesh(np.degrees(phi_edges), cos_edges, clipped(expected).T, cmap="RdBu_r", norm=norm)
    results.warp_chi2[name] = result.p_value
    observed_axes.set_title(
        f"histogram of {len(samples)} points / uniform (χ² vs own pdf: p = {format_p(result.p_value)})", fontsize=8
    )
    expected_axes.set_title("pdf integrated over the bins / uniform", fontsize=8)
    for axes in (grid, cloud, observed_axes, expected_axes):
        if domain == "triangle":
            phi = np.linspace(0.0, math.pi / 4, 200)
            axes.plot(np.degrees(phi), np.cos(phi) / np.sqrt(1 + np.cos(phi) ** 2), color="k", linewidth=0.8)
            axes.set_xlim(0, 45)
            axes.set_ylim(1 / math.sqrt(3), 1.0)
        else:
            axes.set_xlim(-180, 180)
            axes.set_ylim(0.0 if domain == "hemisphere" else -1.0, 1.0)
        axes.set_xlabel("φ (degrees)")
        axes.tick_params(labelsize=7)
    grid.set_ylabel("cos θ (equal-area coordinates)")
    figure.colorbar(
        mesh, ax=[observed_axes, expected_axes], shrink=0.85, label="/ uniform", ticks=[0.25, 0.5, 1, 2, 4], format="%g"
    )
    figure.suptitle(f"warp of {title}", fontsize=10)
    figure.savefig(path, dpi=80)
