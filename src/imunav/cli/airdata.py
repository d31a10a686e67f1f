"""``imunav airdata``: air-data / Doppler wind estimation (simulate, run, faults, thesis)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from types import SimpleNamespace
from typing import Optional

import numpy as np
import typer
from rich.table import Table

from imunav.cli._console import make_console
from imunav.cli._domains import Domain, parse_numbers
from imunav.cli._errors import check_figure_path, check_suffix, fail
from imunav.cli._lazy import lazy
from imunav.cli._progress import progress
from imunav.errors import FileFormatError, InvalidInputError
from imunav.files import atomic_path, check_outputs, write_json

P = lazy("imunav.airdata.plot")
_common = lazy("imunav.io._common")
airdata_filter = lazy("imunav.airdata.filter")
filters_faults = lazy("imunav.filters.faults")
flight = lazy("imunav.airdata.flight")
rotation = lazy("imunav.rotation")
scenario = lazy("imunav.airdata.scenario")

_HELP = """Air data + Doppler radar integration: wind-estimating Kalman filter, robust filtering, fault detection.

Example: imunav airdata thesis --runs 50 --json thesis.json
"""


def _write_atomic(path: Path, write) -> None:
    with atomic_path(path) as tmp:
        write(str(tmp))


def _write_json(path: Path, obj: dict) -> None:
    write_json(path, obj)


def _channels(text: Optional[str]) -> tuple[int, ...] | None:
    if text is None or text.strip().lower() in ("", "all"):
        return None

    return tuple(parse_numbers("--channels", text, Domain(integer=True, lo=0, hi=2), example="'all' or 0,2"))


_MAX_WIND = 150.0  # m/s


def _vec3(text: str, name: str) -> tuple[float, float, float]:
    v = tuple(parse_numbers(name, text, count=3, example="5,-2,0 (N,E,D)"))
    if math.hypot(*v) > _MAX_WIND:
        raise InvalidInputError(f"{name} {text}: each component must be finite and the wind at most {_MAX_WIND:g} m/s "
                                "(the strongest jet-stream winds are about 110 m/s)")
    return v  # type: ignore[return-value]


def _fail(exc: Exception) -> None:
    fail(exc)


airdata_app = typer.Typer(help=_HELP, no_args_is_help=True)


@airdata_app.command("simulate", help="""Simulate a flight (truth, air data, Doppler, attitude) or a thesis scenario and write an .npz file.

