"""ROS 1 / ROS 2 (sqlite3, MCAP) bags: reading, frames, time, bad input (imunav.io.rosbag, imunav.io.logs).

Every bag is built here with ``rosbags``' own writer.  The frame conversion at the edge is checked on
simulated motion in both directions against the physics of REP-103 (a FLU body sees gravity and the
Earth field of an ENU world through the FLU->ENU orientation), not against imunav's own inverse.
"""

from __future__ import annotations

import sys
import warnings

import numpy as np
import pytest
from typer.testing import CliRunner

from imunav.cli.main import app
from imunav.errors import (
    FileFormatError,
    InvalidInputError,
    MissingDependencyError,
    TimeOrderError,
)
from imunav.io import read_imu
from imunav.io.logs import (
    enu_to_ned,
    frd_to_ros,
    list_topics,
    ned_to_enu,
    read_topic,
    ros_to_frd,
)
from imunav.io.rosbag import write_bag
from imunav.rotation import (
    C_ENU_NED,
    integrate_rate,
    quat_conjugate,
    quat_from_euler,
    quat_rotate,
    to_convention,
)
from imunav.timeseries import ImuData

pytest.importorskip("rosbags")

STORAGES = ("ros1", "sqlite3", "mcap")
T0 = 1_712_345_678_901_234_567  # an April 2024 stamp, ns since 1970: too large for float64 seconds
runner = CliRunner()


def _path(tmp_path, storage, name="rec"):
    return tmp_path / (f"{name}.bag" if storage == "ros1" else name)


def _motion(n=400, fs=200.0):
    """FRD/NED truth: a tumbling body (attitude, gyro, specific force, magnetometer in µT)."""
    t = np.arange(n) / fs
    w = np.column_stack([0.8 * np.sin(2.1 * t), -0.5 * np.cos(1.3 * t) + 0.2, 0.6 * np.sin(0.7 * t + 1)])
    q = integrate_rate(quat_from_euler(0.3, -0.2, 1.1), t, w)
    g_n = np.array([0.0, 0.0, 9.81])
    m_n = np.array([20.0, -1.5, 43.0])  # µT, NED, dip ~65°
    qc = quat_conjugate(q)
    f_b = -quat_rotate(qc, np.tile(g_n, (n, 1)))  # specific force at rest-like motion (no linear accel)
    m_b = quat_rotate(qc, np.tile(m_n, (n, 1)))
    return t, q, w, f_b, m_b, g_n, m_n


def _raw_writer(path, storage):
    """rosbags writer + typestore + serializer for ``storage``."""
    from rosbags.typesys import Stores, get_typestore

    if storage == "ros1":
        from rosbags.rosbag1 import Writer

        ts = get_typestore(Stores.ROS1_NOETIC)
        return Writer(path), ts, ts.serialize_ros1
    from rosbags.rosbag2 import StoragePlugin, Writer

    ts = get_typestore(Stores.LATEST)
    return Writer(path, version=9, storage_plugin=StoragePlugin[storage.upper()]), ts, ts.serialize_cdr


def _write_raw(path, storage, topics, big_endian=None):
    """``topics``: {topic: [(record_ns, msgtype, stamp_ns, frame_id, build(T, header)[, seq]) ...]};
    ``big_endian(topic, i)``: message i of a ROS 2 topic serialized as big-endian CDR."""
    writer, ts, ser0 = _raw_writer(path, storage)
    current = {"be": False}

    def ser(msg, msgtype):
        return ts.serialize_cdr(msg, msgtype, little_endian=False) if current["be"] else ser0(msg, msgtype)

    T = ts.types
    with writer:
        conns = {}
        items = []
        for topic, msgs in topics.items():
            for i, (rec, msgtype, stamp, frame, build, *seq) in enumerate(msgs):
                if topic not in conns:
                    conns[topic] = writer.add_connection(topic, msgtype, typestore=ts)
                sec, nsec = divmod(stamp, 1_000_000_000)
                kw = {"seq": seq[0] if seq else i} if storage == "ros1" else {}
                hdr = T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec),
                                                frame_id=frame, **kw)
                current["be"] = bool(big_endian and big_endian(topic, i))
                items.append((rec, conns[topic], ser(build(T, hdr), msgtype)))
        for rec, conn, raw in sorted(items, key=lambda x: x[0]):
            writer.write(conn, rec, raw)


