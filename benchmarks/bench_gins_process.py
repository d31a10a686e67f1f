"""The whole ``imunav gins run --config kf-gins.yaml`` process on a simulated 1,500 s, 100 Hz KF-GINS drive
(issue 26): wall time of the command with and without figures (best of ``--runs``, after one warm-up run), and
in-process phases: imports, reading the KF-GINS files, the filter, writing KF-GINS's outputs, figures.

Run:  PYTHONPATH=src python benchmarks/bench_gins_process.py [--runs 2] [--duration 1500] [--fs 100]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _cli(args: list[str]) -> float:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(Path(__file__).parents[1] / "src"),
                                                                     os.environ.get("PYTHONPATH")]))}
    t = time.perf_counter()
    subprocess.run([sys.executable, "-m", "imunav.cli.main", *args], check=True, env=env, capture_output=True)
    return time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=2)
    ap.add_argument("--duration", type=float, default=1500.0)
    ap.add_argument("--fs", type=float, default=100.0)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as d:
        drive = Path(d) / "drive"
        _cli(["gins", "simulate", "--out", str(drive), "--duration", str(a.duration), "--fs", str(a.fs), "--seed", "1"])
        yaml = str(drive / "kf-gins.yaml")
        _cli(["gins", "run", "--config", yaml, "--out", str(Path(d) / "warm"), "--quiet"])  # numba caches warm
        for plots in ("--plots", "--no-plots"):
            best = min(_cli(["gins", "run", "--config", yaml, "--out", str(Path(d) / f"r{k}{plots}"), "--quiet",
                             plots]) for k in range(a.runs))
            print(f"imunav gins run {plots}: {best:.2f} s wall (best of {a.runs})")
        t0 = time.perf_counter()
        from imunav.ins.gins.outputs import write_run_outputs
        from imunav.ins.gins.setup import load_inputs, run_setup
        t1 = time.perf_counter()
        inputs = load_inputs(None, None, yaml)
        t2 = time.perf_counter()
        res = run_setup(inputs.imu, inputs.gnss, inputs.setup)
        t3 = time.perf_counter()
        write_run_outputs(Path(d) / "p1", res, inputs.setup, gnss=inputs.gnss, plots=False)
        t4 = time.perf_counter()
        write_run_outputs(Path(d) / "p2", res, inputs.setup, gnss=inputs.gnss, plots=True)
        t5 = time.perf_counter()
    print(f"phases (in process): imports {t1 - t0:.2f} s, reading {t2 - t1:.2f} s, filter {t3 - t2:.2f} s, writing "
          f"{t4 - t3:.2f} s, writing with figures {t5 - t4:.2f} s; {res.t.size} IMU samples")


if __name__ == "__main__":
    main()
