# Quickstart targets: `make run` and `make test` work on a fresh machine with only Python 3 and pip.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: setup run demo test test-fast test-slow lint fmus native campaign wheel crosscheck embedded clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	@# the C twin where a C compiler exists (else everything runs in Python; the reason is printed)
	$(BIN)/python -c "from fusion_core import native; print('native twin:', native.reason() or native.build())"
	touch $(STAMP)

setup: $(STAMP)

# The campaign's exit status is 1 when a contract check FAILs (the table says which, and why);
# `make run` reports that verdict and exits 0, failing only when the campaign could not run.
run: setup
	$(BIN)/python build_fmu.py --out dist
	$(BIN)/python -m testbenches run --out reports; status=$$?; \
	  if [ $$status -eq 1 ]; then echo "make run: some contract checks FAIL (see the table above and reports/report.md)"; \
	  elif [ $$status -ne 0 ]; then exit $$status; fi

# A Monte Carlo campaign on a local Dask cluster (two workers): 5 estimators x 5 scenarios x 700
# seeds, each seed another sensor part with its bias instability and gyro scale error drawn from a
# Latin hypercube; percentiles with confidence intervals in reports/campaign/summary.md.
# Run it again and it runs only what is missing.
campaign: setup
	$(BIN)/python -m testbenches campaign --estimator all \
	  --scenario moderate_dynamics,vibration,high_dynamics,shaking,gyro_clipping --seeds 700 \
	  --vary gyro_bias_instability=1e-5:1e-3:log --vary gyro_scale_std=0:0.03 \
	  --out reports/campaign

demo: setup
	$(BIN)/python -m fusion_core.demo

fmus: setup
	$(BIN)/python build_fmu.py --out dist

# The C twin of fusion_core as a shared library (built on first use anyway; this says where).
native: setup
	$(BIN)/python -c "from fusion_core import native; print(native.build())"

# The native FMUs with fusion_core's reference results and fmpy's in the FMI Cross-Check layout,
# validated by fmpy's cross-check tools (reports/crosscheck/).
crosscheck: setup
	$(BIN)/python build_fmu.py --out dist --kind native
	$(BIN)/python -m testbenches crosscheck --fmu-dir dist --out reports/crosscheck

# The C twin on an Arm Cortex-M under QEMU (double on a Cortex-M7, float on a Cortex-M4F): its
# outputs against the desktop's, instructions per sample, RAM and flash (build/embedded/).
# Needs gcc-arm-none-eabi, libnewlib-arm-none-eabi and qemu-system-arm; says so where missing.
embedded: setup
	$(BIN)/python -m testbenches.embedded

# The sdist and a platform wheel carrying the C twin's library and the native FMUs (setup.py).
wheel: setup
	$(BIN)/python -m build --no-isolation --outdir dist-wheel .

# On every core, with the reason of each skipped test listed at the end.
test: setup
	$(BIN)/python -m pytest -q -n auto --dist loadgroup -rs

# The fast tier: everything but the tests that need built FMUs, the heavy integration runs and
# the slow campaigns, on two workers.
test-fast: setup
	$(BIN)/python -m pytest -q -n 2 --dist loadgroup -m 'not slow and not fmu and not heavy'

test-slow: setup
	$(BIN)/python -m pytest -q -m slow

lint: setup
	$(BIN)/ruff check .
	$(BIN)/mypy fusion_core  # the reference is typed: mypy-clean

.PHONY: bench
bench: setup
	$(BIN)/python -m pip install --quiet -e '.[test,bench]'
	$(BIN)/python -m benchmarks --out reports

clean:
	rm -rf dist dist-wheel reports build *.egg-info
