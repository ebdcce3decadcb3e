"""Bit for bit: the sampling outputs of this checkout against a base revision's, row by row.

For a change of a kernel that should not change its outputs (or only some rows): each revision, in its
own process (the base from a temporary git worktree, ``PYTHONPATH`` at its ``src``, its own numba
cache), samples the same cases; reported is, per case, how many rows differ and by how much.

Cases: ``sample_hemisphere`` about 12 random normals (random points, 24 * 40000 + 7 rows: a cut last
orbit), about 4 fixed normals with unscrambled Sobol' points (on the edges of the square: rows on the
equator), stratified points and the paper's maps; ``iter_hemisphere`` about a normal;
``sample_sphere`` and ``sample_hemisphere`` without one; float32 and float64.

Usage::

    python benchmarks/compare_outputs.py --base 5d0170b
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def dump(path):
    from scipy.stats import qmc

    import symsphere as ss

    out = {}
    rng = np.random.default_rng(5)
    for dtype in (np.float32, np.float64):
        name = np.dtype(dtype).name
        for i in range(12):
            normal = rng.normal(size=3)
            out[f"random normal {i} ({name})"] = ss.sample_hemisphere(24 * 40000 + 7, normal=normal, rng=i, dtype=dtype)
        for normal in ([0, 0, 1.0], [0.3, -0.5, 0.8], [1, 1, 1.0], [0, 1e-9, 1]):
            sobol = qmc.Sobol(2, scramble=False)
            out[f"sobol {normal} ({name})"] = ss.sample_hemisphere(24 * 1024, normal=normal, points=sobol, dtype=dtype)
            out[f"stratified {normal} ({name})"] = ss.sample_hemisphere(
                24 * 1024, normal=normal, points="stratified", rng=1, dtype=dtype
            )
            for method in ("paper1", "paper2"):
                out[f"{method} sobol {normal} ({name})"] = ss.sample_hemisphere(
                    24 * 1024, normal=normal, method=method, points=qmc.Sobol(2, scramble=False), dtype=dtype
                )
        blocks = ss.iter_hemisphere(24 * 4096, chunk=24 * 1000, normal=[0.2, 0.1, -1], rng=3, dtype=dtype)
        out[f"iter_hemisphere ({name})"] = np.concatenate(list(blocks))
        out[f"sample_sphere ({name})"] = ss.sample_sphere(48 * 20000 + 5, rng=3, dtype=dtype)
        out[f"sample_hemisphere, no normal ({name})"] = ss.sample_hemisphere(24 * 20000 + 5, rng=3, dtype=dtype)
    np.savez(path, **out)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--base", default="HEAD", help="git revision to compare against (default: %(default)s)")
    parser.add_argument("--dump", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.dump:
        return dump(args.dump)
    with tempfile.TemporaryDirectory(prefix="symsphere-outputs-") as scratch:
        scratch = Path(scratch)
        tree = scratch / "base"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(tree), args.base], check=True)
        try:
            for name, source in (("base", tree), ("new", ROOT)):
                env = dict(os.environ, PYTHONPATH=str(source / "src"), NUMBA_CACHE_DIR=str(scratch / f"numba-{name}"))
                command = [sys.executable, str(Path(__file__).resolve()), "--dump", str(scratch / f"{name}.npz")]
                subprocess.run(command, env=env, check=True, cwd=source)
            base, new = np.load(scratch / "base.npz"), np.load(scratch / "new.npz")
            rows = 0
            print(f"compare_outputs.py: base {args.base} against this checkout\n")
            print("| case | rows | rows that differ | largest difference |\n|---|---:|---:|---:|")
            for key in base.files:
                a, b = base[key], new[key]
                differ = ~np.all(a == b, axis=1)
                rows += len(a)
                largest = float(np.max(np.abs(a[differ].astype(np.float64) - b[differ]), initial=0.0))
                print(f"| {key} | {len(a)} | {int(differ.sum())} | {largest:.2g} |")
            print(f"\n{rows} rows compared")
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(tree)], check=False)
    return None


if __name__ == "__main__":
    main()
