"""CLI messages name flags, not Python keywords (issue 26)."""

from __future__ import annotations

import pytest
from shared_data import data_path
from typer.testing import CliRunner

from imunav.cli._errors import command_line_words
from imunav.cli.main import app


@pytest.mark.parametrize(("library", "cli"), [
    ("or pass force=True (command line: --force) to compensate again", "or pass --force to compensate again"),
    ("e.g. gate_m=2 (command line: --gate-m 2)", "e.g. --gate-m 2"),
    ("choose one with instance=... (CLI: --instance), or topic='s:0' (CLI: --topic s:0)",
     "choose one with --instance, or --topic s:0"),
    ("cut the static part (ImuData.window; command line: --start / --end)", "cut the static part (--start / --end)"),
    ("read_imu(format='ulog') does not take option(s) ['skiprows']; it accepts ['topic', 'mag_topic']",
     "the ulog reader does not take option(s) --skiprows; it accepts --topic, --mag-topic"),
    ("or lower min_coverage=... (command line: --min-coverage) at your own risk", "or lower --min-coverage at your own risk"),
])
def test_library_wording_becomes_flags(library, cli):
    assert command_line_words(library) == cli


def test_a_px4_topic_error_names_the_topic_and_flags_asked_for():
    """`--topic sensor_accel` on a log with three accelerometers: the error is about sensor_accel, in flags."""
    ulg = data_path("px4_ulog", "sample_log_small.ulg")
    r = CliRunner().invoke(app, ["info", str(ulg), "--topic", "sensor_accel"])
    assert r.exit_code == 2
    line = r.stderr.strip()
    assert "sensor_accel" in line and "sensor_gyro" not in line and "--instance" in line, line
    assert "instance=" not in line and "topic=" not in line, line