def _imu_msg(g, a, q_xyzw=None, cov=None):
    def build(T, hdr):
        V = T["geometry_msgs/msg/Vector3"]
        quat = T["geometry_msgs/msg/Quaternion"](*(q_xyzw if q_xyzw is not None else (0.0, 0.0, 0.0, 1.0)))
        oc = np.zeros(9) if q_xyzw is not None else np.r_[-1.0, np.zeros(8)]
        c = np.zeros(9) if cov is None else np.asarray(cov, float)
        return T["sensor_msgs/msg/Imu"](header=hdr, orientation=quat, orientation_covariance=oc,
                                        angular_velocity=V(*g), angular_velocity_covariance=c,
                                        linear_acceleration=V(*a), linear_acceleration_covariance=c)

    return build


def _mag_msg(m_tesla):
    def build(T, hdr):
        return T["sensor_msgs/msg/MagneticField"](header=hdr, magnetic_field=T["geometry_msgs/msg/Vector3"](*m_tesla),
                                                  magnetic_field_covariance=np.zeros(9))

    return build


# ---------------------------------------------------------------- frames, both directions
def test_rep103_flu_enu_is_the_physics_of_the_ros_side():
    """The FLU/ENU expression of the motion obeys REP-103 on its own: R(q_enu_flu)ᵀ g_enu = gravity seen in FLU."""
    t, q, w, f_b, m_b, g_n, m_n = _motion()
    q_ros = to_convention(q, "enu", body="flu")  # FLU body -> ENU world, scalar first
    g_enu, m_enu = C_ENU_NED @ g_n, C_ENU_NED @ m_n
    qc = quat_conjugate(q_ros)
    np.testing.assert_allclose(-quat_rotate(qc, np.tile(g_enu, (len(t), 1))), frd_to_ros(f_b), atol=1e-12)
    np.testing.assert_allclose(quat_rotate(qc, np.tile(m_enu, (len(t), 1))), frd_to_ros(m_b), atol=1e-12)
    # at rest and level the ROS accelerometer reads +g up, imunav's -g down
    np.testing.assert_array_equal(ros_to_frd([[0.0, 0.0, 9.81]]), [[0.0, 0.0, -9.81]])
    # world vectors: north-east-down (1, 2, 3) is east-north-up (2, 1, -3)
    np.testing.assert_array_equal(ned_to_enu([[1.0, 2.0, 3.0]]), [[2.0, 1.0, -3.0]])
    np.testing.assert_array_equal(enu_to_ned(ned_to_enu([[1.0, 2.0, 3.0]])), [[1.0, 2.0, 3.0]])


