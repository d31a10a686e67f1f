"""``imunav lab``: the main job (simulated calibration tests and the steps that follow)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer
from rich.markup import escape
from rich.table import Table

from imunav.cli._console import make_console
from imunav.cli._errors import _debug_wanted, fail, one_line
from imunav.cli._lazy import lazy
from imunav.errors import InvalidInputError
from imunav.files import check_outputs, write_json

imunav_lab = lazy("imunav.lab.runner")
imunav_config = lazy("imunav.lab.config")

_HELP = """Run the lab and write a report folder (index.html, summary.md, summary.json, data/, figures/).

With no arguments it runs every step on the built-in virtual IMU (preset thesis_sim): the 100-position static test, the 120-step rate-table test and a 1 h static record are simulated and analysed, a thermal test gives B(T) and S(T), and the calibration is applied to a fresh recording to check the residual errors against the reported uncertainty.

The report folder gets a manifest.json (run id, seed, configuration, every file with its size and SHA-256), written last; a folder that holds another run is refused unless --overwrite, which clears that run first.

With a TOML lab definition (--config) that has [recordings.<name>] tables it runs on real recordings instead (path, format, column mapping, units, which test). A [spec.<parameter>] table gives datasheet limits (pass / fail in the report); a table named after a step sets its options; [lab] sets seed, title and steps. See examples/lab_real.toml and examples/lab_spec.toml. Exit status 1 when a step fails with an error or a [spec] check fails (unless --no-fail), 2 for a bad lab definition.

Example: imunav lab --out lab-report --seed 0
"""


def lab(
    out: Path = typer.Option(Path("lab-report"), "--out", "-o", help="Report folder to write."),
    config: Optional[Path] = typer.Option(None, "--config", "-c", help="Lab definition (TOML)."),
    seed: int = typer.Option(0, "--seed", help="Root random seed (the seed in --config wins)."),
    steps: Optional[str] = typer.Option(None, "--steps", help="Comma-separated step names to run (default: all)."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bars."),
    json_out: Optional[Path] = typer.Option(None, "--json", help="Also copy summary.json here."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Clear a report folder that holds another run "
                                   "(only files of imunav runs) instead of refusing."),
    no_fail: bool = typer.Option(False, "--no-fail", help="Exit 0 even when a [spec] check fails (the report "
                                 "still marks it)."),
) -> None:
    # the inputs are the definition and every file it names (recordings, segment tables, a step's files); parsing
    # it checks it whole (every table, unit, rate, preset and size) before anything is written
    inputs = imunav_config.parse_lab_config(config).inputs if config is not None and config.is_file() else [config]
    check_outputs(inputs, [json_out], run_folders=[out])

    console = make_console(stderr=True)
    try:
        result = imunav_lab.run_lab(
            out, config, seed, steps=None if steps is None else [s.strip() for s in steps.split(",") if s.strip()],
            progress=not quiet, console=console, overwrite=overwrite,
        )
    except InvalidInputError as exc:
        fail(exc)
    table = Table(title=f"imunav lab → {out}")
    table.add_column("step")
    table.add_column("verdict")
    table.add_column("time (s)", justify="right")
    for s in result.steps:
        verdict = "ERROR" if s.error else {None: "n/a", True: "PASS", False: "FAIL"}[s.passed]
        table.add_row(s.title, verdict, f"{s.seconds:.1f}")
    make_console().print(table)
    checks = [c for c in result.spec_checks if c.limit is not None]
    spec_failed = any(c.passed is False for c in checks)
    if checks:
        failed = [c.name for c in checks if c.passed is False]
        make_console().print(f"specification: {len(checks)} checks, {len(failed)} failed"
                        + (f" ({escape(', '.join(failed[:8]))}{' …' if len(failed) > 8 else ''})" if failed else ""),
                        soft_wrap=True, highlight=False)
    debug = _debug_wanted()
    for s in result.steps:  # one line per failed step (its traceback is in the report, and here with --debug)
        if s.error:
            if debug:
                typer.echo(s.error.rstrip(), err=True)
            typer.echo(f"error: lab step {s.name}: {one_line(s.reason or 'failed')} (details in "
                       f"{Path(out) / 'summary.md'})", err=True)
    if json_out is not None:
        write_json(json_out, result.to_dict())
    typer.echo(f"report: {Path(out) / 'index.html'}")
    if result.failed_steps:
        raise typer.Exit(1)
    if spec_failed and not no_fail:  # as imunav batch does; --no-fail to go on
        typer.echo("exit status 1: a [spec] check failed (--no-fail: exit 0)", err=True)
        raise typer.Exit(1)


def register(app: typer.Typer) -> None:
    app.command("lab", help=_HELP)(lab)
