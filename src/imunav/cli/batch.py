"""``imunav batch ...``: a production batch of IMUs (simulate, calibrate, noise) and a folder of robot or drone
logs (gins) in parallel."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Optional

import numpy as np
import typer
from rich.markup import escape
from rich.table import Table

from imunav.cli._console import make_console
from imunav.cli._domains import COLUMNS_EXAMPLE, parse_json
from imunav.cli._errors import fail, one_line
from imunav.cli._lazy import lazy
from imunav.cli._progress import shows_progress
from imunav.errors import ConfigError, InvalidInputError
from imunav.files import check_outputs, write_json

batch = lazy("imunav.lab.batch")
catalog = lazy("imunav.lab.report.catalog")
logrun = lazy("imunav.ins.gins.logrun")

app = typer.Typer(
    help="Process a folder of recordings (one per unit of a production batch, or one robot / drone log each) in "
    "parallel, with a summary table and per-unit result files.\n\n"
    "Example: imunav batch simulate 4 --out batch --fs 20 --dwell 4 && imunav batch calibrate batch",
    no_args_is_help=True,
)


def register(root: typer.Typer) -> None:
    root.add_typer(app, name="batch")


_EXEC = typer.Option("processes", "--executor", help="processes, dask or serial.")
_WORKERS = typer.Option(None, "--workers", "-j", help="Worker processes (default: all cores).")
_ADDR = typer.Option(None, "--address", help="Dask scheduler address (tcp://host:8786) for --executor dask.")
_QUIET = typer.Option(False, "--quiet", "-q", help="No progress bar (none either when standard error is not a "
                      "terminal).")


def _bar(quiet: bool) -> bool:
    """The library's own bar (imunav.lab.montecarlo) on a terminal only, as imunav.cli._progress draws it."""
    return shows_progress(quiet)
_SPEC = typer.Option(None, "--spec", help="Datasheet spec (TOML with a [spec] table) for pass / fail per unit.")
_JSON = typer.Option(None, "--json", help="Also write the summary (JSON) here.")
_COLS = typer.Option(None, "--columns", help='CSV column mapping as JSON, e.g. \'{"gyro": ["gx","gy","gz"]}\'.')
_FS = typer.Option(None, "--fs", help="Sampling rate, Hz (files without a time column).")
_OVERWRITE = typer.Option(False, "--overwrite", help="Clear an output folder that holds another imunav run "
                          "(only the files its manifest lists) instead of refusing.")
_AU = typer.Option(None, "--accel-unit", help="Accelerometer unit in the files (e.g. g).")
_GU = typer.Option(None, "--gyro-unit", help="Gyro unit in the files (e.g. deg/s).")


def _read_options(fs: Optional[float], accel_unit: Optional[str], gyro_unit: Optional[str],
                  columns: Optional[str]) -> dict[str, Any]:
    opts: dict[str, Any] = {}
    if fs:
        opts["fs"] = fs
    units = {k: v for k, v in (("accel", accel_unit), ("gyro", gyro_unit)) if v}
    if units:
        opts["units"] = units
    if columns:
        opts["columns"] = parse_json("--columns", columns, COLUMNS_EXAMPLE)
    return opts


def _fail(exc: Exception) -> None:
    fail(exc)


def _print_summary(summary: Any, families: list[str], title: str) -> None:
    """Rich table: one row per unit, one column per parameter family (x, y, z in one cell)."""

    t = summary.table
    fams = [f for f in families if any(c.startswith(f + "_") and not c.endswith(("_se", "_err")) for c in t.columns)]
    errs = [c for c in t.columns if c.endswith("_err")]
    tab = Table(title=title)
    tab.add_column("unit")
    tab.add_column("verdict")
    for f in fams:
        tab.add_column(escape(f"{f} x, y, z [{catalog.display_unit(f)}]"), justify="right")
    if errs:
        tab.add_column("max |err|/σ", justify="right")
    for r in t.to_dict(orient="records"):
        p = r.get("passed")
        if r["status"] != "ok":
            verdict = "[red]ERROR[/red]"
        else:
            verdict = "n/a" if p is None or (isinstance(p, float) and math.isnan(p)) else ("PASS" if p else "[red]FAIL[/red]")
        cells = []
        for f in fams:
            vals = [r.get(f"{f}_{a}") for a in "xyz"]
            cells.append(", ".join("–" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:.5g}"
                                   for v in vals))
        if errs:
            z = [abs(r[c] / r[c[:-4] + "_se"]) for c in errs
                 if isinstance(r.get(c), float) and isinstance(r.get(c[:-4] + "_se"), float) and r[c[:-4] + "_se"] > 0]
            cells.append(f"{np.nanmax(z):.2f}" if z else "–")
        tab.add_row(r["unit"], verdict, *cells)
    con = make_console()
    con.width = max(con.width, 150)  # a wide table reads better wrapped by the terminal than squeezed
    con.print(tab)
    _failed_items(t.to_dict(orient="records"))


