# The two front-door commands: `make demo` and `make test`. Both set up .venv when needed.
PYTHON ?= python3.11
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test check setup clean bench

# HEARTBEAT: run a quiet command, saying every 3 s that it still runs (setup stays silent otherwise)
HEARTBEAT = sh -c 'label="$$1"; shift; "$$@" & pid=$$!; n=0; \
	while kill -0 $$pid 2>/dev/null; do sleep 1; n=$$((n + 1)); \
	if [ $$((n % 3)) -eq 0 ] && kill -0 $$pid 2>/dev/null; then echo "  $$label ... $$n s"; fi; done; wait $$pid' heartbeat

$(BIN)/python:
	@command -v $(PYTHON) >/dev/null 2>&1 || { echo "error: $(PYTHON) not found; lmsbench needs CPython 3.11 (set PYTHON=/path/to/python3.11)"; exit 1; }
	@echo "creating $(VENV) with $(PYTHON) ..."
	@$(HEARTBEAT) "creating $(VENV)" $(PYTHON) -m venv $(VENV)
	@$(HEARTBEAT) "upgrading pip" $(BIN)/python -m pip install --quiet --upgrade pip

$(STAMP): $(BIN)/python pyproject.toml
	@echo "installing lmsbench and its dependencies into $(VENV) (once; about a minute) ..."
	@$(HEARTBEAT) "installing" $(BIN)/python -m pip install --quiet -e ".[test]"
	@touch $(STAMP)

setup: $(STAMP)

demo: $(STAMP)
	$(BIN)/lmsbench demo

# static checks: ruff on everything, mypy on the packages listed in pyproject.toml ([tool.mypy] files)
check: $(STAMP)
	$(BIN)/ruff check --no-cache .
	$(BIN)/mypy

# the tests on every core and one worker more, for the tests that wait (pytest-xdist; the count: tests/conftest.py;
# the numba kernels are compiled once, before the workers start:
# tests/conftest.py, which also starts the modules with a test marked slow first; --dist worksteal: a worker
# whose queue is empty takes queued tests from the other's, where the default "load" keeps each queue);
# `-n 0` in PYTEST_ARGS runs them in this process, one by one. The static checks run beside two quiet
# processes that compile most kernels first (tests/warm_kernels.py: ~85 s of CPU on a fresh checkout,
# which conftest's warm-up spent alone after the checks; it then loads them from numba's cache)
test: $(STAMP)
	@$(BIN)/python tests/warm_kernels.py sensor >/dev/null 2>&1 & sensor=$$!; \
	$(BIN)/python tests/warm_kernels.py others >/dev/null 2>&1 & others=$$!; \
	$(MAKE) --no-print-directory check || { kill $$sensor $$others 2>/dev/null; exit 2; }; wait $$sensor $$others || true
	$(BIN)/python -m pytest -q -rs --durations=30 -n auto --dist worksteal $(PYTEST_ARGS)

bench: $(STAMP)
	$(BIN)/lmsbench bench

clean:
	rm -rf $(VENV) results .pytest_cache
