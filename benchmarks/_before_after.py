"""Before / after: a benchmark's headline figures beside those measured at a308974 (main before issue 14).

Each benchmark calls :func:`report` once, at the end of its run::

    report("bench_zupt_speed", {"imunav us/sample": per, "max position diff m": d}, times=("imunav us/sample",))

and prints, for each figure recorded in ``before_a308974.json`` under the same command-line arguments::

    imunav us/sample      before (a308974)  1.79   now  1.81   ratio 1.01
    max position diff m   before (a308974)  0.00156  now 0.00156  unchanged

Figures named in ``times`` are timings (lower is better): the ratio now / before is printed (> 1: slower).
The others are deterministic (seeded) results: ``unchanged`` when within 1e-9 (relative to max(1, |before|)),
else the difference.  Timings on a shared machine vary with its load: compare ratios of runs made one after the
other (the file's ``note`` says how its figures were measured), not a single pair.

With ``IMUNAV_BENCH_RECORD=<file.json>`` in the environment the figures are recorded into that file instead
(the minimum of the timings over repeated runs, the last value of the others): ``before_a308974.json`` was made
so, by this module and the same ``report`` lines in a checkout of a308974.
"""

from __future__ import annotations

import json
import os
import platform
import sys
import time
from collections.abc import Iterable, Mapping
from pathlib import Path

from imunav.files import atomic_path

BEFORE = Path(__file__).with_name("before_a308974.json")
COMMIT = "a308974"
#: |now - before| <= TOL * max(1, |before|): a deterministic figure is unchanged
TOL = 1e-9


def _args() -> str:
    return " ".join(sys.argv[1:])


def _record(path: Path, bench: str, figures: Mapping[str, float], times: set[str]) -> None:
    data = json.loads(path.read_text(encoding="utf-8")) if path.exists() else {"commit": COMMIT, "benchmarks": {}}
    runs = data["benchmarks"].setdefault(bench, {})
    prev = runs.get(_args(), {}).get("figures", {})
    merged = {}
    for k, v in figures.items():
        old = prev.get(k)
        merged[k] = min(v, old) if (k in times and old is not None) else v
    runs[_args()] = {
        "command": f"PYTHONPATH=src python benchmarks/{bench}.py {_args()}".strip(),
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "machine": f"{platform.machine()}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}",
        "runs": runs.get(_args(), {}).get("runs", 0) + 1,
        "times": sorted(times & set(figures)),
        "figures": merged,
    }
    with atomic_path(path) as tmp:  # a benchmark killed half-way leaves the record as it was
        tmp.write_text(json.dumps(data, indent=1, sort_keys=True, allow_nan=False) + "\n", encoding="utf-8")


def report(bench: str, figures: Mapping[str, float], times: Iterable[str] = ()) -> None:
    """Print ``before (a308974)  now  ratio`` (timings) or ``unchanged`` (results) for each headline figure.

    Parameters
    ----------
    bench : str
        The benchmark's file name without ``.py`` (its key in ``before_a308974.json``).
    figures : mapping of str to float
        The headline figures of this run, by name.
    times : iterable of str
        The names in ``figures`` that are timings (lower is better); the others are deterministic results.
    """
    times = set(times)
    figures = {k: float(v) for k, v in figures.items()}
    target = os.environ.get("IMUNAV_BENCH_RECORD")
    if target:
        _record(Path(target), bench, figures, times)
        print(f"(figures recorded in {target})")
        return
    if not BEFORE.exists():
        print(f"(no {BEFORE.name}: no before / after lines)")
        return
    runs = json.loads(BEFORE.read_text(encoding="utf-8"))["benchmarks"].get(bench, {})
    before = runs.get(_args())
    print(f"\nbefore / after issue 14 (before: {COMMIT}, {BEFORE.name}):")
    if before is None:
        print(f"  no figures measured at {COMMIT} with these arguments; measured with: "
              + "; ".join(repr(a) for a in runs) if runs else f"  no figures measured at {COMMIT}")
        return
    width = max(map(len, figures))
    for k, now in figures.items():
        b = before["figures"].get(k)
        if b is None:
            print(f"  {k:{width}s}  (new figure)  now {now:.6g}")
        elif k in times:
            print(f"  {k:{width}s}  before ({COMMIT}) {b:10.4g}  now {now:10.4g}  ratio {now / b:.2f}")
        elif abs(now - b) <= TOL * max(1.0, abs(b)):
            print(f"  {k:{width}s}  before ({COMMIT}) {b:10.6g}  now {now:10.6g}  unchanged")
        else:
            print(f"  {k:{width}s}  before ({COMMIT}) {b:10.6g}  now {now:10.6g}  CHANGED by {now - b:+.3g}")
    if times:
        print(f"  (timings: min over {before['runs']} run(s) at {COMMIT} on {before['machine']}, {before['date']}; "
              "this run's load changes them: compare interleaved runs)")
