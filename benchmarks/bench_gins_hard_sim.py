"""GNSS/INS on the hard robot and the hard car (issue 33): consistency and outage containment over seeded drives.

Each drive is :func:`imunav.sim.hard_log.simulate_hard_robot_log` or :func:`~imunav.sim.hard_log.simulate_hard_car_log`
(every fault of :mod:`imunav.sim.log_faults` on; ``--faults off`` turns them off, the terrain and the drive
kept) run by :func:`imunav.ins.gins.logrun.run_log` on ``log.sources`` with its defaults (the forward filter) and
the antenna's true lever arm; the mounting is estimated, as a user's run does (``--true-mounting`` gives the
truth: the run before issue 33 estimated it only from a rest, and the car never stands still).

Printed: the mean NEES of position, velocity and attitude (epochs every 10 s from 60 s on, against the IMU's
truth; Bar-Shalom, Li & Kirubarajan 2001, §5.4) with the two-sided 95 % band of chi²(3 R K)/(R K) for the mean
of the R drives' K epochs taken as independent (a generous band: epochs 10 s apart are correlated), the mean
NIS / dof of every aid over its accepted updates with its chi² 95 % band, the share of updates rejected, and the
outage test: per drive, one run without the fixes of seeded outages of 10-60 s, the first 60 s after the start
and each 60 s (robot) or 30 s (car) after the end of the one before; at each outage's end (its last
IMU sample without a fix) the horizontal error against the truth and whether it lies inside the predicted 3σ
(``|e| <= 3 √(P_NN + P_EE)``, the criterion of :func:`imunav.ins.gins.logrun.log_outage_test`).  A consistent
filter has its NEES and NIS inside the bands and 90-99 % of outage ends inside 3σ.

Today's filter (main at 8c8bfc6), seeds 0-29, ``--faults on`` / ``--faults off`` (the drives and terrain kept):

===============================  ======================  ==================  ======================  ===================
figure (95 % band)               robot, faults on        robot, faults off   car, faults on          car, faults off
===============================  ======================  ==================  ======================  ===================
NEES pos / vel / att (2.9-3.1)   348 / 25 / 116          2.5 / 2.7 / 141     1255 / 208 / 952        1129 / 197 / 1034
NIS/dof GNSS (0.99-1.01)         2.76 (4.3 % rejected)   0.99                1.57 (9.9 % rejected)   1.89
NIS/dof NHC, odometer            0.88, 0.81              0.18, 0.21          2.54, 3.66 (32 % rej.)  2.28, 3.31 (34 %)
outage ends inside 3σ            17 % of 140             100 % of 140        11 % of 91              20 % of 91
end error RMS / predicted σ      2.39 m / 0.37 m         0.35 m / 0.40 m     18.1 m / 1.56 m         10.5 m / 1.48 m
===============================  ======================  ==================  ======================  ===================

The hard robot has the real Husky bag's symptoms (GNSS NIS 8.3 for 3 degrees of freedom, the bag's 8.9; outage ends
mostly outside their 3σ) and without the faults the same rough drives are consistent but for the attitude NEES,
which is as high on the plain robot with the ``consumer_mems`` preset (README: 139).  The car fails with and
without the faults: the log run starts every log at rest (``vel0`` zero with σ 0.5 m/s, the levelling of the mean
acceleration, the heading fitted to a dead reckoning whose gyro has an unmeasured turn-on bias), which a car already
at 12-25 m/s breaks; the simulation is not the cause (the filter started from the true state on the faults-off car
gives a GNSS NIS of 1.02-1.05 per dof and no rejection).  The car's figures measure the faults only once the log run
can start in motion.

After issue 33's changes to the filter and the log run (the in-motion start, the adaptive GNSS noise, the
identified correlated GNSS error, the car's mounting levelled while driving instead of given), seeds 0-29 (held out:
the identification's factor and lag were chosen on drives 100-107), the forward filter scored:

===============================  ======================  ==================  ======================
figure (95 % band)               robot, faults on        robot, faults off   car, faults on
===============================  ======================  ==================  ======================
NEES pos / vel / att (2.9-3.1)   3.10 / 11.6 / 84        1.72 / 2.66 / 141   12.3 / 16.9 / 76
NIS/dof GNSS (0.99-1.01)         1.114 (2.0 % rejected)  0.992               1.074 (3.3 % rejected)
NIS/dof NHC, odometer            0.45, 0.78              0.18, 0.21          0.82, 1.31
outage ends inside 3σ            100 % of 140            100 % of 140        89 % of 91
end error RMS / predicted σ      2.33 m / 1.63 m         0.36 m / 0.42 m     7.31 m / 3.49 m
===============================  ======================  ==================  ======================

The position's σ now covers the fixes' correlated error (robot position NEES 348 -> 3.10; car 1255 -> 12.3) and the
outage ends lie inside their 3σ (robot 17 % -> 100 %, car 11 % -> 89 %).  Not yet consistent: velocity and
attitude (the ``consumer_mems`` preset's axis misalignment, which the filter does not model, as on the plain robot;
the car's warm-up bias drift), the NHC and odometer NIS of the robot (conservative: their σ floors) and the car's
outage ends 1 % short of 90 %.

Then the hard robot's wheels met changing ground (``odometer_terrain_std`` 0.08 over 20 s: the real bag's wheel
odometry ended its 60 s outages a quarter of the distance off), and the log run learned to cross-validate the
odometer scale's wander on withheld fixes (``imunav.ins.gins.identify``; candidates and windows chosen on robot
seeds 0-3).  The same robot drives, forward filter, the wander as chosen against the scale taken as constant
(``--config '{"odo_scale_corr_time": Infinity}'``, what the run did before), and held-out seeds 200-229:

===============================  ======================  ======================  ======================
figure (95 % band)               seeds 0-29, chosen      seeds 0-29, constant    seeds 200-229, chosen
===============================  ======================  ======================  ======================
NEES pos / vel / att (2.9-3.1)   3.79 / 12.2 / 83        10.9 / 43.6 / 93        3.19 / 12.0 / 82
NIS/dof GNSS (0.99-1.01)         1.090 (2.0 % rejected)  1.092 (2.0 % rejected)  1.093 (2.0 % rejected)
NIS/dof NHC, odometer            0.53, 0.83              0.63, 1.17              0.54, 0.85
outage ends inside 3σ            99.3 % of 140           79.3 % of 140           100 % of 142
end error RMS / predicted σ      2.46 m / 2.07 m         4.75 m / 1.85 m         2.24 m / 2.09 m
===============================  ======================  ======================  ======================

The hard car after the same change (seeds 0-29; it has no terrain fault and its 240 s drives hold two withheld
windows): NEES 12.3 / 17.1 / 76, GNSS NIS/dof 1.075, outage ends inside 3σ 89 % of 91, end error RMS 8.13 m against
a predicted 4.39 m.  Still not consistent: the velocity and attitude NEES (the preset's axis misalignment: the
attitude's roll and pitch σ is 0.03° where the misalignment leaves 0.2°), and the car's outages.

Then (this session of issue 33) two causes found by switching the faults on one group at a time, each reproduced
on the car without any fault: (1) the accelerometers' axis misalignment of the ``consumer_mems`` preset turns the
heading as well as roll and pitch (a car's heading comes from its accelerations: without the misalignment in the
simulation the heading's z² fell from 3.6 to 1.0), and it turns the velocity that the wheels measure in the
body's axes (a car at 20 m/s under a 0.2° tilt: 7 cm/s vertically, where the filter claimed 1.7 cm/s);
``filter.unmodelled_misalignment`` now adds both to the reported covariance; (2) the fixes' correlated error was
read low on a short log, the residuals' mean over the log holding part of it (:func:`~imunav.ins.gins.identify.
gnss_correlated_std` now corrects for that mean's variance; the factor ``k`` kept as chosen on drives 100-107).
No parameter was chosen on the drives below:

===============================  ======================  ======================  ======================
figure (95 % band)               car, seeds 0-29         robot, seeds 200-229    robot, seeds 0-29
===============================  ======================  ======================  ======================
NEES pos / vel / att (2.9-3.1)   7.33 / 5.79 / 8.56      3.20 / 13.6 / 5.94      3.69 / 12.3 / 5.19
NIS/dof GNSS (0.99-1.01)         1.076                   1.064                   1.066
outage ends inside 3σ            92.3 % of 91            100 % of 142            99.3 % of 140
end error RMS / predicted σ      8.28 m / 4.98 m         2.37 m / 2.21 m         2.47 m / 2.20 m
===============================  ======================  ======================  ======================

The car's outage ends now lie inside their 3σ on 92 % (was 89 %); its NEES is still above the band, and the
robot's velocity NEES (12-14) is not explained by one fault: the wheels' over-reading in turns (the largest
share: 3.6 alone, 0.8 with the true over-reading taken out), the IMU's warm-up, the fixes, the side slip and
the time stamps' jitter each add 0.4-0.9 to its per-axis z², and neither a larger odometer σ nor one that grows
with the yaw rate brings it down.

Then (issue 33, the next session) the wheels' over-reading in turns became a state of the core
(``GinsConfig.odo_turn_std``, default 0.3 s/rad: the odometer reads ``(1 + k)(1 + c |ω_z|)`` times the speed).  With
that fault alone (drives 100-103) the velocity NEES fell from 9.45 to 2.37 (2.35 without the fault).  With every
fault on, the odometer wander's candidates gained 5 % over 30 s (the over-reading no longer hidden in the wander,
the cross-validation picked 3 % where 8 % over 20 s was true; seed 0 of the grid's tuning seeds 0-3: outage ends
1.98 -> 1.47 m).  Main before the change and after it, on the same drives:

===============================  ======================  ======================  ======================
figure (95 % band)               robot 200-229, before   robot 200-229, after    robot 0-29, after
===============================  ======================  ======================  ======================
NEES pos / vel / att (2.9-3.1)   3.20 / 13.6 / 5.94      3.29 / 10.9 / 6.42      3.95 / 10.8 / 5.85
NIS/dof GNSS, odometer           1.064, 0.85             1.063, 0.54             1.067, 0.54
outage ends inside 3σ            100 % of 142            97.9 % of 142           99.3 % of 140
end error RMS / predicted σ      2.37 m / 2.21 m         2.71 m / 2.15 m         2.14 m / 2.18 m
===============================  ======================  ======================  ======================

The velocity NEES falls (13.6 -> 10.9 on the held-out drives) and the outage ends now lie inside the 90-99 % band,
but the held-out ends are 0.34 m worse: the over-reading is estimated 0.02-0.05 s/rad high (z 1.6-3.7 on drives
202-215; 0.01-0.03 even without any other fault), and the odometer then under-reads the turns of an outage.  Still
not in band: the velocity (the odometer's wander on changing ground, then the IMU's warm-up, the side slip) and
the attitude.  Drives 0-29 before the change: 3.69 / 12.3 / 5.19, 99.3 %, 2.47 m.  The hard car (no
over-reading: its 0.3 s/rad prior is learnt away) keeps its figures to the digit: NEES 7.33 / 5.80 / 8.55, 91.2 %
of 91 outage ends inside 3σ, 8.30 m against a predicted 5.00 m.

Why the car is still out of band, one fault group left out at a time (``--without``; tuning drives 100-105, NEES
position / velocity / attitude): all on 5.40 / 8.21 / 7.35; without the fixes' correlated error
(``--without gnss_corr_sigma_m``) 1.95 / 7.07 / 7.00; without the IMU's warm-up (``imu_temp_rise_c``) 4.80 / 4.89 /
4.47; without the other seven groups together 5.86 / 6.22 / 5.40.  The position's excess is the fixes' correlated
error, read too low on a 240 s drive; the velocity's and attitude's, the warm-up, whose bias drifts faster than the
preset's Gauss-Markov allows (three times its σ: 6.2 / 3.9 / 4.6, the position worse: a trade not taken).

Run: ``python benchmarks/bench_gins_hard_sim.py --scenario robot --drives 30 --first-seed 0`` (about 3 s per robot
drive and 1.5-4 s per car drive on one core); importable: :func:`drive` and :func:`report` score one drive and a set.


Then the log run chose its process model by the filter's own predictive density of withheld fixes, the odometer's
wander and the IMU bias instability (the preset's times 1, 2 or 4) on one grid (``logrun._process_models``).  Drives
300-329 had never been run before the choice was made (drives 200-207 had guided it), main at 6eba0b1 before:

===============================  ======================  ======================  ======================  ======================
figure (95 % band)               robot, before           robot, after            car, before             car, after
===============================  ======================  ======================  ======================  ======================
NEES pos / vel / att (2.9-3.1)   2.96 / 8.63 / 5.95      2.62 / 6.98 / 4.14      7.06 / 6.96 / 8.30      6.72 / 4.40 / 5.79
NIS/dof GNSS (0.99-1.01)         1.062 (2.0 % rejected)  1.060 (2.0 % rejected)  1.070 (3.7 % rejected)  1.068 (3.7 % rejected)
NIS/dof NHC, odometer            0.60, 0.52              0.38, 0.42              0.84, 1.22              0.54, 1.00
outage ends inside 3σ            97.9 % of 145           98.6 % of 145           98.9 % of 91            100 % of 91
end error RMS / predicted σ      2.84 m / 2.23 m         2.48 m / 2.26 m         9.06 m / 5.35 m         7.29 m / 5.96 m
===============================  ======================  ======================  ======================  ======================

Still not consistent: the velocity and attitude NEES (above their band on both) and the car's position NEES (the
fixes' correlated error: 5.40 -> 1.95 without it on drives 100-105)."""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from types import SimpleNamespace
from typing import Any

