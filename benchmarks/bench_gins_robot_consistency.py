"""GNSS/INS on the simulated robot's log: consistency over seeded drives (issue 24).

Each drive is :func:`imunav.sim.robot_log.simulate_robot_log` written as a ROS 1 bag, read back by
:func:`imunav.io.navlog.read_nav_sources` and run by :func:`imunav.ins.gins.logrun.run_log` with its defaults and
the antenna's lever arm (0, 0, -0.3) m, as a user runs ``imunav gins run robot.bag --gnss-lever-arm 0,0,-0.3``.
Two truths:

* ``matched``: the IMU's errors drawn from the filter's own model (:func:`imunav.ins.gins.truth.matched_errors`
  of ``GinsConfig.from_preset("consumer_mems")``; the run's ``accel_misalignment_std`` set to 0, as the truth
  has none), the wheels slipping sideways and the body bouncing with
  sigma 0.05 m/s (the NHC's sigma) and an odometer noise of 0.05 m/s (its sigma floor): the truth under which
  the NEES is chi^2(3) (Bar-Shalom, Li & Kirubarajan 2001, section 5.4);
* ``preset``: the scenario as the README runs it (the ``consumer_mems`` preset: axis misalignment, flicker,
  g-sensitivity the filter does not model; no slip, odometer noise 0.02 m/s under the 0.05 m/s floor):
  robustness, not consistency.

Printed per truth: the mean NEES of position, velocity and attitude (epochs every 10 s, from 60 s after the
start and from the start), their two-sided 95 % band of chi^2(3 R)/R for one epoch's mean over the R drives,
the mean NIS / dof of the GNSS position, odometer and NHC updates with their band, and the estimated GNSS
latency (truth 0.15 s) and mounting against the truth over the drives.

Run: ``python benchmarks/bench_gins_robot_consistency.py [--drives 30] [--first-seed 100]`` (about 1.5 s per
drive and truth on one core).
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
from scipy.stats import chi2

from imunav.ins.gins import GinsConfig
from imunav.ins.gins.logrun import LogRunOptions, run_log
from imunav.ins.gins.truth import matched_errors, navigation_errors, nees_blocks
from imunav.io.navlog import read_nav_sources
from imunav.rotation import quat_multiply
from imunav.sim.robot_log import simulate_robot_log, write_robot_log

LEVER = (0.0, 0.0, -0.3)
AIDS = ("gnss_position", "odometer", "nhc")


def drive(seed: int, truth: str, folder: Path) -> dict:
    """One drive through a ROS 1 bag: NEES per epoch (3, K) from the start, NIS per aid, latency, mounting."""
    if truth == "matched":
        model = matched_errors(GinsConfig.from_preset("consumer_mems"), np.random.default_rng(seed + 1000)).model
        log = simulate_robot_log(seed, imu_model=model, slip_std=(0.05, 0.05), odometer_noise_std=0.05)
    else:
        log = simulate_robot_log(seed)
    write_robot_log(log, folder, formats=("ros1",))
    # the matched truth has no accelerometer misalignment: none in the attitude σ either (the preset's has one)
    ov = {"accel_misalignment_std": 0.0} if truth == "matched" else {}
    run = run_log(read_nav_sources(folder / "robot.bag"), LogRunOptions(gnss_lever_arm=LEVER, overrides=ov))
    r, tr = run.result, log.truth.trajectory
    q_imu = quat_multiply(tr.q_nb, np.broadcast_to(log.truth.q_base_imu, (tr.t.size, 4)))
    at = np.arange(10.0, tr.t[-1], 10.0)
    k = np.searchsorted(r.cov_t, at, side="right") - 1  # the last covariance record at or before each epoch
    it = np.searchsorted(tr.t, r.cov_t[k] - 1e-9)
    ir = np.searchsorted(r.t, r.cov_t[k] - 1e-9)
    truth_imu = SimpleNamespace(pos_lla=tr.pos_lla[it], vel_ned=tr.vel_ned[it], q_nb=q_imu[it])
    est = SimpleNamespace(lla=r.lla[ir], vel_ned=r.vel_ned[ir], q_nb=r.q_nb[ir])
    e = navigation_errors(truth_imu, np.arange(k.size), est)
    nis = {a: (r.aids[a].nis / r.aids[a].dof)[r.aids[a].accepted.astype(bool)] for a in AIDS if a in r.aids}
    euler, sd = run.mounting_euler()
    err = np.degrees(euler) - np.asarray(log.truth.mounting_euler_deg)
    return {"t": r.cov_t[k], "nees": nees_blocks(e, r.cov_nav[k]), "nis": nis,
            "delay": float(r.gnss_delay[-1]), "delay_true": log.truth.gnss_latency_s,
            "mount_err": (np.remainder(err + 180.0, 360.0) - 180.0), "mount_sd": np.degrees(sd)}


def report(truth: str, runs: list[dict]) -> dict:
    R = len(runs)
    K = min(x["nees"].shape[1] for x in runs)
    nees = np.array([x["nees"][:, :K] for x in runs])  # (R, 3, K)
    t = runs[0]["t"][:K]
    lo, hi = chi2.ppf([0.025, 0.975], 3 * R) / R
    out = {"truth": truth, "drives": R, "nees_band": [lo, hi]}
    for name, sel in (("after_60s", t >= 60.0), ("from_start", t >= 0.0)):
        out[f"nees_{name}"] = dict(zip(("position", "velocity", "attitude"),
                                       nees[:, :, sel].mean(axis=0).mean(axis=1).round(3).tolist()))
    for a in AIDS:
        x = np.concatenate([r["nis"][a] for r in runs if a in r["nis"]])
        dof = {"gnss_position": 3, "odometer": 1, "nhc": 2}[a]
        b = chi2.ppf([0.025, 0.975], dof * x.size) / (dof * x.size)
        # the χ² band holds for white innovations; the drives' own scatter of their mean NIS also counts what is
        # shared inside a drive (the slip's low frequencies, sampled once a second by the NHC)
        per = np.array([r["nis"][a].mean() for r in runs if a in r["nis"] and r["nis"][a].size])  # already per dof
        se = float(per.std(ddof=1) / np.sqrt(per.size))
        out[f"nis_{a}"] = {"mean_per_dof": round(float(x.mean()), 4), "n": int(x.size), "band": b.round(4).tolist(),
                           "drive_se": round(se, 4),
                           "drive_interval": [round(float(per.mean() - 2 * se), 4), round(float(per.mean() + 2 * se), 4)]}
    d = np.array([r["delay"] for r in runs])
    out["latency_s"] = {"truth": runs[0]["delay_true"], "mean": round(float(d.mean()), 4),
                        "sd": round(float(d.std(ddof=1)), 4), "sd_of_mean": round(float(d.std(ddof=1) / np.sqrt(R)), 4)}
    m = np.array([r["mount_err"] for r in runs])
    out["mounting_err_deg"] = {"mean": m.mean(axis=0).round(3).tolist(), "rms": np.sqrt((m**2).mean(axis=0)).round(3).tolist(),
                               "reported_sd": np.array([r["mount_sd"] for r in runs]).mean(axis=0).round(3).tolist()}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--drives", type=int, default=30)
    ap.add_argument("--first-seed", type=int, default=100)
    ap.add_argument("--truths", default="matched,preset")
    a = ap.parse_args()
    for truth in a.truths.split(","):
        t0 = time.perf_counter()
        runs = []
        for seed in range(a.first_seed, a.first_seed + a.drives):
            with tempfile.TemporaryDirectory() as d:
                runs.append(drive(seed, truth, Path(d)))
        rep = report(truth, runs)
        rep["seconds"] = round(time.perf_counter() - t0, 1)
        print(json.dumps(rep, indent=1))


if __name__ == "__main__":
    main()
