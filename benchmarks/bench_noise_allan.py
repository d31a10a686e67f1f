"""Speed of the Allan deviation: imunav vs allantools, and a 1e8 x 6 memory-mapped record.

1. Overlapping ADEV of 10^7 white-noise samples at 100 log-spaced tau:
   imunav.noise.allan_deviation vs allantools.oadev, side by side in this run;
   prints both times, the ratio (target >= 10x) and the max relative
   difference of the deviations (target rtol 1e-9).  imunav is timed twice:
   the full call (noise identification + EDF + chi^2 intervals at every tau)
   and with the noise type fixed (alpha=0, no identification).
2. 10^8 samples x 6 channels, float64 .npy opened with mmap_mode="r"
   (4.8 GB on disk, created once in $IMUNAV_BENCH_DIR or /tmp), octave tau,
   all channels in one call, run in a fresh subprocess: wall time (target
   < 60 s) and peak resident memory of the subprocess (target < 2 GB).

Peak RSS is read from VmHWM in /proc/self/status (the high-water mark of the
child's own address space).  getrusage's ru_maxrss is not used on Linux: the
child is started by fork/vfork + exec, and exec folds the parent's high-water
mark into the child's ru_maxrss, so it reported this script's own peak (the
peer comparison above, or the 4.8 GB written while creating the file) instead
of the child's.

Run: PYTHONPATH=src python benchmarks/bench_noise_allan.py [--skip-big] [--skip-peer]
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

N_PEER = 10_000_000
N_BIG = 100_000_000


def peer_comparison() -> None:
    import allantools

    from imunav.noise import allan_deviation, tau_grid

    y = np.random.default_rng(1).normal(size=N_PEER)
    fs = 100.0
    grids = {
        "plain 100-point logspace": np.unique(np.round(np.logspace(0, np.log10(N_PEER // 2), 100))) / fs,
        'imunav ("log", 100)': tau_grid(N_PEER, fs, ("log", 100)),
    }
    allan_deviation(y[:10_000], fs, grids['imunav ("log", 100)'][:10])  # numba compile / cache load, not timed
    print(f"OADEV of {N_PEER:.0e} samples ({os.cpu_count()} CPUs, load {os.getloadavg()[0]:.1f})")
    ok = True
    for name, taus in grids.items():
        t0 = time.perf_counter()
        r = allan_deviation(y, fs, taus)
        t_full = time.perf_counter() - t0
        t0 = time.perf_counter()
        allan_deviation(y, fs, taus, alpha=0)
        t_fixed = time.perf_counter() - t0
        t0 = time.perf_counter()
        t_at, dev_at, _, _ = allantools.oadev(y, rate=fs, data_type="freq", taus=taus)
        t_peer = time.perf_counter() - t0
        common, ia, ib = np.intersect1d(np.round(r.tau * fs), np.round(t_at * fs), return_indices=True)
        rel = float(np.max(np.abs(r.adev[ia] / dev_at[ib] - 1)))
        print(f" tau grid: {name} ({r.tau.size} tau)")
        print(f"  allantools.oadev            {t_peer:8.2f} s")
        print(f"  imunav (full, with CIs)     {t_full:8.2f} s   speed-up {t_peer / t_full:6.1f}x")
        print(f"  imunav (alpha fixed)        {t_fixed:8.2f} s   speed-up {t_peer / t_fixed:6.1f}x")
        print(f"  max |rel diff| {rel:.2e} over {common.size} common tau (target 1e-9): "
              f"{'MET' if rel < 1e-9 else 'NOT MET'}")
        ok &= rel < 1e-9 and t_peer / t_full >= 10
    print(f"  speed (>= 10x) and equality targets: {'MET' if ok else 'NOT MET'}")


_CHILD = r"""
import resource, sys, time
import numpy as np
from imunav.noise import allan_deviation
x = np.load(sys.argv[1], mmap_mode="r")
allan_deviation(np.zeros((1000, 1)), 100.0)  # compile / load the kernels, not timed
t0 = time.perf_counter()
r = allan_deviation(x, 400.0, "octave")
dt = time.perf_counter() - t0
try:  # Linux: the child's own high-water mark (ru_maxrss also holds the parent's, see the docstring)
    with open("/proc/self/status") as fh:
        peak = next(float(l.split()[1]) for l in fh if l.startswith("VmHWM:")) / 1024.0
except (OSError, StopIteration):
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
print(f"{dt:.2f} {peak:.0f} {r.tau.size} {r.adev[0, 0]:.6g}")
"""


def big_memmap() -> None:
    d = Path(os.environ.get("IMUNAV_BENCH_DIR", "/tmp"))
    path = d / "imunav_bench_1e8x6.npy"
    if not path.exists() or path.stat().st_size < N_BIG * 6 * 8:
        print(f"creating {path} ({N_BIG * 6 * 8 / 1e9:.1f} GB) ...", flush=True)
        mm = np.lib.format.open_memmap(path.with_suffix(".tmp.npy"), mode="w+", dtype=np.float64,
                                       shape=(N_BIG, 6))
        rng = np.random.default_rng(7)
        step = 5_000_000
        for i in range(0, N_BIG, step):
            mm[i : i + step] = rng.normal(size=(min(step, N_BIG - i), 6))
        mm.flush()
        del mm
        os.replace(path.with_suffix(".tmp.npy"), path)
    env = dict(os.environ)
    env["PYTHONPATH"] = str(Path(__file__).resolve().parents[1] / "src") + os.pathsep + env.get("PYTHONPATH", "")
    out = subprocess.run([sys.executable, "-c", _CHILD, str(path)], capture_output=True, text=True, env=env,
                         check=True).stdout.split()
    dt, peak, nt, a0 = float(out[0]), float(out[1]), int(out[2]), float(out[3])
    print(f"OADEV of a memory-mapped {N_BIG:.0e} x 6 float64 record, octave tau ({nt} tau), all channels in one call")
    print(f"  wall time {dt:.1f} s (target < 60 s): {'MET' if dt < 60 else 'NOT MET'}")
    print(f"  peak RSS  {peak:.0f} MB (target < 2048 MB): {'MET' if peak < 2048 else 'NOT MET'}")
    print(f"  check: ADEV(tau0) of unit white noise = {a0:.5f} (expect 1.0 +- 1e-4)")


if __name__ == "__main__":
    if "--skip-peer" not in sys.argv:
        peer_comparison()
    if "--skip-big" not in sys.argv:
        big_memmap()
