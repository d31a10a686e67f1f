"""Files of a GNSS/INS run, written by the library for the command line and the lab alike.

* :func:`write_simulated_drive`: a simulated drive in KF-GINS's formats (IMU increments, GNSS text, truth ``.nav``,
  KF-GINS YAML) plus the same configuration as an imunav TOML.
* :func:`run_summary`: the one definition of a run's summary (the keys of ``summary.json`` and of the lab step's
  ``gins_summary.json``).
* :func:`run_output_paths` / :func:`write_run_outputs`: KF-GINS's outputs of a filter run (``.nav``, IMU errors,
  state σ, the smoothed ``.nav``), its summary and figures.
* :func:`outage_document`: the outage test's JSON document.
"""

from __future__ import annotations

import contextvars
import dataclasses
import importlib.util
import math
import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from imunav.files import atomic_path, write_json
from imunav.ins.gins.layout import LAY
from imunav.ins.gins.plot import FIGURE_NAMES, write_gins_figures
from imunav.ins.gins.result import AidRecord, GinsResult
from imunav.ins.gins.setup import GinsSetup, SimulatedDrive, track_rmse
from imunav.ins.gins.smoother import Separation, common_epochs, forward_backward_separation
from imunav.io.gnss import GnssData, write_gnss_text
from imunav.io.kfgins import (
    ImuIncrements,
    ImuNoise,
    KfGinsConfig,
    NavTrack,
    write_kfgins_config,
    write_kfgins_imu,
    write_kfgins_imu_errors,
    write_kfgins_nav,
    write_kfgins_std,
)
from imunav.rotation import euler_from_quat, quat_conjugate, quat_multiply
from imunav.toml import toml_text

if TYPE_CHECKING:  # the log and outage runs' types: `gins run --config` writes its outputs without reading a log
    from imunav.ins.gins.logrun import LogOutageReport, LogRun
    from imunav.ins.gins.outage import OutageReport
    from imunav.io.navlog import NavSources

__all__ = ["DRIVE_FILES", "HONESTY_LIMITS", "LOG_FILES", "RUN_FILES", "honesty", "log_outage_document",
           "log_output_paths", "log_summary", "outage_document", "run_output_paths", "run_summary", "self_calibration",
           "track_geojson", "write_log_outputs", "write_run_outputs", "write_simulated_drive"]

#: Files of a simulated drive (key -> name in its folder).
DRIVE_FILES = {"imu": "imu.txt", "gnss": "gnss.txt", "truth": "truth.nav", "yaml": "kf-gins.yaml",
               "toml": "gins.toml"}
#: Files of a filter run (KF-GINS's names for its outputs).
RUN_FILES = {"nav": "KF_GINS_Navresult.nav", "err": "KF_GINS_IMU_ERR.txt", "std": "KF_GINS_STD.txt",
             "summary": "summary.json", "smoothed": "KF_GINS_Navresult_smoothed.nav"}

#: Initial σ written into a simulated drive's configurations: position (m), velocity (m/s), attitude (deg).
_DRIVE_INIT_STD = ((0.5, 0.5, 1.0), (0.05, 0.05, 0.05), (0.1, 0.1, 0.5))


