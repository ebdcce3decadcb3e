"""Packaging (issue 13): license, changelog, metadata, one version, a README that renders on PyPI.

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


def _bases():
    """(pages, images): the bases of README's links, derived from pyproject's ``Source`` URL."""
    urls = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]["urls"]
    source = urls["Source"].rstrip("/")
    owner_repo = re.fullmatch(r"https://github\.com/([\w.-]+/[\w.-]+)", source)
    assert owner_repo, f"Source is not a GitHub repository URL: {source}"
    return source, f"https://raw.githubusercontent.com/{owner_repo[1]}/main/"


def test_project_urls_share_one_base():
    urls = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]["urls"]
    source, _ = _bases()
    assert urls["Homepage"] == source
    assert all(url == source or url.startswith(source + "/") for url in urls.values()), urls


def test_readme_links_are_absolute_from_the_source_url_and_exist():
    # PyPI shows README.md away from the repository: a relative link or image (docs/..., docs/images/...)
    # is broken there.  Every target is absolute, under pyproject's Source (pages: .../blob/main/<path>,
    # images: raw.githubusercontent.com/<owner>/<repo>/main/<path>), and <path> exists in the repository.
    source, raw = _bases()
    pages = source + "/blob/main/"
    targets = list(_readme_targets())
    assert len(targets) > 20  # the parser sees README's links
    relative = [t for _, t in targets if not re.match(r"https?://", t)]
    assert relative == [], f"relative links in README.md (use {pages}<path> or {raw}<path>)"
    foreign = [t for _, t in targets if not (t.startswith((pages, raw)) or t == source or t.startswith(source + "/"))]
    assert foreign == [], f"links not under {source}"
    not_raw = [t for image, t in targets if image and not t.startswith(raw)]
    assert not_raw == [], f"images must come from {raw} (a blob/ page is HTML, not an image)"
    paths = {t[len(pages if t.startswith(pages) else raw) :].split("#")[0] for _, t in targets if t.startswith((pages, raw))}
    missing = sorted(p for p in paths if not (ROOT / p).exists())
    assert missing == [], "README.md links to paths that are not in the repository"


def test_readme_renders_as_on_pypi():
    # PyPI's renderer (readme_renderer, GitHub-flavoured Markdown; scripts/check_wheel.py runs it on the wheel's
    # metadata): None means it failed; the images are kept, with absolute sources.
    markdown = pytest.importorskip("readme_renderer.markdown")
    html = markdown.render((ROOT / "README.md").read_text(encoding="utf-8"), variant="GFM")
    assert html is not None and "<h1" in html
    sources = re.findall(r'<img[^>]*\bsrc="([^"]+)"', html)
    assert len(sources) >= 7 and all(s.startswith("https://") for s in sources)
