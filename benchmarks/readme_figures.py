"""The benchmark figures of the README and the user guide: where each comes from, and a check that they still hold.

The pages are the README (the front page) and ``docs/guide/*.md`` (the user
guide); "the README" below means any of them (``documented_text``).

Figures that a quick command gives are checked by ``tests/test_readme.py``
(README examples with an ``expect`` directive) or by the test named beside
them here.  The others come from benchmarks that run for minutes to hours;
each is listed in ``FIGURES`` with the README text that quotes it (verbatim,
up to line breaks: ``tests/test_readme.py`` fails when the README no longer
contains it, so text and list cannot drift apart), the command that
regenerates it, and, where the command's output can be read, a pattern that
reads each figure and the tolerance within which it must agree.

    python benchmarks/readme_figures.py                    # list every figure and its command
    python benchmarks/readme_figures.py --check calib_tc5  # run the command, print README vs measured
    python benchmarks/readme_figures.py --check --max-minutes 15   # every checkable figure of <= 15 min

``--check`` exits 1 when a figure differs from the README by more than its
tolerance.  Tolerances: half a unit of the last digit the README shows for
seeded (deterministic) figures; timings are machine-dependent and are printed
only (``info``).  Commands run from the repository root with this tree's
``src`` first on ``PYTHONPATH``; ``{python}`` is this interpreter and
``{imunav}`` the command line of this tree.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Figure:
    """One README claim: the text that quotes it, the command that regenerates it, how to read it back."""

    name: str
    readme: str  # README text (whitespace-normalised) that quotes the figure(s)
    command: str  # run from the repository root; {python} / {imunav} are filled in
    minutes: float  # rough wall time on the 2-core development machine
    values: dict[str, float] = field(default_factory=dict)  # README value of each figure read back
    patterns: dict[str, str | tuple[str, int]] = field(default_factory=dict)  # regex on the output (, group)
    tol: dict[str, float] = field(default_factory=dict)  # absolute tolerance per figure (default: half a unit)
    bounds: dict[str, tuple[float, float]] = field(default_factory=dict)  # README states a range, not a value
    info: tuple[str, ...] = ()  # machine-dependent figures: printed, never a mismatch
    note: str = ""  # where else it is checked, or why it cannot be run here

    def checkable(self) -> bool:
        return bool(self.patterns)


def _calib(name: str, readme: str, args: str, acc: float, acc_sd: float, gyr: float, gyr_sd: float,
           cover: float) -> Figure:
    return Figure(
        name, readme, f"{{python}} benchmarks/bench_calib_montecarlo.py --runs 100 {args}".strip(), 9.0,
        values={"accel %": acc, "accel sd": acc_sd, "gyro %": gyr, "gyro sd": gyr_sd, "lowest 3σ coverage": cover},
        patterns={"accel %": r"mean success accel ([\d.]+) %", "accel sd": r"mean success accel [\d.]+ % \(sd ([\d.]+)",
                  "gyro %": r"mean success gyro\s+([\d.]+) %", "gyro sd": r"mean success gyro\s+[\d.]+ % \(sd ([\d.]+)",
                  "lowest 3σ coverage": r"lowest coverage: ([\d.]+)"},
        note="seeded: run r simulates with seeds 2r and 2r + 1",
    )


_XIO_ROWS = {  # README row -> (regex of the benchmark's row, column: 1 = 3-D, 2 = horizontal)
    "x-io method": (r"x-io method \(imufusion\), run here", 1),
    "freeacc floor": (r"freeacc 3 m/s\^2[^\n]*\n\s*\+ level floor", 1),
    "freeacc": (r"freeacc 3 m/s\^2[^\n]*\)", 1),
    "freeacc horiz.": (r"freeacc 3 m/s\^2[^\n]*\)", 2),
    "shoe": (r"SHOE 1e8, margin 0\.125 s \(README\)", 1),
    "shoe horiz.": (r"SHOE 1e8, margin 0\.125 s \(README\)", 2),
}

_MC_ROW = r"{f}\s*│\s*([\d.]+) ± ([\d.]+)[^│]*│\s*([\d.]+) ± ([\d.]+)"


def _mc(filt: str, label: str, pitch: float, pitch_sd: float, roll: float, roll_sd: float) -> Figure:
    row = _MC_ROW.format(f=filt)
    return Figure(
        f"attitude_mc_{filt}", f"| {label} | {pitch:.4f} ± {pitch_sd:.4f} | {roll:.4f} ± {roll_sd:.4f} |",
        "{imunav} attitude montecarlo --runs 100 --seed 0", 3.0,
        values={"pitch": pitch, "pitch sd": pitch_sd, "roll": roll, "roll sd": roll_sd},
        patterns={k: (row, i + 1) for i, k in enumerate(("pitch", "pitch sd", "roll", "roll sd"))},
        tol=dict.fromkeys(("pitch", "pitch sd", "roll", "roll sd"), 5e-5),  # the README shows 4 decimals
        note="seeded (--seed 0, run i uses imunav.lab.montecarlo.spawn_generators(0)[i]); same numbers on every executor",
    )


_GINS_ROW = r"\n{k}\s+(-?[\d.]+)"  # a row of bench_gins_outage.py's table: first column


_PYINS_ROW = r"\n{f}\s+" + r"\s+".join([r"([\d.]+) ([\d.]+) ([\d.]+)"] * 3) + r"\s+([\d.]+)"  # bench_gins_pyins
_PYINS_COLS = ("pos N", "pos E", "pos D", "vel N", "vel E", "vel D", "roll", "pitch", "yaw", "us/sample")


def _pyins_row(f: str, values: tuple[float, ...]) -> tuple[dict, dict]:
    """README values and patterns of one row of bench_gins_pyins.py's table (``f``: pyins or imunav)."""
    keys = [f"{f} {c}" for c in _PYINS_COLS]
    return dict(zip(keys, values)), {k: (_PYINS_ROW.format(f=f), i + 1) for i, k in enumerate(keys)}


