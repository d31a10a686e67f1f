"""Trajectories (true motion) and the ideal IMU they produce.

A :class:`Trajectory` holds attitude ``q_nb`` and optionally NED velocity,
geodetic position, body rates relative to the navigation frame and the
kinematic acceleration.  :func:`ideal_imu` turns it into error-free gyro and
accelerometer outputs (strapdown inverse):

    ω_ib^b = ω_nb^b + C_bn (ω_ie^n + ω_en^n)                       (angular rate)
    f^b    = C_bn ( v̇^n + (2 ω_ie^n + ω_en^n) × v^n − g^n )          (specific force)

(Groves 2013, eqs. 5.46 and 5.54 rearranged; the Earth-rate and transport
terms are optional.)  ``v̇^n`` is the rate of change of the NED velocity
(``Trajectory.accel_ned``); ``g^n`` is the gravity model's vector
``(0, 0, +g)``.

Builders: :func:`trajectory_from_attitude` (sampled attitude),
:func:`trajectory_from_functions` (callables of time),
:func:`trajectory_from_waypoints` (smooth splines through key poses).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation, RotationSpline

from imunav import earth
from imunav.errors import InvalidInputError, NonFiniteError, ShapeError, TimeOrderError
from imunav.results import EulerMixin
from imunav.rotation import (
    dcm_from_quat,
    quat_conjugate,
    quat_from_euler,
    quat_multiply,
    quat_normalize,
    rotvec_from_quat,
)
from imunav.timeseries import ImuData
from imunav.units import G0

__all__ = [
    "Trajectory",
    "ideal_imu",
    "body_rate_from_attitude",
    "trajectory_from_attitude",
    "trajectory_from_functions",
    "trajectory_from_waypoints",
]

Array = NDArray[np.float64]

def _vec(x: ArrayLike | None, n: int, name: str) -> Array | None:
    if x is None:
        return None
    a = np.array(x, dtype=float)
    if a.ndim != 2 or a.shape != (n, 3):
        raise ShapeError(f"Trajectory.{name} must have shape ({n}, 3) (one row per time stamp); got {a.shape}")
    if not np.all(np.isfinite(a)):
        rows = np.flatnonzero(~np.all(np.isfinite(a), axis=1))
        raise NonFiniteError(f"Trajectory.{name} has non-finite values at rows {rows[:10].tolist()}")
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class Trajectory(EulerMixin):
    """True motion sampled at times ``t``.

    Parameters
    ----------
    t : numpy.ndarray
        (N,) strictly increasing time, s.
    q_nb : numpy.ndarray
        (N, 4) attitude, body → NED (normalised on construction).
    vel_ned : numpy.ndarray, optional
        (N, 3) NED velocity, m/s, or None (zero).
    pos_lla : numpy.ndarray, optional
        (N, 3) geodetic position (lat rad, lon rad, h m), or None
        (then :func:`ideal_imu` needs ``lat=`` for Earth rate / normal gravity).
    omega_nb_b : numpy.ndarray, optional
        (N, 3) body rate relative to NED in body axes, rad/s, when
        known exactly; None → derived from ``q_nb`` by differentiation.
    accel_ned : numpy.ndarray, optional
        (N, 3) kinematic acceleration ``dv_ned/dt``, m/s², when known
        exactly; None → derived from ``vel_ned`` (or zero when there is none).
    """

    t: Array
    q_nb: Array
    vel_ned: Array | None = None
    pos_lla: Array | None = None
    omega_nb_b: Array | None = None
    accel_ned: Array | None = None

    def __post_init__(self) -> None:
        t = np.array(self.t, dtype=float)
        if t.ndim != 1 or t.size < 2:
            raise ShapeError(f"Trajectory.t must be 1-D with at least 2 samples; got shape {t.shape}")
        if not np.all(np.isfinite(t)):
            raise NonFiniteError(f"Trajectory.t has non-finite values at rows {np.flatnonzero(~np.isfinite(t))[:10].tolist()}")
        bad = np.flatnonzero(np.diff(t) <= 0)
        if bad.size:
            raise TimeOrderError(
                f"Trajectory.t is not strictly increasing at rows {(bad + 1)[:10].tolist()}; sort it and drop duplicates"
            )
        n = t.size
        q = np.array(self.q_nb, dtype=float)
        if q.shape != (n, 4):
            raise ShapeError(f"Trajectory.q_nb must have shape ({n}, 4); got {q.shape}")
        q = quat_normalize(q)
        t.setflags(write=False)
        q.setflags(write=False)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "q_nb", q)
        for name in ("vel_ned", "pos_lla", "omega_nb_b", "accel_ned"):
            object.__setattr__(self, name, _vec(getattr(self, name), n, name))

    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.t.size)

    @property
    def fs(self) -> float:
        """Median sample rate, Hz."""
        return float(1.0 / np.median(np.diff(self.t)))

    @property
    def duration(self) -> float:
        """``t[-1] - t[0]``, s."""
        return float(self.t[-1] - self.t[0])

    def slice(self, i0: int, i1: int) -> "Trajectory":
        """Samples ``i0 … i1-1`` (half-open).

        Parameters
        ----------
        i0, i1 : int
            First and one-past-last sample index.

        Returns
        -------
        Trajectory
            The sub-trajectory.
        """
        kw = {f.name: (None if getattr(self, f.name) is None else getattr(self, f.name)[i0:i1]) for f in fields(self)}
        return Trajectory(**kw)

    def to_dict(self) -> dict:
        """Plain lists for JSON.

        Returns
        -------
        dict
            Every field by name (``t`` in s, ``q_nb``, ``vel_ned`` m/s, ``pos_lla`` rad/rad/m, ...), None where
            absent.
        """
        return {f.name: (None if getattr(self, f.name) is None else getattr(self, f.name).tolist()) for f in fields(self)}


# ---------------------------------------------------------------------------
# differentiation
# ---------------------------------------------------------------------------


def body_rate_from_attitude(t: ArrayLike, q_nb: ArrayLike) -> Array:
    """Body rate ``ω_nb^b`` (rad/s) of a sampled attitude by central differences.

    Each interval gives its mean rate ``φ_k / Δt_k`` with
    ``φ_k = log(q_kᵀ* ⊗ q_{k+1})`` (exact for a rate constant over the
    interval, any rotation angle below π per step).  Sample ``k`` gets the
    Δt-weighted blend of the two neighbouring intervals, which is second-order
    accurate: the error is ≈ Δt²/6 · |ω̈| (plus the coning term
    ≈ Δt²/12 |ω × ω̇|) for smooth motion; the end samples use their single
    interval (first order).  Pass exact rates to :class:`Trajectory` where the
    motion is known analytically.

    Parameters
    ----------
    t : array_like, shape (N,)
        Strictly increasing time, s.
    q_nb : array_like, shape (N, 4)
        Attitude, body (FRD) to NED.

    Returns
    -------
    numpy.ndarray, shape (N, 3)
        ``ω_nb^b``, rad/s, body axes.

    Raises
    ------
    ShapeError
        If ``t`` and ``q_nb`` do not have matching shapes, or there are fewer than 2 samples.
    """
    ta = np.asarray(t, dtype=float)
    q = quat_normalize(np.asarray(q_nb, dtype=float))
    if q.ndim != 2 or q.shape[0] != ta.size:
        raise ShapeError(f"q_nb must be (N, 4) with N = len(t) = {ta.size}; got {q.shape}")
    dt = np.diff(ta)
    phi = rotvec_from_quat(quat_multiply(quat_conjugate(q[:-1]), q[1:]))
    w_int = phi / dt[:, None]
    out = np.empty((ta.size, 3))
    out[0] = w_int[0]
    out[-1] = w_int[-1]
    if ta.size > 2:
        a, b = dt[:-1, None], dt[1:, None]
        # weights for a second-order estimate at the shared sample of two unequal intervals
        out[1:-1] = (w_int[:-1] * b + w_int[1:] * a) / (a + b)
    return out


def _gradient(t: Array, x: Array) -> Array:
    """Second-order derivative of rows of ``x`` along ``t`` (numpy.gradient)."""
    return np.gradient(x, t, axis=0, edge_order=2) if t.size > 2 else np.gradient(x, t, axis=0)


def _vel_from_lla(t: Array, lla: Array) -> Array:
    """NED velocity from sampled geodetic positions (curvilinear rates)."""
    rn, re = earth.radii(lla[:, 0])
    h = lla[:, 2]
    lon = np.unwrap(lla[:, 1])
    d_lat = _gradient(t, lla[:, 0])
    d_lon = _gradient(t, lon)
    d_h = _gradient(t, h)
    return np.stack([(rn + h) * d_lat, (re + h) * np.cos(lla[:, 0]) * d_lon, -d_h], axis=1)


# ---------------------------------------------------------------------------
# ideal IMU
# ---------------------------------------------------------------------------


def ideal_imu(
    traj: Trajectory,
    *,
    earth_rate: bool = True,
    transport_rate: bool = True,
    gravity: str | float = "normal",
    lat: float | None = None,
    h: float = 0.0,
) -> ImuData:
    """Error-free gyro and accelerometer outputs of a trajectory.

    Parameters
    ----------
    traj : Trajectory
        The true motion.
    earth_rate : bool
        Add Earth rotation ``C_bn ω_ie^n`` to the gyro and the
        Coriolis term ``2 ω_ie^n × v^n`` to the specific force.
    transport_rate : bool
        Add ``C_bn ω_en^n`` to the gyro and ``ω_en^n × v^n`` to
        the specific force (zero when the trajectory has no velocity).
    gravity : str or float
        ``"normal"`` (WGS84 normal gravity at the latitude and height,
        :func:`imunav.earth.normal_gravity`), ``"constant"`` (standard gravity
        9.80665 m/s²) or a number (m/s²), applied as ``g^n = (0, 0, +g)``.
    lat, h : latitude (rad) and height (m) used when the trajectory has no
        ``pos_lla``; required then for Earth rate, transport rate with
        velocity, and normal gravity.

    Returns
    -------
    ImuData
        ``gyro = ω_ib^b`` (rad/s) and ``accel = f^b`` (m/s²), body axes.

    Notes
    -----
    Exact (to rounding) when the trajectory carries ``omega_nb_b`` and
    ``accel_ned``; otherwise those are derived by second-order central
    differences (see :func:`body_rate_from_attitude`; velocity is
    differentiated with :func:`numpy.gradient`, error ≈ Δt²/6 · |d³v/dt³|).

    Raises
    ------
    InvalidInputError
        If ``gravity`` is not understood, or ``lat`` is missing where it is needed (no ``pos_lla``).
    """
    if not isinstance(traj, Trajectory):
        raise InvalidInputError(f"traj must be an imunav.sim.Trajectory, not {type(traj).__name__}")
    t = traj.t
    n = traj.n
    # --- position --------------------------------------------------------
    if traj.pos_lla is not None:
        lat_v = traj.pos_lla[:, 0]
        h_v = traj.pos_lla[:, 2]
    elif lat is not None:
        if not np.isfinite(lat) or abs(lat) > np.pi / 2 + 1e-12:
            raise InvalidInputError(f"lat must be a latitude in radians within ±pi/2; got {lat!r}")
        lat_v = np.full(n, float(lat))
        h_v = np.full(n, float(h))
    else:
        lat_v = h_v = None

    vel = traj.vel_ned
    if vel is None and traj.pos_lla is not None and np.ptp(traj.pos_lla, axis=0).max() > 0:
        vel = _vel_from_lla(t, traj.pos_lla)
    need_lat = earth_rate or (transport_rate and vel is not None) or gravity == "normal"
    if need_lat and lat_v is None:
        raise InvalidInputError(
            "ideal_imu needs a latitude for Earth rate / transport rate / normal gravity: pass lat= (rad) "
            "or build the Trajectory with pos_lla, or use earth_rate=False, transport_rate=False, gravity='constant'"
        )

    # --- gravity ---------------------------------------------------------
    # a fixed place (the usual lab case): evaluate the Earth model once
    fixed = lat_v is not None and np.ptp(lat_v) == 0 and np.ptp(h_v) == 0
    if isinstance(gravity, str):
        if gravity == "normal":
            g = np.full(n, earth.normal_gravity(lat_v[0], h_v[0])) if fixed else np.asarray(earth.normal_gravity(lat_v, h_v))
        elif gravity == "constant":
            g = np.full(n, G0)
        else:
            raise InvalidInputError(f"gravity must be 'normal', 'constant' or a number in m/s^2; got {gravity!r}")
    else:
        gv = float(gravity)
        if not np.isfinite(gv) or gv < 0:
            raise InvalidInputError(f"gravity must be a finite non-negative number in m/s^2; got {gravity!r}")
        g = np.full(n, gv)

    # --- kinematics --------------------------------------------------------
    w_nb = traj.omega_nb_b if traj.omega_nb_b is not None else body_rate_from_attitude(t, traj.q_nb)
    if traj.accel_ned is not None:
        acc = np.array(traj.accel_ned)
    elif vel is not None:
        acc = _gradient(t, np.asarray(vel))
    else:
        acc = np.zeros((n, 3))

    w_in = np.zeros((n, 3))  # ω_in^n = ω_ie^n + ω_en^n
    f_n = acc.copy()
    f_n[:, 2] -= g
    if earth_rate:
        w_ie = np.broadcast_to(earth.earth_rate_ned(lat_v[0]), (n, 3)) if fixed else earth.earth_rate_ned(lat_v)
        w_in += w_ie
        if vel is not None:
            f_n += 2.0 * np.cross(w_ie, vel)
    if transport_rate and vel is not None:
        w_en = earth.transport_rate_ned(lat_v, h_v, vel)
        w_in += w_en
        f_n += np.cross(w_en, vel)

    C_nb = dcm_from_quat(traj.q_nb)
    # C_bn x = C_nbᵀ x
    gyro = w_nb + np.einsum("nji,nj->ni", C_nb, w_in)
    accel = np.einsum("nji,nj->ni", C_nb, f_n)
    meta = {
        "source": "imunav.sim.ideal_imu",
        "earth_rate": bool(earth_rate),
        "transport_rate": bool(transport_rate),
        "gravity": gravity if isinstance(gravity, str) else float(gravity),
    }
    return ImuData(np.array(t), gyro, accel, meta=meta)


# ---------------------------------------------------------------------------
# builders
# ---------------------------------------------------------------------------


def _fixed_position(n: int, lat: float | None, lon: float, h: float) -> Array | None:
    if lat is None:
        return None
    return np.tile(np.array([lat, lon, h], dtype=float), (n, 1))


def trajectory_from_attitude(
    t: ArrayLike,
    q_nb: ArrayLike,
    *,
    omega_nb_b: ArrayLike | None = None,
    lat: float | None = None,
    lon: float = 0.0,
    h: float = 0.0,
) -> Trajectory:
    """Rotation-only trajectory at a fixed place (zero velocity).

    ``omega_nb_b`` is derived from ``q_nb`` (:func:`body_rate_from_attitude`)
    unless given; ``lat``/``lon`` (rad) and ``h`` (m) set a constant position.

    Parameters
    ----------
    t : array_like, shape (N,)
        Strictly increasing time, s.
    q_nb : array_like, shape (N, 4)
        Attitude, body (FRD) to NED.
    omega_nb_b : array_like, shape (N, 3), optional
        Exact body rate relative to NED, rad/s.
    lat : float, optional
        Geodetic latitude, rad (None: no position; :func:`ideal_imu` then needs ``lat=``).
    lon : float
        Longitude, rad.
    h : float
        Ellipsoidal height, m.

    Returns
    -------
    Trajectory
        Zero velocity, constant position.
    """
    ta = np.asarray(t, dtype=float)
    qa = np.asarray(q_nb, dtype=float)
    traj = Trajectory(ta, qa, pos_lla=_fixed_position(ta.size, lat, lon, h), omega_nb_b=omega_nb_b)
    if omega_nb_b is None:
        traj = Trajectory(
            traj.t, traj.q_nb, pos_lla=traj.pos_lla, omega_nb_b=body_rate_from_attitude(traj.t, traj.q_nb)
        )
    return traj


def _sample_times(t: ArrayLike | None, duration_s: float | None, fs: float | None) -> Array:
    if t is not None:
        return np.asarray(t, dtype=float)
    if duration_s is None or fs is None:
        raise InvalidInputError("give either t (time stamps, s) or both duration_s and fs (Hz)")
    if fs <= 0 or duration_s <= 0:
        raise InvalidInputError(f"fs and duration_s must be positive; got fs={fs}, duration_s={duration_s}")
    n = int(np.floor(duration_s * fs + 1e-9)) + 1
    return np.arange(n) / float(fs)


def _as_quat(x: Array, n: int, what: str) -> Array:
    a = np.asarray(x, dtype=float)
    if a.shape == (n, 4):
        return a
    if a.shape == (n, 3):  # ZYX Euler (roll, pitch, yaw)
        return quat_from_euler(a)
    raise ShapeError(f"{what} must return (N, 4) quaternions q_nb or (N, 3) Euler (roll, pitch, yaw); got {a.shape}")


def trajectory_from_functions(
    attitude: Callable[[Array], ArrayLike],
    position_ned: Callable[[Array], ArrayLike] | None = None,
    *,
    t: ArrayLike | None = None,
    duration_s: float | None = None,
    fs: float | None = None,
    origin_lla: ArrayLike | None = None,
    step_s: float = 1e-3,
) -> Trajectory:
    """Sample a trajectory given as functions of time.

    Parameters
    ----------
    attitude : callable
        ``f(t) -> (N, 4)`` quaternions ``q_nb`` or ``(N, 3)`` ZYX Euler
        ``(roll, pitch, yaw)`` in rad, vectorised over ``t``.
    position_ned : callable, optional
        ``f(t) -> (N, 3)`` position in metres in the local NED
        frame of ``origin_lla`` (tangent plane at the origin), or None (fixed).
    t : array_like, optional
        Sample times, s.
    duration_s : float, optional
        Duration, s (with ``fs``; t = k / fs).
    fs : float, optional
        Sample rate, Hz.
    origin_lla : array_like, optional
        Origin (lat rad, lon rad, h m); needed with ``position_ned``
        for the geodetic track, optional otherwise.
    step_s : float
        Differentiation step ``δ`` for the derivatives.

    Notes
    -----
    Rates and accelerations are evaluated from the callables with central
    differences at ``t ± δ`` (rates) and a 5-point stencil (velocity,
    acceleration), so they are the *instantaneous* values at each sample, not
    interval means: truncation error ≈ δ²/6·|ω̈| for rates and δ⁴/30·|p⁽⁵⁾|
    resp. δ⁴/90·|p⁽⁶⁾| for velocity / acceleration, rounding ≈ 1e-16·|p|/δ².
    Velocity is the ECEF velocity resolved in NED at the current position
    (so the frame's rotation along the track is accounted for) and
    ``accel_ned`` is its time derivative.

    Returns
    -------
    Trajectory
        The sampled motion with exact-to-truncation rates and accelerations.

    Raises
    ------
    ShapeError
        If a callable returns the wrong shape.
    InvalidInputError
        If neither ``t`` nor ``duration_s`` and ``fs`` are given.
    """
    ta = _sample_times(t, duration_s, fs)
    n = ta.size
    d = float(step_s)
    q = quat_normalize(_as_quat(np.asarray(attitude(ta)), n, "attitude(t)"))
    qm = quat_normalize(_as_quat(np.asarray(attitude(ta - d)), n, "attitude(t)"))
    qp = quat_normalize(_as_quat(np.asarray(attitude(ta + d)), n, "attitude(t)"))
    # ω at t: log(q(t-δ)* q(t+δ)) / 2δ is resolved at the midpoint frame q(t)
    # to second order; the residual frame offset is O(δ²)
    w = rotvec_from_quat(quat_multiply(quat_conjugate(qm), qp)) / (2 * d)
    if position_ned is None:
        pos = None
        if origin_lla is not None:
            o = np.asarray(origin_lla, dtype=float)
            pos = np.tile(o, (n, 1))
        return Trajectory(ta, q, pos_lla=pos, omega_nb_b=w, vel_ned=None if pos is None else np.zeros((n, 3)),
                          accel_ned=None if pos is None else np.zeros((n, 3)))

    o = np.zeros(3) if origin_lla is None else np.asarray(origin_lla, dtype=float)

    def ned(tt: Array) -> Array:
        p = np.asarray(position_ned(tt), dtype=float)
        if p.shape != (tt.size, 3):
            raise ShapeError(f"position_ned(t) must return ({tt.size}, 3) metres; got {p.shape}")
        return p

    # ECEF velocity = C_en(origin) dp/dt (the tangent frame is fixed in ECEF);
    # differentiating the small local coordinates keeps rounding at ~1e-13
    P = {k: ned(ta + k * d) for k in (-3, -2, -1, 0, 1, 2, 3)}
    C_o = earth.dcm_en(o[0], o[1])

    def vel_ned_at(k: int) -> Array:
        dp = (P[k - 2] - 8 * P[k - 1] + 8 * P[k + 1] - P[k + 2]) / (12 * d)
        lla_k = earth.ned_to_lla(P[k], o)
        return earth.vel_ned_from_ecef(dp @ C_o.T, lla_k)

    v = {k: vel_ned_at(k) for k in (-1, 0, 1)}
    lla = earth.ned_to_lla(P[0], o)
    # central difference of the NED velocity (second order in δ)
    acc = (v[1] - v[-1]) / (2 * d)
    return Trajectory(ta, q, vel_ned=v[0], pos_lla=lla, omega_nb_b=w, accel_ned=acc)


def trajectory_from_waypoints(
    t_key: ArrayLike,
    q_key: ArrayLike,
    pos_key_ned: ArrayLike | None = None,
    *,
    fs: float,
    origin_lla: ArrayLike | None = None,
) -> Trajectory:
    """Smooth trajectory through key poses, sampled at ``fs``.

    Attitude: a C² rotation spline through the key attitudes
    (:class:`scipy.spatial.transform.RotationSpline`), with its analytic
    angular rate.  Position (local NED about ``origin_lla``, m): a cubic spline
    per axis with its analytic first and second derivatives (the tangent-plane
    velocity and acceleration; for tracks of a few km the tangent-plane
    approximation errs by about |v|²/R ≈ 1e-5 m/s² at 10 m/s).

    Parameters
    ----------
    t_key : array_like, shape (K,)
        Key times, s, strictly increasing, K ≥ 2.
    q_key : array_like, shape (K, 4) or (K, 3)
        Key attitudes ``q_nb``, or ZYX Euler ``(roll, pitch, yaw)`` in rad.
    pos_key_ned : array_like, shape (K, 3), optional
        Key positions, local NED, m (None: fixed position).
    fs : float
        Sample rate, Hz; samples at ``t_key[0] + k/fs`` up to ``t_key[-1]``.
    origin_lla : array_like, shape (3,), optional
        Origin of the local NED frame (lat rad, lon rad, h m); sets the geodetic track.

    Returns
    -------
    Trajectory
        The sampled motion with the splines' analytic rates and accelerations.

    Raises
    ------
    TimeOrderError
        If ``t_key`` is not 1-D and strictly increasing with at least 2 keys.
    InvalidInputError
        If ``fs`` is not positive.
    ShapeError
        If the key arrays have the wrong shapes.
    """

    tk = np.asarray(t_key, dtype=float)
    if tk.ndim != 1 or tk.size < 2 or np.any(np.diff(tk) <= 0):
        raise TimeOrderError("t_key must be 1-D, strictly increasing, with at least 2 key times")
    qk = quat_normalize(_as_quat(np.asarray(q_key, dtype=float), tk.size, "q_key"))
    if fs <= 0:
        raise InvalidInputError(f"fs must be positive; got {fs}")
    n = int(np.floor((tk[-1] - tk[0]) * fs + 1e-9)) + 1
    ta = tk[0] + np.arange(n) / float(fs)
    # scipy Rotation: scalar-last quaternions of the active rotation, so
    # as_matrix() of q_nb is C_nb; RotationSpline's first derivative is the
    # angular rate resolved in body axes (checked against
    # body_rate_from_attitude in tests/sim/test_trajectory.py)
    rot = Rotation.from_quat(qk[:, [1, 2, 3, 0]])
    spl = RotationSpline(tk, rot)
    r_t = spl(ta)
    q = r_t.as_quat()[:, [3, 0, 1, 2]]
    w = spl(ta, 1)
    if pos_key_ned is None:
        pos = None if origin_lla is None else np.tile(np.asarray(origin_lla, float), (n, 1))
        return Trajectory(ta, q, pos_lla=pos, omega_nb_b=w)
    pk = np.asarray(pos_key_ned, dtype=float)
    if pk.shape != (tk.size, 3):
        raise ShapeError(f"pos_key_ned must have shape ({tk.size}, 3); got {pk.shape}")
    cs = CubicSpline(tk, pk, axis=0, bc_type="natural")
    o = np.zeros(3) if origin_lla is None else np.asarray(origin_lla, dtype=float)
    lla = earth.ned_to_lla(cs(ta), o)
    return Trajectory(ta, q, vel_ned=cs(ta, 1), pos_lla=lla, omega_nb_b=w, accel_ned=cs(ta, 2))
