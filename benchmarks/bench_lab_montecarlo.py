"""Monte Carlo of the attitude paper's scenario through imunav.lab.montecarlo: processes vs Dask.

Acceptance (issue 8): 1,000 Monte Carlo runs of the Candan & Söken scenario
(:mod:`imunav.attitude.scenario`, 245 s at 100 Hz, gravity-vector KF) in under
60 s on 2 cores (batched scenario, :func:`imunav.scenarios.attitude_paper`),
and identical results on a 2-worker Dask LocalCluster on loopback.

Run::

    PYTHONPATH=src python benchmarks/bench_lab_montecarlo.py --runs 1000 --workers 2
    PYTHONPATH=src python benchmarks/bench_lab_montecarlo.py --runs 100 --filters proposed,lee,javed

Prints wall time and CPU time of each executor, runs per second, the
Monte Carlo table (mean / std / percentiles of the RMSEs, deg) next to the
paper's Table 2, and asserts that both executors give bit-identical numbers.
The machine load is printed too: on a shared machine wall time is not CPU time.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

from _before_after import report  # the before (a308974) / after lines


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=1000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--filters", default="proposed", help="comma list of proposed, lee, javed")
    ap.add_argument("--chunk", type=int, default=None, help="runs per task (default runs / (4 workers))")
    ap.add_argument("--no-dask", action="store_true", help="skip the Dask LocalCluster run")
    a = ap.parse_args(argv)

    import numpy as np

    from imunav.attitude.scenario import PAPER_TABLE2
    from imunav.lab.montecarlo import run_montecarlo
    from imunav.scenarios import attitude_paper

    filters = tuple(f.strip() for f in a.filters.split(",") if f.strip())
    print(f"imunav Monte Carlo benchmark: {a.runs} runs of the attitude paper scenario, filters {filters}, "
          f"{a.workers} workers, seed {a.seed}; load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    # compile / warm the numba kernels once in this process (the workers load them from the cache)
    t = time.perf_counter()
    attitude_paper(list(np.random.default_rng(s) for s in range(1)), filters=filters)
    print(f"warm-up (numba cache load / compile): {time.perf_counter() - t:.1f} s")
    # CPU cost of one run, measured in this process (independent of other load on a shared machine)
    n_probe = 5
    c = time.process_time()
    attitude_paper(list(np.random.default_rng(100 + s) for s in range(n_probe)), filters=filters)
    per_run = (time.process_time() - c) / n_probe
    print(f"CPU time per run: {per_run * 1e3:.0f} ms -> {a.runs} runs on {a.workers} cores need >= "
          f"{per_run * a.runs / a.workers:.1f} s when the cores are free (acceptance: < 60 s for 1000 runs on 2)")

    results = {}
    for ex in ("processes",) + (() if a.no_dask else ("dask",)):
        t0 = time.perf_counter()
        mc = run_montecarlo(attitude_paper, a.runs, seed=a.seed, executor=ex, n_workers=a.workers, batched=True,
                            chunk_size=a.chunk, progress=sys.stderr.isatty(), filters=filters)
        wall = time.perf_counter() - t0
        results[ex] = mc
        print(f"{ex:9s}: {wall:7.1f} s wall, {a.runs / wall:7.1f} runs/s")
    mc = results["processes"]
    summ = mc.summary()
    print("\nRMSE over the runs [deg] (mean, std, p5, p50, p95):")
    for col in mc.metrics.columns:
        s = summ[col]
        fname, _, ang = col.partition("_")
        paper = PAPER_TABLE2.get(fname)
        ref = "" if paper is None else f"   paper Table 2: {paper[0] if ang.startswith('pitch') else paper[1]}"
        print(f"  {col:28s} {s['mean']:.4f} {s['std']:.4f} {s['p5']:.4f} {s['p50']:.4f} {s['p95']:.4f}{ref}")
    report("bench_lab_montecarlo", {"CPU ms per run": per_run * 1e3, **{f"{c} mean": summ[c]["mean"] for c in mc.metrics.columns}, **{f"{c} std": summ[c]["std"] for c in mc.metrics.columns}}, times=("CPU ms per run",))
    if "dask" in results:
        same = mc.metrics.equals(results["dask"].metrics)
        print(f"\nDask LocalCluster ({a.workers} workers) identical to local processes: {same}")
        assert same, "Dask and process executors gave different numbers for the same seed"
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
