"""Write docs/reference/cli.md from the ``symsphere`` command's own parser.

    python scripts/cli_reference.py            # rewrite the page
    python scripts/cli_reference.py --check    # exit 1 if the page differs from the parser

tests/test_docs.py runs the check, so the page cannot drift from ``symsphere VERB --help``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from symsphere.apps.cli import build_parser

PAGE = Path(__file__).resolve().parent.parent / "docs" / "reference" / "cli.md"

HEADER = """# The `symsphere` command

Generated from the command's parser by `python scripts/cli_reference.py`; `symsphere VERB --help` prints
the same. Examples of each verb in use: [getting started](../tutorials/getting-started.md),
[integrate](../tutorials/integrate.md), [render with Mitsuba 3](../tutorials/render-with-mitsuba.md),
[reproduce a figure](../how-to/reproduce-a-figure.md).

**Exit status:** 0 on success; 2 for invalid arguments (one line on stderr naming the argument and what is
allowed, never a traceback); 1 when the output cannot be written; 130 on Ctrl-C, 143 on SIGTERM and 129 on
SIGHUP. The files of a run appear together and complete, or not at all. Work estimated to take more than
a day is refused unless `--allow-long`. Set `SYMSPHERE_TRACEBACK=1` to see the traceback of an unexpected
error. The messages themselves: [error messages](errors.md).
"""


def _cell(text: str) -> str:
    return " ".join(text.split()).replace("|", "\\|")


def _values(action: argparse.Action) -> str:
    parts = []
    if action.choices is not None:
        parts.append(", ".join(f"`{c}`" for c in action.choices))
    elif action.nargs == 0:
        parts.append("flag")
    elif action.metavar is not None:
        shown = " ".join(action.metavar) if isinstance(action.metavar, tuple) else action.metavar
        parts.append(f"`{shown}`")
    if action.default not in (None, False, argparse.SUPPRESS):
        parts.append(f"default `{action.default}`")
    return "; ".join(parts)


def render_page() -> str:
    parser = build_parser()
    verbs = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    lines = [HEADER]
    for name, verb in verbs.choices.items():
        lines += [f"## `symsphere {name}`", ""]
        if verb.description:
            lines += [" ".join(verb.description.split()), ""]
        lines += ["| option | values | what |", "|---|---|---|"]
        for action in verb._actions:
            if not action.option_strings or "--help" in action.option_strings:
                continue
            help_text = (action.help or "") % {"default": action.default} if action.help else ""
            required = " (required)" if action.required else ""
            options = ", ".join(f"`{o}`" for o in action.option_strings)
            lines.append(f"| {options}{required} | {_cell(_values(action))} | {_cell(help_text)} |")
        lines.append("")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="compare instead of writing")
    args = parser.parse_args(argv)
    text = render_page()
    if args.check:
        if PAGE.read_text(encoding="utf-8") != text:
            print(f"{PAGE} differs from the parser: run python scripts/cli_reference.py", file=sys.stderr)
            return 1
        return 0
    PAGE.write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
