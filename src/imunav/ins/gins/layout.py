"""Named layouts of the GNSS/INS kernel's vectors (private), generated from name tuples.

* Error state ``dx`` / covariance ``P``: the blocks of :data:`STATE_BLOCKS` that a configuration uses, in that
  order; the integer vector ``lay`` (layout :data:`LAY`) holds the first index of each block, −1 when absent,
  and the error-state size.  Errors are ``true − estimate``.
* Nominal state ``xs`` (layout :data:`NOM`): position (lat rad, lon rad, h m), NED velocity, ``q_nb`` and the
  estimated sensor errors; always the full vector, whatever the error state holds (an error the filter does not
  estimate keeps its initial value).
* Core parameters ``prm`` (float, layout :data:`PRM`): Earth rate, IMU noise, Gauss–Markov processes and the χ²
  gate thresholds by degrees of freedom.  Each aid model reads its own parameter block, whose offset the
  integer vector ``lay`` holds after the :data:`LAY` fields (``lay[N_LAY + kind]``).
* Update context ``ctx`` (layout :data:`CTX`): the angular rates an aid model may need besides the nominal state.
* Carried clock ``carry`` (float, :data:`CARRY`) and ``carry_n`` (int, :data:`CARRY_N`): what one kernel call
  hands to the next (:meth:`imunav.ins.gins.GinsFilter.step`).
* Update log: one row per update the kernel made (time, sample, source, rows, accepted, NIS).
"""

from __future__ import annotations

from imunav.filters._layout import named_layout

#: Error-state blocks in filter order, with their sizes (SI: m, m/s, rad, rad/s, m/s², dimensionless).
STATE_BLOCKS = (
    ("pos", 3),  # δr N E D, m
    ("vel", 3),  # δv N E D, m/s
    ("att", 3),  # φ, rad (navigation frame, C_nb = exp([φ×]) Ĉ_nb)
    ("gyro_bias", 3),  # δb_g, rad/s
    ("accel_bias", 3),  # δb_a, m/s²
    ("gyro_scale", 3),  # δs_g, optional
    ("accel_scale", 3),  # δs_a, optional
    ("odo_scale", 1),  # δk of the odometer, optional
    ("mount", 3),  # μ: IMU mounting error, vehicle frame (C_vb = exp([μ×]) Ĉ_vb), rad, optional
    ("odo_lever", 3),  # δl: wheel contact point from the IMU, body FRD, m, optional
    ("gnss_delay", 1),  # δτ: GNSS receiver latency (stamp − true time of the fix), s, optional
    # the Gauss–Markov parts of the biases when each bias is a random constant plus one (bias_model
    # "constant_and_gauss_markov"): δg_g rad/s, δg_a m/s², optional; the bias blocks above hold the whole bias
    ("gyro_bias_gm", 3),
    ("accel_bias_gm", 3),
    # the GNSS fixes' error correlated in time (multipath, atmosphere), NED, m: a first-order Gauss–Markov process
    # that the position fixes hold besides their white noise, optional
    ("gnss_bias", 3),
    # the odometer's over-reading in turns, per rad/s of the vehicle's yaw rate (skid-steer wheels slip, outer wheels
    # of a steered axle run wider), s/rad, optional
    ("odo_turn", 1),
    # the vehicle's side slip in turns: its lateral velocity −β v_x² ω_z (slip angle β times the lateral acceleration
    # v_x ω_z, a linear tyre's), rad per m/s², optional
    ("side_slip", 1),
)
#: Blocks every configuration estimates.
REQUIRED_BLOCKS = ("pos", "vel", "att", "gyro_bias", "accel_bias")

#: ``lay`` (int64): first index of each state block (−1: not estimated), the error-state size, samples per
#: covariance step, the gate rejections in a row after which an update is forced (0: never), the Schmidt consider
#: blocks as a bit mask (bit i: block i of :data:`STATE_BLOCKS`; 0: none); the aid models' parameter offsets follow
#: (``lay[N_LAY + kind]``).
LAY, N_LAY = named_layout("GinsLayout", tuple((name, 1) for name, _ in STATE_BLOCKS) + (("nx", 1), ("cov_step", 1),
                                                                                      ("max_rejections", 1),
                                                                                      ("consider", 1)))

