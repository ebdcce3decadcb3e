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

- Every code block of the README and of the pages under docs/ runs (below, "every code block").

The Sphinx build itself is not a test: ``make docs`` runs it with warnings as errors, and CI
runs ``make docs`` after ``make test`` (a test would build the docs a second time).
"""

from __future__ import annotations

import ast
import functools
import importlib
import importlib.util
import inspect
import json
import os
import pathlib
import pkgutil
import re
import shlex
import subprocess
import sys

import fresh_processes
import pytest

import symsphere

ROOT = pathlib.Path(__file__).resolve().parent.parent
API_INDEX = ROOT / "docs" / "api" / "index.rst"

# Public modules without a page of their own, and why.
NOT_DOCUMENTED = {
    "symsphere.apps": "a package of applications without names of its own; its modules have pages",
    "symsphere.mitsuba": "needs Mitsuba 3 (the extra 'mitsuba', not in the docs build); docs/reference/mitsuba-plugin.md documents it",
    "symsphere.apps.mitsuba_render": "the render verb's Mitsuba scene files; symsphere render --help and docs/reference/mitsuba-plugin.md",
    "symsphere.apps.render_command": "the render verb of symsphere.apps.cli (its parser and handlers); symsphere render --help",
    "symsphere.render.image": "its public names are documented on the symsphere.render page",
    "symsphere.render.renderer": "its public names are documented on the symsphere.render page",
    "symsphere.render.scene": "its public names are documented on the symsphere.render page",
    "symsphere.render.scene_files": "its public names are documented on the symsphere.render page",
    "symsphere.render.scenes": "its public names are documented on the symsphere.render page",
    **{
        f"symsphere.apps.study.{name}": "the study's internals; symsphere.apps.study documents its interface"
        for name in ("command", "config", "figures", "findings", "report", "results", "run", "samplers")
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
    """The doc comment of constant *name* of a module, following ``from .x import name`` (or ``*``); or None."""
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
                source = importlib.util.resolve_name("." * node.level + (node.module or ""), package)
                if alias.name == "*" and name in getattr(importlib.import_module(source), "__all__", ()):
                    found = doc_comment(source, name, _seen)
                    if found:
                        return found
                elif (alias.asname or alias.name) == name:
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


# --- every code block of the narrative pages runs ---------------------------------------------------
#
# The README and the pages under docs/ are read as a reader would copy from them: every ``python`` block
# runs, in order, in one namespace per page (as in a notebook); every ``pycon`` block is a doctest in that
# namespace; every ``$ symsphere ...`` or ``$ python scripts/...`` line of a ``console`` block runs and must
# exit 0; every ``toml`` block with a ``[camera]`` loads as a scene, every ``xml`` block parses.  A block
# that would run for minutes (or times something) is marked by a comment on the line before it,
# ``<!-- not run: the reason -->``.  A ``print(...)`` whose comment ends in True/False (before any
# colon) must print those words last: ``print(x.passed)  # True`` is checked, not just run.  The pages
# run in fresh processes, in a temporary folder that links the repository's src/, scripts/ and
# benchmarks/ (the console blocks say "from the repository's root"), so no output lands in the checkout.

FENCE = re.compile(r"^```\s*(\S*)")  # the info string: a language, or a MyST directive {toctree}
NOT_RUN = re.compile(r"^<!-- not run: (.+?) -->$")
# Pages whose blocks are not run yet, and why (each a page another change is rewriting at the same time).
NOT_YET_RUN: dict[str, str] = {}
CONSOLE_COMMANDS = ("symsphere", "python")


def doc_pages():
    pages = ["README.md", *sorted(str(p.relative_to(ROOT)) for p in (ROOT / "docs").rglob("*.md"))]
    return [p for p in pages if not p.startswith("docs/_build/")]


def code_blocks(text):
    """(language, code, first line number, reason it is not run or None) of every fenced block."""
    blocks, lines, i = [], text.splitlines(), 0
    while i < len(lines):
        match = FENCE.match(lines[i])
        if match is None:
            i += 1
            continue
        before = next((lines[j].strip() for j in range(i - 1, -1, -1) if lines[j].strip()), "")
        skip = NOT_RUN.match(before)
        end = next(j for j in range(i + 1, len(lines)) if lines[j].startswith("```"))
        blocks.append((match[1], "\n".join(lines[i + 1 : end]) + "\n", i + 2, skip[1] if skip else None))
        i = end + 1
    return blocks


_RUNNER = r"""
import ast, doctest, io, json, re, sys, contextlib

blocks = json.load(open(sys.argv[1], encoding="utf-8"))
namespace = {"__name__": "__docs__"}
BOOLS = re.compile(r"#\s*([^:]*?)\s*(?::|$)")


