"""Rate-table calibration of the gyro scale / misalignment matrix.

After Y. Günhan, *Ataletsel ölçüm birimi hatalarının belirlenmesi ve düzeltilmesi* (Detection and
compensation of inertial measurement unit errors), MSc thesis, Hacettepe University, 2014, §4.1.2-4.1.3,
eq. (20): after removing the bias and the g-dependent term found in the static test, the per-step mean
gyro outputs are regressed on the table rate vectors without intercept::

    ω̃_k − b_g − G f_k = T_g ω_k        →   T_g = W̃ Wᵀ (W Wᵀ)⁻¹

``ω_k`` is the table rate in body axes plus, when the latitude is given, the
vertical Earth rate ``Ω_e sin φ`` along the body up direction (it matters at
the low rates of the profile; the horizontal part averages out on a rotating
table).  ``intercept=True`` adds a bias term, for a rate run powered up
separately from the static run (the thesis does not say whether the two runs share a power-up).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.calib._lsq import linear_fit, paired_means
from imunav.calib._noisecov import segment_mean_covariances
from imunav.calib._segments import as_time, assign_to_windows, check_saturation, segment_means, steady_segments
from imunav.calib.model import ImuCalibration
from imunav.calib.result import CalibrationResult
from imunav.calib.static import _gravity, fit_gyro_static
from imunav.earth import OMEGA_E
from imunav.errors import InsufficientDataError, ShapeError

__all__ = ["ratetable_from_means", "ratetable", "combine"]

Array = NDArray[np.float64]


def ratetable_from_means(
    rates: ArrayLike,
    gyro_means: ArrayLike,
    f_ref: ArrayLike | None = None,
    *,
    base: ImuCalibration | None = None,
    intercept: bool = False,
    latitude: float | None = None,
    up: ArrayLike | None = None,
    segments: Array | None = None,
    serial: bool = True,
    gyro_covs: list[Array] | None = None,
) -> CalibrationResult:
    """Least-squares gyro matrix from per-step means (Günhan 2014, eq. 20).

    Parameters
    ----------
    rates : array_like, shape (K, 3)
        Table rate of each step in body axes, rad/s.
    gyro_means : array_like, shape (K, 3)
        Mean raw gyro output per step, raw units.
    f_ref : array_like, shape (K, 3), optional
        Body specific force during each step, m/s² (for ``G f``).
    base : ImuCalibration, optional
        Calibration from the static test (gyro bias, g-sensitivity and the
        accelerometer part are taken from it); default: zero bias, no ``G``.
    intercept : bool
        Also estimate a bias (separate power-up).
    latitude : float, optional
        Geodetic latitude, rad; with ``up``, adds the vertical Earth rate ``Ω_e sin φ u_k`` to the reference.
    up : array_like, shape (K, 3), optional
        Body up vector during each step.
    segments : numpy.ndarray, optional
        (K, 2) sample ranges of the steps, recorded in the result.
    serial : bool
        Allow for the correlation a drifting bias leaves between consecutive steps (AR(1) feasible GLS).
    gyro_covs : list of numpy.ndarray, optional
        Per-axis (K, K) covariance of the step means (generalised least squares).

    Returns
    -------
    CalibrationResult
        ``base`` with the estimated gyro matrix (and bias with ``intercept``), standard errors and residuals.

    Raises
    ------
    ShapeError
        If the arrays are not (K, 3) with the same K.
    InsufficientDataError
        With too few steps for the parameters.
    DegenerateGeometryError
        If the rates do not excite every axis.
    """
    W, Y = paired_means(rates, "rates", gyro_means, "gyro_means")
    base = base if base is not None else ImuCalibration()
    K = W.shape[0]
    if f_ref is not None:
        f = np.asarray(f_ref, float)
        if f.shape != W.shape:
            raise ShapeError(f"f_ref {f.shape} must match rates {W.shape}")
        Y = Y - f @ base.g_sensitivity.T
    if not intercept:
        Y = Y - base.gyro_bias
    Wt = W.copy()
    if latitude is not None:
        if up is None:
            raise InsufficientDataError("Earth-rate handling needs the body up vector of every step (up=...)")
        u = np.asarray(up, float)
        Wt = Wt + OMEGA_E * np.sin(latitude) * u / np.linalg.norm(u, axis=1)[:, None]
    X = np.hstack([Wt, np.ones((K, 1))]) if intercept else Wt
    fit = linear_fit(X, Y, what="rate-table fit", serial=serial, covs=gyro_covs)
    T = fit.theta[:3].T
    stderr = dict(base.stderr)
    stderr["gyro_matrix"] = fit.stderr[:3].T
    gb = base.gyro_bias
    if intercept:
        gb = fit.theta[3]
        stderr["gyro_bias"] = fit.stderr[3]
    cal = base.with_(gyro_matrix=T, gyro_bias=gb, stderr=stderr, meta={**base.meta, "method_rate": "ratetable"})
    info: dict[str, Any] = {
        "n_steps": K, "gyro_residual_sigma": fit.sigma.tolist(), "intercept": intercept, "_cov_gyro_rate": fit.cov,
    }
    segs = {} if segments is None else {"rate": np.asarray(segments)}
    return CalibrationResult(cal, stderr, {"gyro_rate": fit.residuals}, {"gyro_rate": fit.cond}, segs, "ratetable", info)


def ratetable(
    data: Any,
    rates: ArrayLike,
    up: ArrayLike | None = None,
    *,
    windows: ArrayLike | None = None,
    base: ImuCalibration | None = None,
    gravity: float | None = None,
    latitude: float | None = None,
    intercept: bool = False,
    window_s: float = 1.0,
    min_duration_s: float = 2.0,
    trim_s: float = 0.5,
    full_scale: float | None = None,
    fs: float | None = None,
    serial: bool = True,
    noise_model: Any = None,
) -> CalibrationResult:
    """Rate-table calibration of a recording (e.g. the 120-step test of Günhan 2014, §4.1.2).

    Parameters
    ----------
    data : ImuData
        The recording (or any object with ``t``, ``accel``, ``gyro`` (N, 3)).
    rates : array_like or Segments
        (K, 3) body-frame table rate of each step (rad/s) in time order,
        or an :class:`imunav.sim.Segments` table (its rate rows give rates, up and windows).
    up : array_like, shape (K, 3), optional
        Body up vector during each step (gives ``f = g u``).
    windows : array_like, shape (K, 2), optional
        Nominal step times, s (a hint; the constant-rate samples inside are found from the data).
    base : ImuCalibration, optional
        Calibration from the static test.
    gravity : float, optional
        Local gravity, m/s² (default: normal gravity at ``latitude``, else G0).
    latitude : float, optional
        Geodetic latitude, rad (vertical Earth rate in the reference).
    intercept : bool
        Also estimate a gyro bias.
    window_s, min_duration_s, trim_s : float
        Constant-rate detector settings, s.
    full_scale : float, optional
        Gyro range in raw units; steps touching it are refused.
    fs : float, optional
        Sample rate, Hz, when ``data`` has no time stamps.
    serial : bool
        Allow for correlation between consecutive steps.
    noise_model : ImuErrorModel, optional
        Characterised gyro noise for generalised least squares (see :func:`imunav.calib.multiposition`).

    Returns
    -------
    CalibrationResult
        The calibration with the gyro matrix estimated.

    Raises
    ------
    InsufficientDataError
        If fewer constant-rate segments than steps are found.
    SaturationError
        If a step touches the full-scale range.
    ShapeError
        If ``rates``, ``up`` or ``windows`` have the wrong shape.
    """
    if hasattr(rates, "kind") and hasattr(rates, "axis_b"):  # an imunav.sim Segments table
        st = rates.select("rate")
        rates, up = st.rate[:, None] * st.axis_b, st.up_b
        windows = np.stack([st.t_start, st.t_stop], axis=1) if windows is None else windows
    if up is None:
        raise InsufficientDataError("rate-table calibration needs the body up vector of every step (up=...)")
    gyro = np.asarray(data.gyro, float)
    accel = np.asarray(data.accel, float)
    t, fs_ = as_time(getattr(data, "t", None), gyro.shape[0], fs)
    W = np.asarray(rates, float)
    u = np.asarray(up, float)
    if u.shape != W.shape:
        raise ShapeError(f"up {u.shape} must match rates {W.shape}")
    steady, _ = steady_segments(np.hstack([accel, gyro]), fs_, window_s=window_s, min_duration_s=min_duration_s, trim_s=trim_s)
    if windows is not None:
        segs = assign_to_windows(steady, t, np.asarray(windows, float), what="rate-table calibration")
    else:
        if len(steady) != len(W):
            raise InsufficientDataError(
                f"rate-table calibration: found {len(steady)} constant-rate segments but {len(W)} rates were given; "
                "pass the step time windows (windows=...)"
            )
        segs = steady
    check_saturation(gyro, full_scale, segs, what="gyroscope")
    gm, _, _ = segment_means(gyro, segs)
    g = _gravity(gravity, latitude)
    f = g * u / np.linalg.norm(u, axis=1)[:, None]
    gc = None
    if noise_model is not None:
        gc = segment_mean_covariances(
            noise_model.gyro, t[segs[:, 0]], t[segs[:, 1] - 1] + 1.0 / fs_, segs[:, 1] - segs[:, 0], fs_
        )
    return ratetable_from_means(
        W, gm, f, base=base, intercept=intercept, latitude=latitude, up=u, segments=segs, serial=serial,
        gyro_covs=gc,
    )


def combine(static: CalibrationResult, rate: CalibrationResult) -> CalibrationResult:
    """Merge a static (accelerometer, gyro bias, G) and a rate-table result.

    When the static fit removed the Earth rate, it is seen through the gyro
    matrix (``ω̃ = T_g ω_ie + b_g + G f``), unknown until the rate table; the
    static gyro fit is then repeated with ``T_g ω_ie``.

    Parameters
    ----------
    static : CalibrationResult
        Result of :func:`imunav.calib.multiposition`.
    rate : CalibrationResult
        Result of :func:`ratetable` with ``base`` from the static result.

    Returns
    -------
    CalibrationResult
        The full model with the standard errors of both fits.
    """

    stderr = {**static.stderr, **{k: v for k, v in rate.stderr.items() if k in ("gyro_matrix",)}}
    residuals = {**static.residuals, **rate.residuals}
    inputs = static.info.get("_gyro_static_inputs")
    extra: dict[str, Any] = {}
    scal = static.calibration
    if inputs is not None and inputs[2] is not None:
        f, Gm, er, mode, serial, covs = inputs
        Tg = rate.calibration.gyro_matrix
        gb, G, segb, seG, gres, _, gcov = fit_gyro_static(
            f, Gm, g_sensitivity=mode, earth_rate_b=er @ Tg.T, serial=serial, covs=covs
        )
        scal = scal.with_(gyro_bias=gb, g_sensitivity=G)
        stderr.update(gyro_bias=segb, g_sensitivity=seG)
        residuals["gyro_static"] = gres
        extra["_cov_gyro_static"] = (mode, gcov)
    if rate.info.get("intercept"):
        stderr["gyro_bias"] = rate.stderr["gyro_bias"]
    cal = scal.with_(
        gyro_matrix=rate.calibration.gyro_matrix,
        gyro_bias=rate.calibration.gyro_bias if rate.info.get("intercept") else scal.gyro_bias,
        stderr=stderr,
        meta={"method": "multiposition+ratetable"},
    )
    return CalibrationResult(
        cal, stderr, residuals, {**static.condition, **rate.condition},
        {**static.segments, **rate.segments}, "multiposition+ratetable", {**static.info, **rate.info, **extra},
    )
