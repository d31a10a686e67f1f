"""GNSS/INS on a robot's or a drone's own log: the sources of :func:`imunav.io.navlog.read_nav_sources` in, the
trajectory with its uncertainty out, the IMU mounting, the odometer scale and the GNSS latency estimated on the way.

:func:`run_log` does what a user would otherwise do by hand:

1. **Rest.**  The vehicle stands still where its odometer reads zero and its IMU is quiet (without an odometer:
   where the IMU is quiet with the gyro test; :func:`imunav.timeseries.static_intervals`).  ZUPT + ZARU there, and
   the levelling at rest when the mounting is estimated.
2. **Mounting.**  Given (``mounting``, e.g. from the command line or the bag's ``/tf_static``), or estimated by
   :func:`imunav.ins.gins.mounting.estimate_mounting` for a wheeled vehicle (an odometer), then refined in the
   filter as three error states; without an odometer the IMU is taken as aligned with the vehicle (a PX4 log's
   ``sensor_combined`` is in the body frame).
3. **Initial state.**  Roll and pitch from the specific force at the start; the vehicle's heading and position by
   fitting the odometry dead reckoning (gyro heading, odometer speed) to the first GNSS fixes (a 2-D similarity
   with outlier rejection), or from the magnetometer / GNSS course without an odometer; without GNSS the local
   frame of the dead reckoning (heading 0 at the start, position (0, 0)).
4. **Filter.**  :class:`~imunav.ins.gins.GinsFilter` with the IMU preset's noise model (its white-noise densities
   raised to what the log's rests show, vibration included), the odometer's scale
   factor as a state, the NHC for a wheeled vehicle with the vehicle's side slip in turns as a state
   (:data:`SIDE_SLIP_STD`), the odometer's and the NHC's σ adapted to their innovations (wheels spin, lock and
   slide), the GNSS latency as a state, the χ² gates (jumps of tens of metres are rejected and counted; an update
   forced after :data:`MAX_REJECTIONS` rejections in a row is applied at the gate's edge), and optionally the RTS
   smoother.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav.earth import lla_to_ned, ned_to_lla, normal_gravity
from imunav.errors import InsufficientDataError, InvalidInputError
from imunav.ins.gins.alignment import gyro_bias_in_motion
from imunav.ins.gins.config import GinsConfig, misalignment_std
from imunav.ins.gins.filter import GinsFilter, kernel_setup
from imunav.ins.gins.identify import GNSS_BIAS_TAU, gnss_correlated_std, withheld_score, withheld_windows
from imunav.ins.gins.layout import LAY
from imunav.ins.gins.mounting import MountingEstimate, _levelling, estimate_mounting
from imunav.ins.gins.outage import check_protocol
from imunav.ins.gins.result import GinsResult
from imunav.io.kfgins import NavTrack
from imunav.io.navlog import NavSources
from imunav.results import Result
from imunav.rotation import dcm_from_quat, euler_from_dcm, quat_from_dcm, quat_from_euler
from imunav.sim import presets
from imunav.sim.gnss import outage_schedule
from imunav.timeseries import static_intervals

__all__ = ["LogOutageReport", "LogRun", "LogRunOptions", "gnss_correlated_std", "log_outage_test", "parse_rotation",
           "parse_vector", "run_log", "truth_on_sources"]

Array = NDArray[np.float64]

#: Span of the log that the first pass of the identification covers, s.
GNSS_IDENTIFY_S = 900.0
#: σ of the odometer's scale where nothing measures it (no GNSS: a Schmidt consider state): a wheel's effective
#: radius against its nominal one, tyre wear and pressure, 2 %.
ODO_SCALE_PRIOR_STD = 0.02
#: Candidate wanders of the odometer's scale (σ over ODO_WANDER_TAU s; 0: constant), cross-validated on withheld
#: fixes (:func:`_process_models`), and when the cross-validation's first window starts, s after the log's start.
ODO_WANDER = (0.0, 0.03, 0.05, 0.1)
ODO_WANDER_TAU = 30.0
#: Candidate factors on the preset's IMU bias instability (Gauss–Markov σ of gyros and accelerometers),
#: cross-validated on withheld fixes (:func:`_process_models`); 1: the preset's.
BIAS_INSTABILITY_FACTORS = (1.0, 2.0, 4.0)
WANDER_CV_START_S = 60.0
#: Span of the log the cross-validation runs cover, s (six withheld windows; its runs cost a fraction of a pass).
WANDER_CV_SPAN_S = 600.0
#: Default σ of the GNSS latency state (s), the odometer scale (dimensionless) and the vehicle's slope at rest (rad).
GNSS_DELAY_STD = 0.2
ODO_SCALE_STD = 0.1
LEVEL_STD = math.radians(1.0)
#: Prior σ of the vehicle's side slip per m/s² of lateral acceleration, rad/(m/s²) (``GinsConfig.side_slip_std``),
#: of a slow vehicle (a skid-steer robot's body slides outward in its turns: the hard robot's 0.2) and of a road
#: vehicle (a linear tyre's ``m / 2C_α``, a few thousandths: Gillespie 1992, ch. 6), told apart by the 95th
#: percentile of the wheel speed against SIDE_SLIP_FAST_MPS.  The robot's prior on a car, where ``w_x² ω_z`` is
#: large, let β take the heading's error: hard car attitude NEES 5.4 -> 11.5.
SIDE_SLIP_STD = (0.2, 0.01)
SIDE_SLIP_FAST_MPS = 5.0
#: How far (in prior σ) a self-calibration state may move from its initial value before the run says so
#: (:meth:`LogRun.moved_beyond_prior`), and an estimated mounting is held at its coarse value instead when it also
#: moved more than :data:`MOUNT_HOLD_DEG`.
MOVED_SIGMAS = 4.0
#: ... and by more than this (deg): the levelling and the accelerations find a mounting within a degree or two, so a
#: filter that moves it further fights a model error (the real robot's pitch went from −1.9° to −26.5°, σ 1.4°).
MOUNT_HOLD_DEG = 5.0
#: Gate rejections in a row after which an aid's update is applied anyway (a log's filter must not drift away).
MAX_REJECTIONS = 5
#: A bag's mounting (tf_static, frame_id) is contradicted when the levelling at rest differs from its roll or pitch
#: by more than 3σ plus this, rad.
MOUNT_CHECK_MARGIN = math.radians(2.0)
#: Largest odometer speed (m/s) and wheel yaw rate (rad/s, 0.1 deg/s) of a vehicle at rest.
REST_SPEED = 0.02
REST_YAW_RATE = math.radians(0.1)
#: Window of the odometer's mean speed and yaw rate that the rest test reads, s (centred on each sample), and the
#: largest σ of an odometer sample it takes from the log (m/s).
REST_WINDOW_S = 1.0
REST_NOISE_MAX = 0.1
#: Time between NHC updates while GNSS fixes arrive, s (GinsConfig.nhc_interval_s).  Applied at every 0.2 s
#: covariance step, the NHC pulls the heading towards the side slip while the fixes correct it: on simulated robot
#: loops with slip σ 0.05 m/s (white on a 0.4 s grid) and σ 0.8 m fixes the heading is biased by +0.5° in left loops
#: and −0.5° in right ones (ideal IMU, the slip's σ matched), and gone at 1 s.  In an outage or without GNSS the NHC
#: is all that holds the lateral velocity, and the filter applies it at every step (on the real Jackal bag, 1 s
#: brings the dead reckoning's end from 2.3 m to 8.3 m off robot_localization's).
NHC_INTERVAL = 1.0
#: The configuration fields of the gyro's errors (the initial heading's σ takes them from the preset and overrides).
_GYRO_FIELDS = ("gyro_bias_std", "gyro_scale_std", "init_gyro_scale_std")
#: σ of a mounting that a bag claims (an IMU frame_id equal to the base frame, a /tf_static), rad per axis, carried as
#: consider states when no GNSS can check it.
CLAIMED_MOUNT_STD = math.radians(1.0)
#: Smallest σ of an odometer sample, m/s (a driver's twist covariance is a guess; wheels slip and lag).
ODO_STD_FLOOR = 0.05


@dataclass(frozen=True)
class LogRunOptions:
    """Choices of :func:`run_log` (SI).

    Parameters
    ----------
    preset : str
        IMU error preset of :mod:`imunav.sim.presets` whose noise model the filter uses.
    mounting : array_like, shape (4,), or None
        The IMU's mounting ``q_vb`` (IMU FRD -> vehicle FRD); None: the bag's ``/tf_static`` when it has one,
        else estimated (wheeled vehicle) or the identity.
    gnss_lever_arm : array_like, shape (3,)
        GNSS antenna from the IMU, vehicle FRD axes, m.
    odo_lever_arm : array_like, shape (3,) or None
        Wheel contact point (the odometer's reference) from the IMU, vehicle FRD axes, m; None: the bag's
        ``/tf_static`` IMU position when it has one, else zero.
    estimate_odo_lever_arm : bool
        Estimate the wheel lever arm as states (σ 0.3 m).
    nhc : bool or None
        Non-holonomic constraint; None: on with an odometer (a wheeled ground vehicle).
    nhc_std : float
        σ of the NHC, m/s.
    smoother : bool
        Also run the RTS smoother (the default: an offline run's best trajectory is the smoothed one; False: the
        forward filter alone, as in real time).
    gnss_pos_std : float or None
        σ of a fix whose covariance the log does not give, m.
    overrides : dict
        Any other :class:`~imunav.ins.gins.GinsConfig` field.
    """

    preset: str = "consumer_mems"
    mounting: Any = None
    gnss_lever_arm: Any = (0.0, 0.0, 0.0)
    odo_lever_arm: Any = None
    estimate_odo_lever_arm: bool = False
    nhc: bool | None = None
    nhc_std: float = 0.05
    smoother: bool = True
    gnss_pos_std: float | None = None
    overrides: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class LogRun(Result):
    """What :func:`run_log` did and found.

    Attributes
    ----------
    result : GinsResult
        The filter run (the IMU's trajectory; ``q_vb`` its mounting).
    config : GinsConfig
        The configuration used.
    static : numpy.ndarray of bool, shape (N,)
        The samples declared at rest.
    mounting_coarse : MountingEstimate or None
        The estimate before the filter; with the bag's mounting (``tf_static``, ``frame_id``) the levelling at
        rest as a check of it (roll and pitch; not used); None when the mounting was given, taken as the
        identity, or the log has no rest.
    mounting_source : str
        ``"given"``, ``"tf_static"``, ``"frame_id"`` (the IMU's frame_id is the base frame), ``"estimated"`` or
        ``"identity"``.
    initial : dict
        The initial state and how it was found.
    meta_preset : str
        The IMU preset whose noise model the filter used.
    """

    result: GinsResult
    config: GinsConfig
    static: NDArray[np.bool_]
    mounting_coarse: MountingEstimate | None
    mounting_source: str
    initial: dict[str, Any]
    meta_preset: str = "consumer_mems"

    def state_layout(self) -> NDArray[np.int64]:
        """The run's error-state layout (``lay``: first index of each block of
        :data:`~imunav.ins.gins.layout.STATE_BLOCKS`, −1 when absent) to read ``result.cov_diag``.

        Returns
        -------
        numpy.ndarray of int
            The layout ``lay`` of the run's configuration.
        """
        return kernel_setup(self.config, 1.0, bool(self.result.meta.get("odometer", False)))[1]

    def moved_beyond_prior(self) -> dict[str, Any]:
        """The self-calibration states whose final value lies more than :data:`MOVED_SIGMAS` prior σ from the
        initial one (mounting angles about the vehicle axes in deg, the GNSS latency in s, the odometer scale): a
        mounting pulled 25° off by a filter fighting a model error, or a latency of half a second, is not a
        calibration.

        Returns
        -------
        dict
            Per state (``mount_roll_deg`` ..., ``gnss_latency_s``, ``odometer_scale``): ``change`` and ``sigmas``
            (the change over the prior σ); empty when every state stayed within its prior.
        """
        res, lay = self.result, self.state_layout()
        out: dict[str, Any] = {}
        im = int(lay[LAY.mount])
        if im >= 0 and res.q_vb is not None:
            E = dcm_from_quat(res.q_vb[-1]) @ dcm_from_quat(res.q_vb[0]).T
            mu = np.array([E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]]) / 2
            p0 = np.sqrt(res.cov_diag[0, im:im + 3])
            for j, axis in enumerate(("roll", "pitch", "yaw")):
                if abs(mu[j]) > MOVED_SIGMAS * p0[j]:
                    out[f"mount_{axis}_deg"] = {"change": math.degrees(mu[j]), "sigmas": abs(mu[j]) / p0[j]}
        for block, name, x in (("gnss_delay", "gnss_latency_s", res.gnss_delay),
                               ("odo_scale", "odometer_scale", res.odo_scale),
                               ("odo_turn", "odometer_turn_overread_s_per_rad", res.odo_turn),
                               ("side_slip", "side_slip_rad_per_mps2", res.side_slip)):
            i = int(lay[getattr(LAY, block)])
            if i >= 0 and x is not None:
                d, p0 = float(x[-1] - x[0]), math.sqrt(float(res.cov_diag[0, i]))
                if abs(d) > MOVED_SIGMAS * p0:
                    out[name] = {"change": d, "sigmas": abs(d) / p0}
        return out

    def mounting_euler(self) -> tuple[Array, Array]:
        """The final mounting as ZYX Euler angles (roll, pitch, yaw of the IMU in the vehicle) and their σ, rad.

        The σ maps the filter's mounting-error covariance (small rotations about the vehicle axes), plus the
        preset's accelerometer axis misalignment (:func:`~imunav.ins.gins.config.misalignment_std`) (which the filter does not model: the accelerometers' own axes
        are off the IMU's nominal ones by that much), through the Jacobian of the Euler angles; zero where the
        mounting was not estimated.

        Returns
        -------
        euler : numpy.ndarray, shape (3,)
            Roll, pitch, yaw of the IMU in the vehicle, rad.
        std : numpy.ndarray, shape (3,)
            Their σ, rad.
        """
        res = self.result
        C = dcm_from_quat(res.q_vb[-1])
        e0 = np.asarray(euler_from_dcm(C), dtype=float)
        im = int(self.state_layout()[LAY.mount])
        if im < 0:
            return e0, np.zeros(3)
        mis = misalignment_std(presets.get(self.meta_preset).accel.scale_misalignment)
        P = np.diag(res.cov_diag[-1, im:im + 3] + mis**2)
        J = np.zeros((3, 3))
        h = 1e-6
        for j in range(3):
            mu = np.zeros(3)
            mu[j] = h
            K = np.array([[0.0, -mu[2], mu[1]], [mu[2], 0.0, -mu[0]], [-mu[1], mu[0], 0.0]])
            e1 = np.asarray(euler_from_dcm((np.eye(3) + K) @ C), dtype=float)
            J[:, j] = np.remainder(e1 - e0 + np.pi, 2 * np.pi) - np.pi
        J /= h
        return e0, np.sqrt(np.diag(J @ P @ J.T))


def _gnss_moving(src: NavSources) -> NDArray[np.bool_]:
    """IMU samples where the GNSS shows the vehicle moving: its velocity above 0.3 m/s, or (fixes without velocity)
    its position more than 3σ (and 1 m) from where it was 5 s before or will be 5 s after; all false without
    GNSS.  A vehicle gliding at a steady speed has a quiet IMU: only its fixes tell that it does not stand."""
    imu = src.imu
    g = src.gnss
    if g is None or g.n < 2:
        return np.zeros(imu.n, dtype=bool)
    if g.vel_ned is not None and np.all(np.isfinite(g.vel_ned[:, :2])):
        fast = np.hypot(g.vel_ned[:, 0], g.vel_ned[:, 1]) > 0.3
    else:
        ne = lla_to_ned(g.lla, g.lla[0])[:, :2]
        sd = np.hypot(g.pos_std[:, 0], g.pos_std[:, 1])
        fast = np.zeros(g.n, dtype=bool)
        for lag in (-5.0, 5.0):
            j = np.clip(np.searchsorted(g.t, g.t + lag), 0, g.n - 1)
            far = np.hypot(*(ne[j] - ne).T) > np.maximum(3.0 * np.hypot(sd, sd[j]), 1.0)
            fast |= far & (np.abs(g.t[j] - g.t - lag) < 1.0)
    # each fix speaks for the IMU samples nearest to it
    k = np.clip(np.searchsorted(g.t, imu.t), 1, g.n - 1)
    k = np.where(np.abs(g.t[k - 1] - imu.t) < np.abs(g.t[k] - imu.t), k - 1, k)
    return fast[k] & (imu.t >= g.t[0] - 1.0) & (imu.t <= g.t[-1] + 1.0)


def _rest_masks(src: NavSources) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """``(still, static)`` per IMU sample.  ``still``: the odometer reads no speed and the accelerometers are quiet,
    the specific force is gravity (the levelling's samples), though a skid-steer robot may turn on the spot there;
    ``static``: still and not turning, the wheels' yaw rate zero when the odometer gives one (ZUPT, ZARU, the noise
    at rest: taking a turn on the spot for rest would make its rate a gyro bias).  Without an odometer both are the
    samples where the IMU and its gyro are quiet and the GNSS does not show the vehicle moving
    (:func:`_gnss_moving`)."""
    imu = src.imu
    try:
        quiet = static_intervals(imu, window_s=1.0, use_gyro=True).mask
    except InsufficientDataError:
        quiet = np.zeros(imu.n, dtype=bool)
    if src.odometer is None:
        moving = _gnss_moving(src)
        return quiet & ~moving, quiet & ~moving
    o = src.odometer
    # a driver's placeholder covariance (1e3, 1e6) must not widen the test until a cruising vehicle reads as rest
    sd = (np.zeros(o.t.size) if o.speed_std is None else
          np.minimum(np.asarray(o.speed_std, dtype=float) * np.ones(o.t.size), REST_NOISE_MAX))
    speed, n = _window_mean(o.t, o.speed, REST_WINDOW_S / 2.0)
    # the mean speed over the window is zero within twice its noise: a per-sample test would take the samples whose
    # noise happens to be small for rest, and leave the odometer only its large errors at rest (NIS 1.3)
    limit = REST_SPEED + 2.0 * np.sqrt(_window_mean(o.t, sd**2, REST_WINDOW_S / 2.0)[0] / n)
    still = quiet & (np.interp(imu.t, o.t, np.abs(speed) - limit, left=np.nan, right=np.nan) < 0.0)
    static = still
    if o.yaw_rate is not None:
        rate, _ = _window_mean(o.t, o.yaw_rate, REST_WINDOW_S / 2.0)
        static = still & (np.interp(imu.t, o.t, np.abs(rate), left=np.nan, right=np.nan) < REST_YAW_RATE)
    return still, static


def _window_mean(t: Array, x: Array, half: float) -> tuple[Array, Array]:
    """The mean of ``x`` over the samples within ``±half`` s of each stamp ``t``, and their count."""
    c = np.r_[0.0, np.cumsum(x)]
    a = np.searchsorted(t, t - half, side="left")
    b = np.searchsorted(t, t + half, side="right")
    return (c[b] - c[a]) / (b - a), (b - a).astype(float)


def _noise_at_rest(src: NavSources, static: NDArray[np.bool_]) -> tuple[Array, Array, str]:
    """White-noise densities of the gyro (rad/√s) and accelerometer (m/s/√s) measured at rest: the per-sample σ of
    each rest interval about its own mean, without its first and last :data:`REST_WINDOW_S` (the window of the rest
    test reaches that far into the braking and the start, whose accelerations are not noise: with them, the
    accelerometer's density came out 30 % high on the simulated robot and the filter's velocity σ too large,
    NHC NIS 0.97), where at least 1 s remains; pooled, times ``√Δt`` (a real vehicle's vibration at rest is part of
    what the filter must expect).  Zeros when the log has no such rest."""
    imu = src.imu
    dt = float(np.median(np.diff(imu.t)))
    edges = np.flatnonzero(np.diff(np.r_[0, static.astype(np.int8), 0]))
    trim = int(round(REST_WINDOW_S / dt))
    gv, av, n = np.zeros(3), np.zeros(3), 0
    for a, b in zip(edges[0::2] + trim, edges[1::2] - trim):
        if (b - a) * dt >= 1.0:
            gv += imu.gyro[a:b].var(axis=0, ddof=1) * (b - a - 1)
            av += imu.accel[a:b].var(axis=0, ddof=1) * (b - a - 1)
            n += b - a - 1
    if n == 0:
        return np.zeros(3), np.zeros(3), "no rest of 1 s: the preset's noise densities"
    gyro_nd, accel_nd = np.sqrt(gv / n * dt), np.sqrt(av / n * dt)
    return gyro_nd, accel_nd, (f"measured at rest over {n * dt:.1f} s: gyro {np.degrees(gyro_nd).max() * 60:.3f} "
                               f"deg/sqrt(h), accelerometer {accel_nd.max() * 60:.4f} m/s/sqrt(h) (the larger of these "
                               "and the preset's is used)")


def _initial_gyro_bias(src: NavSources, static: NDArray[np.bool_]) -> tuple[Array, Array | None, str]:
    """The gyro bias before the filter: the mean rate at rest; a log that never rests (10 samples) and has GNSS,
    the mean rate over the drive less its course change (:func:`imunav.ins.gins.alignment.gyro_bias_in_motion`),
    with its σ (the filter then starts from it); else zero.  Returns (bias rad/s, σ or None, how)."""
    imu = src.imu
    if static.sum() > 10:
        return imu.gyro[static].mean(axis=0), None, "mean rate at rest"
    if src.gnss is not None:
        try:
            b, sd = gyro_bias_in_motion(imu, src.gnss)
        except InsufficientDataError as exc:
            return np.zeros(3), None, f"zero ({exc})"
        return b, sd, (f"mean rate over the drive less the GNSS course change (no rest), sigma "
                       f"{math.degrees(float(sd[0])):.3f} deg/s")
    return np.zeros(3), None, "zero (no rest, no GNSS)"


def _initial_tilt(src: NavSources, static: NDArray[np.bool_], C_vb: Array,
                  bias: Array) -> tuple[Array, float, int]:
    """The down direction in IMU axes at the start and its σ (rad): the mean specific force of the first rest
    (σ 0.5°), else of the first second less the vehicle's own acceleration ``(dv/dt, v ω_z, 0)`` from the odometer
    (a car that starts moving: 0.2 m/s² of acceleration is a tilt of 1.2°; σ 2°), else of the first second as it
    is (σ 5°)."""
    imu = src.imu
    fs = 1.0 / float(np.median(np.diff(imu.t)))
    idx = np.flatnonzero(static[: int(60 * fs)])
    if idx.size >= fs:
        run = idx[: int(np.argmax(np.diff(idx) > 1)) + 1] if np.any(np.diff(idx) > 1) else idx
        f = imu.accel[run].mean(axis=0)
        sd = math.radians(0.5)
    else:
        run = np.arange(min(imu.n, max(2, int(fs))))
        f = imu.accel[run].mean(axis=0)
        sd = math.radians(5.0)
        o = src.odometer
        if o is not None and o.t[0] <= imu.t[run[0]] + 1.0 and o.t.size > 2:
            t = imu.t[run]
            h = 0.25
            v = np.interp(t, o.t, o.speed)
            a_x = (np.interp(t + h, o.t, o.speed) - np.interp(t - h, o.t, o.speed)) / (2 * h)
            w_z = ((imu.gyro[run] - bias) @ C_vb.T)[:, 2]
            a_v = np.column_stack([a_x, v * w_z, np.zeros(run.size)])
            f = (imu.accel[run] - a_v @ C_vb).mean(axis=0)
            sd = math.radians(2.0)
    return -f / np.linalg.norm(f), sd, int(run[-1])


def _cut_odometer(od: Any, t_end: float) -> Any:
    """The odometer's samples up to ``t_end``."""
    k = od.t <= t_end
    cut = lambda a: None if a is None else np.asarray(a)[k]  # noqa: E731
    return dataclasses.replace(od, t=od.t[k], speed=od.speed[k], speed_std=cut(od.speed_std), yaw_rate=cut(od.yaw_rate))


def _initial_velocity(src: NavSources, still: NDArray[np.bool_], C_nv: Array, psi_sd: float) -> tuple[Array, float]:
    """The NED velocity at the first IMU sample and its σ (m/s): zero (σ 0.05) at rest; moving, the odometer's
    speed along the vehicle's initial axis ``C_nv e_x`` (σ the speed's error and the heading's, at least 0.5), else
    the first GNSS velocity within 1 s (σ 0.5); else zero with σ 0.5 (a car that starts moving at 8 m/s must not
    start standing still: the filter took 20 s to recover and its latency state absorbed the error)."""
    t0 = float(src.imu.t[0])
    if still[0]:
        return np.zeros(3), 0.05
    o = src.odometer
    if o is not None and o.t[0] <= t0 + 0.5:
        v = float(np.interp(t0, o.t, o.speed))
        return C_nv @ np.array([v, 0.0, 0.0]), max(0.5, abs(v) * psi_sd)
    g = src.gnss
    if g is not None and g.vel_ned is not None and g.t[0] <= t0 + 1.0 and np.all(np.isfinite(g.vel_ned[0])):
        return np.asarray(g.vel_ned[0], dtype=float).copy(), 0.5
    return np.zeros(3), 0.5


def _mag_heading(src: NavSources, d_b: Array, C_vb: Array) -> float:
    """The vehicle's magnetic heading at the start from the mean of the first second of the magnetometer,
    levelled with the IMU's down direction ``d_b`` (rad)."""
    m = src.mag
    assert m is not None
    k = max(2, int(np.searchsorted(m.t, m.t[0] + 1.0)))
    mb = m.field_b[:k].mean(axis=0)
    L = _levelling(d_b)  # IMU -> a level frame (heading of the IMU's projection)
    mh = L @ mb
    psi_imu = math.atan2(-mh[1], mh[0])
    # the vehicle's heading: the IMU's, less the mounting's yaw
    return psi_imu - math.atan2(C_vb[1, 0], C_vb[0, 0])


def _dead_reckoning(src: NavSources, C_vb: Array, bias: Array, *, psi0: float = 0.0, i0: int = 0,
                    i1: int | None = None) -> Array:
    """Wheel-odometry dead reckoning over IMU samples ``i0 .. i1``: the vehicle's heading from ``psi0`` by the gyro's
    vertical rate (less ``bias``, in vehicle axes through ``C_vb``), the odometer speed as read along it; N, E in
    metres from the position at ``i0``, one row per sample."""
    imu = src.imu
    o = src.odometer
    assert o is not None
    sl = slice(i0, imu.n if i1 is None else i1 + 1)
    wz = ((imu.gyro[sl] - bias) @ C_vb.T)[:, 2]
    dt = np.diff(imu.t[sl], prepend=imu.t[sl][0])
    psi = psi0 + np.cumsum(wz * dt)
    v = np.interp(imu.t[sl], o.t, o.speed)
    return np.cumsum(np.column_stack([v * np.cos(psi), v * np.sin(psi)]) * dt[:, None], axis=0)


def _fit_heading(src: NavSources, p_dr: Array, lla_ref: Array) -> tuple[float, Array, float, int, float]:
    """Rotation ψ0 (and translation, scale) fitting the dead reckoning to the GNSS fixes over the first stretch
    of the drive with at least 30 m of travel; two passes reject fixes more than 3 robust σ off.
    Returns (ψ0, start position N E in m from ``lla_ref``, σ of ψ0 from the fit's residuals, fixes used, time of
    the stretch's last fix)."""
    g = src.gnss
    assert g is not None
    imu = src.imu
    ned = lla_to_ned(g.lla, lla_ref)[:, :2]
    pd = _rows_at(g.t, imu.t, p_dr[:, :2])
    travel = np.r_[0.0, np.cumsum(np.hypot(*np.diff(pd, axis=0).T))]
    end = int(np.searchsorted(travel, max(30.0, 0.25 * travel[-1]))) + 1
    use = np.zeros(g.n, dtype=bool)
    use[:end] = True
    psi = 0.0
    T = ned[0]
    for _ in range(3):
        a, b = pd[use], ned[use]
        am, bm = a.mean(axis=0), b.mean(axis=0)
        A, B = a - am, b - bm
        psi = math.atan2(float(np.sum(A[:, 0] * B[:, 1] - A[:, 1] * B[:, 0])), float(np.sum(A[:, 0] * B[:, 0] +
                                                                                          A[:, 1] * B[:, 1])))
        R = np.array([[math.cos(psi), -math.sin(psi)], [math.sin(psi), math.cos(psi)]])
        s = float(np.sum((A @ R.T) * B) / max(np.sum(A**2), 1e-9))
        T = bm - s * (R @ am)
        res = np.hypot(*(ned - (T + s * pd @ R.T)).T)
        mad = 1.4826 * float(np.median(res[use]))
        use = (np.arange(g.n) < end) & (res < 3.0 * mad + 1.0)
    spread = float(np.sqrt(np.sum((pd[use] - pd[use].mean(axis=0)) ** 2)))
    sd = float(np.sqrt(np.mean(res[use] ** 2))) / max(spread, 1e-6)
    if use.sum() < 5 or spread < 10.0:
        raise InsufficientDataError(f"{src.source}: the first {travel[min(end, g.n) - 1]:.0f} m of the drive "
                                    "hold too few fixes to find the heading; give the initial heading")
    return psi, T, sd, int(use.sum()), float(g.t[min(end, g.n) - 1])


def _heading_fit_std(src: NavSources, C_vb: Array, bias: Array, sd_fit: float, t_end: float,
                     config: GinsConfig) -> float:
    """σ of the heading that :func:`_fit_heading` found, its residuals' share ``sd_fit`` and the dead reckoning's
    own heading drift over the fitted stretch together.

    The gyro heading of the dead reckoning errs by ``δk |Δψ| + δb t`` at time ``t`` (scale factor ``δk`` times
    the angle turned, the bias left after the mean at rest ``δb``).  The fitted rotation averages that error over
    the stretch, about half its value at the end:

    ``σ_ψ² = σ_fit² + ((σ_k |Δψ|)² + (σ_b T)²) / 4``

    with ``σ_k`` the vehicle's yaw-rate scale σ from the preset's gyro scale σ per IMU axis through the mounting,
    ``σ_b`` its bias instability (``gyro_bias_std``), ``|Δψ|`` the angle turned and ``T`` the stretch's length.
    On simulated robot loops (a gyro scale σ of 0.9 %, 430° turned over the first 100 m) the residuals alone gave
    0.3-0.5° where the heading erred by up to 3°."""
    imu = src.imu
    k = int(np.searchsorted(imu.t, t_end, side="right"))
    wz = ((imu.gyro[:k] - bias) @ C_vb.T)[:, 2]
    turned = float(np.sum(np.abs(wz[1:]) * np.diff(imu.t[:k]))) if k > 1 else 0.0
    row = C_vb[2]  # the vehicle's yaw rate as a combination of the IMU's axes
    sk, sb = (float(np.sqrt(np.sum(row**2 * np.asarray(0.0 if x is None else x, dtype=float) ** 2 * np.ones(3))))
              for x in (config.init_gyro_scale_std, config.gyro_bias_std))
    span = float(t_end - imu.t[0])
    return math.sqrt(sd_fit**2 + ((sk * turned) ** 2 + (sb * span) ** 2) / 4.0)


def run_log(src: NavSources, options: LogRunOptions | None = None, *,
            progress: Callable[[int, int], None] | None = None) -> LogRun:
    """Run the GNSS/INS filter on a log's navigation sources (module docstring).

    Parameters
    ----------
    src : NavSources
        From :func:`imunav.io.navlog.read_nav_sources`.
    options : LogRunOptions, optional
        Preset, mounting, lever arms, NHC, smoother, configuration overrides.
    progress : callable, optional
        ``progress(done, total)`` as the filter and the smoother go (:meth:`GinsFilter.run`).

    Returns
    -------
    LogRun
        The filter run, its configuration, the rest mask, the mounting and the initial state.

    Raises
    ------
    InsufficientDataError
        If the log is too short to level the IMU or find the heading.
    InvalidInputError
        If an option is out of range (a mounting that is not a rotation, ...).
    """
    o = options or LogRunOptions()
    imu = src.imu
    still, static = _rest_masks(src)
    bias0, bias0_sd, bias_note = _initial_gyro_bias(src, static)
    model = presets.get(o.preset)
    wheeled = src.odometer is not None
    # -- mounting
    coarse = None
    ba_level = float(np.max(np.abs(model.accel.bias))) if np.any(model.accel.bias) else 0.05
    q_vb, source, mount_sd = np.array([1.0, 0.0, 0.0, 0.0]), "identity", None
    mount_note = None
    if o.mounting is not None:
        q_vb = np.asarray(o.mounting, dtype=float)
        if q_vb.shape != (4,) or not np.all(np.isfinite(q_vb)) or abs(np.linalg.norm(q_vb) - 1) > 1e-6:
            raise InvalidInputError(f"mounting must be a unit quaternion (w, x, y, z); got {o.mounting!r}")
        source = "given"
    elif src.imu_to_base is not None:
        q_vb = np.asarray(src.imu_to_base, dtype=float)
        source = "frame_id" if str(src.meta.get("mounting", "")).startswith("the IMU's frame_id") else "tf_static"
        if wheeled:
            # the levelling at rest as a check of the bag's mounting (reported; a contradiction is not ignored)
            try:
                coarse = estimate_mounting(imu, still, accel_bias_std=ba_level, level_noise_std=LEVEL_STD)
            except InsufficientDataError:
                coarse = None
            if coarse is not None:
                used = np.asarray(euler_from_dcm(dcm_from_quat(q_vb)), dtype=float)[:2]
                off = np.abs(np.remainder(coarse.euler[:2] - used + math.pi, 2 * math.pi) - math.pi)
                if np.any(off > 3.0 * coarse.std[:2] + MOUNT_CHECK_MARGIN):
                    if source == "tf_static":
                        raise InvalidInputError(
                            f"{src.source}: the bag's /tf_static mounting has roll, pitch "
                            f"{np.degrees(used).round(2).tolist()} deg but the accelerometers at rest read "
                            f"{np.degrees(coarse.euler[:2]).round(2).tolist()} +- "
                            f"{np.degrees(coarse.std[:2]).round(2).tolist()} deg: give --imu-rotation")
                    # a frame_id is only the driver's claim: estimate the mounting instead
                    mount_note = (f"the IMU's frame_id claims the base frame, but the levelling at rest reads roll, "
                                  f"pitch {np.degrees(coarse.euler[:2]).round(2).tolist()} deg: estimated instead")
                    source, coarse = "estimated_frame_id_contradicted", None
    if source in ("identity", "estimated_frame_id_contradicted") and wheeled:
        od = src.odometer
        assert od is not None
        coarse = estimate_mounting(imu, still, speed_t=od.t, speed=od.speed, accel_bias_std=ba_level,
                                   level_noise_std=LEVEL_STD, gyro_bias=bias0)
        q_vb, source, mount_sd = coarse.q_vb, "estimated", coarse.std
    C_vb = dcm_from_quat(q_vb)
    # -- initial attitude, heading and position
    d_b, tilt_sd, i_rest = _initial_tilt(src, still, C_vb, bias0)
    ref = np.array([0.0, 0.0, 0.0]) if src.gnss is None else src.gnss.lla[0].copy()
    initial: dict[str, Any] = {"gyro_bias": bias_note}
    if mount_note is not None:
        initial["mounting"] = mount_note
    if wheeled and src.gnss is not None:
        p_dr = _dead_reckoning(src, C_vb, bias0)
        psi0, T, psi_fit, used, t_fit = _fit_heading(src, p_dr, ref)
        gyro_model = GinsConfig.from_preset(o.preset, **{k: v for k, v in o.overrides.items() if k in _GYRO_FIELDS})
        psi_sd = _heading_fit_std(src, C_vb, bias0, psi_fit, t_fit, gyro_model)
        pos0 = np.array([T[0], T[1], 0.0])
        initial.update(heading="odometry dead reckoning fitted to the first GNSS fixes", fixes=used)
        pos_sd = 2.0
    elif src.gnss is not None:
        psi0, psi_sd, pos0, pos_sd = 0.0, math.pi / 2, np.zeros(3), 5.0
        how = "unknown (0, sigma 90 deg)"
        v = src.gnss.vel_ned
        if src.mag is not None:
            psi0, psi_sd, how = _mag_heading(src, d_b, C_vb), math.radians(15.0), \
                "magnetometer (tilt-compensated, no declination applied)"
        elif v is not None:
            k = int(np.argmax(np.hypot(v[:, 0], v[:, 1]) > 2.0))
            if np.hypot(*v[k, :2]) > 2.0:
                psi0, psi_sd, how = math.atan2(v[k, 1], v[k, 0]), math.radians(10.0), "GNSS course"
        initial.update(heading=how)
    else:
        psi0, psi_sd, pos0, pos_sd = 0.0, math.radians(0.01), np.zeros(3), 0.01
        initial.update(heading="dead-reckoning frame: heading 0 and position (0, 0) at the start")
    g_v = C_vb @ d_b
    C_nv = np.array([[math.cos(psi0), -math.sin(psi0), 0.0], [math.sin(psi0), math.cos(psi0), 0.0],
                     [0.0, 0.0, 1.0]]) @ _levelling(g_v)
    q0 = quat_from_dcm(C_nv @ C_vb)
    lla0 = ned_to_lla(pos0[None, :], ref)[0] if src.gnss is not None else ref
    vel0, vel_sd = _initial_velocity(src, still, C_nv, psi_sd)
    initial.update(lla0=lla0.tolist(), heading_deg=math.degrees(psi0), heading_std_deg=math.degrees(psi_sd))
    # -- configuration
    # the levelling reads the accelerometer bias as tilt: φ_N ≈ b_E / g, φ_E ≈ −b_N / g (Groves 2013, §5.6.2), so
    # the tilt's σ is the levelling's and the bias's together (the measurements build their correlation)
    ba_sd = np.asarray(o.overrides.get("init_accel_bias_std", GinsConfig.from_preset(o.preset).init_accel_bias_std),
                       dtype=float) * np.ones(3)
    Pb_n = (C_nv @ C_vb) @ np.diag(ba_sd**2) @ (C_nv @ C_vb).T
    g0 = float(normal_gravity(ref[0], ref[2])) if src.gnss is not None else float(normal_gravity(0.0))
    tilt_n = np.sqrt(tilt_sd**2 + np.array([Pb_n[1, 1], Pb_n[0, 0]]) / g0**2)
    cfg_kw: dict[str, Any] = dict(
        lever_arm=C_vb.T @ np.asarray(o.gnss_lever_arm, dtype=float),
        mounting=np.asarray(euler_from_dcm(C_vb), dtype=float), init_pos_std=pos_sd,
        init_vel_std=vel_sd,
        init_att_std=(float(tilt_n[0]), float(tilt_n[1]), max(psi_sd, math.radians(0.5))),
        # a real IMU's accelerometer axes, which nobody calibrated: the tilt they leave is in the reported σ
        accel_misalignment_std=misalignment_std(model.accel.scale_misalignment),
        )
    if mount_sd is not None:
        cfg_kw.update(mounting_std=np.maximum(mount_sd, math.radians(0.05)), level_noise_std=LEVEL_STD)
    elif wheeled and src.gnss is None and source in ("frame_id", "tf_static"):
        # a driver's claim of the mounting: without GNSS nothing checks it, so its error is carried, not estimated
        cfg_kw.update(mounting_std=np.full(3, CLAIMED_MOUNT_STD))
    if wheeled:
        lever_v = o.odo_lever_arm
        if lever_v is None:
            lever_v = (-np.asarray(src.imu_lever_base, dtype=float) if src.imu_lever_base is not None
                       else np.zeros(3))
        # without GNSS nothing measures the odometer's scale: it stays at 1 with the prior σ of a wheel's radius,
        # which the position's σ then carries (a dead reckoning that reported 1.0000 ± 0.0000 claimed a certainty it
        # did not have)
        cfg_kw.update(odo_lever_arm=C_vb.T @ np.asarray(lever_v, dtype=float),
                      odo_scale_std=ODO_SCALE_STD if src.gnss is not None else ODO_SCALE_PRIOR_STD,
                      odo_scale_corr_time=np.inf,
                      odo_noise_std=ODO_STD_FLOOR, wheel_adaptive=True)
        if o.estimate_odo_lever_arm:
            cfg_kw["odo_lever_arm_std"] = 0.3
    if (o.nhc if o.nhc is not None else wheeled):
        fast = src.odometer is not None and float(np.percentile(np.abs(src.odometer.speed), 95)) > SIDE_SLIP_FAST_MPS
        cfg_kw.update(nhc_noise_std=o.nhc_std, nhc_interval_s=NHC_INTERVAL, side_slip_std=SIDE_SLIP_STD[int(fast)])
    if src.gnss is not None:
        # the fixes' reported σ is a prior: the filter scales it to what their innovations show (a u-blox without an
        # accuracy field, a driver's constant covariance, a receiver that under- or over-states it)
        cfg_kw.update(gnss_delay_std=GNSS_DELAY_STD, gnss_adaptive=True)
    else:
        # what only GNSS would observe (the odometer's scale and over-reading in turns, the mounting) keeps its prior
        # σ as Schmidt consider states: the INS's own drift must not "calibrate" it (the Jackal's scale went to 1.61 ±
        # 0.009 that way), and the position's σ carries it
        cfg_kw["consider_states"] = tuple(b for b in ("odo_scale", "odo_turn", "side_slip", "mount", "odo_lever")
                                          if b != "odo_lever" or o.estimate_odo_lever_arm)
    cfg_kw["gate_max_rejections"] = MAX_REJECTIONS
    cfg_kw["bias_model"] = "constant_and_gauss_markov"  # a log's IMU: a turn-on bias that does not decay
    gyro_nd, accel_nd, noise_note = _noise_at_rest(src, static)
    base = GinsConfig.from_preset(o.preset)
    cfg_kw.update(gyro_noise_density=np.maximum(base.gyro_noise_density, gyro_nd),
                  accel_noise_density=np.maximum(base.accel_noise_density, accel_nd))
    initial["noise"] = noise_note
    cfg_kw.update(o.overrides)
    cfg = GinsConfig.from_preset(o.preset, **cfg_kw)
    odo = src.odometer
    if odo is not None and odo.speed_std is not None:
        odo = dataclasses.replace(odo, speed_std=np.maximum(odo.speed_std, ODO_STD_FLOOR))
    e0 = None
    if bias0_sd is not None:  # no rest: the filter starts from the bias read over the drive
        e0 = np.zeros(12)
        e0[:3] = bias0

    def run(c: GinsConfig, smoother: bool, report: Callable[[int, int], None] | None, n: int,
            fixes: Any = None, withheld: Any = None) -> GinsResult:
        """The filter over the first ``n`` IMU samples (the aids cut to them), on ``fixes`` if given, predicting
        the ``withheld`` fixes without using them."""
        gn, od = (src.gnss if fixes is None else fixes), odo
        if n < imu.n:
            t_end = float(imu.t[n - 1])
            gn = None if gn is None else gn.select(gn.t <= t_end, "beyond the first pass")
            od = None if od is None else _cut_odometer(od, t_end)
        return GinsFilter(c).run(imu if n == imu.n else imu.slice(0, n), gn, lla0=lla0, vel0=vel0, q0=q0, odometer=od, imu_errors0=e0,
                                 static=static[:n], baro=None, smoother=smoother, progress=report,
                                 gnss_withheld=withheld)

    two = src.gnss is not None and cfg.gnss_bias_std is None and "gnss_bias_std" not in o.overrides
    # the first pass covers the log's first GNSS_IDENTIFY_S, and 200 fixes at least (the autocovariance's standard
    # error is then a few percent); one bar over both passes
    first_n = 0
    if two:
        g = src.gnss
        assert g is not None
        t_first = max(float(imu.t[0]) + GNSS_IDENTIFY_S, float(g.t[min(200, g.n - 1)]))
        first_n = int(np.searchsorted(imu.t, t_first, side="right"))
    rest_n = imu.n * (1 + int(o.smoother))
    if two:
        # the fixes' error correlated in time: its σ from the memory of their residuals about a first pass without
        # it (gnss_correlated_std); none for white fixes
        first = run(cfg, False, None if progress is None else (lambda done, total: progress(done, total + rest_n)),
                    first_n)
        sig = gnss_correlated_std(first, src.gnss.select(src.gnss.t <= first.t[-1], "beyond the first pass"),
                                  cfg.lever_arm)
        cfg = dataclasses.replace(cfg, gnss_bias_std=sig, gnss_bias_corr_time=GNSS_BIAS_TAU)
        initial["gnss_errors"] = (f"correlated error sigma N E D {np.round(sig, 3).tolist()} m, "
                                  f"{GNSS_BIAS_TAU:g} s: the autocorrelation of the fixes' residuals about a first "
                                  "pass")
        # what the fixes' residuals cannot show, the process's own errors (the odometer scale's wander, the IMU
        # bias's instability), chosen by how well each model predicts fixes withheld from it
        cv_n = min(first_n, int(np.searchsorted(imu.t, float(imu.t[0]) + WANDER_CV_SPAN_S, side="right")))
        cfg = _process_models(cfg, src.gnss, first, lambda c, g, w: run(c, False, None, cv_n, g, w), initial,
                              wander=odo is not None and "odo_scale_corr_time" not in o.overrides,
                              bias=not {"gyro_bias_std", "accel_bias_std"} & set(o.overrides))
    res = run(cfg, o.smoother, None if progress is None else
              (lambda done, total: progress(first_n + done, first_n + total)), imu.n)
    out = LogRun(res, cfg, static, coarse, source, initial, o.preset)
    moved = [k for k, v in out.moved_beyond_prior().items()
             if k.startswith("mount_") and abs(v["change"]) > MOUNT_HOLD_DEG]
    if moved and mount_sd is not None:
        # the filter pulled an estimated mounting beyond what the levelling and the drive support (a model error,
        # not a calibration): the coarse mounting is kept, its σ carried as consider states
        cfg = dataclasses.replace(cfg, consider_states=tuple(dict.fromkeys((*cfg.consider_states, "mount"))))
        initial["mounting_held"] = (f"the filter pulled the mounting ({', '.join(moved)}) beyond {MOVED_SIGMAS:g} "
                                    f"prior sigma and {MOUNT_HOLD_DEG:g} deg: the coarse estimate is kept, its sigma "
                                    "carried")
        out = LogRun(run(cfg, o.smoother, None, imu.n), cfg, static, coarse, source, initial, o.preset)
    return out


def _process_models(cfg: GinsConfig, gnss: Any, first: GinsResult, run: Callable[[GinsConfig, Any, Any], GinsResult],
                    notes: dict[str, Any], *, wander: bool, bias: bool) -> GinsConfig:
    """The process model that best predicts withheld fixes: the odometer scale's wander and the IMU biases'
    instability, chosen together.

    A cross-validation on the log's own fixes, by time windows (:func:`~imunav.ins.gins.identify.withheld_windows`):
    each candidate runs without the windows' fixes but predicting them (``GinsFilter.run(gnss_withheld=…)``) and
    is scored there by the log score of the filter's own predictive density of each fix
    (:func:`~imunav.ins.gins.identify.withheld_score`); the best is kept.  (The one-standard-error rule, the
    least process noise within one standard error of the best over the windows, kept too little on the hard robot:
    drives 300-329, velocity NEES 14.9 and 93.8 % of outage ends inside 3σ, against 8.6 and 97.9 % before the
    grid.)  The fixes follow these errors so closely that their residuals show
    no sign of them, but a run without them for 30 s drifts by them.  Fixes the first pass's gate rejected are not
    scored.  The candidates are the grid of

    * ``wander``: the odometer scale's wander, each of :data:`ODO_WANDER` (σ over :data:`ODO_WANDER_TAU`; 0: a
      constant scale) as the scale state's correlation time ``σ_k² T / σ_w²`` (the prior's σ_k kept, the driving
      noise ``2σ_w²/T`` of the wander);
    * ``bias``: the IMU biases' instability, the Gauss–Markov σ of the gyros and accelerometers times each of
      :data:`BIAS_INSTABILITY_FACTORS`: a log's IMU warms, and a consumer part's datasheet instability, measured
      at a constant temperature, understates how its bias moves then (on the hard car, without the warm-up drift
      the velocity NEES falls from 8.2 to 4.9).

    Chosen one after the other, each would be chosen under the other's wrong value: a bias held too still makes a
    wandering scale look worse than a constant one (hard robot drives 200-207: velocity NEES 20 one after the
    other, 8.5 together).
    """
    if not (wander or bias):
        return cfg
    g = gnss.select(gnss.t <= first.t[-1], "beyond the first pass")
    rec = first.aids.get("gnss_position")
    good = np.asarray(rec.accepted, dtype=bool) if rec is not None and rec.t.size == g.n else np.ones(g.n, bool)
    held = withheld_windows(g.t, float(first.t[0]) + WANDER_CV_START_S)
    if np.count_nonzero(held & good) < 20 or np.count_nonzero(~held) < 20:
        why = (f"not cross-validated: {np.count_nonzero(held & good)} fixes in withheld windows, 20 needed; the log "
               "is too short")
        if wander:
            notes["odometer_errors"] = f"scale constant ({why})"
        if bias:
            notes["imu_errors"] = f"bias instability as the preset's ({why})"
        return cfg
    kept = g.select(~held, "withheld by the cross-validation")
    scored = g.select(held & good, "kept, or rejected by the first pass's gate")
    walks = ODO_WANDER if wander else (None,)
    factors = BIAS_INSTABILITY_FACTORS if bias else (1.0,)
    gb, ab = np.asarray(cfg.gyro_bias_std, dtype=float), np.asarray(cfg.accel_bias_std, dtype=float)
    grid, scores = [], []
    for s_w in walks:
        for f in factors:
            c = dataclasses.replace(cfg, gyro_bias_std=f * gb, accel_bias_std=f * ab)
            if s_w:  # 0 or None: the scale as configured (constant)
                c = dataclasses.replace(c, odo_scale_corr_time=cfg.odo_scale_std**2 * ODO_WANDER_TAU / s_w**2)
            grid.append(((s_w, f), c))
            scores.append(withheld_score(run(c, kept, scored)))
    best = int(np.nanargmin(scores)) if np.any(np.isfinite(scores)) else 0
    (s_w, f), chosen = grid[best]
    table = ", ".join((f"{w:g}/{x:g}" if wander and bias else f"{w:g}" if wander else f"{x:g}") + f": {v:.2f}"
                      for ((w, x), _), v in zip(grid, scores))
    how = (" (cross-validated on withheld fixes, log scores of "
           + ("wander/bias factor" if wander and bias else "wander" if wander else "bias factor") + f": {table})")
    if wander:
        notes["odometer_errors"] = (f"scale wanders by {s_w:g} over {ODO_WANDER_TAU:g} s" if s_w
                                    else "scale constant") + how
    if bias:
        notes["imu_errors"] = f"bias instability {f:g} x the preset's" + how
    return chosen


def parse_rotation(text: str | None, flag: str = "--imu-rotation") -> Array | None:
    """A rotation given as text: a unit quaternion ``"qw,qx,qy,qz"`` or ZYX Euler angles ``"roll,pitch,yaw"`` in
    degrees (IMU FRD -> vehicle FRD).

    Parameters
    ----------
    text : str or None
        The text (None: no rotation).
    flag : str
        The option's name, for the message.

    Returns
    -------
    numpy.ndarray, shape (4,), or None
        The quaternion, scalar first.

    Raises
    ------
    InvalidInputError
        If it is not 3 or 4 finite numbers, or 4 numbers that are not a unit quaternion (within 1e-6).
    """
    if text is None:
        return None
    try:
        v = np.array([float(x) for x in text.replace(" ", "").split(",") if x], dtype=float)
    except ValueError:
        raise InvalidInputError(f"{flag} {text!r}: give 'qw,qx,qy,qz' or 'roll,pitch,yaw' in degrees") from None
    if v.size not in (3, 4) or not np.all(np.isfinite(v)):
        raise InvalidInputError(f"{flag} {text!r}: give 4 numbers (a unit quaternion qw,qx,qy,qz) or 3 (ZYX roll,"
                                "pitch,yaw in degrees)")
    if v.size == 4:
        if abs(float(np.linalg.norm(v)) - 1.0) > 1e-6:
            raise InvalidInputError(f"{flag} {text!r}: a quaternion of norm {np.linalg.norm(v):.6g} is not a "
                                    "rotation (its norm must be 1)")
        return v / np.linalg.norm(v)
    if np.any(np.abs(v) > 360.0):
        raise InvalidInputError(f"{flag} {text!r}: angles in degrees lie within +-360")
    return quat_from_euler(np.radians(v))


def parse_vector(text: str | None, flag: str, default: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> Array:
    """A 3-vector given as text ``"x,y,z"`` (SI).

    Parameters
    ----------
    text : str or None
        The text (None: ``default``).
    flag : str
        The option's name, for the message.
    default : tuple of float
        The value without text.

    Returns
    -------
    numpy.ndarray, shape (3,)
        The vector.

    Raises
    ------
    InvalidInputError
        If it is not 3 finite numbers.
    """
    if text is None:
        return np.array(default, dtype=float)
    try:
        v = np.array([float(x) for x in text.replace(" ", "").split(",") if x], dtype=float)
    except ValueError:
        v = np.zeros(0)
    if v.size != 3 or not np.all(np.isfinite(v)):
        raise InvalidInputError(f"{flag} {text!r}: give 3 finite numbers 'x,y,z' in metres")
    return v


@dataclass(frozen=True)
class LogOutageReport(Result):
    """The outage test of a log: the fixes removed during each outage are the reference, or a truth when given.

    Attributes
    ----------
    outages : list of (float, float)
        Start (s on the sources' time axis) and length of each outage, every shift's in turn.
    end_m : numpy.ndarray, shape (K,)
        Horizontal error at the end of each outage against the reference there (the last fix removed in it, or
        the truth at the last IMU sample of the outage), m.
    max_m : numpy.ndarray, shape (K,)
        Largest horizontal error against the outage's reference points, m.
    contained : numpy.ndarray of bool, shape (K,)
        Every reference point of the outage inside the predicted 3σ, inflated by the fix's own σ when the fixes
        are the reference (``3 √(σ_N² + σ_E² + σ_fix,N² + σ_fix,E²)``; the fix's σ as the run with every fix
        identified it: the reported σ times the adaptive factor, and the correlated error's σ).
    dead_reckoning_end_m : numpy.ndarray, shape (K,)
        The same end error of wheel-odometry dead reckoning (odometer speed as read, gyro heading) started from
        the filter's state at the outage's start, m (NaN without an odometer).
    fixes : numpy.ndarray of int, shape (K,)
        Reference points in each outage: the fixes the run with every fix did not reject as faulty, or the IMU
        samples compared with the truth.
    normalised : numpy.ndarray, shape (K,)
        Largest normalised horizontal error of each outage, ``|e| / √(σ_N² + σ_E² + σ_ref²)`` over its reference
        points (containment is ``normalised <= 3``).
    meta : dict
        The protocol; ``reference`` (``"removed fixes"`` or ``"truth"``) and ``reference_noise_m`` (RMS
        horizontal σ of the reference points: √(mean(σ_N² + σ_E²)) of the fixes, 0 for a truth).
    """

    outages: list[tuple[float, float]]
    end_m: Array
    max_m: Array
    contained: NDArray[np.bool_]
    dead_reckoning_end_m: Array
    fixes: NDArray[np.int64]
    normalised: Array
    meta: dict[str, Any] = field(default_factory=dict)

    def rms(self) -> dict[str, Any]:
        """RMS over the outages of the end and largest errors, the dead reckoning's end error and their ratio.

        Against removed fixes, each end error holds the fix's own noise: ``E[e²] = e_true² + σ_ref²`` with
        ``σ_ref`` = ``reference_noise_m`` (the fixes' stated σ, N and E together), a floor that no filter goes
        under.  ``end_above_noise_m`` and ``dead_reckoning_above_noise_m`` remove it, ``√(RMS² − σ_ref²)``, and
        ``ratio_above_noise`` is their ratio; each is null when ``RMS² − σ_ref²`` is under two standard errors of
        the noise's own mean square over the K outages, ``2 σ_ref² / √K`` (a fix's horizontal noise squared is
        exponential with mean σ_ref² for Gaussian N and E errors): the difference is then the noise's own
        scatter, not the filter's error.  With a truth the two pairs equal the raw ones.

        Returns
        -------
        dict
            ``n_outages``, ``reference``, ``reference_noise_m``, ``end_m``, ``max_m``, ``dead_reckoning_end_m``,
            ``ratio_to_dead_reckoning`` (null without an odometer), ``end_above_noise_m``,
            ``dead_reckoning_above_noise_m``, ``ratio_above_noise``, ``contained_3sigma`` (share).
        """
        def r(x: Array) -> float | None:
            x = x[np.isfinite(x)]
            return float(np.sqrt(np.mean(x**2))) if x.size else None

        n_out = int(self.end_m.size)
        noise = float(self.meta.get("reference_noise_m", 0.0))
        se = 2.0 * noise**2 / math.sqrt(max(n_out, 1))

        def above(x: float | None) -> float | None:
            if x is None:
                return None
            if noise == 0.0:
                return x
            return math.sqrt(x * x - noise * noise) if x * x - noise * noise > se else None

        e, d = r(self.end_m), r(self.dead_reckoning_end_m)
        ea, da = above(e), above(d)
        return {"n_outages": n_out, "reference": self.meta.get("reference", "removed fixes"),
                "reference_noise_m": noise, "end_m": e, "max_m": r(self.max_m), "dead_reckoning_end_m": d,
                "ratio_to_dead_reckoning": (e / d) if (e is not None and d) else None,
                "end_above_noise_m": ea, "dead_reckoning_above_noise_m": da,
                "ratio_above_noise": (ea / da) if (ea is not None and da) else None,
                "contained_3sigma": float(np.mean(self.contained)) if self.contained.size else None,
                "normalised_max": float(np.max(self.normalised)) if self.normalised.size else None}


def _horizontal(lla: Array, ref: Array) -> Array:
    return lla_to_ned(lla, ref)[:, :2]


def _rows_at(t: Array, tp: Array, x: Array) -> Array:
    """The columns of ``x`` (rows at times ``tp``) linearly interpolated to ``t``."""
    return np.column_stack([np.interp(t, tp, x[:, j]) for j in range(x.shape[1])])


def truth_on_sources(truth: NavTrack, src: NavSources) -> NavTrack:
    """A truth's times moved onto the sources' time axis (s since the IMU's first stamp).

    A KF-GINS ``.nav`` truth is stamped in GPS week and seconds of week; a log whose stamps are UTC maps its time
    onto that (:meth:`~imunav.io.navlog.NavSources.gps_time`), one whose clock is not UTC onto its own seconds
    (week 0), as ``imunav gins run LOG`` writes its ``.nav``.

    Parameters
    ----------
    truth : NavTrack
        The reference trajectory (KF-GINS ``.nav`` convention: ``t`` seconds of week of ``week``).
    src : NavSources
        The log's sources.

    Returns
    -------
    NavTrack
        The truth with ``t`` in s since ``src.t0_ns``.

    Raises
    ------
    InvalidInputError
        If the truth does not overlap the log's IMU span.
    """
    g0 = src.gps_time([0.0])
    t = (int(truth.week) - int(g0.week[0])) * 604800.0 + np.asarray(truth.t, dtype=float) - float(g0.sow[0])
    if t.size < 2:
        raise InvalidInputError(f"the truth ({truth.meta.get('source', 'given')}) has {t.size} row(s); it needs at "
                                "least 2 to be interpolated")
    if t[-1] < src.imu.t[0] or t[0] > src.imu.t[-1]:
        raise InvalidInputError(f"the truth ({truth.meta.get('source', 'given')}, week {truth.week}, "
                                f"{truth.t[0]:.3f}-{truth.t[-1]:.3f} s of week) does not overlap {src.source} "
                                f"(week {int(g0.week[0])}, from {float(g0.sow[0]):.3f} s of week): give the truth "
                                "of this log, stamped as its .nav output")
    return dataclasses.replace(truth, t=t)


def log_outage_test(src: NavSources, options: LogRunOptions | None = None, *, converge_s: float = 60.0,
                    every_s: float = 120.0, length_s: float = 60.0, shifts_s: tuple[float, ...] = (0.0, 30.0, 60.0),
                    truth: NavTrack | None = None, truth_std: float = 0.0,
                    progress: Any = None) -> LogOutageReport:
    """GNSS outages on a log: the fixes removed during each outage are the reference, or a truth when given.

    One :func:`run_log` with every fix tells which fixes are faulty (rejected by the gate); then, per shift, the
    scheduled outages (:func:`imunav.sim.gnss.outage_schedule`) remove the fixes, the run is repeated, and each
    outage's horizontal error is measured against its removed good fixes at their stamps (the latency the run
    estimated taken into account), or, with ``truth``, against the truth at the run's IMU samples in the outage.
    Beside it, the dead reckoning of the wheel odometry as read and the gyro heading from the filter's state at the
    outage's start: what the filter adds to the odometer.

    The removed fixes carry their own noise, ``E[e²] = e_true² + σ_fix²`` at each, with ``σ_fix`` as the run with
    every fix identified it (the reported σ times the adaptive factor, and the correlated error's σ: a receiver that
    understates its σ would otherwise make every filter look wrong): a floor the report states
    (:meth:`LogOutageReport.rms`); a truth that is a peer's estimate (comma2k19's pose) has its own,
    ``truth_std``.  The runs are the forward filter's (``options.smoother`` is ignored): an outage tests what the
    filter predicts with no fix, not what a smoother recovers from the fixes after it.

    Parameters
    ----------
    src : NavSources
        The log's sources (with GNSS).
    options : LogRunOptions, optional
        As :func:`run_log`.
    converge_s : float
        Time before the first outage, s.
    every_s, length_s : float
        Outage period and length, s (``every_s > length_s > 0``).
    shifts_s : tuple of float
        Shifts of the first outage, s; one run per shift.
    truth : NavTrack, optional
        Reference trajectory of the IMU's position (KF-GINS ``.nav`` time convention, :func:`truth_on_sources`).
    truth_std : float
        σ of the truth's horizontal position (√(σ_N² + σ_E²), m, >= 0), added to the predicted σ for the
        containment.
    progress : callable, optional
        ``progress(done, total)`` after each run.

    Returns
    -------
    LogOutageReport
        Per outage: end and largest errors, containment, the dead reckoning's end error.

    Raises
    ------
    InvalidInputError
        Without GNSS, when no outage fits after the convergence time, when the truth does not overlap the log, or
        when the protocol counts outages twice (:func:`~imunav.ins.gins.outage.check_protocol`).
    """
    check_protocol(every_s, length_s, shifts_s)
    if src.gnss is None:
        raise InvalidInputError(f"{src.source}: the outage test removes GNSS fixes; the log has none")
    ref_truth = truth_on_sources(truth, src) if truth is not None else None
    if not (math.isfinite(truth_std) and truth_std >= 0):
        raise InvalidInputError(f"truth_std must be >= 0 m; got {truth_std!r}")
    o = dataclasses.replace(options or LogRunOptions(), smoother=False)
    full = run_log(src, o)
    rec = full.result.aids.get("gnss_position")
    good = np.ones(src.gnss.n, dtype=bool)
    if rec is not None:
        t_bad = rec.t[~rec.accepted]
        good &= ~np.isin(src.gnss.t, t_bad)
    t0, t1 = float(src.imu.t[0]), float(src.imu.t[-1])
    fr = full.result
    fix_scale = float(fr.gnss_noise_scale[-1]) if fr.gnss_noise_scale is not None else 1.0
    gb = full.config.gnss_bias_std
    fix_corr = 0.0 if gb is None else float(np.sum(np.asarray(gb, dtype=float)[:2] ** 2))
    outs, end, mx, cont, dr, nfix, ref_var, nmax = [], [], [], [], [], [], [], []
    skipped = 0  # outages without a reference point (no good fix in them, or outside the truth)
    total = len(shifts_s) + 1
    if progress is not None:
        progress(1, total)
    for k, sh in enumerate(shifts_s):
        sched = outage_schedule(t0 + converge_s, t1, every_s=every_s, length_s=length_s, first_s=sh)
        if not sched:
            raise InvalidInputError(f"no {length_s:g} s outage fits after {converge_s:g} s of convergence (shift "
                                    f"{sh:g} s) in a {t1 - t0:g} s log")
        keep = np.ones(src.gnss.n, dtype=bool)
        for s, d in sched:
            keep &= ~((src.gnss.t >= s) & (src.gnss.t < s + d))
        run = run_log(dataclasses.replace(src, gnss=src.gnss.select(keep, "outage test")), o)
        res = run.result
        C_vb = dcm_from_quat(res.q_vb[-1])
        tau = float(res.gnss_delay[-1])
        for s, d in sched:
            if ref_truth is None:
                idx = np.flatnonzero((src.gnss.t >= s) & (src.gnss.t < s + d) & good)
                if idx.size == 0:
                    skipped += 1
                    continue
                tf = src.gnss.t[idx] - tau  # the fixes hold the antenna at their stamp less the latency
                # a fix's own error as the run with every fix identified it, not as the receiver claims it: the
                # reported variance times the adaptive factor, plus the correlated error's
                ref_lla = src.gnss.lla[idx]
                fix_var = fix_scale * np.sum(src.gnss.pos_std[idx, :2] ** 2, axis=1) + fix_corr
                # ... and the run's lla is the IMU's: add the lever arm, turned to NED
                ks = np.clip(np.searchsorted(res.t, tf), 0, res.t.size - 1)
                ant = (dcm_from_quat(res.q_nb[ks]) @ np.asarray(run.config.lever_arm, dtype=float))[:, :2]
            else:
                tf = res.t[(res.t >= max(s, ref_truth.t[0])) & (res.t < min(s + d, ref_truth.t[-1]))]
                if tf.size == 0:
                    skipped += 1
                    continue
                ref_lla = _rows_at(tf, ref_truth.t, ref_truth.lla)
                fix_var = np.full(tf.size, truth_std**2)
                ant = np.zeros((tf.size, 2))  # the truth is the IMU's position
            ref = ref_lla[0]
            e = _horizontal(_rows_at(tf, res.t, res.lla), ref) + ant - _horizontal(ref_lla, ref)
            err = np.hypot(e[:, 0], e[:, 1])
            j = np.clip(np.searchsorted(res.cov_t, tf), 0, res.cov_t.size - 1)
            var = res.cov_diag[j, 0] + res.cov_diag[j, 1] + fix_var
            outs.append((float(s), float(d)))
            end.append(float(err[-1]))
            mx.append(float(err.max()))
            cont.append(bool(np.all(err <= 3.0 * np.sqrt(var))))
            nmax.append(float(np.max(err / np.sqrt(var))))
            nfix.append(int(tf.size))
            ref_var.append(float(fix_var[-1]))
            if src.odometer is not None:
                i0 = int(np.searchsorted(res.t, s))
                i1 = int(np.searchsorted(res.t, tf[-1]))
                C_nv = dcm_from_quat(res.q_nb[i0]) @ C_vb.T  # the vehicle's heading in the filter at i0
                p = _dead_reckoning(src, C_vb, res.gyro_bias[i0], psi0=math.atan2(C_nv[1, 0], C_nv[0, 0]),
                                    i0=i0, i1=i1)
                start = _horizontal(res.lla[i0:i0 + 1], ref)[0]
                dr.append(float(np.hypot(*(start + p[-1] + ant[-1] - _horizontal(ref_lla[-1:], ref)[0]))))
            else:
                dr.append(math.nan)
        if progress is not None:
            progress(k + 2, total)
    if not outs:
        raise InvalidInputError(f"{src.source}: no outage has a reference point ("
                                f"{'no good fix inside any outage' if ref_truth is None else 'the truth covers none'}"
                                "): give a truth that spans the outages, or a longer log")
    return LogOutageReport(outs, np.array(end), np.array(mx), np.array(cont, dtype=bool), np.array(dr),
                           np.array(nfix, dtype=np.int64), np.array(nmax),
                           {"converge_s": converge_s, "every_s": every_s, "length_s": length_s,
                            "shifts_s": list(shifts_s), "t0_s": t0, "faulty_fixes": int(np.sum(~good)),
                            "reference": "removed fixes" if ref_truth is None else "truth",
                            "reference_noise_m": math.sqrt(float(np.mean(ref_var))) if ref_var else 0.0,
                            "skipped_outages": skipped})
