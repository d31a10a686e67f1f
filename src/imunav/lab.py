"""The lab: imunav's main job, a sequence of steps writing one report folder.

``run_lab(out_dir)`` runs the steps named in :data:`STEPS` in order.  A step
is a module ``imunav.labsteps.<name>`` with

* ``TITLE: str`` and
* ``run(ctx: LabContext) -> StepResult``,
* optionally ``report(section, result, ctx)`` to add its own tables and
  figures to the HTML report (default: the summary as a table, figures
  embedded).

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
  :mod:`imunav.labsteps.recordings`); the ``recordings`` step loads them into
  the same artifacts and the simulation-only steps (:data:`SIMULATION_ONLY`)
  are left out of the default step list.

A ``[spec.<parameter>]`` table (min / max, unit; names of
:mod:`imunav.report.catalog`) is a datasheet-style specification: every
parameter the steps report in ``StepResult.parameters`` is checked against
it and the report opens with the pass / fail table.

Outputs in ``out_dir`` (each written atomically): ``summary.json`` (machine
readable: every step's summary, timing, verdict, error), ``summary.md`` and
``index.html`` (the report), plus whatever the steps write (``data/``,
``figures/``), and last ``manifest.json`` (:mod:`imunav.runfolder`: run id,
seed, configuration, every file with size and SHA-256).  A folder holding
another run is refused unless ``overwrite=True``.  A step that raises is
recorded with its traceback and the remaining steps still run.

Example
-------
>>> from imunav.lab import run_lab                                # doctest: +SKIP
>>> result = run_lab("lab-report", rng=0)                         # doctest: +SKIP
"""

from __future__ import annotations

import contextlib
import importlib
import os
import pkgutil
import time
import tomllib
import traceback
import zlib
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Iterator, Mapping

import numpy as np

from imunav.errors import ConfigError
from imunav.io._atomic import json_text, jsonable
from imunav.results import Result

__all__ = ["STEPS", "SIMULATION_ONLY", "LabConfig", "LabContext", "StepResult", "StepRecord", "LabResult", "run_lab",
           "load_lab_config", "parse_lab_config", "available_steps", "embed_png", "display_parameters",
           "harvest_parameters"]

#: Step modules (``imunav.labsteps.<name>``) run by default, in order.
STEPS: list[str] = [
    "simulate_tests",
    "calibration",
    "noise",
    "temperature",
    "compensation",
    "attitude",
    "airdata",
]


