"""Hostile cases generated from the CLI (issue 27): a seeded sample in CI; the full space in
``benchmarks/bench_cli_hostile.py``.

The cases come from the commands' own options (:mod:`cli_hostile`): every command and every option is
covered, numeric options through their declared domains (:mod:`imunav.cli._domains`), paths through their
role.  The sample takes one case of every option that has cases, then random others, with a fixed seed.
"""

from __future__ import annotations

import os

import pytest
from cli_hostile import KNOWN, generate, leaf_commands, make_fixtures, run_case, sample

from imunav.cli._domains import domain_of, flag_of, numeric

SEED = 27
N_SAMPLE = int(os.environ.get("IMUNAV_HOSTILE_SAMPLE", "260"))

CASES, COVERAGE = generate()
SAMPLE = sample([c for c in CASES if c.id not in KNOWN], N_SAMPLE, SEED)


def test_every_command_and_option_is_covered(capsys):
    commands = leaf_commands()
    assert COVERAGE["commands"] == len(commands) >= 28
    for path, cmd in commands:
        for p in cmd.params:
            if numeric(p):
                assert domain_of(path, p) is not None, f"imunav {path} {flag_of(p)} has no declared domain"
    covered = {(c.command, c.flag) for c in CASES}
    sampled = {(c.command, c.flag) for c in SAMPLE}
    assert covered <= sampled or len(SAMPLE) < len(covered)
    with capsys.disabled():
        print(f"\nhostile CLI cases: {COVERAGE['commands']} commands, {COVERAGE['options']} options "
              f"({COVERAGE['numeric']} numeric, {COVERAGE['paths']} paths; {len(covered)} with cases), "
              f"{COVERAGE['cases']} cases, {len(SAMPLE)} sampled (seed {SEED})")


@pytest.fixture(scope="module")
def fixtures(tmp_path_factory):
    root = tmp_path_factory.mktemp("hostile")
    return root, make_fixtures(root)


def test_sample_keeps_the_contract(fixtures, tmp_path):
    """Exit 2, one line naming the option or file, no traceback, inputs byte-identical, nothing left behind."""
    root, values = fixtures
    violations = {}
    for i, c in enumerate(SAMPLE):
        bad = run_case(c, root, values, tmp_path / f"case{i}")
        if bad:
            violations[c.id] = bad
    assert not violations, "\n".join(f"{k}: {v}" for k, v in violations.items())


def test_the_sample_covers_every_family():
    """Issue 36: output pairs, configuration-named inputs, file-system limits and option-multiplied work are
    generated for every command they apply to, and the CI sample runs each family."""
    from cli_hostile import family

    families = {family(c) for c in CASES}
    assert families == {"numeric", "path", "output-pair", "configured-input", "file-size-limit", "work"}
    assert {family(c) for c in SAMPLE} == families
    pairs = {(c.command, c.flag) for c in CASES if family(c) == "output-pair"}
    assert ("calibrate mag", "--out") in pairs and ("lab", "--json") in pairs and ("batch calibrate", "--json") in pairs
