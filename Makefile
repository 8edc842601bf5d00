# The README's two commands: `make demo` (the main job) and `make test` (the whole suite).
# Both create or reuse the local virtual environment .venv by themselves.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
PLUGIN_STAMP := $(VENV)/.installed-mujoco

.PHONY: demo test lint typecheck docs bench gallery clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

$(PLUGIN_STAMP): $(STAMP) explorers/mujoco/pyproject.toml
	$(BIN)/python -m pip install --quiet -e ./explorers/mujoco
	touch $(PLUGIN_STAMP)

demo: $(STAMP)
	$(BIN)/tactile-kb demo

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

typecheck: $(STAMP)
	$(BIN)/mypy tactile_kb

docs: $(STAMP)
	$(BIN)/mkdocs build --strict --quiet --site-dir .site

test: $(PLUGIN_STAMP) lint typecheck docs
	$(BIN)/python -m pytest -q
	$(BIN)/python -m pytest -q explorers/mujoco/tests

bench: $(PLUGIN_STAMP)
	$(BIN)/python benchmarks/run.py

clean:
	rm -rf $(VENV) .site .mypy_cache .pytest_cache .ruff_cache
