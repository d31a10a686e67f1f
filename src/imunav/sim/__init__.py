"""Virtual sensors: trajectories, test profiles, ideal and erroneous IMU outputs.

* :class:`Trajectory`, :func:`ideal_imu` and trajectory builders
  (:mod:`imunav.sim.trajectory`).
* Calibration test profiles (:mod:`imunav.sim.profiles`): multi-position
  static tests, rate tables, six-position and Ferraris-style tests, each with
  its segment table.
* Sensor error models (:mod:`imunav.sim.error_model`), presets
  (:mod:`imunav.sim.presets`) and the magnetometer model
  (:mod:`imunav.sim.magnetometer`).
"""

from __future__ import annotations

from imunav.sim import presets, profiles
from imunav.sim.error_model import (
    BIAS_INSTABILITY_FLOOR,
    Flicker,
    GaussMarkov,
    ImuErrorModel,
    ImuErrorTruth,
    TriadErrors,
    TriadTruth,
    allan_variance_gauss_markov,
    allan_variance_ieee952,
    apply_errors,
    scale_misalignment_matrix,
    simulate_imu,
)
from imunav.sim.magnetometer import MagnetometerModel, simulate_magnetometer
from imunav.sim.profiles import (
    Profile,
    Segments,
    ferraris_profile,
    hundred_position_orientations,
    hundred_position_profile,
    hundred_position_up_vectors,
    multiposition_profile,
    orientations_from_up,
    rate_table_profile,
    rate_table_step_profile,
    rate_table_steps,
    read_segments,
    six_position_orientations,
    six_position_profile,
    six_position_up_vectors,
    static_profile,
    up_from_orientations,
)
from imunav.sim.trajectory import (
    Trajectory,
    body_rate_from_attitude,
    ideal_imu,
    trajectory_from_attitude,
    trajectory_from_functions,
    trajectory_from_waypoints,
)

__all__ = [
    "Trajectory",
    "ideal_imu",
    "body_rate_from_attitude",
    "trajectory_from_attitude",
    "trajectory_from_functions",
    "trajectory_from_waypoints",
    "profiles",
    "Profile",
    "Segments",
    "read_segments",
    "static_profile",
    "multiposition_profile",
    "orientations_from_up",
    "up_from_orientations",
    "hundred_position_up_vectors",
    "hundred_position_orientations",
    "hundred_position_profile",
    "six_position_up_vectors",
    "six_position_orientations",
    "six_position_profile",
    "rate_table_profile",
    "rate_table_steps",
    "rate_table_step_profile",
    "ferraris_profile",
    "GaussMarkov",
    "Flicker",
    "TriadErrors",
    "ImuErrorModel",
    "apply_errors",
    "simulate_imu",
    "presets",
    "MagnetometerModel",
    "simulate_magnetometer",
    "TriadTruth",
    "ImuErrorTruth",
    "scale_misalignment_matrix",
    "allan_variance_gauss_markov",
    "allan_variance_ieee952",
    "BIAS_INSTABILITY_FLOOR",
]