def write_simulated_drive(drive: SimulatedDrive, folder: str | os.PathLike[str]) -> dict[str, Path]:
    """Write a simulated drive in KF-GINS's formats, and its configuration as a KF-GINS YAML and an imunav TOML.

    The YAML holds the preset's noise model in KF-GINS's units, the truth's first sample as the initial state and
    the initial σ of :data:`_DRIVE_INIT_STD`; the TOML the same fields in SI (``GinsConfig`` names).

    Parameters
    ----------
    drive : SimulatedDrive
        From :func:`imunav.ins.gins.setup.simulate_drive`.
    folder : str or os.PathLike
        Output folder (created); the files are named by :data:`DRIVE_FILES`.

    Returns
    -------
    dict of str to pathlib.Path
        The files written.
    """
    out = Path(folder)
    names = {k: out / v for k, v in DRIVE_FILES.items()}
    truth, cfg = drive.truth, drive.setup.config
    fs = drive.fs
    write_kfgins_imu(names["imu"], ImuIncrements.from_imu_data(drive.imu, fs))
    write_gnss_text(names["gnss"], drive.gnss)
    write_kfgins_nav(names["truth"], drive.truth_track())
    pos_std, vel_std, att_std_deg = (np.array(x, dtype=float) for x in _DRIVE_INIT_STD)
    euler = euler_from_quat(truth.q_nb[0])
    zero = np.zeros(3)
    kf = KfGinsConfig(
        source=names["yaml"], imu_path=names["imu"], gnss_path=names["gnss"], output_path=out / "result",
        imu_rate_hz=fs, imu_columns=7, start_time=float(truth.t[0]), end_time=None,
        init_lla=truth.pos_lla[0].copy(), init_vel=truth.vel_ned[0].copy(), init_euler=euler, init_gyro_bias=zero,
        init_accel_bias=zero, init_gyro_scale=zero, init_accel_scale=zero, init_pos_std=pos_std,
        init_vel_std=vel_std, init_att_std=np.radians(att_std_deg), init_gyro_bias_std=cfg.init_gyro_bias_std,
        init_accel_bias_std=cfg.init_accel_bias_std, init_gyro_scale_std=cfg.gyro_scale_std,
        init_accel_scale_std=cfg.accel_scale_std,
        imu_noise_model=ImuNoise(cfg.gyro_noise_density, cfg.accel_noise_density, cfg.gyro_bias_std, cfg.accel_bias_std, cfg.gyro_scale_std,
                       cfg.accel_scale_std, float(cfg.corr_time)),
        antenna_lever_arm=np.asarray(cfg.lever_arm, dtype=float))
    write_kfgins_config(names["yaml"], kf, comment="KF-GINS configuration written by 'imunav gins simulate' (keys "
                                                   "and units of KF-GINS's dataset/kf-gins.yaml)")
    # the same configuration as the YAML, field by field in SI (not the preset, whose mapping may differ)
    noise = {k: np.asarray(getattr(cfg, k)).tolist() for k in ("gyro_noise_density", "accel_noise_density", "gyro_bias_std", "accel_bias_std",
                                                                  "gyro_scale_std", "accel_scale_std",
                                                                  "init_gyro_bias_std", "init_accel_bias_std")}
    doc = {"states": cfg.n_states, **noise, "corr_time": float(cfg.corr_time),
           "lever_arm": np.asarray(cfg.lever_arm).tolist(), "init_pos_std": pos_std.tolist(),
           "init_vel_std": vel_std.tolist(), "init_att_std": np.radians(att_std_deg).tolist(),
           "init": {"lla_deg": np.r_[np.degrees(truth.pos_lla[0, :2]), truth.pos_lla[0, 2]].tolist(),
                    "vel_ned": truth.vel_ned[0].tolist(), "euler_deg": np.degrees(euler).tolist()},
           "imu": {"format": "kf-gins", "rate_hz": fs}}
    with atomic_path(names["toml"]) as tmp:
        tmp.write_text("# imunav GNSS/INS configuration written by 'imunav gins simulate' (SI; "
                       "see imunav.ins.gins.setup)\n" + toml_text(doc), encoding="utf-8")
    return names


def run_summary(res: GinsResult, setup: Any, *, truth: NavTrack | None = None) -> dict[str, Any]:
    """The summary of a filter run: the one definition behind ``imunav gins run``'s ``summary.json`` and the lab
    step's ``gins_summary.json``.

    Parameters
    ----------
    res : GinsResult
        The run.
    setup : GinsSetup
        Its configuration and initial state (only ``setup.config`` is read).
    truth : NavTrack, optional
        A reference: RMSE of the forward (and smoothed) solution against it.

    Returns
    -------
    dict
        ``states``, ``imu_samples``, the GNSS use of :meth:`GinsResult.gnss_summary`, ``gnss_removed`` (fixes left
        out and why), ``aids`` (per aid: updates; ``nis_mean`` over every update, the rejected ones included, and
        ``nis_mean_accepted`` over those the gate accepted, the figure of :func:`honesty`; dof; accepted share; null
        when none) and, with a truth,
        ``rmse`` (and ``rmse_smoothed``) of :func:`~imunav.ins.gins.setup.track_rmse`.
    """
    aids = {}
    for name, rec in res.aids.items():
        ok = np.isfinite(rec.nis)
        aids[name] = {"updates": int(rec.t.size), "nis_mean": float(np.mean(rec.nis[ok])) if ok.any() else None,
                      "nis_mean_accepted": _accepted_nis(rec)[0] if rec.t.size else None,
                      "dof": int(rec.dof[0]) if rec.dof.size else None,
                      "accepted_share": float(np.mean(rec.accepted)) if rec.t.size else None}
    out: dict[str, Any] = {"states": setup.config.n_states, "imu_samples": int(res.t.size), **res.gnss_summary(),
                           "gnss_removed": res.meta.get("removed_gnss", []), "aids": aids}
    if truth is not None:
        out["rmse"] = track_rmse(NavTrack(res.t, res.lla, res.vel_ned, res.q_nb), truth)
        if res.smoothed is not None:
            s = res.smoothed
            out["rmse_smoothed"] = track_rmse(NavTrack(s.t, s.lla, s.vel_ned, s.q_nb), truth)
    return out


