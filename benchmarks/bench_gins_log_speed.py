"""``imunav gins run`` on a long ROS 2 bag, end to end (issue 24, acceptance "speed"): a one-hour log with a
200 Hz IMU (720,000 ``sensor_msgs/Imu``), GNSS at 5 Hz and wheel odometry at 50 Hz, read from a ROS 2 bag and
run in <= 30 s on 2 cores; the reading and filtering times printed separately.

The bag is the simulated ground robot (:func:`imunav.sim.robot_log.simulate_robot_log`: its loops with stops,
the IMU at 200 Hz, the odometer at 50 Hz, GNSS at 5 Hz) written with :func:`imunav.io.rosbag.write_bag` (MCAP by
default); making it is not timed.  Then, each in a fresh subprocess pinned to ``--cores`` cores (numba kernels
compiled and cached by a warm-up run on a short log first):

* **end to end**: ``imunav gins run BAG --out DIR --quiet`` (``--smoother`` with ``--smoother``), wall time and
  CPU time (user + system: what the wall time is on an otherwise idle machine, the run being single-threaded but
  for short numpy / BLAS stretches), with the load average around it;
* **phases**: the calls the command makes, timed one by one: reading (``read_nav_sources``: the IMU topic, then
  the aids), ``run_log`` split by a profile into the rest detection, the mounting estimate, the filter pass and
  the smoother, and the rest (the initial state, the configuration), writing the files (``write_log_outputs``
  without figures) and the figures.

Run:  PYTHONPATH=src python benchmarks/bench_gins_log_speed.py [--minutes 60] [--cores 2] [--smoother]
      [--storage mcap|sqlite3] [--keep DIR]
      (``--minutes 6`` for a quick look; the times scale with the log's length.)
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

_PHASES = r"""
import cProfile, json, pstats, sys, time
from pathlib import Path
t0 = time.perf_counter()
from imunav.ins.gins import logrun, outputs
from imunav.io import navlog
t_import = time.perf_counter() - t0
bag, out, smoother = sys.argv[1], Path(sys.argv[2]), sys.argv[3] == "1"
out.mkdir()
t = {"import_s": t_import}
c = time.perf_counter()
imu_only = navlog.logs.read_log_imu(bag, topic="/imu/data")
t["read_imu_topic_s"] = time.perf_counter() - c
c = time.perf_counter()
src = navlog.read_nav_sources(bag)
t["read_s"] = time.perf_counter() - c
prof = cProfile.Profile()
c = time.perf_counter()
prof.enable()
run = logrun.run_log(src, logrun.LogRunOptions(smoother=smoother))
prof.disable()
t["run_log_s"] = time.perf_counter() - c
st = pstats.Stats(prof).stats
def cum(name, file_part):
    return sum(v[3] for k, v in st.items() if k[2] == name and file_part in k[0])
