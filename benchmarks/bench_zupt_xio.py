"""Loop closure on the x-io Gait-Tracking walks, side by side with x-io's published figures.

x-io's own method (Fusion AHRS + velocity-drift removal between stationary
periods) reports a final displacement of 82 mm (short walk, ~25 m) and 421 mm
(long walk, ~60 m).  The foot ends where it started; the loop-closure error
is the distance between the first and last position (3-D, as x-io reports it).

Printed, for both walks:

0. the peer, run here: x-io's method with the ``imufusion`` package (the
   Fusion AHRS, gain 0.5, 10° acceleration rejection, gyro offset
   correction; moving while the earth acceleration exceeds 3 m/s², widened
   by 0.1 s; velocity integrated while moving, its drift over each moving
   period removed linearly, then integrated to position), on the raw file;

1. the ZUPT INS (9 states) with the README's settings (SHOE, threshold 1e8,
   stances shrunk by 0.125 s, accel_noise_std 2 m/s^2) and with each aid:
   heading hold (no rotation about the vertical in stance), level floor
   (each stance at the initial height: valid here, both walks are on one
   floor), and both;
2. the same INS with x-io's own stance rule, ``--detector freeacc
   --margin-s 0.1`` (moving while the free acceleration |C f + g| exceeds
   3 m/s^2, widened by 0.1 s each side), plain and with the level floor;
3. the sensitivity of the result to the detector settings: the x-io method at
   2 / 3 / 4 m/s^2 x margin 0.05 / 0.1 / 0.15 s, SHOE threshold
   3e7 / 1e8 / 3e8 x stance margin 0 / 0.05 / 0.1 / 0.125 / 0.15 s, and the
   free-acceleration rule at 2 / 3 / 4 m/s^2 x margin 0.05 / 0.1 / 0.15 s:
   median and range, plain and with the level floor.

Each row prints the ratio to the x-io method measured in the same run (< 1:
better); without imufusion, to x-io's published displacement.

Run:  PYTHONPATH=src python benchmarks/bench_zupt_xio.py
"""

from __future__ import annotations

import itertools
import sys

import numpy as np
from _before_after import report  # the before (a308974) / after lines

from imunav.ins import ZuptConfig, ZuptFilter, detect_zero_velocity, loop_closure_error
from imunav.io.datasets import shared_data_path
from imunav.io.foot import read_xio_gait_csv

PUBLISHED = {"short_walk": 0.082, "long_walk": 0.421}


def closure(imu, zv, accel_noise_std=2.0, **kw):
    cfg = ZuptConfig(alignment="first_stance", g=None, accel_noise_std=accel_noise_std, **kw)
    res = ZuptFilter(cfg).run(imu, zv)
    return loop_closure_error(res.position), res


def xio_earth(path):
    """x-io's front end with imufusion: (t, dt, earth acceleration m/s^2), or None without imufusion."""
    try:
        import imufusion as fusion
    except ImportError:
        return None
    raw = np.loadtxt(path, delimiter=",", skiprows=1)
    t, gyr, acc = raw[:, 0], np.ascontiguousarray(raw[:, 1:4]), np.ascontiguousarray(raw[:, 4:7])
    fs = 400.0
    dt = np.diff(t, prepend=t[0])
    bias = fusion.Bias().set_settings(fusion.BiasSettings(fs, 3.0, 5.0))
    ahrs = fusion.Ahrs().set_settings(fusion.AhrsSettings(fs, fusion.CONVENTION_NWU, 0.5, 2000.0, 10.0, 0.0, 5.0))
    earth = np.empty_like(acc)
    for i in range(t.size):
        ahrs.set_sample_period(float(dt[i]))
        ahrs.update_no_magnetometer(bias.update(gyr[i]), acc[i])
        earth[i] = 9.81 * ahrs.get_earth_acceleration()
    return t, dt, earth


def xio_track(t, dt, earth, threshold=3.0, margin_s=0.1, fs=400.0):
    """x-io's back end: moving periods, velocity-drift removal, position (NWU, m)."""
    fast = np.linalg.norm(earth, axis=1) > threshold
    m = int(margin_s * fs)
    # a sample is moving when any sample within margin_s after it or before it is
    ahead = np.array([fast[i:i + m].any() for i in range(t.size)])
    moving = ahead.copy()
    for i in range(m + 1, t.size):
        moving[i] = ahead[i - m:i].any()
    vel = np.zeros_like(earth)
    for i in range(1, t.size):
        if moving[i]:
            vel[i] = vel[i - 1] + dt[i] * earth[i]
    step = np.diff(moving.astype(int))
    starts, stops = np.flatnonzero(step == 1), np.flatnonzero(step == -1)
    stops = stops[stops > starts[0]]
    for a, b in zip(starts, stops):  # a: last stationary sample, b: last moving sample
        frac = (t[a:b + 1] - t[a]) / (t[b] - t[a])
        vel[a:b + 1] -= vel[a] + frac[:, None] * (vel[b] - vel[a])
    return np.cumsum(dt[:, None] * vel, axis=0)