@pytest.mark.parametrize("storage", STORAGES)
def test_ros_to_imunav_on_simulated_motion(tmp_path, storage):
    """FLU/ENU messages written by rosbags read back as the FRD/NED truth (gyro, accel, mag, orientation)."""
    t, q, w, f_b, m_b, _, _ = _motion()
    q_ros = to_convention(q, "enu", body="flu")
    stamps = T0 + np.round(t * 1e9).astype(np.int64)
    g_flu, a_flu, m_flu = frd_to_ros(w), frd_to_ros(f_b), frd_to_ros(m_b) * 1e-6
    cov = [1e-4, 2e-6, 3e-6, 2e-6, 5e-4, 0.0, 3e-6, 0.0, 6e-4]
    p = _path(tmp_path, storage)
    _write_raw(p, storage, {
        "/imu": [(int(s), "sensor_msgs/msg/Imu", int(s), "imu_link",
                  _imu_msg(g_flu[i], a_flu[i], q_ros[i, [1, 2, 3, 0]], cov)) for i, s in enumerate(stamps)],
        "/mag": [(int(s) + 3_000_000, "sensor_msgs/msg/MagneticField", int(s), "imu_link", _mag_msg(m_flu[i]))
                 for i, s in enumerate(stamps)],
    })
    imu = read_topic(p, "/imu")
    np.testing.assert_allclose(imu.values["gyro"], w, atol=1e-12)
    np.testing.assert_allclose(imu.values["accel"], f_b, atol=1e-12)
    d = np.abs(np.sum(imu.values["q_nb"] * q, axis=1))  # same rotation up to the sign of q
    np.testing.assert_allclose(d, 1.0, atol=1e-12)
    c = np.array(imu.meta["covariance"]["gyro"]).reshape(3, 3)  # C Σ Cᵀ: xy and xz flip sign, yz does not
    np.testing.assert_array_equal(c, [[1e-4, -2e-6, -3e-6], [-2e-6, 5e-4, 0.0], [-3e-6, 0.0, 6e-4]])
    mag = read_topic(p, "/mag")
    np.testing.assert_allclose(mag.values["mag"], m_b, rtol=1e-12, atol=1e-12)
    # the receive time is kept: 3 ms after the stamp for the magnetometer
    np.testing.assert_allclose(mag.meta["receive_latency_s"]["median"], 3e-3, atol=1e-12)
    np.testing.assert_allclose(mag.t_receive - mag.t, 3e-3, atol=1e-9)
    d9 = read_imu(p, topic="/imu", mag_topic="/mag")
    np.testing.assert_allclose(d9.mag, m_b, atol=1e-12)
    assert d9.meta["t0_ns"] == T0 and d9.meta["frame_id"] == "imu_link"


@pytest.mark.parametrize("storage", STORAGES)
def test_imunav_to_ros_on_simulated_motion(tmp_path, storage):
    """write_bag (FRD -> FLU, µT -> T): what rosbags deserializes is the FLU expression of the motion."""
    t, q, w, f_b, m_b, _, _ = _motion()
    d = ImuData(t, w, f_b, m_b, meta={"t0_ns": T0})
    p = write_bag(_path(tmp_path, storage), {"/imu": d}, storage=storage)
    from rosbags.highlevel import AnyReader

    with AnyReader([p]) as r:
        got = {}
        for conn, ts, raw in r.messages():
            msg = r.deserialize(raw, conn.msgtype)
            got.setdefault(conn.topic, []).append((msg, ts))
    imu = [m for m, _ in got["/imu"]]
    np.testing.assert_allclose([[m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z] for m in imu],
                               frd_to_ros(w), atol=1e-12)
    np.testing.assert_allclose([[m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z]
                                for m in imu], frd_to_ros(f_b), atol=1e-12)
    np.testing.assert_allclose([[m.magnetic_field.x, m.magnetic_field.y, m.magnetic_field.z]
                                for m, _ in got["/imu/mag"]], frd_to_ros(m_b) * 1e-6, rtol=1e-12, atol=1e-20)
    stamps = [m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec for m in imu]
    assert stamps == (T0 + np.round(t * 1e9).astype(np.int64)).tolist()
    assert [ts for _, ts in got["/imu"]] == stamps  # record time = stamp


