"""The speed tables of the docs are what benchmarks/tables.py writes from the committed results files.

Nothing is timed here: the check regenerates every ``<!-- table: ... -->`` block from its JSON file
and compares the text, so a number edited by hand, a results file replaced without ``make
bench-tables``, or a change of the measured code without the stale note, fails.
"""

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TABLES = [sys.executable, str(ROOT / "benchmarks" / "tables.py")]


def _check(*paths):
    return subprocess.run([*TABLES, "--check", *map(str, paths)], capture_output=True, text=True, timeout=300,
                          cwd=ROOT)  # fmt: skip


def test_generated_tables_equal_what_their_results_files_produce():
    docs = ROOT / "docs" / "results" / "bench-sample.md"
    assert "<!-- table: " in docs.read_text(encoding="utf-8")  # the page has generated tables
    run = _check()
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr


def test_the_check_sees_a_number_edited_by_hand(tmp_path):
    text = (ROOT / "docs" / "results" / "bench-sample.md").read_text(encoding="utf-8")
    block = re.search(r"<!-- table: bench_sample from .*?<!-- /table -->", text, re.S)
    assert block is not None
    row = next(
        line for line in block.group(0).splitlines() if re.match(r"\| sample_sphere, out= \| float64 \| \d", line)
    )
    digit = re.search(r"\d", row[len("| sample_sphere, out= | float64 | ") :])
    assert digit is not None
    at = len("| sample_sphere, out= | float64 | ") + digit.start()
    edited_row = row[:at] + str((int(row[at]) + 1) % 10) + row[at + 1 :]
    path = tmp_path / "edited.md"
    path.write_text(text.replace(row, edited_row, 1), encoding="utf-8")
    run = _check(path)
    assert run.returncode == 1 and edited_row in run.stdout and row in run.stdout


def test_the_check_sees_a_speed_table_written_by_hand_without_its_date(tmp_path):
    table = "| case | median ms |\n|---|---:|\n| sample_sphere | 2.92 |\n"
    undated = tmp_path / "undated.md"
    undated.write_text("Measured today.\n\n" + table, encoding="utf-8")
    dated = tmp_path / "dated.md"
    dated.write_text("Measured today.\n\n<!-- dated 2026-11-22: measured by hand -->\n" + table, encoding="utf-8")
    other = tmp_path / "other.md"
    other.write_text("| option | values |\n|---|---|\n| --n | 48 |\n", encoding="utf-8")  # no time or rate
    run = _check(undated)
    assert run.returncode == 1 and "| case | median ms |" in run.stdout
    assert _check(dated).returncode == 0, _check(dated).stdout
    assert _check(other).returncode == 0