_PYINS_IMUNAV = _pyins_row("imunav", (0.166, 0.161, 0.241, 0.0204, 0.0237, 0.0116, 0.0512, 0.0375, 0.2319, 2.8))
_PYINS_PYINS = _pyins_row("pyins", (0.168, 0.162, 0.266, 0.0274, 0.0299, 0.0161, 0.0629, 0.0503, 0.3252, 2644.0))


_DRIFT_ROW = r"\n{f}\s+" + r"\s+".join([r"([\d.]+)"] * 6)  # bench_gins_pyins.py --outages: h v 3d r p y
_DRIFT_COLS = ("horizontal m", "vertical m", "3-D m", "roll deg", "pitch deg", "heading deg")
def _drift(imunav: tuple[float, ...], pyins: tuple[float, ...]) -> dict[str, tuple[dict, dict]]:
    """README values and output patterns of the two rows of a ``bench_gins_pyins.py --outages`` table."""
    return {f: ({f"{f} {c}": v for c, v in zip(_DRIFT_COLS, vals)},
                {f"{f} {c}": (_DRIFT_ROW.format(f=f), i + 1) for i, c in enumerate(_DRIFT_COLS)})
            for f, vals in (("imunav", imunav), ("pyins", pyins))}


_DRIFT = _drift((10.01, 1.30, 10.08, 0.069, 0.077, 0.58), (34.38, 2.15, 34.45, 0.175, 0.202, 0.95))
_DRIFT25 = _drift((13.20, 0.93, 13.23, 0.087, 0.067, 0.15), (41.59, 2.02, 41.63, 0.247, 0.223, 0.48))


