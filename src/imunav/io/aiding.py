"""Aiding sensors of a navigation filter, as recorded: wheel odometer, barometer, magnetometer.

These are what the log readers (:mod:`imunav.io.navlog`) return and what the simulators
(:func:`imunav.sim.vehicle.simulate_odometer`, :func:`~imunav.sim.vehicle.simulate_baro`,
:func:`imunav.sim.gnss.simulate_magnetometer`) draw; the GNSS/INS filter takes them as aids.  GNSS
fixes are :class:`imunav.io.gnss.GnssData`.  Every type refuses non-finite samples and times that do
not strictly increase (:func:`check_samples`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InvalidInputError, NonFiniteError, ShapeError

__all__ = ["OdometerData", "BaroData", "MagnetometerData", "check_samples"]

Array = NDArray[np.float64]


def check_samples(owner: str, t: ArrayLike, values: ArrayLike, name: str, width: int | None = None) -> tuple[Array, Array]:
    """Validate time-stamped aiding samples: a strictly increasing finite ``t`` and one finite value (row) per stamp.

    Parameters
    ----------
    owner : str
        The data type, for messages (e.g. ``"BaroData"``).
    t : array_like, shape (N,)
        Sample times, s.
    values : array_like, shape (N,) or (N, width)
        The samples.
    name : str
        The samples' field name, for messages.
    width : int, optional
        Columns of ``values`` (None: one value per stamp).

    Returns
    -------
    tuple of numpy.ndarray
        ``t`` and ``values`` as float arrays.

    Raises
    ------
    ShapeError
        If ``t`` is not 1-D or ``values`` does not have one value (row) per stamp.
    NonFiniteError
        If a time or a value is NaN or infinite (rows named).
    InvalidInputError
        If ``t`` does not strictly increase.
    """
    ta = np.asarray(t, dtype=float)
    va = np.asarray(values, dtype=float)
    shape = (ta.size,) if width is None else (ta.size, width)
    if ta.ndim != 1 or va.shape != shape:
        raise ShapeError(f"{owner}.{name} must have shape {shape} (one per time stamp; t has shape {ta.shape}); "
                         f"got {va.shape}")
    bad = ~np.isfinite(ta) | (~np.isfinite(va) if width is None else ~np.all(np.isfinite(va), axis=1))
    if bad.any():
        raise NonFiniteError(f"{owner}: non-finite time or {name} at rows {np.flatnonzero(bad)[:10].tolist()}; "
                             "remove those samples (a missing sample is an absent row, not NaN)")
    step = np.flatnonzero(np.diff(ta) <= 0)
    if step.size:
        raise InvalidInputError(f"{owner}.t must strictly increase; it does not at row {int(step[0]) + 1}")
    return ta, va


def _sigma(owner: str, t: Array, std: ArrayLike | None, name: str) -> Array | None:
    """A per-sample σ (> 0, finite, one per stamp) or None."""
    if std is None:
        return None
    _, s = check_samples(owner, t, std, name)
    bad = np.flatnonzero(s <= 0)
    if bad.size:
        raise InvalidInputError(f"{owner}.{name} must be > 0 (a standard deviation); it is {s[bad[0]]!r} at row "
                                f"{int(bad[0])} ({bad.size} such rows)")
    return s


@dataclass(frozen=True)
class OdometerData:
    """Wheel-odometer forward speed.

    Attributes
    ----------
    t : numpy.ndarray, shape (N,)
        Sample times, s.
    speed : numpy.ndarray, shape (N,)
        Measured forward (body x) speed, m/s.
    meta : dict
        The simulated errors (``lever_arm`` m, ``scale_factor``, ``noise_std`` m/s), or where a reader took
        the speed from.
    speed_std : numpy.ndarray, shape (N,), or None
        1-σ of each sample, m/s (> 0), when the source states it (a ``nav_msgs/Odometry`` twist
        covariance); None: the filter's configured σ applies.
    yaw_rate : numpy.ndarray, shape (N,), or None
        The wheels' yaw rate about the body's down axis, rad/s (FRD; a ``nav_msgs/Odometry`` or
        ``TwistStamped`` ``twist.angular.z`` with its sign flipped), when the source gives it: a skid-steer
        robot turning on the spot reads zero speed but not zero yaw rate.
    """

    t: Array
    speed: Array
    meta: dict[str, Any] = field(default_factory=dict)
    speed_std: Array | None = None
    yaw_rate: Array | None = None

    def __post_init__(self) -> None:
        t, v = check_samples("OdometerData", self.t, self.speed, "speed")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "speed", v)
        object.__setattr__(self, "speed_std", _sigma("OdometerData", t, self.speed_std, "speed_std"))
        if self.yaw_rate is not None:
            _, w = check_samples("OdometerData", t, self.yaw_rate, "yaw_rate")
            object.__setattr__(self, "yaw_rate", w)


@dataclass(frozen=True)
class BaroData:
    """Barometric (ellipsoidal-equivalent) height.

    Attributes
    ----------
    t : numpy.ndarray, shape (N,)
        Sample times, s.
    height : numpy.ndarray, shape (N,)
        Measured height, m (positive up, the ellipsoidal height plus the sensor's errors; a reader gives the
        ISA pressure altitude, whose offset from the ellipsoid the filter's bias state absorbs).
    meta : dict
        The simulated errors (``noise_std`` m, ``bias_std`` m, ``bias_tau`` s, ``bias``: the first bias, m),
        or where a reader took the height from.
    height_std : numpy.ndarray, shape (N,), or None
        1-σ of each sample, m (> 0), when the source states it; None: the filter's configured σ applies.
    """

    t: Array
    height: Array
    meta: dict[str, Any] = field(default_factory=dict)
    height_std: Array | None = None

    def __post_init__(self) -> None:
        t, v = check_samples("BaroData", self.t, self.height, "height")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "height", v)
        object.__setattr__(self, "height_std", _sigma("BaroData", t, self.height_std, "height_std"))


@dataclass(frozen=True)
class MagnetometerData:
    """Calibrated 3-axis magnetometer samples (hard / soft iron removed), body frame.

    Attributes
    ----------
    t : numpy.ndarray, shape (N,)
        Sample times, s.
    field_b : numpy.ndarray, shape (N, 3)
        Measured field, body FRD, µT (any unit: the heading uses its direction).
    meta : dict
        The simulated field and errors, or where a reader took the samples from.
    """

    t: Array
    field_b: Array
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        t, v = check_samples("MagnetometerData", self.t, self.field_b, "field_b", width=3)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "field_b", v)
