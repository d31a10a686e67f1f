"""The three roll / pitch Kalman filters compared by Candan & Söken.

S. Candan, H. E. Söken, paper UHUK-2020-173, Ulusal Havacılık ve Uzay Konferansı (Turkish National
Aeronautics and Space Conference), 2020 ("the paper"), compares J. K. Lee, E. J. Park, S. N. Robinovitch,
"Estimation of attitude and external acceleration using inertial sensor measurement during various
dynamic conditions", IEEE Trans. Instrum. Meas. 61(8), 2012; M. A. Javed, M. Tahir, K. Ali, "Cascaded
Kalman filtering-based attitude and gyro bias estimation with efficient compensation of external
accelerations", IEEE Access 8, 2020 (cascaded, reconstructed); and its proposed adaptive KF.

State x = third row of C_nb (gravity direction in body axes, eq. 7); process
x_t = (I − Δt [y_g]×) x_{t−1} (eqs. 11-12), Q = −Δt² [x]× Σ_g [x]× (eq. 14);
measurement z = y_a − c_a a⁺_{t−1} = g x + v (eqs. 20-23); M = Σ_acc + σ_a² I
with Σ_acc = c_a² ‖a⁺‖² / 3 I (eq. 25, Lee / proposed) or the Javed per-axis
form (eqs. 29-30, reconstruction); gain K = P⁻Hᵀ(HP⁻Hᵀ + S M)⁻¹ (eq. 27).

Fixes of the paper's text (its OCR'd equations are garbled in places) made explicit:

* **Accelerometer sign**: the paper's y_a = g + a reads +g on z
  at rest; a specific-force accelerometer reads −g.  The filter is fed
  y_a := −f, so the paper's equations stay unchanged;
  ``accel_convention="paper"`` accepts data already in the paper convention.
* **Roll / pitch** (eqs. 4-5, garbled): φ = atan2(x₂, x₃),
  θ = atan2(−x₁, hypot(x₂, x₃)).
* **"propagation of F"** reads R; "(25)…(26)" reads (26)…(27); **a** is the
  external acceleration, not the "ideal accelerometer output".
* **Scale factor S** (eq. 26): diagonal Söken-Hajiyev form
  s_i = max{1, ([ν νᵀ]_ii − [H P⁻ Hᵀ]_ii)/M_ii} (mode "B", default; H. E. Söken, C. Hajiyev, "Pico
  satellite attitude estimation via robust unscented Kalman filter in the presence of measurement
  faults", ISA Transactions 49(3), 2010), or the literal ×10⁴ during detected acceleration (mode "A"),
  or none (mode "C", ablation).  S = 1 whenever no external acceleration is detected (10⁰).
* **Javed's c_a** (eq. 28): c_a when detected, 0.5 c_a otherwise; the paper does not give Javed's
  cascaded gyro-bias KF, so a standard design stands in for it (pseudo-measurement
  z_b = (x_t − x_{t−1})/Δt − [x_{t−1}]× y_g = −[x_{t−1}]× b, averaged over a
  window, updated only without detected acceleration).  Flagged "Javed-like".
* **Gyro-noise unit**: see :mod:`imunav.attitude.scenario`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.attitude import _gravity_kernels as _gk
from imunav.attitude._base import gyro3, params_dict, prepare, step_dt, vec3
from imunav.attitude.result import AttitudeResult
from imunav.errors import ConfigError, ShapeError
from imunav.rotation import quat_from_euler
from imunav.timeseries import ImuData
from imunav.units import DEFAULT_GRAVITY

if TYPE_CHECKING:  # the noise package imports scipy.stats: a configuration does not need it
    from imunav.noise.profile import NoiseProfile

__all__ = ["GravityKfConfig", "GravityKF", "LeeKF", "JavedKF", "ProposedKF", "roll_pitch_from_x",
           "process_noise"]

_KINDS = {"lee": 0, "javed": 1, "proposed": 2}
_SMODES = {"A": 0, "B": 1, "C": 2}


@dataclass(frozen=True)
class GravityKfConfig:
    """Filter-side settings (SI, per-sample standard deviations).

    Attributes
    ----------
    gyro_noise_std : float
        Gyro noise per sample, rad/s.
    accel_noise_std : float
        Accelerometer noise per sample, m/s².
    c_a : float
        Lee / Javed external-acceleration constant (eq. 20).
    g : float
        Gravity magnitude, m/s².
    accel_norm_threshold : float
        Detector threshold on ``| |y_a| − g |``, m/s².
    s_mode : {"A", "B", "C"}
        Scale factor S: literal × ``s_fixed`` (A), diagonal Söken-Hajiyev (B), none (C).
    s_fixed : float
        S of mode A during detected acceleration.
    hold_s : float
        Time the detection is held after the last detected sample, s.
    normalize : bool
        Re-normalise the state to unit length after each update.
    exact : bool
        Propagate with the exact rotation ``exp(−Δt [y_g]×)`` instead of ``I − Δt [y_g]×``.
    gyro_bias_random_walk : float
        Javed bias-KF random walk, rad/s/√s.
    bias_pseudo_noise_std : float
        Javed bias pseudo-measurement noise, rad/s.
    bias_window : int
        Samples averaged per Javed bias update, >= 1.
    init_std : float
        Initial standard deviation of each state (P0 = init_std² I; the paper gives none).

    Raises
    ------
    ConfigError
        If ``s_mode`` is unknown, a value is negative or not finite, or ``bias_window < 1``.
    """

    gyro_noise_std: float = 8.7266e-4  # rad/s per sample (0.05 °/s: reading (ii) at 100 Hz)
    accel_noise_std: float = 4.4145e-3  # m/s² per sample (45 µg/√Hz at 100 Hz)
    c_a: float = 0.1  # Lee / Javed constant
    g: float = DEFAULT_GRAVITY
    accel_norm_threshold: float = 0.02  # detector D1 threshold on | |y_a| − g | [m/s²]
    s_mode: Literal["A", "B", "C"] = "B"
    s_fixed: float = 1e4
    hold_s: float = 0.0
    normalize: bool = False
    exact: bool = False
    gyro_bias_random_walk: float = 1e-6  # Javed bias KF random walk [rad/s/√s]
    bias_pseudo_noise_std: float = 5e-3  # Javed bias pseudo-measurement noise [rad/s]
    bias_window: int = 50
    init_std: float = 1e-3  # initial std of each state (P0 = init_std² I; digest default 1e-6 I)

    def __post_init__(self) -> None:
        if self.s_mode not in _SMODES:
            raise ConfigError(f"s_mode must be one of {sorted(_SMODES)}, got {self.s_mode!r}")
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, (int, float)) and not isinstance(v, bool) and not (np.isfinite(v) and v >= 0):
                raise ConfigError(f"GravityKfConfig.{f.name} must be finite and >= 0, got {v}")
        if self.bias_window < 1:
            raise ConfigError("bias_window must be >= 1 sample")

    @classmethod
    def from_noise_profile(cls, profile: NoiseProfile, *, base: GravityKfConfig | None = None,
                           fs: float | None = None, combine: str = "max") -> GravityKfConfig:
        """The configuration ``base`` with the sensor's own noise from a :class:`~imunav.noise.NoiseProfile`.

        This filter takes per-sample standard deviations: ``gyro_noise_std`` = N_g √fs (rad/s) and
        ``accel_noise_std`` = N_a √fs (m/s²), white noise of density N sampled at fs (IEEE Std 952-1997, C.1);
        ``gyro_bias_random_walk`` = K_g (rad/s/√s) for the Javed bias filter.

        Parameters
        ----------
        profile : NoiseProfile
            The sensor's profile; it must hold the gyro and the accelerometer.
        base : GravityKfConfig, optional
            The configuration to start from (default :class:`GravityKfConfig`).
        fs : float, optional
            Sample rate the filter will run at, Hz (default the profile's).
        combine : {"max", "mean"}
            One value for the three axes: the largest (default) or the mean.

        Returns
        -------
        GravityKfConfig
            The configuration.

        Raises
        ------
        ConfigError
            If the profile lacks the gyro or the accelerometer.
        InvalidInputError
            If ``fs`` or ``combine`` is invalid.
        """
        cfg = cls() if base is None else base
        gyro = profile.sensor("gyro", "GravityKfConfig.from_noise_profile")
        profile.sensor("accel", "GravityKfConfig.from_noise_profile")
        return replace(cfg, gyro_noise_std=profile.noise_std("gyro", fs, combine),
                       accel_noise_std=profile.noise_std("accel", fs, combine),
                       gyro_bias_random_walk=gyro.bias_random_walk.combined(combine))

    def vector(self) -> np.ndarray:
        """Packed parameter array of the kernel.

        Returns
        -------
        numpy.ndarray, shape (13,)
            The settings as float64.
        """
        return np.array([float(_SMODES[self.s_mode]) if name == "s_mode" else float(getattr(self, name))
                         for name in _gk.GRAVITY_PARAMS])


def roll_pitch_from_x(x: ArrayLike) -> NDArray[np.float64]:
    """Roll and pitch from the gravity-direction state (the paper's eqs. 4-5, fixed).

    ``φ = atan2(x₂, x₃)``, ``θ = atan2(−x₁, hypot(x₂, x₃))``.

    Parameters
    ----------
    x : array_like, shape (N, 3)
        Gravity direction in body axes (third row of C_nb).

    Returns
    -------
    numpy.ndarray, shape (N, 2)
        Roll and pitch, rad.

    Raises
    ------
    ShapeError
        If ``x`` is not (N, 3).
    """
    a = np.asarray(x, float)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ShapeError(f"x must have shape (N, 3), got {a.shape}")
    return np.column_stack([np.arctan2(a[:, 1], a[:, 2]), np.arctan2(-a[:, 0], np.hypot(a[:, 1], a[:, 2]))])


def process_noise(x: ArrayLike, gyro_noise_std: float, dt: float) -> NDArray[np.float64]:
    """Q = −Δt² [x]× Σ_g [x]× with Σ_g = σ_g² I (the paper's eq. 14).

    Parameters
    ----------
    x : array_like, shape (3,)
        Gravity-direction state.
    gyro_noise_std : float
        Gyro noise per sample, rad/s.
    dt : float
        Step, s.

    Returns
    -------
    numpy.ndarray, shape (3, 3)
        Process-noise covariance of the state.
    """
    v = np.asarray(x, float).reshape(3)
    S = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return -dt * dt * gyro_noise_std**2 * S @ S


@dataclass
class GravityKF:
    """One of the paper's filters.

    Attributes
    ----------
    kind : {"lee", "javed", "proposed"}
        The filter.
    config : GravityKfConfig
        Its settings.
    accel_convention : {"specific_force", "paper"}
        ``"specific_force"`` for ordinary accelerometer data (f = a − g, reads −g on z when level), ``"paper"``
        for data already in the paper's sign convention.

    Raises
    ------
    ConfigError
        If ``kind`` or ``accel_convention`` is unknown.
    """

    kind: Literal["lee", "javed", "proposed"] = "proposed"
    config: GravityKfConfig = field(default_factory=GravityKfConfig)
    accel_convention: Literal["specific_force", "paper"] = "specific_force"

    def __post_init__(self) -> None:
        if self.kind not in _KINDS:
            raise ConfigError(f"kind must be one of {sorted(_KINDS)}, got {self.kind!r}")
        if self.accel_convention not in ("specific_force", "paper"):
            raise ConfigError("accel_convention must be 'specific_force' (f = a - g) or 'paper' (y_a = -f)")

    @property
    def name(self) -> str:
        return f"gravity_{self.kind}"

    def reset(self, x0: ArrayLike | None = None) -> None:
        """Start the per-sample API from ``x0``.

        Parameters
        ----------
        x0 : array_like, shape (3,), optional
            Initial gravity direction in body axes (default level, [0, 0, 1]).
        """
        self.x = np.array([0.0, 0.0, 1.0]) if x0 is None else np.asarray(x0, float).reshape(3).copy()
        self.P = np.eye(3) * self.config.init_std**2
        self._sv = np.zeros(_gk.N_SV)
        self._Pb = np.eye(3) * 1e-6
        self._gprev: np.ndarray | None = None
        self._S = np.ones(3)
        self._work = np.empty((_gk.N_WORK, 3, 3))

    def step(self, gyro: ArrayLike, accel: ArrayLike, dt: float) -> np.ndarray:
        """Process one sample.

        The gyro and accelerometer are those of time t; the gyro of t−1 drives the propagation (eq. 11).  The
        first call after :meth:`reset` only stores the gyro sample.

        Parameters
        ----------
        gyro : array_like, shape (3,)
            Angular rate, body axes, rad/s.
        accel : array_like, shape (3,)
            Accelerometer sample, m/s², in ``accel_convention``.
        dt : float
            Time since the previous sample, s, > 0.

        Returns
        -------
        numpy.ndarray, shape (2,)
            Roll and pitch, rad.

        Raises
        ------
        InvalidInputError
            If ``dt`` is not finite and positive, or the rate exceeds 1e4 rad/s.
        ShapeError
            If a sample is not a 3-vector.
        """
        if not hasattr(self, "x"):
            self.reset()
        g = gyro3(gyro)
        a = vec3(accel, "accel")
        dt = step_dt(dt)
        ya = -a if self.accel_convention == "specific_force" else a
        if self._gprev is not None:
            gp = self._gprev
            _gk.gravity_step(_KINDS[self.kind], self.x, self.P, self._sv, self._Pb, gp, np.ascontiguousarray(ya),
                             dt, self.config.vector(), self._S, self._work)
        self._gprev = g.copy()
        return roll_pitch_from_x(self.x[None, :])[0]

    def run(self, data: ImuData, *, x0: ArrayLike | None = None) -> AttitudeResult:
        """Filter a recording; q_nb has the estimated roll / pitch and yaw = 0.

        Parameters
        ----------
        data : ImuData
            The recording (SI), body FRD.
        x0 : array_like, shape (3,), optional
            Initial gravity direction in body axes (default level, [0, 0, 1]: the paper's filters start level).

        Returns
        -------
        AttitudeResult
            ``q_nb`` with yaw 0; ``bias`` (rad/s) for Javed's filter; ``flags`` holds the state ``x``, the detector
            output ``alpha``, the scale factor ``S`` and the external-acceleration estimate ``a_plus``.

        Raises
        ------
        InvalidInputError
            If ``data`` is not an ImuData with at least 2 samples.
        """
        t, g, a, _, dt, _ = prepare(data, False)
        ya = -a if self.accel_convention == "specific_force" else a
        x_init = np.array([0.0, 0.0, 1.0]) if x0 is None else np.asarray(x0, float).reshape(3)
        P0 = np.eye(3) * self.config.init_std**2
        xs, al, S, ap, bb = _gk.gravity_run(_KINDS[self.kind], x_init, P0, np.ascontiguousarray(g), np.ascontiguousarray(ya),
                                            np.ascontiguousarray(dt), self.config.vector())
        rp = roll_pitch_from_x(xs)
        q = quat_from_euler(rp[:, 0], rp[:, 1], np.zeros(len(rp)))
        return AttitudeResult(t=t, q_nb=q, bias=bb if self.kind == "javed" else None, name=self.name,
                              flags={"x": xs, "alpha": al.astype(bool), "S": S, "a_plus": ap},
                              params={"kind": self.kind, **params_dict(self.config)})


def LeeKF(config: GravityKfConfig | None = None, **kw) -> GravityKF:  # noqa: N802
    """Lee et al. 2012: constant c_a, equal-axis Σ_acc, S = 1.

    Parameters
    ----------
    config : GravityKfConfig, optional
        Filter settings (default :class:`GravityKfConfig` ()).
    **kw
        Further :class:`GravityKF` fields (``accel_convention``).

    Returns
    -------
    GravityKF
        The filter.
    """
    return GravityKF("lee", config or GravityKfConfig(), **kw)


def JavedKF(config: GravityKfConfig | None = None, **kw) -> GravityKF:  # noqa: N802
    """Javed et al. 2020 ("Javed-like" reconstruction of its cascaded bias KF; module docstring).

    Parameters
    ----------
    config : GravityKfConfig, optional
        Filter settings (default :class:`GravityKfConfig` ()).
    **kw
        Further :class:`GravityKF` fields (``accel_convention``).

    Returns
    -------
    GravityKF
        The filter.
    """
    return GravityKF("javed", config or GravityKfConfig(), **kw)


def ProposedKF(config: GravityKfConfig | None = None, **kw) -> GravityKF:  # noqa: N802
    """Candan & Söken 2020: detector-switched c_a ∈ {0, 1}, diagonal S (mode B).

    Parameters
    ----------
    config : GravityKfConfig, optional
        Filter settings (default :class:`GravityKfConfig` ()).
    **kw
        Further :class:`GravityKF` fields (``accel_convention``).

    Returns
    -------
    GravityKF
        The filter.
    """
    return GravityKF("proposed", config or GravityKfConfig(), **kw)
