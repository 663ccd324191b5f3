# Two commands set everything up: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test test-py310 lint typecheck unit bench clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev,viz,ompl,cluster]'
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/sdar demo

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

typecheck: $(STAMP)
	$(BIN)/mypy

# -n auto: one process per CPU, at most four (tests/conftest.py); a module's tests stay in one.
unit: $(STAMP)
	$(BIN)/pytest -n auto --dist loadscope

test: lint typecheck unit

# The declared minimum Python, in its own environment: PY310 names its interpreter.
PY310 ?= python3.10
test-py310:
	$(MAKE) test VENV=.venv310 PYTHON=$(PY310)

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_classical.py

clean:
	rm -rf $(VENV) .venv310 build *.egg-info
