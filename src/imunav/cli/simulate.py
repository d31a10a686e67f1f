"""``imunav simulate``: a calibration test profile through the virtual IMU → recording file."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer
from rich.markup import escape
from rich.progress import Progress

from imunav.cli._console import make_console
from imunav.cli._lazy import lazy
from imunav.errors import ConfigError, InvalidInputError
from imunav.files import check_outputs, write_json
from imunav.units import DEG

io = lazy("imunav.io")
presets = lazy("imunav.sim.presets")
sim = lazy("imunav.sim")

PROFILES = ("static", "multiposition", "ratetable", "sixposition", "ferraris")

_HELP = f"""Simulate a test PROFILE ({", ".join(PROFILES)}) with a virtual IMU and write the recording.

multiposition is the 100-position static test, ratetable the 120-step +-250 deg/s rate-table test (Günhan 2014, section 4.1), sixposition each axis up then down, ferraris six poses plus a full turn about each axis, static one level position for --duration seconds.  The error model is a preset (--preset, 'ideal' = no errors) or a TOML file (--model).  The format follows the suffix of --out (.csv .parquet .h5 .mat .npz); the segment table goes next to it as <name>_segments.json (what imunav calibrate --segments reads).  Earth rate and normal gravity are used when --lat-deg is given (else constant 9.80665 m/s^2).

