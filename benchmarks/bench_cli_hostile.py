"""Every hostile case the CLI generates from its own options (issue 27): the full space of tests/cli_hostile.py.

Runs each case of :func:`cli_hostile.generate` (every command, every option, every value derived from its
type and declared domain, every path fault of its role; and the families of issue 36: two outputs of one
command on one path or inside each other's folders, outputs on files a configuration names, writes under a
file-size limit in every recording format, options that multiply the work beyond the machine) and checks the
contract: exit status 2, one line on stderr naming the option or the file, no traceback, inputs byte-identical,
nothing partial left.  Prints the coverage, the cases per family and the violations, and writes them as JSON.

Usage: PYTHONPATH=src python benchmarks/bench_cli_hostile.py [--json out.json] [--limit N]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from cli_hostile import KNOWN, family, generate, make_fixtures, run_case  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", type=Path, default=None, help="write the coverage and the violations here")
    ap.add_argument("--limit", type=int, default=None, help="run only the first N cases")
    a = ap.parse_args()
    cases, cov = generate()
    if a.limit:
        cases = cases[: a.limit]
    print(f"coverage: {cov['commands']} commands, {cov['options']} options ({cov['numeric']} numeric, "
          f"{cov['paths']} paths), {cov['cases']} cases; running {len(cases)} "
          f"{dict(Counter(family(c) for c in cases))}", flush=True)
    t0 = time.perf_counter()
    violations = []
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        values = make_fixtures(root)
        for i, c in enumerate(cases):
            bad = run_case(c, root, values, root / f"case{i}")
            if bad:
                violations.append({"case": c.id, "argv": c.argv, "violations": bad, "known": KNOWN.get(c.id)})
                print(f"VIOLATION {c.id}{' (known: ' + KNOWN[c.id] + ')' if c.id in KNOWN else ''}: {bad}",
                      flush=True)
            if (i + 1) % 100 == 0:
                print(f"{i + 1} / {len(cases)} cases, {len(violations)} violations, "
                      f"{time.perf_counter() - t0:.0f} s", flush=True)
    secs = time.perf_counter() - t0
    by_cmd = Counter(v["case"].split("-")[0] for v in violations)
    known = sum(1 for v in violations if v["known"])
    print(f"{len(cases)} cases in {secs:.0f} s: {len(violations)} violations {dict(by_cmd)}, {known} of them known "
          "(in code owned elsewhere, reported)")
    if a.json:
        a.json.write_text(json.dumps({**cov, "run": len(cases), "seconds": round(secs, 1),
                                      "violations": violations}, indent=1))
    return 1 if len(violations) > known else 0


if __name__ == "__main__":
    sys.exit(main())
