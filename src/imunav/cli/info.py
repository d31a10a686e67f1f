"""``imunav info``: what is in a recording (rate, gaps, saturation, static intervals)."""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import typer
from rich.table import Table

from imunav.cli._console import make_console
from imunav.cli._lazy import lazy
from imunav.cli._options import END, INSTANCE, LAYOUT, MAG_TOPIC, START, TOPIC, reader_options, window
from imunav.errors import FileFormatError, InvalidInputError
from imunav.files import check_outputs, write_json
from imunav.units import DEG, G0

io = lazy("imunav.io")
logs = lazy("imunav.io.logs")
timeseries = lazy("imunav.timeseries")

_EXAMPLE = (
    "Example:\n\n"
    "  python -c \"import numpy as np; from imunav.io import write_imu; from imunav.timeseries import ImuData; "
    "r = np.random.default_rng(0); write_imu(ImuData.from_arrays(None, r.normal(0, 0.1, (3000, 3)), "
    "r.normal([0, 0, -1], 0.01, (3000, 3)), fs=100, gyro_unit='deg/s', accel_unit='g'), 'rec.csv')\"\n\n"
    "  imunav info rec.csv --json info.json\n\n"
    "  imunav info ../shared/data/mpu6050_tedaldi/example_data_calibration.csv --skiprows 4 --fs 100 "
    "--gyro-unit counts --gyro-scale 1.3323e-4 --accel-unit counts --accel-scale 5.9855e-4 --gyro-full-scale-dps 250\n\n"
    "  imunav info ../shared/data/px4_ulog/sample.ulg                         # topics, counts, rates (index only)\n\n"
    "  imunav info ../shared/data/px4_ulog/sample.ulg --topic sensor_combined  # one topic: gaps, jitter, ..."
)


