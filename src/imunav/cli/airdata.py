"""``imunav airdata``: air-data / Doppler wind estimation (simulate, run, faults, thesis)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import typer
from rich.console import Console
from rich.progress import Progress
from rich.table import Table

from imunav.airdata import plot as P
from imunav.airdata.flight import FlightConfig
from imunav.airdata.flightfile import (
    read_flight_file,
    simulate_flight_file,
    wind_errors,
    write_flight_file,
    write_wind_estimates,
)
from imunav.airdata.scenario import (
    ThesisScenario,
    fault_detection_table,
    load_config,
    thesis_report,
)
from imunav.cli._errors import check_figure_path, check_suffix, fail
from imunav.errors import InvalidInputError
from imunav.files import atomic_path, check_outputs, write_json

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

    try:
        ch = tuple(int(c) for c in text.split(","))
    except ValueError as exc:
        raise InvalidInputError(f"--channels must be 'all' or comma-separated indices 0..2, got {text!r}") from exc
    if any(c < 0 or c > 2 for c in ch):
        raise InvalidInputError(f"--channels must be within 0..2 (x, y, z), got {text!r}")
    return ch


def _vec3(text: str, name: str) -> tuple[float, float, float]:
    try:
        v = tuple(float(x) for x in text.split(","))
    except ValueError as exc:
        raise InvalidInputError(f"{name} must be three comma-separated numbers, got {text!r}") from exc
    if len(v) != 3:
        raise InvalidInputError(f"{name} must be three comma-separated numbers (N,E,D), got {text!r}")
    return v  # type: ignore[return-value]


def _fail(exc: Exception) -> None:
    fail(exc)


app = typer.Typer(help=_HELP, no_args_is_help=True)


@app.command("simulate", help="""Simulate a flight (truth, air data, Doppler, attitude) or a thesis scenario and write an .npz file.

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
        if config is not None:
            scenario = load_config(config)
        elif profile == "thesis":
            scenario = ThesisScenario(kind=kind)
        else:
            scenario = FlightConfig(
                profile=profile, duration=duration, tas=tas, altitude=altitude, wind_ned=_vec3(wind, "--wind"),
                turbulence=turbulence, rate_ads=rate_ads, rate_doppler=rate_doppler)
        content = simulate_flight_file(scenario, seed)
    except InvalidInputError as exc:
        _fail(exc)
        return
    summary = content.summary(out)
    write_flight_file(out, content)
    if json_out is not None:
        _write_json(json_out, summary)
    typer.echo(json.dumps(summary))

@app.command("run", help="""Run the wind filter on a file written by `imunav airdata simulate`.

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
        errors = wind_errors(read_flight_file(path), robust=rb, gate_m=gate_m, alpha=alpha)
    except InvalidInputError as exc:
        _fail(exc)
        return
    if out is not None:
        write_wind_estimates(out, errors)
    if plot is not None:
        fig = P.plot_wind(errors.result) if errors.kind == "thesis" else P.plot_long_horizon(errors.result)
        _write_atomic(plot, lambda tmp: fig.savefig(tmp, dpi=100, format=plot.suffix.lstrip(".") or "png"))
    if json_out is not None:
        _write_json(json_out, errors.summary)
    typer.echo(json.dumps(errors.summary))

@app.command("faults", help="""Monte Carlo fault detection on the thesis scenario: inject a fault, run every detector.

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
        sc = ThesisScenario(**kw)
        with Progress(console=Console(stderr=True), transient=True) as prog:
            task = prog.add_task("Monte Carlo", total=2 * runs)

            def tick(n: int) -> None:
                prog.update(task, advance=n)

            result = fault_detection_table(sc, runs, seed, window=window, p_false_alarm=pfa, horizon=horizon,
                                           on_chunk=tick)
    except InvalidInputError as exc:
        _fail(exc)
        return
    rows = result["rows"]
    table = Table(title=f"{kind} fault at thesis step {onset}, {runs} runs")
    for col in ("detector", "thresholds", "threshold", "median delay", f"within {horizon}", "missed", "FA/step"):
        table.add_column(col)
    for r in rows:
        table.add_row(r["detector"], r["threshold_mode"], f"{r['threshold']:.2f}",
                      "-" if r["median_delay"] is None else f"{r['median_delay']:.0f}",
                      f"{r[f'detected_within_{horizon}']:.2f}", f"{r['missed']:.2f}",
                      f"{r['false_alarm_per_step']:.3f}")
    Console().print(table)
    if json_out is not None:
        _write_json(json_out, result)

@app.command("thesis", help="""Run the thesis scenarios: covariance sequence, wind errors, robust filters, detection and false alarms.

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
        with Console(stderr=True).status(f"thesis scenarios, {runs} Monte Carlo runs"):
            rep = thesis_report(runs, seed, p_false_alarm=pfa, robust_methods=methods)
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


def register(root: typer.Typer) -> None:
    """Add ``imunav airdata`` to the app."""
    root.add_typer(app, name="airdata")
