"""Time to the first sample in a new process: interpreter start, imports, numba cache load, first call.

Each measurement is a fresh subprocess of this Python, timed from outside
(wall clock from spawn to exit); the cases take turns in every round, and
medians over the rounds are reported.  The "warm" cases use symsphere's
numba cache as it is (``src/symsphere/__pycache__/*.nbi, *.nbc``; one untimed
run first fills it if the sources changed).  The "cold" cases point
``NUMBA_CACHE_DIR`` at a new empty temporary directory for every run, so the
kernels compile; the real cache is not touched.

The breakdown runs the same child with ``time.perf_counter`` around
``import symsphere``, the first call and a second call, and
``python -X importtime -c "import symsphere"`` shows which imports take the time.

``--cold-start`` measures instead what a new install pays (docs/results/cold-start.md):
with an empty numba cache, in one new process, the first ``sample_sphere`` and then each
further variant (dtype, point set, domain, frame, map), the first ``integrate`` with a numpy
f, the first ``render`` (its kernel, with the functions LLVM inlines into it); in new processes
the first ``symsphere render --scene cornell`` and ``symsphere demo``; and every kernel numba
compiled on the way, with its compile time (numba's
``"numba:compile"`` events).  Each is run ``--cold`` times; medians are reported, with the
CPU seconds beside the wall seconds (on a shared machine wall time includes waiting).

Usage::

    python benchmarks/first_sample.py                 # 48 * 1024 directions, 7 rounds, 2 cold runs
    python benchmarks/first_sample.py --repeats 11 --cold 3 --json first.json
    python benchmarks/first_sample.py --cold-start --cold 3 --json cold.json
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

from _machine import cpu_name, cpu_snapshot, others_cpu  # benchmarks/_machine.py (the script's folder is on sys.path)
from tables import source_hashes  # benchmarks/tables.py: the measured files, for the tables' stale note

TARGET_SECONDS = 1.0

# What any numba-based first call pays at least: importing numba and the one-time set-up of its
# typing and target contexts (done by the first dispatch, even when the kernel comes from the cache).
NUMBA_FLOOR = (
    "import numba; from numba.core.registry import cpu_target; "
    "cpu_target.typing_context.refresh(); cpu_target.target_context.refresh()"
)

BREAKDOWN = """
import json, time
t0 = time.perf_counter()
import symsphere
t1 = time.perf_counter()
symsphere.sample_sphere({n})
t2 = time.perf_counter()
symsphere.sample_sphere({n})
t3 = time.perf_counter()
print(json.dumps({{"import": t1 - t0, "first_call": t2 - t1, "second_call": t3 - t2}}))
"""


def run_child(code, env=None, *args):
    """Wall seconds of ``python [args] -c code`` from spawn to exit; (seconds, stdout, stderr)."""
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, *args, "-c", code], capture_output=True, text=True, env=env)
    seconds = time.perf_counter() - start
    if proc.returncode != 0:
        raise RuntimeError(f"child failed ({proc.returncode}): {code!r}\n{proc.stderr}")
    return seconds, proc.stdout, proc.stderr


def cold_env():
    """An environment whose numba cache is a new empty directory (cleaned up by the caller)."""
    directory = tempfile.mkdtemp(prefix="symsphere-numba-cold-")
    env = dict(os.environ, NUMBA_CACHE_DIR=directory)
    return env, directory


def _rmtree(directory):
    import shutil

    shutil.rmtree(directory, ignore_errors=True)


def importtime_table(max_depth=3, min_ms=20.0):
    """The import tree of ``import symsphere`` (one warm run of -X importtime), nodes >= *min_ms* cumulative.

    ``-X importtime`` lists modules in post-order with their nesting depth; a
    module is charged to whichever module imported it first.
    """
    _, _, stderr = run_child("import symsphere", None, "-X", "importtime")
    stack = []  # post-order: a line's children are the deeper lines just before it
    for line in stderr.splitlines():
        if not line.startswith("import time:") or "self [us]" in line:
            continue
        self_us, cumulative_us, name = line[len("import time:") :].split("|")
        depth = (len(name) - len(name.lstrip(" ")) - 1) // 2
        node = {
            "module": name.strip(),
            "depth": depth,
            "cumulative_s": int(cumulative_us) / 1e6,
            "self_s": int(self_us) / 1e6,
            "children": [],
        }
        while stack and stack[-1]["depth"] > depth:
            node["children"].insert(0, stack.pop())
        stack.append(node)
    root = next((node for node in stack if node["module"] == "symsphere"), None)
    rows = []

    def walk(node):
        if node["depth"] > max_depth or node["cumulative_s"] * 1e3 < min_ms:
            return
        rows.append(node)
        for child in sorted(node["children"], key=lambda c: -c["cumulative_s"]):
            walk(child)

    if root is not None:
        walk(root)
    lines = ["| module | cumulative ms | self ms |", "|---|---:|---:|"]
    for node in rows:
        indent = "&nbsp;&nbsp;" * node["depth"]
        lines.append(f"| {indent}{node['module']} | {node['cumulative_s'] * 1e3:.0f} | {node['self_s'] * 1e3:.1f} |")
    flat = [{k: v for k, v in node.items() if k != "children"} for node in rows]
    return "\n".join(lines), flat


COLD_STEPS = """
import json, time, sys
from numba.core import event
steps = []
def step(label, call):
    wall, cpu = time.perf_counter(), time.process_time()
    call()
    steps.append((label, time.perf_counter() - wall, time.process_time() - cpu))
