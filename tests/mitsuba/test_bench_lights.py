"""benchmarks/bench_mitsuba_lights.py's measurement: the reference's own noise subtracted from the relMSE, and
the sample count a Mitsuba sampler really renders.

The correction is tested on synthetic images whose variances are known (numpy's generator, fixed seed): a
z-test at 0.01 (two tests, Sidak) of the corrected relMSE against the relMSE of the image alone, with the
standard error of the mean over pixels; the raw relMSE must be rejected by the same test (the reference's
share is 25 % of the image's there, ~100 standard errors).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
from scipy import stats

ROOT = Path(__file__).resolve().parents[2]
ALPHA = 0.01
PIXELS = 400_000


def _bench():
    spec = importlib.util.spec_from_file_location(
        "bench_mitsuba_lights", ROOT / "benchmarks" / "bench_mitsuba_lights.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_references_own_relmse_is_subtracted():
    bench = _bench()
    rng = np.random.default_rng(37)
    truth = rng.uniform(0.05, 2.0, PIXELS)
    sigma = 0.02 * truth  # the image's standard deviation; each half-reference's: the reference's variance is
    half = sigma * np.sqrt(0.5)  # (half^2 / 2) = sigma^2 / 4, a quarter of the image's
    image = truth + sigma * rng.standard_normal(PIXELS)
    a, b = (truth + half * rng.standard_normal(PIXELS) for _ in range(2))
    ref, own = bench.reference(a, b)
    expected_terms = sigma**2 / (truth**2 + 0.01)  # the image's own relMSE, pixel by pixel
    terms = (image - ref) ** 2 / (ref**2 + 0.01) - ((a - b) / 2) ** 2 / (ref**2 + 0.01)
    error = terms.std(ddof=1) / np.sqrt(PIXELS)
    limit = stats.norm.isf((1.0 - (1.0 - ALPHA) ** 0.5) / 2)
    corrected = bench.rel_mse(image, ref) - own
    raw = bench.rel_mse(image, ref)
    assert abs(corrected - expected_terms.mean()) / error < limit, (corrected, expected_terms.mean(), error)
    assert abs(raw - expected_terms.mean()) / error > limit, (raw, expected_terms.mean(), error)
    assert np.isclose(own, np.mean(((a - b) / 2) ** 2 / (ref**2 + 0.01)))


def test_the_sample_count_a_sampler_takes(llvm, tmp_path):
    """Mitsuba's multijitter renders 35 samples per pixel when asked for 32 (a 5 x 7 grid), independent 32: the
    benchmark scales by what is rendered."""
    mi = llvm
    import sys

    sys.path.insert(0, str(ROOT / "benchmarks"))
    from _mitsuba_light_scenes import light_scene

    bench = _bench()
    assert bench._taken_spp(light_scene(mi, "wall_wash", 8, 8, tmp_path), 32) == 32
    assert bench._taken_spp(light_scene(mi, "wall_wash", 8, 8, tmp_path, "multijitter"), 32) == 35
    assert bench._taken_spp(light_scene(mi, "wall_wash", 8, 8, tmp_path, "multijitter"), 64) == 64
