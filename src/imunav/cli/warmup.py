"""``imunav warmup``: compile and cache the numba kernels and the bytecode of the quick-tour commands."""

from __future__ import annotations

import contextlib
import contextvars
import io
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
import typer

from imunav.cli._lazy import lazy

_compile = lazy("imunav.cli._compile")
io_lib = lazy("imunav.io")
main = lazy("imunav.cli.main")
rotation = lazy("imunav.rotation")

def add_magnetometer(src: str = "still.npz", dst: str = "still_mag.npz") -> None:
    """Write ``src`` with a magnetometer (a constant field, 0.1 µT noise): attitude filters compile their
    magnetometer updates on it, as on a PX4 log or a BROAD trial."""
    data = io_lib.read_imu(src)
    rng = np.random.default_rng(0)
    mag = np.array([20.0, 1.0, 45.0]) + 0.1 * rng.standard_normal((data.n, 3))
    io_lib.write_imu(data.with_(mag=mag, mag_unit="uT"), dst)


def rotation_kernels() -> None:
    """Compile the rotation kernels a comparison of attitudes uses (slerp, Euler angles)."""
    t = np.linspace(0.0, 1.0, 11)
    q = rotation.quat_from_euler(0.1 * t, 0.2 * t, 0.3 * t)
    rotation.euler_from_quat(rotation.quat_interp(t, q, t[:-1] + 0.05))
    rotation.quat_multiply(q[:1], q)


#: The quick tour, on small inputs: (what, imunav arguments or a function).  Paths are relative to a scratch
#: folder.  Each step compiles the kernels its command uses, with the array types a real run passes.
TOUR: tuple[tuple[str, tuple[str, ...] | Callable[[], None]], ...] = (
    ("simulate", ("simulate", "static", "--preset", "thesis_sim", "--duration", "300", "--fs", "100",
                  "--out", "still.npz")),
    ("info", ("info", "still.npz")),
    ("noise", ("noise", "still.npz", "--json", "noise.json", "--plot", "allan.png")),
    ("simulate multiposition", ("simulate", "multiposition", "--preset", "thesis_sim", "--fs", "50", "--dwell", "10",
                                "--out", "multi.npz")),
    ("calibrate multiposition", ("calibrate", "multiposition", "multi.npz", "--segments", "multi_segments.json",
                                 "--out", "cal.json")),
    ("compensate", ("compensate", "multi.npz", "--cal", "cal.json", "--out", "compensated.npz")),
    ("attitude run (adaptive)", ("attitude", "run", "still.npz", "--filter", "adaptive")),
    ("attitude run (madgwick_c)", ("attitude", "run", "still.npz", "--filter", "madgwick_c")),
    ("attitude run (mekf)", ("attitude", "run", "still.npz", "--filter", "mekf")),
    ("magnetometer recording", add_magnetometer),
    ("attitude run 9D (adaptive)", ("attitude", "run", "still_mag.npz", "--filter", "adaptive")),
    ("attitude run 9D (madgwick_c)", ("attitude", "run", "still_mag.npz", "--filter", "madgwick_c")),
    ("attitude run 9D (mekf)", ("attitude", "run", "still_mag.npz", "--filter", "mekf")),
    ("rotation kernels", rotation_kernels),
    ("gins simulate", ("gins", "simulate", "--out", "drive", "--duration", "120", "--fs", "50")),
    ("gins run", ("gins", "run", "--config", "drive/kf-gins.yaml", "--out", "drive-run")),
)

_HELP = """Compile the numba kernels of the quick-tour commands and write their bytecode, once, ahead of use.

A first run after an install or upgrade otherwise compiles imunav's numba kernels (tens of seconds on two cores) and, where Python may not write bytecode (PYTHONDONTWRITEBYTECODE=1, pip install --no-compile), compiles the sources at every start.  warmup runs the quick tour (simulate, info, noise, calibrate multiposition, compensate, attitude run, gins run) on small inputs in a scratch folder: numba caches the kernels next to the package where it may write, else in the user's cache folder (or $NUMBA_CACHE_DIR), and the .pyc files of every module the tour imported are written next to the sources.  `make run` calls it after the install.

Example: imunav warmup
"""


def _run_step(argv: Sequence[str] | Callable[[], None]) -> str | None:
    """Run one imunav command (or function) in-process, output swallowed; the last error line on failure.

    Each step runs in a context of its own (:class:`contextvars.Context`), outside warmup's own output
    transaction (:func:`imunav.files.output_transaction`: nested blocks join the outermost one), so that its
    files are in place when it ends, for the next step to read."""
    return contextvars.Context().run(_step, argv)


def _step(argv: Sequence[str] | Callable[[], None]) -> str | None:
    """The body of :func:`_run_step`."""
    if callable(argv):
        try:
            argv()
        except Exception as e:  # noqa: BLE001 - a failed step is reported; its kernels compile on first use
            return f"{type(e).__name__}: {e}"
        return None
    out, err = io.StringIO(), io.StringIO()
    code: object = 0
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main.app(list(argv), standalone_mode=False)
        except SystemExit as e:
            code = e.code
    if code not in (0, None):
        lines = (err.getvalue() or out.getvalue()).strip().splitlines()
        return lines[-1] if lines else f"exit status {code}"
    return None


def warmup(
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Print only the summary line."),
) -> None:
    watch = _compile.watch_compilation()
    t_all = time.perf_counter()
    failed: list[str] = []
    with tempfile.TemporaryDirectory(prefix="imunav-warmup-") as tmp:
        with contextlib.chdir(tmp):
            for what, argv in TOUR:
                t0, n0 = time.perf_counter(), len(watch.kernels)
                error = _run_step(argv)
                if error is not None:
                    failed.append(what)
                if not quiet:
                    state = f"failed: {error}" if error else f"{len(watch.kernels) - n0} kernels compiled"
                    typer.echo(f"  {what:<28} {time.perf_counter() - t0:6.1f} s  {state}")
    bc = _compile.write_bytecode()
    watch.stream = None  # the summary below says it all: no second total at exit
    typer.echo(f"warmup: {len(watch.kernels)} numba kernels compiled in {watch.seconds:.1f} s, "
               f"bytecode of {bc.written} modules written ({bc.current} already current), "
               f"{time.perf_counter() - t_all:.1f} s in all")
    if watch.cache_dirs and not quiet:
        shown = sorted({str(Path(d).parent) if Path(d).name == "__pycache__" else d for d in watch.cache_dirs})
        typer.echo("numba cache: " + ", ".join(shown[:3]) + (f" and {len(shown) - 3} more" if len(shown) > 3 else ""))
    if bc.failed:
        typer.echo(f"warning: no bytecode written for {len(bc.failed)} modules (read-only, e.g. "
                   f"{bc.failed[0]}); set PYTHONPYCACHEPREFIX to a folder you can write and run imunav warmup "
                   "again", err=True)
    if failed:
        typer.echo(f"warning: {len(failed)} warmup step(s) failed ({', '.join(failed)}): their kernels compile "
                   "on first use", err=True)
    sys.stdout.flush()


def register(app: typer.Typer) -> None:
    """Add ``imunav warmup`` to the app."""

    app.command("warmup", help=_HELP)(warmup)
