"""symsphere.render.renderer: ``render``, its arguments and results, determinism, passes and the ``render`` verb."""

import dataclasses
import errno
import math
import os
import pathlib
import pickle

import numba
import numpy as np
import pytest
from references import raises_naming

import symsphere
from symsphere._testing import render_integrator as K
from symsphere.apps.cli import main
from symsphere.render import (
    INTEGRATORS,
    SAMPLERS,
    STRATEGIES,
    RenderSettings,
    cornell,
    load_pfm,
    plan_passes,
    render,
    render_passes,
)

GOOD_TOML = """
[camera]
position = [0, 1, 4]
look_at = [0, 1, 0]
fov = 40

[materials.white]
type = "diffuse"
albedo = 0.7

[[spheres]]
center = [0, 1, 0]
radius = 0.5
material = "white"
"""


def test_cornell_renders_like_smallpt():
    """Cheap sanity: the light is the brightest thing, the left wall red, the right wall blue."""
    image = render("cornell", width=32, height=24, spp=48, seed=5).image
    assert np.all(np.isfinite(image)) and image.min() >= 0
    left, right = image[8:16, 1:4].mean(axis=(0, 1)), image[8:16, -4:-1].mean(axis=(0, 1))
    assert left[0] > 1.5 * left[2] and right[2] > 1.5 * right[0]
    row, col = np.unravel_index(np.argmax(image[..., 0]), image.shape[:2])
    assert 2 <= row <= 4 and 12 <= col <= 20 and image[row, col, 0] > 6  # the light (radiance 12) in the ceiling


# --- determinism -------------------------------------------------------------------


@pytest.mark.parametrize("integrator", INTEGRATORS)
@pytest.mark.parametrize(
    "words",
    [
        dict(strategy="symmetric", points="sobol"),
        dict(strategy="orbit", method="equal_area"),
        dict(strategy="symmetric_cosine", points="sobol"),
        dict(strategy="symmetric", points="sobol_interlaced2"),
    ],
    ids=lambda words: ",".join(words.values()),
)
def test_same_seed_same_image_for_any_thread_count(words, integrator):
    arguments = dict(width=24, height=16, spp=30, integrator=integrator, **words)
    previous = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = render("cornell", seed=42, **arguments).image
        numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
        two = render("cornell", seed=42, **arguments).image
    finally:
        numba.set_num_threads(previous)
    np.testing.assert_array_equal(one, two)
    other = render("cornell", seed=43, **arguments).image
    assert not np.array_equal(one, other)


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_the_image_does_not_depend_on_how_samples_are_split_into_passes(integrator):
    plan = plan_passes("cornell", 16, 12, 48, strategy="symmetric", points="random", seed=9, integrator=integrator)
    rows = np.arange(12, dtype=np.int64)

    def run(splits):
        accum = np.zeros((12, 16, 3))
        first = 0
        for count in splits:
            K.render_pass(*plan.arguments, first, count, rows[::-1].copy(), accum)
            first += count
        return accum

    a, b = run([48]), run([5, 19, 24])
    np.testing.assert_allclose(a, b, rtol=1e-13)  # same samples; only the summation order differs
    np.testing.assert_array_equal(render_passes(plan, 0, 1)[0], run([48]))


def test_render_result_fields():
    result = render("furnace", width=8, height=6, spp=24, method="paper2", seed=1)
    assert result.image.shape == (6, 8, 3) and result.image.dtype == np.float64
    assert result.paths == 8 * 6 * 24 and result.paths_per_second > 0
    settings = (result.strategy, result.points, result.method, result.pixel_filter, result.seed)
    assert settings == ("symmetric", "sobol", "paper2", "box", 1)
    assert (
        result.integrator == "path"
        and render("furnace", width=4, height=4, spp=1, seed=1, integrator="bsdf").integrator == "bsdf"
    )
    assert render("furnace", width=4, height=4, spp=1, strategy="cosine", seed=1).method is None
    assert render("furnace", width=4, height=4, spp=1, strategy="orbit", seed=1).method == "equal_area"
    tent = render("cornell", width=8, height=6, spp=4, pixel_filter="tent", seed=1)
    assert tent.pixel_filter == "tent" and np.all(np.isfinite(tent.image))


