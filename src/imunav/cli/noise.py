"""``imunav noise``: Allan deviation, noise-term fit, PSD cross-check of a static recording."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer
from rich.console import Console
from rich.progress import Progress
from rich.table import Table

from imunav.cli._errors import check_figure_path
from imunav.cli._options import INSTANCE, LAYOUT, TOPIC, reader_options
from imunav.errors import InvalidInputError
from imunav.files import atomic_path, check_outputs, write_json
from imunav.io import read_imu
from imunav.io.kalibr import write_kalibr_yaml
from imunav.io.openvins import write_openvins_yaml
from imunav.io.vins import write_vins_yaml
from imunav.noise import allan_deviation, compare_psd_allan, fit_noise, fit_psd, log_average, psd
from imunav.noise.curvefit import compare_curve_fits
from imunav.noise.plot import plot_allan, plot_psd
from imunav.noise.static import require_static
from imunav.units import to_display

_EXAMPLE = (
    "Example:\n\n"
    "  imunav noise ../shared/data/adis16405/adis16405_imu2.npz --gyro-unit deg/s --accel-unit g "
    "--json noise.json --plot allan.png --psd-plot psd.png --kalibr imu.yaml --openvins kalibr_imu_chain.yaml "
    "--vins vins_imu.yaml"
)
_CH = ("gx", "gy", "gz", "ax", "ay", "az")


def _taus(spec: str) -> Any:
    if spec.startswith("log:"):
        n = spec.split(":", 1)[1].strip()
        if not n.isdigit() or int(n) < 2:
            raise InvalidInputError(f"--taus {spec!r}: log:N needs an integer N >= 2 (e.g. log:50)")
        return ("log", int(n))
    if spec not in ("octave", "decade", "all"):
        raise InvalidInputError(f"--taus {spec!r}: use octave, decade, all or log:N")
    return spec


def _fmt(v: float, se: float) -> str:
    if v == 0:
        return "-"
    return f"{v:.4g} ± {se:.2g}" if se == se else f"{v:.4g}"


def _curve_fits(r: Any) -> dict[str, Any]:
    """Thesis-style smooth fits of each channel's Allan curve (reported beside the term fit)."""

    out: dict[str, Any] = {}
    for c, name in enumerate(r.channels):
        a = r.channel(c)
        try:
            fits = compare_curve_fits(a.tau, a.adev)
            out[name] = {k: {"rms_log10": v.rms_log10, "max_log10": v.max_log10, "has_pole": v.has_pole,
                             "readout": v.readout()} for k, v in fits.items()}
        except (InvalidInputError, ValueError, RuntimeError) as e:  # too few tau points, LM failure
            out[name] = {"error": str(e)}
    return out


