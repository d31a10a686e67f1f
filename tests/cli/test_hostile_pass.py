"""Issue 36: what a hostile pass found after the no-data-loss work -- one test per cause, through the CLI and the
public API.

Two outputs of one command on the same file or inside each other's folders, an output on a file a lab
definition names, a lab definition checked only when its step runs, raw parsing of user text, library
functions that accept nonsense.  ``tests/cli_hostile.py`` generates the same families for every command.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from builders import static_imu
from cli_contract import one_error_line as _exit_2
from typer.testing import CliRunner

from imunav.calib import ImuCalibration
from imunav.cli.main import app
from imunav.io import write_imu
from imunav.timeseries import ImuData

runner = CliRunner()


def _rec(n: int = 3000, fs: float = 50.0) -> ImuData:
    return static_imu(n, fs, seed=1)


def _snapshot(root: Path) -> dict[str, bytes]:
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


@pytest.fixture
def files(tmp_path):
    write_imu(_rec(), tmp_path / "good.npz")
    write_imu(_rec(), tmp_path / "good.csv")
    u = np.random.default_rng(0).normal(size=(400, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    np.savetxt(tmp_path / "mag.csv", 50 * u, delimiter=",", header="mag_x,mag_y,mag_z", comments="")
    for k in (1, 2, 3):
        ImuCalibration().save(tmp_path / f"cal{k}.json")
    return tmp_path


# ------------------------------------------------------------------ 1. two outputs of one command, one file
@pytest.mark.parametrize("argv", [
    ["calibrate", "mag", "mag.csv"],
    ["calibrate", "temperature", "cal1.json@20", "cal2.json@40", "cal3.json@60", "--orders", "1"],
])
def test_an_output_inside_the_report_folder_of_the_same_command_is_refused(files, monkeypatch, argv):
    monkeypatch.chdir(files)
    before = _snapshot(files)
    msg = _exit_2(runner.invoke(app, [*argv, "--out", "rep/report.json", "--report", "rep"]))
    assert "rep/report.json" in msg and "output folder rep" in msg
    assert _snapshot(files) == before and not (files / "rep").exists()


def test_an_output_folder_inside_another_output_folder_is_refused(tmp_path):
    from imunav.errors import InvalidInputError
    from imunav.files import check_outputs

    with pytest.raises(InvalidInputError, match="inside the run folder"):
        check_outputs([], [], folders=[tmp_path / "run" / "rep"], run_folders=[tmp_path / "run"])
    with pytest.raises(OSError, match="another output"):
        check_outputs([], [tmp_path / "a.json"], folders=[tmp_path / "a.json" / "rep"])


def test_lab_output_on_a_recording_the_definition_names_is_refused(files, monkeypatch):
    monkeypatch.chdir(files)
    (files / "lab.toml").write_text('[lab]\nsteps = ["recordings"]\n[recordings.a]\npath = "good.npz"\n'
                                    'test = "static"\n')
    before = _snapshot(files)
    msg = _exit_2(runner.invoke(app, ["lab", "--config", "lab.toml", "--out", "rep", "--quiet", "--json", "good.npz"]))
    assert "good.npz" in msg and "input" in msg
    msg = _exit_2(runner.invoke(app, ["lab", "--config", "lab.toml", "--out", ".", "--quiet"]))
    assert "holds the input" in msg
    assert _snapshot(files) == before and not (files / "rep").exists()


# ------------------------------------------------------------------ 2. a lab definition checked whole first
BAD_LABS = {
    "unknown-unit": ('[lab]\nsteps = ["recordings"]\n[recordings.a]\npath = "good.npz"\ntest = "static"\n'
                     'units = { gyro = "furlongs" }\n', ["[recordings.a]", "units", "furlongs"]),
    "unit-contradicts-file": ('[lab]\nsteps = ["recordings"]\n[recordings.a]\npath = "good.npz"\ntest = "static"\n'
                              'units = { gyro = "deg/s" }\n', ["[recordings.a]", "units", "deg/s"]),
    "rate-contradicts-stamps": ('[lab]\nsteps = ["recordings"]\n[recordings.a]\npath = "good.csv"\ntest = "static"\n'
                                'fs = 200.0\n', ["[recordings.a]", "fs"]),
    "unknown-gins-preset": ('[lab]\nsteps = ["gins"]\n[gins]\npreset = "nope"\n', ["[gins]", "preset", "nope"]),
    "unknown-preset-of-a-step-not-run": ('[lab]\nsteps = ["noise"]\n[temperature]\npreset = "nope"\n',
                                         ["[temperature]", "preset"]),
    "size-beyond-the-machine": ('[lab]\nsteps = ["simulate_tests"]\n[simulate_tests]\nstatic_duration_s = 1e12\n',
                                ["[simulate_tests]", "static_duration_s"]),
    # a step whose inputs no earlier step makes: refused before the first step (was a traceback, exit 1, or a
    # run folder left FAILED after the earlier steps ran)
    "calibration-without-its-tests": ('[lab]\nsteps = ["calibration"]\n', ["[calibration]", "simulate_tests"]),
    "noise-without-its-record": ('[lab]\nsteps = ["simulate_tests", "noise"]\n[simulate_tests]\n'
                                 'tests = ["hundred_position"]\n', ["[noise]", "static_long"]),
    "calibration-on-a-static-recording": ('[lab]\nsteps = ["recordings", "calibration"]\n[recordings.a]\n'
                                          'path = "good.npz"\ntest = "static"\n', ["[calibration]", "rate_table"]),
    "compensation-without-a-calibration": ('[lab]\nsteps = ["recordings", "compensation"]\n[recordings.a]\n'
                                           'path = "good.npz"\ntest = "static"\n', ["[compensation]", "calibration"]),
}


@pytest.mark.parametrize("name", list(BAD_LABS))
def test_a_bad_lab_definition_is_refused_before_the_first_step(files, monkeypatch, name):
    text, words = BAD_LABS[name]
    monkeypatch.chdir(files)
    (files / "lab.toml").write_text(text)
    msg = _exit_2(runner.invoke(app, ["lab", "--config", "lab.toml", "--out", "rep", "--quiet"]))
    assert "lab.toml" in msg and all(w in msg for w in words), msg
    assert not (files / "rep").exists()


def test_a_step_whose_input_step_failed_is_not_run_and_each_failure_is_one_line(tmp_path, monkeypatch):
    """A failing step is one stderr line (its traceback in the report, on stderr only with --debug); a step that
    takes its input from it is not run on a stand-in, and says so."""
    import json
    import sys
    import types

    from imunav.lab import runner as lab_runner

    ran = []

    def boom(ctx):
        raise RuntimeError("deliberate failure")

    def after(ctx):
        ran.append("zz_after")
        raise AssertionError("ran without its input")

    for name, fn, req in (("zz_boom", boom, None), ("zz_after", after, lambda lab, earlier: ["zz_boom"])):
        mod = types.ModuleType(f"imunav.lab.steps.{name}")
        mod.TITLE, mod.run = name, fn
        if req is not None:
            mod.requires = req
        monkeypatch.setitem(sys.modules, f"imunav.lab.steps.{name}", mod)
    monkeypatch.setattr(lab_runner, "available_steps", lambda: ["zz_after", "zz_boom"])
    monkeypatch.chdir(tmp_path)
    r = runner.invoke(app, ["lab", "--steps", "zz_boom,zz_after", "--out", "rep", "--quiet"])
    assert r.exit_code == 1 and "Traceback" not in r.stderr, r.stderr
    lines = r.stderr.strip().splitlines()
    assert lines == ["error: lab step zz_boom: RuntimeError: deliberate failure (details in rep/summary.md)",
                     "error: lab step zz_after: not run: it takes its input from the zz_boom step, which failed "
                     "(details in rep/summary.md)"], r.stderr
    assert ran == []
    steps = json.loads((tmp_path / "rep" / "summary.json").read_text())["steps"]
    assert "Traceback" in steps[0]["error"] and steps[1]["passed"] is False
    r = runner.invoke(app, ["--debug", "lab", "--steps", "zz_boom,zz_after", "--out", "rep2", "--quiet"])
    assert r.exit_code == 1 and "Traceback" in r.stderr


def test_the_library_checks_the_definition_whole(files):
    from imunav.errors import ConfigError
    from imunav.lab.runner import parse_lab_config

    with pytest.raises(ConfigError, match=r"\[gins\] preset"):
        parse_lab_config({"gins": {"preset": "nope"}})
    cfg = parse_lab_config({"_base_dir": str(files), "recordings": {"a": {"path": "good.npz", "test": "static"}},
                            "simulate_tests": {"model": str(files / "cal1.json")}})
    assert {p.name for p in cfg.inputs} == {"good.npz", "cal1.json"}


# ------------------------------------------------------------------ 3. user text parsed in the validation layer
def test_text_where_a_number_belongs_is_one_line_naming_the_option(files, monkeypatch):
    import json

    monkeypatch.chdir(files)
    msg = _exit_2(runner.invoke(app, ["calibrate", "temperature", "cal1.json@20", "cal2.json@40", "cal3.json@60",
                                      "--orders", "a", "--out", "t.json"]))
    assert "--orders" in msg and "'a'" in msg
    msg = _exit_2(runner.invoke(app, ["calibrate", "temperature", "cal1.json@warm", "cal2.json@40", "cal3.json@60",
                                      "--out", "t.json"]))
    assert "cal1.json@warm" in msg
    (files / "bat").mkdir()
    write_imu(_rec(), files / "bat" / "u1.csv")
    msg = _exit_2(runner.invoke(app, ["batch", "calibrate", "bat", "--columns", "{bad", "--out", "bo", "--quiet"]))
    assert "--columns" in msg and "JSON" in msg
    (files / "secs.json").write_text(json.dumps({k: {"start": "a" if k == "x_p" else 0, "end": 10} for k in
                                                 ("x_p", "x_a", "y_p", "y_a", "z_p", "z_a", "x_rot", "y_rot", "z_rot")}))
    msg = _exit_2(runner.invoke(app, ["calibrate", "ferraris", "good.csv", "--sections", "secs.json", "--fs", "50",
                                      "--out", "f.json"]))
    assert "x_p" in msg and "'a'" in msg
    assert not any((files / n).exists() for n in ("t.json", "bo", "f.json"))


# ------------------------------------------------------------------ 8. the public API validates like the CLI
def test_a_zero_or_non_unit_quaternion_is_no_rotation():
    from imunav.errors import InvalidInputError
    from imunav.rotation import dcm_from_quat, quat_rotate

    with pytest.raises(InvalidInputError, match=r"q is not a unit quaternion .*rows \[0\]"):
        dcm_from_quat([0, 0, 0, 0])
    with pytest.raises(InvalidInputError, match=r"rows \[1\]"):
        dcm_from_quat([[1, 0, 0, 0], [2, 0, 0, 0]])
    with pytest.raises(InvalidInputError, match="unit quaternion"):
        quat_rotate([0, 0, 0, 0], [1, 0, 0])
    q = np.array([1.0, 1e-9, 0, 0])  # the drift of a propagated attitude is accepted
    assert np.allclose(dcm_from_quat(q), np.eye(3), atol=1e-8)


def test_rotations_refuse_what_is_no_rotation():
    """A zero quaternion has no inverse nor logarithm, a NaN angle no quaternion, and a matrix that is not
    orthonormal with det +1 (ones, a mirror) no quaternion or Euler angles: each was a silent answer (or a raw
    ZeroDivisionError)."""
    from imunav.errors import InvalidInputError, NonFiniteError
    from imunav.rotation import (
        dcm_from_quat,
        euler_from_dcm,
        quat_from_dcm,
        quat_from_euler,
        quat_inverse,
        rotvec_from_dcm,
        rotvec_from_quat,
    )

    with pytest.raises(NonFiniteError, match="zero quaternion has no inverse"):
        quat_inverse([0, 0, 0, 0])
    assert np.allclose(quat_inverse([2.0, 0, 0, 0]), [0.5, 0, 0, 0])  # a non-unit one still has its inverse
    with pytest.raises(InvalidInputError, match=r"q is not a unit quaternion .*rows \[0\]"):
        rotvec_from_quat([0, 0, 0, 0])
    with pytest.raises(NonFiniteError, match=r"euler .* rows \[1\]"):
        quat_from_euler([[0, 0, 0], [np.nan, 0, 0]])
    for C, what in ((np.ones((3, 3)), "C C\\^T - I"), (-np.eye(3), "det -1")):
        for fn in (quat_from_dcm, euler_from_dcm, rotvec_from_dcm):
            with pytest.raises(InvalidInputError, match=f"C is not a rotation matrix at rows \\[0\\] .*{what}"):
                fn(C)
    C = dcm_from_quat(quat_from_euler(0.1, -0.2, 0.3))
    assert np.allclose(euler_from_dcm(C), [0.1, -0.2, 0.3]) and np.allclose(quat_from_dcm(C), quat_from_euler(0.1, -0.2, 0.3))


def test_allan_deviation_refuses_text_and_complex_samples():
    from imunav.errors import InvalidInputError
    from imunav.noise import allan_deviation

    for x in (["a", "b", "c", "d"], np.ones(10) * 1j, [1, 2, 3j, 4]):
        with pytest.raises(InvalidInputError, match="x must hold real numbers"):
            allan_deviation(x, fs=1.0)
    assert allan_deviation([1, 2, 4, 3], fs=1.0).tau.tolist() == [1.0, 2.0]  # integers are samples


def test_allan_deviation_needs_two_differences():
    from imunav.errors import InsufficientDataError
    from imunav.noise import allan_deviation

    with pytest.raises(InsufficientDataError, match="x: need at least 3 samples"):
        allan_deviation([1.0, 2.0], fs=1.0)
    with pytest.raises(InsufficientDataError, match="need at least 4 samples"):
        allan_deviation([1.0, 2.0, 3.0], fs=1.0, kind="hadamard")
    assert allan_deviation([1.0, 2.0, 4.0], fs=1.0).tau.tolist() == [1.0]


def test_a_complementary_gain_beyond_one_over_dt_is_refused():
    from imunav.attitude import Complementary
    from imunav.errors import InvalidInputError

    d = ImuData(np.arange(10) * 0.5, np.zeros((10, 3)), np.tile([0.0, 0.0, -9.8], (10, 1)))
    with pytest.raises(InvalidInputError, match=r"k_accel=5 .* 0.5 s .* at most 1/dt = 2"):
        Complementary(k_accel=5).run(d)
    with pytest.raises(InvalidInputError, match="k_mag"):
        Complementary(k_mag=50).step([0, 0, 0], [0, 0, -9.8], [1, 0, 0], 0.1)
    assert np.allclose(Complementary(k_accel=2).run(d).q_nb[-1], [1, 0, 0, 0])


def test_a_madgwick_gain_and_a_ukf_field_reference_that_are_no_physics_are_refused():
    from imunav.attitude import UKF, Madgwick
    from imunav.errors import InvalidInputError, NonFiniteError

    with pytest.raises(InvalidInputError, match="Madgwick.beta must be <= 10000"):
        Madgwick(beta=1e300)
    with pytest.raises(NonFiniteError, match="UKF.mag_ref_ned"):
        UKF(mag_ref_ned=[np.nan, 0.0, 0.0])
    with pytest.raises(InvalidInputError, match="non-zero"):
        UKF(mag_ref_ned=[0.0, 0.0, 0.0])
    assert Madgwick(beta=0.1).beta == 0.1 and np.allclose(UKF(mag_ref_ned=[20.0, 0.0, 45.0]).mag_ref_ned,
                                                          [20.0, 0.0, 45.0])


# ------------------------------------------------------------------ 5. a write the file system refuses
@pytest.mark.parametrize("out", ["o.h5", "o.npz", "o.csv"])
def test_a_refused_write_is_one_line_for_every_format(files, out):
    import os
    import resource
    import subprocess
    import sys

    def small_files():
        resource.setrlimit(resource.RLIMIT_FSIZE, (20000, 20000))

    pytest.importorskip("h5py")
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2] / "src"))
    r = subprocess.run([sys.executable, "-m", "imunav.cli.main", "convert", "good.csv", out], cwd=files,
                       capture_output=True, text=True, env=env, timeout=300, preexec_fn=small_files)
    assert r.returncode == 2, r.stderr  # not -11 (SIGSEGV inside the HDF5 library)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and out in lines[0] and "File too large" in lines[0], r.stderr
    assert not (files / out).exists() and not list(files.glob(f".{out}*"))


def test_a_write_refused_inside_a_lab_step_ends_the_lab(files):
    """A step whose figure the file system refuses is not a step's failure in a report that looks complete
    (manifest, exit 1): the lab ends with one line naming the file, exit 2, FAILED."""
    import os
    import resource
    import subprocess
    import sys

    from imunav.lab.runfolder import FAILED, MANIFEST

    def small_files():
        resource.setrlimit(resource.RLIMIT_FSIZE, (30000, 30000))

    (files / "lab.toml").write_text('[lab]\nsteps = ["recordings"]\n[recordings.a]\npath = "good.npz"\n'
                                    'test = "static"\n')
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2] / "src"))
    r = subprocess.run([sys.executable, "-m", "imunav.cli.main", "lab", "--config", "lab.toml", "--out", "rep",
                        "--quiet"], cwd=files, capture_output=True, text=True, env=env, timeout=600,
                       preexec_fn=small_files)
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: rep/") and "File too large" in lines[0], r.stderr
    assert (files / "rep" / FAILED).exists() and not (files / "rep" / MANIFEST).exists()


def test_hdf5_files_are_built_in_memory_and_read_back(files):
    pytest.importorskip("h5py")
    from imunav.io import read_imu
    from imunav.io.mat import write_mat

    rec = read_imu(files / "good.csv")
    for name, write in (("x.h5", write_imu), ("x.mat", lambda d, p: write_mat(d, p, version="7.3"))):
        write(rec, files / name)
        back = read_imu(files / name)
        assert np.array_equal(back.gyro, rec.gyro) and np.array_equal(back.t, rec.t)


# ------------------------------------------------------------------ 7. failures said, unreadable inputs refused
def test_a_batch_says_each_failed_item_on_stderr(files, monkeypatch):
    monkeypatch.chdir(files)
    r = runner.invoke(app, ["batch", "simulate", "2", "--static", "20", "--fs", "20", "--out", "b", "--executor",
                            "serial", "--quiet"])
    assert r.exit_code == 0, r.stderr
    # multiposition calibration of static records: every unit fails (no segments) -> one line per unit
    r = runner.invoke(app, ["batch", "calibrate", "b", "--out", "bc", "--executor", "serial", "--quiet"])
    assert r.exit_code == 1
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("error: ")]
    assert len(lines) == 2 and all("unit_" in ln for ln in lines), r.stderr
    msg = _exit_2(runner.invoke(app, ["batch", "noise", "b", "--terms", "X", "--out", "bn", "--executor", "serial",
                                      "--quiet"]))
    assert "--terms" in msg and "'X'" in msg and not (files / "bn").exists()


def test_info_refuses_what_it_cannot_read(files, monkeypatch):
    monkeypatch.chdir(files)
    np.savez(files / "cplx.npz", t=np.arange(10.0), gyro=np.ones((10, 3)) * (1 + 1j), accel=np.ones((10, 3)) * 1j)
    (files / "hdr.ulg").write_bytes(b"ULog\x01\x12\x35\x01" + bytes(8))
    msg = _exit_2(runner.invoke(app, ["info", "cplx.npz"]))
    assert "cplx.npz" in msg and "complex" in msg
    msg = _exit_2(runner.invoke(app, ["info", "hdr.ulg"]))
    assert "hdr.ulg" in msg and "no topic" in msg
    (files / "dup.csv").write_text("t,gyro_x,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z\n"
                                   + "".join(f"{k / 100},0,9,0,0,0,0,-9.8\n" for k in range(5)))
    msg = _exit_2(runner.invoke(app, ["info", "dup.csv"]))
    assert "dup.csv" in msg and "['gyro_x'] more than once" in msg


def test_an_empty_error_model_is_said_to_be_ideal(files, monkeypatch):
    from imunav.errors import ImunavWarning
    from imunav.sim import ImuErrorModel

    monkeypatch.chdir(files)
    (files / "empty.toml").write_text('name = "e"\n')
    r = runner.invoke(app, ["simulate", "static", "--duration", "2", "--fs", "10", "--model", "empty.toml", "--out",
                            "e.npz"])
    assert r.exit_code == 0 and "warning: empty.toml" in r.stderr and "ideal" in r.stderr, r.stderr
    with pytest.warns(ImunavWarning, match="ideal"):
        ImuErrorModel.from_toml(files / "empty.toml")
    (files / "m.toml").write_text('name = "m"\n[gyro]\nbias = [0.001, 0, 0]\n')
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ImuErrorModel.from_toml(files / "m.toml")


# ------------------------------------------------------------------ 6. exports into another tool's units
def test_px4_magnetometer_offsets_say_their_conversion_or_refuse_a_unit_that_does_not_fit(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    u = np.random.default_rng(0).normal(size=(400, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    np.savetxt("mag_T.csv", 48e-6 * u + [1e-5, 0, 0], delimiter=",", header="mag_x,mag_y,mag_z", comments="")
    # tesla read as the default gauss: a field of 4.8e-5 gauss is no field on Earth
    msg = _exit_2(runner.invoke(app, ["calibrate", "mag", "mag_T.csv", "--out", "m.json", "--px4-params", "m.params"]))
    assert "--mag-unit" in msg and "gauss" in msg and not Path("m.json").exists()
    r = runner.invoke(app, ["calibrate", "mag", "mag_T.csv", "--out", "m.json", "--px4-params", "m.params",
                            "--mag-unit", "T"])
    assert r.exit_code == 0, r.stderr
    assert "converted" in r.stdout and "from T to PX4's gauss (x 10000)" in r.stdout
    text = Path("m.params").read_text()
    assert "# Converted: CAL_MAG0_{X,Y,Z}OFF" in text
    off = float(next(ln.split("\t")[3] for ln in text.splitlines() if "\tCAL_MAG0_XOFF\t" in ln))
    assert off == pytest.approx(0.1, abs=0.01)  # 1e-5 T = 0.1 gauss


# ------------------------------------------------------------------ 4. work multiplied by an option is estimated
def test_taus_all_is_estimated_before_work(files, monkeypatch):
    from imunav.cli._limits import check_limits
    from imunav.errors import ImunavWarning

    monkeypatch.chdir(files)
    # 3,000 samples (60 s at 50 Hz): 1,500 averaging times, each a GLS fit term: said before the work
    with pytest.warns(ImunavWarning, match=r"noise --taus all: 1\.5\de\+03 averaging times .* minutes"):
        check_limits("noise", {"file": "good.npz", "taus": "all"})
    n = 200_000
    write_imu(_rec(n), files / "long.npz")
    msg = _exit_2(runner.invoke(app, ["noise", "long.npz", "--taus", "all"]))
    assert "--taus all" in msg and "--force" in msg
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_limits("noise", {"file": "long.npz", "taus": "octave"})  # the default grid: nothing to say


def test_lstm_training_is_estimated_before_work_and_memory_is_a_limit_not_a_bug(files, monkeypatch):
    """zupt train had no estimate: --windows-per-trial 1e9 ended in an internal error (a 313 GiB MemoryError),
    --hidden 100000 --layers 100 ran without a word.  Refused before work, naming the options; a MemoryError
    (a forced request) is one line and exit 2, not an internal error."""
    import imunav.noise

    monkeypatch.chdir(files)
    (files / "trials").mkdir()
    for extra, word in ((["--windows-per-trial", "1000000000"], "--windows-per-trial 1000000000"),
                        (["--hidden", "100000", "--layers", "100"], "--hidden 100000"),
                        (["--epochs", "1000000000"], "--epochs 1000000000")):
        msg = _exit_2(runner.invoke(app, ["zupt", "train", "trials", "--out", "z.npz", *extra]))
        assert msg.startswith("error: zupt train: 1 trials x") and word in msg and "--force" in msg, msg
    assert not (files / "z.npz").exists()

    def no_memory(*a, **k):
        raise MemoryError("Unable to allocate 313. GiB for an array")

    monkeypatch.setattr(imunav.noise, "allan_deviation", no_memory)
    msg = _exit_2(runner.invoke(app, ["noise", "good.npz", "--json", "n.json"]))
    assert msg == "error: out of memory (Unable to allocate 313. GiB for an array); reduce the request"


def test_a_grid_search_is_estimated_before_work(tmp_path, monkeypatch):
    """attitude benchmark --grid multiplies the work by the product of the grids' sizes: 10^5 parameter sets over
    the BROAD trials ran without an estimate; refused naming the grids (a repeated name counts once)."""
    monkeypatch.chdir(tmp_path)
    values = ",".join(str(k) for k in range(100))
    argv = ["attitude", "benchmark", "broad", "--filter", "madgwick", "--grid", f"beta={values}", "--grid",
            f"nosuch={values}", "--grid", "other=1,2,3,4,5,6,7,8,9,10"]
    msg = _exit_2(runner.invoke(app, argv))
    assert "--grid beta (100 values) x --grid nosuch (100 values) x --grid other (10 values) = 1e+05 parameter" \
        in msg and "--force" in msg, msg
    r = runner.invoke(app, [*argv, "--grid", "other=1"])  # 10^4 sets: under the limit, said, then run
    assert r.exit_code == 2 and r.stderr.startswith("warning: attitude benchmark: --grid beta (100 values)")
    assert "hours" in r.stderr and "no parameter 'nosuch'" in r.stderr


def test_a_forced_long_request_says_its_estimate_and_moves_its_bar(files, monkeypatch):
    """Forced past the limit, a request still says its estimate (a warning line); the noise bar moves through
    each channel's fit (the long part of --taus all), not only between the sensors."""
    import contextlib

    from imunav.cli import noise as noise_cmd
    from imunav.cli._limits import check_limits
    from imunav.errors import ImunavWarning
    from imunav.noise import allan_deviation, fit_noise

    monkeypatch.chdir(files)
    write_imu(_rec(200_000), files / "long.npz")
    with pytest.warns(ImunavWarning, match=r"noise --taus all: .* beyond its limits: running as --force asks"):
        check_limits("noise", {"file": "long.npz", "taus": "all", "force": True})
    calls = []
    r = allan_deviation(_rec(600).gyro, 50.0, "octave", units="rad/s")
    fit_noise(r, progress=lambda k, n: calls.append((k, n)))
    assert calls == [(k, 15) for k in range(1, 16)]  # five stages of each of the three channels
    reports = []

    @contextlib.contextmanager
    def recorder(description, *, quiet=False, total=None):
        yield lambda done, total_: reports.append((done, total_))

    monkeypatch.setattr(noise_cmd, "progress", recorder)
    out = runner.invoke(app, ["noise", "good.npz", "--taus", "octave"])
    assert out.exit_code == 0, out.stderr
    done = [d for d, _ in reports]
    assert done == list(range(1, 35)) and {t for _, t in reports[1:]} == {34}  # 2 x (Allan + 15 fit stages + PSD)


