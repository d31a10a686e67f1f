"""Multiplicative extended Kalman filter (MEKF) with gyro-bias states, 6D / 9D.

Error state δx = [δθ, δb] (6): body-frame attitude error q = q̂ ⊗ exp(δθ) and
gyro-bias error b = b̂ + δb (Markley, "Attitude error representations for
Kalman filtering", JGCD 26(2), 2003; Solà 2017 §7).

Prediction over Δt with ω̄ = ω − b̂::

    q̂ ← q̂ ⊗ exp(ω̄ Δt),  Φ = [[exp(−[ω̄]× Δt), −I Δt], [0, I]],
    Q = diag((σ_g² + k_ω² |ω̄|²) Δt I, σ_b² Δt I).

The accelerometer and magnetometer noise can be given per sample
(``accel_direction_noise_std``, ``heading_noise_std``) or, independent of the sampling rate, as the
time constants of the corrections they make: with ``tilt_time_constant`` > 0 the
per-sample variance is (τ_a σ_g)² / Δt, the white measurement noise whose
steady-state Kalman gain on a random walk of density σ_g is 1/τ_a (likewise
``heading_time_constant`` for the heading).  These are the time constants of VQF (Laidig &
Seel 2023), which hold across sensors and rates.

The rate term (``k_gyro_rate``, default 0) stands for the scale-factor and
misalignment errors of an uncalibrated gyro, whose angle error grows with the
angle turned (Groves, *Principles of GNSS, Inertial, and Multisensor
Integrated Navigation Systems*, 2nd ed., §4.4.3): fast rotations then trust
the gyro less and the references more.
Accelerometer (gravity direction, unit vectors): h = q̂* ⊗ (0,0,−1) ⊗ q̂,
H = [[h]×, 0], three sequential scalar updates, P ← P − K s Kᵀ (the symmetric form of
(I − K H) P for a scalar update; not the Joseph form).  Adaptive R:
R_acc = σ_a² (1 + k_accel (| |f| − g | / 0.01 g)²) + (k_ω |ω̄|)², and the sample
is rejected when | |f| − g | / g exceeds ``accel_reject_threshold``.
Magnetometer: heading only (the horizontal field in the nav frame, yaw
ψ_m = atan2(h_E, h_N)), so field disturbances never tilt the estimate.  The
measured yaw is computed with the estimated tilt, so a tilt error φ leaks into
it through the dip δ: δψ_m = −φ_D + tan δ φ_N (nav-frame errors φ = C_nb δθ).
The update uses that H with the tilt as consider states (Schmidt-Kalman), so
the covariance carries the tilt uncertainty of the heading; tan δ comes from
the reference field.  After each correction the covariance is reset with
G = I − [½ δθ̂]× (Markley 2003).  The field is rejected when its norm or dip deviate from a
reference (learned at start, tracked slowly, re-acquired after a long
disturbance).  Rest detection adds a zero-rate pseudo-measurement
ω_meas − b = 0 for gyro-bias estimation at rest.

Two rest tests exist.  The plain one needs |ω − b̂| < ``rest_gyro_threshold`` and
| |f| − g | < ``rest_accel_threshold`` on every sample for ``rest_time``.  With
``rest_lpf_time_constant`` > 0 it uses instead the deviations from first-order low-passes
of the raw signals, |ω − ω̄|² < ``rest_gyro_threshold``\\ ² and |f − f̄|² < ``rest_accel_threshold``\\ ²,
plus |ω̄_i| < ``lpf_gyro_threshold`` (Laidig & Seel, "VQF", Information Fusion 91,
2023, §4.2): it does not depend on the accelerometer's scale factor or on the
current bias estimate, and one noisy sample does not reset it.

The field norm and dip can be low-passed (``mag_lpf_time_constant``) before the
disturbance test, and the field is used only after ``mag_min_undisturbed`` s of
continuous undisturbed field, so that the samples of a disturbance that pass
the test by chance are not used.  With ``mag_bias=False`` the heading update
treats the gyro bias as consider states (Schmidt-Kalman; zero gain on the bias):
heading errors from a distorted field then do not leak into the bias.

With the adaptive features switched off (the defaults of :class:`MEKF`) it is
the textbook MEKF; :class:`imunav.attitude.adaptive.AdaptiveMEKF` turns them on.
"""

from __future__ import annotations

from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, fields, replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from imunav.attitude import _kernels as _k
from imunav.attitude._base import check_finite_result, check_q0, gyro3, initial_q, params_dict, prepare, step_dt, vec3
from imunav.attitude.result import AttitudeResult
from imunav.errors import ConfigError
from imunav.timeseries import ImuData
from imunav.units import DEFAULT_GRAVITY

