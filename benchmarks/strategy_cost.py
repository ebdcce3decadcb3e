"""What symsphere_path's ``symmetric_cosine`` · Sobol' direction costs per path against the BSDF's own sample.

    .venv/bin/python benchmarks/strategy_cost.py --scenes veach_mis textured --rounds 21

Two measurements, llvm_ad_rgb, each on CPU time (``time.process_time``: Dr.Jit's threads included), which
is steadier than wall-clock seconds on a shared machine:

``parts``
    the direction of :meth:`_local_direction` and pieces of it alone, on 2^20 lanes x 8 vertices in one
    kernel: ns of CPU per lane and vertex (the per-vertex keys: two splitmix64 finalisers and the offset;
    + the Owen-scrambled Sobol' point: two more finalisers, three Laine-Karras permutations; the whole
    direction: + the cosine wedge map and the orbit member; Mitsuba's cosine warp for scale).
``render``
    interleaved rounds (alternating order) of 128 x 128 renders, 32 spp, ``max_depth`` 8, of the scenes of
    ``_mitsuba_light_scenes.py`` with ``emitter_sampling='solid_angle'``; the median CPU seconds, as paths/s
    relative to ``strategy='bsdf'``, of: ``symmetric_cosine`` · Sobol' (this checkout; with ``--base REV``
    also that revision's ``_integrator.py``, in the same process), and two rewritten copies of its direction
    registered here only: ``one mix64 per vertex`` (the same Owen-scrambled Sobol' stream keyed by one 64-bit
    finaliser per vertex and 32-bit hashes: other bits, not the shipped stream) and ``i.i.d. cosine, hashed``
    (a 32-bit hash and Mitsuba's cosine warp per lane: the cheapest direction that replaces the BSDF's).
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import cpu_name, cpu_snapshot, others_cpu
from _mitsuba_light_scenes import LIGHT_SCENES, light_scene

ROOT = Path(__file__).resolve().parents[1]


def _hash32(dr, mi, x):
    """A 32-bit integer finaliser (two multiplies; Wellons' lowbias32 constants)."""
    x = mi.UInt32(x)
    x = (x ^ (x >> 16)) * 0x7FEB352D
    x = (x ^ (x >> 15)) * 0x846CA68B
    return x ^ (x >> 16)


def _directions(dr, mi):
    """The rewritten directions: name -> _local_direction(self, key, s, depth) (symmetric_cosine, Sobol')."""
    from symsphere._constants import INV_PI
    from symsphere.mitsuba import _random as R
    from symsphere.mitsuba import _warps as W

    def one_mix64(self, key, s, depth):
        n = self.group_size
        group = s // n
        vertex_key = R.mix64(key ^ (mi.UInt64(depth) * R.GOLDEN + n))
        s0, s1 = mi.UInt32(vertex_key), mi.UInt32(vertex_key >> 32)
        s2 = _hash32(dr, mi, s0 ^ 0x68E31DA4)
        member = s - n * group + dr.mul_hi(_hash32(dr, mi, s1 ^ ((group + 1) * 0x9E3779B9)), mi.UInt32(n))
        member = dr.select(member >= n, member - n, member)
        i = R._scramble(mi.UInt32(group), s0)
        r = i
        for shift, mask in R._SUPERSET_STEPS:
            r = r ^ ((r >> shift) & mask)
        u = R.fraction(R._reverse32(R._laine_karras(i, s1)))
        v = R.fraction(R._reverse32(R._laine_karras(r, s2)))
        x, y, z = W.orbit_member(*W.cosine_wedge_point(u, v), member, members=8)
        return mi.Vector3f(x, y, z), z * INV_PI

    def iid_cosine(self, key, s, depth):
        h = _hash32(dr, mi, mi.UInt32(key) ^ (depth * 0x9E3779B9) ^ (s * 0x85EBCA6B))
        wo = mi.warp.square_to_cosine_hemisphere(mi.Point2f(R.fraction(h), R.fraction(_hash32(dr, mi, h ^ 0x1234567))))
        return wo, wo.z * INV_PI

    return {"one mix64 per vertex": one_mix64, "i.i.d. cosine, hashed": iid_cosine}


def _methods(module, **overrides):
    methods = {k: v for k, v in vars(module._PathMethods).items() if k not in ("__dict__", "__weakref__")}
    return {**methods, **overrides}


def _base_module(rev):
    """symsphere.mitsuba._integrator as of git revision *rev*, loaded beside this checkout's."""
    source = subprocess.run(["git", "-C", str(ROOT), "show", f"{rev}:src/symsphere/mitsuba/_integrator.py"],
                            check=True, capture_output=True, text=True).stdout  # fmt: skip
    path = Path(tempfile.mkdtemp()) / "_integrator_base.py"
    path.write_text(source, encoding="utf-8")
    spec = importlib.util.spec_from_file_location("symsphere.mitsuba._integrator_base", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def parts(dr, mi, rounds):
    from symsphere._constants import INV_PI
    from symsphere.mitsuba import _integrator as I
    from symsphere.mitsuba import _random as R
    from symsphere.mitsuba import _warps as W

    lanes = 1 << 20
    index = dr.arange(mi.UInt32, lanes)
    key, s = R.pixel_key(mi.UInt64(7), index // 32), index % 32
    dr.eval(key, s)

    class Strategy:
        group_size, points, strategy, method = 8, "sobol", "symmetric_cosine", "equal_area"

    def keys(self, key, s, depth):
        group = s // 8
        vertex_key = R.mix64(key ^ (mi.UInt64(depth) * R.GOLDEN + 8))
        member = s - 8 * group + R.below(R.mix64(vertex_key ^ ((mi.UInt64(group) + 1) * R.ODD)), 8)
        x = R.fraction(mi.UInt32(vertex_key)) + mi.Float(member)
        return mi.Vector3f(x, x, x), x

    def keys_sobol(self, key, s, depth):
        x = keys(self, key, s, depth)[1]
        fu, fv = R.owen_sobol2(s // 8, R.mix64(key ^ (mi.UInt64(depth) * R.GOLDEN + 8)))
        x = x + R.fraction(fu) + R.fraction(fv)
        return mi.Vector3f(x, x, x), x

    def wedge_orbit(self, key, s, depth):
        u = mi.Float(s) * 0.03 + mi.Float(depth) * 0.001
        x, y, z = W.orbit_member(*W.cosine_wedge_point(u, 0.7 * u), (s + depth) & 7, members=8)
        return mi.Vector3f(x, y, z), z * INV_PI

    def mitsuba_cosine(self, key, s, depth):
        u = mi.Float(s) * 0.03 + mi.Float(depth) * 0.001
        wo = mi.warp.square_to_cosine_hemisphere(mi.Point2f(u, 0.7 * u))
        return wo, wo.z * INV_PI

    cases = {"keys (2 mix64, offset)": keys, "keys + Owen-scrambled Sobol' point": keys_sobol,
             "the direction (_local_direction)": I._PathMethods._local_direction,
             "cosine wedge map + orbit member alone": wedge_orbit, "Mitsuba's cosine warp alone": mitsuba_cosine}  # fmt: skip
    print(f"per lane and vertex, ns of CPU (2^20 lanes x 8 vertices, median of {rounds})")
    for name, f in cases.items():
        times = []
        for _ in range(rounds):
            acc = mi.Float(0.0)
            for depth in range(8):
                wo, pdf = f(Strategy(), key, s, mi.UInt32(depth) + 0 * s)
                acc += wo.x + 2 * wo.y + 3 * wo.z + pdf
            start = time.process_time()
            dr.eval(acc)
            dr.sync_thread()
            times.append(time.process_time() - start)
        print(f"  {name:<40} {statistics.median(times) / (8 * lanes) * 1e9:6.2f}")


def render(dr, mi, args):
    from symsphere.mitsuba import _integrator as I

    base_class = mi.ad.integrators.common.RBIntegrator
    classes = {"bsdf": ("bsdf", _methods(I)), "symmetric_cosine · Sobol'": ("symmetric_cosine", _methods(I))}
    if args.base:
        classes[f"symmetric_cosine · Sobol' at {args.base}"] = ("symmetric_cosine", _methods(_base_module(args.base)))
    for name, direction in _directions(dr, mi).items() if not args.shipped else ():
        classes[name] = ("symmetric_cosine", _methods(I, _local_direction=direction))
    integrators = {}
    for number, (name, (strategy, methods)) in enumerate(classes.items()):
        cls = type("SymspherePathCopy", (base_class,), methods)
        mi.register_integrator(f"strategy_cost_{number}", lambda props, c=cls: c(props))
        spec = {"type": f"strategy_cost_{number}", "strategy": strategy, "max_depth": 8, "rr_depth": 5,
                "emitter_sampling": "solid_angle"}  # fmt: skip
        if strategy != "bsdf":
            spec["points"] = "sobol"
        integrators[name] = mi.load_dict(spec)
    workdir = tempfile.mkdtemp()
    for scene_name in args.scenes:
        scene = light_scene(mi, scene_name, 128, 128, workdir)
        for integrator in integrators.values():  # compile
            mi.render(scene, integrator=integrator, spp=32, seed=0)
        cpu = {name: [] for name in integrators}
        before, start = cpu_snapshot(), time.perf_counter()
        for r in range(args.rounds):
            for name in list(integrators) if r % 2 == 0 else list(integrators)[::-1]:
                t0 = time.process_time()
                dr.eval(mi.render(scene, integrator=integrators[name], spp=32, seed=r + 1))
                dr.sync_thread()
                cpu[name].append(time.process_time() - t0)
        load = others_cpu(before, cpu_snapshot(), time.perf_counter() - start)
        share = "?" if load is None else f"{load['share_of_all_cpus']:.0%}"
        print(f"{scene_name}: paths/s (CPU time) x bsdf, median of {args.rounds} rounds; others' CPU share {share}")
        ref = statistics.median(cpu["bsdf"])
        for name, seconds in cpu.items():
            print(f"  {name:<44} {statistics.median(seconds):.4f} s  x{ref / statistics.median(seconds):.3f}")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenes", nargs="+", default=["veach_mis", "textured"], choices=LIGHT_SCENES)
    parser.add_argument("--rounds", type=int, default=21, help="interleaved rounds (default 21)")
    parser.add_argument("--base", metavar="REV", help="also the integrator of git revision REV (e.g. main)")
    parser.add_argument("--shipped", action="store_true", help="render: leave out the two rewritten directions")
    parser.add_argument("--only", choices=("parts", "render"), help="one of the two measurements")
    args = parser.parse_args(argv)
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    import symsphere.mitsuba  # noqa: F401 - registers symsphere_path

    print(f"{cpu_name()}, {os.cpu_count()} CPUs, load {os.getloadavg()[0]:.2f}, Mitsuba {mi.__version__}")
    if args.only != "render":
        parts(dr, mi, args.rounds)
    if args.only != "parts":
        render(dr, mi, args)


if __name__ == "__main__":
    main()
