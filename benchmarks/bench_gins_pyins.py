"""GNSS/INS side by side: imunav and pyins on the SAME simulated IMU and GNSS (issue 15, item 8).

Scenario: a land-vehicle drive (:func:`imunav.sim.vehicle.demo_drive`, turns, hills, stops), the IMU of a
preset (:func:`imunav.sim.simulate_imu`, Earth rate and transport rate included), GNSS position and
velocity at 1 Hz with an antenna lever arm (:func:`imunav.sim.gnss.simulate_gnss`), and one seeded initial
error (position, velocity, attitude) given to both filters.

pyins (package ``python-ins``, MIT; test extra) runs its feedback EKF (``pyins.filters.run_feedback_filter``)
on increments made from the same IMU samples by its own ``compute_increments_from_imu(..., 'rate')``, with
``Position`` and ``NedVelocity`` measurements carrying the same lever arm and per-axis σ, and the same fixes as
imunav: those after the first IMU sample (:meth:`imunav.ins.gins.GinsFilter.run` drops a fix at the first sample,
the initial state standing for it; pyins would use it, one more fix at the start, where the position error is
largest: that alone made pyins' N and E position RMSE 7-8 % smaller over 300 s drives).  Its sensor
models are set from the preset the way a pyins user would: bias σ from the turn-on bias and the
bias-instability σ, bias walk from the Gauss–Markov components (``σ √(2/T)``), noise from the ARW / VRW.

Printed: RMSE of position (N, E, D m), velocity (m/s) and attitude (roll, pitch, yaw deg) against the
truth at the IMU rate, and the wall time per IMU sample (µs) of each filter on the same machine, one after
the other, with their ratio.

Times are CPU seconds of this process (time.process_time): the figures hold on a shared, loaded machine.

With ``--outages``: also the outage protocol of :mod:`imunav.ins.gins.outage` (60 s outages every 180 s after
``--converge`` s, first outage shifted by 0, 60 and 120 s) on the same IMU and GNSS, through both filters, and the
RMS over outages of the per-outage maximum horizontal, vertical and 3-D drift and attitude errors of each
(:func:`imunav.ins.gins.outage.outage_drift` on both tracks; pyins costs about 4 filter runs more;
``--outages-only`` skips the full-GNSS comparison and so one pyins run).  pyins takes milliseconds per IMU
sample: ``--outages --outages-only --duration 425 --converge 60 --fs 50`` is the smallest run with 6 outages
(2 per shift).

With ``--seeds N``: the full-GNSS comparison on N paired scenarios (seeds ``--seed`` .. ``--seed`` + N - 1, each
drawn once and run through both filters): per-seed RMSE of both, their means per axis, and the paired ratio
imunav / pyins per axis (mean of the per-seed ratios ± its standard error over seeds), which says whether a gap
on one seed is noise.  ``--pyins-cache FILE.npz`` then keeps pyins' errors per scenario.

Run:  PYTHONPATH=src python benchmarks/bench_gins_pyins.py [--duration 600] [--preset mems_adis16465] [--seed 1]
      [--outages [--converge 300] [--outages-only] [--pyins-cache FILE.npz]]
      [--seeds N [--pyins-cache FILE.npz]]
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
import time
from dataclasses import dataclass, replace
from types import SimpleNamespace

import numpy as np

from imunav import earth
from imunav.io.gnss import GnssData
from imunav.rotation import (
    euler_from_quat,
    quat_conjugate,
    quat_from_euler,
    quat_from_rotvec,
    quat_multiply,
    rotvec_from_quat,
)
from imunav.sim import presets, simulate_imu
from imunav.sim.error_model import TriadErrors
from imunav.sim.gnss import simulate_gnss
from imunav.sim.trajectory import Trajectory
from imunav.sim.vehicle import demo_drive, vehicle_trajectory
from imunav.timeseries import ImuData
from imunav.units import DEG

LEVER_ARM = np.array([0.5, -0.3, -1.2])  # antenna, body FRD, m
POS_NOISE = np.array([0.5, 0.5, 1.0])  # m, white, N E D
VEL_NOISE = np.array([0.05, 0.05, 0.1])  # m/s
INIT_SD = {"pos": 1.0, "vel": 0.1, "level_deg": 0.1, "azimuth_deg": 1.0}


@dataclass
class Scenario:
    """Everything both filters get: the IMU samples, the GNSS fixes, the initial state and the truth."""

    truth: Trajectory
    imu: ImuData
    gnss: GnssData
    lla0: np.ndarray
    vel0: np.ndarray
    q0: np.ndarray
    preset: str


def make_scenario(duration: float, preset: str, seed: int, fs: float = 100.0) -> Scenario:
    """The drive, its IMU and GNSS, and one initial error drawn from ``INIT_SD`` (seeded)."""
    truth = vehicle_trajectory(demo_drive(duration), fs=fs, origin_lla=(30.44 * DEG, 114.47 * DEG, 20.0),
                               t0=456300.0)
    rng = np.random.default_rng(seed)
    imu = simulate_imu(truth, presets.get(preset), rng=seed)
    gnss = simulate_gnss(truth, pos_noise=POS_NOISE, vel_noise=VEL_NOISE, lever_arm=LEVER_ARM, rng=seed + 1)
    dpos = INIT_SD["pos"] * rng.standard_normal(3)
    rn, re = earth.radii(truth.pos_lla[0, 0])
    lla0 = truth.pos_lla[0] + [dpos[0] / rn, dpos[1] / (re * np.cos(truth.pos_lla[0, 0])), -dpos[2]]
    vel0 = truth.vel_ned[0] + INIT_SD["vel"] * rng.standard_normal(3)
    dphi = np.radians([INIT_SD["level_deg"], INIT_SD["level_deg"], INIT_SD["azimuth_deg"]]) * rng.standard_normal(3)
    q0 = quat_multiply(quat_from_rotvec(dphi), truth.q_nb[0])
    return Scenario(truth, imu, gnss, lla0, vel0, q0, preset)


def scenario_tag(sc: Scenario, **settings) -> str:
    """The key of pyins' cached results: the settings, pyins' version, the fix set it gets and a hash of every array
    both filters get (IMU, GNSS, initial state), so that a changed scenario or peer never reuses stale errors."""
    from importlib.metadata import version

    h = hashlib.sha1()
    for a in (sc.imu.t, sc.imu.gyro, sc.imu.accel, sc.gnss.t, sc.gnss.lla, sc.gnss.pos_std, sc.gnss.vel_ned,
              sc.gnss.vel_std, sc.lla0, sc.vel0, sc.q0):
        h.update(np.ascontiguousarray(a, dtype=float).tobytes())
    head = " ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in settings.items())
    return f"{head} pyins={version('python-ins')} pyins-fixes=after-first-imu-sample sha1={h.hexdigest()[:16]}"


def nav_errors(truth: Trajectory, t: np.ndarray, lla: np.ndarray, vel: np.ndarray, q: np.ndarray) -> dict:
    """RMSE of position (N E D m), velocity (m/s) and attitude (roll pitch yaw deg, small-angle) on the truth grid."""
    idx = np.searchsorted(truth.t, t)
    ok = (idx < truth.n) & (np.abs(truth.t[np.minimum(idx, truth.n - 1)] - t) < 1e-6)
    idx, t = idx[ok], t[ok]
    ref = truth.pos_lla[idx]
    dn = earth.dlla_to_ned(lla[ok] - ref, ref)
    dv = vel[ok] - truth.vel_ned[idx]
    dphi = rotvec_from_quat(quat_multiply(q[ok], quat_conjugate(truth.q_nb[idx])))  # NED frame error
    # in roll/pitch/yaw: compare Euler angles (wrapped)
    de = np.degrees(euler_from_quat(q[ok]) - euler_from_quat(truth.q_nb[idx]))
    de = (de + 180.0) % 360.0 - 180.0

    def rms(x):
        return np.sqrt(np.mean(x**2, axis=0)).tolist()

    return {"pos_rmse_ned_m": rms(dn), "vel_rmse_ned_mps": rms(dv), "att_rmse_rpy_deg": rms(de),
            "att_rmse_total_deg": float(np.degrees(np.sqrt(np.mean(np.sum(dphi**2, axis=1))))), "n": int(ok.sum())}


def _pyins_sensor(te: TriadErrors):
    """pyins EstimationModel parameters from an imunav triad error model (see the module docstring)."""
    sig, tc = te.bias_instability.components() if te.bias_instability is not None else (np.zeros((1, 3)),
                                                                                          np.ones((1, 3)))
    bias_sd = np.sqrt(te.bias**2 + np.sum(sig**2, axis=0)) + 1e-12
    bias_walk = np.sqrt(np.sum(2 * sig**2 / tc, axis=0))
    dev = te.scale_misalignment - np.eye(3)
    scale_sd = np.full((3, 3), max(float(np.sqrt(np.mean(np.diag(dev) ** 2))), 1e-6))
    return bias_sd, te.noise_density, bias_walk, scale_sd


def run_pyins(sc: Scenario, *, track: bool = False) -> dict:
    """pyins' feedback EKF on the scenario: errors and µs per IMU sample (pyins is imported here: a peer);
    with ``track`` also its track (``t``, ``lla``, ``q_nb``, ``euler()``, ``cov_t``, ``cov_diag``) under "track"."""
    import pandas as pd  # pyins works on DataFrames
    from pyins import filters, inertial_sensor, measurements, strapdown  # optional peer (test extra)
    from pyins.util import ACCEL_COLS, GYRO_COLS, LLA_COLS, RPH_COLS, VEL_COLS

    m = presets.get(sc.preset)
    imu_df = pd.DataFrame(np.hstack([sc.imu.gyro, sc.imu.accel]), index=sc.imu.t, columns=GYRO_COLS + ACCEL_COLS)
    t_start = time.process_time()
    inc = strapdown.compute_increments_from_imu(imu_df, "rate")
    g = sc.gnss.select(sc.gnss.t > sc.imu.t[0], "at the first IMU sample (imunav does not use it either)")
    lla_deg = np.column_stack([np.degrees(g.lla[:, :2]), g.lla[:, 2]])
    pos = measurements.Position(pd.DataFrame(lla_deg, index=g.t, columns=LLA_COLS), 1.0, LEVER_ARM)
    pos.R = np.diag(POS_NOISE**2)
    vel = measurements.NedVelocity(pd.DataFrame(g.vel_ned, index=g.t, columns=VEL_COLS), 1.0, LEVER_ARM)
    vel.R = np.diag(VEL_NOISE**2)
    gb, gn, gw, gs = _pyins_sensor(m.gyro)
    ab, an, aw, as_ = _pyins_sensor(m.accel)
    pva0 = pd.Series(np.hstack([np.degrees(sc.lla0[:2]), sc.lla0[2], sc.vel0, np.degrees(euler_from_quat(sc.q0))]),
                     index=LLA_COLS + VEL_COLS + RPH_COLS, name=sc.imu.t[0])
    res = filters.run_feedback_filter(
        pva0, INIT_SD["pos"], INIT_SD["vel"], INIT_SD["level_deg"], INIT_SD["azimuth_deg"], inc,
        gyro_model=inertial_sensor.EstimationModel(gb, gn, gw, gs),
        accel_model=inertial_sensor.EstimationModel(ab, an, aw, as_),
        measurements=[pos, vel], time_step=0.1)
    wall = time.process_time() - t_start
    tr = res.trajectory
    lla = np.column_stack([np.radians(tr[LLA_COLS[:2]].to_numpy()), tr[LLA_COLS[2]].to_numpy()])
    q = quat_from_euler(np.radians(tr[RPH_COLS].to_numpy()))
    out = nav_errors(sc.truth, tr.index.to_numpy(), lla, tr[VEL_COLS].to_numpy(), q)
    out["us_per_sample"] = wall / sc.imu.t.size * 1e6
    if track:
        sd = res.trajectory_sd
        cov = np.zeros((len(sd), 21))
        cov[:, 0:3] = sd[["north", "east", "down"]].to_numpy() ** 2
        out["track"] = SimpleNamespace(t=tr.index.to_numpy(), lla=lla, q_nb=q, euler=lambda: euler_from_quat(q),
                                       cov_t=sd.index.to_numpy(), cov_diag=cov)
    return out


_KEYS = ("horizontal_m", "vertical_m", "drift_3d_m", "roll_deg", "pitch_deg", "heading_deg", "contained")


def _cache_kind(z, path: str, kind: str) -> None:
    """Refuse a cache file of the other kind (outage reports / per-seed errors): one line, nothing overwritten."""
    got = str(z["kind"]) if "kind" in z.files else "unknown"
    if got != kind:
        raise SystemExit(f"{path} holds pyins {got} results, not {kind}: give another --pyins-cache file")


def _load_cache(path: str | None, tag: str) -> list | None:
    """pyins' outage reports of an earlier run on the same scenario (``tag``), or None."""
    from imunav.ins.gins.outage import OutageReport

    if path is None or not os.path.exists(path):
        return None
    with np.load(path, allow_pickle=False) as z:
        _cache_kind(z, path, "outages")
        if str(z["tag"]) != tag:
            print(f"{path}: made for another scenario ({z['tag']}); running pyins again")
            return None
        n = int(z["n_shifts"])
        return [OutageReport([tuple(o) for o in z[f"outages{i}"]], *(np.array(z[f"{k}{i}"]) for k in _KEYS))
                for i in range(n)]


