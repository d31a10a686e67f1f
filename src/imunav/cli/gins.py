"""``imunav gins``: loosely coupled GNSS/INS on KF-GINS files and configurations.

Commands: ``simulate`` (a drive in KF-GINS's formats), ``run`` (the filter on a KF-GINS YAML, or on IMU and
GNSS files with an imunav TOML; :mod:`imunav.ins.gins.setup`) and ``outage-test`` (the KF-GINS paper's outage
protocol, :mod:`imunav.ins.gins.outage`).  The filter is called from one place, :func:`_run_filter`.
"""

from __future__ import annotations

import dataclasses
import importlib.util
from pathlib import Path
from typing import TYPE_CHECKING, Optional

import numpy as np
import typer

from imunav.cli._domains import Domain, parse_numbers
from imunav.cli._lazy import lazy
from imunav.cli._progress import progress
from imunav.errors import ConfigError, InvalidInputError
from imunav.files import check_outputs, write_json

if TYPE_CHECKING:
    from imunav.ins.gins import GinsResult
    from imunav.ins.gins.setup import GinsInputs, GinsSetup
    from imunav.io.kfgins import NavTrack

gins_config = lazy("imunav.ins.gins.config")
logrun = lazy("imunav.ins.gins.logrun")
noise_profile = lazy("imunav.noise.profile")
outage = lazy("imunav.ins.gins.outage")
outputs = lazy("imunav.ins.gins.outputs")
gins_plot = lazy("imunav.ins.gins.plot")
gins_setup = lazy("imunav.ins.gins.setup")
kfgins = lazy("imunav.io.kfgins")
logs = lazy("imunav.io.logs")
navlog = lazy("imunav.io.navlog")
comma2k19 = lazy("imunav.io.comma2k19")
sim = lazy("imunav.sim")

gins_app = typer.Typer(
    help=("Loosely coupled GNSS/INS (error-state Kalman filter) on KF-GINS files.\n\n"
          "Example: imunav gins simulate --out drive && imunav gins run --config drive/kf-gins.yaml "
          "--truth drive/truth.nav"),
    no_args_is_help=True,
)

OUTAGE_NAME = "outage.json"


def register(app: typer.Typer) -> None:
    app.add_typer(gins_app, name="gins")


def _run_filter(inputs: GinsInputs, setup: GinsSetup, *, smoother: bool = False, quiet: bool = False) -> GinsResult:
    """The one call of the GNSS/INS filter in the command line (through :func:`imunav.ins.gins.setup.run_setup`,
    which the lab step calls too), with a bar over its samples (and the smoother's) on a terminal."""
    with progress(_PASS_LABEL[smoother], quiet=quiet) as report:
        return gins_setup.run_setup(inputs.imu, inputs.gnss, setup, odometer=inputs.odometer, smoother=smoother,
                                    progress=report)


#: The bar of the filter's pass over the samples (the smoother's pass counts as many).
_PASS_LABEL = {False: "gins run: filter (samples)", True: "gins run: filter, then smoother (samples)"}


def _say_no_matplotlib(plots: bool) -> None:
    if plots and importlib.util.find_spec("matplotlib") is None:
        typer.echo("note: matplotlib is not installed; no figures written (pip install matplotlib)")


def _inputs(imu: Optional[Path], gnss: Optional[Path], config: Optional[Path], odo: Optional[Path],
            truth: Optional[Path], states: Optional[int]) -> tuple[GinsInputs, GinsSetup, NavTrack | None]:
    """Read the inputs of ``run`` / ``outage-test``; the initial state from the truth when none is configured."""
    if states is not None and states not in (15, 21):
        raise ConfigError(f"--states must be 15 or 21; got {states}")
    inputs = gins_setup.load_inputs(imu, gnss, config, odometer=odo, states=states)
    ref = kfgins.read_kfgins_nav(truth) if truth is not None else None
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
    check_outputs([], [out / name for name in outputs.DRIVE_FILES.values()])
    drive = gins_setup.simulate_drive(duration, preset=preset, fs=fs, seed=seed, t0=sow0)
    outputs.write_simulated_drive(drive, out)
    truth, gnss = drive.truth, drive.gnss
    typer.echo(f"{truth.n} IMU samples ({duration:g} s at {fs:g} Hz, preset {preset}), {gnss.n} GNSS fixes -> {out}")


