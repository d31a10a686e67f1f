"""Wind-estimating air-data / Doppler Kalman filters.

Body-axis wind filter :class:`BodyWindFilter` (Akgün 2002, §5.2-5.3, 6.2a)
--------------------------------------------------------------------------

O. Akgün, *Hava verileri sistemi ile Doppler radarının Kalman süzgeci temelinde tümleştirilmesi*
(Integration of an air data system and a Doppler radar via Kalman filtering), MSc thesis, Istanbul
Technical University, 2002 ("the thesis").
Indirect, open-loop, body-axis filter with state (6)::

    x = [δX, δY, δZ, W_x, W_y, W_z]

**Sign convention (fixed here; the thesis's eqs. 5.3/5.7 and 5.9 disagree, and
the state is read as the wind itself):** ``W`` is the wind in body axes, defined by the wind
triangle ``V_G = V_A + W`` (ground velocity = air velocity + wind), and
``δX = X_G − X_A`` is the correction of the ADS dead-reckoning position
``X_A = Σ V_A T``.  The measurement is the Doppler minus ADS velocity::

    z = V_D − V_A = W + n_D − n_A,      R = (σ_A² + σ_D²) I = 4.01 I

and the outputs are ``V̂_G = V_A + Ŵ`` and ``X̂ = X_A + δX̂`` (thesis eqs.
5.7/5.8 with this sign).  With the thesis simulation ``V_A = V − W + n_A``
(eq. 5.9 as printed) the wind estimate converges to +W, as in its figures.

Model: ``Φ = [[I, T I], [0, (1 − T/τ) I]]`` (eq. 5.2, τ = 600 s; the printed
Φ rounds the diagonal to 1, which changes P by < 1e-6 over 500 steps),
``G = [0; I]``, ``Q = 0.001 I`` applied directly (the (βT − β²T²/2) factor of
eq. 5.2 is *not* used), ``H = [0 I]``, ``P₀ = diag(100, 100, 100, 10, 10, 10)``,
``x̂₀ = [0.1, 0.1, 0.1, 12, 7, 5]``, T = 1 ms.  Steady state
``P₄₄ = (−Q + √(Q² + 4QR))/2 = 0.06283``, gains 0.0157 / 0.00098.

Index convention: row k of every per-step array is the estimate after k + 1
updates; the thesis's "iteration n" is row ``n − 2`` (MATLAB stores the
initial condition at index 1), so its table values at iterations
50/100/101/150/200/≥300 are rows 48/98/99/148/198/≥298
(:func:`iteration_row`).  The thesis's measurement step s is row s − 1.

Long-horizon variant (:class:`LongHorizonFilter`)
-------------------------------------------------
For real flights: the wind in the *navigation* frame (it does not rotate
with the aircraft in turns) as first-order Gauss-Markov (σ_w, τ_w; discrete
``φ = e^{−Δt/τ}``, ``q = σ_w²(1 − φ²)``), NED dead-reckoning position
correction, exact discretisation (Van Loan), Doppler at its own low rate with
the ADS interpolated to the Doppler epochs, ``z = C_nb (V_D − V_A)``,
``R = C_nb (R_D + R_A) C_nbᵀ + σ_turb² I`` (turbulence as measurement noise of
the mean-wind filter), optional robust update.  The position states stay
unobservable (only their correlation with the wind helps): the reported
position σ grows and is reported honestly.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InvalidInputError, ShapeError
from imunav.filters import BatchRun, batch_kalman_filter
from imunav.filters._batch import batch_filter, huber_batch, isolate_batch, masked_update
from imunav.filters._common import inv_sqrt_spd, symmetrize
from imunav.filters._core import van_loan
from imunav.filters.gates import isolation_thresholds
from imunav.filters.kalman import _lti_model, robust_mode
from imunav.results import Result

__all__ = [
    "BodyWindFilterConfig",
    "body_wind_matrices",
    "iteration_row",
    "THESIS_ITERATIONS",
    "THESIS_P44",
    "WindFilterResult",
    "BodyWindFilter",
    "BodyWindState",
    "LongHorizonConfig",
    "LongHorizonResult",
    "LongHorizonFilter",
    "LongHorizonState",
]

Array = NDArray[np.float64]

# Akgün 2002, Table 6.3 (P(4/4) column, optimal filter)
THESIS_ITERATIONS = (50, 100, 101, 150, 200, 300, 500)
THESIS_P44 = (0.0965, 0.0686, 0.0684, 0.0640, 0.0631, 0.0628, 0.0628)


def iteration_row(iteration: int | ArrayLike) -> int | Array:
    """Row of the per-step arrays that matches iteration n of the source's tables (row = n − 2; Akgün 2002).

    Parameters
    ----------
    iteration : int or array_like of int
        Thesis iteration number(s), >= 2.

    Returns
    -------
    int or numpy.ndarray
        Row index (or indices) into the per-step arrays.

    Raises
    ------
    InvalidInputError
        If an iteration is below 2.
    """
    it = np.asarray(iteration)
    if np.any(it < 2):
        raise InvalidInputError("thesis iterations start at 2 (iteration 1 is the initial condition)")
    r = it - 2
    return int(r) if r.ndim == 0 else r


@dataclass(frozen=True)
class BodyWindFilterConfig(Result):
    """Parameters of :class:`BodyWindFilter` (defaults: the values of its source, Akgün 2002, §6.2).

    Attributes
    ----------
    dt : float
        Step T, s (> 0).
    wind_corr_time : float
        Correlation time of the wind states, s (> 0).
    wind_step_var : float
        Process noise variance of the wind states per step, (m/s)², applied directly (> = 0).
    ads_noise_std : float
        ADS velocity noise std per axis, m/s (> 0).
    doppler_noise_std : float
        Doppler velocity noise std per axis, m/s (>= 0).
    init_var : tuple of float
        Initial variances of (δX, δY, δZ, W_x, W_y, W_z), m² and (m/s)².
    x0 : tuple of float
        Initial state, m and m/s.
    velocity_decay : bool
        Use ``1 − T/τ`` on the wind diagonal of Φ (False: the printed 1).

    Raises
    ------
    InvalidInputError
        If a value is out of range or ``init_var`` / ``x0`` do not have 6 entries.

    References
    ----------
    O. Akgün, *Hava verileri sistemi ile Doppler radarının Kalman süzgeci temelinde tümleştirilmesi* (Integration
    of an air data system and a Doppler radar via Kalman filtering), MSc thesis, Istanbul Technical University,
    2002, §5.2-5.3, 6.2a.
    """

    dt: float = 0.001
    wind_corr_time: float = 600.0
    wind_step_var: float = 0.001
    ads_noise_std: float = 2.0
    doppler_noise_std: float = 0.1
    init_var: tuple[float, ...] = (100.0, 100.0, 100.0, 10.0, 10.0, 10.0)
    x0: tuple[float, ...] = (0.1, 0.1, 0.1, 12.0, 7.0, 5.0)
    velocity_decay: bool = True

    def __post_init__(self) -> None:
        if not (self.dt > 0 and self.wind_corr_time > 0 and self.wind_step_var >= 0 and self.ads_noise_std > 0
                and self.doppler_noise_std >= 0):
            raise InvalidInputError(f"invalid filter parameters: dt={self.dt}, wind_corr_time={self.wind_corr_time}, "
                                    f"wind_step_var={self.wind_step_var}, ads_noise_std={self.ads_noise_std}, "
                                    f"doppler_noise_std={self.doppler_noise_std} (need > 0)")
        if len(self.init_var) != 6 or len(self.x0) != 6:
            raise InvalidInputError("init_var and x0 must have 6 entries (δX, δY, δZ, W_x, W_y, W_z)")


def body_wind_matrices(cfg: BodyWindFilterConfig | None = None) -> dict[str, Array]:
    """F (Φ), G, Q, H, R, P0, x0 of the body-axis wind filter (:class:`BodyWindFilter`).

    Parameters
    ----------
    cfg : BodyWindFilterConfig, optional
        Filter parameters (default the thesis's).

    Returns
    -------
    dict of str to numpy.ndarray
        ``F`` (6, 6), ``G`` (6, 3), ``Q`` (3, 3), ``H`` (3, 6), ``R`` (3, 3), ``P0`` (6, 6), ``x0`` (6,).
    """
    c = BodyWindFilterConfig() if cfg is None else cfg
    I3 = np.eye(3)
    F = np.eye(6)
    F[:3, 3:] = c.dt * I3
    if c.velocity_decay:
        F[3:, 3:] = (1.0 - c.dt / c.wind_corr_time) * I3
    G = np.vstack([np.zeros((3, 3)), I3])
    H = np.hstack([np.zeros((3, 3)), I3])
    return {"F": F, "G": G, "Q": c.wind_step_var * I3, "H": H, "R": (c.ads_noise_std**2 + c.doppler_noise_std**2) * I3,
            "P0": np.diag(np.asarray(c.init_var, dtype=np.float64)), "x0": np.asarray(c.x0, dtype=np.float64)}


@dataclass(frozen=True)
class WindFilterResult(Result):
    """One run of the thesis filter.

    Attributes
    ----------
    x : numpy.ndarray, shape (N, 6)
        State estimates (δX, δY, δZ in m, W in m/s, body axes).
    cov_diag : numpy.ndarray, shape (N, 6)
        Diagonal of P.
    innovation : numpy.ndarray, shape (N, 3)
        Innovations, m/s.
    normalized : numpy.ndarray, shape (N, 3)
        Normalised innovations ``S^{-1/2} ν``.
    weights : numpy.ndarray, shape (N, 3)
        1 used, 0 rejected (Huber weight in between).
    wind : numpy.ndarray, shape (N, 3)
        Wind estimate ``x[:, 3:]``, m/s, body axes.
    difference_loop : numpy.ndarray, shape (N, 3)
        ``z`` (the raw wind of the difference loop), m/s.
    velocity : numpy.ndarray, shape (N, 3), or None
        Ground velocity ``V_A + Ŵ``, m/s (when ``v_ads`` is given).
    position : numpy.ndarray, shape (N, 3), or None
        Position ``X_A + δX̂``, m, relative to the start (when ``v_ads`` is given).
    robust : str or None
        The robust update used.
    """

    x: Array
    cov_diag: Array
    innovation: Array
    normalized: Array
    weights: Array
    wind: Array
    difference_loop: Array
    velocity: Array | None = None
    position: Array | None = None
    robust: str | None = None


def _check_z(z: ArrayLike, batch: bool) -> Array:
    zz = np.asarray(z, dtype=np.float64)
    want = 3 if batch else 2
    if zz.ndim != want or zz.shape[-1] != 3:
        raise ShapeError(f"z must have shape {'(runs, N, 3)' if batch else '(N, 3)'}, got {zz.shape}")
    if np.any(np.isinf(zz)):
        raise InvalidInputError("z contains inf; use NaN rows for missing measurements")
    return zz


@dataclass(frozen=True)
class BodyWindState:
    """The body-axis wind filter's estimate after one :meth:`BodyWindFilter.step` (one row of :class:`WindFilterResult`).

    Attributes
    ----------
    x : numpy.ndarray, shape (6,)
        State (δX, δY, δZ in m, W in m/s, body axes).
    cov_diag : numpy.ndarray, shape (6,)
        Diagonal of P.
    innovation, normalized, weights : numpy.ndarray, shape (3,)
        Innovation (m/s), normalised innovation, weights (1 used, 0 rejected); NaN / 0 without a measurement.
    """

    x: Array
    cov_diag: Array
    innovation: Array
    normalized: Array
    weights: Array


class BodyWindFilter:
    """Body-axis wind and position-correction filter on ``z = V_D − V_A`` (Doppler minus air-data velocity; module
    docstring).

    ``run(z)`` filters one sequence, ``run_batch(z)`` many at once (vectorised over runs),
    ``step(z_k)`` one measurement, with the same update code, the state carried between calls.

    Parameters
    ----------
    config : BodyWindFilterConfig, optional
        Filter parameters (default the thesis's).
    robust : {None, "gate", "isolate", "nis", "huber"}, optional
        None (optimal), ``"gate"`` (thesis, per channel |ν̃| < gate_m),
        ``"nis"`` (vector χ² gate at level alpha: rejects whole-sensor
        outliers, recommended for the ADS), ``"isolate"`` (χ² test + w-test
        isolation of single channels) or ``"huber"``.
    gate_m : float, optional
        Per-channel gate half-width, standard deviations (``"gate"``).
    alpha : float, optional
        Test level in (0, 1) (``"isolate"``, ``"nis"``).
    huber_c : float, optional
        Huber threshold (``"huber"``).

    Raises
    ------
    InvalidInputError
        If ``robust`` is unknown or a tuning value is out of range.
    """

    name = "thesis"

    def __init__(self, config: BodyWindFilterConfig | None = None, *, robust: str | None = None, gate_m: float = 2.0,
                 alpha: float = 1e-3, huber_c: float = 1.345) -> None:
        self.config = BodyWindFilterConfig() if config is None else config
        self._mode = robust_mode(robust, gate_m, alpha, huber_c)
        self.robust, self.gate_m, self.alpha, self.huber_c = robust, gate_m, alpha, huber_c
        self._m = body_wind_matrices(self.config)
        m = self._m
        self._lti = _lti_model(6, m["F"], m["Q"], m["H"], m["R"], m["G"])  # (F, G Q Gᵀ, H, R) as run_batch has them
        self.reset()

    def reset(self) -> None:
        """Back to the initial state ``config.x0``, ``diag(config.init_var)``: the next :meth:`step` is the first."""
        self.x = self._m["x0"].copy()
        self.P = self._m["P0"].copy()

    def run_batch(self, z: ArrayLike) -> BatchRun:
        """The filter over a batch of difference measurements ``z = V_D − V_A`` (runs, N, 3).

        Parameters
        ----------
        z : array_like, shape (runs, N, 3)
            Doppler minus ADS body velocity, m/s (NaN rows: no measurement).

        Returns
        -------
        BatchRun
            States, covariance diagonals, innovations and weights of every run.
        """
        m = self._m
        return batch_kalman_filter(m["x0"], m["P0"], m["F"], m["Q"], m["H"], m["R"], _check_z(z, True), G=m["G"],
                                   robust=self.robust, gate_m=self.gate_m, alpha=self.alpha, huber_c=self.huber_c)

    def run(self, z: ArrayLike, *, v_ads: ArrayLike | None = None) -> WindFilterResult:
        """Run the filter on ``z = V_D − V_A`` (N, 3) from the initial state.

        Parameters
        ----------
        z : array_like, shape (N, 3)
            Doppler minus ADS body velocity, m/s (NaN rows: no measurement).
        v_ads : array_like, shape (N, 3), optional
            ADS body velocity, m/s; gives the corrected ground velocity and
            position ``X_A + δX̂`` with ``X_A(k) = T Σ_{j≤k} V_A(j)``
            (positions are relative to the start).

        Returns
        -------
        WindFilterResult
            States, wind, innovations and, with ``v_ads``, ground velocity and position.

        Raises
        ------
        ShapeError
            If ``z`` is not (N, 3) or ``v_ads`` does not have the shape of ``z``.
        """
        c = self.config
        zz = _check_z(z, False)
        r = self.run_batch(zz[None])
        x = r.x[0]
        vel = pos = None
        if v_ads is not None:
            va = np.asarray(v_ads, dtype=np.float64)
            if va.shape != zz.shape:
                raise ShapeError(f"v_ads must have the shape of z {zz.shape}, got {va.shape}")
            vel = va + x[:, 3:]
            pos = c.dt * np.cumsum(va, axis=0) + x[:, :3]
        return WindFilterResult(x, r.cov_diag[0], r.innovation[0], r.normalized[0], r.weights[0], x[:, 3:].copy(),
                                zz, vel, pos, self.robust)

    def step(self, z_k: ArrayLike) -> BodyWindState:
        """One prediction over ``config.dt`` and the update with one measurement (the loop of :meth:`run_batch`).

        Parameters
        ----------
        z_k : array_like, shape (3,)
            Doppler minus ADS body velocity, m/s (all NaN: no measurement, prediction only).

        Returns
        -------
        BodyWindState
            The estimate after this step; ``self.x``, ``self.P`` hold it for the next.

        Raises
        ------
        ShapeError
            If ``z_k`` is not a 3-vector.
        InvalidInputError
            If ``z_k`` holds inf.
        """
        zk = _check_z(np.asarray(z_k, dtype=np.float64)[None], False)
        if zk.shape != (1, 3):
            raise ShapeError(f"z_k must be one measurement of shape (3,), got {np.shape(z_k)}")
        F, Qn, H, R = self._lti
        o = batch_filter(self.x, self.P, F, Qn, H, R, zk[None], self._mode, float(self.gate_m),
                         isolation_thresholds(3, self.alpha), float(self.huber_c), store_full=True)
        self.x, self.P = o["x"][0, 0].copy(), o["P"][0, 0].copy()
        return BodyWindState(self.x.copy(), o["P_diag"][0, 0], o["innovation"][0, 0], o["normalized"][0, 0],
                           o["weights"][0, 0])


# ----------------------------------------------------------------------------------------------
# long-horizon variant


@dataclass(frozen=True)
class LongHorizonConfig(Result):
    """Navigation-frame wind filter for real flights (see module docstring).

    Attributes
    ----------
    wind_std, wind_corr_time : float
        Gauss-Markov mean-wind std (m/s) and correlation time (s).
    turbulence_std, turbulence_corr_time : float
        Gauss-Markov gust std (m/s) and correlation time (s, ≈ L_u / V = 533 m / 200 m/s for Dryden at altitude).
    ads_noise_std, doppler_noise_std : float
        Body-axis velocity noise std (m/s) per axis.
    init_wind_var, init_position_var : float
        Initial variances (m²/s², m²).
    robust : str or None
        None, "gate", "isolate" (default), "nis" or "huber".
    alpha : float
        Test level of "isolate" and "nis", in (0, 1).
    gate_m : float
        Per-channel gate half-width of "gate", standard deviations.

    Raises
    ------
    InvalidInputError
        If a value is out of range or ``robust`` is unknown.
    """

    wind_std: float = 10.0
    wind_corr_time: float = 1800.0
    turbulence_std: float = 1.5
    turbulence_corr_time: float = 2.7
    ads_noise_std: tuple[float, float, float] = (0.3, 0.4, 0.4)
    doppler_noise_std: tuple[float, float, float] = (0.17, 0.17, 0.06)  # 4-beam LS, 0.1 m/s per beam, 65° depression
    init_wind_var: float = 400.0
    init_position_var: float = 1.0
    robust: str | None = "isolate"
    alpha: float = 1e-3
    gate_m: float = 3.0

    def __post_init__(self) -> None:
        if not (self.wind_std > 0 and self.wind_corr_time > 0 and self.turbulence_std >= 0
                and self.turbulence_corr_time > 0):
            raise InvalidInputError("wind_std, wind_corr_time, turbulence_corr_time must be > 0 and "
                                    "turbulence_std >= 0")
        if self.robust not in (None, "gate", "isolate", "nis", "huber"):
            raise InvalidInputError(f"robust must be None, 'gate', 'isolate', 'nis' or 'huber', got {self.robust!r}")
        if not (np.isfinite(self.gate_m) and self.gate_m > 0):
            raise InvalidInputError(f"gate_m must be positive and finite (a gate of {self.gate_m!r} normalised "
                                    "innovations rejects every measurement), e.g. gate_m=3 (command line: --gate-m 3)")
        if not 0.0 < self.alpha < 1.0:
            raise InvalidInputError(f"alpha must be a test level in (0, 1), got {self.alpha!r}")


@dataclass(frozen=True)
class LongHorizonResult(Result):
    """Long-horizon run: estimates at the Doppler epochs ``t``.

    Attributes
    ----------
    t : numpy.ndarray, shape (N,)
        Doppler epochs, s.
    wind : numpy.ndarray, shape (N, 3)
        NED total-wind estimate (mean + gust), m/s.
    wind_std : numpy.ndarray, shape (N, 3)
        Its standard deviation, m/s.
    mean_wind : numpy.ndarray, shape (N, 3)
        The slowly varying part, m/s.
    position : numpy.ndarray, shape (N, 3)
        Corrected NED position relative to the start, m.
    position_std : numpy.ndarray, shape (N, 3)
        Its standard deviation, m.
    normalized : numpy.ndarray, shape (N, 3)
        Normalised innovations.
    weights : numpy.ndarray, shape (N, 3)
        1 used, 0 rejected (Huber weight in between).
    config : LongHorizonConfig
        Settings used.
    """

    t: Array
    wind: Array
    wind_std: Array
    mean_wind: Array
    position: Array
    position_std: Array
    normalized: Array
    weights: Array
    config: LongHorizonConfig = field(default_factory=LongHorizonConfig)


def _van_loan(dt: float, c: LongHorizonConfig) -> tuple[Array, Array]:
    """Exact discrete (Φ, Q) per axis of ``δṗ = W + g``, ``Ẇ = −W/τ_w + w₁``, ``ġ = −g/τ_g + w₂``."""

    A = np.array([[0.0, 1.0, 1.0], [0.0, -1.0 / c.wind_corr_time, 0.0], [0.0, 0.0, -1.0 / c.turbulence_corr_time]])
    Qc = np.diag([0.0, 2.0 * c.wind_std**2 / c.wind_corr_time, 2.0 * c.turbulence_std**2 / c.turbulence_corr_time])
    return van_loan(A, Qc, float(dt))


@dataclass(frozen=True)
class LongHorizonState:
    """The long-horizon filter's estimate after one Doppler epoch (:meth:`LongHorizonFilter.step`).

    Attributes
    ----------
    t : float
        Doppler epoch, s.
    wind, wind_std, mean_wind : numpy.ndarray, shape (3,)
        NED total wind (mean + gust), its standard deviation and the mean part, m/s.
    position_correction, position_std : numpy.ndarray, shape (3,)
        Correction δp of the ADS dead-reckoning position and its standard deviation, m.
    normalized, weights : numpy.ndarray, shape (3,)
        Normalised innovation and weights (1 used, 0 rejected, Huber weight in between).
    """

    t: float
    wind: Array
    wind_std: Array
    mean_wind: Array
    position_correction: Array
    position_std: Array
    normalized: Array
    weights: Array


class LongHorizonFilter:
    """Navigation-frame wind filter for real flights on multi-rate ADS and Doppler data (module docstring).

    ``run(...)`` filters a whole flight; ``step(t, v_doppler_body, C_nb, v_air_ned)`` one Doppler epoch, with
    the same prediction and update code, the state carried between calls.

    Parameters
    ----------
    config : LongHorizonConfig, optional
        Settings (default :class:`LongHorizonConfig`).
    """

    name = "long_horizon"

    def __init__(self, config: LongHorizonConfig | None = None) -> None:
        self.config = LongHorizonConfig() if config is None else config
        c = self.config
        self._Rb = np.diag(np.asarray(c.ads_noise_std, dtype=np.float64) ** 2
                           + np.asarray(c.doppler_noise_std, dtype=np.float64) ** 2)
        self._H = np.hstack([np.zeros((3, 3)), np.eye(3), np.eye(3)])
        self._thr = isolation_thresholds(3, c.alpha)
        self._cache: dict[float, tuple[Array, Array]] = {}
        self.reset()

    def reset(self) -> None:
        """Back to the initial state: the next :meth:`step` is the first epoch (it initialises the wind)."""
        c = self.config
        self.x = np.zeros((1, 9))
        self.P = np.diag([c.init_position_var] * 3 + [c.init_wind_var] * 3
                         + [max(c.turbulence_std, 1e-3) ** 2] * 3)[None]
        self._t: float | None = None

    def _advance(self, tk: float, zk: Array, R: Array) -> LongHorizonState:
        """Predict from the previous epoch to ``tk`` and update with ``zk`` (NED, m/s), covariance ``R``."""
        c = self.config
        x, P, H = self.x, self.P, self._H
        first = self._t is None
        if not first:
            dt = round(float(tk - self._t), 9)
            if dt not in self._cache:
                Phi3, Q3 = _van_loan(dt, c)
                self._cache[dt] = (np.kron(Phi3, np.eye(3)), np.kron(Q3, np.eye(3)))
            F, Q = self._cache[dt]
            x = x @ F.T
            P = symmetrize(F @ P @ F.T + Q)
        nu = zk[None] - x @ H.T
        S = symmetrize(H @ P @ H.T + R)
        nn = (inv_sqrt_spd(S) @ nu[0])[0]
        mode = None if first else c.robust  # the first difference initialises the wind
        if mode == "huber":
            x, P, wk, _ = huber_batch(x, P, zk[None], H, R, 1.345, np.ones((1, 3), dtype=bool))
        else:
            if mode == "gate":
                acc = np.abs(nn[None]) < c.gate_m
            elif mode == "isolate":
                acc = isolate_batch(nu, S, self._thr)
            elif mode == "nis":
                acc = np.full((1, 3), float(nn @ nn) <= self._thr[-1])
            else:
                acc = np.ones((1, 3), dtype=bool)
            x, P, _ = masked_update(x, P, nu, H, R, acc)
            wk = acc.astype(np.float64)
        self.x, self.P, self._t = x, P, tk
        xs, pd = x[0], np.diag(P[0])
        wv = np.diag(H @ P[0] @ H.T)  # variance of W + g (includes their covariance)
        return LongHorizonState(tk, xs[3:6] + xs[6:9], np.sqrt(wv), xs[3:6].copy(), xs[:3].copy(),
                                np.sqrt(pd[:3]), nn, wk[0].copy())

    def step(self, t: float, v_doppler_body: ArrayLike, C_nb: ArrayLike, v_air_ned: ArrayLike) -> LongHorizonState:
        """One Doppler epoch: predict to ``t`` (Van Loan), update with ``z = C_nb V_D − V_A^n``.

        Parameters
        ----------
        t : float
            Doppler epoch, s, after the previous one.
        v_doppler_body : array_like, shape (3,)
            Doppler ground velocity in body axes (FRD), m/s.
        C_nb : array_like, shape (3, 3)
            Body-to-NED rotation at the epoch.
        v_air_ned : array_like, shape (3,)
            ADS air velocity in NED at the epoch (``C_nb V_A``, interpolated to ``t``), m/s.

        Returns
        -------
        LongHorizonState
            The estimate after this epoch.

        Raises
        ------
        ShapeError
            If an input has the wrong shape.
        InvalidInputError
            If an input is not finite or ``t`` is not after the previous epoch.
        """
        vd = np.asarray(v_doppler_body, dtype=np.float64)
        C = np.asarray(C_nb, dtype=np.float64)
        va = np.asarray(v_air_ned, dtype=np.float64)
        if vd.shape != (3,) or va.shape != (3,) or C.shape != (3, 3):
            raise ShapeError(f"v_doppler_body, v_air_ned must be (3,) and C_nb (3, 3); got {vd.shape}, {va.shape}, "
                             f"{C.shape}")
        for name, arr in (("v_doppler_body", vd), ("C_nb", C), ("v_air_ned", va)):
            if not np.all(np.isfinite(arr)):
                raise InvalidInputError(f"{name} contains NaN or inf: {arr!r}")
        tk = float(t)
        if not np.isfinite(tk) or (self._t is not None and not tk > self._t):
            raise InvalidInputError(f"t = {t!r} s must be finite and after the previous epoch ({self._t!r} s)")
        z = np.einsum("kij,kj->ki", C[None], vd[None])[0] - va
        R = np.einsum("kij,jl,kml->kim", C[None], self._Rb, C[None])[0]
        return self._advance(tk, z, R)

    def run(
        self,
        t_ads: ArrayLike,
        v_ads_body: ArrayLike,
        t_doppler: ArrayLike,
        v_doppler_body: ArrayLike,
        C_nb_doppler: ArrayLike,
        C_nb_ads: ArrayLike,
    ) -> LongHorizonResult:
        """Long-horizon wind filter on multi-rate ADS and Doppler data, from the initial state.

        State per NED axis: DR position correction δp, mean wind W, gust g
        (9 states).  The ADS NED air velocity ``C_nb V_A`` is integrated on its
        own time grid (trapezoidal dead reckoning) and interpolated to the
        Doppler epochs; each Doppler sample gives
        ``z = C_nb V_D − C_nb V_A = W + g + noise`` with
        ``R = C_nb (R_D + R_A) C_nbᵀ``.  Φ and Q are discretised exactly (Van Loan 1978,
        IEEE Trans. Autom. Control 23(3)).

        Parameters
        ----------
        t_ads : array_like, shape (N,)
            ADS time, s, strictly increasing.
        v_ads_body : array_like, shape (N, 3)
            ADS air velocity in body axes (FRD), m/s.
        t_doppler : array_like, shape (M,)
            Doppler time, s, strictly increasing, within the ADS span.
        v_doppler_body : array_like, shape (M, 3)
            Doppler ground velocity in body axes (FRD), m/s.
        C_nb_doppler : array_like, shape (M, 3, 3)
            Body-to-NED rotation matrices at the Doppler epochs.
        C_nb_ads : array_like, shape (N, 3, 3)
            Body-to-NED rotation matrices at the ADS epochs.

        Returns
        -------
        LongHorizonResult
            Wind, position and their standard deviations at the Doppler epochs.

        Raises
        ------
        ShapeError
            If an array does not match its time vector.
        InvalidInputError
            If a time vector is not strictly increasing, the Doppler epochs leave the ADS span, or an
            input is not finite.
        """
        c = self.config
        ta = np.asarray(t_ads, dtype=np.float64)
        td = np.asarray(t_doppler, dtype=np.float64)
        va = np.asarray(v_ads_body, dtype=np.float64)
        vd = np.asarray(v_doppler_body, dtype=np.float64)
        Cd = np.asarray(C_nb_doppler, dtype=np.float64)
        Ca = np.asarray(C_nb_ads, dtype=np.float64)
        if va.shape != (ta.size, 3) or Ca.shape != (ta.size, 3, 3):
            raise ShapeError(f"ADS arrays must be (N, 3) and (N, 3, 3) for {ta.size} times; got {va.shape}, "
                             f"{Ca.shape}")
        if vd.shape != (td.size, 3) or Cd.shape != (td.size, 3, 3):
            raise ShapeError(f"Doppler arrays must be (M, 3) and (M, 3, 3) for {td.size} times; got {vd.shape}, "
                             f"{Cd.shape}")
        for name, tt in (("t_ads", ta), ("t_doppler", td)):
            if tt.size < 2 or np.any(np.diff(tt) <= 0):
                raise InvalidInputError(f"{name} must be strictly increasing with >= 2 samples")
        if td[0] < ta[0] or td[-1] > ta[-1]:
            raise InvalidInputError("Doppler epochs must lie within the ADS time span (the ADS is interpolated)")
        for name, a in (("v_ads_body", va), ("v_doppler_body", vd), ("C_nb_ads", Ca), ("C_nb_doppler", Cd)):
            if not np.all(np.isfinite(a)):
                raise InvalidInputError(f"{name} contains NaN or inf at row {int(np.argwhere(~np.isfinite(a))[0, 0])}")
        va_n = np.einsum("kij,kj->ki", Ca, va)
        pa = np.concatenate([np.zeros((1, 3)),
                             np.cumsum(0.5 * (va_n[1:] + va_n[:-1]) * np.diff(ta)[:, None], axis=0)])
        va_d = np.stack([np.interp(td, ta, va_n[:, i]) for i in range(3)], axis=1)
        pa_d = np.stack([np.interp(td, ta, pa[:, i]) for i in range(3)], axis=1)
        z = np.einsum("kij,kj->ki", Cd, vd) - va_d
        R_all = np.einsum("kij,jl,kml->kim", Cd, self._Rb, Cd)
        self.reset()
        st = [self._advance(float(td[k]), z[k], R_all[k]) for k in range(td.size)]
        col = {f.name: np.array([getattr(s_, f.name) for s_ in st]) for f in fields(LongHorizonState)}
        return LongHorizonResult(td, col["wind"], col["wind_std"], col["mean_wind"], pa_d + col["position_correction"],
                                 col["position_std"], col["normalized"], col["weights"], c)
