# Two commands do all the set-up on a fresh machine (Python >= 3.11 with pip and venv):
#   make demo   install into .venv, then sample, test uniformity and write symsphere-demo/report.md
#   make test   install into .venv (with the test extras, and Mitsuba 3: the extra mitsuba), then run the whole test
#               suite in parallel (pytest-xdist, one worker per core; the 20 slowest tests are listed at the end)
#   make docs   install the docs extra too, then build the HTML docs (docs/_build/html; warnings are errors)
#   make gallery  redraw the docs' gallery (docs/images/gallery) from the library
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
DOCS_STAMP := $(VENV)/.docs-installed

.PHONY: demo test mitsuba-setup libllvm bench bench-tables docs gallery clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[test,distributed]"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/symsphere demo

# -n auto: one worker per core; --dist loadgroup: the tests marked xdist_group("dask") (each starts a local
# Dask cluster of worker processes) run on one worker, one after another.  A single file runs serially as
# before: .venv/bin/python -m pytest tests/test_x.py
# OPENBLAS_NUM_THREADS=1 unless set: each worker has its core, and numpy's BLAS threads beside the other
# worker only wait for a core (docs/results/test-times.md: CPU time of the suite's files with one and two).
# compileall: src/'s bytecode written once before the run (an editable install has none).  Where
# PYTHONDONTWRITEBYTECODE is set (it is on the machines the suite is timed on), Python caches none, and each
# process the suite starts (the docs' pages, the CLI, Dask workers) would compile the package's source again.
test: $(STAMP) mitsuba-setup
	$(BIN)/python -m compileall -q src
	OPENBLAS_NUM_THREADS=$${OPENBLAS_NUM_THREADS:-1} $(BIN)/python -m pytest -n auto --dist loadgroup --durations=20

# The Mitsuba 3 tests (tests/mitsuba) need the extra "mitsuba" and, for the LLVM variants, libLLVM >= 16
# (the target libllvm).  Without them the tests skip with the reason; .ci/run sets SYMSPHERE_REQUIRE_MITSUBA=1,
# which makes a missing Mitsuba an error.
mitsuba-setup: $(STAMP) libllvm
	@$(BIN)/python -c "import mitsuba, drjit" 2>/dev/null || $(BIN)/python -m pip install --quiet -e ".[mitsuba]" \
		|| echo "test: could not install the extra 'mitsuba'; tests/mitsuba will be skipped"

# libLLVM >= 16 for Mitsuba's LLVM variants (drjit finds it, or DRJIT_LIBLLVM_PATH names it): Debian's
# libllvm19, installed here as root with apt; elsewhere one line says how.  Without it tests/mitsuba skip
# and bench_sample.py skips its Mitsuba cases.
libllvm: $(STAMP)
	@if $(BIN)/python benchmarks/bench_sample.py --find-llvm >/dev/null; then :; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
		echo "installing libllvm19 for Mitsuba's LLVM backend (apt-get)"; \
		(apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libllvm19) \
			|| echo "apt-get install libllvm19 failed; Mitsuba's LLVM variants cannot run"; \
	else \
		echo "for Mitsuba's LLVM variants run 'sudo apt-get install libllvm19' (or set DRJIT_LIBLLVM_PATH to a libLLVM >= 16)"; \
	fi

# make bench: the speed benchmarks (docs/results/bench-sample.md and the other benchmark pages of docs/results/), then the tables written from their results.  Mitsuba 3 (the optional extra "bench") is
# a peer in the comparison; its LLVM backend needs libLLVM >= 16 (the target libllvm).  Both are optional:
# if either cannot be installed, bench_sample.py says why and skips the Mitsuba cases.
bench: $(STAMP) libllvm
	$(BIN)/python -c "import mitsuba" 2>/dev/null || $(BIN)/python -m pip install --quiet -e ".[bench]" \
		|| echo "bench: could not install mitsuba (the extra 'bench'); the Mitsuba cases will be skipped"
	$(BIN)/python benchmarks/bench_sample.py --json benchmarks/results/bench_sample.json
	$(BIN)/python benchmarks/first_sample.py
	$(BIN)/python benchmarks/bench_render.py equal-time
	$(BIN)/python benchmarks/tables.py

# make bench-tables: rewrite the generated tables of the docs (<!-- table: ... --> blocks) from the committed
# results files, without timing anything; tests/test_benchmark_tables.py checks that they are up to date.
bench-tables: $(STAMP)
	$(BIN)/python benchmarks/tables.py

# make docs: Sphinx + numpydoc API reference and the Markdown pages (docs/conf.py).  -E re-reads
# every page, so that a warning in an unchanged page still fails the next build too.
$(DOCS_STAMP): $(STAMP)
	$(BIN)/python -m pip install --quiet -e ".[docs]"
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)
	$(BIN)/python -m sphinx -E -W --keep-going -b html docs docs/_build/html

# make gallery: every picture of docs/results/gallery.md, drawn from the library (seconds; tests/test_gallery.py
# runs it small).
gallery: $(STAMP)
	$(BIN)/python scripts/gallery.py

clean:
	rm -rf $(VENV) symsphere-demo .pytest_cache
