"""Speed of imunav's attitude filters on a BROAD trial, side by side with
ahrs (pure Python) and vqf (C++ core), in one run.

Acceptance: Mahony and Madgwick <= 2 µs/sample, MEKF <= 10 µs/sample, each
>= 50x faster than the ahrs counterpart; ratio to vqf printed.

Run:  python benchmarks/bench_attitude_speed.py [--trial NAME] [--ahrs-samples 3000]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _before_after import report  # the before (a308974) / after lines

from imunav.attitude.adaptive import AdaptiveMEKF
from imunav.attitude.madgwick import Madgwick
from imunav.attitude.mahony import Mahony
from imunav.attitude.mekf import MEKF
from imunav.io.broad import load_broad
from imunav.io.datasets import shared_data_path


def best_of(fn, repeat=3):
    ts = []
    for _ in range(repeat):  # CPU time of this process: on a shared machine wall time measures the wait for a core
        t0 = time.process_time()
        fn()
        ts.append(time.process_time() - t0)
    return min(ts)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--trial", default="05_undisturbed_slow_rotation_with_breaks_B")
    ap.add_argument("--ahrs-samples", type=int, default=3000, help="samples timed for the slow ahrs filters")
    args = ap.parse_args()
    path = shared_data_path("broad", f"{args.trial}.mat")
    if path is None:
        raise SystemExit("BROAD data not found (set IMUNAV_DATA)")
    tr = load_broad(path)
    d = tr.imu
    n = d.n
    g, a, m = d.gyro, d.accel, d.mag
    dt = 1.0 / tr.fs

    imu = {
        "madgwick": Madgwick(0.1),
        "mahony": Mahony(0.74, 0.0012),
        "mekf": MEKF(),
        "adaptive": AdaptiveMEKF(),
    }
    for f in imu.values():  # compile
        f.run(d.slice(0, 100))
    us = {k: best_of(lambda f=f: f.run(d)) / n * 1e6 for k, f in imu.items()}

    import ahrs.filters as af

    k = args.ahrs_samples

    def ahrs_loop(obj, upd):
        q = np.array([1.0, 0.0, 0.0, 0.0])
        for i in range(k):
            q = upd(q, g[i], a[i], m[i])
        return q

    mad = af.Madgwick(frequency=tr.fs, gain=0.1)
    mah = af.Mahony(frequency=tr.fs, k_P=0.74, k_I=0.0012)
    ekf = af.EKF(gyr=g[:2], acc=a[:2], mag=m[:2], frequency=tr.fs, frame="NED")  # mag given so h() includes it
    ahrs_us = {
        "madgwick": best_of(lambda: ahrs_loop(mad, mad.updateMARG), 1) / k * 1e6,
        "mahony": best_of(lambda: ahrs_loop(mah, mah.updateMARG), 1) / k * 1e6,
        "mekf": best_of(lambda: ahrs_loop(ekf, ekf.update), 1) / k * 1e6,
    }
    ahrs_us["adaptive"] = ahrs_us["mekf"]

    from vqf import VQF

    gg, aa, mm = (np.ascontiguousarray(x) for x in (g, a, m))
    vqf_us = best_of(lambda: VQF(dt).updateBatch(gg, aa, mm)) / n * 1e6

    limits = {"madgwick": 2.0, "mahony": 2.0, "mekf": 10.0, "adaptive": 10.0}
    print(f"BROAD trial {args.trial}: {n} samples; ahrs timed on {k} samples")
    print(f"{'filter':10s} {'imunav us/sa':>12s} {'limit':>6s} {'ahrs us/sa':>11s} {'x faster':>9s} "
          f"{'vqf us/sa':>9s} {'imunav/vqf':>10s}  verdict")
    for key in imu:
        ok = us[key] <= limits[key] and ahrs_us[key] / us[key] >= 50
        print(f"{key:10s} {us[key]:12.2f} {limits[key]:6.1f} {ahrs_us[key]:11.1f} {ahrs_us[key] / us[key]:9.0f} "
              f"{vqf_us:9.2f} {us[key] / vqf_us:10.2f}  {'met' if ok else 'NOT met'}")
    print("(ahrs counterpart of mekf/adaptive: ahrs.filters.EKF)")
    report("bench_attitude_speed", {**{f"{k} us/sample": v for k, v in us.items()}, "vqf us/sample": vqf_us}, times=[f"{k} us/sample" for k in [*us, "vqf"]])


if __name__ == "__main__":
    main()
