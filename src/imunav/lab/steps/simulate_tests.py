"""Lab step: simulate the calibration tests of Günhan (2014) with the virtual IMU.

Tests (Günhan 2014, §4.1 and Tables 5.1/5.2):

* ``hundred_position``: the reconstructed 100-position static test
  (22.5° steps, 30 s per position, minimum-jerk moves between positions);
* ``rate_table``: the exact 120-step ±250 °/s rate-table test (30 s per
  step, rotated axis vertical pointing up, IMU at the table centre);
* ``static_long``: a long level static record for the noise work (1 h).

All three use the same virtual IMU (preset ``thesis_sim`` by default: Tables
5.1 / 5.2, bias instability a Gauss–Markov process with T_c = 5 s, presets.THESIS_TC_S) with
independent random streams per test.  As in the thesis simulation, Earth rate
is off and gravity is the constant 9.80665 m/s² unless configured otherwise.

Options (TOML table ``[simulate_tests]``)::

    preset = "thesis_sim"      # or model = "path/to/model.toml" (relative to the lab TOML)
    fs = 100.0                 # Hz (the thesis logged at 1 kHz)
    dwell_s = 30.0             # per position / rate step
    transition_s = 2.0         # moves and rate ramps
    static_duration_s = 3600.0
    tests = ["hundred_position", "rate_table", "static_long"]
    earth_rate = false
    gravity = "constant"       # "normal", "constant" or m/s^2
    lat_deg = 39.87            # place (used for Earth rate / normal gravity)
    h_m = 938.0
    format = "npz"             # data file format (csv, parquet, hdf5, mat, npz)

Files written: ``data/<test>.<format>`` (recordings), ``data/<test>_segments.csv``
(segment tables), ``data/true_model.toml`` and ``.json`` (the injected
parameters), ``figures/<test>.png``.

Artifacts set (``ctx.artifacts``):

* ``"error_model"``: the true :class:`~imunav.sim.ImuErrorModel`;
* ``"sim"``: dict of the settings (fs, gravity value ``g`` in m/s²,
  ``earth_rate``, ``lat``/``h`` in rad/m, ``ideal_kw`` for :func:`~imunav.sim.ideal_imu`);
* ``"recordings"``: {test: ImuData}; ``"profiles"``: {test: Profile};
  ``"truth"``: {test: {"gyro_bias", "accel_bias"}} (realised total bias
  tracks b + bias instability + ..., (N, 3) SI, everything but white noise);
  ``"files"``: {test: Path}.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from imunav.earth import normal_gravity
from imunav.errors import ConfigError
from imunav.files import atomic_path, write_json
from imunav.io import write_imu
from imunav.lab.report.lab import embed_png
from imunav.lab.steps._api import SIMULATED_TESTS, LabContext, StepResult, check_preset, check_samples
from imunav.lab.steps.recordings import resolve_path
from imunav.sim import (
    ImuErrorModel,
    hundred_position_profile,
    presets,
    rate_table_step_profile,
    simulate_imu,
    static_profile,
)
from imunav.sim.plot import plot_test_recording
from imunav.units import DEG, G0

TITLE = "Simulated calibration tests (virtual IMU)"

_TESTS = SIMULATED_TESTS
_DEFAULTS: dict[str, Any] = {
    "preset": "thesis_sim",
    "model": None,
    "fs": 100.0,
    "dwell_s": 30.0,
    "transition_s": 2.0,
    "remount_s": 5.0,
    "static_duration_s": 3600.0,
    "tests": list(_TESTS),
    "earth_rate": False,
    "gravity": "constant",
    "lat_deg": 39.87,
    "h_m": 938.0,
    "format": "npz",
    "figures": True,
}


def _options(ctx: LabContext) -> dict[str, Any]:
    opts = ctx.step_options(_DEFAULTS, positive=("fs", "dwell_s", "transition_s", "remount_s", "static_duration_s"))
    bad = [t for t in opts["tests"] if t not in _TESTS]
    if bad:
        raise ConfigError(f"[simulate_tests] tests: unknown test(s) {bad}; choose from {list(_TESTS)}")
    if opts["model"]:  # relative to the lab definition's folder, like every path of the definition
        opts["model"] = resolve_path(str(opts["model"]), Path(str(ctx.config.get("_base_dir", "."))),
                                     "[simulate_tests] model")
    return opts


def check(ctx: LabContext) -> list[Path]:
    """Check the ``[simulate_tests]`` table whole, before any step runs (:func:`imunav.lab.config.parse_lab_config`).

    Parameters
    ----------
    ctx : LabContext
        A context holding the lab definition, ``step`` set to this step.

    Returns
    -------
    list of pathlib.Path
        The files the table names (the error ``model``).

    Raises
    ------
    ConfigError
        Naming the table and key: an unknown option or test, a value out of its domain, an unknown
        ``preset`` or ``gravity``, a missing ``model`` file, or a test longer than the lab's sample limit.
    """
    opts = _options(ctx)
    if opts["model"]:
        files = [opts["model"]]
    else:
        files = []
        check_preset("[simulate_tests]", opts["preset"])
    g = opts["gravity"]
    if not (g in ("normal", "constant") or (isinstance(g, (int, float)) and not isinstance(g, bool) and 0 < g < 100)):
        raise ConfigError(f"[simulate_tests] gravity must be 'normal', 'constant' or a number in (0, 100) m/s^2, "
                          f"got {g!r}")
    fs, move = float(opts["fs"]), float(opts["dwell_s"]) + float(opts["transition_s"])
    lengths = {"hundred_position": ("100 x (dwell_s + transition_s) x fs", 100 * move * fs),
               "rate_table": ("120 x (dwell_s + transition_s + remount_s) x fs",
                              120 * (move + float(opts["remount_s"])) * fs),
               "static_long": ("static_duration_s x fs", float(opts["static_duration_s"]) * fs)}
    for name in opts["tests"]:
        check_samples(f"[simulate_tests] {name}", lengths[name][0], lengths[name][1])
    return files


def _error_model(opts: dict[str, Any]) -> Any:

    if opts["model"]:
        return ImuErrorModel.from_toml(opts["model"])
    return presets.get(opts["preset"])


def _true_table(model: Any) -> list[dict]:
    """Injected parameters in the thesis's units (Tables 5.1 / 5.2)."""
    rows = []
    for sensor, tri, bunit, bscale in (("accel", model.accel, "g", 1 / G0), ("gyro", model.gyro, "°/s", 1 / DEG)):
        T = np.asarray(tri.scale_misalignment)
        for i, a in enumerate("xyz"):
            rows.append({"sensor": sensor, "parameter": f"S_{a}", "value": round((T[i, i] - 1) * 1e6, 9), "unit": "ppm"})
        for i, a in enumerate("xyz"):
            rows.append({"sensor": sensor, "parameter": f"B_{a}", "value": round(float(tri.bias[i]) * bscale, 12), "unit": bunit})
        for i, a in enumerate("xyz"):
            for j, b in enumerate("xyz"):
                if i != j:
                    rows.append({"sensor": sensor, "parameter": f"M_{a}{b}", "value": round(T[i, j] * 1e3, 12), "unit": "mrad"})
    G = np.asarray(model.g_sensitivity)
    for i, a in enumerate("xyz"):
        rows.append({"sensor": "gyro", "parameter": f"B_G{a}", "value": round(G[i, i] * G0 / DEG, 12), "unit": "°/s/g"})
    return rows


