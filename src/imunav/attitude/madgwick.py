"""Madgwick gradient-descent AHRS (6D and 9D).

S. O. H. Madgwick, A. J. L. Harrison, R. Vaidyanathan, "Estimation of IMU and
MARG orientation using a gradient descent algorithm", IEEE ICORR 2011; report
(2010) eqs. 20-34.  Update per sample:

    q̇ = ½ q ⊗ [0, ω] − β ∇f / |∇f|,    q ← normalise(q + q̇ Δt),

with f the stacked residuals of the predicted gravity direction and of the
predicted field direction, whose reference is b = [|h_xy|, 0, h_z] with
h = q ⊗ m ⊗ q* (normalised measurements).

``original_c=True`` reproduces the widely used C implementation, which forms
the reference as ``_2bx = sqrt(hx² + hy²)`` (and ``_2bz = hz``) where the
derivation needs ``2·sqrt(...)``: its reference field is half the measured
one.  The Madgwick numbers published with the BROAD benchmark (D. Laidig, M. Caruso, A. Cereatti,
T. Seel, "BROAD—A benchmark for robust inertial orientation estimation", Data 6(7), 2021) come from that
code.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from imunav.attitude import _kernels as _k
from imunav.attitude._base import MAX_RATE, AttitudeReset, check_positive, gyro3, initial_q, prepare, step_dt, vec3
from imunav.attitude.result import AttitudeResult
from imunav.errors import InvalidInputError
from imunav.timeseries import ImuData

__all__ = ["Madgwick"]


@dataclass
class Madgwick(AttitudeReset):
    """Madgwick filter.

    Attributes
    ----------
    beta : float
        Gradient-step gain β, rad/s (0 … 1e4: the gyro's error rate).
    original_c : bool
        Reproduce the original C implementation's half-size field reference (see the module docstring).
    """

    beta: float = 0.1
    original_c: bool = False

    def __post_init__(self) -> None:
        check_positive(beta=self.beta)
        if self.beta > MAX_RATE:  # β is the gyro's error rate: beyond any gyro's range it is no gain
            raise InvalidInputError(f"Madgwick.beta must be <= {MAX_RATE:g} rad/s (a gyro error rate); got {self.beta!r}")
        self.q = np.array([1.0, 0.0, 0.0, 0.0])

    @property
    def name(self) -> str:
        return "madgwick_c" if self.original_c else "madgwick"

    def step(self, gyro: ArrayLike, accel: ArrayLike, mag: ArrayLike | None, dt: float) -> np.ndarray:
        """Process one sample; returns the new q_nb.

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
        use_mag = mag is not None
        q = _k.madgwick_step(
            _k._ned_nwu(self.q), gyro3(gyro), vec3(accel, "accel"), vec3(mag, "mag"), step_dt(dt),
            float(self.beta), use_mag, 0.5 if self.original_c else 1.0,
        )
        self.q = _k._ned_nwu(q)
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
        q_init = initial_q(a, m, um, q0)
        q = _k.madgwick_run(q_init, g, a, m, dt, float(self.beta), um, 0.5 if self.original_c else 1.0)
        self.q = q[-1].copy()
        return AttitudeResult(t=t, q_nb=q, name=self.name,
                              params={"beta": self.beta, "original_c": self.original_c, "use_mag": um})
