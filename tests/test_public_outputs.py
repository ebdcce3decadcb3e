"""The public outputs at fixed seeds, pinned: a refactor must not change a single bit of them.

Every public sampler (the scheme in each map x point set x dtype, about a normal, in chunks), every
warp of :data:`symsphere.warps.WARPS` (forward, pdf, inverse on one grid), every peer, ``integrate``
(Python and compiled integrands), the numba renderer's image for every sampler and, where Mitsuba
runs, ``symsphere_path`` for every strategy: recorded in ``tests/data/public_outputs.npz`` by

    python tests/test_public_outputs.py --record

and compared here.  A change that *means* to change an output re-records the file in the same commit
and says which outputs changed and why.  A new spelling of a recorded output (the renderer's
``strategy`` x ``points`` x ``method`` for its deprecated ``sampler=`` names) is a case of its own,
compared with the recording of the old spelling (:data:`SAME_AS`): both must give the same bits.

Bits are a promise of the machine they were recorded on: numpy's SIMD loops and glibc's libm
variants give other last bits for some arguments on other CPUs (``scripts/numpy_simd_paths.py``).  So
the comparison is exact where the machine's fingerprint (numpy's and LLVM's CPU features, numpy,
numba and Mitsuba versions) equals the recorded one; elsewhere the array outputs of sampling, warps
and integration must agree within a few ulps propagated (rtol 1e-12 in float64, 1e-5 in float32,
atol the same), and the renders, whose paths branch on the last bit (a ray just missing an edge,
Russian roulette), are compared only on the recording machine.
"""

from __future__ import annotations

import hashlib
import json
import platform
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

DATA = Path(__file__).parent / "data" / "public_outputs.npz"
RENDERS = ("render/", "mitsuba/")  # the cases compared only on the recording machine


def fingerprint() -> str:
    """The software and CPU features that decide the last bits of the outputs."""
    import llvmlite.binding as llvm
    import numba

    try:
        from numpy._core._multiarray_umath import __cpu_features__ as numpy_features
    except ImportError:  # pragma: no cover - numpy < 2
        numpy_features = {}
    try:
        import mitsuba

        mitsuba_version = mitsuba.__version__
    except ImportError:
        mitsuba_version = None
    facts = {
        "machine": platform.machine(),
        "numpy": np.__version__,
        "numba": numba.__version__,
        "mitsuba": mitsuba_version,
        "numpy_cpu": sorted(name for name, on in numpy_features.items() if on),
        "llvm_cpu": llvm.get_host_cpu_name(),
        "llvm_features": llvm.get_host_cpu_features().flatten(),
    }
    return json.dumps(facts, sort_keys=True)


def _unit(d: np.ndarray) -> np.ndarray:
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def _sampling_cases() -> dict[str, Callable[[], np.ndarray]]:
    import symsphere as ss

    cases: dict[str, Callable[[], np.ndarray]] = {}
    for method in ("equal_area", "paper1", "paper2"):
        for points in ("random", "stratified", "sobol", "halton"):
            for dtype in (np.float64, np.float32):
                tag = f"{method}/{points}/{np.dtype(dtype).name}"
                cases[f"sample_sphere/{tag}"] = lambda m=method, p=points, t=dtype: ss.sample_sphere(
                    768, method=m, points=p, rng=7, dtype=t
                )
                cases[f"sample_hemisphere/{tag}"] = lambda m=method, p=points, t=dtype: ss.sample_hemisphere(
                    384, method=m, points=p, rng=7, dtype=t
                )
                cases[f"sample_hemisphere_normal/{tag}"] = lambda m=method, p=points, t=dtype: ss.sample_hemisphere(
                    384, method=m, points=p, rng=7, dtype=t, normal=[0.0, 0.6, 0.8]
                )
    cases["sample_sphere/cut_orbit"] = lambda: ss.sample_sphere(101, rng=3)
    cases["iter_sphere/chunks"] = lambda: np.concatenate([c.copy() for c in ss.iter_sphere(480, chunk=96, rng=5)])
    cases["iter_hemisphere/normal"] = lambda: np.concatenate(
        [c.copy() for c in ss.iter_hemisphere(240, chunk=48, rng=5, normal=[1.0, 0.0, 0.0])]
    )

    def directions() -> np.ndarray:
        return np.random.default_rng(11).normal(size=(96, 3))

    for method in ("equal_area", "paper1", "paper2"):
        cases[f"sphere_pdf/{method}"] = lambda m=method: ss.sphere_pdf(_unit(directions()), m)
        cases[f"hemisphere_pdf/{method}"] = lambda m=method: ss.hemisphere_pdf(np.abs(_unit(directions())), m)
    return cases


