"""OpenVINS IMU configuration (``kalibr_imu_chain.yaml``) from an identified noise model.

OpenVINS reads the IMU noise from the file named by ``relative_config_imu``
in its estimator configuration, an OpenCV-YAML file with one ``imu0`` block
(https://docs.openvins.com/gs-calibration.html; the keys of
``config/euroc_mav/kalibr_imu_chain.yaml`` in github.com/rpng/open_vins).
OpenVINS requires every key of the block, so the IMU intrinsics are written
too, as the identity (``Tw``, ``Ta``, ``R_IMUtoGYRO``, ``R_IMUtoACC``) and zero
(``Tg``): imunav's calibration is applied to the data before they reach the
estimator (:meth:`imunav.calib.ImuCalibration.apply`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

from imunav.io._noise import KALIBR_KEYS, check_rate, imu_noise_values, value_lines, write_text

if TYPE_CHECKING:  # annotations only
    from imunav.noise.fit import NoiseFit

__all__ = ["OPENVINS_IMU_KEYS", "write_openvins_yaml"]

#: The keys of the ``imu0`` block, as OpenVINS names them.
OPENVINS_IMU_KEYS = ("T_i_b", "accelerometer_noise_density", "accelerometer_random_walk", "gyroscope_noise_density",
                     "gyroscope_random_walk", "rostopic", "time_offset", "update_rate", "model", "Tw",
                     "R_IMUtoGYRO", "Ta", "R_IMUtoACC", "Tg")


def _matrix(name: str, n: int, diag: float) -> list[str]:
    rows = [[diag if i == j else 0.0 for j in range(n)] for i in range(n)]
    return [f"  {name}:"] + ["    - [ " + ", ".join(f"{v:.1f}" for v in r) + " ]" for r in rows]


def write_openvins_yaml(path: str | os.PathLike[str], gyro: NoiseFit, accel: NoiseFit, update_rate: float,
                        rostopic: str = "/imu0", combine: str = "max") -> Path:
    """Write OpenVINS's ``kalibr_imu_chain.yaml`` with the identified IMU noise.

    Parameters
    ----------
    path : path-like
        The YAML file to write (atomically).
    gyro, accel : NoiseFit
        Noise fits of the gyroscope (rad/s) and accelerometer (m/s^2) channels.
    update_rate : float
        IMU sample rate, Hz.
    rostopic : str
        The IMU topic OpenVINS subscribes to.
    combine : {"max", "mean"}
        One value per sensor: the maximum (default) or mean over the axes.

    Returns
    -------
    Path
        ``path``.

    Notes
    -----
    The values are continuous-time densities (SI), the same as Kalibr's; a
    random walk that the fit did not identify is its upper bound (commented).
    """
    rate = check_rate(update_rate)
    v = imu_noise_values(gyro, accel, combine)
    lines = ["%YAML:1.0", "", "# IMU noise identified by imunav (Allan-variance GLS fit); SI, continuous time.",
             "# Intrinsics are identity: apply the imunav calibration to the data first.", "", "imu0:"]
    lines += _matrix("T_i_b", 4, 1.0)
    lines += value_lines(v, KALIBR_KEYS, indent="  ")
    lines += [f"  rostopic: {rostopic}", "  time_offset: 0.0", f"  update_rate: {rate!r}", '  model: "kalibr"']
    lines += _matrix("Tw", 3, 1.0) + _matrix("R_IMUtoGYRO", 3, 1.0) + _matrix("Ta", 3, 1.0)
    lines += _matrix("R_IMUtoACC", 3, 1.0) + _matrix("Tg", 3, 0.0)
    return write_text(path, lines)
