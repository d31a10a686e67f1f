"""``imunav gins``: loosely coupled GNSS/INS on KF-GINS files and configurations."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import numpy as np
import typer

from imunav import earth
from imunav.errors import ConfigError, InvalidInputError
from imunav.ins.gins import GinsConfig, GinsFilter
from imunav.io._atomic import atomic_path, check_outputs, write_json
from imunav.io.gnss import read_gnss_text, write_gnss_text
from imunav.io.kfgins import (
    ImuIncrements,
    NavTrack,
    load_kfgins_config,
    read_kfgins_imu,
    read_kfgins_nav,
    write_kfgins_imu,
    write_kfgins_imu_errors,
    write_kfgins_nav,
    write_kfgins_std,
)
from imunav.rotation import euler_from_quat, quat_from_euler
from imunav.sim import presets, simulate_imu
from imunav.sim.gnss import simulate_gnss
from imunav.sim.vehicle import demo_drive, vehicle_trajectory
from imunav.units import DEG, HOUR

gins_app = typer.Typer(
    help=("Loosely coupled GNSS/INS (error-state Kalman filter) on KF-GINS files.\n\n"
          "Example: imunav gins simulate --out drive && imunav gins run --config drive/kf-gins.yaml "
          "--truth drive/truth.nav"),
    no_args_is_help=True,
)

NAV_NAME, ERR_NAME, STD_NAME, SUMMARY_NAME = "KF_GINS_Navresult.nav", "KF_GINS_IMU_ERR.txt", "KF_GINS_STD.txt", \
    "summary.json"


def register(app: typer.Typer) -> None:
    app.add_typer(gins_app, name="gins")


def _v(x: np.ndarray, fmt: str = "{:.10g}") -> str:
    return "[ " + ", ".join(fmt.format(float(a)) for a in x) + " ]"


@gins_app.command("simulate")
def simulate_cmd(
    out: Path = typer.Option(..., "--out", help="Folder for imu.txt, gnss.txt, truth.nav and kf-gins.yaml."),
    duration: float = typer.Option(600.0, help="Drive length, s (>= 120)."),
    preset: str = typer.Option("mems_adis16465", help="IMU error preset (imunav.sim.presets)."),
    fs: float = typer.Option(200.0, help="IMU rate, Hz."),
    seed: int = typer.Option(1, help="Random seed."),
    sow0: float = typer.Option(456300.0, "--start-sow", help="GPS second of week of the first sample."),
) -> None:
    """Simulate a land-vehicle drive in KF-GINS's formats: IMU increments, 1 Hz GNSS, the truth and a KF-GINS YAML.

    Example: imunav gins simulate --out drive --duration 600 --preset mems_adis16465
    """
    names = {k: out / v for k, v in (("imu", "imu.txt"), ("gnss", "gnss.txt"), ("truth", "truth.nav"),
                                     ("yaml", "kf-gins.yaml"))}
    check_outputs([], names.values())
    lever = np.array([0.136, -0.301, -0.184])
    truth = vehicle_trajectory(demo_drive(duration), fs=fs, origin_lla=(30.4447873701 * DEG, 114.4718632047 * DEG,
                                                                        20.899), t0=sow0)
    model = presets.get(preset)
    imu = simulate_imu(truth, model, rng=seed)
    gnss = simulate_gnss(truth, pos_noise=(0.5, 0.5, 1.0), vel_noise=None, lever_arm=lever, rng=seed + 1)
    write_kfgins_imu(names["imu"], ImuIncrements.from_imu_data(imu, fs))
    write_gnss_text(names["gnss"], gnss)
    write_kfgins_nav(names["truth"], NavTrack(truth.t, truth.pos_lla, truth.vel_ned, truth.q_nb))
    cfg = GinsConfig.from_preset(preset)
    eul = np.degrees(euler_from_quat(truth.q_nb[0]))
    text = "\n".join([
        "# KF-GINS configuration written by 'imunav gins simulate' (keys and units of KF-GINS's dataset/kf-gins.yaml)",
        'imupath: "imu.txt"', 'gnsspath: "gnss.txt"', 'outputpath: "result"', "imudatalen: 7",
        f"imudatarate: {fs:g}", f"starttime: {sow0:.3f}", "endtime: -1",
        f"initpos: {_v(np.r_[np.degrees(truth.pos_lla[0, :2]), truth.pos_lla[0, 2]], '{:.10f}')}",
        f"initvel: {_v(truth.vel_ned[0])}", f"initatt: {_v(eul, '{:.8f}')}",
        "initgyrbias: [ 0, 0, 0 ]", "initaccbias: [ 0, 0, 0 ]", "initgyrscale: [ 0, 0, 0 ]", "initaccscale: [ 0, 0, 0 ]",
        "initposstd: [ 0.5, 0.5, 1.0 ]", "initvelstd: [ 0.05, 0.05, 0.05 ]", "initattstd: [ 0.1, 0.1, 0.5 ]",
        f"initbgstd: {_v(cfg.init_gyro_bias_std / (DEG / HOUR))}", f"initbastd: {_v(cfg.init_accel_bias_std / 1e-5)}",
        "imunoise:",
        f"  arw: {_v(cfg.arw / (DEG / 60))}", f"  vrw: {_v(cfg.vrw * 60)}",
        f"  gbstd: {_v(cfg.gyro_bias_std / (DEG / HOUR))}", f"  abstd: {_v(cfg.accel_bias_std / 1e-5)}",
        f"  gsstd: {_v(cfg.gyro_scale_std / 1e-6)}", f"  asstd: {_v(cfg.accel_scale_std / 1e-6)}",
        f"  corrtime: {cfg.corr_time / HOUR:.6g}",
        f"antlever: {_v(lever)}", ""])
    with atomic_path(names["yaml"]) as tmp:
        tmp.write_text(text, encoding="utf-8")
    typer.echo(f"{truth.n} IMU samples ({duration:g} s at {fs:g} Hz, preset {preset}), {gnss.n} GNSS fixes -> {out}")


def _rmse(nav: NavTrack, truth: NavTrack) -> dict[str, list[float]]:
    """RMSE of position (N E D m), velocity (m/s) and roll / pitch / yaw (deg) at the truth's common stamps."""
    t_common, ia, ib = np.intersect1d(np.round(nav.t, 6), np.round(truth.t, 6), return_indices=True)
    if t_common.size == 0:
        raise InvalidInputError("the truth file shares no time stamp with the IMU; it must be sampled on the IMU stamps")
    a, b = nav.lla[ia], truth.lla[ib]
    rn, re = earth.radii(b[:, 0])
    d = np.column_stack([(a[:, 0] - b[:, 0]) * (rn + b[:, 2]), (a[:, 1] - b[:, 1]) * (re + b[:, 2]) * np.cos(b[:, 0]),
                         -(a[:, 2] - b[:, 2])])
    de = np.degrees(nav.euler()[ia] - truth.euler()[ib])
    de = (de + 180.0) % 360.0 - 180.0

    def r(x: np.ndarray) -> list[float]:
        return np.sqrt(np.mean(x**2, axis=0)).tolist()

    return {"pos_ned_m": r(d), "vel_ned_mps": r(nav.vel_ned[ia] - truth.vel_ned[ib]), "att_rpy_deg": r(de),
            "n": int(t_common.size)}


