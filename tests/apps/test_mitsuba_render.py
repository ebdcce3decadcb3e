"""``symsphere render --scene FILE.xml`` (symsphere.apps.mitsuba_render): Mitsuba 3 scene files from the CLI.

Hostile files are refused in one line before Mitsuba sees them (too deep a nest, not a regular file) or
after loading, before any rendering (no sensor, an empty film, a non-finite radiance); every option is
honoured or refused in one line; a signal stops a render within a second and writes nothing.  Renders
here are small (a second or two each, llvm_ad_rgb); a run in another variant is a subprocess, so that
the variant of this process stays Mitsuba's default for the other tests.
"""

import os
import re
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from references import scaled_for_load

from symsphere._testing import exr_threads
from symsphere.apps.cli import main


def _probe():
    try:
        import drjit as dr
        import mitsuba as mi
    except ImportError as error:
        return f"Mitsuba 3 is not installed ({error})"
    try:
        mi.set_variant("llvm_ad_rgb")
        dr.eval(dr.arange(mi.Float, 4) * 2)
    except Exception as error:
        return f"Mitsuba's llvm_ad_rgb variant does not run ({error})"
    return None


REASON = _probe()
if REASON is not None and os.environ.get("SYMSPHERE_REQUIRE_MITSUBA") == "1":
    raise RuntimeError(f"SYMSPHERE_REQUIRE_MITSUBA=1 but Mitsuba cannot run: {REASON}")
pytestmark = pytest.mark.skipif(REASON is not None, reason=str(REASON))


@pytest.fixture
def cornell(tmp_path):
    """A copy of the shipped Cornell box (256 x 256, 48 spp in the file) with its meshes, in tmp_path/scene."""
    import symsphere.mitsuba as sm

    source = sm.scene_path("cornell_box")
    folder = tmp_path / "scene"
    folder.mkdir()
    for path in source.parent.glob("cornell_box*"):
        shutil.copy(path, folder / path.name)
    return folder / "cornell_box.xml"


def _variant_of(scene, text, name):
    variant = scene.with_name(name)
    variant.write_text(text)
    return variant


def _one_line_error(capsys):
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    return lines[0]


def _outputs(folder):
    return sorted(p.name for p in folder.iterdir() if p.name.startswith(("out", ".out")))


# --- files refused before Mitsuba loads them ---------------------------------------------------------


@pytest.mark.parametrize("depth", [100, 20_000])
def test_deeply_nested_bsdfs_are_refused_before_mitsuba_loads_them(tmp_path, capsys, depth):
    inner = '<bsdf type="diffuse"/>'
    nest = '<bsdf type="twosided">' * depth + inner + "</bsdf>" * depth
    scene = tmp_path / "nested.xml"
    scene.write_text(f'<scene version="3.0.0"><sensor type="perspective"/><shape type="sphere">{nest}</shape></scene>')
    assert main(["render", "--scene", str(scene), "--out", str(tmp_path / "out.png")]) == 2
    line = _one_line_error(capsys)
    assert str(scene) in line and "nested more than 8 deep" in line
    assert _outputs(tmp_path) == []


def test_deep_element_nesting_is_refused(tmp_path, capsys):
    scene = tmp_path / "deep.xml"
    scene.write_text('<scene version="3.0.0">' + "<shape>" * 65 + "</shape>" * 65 + "</scene>")
    assert main(["render", "--scene", str(scene), "--out", str(tmp_path / "out.png")]) == 2
    assert "elements are nested more than 64 deep" in _one_line_error(capsys)