def run(ctx: LabContext) -> StepResult:
    """Run the step: see the module docstring for what it computes, its options, artifacts and files.

    Parameters
    ----------
    ctx : LabContext
        The lab's context: the step's option table ``ctx.options`` (``[simulate_tests]``), the artifacts it reads and
        sets, the report folder.

    Returns
    -------
    StepResult
        The tests simulated (samples, duration, files) and the injected parameters; no verdict.

    Raises
    ------
    ConfigError
        If ``[simulate_tests]`` has an unknown option or test, a non-positive duration or rate, or an
        invalid ``gravity``.
    """

    opts = _options(ctx)
    model = _error_model(opts)
    fs = float(opts["fs"])
    lat = float(opts["lat_deg"]) * DEG
    h = float(opts["h_m"])
    gravity = opts["gravity"]
    g_value = {"constant": G0}.get(gravity) if isinstance(gravity, str) else float(gravity)
    if gravity == "normal":

        g_value = normal_gravity(lat, h)
    elif isinstance(gravity, str) and gravity != "constant":
        raise ConfigError(f"[simulate_tests] gravity must be 'normal', 'constant' or a number, got {gravity!r}")
    ideal_kw = {"earth_rate": bool(opts["earth_rate"]), "transport_rate": False, "gravity": gravity}

    builders = {
        "hundred_position": lambda: hundred_position_profile(
            fs, opts["dwell_s"], opts["transition_s"], lat=lat, h=h),
        "rate_table": lambda: rate_table_step_profile(
            fs, opts["dwell_s"], opts["transition_s"], remount_s=opts["remount_s"], lat=lat, h=h),
        "static_long": lambda: static_profile(opts["static_duration_s"], fs, lat=lat, h=h, name="static_long"),
    }
    data_dir = ctx.path("data", "x").parent
    fig_dir = ctx.path("figures", "x").parent
    recs, profs, truths, files, figures = {}, {}, {}, {}, []
    tests_summary = {}
    with ctx.task("simulate calibration tests", total=len(opts["tests"])) as advance:
        for name in opts["tests"]:
            prof = builders[name]()
            data, truth = simulate_imu(prof.trajectory, model, ctx.rng(name), return_truth=True, **ideal_kw)
            data = data.with_(meta={**dict(data.meta or {}), "test": name, "preset": model.name, "seed": ctx.seed})
            path = write_imu(data, data_dir / f"{name}.{opts['format']}")
            prof.segments.write_csv(data_dir / f"{name}_segments.csv")
            recs[name], profs[name], files[name] = data, prof, Path(path)
            # keep only the realised total bias tracks (the full truth holds ten (N, 3) arrays)
            truths[name] = {"gyro_bias": truth.gyro.bias, "accel_bias": truth.accel.bias}
            s = prof.summary()
            tests_summary[name] = {
                "file": str(Path(path).relative_to(ctx.out_dir)),
                "samples": s["samples"],
                "fs_hz": round(s["fs_hz"], 9),
                "duration_s": round(s["duration_s"], 6),
                "segments": s["segments"],
            }
            if opts["figures"]:

                fig = plot_test_recording(data, prof.segments, title=f"{name} ({model.name})")
                fpath = fig_dir / f"{name}.png"
                with atomic_path(fpath) as tmp:
                    fig.savefig(tmp, dpi=90)
                # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
                import matplotlib.pyplot as plt

                plt.close(fig)
                figures.append(fpath)
            advance()

    model.to_toml(data_dir / "true_model.toml")
    write_json(data_dir / "true_model.json", model.to_dict())

    ctx.artifacts.update(
        error_model=model,
        sim={"fs": fs, "g": g_value, "gravity": gravity, "earth_rate": bool(opts["earth_rate"]),
             "lat": lat, "h": h, "ideal_kw": ideal_kw},
        recordings=recs, profiles=profs, truth=truths, files=files,
    )
    # check what the test designs promise (counts of the thesis's tests)
    checks = {}
    if "hundred_position" in profs:
        checks["hundred_position_static_segments"] = int(np.sum(profs["hundred_position"].segments.kind == "static"))
    if "rate_table" in profs:
        checks["rate_table_rate_steps"] = int(np.sum(profs["rate_table"].segments.kind == "rate"))
    passed = checks.get("hundred_position_static_segments", 100) == 100 and checks.get("rate_table_rate_steps", 120) == 120
    summary = {
        "preset": model.name,
        "source": model.source,
        "settings": {k: opts[k] for k in ("fs", "dwell_s", "transition_s", "static_duration_s", "earth_rate",
                                          "gravity", "lat_deg", "h_m", "format")},
        "g_m_s2": g_value,
        "tests": tests_summary,
        "checks": checks,
        "true_parameters": {f"{r['sensor']}.{r['parameter']}": r["value"] for r in _true_table(model)},
    }
    table = [{"test": k, **{kk: vv for kk, vv in v.items() if kk != "segments"},
              "segments": ", ".join(f"{n} {c}" for n, c in v["segments"].items())} for k, v in tests_summary.items()]
    return StepResult(
        summary=summary,
        figures=figures,
        passed=passed,
        tables=[("Simulated tests", table), ("Injected parameters (thesis units)", _true_table(model))],
        notes=[
            f"Virtual IMU '{model.name}': {model.source}",
            "Earth rate " + ("on" if opts["earth_rate"] else "off") + f", gravity {g_value:.6f} m/s², "
            f"sampled at {fs:g} Hz; each test has its own random stream (seed {ctx.seed}).",
        ],
    )


def report(section: Any, result: StepResult, ctx: LabContext) -> None:
    """HTML: test table, injected parameters, profile figures.

    Parameters
    ----------
    section : imunav.lab.report.html.Section
        The step's section.
    result : StepResult
        What :func:`run` returned.
    ctx : LabContext
        The lab's context (its ``[spec]`` and artifacts).
    """

    for caption, rows in result.tables:
        section.table(rows, caption)
    for f in result.figures:
        embed_png(section, f, f"{Path(f).stem}: specific force and rate (transitions shaded)")