PROFILE is cruise, turns or manoeuvre (constant wind + Dryden turbulence, each sensor at its own rate),
or thesis (the thesis's 0.5 s / 1 kHz scenario; --kind nominal|outliers|variance|bias|drift|stuck).
--config reads a TOML scenario instead (see examples/airdata_flight.toml).

Example: imunav airdata simulate turns --duration 120 --wind 8,-12,0 --turbulence light --seed 1 --out flight.npz
""")
def simulate(
    profile: str = typer.Argument("turns", help="cruise | turns | manoeuvre | thesis"),
    out: Path = typer.Option(..., "--out", "-o", help="Output .npz file."),
    duration: float = typer.Option(600.0, "--duration", help="Flight duration, s."),
    tas: float = typer.Option(200.0, "--tas", help="True airspeed, m/s."),
    altitude: float = typer.Option(10000.0, "--altitude", help="Start altitude, m."),
    wind: str = typer.Option("8,-12,0", "--wind", help="Mean wind N,E,D (m/s, velocity of the air mass)."),
    turbulence: str = typer.Option("light", "--turbulence", help="none | light | moderate | severe"),
    rate_ads: float = typer.Option(50.0, "--rate-ads", help="Air-data rate, Hz."),
    rate_doppler: float = typer.Option(10.0, "--rate-doppler", help="Doppler rate, Hz."),
    kind: str = typer.Option("nominal", "--kind", help="Thesis scenario kind (profile thesis only)."),
    config: Optional[Path] = typer.Option(None, "--config", help="TOML file with a [flight] or [thesis] table "
                                          "(replaces the other scenario options)."),
    seed: int = typer.Option(0, "--seed", help="Random seed."),
    json_out: Optional[Path] = typer.Option(None, "--json", help="Also write a JSON summary here."),
) -> None:
    check_outputs([config], [out, json_out])

    check_suffix(out, "--out", (".npz",), "the simulated flight (NumPy archive)")

    try:
        loaded = None
        if config is not None:
            loaded = scenario.load_config(config)
            profile = "thesis" if isinstance(loaded, scenario.WindScenario) else loaded.profile
        if profile == "thesis":
            sc = loaded if loaded is not None else scenario.WindScenario(kind=kind)
            kind = sc.kind
            d = scenario.simulate_wind_scenario(sc, rng=seed)
            arrays = {k: getattr(d, k) for k in ("t", "x_true", "wind_true", "v_true", "v_ads", "v_doppler", "z",
                                                 "ads_noise", "anomaly")}
            meta = {"type": "thesis", "scenario": d.scenario.to_dict(), "seed": seed}
            summary = {"file": str(out), "type": "thesis", "kind": kind, "steps": int(d.t.size), "seed": seed}
        else:
            cfg = loaded if loaded is not None else flight.FlightConfig(
                profile=profile, duration=duration, tas=tas, altitude=altitude, wind_ned=_vec3(wind, "--wind"),
                turbulence=turbulence, rate_ads=rate_ads, rate_doppler=rate_doppler)
            f = flight.simulate_flight(cfg, rng=seed)
            arrays = {k: v for k, v in f.__dict__.items() if isinstance(v, np.ndarray)}
            meta = {"type": "flight", "config": cfg.to_dict(), "seed": seed}
            summary = {"file": str(out), "type": "flight", "profile": cfg.profile, "duration_s": cfg.duration,
                       "ads_samples": int(f.t_ads.size), "doppler_samples": int(f.t_doppler.size), "seed": seed}
    except InvalidInputError as exc:
        _fail(exc)
        return

    def w(tmp: str) -> None:
        with open(tmp, "wb") as fh:
            np.savez_compressed(fh, meta=np.array(json.dumps(meta)), **arrays)

    _write_atomic(out, w)
    if json_out is not None:
        _write_json(json_out, summary)
    typer.echo(json.dumps(summary))

@airdata_app.command("run", help="""Run the wind filter on a file written by `imunav airdata simulate`.

A thesis file runs the thesis's 6-state filter (optionally robust); a flight file runs the long-horizon
navigation-frame filter on the multi-rate ADS and Doppler data.  Errors against the truth in the file
are reported.

Example: imunav airdata run flight.npz --robust nis --json run.json
""")
def run(
    path: Path = typer.Argument(..., help="File from `imunav airdata simulate`."),
    robust: str = typer.Option("none", "--robust", help="none | gate | nis | isolate | huber"),
    gate_m: float = typer.Option(2.0, "--gate-m", help="Per-channel gate (robust gate)."),
    alpha: float = typer.Option(1e-3, "--alpha", help="Test level of the nis / isolate gates."),
    json_out: Optional[Path] = typer.Option(None, "--json", help="Write the summary as JSON here."),
    out: Optional[Path] = typer.Option(None, "--out", help="Write the estimates as .npz here."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Write a wind figure (.png) here."),
) -> None:
    check_outputs([path], [json_out, out, plot])

    check_suffix(out, "--out", (".npz",), "the estimates (NumPy archive)")

    check_figure_path(plot, "--plot")

    rb = None if robust == "none" else robust
    try:
        if not path.exists():
            raise FileFormatError(f"{path}: no such file; create one with `imunav airdata simulate`")

        with _common.wrap_read_errors(str(path), "an `imunav airdata simulate` .npz file"), open(path, "rb") as fh, \
                np.load(fh, allow_pickle=False) as z:
            if "meta" not in z:
                raise FileFormatError(f"{path}: not an `imunav airdata simulate` file (no 'meta' entry)")
            meta = json.loads(str(z["meta"]))
            data = {k: z[k] for k in z.files if k != "meta"}
        if meta["type"] == "thesis":
            r = airdata_filter.BodyWindFilter(robust=rb, gate_m=gate_m, alpha=alpha).run(data["z"], v_ads=data["v_ads"])
            k0 = airdata_filter.iteration_row(100)
            e = r.wind[k0:] - data["wind_true"][k0:]
            ed = data["z"][k0:] - data["wind_true"][k0:]
            summary = {"type": "thesis", "robust": robust, "wind_rms_per_axis": np.sqrt(np.mean(e**2, 0)).tolist(),
                       "difference_loop_rms_per_axis": np.sqrt(np.mean(ed**2, 0)).tolist(),
                       "rejected_samples": int((r.weights == 0).sum()),
                       "final_wind": r.wind[-1].tolist(), "true_wind": data["wind_true"][-1].tolist(),
                       "P44_final": float(r.cov_diag[-1, 3])}
            arrays = {"wind": r.wind, "P_diag": r.cov_diag, "normalized": r.normalized, "weights": r.weights}
        elif meta["type"] == "flight":
            r = airdata_filter.LongHorizonFilter(airdata_filter.LongHorizonConfig(robust=rb, alpha=alpha, gate_m=gate_m)).run(
                    data["t_ads"], data["v_ads_body"], data["t_doppler"], data["v_doppler_body"],
                    rotation.dcm_from_euler(data["euler_doppler"]), rotation.dcm_from_euler(data["euler_ads"]))
            wt = np.stack([np.interp(r.t, data["t"], data["wind_ned"][:, i]) for i in range(3)], 1)
            pt = np.stack([np.interp(r.t, data["t"], data["position_ned"][:, i]) for i in range(3)], 1)
            skip = min(r.t.size - 1, 100)
            e = r.wind[skip:] - wt[skip:]
            summary = {"type": "flight", "robust": robust, "epochs": int(r.t.size),
                       "wind_rms_per_axis": np.sqrt(np.mean(e**2, 0)).tolist(),
                       "wind_std_mean": r.wind_std[skip:].mean(0).tolist(),
                       "position_error_end": (r.position[-1] - pt[-1]).tolist(),
                       "position_std_end": r.position_std[-1].tolist(),
                       "rejected_samples": int((r.weights == 0).sum())}
            arrays = {"t": r.t, "wind": r.wind, "wind_std": r.wind_std, "position": r.position,
                      "normalized": r.normalized, "weights": r.weights}
        else:
            raise FileFormatError(f"{path}: unknown file type {meta.get('type')!r}")
    except (InvalidInputError, KeyError) as exc:
        _fail(exc if isinstance(exc, InvalidInputError) else FileFormatError(f"{path}: missing entry {exc}"))
        return
    if out is not None:
        with atomic_path(out) as tmp, open(tmp, "wb") as fh:
            np.savez_compressed(fh, **arrays)
    if plot is not None:
        # with the true wind the file holds (a simulated run)
        if meta["type"] == "thesis":
            fig = P.plot_wind(r, SimpleNamespace(wind_true=data["wind_true"]))
        else:
            fig = P.plot_long_horizon(r, SimpleNamespace(t=data["t"], wind_ned=data["wind_ned"]))
        _write_atomic(plot, lambda tmp: fig.savefig(tmp, dpi=100, format=plot.suffix.lstrip(".") or "png"))
    if json_out is not None:
        _write_json(json_out, summary)
    typer.echo(json.dumps(summary))

@airdata_app.command("faults", help="""Monte Carlo fault detection on the thesis scenario: inject a fault, run every detector.

Reports per detector the detection delay (onset sample = 1), the share detected within --horizon
steps, missed detections, and the per-step / per-run false-alarm rates under nominal data, with the
calibrated thresholds (per-step false-alarm rate --pfa) and the thesis's beside them.

Example: imunav airdata faults --kind variance --magnitude 3.5 --runs 100 --seed 0 --json faults.json
""")
def faults(
    kind: str = typer.Option("variance", "--kind", help="variance | bias | drift | stuck | outliers"),
    magnitude: Optional[float] = typer.Option(None, "--magnitude", help="Noise factor / bias (m/s) / drift (m/s per s)."),
    onset: int = typer.Option(151, "--onset", help="Thesis step of the onset (1-based)."),
    channels: Optional[str] = typer.Option(None, "--channels", help="'all' or e.g. 0,2."),
    runs: int = typer.Option(100, "--runs", help="Monte Carlo runs."),
    window: int = typer.Option(20, "--window", help="Detector window M."),
    pfa: float = typer.Option(0.01, "--pfa", help="Per-step false-alarm rate of the calibrated thresholds."),
    horizon: int = typer.Option(10, "--horizon", help="Steps after the onset counted as timely."),
    seed: int = typer.Option(0, "--seed", help="Random seed."),
    json_out: Optional[Path] = typer.Option(None, "--json", help="Write the table as JSON here."),
) -> None:
    check_outputs([], [json_out])  # before the Monte Carlo

    try:
        kw = {"kind": kind, "fault_step": onset, "channels": _channels(channels)}
        if magnitude is not None:
            key = {"variance": "variance_factor", "bias": "bias", "drift": "drift_rate",
                   "outliers": "outlier_factor"}.get(kind)
            if key is None:
                raise InvalidInputError(f"--magnitude does not apply to kind {kind!r}")
            kw[key] = magnitude
        sc = scenario.WindScenario(**kw)
        if runs < 1:
            raise InvalidInputError(f"--runs must be >= 1, got {runs}")
        thr = filters_faults.calibrated_thresholds(window, 3, pfa)
        th = filters_faults.window_chi2_thresholds(window, 3)
        ss = np.random.SeedSequence(seed).spawn(2)
        chunk = max(1, min(50, runs))
        with progress("Monte Carlo", total=2 * runs) as report:
            done = [0]

            def tick(n: int) -> None:
                done[0] += n
                report(done[0], 2 * runs)

            stats_f = scenario.simulate_detector_statistics(sc, runs, np.random.default_rng(ss[0]), window,
                                                   chunk=chunk, on_chunk=tick)
            stats_n = scenario.simulate_detector_statistics(scenario.WindScenario(kind="nominal"), runs,
                                                   np.random.default_rng(ss[1]), window, chunk=chunk, on_chunk=tick)
    except InvalidInputError as exc:
        _fail(exc)
        return
    o = sc.onset_row
    rows = []
    for d in filters_faults.DETECTORS:
        sn = stats_n[d][:, window - 1:]
        for label, t in (("calibrated", thr[d]), ("thesis", th.get(d))):
            if t is None:
                continue
            summary = scenario.delay_summary(filters_faults.alarms(d, stats_f[d], t), o, horizon)
            fa_step, fa_run = filters_faults.false_alarm_rates(filters_faults.alarms(d, sn, t))
            rows.append({"detector": d, "threshold_mode": label, "threshold": float(t),
                         **{k: summary[k] for k in ("median_delay", "p90_delay", f"detected_within_{horizon}", "missed")},
                         "false_alarm_per_step": fa_step, "false_alarm_per_run": fa_run})
    result = {"scenario": sc.to_dict(), "runs": runs, "seed": seed, "window": window, "pfa": pfa, "rows": rows}
    table = Table(title=f"{kind} fault at thesis step {onset}, {runs} runs")
    for col in ("detector", "thresholds", "threshold (statistic)", "median delay (steps)",
                f"detected within {horizon} steps (share)", "missed (share)", "false alarms per step (share)"):
        table.add_column(col)
    for r in rows:
        table.add_row(r["detector"], r["threshold_mode"], f"{r['threshold']:.2f}",
                      "-" if r["median_delay"] is None else f"{r['median_delay']:.0f}",
                      f"{r[f'detected_within_{horizon}']:.2f}", f"{r['missed']:.2f}",
                      f"{r['false_alarm_per_step']:.3f}")
    make_console().print(table)
    if json_out is not None:
        _write_json(json_out, result)

@airdata_app.command("thesis", help="""Run the thesis scenarios: covariance sequence, wind errors, robust filters, detection and false alarms.

Writes the covariance sequence (beside the thesis's P44), Monte Carlo wind errors against the
difference loop, robust-filter rejection rates, detector false-alarm rates (calibrated and thesis
thresholds) and detection delays, and one seeded run's detection steps.

Example: imunav airdata thesis --runs 50 --json thesis.json
""")
def thesis(
    json_out: Path = typer.Option(..., "--json", help="Output JSON file."),
    runs: int = typer.Option(200, "--runs", help="Monte Carlo runs."),
    seed: int = typer.Option(0, "--seed", help="Random seed."),
    pfa: float = typer.Option(0.01, "--pfa", help="Per-step false-alarm rate of the calibrated thresholds."),
    robust_methods: str = typer.Option("gate2,gate3,nis,isolate,huber", "--robust-methods",
                                       help="Robust filters to compare (gate<m>, nis, isolate, huber); "
                                            "gate2 and nis are required."),
) -> None:
    check_outputs([], [json_out])  # before the Monte Carlo

    try:
        if runs < 2:
            raise InvalidInputError(f"--runs must be >= 2, got {runs}")
        methods = tuple(m.strip() for m in robust_methods.split(",") if m.strip())
        if "gate2" not in methods or "nis" not in methods:
            raise InvalidInputError("--robust-methods must include gate2 and nis (the thesis gate and the χ² gate)")
        with progress(f"thesis scenarios, {runs} Monte Carlo runs") as report:
            report(0, 1)
            rep = scenario.wind_scenario_report(runs, seed, p_false_alarm=pfa, robust_methods=methods)
            report(1, 1)
    except InvalidInputError as exc:
        _fail(exc)
        return
    _write_json(json_out, rep)
    mc = rep["monte_carlo"]
    cov = rep["covariance_sequence"]
    typer.echo("P44: " + ", ".join(f"{i}:{p:.4f} (thesis {t:.4f})" for i, p, t in
                                  zip(cov["iteration"], cov["P44"], cov["P44_thesis"])))
    typer.echo(f"wind RMS {mc['wind']['kf_rms']:.3f} m/s (difference loop {mc['wind']['difference_loop_rms']:.2f}, "
               f"variance ratio {mc['wind']['variance_ratio']:.0f})")
    typer.echo("false alarms per step: " + ", ".join(
        f"{k} {v['per_step']:.3f}" + (f" (thesis thr {v['per_step_thesis']:.3f})" if "per_step_thesis" in v else "")
        for k, v in mc["false_alarms"].items()))
    typer.echo(f"robust rejection of anomalous samples: nis {mc['robust']['nis']['rejected_anomalous']:.3f}, "
               f"thesis gate ±2 {mc['robust']['gate2']['rejected_anomalous']:.3f}")
    typer.echo(f"wrote {json_out}")


def register(app: typer.Typer) -> None:
    app.add_typer(airdata_app, name="airdata")