FIGURES: tuple[Figure, ...] = (
    Figure(
        "cli_hostile",
        "runs the full space: 1622 cases over 29 commands and 368 options (134 numeric, 98 paths), 0 violations, in "
        "51 s on the 2-core machine",
        "{python} benchmarks/bench_cli_hostile.py", 3.0,
        values={"cases": 1622, "violations": 0, "seconds": 51},
        patterns={"cases": r"(\d+) cases in", "violations": r"cases in \d+ s: (\d+) violations",
                  "seconds": r"cases in (\d+) s"},
        tol={"cases": 0, "violations": 0},
        info=("seconds",),
        note="generated from the CLI's options (tests/cli_hostile.py); a seeded sample runs in tests/cli/test_hostile.py",
    ),
    Figure(
        "install_footprint",
        "a venv of 555 MB (no torch, no pyarrow, no h5py, no setuptools in it) and 28 MB of numba caches and bytecode "
        "that `imunav warmup` writes next to the sources, 583 MB in all (target < 600 MB)",
        "{python} benchmarks/bench_install_footprint.py --make-run", 8.0,
        values={"venv MB": 555, "caches MB": 28, "total MB": 583},
        patterns={"venv MB": r"venv (\d+) MB \+", "caches MB": r"sources (\d+) MB =", "total MB": r"= (\d+) MB \("},
        tol={"venv MB": 3, "caches MB": 2, "total MB": 4},
        note="needs the package registry or a warm pip cache (a fresh clone, `make run` with PYTHONDONTWRITEBYTECODE=1)",
    ),
    Figure(
        "first_run_wheel",
        "| `imunav gins run jackal_test2.bag` (ROS bag, odometer, no GNSS) | 79.0 s | 34.9 s | 4.6 s | | "
        "`imunav attitude run sample.ulg --filter mekf` (PX4 ULog) | 46.6 s | 10.8 s | 2.0 s |",
        "{python} benchmarks/bench_first_run.py --wheel", 4.0,
        values={"gins first s": 34.9, "gins warm s": 4.6, "attitude first s": 10.8, "attitude warm s": 2.0},
        patterns={"gins first s": r"gins run jackal_test2\.bag\s+([\d.]+)",
                  "gins warm s": r"gins run jackal_test2\.bag\s+[\d.]+\s+[\d.]+\s+([\d.]+)",
                  "attitude first s": r"attitude run sample\.ulg\s+([\d.]+)",
                  "attitude warm s": r"attitude run sample\.ulg\s+[\d.]+\s+[\d.]+\s+([\d.]+)"},
        info=("gins first s", "gins warm s", "attitude first s", "attitude warm s"),
        note="issue 35; the 'before' column: the same command on the tree before the first-run work (19d2b2a), same "
             "machine and load; timings are machine-dependent",
    ),
    Figure(
        "ulog_px4_agreement",
        "agrees with PX4's onboard `vehicle_attitude` after 10 s to 0.02° / 0.04° / 0.22° RMS in roll / pitch / yaw",
        "{python} -m pytest tests/io/test_ulog.py -q -s", 1.0,
        note="that test asserts < 0.05 / 0.1 / 0.5 deg and prints the measured RMS",
    ),
    Figure(
        "ros_read_speed",
        "runs at 161 % of the speed of iterating and deserializing the same messages with `rosbags` alone (CPU "
        "time, 0.67 s vs 1.08 s), with 279 B of memory per selected message",
        "{python} benchmarks/bench_ros_read.py --size-mb 50", 1.0,
        values={"speed %": 161, "B per message": 279},
        patterns={"speed %": r"imunav at (\d+) % of rosbags", "B per message": r"memory: (\d+) B per selected"},
        info=("speed %", "B per message"),
        note="a 50 MB MCAP bag (the 1 GB default takes about 10 min); CPU time, machine-dependent",
    ),
    Figure(
        "noise_allan_peer",
        "OADEV of 10⁷ samples at 100 log-spaced τ 22× faster than `allantools.oadev` with the same values "
        "(max relative difference 3e-14)",
        "{python} benchmarks/bench_noise_allan.py --skip-big", 3.0,
        values={"speed-up": 22, "max rel diff": 3e-14},
        patterns={"speed-up": r'imunav \("log", 100\)[^\n]*\n[^\n]*\n\s*imunav \(full, with CIs\)\s+[\d.]+ s'
                              r"\s+speed-up\s+([\d.]+)x",
                  "max rel diff": r"max \|rel diff\| ([\d.e+-]+)"},
        info=("speed-up", "max rel diff"),
        note="the benchmark itself checks the targets (>= 10x, rel diff < 1e-9) and prints MET / NOT MET",
    ),
    Figure(
        "noise_allan_memmap",
        "a memory-mapped 10⁸ × 6 record (4.8 GB) in 21–41 s (by machine load) with a peak RSS of 1035 MiB",
        "{python} benchmarks/bench_noise_allan.py --skip-peer", 2.0,
        values={"wall s": 21, "peak RSS MiB": 1035},
        patterns={"wall s": r"wall time ([\d.]+) s", "peak RSS MiB": r"peak RSS\s+([\d.]+) MB"},
        tol={"peak RSS MiB": 60},
        info=("wall s",),
        note="writes a 4.8 GB file once ($IMUNAV_BENCH_DIR or /tmp); RSS = VmHWM of the analysing process",
    ),
    Figure(
        "noise_truth",
        "`benchmarks/bench_noise_truth.py` — 50 runs of the allan_variance_ros simulator parameters: the median of "
        "the signed errors of N and K is below 0.5 % (no bias); the error of one run is typically 0.03 % for N and "
        "5.4 % (accelerometer) / 9.2 % (gyro) for K, which only the longest τ constrain (median |error|); the 95 % "
        "intervals cover the truth in 94–96 % of runs.",
        "{python} benchmarks/bench_noise_truth.py 50", 3.0,
        values={"accel N median |err| %": 0.03, "accel K median |err| %": 5.4,
                "gyro N median |err| %": 0.03, "gyro K median |err| %": 9.2},
        patterns={f"{s} {t}": (rf"(?s){s}: \d+ runs.*?{row}\s+(-?[\d.]+)%\s+(-?[\d.]+)%", g)
                  for s in ("accel", "gyro")
                  for t, row, g in (("N median err %", r"GLS median rel err", 1),
                                    ("K median err %", r"GLS median rel err", 2),
                                    ("N median |err| %", r"GLS median \|rel err\|", 1),
                                    ("K median |err| %", r"GLS median \|rel err\|", 2),
                                    ("N coverage %", r"GLS 95% CI coverage", 1),
                                    ("K coverage %", r"GLS 95% CI coverage", 2))},
        bounds={f"{s} {t}": b for s in ("accel", "gyro")
                for t, b in (("N median err %", (-0.5, 0.5)), ("K median err %", (-0.5, 0.5)),
                             ("N coverage %", (94.0, 96.0)), ("K coverage %", (94.0, 96.0)))},
        note="seeded (numpy default_rng([2026, run, sensor]))",
    ),
    _calib("calib_tc5",
           "| 5 s (preset default, `presets.THESIS_TC_S`) | 99.21 % (sd 0.21) | 99.67 % (sd 0.13) | 0.98 |",
           "", 99.21, 0.21, 99.67, 0.13, 0.98),
    _calib("calib_tc10", "| 10 s (`--tc 10`) | 98.92 % (sd 0.29) | 99.54 % (sd 0.18) | 0.98 |",
           "--tc 10", 98.92, 0.29, 99.54, 0.18, 0.98),
    _calib("calib_tc10_no_noise_model",
           "| 10 s, no noise model (`--no-noise-model`: AR(1) from residuals) | 98.92 % (sd 0.29) | 99.54 % (sd 0.18) "
           "| 0.97 |", "--tc 10 --no-noise-model", 98.92, 0.29, 99.54, 0.18, 0.97),
    _calib("calib_white", "| white noise only (`--tc 0`) | 99.89 % (sd 0.03) | 99.93 % (sd 0.03) | 0.98 |",
           "--tc 0", 99.89, 0.03, 99.93, 0.03, 0.98),
    _mc("lee", "Lee 2012 (c_a = 0.1)", 1.1415, 0.0021, 0.0291, 0.0017),
    _mc("javed", 'Javed 2020 ("Javed-like" reconstruction, c_a = 0.1)', 0.0167, 0.0074, 0.0133, 0.0091),
    _mc("proposed", "proposed (diagonal S, detector D1 τ = 0.02 m/s²)", 0.0311, 0.0020, 0.0315, 0.0020),
    Figure(
        "broad_published",
        "reproduces the published per-trial total RMSE of all 10 trials within 0.0002°; Mahony (Kp 0.74, Ki 0.0012) "
        "within 0.001°",
        "{python} -m pytest tests/attitude/test_broad.py -k all_trials -s -q", 1.0,
        note="checked by that test (largest differences 1.2e-4° Madgwick-C, trial 15; 8.0e-4° Mahony, trial 27)",
    ),
    Figure(
        "broad_table",
        "| **mean** | **2.76** | **2.25** | **1.96** (1.95) = 0.71 × vqf | **1.56** (1.44) = 0.69 × offline VQF |",
        "{python} benchmarks/bench_attitude_broad.py --holdout DIR --workers 2", 60.0,
        note="DIR = data_mat/ of the BROAD repository (20 trials not in the shared data): cannot run here",
    ),
    Figure(
        "attitude_noise_profile",
        "| 9D (total) | profile | 2.502 | 1.210 | 1300 | 0.00 |",
        "{python} benchmarks/bench_attitude_noise_profile.py", 1.0,
        values={"9D defaults": 2.068, "9D profile": 2.502, "6D defaults": 0.634, "6D profile": 0.597},
        patterns={f"{d} {k}": rf"\| mean {d} \(10 trials\) \| {k} \| ([\d.]+)"
                  for d in ("9D", "6D") for k in ("defaults", "profile")},
        note="the shared BROAD trials; deterministic (no seed); the full table is on the noise guide page",
    ),
    Figure(
        "zupt_lstm_cv",
        "| LSTM, `--detector lstm` (guard rule chosen per fold) | **0.176 m (0.46×)** | **0.72 m** | 0.130 m "
        "(worst 0.73 m) |",
        "{python} benchmarks/bench_zupt_lstm_cv.py", 20.0,
        note="trains 6 LSTMs; 'about 15 min on one CPU thread'",
    ),
    Figure(
        "zupt_xio",
        "| x-io's method (imufusion), run by the benchmark | 0.082 m | 0.421 m | | `freeacc --margin-s 0.1 "
        "--level-floor` | 0.057 m | 0.227 m | | `freeacc --margin-s 0.1` (no floor constraint) | 0.130 m (horizontal "
        "0.057) | 0.366 m (horizontal 0.225) | | `shoe --threshold 1e8 --margin-s 0.125 --accel-noise-std 2` | 0.138 m "
        "(horizontal 0.082) | 0.186 m |",
        "{python} benchmarks/bench_zupt_xio.py", 1.0,
        values={f"{w} {k}": v for w, vals in (("short", (0.082, 0.057, 0.130, 0.057, 0.138, 0.082)),
                                               ("long", (0.421, 0.227, 0.366, 0.225, 0.186, None)))
                for k, v in zip(_XIO_ROWS, vals) if v is not None},
        patterns={f"{w} {k}": (rf"(?s){w}_walk:.*?{row}\s+([\d.]+)\s+([\d.]+)", g)
                  for w in ("short", "long") for k, (row, g) in _XIO_ROWS.items()
                  if not (w == "long" and k == "shoe horiz.")},
        tol=dict.fromkeys([f"{w} {k}" for w in ("short", "long") for k in _XIO_ROWS], 5e-4),
        note="the settings sweep below the table is printed by the same command (sensitivity lines)",
    ),
    Figure(
        "gins_outage_nav",
        "RMS of the per-outage maximum drift 0.35 m horizontal, 0.15 m vertical, 0.38 m 3-D, roll / pitch / heading "
        "0.0017° / 0.0014° / 0.0024°, 49 of the 50 outages (98 %) inside the predicted 3σ",
        "{python} benchmarks/bench_gins_outage.py", 5.0,
        values={"outages": 50, "horizontal m": 0.35, "vertical m": 0.15, "3-D m": 0.38, "roll deg": 0.0017,
                "pitch deg": 0.0014, "heading deg": 0.0024, "inside 3σ %": 98},
        patterns={"outages": r"(\d+) outages of 60 s", "horizontal m": _GINS_ROW.format(k="horizontal_m"),
                  "vertical m": _GINS_ROW.format(k="vertical_m"), "3-D m": _GINS_ROW.format(k="3d_m"),
                  "roll deg": _GINS_ROW.format(k="roll_deg"), "pitch deg": _GINS_ROW.format(k="pitch_deg"),
                  "heading deg": _GINS_ROW.format(k="heading_deg"), "inside 3σ %": r"predicted 3 sigma[^:]*: (\d+) %"},
        note="seeded (--seed 1): navigation_a15, 1 h at 200 Hz, 3 filter runs (about 1 min CPU)",
    ),
    Figure(
        "gins_outage_mems",
        "odometer + NHC shrink the horizontal outage drift from 10.06 m to 0.71 m (14.2×)",
        "{python} benchmarks/bench_gins_outage.py --mems", 2.0,
        values={"GNSS only m": 10.06, "ODO + NHC m": 0.71, "ratio": 14.2},
        patterns={"GNSS only m": (r"\nhorizontal_m\s+([\d.]+)\s+([\d.]+)", 1),
                  "ODO + NHC m": (r"\nhorizontal_m\s+([\d.]+)\s+([\d.]+)", 2),
                  "ratio": r"horizontal drift ([\d.]+)x smaller"},
        note="seeded (--seed 1): mems_adis16465, 1 h at 100 Hz, 55 outages; acceptance >= 3x",
    ),
    Figure(
        "gins_speed",
        "2.26 µs per IMU sample for 21 states at 200 Hz with GNSS at 1 Hz (one hour, 720,001 samples, in 1.63 s CPU",
        "{python} benchmarks/bench_gins_speed.py", 1.0,
        values={"us per sample": 2.26, "CPU s": 1.63},
        patterns={"us per sample": r"\(([\d.]+) us per sample", "CPU s": r"min CPU ([\d.]+) s"},
        info=("us per sample", "CPU s"),
        note="CPU time (time.process_time), best of 3 after a warm-up; acceptance <= 3 us per sample, < 10 s wall",
    ),
    Figure(
        "gins_log_speed",
        "runs through `imunav gins run` in 15.4 s of CPU time, 15.3 s wall on 2 cores",
        "{python} benchmarks/bench_gins_log_speed.py", 2.0,
        values={"CPU s": 15.4, "wall s": 15.3},
        patterns={"CPU s": r"s wall, ([\d.]+) s CPU", "wall s": r"2 cores\): ([\d.]+) s wall"},
        info=("CPU s", "wall s"),
        note="one-hour ROS 2 bag (714,383 IMU messages); CPU time (user + system) of the command, machine-dependent; "
             "acceptance <= 30 s on 2 cores; the 77 s before is the same command's CPU time at commit 55dd534",
    ),
    Figure(
        "gins_latency_bound",
        "an estimator that knows the true trajectory and seeks only the latency errs by 22 ms RMS and is within 20 ms "
        "on 62 % of 100 drives",
        "{python} benchmarks/bench_gins_latency_bound.py", 0.2,
        values={"sd ms": 22, "within 20 ms %": 62},
        patterns={"sd ms": r"sd ([\d.]+) ms", "within 20 ms %": r"within 20 ms on (\d+) %"},
        note="seeded drives 500-599 (the ideal estimator: truth known but for the latency)",
    ),
    Figure(
        "gins_robot_consistency",
        "drives 400–429 NEES 2.27, 3.09 and 3.38 from the start (2.23, 2.83, 3.18 after 60 s), NIS 0.994, 0.992 and "
        "1.017",
        "{python} benchmarks/bench_gins_robot_consistency.py --first-seed 400 --truths matched", 1.0,
        values={"NEES position": 2.27, "NEES velocity": 3.09, "NEES attitude": 3.38, "NIS GNSS": 0.994,
                "NIS odometer": 0.992, "NIS NHC": 1.017},
        patterns={"NEES position": r'"nees_from_start": \{\s*"position": ([\d.]+)',
                  "NEES velocity": r'"nees_from_start": \{\s*"position": [\d.]+,\s*"velocity": ([\d.]+)',
                  "NEES attitude": r'"nees_from_start": \{[^}]*"attitude": ([\d.]+)',
                  "NIS GNSS": r'"nis_gnss_position": \{\s*"mean_per_dof": ([\d.]+)',
                  "NIS odometer": r'"nis_odometer": \{\s*"mean_per_dof": ([\d.]+)',
                  "NIS NHC": r'"nis_nhc": \{\s*"mean_per_dof": ([\d.]+)'},
        note="seeded drives 400-429 (held out: first run after the last change of the filter); 30 drives in about "
             "30 s; --first-seed 100 and 200 give the README's in-sample figures",
    ),
    Figure(
        "gins_pyins",
        "RMSE of position N / E / D 0.166 / 0.161 / 0.241 m (pyins 0.168 / 0.162 / 0.266 m), velocity 0.0204 / 0.0237 "
        "/ 0.0116 m/s (pyins 0.0274 / 0.0299 / 0.0161 m/s), roll / pitch / yaw 0.0512° / 0.0375° / 0.2319° (pyins "
        "0.0629° / 0.0503° / 0.3252°); imunav / pyins ratio of the norms of the axes 0.942 (position), 0.764 "
        "(velocity), 0.718 (attitude).",
        "{python} benchmarks/bench_gins_pyins.py", 10.0,
        values={**_PYINS_IMUNAV[0], **_PYINS_PYINS[0], "position ratio": 0.942, "velocity ratio": 0.764,
                "attitude ratio": 0.718, "speed-up": 961},
        patterns={**_PYINS_IMUNAV[1], **_PYINS_PYINS[1],
                  **{f"{k} ratio": rf"{k}\s+RMSE[^\n]*ratio imunav / pyins ([\d.]+)"
                     for k in ("position", "velocity", "attitude")},
                  "speed-up": r"imunav is (\d+)x faster"},
        info=("imunav us/sample", "pyins us/sample", "speed-up"),
        note="seeded (--seed 1; pyins is deterministic); pyins runs 2.6 ms of CPU per IMU sample with "
             "OMP_NUM_THREADS=1 (6.7 ms measured earlier without it), about 3 min CPU, 7 min on the loaded 2-core machine",
    ),
    Figure(
        "gins_pyins_seeds",
        "Over 10 paired seeds (`python benchmarks/bench_gins_pyins.py --seeds 10 --seed 101 --duration 300 --fs 50`) "
        "the ratio per axis, mean ± standard error over seeds, is 0.995 ± 0.002 / 0.995 ± 0.003 / 0.945 ± 0.020 for "
        "position N / E / D, 0.840 ± 0.008 for the velocity norm and 0.813 ± 0.048 for the attitude norm",
        "{python} benchmarks/bench_gins_pyins.py --seeds 10 --seed 101 --duration 300 --fs 50", 20.0,
        values={f"{k} {c}": v for k, vals in (("pos N", (0.995, 0.002)), ("pos E", (0.995, 0.003)),
                                              ("pos D", (0.945, 0.020)), ("|vel|", (0.840, 0.008)),
                                              ("|att|", (0.813, 0.048))) for c, v in zip(("ratio", "SE"), vals)},
        patterns={f"{k} {c}": (r"\n" + re.escape(k) + r"\s+[\d.]+\s+[\d.]+\s+([\d.]+)\s+([\d.]+)", g)
                  for k in ("pos N", "pos E", "pos D", "|vel|", "|att|") for g, c in ((1, "ratio"), (2, "SE"))},
        note="seeded (seeds 101-110, hold-out: not used to find the cause of the one-seed N/E gap); 10 pyins runs "
             "of 15,000 samples, about 8 min CPU with OMP_NUM_THREADS=1 (--pyins-cache FILE.npz keeps them)",
    ),
    Figure(
        "gins_pyins_outages",
        "RMS of the per-outage maximum drift 10.01 / 1.30 / 10.08 m horizontal / vertical / 3-D (pyins 34.38 / 2.15 / "
        "34.45 m), roll / pitch / heading 0.069° / 0.077° / 0.58° (pyins 0.175° / 0.202° / 0.95°)",
        "{python} benchmarks/bench_gins_pyins.py --outages --outages-only --duration 425 --converge 60 --fs 50", 22.0,
        values={"outages": 6, **_DRIFT["imunav"][0], **_DRIFT["pyins"][0]},
        patterns={"outages": r"(\d+) outages; RMS", **_DRIFT["imunav"][1], **_DRIFT["pyins"][1]},
        tol={"imunav vertical m": 0.005},  # the README shows 1.30
        note="seeded (--seed 1); 3 pyins runs, about 15 min CPU (21 min on the loaded 2-core machine)",
    ),
    Figure(
        "gins_pyins_outages_25",
        "RMS of the per-outage maximum drift 13.20 / 0.93 / 13.23 m horizontal / vertical / 3-D (pyins 41.59 / 2.02 / "
        "41.63 m), roll / pitch / heading 0.087° / 0.067° / 0.15° (pyins 0.247° / 0.223° / 0.48°)",
        "{python} benchmarks/bench_gins_pyins.py --outages --outages-only --duration 1800 --converge 300 --fs 50",
        45.0,
        values={"outages": 25, **_DRIFT25["imunav"][0], **_DRIFT25["pyins"][0]},
        patterns={"outages": r"(\d+) outages; RMS", **_DRIFT25["imunav"][1], **_DRIFT25["pyins"][1]},
        tol={k: 0.005 for k in ("imunav horizontal m", "imunav vertical m", "imunav 3-D m", "pyins horizontal m",
                                "pyins vertical m", "pyins 3-D m")},
        note="seeded (--seed 1); 3 pyins runs of 90,000 samples, about 40 min CPU (--pyins-cache FILE.npz keeps them)",
    ),
    Figure(
        "airdata_robust",
        "a per-channel ±2σ gate cannot reject more than ≈ 89 % of ×15 outliers (≈ 11 % of them fall inside ±2σ); "
        "the vector χ² gate (`--robust nis`) rejects ≈ 99.4 % of these whole-sensor outliers and only 0.1 % of good "
        "data",
        "{python} benchmarks/bench_airdata_thesis.py", 6.0,
        values={"gate2 rejected": 0.89, "nis rejected": 0.994, "nis false rejections": 0.001},
        patterns={"gate2 rejected": r"gate2\s+([\d.]+)", "nis rejected": r"\n\s+nis\s+([\d.]+)",
                  "nis false rejections": r"\n\s+nis\s+[\d.]+\s+([\d.]+)"},
        tol={"gate2 rejected": 0.005, "nis rejected": 0.0005, "nis false rejections": 0.0005},
        note="2000 seeded runs (--seed 0); also prints P44 (checked by the README test) and the wind figures",
    ),
    Figure(
        "airdata_alg1",
        "alarms on ≈ 43 % of fault-free steps",
        "{python} benchmarks/bench_airdata_faults.py", 1.0,
        values={"alg1 thesis-threshold alarms": 0.43},
        patterns={"alg1 thesis-threshold alarms": r"alg1\s+[\d.]+\s+[\d.]+\s+[\d.]+\s+[\d.]+\s+([\d.]+)"},
        tol={"alg1 thesis-threshold alarms": 0.005},
        note="2000 seeded runs (--seed 0); the thesis's 28.87 against the calibrated threshold",
    ),
)


