"""Reliability regression tests (the first review): one or more per defect, each failing on the code
before the fix.  docs/reference/reliability.md states the guarantees these tests check.

Subprocess tests run the real command (``python -m symsphere``) so that signals, resource limits and
exit statuses are those a user sees.
"""

from __future__ import annotations

import errno
import json
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import time
import warnings

import numpy as np
import pytest
from references import one_line_error, scaled_for_load, writing_in

import symsphere
from symsphere import harmonics, io, symmetry
from symsphere.apps.cli import main

CLI = [sys.executable, "-m", "symsphere"]


def _listing(directory):
    return sorted(p.name for p in directory.iterdir())


# --- 1. full disk: no SIGBUS, no temporary left, one clear line ---------------------------------


def _unshare_available() -> bool:
    if shutil.which("unshare") is None or sys.platform != "linux":
        return False
    probe = subprocess.run(
        ["unshare", "-rm", "sh", "-c", "d=$(mktemp -d) && mount -t tmpfs -o size=1m tmpfs $d && umount $d"],
        capture_output=True,
    )
    return probe.returncode == 0


@pytest.mark.skipif(not _unshare_available(), reason="needs unshare -rm and tmpfs (a user namespace)")
def test_full_tmpfs_fails_with_one_line_and_no_leftover(tmp_path):
    # The reproduction, scaled down: 8 MiB of tmpfs, a 24 MiB float32 file.
    mount = tmp_path / "small"
    mount.mkdir()
    script = (
        f"mount -t tmpfs -o size=8m tmpfs {mount} && "
        f"{sys.executable} -m symsphere sample --n {48 * 2**16 * 2} --dtype float32 --seed 1 --out {mount}/big.npy; "
        f"echo status=$?; ls -A {mount}"
    )
    run = subprocess.run(["unshare", "-rm", "sh", "-c", script], capture_output=True, text=True, timeout=300)
    assert "status=1\n" in run.stdout, (run.stdout, run.stderr)  # not 135 (SIGBUS)
    assert run.stdout.strip().endswith("status=1"), run.stdout  # and ls printed nothing: no file, no temporary
    line = one_line_error(run.stderr)
    assert "big.npy" in line and "No space left on device" in line


