"""Which of numpy's elementary functions give other bits when its SIMD dispatch is limited.

numpy picks a ufunc's loop at run time by CPU (docs/explanation/testing.md, "Comparing two implementations").
This runs the same ufuncs on the same 10**6 random arguments in two new processes, one with numpy's
dispatch as it is and one with ``NPY_DISABLE_CPU_FEATURES`` set, and prints for each ufunc and dtype
the fraction of results whose bits differ: whether ``NPY_DISABLE_CPU_FEATURES`` makes this machine run
other code, as when the suite is run as an AVX2 machine (docs/results/test-times.md).

    python scripts/numpy_simd_paths.py                                  # X86_V4 AVX512_ICL AVX512_SPR off
    python scripts/numpy_simd_paths.py --disable "X86_V3 X86_V4 AVX512_ICL AVX512_SPR"
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np

UFUNCS = ("sin", "cos", "exp", "expm1", "log", "arctan", "arctan2", "tanh", "sqrt")

CHILD = """
import sys
import numpy as np
x = np.random.default_rng(1).uniform(-10.0, 10.0, 10**6)
out = {}
for dtype in (np.float64, np.float32):
    y = x.astype(dtype)
    for name in sys.argv[2:]:
        f = getattr(np, name)
        if name == "arctan2":
            out[name + "_" + dtype.__name__] = f(y, y[::-1].copy())
        elif name in ("log", "sqrt"):
            out[name + "_" + dtype.__name__] = f(np.abs(y))
        else:
            out[name + "_" + dtype.__name__] = f(y)
np.savez(sys.argv[1], **out)
"""


def _results(path: str, env: dict[str, str]) -> dict[str, np.ndarray]:
    subprocess.run([sys.executable, "-c", CHILD, path, *UFUNCS], env=env, check=True)
    with np.load(path) as data:
        return {key: data[key] for key in data.files}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--disable", default="X86_V4 AVX512_ICL AVX512_SPR", help="NPY_DISABLE_CPU_FEATURES")
    args = parser.parse_args()
    base = {key: value for key, value in os.environ.items() if key != "NPY_DISABLE_CPU_FEATURES"}
    with tempfile.TemporaryDirectory() as directory:
        full = _results(os.path.join(directory, "full.npz"), base)
        limited = _results(os.path.join(directory, "limited.npz"), dict(base, NPY_DISABLE_CPU_FEATURES=args.disable))
    print(f"NPY_DISABLE_CPU_FEATURES={args.disable!r}: results with other bits, of 10**6 arguments")
    for key, values in full.items():
        print(f"  {key:16s} {np.mean(values != limited[key]):8.2%}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
