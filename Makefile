# Two entry points (see README): `make run` and `make test`; `make docs` builds the reference site.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
OUT    ?= lab-report
# torch for `make test` (the LSTM training tests).  pyproject's `learn` extra asks for a range
# (torch>=2.2,<3); installed alone, pip resolves a range to the newest release, which on Linux
# x86_64 is a CUDA build of several GB.  Naming one release first (here the CPU build that the
# project's machines keep on disk, so nothing is downloaded) makes the range already satisfied.
# Override on another machine, e.g. `make test TORCH=torch==2.5.1`.
TORCH  ?= torch==2.13.0

# One venv, one stamp per install level: `make run` then `make test` adds the test extras to the
# same venv; `make run` alone never installs torch or the test peers.
STAMP_VENV := $(VENV)/.stamp-venv
STAMP_RUN  := $(VENV)/.stamp-run
STAMP_TEST := $(VENV)/.stamp-test
STAMP_DOCS := $(VENV)/.stamp-docs

.PHONY: setup run test docs bench clean browser

# Python 3.11's venv also brings setuptools 65 (8 MB, with its bytecode): nothing imports it at run time, and pip
# builds packages (this one included: pyproject's build-system) in an isolated environment with the setuptools they
# ask for, so the venv keeps pip and drops setuptools, as Python >= 3.12's venvs come.
$(STAMP_VENV):
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --upgrade --no-compile pip
	$(BIN)/python -m pip uninstall -y -q setuptools
	touch $@

# what the lab and the quick tour need: the library, its core dependencies and the two small pure-Python readers
# of KF-GINS YAML (gins run --config) and PX4 ULog (no ROS bags: 17 MB with their compression libraries; no h5py
# for HDF5 / MAT v7.3 files, 17 MB; no PyWavelets; no torch, no pyarrow, no test peers).
# --no-compile: Python compiles the modules the lab imports on first use instead of every module of
# every dependency at install time (160 MB of .pyc; benchmarks/bench_install_footprint.py).
# `imunav warmup` then compiles the numba kernels of the quick tour and writes the bytecode of the modules it
# imports (and only those), so that no first run compiles and no start recompiles the sources where Python may
# not write bytecode (PYTHONDONTWRITEBYTECODE=1).
$(STAMP_RUN): pyproject.toml $(STAMP_VENV)
	$(BIN)/python -m pip install --no-compile -e '.[yaml,px4]'
	$(BIN)/imunav warmup
	touch $@

# The test install also runs `imunav warmup` (as `make run`'s does): the quick tour's numba kernels are compiled
# once, here, instead of once in each of the test workers that first needs them (the suite's two workers each
# compiled the attitude and GNSS/INS kernels: minutes of CI), and a later `make run` finds them compiled.
$(STAMP_TEST): pyproject.toml $(STAMP_VENV)
	$(BIN)/python -m pip install '$(TORCH)'
	$(BIN)/python -m pip install -e '.[test,learn,dask]'
	$(BIN)/imunav warmup --quiet
	touch $@ $(STAMP_RUN) $(STAMP_DOCS)

$(STAMP_DOCS): pyproject.toml $(STAMP_VENV)
	$(BIN)/python -m pip install -e '.[docs]'
	touch $@ $(STAMP_RUN)

setup: $(STAMP_TEST)

run: $(STAMP_RUN)
	$(BIN)/imunav lab --out $(OUT) --overwrite

# Debian's Chromium for the report rendering test; skipped (the test then
# skips) where it cannot be installed, e.g. without root.
browser:
	@command -v chromium >/dev/null 2>&1 || { [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1 && \
	  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium) >/dev/null 2>&1; } || \
	  echo "chromium not installed: the browser rendering test will be skipped"

test: $(STAMP_TEST) browser
	$(BIN)/python -m ruff check .
	$(BIN)/python -m pytest -n 2 --dist loadgroup -q --durations=25

# API reference + gallery into docs/_build/html, warnings as errors.  The gallery's figures come
# from a shortened lab run that docs/conf.py starts (docs/gallery.py, docs/gallery_lab.toml), kept
# in docs/_generated: the first build takes about two minutes, a rebuild about 20 s.
docs: $(STAMP_DOCS)
	$(BIN)/python -m sphinx -W --keep-going -b html -q docs docs/_build/html
	@echo "open docs/_build/html/index.html"

bench: $(STAMP_TEST)
	for f in benchmarks/bench_*.py; do $(BIN)/python $$f || exit 1; done

clean:
	rm -rf $(VENV) $(OUT) build *.egg-info src/*.egg-info docs/_build docs/_generated docs/api/generated