def _failed_items(rows: list[dict]) -> None:
    """One line on standard error per item that failed (the table on standard output marks it ERROR)."""
    for r in rows:
        if r["status"] != "ok":
            typer.echo(f"error: {r['unit']}: {one_line(str(r.get('error')))}", err=True)


@app.command("simulate")
def simulate_cmd(
    n_units: int = typer.Argument(..., help="Number of IMUs in the batch."),
    out: Path = typer.Option(Path("batch"), "--out", "-o", help="Batch folder to write."),
    preset: str = typer.Option("thesis_sim", help="Error-model preset the units spread around."),
    spread: float = typer.Option(0.2, help="Relative unit-to-unit spread of bias, scale, misalignment, g-sensitivity."),
    seed: int = typer.Option(0, "--seed", help="Seed (unit k uses child k of the seed sequence)."),
    fs: float = typer.Option(50.0, "--fs", help="Sampling rate, Hz."),
    dwell: float = typer.Option(5.0, "--dwell", help="Seconds per position / rate step."),
    transition: float = typer.Option(1.0, "--transition", help="Seconds per move / rate ramp."),
    rate_table: bool = typer.Option(True, "--rate-table/--no-rate-table", help="Also simulate the 120-step rate-table test."),
    fmt: str = typer.Option("npz", "--format", help="Recording format: npz, csv, parquet, hdf5, mat."),
    static: Optional[float] = typer.Option(None, "--static", help="Instead: one level static record of this many seconds per unit (for noise)."),
    executor: str = _EXEC, workers: Optional[int] = _WORKERS, quiet: bool = _QUIET, overwrite: bool = _OVERWRITE,
) -> None:
    """Simulate a production batch of IMUs: 100-position (and rate-table) tests of N units with unit-to-unit spread.

    Writes <unit>.<format>, <unit>_rate.<format>, segments.json, rate_segments.json, truth/<unit>.json, batch.json and, last, manifest.json (run id, seed, every file with its SHA-256). A folder that holds another run is refused unless --overwrite, which clears it first; batch calibrate / noise trust only the files of a complete manifest.

    Example: imunav batch simulate 4 --out batch --fs 20 --dwell 4 --overwrite
    """

    check_outputs([], [], run_folders=[out])
    try:
        files = batch.simulate_batch(n_units, out, preset=preset, spread=spread, rng=seed, fs=fs, dwell_s=dwell,
                               transition_s=transition, rate_table=rate_table, format=fmt, static_s=static,
                               executor=executor, n_workers=workers, progress=_bar(quiet),
                               overwrite=overwrite)  # type: ignore[arg-type]
    except InvalidInputError as exc:
        _fail(exc)
    typer.echo(f"{len(files)} units written to {out}")


@app.command("calibrate")
def calibrate_cmd(
    folder: Path = typer.Argument(..., help="Batch folder: one recording per unit (+ segments.json)."),
    method: str = typer.Option("multiposition", "--method", "-m", help="multiposition, thesis (static + rate table) or multipose."),
    out: Optional[Path] = typer.Option(None, "--out", "-o", help="Result folder (default FOLDER/calibration)."),
    spec: Optional[Path] = _SPEC,
    json_out: Optional[Path] = _JSON,
    latitude_deg: Optional[float] = typer.Option(None, help="Latitude, deg (normal gravity, Earth-rate removal)."),
    gravity: Optional[float] = typer.Option(None, help="Local gravity, m/s^2."),
    fs: Optional[float] = _FS, accel_unit: Optional[str] = _AU, gyro_unit: Optional[str] = _GU,
    columns: Optional[str] = _COLS,
    executor: str = _EXEC, workers: Optional[int] = _WORKERS, address: Optional[str] = _ADDR, quiet: bool = _QUIET,
    overwrite: bool = _OVERWRITE,
) -> None:
    """Calibrate every unit of a batch folder in parallel; prints the summary table.

    Writes per unit <unit>.json (calibration) and <unit>_report.json, plus summary.csv, summary.json, index.html and manifest.json (the result folder is a run folder: --overwrite to replace one). A batch folder written by batch simulate is read through its manifest (a killed run is refused). Exit status 1 when a unit fails to process or fails the spec.

    Example: imunav batch calibrate batch --method thesis --out batch_thesis --json batch_cal.json
    """

    check_outputs([spec, folder], [json_out], run_folders=[out if out is not None else folder / "calibration"])

    try:
        s = batch.calibrate_batch(folder, method=method, out_dir=out, spec=spec,
                            read_options=_read_options(fs, accel_unit, gyro_unit, columns),
                            latitude=None if latitude_deg is None else math.radians(latitude_deg), gravity=gravity,
                            executor=executor, n_workers=workers, address=address, progress=_bar(quiet),
                            overwrite=overwrite)  # type: ignore[arg-type]
    except InvalidInputError as exc:
        _fail(exc)
    cols = ["accel_bias", "accel_scale", "gyro_bias", "gyro_scale", "gyro_g_sensitivity"]
    _print_summary(s, cols, f"batch calibration ({method}): {len(s.table)} units, {s.seconds:.1f} s")
    _finish(s, json_out)


