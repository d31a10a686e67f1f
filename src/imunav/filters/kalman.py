"""Linear discrete Kalman filter.

Model (Gelb 1974, §4.2; Akgün 2002, eqs. 4.1-4.10)::

    x(k+1) = F x(k) + B u(k) + G w(k),   w ~ N(0, Q)
    z(k)   = H x(k) + v(k),              v ~ N(0, R)

Predict:  ``x⁻ = F x + B u``,  ``P⁻ = F P Fᵀ + G Q Gᵀ``.
Update:   ``ν = z − H x⁻``,  ``S = H P⁻ Hᵀ + R``,  ``K = P⁻ Hᵀ S⁻¹``,
``x = x⁻ + K ν`` and, in Joseph form (Bucy & Joseph 1968),
``P = (I − K H) P⁻ (I − K H)ᵀ + K R Kᵀ``, which stays symmetric positive
semi-definite for any gain.

The steps are those of every imunav filter: the covariance prediction is the core's
:func:`imunav.filters._core.propagate_cov_sparse` and the update its
:func:`imunav.filters._core.joseph_update` (through ``joseph_update_gain``, which also returns the gain),
the numba primitives of the attitude, INS and GNSS/INS filters.

A measurement may be used partially: ``accept`` (one flag per channel) keeps
only the accepted rows of H, R and z, which is how the robust gates of
:mod:`imunav.filters.robust` reject single channels.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import solve_discrete_are

from imunav.errors import InvalidInputError
from imunav.filters._batch import MODE_GATE, MODE_HUBER, MODE_ISOLATE, MODE_NIS, MODE_NONE, batch_filter
from imunav.filters._common import (
    as_covariance,
    as_matrix,
    as_vector,
    inv_sqrt_spd,
    joseph_step,
    predict_covariance,
    symmetrize,
)
from imunav.filters._core import nis as core_nis
from imunav.filters.gates import isolation_thresholds
from imunav.results import Result

__all__ = [
    "KalmanFilter",
    "UpdateResult",
    "KalmanRun",
    "kalman_filter",
    "batch_kalman_filter",
    "BatchRun",
    "riccati_steady_state",
]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class UpdateResult(Result):
    """What one measurement update did.

    Attributes
    ----------
    innovation : numpy.ndarray, shape (m,)
        ``ν = z − H x⁻``, in the measurement's units.
    S : numpy.ndarray, shape (m, m)
        Innovation covariance ``H P⁻ Hᵀ + R``.
    K : numpy.ndarray, shape (n, m)
        Gain actually applied (zero columns for rejected channels).
    normalized : numpy.ndarray, shape (m,)
        ``S^{-1/2} ν`` (≈ N(0, I) when the filter is consistent).
    nis : float
        Normalised innovation squared ``νᵀ S⁻¹ ν`` over all channels.
    accepted : numpy.ndarray of bool, shape (m,)
        Channels used in the update.
    weights : numpy.ndarray, shape (m,)
        Measurement weights (1 = plain update, 0 = rejected, Huber weights in between).
    """

    innovation: Array
    S: Array
    K: Array
    normalized: Array
    nis: float
    accepted: NDArray[np.bool_]
    weights: Array


def riccati_steady_state(F: ArrayLike, Q: ArrayLike, H: ArrayLike, R: ArrayLike, G: ArrayLike | None = None) -> Array:
    """Steady-state *a-posteriori* covariance of the time-invariant filter.

    Solves the discrete algebraic Riccati equation for the prior covariance
    ``P⁻ = F P⁻ Fᵀ − F P⁻ Hᵀ (H P⁻ Hᵀ + R)⁻¹ H P⁻ Fᵀ + G Q Gᵀ``
    (:func:`scipy.linalg.solve_discrete_are` on the dual system) and returns
    ``P = P⁻ − P⁻ Hᵀ S⁻¹ H P⁻``.  For a scalar random walk (F = H = 1) this is
    ``P = (−Q + √(Q² + 4 Q R)) / 2``.

    Parameters
    ----------
    F : array_like, shape (n, n)
        State transition matrix.
    Q : array_like, shape (q, q)
        Process noise covariance (of ``w``; q = n without ``G``).
    H : array_like, shape (m, n)
        Measurement matrix.
    R : array_like, shape (m, m)
        Measurement noise covariance.
    G : array_like, shape (n, q), optional
        Noise-input matrix; default identity.

    Returns
    -------
    numpy.ndarray, shape (n, n)
        Steady-state posterior covariance ``P``.
    """

    F = as_matrix(F, "F")
    n = F.shape[0]
    H = as_matrix(H, "H", None, n)
    Gm = np.eye(n) if G is None else as_matrix(G, "G", n)
    Qn = Gm @ as_covariance(Q, "Q", Gm.shape[1]) @ Gm.T
    R = as_covariance(R, "R", H.shape[0])
    Pp = solve_discrete_are(F.T, H.T, Qn, R)
    S = H @ Pp @ H.T + R
    return symmetrize(Pp - Pp @ H.T @ np.linalg.solve(S, H @ Pp))


class KalmanFilter:
    """Linear Kalman filter with state ``x`` and covariance ``P``.

    Parameters
    ----------
    x0, P0 : array_like
        Initial state (n,) and covariance (n, n) (a vector is a diagonal).
    F, Q, H, R : array_like, optional
        Default model matrices; each call of :meth:`predict` /
        :meth:`update` may override them (time-varying models).
    B : array_like, shape (n, p), optional
        Control matrix; ``u`` is then passed to :meth:`predict`.
    G : array_like, shape (n, q), optional
        Noise-input matrix; Q is then (q, q) and the process
        noise covariance is ``G Q Gᵀ``.

    Attributes
    ----------
    x : numpy.ndarray, shape (n,)
        Current state estimate.
    P : numpy.ndarray, shape (n, n)
        Current covariance.

    Examples
    --------
    >>> kf = KalmanFilter([0.0], [[1.0]], F=[[1.0]], Q=[[0.01]], H=[[1.0]], R=[[0.5]])
    >>> kf.predict(); r = kf.update([0.3])
    """

    def __init__(
        self,
        x0: ArrayLike,
        P0: ArrayLike,
        F: ArrayLike | None = None,
        Q: ArrayLike | None = None,
        H: ArrayLike | None = None,
        R: ArrayLike | None = None,
        B: ArrayLike | None = None,
        G: ArrayLike | None = None,
    ) -> None:
        self.x = as_vector(x0, "x0")
        n = self.x.shape[0]
        self.P = as_covariance(P0, "P0", n)
        self.F = None if F is None else as_matrix(F, "F", n, n)
        self.G = None if G is None else as_matrix(G, "G", n)
        q = n if self.G is None else self.G.shape[1]
        self.Q = None if Q is None else as_covariance(Q, "Q", q)
        self.H = None if H is None else as_matrix(H, "H", None, n)
        self.R = None if R is None else as_covariance(R, "R", None if self.H is None else self.H.shape[0])
        self.B = None if B is None else as_matrix(B, "B", n)

    @property
    def n(self) -> int:
        return int(self.x.shape[0])

    def predict(
        self,
        u: ArrayLike | None = None,
        *,
        F: ArrayLike | None = None,
        Q: ArrayLike | None = None,
        B: ArrayLike | None = None,
        G: ArrayLike | None = None,
    ) -> tuple[Array, Array]:
        """Time update ``x⁻ = F x + B u``, ``P⁻ = F P Fᵀ + G Q Gᵀ`` (in place).

        Parameters
        ----------
        u : array_like, shape (p,), optional
            Control input (needs ``B``).
        F, Q, B, G : array_like, optional
            Model matrices for this step; default those given to the constructor.

        Returns
        -------
        x : numpy.ndarray, shape (n,)
            Predicted state.
        P : numpy.ndarray, shape (n, n)
            Predicted covariance.

        Raises
        ------
        InvalidInputError
            If ``F`` or ``Q`` is given neither here nor to the constructor, or ``u`` without ``B``.
        """
        n = self.n
        Fm = self.F if F is None else as_matrix(F, "F", n, n)
        if Fm is None:
            raise InvalidInputError("predict needs F: pass F= here or to the constructor")
        Gm = self.G if G is None else as_matrix(G, "G", n)
        q = n if Gm is None else Gm.shape[1]
        Qm = self.Q if Q is None else as_covariance(Q, "Q", q)
        if Qm is None:
            raise InvalidInputError("predict needs Q: pass Q= here or to the constructor")
        x = Fm @ self.x
        if u is not None:
            Bm = self.B if B is None else as_matrix(B, "B", n)
            if Bm is None:
                raise InvalidInputError("a control input u was given but no B: pass B=")
            x = x + Bm @ as_vector(u, "u", Bm.shape[1])
        Qn = Qm if Gm is None else Gm @ Qm @ Gm.T
        self.x = x
        self.P = predict_covariance(self.P, Fm, Qn)
        return self.x, self.P

    def innovation(self, z: ArrayLike, *, H: ArrayLike | None = None, R: ArrayLike | None = None
                   ) -> tuple[Array, Array, Array, Array]:
        """``(ν, S, H, R)`` for measurement ``z`` without changing the filter.

        Parameters
        ----------
        z : array_like, shape (m,)
            Measurement.
        H, R : array_like, optional
            Measurement matrix (m, n) and noise covariance (m, m); default the constructor's.

        Returns
        -------
        nu : numpy.ndarray, shape (m,)
            Innovation ``z − H x``.
        S : numpy.ndarray, shape (m, m)
            Innovation covariance ``H P Hᵀ + R``.
        H : numpy.ndarray, shape (m, n)
            The measurement matrix used.
        R : numpy.ndarray, shape (m, m)
            The noise covariance used.

        Raises
        ------
        InvalidInputError
            If ``H`` or ``R`` is missing, or their sizes disagree.
        """
        Hm = self.H if H is None else as_matrix(H, "H", None, self.n)
        if Hm is None:
            raise InvalidInputError("update needs H: pass H= here or to the constructor")
        Rm = self.R if R is None else as_covariance(R, "R", Hm.shape[0])
        if Rm is None:
            raise InvalidInputError("update needs R: pass R= here or to the constructor")
        if Rm.shape[0] != Hm.shape[0]:
            raise InvalidInputError(f"R is {Rm.shape} but H has {Hm.shape[0]} rows")
        zv = as_vector(z, "z", Hm.shape[0])
        nu = zv - Hm @ self.x
        S = symmetrize(Hm @ self.P @ Hm.T + Rm)
        return nu, S, Hm, Rm

    def update(
        self,
        z: ArrayLike,
        *,
        H: ArrayLike | None = None,
        R: ArrayLike | None = None,
        accept: ArrayLike | None = None,
    ) -> UpdateResult:
        """Measurement update in Joseph form (the core's ``joseph_update``); returns an :class:`UpdateResult`.

        Parameters
        ----------
        z : array_like, shape (m,)
            Measurement.
        H : array_like, shape (m, n), optional
            Measurement matrix; default the constructor's.
        R : array_like, shape (m, m), optional
            Measurement noise covariance; default the constructor's.
        accept : array_like of bool, shape (m,), optional
            Channels set False are not used (their gain column is zero).  All
            False leaves x and P at the prediction.

        Returns
        -------
        UpdateResult
            Innovation, its covariance, the gain applied, NIS (over all channels) and the channels used.

        Raises
        ------
        InvalidInputError
            If ``H`` or ``R`` is missing or of the wrong size, or ``accept`` has the wrong length.
        """
        nu, S, Hm, Rm = self.innovation(z, H=H, R=R)
        m = nu.shape[0]
        acc = np.ones(m, dtype=bool) if accept is None else np.asarray(accept, dtype=bool).reshape(-1)
        if acc.shape[0] != m:
            raise InvalidInputError(f"accept must have {m} flags (one per channel), got {acc.shape[0]}")
        normalized = inv_sqrt_spd(S) @ nu
        nis = float(core_nis(nu, S))
        K = np.zeros((self.n, m))
        if acc.any():
            idx = np.flatnonzero(acc)
            self.x, self.P, K[:, idx], _, _ = joseph_step(self.x, self.P, nu[idx], Hm[idx], Rm[np.ix_(idx, idx)])
        return UpdateResult(nu, S, K, normalized, nis, acc, acc.astype(np.float64))


@dataclass(frozen=True)
class KalmanRun(Result):
    """A whole-sequence linear Kalman filter run (see :func:`kalman_filter`).

    Attributes
    ----------
    x_pred : numpy.ndarray, shape (N, n)
        Prior state at each step.
    P_pred : numpy.ndarray, shape (N, n, n)
        Prior covariance at each step.
    x : numpy.ndarray, shape (N, n)
        Posterior state.
    P : numpy.ndarray, shape (N, n, n)
        Posterior covariance.
    innovation : numpy.ndarray, shape (N, m)
        Innovation; NaN at steps without a measurement.
    S : numpy.ndarray, shape (N, m, m)
        Innovation covariance; NaN without a measurement.
    nis : numpy.ndarray, shape (N,)
        Normalised innovation squared; NaN without a measurement.
    """

    x_pred: Array
    P_pred: Array
    x: Array
    P: Array
    innovation: Array
    S: Array
    nis: Array


def _lti_model(
    n: int, F: ArrayLike, Q: ArrayLike, H: ArrayLike, R: ArrayLike, G: ArrayLike | None
) -> tuple[Array, Array, Array, Array]:
    """Validated matrices of a time-invariant model with ``n`` states:
    ``F`` (n, n), process noise in the state space ``G Q Gᵀ`` (n, n),
    ``H`` (m, n) and ``R`` (m, m)."""
    Fm = as_matrix(F, "F", n, n)
    Gm = np.eye(n) if G is None else as_matrix(G, "G", n)
    Qn = Gm @ as_covariance(Q, "Q", Gm.shape[1]) @ Gm.T
    Hm = as_matrix(H, "H", None, n)
    Rm = as_covariance(R, "R", Hm.shape[0])
    return Fm, Qn, Hm, Rm


def kalman_filter(
    x0: ArrayLike,
    P0: ArrayLike,
    F: ArrayLike,
    Q: ArrayLike,
    H: ArrayLike,
    R: ArrayLike,
    z: ArrayLike,
    *,
    G: ArrayLike | None = None,
    B: ArrayLike | None = None,
    u: ArrayLike | None = None,
) -> KalmanRun:
    """Run a time-invariant linear filter over measurements ``z`` (N, m).

    Each step is predict then update of :class:`KalmanFilter` (the first measurement is at step 1, one
    prediction after ``x0``).  Rows of ``z`` that are all NaN are skipped
    (prediction only), which is how slower sensors are handled.  Many runs at
    once: :func:`batch_kalman_filter` (leading batch axis, vectorised over the runs).

    Parameters
    ----------
    x0 : array_like, shape (n,)
        Initial state.
    P0 : array_like, shape (n, n)
        Initial covariance.
    F : array_like, shape (n, n)
        State transition matrix.
    Q : array_like, shape (q, q)
        Process noise covariance (q = n without ``G``).
    H : array_like, shape (m, n)
        Measurement matrix.
    R : array_like, shape (m, m)
        Measurement noise covariance.
    z : array_like, shape (N, m)
        Measurements; all-NaN rows are missing.
    G : array_like, shape (n, q), optional
        Noise-input matrix.
    B : array_like, shape (n, p), optional
        Control matrix (needed with ``u``).
    u : array_like, shape (N, p), optional
        Control input at each step.

    Returns
    -------
    KalmanRun
        Priors, posteriors, innovations and NIS at each step.

    Raises
    ------
    InvalidInputError
        If ``z`` has the wrong shape, contains inf or partly-NaN rows, or ``u`` is given without ``B``.
    """

    x0v = as_vector(x0, "x0")
    n = x0v.shape[0]
    P0m = as_covariance(P0, "P0", n)
    Fm, Qn, Hm, Rm = _lti_model(n, F, Q, H, R, G)
    m = Hm.shape[0]
    zz = np.array(z, dtype=np.float64)
    if zz.ndim == 1 and m == 1:
        zz = zz[:, None]
    if zz.ndim != 2 or zz.shape[1] != m:
        raise InvalidInputError(f"z must have shape (N, {m}), got {zz.shape}")
    if np.any(np.isinf(zz)):
        raise InvalidInputError(f"z contains inf at row {int(np.argwhere(np.isinf(zz))[0, 0])}; use NaN for missing rows")
    part = np.isnan(zz).any(axis=1) & ~np.isnan(zz).all(axis=1)
    if part.any():
        raise InvalidInputError(f"z row {int(np.flatnonzero(part)[0])} is partly NaN; a missing measurement must be all NaN")
    Bu = np.zeros((zz.shape[0], n))
    if u is not None:
        if B is None:
            raise InvalidInputError("u was given without B")
        Bm = as_matrix(B, "B", n)
        uu = np.array(u, dtype=np.float64).reshape(zz.shape[0], Bm.shape[1])
        Bu = uu @ Bm.T
    kf = KalmanFilter(x0v, P0m, F=Fm, Q=Qn, H=Hm, R=Rm, B=np.eye(n))
    res: dict[str, list] = {k: [] for k in ("x_pred", "P_pred", "x", "P", "innovation", "S", "nis")}
    for k in range(zz.shape[0]):
        kf.predict(None if u is None else Bu[k])
        res["x_pred"].append(kf.x.copy())
        res["P_pred"].append(kf.P.copy())
        if np.isnan(zz[k, 0]):
            res["innovation"].append(np.full(m, np.nan))
            res["S"].append(np.full((m, m), np.nan))
            res["nis"].append(np.nan)
        else:
            r = kf.update(zz[k])
            res["innovation"].append(r.innovation)
            res["S"].append(r.S)
            res["nis"].append(r.nis)
        res["x"].append(kf.x.copy())
        res["P"].append(kf.P.copy())
    return KalmanRun(*(np.asarray(res[k]) for k in ("x_pred", "P_pred", "x", "P", "innovation", "S", "nis")))


@dataclass(frozen=True)
class BatchRun(Result):
    """Many independent runs of one linear filter (leading axis = run).

    Attributes
    ----------
    x : numpy.ndarray, shape (R, N, n)
        Posterior states.
    cov_diag : numpy.ndarray, shape (R, N, n)
        Diagonal of the posterior covariance.
    innovation : numpy.ndarray, shape (R, N, m)
        Innovations (NaN without measurement).
    normalized : numpy.ndarray, shape (R, N, m)
        Normalised innovations ``S^{-1/2} ν`` (NaN without measurement).
    weights : numpy.ndarray, shape (R, N, m)
        1 used, 0 rejected, Huber weight in between.
    """

    x: Array
    cov_diag: Array
    innovation: Array
    normalized: Array
    weights: Array


def robust_mode(robust: str | None, gate_m: float, alpha: float, huber_c: float) -> int:
    """The batch loop's mode code of a robust update, after checking its tuning values.

    Parameters
    ----------
    robust : {None, "gate", "isolate", "nis", "huber"}
        Robust update (None: the optimal filter).
    gate_m, alpha, huber_c : float
        Gate half-width (standard deviations), test level in (0, 1), Huber constant.

    Returns
    -------
    int
        One of the ``MODE_*`` codes of :func:`imunav.filters._batch.batch_filter`.

    Raises
    ------
    InvalidInputError
        If ``robust`` is unknown or a tuning value is out of range.
    """
    modes = {None: MODE_NONE, "gate": MODE_GATE, "isolate": MODE_ISOLATE, "huber": MODE_HUBER, "nis": MODE_NIS}
    if robust not in modes:
        raise InvalidInputError(f"robust must be None, 'gate', 'isolate', 'nis' or 'huber', got {robust!r}")
    for name, v in (("gate_m", gate_m), ("huber_c", huber_c)):
        if not (np.isfinite(v) and v > 0):
            raise InvalidInputError(f"{name} must be positive and finite (a gate of {v!r} normalised innovations "
                                    "rejects every measurement or none), e.g. gate_m=2 (command line: --gate-m 2)")
    if not 0.0 < alpha < 1.0:
        raise InvalidInputError(f"alpha must be a test level in (0, 1), got {alpha!r}")
    return modes[robust]


def batch_kalman_filter(
    x0: ArrayLike,
    P0: ArrayLike,
    F: ArrayLike,
    Q: ArrayLike,
    H: ArrayLike,
    R: ArrayLike,
    z: ArrayLike,
    *,
    G: ArrayLike | None = None,
    robust: str | None = None,
    gate_m: float = 2.0,
    alpha: float = 1e-3,
    huber_c: float = 1.345,
) -> BatchRun:
    """Run a time-invariant filter over a batch of measurement sequences z (R, N, m).

    ``robust``: None (optimal), ``"gate"`` (per-channel ``|ν̃_i| < gate_m``),
    ``"isolate"`` (χ² + w-test isolation at level ``alpha``), ``"nis"``
    (the whole measurement rejected when its NIS exceeds χ²_{1−alpha}(m)) or
    ``"huber"`` (see :mod:`imunav.filters.robust`).  x0 may be (n,) or per run (R, n).

    Parameters
    ----------
    x0 : array_like, shape (n,) or (R, n)
        Initial state, shared or per run.
    P0 : array_like, shape (n, n)
        Initial covariance.
    F, Q, H, R : array_like
        Time-invariant model matrices (as in :func:`kalman_filter`).
    z : array_like, shape (R, N, m)
        Measurement sequences; all-NaN rows are missing.
    G : array_like, shape (n, q), optional
        Noise-input matrix.
    robust : {None, "gate", "isolate", "nis", "huber"}, optional
        Robust update (default None: the optimal filter).
    gate_m : float, optional
        Per-channel gate half-width, standard deviations (``"gate"``).
    alpha : float, optional
        Test level in (0, 1) (``"isolate"``, ``"nis"``).
    huber_c : float, optional
        Huber threshold (``"huber"``).

    Returns
    -------
    BatchRun
        Posterior states, covariance diagonals, innovations and weights of every run.

    Raises
    ------
    InvalidInputError
        If ``robust`` is unknown, a tuning value is out of range, or ``x0`` / ``z`` have the wrong shape.
    """

    mode = robust_mode(robust, gate_m, alpha, huber_c)
    P0m = as_covariance(P0, "P0")
    n = P0m.shape[0]
    x0a = np.asarray(x0, dtype=np.float64)
    if x0a.shape[-1:] != (n,) or x0a.ndim > 2 or not np.all(np.isfinite(x0a)):
        raise InvalidInputError(f"x0 must be finite with shape ({n},) or (runs, {n}), got {x0a.shape}")
    Fm, Qn, Hm, Rm = _lti_model(n, F, Q, H, R, G)
    m = Hm.shape[0]
    zz = np.asarray(z, dtype=np.float64)
    if zz.ndim != 3 or zz.shape[2] != m:
        raise InvalidInputError(f"z must have shape (runs, N, {m}), got {zz.shape}")
    if x0a.ndim == 2 and x0a.shape[0] != zz.shape[0]:
        raise InvalidInputError(f"x0 has {x0a.shape[0]} runs but z has {zz.shape[0]}")
    o = batch_filter(x0a, P0m, Fm, Qn, Hm, Rm, zz, mode, float(gate_m),
                     isolation_thresholds(m, alpha), float(huber_c))
    return BatchRun(o["x"], o["P_diag"], o["innovation"], o["normalized"], o["weights"])
