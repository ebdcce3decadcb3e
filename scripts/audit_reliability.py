"""The reliability audit of docs/results/reliability.md, rerunnable: hostile inputs, files that are not ours,
signals, absurd sizes.  Prints one markdown table (and, with --verbose, every finding).

    .venv/bin/python scripts/audit_reliability.py            # about 5 minutes on 2 shared cores
    .venv/bin/python scripts/audit_reliability.py --quick    # the bad-input table only

What it counts (a finding is anything but the last column's "0"):

- bad inputs: every public function of the library below ``symsphere.render`` (the property tests'
  table of valid arguments, ``tests/test_properties.py``, without its ``TRUSTED`` formulas) and ten of
  ``symsphere.render``, called with valid arguments but one, replaced in turn by each of 34 fixed odd values (None, bools, strings, NaN,
  inf, 2**70, empty, ragged, object and complex arrays, ...).  Each call must return finite output or
  raise ValueError/TypeError whose one-line message names the argument, without a warning, within
  10 s.  "crashes" are deaths of the process that runs the table (it is a child process); "hangs" are
  calls past 10 s; "wrong types" other exceptions or warnings; "unnamed" errors that do not name the
  argument; "non-finite" results with NaN or inf.
- not ours: ``sample --out``, ``render --out`` and ``demo --out`` at a FIFO, at a clone of /dev/null
  and of /dev/full (``mknod``, as root only), directly and through a symbolic link: the special file
  must still be one afterwards, and the command must exit 1 or 2 with one line.
- files that block: ``load_scene``/``load_pfm`` and ``render --scene`` on a FIFO, /dev/zero, /dev/urandom
  (through links): each must fail within 30 s saying what the file is.
- signals: ``sample`` (the target exists) and ``render`` sent SIGINT or SIGTERM at several times; after
  each run nothing of ours (``.NAME.<hex>.tmp``, ``.old``, ``.probe``) may be left, the exit status must
  be 0 (the output complete and new) or 130/143 (the target as before), with no traceback.
- absurd sizes: commands that must exit 2 within 20 s naming the argument (or asking for --allow-long),
  and library calls that must raise ValueError naming it at once (``sample_sphere(48 * 2**31)``).
- overflow: ``integrate`` (numpy and compiled f, random, Sobol', hemisphere, ``method='auto'``, a
  tolerance) and ``orbit_average`` with values, sums or variances beyond float64, ``rtol=1e-300``,
  ``atol=1e-300``, and the CLI's ``--rtol 1e-300``: a ValueError naming ``f`` (or the tolerance, or ``p``),
  or a finite result; "silent" is an inf/NaN result or a warning, "unnamed" another error or message.
- Mitsuba files (skipped, with the reason, without Mitsuba): nested BSDFs, no sensor, an empty film, a
  NaN or 1e39 radiance, a directory, FIFO or /dev/zero link named .xml, options that cannot apply: exit
  2 with one line naming the file or option, nothing written.
- signals during a Mitsuba render: SIGINT/SIGTERM at 1.5, 3 and 6 s: exit 130/143 within 1 s, nothing
  written.
- SIGKILL: sample (.npy, .csv), render (numba, Mitsuba), demo and study killed while they work, then run
  again: the kill may leave no file (Linux: unnamed temporaries); the rerun leaves nothing of ours.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import signal
import stat
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CLI = [sys.executable, "-m", "symsphere"]
OURS = re.compile(r"^\..+\.(?:[0-9]+-)?[0-9a-f]{8}\.(tmp|old|probe)$")


# --- bad inputs (run in a child process: a crash is counted, not suffered) ---------------------------


def _odd_values():
    import numpy as np

    class Opaque:
        def __repr__(self):
            return "<opaque>"

    return [
        None, True, "x", b"x", "", 1.5, -1, 0, 2**70, -(2**70), float("nan"), float("inf"), -float("inf"), 1e308,
        -1e-320, [], [[]], {}, Opaque(), np.float32(1.0), 1 + 1j, [1, 2], [[1, 2], [3]], np.zeros((0, 3)),
        np.zeros((0, 2)), np.full((2, 3), np.nan), np.full((2, 2), np.inf), np.array(["a", "b", "c"]),
        np.zeros(3, dtype=object), np.ones((2, 3), dtype=np.complex128), np.ones((2, 3), dtype=bool),
        np.ones((1, 3), dtype=np.int8), np.ones((1, 3), dtype=np.float16), np.ones((2, 2, 3)) * 1e200,
    ]  # fmt: skip


def _render_table(folder):
    import numpy as np

    from symsphere import render as rd

    image = np.full((3, 4, 3), 0.25)
    scene = folder / "ball.json"
    scene.write_text(json.dumps({
        "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 40},
        "materials": {"m": {"type": "diffuse", "albedo": 0.5, "emission": 1}},
        "spheres": [{"center": [0, 0, 0], "radius": 1, "material": "m"}],
    }))  # fmt: skip
    pfm = rd.save_pfm(folder / "a.pfm", image)
    tiny = dict(width=4, height=3, spp=2, seed=1)
    return [
        ("render", rd.render, dict(scene="furnace", **tiny)),
        (
            "plan_passes",
            rd.plan_passes,
            dict(scene="furnace", width=4, height=3, spp=2, strategy="cosine", method=None, pixel_filter="box", seed=1),
        ),  # fmt: skip
        ("load_scene", rd.load_scene, dict(path=scene)),
        ("load_pfm", rd.load_pfm, dict(path=pfm)),
        ("tonemap", rd.tonemap, dict(image=image, exposure=1.0)),
        ("linear_to_srgb", rd.linear_to_srgb, dict(c=image)),
        ("save_png", rd.save_png, dict(path=folder / "b.png", image=image, exposure=1.0)),
        ("save_npy", rd.save_npy, dict(path=folder / "b.npy", image=image)),
        ("save_image_set", rd.save_image_set, dict(paths=[folder / "c.png", folder / "c.pfm"], image=image)),
        ("furnace", rd.furnace, dict(albedo=0.5, emission=1.0)),
    ]


def _all_finite(result, allow_inf=False):
    sys.path.insert(0, str(ROOT / "tests"))
    from test_properties import _all_finite as finite  # the property tests' notion of finite output

    return finite(result, allow_inf=allow_inf)


def bad_input_table(verbose: bool) -> dict[str, int]:
    import warnings

    sys.path.insert(0, str(ROOT / "tests"))
    import test_properties as tp  # the valid arguments of every public library function

    counts = dict(functions=0, calls=0, finite=0, clean=0, unnamed=0, wrong_types=0, non_finite=0, hangs=0)
    folder = Path(tempfile.mkdtemp(prefix="symsphere-audit-"))
    os.chdir(folder)  # relative names land here
    table = []
    for name, function in tp.FUNCTIONS:
        if name in tp.TRUSTED:  # documented as not validating (numba scalar formulas), as the property tests
            continue
        arguments = tp._valid_arguments(name, function)
        if arguments is not None:
            table.append((name, function, arguments, lambda f, a: tp._call(f, a)))
    for name, function, arguments in _render_table(folder):
        table.append((name, function, arguments, lambda f, a: f(**a)))

    def alarm(signum, frame):
        raise TimeoutError

    signal.signal(signal.SIGALRM, alarm)
    from symsphere import render as rd

    rd.render("furnace", width=4, height=3, spp=2, seed=1)  # compile (or load) the kernels before the clock runs
    tp._kernels_compiled.__wrapped__()  # the property tests' warm-up: every sampling kernel, float32 and float64
    may_be_inf = set(tp.MAY_BE_INF) | {"plan_passes"}  # documented: -inf marks "no clip plane" in a plan's tables
    odd = _odd_values()
    for name, function, valid, call in table:
        counts["functions"] += 1
        for replaced in sorted(valid):
            for value in odd:
                arguments = dict(valid, **{replaced: value})
                counts["calls"] += 1
                finding = None
                with warnings.catch_warnings(record=True) as caught:
                    warnings.simplefilter("always")
                    signal.alarm(10)
                    try:
                        result = call(function, arguments)
                        if hasattr(result, "__next__"):
                            result = list(result)
                    except TimeoutError:
                        counts["hangs"] += 1
                        finding = "hang"
                    except (ValueError, TypeError) as exc:
                        message = str(exc)
                        aliases = {"kind": ("type",), "color": ("albedo", "reflectance", "tint")}.get(replaced, ())
                        if name == "load_scene" and message.startswith("scene file "):
                            aliases = ("scene file",)  # names the file the user gave: scene file 'x': ...
                        named = replaced == "f" or any(n in message for n in (replaced, *aliases))
                        if named and message.strip() and "\n" not in message.strip():
                            counts["clean"] += 1
                        else:
                            counts["unnamed"] += 1
                            finding = f"unnamed: {message[:120]!r}"
                    except OSError:  # a path the operating system refuses: documented
                        counts["clean"] += 1
                    except BaseException as exc:
                        counts["wrong_types"] += 1
                        finding = f"{type(exc).__name__}: {str(exc)[:120]}"
                    else:
                        if _all_finite(result, name in may_be_inf):
                            counts["finite"] += 1
                        else:
                            counts["non_finite"] += 1
                            finding = "non-finite result"
                    finally:
                        signal.alarm(0)
                    if caught and finding is None:
                        counts["wrong_types"] += 1
                        finding = f"warning: {caught[0].category.__name__}: {str(caught[0].message)[:100]}"
                if finding and verbose:
                    print(f"  {name}({replaced}={tp.short_repr(value) if hasattr(tp, 'short_repr') else value!r}): "
                          f"{finding}", file=sys.stderr)  # fmt: skip
    return counts


def run_bad_input_table(verbose: bool) -> dict[str, int]:
    """The table in a child process: if it dies, that is a crash."""
    code = (
        "import json, sys; sys.path.insert(0, sys.argv[1])\n"
        "import audit_reliability as a\n"
        "print('AUDIT ' + json.dumps(a.bad_input_table(sys.argv[2] == '1')))\n"
    )
    child = subprocess.run([sys.executable, "-c", code, str(Path(__file__).parent), "1" if verbose else "0"],
                           capture_output=True, text=True)  # fmt: skip
    if verbose:
        sys.stderr.write(child.stderr)
    lines = [line for line in child.stdout.splitlines() if line.startswith("AUDIT ")]
    if child.returncode != 0 or not lines:
        return dict(crashes=1, detail=f"exit {child.returncode}: {child.stderr[-300:]}")
    counts = json.loads(lines[-1][6:])
    counts["crashes"] = 0
    return counts


# --- files that are not ours -----------------------------------------------------------------------------


def _specials(folder: Path) -> list[Path]:
    made = [folder / "fifo"]
    os.mkfifo(made[0])
    if os.geteuid() == 0:
        for name, minor in (("nullclone", 3), ("fullclone", 7)):
            os.mknod(folder / name, 0o666 | stat.S_IFCHR, os.makedev(1, minor))
            made.append(folder / name)
    return made


def not_ours(verbose: bool) -> dict[str, int]:
    counts = dict(cases=0, replaced=0, unclear=0)
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        for special in _specials(folder):
            kind = stat.S_IFMT(os.lstat(special).st_mode)
            for verb, suffix, extra in (("sample", ".npy", ["--n", "96", "--seed", "1"]),
                                        ("render", ".png", ["--width", "4", "--height", "3", "--spp", "2", "--no-progress"]),
                                        ("demo", "", ["--n", "4800", "--no-progress"])):  # fmt: skip
                for through_link in (False, True):
                    out = folder / f"{special.name}-{verb}-{'link' if through_link else 'direct'}{suffix}"
                    if through_link:
                        out.symlink_to(special.name)
                    else:
                        os.link(special, out)  # a second name of the same special file, with the verb's suffix
                    run = subprocess.run(CLI + [verb, *extra, "--out", str(out)], capture_output=True, text=True,
                                         timeout=600, cwd=folder)  # fmt: skip
                    counts["cases"] += 1
                    if stat.S_IFMT(os.lstat(special).st_mode) != kind or stat.S_IFMT(os.stat(out).st_mode) != kind:
                        counts["replaced"] += 1
                        print(f"  replaced: {verb} --out {out.name}", file=sys.stderr)
                        os.unlink(out) if out.exists() else None
                    lines = [line for line in run.stderr.splitlines() if line.strip() and "%" not in line]
                    if run.returncode not in (1, 2) or len(lines) != 1 or "Traceback" in run.stderr:
                        counts["unclear"] += 1
                        print(
                            f"  {verb} --out {out.name}: exit {run.returncode}: {run.stderr[-200:]!r}", file=sys.stderr
                        )
                    elif verbose:
                        print(f"  {verb} --out {out.name}: {lines[0]}", file=sys.stderr)
    return counts


def blocking_files(verbose: bool) -> dict[str, int]:
    counts = dict(cases=0, hangs=0, unclear=0)
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        os.mkfifo(folder / "f.json")
        os.mkfifo(folder / "f.pfm")
        (folder / "z.json").symlink_to("/dev/zero")
        (folder / "u.toml").symlink_to("/dev/urandom")
        (folder / "z.pfm").symlink_to("/dev/zero")
        for file in ("f.json", "z.json", "u.toml", "f.pfm", "z.pfm"):
            loader = "load_pfm" if file.endswith(".pfm") else "load_scene"
            commands = [[sys.executable, "-c", f"from symsphere.render import {loader}; {loader}({file!r})"]]
            if not file.endswith(".pfm"):
                commands.append(CLI + ["render", "--scene", file, "--out", "x.png"])
            for command in commands:
                counts["cases"] += 1
                try:
                    run = subprocess.run(command, capture_output=True, text=True, timeout=30, cwd=folder)
                except subprocess.TimeoutExpired:
                    counts["hangs"] += 1
                    print(f"  hang: {command[-3:]}", file=sys.stderr)
                    continue
                said = run.stderr.strip().splitlines()[-1] if run.stderr.strip() else ""
                if not re.search(r"FIFO|character device", said):
                    counts["unclear"] += 1
                    print(f"  {file}: {said!r}", file=sys.stderr)
                elif verbose:
                    print(f"  {file}: {said}", file=sys.stderr)
    return counts


# --- signals ----------------------------------------------------------------------------------------------


def _writing_in(pid: int, folder: Path, min_size: int = 0) -> bool:
    """Whether process *pid* has a file open in *folder*: its output's temporary (unnamed on Linux)."""
    try:
        descriptors = os.listdir(f"/proc/{pid}/fd")
    except OSError:
        return False
    for descriptor in descriptors:
        try:
            target = os.readlink(f"/proc/{pid}/fd/{descriptor}").removesuffix(" (deleted)")
            size = os.stat(f"/proc/{pid}/fd/{descriptor}").st_size
        except OSError:
            continue
        if os.path.dirname(target) == os.path.realpath(folder) and size >= min_size:
            return True
    return False