def __doc_check__(where, expected, *args, **kwargs):
    buffer = io.StringIO()
    print(*args, **kwargs, file=buffer)
    text = buffer.getvalue()
    sys.stdout.write(text)
    words = text.split()
    if words[-len(expected):] != expected:
        raise AssertionError(f"{where}: printed {text.strip()!r}, the page says it ends in {' '.join(expected)!r}")


class Checked(ast.NodeTransformer):
    def __init__(self, lines, where):
        self.lines, self.where = lines, where

    def visit_Expr(self, node):
        call = node.value
        if isinstance(call, ast.Call) and isinstance(call.func, ast.Name) and call.func.id == "print":
            line = self.lines[node.end_lineno - 1]
            comment = line[line.find("#"):] if "#" in line else ""
            found = BOOLS.match(comment)
            words = found[1].split() if found else []
            tail = []
            for word in reversed(words):
                if word.strip(",") not in ("True", "False"):
                    break
                tail.insert(0, word.strip(","))
            if tail:
                where = f"{self.where}, line {node.lineno}"
                check = ast.Name("__doc_check__", ast.Load())
                head = [ast.Constant(where), ast.List([ast.Constant(w) for w in tail], ast.Load())]
                node.value = ast.Call(check, head + call.args, call.keywords)
                ast.fix_missing_locations(node)
        return node


namespace["__doc_check__"] = __doc_check__
for language, code, where in blocks:
    if language == "python":
        tree = Checked(code.splitlines(), where).visit(ast.parse(code))
        exec(compile(tree, where, "exec"), namespace)
    else:
        test = doctest.DocTestParser().get_doctest(code, namespace, where, where, 0)
        runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
        runner.run(test, clear_globs=False)
        if runner.failures:
            sys.exit(f"{where}: {runner.failures} doctest example(s) failed (output above)")
        namespace = test.globs
"""


@functools.cache
def _mitsuba_reason():
    """None if Mitsuba's llvm_ad_rgb variant runs here, else why not (as tests/mitsuba/conftest.py probes)."""
    try:
        import drjit as dr
        import mitsuba as mi

        mi.set_variant("llvm_ad_rgb")
        dr.eval(dr.arange(mi.Float, 4) * 2)
    except Exception as error:  # ImportError, or an LLVM that does not load
        return f"Mitsuba 3's llvm_ad_rgb variant does not run here: {error}"
    return None


def _needs(blocks, page):
    """The blocks to run, and why the rest were left out (None: all of them).

    Without Mitsuba the page runs up to its first block that imports it, and the test then skips with the
    reason (under ``SYMSPHERE_REQUIRE_MITSUBA=1``, as in CI, it fails instead).  A page that uses
    symsphere.distributed skips without the extra 'distributed'.
    """
    code = "".join(c for language, c, _, skip in blocks if language in ("python", "pycon") and skip is None)
    if "distributed" in code:
        pytest.importorskip("dask.distributed", reason=f"{page} needs the extra 'distributed'")
    first = next((i for i, (_, c, _, skip) in enumerate(blocks) if skip is None and "import mitsuba" in c), None)
    if first is None or (reason := _mitsuba_reason()) is None:
        return blocks, None
    if os.environ.get("SYMSPHERE_REQUIRE_MITSUBA") == "1":
        pytest.fail(f"SYMSPHERE_REQUIRE_MITSUBA=1, but {page} cannot run: {reason}")
    return blocks[:first], f"{page}: ran the blocks before line {blocks[first][2]}; the rest need Mitsuba. {reason}"


def _page_params():
    params = []
    for page in doc_pages():
        marks = (
            [pytest.mark.xdist_group("dask")]
            if "from symsphere import distributed" in (ROOT / page).read_text(encoding="utf-8")
            else []
        )
        if page in NOT_YET_RUN:
            marks.append(pytest.mark.skip(reason=NOT_YET_RUN[page]))
        params.append(pytest.param(page, marks=marks, id=page))
    return params


@pytest.mark.parametrize("page", _page_params())
def test_every_code_block_of_the_page_runs(page, tmp_path):
    blocks, left_out = _needs(code_blocks((ROOT / page).read_text(encoding="utf-8")), page)
    for name in ("src", "scripts", "benchmarks"):
        (tmp_path / name).symlink_to(ROOT / name)
    runnable = []
    for language, code, line, skip in blocks:
        where = f"{page}:{line}"
        if skip is not None:
            continue
        if language in ("python", "pycon"):
            runnable.append((language, code, where))
        elif language == "console":
            _run_console(code, where, tmp_path)
        elif language == "toml":
            import tomllib

            data = tomllib.loads(code)
            if "camera" in data:
                from symsphere.render import scene_from_dict

                scene_from_dict(data, source=where)
        elif language == "xml":
            import xml.etree.ElementTree as ElementTree

            ElementTree.fromstring(code)
        elif language in ("sh", "bash"):
            # The CLI's examples are console blocks, so that they run; sh blocks are set-up (make, pip, dask).
            assert not re.search(r"^\s*symsphere\s", code, flags=re.MULTILINE), f"{where}: make it a console block"
    if runnable:
        run = _run_blocks(runnable, tmp_path)
        assert run.returncode == 0, f"{page}: a block failed\n{run.stdout[-3000:]}\n{run.stderr[-3000:]}"
    if left_out is not None:
        pytest.skip(left_out)


