# Quickstart targets: `make run` and `make test` work on a fresh machine with only Python 3 and pip.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: setup run demo test test-slow lint fmus clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

setup: $(STAMP)

run: setup
	$(BIN)/python build_fmu.py --out dist
	$(BIN)/python -m testbenches run --out reports

demo: setup
	$(BIN)/python -m fusion_core.demo

fmus: setup
	$(BIN)/python build_fmu.py --out dist

test: setup
	$(BIN)/python -m pytest -q

test-slow: setup
	$(BIN)/python -m pytest -q -m slow

lint: setup
	$(BIN)/ruff check .
	$(BIN)/mypy fusion_core  # mypy-clean: what mypyc compiles (fmu_src/compiled_core.py)

.PHONY: bench
bench: setup
	$(BIN)/python -m pip install --quiet -e '.[test,bench]'
	$(BIN)/python -m benchmarks --out reports

clean:
	rm -rf dist reports build *.egg-info
