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
from imunav.attitude._base import check_positive, check_q0, gyro3, initial_q, prepare, step_dt, vec3
from imunav.attitude.result import AttitudeResult
from imunav.timeseries import ImuData

__all__ = ["Mahony"]


@dataclass
class Mahony:
    """Mahony filter; ``kp`` [rad/s], ``ki`` [rad/s²]."""

    kp: float = 1.0
    ki: float = 0.0

    name = "mahony"

    def __post_init__(self) -> None:
        check_positive(kp=self.kp, ki=self.ki)
        self.q = np.array([1.0, 0.0, 0.0, 0.0])
        self.integral = np.zeros(3)

    def reset(self, q0: ArrayLike, bias: ArrayLike | None = None) -> None:
        self.q = check_q0(q0)
        self.integral = -vec3(bias, "bias")

    def step(self, gyro: ArrayLike, accel: ArrayLike, mag: ArrayLike | None, dt: float) -> np.ndarray:
        self.q, self.integral = _k.mahony_step(
            self.q, self.integral, gyro3(gyro), vec3(accel, "accel"), vec3(mag, "mag"),
            step_dt(dt), float(self.kp), float(self.ki), mag is not None,
        )
        return self.q.copy()

    def run(self, data: ImuData, *, q0: ArrayLike | None = None, bias0: ArrayLike | None = None,
            use_mag: bool | None = None) -> AttitudeResult:
        t, g, a, m, dt, um = prepare(data, use_mag)
        q_init = initial_q(a, m, um, q0)
        q, b = _k.mahony_run(q_init, -vec3(bias0, "bias0"), g, a, m, dt, float(self.kp), float(self.ki), um)
        self.q = q[-1].copy()
        self.integral = -b[-1].copy()
        return AttitudeResult(t=t, q_nb=q, bias=b, name=self.name,
                              params={"kp": self.kp, "ki": self.ki, "use_mag": um})