# ---------------------------------------------------------------- bit-exact read back, 2 IMUs + mag
@pytest.mark.parametrize("storage", STORAGES)
def test_two_imus_and_a_magnetometer_read_back_bit_exactly(tmp_path, storage):
    rng = np.random.default_rng(7)
    n0, n1 = 300, 151
    a = ImuData(np.arange(n0) / 200.0, rng.normal(0, 0.3, (n0, 3)), rng.normal([0, 0, -9.81], 0.2, (n0, 3)),
                rng.normal([20, 1, 45], 2.0, (n0, 3)), meta={"t0_ns": T0})
    b = ImuData(np.arange(n1) / 100.0 + 0.0123, rng.normal(0, 0.3, (n1, 3)), rng.normal(0, 9.0, (n1, 3)),
                meta={"t0_ns": T0})
    p = write_bag(_path(tmp_path, storage), {"/imu0": a, "/imu1": b}, storage=storage)
    topics = {ti.topic: ti for ti in list_topics(p)}
    assert set(topics) == {"/imu0", "/imu0/mag", "/imu1"}
    assert topics["/imu0"].count == n0 and topics["/imu1"].count == n1
    assert topics["/imu0"].kind == "imu" and topics["/imu0/mag"].kind == "mag"
    np.testing.assert_allclose(topics["/imu0"].rate_hz, 200.0, rtol=1e-9)
    np.testing.assert_allclose(topics["/imu1"].duration_s, (n1 - 1) / 100.0, atol=1e-9)

    r0 = read_imu(p, topic="/imu0", mag_topic="/imu0/mag")
    r1 = read_imu(p, topic="/imu1")
    for src, got in ((a, r0), (b, r1)):
        # FRD -> FLU -> FRD is two sign flips: the same bits
        assert np.array_equal(got.gyro, src.gyro) and np.array_equal(got.accel, src.accel)
        stamps = T0 + np.round(src.t * 1e9).astype(np.int64)
        assert got.meta["t0_ns"] == int(stamps[0])
        assert np.array_equal(got.t, (stamps - stamps[0]) * 1e-9)  # the documented time axis, exactly
        np.testing.assert_allclose(got.t + (got.meta["t0_ns"] - T0) * 1e-9, src.t, atol=1e-9)
    # magnetometer: µT -> T -> µT, within a few ulp; exactly the tesla values × 1e6
    raw = read_topic(p, "/imu0/mag")
    assert np.array_equal(r0.mag, raw.values["mag"])
    np.testing.assert_allclose(r0.mag, a.mag, rtol=4e-16 * 8)
    assert r0.mag_unit == "uT"


def test_round_trip_through_a_table_keeps_meta(tmp_path):
    """Bag -> Parquet (imunav convert) -> read: same samples, topic and t0 in meta."""
    d = ImuData(np.arange(50) / 100.0, np.ones((50, 3)), np.tile([0.0, 0.0, -9.81], (50, 1)), meta={"t0_ns": T0})
    p = write_bag(tmp_path / "r.mcap.d", {"/imu": d}, storage="mcap")
    out = tmp_path / "imu.parquet"
    r = runner.invoke(app, ["convert", str(p), str(out)])
    assert r.exit_code == 0, r.output
    back = read_imu(out)
    assert np.array_equal(back.gyro, d.gyro) and back.meta["topic"] == "/imu" and back.meta["t0_ns"] == T0
    r = runner.invoke(app, ["convert", str(p), str(p)])  # OUT == IN
    assert r.exit_code == 2 and len(r.stderr.strip().splitlines()) == 1


# ---------------------------------------------------------------- time: out of order, duplicates, drops
def _imu_series(stamps, recs=None, frames=None):
    recs = stamps if recs is None else recs
    frames = frames or ["imu"] * len(stamps)
    return [(int(r), "sensor_msgs/msg/Imu", int(s), f, _imu_msg((0.01 * i, 0.0, 0.0), (0.0, 0.0, 9.81)), i)
            for i, (s, r, f) in enumerate(zip(stamps, recs, frames))]


@pytest.mark.parametrize("storage", ("ros1", "mcap"))
def test_out_of_order_stamps_are_sorted_with_a_warning(tmp_path, storage):
    stamps = T0 + np.arange(20) * 5_000_000
    stamps[[7, 8]] = stamps[[8, 7]]  # delivered out of order; record times increase
    p = _path(tmp_path, storage)
    _write_raw(p, storage, {"/imu": _imu_series(stamps, recs=T0 + np.arange(20) * 5_000_000 + 1000)})
    with pytest.warns(UserWarning, match="sorted by stamp"):
        d = read_imu(p)
    assert d.meta["time"]["out_of_order"] == 1
    np.testing.assert_allclose(np.diff(d.t), 5e-3, atol=1e-12)
    # the samples moved with their stamps: gyro_x was 0.01 * message index
    np.testing.assert_allclose(d.gyro[7:9, 0], [0.08, 0.07], atol=1e-15)


def test_duplicated_stamps_are_refused(tmp_path):
    stamps = T0 + np.arange(10) * 5_000_000
    stamps[4] = stamps[3]
    p = _path(tmp_path, "mcap")
    _write_raw(p, "mcap", {"/imu": _imu_series(stamps, recs=T0 + np.arange(10) * 5_000_000)})
    with pytest.raises(TimeOrderError, match=r"repeat the stamp.*message \[3\]"):
        read_imu(p)


