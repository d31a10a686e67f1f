"""VINS-Fusion IMU parameters (``acc_n``, ``gyr_n``, ``acc_w``, ``gyr_w``, ``g_norm``) from a noise model.

VINS-Fusion (and VINS-Mono) read the IMU noise from the top level of their
OpenCV-YAML configuration (the "imu parameters" block of
``config/euroc/euroc_mono_imu_config.yaml`` in
github.com/HKUST-Aerial-Robotics/VINS-Fusion).  The file written here holds
that block only; merge it into the full configuration.

The values written are the *identified* ones (continuous-time densities,
SI).  VINS users conventionally inflate them (often ×10 or more) to cover
vibration, unmodelled errors and the estimator's approximations: do so
knowingly, in the configuration, after comparing with these numbers.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from imunav.errors import InvalidInputError
from imunav.io._noise import imu_noise_values, value_lines, write_text
from imunav.units import G0

if TYPE_CHECKING:  # annotations only
    from imunav.noise.fit import NoiseFit

__all__ = ["VINS_IMU_KEYS", "write_vins_yaml"]

#: The keys written, as VINS-Fusion names them.
VINS_IMU_KEYS = ("imu", "imu_topic", "acc_n", "gyr_n", "acc_w", "gyr_w", "g_norm")


def write_vins_yaml(path: str | os.PathLike[str], gyro: NoiseFit, accel: NoiseFit, imu_topic: str = "/imu0",
                    g_norm: float = G0, combine: str = "max") -> Path:
    """Write the VINS-Fusion IMU parameter block with the identified noise (not inflated).

    Parameters
    ----------
    path : path-like
        The YAML file to write (atomically).
    gyro, accel : NoiseFit
        Noise fits of the gyroscope (rad/s) and accelerometer (m/s^2) channels.
    imu_topic : str
        The IMU topic.
    g_norm : float
        Local gravity magnitude, m/s^2 (default standard gravity 9.80665; use
        :func:`imunav.earth.normal_gravity` for the site).
    combine : {"max", "mean"}
        One value per sensor: the maximum (default) or mean over the axes.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    InvalidInputError
        If ``g_norm`` is not a gravity magnitude on Earth (9.7-9.9 m/s²).

    Notes
    -----
    ``acc_n``/``gyr_n`` are the white-noise densities ``N`` and
    ``acc_w``/``gyr_w`` the random walks ``K``.  VINS users usually inflate
    them; the file says so in a comment and keeps the identified values.
    """
    g = float(g_norm)
    if not (np.isfinite(g) and 9.7 < g < 9.9):
        raise InvalidInputError(f"g_norm must be the local gravity magnitude on Earth (9.7-9.9 m/s^2); got {g_norm}")
    v = imu_noise_values(gyro, accel, combine)
    lines = ["%YAML:1.0", "",
             "# IMU noise identified by imunav (Allan-variance GLS fit); SI, continuous time.",
             "# These are the identified values, NOT inflated: VINS users conventionally multiply them",
             "# (often by 10 or more) to cover vibration and unmodelled errors; decide that here.",
             "imu: 1", f'imu_topic: "{imu_topic}"']
    lines += value_lines(v, (("acc_n", ("accel", "N")), ("gyr_n", ("gyro", "N")), ("acc_w", ("accel", "K")),
                             ("gyr_w", ("gyro", "K"))))
    lines.append(f"g_norm: {g!r}  # [m/s^2] gravity magnitude")
    return write_text(path, lines)
