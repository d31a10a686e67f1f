"""Speed of the test-profile generators and the ideal IMU (imunav.sim).

Builds the thesis tests at 1 kHz (the rate of the thesis's real logs):
100-position static test (3.2e6 samples), 120-step rate table (3.8e6),
then the ideal IMU of each, and prints samples per second.  No peer
library generates these profiles, so there is no ratio column.

Run: python benchmarks/bench_sim_profiles.py
"""

from __future__ import annotations

import time

from _before_after import report  # the before (a308974) / after lines

from imunav.sim import hundred_position_profile, ideal_imu, rate_table_step_profile


def main() -> None:
    # warm up the numba kernels
    ideal_imu(hundred_position_profile(fs=10.0, dwell_s=1.0, transition_s=1.0).trajectory, earth_rate=False,
              gravity="constant")
    rows = []
    for name, build in (("hundred_position", lambda: hundred_position_profile(fs=1000.0)),
                        ("thesis_rate_table", lambda: rate_table_step_profile(fs=1000.0))):
        t0 = time.perf_counter()
        prof = build()
        t1 = time.perf_counter()
        ideal_imu(prof.trajectory, lat=0.7)
        t2 = time.perf_counter()
        n = prof.trajectory.n
        rows.append((name, n, t1 - t0, t2 - t1))
    print(f"{'profile':<20}{'samples':>10}{'build s':>10}{'ideal s':>10}{'Msamples/s':>12}")
    for name, n, tb, ti in rows:
        print(f"{name:<20}{n:>10}{tb:>10.2f}{ti:>10.2f}{n / (tb + ti) / 1e6:>12.2f}")
    report("bench_sim_profiles", {f"{r[0]} {k} ns/sample": 1e9 * r[i] / r[1] for r in rows for k, i in (("build", 2), ("ideal", 3))}, times=[f"{r[0]} {k} ns/sample" for r in rows for k in ("build", "ideal")])


if __name__ == "__main__":
    main()