@pytest.mark.parametrize("kind", ["directory", "fifo", "link to /dev/zero", "missing"])
def test_scene_that_is_not_a_regular_file_is_named_for_what_it_is(tmp_path, capsys, kind):
    scene = tmp_path / "scene.xml"
    expected = {"directory": "is a directory", "fifo": "is a FIFO", "link to /dev/zero": "is a character device",
                "missing": "no such file"}[kind]  # fmt: skip
    if kind == "directory":
        scene.mkdir()
    elif kind == "fifo":
        os.mkfifo(scene)
    elif kind == "link to /dev/zero":
        scene.symlink_to("/dev/zero")
    assert main(["render", "--scene", str(scene), "--out", str(tmp_path / "out.png")]) == 2
    line = _one_line_error(capsys)
    assert str(scene) in line and expected in line and "does not exist" not in line


# --- scenes that load but cannot render ----------------------------------------------------------------


def test_scene_without_a_sensor_is_refused(cornell, capsys):
    text = re.sub(r"<sensor.*?</sensor>", "", cornell.read_text(), flags=re.S)
    scene = _variant_of(cornell, text, "nosensor.xml")
    assert main(["render", "--scene", str(scene), "--out", str(cornell.parent / "out.png")]) == 2
    line = _one_line_error(capsys)
    assert "has no <sensor>" in line and "internal error" not in line
    # --spp for a file that declares spp but no longer uses it: Mitsuba's reason, not its list's last item
    assert main(["render", "--scene", str(scene), "--spp", "4", "--out", str(cornell.parent / "out.png")]) == 2
    line = _one_line_error(capsys)
    assert "Found unused parameters: $spp=4" in line, line


def test_empty_film_is_refused(cornell, capsys):
    scene = cornell
    assert main(["render", "--scene", str(scene), "--width", "0", "--out", str(cornell.parent / "out.png")]) == 2
    assert "'--width' must be positive" in _one_line_error(capsys)
    text = re.sub(r'name="(width|height)" value="256"', r'name="\1" value="0"', cornell.read_text())
    zero = _variant_of(cornell, text, "zero.xml")
    assert main(["render", "--scene", str(zero), "--out", str(cornell.parent / "out.png")]) == 2
    line = _one_line_error(capsys)
    assert "its film is 0 x 0 pixels" in line and "internal error" not in line


@pytest.mark.parametrize("radiance", ["nan, nan, nan", "1e39, 1e39, 1e39"])
def test_non_finite_radiance_is_refused_and_nothing_is_written(cornell, capsys, radiance):
    text = re.sub(r'(<emitter type="area">\s*<rgb name="radiance" value=")[^"]*"', rf'\g<1>{radiance}"',
                  cornell.read_text())  # fmt: skip
    assert radiance in text
    scene = _variant_of(cornell, text, "bright.xml")
    assert main(["render", "--scene", str(scene), "--spp", "24", "--out", str(cornell.parent / "out.png")]) == 2
    line = _one_line_error(capsys)
    assert "'light.emitter.radiance.value'" in line and "finite" in line
    assert _outputs(cornell.parent) == []


def test_film_larger_than_memory_is_refused(cornell, capsys, monkeypatch):
    from symsphere._testing import validation

    monkeypatch.setattr(validation.values, "machine_memory", lambda: 2**30)  # a 1 GiB machine
    text = re.sub(r'name="(width|height)" value="256"', r'name="\1" value="8000"', cornell.read_text())
    scene = _variant_of(cornell, text, "big.xml")
    assert main(["render", "--scene", str(scene), "--out", str(cornell.parent / "out.png")]) == 2
    line = _one_line_error(capsys)
    assert "8000 x 8000" in line and "more memory than this machine has" in line


def test_long_render_is_refused_without_allow_long(cornell, capsys):
    out = str(cornell.parent / "out.png")
    assert main(["render", "--scene", str(cornell), "--spp", str(48 * 10**6), "--out", out]) == 2
    line = _one_line_error(capsys)
    assert "is estimated to take at least" in line and "--allow-long" in line


# --- options: honoured or refused in one line ---------------------------------------------------------