with event.install_recorder("numba:compile") as recorder:
    step("import symsphere", lambda: __import__("symsphere"))
    import numpy as np
    import symsphere as ss
    step("first sample_sphere(48000)", lambda: ss.sample_sphere(48000, rng=1))
    step("+ dtype=float32", lambda: ss.sample_sphere(48000, rng=1, dtype="float32"))
    step("+ points='sobol'", lambda: ss.sample_sphere(48 * 1024, rng=1, points="sobol"))
    step("+ sample_hemisphere", lambda: ss.sample_hemisphere(24000, rng=1))
    step("+ sample_hemisphere(normal=...)", lambda: ss.sample_hemisphere(24000, rng=1, normal=[0, 1, 1]))
    step("+ method='paper1'", lambda: ss.sample_sphere(48000, rng=1, method="paper1"))
    a = np.array([0.3, 0.2, 0.1])
    step("+ first integrate, numpy f", lambda: ss.integrate(lambda w: np.exp(w @ a), n=48 * 4096, rng=1))
    step("+ first render('cornell', 64 x 48, 48 spp)", lambda: ss.render.render("cornell", width=64, height=48, spp=48, seed=1))
kernels = {}
starts = {}
for timestamp, ev in recorder.buffer:
    key = (str(ev.data["dispatcher"].py_func.__qualname__), str(ev.data["args"]))
    cells = ev.data["dispatcher"].py_func.__closure__
    if cells:
        key = (key[0] + str(tuple(c.cell_contents for c in cells if isinstance(c.cell_contents, (int, bool)))), key[1])
    if ev.is_start:
        starts[key] = timestamp
    elif key in starts:
        kernels[" | ".join(key)] = timestamp - starts.pop(key)
