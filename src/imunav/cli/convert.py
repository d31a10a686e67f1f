"""``imunav convert``: turn a recording (a ROS bag or PX4 ULog topic, a named CSV layout, any readable file)
into an imunav table once (Parquet, HDF5, CSV, MAT, NPZ)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from imunav.cli._lazy import lazy
from imunav.cli._options import END, INSTANCE, LAYOUT, MAG_TOPIC, START, TOPIC, reader_options, window
from imunav.files import check_outputs

io = lazy("imunav.io")

_EXAMPLE = (
    "Examples:\n\n"
    "  imunav convert ../shared/data/px4_ulog/sample.ulg sample.parquet --topic sensor_combined\n\n"
    "  imunav convert ../shared/data/ros_bags/jackal_test2.bag jackal_imu.h5 --topic /imu/data\n\n"
    "  imunav convert sample.parquet sample_window.csv --start 10 --end 40"
)


def convert(
    src: Path = typer.Argument(..., help="Input: ROS bag (.bag, ROS 2 folder, .db3, .mcap), PX4 .ulg, or any file "
                               "read_imu reads."),
    out: Path = typer.Argument(..., help="Output table: .parquet, .h5, .csv, .mat, .npz (format from the suffix)."),
    topic: Optional[str] = TOPIC,
    instance: Optional[int] = INSTANCE,
    mag_topic: Optional[str] = MAG_TOPIC,
    layout: Optional[str] = LAYOUT,
    start: Optional[float] = START,
    end: Optional[float] = END,
    format: Optional[str] = typer.Option(None, "--format", help="Output format (default: from OUT's suffix)."),
    nan_policy: str = typer.Option("raise", "--nan-policy", help="raise, drop or interpolate."),
) -> None:
    """Read one IMU (SI, FRD, magnetometer in µT) and write it as an imunav table, atomically.

    The output keeps the time axis (s since meta.t0_ns), the units and the reader's meta (topic,
    frame conversion, time report); OUT may not be SRC."""

    check_outputs([src], [out])
    data = window(io.read_imu(src, **reader_options(topic=topic, instance=instance, mag_topic=mag_topic,
                                                    layout=layout, nan_policy=nan_policy)), start, end)
    path = io.write_imu(data, out, format=format)
    typer.echo(f"{data.n} samples ({data.duration:.6g} s, {data.fs:.6g} Hz) written to {path}")


convert.__doc__ = (convert.__doc__ or "") + "\n\n" + _EXAMPLE


def register(app: typer.Typer) -> None:
    """Add ``imunav convert`` to the app."""
    app.command("convert", help=convert.__doc__)(convert)