@dataclass(frozen=True)
class StepResult(Result):
    """What a lab step returns.

    Attributes
    ----------
    summary : JSON-able dict of the step's key figures.
    figures : PNG files written by the step (embedded in the HTML report).
    passed : verdict against the step's acceptance, or None when it has none.
    tables : optional ``(caption, rows)`` pairs (rows: list of dicts) for the report.
    notes : optional paragraphs for the report.
    parameters : estimated parameters checked against the lab's ``[spec]``:
        ``{name: (value_si, sigma_si)}`` with the names of
        :mod:`imunav.report.catalog` (``gyro_bias_x``, ``accel_vrw_z``, ...).
    """

    summary: dict
    figures: list[Path] = field(default_factory=list)
    passed: bool | None = None
    tables: list[tuple[str, list[dict]]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    parameters: dict[str, tuple[float, float | None]] = field(default_factory=dict)

    def to_dict(self) -> dict:
        d = {
            "summary": jsonable(self.summary),
            "figures": [str(p) for p in self.figures],
            "passed": self.passed,
        }
        if self.parameters:
            d["parameters"] = {k: {"value_si": v, "sigma_si": s} for k, (v, s) in self.parameters.items()}
        return jsonable(d)


class _NullProgress:
    """Stand-in for :class:`rich.progress.Progress` when output is off."""

    def add_task(self, description: str, total: float | None = None, **kw: Any) -> int:
        return 0

    def update(self, task: int, **kw: Any) -> None:
        pass

    def advance(self, task: int, advance: float = 1) -> None:
        pass

    def remove_task(self, task: int) -> None:
        pass


@dataclass
class LabContext:
    """What every step gets.

    Attributes
    ----------
    out_dir : the report folder (exists).
    seed : the lab's root seed; use :meth:`rng` for a step's own stream.
    progress : a :class:`rich.progress.Progress` (or a silent stand-in) for
        progress bars: ``task = ctx.progress.add_task("…", total=n)``.
    artifacts : shared objects between steps (recordings, true models, …).
    config : the whole lab configuration (parsed TOML).
    """

    out_dir: Path
    seed: int
    progress: Any
    artifacts: dict = field(default_factory=dict)
    config: dict = field(default_factory=dict)
    step: str = ""
    lab: Any = None

    @property
    def mode(self) -> str:
        """``"recordings"`` when the lab runs on real recordings, else ``"virtual"``."""
        return getattr(self.lab, "mode", "virtual")

    @property
    def options(self) -> dict:
        """The TOML table of the running step (``[<step name>]``), or {}."""
        return dict(self.config.get(self.step, {}))

    def rng(self, *key: int | str) -> np.random.Generator:
        """Independent, reproducible generator for ``(seed, step, *key)``."""
        words = [self.seed] + [_word(k) for k in (self.step, *key)]
        return np.random.default_rng(np.random.SeedSequence(words))

    def path(self, *parts: str) -> Path:
        """A path inside ``out_dir`` (parent folders created)."""
        p = self.out_dir.joinpath(*parts)
        p.parent.mkdir(parents=True, exist_ok=True)
        return p

    @contextlib.contextmanager
    def task(self, description: str, total: float | None = None) -> Iterator[Any]:
        """Progress task as a context manager; yields ``advance(n=1)``."""
        tid = self.progress.add_task(description, total=total)
        try:
            yield lambda n=1: self.progress.advance(tid, n)
        finally:  # a finished task shows 100 %, also one of unknown length (total=None)
            self.progress.update(tid, total=total if total is not None else 1, completed=total if total is not None else 1)


def _word(k: int | str) -> int:
    if isinstance(k, (int, np.integer)):
        return int(k) & 0xFFFFFFFF
    return zlib.crc32(str(k).encode("utf-8"))  # stable across runs (unlike hash())


@dataclass(frozen=True)
class StepRecord(Result):
    """One step's outcome inside a lab run."""

    name: str
    title: str
    result: StepResult | None
    seconds: float
    error: str | None = None

    @property
    def passed(self) -> bool | None:
        return False if self.error else (self.result.passed if self.result else None)

    def to_dict(self) -> dict:
        d = {"name": self.name, "title": self.title, "seconds": round(self.seconds, 3), "passed": self.passed}
        if self.result is not None:
            d.update(self.result.to_dict())
            d["passed"] = self.passed
        if self.error:
            d["error"] = self.error
        return d


@dataclass(frozen=True)
class LabResult(Result):
    """A lab run: its folder, step records and overall verdict."""

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
        from imunav import __version__

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
# configuration
# ---------------------------------------------------------------------------


def available_steps() -> list[str]:
    """Names of the step modules present in :mod:`imunav.labsteps`."""
    import imunav.labsteps as pkg

    return sorted(m.name for m in pkgutil.iter_modules(pkg.__path__) if not m.name.startswith("_"))


#: Steps that need the built-in virtual IMU (its truth or its simulation) and
#: are left out of the default step list when the configuration has
#: ``[recordings]``: on real data the ``recordings`` step characterises the
#: static record's noise and ``compensation`` calibrates and checks.
SIMULATION_ONLY: frozenset[str] = frozenset(
    {"simulate_tests", "temperature", "calibration", "noise", "attitude", "airdata"}
)

_TOP_LEVEL = ("lab", "recordings", "spec")


@dataclass(frozen=True)
class LabConfig:
    """A validated lab definition (see :func:`parse_lab_config`).

    Attributes
    ----------
    seed : root seed (None: the caller's).
    title : report title.
    steps : step names in order (None: the default for the mode).
    recordings : name -> :class:`imunav.labsteps.recordings.RecordingSpec`
        (empty: the built-in virtual IMU).
    spec : parameter name -> :class:`imunav.report.SpecLimit` (datasheet limits).
    options : step name -> its option table.
    source : the TOML file (None for a dict).
    """

    seed: int | None = None
    title: str = "imunav lab"
    steps: tuple[str, ...] | None = None
    recordings: dict[str, Any] = field(default_factory=dict)
    spec: dict[str, Any] = field(default_factory=dict)
    options: dict[str, dict] = field(default_factory=dict)
    source: Path | None = None

    @property
    def mode(self) -> str:
        """``"recordings"`` (real data) or ``"virtual"`` (built-in virtual IMU)."""
        return "recordings" if self.recordings else "virtual"

    def default_steps(self) -> list[str]:
        if self.steps is not None:
            return list(self.steps)
        if self.recordings:
            return ["recordings"] + [s for s in STEPS if s not in SIMULATION_ONLY and s != "recordings"]
        return list(STEPS)


def _read_toml(config: str | os.PathLike[str] | Mapping[str, Any]) -> tuple[dict, str, Path | None]:
    if isinstance(config, Mapping):
        return dict(config), "lab configuration", None
    p = Path(config)
    if not p.is_file():
        raise ConfigError(f"lab configuration file not found: {p}")
    try:
        return tomllib.loads(p.read_text(encoding="utf-8")), str(p), p
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{p} is not valid TOML: {exc}") from exc


def parse_lab_config(config: str | os.PathLike[str] | Mapping[str, Any] | None) -> LabConfig:
    """Validate a lab definition (TOML file or dict) into a :class:`LabConfig`.

    Schema (every table optional)::

        [lab]                    seed = 0, title = "...", steps = ["recordings", ...]
        [recordings.<name>]      a real recording (see imunav.labsteps.recordings)
        [spec.<parameter>]       datasheet limit: min / max, unit, description
        [<step>]                 options of a step (e.g. [simulate_tests], [temperature])

    Raises :class:`~imunav.errors.ConfigError` naming the file, table and key.
    """
    if config is None:
        return LabConfig()
    cfg, where, path = _read_toml(config)
    base_dir = path.parent if path is not None else Path(str(cfg.pop("_base_dir", ".")))
    cfg.pop("_base_dir", None)
    steps = available_steps()
    for key, value in cfg.items():
        if key not in _TOP_LEVEL and key not in steps:
            raise ConfigError(
                f"{where}: unknown table [{key}]; valid tables are [lab], [recordings.<name>], [spec.<parameter>] "
                f"and the step tables {', '.join(f'[{s}]' for s in steps if s != 'recordings')}"
            )
        if not isinstance(value, Mapping):
            raise ConfigError(f"{where}: '{key}' must be a table ([{key}]), not {type(value).__name__}")
    for key, value in cfg.items():
        allowed = _step_options(key) if key in steps and key not in _TOP_LEVEL else None
        unknown_opts = sorted(set(value) - set(allowed)) if allowed is not None else []
        if unknown_opts:
            raise ConfigError(f"{where}: unknown option(s) {unknown_opts} in [{key}]; allowed: {sorted(allowed)}")
    lab = cfg.get("lab", {})
    unknown = set(lab) - {"seed", "steps", "title"}
    if unknown:
        raise ConfigError(f"{where}: unknown key(s) {sorted(unknown)} in [lab]; allowed: seed, steps, title")
    if "seed" in lab and (not isinstance(lab["seed"], int) or isinstance(lab["seed"], bool) or lab["seed"] < 0):
        raise ConfigError(f"{where}: [lab] seed must be a non-negative integer, got {lab['seed']!r}")
    if "title" in lab and not isinstance(lab["title"], str):
        raise ConfigError(f"{where}: [lab] title must be a string, got {lab['title']!r}")
    if "steps" in lab:
        if not isinstance(lab["steps"], list) or not all(isinstance(s, str) for s in lab["steps"]):
            raise ConfigError(f"{where}: [lab] steps must be a list of step names")
        bad = [s for s in lab["steps"] if s not in steps]
        if bad:
            raise ConfigError(f"{where}: unknown step(s) {bad} in [lab] steps; available: {steps}")
    recs: dict[str, Any] = {}
    if "recordings" in cfg:
        from imunav.labsteps.recordings import parse_recordings

        recs = parse_recordings(cfg["recordings"], base_dir, where)
    spec: dict[str, Any] = {}
    if "spec" in cfg:
        from imunav.report import load_spec

        try:
            spec = load_spec({"spec": cfg["spec"]})
        except ConfigError as exc:
            raise ConfigError(f"{where}: {exc}") from exc
    return LabConfig(
        seed=lab.get("seed"), title=lab.get("title", "imunav lab"),
        steps=tuple(lab["steps"]) if "steps" in lab else None, recordings=recs, spec=spec,
        options={k: dict(v) for k, v in cfg.items() if k not in ("lab", "spec", "recordings")},
        source=path,
    )


def _step_options(name: str) -> list[str] | None:
    """Option names a step accepts in its table: its ``OPTIONS`` or the keys of its ``_DEFAULTS`` (None: unchecked)."""
    mod = importlib.import_module(f"imunav.labsteps.{name}")
    opts = getattr(mod, "OPTIONS", None)
    if opts is None and isinstance(getattr(mod, "_DEFAULTS", None), Mapping):
        opts = list(mod._DEFAULTS)
    return None if opts is None else list(opts)


def load_lab_config(config: str | os.PathLike[str] | Mapping[str, Any] | None) -> dict:
    """Parse and check a lab configuration (TOML file or dict); returns the tables as a dict.

    The checks are those of :func:`parse_lab_config` (which gives the typed
    form); unknown tables or ``[lab]`` keys raise :class:`~imunav.errors.ConfigError`.
    """
    if config is None:
        return {}
    parse_lab_config(config)
    cfg, _, path = _read_toml(config)
    if path is not None:
        cfg["_base_dir"] = str(path.parent)
    return cfg


# ---------------------------------------------------------------------------
# running
# ---------------------------------------------------------------------------


def _write_text(path: Path, text: str) -> None:
    from imunav.io._atomic import atomic_path

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

    The report folder is a run folder (:mod:`imunav.runfolder`): a folder that
    holds another run is refused unless ``overwrite`` (which clears it first),
    and ``manifest.json`` (run id, seed, configuration, every file with its
    size and SHA-256) is written last; an interrupted or failed lab leaves no
    manifest.

    Parameters
    ----------
    out_dir : report folder (created; new, empty, or an imunav run folder with ``overwrite``).
    config : TOML file or dict (see :func:`load_lab_config`); None = defaults
        (the built-in virtual IMU).
    rng : root seed (int) or Generator; ``[lab] seed`` in the config wins.
    steps : step names to run (default ``[lab] steps`` or :data:`STEPS`).
    progress : show rich progress bars.
    console : a :class:`rich.console.Console` to draw on.
    overwrite : clear a report folder that holds another run instead of refusing.

    Returns
    -------
    LabResult (also written as ``summary.json``).
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
    from imunav.runfolder import RunFolder

    inputs = [typed.source] + [r.path for r in typed.recordings.values()] + [
        r.segments for r in typed.recordings.values()]
    params = {"config": str(typed.source) if typed.source is not None else jsonable(cfg), "steps": names,
              "title": typed.title}
    with RunFolder(out, "lab", seed=seed, parameters=params, overwrite=overwrite, inputs=inputs):
        return _run_steps(out, names, seed, cfg, typed, progress, console)


def _run_steps(out: Path, names: list[str], seed: int, cfg: dict, typed: LabConfig, progress: bool,
               console: Any) -> LabResult:
    """The body of :func:`run_lab` inside its run folder: every step, then summary.json / .md and index.html."""
    if progress:
        from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

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
        overall = prog.add_task(f"lab ({len(names)} steps)", total=len(names))
        for name in names:
            mod = importlib.import_module(f"imunav.labsteps.{name}")
            title = getattr(mod, "TITLE", name)
            ctx.step = name
            prog.update(overall, description=f"lab: {title}")
            t0 = time.perf_counter()
            before = {k: id(v) for k, v in ctx.artifacts.items()}
            try:
                res = mod.run(ctx)
                if not isinstance(res, StepResult):
                    raise TypeError(f"step {name}.run returned {type(res).__name__}, not StepResult")
                if not res.parameters:
                    found = harvest_parameters({k: v for k, v in ctx.artifacts.items() if before.get(k) != id(v)})
                    if found:
                        res = replace(res, parameters=found)
                records.append(StepRecord(name, title, res, time.perf_counter() - t0))
            except Exception:  # a failing step is reported; the others still run
                records.append(StepRecord(name, title, None, time.perf_counter() - t0, traceback.format_exc()))
            prog.advance(overall)
        prog.update(overall, description="lab: done")
    checks = _spec_checks(records, typed.spec)
    result = LabResult(out, seed, records, time.perf_counter() - t_lab, checks)
    _write_text(out / "summary.json", json_text(result.to_dict()))
    _write_text(out / "summary.md", _markdown(result))
    _write_html(result, ctx, typed.title)
    return result


def harvest_parameters(objects: Mapping[str, Any]) -> dict[str, tuple[float, float | None]]:
    """Spec-checkable parameters of the results a step left in the artifacts.

    Recognises calibrations (:class:`imunav.calib.CalibrationResult` /
    :class:`imunav.calib.ImuCalibration` with standard errors) and noise fits
    (:class:`imunav.noise.NoiseFit` of a gyro or accelerometer triad), also
    inside dicts, lists and tuples one level down; names as in
    :mod:`imunav.report.catalog`.  Steps that fill ``StepResult.parameters``
    themselves are not harvested.
    """
    from imunav.report.catalog import calibration_estimates, noise_estimates

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
    from imunav.report import check_spec
    from imunav.report.catalog import expand_spec

    est: dict[str, tuple[float, float | None]] = {}
    for r in records:
        if r.result is not None:
            est.update(r.result.parameters)
    if not spec:
        return []
    return check_spec(est, expand_spec(spec, list(est)))


# ---------------------------------------------------------------------------
# report
# ---------------------------------------------------------------------------


def _verdict_word(p: bool | None) -> str:
    return "n/a" if p is None else ("PASS" if p else "FAIL")


def _flat(d: Mapping[str, Any], prefix: str = "") -> list[tuple[str, Any]]:
    rows: list[tuple[str, Any]] = []
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, Mapping):
            rows += _flat(v, key + ".")
        elif isinstance(v, (list, tuple)) and len(v) > 6:
            rows.append((key, f"[{len(v)} values]"))
        else:
            rows.append((key, v))
    return rows