print(json.dumps({"steps": steps, "kernels": kernels}))
"""


def _cold_command(command, cache):
    """Wall and CPU seconds (children included) of one command with the numba cache *cache*."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache)
    before = os.times()
    start = time.perf_counter()
    proc = subprocess.run(command, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - start
    after = os.times()
    if proc.returncode != 0:
        raise RuntimeError(f"{command} failed ({proc.returncode}):\n{proc.stderr}")
    cpu = (after.children_user - before.children_user) + (after.children_system - before.children_system)
    return wall, cpu, proc


def cold_start(runs, json_path=None):
    """The cold-start table (see the module docstring)."""
    symsphere_cli = [sys.executable, "-m", "symsphere"]
    rows, kernels = {}, {}
    commands = {
        "first `symsphere render --scene cornell --width 64 --height 48 --spp 48`": [
            *symsphere_cli,
            "render",
            "--scene",
            "cornell",
            "--width",
            "64",
            "--height",
            "48",
            "--spp",
            "48",
            "--seed",
            "1",
        ],
        "`symsphere demo` after install": [*symsphere_cli, "demo", "--no-progress"],
    }
    for _ in range(runs):
        cache = tempfile.mkdtemp(prefix="symsphere-numba-cold-")
        try:
            _, _, proc = _cold_command([sys.executable, "-c", COLD_STEPS], cache)
            result = json.loads(proc.stdout.splitlines()[-1])
            for label, wall, cpu in result["steps"]:
                rows.setdefault(label, []).append((wall, cpu))
            for label, seconds in result["kernels"].items():
                kernels.setdefault(label, []).append(seconds)
        finally:
            _rmtree(cache)
        for label, command in commands.items():
            cache = tempfile.mkdtemp(prefix="symsphere-numba-cold-")
            out = tempfile.mkdtemp(prefix="symsphere-cold-out-")
            try:
                extra = (
                    ["--out", os.path.join(out, "render.png")]
                    if "render" in command
                    else ["--out", os.path.join(out, "demo")]
                )
                wall, cpu, _ = _cold_command(command + extra, cache)
                rows.setdefault(label, []).append((wall, cpu))
            finally:
                _rmtree(cache)
                _rmtree(out)
    print(
        f"Cold start (empty NUMBA_CACHE_DIR), {sys.executable}, {os.cpu_count()} CPUs, median of {runs} runs, "
        f"load average {os.getloadavg()[0]:.2f}:\n"
    )
    print("| step | wall s | CPU s |\n|---|---:|---:|")
    for label, values in rows.items():
        print(
            f"| {label} | {statistics.median(v[0] for v in values):.2f} | {statistics.median(v[1] for v in values):.2f} |"
        )
    print("\nKernels compiled by the steps in one process (numba's compile events; wall s, median):\n")
    print("| kernel (closure constants) | argument types | s |\n|---|---|---:|")
    for label, values in sorted(kernels.items(), key=lambda kv: -statistics.median(kv[1])):
        name, _, types = label.partition(" | ")
        print(f"| `{name}` | `{types[:90]}` | {statistics.median(values):.2f} |")
    if json_path:
        with open(json_path, "w", encoding="utf-8") as handle:
            meta = {
                "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
                "command": " ".join([os.path.relpath(sys.executable), *sys.argv]),
                "cpu": cpu_name(),
                "cpus": os.cpu_count(),
                "loadavg_after": os.getloadavg(),
            }
            payload = {"meta": meta, "sources": source_hashes(), "steps": rows, "kernels": kernels, "runs": runs}
            json.dump(payload, handle, indent=1)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=48 * 1024, help="directions of the first call (default: %(default)s)")
    parser.add_argument("--repeats", type=int, default=7, help="rounds of warm runs (default: %(default)s)")
    parser.add_argument(
        "--cold", type=int, default=2, help="cold runs, each with a new empty numba cache (default: %(default)s)"
    )
    parser.add_argument("--json", metavar="FILE", help="also write the results as JSON to FILE")
    parser.add_argument("--cold-start", action="store_true", help="the cold-start table instead (module docstring)")
    args = parser.parse_args(argv)
    if args.cold_start:
        return cold_start(max(1, args.cold), args.json)
    if args.n <= 0 or args.n % 48:
        parser.error(f"--n must be a positive multiple of 48, got {args.n}")

    sample = f"import symsphere; symsphere.sample_sphere({args.n})"
    breakdown = BREAKDOWN.format(n=args.n)
    warm = {
        "python -c pass (interpreter start)": "pass",
        "import numpy": "import numpy",
        "import numba": "import numba",
        "import scipy.stats": "import scipy.stats",
        "floor: import numba + numba's target-context init": NUMBA_FLOOR,
        "import symsphere": "import symsphere",
        f"import symsphere; sample_sphere({args.n})": sample,
    }
    print("priming symsphere's numba cache (one untimed run) ...", file=sys.stderr)
    run_child(sample)
    run_child(breakdown)

    snapshot, wall = cpu_snapshot(), time.perf_counter()
    times = {label: [] for label in warm}
    parts = []
    for round_index in range(args.repeats):
        labels = list(warm)
        start = round_index % len(labels)
        for label in labels[start:] + labels[:start]:
            times[label].append(run_child(warm[label])[0])
        parts.append(json.loads(run_child(breakdown)[1]))

    cold_total, cold_parts = [], []
    for _ in range(args.cold):
        env, directory = cold_env()
        try:
            cold_total.append(run_child(sample, env)[0])
        finally:
            _rmtree(directory)
        env, directory = cold_env()
        try:
            cold_parts.append(json.loads(run_child(breakdown, env)[1]))
        finally:
            _rmtree(directory)

    others = others_cpu(snapshot, cpu_snapshot(), time.perf_counter() - wall)

    import numba
    import numpy

    import symsphere

    first = statistics.median(times[f"import symsphere; sample_sphere({args.n})"])
    print(
        f"Time to first sample in a new process: {sys.executable}, Python {sys.version.split()[0]}, "
        f"symsphere {symsphere.__version__}, numpy {numpy.__version__}, numba {numba.__version__}, "
        f"{os.cpu_count()} CPUs; warm: median of {args.repeats} rounds, cold: {args.cold} runs; "
        f"load average {os.getloadavg()[0]:.2f}"
        + (
            f"; other processes used {others['cpu_s']:.1f} CPU-s in the {others['wall_s']:.0f} s of timing "
            f"({others['share_of_all_cpus']:.0%} of all CPUs)"
            if others
            else ""
        )
        + "\n"
    )
    lines = ["| new process (warm numba cache) | median s | min s |", "|---|---:|---:|"]
    for label, values in times.items():
        lines.append(f"| `{label}` | {statistics.median(values):.3f} | {min(values):.3f} |")
    if cold_total:
        lines.append(
            f"| `{sample}`, **cold** (empty NUMBA_CACHE_DIR) | {statistics.median(cold_total):.3f} | {min(cold_total):.3f} |"
        )
    print("\n".join(lines))

    print("\nInside the child (time.perf_counter):\n")
    lines = ["| cache | import symsphere s | first call s | second call s |", "|---|---:|---:|---:|"]
    for label, rows in (("warm", parts), ("cold", cold_parts)):
        if rows:
            med = {key: statistics.median(r[key] for r in rows) for key in ("import", "first_call", "second_call")}
            lines.append(f"| {label} | {med['import']:.3f} | {med['first_call']:.3f} | {med['second_call']:.4f} |")
    print("\n".join(lines))

    table, imports = importtime_table()
    print(
        "\n`python -X importtime -c 'import symsphere'`, modules of >= 20 ms to depth 3 (a module is charged to its first importer):\n"
    )
    print(table)

    verdict = "reached" if first < TARGET_SECONDS else "NOT reached"
    print(
        f"\nTarget: first sample in a new process with a warm cache < {TARGET_SECONDS:.0f} s: {first:.3f} s, {verdict}."
    )

    if args.json:
        payload = {
            "n": args.n,
            "repeats": args.repeats,
            "warm_s": times,
            "cold_s": cold_total,
            "breakdown_warm": parts,
            "breakdown_cold": cold_parts,
            "importtime": imports,
            "other_processes": others,
            "target_s": TARGET_SECONDS,
            "first_sample_warm_median_s": first,
            "reached": first < TARGET_SECONDS,
        }
        with open(args.json, "w", encoding="utf-8") as handle:
            json.dump(payload, handle, indent=1)


if __name__ == "__main__":
    main()
