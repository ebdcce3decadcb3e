import importlib.util, inspect, sys, time, statistics, os, re
import numpy as np
import symsphere, symsphere._fused as F
from symsphere.integrands import INTEGRANDS
g = INTEGRANDS["exp"]
text = F._specialised_source(g.kernel.symsphere_source)
vsrc = inspect.getsource(F.vexp.py_func).replace('@njit(error_model="numpy", nogil=True)', '@njit(error_model="numpy", nogil=True, fastmath={"contract"})')
consts = "\n".join(f"{k} = {getattr(F, k)!r}" for k in ("_SHIFTER", "_LN2_HI", "_LN2_LO", "_INV_LN2"))
fm = text.replace("from symsphere._fused import vexp", "from symsphere._fused import _float_bits, _bits_float\n" + consts + "\n\n" + vsrc)
fm = fm.replace('nogil=True)\ndef kernel', 'nogil=True, fastmath={"contract"})\ndef kernel').replace('@njit(parallel=True, cache=True, error_model="numpy", nogil=True)', '@njit(parallel=True, cache=True, error_model="numpy", nogil=True, fastmath={"contract"})')
path = "/tmp/fused/fm/fm_kernel.py"; open(path, "w").write(fm)
spec = importlib.util.spec_from_file_location("fm_kernel", path); mod = importlib.util.module_from_spec(spec); sys.modules["fm_kernel"] = mod; spec.loader.exec_module(mod)
plain = F._specialised(g.kernel.symsphere_source)
orig = F._specialised
n = 48 * 2**20
def run(k):
    F._specialised = lambda text: k
    s = time.perf_counter(); r = symsphere.integrate(g, n=n, rng=1); return time.perf_counter() - s, r
for k in (plain, mod.chunk_statistics): run(k)
ts = {"plain": [], "contract": []}
for _ in range(5):
    for name, k in (("plain", plain), ("contract", mod.chunk_statistics)):
        t, r = run(k); ts[name].append(t); print(name, round(t, 3), r.integral, r.standard_error)
print({k: n / statistics.median(v) / 1e6 for k, v in ts.items()}, os.getloadavg())
asm = "\n".join(mod.chunk_statistics.inspect_asm().values())
print("fma ymm", len(re.findall(r"vfmadd\w*[^\n]*ymm", asm)))
