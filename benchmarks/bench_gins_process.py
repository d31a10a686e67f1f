"""The whole ``imunav gins run --config kf-gins.yaml`` process on a simulated 1,500 s, 100 Hz KF-GINS drive
(issue 26: at most 3 s warm on 2 cores, figures included).

Each measurement is a fresh process, after one warm-up run: numba's cache present, and the bytecode of the modules
the command imports written (the warm-up runs without ``PYTHONDONTWRITEBYTECODE``), as ``imunav warmup`` leaves an
install; the measured runs keep the caller's environment:

* the command itself (``python -m imunav.cli.main gins run --config ... --quiet``), with and without figures;
* its phases, timed inside a fresh process that does what the command does: imports (the CLI, the library,
  matplotlib), reading the KF-GINS files, the filter, writing KF-GINS's text outputs and summary, and each figure
  (drawing and PNG writing).

The median of ``--runs`` runs is printed (the machine may be shared), with the command's CPU time (user + system),
which other loads on a shared machine disturb less than its wall time.

Run:  PYTHONPATH=src python benchmarks/bench_gins_process.py [--runs 3] [--duration 1500] [--fs 100]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _env() -> dict[str, str]:
    src = str(Path(__file__).resolve().parents[1] / "src")
    return {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [src, os.environ.get("PYTHONPATH")]))}


def _cli(args: list[str], *, bytecode: bool = False) -> tuple[float, float]:
    """Wall time and CPU time (user + system) of one ``imunav`` process, s; ``bytecode``: the process may write
    the bytecode of what it imports (``PYTHONDONTWRITEBYTECODE`` removed)."""
    env = _env()
    if bytecode:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    subprocess.run([sys.executable, "-m", "imunav.cli.main", *args], check=True, env=env, capture_output=True)
    wall = time.perf_counter() - t
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)


def _phases(yaml: str, out: str) -> dict[str, float]:
    """What ``gins run --config`` does, phase by phase, in this (fresh) process."""
    ph: dict[str, float] = {}
    t = time.perf_counter()
    import imunav.cli.gins  # noqa: F401
    import imunav.cli.main  # noqa: F401
    ph["import CLI"] = time.perf_counter() - t
    t = time.perf_counter()
    from imunav.ins.gins import outputs, plot
    from imunav.ins.gins.setup import load_inputs, run_setup
    ph["import library"] = time.perf_counter() - t
    t = time.perf_counter()
    plt = plot._plt()
    ph["import matplotlib"] = time.perf_counter() - t
    t = time.perf_counter()
    inputs = load_inputs(None, None, yaml)
    ph["reading"] = time.perf_counter() - t
    t = time.perf_counter()
    res = run_setup(inputs.imu, inputs.gnss, inputs.setup)
    ph["filter"] = time.perf_counter() - t
    t = time.perf_counter()
    outputs.write_run_outputs(Path(out) / "text", res, inputs.setup, gnss=inputs.gnss, plots=False)
    ph["writing text + summary"] = time.perf_counter() - t
    for name, make in (("track", lambda: plot.plot_track(res, inputs.gnss)),
                       ("imu_errors", lambda: plot.plot_imu_errors(res))):
        t = time.perf_counter()
        fig = make()
        ph[f"figure {name}: draw"] = time.perf_counter() - t
        t = time.perf_counter()
        fig.savefig(Path(out) / f"{name}.png", format="png", dpi=90)
        plt.close(fig)
        ph[f"figure {name}: png"] = time.perf_counter() - t
    return ph


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--duration", type=float, default=1500.0)
    ap.add_argument("--fs", type=float, default=100.0)
    ap.add_argument("--phases", nargs=2, metavar=("YAML", "OUT"), help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.phases:
        print(json.dumps(_phases(*a.phases)))
        return
    with tempfile.TemporaryDirectory() as d:
        drive = Path(d) / "drive"
        _cli(["gins", "simulate", "--out", str(drive), "--duration", str(a.duration), "--fs", str(a.fs), "--seed", "1"])
        yaml = str(drive / "kf-gins.yaml")
        # numba's cache and the bytecode of what the command imports, as `imunav warmup` leaves them
        _cli(["gins", "run", "--config", yaml, "--out", str(Path(d) / "warm"), "--quiet"], bytecode=True)
        for plots in ("--plots", "--no-plots"):
            runs = [_cli(["gins", "run", "--config", yaml, "--out", str(Path(d) / f"r{k}{plots}"), "--quiet", plots])
                    for k in range(a.runs)]
            wall, cpu = zip(*runs)
            print(f"imunav gins run {plots}: {statistics.median(wall):.2f} s wall ({', '.join(f'{x:.2f}' for x in wall)}), "
                  f"{statistics.median(cpu):.2f} s CPU; median of {a.runs} fresh processes")
        phases = []
        for k in range(a.runs):
            out = Path(d) / f"ph{k}"
            p = subprocess.run([sys.executable, __file__, "--phases", yaml, str(out)], check=True, env=_env(),
                               capture_output=True, text=True)
            phases.append(json.loads(p.stdout))
    print(f"phases (fresh process, median of {a.runs}):")
    for key in phases[0]:
        print(f"  {key:28s} {statistics.median(r[key] for r in phases):6.2f} s")
    print(f"  {'sum':28s} {statistics.median(sum(r.values()) for r in phases):6.2f} s")


if __name__ == "__main__":
    main()
