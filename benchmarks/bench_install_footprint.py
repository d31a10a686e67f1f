"""Install footprint of `make run`: a fresh venv with `pip install --no-compile .`, its size, no torch in it.

Creates a virtual environment in a temporary folder, installs this checkout the way `make run` does
(the core dependencies only: no torch, no pyarrow, no test peers; no byte-compilation at install), uses
it once (`imunav --help`, a short lab run, a numpy-only LSTM detection: Python then writes the .pyc
files of what was imported), and prints the venv size in MB with PASS/FAIL against the target (600 MB,
issue 17), the install time, the largest packages, and whether `import torch` fails there (it must:
LSTM inference is numpy).  Needs the package registry (or a pip cache) for the dependencies.

With ``--make-run`` it checks issue 26's acceptance instead, as a user meets it: a fresh clone of this
checkout's committed HEAD, ``make run`` there with ``PYTHONDONTWRITEBYTECODE=1`` (the install, ``imunav warmup``
and the lab), then the venv's size *with* what warmup and the lab wrote next to the editable sources (numba
caches, bytecode; target < 600 MB), ``imunav CMD --help`` for every command (target <= 0.5 s each) and ``imunav
attitude run sample.ulg`` on the shared PX4 log, warm (target <= 2 s); medians of three runs, the same
``PYTHONDONTWRITEBYTECODE=1``.  Several minutes (the warmup compiles every quick-tour kernel).

Usage:  python benchmarks/bench_install_footprint.py [--target-mb 600] [--keep DIR] [--make-run]
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

LSTM_CHECK = """
import numpy as np
from imunav.learn import LstmDetector
from imunav.sim.gait import simulate_gait
sim = simulate_gait("walk", 4, rng=1, error_model="foot_mems")
zv = LstmDetector.load().detect(sim.imu).zv
print(f"LSTM (numpy) stance recall {np.mean(zv[sim.stance]):.2f}")
"""


def _size_mb(path: Path) -> float:
    total = 0
    for dirpath, _, files in os.walk(path):
        for f in files:
            p = Path(dirpath) / f
            if not p.is_symlink():
                total += p.stat().st_size
    return total / 1e6


SAMPLE = next((p for p in (Path(os.environ.get("IMUNAV_DATA", "")) / "px4_ulog" / "sample.ulg",
                           ROOT.parent / "shared" / "data" / "px4_ulog" / "sample.ulg") if p.is_file()), None)


def _median_run(argv: list[str], env: dict[str, str], cwd: Path, runs: int = 3) -> tuple[float, str | None]:
    """Median wall time of ``runs`` runs of ``argv``, s, and the last error line of a failed run (else None)."""
    times, error = [], None
    for _ in range(runs):
        t0 = time.perf_counter()
        r = subprocess.run(argv, env=env, cwd=cwd, capture_output=True, text=True)
        times.append(time.perf_counter() - t0)
        if r.returncode != 0:
            error = ((r.stderr or r.stdout).strip().splitlines() or [f"exit status {r.returncode}"])[-1]
    return sorted(times)[len(times) // 2], error


def make_run(tmp: Path, target_mb: float) -> int:
    """``make run`` in a fresh clone with PYTHONDONTWRITEBYTECODE=1, then size, --help and attitude run times."""
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
    env.pop("PYTHONPATH", None)
    clone = tmp / "clone"
    subprocess.run(["git", "clone", "-q", "--no-hardlinks", str(ROOT), str(clone)], check=True)
    t0 = time.perf_counter()
    r = subprocess.run(["make", "run", f"PYTHON={getattr(sys, '_base_executable', sys.executable)}"], cwd=clone,
                       env=env, capture_output=True, text=True)
    t_make = time.perf_counter() - t0
    if r.returncode != 0:
        print(f"make run FAILED after {t_make:.0f} s: {(r.stderr or r.stdout)[-1500:]}")
        return 1
    warm = [ln for ln in r.stdout.splitlines() if ln.startswith("warmup:")]
    venv = clone / ".venv"
    size_venv = _size_mb(venv)
    caches = [p for p in (clone / "src").rglob("__pycache__") if p.is_dir()]
    size_src = sum(_size_mb(p) for p in caches)
    user_cache = Path(os.environ.get("NUMBA_CACHE_DIR") or Path.home() / ".cache" / "numba")
    size = size_venv + size_src
    print(f"make run in a fresh clone (PYTHONDONTWRITEBYTECODE=1): {t_make:.0f} s; {warm[0] if warm else ''}")
    print(f"venv {size_venv:.0f} MB + numba caches and bytecode next to the sources {size_src:.0f} MB = {size:.0f} MB "
          f"(target < {target_mb:.0f} MB; user numba cache {user_cache} not counted: warmup writes next to the "
          "package)")
    imunav = str(venv / "bin" / "imunav")
    scratch = tmp / "scratch"
    scratch.mkdir()
    sys.path.insert(0, str(clone / "src"))
    from imunav.cli.main import COMMANDS

    ok = size < target_mb
    slow = []
    for cmd in COMMANDS:
        t, err = _median_run([imunav, cmd, "--help"], env, scratch)
        slow += [f"{cmd} {t:.2f} s"] if t > 0.5 or err else []
        print(f"  imunav {cmd} --help: {t:.2f} s{'' if err is None else ' FAILED ' + err}")
    ok = ok and not slow
    if SAMPLE is None:
        print("attitude run sample.ulg: shared data not found (IMUNAV_DATA): not measured")
    else:
        argv = [imunav, "attitude", "run", str(SAMPLE)]
        subprocess.run(argv, env=env, cwd=scratch, capture_output=True)
        t, err = _median_run(argv, env, scratch)
        print(f"imunav attitude run sample.ulg, warm: {t:.2f} s (target <= 2 s){'' if err is None else ' FAILED ' + err}")
        ok = ok and t <= 2.0 and err is None
    print(f"{'PASS' if ok else 'FAIL'}: size {size:.0f} MB, --help over 0.5 s: {', '.join(slow) or 'none'}")
    return 0 if ok else 1


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--target-mb", type=float, default=600.0)
    ap.add_argument("--keep", type=Path, default=None, help="Build the venv here and keep it.")
    ap.add_argument("--make-run", action="store_true", help="Issue 26's check: make run in a fresh clone, "
                                                             "PYTHONDONTWRITEBYTECODE=1; size, --help, attitude run.")
    a = ap.parse_args()
    if a.make_run:
        tmp = Path(tempfile.mkdtemp(prefix="imunav-makerun-")) if a.keep is None else a.keep
        try:
            return make_run(tmp, a.target_mb)
        finally:
            if a.keep is None:
                shutil.rmtree(tmp, ignore_errors=True)
    # a user's Python writes .pyc files on import; some environments turn that off
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
    tmp = Path(tempfile.mkdtemp(prefix="imunav-footprint-")) if a.keep is None else a.keep
    venv = tmp / "venv"
    try:
        subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
        py = venv / "bin" / "python"
        base = _size_mb(venv)
        # a copy of the tree without build outputs, so that `pip install .` sees what a fresh clone has
        src = tmp / "src"
        shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(".venv", ".git", "build", "*.egg-info",
                                                                 "__pycache__", "_build", "_generated", "lab-report"))
        t0 = time.perf_counter()
        subprocess.run([str(py), "-m", "pip", "install", "-q", "--no-compile", str(src)], check=True)
        t_install = time.perf_counter() - t0
        size_installed = _size_mb(venv)
        torch = subprocess.run([str(py), "-c", "import torch"], capture_output=True, text=True)
        cli = subprocess.run([str(venv / "bin" / "imunav"), "--help"], capture_output=True, text=True)
        t0 = time.perf_counter()
        lab = subprocess.run([str(venv / "bin" / "imunav"), "lab", "--config", str(ROOT / "examples" / "lab_quick.toml"),
                              "--out", str(tmp / "report"), "--quiet"], capture_output=True, text=True)
        t_lab = time.perf_counter() - t0
        lstm = subprocess.run([str(py), "-c", LSTM_CHECK], capture_output=True, text=True)
        size = _size_mb(venv)
        site = next((venv / "lib").glob("python3*/site-packages"))
        pkgs = sorted(((_size_mb(p), p.name) for p in site.iterdir() if p.is_dir()), reverse=True)[:8]
        ok = size < a.target_mb
        print(f"venv after `pip install --no-compile .`: {size_installed:.0f} MB (empty venv {base:.0f} MB), "
              f"install {t_install:.0f} s; after first use: {size:.0f} MB")
        print(f"quick lab in that venv: {'ok' if lab.returncode == 0 else 'FAILED ' + lab.stderr[-300:]} "
              f"({t_lab:.0f} s)")
        print("largest packages: " + ", ".join(f"{n} {s:.0f} MB" for s, n in pkgs))
        print(f"import torch in that venv: {'fails (as it must)' if torch.returncode else 'SUCCEEDS (torch installed!)'}")
        print(f"imunav --help: {'ok' if cli.returncode == 0 else 'FAILED ' + cli.stderr[-300:]}")
        print(lstm.stdout.strip() if lstm.returncode == 0 else "LSTM inference FAILED: " + lstm.stderr[-500:])
        verdict = ok and torch.returncode != 0 and cli.returncode == 0 and lstm.returncode == 0 and lab.returncode == 0
        print(f"{'PASS' if verdict else 'FAIL'}: install footprint {size:.0f} MB against the {a.target_mb:.0f} MB target")
        return 0 if verdict else 1
    finally:
        if a.keep is None:
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
