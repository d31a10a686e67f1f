"""Zero-velocity (stance) detectors for foot-mounted IMUs.

Four generalised likelihood-ratio tests (GLRT) compare a statistic ``T[k]``
with a threshold ``gamma``: the foot is declared stationary when
``T[k] < gamma`` (strictly).  The conventions are those of the published
pyshoe evaluation (Wagstaff, Peretroukhin & Kelly, IEEE Sensors J. 20(2),
2020), which the stored labels of the University of Toronto foot dataset use:

* **SHOE** (stance hypothesis optimal estimator; Skog et al., IEEE TBME
  57(11), 2010, eq. 16)::

      T_n = 1/W sum_{k in block} |y_a,k - g ybar_a/|ybar_a||^2 / sigma_a^2
                                 + |y_w,k|^2 / sigma_w^2

* **ARED** (angular-rate energy): ``T_n = 1/W sum |y_w,k|^2`` (rad²/s²).
* **AMVD** (acceleration moving variance): ``T_n = 1/W sum |y_a,k - ybar_a|^2``.
* **MBGTD** (memory-based graph-theoretic, Olivares et al., Sensors 2012):
  maximum over split pairs of the normalised mean distance between the
  accelerometer samples before and after the split.

Also: a motion-adaptive SHOE (:func:`motion_adaptive`) and the
free-acceleration rule of x-io's Gait-Tracking (:func:`free_acceleration`).

SHOE, ARED and AMVD are evaluated on **non-overlapping blocks** of ``W``
samples and the block value is held over the block; samples after the last
full block get ``T = 0`` (stationary).  MBGTD slides one sample at a time; its
last ``W - 1`` samples get ``T = 1``.  Thresholds scale with ``sigma_a``,
``sigma_w``: a threshold is only meaningful together with them, so the
defaults are the published ones (``sigma_a = 0.00098`` m/s²,
``sigma_w = 8.7266463e-5`` rad/s, ``g = 9.8029`` m/s², ``W = 5``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav._timeseries_kernels import moving_average, runs
from imunav.attitude import Mahony
from imunav.errors import InvalidInputError, ShapeError
from imunav.ins.zupt.filter import ZuptFilter
from imunav.ins.zupt.lstm import LstmDetector
from imunav.ins.zupt.metrics import error_2d
from imunav.ins.zupt.result import DetectorResult
from imunav.ins.zupt.statistics import (
    DETECTORS,
    G_PYSHOE,
    SIGMA_A,
    SIGMA_W,
    _accel_gyro,
    amvd,
    ared,
    detector_statistic,
    mbgtd,
    shoe,
)
from imunav.results import Result
from imunav.rotation import quat_rotate

__all__ = [
    "DETECTORS",
    "DEFAULT_THRESHOLDS",
    "THRESHOLD_GRIDS",
    "DetectorResult",
    "ThresholdSearch",
    "detector_statistic",
    "detect_zero_velocity",
    "shoe",
    "ared",
    "amvd",
    "mbgtd",
    "motion_adaptive",
    "free_acceleration",
    "optimize_threshold",
    "shrink_stances",
]

Array = NDArray[np.float64]

#: Fixed thresholds at 200 Hz with the default sigmas and W = 5: the single
#: threshold per detector with the smallest mean 2-D error over the 42 shared
#: Toronto VICON trials (31-point log grids, ``benchmarks/bench_zupt_lstm_cv.py``:
#: SHOE 0.281 m, ARED 0.307 m, AMVD 0.91 m, MBGTD 2.47 m -- in-sample figures, chosen
#: and scored on the same trials; chosen by leave-one-session-out CV the best fixed
#: classical threshold scores 0.382 m out of fold).
DEFAULT_THRESHOLDS: dict[str, float] = {"shoe": 1.0e8, "ared": 0.79, "amvd": 2.0, "mbgtd": 1.0}

#: Threshold grids of the published per-trial optimisation (pyshoe
#: ``run_threshold_optimization.py``), per detector.
THRESHOLD_GRIDS: dict[str, Array] = {
    "shoe": np.concatenate([
        np.arange(1e5, 1e6, 0.25e5), np.arange(1e6, 1e7, 0.25e6),
        np.arange(1e7, 1e8, 0.25e7), np.arange(1e8, 1e9, 0.25e8)]),
    "ared": np.concatenate([
        np.arange(1e-2, 1e-1, 0.25e-2), np.arange(1e-1, 1, 0.25e-1), np.arange(1, 3, 0.05)]),
    "amvd": np.concatenate([
        np.arange(1e-4, 1e-3, 0.25e-4), np.arange(1e-3, 1e-2, 0.25e-2),
        np.arange(1e-2, 1e-1, 0.25e-2), np.arange(1e-1, 2, 0.25e-1)]),
    "mbgtd": np.concatenate([
        np.arange(1e-3, 1e-2, 0.25e-3), np.arange(1e-2, 1e-1, 0.25e-2), np.arange(1e-1, 1, 0.25e-1)]),
}

def shrink_stances(zv: ArrayLike, margin: int) -> NDArray[np.bool_]:
    """Remove ``margin`` samples at both ends of every stance (run of True).

    Detectors tend to fire while the foot still rolls at heel strike and toe
    off; a ZUPT there loses real motion.  Runs shorter than ``2 margin + 1``
    vanish.

    Parameters
    ----------
    zv : array_like of bool, shape (N,)
        Zero-velocity flags.
    margin : int
        Samples removed at each end of every stance, >= 0.

    Returns
    -------
    numpy.ndarray of bool, shape (N,)
        The shrunk flags (a copy).

    Raises
    ------
    InvalidInputError
        If ``margin`` is negative.
    """
    z = np.asarray(zv, dtype=bool).copy()
    m = int(margin)
    if m < 0:
        raise InvalidInputError(f"margin must be >= 0 samples; got {margin}")
    if m == 0 or z.size == 0:
        return z
    out = np.zeros_like(z)
    for a, b in zip(*runs(np.ascontiguousarray(z))):
        if b - a > 2 * m:
            out[a + m:b - m] = True
    return out


def detect_zero_velocity(data: Any, detector: str = "shoe", threshold: float | ArrayLike | None = None, *,
                         window: int = 5, sigma_a: float = SIGMA_A, sigma_w: float = SIGMA_W,
                         g: float = G_PYSHOE, model: Any = None, margin_s: float = 0.0) -> DetectorResult:
    """Run a zero-velocity detector: ``zv[k] = T[k] < threshold``.

    Parameters
    ----------
    data : ImuData
        IMU recording (``t`` s, ``accel`` m/s², ``gyro`` rad/s, body FRD).
    detector : str, optional
        ``"shoe"``, ``"ared"``, ``"amvd"``, ``"mbgtd"``, ``"adaptive"``
        (:func:`motion_adaptive`), ``"freeacc"`` (:func:`free_acceleration`) or ``"lstm"`` (the shipped
        :class:`imunav.learn.LstmDetector`, or ``model`` when given).
    threshold : float or array_like, shape (N,), optional
        Scalar or per-sample thresholds, > 0, in the statistic's units; default
        :data:`DEFAULT_THRESHOLDS`.  For ``"lstm"`` the probability threshold
        (default 0.85); for ``"freeacc"`` m/s² (default 3).
    window : int, optional
        Window length in samples (default 5).
    sigma_a, sigma_w, g : float, optional
        SHOE's accelerometer (m/s²) and gyroscope (rad/s) noise and gravity (m/s²).
    model : LstmDetector, optional
        Learned detector used for ``"lstm"`` (default the shipped one).
    margin_s : float, optional
        Shrink every detected stance by this much, s, at both ends
        (:func:`shrink_stances`; 0 = the published detector output).

    Returns
    -------
    DetectorResult
        Flags, statistic, thresholds and the settings used.

    Raises
    ------
    InvalidInputError
        If a threshold is not finite and > 0, or ``margin_s`` is negative.
    """
    if threshold is not None:
        th = np.asarray(threshold, dtype=float)
        if not np.all(np.isfinite(th) & (th > 0)):
            raise InvalidInputError(
                f"detector threshold must be finite and > 0 (a statistic below it marks a stance); got {threshold!r}"
                if th.ndim == 0 else "detector thresholds must all be finite and > 0"
            )
    if not (np.isfinite(margin_s) and margin_s >= 0):
        raise InvalidInputError(f"margin_s must be finite and >= 0; got {margin_s}")
    res = _detect(data, detector, threshold, window, sigma_a, sigma_w, g, model)
    if margin_s > 0:
        fs = 1.0 / float(np.median(np.diff(np.asarray(data.t, dtype=float))))
        m = int(round(margin_s * fs))
        res = DetectorResult(shrink_stances(res.zv, m), res.statistic, res.threshold, res.detector,
                             {**res.params, "margin_s": margin_s})
    return res


def _detect(data: Any, detector: str, threshold: Any, window: int, sigma_a: float, sigma_w: float, g: float,
            model: Any) -> DetectorResult:
    name = detector.lower()
    if name == "adaptive":
        return motion_adaptive(data, window=window, sigma_a=sigma_a, sigma_w=sigma_w, g=g)
    if name == "freeacc":
        return free_acceleration(data, threshold=3.0 if threshold is None else float(threshold), g=g)
    if name == "lstm":
        det = model if model is not None else LstmDetector.load()
        return det.detect(data, threshold=0.85 if threshold is None else float(threshold))
    T = detector_statistic(data, name, window=window, sigma_a=sigma_a, sigma_w=sigma_w, g=g)
    gam = DEFAULT_THRESHOLDS[name] if threshold is None else threshold
    gam_arr = np.broadcast_to(np.asarray(gam, dtype=float), T.shape).copy() if np.ndim(gam) == 0 else np.asarray(gam, dtype=float)
    if gam_arr.shape != T.shape:
        raise ShapeError(f"threshold must be a scalar or have shape {T.shape}; got {gam_arr.shape}")
    params = {"window": int(window)}
    if name == "shoe":
        params.update(sigma_a=sigma_a, sigma_w=sigma_w, g=g)
    if np.ndim(gam) == 0:
        params["threshold"] = float(gam)
    return DetectorResult(T < gam_arr, T, gam_arr, name, params)


def motion_adaptive(data: Any, *, thresholds: tuple[float, float] = (1.0e7, 3.5e8),
                    split_rate: float = 4.0, intensity_window_s: float = 1.0, smooth_s: float = 1.0,
                    window: int = 5, sigma_a: float = SIGMA_A, sigma_w: float = SIGMA_W,
                    g: float = G_PYSHOE) -> DetectorResult:
    """Motion-adaptive SHOE: the threshold follows the gait intensity.

    The intensity is the moving RMS of the angular-rate norm over
    ``intensity_window_s``; where it exceeds ``split_rate`` (rad/s, running
    and brisk gait) the threshold is ``thresholds[1]``, else ``thresholds[0]``
    (walking).  The per-sample threshold is then smoothed with a
    ``smooth_s`` moving average, as in the motion-classification adaptive
    detector of Wagstaff et al. (IPIN 2017), with a rule in place of the SVM.

    Parameters
    ----------
    data : ImuData
        IMU recording (``t`` s, ``accel`` m/s², ``gyro`` rad/s, body FRD).
    thresholds : tuple of float, optional
        SHOE thresholds (walk, run), > 0.
    split_rate : float, optional
        Intensity (RMS angular rate, rad/s) above which the run threshold applies.
    intensity_window_s : float, optional
        Window of the moving RMS, s.
    smooth_s : float, optional
        Window of the moving average of the threshold, s.
    window : int, optional
        SHOE window length in samples.
    sigma_a, sigma_w, g : float, optional
        SHOE's accelerometer (m/s²) and gyroscope (rad/s) noise and gravity (m/s²).

    Returns
    -------
    DetectorResult
        Flags, SHOE statistic and the per-sample threshold (``detector = "adaptive"``).

    Raises
    ------
    InvalidInputError
        If ``thresholds`` is not two positive values.
    """
    a, w = _accel_gyro(data)
    t = np.asarray(data.t, dtype=float)
    if len(thresholds) != 2 or min(thresholds) <= 0:
        raise InvalidInputError(f"thresholds must be two positive values (walk, run); got {thresholds!r}")
    fs = 1.0 / float(np.median(np.diff(t))) if t.size > 1 else 1.0
    L = max(1, int(round(intensity_window_s * fs)))
    intensity = np.sqrt(moving_average(np.sum(w * w, axis=1), L))
    gam = np.where(intensity > split_rate, thresholds[1], thresholds[0]).astype(float)
    gam = moving_average(gam, max(1, int(round(smooth_s * fs))))
    T = shoe(a, w, window, sigma_a=sigma_a, sigma_w=sigma_w, g=g)
    params = {"window": int(window), "thresholds": list(thresholds), "split_rate": split_rate,
              "intensity_window_s": intensity_window_s, "smooth_s": smooth_s}
    return DetectorResult(T < gam, T, gam, "adaptive", params)


def free_acceleration(data: Any, *, threshold: float = 3.0, g: float = G_PYSHOE, kp: float = 1.0) -> DetectorResult:
    """Free-acceleration stance rule (x-io Gait-Tracking): ``T = |C_nb f + g^n|``.

    The foot is stationary while the specific force, rotated to the nav frame
    with an AHRS attitude and with gravity removed, is below ``threshold``
    (m/s², x-io: 3).  The attitude comes from :class:`imunav.attitude.Mahony`
    (gain ``kp`` rad/s, no integral term, no magnetometer); only its tilt
    matters, since ``|.|`` ignores the heading.  x-io widens each moving period
    by 0.1 s on both sides: ``detect_zero_velocity(..., margin_s=0.1)``.

    Parameters
    ----------
    data : ImuData
        IMU recording (``t`` s, ``accel`` m/s², ``gyro`` rad/s, body FRD).
    threshold : float, optional
        Free-acceleration threshold, m/s², finite and > 0 (default 3).
    g : float, optional
        Gravity magnitude, m/s² (NED: gravity is ``[0, 0, g]``).
    kp : float, optional
        Proportional gain of the Mahony filter, rad/s.

    Returns
    -------
    DetectorResult
        Flags, ``T`` (m/s²) and the threshold (``detector = "freeacc"``).

    Raises
    ------
    InvalidInputError
        If ``threshold`` is not finite and > 0.
    """

    if not (threshold > 0 and np.isfinite(threshold)):
        raise InvalidInputError(f"threshold must be a finite free acceleration > 0 m/s^2; got {threshold!r}")
    a, _ = _accel_gyro(data)
    q = Mahony(kp=kp, ki=0.0).run(data, use_mag=False).q_nb
    T = np.linalg.norm(quat_rotate(q, a) + np.array([0.0, 0.0, g]), axis=1)
    gam = np.full(T.shape, float(threshold))
    return DetectorResult(T < gam, T, gam, "freeacc", {"threshold": float(threshold), "g": g, "kp": kp})


@dataclass(frozen=True)
class ThresholdSearch(Result):
    """Result of :func:`optimize_threshold`: error per grid threshold and the best one.

    Attributes
    ----------
    detector : str
        Detector name.
    thresholds : numpy.ndarray, shape (K,)
        The grid searched, in the statistic's units.
    errors : numpy.ndarray, shape (K,)
        Metric value (m for the default 2-D error) at each threshold.
    best_threshold : float
        Threshold with the smallest error (ties to the larger).
    best_error : float
        Its error.
    zv : numpy.ndarray of bool, shape (N,)
        Flags of the best threshold.
    """

    detector: str
    thresholds: Array
    errors: Array
    best_threshold: float
    best_error: float
    zv: NDArray[np.bool_]

    def to_dict(self) -> dict[str, Any]:
        """The search as plain JSON types (without the flags).

        Returns
        -------
        dict
            Keys ``detector``, ``thresholds``, ``errors``, ``best_threshold``, ``best_error``.
        """
        return {"detector": self.detector, "thresholds": self.thresholds.tolist(), "errors": self.errors.tolist(),
                "best_threshold": self.best_threshold, "best_error": self.best_error}


def optimize_threshold(data: Any, reference: ArrayLike, detector: str = "shoe",
                       thresholds: Sequence[float] | None = None, *, window: int = 5,
                       metric: Callable[[Array, Array], float] | None = None,
                       config: Any = None) -> ThresholdSearch:
    """Grid-search the detector threshold that minimises the position error.

    For each threshold the ZUPT INS (:meth:`imunav.ins.ZuptFilter.run`, with
    ``config``) runs with the detector output and ``metric(estimate,
    reference)`` (default :func:`imunav.ins.zupt.metrics.error_2d`) scores it; ties
    go to the larger threshold (as in the published search).  ``reference``
    is the (N, 3) reference position, one row per IMU sample.

    Parameters
    ----------
    data : ImuData
        IMU recording (``t`` s, ``accel`` m/s², ``gyro`` rad/s, body FRD).
    reference : array_like, shape (N, 2) or (N, 3)
        Reference position, m (NED), one row per IMU sample.
    detector : {"shoe", "ared", "amvd", "mbgtd"}, optional
        Detector whose threshold is searched.
    thresholds : sequence of float, optional
        Grid to search; default :data:`THRESHOLD_GRIDS` of the detector.
    window : int, optional
        Window length in samples.
    metric : callable, optional
        ``metric(estimate, reference) -> float``; default :func:`imunav.ins.zupt.metrics.error_2d`.
    config : ZuptConfig, optional
        Settings of the ZUPT INS.

    Returns
    -------
    ThresholdSearch
        Error per threshold and the best one.

    Raises
    ------
    InvalidInputError
        If ``thresholds`` is empty or not 1-D.
    ShapeError
        If ``reference`` does not have one row per IMU sample.
    """

    name = detector.lower()
    grid = THRESHOLD_GRIDS[name] if thresholds is None else np.asarray(thresholds, dtype=float)
    if grid.ndim != 1 or grid.size == 0:
        raise InvalidInputError("thresholds must be a non-empty 1-D sequence")
    ref = np.asarray(reference, dtype=float)
    if ref.ndim != 2 or ref.shape[0] != len(data.t) or ref.shape[1] < 2:
        raise ShapeError(f"reference must be (N, 2|3) with N={len(data.t)} rows (one per IMU sample); got {ref.shape}")
    metric = error_2d if metric is None else metric
    T = detector_statistic(data, name, window=window)
    errs = np.empty(grid.size)
    best = (np.inf, 0.0, None)
    for i, gam in enumerate(grid):
        zv = T < gam
        res = ZuptFilter(config).run(data, zv)
        errs[i] = metric(res.position, ref)
        if errs[i] <= best[0]:
            best = (errs[i], float(gam), zv)
    return ThresholdSearch(name, grid, errs, best[1], float(best[0]), best[2])
