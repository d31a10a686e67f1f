"""Lab step: temperature model of bias and scale factor from a simulated thermal test.

The virtual IMU (preset ``consumer_mems`` by default: it has the datasheet's
bias and scale-factor temperature coefficients, ``B(T)``, ``S(T)``) is
calibrated at each temperature of a sweep, as in a thermal chamber
(Günhan 2014, ch. 6): at every temperature a 100-position static
test and a short rate-table test are simulated at that constant temperature
and calibrated (:func:`imunav.calib.multiposition` +
:func:`imunav.calib.ratetable` + :func:`imunav.calib.combine`, generalised
least squares with the characterised noise model).  The calibrations are
then fitted against temperature with :func:`imunav.calib.thermal_calibration`
(polynomial orders 1-5, leave-one-out order choice).

Check: over the swept range the fitted curves must follow the true
``B(T)``, ``S(T)`` of the virtual IMU within 4 σ, σ being the median
standard error of the per-temperature estimates (the fit averages them).

Options (``[temperature]``)::

    preset = "consumer_mems"
    temps_c = [-20, -10, 0, 10, 20, 30, 40, 50, 60]
    fs = 50.0
    dwell_s = 5.0            # per position / rate step
    rate_dps = [50.0, 100.0] # rate-table rates (both signs, about x, y, z)
    orders = [1, 2, 3]

Artifacts set: ``thermal`` (:class:`imunav.calib.ThermalResult`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from imunav import calib
from imunav.calib import thermal_calibration
from imunav.errors import ConfigError
from imunav.files import atomic_path
from imunav.lab.report.lab import embed_png
from imunav.lab.steps._api import LabContext, StepResult, check_preset, check_samples
from imunav.sim import hundred_position_profile, presets, rate_table_profile, simulate_imu
from imunav.units import DEG, G0

#: The report hook shows the parameters itself.
RENDERS_PARAMETERS = True
TITLE = "Temperature model: bias and scale factor vs temperature (thermal test on the virtual IMU)"

_DEFAULTS: dict[str, Any] = {
    "preset": "consumer_mems",
    "temps_c": [-20.0, -10.0, 0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0],
    "fs": 50.0,
    "dwell_s": 5.0,
    "transition_s": 1.0,
    "rate_dps": [50.0, 100.0],
    "orders": [1, 2, 3],
}
_PARAMS = ("accel_bias", "accel_scale", "gyro_bias", "gyro_scale")
_UNITS = {"accel_bias": ("mg", 1e3 / G0), "gyro_bias": ("deg/h", 3600 / DEG), "accel_scale": ("ppm", 1e6),
          "gyro_scale": ("ppm", 1e6)}


def _options(ctx: LabContext) -> dict[str, Any]:
    o = ctx.step_options(_DEFAULTS, positive=("fs", "dwell_s", "transition_s"))
    t = o["temps_c"]
    if not isinstance(t, list) or len(t) < 3 or not all(isinstance(x, (int, float)) for x in t):
        raise ConfigError(f"[temperature] temps_c must be a list of at least 3 temperatures (°C), got {t!r}")
    if len(set(t)) != len(t):
        raise ConfigError("[temperature] temps_c has repeated temperatures")
    if o["dwell_s"] < 4.0:
        raise ConfigError(f"[temperature] dwell_s must be at least 4 s (static detector), got {o['dwell_s']}")
    if not o["orders"] or max(o["orders"]) >= len(t) - 1:
        raise ConfigError(f"[temperature] orders {o['orders']} need more than max(order) + 1 temperatures ({len(t)} given)")
    return o


def check(ctx: LabContext) -> list[Path]:
    """Check the ``[temperature]`` table whole, before any step runs (:func:`imunav.lab.config.parse_lab_config`).

    Parameters
    ----------
    ctx : LabContext
        A context holding the lab definition, ``step`` set to this step.

    Returns
    -------
    list of pathlib.Path
        The files the table names (none).

    Raises
    ------
    ConfigError
        Naming the table and key: an unknown option, a value out of its domain, an unknown ``preset``, or
        a thermal test longer than the lab's sample limit.
    """
    o = _options(ctx)
    check_preset("[temperature]", o["preset"])
    n = len(o["temps_c"]) * 220 * (float(o["dwell_s"]) + float(o["transition_s"])) * float(o["fs"])
    check_samples("[temperature] temps_c", "temperatures x 220 x (dwell_s + transition_s) x fs", n)
    return []


def _true_curve(model: Any, param: str, axis: int, temp_c: np.ndarray) -> np.ndarray:
    sensor, kind = param.split("_")
    tri = getattr(model, sensor)
    dt = temp_c - model.temp_ref_c
    if kind == "bias":
        base, poly = float(np.asarray(tri.bias)[axis]), tri.bias_temp_poly
    else:
        base, poly = float(np.asarray(tri.scale_misalignment)[axis, axis]), tri.scale_temp_poly
    y = np.full_like(dt, base, dtype=float)
    if poly is not None:
        P = np.asarray(poly, float)
        for k in range(P.shape[0]):
            y = y + P[k, axis] * dt ** (k + 1)
    return y


def _calibrate_at(ctx: LabContext, model: Any, temp: float, opts: dict, profiles: tuple) -> tuple[Any, dict]:
    mp, rt = profiles
    kw = {"earth_rate": False, "transport_rate": False, "gravity": "constant"}
    d1 = simulate_imu(mp.trajectory, model, ctx.rng("static", f"{temp:g}"), temp_c=float(temp), **kw)
    d2 = simulate_imu(rt.trajectory, model, ctx.rng("rate", f"{temp:g}"), temp_c=float(temp), **kw)
    st = calib.multiposition(d1, mp.segments, gravity=G0, noise_model=model)
    rr = calib.ratetable(d2, rt.segments, base=st.calibration, gravity=G0, noise_model=model)
    res = calib.combine(st, rr)
    return res.calibration.with_(stderr=dict(res.stderr)), dict(res.stderr)


def run(ctx: LabContext) -> StepResult:
    """Run the step: see the module docstring for what it computes, its options, artifacts and files.

    Parameters
    ----------
    ctx : LabContext
        The lab's context: the step's option table ``ctx.options`` (``[temperature]``), the artifacts it reads and
        sets, the report folder.

    Returns
    -------
    StepResult
        Fitted bias and scale-factor temperature curves against the truth; passed when within 4 sigma.

    Raises
    ------
    ConfigError
        If the preset has no temperature terms.
    """
    opts = _options(ctx)
    model = presets.get(opts["preset"])
    if model.accel.bias_temp_poly is None and model.gyro.bias_temp_poly is None:
        raise ConfigError(f"[temperature] preset {opts['preset']!r} has no temperature terms; use e.g. consumer_mems")
    temps = np.asarray(opts["temps_c"], float)
    fs, dwell = float(opts["fs"]), float(opts["dwell_s"])
    mp = hundred_position_profile(fs, dwell, float(opts["transition_s"]))
    rates, axes = [], []
    for r in opts["rate_dps"]:
        for i in range(3):
            for sgn in (1, -1):
                rates.append(sgn * float(r) * DEG)
                axes.append(np.eye(3)[i])
    rt = rate_table_profile(np.array(rates), np.array(axes), dwell + 1.0, fs, float(opts["transition_s"]))
    cals, ses = [], []
    with ctx.task("thermal test", total=len(temps) + 1) as advance:
        for T in temps:
            c, se = _calibrate_at(ctx, model, T, opts, (mp, rt))
            cals.append(c)
            ses.append(se)
            advance()
        thermal = thermal_calibration(temps, cals, params=_PARAMS, orders=opts["orders"])
        advance()
    ctx.artifacts["thermal"] = thermal

    rows, params, checks = [], {}, []
    tt = np.linspace(temps.min(), temps.max(), 200)
    se_key = {"accel_bias": ("accel_bias", None), "gyro_bias": ("gyro_bias", None),
              "accel_scale": ("accel_matrix", "diag"), "gyro_scale": ("gyro_matrix", "diag")}
    for p in _PARAMS:
        unit, fac = _UNITS[p]
        key, diag = se_key[p]
        for i, a in enumerate("xyz"):
            fit = thermal.fits[p][i]
            s_per = np.array([np.asarray(s[key])[i, i] if diag else np.asarray(s[key])[i] for s in ses])
            sigma = float(np.median(s_per))
            dev = np.abs(fit.curve(tt) - _true_curve(model, p, i, tt))
            z = float(dev.max() / sigma) if sigma > 0 else float("inf")
            checks.append(z <= 4.0)
            best = fit.best
            c1 = float(best.curve.coeffs[1]) / best.curve.scale_c if best.curve.order >= 1 else 0.0
            s1 = float(best.stderr[1]) / best.curve.scale_c if best.curve.order >= 1 else float("nan")
            tc = float(best.curve.center_c)
            h = 1e-3
            true_slope = float((_true_curve(model, p, i, np.array([tc + h])) - _true_curve(model, p, i, np.array([tc - h])))[0] / (2 * h))
            name = f"{p}_tempco_{a}"
            params[name] = (c1, s1)
            rows.append({
                "parameter": f"{p} {a}", "slope unit": f"{unit}/°C", "curve unit": unit, "chosen order": fit.chosen_order,
                f"slope at {tc:g} °C": c1 * fac, "±1σ": s1 * fac, "true slope": true_slope * fac,
                "max |fit − truth|": float(dev.max() * fac), "σ per temperature": sigma * fac,
                "max dev / σ": z, "verdict": bool(z <= 4.0),
            })
    figs = _figures(ctx, thermal, model, temps, tt)
    passed = bool(all(checks))
    summary = {
        "preset": model.name, "temperatures_c": temps.tolist(), "orders_tried": list(opts["orders"]),
        "chosen_orders": {p: [f.chosen_order for f in thermal.fits[p]] for p in _PARAMS},
        "max_dev_over_sigma": float(max(r["max dev / σ"] for r in rows)),
        "acceptance": "fitted B(T), S(T) within 4σ of the truth over the swept range",
    }
    return StepResult(
        summary=summary, figures=figs, passed=passed,
        tables=[("Temperature coefficients (slope of the chosen curve at the centre of the range) and the "
                 "deviation of each fitted curve from the virtual IMU's true curve", rows)],
        notes=[f"Virtual IMU '{model.name}' calibrated at {len(temps)} temperatures from {temps.min():g} to "
               f"{temps.max():g} °C: 100-position static test ({dwell:g} s per position) and a "
               f"{len(rates)}-step rate table at each, at {fs:g} Hz; GLS with the characterised noise model. "
               "Polynomial orders chosen by leave-one-out cross-validation (imunav.calib.thermal_calibration)."],
        parameters=params,
    )


def _figures(ctx: LabContext, thermal: Any, model: Any, temps: np.ndarray, tt: np.ndarray) -> list[Path]:
    # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
    import matplotlib

    matplotlib.use("Agg")
    # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(10, 6.2))
    for ax, p in zip(axes.flat, _PARAMS):
        unit, fac = _UNITS[p]
        for i, (a, col) in enumerate(zip("xyz", ("C0", "C1", "C2"))):
            fit = thermal.fits[p][i]
            ref = _true_curve(model, p, i, np.array([model.temp_ref_c]))[0] if p.endswith("scale") else 0.0
            ax.plot(temps, (fit.values - ref) * fac, "o", color=col, ms=4, label=f"{a} estimates")
            ax.plot(tt, (fit.curve(tt) - ref) * fac, "-", color=col, lw=1.5, label=f"{a} fit (order {fit.chosen_order})")
            ax.plot(tt, (_true_curve(model, p, i, tt) - ref) * fac, "--", color="k", lw=0.8)
        ax.set_title(f"{p.replace('_', ' ')} [{unit}]" + (" (T_ii − T_ii(25 °C))" if p.endswith("scale") else ""),
                     fontsize=9)
        ax.set_xlabel("temperature, °C", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[0, 0].legend(fontsize=6, ncol=2)
    fig.suptitle("Estimates at each temperature (dots), fitted curves (lines), truth (dashed)", fontsize=9)
    fig.tight_layout()
    path = ctx.path("figures", "temperature.png")
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=90)
    plt.close(fig)
    return [path]


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
    for f in result.figures:
        embed_png(section, f, "Bias and scale factor against temperature: estimates, fitted curves and truth")
    for caption, rows in result.tables:
        section.table(rows, caption)