@pytest.mark.parametrize(
    "option, words",
    [
        (["--workers", "2"], "--workers does not apply to Mitsuba scene files"),
        (["--scheduler", "tcp://localhost:8786"], "--scheduler does not apply"),
        (["--filter", "tent"], "--filter does not apply to Mitsuba scene files"),
        (["--integrator", "bsdf"], "--integrator does not apply"),
        (["--out", "x.tif"], "--out must end in .png, .pfm, .npy or .exr"),
        (["--seed", str(2**40)], "--seed must be below 2**32"),
    ],
)
def test_options_that_cannot_apply_are_refused(cornell, capsys, option, words):
    arguments = ["render", "--scene", str(cornell), "--out", str(cornell.parent / "out.png"), *option]
    assert main(arguments) == 2
    assert words in _one_line_error(capsys)


def test_the_files_resolution_is_kept_and_exr_is_written(cornell, capsys):
    import mitsuba as mi

    out = cornell.parent / "out.png"
    assert (
        main(["render", "--scene", str(cornell), "--spp", "24", "--seed", "2", "--out", str(out), "--no-progress"]) == 0
    )
    image = np.load(out.with_suffix(".npy"))
    assert image.shape == (256, 256, 3)  # the file's film, not the numba renderer's 256 x 192
    assert _outputs(cornell.parent) == ["out.exr", "out.npy", "out.pfm", "out.png"]
    with exr_threads.exr_threads():  # Mitsuba's OpenEXR reader with one thread in Dr.Jit's pool waits for ever
        exr = np.array(mi.Bitmap(str(out.with_suffix(".exr"))), dtype=np.float64)
    np.testing.assert_allclose(exr[..., :3], image, rtol=1e-6, atol=0)  # float32 of the same image
    assert "24 spp" in capsys.readouterr().out


def test_width_alone_keeps_the_aspect_ratio_and_threads_are_honoured(cornell, capsys):
    import drjit as dr

    text = cornell.read_text().replace('<default name="height" value="256" />', '<default name="height" value="128" />')
    wide = _variant_of(cornell, text, "wide.xml")
    out = cornell.parent / "out.png"
    threads = dr.thread_count()
    arguments = ["render", "--scene", str(wide), "--width", "64", "--spp", "24", "--threads", "1"]
    assert main([*arguments, "--out", str(out), "--no-progress"]) == 0
    assert np.load(out.with_suffix(".npy")).shape == (32, 64, 3)
    assert "(llvm_ad_rgb, 1 threads)" in capsys.readouterr().out  # rendered on one thread
    assert dr.thread_count() == threads  # and the process's pool is as it was


_ONE_THREAD = """
import sys
from pathlib import Path

import drjit as dr
import numpy as np

from symsphere.apps.cli import main
from symsphere.render import save_image

folder = Path(sys.argv[1])
dr.set_thread_count(1)  # as on a one-CPU machine
save_image(folder / "sky.exr", np.full((4, 8, 3), 0.5))
(folder / "sky.xml").write_text(
    '<scene version="3.0.0"><emitter type="envmap"><string name="filename" value="sky.exr"/></emitter>'
    '<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/>'
    '<integer name="height" value="6"/></film></sensor></scene>'
)
arguments = ["render", "--scene", str(folder / "sky.xml"), "--spp", "4", "--threads", "1"]
status = main([*arguments, "--out", str(folder / "out.png"), "--no-progress"])
print(status, dr.thread_count())
"""


def test_exr_is_read_and_written_with_one_thread_in_drjits_pool(tmp_path):
    # Mitsuba's OpenEXR codec waits forever with one thread in Dr.Jit's pool (a one-CPU machine): with
    # one there, an .exr is written (save_image), a scene file with an .exr environment map is loaded and
    # rendered on one thread, its .exr written, and the pool has one thread again after.  A new process
    # (its pool is its own; a hang is a timeout, not a stuck worker).
    try:
        run = subprocess.run([sys.executable, "-c", _ONE_THREAD, str(tmp_path)], capture_output=True, text=True,
                             timeout=scaled_for_load(120))  # fmt: skip
    except subprocess.TimeoutExpired:
        pytest.fail("reading or writing .exr with one thread in Dr.Jit's pool hung")
    assert run.returncode == 0, run.stderr
    assert run.stdout.split()[-2:] == ["0", "1"], run.stdout + run.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "out.exr",
        "out.npy",
        "out.pfm",
        "out.png",
        "sky.exr",
        "sky.xml",
    ]
    assert np.load(tmp_path / "out.npy").mean() > 0  # the environment map was read: it lights the film