def _normalise(text: str) -> str:
    return " ".join(text.split())


def documented_text() -> str:
    """The README and the user guide's pages (``docs/guide/*.md``) as one text, where each figure is quoted."""
    pages = [ROOT / "README.md", *sorted((ROOT / "docs" / "guide").glob("*.md"))]
    return "\n".join(p.read_text(encoding="utf-8") for p in pages)


def _command(f: Figure) -> str:
    imunav = f"{sys.executable} -m imunav.cli.main"
    return f.command.format(python=sys.executable, imunav=imunav)


def _decimals(x: float) -> float:
    """Half a unit of the last digit of ``x`` as the README writes it."""
    s = repr(float(x))
    if "e" in s:
        return abs(x) * 0.5
    frac = s.partition(".")[2].rstrip("0")
    return 0.5 * 10.0 ** (-len(frac))


def check(f: Figure) -> list[tuple[str, str, float | None, bool]]:
    """Run the figure's command; (figure, README value or range, measured, agrees) for each figure."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), *filter(None, [env.get("PYTHONPATH")])])
    env.setdefault("COLUMNS", "160")
    t0 = time.time()
    res = subprocess.run(_command(f), shell=True, cwd=ROOT, env=env, capture_output=True, text=True)
    out = res.stdout + res.stderr
    print(f"  ({time.time() - t0:.0f} s, exit {res.returncode})")
    rows = []
    for key, pat in f.patterns.items():
        regex, group = pat if isinstance(pat, tuple) else (pat, 1)
        m = re.search(regex, out)
        got = float(m.group(group)) if m else None
        if key in f.bounds:
            lo, hi = f.bounds[key]
            ok = got is not None and lo <= got <= hi
            rows.append((key, f"{lo:g}-{hi:g}", got, ok))
            continue
        want = f.values[key]
        tol = f.tol.get(key, _decimals(want))
        ok = key in f.info or (got is not None and abs(got - want) <= tol + 1e-12)
        rows.append((key, f"{want:g}", got, ok))
    if res.returncode != 0:
        print(out[-3000:])
        rows.append(("exit status", "0", float(res.returncode), False))
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--check", nargs="*", metavar="NAME",
                    help="run these figures' commands (none named: every checkable one)")
    ap.add_argument("--max-minutes", type=float, default=None,
                    help="with --check and no NAME: only the figures this quick")
    a = ap.parse_args(argv)
    readme = _normalise(documented_text())
    by_name = {f.name: f for f in FIGURES}
    if a.check is None:
        for f in FIGURES:
            state = "in README" if _normalise(f.readme) in readme else "NOT IN README"
            how = "checkable" if f.checkable() else "by hand"
            print(f"{f.name:28s} ~{f.minutes:4.0f} min  {how:9s} {state}\n    {f.command}\n    {f.note}".rstrip())
        return 0
    unknown = [n for n in a.check if n not in by_name]
    if unknown:
        ap.error(f"unknown figure(s) {unknown}; choose from {sorted(by_name)}")
    chosen = [by_name[n] for n in a.check] or [f for f in FIGURES if f.checkable()
                                                and (a.max_minutes is None or f.minutes <= a.max_minutes)]
    bad = 0
    for f in chosen:
        print(f"{f.name}: {_command(f)}")
        if _normalise(f.readme) not in readme:
            print("  README no longer quotes:", f.readme)
            bad += 1
        if not f.checkable():
            print("  (no pattern: compare by hand)", f.note)
            continue
        for key, want, got, ok in check(f):
            flag = "info" if key in f.info else ("ok" if ok else "MISMATCH")
            print(f"  {key:20s} README {want:<10s} measured {'-' if got is None else f'{got:g}':<10s} {flag}")
            bad += not ok
    print("all figures agree" if not bad else f"{bad} mismatch(es)")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
