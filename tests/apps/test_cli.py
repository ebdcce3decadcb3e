"""The ``symsphere`` command (symsphere.apps.cli); its atomic output is tested in tests/test_io.py.

The demo verb is tested in test_demo.py, the study verb in test_study.py.
"""

import subprocess
import sys

import numpy as np
import pytest

import symsphere
from symsphere import sample_hemisphere, sample_sphere
from symsphere._testing import kernels
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
def test_integrate_to_tolerance_on_local_cluster_is_identical(capsys):
    """--rtol with --workers: the stages' blocks as tasks, the in-process result (the fused path)."""
    pytest.importorskip("distributed")
    args = ["integrate", "--integrand", "exp", "--rtol", "1e-4", "--seed", "4"]
    assert main(args) == 0
    single = [line for line in capsys.readouterr().out.splitlines() if "estimate" in line or "tolerance" in line]
    assert main(args + ["--workers", "2"]) == 0
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
