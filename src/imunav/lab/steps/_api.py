"""The lab step API: what every step of ``imunav lab`` gets (:class:`LabContext`) and returns (:class:`StepResult`).

A step is a module ``imunav.lab.steps.<name>`` with ``TITLE: str`` and
``run(ctx: LabContext) -> StepResult`` (see :mod:`imunav.lab.runner`).  These types
sit here, below both the steps and the runner, so that a step never imports
the runner that imports it.
"""

from __future__ import annotations

import contextlib
import math
import zlib
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from imunav.errors import ConfigError
from imunav.files import claim_run_file, jsonable
from imunav.results import Result
from imunav.sim import presets

__all__ = ["StepResult", "LabContext", "MAX_SAMPLES", "SIMULATED_TESTS", "check_preset", "check_samples",
           "recordings_before"]

#: The most samples (or epochs) one lab step may simulate: about the reference machine's 24 GiB at the
#: simulator's ~600 bytes per sample (:mod:`imunav.cli._limits`); a larger request is refused when the lab
#: definition is checked, before any step runs.
MAX_SAMPLES = 4e7
#: The recordings the ``simulate_tests`` step makes (its ``tests`` option chooses among them; all by default).
SIMULATED_TESTS = ("hundred_position", "rate_table", "static_long")


@dataclass(frozen=True)
class StepResult(Result):
    """What a lab step returns.

    Attributes
    ----------
    summary : dict
        JSON-able dict of the step's key figures.
    figures : list of pathlib.Path
        PNG files written by the step (embedded in the HTML report).
    passed : bool or None
        Verdict against the step's acceptance, or None when it has none.
    tables : list of (str, list of dict)
        Optional ``(caption, rows)`` pairs for the report.
    notes : list of str
        Optional paragraphs for the report.
    parameters : dict
        Estimated parameters checked against the lab's ``[spec]``: ``{name: (value_si, sigma_si)}`` with the
        names of :mod:`imunav.lab.report.catalog` (``gyro_bias_x``, ``accel_vrw_z``, ...).
    """

    summary: dict
    figures: list[Path] = field(default_factory=list)
    passed: bool | None = None
    tables: list[tuple[str, list[dict]]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    parameters: dict[str, tuple[float, float | None]] = field(default_factory=dict)

    def to_dict(self) -> dict:
        """JSON-ready form (NaN / inf as None).

        Returns
        -------
        dict
            ``summary``, ``figures`` (paths as strings), ``passed`` and, when there are any, ``parameters``
            as ``{name: {"value_si", "sigma_si"}}``.
        """
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
    out_dir : pathlib.Path
        The report folder (exists).
    seed : int
        The lab's root seed; use :meth:`rng` for a step's own stream.
    progress : rich.progress.Progress
        Progress display (or a silent stand-in): ``task = ctx.progress.add_task("…", total=n)``.
    artifacts : dict
        Shared objects between steps (recordings, true models, …).
    config : dict
        The whole lab configuration (parsed TOML).
    step : str
        Name of the running step (set by the runner).
    lab : imunav.lab.config.LabConfig or None
        The typed lab definition.
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

    def step_options(self, defaults: Mapping[str, Any], positive: Iterable[str] = ()) -> dict[str, Any]:
        """The step's option table over its defaults, checked.

        Parameters
        ----------
        defaults : mapping
            Every option the step knows, with its default value.
        positive : iterable of str
            Options that must be positive finite numbers (not booleans).

        Returns
        -------
        dict
            ``defaults`` updated with :attr:`options`.

        Raises
        ------
        ConfigError
            If the table has an option not in ``defaults``, or an option of ``positive`` is not a positive number.
        """
        given = self.options
        unknown = set(given) - set(defaults)
        if unknown:
            raise ConfigError(f"[{self.step}]: unknown option(s) {sorted(unknown)}; allowed: {sorted(defaults)}")
        opts = {**defaults, **given}
        for k in positive:
            v = opts[k]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
                raise ConfigError(f"[{self.step}] {k} must be a positive number, got {opts[k]!r}")
        return opts

    def rng(self, *key: int | str) -> np.random.Generator:
        """Independent, reproducible generator for ``(seed, step, *key)``.

        Parameters
        ----------
        *key : int or str
            Sub-stream key (strings hashed with CRC-32, integers taken modulo 2**32).

        Returns
        -------
        numpy.random.Generator
            PCG64 generator seeded with ``SeedSequence([seed, step, *key])``.
        """
        words = [self.seed] + [_word(k) for k in (self.step, *key)]
        return np.random.default_rng(np.random.SeedSequence(words))

    def path(self, *parts: str) -> Path:
        """A path inside ``out_dir`` (parent folders created).

        Parameters
        ----------
        *parts : str
            Path components below ``out_dir``.

        Returns
        -------
        pathlib.Path
            ``out_dir / parts...``; its parent folder exists, and the path is recorded as the run's
            (:func:`imunav.files.claim_run_file`: a failed or killed lab's folder knows it).
        """
        p = self.out_dir.joinpath(*parts)
        p.parent.mkdir(parents=True, exist_ok=True)
        claim_run_file(p)
        return p

    @contextlib.contextmanager
    def task(self, description: str, total: float | None = None) -> Iterator[Any]:
        """Progress task as a context manager; yields ``advance(n=1)``.

        Parameters
        ----------
        description : str
            Label of the task.
        total : float, optional
            Total amount of work (None: unknown).

        Yields
        ------
        callable
            ``advance(n=1)``: adds ``n`` to the completed work; on exit the task shows 100 %.
        """
        tid = self.progress.add_task(description, total=total)
        try:
            yield lambda n=1: self.progress.advance(tid, n)
        finally:  # a finished task shows 100 %, also one of unknown length (total=None)
            self.progress.update(tid, total=total if total is not None else 1, completed=total if total is not None else 1)


def check_samples(where: str, what: str, n: float) -> None:
    """Refuse a step option set that asks for more than :data:`MAX_SAMPLES` samples.

    Parameters
    ----------
    where : str
        The table and keys, for the message (``"[simulate_tests] static_duration_s x fs"``).
    what : str
        The request in words.
    n : float
        How many samples it asks for.

    Raises
    ------
    ConfigError
        When ``n`` is beyond :data:`MAX_SAMPLES` (or not finite).
    """
    if not (math.isfinite(n) and n <= MAX_SAMPLES):
        raise ConfigError(f"{where}: {what} = {n:.3g} samples, beyond the lab's limit of {MAX_SAMPLES:.3g} per step "
                          f"(about 24 GiB of memory); reduce it")


def check_preset(table: str, name: Any) -> None:
    """Refuse a ``preset`` option that names no IMU preset of :mod:`imunav.sim.presets`.

    Parameters
    ----------
    table : str
        The step table, for the message (``"[gins]"``).
    name : object
        The option's value.

    Raises
    ------
    ConfigError
        Naming the table, the key and the known presets.
    """
    if name not in presets.names():
        raise ConfigError(f"{table} preset: unknown IMU preset {name!r}; known presets: {', '.join(presets.names())}")


def recordings_before(lab: Any, earlier: Iterable[str]) -> dict[str, str]:
    """The recordings the steps before a step will have left, and which step leaves each.

    Parameters
    ----------
    lab : imunav.lab.config.LabConfig
        The typed lab definition.
    earlier : iterable of str
        The steps that run before it, in order.

    Returns
    -------
    dict
        Recording artifact name (``"hundred_position"``, ``"rate_table"``, ``"static_long"``, ``"multipose"``)
        -> the step that makes it (``simulate_tests`` with its ``tests``, or ``recordings`` with its tables).
    """
    made: dict[str, str] = {}
    for step in earlier:
        if step == "simulate_tests":
            tests = dict(getattr(lab, "options", {}) or {}).get("simulate_tests", {}).get("tests", SIMULATED_TESTS)
            made.update({t: step for t in tests})
        elif step == "recordings":
            made.update({spec.artifact: step for spec in (getattr(lab, "recordings", {}) or {}).values()})
    return made


def _word(k: int | str) -> int:
    if isinstance(k, (int, np.integer)):
        return int(k) & 0xFFFFFFFF
    return zlib.crc32(str(k).encode("utf-8"))  # stable across runs (unlike hash())
