"""Names, display units and spec matching of the parameters that reports check.

Every estimated parameter that a lab step or a batch run can check against a
datasheet-style ``[spec]`` has a flat name ``<sensor>_<quantity>_<axis>``:

=============================  ==========================  ===============
name (x, y, z / xy, xz, ...)   meaning                     display unit
=============================  ==========================  ===============
``accel_bias_x``               accelerometer bias          mg
``accel_scale_x``              scale-factor error S        ppm
``accel_misalignment_xy``      misalignment M_xy           mrad
``gyro_bias_x``                gyro bias                   deg/h
``gyro_scale_x``               scale-factor error S        ppm
``gyro_misalignment_xy``       misalignment M_xy           mrad
``gyro_g_sensitivity_x``       g-sensitivity (diagonal)    (deg/h)/g
``gyro_arw_x``                 angle random walk N         deg/sqrt(h)
``gyro_bias_instability_x``    bias instability B          deg/h
``gyro_rrw_x``                 rate random walk K          deg/h/sqrt(h)
``accel_vrw_x``                velocity random walk N      m/s/sqrt(h)
``accel_bias_instability_x``   bias instability B          ug
``accel_rrw_x``                acceleration random walk K  m/s/h/sqrt(h)
=============================  ==========================  ===============

A spec entry named without the axis (``[spec.gyro_bias]``) applies to every
axis (``gyro_bias_x``, ``gyro_bias_y``, ``gyro_bias_z``); an entry with the
axis applies to that one only and wins over the axis-less one.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any

import numpy as np

from imunav.lab.report.spec import SpecLimit
from imunav.units import to_display

__all__ = ["DISPLAY_UNIT", "display_unit", "to_display_value", "calibration_estimates", "noise_estimates",
           "expand_spec", "base_name"]

#: Display unit of each parameter family (name without the axis suffix).
DISPLAY_UNIT: dict[str, str] = {
    "accel_bias": "mg",
    "accel_scale": "ppm",
    "accel_misalignment": "mrad",
    "gyro_bias": "deg/h",
    "gyro_scale": "ppm",
    "gyro_misalignment": "mrad",
    "gyro_g_sensitivity": "(deg/h)/g",
    "gyro_arw": "deg/sqrt(h)",
    "gyro_bias_instability": "deg/h",
    "gyro_rrw": "deg/h/sqrt(h)",
    "accel_vrw": "m/s/sqrt(h)",
    "accel_bias_instability": "ug",
    "accel_rrw": "m/s/h/sqrt(h)",
}

_AXIS = re.compile(r"_(x|y|z|xy|xz|yx|yz|zx|zy)$")
_OFF = ("xy", "xz", "yx", "yz", "zx", "zy")


def base_name(name: str) -> str:
    """``gyro_bias_x`` -> ``gyro_bias`` (names without an axis are returned as they are).

    Parameters
    ----------
    name : str
        A parameter name.

    Returns
    -------
    str
        The name without its axis suffix.
    """
    return _AXIS.sub("", name)


def display_unit(name: str) -> str:
    """Display unit of a parameter name ('' when unknown: shown in SI).

    Parameters
    ----------
    name : str
        A parameter name, with or without axis.

    Returns
    -------
    str
        The display unit of the table in the module docstring.
    """
    return DISPLAY_UNIT.get(base_name(name), "")


def to_display_value(name: str, value_si: float | None) -> float | None:
    """SI value -> display unit of ``name`` (None stays None).

    Parameters
    ----------
    name : str
        A parameter name.
    value_si : float or None
        The value in SI.

    Returns
    -------
    float or None
        The value in :func:`display_unit` of ``name`` (unchanged when the unit is unknown).
    """
    if value_si is None or not np.isfinite(value_si):
        return value_si
    u = display_unit(name)
    return float(to_display(value_si, u)) if u else float(value_si)


def calibration_estimates(calibration: Any, stderr: Mapping[str, Any] | None = None) -> dict[str, tuple[float, float | None]]:
    """Flat ``{name: (value_si, sigma_si)}`` of an :class:`imunav.calib.ImuCalibration`.

    ``stderr`` uses the keys of :class:`imunav.calib.CalibrationResult`
    (``accel_bias``, ``accel_matrix``, ``gyro_bias``, ``gyro_matrix``,
    ``g_sensitivity``); parameters without a standard error (not estimated
    by the method) are left out.

    Parameters
    ----------
    calibration : ImuCalibration
        The calibration (SI raw units).
    stderr : mapping, optional
        Standard errors (default: ``calibration.stderr``).

    Returns
    -------
    dict of str to (float, float or None)
        ``{name: (value_si, sigma_si)}`` (scale errors and misalignments dimensionless, biases in m/s² and
        rad/s, g-sensitivity in rad/s per m/s²).
    """
    se = dict(stderr if stderr is not None else getattr(calibration, "stderr", {}) or {})
    out: dict[str, tuple[float, float | None]] = {}
    for s, T, B in (("accel", calibration.accel_matrix, calibration.accel_bias),
                    ("gyro", calibration.gyro_matrix, calibration.gyro_bias)):
        T = np.asarray(T, float)
        sb = se.get(f"{s}_bias")
        sT = se.get(f"{s}_matrix")
        for i, a in enumerate("xyz"):
            if sb is not None:
                out[f"{s}_bias_{a}"] = (float(B[i]), float(np.asarray(sb)[i]))
        if sT is not None:
            sT = np.asarray(sT, float)
            for i, a in enumerate("xyz"):
                out[f"{s}_scale_{a}"] = (float(T[i, i] - 1.0), float(sT[i, i]))
            for ab in _OFF:
                i, j = "xyz".index(ab[0]), "xyz".index(ab[1])
                out[f"{s}_misalignment_{ab}"] = (float(T[i, j]), float(sT[i, j]))
    sg = se.get("g_sensitivity")
    if sg is not None:
        G = np.asarray(calibration.g_sensitivity, float)
        for i, a in enumerate("xyz"):
            out[f"gyro_g_sensitivity_{a}"] = (float(G[i, i]), float(np.asarray(sg)[i, i]))
    return out


_NOISE_NAMES = {"gyro": {"N": "arw", "B": "bias_instability", "K": "rrw"},
                "accel": {"N": "vrw", "B": "bias_instability", "K": "rrw"}}


def noise_estimates(fit: Any, sensor: str) -> dict[str, tuple[float, float | None]]:
    """Flat ``{name: (value_si, sigma_si)}`` of an :class:`imunav.noise.NoiseFit` of one triad.

    Only the terms the fit selected are returned (a term set to zero by the
    term selection has no estimate).

    Parameters
    ----------
    fit : NoiseFit
        Noise terms of one triad (:func:`imunav.noise.fit_noise`).
    sensor : {"gyro", "accel"}
        The triad.

    Returns
    -------
    dict of str to (float, float or None)
        ``{name: (value_si, sigma_si)}`` for ARW / VRW, bias instability and rate / acceleration random walk.
    """
    out: dict[str, tuple[float, float | None]] = {}
    chans = list(fit.channels)
    for term, label in _NOISE_NAMES[sensor].items():
        if term not in fit.names:
            continue
        i = fit.names.index(term)
        for c, ch in enumerate(chans):
            if not bool(fit.selected[i, c]):
                continue
            axis = "xyz"[c] if len(chans) == 3 else str(ch)
            se = float(fit.se[i, c])
            out[f"{sensor}_{label}_{axis}"] = (float(fit.value[i, c]), se if np.isfinite(se) else None)
    return out


def expand_spec(spec: Mapping[str, SpecLimit], names: list[str] | tuple[str, ...] | Any) -> dict[str, SpecLimit]:
    """Limits per concrete parameter name: axis-less entries apply to every axis.

    Spec entries that match no estimated name are kept under their own name
    (so that :func:`imunav.lab.report.check_spec` reports them as not measured).

    Parameters
    ----------
    spec : mapping of str to SpecLimit
        Limits as loaded (:func:`imunav.lab.report.load_spec`).
    names : sequence of str
        The concrete names estimated.

    Returns
    -------
    dict of str to SpecLimit
        Limits per concrete name.
    """
    names = list(names)
    out: dict[str, SpecLimit] = {}
    used: set[str] = set()
    for n in names:
        if n in spec:
            out[n] = spec[n]
            used.add(n)
        elif base_name(n) in spec:
            out[n] = spec[base_name(n)]
            used.add(base_name(n))
    for k, lim in spec.items():
        if k not in used:
            out[k] = lim
    return out
