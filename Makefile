# The README's two commands: `make demo` (the main job) and `make test` (the whole suite).
# Both create or reuse the local virtual environment .venv by themselves.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
PLUGIN_STAMP := $(VENV)/.installed-mujoco

.PHONY: demo test lint typecheck docs bench gallery clean

# pip's own output (each package as it is collected and installed) shows the progress.
$(STAMP): pyproject.toml
	@test -x $(BIN)/python || { echo ">> creating the virtual environment $(VENV)"; $(PYTHON) -m venv $(VENV); }
	@echo ">> installing tactile-kb into $(VENV) with its dependencies (numpy, scipy, sympy, dd,"
	@echo ">> trimesh, matplotlib, ...) and the development tools (pytest, hypothesis, ruff, mypy,"
	@echo ">> mkdocs) and the batch extras (dask, distributed, pyarrow): a few minutes the first"
	@echo ">> time, seconds afterwards"
	$(BIN)/python -m pip install --upgrade pip
	$(BIN)/python -m pip install -e ".[dev,dask,parquet]"
	@touch $(STAMP)
	@echo ">> installed; the next runs reuse $(VENV)"

$(PLUGIN_STAMP): $(STAMP) explorers/mujoco/pyproject.toml
	@echo ">> installing the MuJoCo explorer plugin (mujoco) into $(VENV)"
	$(BIN)/python -m pip install -e ./explorers/mujoco
	@touch $(PLUGIN_STAMP)

demo: $(STAMP)
	$(BIN)/tactile-kb demo

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/lint-imports --no-cache

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
	cd explorers/mujoco && ../../$(BIN)/lint-imports --no-cache
	$(BIN)/python -m pytest -q explorers/mujoco/tests docs/mujoco.md

gallery: $(STAMP)
	$(BIN)/python -m tactile_kb.gallery docs/gallery

bench: $(PLUGIN_STAMP)
	$(BIN)/python benchmarks/run.py

clean:
	rm -rf $(VENV) .site .mypy_cache .pytest_cache .ruff_cache
