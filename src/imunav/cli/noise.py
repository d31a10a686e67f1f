"""``imunav noise``: Allan deviation, noise-term fit, PSD cross-check of a static recording."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import typer
from rich.markup import escape
from rich.table import Table

from imunav.cli._console import make_console
from imunav.cli._errors import check_figure_path, check_suffix
from imunav.cli._lazy import lazy
from imunav.cli._options import END, INSTANCE, LAYOUT, START, TOPIC, reader_options, window
from imunav.cli._progress import progress
from imunav.errors import ConvergenceError, InvalidInputError
from imunav.files import atomic_path, check_outputs, write_json
from imunav.units import to_display

curvefit = lazy("imunav.noise.curvefit")
imunav_noise = lazy("imunav.noise")
io = lazy("imunav.io")
kalibr = lazy("imunav.io.kalibr")
noise_plot = lazy("imunav.noise.plot")
openvins = lazy("imunav.io.openvins")
noise_profile = lazy("imunav.noise.profile")
static = lazy("imunav.noise.static")
vins = lazy("imunav.io.vins")

_EXAMPLE = (
    "Example:\n\n"
    "  imunav noise ../shared/data/adis16405/adis16405_imu2.npz --gyro-unit deg/s --accel-unit g "
    "--json noise.json --plot allan.png --psd-plot psd.png --kalibr imu.yaml --openvins kalibr_imu_chain.yaml "
    "--vins vins_imu.yaml\n\n"
    "  imunav noise ../shared/data/broad/05_undisturbed_slow_rotation_with_breaks_B.mat --end 25 "
    "--profile broad05.toml"
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
            fits = curvefit.compare_curve_fits(a.tau, a.adev)
            out[name] = {k: {"rms_log10": v.rms_log10, "max_log10": v.max_log10, "has_pole": v.has_pole,
                             "readout": v.readout()} for k, v in fits.items()}
        except (InvalidInputError, ValueError, RuntimeError) as e:  # too few tau points, LM failure
            out[name] = {"error": str(e)}
    return out


def _with_mag(prof: Any, data: Any, rate: float, tau_spec: Any, kind: str, terms: tuple[str, ...], select: str,
              console: Any) -> Any:
    """The profile with the magnetometer's terms added (the same Allan fit), or as it is, saying why not."""
    if data.mag_unit not in noise_profile.SENSORS["mag"]:
        console.print(f"magnetometer in {data.mag_unit!r}: not in the profile (it takes "
                      f"{', '.join(noise_profile.SENSORS['mag'])})")
        return prof
    try:
        r = imunav_noise.allan_deviation(data.mag, rate, tau_spec, kind, units=data.mag_unit,
                                         channels=("mx", "my", "mz"), t=data.t, nan_policy="segments")
        f = imunav_noise.fit_noise(r, terms=terms, select=None if select == "none" else select)
        mag = noise_profile.NoiseProfile.from_fits(fs=prof.fs, duration_s=prof.duration_s, mag=f,
                                                   mag_unit=data.mag_unit).mag
    except (InvalidInputError, ConvergenceError) as exc:
        console.print(f"magnetometer: not in the profile ({exc})")
        return prof
    return dataclasses.replace(prof, mag=mag)


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
    profile_out: Path | None = typer.Option(None, "--profile", help="Noise profile of the sensor (.toml or .json): "
                                            "white noise, bias instability and random walk per axis with standard "
                                            "errors, SI; the filters take it with --noise (needs all three axes of "
                                            "a sensor)."),
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
    start: float | None = START,
    end: float | None = END,
    force: bool = typer.Option(False, "--force", help="Analyse a recording that is not static (moved or rotated)."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar (none either when standard error is "
                               "not a terminal)."),
) -> None:
    """Identify the stochastic errors of a static IMU recording: overlapping Allan
    deviation with confidence intervals, GLS fit of quantization Q, white noise N,
    bias instability B, random walk K and ramp R (with standard errors), the
    IEEE-952 slope read-outs, and the PSD estimate of N as a cross-check.

    The recording must be static (one pose, no rotation): a recording whose mean specific force is far from g,
    or whose 1 s window means change pose or rotate, is refused unless --force."""

    console = make_console()
    exports = {"Kalibr imu.yaml": kalibr_out, "OpenVINS IMU file": openvins_out, "VINS-Fusion IMU block": vins_out}
    check_outputs([file], [json_out, plot, psd_plot, profile_out, *exports.values()])
    check_suffix(profile_out, "--profile", (".toml", ".json"), "the noise profile")
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
    if profile_out is not None:
        whole = [s for s, names in (("gyro", _CH[:3]), ("accel", _CH[3:])) if set(names) <= set(chans)]
        if not whole:
            raise InvalidInputError("--profile: needs the three axes of a sensor (gx,gy,gz and/or ax,ay,az) in "
                                    "--channels")
        if "N" not in term_list:
            raise InvalidInputError("--profile: the white noise N is part of a profile; add N to --terms")
    if select not in ("bic", "aic", "none"):
        raise InvalidInputError(f"--select {select!r}: use bic, aic or none")
    opts = reader_options(units={k: v for k, v in (("gyro", gyro_unit), ("accel", accel_unit)) if v}, fs=fs,
                          skiprows=skiprows, topic=topic, instance=instance, layout=layout)
    data = window(io.read_imu(file, format=format, **opts), start, end)
    rate = float(data.fs)
    if fs is None and abs(rate - round(rate)) < 1e-6 * rate:
        rate = float(round(rate))  # time stamps built from an integer rate
    gaps = data.gaps()
    if gaps:  # logger dropouts: the Allan statistics use the contiguous segments between them
        lost = sum(g.length_s for g in gaps)
        console.print(f"{len(gaps)} time gap(s) (logger dropouts, {lost:.3g} s in all, longest "
                      f"{max(g.length_s for g in gaps):.3g} s): Allan statistics over the {len(gaps) + 1} contiguous "
                      "segments, pooled; the PSD over the samples as they come")

    # gyro-only analyses skip the mean-specific-force test: the accelerometer's unit may be undeclared
    static.require_static(data, force=force, where=str(file), mean_force=any(c.startswith("a") for c in chans))
    groups = []
    for sensor, arr, unit, names in (("gyro", data.gyro, "rad/s", _CH[:3]), ("accel", data.accel, "m/s^2", _CH[3:])):
        idx = [i for i, n in enumerate(names) if n in chans]
        if idx:
            groups.append((sensor, arr[:, idx], unit, tuple(names[i] for i in idx)))
    results: dict[str, Any] = {}
    # steps of the bar: per sensor the Allan variance, the fit's stages (the long part of --taus all: one step per
    # channel until the first fit says how many it has), the PSD
    channels = [arr.shape[1] for _s, arr, _u, _n in groups]
    total = sum(2 + n for n in channels)
    with progress("noise analysis", quiet=quiet, total=total) as report:
        done = 0

        def advance(k: int = 1) -> None:
            nonlocal done
            done += k
            report(done, total)

        for sensor, arr, unit, names in groups:
            r = imunav_noise.allan_deviation(arr, rate, tau_spec, kind, units=unit, channels=names, t=data.t,
                                             nan_policy="segments")
            advance()
            before, guess = done, arr.shape[1]

            def fit_progress(k: int, n: int, before: int = before, guess: int = guess) -> None:
                nonlocal total
                total = sum(2 + c * (n // guess) for c in channels)  # the same stages per channel in every fit
                advance(before + k - done)

            f = imunav_noise.fit_noise(r, terms=term_list, gauss_markov=gm, select=None if select == "none" else select,
                                       quantity=sensor, progress=fit_progress)
            p = imunav_noise.psd(arr, rate, "welch", nperseg=min(arr.shape[0], 2**14), units=unit, channels=names)
            pa = imunav_noise.log_average(p, 10)
            # same band as the Allan fit: below 1/(2 tau_min), clear of the sensor's own filter
            pf = imunav_noise.fit_psd(pa, f_range=[(pa.f[0], min(0.4 * rate, 0.5 / float(tm))) for tm in f.tau_min])
            advance()
            results[sensor] = (r, f, p, pa, pf, imunav_noise.compare_psd_allan(pf, f))

    console.print(f"[bold]{file}[/bold]: {data.n:,} samples at {rate:g} Hz ({data.n / rate:.6g} s), "
                  f"kind={kind}, taus={taus}")
    for sensor, (r, f, _p, _pa, _pf, cmp) in results.items():
        t = Table(title=f"{sensor} noise terms (GLS fit ± standard error; display units)", title_justify="left")
        t.add_column("channel")
        shown = [i for i, nm in enumerate(f.names) if f.selected[i].any() or nm in ("N", "B", "K")]
        for i in shown:
            t.add_column(escape(f"{f.names[i]} [{f.display_units[i]}]"), justify="right")
        t.add_column("N (PSD) / N (Allan) - 1", justify="right")
        t.add_column(escape(f"slope read-out N [{f.display_units[f.names.index('N')]}]"), justify="right")
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
    span = float(data.t[-1] - data.t[0]) - sum(g.length_s for g in gaps)
    ident = {sensor: imunav_noise.identifiability(f, span) for sensor, (_r, f, *_rest) in results.items()}
    for sensor, terms_ in ident.items():
        for term, rows in terms_.items():
            short = [(results[sensor][0].channels[c], row["needs_s"]) for c, row in enumerate(rows)
                     if row["identifiable"] is False]
            if short:
                needs = [n for _, n in short if n is not None]
                console.print(f"{sensor} {term}: not identifiable from this {span:.4g} s record on "
                              f"{', '.join(c for c, _ in short)} (it shows only above the white noise"
                              + (f"; it would need about {max(needs):.3g} s" if needs else ", at no cluster time")
                              + "): the value in the table is an extrapolation")
    if json_out is not None:
        out = {"file": str(file), "fs": rate, "n_samples": int(data.n), "start_s": start, "end_s": end,
               "gaps": [{"t_start": g.t_start, "length_s": g.length_s, "missing_samples": g.missing_samples}
                        for g in gaps], "identifiability": ident}
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
                figs.append(noise_plot.plot_allan(r, f, title=sensor) if which == "allan" else noise_plot.plot_psd(p, pf, pa, title=sensor))
            for k, fig in enumerate(figs):
                target = Path(path) if len(figs) == 1 else Path(path).with_name(
                    f"{Path(path).stem}_{list(results)[k]}{Path(path).suffix}")
                with atomic_path(target) as tmp:
                    fig.savefig(tmp, dpi=110, format=target.suffix.lstrip(".") or "png")
                console.print(f"figure written to {target}")
    if profile_out is not None:
        fits = {s: results[s][1] for s in whole}
        where = str(file) + ("" if start is None and end is None else
                             f" [{'' if start is None else f'{start:g}'}:{'' if end is None else f'{end:g}'} s]")
        prof = noise_profile.NoiseProfile.from_fits(fs=rate, duration_s=span, source=where, **fits)
        if data.mag is not None:  # the magnetometer too, when the record has one in a field unit
            prof = _with_mag(prof, data, rate, tau_spec, kind, term_list, select, console)
        prof.write(profile_out)
        console.print(f"noise profile ({', '.join(prof.sensors())}) written to {profile_out}")
    if wanted:
        fg, fa = results["gyro"][1], results["accel"][1]
        writers = (lambda p: kalibr.write_kalibr_yaml(p, fg, fa, rate), lambda p: openvins.write_openvins_yaml(p, fg, fa, rate),
                   lambda p: vins.write_vins_yaml(p, fg, fa))
        for (what, path), write in zip(exports.items(), writers):
            if path is not None:
                write(path)
                console.print(f"{what} written to {path}")


noise.__doc__ = (noise.__doc__ or "") + "\n\n" + _EXAMPLE


def register(app: typer.Typer) -> None:
    """Add ``imunav noise`` to the app."""
    app.command("noise", help=noise.__doc__)(noise)