def _ours(folder: Path) -> list[str]:
    return [p.name for p in folder.iterdir() if OURS.match(p.name)]


def signals(verbose: bool) -> dict[str, int]:
    import numpy as np

    counts = dict(runs=0, left_behind=0, inconsistent=0, tracebacks=0, during_start_up=0)
    n = 48 * 2**16 * 8
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        plans = [("sample", signum, delay) for signum in (signal.SIGINT, signal.SIGTERM)
                 for delay in (0.0, 0.1, 0.3, 0.6, 1.0, 1.5, 2.5)]  # fmt: skip
        plans += [("render", signum, delay) for signum in (signal.SIGINT, signal.SIGTERM) for delay in (1.0, 4.0, 8.0)]
        for verb, signum, delay in plans:
            for stale in folder.iterdir():
                stale.unlink()
            if verb == "sample":
                out = folder / "d.npy"
                np.save(out, np.zeros((1, 3), np.float32))
                command = CLI + ["sample", "--n", str(n), "--dtype", "float32", "--seed", "3", "--out", str(out)]
            else:
                out = folder / "img.png"
                command = CLI + ["render", "--width", "32", "--height", "24", "--spp", "4800", "--no-progress",
                                 "--out", str(out)]  # fmt: skip
            before = out.read_bytes() if out.exists() else None
            process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            deadline = time.monotonic() + 300
            while verb == "sample" and process.poll() is None and time.monotonic() < deadline:
                if _writing_in(process.pid, folder):
                    break
                time.sleep(0.002)
            time.sleep(delay)
            if process.poll() is None:
                process.send_signal(signum)
            _, stderr = process.communicate(timeout=600)
            counts["runs"] += 1
            left = _ours(folder)
            if left:
                counts["left_behind"] += 1
                print(f"  {verb} {signal.Signals(signum).name} at {delay} s: left {left}", file=sys.stderr)
            if "Traceback" in stderr:
                counts["tracebacks"] += 1
            status = process.returncode
            now = out.read_bytes() if out.exists() else None
            consistent = (status == 0 and now is not None and now != before) or (
                status == 128 + signum and now == before
            )
            if (
                not consistent
                and now == before
                and not left
                and (status == -signum or "KeyboardInterrupt" in stderr)
                and "symsphere" not in stderr.replace("symsphere/", "")
            ):
                # Killed while Python imported the package, before main() installed its handlers: the
                # default action of the signal (nothing was written yet).  Counted apart.
                counts["during_start_up"] += 1
                counts["tracebacks"] -= "Traceback" in stderr
                if verbose:
                    print(f"  {verb} {signal.Signals(signum).name} at {delay} s: during start-up", file=sys.stderr)
            elif not consistent:
                counts["inconsistent"] += 1
                print(f"  {verb} {signal.Signals(signum).name} at {delay} s: exit {status}, "
                      f"{'changed' if now != before else 'unchanged'}: {stderr[-200:]!r}", file=sys.stderr)  # fmt: skip
            elif verbose:
                print(f"  {verb} {signal.Signals(signum).name} at {delay} s: exit {status}", file=sys.stderr)
    return counts


