"""Which machine a benchmark ran on, and how busy it was while it timed: shared by the benchmark scripts."""

from __future__ import annotations

import os
import platform
import sys
import time

__all__ = ["cpu_name", "cpu_snapshot", "others_cpu", "run_header"]


def cpu_name():
    """The CPU model (from /proc/cpuinfo on Linux), else what the platform module knows."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as handle:
            for line in handle:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def cpu_snapshot():
    """(busy CPU-seconds of the machine, CPU-seconds of this process and its children), or None off Linux."""
    import resource

    try:
        with open("/proc/stat", encoding="utf-8") as handle:
            fields = [int(x) for x in handle.readline().split()[1:]]
    except (OSError, ValueError):
        return None
    idle = fields[3] + (fields[4] if len(fields) > 4 else 0)  # idle + iowait
    busy = (sum(fields[:8]) - idle) / os.sysconf("SC_CLK_TCK")  # user nice system idle iowait irq softirq steal
    ours = sum(
        usage.ru_utime + usage.ru_stime
        for usage in (resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN))
    )
    return busy, ours


def others_cpu(before, after, wall):
    """CPU-seconds that other processes used while the cases ran (machine busy time minus ours)."""
    if before is None or after is None:
        return None
    seconds = max((after[0] - before[0]) - (after[1] - before[1]), 0.0)
    return {"cpu_s": seconds, "wall_s": wall, "share_of_all_cpus": seconds / (wall * (os.cpu_count() or 1))}


def run_header():
    """What every results file starts with: the command, the CPU, the time, the load and the measured sources.

    The sources' hashes let ``tables.py`` say when a file predates a change of the code it measures.
    """
    from tables import source_hashes  # tables.py is the one home of the hashing

    return dict(
        command="python " + " ".join(sys.argv),
        cpu=cpu_name(),
        date=time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        load_average=list(os.getloadavg()),
        sources=source_hashes(),
    )
