"""The layout is the architecture (docs/explanation/design.md): checked on the source, so that it stays true.

- private means private: a name with a leading underscore is used only in its own module;
- the library never imports the applications (``symsphere.apps``);
- a module holds one concept, and stays readable: at most 600 lines (ruff-formatted);
- by importing: no library module loads the applications; each public name has one home (a name
  listed in a public module's ``__all__`` is defined there, or in a private module behind exactly
  one public module; package ``__init__``s gather names for their documented namespaces);
- the tests reach private modules only through ``symsphere._testing`` (docs/explanation/testing.md);
- the tests mirror the modules: ``tests/<folders>/test_<name>.py`` tests ``symsphere/<folders>/<name>.py``
  or ``_<name>.py`` (or the package ``<name>/``); the tests of the package as a whole are listed in
  ``PACKAGE_TESTS``;
- the tests' seeds are fixed: none comes from ``hash()``, ``id()``, the clock or the process id.
"""

from __future__ import annotations

import ast
import importlib
import re
import subprocess
import sys
import types
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "symsphere"
SOURCES = sorted(PACKAGE.rglob("*.py"))
GENERATED: set[str] = set()  # no generated modules
# ``python -m symsphere``: an entry point of the applications' layer (it runs symsphere.apps.cli).
ENTRY_POINTS = {"__main__.py"}
MAX_LINES = 600  # ruff-formatted; a module that grows past it is for splitting