# ------------------------------------------------------------------ 9. an interrupt is never lost
@pytest.mark.parametrize("write_after", [False, True])
def test_an_interrupt_swallowed_in_a_callback_from_c_is_not_lost(tmp_path, monkeypatch, write_after):
    """SIGINT during numba's compilation raises KeyboardInterrupt inside a ctypes callback of llvmlite, where
    Python prints "Exception ignored" and goes on: the run used to finish with exit 0 and a manifest.  Latched,
    the interrupt is raised again before the next output is published or the run folder gets its manifest."""
    import ctypes
    import os
    import signal
    import sys

    from imunav.files import latch_interrupts, write_json
    from imunav.lab.runfolder import FAILED, MANIFEST, RunFolder

    old = signal.getsignal(signal.SIGINT)
    monkeypatch.setattr(sys, "unraisablehook", sys.unraisablehook)

    def swallowed() -> None:  # a callback from C, as llvmlite's object-cache notification
        os.kill(os.getpid(), signal.SIGINT)
        sum(range(100_000))

    callback = ctypes.CFUNCTYPE(None)(swallowed)
    run = tmp_path / "run"
    try:
        latch_interrupts()
        with pytest.raises(KeyboardInterrupt), RunFolder(run, "test"):
            write_json(run / "a.json", {"a": 1})
            callback()  # the interrupt lands here and is swallowed
            if write_after:
                write_json(run / "b.json", {"b": 2})
    finally:
        signal.signal(signal.SIGINT, old)
    assert not (run / MANIFEST).exists() and (run / FAILED).exists()
    assert not (run / "a.json").exists() and not (run / "b.json").exists()


