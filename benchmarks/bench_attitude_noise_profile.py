"""BROAD: the adaptive MEKF tuned from the sensor's own noise profile, beside its shipped defaults (issue 34).

Each shared BROAD trial starts with the IMU at rest (26-45 s, before the first sample of the trial's ``movement``
mask).  The noise profile (:class:`imunav.noise.NoiseProfile`: white noise N, bias instability B and random walk K
per axis, from the Allan GLS fit, as ``imunav noise REC --end T --profile OUT.toml`` writes it) is identified on
that rest up to ``--settle`` s before the first movement; the filter then runs from there to the end of the trial,
the last ``--settle`` s of rest letting it align and measure its gyro bias.  Two configurations run on the same
samples:

* ``defaults``: :data:`imunav.attitude.adaptive.ADAPTIVE_DEFAULTS` (the shipped, grid-chosen values; their grid
  was scored on these very trials, so they are in-sample here);
* ``profile``: ``MekfConfig.from_noise_profile(profile, base=ADAPTIVE_DEFAULTS, fs=trial rate)``: the gyro noise
  density, bias random walk and zero-rate pseudo-measurement noise are the sensor's, the correction time
  constants and the gates stay;
* ``bias only``: the defaults with only the profile's bias terms (``gyro_bias_random_walk``, ``zaru_noise_std``),
  the gyro noise density kept at the default's, which stands for more than the sensor's white noise.

Printed per trial and overall, 9D and 6D: the BROAD total RMSE (9D) / inclination RMSE (6D) over the movement
samples, and the attitude NEES against the optical reference: ``e = log(q̂* ⊗ q_ref)`` (the body-frame error of the
MEKF's error state) over the attitude block of the covariance diagonal (:func:`imunav.filters.nees`), mean over the scored samples (χ²(3): 3 for
an honest σ; 6D: the two horizontal components, χ²(2): 2), and the share of samples under the χ² 95 % quantile
(0.95 for an honest σ).  The 9D error holds the optical frame's heading offset from magnetic north, which no
filter models; the 6D NEES is free of it.

Run:  python benchmarks/bench_attitude_noise_profile.py [DIR] [--settle 5] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import replace

import numpy as np

from imunav import filters
from imunav.attitude.adaptive import ADAPTIVE_DEFAULTS, AdaptiveMEKF
from imunav.attitude.mekf import MekfConfig
from imunav.attitude.metrics import attitude_rmse
from imunav.io.broad import broad_trials, load_broad
from imunav.io.datasets import shared_data_path
from imunav.noise import NoiseProfile, allan_deviation, fit_noise
from imunav.rotation import dcm_from_quat, quat_conjugate, quat_multiply, quat_rotate, rotvec_from_quat

CHI2_95 = {2: 5.991464547107979, 3: 7.814727903251178}


def rest_profile(tr, t_end: float) -> NoiseProfile:
    """The noise profile of the trial's first ``t_end`` seconds (at rest), as ``imunav noise --profile`` makes it."""
    n = int(np.searchsorted(tr.imu.t, t_end))
    fits = {}
    for s, arr, unit in (("gyro", tr.imu.gyro[:n], "rad/s"), ("accel", tr.imu.accel[:n], "m/s^2")):
        r = allan_deviation(arr, tr.fs, "octave", "overlapping", units=unit, channels=("x", "y", "z"))
        fits[s] = fit_noise(r, terms=("N", "B", "K", "R"), quantity=s)
    return NoiseProfile.from_fits(fs=tr.fs, duration_s=float(tr.imu.t[n - 1] - tr.imu.t[0]),
                                  source=f"{tr.name} [0:{t_end:.3g} s]", **fits)


