"""Regression guard: the headline rows of this checkout against a base revision, interleaved.

Run it before resolving any change to a kernel or the code around it (docs/explanation/testing.md)::

    python benchmarks/regress.py                    # this working tree against HEAD (uncommitted changes)
    python benchmarks/regress.py --base 5d0170b     # against any git revision
    python benchmarks/regress.py --base main --rounds 11 --no-mitsuba --json regress.json

The base revision is checked out into a temporary git worktree.  Two worker processes run this
script's rows, one with the base's ``src`` first on ``PYTHONPATH`` and one with this checkout's, each
with its own numba cache (a temporary directory: the first call of each row compiles, untimed).  The
workers take turns row by row: in every round each row runs once in each, the order of the two
alternating, and only one process runs at a time, so both see the same machine.  Each turn times one
call; with ``--settle`` the row's second call in a row (the first untimed), as in a user's loop: timed
right after the other worker's call, a row can run slower than right after one of its own (this
checkout's float32 rows about a normal, ``out=``, 1.25-1.79x in each of seven idle runs against 5d0170b),
and 5d0170b's float64 fresh row about a normal took 61 ms settled against 230 ms (``--order`` prints the
first; docs/results/bench-rotation.md).  Both workers run
OpenBLAS with one thread (unless ``OPENBLAS_NUM_THREADS`` is set): its threads, busy-waiting after
5d0170b's numpy products about a normal, took the cores from this checkout's next call (measured: its
rows about a normal 1.3-1.8x slower than with one BLAS thread, the base's the same).  Reported per row:
the median over the rounds of each revision and the speed ratio base / new (above 1: this checkout is
faster); for the sampling rows also each one's fraction of the memory write limit, and the ceiling:
the base's time over the write limit's, the highest speed-up over the base that writing the bytes
allows.  The write limit is the fastest of four fills of the same bytes with the samplers' thread count
(benchmarks/_write_limit.py: numpy ``fill``, a numba ``prange`` loop, the same with non-temporal
stores, a numba loop on Python threads), into a touched buffer for ``out=`` and ``np.empty`` + the fill
for fresh output, so that the page faults count as for the sampler; the fills are this script's own
code, timed in both workers, and the limit is the faster of the two workers'
fastest fill (files written before: each worker's numpy ``fill``, "fill limit").

Rows: ``sample_sphere``, ``sample_hemisphere`` and ``sample_hemisphere`` about the normal (1, 1, 1),
float64 and float32, ``out=`` and fresh (n = 48 * 2**16); ``integrate`` of a numba-compiled f (the
fused kernel); the renderer's paths/s (cornell, 128 x 96, 48 spp, the default sampler); Mitsuba 3's
``symsphere_path`` paths/s (llvm_ad_rgb, the cornell_box scene, 128 x 128, 48 spp; needs the extra
``mitsuba`` and libLLVM >= 16, else skipped with the reason).  A row the base does not have shows "—".
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _machine import cpu_name, cpu_snapshot  # benchmarks/_machine.py (the script's folder is on sys.path)
from _write_limit import fills  # benchmarks/_write_limit.py: the write limit's fills
from tables import source_hashes  # benchmarks/tables.py: the measured files, for the tables' stale note

ROOT = Path(__file__).resolve().parents[1]
N = 48 * 2**16
NORMAL = (1.0, 1.0, 1.0)
RENDER = dict(width=128, height=96, spp=48)
MITSUBA = dict(width=128, height=128, spp=48)


# --- the worker: builds the rows with whichever symsphere is first on sys.path -----------------------


def _sampling_rows(n):
    import numpy as np

    import symsphere

    rows = {}
    for dtype in (np.float64, np.float32):
        name = np.dtype(dtype).name
        buffer = np.full((n, 3), 0.5, dtype)  # touched, as out= is: the untimed first calls compile what is timed
        for (way, kind), fill in fills(n, dtype).items():
            rows[f"write limit: {way}, {kind} ({name})"] = fill
        for label, function, extra in (
            ("sample_sphere", symsphere.sample_sphere, {}),
            ("sample_hemisphere", symsphere.sample_hemisphere, {}),
            ("sample_hemisphere, normal=(1,1,1)", symsphere.sample_hemisphere, {"normal": NORMAL}),
        ):
            rows[f"{label}, out= ({name})"] = lambda f=function, e=extra, d=dtype, b=buffer: f(
                n, rng=1, dtype=d, out=b, **e
            )
            rows[f"{label} ({name})"] = lambda f=function, e=extra, d=dtype: f(n, rng=1, dtype=d, **e)
    return rows


def _integrate_rows(n):
    from numba import njit

    import symsphere

    @njit(cache=True, nogil=True)
    def f(x, y, z):  # pragma: no cover - compiled by numba
        return x * x + 0.5 * y - z * z * z

    return {"integrate, compiled f (fused), 48·2^22": lambda: symsphere.integrate(f, n=48 * 2**22, rng=1)}


def _render_rows():
    from symsphere.render import cornell, render

    scene = cornell()
    return {"render cornell 128×96×48 spp": lambda: render(scene, seed=2, progress=False, **RENDER)}


def _mitsuba_rows():
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", _find_llvm() or "")
    if not os.environ["DRJIT_LIBLLVM_PATH"]:
        del os.environ["DRJIT_LIBLLVM_PATH"]
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    import numpy as np

    import symsphere.mitsuba as sm

    scene = mi.load_file(str(sm.scene_path("cornell_box")), width=MITSUBA["width"], height=MITSUBA["height"])
    spec = {"type": "symsphere_path", "strategy": "symmetric", "points": "random"}
    try:  # Mitsuba's own light sampling on every revision (before emitter_sampling, the only one)
        integrator = mi.load_dict({**spec, "emitter_sampling": "area"})
    except RuntimeError:  # a revision without the parameter: Mitsuba rejects the unreferenced property
        integrator = mi.load_dict(spec)
    seeds = iter(range(1, 10**6))

    def run():
        return np.array(mi.render(scene, integrator=integrator, spp=MITSUBA["spp"], seed=next(seeds)))

    return {"Mitsuba symsphere_path cornell_box 128×128×48 spp": run}


def _find_llvm():
    sys.path.insert(0, str(Path(__file__).parent))
    try:
        from bench_sample import find_libllvm  # type: ignore[attr-defined]
    except ImportError:
        return None
    found = find_libllvm()
    return found[0] if isinstance(found, tuple) else found


PATHS = {"render": RENDER, "Mitsuba": MITSUBA}


def worker(args):
    """Serve rows on stdin/stdout: a JSON line per request ("NAME" -> seconds, or null if missing)."""
    import symsphere

    rows, missing = {}, {}
    builders = [("sampling", lambda: _sampling_rows(args.n)), ("integrate", lambda: _integrate_rows(args.n))]
    if not args.no_render:
        builders.append(("render", _render_rows))
    if not args.no_mitsuba:
        builders.append(("mitsuba", _mitsuba_rows))
    for group, build in builders:
        try:
            built = build()
            for run in built.values():
                run()  # untimed: compile, or load from the cache
            rows.update(built)
        except Exception as error:  # a row the revision does not have, or Mitsuba not installed
            missing[group] = f"{type(error).__name__}: {str(error).splitlines()[0] if str(error) else ''}"
    ready = {"rows": list(rows), "missing": missing, "symsphere": symsphere.__file__, "cpu_s": _own_cpu()}
    print(json.dumps(ready), flush=True)
    for line in sys.stdin:
        name = json.loads(line)
        if name is None:
            break
        if args.settle:
            rows[name]()  # untimed: the timed call follows a call of its own, not the other worker's
        start = time.perf_counter()
        rows[name]()
        print(json.dumps(time.perf_counter() - start), flush=True)
    print(json.dumps(_own_cpu()), flush=True)


# --- the driver --------------------------------------------------------------------------------------


class Worker:
    def __init__(self, tree, cache, args):
        env = dict(os.environ, PYTHONPATH=str(tree / "src"), NUMBA_CACHE_DIR=str(cache))
        # the write limit's prange starts numba's OpenMP threads, maybe before symsphere does: make them wait
        # passively as symsphere would (spinning, they hold the cores the samplers' threads need)
        env.setdefault("OMP_WAIT_POLICY", "passive")
        # OpenBLAS's threads busy-wait after a product (5d0170b's numpy products about a normal) and took
        # the cores from the other worker's next call: its rows about a normal 1.3-1.8x slower, measured
        env.setdefault("OPENBLAS_NUM_THREADS", "1")
        if args.threads:  # one thread: the kernels' own speed, less sensitive to a loaded machine
            env["NUMBA_NUM_THREADS"] = str(args.threads)
        command = [sys.executable, str(Path(__file__).resolve()), "--worker", "--n", str(args.n)]
        command += ["--no-mitsuba"] * args.no_mitsuba + ["--no-render"] * args.no_render + ["--settle"] * args.settle
        self.process = subprocess.Popen(command, cwd=tree, env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                        text=True)  # fmt: skip

    def ready(self):
        return json.loads(self._line())

    def _line(self):
        line = self.process.stdout.readline()
        if not line:
            raise SystemExit(f"regress.py: a worker exited (status {self.process.wait()})")
        return line

    def time(self, name):
        self.process.stdin.write(json.dumps(name) + "\n")
        self.process.stdin.flush()
        return json.loads(self._line())

    def close(self):
        self.process.stdin.write("null\n")
        self.process.stdin.flush()
        cpu = json.loads(self._line())
        self.process.wait()
        return cpu


def _revision(tree, rev="HEAD"):
    return subprocess.run(["git", "-C", str(tree), "rev-parse", "--short", rev], capture_output=True, text=True,
                          check=True).stdout.strip()  # fmt: skip


def _dirty():
    status = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--untracked-files=no"],
                            capture_output=True, text=True, check=True).stdout  # fmt: skip
    return bool(status.strip())


def _limits(name, names):
    """The write-limit rows a sampling row is compared with (same dtype, out= or fresh; the fastest of them
    is the limit), or []."""
    if not name.startswith("sample_"):
        return []
    dtype = name.rsplit("(", 1)[1]
    kind = "out=" if ", out= (" in name else "fresh"
    return [r for r in names if r.startswith("write limit: ") and r.endswith(f", {kind} ({dtype}")]


def _limit(medians, rows):
    """(median, row) of the fastest of *rows* in one worker's medians, or (None, None)."""
    timed = [(medians[r], r) for r in rows if medians.get(r)]
    return min(timed) if timed else (None, None)


