"""The API reference (docs/, built by ``make docs``) keeps its promises.

- Every public module is either documented (listed in ``docs/api/index.rst``, one line each) or
  named in :data:`NOT_DOCUMENTED` with the reason.
- Every public name of a documented module (its ``__all__``) has a runnable example: an
  ``Examples`` section in the docstring of each function and class (``--doctest-modules`` runs
  them).  A constant has no docstring of its own: it needs a doc comment (a string right after
  the assignment, which autodoc shows); examples in a doc comment would not be run, so a constant
  is shown at work in the examples of the functions that take it.

Modules not yet complete are marked ``xfail(strict=True)`` in :data:`INCOMPLETE`: once a module is
complete its xfail fails, as a reminder to delete its entry.

The Sphinx build itself is not a test: ``make docs`` runs it with warnings as errors, and CI
runs ``make docs`` after ``make test`` (a test would build the docs a second time).
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
import inspect
import pathlib
import pkgutil
import re

import pytest

import symsphere

ROOT = pathlib.Path(__file__).resolve().parent.parent
API_INDEX = ROOT / "docs" / "api" / "index.rst"

# Public modules without a page of their own, and why.
NOT_DOCUMENTED = {
    "symsphere.apps": "a package of applications without names of its own; its modules have pages",
    "symsphere.mitsuba": "needs Mitsuba 3 (the extra 'mitsuba', not in the docs build); docs/rendering.md documents it",
    "symsphere.apps.study.compiled": "the study's compiled peer samplers, an internal of the study; docs/study.md describes them",
    "symsphere.apps.mitsuba_render": "the render verb's Mitsuba scene files; symsphere render --help and docs/rendering.md",
    "symsphere.apps.render_command": "the render verb of symsphere.apps.cli (its parser and handlers); symsphere render --help",
    "symsphere.render.image": "its public names are documented on the symsphere.render page",
    "symsphere.render.renderer": "its public names are documented on the symsphere.render page",
    "symsphere.render.scene": "its public names are documented on the symsphere.render page",
    "symsphere.render.scene_files": "its public names are documented on the symsphere.render page",
    "symsphere.render.scenes": "its public names are documented on the symsphere.render page",
    **{
        f"symsphere.apps.study.{name}": "the study's internals; symsphere.apps.study documents its interface"
        for name in ("command", "config", "figures", "report", "results", "run", "samplers")
    },
}

# Documented modules with public names that lack an example (or constants without a doc comment).
# Delete an entry when its module is complete: the strict xfail then turns into a pass.
INCOMPLETE = {}


def documented_modules():
    """The modules of docs/api/index.rst, in order (docs/conf.py reads the same list)."""
    text = API_INDEX.read_text(encoding="utf-8")
    return re.findall(r"^   (symsphere(?:\.\w+)*)\s*$", text, flags=re.MULTILINE)


def public_modules():
    names = ["symsphere"]
    for info in pkgutil.walk_packages(symsphere.__path__, "symsphere."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            names.append(info.name)
    return names


def has_examples(doc):
    """A numpydoc ``Examples`` section with at least one doctest line."""
    match = re.search(r"^Examples\n-{8,}\n(.*?)(?=^\S.*\n-{3,}\n|\Z)", doc or "", flags=re.MULTILINE | re.DOTALL)
    return bool(match) and ">>> " in match.group(1)


def doc_comment(module_name, name, _seen=None):
    """The doc comment of constant *name* of a module, following ``from .x import name``; or None."""
    _seen = set() if _seen is None else _seen
    if (module_name, name) in _seen:
        return None
    _seen.add((module_name, name))
    spec = importlib.util.find_spec(module_name)
    if spec is None or spec.origin is None or not spec.origin.endswith(".py"):
        return None
    tree = ast.parse(pathlib.Path(spec.origin).read_text(encoding="utf-8"))
    package = module_name if spec.submodule_search_locations is not None else module_name.rpartition(".")[0]
    body = tree.body
    for i, node in enumerate(body):
        targets = []
        if isinstance(node, ast.Assign):
            targets = [t.id for t in node.targets if isinstance(t, ast.Name)]
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            targets = [node.target.id]
        if name in targets and i + 1 < len(body):
            following = body[i + 1]
            if isinstance(following, ast.Expr) and isinstance(following.value, ast.Constant):
                if isinstance(following.value.value, str) and following.value.value.strip():
                    return following.value.value
        if isinstance(node, ast.ImportFrom):
            for alias in node.names:
                if (alias.asname or alias.name) == name:
                    source = importlib.util.resolve_name("." * node.level + (node.module or ""), package)
                    found = doc_comment(source, alias.name, _seen)
                    if found:
                        return found
    return None


def lacking(module_name):
    """Public names of a module without an example (constants: without a doc comment)."""
    module = pytest.importorskip(module_name)  # symsphere.distributed needs the extra "distributed"
    missing = []
    for name in module.__all__:
        obj = getattr(module, name)
        if inspect.ismodule(obj):
            continue  # documented on its own page
        if inspect.isclass(obj) or callable(obj):
            if not has_examples(inspect.getdoc(obj)):
                missing.append(name)
        elif not doc_comment(module_name, name):
            missing.append(f"{name} (constant without a doc comment)")
    return missing


def test_every_public_module_is_documented_or_exempt():
    documented = set(documented_modules())
    assert "symsphere" in documented and len(documented) == len(documented_modules())
    missing = [name for name in public_modules() if name not in documented and name not in NOT_DOCUMENTED]
    assert not missing, (
        f"add a line for each of {missing} to docs/api/index.rst (or to NOT_DOCUMENTED, with the reason)"
    )
    stale = sorted((set(NOT_DOCUMENTED) & documented) | (set(NOT_DOCUMENTED) - set(public_modules())))
    assert not stale, f"NOT_DOCUMENTED names modules that are documented or gone: {stale}"


def test_incomplete_names_documented_modules():
    assert set(INCOMPLETE) <= set(documented_modules())


def test_documented_modules_have_all():
    for name in documented_modules():
        module = pytest.importorskip(name)
        assert isinstance(getattr(module, "__all__", None), list | tuple), f"{name} has no __all__"
        assert all(hasattr(module, member) for member in module.__all__), name


def _module_params():
    params = []
    for name in documented_modules():
        marks = [pytest.mark.xfail(strict=True, reason=INCOMPLETE[name])] if name in INCOMPLETE else []
        params.append(pytest.param(name, marks=marks, id=name))
    return params


@pytest.mark.parametrize("module_name", _module_params())
def test_every_public_name_has_an_example(module_name):
    missing = lacking(module_name)
    assert not missing, f"{module_name}: no Examples section in the docstring of {missing}"