@app.command("noise")
def noise_cmd(
    folder: Path = typer.Argument(..., help="Folder of static recordings, one per unit."),
    out: Optional[Path] = typer.Option(None, "--out", "-o", help="Result folder (default FOLDER/noise)."),
    spec: Optional[Path] = _SPEC,
    json_out: Optional[Path] = _JSON,
    fs: Optional[float] = _FS, accel_unit: Optional[str] = _AU, gyro_unit: Optional[str] = _GU,
    columns: Optional[str] = _COLS,
    terms: str = typer.Option("Q,N,B,K,R", "--terms", help="Candidate IEEE-952 terms (BIC selects among them)."),
    force: bool = typer.Option(False, "--force", help="Analyse recordings that are not static (moved or rotated)."),
    executor: str = _EXEC, workers: Optional[int] = _WORKERS, address: Optional[str] = _ADDR, quiet: bool = _QUIET,
    overwrite: bool = _OVERWRITE,
) -> None:
    """Allan-variance noise identification (ARW / VRW, bias instability, random walk) of every unit, in parallel.

    Writes <unit>_noise.json per unit, summary.csv, summary.json and index.html. Each recording must be static
    (one pose, no rotation; judged from its window means and mean specific force): a folder of multi-position
    tests is refused unless --force.

    Example: imunav batch simulate 3 --static 600 --out static_batch && imunav batch noise static_batch --terms N,B,K
    """

    check_outputs([spec, folder], [json_out], run_folders=[out if out is not None else folder / "noise"])

    try:
        s = batch.noise_batch(folder, out_dir=out, spec=spec, read_options=_read_options(fs, accel_unit, gyro_unit, columns),
                        terms=tuple(t.strip() for t in terms.split(",") if t.strip()), executor=executor, n_workers=workers, address=address, progress=_bar(quiet), force=force, overwrite=overwrite)  # type: ignore[arg-type]
    except InvalidInputError as exc:
        _fail(exc)
    cols = ["gyro_arw", "gyro_bias_instability", "accel_vrw", "accel_bias_instability"]
    _print_summary(s, cols, f"batch noise: {len(s.table)} units, {s.seconds:.1f} s")
    _finish(s, json_out)