def test_the_aftermath_of_an_interrupt_in_a_constructor_from_c_prints_nothing(monkeypatch):
    """An interrupt that lands inside llvmlite's ``PassBuilder`` constructor leaves a half-built object whose
    finaliser raises ``AttributeError`` ("Exception ignored in ObjectRef.__del__", 11 lines on stderr where the
    run ends with one).  Once an interrupt arrived, such unraisable errors print nothing; before it they still do."""
    import signal
    import sys

    from imunav.files import latch_interrupts

    old = signal.getsignal(signal.SIGINT)
    shown = []  # what Python's own hook would print
    monkeypatch.setattr(sys, "unraisablehook", lambda u: shown.append(str(u.exc_value)))

    class HalfBuilt:
        def __del__(self):
            raise AttributeError("'PassBuilder' object has no attribute '_as_parameter_'")

    try:
        latch_interrupts()
        HalfBuilt()  # before any interrupt: printed as Python does
        assert len(shown) == 1 and "PassBuilder" in shown[0]
        with pytest.raises(KeyboardInterrupt):
            signal.getsignal(signal.SIGINT)(signal.SIGINT, None)
        HalfBuilt()  # after it: silent
        assert len(shown) == 1
        latch_interrupts()  # a new command starts clean
    finally:
        signal.signal(signal.SIGINT, old)
    HalfBuilt()
    assert len(shown) == 2


