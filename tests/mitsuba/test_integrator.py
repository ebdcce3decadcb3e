"""The ``symsphere_path`` integrator: its randomness, its scheme, its errors, and that it is unbiased.

Statistical tests (fixed seeds): the block test compares every strategy's mean image with Mitsuba's
own ``path`` (the independent reference) on two small scenes, K independent renders (seeds) each,
block by block (4 x 4 pixels, the mean of R, G and B): Welch's t-test (t rather than z: K is small),
two-sided, significance 0.01 for all of them with a Sidak correction over the UNBIASED_TESTS blocks (every
strategy, scene and variant run: llvm_ad_rgb, and cuda_ad_rgb where a CUDA device is present).  Its power,
measured by multiplying the symmetric strategy's block means by 1.01 ... 1.05 and rerunning the same t-test
(with one strategy case fewer, which moves the threshold by < 1 %): a uniform 5 % error is rejected on both
scenes, 2 % on the textured one (median block standard errors 0.8 % and 0.5 %).  The furnace test is a
z-test of the image mean against 1 at 0.01, Sidak-corrected over the strategies and variants.
"""

from __future__ import annotations

import numpy as np
import pytest
from mitsuba_scenes import scene_dict
from scipy import stats

STRATEGY_CASES = [
    {"strategy": "bsdf"},
    {"strategy": "cosine"},
    {"strategy": "cosine", "points": "sobol"},
    {"strategy": "symmetric", "points": "random"},
    {"strategy": "symmetric", "points": "sobol"},
    {"strategy": "symmetric", "points": "random", "method": "paper1"},
    {"strategy": "symmetric_cosine", "points": "random"},
    {"strategy": "symmetric_cosine", "points": "sobol"},
]
SIZE, SPP, SEEDS, BLOCK = 16, 48, 16, 4
SCENES = ("cornell", "textured")
BLOCKS = (SIZE // BLOCK) ** 2


def _jit_variants_run():
    """How many variants the jit_variant tests run in here: llvm_ad_rgb, and cuda_ad_rgb with a CUDA device."""
    try:
        import drjit as dr
    except ImportError:
        return 1
    return 1 + bool(dr.has_backend(dr.JitBackend.CUDA))


UNBIASED_TESTS = len(STRATEGY_CASES) * len(SCENES) * BLOCKS * _jit_variants_run()
ALPHA = 0.01


def _sidak(alpha, count):
    return 1.0 - (1.0 - alpha) ** (1.0 / count)


def _ids(case):
    return "-".join(str(v) for v in case.values())


# --- randomness: bit for bit the renderer's ------------------------------------------------------


def test_random_equals_the_renderers_bitwise(llvm):
    mi = llvm
    from symsphere._testing import hashes, owen_sobol, splitmix
    from symsphere._testing import mitsuba_random as dj

    rng = np.random.default_rng(5)
    keys = rng.integers(0, 2**63, size=64, dtype=np.uint64) * np.uint64(2) + np.uint64(1)
    index = rng.integers(0, 2**32, size=64, dtype=np.uint64)
    index[:4] = [0, 1, 2, 2**32 - 1]
    with np.errstate(over="ignore"):  # numpy scalars warn on the wrap-around the hashes rely on
        ref_mix = [int(splitmix.mix64(k)) for k in keys]
        ref_key = [int(hashes.pixel_key(k, int(i % 1000))) for k, i in zip(keys, index, strict=False)]
        ref_below = [int(hashes.below(k, 24)) for k in keys]
        ref_sobol = [owen_sobol.owen_sobol2(i, k) for i, k in zip(index, keys, strict=False)]
    k = mi.UInt64(keys)
    assert [int(v) for v in dj.mix64(k)] == ref_mix
    assert [int(v) for v in dj.pixel_key(k, mi.UInt32((index % 1000).astype(np.uint32)))] == ref_key
    assert [int(v) for v in dj.below(k, 24)] == ref_below
    x, y = dj.owen_sobol2(mi.UInt32(index.astype(np.uint32)), k)
    assert [int(v) for v in x] == [int(round(a * 2**32)) for a, _ in ref_sobol]
    assert [int(v) for v in y] == [int(round(b * 2**32)) for _, b in ref_sobol]


# --- the scheme: a group of consecutive samples takes all images of one base point ---------------


@pytest.mark.parametrize("case", [c for c in STRATEGY_CASES if c["strategy"].startswith("symmetric")], ids=_ids)
def test_a_group_takes_every_image_of_one_base_point(jit_variant, case):
    mi = jit_variant
    import symsphere.mitsuba  # noqa: F401  (registers the plugin)
    from symsphere._testing import mitsuba_integrator
    from symsphere.mitsuba import fold
    from symsphere.symmetry import SPHERE_MAPS

    GROUP_SIZES = mitsuba_integrator.GROUP_SIZES

    integrator = mi.load_dict({"type": "symsphere_path", **case})
    n = GROUP_SIZES[case["strategy"]]
    s = mi.UInt32(np.arange(4 * n, dtype=np.uint32))
    key = mi.UInt64(0x1234567890ABCDEF)
    for depth in (0, 3):
        wo, pdf = integrator._local_direction(key, s, mi.UInt32(depth))
        d = np.array(wo, dtype=np.float64).T
        assert np.all(d[:, 2] >= 0) and np.all(np.array(pdf) > 0)
        if n == 24:  # the base point in T0 (the inverse of the 24 maps)
            base = np.array(fold(wo)[1], dtype=np.float64).T
        else:  # the base point in the wedge W = {x >= y >= 0}: the inverse of the 8 z-keeping maps
            a = np.abs(d[:, :2])
            base = np.stack([a.max(axis=1), a.min(axis=1), d[:, 2]], axis=1)
        for g in range(4):  # group g: one base point, and its n images, each once
            members = slice(g * n, (g + 1) * n)
            b = base[g * n]
            assert np.all(base[members] == b)
            images = {tuple(b @ m) for m in SPHERE_MAPS[:n]}
            assert {tuple(v) for v in d[members]} == images and len(images) == n
        assert len({tuple(base[g * n]) for g in range(4)}) == 4  # distinct groups, distinct base points
    # the offset: the first member of group 0 differs between vertices (else sample s would stay in one triangle)
    firsts = [tuple(np.sign(np.array(integrator._local_direction(key, mi.UInt32([0]), mi.UInt32(d))[0])[:2, 0]))
              for d in range(12)]  # fmt: skip
    assert len(set(firsts)) > 1  # sample 0 visits more than one quadrant of the local frame


# --- errors ------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "params, words",
    [
        ({"strategy": "orbit"}, "'orbit' is not a valid strategy"),
        ({"points": "halton"}, "'halton' is not a valid points"),
        ({"method": "octahedral"}, "'octahedral' is not a valid method"),
        ({"max_depth": -2}, "'max_depth' must be -1"),
        ({"rr_depth": 0}, "'rr_depth' must be > 0"),
        ({"strategy": "bsdf", "points": "sobol"}, "'points' must be 'random' for strategy='bsdf'"),
    ],
)
def test_bad_parameters_name_the_parameter(llvm, params, words):
    mi = llvm
    import symsphere.mitsuba  # noqa: F401

    with pytest.raises(RuntimeError) as info:  # Mitsuba's loader wraps the plugin's ValueError
        mi.load_dict({"type": "symsphere_path", **params})
    last = str(info.value).strip().splitlines()[-1]
    assert last.startswith("ValueError: ") and words in last


