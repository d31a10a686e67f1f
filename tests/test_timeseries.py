"""ImuData validation, units at the edge, NaN policy, gaps, slicing,
saturation and static-interval detection."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from builders import static_imu
from cli_contract import invoke
from shared_data import data_path

from imunav.errors import (
    ImunavWarning,
    InsufficientDataError,
    InvalidInputError,
    NonFiniteError,
    SaturationError,
    ShapeError,
    TimeOrderError,
    UnitError,
)
from imunav.io import write_imu
from imunav.io.dataframe import from_dataframe, to_dataframe
from imunav.timeseries import ImuData, StaticIntervals, describe, detect_saturation, moving_variance, static_intervals
from imunav.units import DEG, G0

# at rest, with a magnetometer and a temperature when asked
QUIET = {"gyro_sd": 1e-3, "accel_sd": 1e-2}
SENSORS = {"mag": (0.0, 0.0, 0.0), "mag_sd": 1.0, "temp": 25.0, "temp_sd": 0.1}


# -- validation ----------------------------------------------------------------


def test_properties_and_immutability():
    d = static_imu(201, 200.0, **QUIET)
    assert d.n == len(d) == 201
    assert d.fs == pytest.approx(200.0, rel=1e-12)
    assert d.duration == pytest.approx(1.0)
    assert d.dt.shape == (200,)
    with pytest.raises(ValueError):
        d.gyro[0, 0] = 1.0  # read-only arrays
    assert repr(d) == "ImuData(n=201, fs=200 Hz, duration=1 s, channels=gyro,accel)"


def test_nan_raises_naming_rows_and_columns():
    g = np.zeros((10, 3))
    g[3, 1] = np.nan
    g[7, 2] = np.inf
    with pytest.raises(NonFiniteError, match=r"rows 3, 7 \(columns gyro_y, gyro_z\)"):
        ImuData(np.arange(10.0), g, np.zeros((10, 3)))
    with pytest.raises(NonFiniteError, match=r"rows 4 \(column temp\)"):
        ImuData(np.arange(5.0), np.zeros((5, 3)), np.zeros((5, 3)), temp=[1, 2, 3, 4, np.nan])
    with pytest.raises(NonFiniteError, match="t has non-finite values at rows 2"):
        ImuData([0, 1, np.nan, 3], np.zeros((4, 3)), np.zeros((4, 3)))


def test_many_nan_rows_are_summarised():
    g = np.full((50, 3), np.nan)
    with pytest.raises(NonFiniteError, match=r"50 rows in all"):
        ImuData(np.arange(50.0), g, np.zeros((50, 3)))


@pytest.mark.parametrize(
    ("t", "match"),
    [([0.0, 0.1, 0.1, 0.2], "duplicate time stamps at rows 1"), ([0.0, 0.2, 0.1, 0.3], "backwards at rows 1")],
)
def test_time_order(t, match):
    with pytest.raises(TimeOrderError, match=match):
        ImuData(t, np.zeros((4, 3)), np.zeros((4, 3)))


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        (dict(t=np.zeros((4, 1)), gyro=np.zeros((4, 3)), accel=np.zeros((4, 3))), r"t must be 1-D"),
        (dict(t=np.arange(4.0), gyro=np.zeros((4, 2)), accel=np.zeros((4, 3))), r"gyro must have shape \(N, 3\)"),
        (dict(t=np.arange(4.0), gyro=np.zeros((4, 3)), accel=np.zeros((3, 3))), r"accel has 3 rows but t has 4"),
        (dict(t=np.arange(5.0), gyro=np.zeros((3, 5)), accel=np.zeros((5, 3))), r"looks transposed: pass gyro\.T"),
        (dict(t=np.arange(4.0), gyro=np.zeros((4, 3)), accel=np.zeros((4, 3)), temp=np.zeros(3)), r"temp must have shape"),
        (dict(t=np.zeros(0), gyro=np.zeros((0, 3)), accel=np.zeros((0, 3))), r"empty"),
    ],
)
def test_wrong_shape(kw, match):
    with pytest.raises(ShapeError, match=match):
        ImuData(**kw)


# -- units at the edge --------------------------------------------------------


def test_units_converted_to_si():
    d = ImuData.from_arrays(
        [0, 10, 20], [[1, 2, 3]] * 3, [[0, 0, -1]] * 3, time_unit="ms", gyro_unit="deg/s", accel_unit="g"
    )
    np.testing.assert_allclose(d.t, [0, 0.01, 0.02])
    np.testing.assert_allclose(d.gyro[0], np.array([1, 2, 3]) * DEG)
    assert d.accel[0, 2] == -G0
    assert d.meta["units_in"] == {"time": "ms", "gyro": "deg/s", "accel": "g"}


def test_raw_counts_with_scale_and_offset():
    # MPU-6050 at ±2 g: 16384 LSB/g; ±250 °/s: 131 LSB/(°/s)
    d = ImuData.from_arrays(
        None, [[131 + 10, 10, 10]] * 3, [[0, 0, 16384 + 5]] * 3, fs=100.0,
        gyro_unit="counts", gyro_scale=DEG / 131, gyro_offset=10,
        accel_unit="counts", accel_scale=G0 / 16384, accel_offset=5,
    )  # fmt: skip
    np.testing.assert_allclose(d.gyro[0], [DEG, 0, 0], atol=1e-15)
    np.testing.assert_allclose(d.accel[0], [-5 * G0 / 16384, -5 * G0 / 16384, G0])
    np.testing.assert_allclose(d.t, [0, 0.01, 0.02])


def test_per_axis_count_scales_and_offsets():
    # MPU-6050 README: a_cal = K (a_raw + b) with per-axis scale K and bias b (counts)
    b = np.array([-711.5, 358.5, 1840.1])
    k = np.array([6.02e-4, 5.97e-4, 5.86e-4])
    raw = np.array([[711.5, -358.5, -1840.1 - 16735.0]] * 2)
    d = ImuData.from_arrays(None, np.zeros((2, 3)), raw, fs=100.0, accel_unit="counts", accel_scale=k, accel_offset=-b)
    np.testing.assert_allclose(d.accel[0], [0, 0, -16735.0 * 5.86e-4], atol=1e-12)
    with pytest.raises(ShapeError, match="scalars or 3 values"):
        ImuData.from_arrays(None, np.zeros((2, 3)), raw, fs=1.0, accel_unit="counts", accel_scale=k[:2])
    with pytest.raises(UnitError, match="need accel_unit='counts'"):
        ImuData.from_arrays(None, np.zeros((2, 3)), raw, fs=1.0, accel_scale=k)
    with pytest.raises(UnitError, match="needs accel_scale"):
        ImuData.from_arrays(None, np.zeros((2, 3)), raw, fs=1.0, accel_unit="counts", accel_offset=b)


def test_unknown_unit_and_missing_scale():
    with pytest.raises(UnitError, match=r"unknown unit 'furlong/s'.*accepted"):
        ImuData.from_arrays([0, 1], np.zeros((2, 3)), np.zeros((2, 3)), gyro_unit="furlong/s")
    with pytest.raises(UnitError, match="needs a finite, non-zero scale"):
        ImuData.from_arrays([0, 1], np.zeros((2, 3)), np.zeros((2, 3)), accel_unit="counts")
    with pytest.raises(InvalidInputError, match="either t or fs"):
        ImuData.from_arrays([0, 1], np.zeros((2, 3)), np.zeros((2, 3)), fs=10.0)


# -- NaN policy ----------------------------------------------------------------


def test_nan_policy_drop_and_interpolate_report_in_meta():
    t = np.arange(6) * 0.1
    g = np.arange(18, dtype=float).reshape(6, 3)
    g[2, 0] = np.nan
    a = np.zeros((6, 3))
    a[4, 2] = np.nan
    d = ImuData.from_arrays(t, g, a, nan_policy="drop")
    assert d.n == 4 and d.t.tolist() == pytest.approx([0, 0.1, 0.3, 0.5])
    assert d.meta["nan_policy"]["rows"] == [2, 4]
    assert d.meta["nan_policy"]["columns"] == ["gyro_x", "accel_z"]
    d = ImuData.from_arrays(t, g, a, nan_policy="interpolate")
    assert d.n == 6 and d.gyro[2, 0] == pytest.approx(6.0) and d.accel[4, 2] == 0.0
    assert d.meta["nan_policy"]["policy"] == "interpolate"
    json.dumps(d.meta)
    g[0, 1] = np.nan
    with pytest.raises(NonFiniteError, match="start or end"):
        ImuData.from_arrays(t, g, a, nan_policy="interpolate")
    with pytest.raises(InvalidInputError, match="nan_policy must be"):
        ImuData.from_arrays(t, np.zeros((6, 3)), a * 0, nan_policy="ignore")


# -- gaps, slicing, dataframe --------------------------------------------------


def test_gaps_reported():
    t = np.arange(100) * 0.01
    t[50:] += 0.05  # 5 samples missing after index 49
    d = ImuData(t, np.zeros((100, 3)), np.zeros((100, 3)))
    (gap,) = d.gaps()
    assert gap.index == 49 and gap.t_start == pytest.approx(0.49)
    assert gap.length_s == pytest.approx(0.06) and gap.missing_samples == 5
    assert static_imu(100, **QUIET).gaps() == []


def test_slice_time_slice_with():
    d = static_imu(100, **QUIET, **SENSORS)
    s = d.slice(10, 20)
    assert s.n == 10 and s.t[0] == d.t[10] and s.mag is not None and s.temp.shape == (10,)
    ts = d.time_slice(0.25, 0.5)
    assert ts.t[0] == pytest.approx(0.25) and ts.t[-1] == pytest.approx(0.49)
    with pytest.raises(InvalidInputError, match="no samples"):
        d.time_slice(5.0, 6.0)
    w = d.with_(accel=d.accel * 2)
    np.testing.assert_array_equal(w.accel, d.accel * 2)
    with pytest.raises(ShapeError):
        d.with_(gyro=np.zeros((5, 3)))


def test_interp_and_resample_linear_signals_exactly():
    t = np.array([0.0, 0.1, 0.25, 0.3, 0.5])
    g = np.column_stack([2 * t, -t, t + 1])  # linear in t: interpolation is exact
    d = ImuData(t, g, np.column_stack([t, t, t]), temp=20 + t)
    r = d.resample(20.0)
    np.testing.assert_allclose(r.t, np.arange(11) / 20.0, atol=1e-15)
    np.testing.assert_allclose(r.gyro, np.column_stack([2 * r.t, -r.t, r.t + 1]), atol=1e-14)
    np.testing.assert_allclose(r.temp, 20 + r.t, atol=1e-13)
    assert r.meta["resampled_from_hz"] == pytest.approx(1 / 0.125)  # median interval
    with pytest.raises(InvalidInputError, match="does not extrapolate"):
        d.interp([0.0, 0.6])
    with pytest.raises(TimeOrderError):
        d.interp([0.2, 0.1])


def test_dataframe_round_trip_exact():
    d = static_imu(50, **QUIET, **SENSORS).with_(meta={"sensor": "unit"}, mag_unit="nT")
    df = to_dataframe(d)
    assert list(df.columns)[:4] == ["t", "gyro_x", "gyro_y", "gyro_z"]
    r = from_dataframe(df)
    for k in ("t", "gyro", "accel", "mag", "temp"):
        np.testing.assert_array_equal(getattr(r, k), getattr(d, k))
    assert r.mag_unit == "nT" and r.meta == {"sensor": "unit"}
    df2 = df.rename(columns={"t": "time_ms", "gyro_x": "GyrX"}).assign(time_ms=df["t"] * 1e3)
    r2 = from_dataframe(df2, columns={"t": "time_ms", "gx": "GyrX"}, units={"t": "ms"})
    np.testing.assert_allclose(r2.t, d.t, rtol=1e-15)


# -- saturation -----------------------------------------------------------------


def test_saturation_full_scale_and_runs():
    d = static_imu(200, **QUIET)
    g = d.gyro.copy()
    rail = 250 * DEG
    g[50:54, 0] = rail  # clipped for 4 samples
    g[120:123, 2] = -rail
    a = d.accel.copy()
    a[80:82, 1] = 2 * G0
    s = detect_saturation(d.with_(gyro=g, accel=a), gyro_full_scale=rail, accel_full_scale=2 * G0)
    assert s.counts == {"gyro_x": 4, "gyro_y": 0, "gyro_z": 3, "accel_x": 0, "accel_y": 2, "accel_z": 0}
    assert s.rows.tolist() == [50, 51, 52, 53, 80, 81, 120, 121, 122]
    r = detect_saturation(d.with_(gyro=g, accel=a))
    assert r.method == "runs" and r.counts == s.counts
    with pytest.raises(SaturationError, match=r"rows 50, 51, 52, 53, 80, 81, 120, 121, 122: gyro_x \(4\), gyro_z \(3\), accel_y \(2\)"):
        r.check()
    detect_saturation(d).check()  # nothing saturated: no error
    # quantised static data: repeated extremes near the median are not saturation
    q = np.round(d.gyro / 1e-3) * 1e-3
    assert not detect_saturation(d.with_(gyro=q)).any


# -- static intervals ---------------------------------------------------------


def test_moving_variance_matches_numpy(rng):
    x = rng.normal(5.0, 2.0, (1000, 3))
    v = moving_variance(x, 37)
    ref = np.array([x[j : j + 37].var(axis=0).sum() for j in range(1000 - 36)])
    np.testing.assert_allclose(v, ref, rtol=1e-11)
    with pytest.raises(InvalidInputError):
        moving_variance(x, 1)


def test_moving_variance_windows_are_named(rng):
    # the window is trailing (one value per complete window) or centred (one value per sample, cut at the ends);
    # both against numpy's two-pass variance, on data with a large offset (the sliding sums subtract it)
    x = rng.normal([0.0, 0.0, -9.81], 0.01, (600, 3))
    n, h = 20, 10
    per = moving_variance(x, n, per_column=True)
    np.testing.assert_allclose(per, [x[j : j + n].var(axis=0) for j in range(600 - n + 1)], rtol=1e-8)
    np.testing.assert_allclose(moving_variance(x, n), per.sum(axis=1), rtol=1e-14)
    cen = moving_variance(x, n, align="centred", per_column=True)
    ref = [x[max(i - h, 0) : min(i - h + n, 600)].var(axis=0) for i in range(600)]
    assert cen.shape == (600, 3)
    np.testing.assert_allclose(cen, ref, rtol=1e-8)
    np.testing.assert_allclose(moving_variance(x[:, 2], n, align="centred"), cen[:, 2], rtol=1e-14)
    with pytest.raises(InvalidInputError, match="align"):
        moving_variance(x, n, align="leading")


def _synthetic_session(rng, fs=100.0):
    """Static poses separated by tumbling motions; truth = static index ranges."""
    segs = [("s", 4.0), ("m", 2.0), ("s", 3.0), ("m", 1.5), ("s", 5.0), ("m", 2.5), ("s", 2.0)]
    n = int(sum(d for _, d in segs) * fs)
    gyro = rng.normal(0, 2e-3, (n, 3))
    accel = rng.normal(0, 2e-2, (n, 3)) + [0, 0, -G0]
    truth = []
    i = 0
    for kind, dur in segs:
        m = int(dur * fs)
        if kind == "s":
            truth.append((i, i + m))
        else:
            k = np.arange(m) / fs
            gyro[i : i + m] += np.column_stack([np.sin(3 * k), np.cos(2 * k), np.sin(k) + 0.5]) * 1.5
            accel[i : i + m] += np.column_stack([np.sin(4 * k), np.cos(3 * k), np.sin(2 * k)]) * 3.0
        i += m
    return ImuData(np.arange(n) / fs, gyro, accel), truth


@pytest.mark.parametrize("use_gyro", [False, True])
@pytest.mark.parametrize("method", ["axes", "norm"])
def test_static_intervals_synthetic(rng, use_gyro, method):
    d, truth = _synthetic_session(rng)
    si = static_intervals(d, window_s=0.5, min_duration_s=1.0, use_gyro=use_gyro, method=method)
    assert isinstance(si, StaticIntervals)
    w = si.window
    assert len(si) == len(truth)
    for (a, b), (s, e) in zip(truth, si, strict=True):
        assert abs(s - a) < w and abs(e - b) < w, (a, b, s, e, w)
    assert si.mask.sum() == sum(e - s for s, e in si)
    np.testing.assert_array_equal(si.t_start, d.t[si.starts])
    json.dumps(si.to_dict())


def test_static_intervals_noise_free_simulation():
    # ideal (noise-free) data: rest, 2 s rotation about x at 1 rad/s, rest
    fs = 100.0
    n = 1000
    t = np.arange(n) / fs
    ang = np.clip(t - 3.0, 0.0, 2.0)  # rad
    rate = np.where((t >= 3.0) & (t < 5.0), 1.0, 0.0)
    gyro = np.column_stack([rate, 0 * t, 0 * t])
    accel = np.column_stack([0 * t, G0 * np.sin(ang), -G0 * np.cos(ang)])  # gravity seen rotating
    d = ImuData(t, gyro, accel)
    # the rotation starts at sample 300 (gyro) and tilts the accelerometer from sample 301
    assert list(static_intervals(d, window_s=0.5, use_gyro=True)) == [(0, 300), (500, 1000)]
    assert list(static_intervals(d, window_s=0.5)) == [(0, 301), (500, 1000)]


def test_static_intervals_explicit_threshold_and_min_duration(rng):
    d, truth = _synthetic_session(rng)
    si = static_intervals(d, window_s=0.5, threshold=(0.05, 1e-4), use_gyro=True)
    assert len(si) == 4
    assert si.accel_threshold == 0.05 and si.gyro_threshold == 1e-4
    # the 2 s static pose at the end disappears with a 3 s minimum duration
    assert len(static_intervals(d, window_s=0.5, min_duration_s=3.0)) == 3
    assert len(static_intervals(d, window_s=0.5, threshold=0.0)) == 0
    with pytest.raises(InsufficientDataError, match="fewer than one window"):
        static_intervals(d.slice(0, 10), window_s=1.0)
    with pytest.raises(InvalidInputError, match="method"):
        static_intervals(d, method="max")
    with pytest.raises(InvalidInputError, match="threshold"):
        static_intervals(d, threshold=(-1.0, 1.0))


def test_static_intervals_long_record_is_fast():
    import time

    n = 2_000_000
    d = ImuData(np.arange(n) / 1000.0, np.zeros((n, 3)) + 1e-3 * np.sin(np.arange(n))[:, None], np.zeros((n, 3)) + [0, 0, -G0] + 1e-2 * np.cos(np.arange(n) * 0.7)[:, None])
    static_intervals(d.slice(0, 5000), window_s=0.5)  # compile
    t0 = time.perf_counter()
    si = static_intervals(d, window_s=1.0, use_gyro=True)
    # ~0.3 s on an idle core; generous bound so a loaded CI machine does not flake
    assert time.perf_counter() - t0 < 10.0
    assert list(si) == [(0, n)]


# -- real data: MPU-6050 Tedaldi session and imucal Ferraris session ----------------------

# /work/shared/data/mpu6050_tedaldi/README.md: static intervals found upstream (0-based, end exclusive)
MPU_INTERVALS = [
    (150, 3613), (4297, 4299), (4934, 4946), (5585, 5690), (6205, 6368),
    (7018, 7046), (7570, 7765), (8297, 8457), (9094, 9158), (9662, 10095),
]  # fmt: skip


def _mpu():
    from imunav.io import read_imu

    return read_imu(
        data_path("mpu6050_tedaldi", "example_data_calibration.csv"),
        skiprows=4, fs=100.0, units={"gyro": "counts", "accel": "counts"},
        scales={"gyro": DEG / 131, "accel": G0 / 16384},
    )  # fmt: skip


def test_static_intervals_mpu6050_match_readme():
    d = _mpu()
    si = static_intervals(d, window_s=1.0)
    # one detected interval per published interval, each containing it
    assert len(si) == len(MPU_INTERVALS)
    for (a, b), (s, e) in zip(MPU_INTERVALS, si, strict=True):
        assert s <= a and b <= e, ((a, b), (s, e))
    # the initial rest of ~36.5 s (README: T_init) is found
    assert si.durations[0] == pytest.approx(37.6, abs=1.0)


def test_saturation_mpu6050_matches_readme():
    d = _mpu()
    # README: "the gyro saturates (±32768/32767) on 12 samples of x and 6 of z"
    for s in (detect_saturation(d), detect_saturation(d, gyro_full_scale=250 * DEG)):
        assert (s.counts["gyro_x"], s.counts["gyro_y"], s.counts["gyro_z"]) == (12, 0, 6)


def test_static_intervals_imucal_ferraris_sections():
    from imunav.io import read_imu

    d = read_imu(data_path("imucal", "example_ferraris_session.csv"), fs=102.4, units={"gyro": "deg/s"})
    sections = json.loads(data_path("imucal", "example_ferraris_session_list.json").read_text())
    si = static_intervals(d, window_s=1.0)
    for name, sec in sections.items():
        frac = si.mask[sec["start"] : sec["end"]].mean()
        if name.endswith("_rot"):
            assert frac < 0.1, (name, frac)
        else:
            assert frac == 1.0, (name, frac)


def test_static_intervals_vqf_sample_rest_motion_rest():
    from imunav.io import read_imu

    d = read_imu(data_path("vqf_sample", "imu_data.npz"))  # float32 gyr/acc/mag + sampling_rate
    si = static_intervals(d, window_s=1.0)
    # README: rest at the start, motion from ≈9.3 s to ≈41.6 s, rest again at the end
    assert len(si) == 2
    assert si.t_start[0] == 0.0 and si.t_stop[0] == pytest.approx(9.3, abs=1.0)
    assert si.t_start[1] == pytest.approx(41.6, abs=1.0) and si.stops[1] == d.n


def test_std_of_a_constant_1e300_signal_is_zero():
    d = ImuData.from_arrays(None, np.full((100, 3), 1e300), np.tile([0, 0, -G0], (100, 1)), fs=100)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        ch = {c["channel"]: c for c in describe(d).channels}
    assert ch["gyro_x"]["std"] == 0.0 and ch["gyro_x"]["mean"] == pytest.approx(np.degrees(1e300), rel=1e-12)
    assert ch["accel_z"]["std"] == 0.0


def test_accelerometer_in_g_at_rest_warns(tmp_path):
    d = static_imu(3000, accel=(0.0, 0.0, -1.0), accel_sd=0.01 / G0)  # |f| = 1 at rest: the file was in g
    with pytest.warns(ImunavWarning, match="in g"):
        s = describe(d)
    assert s.warnings and "--accel-unit g" in s.warnings[0]
    with warnings.catch_warnings():
        warnings.simplefilter("error", ImunavWarning)
        assert describe(static_imu(3000)).warnings == []  # m/s^2: no warning
    p = write_imu(d, tmp_path / "ing.csv")
    r = invoke("info", p, "--json", tmp_path / "i.json")
    assert r.exit_code == 0
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("warning: ") and "in g" in lines[0]


def test_window_counts_seconds_from_the_first_sample():
    t = 1000.0 + np.arange(100) / 10.0  # a clock that does not start at 0 (boot time, GPS week)
    d = ImuData(t, np.zeros((100, 3)), np.tile([0.0, 0.0, -G0], (100, 1)))
    w = d.window(2.0, 5.0)
    assert w.n == 30 and w.t[0] == pytest.approx(1002.0) and w.t[-1] == pytest.approx(1004.9)
    assert w.meta["provenance"][-1]["op"] == "window"
    assert d.window(None, None) is d and d.window(9.0).n == 10
    for bad in ((-1.0, None), (5.0, 5.0), (20.0, None), (float("nan"), None)):
        with pytest.raises(InvalidInputError):
            d.window(*bad)
