"""Reliability regression tests (the third round): one or more per defect, each
failing on the code before the fix (docs/results/reliability.md lists which, and how that was run).

Calls that could hang on the old code (a FIFO) run in a subprocess with a timeout, so that a hang is a
failure, not a stuck suite.
"""

from __future__ import annotations

import math
import os
import signal
import stat
import subprocess
import sys
import time
import warnings

import numpy as np
import pytest
from references import one_line_error, writing_in

import symsphere
from symsphere import frames, harmonics, io, points, quality, warps
from symsphere.apps import cli
from symsphere.apps.cli import main

CLI = [sys.executable, "-m", "symsphere"]
IS_ROOT = hasattr(os, "geteuid") and os.geteuid() == 0


def _listing(directory):
    return sorted(p.name for p in directory.iterdir())


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


# --- 1. --out never replaces a device or a FIFO, also through a symbolic link -----------------------


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


def test_library_writers_refuse_a_fifo_and_leave_nothing(tmp_path):
    from symsphere.render import save_image_set

    os.mkfifo(tmp_path / "x.npy")
    os.symlink("x.npy", tmp_path / "y.pfm")
    with pytest.raises(OSError, match="FIFO"):
        io.save_directions(tmp_path / "x.npy", np.array([[0.0, 0.0, 1.0]]))
    with pytest.raises(OSError, match="FIFO"):
        save_image_set([tmp_path / "y.png", tmp_path / "y.pfm"], np.zeros((2, 2, 3)))
    with pytest.raises(OSError, match="FIFO"), io.atomic_path(tmp_path / "x.npy"):
        pass
    assert stat.S_ISFIFO(os.lstat(tmp_path / "x.npy").st_mode)
    assert _listing(tmp_path) == ["x.npy", "y.pfm"]  # no temporary, no y.png


def test_demo_out_that_is_a_fifo_is_refused(tmp_path, capsys):
    os.mkfifo(tmp_path / "demo")
    assert main(["demo", "--n", "4800", "--out", str(tmp_path / "demo"), "--no-progress"]) != 0
    assert "demo" in one_line_error(capsys.readouterr().err)
    assert stat.S_ISFIFO(os.lstat(tmp_path / "demo").st_mode) and _listing(tmp_path) == ["demo"]


# --- 2. load_scene refuses a FIFO or a device by what it is, without blocking -----------------------


def test_load_scene_on_a_fifo_or_device_fails_at_once(tmp_path):
    os.mkfifo(tmp_path / "f.json")
    (tmp_path / "z.json").symlink_to("/dev/zero")
    (tmp_path / "u.toml").symlink_to("/dev/urandom")
    code = (
        "import sys\nfrom symsphere.render import load_scene, load_pfm\n"
        "for name in sys.argv[1:]:\n"
        "    try:\n"
        "        (load_pfm if name.endswith('.pfm') else load_scene)(name)\n"
        "    except ValueError as exc:\n"
        "        print(exc)\n"
    )
    os.mkfifo(tmp_path / "p.pfm")
    names = [str(tmp_path / n) for n in ("f.json", "z.json", "u.toml", "p.pfm")]
    run = subprocess.run([sys.executable, "-c", code, *names], capture_output=True, text=True, timeout=60)
    lines = run.stdout.splitlines()
    assert run.returncode == 0 and len(lines) == 4, (run.stdout, run.stderr)
    assert "is a FIFO (named pipe), not a regular file" in lines[0]
    assert "is a character device, not a regular file" in lines[1] and "character device" in lines[2]
    assert "FIFO" in lines[3]


def test_render_scene_fifo_says_what_it_is(tmp_path):
    os.mkfifo(tmp_path / "f.json")
    (tmp_path / "z.json").symlink_to("/dev/zero")
    for name, kind in (("f.json", "a FIFO"), ("z.json", "a character device")):
        run = subprocess.run(CLI + ["render", "--scene", str(tmp_path / name), "--out", str(tmp_path / "x.png")],
                             capture_output=True, text=True, timeout=120)  # fmt: skip
        line = one_line_error(run.stderr)
        assert run.returncode == 2 and kind in line and "does not exist" not in line, line