def _warp_cases() -> dict[str, Callable[[], np.ndarray]]:
    from symsphere.warps import WARPS

    uv = np.random.default_rng(2).random((64, 2))
    cases: dict[str, Callable[[], np.ndarray]] = {}
    for name, warp in sorted(WARPS.items()):
        for dtype in (np.float64, np.float32):
            tag = f"warp/{name}/{np.dtype(dtype).name}"
            cases[f"{tag}/forward"] = lambda w=warp, t=dtype: w.forward(uv.astype(t))
            cases[f"{tag}/pdf"] = lambda w=warp, t=dtype: w.pdf(w.forward(uv.astype(t)))
            cases[f"{tag}/inverse"] = lambda w=warp, t=dtype: w.inverse(w.forward(uv.astype(t)))
    return cases


def _peer_cases() -> dict[str, Callable[[], np.ndarray]]:
    from symsphere.peers import PEERS

    cases: dict[str, Callable[[], np.ndarray]] = {}
    for name, peer in sorted(PEERS.items()):
        n = 86 if name.startswith("lebedev") else 96 * peer.multiple  # 86: a Lebedev rule's size
        cases[f"peer/{name}/random"] = lambda p=peer, n=n: p.sample(n, rng=4)
        if peer.is_map:
            cases[f"peer/{name}/sobol"] = lambda p=peer: p.sample(128 * p.multiple, rng=4, points="sobol")
    return cases


def _integrate_cases() -> dict[str, Callable[[], np.ndarray]]:
    import symsphere as ss
    from symsphere.integrands import INTEGRANDS

    def result(r: ss.IntegrationResult) -> np.ndarray:
        return np.array([r.integral, r.standard_error, r.n_evaluations], dtype=np.float64).ravel()

    cases: dict[str, Callable[[], np.ndarray]] = {}
    for name in ("exp", "cap", "phong", "shifted_cubic4"):
        g = INTEGRANDS[name]
        domain = g.domain
        for points in ("random", "sobol"):
            cases[f"integrate/{name}/{points}"] = lambda g=g, d=domain, p=points: result(
                ss.integrate(g, domain=d, n=48 * 64, points=p, rng=9)
            )
    cases["integrate/python_f"] = lambda: result(
        ss.integrate(lambda w: np.exp(w[:, 0]) * w[:, 2] ** 2, n=48 * 64, rng=9)
    )
    cases["integrate/normal"] = lambda: result(
        ss.integrate(lambda w: w[:, 0] ** 2, domain="hemisphere", normal=[0.0, 0.6, 0.8], n=24 * 64, rng=9)
    )
    cases["integrate/rtol"] = lambda: result(ss.integrate(lambda w: np.exp(w[:, 1]), rtol=1e-3, rng=9))
    return cases


# The renderer's words for its deprecated sampler names (the recordings' names): an independent table,
# not the library's, so that a wrong mapping there fails here.
_WORDS = {
    "symmetric": {"strategy": "symmetric", "points": "random"},
    "symmetric_sobol": {"strategy": "symmetric", "points": "sobol"},
    "equal_area": {"strategy": "orbit", "method": "equal_area"},
    "paper1": {"strategy": "orbit", "method": "paper1"},
    "paper2": {"strategy": "orbit", "method": "paper2"},
    "uniform": {"strategy": "uniform"},
    "cosine": {"strategy": "cosine"},
    "symmetric_cosine": {"strategy": "symmetric_cosine", "points": "random"},
    "symmetric_cosine_sobol": {"strategy": "symmetric_cosine", "points": "sobol"},
    "symmetric_sobol_interlaced2": {"strategy": "symmetric", "points": "sobol_interlaced2"},
    "symmetric_sobol_interlaced3": {"strategy": "symmetric", "points": "sobol_interlaced3"},
    "symmetric_cosine_sobol_interlaced2": {"strategy": "symmetric_cosine", "points": "sobol_interlaced2"},
    "symmetric_cosine_sobol_interlaced3": {"strategy": "symmetric_cosine", "points": "sobol_interlaced3"},
}
SAME_AS: dict[str, str] = {}
"""case of a new spelling -> the recorded case of the old one, which it must equal bit for bit."""


