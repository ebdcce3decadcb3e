"""What a first call compiles: numba's compile events, per function, in a new process with an empty cache.

    python benchmarks/compile_times.py sample          # the first sample_sphere(48000)
    python benchmarks/compile_times.py render --top 25  # the first `symsphere render --scene cornell` 64 x 48

The step runs in a child process whose ``NUMBA_CACHE_DIR`` is a new empty directory (removed afterwards).
Printed: the child's CPU seconds for the import and for the step (compilation is single-threaded), the
step's wall seconds, and the functions numba compiled, longest first, in wall seconds from numba's
``"numba:compile"`` events; a function's time includes the helpers compiled inside it the first time.
The renderer compiles part of its kernel in a second process (``symsphere._compile_ahead``), whose
functions are not listed.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time


def _child(step: str, top: int) -> None:
    cpu, wall = time.process_time(), time.perf_counter()
    from numba.core import event

    import symsphere

    imported = time.process_time() - cpu
    recorder = event.RecordingListener()
    event.register("numba:compile", recorder)
    cpu, wall = time.process_time(), time.perf_counter()
    if step == "sample":
        symsphere.sample_sphere(48000)
    else:
        from symsphere.apps import cli

        with tempfile.TemporaryDirectory() as folder:
            cli.main(["render", "--scene", "cornell", "--width", "64", "--height", "48", "--no-progress",
                      "--out", os.path.join(folder, "cold.png")])  # fmt: skip
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    started: dict[str, list[float]] = {}
    took = []
    for stamp, happened in recorder.buffer:
        dispatcher = happened.data.get("dispatcher")
        name = f"{dispatcher.py_func.__module__}.{dispatcher.py_func.__qualname__}" if dispatcher else "?"
        if happened.is_start:
            started.setdefault(name, []).append(stamp)
        else:
            took.append((stamp - started[name].pop(), name))
    print(f"import symsphere: {imported:.2f} CPU-s; first {step}: {cpu:.2f} CPU-s, {wall:.2f} s wall")
    for seconds, name in sorted(took, reverse=True)[:top]:
        print(f"{seconds:8.3f} s  {name}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("step", choices=["render", "sample"], help="what the new process does first")
    parser.add_argument("--top", type=int, default=15, help="how many functions to list (default: 15)")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        _child(args.step, args.top)
        return 0
    with tempfile.TemporaryDirectory() as cache:
        command = [sys.executable, __file__, args.step, "--top", str(args.top), "--child"]
        return subprocess.run(command, env={**os.environ, "NUMBA_CACHE_DIR": cache}, check=False).returncode


if __name__ == "__main__":
    sys.exit(main())
