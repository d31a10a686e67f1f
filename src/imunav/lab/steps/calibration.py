"""Lab step: deterministic calibration of the simulated 100-position and 120-step tests.

Reads the recordings of the ``simulate_tests`` step, estimates the thesis
model (Günhan 2014, §4.1.3: multi-position least squares for the
accelerometer and the gyro bias / g-sensitivity, rate-table least squares for
the gyro matrix) with parameter standard errors, and reports the spec's
"success" metric (Günhan 2014, Tables 5.3-5.4, mean over the 12 accelerometer and 15 gyro
parameters) against the injected truth, next to the thesis's single-run
figures (Tables 5.3/5.4: 99.15 % / 99.24 %).

Options (TOML table ``[calibration]``)::

    use_noise_model = true   # GLS with the characterised noise (white + GM drift);
                             # false: AR(1) feasible GLS from the residuals
    figures = true

Artifacts read: ``recordings``, ``profiles``, ``error_model``, ``sim``.
Artifacts set: ``"calibration"`` (the estimated :class:`~imunav.calib.ImuCalibration`),
``"calibration_result"`` (the :class:`~imunav.calib.CalibrationResult`).
Files written: ``data/calibration.json``, ``data/calibration_report.json``,
``figures/calibration_residuals.png``.

Verdict: passed when the mean success is at least 98.5 % (accelerometer) and
99.0 % (gyro) - about three run-to-run standard deviations below the means of
the 100-run benchmark at T_c = 10 s (benchmarks/bench_calib_montecarlo.py; the preset now uses 5 s, which only raises them) -
and at least 90 % of the 27 parameters lie within their reported 3σ.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from imunav.calib import (
    ImuCalibration,
    calibration_parameters,
    combine,
    multiposition,
    parameter_stderr,
    ratetable,
    success_percentages,
)
from imunav.calib.model import parameter_names
from imunav.calib.plot import plot_residuals, save_figure
from imunav.errors import ConfigError, InsufficientDataError
from imunav.files import write_json
from imunav.lab.steps._api import LabContext, StepResult, recordings_before
from imunav.units import DEG, G0

TITLE = "Deterministic calibration (100-position + 120-step tests)"

_DEFAULTS: dict[str, Any] = {"use_noise_model": True, "figures": True}
_UNITS = {"S": ("ppm", 1e6), "M": ("mrad", 1e3)}


def _rows(est: Any, truth: Any, stderr: dict, success: dict) -> list[dict]:
    pe, pt = calibration_parameters(est), calibration_parameters(truth)
    names = parameter_names()
    rows = []
    for key in ("accel_S", "accel_B", "accel_M", "gyro_S", "gyro_B", "gyro_BG", "gyro_M"):
        sensor, kind = key.split("_")
        if kind == "B":
            unit, f = ("g", 1 / G0) if sensor == "accel" else ("°/s", 1 / DEG)
        elif kind == "BG":
            unit, f = "°/s/g", G0 / DEG
        else:
            unit, f = _UNITS[kind]
        for i, n in enumerate(names[key]):
            rows.append({
                "sensor": sensor, "parameter": n, "unit": unit,
                "true": float(pt[key][i] * f), "estimated": float(pe[key][i] * f),
                "stderr": float(stderr[key][i] * f),
                "z": float((pe[key][i] - pt[key][i]) / stderr[key][i]),
                "success_%": float(success["per_parameter"][key][i]),
            })
    return rows


def requires(lab: Any, earlier: Sequence[str]) -> list[str]:
    """The earlier steps this step takes its inputs from, checked before the lab runs.

    Parameters
    ----------
    lab : imunav.lab.config.LabConfig
        The typed lab definition.
    earlier : sequence of str
        The steps that run before this one.

    Returns
    -------
    list of str
        ``simulate_tests`` (the two test recordings and the true error model).

    Raises
    ------
    ConfigError
        When no earlier ``simulate_tests`` step makes the ``hundred_position`` and ``rate_table`` recordings.
    """
    made = recordings_before(lab, earlier)
    missing = [t for t in ("hundred_position", "rate_table") if made.get(t) != "simulate_tests"]
    if missing:
        raise ConfigError(f"[calibration] needs the {' and '.join(repr(t) for t in missing)} recording(s) and the "
                          "true error model from the simulate_tests step: run simulate_tests before calibration, "
                          "with them in its tests")
    return ["simulate_tests"]


def run(ctx: LabContext) -> StepResult:
    """Run the step: see the module docstring for what it computes, its options, artifacts and files.

    Parameters
    ----------
    ctx : LabContext
        The lab's context: the step's option table ``ctx.options`` (``[calibration]``), the artifacts it reads and
        sets, the report folder.

    Returns
    -------
    StepResult
        Success metric per sensor, parameters within 3 sigma, estimated parameters with their standard errors.

    Raises
    ------
    InsufficientDataError
        If the ``hundred_position`` or ``rate_table`` recording of ``simulate_tests`` is missing.
    """

    opts = ctx.step_options(_DEFAULTS)
    recs = ctx.artifacts.get("recordings", {})
    profs = ctx.artifacts.get("profiles", {})
    if "hundred_position" not in recs or "rate_table" not in recs:
        raise InsufficientDataError(
            "calibration step needs the 'hundred_position' and 'rate_table' recordings of the simulate_tests step"
        )
    model = ctx.artifacts["error_model"]
    sim = ctx.artifacts.get("sim", {})
    lat = sim.get("lat") if sim.get("earth_rate") else None
    g = sim.get("g")
    nm = model if opts["use_noise_model"] else None
    with ctx.task("calibration: static + rate table", total=2) as advance:
        st = multiposition(recs["hundred_position"], profs["hundred_position"].segments, gravity=g, latitude=lat,
                           noise_model=nm)
        advance()
        rt = ratetable(recs["rate_table"], profs["rate_table"].segments, base=st.calibration, gravity=g,
                       latitude=lat, noise_model=nm)
        advance()
    res = combine(st, rt)
    truth = ImuCalibration.from_error_model(model)
    s = success_percentages(res.calibration, truth)
    se = parameter_stderr(res.stderr)
    rows = _rows(res.calibration, truth, se, s)
    within = float(np.mean([abs(r["z"]) <= 3 for r in rows]))
    res.calibration.save(ctx.path("data", "calibration.json"))
    write_json(ctx.path("data", "calibration_report.json"), res.to_dict())
    figures = []
    if opts["figures"]:
        figures.append(save_figure(plot_residuals(res), ctx.path("figures", "calibration_residuals.png")))
    ctx.artifacts.update(calibration=res.calibration, calibration_result=res)
    passed = s["accel_mean"] >= 98.5 and s["gyro_mean"] >= 99.0 and within >= 0.9
    summary = {
        "accel_mean_success_percent": s["accel_mean"],
        "gyro_mean_success_percent": s["gyro_mean"],
        "thesis_single_run_percent": {"accel": 99.151, "gyro": 99.237},
        "share_within_3_sigma": within,
        "condition": res.condition,
        "noise_model": "characterised (white + GM)" if nm is not None else "AR(1) from residuals",
    }
    return StepResult(
        summary=summary,
        figures=figures,
        passed=passed,
        tables=[("Estimated vs injected parameters (thesis units)", rows)],
        notes=[
            f"Mean success: accelerometer {s['accel_mean']:.3f} %, gyro {s['gyro_mean']:.3f} % "
            "(thesis single run 99.15 % / 99.24 %; the achievable value depends on the bias-instability "
            "correlation time, see the calibration benchmark).",
            f"{100 * within:.0f} % of the 27 parameters lie within their reported 3σ.",
        ],
    )
