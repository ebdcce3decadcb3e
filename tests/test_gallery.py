"""``make gallery`` (scripts/gallery.py) runs: its small configuration writes every promised picture.

The pictures themselves are looked at, not tested; this checks that the script still runs against the
library (a renamed function or a new warp domain would break it) and that each file is a whole PNG.
"""

from __future__ import annotations

from pathlib import Path

import fresh_processes

from symsphere.warps import WARPS

ROOT = Path(__file__).resolve().parent.parent
PNG = b"\x89PNG\r\n\x1a\n"


def test_gallery_script_writes_every_picture(tmp_path):
    out = tmp_path / "gallery"
    # python scripts/gallery.py, forked from a process that imported the library (tests/fresh_processes.py)
    run = fresh_processes.run([str(ROOT / "scripts" / "gallery.py"), "--small", "--out", str(out)], tmp_path)
    assert run.returncode == 0, run.stderr
    expected = {"triangles", "orbit", "convergence_integrate", "convergence_render", "renders"}
    expected |= {f"warp_{name}" for name, warp in WARPS.items() if warp.domain != "disk"}
    written = {p.stem for p in out.iterdir()}
    assert written == expected  # nothing missing, and no stray temporaries left behind
    for path in out.iterdir():
        assert path.read_bytes()[:8] == PNG and path.stat().st_size > 1000, path.name


def test_gallery_page_shows_every_picture_of_the_checked_in_folder():
    page = (ROOT / "docs" / "results" / "gallery.md").read_text(encoding="utf-8")
    folder = ROOT / "docs" / "images" / "gallery"
    pictures = sorted(p.name for p in folder.glob("*.png"))
    assert pictures, "run make gallery"
    missing = [name for name in pictures if f"../images/gallery/{name}" not in page]
    assert missing == []
