"""The package type-checks: ``python -m mypy`` with the configuration of pyproject.toml.

``[tool.mypy]`` is strict and lists the files (``files = ["src/symsphere"]``),
so this runs exactly what a developer runs.  The cache is kept in pytest's
cache directory (git-ignored), so that reruns take a second or two (a cold
run about 15 s).
"""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_mypy_passes(request, tmp_path):
    pytest.importorskip("mypy", reason="mypy is in the 'test' extra")
    if not (ROOT / "pyproject.toml").is_file() or not (ROOT / "src" / "symsphere").is_dir():
        pytest.skip("needs the source tree (pyproject.toml and src/symsphere)")
    pytest_cache = getattr(request.config, "cache", None)  # None under -p no:cacheprovider
    cache = pytest_cache.mkdir("mypy") if pytest_cache is not None else tmp_path / "mypy-cache"
    result = subprocess.run(
        [sys.executable, "-m", "mypy", "--cache-dir", str(cache), "--no-color-output"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, f"mypy failed:\n{result.stdout}{result.stderr}"
