"""`imunav batch`: executor options, checked before any unit is processed."""

from __future__ import annotations

import time

import pytest
from builders import static_imu
from cli_contract import invoke, one_error_line

from imunav.errors import InvalidInputError
from imunav.io import write_imu


@pytest.mark.parametrize("cmd", [["batch", "calibrate"], ["batch", "noise"]])
def test_address_without_the_dask_executor_is_refused(tmp_path, cmd):
    write_imu(static_imu(3000), tmp_path / "u1.npz")
    assert "--executor dask" in one_error_line(invoke(*cmd, tmp_path, "--address", "tcp://127.0.0.1:1", "--quiet"))
    assert not (tmp_path / "calibration").exists() and not (tmp_path / "noise").exists()
    from imunav.lab.montecarlo import run_batch

    with pytest.raises(InvalidInputError, match="dask"):
        run_batch(abs, [1], executor="serial", address="tcp://x:1")


def test_a_dask_scheduler_that_does_not_answer_fails_fast(tmp_path):
    pytest.importorskip("dask.distributed")
    write_imu(static_imu(3000), tmp_path / "u1.npz")
    t0 = time.monotonic()
    line = one_error_line(invoke("batch", "noise", tmp_path, "--executor", "dask", "--address", "tcp://127.0.0.1:9",
                                 "--quiet"))
    assert "did not answer" in line and time.monotonic() - t0 < 25.0
    assert not (tmp_path / "noise").exists()


def test_batch_gins_takes_the_executor_options_of_the_other_batches(tmp_path):
    """batch gins: an address without the Dask executor is refused in one line before any log runs; a folder
    without a log says what a log is."""
    (tmp_path / "a.bag").write_bytes(b"#ROSBAG V2.0\n")
    line = one_error_line(invoke("batch", "gins", tmp_path, "--address", "tcp://127.0.0.1:1", "--quiet"))
    assert "--executor dask" in line and not (tmp_path / "gins").exists()
    (tmp_path / "a.bag").unlink()
    (tmp_path / "notes.txt").write_text("no log here")
    assert ".bag" in one_error_line(invoke("batch", "gins", tmp_path, "--quiet"))
