"""Multi-pose calibration without a rate table (Tedaldi, Pretto & Menegatti, ICRA 2014).

The sensor is held still in many hand-placed poses (36-50 recommended), with
short rotations in between; no reference input is known.  The raw data may
carry any offset (signed counts with zero near 0, unsigned counts with zero
near 32768, ...) and any scale: offsets and scales are estimated, the checks
of the session do not depend on the offset, and the initial guesses of the
iterative fits come from the data.

1. **Static detection.**  After an initial rest of ``init_s`` seconds, a
   sample is static when the accelerometer moving variance over ``wait_s``
   is below ``k · ζ_init`` (ζ_init: the rest-period variance).  Several ``k``
   are tried and the detection with the lowest accelerometer cost kept.
2. **Coverage** (offset-invariant): ``λ_min(C) / trace(C)`` with ``C`` the
   scatter of the pose means ``ã_k`` about their centroid must be at least
   :data:`MIN_COVERAGE` (1/3 for the whole sphere, about 1/9 for a
   hemisphere; :func:`pose_coverage`).
3. **Accelerometer** (gravity-magnitude constraint): minimise
   ``Σ_k (|T_a K_a (ã_k + b_a)| − g)²`` over 9 parameters (3 misalignments of
   an upper-triangular ``T_a``, 3 scales, 3 biases; Tedaldi eqs. 6-9 and 14)
   by Levenberg-Marquardt, started from a closed-form axis-aligned ellipsoid
   fit of the pose means (:func:`accel_initial_guess`: offsets and scales by
   linear least squares).  The iterations run on ``ã_k − c`` (``c``: centroid
   of the pose means) so that an offset of the data leaves them unchanged.
4. **Gyroscope:** bias ``b_g`` = mean over the initial rest;
   ``ω = T_g K_g (ω̃ − b_g)`` with 6 misalignments and 3 scales, fitted so that
   integrating ω between consecutive poses rotates the calibrated gravity
   direction of pose k onto that of pose k+1 (Tedaldi eqs. 10-12 and 15-17).
   The scale is started from the data (:func:`gyro_initial_scale`: the turn
   angle implied by the two gravity directions and the axis of
   ``Σ (ω̃ − b_g) Δt``, divided by ``|Σ (ω̃ − b_g) Δt|``, median over the turns,
   refined on a grid of the full cost).

Standard errors: ``s² (JᵀJ)⁻¹`` with ``s²`` the residual variance of each
fit (K − 9 degrees of freedom for K poses; 2P − 9 for P turns, as the
direction residuals lie in the tangent planes).  The gyro covariance adds
the uncertainty of the accelerometer parameters and of ``b_g`` through the
gravity directions (delta method, ``−(JᵀJ)⁻¹ Jᵀ ∂r/∂x``); everything is
propagated to :class:`ImuCalibration` by the delta method.  Sessions with too
few poses, poor coverage of orientations or saturated static poses are refused.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

from imunav.calib._kernels import rotate_between_poses
from imunav.calib.model import ImuCalibration
from imunav.calib.result import CalibrationResult
from imunav.errors import (
    DegenerateGeometryError,
    InsufficientDataError,
    InvalidInputError,
    NonFiniteError,
    SaturationError,
    ShapeError,
)
from imunav.timeseries import moving_variance
from imunav.units import G0

__all__ = ["TEDALDI_ACCEL_NAMES", "TEDALDI_GYRO_NAMES", "accel_tedaldi_matrix", "gyro_tedaldi_matrix", "multipose"]

Array = NDArray[np.float64]
TEDALDI_ACCEL_NAMES = ("m_yz", "m_zy", "m_zx", "s_x", "s_y", "s_z", "b_x", "b_y", "b_z")
TEDALDI_GYRO_NAMES = ("m_yz", "m_zy", "m_xz", "m_zx", "m_xy", "m_yx", "s_x", "s_y", "s_z")


def accel_tedaldi_matrix(p: Array) -> Array:
    """``T_a K_a`` from ``[m_yz, m_zy, m_zx, s_x, s_y, s_z, ...]`` (Tedaldi et al. 2014, eqs. 6-9).

    ``T_a = [[1, -m_yz, m_zy], [0, 1, -m_zx], [0, 0, 1]]`` (upper triangular), ``K_a = diag(s)``.

    Parameters
    ----------
    p : numpy.ndarray
        Parameter vector; its first six entries are the three misalignments (rad) and three scales (SI per
        raw unit).

    Returns
    -------
    numpy.ndarray, shape (3, 3)
        ``T_a K_a``.
    """
    T = np.array([[1.0, -p[0], p[1]], [0.0, 1.0, -p[2]], [0.0, 0.0, 1.0]])
    return T * np.asarray(p[3:6])[None, :]


def gyro_tedaldi_matrix(p: Array) -> Array:
    """``T_g K_g`` from ``[m_yz, m_zy, m_xz, m_zx, m_xy, m_yx, s_x, s_y, s_z]`` (Tedaldi et al. 2014, eq. 10).

    Parameters
    ----------
    p : numpy.ndarray, shape (9,)
        Six misalignments (rad) and three scales (rad/s per raw unit).

    Returns
    -------
    numpy.ndarray, shape (3, 3)
        ``T_g K_g``.
    """
    T = np.array([[1.0, -p[0], p[1]], [p[2], 1.0, -p[3]], [-p[4], p[5], 1.0]])
    return T * np.asarray(p[6:9])[None, :]


MIN_COVERAGE = 0.02
"""Smallest accepted ``λ_min / trace`` of the centred scatter of the pose means (1/3: full sphere)."""


def pose_coverage(means: ArrayLike) -> float:
    """Offset-invariant coverage of the sphere of gravity directions by the pose means.

    ``λ_min(C) / trace(C)`` with ``C`` the scatter of the pose means about
    their own centroid: 1/3 for poses spread over the whole sphere (or the six
    faces), about 1/9 for a hemisphere, near 0 for poses in one cap, on one
    great circle or on one axis (up and down).  Subtracting the centroid makes
    it independent of the sensor offset (e.g. 32768 counts), and the ratio of
    any common scale factor.  With an unknown offset and radius, the
    information on the offset is ``K · Cov(u)`` (``u``: gravity directions):
    this ratio is its smallest eigenvalue relative to the total.

    Parameters
    ----------
    means : array_like, shape (K, 3)
        Mean accelerometer output of each pose, raw units.

    Returns
    -------
    float
        The coverage ratio in [0, 1/3]; 0 when every pose has the same mean.
    """
    m = np.asarray(means, float)
    d = m - m.mean(0)
    C = d.T @ d / len(d)
    tr = float(np.trace(C))
    if not tr > 0:
        return 0.0
    return float(np.linalg.eigvalsh(C)[0] / tr)


def _quadric_fit(x: Array, kind: str) -> tuple[Array, Array] | None:
    """Algebraic (linear least-squares) fit of ``|diag(r) (x − o)| = 1`` to points ``x`` (K, 3).

    ``kind``: ``"axes"`` (axis-aligned ellipsoid, 6 unknowns) or ``"sphere"``
    (4).  The quadric ``Σ_i q_i x_i² + 2pᵀx + d = 0`` is the null vector of the
    design (its smallest right singular vector); then ``o_i = −p_i/q_i``,
    ``k = Σ_i q_i o_i² − d`` and ``r_i = √(q_i/k)``.  Returns ``(r, o)``, or
    None when the quadric is not an ellipsoid (some ``q_i/k ≤ 0``).
    """
    one = np.ones(len(x))
    lin = [2 * x[:, 0], 2 * x[:, 1], 2 * x[:, 2], one]
    if kind == "axes":
        D = np.column_stack([x[:, 0] ** 2, x[:, 1] ** 2, x[:, 2] ** 2, *lin])
    else:
        D = np.column_stack([np.sum(x**2, axis=1), *lin])
    if len(D) < D.shape[1] - 1:
        return None
    v = np.linalg.svd(D, full_matrices=True)[2][-1]
    q = v[:3] if kind == "axes" else np.full(3, v[0])
    p, d = v[-4:-1], v[-1]
    if np.sum(q) < 0:
        q, p, d = -q, -p, -d
    if not np.all(q > 0):
        return None
    o = -p / q
    k = float(np.sum(q * o**2) - d)
    if not k > 0:
        return None
    return np.sqrt(q / k), o


def accel_initial_guess(means: ArrayLike, gravity: float) -> Array:
    """Closed-form accelerometer offsets and scales from an ellipsoid fit of the pose means.

    The pose means are centred on their centroid ``c`` and divided by their RMS
    distance ``h`` from it (so that the fit does not depend on the offset and
    is well conditioned for raw counts); the axis-aligned ellipsoid
    ``|diag(r) (x − o)| = 1`` is fitted by linear least squares (a sphere when
    that fails) and mapped back to the raw data:
    ``K_a = g diag(r) / h``, ``b_a = −(c + h o)``, misalignments 0.

    Parameters
    ----------
    means : array_like, shape (K, 3)
        Mean accelerometer output of each pose, raw units.
    gravity : float
        Local gravity, m/s².

    Returns
    -------
    numpy.ndarray, shape (9,)
        ``[m_yz, m_zy, m_zx, s_x, s_y, s_z, b_x, b_y, b_z]``: misalignments (0), scales (m/s² per raw unit),
        biases (raw units).

    Raises
    ------
    DegenerateGeometryError
        When every pose has the same mean, or not even a sphere fits the means.
    """
    m = np.asarray(means, float)
    c = m.mean(0)
    h = float(np.sqrt(np.mean(np.sum((m - c) ** 2, axis=1))))
    if not h > 0:
        raise DegenerateGeometryError("multi-pose calibration: every pose has the same mean accelerometer vector")
    x = (m - c) / h
    fit = _quadric_fit(x, "axes") or _quadric_fit(x, "sphere")
    if fit is None:
        raise DegenerateGeometryError(
            "multi-pose calibration: the pose means do not lie on an ellipsoid (not even a sphere fits them); "
            "check that the poses are static and that the accelerometer columns are x, y, z of one sensor"
        )
    r, o = fit
    return np.r_[0.0, 0.0, 0.0, gravity * r / h, -(c + h * o)]


def gyro_initial_scale(raw: Array, offsets: NDArray[np.int64], dt: float, u_from: Array, u_to: Array) -> float:
    """Isotropic gyro scale (SI per raw unit) from the rotations between consecutive poses.

    For each transition, ``Φ = Σ (ω̃ − b_g) Δt`` (raw units · s) gives the
    axis ``n = Φ/|Φ|``; the calibrated gravity directions ``u₀, u₁`` of the two
    poses are ``θ`` apart, and a turn by ``α`` about ``n`` moves ``u₀`` by
    ``cos θ = cos α + (1 − cos α)(n·u₀)²``, so
    ``cos α = (cos θ − (n·u₀)²) / (1 − (n·u₀)²)`` and ``s = α/|Φ|``.  The median
    over the transitions whose axis is at least 30° from gravity and whose
    gravity direction moved by at least 10° is refined on a logarithmic grid
    (×1/3 … ×3) of the full integration cost with ``T_g K_g = s I``.

    Parameters
    ----------
    raw : numpy.ndarray, shape (N, 3)
        Raw gyro samples with the bias removed, raw units.
    offsets : numpy.ndarray of int64
        Sample index where each transition starts and ends (pose boundaries).
    dt : float
        Sample interval, s.
    u_from, u_to : numpy.ndarray, shape (M, 3)
        Calibrated gravity directions (unit vectors) before and after each transition.

    Returns
    -------
    float
        The scale, rad/s per raw unit.
    """

    ratios = []
    for m in range(len(offsets) - 1):
        seg = raw[offsets[m]:offsets[m + 1]]
        phi = (seg[:-1] + seg[1:]).sum(0) * 0.5 * dt
        nphi = float(np.linalg.norm(phi))
        cth = float(np.clip(u_from[m] @ u_to[m], -1.0, 1.0))
        if not nphi > 0 or np.arccos(cth) < np.deg2rad(10):
            continue
        c2 = float(u_from[m] @ phi / nphi) ** 2
        if c2 > 0.75:
            continue
        alpha = np.arccos(np.clip((cth - c2) / (1 - c2), -1.0, 1.0))
        ratios.append(alpha / nphi)

    def cost(s: float) -> float:
        M = np.ascontiguousarray(s * np.eye(3))
        return float(np.sum((rotate_between_poses(raw, offsets, M, dt, u_from) - u_to) ** 2))

    if ratios:
        s0 = float(np.median(ratios))
        grid = s0 * np.exp(np.linspace(-np.log(3), np.log(3), 45))
    else:  # no usable transition: scan 12 decades
        grid = np.logspace(-8, 4, 241)
    costs = [cost(s) for s in grid]
    return float(grid[int(np.argmin(costs))])


def _saturated_fn(spec: Any, name: str) -> Any:
    """``x -> bool array`` of saturated raw values: ``|x| ≥ v`` for a number, ``x ≤ lo or x ≥ hi`` for a pair."""
    if spec is None:
        return None
    v = np.atleast_1d(np.asarray(spec, float))
    if v.size == 1 and v[0] > 0:
        return lambda x: np.abs(x) >= v[0]
    if v.size == 2 and v[0] < v[1]:
        return lambda x: (x <= v[0]) | (x >= v[1])
    raise InvalidInputError(
        f"multi-pose calibration: full_scale for {name} must be a positive number (|raw| limit, e.g. 32767) or "
        f"a (min, max) pair of raw limits (e.g. (0, 65535) for unsigned 16-bit counts), got {spec!r}"
    )


def _intervals(mask: NDArray[np.bool_]) -> NDArray[np.int64]:
    d = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return np.stack([np.flatnonzero(d == 1), np.flatnonzero(d == -1)], axis=1)


def _accel_fit(means: Array, gravity: float, x0: Array, misalignment: bool = True) -> tuple[Any, Array]:
    """LM fit of the 9 (or, without misalignment, 6) accelerometer parameters; returns 9-vector solution.

    The fit runs on the pose means minus their centroid ``c`` (bias ``b + c``),
    so that an offset of the raw data (e.g. 32768 counts) changes neither the
    iterations nor the Jacobian; ``sol.x_full`` holds the bias of the raw data.
    """
    free = np.arange(9) if misalignment else np.arange(3, 9)
    c = means.mean(0)
    centred = means - c

    def full(q: Array) -> Array:
        p = np.zeros(9)
        p[free] = q
        return p

    def fun(q: Array) -> Array:
        p = full(q)
        a = (centred + p[6:9]) @ accel_tedaldi_matrix(p).T
        return np.linalg.norm(a, axis=1) - gravity

    q0 = np.asarray(x0, float).copy()
    q0[6:9] += c
    sol = least_squares(fun, q0[free], method="lm", x_scale="jac", max_nfev=2000)
    r = fun(sol.x)
    sol.x_full = full(sol.x)
    sol.x_full[6:9] -= c
    sol.free = free
    return sol, r


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
    full_scale: tuple[Any, Any] = (None, None),
    accel_scale_guess: float | None = None,
    gyro_scale_guess: float | None = None,
    raw_accel_unit: str = "counts",
    raw_gyro_unit: str = "counts",
    max_misalignment_stderr: float = 0.02,
    strict: bool = True,
    accel_misalignment: bool = True,
) -> CalibrationResult:
    """Tedaldi multi-pose calibration of raw accelerometer + gyro samples.

    Works on raw data of any offset and scale with the defaults, e.g. unsigned
    16-bit counts (zero near 32768, a few hundred counts per m/s² and a few
    thousand per rad/s): ``multipose(accel, gyro, fs, init_s=50)``.

    Parameters
    ----------
    accel, gyro : array_like
        (N, 3) raw samples (e.g. counts, signed or unsigned).
    fs : float
        Sampling rate, Hz.
    init_s : float
        Initial rest period, s (gyro bias and detector noise level).
    wait_s : float
        Detector window, s (also the nominal static time per pose).
    gravity : float
        Local gravity magnitude, m/s².
    factors : tuple
        Detector thresholds tried, in units of the rest-period variance.
    min_static_s : float, optional
        Shortest static interval kept (default 0.25 s).
    min_poses : int
        Fewest poses accepted (the accelerometer fit has 9 unknowns).
    full_scale : tuple
        (accel, gyro) raw saturation limits, each None, a number
        (``|raw| ≥ v`` is saturated: signed counts, e.g. 32767) or a
        ``(min, max)`` pair (``raw ≤ min`` or ``raw ≥ max``: e.g. (0, 65535) for
        unsigned 16-bit counts); saturated static poses are refused,
        transitions with a saturated gyro are left out of the gyro fit
        (listed in ``info["gyro_pairs_excluded"]``).
    accel_scale_guess, gyro_scale_guess : float, optional
        Optional overrides of the initial
        SI-per-raw scales.  Default: from the data, the accelerometer offsets
        and scales of the ellipsoid through the pose means
        (:func:`accel_initial_guess`), the gyro scale from the turns between
        poses (:func:`gyro_initial_scale`).  The accelerometer offsets always
        come from the ellipsoid fit.
    raw_accel_unit, raw_gyro_unit : str
        Unit names of the raw data, recorded in the
        calibration.
    max_misalignment_stderr : float
        Largest acceptable standard error of a
        misalignment angle, rad; a larger one means the poses do not excite it.
    strict : bool
        Refuse such a session (DegenerateGeometryError); with False the
        result is returned and the weak parameters are listed in
        ``info["weak_parameters"]``.
    accel_misalignment : bool
        Estimate the 3 accelerometer misalignments (False:
        fix them at 0 and fit scales and biases only, for sessions whose
        poses cannot separate them).

    Returns
    -------
    CalibrationResult
        Its calibration maps raw units to SI; ``info["tedaldi"]``
        holds the parameters and standard errors in the Tedaldi parameterisation
        (``a = T_a K_a (ã + b_a)``, ``ω = T_g K_g (ω̃ − b_g)``; for unsigned counts
        ``b_a`` is near −32768 and ``b_g`` near +32768), ``info["coverage"]`` the
        coverage figure of the poses kept.

    Raises
    ------
    ShapeError, NonFiniteError, InvalidInputError
        Malformed input.
    InsufficientDataError
        Initial rest or recording too short, too few static poses or turns.
    DegenerateGeometryError
        Poses that do not cover the orientations (``pose_coverage`` below
        :data:`MIN_COVERAGE`), undetermined parameters (strict mode).
    SaturationError
        A static pose reaches ``full_scale``.

    Examples
    --------
    >>> res = multipose(accel_counts, gyro_counts, 100.0, init_s=50)  # doctest: +SKIP
    >>> f, w = res.calibration.apply_arrays(accel_counts, gyro_counts)  # doctest: +SKIP
    """
    a = np.asarray(accel, float)
    g = np.asarray(gyro, float)
    if a.ndim != 2 or a.shape[1] != 3 or g.shape != a.shape:
        raise ShapeError(f"accel {a.shape} and gyro {g.shape} must both be (N, 3)")
    if not fs > 0 or not np.isfinite(fs):
        raise InvalidInputError(f"multi-pose calibration: fs must be a positive number of Hz, got {fs}")
    for name, x in (("accel", a), ("gyro", g)):
        bad = np.flatnonzero(~np.all(np.isfinite(x), axis=1))
        if bad.size:
            raise NonFiniteError(
                f"multi-pose calibration: {name} has NaN or infinite values in {bad.size} rows (first: row "
                f"{bad[0]}); drop or interpolate them first"
            )
    sat_a, sat_g = (_saturated_fn(v, n) for v, n in zip(full_scale, ("accel", "gyro")))
    n_init = int(np.rint(init_s * fs))
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
    nwin = max(int(np.rint(wait_s * fs)), 2)
    mv = np.sum(moving_variance(a, nwin, align="centred", per_column=True) ** 2, axis=1)
    min_len = max(int(np.rint((0.25 if min_static_s is None else min_static_s) * fs)), 2)
    best: dict[str, Any] | None = None
    poor: float | None = None
    tried = []
    for k in factors:
        segs = _intervals(mv < k * zeta)
        segs = segs[(segs[:, 1] - segs[:, 0]) >= min_len]
        tried.append((float(k), len(segs)))
        if len(segs) < min_poses:
            continue
        means = np.array([a[s0:s1].mean(0) for s0, s1 in segs])
        cover = pose_coverage(means)
        if cover < MIN_COVERAGE:
            poor = max(poor, cover) if poor is not None else cover
            continue
        x0 = accel_initial_guess(means, gravity)
        if accel_scale_guess is not None:
            x0[:3] = 0.0
            x0[3:6] = accel_scale_guess
        sol, r = _accel_fit(means, gravity, x0, accel_misalignment)
        cost = float(np.mean(r**2))
        if best is None or cost < best["cost"]:
            best = {"k": float(k), "segs": segs, "means": means, "sol": sol, "res": r, "cost": cost, "cover": cover}
    if best is None and poor is not None:
        raise DegenerateGeometryError(
            f"multi-pose calibration: the poses do not cover the orientations (smallest eigenvalue of the "
            f"scatter of the pose means about their centre, relative to its trace: {poor:.3f} < {MIN_COVERAGE}, "
            "1/3 for full coverage); add poses with every axis up and down"
        )
    if best is None:
        most = max(n for _, n in tried)
        raise InsufficientDataError(
            f"multi-pose calibration: at most {most} static poses found (thresholds tried: {tried}); "
            f"need at least {min_poses} (36-50 recommended) - hold the sensor still for ~{wait_s} s in more poses"
        )
    segs, means, sol = best["segs"], best["means"], best["sol"]
    if sat_a is not None:
        for j, (s0, s1) in enumerate(segs):
            if np.any(sat_a(a[s0:s1])):
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
    if not np.all(np.isfinite(pa)) or not np.all(pa[3:6] > 0):
        raise DegenerateGeometryError(
            f"multi-pose calibration: the accelerometer fit gave scales {pa[3:6]} (SI per raw unit; each must be "
            "positive and finite); the poses do not determine them - add poses with every axis up and down"
        )
    TaKa = accel_tedaldi_matrix(pa)

    # ---------------- gyro: integrate between consecutive poses
    c = means.mean(0)  # centred, so that an offset of the raw data does not change the rounding
    wcal_acc = (means - c + (pa[6:9] + c)) @ TaKa.T
    gdir = wcal_acc / np.linalg.norm(wcal_acc, axis=1)[:, None]
    pairs, excluded = [], []
    for j in range(K - 1):
        i0, i1 = int(segs[j, 1]) - 1, int(segs[j + 1, 0]) + 1
        if sat_g is not None and np.any(sat_g(g[i0:i1])):
            excluded.append(j)
            continue
        pairs.append((j, i0, i1))
    if 3 * len(pairs) <= 9:
        raise InsufficientDataError(
            f"multi-pose gyro fit: {len(pairs)} usable pose-to-pose rotations (excluded for saturation: {excluded}); "
            "need at least 4 - turn more slowly or add poses"
        )

    raw_cat = np.ascontiguousarray(np.vstack([g[i0:i1] - b_g for _, i0, i1 in pairs]))
    offsets = np.concatenate([[0], np.cumsum([i1 - i0 for _, i0, i1 in pairs])]).astype(np.int64)
    u_from = np.ascontiguousarray(np.array([gdir[j] for j, _, _ in pairs]))
    u_to = np.array([gdir[j + 1] for j, _, _ in pairs])

    def gfun(p: Array) -> Array:
        M = np.ascontiguousarray(gyro_tedaldi_matrix(p))
        return (rotate_between_poses(raw_cat, offsets, M, 1.0 / fs, u_from) - u_to).ravel()

    sg0 = (gyro_initial_scale(raw_cat, offsets, 1.0 / fs, u_from, u_to) if gyro_scale_guess is None
           else gyro_scale_guess)
    xg0 = np.array([0, 0, 0, 0, 0, 0, sg0, sg0, sg0], float)
    solg = least_squares(gfun, xg0, method="lm", x_scale="jac", max_nfev=4000)
    # the residuals (differences of unit vectors) lie in the tangent planes: 2 degrees of freedom per pair
    cov_g, s2_g = _cov(solg, 2 * len(pairs), 9)
    pg = solg.x
    if not np.all(np.isfinite(pg)) or not np.all(pg[6:9] != 0):
        raise DegenerateGeometryError(
            f"multi-pose gyro fit: gave scales {pg[6:9]}; the turns do not determine them - turn about every axis"
        )
    TgKg = gyro_tedaldi_matrix(pg)
    se_bg = g[:n_init].std(0, ddof=1) / np.sqrt(n_init)
    # the gyro fit takes the gravity directions (accelerometer parameters) and b_g as known: add their
    # uncertainty, d pg = -(JᵀJ)⁻¹ Jᵀ (∂r/∂x) dx with x = (free accelerometer parameters, b_g)
    jf, jt = [j for j, _, _ in pairs], [j + 1 for j, _, _ in pairs]
    M_g = np.ascontiguousarray(TgKg)

    def gres_x(x: Array) -> Array:
        p = pa.copy()
        p[sol.free] = x[:nfree]
        w = (means - c + (p[6:9] + c)) @ accel_tedaldi_matrix(p).T
        gd = w / np.linalg.norm(w, axis=1)[:, None]
        raw = np.ascontiguousarray(raw_cat - x[nfree:])
        return (rotate_between_poses(raw, offsets, M_g, 1.0 / fs, np.ascontiguousarray(gd[jf])) - gd[jt]).ravel()

    cov_x = np.zeros((nfree + 3, nfree + 3))
    cov_x[:nfree, :nfree] = cov_free
    cov_x[nfree:, nfree:] = np.diag(se_bg**2)
    x_hat = np.r_[pa[sol.free], np.zeros(3)]
    Jx = _numjac(gres_x, x_hat, 1e-3 * np.sqrt(np.diag(cov_x)))
    try:
        A = np.linalg.solve(solg.jac.T @ solg.jac, solg.jac.T @ Jx)
    except np.linalg.LinAlgError:
        raise DegenerateGeometryError("multi-pose gyro fit: singular Jacobian; the turns do not excite every "
                                      "gyro parameter - turn about every axis") from None
    cov_g = cov_g + A @ cov_x @ A.T

    # ---------------- to ImuCalibration (raw = (TK)^-1 SI - b_a ; raw = (TK)^-1 ω + b_g) + delta method
    def acal(p: Array) -> Array:
        return np.concatenate([np.linalg.inv(accel_tedaldi_matrix(p)).ravel(), -p[6:9]])

    def gcal(p: Array) -> Array:
        return np.linalg.inv(gyro_tedaldi_matrix(p)).ravel()

    Ja = _numjac(acal, pa)
    Jg = _numjac(gcal, pg)
    sa = np.sqrt(np.maximum(np.diag(Ja @ cov_a @ Ja.T), 0))
    sgm = np.sqrt(np.maximum(np.diag(Jg @ cov_g @ Jg.T), 0))
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
        "coverage": best["cover"],
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
    info["max_misalignment_stderr"] = max_misalignment_stderr
    if weak and strict:
        raise undetermined_misalignment_error(K, weak, max_misalignment_stderr)
    cond = {"accel": float(np.linalg.cond(sol.jac)), "gyro": float(np.linalg.cond(solg.jac))}
    return CalibrationResult(
        cal, stderr, {"accel_norm": best["res"], "gyro_direction": solg.fun.reshape(-1, 3)}, cond,
        {"static": segs}, "multipose", info,
    )


def undetermined_misalignment_error(
    n_poses: int, weak: list[str], limit: float, *, no_accel_misalignment: str = "accel_misalignment=False",
    not_strict: str = "strict=False",
) -> DegenerateGeometryError:
    """The refusal of a session whose poses leave misalignments undetermined.

    Parameters
    ----------
    n_poses : int
        Number of poses of the session.
    weak : list of str
        The parameters not determined (``"accel m_yz"``, ``"gyro m_xy"``, ...).
    limit : float
        The standard-error limit they exceed, rad.
    no_accel_misalignment : str
        How the caller spells the way out "fit without accelerometer misalignment" (keyword or CLI flag).
    not_strict : str
        How the caller spells the way out "get the estimate anyway".

    Returns
    -------
    DegenerateGeometryError
        The exception to raise, its message naming the ways out.
    """
    ways = ["add poses tilted between the axes (36-50 poses recommended)"]
    if any(w.startswith("accel ") for w in weak):
        ways.append(f"fit without accelerometer misalignment ({no_accel_misalignment})")
    return DegenerateGeometryError(
        f"multi-pose calibration: the {n_poses} poses do not determine {', '.join(weak)} (limit {limit} rad); "
        f"{', '.join(ways)} or pass {not_strict} to get the estimate anyway"
    )


def _numjac(f: Any, x: Array, eps: Array | None = None) -> Array:
    if eps is None:
        eps = 1e-6 * np.maximum(np.abs(x), 1e-6)
    eps = np.where(eps > 0, eps, 1e-9)
    cols = [(f(x + e) - f(x - e)) / (2 * h) for e, h in zip(np.diag(eps), eps)]
    return np.stack(cols, axis=1)
