"""Multi-pose calibration without a rate table (Tedaldi, Pretto & Menegatti, ICRA 2014).

The sensor is held still in many hand-placed poses (36-50 recommended), with
short rotations in between; no reference input is known.

1. **Static detection.**  After an initial rest of ``init_s`` seconds, a
   sample is static when the accelerometer moving variance over ``wait_s``
   is below ``k · ζ_init`` (ζ_init: the rest-period variance).  Several ``k``
   are tried and the detection with the lowest accelerometer cost kept.
2. **Accelerometer** (gravity-magnitude constraint): with the per-pose mean
   raw vector ``ã_k``, minimise ``Σ_k (|T_a K_a (ã_k + b_a)| − g)²`` over 9
   parameters (3 misalignments of an upper-triangular ``T_a``, 3 scales,
   3 biases; Tedaldi eqs. 6-9 and 14) by Levenberg-Marquardt.
3. **Gyroscope:** bias = mean over the initial rest; ``ω = T_g K_g (ω̃ − b_g)``
   with 6 misalignments and 3 scales, fitted so that integrating ω between
   consecutive poses rotates the calibrated gravity direction of pose k onto
   that of pose k+1 (Tedaldi eqs. 10-12 and 15-17).

Standard errors: ``s² (JᵀJ)⁻¹`` with ``s²`` the residual variance of each
fit (per pose / per pose pair), propagated to :class:`ImuCalibration` by the
delta method.  Sessions with too few poses, poor coverage of orientations or
saturated static poses are refused.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

from imunav.calib._segments import moving_variance
from imunav.calib.model import ImuCalibration
from imunav.calib.result import CalibrationResult
from imunav.errors import DegenerateGeometryError, InsufficientDataError, InvalidInputError, SaturationError, ShapeError
from imunav.units import G0

__all__ = ["multipose", "accel_tedaldi_matrix", "gyro_tedaldi_matrix", "TEDALDI_ACCEL_NAMES", "TEDALDI_GYRO_NAMES"]

Array = NDArray[np.float64]
TEDALDI_ACCEL_NAMES = ("m_yz", "m_zy", "m_zx", "s_x", "s_y", "s_z", "b_x", "b_y", "b_z")
TEDALDI_GYRO_NAMES = ("m_yz", "m_zy", "m_xz", "m_zx", "m_xy", "m_yx", "s_x", "s_y", "s_z")


def accel_tedaldi_matrix(p: Array) -> Array:
    """``T_a K_a`` from ``[m_yz, m_zy, m_zx, s_x, s_y, s_z, ...]``."""
    T = np.array([[1.0, -p[0], p[1]], [0.0, 1.0, -p[2]], [0.0, 0.0, 1.0]])
    return T * np.asarray(p[3:6])[None, :]


def gyro_tedaldi_matrix(p: Array) -> Array:
    """``T_g K_g`` from ``[m_yz, m_zy, m_xz, m_zx, m_xy, m_yx, s_x, s_y, s_z]``."""
    T = np.array([[1.0, -p[0], p[1]], [p[2], 1.0, -p[3]], [-p[4], p[5], 1.0]])
    return T * np.asarray(p[6:9])[None, :]


def _intervals(mask: NDArray[np.bool_]) -> NDArray[np.int64]:
    d = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return np.stack([np.flatnonzero(d == 1), np.flatnonzero(d == -1)], axis=1)


def _accel_fit(means: Array, gravity: float, x0: Array, misalignment: bool = True) -> tuple[Any, Array]:
    """LM fit of the 9 (or, without misalignment, 6) accelerometer parameters; returns 9-vector solution."""
    free = np.arange(9) if misalignment else np.arange(3, 9)

    def full(q: Array) -> Array:
        p = np.zeros(9)
        p[free] = q
        return p

    def fun(q: Array) -> Array:
        p = full(q)
        a = (means + p[6:9]) @ accel_tedaldi_matrix(p).T
        return np.linalg.norm(a, axis=1) - gravity

    sol = least_squares(fun, x0[free], method="lm", x_scale="jac", max_nfev=2000)
    sol.x_full = full(sol.x)
    sol.free = free
    return sol, fun(sol.x)


def _cov(sol: Any, n_res: int, n_par: int) -> tuple[Array, float]:
    dof = n_res - n_par
    s2 = float(np.sum(sol.fun**2) / dof) if dof > 0 else float("nan")
    JtJ = sol.jac.T @ sol.jac
    try:
        return s2 * np.linalg.inv(JtJ), s2
    except np.linalg.LinAlgError:
        raise DegenerateGeometryError("multi-pose fit: singular Jacobian; the poses do not excite every parameter") from None


def multipose(
    accel: ArrayLike,
    gyro: ArrayLike,
    fs: float,
    *,
    init_s: float = 30.0,
    wait_s: float = 3.0,
    gravity: float = G0,
    factors: tuple[float, ...] = (2, 3, 5, 7, 10, 15, 20, 30, 50),
    min_static_s: float | None = None,
    min_poses: int = 10,
    full_scale: tuple[float | None, float | None] = (None, None),
    accel_scale_guess: float | None = None,
    gyro_scale_guess: float | None = None,
    raw_accel_unit: str = "counts",
    raw_gyro_unit: str = "counts",
    max_misalignment_stderr: float = 0.02,
    strict: bool = True,
    accel_misalignment: bool = True,
) -> CalibrationResult:
    """Tedaldi multi-pose calibration of raw accelerometer + gyro samples.

    Parameters
    ----------
    accel, gyro : (N, 3) raw samples (e.g. counts).
    fs : sampling rate, Hz.
    init_s : initial rest period, s (gyro bias and detector noise level).
    wait_s : detector window, s (also the nominal static time per pose).
    gravity : local gravity magnitude, m/s².
    factors : detector thresholds tried, in units of the rest-period variance.
    min_static_s : shortest static interval kept (default 0.25 s).
    min_poses : fewest poses accepted (the accelerometer fit has 9 unknowns).
    full_scale : (accel, gyro) raw full-scale values; saturated static poses are
        refused, transitions with a saturated gyro are left out of the gyro fit
        (listed in ``info["gyro_pairs_excluded"]``).
    accel_scale_guess, gyro_scale_guess : initial SI-per-raw scales (default
        from the data: ``g / median |ã|``, and 1).
    max_misalignment_stderr : largest acceptable standard error of a
        misalignment angle, rad; a larger one means the poses do not excite it.
    strict : refuse such a session (DegenerateGeometryError); with False the
        result is returned and the weak parameters are listed in
        ``info["weak_parameters"]``.
    accel_misalignment : estimate the 3 accelerometer misalignments (False:
        fix them at 0 and fit scales and biases only, for sessions whose
        poses cannot separate them).

    Returns
    -------
    CalibrationResult whose calibration maps raw units to SI; ``info["tedaldi"]``
    holds the parameters and standard errors in the Tedaldi parameterisation
    (``a = T_a K_a (ã + b_a)``, ``ω = T_g K_g (ω̃ − b_g)``).
    """
    a = np.asarray(accel, float)
    g = np.asarray(gyro, float)
    if a.ndim != 2 or a.shape[1] != 3 or g.shape != a.shape:
        raise ShapeError(f"accel {a.shape} and gyro {g.shape} must both be (N, 3)")
    if fs <= 0:
        raise InvalidInputError(f"fs must be positive, got {fs}")
    n_init = int(round(init_s * fs))
    if n_init < 10 or n_init >= len(a):
        raise InsufficientDataError(
            f"multi-pose calibration: the initial rest of {init_s} s ({n_init} samples) does not fit the "
            f"{len(a) / fs:.1f} s recording; record a rest period first and give init_s"
        )
    if len(a) < n_init + 2 * min_poses * wait_s * fs / 3:
        raise InsufficientDataError(
            f"multi-pose calibration: recording of {len(a) / fs:.1f} s is too short for {min_poses} poses of "
            f"~{wait_s} s after a {init_s} s rest"
        )
    b_g = g[:n_init].mean(0)
    zeta = float(np.sum(a[:n_init].var(0) ** 2))
    if zeta <= 0:
        raise InvalidInputError("the initial rest period has zero accelerometer variance (constant data?)")
    nwin = max(int(round(wait_s * fs)), 2)
    mv = np.sum(moving_variance(a, nwin) ** 2, axis=1)
    min_len = max(int(round((0.25 if min_static_s is None else min_static_s) * fs)), 2)
    best: dict[str, Any] | None = None
    poor: float | None = None
    tried = []
    for k in factors:
        segs = _intervals(mv < k * zeta)
        segs = segs[(segs[:, 1] - segs[:, 0]) >= min_len]
        tried.append((float(k), int(len(segs))))
        if len(segs) < min_poses:
            continue
        means = np.array([a[s0:s1].mean(0) for s0, s1 in segs])
        u = means / np.linalg.norm(means, axis=1)[:, None]
        cover = float(np.linalg.eigvalsh(u.T @ u / len(u))[0])
        if cover < 0.02:
            poor = max(poor, cover) if poor is not None else cover
            continue
        s0g = gravity / np.median(np.linalg.norm(means, axis=1)) if accel_scale_guess is None else accel_scale_guess
        x0 = np.array([0, 0, 0, s0g, s0g, s0g, 0, 0, 0], float)
        sol, r = _accel_fit(means, gravity, x0, accel_misalignment)
        cost = float(np.mean(r**2))
        if best is None or cost < best["cost"]:
            best = {"k": float(k), "segs": segs, "means": means, "sol": sol, "res": r, "cost": cost}
    if best is None and poor is not None:
        raise DegenerateGeometryError(
            f"multi-pose calibration: the poses do not cover the orientations (smallest eigenvalue of the "
            f"gravity-direction scatter {poor:.3f} < 0.02, 1/3 for full coverage); add poses with every axis "
            "up and down"
        )
    if best is None:
        most = max(n for _, n in tried)
        raise InsufficientDataError(
            f"multi-pose calibration: at most {most} static poses found (thresholds tried: {tried}); "
            f"need at least {min_poses} (36-50 recommended) - hold the sensor still for ~{wait_s} s in more poses"
        )
    segs, means, sol = best["segs"], best["means"], best["sol"]
    if full_scale[0] is not None:
        for j, (s0, s1) in enumerate(segs):
            if np.any(np.abs(a[s0:s1]) >= full_scale[0]):
                raise SaturationError(
                    f"multi-pose calibration: accelerometer saturated in static pose {j} (samples {s0}..{s1}); "
                    "the range is too small for gravity - use a larger range"
                )
    K = len(segs)
    nfree = len(sol.free)
    cov_free, s2_a = _cov(sol, K, nfree)
    cov_a = np.zeros((9, 9))
    cov_a[np.ix_(sol.free, sol.free)] = cov_free
    pa = sol.x_full
    TaKa = accel_tedaldi_matrix(pa)

    # ---------------- gyro: integrate between consecutive poses
    wcal_acc = (means + pa[6:9]) @ TaKa.T
    gdir = wcal_acc / np.linalg.norm(wcal_acc, axis=1)[:, None]
    pairs, excluded = [], []
    for j in range(K - 1):
        i0, i1 = int(segs[j, 1]) - 1, int(segs[j + 1, 0]) + 1
        if full_scale[1] is not None and np.any(np.abs(g[i0:i1]) >= full_scale[1]):
            excluded.append(j)
            continue
        pairs.append((j, i0, i1))
    if 3 * len(pairs) <= 9:
        raise InsufficientDataError(
            f"multi-pose gyro fit: {len(pairs)} usable pose-to-pose rotations (excluded for saturation: {excluded}); "
            "need at least 4 - turn more slowly or add poses"
        )
    from imunav.calib._kernels import rotate_between_poses

    raw_cat = np.ascontiguousarray(np.vstack([g[i0:i1] - b_g for _, i0, i1 in pairs]))
    offsets = np.concatenate([[0], np.cumsum([i1 - i0 for _, i0, i1 in pairs])]).astype(np.int64)
    u_from = np.ascontiguousarray(np.array([gdir[j] for j, _, _ in pairs]))
    u_to = np.array([gdir[j + 1] for j, _, _ in pairs])

    def gfun(p: Array) -> Array:
        M = np.ascontiguousarray(gyro_tedaldi_matrix(p))
        return (rotate_between_poses(raw_cat, offsets, M, 1.0 / fs, u_from) - u_to).ravel()

    sg0 = 1.0 if gyro_scale_guess is None else gyro_scale_guess
    xg0 = np.array([0, 0, 0, 0, 0, 0, sg0, sg0, sg0], float)
    solg = least_squares(gfun, xg0, method="lm", x_scale="jac", max_nfev=4000)
    cov_g, s2_g = _cov(solg, 3 * len(pairs), 9)
    pg = solg.x
    TgKg = gyro_tedaldi_matrix(pg)

    # ---------------- to ImuCalibration (raw = (TK)^-1 SI - b_a ; raw = (TK)^-1 ω + b_g) + delta method
    def acal(p: Array) -> Array:
        return np.concatenate([np.linalg.inv(accel_tedaldi_matrix(p)).ravel(), -p[6:9]])

    def gcal(p: Array) -> Array:
        return np.linalg.inv(gyro_tedaldi_matrix(p)).ravel()

    Ja = _numjac(acal, pa)
    Jg = _numjac(gcal, pg)
    sa = np.sqrt(np.maximum(np.diag(Ja @ cov_a @ Ja.T), 0))
    sgm = np.sqrt(np.maximum(np.diag(Jg @ cov_g @ Jg.T), 0))
    se_bg = g[:n_init].std(0, ddof=1) / np.sqrt(n_init)
    stderr = {
        "accel_matrix": sa[:9].reshape(3, 3), "accel_bias": sa[9:],
        "gyro_matrix": sgm.reshape(3, 3), "gyro_bias": se_bg,
    }
    cal = ImuCalibration(
        accel_bias=-pa[6:9], accel_matrix=np.linalg.inv(TaKa), gyro_bias=b_g, gyro_matrix=np.linalg.inv(TgKg),
        raw_accel_unit=raw_accel_unit, raw_gyro_unit=raw_gyro_unit, stderr=stderr,
        meta={"method": "multipose (Tedaldi 2014)", "fs": fs, "gravity": gravity},
    )
    info = {
        "n_poses": K,
        "threshold_factor": best["k"],
        "thresholds_tried": tried,
        "gyro_pairs_used": len(pairs),
        "gyro_pairs_excluded": excluded,
        "accel_residual_sigma": float(np.sqrt(s2_a)) if np.isfinite(s2_a) else None,
        "gyro_residual_sigma": float(np.sqrt(s2_g)),
        "tedaldi": {
            "accel_names": list(TEDALDI_ACCEL_NAMES), "accel": pa.tolist(),
            "accel_stderr": np.sqrt(np.diag(cov_a)).tolist(),
            "gyro_names": list(TEDALDI_GYRO_NAMES) + ["b_x", "b_y", "b_z"], "gyro": pg.tolist() + b_g.tolist(),
            "gyro_stderr": np.sqrt(np.diag(cov_g)).tolist() + se_bg.tolist(),
        },
    }
    se_ma = np.sqrt(np.diag(cov_a))[:3]
    se_mg = np.sqrt(np.diag(cov_g))[:6]
    weak = [f"accel {n} (stderr {v:.3g} rad)" for n, v in zip(TEDALDI_ACCEL_NAMES[:3], se_ma) if not v <= max_misalignment_stderr]
    weak += [f"gyro {n} (stderr {v:.3g} rad)" for n, v in zip(TEDALDI_GYRO_NAMES[:6], se_mg) if not v <= max_misalignment_stderr]
    info["weak_parameters"] = weak
    if weak and strict:
        raise DegenerateGeometryError(
            f"multi-pose calibration: the {K} poses do not determine {', '.join(weak)} (limit "
            f"{max_misalignment_stderr} rad); add poses tilted between the axes (36-50 poses recommended), "
            "fit without accelerometer misalignment (accel_misalignment=False) or pass strict=False to get "
            "the estimate anyway"
        )
    cond = {"accel": float(np.linalg.cond(sol.jac)), "gyro": float(np.linalg.cond(solg.jac))}
    return CalibrationResult(
        cal, stderr, {"accel_norm": best["res"], "gyro_direction": solg.fun.reshape(-1, 3)}, cond,
        {"static": segs}, "multipose", info,
    )


def _numjac(f: Any, x: Array) -> Array:
    eps = 1e-6 * np.maximum(np.abs(x), 1e-6)
    cols = [(f(x + e) - f(x - e)) / (2 * h) for e, h in zip(np.diag(eps), eps)]
    return np.stack(cols, axis=1)
