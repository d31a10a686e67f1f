"""Adaptive MEKF: resists external acceleration and magnetic disturbances.

Same filter as :class:`imunav.attitude.mekf.MEKF` with the adaptive parts on:

* accelerometer low-passed in the gyro-integrated navigation frame
  (``accel_lpf_time_constant``), so that translational accelerations average out;
* magnetometer used for heading only (it also estimates the vertical gyro
  bias, which a recording without rest needs); rejected while the low-passed field
  norm or dip (computed with the filter's own tilt) deviate from the
  reference, and used again only after ``mag_min_undisturbed`` of continuous
  undisturbed field; the reference is tracked slowly while undisturbed;
* rest detection on the deviations from low-passed gyro and accelerometer
  signals, with a zero-rate pseudo-measurement: gyro-bias estimation at rest
  that works whatever the accelerometer's scale factor;
* accelerometer and magnetometer weights set as correction time constants,
  independent of the sampling rate.

Where the defaults come from
----------------------------
Most are fixed a priori from the physics of the sensors and the motion, as in
VQF (Laidig & Seel, Information Fusion 91, 2023), and were *not* tuned on any
recording:

===========================  ========  ================================================
parameter                    value     reason
===========================  ========  ================================================
``rest_lpf_time_constant``   0.5 s     rest test smoothing (a still hand holds ~0.5 s)
``rest_gyro_threshold``      2 °/s     gyro deviation at rest: noise, not motion
``rest_accel_threshold``     0.5 m/s²  accelerometer deviation at rest
``lpf_gyro_threshold``       2 °/s     largest plausible MEMS gyro bias
``rest_time``                1.5 s     time still before the bias is measured
``mag_lpf_time_constant``    0.05 s    smooths field noise before the disturbance test
``mag_norm_threshold``       10 %      field-norm change that marks a disturbance
``mag_dip_threshold``        10°       dip change: above tilt errors during fast motion
``mag_min_undisturbed``      0.5 s     a disturbance's chance passes are never used
``mag_bias``                 True      heading updates estimate the vertical gyro bias
``accel_lpf_time_constant``  3 s       translational accelerations average out
===========================  ========  ================================================

The accelerometer and magnetometer enter through the time constants of the
corrections they make (``tilt_time_constant``, ``heading_time_constant``; VQF's 3 s and 9 s are in the
grid), so that the defaults mean the same at any sampling rate.
These two and the gyro noise density ``gyro_noise_density`` were chosen over
:data:`ADAPTIVE_GRID` by the grid search on the 10 shared BROAD trials; the
same grid scored by leave-one-trial-out cross-validation
(``benchmarks/bench_attitude_broad.py``) gives the figure to expect on
recordings the defaults never saw.  The rate-dependent gyro noise
(``k_gyro_rate``) is available but off: it helped on fast rotations and hurt
more on translations and near magnets.

Without a magnetometer (6D)
---------------------------
The tilt is then all there is to estimate, and the same grid scored on the
inclination error by leave-one-trial-out cross-validation chooses
``gyro_noise_density`` = 0.001 rad/s/√Hz and ``tilt_time_constant`` = 2 s in
*every* fold (the 9D choice is 0.003 and 3 s): a lower gyro noise lets the
accelerometer reach the gyro bias sooner, and the shorter time constant corrects
sooner the drift that the gyro's scale-factor and misalignment errors build up
while the sensor turns, which in 9D the heading updates also correct.  These are
:data:`ADAPTIVE_DEFAULTS_6D`, which :class:`AdaptiveMEKF` with its shipped defaults
uses whenever it runs without a magnetometer.  Out of fold on the 10 shared BROAD
trials the inclination RMSE is 1.015 × vqf's 6D (undisturbed 1.010, motion
0.991, magnetic 1.036; ``benchmarks/bench_attitude_broad.py --dims 6D``); the
shipped 9D defaults run in 6D gave 1.051 ×.  What is left of vqf's lead is on the
fast rotations, where most of every filter's error is the few-millisecond offset
between the IMU and the optical reference (vqf's own error on trial 07 falls from
1.02° to 0.63° when its output is moved by one sample, 3.5 ms).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from imunav.attitude.mekf import MEKF, MekfConfig

__all__ = ["AdaptiveMEKF", "ADAPTIVE_DEFAULTS", "ADAPTIVE_DEFAULTS_6D", "ADAPTIVE_GRID"]

ADAPTIVE_DEFAULTS = MekfConfig(
    # chosen over ADAPTIVE_GRID (see the module docstring)
    gyro_noise_density=0.003,
    tilt_time_constant=3.0,
    heading_time_constant=27.0,
    # fixed a priori
    k_gyro_rate=0.0,
    gyro_bias_random_walk=2e-5,
    k_accel=0.0,
    accel_reject_threshold=1e9,
    accel_lpf_time_constant=3.0,
    mag_norm_threshold=0.1,
    mag_dip_threshold=float(np.radians(10.0)),
    mag_lpf_time_constant=0.05,
    mag_min_undisturbed=0.5,
    mag_bias=True,
    k_mag=0.0,
    rest_lpf_time_constant=0.5,
    rest_gyro_threshold=float(np.radians(2.0)),
    rest_accel_threshold=0.5,
    lpf_gyro_threshold=float(np.radians(2.0)),
    rest_time=1.5,
    zaru_noise_std=0.002,
    mag_ref_time=0.0,
    k_rate=0.0,
    mag_ref_time_constant=30.0,
)

#: the shipped defaults without a magnetometer (6D): ADAPTIVE_DEFAULTS with the gyro noise and tilt time constant
#: that leave-one-trial-out CV on the BROAD inclination error chose in every fold (module docstring)
ADAPTIVE_DEFAULTS_6D = replace(ADAPTIVE_DEFAULTS, gyro_noise_density=0.001, tilt_time_constant=2.0)

#: the noise levels searched for ADAPTIVE_DEFAULTS (all other parameters fixed a priori)
ADAPTIVE_GRID: dict[str, list[float]] = {
    "gyro_noise_density": [0.001, 0.003],
    "heading_time_constant": [9.0, 18.0, 27.0],
    "tilt_time_constant": [2.0, 3.0],
}


@dataclass
class AdaptiveMEKF(MEKF):
    """MEKF with adaptive R, disturbance rejection and rest bias estimation (module docstring).

    The methods are those of :class:`imunav.attitude.mekf.MEKF`.

    Attributes
    ----------
    config : MekfConfig
        The tuning; default :data:`ADAPTIVE_DEFAULTS`, which runs as :data:`ADAPTIVE_DEFAULTS_6D` without a
        magnetometer (:meth:`effective_config`).
    """

    config: MekfConfig = field(default_factory=lambda: ADAPTIVE_DEFAULTS)

    name = "adaptive"

    def effective_config(self, use_mag: bool) -> MekfConfig:
        """The configuration a run uses: :data:`ADAPTIVE_DEFAULTS_6D` for a run without the magnetometer when
        ``config`` is the shipped :data:`ADAPTIVE_DEFAULTS` (whatever its ``use_mag``), else ``config`` as given.

        Parameters
        ----------
        use_mag : bool
            Whether the run uses the magnetometer (9D).

        Returns
        -------
        MekfConfig
            The configuration (its ``use_mag`` kept from ``config``).
        """
        cfg = self.config
        if use_mag:
            return cfg
        memo = getattr(self, "_config_6d", None)  # (config, its 6D configuration): step() asks at every sample
        if memo is None or memo[0] is not cfg:
            six = replace(ADAPTIVE_DEFAULTS_6D, use_mag=cfg.use_mag)
            memo = (cfg, six if replace(cfg, use_mag=True) == ADAPTIVE_DEFAULTS else cfg)
            self._config_6d = memo
        return memo[1]
