"""GNSS/INS filter speed (issue 15, acceptance "speed"): 21 states, GNSS position + velocity at 1 Hz, a 1-hour
drive at 200 Hz (720,001 IMU samples) through :meth:`imunav.ins.gins.GinsFilter.run`.

Printed: the smallest CPU time (time.process_time) and wall time of three runs after a warm-up run (numba
kernels compiled and cached), and the CPU time per IMU sample (acceptance: <= 3 us per sample, < 10 s per hour).

``--cov-interval-s`` sets the covariance step (default 0.2 s; 0.005 s, the IMU interval, gives KF-GINS's one σ
row per IMU sample).

Run:  PYTHONPATH=src python benchmarks/bench_gins_speed.py [--preset navigation_a15] [--runs 3]
      [--cov-interval-s 0.2]
"""

from __future__ import annotations

import argparse
import time

from imunav.ins.gins import GinsConfig, GinsFilter
from imunav.sim import presets, simulate_imu
from imunav.sim.gnss import simulate_gnss
from imunav.sim.vehicle import demo_drive, vehicle_trajectory


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", default="navigation_a15")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--cov-interval-s", type=float, default=0.2, help="covariance step, s")
    a = ap.parse_args()
    truth = vehicle_trajectory(demo_drive(3600.0), fs=200.0)
    imu = simulate_imu(truth, presets.get(a.preset), rng=1)
    gnss = simulate_gnss(truth, rng=2)
    f = GinsFilter(GinsConfig.from_preset(a.preset, cov_interval_s=a.cov_interval_s))
    start = dict(lla0=truth.pos_lla[0], vel0=truth.vel_ned[0], q0=truth.q_nb[0])
    f.run(imu, gnss, **start)
    cpu, wall = [], []
    for _ in range(a.runs):
        c0, w0 = time.process_time(), time.perf_counter()
        res = f.run(imu, gnss, **start)
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - w0)
    n = imu.t.size
    print(f"{n} IMU samples at 200 Hz, {res.meta['n_states']} states, GNSS 1 Hz, covariance step "
          f"{a.cov_interval_s:g} s: min CPU {min(cpu):.2f} s "
          f"({min(cpu) / n * 1e6:.2f} us per sample, acceptance <= 3), min wall {min(wall):.2f} s "
          f"(acceptance < 10 s)")


if __name__ == "__main__":
    main()
