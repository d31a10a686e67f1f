"""``imunav gins``: loosely coupled GNSS/INS on KF-GINS files and configurations.

Commands: ``simulate`` (a drive in KF-GINS's formats), ``run`` (the filter on a KF-GINS YAML, or on IMU and
GNSS files with an imunav TOML; :mod:`imunav.ins.gins_inputs`) and ``outage-test`` (the KF-GINS paper's outage
protocol, :mod:`imunav.ins.outage`).  The filter is called from one place, :func:`_run_filter`.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path
from typing import Optional

import numpy as np
import typer

from imunav.errors import ConfigError, InvalidInputError
from imunav.ins.gins import GinsResult
from imunav.ins.gins_inputs import (
    GinsInputs,
    GinsSetup,
    load_inputs,
    run_setup,
    simulate_drive,
    track_rmse,
)
from imunav.ins.gins_plot import FIGURE_NAMES, write_gins_figures
from imunav.ins.outage import outage_test
from imunav.io._atomic import atomic_path, check_outputs, write_json
from imunav.io.gnss import write_gnss_text
from imunav.io.kfgins import (
    ImuIncrements,
    NavTrack,
    read_kfgins_nav,
    write_kfgins_imu,
    write_kfgins_imu_errors,
    write_kfgins_nav,
    write_kfgins_std,
)
from imunav.rotation import euler_from_quat
from imunav.sim import Trajectory
from imunav.toml import toml_text
from imunav.units import DEG, HOUR

gins_app = typer.Typer(
    help=("Loosely coupled GNSS/INS (error-state Kalman filter) on KF-GINS files.\n\n"
          "Example: imunav gins simulate --out drive && imunav gins run --config drive/kf-gins.yaml "
          "--truth drive/truth.nav"),
    no_args_is_help=True,
)

NAV_NAME, ERR_NAME, STD_NAME, SUMMARY_NAME = "KF_GINS_Navresult.nav", "KF_GINS_IMU_ERR.txt", "KF_GINS_STD.txt", \
    "summary.json"
OUTAGE_NAME = "outage.json"


def register(app: typer.Typer) -> None:
    app.add_typer(gins_app, name="gins")


def _v(x: np.ndarray, fmt: str = "{:.10g}") -> str:
    return "[ " + ", ".join(fmt.format(float(a)) for a in x) + " ]"


def _run_filter(inputs: GinsInputs, setup: GinsSetup, *, smoother: bool = False) -> GinsResult:
    """The one call of the GNSS/INS filter in the command line (through :func:`imunav.ins.gins_inputs.run_setup`,
    which the lab step calls too)."""
    return run_setup(inputs.imu, inputs.gnss, setup, odometer=inputs.odometer, smoother=smoother)


def _figures(folder: Path, **kw) -> list[Path]:
    """Write the figures when matplotlib is installed, else say so in one line."""
    if importlib.util.find_spec("matplotlib") is None:
        typer.echo("note: matplotlib is not installed; no figures written (pip install matplotlib)")
        return []
    return write_gins_figures(folder, **kw)


def _figure_paths(folder: Path, names: tuple[str, ...]) -> list[Path]:
    return [folder / FIGURE_NAMES[n] for n in names]


def _inputs(imu: Optional[Path], gnss: Optional[Path], config: Optional[Path], odo: Optional[Path],
            truth: Optional[Path], states: Optional[int]) -> tuple[GinsInputs, GinsSetup, NavTrack | None]:
    """Read the inputs of ``run`` / ``outage-test``; the initial state from the truth when none is configured."""
    if states is not None and states not in (15, 21):
        raise ConfigError(f"--states must be 15 or 21; got {states}")
    inputs = load_inputs(imu, gnss, config, odometer=odo, states=states)
    ref = read_kfgins_nav(truth) if truth is not None else None
    setup = inputs.setup
    if not setup.has_init:
        if ref is None:
            raise ConfigError(f"{config}: no initial state; add an [init] table (lla_deg, vel_ned, euler_deg) or "
                              "give --truth to start from the truth")
        setup = setup.with_truth_init(ref, float(inputs.imu.t[0]))
    return inputs, setup, ref


@gins_app.command("simulate")
def simulate_cmd(
    out: Path = typer.Option(..., "--out", help="Folder for imu.txt, gnss.txt, truth.nav and kf-gins.yaml."),
    duration: float = typer.Option(600.0, help="Drive length, s (>= 120)."),
    preset: str = typer.Option("mems_adis16465", help="IMU error preset (imunav.sim.presets)."),
    fs: float = typer.Option(200.0, help="IMU rate, Hz."),
    seed: int = typer.Option(1, help="Random seed."),
    sow0: float = typer.Option(456300.0, "--start-sow", help="GPS second of week of the first sample."),
) -> None:
    """Simulate a land-vehicle drive in KF-GINS's formats: IMU increments, 1 Hz GNSS, the truth, a KF-GINS YAML
    and the same configuration as an imunav TOML (gins.toml).

    Example: imunav gins simulate --out drive --duration 600 --preset mems_adis16465
    """
    names = {k: out / v for k, v in (("imu", "imu.txt"), ("gnss", "gnss.txt"), ("truth", "truth.nav"),
                                     ("yaml", "kf-gins.yaml"), ("toml", "gins.toml"))}
    check_outputs([], names.values())
    drive = simulate_drive(duration, preset=preset, fs=fs, seed=seed, t0=sow0)
    truth, imu, gnss, cfg = drive.truth, drive.imu, drive.gnss, drive.setup.config
    lever = cfg.lever_arm
    write_kfgins_imu(names["imu"], ImuIncrements.from_imu_data(imu, fs))
    write_gnss_text(names["gnss"], gnss)
    write_kfgins_nav(names["truth"], drive.truth_track())
    eul = np.degrees(euler_from_quat(truth.q_nb[0]))
    lla_deg = np.r_[np.degrees(truth.pos_lla[0, :2]), truth.pos_lla[0, 2]]
    pos_std, vel_std, att_std_deg = (0.5, 0.5, 1.0), (0.05, 0.05, 0.05), (0.1, 0.1, 0.5)
    text = "\n".join([
        "# KF-GINS configuration written by 'imunav gins simulate' (keys and units of KF-GINS's dataset/kf-gins.yaml)",
        'imupath: "imu.txt"', 'gnsspath: "gnss.txt"', 'outputpath: "result"', "imudatalen: 7",
        f"imudatarate: {fs:g}", f"starttime: {sow0:.3f}", "endtime: -1",
        f"initpos: {_v(lla_deg, '{:.10f}')}",
        f"initvel: {_v(truth.vel_ned[0])}", f"initatt: {_v(eul, '{:.8f}')}",
        "initgyrbias: [ 0, 0, 0 ]", "initaccbias: [ 0, 0, 0 ]", "initgyrscale: [ 0, 0, 0 ]", "initaccscale: [ 0, 0, 0 ]",
        f"initposstd: {_v(pos_std)}", f"initvelstd: {_v(vel_std)}", f"initattstd: {_v(att_std_deg)}",
        f"initbgstd: {_v(cfg.init_gyro_bias_std / (DEG / HOUR))}", f"initbastd: {_v(cfg.init_accel_bias_std / 1e-5)}",
        "imunoise:",
        f"  arw: {_v(cfg.arw / (DEG / 60))}", f"  vrw: {_v(cfg.vrw * 60)}",
        f"  gbstd: {_v(cfg.gyro_bias_std / (DEG / HOUR))}", f"  abstd: {_v(cfg.accel_bias_std / 1e-5)}",
        f"  gsstd: {_v(cfg.gyro_scale_std / 1e-6)}", f"  asstd: {_v(cfg.accel_scale_std / 1e-6)}",
        f"  corrtime: {cfg.corr_time / HOUR:.6g}",
        f"antlever: {_v(lever)}", ""])
    with atomic_path(names["yaml"]) as tmp:
        tmp.write_text(text, encoding="utf-8")
    # the same configuration as the YAML, field by field in SI (not the preset, whose mapping may differ)
    noise = {k: np.asarray(getattr(cfg, k)).tolist() for k in ("arw", "vrw", "gyro_bias_std", "accel_bias_std",
                                                                  "gyro_scale_std", "accel_scale_std",
                                                                  "init_gyro_bias_std", "init_accel_bias_std")}
    toml = {"states": 21, **noise, "corr_time": float(cfg.corr_time), "lever_arm": lever.tolist(),
            "init_pos_std": list(pos_std),
            "init_vel_std": list(vel_std), "init_att_std": (np.radians(att_std_deg)).tolist(),
            "init": {"lla_deg": lla_deg.tolist(), "vel_ned": truth.vel_ned[0].tolist(), "euler_deg": eul.tolist()},
            "imu": {"format": "kf-gins", "rate_hz": fs}}
    with atomic_path(names["toml"]) as tmp:
        tmp.write_text("# imunav GNSS/INS configuration written by 'imunav gins simulate' (SI; "
                       "see imunav.ins.gins_inputs)\n" + toml_text(toml), encoding="utf-8")
    typer.echo(f"{truth.n} IMU samples ({duration:g} s at {fs:g} Hz, preset {preset}), {gnss.n} GNSS fixes -> {out}")


_IMU_ARG = typer.Argument(None, help="IMU file: KF-GINS increments (7+ columns) or any recording imunav reads "
                                     "(rates, SI, FRD). Omit with a KF-GINS YAML.", show_default=False)
_GNSS_ARG = typer.Argument(None, help="GNSS file: KF-GINS text (s, lat deg, lon deg, h, sigma N E D) or a CSV "
                                      "(columns named in the TOML's [gnss] table).", show_default=False)
_CONFIG_OPT = typer.Option(None, "--config", help="KF-GINS YAML (its keys and units; names the IMU and GNSS files) "
                                                  "or, with IMU GNSS, an imunav TOML (GinsConfig fields in SI, "
                                                  "preset, [init], [imu], [gnss]).")
_ODO_OPT = typer.Option(None, "--odo", help="Odometer file: time s, forward speed m/s (two columns).")
_STATES_OPT = typer.Option(None, "--states", help="15 (no scale factors) or 21 (default: the configuration's, "
                                                  "else 21).")


@gins_app.command("run")
def run_cmd(
    imu: Optional[Path] = _IMU_ARG,
    gnss: Optional[Path] = _GNSS_ARG,
    config: Optional[Path] = _CONFIG_OPT,
    odo: Optional[Path] = _ODO_OPT,
    out: Optional[Path] = typer.Option(None, "--out", help="Output folder (default with a YAML: its outputpath)."),
    truth: Optional[Path] = typer.Option(None, "--truth", help="Truth .nav file (KF-GINS format): RMSE in "
                                                               "summary.json, error figure; the initial state when "
                                                               "the TOML has no [init]."),
    smoother: bool = typer.Option(False, "--smoother", help="Also write the RTS-smoothed solution (*_smoothed.nav)."),
    states: Optional[int] = _STATES_OPT,
    plots: bool = typer.Option(True, "--plots/--no-plots", help="Write the figures (track, errors, IMU errors)."),
) -> None:
    """Run the GNSS/INS filter on a KF-GINS YAML, or on IMU and GNSS files with a TOML; write KF-GINS's outputs
    (.nav, IMU errors, state sigma), summary.json and figures.

    Example: imunav gins run --config drive/kf-gins.yaml --out drive/result --truth drive/truth.nav

    Example: imunav gins run drive/imu.txt drive/gnss.txt --config drive/gins.toml --out res --truth drive/truth.nav
    """
    inputs, setup, ref = _inputs(imu, gnss, config, odo, truth, states)
    folder = out if out is not None else inputs.output_path
    if folder is None:
        raise ConfigError("give --out DIR, the folder for the results")
    outs = {k: folder / v for k, v in (("nav", NAV_NAME), ("err", ERR_NAME), ("std", STD_NAME),
                                       ("summary", SUMMARY_NAME))}
    if smoother:
        outs["smoothed"] = folder / NAV_NAME.replace(".nav", "_smoothed.nav")
    figs = _figure_paths(folder, ("track", "errors", "imu_errors")) if plots else []
    check_outputs([*inputs.paths.values(), truth], [*outs.values(), *figs])
    res = _run_filter(inputs, setup, smoother=smoother)
    nav = NavTrack(res.t, res.lla, res.vel_ned, res.q_nb)
    write_kfgins_nav(outs["nav"], nav)
    write_kfgins_imu_errors(outs["err"], res.t, res.gyro_bias, res.accel_bias, res.gyro_scale, res.accel_scale)
    # the filter's own states only (an odometer scale state follows them); a 15-state filter does not estimate
    # the scale factors: their sigma columns are written as 0, as the README says
    nx = setup.config.n_states
    sd = np.sqrt(np.pad(res.cov_diag[:, :nx], ((0, 0), (0, 21 - nx))))
    write_kfgins_std(outs["std"], res.cov_t, sd[:, 0:3], sd[:, 3:6], sd[:, 6:9], sd[:, 9:12], sd[:, 12:15],
                     sd[:, 15:18], sd[:, 18:21])
    summary: dict = {"config": str(config) if config is not None else None,
                     "inputs": {k: str(v) for k, v in inputs.paths.items()},
                     "initial_state": "configuration" if inputs.setup.has_init else "truth",
                     "imu_samples": int(res.t.size), **res.gnss_summary(),
                     "gnss_removed": res.meta["removed_gnss"], "states": setup.config.n_states,
                     "odometer": inputs.odometer is not None}
    if smoother and res.smoothed is not None:
        s = res.smoothed
        write_kfgins_nav(outs["smoothed"], NavTrack(s.t, s.lla, s.vel_ned, s.q_nb))
    if ref is not None:
        summary["rmse"] = track_rmse(nav, ref)
        if smoother and res.smoothed is not None:
            s = res.smoothed
            summary["rmse_smoothed"] = track_rmse(NavTrack(s.t, s.lla, s.vel_ned, s.q_nb), ref)
    if plots:
        summary["figures"] = [p.name for p in _figures(folder, result=res, gnss=inputs.gnss, truth=ref)]
    write_json(outs["summary"], summary)
    line = f"{res.t.size} IMU samples, {res.gnss_t.size} GNSS fixes -> {folder}"
    if "rmse" in summary:
        line += "; position RMSE N E D " + " ".join(f"{x:.3f}" for x in summary["rmse"]["pos_ned_m"]) + " m"
    typer.echo(line)


def _shifts(text: str) -> tuple[float, ...]:
    try:
        vals = tuple(float(x) for x in text.split(",") if x.strip())
    except ValueError:
        raise InvalidInputError(f"--shifts {text!r}: give comma-separated seconds, e.g. 0,60,120") from None
    if not vals or not all(np.isfinite(v) and v >= 0 for v in vals):
        raise InvalidInputError(f"--shifts {text!r}: give one or more finite shifts >= 0 s, e.g. 0,60,120")
    return vals


@gins_app.command("outage-test")
def outage_cmd(
    imu: Optional[Path] = _IMU_ARG,
    gnss: Optional[Path] = _GNSS_ARG,
    config: Optional[Path] = _CONFIG_OPT,
    odo: Optional[Path] = _ODO_OPT,
    truth: Optional[Path] = typer.Option(None, "--truth", help="Truth .nav file on the IMU stamps (required with "
                                                               "files)."),
    out: Path = typer.Option(..., "--out", help="Output folder: outage.json and the drift figure."),
    preset: Optional[str] = typer.Option(None, "--preset", help="Without files: simulate a drive with this IMU "
                                                                "preset (default navigation_a15)."),
    duration: Optional[float] = typer.Option(None, "--duration", help="Simulated drive length, s [default: 1200]."),
    fs: Optional[float] = typer.Option(None, "--fs", help="Simulated IMU rate, Hz [default: 100]."),
    seed: Optional[int] = typer.Option(None, "--seed", help="Seed of the simulated drive [default: 1]."),
    rtk: Optional[bool] = typer.Option(None, "--rtk/--spp", help="Simulated fixes: RTK (2 / 2 / 3 cm) or SPP-like "
                                                                 "(0.5 / 0.5 / 1 m) [default: --rtk]."),
    converge: float = typer.Option(300.0, "--converge", help="Convergence time before the first outage, s."),
    every: float = typer.Option(180.0, "--every", help="Outage period, s."),
    length: float = typer.Option(60.0, "--length", help="Outage length, s."),
    shifts: str = typer.Option("0,60,120", "--shifts", help="Start shifts of the first outage, s (one run each)."),
    states: Optional[int] = _STATES_OPT,
    plots: bool = typer.Option(True, "--plots/--no-plots", help="Write the outage drift figure."),
) -> None:
    """The KF-GINS paper's outage protocol: after convergence a GNSS outage every period, one run per start shift;
    RMS over outages of the largest horizontal / vertical / 3-D drift and roll / pitch / heading errors, and the
    share of outages inside the predicted 3 sigma.

    Example: imunav gins outage-test --preset navigation_a15 --duration 1200 --seed 1 --out outage

    Example: imunav gins outage-test --config drive/kf-gins.yaml --truth drive/truth.nav --out outage
    """
    sh = _shifts(shifts)
    files = imu is not None or gnss is not None or config is not None
    if files and preset is not None:
        raise ConfigError("--preset simulates a drive; give either --preset or files (IMU GNSS --config, or a "
                          "KF-GINS YAML), not both")
    if files:
        sim_only = [name for name, v in (("--duration", duration), ("--fs", fs), ("--seed", seed),
                                          ("--rtk/--spp", rtk)) if v is not None]
        if sim_only:
            raise ConfigError(f"{', '.join(sim_only)} set(s) the simulated drive; with files the drive is the "
                              "files' own: leave it out")
        if truth is None:
            raise ConfigError("the outage test measures drift against a truth: give --truth FILE.nav")
        inputs, setup, ref = _inputs(imu, gnss, config, odo, truth, states)
        traj = Trajectory(ref.t, ref.q_nb, ref.vel_ned, ref.lla)
        data, fixes, odometer, source = inputs.imu, inputs.gnss, inputs.odometer, str(config)
        in_paths = [*inputs.paths.values(), truth]
    else:
        if odo is not None:
            raise ConfigError("--odo needs IMU and GNSS files; the simulated drive has no odometer")
        name = preset or "navigation_a15"
        duration = 1200.0 if duration is None else duration
        fs = 100.0 if fs is None else fs
        seed = 1 if seed is None else seed
        rtk = True if rtk is None else rtk
        drive = simulate_drive(duration, preset=name, fs=fs, seed=seed,
                               pos_noise=(0.02, 0.02, 0.03) if rtk else (0.5, 0.5, 1.0),
                               states=21 if states is None else states)
        data, fixes, setup, traj, odometer = drive.imu, drive.gnss, drive.setup, drive.truth, None
        source, in_paths = f"simulated: preset {name}, {duration:g} s at {fs:g} Hz, seed {seed}", []
    json_path = out / OUTAGE_NAME
    figs = _figure_paths(out, ("outage",)) if plots else []
    check_outputs(in_paths, [json_path, *figs])
    rep = outage_test(data, fixes, setup.config, traj, lla0=setup.lla0, vel0=setup.vel0, q0=setup.q0,
                      converge_s=converge, every_s=every, length_s=length, shifts_s=sh, odometer=odometer)
    rms = rep.rms()
    doc = {"source": source, "protocol": rep.meta, "states": setup.config.n_states, "rms": rms,
           "outages": [{"start_s": s, "length_s": d, "horizontal_m": h, "vertical_m": v, "drift_3d_m": d3,
                        "roll_deg": r, "pitch_deg": p, "heading_deg": y, "inside_3sigma": bool(c)}
                       for (s, d), h, v, d3, r, p, y, c in zip(rep.outages, rep.horizontal_m, rep.vertical_m,
                                                               rep.drift_3d_m, rep.roll_deg, rep.pitch_deg,
                                                               rep.heading_deg, rep.contained)]}
    if plots:
        doc["figures"] = [p.name for p in _figures(out, outage=rep)]
    write_json(json_path, doc)
    n_in = int(np.sum(rep.contained))
    typer.echo(f"{rms['n_outages']} outages of {length:g} s; RMS of the per-outage maximum drift: horizontal "
               f"{rms['horizontal_m']:.3f} m, vertical {rms['vertical_m']:.3f} m, 3-D {rms['3d_m']:.3f} m; roll "
               f"{rms['roll_deg']:.4f} deg, pitch {rms['pitch_deg']:.4f} deg, heading {rms['heading_deg']:.4f} deg; "
               f"{n_in}/{rms['n_outages']} ({100 * rms['contained_3sigma']:.0f} %) inside the predicted 3 sigma "
               f"-> {json_path}")
