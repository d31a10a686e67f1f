"""Kalibr IMU configuration (``imu.yaml``) from an identified noise model.

Kalibr's IMU file (``kalibr_calibrate_imu_camera --imu imu.yaml``) holds the
continuous-time white-noise densities and bias random walks of the
accelerometer and gyroscope, the ROS topic and the sample rate; Kalibr
discretises with ``update_rate`` (``sigma_d = N sqrt(update_rate)``).  Key
names: Kalibr wiki, "IMU Noise Model" and "Supported Formats"
(https://github.com/ethz-asl/kalibr/wiki/yaml-formats).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

from imunav.io._noise import KALIBR_KEYS, check_rate, imu_noise_values, value_lines, write_text

if TYPE_CHECKING:  # annotations only
    from imunav.noise.fit import NoiseFit

__all__ = ["KALIBR_IMU_KEYS", "write_kalibr_yaml"]

#: The keys written, as Kalibr's IMU configuration names them.
KALIBR_IMU_KEYS = tuple(k for k, _ in KALIBR_KEYS) + ("rostopic", "update_rate")


def write_kalibr_yaml(path: str | os.PathLike[str], gyro: NoiseFit, accel: NoiseFit, update_rate: float,
                      rostopic: str = "/imu0", combine: str = "max") -> Path:
    """Write Kalibr's ``imu.yaml``: noise densities ``N`` and random walks ``K`` (SI, continuous time).

    Parameters
    ----------
    path : path-like
        The YAML file to write (atomically).
    gyro, accel : NoiseFit
        Noise fits of the gyroscope (rad/s) and accelerometer (m/s^2) channels.
    update_rate : float
        IMU sample rate, Hz.
    rostopic : str
        The IMU topic of the bag Kalibr will read.
    combine : {"max", "mean"}
        Kalibr takes one value per sensor: the maximum (conservative, default)
        or the mean over the axes.  The per-axis values are written as comments.

    Returns
    -------
    Path
        ``path``.

    Notes
    -----
    A random walk that the fit did not identify is written as the upper bound
    of the fitted curve (see :func:`imunav.io._noise.imu_noise_values`); its
    comment says so.  Written by hand (no YAML dependency).
    """
    rate = check_rate(update_rate)
    v = imu_noise_values(gyro, accel, combine)
    lines = ["# IMU noise model identified by imunav (Allan-variance GLS fit); SI, continuous time", ""]
    lines += value_lines(v, KALIBR_KEYS)
    lines.append(f"rostopic: {rostopic}")
    lines.append(f"update_rate: {rate!r}  # [Hz]")
    return write_text(path, lines)