def _markdown(result: LabResult) -> str:
    lines = [
        "# imunav lab",
        "",
        f"seed {result.seed} · {result.seconds:.1f} s · overall: **{_verdict_word(result.passed)}**",
        "",
        "| step | verdict | time (s) |",
        "|---|---|---|",
    ]
    for s in result.steps:
        lines.append(f"| {s.title} (`{s.name}`) | {_verdict_word(s.passed)} | {s.seconds:.1f} |")
    checks = [c for c in result.spec_checks if c.limit is not None]
    if checks:
        lines += ["", "## Specification", "", "| parameter | value (SI) | ±1σ (SI) | limit | verdict |", "|---|---|---|---|---|"]
        for c in sorted(checks, key=lambda c: (c.passed is not False, c.name)):
            lines.append(f"| {c.name} | {c.value_si:.6g} | {'' if c.sigma_si is None else f'{c.sigma_si:.3g}'} | "
                         f"{c.limit.describe()} | {_verdict_word(c.passed)} |")
    for s in result.steps:
        lines += ["", f"## {s.title}", ""]
        if s.error:
            lines += ["Step failed:", "", "```", s.error.rstrip(), "```"]
            continue
        assert s.result is not None
        lines += ["| key | value |", "|---|---|"]
        for k, v in _flat(jsonable(s.result.summary)):
            lines.append(f"| {k} | {v} |")
        for f in s.result.figures:
            rel = os.path.relpath(f, result.out_dir)
            lines += ["", f"![{Path(f).stem}]({rel})"]
    return "\n".join(lines) + "\n"


