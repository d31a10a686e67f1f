"""The ZUPT-aided pedestrian INS: zero-velocity detectors (classical GLRT statistics and the LSTM's inference),
the error-state EKF (9 or 15 states) with its numba kernels, and the position metrics of foot-mounted navigation.

=================  ================================================================================
module             owns
=================  ================================================================================
``filter``         :class:`ZuptConfig`, :class:`ZuptFilter` (run / step / reset), results, alignment
``kernels``        the numba loops: detector statistics and the error-state EKF (private)
``statistics``     the SHOE / ARED / AMVD / MBGTD test statistics
``detectors``      thresholds, detector dispatch (:func:`detect_zero_velocity`), threshold search
``lstm``           the LSTM detector's inference (numpy; training in :mod:`imunav.learn.lstm`)
``result``         :class:`DetectorResult`
``metrics``        position-error metrics (published 2-D error, loop closure, RMSE)
``plot``           figures (matplotlib, imported when drawing)
=================  ================================================================================

The names below are also exported by :mod:`imunav.ins`.
"""

from imunav.ins.zupt.detectors import (
    DEFAULT_THRESHOLDS,
    DETECTORS,
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
from imunav.ins.zupt.filter import (
    ZuptConfig,
    ZuptFilter,
    ZuptResult,
    ZuptState,
    align_from_accel,
    first_stance,
    long_stances,
)
from imunav.ins.zupt.metrics import (
    LoopClosure,
    align_heading,
    error_2d,
    loop_closure_error,
    position_rmse,
    vertical_error,
)
from imunav.ins.zupt.result import DetectorResult

__all__ = [
    "DEFAULT_THRESHOLDS", "DETECTORS", "DetectorResult", "ThresholdSearch", "amvd", "ared",
    "detect_zero_velocity", "detector_statistic", "free_acceleration", "mbgtd", "motion_adaptive", "optimize_threshold", "shoe",
    "LoopClosure", "align_heading", "error_2d", "loop_closure_error", "position_rmse", "vertical_error",
    "ZuptConfig", "ZuptFilter", "ZuptResult", "ZuptState", "align_from_accel", "first_stance", "long_stances",
]
