"""The ``symsphere`` command (symsphere.apps.cli); its atomic output is tested in tests/test_io.py.

The demo verb is tested in test_demo.py, the study verb in test_study.py.
"""

import os
import shutil
import signal
import stat
import subprocess
import sys
import time

import fresh_processes
import numpy as np
import pytest
from references import catches, inject_sigint, one_line_error, scaled_for_load, writing_in

import symsphere
from symsphere import sample_hemisphere, sample_sphere
from symsphere._testing import kernels
from symsphere.apps import cli
from symsphere.apps.cli import main


def _read_csv(path, dtype=np.float64):
    with open(path) as handle:
        assert handle.readline() == "x,y,z\n"
    return np.loadtxt(path, delimiter=",", skiprows=1, dtype=dtype, ndmin=2)


def _leftovers(directory):
    """Everything in *directory*: after a failure it must be empty (no target, no temporary)."""
    return sorted(p.name for p in directory.iterdir())


# --- sample ---------------------------------------------------------------------


@pytest.mark.parametrize(
    "method, points, dtype",
    [("equal_area", "random", "float64"), ("paper2", "sobol", "float64"), ("equal_area", "halton", "float32")],
)
@pytest.mark.parametrize("suffix", [".npy", ".csv"])
def test_sample_writes_what_the_library_returns(tmp_path, capsys, method, points, dtype, suffix):
    out = tmp_path / f"directions{suffix}"
    status = main(
        ["sample", "--n", "768", "--method", method, "--points", points, "--seed", "7", "--dtype", dtype]
        + ["--out", str(out)]
    )
    assert status == 0
    expected = sample_sphere(768, method=method, points=points, rng=7, dtype=dtype)
    written = np.load(out) if suffix == ".npy" else _read_csv(out, dtype)
    assert written.dtype == expected.dtype
    # %.17g (float64) and %.9g (float32) round-trip exactly.
    np.testing.assert_array_equal(written, expected)
    closing = capsys.readouterr().out.strip().splitlines()
    assert len(closing) == 1
    assert "768 directions" in closing[0] and str(out) in closing[0] and closing[0].endswith(" s")
    assert _leftovers(tmp_path) == [out.name]


def test_sample_hemisphere_with_normal(tmp_path):
    out = tmp_path / "hemi.npy"
    arguments = ["sample", "--n", "240", "--domain", "hemisphere", "--normal", "0", "2", "0", "--seed", "3"]
    assert main([*arguments, "--out", str(out)]) == 0
    written = np.load(out)
    np.testing.assert_array_equal(written, sample_hemisphere(240, normal=[0.0, 2.0, 0.0], rng=3))
    assert np.all(written[:, 1] >= -1e-15)  # the hemisphere about +y


def test_sample_without_seed_prints_a_seed_that_reproduces_the_file(tmp_path, capsys):
    out = tmp_path / "d.npy"
    assert main(["sample", "--n", "96", "--out", str(out)]) == 0
    seed = int(capsys.readouterr().out.split("seed ")[1].split(",")[0])
    np.testing.assert_array_equal(np.load(out), sample_sphere(96, rng=seed))


def test_sample_replaces_an_existing_file(tmp_path):
    out = tmp_path / "d.csv"
    out.write_text("old\n")
    assert main(["sample", "--n", "48", "--seed", "0", "--out", str(out)]) == 0
    np.testing.assert_array_equal(_read_csv(out), sample_sphere(48, rng=0))