def _save_cache(path: str, tag: str, reps: list) -> None:
    """Write pyins' outage reports atomically (pyins is the slow half of the protocol)."""
    from imunav.files import atomic_path

    arrays = {"kind": np.array("outages"), "tag": np.array(tag), "n_shifts": np.array(len(reps))}
    for i, r in enumerate(reps):
        arrays[f"outages{i}"] = np.array(r.outages, dtype=float).reshape(-1, 2)
        arrays.update({f"{k}{i}": np.asarray(getattr(r, k)) for k in _KEYS})
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        np.savez(fh, **arrays)


def outages(sc: Scenario, converge_s: float, cache: str | None = None, tag: str = "") -> dict:
    """The outage protocol (60 s every 180 s, shifts 0 / 60 / 120 s) through both filters on the same data;
    pyins' reports are read from / written to ``cache`` (an ``.npz`` file) when given."""
    from imunav.ins.gins import GinsFilter
    from imunav.ins.gins.outage import OutageReport, outage_drift
    from imunav.sim.gnss import outage_schedule

    cfg = _imunav_config(sc)
    cached = _load_cache(cache, tag)
    reps: dict[str, list] = {"pyins": [], "imunav": []}
    t0, t1 = float(sc.imu.t[0]), float(sc.imu.t[-1])
    for shift in (0.0, 60.0, 120.0):
        sched = outage_schedule(t0 + converge_s, t1, every_s=180.0, length_s=60.0, first_s=shift)
        keep = np.ones(sc.gnss.n, dtype=bool)
        for s, d in sched:
            keep &= ~((sc.gnss.t >= s) & (sc.gnss.t < s + d))
        cut = replace(sc, gnss=sc.gnss.select(keep, "outage protocol"))
        res = GinsFilter(cfg).run(cut.imu, cut.gnss, lla0=sc.lla0, vel0=sc.vel0, q0=sc.q0)
        reps["imunav"].append(outage_drift(res, sc.truth, sched))
        if cached is None:
            reps["pyins"].append(outage_drift(run_pyins(cut, track=True)["track"], sc.truth, sched))
    if cached is not None:
        print(f"pyins' outage reports read from {cache}")
        reps["pyins"] = cached
    elif cache is not None:
        _save_cache(cache, tag, reps["pyins"])
    return {name: OutageReport([o for r in rs for o in r.outages],
                               *(np.concatenate([getattr(r, k) for r in rs]) for k in _KEYS)).rms()
            for name, rs in reps.items()}