def test_scalar_variants_are_refused():
    import mitsuba as mi

    import symsphere.mitsuba  # noqa: F401

    mi.set_variant("scalar_rgb")
    try:
        with pytest.raises(RuntimeError, match="runs in Mitsuba's JIT variants"):
            mi.load_dict({"type": "symsphere_path"})
    finally:
        mi.set_variant("llvm_ad_rgb")


# --- unbiasedness: every strategy against Mitsuba's path -------------------------------------------


def _renders(mi, scene, integrator):
    return np.stack(
        [np.array(mi.render(scene, integrator=integrator, spp=SPP, seed=seed))[..., :3] for seed in range(SEEDS)]
    )


def _blocks(images):
    k = images.shape[0]
    lum = images.mean(axis=-1).reshape(k, SIZE // BLOCK, BLOCK, SIZE // BLOCK, BLOCK)
    return lum.mean(axis=(2, 4)).reshape(k, -1)


_REFERENCE: dict[tuple[str, str], np.ndarray] = {}  # (variant, scene): Mitsuba path's blocks


@pytest.mark.statistical
@pytest.mark.parametrize("scene_name", SCENES)
@pytest.mark.parametrize("case", STRATEGY_CASES, ids=_ids)
def test_mean_image_agrees_with_mitsubas_path(jit_variant, scene_name, case):
    mi = jit_variant
    import symsphere.mitsuba  # noqa: F401

    scene = mi.load_dict(scene_dict(mi, scene_name, SIZE))
    depth = {"max_depth": 6, "rr_depth": 3}
    key = (mi.variant(), scene_name)
    if key not in _REFERENCE:
        _REFERENCE[key] = _blocks(_renders(mi, scene, mi.load_dict({"type": "path", **depth})))
    ref = _REFERENCE[key]
    ours = _blocks(_renders(mi, scene, mi.load_dict({"type": "symsphere_path", **case, **depth})))
    assert np.all(np.isfinite(ours))
    result = stats.ttest_ind(ours, ref, axis=0, equal_var=False)
    threshold = _sidak(ALPHA, UNBIASED_TESTS)
    assert np.min(result.pvalue) > threshold, (np.min(result.pvalue), ours.mean(0), ref.mean(0))


@pytest.mark.statistical
@pytest.mark.parametrize("case", STRATEGY_CASES, ids=_ids)
def test_white_furnace(jit_variant, case):
    """A white (albedo 1, two-sided) sphere under a uniform sky of radiance 1 has radiance 1 everywhere."""
    mi = jit_variant
    import symsphere.mitsuba  # noqa: F401

    T = mi.ScalarTransform4f
    scene = mi.load_dict({
        "type": "scene",
        "sensor": {"type": "perspective", "fov": 30, "to_world": T().look_at(origin=[0, 0, 4], target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": SIZE, "height": SIZE, "rfilter": {"type": "box"}}},
        "ball": {"type": "sphere", "bsdf": {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [1, 1, 1]}}}},
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [1, 1, 1]}},
    })  # fmt: skip
    integrator = mi.load_dict({"type": "symsphere_path", **case, "max_depth": -1, "rr_depth": 5})
    images = np.stack([np.array(mi.render(scene, integrator=integrator, spp=SPP, seed=s))[..., :3] for s in range(4)])
    values = images.mean(axis=-1).ravel()  # independent pixels (and seeds)
    z = (values.mean() - 1.0) / (values.std(ddof=1) / np.sqrt(values.size))
    assert abs(z) < stats.norm.isf(_sidak(ALPHA, len(STRATEGY_CASES) * _jit_variants_run()) / 2), (values.mean(), z)