# --- absurd sizes -----------------------------------------------------------------------------------------


ABSURD = [
    (["render", "--width", str(2**40), "--height", str(2**40), "--spp", "1"], "--width * --height"),
    (["render", "--width", str(2**31), "--height", str(2**31)], "--width * --height"),
    (["render", "--spp", str(10**15)], "--spp"),
    (["render", "--spp", str(10**13)], "--allow-long"),
    # more than a day, and (below ~1.2 TB of memory) more partial sums than memory holds, said first
    (["integrate", "--integrand", "exp", "--n", str(48 * 10**13)], ("--allow-long", "'--n'")),
    (["sample", "--n", str(48 * 10**13), "--out", "x.npy"], "--allow-long"),
    (["sample", "--n", str(48 * 2**64), "--out", "x.npy"], "'n'"),
    (["study", "--repetitions", "1000000000", "--out", "s"], "--repetitions"),
    (["study", "--repetitions", str(2**70), "--out", "s"], "--repetitions"),
    (["study", "--repetitions", "100000", "--out", "s"], "--allow-long"),
    (["integrate", "--integrand", "exp", "--n", str(48 * 10**13), "--allow-long"], "'--n'"),
    (["integrate", "--integrand", "exp", "--atol", "1e-9", "--n-max", str(48 * 10**14), "--allow-long"], "'--n-max'"),
]

