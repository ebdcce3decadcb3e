"""Packaging: license, changelog, metadata, one version, a README that renders on PyPI.

The wheel itself is built and used in a bare venv by scripts/check_wheel.py, which CI runs after the
suite (.ci/run): it needs pip's index and takes minutes.
"""

import importlib.metadata
import re
import tomllib
from pathlib import Path

import pytest

import symsphere

ROOT = Path(__file__).resolve().parents[1]


def test_license_file_and_spdx_expression():
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert text.startswith("BSD 3-Clause License") and "symsphere developers" in text
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    # PEP 639: a string, not the deprecated table that made setuptools warn three times (setuptools deprecated the table form).
    assert project["license"] == "BSD-3-Clause" and project["license-files"] == ["LICENSE"]
    assert not any(c.startswith("License ::") for c in project.get("classifiers", []))  # deprecated with PEP 639
    requires = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["build-system"]["requires"]
    assert requires == ["setuptools>=77"]  # the first setuptools with PEP 639


def test_installed_metadata():
    metadata = importlib.metadata.metadata("symsphere")
    assert metadata["License-Expression"] == "BSD-3-Clause"
    assert metadata["Author"] == "symsphere developers"


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
    headings = re.findall(r"^### (\w+)$", unreleased, re.M)
    order = ["Added", "Changed", "Deprecated", "Removed", "Fixed", "Security"]  # Keep a Changelog's kinds, in order
    assert headings and headings == [h for h in order if h in headings]


def test_ci_builds_and_uses_the_wheel():
    assert "scripts/check_wheel.py" in (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert "build" in " ".join(
        tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]["optional-dependencies"]["test"]
    )


# --- README as the long description: PyPI renders it away from the repository -------------------

_LINK = re.compile(r"!?\[[^\]]*\]\(\s*<?([^)\s>]+)")  # Markdown links and images: the target
_HTML = re.compile(r"""\b(?:src|href)\s*=\s*["']([^"']+)""", re.I)  # <img src=...>, <a href=...>


def _readme_targets():
    """(is an image, target) of every Markdown link or image and every HTML src/href in README.md."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    for match in _LINK.finditer(text):
        yield match[0].startswith("!"), match[1]
    for match in _HTML.finditer(text):
        yield match[0].lower().lstrip().startswith("src"), match[1]


def test_readme_links_are_relative_or_external_and_exist():
    # The project has no public address yet: README's own files are linked relatively (docs/..., docs/images/...),
    # which works on a code host, in a checkout, in an editor and in the Sphinx build (docs/index.md includes
    # README with :relative-docs: docs/ and :relative-images:), and each names a file of the repository.
    targets = list(_readme_targets())
    assert len(targets) > 20  # the parser sees README's links
    relative = [t for _, t in targets if not re.match(r"https?://|#|mailto:", t)]
    assert len(relative) > 20
    missing = sorted(t for t in relative if not (ROOT / t.split("#")[0]).is_file())
    assert missing == [], "README.md links to paths that are not in the repository"
    # in the Sphinx build a link resolves only under docs/ (:relative-docs:), an image anywhere
    outside_docs = [t for image, t in targets if t in relative and not image and not t.startswith("docs/")]
    assert outside_docs == [], "README.md links outside docs/: broken in the built docs"


def test_readme_renders_as_on_pypi():
    # PyPI's renderer (readme_renderer, GitHub-flavoured Markdown; scripts/check_wheel.py runs it on the wheel's
    # metadata): None means it failed; the images are kept, with the sources README gives them.
    markdown = pytest.importorskip("readme_renderer.markdown")
    html = markdown.render((ROOT / "README.md").read_text(encoding="utf-8"), variant="GFM")
    assert html is not None and "<h1" in html
    sources = re.findall(r'<img[^>]*\bsrc="([^"]+)"', html)
    assert len(sources) >= 1 and all((ROOT / s).is_file() for s in sources)