import numpy as np
from scipy.stats import chi2

from imunav.earth import lla_to_ned
from imunav.ins.gins.logrun import LogRunOptions, run_log
from imunav.ins.gins.truth import navigation_errors, nees_blocks
from imunav.rotation import quat_multiply
from imunav.sim.hard_log import HARD_CAR_FAULTS, HARD_ROBOT_FAULTS, simulate_hard_car_log, simulate_hard_robot_log
from imunav.sim.log_faults import LogFaults
from imunav.sim.robot_log import RobotLog

#: Per scenario: outage lengths (s), the gap after each outage (s).
OUTAGES = {"robot": ((10.0, 60.0), 60.0), "car": ((10.0, 60.0), 30.0)}
CONVERGE_S = 60.0


def simulate(scenario: str, seed: int, faults: bool = True, without: tuple[str, ...] = ()) -> RobotLog:
    """The scenario's drive ``seed``, with its faults or none (``LogFaults()``); ``without``: fields of
    :class:`~imunav.sim.log_faults.LogFaults` set back to their neutral defaults, the other faults kept (one group
    at a time: which fault makes which NEES)."""
    f = HARD_ROBOT_FAULTS if scenario == "robot" else HARD_CAR_FAULTS
    f = dataclasses.replace(f, **{n: getattr(LogFaults(), n) for n in without}) if faults else LogFaults()
    return simulate_hard_robot_log(seed, faults=f) if scenario == "robot" else simulate_hard_car_log(seed, faults=f)


