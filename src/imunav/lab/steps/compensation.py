"""Lab step: apply the calibration to a fresh recording and check the residual errors.

The calibration is the one the calibration step left in ``ctx.artifacts``
(``"calibration_result"``, a :class:`imunav.calib.CalibrationResult`, or
``"calibration"``, an :class:`imunav.calib.ImuCalibration` with standard errors); without one this step estimates it
itself: the thesis method (100-position static test + 120-step rate table,
:func:`imunav.calib.multiposition`, :func:`imunav.calib.ratetable`,
:func:`imunav.calib.combine`) on the virtual IMU, or the method that fits the
real recordings (multi-position with its segment table, else Tedaldi
multi-pose).

Virtual IMU: a *validation* recording is simulated with the same true IMU and
new random streams (``positions`` random attitudes with ``dwell_s`` each,
then ``rate_steps`` constant rates about the body axes).  After
compensation (eqs. 21/22 of Günhan 2014,
``f = T_a⁻¹(ã − b_a)``, ``ω = T_g⁻¹(ω̃ − b_g − G f)``) the error of each
segment mean, with the realised stochastic part of the simulation (bias
instability and white noise, known exactly) removed, is what the calibration
error leaves.  To first order it is ``δb + δT x`` (+ ``δG f`` for the gyro),
so its predicted standard deviation from the calibration's standard errors
is ``σ_i² = σ_b,i² + Σ_j σ_T,ij² x_j²`` (+ ``Σ_j σ_G,ij² f_j²``).  The step
passes when the normalised errors ``z = error / σ`` have an RMS between 0.5
and 2 for both sensors (the reported uncertainty is realistic) and the
residual errors are at least 10× below the raw ones.

Real recordings: the calibration is applied to every recording of the same
unit (``unit`` in ``[recordings.<name>]``); on each
static interval the magnitude of the compensated specific force must equal
local gravity and the gyro mean the (negligible) Earth rate.  The table
shows both before and after compensation.

Options (``[compensation]``): ``positions`` (12), ``dwell_s`` (10), ``rate_steps``
(6: ± ``rate_dps`` about x, y, z), ``rate_dps`` (100), ``fs`` (the
simulated tests' rate).  Artifacts set: ``compensation`` (dict of the
residual tables) and ``calibration`` when the step estimated it.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from imunav import calib
from imunav.calib import ImuCalibration
from imunav.errors import ConfigError
from imunav.files import atomic_path
from imunav.lab.report.catalog import calibration_estimates
from imunav.lab.report.lab import display_parameters, embed_png
from imunav.lab.steps._api import LabContext, StepResult, recordings_before
from imunav.sim import ideal_imu, multiposition_profile, rate_table_profile, simulate_imu
from imunav.timeseries import static_intervals
from imunav.units import DEG, G0

#: The report hook shows the parameters itself.
RENDERS_PARAMETERS = True
TITLE = "Compensation: calibration applied, residual errors vs reported uncertainty"

_FROM_STEP = "the calibration step's estimate"
_DEFAULTS = {"positions": 12, "dwell_s": 10.0, "rate_steps": 6, "rate_dps": 100.0, "fs": None, "trim_s": 1.0}


def _options(ctx: LabContext) -> dict[str, Any]:
    o = ctx.step_options(_DEFAULTS, positive=("dwell_s", "rate_dps", "trim_s"))
    for k in ("positions", "rate_steps"):
        if not isinstance(o[k], int) or o[k] < 0:
            raise ConfigError(f"[compensation] {k} must be a non-negative integer, got {o[k]!r}")
    if o["dwell_s"] <= 2 * o["trim_s"]:
        raise ConfigError(f"[compensation] dwell_s ({o['dwell_s']}) must exceed 2 trim_s ({2 * o['trim_s']})")
    return o


# ---------------------------------------------------------------------------
# calibration source
# ---------------------------------------------------------------------------


def _from_artifacts(ctx: LabContext) -> tuple[Any, dict] | None:
    # the calibration step leaves both the model and the full result (with standard errors)
    c = ctx.artifacts.get("calibration_result") or ctx.artifacts.get("calibration")
    if c is None:
        return None
    if hasattr(c, "calibration"):  # CalibrationResult
        return c.calibration, dict(c.stderr)
    return c, dict(getattr(c, "stderr", {}) or {})


def estimate_calibration(ctx: LabContext) -> tuple[Any, dict, str]:
    """The calibration from the artifacts, else estimated here from the lab's recordings.

    Order: the calibration step's ``calibration_result`` / ``calibration`` artifact; else the thesis method
    on the ``hundred_position`` (+ ``rate_table``) recordings with their segment tables; else Tedaldi
    multi-pose on a ``multipose`` session (Tedaldi, Pretto & Menegatti, "A robust and easy to implement
    method for IMU calibration without external equipments", ICRA 2014).

    Parameters
    ----------
    ctx : LabContext
        The lab's context (artifacts ``calibration_result``, ``calibration``, ``recordings``, ``profiles``,
        ``sim``, ``recording_specs``).

    Returns
    -------
    calibration : imunav.calib.ImuCalibration
        The calibration.
    stderr : dict
        Standard errors of its parameters, SI (same keys and shapes as the parameters).
    how : str
        Where it came from, in words (for the report).

    Raises
    ------
    ConfigError
        If there is no calibration and no recording to estimate one from.
    """

    got = _from_artifacts(ctx)
    if got is not None:
        return got[0], got[1], _FROM_STEP
    recs, profs = ctx.artifacts.get("recordings", {}), ctx.artifacts.get("profiles", {})
    sim = ctx.artifacts.get("sim", {})
    g, lat = sim.get("g"), (sim.get("lat") if sim.get("earth_rate", True) else None)
    specs = ctx.artifacts.get("recording_specs", {})
    if "hundred_position" in recs and "hundred_position" in profs:
        seg = profs["hundred_position"]
        seg = getattr(seg, "segments", seg)
        res = calib.multiposition(recs["hundred_position"], seg, gravity=g, latitude=lat)
        how = "multi-position least squares (100-position test)"
        if "rate_table" in recs and "rate_table" in profs:
            rseg = profs["rate_table"]
            rseg = getattr(rseg, "segments", rseg)
            rr = calib.ratetable(recs["rate_table"], rseg, base=res.calibration, gravity=g, latitude=lat)
            res = calib.combine(res, rr)
            how = "thesis method: 100-position static test + 120-step rate table"
        return res.calibration, dict(res.stderr), how
    if "multipose" in recs:
        d = recs["multipose"]
        sp = specs.get("multipose")
        res = calib.multipose(d.accel, d.gyro, d.fs, init_s=getattr(sp, "init_s", 30.0), wait_s=getattr(sp, "wait_s", 3.0),
                              gravity=(getattr(sp, "gravity", None) or G0), raw_accel_unit="m/s^2",
                              raw_gyro_unit="rad/s", strict=False)
        n = res.info.get("n_poses", res.info.get("poses", "?"))
        return res.calibration, dict(res.stderr), (
            f"Tedaldi multi-pose (no reference), {n} poses; weakly determined parameters keep their large "
            "standard errors")
    raise ConfigError(
        "compensation needs a calibration: run the calibration step first, or give a multiposition test "
        "(with its segments) or a multipose session in [recordings]"
    )


# ---------------------------------------------------------------------------
# virtual IMU validation
# ---------------------------------------------------------------------------


def _random_orientations(rng: np.random.Generator, k: int) -> np.ndarray:
    q = rng.standard_normal((k, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return q * np.sign(q[:, :1] + (q[:, :1] == 0))


def _predicted_sigma(stderr: dict, x: np.ndarray, f: np.ndarray | None, sensor: str) -> np.ndarray:
    """First-order σ of the compensated error of segment means at true input x (K, 3)."""
    sb = np.asarray(stderr.get(f"{sensor}_bias", np.zeros(3)), float)
    sT = np.asarray(stderr.get(f"{sensor}_matrix", np.zeros((3, 3))), float)
    var = sb[None, :] ** 2 + (x**2) @ (sT**2).T
    if f is not None and "g_sensitivity" in stderr:
        var = var + (f**2) @ (np.asarray(stderr["g_sensitivity"], float) ** 2).T
    return np.sqrt(var)


def _virtual(ctx: LabContext, cal: Any, stderr: dict, opts: dict) -> dict[str, Any]:
    model = ctx.artifacts["error_model"]
    sim = ctx.artifacts.get("sim", {})
    fs = float(opts["fs"] or sim.get("fs", 100.0))
    ideal_kw = dict(sim.get("ideal_kw", {"earth_rate": False, "transport_rate": False, "gravity": "constant"}))
    lat = sim.get("lat")
    rng = ctx.rng("validation")
    segs_out: dict[str, Any] = {}
    out: dict[str, Any] = {"accel": [], "gyro": []}
    profiles = []
    if opts["positions"]:
        profiles.append(("static", multiposition_profile(_random_orientations(rng, opts["positions"]), opts["dwell_s"],
                                                          fs, 2.0, lat=lat, h=sim.get("h", 0.0), name="validation_static")))
    if opts["rate_steps"]:
        k = opts["rate_steps"]
        axes = np.array([np.eye(3)[i % 3] for i in range(k)])
        rates = np.array([(1 if (i // 3) % 2 == 0 else -1) * opts["rate_dps"] * DEG for i in range(k)])
        profiles.append(("rate", rate_table_profile(rates, axes, opts["dwell_s"], fs, 2.0, lat=lat,
                                                    h=sim.get("h", 0.0), name="validation_rate")))
    Ta_hat, Tg_hat, G_hat = cal.accel_matrix, cal.gyro_matrix, cal.g_sensitivity
    rows = []
    for kind, prof in profiles:
        ideal = ideal_imu(prof.trajectory, lat=lat, **ideal_kw)
        data, truth = simulate_imu(prof.trajectory, model, ctx.rng("validation", kind), return_truth=True, lat=lat,
                                   **ideal_kw)
        f_c, w_c = cal.apply_arrays(data.accel, data.gyro)
        # the realised stochastic part (known exactly in a simulation), as the compensation maps it
        sa = truth.accel.bias - np.asarray(model.accel.bias) + truth.accel.white_noise
        sg = truth.gyro.bias - np.asarray(model.gyro.bias) + truth.gyro.white_noise
        na = np.linalg.solve(Ta_hat, sa.T).T
        ng = np.linalg.solve(Tg_hat, (sg - na @ G_hat.T).T).T
        seg = prof.segments.select("static" if kind == "static" else "rate")
        trim = int(round(opts["trim_s"] * fs))
        for j in range(len(seg.i_start)):
            i0, i1 = int(seg.i_start[j]) + trim, int(seg.i_stop[j]) - trim
            sl = slice(i0, i1)
            f_true = ideal.accel[sl].mean(axis=0)
            w_true = ideal.gyro[sl].mean(axis=0)
            raw_ea = data.accel[sl].mean(axis=0) - f_true
            raw_eg = data.gyro[sl].mean(axis=0) - w_true
            ea = (f_c[sl] - na[sl]).mean(axis=0) - f_true
            eg = (w_c[sl] - ng[sl]).mean(axis=0) - w_true
            out["accel"].append((ea, f_true, raw_ea))
            out["gyro"].append((eg, w_true, f_true, raw_eg))
            rows.append({"segment": f"{kind} {j + 1}", "kind": kind})
    ea = np.array([e for e, _, _ in out["accel"]])
    fa = np.array([f for _, f, _ in out["accel"]])
    raw_a = np.array([r for _, _, r in out["accel"]])
    eg = np.array([e for e, _, _, _ in out["gyro"]])
    wg = np.array([w for _, w, _, _ in out["gyro"]])
    fg = np.array([f for _, _, f, _ in out["gyro"]])
    raw_g = np.array([r for _, _, _, r in out["gyro"]])
    sa = _predicted_sigma(stderr, fa, None, "accel")
    sgp = _predicted_sigma(stderr, wg, fg, "gyro")
    with np.errstate(divide="ignore", invalid="ignore"):
        za, zg = ea / sa, eg / sgp
    for r, e1, s1, e2, s2, ra, rg in zip(rows, ea, sa, eg, sgp, raw_a, raw_g):
        r.update({
            "raw accel error |·| (mg)": float(np.linalg.norm(ra) / G0 * 1e3),
            "accel error x, y, z (µg)": ", ".join(f"{v / G0 * 1e6:.1f}" for v in e1),
            "predicted σ (µg)": ", ".join(f"{v / G0 * 1e6:.1f}" for v in s1),
            "raw gyro error |·| (deg/h)": float(np.linalg.norm(rg) / DEG * 3600),
            "gyro error x, y, z (deg/h)": ", ".join(f"{v / DEG * 3600:.3f}" for v in e2),
            "predicted σ (deg/h)": ", ".join(f"{v / DEG * 3600:.3f}" for v in s2),
        })
    segs_out.update(
        rows=rows, accel_error=ea, accel_sigma=sa, gyro_error=eg, gyro_sigma=sgp, raw_accel=raw_a, raw_gyro=raw_g,
        z_accel=za, z_gyro=zg,
    )
    return segs_out


def _calibrated_unit(ctx: LabContext) -> str | None:
    """The device whose tests gave the calibration (None: unknown, apply to all)."""
    specs = ctx.artifacts.get("recording_specs", {})
    for test in ("hundred_position", "multipose", "rate_table"):
        if test in specs:
            return specs[test].unit
    return None


def _rms(x: np.ndarray) -> float:
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    return float(np.sqrt(np.mean(x**2))) if x.size else float("nan")


def _real(ctx: LabContext, cal: Any, unit: str | None) -> dict[str, Any]:
    g = ctx.artifacts.get("sim", {}).get("g") or G0
    specs = ctx.artifacts.get("recording_specs", {})
    rows = []
    for name, d in ctx.artifacts.get("recordings", {}).items():
        if unit is not None and name in specs and specs[name].unit != unit:
            continue  # another device: its own calibration would be needed
        try:
            st = static_intervals(d, window_s=1.0, min_duration_s=2.0)
        except Exception:  # noqa: BLE001 - a recording without static parts is simply not checked
            continue
        f_c, w_c = cal.apply_arrays(d.accel, d.gyro)
        for a, b in zip(st.starts[:50], st.stops[:50]):
            raw_n = np.linalg.norm(d.accel[a:b].mean(axis=0))
            cn = np.linalg.norm(f_c[a:b].mean(axis=0))
            rows.append({"recording": name, "t (s)": round(float(d.t[a]), 2), "duration (s)": round(float(d.t[b - 1] - d.t[a]), 2),
                         "|f| − g raw (mg)": (raw_n - g) / G0 * 1e3, "|f| − g compensated (mg)": (cn - g) / G0 * 1e3,
                         "|ω| raw (deg/h)": float(np.linalg.norm(d.gyro[a:b].mean(axis=0)) / DEG * 3600),
                         "|ω| compensated (deg/h)": float(np.linalg.norm(w_c[a:b].mean(axis=0)) / DEG * 3600)})
    return {"rows": rows}


def requires(lab: Any, earlier: Sequence[str]) -> list[str]:
    """The earlier steps this step takes its inputs from, checked before the lab runs (the order of
    :func:`estimate_calibration`).

    Parameters
    ----------
    lab : imunav.lab.config.LabConfig
        The typed lab definition.
    earlier : sequence of str
        The steps that run before this one.

    Returns
    -------
    list of str
        The ``calibration`` step when it runs before; else the step that makes the recordings the calibration is
        estimated from; with the virtual IMU also ``simulate_tests`` (its true model checks the residuals).

    Raises
    ------
    ConfigError
        When there will be no calibration and no recording to estimate one from.
    """
    made = recordings_before(lab, earlier)
    truth = ["simulate_tests"] if "simulate_tests" in earlier else []
    if "calibration" in earlier:
        return ["calibration", *truth]
    for test in ("hundred_position", "multipose"):
        if test in made:
            return sorted({made[test], made.get("rate_table", made[test]), *truth})
    raise ConfigError(
        "[compensation] needs a calibration: run the calibration step before it, or give a multiposition test "
        "(with its segments) or a multipose session in [recordings]")


def run(ctx: LabContext) -> StepResult:
    """Run the step: see the module docstring for what it computes, its options, artifacts and files.

    Parameters
    ----------
    ctx : LabContext
        The lab's context: the step's option table ``ctx.options`` (``[compensation]``), the artifacts it reads and
        sets, the report folder.

    Returns
    -------
    StepResult
        Residual errors against the reported uncertainty (virtual IMU) or gravity / Earth-rate checks per static interval (real recordings).
    """
    opts = _options(ctx)
    with ctx.task("compensation", total=2) as advance:
        cal, stderr, how = estimate_calibration(ctx)
        own = how != _FROM_STEP
        if own:
            ctx.artifacts["calibration"] = cal.with_(stderr=stderr) if not getattr(cal, "stderr", None) else cal
        advance()
        figures: list[Path] = []
        params = calibration_estimates(cal, stderr) if own else {}
        if "error_model" in ctx.artifacts and ctx.mode != "recordings":
            v = _virtual(ctx, cal, stderr, opts)
            rms_za, rms_zg = _rms(v["z_accel"]), _rms(v["z_gyro"])
            ratio_a = _rms(v["accel_error"]) / max(_rms(v["raw_accel"]), 1e-300)
            ratio_g = _rms(v["gyro_error"]) / max(_rms(v["raw_gyro"]), 1e-300)
            passed = bool(0.5 <= rms_za <= 2.0 and 0.5 <= rms_zg <= 2.0 and ratio_a < 0.1 and ratio_g < 0.1)
            summary = {
                "calibration": how, "segments": len(v["rows"]),
                "accel": {"rms_error_ug": _rms(v["accel_error"]) / G0 * 1e6, "rms_raw_error_mg": _rms(v["raw_accel"]) / G0 * 1e3,
                          "rms_z": rms_za, "max_abs_z": float(np.nanmax(np.abs(v["z_accel"])))},
                "gyro": {"rms_error_deg_h": _rms(v["gyro_error"]) / DEG * 3600, "rms_raw_error_deg_h": _rms(v["raw_gyro"]) / DEG * 3600,
                         "rms_z": rms_zg, "max_abs_z": float(np.nanmax(np.abs(v["z_gyro"])))},
                "acceptance": "RMS of error/σ in [0.5, 2] for both sensors and residual < 10 % of the raw error",
            }
            fig = ctx.path("figures", "compensation_z.png")
            _plot_z(v, fig)
            figures.append(fig)
            tables = [("Residual error of each validation segment after compensation (stochastic part removed) "
                       "and its predicted 1σ from the calibration's standard errors", v["rows"])]
            truth = None
            if own:
                tc = ImuCalibration.from_error_model(ctx.artifacts["error_model"])
                full = {k: np.ones((3, 3)) for k in ("accel_matrix", "gyro_matrix", "g_sensitivity")}
                full.update(accel_bias=np.ones(3), gyro_bias=np.ones(3))
                truth = {k: val for k, (val, _) in calibration_estimates(tc, full).items()}
            ctx.artifacts["compensation"] = {"rows": v["rows"], "truth": truth}
        else:
            unit = _calibrated_unit(ctx)
            r = _real(ctx, cal, unit)
            rows = r["rows"]
            comp = np.array([abs(x["|f| − g compensated (mg)"]) for x in rows]) if rows else np.array([])
            raw = np.array([abs(x["|f| − g raw (mg)"]) for x in rows]) if rows else np.array([])
            passed = None if not rows else bool(np.median(comp) <= np.median(raw))
            summary = {"calibration": how, "unit": unit, "static_intervals": len(rows),
                       "median_abs_norm_error_mg": {"raw": float(np.median(raw)) if rows else None,
                                                    "compensated": float(np.median(comp)) if rows else None}}
            tables = [("Static intervals of the recordings: specific-force magnitude vs local gravity and gyro "
                       "magnitude, before and after compensation", rows)]
            ctx.artifacts["compensation"] = {"rows": rows, "truth": None}
        advance()
    notes = [f"Calibration used: {how}.",
             "The compensation is f = T_a⁻¹(ã − b_a), ω = T_g⁻¹(ω̃ − b_g − G f) (Günhan 2014, eqs. 21-22)."]
    return StepResult(summary=summary, figures=figures, passed=passed, tables=tables, notes=notes, parameters=params)


def _plot_z(v: dict, path: Path) -> None:
    # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
    import matplotlib

    matplotlib.use("Agg")
    # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.4), sharey=True)
    for ax, key, title in ((axes[0], "z_accel", "accelerometer"), (axes[1], "z_gyro", "gyro")):
        z = np.asarray(v[key])
        k = np.arange(z.shape[0])
        for i, a in enumerate("xyz"):
            ax.plot(k + 0.15 * (i - 1), z[:, i], "o", ms=4, label=a)
        ax.axhspan(-1, 1, color="0.9", zorder=0, label="±1σ")
        for y in (-3, 3):
            ax.axhline(y, color="0.6", lw=0.8, ls="--")
        ax.set_title(f"{title}: residual error / predicted σ")
        ax.set_xlabel("validation segment")
        ax.legend(fontsize=7, ncol=4)
    axes[0].set_ylabel("z")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=90)
    plt.close(fig)


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
    s = result.summary
    if "accel" in s:
        section.table([
            {"sensor": "accelerometer", "raw error RMS": f"{s['accel']['rms_raw_error_mg']:.3g} mg",
             "residual RMS": f"{s['accel']['rms_error_ug']:.3g} µg", "RMS(error/σ)": s["accel"]["rms_z"],
             "max |error/σ|": s["accel"]["max_abs_z"]},
            {"sensor": "gyro", "raw error RMS": f"{s['gyro']['rms_raw_error_deg_h']:.4g} deg/h",
             "residual RMS": f"{s['gyro']['rms_error_deg_h']:.3g} deg/h", "RMS(error/σ)": s["gyro"]["rms_z"],
             "max |error/σ|": s["gyro"]["max_abs_z"]},
        ], "Residual errors vs reported uncertainty (" + s["acceptance"] + ")")
    if result.parameters:
        truth = ctx.artifacts.get("compensation", {}).get("truth")
        section.parameters(display_parameters(result.parameters, getattr(ctx.lab, "spec", None), truth),
                           "Calibration parameters estimated for the compensation (display units, ±1σ"
                           + (", truth of the virtual IMU)" if truth else ")"))
    for f in result.figures:
        embed_png(section, f, "Residual error of each validation segment divided by its predicted σ (≈ N(0, 1) when "
                              "the reported uncertainty is right)")
    for caption, rows in result.tables:
        section.table(rows, caption)