def embed_png(section: Any, path: str | os.PathLike[str], caption: str | None = None) -> None:
    """Embed a PNG file in a report section (thin alias of ``Section.image``)."""
    section.image(path, caption or Path(path).stem)


def display_parameters(
    params: Mapping[str, tuple[float, float | None]],
    spec: Mapping[str, Any] | None = None,
    truth: Mapping[str, float] | None = None,
) -> list[Any]:
    """:class:`imunav.report.Parameter` rows in display units, with limit and verdict from ``spec``.

    ``params``: ``{name: (value_si, sigma_si)}`` (names of :mod:`imunav.report.catalog`);
    ``truth``: ``{name: value_si}`` (simulations).
    """
    from imunav.report import Parameter, check_spec
    from imunav.report.catalog import display_unit, expand_spec, to_display_value

    lim = expand_spec(spec or {}, list(params)) if spec else {}
    checks = {c.name: c for c in check_spec(params, lim)} if lim else {}
    rows = []
    for name, (v, s) in params.items():
        c = checks.get(name)
        t = None if truth is None or name not in truth else to_display_value(name, truth[name])
        rows.append(Parameter(
            name=name, value=to_display_value(name, v), sigma=to_display_value(name, s), unit=display_unit(name),
            truth=t, limit=None if c is None or c.limit is None else c.limit.describe(),
            passed=None if c is None else c.passed,
        ))
    return rows


