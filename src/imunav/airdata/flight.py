"""Flight simulation for air-data / Doppler integration (truth + sensors, seeded).

Two families:

* **Thesis aircraft** (O. Akgün, *Integration of an air data system and a Doppler radar via Kalman
  filtering* (in Turkish), MSc thesis, Istanbul Technical University, 2002, §5.3.2, 6.2d): the
  "Charlie A" 12-state linear model of D. McLean, *Automatic Flight Control Systems*, Prentice Hall,
  1990, ``x = [u, w, q, θ, β, p, r, φ, ψ, X, Y, Z]``
  (u, w perturbations about U₀ = 250 m/s) with u = 0, Euler-discretised at
  T = 1 ms.  The discrete matrix printed in the thesis is garbled; the
  continuous matrix here uses the coarse derivatives it implies
  (Z_u = −0.1, Z_w = −0.3, M_q = −0.4, Y_v = −1, L'_β = −1, L'_p = −5,
  L'_r = 0.4, N'_β = 0.6, N'_r = −0.1) and the physically correct gravity and
  kinematic terms (−g cos γ₀ in the u row, g/U₀ in the β row, φ̇ = p,
  ψ̇ = r at γ₀ = 0).  Body velocity ``V = (U₀ + u, U₀ β, w)`` (kinematic
  rows), position its running sum; φ₀ = 5° (the thesis's "5" read as degrees).
  The true velocity cancels in the filter measurement.
* **General flights** (:func:`simulate_flight`, not in the thesis): cruise,
  turns (coordinated 90° turns at half standard rate) and manoeuvring profiles (turns,
  climbs, descents, speed changes) with a constant NED wind plus Dryden
  turbulence (MIL-F-8785C forms, L_u = 2L_v = 2L_w = 533 m above 2000 ft),
  each sensor at its own rate: air data (static / total pressure, TAT,
  α/β vanes → ADS body velocity through :mod:`imunav.airdata`), a beam-level
  Doppler radar (:func:`imunav.airdata.doppler.simulate_doppler`) and an
  attitude reference.

Wind convention: ``V_G = V_A + W``.  The aircraft flies its commanded air
velocity relative to the mean wind (smooth ground track); gusts change the
air-relative velocity the air-data system sees, ``V_A = V_G − (W̄ + gust)``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import cholesky, solve_discrete_lyapunov
from scipy.signal import lfilter, ss2tf, tf2ss

from imunav.airdata.airdata import air_data, aoa_sideslip, pitot_ratio, tas_to_body, total_temperature
from imunav.airdata.doppler import DopplerErrors, janus_beams, simulate_doppler
from imunav.atmosphere import G0, isa
from imunav.errors import InvalidInputError
from imunav.filters._core import van_loan
from imunav.results import Result
from imunav.rotation import dcm_from_euler

__all__ = [
    "CHARLIE_STATES",
    "charlie_model",
    "LinearAircraftFlight",
    "simulate_linear_aircraft",
    "dryden_gusts",
    "TURBULENCE_SIGMA",
    "FlightConfig",
    "FlightData",
    "simulate_flight",
]

Array = NDArray[np.float64]
CHARLIE_STATES = ("u", "w", "q", "theta", "beta", "p", "r", "phi", "psi", "X", "Y", "Z")


def charlie_model(dt: float = 0.001, u0: float = 250.0) -> tuple[Array, Array]:
    """Continuous and Euler-discrete (``I + A T``) 12×12 matrices of the thesis aircraft (module docstring).

    Parameters
    ----------
    dt : float
        Step T, s, > 0.
    u0 : float
        Trim airspeed U₀, m/s, > 0.

    Returns
    -------
    A : numpy.ndarray, shape (12, 12)
        Continuous state matrix (SI: m/s, rad, rad/s, m).
    F : numpy.ndarray, shape (12, 12)
        Discrete transition matrix ``I + A T``.

    Raises
    ------
    InvalidInputError
        If ``dt`` or ``u0`` is not positive.
    """
    if not dt > 0 or not u0 > 0:
        raise InvalidInputError(f"dt and u0 must be > 0, got {dt}, {u0}")
    A = np.zeros((12, 12))
    u, w, q, th, be, p, r, ph, ps, X, Y, Z = range(12)
    A[u, u], A[u, th] = 0.0, -G0
    A[w, u], A[w, w], A[w, q] = -0.1, -0.3, u0
    A[q, q] = -0.4
    A[th, q] = 1.0
    A[be, be], A[be, r], A[be, ph] = -1.0, -1.0, G0 / u0
    A[p, be], A[p, p], A[p, r] = -1.0, -5.0, 0.4
    A[r, be], A[r, r] = 0.6, -0.1
    A[ph, p] = 1.0
    A[ps, r] = 1.0
    A[X, u] = 1.0
    A[Y, be] = u0
    A[Z, w] = 1.0
    return A, np.eye(12) + A * dt


@dataclass(frozen=True)
class LinearAircraftFlight(Result):
    """A run of the linear aircraft model (:func:`simulate_linear_aircraft`).

    Attributes
    ----------
    t : numpy.ndarray, shape (N,)
        Time, s.
    states : numpy.ndarray, shape (N, 12)
        ``[u, w, q, θ, β, p, r, φ, ψ, X, Y, Z]`` (m/s, rad, rad/s, m).
    velocity : numpy.ndarray, shape (N, 3)
        Body velocity ``(U₀ + u, U₀ β, w)``, m/s.
    position : numpy.ndarray, shape (N, 3)
        Position, m.
    """

    t: Array
    states: Array
    velocity: Array
    position: Array


def simulate_linear_aircraft(n_steps: int = 500, dt: float = 0.001, u0: float = 250.0,
                             beta0: float = 0.1, phi0_deg: float = 5.0, psi0: float = 0.1,
                             x0: float = 0.1, y0: float = 0.1, altitude: float = 12200.0) -> LinearAircraftFlight:
    """Free response (u = 0) of the linear aircraft model (the Charlie model) from the initial state of Akgün 2002,
    §5.3.2.

    Parameters
    ----------
    n_steps : int
        Number of steps.
    dt : float
        Step, s.
    u0 : float
        Trim airspeed, m/s.
    beta0 : float
        Initial sideslip, rad.
    phi0_deg : float
        Initial roll angle, degrees.
    psi0 : float
        Initial heading, rad.
    x0, y0 : float
        Initial horizontal position, m.
    altitude : float
        Initial altitude, m.

    Returns
    -------
    LinearAircraftFlight
        States, body velocity and position at every step.

    Raises
    ------
    InvalidInputError
        If ``n_steps < 1`` (or ``dt``, ``u0`` are not positive).
    """
    if n_steps < 1:
        raise InvalidInputError(f"n_steps must be >= 1, got {n_steps}")
    _, Ad = charlie_model(dt, u0)
    s = np.zeros(12)
    s[4], s[7], s[8], s[9], s[10], s[11] = beta0, np.deg2rad(phi0_deg), psi0, x0, y0, altitude
    S = np.empty((n_steps, 12))
    for k in range(n_steps):
        s = Ad @ s
        S[k] = s
    vel = np.stack([u0 + S[:, 0], u0 * S[:, 4], S[:, 1]], axis=1)
    pos = np.array([x0, y0, 0.0]) + dt * np.cumsum(vel, axis=0)
    return LinearAircraftFlight(dt * np.arange(1, n_steps + 1), S, vel, pos)


# ----------------------------------------------------------------------------------------------
# Dryden turbulence

TURBULENCE_SIGMA = {"none": 0.0, "light": 1.5, "moderate": 3.0, "severe": 6.5}  # m/s, high altitude


def _shaping_discrete(num: Array, den: Array, dt: float) -> tuple[Array, Array, Array]:
    """Discrete (Φ, Γ-cov, C) of a strictly proper / proper SISO shaping filter, unit-variance output."""

    A, B, C, D = tf2ss(num, den)
    Phi, Qd = van_loan(np.ascontiguousarray(A, dtype=np.float64), np.ascontiguousarray(B @ B.T, dtype=np.float64),
                       float(dt))
    if np.any(np.abs(D) > 0):
        raise InvalidInputError("shaping filter must be strictly proper")
    P = solve_discrete_lyapunov(Phi, Qd)
    var = float((C @ P @ C.T).item())
    return Phi, Qd, C / np.sqrt(var)


def dryden_gusts(n: int, dt: float, airspeed: float, sigma: float | tuple[float, float, float],
                 length_u: float = 533.0, rng: np.random.Generator | int | None = None) -> Array:
    """Dryden gust velocities along (longitudinal, lateral, vertical) axes, m/s.

    u: ``H(s) ∝ 1/(1 + τ_u s)``; v, w: ``H(s) ∝ (1 + √3 τ s)/(1 + τ s)²`` with
    ``τ = L/V``, L_v = L_w = L_u/2 (MIL-F-8785C, 1980); each output scaled to the
    requested standard deviation exactly (stationary start).

    Parameters
    ----------
    n : int
        Number of samples.
    dt : float
        Step, s.
    airspeed : float
        True airspeed V, m/s, > 0.
    sigma : float or tuple of float
        Gust standard deviation, m/s: one for all axes or (u, v, w).
    length_u : float
        Longitudinal scale length L_u, m.
    rng : numpy.random.Generator or int, optional
        Random generator or seed.

    Returns
    -------
    numpy.ndarray, shape (n, 3)
        Gust velocities, m/s.

    Raises
    ------
    InvalidInputError
        If a parameter is not positive (``sigma`` >= 0).
    """

    sig = np.broadcast_to(np.asarray(sigma, dtype=np.float64), (3,))
    if np.any(sig < 0) or not airspeed > 0 or not length_u > 0 or not dt > 0:
        raise InvalidInputError("sigma must be >= 0 and airspeed, length_u, dt > 0")
    gen = np.random.default_rng(rng)
    out = np.zeros((n, 3))
    for i, (L, num_fn) in enumerate(((length_u, None), (length_u / 2, 1), (length_u / 2, 1))):
        if sig[i] == 0:
            continue
        tau = L / airspeed
        if num_fn is None:
            Phi, Qd, C = _shaping_discrete(np.array([1.0]), np.array([tau, 1.0]), dt)
        else:
            Phi, Qd, C = _shaping_discrete(np.array([np.sqrt(3) * tau, 1.0]), np.array([tau**2, 2 * tau, 1.0]), dt)
        m = Phi.shape[0]
        Lq = cholesky(Qd + 1e-15 * np.eye(m), lower=True)
        x0 = cholesky(solve_discrete_lyapunov(Phi, Qd) + 1e-15 * np.eye(m), lower=True) @ gen.standard_normal(m)
        e = gen.standard_normal((n, m))
        # y_k = C x_k, x_k = Φ x_{k−1} + Lq e_k: linear filters per noise input, plus the free response of x0
        y = np.zeros(n)
        for j in range(m):
            b, a = ss2tf(Phi, Lq[:, j:j + 1], C, np.zeros((1, 1)))
            b = np.atleast_1d(b[0])
            y += lfilter(np.concatenate([b[1:], [0.0]]) if b[0] == 0 else b, a, e[:, j])
        xk = x0.copy()
        free = np.empty(min(n, int(40 * tau / dt) + 1))
        for k in range(free.size):  # the free response decays with τ = L/V
            xk = Phi @ xk
            free[k] = (C @ xk).item()
        y[:free.size] += free
        out[:, i] = sig[i] * y
    return out


# ----------------------------------------------------------------------------------------------
# general flights


@dataclass(frozen=True)
class FlightConfig(Result):
    """A simulated flight (SI; angles in degrees where named so).

    Attributes
    ----------
    profile : str
        "cruise", "turns" (alternating 90° turns at 1.5°/s) or "manoeuvre" (turns + climbs/descents + speed
        changes).
    duration : float
        Flight length, s.
    tas : float
        True airspeed, m/s.
    altitude : float
        Initial altitude, m.
    heading_deg : float
        Initial heading, degrees.
    wind_ned : tuple of float
        Constant mean wind (velocity of the air mass, m/s, NED).
    turbulence : str
        "none", "light", "moderate", "severe" (Dryden σ 0/1.5/3/6.5 m/s).
    rate_truth, rate_ads, rate_doppler : float
        Hz (truth must be a multiple of the sensor rates).
    ps_noise_std, qc_noise_std, tat_noise_std, alpha_noise_std_deg, beta_noise_std_deg : float
        Air-data system noise: static and impact pressure (Pa), total air temperature (K), angles (deg).
    alpha_trim_deg : float
        Trim angle of attack, degrees.
    n_beams : int
        Doppler beams (3 or 4).
    depression_deg : float
        Doppler beam depression, degrees.
    doppler : DopplerErrors
        Beam-level error model.
    over_water : tuple of (float, float)
        ``[(t0, t1), ...]`` intervals over water, s.
    attitude_noise_std_deg : float
        Attitude-reference noise (per Euler angle), degrees.
    """

    profile: str = "turns"
    duration: float = 600.0
    tas: float = 200.0
    altitude: float = 10000.0
    heading_deg: float = 0.0
    wind_ned: tuple[float, float, float] = (8.0, -12.0, 0.0)
    turbulence: str = "light"
    rate_truth: float = 100.0
    rate_ads: float = 50.0
    rate_doppler: float = 10.0
    ps_noise_std: float = 10.0
    qc_noise_std: float = 10.0
    tat_noise_std: float = 0.25
    alpha_noise_std_deg: float = 0.1
    beta_noise_std_deg: float = 0.1
    alpha_trim_deg: float = 2.0
    n_beams: int = 4
    depression_deg: float = 65.0
    doppler: DopplerErrors = field(default_factory=lambda: DopplerErrors(noise=0.1, scale=0.0))
    over_water: tuple[tuple[float, float], ...] = ()
    attitude_noise_std_deg: float = 0.0

    def __post_init__(self) -> None:
        if self.profile not in ("cruise", "turns", "manoeuvre"):
            raise InvalidInputError(f"profile must be cruise, turns or manoeuvre, got {self.profile!r}")
        if self.turbulence not in TURBULENCE_SIGMA:
            raise InvalidInputError(f"turbulence must be one of {list(TURBULENCE_SIGMA)}, got {self.turbulence!r}")
        if not (self.duration > 0 and self.tas > 30 and self.rate_truth > 0):
            raise InvalidInputError("duration must be > 0, tas > 30 m/s, rates > 0")
        for name in ("duration", "tas", "altitude", "rate_truth", "rate_ads", "rate_doppler"):
            v = getattr(self, name)
            if not np.isfinite(v) or (name != "altitude" and v <= 0):
                raise InvalidInputError(f"{name} = {v}: must be a finite number" + ("" if name == "altitude" else " > 0")
                                        + " (--rate-ads / --rate-doppler are in Hz)")
        for name in ("rate_ads", "rate_doppler"):
            ratio = self.rate_truth / getattr(self, name)
            if abs(ratio - round(ratio)) > 1e-9 or ratio < 1:
                raise InvalidInputError(f"rate_truth ({self.rate_truth} Hz) must be an integer multiple of "
                                        f"{name} ({getattr(self, name)} Hz)")


@dataclass(frozen=True)
class FlightData(Result):
    """Truth and sensor outputs of :func:`simulate_flight` (SI, angles in rad).

    Attributes
    ----------
    t : numpy.ndarray, shape (N,)
        Truth epochs (``rate_truth``), s.
    position_ned, velocity_ned : numpy.ndarray, shape (N, 3)
        Position (m) and ground velocity (m/s), NED.
    wind_ned : numpy.ndarray, shape (N, 3)
        Wind (mean + gust), m/s, NED.
    euler : numpy.ndarray, shape (N, 3)
        Roll, pitch, yaw, rad.
    v_air_body : numpy.ndarray, shape (N, 3)
        Air-relative velocity in body axes (FRD), m/s.
    tas : numpy.ndarray, shape (N,)
        True airspeed, m/s.
    altitude : numpy.ndarray, shape (N,)
        Altitude, m.
    t_ads : numpy.ndarray
        Air-data epochs (``rate_ads``), s.
    p_static, p_total : numpy.ndarray
        Measured static and total pressure, Pa.
    tat : numpy.ndarray
        Measured total air temperature, K.
    alpha, beta : numpy.ndarray
        Measured angle of attack and sideslip, rad.
    tas_ads : numpy.ndarray
        True airspeed from the air-data computer, m/s.
    v_ads_body : numpy.ndarray
        Air-data velocity in body axes, m/s.
    euler_ads : numpy.ndarray
        Attitude reference at the air-data epochs, rad.
    t_doppler : numpy.ndarray
        Doppler epochs (``rate_doppler``), s.
    v_doppler_body : numpy.ndarray
        Doppler ground velocity in body axes, m/s.
    beam_velocity : numpy.ndarray
        Doppler beam velocities, m/s.
    euler_doppler : numpy.ndarray
        Attitude reference at the Doppler epochs, rad.
    over_water : numpy.ndarray of bool
        Doppler epochs over water.
    config : FlightConfig
        The configuration simulated.
    """

    t: Array
    position_ned: Array
    velocity_ned: Array
    wind_ned: Array
    euler: Array
    v_air_body: Array
    tas: Array
    altitude: Array
    t_ads: Array
    p_static: Array
    p_total: Array
    tat: Array
    alpha: Array
    beta: Array
    tas_ads: Array
    v_ads_body: Array
    euler_ads: Array
    t_doppler: Array
    v_doppler_body: Array
    beam_velocity: Array
    euler_doppler: Array
    over_water: Array
    config: FlightConfig

    def C_nb(self, which: str = "doppler") -> Array:
        """Attitude DCMs at the ADS or Doppler epochs (from the attitude reference), or of the truth.

        Parameters
        ----------
        which : {"doppler", "ads", "truth"}
            Epochs (the truth's attitude for ``"truth"``).

        Returns
        -------
        numpy.ndarray, shape (N, 3, 3)
            ``C_nb``, body (FRD) to NED.
        """
        e = {"doppler": self.euler_doppler, "ads": self.euler_ads, "truth": self.euler}[which]
        return dcm_from_euler(e)


def _profiles(cfg: FlightConfig, t: Array) -> tuple[Array, Array, Array]:
    """Commanded (heading rate rad/s, flight-path angle rad, TAS m/s) on the truth grid."""
    n = t.size
    psidot = np.zeros(n)
    gamma = np.zeros(n)
    V = np.full(n, cfg.tas)
    std = np.deg2rad(3.0)  # standard-rate turn
    if cfg.profile in ("turns", "manoeuvre"):
        # 90° turn at half standard rate (1.5°/s, 60 s) every 120 s, alternating direction,
        # smoothed entry/exit (5 s ramps)
        ph = np.mod(t, 120.0)
        sgn = np.where(np.mod(np.floor(t / 120.0), 2) == 0, 1.0, -1.0)
        ramp = np.clip(np.minimum(ph - 50.0, 115.0 - ph) / 5.0, 0.0, 1.0)
        psidot = sgn * 0.5 * std * ramp
    if cfg.profile == "manoeuvre":
        ph2 = np.mod(t + 30.0, 240.0)
        gamma = np.deg2rad(3.0) * (np.clip(np.minimum(ph2, 60 - ph2) / 5.0, 0, 1)
                                   - np.clip(np.minimum(ph2 - 120, 180 - ph2) / 5.0, 0, 1))
        V = cfg.tas * (1.0 + 0.1 * np.sin(2 * np.pi * t / 300.0))
    return psidot, gamma, V


def simulate_flight(cfg: FlightConfig | None = None, rng: np.random.Generator | int | None = None) -> FlightData:
    """Simulate truth, air-data, Doppler and attitude outputs of a flight (seeded).

    Parameters
    ----------
    cfg : FlightConfig, optional
        The flight (default: :class:`FlightConfig` ()).
    rng : numpy.random.Generator or int, optional
        Random generator or seed.

    Returns
    -------
    FlightData
        Truth and sensor outputs.

    Raises
    ------
    InvalidInputError
        If the configuration is inconsistent (unknown profile or turbulence, rates that do not divide the
        truth rate, non-positive durations or speeds).
    """
    c = FlightConfig() if cfg is None else cfg
    gen = np.random.default_rng(rng)
    dt = 1.0 / c.rate_truth
    n = int(round(c.duration * c.rate_truth)) + 1
    t = dt * np.arange(n)
    psidot, gamma, V = _profiles(c, t)
    psi = np.deg2rad(c.heading_deg) + np.concatenate([[0.0], np.cumsum(0.5 * (psidot[1:] + psidot[:-1]) * dt)])
    v_air_nom = V[:, None] * np.stack([np.cos(gamma) * np.cos(psi), np.cos(gamma) * np.sin(psi), -np.sin(gamma)], 1)
    w_mean = np.asarray(c.wind_ned, dtype=np.float64)
    v_ground = v_air_nom + w_mean
    pos = np.concatenate([np.zeros((1, 3)), np.cumsum(0.5 * (v_ground[1:] + v_ground[:-1]) * dt, axis=0)])
    alt = c.altitude - pos[:, 2]
    if np.any(alt < 0) or np.any(alt > 47000):
        raise InvalidInputError("the profile leaves the ISA altitude range; lower the duration or climb")
    roll = np.arctan(V * psidot / G0)  # coordinated turn
    nload = 1.0 / np.cos(roll)
    pitch = gamma + np.deg2rad(c.alpha_trim_deg) * nload
    euler = np.stack([roll, pitch, psi], axis=1)
    C = dcm_from_euler(euler)
    gust_axes = dryden_gusts(n, dt, float(c.tas), TURBULENCE_SIGMA[c.turbulence], rng=gen)
    # gust axes: longitudinal / lateral / vertical in the (heading, level) frame
    ch, sh = np.cos(psi), np.sin(psi)
    gust_ned = np.stack([ch * gust_axes[:, 0] - sh * gust_axes[:, 1], sh * gust_axes[:, 0] + ch * gust_axes[:, 1],
                         gust_axes[:, 2]], axis=1)
    wind = w_mean + gust_ned
    v_air_ned = v_ground - wind
    v_air_body = np.einsum("kji,kj->ki", C, v_air_ned)  # C_nbᵀ v
    tas = np.linalg.norm(v_air_body, axis=1)

    # ---- air data at rate_ads
    ia = np.arange(0, n, int(round(c.rate_truth / c.rate_ads)))
    atm = isa(alt[ia])
    M = tas[ia] / atm.speed_of_sound
    ps_true = atm.pressure
    pt_true = ps_true * pitot_ratio(M)
    na = ia.size
    ps_m = ps_true + c.ps_noise_std * gen.standard_normal(na)
    pt_m = ps_m + (pt_true - ps_true) + c.qc_noise_std * gen.standard_normal(na)
    tat_m = total_temperature(atm.temperature, M) + c.tat_noise_std * gen.standard_normal(na)
    ad = air_data(pt_m, ps_m, tat_m)
    al_t, be_t = aoa_sideslip(v_air_body[ia])
    al_m = al_t + np.deg2rad(c.alpha_noise_std_deg) * gen.standard_normal(na)
    be_m = be_t + np.deg2rad(c.beta_noise_std_deg) * gen.standard_normal(na)
    v_ads = tas_to_body(ad.tas, al_m, be_m)
    eul_a = euler[ia] + np.deg2rad(c.attitude_noise_std_deg) * gen.standard_normal((na, 3))

    # ---- Doppler at rate_doppler
    idd = np.arange(0, n, int(round(c.rate_truth / c.rate_doppler)))
    v_g_body = np.einsum("kji,kj->ki", C[idd], v_ground[idd])
    water = np.zeros(idd.size)
    for t0, t1 in c.over_water:
        water[(t[idd] >= t0) & (t[idd] < t1)] = 1.0
    dm = simulate_doppler(v_g_body, janus_beams(c.n_beams, c.depression_deg), c.doppler, water, gen)
    eul_d = euler[idd] + np.deg2rad(c.attitude_noise_std_deg) * gen.standard_normal((idd.size, 3))
    return FlightData(t, pos, v_ground, wind, euler, v_air_body, tas, alt,
                      t[ia], ps_m, pt_m, tat_m, al_m, be_m, ad.tas, v_ads, eul_a,
                      t[idd], dm.velocity, dm.beam_velocity, eul_d, water.astype(bool), c)