# Library calls that must raise ValueError naming the argument at once (not run on, not MemoryError).
ABSURD_API = [
    ("symsphere.sample_sphere(48 * 2**31)", "'n'"),
    ("symsphere.sample_hemisphere(24 * 2**33)", "'n'"),
    ("symsphere.render.render('furnace', width=10**7, height=10**7, spp=1)", "'width * height'"),
    ("symsphere.integrate(lambda w: w[:, 0], n=48 * 10**13)", "'n'"),  # its partial sums: beyond memory
    ("symsphere.integrate(lambda w: w[:, 0], atol=1e-9, n_max=48 * 10**14)", "'n_max'"),
    (
        "symsphere.integrate(lambda w: w[:, 0], n=48 * 10**12, points='sobol', replicates=10**12 // 4096)",
        "'replicates'",
    ),
    ("__import__('symsphere.distributed').distributed.integrate(lambda w: w[:, 0], n=48 * 10**13)", "'n'"),
]


def absurd_sizes(verbose: bool) -> dict[str, int]:
    counts = dict(cases=0, slow=0, unnamed=0)
    with tempfile.TemporaryDirectory() as name:
        for arguments, named in ABSURD:
            counts["cases"] += 1
            start = time.monotonic()
            try:
                run = subprocess.run(CLI + arguments, capture_output=True, text=True, timeout=60, cwd=name)
            except subprocess.TimeoutExpired:
                counts["slow"] += 1
                continue
            if time.monotonic() - start > 20:
                counts["slow"] += 1
                print(f"  slow ({time.monotonic() - start:.0f} s): {' '.join(arguments)}", file=sys.stderr)
            said = any(name in run.stderr for name in ((named,) if isinstance(named, str) else named))
            if run.returncode != 2 or not said or "Traceback" in run.stderr:
                counts["unnamed"] += 1
                print(f"  {' '.join(arguments)}: exit {run.returncode}: {run.stderr[-200:]!r}", file=sys.stderr)
            elif verbose:
                print(f"  {' '.join(arguments)}: {run.stderr.strip()}", file=sys.stderr)
        for call, named in ABSURD_API:
            counts["cases"] += 1
            code = (
                "import symsphere, symsphere.render\n"
                f"try:\n    {call}\n    print('ran')\n"
                "except ValueError as error:\n    print('ValueError', error)\n"
                "except BaseException as error:\n    print(type(error).__name__, error)\n"
            )
            try:
                run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
            except subprocess.TimeoutExpired:
                counts["slow"] += 1
                print(f"  slow: {call}", file=sys.stderr)
                continue
            if not run.stdout.startswith("ValueError") or named not in run.stdout:
                counts["unnamed"] += 1
                print(f"  {call}: {run.stdout.strip()[-200:]!r}", file=sys.stderr)
            elif verbose:
                print(f"  {call}: {run.stdout.strip()}", file=sys.stderr)
    return counts


