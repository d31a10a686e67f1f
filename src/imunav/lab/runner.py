"""The lab: imunav's main job, a sequence of steps writing one report folder.

``run_lab(out_dir)`` runs the steps named in :data:`STEPS` in order.  A step
is a module ``imunav.lab.steps.<name>`` with

* ``TITLE: str`` and
* ``run(ctx: LabContext) -> StepResult``,
* optionally ``report(section, result, ctx)`` to add its own tables and
  figures to the HTML report (default: the summary as a table, figures
  embedded),
* optionally ``requires(lab, earlier) -> list[str]``: the earlier steps it
  takes its inputs from, called for every step before the first one runs (a
  :class:`~imunav.errors.ConfigError` when no earlier step gives them: the
  lab is refused whole, nothing written).  A step whose input step failed is
  not run (recorded as failed, with the reason).

Steps share objects through ``ctx.artifacts`` (a dict); the keys written by
each step are listed in its module docstring.  Each step's options come from
the TOML table named after it (``ctx.options``); ``[lab]`` holds
``seed``, ``title`` and ``steps`` (a subset / order of :data:`STEPS`).

Two modes (:func:`parse_lab_config` validates the TOML into a
:class:`LabConfig`):

* **virtual IMU** (no ``[recordings]``): ``simulate_tests`` makes the test
  recordings with the built-in virtual IMU, the other steps analyse them;
* **real recordings**: ``[recordings.<name>]`` tables name files, their format,
  column mapping and units, and which test each one is (see
  :mod:`imunav.lab.steps.recordings`); the ``recordings`` step loads them into
  the same artifacts and the simulation-only steps (:data:`SIMULATION_ONLY`)
  are left out of the default step list.

A ``[spec.<parameter>]`` table (min / max, unit; names of
:mod:`imunav.lab.report.catalog`) is a datasheet-style specification: every
parameter the steps report in ``StepResult.parameters`` is checked against
it and the report opens with the pass / fail table.

Outputs in ``out_dir`` (each written atomically): ``summary.json`` (machine
readable: every step's summary, timing, verdict, error), ``summary.md`` and
``index.html`` (the report), plus whatever the steps write (``data/``,
``figures/``), and last ``manifest.json`` (:mod:`imunav.lab.runfolder`: run id,
seed, configuration, every file with size and SHA-256).  A folder holding
another run is refused unless ``overwrite=True``.  A step that raises is
recorded with its traceback and the remaining steps still run, except those that take their inputs from it.

Example
-------
>>> from imunav.lab.runner import run_lab                         # doctest: +SKIP
>>> result = run_lab("lab-report", rng=0)                         # doctest: +SKIP
"""

from __future__ import annotations

import contextlib
import errno
import importlib
import os
import re
import time
import traceback
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Mapping

import numpy as np
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from imunav import __version__
from imunav.errors import ConfigError
from imunav.files import atomic_path, json_text, jsonable
from imunav.lab.config import (
    SIMULATION_ONLY,
    STEPS,
    LabConfig,
    available_steps,
    load_lab_config,
    parse_lab_config,
)
from imunav.lab.report.catalog import calibration_estimates, expand_spec, noise_estimates
from imunav.lab.report.lab import display_parameters, embed_png, lab_markdown, write_lab_html
from imunav.lab.report.spec import check_spec
from imunav.lab.runfolder import RunFolder
from imunav.lab.steps._api import LabContext, StepResult, _NullProgress
from imunav.lab.steps.recordings import LOADED, read_recordings
from imunav.results import Result

__all__ = ["STEPS", "SIMULATION_ONLY", "LabConfig", "LabContext", "StepResult", "StepRecord", "LabResult", "run_lab",
           "load_lab_config", "parse_lab_config", "available_steps", "embed_png", "display_parameters",
           "harvest_parameters"]

