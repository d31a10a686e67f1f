"""Install footprint of `make run`: a fresh venv with `pip install --no-compile .`, its size, no torch in it.

Creates a virtual environment in a temporary folder, installs this checkout the way `make run` does
(the core dependencies only: no torch, no pyarrow, no test peers; no byte-compilation at install), uses
it once (`imunav --help`, a short lab run, a numpy-only LSTM detection: Python then writes the .pyc
files of what was imported), and prints the venv size in MB with PASS/FAIL against the target (600 MB,
issue 17), the install time, the largest packages, and whether `import torch` fails there (it must:
LSTM inference is numpy).  Needs the package registry (or a pip cache) for the dependencies.

Usage:  python benchmarks/bench_install_footprint.py [--target-mb 600] [--keep DIR]
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


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--target-mb", type=float, default=600.0)
    ap.add_argument("--keep", type=Path, default=None, help="Build the venv here and keep it.")
    a = ap.parse_args()
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
