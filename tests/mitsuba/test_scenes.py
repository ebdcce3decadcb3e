"""The shipped Mitsuba scene files, ``symsphere render --scene FILE.xml``, and the import boundary."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from symsphere.apps.cli import main


@pytest.mark.parametrize("name", ["cornell_box", "veach_mis", "door_room", "textured", "smallpt_cornell", "gap"])
def test_shipped_scenes_load_in_plain_mitsuba_and_render(llvm, name):
    mi = llvm
    import symsphere.mitsuba as sm

    assert name in sm.SCENES
    path = sm.scene_path(name)
    scene = mi.load_file(str(path), width=16, height=12, spp=8)  # plain Mitsuba: integrator path
    assert "PathIntegrator" in str(scene.integrator())
    image = np.array(
        mi.render(scene, integrator=mi.load_dict({"type": "symsphere_path", "strategy": "symmetric_cosine"}), spp=8)
    )
    assert image.shape[:2] == (12, 16) and np.all(np.isfinite(image)) and image.mean() > 0


def test_integrator_tag_in_a_scene_file(llvm, tmp_path):
    """``<integrator type="symsphere_path">`` with its parameters, in a scene file loaded by plain Mitsuba."""
    mi = llvm
    import symsphere.mitsuba  # noqa: F401  (registers symsphere_path)

    path = tmp_path / "scene.xml"
    path.write_text("""<scene version="3.0.0">
    <integrator type="symsphere_path">
        <string name="strategy" value="symmetric_cosine"/>
        <string name="points" value="sobol"/>
        <integer name="max_depth" value="4"/>
    </integrator>
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
        <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
    </sensor>
    <shape type="sphere"><bsdf type="diffuse"/></shape>
    <emitter type="constant"/>
</scene>""")
    scene = mi.load_file(str(path))
    text = str(scene.integrator())
    assert "SymspherePath" in text and "strategy='symmetric_cosine'" in text and "points='sobol'" in text
    assert "max_depth=4" in text
    image = np.array(mi.render(scene))
    assert image.shape[:2] == (8, 8) and np.all(np.isfinite(image)) and image.mean() > 0


def test_cli_renders_a_mitsuba_scene_file(llvm, tmp_path, capsys):
    import symsphere.mitsuba as sm

    out = tmp_path / "gap.png"
    status = main(["render", "--scene", str(sm.scene_path("gap")), "--width", "16", "--height", "12", "--spp", "24",
                   "--strategy", "symmetric", "--seed", "3", "--out", str(out), "--no-progress"])  # fmt: skip
    assert status == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["gap.exr", "gap.npy", "gap.pfm", "gap.png"]
    assert np.load(tmp_path / "gap.npy").shape == (12, 16, 3)
    assert "symsphere_path strategy symmetric, points sobol" in capsys.readouterr().out


@pytest.mark.parametrize(
    "content, words",
    [
        (
            '<scene version="3.0.0"><shape type="sphere"><bsdf type="nosuch"/></shape></scene>',
            'Plugin "nosuch" not found',
        ),
        ("<scene version=", "scene file"),
    ],
)
def test_cli_broken_scene_file_is_one_line(llvm, tmp_path, capsys, content, words):
    bad = tmp_path / "bad.xml"
    bad.write_text(content)
    status = main(["render", "--scene", str(bad), "--spp", "24", "--out", str(tmp_path / "x.png")])
    err = capsys.readouterr().err
    assert status == 2 and err.count("\n") == 1 and str(bad) in err and words in err
    assert not list(tmp_path.glob("x.*"))


def test_cli_spp_and_sampler_errors(llvm, tmp_path, capsys):
    import symsphere.mitsuba as sm

    scene = str(sm.scene_path("cornell_box"))
    # an spp that is not a multiple of the group: rounded up by the integrator (with Mitsuba's log warning)
    assert main(["render", "--scene", scene, "--spp", "10", "--out", str(tmp_path / "x.png")]) == 0
    assert (tmp_path / "x.png").stat().st_size > 0
    capsys.readouterr()
    assert main(["render", "--scene", scene, "--strategy", "uniform", "--out", str(tmp_path / "x.png")]) == 2
    assert "invalid choice: 'uniform' (choose from 'bsdf', 'cosine', " in capsys.readouterr().err
    assert (
        main(["render", "--scene", scene, "--strategy", "bsdf", "--points", "sobol", "--out", str(tmp_path / "x.png")])
        == 2
    )
    assert "--points sobol does not apply to --strategy bsdf" in capsys.readouterr().err


def test_cli_deprecated_sampler_warns_on_stderr_and_renders_the_same(llvm, tmp_path, capsys):
    import symsphere.mitsuba as sm

    base = ["render", "--scene", str(sm.scene_path("gap")), "--width", "8", "--height", "6", "--spp", "8"]
    base += ["--seed", "3", "--no-progress"]
    assert main([*base, "--sampler", "symmetric_cosine_sobol", "--out", str(tmp_path / "old.png")]) == 0
    assert "--sampler is deprecated; use --strategy symmetric_cosine --points sobol" in capsys.readouterr().err
    new = ["--strategy", "symmetric_cosine", "--points", "sobol", "--out", str(tmp_path / "new.png")]
    assert main([*base, *new]) == 0
    assert "deprecated" not in capsys.readouterr().err
    np.testing.assert_array_equal(np.load(tmp_path / "old.npy"), np.load(tmp_path / "new.npy"))


def test_import_symsphere_never_imports_mitsuba():
    code = "import sys, symsphere, symsphere.render, symsphere.apps.cli; print('mitsuba' in sys.modules or 'drjit' in sys.modules)"
    assert (
        subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
        == "False"
    )