#: ``xs`` (float): nominal navigation state and sensor errors.
#: ``q_vb``: the IMU's attitude in the vehicle frame (IMU FRD -> vehicle FRD, scalar first); ``odo_lever``: the wheel
#: contact point from the IMU, body FRD, m; ``gnss_delay``: the GNSS latency, s; ``gnss_bias``: the fixes' correlated
#: error, NED, m; ``gnss_r_scale``: the factor on the fixes' reported covariance that the filter applies (1 without
#: adaptation, or while the estimate ``gnss_r_est`` is within two standard errors of 1), ``gnss_r_weight`` the
#: estimate's information (the inverse of its variance; the reported σ counts as ``gnss_adaptive_prior_fixes`` fixes);
#: ``odo_turn``: the odometer's over-reading per rad/s of yaw rate, s/rad; ``odo_r_*``, ``nhc_r_*``: the same three for the
#: odometer's and the NHC's covariance (``GinsConfig.wheel_adaptive``); ``side_slip``: the vehicle's side slip per
#: m/s² of lateral acceleration, rad/(m/s²).
NOM, N_NOM = named_layout("GinsNominal", (("lla", 3), ("vel", 3), ("q", 4), ("gyro_bias", 3), ("accel_bias", 3),
                                          ("gyro_scale", 3), ("accel_scale", 3), ("odo_scale", 1), ("q_vb", 4),
                                          ("odo_lever", 3), ("gnss_delay", 1), ("gnss_bias", 3),
                                          ("gnss_r_scale", 1), ("gnss_r_est", 1),
                                          ("gnss_r_weight", 1), ("odo_turn", 1),
                                          ("odo_r_scale", 1), ("odo_r_est", 1), ("odo_r_weight", 1),
                                          ("nhc_r_scale", 1), ("nhc_r_est", 1), ("nhc_r_weight", 1),
                                          ("side_slip", 1)))
#: the sensor errors of ``xs`` (GinsFilter.imu_errors: 13 values)
N_SENSOR_ERRORS = NOM.odo_scale + 1 - NOM.gyro_bias

#: Largest number of rows of one update (joint updates included); gate thresholds exist for 1 .. MAX_ROWS.
MAX_ROWS = 9

#: ``prm`` (float): core parameters.  ``*_q``: driving-noise PSD 2σ²/T of a Gauss–Markov state; ``*_t``: its
#: correlation time, s; ``gnss_adapt``: the adaptive GNSS noise's forgetting weight per fix (0: off) and its lowest
#: and highest factor on the reported covariance; ``wheel_adapt``: the same for the wheel aids (odometer and NHC, per
#: update); ``gate``: χ²(m) thresholds, ``prm[PRM.gate + m − 1]``.
PRM, N_PRM = named_layout("GinsParams", (
    ("omega_e", 1), ("gyro_noise_density", 3), ("accel_noise_density", 3),
    ("gyro_bias_q", 3), ("accel_bias_q", 3), ("gyro_scale_q", 3), ("accel_scale_q", 3), ("odo_scale_q", 1),
    ("gyro_bias_t", 3), ("accel_bias_t", 3), ("gyro_scale_t", 3), ("accel_scale_t", 3), ("odo_scale_t", 1),
    ("gnss_bias_q", 3), ("gnss_bias_t", 1), ("gnss_adapt", 3), ("wheel_adapt", 3),
    ("gate", MAX_ROWS),
))

#: ``ctx`` (float): ``w_mean``: compensated mean body rate over the last covariance interval (rad/s);
#: ``w_sample``: the rate of the current IMU sample less the estimated gyro bias; ``w_raw``: the raw mean rate since
#: the last covariance epoch; ``dt_raw``: that span, s.
CTX, N_CTX = named_layout("GinsContext", (("w_mean", 3), ("w_sample", 3), ("w_raw", 3), ("dt_raw", 1)))

#: ``carry`` (float): time of the last covariance propagation, Σ ω^b h and Σ f^b h since then, Σ raw Δθ since the
#: last covariance epoch and its time.  ``carry_n`` (int): samples since the last propagation.
CARRY, N_CARRY = named_layout("GinsCarry", (("t_cov", 1), ("sum_w", 3), ("sum_f", 3), ("sum_raw", 3),
                                            ("t_raw", 1)))
#: ``carry_n`` also counts each update source's gate rejections in a row (timed kind, or N_AIDS + sampled group).
MAX_SOURCES = 32
CARRY_N, N_CARRY_N = named_layout("GinsCarryN", (("n_cov", 1), ("rejections", MAX_SOURCES)))

#: Largest number of models in one joint update (the update log keeps the NIS of each model's rows alone).
MAX_GROUP = 3
#: Largest number of measurement columns of one aid model (``z``); timed aids have at most 3 with a 3×3 ``r``.
MAX_WIDTH = 6
