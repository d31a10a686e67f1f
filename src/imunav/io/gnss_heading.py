"""Dual-antenna GNSS heading: the baseline heading and pitch a moving-base receiver reports (:class:`DualAntennaData`).

A moving-base RTK pair (u-blox RELPOSNED, Septentrio, Trimble heading receivers) gives the direction of the
baseline from its primary to its secondary antenna: azimuth from north, clockwise, and elevation above the
horizontal, each with its σ.  The GNSS/INS aid that uses them is :mod:`imunav.ins.gins.aids.dual_antenna`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InvalidInputError, NonFiniteError, ShapeError

__all__ = ["DualAntennaData"]


@dataclass(frozen=True)
class DualAntennaData:
    """Heading and pitch of a dual-antenna (moving-base) GNSS baseline, at the receiver's time stamps.

    Parameters
    ----------
    t : array_like, shape (K,)
        Time stamps, s, strictly increasing (the IMU's time axis).
    heading : array_like, shape (K,)
        Azimuth of the baseline from north, clockwise, rad.
    pitch : array_like, shape (K,)
        Elevation of the baseline above the horizontal, rad (|pitch| < π/2).
    heading_std, pitch_std : float or array_like, shape (K,)
        Their σ, rad (> 0; a scalar applies to every epoch).
    meta : dict
        Provenance.

    Raises
    ------
    ShapeError
        If the arrays do not have K elements.
    NonFiniteError
        If a value is not finite.
    InvalidInputError
        If the stamps are not strictly increasing, a pitch is outside (−π/2, π/2) or a σ is not > 0.
    """

    t: NDArray[np.float64]
    heading: NDArray[np.float64]
    pitch: NDArray[np.float64]
    heading_std: Any
    pitch_std: Any
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        s = object.__setattr__
        t = np.asarray(self.t, dtype=float)
        k = t.size
        s(self, "t", t)
        for name in ("heading", "pitch", "heading_std", "pitch_std"):
            a = np.asarray(getattr(self, name), dtype=float) * np.ones(k)
            if a.shape != (k,):
                raise ShapeError(f"DualAntennaData.{name} must have {k} values, one per time stamp; got {a.shape}")
            if not np.all(np.isfinite(a)):
                raise NonFiniteError(f"DualAntennaData.{name} has a non-finite value at index "
                                     f"{int(np.flatnonzero(~np.isfinite(a))[0])}")
            s(self, name, a)
        if t.ndim != 1 or k < 1 or np.any(np.diff(t) <= 0):
            raise InvalidInputError("DualAntennaData.t must be strictly increasing time stamps, s")
        if np.any(np.abs(self.pitch) >= math.pi / 2):
            raise InvalidInputError("DualAntennaData.pitch must lie in (-pi/2, pi/2) rad (is it in degrees?)")
        for name in ("heading_std", "pitch_std"):
            if np.any(getattr(self, name) <= 0):
                raise InvalidInputError(f"DualAntennaData.{name} must be > 0 rad")

    def measurements(self, baseline: ArrayLike | None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``z`` (K, 2) and ``r`` (K, 2, 2) of the timed aid, for a configured baseline.

        Parameters
        ----------
        baseline : array_like, shape (3,), or None
            ``GinsConfig.dual_antenna_baseline``, body FRD, m.

        Returns
        -------
        z, r : numpy.ndarray
            Heading and pitch (rad) and their diagonal covariance (rad²).

        Raises
        ------
        InvalidInputError
            If no baseline is configured, or it is shorter than 1 cm.
        """
        if baseline is None or float(np.linalg.norm(baseline)) < 0.01:
            raise InvalidInputError("dual-antenna heading needs GinsConfig.dual_antenna_baseline (the secondary "
                                    f"antenna from the primary, body FRD, m; at least 1 cm); got {baseline!r}")
        r = np.zeros((self.t.size, 2, 2))
        r[:, 0, 0] = self.heading_std**2
        r[:, 1, 1] = self.pitch_std**2
        return np.column_stack([self.heading, self.pitch]), r
