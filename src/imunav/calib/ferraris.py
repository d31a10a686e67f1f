"""Ferraris et al. (1995) calibration: six static poses and three full turns.

The method used by imucal (Küderle et al., JOSS 2022), re-derived here from
its description (imucal data README).  With ``U_p`` / ``U_a`` the 3×3
matrices whose columns are the mean accelerometer vectors of the x/y/z
"parallel" (+1 g) and "antiparallel" (−1 g) poses::

    b_a = diag(U_p + U_a) / 2,      T_a = (U_p − U_a) / (2 g)
    b_g = mean gyro over all static samples
    G   = (G_p − G_a) / (2 g)       (mean gyro vectors per pose)

and, for each rotation section r about axis j, the integral of
``ω̃ − b_g − G f̂`` over time divided by the expected angle gives column j of
``T_g``.  imucal splits ``T = K R`` (row norms in ``K``); ``ImuCalibration``
keeps ``T`` and converts (:meth:`ImuCalibration.to_imucal`).

Standard errors follow white-noise theory from the within-section scatter
(the method has no redundant poses to estimate a residual scatter), so they
are optimistic when the bias drifts during the session.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.calib._lsq import design_condition
from imunav.calib.model import ImuCalibration
from imunav.calib.result import CalibrationResult
from imunav.errors import DegenerateGeometryError, InsufficientDataError, InvalidInputError, SaturationError
from imunav.units import DEG

__all__ = ["FERRARIS_SECTIONS", "ferraris", "ferraris_from_session"]

Array = NDArray[np.float64]
FERRARIS_SECTIONS = ("x_p", "x_a", "y_p", "y_a", "z_p", "z_a", "x_rot", "y_rot", "z_rot")


def ferraris(
    sections: Mapping[str, tuple[ArrayLike, ArrayLike]],
    fs: float,
    *,
    gravity: float = 9.81,
    expected_angle_deg: float = -360.0,
    raw_accel_unit: str = "m/s^2",
    raw_gyro_unit: str = "rad/s",
    full_scale: tuple[float | None, float | None] = (None, None),
) -> CalibrationResult:
    """Ferraris calibration from the nine labelled sections.

    F. Ferraris, U. Grimaldi, M. Parvis, "Procedure for effortless in-field calibration of three-axial rate
    gyro and accelerometers", Sensors and Materials 7(5), 1995; section names and conventions as in the
    imucal package (A. Küderle et al., mad-lab-fau).

    Parameters
    ----------
    sections : mapping of str to (array_like, array_like)
        ``{"x_p": (accel, gyro), ...}`` with the keys of :data:`FERRARIS_SECTIONS`; arrays (n, 3) in raw
        units.
    fs : float
        Sampling rate, Hz (the rotation integrals are sums / fs).
    gravity : float
        Local gravity, m/s² (imucal default 9.81).
    expected_angle_deg : float
        Angle the sensor should measure per rotation, degrees (imucal default −360; use +360 for the opposite
        turning sense).
    raw_accel_unit, raw_gyro_unit : str
        Units of the raw accelerometer and gyro data.
    full_scale : tuple of (float or None)
        (accel, gyro) ranges in raw units; sections touching them are refused.

    Returns
    -------
    CalibrationResult
        Biases, scale / misalignment matrices and gyro g-sensitivity.

    Raises
    ------
    InsufficientDataError
        If a section is missing or too short.
    InvalidInputError
        If ``fs`` is not positive or ``expected_angle_deg`` is zero.
    SaturationError
        If a section touches the full-scale range.
    DegenerateGeometryError
        If the sections do not excite every axis.
    """
    missing = [k for k in FERRARIS_SECTIONS if k not in sections]
    if missing:
        raise InsufficientDataError(
            f"Ferraris calibration needs the sections {list(FERRARIS_SECTIONS)}; missing {missing}"
        )
    if fs <= 0:
        raise InvalidInputError(f"fs must be positive, got {fs}")
    if expected_angle_deg == 0:
        raise InvalidInputError("expected_angle_deg must be non-zero (e.g. -360 or 360)")
    acc = {k: np.asarray(sections[k][0], float) for k in FERRARIS_SECTIONS}
    gyr = {k: np.asarray(sections[k][1], float) for k in FERRARIS_SECTIONS}
    for k in FERRARIS_SECTIONS:
        if acc[k].ndim != 2 or acc[k].shape[1] != 3 or gyr[k].shape != acc[k].shape or len(acc[k]) < 2:
            raise InsufficientDataError(
                f"section {k!r}: accel {acc[k].shape} / gyro {gyr[k].shape} must be (n ≥ 2, 3) with equal n"
            )
        for arr, fsc, name in ((acc[k], full_scale[0], "accelerometer"), (gyr[k], full_scale[1], "gyroscope")):
            if fsc is not None and np.any(np.abs(arr) >= fsc):
                raise SaturationError(f"section {k!r}: {name} reaches its full-scale range {fsc:g}")
    static = ["x_p", "y_p", "z_p", "x_a", "y_a", "z_a"]
    mean_a = {k: acc[k].mean(0) for k in static}
    se_a = {k: acc[k].std(0, ddof=1) / np.sqrt(len(acc[k])) for k in static}
    mean_g = {k: gyr[k].mean(0) for k in static}
    se_g = {k: gyr[k].std(0, ddof=1) / np.sqrt(len(gyr[k])) for k in static}
    Up = np.stack([mean_a[f"{a}_p"] for a in "xyz"], axis=1)
    Ua = np.stack([mean_a[f"{a}_a"] for a in "xyz"], axis=1)
    Sp = np.stack([se_a[f"{a}_p"] for a in "xyz"], axis=1)
    Sa = np.stack([se_a[f"{a}_a"] for a in "xyz"], axis=1)
    b_a = np.diag(Up + Ua) / 2.0
    T_a = (Up - Ua) / (2.0 * gravity)
    se_ba = np.sqrt(np.diag(Sp) ** 2 + np.diag(Sa) ** 2) / 2.0
    se_Ta = np.sqrt(Sp**2 + Sa**2) / (2.0 * gravity)
    all_static_g = np.vstack([gyr[k] for k in static])
    b_g = all_static_g.mean(0)
    # gyro noise: pooled within-pose standard deviation (the pose-to-pose
    # differences G f are signal, not noise)
    ss = sum(((gyr[k] - mean_g[k]) ** 2).sum(0) for k in static)
    sig_g = np.sqrt(ss / (len(all_static_g) - len(static)))
    se_bg = sig_g / np.sqrt(len(all_static_g))
    Gp = np.stack([mean_g[f"{a}_p"] for a in "xyz"], axis=1)
    Ga = np.stack([mean_g[f"{a}_a"] for a in "xyz"], axis=1)
    G = (Gp - Ga) / (2.0 * gravity)
    se_G = np.sqrt(np.stack([se_g[f"{a}_p"] for a in "xyz"], 1) ** 2 + np.stack([se_g[f"{a}_a"] for a in "xyz"], 1) ** 2) / (2 * gravity)
    _check_matrix(T_a, "accelerometer", "the parallel and antiparallel poses ({a}_p, {a}_a)",
                  "each pair must read +g and -g along its axis")
    T_a_inv = np.linalg.inv(T_a)
    angle = expected_angle_deg * DEG
    T_g = np.zeros((3, 3))
    se_Tg = np.zeros((3, 3))
    for j, a in enumerate("xyz"):
        k = f"{a}_rot"
        f_cal = (acc[k] - b_a) @ T_a_inv.T
        w = gyr[k] - b_g - f_cal @ G.T
        T_g[:, j] = w.sum(0) / fs / angle
        # sum_t w_t carries the rotation's own noise (n sig^2), the bias estimate
        # removed n times (n^2 se_bg^2) and the G estimate times sum_t f_t
        # (sum_k S_k^2 se_G[:, k]^2); b_g and G are uncorrelated for equal pose lengths
        n_rot, S = len(w), f_cal.sum(0)
        var_sum = n_rot * sig_g**2 + n_rot**2 * se_bg**2 + (se_G**2) @ (S**2)
        se_Tg[:, j] = np.sqrt(var_sum) / fs / abs(angle)
    _check_matrix(T_g, "gyro", "the rotation section {a}_rot",
                  f"each must hold one full turn about its axis ({expected_angle_deg:g} deg as measured)",
                  signed=False)
    stderr = {
        "accel_bias": se_ba, "accel_matrix": se_Ta, "gyro_bias": se_bg,
        "g_sensitivity": se_G, "gyro_matrix": se_Tg,
    }
    cal = ImuCalibration(
        accel_bias=b_a, accel_matrix=T_a, gyro_bias=b_g, gyro_matrix=T_g, g_sensitivity=G,
        raw_accel_unit=raw_accel_unit, raw_gyro_unit=raw_gyro_unit, stderr=stderr,
        meta={"method": "ferraris", "gravity": gravity, "expected_angle_deg": expected_angle_deg, "fs": fs},
    )
    # residuals: |f̂| − g in each static pose, and the turned angle error per rotation
    res_a = np.array([np.linalg.norm(T_a_inv @ (mean_a[k] - b_a)) - gravity for k in static])
    X6 = np.vstack([np.hstack([gravity * s * np.eye(3)[i], 1.0]) for s in (1, -1) for i in range(3)])
    return CalibrationResult(
        cal, stderr, {"accel_norm": res_a}, {"accel": design_condition(X6)}, {}, "ferraris",
        {"n_static_samples": len(all_static_g), "fs": fs},
    )


#: Largest condition number accepted for T_a and T_g: a real sensor's scale factors differ by a few
#: percent and its misalignments are small, so T is close to a multiple of the identity (cond ~ 1).
_MAX_COND = 100.0


def _check_matrix(T: Array, sensor: str, what: str, need: str, signed: bool = True) -> None:
    """Refuse a Ferraris T whose columns do not point along their axes (identical, swapped or empty sections).

    ``signed``: the diagonal must also be positive (accelerometer: ``x_p`` reads +g); the gyro's sign
    depends on the turning sense (``expected_angle_deg``), so only its magnitude is checked.
    """

    cols = np.linalg.norm(T, axis=0)
    diag = np.diag(T) if signed else np.abs(np.diag(T))
    with np.errstate(divide="ignore", invalid="ignore"):
        cond = np.linalg.cond(T) if np.all(np.isfinite(T)) and cols.min() > 0 else np.inf
    bad = [j for j in range(3) if not (diag[j] > 0.5 * cols[j] > 0)]
    if bad or not cond < _MAX_COND:
        j = bad[0] if bad else int(np.argmin(cols))
        a = "xyz"[j]
        raise DegenerateGeometryError(
            f"Ferraris: the {sensor} matrix is degenerate (condition {cond:.3g}, column {a}: "
            f"{np.array2string(T[:, j], precision=4)}): check {what.format(a=a)}; {need}. Identical, swapped or "
            "mislabelled sections give this; check the section list"
        )


def ferraris_from_session(
    accel: ArrayLike,
    gyro: ArrayLike,
    section_list: Mapping[str, Any],
    fs: float,
    **kwargs: Any,
) -> CalibrationResult:
    """Ferraris calibration of a continuous recording with an imucal-style section list.

    Parameters
    ----------
    accel : array_like, shape (N, 3)
        Raw accelerometer samples.
    gyro : array_like, shape (N, 3)
        Raw gyro samples.
    section_list : mapping
        ``{"x_p": {"start": i0, "end": i1}, ...}`` (row positions, end exclusive) or ``{"x_p": (i0, i1), ...}``.
    fs : float
        Sampling rate, Hz.
    **kwargs
        Keywords of :func:`ferraris`.

    Returns
    -------
    CalibrationResult
        As :func:`ferraris`.

    Raises
    ------
    InsufficientDataError
        If a section is missing.
    InvalidInputError
        If a section's range is outside the recording.
    """
    a = np.asarray(accel, float)
    g = np.asarray(gyro, float)
    secs: dict[str, tuple[Array, Array]] = {}
    for k in FERRARIS_SECTIONS:
        if k not in section_list:
            raise InsufficientDataError(f"section list lacks {k!r}; needs {list(FERRARIS_SECTIONS)}")
        i0, i1 = _section_rows(k, section_list[k])
        if not 0 <= i0 < i1 <= len(a):
            raise InvalidInputError(f"section {k!r}: rows {i0}..{i1} outside the recording (0..{len(a)})")
        secs[k] = (a[i0:i1], g[i0:i1])
    res = ferraris(secs, fs, **kwargs)
    res.segments["sections"] = np.array([_section_rows(k, section_list[k]) for k in FERRARIS_SECTIONS])
    return res


def _section_rows(name: str, v: Any) -> tuple[int, int]:
    """(start, end) row positions of one section of an imucal section list, checked to be integers."""
    if isinstance(v, Mapping):
        if "start" not in v or "end" not in v:
            raise InvalidInputError(f"section {name!r}: needs start and end row positions, e.g. "
                                    f'{{"start": 0, "end": 500}}; got {dict(v)!r}')
        pair = (v["start"], v["end"])
    elif isinstance(v, (list, tuple)) and len(v) == 2:
        pair = (v[0], v[1])
    else:
        raise InvalidInputError(f"section {name!r}: give {{\"start\": i0, \"end\": i1}} or [i0, i1], not {v!r}")
    out = []
    for key, x in zip(("start", "end"), pair):
        if isinstance(x, bool) or not isinstance(x, (int, np.integer, float, np.floating)) or not float(x).is_integer():
            raise InvalidInputError(f"section {name!r}: {key} {x!r} is not a row position (a whole number of rows)")
        out.append(int(x))
    return out[0], out[1]
