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

from imunav._docstrings import fill_doc
from imunav.attitude import _kernels as _k
from imunav.attitude._base import AttitudeReset, check_positive, gyro3, initial_q, prepare, step_dt, vec3
from imunav.attitude.result import AttitudeResult
from imunav.timeseries import ImuData

__all__ = ["Madgwick"]


@dataclass
class Madgwick(AttitudeReset):
    """Madgwick filter.

    Attributes
    ----------
    beta : float
        Gradient-step gain β, rad/s.
    original_c : bool
        Reproduce the original C implementation's half-size field reference (see the module docstring).
    """

    beta: float = 0.1
    original_c: bool = False

    def __post_init__(self) -> None:
        check_positive(beta=self.beta)
        self.q = np.array([1.0, 0.0, 0.0, 0.0])

    @property
    def name(self) -> str:
        return "madgwick_c" if self.original_c else "madgwick"

    @fill_doc
    def step(self, gyro: ArrayLike, accel: ArrayLike, mag: ArrayLike | None, dt: float) -> np.ndarray:
        """Process one sample; returns the new q_nb.

        %(att_step)s
        """
        use_mag = mag is not None
        q = _k.madgwick_step(
            _k._ned_nwu(self.q), gyro3(gyro), vec3(accel, "accel"), vec3(mag, "mag"), step_dt(dt),
            float(self.beta), use_mag, 0.5 if self.original_c else 1.0,
        )
        self.q = _k._ned_nwu(q)
        return self.q.copy()

    @fill_doc
    def run(self, data: ImuData, *, q0: ArrayLike | None = None, use_mag: bool | None = None) -> AttitudeResult:
        """Filter a whole recording (numba kernel).

        %(att_run_gain)s
        """
        t, g, a, m, dt, um = prepare(data, use_mag)
        q_init = initial_q(a, m, um, q0)
        q = _k.madgwick_run(q_init, g, a, m, dt, float(self.beta), um, 0.5 if self.original_c else 1.0)
        self.q = q[-1].copy()
        return AttitudeResult(t=t, q_nb=q, name=self.name,
                              params={"beta": self.beta, "original_c": self.original_c, "use_mag": um})