# --- integrands that overflow, tolerances float64 cannot resolve ---------------------------------------

OVERFLOW_CODE = """
import json, sys, time, warnings
import numpy as np
from numba import njit
import symsphere
from symsphere.integrands import orbit_average

huge = lambda w: np.full(len(w), 1e308)
signed = lambda w: np.where(w[:, 0] > 0, 1e308, -1e308)  # the sum is finite, its variance is not
def grows(w):  # inf for some directions; quietly, so that any warning seen is the library's
    with np.errstate(over="ignore"):
        return np.full(len(w), 1e300) * np.exp(700 * w[:, 2])
def square(w):
    with np.errstate(over="ignore"):
        return w[:, 0] ** 2
huge_compiled = njit(lambda x, y, z: 1e308)
CASES = [
    ("integrate(huge, n=96)", lambda: symsphere.integrate(huge, n=96, rng=1), "'f'"),
    ("integrate(huge, atol=1e-3)", lambda: symsphere.integrate(huge, atol=1e-3, rng=1), "'f'"),
    ("integrate(huge_compiled, n=96)", lambda: symsphere.integrate(huge_compiled, n=96, rng=1), "'f'"),
    ("integrate(signed, n=96)", lambda: symsphere.integrate(signed, n=96, rng=1), "'f'"),
    ("integrate(grows, n=4800)", lambda: symsphere.integrate(grows, n=4800, rng=1), "'f'"),
    ("integrate(huge, sobol)", lambda: symsphere.integrate(huge, n=384, points="sobol", rng=1), "'f'"),
    ("integrate(huge, hemisphere)", lambda: symsphere.integrate(huge, n=48, domain="hemisphere", rng=1), "'f'"),
    ("integrate(huge, method=auto)", lambda: symsphere.integrate(huge, rtol=1e-6, method="auto", rng=1), "'f'"),
    ("integrate(exp, rtol=1e-300)", lambda: symsphere.integrate(lambda w: np.exp(w[:, 0]), rtol=1e-300), "'rtol'"),
    ("integrate(exp, atol=1e-300)", lambda: symsphere.integrate(lambda w: np.exp(w[:, 0]), atol=1e-300,
                                                               n_max=48 * 2**10, rng=1), None),
    ("orbit_average(huge)", lambda: orbit_average(huge, [0.3, 0.2, 0.9]), "'f'"),
    ("orbit_average(grows)", lambda: orbit_average(grows, [[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]]), "'f'"),
    ("orbit_average(p=1e308)", lambda: orbit_average(square, [[1e308] * 3]), "'p'"),
]
for name, call, named in CASES:
    start = time.monotonic()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = call()
            value = np.asarray(getattr(result, "integral", result), dtype=float)
            error = getattr(result, "standard_error", 0.0)
            outcome = "finite" if np.all(np.isfinite(value)) and not np.any(np.isinf(error)) else "non-finite"
            message = repr(value.ravel()[:2].tolist())
        except ValueError as exc:
            outcome, message = ("named" if named and named in str(exc) else "unnamed"), str(exc)
        except Exception as exc:
            outcome, message = "wrong type", f"{type(exc).__name__}: {exc}"
    warned = [str(w.message) for w in caught if not str(w.message).startswith("integrate: the tolerance")]
    print(json.dumps(dict(name=name, outcome=outcome, message=message[:200], warned=warned,
                          seconds=time.monotonic() - start)), flush=True)
"""


