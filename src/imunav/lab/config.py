"""The lab definition: a TOML file (or dict) validated into a :class:`LabConfig`.

Tables: ``[lab]`` (seed, title, steps), ``[recordings.<name>]`` (real recordings,
:mod:`imunav.lab.steps.recordings`), ``[spec.<parameter>]`` (datasheet limits,
:mod:`imunav.lab.report.spec`) and one table of options per step.  The runner is
:func:`imunav.lab.runner.run_lab`, which re-exports everything here.
"""

from __future__ import annotations

import importlib
import os
import pkgutil
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import imunav.lab.steps as pkg
from imunav.errors import ConfigError
from imunav.lab.report import SpecLimit, load_spec
from imunav.lab.steps._api import LabContext
from imunav.lab.steps.recordings import RecordingSpec, parse_recordings
from imunav.toml import read_toml

__all__ = ["STEPS", "SIMULATION_ONLY", "LabConfig", "available_steps", "parse_lab_config", "load_lab_config"]


#: Step modules (``imunav.lab.steps.<name>``) run by default, in order.
STEPS: list[str] = [
    "simulate_tests",
    "calibration",
    "noise",
    "temperature",
    "compensation",
    "attitude",
    "airdata",
]


def available_steps() -> list[str]:
    """Names of the step modules present in :mod:`imunav.lab.steps`.

    Returns
    -------
    list of str
        Sorted public module names of the package (each a valid ``[lab] steps`` entry and option table).
    """

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
    seed : int or None
        Root seed of the lab's random streams (None: the caller's ``rng``).
    title : str
        Report title.
    steps : tuple of str or None
        Step names in order (None: :meth:`default_steps` for the mode).
    recordings : dict
        Name -> :class:`imunav.lab.steps.recordings.RecordingSpec` (empty: the built-in virtual IMU).
    spec : dict
        Parameter name -> :class:`imunav.lab.report.SpecLimit` (datasheet limits).
    options : dict
        Step name -> its option table.
    source : pathlib.Path or None
        The TOML file (None for a dict).
    named : tuple of pathlib.Path
        The files the step tables name (an error model, GNSS/INS inputs), found by each step's ``check``.
    """

    seed: int | None = None
    title: str = "imunav lab"
    steps: tuple[str, ...] | None = None
    recordings: dict[str, RecordingSpec] = field(default_factory=dict)
    spec: dict[str, SpecLimit] = field(default_factory=dict)
    options: dict[str, dict[str, object]] = field(default_factory=dict)
    source: Path | None = None
    named: tuple[Path, ...] = ()

    @property
    def inputs(self) -> list[Path]:
        """Every file the definition names and the lab reads: the TOML file itself, each recording and its
        segment table, and the files of the step tables (:attr:`named`).  The command line checks its outputs
        against them before any work (:func:`imunav.files.check_outputs`)."""
        recs = [p for r in self.recordings.values() for p in (r.path, r.segments) if p is not None]
        return [p for p in (self.source, *recs, *self.named) if p is not None]

    @property
    def mode(self) -> str:
        """``"recordings"`` (real data) or ``"virtual"`` (built-in virtual IMU)."""
        return "recordings" if self.recordings else "virtual"

    def default_steps(self) -> list[str]:
        """Steps to run: ``steps`` if given, else the defaults for the mode.

        Returns
        -------
        list of str
            ``steps``; else, with recordings, ``"recordings"`` followed by the :data:`STEPS` that are not
            :data:`SIMULATION_ONLY`; else :data:`STEPS`.
        """
        if self.steps is not None:
            return list(self.steps)
        if self.recordings:
            return ["recordings"] + [s for s in STEPS if s not in SIMULATION_ONLY and s != "recordings"]
        return list(STEPS)


def _read_toml(config: str | os.PathLike[str] | Mapping[str, Any]) -> tuple[dict, str, Path | None]:
    if isinstance(config, Mapping):
        return dict(config), "lab configuration", None
    p = Path(config)
    return read_toml(p, "lab configuration"), str(p), p


def parse_lab_config(config: str | os.PathLike[str] | Mapping[str, Any] | None) -> LabConfig:
    """Validate a lab definition (TOML file or dict) into a :class:`LabConfig`.

    Schema (every table optional)::

        [lab]                    seed = 0, title = "...", steps = ["recordings", ...]
        [recordings.<name>]      a real recording (see imunav.lab.steps.recordings)
        [spec.<parameter>]       datasheet limit: min / max, unit, description
        [<step>]                 options of a step (e.g. [simulate_tests], [temperature])

    Parameters
    ----------
    config : str, os.PathLike, Mapping or None
        Path of a TOML file, or its tables as a dict (a ``_base_dir`` key sets the folder relative recording
        paths are resolved against); None gives the default :class:`LabConfig`.

    Returns
    -------
    LabConfig
        The validated definition.

    Raises
    ------
    ConfigError
        If the file is missing or not TOML, or a table, key, option, step name or value is unknown or of the
        wrong type; the message names the file, table and key.
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

        recs = parse_recordings(cfg["recordings"], base_dir, where)
    spec: dict[str, Any] = {}
    if "spec" in cfg:

        try:
            spec = load_spec({"spec": cfg["spec"]})
        except ConfigError as exc:
            raise ConfigError(f"{where}: {exc}") from exc
    options = {k: dict(v) for k, v in cfg.items() if k not in ("lab", "spec", "recordings")}
    named = _check_steps(options, base_dir, where)
    return LabConfig(
        seed=lab.get("seed"), title=lab.get("title", "imunav lab"),
        steps=tuple(lab["steps"]) if "steps" in lab else None, recordings=recs, spec=spec,
        options=options, source=path, named=tuple(named),
    )