def test_drops_and_jitter_are_reported(tmp_path):
    k = np.r_[0:50, 53:100]  # messages 50, 51, 52 dropped
    stamps = T0 + k * 4_000_000 + np.where(k % 2 == 0, 0, 100_000)  # ±0.1 ms alternating jitter
    p = _path(tmp_path, "ros1")
    _write_raw(p, "ros1", {"/imu": _imu_series(stamps)})
    d = read_imu(p)
    tq = d.meta["time"]
    assert tq["gaps"] == 1 and tq["missing_estimate"] == 3 and tq["out_of_order"] == 0
    # intervals alternate 4.1 / 3.9 ms (the gap excluded): std 0.1 ms, worst 0.1 or 0.2 ms from the median
    np.testing.assert_allclose(tq["jitter_std_s"], 1e-4, rtol=0.02)
    assert 0.99e-4 < tq["jitter_max_s"] < 2.01e-4
    r = runner.invoke(app, ["info", str(p), "--topic", "/imu"])
    assert r.exit_code == 0, r.output
    assert "1 gap(s), about 3 message(s) missing" in r.stdout


# ---------------------------------------------------------------- bad input
@pytest.fixture(scope="module")
def two_imu_bag(tmp_path_factory):
    d = ImuData(np.arange(40) / 100.0, np.zeros((40, 3)), np.tile([0.0, 0.0, -9.81], (40, 1)), meta={"t0_ns": T0})
    return write_bag(tmp_path_factory.mktemp("bags") / "two", {"/imu_a": d, "/imu_b": d}, storage="sqlite3")


def test_several_imus_and_none_chosen_lists_them(two_imu_bag):
    with pytest.raises(InvalidInputError, match=r"2 IMU topics: /imu_a, /imu_b; choose one with topic="):
        read_imu(two_imu_bag)
    assert read_imu(two_imu_bag, topic="/imu_b").meta["topic"] == "/imu_b"


def test_bag_without_the_topic(two_imu_bag):
    with pytest.raises(InvalidInputError, match=r"no topic '/imu' in the bag; its topics: /imu_a \(sensor_msgs/msg/Imu\)"):
        read_imu(two_imu_bag, topic="/imu")
    with pytest.raises(InvalidInputError, match="instance= is for PX4"):
        read_imu(two_imu_bag, topic="/imu_a", instance=1)
    with pytest.raises(InvalidInputError, match="does not take option"):
        read_imu(two_imu_bag, topic="/imu_a", skiprows=3)


def test_bag_without_an_imu(tmp_path):
    p = _path(tmp_path, "mcap")
    _write_raw(p, "mcap", {"/mag": [(T0, "sensor_msgs/msg/MagneticField", T0, "m", _mag_msg((1e-5, 0.0, 4e-5)))]})
    with pytest.raises(FileFormatError, match="no sensor_msgs/Imu topic in the bag; its topics: /mag"):
        read_imu(p)
    with pytest.raises(InvalidInputError, match="not sensor_msgs/Imu"):
        read_imu(p, topic="/mag")


def test_topic_with_mixed_frame_ids_is_refused(tmp_path):
    stamps = T0 + np.arange(6) * 5_000_000
    p = _path(tmp_path, "ros1")
    _write_raw(p, "ros1", {"/imu": _imu_series(stamps, frames=["imu_a", "imu_b"] * 3)})
    with pytest.raises(FileFormatError, match=r"mixes frame_ids \{'imu_a': 3, 'imu_b': 3\}"):
        read_imu(p)


def test_missing_extra_names_it(monkeypatch, two_imu_bag):
    for k in [k for k in sys.modules if k == "rosbags" or k.startswith("rosbags.")]:
        monkeypatch.setitem(sys.modules, k, None)
    with pytest.raises(MissingDependencyError, match=r"pip install 'imunav\[ros\]'"):
        read_imu(two_imu_bag, topic="/imu_a")
    r = runner.invoke(app, ["info", str(two_imu_bag)])
    assert r.exit_code == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "imunav[ros]" in lines[0] and "Traceback" not in r.stderr


