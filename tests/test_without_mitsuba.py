"""A user without Mitsuba 3 (the extra ``mitsuba``): one line saying what to install, never a traceback.

Runs wherever the suite runs, Mitsuba installed or not: a subprocess hides ``mitsuba`` and ``drjit``
with an import hook that refuses them, as a machine without the extra would.
"""

from __future__ import annotations

import subprocess
import sys

_HIDE = """
import importlib.abc, sys
class _Refuse(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in ("mitsuba", "drjit"):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None
sys.meta_path.insert(0, _Refuse())
"""


def _run(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", _HIDE + code], capture_output=True, text=True, timeout=120)


def test_import_symsphere_mitsuba_says_what_to_install():
    done = _run(
        "try:\n    import symsphere.mitsuba\nexcept ImportError as error:\n    print(error)\nelse:\n    print('imported')"
    )
    assert done.returncode == 0, done.stderr
    message = done.stdout.strip()
    assert "\n" not in message and "pip install 'symsphere[mitsuba]'" in message and "libllvm19" in message


def test_cli_mitsuba_scene_without_mitsuba_is_one_line(tmp_path):
    scene = tmp_path / "scene.xml"
    scene.write_text('<scene version="3.0.0"/>\n', encoding="utf-8")
    out = tmp_path / "img.png"
    done = _run(
        f"from symsphere.apps.cli import main; raise SystemExit(main(['render', '--scene', {str(scene)!r}, '--out', {str(out)!r}]))"
    )
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    assert str(scene) in lines[0] and "pip install 'symsphere[mitsuba]'" in lines[0]
    assert not out.exists()
