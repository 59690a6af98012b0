# rotorcheck: every target creates and uses its own virtual environment in .venv
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: venv demo test lint samples golden bench clean

$(STAMP): pyproject.toml
	$(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

venv: $(STAMP)

demo: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python -m tools.demo

test: $(STAMP)
	$(BIN)/ruff check rotorcheck tests bench tools
	$(BIN)/python -m mypy rotorcheck
	MPLBACKEND=Agg $(BIN)/python -m pytest -q -n 2 --dist loadfile

lint: $(STAMP)
	$(BIN)/ruff check rotorcheck tests bench tools
	$(BIN)/python -m mypy rotorcheck

samples: $(STAMP)
	$(BIN)/python -m tools.samples data_samples

golden: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python -m tools.golden --write

bench: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python -m bench

clean:
	rm -rf $(VENV) rotorcheck-out .pytest_cache