def test_cli_takes_a_bag_with_topic(tmp_path, two_imu_bag):
    r = runner.invoke(app, ["info", str(two_imu_bag)])
    assert r.exit_code == 0 and "/imu_a" in r.stdout and "/imu_b" in r.stdout
    r = runner.invoke(app, ["attitude", "run", str(two_imu_bag), "--topic", "/imu_a", "--filter", "mekf"])
    assert r.exit_code == 0, r.output
    r = runner.invoke(app, ["info", str(two_imu_bag)] + ["--topic", "/nope"])
    assert r.exit_code == 2 and "no topic '/nope'" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    r = runner.invoke(app, ["noise", str(two_imu_bag)])  # two IMUs, none chosen
    assert r.exit_code == 2 and "/imu_a, /imu_b" in r.stderr


def test_seq_gaps_of_ros1_are_counted(tmp_path):
    stamps = T0 + np.arange(10) * 5_000_000
    msgs = _imu_series(stamps)
    del msgs[4]  # header.seq counts every message written; the gap shows a drop on the recorder side
    p = _path(tmp_path, "ros1")
    _write_raw(p, "ros1", {"/imu": msgs})
    d = read_topic(p, "/imu")
    assert d.meta["time"]["gaps"] == 1 and d.meta["time"]["missing_estimate"] == 1
    assert d.meta["seq_gaps"] == {"gaps": 1, "missing": 1} and d.meta["format"] == "rosbag1"


def test_warning_free_normal_read(two_imu_bag):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_imu(two_imu_bag, topic="/imu_a")


def test_gnss_pressure_and_temperature_topics(tmp_path):
    """NavSatFix (deg, m), TwistStamped (ENU -> NED), FluidPressure (Pa), Temperature (°C, merged as temp)."""
    stamps = T0 + np.arange(5) * 200_000_000

    def fix(T, hdr):
        st = T["sensor_msgs/msg/NavSatStatus"](status=0, service=1)
        return T["sensor_msgs/msg/NavSatFix"](header=hdr, status=st, latitude=47.3977, longitude=8.5456, altitude=530.5,
                                              position_covariance=np.r_[4.0, 0, 0, 0, 4.0, 0, 0, 0, 9.0],
                                              position_covariance_type=2)

    def vel(T, hdr):
        V = T["geometry_msgs/msg/Vector3"]
        tw = T["geometry_msgs/msg/Twist"](linear=V(1.0, 2.0, 3.0), angular=V(0.0, 0.0, 0.5))  # east, north, up
        return T["geometry_msgs/msg/TwistStamped"](header=hdr, twist=tw)

    def baro(T, hdr):
        return T["sensor_msgs/msg/FluidPressure"](header=hdr, fluid_pressure=95123.5, variance=4.0)

    def temp(T, hdr):
        return T["sensor_msgs/msg/Temperature"](header=hdr, temperature=21.5, variance=0.01)

    imu_stamps = T0 + np.arange(41) * 20_000_000
    p = _path(tmp_path, "sqlite3")
    _write_raw(p, "sqlite3", {
        "/fix": [(int(s), "sensor_msgs/msg/NavSatFix", int(s), "gps", fix) for s in stamps],
        "/vel": [(int(s), "geometry_msgs/msg/TwistStamped", int(s), "gps", vel) for s in stamps],
        "/baro": [(int(s), "sensor_msgs/msg/FluidPressure", int(s), "baro", baro) for s in stamps],
        "/temp": [(int(s), "sensor_msgs/msg/Temperature", int(s), "imu", temp) for s in stamps],
        "/imu": _imu_series(imu_stamps),
    })
    kinds = {ti.topic: ti.kind for ti in list_topics(p)}
    assert kinds == {"/fix": "gnss", "/vel": "gnss_velocity", "/baro": "pressure", "/temp": "temperature", "/imu": "imu"}
    g = read_topic(p, "/fix")
    assert g.values["lat_deg"][0] == 47.3977 and g.values["alt_m"][0] == 530.5
    np.testing.assert_array_equal(g.values["pos_cov_enu_diag"][0], [4.0, 4.0, 9.0])
    v = read_topic(p, "/vel")
    np.testing.assert_array_equal(v.values["vel_ned"], np.tile([2.0, 1.0, -3.0], (5, 1)))
    np.testing.assert_array_equal(v.values["rate_frd"], np.tile([0.0, 0.0, -0.5], (5, 1)))
    assert read_topic(p, "/baro").values["pressure"][0] == 95123.5
    d = read_imu(p, topic="/imu", temp_topic="/temp")
    np.testing.assert_array_equal(d.temp, 21.5)
    assert d.n == 41 and d.meta["temp_from"]["topic"] == "/temp"
    with pytest.raises(InvalidInputError, match="without mag data"):
        read_imu(p, topic="/imu", mag_topic="/baro")


