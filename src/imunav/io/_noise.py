"""The IMU noise values that the estimator configuration files take (shared by the writers).

Kalibr, OpenVINS and VINS-Fusion each take one white-noise density ``N`` and
one bias random walk ``K`` per sensor (gyroscope, accelerometer), in SI units
and continuous time.  :func:`imu_noise_values` picks them from two
:class:`~imunav.noise.NoiseFit` results.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from imunav.errors import InvalidInputError
from imunav.files import atomic_path

if TYPE_CHECKING:  # only for the annotations: the writers take the fits the user already has
    from imunav.noise.fit import NoiseFit

__all__ = ["KALIBR_KEYS", "NoiseValue", "check_rate", "imu_noise_values", "value_lines", "write_text"]

#: SI units of the four values, by (sensor, term).
UNITS = {("gyro", "N"): "rad/s/sqrt(Hz)", ("gyro", "K"): "rad/s^2/sqrt(Hz)",
         ("accel", "N"): "m/s^2/sqrt(Hz)", ("accel", "K"): "m/s^3/sqrt(Hz)"}


#: Kalibr's key for each value (OpenVINS reads the same keys).
KALIBR_KEYS = (("accelerometer_noise_density", ("accel", "N")), ("accelerometer_random_walk", ("accel", "K")),
               ("gyroscope_noise_density", ("gyro", "N")), ("gyroscope_random_walk", ("gyro", "K")))


@dataclass(frozen=True)
class NoiseValue:
    """One value of a configuration file and how it was obtained.

    Attributes
    ----------
    value : float
        The number written (SI, continuous time).
    per_axis : tuple of float
        The per-axis values it was combined from.
    unit : str
        SI unit of ``value``.
    note : str
        How it was obtained (``"max of per-axis fits"``, or the upper-bound explanation).
    """

    value: float
    per_axis: tuple[float, ...]
    unit: str
    note: str

    def comment(self) -> str:
        """A one-line YAML comment: unit, origin and the per-axis values."""
        return f"[{self.unit}] {self.note}: " + ", ".join(f"{p:.6e}" for p in self.per_axis)


def _k_upper_bound(fit: NoiseFit, c: int) -> float:
    """The largest random walk the fitted curve allows: ``K^2 tau/3 <= AVAR(tau_max)``."""
    tmax = float(np.max(fit.tau))
    return float(np.sqrt(3.0 * fit.model_avar(np.array([tmax]), c)[0] / tmax))


def imu_noise_values(gyro: NoiseFit, accel: NoiseFit, combine: str = "max") -> dict[tuple[str, str], NoiseValue]:
    """White noise ``N`` and random walk ``K`` of each sensor, combined over the axes.

    Parameters
    ----------
    gyro, accel : NoiseFit
        Fits of the gyroscope (rad/s) and accelerometer (m/s^2) channels.
    combine : {"max", "mean"}
        How the per-axis values become one: ``"max"`` (conservative, default) or ``"mean"``.

    Returns
    -------
    dict
        ``{("gyro", "N"): NoiseValue, ("gyro", "K"): ..., ("accel", "N"): ..., ("accel", "K"): ...}``.

    Raises
    ------
    InvalidInputError
        Unknown ``combine``, a fit of the wrong quantity, or a white noise ``N`` that the fit did not identify.

    Notes
    -----
    The estimators refuse a zero random walk (Kalibr checks ``> 0``).  When the
    term selection left ``K`` out (the record is too short to see it), the
    value written is the upper bound ``sqrt(3 AVAR(tau_max) / tau_max)`` of the
    fitted curve, and the note says so.
    """
    pick = {"max": np.max, "mean": np.mean}.get(combine)
    if pick is None:
        raise InvalidInputError(f"combine={combine!r}; use 'max' or 'mean'")
    out: dict[tuple[str, str], NoiseValue] = {}
    for sensor, fit in (("gyro", gyro), ("accel", accel)):
        if fit.quantity not in (None, sensor):
            raise InvalidInputError(f"the {sensor} argument holds a {fit.quantity} fit; pass the gyro fit first, "
                                    "then the accelerometer fit")
        for term in ("N", "K"):
            vals = (fit.value[fit.names.index(term)] if term in fit.names
                    else np.zeros(len(fit.channels))).astype(float)
            sel = (fit.selected[fit.names.index(term)] if term in fit.names
                   else np.zeros(len(fit.channels), bool)) & (vals > 0)
            note = f"{combine} of per-axis fits"
            if term == "N" and not sel.all():
                bad = [fit.channels[c] for c in np.flatnonzero(~sel)]
                raise InvalidInputError(f"{sensor} white noise N was not identified on {bad}: the estimator "
                                        "configuration needs it; fit with N among the candidate terms")
            if term == "K" and not sel.all():
                vals = np.array([vals[c] if sel[c] else _k_upper_bound(fit, c) for c in range(vals.size)])
                note = (f"{combine} of per-axis values; K not identified on "
                        f"{[fit.channels[c] for c in np.flatnonzero(~sel)]} (record too short): "
                        "upper bound sqrt(3 AVAR(tau_max)/tau_max) of the fitted curve there")
            out[(sensor, term)] = NoiseValue(float(pick(vals)), tuple(float(v) for v in vals),
                                             UNITS[(sensor, term)], note)
    return out


def value_lines(values: dict[tuple[str, str], NoiseValue], keys: tuple[tuple[str, tuple[str, str]], ...],
                indent: str = "") -> list[str]:
    """``key: value  # comment`` YAML lines, one per ``(key, (sensor, term))`` of ``keys``."""
    return [f"{indent}{key}: {values[sk].value!r}  # {values[sk].comment()}" for key, sk in keys]


def check_rate(update_rate: float) -> float:
    """``update_rate`` as a finite float > 0 (Hz), else :class:`InvalidInputError`."""
    r = float(update_rate)
    if not (np.isfinite(r) and r > 0):
        raise InvalidInputError(f"update_rate must be the IMU sample rate in Hz (> 0); got {update_rate}")
    return r


def write_text(path: str | os.PathLike[str], lines: list[str]) -> Path:
    """Write ``lines`` (newline-terminated) to ``path`` atomically; returns the path."""

    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return Path(path)