def _imunav_config(sc: Scenario, scale_factors: bool = True):
    from imunav.ins.gins import GinsConfig

    return GinsConfig.from_preset(sc.preset, lever_arm=LEVER_ARM, scale_factors=scale_factors,
                                  init_pos_std=INIT_SD["pos"], init_vel_std=INIT_SD["vel"],
                                  init_att_std=np.radians([INIT_SD["level_deg"], INIT_SD["level_deg"],
                                                           INIT_SD["azimuth_deg"]]))


def run_imunav(sc: Scenario, *, scale_factors: bool = True) -> dict:
    """imunav's GNSS/INS filter (:class:`imunav.ins.gins.GinsFilter`, 21 states) on the scenario; the time is that of
    a second call (the first compiles the numba kernels, cached on disk afterwards)."""
    from imunav.ins.gins import GinsFilter

    cfg = _imunav_config(sc, scale_factors)
    GinsFilter(cfg).run(sc.imu, sc.gnss, lla0=sc.lla0, vel0=sc.vel0, q0=sc.q0)
    t0 = time.process_time()
    res = GinsFilter(cfg).run(sc.imu, sc.gnss, lla0=sc.lla0, vel0=sc.vel0, q0=sc.q0)
    wall = time.process_time() - t0
    out = nav_errors(sc.truth, res.t, res.lla, res.vel_ned, res.q_nb)
    out["us_per_sample"] = wall / sc.imu.t.size * 1e6
    return out


