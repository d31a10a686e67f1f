"""Units declared in a file win over reader options (issue 16): a contradicting option is an error naming both."""

import json

import numpy as np
import pytest
from builders import static_imu
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from imunav.cli.main import app
from imunav.errors import UnitError
from imunav.io import read_imu, write_imu
from imunav.units import unit_factor


def _rec(n=200):
    return static_imu(n, accel=(0.0, 0.0, -9.81), mag=(20.0, 0.0, 40.0), mag_unit="uT")


@pytest.mark.parametrize("ext", ["csv", "parquet", "h5", "npz", "mat"])
def test_contradicting_unit_refused_matching_accepted(tmp_path, ext):
    p = write_imu(_rec(), tmp_path / f"rec.{ext}")
    with pytest.raises(UnitError, match=r"declares gyro in 'rad/s'.*'deg/s'"):
        read_imu(p, units={"gyro": "deg/s"})
    with pytest.raises(UnitError, match=r"declares t in 's'.*'ms'"):
        read_imu(p, units={"t": "ms"})
    # the same unit, however spelled, is not a contradiction: values unchanged
    got = read_imu(p, units={"gyro": "rad/s", "accel": "m/s^2"})
    np.testing.assert_array_equal(got.gyro, _rec().gyro)


def test_option_fills_in_an_undeclared_unit(tmp_path):
    p = tmp_path / "plain.csv"
    d = _rec()
    np.savetxt(p, np.column_stack([d.t, np.degrees(d.gyro), d.accel]), delimiter=",",
               header="t,gx,gy,gz,ax,ay,az", comments="")
    got = read_imu(p, units={"gyro": "deg/s"})
    np.testing.assert_allclose(got.gyro, d.gyro, rtol=1e-12)


def test_cli_info_refuses_a_contradicting_flag(tmp_path):
    p = write_imu(_rec(), tmp_path / "rec.csv")
    r = CliRunner().invoke(app, ["info", str(p), "--gyro-unit", "deg/s"])
    assert r.exit_code == 2
    err = r.stderr if hasattr(r, "stderr") else r.output
    assert "declares gyro in 'rad/s'" in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
    ok = CliRunner().invoke(app, ["info", str(p), "--json", str(tmp_path / "i.json")])
    assert ok.exit_code == 0, ok.output
    json.loads((tmp_path / "i.json").read_text())


# --------------------------------------------------------------------- issue 27: declared units are applied
DEG = np.pi / 180.0
G0 = 9.80665


def _non_si(d):
    """The recording in the declared units: t in ms, gyro in deg/s, accel in g."""
    return d.t * 1e3, d.gyro / DEG, d.accel / G0


def _assert_si(got, d):
    np.testing.assert_allclose(got.t, d.t, rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.gyro, d.gyro, rtol=1e-12, atol=0)
    np.testing.assert_allclose(got.accel, d.accel, rtol=1e-12, atol=0)