# ---------------------------------------------------------------- the fixed-layout fast path
def _odom_msg(v, w, var, child):
    def build(T, hdr):
        V = T["geometry_msgs/msg/Vector3"]
        cov = np.zeros(36)
        cov[0] = var
        pose = T["geometry_msgs/msg/PoseWithCovariance"](
            pose=T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=1.0, y=2.0, z=3.0),
                                             orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)),
            covariance=np.arange(36.0))
        tw = T["geometry_msgs/msg/TwistWithCovariance"](twist=T["geometry_msgs/msg/Twist"](linear=V(*v), angular=V(*w)),
                                                          covariance=cov)
        return T["nav_msgs/msg/Odometry"](header=hdr, child_frame_id=child, pose=pose, twist=tw)

    return build


def _imu_topics(n=300):
    """IMU topics whose raw layouts differ: frame_id lengths, covariances that vary, a big-endian one."""
    rng = np.random.default_rng(4)
    stamps = T0 + np.arange(n) * 5_000_000 + rng.integers(0, 1000, n)

    def series(frames, q=False, cov=False):
        out = []
        for i, (s, f) in enumerate(zip(stamps, frames)):
            g, a = rng.standard_normal(3), rng.standard_normal(3) * 9.81
            qv = np.r_[rng.standard_normal(3) * 0.1, 1.0]
            qv = tuple(qv / np.linalg.norm(qv)) if q else None
            c = rng.random(9) * 1e-4 if cov and i % 7 == 3 else np.full(9, 1e-5) if cov else None
            out.append((int(s) + 17, "sensor_msgs/msg/Imu", int(s), f, _imu_msg(tuple(g), tuple(a), qv, c), i + 1))
        return out

    return {"/short": series(["i"] * n), "/long": series(["imu_link_of_a_longer_name"] * n, q=True, cov=True),
            "/mixed_endian": series(["imu"] * n, cov=True), "/big": series(["imu_big"] * n, q=True),
            "/two_frames": series(["imu_a", "imu_b"] * (n // 2)),
            "/two_lengths": series(["imu", "imu_2"] * (n // 2)),
            "/odom": [(int(s) + 3, "nav_msgs/msg/Odometry", int(s), "odom",
                       _odom_msg(tuple(rng.standard_normal(3)), tuple(rng.standard_normal(3)), rng.random() * 0.01,
                                 "base_link"), i + 1) for i, s in enumerate(stamps[::5])],
            "/odom_children": [(int(s) + 3, "nav_msgs/msg/Odometry", int(s), "odom",
                                _odom_msg((0.5, 0.0, 0.0), (0.0, 0.0, 0.1), 0.0, ("base", "base_link")[i % 2]), i + 1)
                               for i, s in enumerate(stamps[::5])]}


@pytest.mark.parametrize("storage", STORAGES)
def test_fixed_layout_fast_path_is_bit_identical_to_rosbags(tmp_path, storage, monkeypatch):
    """sensor_msgs/Imu and nav_msgs/Odometry parsed with numpy from the raw bytes (imunav.io.rosbag._fixed_chunk)
    give what rosbags' per-message deserialization gives, bit for bit, on ROS 1 and ROS 2 (sqlite3, MCAP) bags
    with frame_ids of several lengths, covariances that vary, big-endian CDR and a topic mixing both byte orders;
    a topic mixing frame_ids (of one length or of two) or child frames is refused with the same message."""
    import imunav.io.rosbag as rb

    p = _path(tmp_path, storage)
    be = (lambda topic, i: topic == "/big" or (topic == "/mixed_endian" and i % 2 == 1)) if storage != "ros1" else None
    _write_raw(p, storage, _imu_topics(), big_endian=be)
    fast, used = {}, {}
    chunk = rb._fixed_chunk
    for topic in ("/short", "/long", "/mixed_endian", "/big", "/two_frames", "/two_lengths", "/odom",
                  "/odom_children"):
        calls = []
        monkeypatch.setattr(rb, "_fixed_chunk", lambda *a, calls=calls: calls.append(chunk(*a)) or calls[-1])
        try:
            fast[topic] = read_topic(p, topic)
        except FileFormatError as e:
            fast[topic] = str(e)
        used[topic] = all(c is not None for c in calls)
    # numpy parsed every chunk but those mixing byte orders or frame_ids of one length (rosbags reads them)
    assert used == {"/short": True, "/long": True, "/mixed_endian": storage == "ros1", "/big": True,
                    "/two_frames": False, "/two_lengths": True, "/odom": True, "/odom_children": True}
    monkeypatch.setattr(rb, "_fixed_chunk", lambda *a: None)  # rosbags' deserialization of every message
    for topic, f in fast.items():
        if isinstance(f, str):
            with pytest.raises(FileFormatError) as e:
                read_topic(p, topic)
            assert str(e.value) == f and ("mixes frame_ids" in f or "mixes child_frame_ids" in f)
            continue
        s = read_topic(p, topic)
        assert f.values.keys() == s.values.keys() and f.meta == s.meta, topic
        for k in s.values:
            assert f.values[k].tobytes() == s.values[k].tobytes(), (topic, k)
        assert f.t.tobytes() == s.t.tobytes() and f.t_receive.tobytes() == s.t_receive.tobytes()
    assert fast["/long"].meta["covariance"]["varies"] and "q_nb" in fast["/big"].values
    ok = [t for t, f in fast.items() if not isinstance(f, str)]
    monkeypatch.setattr(rb, "_fixed_chunk", chunk)
    together = rb.read_topics(p, ok)  # one pass over the bag: the same topics
    for t in ok:
        assert together[t].meta == fast[t].meta and all(
            together[t].values[k].tobytes() == fast[t].values[k].tobytes() for k in fast[t].values)
    assert "child_frame_ids" in fast["/odom_children"] and fast["/odom"].meta["child_frame_id"] == "base_link"


def test_a_damaged_chunk_of_a_bag_is_named(tmp_path):
    """A bz2 chunk whose bytes were damaged (the index intact) ended in ``error: Invalid data stream``, naming no
    file: rosbags' error while reading the records is now a FileFormatError naming the bag, through the CLI too."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    T = ts.types
    path = tmp_path / "rec.bag"
    writer = Writer(path)
    writer.set_compression(Writer.CompressionFormat.BZ2)
    with writer:
        conn = writer.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=ts)
        for i in range(3000):
            stamp = T0 + i * 5_000_000
            hdr = T["std_msgs/msg/Header"](seq=i, stamp=T["builtin_interfaces/msg/Time"](
                sec=stamp // 1_000_000_000, nanosec=stamp % 1_000_000_000), frame_id="imu")
            msg = _imu_msg([0.01 * np.sin(i), 0.0, 0.0], [0.0, 0.0, 9.81])(T, hdr)
            writer.write(conn, stamp, ts.serialize_ros1(msg, "sensor_msgs/msg/Imu"))
    assert read_imu(path).n == 3000
    raw = bytearray(path.read_bytes())
    mid = len(raw) // 2
    raw[mid:mid + 2000] = bytes(2000)
    path.write_bytes(raw)
    with pytest.raises(FileFormatError, match=r"rec\.bag: a record of the bag cannot be read \(OSError: Invalid data "
                                              r"stream\); the bag is damaged"):
        read_imu(path)
    r = runner.invoke(app, ["info", str(path), "--topic", "/imu"])
    assert r.exit_code == 2 and len(r.stderr.strip().splitlines()) == 1 and "rec.bag: a record" in r.stderr, r.stderr
