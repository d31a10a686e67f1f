"""``imunav zupt``: foot-mounted ZUPT-aided INS, detectors and the LSTM detector."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any, Optional

import numpy as np
import typer
from rich.progress import Progress, track
from rich.table import Table

from imunav.cli._console import make_console
from imunav.cli._errors import check_suffix, fail
from imunav.cli._lazy import lazy
from imunav.cli._options import INSTANCE, LAYOUT, TOPIC, reader_options
from imunav.errors import FileFormatError, ImunavError
from imunav.files import atomic_path, check_outputs, write_json

_common = lazy("imunav.io._common")
foot = lazy("imunav.io.foot")
ins = lazy("imunav.ins")
io = lazy("imunav.io")
learn = lazy("imunav.learn")
learn_lstm = lazy("imunav.learn.lstm")
logs = lazy("imunav.io.logs")
noise_profile = lazy("imunav.noise.profile")

zupt_app = typer.Typer(
    help=("Foot-mounted INS with zero-velocity updates.\n\n"
          "Example: imunav zupt run ../shared/data/foot/pyshoe_vicon/2017-11-22-11-22-03.mat --detector shoe"),
    no_args_is_help=True,
)


def register(app: typer.Typer) -> None:
    app.add_typer(zupt_app, name="zupt")


def _write_json(path: Path, obj: Any) -> None:
    write_json(path, obj, indent=1)


def load_foot_file(path: Path, **read: Any) -> Any:
    """Read a foot recording by its format: pyshoe ``.mat``, x-io or FGO ``.csv``; a ROS bag / PX4 ULog (or
    any file with ``read`` options such as ``topic`` / ``layout``) through :func:`imunav.io.read_imu`."""

    if read or (path.exists() and logs.log_kind(path) is not None):
        return foot.FootTrial(io.read_imu(path, **read), name=path.stem)
    _common.check_nonempty(path)
    if path.suffix.lower() == ".mat":
        return foot.read_pyshoe_mat(path)
    if path.suffix.lower() == ".csv":
        with open(path) as fh:
            header = fh.readline()
        if "Gyroscope X (deg/s)" in header:
            return foot.read_xio_gait_csv(path)
        if "time_index" in header and "acc_x" in header:
            gt = path.with_name("positionGt.csv")
            return foot.read_fgo_csv(path, gt if gt.is_file() else None)
    raise FileFormatError(f"{path}: unknown foot-recording format (pyshoe .mat, x-io Gait-Tracking .csv or "
                          "Constrained-ZUPT-FGO imuMeas*.csv)")


def _fail(exc: Exception) -> None:
    fail(exc)


@zupt_app.command("run")
def run_cmd(
    file: Path = typer.Argument(..., help="Foot recording (.mat pyshoe, .csv x-io / FGO, a ROS bag or PX4 .ulg)."),
    detector: str = typer.Option("shoe", "--detector", "-d", help="shoe, ared, amvd, mbgtd, adaptive, freeacc, lstm, or 'labels:NAME' for stored labels."),
    threshold: Optional[float] = typer.Option(None, help="Detector threshold (default: the library default)."),
    states: int = typer.Option(9, help="9 (thesis) or 15 (with biases)."),
    zaru: bool = typer.Option(False, help="Zero angular-rate updates (needs --states 15)."),
    zaru_min_s: float = typer.Option(0.0, help="Apply the ZARU only in stances at least this long, s (e.g. 1: standing still only)."),
    heading_hold: bool = typer.Option(False, help="No rotation about the vertical during each stance."),
    level_floor: bool = typer.Option(False, help="Flat-floor constraint: every stance at the initial height (not for stairs or ramps)."),
    margin_s: float = typer.Option(0.0, help="Shrink each detected stance by this many seconds at both ends."),
    accel_noise_std: Optional[float] = typer.Option(None, help="Accelerometer noise per sample, m/s^2 (default 0.5, "
                                                    "pyshoe's; with --noise the sensor's, unless given)."),
    noise: Optional[Path] = typer.Option(None, "--noise", help="Noise profile of the foot IMU (imunav noise "
                                         "--profile): per-sample accelerometer and gyro noise at this recording's "
                                         "rate and the bias random walks from it."),
    model: Optional[Path] = typer.Option(None, help="LSTM model file (default: the shipped one)."),
    out: Optional[Path] = typer.Option(None, help="Write the trajectory (t, position, velocity, quaternion, zv) to .npz."),
    json_out: Optional[Path] = typer.Option(None, "--json", help="Write the summary as JSON."),
    topic: Optional[str] = TOPIC,
    instance: Optional[int] = INSTANCE,
    layout: Optional[str] = LAYOUT,
) -> None:
    """Run the ZUPT-aided INS on one recording and print its errors.

    Example: imunav zupt run ../shared/data/foot/pyshoe_vicon/2017-11-22-11-22-03.mat --detector shoe

    A foot IMU in a ROS bag or a PX4 log: give the log and its IMU topic (--topic, e.g. /foot/imu).
    """

    check_outputs([file, model, noise], [out, json_out])

    check_suffix(out, "--out", (".npz",), "the trajectory (NumPy archive)")

    try:
        prof = noise_profile.read_noise_profile(noise) if noise is not None else None
        trial = load_foot_file(file, **reader_options(topic=topic, instance=instance, layout=layout))
        guard = None
        if detector.startswith("labels:"):
            key = detector.split(":", 1)[1]
            if key not in trial.labels:
                raise typer.BadParameter(f"the file has no stored labels {key!r}; it has {sorted(trial.labels)}")
            zv = trial.labels[key]
        else:
            m = None
            if model is not None:
                m = learn.LstmDetector.load(model)
            det_res = ins.detect_zero_velocity(trial.imu, detector, threshold, model=m, margin_s=margin_s)
            zv = det_res.zv
            guard = det_res.params.get("guard")
        xio_like = trial.position is None
        cfg = ins.ZuptConfig(states=states, zaru=zaru, zaru_min_s=zaru_min_s, heading_hold=heading_hold,
                         level_floor=level_floor, accel_noise_std=0.5 if accel_noise_std is None else accel_noise_std,
                         alignment="first_stance" if xio_like else "samples",
                         **({"g": None} if xio_like else {}))  # else ZuptConfig's default, pyshoe's gravity
        if prof is not None:  # the sensor's noise at this recording's rate; an explicit --accel-noise-std wins
            cfg = ins.ZuptConfig.from_noise_profile(prof, base=cfg, fs=float(trial.imu.fs))
            if accel_noise_std is not None:
                cfg = dataclasses.replace(cfg, accel_noise_std=accel_noise_std)
            typer.echo(f"noise from {noise}: accel_noise_std {cfg.accel_noise_std:.4g} m/s^2, gyro_noise_std "
                       f"{cfg.gyro_noise_std:.4g} rad/s per sample at {float(trial.imu.fs):.6g} Hz")
        res = ins.ZuptFilter(cfg).run(trial.imu, zv)
    except ImunavError as exc:
        _fail(exc)
    lc = ins.loop_closure_error(res.position)
    summary: dict[str, Any] = {"file": str(file), "detector": detector, "samples": int(trial.imu.n),
                               "stance_fraction": float(np.mean(zv)), "distance_m": lc.distance_travelled,
                               "loop_closure_m": lc.error_3d, "loop_closure_horizontal_m": lc.horizontal,
                               "loop_closure_vertical_m": lc.vertical}
    if trial.position is not None:
        summary["error_2d_m"] = ins.error_2d(res.position, trial.position)
    if guard is not None:  # the LSTM's SHOE guard: share of samples that took SHOE's flags
        summary["guard_fallback_fraction"] = float(guard["fallback_fraction"])
    for k, v in summary.items():
        typer.echo(f"{k:28s} {v:.4f}" if isinstance(v, float) else f"{k:28s} {v}")
    if out is not None:
        with atomic_path(out) as tmp, open(tmp, "wb") as fh:  # a failed write leaves no temp file
            np.savez_compressed(fh, t=res.t, position=res.position, velocity=res.velocity,
                                quaternion=res.q_nb, zv=res.zv)
    if json_out is not None:
        _write_json(json_out, summary)


@zupt_app.command("train")
def train_cmd(
    directory: Path = typer.Argument(..., help="Folder of pyshoe-format *.mat trials."),
    out: Path = typer.Option(Path("zupt_lstm.npz"), help="Model file to write."),
    windows_per_trial: Optional[int] = typer.Option(None, help="Training windows drawn per trial."),
    epochs: Optional[int] = typer.Option(None, help="Epochs."),
    layers: Optional[int] = typer.Option(None, help="Stacked LSTM layers (thesis: 6)."),
    hidden: Optional[int] = typer.Option(None, help="Units per layer (thesis: 80)."),
    budget_s: Optional[float] = typer.Option(None, help="Stop training after this many seconds (result then depends on machine speed)."),
    seed: int = typer.Option(0, help="Random seed."),
    threads: int = typer.Option(1, help="Torch CPU threads."),
    shoe_threshold: float | None = typer.Option(None, help="SHOE threshold of the stance guard (default: the SHOE grid value with the smallest mean 2-D error over these trials)."),
) -> None:
    """Train the LSTM zero-velocity detector on labelled trials (labels: best stored classical detector per trial).

    The stance guard's SHOE threshold is chosen on the same training trials
    (the protocol of benchmarks/bench_zupt_lstm_cv.py, applied to all of them).

    Example: imunav zupt train ../shared/data/foot/pyshoe_vicon --out zupt_lstm.npz
    """

    check_outputs([directory], [out])  # before the long training
    check_suffix(out, "--out", (".npz",), "the model (NumPy archive)")

    try:
        learn_lstm.require_torch()  # before the slow label selection: training is the one command that needs torch
    except ImunavError as exc:
        _fail(exc)
    files = sorted(directory.glob("*.mat"))
    if not files:
        _fail(FileNotFoundError(f"no *.mat trials in {directory}"))
    kw: dict[str, Any] = {"seed": seed}
    for k, v in (("windows_per_trial", windows_per_trial), ("epochs", epochs), ("layers", layers),
                 ("hidden", hidden), ("time_budget_s", budget_s)):
        if v is not None:
            kw[k] = v
    try:
        learn.LstmConfig(**kw)  # validate the options before the slow part
        trials = [foot.read_pyshoe_mat(f) for f in files]
        if shoe_threshold is None:
            shoe_threshold, _ = learn.select_shoe_threshold(trials)
            typer.echo(f"guard: SHOE threshold {shoe_threshold:.4g} (smallest mean 2-D error over the {len(trials)} trials)")
        cfg = learn.LstmConfig(**kw, shoe_threshold=shoe_threshold)
        labels = []
        audit = []
        for tr in trials:
            y, det, err = learn.best_labels(tr)
            labels.append(y)
            audit.append({"trial": tr.name, "detector": det, "error_2d_m": err})
        with Progress() as prog:
            task = prog.add_task("training", total=None)

            def cb(done: int, total: int, loss: float) -> None:
                prog.update(task, completed=done, total=total, description=f"training (loss {loss:.3f})")

            model, rep = learn.train_lstm([t.imu for t in trials], labels, cfg, progress=cb, threads=threads)
        model.info["label_audit"] = audit
        model.save(out)
    except ImunavError as exc:
        _fail(exc)
    typer.echo(f"trained on {len(trials)} trials, {rep.n_windows} windows in {rep.seconds:.0f} s "
               f"(training accuracy {rep.train_accuracy:.3f}); model written to {out}")


@zupt_app.command("benchmark")
def benchmark_cmd(
    directory: Path = typer.Argument(..., help="Folder of pyshoe-format *.mat trials."),
    json_out: Optional[Path] = typer.Option(None, "--json", help="Write per-trial 2-D errors as JSON."),
    model: Optional[Path] = typer.Option(None, help="LSTM model file (default: the shipped one)."),
    limit: Optional[int] = typer.Option(None, min=1, help="Only the first N trials (sorted by name), N >= 1."),
) -> None:
    """Every detector (fixed thresholds) and the LSTM on every trial: per-trial 2-D error.

    Example: imunav zupt benchmark ../shared/data/foot/pyshoe_vicon --limit 3 --json zupt-bench.json
    """

    check_outputs([directory, model], [json_out])

    files = sorted(directory.glob("*.mat"))[:limit]
    if not files:
        _fail(FileNotFoundError(f"no *.mat trials in {directory}"))
    try:
        lstm = learn.LstmDetector.load(model)
        names = list(ins.DETECTORS) + ["lstm"]
        rows = []
        for f in track(files, description="trials"):
            tr = foot.read_pyshoe_mat(f)
            if tr.position is None:
                raise ImunavError(f"{f}: no ground truth 'gt'; the benchmark needs it")
            row: dict[str, Any] = {"trial": tr.name}
            for name in names:
                zv = (lstm.detect(tr.imu).zv if name == "lstm"
                      else ins.detect_zero_velocity(tr.imu, name, ins.DEFAULT_THRESHOLDS[name]).zv)
                row[name] = ins.error_2d(ins.ZuptFilter().run(tr.imu, zv).position, tr.position)
            rows.append(row)
    except ImunavError as exc:
        _fail(exc)
    table = Table(title="2-D error (m), fixed thresholds")
    table.add_column("trial")
    for n in names:
        table.add_column(n, justify="right")
    for r in rows:
        table.add_row(r["trial"], *[f"{r[n]:.3f}" for n in names])
    means = {n: float(np.mean([r[n] for r in rows])) for n in names}
    table.add_row("mean", *[f"{means[n]:.3f}" for n in names])
    make_console().print(table)
    if json_out is not None:
        _write_json(json_out, {"thresholds": {k: ins.DEFAULT_THRESHOLDS[k] for k in ins.DETECTORS}, "trials": rows,
                               "mean": means})