def main() -> int:
    base = shared_data_path("foot", "xio_gait")
    if base is None or not (base / "short_walk.csv").is_file():
        print("x-io walks not found (set IMUNAV_DATA or put the data in ../shared/data); nothing to measure")
        return 0
    FIGS = {}  # headline figures for the before/after lines
    for name, pub in PUBLISHED.items():
        imu = read_xio_gait_csv(base / f"{name}.csv").imu
        zv = detect_zero_velocity(imu, "shoe", 1e8, margin_s=0.125).zv
        print(f"\n{name}: {imu.n} samples, {imu.t[-1]:.1f} s; x-io published {pub * 1000:.0f} mm")
        print(f"  {'configuration':60s} {'3-D':>8s} {'horiz.':>8s} {'vert.':>8s} {'ratio':>6s}  (ratio: to the x-io method run here)")

        front = xio_earth(base / f"{name}.csv")
        ref = pub
        if front is None:
            print("  x-io method: imufusion not installed (pip install imufusion); ratios are to the published figure")
        else:
            pos = xio_track(*front)
            ref = float(np.linalg.norm(pos[-1] - pos[0]))
            print(f"  {'x-io method (imufusion), run here':60s} {ref:8.4f} "
                  f"{float(np.hypot(*(pos[-1, :2] - pos[0, :2]))):8.4f} {abs(pos[-1, 2] - pos[0, 2]):8.4f} "
                  f"{1.0:6.2f}")

        def row(label, lc, ref=ref, name=name):
            FIGS[f"{name} row {len(FIGS) % 7 + 1} ({label.strip()}) 3-D m"] = lc.error_3d
            print(f"  {label:60s} {lc.error_3d:8.4f} {lc.horizontal:8.4f} {abs(lc.vertical):8.4f} "
                  f"{lc.error_3d / ref:6.2f}")

        lc0, res0 = closure(imu, zv)
        row("SHOE 1e8, margin 0.125 s (README)", lc0)
        row("  + heading hold", closure(imu, zv, heading_hold=True)[0])
        row("  + level floor", closure(imu, zv, level_floor=True)[0])
        row("  + heading hold + level floor", closure(imu, zv, heading_hold=True, level_floor=True)[0])
        zx = detect_zero_velocity(imu, "freeacc", 3.0, margin_s=0.1).zv
        row("freeacc 3 m/s^2, margin 0.1 s (x-io's rule; CLI defaults)", closure(imu, zx, accel_noise_std=0.5)[0])
        row("  + level floor", closure(imu, zx, accel_noise_std=0.5, level_floor=True)[0])
        row("  + level floor, accel_noise_std 2", closure(imu, zx, level_floor=True)[0])
        sweeps = {"shoe": itertools.product((3e7, 1e8, 3e8), (0.0, 0.05, 0.1, 0.125, 0.15)),
                  "freeacc": itertools.product((2.0, 3.0, 4.0), (0.05, 0.1, 0.15))}
        if front is not None:
            v = np.array([np.linalg.norm(p[-1] - p[0]) for p in
                          (xio_track(*front, threshold=thr, margin_s=m)
                           for thr, m in itertools.product((2.0, 3.0, 4.0), (0.05, 0.1, 0.15)))])
            print(f"  sensitivity x-io method (9 settings): median {np.median(v):.3f} m, "
                  f"range {v.min():.3f}-{v.max():.3f} m, below published in {np.mean(v < pub) * 100:.0f} %")
        for det, grid in sweeps.items():
            zvs = [detect_zero_velocity(imu, det, thr, margin_s=m).zv for thr, m in grid]
            for floor in (False, True):
                v = np.array([closure(imu, z, level_floor=floor)[0].error_3d for z in zvs])
                label = "level floor" if floor else "plain"
                print(f"  sensitivity {det} ({label}, {v.size} settings): median {np.median(v):.3f} m, "
                      f"range {v.min():.3f}-{v.max():.3f} m, below published in {np.mean(v < pub) * 100:.0f} %")
    report("bench_zupt_xio", FIGS)
    return 0


if __name__ == "__main__":
    sys.exit(main())