def test_npy_is_written_without_a_memory_map(tmp_path, monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("a memory map turns ENOSPC into SIGBUS")

    monkeypatch.setattr(np.lib.format, "open_memmap", refuse)
    monkeypatch.setattr(np, "memmap", refuse)
    path = tmp_path / "d.npy"
    n = 48 * 300
    io.stream_directions(
        path, n, np.float32, lambda out: symsphere.iter_sphere(n, chunk=48 * 64, rng=3, dtype=np.float32)
    )
    np.testing.assert_array_equal(np.load(path), symsphere.sample_sphere(n, rng=3, dtype=np.float32))


def test_space_is_reserved_before_any_block_is_computed(tmp_path, monkeypatch):
    computed = []

    def fallocate(fd, offset, length):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    def blocks(out):
        computed.append(True)
        yield np.zeros((48, 3))

    monkeypatch.setattr(os, "posix_fallocate", fallocate, raising=False)
    with pytest.raises(OSError, match="No space left"):
        io.stream_directions(tmp_path / "d.npy", 48, np.float64, blocks)
    assert computed == [] and _listing(tmp_path) == []


@pytest.mark.skipif(not hasattr(signal, "SIGXFSZ"), reason="POSIX file-size limit")
def test_file_size_limit_gives_one_line_and_no_leftover(tmp_path):
    # RLIMIT_FSIZE stands in for a full disk where no tmpfs can be mounted (EFBIG instead of ENOSPC).
    code = (
        "import resource, signal, sys\n"
        "signal.signal(signal.SIGXFSZ, signal.SIG_IGN)\n"
        "resource.setrlimit(resource.RLIMIT_FSIZE, (1 << 20, 1 << 20))\n"
        "from symsphere.apps.cli import main\n"
        f"sys.exit(main(['sample', '--n', '{48 * 2**14}', '--seed', '1', '--out', sys.argv[1]]))\n"
    )
    run = subprocess.run([sys.executable, "-c", code, str(tmp_path / "d.npy")], capture_output=True, text=True)
    assert run.returncode == 1, run.stderr
    assert "d.npy" in one_line_error(run.stderr)
    assert _listing(tmp_path) == []


# --- 2. SIGTERM: clean up, say so, exit 143 -----------------------------------------------------


def _start_and_terminate(args, tmp_path, wait_for):
    process = subprocess.Popen(CLI + args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not wait_for(process) and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    assert process.poll() is None, "the command finished before it could be signalled"
    process.send_signal(signal.SIGTERM)
    _, stderr = process.communicate(timeout=120)
    return process.returncode, stderr


def test_sigterm_during_sample_removes_the_temporary(tmp_path):
    def temporary_exists(process):
        return writing_in(process.pid, tmp_path, min_size=1)

    status, stderr = _start_and_terminate(
        ["sample", "--n", str(48 * 2**22), "--chunk", str(48 * 2**12), "--out", str(tmp_path / "d.npy")],
        tmp_path,
        temporary_exists,
    )
    assert status == 143
    assert "terminated (SIGTERM); nothing was written" in one_line_error(stderr)
    assert _listing(tmp_path) == []


def test_sigterm_during_render_writes_nothing(tmp_path):
    started = time.monotonic()
    status, stderr = _start_and_terminate(
        ["render", "--scene", "cornell", "--width", "64", "--height", "48", "--spp", "480000", "--no-progress",
         "--out", str(tmp_path / "img.png")],
        tmp_path,
        lambda process: time.monotonic() - started > 4.0,
    )  # fmt: skip
    assert status == 143
    assert "terminated (SIGTERM)" in one_line_error(stderr)
    assert _listing(tmp_path) == []


def test_sigterm_handler_is_restored_after_main(tmp_path):
    before = signal.getsignal(signal.SIGTERM)
    assert main(["sample", "--n", "48", "--seed", "1", "--out", str(tmp_path / "d.npy")]) == 0
    assert signal.getsignal(signal.SIGTERM) is before


# --- 3. sample's memory is flat in N --------------------------------------------------------------


def _peak_rss_mb(args):
    code = (
        "import resource, sys\n"
        "from symsphere.apps.cli import main\n"
        "status = main(sys.argv[1:])\n"
        "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)\n"
        "sys.exit(status)\n"
    )
    run = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr
    return float(run.stdout.split()[-1])


@pytest.mark.slow
def test_sample_peak_rss_does_not_grow_with_n(tmp_path):
    small = _peak_rss_mb(["sample", "--n", str(48 * 2**15), "--dtype", "float32", "--seed", "1",
                          "--out", str(tmp_path / "small.npy")])  # fmt: skip
    large = _peak_rss_mb(["sample", "--n", str(48 * 2**21), "--dtype", "float32", "--seed", "1",
                          "--out", str(tmp_path / "large.npy")])  # fmt: skip
    # 64 times the directions (1.2 GB of output): the old memory map kept it all resident.
    assert large - small < 100, (small, large)
    assert np.load(tmp_path / "large.npy", mmap_mode="r").shape == (48 * 2**21, 3)


# --- 4. the files of a render appear as a set -----------------------------------------------------


def _write_set(paths, texts):
    with io.atomic_paths(paths) as temporaries:
        for temporary, text in zip(temporaries, texts, strict=False):
            temporary.write_text(text)


def test_atomic_paths_failure_while_writing_changes_nothing(tmp_path):
    paths = [tmp_path / name for name in ("a.png", "a.pfm", "a.npy")]
    _write_set(paths, ["old png", "old pfm", "old npy"])
    with pytest.raises(KeyboardInterrupt):
        with io.atomic_paths(paths) as temporaries:
            temporaries[0].write_text("new png")
            raise KeyboardInterrupt
    assert [p.read_text() for p in paths] == ["old png", "old pfm", "old npy"]
    assert _listing(tmp_path) == ["a.npy", "a.pfm", "a.png"]


def test_atomic_paths_failed_rename_restores_the_old_set(tmp_path, monkeypatch):
    paths = [tmp_path / name for name in ("a.png", "a.pfm", "a.npy")]
    _write_set(paths[:2], ["old png", "old pfm"])  # a.npy did not exist before
    real_replace = os.replace
    calls = []

    def failing_replace(source, target):
        calls.append(target)
        if len(calls) == 3:  # the third rename (a.npy) fails: disk error, signal, ...
            raise OSError(errno.EIO, "I/O error", str(target))
        return real_replace(source, target)

    monkeypatch.setattr(os, "replace", failing_replace)
    with pytest.raises(OSError, match="I/O error"):
        _write_set(paths, ["new png", "new pfm", "new npy"])
    monkeypatch.setattr(os, "replace", real_replace)
    assert [p.read_text() for p in paths[:2]] == ["old png", "old pfm"]
    assert _listing(tmp_path) == ["a.pfm", "a.png"]


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


# --- 5. rotated hemisphere rows stay on the hemisphere ---------------------------------------------


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_rotated_hemisphere_rows_have_positive_pdf(dtype):
    from scipy.stats import qmc

    normal = [0.3, -0.5, 0.8]
    d = symsphere.sample_hemisphere(96, normal=normal, points=qmc.Sobol(2, scramble=False), dtype=dtype)
    assert np.all(symsphere.hemisphere_pdf(d, normal=normal) > 0)
    rng = np.random.default_rng(12)
    for seed in range(40):  # the random float32 scan found 357 such rows
        normal = rng.normal(size=3)
        d = symsphere.sample_hemisphere(24 * 512, normal=normal, rng=seed, dtype=dtype)
        assert np.all(symsphere.hemisphere_pdf(d, normal=normal) > 0)


# --- 6. Sobol' beyond 2**30 points is rejected at the call ------------------------------------------


def test_sobol_beyond_its_length_is_rejected_at_the_call():
    with pytest.raises(ValueError, match=r"'n'=103079215104 needs 2147483648 Sobol' points"):
        symsphere.iter_sphere(48 * 2**31, points="sobol")
    with pytest.raises(ValueError, match="Sobol'"):
        symsphere.integrate(lambda d: d[:, 2], n=48 * 8 * 2**31, points="sobol")
    from scipy.stats import qmc

    engine = qmc.Sobol(2, scramble=False)
    engine.fast_forward(2**30 - 4)
    with pytest.raises(ValueError, match="after the engine's 1073741820"):
        symsphere.sample_sphere(48 * 8, points=engine)


def test_sobol_beyond_its_length_is_rejected_by_distributed():
    distributed = pytest.importorskip("symsphere.distributed")
    pytest.importorskip("dask")
    with pytest.raises(ValueError, match="Sobol'"):
        distributed.sample_sphere(48 * 2**31, points="sobol")


# --- 7. absurd sizes fail fast, naming the argument -------------------------------------------------


def _fails_fast(call, error, match, seconds=5.0):
    start = time.monotonic()
    with pytest.raises(error, match=match):
        call()
    assert time.monotonic() - start < scaled_for_load(seconds)  # instead of allocating or computing for minutes


def test_absurd_sizes_fail_fast_naming_the_argument():
    from symsphere.render import render

    _fails_fast(lambda: symsphere.sample_sphere(48 * 2**64), ValueError, r"'n'=.* is too large")
    _fails_fast(lambda: symsphere.integrate(lambda d: d[:, 0], n=48 * 2**64), ValueError, "'n'")
    _fails_fast(lambda: symsphere.iter_sphere(48 * 2**64), ValueError, "'n_total'")
    _fails_fast(lambda: render("cornell", spp=10**15), ValueError, r"'spp'=1000000000000000 is too large")
    _fails_fast(lambda: harmonics.sh_polynomial(10**5, 0), ValueError, "'l'")
    _fails_fast(lambda: harmonics.monomial_integral(10**7, 0, 0), ValueError, r"'a \+ b \+ c'")
    _fails_fast(lambda: harmonics.real_sh_basis(10**6, [0, 0, 1]), ValueError, "'lmax'")


def test_absurd_dask_graphs_fail_fast():
    distributed = pytest.importorskip("symsphere.distributed")
    pytest.importorskip("dask")
    _fails_fast(lambda: distributed.sample_sphere(n=48 * 10**13), ValueError, "'chunks'", seconds=10)
    _fails_fast(
        lambda: distributed.integrate(lambda d: d[:, 0], n=48 * 10**13, client=None), ValueError, "'chunk_blocks'"
    )


def test_a_long_integration_prints_an_estimate_first(capsys, monkeypatch):
    from symsphere.apps import cli

    monkeypatch.setattr(cli, "_ESTIMATE_ABOVE", 48 * 2**10)  # "long", scaled down
    assert main(["integrate", "--integrand", "exp", "--n", str(48 * 2**12), "--seed", "1"]) == 0
    err = capsys.readouterr().err
    assert f"{48 * 2**12} evaluations, estimated" in err and "evaluations/s" in err


# --- 8. no traceback from the command line ----------------------------------------------------------


def _scene_text(settings="", sphere_radius="1"):
    return (
        "camera = {position = [0, 0, 4], look_at = [0, 0, 0], fov = 40}\n"
        'materials.lamp = {type = "diffuse", albedo = 0.5, emission = 1}\n'
        f'spheres = [{{center = [0, 0, 0], radius = {sphere_radius}, material = "lamp"}}]\n' + settings
    )


@pytest.mark.parametrize(
    "name, text, words",
    [
        ("huge.toml", _scene_text(sphere_radius="1" + "0" * 400), "spheres[0].radius must be at most 1e+30"),
        ("depth.toml", _scene_text("settings = {max_depth = 1000000000000000000000000000000}\n"),
         "settings.max_depth must be at most 1000000"),
        ("deep.json", "[" * 100_000 + "]" * 100_000, "nested too deeply"),
        ("deep.toml", "a = " + "[" * 10_000 + "]" * 10_000 + "\n", "nested too deeply"),
        ("digits.json", '{"name": ' + "9" * 5000 + "}", "not valid JSON"),
        ("emission.toml", _scene_text().replace("emission = 1", "emission = 1e308"), "emission must be at most 1e+30"),
    ],
)  # fmt: skip
def test_hostile_scene_files_give_one_line(tmp_path, capsys, name, text, words):
    scene = tmp_path / name
    scene.write_text(text)
    status = main(["render", "--scene", str(scene), "--width", "4", "--height", "4", "--spp", "1",
                   "--no-progress", "--out", str(tmp_path / "x.png")])  # fmt: skip
    assert status == 2
    line = one_line_error(capsys.readouterr().err)
    assert words in line
    assert _listing(tmp_path) == [name]


def test_timeout_nan_with_scheduler_is_a_usage_error(capsys):
    status = main(
        ["integrate", "--integrand", "exp", "--n", "48", "--scheduler", "tcp://127.0.0.1:9", "--timeout", "nan"]
    )
    assert status == 2
    assert "--timeout must be a positive number" in one_line_error(capsys.readouterr().err)


def test_exposure_inf_is_rejected_before_rendering(tmp_path, capsys):
    start = time.monotonic()
    status = main(["render", "--spp", "9600000", "--exposure", "inf", "--out", str(tmp_path / "x.png")])
    assert status == 2 and time.monotonic() - start < scaled_for_load(5)
    assert "--exposure must be a positive finite number" in one_line_error(capsys.readouterr().err)


def test_unexpected_errors_are_one_line(tmp_path, capsys, monkeypatch):
    from symsphere.apps import cli

    def broken(*args, **kwargs):
        raise RuntimeError("something\nbroke")

    monkeypatch.setattr(cli, "stream_directions", broken)
    monkeypatch.delenv("SYMSPHERE_TRACEBACK", raising=False)
    assert main(["sample", "--n", "48", "--out", str(tmp_path / "d.npy")]) == 1
    assert "internal error: RuntimeError: something broke" in one_line_error(capsys.readouterr().err)


# --- 9. the documented exception types ------------------------------------------------------------


def test_exception_types():
    deep = np.zeros((1,) * 33 + (3,))
    for call in (
        lambda: symmetry.fold(deep),
        lambda: symsphere.sphere_pdf(deep),
        lambda: symsphere.hemisphere_pdf(deep),
    ):
        with pytest.raises(ValueError, match="'d' has 34 dimensions"):
            call()
    with pytest.raises(ValueError, match="'l'"):
        harmonics.real_sh(10**5, 0, [0.0, 0.0, 1.0])
    from symsphere.render import Camera, Scene, SceneError, Sphere, diffuse, write_outputs

    with pytest.raises(TypeError, match="'result'"):
        write_outputs(None, "x.png")
    with pytest.raises(SceneError, match="max_depth must be at most"):
        Scene("s", Camera((0, 0, 5), (0, 0, -1), 40), {"m": diffuse(0.5, 1.0)}, (Sphere((0, 0, 0), 1, "m"),),
              max_depth=10**30)  # fmt: skip


def test_distributed_exception_types():
    distributed = pytest.importorskip("symsphere.distributed")
    pytest.importorskip("dask")
    with pytest.raises(TypeError, match="'client'"):
        distributed.close_client(None)
    with pytest.raises(TypeError, match="'client'"):
        distributed.integrate(lambda d: d[:, 0], client=5, n=48)
    with pytest.raises(TypeError, match="'timeout'"):
        distributed.connect("tcp://127.0.0.1:9", timeout="x")
    with pytest.raises(ValueError, match="'timeout'"):
        distributed.connect("tcp://127.0.0.1:9", timeout=float("nan"))


# --- 10. extreme but valid normals --------------------------------------------------------------------


@pytest.mark.parametrize("scale", [1e200, 1e-170, 1e-320])
def test_extreme_normals_are_accepted_without_warning(scale):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        d = symsphere.sample_hemisphere(48, normal=[scale, 0.0, 0.0], rng=4)
        density = symsphere.hemisphere_pdf(d, normal=[scale, 0.0, 0.0])
    np.testing.assert_array_equal(d, symsphere.sample_hemisphere(48, normal=[1.0, 0.0, 0.0], rng=4))
    assert np.all(density > 0)


# --- 11. no silent NaN or inf -------------------------------------------------------------------------


def test_zero_and_non_unit_vectors_are_rejected():
    from symsphere import warps

    for call in (
        lambda: warps.square_to_cosine_hemisphere_pdf([0.0, 0.0, 0.0]),
        lambda: warps.spherical_triangle_to_square([0.0, 0.0, 0.0], *warps.T0_VERTICES),
        lambda: symsphere.triangle_to_square([0.0, 0.0, 0.0], "paper1"),
        lambda: symsphere.sphere_pdf([0.0, 0.0, 2.0], "paper1"),
        lambda: symsphere.hemisphere_pdf([0.0, 0.0, 0.5]),
    ):
        with pytest.raises(ValueError, match="unit vectors"):
            call()


def test_unit_direction_check_tolerance_and_extreme_norms():
    # The check compares squared norms with (1 -+ tol)^2; the message reports the first bad vector's norm,
    # computed without overflow or underflow (the reference: math.hypot, exact to an ulp).
    import math

    from symsphere._testing import validation

    check_unit_directions, tol = validation.check_unit_directions, validation.UNIT_TOLERANCE
    ok = np.array([[0.0, 0.0, 1.0 + 0.9 * tol], [0.0, 1.0 - 0.9 * tol, 0.0], [0.6, 0.0, -0.8]])
    assert check_unit_directions(ok) is not None
    assert check_unit_directions(ok.astype(np.float32)).dtype == np.float32
    for bad in ([0.0, 0.0, 1.0 + 1.1 * tol], [1.0 - 1.1 * tol, 0.0, 0.0], [1e200, 1e200, 0.0], [1e-200, 0.0, 0.0]):
        rows = np.array([[0.0, 0.0, 1.0], bad, [0.0, 0.0, 2.0]])  # the first bad row is reported
        expected = math.hypot(*bad)
        with pytest.raises(ValueError, match="unit vectors") as info:
            check_unit_directions(rows)
        reported = float(str(info.value).rsplit("norm of ", 1)[1])
        assert reported == pytest.approx(expected, rel=1e-5), (bad, reported)


def test_functions_of_f_reject_nan_and_complex():
    from symsphere.integrands import orbit_average

    with pytest.raises(ValueError, match="'f' returned non-finite"):
        orbit_average(lambda d: np.where(d[:, 0] > 0, np.nan, 1.0), [0.3, 0.2, 0.9])
    with pytest.raises(TypeError, match="complex"):
        symsphere.integrate(lambda d: np.exp(1j * d[:, 0]), n=48, rng=1)


def test_triangle_pdf_float32_near_the_vertex_is_quiet():
    p = np.array([1e-30, 0.0, 1.0], dtype=np.float32)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for method in ("paper1", "paper2"):
            density = symsphere.square_to_triangle_pdf(p, method)
            assert density.dtype == np.float32 and density > 0


def test_huge_emission_is_rejected_not_rendered_as_inf():
    from symsphere.render import SceneError, diffuse, scene_from_dict

    with pytest.raises(SceneError, match="emission must be at most"):
        scene_from_dict({
            "camera": {"position": [0, 0, 4], "direction": [0, 0, -1], "fov": 40},
            "materials": {"lamp": {"type": "diffuse", "albedo": 0, "emission": 1e308}},
            "spheres": [{"center": [0, 0, 0], "radius": 1, "material": "lamp"}],
        })  # fmt: skip
    assert diffuse(0.5, emission=1e30).emission == (1e30,) * 3


# --- 12. minor --------------------------------------------------------------------------------------


def test_connect_none_does_not_start_a_cluster():
    distributed = pytest.importorskip("symsphere.distributed")
    pytest.importorskip("dask")
    with pytest.raises(TypeError, match="'address'"):
        distributed.connect(None)


def test_out_through_a_symlink_keeps_the_link(tmp_path):
    real = tmp_path / "data" / "d.npy"
    real.parent.mkdir()
    real.write_bytes(b"old")
    link = tmp_path / "link.npy"
    link.symlink_to(real)
    assert main(["sample", "--n", "48", "--seed", "2", "--out", str(link)]) == 0
    assert link.is_symlink()
    np.testing.assert_array_equal(np.load(real), symsphere.sample_sphere(48, rng=2))
    assert sorted(p.name for p in real.parent.iterdir()) == ["d.npy"]


def test_dielectric_validates_at_once():
    from symsphere.render import dielectric

    for bad in (-1.0, float("nan"), "glass"):
        with pytest.raises(ValueError, match="ior"):
            dielectric(ior=bad)


def test_save_png_refuses_another_suffix(tmp_path):
    from symsphere.render import save_npy, save_pfm, save_png

    for save, name in ((save_png, "x.jpg"), (save_pfm, "x.png"), (save_npy, "x.pfm")):
        with pytest.raises(ValueError, match="must end in"):
            save(tmp_path / name, np.zeros((1, 1, 3)))
    assert _listing(tmp_path) == []


def test_scene_file_too_large_is_refused(tmp_path):
    from symsphere.render import SceneError, load_scene
    from symsphere.render.scene_files import MAX_SCENE_BYTES

    path = tmp_path / "big.json"
    path.write_text(json.dumps({"name": "x" * (MAX_SCENE_BYTES + 10)}))
    with pytest.raises(SceneError, match="larger than"):
        load_scene(path)