def _write_kfgins_files(names: dict[str, Path], res: GinsResult, n_states: int, t_nav: NDArray[np.float64],
                        week: int, q_vb: NDArray[np.float64] | None = None) -> None:
    """KF-GINS's ``.nav`` (and the smoothed one, when ``names`` has ``smoothed``), IMU-error (when ``names`` has
    ``err``) and state-σ files of a run, with the time column ``t_nav`` (one per IMU sample; the σ rows at the
    covariance epochs interpolated on it) and GPS ``week``.
    With ``q_vb`` (the IMU's mounting per sample) the ``.nav`` attitude is the vehicle's, ``q_nb ⊗ q_vbᵀ``.  The
    σ file holds the filter's own 15 or 21 states (a 15-state filter's scale-factor σ written 0)."""
    def attitude(q_nb: NDArray[np.float64]) -> NDArray[np.float64]:
        return q_nb if q_vb is None else quat_multiply(q_nb, quat_conjugate(q_vb))

    write_kfgins_nav(names["nav"], NavTrack(t_nav, res.lla, res.vel_ned, attitude(res.q_nb), week))
    if "err" in names:
        write_kfgins_imu_errors(names["err"], t_nav, res.gyro_bias, res.accel_bias, res.gyro_scale, res.accel_scale)
    sd = np.sqrt(np.pad(res.cov_diag[:, :n_states], ((0, 0), (0, 21 - n_states))))
    t_cov = res.cov_t if t_nav is res.t else np.interp(res.cov_t, res.t, t_nav)
    write_kfgins_std(names["std"], t_cov, sd[:, 0:3], sd[:, 3:6], sd[:, 6:9], sd[:, 9:12], sd[:, 12:15],
                     sd[:, 15:18], sd[:, 18:21])
    if res.smoothed is not None and "smoothed" in names:
        s = res.smoothed
        write_kfgins_nav(names["smoothed"], NavTrack(t_nav, s.lla, s.vel_ned, attitude(s.q_nb), week))


def run_output_paths(folder: str | os.PathLike[str], *, smoother: bool = False, plots: bool = True,
                     truth: bool = False) -> dict[str, Path]:
    """The files :func:`write_run_outputs` writes into ``folder`` (to check them before a run).

    Parameters
    ----------
    folder : str or os.PathLike
        The output folder.
    smoother : bool
        With the smoothed ``.nav``.
    plots : bool
        With the figures (track, IMU errors; errors with a truth).
    truth : bool
        A truth is given (the error figure).

    Returns
    -------
    dict of str to pathlib.Path
        Key (:data:`RUN_FILES` keys, figure names of :data:`~imunav.ins.gins.plot.FIGURE_NAMES`) -> path.
    """
    out = Path(folder)
    keys = ["nav", "err", "std", "summary"] + (["smoothed"] if smoother else [])
    paths = {k: out / RUN_FILES[k] for k in keys}
    if plots:
        paths.update({k: out / FIGURE_NAMES[k] for k in ("track", "imu_errors") + (("errors",) if truth else ())})
    return paths


