"""attitude run on PX4 logs as a PX4 user compares it (issue 26): magnetometer topic, declination, RMS to the log."""

from __future__ import annotations

import json

import numpy as np
import pytest
from shared_data import data_path
from typer.testing import CliRunner

from imunav.attitude.px4 import declination, to_true_north
from imunav.rotation import euler_from_quat, quat_from_euler

pytest.importorskip("pyulog")


def test_declination_turns_the_yaw_and_follows_the_estimator_in_use():
    q = quat_from_euler(0.1, -0.2, 0.3)[None, :]
    e = euler_from_quat(to_true_north(q, 4.0))[0]
    np.testing.assert_allclose(e, [0.1, -0.2, 0.3 + np.deg2rad(4.0)], atol=1e-12)
    assert declination({"px4_params": {"SYS_MC_EST_GROUP": 2, "EKF2_MAG_DECL": 2.98, "ATT_MAG_DECL": 1.0}}) == (
        2.98, "EKF2_MAG_DECL")
    assert declination({"px4_params": {"SYS_MC_EST_GROUP": 1, "EKF2_MAG_DECL": 2.98, "ATT_MAG_DECL": 1.0}}) == (
        1.0, "ATT_MAG_DECL")
    assert declination({}) == (None, None)


# (log, magnetometer used, declination applied, largest yaw RMS to vehicle_attitude in deg): measured
# 0.22 (sample.ulg, its sensor_combined carries the magnetometer), 0.08 (SITL, vehicle_magnetometer);
# the small log's 6 s leave the filter converging (15 deg, bound only by the log's length)
@pytest.mark.parametrize(("name", "mag", "decl", "yaw_max"), [
    ("sample.ulg", "in the IMU topic", 0.0, 0.5),
    ("sample_logging_tagged_and_default_params.ulg", "vehicle_magnetometer", 2.98, 0.3),
    ("sample_log_small.ulg", "vehicle_magnetometer", 3.99, 30.0),
])
def test_attitude_run_compares_with_the_logs_attitude(tmp_path, name, mag, decl, yaw_max):
    from imunav.cli.main import app

    out = tmp_path / "run.json"
    r = CliRunner().invoke(app, ["attitude", "run", str(data_path("px4_ulog", name)), "--filter", "mekf",
                                 "--json", str(out)], env={"COLUMNS": "200"})
    assert r.exit_code == 0, r.output
    assert "RMS difference to the log's vehicle_attitude" in r.output and "declination:" in r.output
    px4 = json.loads(out.read_text())["px4"]
    assert px4["mag_topic"] == mag and px4["declination_deg"] == pytest.approx(decl, abs=0.01)
    rms = px4["reference"]["rms_deg"]
    assert rms["roll"] < 0.2 and rms["pitch"] < 0.2 and rms["yaw"] < yaw_max, rms