def test_the_plan_and_the_result_share_one_record_of_settings():
    plan = plan_passes("furnace", 4, 3, 5, None, "paper1", "tent", 11, "bsdf", strategy="symmetric", points="random")
    result = render("furnace", width=4, height=3, spp=5, strategy="symmetric", points="random", method="paper1",
                    pixel_filter="tent", seed=11, integrator="bsdf")  # fmt: skip
    expected = RenderSettings(width=4, height=3, spp=5, strategy="symmetric", points="random", method="paper1",
                              pixel_filter="tent", seed=11, integrator="bsdf")  # fmt: skip
    assert plan.settings() == result.settings() == expected
    assert isinstance(plan, RenderSettings) and isinstance(result, RenderSettings)
    names = [f.name for f in dataclasses.fields(RenderSettings)]
    assert names == ["width", "height", "spp", "strategy", "points", "method", "pixel_filter", "seed", "integrator"]
    assert [getattr(result, name) for name in names] == [4, 3, 5, "symmetric", "random", "paper1", "tent", 11, "bsdf"]
    assert result.scene == plan.scene.name and result.paths == 4 * 3 * 5
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.spp = 6  # type: ignore[misc]
    assert pickle.loads(pickle.dumps(plan)).settings() == expected  # Dask ships plans to workers


@pytest.mark.parametrize(
    "kwargs, named",
    [
        (dict(strategy="nope"), "strategy"),
        (dict(strategy="bsdf"), "strategy"),  # symsphere_path's only
        (dict(strategy="cosine", points="sobol"), "points"),  # symsphere_path's only
        (dict(strategy="orbit", points="sobol"), "points"),
        (dict(strategy="cosine", method="paper1"), "method"),
        (dict(strategy="symmetric_cosine", method="equal_area"), "method"),
        (dict(points="halton"), "points"),
        (dict(method="nope"), "method"),
        (dict(width=0), "width"),
        (dict(spp=0), "spp"),
        (dict(seed=-1), "seed"),
        (dict(pixel_filter="gauss"), "pixel_filter"),
        (dict(scene="nope"), "scene"),
        (dict(threads=0), "threads"),
        (dict(integrator="nee"), "integrator"),
    ],
)
def test_render_rejects_bad_arguments(kwargs, named):
    arguments = dict(scene="cornell", width=4, height=4, spp=1, seed=0) | kwargs
    with pytest.raises(ValueError, match=named):
        render(**arguments)


# --- the deprecated sampler= spelling (one release) ---------------------------------------------

# Every old name, its new words and the warning's text, written out here (not read from the library).
OLD_SPELLINGS = {
    "symmetric": "strategy='symmetric', points='random'",
    "symmetric_sobol": "strategy='symmetric', points='sobol'",
    "equal_area": "strategy='orbit', points='random', method='equal_area'",
    "paper1": "strategy='orbit', points='random', method='paper1'",
    "paper2": "strategy='orbit', points='random', method='paper2'",
    "uniform": "strategy='uniform', points='random'",
    "cosine": "strategy='cosine', points='random'",
    "symmetric_cosine": "strategy='symmetric_cosine', points='random'",
    "symmetric_cosine_sobol": "strategy='symmetric_cosine', points='sobol'",
    "symmetric_sobol_interlaced2": "strategy='symmetric', points='sobol_interlaced2'",
    "symmetric_sobol_interlaced3": "strategy='symmetric', points='sobol_interlaced3'",
    "symmetric_cosine_sobol_interlaced2": "strategy='symmetric_cosine', points='sobol_interlaced2'",
    "symmetric_cosine_sobol_interlaced3": "strategy='symmetric_cosine', points='sobol_interlaced3'",
}


@pytest.mark.parametrize("sampler", sorted(OLD_SPELLINGS))
def test_a_deprecated_sampler_warns_with_the_new_spelling_and_renders_the_same_plan(sampler):
    # The plan holds the kernel's codes: equal plans render equal images (the images themselves are pinned
    # for both spellings in tests/test_public_outputs.py).
    with pytest.warns(DeprecationWarning) as caught:
        old = plan_passes("cornell", 4, 4, 2, sampler, seed=1)
    assert [str(w.message) for w in caught] == [f"sampler={sampler!r} is deprecated; use {OLD_SPELLINGS[sampler]}"]
    assert caught[0].filename == __file__  # points at the caller's line
    words = dict(part.split("=") for part in OLD_SPELLINGS[sampler].replace("'", "").split(", "))
    new = plan_passes("cornell", 4, 4, 2, seed=1, **words)
    assert new.arguments[12:] == old.arguments[12:] and new.settings() == old.settings()
    with pytest.warns(DeprecationWarning, match="'sampler' is deprecated"):
        assert old.sampler == sampler


