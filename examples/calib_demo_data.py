"""Write small simulated calibration sessions for the ``imunav calibrate`` examples.

    python examples/calib_demo_data.py demo

creates, in ``demo/``: ``static.npz`` + ``static_segments.json`` (100-position
test), ``rate.npz`` + ``rate_segments.json`` (120-step rate table),
``truth.json`` (the injected calibration) and ``mag.csv`` (a distorted
magnetometer sphere).  The IMU carries the thesis Table 5.1/5.2 errors and
white noise; 20 Hz and short dwells keep the files small.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np


def thesis_truth():
    from imunav.calib import ImuCalibration
    from imunav.units import DEG, G0

    def T(S, M):
        t = np.eye(3) + np.diag(np.asarray(S) * 1e-6)
        t[0, 1], t[0, 2], t[1, 0], t[1, 2], t[2, 0], t[2, 1] = np.asarray(M) * 1e-3
        return t

    return ImuCalibration(
        accel_bias=np.array([0.3945, 0.2899, -0.3371]) * G0,
        accel_matrix=T([21283, 17592, 18409], [7.8824, 4.1317, 5.5272, 4.8791, 6.2235, 8.9376]),
        gyro_bias=np.array([1.4402, -0.7611, 1.5269]) * DEG,
        gyro_matrix=T([19872, 32650, 14883], [8.4814, 3.9864, 5.1457, 6.5572, 6.1988, 7.3812]),
        g_sensitivity=np.diag([0.0485, 0.0617, 0.0432]) * DEG / G0,
        meta={"source": "imu-error-calibration Tables 5.1/5.2"},
    )


def main(out: str | Path, fs: float = 20.0, dwell_s: float = 8.0, seed: int = 0) -> Path:
    from imunav.io import write_imu
    from imunav.sim import hundred_position_profile, ideal_imu, thesis_rate_table_profile

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    truth = thesis_truth()
    truth.save(out / "truth.json")
    lat = np.deg2rad(40.0)
    for name, prof in (
        ("static", hundred_position_profile(fs=fs, dwell_s=dwell_s, lat=lat)),
        ("rate", thesis_rate_table_profile(fs=fs, dwell_s=dwell_s, lat=lat)),
    ):
        ideal = ideal_imu(prof.trajectory)
        a, g = truth.invert_arrays(ideal.accel, ideal.gyro)
        a = a + rng.normal(scale=0.00043 * 9.80665 * np.sqrt(fs), size=a.shape)
        g = g + rng.normal(scale=np.deg2rad(0.0057) * np.sqrt(fs), size=g.shape)
        write_imu(ideal.with_(accel=a, gyro=g), out / f"{name}.npz")
        (out / f"{name}_segments.json").write_text(json.dumps(prof.to_dict()))
    u = rng.normal(size=(1500, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    c, s = np.cos(np.deg2rad(11.3)), np.sin(np.deg2rad(11.3))
    R = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    W = R @ np.diag([1.0150, 0.9393, 1.0455]) @ R.T
    h = 48.0 * u @ W.T + np.array([15.85, -3.749, 19.196]) + rng.normal(scale=0.1, size=u.shape)
    np.savetxt(out / "mag.csv", h, delimiter=",", header="mag_x,mag_y,mag_z", comments="")
    return out


if __name__ == "__main__":
    print(main(sys.argv[1] if len(sys.argv) > 1 else "demo"))
