"""Initial attitude alignment from accelerometer (+ magnetometer) samples.

Static (coarse) alignment: the mean specific force gives the down axis in body
coordinates, d_b = −f̄/|f̄|; with a magnetometer the horizontal field gives
(magnetic) north, e_b = d_b × m̄ / |d_b × m̄|, n_b = e_b × d_b; the rows of
C_nb are n_b, e_b, d_b (Groves 2013, §5.6.2 / §6.1.1, TRIAD form).  Without a
magnetometer the yaw is set to ``yaw`` (default 0).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import DegenerateGeometryError, ShapeError
from imunav.rotation import quat_from_dcm, quat_from_euler, quat_multiply

Array = NDArray[np.float64]

__all__ = ["align", "tilt_from_accel", "broad_reference_start"]


def _mean3(x: ArrayLike, name: str) -> Array:
    a = np.asarray(x, float)
    if a.ndim == 1:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != 3 or a.shape[0] == 0:
        raise ShapeError(f"{name} must be a (3,) sample or (N, 3) samples, got {np.shape(x)}")
    if not np.all(np.isfinite(a)):
        raise ShapeError(f"{name} contains NaN/inf; pass finite samples")
    return a.mean(axis=0)


def tilt_from_accel(accel: ArrayLike) -> tuple[float, float]:
    """Roll and pitch from specific force: roll = atan2(−f_y, −f_z), pitch = atan2(f_x, sqrt(f_y² + f_z²)).

    Groves 2013, §5.6.2 (leveling): at rest the specific force is minus gravity in body axes.

    Parameters
    ----------
    accel : array_like, shape (3,)
        Specific force, body axes (FRD), m/s² (any unit).

    Returns
    -------
    roll, pitch : float
        Angles, rad.

    Raises
    ------
    DegenerateGeometryError
        If the specific force is zero.
    """
    f = _mean3(accel, "accel")
    if np.linalg.norm(f) == 0.0:
        raise DegenerateGeometryError("accelerometer mean is zero; alignment needs gravity (a static sample)")
    return float(np.arctan2(-f[1], -f[2])), float(np.arctan2(f[0], np.hypot(f[1], f[2])))


def align(accel: ArrayLike, mag: ArrayLike | None = None, *, yaw: float = 0.0) -> Array:
    """Body->NED quaternion from mean accelerometer (and magnetometer) samples.

    Parameters
    ----------
    accel : array_like
        (3,) or (N, 3) specific force [m/s²].
    mag : array_like, optional
        (3,) or (N, 3) magnetic field (any unit) or None.
    yaw : float
        Heading [rad] used when ``mag`` is None.

    Returns
    -------
    numpy.ndarray, shape (4,)
        ``q_nb``, body (FRD) to NED (magnetic north with a magnetometer).

    Raises
    ------
    DegenerateGeometryError
        If the specific force is zero, or the field is parallel to it (no horizontal component).
    """
    f = _mean3(accel, "accel")
    fn = np.linalg.norm(f)
    if fn == 0.0:
        raise DegenerateGeometryError("accelerometer mean is zero; alignment needs gravity (a static sample)")
    if mag is None:
        roll, pitch = tilt_from_accel(f)
        return quat_from_euler(roll, pitch, yaw)
    m = _mean3(mag, "mag")
    d = -f / fn
    e = np.cross(d, m)
    en = np.linalg.norm(e)
    if en < 1e-9 * max(np.linalg.norm(m), 1e-300):
        raise DegenerateGeometryError(
            "magnetic field is parallel to gravity (or zero); heading is undefined, pass mag=None and a yaw"
        )
    e /= en
    nvec = np.cross(e, d)
    C_nb = np.vstack([nvec, e, d])
    return quat_from_dcm(C_nb)


def broad_reference_start(acc0: ArrayLike, mag0: ArrayLike) -> Array:
    """Initial state of the BROAD reference Madgwick / Mahony runs, as q_nb (NED).

    The BROAD example code builds R = [x y z] with z = f, x = (z × −m) × z,
    y = z × x (columns normalised), converts R to a quaternion with the
    per-component ``sqrt`` / ``copysign`` formula and sets it as the state of
    the C filters, whose Earth frame is NWU.  Those columns are the Earth axes
    expressed in sensor coordinates, so the state set is the *inverse*
    (sensor <- Earth) of the aligned orientation: the reference runs start with
    a wrong attitude and converge during the initial rest.  This function
    reproduces that start exactly and maps it to imunav's NED frame
    (q_ned = q_ned_nwu ⊗ q_nwu, q_ned_nwu = rotation of π about x).

    Parameters
    ----------
    acc0 : array_like, shape (3,)
        First accelerometer sample, body axes.
    mag0 : array_like, shape (3,)
        First magnetometer sample, body axes.

    Returns
    -------
    numpy.ndarray, shape (4,)
        The start attitude ``q_nb`` (NED) of the reference runs.
    """
    z = np.asarray(acc0, float).reshape(3)
    m = np.asarray(mag0, float).reshape(3)
    x = np.cross(np.cross(z, -m), z)
    y = np.cross(z, x)
    R = np.column_stack([x / np.linalg.norm(x), y / np.linalg.norm(y), z / np.linalg.norm(z)])
    w2 = (1 + R[0, 0] + R[1, 1] + R[2, 2]) / 4
    x2 = (1 + R[0, 0] - R[1, 1] - R[2, 2]) / 4
    y2 = (1 - R[0, 0] + R[1, 1] - R[2, 2]) / 4
    z2 = (1 - R[0, 0] - R[1, 1] + R[2, 2]) / 4
    with np.errstate(invalid="ignore"):
        q = np.array(
            [
                np.sqrt(w2),
                np.copysign(np.sqrt(x2), R[2, 1] - R[1, 2]),
                np.copysign(np.sqrt(y2), R[0, 2] - R[2, 0]),
                np.copysign(np.sqrt(z2), R[1, 0] - R[0, 1]),
            ]
        )
    q = np.nan_to_num(q)
    q /= np.linalg.norm(q)
    return quat_multiply(np.array([0.0, 1.0, 0.0, 0.0]), q)
