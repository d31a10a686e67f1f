"""GNSS/INS outputs before / after a change: every array of GinsFilter on seven seeded scenarios (GNSS position and
velocity with a lever arm, 21 states and the smoother; every aid: odometer, NHC, ZUPT + ZARU, barometer,
magnetometer, 15 states; increments at a 0.05 s covariance step; odometer without NHC; NHC with a loose gate; the
step-by-step filter) saved from one tree and compared on another.

Run:  PYTHONPATH=src python benchmarks/bench_gins_identity.py save before.npz   (on the old tree)
      PYTHONPATH=src python benchmarks/bench_gins_identity.py cmp before.npz    (on the new tree)

Prints each array whose relative difference exceeds 1e-9 and the worst relative difference (the aids refactor of
issue 25: 143 arrays, worst 4.7e-12).
"""
import sys

import numpy as np

from imunav.ins.gins import GinsConfig, GinsFilter
from imunav.io.kfgins import ImuIncrements
from imunav.sim import presets, simulate_imu
from imunav.sim.gnss import simulate_gnss, simulate_magnetometer
from imunav.sim.vehicle import demo_drive, simulate_baro, simulate_odometer, vehicle_trajectory
from imunav.units import DEG

ORIGIN = (30.44 * DEG, 114.47 * DEG, 20.0)
LEVER = (0.136, -0.301, -0.184)
WHEEL = (0.0, 0.8, 0.3)

def flat(res, prefix, out):
    for k, v in vars(res).items():
        if isinstance(v, np.ndarray):
            out[f"{prefix}.{k}"] = np.asarray(v, dtype=float)
        elif hasattr(v, "lla") and hasattr(v, "cov_nav"):
            flat(v, prefix + "." + k, out)

def main(mode, path):
    out = {}
    truth = vehicle_trajectory(demo_drive(240), fs=100, origin_lla=ORIGIN)
    st = dict(lla0=truth.pos_lla[0], vel0=truth.vel_ned[0], q0=truth.q_nb[0])
    imu = simulate_imu(truth, presets.get("mems_adis16465"), rng=1)
    g = simulate_gnss(truth, lever_arm=LEVER, t_offset=0.0073, rng=2)
    # 1: GNSS pos+vel, lever arm, 21 states, smoother
    cfg = GinsConfig.from_preset("mems_adis16465", lever_arm=LEVER)
    flat(GinsFilter(cfg).run(imu, g, smoother=True, **st), "a", out)
    # 2: every aid
    odo = simulate_odometer(truth, lever_arm=WHEEL, scale_factor=0.005, noise_std=0.05, rng=5)
    baro = simulate_baro(truth, rng=6)
    mag = simulate_magnetometer(truth, rng=7)
    static = np.linalg.norm(truth.vel_ned, axis=1) < 1e-3
    cfg2 = GinsConfig.from_preset("mems_adis16465", lever_arm=LEVER, nhc_noise_std=0.1, odo_lever_arm=WHEEL,
                                  scale_factors=False)
    flat(GinsFilter(cfg2).run(imu, g, odometer=odo, baro=baro, mag=mag, static=static, smoother=True, **st), "b", out)
    cfg3 = GinsConfig.from_preset("mems_adis16465", lever_arm=LEVER, nhc_noise_std=0.1, odo_lever_arm=WHEEL,
                                  use_gnss_velocity=False, cov_interval_s=0.05)
    flat(GinsFilter(cfg3).run(ImuIncrements.from_imu_data(imu, 100.0), g, odometer=odo, baro=baro, mag=mag,
                              static=static, **st), "c", out)
    cfg4 = GinsConfig.from_preset("mems_adis16465", lever_arm=LEVER, odo_lever_arm=WHEEL)
    flat(GinsFilter(cfg4).run(imu, g, odometer=odo, static=static, **st), "d", out)
    cfg5 = GinsConfig.from_preset("mems_adis16465", nhc_noise_std=0.05, gate_alpha=0.05)
    flat(GinsFilter(cfg5).run(imu, g, static=static, **st), "e", out)
    # 3: step mode
    f = GinsFilter(cfg)
    n = 3000
    f.reset(lla0=st["lla0"], vel0=st["vel0"], q0=st["q0"], t0=imu.t[0], fs=100.0, odometer=True)
    dth = imu.gyro * 0.01
    dv = imu.accel * 0.01
    odo_at = np.interp(imu.t, odo.t, odo.speed)
    rec = []
    for k in range(1, n):
        f.step(imu.t[k], dth[k], dv[k], gnss=g, odometer_speed=odo_at[k] if k % 10 == 0 else None,
               static=bool(static[k]), mag_field=mag.field_b[k // 10] if k % 50 == 0 else None)
        rec.append(np.concatenate([f.lla, f.vel_ned, f.q_nb, f.imu_errors, np.diag(f.P)]))
    out["step"] = np.array(rec)
    if mode == "save":
        np.savez(path, **out)
        print("saved", len(out))
    else:
        ref = np.load(path)
        worst = 0.0
        for k in ref.files:
            if k not in out:
                print("MISSING", k)
                continue
            a, b = ref[k], out[k]
            if a.shape != b.shape:
                print("SHAPE", k, a.shape, b.shape)
                continue
            both = np.isnan(a) & np.isnan(b)
            if np.any(np.isnan(a) != np.isnan(b)):
                print("NAN MISMATCH", k, int(np.sum(np.isnan(a) != np.isnan(b))))
            d = np.abs(np.where(both, 0, a - b)) / np.maximum(1.0, np.abs(np.where(both, 0, a)))
            m = float(np.nanmax(d)) if d.size else 0.0
            worst = max(worst, m)
            if m > 1e-9:
                print("DIFF", k, m)
        print("worst relative diff", worst, "arrays", len(ref.files))

if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