def _write_declared(tmp_path, kind, d):
    import h5py
    import pyarrow as pa
    import pyarrow.parquet as pq
    import scipy.io

    t, g, a = _non_si(d)
    units = {"t": "ms", "gyro": "deg/s", "accel": "g"}
    header = json.dumps({"format": "imunav-imu", "version": 1, "units": units})
    names = ["gx", "gy", "gz", "ax", "ay", "az"]
    block = np.column_stack([t, g, a])
    if kind == "csv-header":
        p = tmp_path / "h.csv"
        p.write_text(f"# imunav {header}\nt,{','.join(names)}\n" + "".join(",".join(map(repr, r)) + "\n" for r in block.tolist()))
    elif kind in ("csv-brackets", "csv-parens"):
        p = tmp_path / f"{kind}.csv"
        ann = (lambda n, u: f"{n}[{u}]") if kind == "csv-brackets" else (lambda n, u: f"{n} ({u})")
        head = [ann("t", "ms")] + [ann(n, "deg/s") for n in names[:3]] + [ann(n, "g") for n in names[3:]]
        p.write_text(",".join(head) + "\n" + "".join(",".join(map(repr, r)) + "\n" for r in block.tolist()))
    elif kind == "hdf5-attrs":
        p = tmp_path / "a.h5"
        with h5py.File(p, "w") as fh:
            for name, arr, u in (("t", t, "ms"), ("gyro", g, "deg/s"), ("accel", a, "g")):
                fh.create_dataset(name, data=arr).attrs["units"] = u
    elif kind == "hdf5-group":
        p = tmp_path / "g.h5"
        with h5py.File(p, "w") as fh:
            for name, arr in (("t", t), ("gyro", g), ("accel", a)):
                fh.create_dataset(name, data=arr)
            fh.attrs["units"] = json.dumps(units)
    elif kind == "mat-units":
        p = tmp_path / "u.mat"
        scipy.io.savemat(p, {"t": t[:, None], "gyro": g, "accel": a, "units": json.dumps(units)})
    elif kind == "mat-per-variable":
        p = tmp_path / "v.mat"
        scipy.io.savemat(p, {"t": t[:, None], "gyro": g, "accel": a, "t_unit": "ms", "gyro_unit": "deg/s",
                             "accel_unit": "g"})
    elif kind == "parquet-field":
        p = tmp_path / "f.parquet"
        fields = [pa.field("t", pa.float64(), metadata={"unit": "ms"})]
        fields += [pa.field(n, pa.float64(), metadata={"unit": "deg/s" if n[0] == "g" else "g"}) for n in names]
        pq.write_table(pa.table([pa.array(c) for c in block.T], schema=pa.schema(fields)), p)
    elif kind == "parquet-names":
        p = tmp_path / "n.parquet"
        head = ["t[ms]"] + [f"{n}[deg/s]" for n in names[:3]] + [f"{n}[g]" for n in names[3:]]
        pq.write_table(pa.table({h: c for h, c in zip(head, block.T)}), p)
    elif kind == "npz-header":
        p = tmp_path / "h.npz"
        np.savez(p, t=t, gyro=g, accel=a, imunav=np.array(header))
    return p


KINDS = ["csv-header", "csv-brackets", "csv-parens", "hdf5-attrs", "hdf5-group", "mat-units", "mat-per-variable",
         "parquet-field", "parquet-names", "npz-header"]


@pytest.mark.parametrize("kind", KINDS)
def test_declared_non_si_units_are_applied_in_every_format(tmp_path, kind):
    """ms, deg/s and g declared in the file come back as s, rad/s and m/s^2 (the 57x / 9.8x errors of issue 27);
    then written by imunav (SI) and read again: the same values."""
    d = _rec()
    p = _write_declared(tmp_path, kind, d)
    got = read_imu(p)
    _assert_si(got, d)
    # an option that agrees with the declaration is fine; one that contradicts it is an error
    _assert_si(read_imu(p, units={"gyro": "deg/s"}), d)
    with pytest.raises(UnitError, match="declares gyro in 'deg/s'"):
        read_imu(p, units={"gyro": "rad/s"})
    for ext in ("csv", "parquet", "h5", "npz", "mat"):
        _assert_si(read_imu(write_imu(got, tmp_path / f"back.{ext}")), d)


@pytest.mark.parametrize("unit, match", [("", "unit string"), ("furlongs/s", "unknown unit"),
                                         ("g", "not a unit of angular_rate"), ("m/s^2", "not a unit of angular_rate")])