if TYPE_CHECKING:  # the noise package imports scipy.stats: a configuration does not need it
    from imunav.noise.profile import NoiseProfile

__all__ = ["MekfConfig", "MEKF"]


@dataclass(frozen=True)
class MekfConfig:
    """MEKF tuning (SI; see the module docstring for the equations).

    Attributes
    ----------
    gyro_noise_density : float
        Gyro white-noise density σ_g, rad/s/√Hz.
    gyro_bias_random_walk : float
        Gyro-bias random-walk density σ_b, rad/s/√s.
    accel_direction_noise_std : float
        Noise of the measured gravity direction (unit vector) per sample.
    k_accel : float
        Inflation of R_acc with the specific-force norm deviation, ``(1 + k_accel (| |f| − g | / 0.01 g)²)``.
    accel_reject_threshold : float
        Accelerometer sample rejected when ``| |f| − g | / g`` exceeds it.
    heading_noise_std : float
        Heading noise per sample, rad (at a horizontal field of |m|).
    mag_norm_threshold : float
        Relative field-norm deviation from the reference that marks a disturbance.
    mag_dip_threshold : float
        Dip deviation from the reference that marks a disturbance, rad.
    k_mag : float
        Inflation of the heading R with the norm and dip deviations.
    rest_gyro_threshold : float
        Rest threshold on the gyro, rad/s (0 disables rest detection).
    rest_accel_threshold : float
        Rest threshold on the accelerometer, m/s².
    rest_time : float
        Time at rest before the zero-rate pseudo-measurement, s.
    zaru_noise_std : float
        Noise of the zero-rate pseudo-measurement, rad/s.
    g : float
        Gravity magnitude, m/s², > 0.
    mag_ref_time : float
        Continuous disturbance after which the field reference is re-acquired, s (0: never).
    k_rate : float
        Adds ``(k_rate |ω̄|)²`` to the accelerometer variance, s.
    mag_ref_time_constant : float
        Time constant of the slow tracking of the field reference while undisturbed, s (0: fixed).
    use_mag : bool
        Use the magnetometer when the recording has one.
    accel_lpf_time_constant : float
        Low-pass time constant of the specific force in the gyro-integrated navigation frame, s
        (Laidig & Seel 2023, §4.1; 0: off).
    init_att_std : float
        Initial attitude standard deviation, rad.
    init_gyro_bias_std : float
        Initial gyro-bias standard deviation, rad/s.
    rest_lpf_time_constant : float
        > 0: rest test on the deviations from low-passes of this time constant, s (module docstring).
    mag_lpf_time_constant : float
        Low-pass time constant of the field norm and dip before the disturbance test, s.
    mag_min_undisturbed : float
        Continuous undisturbed field needed before the field is used again, s.
    mag_bias : bool
        False: the heading update corrects the attitude only (bias as consider states).
    lpf_gyro_threshold : float
        No rest while a low-passed gyro axis exceeds it, rad/s.
    k_gyro_rate : float
        Gyro noise density grows as ``sqrt(σ_g² + (k |ω|)²)``, √s.
    tilt_time_constant : float
        > 0: tilt-correction time constant, s, replacing ``accel_direction_noise_std`` (rate-independent).
    heading_time_constant : float
        > 0: heading-correction time constant, s, replacing ``heading_noise_std`` (rate-independent).

    Raises
    ------
    ConfigError
        If a value is negative or not finite, ``g`` is not positive, or the square of an initial σ overflows.
    """

    gyro_noise_density: float = 0.005  # rad/s/√Hz
    gyro_bias_random_walk: float = 1e-5  # rad/s/√s
    accel_direction_noise_std: float = 0.02  # unit-vector noise per sample
    k_accel: float = 0.0
    accel_reject_threshold: float = 1e9
    heading_noise_std: float = 0.05  # rad per sample (at a horizontal field of |m|)
    mag_norm_threshold: float = 1e9
    mag_dip_threshold: float = 1e9
    k_mag: float = 0.0
    rest_gyro_threshold: float = 0.0  # rad/s, 0 disables rest detection
    rest_accel_threshold: float = 0.2
    rest_time: float = 1.0
    zaru_noise_std: float = 0.002
    g: float = DEFAULT_GRAVITY
    mag_ref_time: float = 0.0
    k_rate: float = 0.0
    mag_ref_time_constant: float = 0.0
    use_mag: bool = True
    accel_lpf_time_constant: float = 0.0
    init_att_std: float = 0.1  # rad (initial attitude std)
    init_gyro_bias_std: float = 0.01  # rad/s (initial bias std)
    rest_lpf_time_constant: float = 0.0  # s; > 0: rest test on deviations from a low-pass (see module docstring)
    mag_lpf_time_constant: float = 0.0  # s; low-pass of field norm and dip before the disturbance test
    mag_min_undisturbed: float = 0.0  # s of continuous undisturbed field before the field is used again
    mag_bias: bool = True  # False: the heading update corrects the attitude only (bias as consider states)
    lpf_gyro_threshold: float = 1e9  # rad/s; no rest while a low-passed gyro axis exceeds it
    k_gyro_rate: float = 0.0  # √s; gyro noise density grows as sqrt(σ_g² + (k |ω|)²)
    tilt_time_constant: float = 0.0  # s; > 0: replaces accel_direction_noise_std (rate-independent)
    heading_time_constant: float = 0.0  # s; > 0: replaces heading_noise_std (rate-independent)

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name not in ("use_mag", "mag_bias") and not (np.isfinite(v) and v >= 0):
                raise ConfigError(f"MekfConfig.{f.name} must be finite and >= 0, got {v}")
        if self.g <= 0:
            raise ConfigError(f"MekfConfig.g must be > 0, got {self.g}")
        for name in ("init_att_std", "init_gyro_bias_std"):
            v = getattr(self, name)
            if not np.isfinite(float(v) * float(v)):  # P0 holds the squares
                raise ConfigError(f"MekfConfig.{name} = {v!r}: its square, the initial variance, overflows; give a "
                                  "standard deviation in SI (rad, rad/s), e.g. 0.1")

    @classmethod
    def from_noise_profile(cls, profile: NoiseProfile, *, base: MekfConfig | None = None, fs: float | None = None,
                           combine: str = "max") -> MekfConfig:
        """The configuration ``base`` with the sensor's own noise from a :class:`~imunav.noise.NoiseProfile`.

        The fields that stand for the sensor's noise are replaced, each in its own unit:

        * ``gyro_noise_density`` = N_g, the gyro white-noise density, rad/s/√Hz (continuous time, as here);
        * ``gyro_bias_random_walk`` = K_g, the gyro rate random walk, rad/s/√s;
        * ``zaru_noise_std`` = N_g √fs, the per-sample σ of the raw rate that the zero-rate pseudo-measurement
          reads at rest (white noise of density N sampled at fs; IEEE Std 952-1997, C.1), rad/s;
        * ``accel_direction_noise_std`` = N_a √fs / g, the accelerometer's per-sample white noise as noise of the
          gravity direction (a unit vector), when the profile has the accelerometer.

        The others keep ``base``'s values.  With ``tilt_time_constant`` > 0 (the adaptive filter's defaults) the
        accelerometer enters through that correction time constant, whose variance ``(τ_a σ_g)² / Δt`` models the
        motion's accelerations, not the sensor's noise, and ``accel_direction_noise_std`` is not used; likewise
        the heading (a magnetometer's disturbances dwarf its noise).

        Parameters
        ----------
        profile : NoiseProfile
            The sensor's profile (``imunav noise REC --profile OUT.toml``); it must hold the gyro.
        base : MekfConfig, optional
            The configuration to start from (default :class:`MekfConfig`; the adaptive filter's is
            :data:`imunav.attitude.adaptive.ADAPTIVE_DEFAULTS`).
        fs : float, optional
            Sample rate the filter will run at, Hz (default the profile's): the per-sample σ depend on it.
        combine : {"max", "mean"}
            One value for the three axes: the largest (default) or the mean.

        Returns
        -------
        MekfConfig
            The configuration.

        Raises
        ------
        ConfigError
            If the profile has no gyro.
        InvalidInputError
            If ``fs`` or ``combine`` is invalid.
        """
        cfg = cls() if base is None else base
        gyro = profile.sensor("gyro", "MekfConfig.from_noise_profile")
        kw = {"gyro_noise_density": gyro.noise_density.combined(combine),
              "gyro_bias_random_walk": gyro.bias_random_walk.combined(combine),
              "zaru_noise_std": profile.noise_std("gyro", fs, combine)}
        if profile.accel is not None:
            kw["accel_direction_noise_std"] = profile.noise_std("accel", fs, combine) / cfg.g
        return replace(cfg, **kw)

    def vector(self) -> np.ndarray:
        """Packed parameter array of the kernel: the fields named in ``_kernels.MEKF_PARAMS``, in that order.

        Returns
        -------
        numpy.ndarray, shape (27,)
            The parameters as float64 (booleans as 0 / 1).
        """
        return np.array([float(getattr(self, name)) for name in _k.MEKF_PARAMS], dtype=np.float64)

    def P0(self) -> np.ndarray:
        """Initial error covariance ``diag(init_att_std² I₃, init_gyro_bias_std² I₃)``.

        Returns
        -------
        numpy.ndarray, shape (6, 6)
            Covariance of ``[δθ (rad), δb (rad/s)]``.
        """
        return np.diag([self.init_att_std**2] * 3 + [self.init_gyro_bias_std**2] * 3)


