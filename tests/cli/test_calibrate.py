"""imunav calibrate / compensate end to end on the demo data (examples/calib_demo_data.py)."""

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest
from builders import degenerate_mag_clouds
from typer.testing import CliRunner

from imunav.cli.main import app

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    spec = importlib.util.spec_from_file_location("calib_demo_data", ROOT / "examples" / "calib_demo_data.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.main(tmp_path_factory.mktemp("demo"), fs=5.0, dwell_s=6.0)


def _run(*args):
    r = CliRunner().invoke(app, [str(a) for a in args])
    assert r.exit_code == 0, r.output + repr(r.exception)
    return r.output


def test_ratetable_with_static_and_compensate(demo):
    from imunav.calib import ImuCalibration, success_percentages
    from imunav.io import read_imu

    out = demo / "cal.json"
    _run("calibrate", "ratetable", demo / "rate.npz", "--segments", demo / "rate_segments.json",
         "--static", demo / "static.npz", "--static-segments", demo / "static_segments.json",
         "--latitude-deg", 40, "--noise-model", demo / "noise_model.toml", "--out", out, "--report", demo / "rep")
    from imunav.calib import calibration_parameters, parameter_stderr

    cal, truth = ImuCalibration.load(out), ImuCalibration.load(demo / "truth.json")
    s = success_percentages(cal, truth)
    assert s["accel_mean"] > 96.0 and s["gyro_mean"] > 97.0  # 6-s dwells: worse than the thesis's 30 s
    pe, pt, se = calibration_parameters(cal), calibration_parameters(truth), parameter_stderr(cal.stderr)
    z = np.concatenate([(pe[k] - pt[k]) / se[k] for k in pt])
    assert np.mean(np.abs(z) <= 3) >= 0.9, z
    assert (demo / "rep" / "residuals.png").stat().st_size > 1000
    rep = json.loads((demo / "rep" / "report.json").read_text())
    assert rep["method"] == "multiposition+ratetable" and "accel" in rep["condition"]
    _run("compensate", demo / "static.npz", "--cal", out, "--out", demo / "comp.npz")
    comp = read_imu(demo / "comp.npz")
    # compensated static specific force has the local gravity magnitude
    assert abs(np.median(np.linalg.norm(comp.accel, axis=1)) - 9.8017) < 0.02


def _params(path):
    """QGroundControl parameter file -> {name: value} (comment lines start with #; fields are tab-separated)."""
    rows = [ln.split("\t") for ln in path.read_text().splitlines() if ln and not ln.startswith("#")]
    return {r[2]: float(r[3]) for r in rows}


def test_multiposition_and_mag(demo):
    from imunav.calib import ImuCalibration

    out = _run("calibrate", "multiposition", demo / "static.npz", "--segments", demo / "static_segments.json",
               "--out", demo / "s.json", "--px4-params", demo / "s.params")
    cal, p = ImuCalibration.load(demo / "s.json"), _params(demo / "s.params")
    np.testing.assert_array_equal([p[f"CAL_ACC0_{a}OFF"] for a in "XYZ"], cal.accel_bias)
    np.testing.assert_array_equal([p[f"CAL_GYRO0_{a}OFF"] for a in "XYZ"], cal.gyro_bias)
    # the misalignment a multi-position fit estimates has no PX4 parameter: dropped, and said so
    assert "dropped: accelerometer cross-axis" in out and "accelerometer cross-axis" in (demo / "s.params").read_text()
    out = _run("calibrate", "mag", demo / "mag.csv", "--out", demo / "mag.json", "--px4-params", demo / "mag.params",
               "--mag-unit", "uT")
    pm = _params(demo / "mag.params")
    np.testing.assert_allclose([pm[f"CAL_MAG0_{a}OFF"] for a in "XYZ"],
                               np.array(json.loads((demo / "mag.json").read_text())["b"]) * 0.01, rtol=1e-15)
    d = json.loads((demo / "mag.json").read_text())
    np.testing.assert_allclose(d["b"], [15.85, -3.749, 19.196], atol=0.05)
    assert "written" in out
    _run("calibrate", "mag", demo / "mag.csv", "--method", "rotation-scale", "--out", demo / "mag2.json")


def test_temperature_command(demo, tmp_path):
    from imunav.calib import ImuCalibration

    base = ImuCalibration.load(demo / "truth.json")
    args = []
    for t in (-30, -10, 10, 30, 50):
        p = tmp_path / f"c{t}.json"
        base.with_(accel_bias=base.accel_bias + 1e-3 * t).save(p)
        args.append(f"{p}@{t}")
    _run("calibrate", "temperature", *args, "--orders", "1,2", "--params", "accel_bias", "--out", tmp_path / "th.json")
    th = ImuCalibration.load(tmp_path / "th.json")
    assert th.meta["thermal"]["accel_bias"] == [1, 1, 1]
    a, _ = th.invert_arrays(np.zeros((1, 3)), np.zeros((1, 3)), temp_c=np.array([20.0]))
    np.testing.assert_allclose(a[0], base.accel_bias + 0.02, atol=1e-12)


def test_ferraris_command_on_imucal_session(tmp_path):
    from shared_data import data_path

    sess = data_path("imucal", "example_ferraris_session.csv")
    secs = data_path("imucal", "example_ferraris_session_list.json")
    _run("calibrate", "ferraris", sess, "--sections", secs, "--fs", 102.4, "--gyro-unit", "deg/s",
         "--out", tmp_path / "f.json", "--imucal-out", tmp_path / "fi.json")
    d = json.loads((tmp_path / "fi.json").read_text())
    assert d["cal_type"] == "Ferraris" and np.allclose(np.diag(d["K_a"]), [0.99675, 1.00244, 1.02340], atol=1e-4)


def test_bad_temperature_argument(tmp_path):
    r = CliRunner().invoke(app, ["calibrate", "temperature", "nofile.json", "--out", str(tmp_path / "x.json")])
    assert r.exit_code == 2 and "FILE@TEMP_C" in r.stderr


def test_multipose_command_on_unsigned_counts_with_defaults(tmp_path):
    """A raw unsigned-count session (zero near 32768) calibrates with only --fs and --init-s."""
    from builders import PA_U, PG_U, unsigned_count_session

    from imunav.calib import ImuCalibration
    from imunav.calib.multipose import accel_tedaldi_matrix, gyro_tedaldi_matrix

    a, g = unsigned_count_session(21)
    csv = tmp_path / "session.csv"
    np.savetxt(csv, np.c_[a, g], delimiter=",", fmt="%d", header="ax,ay,az,gx,gy,gz", comments="")
    _run("calibrate", "multipose", csv, "--fs", 100, "--init-s", 50, "--out", tmp_path / "cal.json")
    cal = ImuCalibration.load(tmp_path / "cal.json")
    # raw = accel_matrix @ f + accel_bias: the inverse of T_a K_a, scales within 0.3 %
    np.testing.assert_allclose(np.diag(cal.accel_matrix), np.diag(np.linalg.inv(accel_tedaldi_matrix(PA_U))), rtol=3e-3)
    np.testing.assert_allclose(np.diag(cal.gyro_matrix), np.diag(np.linalg.inv(gyro_tedaldi_matrix(PG_U))), rtol=3e-3)
    np.testing.assert_allclose(cal.accel_bias, -PA_U[6:], atol=5.0)


@pytest.mark.parametrize("kind", ["point", "line", "plane"])
def test_cli_minmax_degenerate_is_an_error_not_nan(tmp_path, kind):
    from typer.testing import CliRunner

    from imunav.cli.main import app

    np.savez(tmp_path / "m.npz", mag=degenerate_mag_clouds()[kind])
    r = CliRunner().invoke(app, ["calibrate", "mag", str(tmp_path / "m.npz"), "--method", "minmax",
                                 "--out", str(tmp_path / "c.json")])
    assert r.exit_code == 2 and "Traceback" not in r.stderr, r.stderr
    assert not (tmp_path / "c.json").exists()


def test_imucal_export_round_trips_through_imucal(tmp_path):
    """--imucal-out on imucal's shared continuous session (°/s in the file): imucal's own reader loads the file and
    it agrees with imucal's own Ferraris on the same session (issue 26: K_g came out 0.0179 for 1.028)."""
    imucal = pytest.importorskip("imucal")
    import pandas as pd
    from imucal.management import load_calibration_info
    from shared_data import data_path

    csv, secs = data_path("imucal", "example_ferraris_session.csv"), data_path("imucal", "example_ferraris_session_list.json")
    out = tmp_path / "imucal.json"
    r = CliRunner().invoke(app, ["calibrate", "ferraris", str(csv), "--sections", str(secs), "--fs", "102.4",
                                 "--gyro-unit", "deg/s", "--out", str(tmp_path / "cal.json"), "--imucal-out", str(out)])
    assert r.exit_code == 0, r.output
    assert "raw data in m/s^2 and deg/s, calibrated in m/s^2 and deg/s" in " ".join(r.output.split())
    mine = load_calibration_info(out)
    df = pd.read_csv(csv).set_index("n_samples")
    regions = imucal.ferraris_regions_from_section_list(df, pd.DataFrame(json.loads(Path(secs).read_text())).T)
    peer = imucal.FerrarisCalibration().compute(regions, sampling_rate_hz=102.4, from_acc_unit="m/s^2",
                                               from_gyr_unit="deg/s")
    assert (mine.from_gyr_unit, mine.gyr_unit, mine.from_acc_unit) == ("deg/s", "deg/s", "m/s^2")
    for k in ("K_a", "R_a", "b_a", "K_g", "R_g", "K_ga", "b_g"):
        a, b = np.asarray(getattr(mine, k)), np.asarray(getattr(peer, k))
        assert np.max(np.abs(a - b)) <= 1e-9 * np.max(np.abs(b)), (k, a, b)
    assert np.diag(mine.K_g) == pytest.approx([1.028, 0.982, 0.998], abs=1e-3)
