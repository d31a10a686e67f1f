"""Truth recovery of the noise fit on the allan_variance_ros simulator parameters.

50 seeded simulations (400 Hz, 11,000 s) of white rate noise N plus rate random
walk K, for the accelerometer (N = 0.0025020 m/s^2/sqrt(Hz), K = 6.9724e-5
m/s^3/sqrt(Hz)) and the gyro (N = 1.8883e-4 rad/s/sqrt(Hz), K = 2.5565e-6
rad/s^2/sqrt(Hz)) of references.md §1.  For each: overlapping ADEV (octave
tau), GLS-NNLS fit with BIC term selection over Q, N, B, K, R, and the classic
slope read-outs.  Prints median relative error (signed and absolute) of N and
K, and how often the 95 % intervals contain the truth.

Acceptance: median relative error of N and K <= 5 %, 95 % intervals cover the
truth in >= 90 % of runs.

Run: PYTHONPATH=src python benchmarks/bench_noise_truth.py [n_runs]
"""

from __future__ import annotations

import sys
import time

import numpy as np
from _before_after import report  # the before (a308974) / after lines

from imunav.noise import allan_deviation, fit_noise

SENSORS = {
    "accel": (0.0025020, 6.9724e-05, "m/s^2"),
    "gyro": (1.8883e-04, 2.5565e-06, "rad/s"),
}
FS, DURATION = 400.0, 11_000.0


def simulate(n_d: float, k: float, rng: np.random.Generator) -> np.ndarray:
    n = int(FS * DURATION)
    white = rng.normal(scale=n_d * np.sqrt(FS), size=n)
    walk = np.cumsum(rng.normal(scale=k / np.sqrt(FS), size=n))
    return white + walk


def main(n_runs: int = 50) -> None:
    t0 = time.perf_counter()
    FIGS = {}  # headline figures for the before/after lines
    for name, (n_true, k_true, unit) in SENSORS.items():
        est = []
        inside = []
        slope = []
        for seed in range(n_runs):
            rng = np.random.default_rng([2026, seed, 0 if name == "accel" else 1])
            y = simulate(n_true, k_true, rng)
            r = allan_deviation(y, FS, "octave", units=unit)
            f = fit_noise(r)
            iN, iK = f.names.index("N"), f.names.index("K")
            est.append((f.value[iN, 0], f.value[iK, 0]))
            inside.append((f.ci_lo[iN, 0] <= n_true <= f.ci_hi[iN, 0], f.ci_lo[iK, 0] <= k_true <= f.ci_hi[iK, 0]))
            slope.append((f.slopes.value[1, 0], f.slopes.value[3, 0]))
        est = np.array(est)
        inside = np.array(inside)
        slope = np.array(slope)
        truth = np.array([n_true, k_true])
        rel = est / truth - 1
        rel_s = slope / truth - 1
        print(f"\n{name}: {n_runs} runs, {FS:g} Hz x {DURATION:g} s, truth N={n_true:.5g} K={k_true:.5g}")
        print(f"{'':24s}{'N':>12s}{'K':>12s}")
        print(f"{'GLS median rel err':24s}{np.median(rel[:, 0]):12.2%}{np.median(rel[:, 1]):12.2%}")
        print(f"{'GLS median |rel err|':24s}{np.median(abs(rel[:, 0])):12.2%}{np.median(abs(rel[:, 1])):12.2%}")
        print(f"{'GLS 95% CI coverage':24s}{inside[:, 0].mean():12.0%}{inside[:, 1].mean():12.0%}")
        print(f"{'slope median rel err':24s}{np.median(rel_s[:, 0]):12.2%}{np.median(rel_s[:, 1]):12.2%}")
        print(f"{'slope median |rel err|':24s}{np.median(abs(rel_s[:, 0])):12.2%}{np.median(abs(rel_s[:, 1])):12.2%}")
        FIGS.update({f"{name} GLS median rel err {p}": np.median(rel[:, i]) for i, p in enumerate("NK")})
        FIGS.update({f"{name} GLS CI coverage {p}": inside[:, i].mean() for i, p in enumerate("NK")})
        ok = (np.all(np.abs(np.median(rel, axis=0)) <= 0.05) and np.all(inside.mean(axis=0) >= 0.9))
        print(f"acceptance (median rel err <= 5 %, coverage >= 90 %): {'MET' if ok else 'NOT MET'}")
    print(f"\ntotal {time.perf_counter() - t0:.0f} s")
    report("bench_noise_truth", {"total s": time.perf_counter() - t0, **FIGS}, times=("total s",))


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 50)
