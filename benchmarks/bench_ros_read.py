"""Reading an IMU topic of a ROS 2 MCAP bag: imunav vs iterating the same messages with rosbags alone.

Makes a bag of ``--size-mb`` MB (default 1024) in a temporary folder with one ``sensor_msgs/Imu`` topic
at 1 kHz and a ``sensor_msgs/MagneticField`` topic at 100 Hz (``imunav.io.rosbag.write_bag``), then
times, each in a fresh subprocess (so that the peak resident memory, ``ru_maxrss``, is that run's own):

* ``rosbags``: ``AnyReader``, every message of the IMU connection deserialized (``reader.deserialize``),
  nothing kept: the floor any reader built on rosbags pays;
* ``imunav``: ``read_imu(bag, topic="/imu")``, an ImuData in SI / FRD.

Peak memory is the process's ``VmHWM`` (``/proc/self/status``; ``ru_maxrss`` would carry the parent's
peak across the fork on Linux).

Target (issue 17): imunav time ≤ 2 × rosbags time (≥ 50 % of its speed), and memory linear in the
selected topic only: the peak over the interpreter's baseline, per IMU message, is printed next to the
size of a message in the bag.

Run: ``python benchmarks/bench_ros_read.py`` (1 GB; about 10 min on one core), or
``--size-mb 50`` for a quick check.  ``--keep DIR`` keeps the bag there.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

BYTES_PER_IMU_MSG = 380  # CDR Imu (~330 B) + MCAP record and index, measured on a small bag

_HWM = """
def hwm_kb():
    for line in open('/proc/self/status'):
        if line.startswith('VmHWM:'):
            return int(line.split()[1])
"""

_ROSBAGS = _HWM + """
import json, sys, time
from pathlib import Path
from rosbags.highlevel import AnyReader
t0, c0 = time.perf_counter(), time.process_time()
n = 0
with AnyReader([Path(sys.argv[1])]) as r:
    conns = [c for c in r.connections if c.topic == '/imu']
    for conn, ts, raw in r.messages(connections=conns):
        msg = r.deserialize(raw, conn.msgtype)
        n += 1
print(json.dumps({'n': n, 'time_s': time.perf_counter() - t0, 'cpu_s': time.process_time() - c0,
                  'maxrss_kb': hwm_kb()}))
"""

_IMUNAV = _HWM + """
import json, sys, time
from imunav.io import read_imu
import imunav.io.rosbag, imunav.rotation, rosbags.highlevel  # imports (numba kernels: ~1 s once) untimed
base = hwm_kb()
t0, c0 = time.perf_counter(), time.process_time()
d = read_imu(sys.argv[1], topic='/imu')
print(json.dumps({'n': d.n, 'time_s': time.perf_counter() - t0, 'cpu_s': time.process_time() - c0,
                  'maxrss_kb': hwm_kb(), 'base_kb': base}))