def test_a_negative_count_scale_mirrors_the_triad_and_is_refused(tmp_path, monkeypatch):
    """One scale for three axes that is negative mirrors them (a left-handed frame, no sensor's): refused by the
    option's domain and by the library; a per-axis scale may still count one axis the other way."""
    from imunav.errors import UnitError

    monkeypatch.chdir(tmp_path)
    rng = np.random.default_rng(0)
    raw = np.column_stack([rng.normal(0, 10, (500, 5)), 16384 + rng.normal(0, 10, 500)])
    np.savetxt("raw.csv", raw, delimiter=",", header="gx,gy,gz,ax,ay,az", comments="")
    for flag in ("--gyro-scale", "--accel-scale"):
        msg = _exit_2(runner.invoke(app, ["info", "raw.csv", "--fs", "50", "--gyro-unit", "counts", "--accel-unit",
                                          "counts", "--gyro-scale", "1e-4", "--accel-scale", "6e-4", flag, "-1"]))
        assert msg.startswith(f"error: {flag} -1") and "(0, 1e+06]" in msg
    with pytest.raises(UnitError, match=r"gyro_scale=-0\.001: .* mirrors"):
        ImuData.from_arrays(None, raw[:, :3], raw[:, 3:], fs=50.0, gyro_unit="counts", gyro_scale=-1e-3,
                            accel_unit="counts", accel_scale=6e-4)
    with pytest.raises(UnitError, match=r"scales\['mag'\]=-0\.1"):
        from imunav.io import read_imu

        np.savetxt("m.csv", np.column_stack([raw, raw[:, :3]]), delimiter=",", comments="",
                   header="gx,gy,gz,ax,ay,az,mx,my,mz")
        read_imu("m.csv", fs=50.0, units={"mag": "counts"}, scales={"mag": -0.1})
    d = ImuData.from_arrays(None, raw[:, :3], raw[:, 3:], fs=50.0, gyro_unit="counts", gyro_scale=[1e-3, -1e-3, 1e-3],
                            accel_unit="counts", accel_scale=6e-4)
    assert np.allclose(d.gyro[:, 1], -1e-3 * raw[:, 1])


