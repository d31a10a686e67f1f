"""Mahony explicit complementary filter with gyro-bias integral (6D / 9D).

R. Mahony, T. Hamel, J.-M. Pflimlin, "Nonlinear complementary filters on the
special orthogonal group", IEEE TAC 53(5), 2008, eq. 32 (explicit form):

    e = â × v̂ + m̂ × ŵ,   b̂̇ = −k_i e,   q̇ = ½ q ⊗ [0, ω − b̂ + k_p e],

with v̂, ŵ the predicted gravity-up and field directions in the body frame
(field reference [|h_xy|, 0, h_z] from the measurement, h = q ⊗ m ⊗ q*).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from imunav.attitude import _kernels as _k
from imunav.attitude._base import MAX_RATE, check_positive, check_q0, gyro3, initial_q, prepare, step_dt, vec3
from imunav.attitude.result import AttitudeResult
from imunav.errors import InvalidInputError
from imunav.timeseries import ImuData

__all__ = ["Mahony"]


@dataclass
class Mahony:
    """Mahony explicit complementary filter (Mahony, Hamel & Pflimlin 2008, eq. 32).

    Attributes
    ----------
    kp : float
        Proportional gain k_p, rad/s.
    ki : float
        Integral (gyro-bias) gain k_i, rad/s².

    Raises
    ------
    InvalidInputError
        If a gain is negative, not finite or above 1e4 (beyond any gyro's rate: the filter's numbers overflow).
    """

    kp: float = 1.0
    ki: float = 0.0

    name = "mahony"

    def __post_init__(self) -> None:
        check_positive(kp=self.kp, ki=self.ki)
        for k, v, unit in (("kp", self.kp, "rad/s"), ("ki", self.ki, "rad/s²")):
            if v > MAX_RATE:  # a correction rate beyond any gyro's range: its arithmetic overflows
                raise InvalidInputError(f"Mahony.{k} must be <= {MAX_RATE:g} {unit} (a gain on the attitude error); "
                                        f"got {v!r}")
        self.q = np.array([1.0, 0.0, 0.0, 0.0])
        self.integral = np.zeros(3)

    def reset(self, q0: ArrayLike, bias: ArrayLike | None = None) -> None:
        """Set the attitude the next :meth:`step` starts from.

        Parameters
        ----------
        q0 : array_like, shape (4,)
            Attitude ``q_nb`` [w, x, y, z], body (FRD) to NED (normalised here).
        bias : array_like, shape (3,), optional
            Initial gyro-bias estimate, rad/s (default zero).

        Raises
        ------
        ShapeError
            If ``q0`` is not a (4,) quaternion.
        NonFiniteError
            If ``q0`` is zero or not finite.
        """
        self.q = check_q0(q0)
        self.integral = -vec3(bias, "bias")

    def step(self, gyro: ArrayLike, accel: ArrayLike, mag: ArrayLike | None, dt: float) -> np.ndarray:
        """Process one sample: ``e = â × v̂ + m̂ × ŵ``, ``b̂ ← b̂ − k_i e Δt``, ``q ← q ⊗ exp((ω − b̂ + k_p e) Δt)``.

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
        self.q, self.integral = _k.mahony_step(
            self.q, self.integral, gyro3(gyro), vec3(accel, "accel"), vec3(mag, "mag"),
            step_dt(dt), float(self.kp), float(self.ki), mag is not None,
        )
        return self.q.copy()

    def run(self, data: ImuData, *, q0: ArrayLike | None = None, bias0: ArrayLike | None = None,
            use_mag: bool | None = None) -> AttitudeResult:
        """Filter a whole recording (numba kernel).

        Parameters
        ----------
        data : ImuData
            The recording (SI: rad/s, m/s²; magnetometer in any unit), body FRD.
        q0 : array_like, shape (4,), optional
            Initial attitude ``q_nb`` (default: :func:`imunav.attitude.alignment.align` of the first accelerometer
            / magnetometer sample).
        bias0 : array_like, shape (3,), optional
            Initial gyro-bias estimate, rad/s.
        use_mag : bool, optional
            Use the magnetometer (9D); default: when the recording has one.

        Returns
        -------
        AttitudeResult
            ``q_nb`` and the gyro-bias estimate (rad/s) at every sample, with the filter's name and parameters.

        Raises
        ------
        InvalidInputError
            If ``data`` is not an ImuData with at least 2 samples, ``use_mag=True`` without a magnetometer, or a
            rate exceeds 1e4 rad/s.
        """
        t, g, a, m, dt, um = prepare(data, use_mag)
        q_init = initial_q(a, m, um, q0)
        q, b = _k.mahony_run(q_init, -vec3(bias0, "bias0"), g, a, m, dt, float(self.kp), float(self.ki), um)
        self.q = q[-1].copy()
        self.integral = -b[-1].copy()
        return AttitudeResult(t=t, q_nb=q, bias=b, name=self.name,
                              params={"kp": self.kp, "ki": self.ki, "use_mag": um})
