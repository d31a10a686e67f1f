"""Synthetic recordings for the tests, in one place (small numpy builders, independent of imunav.sim).

- :func:`static_imu`: the seeded IMU recording at rest, level (white noise about zero rate and ``(0, 0, -g)``);
- :func:`rotating_imu`: a smooth random rotation with magnetometer, and the truth (attitude tests);
- the calibration sessions: :func:`multipose_session`, :func:`hand_session`, :func:`unsigned_count_session`,
  the thesis's truth (:func:`thesis_truth`) and its positions / rate steps.

Every builder takes its seed (or generator) and draws in a fixed order, so a test's data are the same on every run.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from imunav.calib.model import ImuCalibration
from imunav.calib.multipose import accel_tedaldi_matrix, gyro_tedaldi_matrix
from imunav.rotation import (
    dcm_from_quat,
    quat_conjugate,
    quat_exp,
    quat_from_euler,
    quat_from_rotvec,
    quat_inverse,
    quat_multiply,
    quat_rotate,
    rotvec_from_quat,
)
from imunav.timeseries import ImuData
from imunav.units import G0

G = G0  # standard gravity, m/s^2: the calibration sessions' and static_imu's default


# ---------------------------------------------------------------- IMU recordings
def static_imu(n: int = 1000, fs: float = 100.0, *, seed: int | np.random.Generator | None = 0,
               accel: ArrayLike = (0.0, 0.0, -G0), gyro_sd: float = 0.01, accel_sd: float = 0.01,
               mag: ArrayLike | None = None, mag_sd: float = 0.0, temp: float | None = None, temp_sd: float = 0.0,
               **fields) -> ImuData:
    """A recording at rest: ``n`` samples at ``fs`` Hz from ``t = 0``, SI, body FRD.

    Gyro ``N(0, gyro_sd)``, specific force ``N(accel, accel_sd)`` (level by default: ``(0, 0, -g)``), then, when
    given, a magnetometer ``N(mag, mag_sd)`` and a temperature ``N(temp, temp_sd)``, drawn in that order from
    ``numpy.random.default_rng(seed)`` (a generator is used as it is); a zero σ gives the constant itself, with
    nothing drawn.  ``fields`` go to :class:`ImuData` (``mag_unit``, ``meta``).
    """
    r = np.random.default_rng(seed)

    def draw(mean, sd, shape):
        mean = np.asarray(mean, float)
        return r.normal(mean, sd, shape) if sd else np.broadcast_to(mean, shape).copy()

    gyro = draw(0.0, gyro_sd, (n, 3))
    f = draw(accel, accel_sd, (n, 3))
    m = None if mag is None else draw(mag, mag_sd, (n, 3))
    tc = None if temp is None else draw(temp, temp_sd, (n,))
    return ImuData(np.arange(n) / fs, gyro, f, m, tc, **fields)


G_ROTATING = 9.81  # gravity of rotating_imu, m/s^2
MAG_NED = np.array([18.0, 0.0, 45.0])  # µT, north / down


def rotating_imu(rng, *, duration=60.0, fs=100.0, rate_amp=0.6, bias=(0.01, -0.02, 0.015), sg=0.002, sa=0.05,
                 sm=0.3, q0=None):
    """Smooth random rotation; ZOH gyro (sample k held over (t_{k-1}, t_k]).

    Returns ImuData, true q_nb (N, 4), per-sample noise stds (sg [rad/s], sa [m/s²], sm [µT]).
    """
    r = np.random.default_rng(rng)
    n = int(duration * fs)
    t = np.arange(n) / fs
    dt = 1.0 / fs
    f = r.uniform(0.05, 0.3, 3)
    ph = r.uniform(0, 2 * np.pi, 3)
    w = rate_amp * np.sin(2 * np.pi * f[None, :] * t[:, None] + ph[None, :])
    q = np.empty((n, 4))
    qk = quat_from_euler(0.2, -0.1, 1.0) if q0 is None else np.asarray(q0, float)
    for k in range(n):
        if k > 0:
            qk = quat_multiply(qk, quat_exp(w[k] * dt))
        q[k] = qk
    qc = quat_conjugate(q)
    fb = quat_rotate(qc, np.tile([0.0, 0.0, -G_ROTATING], (n, 1))) + r.normal(0, sa, (n, 3))
    mb = quat_rotate(qc, np.tile(MAG_NED, (n, 1))) + r.normal(0, sm, (n, 3))
    gyr = w + np.asarray(bias) + r.normal(0, sg, (n, 3))
    return ImuData(t=t, gyro=gyr, accel=fb, mag=mb), q


#: the disturbances of disturbed_imu: field x1.6 over [20, 23) s, +3 m/s² on x over [30, 31) s
DISTURBED_FIELD_S = (20.0, 23.0)
DISTURBED_ACCEL_S = (30.0, 31.0)


def disturbed_imu(fs=100.0):
    """10 s at rest, then 30 s of rotation (rotating_imu, seed 7) with a field disturbance and an acceleration bump.

    Returns ImuData and the true q_nb (N, 4); the disturbances are :data:`DISTURBED_FIELD_S` and
    :data:`DISTURBED_ACCEL_S`.
    """
    q0 = quat_from_euler(0.2, -0.1, 1.0)
    moving, q_mov = rotating_imu(7, duration=30.0, fs=fs, q0=q0)
    r = np.random.default_rng(8)
    ns = int(10 * fs)
    qc = np.tile(quat_conjugate(q0), (ns, 1))
    acc = np.vstack([quat_rotate(qc, np.tile([0, 0, -G_ROTATING], (ns, 1))) + r.normal(0, 0.05, (ns, 3)),
                     moving.accel])
    mag = np.vstack([quat_rotate(qc, np.tile(MAG_NED, (ns, 1))) + r.normal(0, 0.3, (ns, 3)), moving.mag])
    gyr = np.vstack([np.array([0.01, -0.02, 0.015]) + r.normal(0, 0.002, (ns, 3)), moving.gyro])
    n = gyr.shape[0]
    mag[int(DISTURBED_FIELD_S[0] * fs):int(DISTURBED_FIELD_S[1] * fs)] *= 1.6
    acc[int(DISTURBED_ACCEL_S[0] * fs):int(DISTURBED_ACCEL_S[1] * fs), 0] += 3.0
    return ImuData(t=np.arange(n) / fs, gyro=gyr, accel=acc, mag=mag), np.vstack([np.tile(q0, (ns, 1)), q_mov])


def angle_err_deg(q_est, q_true):
    """Angle of the rotation between two attitudes, deg, per row."""
    d = quat_multiply(quat_conjugate(q_true), q_est)
    return np.degrees(2 * np.arccos(np.clip(np.abs(d[:, 0]), 0, 1)))


# ---------------------------------------------------------------- calibration sessions


def random_poses(n: int, rng: np.random.Generator) -> np.ndarray:
    """n attitudes q_nb spread over the sphere of gravity directions."""
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1)[:, None]


def multipose_session(poses, fs, *, rest_s=30.0, static_s=3.0, move_s=1.5):
    """Ideal specific force and body rate for rest, then poses joined by constant-rate turns."""
    fs_list, ws_list = [], []
    g_n = np.array([0.0, 0.0, -G])

    def static(q, dur):
        n = int(np.rint(dur * fs))
        C = dcm_from_quat(q)
        fs_list.append(np.tile(C.T @ g_n, (n, 1)))
        ws_list.append(np.zeros((n, 3)))

    static(poses[0], rest_s)
    for k in range(1, len(poses)):
        dq = quat_multiply(quat_inverse(poses[k - 1]), poses[k])
        rv = rotvec_from_quat(dq)
        n = int(np.rint(move_s * fs))
        w = rv / move_s
        s = (np.arange(n) + 1) / n
        qs = quat_multiply(np.tile(poses[k - 1], (n, 1)), quat_from_rotvec(s[:, None] * rv[None, :]))
        C = dcm_from_quat(qs)
        fs_list.append(np.einsum("nji,j->ni", C, g_n))
        ws_list.append(np.tile(w, (n, 1)))
        static(poses[k], static_s)
    return np.vstack(fs_list), np.vstack(ws_list)


def hundred_positions() -> np.ndarray:
    """The spec's reconstructed 100-position list (imu-error-calibration §5.2): body up vectors.

    Per axis i: −1 g → +1 g through +k, back through −k, −1 g → +1 g through +j,
    back through −j (9 + 8 + 8 + 8 positions, 22.5° steps); then one level position.
    """
    th = np.deg2rad(np.arange(0, 181, 22.5))
    out = []
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        for n_sweep, (other, sgn) in enumerate(((k, 1), (k, -1), (j, 1), (j, -1))):
            forward = n_sweep % 2 == 0  # -1 g -> +1 g, else back
            for n, a in enumerate(th):
                if n_sweep > 0 and n == 0:
                    continue
                u = np.zeros(3)
                u[i] = -np.cos(a) if forward else np.cos(a)
                u[other] = sgn * np.sin(a)
                out.append(u)
    out.append(np.array([0.0, 0.0, -1.0]))  # level (FRD: up is -z)
    return np.array(out)


def thesis_truth():
    """Tables 5.1 / 5.2 parameters as an ImuCalibration (SI)."""
    g, d = G, np.pi / 180
    Sa = np.array([21283, 17592, 18409]) * 1e-6
    Ba = np.array([0.3945, 0.2899, -0.3371]) * g
    Ma = np.array([7.8824, 4.1317, 5.5272, 4.8791, 6.2235, 8.9376]) * 1e-3
    Sg = np.array([19872, 32650, 14883]) * 1e-6
    Bg = np.array([1.4402, -0.7611, 1.5269]) * d
    BG = np.array([0.0485, 0.0617, 0.0432]) * d / g
    Mg = np.array([8.4814, 3.9864, 5.1457, 6.5572, 6.1988, 7.3812]) * 1e-3

    def T(S, M):
        T = np.eye(3) + np.diag(S)
        T[0, 1], T[0, 2], T[1, 0], T[1, 2], T[2, 0], T[2, 1] = M
        return T

    return ImuCalibration(accel_bias=Ba, accel_matrix=T(Sa, Ma), gyro_bias=Bg, gyro_matrix=T(Sg, Mg), g_sensitivity=np.diag(BG))


def rate_table_steps() -> tuple[np.ndarray, np.ndarray]:
    """120 steps: body rate vectors (rad/s) and up vectors (rotated axis up)."""
    seq = np.r_[np.arange(0, 251, 25), np.arange(225, 0, -25), 0, np.arange(-25, -251, -25), np.arange(-225, 0, 25)]
    assert seq.size == 40
    W, U = [], []
    for i in range(3):
        e = np.zeros(3)
        e[i] = 1.0
        for r in seq:
            W.append(np.deg2rad(r) * e)
            U.append(e)
    return np.array(W), np.array(U)


def hand_session(poses, fs, rng, *, rest_s=50.0, static_s=(7.0, 10.0), move_s=(2.5, 4.0), wobble=0.3):
    """Ideal specific force and body rate of a hand-rotated multi-pose session.

    Rest, then the poses; each turn takes a random time in ``move_s`` along the
    minimum-jerk profile of hand movements (``s(τ) = 10τ³ − 15τ⁴ + 6τ⁵``,
    ``τ = t/T``, of the rotation vector between the poses) and a detour ``exp(sin²(πt/T) δ)``, ``|δ| ≤ wobble`` rad,
    so the axis wanders as a hand's would (the rate is continuous and 0 at both ends); each pose is held for a random time in
    ``static_s``.  The rate is the exact body rate at each sample (central
    difference over 1e-4 s), the specific force ``Cᵀ g_n`` (turns are pure rotations).
    """
    g_n = np.array([0.0, 0.0, -G])
    f_list, w_list = [], []

    def static(q, dur):
        n = int(np.rint(dur * fs))
        f_list.append(np.tile(dcm_from_quat(q).T @ g_n, (n, 1)))
        w_list.append(np.zeros((n, 3)))

    static(poses[0], rest_s)
    for k in range(1, len(poses)):
        rv = rotvec_from_quat(quat_multiply(quat_inverse(poses[k - 1]), poses[k]))
        n = int(np.rint(rng.uniform(*move_s) * fs))
        T = n / fs
        delta = rng.uniform(-1, 1, 3) * wobble / np.sqrt(3)

        def q_at(t, q0=poses[k - 1], rv=rv, T=T, delta=delta):
            t = np.clip(t, 0.0, T)
            tau = t / T
            s = tau**3 * (10 - 15 * tau + 6 * tau**2)
            q = quat_multiply(np.tile(q0, (len(t), 1)), quat_from_rotvec(s[:, None] * rv[None, :]))
            return quat_multiply(q, quat_from_rotvec(np.sin(np.pi * t / T)[:, None] ** 2 * delta[None, :]))

        t = (np.arange(n) + 1) / fs
        h = 1e-4
        w = rotvec_from_quat(quat_multiply(quat_inverse(q_at(t - h)), q_at(t + h))) / (2 * h)
        w[t >= T] = 0.0
        f_list.append(np.einsum("nji,j->ni", dcm_from_quat(q_at(t)), g_n))
        w_list.append(w)
        static(poses[k], rng.uniform(*static_s))
    return np.vstack(f_list), np.vstack(w_list)


# A 16-bit IMU read as unsigned counts (zero near 32768): 415 counts per m/s², 4,778 counts per rad/s,
# misalignments of about 0.01 rad; white noise 8 counts (accel) and 3 counts (gyro) per sample, then
# rounded to integers within 0..65535.
SA, SG = 1 / 415.0, 1 / 4778.0
PA_U = np.array([0.011, -0.009, 0.012, 1.004 * SA, 0.997 * SA, 1.002 * SA, -32768 - 40, -32768 + 25, -32768 + 60.0])
PG_U = np.array([-0.01, 0.009, -0.012, 0.011, -0.0098, 0.0105, 1.003 * SG, 0.996 * SG, 1.001 * SG])
BG_U = np.array([32768 - 30, 32768 + 12, 32768 + 5.0])


def unsigned_count_session(seed, n_poses=40):
    """Hand-rotated session: 50 s rest, 40 poses held 7-10 s, minimum-jerk turns of 2.5-4 s (~51,000 samples)."""
    truth = ImuCalibration(
        accel_bias=-PA_U[6:], accel_matrix=np.linalg.inv(accel_tedaldi_matrix(PA_U)), gyro_bias=BG_U,
        gyro_matrix=np.linalg.inv(gyro_tedaldi_matrix(PG_U)), raw_accel_unit="counts", raw_gyro_unit="counts",
    )
    rng = np.random.default_rng(seed)
    f, w = hand_session(random_poses(n_poses, rng), 100.0, rng, rest_s=50.0)
    a, g = truth.invert_arrays(f, w)
    a = np.round(a + rng.normal(scale=8.0, size=a.shape))
    g = np.round(g + rng.normal(scale=3.0, size=g.shape))
    assert a.min() >= 0 and a.max() <= 65535 and g.min() >= 0 and g.max() <= 65535  # plausible raw counts
    return a, g


def degenerate_mag_clouds() -> dict[str, np.ndarray]:
    """Magnetometer samples that span no volume: a point, a line and a plane (200 samples each, seeded)."""
    rng = np.random.default_rng(0)
    point = np.tile([20.0, -5.0, 40.0], (200, 1))
    t = rng.uniform(-1, 1, 200)
    line = np.outer(t, [1.0, 2.0, 0.5]) * 30 + [3, 4, 5]
    ang = rng.uniform(0, 2 * np.pi, 200)
    plane = np.c_[30 * np.cos(ang), 30 * np.sin(ang), np.zeros(200)] + [1, 2, 3]
    return {"point": point, "line": line, "plane": plane}