def _write_html(result: LabResult, ctx: LabContext, title: str) -> None:
    from imunav.report import Report
    from imunav.report.catalog import display_unit, to_display_value

    mode = "real recordings" if ctx.mode == "recordings" else "built-in virtual IMU"
    rep = Report(title, f"{mode} · seed {result.seed} · {len(result.steps)} steps · {result.seconds:.1f} s")
    ov = rep.section("Overview", result.passed)
    ov.text(
        "Each step below has its own section with tables and figures; every estimated parameter is given "
        "with its 1σ uncertainty" + (" and checked against the datasheet specification of the lab definition."
                                     if result.spec_checks else ".")
    )
    ov.table([{"step": s.title, "name": s.name, "verdict": s.passed, "time (s)": round(s.seconds, 1),
               "parameters": len(s.result.parameters) if s.result else 0,
               "note": "error: see section" if s.error else ""} for s in result.steps], "Steps")
    if result.spec_checks:
        checks = sorted((c for c in result.spec_checks if c.limit is not None),
                        key=lambda c: (c.passed is not False, c.name))
        sec = rep.section("Specification (datasheet limits)", result.spec_passed)
        n_fail = sum(1 for c in checks if c.passed is False)
        sec.text(f"{len(checks)} parameters checked, {n_fail} outside the limits (failed checks first). "
                 "A limit with only a maximum applies to the magnitude; a spec item that no step measured fails.")
        sec.table([{"parameter": c.name,
                    "value": to_display_value(c.name, c.value_si) if c.limit is None or not c.limit.unit
                    else _to_unit(c.value_si, c.limit.unit),
                    "±1σ": None if c.sigma_si is None else (_to_unit(c.sigma_si, c.limit.unit) if c.limit and c.limit.unit
                                                             else to_display_value(c.name, c.sigma_si)),
                    "unit": (c.limit.unit if c.limit and c.limit.unit else display_unit(c.name)),
                    "limit": c.limit.describe() if c.limit else "", "verdict": c.passed} for c in checks],
                  "Parameters against the specification")
    for s in result.steps:
        sec = rep.section(s.title, s.passed)
        if s.error:
            sec.text("This step failed; its traceback follows.")
            sec.code(s.error)
            continue
        assert s.result is not None
        mod = importlib.import_module(f"imunav.labsteps.{s.name}")
        for para in s.result.notes:
            sec.text(para)
        custom = getattr(mod, "report", None)
        if custom is not None:
            custom(sec, s.result, ctx)
            if s.result.parameters and not getattr(mod, "RENDERS_PARAMETERS", False):
                sec.parameters(display_parameters(s.result.parameters, ctx.lab.spec if ctx.lab else None),
                               "Estimated parameters (display units, ±1σ)")
        else:
            sec.table([{"key": k, "value": v} for k, v in _flat(jsonable(s.result.summary))], "summary")
            for caption, rows in s.result.tables:
                sec.table(rows, caption)
            if s.result.parameters:
                sec.parameters(display_parameters(s.result.parameters, ctx.lab.spec if ctx.lab else None),
                               "Estimated parameters (display units, ±1σ)")
            for f in s.result.figures:
                embed_png(sec, f)
    rep.write(result.out_dir / "index.html")


def _to_unit(x: float | None, unit: str) -> float | None:
    from imunav.units import to_display

    if x is None or not np.isfinite(x):
        return x
    if unit == "abs_ppm":
        return x * 1e6
    return float(to_display(x, unit))
