"""Generic Kalman machinery shared by the attitude, navigation and air-data filters.

* :class:`KalmanFilter`, :class:`ExtendedKalmanFilter`,
  :class:`UnscentedKalmanFilter` share ``x``, ``P``, ``predict`` and
  ``update`` (``F``, ``Q``, ``H``, ``R``; ``B``/``u`` optional); Joseph-form
  updates, symmetric P; ``update`` returns an :class:`UpdateResult`.  Their steps are the
  primitives of the numba estimation core (:mod:`imunav.filters._core`: ``propagate_cov_sparse``,
  ``joseph_update``, ``nis``, the unscented transform) that the attitude, INS and GNSS/INS filters are
  built from.
* :func:`kalman_filter` runs :class:`KalmanFilter` over a whole sequence;
  :func:`batch_kalman_filter` runs many sequences at once, vectorised over the runs.
* :mod:`~imunav.filters.consistency`: NIS / NEES and χ² bounds.
* :mod:`~imunav.filters.robust`: per-channel gate, χ² isolation, Huber IRLS.
* :mod:`~imunav.filters.faults`: window χ² detectors, NIS test, CUSUM,
  latching, channel isolation and fault injection.
"""

from __future__ import annotations

from imunav.filters.consistency import ConsistencyResult, chi2_bounds, consistency_test, nees, nis
from imunav.filters.ekf import ExtendedKalmanFilter, numerical_jacobian
from imunav.filters.faults import (
    Fault,
    FaultDetectionResult,
    FaultDetectorResult,
    alarms,
    calibrated_thresholds,
    detect_faults,
    detection_delays,
    detector_statistics,
    false_alarm_rates,
    inject_faults,
    latch,
    window_chi2_thresholds,
    window_statistics,
)
from imunav.filters.gates import gate_channels, isolate_channels, nis_gate
from imunav.filters.kalman import (
    BatchRun,
    KalmanFilter,
    KalmanRun,
    UpdateResult,
    batch_kalman_filter,
    kalman_filter,
    riccati_steady_state,
)
from imunav.filters.robust import huber_update, robust_update
from imunav.filters.ukf import UnscentedKalmanFilter, sigma_points

__all__ = [
    "KalmanFilter",
    "ExtendedKalmanFilter",
    "UnscentedKalmanFilter",
    "UpdateResult",
    "KalmanRun",
    "kalman_filter",
    "batch_kalman_filter",
    "BatchRun",
    "riccati_steady_state",
    "numerical_jacobian",
    "sigma_points",
    "nis",
    "nees",
    "chi2_bounds",
    "consistency_test",
    "ConsistencyResult",
    "gate_channels",
    "isolate_channels",
    "nis_gate",
    "huber_update",
    "robust_update",
    "Fault",
    "inject_faults",
    "detect_faults",
    "alarms",
    "detector_statistics",
    "FaultDetectorResult",
    "FaultDetectionResult",
    "calibrated_thresholds",
    "window_chi2_thresholds",
    "window_statistics",
    "latch",
    "false_alarm_rates",
    "detection_delays",
]
