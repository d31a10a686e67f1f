"""Every ``imunav ... --help`` example, run as written, in order, in an empty folder, each as a fresh process
(issue 26).  ``tests/cli/test_help_examples.py`` runs the quick ones in CI; this runs all of them, the long ones
(:data:`help_examples.LONG`, with the reason each is left out of CI) included, and prints each one's time.

Run:  PYTHONPATH=src python benchmarks/bench_help_examples.py
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "src"), str(ROOT / "tests")]

from help_examples import LONG, help_examples, run_step, steps, work_folder  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.parse_args()
    shared = Path(os.environ.get("IMUNAV_DATA") or ROOT.parent / "shared" / "data")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT / "src"),
                                                                     os.environ.get("PYTHONPATH")]))}
    failed = 0
    with tempfile.TemporaryDirectory(prefix="imunav-help-examples-") as tmp:
        work = work_folder(Path(tmp), shared)
        os.chdir(work)
        total = time.perf_counter()
        for where, example in help_examples():
            long = example in LONG
            t0 = time.perf_counter()
            status = "ok"
            for argv in steps(example):
                code, out = run_step(argv, subprocess_env=env)
                if code != 0:
                    status = f"FAILED (exit {code}): {(out.strip().splitlines() or [''])[-1]}"
                    failed += 1
                    break
            print(f"{time.perf_counter() - t0:7.1f} s  {'long ' if long else 'quick'}  {where}: {example[:110]}  "
                  f"{status}", flush=True)
        os.chdir(ROOT)
        print(f"{time.perf_counter() - total:.0f} s in all; {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
