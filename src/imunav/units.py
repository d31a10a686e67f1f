"""Units: SI inside, conversions at the edges, IEEE-952 display units.

Inside imunav every quantity is SI (s, m, m/s, m/s^2, rad, rad/s, degC).
This module converts recordings declared in other units to SI
(:func:`to_si`) and SI noise parameters to the display units in which
datasheets and IEEE Std 952-1997 quote them (:func:`to_display`).

Display units (with x = value in SI):

========================  ============================  =================================
term                      SI unit                       display unit
========================  ============================  =================================
angle random walk N       rad/s/sqrt(Hz)=rad/sqrt(s)    deg/sqrt(h)  (x*180/pi*60)
gyro bias instability B   rad/s                         deg/h        (x*180/pi*3600)
rate random walk K        rad/s/sqrt(s)                 deg/h/sqrt(h) (x*180/pi*3600*60)
rate ramp R               rad/s^2                       deg/h^2      (x*180/pi*3600^2)
velocity random walk N    m/s/sqrt(s)                   m/s/sqrt(h)  (x*60)
accel bias instability B  m/s^2                         ug           (x/g0*1e6)
accel random walk K       m/s^2/sqrt(s)                 m/s/h/sqrt(h) (x*3600*60)
noise density             unit/sqrt(Hz)                 ug/sqrt(Hz), deg/s/sqrt(Hz)
scale factor              1 (ratio)                     ppm          (x*1e6)
misalignment              rad                           mrad         (x*1e3)
========================  ============================  =================================
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import UnitError

__all__ = [
    "DEFAULT_GRAVITY",
    "G0",
    "DEG",
    "ARCSEC",
    "HOUR",
    "DISPLAY_UNITS",
    "deg2rad",
    "rad2deg",
    "to_si",
    "from_si",
    "to_display",
    "from_display",
    "unit_factor",
    "normalize_unit",
]

#: Standard gravity, m/s^2 (CGPM 1901; used for g <-> m/s^2 conversions only,
#: not as a model of local gravity -- see :mod:`imunav.earth`).
G0: Final[float] = 9.80665
#: The gravity magnitude every filter configuration and simulation assumes when none is given, m/s^2 (a rounded
#: mid-latitude value: normal gravity runs from 9.780 at the equator to 9.832 at the poles, and
#: :func:`imunav.earth.normal_gravity` gives the local one).  A method that needs another value for compatibility
#: names it explicitly (the ZUPT INS: pyshoe's :data:`imunav.ins.zupt.statistics.G_PYSHOE`).
DEFAULT_GRAVITY: Final[float] = 9.81
#: One degree in radians.
DEG: Final[float] = math.pi / 180.0
#: One arc second in radians.
ARCSEC: Final[float] = DEG / 3600.0
#: One hour in seconds.
HOUR: Final[float] = 3600.0


def deg2rad(x: ArrayLike) -> NDArray[np.float64]:
    """Degrees to radians, ``x * pi / 180``.

    Parameters
    ----------
    x : array_like
        Angle(s) or angular rate(s) in degrees (or deg/s).

    Returns
    -------
    numpy.ndarray
        The same values in radians (or rad/s), float64, same shape as ``x``.
    """
    return np.asarray(x, dtype=float) * DEG


def rad2deg(x: ArrayLike) -> NDArray[np.float64]:
    """Radians to degrees, ``x * 180 / pi``.

    Parameters
    ----------
    x : array_like
        Angle(s) or angular rate(s) in radians (or rad/s).

    Returns
    -------
    numpy.ndarray
        The same values in degrees (or deg/s), float64, same shape as ``x``.
    """
    return np.asarray(x, dtype=float) / DEG


# --- quantity units at the edge --------------------------------------------
# Each quantity maps accepted spellings (lower case, spaces removed) to the
# factor that multiplies a value to give SI.
_ALIASES: dict[str, dict[str, float]] = {
    "angular_rate": {
        "rad/s": 1.0,
        "deg/s": DEG,
        "dps": DEG,
        "°/s": DEG,
        "deg/h": DEG / HOUR,
        "°/h": DEG / HOUR,
        "rpm": 2.0 * math.pi / 60.0,
        "mrad/s": 1e-3,
    },
    "acceleration": {
        "m/s^2": 1.0,
        "m/s2": 1.0,
        "m/s**2": 1.0,
        "g": G0,
        "mg": G0 * 1e-3,
        "ug": G0 * 1e-6,
        "µg": G0 * 1e-6,
        "ft/s^2": 0.3048,
        "ft/s2": 0.3048,
    },
    "angle": {"rad": 1.0, "deg": DEG, "°": DEG, "mrad": 1e-3, "arcsec": ARCSEC, "arcmin": DEG / 60},
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "ns": 1e-9, "min": 60.0, "h": HOUR},
    "temperature": {"degc": 1.0, "°c": 1.0, "c": 1.0},
    "velocity": {"m/s": 1.0, "km/h": 1 / 3.6, "kn": 1852.0 / 3600.0, "kt": 1852.0 / 3600.0, "ft/s": 0.3048},
    "length": {"m": 1.0, "km": 1e3, "ft": 0.3048, "nmi": 1852.0, "cm": 1e-2, "mm": 1e-3},
    "pressure": {"pa": 1.0, "hpa": 100.0, "mbar": 100.0, "kpa": 1e3, "inhg": 3386.389, "bar": 1e5},
    # Magnetic field is kept in the user's unit; these allow explicit conversion.
    "magnetic_field": {"t": 1.0, "ut": 1e-6, "µt": 1e-6, "nt": 1e-9, "gauss": 1e-4, "g": 1e-4, "mgauss": 1e-7},
}

_QUANTITY_ALIASES = {
    "gyro": "angular_rate",
    "rate": "angular_rate",
    "accel": "acceleration",
    "acc": "acceleration",
    "temp": "temperature",
    "mag": "magnetic_field",
}


def _quantity(quantity: str) -> str:
    q = _QUANTITY_ALIASES.get(quantity, quantity)
    if q not in _ALIASES:
        raise UnitError(
            f"unknown quantity {quantity!r}; known quantities: {sorted(_ALIASES)} "
            f"(or the short names {sorted(_QUANTITY_ALIASES)})"
        )
    return q


def normalize_unit(unit: str) -> str:
    """Canonical spelling of a unit string (lower case, no spaces, ``sec`` -> ``s``).

    Parameters
    ----------
    unit : str
        A unit as a user writes it, e.g. ``"Deg / Sec"``.

    Returns
    -------
    str
        The spelling used as a key of the unit tables, e.g. ``"deg/s"``.
    """
    return unit.strip().lower().replace(" ", "").replace("sec", "s")


def unit_factor(unit: str, quantity: str) -> float:
    """Factor f such that ``value_si = f * value_in_unit``.

    Parameters
    ----------
    unit : str
        Unit of the values, e.g. ``"deg/s"``, ``"g"``, ``"hPa"`` (case and spaces do not matter).
    quantity : str
        The physical quantity: ``"angular_rate"`` (``"gyro"``), ``"acceleration"`` (``"accel"``), ``"angle"``,
        ``"time"``, ``"temperature"``, ``"velocity"``, ``"length"``, ``"pressure"``, ``"magnetic_field"``
        (``"mag"``).

    Returns
    -------
    float
        The multiplicative factor to SI (s, m, m/s, m/s^2, rad, rad/s, degC, Pa, T).  Standard gravity for
        ``g`` is :data:`G0` = 9.80665 m/s^2 (CGPM 1901; BIPM, *The International System of Units*, 9th ed.,
        2019).

    Raises
    ------
    UnitError
        If the quantity is unknown, or the unit is unknown for that quantity; the message lists the
        accepted spellings.
    """
    q = _quantity(quantity)
    u = normalize_unit(unit)
    table = _ALIASES[q]
    if u not in table:
        raise UnitError(
            f"unknown unit {unit!r} for {q}; accepted: {sorted(table)}. "
            "For raw sensor counts use unit='counts' with scale=<SI units per count>."
        )
    return table[u]


def to_si(
    values: ArrayLike,
    unit: str,
    quantity: str,
    *,
    scale: float | None = None,
    offset: float = 0.0,
) -> NDArray[np.float64]:
    """Convert values declared in ``unit`` to SI.

    ``value_si = f * value`` with ``f`` from :func:`unit_factor`; for raw counts
    ``value_si = (counts - offset) * scale``.

    Parameters
    ----------
    values : array_like
        Values in ``unit``.
    unit : str
        Unit of ``values`` (``"deg/s"``, ``"g"``, ...), or ``"counts"`` for raw
        sensor counts, in which case ``scale`` (SI units per count) is needed.
    quantity : str
        ``"angular_rate"``/``"gyro"``, ``"acceleration"``/``"accel"``,
        ``"angle"``, ``"time"``, ``"temperature"``, ``"velocity"``,
        ``"length"``, ``"pressure"``, ``"magnetic_field"``.
    scale : float, optional
        SI units per count for ``unit="counts"``.
    offset : float
        Subtracted from counts before scaling (``unit="counts"`` only), in counts.

    Returns
    -------
    numpy.ndarray
        The values in SI units, float64, same shape as ``values``.

    Raises
    ------
    UnitError
        If the unit or quantity is unknown, if counts come without a finite non-zero ``scale``, or if
        ``scale`` is given with a unit other than counts.
    """
    x = np.asarray(values, dtype=float)
    if normalize_unit(unit) in ("counts", "count", "lsb", "raw"):
        if scale is None or not np.isfinite(scale) or scale == 0:
            raise UnitError(
                f"{quantity} declared in raw counts needs a finite, non-zero scale "
                "(SI units per count), e.g. scale=9.80665/16384 for a +-2 g 16-bit accelerometer"
            )
        return (x - offset) * float(scale)
    if scale is not None:
        raise UnitError(f"scale is only used with unit='counts', not with unit={unit!r}")
    return x * unit_factor(unit, quantity)


def from_si(values: ArrayLike, unit: str, quantity: str) -> NDArray[np.float64]:
    """Convert SI values to ``unit``: the inverse of :func:`to_si` (no counts), ``value = value_si / f``.

    Parameters
    ----------
    values : array_like
        Values in SI units.
    unit : str
        Target unit, e.g. ``"deg/s"``.
    quantity : str
        The physical quantity (see :func:`unit_factor`).

    Returns
    -------
    numpy.ndarray
        The values in ``unit``, float64, same shape as ``values``.

    Raises
    ------
    UnitError
        If the unit or quantity is unknown.
    """
    return np.asarray(values, dtype=float) / unit_factor(unit, quantity)


# --- IEEE-952 display units --------------------------------------------------
#: display-unit name -> factor from SI (display = factor * si)
DISPLAY_UNITS: dict[str, float] = {
    "deg/sqrt(h)": (1 / DEG) * 60.0,  # ARW: rad/sqrt(s) -> deg/sqrt(h)
    "deg/h": (1 / DEG) * HOUR,  # gyro bias (instability)
    "deg/s": 1 / DEG,
    "deg/h/sqrt(h)": (1 / DEG) * HOUR * 60.0,  # RRW: rad/s/sqrt(s) -> deg/h/sqrt(h)
    "deg/h^2": (1 / DEG) * HOUR**2,  # rate ramp: rad/s^2 -> deg/h^2
    "deg/s/sqrt(hz)": 1 / DEG,
    "deg/h/sqrt(hz)": (1 / DEG) * HOUR,
    "m/s/sqrt(h)": 60.0,  # VRW: m/s/sqrt(s) -> m/s/sqrt(h)
    "m/s/h/sqrt(h)": HOUR * 60.0,  # accel random walk
    "m/s^2/sqrt(hz)": 1.0,
    "ug": 1e6 / G0,
    "mg": 1e3 / G0,
    "ug/sqrt(hz)": 1e6 / G0,
    "mg/sqrt(hz)": 1e3 / G0,
    "ppm": 1e6,
    "mrad": 1e3,
    "urad": 1e6,
    "arcsec": 1 / ARCSEC,
    "deg": 1 / DEG,
    "(deg/h)/g": (1 / DEG) * HOUR * G0,  # g-sensitivity: rad/s per m/s^2
    "(deg/s)/g": (1 / DEG) * G0,
}


def _display_key(unit: str) -> str:
    u = unit.strip().lower().replace(" ", "").replace("°", "deg").replace("√", "sqrt").replace("µ", "u")
    u = u.replace("sqrt(hr)", "sqrt(h)").replace("/hr", "/h").replace("²", "^2")
    if u not in DISPLAY_UNITS:
        raise UnitError(f"unknown display unit {unit!r}; known: {sorted(DISPLAY_UNITS)}")
    return u


def to_display(x_si: ArrayLike, unit: str) -> NDArray[np.float64] | float:
    """Convert an SI value to a display unit, e.g. ARW rad/sqrt(s) -> deg/sqrt(h).

    ``display = factor * x_si`` with the factors of :data:`DISPLAY_UNITS` (the table in the module
    docstring), the units in which IEEE Std 952-1997 (Annex C) and datasheets quote noise terms.

    Parameters
    ----------
    x_si : array_like
        Value(s) in SI units (rad/sqrt(s), rad/s, m/s/sqrt(s), ratio, rad, ...).
    unit : str
        Display unit, a key of :data:`DISPLAY_UNITS` (``°``, ``√``, ``µ``, ``hr`` and ``²`` are accepted as
        spellings of ``deg``, ``sqrt``, ``u``, ``h`` and ``^2``).

    Returns
    -------
    float or numpy.ndarray
        The value(s) in the display unit: a float for a scalar input.

    Raises
    ------
    UnitError
        If the display unit is unknown; the message lists the known ones.

    Examples
    --------
    >>> round(float(to_display(1e-3, "deg/sqrt(h)")), 6)   # 1 mrad/sqrt(s)
    3.437747
    """
    out = np.asarray(x_si, dtype=float) * DISPLAY_UNITS[_display_key(unit)]
    return float(out) if out.ndim == 0 else out


def from_display(x: ArrayLike, unit: str) -> NDArray[np.float64] | float:
    """Convert a display-unit value to SI: the inverse of :func:`to_display`, ``x_si = x / factor``.

    Parameters
    ----------
    x : array_like
        Value(s) in the display unit.
    unit : str
        Display unit, a key of :data:`DISPLAY_UNITS`.

    Returns
    -------
    float or numpy.ndarray
        The value(s) in SI units: a float for a scalar input.

    Raises
    ------
    UnitError
        If the display unit is unknown.
    """
    out = np.asarray(x, dtype=float) / DISPLAY_UNITS[_display_key(unit)]
    return float(out) if out.ndim == 0 else out
