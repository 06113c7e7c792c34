# Needs only python3 and make: the first run creates .venv and installs hoseline into it.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin

.PHONY: demo test bench clean fuzz
.DELETE_ON_ERROR:

demo: $(VENV)/.installed-test
	$(BIN)/hoseline demo

test: $(VENV)/.installed-test
	$(BIN)/python -m pytest

bench: $(VENV)/.installed-bench
	$(BIN)/python bench/run.py
	$(BIN)/python bench/bench_sweep.py

clean:
	rm -rf $(VENV) out build dist *.egg-info .pytest_cache

$(BIN)/python:
	$(PYTHON) -m venv $(VENV) || { echo "could not create $(VENV): on Debian/Ubuntu install python3-venv"; exit 1; }
	$(BIN)/python -m pip install --quiet --upgrade pip

# A stamp per extra; pip runs again when pyproject.toml changes.  Then the solver's kernels are compiled into
# the installation's cache (hoseline compile, about a minute once), as an ahead-of-time build would: no run
# after `make` waits for the compiler.
$(VENV)/.installed-%: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[$*]'
	$(BIN)/hoseline compile
	touch $@

# The long fuzzing campaign (README, Fuzzing): 10 000 generated inputs through the command line.
fuzz: $(VENV)/.installed-test
	$(BIN)/python bench/fuzz.py --count 10000
