"""Entry point of the ``imunav`` command.

Each command module in :mod:`imunav.cli` exposes ``register(app)``, which adds
its command or command group to the Typer app; :data:`COMMANDS` names them and
:class:`imunav.cli._lazy.LazyGroup` imports a module only when its command is
used, so that ``imunav --help`` starts in a fraction of a second.  Keep the modules thin: they
parse options, call the library and print / write results.  They do not catch
errors: :class:`imunav.cli._errors.ImunavGroup` turns every imunav error and
every OS error into one line on stderr and exit status 2 (a traceback only
with ``--debug``), and any other exception into exit status 1.
"""

from __future__ import annotations

import os

import numpy as np
import typer

from imunav import __version__
from imunav.cli._lazy import LazyGroup

#: The commands, in the order ``imunav --help`` lists them: name (the module ``imunav.cli.<name>``, with a
#: ``register(app)`` function) -> the first sentence of the command's help, listed without importing the
#: module (tests/cli/test_main.py checks each against the command's own help).
COMMANDS: dict[str, str] = {
    "info": "Rate, duration, gaps, saturation, static intervals and per-channel mean/std of a recording.",
    "convert": "Read one IMU (SI, FRD, magnetometer in µT) and write it as an imunav table, atomically.",
    "noise": "Identify the stochastic errors of a static IMU recording: overlapping Allan deviation with "
             "confidence intervals, GLS fit of quantization Q, white noise N, bias instability B, random walk K "
             "and ramp R (with standard errors), the IEEE-952 slope read-outs, and the PSD estimate of N as a "
             "cross-check.",
    "simulate": "Simulate a test PROFILE (static, multiposition, ratetable, sixposition, ferraris) with a virtual "
                "IMU and write the recording.",
    "calibrate": "Calibrate an IMU or magnetometer from a recording; writes the calibration JSON.",
    "compensate": "Compensate a recording with a calibration (accelerometer first, then gyro).",
    "lab": "Run the lab and write a report folder (index.html, summary.md, summary.json, data/, figures/).",
    "attitude": "Attitude filters (Madgwick, Mahony, MEKF, UKF, adaptive, smoother, paper KFs).",
    "zupt": "Foot-mounted INS with zero-velocity updates.",
    "gins": "Loosely coupled GNSS/INS (error-state Kalman filter) on KF-GINS files.",
    "airdata": "Air data + Doppler radar integration: wind-estimating Kalman filter, robust filtering, fault "
               "detection.",
    "batch": "Process a folder of recordings (one per unit of a production batch, or one robot / drone log each) "
             "in parallel, with a summary table and per-unit result files.",
    "warmup": "Compile the numba kernels of the quick-tour commands and write their bytecode, once, ahead of use.",
}


def _no_hugepages() -> None:
    """Ask numpy not to back its large arrays with transparent huge pages in this process (numpy's documented
    ``NUMPY_MADVISE_HUGEPAGE=0``, applied after its import; a value the user set is kept, and child processes get it).

    A command's arrays are written once, front to back, where a huge page saves no measurable time, but on a
    virtual machine that hands its free memory back to the host (free page reporting) each first write of a fresh
    2 MB page cost 10-25 ms of system time: ``imunav gins run`` on a one-hour 200 Hz bag spent 12 s of system time
    in the filter writing its 1.2 GB of covariance records with huge pages, 0.8 s without them (issue 33).  Only the
    command line does this, the process being its own; the library leaves numpy's settings alone."""
    if "NUMPY_MADVISE_HUGEPAGE" in os.environ:
        return
    os.environ["NUMPY_MADVISE_HUGEPAGE"] = "0"
    toggle = getattr(getattr(getattr(np, "_core", None), "multiarray", None), "_set_madvise_hugepage", None)
    if toggle is not None:  # numpy >= 2 (numpy 1.26 reads only the variable, at its import)
        toggle(False)


_no_hugepages()

#: LLVM optimisation level of the numba kernels a command compiles (``NUMBA_OPT``; numba's default is 3)
NUMBA_OPT_LEVEL = "2"


def _numba_opt_level() -> None:
    """Have numba compile the kernels of a command at LLVM level :data:`NUMBA_OPT_LEVEL` instead of its default 3,
    unless the user set ``NUMBA_OPT`` (kept; child processes inherit the choice).

    Set before numba is imported (a command imports it with its library, :mod:`imunav.cli._lazy`); numba reads the
    variable at import and again at each compilation.  Measured on the shared 2-core machine (issue 35; the
    command line, a fresh numba cache each, load 1.5-1.8): the first ``imunav gins run`` on the Jackal bag 26.7 s
    at level 3 -> 23.6 s at level 2 (``gins_run`` 16.9 -> 15.7 s; level 1 saves nothing more; level 0 compiles in
    19 s but its warm run takes 17.8 s against 2.8), the first ``attitude run`` on the PX4 sample unchanged
    (``mekf_core`` 4.2-4.4 s at either level).  The speed of the compiled kernels is unchanged: the one-hour bag
    (benchmarks/bench_gins_log_speed.py) 23.0 -> 24.0 s wall, 23.0 -> 21.2 s CPU (filter 3.20 -> 3.03 s); the
    MEKF 0.71 -> 0.72 and the adaptive MEKF 0.88 -> 0.90 x vqf's time per sample
    (benchmarks/bench_attitude_speed.py, means of five runs each, spread +-0.04).  The outputs of
    ``gins run --smoother`` and ``attitude run`` are bit-identical: without fast-math reassociation the
    optimisation level changes no rounding.  numba's cache does not record the level: a kernel compiled by a
    command serves a library call, and the other way round."""
    os.environ.setdefault("NUMBA_OPT", NUMBA_OPT_LEVEL)


_numba_opt_level()


class _Group(LazyGroup):
    summaries = COMMANDS


app = typer.Typer(
    cls=_Group,
    name="imunav",
    help=(
        "Inertial sensors end to end: simulate, characterize, calibrate IMUs and "
        "magnetometers; attitude and navigation filters.\n\n"
        "Example: imunav lab --out lab-report"
    ),
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_show_locals=False,
    rich_markup_mode=None,
)


@app.callback(invoke_without_command=True)
def _main(
    ctx: typer.Context,
    version: bool = typer.Option(False, "--version", help="Print the version and exit.", is_eager=True),
    debug: bool = typer.Option(False, "--debug", help="On an error, also print the Python traceback."),
) -> None:
    if version:
        typer.echo(__version__)
        raise typer.Exit()
    if ctx.invoked_subcommand is None:
        typer.echo(ctx.get_help())
        raise typer.Exit()


if __name__ == "__main__":  # pragma: no cover
    app()