def test_render_warns_at_the_callers_line_and_refuses_two_spellings():
    with pytest.warns(DeprecationWarning, match="use strategy='cosine', points='random'") as caught:
        render("furnace", width=2, height=2, spp=1, sampler="cosine", seed=1)
    assert caught[0].filename == __file__
    for extra in (dict(strategy="cosine"), dict(points="random")):
        with pytest.raises(ValueError, match="not both"):
            render("furnace", width=2, height=2, spp=1, sampler="cosine", seed=1, **extra)


@pytest.mark.parametrize(
    "kwargs, named",
    [
        (dict(sampler="nope"), "sampler"),
        (dict(sampler="cosine", method="paper1"), "method"),
        (dict(sampler="paper1", method="paper2"), "method"),
        (dict(sampler="symmetric_cosine", method="equal_area"), "method"),
        (dict(sampler="symmetric_cosine_sobol_interlaced2", method="paper1"), "method"),
        (dict(sampler="symmetric_sobol_interlaced3", method="nope"), "method"),
    ],
)
@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # a valid old name warns before the method is checked
def test_a_deprecated_sampler_is_checked_as_before(kwargs, named):
    arguments = dict(scene="cornell", width=4, height=4, spp=1, seed=0) | kwargs
    with pytest.raises(ValueError, match=named):
        render(**arguments)


def test_render_rejects_a_non_integer_count():
    # check_count's convention (as symsphere.sample_sphere): a count of the wrong type is a TypeError
    with pytest.raises(TypeError, match="'spp' must be an integer"):
        render("cornell", width=4, height=4, spp=2.5, seed=0)


# --- the render verb ----------------------------------------------------------------