"""

_BASE = _HWM + """
import json
from imunav.io import read_imu
import imunav.io.rosbag, imunav.rotation, rosbags.highlevel
print(json.dumps({'maxrss_kb': hwm_kb()}))
"""


def make_bag(path: Path, size_mb: float, seed: int = 0) -> tuple[int, float]:
    """Write the bag; returns (IMU messages, seconds taken)."""
    from imunav.io.logs import TopicData
    from imunav.io.rosbag import write_bag
    from imunav.timeseries import ImuData

    n = max(int(size_mb * 1e6 / BYTES_PER_IMU_MSG), 1000)
    rng = np.random.default_rng(seed)
    t = np.arange(n) / 1000.0
    imu = ImuData(t, rng.normal(0, 0.01, (n, 3)), rng.normal([0, 0, -9.81], 0.05, (n, 3)),
                  meta={"t0_ns": 1_700_000_000_000_000_000})
    k = n // 10
    mag = TopicData("/mag", "mag", t[::10][:k], {"mag": rng.normal([20, 0, 45], 0.5, (k, 3))}, {"mag": "uT"},
                    meta={"t0_ns": 1_700_000_000_000_000_000})
    t0 = time.perf_counter()
    write_bag(path, {"/imu": imu, "/mag": mag}, storage="mcap")
    return n, time.perf_counter() - t0


def _run(code: str, bag: Path) -> dict:
    env = dict(os.environ)
    src = str(Path(__file__).resolve().parents[1] / "src")
    env["PYTHONPATH"] = src + os.pathsep + env.get("PYTHONPATH", "")
    out = subprocess.run([sys.executable, "-c", code, str(bag)], capture_output=True, text=True, env=env, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size-mb", type=float, default=1024.0, help="bag size in MB (default 1024)")
    ap.add_argument("--keep", type=Path, default=None, help="folder to keep the bag in (default: a temp folder)")
    ap.add_argument("--json", type=Path, default=None, help="write the figures as JSON")
    a = ap.parse_args(argv)
    root = Path(tempfile.mkdtemp(prefix="bench_ros_")) if a.keep is None else a.keep
    root.mkdir(parents=True, exist_ok=True)
    bag = root / f"imu_{int(a.size_mb)}mb"
    try:
        if not bag.exists():
            n, tw = make_bag(bag, a.size_mb)
            print(f"wrote {bag} ({n:,} IMU messages at 1 kHz + /mag at 100 Hz) in {tw:.1f} s")
        size = sum(f.stat().st_size for f in bag.rglob("*") if f.is_file())
        print(f"bag size: {size / 1e6:.1f} MB")
        base = _run(_BASE, bag)
        rb = _run(_ROSBAGS, bag)
        im = _run(_IMUNAV, bag)
        assert rb["n"] == im["n"], (rb, im)
        ratio = rb["cpu_s"] / im["cpu_s"]  # CPU time: the wall time of a shared machine varies with its load
        extra_kb = im["maxrss_kb"] - base["maxrss_kb"]
        res = {
            "bag_mb": size / 1e6, "imu_messages": im["n"],
            "rosbags_s": rb["time_s"], "imunav_s": im["time_s"], "rosbags_cpu_s": rb["cpu_s"],
            "imunav_cpu_s": im["cpu_s"],
            "speed_ratio_imunav_over_rosbags": ratio,
            "rosbags_peak_rss_mb": rb["maxrss_kb"] / 1024, "imunav_peak_rss_mb": im["maxrss_kb"] / 1024,
            "baseline_rss_mb": base["maxrss_kb"] / 1024,
            "imunav_extra_bytes_per_imu_message": extra_kb * 1024 / im["n"],
            "bag_bytes_per_imu_message": size / im["n"],
        }
        print(f"rosbags alone (iterate + deserialize): {rb['time_s']:.2f} s wall, {rb['cpu_s']:.2f} s CPU "
              f"({im['n'] / rb['cpu_s']:,.0f} msg/s), peak RSS {rb['maxrss_kb'] / 1024:.0f} MB")
        print(f"imunav read_imu(topic='/imu'):        {im['time_s']:.2f} s wall, {im['cpu_s']:.2f} s CPU "
              f"({im['n'] / im['cpu_s']:,.0f} msg/s), "
              f"peak RSS {im['maxrss_kb'] / 1024:.0f} MB (baseline after imports {base['maxrss_kb'] / 1024:.0f} MB)")
        print(f"speed (CPU time): imunav at {100 * ratio:.0f} % of rosbags alone (target >= 50 %)")
        print(f"memory: {res['imunav_extra_bytes_per_imu_message']:.0f} B per selected message over the baseline, "
              f"vs {res['bag_bytes_per_imu_message']:.0f} B per message in the bag (ImuData: 7 float64 = 56 B)")
        if a.json is not None:
            from imunav.files import write_json

            write_json(a.json, res)
        return res
    finally:
        if a.keep is None:
            shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