def _module_name(path: Path, package: Path = PACKAGE) -> str:
    parts = path.relative_to(package.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _resolve(path: Path, node: ast.ImportFrom, root: Path = PACKAGE) -> str:
    """The absolute module name of an ``ImportFrom`` in *path*."""
    if not node.level:
        return node.module or ""
    package = _module_name(path, root).split(".")
    if path.name != "__init__.py":
        package = package[:-1]
    base = package[: len(package) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _is_private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def _ours(module: str) -> bool:
    return module == "symsphere" or module.startswith("symsphere.")


def _is_module(dotted: str, root: Path) -> bool:
    target = root.parent / Path(*dotted.split("."))
    return target.with_suffix(".py").exists() or (target / "__init__.py").exists()


def _violations(path: Path, root: Path = PACKAGE) -> list[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found = []
    module_aliases = {}  # local name -> our module it is bound to
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            source = _resolve(path, node, root)
            if not _ours(source):
                continue
            for alias in node.names:
                target = f"{source}.{alias.name}"
                if _is_private(alias.name) and not _is_module(target, root):
                    found.append(f"{path.name}:{node.lineno} imports the private name {alias.name} from {source}")
                module_aliases[alias.asname or alias.name] = target
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if _ours(alias.name):
                    module_aliases[alias.asname or alias.name.split(".")[0]] = alias.name
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Attribute)
            and _is_private(node.attr)
            and isinstance(node.value, ast.Name)
            and node.value.id in module_aliases
        ):
            target = module_aliases[node.value.id]
            if _is_module(target, root):
                found.append(f"{path.name}:{node.lineno} uses the private name {node.attr} of {target}")
    return found


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_private_names_stay_in_their_module(path):
    assert _violations(path) == []


def _is_application(path: Path) -> bool:
    relative = path.relative_to(PACKAGE)
    return "apps" in relative.parts or (len(relative.parts) == 1 and relative.name in ENTRY_POINTS)


@pytest.mark.parametrize(
    "path", [p for p in SOURCES if not _is_application(p)], ids=lambda p: str(p.relative_to(PACKAGE))
)
def test_the_library_never_imports_the_applications(path):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            names = [_resolve(path, node)] + [f"{_resolve(path, node)}.{a.name}" for a in node.names]
        elif isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        else:
            continue
        assert not any(n == "symsphere.apps" or n.startswith("symsphere.apps.") for n in names), (
            f"{path.name}:{node.lineno} imports the applications"
        )


@pytest.mark.parametrize(
    "path", [p for p in SOURCES if p.name not in GENERATED], ids=lambda p: str(p.relative_to(PACKAGE))
)
def test_modules_stay_readable(path):
    lines = len(path.read_text(encoding="utf-8").splitlines())
    assert lines <= MAX_LINES, f"{path.relative_to(PACKAGE)} has {lines} lines; split it by concept"


def test_the_checker_sees_a_violation(tmp_path):
    # The check can fail: a module that imports another's private name, or reaches into it, is caught;
    # a private *module* with public names (scipy's ``_qmc`` pattern) is allowed.
    package = tmp_path / "symsphere"
    package.mkdir()
    for name in ("__init__", "symmetry", "maps", "_kernels"):
        (package / f"{name}.py").write_text("")
    probe = package / "probe.py"
    probe.write_text(
        "from .symmetry import _fold\nimport symsphere.maps as m\nm._REGISTRY\nfrom ._kernels import fill\n"
    )
    found = _violations(probe, package)
    assert len(found) == 2, found


# --- the rules by importing, not only by reading -------------------------------------------------

LIBRARY_MODULES = [
    _module_name(p)
    for p in SOURCES
    if not _is_application(p) and "mitsuba" not in p.relative_to(PACKAGE).parts and p.name != "_testing.py"
]
PUBLIC_MODULES = [m for m in LIBRARY_MODULES if not any(part.startswith("_") for part in m.split("."))]


def _public(dotted: str) -> bool:
    return not any(part.startswith("_") for part in dotted.split("."))


def test_importing_the_library_loads_no_application():
    # Every library module, imported in a fresh process (so that a lazy attribute like the old
    # ``ss.study`` or an import cycle is exercised too): symsphere.apps never appears in sys.modules.
    code = (
        "import importlib, sys\n"
        f"for name in {LIBRARY_MODULES!r}:\n"
        "    importlib.import_module(name)\n"
        "import symsphere\n"
        "for name in dir(symsphere):\n"
        "    getattr(symsphere, name)\n"
        "loaded = sorted(m for m in sys.modules if m == 'symsphere.apps' or m.startswith('symsphere.apps.'))\n"
        "print(loaded)\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "[]", run.stdout


def _homes(modules: list[str]) -> dict[tuple[str, str], list[str]]:
    """(defining module, name) -> the public modules (not package namespaces) whose ``__all__`` lists it."""
    listed: dict[tuple[str, str], list[str]] = {}
    for dotted in modules:
        module = importlib.import_module(dotted)
        if hasattr(module, "__path__"):  # a package __init__: its documented namespace gathers names
            continue
        for name in getattr(module, "__all__", ()):
            value = getattr(module, name)
            if isinstance(value, types.ModuleType):
                continue
            home = getattr(value, "__module__", None) if callable(value) else None
            listed.setdefault((home or f"{dotted} (a value)", name), []).append(dotted)
    return listed


def test_each_public_name_has_one_home():
    # A name defined in a public module is listed in that module's __all__ only; a name defined in a
    # private module (scipy's _qmc pattern) is listed by one public module.  Package __init__s excepted.
    problems = []
    for (home, name), modules in _homes(PUBLIC_MODULES).items():
        if _public(home.split(" ")[0]) and " (a value)" not in home:
            if modules != [home]:
                problems.append(f"{name}: defined in {home}, listed by {modules}")
        elif len(modules) > 1:
            problems.append(f"{name} ({home}): listed by {modules}")
    assert problems == []


def test_the_home_check_sees_a_re_export(tmp_path, monkeypatch):
    package = tmp_path / "probe_pkg"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "a.py").write_text("__all__ = ['f']\ndef f(): pass\n")
    (package / "b.py").write_text("from .a import f\n__all__ = ['f']\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    listed = _homes(["probe_pkg.a", "probe_pkg.b"])
    assert listed == {("probe_pkg.a", "f"): ["probe_pkg.a", "probe_pkg.b"]}


# --- the tests reach the internals through one door ----------------------------------------------

TESTS = Path(__file__).resolve().parent
TEST_SOURCES = sorted(TESTS.rglob("*.py"))
TESTING_HOOK = "symsphere._testing"


def _private_uses(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and _ours(node.module) and not node.level:
            if node.module == TESTING_HOOK:
                continue
            if not _public(node.module):
                found.append(f"{path.name}:{node.lineno} imports from {node.module}")
            found += [f"{path.name}:{node.lineno} imports {a.name}" for a in node.names if _is_private(a.name)]
        elif isinstance(node, ast.Import):
            found += [
                f"{path.name}:{node.lineno} imports {a.name}"
                for a in node.names
                if _ours(a.name) and not _public(a.name) and a.name != TESTING_HOOK
            ]
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            # code run in a subprocess: ``import symsphere._x`` inside a string
            found += [
                f"{path.name}:{node.lineno} runs {m}"
                for m in re.findall(r"\bimport (symsphere(?:\.\w+)+)", node.value)
                if not _public(m) and m != TESTING_HOOK
            ]
    return found


@pytest.mark.parametrize(
    "path",
    [p for p in TEST_SOURCES if p != Path(__file__).resolve()],  # itself: the probe's text
    ids=lambda p: str(p.relative_to(TESTS)),
)
def test_tests_reach_internals_only_through_the_testing_hook(path):
    assert _private_uses(path) == []


# Tests of the package as a whole (or of the repository around it), not of one module: its layout and
# typing, the docs and the site, packaging, the pinned public outputs, the property-based error
# contract of every public function, examples and first contact, the statistical uniformity of every
# sampler.
PACKAGE_TESTS = {
    "test_architecture.py", "test_typing.py", "test_docs.py", "test_site.py", "test_gallery.py",
    "test_examples.py", "test_packaging.py", "test_benchmark_tables.py", "test_public_outputs.py",
    "test_properties.py", "test_properties_apps.py", "test_ux.py", "test_without_mitsuba.py",
    "statistical/test_uniformity.py", "mitsuba/test_bench_lights.py",
}  # fmt: skip


def _tested_module(test: Path, package: Path = PACKAGE) -> Path | None:
    """The module a test file is named after (``tests/a/test_b.py``: ``a/b.py``, ``a/_b.py`` or the package
    ``a/b/``, under *package*), or None."""
    name = test.stem.removeprefix("test_")
    folder = package.joinpath(*test.parent.relative_to(TESTS).parts)
    for candidate in (folder / f"{name}.py", folder / f"_{name}.py", folder / name / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


@pytest.mark.parametrize("path", sorted(TESTS.rglob("test_*.py")), ids=lambda p: str(p.relative_to(TESTS)))
def test_each_test_file_is_named_after_its_module(path):
    relative = path.relative_to(TESTS).as_posix()
    assert relative in PACKAGE_TESTS or _tested_module(path) is not None, (
        f"tests/{relative} is named after no module of symsphere: name it tests/<folders>/test_<module>.py "
        "after the module it tests (merge it into that file if one exists), or list it in PACKAGE_TESTS"
    )


def test_the_layout_check_sees_a_misnamed_test():
    assert _tested_module(TESTS / "warps" / "test_triangle.py") == PACKAGE / "warps" / "_triangle.py"
    assert _tested_module(TESTS / "apps" / "test_study.py") == PACKAGE / "apps" / "study" / "__init__.py"
    assert _tested_module(TESTS / "test_io.py") == PACKAGE / "io" / "__init__.py"
    assert _tested_module(TESTS / "test_tolerance.py") is None  # integration to a tolerance: test_integration.py
    assert _tested_module(TESTS / "test_integrate_auto.py") is None  # integrate(method="auto"): test_auto.py


def test_the_hook_check_sees_a_private_import(tmp_path):
    probe = tmp_path / "test_probe.py"
    probe.write_text(
        "from symsphere._kernels import fill\nfrom symsphere.maps import _sin_small\nimport symsphere._fused\n"
        "from symsphere._testing import kernels\ncode = 'import symsphere._threads'\n"
    )
    assert len(_private_uses(probe)) == 4


def test_no_issue_numbers_in_code_tests_or_docs():
    # History is CHANGELOG.md's, and even there told by what changed, not by a tracker's numbers
    # (another project's issue, cited as a source, is a reference: allowed).
    root = PACKAGE.parents[1]
    pattern = re.compile(r"\b[Ii]ssues?\s+#?\d+|\(#\d+\)|\b[Ii]ssue-\d+")
    files = [*SOURCES, *TEST_SOURCES, *sorted((root / "docs").glob("*.md")), root / "README.md", root / "CHANGELOG.md"]
    found = [
        f"{path.relative_to(root)}:{number}: {line.strip()}"
        for path in files
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
        if pattern.search(line) and "OpenBLAS issue" not in line
    ]
    assert found == []


# --- the tests' seeds are fixed -------------------------------------------------------------
# A statistical test draws the same numbers in every run (docs/explanation/testing.md): no seed comes from what
# changes between processes or runs (hash() of a str, id(), the clock, the process id).

_SEEDED = {"default_rng", "SeedSequence", "PCG64", "Generator", "RandomState", "seed"}
_CHANGING = {"hash", "id", "time", "time_ns", "perf_counter", "perf_counter_ns", "monotonic", "getpid", "urandom"}


def _called_name(node: ast.Call) -> str:
    return node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, "id", "")


def _changing_seeds(path: Path) -> list[str]:
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if not isinstance(node, ast.Call):
            continue
        seeds = list(node.args) if _called_name(node) in _SEEDED else []
        seeds += [k.value for k in node.keywords if k.arg in ("rng", "seed", "random_state")]
        for seed in seeds:
            changing = sorted({_called_name(n) for n in ast.walk(seed) if isinstance(n, ast.Call)} & _CHANGING)
            if changing:
                found.append(f"{path.name}:{node.lineno} seeds from {', '.join(changing)}()")
    return found


def test_no_test_seeds_from_what_changes_between_runs():
    found = [v for path in TEST_SOURCES for v in _changing_seeds(path)]  # this file too: its probe is a string
    assert found == []


def test_the_seed_check_sees_a_changing_seed(tmp_path):
    probe = tmp_path / "test_probe.py"
    probe.write_text(
        "import os, time, zlib\nimport numpy as np\n"
        "a = np.random.default_rng(abs(hash('case')) % 2**32)\n"
        "b = f(n=3, rng=int(time.time()))\n"
        "c = np.random.SeedSequence([os.getpid(), 1])\n"
        "ok = np.random.default_rng(zlib.crc32(b'case'))\n"
    )
    assert [v.split(" ", 1)[1] for v in _changing_seeds(probe)] == [
        "seeds from hash()",
        "seeds from time()",
        "seeds from getpid()",
    ]