def noise(
    file: Path = typer.Argument(..., help="Static recording: .csv/.txt, .parquet, .h5, .mat, .npz, ROS bag or PX4 .ulg."),
    channels: str = typer.Option(",".join(_CH), "--channels", help="Comma-separated subset of gx,gy,gz,ax,ay,az."),
    json_out: Path | None = typer.Option(None, "--json", help="Write Allan curves, fitted terms and PSD terms as JSON."),
    plot: Path | None = typer.Option(None, "--plot", help="Allan-deviation figure with fit and CIs (.png/.pdf/.svg)."),
    psd_plot: Path | None = typer.Option(None, "--psd-plot", help="PSD figure with the fitted model."),
    kalibr_out: Path | None = typer.Option(None, "--kalibr", "--yaml", help="Kalibr imu.yaml (needs gyro and accel "
                                         "channels; --yaml is the older name)."),
    openvins_out: Path | None = typer.Option(None, "--openvins", help="OpenVINS kalibr_imu_chain.yaml (IMU noise)."),
    vins_out: Path | None = typer.Option(None, "--vins", help="VINS-Fusion IMU block: acc_n, gyr_n, acc_w, gyr_w, "
                                         "g_norm (identified values, not inflated)."),
    kind: str = typer.Option("overlapping", "--kind", help="overlapping, standard or total (the fit needs these)."),
    taus: str = typer.Option("octave", "--taus", help="octave, decade, all, or log:N."),
    terms: str = typer.Option("N,B,K,R", "--terms", help="Candidate terms among Q,N,B,K,R (Q, angle/velocity "
                              "quantization, belongs to increment outputs; add it for those)."),
    gm: int = typer.Option(0, "--gm", help="Number of Gauss-Markov terms to add to the fit."),
    select: str = typer.Option("bic", "--select", help="Term selection: bic, aic or none."),
    fs: float | None = typer.Option(None, "--fs", help="Sampling rate (Hz) when the file has no time column."),
    gyro_unit: str | None = typer.Option(None, "--gyro-unit", help="Unit of the gyro columns (rad/s, deg/s, ...)."),
    accel_unit: str | None = typer.Option(None, "--accel-unit", help="Unit of the accel columns (m/s^2, g, mg, ...)."),
    format: str | None = typer.Option(None, "--format", help="csv, parquet, hdf5, mat, npz, rosbag, ulog (default: "
                                      "suffix / content)."),
    skiprows: int | None = typer.Option(None, "--skiprows", help="CSV: lines to skip before the header."),
    topic: str | None = TOPIC,
    instance: int | None = INSTANCE,
    layout: str | None = LAYOUT,
    force: bool = typer.Option(False, "--force", help="Analyse a recording that is not static (moved or rotated)."),
) -> None:
    """Identify the stochastic errors of a static IMU recording: overlapping Allan
    deviation with confidence intervals, GLS fit of quantization Q, white noise N,
    bias instability B, random walk K and ramp R (with standard errors), the
    IEEE-952 slope read-outs, and the PSD estimate of N as a cross-check.

    The recording must be static (one pose, no rotation): a recording whose mean specific force is far from g,
    or whose 1 s window means change pose or rotate, is refused unless --force."""

    console = Console()
    exports = {"Kalibr imu.yaml": kalibr_out, "OpenVINS IMU file": openvins_out, "VINS-Fusion IMU block": vins_out}
    check_outputs([file], [json_out, plot, psd_plot, *exports.values()])
    check_figure_path(plot, "--plot")
    check_figure_path(psd_plot, "--psd-plot")
    tau_spec = _taus(taus)
    chans = [c.strip() for c in channels.split(",") if c.strip()]
    bad = [c for c in chans if c not in _CH]
    if bad or not chans:
        raise InvalidInputError(f"--channels: unknown {bad}; choose from {','.join(_CH)}")
    wanted = [opt for opt, path in zip(("--kalibr", "--openvins", "--vins"), exports.values()) if path is not None]
    if wanted and not (set(chans) & set(_CH[:3]) and set(chans) & set(_CH[3:])):
        raise InvalidInputError(f"{', '.join(wanted)}: needs both gyro and accel channels; add them to --channels")
    term_list = tuple(t.strip().upper() for t in terms.split(",") if t.strip())
    if select not in ("bic", "aic", "none"):
        raise InvalidInputError(f"--select {select!r}: use bic, aic or none")
    opts = reader_options(units={k: v for k, v in (("gyro", gyro_unit), ("accel", accel_unit)) if v}, fs=fs,
                          skiprows=skiprows, topic=topic, instance=instance, layout=layout)
    data = read_imu(file, format=format, **opts)
    rate = float(data.fs)
    if fs is None and abs(rate - round(rate)) < 1e-6 * rate:
        rate = float(round(rate))  # time stamps built from an integer rate
    if data.gaps():
        raise InvalidInputError(f"{file}: the record has {len(data.gaps())} time gap(s); the noise analysis "
                                "needs one gap-free static record (split it, or use imunav.noise.allan_deviation "
                                "with nan_policy='segments')")

    # gyro-only analyses skip the mean-specific-force test: the accelerometer's unit may be undeclared
    require_static(data, force=force, where=str(file), mean_force=any(c.startswith("a") for c in chans))
    groups = []
    for sensor, arr, unit, names in (("gyro", data.gyro, "rad/s", _CH[:3]), ("accel", data.accel, "m/s^2", _CH[3:])):
        idx = [i for i, n in enumerate(names) if n in chans]
        if idx:
            groups.append((sensor, arr[:, idx], unit, tuple(names[i] for i in idx)))
    results: dict[str, Any] = {}
    with Progress(console=console, transient=True) as prog:
        task = prog.add_task("noise analysis", total=3 * len(groups))
        for sensor, arr, unit, names in groups:
            r = allan_deviation(arr, rate, tau_spec, kind, units=unit, channels=names)
            prog.advance(task)
            f = fit_noise(r, terms=term_list, gauss_markov=gm, select=None if select == "none" else select,
                          quantity=sensor)
            prog.advance(task)
            p = psd(arr, rate, "welch", nperseg=min(arr.shape[0], 2**14), units=unit, channels=names)
            pa = log_average(p, 10)
            # same band as the Allan fit: below 1/(2 tau_min), clear of the sensor's own filter
            pf = fit_psd(pa, f_range=[(pa.f[0], min(0.4 * rate, 0.5 / float(tm))) for tm in f.tau_min])
            prog.advance(task)
            results[sensor] = (r, f, p, pa, pf, compare_psd_allan(pf, f))

    console.print(f"[bold]{file}[/bold]: {data.n:,} samples at {rate:g} Hz ({data.n / rate:.6g} s), "
                  f"kind={kind}, taus={taus}")
    for sensor, (r, f, _p, _pa, _pf, cmp) in results.items():
        t = Table(title=f"{sensor} noise terms (GLS fit ± standard error; display units)", title_justify="left")
        t.add_column("channel")
        shown = [i for i, nm in enumerate(f.names) if f.selected[i].any() or nm in ("N", "B", "K")]
        for i in shown:
            t.add_column(f"{f.names[i]} [{f.display_units[i]}]", justify="right")
        t.add_column("N (PSD) / N (Allan) - 1", justify="right")
        t.add_column(f"slope read-out N [{f.display_units[f.names.index('N')]}]", justify="right")
        t.add_column("fit from tau (s)", justify="right")
        for c, name in enumerate(r.channels):
            row = [name]
            for i in shown:
                d = f.display(f.names[i])[c]
                scale = d / f.value[i, c] if f.value[i, c] else 1.0
                row.append(_fmt(d, f.se[i, c] * scale) if f.selected[i, c] else "-")
            row.append(f"{cmp['N'][c]:+.1%}")
            iN = f.names.index("N")
            du = f.display_units[iN]
            sN = f.slopes.value[1, c] if du == f.units[iN] else to_display(f.slopes.value[1, c], du)
            row.append(f"{sN:.4g}")
            row.append(f"{f.tau_min[c]:.3g}")
            t.add_row(*row)
        console.print(t)
    if json_out is not None:
        out = {"file": str(file), "fs": rate, "n_samples": int(data.n)}
        for sensor, (r, f, _p, _pa, pf, cmp) in results.items():
            out[sensor] = {"allan": r.to_dict(), "fit": f.to_dict(), "psd_fit": pf.to_dict(), "psd_vs_allan": cmp,
                           "curve_fits": _curve_fits(r)}
        write_json(json_out, out, indent=1)
        console.print(f"results written to {json_out}")
    if plot is not None or psd_plot is not None:
        for path, which in ((plot, "allan"), (psd_plot, "psd")):
            if path is None:
                continue
            figs = []
            for sensor, (r, f, p, pa, pf, _) in results.items():
                figs.append(plot_allan(r, f, title=sensor) if which == "allan" else plot_psd(p, pf, pa, title=sensor))
            for k, fig in enumerate(figs):
                target = Path(path) if len(figs) == 1 else Path(path).with_name(
                    f"{Path(path).stem}_{list(results)[k]}{Path(path).suffix}")
                with atomic_path(target) as tmp:
                    fig.savefig(tmp, dpi=110, format=target.suffix.lstrip(".") or "png")
                console.print(f"figure written to {target}")
    if wanted:
        fg, fa = results["gyro"][1], results["accel"][1]
        writers = (lambda p: write_kalibr_yaml(p, fg, fa, rate), lambda p: write_openvins_yaml(p, fg, fa, rate),
                   lambda p: write_vins_yaml(p, fg, fa))
        for (what, path), write in zip(exports.items(), writers):
            if path is not None:
                write(path)
                console.print(f"{what} written to {path}")


noise.__doc__ = (noise.__doc__ or "") + "\n\n" + _EXAMPLE


def register(app: typer.Typer) -> None:
    """Add ``imunav noise`` to the app."""
    app.command("noise", help=noise.__doc__)(noise)