def _fmt(r: dict) -> list[str]:
    return [" ".join(f"{v:.3f}" for v in r["pos_rmse_ned_m"]), " ".join(f"{v:.4f}" for v in r["vel_rmse_ned_mps"]),
            " ".join(f"{v:.4f}" for v in r["att_rmse_rpy_deg"]), f"{r['us_per_sample']:.1f}"]


def _compare(ours: dict, peer: dict) -> None:
    """Print both filters' errors and speeds with full GNSS, and the ratios."""
    rows = {"pyins": _fmt(peer), "imunav": _fmt(ours)}
    head = ["pos RMSE N E D (m)", "vel RMSE N E D (m/s)", "att RMSE r p y (deg)", "us/sample"]
    print(f"{'':8s}" + "".join(f"{h:>28s}" for h in head))
    for name, cells in rows.items():
        print(f"{name:8s}" + "".join(f"{c:>28s}" for c in cells))
    print(f"imunav is {peer['us_per_sample'] / ours['us_per_sample']:.0f}x faster per IMU sample (acceptance >= 20)")
    for key, name, unit in (("pos_rmse_ned_m", "position", "m"), ("vel_rmse_ned_mps", "velocity", "m/s"),
                            ("att_rmse_rpy_deg", "attitude", "deg")):
        x, y = np.linalg.norm(ours[key]), np.linalg.norm(peer[key])
        print(f"{name:9s} RMSE (norm of the axes): imunav {x:.4f} {unit}, pyins {y:.4f} {unit}, "
              f"ratio imunav / pyins {x / y:.3f} (acceptance <= 1)")


