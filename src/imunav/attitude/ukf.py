"""Unscented Kalman filter for attitude and gyro bias (error-state, USQUE-like).

Sigma points are drawn on the 6-D error state [δθ, δb] around the nominal
(q̂, b̂) with the scaled unscented transform (Julier 2002; Wan & van der Merwe
2000: λ = α²(n + κ) − n, W₀ᵐ = λ/(n+λ), W₀ᶜ = W₀ᵐ + 1 − α² + β,
Wᵢ = 1/(2(n+λ))); each point is mapped to a quaternion q̂ ⊗ exp(δθᵢ),
propagated with ω − bᵢ, and expressed again as a rotation vector relative to
the propagated centre (Crassidis & Markley, "Unscented filtering for
spacecraft attitude estimation", JGCD 26(4), 2003, with the Hamilton
body-error convention).  Measurements: the unit specific-force direction
(predicted up direction q* ⊗ (0,0,−1) ⊗ q) and, in 9D, the unit field direction
predicted from the reference ``mag_ref_ned`` (learned from the first sample
when not given).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from imunav.attitude import _kernels as _k
from imunav.attitude._base import check_finite_result, check_q0, gyro3, initial_q, params_dict, prepare, step_dt, vec3
from imunav.attitude.result import AttitudeResult
from imunav.errors import ConfigError, InvalidInputError
from imunav.rotation import quat_rotate
from imunav.timeseries import ImuData
from imunav.units import DEFAULT_GRAVITY

if TYPE_CHECKING:  # the noise package imports scipy.stats: a configuration does not need it
    from imunav.noise.profile import NoiseProfile

__all__ = ["UkfConfig", "UKF"]


#: (index into the MEKF parameter layout, UkfConfig field) of the parameters the UKF kernel reads
_KERNEL_SLOTS = ((_k.P_GYRO_NOISE_DENSITY, "gyro_noise_density"), (_k.P_GYRO_BIAS_RANDOM_WALK, "gyro_bias_random_walk"),
                 (_k.P_ACCEL_DIRECTION_NOISE_STD, "accel_direction_noise_std"),
                 (_k.P_ACCEL_REJECT_THRESHOLD, "accel_reject_threshold"),
                 (_k.P_HEADING_NOISE_STD, "mag_direction_noise_std"), (_k.P_G, "g"))


@dataclass(frozen=True)
class UkfConfig:
    """UKF tuning (SI).

    Attributes
    ----------
    gyro_noise_density : float
        Gyro white-noise density, rad/s/√Hz.
    gyro_bias_random_walk : float
        Gyro-bias random-walk density, rad/s/√s.
    accel_direction_noise_std : float
        Noise of the measured gravity direction (unit vector) per sample.
    mag_direction_noise_std : float
        Noise of the measured field direction (unit vector) per sample.
    accel_reject_threshold : float
        Accelerometer sample rejected when ``| |f| − g | / g`` exceeds it.
    g : float
        Gravity magnitude, m/s².
    alpha, beta, kappa : float
        Scaled unscented transform parameters (spread, prior-distribution and secondary scaling; E. A. Wan,
        R. van der Merwe, "The unscented Kalman filter for nonlinear estimation", IEEE AS-SPCC 2000).
    init_att_std : float
        Initial attitude standard deviation, rad.
    init_gyro_bias_std : float
        Initial gyro-bias standard deviation, rad/s.

    Raises
    ------
    ConfigError
        If a value is out of range.
    """
    gyro_noise_density: float = 0.005  # rad/s/√Hz
    gyro_bias_random_walk: float = 1e-5  # rad/s/√s
    accel_direction_noise_std: float = 0.05  # unit-vector noise per sample
    mag_direction_noise_std: float = 0.05  # unit-vector noise per sample
    accel_reject_threshold: float = 1e9  # reject when | |f| - g | / g above
    g: float = DEFAULT_GRAVITY
    alpha: float = 1e-1
    beta: float = 2.0
    kappa: float = 0.0
    init_att_std: float = 0.1
    init_gyro_bias_std: float = 0.01

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if not np.isfinite(v) or (v < 0 and f.name != "kappa"):
                raise ConfigError(f"UkfConfig.{f.name} must be finite and >= 0, got {v}")
        if self.alpha <= 0:
            raise ConfigError("UkfConfig.alpha must be > 0")

    @classmethod
    def from_noise_profile(cls, profile: NoiseProfile, *, base: UkfConfig | None = None, fs: float | None = None,
                           combine: str = "max") -> UkfConfig:
        """The configuration ``base`` with the sensor's own noise from a :class:`~imunav.noise.NoiseProfile`.

        ``gyro_noise_density`` = N_g (rad/s/√Hz), ``gyro_bias_random_walk`` = K_g (rad/s/√s) and, when the profile
        has the accelerometer, ``accel_direction_noise_std`` = N_a √fs / g, its per-sample white noise (IEEE Std
        952-1997, C.1: σ = N √fs) as noise of the gravity direction (a unit vector).  The magnetometer's direction
        noise keeps ``base``'s value (disturbances of the field dwarf the sensor's noise).

        Parameters
        ----------
        profile : NoiseProfile
            The sensor's profile; it must hold the gyro.
        base : UkfConfig, optional
            The configuration to start from (default :class:`UkfConfig`).
        fs : float, optional
            Sample rate the filter will run at, Hz (default the profile's).
        combine : {"max", "mean"}
            One value for the three axes: the largest (default) or the mean.

        Returns
        -------
        UkfConfig
            The configuration.

        Raises
        ------
        ConfigError
            If the profile has no gyro.
        InvalidInputError
            If ``fs`` or ``combine`` is invalid.
        """
        cfg = cls() if base is None else base
        gyro = profile.sensor("gyro", "UkfConfig.from_noise_profile")
        kw = {"gyro_noise_density": gyro.noise_density.combined(combine),
              "gyro_bias_random_walk": gyro.bias_random_walk.combined(combine)}
        if profile.accel is not None:
            kw["accel_direction_noise_std"] = profile.noise_std("accel", fs, combine) / cfg.g
        return replace(cfg, **kw)

    def vector(self, use_mag: bool) -> np.ndarray:
        """Packed parameter array of the kernel.

        Parameters
        ----------
        use_mag : bool
            Whether the magnetometer update is on.

        Returns
        -------
        numpy.ndarray
            The parameters as float64.
        """
        p = np.zeros(_k.N_PARAMS)
        # the MEKF layout's slots, by this config's fields: the field direction's σ takes the heading-noise slot
        for slot, name in _KERNEL_SLOTS:
            p[slot] = getattr(self, name)
        p[_k.P_USE_MAG] = 1.0 if use_mag else 0.0
        return p

    def P0(self) -> np.ndarray:
        """Initial error covariance ``diag(init_att_std² I₃, init_gyro_bias_std² I₃)``.

        Returns
        -------
        numpy.ndarray, shape (6, 6)
            Covariance of ``[δθ (rad), δb (rad/s)]``.
        """
        return np.diag([self.init_att_std**2] * 3 + [self.init_gyro_bias_std**2] * 3)


@dataclass
class UKF:
    """Error-state UKF (Crassidis & Markley 2003; module docstring).

    Attributes
    ----------
    config : UkfConfig
        The tuning.
    mag_ref_ned : numpy.ndarray, shape (3,), or None
        Reference field direction in NED (normalised; finite and non-zero); None: learned from the first sample in
        :meth:`run`, north in :meth:`step`.

    Raises
    ------
    ShapeError
        If ``mag_ref_ned`` is not a 3-vector.
    NonFiniteError
        If it is not finite.
    InvalidInputError
        If it is zero.
    """

    config: UkfConfig = field(default_factory=UkfConfig)
    mag_ref_ned: np.ndarray | None = None

    name = "ukf"

    def __post_init__(self) -> None:
        if self.mag_ref_ned is not None:
            m = vec3(self.mag_ref_ned, "UKF.mag_ref_ned")
            if not np.linalg.norm(m) > 0:
                raise InvalidInputError("UKF.mag_ref_ned must be a non-zero field direction (NED); got zero")
            self.mag_ref_ned = m
        self.q = np.array([1.0, 0.0, 0.0, 0.0])
        self.b = np.zeros(3)
        self.P = self.config.P0()

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

    def _ref(self) -> np.ndarray:
        if self.mag_ref_ned is None:
            return np.array([1.0, 0.0, 0.0])
        m = vec3(self.mag_ref_ned, "mag_ref_ned")
        return m / np.linalg.norm(m)

    def step(self, gyro: ArrayLike, accel: ArrayLike, mag: ArrayLike | None, dt: float) -> np.ndarray:
        """Process one sample (unscented prediction and updates).

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
        pr = self.config
        self.q, self.b, self.P, _, _ = _k.ukf_step(
            self.q, self.b, self.P, gyro3(gyro), vec3(accel, "accel"), vec3(mag, "mag"), step_dt(dt),
            pr.vector(mag is not None), pr.alpha, pr.beta, pr.kappa, self._ref())
        return self.q.copy()

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
            Use the magnetometer (9D); default: when the recording has one.

        Returns
        -------
        AttitudeResult
            ``q_nb``, gyro bias (rad/s) and covariance diagonal at every sample; ``flags`` holds ``nis``
            and ``nis_dof``.

        Raises
        ------
        InvalidInputError
            If ``data`` is not an ImuData with at least 2 samples, ``use_mag=True`` without a magnetometer, or a
            rate exceeds 1e4 rad/s.
        ConvergenceError
            If the filter's numbers overflow (a noise or initial σ far outside any sensor's range): the sample from
            which its attitude or covariance is not finite.
        """
        t, g, a, m, dt, um = prepare(data, use_mag)
        pr = self.config
        q_init = initial_q(a, m, um, q0)
        if self.mag_ref_ned is None and um:
            ref = quat_rotate(q_init, m[0])
            ref = ref / np.linalg.norm(ref)
        else:
            ref = self._ref()
        qs, bs, pd, Pa, nis, dof = _k.ukf_run(q_init, vec3(bias0, "bias0"), pr.P0(), g, a, m, dt, pr.vector(um),
                                              pr.alpha, pr.beta, pr.kappa, ref)
        params = {**params_dict(pr), "use_mag": um}
        check_finite_result(self.name, t, qs, pd, params)
        self.q, self.b, self.P = qs[-1].copy(), bs[-1].copy(), Pa[-1].copy()
        return AttitudeResult(t=t, q_nb=qs, bias=bs, cov_diag=pd, flags={"nis": nis, "nis_dof": dof},
                              name=self.name, params=params)
