"""Lab step: GNSS/INS navigation (loosely coupled error-state filter) on a configured IMU + GNSS set.

The set is either files, read as ``imunav gins run`` reads them (:mod:`imunav.ins.gins.setup`), or, without
files, a simulated land-vehicle drive (:func:`imunav.ins.gins.setup.simulate_drive`).  Not among the
default steps: name it in ``[lab] steps`` (``steps = ["gins"]``).

Options (TOML table ``[gins]``; paths relative to the lab TOML, or ``shared:<folder>/<file>``)::

    config = "drive/gins.toml"   # an imunav TOML (with imu and gnss) or a KF-GINS YAML (names its own files)
    imu = "drive/imu.txt"
    gnss = "drive/gnss.txt"
    truth = "drive/truth.nav"    # optional: RMSE, error figure, initial state when the TOML has no [init]
    odo = "drive/odo.txt"        # optional odometer (time s, speed m/s)
    states = 21                  # 15 or 21
    # without files: a simulated drive
    preset = "mems_adis16465"
    duration = 300               # s
    fs = 100                     # Hz
    seed = 1                     # default: drawn from the lab's seed

Acceptance (``passed``): the mean NIS of the GNSS position updates lies inside the two-sided 99 % band of the
mean of ``n`` independent χ²(3) variables (``n`` fixes used), and at least 99 % of the fixes pass the χ² gate.

Files written: ``data/gins_summary.json``, ``figures/gins_track.png``, ``figures/gins_imu_errors.png`` and,
with a truth, ``figures/gins_errors.png``.  Artifacts set: ``"gins"`` (the summary dict).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from imunav._quantiles import chi2_ppf
from imunav.errors import ConfigError
from imunav.files import write_json
from imunav.ins.gins.outputs import run_summary
from imunav.ins.gins.plot import write_gins_figures
from imunav.ins.gins.setup import load_inputs, run_setup, simulate_drive
from imunav.io.kfgins import NavTrack, read_kfgins_nav
from imunav.lab.steps._api import LabContext, StepResult, check_preset, check_samples
from imunav.lab.steps.recordings import resolve_path

TITLE = "GNSS/INS: loosely coupled error-state filter"

#: Option names of the [gins] table (checked when the lab definition is parsed).
OPTIONS = ("config", "imu", "gnss", "truth", "odo", "states", "preset", "duration", "fs", "seed")
_FILES = ("config", "imu", "gnss", "truth", "odo")


def _nis_band(n: int, dof: int = 3, p: float = 0.99) -> tuple[float, float]:
    """Two-sided ``p`` band of the mean of ``n`` independent χ²(dof) variables."""
    return float(chi2_ppf((1 - p) / 2, n * dof) / n), float(chi2_ppf((1 + p) / 2, n * dof) / n)


def _int(opts: dict[str, Any], key: str, default: int) -> int:
    v = opts.get(key, default)
    if isinstance(v, bool) or not isinstance(v, int):
        raise ConfigError(f"[gins] {key} must be an integer; got {v!r}")
    return v


def _positive(opts: dict[str, Any], key: str, default: float) -> float:
    v = opts.get(key, default)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
        raise ConfigError(f"[gins] {key} must be a positive number; got {v!r}")
    return float(v)


def _checked(ctx: LabContext) -> tuple[int | None, dict[str, Path]]:
    """(states, the files of the table resolved), the ``[gins]`` table checked whole."""
    opts = ctx.options
    unknown = set(opts) - set(OPTIONS)
    if unknown:
        raise ConfigError(f"[gins] unknown option(s) {sorted(unknown)}; known: {', '.join(OPTIONS)}")
    states = _int(opts, "states", 21) if "states" in opts or not any(k in opts for k in _FILES) else None
    if states is not None and states not in (15, 21):
        raise ConfigError(f"[gins] states must be 15 or 21; got {states!r}")
    base = Path(str(ctx.config.get("_base_dir", ".")))
    for k in _FILES:
        if k in opts and not isinstance(opts[k], str):
            raise ConfigError(f"[gins] {k} must be a file path (a string); got {opts[k]!r}")
    paths = {k: resolve_path(str(opts[k]), base, f"[gins] {k}") for k in _FILES if k in opts}
    sim_keys = sorted({"preset", "duration", "fs", "seed"} & set(opts))
    if paths and sim_keys:
        raise ConfigError(f"[gins] {sim_keys} simulate a drive; they do not go with files {sorted(paths)}")
    if not paths:
        preset = opts.get("preset", "mems_adis16465")
        check_preset("[gins]", preset)
        if "seed" in opts and _int(opts, "seed", 0) < 0:
            raise ConfigError(f"[gins] seed must be a non-negative integer; got {opts['seed']!r}")
        check_samples("[gins] duration x fs", "duration x fs",
                      _positive(opts, "duration", 300.0) * _positive(opts, "fs", 100.0))
    return states, paths


def check(ctx: LabContext) -> list[Path]:
    """Check the ``[gins]`` table whole, before any step runs (:func:`imunav.lab.config.parse_lab_config`).

    Parameters
    ----------
    ctx : LabContext
        A context holding the lab definition, ``step`` set to this step.

    Returns
    -------
    list of pathlib.Path
        The files the table names (config, imu, gnss, truth, odo), resolved.

    Raises
    ------
    ConfigError
        Naming the table and key: an unknown option, a missing file, files mixed with a simulated drive, an
        unknown ``preset``, a value out of its domain, or a drive longer than the lab's sample limit.
    """
    return list(_checked(ctx)[1].values())


def run(ctx: LabContext) -> StepResult:
    """Run the step: see the module docstring for what it computes, its options, artifacts and files.

    Parameters
    ----------
    ctx : LabContext
        The lab's context: the step's option table ``ctx.options`` (``[gins]``), the report folder.

    Returns
    -------
    StepResult
        Fixes used, GNSS NIS, RMSE against the truth when there is one; passed per the acceptance of the
        module docstring.

    Raises
    ------
    ConfigError
        If ``[gins]`` has an unknown option, mixes files with a simulated drive, or a file is missing.
    """
    opts = ctx.options
    states, paths = _checked(ctx)
    with ctx.task("GNSS/INS", total=2) as advance:
        if paths:
            inputs = load_inputs(paths.get("imu"), paths.get("gnss"), paths.get("config"), odometer=paths.get("odo"),
                                 states=states)
            imu, gnss, setup, odometer = inputs.imu, inputs.gnss, inputs.setup, inputs.odometer
            truth: NavTrack | None = read_kfgins_nav(paths["truth"]) if "truth" in paths else None
            if not setup.has_init and truth is not None:
                setup = setup.with_truth_init(truth, float(imu.t[0]))
            source = {k: str(v) for k, v in paths.items()}
        else:
            preset = str(opts.get("preset", "mems_adis16465"))
            seed = _int(opts, "seed", int(ctx.rng().integers(2**31)))
            drive = simulate_drive(_positive(opts, "duration", 300.0), preset=preset, fs=_positive(opts, "fs", 100.0),
                                   seed=seed, states=states)
            imu, gnss, setup, odometer, truth = drive.imu, drive.gnss, drive.setup, None, drive.truth_track()
            source = {"simulated": preset, "duration_s": float(drive.truth.duration), "seed": seed}
        advance()
        res = run_setup(imu, gnss, setup, odometer=odometer)
        advance()
    gs = res.gnss_summary()
    n = gs["gnss_used"]
    lo, hi = _nis_band(max(n, 1))
    nis_mean = float("nan") if gs["gnss_position_nis_mean"] is None else gs["gnss_position_nis_mean"]
    accepted = float("nan") if gs["gnss_accepted_share"] is None else gs["gnss_accepted_share"]
    summary: dict[str, Any] = {"source": source, **run_summary(res, setup, truth=truth), "nis_band_99": [lo, hi]}
    write_json(ctx.path("data", "gins_summary.json"), summary)
    figs = write_gins_figures(Path(ctx.out_dir) / "figures", res, gnss=gnss, truth=truth)
    ctx.artifacts["gins"] = summary
    passed = bool(n > 0 and lo <= nis_mean <= hi and accepted >= 0.99)
    notes = [f"Mean NIS of the {n} GNSS position updates {nis_mean:.3f} (99 % band of the mean of {n} χ²(3): "
             f"{lo:.3f}..{hi:.3f}); {100 * accepted:.1f} % of the fixes passed the χ² gate."]
    rows = []
    if "rmse" in summary:
        r = summary["rmse"]
        rows = [{"quantity": q, "N / roll": round(v[0], 4), "E / pitch": round(v[1], 4), "D / yaw": round(v[2], 4)}
                for q, v in (("position RMSE (m)", r["pos_ned_m"]), ("velocity RMSE (m/s)", r["vel_ned_mps"]),
                             ("attitude RMSE (deg)", r["att_rpy_deg"]))]
    return StepResult(summary, figs, passed, tables=[("Errors against the truth", rows)] if rows else [],
                      notes=notes)