@pytest.mark.parametrize(
    "arguments, named",
    [
        (["--n", "100"], "'n'"),  # not a multiple of 48
        (["--n", "36", "--domain", "hemisphere"], "'n'"),  # not a multiple of 24
        (["--n", "0"], "'n'"),
        (["--n", "96", "--method", "bogus"], "--method"),
        (["--n", "96", "--points", "lattice"], "--points"),
        (["--n", "96", "--points", "stratified"], "stratified"),  # 96/48 = 2 is not a square
        (["--n", "96", "--dtype", "float16"], "--dtype"),
        (["--n", "96", "--seed", "-1"], "--seed"),
        (["--n", "96", "--normal", "0", "0", "1"], "--normal"),  # sphere has no normal
        (["--n", "96", "--domain", "hemisphere", "--normal", "0", "0", "0"], "'normal'"),
        (["--n", "many"], "--n"),
    ],
)
def test_sample_rejects_invalid_values(tmp_path, capsys, arguments, named):
    out = tmp_path / "d.npy"
    assert main(["sample", *arguments, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "symsphere sample: error:" in err and named in err
    assert "Traceback" not in err
    assert _leftovers(tmp_path) == []


@pytest.mark.parametrize("name", ["d.txt", "d", "d.npz"])
def test_sample_rejects_unknown_suffix(tmp_path, capsys, name):
    assert main(["sample", "--n", "96", "--out", str(tmp_path / name)]) == 2
    err = capsys.readouterr().err
    assert "--out" in err and ".npy" in err and ".csv" in err
    assert _leftovers(tmp_path) == []


def test_sample_into_missing_directory_fails_cleanly(tmp_path, capsys):
    out = tmp_path / "missing" / "d.npy"
    assert main(["sample", "--n", "96", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert str(out) in err and "Traceback" not in err


# --- atomic output --------------------------------------------------------------


def test_interrupted_command_leaves_no_file_and_keeps_the_old_one(tmp_path, monkeypatch, capsys):

    out = tmp_path / "d.npy"
    out.write_bytes(b"previous run")
    calls = []
    original = kernels.fill  # the one kernel entry of every sampling call

    def interrupted_on_third_chunk(*args):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return original(*args)

    monkeypatch.setattr(kernels, "fill", interrupted_on_third_chunk)
    assert main(["sample", "--n", "960", "--chunk", "96", "--seed", "1", "--out", str(out)]) == 130
    assert len(calls) == 3
    assert "interrupted" in capsys.readouterr().err
    assert _leftovers(tmp_path) == [out.name]
    assert out.read_bytes() == b"previous run"


@pytest.mark.parametrize("suffix", [".npy", ".csv"])
def test_streamed_output_equals_one_shot(tmp_path, suffix):
    out = tmp_path / f"d{suffix}"
    args = ["sample", "--n", "4800", "--chunk", "480", "--domain", "hemisphere", "--normal", "0", "1", "1"]
    assert main(args + ["--seed", "9", "--out", str(out)]) == 0
    got = np.load(out) if suffix == ".npy" else np.loadtxt(out, delimiter=",", skiprows=1)
    from symsphere import sample_hemisphere

    assert np.array_equal(got, sample_hemisphere(4800, normal=[0, 1, 1], rng=9))


# --- help and version -----------------------------------------------------------


@pytest.mark.parametrize("verb", [[], ["sample"], ["demo"]])
def test_help_exits_zero(capsys, verb):
    assert main([*verb, "--help"]) == 0
    assert "usage: symsphere" in capsys.readouterr().out


def test_version(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"symsphere {symsphere.__version__}"


def test_no_verb_is_a_usage_error(capsys):
    assert main([]) == 2
    assert "usage: symsphere" in capsys.readouterr().err


def test_python_dash_m(tmp_path):
    run = subprocess.run(
        [sys.executable, "-m", "symsphere", "sample", "--n", "50", "--out", str(tmp_path / "d.npy")],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 2
    assert "symsphere sample: error: 'n'=50 is not a multiple of 48" in run.stderr
    assert "Traceback" not in run.stderr
    assert _leftovers(tmp_path) == []


def test_integrate_prints_estimate_and_exact(capsys):
    assert main(["integrate", "--integrand", "exp", "--n", "4800", "--seed", "1"]) == 0
    out = capsys.readouterr().out
    assert "estimate" in out and "exact     14.5379897513" in out and "100 orbits" in out


@pytest.mark.xdist_group("dask")  # local Dask clusters: with the other cluster tests (Makefile: --dist loadgroup)
def test_integrate_on_local_cluster_is_identical(capsys):
    pytest.importorskip("distributed")
    args = ["integrate", "--integrand", "cap", "--n", str(48 * 4096 * 2), "--seed", "4"]
    assert main(args) == 0
    single = [line for line in capsys.readouterr().out.splitlines() if "estimate" in line]
    assert main(args + ["--workers", "2"]) == 0
    clustered = [line for line in capsys.readouterr().out.splitlines() if "estimate" in line]
    assert single == clustered and single


@pytest.mark.xdist_group("dask")
def test_integrate_to_tolerance_on_a_running_cluster_is_identical(capsys, dask_client):
    """--rtol with --scheduler: the stages' blocks as tasks, the in-process result (the fused path).  The
    running cluster is the session's (tests/conftest.py); --rtol with --workers is the command that
    docs/tutorials/scale-out.md shows, and tests/test_docs.py runs it."""
    args = ["integrate", "--integrand", "exp", "--rtol", "1e-4", "--seed", "4"]
    assert main(args) == 0
    single = [line for line in capsys.readouterr().out.splitlines() if "estimate" in line or "tolerance" in line]
    assert main(args + ["--scheduler", dask_client.scheduler.address]) == 0
    clustered = [line for line in capsys.readouterr().out.splitlines() if "estimate" in line or "tolerance" in line]
    assert single == clustered and len(single) == 2


@pytest.mark.parametrize(
    "args, match",
    [
        (["integrate", "--integrand", "nope", "--n", "48"], "--integrand 'nope' is not known"),
        (["integrate", "--integrand", "exp", "--n", "50"], "'n'=50 is not a multiple of 48"),
        (["integrate", "--integrand", "exp", "--n", "48", "--workers", "0"], "--workers must be a positive integer"),
    ],
)
def test_integrate_bad_arguments(capsys, args, match):
    assert main(args) == 2
    assert match in capsys.readouterr().err


def test_unreachable_scheduler_is_a_clear_error(capsys):
    pytest.importorskip("distributed")
    args = ["integrate", "--integrand", "exp", "--n", "48", "--scheduler", "tcp://127.0.0.1:9", "--timeout", "1"]
    assert main(args) == 1
    assert "could not reach the Dask scheduler" in capsys.readouterr().err


def test_cli_start_imports_no_heavy_scipy():
    """Starting the command line imports what ``import symsphere`` does of scipy, not scipy.integrate,
    scipy.special or scipy.spatial (~0.5 s of every start; docs/results/cold-start.md, "No scipy at command-line start")."""
    code = (
        "import sys, symsphere.apps.cli\n"
        "print(sorted(m for m in ('scipy.integrate', 'scipy.special', 'scipy.spatial') if m in sys.modules))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)
    assert done.stdout.strip() == "[]", done.stdout


def test_a_signal_dropped_in_a_callback_that_made_the_work_fail_ends_as_the_signal(tmp_path, monkeypatch, capsys):
    # numba's compile drops a KeyboardInterrupt raised in an LLVM callback and then fails with
    # "no compiled object yet": the run must end as interrupted (130), not as an internal error (1).
    import signal

    from symsphere.apps import cli

    def fails_after_a_lost_interrupt(args):
        try:
            signal.raise_signal(signal.SIGINT)
        except KeyboardInterrupt:
            pass  # lost, as inside a C callback
        raise RuntimeError("no compiled object yet for <Library '_first_non_unit_row'>")

    monkeypatch.setattr(cli, "_run_sample", fails_after_a_lost_interrupt)
    assert main(["sample", "--n", "48", "--out", str(tmp_path / "d.npy")]) == 130
    err = capsys.readouterr().err
    assert "interrupted; nothing was written" in err and "internal error" not in err
    assert _leftovers(tmp_path) == []


# --- full disks, signals, memory and messages of the commands (sample, render, integrate): one line, the documented exit status, nothing left behind ---


CLI = [sys.executable, "-m", "symsphere"]
IS_ROOT = hasattr(os, "geteuid") and os.geteuid() == 0
N_LATE = 48 * 2**10


def _listing(directory):
    return sorted(p.name for p in directory.iterdir())


def _unshare_available() -> bool:
    if shutil.which("unshare") is None or sys.platform != "linux":
        return False
    probe = subprocess.run(
        ["unshare", "-rm", "sh", "-c", "d=$(mktemp -d) && mount -t tmpfs -o size=1m tmpfs $d && umount $d"],
        capture_output=True,
    )
    return probe.returncode == 0


def _start_and_terminate(args, tmp_path, wait_for):
    process = fresh_processes.Child(["-m", "symsphere", *args], tmp_path)  # python -m symsphere, forked
    deadline = time.monotonic() + 120
    while not wait_for(process) and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    assert process.poll() is None, "the command finished before it could be signalled"
    process.send_signal(signal.SIGTERM)
    _, stderr = process.communicate(timeout=120)
    return process.returncode, stderr


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


def _scene_text(settings="", sphere_radius="1"):
    return (
        "camera = {position = [0, 0, 4], look_at = [0, 0, 0], fov = 40}\n"
        'materials.lamp = {type = "diffuse", albedo = 0.5, emission = 1}\n'
        f'spheres = [{{center = [0, 0, 0], radius = {sphere_radius}, material = "lamp"}}]\n' + settings
    )


def _special_files(tmp_path):
    """(name, path, kind test) for a FIFO and, as root, a clone of /dev/null (c 1 3) and of /dev/full (c 1 7)."""
    made = []
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    made.append((fifo, stat.S_ISFIFO))
    if IS_ROOT:
        for name, minor in (("nullclone", 3), ("fullclone", 7)):
            os.mknod(tmp_path / name, 0o666 | stat.S_IFCHR, os.makedev(1, minor))
            made.append((tmp_path / name, stat.S_ISCHR))
    return made


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
    started = time.monotonic() + (0 if sys.platform == "linux" else 2.0)  # elsewhere: 4 s after the start
    status, stderr = _start_and_terminate(
        ["render", "--scene", "cornell", "--width", "64", "--height", "48", "--spp", "480000", "--no-progress",
         "--out", str(tmp_path / "img.png")],
        tmp_path,
        # main() has installed its handler (a loaded machine can take seconds to import the package), then 2 s
        lambda process: (catches(process.pid, signal.SIGTERM) or sys.platform != "linux")
        and time.monotonic() - started > 2.0,
    )  # fmt: skip
    assert status == 143
    assert "terminated (SIGTERM)" in one_line_error(stderr)
    assert _listing(tmp_path) == []


def test_sigterm_handler_is_restored_after_main(tmp_path):
    before = signal.getsignal(signal.SIGTERM)
    assert main(["sample", "--n", "48", "--seed", "1", "--out", str(tmp_path / "d.npy")]) == 0
    assert signal.getsignal(signal.SIGTERM) is before


@pytest.mark.slow
def test_sample_peak_rss_does_not_grow_with_n(tmp_path):
    small = _peak_rss_mb(["sample", "--n", str(48 * 2**15), "--dtype", "float32", "--seed", "1",
                          "--out", str(tmp_path / "small.npy")])  # fmt: skip
    large = _peak_rss_mb(["sample", "--n", str(48 * 2**20), "--dtype", "float32", "--seed", "1",
                          "--out", str(tmp_path / "large.npy")])  # fmt: skip
    # 32 times the directions (604 MB of output, 6 times the bound): the old memory map kept it all resident.
    assert large - small < 100, (small, large)
    assert np.load(tmp_path / "large.npy", mmap_mode="r").shape == (48 * 2**20, 3)


def test_a_long_integration_prints_an_estimate_first(capsys, monkeypatch):
    from symsphere.apps import cli

    monkeypatch.setattr(cli, "_ESTIMATE_ABOVE", 48 * 2**10)  # "long", scaled down
    assert main(["integrate", "--integrand", "exp", "--n", str(48 * 2**12), "--seed", "1"]) == 0
    err = capsys.readouterr().err
    assert f"{48 * 2**12} evaluations, estimated" in err and "evaluations/s" in err


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


@pytest.mark.parametrize("through_link", [False, True])
def test_sample_out_refuses_devices_and_fifos(tmp_path, capsys, through_link):
    for special, is_kind in _special_files(tmp_path):
        out = special
        if through_link:
            out = tmp_path / f"{special.name}-link.npy"
            out.symlink_to(special.name)
        else:  # the suffix check comes first: give the special file a .npy name
            out = special.rename(tmp_path / f"{special.name}.npy")
            special = out
        status = main(["sample", "--n", "96", "--seed", "1", "--out", str(out)])
        line = one_line_error(capsys.readouterr().err)
        assert status == 1 and str(out) in line and "not a regular file" in line, line
        assert is_kind(os.lstat(special).st_mode), f"{special} was replaced"


def test_render_scene_fifo_says_what_it_is(tmp_path):
    os.mkfifo(tmp_path / "f.json")
    (tmp_path / "z.json").symlink_to("/dev/zero")
    for name, kind in (("f.json", "a FIFO"), ("z.json", "a character device")):
        run = fresh_processes.run(["-m", "symsphere", "render", "--scene", str(tmp_path / name), "--out",
                                   str(tmp_path / "x.png")], tmp_path, timeout=120)  # fmt: skip
        line = one_line_error(run.stderr)
        assert run.returncode == 2 and kind in line and "does not exist" not in line, line


def test_absurd_render_sizes_name_the_argument(capsys):
    cases = [
        (["--width", str(2**40), "--height", str(2**40), "--spp", "1"], "'--width * --height'"),
        (["--width", str(2**31), "--height", str(2**31)], "'--width * --height'"),
        (["--spp", str(10**15)], "'--spp'"),
    ]
    for options, named in cases:
        start = time.monotonic()
        assert main(["render", *options, "--out", "never.png"]) == 2
        line = one_line_error(capsys.readouterr().err)
        assert named in line and "at most" in line and "array is too big" not in line, line
        assert time.monotonic() - start < 10
    with pytest.raises(ValueError, match=r"'width \* height'=4611686018427387904 is too large"):
        symsphere.render.render("furnace", width=2**31, height=2**31, spp=1)


def test_work_beyond_a_day_needs_allow_long(capsys, monkeypatch):
    from symsphere._testing import validation

    monkeypatch.setattr(symsphere.render, "render", lambda *a, **k: pytest.fail("rendered"))
    # A machine whose memory holds the partial sums of 48e13 evaluations (on a smaller one the memory
    # bound, which --allow-long cannot lift, is said first: tests/test_integration.py)
    monkeypatch.setattr(validation.values, "machine_memory", lambda: 2**50)
    start = time.monotonic()
    assert main(["render", "--spp", str(10**13), "--out", "never.png"]) == 2
    assert "--allow-long" in one_line_error(capsys.readouterr().err)
    assert main(["integrate", "--integrand", "exp", "--n", str(48 * 10**13)]) == 2
    line = one_line_error(capsys.readouterr().err)
    assert "days" in line and "--allow-long" in line, line
    assert main(["sample", "--n", str(48 * 10**13), "--out", "never.npy"]) == 2
    assert "--allow-long" in one_line_error(capsys.readouterr().err)
    assert time.monotonic() - start < 60
    for verb in ("sample", "integrate", "render"):
        assert "--allow-long" in cli.build_parser()._subparsers._group_actions[0].choices[verb].format_help()


@pytest.mark.usefixtures("python_sigint_handler")
@pytest.mark.parametrize(
    "where, expected",
    [(("block", 1), 130), (("block", 3), 130), (("fsync", 1), 130), (("replace", 1), 0), (("print", 1), 0)],
)
def test_late_sigint_in_process_has_one_outcome(tmp_path, monkeypatch, capsys, where, expected):
    out = tmp_path / "d.npy"
    np.save(out, np.zeros((1, 3)))
    old = out.read_bytes()
    name, at_call = where
    if name == "block":  # while the blocks are computed and written into the temporary
        real_iter = cli.iter_sphere

        def iter_sphere(*args, **kwargs):
            for index, block in enumerate(real_iter(*args, **kwargs), 1):
                if index == at_call:
                    os.kill(os.getpid(), signal.SIGINT)
                yield block

        monkeypatch.setattr(cli, "iter_sphere", iter_sphere)
    elif name == "print":
        import builtins

        inject_sigint(monkeypatch, builtins, "print", at_call)
    else:
        inject_sigint(monkeypatch, os, name, at_call)
    status = main(["sample", "--n", str(N_LATE), "--chunk", str(48 * 2**8), "--seed", "1", "--out", str(out)])
    monkeypatch.undo()
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert status == expected, err
    assert _listing(tmp_path) == ["d.npy"]
    if expected == 130:
        assert out.read_bytes() == old and "interrupted; nothing was written" in err
    else:
        np.testing.assert_array_equal(np.load(out), symsphere.sample_sphere(N_LATE, rng=1))


def test_late_sigint_at_many_times(tmp_path):
    # The case, scaled down (float32, the target exists): SIGINT at times spread over the
    # window from the moment the temporary appears to the process's end.  Every run either rolls back
    # (130, the old file, one line) or finishes (0, the complete new file); never a death by signal or
    # a traceback.  The window is measured by a first run that is not signalled (it must finish), so
    # the signals land inside it on a fast or a slow machine (fixed delays of up to 2.5 s had landed
    # after the end, sending nothing, in about a third of the runs); so n need not be large to be hit.
    n = 48 * 2**16
    out = tmp_path / "d.npy"

    def run(fraction=None, window=0.0):
        np.save(out, np.zeros((1, 3), np.float32))
        # python -m symsphere, forked from a process that imported the library (tests/fresh_processes.py): the
        # signals land after the imports (the temporary appears later), so a new interpreter's start adds nothing
        process = fresh_processes.Child(
            ["-m", "symsphere", "sample", "--n", str(n), "--dtype", "float32", "--seed", "2", "--out", str(out)],
            tmp_path,
        )
        deadline = time.monotonic() + 120
        while process.poll() is None and time.monotonic() < deadline:
            if writing_in(process.pid, tmp_path):
                break
            time.sleep(0.002)
        appeared = time.monotonic()
        if fraction is not None:
            time.sleep(fraction * window)
            if process.poll() is None:
                process.send_signal(signal.SIGINT)
        stdout, stderr = process.communicate(timeout=120)
        window = time.monotonic() - appeared
        assert "Traceback" not in stderr and process.returncode in (0, 130), (fraction, process.returncode, stderr)
        assert _listing(tmp_path) == ["d.npy"]
        data = np.load(out)
        if process.returncode == 130:
            assert data.shape == (1, 3) and "nothing was written" in one_line_error(stderr)
        else:
            assert data.shape == (n, 3) and "wrote" in stdout
        return process.returncode, window

    status, window = run()
    assert status == 0
    outcomes = [run(fraction, window)[0] for fraction in (0.0, 0.02, 0.05, 0.1, 0.2, 0.35, 0.5, 0.65, 0.8, 0.95)]
    assert 130 in outcomes  # the early signals rolled back


def test_render_out_errors_name_the_path_before_rendering(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(symsphere.render, "render", lambda *a, **k: pytest.fail("rendered before checking --out"))
    (tmp_path / "afile").write_text("a file, not a directory")
    (tmp_path / "x.pfm").mkdir()
    cases = [
        ("/proc/x.png", "/proc/x.png"),
        (str(tmp_path / "x.png"), "x.pfm"),  # the PFM written beside it is a directory
        (str(tmp_path / "afile" / "x.png"), "is not a directory"),
    ]
    for out, said in cases:
        assert main(["render", "--width", "4", "--height", "3", "--spp", "2", "--out", out]) == 1
        line = one_line_error(capsys.readouterr().err)
        assert said in line and ".tmp" not in line and "'paths'" not in line, line
    assert _listing(tmp_path) == ["afile", "x.pfm"]


def test_sigkill_during_a_write_leaves_nothing_and_stale_temporaries_are_removed(tmp_path):
    out = tmp_path / "big.npy"
    process = fresh_processes.Child(
        ["-m", "symsphere", "sample", "--n", str(48 * 2**22), "--chunk", str(48 * 2**12), "--out", str(out)], tmp_path
    )
    deadline = time.monotonic() + 120
    while not writing_in(process.pid, tmp_path, min_size=1) and time.monotonic() < deadline:
        time.sleep(0.01)
    process.kill()
    process.communicate(timeout=60)
    if hasattr(os, "O_TMPFILE"):  # Linux: the temporary was unnamed; SIGKILL leaves nothing at all
        assert _listing(tmp_path) == []
    # What a killed process leaves where files cannot be unnamed (or in the instant of the rename): a
    # temporary named after its process, which no longer exists (a pid beyond the kernel's maximum).
    dead = tmp_path / ".big.npy.4194305-0123abcd.tmp"
    dead.write_text("a killed run's partial output")
    live = tmp_path / ".big.npy.0123abcd.tmp"  # a writer still at work: locked, so never taken
    live.write_text("in use")
    import fcntl

    with open(live) as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        old = time.time() - 3600
        os.utime(live, (old, old))
        (tmp_path / ".big.npy.notours.tmp").write_text("another pattern")
        os.utime(tmp_path / ".big.npy.notours.tmp", (old, old))
        run = fresh_processes.run(["-m", "symsphere", "sample", "--n", "96", "--seed", "1", "--out", str(out)], tmp_path,
                                  timeout=120)  # fmt: skip
        assert run.returncode == 0, run.stderr
        assert _listing(tmp_path) == [".big.npy.0123abcd.tmp", ".big.npy.notours.tmp", "big.npy"]
        assert "note: removed 1 temporary that a killed run left beside big.npy (.big.npy.4194305-0123abcd.tmp)" in (
            run.stderr
        )
