"""Zero-velocity-aided pedestrian INS: error-state EKF (9 or 15 states).

Nominal state: position ``p``, velocity ``v`` (local-level NED frame fixed at
the start, no Earth rate, constant gravity ``(0, 0, g)``), attitude ``q_nb``
and, with 15 states, accelerometer / gyro biases.  Error state
``dx = [dp, dv, dphi, (dba, dbg)]`` with ``p = p̂ + dp``, ``v = v̂ + dv``,
``C_nb = exp([dphi×]) Ĉ_nb`` and ``b = b̂ + db``.  Discrete model
(Şahin 2022 §3.1, with its misprints corrected; Solà 2017 §6; Foxlin
2005)::

    Phi = [[I, dt I, 0,              0,        0       ],
           [0, I,   -dt [f^n ×],    -dt Ĉ,    0       ],
           [0, 0,    I,              0,       -dt Ĉ    ],
           [0, 0,    0,              I,        0       ],
           [0, 0,    0,              0,        I       ]]
    Q_d = diag(0, accel_noise_std² dt², gyro_noise_std² dt², sigma_ba² dt, sigma_bg² dt)

``accel_noise_std`` / ``gyro_noise_std`` are per-sample noise standard deviations (the
OpenShoe / pyshoe convention).  When the detector declares the foot
stationary the ZUPT pseudo-measurement ``z = 0 - v̂ = H dx + nu``,
``H = [0 I 0 ...]``, ``R = zupt_noise_std² I`` is applied in Joseph form, the error
is injected into the nominal state and reset.  Options, each a stance
pseudo-measurement with unit-row H:

* ZARU (15 states): ``z = ω̃ - b̂_g = δb_g + ν``, optionally only in stances
  of at least ``zaru_min_s`` (standing still, not a rolling walking stance);
* heading hold: the rotation about the nav vertical since the stance's first
  sample is 0: with ``C = exp([δφ×]) Ĉ``, ``z = -[log(Ĉ_k Ĉ_ref^T)]_z = δφ_z + ν``
  (a zero heading-change constraint, written so that a tilted mounting, whose
  ZYX yaw changes when the foot only pitches, does not break it);
* level floor: ``z = p_z0 - p̂_z = δp_z + ν`` (every stance at the start height).

The initial roll and pitch come from the mean specific force of the first
stance (or of the first ``align_samples`` samples), yaw = ``init_yaw``:
``roll = atan2(-f_y, -f_z)``, ``pitch = atan2(f_x, sqrt(f_y² + f_z²))``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav._timeseries_kernels import runs
from imunav.errors import (
    ConfigError,
    InsufficientDataError,
    InvalidInputError,
    NonFiniteError,
    ShapeError,
    TimeOrderError,
)
from imunav.ins.zupt import kernels as _k
from imunav.ins.zupt.statistics import G_PYSHOE
from imunav.results import EulerMixin, Result
from imunav.rotation import quat_from_euler

if TYPE_CHECKING:  # the noise package imports scipy.stats: a configuration does not need it
    from imunav.noise.profile import NoiseProfile

__all__ = ["ZuptConfig", "ZuptFilter", "ZuptResult", "ZuptState", "align_from_accel", "first_stance", "long_stances"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class ZuptConfig:
    """Settings of the ZUPT-aided INS (defaults: the published pyshoe set).

    Attributes
    ----------
    states : int
        9 (p, v, attitude) or 15 (+ accel and gyro biases).
    accel_noise_std : float
        Accelerometer noise per sample, m/s² (default 0.5).
    gyro_noise_std : float
        Gyro noise per sample, rad/s (default 0.5 °/s).
    zupt_noise_std : float
        ZUPT velocity-measurement noise, m/s (default 0.01).
    accel_bias_random_walk, gyro_bias_random_walk : float
        Bias random walks (15 states), m/s²/√s and rad/s/√s, >= 0.
    init_pos_std, init_vel_std, init_att_std : float
        Initial error std (m, m/s, rad).
    init_accel_bias_std, init_gyro_bias_std : float
        Initial bias std (15 states; m/s², rad/s).
    g : float or None
        Gravity, m/s²; ``None`` uses the norm of the mean specific force of
        the alignment samples.  Default :data:`~imunav.ins.zupt.statistics.G_PYSHOE` (9.8029 m/s²), pyshoe's
        value, not the package's :data:`~imunav.units.DEFAULT_GRAVITY`: the ZUPT INS keeps pyshoe's defaults so
        that its published results reproduce.
    alignment : {"samples", "first_stance"}
        ``"samples"`` (first ``align_samples`` samples) or
        ``"first_stance"`` (the first detected stance, at most
        ``align_samples_max`` samples).
    align_samples : int
        Number of samples averaged for the alignment with ``"samples"``, >= 1.
    align_samples_max : int
        Most samples of the first stance averaged with ``"first_stance"``.
    init_yaw : float
        Initial yaw, rad (ZYX).
    zaru : bool
        Zero angular-rate update during stance (needs 15 states).
    zaru_noise_std : float
        Its noise, rad/s.
    zaru_min_s : float
        Apply the ZARU only in stances lasting at least this long, s.
        A walking foot rolls during its short stances (heel to toe), so a
        ZARU there biases the gyro estimate; with e.g. 1 s only the truly
        still periods (standing before, between and after walks) calibrate it.
    heading_hold : bool
        No rotation about the vertical during each stance (the nav-frame
        rotation since the stance's first sample, not a yaw-angle difference,
        so it holds for a tilted mounting).
    heading_noise_std : float
        Noise of the heading hold, rad.
    level_floor : bool
        The walk stays on one level: each stance measures the height
        as the initial height (a flat-floor constraint; wrong on stairs or ramps).
    floor_noise_std : float
        Noise of the level-floor measurement, m.
    integration : {"euler", "coning"}
        ``"euler"`` (first order, the thesis and pyshoe: rate of sample k held
        over interval k) or ``"coning"`` (trapezoid increments of the point samples with
        the two-sample coning / sculling corrections).

    Raises
    ------
    ConfigError
        If a value is out of range or the options are inconsistent (``zaru`` with 9 states).
    """

    states: int = 9
    accel_noise_std: float = 0.5
    gyro_noise_std: float = 0.5 * math.pi / 180.0
    zupt_noise_std: float = 0.01
    accel_bias_random_walk: float = 1e-3
    gyro_bias_random_walk: float = 1e-5
    init_pos_std: float = 1e-5
    init_vel_std: float = 1e-5
    init_att_std: float = 0.1 * math.pi / 180.0
    init_accel_bias_std: float = 0.1
    init_gyro_bias_std: float = 0.01
    g: float | None = G_PYSHOE
    alignment: Literal["samples", "first_stance"] = "samples"
    align_samples: int = 20
    align_samples_max: int = 400
    init_yaw: float = 0.0
    zaru: bool = False
    zaru_noise_std: float = 0.01
    zaru_min_s: float = 0.0
    heading_hold: bool = False
    heading_noise_std: float = 0.5 * math.pi / 180.0
    level_floor: bool = False
    floor_noise_std: float = 0.01
    integration: Literal["euler", "coning"] = "euler"

    def __post_init__(self) -> None:
        if self.states not in (9, 15):
            raise ConfigError(f"states must be 9 or 15; got {self.states}")
        for name in ("accel_noise_std", "gyro_noise_std", "zupt_noise_std", "init_pos_std", "init_vel_std", "init_att_std", "zaru_noise_std",
                     "heading_noise_std", "floor_noise_std", "init_accel_bias_std", "init_gyro_bias_std"):
            val = getattr(self, name)
            if not (val > 0 and math.isfinite(val)):
                raise ConfigError(f"{name} must be finite and > 0; got {val!r}")
        for name in ("accel_bias_random_walk", "gyro_bias_random_walk"):
            if not getattr(self, name) >= 0:
                raise ConfigError(f"{name} must be >= 0; got {getattr(self, name)!r}")
        if self.g is not None and not self.g > 0:
            raise ConfigError(f"g must be > 0 or None (estimate from the alignment samples); got {self.g!r}")
        if self.alignment not in ("samples", "first_stance"):
            raise ConfigError(f"alignment must be 'samples' or 'first_stance'; got {self.alignment!r}")
        if self.integration not in ("euler", "coning"):
            raise ConfigError(f"integration must be 'euler' or 'coning'; got {self.integration!r}")
        if self.zaru and self.states != 15:
            raise ConfigError("zaru=True needs the gyro-bias states: set states=15")
        if not (self.zaru_min_s >= 0 and math.isfinite(self.zaru_min_s)):
            raise ConfigError(f"zaru_min_s must be finite and >= 0; got {self.zaru_min_s!r}")
        if self.align_samples < 1:
            raise ConfigError(f"align_samples must be >= 1; got {self.align_samples}")

    @classmethod
    def from_noise_profile(cls, profile: NoiseProfile, *, base: ZuptConfig | None = None, fs: float | None = None,
                           combine: str = "max") -> ZuptConfig:
        """The configuration ``base`` with the sensor's own noise from a :class:`~imunav.noise.NoiseProfile`.

        The ZUPT INS takes per-sample standard deviations (the OpenShoe / pyshoe convention, module docstring:
        ``Q_d = diag(0, σ_a² Δt², σ_g² Δt², K_a² Δt, K_g² Δt)``), so

        * ``accel_noise_std`` = N_a √fs (m/s²) and ``gyro_noise_std`` = N_g √fs (rad/s): white noise of density N
          sampled at fs (IEEE Std 952-1997, C.1), whose velocity / angle variance over Δt = 1/fs is then N² Δt;
        * ``accel_bias_random_walk`` = K_a (m/s²/√s), ``gyro_bias_random_walk`` = K_g (rad/s/√s).

        The published pyshoe values (0.5 m/s², 0.5 °/s per sample) are far above a foot IMU's own noise: they
        also cover the impacts and the model errors of walking.  A profile gives the sensor's part only, the floor
        under which these σ should not go.

        Parameters
        ----------
        profile : NoiseProfile
            The sensor's profile; it must hold the gyro and the accelerometer.
        base : ZuptConfig, optional
            The configuration to start from (default :class:`ZuptConfig`).
        fs : float, optional
            Sample rate the filter will run at, Hz (default the profile's).
        combine : {"max", "mean"}
            One value for the three axes: the largest (default) or the mean.

        Returns
        -------
        ZuptConfig
            The configuration.

        Raises
        ------
        ConfigError
            If the profile lacks the gyro or the accelerometer.
        InvalidInputError
            If ``fs`` or ``combine`` is invalid.
        """
        cfg = cls() if base is None else base
        gyro = profile.sensor("gyro", "ZuptConfig.from_noise_profile")
        accel = profile.sensor("accel", "ZuptConfig.from_noise_profile")
        return replace(cfg, accel_noise_std=profile.noise_std("accel", fs, combine),
                       gyro_noise_std=profile.noise_std("gyro", fs, combine),
                       accel_bias_random_walk=accel.bias_random_walk.combined(combine),
                       gyro_bias_random_walk=gyro.bias_random_walk.combined(combine))

    def to_dict(self) -> dict[str, Any]:
        """The settings as a plain dict.

        Returns
        -------
        dict
            One key per field.
        """
        return asdict(self)


@dataclass(frozen=True)
class ZuptResult(EulerMixin, Result):
    """Output of :meth:`ZuptFilter.run` (arrays one row per sample).

    Attributes
    ----------
    t : numpy.ndarray, shape (N,)
        Time, s.
    position : numpy.ndarray, shape (N, 3)
        Position in the local NED frame, m.
    velocity : numpy.ndarray, shape (N, 3)
        Velocity in NED, m/s.
    q_nb : numpy.ndarray, shape (N, 4)
        Attitude, scalar-first quaternion body (FRD) -> nav (NED).
    accel_bias : numpy.ndarray, shape (N, 3)
        Accelerometer bias estimate, m/s² (zero with 9 states).
    gyro_bias : numpy.ndarray, shape (N, 3)
        Gyro bias estimate, rad/s (zero with 9 states).
    cov_diag : numpy.ndarray, shape (N, 9 or 15)
        Diagonal of the error covariance P after each step.
    innovation : numpy.ndarray, shape (N, 3)
        ZUPT innovation ``-v̂``, m/s, at the updated samples (NaN elsewhere).
    innovation_var : numpy.ndarray, shape (N, 3)
        Diagonal of its covariance ``S``, m²/s² (NaN elsewhere).
    P : numpy.ndarray, shape (9, 9) or (15, 15)
        Final full error covariance.
    zv : numpy.ndarray of bool, shape (N,)
        Stance flags used.
    config : ZuptConfig
        Settings used.
    """

    t: Array
    position: Array
    velocity: Array
    q_nb: Array
    accel_bias: Array
    gyro_bias: Array
    cov_diag: Array
    innovation: Array
    innovation_var: Array
    P: Array
    zv: NDArray[np.bool_]
    config: ZuptConfig = field(default_factory=ZuptConfig)


    @property
    def position_std(self) -> Array:
        return np.sqrt(self.cov_diag[:, 0:3])

    def to_dict(self) -> dict[str, Any]:
        """The track as plain JSON types (biases only with 15 states).

        Returns
        -------
        dict
            Keys ``t``, ``position``, ``velocity``, ``q_nb``, ``cov_diag``, ``zv``, ``config``
            (and ``accel_bias``, ``gyro_bias``).
        """
        d = {k: getattr(self, k).tolist() for k in ("t", "position", "velocity", "q_nb", "cov_diag")}
        d["zv"] = self.zv.astype(int).tolist()
        if self.config.states == 15:
            d["accel_bias"] = self.accel_bias.tolist()
            d["gyro_bias"] = self.gyro_bias.tolist()
        d["config"] = self.config.to_dict()
        return d


def align_from_accel(accel_mean: ArrayLike, yaw: float = 0.0) -> Array:
    """Quaternion ``q_nb`` levelled from a mean specific force (body FRD).

    ``roll = atan2(−f_y, −f_z)``, ``pitch = atan2(f_x, √(f_y² + f_z²))`` (Groves 2013,
    *Principles of GNSS, Inertial, and Multisensor Integrated Navigation Systems*, 2nd ed., §5.6, leveling).

    Parameters
    ----------
    accel_mean : array_like, shape (3,)
        Mean specific force at rest, m/s², body FRD.
    yaw : float, optional
        Yaw to set, rad.

    Returns
    -------
    numpy.ndarray, shape (4,)
        ``q_nb``, scalar first, body -> NED.

    Raises
    ------
    InvalidInputError
        If ``accel_mean`` is not a finite non-zero 3-vector.
    """
    f = np.asarray(accel_mean, dtype=float)
    if f.shape != (3,) or not np.all(np.isfinite(f)) or np.linalg.norm(f) == 0:
        raise InvalidInputError(f"accel_mean must be a finite non-zero 3-vector; got {f!r}")
    roll = math.atan2(-f[1], -f[2])
    pitch = math.atan2(f[0], math.hypot(f[1], f[2]))
    return np.asarray(quat_from_euler(roll, pitch, yaw), dtype=float)


def first_stance(zv: ArrayLike) -> tuple[int, int]:
    """Half-open index range of the first run of True in ``zv``.

    Parameters
    ----------
    zv : array_like of bool, shape (N,)
        Stance flags.

    Returns
    -------
    start, stop : int
        Indices of the first stance, ``zv[start:stop]`` all True.

    Raises
    ------
    InsufficientDataError
        If ``zv`` has no True sample.
    """
    starts, stops = runs(np.ascontiguousarray(np.asarray(zv, dtype=bool)))
    if starts.size == 0:
        raise InsufficientDataError("the detector found no stationary sample; cannot align from a stance "
                                    "(raise the threshold or use alignment='samples')")
    return int(starts[0]), int(stops[0])


def long_stances(t: ArrayLike, zv: ArrayLike, min_s: float) -> NDArray[np.bool_]:
    """Mask of the samples of ``zv`` that belong to a stance lasting at least ``min_s`` seconds.

    Parameters
    ----------
    t : array_like, shape (N,)
        Time, s.
    zv : array_like of bool, shape (N,)
        Stance flags.
    min_s : float
        Shortest stance kept, s (first to last sample of the stance).

    Returns
    -------
    numpy.ndarray of bool, shape (N,)
        True on the samples of the long stances.

    Raises
    ------
    ShapeError
        If ``t`` and ``zv`` are not 1-D of the same length.
    """
    tt = np.asarray(t, dtype=float)
    z = np.asarray(zv, dtype=bool)
    if tt.ndim != 1 or z.shape != tt.shape:
        raise ShapeError(f"t and zv must be 1-D of the same length; got {tt.shape} and {z.shape}")
    out = np.zeros(z.shape, dtype=bool)
    for i0, i1 in zip(*runs(np.ascontiguousarray(z))):
        if tt[i1 - 1] - tt[i0] >= min_s:
            out[i0:i1] = True
    return out


def _arrays(data: Any) -> tuple[Array, Array, Array]:
    try:
        t = np.ascontiguousarray(data.t, dtype=np.float64)
        a = np.ascontiguousarray(data.accel, dtype=np.float64)
        w = np.ascontiguousarray(data.gyro, dtype=np.float64)
    except AttributeError as exc:
        raise InvalidInputError(f"data must be an ImuData (t, gyro, accel); got {type(data).__name__}") from exc
    if a.shape != (t.size, 3) or w.shape != (t.size, 3):
        raise ShapeError(f"accel {a.shape} and gyro {w.shape} must be ({t.size}, 3)")
    if t.size < 2:
        raise InsufficientDataError("the recording needs at least 2 samples")
    if np.any(np.diff(t) <= 0):
        bad = np.flatnonzero(np.diff(t) <= 0)
        raise TimeOrderError(f"time stamps not strictly increasing at rows {(bad + 1)[:10].tolist()}")
    return t, a, w


def _kernel_params(cfg: ZuptConfig, g: float) -> Any:
    """The kernel's parameter record for ``cfg`` and gravity ``g``."""
    return _k.ZuptKernelParams(
        nx=cfg.states, g=g, accel_noise_std=float(cfg.accel_noise_std), gyro_noise_std=float(cfg.gyro_noise_std),
        accel_bias_random_walk=float(cfg.accel_bias_random_walk), gyro_bias_random_walk=float(cfg.gyro_bias_random_walk),
        zupt_noise_std=float(cfg.zupt_noise_std), zaru_noise_std=float(cfg.zaru_noise_std), heading_hold=bool(cfg.heading_hold),
        heading_noise_std=float(cfg.heading_noise_std), coning=cfg.integration == "coning",
        level_floor=bool(cfg.level_floor), floor_noise_std=float(cfg.floor_noise_std))


def _initial_cov(cfg: ZuptConfig) -> Array:
    """``P0 = diag(init_pos_std², init_vel_std², init_att_std² (, init_accel_bias_std², init_gyro_bias_std²))``."""
    p0 = [cfg.init_pos_std] * 3 + [cfg.init_vel_std] * 3 + [cfg.init_att_std] * 3
    if cfg.states == 15:
        p0 += [cfg.init_accel_bias_std] * 3 + [cfg.init_gyro_bias_std] * 3
    return np.diag(np.square(p0))


def _position(initial_position: ArrayLike) -> Array:
    pos0 = np.asarray(initial_position, dtype=float)
    if pos0.shape != (3,):
        raise ShapeError(f"initial_position must be a 3-vector; got shape {pos0.shape}")
    if not np.all(np.isfinite(pos0)):
        raise NonFiniteError(f"initial_position must be finite; got {pos0!r}")
    return np.array(pos0, dtype=np.float64)


def _quaternion(q: ArrayLike) -> Array:
    q0 = np.asarray(q, dtype=float)
    if q0.shape != (4,) or not abs(np.linalg.norm(q0) - 1.0) <= 1e-6:
        raise InvalidInputError(f"initial_quaternion must be a unit quaternion [w, x, y, z]; got {q0!r}")
    return np.array(q0, dtype=np.float64)


def _sample3(x: ArrayLike, name: str) -> Array:
    a = np.asarray(x, dtype=np.float64)
    if a.shape != (3,):
        raise ShapeError(f"{name} must be a 3-vector (one sample, body FRD); got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{name} contains NaN or inf: {a!r}; a step needs a valid sample")
    return a


@dataclass(frozen=True)
class ZuptState(EulerMixin):
    """The ZUPT filter's estimate after one :meth:`ZuptFilter.step` (the fields of one row of :class:`ZuptResult`).

    Attributes
    ----------
    t : float
        Time, s.
    position, velocity : numpy.ndarray, shape (3,)
        Position (m) and velocity (m/s), local NED.
    q_nb : numpy.ndarray, shape (4,)
        Attitude, scalar first, body (FRD) -> NED.
    accel_bias, gyro_bias : numpy.ndarray, shape (3,)
        Bias estimates, m/s² and rad/s (zero with 9 states).
    cov_diag : numpy.ndarray, shape (9 or 15,)
        Diagonal of the error covariance.
    innovation, innovation_var : numpy.ndarray, shape (3,)
        ZUPT innovation ``-v̂`` (m/s) and the diagonal of its covariance (m²/s²); NaN when no ZUPT applied.
    """

    t: float
    position: Array
    velocity: Array
    q_nb: Array
    accel_bias: Array
    gyro_bias: Array
    cov_diag: Array
    innovation: Array
    innovation_var: Array


class ZuptFilter:
    """Zero-velocity-aided INS (error-state EKF, 9 or 15 states; equations in the module docstring).

    ``run(data, zv)`` filters a whole recording with the fused numba kernel; ``step(t, gyro, accel, zv)``
    processes one sample with the same kernel (a window of one sample, the filter state carried between
    calls), so that stepping through a recording gives the trajectory of ``run``.

    Parameters
    ----------
    config : ZuptConfig, optional
        Settings (default: 9 states, pyshoe noise values).

    Raises
    ------
    ConfigError
        If ``config`` is not a :class:`ZuptConfig`.

    Examples
    --------
    >>> from imunav.ins import ZuptConfig, ZuptFilter
    >>> res = ZuptFilter(ZuptConfig(states=15)).run(imu, zv)          # doctest: +SKIP
    >>> f = ZuptFilter(); f.reset(q_nb=res.q_nb[0])                    # doctest: +SKIP
    >>> state = f.step(imu.t[0], imu.gyro[0], imu.accel[0], zv[0])     # doctest: +SKIP
    """

    name = "zupt"

    def __init__(self, config: ZuptConfig | None = None) -> None:
        cfg = ZuptConfig() if config is None else config
        if not isinstance(cfg, ZuptConfig):
            raise ConfigError(f"config must be a ZuptConfig; got {type(cfg).__name__}")
        self.config = cfg
        self.reset()

    def reset(self, q_nb: ArrayLike | None = None, *, position: ArrayLike = (0.0, 0.0, 0.0),
              g: float | None = None) -> None:
        """Forget the state: the next :meth:`step` is the first sample of a recording.

        Parameters
        ----------
        q_nb : array_like, shape (4,), optional
            Initial attitude (scalar first); default: levelled from the first sample's specific force
            (:func:`align_from_accel`, yaw ``config.init_yaw``), as :meth:`run` with ``align_samples=1``.
        position : array_like, shape (3,), optional
            Initial position, m, NED.
        g : float, optional
            Gravity, m/s²; default ``config.g``, or the norm of the first sample's specific force when that is None.

        Raises
        ------
        InvalidInputError
            If ``q_nb`` is not a unit quaternion or ``g`` is not finite and > 0.
        ShapeError
            If ``position`` is not a 3-vector.
        """
        self._q_init = None if q_nb is None else _quaternion(q_nb)
        self._pos_init = _position(position)
        if g is not None and not (math.isfinite(g) and g > 0):
            raise InvalidInputError(f"g must be finite and > 0 m/s²; got {g!r}")
        self._g_init = g
        self._prev: dict[str, Any] | None = None

    def _carry(self, t: float, accel: Array, gyro: Array, q: Array, v: Array, p: Array, ba: Array, bg: Array,
               P: Array, dth: Array, dv: Array, q_ref: Array, stance: NDArray[np.bool_], floor: float,
               prm: Any) -> None:
        # The two-row window that each later step runs the kernel over, allocated once: row 1 holds the last
        # sample and its state; a step moves row 1 to row 0 and writes the new sample into row 1, in place
        # (building the arrays and named tuples afresh at every step cost ~10 % of a step).
        nx = P.shape[0]
        inp = _k.ZuptInput(np.array([t, t]), np.stack([accel, accel]), np.stack([gyro, gyro]),
                           np.zeros(2, dtype=np.bool_), np.zeros(2, dtype=np.bool_))
        rows = _k.ZuptRows(np.stack([q, q]), np.stack([v, v]), np.stack([p, p]), np.stack([ba, ba]),
                           np.stack([bg, bg]), np.empty((2, nx)), np.full((2, 3), np.nan), np.full((2, 3), np.nan))
        carry = _k.ZuptCarry(P, dth, dv, q_ref, stance, floor)
        self._prev = {"t": t, "inp": inp, "rows": rows, "carry": carry, "prm": prm,
                      "shift": (inp.t, inp.acc, inp.gyr, rows.q, rows.v, rows.p, rows.ba, rows.bg)}

    def step(self, t: float, gyro: ArrayLike, accel: ArrayLike, zv: bool = False, *,
             zaru: bool | None = None) -> ZuptState:
        """Process one sample: propagate with it and, if ``zv``, apply the stance updates.

        The first call after construction or :meth:`reset` only sets the initial state (as row 0 of
        :meth:`run`); each later call is one iteration of the kernel of :meth:`run`.

        Parameters
        ----------
        t : float
            Time of the sample, s, after the previous one.
        gyro : array_like, shape (3,)
            Angular rate, rad/s, body FRD.
        accel : array_like, shape (3,)
            Specific force, m/s², body FRD.
        zv : bool, optional
            The foot is stationary at this sample (ZUPT and the enabled stance aids).
        zaru : bool, optional
            Apply the ZARU at this sample; default ``config.zaru and zv``.  With ``config.zaru_min_s`` > 0
            it must be given (the stance's length is known only at its end: e.g. from :func:`long_stances`).

        Returns
        -------
        ZuptState
            The estimate after this sample.

        Raises
        ------
        TimeOrderError
            If ``t`` is not finite or not after the previous sample.
        ShapeError
            If ``gyro`` or ``accel`` is not a 3-vector.
        NonFiniteError
            If a sample holds NaN or inf.
        ConfigError
            If ``zaru`` is needed but not given, or given while ``config.zaru`` is False.
        """
        cfg = self.config
        tk = float(t)
        w = _sample3(gyro, "gyro")
        a = _sample3(accel, "accel")
        if zaru is None:
            if cfg.zaru and cfg.zaru_min_s > 0:
                raise ConfigError("with zaru_min_s > 0 a step cannot know the stance's length: pass zaru=True/False "
                                  "(e.g. from imunav.ins.long_stances over the recording)")
            zaru = bool(cfg.zaru and zv)
        elif zaru and not cfg.zaru:
            raise ConfigError("zaru=True in step() needs ZuptConfig(zaru=True, states=15)")
        prev = self._prev
        if prev is None:
            if not math.isfinite(tk):
                raise TimeOrderError(f"t must be finite; got {t!r}")
            q0 = align_from_accel(a, cfg.init_yaw) if self._q_init is None else self._q_init
            g = self._g_init if self._g_init is not None else (float(np.linalg.norm(a)) if cfg.g is None
                                                                   else float(cfg.g))
            P = _initial_cov(cfg)
            z3 = np.zeros(3)
            self._carry(tk, a, w, np.array(q0, dtype=np.float64), z3, self._pos_init.copy(), z3, z3, P, np.zeros(3),
                        np.zeros(3), np.array(q0, dtype=np.float64), np.zeros(1, dtype=np.bool_),
                        float(self._pos_init[2]), _kernel_params(cfg, g))
            nan3 = np.full(3, np.nan)
            return ZuptState(tk, self._pos_init.copy(), z3.copy(), np.array(q0, dtype=np.float64), z3.copy(),
                             z3.copy(), np.diag(P).copy(), nan3, nan3.copy())
        if not (math.isfinite(tk) and tk > prev["t"]):
            raise TimeOrderError(f"t = {t!r} s is not after the previous sample's {prev['t']!r} s; "
                                 "samples must come in strictly increasing time")
        for x in prev["shift"]:
            x[0] = x[1]
        inp, rows = prev["inp"], prev["rows"]
        inp.t[1] = tk
        inp.acc[1] = a
        inp.gyr[1] = w
        inp.zv[1] = zv
        inp.zaru[1] = zaru
        rows.innov[1] = np.nan
        rows.svar[1] = np.nan
        prev["t"] = tk
        _k.zupt_ekf_window(inp, rows, prev["carry"], prev["prm"])
        return ZuptState(tk, rows.p[1].copy(), rows.v[1].copy(), rows.q[1].copy(), rows.ba[1].copy(),
                         rows.bg[1].copy(), rows.Pd[1].copy(), rows.innov[1].copy(), rows.svar[1].copy())

    @property
    def P(self) -> Array | None:
        """Error covariance after the last sample (None before the first :meth:`step` / :meth:`run`).

        Returns
        -------
        numpy.ndarray or None
            (9, 9) or (15, 15).
        """
        return None if self._prev is None else self._prev["carry"].P.copy()

    def run(self, data: Any, zv: ArrayLike, *, initial_position: ArrayLike = (0.0, 0.0, 0.0),
            initial_quaternion: ArrayLike | None = None) -> ZuptResult:
        """Run the ZUPT-aided INS over a recording (the fused numba kernel).

        Afterwards :meth:`step` goes on from the recording's last sample.

        Parameters
        ----------
        data : ImuData
            Recording (t s, gyro rad/s, accel m/s², body FRD).
        zv : array_like of bool, shape (N,), or DetectorResult
            Stance flags (a detector's ``zv`` or stored labels).
        initial_position : array_like, shape (3,), optional
            Initial position, m, NED.
        initial_quaternion : array_like, shape (4,), optional
            ``q_nb`` (scalar first) overriding the alignment (gravity
            ``g`` is still taken from the config / alignment samples).

        Returns
        -------
        ZuptResult
            Position, velocity, attitude, biases and covariance at every sample.

        Raises
        ------
        ShapeError
            If ``zv`` or ``initial_position`` has the wrong shape.
        InvalidInputError
            If ``initial_quaternion`` is not a unit quaternion.
        """
        cfg = self.config
        t, a, w = _arrays(data)
        z = np.asarray(getattr(zv, "zv", zv))
        if z.shape != t.shape:
            raise ShapeError(f"zv must have shape ({t.size},) like the recording; got {z.shape}")
        z = np.ascontiguousarray(z.astype(bool))
        if cfg.alignment == "samples":
            i0, i1 = 0, min(cfg.align_samples, t.size)
        else:
            i0, i1 = first_stance(z)
            i1 = min(i1, i0 + cfg.align_samples_max)
        fmean = a[i0:i1].mean(axis=0)
        q0 = align_from_accel(fmean, cfg.init_yaw) if initial_quaternion is None else _quaternion(initial_quaternion)
        g = float(np.linalg.norm(fmean)) if cfg.g is None else float(cfg.g)
        pos0 = _position(initial_position)
        # fresh, writable, contiguous float64 arrays: one compiled signature for every caller
        q0 = np.array(q0, dtype=np.float64)
        t, a, w = (np.array(x, dtype=np.float64, order="C") for x in (t, a, w))
        zaru_mask = long_stances(t, z, cfg.zaru_min_s) if cfg.zaru else np.zeros(t.size, dtype=bool)
        prm = _kernel_params(cfg, g)
        rows, carry = _k.zupt_ekf_kernel(_k.ZuptInput(t, a, w, z, zaru_mask), q0, pos0, np.zeros(3), np.zeros(3),
                                         np.zeros(3), _initial_cov(cfg), prm)
        q, v, p, ba, bg, Pd, innov, svar = rows
        P, dth, dv, q_ref, stance = carry.P, carry.dth_prev, carry.dv_prev, carry.q_ref, carry.stance
        self._carry(float(t[-1]), a[-1].copy(), w[-1].copy(), q[-1].copy(), v[-1].copy(), p[-1].copy(),
                    ba[-1].copy(), bg[-1].copy(), P.copy(), dth, dv, q_ref, stance, float(pos0[2]), prm)
        return ZuptResult(t, p, v, q, ba, bg, Pd, innov, svar, P, z, cfg)