def options(scenario: str, log: RobotLog, *, true_mounting: bool = False, config: dict[str, Any] | None = None,
            **overrides: Any) -> LogRunOptions:
    """The log run's defaults with the true antenna lever arm; with ``true_mounting`` the true mounting (what the
    car needed before the log run could level while driving); ``config``: GinsConfig overrides."""
    kw: dict[str, Any] = {"gnss_lever_arm": tuple(log.truth.gnss_lever_arm_base), "smoother": False}
    if true_mounting:
        kw["mounting"] = log.truth.q_base_imu
    if config:
        kw["overrides"] = dict(config)
    return LogRunOptions(**{**kw, **overrides})


def outage_plan(t_end: float, lengths: tuple[float, float], gap: float, rng: np.random.Generator) -> list[tuple[float, float]]:
    """Outages ``(start, length)`` from :data:`CONVERGE_S` on, lengths uniform in ``lengths``, ``gap`` apart."""
    out, s = [], CONVERGE_S
    while True:
        d = float(rng.uniform(*lengths))
        if s + d > t_end - 1.0:
            return out
        out.append((s, d))
        s += d + gap


def nav_scores(log: RobotLog, run: Any, every_s: float = 10.0) -> dict[str, Any]:
    """NEES (3, K) of position, velocity, attitude every ``every_s`` from :data:`CONVERGE_S` on, and per aid the
    accepted NIS / dof and the share rejected."""
    r, tr = run.result, log.truth.trajectory
    q_imu = quat_multiply(tr.q_nb, np.broadcast_to(log.truth.q_base_imu, (tr.t.size, 4)))
    at = np.arange(CONVERGE_S, min(tr.t[-1], r.cov_t[-1]), every_s)
    k = np.searchsorted(r.cov_t, at, side="right") - 1
    it = np.clip(np.searchsorted(tr.t, r.cov_t[k] - 1e-9), 0, tr.t.size - 1)
    ir = np.searchsorted(r.t, r.cov_t[k] - 1e-9)
    truth_imu = SimpleNamespace(pos_lla=tr.pos_lla[it], vel_ned=tr.vel_ned[it], q_nb=q_imu[it])
    est = SimpleNamespace(lla=r.lla[ir], vel_ned=r.vel_ned[ir], q_nb=r.q_nb[ir])
    e = navigation_errors(truth_imu, np.arange(k.size), est)
    nis = {a: (rec.nis / rec.dof)[rec.accepted.astype(bool)] for a, rec in r.aids.items()}
    rejected = {a: float(np.mean(~rec.accepted.astype(bool))) for a, rec in r.aids.items()}
    dof = {a: int(np.max(rec.dof)) for a, rec in r.aids.items() if rec.dof.size}
    return {"nees": nees_blocks(e, r.cov_nav[k]), "nis": nis, "rejected": rejected, "dof": dof}


