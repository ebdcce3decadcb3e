"""The demo: chi-square tests of the three maps, written up as a report and a figure.

``run_demo`` samples the sphere and the hemisphere with every map of
:data:`symsphere.METHODS` and tests the samples, and their folds into the
fundamental triangle T0 = {z >= x >= y >= 0}, against the uniform density;
the paper's maps are also tested against their own densities.  The results
go to ``report.md`` and ``figure.png``; ``render.png`` is a small render of
smallpt's Cornell box with the scheme, described at the end of the report.

Why one direction per orbit is tested
-------------------------------------
Rows ``48 i ... 48 i + 47`` of :func:`~symsphere.sample_sphere` are the
orbit of one base point, so they are not independent, and Pearson's test
assumes independent samples.  The (phi, cos theta) bins are mapped onto each
other by several of the 48 symmetries, so symmetric bins get *identical*
counts and the statistic is a multiple of a chi-square variable with fewer
degrees of freedom: its p-values pile up at 0 and 1 even for an exactly
uniform sampler.  The demo therefore keeps one member of each orbit, chosen
at random; those are independent, and uniform if and only if the map is.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .. import __version__
from .._typing import Float64Array, FloatArray, MapMethod
from .._validation import check_count, check_seed
from ..io import atomic_directory
from ..sampling import hemisphere_pdf, sample_hemisphere, sample_sphere, sphere_pdf
from ..symmetry import fold
from ..warps import METHODS, square_to_triangle_pdf, triangle_warp
from ._format import format_p

if TYPE_CHECKING:  # scipy.stats loads only when a demo runs (see run_demo)
    from ..stats import Chi2Result

__all__ = ["run_demo", "DEMO_FILES", "FAMILY_SIGNIFICANCE"]

DEMO_FILES = ("report.md", "figure.png", "render.png")
"""The files :func:`run_demo` writes; a directory holding only these may be replaced."""

FAMILY_SIGNIFICANCE = 0.01
"""Chance that any of the demo's tests rejects an exactly uniform sampler."""

_DOMAINS = ("sphere", "hemisphere", "triangle")
_SCATTER_ORBITS = 64  # 64 whole orbits = 3072 directions in the scatter plots


@dataclass(frozen=True)
class _Test:
    domain: str
    method: str
    reference: str  # 'uniform' or the method's own name
    samples: FloatArray
    pdf: Callable[[FloatArray], FloatArray]


