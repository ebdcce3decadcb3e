"""Before/after: one benchmark script run on two revisions of symsphere in interleaved rounds.

The base revision is checked out into a temporary git worktree; each round runs the
script once with that tree's ``src`` first on ``PYTHONPATH`` and once with this
checkout's (the order alternating between rounds), each revision with its own warm
numba cache (one untimed run first fills it).  Every number of the script's ``--json``
output whose key (or the key of the dict holding it) matches ``--keys`` (default: ``median``)
is collected per round; reported is, per number, the median over the rounds of each revision
and the speed ratio: base / new for times, new / base with ``--rate`` (numbers per second);
above 1 the new revision is faster.

Usage::

    python benchmarks/compare_revisions.py --base db6d760 --rounds 3 -- \\
        benchmarks/bench_sample.py --no-mitsuba --no-integrate --no-profile --repeats 7
    python benchmarks/compare_revisions.py --base db6d760 --keys '^(numpy|fused|limit)$' -- \
        benchmarks/bench_integrate.py --rounds 3
    python benchmarks/compare_revisions.py --base db6d760 --rate -- \
        benchmarks/bench_render.py paths-vs-mitsuba --no-mitsuba --samplers cosine symmetric_sobol --rounds 3
    python benchmarks/compare_revisions.py --base db6d760 --rate --same-script --keys . -- benchmarks/render_rate.py
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _numbers(payload, pattern, prefix="", parent=""):
    """{path: value} of the numbers in a JSON document whose key or parent key matches *pattern*."""
    found = {}
    if isinstance(payload, dict):
        label = next(
            (payload[k] for k in ("label", "name", "case", "integrand", "scene") if isinstance(payload.get(k), str)),
            None,
        )
        extra = "/".join(str(payload[k]) for k in ("dtype", "group") if isinstance(payload.get(k), str))
        here = prefix + (f"[{label}{'/' + extra if extra else ''}]" if label else "")
        for key, value in payload.items():
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                if re.search(pattern, key) or re.search(pattern, parent):
                    found[f"{here}.{key}"] = float(value)
            elif isinstance(value, (dict, list)):
                found.update(_numbers(value, pattern, f"{here}.{key}", key))
    elif isinstance(payload, list):
        for index, value in enumerate(payload):
            found.update(_numbers(value, pattern, f"{prefix}[{index}]", parent))
    return found


def _run(
    tree: Path, cache: Path, script: list[str], out: Path, pattern: str, script_tree: Path | None = None
) -> dict[str, float]:
    env = dict(os.environ, PYTHONPATH=str(tree / "src"), NUMBA_CACHE_DIR=str(cache))
    command = [sys.executable, str((script_tree or tree) / script[0]), *script[1:], "--json", str(out)]
    subprocess.run(command, cwd=tree, env=env, check=True, stdout=subprocess.DEVNULL)
    return _numbers(json.loads(out.read_text()), pattern)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--base", required=True, help="the revision to compare against (any git revision)")
    parser.add_argument("--rounds", type=int, default=3, help="interleaved rounds (default: %(default)s)")
    parser.add_argument("--json", type=Path, help="write the per-round numbers here")
    parser.add_argument(
        "--keys", default="median", help="regular expression for the keys to compare (default: %(default)s)"
    )
    parser.add_argument("--rate", action="store_true", help="the numbers are rates (higher is faster), not times")
    parser.add_argument(
        "--same-script",
        action="store_true",
        help="run this checkout's script against both revisions (for a script the base does not have)",
    )
    parser.add_argument(
        "script",
        nargs=argparse.REMAINDER,
        help="-- the benchmark script (relative to the repository) and its arguments",
    )
    args = parser.parse_args(argv)
    script = args.script[1:] if args.script[:1] == ["--"] else args.script
    if not script:
        parser.error("give the benchmark script after --")
    with tempfile.TemporaryDirectory(prefix="symsphere-compare-") as scratch:
        scratch = Path(scratch)
        base_tree = scratch / "base"
        subprocess.run(
            ["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(base_tree), args.base], check=True
        )
        try:
            trees = {"base": base_tree, "new": ROOT}
            caches = {name: scratch / f"numba-{name}" for name in trees}
            script_tree = ROOT if args.same_script else None
            for name in trees:  # untimed: fill each revision's numba cache
                _run(trees[name], caches[name], script, scratch / "warm.json", args.keys, script_tree)
            rounds: dict[str, list[dict[str, float]]] = {"base": [], "new": []}
            for index in range(args.rounds):
                order = ["base", "new"] if index % 2 == 0 else ["new", "base"]
                for name in order:
                    rounds[name].append(
                        _run(
                            trees[name], caches[name], script, scratch / f"{name}-{index}.json", args.keys, script_tree
                        )
                    )
                print(f"round {index + 1}/{args.rounds} done", file=sys.stderr)
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(base_tree)], check=False)
    keys = [k for k in rounds["new"][0] if all(k in r for r in rounds["base"] + rounds["new"])]
    print(f"`{' '.join(script)}`: base {args.base} vs this checkout, medians of {args.rounds} interleaved rounds\n")
    print(f"| number | base | new | {'new / base' if args.rate else 'base / new'} (speed) |\n|---|---:|---:|---:|")
    summary = {}
    for key in keys:
        base = statistics.median(r[key] for r in rounds["base"])
        new = statistics.median(r[key] for r in rounds["new"])
        ratio = (new / base if args.rate else base / new) if new and base else None
        summary[key] = {"base": base, "new": new, "speed_ratio": ratio}
        shown = f"{ratio:.2f}×" if ratio is not None else "—"
        print(f"| {key} | {base:.4g} | {new:.4g} | {shown} |")
    if args.json:
        args.json.write_text(
            json.dumps({"base": args.base, "script": script, "rounds": rounds, "summary": summary}, indent=1)
        )


if __name__ == "__main__":
    main()
