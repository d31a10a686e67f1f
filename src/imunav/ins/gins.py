"""Loosely coupled GNSS/INS: an error-state Kalman filter on the NED strapdown, aided by GNSS position and velocity.

:class:`GinsFilter` integrates IMU rates (:class:`~imunav.timeseries.ImuData`, with two-sample coning / sculling
corrections) or increments (:class:`~imunav.io.kfgins.ImuIncrements`) with
:func:`imunav.filters._core.strapdown_step_ned` and estimates 15 error states (position, velocity, attitude,
gyro and accelerometer biases) or 21 (plus scale factors), biases and scale factors being first-order
Gauss–Markov processes with configurable σ and correlation time (:class:`GinsConfig`).  GNSS fixes are used at
their own time stamps between IMU samples, with the antenna lever arm, behind a χ² gate; every epoch's NIS is
recorded.  Odometer + non-holonomic constraint, ZUPT + ZARU, barometric height and magnetometer heading are
further aiding models, each with its gate and NIS record.  ``GinsFilter(config).run(imu, gnss, ...)`` filters a
recording; ``reset(...)`` then ``step(t, dθ, dv, gnss=..., ...)`` runs the same kernel one increment at a time.
The equations are in :mod:`imunav.ins._gins_kernels`.

Example
-------
>>> import numpy as np
>>> from imunav.ins.gins import GinsConfig, GinsFilter
>>> from imunav.sim import presets, simulate_imu
>>> from imunav.sim.gnss import simulate_gnss
>>> from imunav.sim.vehicle import demo_drive, vehicle_trajectory
>>> truth = vehicle_trajectory(demo_drive(120), fs=100)
>>> imu = simulate_imu(truth, presets.get("navigation_a15"), rng=1)
>>> gnss = simulate_gnss(truth, rng=2)
>>> cfg = GinsConfig.from_preset("navigation_a15")
>>> res = GinsFilter(cfg).run(imu, gnss, lla0=truth.pos_lla[0], vel0=truth.vel_ned[0], q0=truth.q_nb[0])
>>> bool(np.all(np.isfinite(res.lla)))
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav._quantiles import chi2_ppf
from imunav.earth import OMEGA_E, ned_to_dlla
from imunav.errors import InvalidInputError, NonFiniteError, ShapeError
from imunav.ins import _gins_kernels as _k
from imunav.ins.strapdown import coning_sculling_increments
from imunav.io.gnss import GnssData
from imunav.io.kfgins import ImuIncrements, KfGinsConfig
from imunav.results import EulerMixin, Result
from imunav.rotation import quat_from_rotvec, quat_multiply, quat_normalize
from imunav.sim import presets
from imunav.sim.gnss import MagnetometerData
from imunav.sim.vehicle import BaroData, OdometerData
from imunav.timeseries import ImuData

__all__ = ["GinsConfig", "GinsFilter", "GinsResult", "SmoothedTrack", "STATE_NAMES"]

Array = NDArray[np.float64]

#: Names of the error states, in filter order (the first 15 of the 21-state filter are the 15-state filter).
STATE_NAMES = tuple(f"{g}_{a}" for g in ("pos", "vel", "att", "gyro_bias", "accel_bias", "gyro_scale",
                                           "accel_scale") for a in "xyz")


def _v3(x: ArrayLike, name: str, *, positive: bool = False, nonneg: bool = False) -> Array:
    a = np.asarray(x, dtype=float) * np.ones(3)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ShapeError(f"GinsConfig.{name} must be a finite scalar or 3-vector; got {x!r}")
    if positive and np.any(a <= 0):
        raise InvalidInputError(f"GinsConfig.{name} = {a.tolist()}: a standard deviation / time must be > 0")
    if nonneg and np.any(a < 0):
        raise InvalidInputError(f"GinsConfig.{name} = {a.tolist()}: must be >= 0")
    return a


@dataclass(frozen=True)
class GinsConfig:
    """Configuration of :class:`GinsFilter`, SI units.

    A scalar given for a 3-vector applies to the three axes.

    Parameters
    ----------
    arw : float or array_like, shape (3,)
        Gyro white noise (angle random walk), rad/√s (> 0).
    vrw : float or array_like, shape (3,)
        Accelerometer white noise (velocity random walk), m/s/√s (> 0).
    gyro_bias_std, accel_bias_std : float or array_like, shape (3,)
        Stationary Gauss–Markov σ of the biases, rad/s and m/s² (> 0).
    gyro_scale_std, accel_scale_std : float or array_like, shape (3,)
        Stationary Gauss–Markov σ of the scale-factor errors, dimensionless (> 0).
    corr_time : float
        Correlation time of the bias and odometer-scale Gauss–Markov states, s (> 0; KF-GINS: ``corrtime``;
        ``inf``: random constants, no process noise — a state's variance then keeps its initial value, where a
        Gauss–Markov state's initial variance above its stationary σ² decays as ``exp(−2t/T)``).
    scale_factors : bool
        True: 21 states; False: 15 (no scale-factor states).
    init_pos_std, init_vel_std, init_att_std : float or array_like, shape (3,)
        Initial σ of position (m, NED), velocity (m/s, NED) and attitude (rad, about N/E/D: roll, pitch,
        yaw at level).
    init_gyro_bias_std, init_accel_bias_std : float or array_like, shape (3,), optional
        Initial σ of the bias states, rad/s and m/s² (default: their Gauss–Markov σ).
    init_gyro_scale_std, init_accel_scale_std : float or array_like, shape (3,), optional
        Initial σ of the scale-factor states, dimensionless (default: their Gauss–Markov σ).
    lever_arm : array_like, shape (3,)
        GNSS antenna from the IMU, body FRD, m.
    use_gnss_velocity : bool
        Use the fixes' velocity when they have one.
    gate_alpha : float
        False-alarm probability of the χ² gates, in [0, 1) (0 disables the gates).
    cov_interval_s : float
        Covariance propagation step, s (> 0; the nominal state is integrated every sample).
    odo_lever_arm : array_like, shape (3,)
        Wheel contact point from the IMU, body FRD, m (odometer and non-holonomic constraint).
    odo_noise : float
        Odometer speed σ, m/s (> 0).  The odometer and the NHC are applied at the covariance steps, not while
        ``static`` says the vehicle stands still (the ZUPT holds the velocity then; a wheel encoder reads 0).
    odo_scale_std : float
        σ of the odometer scale-factor state (Gauss–Markov with ``corr_time``), dimensionless (> 0).
    nhc_noise : float or None
        σ of the non-holonomic constraint (zero lateral and vertical wheel velocity), m/s: the side slip and
        suspension velocity of the body in motion; None: off.  Not applied while ``static`` says the vehicle
        stands still: the ZUPT constrains the same velocity then (with ``zupt_noise``), and the one velocity
        used twice as two independent measurements would make the filter overconfident.
    zupt_noise : float
        σ of the zero-velocity update applied while ``static`` says the vehicle stands still, m/s: the body's
        vibration at rest, e.g. engine idle (> 0).
    zaru_noise : float
        σ of the angular-rate disturbance at rest (vibration), rad/s (>= 0).  The zero-angular-rate update reads
        the mean raw rate over the covariance step Δt; the gyros' white noise adds ``ARW² / Δt`` per axis to
        its variance by itself.
    baro_noise : float
        σ of the barometric height, m (its bias included: no baro-bias state; > 0).
    scale_corr_time : float or None
        Correlation time of the IMU scale-factor states, s (> 0; ``inf``: random constants, no process
        noise; None: ``corr_time``, as KF-GINS).
    declination : float
        Magnetic declination, rad (east positive), for the magnetometer heading.
    mag_heading_noise : float
        σ of the magnetometer heading, rad (> 0; about the field noise over its horizontal strength, plus
        the residual calibration and disturbance errors).

    Raises
    ------
    ShapeError
        If a vector field is neither a finite scalar nor a finite 3-vector.
    InvalidInputError
        If a σ, a time or the gate probability is out of range.
    """

    arw: Any
    vrw: Any
    gyro_bias_std: Any
    accel_bias_std: Any
    gyro_scale_std: Any = 1e-3
    accel_scale_std: Any = 1e-3
    corr_time: float = 3600.0
    scale_factors: bool = True
    init_pos_std: Any = 1.0
    init_vel_std: Any = 0.1
    init_att_std: Any = (1e-3, 1e-3, 1e-2)
    init_gyro_bias_std: Any = None
    init_accel_bias_std: Any = None
    init_gyro_scale_std: Any = None
    init_accel_scale_std: Any = None
    lever_arm: Any = (0.0, 0.0, 0.0)
    use_gnss_velocity: bool = True
    gate_alpha: float = 1e-6
    cov_interval_s: float = 0.2
    odo_lever_arm: Any = (0.0, 0.0, 0.0)
    odo_noise: float = 0.05
    odo_scale_std: float = 0.01
    nhc_noise: float | None = None
    zupt_noise: float = 0.01
    zaru_noise: float = 1e-4
    baro_noise: float = 2.0
    scale_corr_time: float | None = None
    declination: float = 0.0
    mag_heading_noise: float = 0.02

    def __post_init__(self) -> None:
        s = object.__setattr__
        for name in ("arw", "vrw", "gyro_bias_std", "accel_bias_std", "gyro_scale_std", "accel_scale_std",
                     "init_pos_std", "init_vel_std", "init_att_std"):
            s(self, name, _v3(getattr(self, name), name, positive=True))
        for name, src in (("init_gyro_bias_std", "gyro_bias_std"), ("init_accel_bias_std", "accel_bias_std"),
                          ("init_gyro_scale_std", "gyro_scale_std"), ("init_accel_scale_std", "accel_scale_std")):
            v = getattr(self, name)
            s(self, name, getattr(self, src) if v is None else _v3(v, name, positive=True))
        s(self, "lever_arm", _v3(self.lever_arm, "lever_arm"))
        s(self, "odo_lever_arm", _v3(self.odo_lever_arm, "odo_lever_arm"))
        if not np.isfinite(self.declination) or abs(self.declination) > np.pi:
            raise InvalidInputError(f"GinsConfig.declination must be in [-pi, pi] rad; got {self.declination!r}")
        for name in ("odo_noise", "odo_scale_std", "mag_heading_noise"):
            if not (np.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                raise InvalidInputError(f"GinsConfig.{name} must be > 0; got {getattr(self, name)!r}")
        if self.nhc_noise is not None and not (np.isfinite(self.nhc_noise) and self.nhc_noise > 0):
            raise InvalidInputError(f"GinsConfig.nhc_noise must be > 0 m/s or None; got {self.nhc_noise!r}")
        if not (self.corr_time > 0):
            raise InvalidInputError(f"GinsConfig.corr_time must be > 0 s (inf: constant); got {self.corr_time!r}")
        if not (0 <= self.gate_alpha < 1):
            raise InvalidInputError(f"GinsConfig.gate_alpha must be in [0, 1); got {self.gate_alpha!r}")
        if self.scale_corr_time is not None and not (self.scale_corr_time > 0):
            raise InvalidInputError(f"GinsConfig.scale_corr_time must be > 0 s (inf: constant) or None; "
                                    f"got {self.scale_corr_time!r}")
        if not (self.cov_interval_s > 0):
            raise InvalidInputError(f"GinsConfig.cov_interval_s must be > 0 s; got {self.cov_interval_s!r}")

    @property
    def n_states(self) -> int:
        """15 or 21."""
        return _k.NX21 if self.scale_factors else _k.NX15

    @classmethod
    def from_kfgins(cls, cfg: KfGinsConfig, **overrides: Any) -> GinsConfig:
        """The filter configuration of a KF-GINS YAML (:func:`imunav.io.kfgins.load_kfgins_config`).

        Noise densities, Gauss–Markov σ and correlation time, initial σ and the antenna lever arm are
        taken from ``cfg``; the other fields keep their defaults.

        Parameters
        ----------
        cfg : KfGinsConfig
            The configuration read by :func:`~imunav.io.kfgins.load_kfgins_config` (SI).
        **overrides
            Any field of :class:`GinsConfig`, replacing the value taken from ``cfg``.

        Returns
        -------
        GinsConfig
            The filter configuration.
        """
        n = cfg.noise
        kw: dict[str, Any] = dict(
            arw=n.arw, vrw=n.vrw, gyro_bias_std=n.gyro_bias_std, accel_bias_std=n.accel_bias_std,
            gyro_scale_std=n.gyro_scale_std, accel_scale_std=n.accel_scale_std, corr_time=n.corr_time,
            init_pos_std=cfg.init_pos_std, init_vel_std=cfg.init_vel_std, init_att_std=cfg.init_att_std,
            init_gyro_bias_std=cfg.init_gyro_bias_std, init_accel_bias_std=cfg.init_accel_bias_std,
            init_gyro_scale_std=cfg.init_gyro_scale_std, init_accel_scale_std=cfg.init_accel_scale_std,
            lever_arm=cfg.antenna_lever_arm,
        )
        kw.update(overrides)
        return cls(**kw)

    @classmethod
    def from_preset(cls, name: str, *, white_below_s: float = 100.0, **overrides: Any) -> GinsConfig:
        """A configuration matched to what the IMU preset of :mod:`imunav.sim.presets` simulates: white noise
        densities, biases as a random constant (the turn-on bias) plus the in-run instability, scale factors as
        random constants.

        The initial bias σ is ``√(b_0² + Σ σ_i²)`` (turn-on bias and the bias-instability components
        ``σ_i``, ``τ_i``) and the correlation time ``T`` the longest ``τ_i``.  Components with
        ``τ_i < white_below_s`` average out within the spans the filter bridges and are modelled as white
        noise added to the ARW / VRW (PSD ``2σ_i²τ_i``); the Gauss–Markov σ of the bias states is chosen so
        that their driving noise ``2σ²/T`` equals that of the slower ones, ``Σ 2σ_i²/τ_i``.  Folding the
        constant turn-on bias into the Gauss–Markov σ instead (before) made the ADIS16465-class accelerometer
        bias walk about 20 times too strong (position RMSE 1.10 x pyins' in ``benchmarks/bench_gins_pyins.py``);
        driving the bias with every component (``white_below_s = 0``) makes the gyro bias walk too fast
        (outage drift 33.6 m vs 8.7 m).  Measured on the ADIS16465 preset (pyins-bench position RMSE m /
        60 s outage horizontal drift m, GNSS only, 900 s drive) for ``white_below_s`` = 0, 1, 10, 30, 100, 300,
        3000 s: 0.354 / 33.6, 0.337 / 18.7, 0.330 / 11.7, 0.331 / 9.3, 0.334 / 8.7, 0.339 / 11.5, 0.354 / 24.1:
        100 s is kept.  The scale σ is 1.5 times the preset's scale-factor error, with
        ``scale_corr_time = inf`` (the presets' scale factors are constants).

        Parameters
        ----------
        name : str
            Preset name (:func:`imunav.sim.presets.get`, e.g. ``"navigation_a15"``).
        white_below_s : float
            Bias-instability components with a shorter correlation time are modelled as white noise, s (>= 0).
        **overrides
            Any field of :class:`GinsConfig`, replacing the value derived from the preset.

        Returns
        -------
        GinsConfig
            The filter configuration.

        Raises
        ------
        InvalidInputError
            If ``white_below_s`` is negative, or a field is out of range (as :class:`GinsConfig`).
        """
        m = presets.get(name)

        if not (white_below_s >= 0):
            raise InvalidInputError(f"white_below_s must be >= 0 s; got {white_below_s!r}")

        def parts(te):
            sig, tc = te.bias_instability.components() if te.bias_instability is not None else (np.zeros((1, 3)),
                                                                                                  np.full((1, 3), 3600.0))
            slow = tc >= white_below_s
            walk = np.sum(np.where(slow, 2.0 * sig**2 / tc, 0.0), axis=0)
            white = np.sqrt(te.noise_density**2 + np.sum(np.where(slow, 0.0, 2.0 * sig**2 * tc), axis=0))
            return np.sqrt(te.bias**2 + np.sum(sig**2, axis=0)), walk, float(np.max(tc)), white

        gb0, gq, tg, gw = parts(m.gyro)
        ab0, aq, ta, aw = parts(m.accel)
        tc = max(tg, ta)
        kw: dict[str, Any] = dict(
            arw=np.maximum(gw, 1e-9), vrw=np.maximum(aw, 1e-9),
            gyro_bias_std=np.maximum(np.sqrt(gq * tc / 2.0), 1e-12),
            accel_bias_std=np.maximum(np.sqrt(aq * tc / 2.0), 1e-12),
            init_gyro_bias_std=np.maximum(gb0, 1e-12), init_accel_bias_std=np.maximum(ab0, 1e-12),
            gyro_scale_std=np.maximum(np.abs(np.diag(m.gyro.scale_misalignment) - 1), 1e-6) * 1.5,
            accel_scale_std=np.maximum(np.abs(np.diag(m.accel.scale_misalignment) - 1), 1e-6) * 1.5,
            corr_time=tc, scale_corr_time=np.inf,
        )
        kw.update(overrides)
        return cls(**kw)


@dataclass(frozen=True)
class GinsResult(EulerMixin, Result):
    """Output of :class:`GinsFilter` (SI).

    Attributes
    ----------
    t : numpy.ndarray, shape (N,)
        IMU times, s.
    lla : numpy.ndarray, shape (N, 3)
        Estimated position of the IMU: lat rad, lon rad, ellipsoidal height m.
    vel_ned : numpy.ndarray, shape (N, 3)
        Estimated velocity, NED, m/s.
    q_nb : numpy.ndarray, shape (N, 4)
        Estimated attitude, Hamilton scalar-first quaternion, body (FRD) -> NED.
    gyro_bias, accel_bias, gyro_scale, accel_scale : numpy.ndarray, shape (N, 3)
        Estimated IMU errors: biases rad/s and m/s², scale factors dimensionless (zero for 15 states).
    odo_scale : numpy.ndarray, shape (N,)
        Estimated odometer scale factor (zero without odometer).
    cov_t : numpy.ndarray, shape (M,)
        Times of the covariance records, s (every covariance step, barometer and magnetometer sample).
    cov_diag : numpy.ndarray, shape (M, n)
        Variances of the error states (:data:`STATE_NAMES`, then the odometer scale), SI squared.
    cov_nav : numpy.ndarray, shape (M, 9, 9)
        Position (m, NED) / velocity (m/s) / attitude (rad) block of the covariance.
    gnss_t : numpy.ndarray, shape (G,)
        Times of the fixes used, s.
    nis : numpy.ndarray, shape (G, 2)
        Normalised innovation squared of the position / velocity update of each fix (NaN: not used).
    accepted : numpy.ndarray of bool, shape (G, 2)
        Whether the position / velocity update passed the χ² gate.
    vehicle_t : numpy.ndarray, shape (V,)
        Times of the odometer / NHC updates, s.
    vehicle_nis : numpy.ndarray, shape (V,)
        Their normalised innovation squared.
    vehicle_dof : numpy.ndarray of int, shape (V,)
        Their number of measurement rows (1-3).
    vehicle_accepted : numpy.ndarray of bool, shape (V,)
        Whether they passed the χ² gate.
    config : GinsConfig
        The configuration.
    meta : dict
        Removed fixes, number of states, gate threshold, covariance step, aids used.
    smoothed : SmoothedTrack or None
        The RTS solution when asked for (``GinsFilter.run(..., smoother=True)``).
    zupt_nis, baro_nis, mag_nis : numpy.ndarray, shape (N,), or None
        NIS of the ZUPT + ZARU (6 dof), barometer (1 dof) and magnetometer-heading (1 dof) updates per IMU
        sample, NaN where none was applied.
    odo_nis, nhc_nis, zupt_vel_nis, zaru_nis : numpy.ndarray, shape (N,), or None
        Each aiding model's own NIS per IMU sample (NaN where it was not applied): the odometer row (1 dof)
        and the NHC rows (2 dof) of the joint vehicle update, the ZUPT velocity rows (3 dof) and the ZARU
        rate rows (3 dof) of the joint rest update — the marginals of the joint innovation before the
        update, χ²(dof) for a consistent filter.
    """

    t: Array
    lla: Array
    vel_ned: Array
    q_nb: Array
    gyro_bias: Array
    accel_bias: Array
    gyro_scale: Array
    accel_scale: Array
    odo_scale: Array
    cov_t: Array
    cov_diag: Array
    cov_nav: Array
    gnss_t: Array
    nis: Array
    accepted: Array
    vehicle_t: Array
    vehicle_nis: Array
    vehicle_dof: Array
    vehicle_accepted: Array
    config: GinsConfig
    meta: dict[str, Any] = field(default_factory=dict)
    smoothed: SmoothedTrack | None = None
    zupt_nis: Array | None = None
    baro_nis: Array | None = None
    mag_nis: Array | None = None
    odo_nis: Array | None = None
    nhc_nis: Array | None = None
    zupt_vel_nis: Array | None = None
    zaru_nis: Array | None = None

    def gnss_summary(self) -> dict[str, Any]:
        """How the GNSS fixes were used: one definition for the CLI summary and the lab step.

        Returns
        -------
        dict
            ``gnss_fixes``: fixes the filter processed (after the first IMU sample); ``gnss_used``: those whose position
            update was evaluated (finite NIS); ``gnss_position_nis_mean``: the mean NIS of those (χ²(3) mean 3
            for a consistent filter; None when there is none); ``gnss_accepted_share``: the share of them that
            passed the χ² gate (None when there is none).
        """
        nis = self.nis[:, 0] if self.nis.size else np.zeros(0)
        used = np.isfinite(nis)
        n = int(used.sum())
        return {"gnss_fixes": int(self.gnss_t.size), "gnss_used": n,
                "gnss_position_nis_mean": float(np.mean(nis[used])) if n else None,
                "gnss_accepted_share": float(np.mean(self.accepted[used, 0])) if n else None}


@dataclass(frozen=True)
class SmoothedTrack(EulerMixin, Result):
    """RTS-smoothed navigation (Rauch, Tung & Striebel, "Maximum likelihood estimates of linear dynamic
    systems", AIAA Journal 3(8), 1965), SI.

    Attributes
    ----------
    t : numpy.ndarray, shape (N,)
        IMU times, s.
    lla : numpy.ndarray, shape (N, 3)
        Smoothed position: lat rad, lon rad, ellipsoidal height m.
    vel_ned : numpy.ndarray, shape (N, 3)
        Smoothed velocity, NED, m/s.
    q_nb : numpy.ndarray, shape (N, 4)
        Smoothed attitude, Hamilton scalar-first quaternion, body (FRD) -> NED.
    cov_t : numpy.ndarray, shape (M,)
        Times of the smoother epochs, s.
    cov_nav : numpy.ndarray, shape (M, 9, 9)
        Smoothed position (m, NED) / velocity (m/s) / attitude (rad) covariance.
    """

    t: Array
    lla: Array
    vel_ned: Array
    q_nb: Array
    cov_t: Array
    cov_nav: Array


def _rts(t: Array, lla: Array, vel: Array, q: Array, rec_t: Array, phi: Array, ppri: Array, ppost: Array,
         inj: Array, state: Array) -> SmoothedTrack:
    """Rauch–Tung–Striebel backward pass over the error state of the feedback filter (Rauch, Tung & Striebel
    1965; Groves 2013, §3.4.2), then the smoothed corrections applied to the nominal trajectory.

    With the posterior error at every epoch reset to zero by the feedback, the smoothed error ``δs_r`` (true minus
    posterior nominal at r) obeys ``δs_r = A_r (δs_{r+1} + δx_inj,{r+1})``, ``A_r = P_r⁺ Φ_{r+1}ᵀ (P_{r+1}⁻)⁻¹``,
    ``P_r^s = P_r⁺ + A_r (P_{r+1}^s − P_{r+1}⁻) A_rᵀ``; between epochs the correction is interpolated in time
    from ``δs_r`` (after r) to ``δs_{r+1} + δx_inj,{r+1}`` (before the injection at r+1).
    """
    M, n = inj.shape
    ds = np.zeros((M, n))
    Ps = np.empty((M, 9, 9))
    Pn = ppost[M - 1].copy()
    Ps[M - 1] = Pn[:9, :9]
    for r in range(M - 2, -1, -1):
        A = np.linalg.solve(ppri[r + 1].T, (ppost[r] @ phi[r + 1].T).T).T
        ds[r] = A @ (ds[r + 1] + inj[r + 1])
        Pn = ppost[r] + A @ (Pn - ppri[r + 1]) @ A.T
        Ps[r] = Pn[:9, :9]
    before = ds + inj  # relative to the prior nominal at each epoch (before its injection)
    i = np.clip(np.searchsorted(rec_t, t, side="right") - 1, 0, M - 1)
    j = np.minimum(i + 1, M - 1)
    span = rec_t[j] - rec_t[i]
    w = np.where(span > 0, (t - rec_t[i]) / np.where(span > 0, span, 1.0), 0.0)[:, None]
    corr = (1 - w) * ds[i] + w * before[j]
    out_lla = lla + ned_to_dlla(corr[:, 0:3], lla)
    out_q = quat_multiply(quat_from_rotvec(corr[:, 6:9]), q)
    return SmoothedTrack(t, out_lla, vel + corr[:, 3:6], quat_normalize(out_q), rec_t.copy(), Ps)


def _increments(imu: ImuData | ImuIncrements) -> tuple[Array, Array, Array]:
    if isinstance(imu, ImuIncrements):
        dth = np.array(imu.dtheta, dtype=float)
        dv = np.array(imu.dvel, dtype=float)
        # two-sample coning / sculling and rotation compensation on the increments (Savage 1998)
        c = np.zeros_like(dth)
        s = np.zeros_like(dv)
        c[1:] = np.cross(dth[:-1], dth[1:]) / 12.0
        s[1:] = (np.cross(dth[:-1], dv[1:]) + np.cross(dv[:-1], dth[1:])) / 12.0
        dv_out = dv + 0.5 * np.cross(dth, dv) + s
        return np.ascontiguousarray(imu.t, dtype=float), dth + c, dv_out
    if isinstance(imu, ImuData):
        dth, dv = coning_sculling_increments(imu, True)
        return np.ascontiguousarray(imu.t, dtype=float), dth, dv
    raise InvalidInputError(f"imu must be an ImuData (rates) or ImuIncrements; got {type(imu).__name__}")


def _initial_state(lla0: ArrayLike, vel0: ArrayLike, q0: ArrayLike,
                   imu_errors0: ArrayLike | None) -> tuple[Array, Array, Array, Array]:
    lla = np.array(lla0, dtype=float)
    if lla.shape != (3,) or not np.all(np.isfinite(lla)) or abs(lla[0]) >= np.pi / 2:
        raise InvalidInputError(f"lla0 must be (lat rad, lon rad, h m) with |lat| < pi/2; got {lla0!r}")
    v = np.array(vel0, dtype=float)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ShapeError(f"vel0 must be a finite 3-vector (NED m/s); got {vel0!r}")
    q = quat_normalize(np.array(q0, dtype=float))
    err = np.zeros(_k.NE)
    if imu_errors0 is not None:
        e0 = np.asarray(imu_errors0, dtype=float)
        if e0.shape != (12,):
            raise ShapeError(f"imu_errors0 must have 12 values (bg, ba, sg, sa); got shape {e0.shape}")
        err[:12] = e0
    return lla, v, q, err


def _params(c: GinsConfig, fs: float, odometer: bool) -> Array:
    """The kernel's parameter vector (layout ``K_*`` of :mod:`imunav.ins._gins_kernels`)."""
    nb = c.n_states
    prm = np.zeros(_k.NK)
    prm[_k.K_OMEGA_E] = OMEGA_E
    prm[_k.K_ARW:_k.K_ARW + 3] = c.arw
    prm[_k.K_VRW:_k.K_VRW + 3] = c.vrw
    ts = c.corr_time if c.scale_corr_time is None else float(c.scale_corr_time)
    for kq, kt, sd, tc in ((_k.K_BG_Q, _k.K_BG_T, c.gyro_bias_std, c.corr_time),
                           (_k.K_BA_Q, _k.K_BA_T, c.accel_bias_std, c.corr_time),
                           (_k.K_SG_Q, _k.K_SG_T, c.gyro_scale_std, ts), (_k.K_SA_Q, _k.K_SA_T, c.accel_scale_std, ts)):
        prm[kq:kq + 3] = 2.0 * sd**2 / tc
        prm[kt:kt + 3] = tc
    prm[_k.K_LEVER:_k.K_LEVER + 3] = c.lever_arm
    big = 1e300

    def gate(dof: int) -> float:
        return float(chi2_ppf(1 - c.gate_alpha, dof)) if c.gate_alpha > 0 else big

    prm[_k.K_GATE_POS] = gate(3)
    prm[_k.K_GATE_VEL] = gate(3)
    prm[_k.K_COV_STEP] = max(1, int(round(c.cov_interval_s * fs)))
    prm[_k.K_USE_VEL] = 1.0 if c.use_gnss_velocity else 0.0
    prm[_k.K_NB] = nb
    prm[_k.K_I_ODO] = nb if odometer else -1
    prm[_k.K_ODO_Q] = 2.0 * c.odo_scale_std**2 / c.corr_time
    prm[_k.K_ODO_T] = c.corr_time
    prm[_k.K_ODO_LEVER:_k.K_ODO_LEVER + 3] = c.odo_lever_arm
    prm[_k.K_NHC_R] = 0.0 if c.nhc_noise is None else c.nhc_noise**2
    for key, dof in ((_k.K_GATE_VEH, 3), (_k.K_GATE_VEH2, 2), (_k.K_GATE_VEH1, 1)):
        prm[key] = gate(dof)
    for key, sd in ((_k.K_ZUPT_SD, c.zupt_noise), (_k.K_BARO_SD, c.baro_noise)):
        if not (np.isfinite(sd) and sd > 0):
            raise InvalidInputError(f"GinsConfig zupt_noise / baro_noise must be > 0; got {sd!r}")
        prm[key] = sd
    if not (np.isfinite(c.zaru_noise) and c.zaru_noise >= 0):
        raise InvalidInputError(f"GinsConfig.zaru_noise must be >= 0 rad/s; got {c.zaru_noise!r}")
    prm[_k.K_ZARU_SD] = c.zaru_noise
    prm[_k.K_GATE_ZUPT] = gate(6)
    prm[_k.K_GATE_BARO] = gate(1)
    prm[_k.K_DECL] = c.declination
    prm[_k.K_MAG_SD] = c.mag_heading_noise
    prm[_k.K_GATE_MAG] = gate(1)
    return prm


def _on_imu_grid(t: Array, aid: Any, kind: type, name: str, field_name: str) -> Array:
    """An aiding series (odometer speed, barometric height) interpolated to the IMU stamps inside its span,
    NaN outside."""
    out = np.full(t.size, np.nan)
    if not isinstance(aid, kind):
        raise InvalidInputError(f"{name} must be a {kind.__name__}; got {type(aid).__name__}")
    at = np.asarray(aid.t, dtype=float)
    if at.size < 2 or np.any(np.diff(at) <= 0):
        raise InvalidInputError(f"{name} time stamps must be strictly increasing (at least 2 samples)")
    inside = (t >= at[0]) & (t <= at[-1])
    if not inside.any():
        raise InvalidInputError(f"{name} time {at[0]:.3f}..{at[-1]:.3f} s lies outside the IMU span")
    out[inside] = np.interp(t[inside], at, np.asarray(getattr(aid, field_name), dtype=float))
    return out


def _at_imu_samples(t: Array, aid: Any, kind: type, name: str, field_name: str) -> Array:
    """Aiding samples (barometer, magnetometer) placed at the nearest IMU stamp (not interpolated: interpolating
    white noise between two samples would shrink its variance below the σ the update assumes), NaN elsewhere."""
    if not isinstance(aid, kind):
        raise InvalidInputError(f"{name} must be a {kind.__name__}; got {type(aid).__name__}")
    at = np.asarray(aid.t, dtype=float)
    if at.size < 2 or np.any(np.diff(at) <= 0):
        raise InvalidInputError(f"{name} time stamps must be strictly increasing (at least 2 samples)")
    half = 0.5 * float(np.median(np.diff(t)))
    inside = (at >= t[0] - half) & (at <= t[-1] + half)
    if not inside.any():
        raise InvalidInputError(f"{name} time {at[0]:.3f}..{at[-1]:.3f} s lies outside the IMU span")
    k = np.clip(np.searchsorted(t, at[inside]), 1, t.size - 1)
    k = np.where(np.abs(t[k - 1] - at[inside]) < np.abs(t[k] - at[inside]), k - 1, k)
    if np.any(np.diff(k) == 0):
        raise InvalidInputError(f"{name}: two samples fall on one IMU sample (rate above the IMU rate); "
                                "decimate or average it first")
    val = np.asarray(getattr(aid, field_name), dtype=float)
    out = np.full((t.size,) + val.shape[1:], np.nan)
    out[k] = val[inside]
    return out


class GinsFilter:
    """The loosely coupled GNSS/INS filter: :meth:`run` over a recording, or :meth:`reset` then :meth:`step`
    sample by sample (the same numba kernel, :func:`imunav.ins._gins_kernels.gins_run`, for both).

    The loosely coupled INS/GNSS integration of Groves (*Principles of GNSS, Inertial, and Multisensor
    Integrated Navigation Systems*, 2nd ed., Artech House 2013, ch. 14): closed-loop error-state Kalman
    filter, the estimated errors fed back into the nominal state after each update.

    Parameters
    ----------
    config : GinsConfig
        Noise model, initial σ, lever arms and gates.

    Attributes
    ----------
    t : float
        Time of the current state, s (after :meth:`reset` / :meth:`step` / :meth:`run`).
    lla, vel_ned, q_nb : numpy.ndarray
        Current position (lat rad, lon rad, h m), NED velocity (m/s), attitude (body FRD -> NED).
    imu_errors : numpy.ndarray, shape (13,)
        Current gyro bias, accel bias, gyro scale, accel scale, odometer scale.
    P : numpy.ndarray, shape (n, n)
        Current error-state covariance (:data:`STATE_NAMES`, then the odometer scale).
    last_nis : dict
        NIS of the updates of the last :meth:`step`: ``gnss`` (G, 2) position / velocity, ``vehicle``,
        ``zupt``, ``baro``, ``mag``, and each model alone: ``odo``, ``nhc``, ``zupt_vel``, ``zaru`` (NaN when
        not applied).

    Raises
    ------
    InvalidInputError
        If ``config`` is not a :class:`GinsConfig`.
    """

    def __init__(self, config: GinsConfig) -> None:
        if not isinstance(config, GinsConfig):
            raise InvalidInputError(f"GinsFilter needs a GinsConfig; got {type(config).__name__}")
        self.config = config
        self._prm: Array | None = None
        self.last_nis: dict[str, Any] = {}

    def reset(self, *, lla0: ArrayLike, vel0: ArrayLike, q0: ArrayLike, t0: float, fs: float,
              imu_errors0: ArrayLike | None = None, odometer: bool = False, dtheta0: ArrayLike | None = None,
              dvel0: ArrayLike | None = None) -> None:
        """Set the state the next :meth:`step` starts from (covariance back to the configured initial σ).

        Parameters
        ----------
        lla0, vel0, q0 : array_like, shapes (3,), (3,), (4,)
            Initial position (lat rad, lon rad, h m), NED velocity (m/s) and ``q_nb`` (body FRD -> NED,
            scalar first) at ``t0``.
        t0 : float
            Time of the initial state, s.
        fs : float
            IMU rate, Hz (> 0): sets the covariance step ``cov_interval_s`` in samples.
        imu_errors0 : array_like, shape (12,), optional
            Initial gyro bias (rad/s), accel bias (m/s²), gyro scale, accel scale (default zeros).
        odometer : bool
            Add the odometer scale-factor state (to use ``odometer_speed`` in :meth:`step`).
        dtheta0, dvel0 : array_like, shape (3,), optional
            The raw increments ending at ``t0`` (for the two-sample coning / sculling of the first step;
            default zeros).

        Raises
        ------
        InvalidInputError
            If ``lla0`` is not a position in radians, ``fs`` is not > 0 or an aiding σ is not > 0.
        ShapeError
            If ``vel0`` or ``imu_errors0`` has the wrong shape.
        """
        if not (np.isfinite(fs) and fs > 0):
            raise InvalidInputError(f"GinsFilter.reset: fs must be > 0 Hz; got {fs!r}")
        self.lla, self.vel_ned, self.q_nb, self.imu_errors = _initial_state(lla0, vel0, q0, imu_errors0)
        c = self.config
        nb = c.n_states
        nx = nb + (1 if odometer else 0)
        sd0 = np.concatenate([c.init_pos_std, c.init_vel_std, c.init_att_std, c.init_gyro_bias_std,
                              c.init_accel_bias_std, c.init_gyro_scale_std, c.init_accel_scale_std])[:nb]
        self.P = np.diag(np.concatenate([sd0, [c.odo_scale_std]])[:nx] ** 2)
        self._prm = _params(c, float(fs), odometer)
        self._use_vel = bool(c.use_gnss_velocity)
        self.t = float(t0)
        self._carry = np.zeros(_k.NC)
        self._carry[_k.C_T_COV] = self.t
        self._carry[_k.C_T_RAW] = self.t
        self._prev = np.zeros((2, 3))
        for row, x, name in ((0, dtheta0, "dtheta0"), (1, dvel0, "dvel0")):
            if x is not None:
                self._prev[row] = _vec3_input(x, name)
        self._odometer = bool(odometer)
        self.last_nis = {}

    def step(self, t: float, dtheta: ArrayLike, dvel: ArrayLike, *, gnss: GnssData | None = None,
             odometer_speed: float | None = None, static: bool = False, baro_height: float | None = None,
             mag_field: ArrayLike | None = None) -> None:
        """Process one IMU increment over ``(self.t, t]`` and the aiding measurements of that interval.

        The state attributes (``lla``, ``vel_ned``, ``q_nb``, ``imu_errors``, ``P``, ``t``) are updated in
        place; :meth:`run` over the same increments gives the same result.

        Parameters
        ----------
        t : float
            End time of the increment, s (> ``self.t``).
        dtheta, dvel : array_like, shape (3,)
            Raw angle (rad) and velocity (m/s) increments over ``(self.t, t]``, body FRD (coning / sculling
            applied here, as :meth:`run` does for :class:`~imunav.io.kfgins.ImuIncrements`).
        gnss : GnssData, optional
            Fixes; those stamped inside ``(self.t, t]`` are used at their own time stamps.
        odometer_speed : float, optional
            Wheel speed at ``t``, m/s (needs ``reset(..., odometer=True)``).
        static : bool
            The vehicle stands still at ``t``: ZUPT + ZARU.
        baro_height : float, optional
            Barometric height at ``t``, m.
        mag_field : array_like, shape (3,), optional
            Calibrated magnetometer sample at ``t``, body frame (any unit): heading update.

        Raises
        ------
        InvalidInputError
            Before :meth:`reset`, if ``t`` is not after the current time, or with an odometer speed and no
            odometer state.
        ShapeError
            If an increment is not a finite 3-vector.
        NonFiniteError
            If ``odometer_speed`` or ``baro_height`` is given but not finite.
        """
        if self._prm is None:
            raise InvalidInputError("GinsFilter.step before reset(): call reset(lla0=..., t0=..., fs=...) first")
        t = float(t)
        if not t > self.t:
            raise InvalidInputError(f"GinsFilter.step: t = {t!r} s is not after the current time {self.t!r} s")
        if odometer_speed is not None and not self._odometer:
            raise InvalidInputError("GinsFilter.step: odometer_speed needs reset(..., odometer=True)")
        raw = np.vstack([self._prev, _vec3_input(dtheta, "dtheta"), _vec3_input(dvel, "dvel")])
        dth = np.array([raw[0], raw[2]])
        dv = np.array([raw[1], raw[3]])
        _, dth, dv = _increments(ImuIncrements(np.array([self.t, t]), dth, dv, np.full(2, t - self.t)))
        self._prev = raw[2:]
        if gnss is None:
            gt, glla, grp, gvel, grv = np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)), np.ones((0, 3))
            use_vel = False
        else:
            i0, i1 = np.searchsorted(gnss.t, [self.t, t], side="right")
            sl = slice(int(i0), int(i1))
            gt, glla, grp = gnss.t[sl], gnss.lla[sl], gnss.pos_std[sl] ** 2
            use_vel = self._use_vel and gnss.vel_ned is not None
            gvel = gnss.vel_ned[sl] if use_vel else np.zeros((gt.size, 3))
            grv = gnss.vel_std[sl] ** 2 if use_vel else np.ones((gt.size, 3))
        self._prm[_k.K_USE_VEL] = 1.0 if use_vel else 0.0
        for name, v in (("odometer_speed", odometer_speed), ("baro_height", baro_height)):
            if v is not None and not math.isfinite(float(v)):
                raise NonFiniteError(f"GinsFilter.step: {name} = {v!r} is not finite; pass None when there is no "
                                     "sample at this time")
        odo = np.array([np.nan, np.nan if odometer_speed is None else float(odometer_speed)])
        baro = np.array([np.nan, np.nan if baro_height is None else float(baro_height)])
        mag = np.full((2, 3), np.nan)
        if mag_field is not None:
            mag[1] = _vec3_input(mag_field, "mag_field")
        out = self._kernel(np.array([self.t, t]), dth, dv, gt, glla, grp, gvel, grv, odo,
                           np.array([0.0, 1.0 if static else 0.0]), baro, mag, 0, False, False)
        self.t = t
        self.last_nis = {"gnss": out["nis"], "vehicle": float(out["veh"][1, 0])}
        self.last_nis.update({name: float(out["aid"][1, col]) for name, col in _AID_COLUMNS.items()})

    def _kernel(self, t: Array, dth: Array, dv: Array, gt: Array, glla: Array, grp: Array, gvel: Array,
                grv: Array, odo: Array, static: Array, baro: Array, mag: Array, nrec: int, first: bool,
                final: bool) -> dict[str, Any]:
        """One call of the kernel from the current state over ``t`` (the state at t[0]), in place."""
        n, ng, nx = t.size, gt.size, self.P.shape[0]
        cs = int(self._prm[_k.K_COV_STEP])
        mmax = n // cs + 3 + int(np.count_nonzero(~np.isnan(baro)) + np.count_nonzero(~np.isnan(mag[:, 0])))
        o: dict[str, Any] = dict(
            q=np.empty((n, 4)), v=np.empty((n, 3)), lla=np.empty((n, 3)), err=np.empty((n, _k.NE)),
            cov_t=np.empty(mmax), cov_diag=np.empty((mmax, nx)), cov_nav=np.empty((mmax, 9, 9)),
            nis=np.full((ng, 2), np.nan), acc=np.zeros((ng, 2)), veh=np.full((n, 3), np.nan),
            rec_t=np.zeros(nrec), rec_phi=np.zeros((nrec, nx, nx)), rec_ppri=np.zeros((nrec, nx, nx)),
            rec_ppost=np.zeros((nrec, nx, nx)), rec_inj=np.zeros((nrec, nx)), rec_state=np.zeros((nrec, 10)),
            aid=np.full((n, _k.NA), np.nan))
        c = np.ascontiguousarray
        o["m"], o["r"] = _k.gins_run(
            t, c(dth), c(dv), c(gt), c(glla), c(grp), c(gvel), c(grv), odo, np.full(n, self.config.odo_noise**2),
            self.q_nb, self.vel_ned, self.lla, self.imu_errors, self.P, self._carry, self._prm,
            o["q"], o["v"], o["lla"], o["err"], o["cov_t"], o["cov_diag"], o["cov_nav"], o["nis"], o["acc"], o["veh"],
            o["rec_t"], o["rec_phi"], o["rec_ppri"], o["rec_ppost"], o["rec_inj"], o["rec_state"], static, baro,
            c(mag), o["aid"], first, final)
        return o

    def run(self, imu: ImuData | ImuIncrements, gnss: GnssData, *, lla0: ArrayLike, vel0: ArrayLike,
            q0: ArrayLike, imu_errors0: ArrayLike | None = None, odometer: OdometerData | None = None,
            smoother: bool = False, static: ArrayLike | None = None, baro: BaroData | None = None,
            mag: MagnetometerData | None = None) -> GinsResult:
        """Run the filter forward over the IMU recording (from a :meth:`reset` at its first sample).

        Parameters
        ----------
        imu : ImuData or ImuIncrements
            Rates (rad/s, m/s², body FRD; coning / sculling applied) or increments (Δθ rad, Δv m/s).
        gnss : GnssData
            The fixes; those outside the IMU span, or at its first sample, are removed (recorded in ``meta``),
            none inside is an error.
        lla0, vel0, q0 : array_like, shapes (3,), (3,), (4,)
            Initial position (lat rad, lon rad, h m), NED velocity (m/s) and ``q_nb`` (body FRD -> NED,
            scalar first) at ``imu.t[0]``.
        imu_errors0 : array_like, shape (12,), optional
            Initial gyro bias (rad/s), accel bias (m/s²), gyro scale, accel scale (default zeros).
        odometer : OdometerData, optional
            Wheel speeds (:class:`imunav.sim.vehicle.OdometerData`), interpolated to the IMU stamps inside
            their span; adds the odometer scale-factor state.
        smoother : bool
            Also run the RTS smoother (``result.smoothed``); keeps three n x n matrices per covariance epoch
            (about 190 MB per hour at 200 Hz with 21 states and the default 0.2 s step).
        static : array_like of bool, shape (N,), optional
            True where the vehicle stands still (e.g. from :mod:`imunav.ins.detectors`): ZUPT + ZARU.
        baro : BaroData, optional
            Barometric heights (:class:`imunav.sim.vehicle.BaroData`), each used at the nearest IMU stamp (a
            covariance epoch there).
        mag : MagnetometerData, optional
            Calibrated magnetometer (:class:`imunav.sim.gnss.MagnetometerData`): heading updates
            (``config.declination``, ``config.mag_heading_noise``), each at the nearest IMU stamp.

        Returns
        -------
        GinsResult
            The filtered trajectory, IMU errors, covariance records and the NIS of every update.

        Raises
        ------
        InvalidInputError
            If there are fewer than 2 IMU samples, ``lla0`` is not a position in radians, the odometer or
            barometer is not of its type or does not overlap the IMU span, or an aiding σ is not > 0 (also:
            no GNSS fix inside the IMU span).
        ShapeError
            If ``vel0``, ``imu_errors0`` or ``static`` has the wrong shape.
        """
        t, dth, dv = _increments(imu)
        if t.size < 2:
            raise InvalidInputError("GinsFilter.run needs at least 2 IMU samples")
        g = gnss.within(float(t[0]), float(t[-1]))
        g = g.select(g.t > t[0], "at the first IMU sample (the initial state stands for it)")
        n = t.size
        odo = np.full(n, np.nan) if odometer is None else _on_imu_grid(t, odometer, OdometerData, "odometer", "speed")
        st = np.zeros(n) if static is None else np.asarray(static, dtype=bool).astype(float)
        if st.shape != (n,):
            raise ShapeError(f"static must be (N,) = ({n},) booleans, one per IMU sample; got {st.shape}")
        hb = np.full(n, np.nan) if baro is None else _at_imu_samples(t, baro, BaroData, "baro", "height")
        mg = np.full((n, 3), np.nan) if mag is None else _at_imu_samples(t, mag, MagnetometerData, "mag", "field_b")
        self.reset(lla0=lla0, vel0=vel0, q0=q0, t0=float(t[0]), fs=1.0 / float(np.median(np.diff(t))),
                   imu_errors0=imu_errors0, odometer=odometer is not None)
        c = self.config
        use_vel = c.use_gnss_velocity and g.vel_ned is not None
        self._prm[_k.K_USE_VEL] = 1.0 if use_vel else 0.0
        ng = g.n
        nrec = (n // int(self._prm[_k.K_COV_STEP]) + ng + 3 + int(np.count_nonzero(~np.isnan(hb))) +
                int(np.count_nonzero(~np.isnan(mg[:, 0])))) if smoother else 0
        o = self._kernel(t, dth, dv, g.t, g.lla, g.pos_std**2, g.vel_ned if use_vel else np.zeros((ng, 3)),
                         g.vel_std**2 if use_vel else np.ones((ng, 3)), odo, st, hb, mg, nrec, True, True)
        self.t = float(t[-1])
        self._prev = np.vstack([imu.dtheta[-1], imu.dvel[-1]]) if isinstance(imu, ImuIncrements) else np.zeros((2, 3))
        m, r = o["m"], o["r"]
        smoothed = None
        if smoother:
            smoothed = _rts(t, o["lla"], o["v"], o["q"], o["rec_t"][:r], o["rec_phi"][:r], o["rec_ppri"][:r],
                            o["rec_ppost"][:r], o["rec_inj"][:r], o["rec_state"][:r])
        veh = o["veh"]
        used = ~np.isnan(veh[:, 0])
        err = o["err"]
        meta = {"removed_gnss": g.meta.get("removed", []), "n_states": self.P.shape[0],
                "gate_threshold": float(self._prm[_k.K_GATE_POS]), "cov_step_samples": int(self._prm[_k.K_COV_STEP]),
                "gnss_velocity": bool(use_vel), "odometer": odometer is not None, "nhc": c.nhc_noise is not None}
        return GinsResult(t, o["lla"], o["v"], o["q"], err[:, 0:3], err[:, 3:6], err[:, 6:9], err[:, 9:12],
                          err[:, _k.E_ODO], o["cov_t"][:m], o["cov_diag"][:m], o["cov_nav"][:m], g.t.copy(), o["nis"],
                          o["acc"] > 0.5, t[used], veh[used, 0], veh[used, 2].astype(int), veh[used, 1] > 0.5, c, meta,
                          smoothed, **{f"{name}_nis": o["aid"][:, col].copy() for name, col in _AID_COLUMNS.items()})


#: The per-sample aiding NIS records of the kernel: GinsResult field ``<name>_nis`` / ``last_nis`` key -> column.
_AID_COLUMNS = {"zupt": _k.A_ZUPT, "baro": _k.A_BARO, "mag": _k.A_MAG, "odo": _k.A_ODO, "nhc": _k.A_NHC,
                "zupt_vel": _k.A_ZUPT_V, "zaru": _k.A_ZARU}


def _vec3_input(x: ArrayLike, name: str) -> Array:
    a = np.asarray(x, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ShapeError(f"GinsFilter: {name} must be a finite 3-vector; got {x!r}")
    return a
