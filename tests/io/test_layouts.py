"""Named CSV layouts (imunav.io.layouts): EuRoC / TUM-VI, Kalibr, ulog2csv's sensor_combined, x-io."""

from __future__ import annotations

import numpy as np
import pytest
from shared_data import data_path
from typer.testing import CliRunner

from imunav.cli.main import app
from imunav.errors import InvalidInputError
from imunav.io import read_imu

runner = CliRunner()
T0 = 1_403_636_579_758_555_392  # EuRoC MH_01's first IMU stamp, ns: not exact as a float64


def _rows(n=50):
    rng = np.random.default_rng(3)
    stamps = T0 + np.arange(n, dtype=np.int64) * 5_000_000 + rng.integers(0, 3, n)  # ns jitter of a real clock
    return stamps, rng.normal(0, 0.2, (n, 3)), rng.normal([9.8, 0, 0], 0.1, (n, 3))


@pytest.mark.parametrize("layout", ["euroc", "tum-vi"])
def test_euroc_tumvi(tmp_path, layout):
    stamps, w, a = _rows()
    p = tmp_path / "data.csv"
    lines = ["#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
             "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]"]
    lines += [",".join([str(s)] + [repr(float(v)) for v in (*w[i], *a[i])]) for i, s in enumerate(stamps)]
    p.write_text("\n".join(lines) + "\n")
    d = read_imu(p, layout=layout)
    assert np.array_equal(d.gyro, w) and np.array_equal(d.accel, a)  # no frame conversion: the sensor frame S
    assert d.meta["t_origin_raw"] == int(stamps[0]) and d.meta["layout"] == layout
    # integer arithmetic before float: every ns of the stamps survives
    np.testing.assert_array_equal(np.round(d.t * 1e9).astype(np.int64), stamps - stamps[0])
    r = runner.invoke(app, ["info", str(p), "--layout", layout])
    assert r.exit_code == 0, r.output


def test_kalibr(tmp_path):
    stamps, w, a = _rows()
    p = tmp_path / "imu.csv"
    lines = ["timestamp,omega_x,omega_y,omega_z,alpha_x,alpha_y,alpha_z"]
    lines += [",".join([str(s)] + [repr(float(v)) for v in (*w[i], *a[i])]) for i, s in enumerate(stamps)]
    p.write_text("\n".join(lines) + "\n")
    d = read_imu(p, layout="kalibr")
    assert np.array_equal(d.gyro, w) and np.array_equal(d.accel, a)
    np.testing.assert_array_equal(np.round(d.t * 1e9).astype(np.int64), stamps - stamps[0])


def test_px4_csv_matches_the_ulog_reader(tmp_path):
    """The CSV ulog2csv writes for sensor_combined reads like the ULog itself (µs, gauss -> µT)."""
    pytest.importorskip("pyulog")
    from pyulog.ulog2csv import convert_ulog2csv

    src = data_path("px4_ulog", "sample.ulg")
    convert_ulog2csv(str(src), "sensor_combined", str(tmp_path), ",", None, None)
    csv = next(tmp_path.glob("*sensor_combined_0.csv"))
    a, b = read_imu(src), read_imu(csv, layout="px4-csv")
    np.testing.assert_allclose(b.gyro, a.gyro, rtol=1e-6)  # ulog2csv prints float32 values as text
    np.testing.assert_allclose(b.mag, a.mag, rtol=1e-6)
    assert b.mag_unit == "uT" and "t_origin_raw" not in b.meta  # µs since boot fit a float64 exactly
    np.testing.assert_allclose(b.t - b.t[0], a.t, atol=1e-9)


def test_xio_reuses_the_foot_reader():
    p = data_path("foot", "xio_gait", "short_walk.csv")
    d = read_imu(p, layout="xio")
    assert d.meta["frame_adapter"] == "z-up -> FRD" and d.meta["layout"] == "xio"
    assert np.median(d.accel[:50, 2]) < -8.0  # z up (+1 g) became FRD (-g)


def test_unknown_layout_and_clashes(tmp_path):
    p = tmp_path / "x.csv"
    p.write_text("timestamp,omega_x,omega_y,omega_z,alpha_x,alpha_y,alpha_z\n1,0,0,0,0,0,9.8\n2,0,0,0,0,0,9.8\n")
    with pytest.raises(InvalidInputError, match="unknown CSV layout 'vicon'; choose one of"):
        read_imu(p, layout="vicon")
    with pytest.raises(InvalidInputError, match=r"sets \['units'\]"):
        read_imu(p, layout="kalibr", units={"t": "s"})
    with pytest.raises(InvalidInputError, match="does not combine with format='parquet'"):
        read_imu(p, format="parquet", layout="kalibr")
    r = runner.invoke(app, ["info", str(p), "--layout", "vicon"])
    assert r.exit_code == 2 and len(r.stderr.strip().splitlines()) == 1


def test_layouts_through_the_cli_options(tmp_path):
    """The CLI always passes nan_policy: the x-io layout takes its default; an option of another source (a bag's
    --instance / --mag-topic) on a CSV layout is a one-line user error, not an internal TypeError (review finding)."""
    x = data_path("foot", "xio_gait", "short_walk.csv")
    r = runner.invoke(app, ["convert", str(x), str(tmp_path / "x.npz"), "--layout", "xio"])
    assert r.exit_code == 0, r.output
    stamps, w, a = _rows()
    p = tmp_path / "data.csv"
    p.write_text("#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
                 "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n"
                 + "\n".join(",".join([str(s)] + [repr(float(v)) for v in (*w[i], *a[i])])
                             for i, s in enumerate(stamps)) + "\n")
    with pytest.raises(InvalidInputError, match="instance"):
        read_imu(p, layout="euroc", instance=1)
    for opt in (["--instance", "1"], ["--mag-topic", "x"]):
        r = runner.invoke(app, ["convert", str(p), str(tmp_path / "o.npz"), "--layout", "euroc", *opt])
        assert r.exit_code == 2 and len(r.stderr.strip().splitlines()) == 1 and "internal" not in r.stderr, r.stderr
