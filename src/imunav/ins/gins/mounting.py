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

**Levelling while driving.**  A car on a highway may never stand still.  With less than one second at rest and a
speed, the gravity direction comes from the moving samples instead: the specific force less the vehicle's own
acceleration, ``f − C_bv (dv/dt, v ω_z, 0)`` (the mounting's yaw from step 2, the two steps iterated twice),
averaged over the drive.  The road's mean grade and crossfall over the drive are then part of the tilt's error
(σ ``drive_level_std``, 2° by default: the mean of a highway's grade over a minute), which the filter's NHC
narrows for the pitch.

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
                      min_accel: float = 0.05, drive_level_std: float = math.radians(2.0),
                      gyro_bias: ArrayLike = (0.0, 0.0, 0.0)) -> MountingEstimate:
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
    drive_level_std : float
        σ of the road's mean slope over the drive, rad, when the levelling is done while driving (less than 1 s at
        rest, a speed given).
    gyro_bias : array_like, shape (3,)
        The gyro bias to take out of the yaw rate of the lateral acceleration ``v ω_z``, rad/s (a raw phone gyro's
        4°/s at 20 m/s is 1.4 m/s² of false lateral acceleration).

    Returns
    -------
    MountingEstimate
        ``C_vb``, its Euler angles and σ.

    Raises
    ------
    InsufficientDataError
        With fewer than one second at rest and no speed, or (with a speed) too little acceleration to see the
        yaw.
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
    bg = np.asarray(gyro_bias, dtype=float) * np.ones(3)
    driving = bool(st.sum() < fs)
    if driving and speed is None:
        raise InsufficientDataError(f"estimate_mounting: {int(st.sum())} samples at rest ({st.sum() / fs:.2f} s); "
                                    "the levelling needs at least 1 s standing still, or the vehicle's speed to "
                                    "level while driving (or give the mounting)")
    if not driving:
        f_rest = imu.accel[st].mean(axis=0)
        g = float(np.linalg.norm(f_rest))
        C_Lb = _levelling(-f_rest / g)
        tilt_sd = math.sqrt(level_noise_std**2 + (accel_bias_std / g) ** 2 +
                            float(np.mean(imu.accel[st].var(axis=0))) / (g**2 * st.sum()))
        psi, psi_sd, nmov, batches = 0.0, math.pi, 0, []
        if speed is not None:
            psi, psi_sd, nmov, batches, _ = _yaw_fit(imu, st, C_Lb, speed_t, speed, fs, window_s, chunks, min_accel,
                                                     bg)
    else:
        # the mean specific force of the moving samples holds the vehicle's mean acceleration: take it out with the
        # mounting found so far, twice
        ts, vs = np.asarray(speed_t, dtype=float), np.asarray(speed, dtype=float)
        C_Lb = _levelling(-imu.accel.mean(axis=0) / np.linalg.norm(imu.accel.mean(axis=0)))
        for _ in range(3):
            psi, psi_sd, nmov, batches, kin = _yaw_fit(imu, st, C_Lb, ts, vs, fs, window_s, chunks, min_accel, bg)
            Cz = np.array([[math.cos(psi), -math.sin(psi), 0.0], [math.sin(psi), math.cos(psi), 0.0],
                           [0.0, 0.0, 1.0]])
            C_vb = Cz @ C_Lb
            f_rest = (imu.accel[kin.inside] - kin.acc_v[kin.inside] @ C_vb).mean(axis=0)
            C_Lb = _levelling(-f_rest / np.linalg.norm(f_rest))
        g = float(np.linalg.norm(f_rest))
        tilt_sd = math.sqrt(drive_level_std**2 + (accel_bias_std / g) ** 2)
    Cz = np.array([[math.cos(psi), -math.sin(psi), 0.0], [math.sin(psi), math.cos(psi), 0.0], [0.0, 0.0, 1.0]])
    C_vb = Cz @ C_Lb
    return MountingEstimate(quat_from_dcm(C_vb), np.asarray(euler_from_dcm(C_vb), dtype=float),
                            np.array([tilt_sd, tilt_sd, psi_sd]), int(st.sum()), nmov,
                            {"gravity_at_rest" if not driving else "gravity_while_driving": f_rest.tolist(),
                             "yaw_batches": batches,
                             "method": ("levelling while driving (no rest: the specific force less the vehicle's "
                                        "acceleration, averaged over the drive) + yaw from the vehicle's "
                                        "accelerations") if driving else
                             "levelling at rest + yaw from the vehicle's accelerations"
                             if speed is not None else "levelling at rest (no speed: yaw unknown)"})


@dataclass(frozen=True)
class _Kinematics:
    """The vehicle's own acceleration ``(dv/dt, v ω_z, 0)`` in its axes at each IMU sample, and where the speed
    covers the IMU."""

    acc_v: Array
    inside: NDArray[np.bool_]


def _yaw_fit(imu: ImuData, st: NDArray[np.bool_], C_Lb: Array, speed_t: ArrayLike, speed: ArrayLike, fs: float,
             window_s: float, chunks: int, min_accel: float,
             bg: Array) -> tuple[float, float, int, list[float], _Kinematics]:
    """Step 2 of the module docstring: the mounting's yaw ψ in the levelled frame ``C_Lb`` (the gyro less ``bg``),
    its batch-means σ, the moving samples used, each batch's yaw, and the vehicle's kinematic acceleration."""
    ts = np.asarray(speed_t, dtype=float)
    vs = np.asarray(speed, dtype=float)
    inside = (imu.t >= ts[0]) & (imu.t <= ts[-1])
    if ts.size < 2 or not inside.any():
        raise InvalidInputError("estimate_mounting: the speed does not overlap the IMU")
    w = max(1, int(round(window_s * fs)))
    v = _moving_mean(np.interp(imu.t, ts, vs), w)
    fL = _moving_mean(imu.accel @ C_Lb.T, w)
    wz = _moving_mean((imu.gyro - bg) @ C_Lb.T, w)[:, 2]
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
    wts, dev, batches = [], [], []
    for part in np.array_split(idx, chunks):
        b = math.atan2(cross[part].sum(), dot[part].sum())
        batches.append(b)
        dev.append(math.remainder(b - psi, 2 * math.pi))
        wts.append(float((ax[part] ** 2 + ay[part] ** 2).sum()))
    wa, da = np.array(wts), np.array(dev)
    psi_sd = math.sqrt(float(np.sum(wa * da**2) / np.sum(wa)) / (chunks - 1))
    acc_v = np.column_stack([ax, ay, np.zeros_like(ax)])
    return psi, psi_sd, nmov, batches, _Kinematics(acc_v, inside & ~st)
