"""Small seeded attitude simulation shared by the attitude tests."""

from __future__ import annotations

import numpy as np

from imunav.rotation import quat_conjugate, quat_exp, quat_from_euler, quat_multiply, quat_rotate
from imunav.timeseries import ImuData

G = 9.81
MAG_NED = np.array([18.0, 0.0, 45.0])  # µT, north / down


def simulate(rng, *, duration=60.0, fs=100.0, rate_amp=0.6, bias=(0.01, -0.02, 0.015), sg=0.002, sa=0.05,
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
    fb = quat_rotate(qc, np.tile([0.0, 0.0, -G], (n, 1))) + r.normal(0, sa, (n, 3))
    mb = quat_rotate(qc, np.tile(MAG_NED, (n, 1))) + r.normal(0, sm, (n, 3))
    gyr = w + np.asarray(bias) + r.normal(0, sg, (n, 3))
    return ImuData(t=t, gyro=gyr, accel=fb, mag=mb), q


def angle_err_deg(q_est, q_true):
    d = quat_multiply(quat_conjugate(q_true), q_est)
    return np.degrees(2 * np.arccos(np.clip(np.abs(d[:, 0]), 0, 1)))
