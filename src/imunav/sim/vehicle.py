"""Land-vehicle trajectories (truth for GNSS/INS) and the vehicle's own sensors.

A drive is a list of manoeuvres: :func:`straight`, :func:`speed_change`,
:func:`turn`, :func:`stop`, :func:`hill` and, for rough terrain, :func:`bank` (a
side slope: roll) and :func:`bump`.  :func:`vehicle_trajectory` turns
it into a :class:`~imunav.sim.trajectory.Trajectory` on the WGS84 ellipsoid
(geodetic position, NED velocity, ``q_nb``, and the *exact* body rate
``ω_nb^b`` and NED acceleration ``v̇^n``), so that
:func:`~imunav.sim.error_model.simulate_imu` / :func:`~imunav.sim.trajectory.ideal_imu`
give the IMU a strapdown NED mechanization expects, with Earth rotation and
transport rate.

Vehicle model: the body x axis points along the velocity (no side slip, no
vertical body velocity: the non-holonomic constraint holds exactly), roll is
the side slope φ (zero without :func:`bank` / :func:`bump`), pitch is the road
grade γ and yaw the heading ψ::

    v^n = s (cos γ cos ψ, cos γ sin ψ, −sin γ),
    ω_nb^b = (φ̇ − ψ̇ sin γ, γ̇ cos φ + ψ̇ sin φ cos γ, −γ̇ sin φ + ψ̇ cos φ cos γ)

(ZYX Euler rates, Groves 2013 eq. 2.58 inverted; roll about the body x axis
leaves ``v^n`` unchanged).

Optionally (``slip_std``, ``idle_vibration_std`` of :func:`vehicle_trajectory`)
the body of a real car also moves sideways and vertically while it drives (side
slip, suspension) and vibrates at rest (engine idle): a zero-mean, band-limited
body velocity ``δv^b`` in closed form, added to ``v^n`` through ``C_nb`` with
its exact derivative, the attitude and body rate unchanged.  Then the
non-holonomic constraint and the zero-velocity update have in the truth the
white measurement noise their σ stands for.

Every manoeuvre shapes a rate (acceleration ṡ, yaw rate ψ̇, grade rate γ̇)
with Hann pulses ``A/T (1 − cos 2πu)``, ``u = (t − t0)/T``: rates, values and
their derivatives are closed-form and continuous, and the IMU signals have no
steps.  Geodetic position is integrated from ``v^n`` with Simpson's rule on
half-steps (``lat' = v_N/(R_N + h)``, ``lon' = v_E/((R_E + h) cos lat)``,
``h' = −v_D``; Groves 2013 eq. 2.111), error below 1e-12 rad at 100 Hz.

:func:`simulate_odometer` (wheel speed, with a lever arm and a scale factor)
and :func:`simulate_baro` (barometric height, with a Gauss–Markov bias) are
sampled from the same truth.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav import earth
from imunav.errors import InvalidInputError, ShapeError
from imunav.io.aiding import BaroData, OdometerData
from imunav.rotation import dcm_from_euler, dcm_from_quat, quat_from_euler
from imunav.sim.trajectory import Trajectory, body_rate_from_attitude
from imunav.units import DEG

__all__ = [
    "Maneuver",
    "straight",
    "speed_change",
    "turn",
    "stop",
    "hill",
    "bank",
    "bump",
    "vehicle_trajectory",
    "demo_drive",
    "OdometerData",
    "BaroData",
    "simulate_odometer",
    "simulate_baro",
    "gauss_markov_sequence",
    "wheel_slip_bursts",
]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Maneuver:
    """One manoeuvre of a drive (build it with :func:`straight`, :func:`turn`, ...).

    Parameters
    ----------
    kind : {"straight", "speed", "turn", "stop", "hill", "bank", "bump"}
        What the manoeuvre does.
    duration_s : float
        Length, s (> 0).
    to_speed : float
        Speed reached at the end, m/s (kind ``"speed"``).
    dheading : float
        Heading change, rad (kind ``"turn"``; positive turns right, towards east from north).
    grade : float
        Road grade reached, rad (kind ``"hill"``; positive climbs; ``|grade| < 45°``), or the bump's peak pitch
        (kind ``"bump"``).
    ramp_s : float
        Time to reach the grade (roll) and to come back, s (kinds ``"hill"`` and ``"bank"``; in
        ``(0, duration_s / 2]``).
    roll : float
        Side slope reached, rad (kind ``"bank"``; positive: right side down; ``|roll| < 30°``), or the bump's
        peak roll (kind ``"bump"``).

    Raises
    ------
    InvalidInputError
        If ``kind`` is unknown, ``duration_s`` is not a positive number, a value is not finite, or a
        hill's grade or ramp is out of range.
    """

    kind: str
    duration_s: float
    to_speed: float = 0.0
    dheading: float = 0.0
    grade: float = 0.0
    ramp_s: float = 0.0
    roll: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in ("straight", "speed", "turn", "stop", "hill", "bank", "bump"):
            raise InvalidInputError(f"Maneuver.kind {self.kind!r} is unknown; use straight, speed, turn, stop, hill, "
                                    "bank or bump")
        if not (math.isfinite(self.duration_s) and self.duration_s > 0):
            raise InvalidInputError(f"{self.kind}: duration_s must be a positive number of seconds; got {self.duration_s!r}")
        for name in ("to_speed", "dheading", "grade", "ramp_s", "roll"):
            if not math.isfinite(getattr(self, name)):
                raise InvalidInputError(f"{self.kind}: {name} must be finite; got {getattr(self, name)!r}")
        if self.kind == "hill":
            if abs(self.grade) >= math.radians(45):
                raise InvalidInputError(f"hill: grade {math.degrees(self.grade):.3g} deg is not a road; keep |grade| < 45 deg")
            if not (0 < self.ramp_s <= self.duration_s / 2):
                raise InvalidInputError(
                    f"hill: ramp_s must be in (0, duration_s/2] = (0, {self.duration_s / 2:g}] s; got {self.ramp_s!r}"
                )
        if self.kind in ("bank", "bump"):
            if abs(self.roll) >= math.radians(30) or abs(self.grade) >= math.radians(30):
                raise InvalidInputError(f"{self.kind}: roll and pitch must stay under 30 deg; got "
                                        f"{math.degrees(self.roll):.3g}, {math.degrees(self.grade):.3g} deg")
            if self.kind == "bank" and not (0 < self.ramp_s <= self.duration_s / 2):
                raise InvalidInputError(
                    f"bank: ramp_s must be in (0, duration_s/2] = (0, {self.duration_s / 2:g}] s; got {self.ramp_s!r}")


def straight(duration_s: float) -> Maneuver:
    """Constant speed and heading for ``duration_s`` seconds.

    Parameters
    ----------
    duration_s : float
        Length, s (> 0).

    Returns
    -------
    Maneuver
        A ``"straight"`` manoeuvre.
    """
    return Maneuver("straight", float(duration_s))


def speed_change(to_speed: float, duration_s: float) -> Maneuver:
    """Accelerate (or brake) smoothly to ``to_speed`` m/s over ``duration_s`` s.

    Peak acceleration is ``2 Δs / duration_s`` for a change Δs.

    Parameters
    ----------
    to_speed : float
        Speed at the end, m/s (>= 0; checked by :func:`vehicle_trajectory`).
    duration_s : float
        Length, s (> 0).

    Returns
    -------
    Maneuver
        A ``"speed"`` manoeuvre.
    """
    return Maneuver("speed", float(duration_s), to_speed=float(to_speed))


def turn(angle_deg: float, duration_s: float) -> Maneuver:
    """Change heading by ``angle_deg`` (positive: to the right) over ``duration_s`` s at the current speed.

    Peak yaw rate ``2 angle / duration_s``; lateral acceleration ``speed × yaw rate``.

    Parameters
    ----------
    angle_deg : float
        Heading change, degrees (positive: clockwise seen from above, to the right).
    duration_s : float
        Length, s (> 0).

    Returns
    -------
    Maneuver
        A ``"turn"`` manoeuvre (``dheading`` in rad).
    """
    return Maneuver("turn", float(duration_s), dheading=float(angle_deg) * DEG)


def stop(duration_s: float) -> Maneuver:
    """Stand still for ``duration_s`` s (the speed reached so far must be zero: brake first with
    :func:`speed_change`).

    Parameters
    ----------
    duration_s : float
        Length, s (> 0).

    Returns
    -------
    Maneuver
        A ``"stop"`` manoeuvre.
    """
    return Maneuver("stop", float(duration_s))


def hill(grade_deg: float, duration_s: float, ramp_s: float = 5.0) -> Maneuver:
    """Climb (``grade_deg`` > 0) or descend: the grade rises to ``grade_deg`` over ``ramp_s``,
    holds, and returns to level over the last ``ramp_s`` of ``duration_s``.

    Parameters
    ----------
    grade_deg : float
        Road grade (pitch) held on the hill, degrees (``|grade_deg| < 45``; positive climbs).
    duration_s : float
        Length of the whole manoeuvre, s (> 0).
    ramp_s : float
        Time to reach the grade, and to come back to level, s (in ``(0, duration_s / 2]``).

    Returns
    -------
    Maneuver
        A ``"hill"`` manoeuvre (``grade`` in rad).
    """
    return Maneuver("hill", float(duration_s), grade=float(grade_deg) * DEG, ramp_s=float(ramp_s))


def bank(roll_deg: float, duration_s: float, ramp_s: float = 3.0) -> Maneuver:
    """Drive across a side slope: the roll rises to ``roll_deg`` over ``ramp_s``, holds, and returns to level
    over the last ``ramp_s`` of ``duration_s`` (a cambered road, a field's slope; heading and speed unchanged).

    Parameters
    ----------
    roll_deg : float
        Roll held, degrees (``|roll_deg| < 30``; positive: the right side lower).
    duration_s : float
        Length of the whole manoeuvre, s (> 0).
    ramp_s : float
        Time to reach the roll, and to come back to level, s (in ``(0, duration_s / 2]``).

    Returns
    -------
    Maneuver
        A ``"bank"`` manoeuvre (``roll`` in rad).
    """
    return Maneuver("bank", float(duration_s), roll=float(roll_deg) * DEG, ramp_s=float(ramp_s))


def bump(pitch_deg: float, roll_deg: float = 0.0, duration_s: float = 1.0) -> Maneuver:
    """Drive over a bump: pitch (and roll, one wheel higher) swing to ``+peak``, through ``−peak`` and back to level
    in ``duration_s``, Hann-shaped rates (pulses of a quarter, a half and a quarter of the duration, areas
    ``+p, −2p, +p``): the vehicle rises and comes back to its height, a short, sharp attitude change that
    excites the IMU beyond the slow manoeuvres.

    Parameters
    ----------
    pitch_deg, roll_deg : float
        Peak pitch and roll, degrees (each ``< 30`` in size).
    duration_s : float
        Length, s (> 0).

    Returns
    -------
    Maneuver
        A ``"bump"`` manoeuvre (``grade``, ``roll`` in rad).
    """
    return Maneuver("bump", float(duration_s), grade=float(pitch_deg) * DEG, roll=float(roll_deg) * DEG)


# ---------------------------------------------------------------------------
# Hann pulses: rate A/T (1 - cos 2πu) on [t0, t0 + T], area A
# ---------------------------------------------------------------------------


@dataclass
class _Signal:
    """A signal x(t) whose rate is a sum of non-overlapping Hann pulses: x, ẋ, ẍ in closed form."""

    x0: float
    pulses: list[tuple[float, float, float]] = field(default_factory=list)  # (t0, T, area)

    def eval(self, t: Array) -> tuple[Array, Array, Array]:
        """x, ẋ, ẍ at the sorted times ``t``."""
        jump = np.zeros(t.size + 1)
        xd = np.zeros(t.size)
        xdd = np.zeros(t.size)
        x = np.zeros(t.size)
        for s, d, a in self.pulses:
            i0, i1 = np.searchsorted(t, [s, s + d], side="right")
            jump[i1] += a  # the full area from the end of the pulse on
            u = (t[i0:i1] - s) / d
            w = 2.0 * np.pi * u
            x[i0:i1] += a * (u - np.sin(w) / (2.0 * np.pi))
            xd[i0:i1] += a / d * (1.0 - np.cos(w))
            xdd[i0:i1] += a / d * (2.0 * np.pi / d) * np.sin(w)
        return self.x0 + x + np.cumsum(jump)[:-1], xd, xdd


def _plan(maneuvers: Sequence[Maneuver], speed0: float) -> tuple[_Signal, _Signal, _Signal, _Signal, float]:
    speed = _Signal(speed0)
    heading = _Signal(0.0)
    grade = _Signal(0.0)
    roll = _Signal(0.0)
    t = 0.0
    s_now = speed0
    for i, m in enumerate(maneuvers):
        if not isinstance(m, Maneuver):
            raise InvalidInputError(f"maneuvers[{i}] is a {type(m).__name__}; build it with straight(), turn(), ...")
        if m.kind == "speed":
            if m.to_speed < 0:
                raise InvalidInputError(f"maneuvers[{i}]: speed_change to {m.to_speed} m/s; a vehicle speed is >= 0 "
                                        "(this generator drives forwards only)")
            speed.pulses.append((t, m.duration_s, m.to_speed - s_now))
            s_now = m.to_speed
        elif m.kind == "turn":
            heading.pulses.append((t, m.duration_s, m.dheading))
        elif m.kind == "stop" and s_now != 0.0:
            raise InvalidInputError(f"maneuvers[{i}]: stop at {s_now} m/s; brake first with speed_change(0, duration_s)")
        elif m.kind == "hill":
            if s_now == 0.0:
                raise InvalidInputError(f"maneuvers[{i}]: a hill at standstill cannot change height; drive first")
            grade.pulses.append((t, m.ramp_s, m.grade))
            grade.pulses.append((t + m.duration_s - m.ramp_s, m.ramp_s, -m.grade))
        elif m.kind in ("bank", "bump"):
            if s_now == 0.0:
                raise InvalidInputError(f"maneuvers[{i}]: a {m.kind} at standstill; drive first")
            if m.kind == "bank":
                roll.pulses += [(t, m.ramp_s, m.roll), (t + m.duration_s - m.ramp_s, m.ramp_s, -m.roll)]
            else:
                q = m.duration_s / 4.0
                for sig, peak in ((grade, m.grade), (roll, m.roll)):
                    if peak != 0.0:
                        sig.pulses += [(t, q, peak), (t + q, 2.0 * q, -2.0 * peak), (t + 3.0 * q, q, peak)]
        t += m.duration_s
    return speed, heading, grade, roll, t


def _simpson_cumulative(f: Array, dt: float) -> Array:
    """Cumulative integral on a grid of step ``dt`` from values on the half-step grid (``f[::2]`` on the grid)."""
    inc = dt / 6.0 * (f[0:-1:2] + 4.0 * f[1::2] + f[2::2])
    return np.concatenate([[0.0], np.cumsum(inc)])


def _half_grid(x: Array, xd: Array, dt: float) -> Array:
    """Values on the half-step grid from grid values and derivatives (cubic Hermite at the mid points)."""
    out = np.empty(2 * x.size - 1)
    out[0::2] = x
    out[1::2] = 0.5 * (x[:-1] + x[1:]) + dt / 8.0 * (xd[:-1] - xd[1:])
    return out


#: sinusoids per axis of the body-velocity perturbation, and the Hann ramp (s) between the moving and resting σ
_N_TONES = 32
_REST_RAMP_S = 0.5


def _rest_weight(maneuvers: Sequence[Maneuver], total: float) -> _Signal:
    """r(t): 1 during the stops, 0 in motion, Hann steps of up to ``_REST_RAMP_S`` just outside each stop."""
    spans: list[list[float]] = []
    t = 0.0
    for m in maneuvers:
        if m.kind == "stop":
            if spans and spans[-1][1] == t:
                spans[-1][1] = t + m.duration_s
            else:
                spans.append([t, t + m.duration_s])
        t += m.duration_s
    r = _Signal(0.0)
    for i, (a, b) in enumerate(spans):
        before = a - (spans[i - 1][1] if i else 0.0)
        after = (spans[i + 1][0] if i + 1 < len(spans) else total) - b
        if a <= 0.0:
            r.x0 = 1.0
        else:
            d = min(_REST_RAMP_S, before)
            r.pulses.append((a - d, d, 1.0))
        if after > 0.0:
            d = min(_REST_RAMP_S, after)
            r.pulses.append((b, d, -1.0))
    return r


def _tones(n: int, h: float, band: tuple[float, float], g: np.random.Generator) -> tuple[Array, Array]:
    """Three unit-variance sums of ``_N_TONES`` sinusoids (one per column) and their derivatives at ``t = k h``,
    ``k < n``.  With ``t = T_b + τ_i`` (blocks of L samples), ``cos(ω t + φ) = cos(ω T_b + φ) cos ω τ_i −
    sin(ω T_b + φ) sin ω τ_i``: the sum over the sinusoids is a matrix product, exact to rounding."""
    lo, hi = band
    m = _N_TONES
    f = lo + (np.arange(m)[:, None] + g.random((m, 3))) * ((hi - lo) / m)  # one frequency per sub-band
    phase = 2.0 * np.pi * g.random((m, 3))
    w = 2.0 * np.pi * f
    a = math.sqrt(2.0 / m)
    L = max(1, math.isqrt(n))
    nb = -(-n // L)
    tb = np.arange(nb) * (L * h)
    ti = np.arange(L) * h
    u = np.empty((nb * L, 3))
    ud = np.empty((nb * L, 3))
    for j in range(3):
        A = np.multiply.outer(tb, w[:, j]) + phase[:, j]
        B = np.multiply.outer(ti, w[:, j])
        ca, sa, cb, sb = a * np.cos(A), a * np.sin(A), np.cos(B), np.sin(B)
        u[:, j] = (ca @ cb.T - sa @ sb.T).ravel()
        ud[:, j] = -((sa * w[:, j]) @ cb.T + (ca * w[:, j]) @ sb.T).ravel()
    return u[:n], ud[:n]


def _body_velocity_perturbation(maneuvers: Sequence[Maneuver], total: float, th: Array, h: float, slip: Array,
                                idle: float, band: tuple[float, float], rng: Any) -> tuple[Array, Array]:
    """δv^b and its derivative at ``th = k h``: amplitude ``A(t) = σ_move + (σ_rest − σ_move) r(t)`` times the
    tones."""
    g = np.random.default_rng(rng)
    u, ud = _tones(th.size, h, band, g)
    r, rd, _ = _rest_weight(maneuvers, total).eval(th)
    s_move = np.array([0.0, slip[0], slip[1]])
    ds = np.full(3, idle) - s_move
    amp = s_move + np.multiply.outer(r, ds)
    return amp * u, np.multiply.outer(rd, ds) * u + amp * ud


def _check_perturbation(slip_std: ArrayLike, idle_vibration_std: float, band_hz: ArrayLike,
                        fs: float) -> tuple[Array, float, tuple[float, float]]:
    slip = np.asarray(slip_std, dtype=float)
    if slip.shape != (2,) or not np.all(np.isfinite(slip)) or np.any(slip < 0):
        raise InvalidInputError(f"slip_std must be (lateral, vertical) sigmas >= 0 m/s, finite; got {slip_std!r}")
    if not (math.isfinite(idle_vibration_std) and idle_vibration_std >= 0):
        raise InvalidInputError(f"idle_vibration_std must be a sigma >= 0 m/s, finite; got {idle_vibration_std!r}")
    band = np.asarray(band_hz, dtype=float)
    on = bool(np.any(slip > 0) or idle_vibration_std > 0)  # the band matters only with a perturbation
    if on and (band.shape != (2,) or not np.all(np.isfinite(band)) or not (0 < band[0] < band[1] < fs / 2)):
        raise InvalidInputError(f"vibration_band_hz must be (low, high) Hz with 0 < low < high < fs/2 = {fs / 2:g} "
                                f"(the samples must resolve it); got {band_hz!r}")
    return slip, float(idle_vibration_std), ((float(band[0]), float(band[1])) if on else (0.0, 0.0))


def vehicle_trajectory(
    maneuvers: Sequence[Maneuver],
    *,
    fs: float = 200.0,
    origin_lla: ArrayLike = (30.0 * DEG, 114.0 * DEG, 20.0),
    heading0_deg: float = 0.0,
    speed0: float = 0.0,
    t0: float = 0.0,
    slip_std: ArrayLike = (0.0, 0.0),
    idle_vibration_std: float = 0.0,
    vibration_band_hz: ArrayLike = (0.5, 10.5),
    rng: Any = None,
    turn_slip: float = 0.0,
) -> Trajectory:
    """Truth trajectory of a drive, sampled at the IMU rate.

    Parameters
    ----------
    maneuvers : sequence of :class:`Maneuver`
        The drive, in order (:func:`straight`, :func:`speed_change`, :func:`turn`, :func:`stop`, :func:`hill`).
    fs : float
        Sample rate, Hz.
    origin_lla : (3,)
        Start position (lat rad, lon rad, h m).
    heading0_deg : float
        Initial heading, degrees clockwise from north.
    speed0 : float
        Initial speed, m/s.
    t0 : float
        Time of the first sample, s (e.g. a GPS second of week).
    slip_std : array_like, shape (2,)
        σ of the body's lateral (side slip) and vertical (suspension) velocity while the vehicle moves, m/s
        (>= 0; default none: the non-holonomic constraint holds exactly).
    idle_vibration_std : float
        σ of the body's velocity on each axis during the :func:`stop` manoeuvres (engine idle), m/s (>= 0;
        default none: the vehicle stands exactly still).  Only ``stop`` manoeuvres idle: a drive that starts at
        rest with a ``speed_change`` has the in-motion ``slip_std`` until it moves — start it with a ``stop``.
    vibration_band_hz : array_like, shape (2,)
        Frequency band (low, high) of both perturbations, Hz (``0 < low < high < fs / 2``; checked when a
        perturbation is on).
    rng : numpy.random.Generator or int, optional
        Random generator or seed.
        Draws the perturbations' frequencies and phases (unused when both are off).
    turn_slip : float
        Side slip in turns, rad of body slip angle per m/s² of lateral acceleration (>= 0; default none): the
        body's lateral velocity ``δv_y = −k s · s ψ̇`` (the velocity points outside the turn, the nose inside),
        the steady-state cornering of the linear single-track (bicycle) model, whose body slip angle at speed
        grows with the lateral acceleration (Gillespie, *Fundamentals of Vehicle Dynamics*, SAE 1992, ch. 6;
        about 0.002-0.005 rad per m/s² for a car; a skid-steered robot slides far more).  Unlike
        ``slip_std`` it is not white: the non-holonomic constraint is biased through every turn.

    Returns
    -------
    Trajectory
        With ``pos_lla``, ``vel_ned``, ``q_nb``, exact ``omega_nb_b`` and ``accel_ned``.

    Raises
    ------
    InvalidInputError
        If ``maneuvers`` is empty or holds something else than a :class:`Maneuver`, ``fs`` or ``speed0``
        is not valid, the origin latitude is beyond ±85° (likely degrees), the drive reaches a
        negative speed, stops while moving, or climbs a hill (bank, bump) at standstill, or a perturbation
        σ, the band or ``turn_slip`` is out of range.
    ShapeError
        If ``origin_lla`` is not a finite 3-vector.

    Notes
    -----
    Body-velocity perturbations (on when a σ is > 0).  The attitude and body rate stay those of the
    manoeuvres; the body velocity gains ``δv^b(t) = A(t) ∘ u(t)``::

        v^n = C_nb (s e_x + δv^b),      v̇^n = C_nb (ω_nb^b × (s e_x + δv^b) + ṡ e_x + δv̇^b),
        A(t) = σ_move + (σ_rest − σ_move) r(t),   σ_move = (0, σ_lat, σ_vert),   σ_rest = σ_idle (1, 1, 1),

    with ``r(t)`` 1 during the stops, 0 in motion, and Hann steps of 0.5 s just outside each stop (in the
    last 0.5 s of the braking and the first 0.5 s of driving away, where the speed is a few mm/s).  Each
    component of ``u`` is ``√(2/M) Σ_m cos(2π f_m t + φ_m)`` with M = 32 sinusoids, one frequency drawn
    uniformly in each of M equal sub-bands of the band and uniform phases: zero mean, unit time-averaged
    variance, no DC part (at rest the position stays within ``√(2M) σ / (2π f_low)`` of where it stood,
    with an rms of ``σ / (2π √(f_low f_high))``),
    and closed-form derivatives, so that ``vel_ned``, ``accel_ned`` and ``omega_nb_b`` stay exact,
    :func:`~imunav.sim.trajectory.ideal_imu` stays exact and the position integrates the perturbed
    ``v^n``.  Its autocorrelation is ``ρ(τ) = (sin 2π f_high τ − sin 2π f_low τ) / (2π (f_high − f_low) τ)``
    on average over the draws: with the default band of 10 Hz width, ``ρ(k 0.1 s) = 0`` for every k ≥ 1, so
    that values 0.1 s or 0.2 s apart are uncorrelated (0.2 s is the default covariance step of
    :class:`~imunav.ins.gins.GinsFilter`, where NHC and ZUPT are applied; a barometer or magnetometer at
    10 Hz adds steps 0.1 s apart): folded at 10 Hz the frequencies cover the samples' Nyquist band evenly,
    the sampled sequence is white.  The stratified frequencies leave at the first lags a residual of the
    order of ``2π k / M / √(2M)`` (≈ 0.02 at k = 1).  Such a perturbation is then a white measurement noise
    of σ ``σ_lat``, ``σ_vert`` for the non-holonomic constraint and ``σ_idle`` for the ZUPT, as the filter
    models it, and the filter's error, made of earlier samples, is uncorrelated with the current one: no
    bias on their NIS.  Choose ``fs`` well above ``f_high``: an IMU sampled at ``fs`` and integrated by
    the mechanization's fourth-order rule (:func:`imunav.ins.strapdown.coning_sculling_increments`) sees a
    sinusoid of frequency f scaled by about ``1 − 11 (2π f / fs)⁴ / 720`` (−0.13 % at 2.6 Hz and 30 Hz; the
    trapezoid's ``1 − (2π f / fs)² / 12`` is −2.5 % there).
    """
    if not maneuvers:
        raise InvalidInputError("vehicle_trajectory: give at least one manoeuvre, e.g. [straight(60)]")
    if not (math.isfinite(fs) and fs > 0):
        raise InvalidInputError(f"fs must be a positive sample rate in Hz; got {fs!r}")
    if not (math.isfinite(speed0) and speed0 >= 0):
        raise InvalidInputError(f"speed0 must be a speed >= 0 m/s; got {speed0!r}")
    o = np.asarray(origin_lla, dtype=float)
    if o.shape != (3,) or not np.all(np.isfinite(o)):
        raise ShapeError(f"origin_lla must be (lat rad, lon rad, h m); got {origin_lla!r}")
    if abs(o[0]) > math.radians(85):
        raise InvalidInputError(f"origin latitude {math.degrees(o[0]):.4g} deg: give it in radians, within +-85 deg")
    slip, idle, band = _check_perturbation(slip_std, idle_vibration_std, vibration_band_hz, float(fs))
    if not (math.isfinite(turn_slip) and turn_slip >= 0):
        raise InvalidInputError(f"turn_slip must be >= 0 rad per m/s^2, finite; got {turn_slip!r}")
    speed, heading, grade, roll, total = _plan(maneuvers, float(speed0))
    heading.x0 = float(heading0_deg) * DEG
    dt = 1.0 / float(fs)
    n = int(math.floor(total * fs + 1e-9)) + 1
    th = np.arange(2 * n - 1) * (dt / 2.0)  # grid and mid points
    s, sd, _ = speed.eval(th)
    psi, psid, psidd = heading.eval(th)
    gam, gamd, _ = grade.eval(th)
    rolled = bool(roll.pulses)
    phi, phid, _ = roll.eval(th)
    if np.any(s < -1e-9):
        raise InvalidInputError("the drive reaches a negative speed; check the speed_change targets")
    s = np.maximum(s, 0.0)
    cg, sg, cp, sp = np.cos(gam), np.sin(gam), np.cos(psi), np.sin(psi)
    vel = np.stack([s * cg * cp, s * cg * sp, -s * sg], axis=1)
    acc = np.stack([
        sd * cg * cp - s * (sg * gamd * cp + cg * sp * psid),
        sd * cg * sp - s * (sg * gamd * sp - cg * cp * psid),
        -sd * sg - s * cg * gamd,
    ], axis=1)
    if rolled:
        cf, sf = np.cos(phi), np.sin(phi)
        w_all = np.stack([phid - psid * sg, gamd * cf + psid * sf * cg, -gamd * sf + psid * cf * cg], axis=1)
    else:
        w_all = np.stack([-psid * sg, gamd, psid * cg], axis=1)
    if np.any(slip > 0) or idle > 0 or turn_slip > 0:
        if np.any(slip > 0) or idle > 0:
            dvb, dvb_dot = _body_velocity_perturbation(maneuvers, total, th, dt / 2.0, slip, idle, band, rng)
        else:
            dvb, dvb_dot = np.zeros((th.size, 3)), np.zeros((th.size, 3))
        if turn_slip > 0:  # δv_y = −k s² ψ̇ and its derivative
            dvb[:, 1] -= turn_slip * s * s * psid
            dvb_dot[:, 1] -= turn_slip * (2.0 * s * sd * psid + s * s * psidd)
        if rolled:
            c_nb = dcm_from_euler(phi, gam, psi)
        else:
            c_nb = np.stack([np.stack([cg * cp, cg * sp, -sg], axis=1), np.stack([-sp, cp, np.zeros_like(sp)], axis=1),
                             np.stack([sg * cp, sg * sp, cg], axis=1)], axis=2)  # columns: body x, y, z in NED
        w_h = w_all
        vel = vel + np.einsum("nij,nj->ni", c_nb, dvb)
        acc = acc + np.einsum("nij,nj->ni", c_nb, np.cross(w_h, dvb) + dvb_dot)
    # geodetic position: h first, then latitude by fixed-point iteration (R_N depends weakly on lat), then lon
    h = o[2] + _simpson_cumulative(-vel[:, 2], dt)
    h_half = _half_grid(h, -vel[0::2, 2], dt)
    lat = np.full(th.size, o[0])
    for _ in range(4):
        rn, _re = earth.radii(lat)
        f = vel[:, 0] / (rn + h_half)
        lat = _half_grid(o[0] + _simpson_cumulative(f, dt), f[0::2], dt)
    rn, re = earth.radii(lat)
    lon_rate = vel[:, 1] / ((re + h_half) * np.cos(lat))
    lon = o[1] + _simpson_cumulative(lon_rate, dt)
    g = slice(0, None, 2)
    lla = np.stack([lat[g], lon, h], axis=1)
    q = quat_from_euler(phi[g] if rolled else np.zeros(n), gam[g], psi[g])
    w = w_all[g]
    t = float(t0) + np.arange(n) * dt
    return Trajectory(t, q, vel_ned=vel[g], pos_lla=lla, omega_nb_b=w, accel_ned=acc[g])


def demo_drive(duration_s: float = 600.0, *, speed: float = 15.0) -> list[Maneuver]:
    """A drive of about ``duration_s`` seconds: start from rest, then repeated blocks of straights,
    left and right turns, a hill, a speed change and a stop (the scenario of the tests and benchmarks).

    Parameters
    ----------
    duration_s : float
        Approximate length of the drive, s (>= 120); it ends with a 15 s brake to rest.
    speed : float
        Cruise speed, m/s (the blocks also drive at 1.5 × ``speed``).

    Returns
    -------
    list of Maneuver
        The drive, for :func:`vehicle_trajectory`.

    Raises
    ------
    InvalidInputError
        If ``duration_s`` is below 120 s or not finite.
    """
    if not (math.isfinite(duration_s) and duration_s >= 120):
        raise InvalidInputError(f"demo_drive: duration_s must be at least 120 s; got {duration_s!r}")
    m: list[Maneuver] = [stop(20.0), speed_change(speed, 15.0)]
    t = 35.0
    block = [
        straight(20.0), turn(90.0, 10.0), straight(15.0), hill(3.0, 30.0, 6.0), turn(-45.0, 8.0),
        speed_change(1.5 * speed, 12.0), straight(10.0), turn(-135.0, 14.0), speed_change(speed, 10.0),
        turn(30.0, 6.0), speed_change(0.0, 12.0), stop(8.0), speed_change(speed, 12.0),
    ]
    blen = sum(b.duration_s for b in block)
    while t + blen + 30.0 <= duration_s:
        m.extend(block)
        t += blen
    rest = duration_s - t - 15.0
    if rest > 0:
        m.append(straight(rest))
    m.append(speed_change(0.0, 15.0))
    return m


# ---------------------------------------------------------------------------
# vehicle sensors: odometer and barometer
# ---------------------------------------------------------------------------


def gauss_markov_sequence(t: Array, sigma: ArrayLike, tau: float, rng: np.random.Generator) -> Array:
    """Stationary first-order Gauss–Markov samples at times ``t`` (exact discretisation).

    ``x_k = e^{-Δt/T} x_{k-1} + σ √(1 − e^{-2Δt/T}) w_k``, ``x_0 ~ N(0, σ²)``, ``w_k ~ N(0, 1)``
    (Brown & Hwang, *Introduction to Random Signals and Applied Kalman Filtering*, 4th ed., Wiley
    2012, first-order Gauss–Markov process); ``tau = inf`` gives a random constant.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Sample times, s (increasing; the steps need not be equal).
    sigma : float or array_like, shape (m,)
        Stationary standard deviation, one value or one per column (finite, >= 0), in the unit of the
        output.
    tau : float
        Correlation time T, s (> 0; ``inf`` allowed).
    rng : numpy.random.Generator
        Source of the normal draws.

    Returns
    -------
    numpy.ndarray, shape (N,) or (N, m)
        The samples: (N,) for a scalar ``sigma``, else one column per entry of ``sigma``.

    Raises
    ------
    InvalidInputError
        If ``sigma`` is negative or not finite, or ``tau`` is not > 0.
    """
    sig = np.atleast_1d(np.asarray(sigma, dtype=float))
    if np.any(sig < 0) or not np.all(np.isfinite(sig)):
        raise InvalidInputError(f"Gauss-Markov sigma must be finite and >= 0; got {sigma!r}")
    if not (tau > 0):
        raise InvalidInputError(f"Gauss-Markov correlation time must be > 0 s; got {tau!r}")
    n = t.size
    w = rng.standard_normal((n, sig.size))
    out = np.empty((n, sig.size))
    out[0] = sig * w[0]
    phi = np.exp(-np.diff(t) / tau)
    c = np.sqrt(1.0 - phi * phi)
    for k in range(1, n):
        out[k] = phi[k - 1] * out[k - 1] + sig * c[k - 1] * w[k]
    return out[:, 0] if np.ndim(sigma) == 0 else out


def _lever(x: ArrayLike, name: str) -> Array:
    a = np.asarray(x, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ShapeError(f"{name} must be a finite 3-vector in body FRD metres; got {x!r}")
    return a


def omega_eb_b(truth: Trajectory) -> Array:
    """Body rate relative to the Earth, ``ω_eb^b = ω_nb^b + C_bn ω_en^n`` (rad/s), per sample.

    ``ω_en^n`` is the transport rate of the NED frame over the ellipsoid (Groves, *Principles of GNSS,
    Inertial, and Multisensor Integrated Navigation Systems*, 2nd ed., Artech House 2013, §5.4);
    ``ω_nb^b`` is the trajectory's own, or differentiated from ``q_nb`` when it has none.

    Parameters
    ----------
    truth : Trajectory
        With ``pos_lla`` (lat rad, lon rad, h m), ``vel_ned`` (m/s) and ``q_nb`` (body FRD -> NED).

    Returns
    -------
    numpy.ndarray, shape (N, 3)
        ``ω_eb^b``, body FRD, rad/s.

    Raises
    ------
    InvalidInputError
        If ``truth`` has no ``pos_lla`` or no ``vel_ned``.
    """
    if truth.pos_lla is None or truth.vel_ned is None:
        raise InvalidInputError("the truth trajectory needs pos_lla and vel_ned (use vehicle_trajectory)")
    w_nb = truth.omega_nb_b
    if w_nb is None:
        w_nb = body_rate_from_attitude(truth.t, truth.q_nb)
    w_en = earth.transport_rate_ned(truth.pos_lla[:, 0], truth.pos_lla[:, 2], truth.vel_ned)
    return w_nb + np.einsum("nji,nj->ni", dcm_from_quat(truth.q_nb), w_en)


def lever_arm_velocity_body(truth: Trajectory, lever_b: ArrayLike) -> Array:
    """Body-frame velocity (m/s) of the point at ``lever_b`` (body FRD, m): ``C_bn v^n + ω_eb^b × l``.

    Parameters
    ----------
    truth : Trajectory
        With ``pos_lla``, ``vel_ned`` (m/s) and ``q_nb`` (body FRD -> NED), e.g. from
        :func:`vehicle_trajectory`.
    lever_b : array_like, shape (3,)
        The point, from the IMU, in body FRD axes, m.

    Returns
    -------
    numpy.ndarray, shape (N, 3)
        Its velocity relative to the Earth, resolved in body FRD axes, m/s.
    """
    lb = _lever(lever_b, "lever_b")
    v_b = np.einsum("nji,nj->ni", dcm_from_quat(truth.q_nb), truth.vel_ned)
    return v_b + np.cross(omega_eb_b(truth), lb)



def _decimate(truth: Trajectory, rate_hz: float | None) -> Array:
    if rate_hz is None:
        return np.arange(truth.n)
    if not (math.isfinite(rate_hz) and 0 < rate_hz <= truth.fs + 1e-9):
        raise InvalidInputError(f"rate_hz must be in (0, {truth.fs:g}] Hz (the truth rate); got {rate_hz!r}")
    step = max(1, int(round(truth.fs / rate_hz)))
    return np.arange(0, truth.n, step)


def simulate_odometer(
    truth: Trajectory,
    *,
    lever_arm: ArrayLike = (0.0, 0.0, 0.0),
    scale_factor: float = 0.0,
    noise_std: float = 0.0,
    rate_hz: float | None = None,
    rng: Any = None,
    latency_s: float = 0.0,
    scale_change: float = 0.0,
    scale_change_tau_s: float = 300.0,
    turn_overread: float = 0.0,
    resolution: float = 0.0,
    terrain_scale_std: float = 0.0,
    terrain_scale_tau_s: float = 20.0,
    slip_std: float = 0.0,
    slip_every_s: float = 30.0,
    slip_s: float = 2.0,
) -> OdometerData:
    """Wheel speed: forward body velocity at the wheel, ``(1 + k) (C_bn v^n + ω_eb^b × l)_x + w``.

    What real wheels add (each off by default; the odometer's errors in Groves 2013, §6.3): the reading
    stamped ``t`` holds the speed at ``t − latency_s`` (CAN and driver delays, linearly interpolated between
    truth samples); the scale drifts as the tyre warms and its pressure
    and load change, ``(1 + k)(1 + Δ (1 − e^{−t/T}))`` with ``Δ = scale_change`` (a relative radius change
    −Δ) and ``T = scale_change_tau_s``; the wheels slip and the track scrubs in turns (skid steering,
    differential slip), reading ``(1 + c |ω_z|)`` times more with ``c = turn_overread`` s/rad; and the value
    is quantised, ``q round(x / q)`` with ``q = resolution`` (an encoder's counts over the sample interval, a
    CAN signal's least bit); and the ground changes under the wheels, the scale times ``(1 + g(t))`` with ``g``
    a first-order Gauss–Markov process of σ ``terrain_scale_std`` and correlation time ``terrain_scale_tau_s``
    (grass, gravel and asphalt give a skid-steered robot effective wheel radii that differ by 5-15 %: the
    slip ratios measured by Mandow et al. 2007, "Experimental kinematics for wheeled skid-steer mobile
    robots", IROS, and the reason Clearpath's Husky driver scales its track width by 1.5-1.9); and the wheels spin
    or lock for a while, a burst of ``slip_s`` seconds, starting at the instants of a Poisson process of mean
    interval ``slip_every_s``, in which the reading is off by a constant drawn from ``N(0, slip_std²)`` (on the
    real Jackal bag of ``shared/data/ros_bags`` the wheels read 1.98 m/s for 3 s while the IMU shows the body
    decelerating at 1-1.6 m/s², then 0.12 m/s for 2 s while the body still moves; the wheel speed there changes
    twice as fast as the body's: a skid-steer robot on loose ground, driven by a joystick's steps).

    With the body-velocity perturbations of :func:`vehicle_trajectory`, the side slip and suspension velocity
    are perpendicular to the body x axis: in motion the reading is the forward speed as without them.  At rest
    it is the body's fore-aft idle velocity at the wheel (a sensor of the body's forward velocity; a real wheel
    encoder would read 0 there).  The GNSS/INS filter does not use the odometer while ``static`` says the
    vehicle stands still: the ZUPT holds that velocity then.

    Parameters
    ----------
    truth : Trajectory
        The truth, from :func:`vehicle_trajectory`.
    lever_arm : array_like, shape (3,)
        Wheel contact point from the IMU, body FRD, m.
    scale_factor : float
        k, the odometer scale-factor error (dimensionless, e.g. 0.005).
    noise_std : float
        White-noise σ of each sample, m/s (>= 0).
    rate_hz : float, optional
        Output rate, Hz, at most the truth rate (default: every truth sample).
    rng : numpy.random.Generator or int, optional
        Random generator or seed.
    latency_s : float
        Age of each reading at its stamp, s (>= 0; the first readings hold the first truth sample's speed).
    scale_change : float
        Δ, the relative scale change reached after a few ``scale_change_tau_s`` (finite, > −1).
    scale_change_tau_s : float
        Its time constant T, s (> 0).
    turn_overread : float
        c, the over-reading per rad/s of yaw rate, s/rad (>= 0).
    resolution : float
        q, the quantum of the readings, m/s (>= 0; 0: none).
    terrain_scale_std : float
        σ of the terrain's Gauss–Markov scale variation ``g`` (dimensionless, >= 0; 0: none).
    terrain_scale_tau_s : float
        Its correlation time, s (> 0).
    slip_std : float
        σ of the reading's error during a burst of wheel spin or lock, m/s (>= 0; 0: none).
    slip_every_s : float
        Mean interval between the bursts' starts, s (> 0).
    slip_s : float
        Length of each burst, s (> 0).

    Returns
    -------
    OdometerData
        The speeds, with the simulated errors in ``meta``.

    Raises
    ------
    InvalidInputError
        If ``noise_std``, ``latency_s``, ``turn_overread``, ``resolution``, ``terrain_scale_std`` or ``slip_std``
        is negative or not finite, ``scale_factor`` is not finite, ``scale_change`` is not above −1 or
        ``scale_change_tau_s``, ``terrain_scale_tau_s``, ``slip_every_s`` or ``slip_s`` is not > 0.
    """
    if not (math.isfinite(noise_std) and noise_std >= 0) or not math.isfinite(scale_factor):
        raise InvalidInputError(f"noise_std must be >= 0 m/s and scale_factor finite; got {noise_std!r}, {scale_factor!r}")
    for name, x in (("latency_s", latency_s), ("turn_overread", turn_overread), ("resolution", resolution),
                    ("terrain_scale_std", terrain_scale_std), ("slip_std", slip_std)):
        if not (math.isfinite(x) and x >= 0):
            raise InvalidInputError(f"simulate_odometer: {name} must be >= 0, finite; got {x!r}")
    if not (math.isfinite(scale_change) and scale_change > -1.0 and scale_change_tau_s > 0):
        raise InvalidInputError(f"simulate_odometer: scale_change must be > -1 and scale_change_tau_s > 0 s; got "
                                f"{scale_change!r}, {scale_change_tau_s!r}")
    for name, x in (("terrain_scale_tau_s", terrain_scale_tau_s), ("slip_every_s", slip_every_s), ("slip_s", slip_s)):
        if not (math.isfinite(x) and x > 0):
            raise InvalidInputError(f"simulate_odometer: {name} must be > 0 s; got {x!r}")
    g = np.random.default_rng(rng)
    idx = _decimate(truth, rate_hz)
    t = truth.t[idx].copy()
    meta = {"lever_arm": list(map(float, _lever(lever_arm, "lever_arm"))), "scale_factor": float(scale_factor),
            "noise_std": float(noise_std)}
    if (latency_s == 0 and scale_change == 0 and turn_overread == 0 and resolution == 0 and terrain_scale_std == 0
            and slip_std == 0):
        v = lever_arm_velocity_body(truth, lever_arm)[idx, 0]
        speed = (1.0 + scale_factor) * v + noise_std * g.standard_normal(idx.size)
        return OdometerData(t, speed, meta)
    ts = t - latency_s  # the instants the readings hold
    v = np.interp(ts, truth.t, lever_arm_velocity_body(truth, lever_arm)[:, 0])
    wz = np.interp(ts, truth.t, omega_eb_b(truth)[:, 2])
    k = (1.0 + scale_factor) * (1.0 + scale_change * -np.expm1(-(t - truth.t[0]) / scale_change_tau_s))
    speed = k * (1.0 + turn_overread * np.abs(wz)) * v + noise_std * g.standard_normal(idx.size)
    if terrain_scale_std > 0:  # drawn after the white noise: a log without it keeps its noise
        speed = speed * (1.0 + gauss_markov_sequence(t, terrain_scale_std, terrain_scale_tau_s, g))
    if slip_std > 0:  # drawn after the others too
        speed = speed + wheel_slip_bursts(t, slip_std, slip_every_s, slip_s, g)
    if resolution > 0:
        speed = resolution * np.round(speed / resolution)
    meta.update({"latency_s": float(latency_s), "scale_change": float(scale_change),
                 "scale_change_tau_s": float(scale_change_tau_s), "turn_overread": float(turn_overread),
                 "resolution": float(resolution), "terrain_scale_std": float(terrain_scale_std),
                 "terrain_scale_tau_s": float(terrain_scale_tau_s), "slip_std": float(slip_std),
                 "slip_every_s": float(slip_every_s), "slip_s": float(slip_s)})
    return OdometerData(t, speed, meta)


def wheel_slip_bursts(t: Array, std: float, every_s: float, length_s: float, rng: Any = None) -> Array:
    """The wheel speed's error of bursts of spin or lock: zero, but for ``length_s`` seconds after each instant of
    a Poisson process of mean interval ``every_s`` over ``t``, a constant drawn from ``N(0, std²)`` (overlapping
    bursts add).

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Stamps of the readings, s, increasing.
    std : float
        σ of a burst's error, m/s (>= 0).
    every_s : float
        Mean interval between the bursts' starts, s (> 0).
    length_s : float
        Length of each burst, s (> 0).
    rng : numpy.random.Generator or int, optional
        Random generator or seed.

    Returns
    -------
    numpy.ndarray, shape (N,)
        The error of each reading, m/s.
    """
    g = np.random.default_rng(rng)
    span = float(t[-1] - t[0]) if t.size else 0.0
    starts = t[0] + np.sort(g.uniform(0.0, span, g.poisson(span / every_s))) if t.size else np.zeros(0)
    err = np.zeros(t.size)
    for s0, e in zip(starts, std * g.standard_normal(starts.size)):
        err[(t >= s0) & (t < s0 + length_s)] += e
    return err


def simulate_baro(
    truth: Trajectory,
    *,
    noise_std: float = 0.5,
    bias_std: float = 2.0,
    bias_tau: float = 600.0,
    rate_hz: float | None = 10.0,
    rng: Any = None,
) -> BaroData:
    """Barometric height: ``h + b + w`` with a Gauss–Markov bias ``b`` (σ ``bias_std`` m, correlation time
    ``bias_tau`` s; weather and the geoid–ellipsoid offset) and white noise ``noise_std`` m.

    Parameters
    ----------
    truth : Trajectory
        The truth, with ``pos_lla`` (from :func:`vehicle_trajectory`).
    noise_std : float
        White-noise σ of each sample, m (>= 0).
    bias_std : float
        Stationary σ of the bias, m (>= 0).
    bias_tau : float
        Correlation time of the bias, s (> 0; ``inf``: a constant bias).
    rate_hz : float, optional
        Output rate, Hz, at most the truth rate (None: every truth sample).
    rng : numpy.random.Generator or int, optional
        Random generator or seed.

    Returns
    -------
    BaroData
        The heights, with the simulated errors in ``meta``.

    Raises
    ------
    InvalidInputError
        If ``truth`` has no ``pos_lla`` or ``noise_std`` is negative or not finite.
    """
    if truth.pos_lla is None:
        raise InvalidInputError("the truth trajectory needs pos_lla (use vehicle_trajectory)")
    if not (math.isfinite(noise_std) and noise_std >= 0):
        raise InvalidInputError(f"noise_std must be >= 0 m; got {noise_std!r}")
    g = np.random.default_rng(rng)
    idx = _decimate(truth, rate_hz)
    t = truth.t[idx]
    b = gauss_markov_sequence(t, float(bias_std), float(bias_tau), g)
    hgt = truth.pos_lla[idx, 2] + b + noise_std * g.standard_normal(idx.size)
    return BaroData(t.copy(), hgt, {"noise_std": float(noise_std), "bias_std": float(bias_std),
                                    "bias_tau": float(bias_tau), "bias": b.tolist()[:1]})