def _render_cases() -> dict[str, Callable[[], np.ndarray]]:
    from symsphere.render import SAMPLERS, render

    def old(scene: str, sampler: str) -> np.ndarray:
        with pytest.deprecated_call(match=f"sampler={sampler!r} is deprecated"):
            return np.asarray(render(scene, width=12, height=9, spp=48, sampler=sampler, seed=3, threads=2).image)

    def new(scene: str, words: dict[str, str]) -> np.ndarray:
        return np.asarray(render(scene, width=12, height=9, spp=48, seed=3, threads=2, **words).image)

    cases: dict[str, Callable[[], np.ndarray]] = {}
    assert set(SAMPLERS) == set(_WORDS)
    for sampler in SAMPLERS:
        cases[f"render/cornell/{sampler}"] = lambda s=sampler: old("cornell", s)
        spelling = ",".join(f"{k}={v}" for k, v in _WORDS[sampler].items())
        cases[f"render/cornell/{spelling}"] = lambda s=sampler: new("cornell", _WORDS[s])
        SAME_AS[f"render/cornell/{spelling}"] = f"render/cornell/{sampler}"
    cases["render/translucent/symmetric"] = lambda: old("translucent", "symmetric")
    cases["render/translucent/strategy=symmetric,points=random"] = lambda: new("translucent", _WORDS["symmetric"])
    SAME_AS["render/translucent/strategy=symmetric,points=random"] = "render/translucent/symmetric"
    cases["render/cornell/default"] = lambda: np.asarray(
        render("cornell", width=12, height=9, spp=48, seed=3, threads=2).image
    )
    SAME_AS["render/cornell/default"] = "render/cornell/symmetric_sobol"  # the default: strategy symmetric, Sobol'
    return cases


def _mitsuba_cases() -> dict[str, Callable[[], np.ndarray]]:
    try:
        import mitsuba as mi

        mi.set_variant("llvm_ad_rgb")
        import symsphere.mitsuba as sm
    except Exception:
        return {}
    cases: dict[str, Callable[[], np.ndarray]] = {}
    for strategy in sm.STRATEGIES:
        for points in sm.POINTS if strategy != "bsdf" else ("random",):

            def run(s: str = strategy, p: str = points) -> np.ndarray:
                mi.set_variant("llvm_ad_rgb")
                scene = mi.load_file(str(sm.scene_path("cornell_box")), width=12, height=9)
                integrator = mi.load_dict({"type": "symsphere_path", "strategy": s, "points": p})
                return np.array(mi.render(scene, integrator=integrator, spp=48, seed=5))

            cases[f"mitsuba/cornell_box/{strategy}/{points}"] = run
    return cases


def cases() -> dict[str, Callable[[], np.ndarray]]:
    out: dict[str, Callable[[], np.ndarray]] = {}
    for group in (_sampling_cases, _warp_cases, _peer_cases, _integrate_cases, _render_cases, _mitsuba_cases):
        out.update(group())
    return out


def _digest(a: np.ndarray) -> str:
    a = np.ascontiguousarray(a)
    return hashlib.sha256(f"{a.dtype.str}{a.shape}".encode() + a.tobytes()).hexdigest()[:16]


def record() -> None:
    arrays = {name: np.asarray(make()) for name, make in cases().items() if name not in SAME_AS}
    DATA.parent.mkdir(exist_ok=True)
    np.savez_compressed(DATA, __fingerprint__=np.array(fingerprint()), **arrays)
    print(f"recorded {len(arrays)} outputs in {DATA}")


_RECORDED = np.load(DATA) if DATA.exists() else None
_CASES = cases()


def test_every_case_is_recorded_and_every_recording_has_a_case():
    assert _RECORDED is not None, f"{DATA} is missing: python {Path(__file__).name} --record"
    recorded = set(_RECORDED.files) - {"__fingerprint__"}
    mitsuba_absent = not any(name.startswith("mitsuba/") for name in _CASES)
    expected = {name for name in recorded if not (mitsuba_absent and name.startswith("mitsuba/"))}
    assert set(_CASES) - set(SAME_AS) == expected
    assert set(SAME_AS.values()) <= recorded


@pytest.mark.parametrize("name", sorted(_CASES))
def test_output_is_unchanged(name):
    recorded = SAME_AS.get(name, name)
    if _RECORDED is None or recorded not in _RECORDED.files:
        pytest.fail(f"{recorded} is not recorded: python tests/{Path(__file__).name} --record")
    expected = _RECORDED[recorded]
    got = np.asarray(_CASES[name]())
    assert got.dtype == expected.dtype and got.shape == expected.shape
    if str(_RECORDED["__fingerprint__"]) == fingerprint():
        assert _digest(got) == _digest(expected), f"{name}: the bits changed"
    elif name.startswith(RENDERS):
        pytest.skip("renders are pinned on the recording machine only (their paths branch on the last bit)")
    else:
        tol = 1e-5 if got.dtype == np.float32 else 1e-12
        np.testing.assert_allclose(got, expected, rtol=tol, atol=tol, equal_nan=False)


if __name__ == "__main__":
    if sys.argv[1:] == ["--record"]:
        record()
    else:
        sys.exit(f"usage: python {sys.argv[0]} --record")
