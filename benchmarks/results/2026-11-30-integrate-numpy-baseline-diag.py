import sys, time, statistics, os, json
import numpy as np
mode = sys.argv[1]
if "early" in mode:
    import numba; numba.get_num_threads()   # what bench_integrate.py's main() did before any kernel
import symsphere
from symsphere.integrands import INTEGRANDS
A = np.array([0.7, -0.4, 0.5])
n = 48 * 2**20
lam = lambda w: np.exp(w @ A)
suite = INTEGRANDS["exp"].f
def t(f):
    s = time.perf_counter(); symsphere.integrate(f, n=n, rng=1); return time.perf_counter() - s
symsphere.integrate(lam, n=48*4096, rng=1)
if "inter" in mode:
    symsphere.integrate(INTEGRANDS["exp"], n=48*4096, rng=1)
res = {"lambda": [], "suite": []}
for r in range(2):
    for k, f in (("lambda", lam), ("suite", suite)):
        res[k].append(t(f))
        if "inter" in mode:
            t(INTEGRANDS["exp"])
print(json.dumps(dict(mode=mode, load=os.getloadavg()[0], **{k: statistics.median(v) for k, v in res.items()})))