_IMU_ARG = typer.Argument(None, help="IMU file: KF-GINS increments (7+ columns) or any recording imunav reads "
                                     "(rates, SI, FRD). Omit with a KF-GINS YAML.", show_default=False)
_GNSS_ARG = typer.Argument(None, help="GNSS file: KF-GINS text (s, lat deg, lon deg, h, sigma N E D) or a CSV "
                                      "(columns named in the TOML's [gnss] table).", show_default=False)
_CONFIG_OPT = typer.Option(None, "--config", help="KF-GINS YAML (its keys and units; names the IMU and GNSS files) "
                                                  "or, with IMU GNSS, an imunav TOML (GinsConfig fields in SI, "
                                                  "preset, [init], [imu], [gnss]).")
_ODO_OPT = typer.Option(None, "--odo", help="Odometer file: time s, forward speed m/s (two columns; a third: "
                                                "the speed's sigma, m/s).")
_STATES_OPT = typer.Option(None, "--states", help="15 (no scale factors) or 21 (default: the configuration's, "
                                                  "else 21).")
# the options of a log's sources, shared by `run` and `outage-test`
_IMU_TOPIC_OPT = typer.Option(None, "--imu-topic", help="With a log: the IMU topic (sensor_msgs/Imu, PX4 "
                                                        "sensor_combined).")
_GNSS_TOPIC_OPT = typer.Option(None, "--gnss-topic", help="With a log: the GNSS topic (NavSatFix, PX4 "
                                                          "vehicle_gps_position / sensor_gps).")
_ODO_TOPIC_OPT = typer.Option(None, "--odo-topic", help="With a log: the wheel odometry topic (nav_msgs/Odometry, "
                                                        "TwistStamped).")
_MAG_TOPIC_OPT = typer.Option(None, "--mag-topic", help="With a log: the magnetometer topic.")
_BARO_TOPIC_OPT = typer.Option(None, "--baro-topic", help="With a log: the barometer topic.")
_GYRO_OPT = typer.Option(None, "--gyro", help="With a comma2k19 segment: 'calibrated' (Android's bias-corrected "
                                              "gyro, the default) or 'raw'.")
_ROTATION_OPT = typer.Option(None, "--imu-rotation", help="With a log: the IMU's mounting in the vehicle, "
                                                          "'qw,qx,qy,qz' or ZYX 'roll,pitch,yaw' in degrees (default: "
                                                          "the bag's /tf_static, else estimated).")
_LEVER_OPT = typer.Option(None, "--gnss-lever-arm", help="With a log: the GNSS antenna from the IMU, vehicle FRD, "
                                                         "m: 'x,y,z'.")
_PRESET_LOG_OPT = typer.Option("consumer_mems", "--preset", help="With a log: the IMU error preset whose noise "
                                                                 "model the filter uses.")


def _log_sources(path: Path, *, imu_topic: Optional[str], gnss_topic: Optional[str], odo_topic: Optional[str],
                 mag_topic: Optional[str], baro_topic: Optional[str], gyro: Optional[str]) -> "navlog.NavSources":
    """A log's sources with the topics (or, for a comma2k19 segment, the gyro) the options choose."""
    return navlog.read_nav_sources(path, imu_topic=imu_topic, gnss_topic=gnss_topic, odo_topic=odo_topic,
                                   mag_topic=mag_topic, baro_topic=baro_topic, gyro=gyro)


