"""Basic complementary filter: gyro strapdown with first-order tilt and
heading corrections.

Each sample: q ← q ⊗ exp(ω Δt); the estimate is then rotated, in the nav
frame, by the fraction k_accel Δt of the angle between the measured gravity
direction and the vertical (about the horizontal axis joining them), and by
the fraction k_mag Δt of the heading of the horizontal field (about the
vertical).  k_accel, k_mag [1/s] are the inverse time constants; the heading
correction never changes the inclination (cf. the "basic" filter of Laidig &
Seel, Information Fusion 91, 2023, §3).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from imunav.attitude import _kernels as _k
from imunav.attitude._base import AttitudeReset, check_positive, gyro3, initial_q, prepare, step_dt, vec3
from imunav.attitude.result import AttitudeResult
from imunav.errors import InvalidInputError
from imunav.timeseries import ImuData

__all__ = ["Complementary"]


@dataclass
class Complementary(AttitudeReset):
    """Complementary filter with time constants 1/k_accel and 1/k_mag [s] (module docstring).

    ``run`` and ``step`` raise :class:`~imunav.errors.InvalidInputError` when a gain times the time step exceeds 1
    (each correction turns by ``k Δt`` of its angle: beyond 1 it overshoots the measured direction).

    Attributes
    ----------
    k_accel : float
        Tilt-correction gain, 1/s.
    k_mag : float
        Heading-correction gain, 1/s.
    """

    k_accel: float = 0.3
    k_mag: float = 0.1

    name = "complementary"

    def __post_init__(self) -> None:
        check_positive(k_accel=self.k_accel, k_mag=self.k_mag)
        self.q = np.array([1.0, 0.0, 0.0, 0.0])

    def _checked_step(self, dt: float) -> float:
        """``dt`` checked against the gains: each correction turns by the fraction ``k Δt`` of its angle, which
        beyond 1 overshoots the measured direction (and from 2 on diverges), so ``k Δt <= 1``."""
        for name, k in (("k_accel", self.k_accel), ("k_mag", self.k_mag)):
            if k * dt > 1.0:
                raise InvalidInputError(
                    f"Complementary {name}={k:g} 1/s with a time step of {dt:g} s corrects {k * dt:.3g} times the "
                    f"angle per sample (overshoot); {name} is an inverse time constant: give at most 1/dt = "
                    f"{1.0 / dt:.3g} 1/s (the default is {0.3 if name == 'k_accel' else 0.1})")
        return dt

    def step(self, gyro: ArrayLike, accel: ArrayLike, mag: ArrayLike | None, dt: float) -> np.ndarray:
        """Process one sample: strapdown, then the tilt and heading corrections.

        Parameters
        ----------
        gyro : array_like, shape (3,)
            Angular rate, body axes (FRD), rad/s.
        accel : array_like, shape (3,)
            Specific force, body axes, m/s² (any unit: only its direction is used).
        mag : array_like, shape (3,), or None
            Magnetic field, body axes (any unit); None for a 6D update.
        dt : float
            Time since the previous sample, s, > 0.

        Returns
        -------
        numpy.ndarray, shape (4,)
            The new attitude ``q_nb``.

        Raises
        ------
        InvalidInputError
            If ``dt`` is not finite and positive, or the rate exceeds 1e4 rad/s (not rad/s).
        ShapeError
            If a sample is not a 3-vector.
        NonFiniteError
            If a sample is not finite.
        """
        d = self._checked_step(step_dt(dt))
        self.q = _k.complementary_step(self.q, gyro3(gyro), vec3(accel, "accel"), vec3(mag, "mag"),
                                       d, float(self.k_accel), float(self.k_mag), mag is not None)
        return self.q.copy()

    def run(self, data: ImuData, *, q0: ArrayLike | None = None, use_mag: bool | None = None) -> AttitudeResult:
        """Filter a whole recording (numba kernel).

        Parameters
        ----------
        data : ImuData
            The recording (SI: rad/s, m/s²; magnetometer in any unit), body FRD.
        q0 : array_like, shape (4,), optional
            Initial attitude ``q_nb`` (default: :func:`imunav.attitude.alignment.align` of the first accelerometer
            / magnetometer sample).
        use_mag : bool, optional
            Use the magnetometer (9D); default: when the recording has one.

        Returns
        -------
        AttitudeResult
            ``q_nb`` at every sample, with the filter's name and parameters.

        Raises
        ------
        InvalidInputError
            If ``data`` is not an ImuData with at least 2 samples, ``use_mag=True`` without a magnetometer, or a
            rate exceeds 1e4 rad/s.
        """
        t, g, a, m, dt, um = prepare(data, use_mag)
        self._checked_step(float(dt.max()))
        q = _k.complementary_run(initial_q(a, m, um, q0), g, a, m, dt, float(self.k_accel), float(self.k_mag), um)
        self.q = q[-1].copy()
        return AttitudeResult(t=t, q_nb=q, name=self.name,
                              params={"k_accel": self.k_accel, "k_mag": self.k_mag, "use_mag": um})
