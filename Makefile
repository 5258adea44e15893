# `make demo` and `make test` build .venv from pyproject.toml and refresh it when pyproject changes.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test test-slow lint typecheck bench fuzz clean browser

# Where the environment sets PYTHONDONTWRITEBYTECODE, every test run would compile the project
# and re-run pytest's assertion rewriting of every test module in every worker (about 6 s of
# each worker's start here); the test targets let Python keep its bytecode caches.
PYTEST := PYTHONDONTWRITEBYTECODE= $(BIN)/python -m pytest

FUZZ_CASES ?= 1000
FUZZ_ARGS  ?=

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev,robots,dask]'
	touch $(STAMP)

demo: $(STAMP)
	mkdir -p out
	$(BIN)/synth plan fixtures/tasks/seed_4_8.yaml -o out/seed_4_8.al --svg out/seed_4_8_plan.svg
	$(BIN)/synth view fixtures/tasks/seed_4_8.yaml out/seed_4_8.al -o out/seed_4_8_view.html
	$(BIN)/synth errors fixtures/tasks/seed_4_8.yaml --from BH1 --to PIN1
	$(BIN)/synth errors fixtures/tasks/screw_on_driver.yaml --from hole --to tip

lint: $(STAMP)
	$(BIN)/ruff check synth server tests benchmarks
	$(BIN)/ruff format --check synth server tests benchmarks

typecheck: $(STAMP)
	$(BIN)/mypy

# The browser test of `synth view` renders the page in Debian's headless Chromium: install it when
# root and missing (tests/test_view_browser.py skips, saying why, where it cannot be installed).
browser:
	@command -v chromium >/dev/null 2>&1 || { [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1 \
	  && { DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends chromium \
	       || { apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends chromium; }; } \
	  || echo "chromium not installed: the browser test will skip"; }

# The default suite leaves out the long Monte Carlo runs (pytest -m "not slow", pyproject.toml)
# and spreads the tests over the cores (work stealing: a worker left with long tests at the end
# hands them to an idle one); `make test-slow` runs the rest.
test: $(STAMP) lint typecheck browser
	$(PYTEST) -n auto --dist worksteal

test-slow: $(STAMP)
	$(PYTEST) -n auto --dist worksteal -m slow

bench: $(STAMP)
	for b in benchmarks/*.py; do $(BIN)/python $$b || exit 1; done

# N hostile cases per surface (task specs, AL programs, the API); a table of counts (docs/api.md).
fuzz: $(STAMP)
	$(BIN)/python tests/fuzz/fuzzrun.py --cases $(FUZZ_CASES) $(FUZZ_ARGS)

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache .ruff_cache .mypy_cache
