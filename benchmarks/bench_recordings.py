"""Recordings: static-interval detection on 1e7 samples and I/O throughput.

Run: ``python benchmarks/bench_recordings.py [n_static] [n_io]``.
Prints imunav's time for ``static_intervals`` on a 6-axis record of
``n_static`` samples (default 1e7) next to a pandas ``rolling().var()``
implementation of the same statistic (the usual way of writing it), and the
write / read time and file size of every format for ``n_io`` samples
(default 1e6), checking that each read gives back the written bits.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time

import numpy as np
import pandas as pd
from _before_after import report  # the before (a308974) / after lines

from imunav.io import FORMATS, read_imu, write_imu
from imunav.timeseries import ImuData, static_intervals
from imunav.units import G0

FIGS: dict[str, float] = {}  # headline figures for the before/after lines


def _record(n: int, seed: int = 0) -> ImuData:
    r = np.random.default_rng(seed)
    fs = 1000.0
    gyro = r.normal(0, 1e-3, (n, 3))
    accel = r.normal(0, 1e-2, (n, 3)) + [0, 0, -G0]
    # alternate 20 s rest / 5 s motion
    period = int(25 * fs)
    phase = np.arange(n) % period
    moving = phase >= int(20 * fs)
    gyro[moving] += 0.5
    accel[moving, 0] += 2.0 * np.sin(phase[moving] / fs * 7.0)
    return ImuData(np.arange(n) / fs, gyro, accel)


def bench_static(n: int) -> None:
    d = _record(n)
    static_intervals(d.slice(0, 10_000), window_s=0.5)  # numba compile / cache load
    t0 = time.perf_counter()
    si = static_intervals(d, window_s=1.0, use_gyro=True)
    t_imunav = time.perf_counter() - t0
    w = si.window
    t0 = time.perf_counter()
    sa = pd.DataFrame(d.accel).rolling(w).var(ddof=0).sum(axis=1).to_numpy()[w - 1 :]
    sg = pd.DataFrame(d.gyro).rolling(w).var(ddof=0).sum(axis=1).to_numpy()[w - 1 :]
    quiet = (sa <= si.accel_threshold) & (sg <= si.gyro_threshold)
    t_pandas = time.perf_counter() - t0
    print(f"static_intervals, {n:.0e} samples x 6 axes: imunav {t_imunav:.2f} s (full detector, {len(si)} intervals); "
          f"pandas rolling var (statistic + threshold only) {t_pandas:.2f} s; ratio {t_pandas / t_imunav:.1f}x")  # fmt: skip
    # same statistic, same windows: the static windows must agree
    s2 = static_intervals(d, window_s=1.0, threshold=(si.accel_threshold, si.gyro_threshold), use_gyro=True)
    assert np.array_equal(s2.mask, si.mask)
    print(f"  pandas marks {quiet.mean():.3f} of the windows static; imunav marks {si.mask.mean():.3f} of the samples")
    FIGS.update({"static_intervals ns/sample": 1e9 * t_imunav / n, "pandas rolling var ns/sample": 1e9 * t_pandas / n, "static intervals found": len(si), "static share": si.mask.mean()})


def bench_io(n: int) -> None:
    d = _record(n, seed=1).with_(temp=np.full(n, 25.0))
    with tempfile.TemporaryDirectory() as tmp:
        print(f"I/O, {n:.0e} samples (t, gyro, accel, temp):")
        for fmt in FORMATS:
            p = os.path.join(tmp, "rec" + {"csv": ".csv", "parquet": ".parquet", "hdf5": ".h5", "npz": ".npz"}.get(fmt, ".mat"))
            t0 = time.perf_counter()
            write_imu(d, p, format=fmt)
            t1 = time.perf_counter()
            back = read_imu(p)
            t2 = time.perf_counter()
            exact = all(np.array_equal(getattr(d, k).view(np.uint64), getattr(back, k).view(np.uint64)) for k in ("t", "gyro", "accel", "temp"))
            FIGS.update({f"{fmt} write us/sample": 1e6 * (t1 - t0) / n, f"{fmt} read us/sample": 1e6 * (t2 - t1) / n})
            print(f"  {fmt:8s} write {t1 - t0:6.2f} s  read {t2 - t1:6.2f} s  {os.path.getsize(p) / 1e6:7.1f} MB  bit-exact {exact}")


if __name__ == "__main__":
    n_static = int(float(sys.argv[1])) if len(sys.argv) > 1 else 10_000_000
    n_io = int(float(sys.argv[2])) if len(sys.argv) > 2 else 1_000_000
    bench_static(n_static)
    bench_io(n_io)
    report("bench_recordings", FIGS, times=[k for k in FIGS if k.endswith("/sample")])
