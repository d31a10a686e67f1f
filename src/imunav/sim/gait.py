"""Foot-mounted gait simulator: walking, running and stairs with known truth.

The foot alternates stance (stationary, flat, known duration) and swing.  In
swing ``s = (t - t_0) / T_swing`` runs over [0, 1] and

* the horizontal displacement follows the minimum-jerk profile
  ``L (10 s³ - 15 s⁴ + 6 s⁵)`` along the current heading (T. Flash, N. Hogan, "The coordination of
  arm movements", J. Neuroscience 5(7), 1985),
* the height rises by ``clearance sin⁴(π s) + rise (10 s³ - 15 s⁴ + 6 s⁵)``
  (zero vertical acceleration at touch-down and toe-off)
  (``rise`` = step height on stairs),
* the pitch is ``-pitch_amp sin(2π s)(1 - cos(2π s)) / 2`` (toe-off then
  heel-strike; zero rate and angular acceleration at both ends),
* the heading turns by ``turn`` with the minimum-jerk profile.

All derivatives are analytic, so the ideal IMU (via
:func:`imunav.sim.trajectory.ideal_imu`, no Earth rate, constant gravity) is
exact; sensor errors are applied once with :func:`imunav.sim.apply_errors`.
Speeds vary per step: ``speed`` is drawn around the mode's nominal value.

Modes (nominal step length, swing time, stance time, clearance, pitch):
``walk`` (1.4 m, 0.40 s, 0.60 s, 0.10 m, 35°), ``run`` (2.4 m, 0.45 s, 0.25 s,
0.20 m, 60°), ``stairs`` (0.6 m, 0.55 s, 0.65 s, 0.05 m, 20°; rise 0.34 m =
two 0.17 m steps per stride).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav.errors import InvalidInputError
from imunav.results import EulerMixin, Result
from imunav.rotation import quat_from_euler
from imunav.sim import GaussMarkov, ImuErrorModel, Trajectory, TriadErrors, apply_errors, ideal_imu
from imunav.timeseries import ImuData

__all__ = ["GaitSimulation", "GAIT_MODES", "simulate_gait", "foot_mems_model"]

Array = NDArray[np.float64]

#: mode -> (step length m, swing s, stance s, clearance m, pitch amplitude rad, rise m)
GAIT_MODES: dict[str, tuple[float, float, float, float, float, float]] = {
    "walk": (1.4, 0.40, 0.60, 0.10, math.radians(35.0), 0.0),
    "run": (2.4, 0.45, 0.25, 0.20, math.radians(60.0), 0.0),
    "stairs": (0.6, 0.55, 0.65, 0.05, math.radians(20.0), 0.34),
}


@dataclass(frozen=True)
class GaitSimulation(EulerMixin, Result):
    """Simulated foot motion and IMU.

    Attributes
    ----------
    imu : ImuData
        The IMU samples with the sensor errors of the error model (FRD body frame, rad/s, m/s²).
    ideal : ImuData
        The same samples without sensor errors.
    position : numpy.ndarray, shape (N, 3)
        True foot position, NED, m.
    velocity : numpy.ndarray, shape (N, 3)
        True foot velocity, NED, m/s.
    q_nb : numpy.ndarray, shape (N, 4)
        True attitude, Hamilton scalar-first quaternion, body (FRD) to NED.
    stance : numpy.ndarray of bool, shape (N,)
        True when the foot is flat on the ground (zero velocity).
    gyro_bias, accel_bias : numpy.ndarray, shape (N, 3)
        Realised total gyro (rad/s) and accelerometer (m/s²) biases, zero without an error model.
    modes : list of str
        The gait mode of each stride (``"walk"``, ``"run"``, ``"stairs"``).
    """

    imu: ImuData
    ideal: ImuData
    position: Array
    velocity: Array
    q_nb: Array
    stance: NDArray[np.bool_]
    gyro_bias: Array
    accel_bias: Array
    modes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (time, true position, stance, modes; not the IMU samples).

        Returns
        -------
        dict
            ``t`` (s), ``position`` (NED, m), ``stance`` (0/1), ``modes``.
        """
        return {"t": self.imu.t.tolist(), "position": self.position.tolist(), "stance": self.stance.astype(int).tolist(),
                "modes": self.modes}