def outage_ends(log: RobotLog, opts: LogRunOptions, plan: list[tuple[float, float]]) -> dict[str, Any]:
    """One run without the fixes inside the outages of ``plan``: at each outage's end the horizontal error
    against the truth (m) and its predicted σ (``√(P_NN + P_EE)``, m)."""
    src = log.sources
    g = src.gnss
    keep = np.ones(g.n, dtype=bool)
    for s, d in plan:
        keep &= ~((g.t >= s) & (g.t < s + d))
    res = run_log(dataclasses.replace(src, gnss=g.select(keep, "outage test")), opts).result
    tr = log.truth.trajectory
    err, sd = [], []
    for s, d in plan:
        i = int(np.searchsorted(res.t, s + d, side="left")) - 1  # the last IMU sample inside the outage
        j = int(np.searchsorted(res.cov_t, res.t[i], side="right")) - 1
        it = int(np.argmin(np.abs(tr.t - res.t[i])))
        e = lla_to_ned(res.lla[i:i + 1], tr.pos_lla[it])[0, :2]
        err.append(float(np.hypot(*e)))
        sd.append(float(np.sqrt(res.cov_diag[j, 0] + res.cov_diag[j, 1])))
    return {"err_m": np.array(err), "sd_m": np.array(sd), "lengths_s": np.array([d for _, d in plan])}


