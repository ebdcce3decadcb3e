"""Packaging (issue 13): license, changelog, metadata, one version.

The wheel itself is built and used in a bare venv by scripts/check_wheel.py, which CI runs after the
suite (.ci/run): it needs pip's index and takes minutes.
"""

import importlib.metadata
import re
import tomllib
from pathlib import Path

import symsphere

ROOT = Path(__file__).resolve().parents[1]


def test_license_file_and_spdx_expression():
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert text.startswith("BSD 3-Clause License") and "symsphere developers" in text
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    # PEP 639: a string, not the deprecated table that made setuptools warn three times (defect 6).
    assert project["license"] == "BSD-3-Clause" and project["license-files"] == ["LICENSE"]
    assert not any(c.startswith("License ::") for c in project.get("classifiers", []))  # deprecated with PEP 639
    requires = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["build-system"]["requires"]
    assert requires == ["setuptools>=77"]  # the first setuptools with PEP 639


def test_installed_metadata():
    metadata = importlib.metadata.metadata("symsphere")
    assert metadata["License-Expression"] == "BSD-3-Clause"
    assert metadata["Author"] == "symsphere developers"
    urls = dict(url.split(", ", 1) for url in metadata.get_all("Project-URL"))
    assert {"Homepage", "Source", "Issues", "Changelog", "Documentation"} <= set(urls)


def test_one_version():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    assert "version" in project["project"]["dynamic"]
    assert project["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "symsphere.__version__"}
    assert importlib.metadata.version("symsphere") == symsphere.__version__


def test_changelog_keeps_a_changelog():
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    assert text.startswith("# Changelog") and "keepachangelog.com" in text
    release = re.search(r"^## \[(\d+\.\d+\.\d+)\] - Unreleased$", text, re.M)
    assert release and symsphere.__version__.startswith(release[1])
    unreleased = text[release.end() : text.index("\n## [", release.end())]
    assert [h for h in re.findall(r"^### (\w+)$", unreleased, re.M)] == ["Added", "Changed", "Fixed"]


def test_ci_builds_and_uses_the_wheel():
    assert "scripts/check_wheel.py" in (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert "build" in " ".join(
        tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]["optional-dependencies"]["test"]
    )