def _cached_pyins(sc: Scenario, cache: str | None, tag: str) -> dict:
    """pyins' errors on the scenario ``tag``: read from ``cache`` (an ``.npz`` of JSON strings keyed by scenario)
    when there, else run and added to it (written atomically)."""
    from imunav.files import atomic_path

    entries: dict[str, str] = {}
    if cache is not None and os.path.exists(cache):
        with np.load(cache, allow_pickle=False) as z:
            _cache_kind(z, cache, "per-seed errors")
            entries = {k: str(z[k]) for k in z.files if k != "kind"}
    if tag in entries:
        return json.loads(entries[tag])
    out = run_pyins(sc)
    if cache is not None:
        entries[tag] = json.dumps(out)
        with atomic_path(cache) as tmp, open(tmp, "wb") as fh:
            np.savez(fh, kind=np.array("per-seed errors"), **{k: np.array(v) for k, v in entries.items()})
    return out


_AXES = (("pos_rmse_ned_m", ("pos N", "pos E", "pos D"), "m"), ("vel_rmse_ned_mps", ("vel N", "vel E", "vel D"), "m/s"),
         ("att_rmse_rpy_deg", ("roll", "pitch", "yaw"), "deg"))


def _table(r: dict) -> np.ndarray:
    """The 12 figures of one run: per-axis RMSE of position, velocity, attitude, then the norms of the three."""
    return np.array([*(v for key, _, _ in _AXES for v in r[key]), *(np.linalg.norm(r[key]) for key, _, _ in _AXES)])


def seeds(a: argparse.Namespace) -> None:
    """The full-GNSS comparison on ``a.seeds`` paired scenarios: per-seed rows, means, paired ratios ± SE."""
    ours, peer = [], []
    for seed in range(a.seed, a.seed + a.seeds):
        sc = make_scenario(a.duration, a.preset, seed, a.fs)
        tag = scenario_tag(sc, duration=a.duration, preset=a.preset, seed=seed, fs=a.fs)
        r, p = run_imunav(sc), _cached_pyins(sc, a.pyins_cache, tag)
        ours.append(_table(r))
        peer.append(_table(p))
        print(f"seed {seed}: pos N E D (m) imunav {_fmt(r)[0]}  pyins {_fmt(p)[0]};  norms pos vel att imunav "
              + " ".join(f"{v:.4f}" for v in ours[-1][9:]) + "  pyins " + " ".join(f"{v:.4f}" for v in peer[-1][9:]),
              flush=True)
    x, y = np.array(ours), np.array(peer)
    ratio = x / y
    se = ratio.std(axis=0, ddof=1) / np.sqrt(len(ratio)) if len(ratio) > 1 else np.full(ratio.shape[1], np.nan)
    names = [(n, u) for _, ns, u in _AXES for n in ns] + [(f"|{k[:3]}|", u) for k, _, u in _AXES]
    print(f"{a.seeds} seeds ({a.seed}..{a.seed + a.seeds - 1}), {a.duration:g} s drives at {a.fs:g} Hz, {a.preset}: "
          "mean RMSE of each filter and paired ratio imunav / pyins (mean of per-seed ratios +- SE over seeds)")
    print(f"{'':8s}{'imunav':>12s}{'pyins':>12s}{'ratio':>10s}{'SE':>8s}")
    for j, (n, u) in enumerate(names):
        print(f"{n:8s}{x[:, j].mean():>12.4f}{y[:, j].mean():>12.4f}{ratio[:, j].mean():>10.3f}{se[j]:>8.3f}  {u}")


