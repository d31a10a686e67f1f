"""``imunav compensate``: apply a calibration to a recording."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import numpy as np
import typer

from imunav.cli._lazy import lazy
from imunav.cli._options import END, START, window
from imunav.cli.calibrate import _read
from imunav.files import check_outputs

calib = lazy("imunav.calib")
io = lazy("imunav.io")


def register(root: typer.Typer) -> None:
    root.command(name="compensate")(compensate)


def compensate(
    recording: Path = typer.Argument(..., help="Raw recording (any read_imu format)."),
    cal: Path = typer.Option(..., "--cal", help="Calibration JSON (imunav or imucal Ferraris)."),
    out: Path = typer.Option(..., "--out", "-o", help="Compensated recording to write (format from suffix)."),
    fs: Optional[float] = typer.Option(None, help="Sampling rate, Hz (files without a time column)."),
    accel_unit: Optional[str] = typer.Option(None, help="Accelerometer unit in the file."),
    gyro_unit: Optional[str] = typer.Option(None, help="Gyro unit in the file."),
    temp_c: Optional[float] = typer.Option(None, help="Constant temperature, °C, when the file has none."),
    start: Optional[float] = START,
    end: Optional[float] = END,
    force: bool = typer.Option(False, "--force", help="Compensate even if the recording's provenance says it "
                               "was already compensated with this calibration."),
) -> None:
    """Compensate a recording with a calibration (accelerometer first, then gyro).

    The step (calibration hash and file, time) is recorded in the output's metadata (meta.provenance); a
    recording already compensated with the same calibration is refused unless --force, and one compensated
    with another calibration gets a warning.

    Example: imunav compensate static.npz --cal cal.json --out static_compensated.npz
    """

    check_outputs([recording, cal], [out])

    data = window(_read(recording, fs, accel_unit, gyro_unit, None, None, None, None), start, end)
    c = calib.ImuCalibration.load(cal)
    t = None if temp_c is None else np.full(data.n, temp_c)
    io.write_imu(c.apply(data, temp_c=t, force=force, source=str(cal)), out)
    typer.echo(f"compensated {data.n} samples -> {out}")