# ------------------------------------------------------------------ leftovers of the second pass
@pytest.fixture(scope="module")
def kfgins_folder(tmp_path_factory):
    """A KF-GINS folder of ``gins simulate`` (120 s at 10 Hz), made once for the module."""
    root = tmp_path_factory.mktemp("kfgins")
    r = runner.invoke(app, ["gins", "simulate", "--out", str(root / "d"), "--duration", "120", "--fs", "10",
                            "--seed", "3"])
    assert r.exit_code == 0, r.output
    return root / "d"


@pytest.mark.parametrize("outputpath", [".", "imu.txt", "..", "kf-gins.yaml"])
def test_a_kfgins_outputpath_follows_the_rule_of_out(tmp_path, monkeypatch, outputpath, kfgins_folder):
    """A KF-GINS YAML's ``outputpath`` is the output folder as ``--out`` is: ``"."`` (the YAML's own folder)
    wrote KF-GINS's outputs beside the IMU, GNSS and YAML files that ``--out`` there refuses; now refused the
    same way, naming the YAML and its key, before anything is written."""
    import shutil

    monkeypatch.chdir(tmp_path)
    shutil.copytree(kfgins_folder, "d")
    yaml = Path("d/kf-gins.yaml")
    yaml.write_text(yaml.read_text().replace('outputpath: "result"', f'outputpath: "{outputpath}"'))
    before = _snapshot(tmp_path)
    msg = _exit_2(runner.invoke(app, ["gins", "run", "--config", "d/kf-gins.yaml", "--no-plots"]))
    assert msg.startswith("error: d/kf-gins.yaml, key 'outputpath': the output folder") and "--out DIR" in msg, msg
    assert ("holds the inputs" if outputpath in (".", "..") else "is the input") in msg
    assert _snapshot(tmp_path) == before
    if outputpath != ".":
        return
    # --out there is refused by the same rule; a folder of its own is written
    assert "holds the input" in _exit_2(runner.invoke(app, ["gins", "run", "--config", "d/kf-gins.yaml", "--out", "d",
                                                            "--no-plots"]))
    yaml.write_text(yaml.read_text().replace(f'outputpath: "{outputpath}"', 'outputpath: "res"'))
    r = runner.invoke(app, ["gins", "run", "--config", "d/kf-gins.yaml", "--no-plots"])
    assert r.exit_code == 0, r.output
    assert Path("d/res/KF_GINS_Navresult.nav").is_file()


