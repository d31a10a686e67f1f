"""Static multi-position calibration: six-position closed form and least squares.

After Y. Günhan, *Ataletsel ölçüm birimi hatalarının belirlenmesi ve düzeltilmesi* (Detection and
compensation of inertial measurement unit errors), MSc thesis, Hacettepe University, 2014, §4.1.1 and
§4.1.3 (eqs. 17-19) and Appendix A (six-position test, eqs. 31-42); E. Atasoy, *Estimation and analysis
of error parameters of attitude-heading reference system sensors* (in Turkish), MSc thesis, Başkent
University, §5.1.  Multi-position designs as in D. Tedaldi, A. Pretto, E. Menegatti, "A robust and easy
to implement method for IMU calibration without external equipments", IEEE ICRA 2014.

Accelerometer: with the reference specific force ``f_k`` of position k (from
the known orientation, ``|f| = g``) and the per-position mean ``ã_k``,
``ã_k = T_a f_k + b_a`` is a linear regression on ``X = [f_k, 1]`` (eq. 18).

Gyroscope (static): ``ω̃_k = b_g + G f_k + ω_ie,k`` with the Earth rate
``ω_ie`` either neglected (thesis) or removed: fully when the orientations
are attitudes ``q_nb`` and the latitude is known, else its vertical part
``Ω_e sin φ`` along the body "up" direction (the thesis says only "Earth rate").  ``G`` is
diagonal (eq. 19, fitted per axis as ``ω̃_i = G_ii f_i + b_i``), full, or
omitted.  The gyro scale matrix needs a rate table (:mod:`.ratetable`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.calib._lsq import design_condition, linear_fit, paired_means
from imunav.calib._noisecov import segment_mean_covariances
from imunav.calib._segments import (
    as_time,
    assign_to_windows,
    check_saturation,
    segment_means,
    steady_segments,
)
from imunav.calib.model import ImuCalibration
from imunav.calib.result import CalibrationResult
from imunav.earth import OMEGA_E, normal_gravity
from imunav.errors import DegenerateGeometryError, InsufficientDataError, InvalidInputError, NonFiniteError, ShapeError
from imunav.rotation import dcm_from_quat
from imunav.units import G0

__all__ = [
    "reference_specific_force",
    "earth_rate_body",
    "fit_accel_positions",
    "fit_gyro_static",
    "multiposition_from_means",
    "multiposition",
    "six_position",
]

Array = NDArray[np.float64]


def _gravity(gravity: float | None, latitude: float | None, height: float = 0.0) -> float:
    if gravity is not None:
        return float(gravity)
    if latitude is not None:
        return float(normal_gravity(latitude, height))
    return G0


def reference_specific_force(orientations: ArrayLike, gravity: float = G0) -> Array:
    """Body specific force at rest for each orientation.

    Up vectors give ``f_b = g u_b`` (the specific force at rest points up); attitudes give
    ``f_b = C_bn (0, 0, −g)`` in NED.

    Parameters
    ----------
    orientations : array_like, shape (K, 3) or (K, 4)
        Body-frame "up" unit vectors (normalised here), or attitudes ``q_nb`` (NED), one per position.
    gravity : float
        Local gravity magnitude, m/s².

    Returns
    -------
    numpy.ndarray, shape (K, 3)
        Specific force in body axes (FRD), m/s².

    Raises
    ------
    ShapeError
        If ``orientations`` is not (K, 3) or (K, 4).
    InvalidInputError
        If an up vector is zero or not finite.
    """
    o = np.asarray(orientations, dtype=float)
    if o.ndim != 2 or o.shape[1] not in (3, 4):
        raise ShapeError(f"orientations must be (K, 3) up vectors or (K, 4) quaternions, got {o.shape}")
    if o.shape[1] == 3:
        n = np.linalg.norm(o, axis=1)
        if np.any(n == 0):
            raise InvalidInputError(f"orientation rows {np.flatnonzero(n == 0)[:10].tolist()} are zero vectors")
        return gravity * o / n[:, None]

    C = dcm_from_quat(o)  # C_nb
    return np.einsum("kji,j->ki", C, np.array([0.0, 0.0, -gravity]))


def earth_rate_body(orientations: ArrayLike, latitude: float | None) -> Array | None:
    """Earth rate in body axes per position (None when ``latitude`` is None).

    Quaternion orientations give the full vector ``C_bn ω_ie^n``; up vectors
    only the vertical component ``Ω_e sin φ · u_b`` (the heading is unknown).

    Parameters
    ----------
    orientations : array_like, shape (K, 3) or (K, 4)
        Body-frame "up" unit vectors (normalised here), or attitudes ``q_nb`` (NED), one per position.
    latitude : float or None
        Geodetic latitude, rad.

    Returns
    -------
    numpy.ndarray, shape (K, 3), or None
        Earth rate in body axes, rad/s.
    """
    if latitude is None:
        return None
    o = np.asarray(orientations, dtype=float)
    if o.shape[1] == 4:
        w_n = OMEGA_E * np.array([np.cos(latitude), 0.0, -np.sin(latitude)])
        return np.einsum("kji,j->ki", dcm_from_quat(o), w_n)
    u = o / np.linalg.norm(o, axis=1)[:, None]
    return OMEGA_E * np.sin(latitude) * u


def fit_accel_positions(
    f_ref: Array, accel_means: Array, serial: bool = True, covs: list[Array] | None = None
) -> tuple[Array, Array, Array, Array, Any]:
    """Least squares of ``ã = T f + b`` over the positions (Günhan 2014, eq. 18).

    Parameters
    ----------
    f_ref : array_like, shape (K, 3)
        Reference specific force of each position, body frame, m/s² (:func:`reference_specific_force`).
    accel_means : numpy.ndarray, shape (K, 3)
        Mean accelerometer output of each position, raw units.
    serial : bool
        Allow for the correlation a drifting bias leaves between consecutive positions (AR(1) feasible GLS).
    covs : list of numpy.ndarray, optional
        Per-axis (K, K) covariance of the position means (generalised least squares).

    Returns
    -------
    T : numpy.ndarray, shape (3, 3)
        Scale-factor / misalignment matrix, raw units per m/s².
    b : numpy.ndarray, shape (3,)
        Bias, raw units.
    se_T, se_b : numpy.ndarray
        Their standard errors.
    fit : object
        The per-axis fit (residuals, condition, parameter covariance).
    """
    K = f_ref.shape[0]
    X = np.hstack([f_ref, np.ones((K, 1))])
    fit = linear_fit(X, accel_means, what="accelerometer multi-position fit", serial=serial, covs=covs)
    T = fit.theta[:3].T
    b = fit.theta[3]
    return T, b, fit.stderr[:3].T, fit.stderr[3], fit


def fit_gyro_static(
    f_ref: Array,
    gyro_means: Array,
    *,
    g_sensitivity: str = "diagonal",
    earth_rate_b: Array | None = None,
    serial: bool = True,
    covs: list[Array] | None = None,
) -> tuple[Array, Array, Array, Array, Array, float, Array]:
    """Static gyro fit (Günhan 2014, eq. 19): bias and g-sensitivity.

    Parameters
    ----------
    f_ref : array_like, shape (K, 3)
        Reference specific force of each position, body frame, m/s² (:func:`reference_specific_force`).
    gyro_means : numpy.ndarray, shape (K, 3)
        Mean gyro output of each position, raw units.
    g_sensitivity : {"diagonal", "full", "none"}
        Form of ``G``.
    earth_rate_b : numpy.ndarray, shape (K, 3), optional
        Earth rate in body axes to remove, rad/s (:func:`earth_rate_body`).
    serial : bool
        Allow for the correlation a drifting bias leaves between consecutive positions (AR(1) feasible GLS).
    covs : list of numpy.ndarray, optional
        Per-axis (K, K) covariance of the position means.

    Returns
    -------
    b : numpy.ndarray, shape (3,)
        Bias, raw units.
    G : numpy.ndarray, shape (3, 3)
        g-sensitivity, raw units per m/s².
    se_b, se_G : numpy.ndarray
        Their standard errors.
    residuals : numpy.ndarray, shape (K, 3)
        Residual of each position, raw units.
    condition : float
        Condition number of the (column-scaled) design.
    cov : numpy.ndarray
        Per-axis parameter covariance: (3, 2, 2) of ``[G_ii, b_i]`` for "diagonal", (3, 4, 4) of
        ``[G_i:, b_i]`` for "full", (3, 1, 1) for "none".

    Raises
    ------
    InvalidInputError
        If ``g_sensitivity`` is unknown.
    """
    y = gyro_means - (earth_rate_b if earth_rate_b is not None else 0.0)
    K = f_ref.shape[0]
    G = np.zeros((3, 3))
    seG = np.zeros((3, 3))
    b = np.zeros(3)
    seb = np.zeros(3)
    res = np.zeros_like(y)
    cond = 1.0
    if g_sensitivity == "none":
        fit = linear_fit(np.ones((K, 1)), y, what="gyro static fit (bias only)", serial=serial, covs=covs)
        b, seb, res, pcov = fit.theta[0], fit.stderr[0], fit.residuals, fit.cov
    elif g_sensitivity == "diagonal":
        pcov = np.zeros((3, 2, 2))
        for i in range(3):
            X = np.stack([f_ref[:, i], np.ones(K)], axis=1)
            fit = linear_fit(
                X, y[:, i], what=f"gyro static fit, axis {'xyz'[i]}", serial=serial,
                covs=None if covs is None else [covs[i]],
            )
            G[i, i], b[i] = fit.theta[:, 0]
            seG[i, i], seb[i] = fit.stderr[:, 0]
            res[:, i] = fit.residuals[:, 0]
            pcov[i] = fit.cov[0]
            cond = max(cond, fit.cond)
    elif g_sensitivity == "full":
        X = np.hstack([f_ref, np.ones((K, 1))])
        fit = linear_fit(X, y, what="gyro static fit (full g-sensitivity)", serial=serial, covs=covs)
        G, b, seG, seb, res, cond = fit.theta[:3].T, fit.theta[3], fit.stderr[:3].T, fit.stderr[3], fit.residuals, fit.cond
        pcov = fit.cov
    else:
        raise InvalidInputError(f"g_sensitivity must be 'diagonal', 'full' or 'none', not {g_sensitivity!r}")
    return b, G, seb, seG, res, cond, pcov


def multiposition_from_means(
    f_ref: ArrayLike,
    accel_means: ArrayLike,
    gyro_means: ArrayLike | None = None,
    *,
    earth_rate_b: ArrayLike | None = None,
    g_sensitivity: str = "diagonal",
    segments: Array | None = None,
    serial: bool = True,
    accel_covs: list[Array] | None = None,
    gyro_covs: list[Array] | None = None,
) -> CalibrationResult:
    """Multi-position least squares on per-position means (any K ≥ 5 positions).

    The gyro matrix stays identity (a static test cannot excite it); combine
    with :func:`imunav.calib.ratetable.ratetable` for the full model.

    Parameters
    ----------
    f_ref : array_like, shape (K, 3)
        Reference specific force of each position, body frame, m/s² (:func:`reference_specific_force`).
    accel_means : array_like, shape (K, 3)
        Mean accelerometer output of each position, raw units.
    gyro_means : array_like, shape (K, 3), optional
        Mean gyro output of each position, raw units.
    earth_rate_b : array_like, shape (K, 3), optional
        Earth rate in body axes to remove from the gyro means, rad/s.
    g_sensitivity : {"diagonal", "full", "none"}
        Form of ``G``.
    segments : numpy.ndarray, optional
        (K, 2) sample ranges of the positions, recorded in the result.
    serial : bool
        Treat the positions as a time sequence and allow for the correlation a drifting bias leaves between
        neighbours (AR(1) feasible GLS); False for positions recorded independently.
    accel_covs, gyro_covs : list of numpy.ndarray, optional
        Per-axis (K, K) covariance of the position means from a characterised noise model (white noise +
        Gauss-Markov drift): generalised least squares with exact standard errors (see :func:`multiposition`).

    Returns
    -------
    CalibrationResult
        Accelerometer bias and matrix, gyro bias and g-sensitivity, with standard errors, residuals and the
        condition of each design.

    Raises
    ------
    ShapeError
        If the arrays are not (K, 3) with the same K.
    InsufficientDataError
        With too few positions for the parameters.
    DegenerateGeometryError
        If the positions do not excite every axis.
    """
    f, A = paired_means(f_ref, "f_ref", accel_means, "accel_means")
    T, b, seT, seb, fit = fit_accel_positions(f, A, serial, accel_covs)
    stderr: dict[str, Array] = {"accel_matrix": seT, "accel_bias": seb}
    residuals = {"accel": fit.residuals}
    cond = {"accel": fit.cond}
    info: dict[str, Any] = {
        "n_positions": int(f.shape[0]),
        "accel_residual_sigma": fit.sigma.tolist(),
        "accel_residual_rho": None if fit.rho is None else fit.rho.tolist(),
        "_cov_accel": fit.cov,
    }
    gb, G = np.zeros(3), np.zeros((3, 3))
    if gyro_means is not None:
        Gm = np.asarray(gyro_means, float)
        if Gm.shape != f.shape:
            raise ShapeError(f"gyro_means {Gm.shape} must match f_ref {f.shape}")
        er = None if earth_rate_b is None else np.asarray(earth_rate_b, float)
        gb, G, segb, seG, gres, gcond, gcov = fit_gyro_static(
            f, Gm, g_sensitivity=g_sensitivity, earth_rate_b=er, serial=serial, covs=gyro_covs
        )
        stderr.update(gyro_bias=segb, g_sensitivity=seG)
        residuals["gyro_static"] = gres
        cond["gyro_static"] = gcond
        info["_cov_gyro_static"] = (g_sensitivity, gcov)
        # kept for combine(): the Earth rate is seen through T_g, known only after the rate table
        info["_gyro_static_inputs"] = (f, Gm, er, g_sensitivity, serial, gyro_covs)
    cal = ImuCalibration(
        accel_bias=b, accel_matrix=T, gyro_bias=gb, g_sensitivity=G, stderr=stderr,
        meta={"method": "multiposition", "n_positions": int(f.shape[0])},
    )
    segs = {} if segments is None else {"static": np.asarray(segments)}
    return CalibrationResult(cal, stderr, residuals, cond, segs, "multiposition", info)


def _static_means(
    data: Any, orientations: Array, windows: ArrayLike | None, *, window_s: float, min_duration_s: float,
    trim_s: float, full_scale: tuple[float | None, float | None], fs: float | None,
) -> tuple[Array, Array, NDArray[np.int64], Array, float]:
    accel = np.asarray(data.accel, float)
    gyro = np.asarray(data.gyro, float)
    t, fs_ = as_time(getattr(data, "t", None), accel.shape[0], fs)
    steady, thr = steady_segments(
        np.hstack([accel, gyro]), fs_, window_s=window_s, min_duration_s=min_duration_s, trim_s=trim_s
    )
    K = orientations.shape[0]
    if windows is not None:
        w = np.asarray(windows, float)
        if w.shape != (K, 2):
            raise ShapeError(f"windows must be (K, 2) = ({K}, 2) start/stop times, got {w.shape}")
        segs = assign_to_windows(steady, t, w, what="multi-position calibration")
    else:
        if len(steady) != K:
            raise InsufficientDataError(
                f"multi-position calibration: found {len(steady)} static segments but {K} orientations were "
                "given; pass the time windows of the positions (windows=...) or adjust window_s/min_duration_s"
            )
        segs = steady
    check_saturation(accel, full_scale[0], segs, what="accelerometer")
    check_saturation(gyro, full_scale[1], segs, what="gyroscope")
    am, _, _ = segment_means(accel, segs)
    gm, _, _ = segment_means(gyro, segs)
    return am, gm, segs, t, fs_


def multiposition(
    data: Any,
    orientations: ArrayLike,
    *,
    windows: ArrayLike | None = None,
    gravity: float | None = None,
    latitude: float | None = None,
    g_sensitivity: str = "diagonal",
    window_s: float = 1.0,
    min_duration_s: float = 2.0,
    trim_s: float = 0.5,
    full_scale: tuple[float | None, float | None] = (None, None),
    fs: float | None = None,
    serial: bool = True,
    noise_model: Any = None,
) -> CalibrationResult:
    """Multi-position static calibration of a recording (e.g. the 100-position test of Günhan 2014, §4.1.1).

    Parameters
    ----------
    data : ImuData
        The recording (or any object with ``t``, ``accel``, ``gyro`` (N, 3)); raw or SI units.
    orientations : array_like or Segments
        (K, 3) body up vectors or (K, 4) ``q_nb``, one per position in time order,
        or an :class:`imunav.sim.Segments` table (its static rows give ``q_nb`` and ``windows``).
    windows : array_like, shape (K, 2), optional
        Nominal start/stop times of the positions, s (a hint: the
        static samples inside each window are found from the data); without
        it, exactly K static segments must be detected.
    gravity : float, optional
        Local gravity, m/s² (default: normal gravity at ``latitude``, else G0).
    latitude : float, optional
        Geodetic latitude, rad; enables Earth-rate removal in the gyro static fit.
    g_sensitivity : {"diagonal", "full", "none"}
        ``"diagonal"`` (thesis), ``"full"`` or ``"none"``.
    window_s, min_duration_s, trim_s : float
        Static detector settings, s: window of the variance test, shortest static segment, and the span
        trimmed at each end of a segment.
    full_scale : tuple of (float or None)
        (accel, gyro) ranges in raw units; segments touching them are refused.
    fs : float, optional
        Sample rate, Hz, when ``data`` has no time stamps.
    serial : bool
        Allow for correlation between consecutive positions (AR(1) GLS).
    noise_model : ImuErrorModel, optional
        Characterised noise (an :class:`imunav.sim.ImuErrorModel`
        or any object with ``accel`` / ``gyro`` carrying ``noise_density`` and
        ``bias_instability``, as found by Allan analysis): the exact covariance
        of the position means (white noise + Gauss-Markov drift across the
        session's timing) is used for generalised least squares, so standard
        errors account for the time-correlated bias.

    Returns
    -------
    CalibrationResult
        The calibration (gyro matrix identity), standard errors, residuals, the segments used.

    Raises
    ------
    InsufficientDataError
        If fewer static segments than positions are found, or a segment is too short.
    SaturationError
        If a segment touches the full-scale range.
    ShapeError
        If ``orientations`` or ``windows`` have the wrong shape.
    DegenerateGeometryError
        If the positions do not excite every axis.
    """
    if hasattr(orientations, "kind") and hasattr(orientations, "q_nb"):  # an imunav.sim Segments table
        st = orientations.select("static")
        orientations = st.q_nb
        windows = np.stack([st.t_start, st.t_stop], axis=1) if windows is None else windows
    o = np.asarray(orientations, float)
    g = _gravity(gravity, latitude)
    f_ref = reference_specific_force(o, g)
    am, gm, segs, t, fs_ = _static_means(
        data, o, windows, window_s=window_s, min_duration_s=min_duration_s, trim_s=trim_s,
        full_scale=full_scale, fs=fs,
    )
    ac = gc = None
    if noise_model is not None:
        t0, t1, n = t[segs[:, 0]], t[segs[:, 1] - 1] + 1.0 / fs_, segs[:, 1] - segs[:, 0]
        ac = segment_mean_covariances(noise_model.accel, t0, t1, n, fs_)
        gc = segment_mean_covariances(noise_model.gyro, t0, t1, n, fs_)
    res = multiposition_from_means(
        f_ref, am, gm, earth_rate_b=earth_rate_body(o, latitude), g_sensitivity=g_sensitivity, segments=segs,
        serial=serial, accel_covs=ac, gyro_covs=gc,
    )
    res.info["gravity"] = g
    return res


def six_position(
    accel_means: ArrayLike,
    gyro_means: ArrayLike | None = None,
    f_ref: ArrayLike | None = None,
    *,
    gravity: float = G0,
    latitude: float | None = None,
) -> CalibrationResult:
    """Six-position test, closed form (Günhan 2014, Appendix A, eqs. 31-42).

    ``accel_means`` in the order +x up, −x up, +y up, −y up, +z up, −z up
    (or any order if ``f_ref`` gives the reference specific forces):
    ``B_i = (ã_i,up + ã_i,down)/2``, ``T_ii = (ã_i,up − ã_i,down)/(2g)``,
    ``T_ij = (ã_i|j up − ã_i|j down)/(2g)``.  The gyro bias is the mean over
    the six poses (vertical Earth rate removed when ``latitude`` is given);
    g-sensitivity is not identifiable from six poses and is left zero.

    Standard errors come from the 2 residual degrees of freedom per axis of
    the equivalent least-squares fit (no misalignment-free assumption).

    Parameters
    ----------
    accel_means : array_like, shape (6, 3)
        Mean accelerometer output of each pose, raw units.
    gyro_means : array_like, shape (6, 3), optional
        Mean gyro output of each pose, raw units.
    f_ref : array_like, shape (6, 3), optional
        Reference specific force of each pose, m/s² (default: the order above).
    gravity : float
        Local gravity, m/s².
    latitude : float, optional
        Geodetic latitude, rad, to remove the vertical Earth rate from the gyro bias.

    Returns
    -------
    CalibrationResult
        Accelerometer bias and matrix, gyro bias, with standard errors.

    Raises
    ------
    ShapeError
        If the means are not (6, 3).
    NonFiniteError
        If a mean is not finite.
    InvalidInputError
        If ``f_ref`` does not hold six axis-aligned poses.
    DegenerateGeometryError
        If the poses do not point each axis up and down.
    """
    A = np.asarray(accel_means, float)
    if A.shape != (6, 3):
        raise ShapeError(f"six_position needs accel_means of shape (6, 3), got {A.shape}")
    if not (np.isfinite(gravity) and gravity > 0):
        raise InvalidInputError(f"gravity must be finite and > 0 m/s^2, got {gravity}")
    if not np.all(np.isfinite(A)):
        raise NonFiniteError("six_position: accel_means contains NaN/inf")
    if f_ref is None:
        u = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    else:
        u = np.asarray(f_ref, float)
        u = u / np.linalg.norm(u, axis=1)[:, None]
    up = np.zeros(3, int)
    dn = np.zeros(3, int)
    for i in range(3):
        dots = u[:, i]
        up[i], dn[i] = int(np.argmax(dots)), int(np.argmin(dots))
        if dots[up[i]] < 0.99 or dots[dn[i]] > -0.99:
            raise DegenerateGeometryError(
                f"six_position: no pose has axis {'xyz'[i]} within 8° of up and down; "
                "use multiposition() for arbitrary orientations"
            )
    T = np.zeros((3, 3))
    for j in range(3):
        T[:, j] = (A[up[j]] - A[dn[j]]) / (2 * gravity)
    # the sensor reads its own axis with the sign of the pose: a negative diagonal means the poses are given in
    # another order (or the accelerometer measures -f), not an axis that points backwards
    flipped = [("xyz"[i], float(T[i, i])) for i in range(3) if not T[i, i] > 0]
    if flipped:
        raise DegenerateGeometryError(
            f"six_position: the {', '.join(a for a, _ in flipped)} axis reads the opposite sign of its pose (scale "
            f"{', '.join(f'{v:.3g}' for _, v in flipped)}); give the poses in the order +x up, -x up, +y up, -y up, "
            "+z up, -z up (or pass f_ref), with accel_means as specific force (+g on the axis pointing up)"
        )
    b = np.array([(A[up[i], i] + A[dn[i], i]) / 2 for i in range(3)])
    # residual scatter of the equivalent LS model for honest standard errors
    X = np.hstack([gravity * u, np.ones((6, 1))])
    fit = linear_fit(X, A, what="six-position fit")
    stderr: dict[str, Array] = {"accel_matrix": fit.stderr[:3].T, "accel_bias": fit.stderr[3]}
    residuals = {"accel": A - (gravity * u @ T.T + b)}
    cond = {"accel": design_condition(X)}
    gb = np.zeros(3)
    if gyro_means is not None:
        Gm = np.asarray(gyro_means, float)
        er = 0.0 if latitude is None else OMEGA_E * np.sin(latitude) * u
        y = Gm - er
        gb = y.mean(0)
        stderr["gyro_bias"] = y.std(0, ddof=1) / np.sqrt(6)
        residuals["gyro_static"] = y - gb
    cal = ImuCalibration(accel_bias=b, accel_matrix=T, gyro_bias=gb, stderr=stderr, meta={"method": "six_position"})
    return CalibrationResult(cal, stderr, residuals, cond, {}, "six_position", {"gravity": gravity})
