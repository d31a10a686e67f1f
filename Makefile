# Two entry points (see README): `make run` and `make test`.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
OUT    ?= lab-report

.PHONY: setup run test bench clean

$(BIN)/imunav: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --upgrade pip
	$(BIN)/python -m pip install -e '.[test,learn,dask]'
	touch $(BIN)/imunav

setup: $(BIN)/imunav

run: setup
	$(BIN)/imunav lab --out $(OUT)

test: setup
	$(BIN)/python -m pytest -n 2 -q

bench: setup
	for f in benchmarks/bench_*.py; do $(BIN)/python $$f || exit 1; done

clean:
	rm -rf $(VENV) $(OUT) build *.egg-info src/*.egg-info