@dataclass(frozen=True)
class StepRecord(Result):
    """One step's outcome inside a lab run.

    Parameters
    ----------
    name : str
        Step module name (``imunav.lab.steps.<name>``).
    title : str
        The step's ``TITLE``.
    result : StepResult or None
        What the step returned (None when it raised).
    seconds : float
        Wall-clock duration of the step, s.
    error : str, optional
        Traceback of the exception the step raised, or why it did not run (None: it finished).
    """

    name: str
    title: str
    result: StepResult | None
    seconds: float
    error: str | None = None

    @property
    def passed(self) -> bool | None:
        return False if self.error else (self.result.passed if self.result else None)

    @property
    def reason(self) -> str | None:
        """Why the step failed, in one line: the exception's last line (None: it finished)."""
        if not self.error:
            return None
        lines = [ln.strip() for ln in self.error.strip().splitlines() if ln.strip()]
        return re.sub(r"^(?:\w+\.)+(?=\w+: )", "", lines[-1]) if lines else None  # the class without its module

    def to_dict(self) -> dict:
        """JSON-ready form (the record in ``summary.json``).

        Returns
        -------
        dict
            ``name``, ``title``, ``seconds``, ``passed``, the step result's keys and ``error`` when it failed.
        """
        d = {"name": self.name, "title": self.title, "seconds": round(self.seconds, 3), "passed": self.passed}
        if self.result is not None:
            d.update(self.result.to_dict())
            d["passed"] = self.passed
        if self.error:
            d["error"] = self.error
        return d


@dataclass(frozen=True)
class LabResult(Result):
    """A lab run: its folder, step records and overall verdict.

    Parameters
    ----------
    out_dir : pathlib.Path
        The report folder.
    seed : int
        Root seed of the run.
    steps : list of StepRecord
        One record per step, in run order.
    seconds : float
        Wall-clock duration of the whole lab, s.
    spec_checks : list of imunav.lab.report.SpecCheck
        Every estimated parameter checked against the ``[spec]`` limits (empty without a spec).
    """

    out_dir: Path
    seed: int
    steps: list[StepRecord]
    seconds: float
    spec_checks: list[Any] = field(default_factory=list)

    @property
    def spec_passed(self) -> bool | None:
        """All limits of the ``[spec]`` met (None without a spec)."""
        v = [c.passed for c in self.spec_checks if c.passed is not None]
        return None if not v else all(v)

    @property
    def passed(self) -> bool | None:
        v = [s.passed for s in self.steps if s.passed is not None]
        if self.spec_passed is not None:
            v.append(self.spec_passed)
        return None if not v else all(v)

    @property
    def failed_steps(self) -> list[str]:
        return [s.name for s in self.steps if s.error]

    def to_dict(self) -> dict:
        """JSON-ready form (the content of ``summary.json``).

        Returns
        -------
        dict
            ``imunav_version``, ``seed``, ``seconds``, ``passed``, ``spec_passed``, ``spec_checks`` and ``steps``.
        """
        return {
            "imunav_version": __version__,
            "seed": self.seed,
            "seconds": round(self.seconds, 3),
            "passed": self.passed,
            "spec_passed": self.spec_passed,
            "spec_checks": [c.to_dict() for c in self.spec_checks],
            "steps": [s.to_dict() for s in self.steps],
        }


# ---------------------------------------------------------------------------
# running
# ---------------------------------------------------------------------------


def _write_text(path: Path, text: str) -> None:
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def _seed_of(rng: Any) -> int:
    if rng is None:
        return 0
    if isinstance(rng, (int, np.integer)):
        if int(rng) < 0:
            raise ConfigError(f"the lab seed must be a non-negative integer, got {rng}")
        return int(rng)
    if isinstance(rng, np.random.Generator):
        return int(rng.integers(0, 2**31 - 1))
    raise ConfigError(f"rng must be an integer seed or a numpy Generator, not {type(rng).__name__}")


