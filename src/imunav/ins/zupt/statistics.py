"""Zero-velocity test statistics of foot-mounted IMUs: SHOE, ARED, AMVD and MBGTD.

The formulas, the block conventions and the published default sigmas are
stated in :mod:`imunav.ins.zupt.detectors`, which thresholds these statistics.
They sit in their own module so that the learned detector
(:mod:`imunav.learn.lstm`, which checks its flags with SHOE) and the
classical ones (which can dispatch to the learned one) share them without
importing each other.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InvalidInputError, ShapeError
from imunav.ins.zupt import kernels as _k

__all__ = ["DETECTORS", "SIGMA_A", "SIGMA_W", "G_PYSHOE", "detector_statistic", "shoe", "ared", "amvd", "mbgtd"]

Array = NDArray[np.float64]

#: Names of the classical detectors.
DETECTORS: tuple[str, ...] = ("shoe", "ared", "amvd", "mbgtd")

SIGMA_A = 0.00098
SIGMA_W = 8.7266463e-5
#: pyshoe's gravity, m/s² (the ZUPT detectors' and INS's default, so that pyshoe's published results reproduce;
#: elsewhere the package assumes :data:`imunav.units.DEFAULT_GRAVITY`).
G_PYSHOE = 9.8029


def _vec(x: ArrayLike, name: str) -> Array:
    a = np.ascontiguousarray(x, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ShapeError(f"{name} must have shape (N, 3); got {a.shape}")
    if not np.all(np.isfinite(a)):
        rows = np.flatnonzero(~np.all(np.isfinite(a), axis=1))
        raise InvalidInputError(f"{name} has non-finite values at rows {rows[:10].tolist()}; remove or interpolate them")
    return a


def _window(W: int, n: int) -> int:
    if int(W) != W or W < 2:
        raise InvalidInputError(f"window must be an integer >= 2 samples; got {W!r}")
    if n < W:
        raise InvalidInputError(f"the recording has {n} samples, fewer than the window W={W}; use a shorter window")
    return int(W)


def shoe(accel: ArrayLike, gyro: ArrayLike, window: int = 5, *, sigma_a: float = SIGMA_A,
         sigma_w: float = SIGMA_W, g: float = G_PYSHOE) -> Array:
    """SHOE statistic (N,) on non-overlapping blocks (Skog et al., IEEE TBME 57(11), 2010, eq. 16).

    ``T = 1/W Σ |y_a,k − g ȳ_a/|ȳ_a||² / σ_a² + |y_w,k|² / σ_w²`` over each block of ``W``
    samples, held over the block; samples after the last full block get 0.

    Parameters
    ----------
    accel : array_like, shape (N, 3)
        Specific force in the body (FRD) frame, m/s².
    gyro : array_like, shape (N, 3)
        Angular rate in the body (FRD) frame, rad/s.
    window : int, optional
        Window length ``W`` in samples, >= 2 (default 5).
    sigma_a : float, optional
        Accelerometer noise standard deviation, m/s², > 0.
    sigma_w : float, optional
        Gyroscope noise standard deviation, rad/s, > 0.
    g : float, optional
        Gravity magnitude, m/s², > 0.

    Returns
    -------
    numpy.ndarray, shape (N,)
        The statistic (dimensionless).

    Raises
    ------
    ShapeError
        If ``accel`` and ``gyro`` differ in shape.
    InvalidInputError
        If a sigma or ``g`` is not > 0, or ``accel`` has all-zero rows.
    """
    a = _vec(accel, "accel")
    w = _vec(gyro, "gyro")
    if a.shape != w.shape:
        raise ShapeError(f"accel {a.shape} and gyro {w.shape} must have the same shape")
    if sigma_a <= 0 or sigma_w <= 0 or g <= 0:
        raise InvalidInputError(f"sigma_a, sigma_w and g must be > 0; got {sigma_a}, {sigma_w}, {g}")
    W = _window(window, a.shape[0])
    if np.any(np.linalg.norm(a, axis=1) == 0):
        raise InvalidInputError("accel has all-zero rows; SHOE needs the gravity direction (check the units/columns)")
    return _k.shoe_blocks(a, w, W, float(sigma_a), float(sigma_w), float(g))


def ared(gyro: ArrayLike, window: int = 5) -> Array:
    """ARED statistic (N,), rad²/s², on non-overlapping blocks: ``T = 1/W Σ |y_w,k|²``.

    Parameters
    ----------
    gyro : array_like, shape (N, 3)
        Angular rate in the body (FRD) frame, rad/s.
    window : int, optional
        Window length ``W`` in samples, >= 2 (default 5).

    Returns
    -------
    numpy.ndarray, shape (N,)
        The angular-rate energy, rad²/s², held over each block.
    """
    w = _vec(gyro, "gyro")
    return _k.ared_blocks(w, _window(window, w.shape[0]))


def amvd(accel: ArrayLike, window: int = 5) -> Array:
    """AMVD statistic (N,), (m/s²)², on non-overlapping blocks: ``T = 1/W Σ |y_a,k − ȳ_a|²``.

    Parameters
    ----------
    accel : array_like, shape (N, 3)
        Specific force in the body (FRD) frame, m/s².
    window : int, optional
        Window length ``W`` in samples, >= 2 (default 5).

    Returns
    -------
    numpy.ndarray, shape (N,)
        The acceleration moving variance, (m/s²)², held over each block.
    """
    a = _vec(accel, "accel")
    return _k.amvd_blocks(a, _window(window, a.shape[0]))


def mbgtd(accel: ArrayLike, window: int = 5, *, tail: float = 1.0) -> Array:
    """MBGTD statistic (N,), m/s², on a per-sample sliding window.

    The last ``window - 1`` samples get ``tail`` (published convention: 1).  The statistic is
    the memory-based graph-theoretic test of Olivares et al. (Sensors 12(7), 2012).

    Parameters
    ----------
    accel : array_like, shape (N, 3)
        Specific force in the body (FRD) frame, m/s².
    window : int, optional
        Window length ``W`` in samples, >= 2 (default 5).
    tail : float, optional
        Value given to the last ``window - 1`` samples (default 1).

    Returns
    -------
    numpy.ndarray, shape (N,)
        The statistic, m/s².
    """
    a = _vec(accel, "accel")
    return _k.mbgtd_sliding(a, _window(window, a.shape[0]), float(tail))


def _accel_gyro(data: Any) -> tuple[Array, Array]:
    try:
        return _vec(data.accel, "data.accel"), _vec(data.gyro, "data.gyro")
    except AttributeError as exc:
        raise InvalidInputError(
            "data must be an ImuData (or have .accel and .gyro arrays (N, 3)); "
            f"got {type(data).__name__}") from exc


def detector_statistic(data: Any, detector: str = "shoe", *, window: int = 5, sigma_a: float = SIGMA_A,
                       sigma_w: float = SIGMA_W, g: float = G_PYSHOE) -> Array:
    """Statistic ``T`` (N,) of a named detector on an :class:`~imunav.timeseries.ImuData`.

    Parameters
    ----------
    data : ImuData
        IMU recording (or any object with ``accel`` and ``gyro`` arrays (N, 3), SI, body FRD).
    detector : {"shoe", "ared", "amvd", "mbgtd"}, optional
        Detector name (case-insensitive; default ``"shoe"``).
    window : int, optional
        Window length in samples, >= 2.
    sigma_a, sigma_w, g : float, optional
        SHOE's accelerometer (m/s²) and gyroscope (rad/s) noise and gravity (m/s²).

    Returns
    -------
    numpy.ndarray, shape (N,)
        The statistic (units of the detector: see :func:`shoe`, :func:`ared`, :func:`amvd`,
        :func:`mbgtd`).

    Raises
    ------
    InvalidInputError
        If the detector name is unknown.
    """
    name = detector.lower()
    a, w = _accel_gyro(data)
    if name == "shoe":
        return shoe(a, w, window, sigma_a=sigma_a, sigma_w=sigma_w, g=g)
    if name == "ared":
        return ared(w, window)
    if name == "amvd":
        return amvd(a, window)
    if name == "mbgtd":
        return mbgtd(a, window)
    raise InvalidInputError(f"unknown detector {detector!r}; choose one of {', '.join(DETECTORS)}")
