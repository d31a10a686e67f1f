"""Shared test fixtures.

Real recordings live outside the repository (``IMUNAV_DATA`` or
``../shared/data``); tests that need them use ``from shared_data import
data_path``, which skips with the missing path named when they are absent.
"""

from __future__ import annotations

import re

import pytest
from shared_data import ROOT, data_path  # noqa: E402,F401  (re-exported for old imports)

try:  # pytest >= 9: a node's id is structured (see _suffix_group)
    from _pytest.nodeid import coerce_node_id
except ImportError:
    coerce_node_id = None


@pytest.fixture
def rng():
    import numpy as np

    return np.random.default_rng(20261122)


# -- the fault suite's captured stderr (issue 16: `grep -c Traceback` over it must be 0) ---------------
# tests/cli/test_errors.py appends every case's stderr to <dir>/<worker>.log; the controller counts the
# lines with "Traceback" over all workers at the end, fails the session if there is one, and prints
# the count.  Set IMUNAV_FAULT_LOG_DIR to keep the logs (then: grep -c Traceback $IMUNAV_FAULT_LOG_DIR/*.log).
FAULT_LOG_ENV = "IMUNAV_FAULT_LOG_DIR"


#: Test files (and README examples) that run the GNSS/INS kernels: they share one xdist worker
#: (``--dist loadgroup`` in the Makefile), so that a fresh checkout compiles those numba kernels
#: (about a minute and a half of CPU) once, not once per worker; later runs load numba's cache.
GINS_GROUP = "gins"


def pytest_collection_modifyitems(config, items):
    for item in items:
        block = getattr(item, "callspec", None) and item.callspec.params.get("block")
        text = getattr(block, "text", "")
        if "test_gins" in item.nodeid or "ins/gins/" in item.nodeid or re.search(r"\bgins\b|GinsFilter|lab_gins", text):
            item.add_marker(pytest.mark.xdist_group(GINS_GROUP))
    if getattr(config.option, "loadgroup", False):  # an xdist worker under --dist loadgroup
        for item in items:
            _suffix_group(item)


def _suffix_group(item) -> None:
    """What pytest-xdist's own hook does for ``--dist loadgroup`` (``NODEID@group``, the scheduler's work unit),
    done here because under pytest >= 9 the node id lives in ``item._id`` and xdist 3.8 still writes
    ``item._nodeid``, which nothing reads: every ``xdist_group`` was silently ignored (the docs site was built by
    both workers, the GNSS/INS kernels compiled by both)."""
    names = sorted({str(m.args[0] if m.args else m.kwargs.get("name", "default"))
                    for m in item.iter_markers("xdist_group")})
    if not names or "@" in item.nodeid.rsplit("]", 1)[-1]:
        return
    new = f"{item.nodeid}@{'_'.join(names)}"
    if coerce_node_id is not None and hasattr(item, "_id"):
        item._id = coerce_node_id(new)
        assert item.nodeid == new, (item.nodeid, new)
    else:
        item._nodeid = new


def pytest_configure(config):
    import os
    import tempfile
    from pathlib import Path

    if hasattr(config, "workerinput"):  # an xdist worker: it inherited the controller's environment
        return
    d = os.environ.get(FAULT_LOG_ENV)
    if d:
        for p in Path(d).glob("*.log"):
            p.unlink()
    else:
        os.environ[FAULT_LOG_ENV] = tempfile.mkdtemp(prefix="imunav-fault-log-")


def pytest_sessionfinish(session, exitstatus):
    import os
    from pathlib import Path

    if hasattr(session.config, "workerinput"):
        return
    d = Path(os.environ.get(FAULT_LOG_ENV, ""))
    logs = sorted(d.glob("*.log")) if d.is_dir() else []
    if not logs:
        return
    text = "".join(p.read_text(encoding="utf-8") for p in logs)
    n_cases = text.count("=== case ")
    n_tb = sum("Traceback" in ln for ln in text.splitlines())
    session.config._imunav_fault_summary = (n_cases, n_tb, d)
    if n_tb and session.exitstatus == 0:
        session.exitstatus = 1


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    s = getattr(config, "_imunav_fault_summary", None)
    if s:
        terminalreporter.write_line(f"fault suite: stderr of {s[0]} CLI cases in {s[2]}; lines with 'Traceback': {s[1]}")