@pytest.mark.parametrize("hide_emitters", [False, True])
def test_bsdf_strategy_reproduces_mitsubas_path_at_the_same_seed(jit_variant, hide_emitters):
    """strategy='bsdf' restates path.cpp with the same sampler calls in the same order: the same image at the
    same seed, up to float32 rounding of operations the two compile differently (bound: 1e-4 of the image's
    maximum; measured 4e-9).  With hide_emitters the camera ray passes through area emitters, as Mitsuba's."""
    mi = jit_variant
    import symsphere.mitsuba as sm

    scene = mi.load_file(str(sm.scene_path("cornell_box")), width=16, height=16)
    options = {"max_depth": 6, "hide_emitters": hide_emitters}
    ref = np.array(mi.render(scene, integrator=mi.load_dict({"type": "path", **options}), spp=24, seed=7))
    ours = np.array(
        mi.render(
            scene, integrator=mi.load_dict({"type": "symsphere_path", "strategy": "bsdf", **options}), spp=24, seed=7
        )
    )
    assert np.max(np.abs(ours - ref)) <= 1e-4 * np.max(ref)


@pytest.mark.parametrize("two_sided", [False, True])
def test_cosine_strategy_is_the_diffuse_bsdfs_own_sample(llvm, two_sided):
    """strategy='cosine' takes the BSDF's own sample at Lambertian vertices because Mitsuba's diffuse samples
    exactly that strategy: wo = square_to_cosine_hemisphere of the same 2D sample (for twosided, of the side
    the ray arrives on: wo.z takes wi.z's sign), pdf |wo.z| / pi, weight the reflectance; checked here on
    Mitsuba's BSDFs themselves, bit for bit (the same float32 operations), for rays from both sides."""
    mi = llvm
    import drjit as dr

    diffuse = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.3, 0.5, 0.7]}}
    bsdf = mi.load_dict({"type": "twosided", "bsdf": diffuse} if two_sided else diffuse)
    rng = np.random.default_rng(11)
    n = 4096
    u = rng.random((2, n)).astype(np.float32)
    wi = rng.normal(size=(3, n))
    wi /= np.linalg.norm(wi, axis=0)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(wi.astype(np.float32))
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    sample, weight = bsdf.sample(mi.BSDFContext(), si, mi.Float(rng.random(n).astype(np.float32)), mi.Point2f(u))
    expected = mi.warp.square_to_cosine_hemisphere(mi.Point2f(u))
    wo, ex = np.array(sample.wo), np.array(expected)
    front = wi[2] > 0
    valid = front | two_sided
    ex[2] = np.where(wi[2] < 0, -ex[2], ex[2])  # twosided: the back side samples the mirrored hemisphere
    assert np.array_equal(wo[:, valid], ex[:, valid])
    assert np.array_equal(np.array(sample.pdf)[valid], np.abs(ex[2, valid]) * np.float32(1 / np.pi))
    assert np.allclose(np.array(weight)[:, valid], np.array([[0.3], [0.5], [0.7]]), rtol=1e-6, atol=0)
    assert np.all(np.array(weight)[:, ~valid] == 0)  # one-sided: nothing from behind


def test_cosine_strategy_renders_the_bsdf_strategys_image(llvm):
    """The consequence, end to end: the two strategies give the same image at the same seed, bit for bit (and
    cosine with Sobol' points, its own directions, another)."""
    mi = llvm
    import symsphere.mitsuba as sm

    scene = mi.load_file(str(sm.scene_path("textured")), width=16, height=16)
    cases = (("bsdf", "random"), ("cosine", "random"), ("cosine", "sobol"))
    integrators = [mi.load_dict({"type": "symsphere_path", "strategy": s, "points": p}) for s, p in cases]
    images = [np.array(mi.render(scene, integrator=integrator, spp=8, seed=3)) for integrator in integrators]
    assert np.array_equal(images[0], images[1])
    assert not np.array_equal(images[0], images[2])  # Sobol' points: its own directions, not the BSDF's