def _check_steps(options: Mapping[str, Mapping[str, Any]], base_dir: Path, where: str) -> list[Path]:
    """Each step table checked whole by its step's ``check(ctx)`` (when the step has one), before any step
    runs; the files the tables name."""
    named: list[Path] = []
    for name, table in options.items():
        check = getattr(importlib.import_module(f"imunav.lab.steps.{name}"), "check", None)
        if check is None:
            continue
        ctx = LabContext(out_dir=Path("."), seed=0, progress=None, config={name: dict(table), "_base_dir": str(base_dir)},
                         step=name)
        try:
            named += check(ctx)
        except ConfigError as exc:
            raise ConfigError(f"{where}: {exc}") from None
    return named


def _step_options(name: str) -> list[str] | None:
    """Option names a step accepts in its table: its ``OPTIONS`` or the keys of its ``_DEFAULTS`` (None: unchecked)."""
    mod = importlib.import_module(f"imunav.lab.steps.{name}")
    opts = getattr(mod, "OPTIONS", None)
    if opts is None and isinstance(getattr(mod, "_DEFAULTS", None), Mapping):
        opts = list(mod._DEFAULTS)
    return None if opts is None else list(opts)


def load_lab_config(config: str | os.PathLike[str] | Mapping[str, Any] | None) -> dict:
    """Parse and check a lab configuration (TOML file or dict); returns the tables as a dict.

    The checks are those of :func:`parse_lab_config` (which gives the typed
    form); unknown tables or ``[lab]`` keys raise :class:`~imunav.errors.ConfigError`.

    Parameters
    ----------
    config : str, os.PathLike, Mapping or None
        Path of a TOML file or its tables as a dict; None gives ``{}``.

    Returns
    -------
    dict
        The raw tables; read from a file, with ``_base_dir`` set to the file's folder.
    """
    if config is None:
        return {}
    parse_lab_config(config)
    cfg, _, path = _read_toml(config)
    if path is not None:
        cfg["_base_dir"] = str(path.parent)
    return cfg