@gins_app.command("run")
def run_cmd(
    config: Path = typer.Option(..., "--config", help="KF-GINS YAML configuration (its keys and units)."),
    out: Optional[Path] = typer.Option(None, "--out", help="Output folder (default: the YAML's outputpath)."),
    truth: Optional[Path] = typer.Option(None, "--truth", help="Truth .nav file: adds the RMSE to summary.json."),
    smoother: bool = typer.Option(False, "--smoother", help="Also write the RTS-smoothed solution (*_smoothed.nav)."),
    states: int = typer.Option(21, help="15 (no scale factors) or 21."),
) -> None:
    """Run the GNSS/INS filter on a KF-GINS configuration; write KF-GINS's outputs (.nav, IMU errors, state
    sigma) and summary.json.

    Example: imunav gins run --config drive/kf-gins.yaml --out drive/result --truth drive/truth.nav
    """
    if states not in (15, 21):
        raise ConfigError(f"--states must be 15 or 21; got {states}")
    cfg = load_kfgins_config(config)
    folder = out if out is not None else cfg.output_path
    outs = {k: folder / v for k, v in (("nav", NAV_NAME), ("err", ERR_NAME), ("std", STD_NAME),
                                       ("summary", SUMMARY_NAME))}
    if smoother:
        outs["smoothed"] = folder / NAV_NAME.replace(".nav", "_smoothed.nav")
    check_outputs([config, cfg.imu_path, cfg.gnss_path, truth], outs.values())
    inc = read_kfgins_imu(cfg.imu_path, cfg.imu_rate_hz)
    end = cfg.end_time if cfg.end_time is not None else float(inc.t[-1])
    keep = (inc.t >= cfg.start_time) & (inc.t <= end)
    if keep.sum() < 2:
        raise ConfigError(f"{config}: no IMU samples between starttime {cfg.start_time} and endtime {end} "
                          f"(the IMU file spans {inc.t[0]:.3f}..{inc.t[-1]:.3f} s)")
    inc = ImuIncrements(inc.t[keep], inc.dtheta[keep], inc.dvel[keep], inc.dt[keep], inc.meta)
    gnss = read_gnss_text(cfg.gnss_path)
    gcfg = GinsConfig.from_kfgins(cfg, scale_factors=states == 21)
    err0 = np.concatenate([cfg.init_gyro_bias, cfg.init_accel_bias, cfg.init_gyro_scale, cfg.init_accel_scale])
    res = GinsFilter(gcfg).run(inc, gnss, lla0=cfg.init_lla, vel0=cfg.init_vel, q0=quat_from_euler(cfg.init_euler),
                               imu_errors0=err0, smoother=smoother)
    nav = NavTrack(res.t, res.lla, res.vel_ned, res.q_nb)
    write_kfgins_nav(outs["nav"], nav)
    write_kfgins_imu_errors(outs["err"], res.t, res.gyro_bias, res.accel_bias, res.gyro_scale, res.accel_scale)
    sd = np.sqrt(np.pad(res.cov_diag, ((0, 0), (0, max(0, 21 - res.cov_diag.shape[1]))))[:, :21])
    write_kfgins_std(outs["std"], res.cov_t, sd[:, 0:3], sd[:, 3:6], sd[:, 6:9], sd[:, 9:12], sd[:, 12:15],
                     sd[:, 15:18], sd[:, 18:21])
    summary: dict = {"config": str(config), "imu_samples": int(res.t.size), "gnss_used": int(res.gnss_t.size),
                     "gnss_removed": res.meta["removed_gnss"], "states": gcfg.n_states,
                     "gnss_position_nis_mean": float(np.nanmean(res.nis[:, 0])) if res.nis.size else None,
                     "gnss_accepted_share": float(res.accepted[:, 0].mean()) if res.nis.size else None}
    if smoother and res.smoothed is not None:
        s = res.smoothed
        write_kfgins_nav(outs["smoothed"], NavTrack(s.t, s.lla, s.vel_ned, s.q_nb))
    if truth is not None:
        ref = read_kfgins_nav(truth)
        summary["rmse"] = _rmse(nav, ref)
        if smoother and res.smoothed is not None:
            s = res.smoothed
            summary["rmse_smoothed"] = _rmse(NavTrack(s.t, s.lla, s.vel_ned, s.q_nb), ref)
    write_json(outs["summary"], summary)
    line = f"{res.t.size} IMU samples, {res.gnss_t.size} GNSS fixes -> {folder}"
    if "rmse" in summary:
        line += "; position RMSE N E D " + " ".join(f"{x:.3f}" for x in summary["rmse"]["pos_ned_m"]) + " m"
    typer.echo(line)
