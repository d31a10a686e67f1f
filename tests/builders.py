"""Small numpy simulators for the calibration tests (independent of imunav.sim)."""

from __future__ import annotations

import numpy as np

from imunav.rotation import (
    dcm_from_quat,
    quat_from_rotvec,
    quat_inverse,
    quat_multiply,
    rotvec_from_quat,
)

G = 9.80665


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
    from imunav.calib.model import ImuCalibration

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


def thesis_rate_steps() -> tuple[np.ndarray, np.ndarray]:
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