def overflow(verbose: bool) -> dict[str, int]:
    """Integrands whose values, sums or variances overflow float64, and tolerances it cannot resolve: one
    ValueError naming f (or the tolerance) at once, or a finite result; never inf/NaN, never only a warning."""
    counts = dict(cases=0, silent=0, unnamed=0, slow=0)
    try:
        run = subprocess.run([sys.executable, "-c", OVERFLOW_CODE], capture_output=True, text=True, timeout=600)
    except subprocess.TimeoutExpired:
        counts["slow"] += 1
        return counts
    for line in run.stdout.splitlines():
        case = json.loads(line)
        counts["cases"] += 1
        bad = case["outcome"] in ("non-finite",) or case["warned"]
        counts["silent"] += bool(bad)
        counts["unnamed"] += case["outcome"] in ("unnamed", "wrong type")
        counts["slow"] += case["seconds"] > 20
        if bad or case["outcome"] in ("unnamed", "wrong type") or case["seconds"] > 20 or verbose:
            print(f"  {case['name']}: {case['outcome']} {case['message']!r} {case['warned']}", file=sys.stderr)
    if run.returncode != 0:
        counts["unnamed"] += 1
        print(f"  the overflow cases' process: exit {run.returncode}: {run.stderr[-300:]!r}", file=sys.stderr)
    for arguments, named, status in (
        (["integrate", "--integrand", "exp", "--seed", "1", "--rtol", "1e-300"], "'--rtol'", 2),
        (["integrate", "--integrand", "exp", "--seed", "1", "--atol", "1e-300", "--n-max", "49152"], "NOT reached", 0),
    ):
        counts["cases"] += 1
        start = time.monotonic()
        done = subprocess.run(CLI + arguments, capture_output=True, text=True, timeout=300)
        counts["slow"] += time.monotonic() - start > 20
        said = done.stderr + done.stdout
        if done.returncode != status or named not in said or "Traceback" in said or "Warning" in said:
            counts["unnamed"] += 1
            print(f"  {' '.join(arguments)}: exit {done.returncode}: {said[-200:]!r}", file=sys.stderr)
        elif verbose:
            print(f"  {' '.join(arguments)}: {said.strip()[-200:]}", file=sys.stderr)
    return counts


# --- Mitsuba scene files ------------------------------------------------------------------------------


def _mitsuba_missing() -> str | None:
    run = subprocess.run([sys.executable, "-c", "import mitsuba as mi; mi.set_variant('llvm_ad_rgb')"],
                         capture_output=True, text=True)  # fmt: skip
    return None if run.returncode == 0 else (run.stderr.strip().splitlines() or ["?"])[-1]


def _cornell_copy(folder: Path) -> Path:
    import shutil

    source = ROOT / "src" / "symsphere" / "mitsuba" / "scenes"
    for path in source.glob("cornell_box*"):
        shutil.copy(path, folder / path.name)
    return folder / "cornell_box.xml"


def mitsuba_files(verbose: bool) -> dict[str, int]:
    """Hostile and unrenderable Mitsuba scene files, and options that cannot apply: each must exit 2 within
    60 s with one line naming the file or the option, nothing written."""
    counts = dict(cases=0, slow=0, unclear=0, written=0)
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        scene = _cornell_copy(folder)
        text = scene.read_text()
        cases: list[tuple[list[str], str]] = []
        for depth in (100, 1000, 20000):
            nest = '<bsdf type="twosided">' * depth + '<bsdf type="diffuse"/>' + "</bsdf>" * depth
            path = folder / f"nested{depth}.xml"
            path.write_text(f'<scene version="3.0.0"><shape type="sphere">{nest}</shape></scene>')
            cases.append(([str(path)], "nested more than"))
        variants = {
            "nosensor": (re.sub(r"<sensor.*?</sensor>", "", text, flags=re.S), "has no <sensor>"),
            "zero": (re.sub(r'name="(width|height)" value="256"', r'name="\1" value="0"', text), "0 x 0 pixels"),
            "nan": (re.sub(r'(<emitter type="area">\s*<rgb name="radiance" value=")[^"]*"', r'\g<1>nan, nan, nan"',
                           text), "is nan"),
            "huge": (re.sub(r'(<emitter type="area">\s*<rgb name="radiance" value=")[^"]*"', r'\g<1>1e39, 1e39, 1e39"',
                            text), "is inf"),
        }  # fmt: skip
        for stem, (content, words) in variants.items():
            (folder / f"{stem}.xml").write_text(content)
            cases.append(([str(folder / f"{stem}.xml")], words))
        (folder / "dir.xml").mkdir()
        os.mkfifo(folder / "fifo.xml")
        (folder / "zero-link.xml").symlink_to("/dev/zero")
        cases += [([str(folder / "dir.xml")], "is a directory"), ([str(folder / "fifo.xml")], "is a FIFO"),
                  ([str(folder / "zero-link.xml")], "is a character device")]  # fmt: skip
        for option in (["--workers", "2"], ["--filter", "tent"], ["--integrator", "bsdf"], ["--variant", "nosuch"]):
            cases.append(([str(scene), *option], option[0]))
        out = folder / "out" / "img.png"
        out.parent.mkdir()
        for arguments, words in cases:
            counts["cases"] += 1
            command = CLI + ["render", "--scene", *arguments, "--out", str(out), "--no-progress"]
            start = time.monotonic()
            try:
                run = subprocess.run(command, capture_output=True, text=True, timeout=60)
            except subprocess.TimeoutExpired:
                counts["slow"] += 1
                print(f"  slow: {' '.join(arguments)}", file=sys.stderr)
                continue
            lines = [line for line in run.stderr.splitlines() if line.strip() and "WARN" not in line]
            if time.monotonic() - start > 30:
                counts["slow"] += 1
            if run.returncode != 2 or len(lines) != 1 or words not in lines[0] or "internal error" in lines[0]:
                counts["unclear"] += 1
                print(f"  render --scene {' '.join(arguments)}: exit {run.returncode}: {run.stderr[-200:]!r}",
                      file=sys.stderr)  # fmt: skip
            elif verbose:
                print(f"  render --scene {' '.join(arguments)}: {lines[0]}", file=sys.stderr)
            if list(out.parent.iterdir()):
                counts["written"] += 1
    return counts


