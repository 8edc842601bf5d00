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
	$(BIN)/python -m pip install --quiet -e ".[dev,dask,parquet]"
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
	$(BIN)/mypy tactile_kb explorers/mujoco/tactile_kb_mujoco

docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict --site-dir .site

# On a fresh clone the core suite runs before the MuJoCo plugin is installed, which shows the
# core works without it; then the plugin is installed and its tests (with the explorer contract
# suite) and its docs page run.
test: lint typecheck docs
	$(BIN)/python -m pytest -q --ignore=docs/mujoco.md
	$(MAKE) --no-print-directory $(PLUGIN_STAMP)
	$(BIN)/python -m pytest -q explorers/mujoco/tests docs/mujoco.md

gallery: $(STAMP)
	$(BIN)/python -m tactile_kb.gallery docs/gallery

bench: $(PLUGIN_STAMP)
	$(BIN)/python benchmarks/run.py

clean:
	rm -rf $(VENV) .site .mypy_cache .pytest_cache .ruff_cache
