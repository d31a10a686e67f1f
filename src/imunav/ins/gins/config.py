"""Configuration of the GNSS/INS filter (:class:`GinsConfig`): noise model, initial σ, lever arms, aids, gates.

Every field is SI.  A scalar given for a 3-vector applies to the three axes.  :meth:`GinsConfig.from_kfgins` reads
a KF-GINS YAML's configuration, :meth:`GinsConfig.from_preset` one matched to an IMU preset of
:mod:`imunav.sim.presets`.  The TOML and KF-GINS-YAML keys of ``imunav gins run`` are the field names
(:mod:`imunav.ins.gins.setup`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InvalidInputError, ShapeError
from imunav.io.kfgins import KfGinsConfig
from imunav.sim import presets

if TYPE_CHECKING:  # the noise package imports scipy.stats: a configuration does not need it
    from imunav.noise.profile import NoiseProfile

__all__ = ["BIAS_MODELS", "GinsConfig", "STATE_NAMES"]

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


#: The bias models of :attr:`GinsConfig.bias_model`.
BIAS_MODELS = ("gauss_markov", "constant_and_gauss_markov")
#: The state blocks that may be held as Schmidt consider states (``GinsConfig.consider_states``): the vehicle's and
#: the receiver's self-calibration, not the navigation state or the IMU errors.
CONSIDER_BLOCKS = ("odo_scale", "odo_turn", "mount", "odo_lever", "gnss_delay", "gnss_bias", "side_slip")


def misalignment_std(m: ArrayLike) -> float:
    """σ of a triad's axis misalignment: the RMS of the off-diagonal elements of its scale-misalignment matrix
    (``M = I + diag(s) + off``, rad for small angles), those that are not zero (0 when all are).

    Parameters
    ----------
    m : array_like, shape (3, 3)
        The scale-misalignment matrix.

    Returns
    -------
    float
        The σ, rad.
    """
    a = np.asarray(m, dtype=float)
    off = a[~np.eye(3, dtype=bool)]
    off = off[off != 0]
    return float(np.sqrt(np.mean(off**2))) if off.size else 0.0


@dataclass(frozen=True)
class GinsConfig:
    """Configuration of :class:`GinsFilter`, SI units.

    A scalar given for a 3-vector applies to the three axes.

    Parameters
    ----------
    gyro_noise_density : float or array_like, shape (3,)
        Gyro white-noise density (the angle random walk; ``arw`` in KF-GINS's YAML), rad/s/√Hz = rad/√s (> 0).
    accel_noise_density : float or array_like, shape (3,)
        Accelerometer white-noise density (the velocity random walk; ``vrw`` in KF-GINS's YAML), m/s²/√Hz =
        m/s/√s (> 0).
    gyro_bias_std, accel_bias_std : float or array_like, shape (3,)
        Stationary Gauss–Markov σ of the biases, rad/s and m/s² (> 0).
    gyro_scale_std, accel_scale_std : float or array_like, shape (3,)
        Stationary Gauss–Markov σ of the scale-factor errors, dimensionless (> 0).
    corr_time : float
        Correlation time of the bias and odometer-scale Gauss–Markov states, s (> 0; KF-GINS: ``corrtime``;
        ``inf``: random constants, no process noise — a state's variance then keeps its initial value, where a
        Gauss–Markov state's initial variance above its stationary σ² decays as ``exp(−2t/T)``).
    bias_model : str
        ``"gauss_markov"`` (default, KF-GINS's model): each bias error state is a first-order Gauss–Markov
        process of ``corr_time``; its initial variance decays to the stationary one within a few ``T``.
        ``"constant_and_gauss_markov"``: each bias is a random constant (the turn-on bias) plus the Gauss–Markov
        instability, as a real IMU's is, together of initial σ ``init_*_bias_std``; the filter carries the
        Gauss–Markov parts as six more states beside the whole biases, ``δḃ = δġ = −δg / T + w`` (Maybeck 1979,
        §4.11, shaping filters), so that it neither forgets the constant part (the Gauss–Markov model's
        overconfidence in the biases and the tilt) nor lets the bias wander like a random walk of the
        Gauss–Markov's noise density (``√(2σ²/T)``, unbounded: NHC NIS 0.969 and odometer 0.988 on 30 robot
        drives with that approximation, 0.99x with the two states).
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
    gate_max_rejections : int
        After this many gate rejections in a row of one aid (or joint group of aids), its next update is applied
        anyway, so that a filter that has drifted off comes back on a continuous aid (odometer, NHC, ZUPT); 0:
        never (>= 0).
    cov_interval_s : float
        Covariance propagation step, s (> 0; the nominal state is integrated every sample).
    odo_lever_arm : array_like, shape (3,)
        Wheel contact point from the IMU, body FRD, m (odometer and non-holonomic constraint).
    odo_noise_std : float
        Odometer speed σ, m/s (> 0).  The odometer and the NHC are applied at the covariance steps, not while
        ``static`` says the vehicle stands still (the ZUPT holds the velocity then; a wheel encoder reads 0).
    odo_scale_std : float
        σ of the odometer scale-factor state (Gauss–Markov with ``corr_time``), dimensionless (> 0).
    odo_turn_std : float or None
        Prior σ of the odometer's over-reading in turns ``c`` (a random constant, initial value 0), s/rad: the
        odometer reads ``(1 + k)(1 + c |ω_z|)`` times the forward speed, ``ω_z`` the vehicle's yaw rate (the wheels of
        a skid-steer vehicle slip in its turns and read more than the body moves; :mod:`imunav.ins.gins.aids.odometer`);
        None: not estimated (``c = 0``).  The default 0.3 s/rad covers a skid-steer robot's over-reading (0.3 s/rad in
        :data:`imunav.sim.hard_log.HARD_ROBOT_FAULTS`); a car's averaged wheel speeds over-read little (second order
        in the steering angle), which the fixes then show.  Without GNSS the log run holds it as a consider state:
        its prior σ reaches the position's σ in turns.
    side_slip_std : float or None
        Prior σ of the vehicle's side slip in turns ``β`` (a random constant, initial value 0), rad per m/s² of
        lateral acceleration: the NHC's lateral row holds ``v_y = −β v_x² ω_z`` instead of 0 (a linear tyre's slip
        angle is proportional to the lateral acceleration ``v_x ω_z``: Gillespie 1992, *Fundamentals of Vehicle
        Dynamics*, ch. 6; a skid-steer robot's body slides outward in its turns: Mandow et al. 2007);
        :mod:`imunav.ins.gins.aids.nhc`); None: not estimated (``β = 0``), and without the NHC it is never.  A robot
        that always turns the same way otherwise takes the slip as a mounting yaw (the hard robot's mounting erred by
        2° in yaw with a σ of 0.4°, and its GNSS latency moved by 0.1-0.3 s).
    nhc_noise_std : float or None
        σ of the non-holonomic constraint (zero lateral and vertical wheel velocity), m/s: the side slip and
        suspension velocity of the body in motion; None: off.  Not applied while ``static`` says the vehicle
        stands still: the ZUPT constrains the same velocity then (with ``zupt_noise_std``), and the one velocity
        used twice as two independent measurements would make the filter overconfident.
    nhc_interval_s : float or None
        Time between NHC updates while GNSS fixes arrive, s (> 0): the constraint is applied at the first sample of
        each interval of this length (counted from the run's start) while the vehicle moves and the last fix is at
        most two intervals old, at every covariance step in a GNSS outage or without GNSS (it is then all that
        holds the lateral velocity); None: at every covariance step throughout.  Applied at every 0.2 s step while
        fixes arrive, the NHC pulls the heading towards the side slip that ``nhc_noise_std`` stands for, and the
        fixes pull it back: on simulated robot loops (ideal IMU, σ 0.8 m fixes, slip σ 0.05 m/s, the NHC's) a
        heading bias of about +0.5° in left loops and −0.5° in right ones, none with exact fixes, gone at 1 s.
    zupt_noise_std : float
        σ of the zero-velocity update applied while ``static`` says the vehicle stands still, m/s: the body's
        vibration at rest, e.g. engine idle (> 0).
    zaru_noise_std : float
        σ of the angular-rate disturbance at rest (vibration), rad/s (>= 0).  The zero-angular-rate update reads
        the mean raw rate over the covariance step Δt; the gyros' white noise adds ``gyro_noise_density² / Δt``
        per axis to its variance by itself.
    baro_noise_std : float
        σ of the barometric height, m (its bias included: no baro-bias state; > 0).
    scale_corr_time : float or None
        Correlation time of the IMU scale-factor states, s (> 0; ``inf``: random constants, no process
        noise; None: ``corr_time``, as KF-GINS).
    accel_misalignment_std : float
        σ of each off-diagonal element of the accelerometer triad's scale-misalignment matrix, rad (>= 0; 0: none).
        Not a state: the accelerometers' axes are off the IMU's nominal ones by that much, so the attitude the
        filter finds by matching the specific force to gravity (roll, pitch: a tilt of ``m_yz`` about x and
        ``m_xz`` about y for a level IMU) and to the accelerations its aids show (heading) is off by it too
        (Groves 2013, §4.4.2), and nothing the filter measures tells it apart.  The reported covariance
        (``GinsResult.cov_nav``, ``cov_diag``, the smoothed track's) adds ``σ²`` to each attitude error, and
        with wheel aids (odometer, NHC: a velocity measured in the body's axes) the velocity that rotation turns
        (:func:`imunav.ins.gins.filter.unmodelled_misalignment`): a consumer MEMS triad's 0.2° is ten times the
        roll and pitch σ the filter reaches on its own.  A log run (:func:`imunav.ins.gins.logrun.run_log`: a
        real IMU whose axes nobody calibrated) takes it from its preset (:func:`misalignment_std`); a run on a
        calibrated IMU, or one whose accelerometer biases are free to absorb the tilt (a static alignment),
        leaves it at 0.
    declination : float
        Magnetic declination, rad (east positive), for the magnetometer heading.
    mag_heading_noise_std : float
        σ of the magnetometer heading, rad (> 0; about the field noise over its horizontal strength, plus
        the residual calibration and disturbance errors).
    odo_scale_corr_time : float or None
        Correlation time of the odometer scale-factor state, s (> 0; ``inf``: a random constant, a tyre's
        scale; None: ``corr_time``).
    mounting : array_like, shape (3,)
        The IMU's attitude in the vehicle frame, ZYX Euler (roll, pitch, yaw), rad: ``C_vb`` turns IMU axes into
        vehicle FRD axes (the odometer and the NHC act on the vehicle's axes; default: the IMU is aligned with the
        vehicle).
    mounting_std : array_like, shape (3,), or None
        Initial σ of the mounting error states (roll, pitch, yaw about the vehicle axes), rad (> 0); None: the
        mounting is not estimated.  Random constants.
    odo_lever_arm_std : array_like, shape (3,), or None
        Initial σ of the wheel lever-arm states, m (> 0); None: not estimated.  Random constants.
    level_noise_std : float or None
        σ of the vehicle's roll and pitch while it stands still (the ground's slope where it stops), rad (> 0);
        None: no levelling update at rest.  Ties the mounting's roll, which the odometer and NHC do not see.
    gnss_delay : float
        GNSS receiver latency, s: a fix stamped ``t`` is the position at ``t − gnss_delay`` (|value| < 1 s).
    gnss_delay_std : float or None
        Initial σ of the latency state, s (> 0); None: not estimated.  A random constant.
    gnss_bias_std : array_like, shape (3,), or None
        σ of the GNSS fixes' error correlated in time (multipath, atmosphere), north, east, down, m (> 0): a
        first-order Gauss–Markov state of correlation time ``gnss_bias_corr_time`` that the fixes hold besides their
        white noise (Groves 2013, §9.4.2); None: the fixes' errors are white.
    gnss_bias_corr_time : float
        Its correlation time, s (> 0).
    gnss_adaptive : bool
        Scale the fixes' reported covariance by a factor estimated from their innovations (covariance matching,
        ``kernels._adapt_noise``), bounded by ``gnss_adaptive_bounds``; the factor reached is in
        ``GinsResult.gnss_noise_scale``.
    gnss_adaptive_window : float
        Fixes the adaptive factor averages over (its forgetting weight is the inverse), >= 1.
    gnss_adaptive_bounds : tuple of float
        Lowest and highest factor on the reported covariance (0 < low <= 1 <= high).
    gnss_adaptive_prior_fixes : float
        How many fixes the reported σ counts as in the adaptive factor's mean (>= 1): the first fixes, whose
        innovations hold the initial position's error, cannot drive it to a bound alone.
    wheel_adaptive : bool
        Scale the odometer's speed variance and the NHC's, each by its own factor estimated from its innovations,
        as ``gnss_adaptive`` does the fixes' (``kernels._adapt_noise``), bounded by ``wheel_adaptive_bounds``; the
        factors reached are in ``GinsResult.odo_noise_scale`` and ``nhc_noise_scale``.  A real wheel's
        errors are not a constant white noise: a skid-steer robot's wheels spin up and lock ahead of the body
        (the Jackal bag's wheel speed changes twice as fast as the IMU says the body does) and scrub in turns.
    wheel_adaptive_window : float
        Updates each factor averages over (its forgetting weight is the inverse), >= 1.
    wheel_adaptive_bounds : tuple of float
        Lowest and highest factor on each wheel aid's covariance (0 < low <= 1 <= high).
    wheel_adaptive_prior_updates : float
        How many updates the configured σ counts as in the factor's mean (>= 1).
    consider_states : tuple of str
        State blocks held as Schmidt consider states (``"odo_scale"``, ``"odo_turn"``, ``"mount"``, ``"odo_lever"``,
        ``"gnss_delay"``, ``"gnss_bias"``): their prior σ and correlations reach the other states' covariance, but no
        update moves them (what a drive cannot observe, e.g. the odometer scale without GNSS, stays at its prior
        instead of being "estimated" from the INS's own drift).
    dual_antenna_baseline : array_like, shape (3,), or None
        Dual-antenna GNSS heading: the secondary antenna from the primary, body FRD, m (at least 1 cm); needed
        to use :class:`~imunav.ins.gins.aids.dual_antenna.DualAntennaData`.

    Raises
    ------
    ShapeError
        If a vector field is neither a finite scalar nor a finite 3-vector.
    InvalidInputError
        If a σ, a time or the gate probability is out of range.
    """

    gyro_noise_density: ArrayLike
    accel_noise_density: ArrayLike
    gyro_bias_std: ArrayLike
    accel_bias_std: ArrayLike
    gyro_scale_std: ArrayLike = 1e-3
    accel_scale_std: ArrayLike = 1e-3
    corr_time: float = 3600.0
    scale_factors: bool = True
    init_pos_std: ArrayLike = 1.0
    init_vel_std: ArrayLike = 0.1
    init_att_std: ArrayLike = (1e-3, 1e-3, 1e-2)
    init_gyro_bias_std: ArrayLike | None = None
    init_accel_bias_std: ArrayLike | None = None
    init_gyro_scale_std: ArrayLike | None = None
    init_accel_scale_std: ArrayLike | None = None
    lever_arm: ArrayLike = (0.0, 0.0, 0.0)
    use_gnss_velocity: bool = True
    gate_alpha: float = 1e-6
    gate_max_rejections: int = 0
    cov_interval_s: float = 0.2
    odo_lever_arm: ArrayLike = (0.0, 0.0, 0.0)
    odo_noise_std: float = 0.05
    odo_scale_std: float = 0.01
    odo_turn_std: float | None = 0.3
    side_slip_std: float | None = None
    nhc_noise_std: float | None = None
    nhc_interval_s: float | None = None
    zupt_noise_std: float = 0.01
    zaru_noise_std: float = 1e-4
    baro_noise_std: float = 2.0
    scale_corr_time: float | None = None
    accel_misalignment_std: float = 0.0
    declination: float = 0.0
    mag_heading_noise_std: float = 0.02
    dual_antenna_baseline: ArrayLike | None = None
    odo_scale_corr_time: float | None = None
    mounting: ArrayLike = (0.0, 0.0, 0.0)
    mounting_std: ArrayLike | None = None
    odo_lever_arm_std: ArrayLike | None = None
    level_noise_std: float | None = None
    gnss_delay: float = 0.0
    gnss_delay_std: float | None = None
    bias_model: str = "gauss_markov"
    gnss_bias_std: ArrayLike | None = None
    gnss_bias_corr_time: float = 60.0
    gnss_adaptive: bool = False
    gnss_adaptive_window: float = 100.0
    gnss_adaptive_bounds: tuple[float, float] = (0.01, 100.0)
    gnss_adaptive_prior_fixes: float = 10.0
    wheel_adaptive: bool = False
    wheel_adaptive_window: float = 25.0
    wheel_adaptive_bounds: tuple[float, float] = (1.0, 400.0)
    wheel_adaptive_prior_updates: float = 10.0
    consider_states: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        s = object.__setattr__
        cons = (self.consider_states,) if isinstance(self.consider_states, str) else tuple(self.consider_states)
        bad = [c for c in cons if c not in CONSIDER_BLOCKS]
        if bad:
            raise InvalidInputError(f"GinsConfig.consider_states: {bad} cannot be consider states; choose among "
                                    f"{list(CONSIDER_BLOCKS)}")
        s(self, "consider_states", cons)
        if self.gnss_bias_std is not None:
            s(self, "gnss_bias_std", _v3(self.gnss_bias_std, "gnss_bias_std", positive=True))
        if not (np.isfinite(self.gnss_bias_corr_time) and self.gnss_bias_corr_time > 0):
            raise InvalidInputError(f"GinsConfig.gnss_bias_corr_time must be > 0 s; got {self.gnss_bias_corr_time!r}")
        for aid, unit, prior in (("gnss", "fix", "gnss_adaptive_prior_fixes"),
                                 ("wheel", "update", "wheel_adaptive_prior_updates")):
            window = getattr(self, f"{aid}_adaptive_window")
            if not (np.isfinite(window) and window >= 1):
                raise InvalidInputError(f"GinsConfig.{aid}_adaptive_window must be >= 1 {unit}; got {window!r}")
            if not (np.isfinite(getattr(self, prior)) and getattr(self, prior) >= 1):
                raise InvalidInputError(f"GinsConfig.{prior} must be >= 1; got {getattr(self, prior)!r}")
            bounds = getattr(self, f"{aid}_adaptive_bounds")
            lo_hi = tuple(float(x) for x in np.ravel(bounds))
            if len(lo_hi) != 2 or not (0 < lo_hi[0] <= 1.0 <= lo_hi[1] < np.inf):
                raise InvalidInputError(f"GinsConfig.{aid}_adaptive_bounds must be (low, high) with 0 < low <= 1 <= "
                                        f"high; got {bounds!r}")
            s(self, f"{aid}_adaptive_bounds", lo_hi)
        if self.bias_model not in BIAS_MODELS:
            raise InvalidInputError(f"GinsConfig.bias_model must be one of {', '.join(BIAS_MODELS)}; "
                                    f"got {self.bias_model!r}")
        for name in ("gyro_noise_density", "accel_noise_density", "gyro_bias_std", "accel_bias_std", "gyro_scale_std",
                     "accel_scale_std", "init_pos_std", "init_vel_std", "init_att_std"):
            s(self, name, _v3(getattr(self, name), name, positive=True))
        for name, src in (("init_gyro_bias_std", "gyro_bias_std"), ("init_accel_bias_std", "accel_bias_std"),
                          ("init_gyro_scale_std", "gyro_scale_std"), ("init_accel_scale_std", "accel_scale_std")):
            v = getattr(self, name)
            s(self, name, getattr(self, src) if v is None else _v3(v, name, positive=True))
        s(self, "lever_arm", _v3(self.lever_arm, "lever_arm"))
        s(self, "odo_lever_arm", _v3(self.odo_lever_arm, "odo_lever_arm"))
        if self.odo_scale_corr_time is not None and not (self.odo_scale_corr_time > 0):
            raise InvalidInputError(f"GinsConfig.odo_scale_corr_time must be > 0 s (inf: constant) or None; "
                                    f"got {self.odo_scale_corr_time!r}")
        s(self, "mounting", _v3(self.mounting, "mounting"))
        if np.any(np.abs(self.mounting) > np.pi):
            raise InvalidInputError(f"GinsConfig.mounting = {self.mounting.tolist()} rad; angles lie in [-pi, pi] "
                                    "(given in degrees?)")
        for name in ("mounting_std", "odo_lever_arm_std"):
            if getattr(self, name) is not None:
                s(self, name, _v3(getattr(self, name), name, positive=True))
        if not (np.isfinite(self.gnss_delay) and abs(self.gnss_delay) < 1.0):
            raise InvalidInputError(f"GinsConfig.gnss_delay must be a latency in (-1, 1) s; got {self.gnss_delay!r}")
        if self.level_noise_std is not None and not (np.isfinite(self.level_noise_std)
                                                     and 0 < self.level_noise_std < 1.0):
            raise InvalidInputError(f"GinsConfig.level_noise_std must be in (0, 1) rad or None; "
                                    f"got {self.level_noise_std!r}")
        if self.nhc_interval_s is not None and not (np.isfinite(self.nhc_interval_s) and self.nhc_interval_s > 0):
            raise InvalidInputError(f"GinsConfig.nhc_interval_s must be > 0 s or None; got {self.nhc_interval_s!r}")
        if self.odo_turn_std is not None and not (np.isfinite(self.odo_turn_std) and self.odo_turn_std > 0):
            raise InvalidInputError(f"GinsConfig.odo_turn_std must be > 0 s/rad or None; got {self.odo_turn_std!r}")
        if self.side_slip_std is not None and not (np.isfinite(self.side_slip_std) and self.side_slip_std > 0):
            raise InvalidInputError(f"GinsConfig.side_slip_std must be > 0 rad/(m/s^2) or None; got "
                                    f"{self.side_slip_std!r}")
        if self.gnss_delay_std is not None and not (np.isfinite(self.gnss_delay_std) and self.gnss_delay_std > 0):
            raise InvalidInputError(f"GinsConfig.gnss_delay_std must be > 0 s or None; got {self.gnss_delay_std!r}")
        if self.dual_antenna_baseline is not None:
            s(self, "dual_antenna_baseline", _v3(self.dual_antenna_baseline, "dual_antenna_baseline"))
        if not np.isfinite(self.declination) or abs(self.declination) > np.pi:
            raise InvalidInputError(f"GinsConfig.declination must be in [-pi, pi] rad; got {self.declination!r}")
        for name in ("odo_noise_std", "odo_scale_std", "mag_heading_noise_std"):
            if not (np.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                raise InvalidInputError(f"GinsConfig.{name} must be > 0; got {getattr(self, name)!r}")
        if self.nhc_noise_std is not None and not (np.isfinite(self.nhc_noise_std) and self.nhc_noise_std > 0):
            raise InvalidInputError(f"GinsConfig.nhc_noise_std must be > 0 m/s or None; got {self.nhc_noise_std!r}")
        if not (self.corr_time > 0):
            raise InvalidInputError(f"GinsConfig.corr_time must be > 0 s (inf: constant); got {self.corr_time!r}")
        if isinstance(self.gate_max_rejections, bool) or not isinstance(self.gate_max_rejections, (int, np.integer)) \
                or self.gate_max_rejections < 0:
            raise InvalidInputError(f"GinsConfig.gate_max_rejections must be an integer >= 0; got "
                                    f"{self.gate_max_rejections!r}")
        if not (0 <= self.gate_alpha < 1):
            raise InvalidInputError(f"GinsConfig.gate_alpha must be in [0, 1); got {self.gate_alpha!r}")
        if not (np.isfinite(self.accel_misalignment_std) and self.accel_misalignment_std >= 0):
            raise InvalidInputError(f"GinsConfig.accel_misalignment_std must be >= 0 rad, finite; got "
                                    f"{self.accel_misalignment_std!r}")
        if self.scale_corr_time is not None and not (self.scale_corr_time > 0):
            raise InvalidInputError(f"GinsConfig.scale_corr_time must be > 0 s (inf: constant) or None; "
                                    f"got {self.scale_corr_time!r}")
        if not (self.cov_interval_s > 0):
            raise InvalidInputError(f"GinsConfig.cov_interval_s must be > 0 s; got {self.cov_interval_s!r}")

    @property
    def n_states(self) -> int:
        """Navigation and IMU-error states: 15, or 21 with the scale factors (an odometer adds one)."""
        return 21 if self.scale_factors else 15

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

        Raises
        ------
        InvalidInputError
            If a field is out of range (as :class:`GinsConfig`).
        """
        n = cfg.imu_noise_model
        kw: dict[str, Any] = dict(
            gyro_noise_density=n.gyro_noise_density, accel_noise_density=n.accel_noise_density,
            gyro_bias_std=n.gyro_bias_std, accel_bias_std=n.accel_bias_std,
            gyro_scale_std=n.gyro_scale_std, accel_scale_std=n.accel_scale_std, corr_time=n.corr_time,
            init_pos_std=cfg.init_pos_std, init_vel_std=cfg.init_vel_std, init_att_std=cfg.init_att_std,
            init_gyro_bias_std=cfg.init_gyro_bias_std, init_accel_bias_std=cfg.init_accel_bias_std,
            init_gyro_scale_std=cfg.init_gyro_scale_std, init_accel_scale_std=cfg.init_accel_scale_std,
            lever_arm=cfg.antenna_lever_arm,
        )
        kw.update(overrides)
        return cls(**kw)

    @classmethod
    def from_noise_profile(cls, profile: NoiseProfile, *, base: GinsConfig | None = None,
                           corr_time: float | None = None, **overrides: Any) -> GinsConfig:
        """The configuration with the sensor's own noise from a :class:`~imunav.noise.NoiseProfile`, per axis.

        * ``gyro_noise_density`` = N_g (rad/s/√Hz), ``accel_noise_density`` = N_a (m/s²/√Hz): continuous-time
          densities, as this filter takes them (no sample rate enters);
        * ``gyro_bias_std``, ``accel_bias_std``: the stationary σ of the first-order Gauss–Markov bias states of
          correlation time T = ``corr_time``, ``σ² = B² + K² T / 2``: the bias wanders by about its
          instability B, and for times short against T the Gauss–Markov process is a random walk of density
          ``√(2σ²/T)`` ≥ K, the sensor's bias random walk (Maybeck 1979, §4.11; El-Sheimy, Hou, Niu, IEEE
          Trans. Instrum. Meas. 57(1), 2008).

        A profile says nothing of the turn-on bias nor of the scale factors: the initial bias σ
        (``init_*_bias_std``) and the scale σ keep ``base``'s values (without ``base``, the Gauss–Markov σ and
        the defaults of :class:`GinsConfig`); give the turn-on bias from the data sheet in ``overrides``.

        Parameters
        ----------
        profile : NoiseProfile
            The sensor's profile; it must hold the gyro and the accelerometer.
        base : GinsConfig, optional
            The configuration to start from (e.g. the one of a KF-GINS YAML or of ``imunav gins run``'s TOML).
        corr_time : float, optional
            Correlation time T of the bias states, s (default ``base.corr_time``, else 3600 s).
        **overrides
            Any field of :class:`GinsConfig`, replacing the value derived from the profile.

        Returns
        -------
        GinsConfig
            The configuration.

        Raises
        ------
        ConfigError
            If the profile lacks the gyro or the accelerometer.
        InvalidInputError
            If ``corr_time`` is not > 0, or a field is out of range (as :class:`GinsConfig`).
        """
        gyro = profile.sensor("gyro", "GinsConfig.from_noise_profile")
        accel = profile.sensor("accel", "GinsConfig.from_noise_profile")
        T = float(corr_time if corr_time is not None else (base.corr_time if base is not None else 3600.0))
        if not T > 0:
            raise InvalidInputError(f"corr_time must be > 0 s (inf: random constants); got {corr_time!r}")

        def gm_std(sensor: Any) -> Array:
            k2 = sensor.bias_random_walk.value**2
            walk = np.zeros(3) if np.isinf(T) else k2 * T / 2.0
            return np.maximum(np.sqrt(sensor.bias_instability.value**2 + walk), 1e-12)

        kw: dict[str, Any] = dict(
            gyro_noise_density=gyro.noise_density.value.copy(), accel_noise_density=accel.noise_density.value.copy(),
            gyro_bias_std=gm_std(gyro), accel_bias_std=gm_std(accel), corr_time=T)
        kw.update(overrides)
        if base is None:
            return cls(**kw)
        return replace(base, **kw)

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
            gyro_noise_density=np.maximum(gw, 1e-9), accel_noise_density=np.maximum(aw, 1e-9),
            gyro_bias_std=np.maximum(np.sqrt(gq * tc / 2.0), 1e-12),
            accel_bias_std=np.maximum(np.sqrt(aq * tc / 2.0), 1e-12),
            init_gyro_bias_std=np.maximum(gb0, 1e-12), init_accel_bias_std=np.maximum(ab0, 1e-12),
            gyro_scale_std=np.maximum(np.abs(np.diag(m.gyro.scale_misalignment) - 1), 1e-6) * 1.5,
            accel_scale_std=np.maximum(np.abs(np.diag(m.accel.scale_misalignment) - 1), 1e-6) * 1.5,
            corr_time=tc, scale_corr_time=np.inf,
        )
        kw.update(overrides)
        return cls(**kw)