def drive(scenario: str, seed: int, faults: bool = True, *, true_mounting: bool = False,
          config: dict[str, Any] | None = None, without: tuple[str, ...] = ()) -> dict[str, Any]:
    """One drive: :func:`nav_scores` of the full run (the forward filter) and :func:`outage_ends` of the outage
    run; ``without``: faults left out (:func:`simulate`)."""
    log = simulate(scenario, seed, faults, without)
    opts = options(scenario, log, true_mounting=true_mounting, config=config)
    out = nav_scores(log, run_log(log.sources, opts))
    lengths, gap = OUTAGES[scenario]
    plan = outage_plan(float(log.imu.t[-1]), lengths, gap, np.random.default_rng([seed, 7]))
    out["outages"] = outage_ends(log, opts, plan)
    return out


def report(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Means over the drives with their χ² 95 % bands, and the outage containment."""
    R = len(runs)
    K = min(x["nees"].shape[1] for x in runs)
    nees = np.array([x["nees"][:, :K] for x in runs])  # (R, 3, K)
    lo, hi = chi2.ppf([0.025, 0.975], 3 * R * K) / (R * K)
    out: dict[str, Any] = {"drives": R, "nees_mean": dict(zip(("position", "velocity", "attitude"),
                                                                nees.mean(axis=(0, 2)).round(2).tolist())),
                           "nees_band": [round(float(lo), 3), round(float(hi), 3)], "nis": {}}
    for a in sorted({a for r in runs for a in r["nis"]}):
        x = np.concatenate([r["nis"][a] for r in runs if a in r["nis"]])
        dof = max(r["dof"][a] for r in runs if a in r["dof"])
        b = chi2.ppf([0.025, 0.975], dof * x.size) / (dof * x.size) if x.size else [np.nan, np.nan]
        out["nis"][a] = {"mean_per_dof": round(float(x.mean()), 3) if x.size else None, "dof": dof,
                         "n": int(x.size), "band": [round(float(v), 3) for v in b],
                         "rejected": round(float(np.mean([r["rejected"][a] for r in runs if a in r["rejected"]])), 3)}
    err = np.concatenate([r["outages"]["err_m"] for r in runs])
    sd = np.concatenate([r["outages"]["sd_m"] for r in runs])
    inside = err <= 3.0 * sd
    n = inside.size
    out["outage_ends"] = {"n": int(n), "inside_3sigma": round(float(inside.mean()), 3) if n else None,
                          "target": [0.90, 0.99], "err_rms_m": round(float(np.sqrt(np.mean(err**2))), 2) if n else None,
                          "predicted_sd_rms_m": round(float(np.sqrt(np.mean(sd**2))), 2) if n else None,
                          "normalised_err_rms": round(float(np.sqrt(np.mean((err / sd) ** 2))), 2) if n else None}
    return out


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--drives", type=int, default=30)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--scenario", choices=("robot", "car"), default="robot")
    ap.add_argument("--faults", choices=("on", "off"), default="on")
    ap.add_argument("--true-mounting", action="store_true", help="give the run the true mounting")
    ap.add_argument("--config", default=None, help="GinsConfig overrides as JSON, e.g. '{\"gnss_bias_std\": 1}'")
    ap.add_argument("--without", default="", help="LogFaults fields set back to neutral, comma-separated "
                    "(e.g. imu_temp_rise_c or gnss_corr_sigma_m): the scenario's other faults kept")
    a = ap.parse_args(argv)
    without = tuple(w for w in a.without.split(",") if w)
    unknown = sorted(set(without) - {f.name for f in dataclasses.fields(LogFaults)})
    if unknown:
        ap.error(f"--without: {unknown} are not LogFaults fields")
    cfg = json.loads(a.config) if a.config else None
    t0 = time.perf_counter()
    runs = [drive(a.scenario, s, a.faults == "on", true_mounting=a.true_mounting, config=cfg, without=without)
            for s in range(a.first_seed, a.first_seed + a.drives)]
    rep = {"scenario": a.scenario, "faults": a.faults, "without": list(without), "first_seed": a.first_seed,
           "config": cfg, **report(runs),
           "seconds": round(time.perf_counter() - t0, 1)}
    print(json.dumps(rep, indent=1))
    return rep


if __name__ == "__main__":
    main()
