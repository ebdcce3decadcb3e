"""The layout is the architecture (docs/design.md): checked on the source, so that it stays true.

- private means private: a name with a leading underscore is used only in its own module;
- the library never imports the applications (``symsphere.apps``);
- a module holds one concept, and stays readable: at most ~850 lines (ruff-formatted).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "symsphere"
SOURCES = sorted(PACKAGE.rglob("*.py"))
GENERATED: set[str] = set()  # no generated modules
# ``python -m symsphere``: an entry point of the applications' layer (it runs symsphere.apps.cli).
ENTRY_POINTS = {"__main__.py"}
MAX_LINES = 850  # 700 before ruff format put long calls one argument per line; the largest modules are for splitting


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
