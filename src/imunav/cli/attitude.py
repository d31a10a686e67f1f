"""``imunav attitude``: run attitude filters, the BROAD benchmark, the paper's Monte Carlo."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Optional

import numpy as np
import typer
from rich.markup import escape
from rich.progress import Progress
from rich.table import Table

from imunav.cli._console import make_console
from imunav.cli._errors import check_figure_path
from imunav.cli._lazy import lazy
from imunav.cli._options import END, INSTANCE, LAYOUT, MAG_TOPIC, START, TOPIC, read_recording, reader_options, window
from imunav.errors import ConfigError, ConvergenceError
from imunav.files import check_outputs, write_json

alignment = lazy("imunav.attitude.alignment")
attitude_plot = lazy("imunav.attitude.plot")
benchmark = lazy("imunav.attitude.benchmark")
broad = lazy("imunav.io.broad")
datasets = lazy("imunav.io.datasets")
logs = lazy("imunav.io.logs")
metrics = lazy("imunav.attitude.metrics")
noise_profile = lazy("imunav.noise.profile")
montecarlo = lazy("imunav.lab.montecarlo")
px4 = lazy("imunav.attitude.px4")
rotation = lazy("imunav.rotation")
scenario = lazy("imunav.attitude.scenario")
scenarios = lazy("imunav.scenarios")


app = typer.Typer(help="Attitude filters (Madgwick, Mahony, MEKF, UKF, adaptive, smoother, paper KFs).\n\n"
                  "Example: imunav attitude run ../shared/data/broad/05_undisturbed_slow_rotation_with_breaks_B.mat "
                  "--filter madgwick_c",
                  no_args_is_help=True)


def _parse_params(items: list[str] | None) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for it in items or []:
        if "=" not in it:
            raise ConfigError(f"--param {it!r}: expected NAME=VALUE, e.g. --param beta=0.1")
        k, v = it.split("=", 1)
        out[k.strip()] = _value(v)
    return out


def _value(v: str) -> Any:
    s = v.strip()
    if s.lower() in ("true", "false"):
        return s.lower() == "true"
    try:
        return int(s)
    except ValueError:
        pass
    try:
        return float(s)
    except ValueError:
        return s


def _resolve(path: Path, is_dir: bool) -> Path:
    """The path as given, else the same name inside the shared BROAD folder."""
    if path.exists():
        return path

    cand = datasets.shared_data_path("broad") if is_dir and path.name == "broad" else datasets.shared_data_path("broad", path.name)
    if cand is not None and cand.exists():
        return cand
    raise ConfigError(f"{path} not found (nor in the shared BROAD folder); set IMUNAV_DATA or pass an existing path")


def _write_json(obj: Any, path: Path) -> None:
    write_json(path, obj, indent=1)


@app.command("run")
def run_cmd(
    file: Path = typer.Argument(..., help="Recording: a BROAD trial (*.mat) or any file imunav.io can read (also a ROS "
                                "bag or PX4 .ulg)."),
    filter: str = typer.Option("adaptive", "--filter", "-f", help="Filter name (see `benchmark --help`)."),
    param: Optional[list[str]] = typer.Option(None, "--param", "-p", help="Parameter override NAME=VALUE."),
    no_mag: bool = typer.Option(False, "--no-mag", help="6D: ignore the magnetometer."),
    json_out: Optional[Path] = typer.Option(None, "--json", help="Write the result (quaternions, flags) as JSON."),
    noise: Optional[Path] = typer.Option(None, "--noise", help="Noise profile of the sensor (imunav noise --profile): "
                                         "the filter's gyro noise density, bias random walk and per-sample noise "
                                         "from it (mekf, adaptive, smoother, ukf; --param still wins)."),
    topic: Optional[str] = TOPIC,
    instance: Optional[int] = INSTANCE,
    mag_topic: Optional[str] = MAG_TOPIC,
    layout: Optional[str] = LAYOUT,
    start: Optional[float] = START,
    end: Optional[float] = END,
) -> None:
    """Run one filter over a whole recording and print a summary (BROAD RMSE when a reference exists).

    Example: imunav attitude run ../shared/data/broad/05_undisturbed_slow_rotation_with_breaks_B.mat --filter madgwick_c

    Example (PX4 log; sensor_combined carries its magnetometer):
    imunav attitude run ../shared/data/px4_ulog/sample.ulg --topic sensor_combined --filter mekf

    Example (the filter's noise from the sensor's own, identified on the trial's first 25 s at rest):
    imunav noise ../shared/data/broad/05_undisturbed_slow_rotation_with_breaks_B.mat --end 25 --profile
    broad05.toml && imunav attitude run 05_undisturbed_slow_rotation_with_breaks_B.mat --noise broad05.toml
    """

    check_outputs([file, noise], [json_out], inputs_exist=False)  # a BROAD trial name is looked up in the shared data

    con = make_console()

    file = _resolve(file, False)
    params = _parse_params(param)
    f = benchmark.make_filter(filter, params)
    prof = None
    if noise is not None:
        prof = noise_profile.read_noise_profile(noise)
        if filter not in benchmark.NOISE_FILTERS:
            raise ConfigError(f"--noise: filter {filter!r} takes no noise parameters (fixed gains); use one of "
                              f"{', '.join(benchmark.NOISE_FILTERS)}")
    ref = None
    opts = reader_options(topic=topic, instance=instance, mag_topic=mag_topic, layout=layout)
    if file.suffix.lower() == ".mat" and not opts:
        tr = broad.load_broad(file)
        data, ref, mask = tr.imu, tr.q_ref_nb, tr.movement
    else:
        data = read_recording(file, **opts)
    px4_log = logs.log_kind(file) == "ulog"
    px4_out: dict[str, Any] = {}
    if px4_log and not no_mag and mag_topic is None:
        # the magnetometer topic that holds data (sensor_combined of newer logs carries none)
        mt = px4.magnetometer_topic(file, data)
        if mt is not None:
            data = read_recording(file, **{**opts, "mag_topic": mt})
            con.print(f"magnetometer: {mt}, interpolated onto the IMU stamps on the log's clock (--mag-topic to "
                      "choose another)")
        px4_out["mag_topic"] = mt if mt is not None else ("in the IMU topic" if data.mag is not None else None)
        if data.mag is None:
            con.print("no magnetometer data in this log: 6D, the yaw is not observable")
    if start is not None or end is not None:
        cut = window(data, start, end)
        if ref is not None:  # the BROAD reference and movement mask, cut alike
            i0 = int(np.searchsorted(data.t, cut.t[0]))
            ref, mask = ref[i0:i0 + cut.n], mask[i0:i0 + cut.n]
        data = cut
    kw: dict[str, Any] = {"use_mag": False if no_mag else None}
    if prof is not None:  # the profile's fields at this recording's rate; --param overrides them
        from_profile = benchmark.noise_parameters(filter, prof, fs=float(data.fs))
        f = benchmark.make_filter(filter, {**from_profile, **params})
        con.print(f"noise from {noise}: " + ", ".join(f"{k} = {v:.4g}" for k, v in from_profile.items()
                                                      if k not in params))

    if ref is not None and benchmark.reference_start(filter) and not no_mag:
        # start like the BROAD reference runs (first accelerometer / magnetometer sample)

        kw["q0"] = alignment.broad_reference_start(data.accel[0], data.mag[0])
    given = [f"--param {k_}={v}" for k_, v in params.items()] + ([f"--noise {noise}"] if prof is not None else [])
    try:
        res = f.run(data, **kw)
    except ConvergenceError as exc:  # the Kalman filters refuse their own overflow; say what the command gave them
        if not given:
            raise
        raise ConvergenceError(f"{exc}; it was given {', '.join(given)}") from None
    bad = ~np.isfinite(res.q_nb).all(axis=1)
    if bad.any():  # the filters that do not check themselves: a gain far out of range makes their numbers overflow
        k = int(np.argmax(bad))
        raise ConvergenceError(f"{res.name} diverged: its attitude is not finite from sample {k} (t = "
                               f"{res.t[k] - res.t[0]:.6g} s) on; check what it was given"
                               + (f" ({', '.join(given)})" if given else "") + ": a noise or gain far outside "
                               "the sensor's range")

    q_final = res.q_nb
    decl = None
    if px4_log:
        used_mag = data.mag is not None and not no_mag
        decl, key = px4.declination(data.meta)
        if decl is not None and used_mag:
            q_final = px4.to_true_north(res.q_nb, decl)
            con.print(f"declination: {key} = {decl:.2f} deg added to the yaw (PX4 references true north, the "
                      "magnetometer magnetic north)")
        elif used_mag:
            con.print("declination: the log has no EKF2_MAG_DECL / ATT_MAG_DECL; the yaw is referenced to "
                      "magnetic north")
        else:
            decl = None
        px4_out["declination_deg"] = decl if used_mag else None
        px4_out["declination_parameter"] = key if used_mag and decl is not None else None
    e = np.degrees(rotation.euler_from_quat(q_final[-1]))
    con.print(f"[bold]{res.name}[/bold]: {res.n} samples, final roll/pitch/yaw = "
              f"{e[0]:.2f} / {e[1]:.2f} / {e[2]:.2f} deg" + (" (true north)" if decl is not None else ""))
    summary: dict[str, Any] = {"filter": res.name, "params": res.params}
    if px4_log:
        names = {ti.topic for ti in logs.list_topics(file)}
        ref_topic = next((t for t in px4.REFERENCE_TOPICS if t in names), None)
        if ref_topic is None:
            con.print("the log has no vehicle_attitude: no comparison with PX4's estimate")
        else:
            cmp = px4.compare(data, res.q_nb, logs.read_topic(file, ref_topic), t_from=min(10.0, 0.3 * data.duration),
                              declination_deg=decl)
            r = cmp.rms_deg
            con.print(f"RMS difference to the log's {ref_topic} from {cmp.t_from_s:.3g} s on ({cmp.samples} samples): "
                      f"roll {r['roll']:.3f}, pitch {r['pitch']:.3f}, yaw {r['yaw']:.3f} deg")
            px4_out["reference"] = cmp.to_dict()
        summary["px4"] = px4_out
    if ref is not None:
        r = metrics.attitude_rmse(res.q_nb, ref, mask)
        con.print(f"BROAD RMSE over movement: total {r.total_rmse_deg:.3f}, heading {r.heading_rmse_deg:.3f}, "
                  f"inclination {r.inclination_rmse_deg:.3f} deg")
        summary["rmse"] = r.to_dict()
    if json_out:
        _write_json({**summary, "result": res.to_dict()}, json_out)
        con.print(f"wrote {json_out}")


@app.command("benchmark")
def benchmark_cmd(
    directory: Path = typer.Argument(Path("broad"), help="Folder with BROAD trial files (*.mat); default: the shared BROAD folder."),
    filter: Optional[list[str]] = typer.Option(None, "--filter", "-f", help="Filter(s); default adaptive + smoother."),
    param: Optional[list[str]] = typer.Option(None, "--param", "-p", help="Override NAME=VALUE (all filters)."),
    grid: Optional[list[str]] = typer.Option(None, "--grid", "-g",
                                             help="Grid search NAME=v1,v2,... (first --filter only)."),
    workers: int = typer.Option(0, "--workers", "-j", help="Processes for the grid (0 = all cores)."),
    json_out: Optional[Path] = typer.Option(None, "--json", help="Write per-trial RMSE per filter as JSON."),
) -> None:
    """Run filters with ONE parameter set on every trial; per-trial total / heading / inclination RMSE.

    Example: imunav attitude benchmark broad --filter madgwick_c --filter adaptive --json bench.json
    """

    check_outputs([], [json_out])  # before the benchmark

    con = make_console()
    files = broad.broad_trials(_resolve(directory, True))
    names = filter or ["adaptive", "smoother"]
    for n in names:
        if n not in benchmark.FILTERS:
            raise ConfigError(f"unknown filter {n!r}; choose from {', '.join(benchmark.FILTERS)}")
    params = _parse_params(param)
    out: dict[str, Any] = {"trials": [f.stem for f in files], "filters": {}}
    if grid:
        g: dict[str, list[Any]] = {}
        for it in grid:
            if "=" not in it:
                raise ConfigError(f"--grid {it!r}: expected NAME=v1,v2,...")
            k, v = it.split("=", 1)
            g[k] = [_value(x) for x in v.split(",")]
        g = {**{k: [v] for k, v in params.items()}, **g}
        with Progress(console=con) as prog:
            task = prog.add_task(f"grid {names[0]}", total=None)
            res = benchmark.grid_search(names[0], g, files, workers=workers or None,
                              progress=lambda i, n: prog.update(task, completed=i, total=n))
        t = Table(title=f"grid search {names[0]} (best first)")
        for c in ("params", "total", "heading", "inclination"):
            t.add_column(c)
        for r in res[:10]:
            m = r.means()
            t.add_row(json.dumps(r.params), f"{m['total_rmse_deg']:.3f}", f"{m['heading_rmse_deg']:.3f}",
                      f"{m['inclination_rmse_deg']:.3f}")
        con.print(t)
        out["grid"] = [r.to_dict() for r in res]
        if len(files) >= 2:
            cv, _ = benchmark.cv_grid_search(names[0], g, files, results=res)
            con.print(f"best set in sample {cv.in_sample_mean:.3f} deg; leave-one-trial-out (each trial scored with "
                      f"the set best on the others) {cv.oof_mean:.3f} deg: expect the latter on new recordings")
            out["cv"] = cv.to_dict()
        results = [res[0]]
    else:
        results = []
        with Progress(console=con) as prog:
            task = prog.add_task("filters", total=len(names))
            for n in names:
                results.append(benchmark.evaluate(n, params, files))
                prog.advance(task)
    t = Table(title=escape("BROAD RMSE [deg] (total / heading / inclination)"))
    t.add_column("trial")
    for r in results:
        t.add_column(r.filter)
    for i, f in enumerate(files):
        t.add_row(f.stem, *[f"{r.trials[i].total_rmse_deg:.2f} / {r.trials[i].heading_rmse_deg:.2f} / "
                            f"{r.trials[i].inclination_rmse_deg:.2f}" for r in results])
    t.add_row("[bold]mean[/bold]", *[" / ".join(f"{v:.2f}" for v in r.means().values()) for r in results])
    con.print(t)
    for r in results:
        out["filters"][r.filter] = r.to_dict()
    if json_out:
        _write_json(out, json_out)
        con.print(f"wrote {json_out}")


@app.command("montecarlo")
def montecarlo_cmd(
    runs: int = typer.Option(100, "--runs", "-n", help="Number of seeded runs."),
    seed: int = typer.Option(0, "--seed", help="Root seed (run i uses imunav.lab.montecarlo.spawn_generators(seed)[i])."),
    gyro_noise_unit: str = typer.Option("deg/s/sqrt(Hz)", "--gyro-noise-unit",
                                        help="Reading of the paper's 0.005 gyro noise: deg/s/sqrt(Hz) or deg/sqrt(h)."),
    filters: str = typer.Option("lee,javed,proposed", "--filters", "-f",
                                help="Comma list of the paper's filters: lee, javed, proposed."),
    executor: str = typer.Option("processes", "--executor", "-e",
                                 help="processes (local pool), dask (LocalCluster, or --address) or serial. "
                                      "All give identical numbers for the same seed."),
    workers: Optional[int] = typer.Option(None, "--workers", "-j", help="Worker processes (default: all cores)."),
    address: Optional[str] = typer.Option(None, "--address",
                                          help="Dask scheduler address (tcp://host:port); default: a local cluster."),
    duration: float = typer.Option(245.0, "--duration", help="Scenario length [s] (paper: about 245 s)."),
    json_out: Optional[Path] = typer.Option(None, "--json", help="Write the RMSE table and per-run values."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Write RMSE box plots (PNG)."),
) -> None:
    """The Candan & Söken scenario (245 s, 100 Hz, external-acceleration windows): Table 2 of the paper.

    Runs are batched (:func:`imunav.scenarios.attitude_paper`) and spread over
    :func:`imunav.lab.montecarlo.run_montecarlo`'s executor.

    Example: imunav attitude montecarlo --runs 5 --executor serial --json mc.json
    """

    check_outputs([], [json_out, plot])
    check_figure_path(plot, "--plot")


    con = make_console()
    names = tuple(f.strip() for f in filters.split(",") if f.strip())
    scn = scenario.PaperScenario(gyro_noise_unit=gyro_noise_unit, duration=duration)  # type: ignore[arg-type]
    every = scenario.default_filters(scn)
    unknown = [f for f in names if f not in every]
    if unknown or not names:
        raise ConfigError(f"--filters {filters!r}: unknown filter(s) {unknown}; choose from {sorted(every)}")
    res = montecarlo.run_montecarlo(scenarios.attitude_paper, runs, seed=seed, batched=True, executor=executor,  # type: ignore[arg-type]
                         n_workers=workers, address=address, progress=True,
                         description="attitude Monte Carlo", filters=names, duration=duration,
                         gyro_noise_unit=gyro_noise_unit)
    t = Table(title=escape(f"RMSE [deg] over {runs} runs (mean ± std); paper Table 2 in brackets"))
    for c in ("filter", "pitch", "roll"):
        t.add_column(c)
    for k, v in scenarios.paper_table(res).items():
        p = scenario.PAPER_TABLE2.get(k, (float("nan"),) * 2)
        t.add_row(k, f"{v['pitch_mean']:.4f} ± {v['pitch_std']:.4f} [{p[0]}]",
                  f"{v['roll_mean']:.4f} ± {v['roll_std']:.4f} [{p[1]}]")
    con.print(t)
    if json_out:
        _write_json(scenarios.paper_report(res, scn, {k: every[k] for k in names}), json_out)
        con.print(f"wrote {json_out}")
    if plot:
        attitude_plot.save(attitude_plot.plot_montecarlo_box(scenarios.paper_rmse(res)), plot)
        con.print(f"wrote {plot}")


def register(root: typer.Typer) -> None:
    root.add_typer(app, name="attitude")
