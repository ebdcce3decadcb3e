"""The common part of the NaN/inf scans (scan_*.py): each scan's counts timed into one record, the record as JSON."""

from __future__ import annotations

import json
import time


def timed(record, name, scan):
    """Run ``scan()`` (a dict of counts), add its seconds, store it as ``record[name]`` and print it."""
    start = time.perf_counter()
    counts = scan()
    counts["seconds"] = round(time.perf_counter() - start, 1)
    record[name] = counts
    print(name, counts, flush=True)


def write(path, record):
    """Write *record* as indented JSON to *path* (nothing when *path* is None)."""
    if path:
        with open(path, "w", encoding="utf-8") as f:
            json.dump(record, f, indent=1)
            f.write("\n")
