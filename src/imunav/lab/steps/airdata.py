"""Lab step: the air-data / Doppler wind filter of Akgün (2002), reproduced and corrected.

Runs the thesis scenarios (``imunav.airdata.scenario``): the covariance
sequence against the thesis's P44 column, seeded Monte Carlo wind errors
against the difference loop, robust-filter rejection of outliers, detector
false-alarm rates (calibrated and thesis thresholds) and detection delays,
and writes the thesis's figures for one seeded run.

Options (TOML table ``[airdata]``)::

    runs = 100          # Monte Carlo runs
    p_false_alarm = 0.01
    robust_methods = ["gate2", "gate3", "nis", "isolate", "huber"]

Files written: ``data/airdata_thesis.json``, ``figures/airdata_wind.png``,
``figures/airdata_innovations.png``, ``figures/airdata_detectors.png``.
Artifacts set: ``"airdata"`` (the report dict).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from imunav.airdata import plot as P
from imunav.airdata.filter import BodyWindFilter
from imunav.airdata.scenario import WindScenario, simulate_wind_scenario, wind_scenario_report
from imunav.errors import ConfigError
from imunav.files import atomic_path, write_json
from imunav.filters import detect_faults
from imunav.lab.steps._api import LabContext, StepResult

TITLE = "Air data + Doppler radar: wind filter, robust filtering, fault detection"

#: Option names of the [airdata] table (checked when the lab definition is parsed).
OPTIONS = ("runs", "p_false_alarm", "robust_methods")


def run(ctx: LabContext) -> StepResult:
    """Run the step: see the module docstring for what it computes, its options, artifacts and files.

    Parameters
    ----------
    ctx : LabContext
        The lab's context: the step's option table ``ctx.options`` (``[airdata]``), the artifacts it reads and
        sets, the report folder.

    Returns
    -------
    StepResult
        Covariance check against the thesis, Monte Carlo wind errors, robust-filter and detector figures; passed per the acceptance of the module docstring.

    Raises
    ------
    ConfigError
        If ``[airdata]`` has an unknown option or ``robust_methods`` lacks ``gate2`` or ``nis``.
    """
    opts = ctx.options
    unknown = set(opts) - set(OPTIONS)
    if unknown:
        raise ConfigError(f"[airdata] unknown option(s) {sorted(unknown)}; known: runs, p_false_alarm, robust_methods")
    runs = int(opts.get("runs", 100))
    pfa = float(opts.get("p_false_alarm", 0.01))
    methods = tuple(opts.get("robust_methods", ("gate2", "gate3", "nis", "isolate", "huber")))
    if "gate2" not in methods or "nis" not in methods:
        raise ConfigError("[airdata] robust_methods must include 'gate2' and 'nis' (the thesis gate and the χ² gate)")
    seed = int(ctx.rng().integers(2**31))
    task = ctx.progress.add_task("air data: thesis scenarios", total=2)
    rep = wind_scenario_report(runs, seed, p_false_alarm=pfa, robust_methods=methods)
    ctx.progress.update(task, advance=1)
    data_dir = Path(ctx.out_dir) / "data"
    fig_dir = Path(ctx.out_dir) / "figures"
    data_dir.mkdir(parents=True, exist_ok=True)
    fig_dir.mkdir(parents=True, exist_ok=True)
    out = data_dir / "airdata_thesis.json"
    write_json(out, rep)

    d = simulate_wind_scenario(WindScenario(kind="variance"), seed)
    r = BodyWindFilter(robust="nis").run(d.z)
    det = detect_faults(r.normalized, 20, p_false_alarm=pfa, start=d.scenario.onset_row)
    figs = []
    for name, fig in (("wind", P.plot_wind(r, d)), ("innovations", P.plot_innovations(r)),
                      ("detectors", P.plot_detectors(det))):
        path = fig_dir / f"airdata_{name}.png"
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=90)
        figs.append(path)
    ctx.progress.update(task, advance=1)

    mc = rep["monte_carlo"]
    cov = rep["covariance_sequence"]
    p44_ok = bool(np.max(np.abs(np.subtract(cov["P44"], cov["P44_thesis"]))) <= 1e-4)
    wind_ok = max(mc["wind"]["kf_rms_per_axis"]) <= 0.2 and mc["wind"]["variance_ratio"] >= 10
    det_ok = all(mc["detection"]["variance"][k]["calibrated"]["detected_within_10"] >= 0.95
                 for k in ("alg1", "alg3", "nis", "cusum_var"))
    fa_ok = all(v["per_step"] <= 0.05 for v in mc["false_alarms"].values())
    nis = mc["robust"]["nis"]
    rob_ok = nis["rejected_anomalous"] >= 0.9 and abs(nis["nominal_rms_ratio_to_optimal"] - 1) <= 0.1
    summary = {
        "runs": runs,
        "P44": dict(zip(map(str, cov["iteration"]), np.round(cov["P44"], 5).tolist())),
        "wind_rms": mc["wind"]["kf_rms"],
        "difference_loop_rms": mc["wind"]["difference_loop_rms"],
        "variance_ratio": mc["wind"]["variance_ratio"],
        "robust_rejected_nis": nis["rejected_anomalous"],
        "robust_rejected_thesis_gate": mc["robust"]["gate2"]["rejected_anomalous"],
        "alg1_false_alarms_calibrated": mc["false_alarms"]["alg1"]["per_step"],
        "alg1_false_alarms_thesis_threshold": mc["false_alarms"]["alg1"]["per_step_thesis"],
        "checks": {"covariance_sequence": p44_ok, "wind": wind_ok, "variance_fault_within_10": det_ok,
                   "false_alarms_le_5pct": fa_ok, "robust": rob_ok},
    }
    ctx.artifacts["airdata"] = rep
    fa_rows = [{"detector": k, "threshold": round(v["threshold"], 2), "per step": round(v["per_step"], 4),
                "thesis threshold": round(v.get("thesis_threshold", float("nan")), 2) if "thesis_threshold" in v else "",
                "per step (thesis)": round(v["per_step_thesis"], 4) if "per_step_thesis" in v else ""}
               for k, v in mc["false_alarms"].items()]
    rob_rows = [{"method": k, **{kk: round(vv, 4) for kk, vv in v.items() if isinstance(vv, float)}}
                for k, v in mc["robust"].items()]
    return StepResult(summary, figs, all((p44_ok, wind_ok, det_ok, fa_ok, rob_ok)),
                      tables=[("Detector false alarms per step under nominal data", fa_rows),
                              ("Robust filters with ×15 outliers", rob_rows)],
                      notes=["Thesis iteration n is row n − 2; sign convention V_G = V_A + W, z = V_D − V_A."])
