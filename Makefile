# The two set-up commands of the README. Each creates .venv if needed and installs the package.
PY ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test bench clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[test]"
	touch $(STAMP)

## demo: the main job on the built-in default rig: controlled launches, verification, report
demo: $(STAMP)
	$(BIN)/wetclutch report --out out/report

## test: the whole test suite
test: $(STAMP)
	$(BIN)/python -m pytest -n 2 -q

## bench: speed benchmarks (not part of the tests)
bench: $(STAMP)
	$(BIN)/python benchmarks/bench_engine.py
	$(BIN)/python benchmarks/bench_actuator.py
	$(BIN)/python benchmarks/bench_launch.py
	$(BIN)/python benchmarks/bench_identify.py
	$(BIN)/python benchmarks/bench_compile.py
	$(BIN)/python benchmarks/bench_tune.py

clean:
	rm -rf $(VENV) out .pytest_cache