def write_run_outputs(folder: str | os.PathLike[str], res: GinsResult, setup: GinsSetup, *,
                      gnss: GnssData | None = None, truth: NavTrack | None = None, plots: bool = True,
                      extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """Write KF-GINS's outputs of a run (``.nav``; IMU errors; state σ, the 15-state filter's scale-factor σ
    columns 0; the smoothed ``.nav`` when the run has one), its figures and ``summary.json``.

    Parameters
    ----------
    folder : str or os.PathLike
        Output folder (created); names of :data:`RUN_FILES`.
    res : GinsResult
        The run.
    setup : GinsSetup
        Its configuration and initial state.
    gnss : GnssData, optional
        The fixes, drawn on the track figure.
    truth : NavTrack, optional
        A reference: RMSE in the summary and the error figure.
    plots : bool
        Write the figures (when matplotlib is installed; the summary says which were written).
    extra : dict, optional
        Keys added to the summary first (the command's inputs).

    Returns
    -------
    dict
        The summary written (:func:`run_summary` plus ``extra`` and ``figures``).
    """
    names = run_output_paths(folder, smoother=res.smoothed is not None, plots=False)
    # The text files (tens of MB for a long drive) are written by a second thread while this one draws the
    # figures: their formatter (numba, without the GIL) and the file writes run beside matplotlib.  The thread
    # runs in a copy of this context, so that its files join the command's output transaction.
    with ThreadPoolExecutor(max_workers=1) as pool:
        text = pool.submit(contextvars.copy_context().run, _write_kfgins_files, names, res, setup.config.n_states,
                           res.t, 0)
        summary = {**(extra or {}), **run_summary(res, setup, truth=truth)}
        if plots:
            summary["figures"] = [p.name for p in write_figures(folder, result=res, gnss=gnss, truth=truth)]
        text.result()
    write_json(names["summary"], summary)
    return summary


def write_figures(folder: str | os.PathLike[str], **kw: Any) -> list[Path]:
    """:func:`~imunav.ins.gins.plot.write_gins_figures` when matplotlib is installed, else none (the caller says
    so).

    Parameters
    ----------
    folder : str or os.PathLike
        Output folder.
    **kw
        ``result``, ``gnss``, ``truth``, ``outage`` of :func:`~imunav.ins.gins.plot.write_gins_figures`.

    Returns
    -------
    list of pathlib.Path
        The figures written.
    """
    if importlib.util.find_spec("matplotlib") is None:
        return []
    return write_gins_figures(folder, **kw)


def outage_document(rep: OutageReport, *, source: str, states: int) -> dict[str, Any]:
    """The outage test's JSON document: the protocol, the RMS over outages and every outage's drift.

    Parameters
    ----------
    rep : OutageReport
        From :func:`imunav.ins.gins.outage.outage_test`.
    source : str
        Where the drive came from (a configuration file, or the simulation's parameters).
    states : int
        The filter's navigation and IMU-error states (15 or 21).

    Returns
    -------
    dict
        ``source``, ``protocol``, ``states``, ``rms`` (:meth:`OutageReport.rms`) and ``outages`` (start and length
        s, horizontal / vertical / 3-D drift m, roll / pitch / heading deg, inside the predicted 3σ).
    """
    return {"source": source, "protocol": rep.meta, "states": states, "rms": rep.rms(),
            "outages": [{"start_s": s, "length_s": d, "horizontal_m": h, "vertical_m": v, "drift_3d_m": d3,
                         "roll_deg": r, "pitch_deg": p, "heading_deg": y, "inside_3sigma": bool(c)}
                        for (s, d), h, v, d3, r, p, y, c in zip(rep.outages, rep.horizontal_m, rep.vertical_m,
                                                                rep.drift_3d_m, rep.roll_deg, rep.pitch_deg,
                                                                rep.heading_deg, rep.contained)]}


def log_outage_document(rep: LogOutageReport, *, source: str) -> dict[str, Any]:
    """The JSON document of the outage test on a log: the protocol, the RMS over outages and every outage.

    Parameters
    ----------
    rep : LogOutageReport
        From :func:`imunav.ins.gins.logrun.log_outage_test`.
    source : str
        The log.

    Returns
    -------
    dict
        ``source``, ``protocol``, ``rms`` (:meth:`LogOutageReport.rms`: the reference, its own noise, the end and
        largest horizontal errors, the odometry dead reckoning's and their ratios) and ``outages`` (start and
        length s, end and largest horizontal error m, inside the predicted 3σ, the largest normalised error, the
        dead reckoning's end error m, reference points).
    """
    return {"source": source, "protocol": rep.meta, "rms": rep.rms(),
            "outages": [{"start_s": s0, "length_s": d, "end_m": e, "max_m": m, "inside_3sigma": bool(c),
                         "normalised_max": float(z),
                         "dead_reckoning_end_m": None if not np.isfinite(r) else float(r), "fixes": int(n)}
                        for (s0, d), e, m, c, z, r, n in zip(rep.outages, rep.end_m, rep.max_m, rep.contained,
                                                             rep.normalised, rep.dead_reckoning_end_m, rep.fixes)]}


#: Files of a run on a log besides :data:`RUN_FILES` (whose ``.nav`` and σ file hold the trajectory the run
#: recommends: the smoothed one by default): the track as GeoJSON, and the forward filter's ``.nav`` and σ file.
LOG_FILES = {"geojson": "track.geojson", "forward": "KF_GINS_Navresult_forward.nav",
             "std_forward": "KF_GINS_STD_forward.txt"}


def log_output_paths(folder: str | os.PathLike[str], *, smoother: bool = True, plots: bool = True,
                     truth: bool = False) -> dict[str, Path]:
    """The files :func:`write_log_outputs` writes into ``folder`` (to check them before a run).

    Parameters
    ----------
    folder : str or os.PathLike
        The output folder.
    smoother : bool
        The run has the smoother: the forward filter's ``.nav`` and σ file beside the recommended ones, and the
        separation figure.
    plots : bool
        With the figures.
    truth : bool
        A truth is given (the error figure).

    Returns
    -------
    dict of str to pathlib.Path
        Key (:data:`RUN_FILES`, :data:`LOG_FILES` keys, figure names) -> path.
    """
    out = Path(folder)
    paths = {k: out / RUN_FILES[k] for k in ("nav", "err", "std", "summary")}
    paths["geojson"] = out / LOG_FILES["geojson"]
    if smoother:
        paths.update({k: out / LOG_FILES[k] for k in ("forward", "std_forward")})
    if plots:
        figs = ("track", "imu_errors") + (("errors",) if truth else ()) + (("separation",) if smoother else ())
        paths.update({k: out / FIGURE_NAMES[k] for k in figs})
    return paths


def _recommended(res: GinsResult) -> GinsResult:
    """The run as the smoother recommends it: the smoothed position, velocity and attitude, and their smoothed σ in
    the navigation block of the covariance records (the sensor errors' σ stay the forward filter's)."""
    s = res.smoothed
    assert s is not None
    cd = res.cov_diag.copy()
    j, i = common_epochs(s.cov_t, res.cov_t)
    cd[i, :9] = np.diagonal(s.cov_nav[j], axis1=1, axis2=2)
    cn = res.cov_nav.copy()
    cn[i] = s.cov_nav[j]
    return dataclasses.replace(res, lla=s.lla, vel_ned=s.vel_ned, q_nb=s.q_nb, cov_diag=cd, cov_nav=cn,
                               smoothed=None)


#: The honesty checks of a run on a log (:func:`honesty`): the mean GNSS NIS over its degrees of freedom, the share
#: of fixes rejected, the mean normalised forward–backward separation over its 2 degrees of freedom, beyond which the
#: summary says the trajectory cannot be trusted.
HONESTY_LIMITS = {"gnss_nis_ratio": 2.0, "rejected_share": 0.1, "separation_d2_ratio": 2.0, "aid_nis_ratio": 2.0}

#: How the verdict names an aid of ``GinsResult.aids`` (the GNSS position has its own checks).
_AID_WORDS = {"odometer": "the odometer", "nhc": "the non-holonomic constraint (no side or vertical slip)",
              "zupt": "the zero-velocity updates", "zaru": "the zero-rate updates",
              "vehicle_level": "the vehicle's levelling at rest", "gnss_velocity": "the GNSS velocity",
              "dual_antenna": "the dual-antenna heading", "baro": "the barometer",
              "mag_heading": "the magnetometer's heading"}


def _accepted_nis(rec: AidRecord) -> tuple[float | None, int, float]:
    """An aid's mean NIS over the updates the gate accepted (None when none), its degrees of freedom and the share
    of its updates the gate rejected (:func:`honesty`'s figures of one aid)."""
    ok = rec.accepted & np.isfinite(rec.nis)
    return (float(np.mean(rec.nis[ok])) if ok.any() else None, int(rec.dof[0]), float(np.mean(~rec.accepted)))


def honesty(run: LogRun, separation: Separation | None = None) -> dict[str, Any]:
    """What the log's own statistics say of its trajectory, in words: the one truth-free verdict of a run.

    Checks (:data:`HONESTY_LIMITS`): the GNSS position NIS (mean over the accepted fixes, χ²(3) for a consistent
    filter), the share of fixes the gate rejected, the adaptive noise factor pinned at its upper bound (the fixes
    scatter more than any factor allowed explains), the same two for every other aid (odometer, NHC, ZUPT ...: its
    mean NIS over the accepted updates against its degrees of freedom, and the share the gate rejected; a real
    robot's wheel odometry whose reported σ is far too small, or a skid-steer turn the model does not know, shows
    there before anywhere else), a self-calibration state moved more than
    :data:`~imunav.ins.gins.logrun.MOVED_SIGMAS` prior σ (:meth:`~imunav.ins.gins.logrun.LogRun.moved_beyond_prior`),
    and the forward–backward separation ``d²`` (χ²(2)).

    Parameters
    ----------
    run : LogRun
        The run.
    separation : Separation, optional
        Its forward–backward separation (with the smoother).

    Returns
    -------
    dict
        ``trustworthy`` (bool), ``verdict`` (a sentence), ``reasons`` (one sentence per failed check), ``checks``
        (the figures).
    """
    res = run.result
    reasons: list[str] = []
    checks: dict[str, Any] = {}
    rec = res.aids.get("gnss_position")
    if rec is not None and rec.t.size:
        mean_nis, _, share = _accepted_nis(rec)
        checks.update(gnss_nis_mean=mean_nis, gnss_nis_dof=3, gnss_rejected_share=share)
        if mean_nis is not None and mean_nis > HONESTY_LIMITS["gnss_nis_ratio"] * 3:
            reasons.append(f"the GNSS fixes lie further from the track than its sigma says (mean NIS {mean_nis:.1f} "
                           "for 3 degrees of freedom)")
        if share > HONESTY_LIMITS["rejected_share"]:
            reasons.append(f"the gate rejected {100 * share:.0f} % of the fixes")
        cfg = run.config
        if cfg.gnss_adaptive and res.gnss_noise_scale is not None:
            sc = float(res.gnss_noise_scale[-1])
            lo, hi = cfg.gnss_adaptive_bounds
            checks.update(gnss_sigma_factor=math.sqrt(sc))
            if sc >= hi * (1 - 1e-9):
                reasons.append(f"the fixes scatter more than {math.sqrt(hi):.0f} times their reported sigma")
    for name, rec in res.aids.items():
        if name == "gnss_position" or not rec.t.size:
            continue
        mean_nis, dof, share = _accepted_nis(rec)
        checks.update({f"{name}_nis_mean": mean_nis, f"{name}_nis_dof": dof, f"{name}_rejected_share": share})
        bad = []
        if mean_nis is not None and mean_nis > HONESTY_LIMITS["aid_nis_ratio"] * dof:
            bad.append(f"mean NIS {mean_nis:.1f} for {dof} degree{'s' if dof > 1 else ''} of freedom")
        if share > HONESTY_LIMITS["rejected_share"]:
            bad.append(f"the gate rejected {100 * share:.0f} % of its updates")
        if bad:
            reasons.append(f"{_AID_WORDS.get(name, name)} disagrees with the IMU more than its sigma allows "
                           f"({'; '.join(bad)}): its sigma is too small, or the vehicle does what the model does not "
                           "(wheel slip, a skid-steer turn)")
    moved = run.moved_beyond_prior()
    if moved:
        checks["moved_beyond_prior"] = moved
        reasons.append("the drive pulled " + ", ".join(f"{k} {v['change']:.3g} ({v['sigmas']:.1f} prior sigma)"
                                                        for k, v in moved.items())
                       + " from where it began: more than the prior allows without a model error")
    if separation is not None:
        d2 = separation.summary()["mean_d2"]
        checks.update(separation_mean_d2=d2, separation_dof=2)
        if d2 is not None and d2 > HONESTY_LIMITS["separation_d2_ratio"] * 2:
            reasons.append(f"the forward filter and the smoother part by more than their sigma allows (mean d2 "
                           f"{d2:.1f} for 2 degrees of freedom): the forward filter was overconfident")
    verdict = ("the log's own statistics agree with the sigma the run reports (GNSS NIS, rejected fixes, "
               "every aid's NIS, forward-backward separation)" if not reasons else
               "the trajectory and its sigma cannot be trusted: " + "; ".join(reasons))
    return {"trustworthy": not reasons, "verdict": verdict, "reasons": reasons, "checks": checks}


def self_calibration(run: LogRun) -> dict[str, Any]:
    """Which self-calibration states the drive observed: each one's prior σ, final σ and their ratio, and
    ``observable`` when the drive halved its σ (``"weak"`` when it took off at least a tenth, ``false`` when the
    prior stands: the value is then the prior's, not a measurement).

    Parameters
    ----------
    run : LogRun
        The run.

    Returns
    -------
    dict
        Per state (``mount_roll``, ``mount_pitch``, ``mount_yaw``, ``odometer_scale``, ``odometer_turn_overread``,
        ``gnss_latency``, ``odo_lever_x`` ...): ``prior_std``, ``std``, ``ratio``, ``observable``; SI units (rad, s,
        m).
    """
    lay = run.state_layout()
    res = run.result
    out: dict[str, Any] = {}
    names = {"mount": ("mount_roll", "mount_pitch", "mount_yaw"), "odo_scale": ("odometer_scale",),
             "odo_turn": ("odometer_turn_overread",), "side_slip": ("side_slip",), "gnss_delay": ("gnss_latency",),
             "odo_lever": ("odo_lever_x", "odo_lever_y", "odo_lever_z"),
             "gnss_bias": ("gnss_bias_n", "gnss_bias_e", "gnss_bias_d")}
    for block, labels in names.items():
        i = int(lay[getattr(LAY, block)])
        if i < 0:
            continue
        for j, label in enumerate(labels):
            p0 = float(np.sqrt(res.cov_diag[0, i + j]))
            p1 = float(np.sqrt(res.cov_diag[-1, i + j]))
            ratio = p1 / p0 if p0 > 0 else None
            obs: bool | str = bool(ratio is not None and ratio < 0.5) or ("weak" if ratio is not None and ratio < 0.9
                                                                           else False)
            out[label] = {"prior_std": p0, "std": p1, "ratio": ratio, "observable": obs}
    return out


def log_summary(run: LogRun, sources: NavSources, separation: Separation | None = None) -> dict[str, Any]:
    """What a run on a log found: the one definition of its ``summary.json`` keys beyond :func:`run_summary`.

    Parameters
    ----------
    run : LogRun
        From :func:`imunav.ins.gins.logrun.run_log`.
    sources : NavSources
        The log's sources.
    separation : Separation, optional
        The forward–backward separation of a run with the smoother.

    Returns
    -------
    dict
        ``trajectory`` (which track the ``.nav`` holds), ``honesty`` (:func:`honesty`), ``self_calibration``
        (:func:`self_calibration`), ``gnss_noise`` (the adaptive factor on the fixes' reported σ), ``wheel_noise``
        (the odometer's and the NHC's factors on their σ, null without wheels), ``separation``
        (:meth:`~imunav.ins.gins.smoother.Separation.summary`, null without the smoother); ``t0_unix`` (UTC of the first row, s since 1970; null when the log's clock is not UTC) and ``time_note``;
        ``sources`` (per role: topic, type, count, rate, what the reader refused); ``static_share``; ``mounting``
        (roll, pitch, yaw of the IMU in the vehicle, deg, with σ; its source: given, tf_static, estimated or
        identity; the coarse estimate before the filter); ``odometer_scale`` (reading / true speed − 1, with σ);
        ``odometer_turn_overread`` (the over-reading per rad/s of yaw rate, s/rad, with σ); ``side_slip`` (the
        vehicle's slip angle per m/s² of lateral acceleration, rad/(m/s²), with σ; null without it); in each of these,
        ``estimated`` is false when the configuration has no such state or holds it at its prior (a Schmidt consider
        state: the odometer's without GNSS);
        ``gnss_time_offset_s`` (the receiver's latency, with σ); ``gnss_rejected`` (share of the fixes the
        reader refused or the χ² gate rejected, and why); ``initial`` (how the initial state was found);
        ``duration_s`` (the IMU's span, s) and ``final_position_std_m`` (σ north, east, down of the last
        position, m).
    """
    res = run.result
    lay = run.state_layout()
    sd = np.sqrt(res.cov_diag[-1])

    def state(block: str, value: float) -> dict[str, Any]:
        i = int(lay[getattr(LAY, block)])
        return {"value": float(value), "std": float(sd[i]) if i >= 0 else None,
                "estimated": i >= 0 and block not in run.config.consider_states}

    e, esd = run.mounting_euler()
    mount = {"roll_deg": float(np.degrees(e[0])), "pitch_deg": float(np.degrees(e[1])),
             "yaw_deg": float(np.degrees(e[2])), "std_deg": np.degrees(esd).tolist(), "source": run.mounting_source,
             "q_vb": res.q_vb[-1].tolist() if res.q_vb is not None else None}
    if run.mounting_coarse is not None:
        mount["coarse_deg"] = np.degrees(run.mounting_coarse.euler).tolist()
        mount["coarse_std_deg"] = np.degrees(run.mounting_coarse.std).tolist()
        mount["method"] = run.mounting_coarse.meta.get("method")
    g_meta = sources.meta.get("gnss", {}) if isinstance(sources.meta.get("gnss"), dict) else {}
    rec = res.aids.get("gnss_position")
    n_gate = int(np.sum(~rec.accepted)) if rec is not None else 0
    n_used = int(rec.t.size) if rec is not None else 0
    refused = list(g_meta.get("removed", []))  # [{"reason": ..., "epochs": n}, ...] of the reader
    n_refused = int(sum(int(r.get("epochs", 0)) for r in refused))
    total = n_used + n_refused
    return {
        "t0_unix": sources.t0_unix if sources.time_is_utc else None,
        "time_note": ("the .nav time columns are GPS week and seconds of week" if sources.time_is_utc else
                      "the log's stamps are not UTC (a clock that starts at boot): the .nav week column is 0 and its "
                      "seconds column the log's own time"),
        "sources": sources.to_dict(),
        "static_share": float(np.mean(run.static)),
        "mounting": mount,
        "odometer_scale": state("odo_scale", res.odo_scale[-1]) if sources.odometer is not None else None,
        "odometer_turn_overread": (state("odo_turn", res.odo_turn[-1] if res.odo_turn is not None else 0.0)
                                   if sources.odometer is not None else None),
        "side_slip": (state("side_slip", res.side_slip[-1])
                      if res.side_slip is not None and int(lay[LAY.side_slip]) >= 0 else None),
        "gnss_time_offset_s": state("gnss_delay", res.gnss_delay[-1]) if sources.gnss is not None else None,
        "gnss_rejected": {"share": (n_gate + n_refused) / total if total else None, "by_gate": n_gate,
                          "by_reader": refused, "fixes": total},
        "initial": run.initial,
        "duration_s": float(sources.imu.t[-1] - sources.imu.t[0]),
        "final_position_std_m": sd[int(lay[LAY.pos]):int(lay[LAY.pos]) + 3].tolist(),
        "trajectory": ("RTS-smoothed (forward filter and backward pass over the whole log): the .nav and the sigma "
                       "file; the forward filter's in *_forward" if res.smoothed is not None else
                       "forward filter (real time)"),
        "honesty": honesty(run, separation),
        "self_calibration": self_calibration(run),
        "gnss_noise": _gnss_noise(run) if sources.gnss is not None else None,
        "wheel_noise": _wheel_noise(run),
        "separation": separation.summary() if separation is not None else None,
    }


def _noise_factor(scale: NDArray[np.float64], bounds: tuple[float, float], method: str) -> dict[str, Any]:
    """An adaptive factor on an aid's covariance (its series over the run), as a factor on its σ: at the end, its
    largest, its bounds and whether it ended at one."""
    sc = float(scale[-1])
    lo, hi = bounds
    return {"adaptive": True, "sigma_factor": math.sqrt(sc), "sigma_factor_max": math.sqrt(float(np.max(scale))),
            "sigma_factor_bounds": [math.sqrt(lo), math.sqrt(hi)],
            "at_bound": bool(sc <= lo * (1 + 1e-9) or sc >= hi * (1 - 1e-9)), "method": method}


def _gnss_noise(run: LogRun) -> dict[str, Any]:
    """The adaptive factor on the fixes' reported covariance at the end of the run, as a factor on their σ."""
    res, cfg = run.result, run.config
    if not cfg.gnss_adaptive or res.gnss_noise_scale is None:
        return {"adaptive": False}
    return _noise_factor(res.gnss_noise_scale, cfg.gnss_adaptive_bounds, "covariance matching of the position "
                         "innovations (imunav.ins.gins.kernels._adapt_noise)")


def _wheel_noise(run: LogRun) -> dict[str, Any] | None:
    """The adaptive factors on the odometer's and the NHC's σ (None without wheels)."""
    res, cfg = run.result, run.config
    used = {name: getattr(res, f"{key}_noise_scale") for name, key in (("odometer", "odo"), ("nhc", "nhc"))
            if res.aids.get(name) is not None and res.aids[name].t.size}
    if not used:
        return None
    if not cfg.wheel_adaptive:
        return {name: {"adaptive": False} for name in used}
    return {name: _noise_factor(sc, cfg.wheel_adaptive_bounds, f"covariance matching of the {name}'s innovations "
                                "(imunav.ins.gins.kernels._adapt_noise)") for name, sc in used.items()}


def track_geojson(res: GinsResult, gnss: GnssData | None, *, every_s: float = 1.0) -> dict[str, Any]:
    """The trajectory (one point every ``every_s`` s) as a GeoJSON LineString and the fixes as Points (with
    ``accepted`` by the χ² gate), in WGS84 longitude / latitude degrees and ellipsoidal height (RFC 7946).

    Parameters
    ----------
    res : GinsResult
        The run.
    gnss : GnssData or None
        The fixes it used.
    every_s : float
        Spacing of the track's points, s.

    Returns
    -------
    dict
        A FeatureCollection.
    """
    t = res.t
    keep = np.unique(np.r_[np.searchsorted(t, np.arange(t[0], t[-1], every_s)), t.size - 1])
    coords = [[float(np.degrees(res.lla[i, 1])), float(np.degrees(res.lla[i, 0])), float(res.lla[i, 2])]
              for i in keep]
    feats: list[dict[str, Any]] = [{"type": "Feature", "geometry": {"type": "LineString", "coordinates": coords},
                                    "properties": {"name": "GNSS/INS track", "t0_s": float(t[0]),
                                                   "t1_s": float(t[-1])}}]
    rec = res.aids.get("gnss_position")
    if gnss is not None and rec is not None:
        acc = dict(zip(np.round(rec.t, 9).tolist(), rec.accepted.tolist()))
        for i in range(gnss.n):
            feats.append({"type": "Feature",
                          "geometry": {"type": "Point", "coordinates": [float(np.degrees(gnss.lla[i, 1])),
                                                                        float(np.degrees(gnss.lla[i, 0])),
                                                                        float(gnss.lla[i, 2])]},
                          "properties": {"t_s": float(gnss.t[i]),
                                         "accepted": acc.get(round(float(gnss.t[i]), 9))}})
    return {"type": "FeatureCollection", "features": feats}


def write_log_outputs(folder: str | os.PathLike[str], run: LogRun, sources: NavSources, *,
                      plots: bool = True, truth: NavTrack | None = None) -> dict[str, Any]:
    """Write a run on a log: KF-GINS's ``.nav`` and σ file of the trajectory the run recommends (the smoothed one
    when the run has the smoother, :func:`log_output_paths`; the vehicle's attitude, GPS week and seconds of week
    from the log's UTC stamps), the forward filter's beside them, the IMU errors, ``track.geojson``, the figures
    (the separation of the forward filter and the smoother among them) and ``summary.json`` (:func:`run_summary`
    and :func:`log_summary`).

    Parameters
    ----------
    folder : str or os.PathLike
        Output folder (created).
    run : LogRun
        From :func:`imunav.ins.gins.logrun.run_log`.
    sources : NavSources
        The log's sources.
    plots : bool
        Write the figures.
    truth : NavTrack, optional
        A reference on the sources' time axis (:func:`imunav.ins.gins.logrun.truth_on_sources`): RMSE of the
        recommended and the forward tracks in the summary, and the error figure.

    Returns
    -------
    dict
        The summary written.
    """
    out = Path(folder)
    res = run.result
    gt = sources.gps_time(res.t)
    week = int(gt.week[0]) if gt.week.size else 0
    sow = np.asarray(gt.sow, dtype=float) + (np.asarray(gt.week, dtype=float) - week) * 604800.0
    sep = forward_backward_separation(res) if res.smoothed is not None else None
    names = log_output_paths(out, smoother=sep is not None, plots=False)
    forward = dataclasses.replace(res, smoothed=None)
    best = _recommended(res) if sep is not None else forward
    _write_kfgins_files({k: names[k] for k in ("nav", "err", "std")}, best, run.config.n_states, sow, week,
                        q_vb=res.q_vb)
    if sep is not None:
        _write_kfgins_files({"nav": names["forward"], "std": names["std_forward"]}, forward, run.config.n_states,
                            sow, week, q_vb=res.q_vb)
    write_json(names["geojson"], track_geojson(best, sources.gnss))
    summary = {"log": sources.source, **run_summary(best, _LogSetup(run.config), truth=truth),
               **log_summary(run, sources, sep),
               "frames": "position of the IMU, attitude of the vehicle (IMU attitude composed with its mounting)"}
    if truth is not None and sep is not None:
        summary["rmse_forward"] = track_rmse(NavTrack(res.t, res.lla, res.vel_ned, res.q_nb), truth)
    if plots:
        summary["figures"] = [p.name for p in write_figures(out, result=best, gnss=sources.gnss, truth=truth,
                                                            separation=sep)]
    write_json(names["summary"], summary)
    return summary


@dataclass(frozen=True)
class _LogSetup:
    """The part of a :class:`GinsSetup` that :func:`run_summary` reads."""

    config: Any
