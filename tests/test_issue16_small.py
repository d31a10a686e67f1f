"""The single cases of issue 16 (items 5 and 6 "Smaller"): each misbehaved before its fix."""

from __future__ import annotations

import os
import time
import warnings

import numpy as np
import pytest
from typer.testing import CliRunner

from imunav.cli.main import app
from imunav.errors import (
    DegenerateGeometryError,
    ImunavWarning,
    InvalidInputError,
    ShapeError,
)
from imunav.io import read_imu, write_imu
from imunav.timeseries import ImuData, describe

G = 9.80665


def _cli(*args, **kw):
    return CliRunner().invoke(app, [str(a) for a in args], **kw)


def _one_line(r, code=2):
    assert r.exit_code == code, (r.exit_code, r.stdout[-800:], r.stderr[-1500:])
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    return lines[0]


def _static(n=3000, fs=100.0, accel_scale=1.0, seed=0):
    r = np.random.default_rng(seed)
    return ImuData.from_arrays(None, r.normal(0, 0.01, (n, 3)), r.normal([0, 0, -G], 0.01, (n, 3)) * accel_scale,
                               fs=fs)


# ---------------------------------------------------------------- --fs with a time column
def test_fs_contradicting_the_time_column_is_an_error(tmp_path):
    p = write_imu(_static(), tmp_path / "rec.csv")
    with pytest.raises(InvalidInputError, match=r"time column \(samples at 100 Hz\).*fs=50"):
        read_imu(p, fs=50.0)
    assert read_imu(p, fs=100.0).n == 3000  # agreeing: accepted
    assert "fs=50" in _one_line(_cli("info", p, "--fs", "50"))


# ---------------------------------------------------------------- option ranges
@pytest.mark.parametrize("limit", ["-1", "0"])
def test_zupt_benchmark_limit_must_be_positive(tmp_path, limit):
    line = _one_line(_cli("zupt", "benchmark", tmp_path, "--limit", limit))
    assert "--limit" in line


def test_lab_with_an_empty_step_list_is_refused(tmp_path):
    assert "no lab step" in _one_line(_cli("lab", "--steps", ",", "--out", tmp_path / "r", "--quiet"))
    assert not (tmp_path / "r").exists()


def test_unknown_option_in_a_step_table_is_exit_2(tmp_path):
    cfg = tmp_path / "lab.toml"
    cfg.write_text("[attitude]\nmc_run = 3\n")  # typo of mc_runs
    line = _one_line(_cli("lab", "--config", cfg, "--out", tmp_path / "r", "--quiet"))
    assert "mc_run" in line and "[attitude]" in line
    assert not (tmp_path / "r").exists()


@pytest.mark.parametrize("cmd", [["batch", "calibrate"], ["batch", "noise"]])
def test_address_without_the_dask_executor_is_refused(tmp_path, cmd):
    write_imu(_static(), tmp_path / "u1.npz")
    assert "--executor dask" in _one_line(_cli(*cmd, tmp_path, "--address", "tcp://127.0.0.1:1", "--quiet"))
    assert not (tmp_path / "calibration").exists() and not (tmp_path / "noise").exists()
    from imunav.lab.montecarlo import run_batch

    with pytest.raises(InvalidInputError, match="dask"):
        run_batch(abs, [1], executor="serial", address="tcp://x:1")


def test_attitude_montecarlo_address_without_dask_is_refused():
    assert "--executor dask" in _one_line(_cli("attitude", "montecarlo", "--runs", "1", "--executor", "serial",
                                               "--address", "tcp://127.0.0.1:1"))


def test_a_dask_scheduler_that_does_not_answer_fails_fast(tmp_path):
    pytest.importorskip("dask.distributed")
    write_imu(_static(), tmp_path / "u1.npz")
    t0 = time.monotonic()
    line = _one_line(_cli("batch", "noise", tmp_path, "--executor", "dask", "--address", "tcp://127.0.0.1:9",
                          "--quiet"))
    assert "did not answer" in line and time.monotonic() - t0 < 25.0
    assert not (tmp_path / "noise").exists()