FLAG_NAMES = {"acc_rejected": 1, "mag_disturbed": 2, "rest": 4}


@dataclass
class MEKF:
    """Multiplicative extended Kalman filter: attitude ``q_nb`` and gyro bias, error state on the tangent space.

    The state is the quaternion ``q_nb`` (Hamilton, scalar-first, body FRD -> NED) and the gyro bias; the
    filter estimates a 3-vector attitude error and a bias error and folds them back into the reference
    quaternion after each update (Markley, "Attitude error representations for Kalman filtering", J.
    Guidance, Control, and Dynamics 26(2), 2003).

    Parameters
    ----------
    config : MekfConfig
        Noise densities, gates and initial uncertainties (default :class:`MekfConfig`); see
        :meth:`with_params` to replace a few of them.
    """

    config: MekfConfig = field(default_factory=MekfConfig)

    name = "mekf"

    def __post_init__(self) -> None:
        self.q = np.array([1.0, 0.0, 0.0, 0.0])
        self.b = np.zeros(3)
        self.P = self.config.P0()
        self._st = np.zeros(_k.N_STATE)
        self._phi = np.eye(6)

    @classmethod
    def with_params(cls, **kw: float) -> "MEKF":
        """A filter with the default parameters, some replaced.

        Parameters
        ----------
        **kw
            :class:`MekfConfig` fields and their values.

        Returns
        -------
        MEKF
            The filter.

        Raises
        ------
        ConfigError
            If a name is not a parameter, or a value is invalid.
        """
        base = cls().config
        try:
            return cls(replace(base, **kw))
        except TypeError as exc:
            raise ConfigError(f"unknown MEKF parameter in {sorted(kw)}: {exc}") from exc

    def reset(self, q0: ArrayLike, bias: ArrayLike | None = None) -> None:
        """Set the state the next :meth:`step` starts from (covariance back to ``config.P0()``).

        Parameters
        ----------
        q0 : array_like, shape (4,)
            Attitude ``q_nb`` [w, x, y, z], body (FRD) to NED (normalised here).
        bias : array_like, shape (3,), optional
            Initial gyro-bias estimate, rad/s (default zero).

        Raises
        ------
        ShapeError
            If ``q0`` is not a (4,) quaternion.
        NonFiniteError
            If ``q0`` is zero or not finite.
        """
        self.q = check_q0(q0)
        self.b = vec3(bias, "bias")
        self.P = self.config.P0()
        self._st = np.zeros(_k.N_STATE)

    def step(self, gyro: ArrayLike, accel: ArrayLike, mag: ArrayLike | None, dt: float) -> np.ndarray:
        """Process one sample; returns q_nb.  ``self.P``, ``self.b`` are updated in place.

        Parameters
        ----------
        gyro : array_like, shape (3,)
            Angular rate, body axes (FRD), rad/s.
        accel : array_like, shape (3,)
            Specific force, body axes, m/s² (any unit: only its direction is used).
        mag : array_like, shape (3,), or None
            Magnetic field, body axes (any unit); None for a 6D update.
        dt : float
            Time since the previous sample, s, > 0.

        Returns
        -------
        numpy.ndarray, shape (4,)
            The new attitude ``q_nb``.

        Raises
        ------
        InvalidInputError
            If ``dt`` is not finite and positive, or the rate exceeds 1e4 rad/s (not rad/s).
        ShapeError
            If a sample is not a 3-vector.
        NonFiniteError
            If a sample is not finite.
        """
        p = self.effective_config(mag is not None and self.config.use_mag).vector()
        if mag is None:
            p[_k.P_USE_MAG] = 0.0
        self.q, self.b = _k.mekf_step(self.q, self.b, self.P, self._st, gyro3(gyro), vec3(accel, "accel"),
                                      vec3(mag, "mag"), step_dt(dt), p, self._phi)
        return self.q.copy()

    def effective_config(self, use_mag: bool) -> MekfConfig:
        """The configuration a run uses, with (``use_mag`` True) or without the magnetometer: ``config``.

        :class:`~imunav.attitude.adaptive.AdaptiveMEKF` overrides it: its shipped defaults differ without a
        magnetometer.

        Parameters
        ----------
        use_mag : bool
            Whether the run uses the magnetometer (9D).

        Returns
        -------
        MekfConfig
            The configuration.
        """
        return self.config

    def _run(self, data: ImuData, q0: ArrayLike | None, bias0: ArrayLike | None, use_mag: bool | None,
             store: bool):
        um_req = self.config.use_mag if use_mag is None else use_mag
        t, g, a, m, dt, um = prepare(data, um_req and data.mag is not None if use_mag is None else use_mag)
        prm = self.effective_config(um)
        p = prm.vector()
        p[_k.P_USE_MAG] = 1.0 if um else 0.0
        q_init = initial_q(a, m, um, q0)
        P0 = prm.P0()
        b0 = vec3(bias0, "bias0")
        out = _k.mekf_run(q_init, b0, P0, g, a, m, dt, p, store)
        return t, g, dt, um, q_init, b0, P0, out

    def run(self, data: ImuData, *, q0: ArrayLike | None = None, bias0: ArrayLike | None = None,
            use_mag: bool | None = None) -> AttitudeResult:
        """Filter a whole recording (numba kernel).

        Parameters
        ----------
        data : ImuData
            The recording (SI: rad/s, m/s²; magnetometer in any unit), body FRD.
        q0 : array_like, shape (4,), optional
            Initial attitude ``q_nb`` (default: :func:`imunav.attitude.alignment.align` of the first accelerometer
            / magnetometer sample).
        bias0 : array_like, shape (3,), optional
            Initial gyro-bias estimate, rad/s (default zero).
        use_mag : bool, optional
            Use the magnetometer (9D); default: ``config.use_mag`` and the recording has one.

        Returns
        -------
        AttitudeResult
            ``q_nb``, gyro bias (rad/s) and covariance diagonal at every sample; ``flags`` holds
            ``acc_rejected``, ``mag_disturbed``, ``rest`` (bool per sample) and ``nis``, ``nis_dof``.

        Raises
        ------
        InvalidInputError
            If ``data`` is not an ImuData with at least 2 samples, ``use_mag=True`` without a magnetometer, or a
            rate exceeds 1e4 rad/s.
        ConvergenceError
            If the filter's numbers overflow (a noise or initial σ far outside any sensor's range): the sample from
            which its attitude or covariance is not finite.
        """
        t, _, _, um, _, _, _, (q, b, pd, fl, nis, dof, *_rest) = self._run(data, q0, bias0, use_mag, False)
        params = {**params_dict(self.effective_config(um)), "use_mag": um}
        check_finite_result(self.name, t, q, pd, params)
        self.q, self.b = q[-1].copy(), b[-1].copy()
        flags = {k: (fl & v) > 0 for k, v in FLAG_NAMES.items()}
        flags["nis"] = nis
        flags["nis_dof"] = dof
        return AttitudeResult(t=t, q_nb=q, bias=b, cov_diag=pd, flags=flags, name=self.name, params=params)

    def run_many(self, recordings: Sequence[ImuData], *, workers: int = 2,
                 use_mag: bool | None = None) -> list[AttitudeResult]:
        """Filter many recordings side by side (batch mode: a fleet's logs, a Monte Carlo study).

        Each recording is filtered by a fresh filter of this configuration, exactly as :meth:`run` with the default
        initial state would; the numba kernel releases the GIL, so ``workers`` threads use as many cores.  The state
        of this filter (``q``, ``b``) is not changed.

        Parameters
        ----------
        recordings : sequence of ImuData
            The recordings (SI, body FRD).
        workers : int, optional
            Threads, >= 1 (default 2).
        use_mag : bool, optional
            As in :meth:`run`, for every recording.

        Returns
        -------
        list of AttitudeResult
            One result per recording, in order.

        Raises
        ------
        ConfigError
            If ``workers`` < 1.
        InvalidInputError
            As :meth:`run`, for the first recording that fails.
        """
        if int(workers) < 1:
            raise ConfigError(f"workers must be >= 1, got {workers}")
        recs = list(recordings)

        def one(d: ImuData) -> AttitudeResult:
            return type(self)(self.config).run(d, use_mag=use_mag)

        if int(workers) == 1 or len(recs) < 2:
            return [one(d) for d in recs]
        with ThreadPoolExecutor(max_workers=int(workers)) as ex:
            return list(ex.map(one, recs))
