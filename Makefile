# Two commands do all the set-up on a fresh machine (Python >= 3.11 with pip and venv):
#   make demo   install into .venv, then sample, test uniformity and write symsphere-demo/report.md
#   make test   install into .venv (with the test extras), then run the whole test suite
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test bench clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[test,distributed]"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/symsphere demo

test: $(STAMP)
	$(BIN)/python -m pytest

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_sample.py

clean:
	rm -rf $(VENV) symsphere-demo .pytest_cache