def _log_truth(path: Optional[Path]) -> "NavTrack | None":
    """A reference for a log's run: a KF-GINS ``.nav`` file, or a comma2k19 segment folder (its fused pose)."""
    if path is None:
        return None
    if comma2k19.is_comma2k19_segment(path):
        return comma2k19.read_comma2k19_pose(path)
    return kfgins.read_kfgins_nav(path)


@gins_app.command("run")
def run_cmd(
    imu: Optional[Path] = _IMU_ARG,
    gnss: Optional[Path] = _GNSS_ARG,
    config: Optional[Path] = _CONFIG_OPT,
    odo: Optional[Path] = _ODO_OPT,
    out: Optional[Path] = typer.Option(None, "--out", help="Output folder (default with a YAML: its outputpath)."),
    truth: Optional[Path] = typer.Option(None, "--truth", help="Truth .nav file (KF-GINS format), or with a log a "
                                                               "comma2k19 segment (its fused pose): RMSE in "
                                                               "summary.json, error figure; the initial state when "
                                                               "the TOML has no [init]."),
    smoother: bool = typer.Option(False, "--smoother", help="Also write the RTS-smoothed solution (*_smoothed.nav); "
                                                            "a log's run has it by default (--forward-only)."),
    states: Optional[int] = _STATES_OPT,
    plots: bool = typer.Option(True, "--plots/--no-plots", help="Write the figures (track, errors, IMU errors)."),
    imu_topic: Optional[str] = _IMU_TOPIC_OPT,
    gnss_topic: Optional[str] = _GNSS_TOPIC_OPT,
    odo_topic: Optional[str] = _ODO_TOPIC_OPT,
    mag_topic: Optional[str] = _MAG_TOPIC_OPT,
    baro_topic: Optional[str] = _BARO_TOPIC_OPT,
    gyro: Optional[str] = _GYRO_OPT,
    imu_rotation: Optional[str] = _ROTATION_OPT,
    gnss_lever_arm: Optional[str] = _LEVER_OPT,
    preset: str = _PRESET_LOG_OPT,
    forward_only: bool = typer.Option(False, "--forward-only", help="With a log: the forward filter's trajectory "
                                                                    "only (real time), without the smoother."),
    noise: Optional[Path] = typer.Option(None, "--noise", help="Noise profile of the IMU (imunav noise --profile): "
                                         "per-axis noise densities and the bias Gauss-Markov sigma from it, in place "
                                         "of the configuration's or the preset's."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar."),
) -> None:
    """Run the GNSS/INS filter on a robot's or a drone's log (ROS 1 bag, ROS 2 bag folder, PX4 ULog, or a folder of
    KF-GINS text files with a sources.toml, run as a log), on a KF-GINS YAML, or on IMU and GNSS files with a TOML; write KF-GINS's outputs (.nav, IMU errors, state sigma),
    summary.json and figures (a log: also track.geojson, the mounting, odometer scale and GNSS latency found).

    Example (a real robot's ROS 1 bag, no GNSS: dead reckoning): imunav gins run
    ../shared/data/ros_bags/jackal_test2.bag --out jackal-run

    Example (a real car: a comma2k19 segment, against comma's fused pose): imunav gins run
    ../shared/data/comma2k19/example1 --truth ../shared/data/comma2k19/example1 --out car

    Example: imunav gins run --config drive/kf-gins.yaml --out drive/result --truth drive/truth.nav

    Example: imunav gins run drive/imu.txt drive/gnss.txt --config drive/gins.toml --out res --truth drive/truth.nav
    """
    if imu is not None and navlog.is_nav_log(imu):
        if gnss is not None or config is not None or odo is not None or states is not None:
            raise ConfigError(f"{imu} is a log: it names its own sources; choose topics with --imu-topic / "
                              "--gnss-topic / --odo-topic / --mag-topic / --baro-topic instead of files")
        if out is None:
            raise ConfigError("give --out DIR, the folder for the results")
        if forward_only and smoother:
            raise ConfigError("--forward-only and --smoother contradict each other; a log's run has the smoother "
                              "by default")
        outs = outputs.log_output_paths(out, smoother=not forward_only, plots=plots, truth=truth is not None)
        check_outputs([p for p in (imu, truth, noise) if p is not None], outs.values())
        overrides = {}
        if noise is not None:  # the profile's noise densities and bias sigma replace the preset's
            base = gins_config.GinsConfig.from_preset(preset)
            cfg = gins_config.GinsConfig.from_noise_profile(noise_profile.read_noise_profile(noise), base=base)
            overrides = {k: getattr(cfg, k) for k in _NOISE_FIELDS}
        opts = logrun.LogRunOptions(preset=preset, mounting=logrun.parse_rotation(imu_rotation, "--imu-rotation"),
                                    gnss_lever_arm=logrun.parse_vector(gnss_lever_arm, "--gnss-lever-arm"),
                                    smoother=not forward_only, overrides=overrides)
        with progress("gins run: reading the log", quiet=quiet, total=1) as report:
            sources = _log_sources(imu, imu_topic=imu_topic, gnss_topic=gnss_topic, odo_topic=odo_topic,
                                   mag_topic=mag_topic, baro_topic=baro_topic, gyro=gyro)
            ref = _log_truth(truth)
            report(1, 1)
        with progress(_PASS_LABEL[not forward_only], quiet=quiet) as report:
            run = logrun.run_log(sources, opts, progress=report)
        ref_run = None if ref is None else logrun.truth_on_sources(ref, sources).at(run.result.t)
        with progress("gins run: writing", quiet=quiet, total=1) as report:
            summary = outputs.write_log_outputs(out, run, sources, plots=plots, truth=ref_run)
            report(1, 1)
        _say_no_matplotlib(plots)
        m = summary["mounting"]
        line = (f"{summary['imu_samples']} IMU samples, {summary.get('gnss_used', 0)} GNSS fixes used -> {out}; "
                f"mounting roll {m['roll_deg']:.2f} pitch {m['pitch_deg']:.2f} yaw {m['yaw_deg']:.2f} deg "
                f"({m['source']})")
        if summary["odometer_scale"] is not None:
            line += f"; odometer scale {1 + summary['odometer_scale']['value']:.4f}"
        if summary["gnss_time_offset_s"] is not None:
            lat = summary["gnss_time_offset_s"]
            line += f"; GNSS latency {lat['value']:.3f} +- {lat['std']:.3f} s"
        if "rmse" in summary:
            line += ("; horizontal RMSE against the truth " +
                     f"{float(np.hypot(*summary['rmse']['pos_ned_m'][:2])):.3f} m")
        typer.echo(line)
        typer.echo(f"honesty: {summary['honesty']['verdict']}")
        return
    rot_opts = [k for k, v in (("--imu-topic", imu_topic), ("--gnss-topic", gnss_topic), ("--odo-topic", odo_topic),
                               ("--mag-topic", mag_topic), ("--baro-topic", baro_topic), ("--gyro", gyro),
                               ("--imu-rotation", imu_rotation), ("--gnss-lever-arm", gnss_lever_arm)) if v is not None]
    if forward_only:
        rot_opts.append("--forward-only")
    if rot_opts:
        raise ConfigError(f"{', '.join(rot_opts)} go with a log (a .bag, a ROS 2 bag folder or a .ulg); the files of "
                          "this run name their own inputs")
    prof = noise_profile.read_noise_profile(noise) if noise is not None else None
    inputs, setup, ref = _inputs(imu, gnss, config, odo, truth, states)
    folder = out if out is not None else inputs.output_path
    if folder is None:
        raise ConfigError("give --out DIR, the folder for the results")
    outs = outputs.run_output_paths(folder, smoother=smoother, plots=plots, truth=ref is not None)
    ins = [*inputs.paths.values(), truth, noise]
    try:  # the folder as `--out` is checked (a report folder): it may not be or hold an input, wherever it is named
        check_outputs(ins, [], folders=[folder])
    except InvalidInputError as exc:
        if out is not None:
            raise
        raise ConfigError(f"{config}, key 'outputpath': {exc} (set outputpath to a folder of its own, e.g. "
                          "outputpath: \"result\", or give --out DIR)") from None
    check_outputs(ins, outs.values())
    if prof is not None:  # the profile's noise densities and bias sigma replace the configuration's
        cfg = gins_config.GinsConfig.from_noise_profile(prof, base=setup.config)
        setup = dataclasses.replace(setup, config=cfg)
        typer.echo(f"noise from {noise}: gyro_noise_density {' '.join(f'{v:.3g}' for v in cfg.gyro_noise_density)} "
                   f"rad/s/sqrt(Hz), accel_noise_density {' '.join(f'{v:.3g}' for v in cfg.accel_noise_density)} "
                   f"m/s^2/sqrt(Hz), corr_time {cfg.corr_time:g} s")
    res = _run_filter(inputs, setup, smoother=smoother, quiet=quiet)
    summary = outputs.write_run_outputs(
        folder, res, setup, gnss=inputs.gnss, truth=ref, plots=plots,
        extra={"config": str(config) if config is not None else None,
               "inputs": {k: str(v) for k, v in inputs.paths.items()},
               "initial_state": "configuration" if inputs.setup.has_init else "truth",
               "odometer": inputs.odometer is not None})
    _say_no_matplotlib(plots)
    line = f"{res.t.size} IMU samples, {res.gnss_t.size} GNSS fixes -> {folder}"
    if "rmse" in summary:
        line += "; position RMSE N E D " + " ".join(f"{x:.3f}" for x in summary["rmse"]["pos_ned_m"]) + " m"
    typer.echo(line)


#: The GinsConfig fields a noise profile sets (:meth:`~imunav.ins.gins.config.GinsConfig.from_noise_profile`).
_NOISE_FIELDS = ("gyro_noise_density", "accel_noise_density", "gyro_bias_std", "accel_bias_std")


def _shifts(text: str) -> tuple[float, ...]:
    return tuple(parse_numbers("--shifts", text, Domain(lo=0.0, unit="s"), example="0,60,120"))


@gins_app.command("outage-test")
def outage_cmd(
    imu: Optional[Path] = _IMU_ARG,
    gnss: Optional[Path] = _GNSS_ARG,
    config: Optional[Path] = _CONFIG_OPT,
    odo: Optional[Path] = _ODO_OPT,
    truth: Optional[Path] = typer.Option(None, "--truth", help="Truth .nav file on the IMU stamps (required with "
                                                               "files; with a log, the reference instead of the "
                                                               "removed fixes: a .nav, or a comma2k19 segment's "
                                                               "fused pose)."),
    truth_std: float = typer.Option(0.0, "--truth-std", help="With a log and --truth: the reference's own horizontal "
                                                             "sigma, m, added to the predicted sigma (a peer's pose "
                                                             "is not survey truth)."),
    out: Path = typer.Option(..., "--out", help="Output folder: outage.json and the drift figure."),
    preset: Optional[str] = typer.Option(None, "--preset", help="Without files: simulate a drive with this IMU "
                                                                "preset (default navigation_a15); with a log: the "
                                                                "IMU preset of the filter's noise model "
                                                                "(consumer_mems)."),
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
    gnss_lever_arm: Optional[str] = _LEVER_OPT,
    imu_topic: Optional[str] = _IMU_TOPIC_OPT,
    gnss_topic: Optional[str] = _GNSS_TOPIC_OPT,
    odo_topic: Optional[str] = _ODO_TOPIC_OPT,
    mag_topic: Optional[str] = _MAG_TOPIC_OPT,
    baro_topic: Optional[str] = _BARO_TOPIC_OPT,
    gyro: Optional[str] = _GYRO_OPT,
    imu_rotation: Optional[str] = _ROTATION_OPT,
    plots: bool = typer.Option(True, "--plots/--no-plots", help="Write the outage drift figure (not with a log: "
                                                                "its outage.json holds every outage)."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar."),
) -> None:
    """The KF-GINS paper's outage protocol: after convergence a GNSS outage every period, one run per start shift;
    RMS over outages of the largest horizontal / vertical / 3-D drift and roll / pitch / heading errors, and the
    share of outages inside the predicted 3 sigma.

    Example: imunav gins outage-test --preset navigation_a15 --duration 1200 --seed 1 --out outage

    Example: imunav gins outage-test --config drive/kf-gins.yaml --truth drive/truth.nav --out outage

    Example (a simulated robot's ROS 1 bag, its antenna 0.3 m above the IMU, the fixes removed during each outage
    its reference): python -c "import pathlib; from imunav.sim.robot_log import simulate_robot_log, write_robot_log;
    d = pathlib.Path('robot'); d.mkdir(exist_ok=True); write_robot_log(simulate_robot_log(1), d, formats=('ros1',
    'kfgins'))" && imunav gins outage-test robot/robot.bag --gnss-lever-arm 0,0,-0.3 --converge 60 --every 120
    --length 60 --shifts 0,30,60 --out robot-outage

    Example (the same outages against the drive's truth, a KF-GINS .nav): imunav gins outage-test robot/robot.bag
    --gnss-lever-arm 0,0,-0.3 --truth robot/kfgins/truth.nav --converge 60 --every 120 --length 60 --shifts
    0,30,60 --out robot-outage-truth

    Example (a real car, 10 s outages against comma's fused pose, its own sigma 0.5 m): imunav gins outage-test
    ../shared/data/comma2k19/example1 --truth ../shared/data/comma2k19/example1 --truth-std 0.5 --converge 20
    --every 15 --length 10 --shifts 0,5,10 --out car-outage
    """
    sh = _shifts(shifts)
    outage.check_protocol(every, length, sh)  # before any reading: a log's run takes the same protocol
    if imu is not None and navlog.is_nav_log(imu):
        extra = [n for n, v in (("GNSS file", gnss), ("--config", config), ("--odo", odo),
                                ("--duration", duration), ("--fs", fs), ("--seed", seed), ("--rtk/--spp", rtk),
                                ("--states", states)) if v is not None]
        if extra:
            raise ConfigError(f"{imu} is a log: the fixes removed during each outage (or --truth) are the "
                              f"reference; leave out {', '.join(extra)}")
        if truth_std < 0 or not np.isfinite(truth_std):
            raise ConfigError(f"--truth-std {truth_std}: the reference's sigma is >= 0 m")
        if truth_std > 0 and truth is None:
            raise ConfigError("--truth-std is the sigma of the --truth reference; give --truth")
        json_path = out / OUTAGE_NAME
        check_outputs([p for p in (imu, truth) if p is not None], [json_path])
        sources = _log_sources(imu, imu_topic=imu_topic, gnss_topic=gnss_topic, odo_topic=odo_topic,
                               mag_topic=mag_topic, baro_topic=baro_topic, gyro=gyro)
        ref = _log_truth(truth)
        with progress("gins outage-test: the run with every fix, then one per shift", quiet=quiet,
                      total=len(sh) + 1) as report:
            opts = logrun.LogRunOptions(preset=preset or "consumer_mems",
                                        mounting=logrun.parse_rotation(imu_rotation, "--imu-rotation"),
                                        gnss_lever_arm=logrun.parse_vector(gnss_lever_arm, "--gnss-lever-arm"))
            rep = logrun.log_outage_test(sources, opts, converge_s=converge, every_s=every, length_s=length,
                                         shifts_s=sh, truth=ref, truth_std=truth_std, progress=report)
        doc = outputs.log_outage_document(rep, source=str(imu))
        write_json(json_path, doc)
        rms = doc["rms"]
        ratio, dr = rms["ratio_to_dead_reckoning"], rms["dead_reckoning_end_m"]
        dr_text = "no odometer" if dr is None else f"odometry dead reckoning {dr:.3f} m (ratio {ratio:.2f})"
        noise = rms["reference_noise_m"]

        def above(key: str) -> str:
            v = rms[key]
            return "within the noise" if v is None else f"{v:.3f} m"

        whose = "the fixes'" if rms["reference"] == "removed fixes" else "the reference's"
        floor = "" if not noise or dr is None else (
            f"; less {whose} own noise ({noise:.2f} m): {above('end_above_noise_m')} vs "
            f"{above('dead_reckoning_above_noise_m')}")
        typer.echo(f"{rms['n_outages']} outages of {length:g} s against the {rms['reference']}: RMS horizontal "
                   f"error at their end {rms['end_m']:.3f} m, largest {rms['max_m']:.3f} m; {dr_text}{floor}; "
                   f"{100 * rms['contained_3sigma']:.0f} % inside the predicted 3 sigma (largest normalised error "
                   f"{rms['normalised_max']:.2f}) -> {json_path}")
        return
    log_only = [k for k, v in (("--gnss-lever-arm", gnss_lever_arm), ("--imu-topic", imu_topic),
                               ("--gnss-topic", gnss_topic), ("--odo-topic", odo_topic), ("--mag-topic", mag_topic),
                               ("--baro-topic", baro_topic), ("--gyro", gyro), ("--imu-rotation", imu_rotation))
                if v is not None]
    if truth_std != 0.0:
        log_only.append("--truth-std")
    if log_only:
        raise ConfigError(f"{', '.join(log_only)} go(es) with a log (a .bag, a ROS 2 bag folder, a .ulg, a "
                          "comma2k19 segment); files and the simulated drive name their own sources")
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
        traj = sim.Trajectory(ref.t, ref.q_nb, ref.vel_ned, ref.lla)
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
        drive = gins_setup.simulate_drive(duration, preset=name, fs=fs, seed=seed,
                               pos_noise=(0.02, 0.02, 0.03) if rtk else (0.5, 0.5, 1.0),
                               states=21 if states is None else states)
        data, fixes, setup, traj, odometer = drive.imu, drive.gnss, drive.setup, drive.truth, None
        source, in_paths = f"simulated: preset {name}, {duration:g} s at {fs:g} Hz, seed {seed}", []
    json_path = out / OUTAGE_NAME
    figs = [out / gins_plot.FIGURE_NAMES["outage"]] if plots else []
    check_outputs(in_paths, [json_path, *figs])
    with progress("gins outage-test: one run per shift", quiet=quiet, total=len(sh)) as report:
        rep = outage.outage_test(data, fixes, setup.config, traj, lla0=setup.lla0, vel0=setup.vel0, q0=setup.q0,
                                 converge_s=converge, every_s=every, length_s=length, shifts_s=sh, odometer=odometer,
                                 progress=report)
    rms = rep.rms()
    doc = outputs.outage_document(rep, source=source, states=setup.config.n_states)
    if plots:
        doc["figures"] = [p.name for p in outputs.write_figures(out, outage=rep)]
        _say_no_matplotlib(plots)
    write_json(json_path, doc)
    n_in = int(np.sum(rep.contained))
    typer.echo(f"{rms['n_outages']} outages of {length:g} s; RMS of the per-outage maximum drift: horizontal "
               f"{rms['horizontal_m']:.3f} m, vertical {rms['vertical_m']:.3f} m, 3-D {rms['3d_m']:.3f} m; roll "
               f"{rms['roll_deg']:.4f} deg, pitch {rms['pitch_deg']:.4f} deg, heading {rms['heading_deg']:.4f} deg; "
               f"{n_in}/{rms['n_outages']} ({100 * rms['contained_3sigma']:.0f} %) inside the predicted 3 sigma "
               f"-> {json_path}")
