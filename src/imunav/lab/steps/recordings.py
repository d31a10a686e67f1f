"""Lab step: load real recordings named in the lab definition (``[recordings.<name>]``).

Each table describes one recording file and which test it is::

    [recordings.adis_static]
    path = "shared:adis16405/adis16405_imu2.npz"   # "shared:" = the shared data folder
                                                   # (IMUNAV_DATA, else ../shared/data);
                                                   # other paths: relative to the TOML file
    test = "static"            # static | multiposition | rate_table | multipose
    unit = "ADIS16405 #2"      # optional: the device (default "imu"); a calibration is
                               # applied only to recordings of the same unit
    format = "npz"             # optional: from the suffix
    units = { gyro = "deg/s", accel = "g" }        # units in the file (SI by default)
    fs = 100.0                 # when the file has no time column
    max_duration_s = 3600.0    # optional: keep only the first hour
    # CSV / raw counts:
    # columns = { accel = ["ax", "ay", "az"], gyro = ["gx", "gy", "gz"] }
    # scales = { accel = 5.9855e-4, gyro = 1.3323e-4 }   # SI per count (with units = "counts")
    # skiprows = 4 ; delimiter = "," ; offsets = { ... } ; nan_policy = "raise"
    # layout = "euroc"                    # a named CSV layout (euroc, tum-vi, kalibr, px4-csv, xio)
    # ROS bag / PX4 ULog (path = "flight.ulg", "run.bag", a ROS 2 bag folder, .db3, .mcap):
    # topic = "/imu/data" ; instance = 1 ; mag_topic = "/imu/mag"
    # segments = "static_segments.json"   # multiposition / rate_table: the segment table
    # init_s = 36.5 ; wait_s = 3.0        # multipose: initial rest and time per pose
    # gravity = 9.80665 ; latitude_deg = 45.0

A ``static`` recording is also characterised here: overlapping Allan
deviation and the IEEE-952 terms N, B, K of both triads with their 95 %
intervals, checked against the ``[spec]`` (the virtual IMU's ``noise`` step
does the same with the comparison against the injected truth).

Artifacts set (the same keys as :mod:`imunav.lab.steps.simulate_tests`, so the
analysis steps work on either): ``recordings`` (test name -> ImuData, test
names ``static_long`` for ``static``, ``hundred_position`` for
``multiposition``, ``rate_table``, ``multipose``), ``profiles`` (test name ->
Segments table, when given), ``recording_specs`` (test name ->
:class:`RecordingSpec`), ``files``; ``sim`` holds ``g`` and ``lat`` when given.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from imunav.errors import ConfigError, ImunavError, InvalidInputError
from imunav.files import atomic_path
from imunav.io import read_imu
from imunav.io.datasets import shared_data_dir
from imunav.lab.report.catalog import noise_estimates
from imunav.lab.report.lab import display_parameters, embed_png
from imunav.lab.steps._api import LabContext, StepResult
from imunav.noise import allan_deviation, fit_noise
from imunav.noise.plot import plot_allan
from imunav.sim import Segments
from imunav.units import to_display

#: The report hook shows the parameters itself.
RENDERS_PARAMETERS = True
TITLE = "Recordings (real data) and noise of the static record"

#: ``test`` value -> artifact name used by the analysis steps.
TESTS = {"static": "static_long", "multiposition": "hundred_position", "rate_table": "rate_table",
         "multipose": "multipose"}

#: The artifact holding the recordings :func:`read_recordings` read before the steps ran (the runner's check).
LOADED = "recordings_read"

_READ_KEYS = ("format", "columns", "units", "scales", "offsets", "fs", "t0", "delimiter", "skiprows", "nan_policy",
              "mag_unit", "topic", "instance", "mag_topic", "layout")
_LAB_KEYS = ("path", "test", "unit", "segments", "max_duration_s", "t_start_s", "init_s", "wait_s", "gravity",
             "latitude_deg", "description")


@dataclass(frozen=True)
class RecordingSpec:
    """One recording of a lab definition, validated.

    Attributes
    ----------
    name : str
        The table name.
    path : pathlib.Path
        Resolved file path (or ROS 2 bag folder).
    test : str
        ``static``, ``multiposition``, ``rate_table`` or ``multipose``.
    read : dict
        Options for :func:`imunav.io.read_imu` (format, columns, units, scales, ...).
    segments : pathlib.Path or None
        Segment table JSON (multiposition / rate_table), resolved.
    t_start_s, max_duration_s : float
        The part of the file to use: from ``t_start_s`` after its first sample, at most ``max_duration_s``
        long (None: to the end), s.
    init_s, wait_s : float
        Multi-pose session timing: initial rest and time per pose, s.
    gravity : float or None
        Local gravity, m/s² (None: the method's default).
    latitude_deg : float or None
        Geodetic latitude, degrees in [-90, 90] (Earth rate, normal gravity), or None.
    description : str
        Free text shown in the report.
    unit : str
        The device (a calibration is applied only to recordings of the same unit).
    """

    name: str
    path: Path
    test: str
    read: dict[str, Any] = field(default_factory=dict)
    segments: Path | None = None
    t_start_s: float = 0.0
    max_duration_s: float | None = None
    init_s: float = 30.0
    wait_s: float = 3.0
    gravity: float | None = None
    latitude_deg: float | None = None
    description: str = ""
    unit: str = "imu"

    @property
    def artifact(self) -> str:
        return TESTS[self.test]


def resolve_path(value: str, base_dir: Path, where: str) -> Path:
    """``shared:<sub/path>`` -> the shared data folder; relative paths -> relative to ``base_dir``.

    Parameters
    ----------
    value : str
        Path as written in the lab definition.
    base_dir : pathlib.Path
        Folder relative paths are resolved against (the TOML file's).
    where : str
        Location for error messages (file and table).

    Returns
    -------
    pathlib.Path
        An existing file, or a ROS 2 bag folder (with ``metadata.yaml``).

    Raises
    ------
    ConfigError
        If the shared data folder is not found for a ``shared:`` path, or the file does not exist.
    """
    if value.startswith("shared:"):
        root = shared_data_dir()
        if root is None:
            raise ConfigError(
                f"{where}: path {value!r} is in the shared data folder, which was not found; set IMUNAV_DATA to the "
                "folder that holds the data sets (or put them in ../shared/data next to the project)"
            )
        p = root / value[len("shared:"):]
    else:
        p = Path(value).expanduser()
        if not p.is_absolute():
            p = base_dir / p
    if not (p.is_file() or (p / "metadata.yaml").is_file()):  # a file, or a ROS 2 bag folder
        raise ConfigError(f"{where}: recording file {p} does not exist")
    return p


def _num(tab: Mapping[str, Any], key: str, where: str, *, positive: bool = True) -> float | None:
    if key not in tab:
        return None
    v = tab[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or (positive and v <= 0) or not np.isfinite(v):
        raise ConfigError(f"{where}: {key} must be a {'positive ' if positive else ''}number, got {v!r}")
    return float(v)


def parse_recordings(table: Mapping[str, Any], base_dir: Path, where: str = "lab configuration") -> dict[str, RecordingSpec]:
    """Validate ``[recordings.<name>]`` tables into :class:`RecordingSpec` objects.

    Parameters
    ----------
    table : Mapping
        The ``[recordings]`` table: name -> its table.
    base_dir : pathlib.Path
        Folder relative paths are resolved against.
    where : str
        Location for error messages.

    Returns
    -------
    dict
        Name -> :class:`RecordingSpec`, in table order.

    Raises
    ------
    ConfigError
        If the table is empty, or an entry is not a table, has an unknown key, no ``path``, an unknown
        ``test`` or one already given, a missing file or segment table, or an option of the wrong type or
        range; the message names the table and key.
    """
    if not table:
        raise ConfigError(f"{where}: [recordings] is empty; add at least one [recordings.<name>] table")
    out: dict[str, RecordingSpec] = {}
    seen_tests: dict[str, str] = {}
    for name, tab in table.items():
        w = f"{where}: [recordings.{name}]"
        if not isinstance(tab, Mapping):
            raise ConfigError(f"{w} must be a table with path = ... and test = ...")
        unknown = set(tab) - set(_READ_KEYS) - set(_LAB_KEYS)
        if unknown:
            raise ConfigError(f"{w}: unknown key(s) {sorted(unknown)}; allowed: {', '.join(_LAB_KEYS + _READ_KEYS)}")
        if "path" not in tab or not isinstance(tab["path"], str):
            raise ConfigError(f"{w}: path is required (a file path, or shared:<folder>/<file>)")
        test = tab.get("test")
        if test not in TESTS:
            raise ConfigError(f"{w}: test must be one of {', '.join(TESTS)}; got {test!r}")
        if test in seen_tests:
            raise ConfigError(f"{w}: test {test!r} is already given by [recordings.{seen_tests[test]}]; one recording per test")
        seen_tests[test] = name
        for k in ("columns", "units", "scales", "offsets"):
            if k in tab and not isinstance(tab[k], Mapping):
                raise ConfigError(f"{w}: {k} must be a table, e.g. {k} = {{ gyro = ..., accel = ... }}")
        if "format" in tab and tab["format"] not in ("csv", "parquet", "hdf5", "mat", "npz", "rosbag", "ulog"):
            raise ConfigError(f"{w}: format must be csv, parquet, hdf5, mat, npz, rosbag or ulog; got {tab['format']!r}")
        for k in ("topic", "mag_topic", "layout"):
            if k in tab and not isinstance(tab[k], str):
                raise ConfigError(f"{w}: {k} must be a string (a bag / ULog topic, or a CSV layout name), got {tab[k]!r}")
        if "instance" in tab and (not isinstance(tab["instance"], int) or isinstance(tab["instance"], bool)
                                  or tab["instance"] < 0):
            raise ConfigError(f"{w}: instance must be a non-negative integer (a PX4 multi_id), got {tab['instance']!r}")
        if "skiprows" in tab and (not isinstance(tab["skiprows"], int) or tab["skiprows"] < 0):
            raise ConfigError(f"{w}: skiprows must be a non-negative integer, got {tab['skiprows']!r}")
        read = {k: (dict(tab[k]) if isinstance(tab[k], Mapping) else tab[k]) for k in _READ_KEYS if k in tab}
        if "fs" in read:
            read["fs"] = _num(tab, "fs", w)
        seg = None
        if test in ("multiposition", "rate_table"):
            if "segments" not in tab:
                raise ConfigError(f"{w}: a {test} test needs segments = \"<segment table JSON>\" (Profile.to_dict() format)")
            seg = resolve_path(str(tab["segments"]), base_dir, w)
        elif "segments" in tab:
            raise ConfigError(f"{w}: segments applies to multiposition and rate_table tests only")
        lat = _num(tab, "latitude_deg", w, positive=False)
        if lat is not None and not -90 <= lat <= 90:
            raise ConfigError(f"{w}: latitude_deg must lie in [-90, 90], got {lat}")
        out[name] = RecordingSpec(
            name=name, path=resolve_path(tab["path"], base_dir, w), test=test, read=read, segments=seg,
            t_start_s=_num(tab, "t_start_s", w, positive=False) or 0.0, max_duration_s=_num(tab, "max_duration_s", w),
            init_s=_num(tab, "init_s", w) or 30.0, wait_s=_num(tab, "wait_s", w) or 3.0,
            gravity=_num(tab, "gravity", w), latitude_deg=lat, description=str(tab.get("description", "")),
            unit=str(tab.get("unit", "imu")),
        )
    return out


def _segments(path: Path) -> Any:
    return Segments.read(path)


def read_recordings(specs: Mapping[str, RecordingSpec], where: str = "lab configuration") -> dict[str, Any]:
    """Read every recording of a lab definition (and its segment table), cut to its part: the check of the
    ``[recordings]`` tables against the files themselves, done before any step runs.

    Parameters
    ----------
    specs : Mapping
        Name -> :class:`RecordingSpec`.
    where : str
        The lab definition, for messages.

    Returns
    -------
    dict
        Name -> ``(ImuData, Segments or None)``.

    Raises
    ------
    ConfigError
        Naming the file, the table and the key when a recording cannot be read as the table says (an unknown
        unit, a unit or rate that contradicts the file, a column that is not there) or its part is empty.
    """
    out: dict[str, Any] = {}
    for name, sp in specs.items():
        w = f"{where}: [recordings.{name}]"
        try:
            data = read_imu(sp.path, **sp.read)
            if sp.t_start_s or sp.max_duration_s:
                t0 = data.t[0] + sp.t_start_s
                t1 = t0 + sp.max_duration_s if sp.max_duration_s else data.t[-1] + 1.0
                data = data.time_slice(t0, t1)
            seg = _segments(sp.segments) if sp.segments is not None else None
        except (ImunavError, ValueError, OSError) as exc:
            keys = [k for k in sp.read if k in str(exc)] or list(sp.read)
            raise ConfigError(f"{w} ({', '.join(keys) or 'path'}): {exc}") from None
        out[name] = (data, seg)
    return out


def requires(lab: Any, earlier: Sequence[str]) -> list[str]:
    """Checked before the lab runs: the step reads the definition's ``[recordings.<name>]`` tables.

    Parameters
    ----------
    lab : imunav.lab.config.LabConfig
        The typed lab definition.
    earlier : sequence of str
        The steps that run before this one (none of them is an input).

    Returns
    -------
    list of str
        Empty: the step takes no input from another step.

    Raises
    ------
    ConfigError
        If the definition has no ``[recordings.<name>]`` table.
    """
    if not getattr(lab, "recordings", None):
        raise ConfigError("the recordings step needs [recordings.<name>] tables in the lab definition")
    return []


def run(ctx: LabContext) -> StepResult:
    """Run the step: see the module docstring for what it computes, its options, artifacts and files.

    Parameters
    ----------
    ctx : LabContext
        The lab's context: the step's option table ``ctx.options`` (``[recordings]``), the artifacts it reads and
        sets, the report folder.

    Returns
    -------
    StepResult
        One row per recording; for a static record its noise terms (``parameters``) for the ``[spec]`` check.

    Raises
    ------
    ConfigError
        If the lab definition has no ``[recordings.<name>]`` table.
    """
    specs: dict[str, RecordingSpec] = dict(getattr(ctx.lab, "recordings", {}) or {})
    if not specs:
        raise ConfigError("the recordings step needs [recordings.<name>] tables in the lab definition")
    recs, profs, files, rows = {}, {}, {}, []
    sim: dict[str, Any] = {}
    loaded = ctx.artifacts.pop(LOADED, None) or read_recordings(specs)
    with ctx.task("read recordings", total=len(specs)) as advance:
        for name, sp in specs.items():
            data, seg = loaded[name]
            recs[sp.artifact] = data
            files[sp.artifact] = sp.path
            if seg is not None:
                profs[sp.artifact] = seg
            if sp.gravity is not None:
                sim["g"] = sp.gravity
            if sp.latitude_deg is not None:
                sim["lat"] = np.deg2rad(sp.latitude_deg)
            gaps = data.gaps()
            rows.append({
                "recording": name, "unit": sp.unit, "test": sp.test, "file": sp.path.name, "samples": int(data.n),
                "rate (Hz)": round(float(data.fs), 6), "duration (s)": round(float(data.duration), 3),
                "gaps": len(gaps),
                "gyro mean (deg/s)": ", ".join(f"{v:.4g}" for v in np.rad2deg(data.gyro.mean(axis=0))),
                "|f| mean (m/s²)": round(float(np.linalg.norm(data.accel, axis=1).mean()), 5),
            })
            advance()
    params: dict[str, tuple[float, float | None]] = {}
    figures, noise_rows = [], []
    notes_extra = []
    if "static_long" in recs:
        try:
            params, figures, noise_rows = _characterise_static(ctx, recs["static_long"], specs)
        except InvalidInputError as exc:  # e.g. a record too short for an Allan fit: say so, keep the rest
            notes_extra.append(f"Noise terms of the static record not identified: {exc}")
    ctx.artifacts.update(recordings=recs, profiles=profs, files=files, recording_specs={s.artifact: s for s in specs.values()})
    ctx.artifacts.setdefault("sim", {}).update(sim)
    summary = {"recordings": {r["recording"]: {k: v for k, v in r.items() if k != "recording"} for r in rows}}
    if noise_rows:
        summary["static_noise"] = {r["term"] + " " + r["sensor"]: r for r in noise_rows}
    tables = [("Recordings", rows)]
    if noise_rows:
        tables.append(("Noise terms of the static record (overlapping Allan variance, GLS fit of N, B, K with "
                       "BIC term selection; 95 % intervals)", noise_rows))
    return StepResult(
        summary=summary, passed=True, tables=tables, figures=figures, parameters=params,
        notes=[f"{len(rows)} recording(s) read and converted to SI at the edge (units and column mapping from the "
               "lab definition)."] + [f"{s.name}: {s.description}" for s in specs.values() if s.description] + notes_extra,
    )


def _characterise_static(ctx: LabContext, data: Any, specs: Mapping[str, RecordingSpec]) -> tuple[dict, list, list]:
    """Allan deviation and IEEE-952 noise terms (N, B, K) of the static record, both triads.

    The real-data counterpart of the virtual IMU's noise step (which also
    compares with the injected truth): white noise N (ARW / VRW), bias
    instability B and random walk K by generalised least squares on the
    overlapping Allan variance (:func:`imunav.noise.fit_noise`).
    """

    params: dict[str, tuple[float, float | None]] = {}
    figs, rows = [], []
    name = next((s.name for s in specs.values() if s.artifact == "static_long"), "static")
    disp = {"gyro": {"N": "deg/sqrt(h)", "B": "deg/h", "K": "deg/h/sqrt(h)"},
            "accel": {"N": "m/s/sqrt(h)", "B": "ug", "K": "m/s/h/sqrt(h)"}}
    with ctx.task("noise of the static record", total=2) as advance:
        for sensor, x, unit in (("gyro", data.gyro, "rad/s"), ("accel", data.accel, "m/s^2")):
            ad = allan_deviation(x, data.fs, units=unit, channels=["x", "y", "z"])
            fit = fit_noise(ad, ("N", "B", "K"), quantity=sensor)
            params.update(noise_estimates(fit, sensor))
            for term, du in disp[sensor].items():
                i = fit.names.index(term)
                for c, a in enumerate("xyz"):
                    sel = bool(fit.selected[i, c])
                    rows.append({
                        "sensor": sensor, "term": term, "axis": a, "unit": du,
                        "value": float(to_display(fit.value[i, c], du)) if sel else None,
                        "95 % low": float(to_display(fit.ci_lo[i, c], du)) if sel else None,
                        "95 % high": float(to_display(fit.ci_hi[i, c], du)) if sel else None,
                        "selected": "yes" if sel else "no (BIC)",
                    })
            fig = plot_allan(ad, fit, title=f"{sensor}: {name}")
            path = ctx.path("figures", f"recordings_allan_{sensor}.png")

            with atomic_path(path) as tmp:
                fig.savefig(tmp, format="png", dpi=80)
            figs.append(path)
            advance()
    return params, figs, rows


def report(section: Any, result: StepResult, ctx: LabContext) -> None:
    """Add the step's tables and figures to its section of the HTML report.

    Parameters
    ----------
    section : imunav.lab.report.html.Section
        The step's section.
    result : StepResult
        What :func:`run` returned.
    ctx : LabContext
        The lab's context (its ``[spec]`` and artifacts).
    """
    for caption, rows in result.tables[:1]:
        section.table(rows, caption)
    for f in result.figures:
        embed_png(section, f, f"Allan deviation of the static record with its confidence band and the fitted terms "
                              f"({Path(f).stem.rsplit('_', 1)[-1]})")
    for caption, rows in result.tables[1:]:
        section.table(rows, caption)
    if result.parameters:
        section.parameters(display_parameters(result.parameters, getattr(ctx.lab, "spec", None)),
                           "Noise parameters checked against the specification (display units, ±1σ)")
    specs = getattr(ctx.lab, "recordings", {}) or {}
    section.code("\n".join(f"{s.name}: {s.path}  (test {s.test}; read options {json.dumps(s.read)})"
                           for s in specs.values()))
