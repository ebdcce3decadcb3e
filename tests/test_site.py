"""The built documentation as a reader meets it (``make docs`` builds it into docs/_build/html).

- Every internal link and image of every built page resolves: the file exists and, for ``#anchor``,
  the target page has that id (Sphinx with -W already fails on a broken link between Markdown pages;
  this also covers the theme's links, the API pages and raw HTML).
- The index and two pages, opened in headless Chromium (Debian's chromium + chromium-driver, driven by
  selenium) over HTTP from a local server: every image has loaded (``naturalWidth > 0``), and the search
  page answers a query with results (the theme's search runs in the browser, on searchindex.js).

Both need a built site that is newer than its sources; otherwise they skip with the reason.  The browser
test skips where Chromium is missing; ``.ci/run`` builds the docs, installs Chromium and sets
``SYMSPHERE_REQUIRE_BROWSER=1``, under which a missing browser or site is an error, not a skip.
"""

from __future__ import annotations

import functools
import html.parser
import http.server
import os
import shutil
import threading
import urllib.parse
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SITE = ROOT / "docs" / "_build" / "html"
REQUIRED = os.environ.get("SYMSPHERE_REQUIRE_BROWSER") == "1"
PAGES = ("index.html", "tutorials/getting-started.html", "results/gallery.html")


def _site_reason() -> str | None:
    index = SITE / "index.html"
    if not index.is_file():
        return f"no built site at {SITE}: run make docs"
    sources = [ROOT / "README.md", *(p for p in (ROOT / "docs").rglob("*") if p.suffix in (".md", ".rst", ".py"))]
    newest = max(p.stat().st_mtime for p in sources if "_build" not in p.parts)
    if newest > index.stat().st_mtime:
        return "the built site is older than its sources: run make docs"
    return None


def _skip_or_fail(reason: str) -> None:
    if REQUIRED:
        pytest.fail(f"SYMSPHERE_REQUIRE_BROWSER=1 but {reason}")
    pytest.skip(reason)


@pytest.fixture(scope="module")
def site() -> Path:
    reason = _site_reason()
    if reason is not None:
        _skip_or_fail(reason)
    return SITE


# --- internal links -----------------------------------------------------------------------------------


class _Links(html.parser.HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.ids: set[str] = set()
        self.targets: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        values = dict(attrs)
        if values.get("id"):
            self.ids.add(values["id"] or "")
        if tag == "a" and values.get("name"):
            self.ids.add(values["name"] or "")
        for key in ("href", "src"):
            if tag in ("a", "img", "link", "script") and values.get(key):
                self.targets.append(values[key] or "")


@functools.cache
def _parse(path: Path) -> _Links:
    parser = _Links()
    parser.feed(path.read_text(encoding="utf-8"))
    return parser


def broken_links(site: Path) -> list[str]:
    """'page -> target (why)' for every internal link or image of the built site that does not resolve."""
    broken = []
    for page in sorted(site.rglob("*.html")):
        if "_static" in page.parts or "_sources" in page.parts:
            continue
        for target in _parse(page).targets:
            parts = urllib.parse.urlsplit(target)
            if parts.scheme or parts.netloc or target.startswith(("mailto:", "javascript:", "data:")):
                continue  # external: not this check's business
            path = urllib.parse.unquote(parts.path)
            resolved = (page.parent / path).resolve() if path else page
            if resolved.is_dir():
                resolved = resolved / "index.html"
            where = f"{page.relative_to(site)} -> {target}"
            if not resolved.is_file():
                broken.append(f"{where} (no such file)")
            elif parts.fragment and resolved.suffix == ".html":
                if urllib.parse.unquote(parts.fragment) not in _parse(resolved).ids:
                    broken.append(f"{where} (no such anchor)")
    return broken


def test_every_internal_link_and_image_resolves(site):
    assert broken_links(site) == []


def test_link_check_sees_a_broken_link_and_a_broken_anchor(tmp_path):
    (tmp_path / "a.html").write_text('<p id="here"><a href="b.html#nowhere">b</a><a href="#here">a</a></p>')
    (tmp_path / "b.html").write_text('<img src="missing.png"><a href="a.html#here">a</a>')
    assert broken_links(tmp_path) == [
        "a.html -> b.html#nowhere (no such anchor)",
        "b.html -> missing.png (no such file)",
    ]


# --- in a real browser ----------------------------------------------------------------------------------

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
CHROMEDRIVER = shutil.which("chromedriver")


class _Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: object) -> None:
        pass


