# `make demo` and `make test` build .venv from pyproject.toml and refresh it when pyproject changes.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test lint typecheck bench fuzz clean

FUZZ_CASES ?= 1000
FUZZ_ARGS  ?=

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev,robots,dask]'
	touch $(STAMP)

demo: $(STAMP)
	mkdir -p out
	$(BIN)/synth plan fixtures/tasks/seed_4_8.yaml -o out/seed_4_8.al
	$(BIN)/synth errors fixtures/tasks/seed_4_8.yaml --from BH1 --to PIN1
	$(BIN)/synth errors fixtures/tasks/screw_on_driver.yaml --from hole --to tip

lint: $(STAMP)
	$(BIN)/ruff check synth server tests benchmarks
	$(BIN)/ruff format --check synth server tests benchmarks

typecheck: $(STAMP)
	$(BIN)/mypy

test: $(STAMP) lint typecheck
	$(BIN)/python -m pytest

bench: $(STAMP)
	for b in benchmarks/*.py; do $(BIN)/python $$b || exit 1; done

# N hostile cases per surface (task specs, AL programs, the API); a table of counts (docs/api.md).
fuzz: $(STAMP)
	$(BIN)/python tests/fuzz/fuzzrun.py --cases $(FUZZ_CASES) $(FUZZ_ARGS)

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache .ruff_cache .mypy_cache