def _mitsuba_loaded(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/maps") as maps:
            return "libmitsuba" in maps.read()
    except OSError:
        return False


def mitsuba_signals(verbose: bool) -> dict[str, int]:
    """SIGINT and SIGTERM at several times during a Mitsuba render that would take minutes (counted from
    Mitsuba's loading, so that a loaded machine's slow start-up is not what is signalled): exit 130/143
    within a second of the signal, nothing written."""
    counts = dict(runs=0, late=0, wrong_status=0, written=0, worst_ms=0)
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        scene = _cornell_copy(folder)
        out = folder / "out" / "img.png"
        out.parent.mkdir()
        command = CLI + ["render", "--scene", str(scene), "--width", "256", "--height", "192", "--spp", "4800",
                         "--seed", "1", "--no-progress", "--out", str(out)]  # fmt: skip
        for signum in (signal.SIGINT, signal.SIGTERM):
            for delay in (1.5, 3.0, 6.0):
                counts["runs"] += 1
                process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                deadline = time.monotonic() + 120
                while not _mitsuba_loaded(process.pid) and process.poll() is None and time.monotonic() < deadline:
                    time.sleep(0.05)  # main() runs once Mitsuba loads: the delay counts from there, not start-up
                time.sleep(delay)
                sent = time.monotonic()
                process.send_signal(signum)
                try:
                    _, stderr = process.communicate(timeout=30)
                except subprocess.TimeoutExpired:
                    process.kill()
                    _, stderr = process.communicate()
                waited = time.monotonic() - sent
                counts["worst_ms"] = max(counts["worst_ms"], round(waited * 1000))
                if waited > 1.0:
                    counts["late"] += 1
                    print(f"  {signal.Signals(signum).name} at {delay} s: exit after {waited:.2f} s", file=sys.stderr)
                if process.returncode != 128 + signum or "nothing was written" not in stderr:
                    counts["wrong_status"] += 1
                    print(f"  {signal.Signals(signum).name} at {delay} s: exit {process.returncode}: {stderr[-200:]!r}",
                          file=sys.stderr)  # fmt: skip
                elif verbose:
                    print(f"  {signal.Signals(signum).name} at {delay} s: exit {process.returncode} after "
                          f"{waited:.3f} s", file=sys.stderr)  # fmt: skip
                if list(out.parent.iterdir()):
                    counts["written"] += 1
                    for path in out.parent.iterdir():
                        path.unlink()
    return counts


# --- SIGKILL ------------------------------------------------------------------------------------------------


def sigkill(verbose: bool, mitsuba: bool) -> dict[str, int]:
    """Each writing command SIGKILLed while it writes (or works), then run again to completion: what the
    kill left (files: nothing, on Linux) and what the successful rerun left (nothing of ours)."""
    counts = dict(runs=0, files_left_by_kill=0, left_after_rerun=0, rerun_failed=0)
    jobs: list[tuple[str, list[str], list[str], str]] = [
        ("sample .npy", ["sample", "--n", str(48 * 2**22), "--chunk", str(48 * 2**12), "--out", "d.npy"],
         ["sample", "--n", "96", "--seed", "1", "--out", "d.npy"], "file"),
        ("sample .csv", ["sample", "--n", str(48 * 2**18), "--out", "d.csv"],
         ["sample", "--n", "96", "--seed", "1", "--out", "d.csv"], "file"),
        ("render", ["render", "--width", "512", "--height", "384", "--spp", "4800", "--no-progress", "--out", "i.png"],
         ["render", "--width", "8", "--height", "6", "--spp", "24", "--no-progress", "--out", "i.png"], "work"),
        ("demo", ["demo", "--n", "48000", "--no-progress", "--out", "demo"],
         ["demo", "--n", "4800", "--no-progress", "--out", "demo"], "directory"),
        ("study", ["study", "--config", "small", "--no-progress", "--out", "study"],
         ["study", "--config", "small", "--k-max", "4", "--repetitions", "2", "--no-progress", "--out", "study"],
         "directory"),
    ]  # fmt: skip
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        if mitsuba:
            scene = str(_cornell_copy(folder))
            jobs.append(("Mitsuba render", ["render", "--scene", scene, "--spp", "4800", "--no-progress", "--out", "m.png"],
                         ["render", "--scene", scene, "--width", "16", "--spp", "24", "--no-progress", "--out", "m.png"],
                         "work"))  # fmt: skip
        for label, killed, rerun, kind in jobs:
            counts["runs"] += 1
            before = set(os.listdir(folder))
            process = subprocess.Popen(CLI + killed, cwd=folder, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            deadline = time.monotonic() + 120
            if kind == "file":  # while its temporary holds data
                while (
                    not _writing_in(process.pid, folder, 1) and process.poll() is None and time.monotonic() < deadline
                ):
                    time.sleep(0.01)
            elif kind == "directory":  # once its temporary directory exists
                while not _ours(folder) and process.poll() is None and time.monotonic() < deadline:
                    time.sleep(0.05)
                time.sleep(1.0)
            else:
                time.sleep(4.0)
            process.kill()
            process.wait()
            left = sorted(set(os.listdir(folder)) - before)
            if kind != "directory" and left:
                counts["files_left_by_kill"] += 1
                print(f"  {label}: SIGKILL left {left}", file=sys.stderr)
            run = subprocess.run(CLI + rerun, cwd=folder, capture_output=True, text=True, timeout=600)
            if run.returncode != 0:
                counts["rerun_failed"] += 1
                print(f"  {label}: the rerun failed: {run.stderr[-200:]!r}", file=sys.stderr)
            if _ours(folder):
                counts["left_after_rerun"] += 1
                print(f"  {label}: after the rerun: {_ours(folder)}", file=sys.stderr)
            elif verbose:
                said = [line for line in run.stderr.splitlines() if "removed" in line]
                print(f"  {label}: killed left {left or 'nothing'}; rerun {said or 'said nothing'}", file=sys.stderr)
    return counts


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the bad-input table only")
    parser.add_argument("--verbose", action="store_true", help="print every case, not only the findings")
    args = parser.parse_args()
    start = time.monotonic()
    rows = []
    table = run_bad_input_table(args.verbose)
    if "detail" in table:
        print(f"bad-input table crashed: {table['detail']}", file=sys.stderr)
    rows.append(("bad inputs", f"{table.get('calls', '?')} calls of {table.get('functions', '?')} functions "
                 f"({table.get('clean', '?')} clean errors, {table.get('finite', '?')} finite results)",
                 f"crashes {table['crashes']}, hangs {table.get('hangs', '?')}, wrong types {table.get('wrong_types', '?')}, "
                 f"unnamed {table.get('unnamed', '?')}, non-finite {table.get('non_finite', '?')}"))  # fmt: skip
    if not args.quick:
        c = not_ours(args.verbose)
        rows.append(
            (
                "not ours",
                f"{c['cases']} --out at FIFOs/devices, direct and via links",
                f"replaced {c['replaced']}, unclear {c['unclear']}",
            )
        )
        c = blocking_files(args.verbose)
        rows.append(
            (
                "files that block",
                f"{c['cases']} loads of FIFOs, /dev/zero, /dev/urandom",
                f"hangs {c['hangs']}, unclear {c['unclear']}",
            )
        )
        c = signals(args.verbose)
        rows.append(
            (
                "signals",
                f"{c['runs']} runs of sample/render sent SIGINT/SIGTERM",
                f"left behind {c['left_behind']}, inconsistent {c['inconsistent']}, tracebacks {c['tracebacks']} "
                f"(and {c['during_start_up']} killed during start-up, before any work)",
            )
        )
        c = absurd_sizes(args.verbose)
        rows.append(("absurd sizes", f"{c['cases']} commands and calls", f"slow {c['slow']}, unnamed {c['unnamed']}"))
        c = overflow(args.verbose)
        rows.append(("overflow", f"{c['cases']} integrands and tolerances beyond float64",
                     f"silent {c['silent']}, unnamed {c['unnamed']}, slow {c['slow']}"))  # fmt: skip
        missing = _mitsuba_missing()
        if missing is None:
            c = mitsuba_files(args.verbose)
            rows.append(("Mitsuba files", f"{c['cases']} hostile scene files and options",
                         f"slow {c['slow']}, unclear {c['unclear']}, written {c['written']}"))  # fmt: skip
            c = mitsuba_signals(args.verbose)
            rows.append(("signals during a Mitsuba render", f"{c['runs']} runs sent SIGINT/SIGTERM 1.5-6 s into it",
                         f"late (> 1 s) {c['late']}, wrong status {c['wrong_status']}, written {c['written']} "
                         f"(slowest exit {c['worst_ms']} ms)"))  # fmt: skip
        else:
            rows.append(("Mitsuba", "skipped", f"Mitsuba cannot run here: {missing}"))
        c = sigkill(args.verbose, mitsuba=missing is None)
        rows.append(("SIGKILL", f"{c['runs']} commands killed while writing, then rerun",
                     f"files left by the kill {c['files_left_by_kill']}, left after the rerun "
                     f"{c['left_after_rerun']}, reruns failed {c['rerun_failed']}"))  # fmt: skip
    print("| part | cases | findings |")
    print("|------|-------|----------|")
    for row in rows:
        print("| " + " | ".join(row) + " |")
    print(f"\n({time.monotonic() - start:.0f} s; python {sys.version.split()[0]}, euid {os.geteuid()})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
