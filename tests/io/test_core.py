"""Readers and writers: bit-exact round trips, atomic writes, bad files."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.io
from builders import static_imu
from cli_contract import invoke, one_error_line
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from shared_data import data_path

from imunav.errors import FileFormatError, InvalidInputError, NonFiniteError, ShapeError, TimeOrderError, UnitError
from imunav.io import FORMATS, read_imu, write_imu
from imunav.timeseries import ImuData
from imunav.units import DEG, G0

SUFFIX = {"csv": ".csv", "parquet": ".parquet", "hdf5": ".h5", "mat": ".mat", "mat73": ".mat", "npz": ".npz"}
FIELDS = ("t", "gyro", "accel", "mag", "temp")

EXTREMES = np.array(
    [0.0, -0.0, 5e-324, -5e-324, 2.2250738585072014e-308 / 3, 1e-300, -1e-300, 1.7976931348623157e308,
     -1.7976931348623157e308, 1e300, np.pi, -1 / 3, 0.1, 1e16 + 2, 123456789.123456789],
)  # fmt: skip


def extreme_data(seed: int, n: int = 40, mag: bool = True, temp: bool = True) -> ImuData:
    """Seeded arrays mixing ordinary values, subnormals, -0.0 and huge floats."""
    r = np.random.default_rng(seed)

    def block(shape):
        x = r.standard_normal(shape) * 10.0 ** r.integers(-5, 5, shape)
        pick = r.random(shape) < 0.3
        x[pick] = r.choice(EXTREMES, size=int(pick.sum()))
        # random finite bit patterns too
        bits = r.integers(0, 2**63, size=shape, dtype=np.int64).view(np.float64)
        pick2 = (r.random(shape) < 0.1) & np.isfinite(bits)
        x[pick2] = bits[pick2]
        return x

    t = np.concatenate([[0.0, 5e-324, 1e-300, 1e-10], 1e3 + np.cumsum(r.uniform(1e-6, 1.0, n - 4))])
    return ImuData(
        t, block((n, 3)), block((n, 3)), block((n, 3)) if mag else None, block(n) if temp else None,
        mag_unit="µT" if mag else "uT", meta={"sensor": "test ü", "serial": seed, "nested": {"a": [1, 2.5]}},
    )  # fmt: skip


def assert_bit_equal(a: ImuData, b: ImuData) -> None:
    for f in FIELDS:
        x, y = getattr(a, f), getattr(b, f)
        if x is None:
            assert y is None, f
            continue
        assert x.shape == y.shape, f
        assert x.dtype == y.dtype == np.float64, f
        np.testing.assert_array_equal(x.view(np.uint64), y.view(np.uint64), err_msg=f)
    assert a.mag_unit == b.mag_unit
    assert a.meta == b.meta


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize(("mag", "temp"), [(False, False), (True, False), (False, True), (True, True)])
def test_round_trip_bit_exact(tmp_path, fmt, mag, temp):
    for seed in range(3):
        d = extreme_data(seed, mag=mag, temp=temp)
        p = tmp_path / f"rec{seed}{SUFFIX[fmt]}"
        write_imu(d, p, format=fmt)
        back = read_imu(p)  # format from the suffix, MAT version from the header
        assert_bit_equal(d, back)
        # overwriting an existing file works and leaves no temporary file behind
        write_imu(d, p, format=fmt)
    assert sorted(os.listdir(tmp_path)) == [f"rec{s}{SUFFIX[fmt]}" for s in range(3)]


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    vals=hnp.arrays(np.float64, (6, 7), elements=st.floats(allow_nan=False, allow_infinity=False)),
    fmt=st.sampled_from(["csv", "npz", "mat73"]),
)
def test_round_trip_hypothesis(tmp_path, vals, fmt):
    t = np.arange(6) * 0.01 + 1.0
    d = ImuData(t, vals[:, :3], vals[:, 3:6], temp=vals[:, 6])
    p = tmp_path / f"h{SUFFIX[fmt]}"
    write_imu(d, p, format=fmt)
    assert_bit_equal(d, read_imu(p))


def test_mat73_is_matlab_layout(tmp_path):
    d = extreme_data(1, n=10)
    p = write_imu(d, tmp_path / "r.mat", format="mat73")
    assert scipy.io.matlab.matfile_version(str(p)) == (2, 0)  # MATLAB 7.3 header recognised
    raw = p.read_bytes()
    assert raw[:19] == b"MATLAB 7.3 MAT-file" and raw[126:128] == b"IM" and raw[512:516] == b"\x89HDF"
    with h5py.File(p, "r") as fh:
        assert fh["gyro"].shape == (3, 10)  # column-major: MATLAB 10x3
        assert fh["t"].shape == (1, 10)  # MATLAB 10x1 column
        assert fh["gyro"].attrs["MATLAB_class"] == b"double"
        assert fh["mag_unit"].attrs["MATLAB_class"] == b"char"
        np.testing.assert_array_equal(fh["gyro"][()].T, d.gyro)
    p5 = write_imu(d, tmp_path / "r5.mat")
    m = scipy.io.loadmat(str(p5))
    assert m["gyro"].shape == (10, 3) and m["t"].shape == (10, 1)
    assert str(m["mag_unit"][0]) == "µT"


def test_atomic_write_leaves_target_untouched_on_failure(tmp_path):
    d = extreme_data(0)
    for fmt in FORMATS:
        p = tmp_path / f"x{SUFFIX[fmt]}"
        write_imu(d, p, format=fmt)
        before = p.read_bytes()
        bad = d.with_(meta={"obj": object()})  # not JSON-serialisable
        with pytest.raises(InvalidInputError, match="meta"):
            write_imu(bad, p, format=fmt)
        assert p.read_bytes() == before
    assert len(os.listdir(tmp_path)) == len(FORMATS) - 1  # mat and mat73 share x.mat; no temp files


# -- foreign CSV layouts -------------------------------------------------------------


def test_csv_column_mapping_units_counts_and_delimiters(tmp_path):
    p = tmp_path / "log.txt"
    p.write_text("time_ms;GyrX;GyrY;GyrZ;AccX;AccY;AccZ\n0;131;0;-131;0;0;-16384\n10;0;262;0;16384;0;0\n")
    d = read_imu(
        p,
        columns={"t": "time_ms", "gyro": ["GyrX", "GyrY", "GyrZ"], "ax": "AccX", "ay": "AccY", "az": "AccZ"},
        units={"t": "ms", "gyro": "counts", "accel": "counts"},
        scales={"gyro": DEG / 131, "accel": G0 / 16384},
    )
    np.testing.assert_allclose(d.t, [0, 0.01])
    np.testing.assert_allclose(d.gyro, [[DEG, 0, -DEG], [0, 2 * DEG, 0]])
    np.testing.assert_allclose(d.accel, [[0, 0, -G0], [G0, 0, 0]])
    # whitespace-separated, aliases with unit annotations, mag in nT
    p2 = tmp_path / "log.dat"
    p2.write_text("Time[s]  gyr_x gyr_y gyr_z acc_x acc_y acc_z mag_x mag_y mag_z\n"
                  "0.0 1 2 3 4 5 6 7 8 9\n0.5 1 2 3 4 5 6 7 8 9\n")  # fmt: skip
    d2 = read_imu(p2, units={"gyro": "deg/s", "accel": "g", "mag": "nT"})
    assert d2.mag_unit == "nT" and d2.mag[0].tolist() == [7, 8, 9]
    assert d2.accel[0, 0] == pytest.approx(4 * G0)
    # spreadsheet export with a byte-order mark and CRLF line ends
    p4 = tmp_path / "excel.csv"
    p4.write_bytes("\ufefftime,gx,gy,gz,ax,ay,az\r\n0,1,2,3,4,5,6\r\n1,1,2,3,4,5,6\r\n".encode("utf-8"))
    assert read_imu(p4).t.tolist() == [0.0, 1.0]
    # no header: positional mapping, no time column: fs
    p3 = tmp_path / "raw.csv"
    p3.write_text("1,2,3,4,5,6\n1,2,3,4,5,6\n1,2,3,4,5,6\n")
    d3 = read_imu(p3, columns={"gyro": [3, 4, 5], "accel": [0, 1, 2]}, fs=50.0)
    assert d3.gyro[0].tolist() == [4, 5, 6] and d3.t.tolist() == [0.0, 0.02, 0.04]


# -- bad input: each raises a clear imunav error -----------------------------------------


def _good_file(tmp_path, fmt, n=30):
    d = extreme_data(3, n=n)
    p = tmp_path / f"good{SUFFIX[fmt]}"
    write_imu(d, p, format=fmt)
    return p


@pytest.mark.parametrize("fmt", FORMATS)
def test_empty_file(tmp_path, fmt):
    p = tmp_path / f"empty{SUFFIX[fmt]}"
    p.write_bytes(b"")
    with pytest.raises(FileFormatError, match="empty"):
        read_imu(p, format=fmt)


@pytest.mark.parametrize("fmt", FORMATS)
def test_truncated_file(tmp_path, fmt):
    p = _good_file(tmp_path, fmt, n=2000)
    raw = p.read_bytes()
    cut = tmp_path / f"cut{SUFFIX[fmt]}"
    if fmt == "csv":
        # cut in the middle of the last row
        cut.write_bytes(raw[: raw.rstrip(b"\n").rfind(b"\n") + 15])
        match = r"last row has \d of 11 fields.*truncated"
    else:
        cut.write_bytes(raw[: len(raw) // 2])
        match = "cannot read|truncated|too short"
    with pytest.raises(FileFormatError, match=match):
        read_imu(cut)


def test_csv_written_by_imunav_cut_inside_last_number(tmp_path):
    p = _good_file(tmp_path, "csv", n=50)
    raw = p.read_bytes()
    cut = tmp_path / "cut.csv"
    cut.write_bytes(raw[:-3])  # the last row keeps all its fields but loses digits
    with pytest.raises(FileFormatError, match="does not end with a newline; it looks truncated"):
        read_imu(cut)


def test_csv_header_only_and_comments_only(tmp_path):
    p = tmp_path / "h.csv"
    p.write_text("t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z\n")
    with pytest.raises(FileFormatError, match="no data rows"):
        read_imu(p)
    p.write_text("# just a comment\n\n")
    with pytest.raises(FileFormatError, match="no header and no data"):
        read_imu(p)


def test_wrong_column_names(tmp_path):
    p = tmp_path / "w.csv"
    p.write_text("time,wx,wy,wz,foo,bar,baz\n0,1,2,3,4,5,6\n1,1,2,3,4,5,6\n")
    with pytest.raises(FileFormatError, match=r"cannot find the columns for \['ax', 'ay', 'az'\]\. Found columns \['time', 'wx'.*expected names like \{'ax': 'accel_x'"):
        read_imu(p)
    with pytest.raises(FileFormatError, match=r"column 'GyroX' \(columns\['gx'\]\) not found; the file has columns \['time'"):
        read_imu(p, columns={"gx": "GyroX"})
    with pytest.raises(InvalidInputError, match="unknown key 'speed'"):
        read_imu(p, columns={"speed": "foo"})
    p.write_text("gx,gy,gz,ax,ay,az\n0,1,2,3,4,5\n")
    with pytest.raises(FileFormatError, match="no time column.*pass fs="):
        read_imu(p)


def test_missing_datasets_hdf5_npz_mat(tmp_path):
    p = tmp_path / "m.h5"
    with h5py.File(p, "w") as fh:
        fh["time"] = np.arange(3.0)
        fh["angular_velocity"] = np.zeros((3, 3))
        fh["acc"] = np.zeros((3, 3))
    with pytest.raises(FileFormatError, match=r"missing dataset\(s\) for \['gyro'\]\. Found \['acc', 'angular_velocity', 'time'\]"):
        read_imu(p)
    d = read_imu(p, columns={"gyro": "angular_velocity"})
    assert d.n == 3
    q = tmp_path / "m.npz"
    np.savez(q, t=np.arange(3.0), gyro=np.zeros((3, 3)))
    with pytest.raises(FileFormatError, match=r"missing array\(s\) for \['accel'\]"):
        read_imu(q)
    m = tmp_path / "m.mat"
    scipy.io.savemat(m, {"t": np.arange(3.0), "x": np.zeros((3, 3))})
    with pytest.raises(FileFormatError, match=r"missing variable\(s\) for \['gyro', 'accel'\]"):
        read_imu(m)


def test_nan_in_file_names_file_rows_columns(tmp_path):
    p = tmp_path / "n.csv"
    p.write_text("t,gx,gy,gz,ax,ay,az\n0,0,0,0,0,0,0\n1,0,nan,0,0,0,0\n2,0,0,0,0,0,\n3,0,0,0,0,0,0\n")
    with pytest.raises(NonFiniteError, match=r"n\.csv: gyro has NaN/inf at rows 1 \(columns gyro_y\)"):
        read_imu(p)
    d = read_imu(p, nan_policy="drop")
    assert d.n == 2 and d.meta["nan_policy"]["rows"] == [1, 2]
    assert d.meta["nan_policy"]["columns"] == ["gyro_y", "accel_z"]


@pytest.mark.parametrize(("times", "match"), [("0,1,1,2", "duplicate time stamps at rows 1"), ("0,2,1,3", "backwards at rows 1")])
def test_bad_time_in_file(tmp_path, times, match):
    p = tmp_path / "t.csv"
    rows = "".join(f"{t},0,0,0,0,0,0\n" for t in times.split(","))
    p.write_text("t,gx,gy,gz,ax,ay,az\n" + rows)
    with pytest.raises(TimeOrderError, match=match):
        read_imu(p)
    q = tmp_path / "t.npz"
    np.savez(q, t=np.array(times.split(","), float), gyro=np.zeros((4, 3)), accel=np.zeros((4, 3)))
    with pytest.raises(TimeOrderError, match="t.npz: .*" + match):
        read_imu(q)


def test_wrong_shape_in_file(tmp_path):
    p = tmp_path / "s.h5"
    with h5py.File(p, "w") as fh:
        fh["t"] = np.arange(4.0)
        fh["gyro"] = np.zeros((4, 2))
        fh["accel"] = np.zeros((4, 3))
    with pytest.raises(ShapeError, match=r"s\.h5: gyro must have shape \(N, 3\)"):
        read_imu(p)
    q = tmp_path / "s.npz"
    np.savez(q, t=np.arange(4.0), gyro=np.zeros((4, 3)), accel=np.zeros((5, 3)))
    with pytest.raises(ShapeError, match="accel has 5 rows but t has 4"):
        read_imu(q)


def test_unknown_unit_format_option(tmp_path):
    p = _good_file(tmp_path, "csv")
    with pytest.raises(UnitError, match="unknown unit 'parsec/s'"):
        read_imu(p, units={"gyro": "parsec/s"})
    with pytest.raises(InvalidInputError, match="cannot tell the format"):
        read_imu(tmp_path / "x.xyz")
    with pytest.raises(InvalidInputError, match="unknown format 'excel'"):
        read_imu(p, format="excel")
    with pytest.raises(InvalidInputError, match=r"does not take option\(s\) \['colums'\]"):
        read_imu(p, colums={})
    with pytest.raises(FileNotFoundError):
        read_imu(tmp_path / "missing.csv")


def test_text_in_numeric_column(tmp_path):
    p = tmp_path / "x.csv"
    p.write_text("t,gx,gy,gz,ax,ay,az\n0,0,0,0,0,0,0\n1,0,oops,0,0,0,0\n")
    with pytest.raises(FileFormatError, match=r"column 'gy' \(gy\) holds non-numeric values, first at data row 1"):
        read_imu(p)


def test_wrong_format_content(tmp_path):
    p = tmp_path / "fake.h5"
    p.write_text("this is not hdf5")
    with pytest.raises(FileFormatError, match="cannot read it as HDF5"):
        read_imu(p)
    q = tmp_path / "fake.mat"
    q.write_bytes(b"x" * 200)
    with pytest.raises(FileFormatError, match="not a MAT-file"):
        read_imu(q)


# -- real recordings ----------------------------------------------------------------


def test_read_mpu6050_raw_counts():
    # README: 10,245 rows, 100 Hz, int16 counts at ±2 g / ±250 °/s, 5 header lines
    d = read_imu(
        data_path("mpu6050_tedaldi", "example_data_calibration.csv"), skiprows=4, fs=100.0,
        units={"gyro": "counts", "accel": "counts"}, scales={"gyro": DEG / 131, "accel": G0 / 16384},
    )  # fmt: skip
    assert d.n == 10245 and d.duration == pytest.approx(102.44)
    raw = d.accel[:3000].mean(axis=0) / (G0 / 16384)
    # README published accel bias (added, counts) and scale ((m/s²)/count): |a| = g at rest
    b = np.array([-711.5163422327075, 358.5054836108664, 1840.128451085784])
    s = np.array([6.020083400010407e-04, 5.968449488725015e-04, 5.859241382355085e-04])
    assert np.linalg.norm((raw + b) * s) == pytest.approx(G0, rel=2e-3)


def test_read_adis16405_npz():
    # README: 1e6 samples at 100 Hz, gyro deg/s, accel g, z ≈ −1.018 g
    d = read_imu(data_path("adis16405", "adis16405_imu2.npz"), units={"gyro": "deg/s", "accel": "g"})
    assert d.n == 1_000_000 and d.fs == pytest.approx(100.0)
    assert d.accel[:, 2].mean() / G0 == pytest.approx(-1.018, abs=0.005)


def test_csv_iso_datetime_time_column(tmp_path):
    p = tmp_path / "logger.csv"
    p.write_text(
        "timestamp,gx,gy,gz,ax,ay,az\n"
        "2024-05-01T12:00:00.000Z,0,0,0,0,0,-9.8\n"
        "2024-05-01T12:00:00.010Z,0,0,0,0,0,-9.8\n"
        "2024-05-01T12:00:00.025Z,0,0,0,0,0,-9.8\n"
    )
    d = read_imu(p)
    np.testing.assert_allclose(d.t, [0.0, 0.010, 0.025], rtol=0, atol=1e-15)
    assert d.meta["t_origin"].startswith("2024-05-01T12:00:00")
    p.write_text("timestamp,gx,gy,gz,ax,ay,az\n2024-05-01T12:00:00Z,0,0,0,0,0,0\nyesterday,0,0,0,0,0,0\n")
    with pytest.raises(FileFormatError, match=r"time column 'timestamp' holds date-times but data row 1 \('yesterday'\)"):
        read_imu(p)


def test_parquet_without_pyarrow_names_the_extra(tmp_path, monkeypatch):
    """pyarrow is the `parquet` extra (not in the core install): Parquet I/O says what to install, other formats work."""
    import sys

    from imunav.errors import MissingDependencyError
    from imunav.io import read_imu, write_imu
    from imunav.timeseries import ImuData

    data = ImuData.from_arrays(None, np.zeros((10, 3)), np.tile([0.0, 0.0, -9.81], (10, 1)), fs=10.0)
    write_imu(data, tmp_path / "r.parquet")
    monkeypatch.setitem(sys.modules, "pyarrow", None)
    monkeypatch.setitem(sys.modules, "pyarrow.parquet", None)
    with pytest.raises(MissingDependencyError, match=r"pip install 'imunav\[parquet\]'"):
        read_imu(tmp_path / "r.parquet")
    with pytest.raises(MissingDependencyError, match="parquet"):
        write_imu(data, tmp_path / "s.parquet")
    assert not (tmp_path / "s.parquet").exists()
    np.testing.assert_array_equal(read_imu(write_imu(data, tmp_path / "r.npz")).accel, data.accel)


def test_fs_contradicting_the_time_column_is_an_error(tmp_path):
    p = write_imu(static_imu(3000), tmp_path / "rec.csv")
    with pytest.raises(InvalidInputError, match=r"time column \(samples at 100 Hz\).*fs=50"):
        read_imu(p, fs=50.0)
    assert read_imu(p, fs=100.0).n == 3000  # agreeing: accepted
    assert "fs=50" in one_error_line(invoke("info", p, "--fs", "50"))


def test_importing_one_reader_loads_neither_pandas_nor_scipy_io():
    """imunav.io's readers and writers load on first use (issue 35): importing the log readers (what a first
    `attitude run` on a PX4 log needs) loads neither pandas (the CSV reader's) nor scipy.io (the MAT reader's),
    and `from imunav.io import read_imu` / `imunav.io.to_dataframe` still give the functions."""
    code = ("import sys\n"
            "import imunav.io.logs, imunav.io.ulog, imunav.io.rosbag\n"
            "print(sorted(m for m in ('pandas', 'scipy.io', 'imunav.io.core') if m in sys.modules))\n"
            "import imunav.io as io\n"
            "from imunav.io import read_imu, FORMATS\n"
            "print(read_imu.__module__, io.to_dataframe.__module__, 'csv' in FORMATS, 'pandas' in sys.modules)\n"
            "try:\n"
            "    io.no_such_name\n"
            "except AttributeError as e:\n"
            "    print(e)\n")
    src = str(Path(__file__).resolve().parents[2] / "src")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in (src, os.environ.get("PYTHONPATH")) if p)}
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines() == ["[]", "imunav.io.core imunav.io.dataframe True True",
                                     "module 'imunav.io' has no attribute 'no_such_name'"], r.stdout
