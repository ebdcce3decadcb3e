"""The Mitsuba 3 tests: skipped with the reason where Mitsuba (or an LLVM for its JIT) is missing.

With ``SYMSPHERE_REQUIRE_MITSUBA=1`` (``.ci/run`` sets it) a missing Mitsuba is an error, not a skip,
so that CI cannot pass without running them.  Every test runs in ``llvm_ad_rgb``; the ``jit_variant``
fixture adds ``cuda_ad_rgb`` where a CUDA device is present (skipped with the reason otherwise).
"""

from __future__ import annotations

import os

import pytest

REQUIRED = os.environ.get("SYMSPHERE_REQUIRE_MITSUBA") == "1"


def _probe() -> str | None:
    """None if Mitsuba's llvm_ad_rgb variant runs a kernel here, else the reason it does not."""
    try:
        import drjit as dr
        import mitsuba as mi
    except ImportError as error:
        return f"Mitsuba 3 is not installed ({error}); pip install -e '.[mitsuba]'"
    try:
        mi.set_variant("llvm_ad_rgb")
        dr.eval(dr.arange(mi.Float, 4) * 2)
    except Exception as error:
        return f"Mitsuba's llvm_ad_rgb variant does not run ({error}); Debian: apt-get install libllvm19"
    return None


REASON = _probe()
if REASON is not None and REQUIRED:
    raise RuntimeError(f"SYMSPHERE_REQUIRE_MITSUBA=1 but the Mitsuba tests cannot run: {REASON}")


def _cuda_reason() -> str | None:
    if REASON is not None:
        return REASON
    import drjit as dr

    return None if dr.has_backend(dr.JitBackend.CUDA) else "no CUDA device: the cuda_ad_rgb variant is not tested"


@pytest.fixture(autouse=True)
def _mitsuba_available():
    if REASON is not None:
        pytest.skip(REASON)


@pytest.fixture
def llvm():
    """Mitsuba in the llvm_ad_rgb variant."""
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    return mi


@pytest.fixture(params=["llvm_ad_rgb", "cuda_ad_rgb"])
def jit_variant(request):
    """Mitsuba in each JIT variant that runs here (cuda_ad_rgb only with a CUDA device)."""
    if request.param.startswith("cuda"):
        reason = _cuda_reason()
        if reason is not None:
            pytest.skip(reason)
    import mitsuba as mi

    mi.set_variant(request.param)
    return mi
