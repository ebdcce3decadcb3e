"""Scale-out benchmark: distributed.integrate on a LocalCluster of 1 vs 2 worker processes.

Measures, in one run and as medians over repeats:
- wall time of ``symsphere.distributed.integrate`` with 1 and with 2 single-threaded
  worker processes (the same integrand, n and seed; results checked bit-identical),
  and the speed-up 1 -> 2 workers (target >= 1.8x on 2 cores);
- per-task overhead: the same n cut into many one-block tasks vs few large tasks;
- the single-process ``symsphere.integrate`` with numba's threads, for reference.

    python benchmarks/bench_distributed.py [--n-blocks 64] [--repeats 3]
"""

import argparse
import statistics
import time

import numpy as np

import symsphere
from symsphere import distributed
from symsphere.points import BLOCK

A = np.array([0.7, -0.4, 0.5])


def integrand(w):
    # a moderately expensive integrand, as real ones are: ~10 transcendental calls per direction
    s = w @ A
    return np.exp(s) * np.cos(3 * s) + np.log1p(w[:, 2] ** 2) + np.sin(w[:, 0] * w[:, 1])


def median_time(call, repeats):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        result = call()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n-blocks", type=int, default=64, help="blocks of 4096 orbits (default 64: 12.6M directions)")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    n = 48 * BLOCK * args.n_blocks
    kwargs = dict(n=n, rng=1)

    single_time, single = median_time(lambda: symsphere.integrate(integrand, **kwargs), args.repeats)
    rows = [("symsphere.integrate, 1 process (numba threads)", single_time, "")]
    times = {}
    for workers in (1, 2):
        client = distributed.local_client(workers)
        try:
            distributed.integrate(integrand, client=client, n=48 * BLOCK, rng=0)  # warm up: imports, numba cache
            for chunk_blocks, label in ((4, "4 blocks per task"), (1, "1 block per task")):
                elapsed, result = median_time(
                    lambda: distributed.integrate(integrand, client=client, chunk_blocks=chunk_blocks, **kwargs),
                    args.repeats,
                )
                assert result.integral == single.integral and result.standard_error == single.standard_error
                times[workers, chunk_blocks] = elapsed
                rows.append((f"distributed.integrate, {workers} worker(s), {label}", elapsed, "bit-identical"))
        finally:
            distributed.close_client(client)

    print(f"n = {n} directions ({args.n_blocks} blocks), median of {args.repeats}; symsphere {symsphere.__version__}\n")
    print("| run | seconds | Mdirections/s | result |")
    print("|---|---:|---:|---|")
    for label, seconds, note in rows:
        print(f"| {label} | {seconds:.3f} | {n / seconds / 1e6:.1f} | {note} |")
    speedup = times[1, 4] / times[2, 4]
    tasks_small, tasks_large = args.n_blocks, -(-args.n_blocks // 4)
    overhead = (times[2, 1] - times[2, 4]) / (tasks_small - tasks_large)
    print(f"\nspeed-up 1 -> 2 workers (4 blocks per task): {speedup:.2f}x (target >= 1.8x)")
    print(f"per-task overhead (2 workers, {tasks_small} vs {tasks_large} tasks): {overhead * 1e3:.1f} ms per task")


if __name__ == "__main__":
    main()
