"""Write small simulated calibration sessions for the ``imunav calibrate`` examples.

    python examples/calib_demo_data.py demo

creates, in ``demo/``: ``static.npz`` + ``static_segments.json`` (100-position
test), ``rate.npz`` + ``rate_segments.json`` (120-step rate table),
``truth.json`` (the injected calibration), ``noise_model.toml`` (the virtual
IMU's error model, standing for an Allan characterisation) and ``mag.csv`` (a
distorted magnetometer sphere).  The virtual IMU is the ``thesis_sim`` preset
(Tables 5.1/5.2, white noise, Gauss-Markov bias drift); 20 Hz and short dwells
keep the files small.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np


def main(out: str | Path, fs: float = 20.0, dwell_s: float = 8.0, seed: int = 0) -> Path:
    from imunav.calib import ImuCalibration
    from imunav.io import write_imu
    from imunav.sim import apply_errors, hundred_position_profile, ideal_imu, presets, rate_table_step_profile

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    model = presets.get("thesis_sim")
    ImuCalibration.from_error_model(model).save(out / "truth.json")
    model.to_toml(out / "noise_model.toml")
    lat = np.deg2rad(40.0)
    for k, (name, prof) in enumerate((
        ("static", hundred_position_profile(fs=fs, dwell_s=dwell_s, lat=lat)),
        ("rate", rate_table_step_profile(fs=fs, dwell_s=dwell_s, lat=lat)),
    )):
        ideal = ideal_imu(prof.trajectory)
        write_imu(apply_errors(ideal, model, rng=seed * 2 + k), out / f"{name}.npz")
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
