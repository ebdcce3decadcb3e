"""Statistical validation of the renderer: the white furnace, and unbiasedness against a reference.

Both use fixed seeds (the images are reproducible), so a run either passes or
fails; the thresholds are chosen so that a correct renderer fails with small
probability over the choice of seeds.

Furnace
    Inside a closed diffuse sphere of albedo rho emitting Le, the radiance is
    exactly Le / (1 - rho).  Pixels have independent random streams (and
    independent scrambles), so they are the independent units: the stated
    error is the standard deviation of the pixel means over sqrt(#pixels).
    Each test asks for the mean within 4 standard errors.  Uniform-direction
    samplers (every sampler but ``cosine``) weight a bounce by
    X = 2 rho cos(theta) with cos(theta) uniform, E[X^2] = 4 rho^2 / 3, which
    exceeds 1 for rho > sqrt(3)/2 = 0.866: their variance in the closed diffuse
    furnace is then infinite and no standard error means anything.  So the
    closed diffuse furnace uses rho = 0.3, 0.6 and 0.85 for them (0.9 for
    ``cosine``); the translucent furnace (Lambertian reflection + transmission,
    full-sphere sampling, background Le / (1 - rho)), where only reflected
    paths continue (E[X^2 1{reflected}] = 2 rho^2 / 3), runs all samplers at
    rho = 0.3, 0.6, 0.9.

Unbiasedness
    Every sampler renders a 32 x 24 Cornell box as R = 8 independent replicates
    of 48 spp; the reference is 8 replicates of 512 spp with ``cosine`` and
    other seeds.  Per pixel, the replicate mean and its variance
    (sample variance / R); per 8 x 8 block and channel, the block mean and its
    variance (sum of the pixel variances / 64^2: pixels are independent).
    z = (block mean - reference block mean) / sqrt(var + reference var),
    two-sided, 12 blocks x 3 channels x 7 samplers = 252 tests, Sidak-corrected
    so that a correct renderer fails any of them with probability 0.01.
"""

import math

import numpy as np
import pytest
from scipy import stats

from symsphere.render import SAMPLERS, furnace, render

FAMILY_SIGNIFICANCE = 0.01

# --- furnace ------------------------------------------------------------------------

_FURNACE_CASES = [
    (sampler, rho, translucent)
    for sampler in SAMPLERS
    for translucent in (False, True)
    for rho in (0.3, 0.6, (0.9 if translucent or sampler == "cosine" else 0.85))
]


@pytest.mark.parametrize("sampler, rho, translucent", _FURNACE_CASES)
def test_furnace_radiance_is_le_over_one_minus_rho(sampler, rho, translucent):
    emission = 0.7
    scene = furnace(albedo=rho, emission=emission, translucent=translucent)
    result = render(scene, width=32, height=32, spp=48, sampler=sampler, seed=round(1000 * rho) + translucent)
    image = result.image
    np.testing.assert_array_equal(image[..., 0], image[..., 1])  # grey scene, same paths for every channel
    pixels = image[..., 0].ravel()
    mean = pixels.mean()
    standard_error = pixels.std(ddof=1) / math.sqrt(pixels.size)
    expected = emission / (1 - rho)
    assert abs(mean - expected) <= 4 * standard_error, (mean, expected, standard_error)
    assert standard_error < 0.05 * expected  # the test has teeth


# --- unbiasedness against a high-spp reference --------------------------------------

_W, _H, _BLOCK = 32, 24, 8
_REPLICATES = 8


def _replicate_stats(sampler, spp, seed0):
    images = np.stack(
        [render("cornell", width=_W, height=_H, spp=spp, sampler=sampler, seed=seed0 + r).image for r in range(_REPLICATES)]
    )
    mean = images.mean(axis=0)
    variance_of_mean = images.var(axis=0, ddof=1) / _REPLICATES
    blocks = lambda a: a.reshape(_H // _BLOCK, _BLOCK, _W // _BLOCK, _BLOCK, 3)  # noqa: E731
    block_mean = blocks(mean).mean(axis=(1, 3))
    block_variance = blocks(variance_of_mean).sum(axis=(1, 3)) / _BLOCK**4
    return block_mean, block_variance


@pytest.fixture(scope="module")
def reference():
    return _replicate_stats("cosine", 512, seed0=90_000)


@pytest.mark.slow
@pytest.mark.parametrize("sampler", SAMPLERS)
def test_every_sampler_agrees_with_the_reference(sampler, reference):
    ref_mean, ref_variance = reference
    block_mean, block_variance = _replicate_stats(sampler, 48, seed0=1000 * (SAMPLERS.index(sampler) + 1))
    z = (block_mean - ref_mean) / np.sqrt(block_variance + ref_variance)
    tests = len(SAMPLERS) * z.size
    per_test = 1 - (1 - FAMILY_SIGNIFICANCE) ** (1 / tests)
    critical = stats.norm.isf(per_test / 2)  # about 4.1
    assert np.all(np.abs(z) < critical), (np.abs(z).max(), critical, np.unravel_index(np.abs(z).argmax(), z.shape))
    # the blocks are well estimated: relative standard error below 5% where there is light
    lit = ref_mean > 0.05
    assert np.all(np.sqrt(block_variance[lit]) < 0.1 * ref_mean[lit]), np.max(np.sqrt(block_variance[lit]) / ref_mean[lit])
