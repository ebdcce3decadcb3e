"""Where the test suite's time goes: each test's wall and CPU seconds, and a table per file.

As a pytest plugin (benchmarks/ on the path), one JSON line per test and per process (an xdist worker's
``cpu-gw0.jsonl``, ...) in ``SUITE_CPU_DIR`` (default: the working folder):

    PYTHONPATH=benchmarks SUITE_CPU_DIR=/tmp/suite .venv/bin/python -m pytest -n auto --dist loadgroup -p suite_cpu

CPU seconds are the worker's own (``self``) and those of the child processes it reaped during the test
(``child``); processes it did not reap (a Dask cluster's workers, a fork server's children) are not in
them, so on a loaded machine compare wall seconds of the same files only between runs in the same
conditions.  Then

    python benchmarks/suite_cpu.py /tmp/suite [--top 25]

prints the files by their tests' wall seconds (summed over the workers) and each worker's busy span.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

import pytest

_out = None


def _cpu() -> tuple[float, float]:
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime, children.ru_utime + children.ru_stime


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item: Any, nextitem: Any) -> Any:
    global _out
    if _out is None:
        worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
        folder = Path(os.environ.get("SUITE_CPU_DIR", "."))
        folder.mkdir(parents=True, exist_ok=True)
        _out = open(folder / f"cpu-{worker}.jsonl", "a", encoding="utf-8")  # kept open for the whole run
    own0, child0 = _cpu()
    start = time.perf_counter()
    yield
    own1, child1 = _cpu()
    row = {"id": item.nodeid, "self": own1 - own0, "child": child1 - child0, "wall": time.perf_counter() - start}
    row["end"] = time.time()
    _out.write(json.dumps(row) + "\n")
    _out.flush()


def summary(folder: Path, top: int) -> str:
    lines = []
    by_file: dict[str, list[float]] = defaultdict(lambda: [0, 0.0, 0.0])
    for path in sorted(folder.glob("cpu-*.jsonl")):
        rows = [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines()]
        if not rows:
            continue
        span = rows[-1]["end"] - (rows[0]["end"] - rows[0]["wall"])
        busy = sum(r["wall"] for r in rows)
        lines.append(f"{path.name}: {len(rows)} tests, {busy:.1f} s in tests over a span of {span:.1f} s")
        for r in rows:
            entry = by_file[r["id"].split("::")[0]]
            entry[0] += 1
            entry[1] += r["wall"]
            entry[2] += r["self"] + r["child"]
    lines.append("| file | tests | wall s | CPU s (reaped) |")
    lines.append("| --- | ---: | ---: | ---: |")
    ranked = sorted(by_file.items(), key=lambda item: -item[1][1])
    for name, (count, wall, cpu) in ranked[:top]:
        lines.append(f"| `{name}` | {count:.0f} | {wall:.1f} | {cpu:.1f} |")
    total_wall = sum(entry[1] for entry in by_file.values())
    lines.append(f"| all {len(by_file)} files | {sum(e[0] for e in by_file.values()):.0f} | {total_wall:.1f} | |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folder", type=Path, help="the SUITE_CPU_DIR of a run")
    parser.add_argument("--top", type=int, default=25, help="how many files to list (default 25)")
    args = parser.parse_args()
    print(summary(args.folder, args.top))


if __name__ == "__main__":
    main()