def run_demo(
    out_dir: str | os.PathLike[str] = "symsphere-demo", n: int = 48 * 2**14, seed: int = 0, progress: bool = True
) -> Path:
    """Test every map for uniformity and write ``report.md``, ``figure.png`` and ``render.png``.

    Parameters
    ----------
    out_dir : str or os.PathLike, optional
        Directory to write.  It is built next to its final place and renamed
        into it only when complete.  An existing *out_dir* is replaced if it
        is empty or holds only an earlier demo's files (:data:`DEMO_FILES`);
        otherwise ``FileExistsError`` is raised before any
        work, so that a mistyped path cannot delete anything.
    n : int, optional
        Directions per sample (sphere and hemisphere, per map), a positive
        multiple of 48.  The tests see ``n / 48`` independent directions on
        the sphere and T0 and ``n / 24`` on the hemisphere (one per orbit, see
        the module docstring).  Default ``48 * 2**14``.
    seed : int, optional
        Seeds all the sampling; the same seed gives the same report.
    progress : bool, optional
        Say on stderr which of the four steps runs (sampling, the tests,
        the figure, the render) and show a progress bar over the tests (the
        bar only on a terminal).

    Returns
    -------
    pathlib.Path
        The path of ``report.md``.

    Notes
    -----
    Per map, the tests against the uniform density are on the sphere, the
    hemisphere, and T0 (the sphere samples folded with
    :func:`~symsphere.fold`).  The paper's maps are also tested against their
    own densities (:func:`~symsphere.sphere_pdf`,
    :func:`~symsphere.hemisphere_pdf`, :func:`~symsphere.square_to_triangle_pdf`), which
    they should pass.  All tests share a Sidak correction, so that an exactly
    uniform sampler fails any of them with probability
    :data:`FAMILY_SIGNIFICANCE`.

    Examples
    --------
    >>> from symsphere.apps.demo import run_demo
    >>> report = run_demo("/tmp/symsphere-demo", n=48 * 2**10, progress=False)  # doctest: +SKIP
    >>> print(report.read_text())  # doctest: +SKIP
    """
    # Function-level: tqdm.auto (~60 ms) and scipy.stats (~1 s) load only when a demo runs.
    from tqdm.auto import tqdm

    from ..stats import chi2_test, one_per_orbit

    n = check_count(n, "n", multiple=48)
    seed_sequence = np.random.SeedSequence(check_seed(seed))
    sampling_seeds = seed_sequence.spawn(2 * len(METHODS))
    choice_rng = np.random.default_rng(seed_sequence.spawn(1)[0])

    def step(number: int, what: str) -> None:
        if progress:
            print(f"demo: step {number}/4: {what}", file=sys.stderr, flush=True)

    from ..render.renderer import compile_in_background  # function-level: numba kernels (see run_demo)

    # A new install: the render's kernel compiles on the second core during steps 1-3.
    with atomic_directory(out_dir, replaceable=DEMO_FILES) as build_dir, compile_in_background() as kernel_ready:
        step(1, f"sampling {n} directions per map and domain ({', '.join(METHODS)}; sphere, hemisphere)")
        tests: list[_Test] = []
        scatter: dict[str, FloatArray] = {}
        for index, method in enumerate(METHODS):
            sphere = sample_sphere(n, method=method, rng=sampling_seeds[2 * index])
            hemisphere = sample_hemisphere(n, method=method, rng=sampling_seeds[2 * index + 1])
            scatter[method] = sphere[: 48 * _SCATTER_ORBITS]
            independent_sphere = one_per_orbit(sphere, 48, choice_rng)
            independent_hemisphere = one_per_orbit(hemisphere, 24, choice_rng)
            tests.extend(_tests_of(method, independent_sphere, independent_hemisphere))

        step(2, f"{len(tests)} chi-square tests")
        results = []
        bar = tqdm(tests, desc="chi-square tests", unit="test", disable=True if not progress else None)
        for test in bar:
            bar.set_postfix_str(f"{test.method} on the {test.domain}")
            results.append(
                chi2_test(
                    test.samples,
                    test.pdf,
                    test.domain,
                    significance=FAMILY_SIGNIFICANCE,
                    test_count=len(tests),
                )
            )

        step(3, "the figure")
        _write_figure(build_dir / "figure.png", tests, results, scatter)
        step(4, "rendering the Cornell box")
        kernel_ready()
        render_lines = _render(build_dir / "render.png", seed)
        shown = len(next(iter(scatter.values())))  # what the scatter plots show: n < 3072 shows all n
        report = _report(tests, results, n, seed, shown) + render_lines
        (build_dir / "report.md").write_text(report, encoding="utf-8")
    return Path(out_dir) / "report.md"


# --- private ------------------------------------------------------------------


def _tests_of(method: MapMethod, sphere: FloatArray, hemisphere: FloatArray) -> list[_Test]:
    from ..stats import uniform_pdf  # function-level: scipy.stats (see run_demo)

    _, base = fold(sphere)  # the whole orbit folds to the same point of T0
    tests = [
        _Test("sphere", method, "uniform", sphere, uniform_pdf("sphere")),
        _Test("hemisphere", method, "uniform", hemisphere, uniform_pdf("hemisphere")),
        _Test("triangle", method, "uniform", base, uniform_pdf("triangle")),
    ]
    if not triangle_warp(method).uniform:
        tests += [
            _Test("sphere", method, method, sphere, lambda d: sphere_pdf(d, method)),
            _Test("hemisphere", method, method, hemisphere, lambda d: hemisphere_pdf(d, method)),
            _Test("triangle", method, method, base, lambda p: square_to_triangle_pdf(p, method)),
        ]
    return tests


def _reference_name(test: _Test) -> str:
    if test.reference == "uniform":
        return "uniform"
    own = {"sphere": "sphere_pdf", "hemisphere": "hemisphere_pdf", "triangle": "square_to_triangle_pdf"}[test.domain]
    return f"own: `{own}(·, '{test.method}')`"


def _format_range(low: float, high: float) -> str:
    return "n/a" if math.isnan(low) else f"{low:.2f}–{high:.2f}"


def _p_equals(p: float) -> str:
    return "p < 1e-300" if p == 0 else f"p = {format_p(p)}"


def _join(words: Iterable[str]) -> str:
    listed = list(words)
    return listed[0] if len(listed) == 1 else ", ".join(listed[:-1]) + " and " + listed[-1]


