"""How well can the robot scenario's GNSS latency be known at all?  An ideal estimator (issue 24).

The acceptance item asks for the latency within 20 ms of the truth on the simulated robot
(:func:`imunav.sim.robot_log.simulate_robot_log`: GNSS at 2.5 Hz, σ 0.8 m, 0.15 s late, the robot at 1 m/s).
A latency τ moves each fix by ``v τ`` along the track, so that N fixes of σ at speed v carry ``σ_τ ≥ σ / (v √N)``
(Cramér–Rao, the trajectory known): about 0.8 m / (1 m/s · √1,100) = 24 ms.  This benchmark runs the estimator
that knows everything but τ: the true trajectory, the outliers removed, and the least-squares τ of the horizontal
fixes against the truth delayed by τ.  No filter, which must also estimate the trajectory, can do better.

Printed: the mean and the spread of its error over the drives and the share within 20 ms.

Run: ``python benchmarks/bench_gins_latency_bound.py [--drives 100] [--first-seed 500]`` (about 7 s).
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.optimize import minimize_scalar

from imunav.earth import lla_to_ned
from imunav.sim.robot_log import simulate_robot_log


def ideal_latency_error(seed: int) -> float:
    """The ideal estimator's latency error on one drive, s."""
    log = simulate_robot_log(seed)
    tr, g = log.truth.trajectory, log.gnss
    ned = lla_to_ned(tr.pos_lla, tr.pos_lla[0])[:, :2]
    keep = ~log.truth.gnss_outlier
    tf, pf = g.t[keep], lla_to_ned(g.lla[keep], tr.pos_lla[0])[:, :2]

    def cost(tau: float) -> float:
        p = np.column_stack([np.interp(tf - tau, tr.t, ned[:, j]) for j in range(2)])
        return float(np.sum((pf - p) ** 2))

    tau = minimize_scalar(cost, bounds=(0.0, 0.4), method="bounded", options={"xatol": 1e-5}).x
    return float(tau - log.truth.gnss_latency_s)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--drives", type=int, default=100)
    ap.add_argument("--first-seed", type=int, default=500)
    a = ap.parse_args()
    e = np.array([ideal_latency_error(s) for s in range(a.first_seed, a.first_seed + a.drives)])
    print(f"ideal estimator over {e.size} drives: mean error {e.mean() * 1e3:.1f} ms, sd {e.std(ddof=1) * 1e3:.1f} ms, "
          f"within 20 ms on {np.mean(np.abs(e) < 0.02) * 100:.0f} % of drives")


if __name__ == "__main__":
    main()