@pytest.fixture(scope="module")
def browser(site):
    if CHROMIUM is None or CHROMEDRIVER is None:
        _skip_or_fail("Chromium and ChromeDriver are not installed (Debian: apt-get install chromium chromium-driver)")
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        _skip_or_fail("selenium is not installed (the extra 'test')")
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    # --no-sandbox: CI runs as root; the rest keep Chromium off the (closed) network and quick to start
    for flag in (
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-dev-shm-usage",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
    ):
        options.add_argument(flag)
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(_Quiet, directory=str(site)))
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    driver = webdriver.Chrome(options=options, service=Service(CHROMEDRIVER))
    driver.set_page_load_timeout(60)
    try:
        yield driver, f"http://127.0.0.1:{server.server_address[1]}/"
    finally:
        driver.quit()
        server.shutdown()
        server.server_close()


def _wait(driver, condition, timeout=30):
    from selenium.webdriver.support.ui import WebDriverWait

    return WebDriverWait(driver, timeout).until(condition)


def _images(driver, url):
    """(src, naturalWidth) of every image of the page at *url*, once each has loaded or failed."""
    driver.get(url)
    _wait(driver, lambda d: d.execute_script("return document.readyState") == "complete")
    _wait(driver, lambda d: d.execute_script("return Array.from(document.images).every(i => i.complete)"))
    return driver.execute_script("return Array.from(document.images).map(i => [i.getAttribute('src'), i.naturalWidth])")


def test_image_check_sees_an_image_that_does_not_load(browser):
    driver, base = browser
    images = _images(driver, base + "index.html")
    assert images and all(width > 0 for _, width in images)
    missing = base + "_images/no-such-picture.png"  # from the same server, no file written into the site
    assert _images(driver, f'data:text/html,<img src="{missing}">') == [[missing, 0]]


@pytest.mark.parametrize("page", PAGES)
def test_page_opens_in_chromium_and_its_images_load(browser, page):
    driver, base = browser
    images = _images(driver, base + page)
    content = [src for src, _ in images if "_static" not in src]  # the page's own pictures, not the theme's logo
    assert content, f"{page}: no images found"
    assert [src for src, width in images if width == 0] == []
    assert driver.title and "symsphere" in driver.title


def test_search_box_answers_in_chromium(browser):
    driver, base = browser
    driver.get(base + "index.html")
    # the theme's search box is a form that submits to search.html?q=...
    form = driver.execute_script(
        "const f = document.querySelector('form.bd-search, form[action*=\"search\"]');"
        "return f ? f.getAttribute('action') : null"
    )
    assert form is not None and "search" in form
    driver.get(urllib.parse.urljoin(base + "index.html", form) + "?q=orbit")
    # Sphinx lists the matches one by one and then writes "Search finished, ..." into the summary: wait for
    # that, not for the first match (the page sought may come later in the list)
    results = _wait(
        driver,
        lambda d: d.execute_script(
            "const s = document.querySelector('.search-summary');"
            "if (!s || !s.textContent.startsWith('Search finished')) return false;"
            "return Array.from(document.querySelectorAll('#search-results li, ul.search li')).map(li => li.textContent)"
        ),
        timeout=60,
    )
    assert len(results) >= 3  # "orbit" is on many pages
    assert any("Getting started" in text for text in results)
