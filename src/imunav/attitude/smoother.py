"""Offline forward-backward smoother (RTS on the MEKF error state).

The forward pass is the adaptive MEKF (:mod:`imunav.attitude.mekf`), storing
P⁺_k, P⁻_k and Φ_k; the backward pass is the Rauch-Tung-Striebel recursion
(Rauch, Tung, Striebel, AIAA J. 3(8), 1965) applied to the error state with
the nominal trajectory re-linearised at the filtered estimate:

    C_k = P⁺_k Φ_{k+1}ᵀ (P⁻_{k+1})⁻¹
    δx^s_k = C_k (x^s_{k+1} ⊟ x̂⁻_{k+1}),  x^s_k = x̂⁺_k ⊞ δx^s_k
    P^s_k = P⁺_k + C_k (P^s_{k+1} − P⁻_{k+1}) C_kᵀ

where x̂⁻_{k+1} is the filter's one-step prediction from x̂⁺_k and ⊞ / ⊟ are
the multiplicative attitude update / its inverse (rotation vector of
q̂⁻* ⊗ q^s) plus the additive bias.  Intervals where the magnetometer was
rejected get their heading from both sides, which is where the smoother gains
most over the real-time filter.

Why the smoother has its own defaults
-------------------------------------
A field disturbance costs the two problems differently.  The real-time filter
must keep using a slightly distorted field, or its heading drifts on the gyro
alone until the disturbance ends; so :data:`imunav.attitude.adaptive.ADAPTIVE_DEFAULTS`
reject the field only when its norm or dip deviate by 10 % or 10°.  The
smoother bridges a rejected interval from both of its ends, so it can afford to
reject much smaller deviations.  Those matter: on BROAD, moving the sensor
through the room changes the field norm by up to 9 % and the dip by 2–3°, and
the heading of the field by 3–10° (distortion the 10 % / 10° test lets through);
the real-time tolerances made the smoother *worse* than the forward filter on
those trials (it fits the distorted field from both sides).

The accelerometer and the gyro bias differ too.  The real-time filter low-passes
the specific force over 3 s so that translational accelerations average out, at
the cost of a lag; the smoother averages them from both sides, so a 1 s low-pass
with a slower tilt correction (6 s) serves it better.  And it can let the gyro
bias move faster (random walk 2e-4 rad/s/√s instead of 2e-5): the bias a
rotation makes apparent (scale-factor and misalignment errors) is then followed
and, seen from both sides, not mistaken for tilt.  ``SMOOTHER_DEFAULTS`` are
``ADAPTIVE_DEFAULTS`` with the disturbance test, the heading and tilt time
constants, the accelerometer low-pass and the bias random walk chosen over
:data:`SMOOTHER_GRID` (128 sets) by leave-one-trial-out cross-validation on the
10 shared BROAD trials (``benchmarks/bench_attitude_broad.py``,
:mod:`imunav.crossval`): 0.694 × offline VQF's mean total RMSE out of fold
(0.641 × in sample; it was 0.714 × out of fold with the real-time filter's
accelerometer and bias settings, issue 34); every other parameter is the
real-time filter's.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike

from imunav.attitude import _kernels as _k
from imunav.attitude._base import check_finite_result, params_dict
from imunav.attitude.adaptive import ADAPTIVE_DEFAULTS
from imunav.attitude.mekf import FLAG_NAMES, MEKF, MekfConfig
from imunav.attitude.result import AttitudeResult
from imunav.timeseries import ImuData

__all__ = ["Smoother", "SMOOTHER_DEFAULTS", "SMOOTHER_GRID"]

#: the values searched for SMOOTHER_DEFAULTS (all other parameters are ADAPTIVE_DEFAULTS'; module docstring)
SMOOTHER_GRID: dict[str, list[float]] = {
    "heading_time_constant": [18.0, 27.0],
    "mag_norm_threshold": [0.05, 0.1],
    "mag_dip_threshold": [float(np.radians(5.0)), float(np.radians(10.0))],
    "mag_min_undisturbed": [0.5, 2.0],
    "gyro_bias_random_walk": [1e-4, 2e-4],
    "accel_lpf_time_constant": [1.0, 3.0],
    "tilt_time_constant": [3.0, 6.0],
}

#: forward-pass tuning of the smoother: ADAPTIVE_DEFAULTS with the values chosen over SMOOTHER_GRID
SMOOTHER_DEFAULTS = replace(
    ADAPTIVE_DEFAULTS,
    heading_time_constant=18.0,
    mag_norm_threshold=0.05,
    mag_dip_threshold=float(np.radians(5.0)),
    mag_min_undisturbed=0.5,
    gyro_bias_random_walk=2e-4,
    accel_lpf_time_constant=1.0,
    tilt_time_constant=6.0,
)


@dataclass
class Smoother:
    """RTS smoother over the adaptive MEKF (offline only: no step API).

    Attributes
    ----------
    config : MekfConfig
        Tuning of the forward MEKF; default :data:`SMOOTHER_DEFAULTS` (module docstring).
    """

    config: MekfConfig = field(default_factory=lambda: SMOOTHER_DEFAULTS)

    name = "smoother"

    def run(self, data: ImuData, *, q0: ArrayLike | None = None, bias0: ArrayLike | None = None,
            use_mag: bool | None = None) -> AttitudeResult:
        """Forward MEKF pass, then the backward RTS pass (Rauch, Tung & Striebel 1965; module docstring).

        Parameters
        ----------
        data : ImuData
            The recording (SI: rad/s, m/s²; magnetometer in any unit), body FRD.
        q0 : array_like, shape (4,), optional
            Initial attitude ``q_nb`` (default: :func:`imunav.attitude.alignment.align` of the first accelerometer
            / magnetometer sample).
        bias0 : array_like, shape (3,), optional
            Initial gyro-bias estimate, rad/s (default zero).
        use_mag : bool, optional
            Use the magnetometer (9D); default: when the recording has one.

        Returns
        -------
        AttitudeResult
            Smoothed ``q_nb``, gyro bias (rad/s) and covariance diagonal at every sample, with the forward
            filter's flags.

        Raises
        ------
        InvalidInputError
            If ``data`` is not an ImuData with at least 2 samples, ``use_mag=True`` without a magnetometer, or a
            rate exceeds 1e4 rad/s.
        ConvergenceError
            If the filter's numbers overflow (a noise or initial σ far outside any sensor's range): the sample from
            which its attitude or covariance is not finite.
        """
        f = MEKF(self.config)
        t, g, dt, um, q_init, b0, P0, out = f._run(data, q0, bias0, use_mag, True)
        qf, bf, pf, fl, _, _, Pu, Pp, Ph = out
        params = {**params_dict(self.config), "use_mag": um}
        check_finite_result(self.name, t, qf, pf, params)  # the forward pass: RTS on NaN would only spread them
        qs, bs, pd = _k.rts_smooth(qf, bf, Pu, Pp, Ph, g, dt, P0, q_init, b0)
        flags = {k: (fl & v) > 0 for k, v in FLAG_NAMES.items()}
        check_finite_result(self.name, t, qs, pd, params)
        return AttitudeResult(t=t, q_nb=qs, bias=bs, cov_diag=pd, flags=flags, name=self.name, params=params)