def run_lab(
    out_dir: str | os.PathLike[str],
    config: str | os.PathLike[str] | Mapping[str, Any] | None = None,
    rng: Any = 0,
    *,
    steps: list[str] | None = None,
    progress: bool = True,
    console: Any = None,
    overwrite: bool = False,
) -> LabResult:
    """Run the lab steps and write the report folder.

    The report folder is a run folder (:mod:`imunav.lab.runfolder`): a folder that
    holds another run is refused unless ``overwrite`` (which removes only the
    files imunav runs wrote), and ``manifest.json`` (run id, seed,
    configuration, every file with its size and SHA-256) is written last; an
    interrupted or failed lab removes its files and leaves ``FAILED``.  A
    :class:`~imunav.errors.ConfigError` raised by a step (a misconfigured
    lab) ends the lab; any other failing step is reported and the others run.

    Parameters
    ----------
    out_dir : str or os.PathLike
        Report folder (created; new, empty, or an imunav run folder with ``overwrite``).
    config : str, os.PathLike, Mapping or None
        TOML file or dict (see :func:`load_lab_config`); None = defaults (the built-in virtual IMU).
    rng : int or numpy.random.Generator or None
        Root seed (a Generator contributes one drawn integer; None: 0); ``[lab] seed`` in the config wins.
    steps : list of str, optional
        Step names to run (default ``[lab] steps`` or :data:`STEPS`).
    progress : bool
        Show rich progress bars.
    console : rich.console.Console, optional
        Console to draw the progress on.
    overwrite : bool
        Clear a report folder that holds another run instead of refusing.

    Returns
    -------
    LabResult
        The run, also written as ``summary.json``.

    Raises
    ------
    ConfigError
        If the configuration is invalid, a step name is unknown, the step list is empty or ``rng`` is a
        negative integer or of another type.
    """
    typed = parse_lab_config(config)
    cfg = load_lab_config(config)
    seed = typed.seed if typed.seed is not None else _seed_of(rng)
    names = list(steps if steps is not None else typed.default_steps())
    known = available_steps()
    bad = [s for s in names if s not in known]
    if bad:
        raise ConfigError(f"unknown lab step(s) {bad}; available: {known}")
    if not names:
        raise ConfigError("no lab step to run (the step list is empty); name steps from: " + ", ".join(known))
    out = Path(out_dir)
    needs = _step_inputs(typed, names)

    inputs = typed.inputs
    params = {"config": str(typed.source) if typed.source is not None else jsonable(cfg), "steps": names,
              "title": typed.title}
    # the recordings are read against their tables before the run folder exists: a unit, a rate or a column
    # that contradicts the file is a ConfigError naming the table and key, and nothing is written
    loaded = read_recordings(typed.recordings, str(typed.source or "lab configuration")) \
        if "recordings" in names and typed.recordings else None
    with RunFolder(out, "lab", seed=seed, parameters=params, overwrite=overwrite, inputs=inputs):
        return _run_steps(out, names, seed, cfg, typed, progress, console, loaded, needs)


#: errno of a write the file system refuses (file too large, no space, quota, read-only): it ends the lab (exit 2,
#: the run folder FAILED), as it would any command, instead of a step's failure in a report that looks complete.
_REFUSED_WRITE = frozenset({errno.EFBIG, errno.ENOSPC, errno.EDQUOT, errno.EROFS})


def _step_inputs(typed: LabConfig, names: list[str]) -> dict[str, list[str]]:
    """Each step's ``requires(lab, earlier)``, before any step runs: step -> the earlier steps it takes inputs
    from; a step whose inputs no earlier step gives is a ConfigError naming the definition."""
    needs: dict[str, list[str]] = {}
    for i, name in enumerate(names):
        requires = getattr(importlib.import_module(f"imunav.lab.steps.{name}"), "requires", None)
        if requires is None:
            continue
        try:
            needs[name] = list(requires(typed, names[:i]))
        except ConfigError as exc:
            where = f"{typed.source}: " if typed.source is not None else ""
            raise ConfigError(f"{where}{exc} (steps: {', '.join(names)})") from None
    return needs