def score(tr, i0: int, cfg: MekfConfig, use_mag: bool) -> dict:
    """BROAD RMSE and attitude NEES of the adaptive MEKF with ``cfg`` run from sample ``i0``."""
    data = tr.imu.slice(i0, tr.imu.n)
    ref, mask = tr.q_ref_nb[i0:], tr.movement[i0:]
    t0 = time.process_time()
    res = AdaptiveMEKF(cfg).run(data, use_mag=use_mag)
    cpu = time.process_time() - t0
    r = attitude_rmse(res.q_nb, ref, mask)
    ok = mask & np.all(np.isfinite(ref), axis=1)
    e = rotvec_from_quat(quat_multiply(quat_conjugate(res.q_nb[ok]), ref[ok]))  # body-frame error, q_ref = q̂ ⊗ δq
    var = res.cov_diag[ok, :3]
    if use_mag:
        nees, dof = filters.nees(e, np.einsum("ni,ij->nij", var, np.eye(3))), 3
    else:  # inclination: the error about the two horizontal nav axes (body error rotated to NED)
        en = quat_rotate(res.q_nb[ok], e)
        # the body-frame covariance (its diagonal) rotated alike; its horizontal block
        C = dcm_from_quat(res.q_nb[ok])
        Pn = np.einsum("nij,nj,nkj->nik", C, var, C)[:, :2, :2]
        nees, dof = filters.nees(en[:, :2], Pn), 2
    return {"rmse_deg": r.total_rmse_deg if use_mag else r.inclination_rmse_deg,
            "nees_mean": float(np.mean(nees)), "nees_dof": dof,
            "in_95": float(np.mean(nees < CHI2_95[dof])), "cpu_s": cpu}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dir", nargs="?", default=None, help="BROAD trials (default: the shared data)")
    ap.add_argument("--settle", type=float, default=5.0, help="s of rest left to the filter before the movement")
    ap.add_argument("--json", default=None)
    a = ap.parse_args()
    d = a.dir or shared_data_path("broad")
    if d is None:
        print("BROAD trials not found (set IMUNAV_DATA); skipped")
        sys.exit(0)
    rows, out = [], {}
    cpu0 = time.process_time()
    for path in broad_trials(d):
        tr = load_broad(path)
        i_move = int(np.argmax(tr.movement))
        t_end = float(tr.imu.t[i_move]) - a.settle
        prof = rest_profile(tr, t_end)
        i0 = int(np.searchsorted(tr.imu.t, t_end))
        cfg_p = MekfConfig.from_noise_profile(prof, base=ADAPTIVE_DEFAULTS, fs=tr.fs)
        g = prof.gyro
        rec = {"rest_s": float(tr.imu.t[i_move]), "profile_s": t_end,
               "gyro_noise_density": g.noise_density.value.tolist(),
               "gyro_bias_random_walk": g.bias_random_walk.value.tolist(),
               "gyro_bias_random_walk_identified": g.bias_random_walk.identified.tolist(),
               "config": {k: getattr(cfg_p, k) for k in ("gyro_noise_density", "gyro_bias_random_walk",
                                                          "zaru_noise_std", "accel_direction_noise_std")}}
        cfg_b = replace(ADAPTIVE_DEFAULTS, gyro_bias_random_walk=cfg_p.gyro_bias_random_walk,
                        zaru_noise_std=cfg_p.zaru_noise_std)
        for dim, um in (("9D", True), ("6D", False)):
            rec[dim] = {"defaults": score(tr, i0, ADAPTIVE_DEFAULTS, um), "profile": score(tr, i0, cfg_p, um),
                        "bias only": score(tr, i0, cfg_b, um)}
        out[tr.name] = rec
        rows.append((tr.name, rec))
        print(f"{tr.name[:40]:40s} rest {rec['rest_s']:5.1f} s  N_g {np.max(g.noise_density.value):.3g} rad/s/√Hz "
              f"(defaults {ADAPTIVE_DEFAULTS.gyro_noise_density:g})  K_g {np.max(g.bias_random_walk.value):.3g}"
              f"{'' if g.bias_random_walk.identified.all() else ' (bound)'}", flush=True)
        for dim in ("9D", "6D"):
            dd, pp, bb = rec[dim]["defaults"], rec[dim]["profile"], rec[dim]["bias only"]
            print(f"    {dim}: error {dd['rmse_deg']:.3f} -> {pp['rmse_deg']:.3f} (bias only {bb['rmse_deg']:.3f}) deg"
                  f"   NEES/dof {dd['nees_mean'] / dd['nees_dof']:.3g} -> {pp['nees_mean'] / pp['nees_dof']:.3g} "
                  f"({bb['nees_mean'] / bb['nees_dof']:.3g})   in 95 % {dd['in_95']:.2f} -> {pp['in_95']:.2f} "
                  f"({bb['in_95']:.2f})", flush=True)
    print()
    print("| | configuration | error (deg) | ratio to defaults | NEES / dof | in χ² 95 % |")
    print("|---|---|---|---|---|---|")
    summary = {}
    for dim in ("9D", "6D"):
        m = {k: {q: float(np.mean([r[dim][k][q] / (r[dim][k]["nees_dof"] if q == "nees_mean" else 1)
                                   for _, r in rows])) for q in ("rmse_deg", "nees_mean", "in_95")}
             for k in ("defaults", "profile", "bias only")}
        summary[dim] = m
        for k, v in m.items():
            print(f"| mean {dim} ({len(rows)} trials) | {k} | {v['rmse_deg']:.3f} | "
                  f"{v['rmse_deg'] / m['defaults']['rmse_deg']:.3f} | {v['nees_mean']:.3g} | {v['in_95']:.2f} |")
    print(f"\nCPU time {time.process_time() - cpu0:.1f} s (profiles, 60 filter runs; shared loaded machine)")
    if a.json:
        with open(a.json, "w", encoding="utf-8") as fh:
            json.dump({"trials": out, "summary": summary, "settle_s": a.settle}, fh, indent=1)


if __name__ == "__main__":
    main()
