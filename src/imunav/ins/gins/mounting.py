"""How the IMU sits in the vehicle: a coarse estimate of the mounting from a drive, before the filter refines it.

The mounting is the rotation ``C_vb`` from the IMU's FRD axes to the vehicle's FRD axes (its ZYX Euler angles are
the IMU's roll, pitch and yaw in the vehicle).  :func:`estimate_mounting` finds it in two steps, the approach of
the automotive dead-reckoning receivers (u-blox ESF "automatic IMU-mount alignment"; Chen et al. 2020; Vinande et
al. 2010):

1. **Levelling at rest.**  Standing on level ground, the vehicle's down axis is gravity's: the mean specific force
   ``f̄`` of the static samples gives it in IMU axes, ``d = −f̄ / |f̄|``, and ``C_Lb`` is the smallest rotation that
   takes ``d`` to ``e_z``.  Its error is the ground's slope and the accelerometer bias over g (σ per axis
   ``√(level_noise_std² + (σ_ba / g)²)``).
2. **Yaw from the vehicle's own accelerations.**  Moving, a wheeled vehicle accelerates along its x axis
   (``a_x = dv/dt``, ``v`` the odometer or GNSS speed) and, turning, along y (``a_y = v ω_z``); in the levelled
   frame the horizontal specific force is the same vector turned by the mounting's yaw ψ, so
   ``ψ = atan2(Σ (f_x a_y − f_y a_x), Σ (f_x a_x + f_y a_y))`` (least squares over the moving samples, both sides
   low-passed by the same moving mean).  Its σ is that of the mean of ``chunks`` independent stretches of the drive
   (batch means): the residuals are correlated in time, so a per-sample σ would be too small.

``C_vb = R_z(ψ) C_Lb``.  The GNSS/INS filter takes it as its initial mounting with these σ and refines it
(``GinsConfig.mounting_std``): the NHC and the odometer observe pitch and yaw, the levelling at rest
(``level_noise_std``) the roll.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav._timeseries_kernels import moving_average
from imunav.errors import InsufficientDataError, InvalidInputError, ShapeError
from imunav.results import Result
from imunav.rotation import euler_from_dcm, quat_from_dcm
from imunav.timeseries import ImuData

__all__ = ["MountingEstimate", "estimate_mounting"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class MountingEstimate(Result):
    """A coarse IMU mounting and its uncertainty.

    Attributes
    ----------
    q_vb : numpy.ndarray, shape (4,)
        IMU FRD -> vehicle FRD, Hamilton scalar-first.
    euler : numpy.ndarray, shape (3,)
        Its ZYX Euler angles (roll, pitch, yaw of the IMU in the vehicle), rad.
    std : numpy.ndarray, shape (3,)
        σ of small rotations about the vehicle's x, y, z axes, rad (the filter's mounting error states).
    static_samples, motion_samples : int
        Samples used for the levelling and for the yaw.
    meta : dict
        The gravity measured at rest, the yaw of each batch (rad), the method.
    """

    q_vb: Array
    euler: Array
    std: Array
    static_samples: int
    motion_samples: int
    meta: dict[str, Any] = field(default_factory=dict)


def _levelling(d: Array) -> Array:
    """The smallest rotation taking the unit vector ``d`` to ``e_z`` (Rodrigues)."""
    ez = np.array([0.0, 0.0, 1.0])
    ax = np.cross(d, ez)
    s = float(np.linalg.norm(ax))
    c = float(d @ ez)
    if s < 1e-12:
        return np.eye(3) if c > 0 else np.diag([1.0, -1.0, -1.0])
    K = np.array([[0.0, -ax[2], ax[1]], [ax[2], 0.0, -ax[0]], [-ax[1], ax[0], 0.0]])
    return np.eye(3) + K + K @ K * ((1.0 - c) / s**2)


def _moving_mean(x: Array, w: int) -> Array:
    """Centred moving mean of ``w`` samples along axis 0, column by column (edges: the available samples)."""
    if x.ndim == 1:
        return moving_average(np.ascontiguousarray(x, dtype=float), w)
    return np.column_stack([moving_average(np.ascontiguousarray(x[:, j], dtype=float), w) for j in range(x.shape[1])])


def estimate_mounting(imu: ImuData, static: ArrayLike, *, speed_t: ArrayLike | None = None,
                      speed: ArrayLike | None = None, accel_bias_std: float = 0.0,
                      level_noise_std: float = math.radians(1.0), window_s: float = 1.0, chunks: int = 10,
                      min_accel: float = 0.05) -> MountingEstimate:
    """The IMU's mounting in a wheeled vehicle from its rest and its accelerations (module docstring).

    Parameters
    ----------
    imu : ImuData
        The IMU as recorded (SI, its own FRD axes).
    static : array_like of bool, shape (N,)
        The vehicle stands still (e.g. the odometer reads zero and the IMU is quiet).
    speed_t, speed : array_like, shape (M,), optional
        The vehicle's forward speed (odometer, or GNSS ground speed) and its times, s and m/s; without them the
        yaw is not estimated (0 with σ π).
    accel_bias_std : float
        σ of the accelerometer bias, m/s² (its share of the levelling error).
    level_noise_std : float
        σ of the ground's slope where the vehicle stands, rad.
    window_s : float
        Moving-mean window of the yaw fit, s.
    chunks : int
        Batches of the yaw's batch-means σ (>= 3).
    min_accel : float
        Samples whose horizontal acceleration is below this (m/s²) are left out of the yaw fit.

    Returns
    -------
    MountingEstimate
        ``C_vb``, its Euler angles and σ.

    Raises
    ------
    InsufficientDataError
        With fewer than one second at rest, or (with a speed) too little acceleration to see the yaw.
    InvalidInputError
        If the speed does not overlap the IMU, or an option is out of range.
    ShapeError
        If ``static`` does not have one value per IMU sample.
    """
    st = np.asarray(static, dtype=bool)
    if st.shape != (imu.n,):
        raise ShapeError(f"static must have one value per IMU sample ({imu.n}); got shape {st.shape}")
    if not (chunks >= 3 and window_s > 0 and accel_bias_std >= 0 and level_noise_std >= 0):
        raise InvalidInputError("estimate_mounting: chunks >= 3, window_s > 0, accel_bias_std and level_noise_std >= 0")
    fs = 1.0 / float(np.median(np.diff(imu.t)))
    if st.sum() < fs:
        raise InsufficientDataError(f"estimate_mounting: {int(st.sum())} samples at rest ({st.sum() / fs:.2f} s); "
                                    "the levelling needs at least 1 s standing still (or give the mounting)")
    f_rest = imu.accel[st].mean(axis=0)
    g = float(np.linalg.norm(f_rest))
    C_Lb = _levelling(-f_rest / g)
    tilt_sd = math.sqrt(level_noise_std**2 + (accel_bias_std / g) ** 2 + float(np.mean(imu.accel[st].var(axis=0))) /
                        (g**2 * st.sum()))
    psi, psi_sd, nmov, batches = 0.0, math.pi, 0, []
    if speed is not None:
        ts = np.asarray(speed_t, dtype=float)
        vs = np.asarray(speed, dtype=float)
        inside = (imu.t >= ts[0]) & (imu.t <= ts[-1])
        if ts.size < 2 or not inside.any():
            raise InvalidInputError("estimate_mounting: the speed does not overlap the IMU")
        w = max(1, int(round(window_s * fs)))
        v = _moving_mean(np.interp(imu.t, ts, vs), w)
        fL = _moving_mean(imu.accel @ C_Lb.T, w)
        wz = _moving_mean(imu.gyro @ C_Lb.T, w)[:, 2]
        ax = np.gradient(v, imu.t)
        ay = v * wz
        use = inside & ~st & (np.hypot(ax, ay) > min_accel)
        nmov = int(use.sum())
        if nmov < chunks * w:
            raise InsufficientDataError(f"estimate_mounting: {nmov} moving samples with more than {min_accel} m/s² "
                                        "of acceleration; the yaw needs turns and speed changes (or give the mounting)")
        cross = fL[:, 0] * ay - fL[:, 1] * ax
        dot = fL[:, 0] * ax + fL[:, 1] * ay
        psi = math.atan2(cross[use].sum(), dot[use].sum())
        idx = np.flatnonzero(use)
        wts, dev = [], []
        for part in np.array_split(idx, chunks):
            b = math.atan2(cross[part].sum(), dot[part].sum())
            batches.append(b)
            dev.append(math.remainder(b - psi, 2 * math.pi))
            wts.append(float((ax[part] ** 2 + ay[part] ** 2).sum()))
        wa, da = np.array(wts), np.array(dev)
        psi_sd = math.sqrt(float(np.sum(wa * da**2) / np.sum(wa)) / (chunks - 1))
    Cz = np.array([[math.cos(psi), -math.sin(psi), 0.0], [math.sin(psi), math.cos(psi), 0.0], [0.0, 0.0, 1.0]])
    C_vb = Cz @ C_Lb
    return MountingEstimate(quat_from_dcm(C_vb), np.asarray(euler_from_dcm(C_vb), dtype=float),
                            np.array([tilt_sd, tilt_sd, psi_sd]), int(st.sum()), nmov,
                            {"gravity_at_rest": f_rest.tolist(), "yaw_batches": batches,
                             "method": "levelling at rest + yaw from the vehicle's accelerations"
                             if speed is not None else "levelling at rest (no speed: yaw unknown)"})
