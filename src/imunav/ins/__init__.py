"""Inertial navigation: strapdown mechanization, zero-velocity detectors and
the ZUPT-aided pedestrian INS (error-state EKF), with position metrics.

Quick use::

    from imunav.io.foot import read_pyshoe_mat
    from imunav.ins import ZuptFilter, detect_zero_velocity, error_2d
    trial = read_pyshoe_mat("trial.mat")
    zv = detect_zero_velocity(trial.imu, "shoe", 1e8)
    res = ZuptFilter().run(trial.imu, zv.zv)
    print(error_2d(res.position, trial.position))
"""

from imunav.ins.detectors import (
    DEFAULT_THRESHOLDS,
    DETECTORS,
    DetectorResult,
    ThresholdSearch,
    amvd,
    ared,
    detect_zero_velocity,
    detector_statistic,
    free_acceleration,
    mbgtd,
    motion_adaptive,
    optimize_threshold,
    shoe,
)
from imunav.ins.metrics import LoopClosure, align_heading, error_2d, loop_closure_error, position_rmse, vertical_error
from imunav.ins.strapdown import StrapdownResult, coning_sculling_increments, strapdown_local, strapdown_ned
from imunav.ins.zupt import (
    ZuptConfig,
    ZuptFilter,
    ZuptResult,
    ZuptState,
    align_from_accel,
    first_stance,
    long_stances,
)

__all__ = [
    "DEFAULT_THRESHOLDS", "DETECTORS", "DetectorResult", "ThresholdSearch", "amvd", "ared",
    "detect_zero_velocity", "detector_statistic", "free_acceleration", "mbgtd", "motion_adaptive", "optimize_threshold", "shoe",
    "LoopClosure", "align_heading", "error_2d", "loop_closure_error", "position_rmse", "vertical_error",
    "StrapdownResult", "coning_sculling_increments", "strapdown_local", "strapdown_ned",
    "ZuptConfig", "ZuptFilter", "ZuptResult", "ZuptState", "align_from_accel", "first_stance", "long_stances",
]