_THREADS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def _single_threaded() -> None:
    """Run again with one BLAS thread unless the environment sets them: pyins' CPU time per sample
    (time.process_time) counts every BLAS thread, and the threads must be set before numpy is loaded."""
    if any(v not in os.environ for v in _THREADS):
        env = {**os.environ, **{v: os.environ.get(v, "1") for v in _THREADS}}
        os.execve(sys.executable, [sys.executable, *sys.argv], env)


def main() -> None:
    _single_threaded()
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=600.0, help="drive length, s")
    ap.add_argument("--preset", default="mems_adis16465", help="IMU preset (imunav.sim.presets)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--fs", type=float, default=100.0, help="IMU rate, Hz")
    ap.add_argument("--outages", action="store_true", help="also the outage protocol through both filters")
    ap.add_argument("--converge", type=float, default=300.0, help="convergence before the first outage, s")
    ap.add_argument("--outages-only", action="store_true",
                    help="with --outages: skip the full-GNSS comparison (saves one pyins run)")
    ap.add_argument("--pyins-cache", metavar="FILE.npz",
                    help="with --outages: read pyins' outage reports from FILE when it was made for the same "
                         "scenario, else write them there (pyins takes most of the time); with --seeds: pyins' "
                         "errors per scenario, read from FILE or added to it")
    ap.add_argument("--seeds", type=int, default=0, metavar="N",
                    help="full-GNSS comparison on N paired seeds (--seed .. --seed + N - 1): per-seed and mean "
                         "RMSE per axis, paired ratio +- SE")
    a = ap.parse_args()
    if a.outages_only and not a.outages:
        ap.error("--outages-only needs --outages")
    if a.seeds < 0 or (a.seeds and a.outages):
        ap.error("--seeds takes N >= 1 and runs the full-GNSS comparison only (not with --outages)")
    if a.seeds:
        seeds(a)
        return
    sc = make_scenario(a.duration, a.preset, a.seed, a.fs)
    print(f"drive {a.duration:.0f} s, {sc.imu.t.size} IMU samples at {a.fs:g} Hz, preset {a.preset}, "
          f"{sc.gnss.n} GNSS fixes (1 Hz, lever arm {LEVER_ARM.tolist()} m), seed {a.seed}")
    if not a.outages_only:
        _compare(run_imunav(sc), run_pyins(sc))
    if a.outages:
        tag = scenario_tag(sc, duration=a.duration, preset=a.preset, seed=a.seed, fs=a.fs, converge=a.converge)
        rms = outages(sc, a.converge, a.pyins_cache, tag)
        print(f"outage protocol (60 s every 180 s after {a.converge:g} s, shifts 0 / 60 / 120 s): "
              f"{rms['imunav']['n_outages']} outages; RMS over outages of the per-outage maximum")
        print(f"{'':14s}" + "".join(f"{k:>14s}" for k in ("horizontal_m", "vertical_m", "3d_m", "roll_deg",
                                                         "pitch_deg", "heading_deg")))
        for name in ("pyins", "imunav"):
            r = rms[name]
            print(f"{name:14s}" + "".join(f"{r[k]:>14.4f}" for k in ("horizontal_m", "vertical_m", "3d_m",
                                                                     "roll_deg", "pitch_deg", "heading_deg")))
        print("drift ratio imunav / pyins (acceptance <= 1): " + ", ".join(
            f"{k} {rms['imunav'][k] / rms['pyins'][k]:.3f}" for k in ("horizontal_m", "vertical_m", "3d_m")))


if __name__ == "__main__":
    main()
