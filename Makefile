# The two front-door commands: `make demo` and `make test`. Both set up .venv when needed.
PYTHON ?= python3.11
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test check setup clean bench

$(BIN)/python:
	@command -v $(PYTHON) >/dev/null 2>&1 || { echo "error: $(PYTHON) not found; lmsbench needs CPython 3.11 (set PYTHON=/path/to/python3.11)"; exit 1; }
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(STAMP): $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install --quiet -e ".[test]"
	@touch $(STAMP)

setup: $(STAMP)

demo: $(STAMP)
	$(BIN)/lmsbench demo

# static checks: ruff on everything, mypy on the packages listed in pyproject.toml ([tool.mypy] files)
check: $(STAMP)
	$(BIN)/ruff check --no-cache .
	$(BIN)/mypy

test: check
	$(BIN)/python -m pytest -q -rs

bench: $(STAMP)
	$(BIN)/lmsbench bench

clean:
	rm -rf $(VENV) results .pytest_cache
