"""The package installs like any other (issue 35, deliverable 4).

``python -m build`` makes an sdist and, from it, a wheel; the wheel carries the package and what it needs at run
time (the shipped LSTM model, ``py.typed``, the licence) and nothing from the tests, the docs or numba's caches;
installed into a fresh virtual environment (not the source tree), ``imunav --version`` and a command run from it.

The fresh venv gets the wheel with ``pip install --no-deps --no-index``; its dependencies (numpy, numba, ...) are
this interpreter's, reached through a ``.pth`` line (a path, not a site directory: this environment's own ``.pth``
files, such as an editable install of imunav, are not run), so the test needs no network.  The build runs without
isolation when this interpreter has setuptools (offline, as in ``make test``'s venv), else with it (pip then
fetches setuptools).  Slow: a build and a venv take about half a minute.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
import tarfile
import venv
import zipfile
from pathlib import Path

import pytest
from shared_data import ROOT

import imunav

pytestmark = pytest.mark.slow

_COPY_IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc", "*.nbi", "*.nbc", "*.egg-info", "build", "dist",
                                      "_build", "_generated", "generated", ".venv", ".pytest_cache", ".hypothesis")


@pytest.fixture(scope="module")
def dist(tmp_path_factory) -> Path:
    """The sdist and the wheel, built from a copy of the tree (the build writes ``*.egg-info`` beside the sources)."""
    pytest.importorskip("build")
    tmp = tmp_path_factory.mktemp("pkg")
    tree = tmp / "tree"
    tree.mkdir()
    for name in ("pyproject.toml", "README.md", "LICENSE", "CHANGELOG.md", "MANIFEST.in", "Makefile"):
        shutil.copy(ROOT / name, tree / name)
    for name in ("src", "tests", "docs", "examples", "benchmarks"):
        shutil.copytree(ROOT / name, tree / name, ignore=_COPY_IGNORE, symlinks=True)
    isolation = ["--no-isolation"] if _has("setuptools") else []
    out = tmp / "dist"
    res = subprocess.run([sys.executable, "-m", "build", *isolation, "--outdir", str(out), str(tree)],
                         capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    return out


def _has(module: str) -> bool:
    import importlib.util

    return importlib.util.find_spec(module) is not None


def _wheel(dist: Path) -> Path:
    (whl,) = dist.glob("imunav-*.whl")
    return whl


def test_build_makes_a_wheel_and_an_sdist(dist):
    whl = _wheel(dist)
    assert whl.name == f"imunav-{imunav.__version__}-py3-none-any.whl"
    (sdist,) = dist.glob("imunav-*.tar.gz")
    with tarfile.open(sdist) as tf:
        names = {n.split("/", 1)[1] for n in tf.getnames() if "/" in n}
    for must in ("pyproject.toml", "README.md", "LICENSE", "CHANGELOG.md", "src/imunav/__init__.py",
                 "src/imunav/data/zupt_lstm.npz", "tests/test_packaging.py", "docs/guide/index.md"):
        assert must in names, must
    assert not [n for n in names if n.endswith((".pyc", ".nbi", ".nbc"))]


def test_the_wheel_carries_what_it_needs_and_nothing_from_the_tests(dist):
    with zipfile.ZipFile(_wheel(dist)) as z:
        names = z.namelist()
        meta = z.read(f"imunav-{imunav.__version__}.dist-info/METADATA").decode()
    assert "imunav/data/zupt_lstm.npz" in names  # the shipped LSTM zero-velocity model
    assert "imunav/py.typed" in names
    assert any(n.endswith("licenses/LICENSE") for n in names)
    assert {n.split("/")[0] for n in names} == {"imunav", f"imunav-{imunav.__version__}.dist-info"}, names
    bad = [n for n in names if n.endswith((".pyc", ".nbi", ".nbc")) or "/tests/" in n or "conftest" in n]
    assert not bad, bad
    # every module of the source tree is in the wheel
    src = {str(p.relative_to(ROOT / "src")) for p in (ROOT / "src" / "imunav").rglob("*.py")}
    assert src <= set(names), sorted(src - set(names))[:10]
    for field in ("License-Expression: MIT", "Classifier: Programming Language :: Python :: 3.11",
                  "Project-URL: Documentation", "Project-URL: Changelog", "Requires-Python: >=3.11",
                  "Provides-Extra: ros", "Provides-Extra: px4"):
        assert field in meta, field


def test_a_fresh_venv_runs_the_installed_wheel(dist, tmp_path):
    env_dir = tmp_path / "venv"
    venv.EnvBuilder(with_pip=True, symlinks=True).create(env_dir)
    py = env_dir / "bin" / "python"
    # nothing of this checkout on the path (PYTHONPATH=src would show pip an imunav already there)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")}
    env["MPLBACKEND"] = "Agg"
    site = Path(subprocess.run([py, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               env=env, capture_output=True, text=True, check=True).stdout.strip())
    res = subprocess.run([py, "-m", "pip", "install", "-q", "--no-deps", "--no-index", str(_wheel(dist))],
                         env=env, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr[-3000:]
    # then the dependencies of this interpreter, as a plain path after the venv's own site-packages (added after
    # the install, so that pip neither sees nor touches this environment's packages)
    (site / "_imunav_test_deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    work = tmp_path / "work"
    work.mkdir()
    where = subprocess.run([py, "-c", "import imunav, sys; print(imunav.__file__)"], cwd=work, env=env,
                           capture_output=True, text=True, timeout=120)
    assert where.returncode == 0, where.stderr
    assert Path(where.stdout.strip()).is_relative_to(site), where.stdout  # the wheel's copy, not the source tree
    exe = env_dir / "bin" / "imunav"
    ver = subprocess.run([exe, "--version"], cwd=work, env=env, capture_output=True, text=True, timeout=120)
    assert ver.returncode == 0 and imunav.__version__ in ver.stdout, ver.stdout + ver.stderr
    # one command end to end from the installed package: simulate a short static recording, then describe it
    sim = subprocess.run([exe, "simulate", "static", "--preset", "ideal", "--duration", "20", "--fs", "50",
                          "--out", "still.csv"], cwd=work, env=env, capture_output=True, text=True, timeout=600)
    assert sim.returncode == 0, sim.stdout[-2000:] + sim.stderr[-2000:]
    info = subprocess.run([exe, "info", "still.csv"], cwd=work, env=env, capture_output=True, text=True, timeout=600)
    assert info.returncode == 0, info.stdout[-2000:] + info.stderr[-2000:]
    assert "1001" in info.stdout.replace(",", ""), info.stdout  # 0 to 20 s at 50 Hz
