"""What real vehicle logs have and a clean simulation lacks: the faults of :func:`imunav.sim.robot_log.simulate_vehicle_log`.

A filter tuned on white GNSS noise, an IMU sampled on a perfect clock and wheels that read the true speed is
confident on real logs where it should not be (issue 33: on a real robot bag the GNSS NIS is 8.9 for 3 degrees
of freedom and no 60 s outage ends inside its predicted 3σ).  :class:`LogFaults` switches on, one argument each
and every one off by default, what real drives add:

GNSS (:func:`gnss_faults`, applied to the fixes of :func:`~imunav.sim.gnss.simulate_gnss`, whose Gauss–Markov
term gives the correlated error):

* **errors correlated in time**: a first-order Gauss–Markov position error per axis (σ_c, correlation time T
  of 10-100 s) beside the white noise.  Multipath and the residual ionospheric and tropospheric delays of a
  single-frequency receiver change over tens of seconds to minutes as the satellites and the vehicle move
  (Groves 2013, *Principles of GNSS, Inertial, and Multisensor Integrated Navigation Systems*, 2nd ed., ch. 9,
  the range error sources and how slowly they change; Brown & Hwang 2012, *Introduction to Random Signals and
  Applied Kalman Filtering*, 4th ed., model such slowly varying errors as Gauss–Markov processes).  The fixes report ``σ = √(σ_w² + σ_c²)``: the right marginal
  σ, but a filter that takes the fixes as independent counts the same error many times;
* **a reported σ wrong by a factor**: the fixes' ``pos_std`` is the true σ times ``gnss_std_factor`` (< 1:
  understated, as receivers' accuracy estimates from their own residuals are under multipath; > 1: overstated).
  Receivers' σ (NMEA GST, u-blox hAcc) come from a model of the receiver, not from the error met (Groves
  2013, ch. 9: multipath and non-line-of-sight reception bias the solution in ways its residuals do not show);
* **jumps and slow drifts at rest**: while the vehicle stands (under trees, beside a building) the position
  wanders at a constant velocity drawn per stop (σ ``gnss_rest_drift_mps`` per horizontal axis) and, with
  probability ``gnss_rest_jump_prob`` per stop, jumps by ``gnss_rest_jump_m`` (half to once that, in a uniform
  direction) at a uniform instant of the stop; both relax with time constant ``gnss_rest_relax_s`` once it
  drives away (a static receiver's multipath error changes only as the satellites move, a moving one's
  averages out over the vehicle's motion: Groves 2013, ch. 9);
* **fixes that repeat**: after a fix, with probability ``gnss_repeat_prob``, the next 1 to ``gnss_repeat_max``
  epochs carry the same position and σ under new stamps (a driver that republishes the last solution when the
  receiver sends no new one, e.g. on each NMEA sentence of the same epoch).

IMU (:func:`warmup_temperature`, :func:`imu_stamps`): misalignment, scale and g-sensitivity are those of the
error model (:mod:`imunav.sim.presets` ``consumer_mems`` holds an MPU-6050's); the sensor warms by
``imu_temp_rise_c`` with time constant ``imu_temp_tau_s`` after power-on, moving its biases and scales through
the model's temperature polynomials; the stamps carry a white jitter of σ ``imu_stamp_jitter_s`` (a host that
stamps messages on arrival through USB or a serial link).

Wheels (:func:`~imunav.sim.vehicle.vehicle_trajectory` ``turn_slip``, :func:`~imunav.sim.vehicle.simulate_odometer`):
side slip in turns, over-reading in turns, a tyre radius that changes, quantised and late readings, and bursts of
wheel spin or lock (:func:`~imunav.sim.vehicle.wheel_slip_bursts`: a skid-steer robot on loose ground; the real
Jackal bag's wheels read 1.98 m/s for 3 s while its IMU shows the body decelerating).

Every realised fault is recorded (the ``faults`` dict of :class:`~imunav.sim.robot_log.RobotLogTruth`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav import earth
from imunav.errors import InvalidInputError
from imunav.io.gnss import GnssData

__all__ = ["LogFaults", "gnss_faults", "imu_stamps", "warmup_temperature"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class LogFaults:
    """The faults of a real log (module docstring for each one's source), every one off by default.

    Parameters
    ----------
    gnss_corr_sigma_m : tuple of float
        σ_c of the Gauss–Markov position error north, east, down, m (>= 0).
    gnss_corr_tau_s : float
        Its correlation time T, s (> 0; 10-100 s for multipath and atmosphere).
    gnss_std_factor : float
        Reported σ / true σ of the fixes (> 0; 1: honest).
    gnss_rest_drift_mps : float
        σ of the drift velocity of the fixes per stop, each horizontal axis, m/s (>= 0).
    gnss_rest_jump_m : float
        Size of a jump at rest, m (>= 0; each jump half to once this).
    gnss_rest_jump_prob : float
        Probability of a jump per stop (0-1).
    gnss_rest_relax_s : float
        Time constant with which the offset built at rest fades once the vehicle moves, s (> 0).
    gnss_repeat_prob : float
        Probability that a fix is followed by repeats of itself (0 <= p < 1).
    gnss_repeat_max : int
        Most repeats after a fix (>= 1; the number is uniform in 1..max).
    imu_temp_rise_c : float
        Warm-up of the IMU after power-on, °C (finite; 0: a constant temperature, the model's reference).
    imu_temp_tau_s : float
        Its time constant, s (> 0).
    imu_stamp_jitter_s : float
        σ of the white error of each IMU stamp, s (>= 0; kept under 0.4 of the sample interval).
    turn_slip : float
        Side slip in turns, rad per m/s² of lateral acceleration (:func:`~imunav.sim.vehicle.vehicle_trajectory`).
    odometer_turn_overread : float
        Odometer over-reading per rad/s of yaw rate, s/rad (:func:`~imunav.sim.vehicle.simulate_odometer`).
    odometer_scale_change : float
        Relative change of the odometer scale reached as the tyres warm (> −1; a radius change of about −Δ).
    odometer_scale_tau_s : float
        Its time constant, s (> 0).
    odometer_resolution : float
        Quantum of the speed readings, m/s (>= 0).
    odometer_latency_s : float
        Age of each speed reading at its stamp, s (>= 0).
    odometer_terrain_std : float
        σ of the odometer scale's variation with the ground under the wheels, a Gauss–Markov process
        (dimensionless, >= 0; :func:`~imunav.sim.vehicle.simulate_odometer`'s ``terrain_scale_std``).
    odometer_terrain_tau_s : float
        Its correlation time, s (> 0).
    odometer_slip_std : float
        σ of the speed reading's error during a burst of wheel spin or lock, m/s (>= 0; 0: none;
        :func:`~imunav.sim.vehicle.wheel_slip_bursts`).
    odometer_slip_every_s : float
        Mean interval between the bursts' starts, s (> 0).
    odometer_slip_s : float
        Length of each burst, s (> 0).

    Raises
    ------
    InvalidInputError
        If a value is out of its range.
    """

    gnss_corr_sigma_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    gnss_corr_tau_s: float = 30.0
    gnss_std_factor: float = 1.0
    gnss_rest_drift_mps: float = 0.0
    gnss_rest_jump_m: float = 0.0
    gnss_rest_jump_prob: float = 0.5
    gnss_rest_relax_s: float = 5.0
    gnss_repeat_prob: float = 0.0
    gnss_repeat_max: int = 3
    imu_temp_rise_c: float = 0.0
    imu_temp_tau_s: float = 600.0
    imu_stamp_jitter_s: float = 0.0
    turn_slip: float = 0.0
    odometer_turn_overread: float = 0.0
    odometer_scale_change: float = 0.0
    odometer_scale_tau_s: float = 300.0
    odometer_resolution: float = 0.0
    odometer_latency_s: float = 0.0
    odometer_terrain_std: float = 0.0
    odometer_terrain_tau_s: float = 20.0
    odometer_slip_std: float = 0.0
    odometer_slip_every_s: float = 30.0
    odometer_slip_s: float = 2.0

    def __post_init__(self) -> None:
        c = np.asarray(self.gnss_corr_sigma_m, dtype=float)
        if c.shape != (3,) or not np.all(np.isfinite(c)) or np.any(c < 0):
            raise InvalidInputError(f"LogFaults.gnss_corr_sigma_m must be 3 sigmas >= 0 m (N, E, D); got "
                                    f"{self.gnss_corr_sigma_m!r}")
        positive = ("gnss_corr_tau_s", "gnss_std_factor", "gnss_rest_relax_s", "imu_temp_tau_s",
                    "odometer_scale_tau_s", "odometer_terrain_tau_s", "odometer_slip_every_s", "odometer_slip_s")
        nonneg = ("gnss_rest_drift_mps", "gnss_rest_jump_m", "imu_stamp_jitter_s", "turn_slip",
                  "odometer_turn_overread", "odometer_resolution", "odometer_latency_s", "odometer_terrain_std",
                  "odometer_slip_std")
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name == "gnss_corr_sigma_m":
                continue
            if not (isinstance(v, (int, float)) and math.isfinite(v)):
                raise InvalidInputError(f"LogFaults.{f.name} must be a finite number; got {v!r}")
            if (f.name in positive and v <= 0) or (f.name in nonneg and v < 0):
                raise InvalidInputError(f"LogFaults.{f.name} must be {'> 0' if f.name in positive else '>= 0'}; "
                                        f"got {v!r}")
        if not (0 <= self.gnss_rest_jump_prob <= 1 and 0 <= self.gnss_repeat_prob < 1):
            raise InvalidInputError(f"LogFaults: gnss_rest_jump_prob must be in [0, 1] and gnss_repeat_prob in [0, 1);"
                                    f" got {self.gnss_rest_jump_prob!r}, {self.gnss_repeat_prob!r}")
        if int(self.gnss_repeat_max) != self.gnss_repeat_max or self.gnss_repeat_max < 1:
            raise InvalidInputError(f"LogFaults.gnss_repeat_max must be an integer >= 1; got {self.gnss_repeat_max!r}")
        if self.odometer_scale_change <= -1:
            raise InvalidInputError(f"LogFaults.odometer_scale_change must be > -1; got {self.odometer_scale_change!r}")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict of the switches.

        Returns
        -------
        dict
            Field name -> value.
        """
        return {f.name: (list(getattr(self, f.name)) if f.name == "gnss_corr_sigma_m" else getattr(self, f.name))
                for f in fields(self)}


def warmup_temperature(t: ArrayLike, rise_c: float, tau_s: float, start_c: float = 25.0) -> Array:
    """The IMU's temperature after power-on, ``T(t) = T₀ + ΔT (1 − e^{−(t − t₀)/τ})`` (a first-order thermal
    lag of the board's self-heating, the shape of a MEMS IMU's warm-up drift).

    Parameters
    ----------
    t : array_like, shape (N,)
        Times, s (``t₀ = t[0]``).
    rise_c : float
        ΔT, °C.
    tau_s : float
        τ, s (> 0).
    start_c : float
        T₀, °C.

    Returns
    -------
    numpy.ndarray, shape (N,)
        Temperatures, °C.
    """
    tt = np.asarray(t, dtype=float)
    return start_c + rise_c * -np.expm1(-(tt - tt[0]) / tau_s)


def imu_stamps(t: ArrayLike, jitter_s: float, rng: np.random.Generator) -> Array:
    """Stamps of samples taken at ``t`` with a white jitter: ``t_k + e_k``, ``e_k ~ N(0, σ²)`` cut at ±0.4 of
    the smallest sample interval (the stamps stay increasing), ``e_0 = e_{N−1} = 0`` (the log spans the drive: its
    origin is the first sample, and the aids up to the last sample lie inside it).

    Parameters
    ----------
    t : array_like, shape (N,)
        True sample times, s (increasing).
    jitter_s : float
        σ, s (>= 0).
    rng : numpy.random.Generator
        Source of the draws.

    Returns
    -------
    numpy.ndarray, shape (N,)
        The stamps, s.
    """
    tt = np.asarray(t, dtype=float)
    if jitter_s == 0 or tt.size < 2:
        return tt.copy()
    cut = 0.4 * float(np.min(np.diff(tt)))
    e = np.clip(jitter_s * rng.standard_normal(tt.size), -cut, cut)
    e[0] = e[-1] = 0.0
    return tt + e


def _rest_runs(moving: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """``[i0, i1)`` index runs where ``moving`` is False."""
    still = np.concatenate([[False], ~moving, [False]]).astype(np.int8)
    d = np.diff(still)
    return list(zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist()))


def gnss_faults(fixes: GnssData, speed: ArrayLike, faults: LogFaults,
                rng: np.random.Generator) -> tuple[GnssData, dict[str, Any]]:
    """The rest offsets, repeats and the misreported σ of :class:`LogFaults` on simulated fixes.

    Rest: the fixes where ``speed`` is under 0.02 m/s form the stops; in each, the offset
    ``o(t) = d (t − t_s) + J H(t − t_J)`` (drift velocity ``d``, a jump ``J`` at ``t_J`` with probability
    ``gnss_rest_jump_prob``), after it ``o(t_e) e^{−(t − t_e)/τ_r}`` until the next stop.  Repeats: a fix
    ``k`` whose draw falls under ``gnss_repeat_prob`` is copied (position and σ) onto the next 1..max fixes.
    Then ``pos_std`` times ``gnss_std_factor``.

    Parameters
    ----------
    fixes : GnssData
        The fixes with their true σ (:func:`~imunav.sim.gnss.simulate_gnss`).
    speed : array_like, shape (M,)
        The vehicle's true speed at each fix, m/s.
    faults : LogFaults
        The switches.
    rng : numpy.random.Generator
        Source of the draws.

    Returns
    -------
    GnssData
        The fixes as logged.
    dict
        ``gnss_rest_offset_ned`` (M, 3), m; ``gnss_repeated`` (M,) bool; ``gnss_true_std`` (M, 3), m: the σ of
        each logged fix's own noise (the repeated fix's).
    """
    n = fixes.n
    sp = np.asarray(speed, dtype=float)
    off = np.zeros((n, 3))
    if faults.gnss_rest_drift_mps > 0 or faults.gnss_rest_jump_m > 0:
        runs = _rest_runs(sp >= 0.02)
        t = fixes.t
        for r, (i0, i1) in enumerate(runs):
            d = faults.gnss_rest_drift_mps * rng.standard_normal(2)
            off[i0:i1, :2] = np.outer(t[i0:i1] - t[i0], d)
            if rng.random() < faults.gnss_rest_jump_prob and faults.gnss_rest_jump_m > 0:
                j = int(rng.integers(i0, i1))
                a = rng.uniform(0.0, 2.0 * math.pi)
                size = faults.gnss_rest_jump_m * rng.uniform(0.5, 1.0)
                off[j:i1, 0] += size * math.cos(a)
                off[j:i1, 1] += size * math.sin(a)
            end = runs[r + 1][0] if r + 1 < len(runs) else n
            if i1 < end:
                off[i1:end] = np.outer(np.exp(-(t[i1:end] - t[i1 - 1]) / faults.gnss_rest_relax_s), off[i1 - 1])
    lla = fixes.lla + earth.ned_to_dlla(off, fixes.lla) if np.any(off) else fixes.lla.copy()
    std = fixes.pos_std.copy()
    repeated = np.zeros(n, dtype=bool)
    if faults.gnss_repeat_prob > 0:
        start = rng.random(n) < faults.gnss_repeat_prob
        count = rng.integers(1, int(faults.gnss_repeat_max) + 1, size=n)
        k = 0
        while k < n:
            if start[k]:
                m = min(int(count[k]), n - 1 - k)
                lla[k + 1:k + 1 + m] = lla[k]
                std[k + 1:k + 1 + m] = std[k]
                repeated[k + 1:k + 1 + m] = True
                k += m + 1
            else:
                k += 1
    meta = {**fixes.meta, "faults": faults.to_dict()}
    out = GnssData(fixes.t.copy(), lla, std * faults.gnss_std_factor, fixes.vel_ned, fixes.vel_std, meta)
    return out, {"gnss_rest_offset_ned": off, "gnss_repeated": repeated, "gnss_true_std": std}
