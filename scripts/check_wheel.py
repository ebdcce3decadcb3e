"""Build the wheel and sdist, install the wheel into a bare venv, and use it as a first-time user would.

Run by CI (.ci/run) after the test suite; needs the test extra (``build``) and the network (or a
warm pip cache) for the wheel's dependencies.  Checks, each with a clear failure message:

1. ``python -m build`` makes a wheel and an sdist without setuptools' deprecation warnings
  ; both carry LICENSE, the sdist also CHANGELOG.md; the wheel's metadata has
   the SPDX license expression, the author, no project URL (there is no public address yet) and the
   version of ``symsphere.__version__``; its long description (README.md) renders as PyPI renders it
   (``readme_renderer``, as ``twine check``), and each of its relative links and images names a file of
   the repository (relative, so that they work in a checkout, an editor and the Sphinx build; on PyPI
   they stay broken until there is a public address to make them absolute).
2. In a fresh venv with nothing but ``pip install <wheel>`` (no extras):
   ``symsphere --version`` agrees with ``symsphere.__version__``; the README's example runs;
   ``symsphere sample --n 480`` writes its file; ``symsphere integrate ... --workers 2`` exits 2 with
   one line that names the extra to install.  With ``--demo``, also
   ``symsphere demo --n 480`` (its small render compiles the path tracer in the fresh install:
   about 3 more minutes on 2 busy cores).

    python scripts/check_wheel.py [--demo] [--keep DIR]

About a minute on 2 cores with a warm pip cache (49-56 s alone, 36 s beside the docs build in .ci/run,
2-core Intel Xeon, 2026-12-03): pip, and numba compiling the sampling kernels in the fresh install, take
most of it.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tarfile
import tempfile
import time
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def run(command, *, cwd=None, expect=0, timeout=600):
    start = time.perf_counter()
    done = subprocess.run([str(c) for c in command], cwd=cwd, capture_output=True, text=True, timeout=timeout)
    print(f"  {time.perf_counter() - start:5.1f} s  {' '.join(str(c) for c in command)[:110]}", flush=True)
    if done.returncode != expect:
        sys.exit(
            f"check_wheel: {command[0]} ... exited {done.returncode}, expected {expect}\n"
            f"--- stdout\n{done.stdout[-3000:]}\n--- stderr\n{done.stderr[-3000:]}"
        )
    return done


def check(condition, message):
    if not condition:
        sys.exit(f"check_wheel: {message}")


def readme_example() -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    block = re.search(r"## Three examples\n.*?```python\n(.*?)```", text, re.S)  # the first: sampling
    check(block is not None, "README.md has no python block under '## Three examples'")
    return block[1]


def check_long_description(metadata: str) -> None:
    """The wheel's long description renders as on PyPI (readme_renderer, GFM); its relative links name files."""
    try:
        from readme_renderer.markdown import render
    except ImportError:
        sys.exit("check_wheel: readme_renderer is missing: pip install -e '.[test]'")
    header, _, body = metadata.partition("\n\n")
    check("Description-Content-Type: text/markdown" in header, "the long description is not declared Markdown")
    html = render(body, variant="GFM")
    check(html is not None and "<h1" in html, "the long description does not render (readme_renderer)")
    relative = sorted({t for t in re.findall(r'(?:src|href)="([^"]+)"', html) if not re.match(r"https?://|#", t)})
    missing = [t for t in relative if not (ROOT / t.split("#")[0]).is_file()]
    check(
        relative and not missing, f"the long description links to files that are not in the repository: {missing[:5]}"
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--demo", action="store_true", help="run `symsphere demo --n 480` too (slow: compiles the renderer)"
    )
    parser.add_argument(
        "--keep", type=Path, default=None, help="work in DIR and keep it (default: a temporary directory)"
    )
    args = parser.parse_args()
    work = args.keep or Path(tempfile.mkdtemp(prefix="symsphere-wheel-"))
    work.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    try:
        print("build:")
        dist = work / "dist"
        shutil.rmtree(dist, ignore_errors=True)
        built = run([sys.executable, "-m", "build", "--sdist", "--wheel", "--outdir", dist, ROOT])
        output = built.stdout + built.stderr
        check("Deprecat" not in output, "the build prints a deprecation warning:\n" + "\n".join(
            line for line in output.splitlines() if "eprecat" in line))  # fmt: skip
        wheel = next(dist.glob("symsphere-*.whl"))
        sdist = next(dist.glob("symsphere-*.tar.gz"))
        with zipfile.ZipFile(wheel) as archive:
            names = archive.namelist()
            metadata = archive.read(next(n for n in names if n.endswith(".dist-info/METADATA"))).decode()
        check(any(n.endswith(".dist-info/licenses/LICENSE") for n in names), "the wheel has no LICENSE")
        check("License-Expression: BSD-3-Clause" in metadata, "no License-Expression in the wheel's METADATA")
        check(
            "Project-URL:" not in metadata and "Author: symsphere developers" in metadata, "a project URL, or no author"
        )
        check_long_description(metadata)
        with tarfile.open(sdist) as archive:
            members = {Path(m).name for m in archive.getnames()}
        check(
            {"LICENSE", "CHANGELOG.md", "README.md"} <= members,
            f"the sdist lacks LICENSE or CHANGELOG.md: {sorted(members)[:20]}",
        )

        print("a bare venv with the wheel only:")
        venv = work / "venv"
        shutil.rmtree(venv, ignore_errors=True)
        run([sys.executable, "-m", "venv", "--without-pip", venv])  # pip comes from outside: faster
        python = venv / "bin" / "python"
        symsphere = venv / "bin" / "symsphere"
        run(
            [
                sys.executable,
                "-m",
                "pip",
                "--python",
                python,
                "install",
                "--quiet",
                "--no-compile",
                "--disable-pip-version-check",
                wheel,
            ]
        )  # no .pyc: faster
        version = run([symsphere, "--version"]).stdout.strip()
        module = run([python, "-c", "import symsphere; print(symsphere.__version__)"]).stdout.strip()
        check(version == f"symsphere {module}" and f"Version: {module}" in metadata, f"{version!r} vs {module!r}")
        example = run([python, "-c", readme_example()], cwd=work)
        check("True" in example.stdout, f"README example printed {example.stdout!r}")
        sample = run([symsphere, "sample", "--n", "480", "--seed", "1", "--out", work / "d.npy"])
        check((work / "d.npy").is_file() and "wrote 480 directions" in sample.stdout, "sample wrote no file")
        if args.demo:
            demo = run([symsphere, "demo", "--n", "480", "--seed", "1", "--no-progress", "--out", work / "demo"])
            check((work / "demo" / "report.md").is_file() and "report:" in demo.stdout, "demo wrote no report")
        workers = run(
            [symsphere, "integrate", "--integrand", "exp", "--n", "4800", "--workers", "2"], expect=2
        )  # fmt: skip
        lines = workers.stderr.strip().splitlines()
        check(
            len(lines) == 1 and lines[0].endswith("pip install 'symsphere[distributed]'"),
            f"--workers without dask: {workers.stderr!r}",
        )
    finally:
        if args.keep is None:
            shutil.rmtree(work, ignore_errors=True)
    print(f"check_wheel: all good ({time.perf_counter() - start:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