@pytest.mark.parametrize("gate", ["0", "-1", "nan"])
def test_gate_m_must_be_positive(tmp_path, gate):
    from imunav.airdata.filter import ThesisFilter

    with pytest.raises(InvalidInputError, match="gate_m"):
        ThesisFilter(robust="gate", gate_m=float(gate)).run(np.zeros((20, 3)))
    assert _cli("airdata", "simulate", "cruise", "--duration", "20", "--out", tmp_path / "a.npz").exit_code == 0
    assert "gate" in _one_line(_cli("airdata", "run", tmp_path / "a.npz", "--robust", "gate", "--gate-m", gate))


# ---------------------------------------------------------------- statistics of extreme values
def test_std_of_a_constant_1e300_signal_is_zero():
    d = ImuData.from_arrays(None, np.full((100, 3), 1e300), np.tile([0, 0, -G], (100, 1)), fs=100)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        ch = {c["channel"]: c for c in describe(d).channels}
    assert ch["gyro_x"]["std"] == 0.0 and ch["gyro_x"]["mean"] == pytest.approx(np.degrees(1e300), rel=1e-12)
    assert ch["accel_z"]["std"] == 0.0


def test_channels_in_rows_are_refused():
    from imunav.noise import allan_deviation, psd

    x = np.random.default_rng(0).normal(size=(6, 5000))
    with pytest.raises(ShapeError, match=r"transposed: pass x\.T"):
        allan_deviation(x, 100.0)
    with pytest.raises(ShapeError, match="transposed"):
        psd(x, 100.0)
    assert allan_deviation(x.T, 100.0).adev.shape[1] == 6


def test_accelerometer_in_g_at_rest_warns(tmp_path):
    d = _static(accel_scale=1 / G)  # |f| = 1 at rest: the file was in g
    with pytest.warns(ImunavWarning, match="in g"):
        s = describe(d)
    assert s.warnings and "--accel-unit g" in s.warnings[0]
    with warnings.catch_warnings():
        warnings.simplefilter("error", ImunavWarning)
        assert describe(_static()).warnings == []  # m/s^2: no warning
    p = write_imu(d, tmp_path / "ing.csv")
    r = _cli("info", p, "--json", tmp_path / "i.json")
    assert r.exit_code == 0
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("warning: ") and "in g" in lines[0]


# ---------------------------------------------------------------- output files
def test_airdata_simulate_out_csv_is_refused(tmp_path):
    assert ".npz" in _one_line(_cli("airdata", "simulate", "cruise", "--duration", "20", "--out", tmp_path / "x.csv"))
    assert not (tmp_path / "x.csv").exists()


def test_failed_zupt_run_out_leaves_no_temp_file(tmp_path, monkeypatch):
    from shared_data import data_path

    trial = sorted(data_path("foot", "pyshoe_vicon").glob("*.mat"))[0]

    def disk_full(*a, **k):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(np, "savez_compressed", disk_full)
    r = _cli("zupt", "run", trial, "--out", tmp_path / "z.npz")
    assert "No space left" in _one_line(r)
    assert list(tmp_path.iterdir()) == []


def test_json_and_figure_outputs_follow_the_umask(tmp_path):
    """--plot / --yaml / --json files were created 0600 by mkstemp; they must get 0666 & ~umask like the rest."""
    old = os.umask(0o022)
    try:
        write_imu(_static(), tmp_path / "st.csv")
        assert _cli("noise", tmp_path / "st.csv", "--terms", "N,K", "--yaml", tmp_path / "imu.yaml",
                    "--json", tmp_path / "n.json").exit_code == 0
        assert _cli("airdata", "simulate", "cruise", "--duration", "20", "--out", tmp_path / "a.npz",
                    "--json", tmp_path / "as.json").exit_code == 0
        assert _cli("airdata", "run", tmp_path / "a.npz", "--plot", tmp_path / "ar.png",
                    "--json", tmp_path / "ar.json").exit_code == 0
        import matplotlib

        from imunav.attitude.plot import save

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        save(plt.figure(), tmp_path / "fig.png")
    finally:
        os.umask(old)
    modes = {p.name: p.stat().st_mode & 0o777 for p in tmp_path.iterdir()}
    assert set(modes.values()) == {0o644}, modes