def test_render_verb_writes_png_pfm_npy(tmp_path, capsys):
    out = tmp_path / "img.png"
    arguments = ["render", "--scene", "cornell", "--width", "16", "--height", "12", "--spp", "24"]
    status = main([*arguments, "--strategy", "symmetric", "--seed", "3", "--no-progress", "--out", str(out)])
    assert status == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["img.npy", "img.pfm", "img.png"]
    expected = render("cornell", width=16, height=12, spp=24, strategy="symmetric", points="sobol", seed=3).image
    np.testing.assert_array_equal(np.load(tmp_path / "img.npy"), expected)
    np.testing.assert_array_equal(load_pfm(tmp_path / "img.pfm"), expected.astype(np.float32))
    assert (tmp_path / "img.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    closing = capsys.readouterr().out.strip().splitlines()
    assert len(closing) == 1 and "Mpaths/s" in closing[0] and " s = " in closing[0] and str(out) in closing[0]
    assert "strategy symmetric, points sobol, method equal_area" in closing[0]


@pytest.mark.parametrize(
    "old, new",
    [
        (["--sampler", "symmetric_cosine_sobol"], ["--strategy", "symmetric_cosine", "--points", "sobol"]),
        (["--sampler", "paper1"], ["--strategy", "orbit", "--points", "random", "--method", "paper1"]),
        (["--sampler", "symmetric", "--method", "paper2"], ["--strategy", "symmetric", "--points", "random"]),
    ],
)
def test_the_render_verbs_deprecated_sampler_warns_on_stderr_and_renders_the_same(tmp_path, capsys, old, new):
    base = ["render", "--scene", "furnace", "--width", "4", "--height", "3", "--spp", "16", "--seed", "2"]
    assert main([*base, *old, "--no-progress", "--out", str(tmp_path / "old.png")]) == 0
    err = capsys.readouterr().err
    assert f"--sampler is deprecated; use {' '.join(new)}" in err
    method = ["--method", old[-1]] if "--method" in old else []
    assert main([*base, *new, *method, "--no-progress", "--out", str(tmp_path / "new.png")]) == 0
    assert "deprecated" not in capsys.readouterr().err
    np.testing.assert_array_equal(np.load(tmp_path / "old.npy"), np.load(tmp_path / "new.npy"))


@pytest.mark.parametrize(
    "arguments, named",
    [
        (["--sampler", "nope"], "--sampler"),
        (["--strategy", "nope"], "--strategy"),
        (["--strategy", "cosine", "--points", "sobol"], "--points"),
        (["--strategy", "uniform", "--method", "paper1"], "--method"),
        (["--sampler", "cosine", "--strategy", "cosine"], "--sampler"),
        (["--spp", "0"], "--spp"),
        (["--seed", "-2"], "--seed"),
        (["--out", "x.jpg"], "--out"),
        (["--scene", "nope"], "scene"),
        (["--sampler", "uniform", "--method", "paper1"], "method"),
        (["--exposure", "0"], "--exposure"),
    ],
)
def test_render_verb_rejects_bad_arguments(tmp_path, capsys, arguments, named):
    base = ["render", "--width", "4", "--height", "4", "--spp", "1", "--no-progress"]
    if "--out" not in arguments:
        base += ["--out", str(tmp_path / "x.png")]
    assert main([*base, *arguments]) == 2
    err = capsys.readouterr().err
    assert named in err
    assert not any(p.suffix in (".png", ".pfm", ".npy") for p in tmp_path.iterdir())


def test_render_verb_names_a_bad_scene_file(tmp_path, capsys):
    path = tmp_path / "s.toml"
    path.write_text(GOOD_TOML.replace("radius = 0.5", "radius = -0.5", 1))
    assert main(["render", "--scene", str(path), "--out", str(tmp_path / "x.png"), "--no-progress"]) == 2
    assert f"scene file {str(path)!r}: spheres[0].radius must be positive" in capsys.readouterr().err
    missing = tmp_path / "missing.toml"
    assert main(["render", "--scene", str(missing), "--out", str(tmp_path / "x.png"), "--no-progress"]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_strategies_and_deprecated_samplers_listed():
    assert STRATEGIES == ("cosine", "orbit", "symmetric", "symmetric_cosine", "uniform")
    assert set(SAMPLERS) == set(OLD_SPELLINGS)
    assert INTEGRATORS == ("path", "bsdf")
    assert math.isclose(2 * math.tan(math.radians(cornell().camera.fov) / 2), 0.5135, rel_tol=1e-15)


def test_an_image_larger_than_memory_is_refused_before_any_allocation(monkeypatch):
    from symsphere._testing import validation
    from symsphere.render import render

    monkeypatch.setattr(validation.values, "machine_memory", lambda: 2**30)  # a 1 GiB machine: ~6.7 Mpixels
    with pytest.raises(ValueError, match=r"'width \* height'=67108864 is too large .* on this machine"):
        render("furnace", width=8192, height=8192, spp=1, strategy="cosine", seed=1)
    assert validation.memory_pixel_limit(160) == 2**30 // 160


# --- write_outputs: all or nothing ---------------------------------------------------------------------------------


def test_write_outputs_is_all_or_nothing_and_names_the_failing_file(tmp_path, monkeypatch):
    from symsphere.render import image as image_module
    from symsphere.render import render, write_outputs

    result = render("furnace", width=4, height=4, spp=2, strategy="cosine", seed=1)
    write_outputs(result, tmp_path / "f.png")
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    real_encode, real_write_bytes = image_module._encode, pathlib.Path.write_bytes

    written = []

    def full_disk_at_pfm(self, data):  # the files are encoded first, then written to their temporaries
        written.append(self)
        if len(written) == 2:  # PNG, then PFM: the temporaries are unnamed on Linux, so count
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(self))
        return real_write_bytes(self, data)

    monkeypatch.setattr(
        image_module, "_encode", lambda suffix, image, exposure: real_encode(suffix, image, exposure * 2)
    )
    monkeypatch.setattr(pathlib.Path, "write_bytes", full_disk_at_pfm)
    with pytest.raises(OSError) as caught:
        write_outputs(result, tmp_path / "f.png", exposure=0.5)
    assert caught.value.filename == str(tmp_path / "f.pfm")  # the file that failed, not the PNG
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


@pytest.mark.parametrize(
    "call, error, named",
    [
        (lambda: symsphere.render.render("furnace", width=2, height=2, spp=1, seed=np.random.PCG64(1)), TypeError,
         "'seed'"),
    ],
)  # fmt: skip
def test_wrong_types_and_values_name_the_argument(call, error, named):
    raises_naming(call, error, named)
