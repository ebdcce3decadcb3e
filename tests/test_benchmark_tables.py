"""The speed tables of the docs are what benchmarks/tables.py writes from the committed results files.

Nothing is timed here: the check regenerates every ``<!-- table: ... -->`` block from its JSON file
and compares the text, so a number edited by hand, a results file replaced without ``make
bench-tables``, or a change of the measured code without the stale note, fails.
"""

import json
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


def _benchmarks_run(code, tmp_path):
    """Run *code* with benchmarks/ on sys.path, in a numba cache of its own."""
    env = {**__import__("os").environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba"), "OMP_WAIT_POLICY": "passive"}
    return subprocess.run([sys.executable, "-c", f"import sys; sys.path.insert(0, 'benchmarks')\n{code}"],
                          capture_output=True, text=True, timeout=300, cwd=ROOT, env=env)  # fmt: skip


def test_the_write_limit_fills_write_their_bytes_and_nothing_beside(tmp_path):
    # every way of benchmarks/_write_limit.py, on slices that start off a 64-byte boundary and end inside a
    # line (the non-temporal fill's scalar head and tail), shorter and longer than one line; ~10 s (compiles)
    code = """
import numpy as np
from _write_limit import FILLS
for way, fill in FILLS.items():
    for dtype in (np.float64, np.float32):
        for start in (0, 1, 3, 5):
            for n in (0, 3, 17, 1000, 4099):
                buffer = np.zeros(n + 40, dtype)
                fill(buffer[start : start + n], 0.5)
                assert (buffer[start : start + n] == 0.5).all(), (way, dtype, start, n)
                assert not buffer[:start].any() and not buffer[start + n :].any(), (way, dtype, start, n)
print("ok", len(FILLS))
"""
    run = _benchmarks_run(code, tmp_path)
    assert run.returncode == 0 and run.stdout.split() == ["ok", "4"], run.stdout + run.stderr


def test_regress_takes_the_faster_fastest_fill_of_both_workers_as_the_limit(tmp_path):
    # medians in seconds: the base's fastest fill is "a" (2 s), the new's "b" (1.5 s): the limit is 1.5 s
    code = """
import json
from regress import table_rows, table_text
names = ["write limit: a, out= (float64)", "write limit: b, out= (float64)", "write limit: a, fresh (float64)",
         "sample_sphere, out= (float64)", "sample_sphere (float64)", "integrate"]
medians = {"base": dict(zip(names, [2.0, 4.0, 8.0, 10.0, 16.0, 1.0])),
           "new": dict(zip(names, [3.0, 1.5, 9.0, 5.0, 12.0, 1.0]))}
table = table_rows(names, medians)
print(json.dumps(table))
print(table_text({"table": table}))
"""
    run = _benchmarks_run(code, tmp_path)
    assert run.returncode == 0, run.stdout + run.stderr
    rows = {row["row"]: row for row in json.loads(run.stdout.splitlines()[0])}
    out = rows["sample_sphere, out= (float64)"]
    assert (out["limit_base"], out["limit_new"]) == ("write limit: a, out= (float64)", "write limit: b, out= (float64)")
    assert out["ceiling"] == 10.0 / 1.5 and out["base_of_limit"] == 1.5 / 10.0 and out["new_of_limit"] == 1.5 / 5.0
    fresh = rows["sample_sphere (float64)"]  # only the fresh fill: the base's 8 s
    assert fresh["ceiling"] == 16.0 / 8.0 and fresh["new_of_limit"] == 8.0 / 12.0
    assert "ceiling" not in rows["integrate"] and "ceiling" not in rows["write limit: a, out= (float64)"]
    text = run.stdout.split("\n", 1)[1]
    assert "| ceiling new / base |" in text and "| sample_sphere, out= (float64) | 10000.00 | 5000.00 | 2.00× |" in text
    assert "| write limit: b, out= (float64) — the limit |" in text and "6.67× |" in text


def test_a_change_of_code_a_run_left_out_does_not_make_it_stale(tmp_path):
    # a regress run with --no-mitsuba measured no file under src/symsphere/mitsuba/: a change there leaves its
    # table as it is; a change elsewhere in src, or the same change for a run with the Mitsuba row, makes it stale.
    # No run measures the tests' door (_testing.py), and regress.py none of the command line (apps/), which the
    # cold start's CLI rows do measure.
    code = """
import tables
current = tables.source_hashes()
mitsuba = next(p for p in current if p.startswith('src/symsphere/mitsuba/'))
kernel = 'src/symsphere/_kernels.py'
def changed(command, path):
    sources = {**current, path: '0' * 40}
    return tables._changed(('src/symsphere/',), {'command': command, 'sources': sources}, None)
print(changed('python benchmarks/regress.py --no-mitsuba', mitsuba))
print(changed('python benchmarks/regress.py', mitsuba) == [mitsuba])
print(changed('python benchmarks/regress.py --no-mitsuba --no-render', kernel) == [kernel])
cli = 'src/symsphere/apps/cli.py'
print(changed('python benchmarks/regress.py', cli), changed('python benchmarks/regress.py', 'src/symsphere/_testing.py'))
print(changed('python benchmarks/first_sample.py --cold-start', cli) == [cli])
"""
    run = _benchmarks_run(code, tmp_path)
    assert run.returncode == 0, run.stderr
    assert run.stdout.split() == ["[]", "True", "True", "[]", "[]", "True"]