def test_a_numba_cache_the_file_system_refuses_is_named_with_its_fix(files, tmp_path):
    """numba writes its cache of compiled kernels on first use; a write the file system refused there (a file-size
    limit) ended as ``error: File too large``, naming no file: now the cache file and what to do."""
    import os
    import resource
    import subprocess
    import sys

    def small_files():
        resource.setrlimit(resource.RLIMIT_FSIZE, (1024, 1024))

    cache = tmp_path / "numba-cache"  # empty: numba compiles and writes there first (it takes NUMBA_CACHE_DIR first)
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2] / "src"), NUMBA_CACHE_DIR=str(cache))
    env.pop("IMUNAV_DEBUG", None)
    argv = [sys.executable, "-m", "imunav.cli.main", "info", "good.csv"]
    r = subprocess.run(argv, cwd=files, capture_output=True, text=True, env=env, timeout=300, preexec_fn=small_files)
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: numba could not write its cache of imunav's compiled "
                                                   f"kernels, {cache}{os.sep}"), r.stderr
    assert "(File too large)" in lines[0] and "ulimit -f" in lines[0] and "imunav warmup" in lines[0]
    r = subprocess.run([*argv[:3], "--debug", *argv[3:]], cwd=files, capture_output=True, text=True, env=env,
                       timeout=300, preexec_fn=small_files)
    assert r.returncode == 2 and "Traceback" in r.stderr and "numba/core/caching.py" in r.stderr, r.stderr