def _parse_columns(items: list[str]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for it in items:
        if "=" not in it:
            raise InvalidInputError(f"--column expects KEY=NAME (e.g. gx=GyroX), got {it!r}")
        k, v = it.split("=", 1)
        out[k.strip()] = int(v) if v.strip().isdigit() else v.strip()
    return out


def info(
    file: Path = typer.Argument(..., help="Recording: .csv/.txt, .parquet, .h5, .mat (v5 or v7.3), .npz; ROS bag "
                                "(.bag, ROS 2 folder, .db3, .mcap) or PX4 .ulg."),
    format: str | None = typer.Option(None, "--format", help="csv, parquet, hdf5, mat, npz, rosbag, ulog (default: from "
                                      "the suffix / content)."),
    topic: str | None = TOPIC,
    instance: int | None = INSTANCE,
    mag_topic: str | None = MAG_TOPIC,
    layout: str | None = LAYOUT,
    start: float | None = START,
    end: float | None = END,
    json_out: Path | None = typer.Option(None, "--json", help="Also write the summary as JSON to this file."),
    window_s: float = typer.Option(1.0, "--window", help="Static detector window (s)."),
    min_static_s: float | None = typer.Option(None, "--min-static", help="Shortest static interval kept (s); default = window."),
    gyro_fs_dps: float | None = typer.Option(None, "--gyro-full-scale-dps", help="Gyro range (°/s) for saturation."),
    accel_fs_g: float | None = typer.Option(None, "--accel-full-scale-g", help="Accelerometer range (g) for saturation."),
    fs: float | None = typer.Option(None, "--fs", help="Sampling rate (Hz) when the file has no time column."),
    time_unit: str | None = typer.Option(None, "--time-unit", help="Unit of the time column (s, ms, us, ns)."),
    gyro_unit: str | None = typer.Option(None, "--gyro-unit", help="rad/s, deg/s, rpm or counts."),
    accel_unit: str | None = typer.Option(None, "--accel-unit", help="m/s^2, g, mg or counts."),
    gyro_scale: float | None = typer.Option(None, "--gyro-scale", help="rad/s per count (with --gyro-unit counts)."),
    accel_scale: float | None = typer.Option(None, "--accel-scale", help="m/s² per count (with --accel-unit counts)."),
    skiprows: int | None = typer.Option(None, "--skiprows", help="CSV: lines to skip before the header."),
    column: list[str] = typer.Option([], "--column", help="Column mapping KEY=NAME, repeatable (keys t gx gy gz ax ay az mx my mz temp)."),
    nan_policy: str = typer.Option("raise", "--nan-policy", help="raise, drop or interpolate."),
    max_rows: int = typer.Option(10, "--max-rows", help="Rows shown per table of gaps / static intervals."),
) -> None:
    """Rate, duration, gaps, saturation, static intervals and per-channel mean/std of a recording.

    On a ROS bag or PX4 ULog without --topic: the topics (instances) with type, count, rate and
    duration, from the index, without reading the messages; with --topic: that IMU as above, plus
    the jitter, drops and out-of-order stamps of its messages."""

    console = make_console()
    check_outputs([file], [json_out])
    if not (math.isfinite(window_s) and window_s > 0):
        raise InvalidInputError(f"--window {window_s}: the static-detector window must be a finite number of seconds > 0")
    if min_static_s is not None and not (math.isfinite(min_static_s) and min_static_s > 0):
        raise InvalidInputError(f"--min-static {min_static_s}: must be a finite number of seconds > 0")

    if topic is None and format in (None, "rosbag", "ulog") and file.exists() and logs.log_kind(file) is not None:
        _list_topics(console, file, json_out)
        return
    opts = reader_options(
        units={k: v for k, v in (("t", time_unit), ("gyro", gyro_unit), ("accel", accel_unit)) if v},
        scales={k: v for k, v in (("gyro", gyro_scale), ("accel", accel_scale)) if v is not None},
        fs=fs, skiprows=skiprows, columns=_parse_columns(column) if column else None, nan_policy=nan_policy,
        topic=topic, instance=instance, mag_topic=mag_topic, layout=layout,
    )
    data = window(io.read_imu(file, format=format, **opts), start, end)
    s = timeseries.describe(
        data,
        window_s=window_s,
        min_duration_s=min_static_s,
        gyro_full_scale=None if gyro_fs_dps is None else gyro_fs_dps * DEG,
        accel_full_scale=None if accel_fs_g is None else accel_fs_g * G0,
    )

    d = s.to_dict()
    head = Table(title=f"{file}", show_header=False, title_justify="left")
    head.add_column("", style="bold")
    head.add_column("")
    head.add_row("samples", f"{s.n:,}")
    head.add_row("duration", f"{s.duration_s:.6g} s")
    head.add_row("rate", f"{s.fs_hz:.6g} Hz (dt {s.dt_min_s:.4g} … {s.dt_max_s:.4g} s, std {s.dt_std_s:.3g} s)")
    head.add_row("gaps (dt > 1.5× median)", f"{len(s.gaps)} ({d['missing_samples']} missing samples)")
    sat = s.saturation
    sat_txt = ", ".join(f"{k} {v}" for k, v in sat.counts.items() if v) or "none"
    head.add_row(f"saturation ({sat.method})", sat_txt)
    if s.static is None:
        head.add_row("static intervals", f"not computed (record shorter than the {window_s} s window)")
    else:
        tot = float(s.static.mask.sum()) / s.fs_hz
        head.add_row("static intervals", f"{len(s.static)} ({tot:.4g} s in all, window {s.static.window} samples)")
    if s.mag_unit:
        head.add_row("magnetometer unit", s.mag_unit)
    tq = s.meta.get("time") if isinstance(s.meta.get("time"), dict) else None
    if tq is not None and "dt_median_s" in tq:  # a bag / log topic: its message timing
        head.add_row("messages: jitter", f"std {tq['jitter_std_s']:.3g} s, worst {tq['jitter_max_s']:.3g} s from the "
                     f"median {tq['dt_median_s']:.6g} s")
        head.add_row("messages: drops", f"{tq['gaps']} gap(s), about {tq['missing_estimate']} message(s) missing")
        head.add_row("messages: out of order", f"{tq['out_of_order']}" + (" (sorted by stamp)" if tq["out_of_order"] else ""))
    for k, v in s.meta.items():
        head.add_row(f"meta.{k}", str(v)[:80])
    console.print(head)

    ch = Table(title="channels", title_justify="left")
    for c, j in (("channel", "left"), ("unit", "left"), ("mean", "right"), ("std", "right"), ("min", "right"), ("max", "right")):
        ch.add_column(c, justify=j)  # type: ignore[arg-type]
    for row in s.channels:
        ch.add_row(row["channel"], row["unit"], *(f"{row[k]:.6g}" for k in ("mean", "std", "min", "max")))
    console.print(ch)

    if s.static is not None and len(s.static):
        st = Table(title="static intervals", title_justify="left")
        for c in ("#", "start", "stop", "t_start (s)", "duration (s)"):
            st.add_column(c, justify="right")
        for k, (a, b) in enumerate(s.static):
            if k >= max_rows:
                st.add_row("…", "", "", "", f"{len(s.static) - max_rows} more")
                break
            st.add_row(str(k), str(a), str(b), f"{s.static.t_start[k]:.6g}", f"{(b - a) / s.fs_hz:.4g}")
        console.print(st)
    if s.gaps:
        gt = Table(title="gaps", title_justify="left")
        for c in ("after row", "t (s)", "length (s)", "missing samples"):
            gt.add_column(c, justify="right")
        for k, g in enumerate(s.gaps):
            if k >= max_rows:
                gt.add_row("…", "", "", f"{len(s.gaps) - max_rows} more")
                break
            gt.add_row(str(g.index), f"{g.t_start:.6g}", f"{g.length_s:.4g}", str(g.missing_samples))
        console.print(gt)

    if json_out is not None:
        write_json(json_out, d)
        console.print(f"summary written to {json_out}")


def _list_topics(console: Any, file: Path, json_out: Path | None) -> None:
    """The topics of a bag / ULog as a table (and JSON), with the time the listing took."""

    t0 = time.perf_counter()
    topics = logs.list_topics(file)
    if not topics:
        raise FileFormatError(f"{file}: the log holds no topic (no message of any sensor: only a header, or "
                              "the recording was cut off); nothing to read")
    took = time.perf_counter() - t0
    ulog = all(ti.instance is not None for ti in topics)  # a ULog: the type is the topic name
    tab = Table(title=f"{file}: {len(topics)} topics (listed in {took:.2f} s)", title_justify="left")
    cols = [("topic", "left"), ("instance" if ulog else "type", "right" if ulog else "left"), ("reads as", "left"),
            ("count", "right"), ("rate (Hz)", "right"), ("duration (s)", "right")]
    for c, j in cols:
        tab.add_column(c, justify=j, no_wrap=c in ("topic", "type"))  # type: ignore[arg-type]
    for ti in topics:
        tab.add_row(ti.topic, str(ti.instance) if ulog else ti.msgtype, ti.kind or "",
                    f"{ti.count:,}", "" if ti.rate_hz is None else f"{ti.rate_hz:.6g}",
                    "" if ti.duration_s is None else f"{ti.duration_s:.6g}")
    console.print(tab)
    console.print("choose one with --topic (and --instance for a PX4 topic with several instances)")
    if json_out is not None:
        write_json(json_out, {"file": str(file), "list_time_s": took, "topics": [ti.to_dict() for ti in topics]})
        console.print(f"summary written to {json_out}")


info.__doc__ = (info.__doc__ or "") + "\n\n" + _EXAMPLE


def register(app: typer.Typer) -> None:
    """Add ``imunav info`` to the app."""
    app.command("info", help=info.__doc__)(info)
