"""numba's disk cache is dropped when a file that a cached kernel inlines changes."""

import os
import subprocess
import sys
import textwrap

import pytest

KERNEL = textwrap.dedent(
    """
    from numba import njit
    from symsphere._testing import numba_cache

    invalidate_if_changed = numba_cache.invalidate_if_changed
    import helper

    @njit(cache=True)
    def kernel(x):
        return helper.scale(x)

    invalidate_if_changed(kernel, [helper.__file__])
    print(kernel(2.0))
    """
)


def _run(folder, env):
    result = subprocess.run(
        [sys.executable, "-c", "import kernel"], cwd=folder, env=env, capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr
    return float(result.stdout.split()[-1])


@pytest.mark.parametrize("own_cache_dir", [False, True], ids=["next-to-source", "NUMBA_CACHE_DIR"])
def test_editing_an_inlined_file_drops_the_cached_kernel(tmp_path, own_cache_dir):
    source = tmp_path / "src"
    source.mkdir()
    (source / "kernel.py").write_text(KERNEL)
    helper = source / "helper.py"
    helper.write_text(
        "from numba.extending import register_jitable\n\n@register_jitable\ndef scale(x):\n    return 3 * x\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["PYTHONPATH"] = os.pathsep.join([str(source), *sys.path])
    if own_cache_dir:
        env["NUMBA_CACHE_DIR"] = str(tmp_path / "cache")
    assert _run(source, env) == 6.0
    assert _run(source, env) == 6.0  # from the cache
    cached = list((tmp_path / "cache").rglob("kernel.*.nbi")) if own_cache_dir else list(source.rglob("kernel.*.nbi"))
    assert cached, "numba did not cache the kernel where expected"
    helper.write_text(helper.read_text().replace("3 * x", "5 * x"))
    assert _run(source, env) == 10.0  # numba alone would still return 6.0 (kernel.py did not change)


def test_dependencies_are_derived_from_the_kernel_modules_imports():
    # Independent reference: the files whose functions or tables the sampling kernels inline, by reading the code.
    from pathlib import Path

    import symsphere
    from symsphere._testing import kernels, numba_cache

    paths = {Path(p).resolve() for p in numba_cache.kernel_dependencies(kernels.fill_orbits)}
    names = {p.name for p in paths}
    assert {"_kernels.py", "_triangle.py", "symmetry.py"} <= names  # _triangle.py: the maps onto T0
    # consumers are not dependencies: the sampling module, the package's own __init__ (warps/__init__.py,
    # which the kernels import the maps through, is one)
    assert "sampling.py" not in names and Path(symsphere.__file__).resolve() not in paths


def test_importing_the_kernels_touches_no_cache(tmp_path):
    # No side effect at import: the digest stamp is written only when a kernel is first run.  (numba itself
    # creates the empty cache directory when a cache=True kernel is defined: directories are not counted.)
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["NUMBA_CACHE_DIR"] = str(tmp_path)
    code = "import symsphere, symsphere._testing; import pathlib, sys; print(sum(p.is_file() for p in pathlib.Path(sys.argv[1]).rglob('*')))"
    result = subprocess.run(
        [sys.executable, "-c", code, str(tmp_path)], env=env, capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split()[-1] == "0"
    code = "import symsphere, pathlib, sys; symsphere.sample_sphere(48); print(len(list(pathlib.Path(sys.argv[1]).rglob('*.deps-sha256'))))"
    result = subprocess.run(
        [sys.executable, "-c", code, str(tmp_path)], env=env, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    assert int(result.stdout.split()[-1]) >= 1
