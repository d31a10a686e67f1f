"""Inertial navigation: strapdown mechanization, the ZUPT-aided pedestrian INS (:mod:`imunav.ins.zupt`:
zero-velocity detectors, error-state EKF, position metrics) and the loosely coupled GNSS/INS
(:mod:`imunav.ins.gins`).

Quick use::

    from imunav.io.foot import read_pyshoe_mat
    from imunav.ins import ZuptFilter, detect_zero_velocity, error_2d
    trial = read_pyshoe_mat("trial.mat")
    zv = detect_zero_velocity(trial.imu, "shoe", 1e8)
    res = ZuptFilter().run(trial.imu, zv.zv)
    print(error_2d(res.position, trial.position))
"""

from imunav.ins.strapdown import StrapdownResult, coning_sculling_increments, strapdown_local, strapdown_ned
from imunav.ins.zupt import (
    DEFAULT_THRESHOLDS,
    DETECTORS,
    DetectorResult,
    LoopClosure,
    ThresholdSearch,
    ZuptConfig,
    ZuptFilter,
    ZuptResult,
    ZuptState,
    align_from_accel,
    align_heading,
    amvd,
    ared,
    detect_zero_velocity,
    detector_statistic,
    error_2d,
    first_stance,
    free_acceleration,
    long_stances,
    loop_closure_error,
    mbgtd,
    motion_adaptive,
    optimize_threshold,
    position_rmse,
    shoe,
    vertical_error,
)

__all__ = [
    "DEFAULT_THRESHOLDS", "DETECTORS", "DetectorResult", "ThresholdSearch", "amvd", "ared",
    "detect_zero_velocity", "detector_statistic", "free_acceleration", "mbgtd", "motion_adaptive", "optimize_threshold", "shoe",
    "LoopClosure", "align_heading", "error_2d", "loop_closure_error", "position_rmse", "vertical_error",
    "StrapdownResult", "coning_sculling_increments", "strapdown_local", "strapdown_ned",
    "ZuptConfig", "ZuptFilter", "ZuptResult", "ZuptState", "align_from_accel", "first_stance", "long_stances",
]
