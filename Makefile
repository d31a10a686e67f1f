# Two entry points (see README): `make run` and `make test`.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
OUT    ?= lab-report

.PHONY: setup run test bench clean browser

$(BIN)/imunav: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --upgrade pip
	$(BIN)/python -m pip install -e '.[test,learn,dask]'
	touch $(BIN)/imunav

setup: $(BIN)/imunav

run: setup
	$(BIN)/imunav lab --out $(OUT) --overwrite

# Debian's Chromium for the report rendering test; skipped (the test then
# skips) where it cannot be installed, e.g. without root.
browser:
	@command -v chromium >/dev/null 2>&1 || { [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1 && \
	  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium) >/dev/null 2>&1; } || \
	  echo "chromium not installed: the browser rendering test will be skipped"

test: setup browser
	$(BIN)/python -m pytest -n 2 -q

bench: setup
	for f in benchmarks/bench_*.py; do $(BIN)/python $$f || exit 1; done

clean:
	rm -rf $(VENV) $(OUT) build *.egg-info src/*.egg-info