# --- 3. absurd sizes name the argument and the limit; work beyond a day needs --allow-long ---------


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
    monkeypatch.setattr(symsphere.render, "render", lambda *a, **k: pytest.fail("rendered"))
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


# --- 4. a late SIGINT: before the rename, roll back (130); once it has begun, finish (0) ----------


N_LATE = 48 * 2**10


@pytest.fixture(autouse=True)
def _python_sigint_handler():
    """Python's own SIGINT handler (KeyboardInterrupt) in every test: a pytest-xdist worker runs with another."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def _inject_sigint(monkeypatch, module, name, at_call):
    """Send SIGINT to this process from inside the at_call-th call of module.name (after the call)."""
    real = getattr(module, name)
    calls = []

    def wrapper(*args, **kwargs):
        calls.append(None)
        result = real(*args, **kwargs)
        if len(calls) == at_call:
            os.kill(os.getpid(), signal.SIGINT)
        return result

    monkeypatch.setattr(module, name, wrapper)


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

        _inject_sigint(monkeypatch, builtins, "print", at_call)
    else:
        _inject_sigint(monkeypatch, os, name, at_call)
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


def test_sigint_just_after_the_temporary_is_created_leaves_nothing(tmp_path, monkeypatch):
    # The window between the temporary's creation (os.open) and its entry in the list of files to
    # remove: a SIGINT there (found by test_late_sigint_at_many_times on a loaded machine) is deferred
    # until the file is listed, so the rollback removes it.
    import fcntl

    from symsphere.io import atomic_path

    out = tmp_path / "d.npy"
    out.write_bytes(b"old")
    if hasattr(os, "O_TMPFILE"):  # Linux: the temporary is the unnamed file of the first os.open
        _inject_sigint(monkeypatch, os, "open", 1)
    else:
        _inject_sigint(monkeypatch, fcntl, "flock", 1)  # right after the temporary's os.open
    with pytest.raises(KeyboardInterrupt):
        with atomic_path(out) as tmp:
            tmp.write_bytes(b"new")
    monkeypatch.undo()
    assert _listing(tmp_path) == ["d.npy"] and out.read_bytes() == b"old"


def test_sigint_during_the_renames_of_a_set_is_delivered_after_them(tmp_path, monkeypatch):
    from symsphere.render import save_image_set

    paths = [tmp_path / f"a{s}" for s in (".png", ".pfm", ".npy")]
    save_image_set(paths, np.zeros((2, 2, 3)))
    _inject_sigint(monkeypatch, os, "replace", 2)  # between the second and the third rename
    with pytest.raises(KeyboardInterrupt):
        save_image_set(paths, np.ones((2, 2, 3)))
    monkeypatch.undo()
    assert np.load(paths[2]).tolist() == np.ones((2, 2, 3)).tolist()  # all three are the new ones
    assert _listing(tmp_path) == ["a.npy", "a.pfm", "a.png"]


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
        process = subprocess.Popen(CLI + ["sample", "--n", str(n), "--dtype", "float32", "--seed", "2", "--out", str(out)],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
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


# --- 5. wrong exception types and unnamed arguments --------------------------------------------------


@pytest.mark.parametrize(
    "call, error, named",
    [
        (lambda: frames.to_local(np.ones((1, 3)), None), TypeError, "'basis'"),
        (lambda: frames.to_world("abc", np.eye(3)), TypeError, "'local'"),
        (lambda: frames.to_world(np.ones((1, 3)), "xyz"), TypeError, "'basis'"),
        (lambda: frames.frame([math.nan, 0, 1]), ValueError, "'normal'"),
        (lambda: frames.frame([0, 0, 2.0]), ValueError, "'normal'"),
        (lambda: frames.frame_rows(math.inf, 0, 1), ValueError, "'nx'"),
        (lambda: frames.frame_rows(None, 0, 1), TypeError, "'nx'"),
        (lambda: harmonics.polynomial_integral({(2, 0, 0): math.inf}), ValueError, "'coeffs'"),
        (lambda: harmonics.polynomial_integral({(2, 0, 0): math.nan}), ValueError, "'coeffs'"),
        (lambda: harmonics.polynomial_integral({(2, 0, 0): "1"}), TypeError, "'coeffs'"),
        (lambda: warps.cosine_wedge_point(-1.0, 0.4), ValueError, "'u'"),
        (lambda: warps.cosine_wedge_point(0.5, math.nan), ValueError, "'v'"),
        (lambda: warps.cosine_wedge_density(None, 0.0, 1.0), TypeError, "'x'"),
        (lambda: warps.cosine_wedge_density(0.0, 0.0, 2.0), ValueError, "'x, y, z'"),
        (lambda: warps.cosine_wedge_uv(0.0, 0.6, 0.8), ValueError, "'x', 'y', 'z'"),
        (lambda: symsphere.render.render("furnace", width=2, height=2, spp=1, seed=np.random.PCG64(1)), TypeError,
         "'seed'"),
    ],
)  # fmt: skip
def test_wrong_types_and_values_name_the_argument(call, error, named):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(error, match=named):
            call()


def test_scalar_functions_still_compile_in_kernels():
    from numba import njit

    @njit
    def kernel(u, v):
        x, y, z = warps.cosine_wedge_point(u, v)
        t, b = frames.frame_rows(x, y, z)
        return z, t[0], warps.cosine_wedge_density(x, y, z), warps.cosine_wedge_uv(x, y, z)[0]

    z, t0, density, u = kernel(0.75, 0.3)
    assert z == 0.5 and abs(density - 4 / math.pi) < 1e-15 and abs(u - 0.75) < 1e-15
    assert t0 == frames.frame_rows(*warps.cosine_wedge_point(0.75, 0.3))[0][0]


# --- 6. integrate with an f of shape (m, 0) -----------------------------------------------------------


@pytest.mark.parametrize("options", [dict(n=96), dict(atol=1e-2)])
def test_integrate_rejects_empty_components(options):
    with pytest.raises(ValueError, match="'f' must return shape"):
        symsphere.integrate(lambda d: np.zeros((len(d), 0)), rng=1, **options)


# --- 7. per_point is checked for every point set --------------------------------------------------------


@pytest.mark.parametrize("point_set", ["random", "sobol", "halton", "sobol_interlaced2", "sobol_interlaced3"])
def test_per_point_is_checked(point_set):
    with pytest.raises(TypeError, match="'per_point'"):
        points.unit_square_points(64, point_set, 1, per_point="x")
    for bad in (-1, 0):
        with pytest.raises(ValueError, match="'per_point'"):
            points.unit_square_points(64, point_set, 1, per_point=bad)
    with pytest.raises(ValueError, match="per_point"):
        points.unit_square_points(64, point_set, 1, per_point=2**60)
    assert points.unit_square_points(64, point_set, 1, per_point=48).shape == (64, 2)


# --- 8. render --out errors name the user's path and come before the render ------------------------


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


# --- 9. temporaries: none during the render, and a killed run's are removed by the next ----------------


def test_image_temporaries_exist_only_while_writing(tmp_path, monkeypatch):
    from symsphere.render import image as image_module

    real_encode = image_module._encode
    seen = []

    def encode(*args):
        seen.append(_listing(tmp_path))
        return real_encode(*args)

    monkeypatch.setattr(image_module, "_encode", encode)
    image_module.save_image_set([tmp_path / "a.png", tmp_path / "a.pfm", tmp_path / "a.npy"], np.zeros((2, 2, 3)))
    assert seen == [[], [], []]


def test_sigkill_during_a_write_leaves_nothing_and_stale_temporaries_are_removed(tmp_path):
    out = tmp_path / "big.npy"
    process = subprocess.Popen(CLI + ["sample", "--n", str(48 * 2**22), "--chunk", str(48 * 2**12), "--out", str(out)],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
    deadline = time.monotonic() + 120
    while not writing_in(process.pid, tmp_path, min_size=1) and time.monotonic() < deadline:
        time.sleep(0.01)
    process.kill()
    process.wait(timeout=60)
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
        run = subprocess.run(CLI + ["sample", "--n", "96", "--seed", "1", "--out", str(out)], capture_output=True,
                             text=True, timeout=120)  # fmt: skip
        assert run.returncode == 0, run.stderr
        assert _listing(tmp_path) == [".big.npy.0123abcd.tmp", ".big.npy.notours.tmp", "big.npy"]
        assert "note: removed 1 temporary that a killed run left beside big.npy (.big.npy.4194305-0123abcd.tmp)" in (
            run.stderr
        )


def test_a_killed_demo_or_study_directory_is_removed_by_the_next_write(tmp_path):
    target = tmp_path / "report"
    left = tmp_path / ".report.4194305-89abcdef.tmp"  # a pid beyond the kernel's maximum: no such process
    left.mkdir()
    (left / "figure.png").write_bytes(b"partial")
    with pytest.warns(UserWarning, match=r"removed 1 temporary that a killed run left beside report"):
        with io.atomic_directory(target) as build:
            (build / "report.md").write_text("# done")
    assert _listing(tmp_path) == ["report"]


# --- 10. no zero, non-unit or NaN rows written; no negative weights ----------------------------------


def test_writers_refuse_rows_that_are_not_directions(tmp_path):
    for rows in (np.zeros((2, 3)), np.array([[0.0, 0.0, 2.0]])):
        with pytest.raises(ValueError, match="'directions'"):
            io.save_directions(tmp_path / "d.npy", rows)
    with pytest.raises(ValueError, match="'blocks'"):
        io.stream_directions(tmp_path / "d.npy", 48, np.float64, lambda out: [np.full((48, 3), np.nan)])
    with pytest.raises(ValueError, match="'blocks'"):
        io.stream_directions(tmp_path / "d.csv", 48, np.float32, lambda out: [np.zeros((48, 3))])
    assert _listing(tmp_path) == []


def test_cap_discrepancy_refuses_negative_weights():
    x = np.vstack([np.eye(3), -np.eye(3)])
    with pytest.raises(ValueError, match="'weights' must be >= 0"):
        quality.cap_discrepancy(x, weights=np.array([1.0, -1, 1, 1, 1, 1]))


# --- 11. returned hemisphere rows are on or above the plane, in their dtype and in float64 ---------


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_rotated_hemisphere_rows_are_not_below_the_plane(dtype):
    from scipy.stats import qmc

    cases = [
        (
            [0.3, -0.5, 0.8],
            symsphere.sample_hemisphere(96, normal=[0.3, -0.5, 0.8], points=qmc.Sobol(2, scramble=False), dtype=dtype),
        )
    ]
    rng = np.random.default_rng(22)
    for seed in range(40):
        normal = rng.normal(size=3)
        cases.append((normal, symsphere.sample_hemisphere(24 * 512, normal=normal, rng=seed, dtype=dtype)))
    for normal, d in cases:
        normal = np.asarray(normal)
        assert np.all(d.astype(np.float64) @ normal >= 0)  # the check, in float64
        assert np.all(d @ normal.astype(dtype) >= 0)  # and in the rows' own dtype
        unit = normal / np.linalg.norm(normal)
        assert np.all(d.astype(np.float64) @ unit >= 0) and np.all(d @ unit.astype(dtype) >= 0)
    block = next(iter(symsphere.iter_hemisphere(24 * 64, chunk=24 * 32, normal=[0.3, -0.5, 0.8],
                                                points=qmc.Sobol(2, scramble=False), dtype=dtype)))  # fmt: skip
    assert np.all(block.astype(np.float64) @ np.array([0.3, -0.5, 0.8]) >= 0)