# ---------------------------------------------------------------- calibration degenerate input
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
    from imunav.calib.ferraris import FERRARIS_SECTIONS, ferraris

    secs = _ferraris_sections(np.random.default_rng(0))
    np.testing.assert_allclose(ferraris(secs, 100.0).calibration.gyro_matrix, np.eye(3), atol=1e-3)
    with pytest.raises(DegenerateGeometryError, match="accelerometer matrix is degenerate"):
        ferraris({k: secs["x_p"] for k in FERRARIS_SECTIONS}, 100.0)
    with pytest.raises(DegenerateGeometryError, match="y_rot"):
        ferraris({**secs, "y_rot": secs["x_p"]}, 100.0)  # a "rotation" without rotation
    with pytest.raises(DegenerateGeometryError, match="x_p, x_a"):
        ferraris({**secs, "x_p": secs["x_a"], "x_a": secs["x_p"]}, 100.0)  # swapped poses


def _sphere(n=500, seed=1):
    u = np.random.default_rng(seed).normal(size=(n, 3))
    return u / np.linalg.norm(u, axis=1, keepdims=True)


@pytest.mark.parametrize("kind", ["repeated", "zeros", "denormals"])
def test_fit_ellipsoid_refuses_degenerate_clouds(kind):
    from imunav.calib.magnetometer import fit_ellipsoid

    h = {"repeated": np.tile([20.0, -5.0, 40.0], (200, 1)), "zeros": np.zeros((200, 3)),
         "denormals": _sphere() * 1e-310}[kind]
    with pytest.raises(DegenerateGeometryError):
        fit_ellipsoid(h)


def test_fit_ellipsoid_refuses_values_beyond_any_unit():
    from imunav.calib.magnetometer import fit_ellipsoid

    with pytest.raises(InvalidInputError, match="no unit"):
        fit_ellipsoid(_sphere() * 1e200)


def test_fit_ellipsoid_fits_a_perfect_noise_free_sphere():
    from imunav.calib.magnetometer import fit_ellipsoid

    for field_norm in (None, 50.0):
        c = fit_ellipsoid(50.0 * _sphere() + [10.0, -5.0, 3.0], field_norm=field_norm)
        np.testing.assert_allclose(c.b, [10.0, -5.0, 3.0], atol=1e-9)
        np.testing.assert_allclose(c.A, np.eye(3), atol=1e-9)
        assert c.field_norm == pytest.approx(50.0, rel=1e-12)


# ---------------------------------------------------------------- progress of the lab
def test_lab_tasks_end_at_100_percent_and_the_monte_carlo_reports_progress(tmp_path):
    from imunav.lab.montecarlo import run_montecarlo
    from imunav.lab.runner import LabContext
    from imunav.scenarios import attitude_paper

    class Recorder:
        def __init__(self):
            self.tasks = {}

        def add_task(self, description, total=None, **kw):
            self.tasks[description] = {"total": total, "completed": 0}
            return description

        def advance(self, tid, n=1):
            self.tasks[tid]["completed"] += n

        def update(self, tid, **kw):
            self.tasks[tid].update({k: v for k, v in kw.items() if k in ("total", "completed")})

    rec = Recorder()
    ctx = LabContext(out_dir=tmp_path, seed=0, progress=rec)
    with ctx.task("unknown length", total=None):
        pass
    t = rec.tasks["unknown length"]
    assert t["total"] and t["completed"] == t["total"]
    seen = []
    run_montecarlo(attitude_paper, 3, seed=0, executor="serial", batched=True, chunk_size=1, duration=5.0,
                   progress=lambda done, total: seen.append((done, total)))
    assert seen == [(1, 3), (2, 3), (3, 3)]