def foot_mems_model(scale: float = 1.0) -> Any:
    """A foot-mounted MEMS IMU error model (MicroStrain 3DM-GX5-25 class, datasheet values).

    Gyro: bias 0.05 °/s per axis pattern, noise 0.005 °/s/√Hz, bias
    instability GM(8 °/h, 100 s); accel: bias 2-4 mg, noise 60 µg/√Hz,
    GM(0.04 mg, 100 s).

    Parameters
    ----------
    scale : float
        Multiplies every term (0 gives an ideal sensor).

    Returns
    -------
    ImuErrorModel
        The error model, SI.
    """

    dps = math.pi / 180.0
    mg = 9.80665e-3
    gyro = TriadErrors(bias=scale * np.array([0.05, -0.04, 0.03]) * dps, noise_density=scale * 0.005 * dps,
                       bias_instability=GaussMarkov(sigma=scale * 8.0 * dps / 3600.0, tau=100.0))
    accel = TriadErrors(bias=scale * np.array([3.0, -2.0, 4.0]) * mg, noise_density=scale * 60e-6 * 9.80665,
                        bias_instability=GaussMarkov(sigma=scale * 0.04 * mg, tau=100.0))
    return ImuErrorModel(gyro=gyro, accel=accel, name="foot_mems",
                         source="representative 3DM-GX5-25-class figures (datasheet order of magnitude)")


def _mj(s: Array) -> tuple[Array, Array, Array]:
    """Minimum-jerk 10s³-15s⁴+6s⁵ and its first two derivatives in s."""
    return (10 * s**3 - 15 * s**4 + 6 * s**5, 30 * s**2 - 60 * s**3 + 30 * s**4, 60 * s - 180 * s**2 + 120 * s**3)