Example: imunav simulate multiposition --preset thesis_sim --fs 100 --seed 1 --out static.npz
"""


def simulate(
    profile: str = typer.Argument(..., help=f"Test profile: {' | '.join(PROFILES)}."),
    out: Path = typer.Option(..., "--out", "-o", help="Recording file to write (format from the suffix)."),
    preset: Optional[str] = typer.Option(None, "--preset", help="Error-model preset (default thesis_sim; 'ideal' = none)."),
    model: Optional[Path] = typer.Option(None, "--model", help="Error model TOML file (instead of --preset)."),
    fs: float = typer.Option(100.0, "--fs", help="Sample rate, Hz."),
    seed: int = typer.Option(0, "--seed", help="Random seed (same seed, same numbers)."),
    dwell: float = typer.Option(30.0, "--dwell", help="Seconds per position / rate step."),
    transition: float = typer.Option(2.0, "--transition", help="Seconds per move / rate ramp."),
    duration: float = typer.Option(600.0, "--duration", help="Duration of the 'static' profile, s."),
    lat_deg: Optional[float] = typer.Option(None, "--lat-deg", help="Latitude, deg (turns on Earth rate and normal gravity)."),
    h_m: float = typer.Option(0.0, "--h-m", help="Height above the ellipsoid, m."),
    earth_rate: Optional[bool] = typer.Option(None, "--earth-rate/--no-earth-rate", help="Earth rate in the gyros (default: on iff --lat-deg)."),
    gravity: Optional[str] = typer.Option(None, "--gravity", help="'normal', 'constant' or m/s^2 (default: normal iff --lat-deg)."),
    segments: Optional[Path] = typer.Option(None, "--segments", help="Segment table to write, .json or .csv (default <out stem>_segments.json)."),
    json_out: Optional[Path] = typer.Option(None, "--json", help="Also write a JSON summary here."),
) -> None:
    seg_path = segments if segments is not None else default_segments_path(out)
    if segments is None and model is not None and seg_path.resolve() == model.expanduser().resolve():
        raise InvalidInputError(f"the default segment table {seg_path} (named after --out) is the --model file "
                                f"{model}; give --segments another path, or another --out")
    check_outputs([model], [out, seg_path, json_out])

    console = make_console(stderr=True)
    try:
        summary = run_simulate(
            profile, out, preset=preset, model=model, fs=fs, seed=seed, dwell=dwell, transition=transition,
            duration=duration, lat_deg=lat_deg, h_m=h_m, earth_rate=earth_rate, gravity=gravity,
            segments=segments, console=console,
        )
    except InvalidInputError as exc:
        console.print(f"[red]error:[/red] {escape(str(exc))}", soft_wrap=True)
        raise typer.Exit(2) from exc
    if json_out is not None:
        write_json(json_out, summary)
    typer.echo(
        f"wrote {summary['file']}: {summary['samples']} samples, {summary['duration_s']:.1f} s at "
        f"{summary['fs_hz']:g} Hz, {summary['segments']} ({summary['error_model']})"
    )


def register(app: typer.Typer) -> None:
    app.command("simulate", help=_HELP)(simulate)


def default_segments_path(out: Path) -> Path:
    """The segment table written beside a recording when ``--segments`` is not given: ``<out stem>_segments.json``."""
    return Path(out).with_name(Path(out).stem + "_segments.json")


def run_simulate(
    profile: str,
    out: Path,
    *,
    preset: str | None = None,
    model: Path | None = None,
    fs: float = 100.0,
    seed: int = 0,
    dwell: float = 30.0,
    transition: float = 2.0,
    duration: float = 600.0,
    lat_deg: float | None = None,
    h_m: float = 0.0,
    earth_rate: bool | None = None,
    gravity: str | None = None,
    segments: Path | None = None,
    console: object | None = None,
) -> dict:
    """What ``imunav simulate`` does, callable from Python; returns the summary dict."""

    if profile not in PROFILES:
        raise InvalidInputError(f"unknown profile {profile!r}; choose one of {', '.join(PROFILES)}")
    if preset is not None and model is not None:
        raise ConfigError("give either --preset or --model, not both")
    lat = None if lat_deg is None else lat_deg * DEG
    if earth_rate is None:
        earth_rate = lat is not None
    if gravity is None:
        gravity = "normal" if lat is not None else "constant"
    g: str | float = gravity
    if gravity not in ("normal", "constant"):
        try:
            g = float(gravity)
        except ValueError as exc:
            raise InvalidInputError(f"--gravity must be 'normal', 'constant' or a number in m/s^2, not {gravity!r}") from exc
        if not (0 < g <= 100):  # NaN fails too
            raise InvalidInputError(f"--gravity {gravity}: must be 'normal', 'constant' or a finite number in (0, 100] "
                                    "(m/s^2)")
    if (earth_rate or g == "normal") and lat is None:
        raise InvalidInputError("Earth rate and normal gravity need --lat-deg (or use --no-earth-rate --gravity constant)")
    kw = {"lat": lat, "h": h_m}
    builders = {
        "static": lambda: sim.static_profile(duration, fs, **kw),
        "multiposition": lambda: sim.hundred_position_profile(fs, dwell, transition, **kw),
        "ratetable": lambda: sim.rate_table_step_profile(fs, dwell, transition, **kw),
        "sixposition": lambda: sim.six_position_profile(fs, dwell, transition, **kw),
        "ferraris": lambda: sim.ferraris_profile(fs, dwell, transition, **kw),
    }
    ideal_kw = {"earth_rate": bool(earth_rate), "transport_rate": False, "gravity": g}
    with Progress(console=console, transient=True) as prog:
        task = prog.add_task(f"simulate {profile}", total=3)
        prof = builders[profile]()
        prog.advance(task)
        name = preset or "thesis_sim"
        if model is not None:
            em = sim.ImuErrorModel.from_toml(model)
            data = _simulate(prof, em, seed, ideal_kw)
            name = em.name or Path(model).stem
        elif name == "ideal":
            data = sim.ideal_imu(prof.trajectory, **ideal_kw)
        else:
            data = _simulate(prof, presets.get(name), seed, ideal_kw)
        prog.advance(task)
        data = data.with_(meta={**dict(data.meta or {}), "profile": profile, "error_model": name, "seed": seed})
        path = io.write_imu(data, out)
        seg_path = segments if segments is not None else default_segments_path(out)
        prof.segments.write(seg_path)
        prog.advance(task)
    s = prof.summary()
    return {
        "file": str(path),
        "segments_file": str(seg_path),
        "profile": profile,
        "error_model": name,
        "seed": seed,
        "samples": s["samples"],
        "fs_hz": s["fs_hz"],
        "duration_s": s["duration_s"],
        "segments": s["segments"],
        "earth_rate": bool(earth_rate),
        "gravity": g,
    }


def _simulate(prof, model, seed, ideal_kw):
    return sim.simulate_imu(prof.trajectory, model, seed, **ideal_kw)
