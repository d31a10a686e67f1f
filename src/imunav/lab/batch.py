"""Production-batch processing: many IMUs, one command, one summary table.

A *batch folder* holds one recording per unit (any :func:`imunav.io.read_imu`
format), named after the unit::

    batch/
      unit_001.npz            static multi-position test of unit 001
      unit_001_rate.npz       (optional) its rate-table test
      segments.json           segment table of the static test (shared by all units,
                              or <unit>_segments.json per unit)
      rate_segments.json      segment table of the rate-table test (or <unit>_rate_segments.json)
      truth/unit_001.json     (simulated batches) the true error model

:func:`simulate_batch` writes such a folder for N virtual IMUs whose
parameters spread from unit to unit around a preset; :func:`calibrate_batch`
and :func:`noise_batch` process every unit in parallel with
:func:`imunav.lab.montecarlo.run_batch`, write one result file per unit and
return a :class:`BatchSummary` (one row per unit: every parameter with its
standard error, its error against the truth when known, pass / fail against
an optional datasheet spec).

:func:`gins_batch` does the same for a folder of robot or drone logs (ROS 1
``.bag`` files, ROS 2 bag folders, PX4 ``.ulg`` files): each log goes through
the pipeline of ``imunav gins run LOG`` (:func:`gins_log`), into a result
folder of its own, and the summary table holds per log its sources, duration,
mounting, odometer scale and GNSS latency with their σ, the share of fixes
rejected and the final position σ.

Methods of :func:`calibrate_batch`:

``multiposition``
    static multi-position least squares (accelerometer T and b, gyro bias and
    g-sensitivity), :func:`imunav.calib.multiposition`;
``thesis``
    ``multiposition`` combined with the rate-table fit of the gyro matrix
    (needs ``<unit>_rate.<ext>``), the full model of Günhan 2014 (Y. Günhan, *Detection and
    compensation of inertial measurement unit errors* (in Turkish), MSc thesis, Hacettepe University, 2014);
``multipose``
    hand-placed poses without a reference (Tedaldi-style), :func:`imunav.calib.multipose`.
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from imunav import calib
from imunav.calib import ImuCalibration
from imunav.errors import ConfigError, InvalidInputError, NotStaticError
from imunav.files import atomic_path, jsonable, write_json
from imunav.ins.gins.logrun import LogRunOptions, run_log
from imunav.ins.gins.outputs import write_log_outputs
from imunav.io import read_imu, write_imu
from imunav.io.navlog import is_nav_log, read_nav_sources
from imunav.lab.montecarlo import Executor, run_batch, spawn_generators
from imunav.lab.report import check_spec, load_spec
from imunav.lab.report.batch import write_batch_html
from imunav.lab.report.catalog import (
    DISPLAY_UNIT,
    base_name,
    calibration_estimates,
    expand_spec,
    noise_estimates,
    to_display_value,
)
from imunav.lab.runfolder import RunFolder, trusted_files
from imunav.noise.allan import allan_deviation
from imunav.noise.fit import TERMS, fit_noise
from imunav.noise.static import require_static
from imunav.results import Result
from imunav.sim import (
    ImuErrorModel,
    hundred_position_profile,
    presets,
    rate_table_step_profile,
    read_segments,
    simulate_imu,
    static_profile,
)

__all__ = [
    "RECORDING_SUFFIXES",
    "BatchSummary",
    "find_units",
    "simulate_batch",
    "calibrate_unit",
    "calibrate_batch",
    "noise_unit",
    "noise_batch",
    "CALIBRATION_METHODS",
    "find_logs",
    "gins_log",
    "gins_batch",
    "GINS_COLUMNS",
]

RECORDING_SUFFIXES = (".npz", ".csv", ".parquet", ".h5", ".hdf5", ".mat")
CALIBRATION_METHODS = ("multiposition", "thesis", "multipose")


# ---------------------------------------------------------------------------
# folder layout
# ---------------------------------------------------------------------------


def _batch_files(folder: str | os.PathLike[str]) -> tuple[list[Path], list[str] | None]:
    """(unit recordings, trusted files or None).

    A run folder (written by :func:`simulate_batch`) is read through its verified manifest
    (:func:`imunav.lab.runfolder.trusted_files`): only the files it lists are used, and an incomplete run
    (killed, or still running) is refused.  A plain folder of recordings is used as it is, hidden files
    (temporary files of a killed writer) ignored.
    """

    d = Path(folder)
    if not d.is_dir():
        raise InvalidInputError(f"batch folder {d} does not exist or is not a folder")
    trusted = trusted_files(d)
    top = [p for p in trusted if p.parent == d] if trusted is not None else [
        p for p in d.iterdir() if p.is_file() and not p.name.startswith(".")]
    units = sorted(p for p in top if p.suffix.lower() in RECORDING_SUFFIXES and not p.stem.endswith("_rate"))
    if not units:
        raise InvalidInputError(
            f"batch folder {d} has no recordings (files ending in {', '.join(RECORDING_SUFFIXES)}); "
            "put one recording per unit there"
        )
    return units, None if trusted is None else [str(p.resolve()) for p in trusted]


def find_units(folder: str | os.PathLike[str]) -> list[Path]:
    """Recordings of the units in ``folder`` (sorted; ``*_rate.*`` companions and hidden files excluded).

    A folder written by :func:`simulate_batch` is read through its manifest: only the recordings it lists
    count, and a folder without a complete manifest (a killed run) is refused
    (:class:`~imunav.errors.RunFolderError`).

    Parameters
    ----------
    folder : str or os.PathLike
        The batch folder.

    Returns
    -------
    list of pathlib.Path
        One recording per unit, sorted by name.
    """
    return _batch_files(folder)[0]


def _usable(p: Path, trusted: Sequence[str] | None) -> bool:
    return p.is_file() and not p.name.startswith(".") and (trusted is None or str(p.resolve()) in trusted)


def _sidecar(rec: Path, suffix: str, shared: str, trusted: Sequence[str] | None = None) -> Path | None:
    own = rec.with_name(f"{rec.stem}{suffix}.json")
    if _usable(own, trusted):
        return own
    common = rec.parent / shared
    return common if _usable(common, trusted) else None


# ---------------------------------------------------------------------------
# simulation of a production batch
# ---------------------------------------------------------------------------


def _spread_model(model: Any, rng: np.random.Generator, spread: float, name: str) -> Any:
    """One unit: every deterministic parameter p -> p (1 + spread z), z ~ N(0, 1)."""

    def jitter(x: Any) -> np.ndarray:
        a = np.asarray(x, float)
        return a * (1.0 + spread * rng.standard_normal(a.shape))

    def triad(tri: Any) -> Any:
        T = np.asarray(tri.scale_misalignment, float)
        E = T - np.eye(3)  # S on the diagonal, M off it
        return replace(tri, bias=jitter(tri.bias), scale_misalignment=np.eye(3) + jitter(E))

    return model.replace(gyro=triad(model.gyro), accel=triad(model.accel),
                         g_sensitivity=jitter(model.g_sensitivity), name=name)


def _simulate_unit(item: tuple[int, str], *, out_dir: str, preset: str, spread: float, seed: int, n_units: int,
                   fs: float, dwell_s: float, transition_s: float, rate_table: bool, fmt: str,
                   static_s: float | None = None) -> dict[str, Any]:
    k, name = item
    rng = spawn_generators(seed, 1, k)[0]
    model = _spread_model(presets.get(preset), rng, spread, name)
    out = Path(out_dir)
    prof = static_profile(static_s, fs) if static_s else hundred_position_profile(fs, dwell_s, transition_s)
    data = simulate_imu(prof.trajectory, model, rng, earth_rate=False, transport_rate=False, gravity="constant")
    files = [write_imu(data.with_(meta={"unit": name, "preset": preset, "seed": seed}), out / f"{name}.{fmt}")]
    if rate_table and not static_s:
        rp = rate_table_step_profile(fs, dwell_s, transition_s)
        rd = simulate_imu(rp.trajectory, model, rng, earth_rate=False, transport_rate=False, gravity="constant")
        files.append(write_imu(rd.with_(meta={"unit": name}), out / f"{name}_rate.{fmt}"))
    (out / "truth").mkdir(exist_ok=True)
    write_json(out / "truth" / f"{name}.json", model.to_dict())
    return {"unit": name, "files": [str(f) for f in files], "samples": int(data.n)}


def simulate_batch(
    n_units: int,
    out_dir: str | os.PathLike[str],
    *,
    preset: str = "thesis_sim",
    spread: float = 0.2,
    rng: int = 0,
    fs: float = 50.0,
    dwell_s: float = 5.0,
    transition_s: float = 1.0,
    rate_table: bool = True,
    format: str = "npz",
    static_s: float | None = None,
    executor: Executor = "processes",
    n_workers: int | None = None,
    progress: bool = False,
    overwrite: bool = False,
) -> list[Path]:
    """Simulate a production batch of ``n_units`` IMUs (seeded, unit-to-unit spread).

    Unit ``k`` gets the generator :func:`imunav.lab.montecarlo.spawn_generators`
    ``(rng, ...)[k]``; its biases, scale factors, misalignments and
    g-sensitivities are the preset's, each multiplied by ``1 + spread·z``
    with ``z ~ N(0, 1)`` (the noise parameters stay the preset's).  Each unit
    runs the 100-position static test (and the thesis's 120-step rate-table
    test when ``rate_table``) at ``fs`` with ``dwell_s`` per position/step;
    with ``static_s`` each unit instead records one level static test of that
    length (for noise identification).

    ``out_dir`` is a run folder (:mod:`imunav.lab.runfolder`): new or empty, or
    (``overwrite=True``) a previous run that is cleared first, so that no unit
    of another run stays beside these; ``segments.json``, ``batch.json`` and
    last ``manifest.json`` are written after the units.

    Parameters
    ----------
    n_units : int
        Number of units, >= 1 (named ``unit_001`` ...).
    out_dir : str or os.PathLike
        The batch folder to write (a run folder).
    preset : str
        Name of the error-model preset (:mod:`imunav.sim.presets`) the units spread around.
    spread : float
        Relative 1-sigma unit-to-unit spread of the deterministic parameters, >= 0 (0.2 = 20 %).
    rng : int
        Master seed.
    fs : float
        Sample rate, Hz.
    dwell_s : float
        Duration of each static position / rate step, s.
    transition_s : float
        Duration of each transition between positions, s.
    rate_table : bool
        Also simulate the rate-table test (``<unit>_rate.<format>`` and ``rate_segments.json``).
    format : {"npz", "csv", "parquet", "hdf5", "mat"}
        File format of the recordings.
    static_s : float, optional
        Instead of the multi-position test, one level static record of this length, s (for noise batches).
    executor : {"serial", "processes", "dask"}
        Where the units are processed (:func:`imunav.lab.montecarlo.run_batch`).
    n_workers : int, optional
        Worker processes (default: number of cores).
    progress : bool
        Show a progress bar.
    overwrite : bool
        Clear a previous run in ``out_dir`` instead of refusing.

    Returns
    -------
    list of pathlib.Path
        The unit recordings (static tests) written to ``out_dir``.

    Raises
    ------
    InvalidInputError
        If ``n_units`` is not a positive integer, ``spread`` is negative or not finite, ``format`` is unknown
        or ``static_s`` is not positive.
    """

    if not isinstance(n_units, (int, np.integer)) or n_units < 1:
        raise InvalidInputError(f"n_units must be a positive integer, got {n_units!r}")
    if not (spread >= 0 and np.isfinite(spread)):
        raise InvalidInputError(f"spread must be a non-negative number, got {spread!r}")
    if format not in ("npz", "csv", "parquet", "hdf5", "mat"):
        raise InvalidInputError(f"format must be one of npz, csv, parquet, hdf5, mat; got {format!r}")
    presets.get(preset)  # fails early with the list of presets
    out = Path(out_dir)
    width = max(3, len(str(n_units)))
    names = [f"unit_{k + 1:0{width}d}" for k in range(n_units)]
    if static_s is not None and not (static_s > 0):
        raise InvalidInputError(f"static_s must be a positive duration in seconds, got {static_s!r}")

    params = {"n_units": n_units, "preset": preset, "spread": spread, "seed": int(rng), "fs": fs,
              "dwell_s": dwell_s, "transition_s": transition_s, "rate_table": rate_table and not static_s,
              "static_s": static_s, "format": format, "units": names}
    with RunFolder(out, "batch-simulate", seed=int(rng), parameters=params, overwrite=overwrite):
        res = run_batch(
            _simulate_unit, list(enumerate(names)), executor=executor, n_workers=n_workers, progress=progress,
            description="simulate units", out_dir=str(out), preset=preset, spread=float(spread), seed=int(rng),
            n_units=n_units, fs=float(fs), dwell_s=float(dwell_s), transition_s=float(transition_s),
            rate_table=bool(rate_table), fmt=format, static_s=None if not static_s else float(static_s),
        )
        for _name, r in zip(names, res):
            if isinstance(r, BaseException):
                raise r
        # the tables that describe the batch come after the units (a killed run leaves no batch.json)
        if not static_s:
            write_json(out / "segments.json", hundred_position_profile(fs, dwell_s, transition_s).to_dict())
        if rate_table and not static_s:
            write_json(out / "rate_segments.json", rate_table_step_profile(fs, dwell_s, transition_s).to_dict())
        write_json(out / "batch.json", params)
    return [out / f"{n}.{format}" for n in names]


# ---------------------------------------------------------------------------
# summary
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class BatchSummary(Result):
    """Per-unit results of a batch run.

    Attributes
    ----------
    kind : str
        ``"calibration"`` or ``"noise"``.
    table : pandas.DataFrame
        One row per unit: ``unit``, ``status`` (ok / error), ``passed`` (spec verdict, None without a spec),
        ``error`` and per parameter the value (display unit), ``<name>_se`` and ``<name>_err``
        (estimate − truth, when the truth is known).
    units : dict
        Per unit the full result dict (or ``{"error": message}``).
    spec_checks : dict
        Per unit the list of :class:`imunav.lab.report.SpecCheck` dicts.
    out_dir : pathlib.Path or None
        Folder with the per-unit files and the summary.
    seconds : float
        Wall-clock duration of the batch, s.
    """

    kind: str
    table: pd.DataFrame
    units: dict[str, dict[str, Any]]
    spec_checks: dict[str, list[dict[str, Any]]] = field(default_factory=dict)
    out_dir: Path | None = None
    seconds: float = 0.0

    @property
    def n_failed(self) -> int:
        return int((self.table["status"] != "ok").sum())

    @property
    def passed(self) -> bool | None:
        v = [p for p in self.table["passed"].tolist() if p is not None and not (isinstance(p, float) and np.isnan(p))]
        if self.n_failed:
            return False
        return None if not v else bool(all(v))

    def statistics(self) -> pd.DataFrame:
        """Mean, standard deviation, min and max over the units of every parameter column.

        Returns
        -------
        pandas.DataFrame
            One row per value / ``_err`` column (display units; ``_se`` columns left out), columns ``mean``,
            ``std`` (ddof=1), ``min``, ``max``.
        """
        num = self.table.drop(columns=[c for c in ("unit", "status", "passed", "error") if c in self.table])
        num = num[[c for c in num.columns if not c.endswith("_se")]].apply(pd.to_numeric, errors="coerce")
        return pd.DataFrame({"mean": num.mean(), "std": num.std(ddof=1), "min": num.min(), "max": num.max()})

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (the content of ``summary.json``).

        Returns
        -------
        dict
            ``kind``, ``n_units``, ``n_failed``, ``passed``, ``seconds``, ``table`` (one dict per row) and
            ``spec_checks``.
        """
        return {
            "kind": self.kind,
            "n_units": int(len(self.table)),
            "n_failed": self.n_failed,
            "passed": self.passed,
            "seconds": round(self.seconds, 3),
            "table": json.loads(self.table.to_json(orient="records")),
            "spec_checks": self.spec_checks,
        }


def _spec_rows(estimates: Mapping[str, tuple[float, float | None]], spec: Any) -> tuple[list[dict], bool | None]:
    if not spec:
        return [], None

    # a batch checks the parameter families it measures (a calibration batch ignores the noise lines
    # of a full datasheet); inside those families a limit without an estimate still fails
    fams = {base_name(n) for n in estimates}
    spec = {k: v for k, v in spec.items() if k in estimates or base_name(k) in fams or k in fams}
    checks = check_spec(estimates, expand_spec(spec, list(estimates)))
    rows = [c.to_dict() for c in checks if c.limit is not None]
    verdicts = [c.passed for c in checks if c.passed is not None]
    return rows, (None if not verdicts else all(verdicts))


def _summarise(kind: str, names: list[str], results: list[Any], spec: Any, out_dir: Path | None,
               seconds: float) -> BatchSummary:
    rows, units, checks = [], {}, {}
    for name, r in zip(names, results):
        if isinstance(r, BaseException):
            rows.append({"unit": name, "status": "error", "passed": False, "error": f"{type(r).__name__}: {r}"})
            units[name] = {"error": f"{type(r).__name__}: {r}"}
            continue
        est = r["estimates"]
        truth = r.get("truth") or {}
        spec_rows, verdict = _spec_rows({k: (v[0], v[1]) for k, v in est.items()}, spec)
        checks[name] = spec_rows
        row: dict[str, Any] = {"unit": name, "status": "ok", "passed": verdict}
        for k, (v, s) in est.items():
            row[k] = to_display_value(k, v)
            row[f"{k}_se"] = to_display_value(k, s)
            if k in truth:
                row[f"{k}_err"] = to_display_value(k, v - truth[k])
        rows.append(row)
        units[name] = r
    table = pd.DataFrame(rows)
    if "error" not in table:
        table["error"] = None
    return BatchSummary(kind, table, units, checks, out_dir, seconds)


def write_summary(summary: BatchSummary, out_dir: Path, title: str) -> dict[str, Path]:
    """``summary.csv``, ``summary.json`` and ``index.html`` (:func:`imunav.lab.report.batch.write_batch_html`).

    Parameters
    ----------
    summary : BatchSummary
        The batch's results.
    out_dir : pathlib.Path
        Folder to write into (existing).
    title : str
        Title of the HTML page.

    Returns
    -------
    dict
        ``{"csv", "json", "html"}`` -> path written.
    """

    paths = {}
    with atomic_path(out_dir / "summary.csv") as tmp:
        summary.table.to_csv(tmp, index=False)
    paths["csv"] = out_dir / "summary.csv"
    paths["json"] = write_json(out_dir / "summary.json", summary.to_dict())

    paths["html"] = write_batch_html(summary, out_dir, title)
    return paths


# ---------------------------------------------------------------------------
# calibration of a batch
# ---------------------------------------------------------------------------


def _truth_estimates(rec: Path, trusted: Sequence[str] | None = None) -> dict[str, float]:
    """True parameters of a simulated unit (``truth/<unit>.json``, if the manifest lists it), flat names, SI."""

    p = rec.parent / "truth" / f"{rec.stem}.json"
    if not _usable(p, trusted):
        return {}
    model = ImuErrorModel.from_dict(json.loads(p.read_text(encoding="utf-8")))
    cal = ImuCalibration.from_error_model(model)
    full = {k: np.ones((3, 3)) for k in ("accel_matrix", "gyro_matrix", "g_sensitivity")}
    full.update(accel_bias=np.ones(3), gyro_bias=np.ones(3))
    return {k: v for k, (v, _) in calibration_estimates(cal, full).items()}


def calibrate_unit(
    recording: str | os.PathLike[str],
    *,
    method: str = "multiposition",
    out_dir: str | os.PathLike[str] | None = None,
    read_options: Mapping[str, Any] | None = None,
    latitude: float | None = None,
    gravity: float | None = None,
    trusted: Sequence[str] | None = None,
) -> dict[str, Any]:
    """Calibrate one unit of a batch folder; writes ``<out_dir>/<unit>.json`` (the calibration).

    ``trusted``: the only files of the folder that may be used (its manifest, see :func:`find_units`),
    or None for a plain folder.

    Parameters
    ----------
    recording : str or os.PathLike
        The unit's static multi-position recording.
    method : {"multiposition", "thesis", "multipose"}
        Calibration method (module docstring).
    out_dir : str or os.PathLike, optional
        Where to write ``<unit>.json`` and ``<unit>_report.json`` (None: nothing written).
    read_options : Mapping, optional
        Keyword arguments of :func:`imunav.io.read_imu` (columns, units, ...).
    latitude : float, optional
        Geodetic latitude, rad (normal gravity and Earth-rate removal of the multi-position methods).
    gravity : float, optional
        Local gravity magnitude, m/s^2 (default: normal gravity at ``latitude``, else 9.80665).
    trusted : sequence of str, optional
        The only files of the folder that may be used (its manifest, see :func:`find_units`), or None for a
        plain folder.

    Returns
    -------
    dict
        ``{"unit", "method", "estimates": {name: (value_si, se_si)}, "truth": {name: value_si}`` (simulated
        batches, else empty) ``, "files", "residual_rms", "condition"}``.

    Raises
    ------
    ConfigError
        If ``method`` is unknown.
    InvalidInputError
        If the segment table (or, for ``thesis``, the rate-table test or its segments) is missing.
    """

    rec = Path(recording)
    if method not in CALIBRATION_METHODS:
        raise ConfigError(f"unknown calibration method {method!r}; choose from {', '.join(CALIBRATION_METHODS)}")
    opts = dict(read_options or {})
    data = read_imu(rec, **opts)
    if method in ("multiposition", "thesis"):
        seg = _sidecar(rec, "_segments", "segments.json", trusted)
        if seg is None:
            raise InvalidInputError(
                f"{rec}: no segment table for the multi-position test; put {rec.stem}_segments.json or "
                "segments.json (Profile.to_dict() format) next to the recordings"
            )
        res = calib.multiposition(data, read_segments(seg), latitude=latitude, gravity=gravity)
        if method == "thesis":
            rate = next((p for p in sorted(rec.parent.glob(f"{rec.stem}_rate.*"))
                         if p.suffix.lower() in RECORDING_SUFFIXES and _usable(p, trusted)), None)
            rseg = _sidecar(rec.with_name(f"{rec.stem}_rate{rec.suffix}"), "_segments", "rate_segments.json", trusted)
            if rate is None or rseg is None:
                raise InvalidInputError(
                    f"{rec}: method 'thesis' needs the rate-table test {rec.stem}_rate.<ext> and its segment table "
                    "rate_segments.json (or use --method multiposition)"
                )
            rres = calib.ratetable(read_imu(rate, **opts), read_segments(rseg), base=res.calibration,
                                   latitude=latitude, gravity=gravity)
            res = calib.combine(res, rres)
    else:
        res = calib.multipose(data.accel, data.gyro, data.fs, gravity=gravity or 9.80665,
                              raw_accel_unit="m/s^2", raw_gyro_unit="rad/s")
    cal = res.calibration
    files = {}
    if out_dir is not None:
        od = Path(out_dir)
        od.mkdir(parents=True, exist_ok=True)
        files["calibration"] = str(cal.save(od / f"{rec.stem}.json"))
        files["report"] = str(write_json(od / f"{rec.stem}_report.json", res.to_dict()))
    return {
        "unit": rec.stem,
        "method": res.method or method,
        "estimates": calibration_estimates(cal, res.stderr),
        "truth": _truth_estimates(rec, trusted),
        "files": files,
        "residual_rms": {k: np.sqrt(np.mean(np.asarray(v, float) ** 2, axis=0)).tolist() for k, v in res.residuals.items()},
        "condition": {k: float(v) for k, v in res.condition.items()},
    }


def _load_spec(spec: Any) -> Any:
    """The limits of a batch: a spec whose parameter a batch never estimates is refused, listing the known ones."""
    if spec is None:
        return None
    limits = spec if isinstance(spec, Mapping) and all(hasattr(v, "max_si") for v in spec.values()) else load_spec(spec)
    unknown = sorted(n for n in limits if base_name(n) not in DISPLAY_UNIT)
    if unknown:
        raise ConfigError(f"{spec if isinstance(spec, (str, os.PathLike)) else 'spec'}: no batch estimates "
                          f"{', '.join(unknown)}; the parameters are {', '.join(sorted(DISPLAY_UNIT))} "
                          "(with _x / _y / _z for one axis)")
    return limits


def calibrate_batch(
    folder: str | os.PathLike[str],
    *,
    method: str = "multiposition",
    out_dir: str | os.PathLike[str] | None = None,
    spec: Any = None,
    read_options: Mapping[str, Any] | None = None,
    latitude: float | None = None,
    gravity: float | None = None,
    executor: Executor = "processes",
    n_workers: int | None = None,
    address: str | None = None,
    progress: bool = False,
    overwrite: bool = False,
) -> BatchSummary:
    """Calibrate every unit of a batch folder in parallel.

    Writes ``<unit>.json`` (calibration), ``<unit>_report.json`` (parameters,
    standard errors, residuals), ``summary.csv``, ``summary.json`` and
    ``index.html`` to ``out_dir`` (default ``<folder>/calibration``).  A unit
    that fails (bad file, missing segments, degenerate design) is reported in
    the table with its error; the others are still processed.

    A batch folder written by :func:`simulate_batch` is read through its
    manifest (only the files it lists, checked against their SHA-256; a killed
    run is refused).  ``out_dir`` is a run folder of its own
    (:mod:`imunav.lab.runfolder`; ``overwrite`` clears a previous one).

    Parameters
    ----------
    folder : str or os.PathLike
        The batch folder.
    method : {"multiposition", "thesis", "multipose"}
        Calibration method (module docstring).
    out_dir : str or os.PathLike, optional
        Output run folder (default ``<folder>/calibration``).
    spec : str, os.PathLike, Mapping or None
        Datasheet limits: a spec TOML file or table (:func:`imunav.lab.report.load_spec`), or parsed limits.
    read_options : Mapping, optional
        Keyword arguments of :func:`imunav.io.read_imu` (columns, units, ...).
    latitude : float, optional
        Geodetic latitude, rad (as in :func:`calibrate_unit`).
    gravity : float, optional
        Local gravity magnitude, m/s^2 (as in :func:`calibrate_unit`).
    executor : {"serial", "processes", "dask"}
        Where the units are processed (:func:`imunav.lab.montecarlo.run_batch`).
    n_workers : int, optional
        Worker processes (default: number of cores).
    address : str, optional
        Dask scheduler address (Dask executor only; None: a local cluster).
    progress : bool
        Show a progress bar.
    overwrite : bool
        Clear a previous run in ``out_dir`` instead of refusing.

    Returns
    -------
    BatchSummary
        One row per unit (also written as ``summary.csv`` / ``summary.json``).

    Raises
    ------
    ConfigError
        If ``method`` is unknown.
    """

    if method not in CALIBRATION_METHODS:
        raise ConfigError(f"unknown calibration method {method!r}; choose from {', '.join(CALIBRATION_METHODS)}")
    limits = _load_spec(spec)
    units, trusted = _batch_files(folder)
    od = Path(out_dir) if out_dir is not None else Path(folder) / "calibration"
    params = {"folder": str(folder), "method": method, "latitude": latitude, "gravity": gravity,
              "read_options": dict(read_options or {}), "spec": str(spec) if isinstance(spec, (str, Path)) else None}
    with RunFolder(od, "batch-calibrate", parameters=params, overwrite=overwrite, inputs=[*units, _spec_path(spec)]):
        t0 = time.perf_counter()
        res = run_batch(calibrate_unit, [str(u) for u in units], executor=executor, n_workers=n_workers,
                        address=address, progress=progress, description=f"calibrate ({method})", method=method,
                        out_dir=str(od), read_options=dict(read_options or {}), latitude=latitude, gravity=gravity,
                        trusted=trusted)
        summary = _summarise("calibration", [u.stem for u in units], res, limits, od, time.perf_counter() - t0)
        write_summary(summary, od, f"Batch calibration ({method}) of {Path(folder).name}")
    return summary


def _spec_path(spec: Any) -> Path | None:
    return Path(spec) if isinstance(spec, (str, os.PathLike)) else None


# ---------------------------------------------------------------------------
# noise identification of a batch
# ---------------------------------------------------------------------------


def noise_unit(
    recording: str | os.PathLike[str],
    *,
    out_dir: str | os.PathLike[str] | None = None,
    read_options: Mapping[str, Any] | None = None,
    terms: Sequence[str] = ("Q", "N", "B", "K", "R"),
    force: bool = False,
) -> dict[str, Any]:
    """Allan-variance noise identification of one static recording (gyro and accelerometer).

    The recording must be static (:func:`imunav.noise.require_static`: one pose, no rotation);
    otherwise :class:`~imunav.errors.NotStaticError` unless ``force=True``.
    Writes ``<out_dir>/<unit>_noise.json`` (both :class:`imunav.noise.NoiseFit`) and
    returns ``{"unit", "estimates": {name: (value_si, se_si)}, "files"}``.

    Parameters
    ----------
    recording : str or os.PathLike
        The unit's static recording.
    out_dir : str or os.PathLike, optional
        Where to write ``<unit>_noise.json`` (None: nothing written).
    read_options : Mapping, optional
        Keyword arguments of :func:`imunav.io.read_imu` (columns, units, ...).
    terms : sequence of str
        Allan-variance terms to fit (IEEE Std 952-1997 Annex C): ``Q`` quantisation, ``N`` angle / velocity
        random walk, ``B`` bias instability, ``K`` rate random walk, ``R`` rate ramp.
    force : bool
        Analyse a recording that is not static.

    Returns
    -------
    dict
        ``{"unit", "estimates": {name: (value_si, se_si)}, "truth": {}, "files"}``.
    """

    rec = Path(recording)
    data = read_imu(rec, **dict(read_options or {}))
    require_static(data, force=force, where=str(rec))
    est: dict[str, tuple[float, float | None]] = {}
    fits = {}
    for sensor, x in (("gyro", data.gyro), ("accel", data.accel)):
        ad = allan_deviation(x, data.fs, units="rad/s" if sensor == "gyro" else "m/s^2")
        fit = fit_noise(ad, tuple(terms), quantity=sensor)
        fits[sensor] = fit.to_dict()
        est.update(noise_estimates(fit, sensor))
    files = {}
    if out_dir is not None:
        od = Path(out_dir)
        od.mkdir(parents=True, exist_ok=True)
        files["noise"] = str(write_json(od / f"{rec.stem}_noise.json",
                                      {"unit": rec.stem, "fs_hz": data.fs, "duration_s": data.duration, **fits}))
    return {"unit": rec.stem, "estimates": est, "truth": {}, "files": files}


def noise_batch(
    folder: str | os.PathLike[str],
    *,
    out_dir: str | os.PathLike[str] | None = None,
    spec: Any = None,
    read_options: Mapping[str, Any] | None = None,
    terms: Sequence[str] = ("Q", "N", "B", "K", "R"),
    executor: Executor = "processes",
    n_workers: int | None = None,
    address: str | None = None,
    progress: bool = False,
    force: bool = False,
    overwrite: bool = False,
) -> BatchSummary:
    """Noise identification (Allan variance + GLS term fit) of every unit's static recording, in parallel.

    Writes ``<unit>_noise.json``, ``summary.csv``, ``summary.json`` and
    ``index.html`` to ``out_dir`` (default ``<folder>/noise``).  A unit whose
    recording is not static (:func:`imunav.noise.require_static`) fails with the
    reason; when no unit is static (e.g. a folder of multi-position tests) the
    batch is refused with :class:`~imunav.errors.NotStaticError` before any
    result is written.  ``force=True`` analyses them anyway.  Folders are read
    and written as in :func:`calibrate_batch` (manifests, ``overwrite``).

    Parameters
    ----------
    folder : str or os.PathLike
        The batch folder.
    out_dir : str or os.PathLike, optional
        Output run folder (default ``<folder>/noise``).
    spec : str, os.PathLike, Mapping or None
        Datasheet limits (as in :func:`calibrate_batch`).
    read_options : Mapping, optional
        Keyword arguments of :func:`imunav.io.read_imu` (columns, units, ...).
    terms : sequence of str
        Allan-variance terms to fit (as in :func:`noise_unit`).
    executor : {"serial", "processes", "dask"}
        Where the units are processed (:func:`imunav.lab.montecarlo.run_batch`).
    n_workers : int, optional
        Worker processes (default: number of cores).
    address : str, optional
        Dask scheduler address (Dask executor only; None: a local cluster).
    progress : bool
        Show a progress bar.
    force : bool
        Analyse recordings that are not static.
    overwrite : bool
        Clear a previous run in ``out_dir`` instead of refusing.

    Returns
    -------
    BatchSummary
        One row per unit (also written as ``summary.csv`` / ``summary.json``).

    Raises
    ------
    NotStaticError
        If no unit's recording is static (and ``force`` is False).
    InvalidInputError
        If ``terms`` is empty or names an unknown term (before any unit is read).
    """

    bad = [t for t in terms if t not in TERMS]
    if bad or not terms:
        raise InvalidInputError(f"terms: unknown term(s) {bad} (command line: --terms); choose from {', '.join(TERMS)}"
                                if bad else f"terms is empty (command line: --terms); choose from {', '.join(TERMS)}")
    limits = _load_spec(spec)
    units, _ = _batch_files(folder)
    od = Path(out_dir) if out_dir is not None else Path(folder) / "noise"
    params = {"folder": str(folder), "terms": list(terms), "force": bool(force),
              "read_options": dict(read_options or {}), "spec": str(spec) if isinstance(spec, (str, Path)) else None}
    with RunFolder(od, "batch-noise", parameters=params, overwrite=overwrite, inputs=[*units, _spec_path(spec)]):
        t0 = time.perf_counter()
        res = run_batch(noise_unit, [str(u) for u in units], executor=executor, n_workers=n_workers,
                        address=address, progress=progress, description="noise", out_dir=str(od),
                        read_options=dict(read_options or {}), terms=tuple(terms), force=bool(force))
        moving = [r for r in res if isinstance(r, NotStaticError)]
        if moving and len(moving) == len(res):
            raise NotStaticError(f"no unit of {folder} is static ({len(moving)} of {len(res)} recordings moved); "
                                 f"first: {moving[0]}")
        summary = _summarise("noise", [u.stem for u in units], res, limits, od, time.perf_counter() - t0)
        write_summary(summary, od, f"Batch noise identification of {Path(folder).name}")
    return summary


# ---------------------------------------------------------------------------
# GNSS/INS on a folder of logs
# ---------------------------------------------------------------------------

#: Columns of a GNSS/INS batch's table after ``unit``, ``status``, ``passed``, ``error`` (SI unless the name says).
GINS_COLUMNS = (
    "log", "sources", "duration_s", "imu_samples", "gnss_used",
    "mounting_roll_deg", "mounting_pitch_deg", "mounting_yaw_deg",
    "mounting_roll_std_deg", "mounting_pitch_std_deg", "mounting_yaw_std_deg", "mounting_source",
    "odometer_scale", "odometer_scale_std", "gnss_time_offset_s", "gnss_time_offset_std_s",
    "gnss_rejected_share", "final_pos_std_n_m", "final_pos_std_e_m", "final_pos_std_d_m",
)


def find_logs(folder: str | os.PathLike[str]) -> list[Path]:
    """The logs of a folder: ROS 1 ``.bag`` files, ROS 2 bag folders (``metadata.yaml``), bare ROS 2 ``.db3`` /
    ``.mcap`` files, PX4 ``.ulg`` files and folders of KF-GINS text files (``sources.toml``,
    :func:`imunav.io.navlog.is_nav_log`), sorted; hidden entries and anything else (result folders, notes) are
    left out.  A file named like a log that is not one is listed:
    its run fails with the reason.

    Parameters
    ----------
    folder : str or os.PathLike
        The folder.

    Returns
    -------
    list of pathlib.Path
        The logs.

    Raises
    ------
    InvalidInputError
        If ``folder`` is not a folder or holds no log.
    """
    d = Path(folder)
    if not d.is_dir():
        raise InvalidInputError(f"log folder {d} does not exist or is not a folder")
    logs = sorted(p for p in d.iterdir() if not p.name.startswith(".")
                  and (p.is_dir() and is_nav_log(p)
                       or p.is_file() and p.suffix.lower() in (".bag", ".db3", ".mcap", ".ulg")))
    if not logs:
        raise InvalidInputError(f"log folder {d} holds no log (ROS 1 .bag files, ROS 2 bag folders with a "
                                "metadata.yaml, .db3 / .mcap files, PX4 .ulg files); put the logs there")
    return logs


def _log_names(logs: Sequence[Path]) -> list[str]:
    """Result folder of each log: its stem, or its whole name when two logs share a stem."""
    stems = [p.stem if p.is_file() else p.name for p in logs]
    return [s if stems.count(s) == 1 else p.name for s, p in zip(stems, logs)]


def gins_log(
    log: str | os.PathLike[str],
    *,
    out_dir: str | os.PathLike[str],
    topics: Mapping[str, str | None] | None = None,
    options: LogRunOptions | None = None,
    plots: bool = True,
) -> dict[str, Any]:
    """One log through the pipeline of ``imunav gins run LOG``: :func:`imunav.io.navlog.read_nav_sources`,
    :func:`imunav.ins.gins.logrun.run_log`, :func:`imunav.ins.gins.outputs.write_log_outputs` into ``out_dir``.

    Parameters
    ----------
    log : str or os.PathLike
        A ROS 1 bag, a ROS 2 bag folder or a PX4 ULog.
    out_dir : str or os.PathLike
        The log's result folder (created).
    topics : mapping, optional
        Keyword arguments of :func:`~imunav.io.navlog.read_nav_sources` naming topics (``imu_topic``,
        ``gnss_topic``, ``odo_topic``, ``mag_topic``, ``baro_topic``); None entries are chosen automatically.
    options : LogRunOptions, optional
        Preset, mounting, lever arms, smoother (:class:`~imunav.ins.gins.logrun.LogRunOptions`).
    plots : bool
        Write the figures.

    Returns
    -------
    dict
        ``{"unit", "log", "folder", "summary"}``: the run's ``summary.json`` content.
    """
    sources = read_nav_sources(log, **{k: v for k, v in dict(topics or {}).items() if v is not None})
    run = run_log(sources, options)
    summary = write_log_outputs(out_dir, run, sources, plots=plots)
    return {"unit": Path(out_dir).name, "log": os.fspath(log), "folder": os.fspath(out_dir), "summary": summary}


def _gins_row(name: str, log: Path, r: Any) -> dict[str, Any]:
    """The table row of one log: the values of its ``summary.json`` (the odometer scale as the factor, 1 + k)."""
    row: dict[str, Any] = {"unit": name, "status": "ok", "passed": None, "error": None, "log": str(log)}
    if isinstance(r, BaseException):
        row.update(status="error", passed=False, error=f"{type(r).__name__}: {r}")
        return row
    s = r["summary"]
    src = s["sources"]["sources"]
    row["sources"] = "; ".join(
        f"{role} {v['topic']} ({v['used']}" + (f" at {v['rate_hz']:.4g} Hz)" if v["rate_hz"] else ")")
        for role, v in src.items())
    m = s["mounting"]
    odo, lat = s["odometer_scale"], s["gnss_time_offset_s"]
    rej = s["gnss_rejected"]["share"]
    row.update({
        "duration_s": s["duration_s"], "imu_samples": s["imu_samples"], "gnss_used": s.get("gnss_used", 0),
        "mounting_roll_deg": m["roll_deg"], "mounting_pitch_deg": m["pitch_deg"], "mounting_yaw_deg": m["yaw_deg"],
        "mounting_roll_std_deg": m["std_deg"][0], "mounting_pitch_std_deg": m["std_deg"][1],
        "mounting_yaw_std_deg": m["std_deg"][2], "mounting_source": m["source"],
        "odometer_scale": None if odo is None else 1.0 + odo["value"],
        "odometer_scale_std": None if odo is None else odo["std"],
        "gnss_time_offset_s": None if lat is None else lat["value"],
        "gnss_time_offset_std_s": None if lat is None else lat["std"],
        "gnss_rejected_share": rej,
        "final_pos_std_n_m": s["final_position_std_m"][0], "final_pos_std_e_m": s["final_position_std_m"][1],
        "final_pos_std_d_m": s["final_position_std_m"][2],
    })
    return row


def _markdown_table(table: pd.DataFrame, title: str) -> str:
    """``summary.md``: the table in Markdown, numbers to 6 significant digits, empty cells for missing values."""
    cols = [c for c in table.columns if c != "passed"]

    def cell(v: Any) -> str:
        if v is None or (isinstance(v, float) and not np.isfinite(v)):
            return ""
        if isinstance(v, (float, np.floating)):
            return f"{v:.6g}"
        return str(v).replace("|", "\\|")

    lines = [f"# {title}", "", "| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    lines += ["| " + " | ".join(cell(r[c]) for c in cols) + " |" for r in table.to_dict(orient="records")]
    return "\n".join(lines) + "\n"


def gins_batch(
    folder: str | os.PathLike[str],
    *,
    out_dir: str | os.PathLike[str] | None = None,
    topics: Mapping[str, str | None] | None = None,
    options: LogRunOptions | None = None,
    plots: bool = True,
    executor: Executor = "processes",
    n_workers: int | None = None,
    address: str | None = None,
    progress: bool = False,
    overwrite: bool = False,
) -> BatchSummary:
    """GNSS/INS on every log of a folder (:func:`find_logs`), in parallel, as ``imunav gins run LOG`` on each.

    Writes one result folder per log (``<out_dir>/<log stem>/``: the ``.nav``, IMU errors, state σ,
    ``track.geojson``, ``summary.json`` and figures of :func:`gins_log`) and ``summary.csv``, ``summary.json``
    and ``summary.md`` (one row per log, columns ``unit``, ``status``, ``passed`` (always None: no spec),
    ``error`` and :data:`GINS_COLUMNS`).  A log that fails (not a log, no IMU topic, too short ...) is a row
    with its error; the others are still processed.  ``out_dir`` is a run folder (:mod:`imunav.lab.runfolder`;
    ``overwrite`` clears a previous one).

    Parameters
    ----------
    folder : str or os.PathLike
        The folder of logs.
    out_dir : str or os.PathLike, optional
        Output run folder (default ``<folder>/gins``).
    topics : mapping, optional
        The topics, as in :func:`gins_log` (the same for every log).
    options : LogRunOptions, optional
        As in :func:`gins_log` (the same for every log).
    plots : bool
        Write each log's figures.
    executor : {"serial", "processes", "dask"}
        Where the logs are processed (:func:`imunav.lab.montecarlo.run_batch`).
    n_workers : int, optional
        Worker processes (default: number of cores).
    address : str, optional
        Dask scheduler address (Dask executor only; None: a local cluster).
    progress : bool
        Show a progress bar.
    overwrite : bool
        Clear a previous run in ``out_dir`` instead of refusing.

    Returns
    -------
    BatchSummary
        ``kind`` ``"gins"``, one row per log; ``units`` holds each log's ``summary.json`` content (or its error).

    Raises
    ------
    InvalidInputError
        If ``folder`` holds no log.
    """
    logs = find_logs(folder)
    names = _log_names(logs)
    od = Path(out_dir) if out_dir is not None else Path(folder) / "gins"
    opts = options or LogRunOptions()
    params = {"folder": str(folder), "topics": {k: v for k, v in dict(topics or {}).items() if v is not None},
              "options": jsonable(asdict(opts)), "plots": bool(plots)}
    with RunFolder(od, "batch-gins", parameters=params, overwrite=overwrite,
                   inputs=[p for p in logs if p.is_file()]):
        t0 = time.perf_counter()
        items = [(str(p), str(od / n)) for p, n in zip(logs, names)]
        out = run_batch(_gins_item, items, executor=executor, n_workers=n_workers, address=address,
                        progress=progress, description="gins", topics=dict(topics or {}), options=opts,
                        plots=bool(plots))
        rows = [_gins_row(n, p, r) for n, p, r in zip(names, logs, out)]
        table = pd.DataFrame(rows, columns=["unit", "status", "passed", "error", *GINS_COLUMNS])
        table = table.astype(object).where(pd.notna(table), None)
        units = {n: (r["summary"] if not isinstance(r, BaseException) else {"error": f"{type(r).__name__}: {r}"})
                 for n, r in zip(names, out)}
        summary = BatchSummary("gins", table, units, {}, od, time.perf_counter() - t0)
        with atomic_path(od / "summary.csv") as tmp:
            table.to_csv(tmp, index=False)
        write_json(od / "summary.json", summary.to_dict())
        with atomic_path(od / "summary.md") as tmp:
            tmp.write_text(_markdown_table(table, f"GNSS/INS on the logs of {Path(folder).name}"), encoding="utf-8")
    return summary


def _gins_item(item: tuple[str, str], **kw: Any) -> dict[str, Any]:
    """:func:`gins_log` on one ``(log, result folder)`` pair (the form :func:`run_batch` passes)."""
    return gins_log(item[0], out_dir=item[1], **kw)