def _run_steps(out: Path, names: list[str], seed: int, cfg: dict, typed: LabConfig, progress: bool,
               console: Any, loaded: dict | None = None, needs: Mapping[str, list[str]] | None = None) -> LabResult:
    """The body of :func:`run_lab` inside its run folder: every step, then summary.json / .md and index.html."""
    if progress:
        prog_cm: Any = Progress(
            TextColumn("{task.description}"), BarColumn(), TextColumn("{task.percentage:>3.0f}%"),
            TimeElapsedColumn(), console=console, transient=False,
        )
    else:
        prog_cm = contextlib.nullcontext(_NullProgress())

    records: list[StepRecord] = []
    t_lab = time.perf_counter()
    with prog_cm as prog:
        ctx = LabContext(out_dir=out, seed=seed, progress=prog, config=cfg, lab=typed)
        if loaded is not None:
            ctx.artifacts[LOADED] = loaded
        overall = prog.add_task(f"lab ({len(names)} steps)", total=len(names))
        for name in names:
            mod = importlib.import_module(f"imunav.lab.steps.{name}")
            title = getattr(mod, "TITLE", name)
            ctx.step = name
            prog.update(overall, description=f"lab: {title}")
            t0 = time.perf_counter()
            before = {k: id(v) for k, v in ctx.artifacts.items()}
            failed = [r.name for r in records if r.error and r.name in (needs or {}).get(name, [])]
            if failed:  # its inputs are missing: not run on a stand-in
                which = f"the {failed[0]} step, which" if len(failed) == 1 else \
                    f"the {', '.join(failed[:-1])} and {failed[-1]} steps, which"
                records.append(StepRecord(name, title, None, 0.0, f"not run: it takes its input from {which} failed"))
                prog.advance(overall)
                continue
            try:
                res = mod.run(ctx)
                if not isinstance(res, StepResult):
                    raise TypeError(f"step {name}.run returned {type(res).__name__}, not StepResult")
                if not res.parameters:
                    found = harvest_parameters({k: v for k, v in ctx.artifacts.items() if before.get(k) != id(v)})
                    if found:
                        res = replace(res, parameters=found)
                records.append(StepRecord(name, title, res, time.perf_counter() - t0))
            except ConfigError:
                raise  # the lab is configured wrongly: a user error, not a step's result (the run folder fails)
            except OSError as exc:
                if exc.errno in _REFUSED_WRITE:  # the file system refused a write: the run fails, not the step
                    raise
                records.append(StepRecord(name, title, None, time.perf_counter() - t0, traceback.format_exc()))
            except Exception:  # a failing step is reported; the others still run
                records.append(StepRecord(name, title, None, time.perf_counter() - t0, traceback.format_exc()))
            prog.advance(overall)
        prog.update(overall, description="lab: done")
    checks = _spec_checks(records, typed.spec)
    result = LabResult(out, seed, records, time.perf_counter() - t_lab, checks)
    _write_text(out / "summary.json", json_text(result.to_dict()))
    _write_text(out / "summary.md", lab_markdown(result))
    write_lab_html(result, ctx, typed.title)
    return result


def harvest_parameters(objects: Mapping[str, Any]) -> dict[str, tuple[float, float | None]]:
    """Spec-checkable parameters of the results a step left in the artifacts.

    Recognises calibrations (:class:`imunav.calib.CalibrationResult` /
    :class:`imunav.calib.ImuCalibration` with standard errors) and noise fits
    (:class:`imunav.noise.NoiseFit` of a gyro or accelerometer triad), also
    inside dicts, lists and tuples one level down; names as in
    :mod:`imunav.lab.report.catalog`.  Steps that fill ``StepResult.parameters``
    themselves are not harvested.

    Parameters
    ----------
    objects : Mapping
        Artifacts a step added or replaced (name -> object).

    Returns
    -------
    dict
        ``{name: (value_si, sigma_si)}``; objects that are not recognised, or fail to convert, are skipped.
    """

    out: dict[str, tuple[float, float | None]] = {}

    def visit(o: Any, depth: int) -> None:
        cls = type(o).__name__
        if cls == "CalibrationResult":
            out.update(calibration_estimates(o.calibration, o.stderr))
        elif cls == "ImuCalibration" and getattr(o, "stderr", None):
            out.update(calibration_estimates(o, o.stderr))
        elif cls == "NoiseFit" and getattr(o, "quantity", None) in ("gyro", "accel") and len(o.channels) == 3:
            out.update(noise_estimates(o, o.quantity))
        elif depth < 2 and isinstance(o, Mapping):
            for v in o.values():
                visit(v, depth + 1)
        elif depth < 2 and isinstance(o, (list, tuple)):
            for v in o:
                visit(v, depth + 1)

    for v in objects.values():
        try:
            visit(v, 0)
        except Exception:  # noqa: BLE001 - harvesting is best effort; the step's own report is unaffected
            continue
    return out


def _spec_checks(records: list[StepRecord], spec: Mapping[str, Any]) -> list[Any]:
    """Every parameter the steps estimated, checked against the ``[spec]`` limits."""

    est: dict[str, tuple[float, float | None]] = {}
    for r in records:
        if r.result is not None:
            est.update(r.result.parameters)
    if not spec:
        return []
    return check_spec(est, expand_spec(spec, list(est)))