def test_no_writable_numba_cache_folder_is_a_user_error_naming_the_folders(files, monkeypatch):
    """Where numba may write none of its cache folders (a read-only install, no writable home) it raises a
    RuntimeError at the first import of a kernel module: an internal error ("this is a bug"); now one line naming
    the folders tried and NUMBA_CACHE_DIR, exit 2, the traceback with --debug."""
    import imunav.io

    monkeypatch.chdir(files)
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.delenv("IMUNAV_DEBUG", raising=False)
    src = str(Path(imunav.io.__file__).parent / "_text.py")

    def no_locator(*a, **k):
        raise RuntimeError(f"cannot cache function '_fixed_into': no locator available for file '{src}'")

    monkeypatch.setattr(imunav.io, "read_imu", no_locator)
    msg = _exit_2(runner.invoke(app, ["info", "good.csv"]))
    assert msg.startswith(f"error: numba cannot cache imunav's compiled kernels (of {src}): none of its cache "
                          f"folders can be written ({Path(src).parent / '__pycache__'}, "), msg
    assert msg.endswith("set NUMBA_CACHE_DIR to a folder you may write (e.g. export NUMBA_CACHE_DIR=/tmp/numba-cache)")
    r = runner.invoke(app, ["--debug", "info", "good.csv"])
    assert r.exit_code == 2 and "Traceback" in r.stderr and "no locator available" in r.stderr
    # a RuntimeError of another origin is still an internal error
    monkeypatch.setattr(imunav.io, "read_imu", lambda *a, **k: (_ for _ in ()).throw(RuntimeError("boom")))
    assert "internal error: RuntimeError: boom" in _exit_2(runner.invoke(app, ["info", "good.csv"]), 1)


def _torch_errors():
    torch = pytest.importorskip("torch")
    errs = [MemoryError("Unable to allocate 12. GiB"),
            RuntimeError("CUDA out of memory. Tried to allocate 2.00 GiB (GPU 0; 15.78 GiB total capacity)"),
            RuntimeError("[enforce fail at alloc_cpu.cpp:117] data. DefaultCPUAllocator: not enough memory: you "
                         "tried to allocate 8589934592 bytes.")]
    for t in (getattr(torch, "OutOfMemoryError", None), getattr(torch.cuda, "OutOfMemoryError", None)):
        if isinstance(t, type):
            errs.append(t("CUDA out of memory. Tried to allocate 20.00 MiB"))
    return torch, errs


def test_lstm_training_out_of_memory_is_a_limit_not_a_bug(tmp_path, monkeypatch):
    """``zupt train --force`` whose training torch cannot allocate (``torch.OutOfMemoryError``, or the
    ``RuntimeError`` "CUDA out of memory" / "not enough memory" of older torch) ended as "internal error ... this is a
    bug": now a MemoryError from ``train_lstm`` that says what the training held and what to reduce, and on the
    command line one line, exit 2, no model written.  Another RuntimeError of torch is still a bug."""
    import scipy.io

    import imunav.learn
    from imunav.learn import LstmConfig, train_lstm
    from imunav.sim.gait import simulate_gait

    torch, errs = _torch_errors()
    monkeypatch.chdir(tmp_path)
    sim = simulate_gait("walk", 4, rng=1, error_model=None)
    (tmp_path / "trials").mkdir()
    imu = np.column_stack([sim.imu.accel, sim.imu.gyro])
    scipy.io.savemat(tmp_path / "trials" / "t.mat", {"imu": imu, "ts": sim.imu.t, "gt": np.zeros((sim.imu.n, 3)),
                                                     "zv_shoe_opt": sim.stance.astype(float)})
    monkeypatch.setattr(imunav.learn, "best_labels", lambda tr, *a, **k: (tr.labels["shoe"], "shoe", 0.1))
    argv = ["zupt", "train", "trials", "--out", "z.npz", "--shoe-threshold", "1e7", "--epochs", "1",
            "--windows-per-trial", "2", "--layers", "1", "--hidden", "4", "--force"]
    for err in errs:
        def oom(*a, _err=err, **k):
            raise _err

        monkeypatch.setattr(torch.nn.LSTM, "forward", oom)
        msg = _exit_2(runner.invoke(app, argv))
        assert msg.startswith("error: training the LSTM ran out of memory (") and "internal error" not in msg, msg
        assert "1 x 4 LSTM units" in msg and "reduce the model (--hidden / --layers)" in msg, msg
        assert not (tmp_path / "z.npz").exists()
        with pytest.raises(MemoryError, match=r"LstmConfig\.hidden / layers; command line: --hidden / --layers"):
            train_lstm([sim.imu], [sim.stance], LstmConfig(layers=1, hidden=4, epochs=1, windows_per_trial=2))
    r = runner.invoke(app, ["--debug", *argv])
    assert r.exit_code == 2 and "Traceback" in r.stderr and "in oom" in r.stderr

    def bug(*a, **k):
        raise RuntimeError("input.size(-1) must be equal to input_size")

    monkeypatch.setattr(torch.nn.LSTM, "forward", bug)
    assert "internal error: RuntimeError" in _exit_2(runner.invoke(app, argv), 1)
    monkeypatch.undo()


