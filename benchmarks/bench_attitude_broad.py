"""BROAD accuracy: imunav filters with ONE parameter set for all trials vs vqf
(PyPI vqf, default settings, 9D), measured side by side, per-trial tables.

Acceptance: best imunav real-time filter mean total RMSE <= vqf's; the
offline smoother >= 15 % below vqf (real-time); Madgwick original_c (β = 0.12,
BROAD reference start) within 0.1° of each published per-trial total RMSE.

Run:  python benchmarks/bench_attitude_broad.py [DIR] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from imunav.attitude.benchmark import evaluate
from imunav.attitude.metrics import attitude_rmse
from imunav.io.broad import broad_trials, from_enu, load_broad
from imunav.io.datasets import shared_data_path


def vqf_scores(files, offline=False):
    from vqf import VQF, offlineVQF

    out = []
    for f in files:
        tr = load_broad(f)
        g, a, m = (np.ascontiguousarray(x) for x in (tr.imu.gyro, tr.imu.accel, tr.imu.mag))
        q = offlineVQF(g, a, m, 1.0 / tr.fs)["quat9D"] if offline else VQF(1.0 / tr.fs).updateBatch(g, a, m)["quat9D"]
        e = attitude_rmse(from_enu(q), tr.q_ref_nb, tr.movement)  # vqf's Earth frame is ENU
        out.append((tr.name, e.total_rmse_deg, e.heading_rmse_deg, e.inclination_rmse_deg))
    return out


def table(title, rows_a, name_a, rows_b, name_b):
    print(f"\n{title}")
    print(f"{'trial':48s} {name_a:>22s} {name_b:>22s}")
    for ra, rb in zip(rows_a, rows_b):
        print(f"{ra[0]:48s} {ra[1]:6.2f}/{ra[2]:6.2f}/{ra[3]:6.2f}   {rb[1]:6.2f}/{rb[2]:6.2f}/{rb[3]:6.2f}")
    ma = np.mean([r[1:] for r in rows_a], axis=0)
    mb = np.mean([r[1:] for r in rows_b], axis=0)
    print(f"{'mean (total/heading/inclination)':48s} {ma[0]:6.2f}/{ma[1]:6.2f}/{ma[2]:6.2f}   "
          f"{mb[0]:6.2f}/{mb[1]:6.2f}/{mb[2]:6.2f}")
    return ma, mb


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("dir", nargs="?", default=None)
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    d = Path(args.dir) if args.dir else shared_data_path("broad")
    if d is None:
        sys.exit("BROAD data not found (set IMUNAV_DATA)")
    files = broad_trials(d)
    vq = vqf_scores(files)

    res = {}
    for name in ("adaptive", "smoother", "madgwick_c", "mahony", "mekf"):
        r = evaluate(name, None, files)
        res[name] = [(t.trial, t.total_rmse_deg, t.heading_rmse_deg, t.inclination_rmse_deg) for t in r.trials]

    ma, mv = table("Real time: imunav adaptive MEKF vs vqf (RMSE deg, total/heading/inclination)",
                   res["adaptive"], "imunav adaptive", vq, "vqf 9D default")
    ms, _ = table("Offline: imunav RTS smoother vs vqf real time", res["smoother"], "imunav smoother", vq,
                  "vqf 9D default")
    print(f"\nreal time: imunav {ma[0]:.3f} vs vqf {mv[0]:.3f} deg -> {'met' if ma[0] <= mv[0] else 'NOT met'}")
    print(f"smoother: {ms[0]:.3f} deg = {100 * (1 - ms[0] / mv[0]):.1f} % below vqf (need >= 15 %) -> "
          f"{'met' if ms[0] <= 0.85 * mv[0] else 'NOT met'}")
    pub_path = d / "published_rmse.json"
    if pub_path.exists():
        pub = json.loads(pub_path.read_text())["madgwick"]["trials"]
        diffs = [abs(r[1] - pub[r[0]]["total_rmse_deg"]) for r in res["madgwick_c"] if r[0] in pub]
        print(f"madgwick original_c vs published: max |diff| {max(diffs):.4f} deg over {len(diffs)} trials -> "
              f"{'met' if max(diffs) <= 0.1 else 'NOT met'}")
    others = {k: float(np.mean([r[1] for r in v])) for k, v in res.items()}
    print("mean total RMSE of all imunav filters:", {k: round(v, 3) for k, v in others.items()})
    if args.json:
        Path(args.json).write_text(json.dumps({"vqf": vq, **res}, indent=1))


if __name__ == "__main__":
    main()