def test_a_film_of_fixed_size_refuses_width(cornell, capsys):
    text = cornell.read_text().replace('value="$width"', 'value="64"').replace('value="$height"', 'value="48"')
    text = re.sub(r'<default name="(width|height)"[^>]*/>', "", text)
    fixed = _variant_of(cornell, text, "fixed.xml")
    assert main(["render", "--scene", str(fixed), "--width", "32", "--out", str(cornell.parent / "out.png")]) == 2
    assert "fixes its film's size" in _one_line_error(capsys)


def test_help_lists_only_what_applies_in_a_stable_order(cornell):
    def helps():
        command = [sys.executable, "-m", "symsphere", "render", "--scene", str(cornell), "--help"]
        return subprocess.run(command, capture_output=True, text=True, check=True).stdout

    first, second = helps(), helps()
    assert first == second
    choices = re.search(r"--strategy \{([^}]*)\}", first).group(1).split(",")
    assert choices == sorted(choices) == ["bsdf", "cosine", "symmetric", "symmetric_cosine"]
    assert re.search(r"--points \{([^}]*)\}", first).group(1).split(",") == ["random", "sobol"]
    choices = re.search(r"--sampler \{([^}]*)\}", first).group(1).split(",")  # deprecated, for one release
    assert choices == sorted(choices) == ["bsdf", "cosine", "symmetric", "symmetric_cosine", "symmetric_cosine_sobol",
                                          "symmetric_sobol"]  # fmt: skip
    for absent in ("--filter", "--workers", "--integrator", "uniform", "interlaced", "translucent"):
        assert absent not in first
    assert "--variant" in first and "--variant" not in main_help()


def main_help():
    command = [sys.executable, "-m", "symsphere", "render", "--help"]
    return subprocess.run(command, capture_output=True, text=True, check=True).stdout


def test_variants_are_sorted_in_refusals_and_cuda_needs_a_device(cornell, capsys):
    import drjit as dr
    import mitsuba as mi

    out = str(cornell.parent / "out.png")
    assert main(["render", "--scene", str(cornell), "--variant", "nosuch", "--out", out]) == 2
    line = _one_line_error(capsys)
    listed = re.findall(r"'([a-z_]+)'", line.split("use one of")[1])
    assert listed == sorted(mi.variants())
    if not dr.has_backend(dr.JitBackend.CUDA):
        assert main(["render", "--scene", str(cornell), "--variant", "cuda_ad_rgb", "--out", out]) == 2
        assert "needs a CUDA device" in _one_line_error(capsys)
    assert main(["render", "--variant", "llvm_ad_rgb", "--scene", "furnace", "--out", out]) == 2
    assert "--variant applies to Mitsuba 3 scene files" in _one_line_error(capsys)


def test_other_variants_render_in_their_own_process(cornell):
    out = cornell.parent / "out.png"
    for variant, status in (("llvm_ad_mono", 0), ("llvm_ad_spectral", 0), ("scalar_rgb", 2)):
        command = [sys.executable, "-m", "symsphere", "render", "--scene", str(cornell), "--variant", variant,
                   "--width", "16", "--spp", "24", "--seed", "1", "--out", str(out), "--no-progress"]  # fmt: skip
        run = subprocess.run(command, capture_output=True, text=True, timeout=300)
        assert run.returncode == status, run.stderr
        if status == 0:
            assert f"({variant}, " in run.stdout
            image = np.load(out.with_suffix(".npy"))
            assert image.shape == (16, 16, 3) and np.isfinite(image).all() and image.mean() > 0
        else:
            assert "symsphere_path runs in Mitsuba's JIT variants" in run.stderr
            assert len(run.stderr.strip().splitlines()) == 1