def _report(tests: list[_Test], results: list[Chi2Result], n: int, seed: int, shown: int) -> str:
    threshold = results[0].threshold
    lines = [
        "# symsphere demo: are the maps uniform?",
        "",
        f"symsphere {__version__}; n = {n} directions per sample, seed {seed}.  "
        f"Each map samples the sphere and the hemisphere (pole (0, 0, 1)).",
        "",
        f"The tests see one randomly chosen direction of each orbit ({n // 48} independent directions "
        f"on the sphere and on T0, {n // 24} on the hemisphere): the 48 (24) directions of an orbit "
        "are not independent, and Pearson's chi-square test on all of them would give meaningless "
        "p-values.  *triangle* is the fundamental triangle T0 = {z >= x >= y >= 0}, into which the "
        "sphere samples are folded with `symsphere.fold`.",
        "",
        f"Bins are equal-area in (φ, cos θ).  {len(results)} tests, Šidák-corrected so that an exactly "
        f"uniform sampler fails any of them with probability {FAMILY_SIGNIFICANCE}: a test passes if "
        f"p ≥ {threshold:.3g}.",
        "",
        "| domain | method | reference pdf | χ² | dof | p-value | result | observed/expected per bin (min–max) |",
        "|---|---|---|---:|---:|---:|---|---|",
    ]
    for test, result in zip(tests, results, strict=False):
        low, high = result.ratio_range
        lines.append(
            f"| {test.domain} | {test.method} | {_reference_name(test)} | {result.statistic:.1f} | {result.dof} "
            f"| {format_p(result.p_value)} | {_result_word(result)} | {_format_range(low, high)} |"
        )
    lines += ["", "## What this shows", ""]
    lines += [f"- {_verdict(method, tests, results)}" for method in METHODS]
    lines += [
        "",
        "`figure.png`: top row, observed/expected counts of the folded samples in (φ, cos θ) bins of T0 "
        "(1 is uniform; white: outside T0, or a sliver with expected count below 5); bottom row, "
        f"{shown // 48} whole orbit{'s' if shown != 48 else ''} ({shown} directions) of each map in a Mollweide "
        "projection (longitude φ, latitude 90° − θ).",
        "",
    ]
    return "\n".join(lines)


def _render(path: Path, seed: int) -> str:
    """A small render of smallpt's Cornell box with the paper's scheme; the report's closing section."""
    from ..render import render, save_png  # function-level: ~0.3 s to import, and numba kernels

    result = render("cornell", width=64, height=48, spp=48, strategy="symmetric", points="sobol", seed=seed)
    save_png(path, result.image)
    return "\n".join(
        [
            "",
            "## A render with the symmetric scheme",
            "",
            f"![Cornell box](render.png)  smallpt's Cornell box, {result.width}×{result.height}, {result.spp} paths "
            f"per pixel, directions at diffuse vertices by the paper's scheme (strategy `symmetric`, points `sobol`: groups of 24 paths "
            f"share a base point per bounce, from an Owen-scrambled Sobol' sequence, and take its 24 orbit members; "
            f"equal-area map; seed {seed}).  "
            "`symsphere render --help` for more; docs/reference/renderer.md for the strategies.",
            "",
        ]
    )


def _verdict(method: MapMethod, tests: list[_Test], results: list[Chi2Result]) -> str:
    """One sentence per map, from the measured results (never assumed)."""
    mine = [(t, r) for t, r in zip(tests, results, strict=False) if t.method == method and _testable(r)]
    uniform = [(t, r) for t, r in mine if t.reference == "uniform"]
    own = [(t, r) for t, r in mine if t.reference != "uniform"]
    if not uniform:
        return (
            f"**{method} was not tested**: too few samples for two cells of 5 expected counts; rerun with a larger --n."
        )
    failed = [t.domain for t, r in uniform if not r.passed]
    if triangle_warp(method).uniform:
        if not failed:
            return (
                f"**{method} passes** every test against the uniform density "
                f"({_join(t.domain for t, _ in uniform)}): it is uniform, as constructed."
            )
        return (
            f"**{method} fails** against the uniform density on the {_join(failed)}. "
            f"This map is exactly uniform by construction, so this is either the "
            f"{FAMILY_SIGNIFICANCE:.0%} false alarm the tests allow or a bug: rerun with another --seed."
        )
    smallest_p = min(r.p_value for _, r in uniform)
    if failed:
        sentence = (
            f"**{method} fails** against the uniform density on the {_join(failed)} "
            f"(smallest p-value {format_p(smallest_p)}): the paper's map is not uniform, "
            "measured here."
        )
    else:
        sentence = (
            f"**{method} passes** against the uniform density at this n: too few samples to detect "
            "its non-uniformity; rerun with a larger --n."
        )
    own_failed = [t.domain for t, r in own if not r.passed]
    if not own:
        pass
    elif not own_failed:
        sentence += (
            " Against its own density it passes: it samples that density, not the uniform one "
            "(unbiased estimates must weight by 1/pdf)."
        )
    else:
        sentence += f" Against its own density it fails on the {_join(own_failed)}."
    return sentence