def test_unknown_empty_or_wrong_quantity_declared_unit_is_an_error(tmp_path, unit, match):
    d = _rec(20)
    csv = tmp_path / "r.csv"
    head = f"# imunav {json.dumps({'units': {'gyro': unit}})}\nt,gx,gy,gz,ax,ay,az\n"
    csv.write_text(head + "".join(",".join(map(repr, r)) + "\n" for r in np.column_stack([d.t, d.gyro, d.accel]).tolist()))
    with pytest.raises(UnitError, match=match):
        read_imu(csv)
    ann = tmp_path / "a.csv"
    ann.write_text(f"t,gx[{unit}],gy[{unit}],gz[{unit}],ax,ay,az\n"
                   + "".join(",".join(map(repr, r)) + "\n" for r in np.column_stack([d.t, d.gyro, d.accel]).tolist()))
    with pytest.raises(UnitError, match=match):
        read_imu(ann)


def test_columns_of_one_group_that_disagree_are_an_error(tmp_path):
    d = _rec(20)
    p = tmp_path / "mixed.csv"
    p.write_text("t,gx[deg/s],gy[rad/s],gz[deg/s],ax,ay,az\n"
                 + "".join(",".join(map(repr, r)) + "\n" for r in np.column_stack([d.t, d.gyro, d.accel]).tolist()))
    with pytest.raises(UnitError, match="different units"):
        read_imu(p)


def test_cli_applies_the_declared_units(tmp_path):
    """Through the CLI: `imunav convert` of a CSV declaring deg/s and g writes SI values (was 57x / 9.8x off)."""
    d = _rec()
    src = _write_declared(tmp_path, "csv-header", d)
    r = CliRunner().invoke(app, ["convert", str(src), str(tmp_path / "si.npz")])
    assert r.exit_code == 0, r.output
    _assert_si(read_imu(tmp_path / "si.npz"), d)
    bad = tmp_path / "bad.csv"
    bad.write_text("t,gx[furlongs],gy[furlongs],gz[furlongs],ax,ay,az\n0,0,0,0,0,0,-1\n0.01,0,0,0,0,0,-1\n")
    r = CliRunner().invoke(app, ["convert", str(bad), str(tmp_path / "x.npz")])
    err = r.stderr if hasattr(r, "stderr") else r.output
    assert r.exit_code == 2 and "furlongs" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "x.npz").exists()


_SPELLINGS = {"gyro": ["rad/s", "deg/s", "dps", "°/s", "deg/h", "rpm", "mrad/s", "Deg / Sec"],
              "accel": ["m/s^2", "m/s2", "m/s**2", "g", "mg", "ug", "µg", "ft/s^2"]}


@settings(max_examples=25, deadline=None, derandomize=True)
@given(gu=st.sampled_from(_SPELLINGS["gyro"]), au=st.sampled_from(_SPELLINGS["accel"]),
       tu=st.sampled_from(["s", "ms", "us", "ns"]), style=st.sampled_from(["[{}]", " ({})", "header"]))
def test_any_accepted_spelling_declared_in_a_csv_is_applied(tmp_path_factory, gu, au, tu, style):
    """Property: whatever accepted unit a CSV declares (header or column names), reading gives SI."""
    d = _rec(50)
    fg, fa, ft = unit_factor(gu, "gyro"), unit_factor(au, "accel"), unit_factor(tu, "time")
    block = np.column_stack([d.t / ft, d.gyro / fg, d.accel / fa])
    p = tmp_path_factory.mktemp("spell") / "r.csv"
    names = ["t", "gx", "gy", "gz", "ax", "ay", "az"]
    units = [tu] + [gu] * 3 + [au] * 3
    if style == "header":
        head = f"# imunav {json.dumps({'units': {'t': tu, 'gyro': gu, 'accel': au}})}\n{','.join(names)}\n"
    else:
        head = ",".join(n + style.format(u) for n, u in zip(names, units)) + "\n"
    p.write_text(head + "".join(",".join(map(repr, r)) + "\n" for r in block.tolist()), encoding="utf-8")
    got = read_imu(p)
    np.testing.assert_allclose(got.gyro, d.gyro, rtol=1e-12, atol=1e-300)
    np.testing.assert_allclose(got.accel, d.accel, rtol=1e-12)
    np.testing.assert_allclose(got.t, d.t, rtol=1e-12, atol=1e-15)
