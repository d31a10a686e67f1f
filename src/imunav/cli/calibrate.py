"""``imunav calibrate ...``: deterministic IMU and magnetometer calibration.

Each sub-command writes the calibration JSON (``--out``) and, with
``--report DIR``, a ``report.json`` (parameters, standard errors, residuals,
design condition) and residual plots.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Optional

import numpy as np
import typer
from rich.markup import escape
from rich.table import Table

from imunav.cli._console import make_console
from imunav.cli._domains import COLUMNS_EXAMPLE, DOMAINS, parse_json, parse_numbers
from imunav.cli._lazy import lazy
from imunav.cli._options import END, INSTANCE, LAYOUT, START, TOPIC, reader_options, window
from imunav.errors import FileFormatError, InvalidInputError
from imunav.files import check_outputs, check_writable, read_json, write_json

_common = lazy("imunav.io._common")
calib = lazy("imunav.calib")
calib_multipose = lazy("imunav.calib.multipose")
calib_temperature = lazy("imunav.calib.temperature")
io = lazy("imunav.io")
logs = lazy("imunav.io.logs")
magnetometer = lazy("imunav.calib.magnetometer")
pd = lazy("pandas")
plot = lazy("imunav.calib.plot")
px4params = lazy("imunav.io.px4params")
sim = lazy("imunav.sim")

app = typer.Typer(
    help="Calibrate an IMU or magnetometer from a recording; writes the calibration JSON.\n\n"
    "Example (after imunav simulate's): imunav calibrate multiposition static.npz --segments static_segments.json "
    "--out cal.json",
    no_args_is_help=True,
)


def register(root: typer.Typer) -> None:
    root.add_typer(app, name="calibrate")


# ---------------------------------------------------------------- helpers
def _read(path: Path, fs: Optional[float], accel_unit: Optional[str], gyro_unit: Optional[str],
          accel_scale: Optional[float], gyro_scale: Optional[float], skiprows: Optional[int],
          columns: Optional[str], topic: Optional[str] = None, instance: Optional[int] = None,
          layout: Optional[str] = None) -> Any:
    return io.read_imu(path, **reader_options(
        units={k: v for k, v in (("accel", accel_unit), ("gyro", gyro_unit)) if v},
        scales={k: v for k, v in (("accel", accel_scale), ("gyro", gyro_scale)) if v},
        fs=fs or None, skiprows=skiprows, columns=_columns(columns) if columns else None,
        topic=topic, instance=instance, layout=layout,
    ))


def _columns(text: str) -> Any:
    return parse_json("--columns", text, COLUMNS_EXAMPLE)


def _segments(path: Path) -> Any:
    return sim.Segments.read(path)


def _check_report(report: Optional[Path]) -> None:
    """Refuse, before any work, a report folder that cannot be created or written (e.g. an existing file)."""
    if report is not None:
        check_writable(report / "report.json")


def _px4(px4_params: Optional[Path], **calibration: Any) -> Any:
    """The PX4 parameters (:func:`imunav.io.px4params.px4_parameters`) when ``--px4-params`` is given, else None;
    computed before any file is written, so a calibration PX4 cannot take leaves no file behind."""
    if px4_params is None:
        return None

    return px4params.px4_parameters(**calibration)


def _write_px4(params: Any, path: Optional[Path]) -> None:
    if params is None or path is None:
        return
    params.write(path)
    typer.echo(f"PX4 parameters written to {path}")
    for d in params.dropped:
        typer.echo(f"  not expressible in PX4, dropped: {d}")
    for c in params.converted:
        typer.echo(f"  converted: {c}")


def _finish(result: Any, out: Path, report: Optional[Path], *, save: Any = None, px4: Optional[Path] = None) -> None:


    px4_values = _px4(px4, imu=result.calibration)

    if report is not None:
        # the report folder first: a report that cannot be written leaves no calibration behind either

        report.mkdir(parents=True, exist_ok=True)
        check_writable(report / "report.json")
    (save or result.calibration.save)(out)
    con = make_console()
    if report is not None:
        write_json(report / "report.json", result.to_dict())
        plot.save_figure(plot.plot_residuals(result), report / "residuals.png")
    tab = Table(title=f"{result.method}: residual RMS and design condition")
    tab.add_column("fit")
    tab.add_column("residual RMS (x, y, z)")
    tab.add_column("unit")
    tab.add_column("condition number")
    cal = result.calibration
    for k, r in result.residuals.items():
        rms = np.sqrt(np.mean(np.asarray(r, float) ** 2, axis=0))
        c = result.condition.get(k, result.condition.get(k.split("_")[0], float("nan")))
        unit = cal.raw_accel_unit if k.startswith("accel") else cal.raw_gyro_unit if k.startswith("gyro") else "raw"
        tab.add_row(k, np.array2string(np.atleast_1d(rms), precision=4), unit, f"{c:.3g}")
    con.print(tab)
    con.print(f"calibration written to {out}" + (f", report in {report}" if report else ""))
    _write_px4(px4_values, px4)


_FS = typer.Option(None, help="Sampling rate, Hz (files without a time column).")
_AU = typer.Option(None, help="Accelerometer unit in the file (e.g. g); default m/s^2.")
_GU = typer.Option(None, help="Gyro unit in the file (e.g. deg/s); default rad/s.")
_AS = typer.Option(None, help="Scale applied to raw accelerometer values (e.g. counts to g).")
_GS = typer.Option(None, help="Scale applied to raw gyro values.")
_SK = typer.Option(None, help="Lines to skip before the CSV header.")
_COL = typer.Option(None, help='Column mapping as JSON, e.g. \'{"gyro": ["gx","gy","gz"]}\'.')
_OUT = typer.Option(..., "--out", "-o", help="Calibration JSON to write.")
_NM = typer.Option(None, help="Characterised noise (ImuErrorModel TOML: noise densities, bias instability) "
                   "for generalised least squares; default: AR(1) from the residuals.")


def _noise_model(path: Optional[Path]) -> Any:
    if path is None:
        return None

    return sim.ImuErrorModel.from_toml(path)
_REP = typer.Option(None, help="Folder for report.json and residual plots.")
_PX4 = typer.Option(None, "--px4-params", help="Also write the calibration as PX4 parameters (QGroundControl "
                    ".params file: CAL_ACC0_*, CAL_GYRO0_*, CAL_MAG0_*); terms PX4 cannot express are dropped and "
                    "listed in its header.")


# ---------------------------------------------------------------- commands
@app.command()
def multiposition(
    recording: Path = typer.Argument(..., help="Static multi-position recording (any read_imu format)."),
    segments: Path = typer.Option(..., help="Segment table, .json or .csv (as imunav simulate writes it next to the recording)."),
    out: Path = _OUT,
    report: Optional[Path] = _REP,
    px4_params: Optional[Path] = _PX4,
    latitude_deg: Optional[float] = typer.Option(None, help="Latitude, deg: normal gravity and Earth-rate removal."),
    gravity: Optional[float] = typer.Option(None, help="Local gravity, m/s^2 (default normal gravity / 9.80665)."),
    g_sensitivity: str = typer.Option("diagonal", help="Gyro g-sensitivity: diagonal, full or none."),
    noise_model: Optional[Path] = _NM,
    fs: Optional[float] = _FS, accel_unit: Optional[str] = _AU, gyro_unit: Optional[str] = _GU,
    accel_scale: Optional[float] = _AS, gyro_scale: Optional[float] = _GS, skiprows: Optional[int] = _SK,
    columns: Optional[str] = _COL, topic: Optional[str] = TOPIC, instance: Optional[int] = INSTANCE,
    layout: Optional[str] = LAYOUT,
) -> None:
    """Multi-position least squares (accelerometer T, b; gyro bias and g-sensitivity).

    Example: imunav calibrate multiposition static.npz --segments static_segments.json --out static_cal.json --report rep --px4-params static_cal.params
    """

    check_outputs([recording, segments, noise_model], [out, px4_params], folders=[report])
    _check_report(report)

    data = _read(recording, fs, accel_unit, gyro_unit, accel_scale, gyro_scale, skiprows, columns, topic, instance,
                 layout)
    lat = None if latitude_deg is None else np.deg2rad(latitude_deg)
    res = calib.multiposition(data, _segments(segments), latitude=lat, gravity=gravity, g_sensitivity=g_sensitivity,
                              noise_model=_noise_model(noise_model))
    _finish(res, out, report, px4=px4_params)


@app.command()
def ratetable(
    recording: Path = typer.Argument(..., help="Rate-table recording."),
    segments: Path = typer.Option(..., help="Segment table (.json or .csv) of the rate-table run."),
    out: Path = _OUT,
    static: Optional[Path] = typer.Option(None, help="Static multi-position recording (gives bias and g-sensitivity)."),
    static_segments: Optional[Path] = typer.Option(None, help="Segment table (.json or .csv) of the static recording."),
    base: Optional[Path] = typer.Option(None, help="Existing calibration JSON to take bias / g-sensitivity from."),
    intercept: bool = typer.Option(False, help="Estimate a separate gyro bias in the rate fit."),
    report: Optional[Path] = _REP,
    px4_params: Optional[Path] = _PX4,
    latitude_deg: Optional[float] = typer.Option(None, help="Latitude, deg (Earth rate, normal gravity)."),
    noise_model: Optional[Path] = _NM,
    fs: Optional[float] = _FS, accel_unit: Optional[str] = _AU, gyro_unit: Optional[str] = _GU,
    accel_scale: Optional[float] = _AS, gyro_scale: Optional[float] = _GS, skiprows: Optional[int] = _SK,
    columns: Optional[str] = _COL, topic: Optional[str] = TOPIC, instance: Optional[int] = INSTANCE,
    layout: Optional[str] = LAYOUT,
) -> None:
    """Rate-table least squares for the gyro matrix (with the static test: the full thesis model).

    Example: imunav simulate ratetable --preset thesis_sim --out rate.npz && imunav calibrate ratetable rate.npz --segments rate_segments.json --static static.npz --static-segments static_segments.json --out cal.json
    """

    check_outputs([recording, segments, static, static_segments, base, noise_model], [out, px4_params],
                  folders=[report])
    _check_report(report)
    if static is not None and base is not None:
        raise InvalidInputError("--base and --static both give the bias / g-sensitivity: give one of them")
    if static_segments is not None and static is None:
        raise InvalidInputError("--static-segments is the segment table of --static: give --static too, or drop it")

    lat = None if latitude_deg is None else np.deg2rad(latitude_deg)
    rd = (fs, accel_unit, gyro_unit, accel_scale, gyro_scale, skiprows, columns, topic, instance, layout)
    st = None
    nm = _noise_model(noise_model)
    if static is not None:
        if static_segments is None:
            raise typer.BadParameter("--static needs --static-segments")
        st = calib.multiposition(_read(static, *rd), _segments(static_segments), latitude=lat, noise_model=nm)
        b = st.calibration
    else:
        b = calib.ImuCalibration.load(base) if base is not None else None
    res = calib.ratetable(_read(recording, *rd), _segments(segments), base=b, latitude=lat, intercept=intercept,
                          noise_model=nm)
    if st is not None:
        res = calib.combine(st, res)
    _finish(res, out, report, px4=px4_params)


@app.command()
def ferraris(
    recording: Path = typer.Argument(..., help="Continuous Ferraris session (6 poses + 3 turns)."),
    sections: Path = typer.Option(..., help='imucal section list JSON: {"x_p": {"start": i0, "end": i1}, ...}.'),
    out: Path = _OUT,
    imucal_out: Optional[Path] = typer.Option(None, help="Also write the imucal FerrarisCalibrationInfo JSON, for the raw data in the units of the file (--accel-unit, --gyro-unit)."),
    gravity: float = typer.Option(9.81, help="Gravity used by the method (imucal default 9.81)."),
    expected_angle_deg: float = typer.Option(-360.0, help="Angle measured per turn (imucal default -360)."),
    report: Optional[Path] = _REP,
    px4_params: Optional[Path] = _PX4,
    fs: Optional[float] = _FS, accel_unit: Optional[str] = _AU, gyro_unit: Optional[str] = _GU,
    accel_scale: Optional[float] = _AS, gyro_scale: Optional[float] = _GS, skiprows: Optional[int] = _SK,
    columns: Optional[str] = _COL, topic: Optional[str] = TOPIC, instance: Optional[int] = INSTANCE,
    layout: Optional[str] = LAYOUT,
) -> None:
    """Ferraris six-pose + three-turn calibration (imucal-compatible).

    Example (imucal's session in the shared data): imunav calibrate ferraris ../shared/data/imucal/example_ferraris_session.csv --sections ../shared/data/imucal/example_ferraris_session_list.json --fs 102.4 --gyro-unit deg/s --out ferraris_cal.json --imucal-out ferraris_imucal.json
    """

    check_outputs([recording, sections], [out, px4_params, imucal_out], folders=[report])
    _check_report(report)


    data = _read(recording, fs, accel_unit, gyro_unit, accel_scale, gyro_scale, skiprows, columns, topic, instance,
                 layout)

    secs = read_json(sections, "imucal section list JSON")
    res = calib.ferraris_from_session(data.accel, data.gyro, secs, data.fs, gravity=gravity,
                                expected_angle_deg=expected_angle_deg)
    _finish(res, out, report, px4=px4_params)
    if imucal_out is not None:
        # for the raw data as the file holds them (imucal applies its calibration to those)
        info = res.calibration.to_imucal(from_acc_unit=accel_unit if accel_unit in ("m/s^2", "g") else None,
                                         from_gyr_unit=gyro_unit if gyro_unit in ("rad/s", "deg/s") else None)
        write_json(imucal_out, info)
        typer.echo(f"imucal FerrarisCalibrationInfo written to {imucal_out} (raw data in {info['from_acc_unit']} and "
                   f"{info['from_gyr_unit']}, calibrated in {info['acc_unit']} and {info['gyr_unit']})")


@app.command()
def multipose(
    recording: Path = typer.Argument(..., help="Multi-pose session: initial rest, then hand-placed static poses."),
    out: Path = _OUT,
    init_s: float = typer.Option(30.0, help="Initial rest period, s."),
    wait_s: float = typer.Option(3.0, help="Static detector window / time per pose, s."),
    gravity: float = typer.Option(9.80665, help="Local gravity magnitude, m/s^2."),
    strict: bool = typer.Option(True, help="Refuse sessions whose poses leave a misalignment undetermined."),
    accel_misalignment: bool = typer.Option(True, help="Estimate the accelerometer misalignments (else fix at 0)."),
    report: Optional[Path] = _REP,
    px4_params: Optional[Path] = _PX4,
    fs: Optional[float] = _FS, accel_unit: Optional[str] = _AU, gyro_unit: Optional[str] = _GU,
    accel_scale: Optional[float] = _AS, gyro_scale: Optional[float] = _GS, skiprows: Optional[int] = _SK,
    columns: Optional[str] = _COL, topic: Optional[str] = TOPIC, instance: Optional[int] = INSTANCE,
    layout: Optional[str] = LAYOUT, start: Optional[float] = START, end: Optional[float] = END,
) -> None:
    """Tedaldi et al. (2014) multi-pose calibration without a rate table.

    Example (the MPU-6050 session in the shared data): imunav calibrate multipose ../shared/data/mpu6050_tedaldi/example_data_calibration.csv --skiprows 4 --fs 100 --accel-unit counts --accel-scale 5.9855e-4 --gyro-unit counts --gyro-scale 1.3323e-4 --init-s 36.5 --no-accel-misalignment --out mpu_cal.json
    """

    check_outputs([recording], [out, px4_params], folders=[report])
    _check_report(report)

    data = window(_read(recording, fs, accel_unit, gyro_unit, accel_scale, gyro_scale, skiprows, columns, topic,
                        instance, layout), start, end)
    res = calib.multipose(data.accel, data.gyro, data.fs, init_s=init_s, wait_s=wait_s, gravity=gravity, strict=False,
                          accel_misalignment=accel_misalignment, raw_accel_unit="m/s^2", raw_gyro_unit="rad/s")
    if strict and res.info["weak_parameters"]:  # the library's refusal, naming this command's flags
        raise calib_multipose.undetermined_misalignment_error(
            res.info["n_poses"], res.info["weak_parameters"], res.info["max_misalignment_stderr"],
            no_accel_misalignment="--no-accel-misalignment", not_strict="--no-strict",
        )
    _finish(res, out, report, px4=px4_params)
    if res.info["weak_parameters"]:
        typer.echo("weakly determined: " + "; ".join(res.info["weak_parameters"]), err=True)


#: units of the parameters a thermal calibration models (SI, as the calibration JSON stores them)
_THERMAL_UNITS = {"accel_bias": "m/s^2", "gyro_bias": "rad/s", "accel_scale": "1 (scale factor)",
                  "gyro_scale": "1 (scale factor)"}


@app.command()
def temperature(
    calibrations: list[str] = typer.Argument(..., help="Calibration JSON files as FILE@TEMP_C (one per temperature)."),
    out: Path = _OUT,
    orders: str = typer.Option("1,2,3,4,5", help="Polynomial orders to try."),
    order: Optional[int] = typer.Option(None, help="Force this order (default: leave-one-out choice)."),
    model: str = typer.Option("poly", help="poly or piecewise (polynomial + one step)."),
    params: str = typer.Option("accel_bias,accel_scale,gyro_bias,gyro_scale", help="Parameters to model."),
    report: Optional[Path] = _REP,
) -> None:
    """Bias and scale factor as polynomials of temperature (order by leave-one-out CV).

    Example (the calibrations of the examples above standing for three temperatures): imunav calibrate temperature static_cal.json@-10 cal.json@25 static_cal.json@40 --orders 1 --params accel_bias --out thermal_cal.json
    """

    for item in calibrations:
        if "@" not in item:
            raise InvalidInputError(f"argument {item!r}: write each calibration as FILE@TEMP_C, e.g. cal.json@25")
    files = [c.rsplit("@", 1)[0] for c in calibrations]
    temps = [parse_numbers(f"argument {c}", c.rsplit("@", 1)[1], DOMAINS["--temp-c"], count=1,
                           example="cal.json@25")[0] for c in calibrations]
    order_list = parse_numbers("--orders", orders, DOMAINS["--order"], example="1,2,3")
    check_outputs(files, [out], folders=[report])
    _check_report(report)
    cals = [calib.ImuCalibration.load(f) for f in files]
    res = calib_temperature.thermal_calibration(
        temps, cals, params=[p.strip() for p in params.split(",")], orders=order_list,
        order=order, model=model,
    )
    res.calibration.save(out)
    tab = Table(title="temperature fits: MSE per order, in the parameter's unit squared (chosen order marked *)")
    tab.add_column("parameter")
    ords = [f.order for f in next(iter(res.fits.values()))[0].fits]
    for o in ords:
        tab.add_column(f"order {o}")
    for k, fits in res.fits.items():
        for i, f in enumerate(fits):
            tab.add_row(escape(f"{k}[{'xyz'[i]}] [{_THERMAL_UNITS.get(k, 'SI')}]"), *[f"{m.mse:.3g}" + ("*" if m.order == f.chosen_order else "") for m in f.fits])
    make_console().print(tab)
    if report is not None:
        report.mkdir(parents=True, exist_ok=True)
        write_json(report / "report.json", res.to_dict())
        for k, fits in res.fits.items():
            for i, f in enumerate(fits):
                fig = plot.plot_temperature_fit(f, f"{k} {'xyz'[i]}")
                unit = _THERMAL_UNITS.get(k, "SI")
                fig.axes[0].set_ylabel(f"{k} {'xyz'[i]}, {unit}")
                fig.axes[1].set_ylabel(f"residual, {unit}")
                plot.save_figure(fig, report / f"{k}_{'xyz'[i]}.png")
    typer.echo(f"calibration with temperature model written to {out}")


@app.command()
def mag(
    recording: Path = typer.Argument(..., help="Magnetometer samples: CSV/NPZ with mag_x, mag_y, mag_z (or mx..), "
                                     "or a ROS bag / PX4 ULog magnetometer topic (µT, FRD)."),
    out: Path = _OUT,
    method: str = typer.Option("ellipsoid", help="ellipsoid (Li & Griffiths), rotation-scale (thesis) or minmax."),
    field_norm: Optional[float] = typer.Option(None, help="Known field magnitude (data unit); default det(A) = 1."),
    min_coverage: float = typer.Option(0.3, help="Smallest accepted sphere coverage, 0-1 (ellipsoid and minmax)."),
    report: Optional[Path] = _REP,
    topic: Optional[str] = TOPIC, instance: Optional[int] = INSTANCE,
    px4_params: Optional[Path] = _PX4,
    mag_unit: Optional[str] = typer.Option(None, help="Unit of the magnetometer data (gauss, uT, nT, T), for "
                                           "--px4-params (PX4's offsets are gauss). Default: uT for a bag or "
                                           "ULog (their readers convert to uT), gauss for a table."),
) -> None:
    """Hard- and soft-iron magnetometer calibration: h_cal = A (h - b).

    Example (a distorted sphere of readings, µT, written first): python -c "import numpy as np; r =
    np.random.default_rng(0); u = r.normal(size=(1500, 3)); u /= np.linalg.norm(u, axis=1)[:, None];
    np.savetxt('mag.csv', 48 * u * [1.02, 0.94, 1.05] + [15.9, -3.7, 19.2] + r.normal(0, 0.1, u.shape),
    delimiter=',', header='mag_x,mag_y,mag_z', comments='')" && imunav calibrate mag mag.csv --out mag_cal.json
    --report mag_report --px4-params mag.params --mag-unit uT

    On a PX4 log, name the magnetometer: --topic sensor_mag --instance 0 (a flight alone seldom covers enough of the
    sphere: turn the vehicle by hand through every orientation while it logs).
    """

    check_outputs([recording], [out, px4_params], folders=[report])
    _check_report(report)



    h = _read_mag(recording, topic, instance)
    if method == "ellipsoid":
        cal = magnetometer.fit_ellipsoid(h, field_norm, min_coverage=min_coverage)
    elif method == "rotation-scale":
        cal = magnetometer.soft_iron_rotation_scale(h)
    elif method == "minmax":
        cal = magnetometer.fit_minmax(h, min_coverage=min_coverage)
    else:
        raise InvalidInputError(f"--method must be ellipsoid, rotation-scale or minmax, not {method!r}")
    if mag_unit is None:
        mag_unit = "uT" if logs.log_kind(recording) is not None else "gauss"
    px4_values = _px4(px4_params, mag=cal, mag_unit=mag_unit)
    write_json(out, cal.to_dict())
    if report is not None:
        report.mkdir(parents=True, exist_ok=True)
        write_json(report / "report.json", cal.to_dict())
        plot.save_figure(plot.plot_magnetometer(h, cal), report / "projections.png")
    make_console().print({"b": cal.b.round(6).tolist(), "field_norm": round(cal.field_norm, 6), "quality": cal.quality})
    typer.echo(f"magnetometer calibration written to {out}")
    _write_px4(px4_values, px4_params)


def _read_mag(path: Path, topic: Optional[str] = None, instance: Optional[int] = None) -> np.ndarray:
    p = Path(path)
    if p.exists() and logs.log_kind(p) is not None:
        if topic is None:
            raise InvalidInputError(f"{p}: name the magnetometer topic with --topic (`imunav info {p}` lists them)")
        d = logs.read_topic(p, topic, instance=instance)
        if "mag" not in d.values:
            raise InvalidInputError(f"{p}: topic {topic!r} is a {d.kind} topic, not a magnetometer")
        return np.asarray(d.values["mag"], float)
    if topic is not None or instance is not None:
        raise InvalidInputError(f"{p}: --topic / --instance apply to ROS bags and PX4 ULogs only")

    _common.check_nonempty(p)
    if p.suffix == ".npz":
        with _common.wrap_read_errors(str(p), "NPZ"), open(p, "rb") as fh, np.load(fh, allow_pickle=False) as z:
            for k in ("mag", "h", "m"):
                if k in z:
                    return np.asarray(z[k], float)
            names = list(z.files)
        raise FileFormatError(f"{p}: no 'mag' array (found {names})")

    df = pd.read_csv(p, comment="#")
    low = {c.lower().replace("_", ""): c for c in df.columns}
    for names in (("magx", "magy", "magz"), ("mx", "my", "mz"), ("hx", "hy", "hz")):
        if all(n in low for n in names):
            return df[[low[n] for n in names]].to_numpy(float)
    raise FileFormatError(f"{p}: needs columns mag_x, mag_y, mag_z (or mx, my, mz); found {list(df.columns)}")
