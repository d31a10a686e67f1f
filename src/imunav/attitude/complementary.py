"""Basic complementary filter: gyro strapdown with first-order tilt and
heading corrections.

Each sample: q ← q ⊗ exp(ω Δt); the estimate is then rotated, in the nav
frame, by the fraction k_acc Δt of the angle between the measured gravity
direction and the vertical (about the horizontal axis joining them), and by
the fraction k_mag Δt of the heading of the horizontal field (about the
vertical).  k_acc, k_mag [1/s] are the inverse time constants; the heading
correction never changes the inclination (cf. the "basic" filter of Laidig &
Seel, Information Fusion 91, 2023, §3).
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

__all__ = ["Complementary"]


@dataclass
class Complementary(AttitudeReset):
    """Complementary filter with time constants 1/k_acc and 1/k_mag [s] (module docstring).

    Attributes
    ----------
    k_acc : float
        Tilt-correction gain, 1/s.
    k_mag : float
        Heading-correction gain, 1/s.
    """

    k_acc: float = 0.3
    k_mag: float = 0.1

    name = "complementary"

    def __post_init__(self) -> None:
        check_positive(k_acc=self.k_acc, k_mag=self.k_mag)
        self.q = np.array([1.0, 0.0, 0.0, 0.0])

    @fill_doc
    def step(self, gyro: ArrayLike, accel: ArrayLike, mag: ArrayLike | None, dt: float) -> np.ndarray:
        """Process one sample: strapdown, then the tilt and heading corrections.

        %(att_step)s
        """
        self.q = _k.complementary_step(self.q, gyro3(gyro), vec3(accel, "accel"), vec3(mag, "mag"),
                                       step_dt(dt), float(self.k_acc), float(self.k_mag), mag is not None)
        return self.q.copy()

    @fill_doc
    def run(self, data: ImuData, *, q0: ArrayLike | None = None, use_mag: bool | None = None) -> AttitudeResult:
        """Filter a whole recording (numba kernel).

        %(att_run_gain)s
        """
        t, g, a, m, dt, um = prepare(data, use_mag)
        q = _k.complementary_run(initial_q(a, m, um, q0), g, a, m, dt, float(self.k_acc), float(self.k_mag), um)
        self.q = q[-1].copy()
        return AttitudeResult(t=t, q_nb=q, name=self.name,
                              params={"k_acc": self.k_acc, "k_mag": self.k_mag, "use_mag": um})