def _profile(gyro_n: float):
    from imunav.noise import NoiseProfile, NoiseTerm, SensorNoise

    nan = float("nan")

    def sensor(unit, n):
        return SensorNoise(unit, NoiseTerm([n] * 3, [nan] * 3, [True] * 3), NoiseTerm([0.0] * 3, [nan] * 3, [False] * 3),
                           NoiseTerm([1e-5] * 3, [nan] * 3, [False] * 3))

    return NoiseProfile(fs=10.0, duration_s=600.0, gyro=sensor("rad/s", gyro_n), accel=sensor("m/s^2", 1e-3))


def test_a_filter_whose_numbers_overflow_is_refused_not_written(tmp_path, monkeypatch):
    """A noise far outside any sensor's (a hand-edited profile's 1e300 rad/s/sqrt(Hz)) overflows the filters:
    ``attitude run`` said "q has non-finite values ...; remove or interpolate them first" (about the input), and
    ``gins run`` exited 0 with NaN sigma files, every GNSS fix rejected.  Both now say the filter diverged and
    what it was given, exit 2, nothing written."""
    monkeypatch.chdir(tmp_path)
    write_imu(_rec(600), tmp_path / "good.npz")
    _profile(1e300).write(tmp_path / "huge.toml")
    for extra, given in ((["--param", "gyro_noise_density=1e300"], "--param gyro_noise_density=1e+300"),
                         (["--noise", "huge.toml"], "--noise huge.toml")):
        msg = _exit_2(runner.invoke(app, ["attitude", "run", "good.npz", "--filter", "mekf", "--json", "a.json",
                                          *extra]))
        assert msg.startswith("error: mekf diverged: its attitude is not finite from sample ") and given in msg, msg
    r = runner.invoke(app, ["gins", "simulate", "--out", "d", "--duration", "120", "--fs", "10", "--seed", "3"])
    assert r.exit_code == 0, r.output
    msg = _exit_2(runner.invoke(app, ["gins", "run", "--config", "d/kf-gins.yaml", "--out", "o", "--no-plots",
                                      "--noise", "huge.toml"]))
    assert msg.startswith("error: GinsFilter.run diverged: its covariance is not finite from t = ") and \
        "gyro_noise_density 1e+300" in msg, msg
    assert not (tmp_path / "o").exists() and not (tmp_path / "a.json").exists()
    _profile(1e-3).write(tmp_path / "fine.toml")  # the same run with a sensor's noise
    r = runner.invoke(app, ["gins", "run", "--config", "d/kf-gins.yaml", "--out", "o", "--no-plots", "--noise",
                            "fine.toml"])
    assert r.exit_code == 0, r.output


@pytest.mark.parametrize("extra, words", [
    (["--shifts", "0,0"], "shifts_s repeats 0 s (--shifts)"),
    (["--every", "60", "--shifts", "0,60"], "shifts_s 60 s is outside [0, every_s = 60 s) (--shifts, --every)"),
    (["--every", "20", "--length", "30"], "need every_s > length_s > 0 (--every > --length > 0); got every_s=20"),
])
def test_an_outage_protocol_that_counts_outages_twice_is_refused(tmp_path, extra, words):
    """``gins outage-test --shifts 0,0`` ran the same outages twice and reported 4/4 inside 3 sigma for two
    outages; a shift of a period or more repeats a shorter one's windows.  Refused before any work (also
    through the API: outage_test)."""
    from imunav.errors import InvalidInputError
    from imunav.ins.gins.outage import check_protocol

    msg = _exit_2(runner.invoke(app, ["gins", "outage-test", "--out", str(tmp_path / "o"), "--converge", "30",
                                      "--length", "10", *extra]))
    assert words in msg, msg
    assert not (tmp_path / "o").exists()
    with pytest.raises(InvalidInputError, match="repeats 5"):
        check_protocol(15.0, 10.0, (0.0, 5.0, 5.0))
    check_protocol(15.0, 10.0, (0.0, 5.0, 10.0))  # the car example of the guide
    from imunav.ins.gins.logrun import log_outage_test
    from imunav.sim.robot_log import simulate_robot_log

    with pytest.raises(InvalidInputError, match="repeats 0"):  # the log run's outage test too, before any run
        log_outage_test(simulate_robot_log(3, distance_m=80.0).sources, every_s=60.0, length_s=10.0,
                        shifts_s=(0.0, 0.0))


def test_a_recording_of_unknown_format_is_refused_in_command_line_words(tmp_path):
    """``info`` on a folder (a comma2k19 segment) or an unknown suffix said "pass format= one of [...]", the
    library's keyword: now the flag, and what a folder is."""
    from imunav.errors import InvalidInputError
    from imunav.io import read_imu

    (tmp_path / "seg").mkdir()
    msg = _exit_2(runner.invoke(app, ["info", str(tmp_path / "seg")]))
    assert "from a folder that is not a ROS 2 bag" in msg and "give --format NAME, NAME one of csv" in msg, msg
    assert "format=" not in msg
    (tmp_path / "r.foo").write_text("1,2,3\n")
    assert "give --format NAME" in _exit_2(runner.invoke(app, ["info", str(tmp_path / "r.foo")]))
    with pytest.raises(InvalidInputError, match=r"give format=NAME \(command line: --format NAME\)"):
        read_imu(tmp_path / "r.foo")
