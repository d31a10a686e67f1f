"""Named CSV layouts: a column / unit mapping for :func:`imunav.io.csv.read_csv`, not a parser of their own.

========  ==========================================================  ===========================================
layout    columns (units)                                             frame
========  ==========================================================  ===========================================
euroc     ``#timestamp [ns], w_RS_S_x..z [rad s^-1],                  the sensor frame S as recorded (EuRoC's
          a_RS_S_x..z [m s^-2]`` (the header is a ``#`` line, so      ADIS16448 is mounted with x up): no
          columns are taken by position)                              conversion; specific force (+g up at rest)
tum-vi    the same as euroc (TUM-VI ``mav0/imu0/data.csv``)           sensor frame as recorded, no conversion
kalibr    ``timestamp`` (ns), ``omega_x..z`` (rad/s),                 sensor frame as recorded, no conversion
          ``alpha_x..z`` (m/s²): Kalibr's ``imu.csv``
px4-csv   ``timestamp`` (µs), ``gyro_rad[0..2]``,                     PX4 FRD: passes through
          ``accelerometer_m_s2[0..2]``, ``magnetometer_ga[0..2]``
          (gauss, when present): ``ulog2csv``'s sensor_combined
xio       x-io NGIMU / Gait-Tracking ``Time (s)``, ``Gyroscope X      z up → FRD by a 180° turn about x
          (deg/s)``, ``Accelerometer X (g)``                          (:func:`imunav.io.foot.read_xio_gait_csv`)
========  ==========================================================  ===========================================

Time stamps in integer nanoseconds since 1970 (EuRoC, TUM-VI, Kalibr: ~1.4e18) do not fit a float64
exactly; the CSV reader then subtracts the first stamp in integer arithmetic and keeps it in
``meta["t_origin_raw"]`` (in the file's time unit), so ``t`` starts at 0 with nanosecond resolution.
"""

from __future__ import annotations

import os
from typing import Any

from imunav.errors import InvalidInputError
from imunav.io._common import call_reader
from imunav.io.csv import read_csv
from imunav.io.foot import read_xio_gait_csv
from imunav.timeseries import ImuData
from imunav.units import unit_factor

__all__ = ["LAYOUTS", "layout_options", "read_layout"]

_EUROC = {
    "columns": {"t": 0, "gyro": [1, 2, 3], "accel": [4, 5, 6]},
    "units": {"t": "ns"},
    "frame": "sensor frame as recorded (no conversion)",
}
#: Layout name -> reader options (``columns``, ``units``, optional ``mag`` columns) and its frame.
LAYOUTS: dict[str, dict[str, Any]] = {
    "euroc": _EUROC,
    "tum-vi": _EUROC,
    "kalibr": {
        "columns": {"t": "timestamp", "gyro": ["omega_x", "omega_y", "omega_z"],
                    "accel": ["alpha_x", "alpha_y", "alpha_z"]},
        "units": {"t": "ns"},
        "frame": "sensor frame as recorded (no conversion)",
    },
    "px4-csv": {
        "columns": {"t": "timestamp", "gyro": [f"gyro_rad[{i}]" for i in range(3)],
                    "accel": [f"accelerometer_m_s2[{i}]" for i in range(3)]},
        "optional": {"mag": [f"magnetometer_ga[{i}]" for i in range(3)]},
        "units": {"t": "us"},
        "mag_unit": "gauss",
        "frame": "PX4 FRD (passes through)",
    },
    "xio": {"frame": "z up -> FRD: (x, -y, -z)"},
}


def _header(path: str | os.PathLike[str]) -> list[str]:
    with open(path, encoding="utf-8-sig", errors="replace") as fh:
        for line in fh:
            s = line.strip()
            if s and not s.startswith("#"):
                return [c.strip() for c in s.split(",")]
    return []


def layout_options(path: str | os.PathLike[str], layout: str) -> dict[str, Any]:
    """Reader options of ``layout`` for the file at ``path`` (optional columns only when its header has them).

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file (its header is read).
    layout : str
        One of :data:`LAYOUTS`.

    Returns
    -------
    dict
        ``columns``, ``units`` and further :func:`imunav.io.csv.read_csv` options.

    Raises
    ------
    InvalidInputError
        If the layout is unknown.
    """
    key = str(layout).lower().replace("_", "-")
    if key not in LAYOUTS or key == "xio":
        raise InvalidInputError(f"unknown CSV layout {layout!r}; choose one of {sorted(LAYOUTS)}")
    spec = LAYOUTS[key]
    cols = dict(spec["columns"])
    opt = spec.get("optional", {})
    if opt:
        head = _header(path)
        for group, names in opt.items():
            if all(n in head for n in names):
                cols[group] = list(names)
    out: dict[str, Any] = {"columns": cols, "units": dict(spec["units"]),
                           "meta": {"layout": key, "frame": spec["frame"]}}
    if "mag" in cols and "mag_unit" in spec:
        out["units"]["mag"] = spec["mag_unit"]
    return out


def read_layout(path: str | os.PathLike[str], layout: str, *, meta: dict[str, Any] | None = None, **options: Any) -> ImuData:
    """Read a CSV in a named layout (what ``read_imu(path, layout=...)`` calls).

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file.
    layout : str
        One of :data:`LAYOUTS`.
    meta : dict, optional
        Entries added to the result's ``meta``.
    **options
        Further :func:`imunav.io.csv.read_csv` options (``nan_policy``, ``skiprows`` ...); the
        layout's ``columns`` and ``units`` cannot be overridden (use plain ``read_imu`` for that).

    Returns
    -------
    ImuData
        The recording in SI units; the body frame per layout as in the module docstring's table (the
        sensor frame as recorded, or FRD for px4-csv and xio).

    Raises
    ------
    InvalidInputError
        If the layout is unknown, or ``options`` set what the layout fixes (``columns``, ``units``; any
        option for ``xio``).
    """

    key = str(layout).lower().replace("_", "-")
    if key == "xio":
        # nan_policy="raise" is what the x-io reader does anyway (the CLI always passes it)
        extra = sorted(k for k, v in options.items() if not (k == "nan_policy" and v == "raise"))
        if extra:
            raise InvalidInputError(f"layout 'xio' takes no reader options, got {extra}")
        d = read_xio_gait_csv(path).imu
        return d.with_(meta={**d.meta, "layout": "xio", **(meta or {})})
    opts = layout_options(path, key)
    clash = sorted(set(options) & {"columns", "units"})
    if clash:
        raise InvalidInputError(f"layout={layout!r} sets {clash}; drop them, or read without a layout")
    opts["meta"].update(meta or {})
    d = call_reader(read_csv, f"read_imu(layout={layout!r})", path, **opts, **options)
    if d.mag is not None and d.mag_unit != "uT":
        # gauss (PX4) -> µT, imunav's magnetometer unit, at the edge
        f = unit_factor(d.mag_unit, "magnetic_field") / unit_factor("uT", "magnetic_field")
        d = d.with_(mag=d.mag * f, mag_unit="uT")
    return d