t["rest_detection_s"] = cum("_static", "logrun")
t["mounting_s"] = cum("estimate_mounting", "mounting")
t["filter_s"] = cum("run", "gins/filter")
t["smoother_s"] = cum("rts_smooth", "smoother") if smoother else 0.0
c = time.perf_counter()
outputs.write_log_outputs(out, run, src, plots=False)
t["write_s"] = time.perf_counter() - c
c = time.perf_counter()
outputs.write_figures(out, result=run.result, gnss=src.gnss)
t["figures_s"] = time.perf_counter() - c
t["samples"] = {"imu": int(src.imu.n), "gnss": int(src.gnss.n), "odometer": int(src.odometer.t.size)}
t["duration_s"] = float(src.imu.t[-1])
print(json.dumps(t))
"""


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT / "src") + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


def _pinned(cmd: list[str], cores: int) -> list[str]:
    """``cmd`` on the first ``cores`` CPUs (taskset when present)."""
    if shutil.which("taskset") and os.cpu_count() and cores < (os.cpu_count() or 1):
        return ["taskset", "-c", f"0-{cores - 1}", *cmd]
    return cmd


def make_bag(path: Path, minutes: float, storage: str) -> dict[str, float]:
    """The robot drive of about ``minutes`` at 200 Hz (IMU), 50 Hz (odometer), 5 Hz (GNSS) as a ROS 2 bag."""
    from imunav.io.rosbag import write_bag
    from imunav.sim.robot_log import simulate_robot_log

    c = time.perf_counter()
    # one loop of robot_loops: 85 m and about 98 s at 1 m/s (turns, ramps and a 5 s stop); 15 s at rest around
    loops = max(1, round((minutes * 60.0 - 15.0) / 98.0))
    log = simulate_robot_log(7, distance_m=85.0 * loops, imu_rate_hz=200.0, odometer_rate_hz=50.0, gnss_rate_hz=5.0)
    t_sim = time.perf_counter() - c
    c = time.perf_counter()
    write_bag(path, {"/imu/data": log.imu, "/odom": log.odometer, "/gps/fix": log.gnss}, storage=storage,
              frame_ids={"/imu/data": "imu_link", "/gps/fix": "gps"})
    return {"simulate_s": t_sim, "write_bag_s": time.perf_counter() - c, "duration_s": float(log.imu.t[-1]),
            "imu": log.imu.n, "gnss": log.gnss.n, "odometer": int(log.odometer.t.size),
            "bag_mb": sum(f.stat().st_size for f in path.rglob("*") if f.is_file()) / 1e6}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, default=60.0, help="length of the log, min (default 60)")
    ap.add_argument("--cores", type=int, default=2, help="CPUs the timed runs may use (taskset)")
    ap.add_argument("--storage", default="mcap", choices=("mcap", "sqlite3"))
    ap.add_argument("--smoother", action="store_true", help="also run (and time) the RTS smoother")
    ap.add_argument("--keep", type=Path, default=None, help="keep the bag and the outputs in this new folder")
    a = ap.parse_args()
    work = a.keep if a.keep is not None else Path(tempfile.mkdtemp(prefix="bench_gins_log_"))
    work.mkdir(parents=True, exist_ok=True)
    try:
        bag = work / "long_ros2"
        made = make_bag(bag, a.minutes, a.storage)
        print(f"bag: {made['imu']} IMU, {made['odometer']} odometry, {made['gnss']} GNSS messages over "
              f"{made['duration_s'] / 60:.1f} min, {made['bag_mb']:.0f} MB {a.storage} (simulated in "
              f"{made['simulate_s']:.1f} s, written in {made['write_bag_s']:.1f} s; not timed)", flush=True)
        warm = work / "warm"
        warm.mkdir()
        from imunav.sim.robot_log import simulate_robot_log, write_robot_log

        write_robot_log(simulate_robot_log(1, distance_m=80.0), warm, formats=("ros2",))
        py = sys.executable
        flags = ["--quiet"] + (["--smoother"] if a.smoother else [])
        subprocess.run([py, "-m", "imunav.cli.main", "gins", "run", str(warm / "robot_ros2"), "--out",
                        str(warm / "out"), *flags], check=True, env=_env(), capture_output=True)
        c = time.perf_counter()
        ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        load0 = os.getloadavg()[0]
        r = subprocess.run(_pinned([py, "-m", "imunav.cli.main", "gins", "run", str(bag), "--out",
                                    str(work / "run"), *flags], a.cores), env=_env(), capture_output=True, text=True)
        wall = time.perf_counter() - c
        ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
        load1 = os.getloadavg()[0]
        if r.returncode != 0:
            raise SystemExit(f"imunav gins run failed: {r.stderr.strip()}")
        # the phases without the command line's process settings would not be its phases: numpy without transparent
        # huge pages, as `imunav` sets it (imunav.cli.main._no_hugepages; with them the filter's first writes of its
        # records took 12 s more of system time on this project's VMs)
        r2 = subprocess.run(_pinned([py, "-c", _PHASES, str(bag), str(work / "phases"), "1" if a.smoother else "0"],
                                    a.cores), env={**_env(), "NUMPY_MADVISE_HUGEPAGE": "0"}, capture_output=True,
                            text=True)
        if r2.returncode != 0:
            raise SystemExit(f"phases failed: {r2.stderr.strip()}")
        t = json.loads(r2.stdout.strip().splitlines()[-1])
        other = t["run_log_s"] - t["rest_detection_s"] - t["mounting_s"] - t["filter_s"]
        scale = 3600.0 / t["duration_s"]
        per_hour = "" if math.isclose(scale, 1, rel_tol=0.02) else f"; x{scale:.2f}: {wall * scale:.1f} s per hour"
        print(f"end to end (imunav gins run, {a.cores} cores): {wall:.1f} s wall, {cpu:.1f} s CPU (user + system) for "
              f"{t['duration_s'] / 60:.1f} min of log (acceptance for one hour: <= 30 s{per_hour}); load average "
              f"{load0:.1f} -> {load1:.1f} on {os.cpu_count()} CPUs (a shared machine's wall time exceeds the CPU "
              "time of this mostly single-threaded run)")
        print(f"  reading (read_nav_sources): {t['read_s']:.2f} s, (the IMU topic read alone: {t['read_imu_topic_s']:.2f} s, "
              f"{t['samples']['imu']} messages, {t['read_imu_topic_s'] / t['samples']['imu'] * 1e6:.1f} us each)")
        smooth = f" + smoother {t['smoother_s']:.2f}" if a.smoother else ""
        print(f"  run_log: {t['run_log_s']:.2f} s = rest detection {t['rest_detection_s']:.2f} + mounting "
              f"{t['mounting_s']:.2f} + filter {t['filter_s'] - t['smoother_s']:.2f}{smooth} + initial state and "
              f"configuration {other:.2f} s")
        print(f"  writing the files: {t['write_s']:.2f} s, figures {t['figures_s']:.2f} s; interpreter and imports "
              f"{t['import_s']:.2f} s")
    finally:
        if a.keep is None:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