def _run_blocks(runnable, folder):
    script = folder / "blocks.json"
    script.write_text(json.dumps(runnable), encoding="utf-8")
    return fresh_processes.run(["-c", _RUNNER, str(script)], folder)  # a new process, as a reader's


def test_runner_checks_what_the_page_says_it_prints(tmp_path):
    # the probes: a print whose comment claims the wrong truth value, and a doctest with the wrong output
    ok = _run_blocks(
        [("python", "x = 2\nprint(x == 2)  # True: two\n", "p:1"), ("pycon", ">>> x\n2\n", "p:4")], tmp_path
    )
    assert ok.returncode == 0, ok.stderr
    wrong = _run_blocks([("python", "print(1 == 2, 3)  # False True\n", "p:1")], tmp_path)
    assert wrong.returncode != 0 and "the page says it ends in 'False True'" in wrong.stderr
    doctest_wrong = _run_blocks([("pycon", ">>> 1 + 1\n3\n", "p:1")], tmp_path)
    assert doctest_wrong.returncode != 0 and "doctest example(s) failed" in doctest_wrong.stderr


def _run_console(code, where, folder):
    for line in code.splitlines():
        if not line.startswith("$ "):
            continue  # a command's output, shown
        words = shlex.split(line[2:], comments=True)
        assert words and words[0] in CONSOLE_COMMANDS, f"{where}: {words[0]!r} is not run here; mark the block"
        argv = ["-m", "symsphere", *words[1:]] if words[0] == "symsphere" else words[1:]
        run = fresh_processes.run(argv, folder)
        assert run.returncode == 0, f"{where}: {line}\n{run.stdout[-2000:]}\n{run.stderr[-2000:]}"


def test_pages_not_run_yet_exist_or_are_expected():
    # an entry for a page that is gone (or renamed) would hide nothing and should go
    stale = [page for page in NOT_YET_RUN if not (ROOT / page).exists()]
    assert stale == []


def test_blocks_not_run_are_few_and_say_why():
    skipped = [
        (page, line, reason)
        for page in doc_pages()
        if page not in NOT_YET_RUN
        for _, _, line, reason in code_blocks((ROOT / page).read_text(encoding="utf-8"))
        if reason is not None
    ]
    assert all(len(reason) > 20 for _, _, reason in skipped), skipped
    assert len(skipped) <= 8, skipped  # a new one needs a reason good enough to raise this


def test_code_block_parser_sees_the_blocks_and_the_marks():
    text = "a\n\n<!-- not run: takes an hour on two cores -->\n```python\nx = 1\n```\n\n```console\n$ symsphere --help\n```\n"
    assert code_blocks(text) == [
        ("python", "x = 1\n", 5, "takes an hour on two cores"),
        ("console", "$ symsphere --help\n", 9, None),
    ]


def test_cli_reference_is_generated_from_the_parser():
    run = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "cli_reference.py"), "--check"], capture_output=True, text=True
    )
    assert run.returncode == 0, run.stderr


# --- the shape the reader meets -----------------------------------------------------------------------

MACHINE_OR_DATE = re.compile(r"\b(?:AMD|EPYC|Xeon|Intel|Zen ?\d|load average|\d{4}-\d\d-\d\d|\d\d:\d\d UTC)\b")
GENERATED_TABLE = re.compile(r"<!-- table: [^>]*-->.*?<!-- /table -->", flags=re.DOTALL)


def test_readme_is_a_front_page():
    lines = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 200
    assert any(line.startswith("pip install") for line in lines[:40]), "installation within the first 40 lines"


@pytest.mark.parametrize("page", [p for p in doc_pages() if p not in NOT_YET_RUN])
def test_page_is_short_and_dates_and_machines_stay_in_the_results(page):
    text = (ROOT / page).read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 400, f"{page}: split it (no page over 400 lines)"
    if not page.startswith("docs/results/"):
        # a generated table (the README's speed sentence) comes from a results file, machine and all
        found = MACHINE_OR_DATE.findall(GENERATED_TABLE.sub("", text))
        assert found == [], f"{page}: dates and machines belong in docs/results/, found {found}"


def test_machine_and_date_pattern_sees_them():
    probe = "measured on a 2-core AMD EPYC at 05:43 UTC on 2026-11-22 (load average 3)"
    assert MACHINE_OR_DATE.findall(probe) == ["AMD", "EPYC", "05:43 UTC", "2026-11-22", "load average"]
    assert MACHINE_OR_DATE.findall("pick Lebedev for smooth f; 48 maps; n = 786 432") == []