def test_passes_and_their_seeds_reproduce_the_image(cornell, monkeypatch):
    from symsphere.apps import mitsuba_render

    assert mitsuba_render.plan_passes(4800, 256 * 192, 24) == [72] * 66 + [48]
    assert mitsuba_render.plan_passes(10, 100, 24) == [10]  # not whole groups: one pass, the integrator's rule
    monkeypatch.setattr(mitsuba_render, "PASS_PATHS", 2**12)  # 16 x 16 pixels at 96 spp: four passes of 24
    assert mitsuba_render.plan_passes(96, 16 * 16, 24) == [24] * 4
    images = []
    for _ in range(2):
        out = cornell.parent / "out.png"
        arguments = ["render", "--scene", str(cornell), "--width", "16", "--spp", "96", "--seed", "5"]
        assert main([*arguments, "--out", str(out), "--no-progress"]) == 0
        images.append(np.load(out.with_suffix(".npy")))
    # Mitsuba adds samples into the film with atomics, in an order that varies: equal to float32's rounding
    np.testing.assert_allclose(images[0], images[1], rtol=1e-5, atol=1e-7)


# --- signals --------------------------------------------------------------------------------------------


def _mitsuba_loaded(pid):
    try:
        with open(f"/proc/{pid}/maps") as maps:
            return "libmitsuba" in maps.read()
    except OSError:
        return False


@pytest.mark.parametrize("signum, status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_stops_a_render_within_a_second_and_writes_nothing(cornell, signum, status):
    out = cornell.parent / "out.png"
    command = [sys.executable, "-m", "symsphere", "render", "--scene", str(cornell), "--width", "256", "--height",
               "192", "--spp", "4800", "--seed", "1", "--out", str(out), "--no-progress"]  # fmt: skip
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not _mitsuba_loaded(process.pid) and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)  # main() runs (its handlers set) once Mitsuba loads: not Python's start-up
    time.sleep(1.5)  # the scene loaded, the render under way (it would take a minute)
    sent = time.monotonic()
    process.send_signal(signum)
    try:
        _, err = process.communicate(timeout=2.0)
    except subprocess.TimeoutExpired:
        process.kill()
        process.communicate()
        pytest.fail(f"still running 2 s after {signal.Signals(signum).name}")
    assert time.monotonic() - sent < 2.0
    assert process.returncode == status, err
    assert "nothing was written" in err
    assert _outputs(cornell.parent) == []


def test_a_signal_while_mitsuba_is_imported_ends_cleanly(cornell):
    # Importing Mitsuba runs Python inside nanobind's module initialisation: a KeyboardInterrupt raised
    # there ended the process with SIGABRT ("terminate called after throwing ... python_error") or SIGSEGV
    # in 5 of 12 runs signalled the moment Mitsuba's library was mapped.  The signals wait for the import.
    out = cornell.parent / "out.png"
    command = [sys.executable, "-m", "symsphere", "render", "--scene", str(cornell), "--spp", "4800", "--seed", "1",
               "--out", str(out), "--no-progress"]  # fmt: skip
    for signum, status in [(signal.SIGINT, 130), (signal.SIGTERM, 143)] * 3:
        process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 120
        while not _mitsuba_loaded(process.pid) and process.poll() is None and time.monotonic() < deadline:
            time.sleep(0.002)
        process.send_signal(signum)
        _, err = process.communicate(timeout=60)
        assert process.returncode == status, err[-2000:]
        assert "nothing was written" in err and "Traceback" not in err
    assert _outputs(cornell.parent) == []
