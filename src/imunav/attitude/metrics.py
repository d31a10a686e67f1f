"""Attitude error metrics, including the BROAD benchmark metric.

BROAD metric (Laidig, Caruso, Cereatti, Seel, "BROAD — A Benchmark for Robust
Inertial Orientation Estimation", Data 6(7):72, 2021): with the error
quaternion expressed in the Earth frame,

    q_err = q_est ⊗ q_ref⁻¹  = [w, x, y, z],
    total       = 2 acos |w|,
    heading     = 2 atan |z / w|            (rotation about the vertical),
    inclination = 2 acos sqrt(w² + z²)      (remaining tilt),

and the RMSE of each angle over the scored (``movement``) samples, skipping
samples whose reference is NaN.  The three angles only use |w|, |z| and
w² + z², so they are identical whether both quaternions are given in ENU or
both in NED (the frame change negates z): the metric can be evaluated
directly on imunav's ``q_nb``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InsufficientDataError, ShapeError
from imunav.results import Result
from imunav.rotation import quat_conjugate, quat_multiply

Array = NDArray[np.float64]

__all__ = ["ErrorAngles", "AttitudeRmse", "error_angles", "attitude_rmse", "euler_rmse"]


@dataclass(frozen=True)
class ErrorAngles:
    """Per-sample error angles (NaN where the reference is NaN).

    Attributes
    ----------
    total : numpy.ndarray, shape (N,)
        Total error angle ``2 acos |w|``, rad.
    heading : numpy.ndarray, shape (N,)
        Heading error ``2 atan |z / w|``, rad.
    inclination : numpy.ndarray, shape (N,)
        Inclination error ``2 acos sqrt(w² + z²)``, rad.
    """

    total: Array
    heading: Array
    inclination: Array


@dataclass(frozen=True)
class AttitudeRmse(Result):
    """RMSE of the BROAD error angles and the number of samples used.

    Attributes
    ----------
    total_rmse_deg, heading_rmse_deg, inclination_rmse_deg : float
        RMSE of each error angle, degrees.
    n_used : int
        Number of samples scored.
    """

    total_rmse_deg: float
    heading_rmse_deg: float
    inclination_rmse_deg: float
    n_used: int

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary.

        Returns
        -------
        dict
            The four attributes by name.
        """
        return {
            "total_rmse_deg": self.total_rmse_deg,
            "heading_rmse_deg": self.heading_rmse_deg,
            "inclination_rmse_deg": self.inclination_rmse_deg,
            "n_used": self.n_used,
        }


def _quats(q: ArrayLike, name: str) -> Array:
    a = np.asarray(q, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 4:
        raise ShapeError(f"{name} must have shape (N, 4) (scalar-first quaternions), got {a.shape}")
    return a / np.linalg.norm(a, axis=1)[:, None]


def error_angles(q_est: ArrayLike, q_ref: ArrayLike) -> ErrorAngles:
    """Total, heading and inclination error angles of the Earth-frame error quaternion (Laidig et al. 2021).

    Parameters
    ----------
    q_est : array_like, shape (N, 4)
        Estimated attitude ``q_nb``.
    q_ref : array_like, shape (N, 4)
        Reference attitude ``q_nb`` (rows with NaN are skipped).

    Returns
    -------
    ErrorAngles
        The three angles at each sample, rad.

    Raises
    ------
    ShapeError
        If the arrays are not (N, 4) with the same N.
    """
    qe = _quats(q_est, "q_est")
    qr = _quats(q_ref, "q_ref")
    if qe.shape != qr.shape:
        raise ShapeError(f"q_est {qe.shape} and q_ref {qr.shape} must have the same shape")
    d = quat_multiply(qe, quat_conjugate(qr)) if len(qe) else np.empty((0, 4))
    with np.errstate(invalid="ignore", divide="ignore"):
        d = d / np.linalg.norm(d, axis=1)[:, None]
        w = np.abs(d[:, 0])
        z = np.abs(d[:, 3])
        total = 2.0 * np.arccos(np.clip(w, 0.0, 1.0))
        heading = 2.0 * np.arctan2(z, w)  # = 2 atan|z/w|, also defined at w = 0
        incl = 2.0 * np.arccos(np.clip(np.sqrt(w * w + z * z), 0.0, 1.0))
    return ErrorAngles(total, heading, incl)


def attitude_rmse(q_est: ArrayLike, q_ref: ArrayLike, mask: ArrayLike | None = None) -> AttitudeRmse:
    """BROAD RMSE over ``mask`` (all samples if None), NaN references skipped (Laidig et al. 2021).

    Parameters
    ----------
    q_est : array_like, shape (N, 4)
        Estimated attitude ``q_nb``.
    q_ref : array_like, shape (N, 4)
        Reference attitude ``q_nb`` (rows with NaN are skipped).
    mask : array_like of bool, shape (N,), optional
        Samples scored (BROAD: the ``movement`` samples).

    Returns
    -------
    AttitudeRmse
        RMSE of the three angles, degrees.

    Raises
    ------
    ShapeError
        If the shapes do not match.
    InsufficientDataError
        If no sample is left to score.
    """
    e = error_angles(q_est, q_ref)
    n = e.total.shape[0]
    m = np.ones(n, bool) if mask is None else np.asarray(mask).astype(bool).reshape(-1)
    if m.shape[0] != n:
        raise ShapeError(f"mask has {m.shape[0]} samples, the quaternions {n}; pass one flag per sample")
    ok = m & np.isfinite(e.total)
    if not ok.any():
        raise InsufficientDataError("no sample is both selected by the mask and has a finite reference")

    def r(x: Array) -> float:
        return float(np.degrees(np.sqrt(np.mean(x[ok] ** 2))))

    return AttitudeRmse(r(e.total), r(e.heading), r(e.inclination), int(ok.sum()))


def euler_rmse(euler_est: ArrayLike, euler_ref: ArrayLike, mask: ArrayLike | None = None) -> Array:
    """RMSE per Euler angle (roll, pitch, yaw), angle differences wrapped to ±180°.

    Parameters
    ----------
    euler_est : array_like, shape (N, k)
        Estimated ZYX Euler angles, rad (k = 2 for roll and pitch, or 3).
    euler_ref : array_like, shape (N, k)
        Reference angles, rad.
    mask : array_like of bool, shape (N,), optional
        Samples scored.

    Returns
    -------
    numpy.ndarray, shape (k,)
        RMSE of each angle, degrees.

    Raises
    ------
    ShapeError
        If the shapes do not match.
    """
    a = np.asarray(euler_est, float)
    b = np.asarray(euler_ref, float)
    if a.shape != b.shape:
        raise ShapeError(f"euler_est {a.shape} and euler_ref {b.shape} must have the same shape")
    d = np.angle(np.exp(1j * (a - b)))
    if mask is not None:
        d = d[np.asarray(mask, bool)]
    return np.degrees(np.sqrt(np.mean(d**2, axis=0)))
