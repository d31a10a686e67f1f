"""The air-data / Doppler wind scenarios (simulated flights of the body-axis wind filter) and their Monte Carlo
evaluation.

After O. Akgün, *Hava verileri sistemi ile Doppler radarının Kalman süzgeci temelinde tümleştirilmesi*
(Integration of an air data system and a Doppler radar via Kalman filtering), MSc thesis, Istanbul
Technical University, 2002, §5.3 and ch. 6 ("the thesis").

Scenario (the thesis's §6.2): T = 1 ms, 500 steps, ADS noise σ = 2 m/s and Doppler
σ = 0.1 m/s per body axis at every step, true wind (Gauss-Markov truth with
no process noise, eq. 5.5) from ``x_g(0) = [0.1, 0.1, 0.1, 7, 5, 1.7]``,
true aircraft velocity from the Charlie model (it cancels in z).  Sensors,
with the sign convention of :mod:`imunav.airdata.filter`::

    V_A = V − W + n_A   (eq. 5.9),    V_D = V + n_D   (eq. 5.10),    z = V_D − V_A

Kinds: ``nominal``; ``outliers`` (ADS noise ×15 at thesis steps 100, 200,
300, 400 on all channels); ``variance`` (ADS noise ×3.5 from thesis step 151
on); ``bias`` (+10 m/s on the ADS from step 151); ``drift``; ``stuck``.
Thesis step s is row s − 1 of the arrays.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav.airdata.doppler import DopplerErrors
from imunav.airdata.filter import (
    THESIS_ITERATIONS,
    THESIS_P44,
    BodyWindFilter,
    BodyWindFilterConfig,
    body_wind_matrices,
    iteration_row,
)
from imunav.airdata.flight import FlightConfig, simulate_linear_aircraft
from imunav.errors import ConfigError, InvalidInputError
from imunav.filters import Fault, inject_faults
from imunav.filters.faults import (
    DETECTORS,
    alarms,
    calibrated_thresholds,
    detect_faults,
    detection_delays,
    detector_statistics,
    false_alarm_rates,
    window_chi2_thresholds,
)
from imunav.results import Result
from imunav.toml import read_toml

__all__ = [
    "KINDS",
    "WindScenario",
    "WindScenarioData",
    "simulate_wind_scenario",
    "simulate_wind_scenario_batch",
    "simulate_detector_statistics",
    "delay_summary",
    "fault_detection_table",
    "covariance_sequence",
    "actual_error_covariance",
    "WindMonteCarlo",
    "wind_monte_carlo",
    "wind_scenario_report",
    "load_config",
    "wind_scenario_tables",
]

Array = NDArray[np.float64]
KINDS = ("nominal", "outliers", "variance", "bias", "drift", "stuck")


@dataclass(frozen=True)
class WindScenario(Result):
    """Wind-scenario parameters (defaults and 1-based steps as in the source, Akgün 2002, §6.2).

    Attributes
    ----------
    kind : str
        ``"nominal"``, ``"outliers"``, ``"variance"``, ``"bias"``, ``"drift"`` or ``"stuck"``.
    n_steps : int
        Number of filter steps.
    dt : float
        Step, s.
    ads_noise_std, doppler_noise_std : float
        Noise standard deviation per body axis of the air-data and Doppler velocities, m/s.
    wind_corr_time : float
        Correlation time of the Gauss-Markov wind, s.
    x_true0 : tuple of float
        Initial true state ``(δX, W)``: position error (m) and wind (m/s), body axes.
    outlier_steps : tuple of int
        Steps of the outliers (``kind="outliers"``).
    outlier_factor : float
        Noise multiplier of an outlier.
    fault_step : int
        First step of a variance, bias, drift or stuck fault.
    variance_factor : float
        Noise multiplier of a variance fault.
    bias : float
        Bias fault, m/s.
    drift_rate : float
        Drift fault rate, m/s per s.
    channels : tuple of int or None
        Body axes affected by the fault (None: all).
    filter : BodyWindFilterConfig
        The filter run on the scenario.
    """

    kind: str = "nominal"
    n_steps: int = 500
    dt: float = 0.001
    ads_noise_std: float = 2.0
    doppler_noise_std: float = 0.1
    wind_corr_time: float = 600.0
    x_true0: tuple[float, ...] = (0.1, 0.1, 0.1, 7.0, 5.0, 1.7)
    outlier_steps: tuple[int, ...] = (100, 200, 300, 400)
    outlier_factor: float = 15.0
    fault_step: int = 151
    variance_factor: float = 3.5
    bias: float = 10.0
    drift_rate: float = 200.0  # m/s per s (0.2 m/s per 1 ms step)
    channels: tuple[int, ...] | None = None
    filter: BodyWindFilterConfig = field(default_factory=BodyWindFilterConfig)

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise InvalidInputError(f"kind must be one of {KINDS}, got {self.kind!r}")
        if self.n_steps < 25:
            raise InvalidInputError(f"n_steps must be >= 25 (detector window), got {self.n_steps}")
        if not 1 <= self.fault_step <= self.n_steps:
            raise InvalidInputError(f"fault_step must be within 1..{self.n_steps}, got {self.fault_step}")
        if any(not 1 <= s <= self.n_steps for s in self.outlier_steps):
            raise InvalidInputError(f"outlier_steps must be within 1..{self.n_steps}")

    @property
    def onset_row(self) -> int:
        return self.fault_step - 1

    def faults(self) -> list[Fault]:
        """The injected faults of this scenario, for :mod:`imunav.filters.faults`.

        Returns
        -------
        list of Fault
            One entry per fault (empty for ``"nominal"`` and ``"outliers"``).
        """
        ch = self.channels
        o = self.onset_row
        return {
            "nominal": [],
            "outliers": [Fault("outlier", magnitude=self.outlier_factor, channels=ch,
                               steps=tuple(s - 1 for s in self.outlier_steps))],
            "variance": [Fault("noise", o, self.variance_factor, ch)],
            "bias": [Fault("bias", o, self.bias, ch)],
            "drift": [Fault("drift", o, self.drift_rate, ch)],
            "stuck": [Fault("stuck", o, 0.0, ch)],
        }[self.kind]

    def anomaly_mask(self) -> NDArray[np.bool_]:
        """Where the injected fault / outlier affects a sample.

        Returns
        -------
        numpy.ndarray of bool, shape (N, 3)
            True at the affected (step, body axis).

        Raises
        ------
        InvalidInputError
            If the kind is unknown, or a step or channel lies outside the run.
        """
        m = np.zeros((self.n_steps, 3), dtype=bool)
        ch = slice(None) if self.channels is None else list(self.channels)
        if self.kind == "outliers":
            rows = [s - 1 for s in self.outlier_steps]
            for r in rows:
                m[r, ch] = True
        elif self.kind != "nominal":
            m[self.onset_row:, ch] = True
        return m


@dataclass(frozen=True)
class WindScenarioData(Result):
    """One simulated run of a wind scenario: truth and sensors, (N, 3) per body axis unless noted.

    Attributes
    ----------
    t : numpy.ndarray, shape (N,)
        Time, s.
    x_true : numpy.ndarray, shape (N, 6)
        True error state ``(δX, W)``: position error (m), wind (m/s).
    wind_true : numpy.ndarray, shape (N, 3)
        ``x_true[:, 3:]``, m/s.
    v_true : numpy.ndarray
        Body velocity over the ground, m/s.
    v_ads : numpy.ndarray
        Air-data velocity, m/s.
    v_doppler : numpy.ndarray
        Doppler velocity, m/s.
    z : numpy.ndarray
        Filter measurement ``V_D − V_A``, m/s.
    ads_noise : numpy.ndarray
        Air-data noise drawn, m/s.
    anomaly : numpy.ndarray of bool
        :meth:`WindScenario.anomaly_mask`.
    scenario : WindScenario
        The scenario simulated.
    """

    t: Array
    x_true: Array
    wind_true: Array
    v_true: Array
    v_ads: Array
    v_doppler: Array
    z: Array
    ads_noise: Array
    anomaly: NDArray[np.bool_]
    scenario: WindScenario


def _truth(sc: WindScenario) -> Array:
    cfg = replace(sc.filter, dt=sc.dt, wind_corr_time=sc.wind_corr_time)
    F = body_wind_matrices(cfg)["F"]
    x = np.asarray(sc.x_true0, dtype=np.float64)
    out = np.empty((sc.n_steps, 6))
    for k in range(sc.n_steps):
        x = F @ x
        out[k] = x
    return out


def _simulate(s: WindScenario, n_runs: int, rng: np.random.Generator | int | None) -> tuple[Array, ...]:
    """Truth x (N, 6), aircraft velocity v (N, 3), ADS va, Doppler vd and ADS noise (runs, N, 3)."""

    gen = np.random.default_rng(rng)
    xt = _truth(s)
    N = s.n_steps
    v = simulate_linear_aircraft(N, s.dt).velocity  # same deterministic flight for every run
    na = s.ads_noise_std * gen.standard_normal((n_runs, N, 3))
    nd = s.doppler_noise_std * gen.standard_normal((n_runs, N, 3))
    va = v[None] - xt[None, :, 3:] + na  # eq. 5.9; faults act on the ADS output
    faults = s.faults()
    if faults:
        va = np.stack([inject_faults(va[r], faults, noise=na[r], dt=s.dt) for r in range(n_runs)])
    return xt, v, va, v[None] + nd, na


def simulate_wind_scenario_batch(sc: WindScenario | None = None, n_runs: int = 100,
                          rng: np.random.Generator | int | None = None) -> tuple[Array, Array, Array]:
    """Measurements of many runs of a scenario at once, for Monte Carlo.

    Parameters
    ----------
    sc : WindScenario, optional
        The scenario (default: the nominal one).
    n_runs : int
        Number of runs, >= 1.
    rng : numpy.random.Generator or int, optional
        Random generator or seed.

    Returns
    -------
    z : numpy.ndarray, shape (runs, N, 3)
        Filter measurements ``V_D − V_A``, m/s.
    x_true : numpy.ndarray, shape (N, 6)
        True state (the same for every run: the truth has no process noise).
    ads_noise : numpy.ndarray, shape (runs, N, 3)
        Air-data noise drawn, m/s.

    Raises
    ------
    InvalidInputError
        If ``n_runs < 1``.
    """
    s = WindScenario() if sc is None else sc
    if n_runs < 1:
        raise InvalidInputError(f"n_runs must be >= 1, got {n_runs}")
    xt, _, va, vd, na = _simulate(s, n_runs, rng)
    return vd - va, xt, na


def simulate_wind_scenario(sc: WindScenario | None = None, rng: np.random.Generator | int | None = None) -> WindScenarioData:
    """One run of a wind scenario with the aircraft truth (Charlie model) and both sensors.

    Parameters
    ----------
    sc : WindScenario, optional
        The scenario (default: the nominal one).
    rng : numpy.random.Generator or int, optional
        Random generator or seed.

    Returns
    -------
    WindScenarioData
        Truth and sensor outputs.
    """
    s = WindScenario() if sc is None else sc
    xt, v, va, vd, na = _simulate(s, 1, rng)
    return WindScenarioData(s.dt * np.arange(1, s.n_steps + 1), xt, xt[:, 3:].copy(), v, va[0], vd[0], vd[0] - va[0], na[0],
                      s.anomaly_mask(), s)


def simulate_detector_statistics(
    sc: WindScenario,
    n_runs: int,
    rng: np.random.Generator | int | None,
    window: int,
    *,
    chunk: int = 250,
    cfg: BodyWindFilterConfig | None = None,
    on_chunk: Callable[[int], None] | None = None,
) -> dict[str, Array]:
    """Detector statistics of many simulated runs through the thesis filter.

    :func:`imunav.filters.faults.detector_statistics` with window ``window`` over ``n_runs`` runs of ``sc``,
    simulated ``chunk`` runs at a time (bounded memory).

    Parameters
    ----------
    sc : WindScenario
        The scenario.
    n_runs : int
        Number of runs.
    rng : numpy.random.Generator or int, optional
        Random generator or seed.
    window : int
        Detector window, steps.
    chunk : int
        Runs simulated at a time.
    cfg : BodyWindFilterConfig, optional
        Filter configuration (default: the thesis's values).
    on_chunk : callable, optional
        Called as ``on_chunk(n)`` after each chunk of ``n`` runs (progress).

    Returns
    -------
    dict of str to numpy.ndarray
        Per detector, its statistic for every run (runs stacked along the first axis).

    Raises
    ------
    InvalidInputError
        If ``n_runs < 1``.
    """
    if n_runs < 1:
        raise InvalidInputError(f"n_runs must be >= 1, got {n_runs}")
    gen = np.random.default_rng(rng)
    out: dict[str, list[Array]] = {d: [] for d in DETECTORS}
    for i in range(0, n_runs, chunk):
        n = min(chunk, n_runs - i)
        z, _, _ = simulate_wind_scenario_batch(sc, n, gen)
        st = detector_statistics(BodyWindFilter(cfg).run_batch(z).normalized, window)
        for d in DETECTORS:
            out[d].append(st[d])
        if on_chunk is not None:
            on_chunk(n)
    return {d: np.concatenate(v) for d, v in out.items()}


def delay_summary(alarm: NDArray[np.bool_], onset_row: int, horizon: int = 10) -> dict[str, float | None]:
    """Detection-delay figures of an alarm matrix for a fault at ``onset_row``.

    Delays as :func:`imunav.filters.faults.detection_delays` (the onset sample is delay 1).

    Parameters
    ----------
    alarm : numpy.ndarray of bool, shape (runs, steps)
        Alarm of each run at each step.
    onset_row : int
        Row of the first faulty sample.
    horizon : int
        Steps within which a detection counts as prompt.

    Returns
    -------
    dict
        ``median_delay``, ``p90_delay``, ``p99_delay``, ``max_delay`` (steps; None when no run detects),
        ``detected_within_<horizon>`` and ``missed`` (share of runs never detected).
    """
    delays, missed = detection_delays(alarm, onset_row)
    _, missed_h = detection_delays(alarm, onset_row, horizon)
    ok = delays[np.isfinite(delays)]
    return {
        "median_delay": float(np.median(ok)) if ok.size else None,
        "p90_delay": float(np.percentile(ok, 90)) if ok.size else None,
        "p99_delay": float(np.percentile(ok, 99)) if ok.size else None,
        "max_delay": float(ok.max()) if ok.size else None,
        f"detected_within_{horizon}": 1.0 - missed_h,
        "missed": missed,
    }


def fault_detection_table(sc: WindScenario, runs: int, seed: int, *, window: int = 20, p_false_alarm: float = 0.01,
                          horizon: int = 10, chunk: int = 50,
                          on_chunk: Callable[[int], None] | None = None) -> dict[str, Any]:
    """Monte Carlo fault detection on a thesis scenario: every detector's delay, misses and false alarms.

    ``runs`` runs of ``sc`` (the fault) and ``runs`` nominal runs go through the thesis filter
    (:func:`simulate_detector_statistics`, seeds spawned from ``seed``); each detector of
    :data:`imunav.filters.faults.DETECTORS` is thresholded with the calibrated thresholds (per-step false-alarm
    rate ``p_false_alarm``) and with the thesis's, where it has one.

    Parameters
    ----------
    sc : WindScenario
        The fault scenario.
    runs : int
        Monte Carlo runs of the fault and of the nominal scenario (>= 1).
    seed : int
        Random seed.
    window : int, optional
        Detector window M, steps.
    p_false_alarm : float, optional
        Per-step false-alarm rate of the calibrated thresholds.
    horizon : int, optional
        Steps after the onset counted as timely.
    chunk : int, optional
        Runs simulated at a time (at most ``runs``).
    on_chunk : callable, optional
        Called as ``on_chunk(n)`` after each chunk of ``n`` runs (progress; ``2 runs`` in all).

    Returns
    -------
    dict
        ``scenario``, ``runs``, ``seed``, ``window``, ``pfa`` and ``rows``: per detector and threshold mode
        (``"calibrated"``, ``"thesis"``) the ``threshold``, ``median_delay``, ``p90_delay`` (steps, onset = 1;
        None if never detected), ``detected_within_<horizon>``, ``missed`` (shares of runs) and
        ``false_alarm_per_step``, ``false_alarm_per_run`` under nominal data (the JSON of ``imunav airdata
        faults``).

    Raises
    ------
    InvalidInputError
        If ``runs`` < 1.
    """
    if runs < 1:
        raise InvalidInputError(f"--runs must be >= 1, got {runs}")
    thr = calibrated_thresholds(window, 3, p_false_alarm)
    th = window_chi2_thresholds(window, 3)
    ss = np.random.SeedSequence(seed).spawn(2)
    chunk = max(1, min(chunk, runs))
    stats_f = simulate_detector_statistics(sc, runs, np.random.default_rng(ss[0]), window, chunk=chunk,
                                           on_chunk=on_chunk)
    stats_n = simulate_detector_statistics(WindScenario(kind="nominal"), runs, np.random.default_rng(ss[1]), window,
                                           chunk=chunk, on_chunk=on_chunk)
    o = sc.onset_row
    rows = []
    for d in DETECTORS:
        sn = stats_n[d][:, window - 1:]
        for label, t in (("calibrated", thr[d]), ("thesis", th.get(d))):
            if t is None:
                continue
            summary = delay_summary(alarms(d, stats_f[d], t), o, horizon)
            fa_step, fa_run = false_alarm_rates(alarms(d, sn, t))
            rows.append({"detector": d, "threshold_mode": label, "threshold": float(t),
                         **{k: summary[k] for k in ("median_delay", "p90_delay", f"detected_within_{horizon}", "missed")},
                         "false_alarm_per_step": fa_step, "false_alarm_per_run": fa_run})
    return {"scenario": sc.to_dict(), "runs": runs, "seed": seed, "window": window, "pfa": p_false_alarm, "rows": rows}


def covariance_sequence(cfg: BodyWindFilterConfig | None = None, n_steps: int = 500) -> dict[str, list[float]]:
    """P44 and P11 at the thesis's table iterations, beside the thesis's P44 values (Akgün 2002, Table 6.3).

    Parameters
    ----------
    cfg : BodyWindFilterConfig, optional
        Filter configuration (default: the thesis's values).
    n_steps : int
        Number of steps.

    Returns
    -------
    dict of str to list of float
        ``iteration``, ``P44`` and ``P11`` of the filter, and the thesis's column ``P44_thesis``.
    """
    r = BodyWindFilter(cfg).run(np.zeros((n_steps, 3)))
    rows = iteration_row(np.asarray(THESIS_ITERATIONS))
    return {"iteration": list(THESIS_ITERATIONS), "P44": [float(r.cov_diag[k, 3]) for k in rows],
            "P11": [float(r.cov_diag[k, 0]) for k in rows], "P44_thesis": list(THESIS_P44)}


def actual_error_covariance(cfg: BodyWindFilterConfig | None = None, n_steps: int = 500,
                            x_error0: tuple[float, ...] = (0.0, 0.0, 0.0, 5.0, 2.0, 3.3),
                            ads_noise_std: float = 2.0, doppler_noise_std: float = 0.1) -> tuple[Array, Array]:
    """Exact mean and covariance of the estimation error when the truth has no process noise.

    The thesis's truth (eq. 5.5) has no process noise while the filter assumes
    Q = 0.001, so the actual error ``e = x̂ − x`` evolves as
    ``e⁺ = (I − K H) F e⁻ + K v`` with the filter's own gains K:
    ``E⁺ = (I−KH) F E Fᵀ (I−KH)ᵀ + K R_true Kᵀ`` and mean ``(I−KH) F μ``
    (initial error = x̂₀ − x_g(0)).

    Parameters
    ----------
    cfg : BodyWindFilterConfig, optional
        Filter configuration (default: the thesis's values).
    n_steps : int
        Number of steps.
    x_error0 : tuple of float
        Initial estimation error, m and m/s.
    ads_noise_std, doppler_noise_std : float
        True noise standard deviations, m/s.

    Returns
    -------
    mean : numpy.ndarray, shape (N, 6)
        Mean error.
    var : numpy.ndarray, shape (N, 6)
        Diagonal of the error covariance.
    """
    m = body_wind_matrices(cfg)
    F, H, G, Q, R = m["F"], m["H"], m["G"], m["Q"], m["R"]
    Rt = (ads_noise_std**2 + doppler_noise_std**2) * np.eye(3)
    P = m["P0"].copy()
    E = np.zeros((6, 6))
    mu = np.asarray(x_error0, dtype=np.float64)
    mus = np.empty((n_steps, 6))
    Es = np.empty((n_steps, 6))
    I6 = np.eye(6)
    for k in range(n_steps):
        P = F @ P @ F.T + G @ Q @ G.T
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
        A = (I6 - K @ H)
        P = A @ P @ A.T + K @ R @ K.T
        E = A @ F @ E @ F.T @ A.T + K @ Rt @ K.T
        mu = A @ F @ mu
        mus[k] = mu
        Es[k] = np.diag(E)
    return mus, Es


@dataclass(frozen=True)
class WindMonteCarlo(Result):
    """Monte Carlo figures of the wind scenarios (see :func:`wind_monte_carlo`).

    Attributes
    ----------
    n_runs : int
        Runs per scenario.
    seed : int
        Seed of the run.
    wind : dict
        Wind-error figures of the nominal scenario.
    robust : dict
        Rejection figures of each robust method.
    false_alarms : dict
        False-alarm rates of every detector.
    detection : dict
        Detection delays of the variance and bias faults.
    thresholds : dict
        Calibrated and thesis detector thresholds.
    """

    n_runs: int
    seed: int
    wind: dict
    robust: dict
    false_alarms: dict
    detection: dict
    thresholds: dict


def _rms_theory(cfg: BodyWindFilterConfig, n_steps: int, k0: int) -> float:
    mu, E = actual_error_covariance(cfg, n_steps)
    return float(np.sqrt(np.mean(mu[k0:, 3:] ** 2 + E[k0:, 3:])))


def _rms(e: Array, axis=None) -> Array:
    return np.sqrt(np.mean(e**2, axis=axis))


def wind_monte_carlo(
    n_runs: int = 200,
    rng: int = 0,
    *,
    p_false_alarm: float = 0.01,
    window: int = 20,
    robust_methods: tuple[str, ...] = ("gate2", "gate3", "nis", "isolate", "huber"),
    horizon: int = 10,
) -> WindMonteCarlo:
    """Seeded Monte Carlo of all thesis scenarios.

    * wind: per-axis RMS wind error of the KF over thesis iterations ≥ 100
      (rows ≥ 98) and of the difference loop, variance ratio, RMS position
      error at the last step.
    * robust: for each method, the share of injected anomalous channel-samples
      rejected (weight 0; Huber: weight < 0.1), false rejections on nominal
      data, nominal RMS relative to the optimal filter, and RMS over the 50
      steps after each outlier.
    * false_alarms: per-step and per-run false-alarm rates of every detector
      under nominal data (rows where the window is full), with the calibrated
      and the thesis thresholds.
    * detection: variance and bias faults: detection delay (onset sample =
      delay 1) median / p90 / max, share detected within ``horizon`` steps,
      missed by the end of the run.

    Parameters
    ----------
    n_runs : int
        Runs per scenario.
    rng : int
        Seed.
    p_false_alarm : float
        Per-step false-alarm probability the detector thresholds are calibrated to.
    window : int
        Detector window, steps.
    robust_methods : tuple of str
        Robust updates compared (``"gate2"``, ``"gate3"``, ``"nis"``, ``"isolate"``, ``"huber"``).
    horizon : int
        Steps within which a detection counts as prompt.

    Returns
    -------
    WindMonteCarlo
        The figures above.

    Raises
    ------
    InvalidInputError
        If a robust method is unknown.
    """
    seed = int(rng)
    ss = np.random.SeedSequence(seed)
    seeds = {k: int(s.generate_state(1)[0]) for k, s in zip(KINDS, ss.spawn(len(KINDS)))}
    base = WindScenario()
    cfg = base.filter
    k0 = iteration_row(100)

    # ---- nominal: optimal filter accuracy
    z, xt, _ = simulate_wind_scenario_batch(base, n_runs, seeds["nominal"])
    opt = BodyWindFilter(cfg).run_batch(z)
    ew = opt.x[:, k0:, 3:] - xt[None, k0:, 3:]
    ed = z[:, k0:] - xt[None, k0:, 3:]
    ep = opt.x[:, -1, :3] - xt[None, -1, :3]
    wind = {
        "kf_rms_per_axis": _rms(ew, (0, 1)).tolist(),
        "kf_rms_theory": _rms_theory(cfg, base.n_steps, k0),
        "kf_rms": float(_rms(ew)),
        "difference_loop_rms": float(_rms(ed)),
        "variance_ratio": float(np.var(ed) / np.var(ew)),
        "kf_mean_error": float(np.mean(ew)),
        "P44_steady": float(opt.cov_diag[0, -1, 3]),
        "empirical_error_variance": float(np.var(ew)),
        "position_state_rms_end": float(_rms(ep)),
        "rows": [int(k0), int(base.n_steps - 1)],
    }
    nominal_rms = float(_rms(ew))

    # ---- robust filters
    zo, xto, _ = simulate_wind_scenario_batch(replace(base, kind="outliers"), n_runs, seeds["outliers"])
    mask = replace(base, kind="outliers").anomaly_mask()
    opt_o = BodyWindFilter(cfg).run_batch(zo)
    after = np.zeros(base.n_steps, dtype=bool)
    for s in base.outlier_steps:
        after[s - 1:s - 1 + 50] = True

    def _after_rms(x: Array) -> float:
        return float(_rms(x[:, after, 3:] - xto[None, after, 3:]))

    robust = {"optimal": {"rms_with_outliers": float(_rms(opt_o.x[:, k0:, 3:] - xto[None, k0:, 3:])),
                          "rms_50_steps_after_outliers": _after_rms(opt_o.x), "nominal_rms": nominal_rms,
                          "n_anomalous_samples_per_run": int(mask.sum())}}
    for meth in robust_methods:
        kw: dict = {}
        if meth.startswith("gate"):
            kw = {"robust": "gate", "gate_m": float(meth[4:])}
        elif meth in ("isolate", "nis"):
            kw = {"robust": meth}
        elif meth == "huber":
            kw = {"robust": "huber"}
        else:
            raise InvalidInputError(f"unknown robust method {meth!r}: use gate<m>, nis, isolate or huber")
        ro = BodyWindFilter(cfg, **kw).run_batch(zo)
        rn = BodyWindFilter(cfg, **kw).run_batch(z)
        rej = ro.weights < (0.1 if meth == "huber" else 0.5)
        rejn = rn.weights < (0.1 if meth == "huber" else 0.5)
        nom_rms = float(_rms(rn.x[:, k0:, 3:] - xt[None, k0:, 3:]))
        robust[meth] = {
            "rejected_anomalous": float(rej[:, mask].mean()),
            "rejected_nominal": float(rejn.mean()),
            "nominal_rms": nom_rms,
            "nominal_rms_ratio_to_optimal": nom_rms / nominal_rms,
            "rms_with_outliers": float(_rms(ro.x[:, k0:, 3:] - xto[None, k0:, 3:])),
            "rms_50_steps_after_outliers": _after_rms(ro.x),
        }

    # ---- detectors: thresholds, false alarms on nominal data
    M = window
    thr = calibrated_thresholds(M, 3, p_false_alarm)
    th = window_chi2_thresholds(M, 3)
    stats_n = detector_statistics(opt.normalized, M)
    valid = np.zeros(base.n_steps, dtype=bool)
    valid[M - 1:] = True
    fa = {}
    for d in DETECTORS:
        a = alarms(d, stats_n[d], thr[d])
        ps, pr = false_alarm_rates(a[:, valid])
        fa[d] = {"threshold": thr[d], "per_step": ps, "per_run": pr}
        if d in th:
            at = alarms(d, stats_n[d], th[d])
            pst, prt = false_alarm_rates(at[:, valid])
            fa[d].update(thesis_threshold=th[d], per_step_thesis=pst, per_run_thesis=prt)

    # ---- detection of variance and bias faults
    det = {}
    for kind in ("variance", "bias", "drift", "stuck"):
        sc = replace(base, kind=kind)
        zf, _, _ = simulate_wind_scenario_batch(sc, n_runs, seeds[kind])
        rf = BodyWindFilter(cfg).run_batch(zf)
        st = detector_statistics(rf.normalized, M)
        o = sc.onset_row
        det[kind] = {"onset_row": o}
        for d in DETECTORS:
            entry = {}
            for label, t in (("calibrated", thr[d]), ("thesis", th.get(d))):
                if t is None:
                    continue
                summary = delay_summary(alarms(d, st[d], t), o, horizon)
                entry[label] = {k: summary[k] for k in
                                ("median_delay", "p90_delay", "max_delay", f"detected_within_{horizon}", "missed")}
            det[kind][d] = entry
    thr_out = {"calibrated": thr, "thesis": th, "p_false_alarm": p_false_alarm, "window": M}
    return WindMonteCarlo(n_runs, seed, wind, robust, fa, det, thr_out)


def wind_scenario_report(n_runs: int = 200, rng: int = 0, **kw) -> dict:
    """Everything ``imunav airdata thesis`` writes: covariance sequence, Monte Carlo, one seeded run's detection steps.

    Parameters
    ----------
    n_runs : int
        Monte Carlo runs per scenario.
    rng : int
        Seed.
    **kw
        Keywords of :func:`wind_monte_carlo`.

    Returns
    -------
    dict
        JSON-ready report.
    """

    cov = covariance_sequence()
    mc = wind_monte_carlo(n_runs, rng, **kw)
    single = {}
    for kind in ("variance", "bias"):
        d = simulate_wind_scenario(WindScenario(kind=kind), rng)
        r = BodyWindFilter().run(d.z)
        out = {}
        for mode in ("calibrated", "thesis"):
            res = detect_faults(r.normalized, 20, threshold_mode=mode, start=d.scenario.onset_row)
            # thesis step of the detection: row + 1
            out[mode] = {k: (v.first_alarm + 1 if v.first_alarm >= 0 else None) for k, v in res.detectors.items()}
        single[kind] = {"fault_step": d.scenario.fault_step, "detection_step": out,
                        "thesis_detection_step": {"variance": {"alg1": 152, "alg2": 160, "alg3": 153},
                                                  "bias": {"alg3": 152}}[kind]}
    return {"covariance_sequence": cov, "monte_carlo": mc.to_dict(), "single_run_detection": single,
            "wind_scenario_tables": wind_scenario_tables(rng)}


def wind_scenario_tables(rng: int = 0) -> dict:
    """One seeded run laid out like Tables 6.1 and 6.3 of the source (Akgün 2002; x axis).

    Table 6.1: wind x error of the difference loop and of the KF at iterations
    50…500.  Table 6.3: x wind error and P44 of the optimal and the robust
    filter (thesis gate ±2 and vector χ² gate) with outliers at steps
    100/200/300/400, at iterations 50, 100, 101, …, 500.  Errors are
    estimate − truth, m/s; iteration n is row n − 2.

    Parameters
    ----------
    rng : int
        Seed.

    Returns
    -------
    dict
        ``table_6_1`` and ``table_6_3`` (columns of the tables) and ``seed``.
    """
    its1 = list(range(50, 501, 50))
    d = simulate_wind_scenario(WindScenario(), rng)
    r = BodyWindFilter().run(d.z)
    rows = iteration_row(np.asarray(its1))
    t61 = [{"iteration": i, "difference_loop": float(d.z[k, 0] - d.wind_true[k, 0]),
            "kf": float(r.wind[k, 0] - d.wind_true[k, 0])} for i, k in zip(its1, rows)]
    its3 = [50, 100, 101, 150, 200, 201, 250, 300, 301, 350, 400, 401, 450, 500]
    do = simulate_wind_scenario(WindScenario(kind="outliers"), rng)
    runs = {"optimal": BodyWindFilter().run(do.z), "gate2": BodyWindFilter(robust="gate", gate_m=2.0).run(do.z),
            "nis": BodyWindFilter(robust="nis").run(do.z)}
    t63 = []
    for i, k in zip(its3, iteration_row(np.asarray(its3))):
        row = {"iteration": i}
        for name, rr in runs.items():
            row[f"{name}_err"] = float(rr.wind[k, 0] - do.wind_true[k, 0])
            row[f"{name}_P44"] = float(rr.cov_diag[k, 3])
        t63.append(row)
    return {"table_6_1": t61, "table_6_3": t63, "seed": int(rng)}


def load_config(path) -> "WindScenario | object":
    """Read a TOML scenario.

    A ``[thesis]`` table gives a :class:`WindScenario`, a ``[flight]`` table a
    :class:`imunav.airdata.flight.FlightConfig` (tuples given as arrays; ``doppler`` as a sub-table of
    :class:`~imunav.airdata.doppler.DopplerErrors` fields).

    Parameters
    ----------
    path : str or os.PathLike
        The TOML file.

    Returns
    -------
    WindScenario or FlightConfig
        The scenario.

    Raises
    ------
    ConfigError
        If the file cannot be read or parsed, has neither table, or holds unknown keys or bad values.
    """

    p = Path(path)
    doc = read_toml(p, "scenario")
    keys = [k for k in ("thesis", "flight") if k in doc]
    if len(keys) != 1:
        raise ConfigError(f"{p}: needs exactly one [thesis] or [flight] table, found {list(doc) or 'none'}")
    table = dict(doc[keys[0]])
    if keys[0] == "thesis":
        cls = WindScenario
    else:
        cls = FlightConfig
        if "doppler" in table:
            sub = table.pop("doppler")
            known = {f.name for f in dataclasses.fields(DopplerErrors)}
            bad = set(sub) - known
            if bad:
                raise ConfigError(f"{p}: [flight.doppler] unknown key(s) {sorted(bad)}; known: {sorted(known)}")
            table["doppler"] = DopplerErrors(**{k: tuple(v) if isinstance(v, list) else v for k, v in sub.items()})
    known = {f.name for f in dataclasses.fields(cls)} - {"filter"}
    bad = set(table) - known
    if bad:
        raise ConfigError(f"{p}: [{keys[0]}] unknown key(s) {sorted(bad)}; known: {sorted(known)}")
    conv = {k: (tuple(tuple(x) if isinstance(x, list) else x for x in v) if isinstance(v, list) else v)
            for k, v in table.items()}
    try:
        return cls(**conv)
    except InvalidInputError as exc:
        raise ConfigError(f"{p}: {exc}") from exc
    except TypeError as exc:
        raise ConfigError(f"{p}: {exc}") from exc