def report(result):
    print(f"regress.py: base {result['base']} vs this checkout {result['new']}; numba threads: {result['threads']}; "
          f"medians of {result['rounds']} "
          f"interleaved rounds ({'second' if result['settle'] else 'only'} call of each turn timed); n = {result['n']}; {result['cpu']}, {os.cpu_count()} CPUs; "
          f"others' CPU share {result['others_share']}")  # fmt: skip
    for name in ("base", "new"):
        print(f"  {name}: symsphere imported from {result['symsphere'][name]}")
    for name, why in sorted({**result["missing"]["base"], **result["missing"]["new"]}.items()):
        print(f"  skipped in {'new' if name in result['missing']['new'] else 'base'}: {name}: {why}")
    print()
    print(table_text(result))


def table_text(result):
    """The table of a result (also benchmarks/tables.py's, for the docs); files written before the write
    limit and the ceiling have "fill limit" rows (numpy's one-thread ``fill``) and no ceiling column."""
    ceiling = any("ceiling" in row for row in result["table"])
    limit = "write limit" if ceiling else "fill limit"
    lines = [
        f"| row | base (ms) | new (ms) | speed new / base | base of {limit} | new of {limit} |"
        + " ceiling new / base |" * ceiling,
        "|---|---:|---:|---:|---:|---:|" + "---:|" * ceiling,
    ]
    limits = {row.get(f"limit_{name}") for row in result["table"] for name in ("base", "new")}  # fastest fills
    for row in result["table"]:
        base, new = row["base_ms"], row["new_ms"]
        cells = [f"{base:.2f}" if base else "—", f"{new:.2f}" if new else "—"]
        cells.append(f"{row['speed_ratio']:.2f}×" if row["speed_ratio"] else "—")
        keys = ("base_of_limit", "new_of_limit") + ("ceiling",) * ceiling
        cells += [f"{row[key]:.2f}×" if row.get(key) else "" for key in keys]
        label = row["row"]
        if row.get("mpaths_per_s_new"):
            label += f" ({row['mpaths_per_s_base'] or 0:.2f} → {row['mpaths_per_s_new']:.2f} M paths/s)"
        if label in limits:
            label += " — the limit"  # in either process
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def table_rows(names, medians):
    """The table's entries from each worker's medians in seconds (``medians[name][row]``, name base or new)."""
    table = []
    for row in names:
        base, new = medians["base"][row], medians["new"][row]
        entry = {"row": row, "base_ms": base and base * 1e3, "new_ms": new and new * 1e3,
                 "speed_ratio": base / new if base and new else None}  # fmt: skip
        limits = _limits(row, names)
        if limits:
            # the fills are the same code in both processes: the faster of their fastest is the machine's write
            # limit in this run (one process's alone moved by up to 2.2x under load)
            refs = []
            for name in ("base", "new"):
                ref, entry[f"limit_{name}"] = _limit(medians[name], limits)
                refs += [ref] if ref else []
            ref = min(refs, default=None)
            for name in ("base", "new"):
                own = medians[name][row]
                entry[f"{name}_of_limit"] = ref / own if own and ref else None
            entry["ceiling"] = base / ref if base and ref else None  # the highest speed-up over the base possible
        for prefix, size in PATHS.items():
            if row.startswith(prefix):
                paths = size["width"] * size["height"] * size["spp"]
                for name in ("base", "new"):
                    entry[f"mpaths_per_s_{name}"] = paths / medians[name][row] / 1e6 if medians[name][row] else None
        table.append(entry)
    return table


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--base", default="HEAD", help="git revision to compare against (default: %(default)s)")
    parser.add_argument("--rounds", type=int, default=7, help="interleaved rounds (default: %(default)s)")
    parser.add_argument("--n", type=int, default=N, help="directions per sampling call (default: %(default)s)")
    parser.add_argument("--no-mitsuba", action="store_true", help="skip the Mitsuba row")
    parser.add_argument("--no-render", action="store_true", help="skip the renderer's row")
    parser.add_argument("--threads", type=int, help="NUMBA_NUM_THREADS of both workers (default: numba's own)")
    parser.add_argument("--settle", action=argparse.BooleanOptionalAction, default=False,
                        help="time each turn's second call in a row, the first untimed (default: one call)")  # fmt: skip
    parser.add_argument("--json", type=Path, help="also write every timing and the table here")
    parser.add_argument("--order", nargs="+", type=Path, metavar="JSON",
                        help="print how each row's time moved with its place in the turn, from results files")  # fmt: skip
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        return worker(args)
    if args.order:
        return order_effect(args.order)
    base_rev = _revision(ROOT, args.base)
    new_rev = _revision(ROOT) + ("+changes" if _dirty() else "")
    with tempfile.TemporaryDirectory(prefix="symsphere-regress-") as scratch:
        scratch = Path(scratch)
        base_tree = scratch / "base"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(base_tree), base_rev],
                       check=True)  # fmt: skip
        workers = {}
        try:
            print("compiling both revisions' kernels (empty numba caches: a minute or two) ...", file=sys.stderr)
            workers = {name: Worker(tree, scratch / f"numba-{name}", args)
                       for name, tree in (("base", base_tree), ("new", ROOT))}  # fmt: skip
            hello = {name: w.ready() for name, w in workers.items()}
            names = [r for r in hello["new"]["rows"]] + [
                r for r in hello["base"]["rows"] if r not in hello["new"]["rows"]
            ]
            times = {name: {r: [] for r in names} for name in workers}
            before, started, ours_before = cpu_snapshot(), time.perf_counter(), _own_cpu()
            for index in range(args.rounds):
                for position, row in enumerate(names):
                    order = ("base", "new") if (index + position) % 2 == 0 else ("new", "base")
                    for name in order:
                        if row in hello[name]["rows"]:
                            times[name][row].append(workers[name].time(row))
                print(f"round {index + 1}/{args.rounds} done", file=sys.stderr)
            wall = time.perf_counter() - started
            after = cpu_snapshot()
            worker_cpu = sum(w.close() - hello[name]["cpu_s"] for name, w in workers.items())  # while timing
            workers = {}
        finally:
            for w in workers.values():
                w.process.kill()
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(base_tree)], check=False)
    share = "?"
    if before is not None and after is not None:
        others = (after[0] - before[0]) - worker_cpu - (_own_cpu() - ours_before)
        share = f"{max(others, 0.0) / (wall * (os.cpu_count() or 1)):.0%}"
    medians = {name: {r: statistics.median(t) if t else None for r, t in rows.items()} for name, rows in times.items()}
    table = table_rows(names, medians)
    result = {
        "base": base_rev, "new": new_rev, "rounds": args.rounds, "n": args.n, "cpu": cpu_name(),
        "threads": args.threads or "numba's default", "settle": args.settle,
        "others_share": share, "missing": {name: hello[name]["missing"] for name in hello},
        "symsphere": {name: hello[name]["symsphere"] for name in hello}, "table": table, "times": times,
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "command": " ".join(["python", "benchmarks/regress.py", *(argv if argv is not None else sys.argv[1:])]),
        "sources": source_hashes(),
    }  # fmt: skip
    report(result)
    if share != "?" and float(share.rstrip("%")) > 20 and not args.threads:
        print("\nregress.py: other processes used much of the CPUs while it timed; the two-thread kernels suffer "
              "most (rerun with --threads 1, or on an idle machine)", file=sys.stderr)  # fmt: skip
    if args.json:
        args.json.write_text(json.dumps(result, indent=1))
    return None


def order_effect(paths):
    """Print, per file and row, each side's median time when it ran second in a turn over its median when
    it ran first (the round's order alternates by round and row, as in :func:`main`)."""
    for path in paths:
        result = json.loads(Path(path).read_text())
        names = [row["row"] for row in result["table"]]
        print(
            f"{path}: others' CPU share {result['others_share']}; {'settled' if result.get('settle') else 'one call per turn'}"
        )
        for position, row in enumerate(names):
            cells = []
            for side in ("base", "new"):
                runs = result["times"][side][row]
                first_is_base = [(index + position) % 2 == 0 for index in range(len(runs))]
                second = [t for t, b in zip(runs, first_is_base, strict=True) if b == (side == "new")]
                first = [t for t, b in zip(runs, first_is_base, strict=True) if b != (side == "new")]
                ok = second and first and statistics.median(first)
                cells.append(
                    f"{side} {statistics.median(second) / statistics.median(first):.2f}" if ok else f"{side} —"
                )
            print(f"  {row}: second / first: " + ", ".join(cells))


def _own_cpu():
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


if __name__ == "__main__":
    main()
