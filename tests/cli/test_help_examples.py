"""Every ``imunav ... --help`` example runs as written, after the ones before it, in an empty folder (issue 26).

The examples are read from the help texts themselves (``tests/help_examples.py``), in the order a user reads them:
the commands as ``imunav --help`` lists them, a group's own help before its subcommands'.  An example that needs a
file finds it written by an example before it (commands chain) or in the shared data (``../shared/data/...``).

The long examples (``help_examples.LONG``: a whole lab, Monte Carlo runs, LSTM training, ...) would add minutes to
CI; each is listed there with its reason and ``benchmarks/bench_help_examples.py`` runs every example, those
included, in the same order.  No quick example reads a file that only a long one writes.
"""

from __future__ import annotations

import time

import pytest
from help_examples import LONG, help_examples, run_step, steps, work_folder
from shared_data import data_path


def test_every_command_has_an_example_and_every_long_one_is_named():
    """Each command and subcommand shows at least one example; the long list names only examples that exist."""
    examples = help_examples()
    where = {w for w, _ in examples}
    assert {"imunav convert", "imunav gins run", "imunav calibrate mag", "imunav batch noise"} <= where
    assert set(LONG) <= {e for _, e in examples}, set(LONG) - {e for _, e in examples}


def _quicker(argv: list[str]) -> list[str]:
    """Batch commands on the serial executor (a few tiny units: no process pool to start)."""
    if argv[:2] == ["imunav", "batch"]:
        argv = [*argv, "--executor", "serial", "--quiet"]
    return argv


def test_the_help_examples_run_in_order_in_an_empty_folder(tmp_path, monkeypatch):
    """The quick examples, in order, each command through the CLI in this process."""
    shared = data_path("px4_ulog", "sample.ulg").parents[1]
    for sub in ("broad", "imucal", "mpu6050_tedaldi", "foot", "ros_bags", "adis16405"):
        if not (shared / sub).is_dir():
            pytest.skip(f"shared data {shared / sub} not found")
    work = work_folder(tmp_path, shared)
    monkeypatch.chdir(work)
    ran = []
    for where, example in help_examples():
        if example in LONG:
            continue
        t0 = time.perf_counter()
        for argv in steps(example):
            argv = _quicker(argv)
            code, out = run_step(argv)
            assert code == 0, (where, example, out[-2000:])
        ran.append((time.perf_counter() - t0, example))
    print("\n".join(f"{t:6.1f} s  {e[:100]}" for t, e in ran))  # pytest -s: what each example costs here
    assert len(ran) >= 30
