"""The sampling kernels' CPU time on one thread: this checkout against a base revision, in one process.

    python benchmarks/kernel_cpu.py --base main --rounds 25

For a loaded machine: ``time.thread_time()`` around each call counts only the time the calling thread ran
(with ``numba.set_num_threads(1)`` the kernel runs in that thread), not the time it waited for a core, so
it is the kernel's own cost, stalls on memory included.  It says nothing about two threads sharing the
memory system (``regress.py`` on an idle machine does).  With ``--threads 2`` the kernels run on two
threads and the clock is ``time.process_time()``, the CPU time of all the process's threads: what two
threads cost together, stalls included (e.g. on a cache line both write), still blind to waiting for a
core; numpy's ``fill`` stays on one thread.  The base revision's ``src/symsphere`` is
copied out of git under another package name (``symsphere_base``) and imported beside this checkout's;
the rows (numpy's ``fill`` of a buffer, ``sample_sphere``, ``sample_hemisphere`` and
``sample_hemisphere`` about (1, 1, 1), all ``out=``, each into a buffer of its own, n = 48 * 2**16, float64
and float32; with ``--fresh`` also each with fresh output) take turns in every round.  Printed: the
median and the minimum in ms, and the fraction of ``fill`` (its minimum over the row's minimum).

    python benchmarks/kernel_cpu.py --stores --rounds 11 [--threads 2] [--n 196608]

With ``--stores`` (no base): this checkout's rows, ``out=`` and fresh, each with the kernels' plain
stores (``_kernels.stream_override = False``), with their rule (``None``: non-temporal stores for an
``out=`` of at least ``_kernels.STREAM_BYTES`` whose pages are in memory) and with non-temporal stores
forced (``True``); beside them the non-temporal fill of the write limit (``out=``) and
the plain one (fresh), benchmarks/_write_limit.py.  Each ``out=`` row writes a buffer of its own, and
each round times a row's second call in a row: the host's cache keeps what plain stores wrote (its L3 is
reported as 480 MiB) and not what non-temporal ones did, so a row after another would be timed with the
other's cache.  With ``--threads 2`` the clock is the wall clock
(``time.perf_counter``), as two threads' CPU time says nothing about their waits for memory.

    python benchmarks/kernel_cpu.py --timeline --rounds 21 [--n 196608] [--swap]

With ``--timeline`` (no base): when each part of this checkout's ``sample_sphere(out=)`` (two threads,
float32 and float64) starts and ends in its thread, in us from the call's start (``time.perf_counter_ns``
stamps in a copy of ``symsphere._threads.run_parts``): the launch, part 0 in the calling thread, part 1
on the pool, the caller back from its wait, the call's end; medians over rounds of each call's second run
in a row, beside the write limit (the ``prange`` non-temporal fill) of the same rounds and the other
processes' share of the CPUs (``/proc/stat``); per call, the pool's late start and the caller's wait.
With ``--swap`` the calling thread runs part 1 (the second half of the rows) and the pool part 0: whether a
slower part is the thread or the half of the buffer it writes.

    python benchmarks/kernel_cpu.py --asm

With ``--asm``: the vector and scalar floating-point instructions and permutations of the kernel about a
normal (random points, the equal-area map; float64 and float32 rows, plain stores), counted in its
assembly, compiled in an empty numba cache (numba shows no assembly for cached code).  The rotated store
appears twice in the kernel, for the whole orbits and for a cut one.

    python benchmarks/kernel_cpu.py --bound --rounds 15

With ``--bound``: what bounds the rows about a normal, in ns of one thread's CPU per orbit (24 directions;
medians), float32 and float64: the rotated store alone and the hemisphere's orbit store alone (256 fixed
points stored over and over into 32 rows on cache lines, in L1: the stores' own arithmetic); the whole
kernel (random points, equal-area map) in the cache (its dispatcher called 10 times into an output of 512
and of 1536 orbits, 0.15-0.9 MB: the slope between the two, without the calls' fixed cost); and at n = 48 * 2**16 (``--n``) into a
touched ``out=`` (non-temporal stores, the kernels' rule) and fresh (``_blocks.empty_rows``, page faults
included), beside the write limit's non-temporal fill (touched) and ``prange`` fill (fresh) of the same
bytes (benchmarks/_write_limit.py).  Each timed call follows one of its own.

    python benchmarks/kernel_cpu.py --pause 3 --rounds 5

With ``--pause P`` (no base): fresh output (two threads, wall clock) timed right after a call of its own and
after a pause of P seconds, for the write limit's ``prange`` fill and the samplers: a guest whose kernel
reports free memory to its host (Linux's free page reporting, ``virtio_balloon``) gives the freed pages back
after ~2 s, and the next first touch of them faults in the host too.  The pause is slept, and spun (the
calling thread busy, so that a slower call after it is not the CPU waking up).  Printed beside the times: the
kernel's ``page_reporting_order`` (free blocks of at least 2**order pages are reported) if it has one.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
N = 48 * 2**16


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--base", default="HEAD", help="git revision to compare against (default: HEAD)")
    parser.add_argument("--rounds", type=int, default=25, help="interleaved rounds (default: 25)")
    parser.add_argument("--threads", type=int, default=1, help="numba threads of the kernels (default: 1)")
    parser.add_argument("--fresh", action="store_true", help="also the rows with fresh output (np.empty)")
    parser.add_argument("--stores", action="store_true", help="this checkout's plain against streamed stores")
    parser.add_argument("--n", type=int, default=N, help=f"directions per call (default: {N})")
    parser.add_argument("--asm", action="store_true", help="count the instructions of the kernel about a normal")
    parser.add_argument("--timeline", action="store_true", help="when each part of sample_sphere(out=) runs")
    parser.add_argument("--swap", action="store_true", help="--timeline: the calling thread runs the last part")
    parser.add_argument("--bound", action="store_true", help="per orbit: the stores alone, in the cache, out=, fresh")
    parser.add_argument("--pause", type=float, default=0.0, help="fresh output after a call and after P seconds")
    args = parser.parse_args(argv)
    modes = [  # each measures this checkout only, from its src (and the benchmarks' helpers)
        (args.pause, lambda: _pause(args.rounds, args.n, args.pause)),
        (args.bound, lambda: _bound(args.rounds, args.n)),
        (args.timeline, lambda: _timeline(args.rounds, args.n, args.swap)),
        (args.asm, _asm),
        (args.stores, lambda: _stores(args.rounds, args.threads, args.n)),
    ]
    for chosen, measure in modes:
        if chosen:
            sys.path[:0] = [str(ROOT / "benchmarks"), str(ROOT / "src")]
            measure()
            return 0
    with tempfile.TemporaryDirectory() as folder:
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", args.base, "src/symsphere"], check=True,
                                 capture_output=True).stdout  # fmt: skip
        subprocess.run(["tar", "-x", "-C", folder], input=archive, check=True)
        (Path(folder) / "src" / "symsphere").rename(Path(folder) / "symsphere_base")
        sys.path.insert(0, folder)
        sys.path.insert(0, str(ROOT / "src"))
        _run(args.base, args.rounds, args.threads, args.fresh)
    return 0


def _run(base: str, rounds: int, threads: int, fresh: bool) -> None:
    import numpy as np
    import symsphere_base  # type: ignore[import-not-found]  # the copy made above
    from numba import set_num_threads

    import symsphere

    set_num_threads(threads)
    clock = time.thread_time if threads == 1 else time.process_time
    rows = {}
    for dtype in (np.float64, np.float32):
        buffer = np.empty((N, 3), dtype)
        name = np.dtype(dtype).name
        rows[f"fill ({name})"] = lambda b=buffer: b.fill(0.5)
        for tag, package in ((base, symsphere_base), ("this checkout", symsphere)):
            for label, extra in (
                ("sample_sphere", {}),
                ("sample_hemisphere", {}),
                ("normal=(1,1,1)", {"normal": (1.0, 1.0, 1.0)}),
            ):
                call = package.sample_sphere if label == "sample_sphere" else package.sample_hemisphere
                # each row its own buffer: plain stores leave it in the cache, non-temporal ones do not
                out = np.full((N, 3), 0.5, dtype)
                rows[f"{label}, out= ({name}), {tag}"] = lambda c=call, d=dtype, b=out, e=extra: c(
                    N, rng=1, dtype=d, out=b, **e
                )
                if fresh:
                    rows[f"{label}, fresh ({name}), {tag}"] = partial(call, N, rng=1, dtype=dtype, **extra)
    for run in rows.values():
        run()
    times: dict[str, list[float]] = {key: [] for key in rows}
    keys = list(rows)
    for r in range(rounds):
        for key in keys[r % len(keys) :] + keys[: r % len(keys)]:
            start = clock()
            rows[key]()
            times[key].append(clock() - start)
    what = "one thread, thread CPU ms" if threads == 1 else f"{threads} threads, process CPU ms"
    print(f"kernel_cpu.py: {what} over {rounds} interleaved rounds, n = {N}")
    for key in keys:
        fill = min(times[f"fill ({'float64' if 'float64' in key else 'float32'})"])
        print(f"{key:50s} median {statistics.median(times[key]) * 1e3:7.2f}  min {min(times[key]) * 1e3:7.2f}"
              f"  of fill {fill / min(times[key]):.2f}")  # fmt: skip


def _timeline(rounds: int, n: int, swap: bool = False) -> None:
    import os
    from concurrent.futures import wait

    import _write_limit  # type: ignore[import-not-found]  # benchmarks/, put on the path above
    import numpy as np
    from numba import set_num_threads

    import symsphere
    from symsphere import _threads

    set_num_threads(2)
    stamps: dict[str, int] = {}
    clock = time.perf_counter_ns

    def run_parts(task: Callable[[int], None], count: int) -> None:  # _threads.run_parts, with stamps
        stamps["launch"] = clock()

        def part(index: int) -> None:
            stamps[f"start {index}"] = clock()
            task(index)
            stamps[f"end {index}"] = clock()

        mine = count - 1 if swap else 0  # --swap: which half a thread writes, not which thread, if it matters
        futures = [_threads._executor().submit(part, index) for index in range(count) if index != mine]
        try:
            part(mine)
        finally:
            wait(futures)
        stamps["back"] = clock()
        for future in futures:
            future.result()

    _threads.run_parts = run_parts  # run_kernel looks it up at each call

    def busy() -> tuple[int, int]:
        jiffies = [int(x) for x in Path("/proc/stat").read_text().split("\n")[0].split()[1:]]
        return sum(jiffies) - jiffies[3] - jiffies[4], sum(jiffies)

    who = (
        "part 1 in the calling thread, part 0 on the pool"
        if swap
        else "part 0 in the calling thread, part 1 on the pool"
    )
    print(f"kernel_cpu.py --timeline: us from the call's start, medians of {rounds} rounds, n = {n}; {who}")
    for dtype in (np.float32, np.float64):
        out = np.full((n, 3), 0.5, dtype)
        rows: list[dict[str, float]] = []
        limit = []
        busy0, all0, mine0 = *busy(), sum(os.times()[:2])
        for _ in range(rounds):
            for _ in range(2):
                stamps.clear()
                start = clock()
                symsphere.sample_sphere(n, rng=1, dtype=dtype, out=out)
                end = clock()
            rows.append({key: (value - start) / 1e3 for key, value in stamps.items()} | {"end": (end - start) / 1e3})
            for _ in range(2):
                start = clock()
                _write_limit._nontemporal(out.reshape(-1), 0.5)
                end = clock()
            limit.append((end - start) / 1e3)
        busy1, all1, mine1 = *busy(), sum(os.times()[:2])
        others = max(0.0, (busy1 - busy0 - (mine1 - mine0) * os.sysconf("SC_CLK_TCK")) / (all1 - all0))
        median = {key: statistics.median(row[key] for row in rows) for key in rows[0]}
        fill = statistics.median(limit)
        span = max(median["end 0"], median.get("end 1", 0.0)) - min(median["start 0"], median.get("start 1", 1e30))
        print(f"{np.dtype(dtype).name}: write limit {fill:.0f} us; others' share of the CPUs {others:.0%}")
        print("  " + "  ".join(f"{key} {value:.0f}" for key, value in median.items()))
        print(f"  call {fill / median['end']:.2f}x of the limit, the parts' span {fill / span:.2f}x")
        if "end 1" in median:  # per call, then the median: the pool's late start, the caller's wait after the last end
            caller, pool = (1, 0) if swap else (0, 1)
            lag = statistics.median(row[f"start {pool}"] - row[f"start {caller}"] for row in rows)
            last = [row["back"] - max(row["end 0"], row["end 1"]) for row in rows]
            pool_last = sum(row[f"end {pool}"] > row[f"end {caller}"] for row in rows)
            print(f"  pool's start after the caller's {lag:.0f} us; back after the last part's end {statistics.median(last):.0f} us "
                  f"(max {max(last):.0f}); the pool's part ended last in {pool_last} of {rounds} calls")  # fmt: skip


def _stores(rounds: int, threads: int, n: int) -> None:
    import os

    os.environ.setdefault("OMP_WAIT_POLICY", "passive")  # the fills' prange threads, as symsphere starts them
    import numpy as np
    from _write_limit import fills  # type: ignore[import-not-found]  # benchmarks/ is on sys.path
    from numba import set_num_threads

    import symsphere
    from symsphere._testing import kernels

    set_num_threads(threads)
    clock = time.thread_time if threads == 1 else time.perf_counter
    rows: dict[str, tuple[bool | None, Callable[[], object]]] = {}
    for dtype in (np.float64, np.float32):
        name = np.dtype(dtype).name
        limit = fills(n, dtype)
        rows[f"write limit, out= ({name})"] = (None, limit["numba prange, non-temporal", "out="])
        rows[f"write limit, fresh ({name})"] = (None, limit["numba prange", "fresh"])
        for label, call, extra in (
            ("sample_sphere", symsphere.sample_sphere, {}),
            ("sample_hemisphere", symsphere.sample_hemisphere, {}),
            ("normal=(1,1,1)", symsphere.sample_hemisphere, {"normal": (1.0, 1.0, 1.0)}),
        ):
            for kind in ("out=", "fresh"):
                for stores, override in (("plain", False), ("rule", None), ("streamed", True)):
                    out = None if kind == "fresh" else np.full((n, 3), 0.5, dtype)  # each row its own buffer
                    rows[f"{label}, {kind} ({name}), {stores}"] = (
                        override,
                        partial(call, n, rng=1, dtype=dtype, out=out, **extra),
                    )

    def run(key: str) -> None:
        kernels.stream_override, call = rows[key]
        call()

    for key in rows:
        run(key)
    times: dict[str, list[float]] = {key: [] for key in rows}
    keys = list(rows)
    for r in range(rounds):
        for key in keys[r % len(keys) :] + keys[: r % len(keys)]:
            for _ in range(2):  # the call timed follows one of its own (the cache as the row leaves it)
                start = clock()
                run(key)
            times[key].append(clock() - start)
    kernels.stream_override = None
    what = "one thread, thread CPU ms" if threads == 1 else f"{threads} threads, wall ms"
    print(f"kernel_cpu.py --stores: {what} over {rounds} interleaved rounds, n = {n}")
    for key in keys:
        print(f"{key:50s} median {statistics.median(times[key]) * 1e3:7.2f}  min {min(times[key]) * 1e3:7.2f}")


def _pause(rounds: int, n: int, pause: float) -> None:
    import os

    os.environ.setdefault("OMP_WAIT_POLICY", "passive")  # the fills' prange threads, as symsphere starts them
    import numpy as np
    from _write_limit import fills  # type: ignore[import-not-found]  # benchmarks/ is on sys.path

    import symsphere

    rows: dict[str, Callable[[], object]] = {}
    for dtype in (np.float64, np.float32):
        name = np.dtype(dtype).name
        rows[f"write limit: numba prange, fresh ({name})"] = fills(n, dtype)["numba prange", "fresh"]
        rows[f"sample_hemisphere, fresh ({name})"] = partial(symsphere.sample_hemisphere, n, rng=1, dtype=dtype)
        rows[f"normal=(1,1,1), fresh ({name})"] = partial(
            symsphere.sample_hemisphere, n, rng=1, dtype=dtype, normal=(1.0, 1.0, 1.0)
        )
    for call in rows.values():
        call()
    ways = ("after", "slept", "spun")
    times: dict[tuple[str, str], list[float]] = {(key, way): [] for key in rows for way in ways}
    loads = []
    for _ in range(rounds):
        for key, call in rows.items():
            for way in ways:
                call()  # untimed: "after" follows it at once, the others after the pause
                if way == "slept":
                    time.sleep(pause)
                elif way == "spun":
                    end = time.perf_counter() + pause
                    while time.perf_counter() < end:
                        pass
                start = time.perf_counter()
                call()
                times[key, way].append(time.perf_counter() - start)
        loads.append(os.getloadavg()[0])
    order = Path("/sys/module/page_reporting/parameters/page_reporting_order")
    reporting = order.read_text().strip() if order.exists() else "none"
    print(f"kernel_cpu.py --pause {pause:g}: two threads' wall ms (medians, min), {rounds} interleaved rounds, "
          f"n = {n}; page_reporting_order {reporting}; load average {min(loads):.2f}-{max(loads):.2f}")  # fmt: skip
    for key in rows:
        cells = [
            f"{way} {statistics.median(times[key, way]) * 1e3:7.2f} ({min(times[key, way]) * 1e3:6.2f})" for way in ways
        ]
        print(f"{key:44s} " + "  ".join(cells))


def _repeat(kernel: Callable[..., object], arguments: tuple[object, ...]) -> None:
    for _ in range(10):
        kernel(*arguments)


def _bound(rounds: int, n: int) -> None:
    import os

    os.environ.setdefault("OMP_WAIT_POLICY", "passive")  # the fills' prange threads, as symsphere starts them
    import numpy as np
    from _write_limit import fills  # type: ignore[import-not-found]  # benchmarks/ is on sys.path
    from numba import njit, set_num_threads

    import symsphere
    from symsphere._testing import blocks, kernels
    from symsphere.frames import frame

    set_num_threads(1)
    count = 24
    basis = frame(np.ones(3) / np.sqrt(3.0))
    seed = symsphere.points.BasePoints("random", 1, total=n).seed_words
    points = np.random.default_rng(0).random((3, 256))

    @njit(nogil=True)
    def alone(rotated, rows, repeats, weights):  # pragma: no cover - compiled by numba
        for i in range(repeats):
            x, y, z = points[0, i & 255], points[1, i & 255], points[2, i & 255]
            if rotated:
                kernels.store_rotated_hemisphere(x, y, z, rows, i & 31, weights)
            else:
                kernels.store_hemisphere_orbit(x, y, z, rows, i & 31)

    rows: dict[str, tuple[float, Callable[[], object]]] = {}  # per orbit: (orbits a call, the call)
    m = n // count
    for dtype in (np.float32, np.float64):
        name = np.dtype(dtype).name
        stage = blocks.empty_rows(32 * count, np.dtype(dtype)).reshape(32, 3 * count)
        limit = fills(n, dtype)
        rows[f"write limit, out= ({name})"] = (m, limit["numba prange, non-temporal", "out="])
        rows[f"write limit, fresh ({name})"] = (m, limit["numba prange", "fresh"])
        for label, frame_basis in (("hemisphere", None), ("about (1,1,1)", basis)):
            weights = kernels.rotated_weights(basis, count)
            rows[f"{label}: its store alone, in L1 ({name})"] = (
                2**16,
                partial(alone, frame_basis is not None, stage, 2**16, weights),
            )
            kind = kernels._HEMISPHERE if frame_basis is None else kernels._HEMISPHERE_ROTATED
            kernel = kernels._fill_kernel(kernels._RANDOM, 0, kind, False)
            kernel_weights = kernels._NO_WEIGHTS if frame_basis is None else weights
            normal = kernels._NO_NORMAL if frame_basis is None else np.ascontiguousarray(basis[2])
            for size in (512, 1536):  # the kernel's own dispatcher, 10 calls a turn: no Python around it
                out = np.empty((size, 3 * count), dtype)
                state = kernels.RandomPoints(seed, 0, size).part_input(0)
                arguments = (state, 0, size, kernel_weights, normal, out, np.empty((0, 3), dtype), 0)
                rows[f"{label}: kernel, {size} orbits ({name})"] = (10 * size, partial(_repeat, kernel, arguments))
            touched = np.full((m * count, 3), 0.5, dtype)
            rows[f"{label}: kernel, out= ({name})"] = (
                m,
                partial(
                    kernels.fill_orbits, kernels.RandomPoints(seed, 0, m), "equal_area", count, frame_basis, touched
                ),
            )
            rows[f"{label}: kernel, fresh ({name})"] = (
                m,
                lambda b=frame_basis, d=dtype: kernels.fill_orbits(
                    kernels.RandomPoints(seed, 0, m), "equal_area", count, b, blocks.empty_rows(m * count, np.dtype(d))
                ),
            )
    for _, call in rows.values():
        call()
    times: dict[str, list[float]] = {key: [] for key in rows}
    keys = list(rows)
    for r in range(rounds):
        for key in keys[r % len(keys) :] + keys[: r % len(keys)]:
            for _ in range(2):  # the call timed follows one of its own
                start = time.thread_time()
                rows[key][1]()
            times[key].append((time.thread_time() - start) / rows[key][0] * 1e9)
    print(f"kernel_cpu.py --bound: one thread, thread CPU ns per orbit of {count} directions (medians), "
          f"{rounds} interleaved rounds, n = {n}")  # fmt: skip
    for key in keys:
        if "1536 orbits" in key:
            small = statistics.median(times[key.replace("1536", "512")]) * 5120
            print(f"{key.replace(', 1536 orbits', ' in the cache'):60s} "
                  f"{(statistics.median(times[key]) * 15360 - small) / 10240:7.2f}")  # fmt: skip
        elif "512 orbits" not in key:
            print(f"{key:60s} {statistics.median(times[key]):7.2f}")


def _asm() -> None:
    import collections
    import os
    import re

    with tempfile.TemporaryDirectory() as cache:
        os.environ["NUMBA_CACHE_DIR"] = cache  # before numba is imported: read when it loads
        import numpy as np

        import symsphere
        from symsphere._testing import kernels

        for dtype in (np.float64, np.float32):
            symsphere.sample_hemisphere(48 * 100, rng=1, dtype=dtype, normal=(1.0, 1.0, 1.0))
        kernel = kernels._fill_kernel(kernels._RANDOM, 0, kernels._HEMISPHERE_ROTATED, False)
        for signature, text in kernel.inspect_asm().items():
            counts: collections.Counter[str] = collections.Counter()
            for op, operands in re.findall(
                r"^\s+(v(?:mul|add|sub|cvt|perm|shuf|xor)\w*|vbroadcastsd)\s+([^\n]*)", text, re.M
            ):
                width = next((r for r in ("zmm", "ymm", "xmm") if r in operands), "")
                counts[f"{op} {width}"] += 1
            print(f"rows {signature[5].dtype}: " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))


if __name__ == "__main__":
    sys.exit(main())