@app.command("gins")
def gins_cmd(
    folder: Path = typer.Argument(..., help="Folder of logs: ROS 1 .bag files, ROS 2 bag folders, PX4 .ulg files."),
    out: Optional[Path] = typer.Option(None, "--out", "-o", help="Result folder (default FOLDER/gins)."),
    json_out: Optional[Path] = _JSON,
    imu_topic: Optional[str] = typer.Option(None, "--imu-topic", help="The IMU topic of every log."),
    gnss_topic: Optional[str] = typer.Option(None, "--gnss-topic", help="The GNSS topic of every log."),
    odo_topic: Optional[str] = typer.Option(None, "--odo-topic", help="The wheel odometry topic of every log."),
    mag_topic: Optional[str] = typer.Option(None, "--mag-topic", help="The magnetometer topic of every log."),
    baro_topic: Optional[str] = typer.Option(None, "--baro-topic", help="The barometer topic of every log."),
    imu_rotation: Optional[str] = typer.Option(None, "--imu-rotation", help="The IMU's mounting in the vehicle, "
                                               "'qw,qx,qy,qz' or ZYX 'roll,pitch,yaw' in degrees (default: each "
                                               "bag's /tf_static, else estimated)."),
    gnss_lever_arm: Optional[str] = typer.Option(None, "--gnss-lever-arm", help="The GNSS antenna from the IMU, "
                                                 "vehicle FRD, m: 'x,y,z'."),
    preset: str = typer.Option("consumer_mems", "--preset", help="The IMU error preset whose noise model the "
                                                                 "filter uses."),
    smoother: bool = typer.Option(False, "--smoother", help="The RTS-smoothed trajectory of each log (the default; "
                                                            "kept for earlier command lines)."),
    forward_only: bool = typer.Option(False, "--forward-only", help="The forward filter's trajectory only (real "
                                                                    "time), without the smoother."),
    plots: bool = typer.Option(True, "--plots/--no-plots", help="Write each log's figures."),
    executor: str = _EXEC, workers: Optional[int] = _WORKERS, address: Optional[str] = _ADDR, quiet: bool = _QUIET,
    overwrite: bool = _OVERWRITE,
) -> None:
    """GNSS/INS on every log of a folder, in parallel: each as `imunav gins run LOG` (same options, the same for
    every log), one result folder per log, and a summary table.

    Writes FOLDER/gins/<log>/ (the .nav, IMU errors, state sigma, track.geojson, summary.json and figures of gins
    run) and summary.csv, summary.json, summary.md: per log its sources, duration, mounting, odometer scale and GNSS
    latency with their sigma, the share of fixes rejected and the final position sigma. A log that fails is a row
    with its error. Exit status 1 when a log fails.

    Example (two short simulated robot drives, a ROS 1 and a ROS 2 bag, their antennas 0.3 m above the IMU):
    python -c "import pathlib; from imunav.sim.robot_log import simulate_robot_log, write_robot_log; d =
    pathlib.Path('logs'); d.mkdir(exist_ok=True); write_robot_log(simulate_robot_log(1, distance_m=80.0), d,
    formats=('ros1',)); write_robot_log(simulate_robot_log(2, distance_m=80.0), d, formats=('ros2',))" && imunav
    batch gins logs --gnss-lever-arm 0,0,-0.3 --no-plots
    """

    check_outputs([folder], [json_out], run_folders=[out if out is not None else folder / "gins"])
    if smoother and forward_only:
        _fail(ConfigError("--forward-only and --smoother contradict each other; the smoother is the default"))
    try:
        opts = logrun.LogRunOptions(preset=preset, mounting=logrun.parse_rotation(imu_rotation, "--imu-rotation"),
                                    gnss_lever_arm=logrun.parse_vector(gnss_lever_arm, "--gnss-lever-arm"),
                                    smoother=not forward_only)
        topics = {"imu_topic": imu_topic, "gnss_topic": gnss_topic, "odo_topic": odo_topic, "mag_topic": mag_topic,
                  "baro_topic": baro_topic}
        s = batch.gins_batch(folder, out_dir=out, topics=topics, options=opts, plots=plots, executor=executor,
                             n_workers=workers, address=address, progress=_bar(quiet),
                             overwrite=overwrite)  # type: ignore[arg-type]
    except InvalidInputError as exc:
        _fail(exc)
    _print_gins(s, f"batch gins: {len(s.table)} logs, {s.seconds:.1f} s")
    if json_out is not None:
        write_json(json_out, s.to_dict())
    typer.echo(f"summary: {s.out_dir / 'summary.csv'}, {s.out_dir / 'summary.md'}")
    if s.n_failed:
        raise typer.Exit(1)


def _print_gins(summary: Any, title: str) -> None:
    """Rich table: one row per log, the mounting, odometer scale, GNSS latency and final position sigma."""

    def num(v: Any, fmt: str) -> str:
        return "–" if v is None or (isinstance(v, float) and math.isnan(v)) else format(v, fmt)

    tab = Table(title=title)
    for c in ("log", "status", "s", "mounting r, p, y [deg] (σ)", "odometer scale (σ)", "GNSS latency [s] (σ)",
              "rejected", "final σ N, E, D [m]"):
        tab.add_column(escape(c), justify="left" if c in ("log", "status") else "right")
    for r in summary.table.to_dict(orient="records"):
        if r["status"] != "ok":
            tab.add_row(r["unit"], "[red]ERROR[/red]", *["–"] * 6)
            continue
        mount = ", ".join(f"{num(r[f'mounting_{a}_deg'], '.2f')} ({num(r[f'mounting_{a}_std_deg'], '.2f')})"
                          for a in ("roll", "pitch", "yaw"))
        tab.add_row(r["unit"], "ok", num(r["duration_s"], ".0f"), mount,
                    f"{num(r['odometer_scale'], '.4f')} ({num(r['odometer_scale_std'], '.4f')})",
                    f"{num(r['gnss_time_offset_s'], '.3f')} ({num(r['gnss_time_offset_std_s'], '.3f')})",
                    num(r["gnss_rejected_share"], ".1%"),
                    ", ".join(num(r[f"final_pos_std_{a}_m"], ".2f") for a in "ned"))
    con = make_console()
    con.width = max(con.width, 150)
    con.print(tab)
    _failed_items(summary.table.to_dict(orient="records"))


def _finish(summary: Any, json_out: Optional[Path]) -> None:
    if json_out is not None:
        write_json(json_out, summary.to_dict())
    typer.echo(f"summary: {summary.out_dir / 'summary.csv'}, report: {summary.out_dir / 'index.html'}")
    if summary.n_failed or summary.passed is False:
        raise typer.Exit(1)
