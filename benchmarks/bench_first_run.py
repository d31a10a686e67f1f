"""First run against warm run of every quick-tour command, side by side (issue 26).

A *fresh install* is emulated without the network: the same interpreter and packages, but with empty
caches -- no bytecode (``PYTHONDONTWRITEBYTECODE=1`` and an empty ``PYTHONPYCACHEPREFIX``, as after
``pip install --no-compile``) and no compiled numba kernels (an empty ``NUMBA_CACHE_DIR``).  Three passes
over the quick tour (``imunav.cli.warmup.TOUR``, plus ``attitude run`` on the shared PX4 log when present):

* ``first``: fresh caches, no warmup -- what a user met before ``imunav warmup``;
* ``after warmup``: fresh caches, ``imunav warmup`` once (timed), then the tour -- what ``make run`` gives;
* ``warm``: the same tour again on those caches.

Each command runs in a subprocess (``python -m imunav.cli.main``), timed wall-clock.  The target is
``after warmup - warm <= 5 s`` for every command.

Usage:  python benchmarks/bench_first_run.py [--skip-cold]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from imunav.cli.warmup import TOUR  # noqa: E402

SAMPLE = next((p for p in (Path(os.environ.get("IMUNAV_DATA", "")) / "px4_ulog" / "sample.ulg",
                           ROOT.parent / "shared" / "data" / "px4_ulog" / "sample.ulg") if p.is_file()), None)


def _tour() -> list[tuple[str, tuple[str, ...]]]:
    tour: list = [("noise --help", ("noise", "--help"))] + list(TOUR)
    if SAMPLE is not None:
        tour.append(("attitude run sample.ulg", ("attitude", "run", str(SAMPLE), "--topic", "sensor_combined",
                                                 "--filter", "mekf")))
    return tour


def _env(cache: Path) -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT / "src"), "PYTHONDONTWRITEBYTECODE": "1",
            "PYTHONPYCACHEPREFIX": str(cache / "pyc"), "NUMBA_CACHE_DIR": str(cache / "numba")}


def _run(argv: tuple[str, ...], env: dict[str, str], cwd: Path) -> float:
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "imunav.cli.main", *argv], env=env, cwd=cwd, capture_output=True,
                       text=True)
    dt = time.perf_counter() - t0
    if r.returncode != 0:
        print(f"  imunav {' '.join(argv)} failed: {(r.stderr or r.stdout).strip().splitlines()[-1:]}")
    return dt


def _pass(tour: list[tuple[str, tuple[str, ...]]], env: dict[str, str], scratch: Path) -> dict[str, float]:
    scratch.mkdir(parents=True)
    out = {}
    for what, argv in tour:
        if callable(argv):  # a preparation step of the tour (a file), not a command: not timed
            cwd = os.getcwd()
            os.chdir(scratch)
            try:
                argv()
            finally:
                os.chdir(cwd)
        else:
            out[what] = _run(argv, env, scratch)
    return out


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--skip-cold", action="store_true", help="Skip the pass without warmup (the slowest).")
    a = ap.parse_args()
    tour = _tour()
    with tempfile.TemporaryDirectory(prefix="imunav-first-run-") as tmp:
        root = Path(tmp)
        cold = {} if a.skip_cold else _pass(tour, _env(root / "cache-cold"), root / "cold")
        env = _env(root / "cache-warmup")
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "imunav.cli.main", "warmup", "--quiet"], env=env, cwd=root, check=True)
        t_warmup = time.perf_counter() - t0
        after = _pass(tour, env, root / "after")
        warm = _pass(tour, env, root / "warm")
    print(f"\nimunav warmup on fresh caches: {t_warmup:.1f} s\n")
    print(f"{'command':<28} {'first, no warmup [s]':>21} {'first after warmup [s]':>23} {'warm [s]':>9} "
          f"{'after - warm [s]':>17}")
    worst = 0.0
    for what in after:
        d = after[what] - warm[what]
        worst = max(worst, d)
        c = f"{cold[what]:.2f}" if what in cold else "-"
        print(f"{what:<28} {c:>21} {after[what]:>23.2f} {warm[what]:>9.2f} {d:>+17.2f}")
    ok = worst <= 5.0
    print(f"\nlargest first-after-warmup minus warm: {worst:.2f} s ({'PASS' if ok else 'FAIL'}: target <= 5 s); "
          f"{os.cpu_count()} CPUs, load {os.getloadavg()[0]:.1f}")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
