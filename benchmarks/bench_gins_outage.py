"""KF-GINS outage protocol on a simulated navigation-grade drive (issue 15, acceptance "navigation-grade preset").

Scenario: a 1-hour land-vehicle drive at 200 Hz (:func:`imunav.sim.vehicle.demo_drive`: straights, turns, hills,
speed changes and stops), the IMU of the ``navigation_a15`` preset (KF-GINS's Leador-A15 ``imunoise``: ARW
0.003 deg/sqrt(h), VRW 0.03 m/s/sqrt(h), Gauss-Markov biases 0.027 deg/h and 15 mGal, T = 4 h), RTK-class GNSS
positions at 1 Hz (sigma 1 / 1 / 2 cm, as in KF-GINS's GNSS-RTK.txt) with KF-GINS's antenna lever arm, and the
21-state filter configured from the preset (position updates only, as KF-GINS).  After 600 s of convergence, a
60 s outage every 180 s, repeated with the first outage shifted by 0, 60 and 120 s.

Printed: RMS over all outages of the per-outage maximum horizontal, vertical and 3-D drift and of the maximum
roll, pitch and heading errors, beside KF-GINS's published figures for its Leador-A15 data set (0.647 m,
0.587 m, 0.874 m, heading 0.020 deg).  The data differ (a simulated drive with a matched error model, not the
recorded one: the real unit's errors are not exactly Gauss-Markov, the real trajectory and its dynamics differ,
and the RTK reference has its own errors), so this is a sanity comparison of magnitude.  Also printed: the
share of outages whose drift the filter's predicted 3 sigma contains (acceptance: >= 95 %).

Times are CPU seconds of this process (time.process_time): the figures hold on a shared, loaded machine.

With ``--mems``: the MEMS acceptance instead: the ``mems_adis16465`` preset at 100 Hz, the same protocol
run with GNSS only and with odometer + non-holonomic constraint (odometer on the right rear wheel, on the
rear axle below the IMU, scale error 0.5 %, noise 0.05 m/s), and the ratio of the horizontal drifts
(acceptance: >= 3).

Run:  PYTHONPATH=src python benchmarks/bench_gins_outage.py [--duration 3600] [--fs 200] [--seed 1] [--mems]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from imunav.ins.gins import GinsConfig
from imunav.ins.gins.outage import outage_test
from imunav.sim import presets, simulate_imu
from imunav.sim.gnss import simulate_gnss
from imunav.sim.vehicle import demo_drive, simulate_odometer, vehicle_trajectory
from imunav.units import DEG

KFGINS_PUBLISHED = {"horizontal_m": 0.647, "vertical_m": 0.587, "3d_m": 0.874, "heading_deg": 0.020}
LEVER = (0.136, -0.301, -0.184)  # KF-GINS dataset/kf-gins.yaml antlever


WHEEL = (0.0, 0.8, 0.3)  # right rear wheel contact point, body FRD, m (the IMU sits above the rear axle)


def mems(a: argparse.Namespace) -> None:
    """MEMS preset with and without odometer + NHC on the same data."""
    truth = vehicle_trajectory(demo_drive(a.duration), fs=100.0, origin_lla=(30.44 * DEG, 114.47 * DEG, 20.0))
    imu = simulate_imu(truth, presets.get("mems_adis16465"), rng=a.seed)
    gnss = simulate_gnss(truth, pos_noise=(0.02, 0.02, 0.04), vel_noise=None, lever_arm=LEVER, rng=a.seed + 1)
    odo = simulate_odometer(truth, lever_arm=WHEEL, scale_factor=0.005, noise_std=0.05, rng=a.seed + 2)
    base = dict(lever_arm=LEVER, use_gnss_velocity=False, init_pos_std=0.05, init_vel_std=0.05,
                init_att_std=np.radians([0.1, 0.1, 0.5]))
    out = {}
    for name, kw, o in (("GNSS only", {}, None),
                        ("GNSS + ODO + NHC", dict(nhc_noise_std=0.1, odo_lever_arm=WHEEL, odo_noise_std=0.05,
                                                  odo_scale_std=0.01), odo)):
        cfg = GinsConfig.from_preset("mems_adis16465", **base, **kw)
        out[name] = outage_test(imu, gnss, cfg, truth, lla0=truth.pos_lla[0], vel0=truth.vel_ned[0],
                                q0=truth.q_nb[0], converge_s=300.0, odometer=o).rms()
    print(f"{a.duration:.0f} s drive at 100 Hz, preset mems_adis16465, seed {a.seed}, "
          f"{out['GNSS only']['n_outages']} outages of 60 s")
    print(f"{'RMS of per-outage max':28s}" + "".join(f"{n:>20s}" for n in out))
    for k in ("horizontal_m", "vertical_m", "3d_m", "roll_deg", "pitch_deg", "heading_deg", "contained_3sigma"):
        print(f"{k:28s}" + "".join(f"{r[k]:>20.4f}" for r in out.values()))
    ratio = out["GNSS only"]["horizontal_m"] / out["GNSS + ODO + NHC"]["horizontal_m"]
    print(f"horizontal drift {ratio:.1f}x smaller with ODO + NHC (acceptance >= 3)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=3600.0)
    ap.add_argument("--fs", type=float, default=200.0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--preset", default="navigation_a15")
    ap.add_argument("--mems", action="store_true", help="the MEMS ODO + NHC comparison instead")
    a = ap.parse_args()
    if a.mems:
        mems(a)
        return
    t0 = time.process_time()
    truth = vehicle_trajectory(demo_drive(a.duration), fs=a.fs, origin_lla=(30.4447873701 * DEG, 114.4718632047 * DEG,
                                                                          20.899), t0=456300.0)
    imu = simulate_imu(truth, presets.get(a.preset), rng=a.seed)
    gnss = simulate_gnss(truth, pos_noise=(0.01, 0.01, 0.02), vel_noise=None, lever_arm=LEVER, rng=a.seed + 1)
    cfg = GinsConfig.from_preset(a.preset, lever_arm=LEVER, use_gnss_velocity=False, init_pos_std=(0.005, 0.004, 0.008),
                                 init_vel_std=(0.003, 0.004, 0.004), init_att_std=np.radians([0.003, 0.003, 0.023]))
    t_sim = time.process_time() - t0
    t0 = time.process_time()
    rep = outage_test(imu, gnss, cfg, truth, lla0=truth.pos_lla[0], vel0=truth.vel_ned[0], q0=truth.q_nb[0],
                      converge_s=600.0)
    t_run = time.process_time() - t0
    r = rep.rms()
    print(f"{a.duration:.0f} s drive at {a.fs:g} Hz, preset {a.preset}, seed {a.seed}: {r['n_outages']} outages of 60 s "
          f"(3 shifts); simulation {t_sim:.1f} s CPU, 3 filter runs {t_run:.1f} s CPU "
          f"({t_run / 3 / truth.n * 1e6:.2f} us per IMU sample incl. outage bookkeeping)")
    print(f"{'RMS of per-outage max':28s}{'imunav (simulated)':>20s}{'KF-GINS (published, A15)':>28s}")
    for k in ("horizontal_m", "vertical_m", "3d_m", "roll_deg", "pitch_deg", "heading_deg"):
        pub = KFGINS_PUBLISHED.get(k)
        print(f"{k:28s}{r[k]:>20.4f}{'' if pub is None else f'{pub:.3f}':>28s}")
    print(f"outages inside the predicted 3 sigma (N, E, D at every covariance record): "
          f"{100 * r['contained_3sigma']:.0f} % (acceptance >= 95 %)")


if __name__ == "__main__":
    main()
