"""Adaptive MEKF: resists external acceleration and magnetic disturbances.

Same filter as :class:`imunav.attitude.mekf.MEKF` with the adaptive parts on:

* accelerometer R inflated with (| |f| − g | / g)² and with the rotation rate
  (centripetal / tangential acceleration of an off-centre sensor), samples with
  a large norm deviation rejected;
* magnetometer used for heading only, rejected while the field norm or the dip
  angle (computed with the filter's own tilt, not with the raw accelerometer)
  deviate from the reference; the reference is tracked slowly while
  undisturbed and re-acquired after ``mag_ref_time`` of continuous disturbance;
* rest detection (|ω − b̂| and | |f| − g | small for ``rest_time``) with a
  zero-rate pseudo-measurement, i.e. gyro-bias estimation at rest.

The defaults are the single parameter set chosen by the BROAD grid search
(``imunav attitude benchmark --grid``; see benchmarks/bench_attitude_broad.py).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from imunav.attitude.mekf import MEKF, MekfParams

__all__ = ["AdaptiveMEKF", "ADAPTIVE_DEFAULTS"]

ADAPTIVE_DEFAULTS = MekfParams(
    sigma_gyro=0.003,
    sigma_bias=2e-5,
    sigma_acc=0.15,
    k_acc=0.0,
    acc_reject=1e9,
    acc_lpf_tau=3.0,
    sigma_mag=0.3,
    mag_norm_tol=0.1,
    mag_dip_tol=0.07,
    k_mag=0.0,
    rest_gyro=0.02,
    rest_acc=0.2,
    rest_time=1.5,
    sigma_rest=0.002,
    mag_ref_time=0.0,
    k_rate=0.0,
    ref_tau=30.0,
)


@dataclass
class AdaptiveMEKF(MEKF):
    """MEKF with adaptive R, disturbance rejection and rest bias estimation."""

    params: MekfParams = field(default_factory=lambda: ADAPTIVE_DEFAULTS)

    name = "adaptive"