def simulate_gait(modes: str | list[str] = "walk", strides: int = 20, *, fs: float = 200.0,
                  speed_jitter: float = 0.1, turn_deg: float = 0.0, initial_stance_s: float = 2.0,
                  final_stance_s: float = 1.0, g: float = 9.80665, error_model: Any = "foot_mems",
                  rng: Any = None) -> GaitSimulation:
    """Simulate a foot-mounted IMU over ``strides`` strides (module docstring).

    Parameters
    ----------
    modes : str or list of str
        One mode or a list cycled per stride (``"walk"``, ``"run"``, ``"stairs"``).
    strides : int
        Number of swing phases.
    fs : float
        Sample rate, Hz.
    speed_jitter : float
        Relative spread (uniform ±) of step length and times per stride.
    turn_deg : float
        Heading change per stride, degrees (e.g. 360 / strides for a loop).
    initial_stance_s, final_stance_s : float
        Standing still before / after, s.
    g : float
        Gravity, m/s² (``g^n = (0, 0, g)``).
    error_model : ImuErrorModel or str or None
        An :class:`imunav.sim.ImuErrorModel`, ``"foot_mems"`` (:func:`foot_mems_model`) or None (ideal).
    rng : numpy.random.Generator or int, optional
        Random generator or seed.

    Returns
    -------
    GaitSimulation
        IMU output and truth.

    Raises
    ------
    InvalidInputError
        If a mode is unknown, ``strides < 1``, ``fs <= 0``, ``speed_jitter`` is outside [0, 0.5), or
        ``error_model`` is not understood.
    """

    gen = np.random.default_rng(rng)
    seq = [modes] if isinstance(modes, str) else list(modes)
    for m in seq:
        if m not in GAIT_MODES:
            raise InvalidInputError(f"unknown gait mode {m!r}; choose from {sorted(GAIT_MODES)}")
    if strides < 1 or fs <= 0 or not 0 <= speed_jitter < 0.5:
        raise InvalidInputError(f"need strides >= 1, fs > 0, 0 <= speed_jitter < 0.5; got {strides}, {fs}, {speed_jitter}")
    dt = 1.0 / fs
    # --- phase schedule
    phases: list[tuple[str, float, dict]] = [("stance", initial_stance_s, {})]
    used = []
    for k in range(strides):
        m = seq[k % len(seq)]
        used.append(m)
        L, Ts, Tst, clr, pa, rise = GAIT_MODES[m]
        j = 1.0 + gen.uniform(-speed_jitter, speed_jitter)
        phases.append(("swing", Ts / math.sqrt(j), {"L": L * j, "clr": clr, "pa": pa * j, "rise": rise,
                                                    "turn": math.radians(turn_deg)}))
        phases.append(("stance", Tst / math.sqrt(j) if k < strides - 1 else final_stance_s, {}))
    total = sum(p[1] for p in phases)
    n = int(math.floor(total * fs)) + 1
    t = np.arange(n) * dt
    pos = np.zeros((n, 3))
    vel = np.zeros((n, 3))
    acc = np.zeros((n, 3))
    pitch = np.zeros(n)
    dpitch = np.zeros(n)
    yaw = np.zeros(n)
    dyaw = np.zeros(n)
    stance = np.zeros(n, bool)
    p0 = np.zeros(3)
    psi0 = 0.0
    t0 = 0.0
    for kind, T, par in phases:
        i0 = int(math.ceil(t0 * fs - 1e-9))
        i1 = min(n, int(math.ceil((t0 + T) * fs - 1e-9)))
        sl = slice(i0, i1)
        if kind == "stance":
            pos[sl] = p0
            yaw[sl] = psi0
            stance[sl] = True
        else:
            s = (t[sl] - t0) / T
            f, df, ddf = _mj(s)
            psi = psi0 + par["turn"] * f
            dpsi = par["turn"] * df / T
            ddpsi = par["turn"] * ddf / T**2
            # horizontal: along a heading that turns with the same profile: x' = L f'(s)/T (cos psi, sin psi)
            sp = par["L"] * df / T
            dsp = par["L"] * ddf / T**2
            c, sn = np.cos(psi), np.sin(psi)
            vel[sl, 0] = sp * c
            vel[sl, 1] = sp * sn
            acc[sl, 0] = dsp * c - sp * sn * dpsi
            acc[sl, 1] = dsp * sn + sp * c * dpsi
            # integrate the horizontal position (the heading turns: no closed form); Simpson-exact enough
            # via cumulative trapezoid on a fine grid
            fine = np.linspace(0.0, 1.0, 4001)
            ff, dff, _ = _mj(fine)
            vx = par["L"] * dff * np.cos(psi0 + par["turn"] * ff)
            vy = par["L"] * dff * np.sin(psi0 + par["turn"] * ff)
            cx = np.concatenate([[0], np.cumsum(0.5 * (vx[1:] + vx[:-1]) * np.diff(fine))])
            cy = np.concatenate([[0], np.cumsum(0.5 * (vy[1:] + vy[:-1]) * np.diff(fine))])
            pos[sl, 0] = p0[0] + np.interp(s, fine, cx)
            pos[sl, 1] = p0[1] + np.interp(s, fine, cy)
            # vertical (NED: z down)
            sp_, cp_ = np.sin(np.pi * s), np.cos(np.pi * s)
            h = par["clr"] * sp_**4 + par["rise"] * f
            dh = (par["clr"] * 4 * np.pi * sp_**3 * cp_ + par["rise"] * df) / T
            ddh = (par["clr"] * 4 * np.pi**2 * sp_**2 * (3 * cp_**2 - sp_**2) + par["rise"] * ddf) / T**2
            pos[sl, 2] = p0[2] - h
            vel[sl, 2] = -dh
            acc[sl, 2] = -ddh
            # pitch: heel-off (toe down, negative pitch) then heel-strike, zero rate at both ends
            w = 2 * np.pi * s
            pitch[sl] = -par["pa"] * np.sin(w) * (1 - np.cos(w)) / 2
            dpitch[sl] = -par["pa"] * (np.cos(w) * (1 - np.cos(w)) + np.sin(w) ** 2) / 2 * 2 * np.pi / T
            yaw[sl] = psi
            dyaw[sl] = dpsi
            end = np.array([cx[-1], cy[-1], -par["rise"]])
            p0 = p0 + end
            psi0 = psi0 + par["turn"]
            _ = ddpsi
        t0 += T
    # fill any sample after the last phase boundary
    q = quat_from_euler(np.zeros(n), pitch, yaw)
    # ZYX with roll = 0: omega_nb^b = [-psi' sin(theta), theta', psi' cos(theta)]
    omega = np.column_stack([-dyaw * np.sin(pitch), dpitch, dyaw * np.cos(pitch)])
    traj = Trajectory(t, q, vel_ned=vel, omega_nb_b=omega, accel_ned=acc)
    ideal = ideal_imu(traj, earth_rate=False, transport_rate=False, gravity=float(g))
    if error_model is None:
        imu = ideal
        gb = np.zeros((n, 3))
        ab = np.zeros((n, 3))
    else:
        model = foot_mems_model() if isinstance(error_model, str) and error_model == "foot_mems" else error_model
        if isinstance(model, str):
            raise InvalidInputError(f"unknown error model {error_model!r}; pass an ImuErrorModel, 'foot_mems' or None")
        imu, truth = apply_errors(ideal, model, gen, return_truth=True)
        gb = np.asarray(truth.gyro.bias)
        ab = np.asarray(truth.accel.bias)
    return GaitSimulation(imu, ideal, pos, vel, np.asarray(q), stance, gb, ab, used)