def _testable(result: Chi2Result) -> bool:
    """False if too few samples left a test with nothing to compare (p-value NaN)."""
    return not math.isnan(result.p_value)


def _result_word(result: Chi2Result) -> str:
    if not _testable(result):
        return "too few samples"
    return "pass" if result.passed else "**FAIL**"


def _write_figure(path: Path, tests: list[_Test], results: list[Chi2Result], scatter: dict[str, FloatArray]) -> None:
    # The object-oriented API with an Agg canvas: no pyplot state, no GUI backend.  Function-level:
    # matplotlib and scipy.stats load only when a figure is drawn.
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.colors import TwoSlopeNorm
    from matplotlib.figure import Figure

    from ..bins import equal_area_bins

    triangle = {
        t.method: r for t, r in zip(tests, results, strict=False) if t.domain == "triangle" and t.reference == "uniform"
    }
    ratios: dict[str, Float64Array] = {}
    for method, result in triangle.items():
        ratio = np.full(result.expected.shape, np.nan)
        inside = result.expected > 0  # bins of the bounding rectangle that meet T0
        np.divide(result.observed, result.expected, out=ratio, where=inside)
        # Slivers of T0 with tiny expected counts would dominate the colour scale with noise.
        ratio[result.expected < 5.0] = np.nan
        ratios[method] = ratio
    finite = np.concatenate([r[np.isfinite(r)] for r in ratios.values()] + [np.array([0.9, 1.1])])
    low, high = float(finite.min()), float(finite.max())  # a scale centred on 1 needs low < 1 < high
    norm = TwoSlopeNorm(vcenter=1.0, vmin=low, vmax=high)

    figure = Figure(figsize=(4.4 * len(METHODS), 6.8), layout="constrained")
    FigureCanvasAgg(figure)
    grid = figure.add_gridspec(2, len(METHODS), height_ratios=(1.35, 1.0))
    image = None
    for column, method in enumerate(METHODS):
        result = triangle[method]
        phi_edges, cos_edges = equal_area_bins("triangle", result.observed.shape)
        axes = figure.add_subplot(grid[0, column])
        image = axes.pcolormesh(np.degrees(phi_edges), cos_edges, ratios[method].T, cmap="RdBu_r", norm=norm)
        phi = np.linspace(0, np.pi / 4, 200)
        axes.plot(np.degrees(phi), np.cos(phi) / np.sqrt(1 + np.cos(phi) ** 2), color="k", lw=0.8)
        verdict = _result_word(result).strip("*")
        axes.set_title(f"{method}: T0, {verdict} vs uniform ({_p_equals(result.p_value)})", fontsize=9)
        axes.set_xlabel("φ (degrees)")
        axes.set_ylabel("cos θ")

        directions = scatter[method]
        axes = figure.add_subplot(grid[1, column], projection="mollweide")
        axes.scatter(
            np.arctan2(directions[:, 1], directions[:, 0]),
            np.arcsin(np.clip(directions[:, 2], -1.0, 1.0)),
            s=1.5,
            color="k",
            alpha=0.6,
            linewidths=0,
            rasterized=True,
        )
        axes.set_title(f"{method}: {len(directions)} directions", fontsize=9)
        axes.grid(True, lw=0.3)
        axes.set_xticklabels([])  # longitude labels would cover the equator, where the paper's maps cluster
        axes.tick_params(labelsize=6)
    assert image is not None  # METHODS is not empty
    figure.colorbar(image, ax=figure.axes[::2], label="observed / expected (uniform)", shrink=0.9)
    figure.suptitle("Folded samples relative to the uniform density (top) and sphere samples (bottom)")
    figure.savefig(path, dpi=110)
