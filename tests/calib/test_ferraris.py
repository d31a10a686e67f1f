"""Ferraris calibration against imucal's expected calibration (shared data) and a simulated session."""

import json

import numpy as np
import pytest
from builders import thesis_truth
from shared_data import data_path

from imunav.calib import FERRARIS_SECTIONS, ImuCalibration, ferraris, ferraris_from_session
from imunav.errors import DegenerateGeometryError, InsufficientDataError, SaturationError


def _annotated():
    import pandas as pd

    d = pd.read_csv(data_path("imucal", "annotated_session.csv"))
    return {
        p: (g[["acc_x", "acc_y", "acc_z"]].to_numpy(float), g[["gyr_x", "gyr_y", "gyr_z"]].to_numpy(float))
        for p, g in d.groupby("part")
    }


def test_reproduces_imucal_example_cal():
    """imucal tests/snapshots/example_cal.json from annotated_session.csv at 204.8 Hz (imucal README)."""
    secs = _annotated()
    r = ferraris(secs, 204.8, raw_accel_unit="counts", raw_gyro_unit="counts")
    got = r.calibration.to_imucal()
    exp = json.loads(data_path("imucal", "example_cal.json").read_text())
    for k in ("K_a", "R_a", "b_a", "K_g", "R_g", "K_ga", "b_g"):
        a, b = np.asarray(got[k]), np.asarray(exp[k])
        assert np.max(np.abs(a - b)) <= 1e-6 * np.max(np.abs(b)), k
    assert got["from_acc_unit"] == "a.u." and got["cal_type"] == "Ferraris"
    # the imucal file loads back into the same model
    back = ImuCalibration.from_imucal(exp)
    np.testing.assert_allclose(back.gyro_matrix, r.calibration.gyro_matrix, rtol=1e-9)


def test_matches_imucal_run_on_the_same_input():
    """The peer run live on the same annotated session (imucal, test extra): every matrix agrees to 1e-12 relative."""
    imucal = pytest.importorskip("imucal")
    import pandas as pd

    d = pd.read_csv(data_path("imucal", "annotated_session.csv")).set_index("part")
    peer = imucal.FerrarisCalibration().compute(imucal.ferraris_regions_from_df(d), sampling_rate_hz=204.8,
                                               from_acc_unit="a.u.", from_gyr_unit="a.u.")
    got = ferraris(_annotated(), 204.8, raw_accel_unit="counts", raw_gyro_unit="counts").calibration.to_imucal()
    for k in ("K_a", "R_a", "b_a", "K_g", "R_g", "K_ga", "b_g"):
        a, b = np.asarray(got[k]), np.asarray(getattr(peer, k))
        rel = np.max(np.abs(a - b)) / np.max(np.abs(b))
        print(f"{k}: max relative difference to imucal {rel:.1e}")
        assert rel <= 1e-12, k


def test_continuous_session_matches_imucal_output():
    """Calibrating the continuous session and applying it gives ferraris_example.csv (rtol 1e-5 upstream)."""
    import pandas as pd

    s = pd.read_csv(data_path("imucal", "example_ferraris_session.csv"))
    secs = json.loads(data_path("imucal", "example_ferraris_session_list.json").read_text())
    acc = s[["acc_x", "acc_y", "acc_z"]].to_numpy(float)
    gyr = np.deg2rad(s[["gyr_x", "gyr_y", "gyr_z"]].to_numpy(float))
    r = ferraris_from_session(acc, gyr, secs, 102.4)
    f, w = r.calibration.apply_arrays(acc[:50], gyr[:50])
    e = pd.read_csv(data_path("imucal", "ferraris_example.csv"))
    np.testing.assert_allclose(f, e[["acc_x", "acc_y", "acc_z"]].to_numpy(), rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(np.rad2deg(w), e[["gyr_x", "gyr_y", "gyr_z"]].to_numpy(), rtol=1e-6, atol=1e-9)


def test_simulated_sections_recover_truth(rng):
    """Ideal poses and turns: the closed form is exact (up to the turn integration)."""
    truth = thesis_truth()
    g, fs = 9.81, 100.0
    secs = {}
    for i, ax in enumerate("xyz"):
        for sgn, tag in ((1, "p"), (-1, "a")):
            f = np.zeros((300, 3))
            f[:, i] = sgn * g
            a, w = truth.invert_arrays(f, np.zeros_like(f))
            secs[f"{ax}_{tag}"] = (a, w)
        # one full turn measured as -360 deg (imucal's default sense) about axis i, gravity along i
        n = 1000
        wt = np.zeros((n, 3))
        wt[:, i] = -2 * np.pi / n * fs
        f = np.zeros((n, 3))
        f[:, i] = g
        secs[f"{ax}_rot"] = truth.invert_arrays(f, wt)
    r = ferraris(secs, fs, gravity=g)
    c = r.calibration
    np.testing.assert_allclose(c.accel_matrix, truth.accel_matrix, atol=1e-14)
    np.testing.assert_allclose(c.gyro_matrix, truth.gyro_matrix, atol=1e-12)
    np.testing.assert_allclose(c.g_sensitivity, truth.g_sensitivity, atol=1e-15)
    # the six static poses give the bias: (+g) and (-g) poses cancel G f
    np.testing.assert_allclose(c.gyro_bias, truth.gyro_bias, atol=1e-15)


def test_refusals():
    secs = {k: (np.zeros((5, 3)), np.zeros((5, 3))) for k in FERRARIS_SECTIONS if k != "z_rot"}
    with pytest.raises(InsufficientDataError, match="missing \\['z_rot'\\]"):
        ferraris(secs, 100.0)
    secs["z_rot"] = (np.zeros((5, 3)), np.full((5, 3), 40.0))
    with pytest.raises(SaturationError, match="z_rot"):
        ferraris(secs, 100.0, full_scale=(None, 35.0))


def _ferraris_sections(rng):
    secs = {}
    for i, a in enumerate("xyz"):
        e = np.eye(3)[i] * 9.81
        secs[f"{a}_p"] = (rng.normal(e, 0.01, (200, 3)), rng.normal(0, 1e-3, (200, 3)))
        secs[f"{a}_a"] = (rng.normal(-e, 0.01, (200, 3)), rng.normal(0, 1e-3, (200, 3)))
        w = np.zeros((360, 3))
        w[:, i] = -np.radians(360) / 3.6  # one turn in 3.6 s at 100 Hz
        secs[f"{a}_rot"] = (rng.normal([0, 0, 9.81], 0.01, (360, 3)), w)
    return secs


def test_ferraris_identical_or_empty_sections_are_refused():
    secs = _ferraris_sections(np.random.default_rng(0))
    np.testing.assert_allclose(ferraris(secs, 100.0).calibration.gyro_matrix, np.eye(3), atol=1e-3)
    with pytest.raises(DegenerateGeometryError, match="accelerometer matrix is degenerate"):
        ferraris({k: secs["x_p"] for k in FERRARIS_SECTIONS}, 100.0)
    with pytest.raises(DegenerateGeometryError, match="y_rot"):
        ferraris({**secs, "y_rot": secs["x_p"]}, 100.0)  # a "rotation" without rotation
    with pytest.raises(DegenerateGeometryError, match="x_p, x_a"):
        ferraris({**secs, "x_p": secs["x_a"], "x_a": secs["x_p"]}, 100.0)  # swapped poses
