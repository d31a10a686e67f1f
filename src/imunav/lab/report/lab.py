"""The lab's report: ``summary.md`` and the HTML page ``index.html`` of a lab run, and the helpers steps use to
add to it (:func:`embed_png`, :func:`display_parameters`).

The runner (:func:`imunav.lab.runner.run_lab`) calls :func:`lab_markdown` and :func:`write_lab_html` on its
:class:`~imunav.lab.runner.LabResult`; a step module may add its own section content with ``report(section, result, ctx)``.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from imunav.files import jsonable
from imunav.lab.report.catalog import display_unit, expand_spec, to_display_value
from imunav.lab.report.html import Parameter, Report
from imunav.lab.report.spec import check_spec
from imunav.lab.steps._api import LabContext
from imunav.units import to_display

__all__ = ["lab_markdown", "write_lab_html", "embed_png", "display_parameters"]


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


def lab_markdown(result: Any) -> str:
    """``summary.md`` of a :class:`~imunav.lab.runner.LabResult`: verdicts, specification table, each step's summary and figures.

    Parameters
    ----------
    result : imunav.lab.runner.LabResult
        A finished lab run.

    Returns
    -------
    str
        Markdown text, SI values, figures linked relative to ``result.out_dir``.
    """
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
        # value, its sigma and the limit in one unit: the limit's
        lines += ["", "## Specification", "", "| parameter | value | ±1σ | unit | limit | verdict |",
                  "|---|---|---|---|---|---|"]
        for c in sorted(checks, key=lambda c: (c.passed is not False, c.name)):
            u = c.limit.unit if c.limit.unit else display_unit(c.name)
            v = _to_unit(c.value_si, u) if c.limit.unit else to_display_value(c.name, c.value_si)
            sd = None if c.sigma_si is None else (_to_unit(c.sigma_si, u) if c.limit.unit
                                                  else to_display_value(c.name, c.sigma_si))
            lines.append(f"| {c.name} | {'' if v is None else f'{v:.6g}'} | {'' if sd is None else f'{sd:.3g}'} | "
                         f"{u} | {c.limit.describe()} | {_verdict_word(c.passed)} |")
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
    """Embed a PNG file in a report section (thin alias of ``Section.image``).

    Parameters
    ----------
    section : imunav.lab.report.html.Section
        Section of the HTML report.
    path : str or os.PathLike
        The PNG file.
    caption : str, optional
        Caption (default: the file's stem).
    """
    section.image(path, caption or Path(path).stem)


def display_parameters(
    params: Mapping[str, tuple[float, float | None]],
    spec: Mapping[str, Any] | None = None,
    truth: Mapping[str, float] | None = None,
) -> list[Any]:
    """:class:`imunav.lab.report.Parameter` rows in display units, with limit and verdict from ``spec``.

    Parameters
    ----------
    params : Mapping
        ``{name: (value_si, sigma_si)}`` (names of :mod:`imunav.lab.report.catalog`; ``sigma_si`` may be None).
    spec : Mapping, optional
        Datasheet limits by parameter name (:func:`imunav.lab.report.load_spec`); None: no verdict.
    truth : Mapping, optional
        ``{name: value_si}`` true values (simulations).

    Returns
    -------
    list of imunav.lab.report.Parameter
        One row per entry of ``params``, value, 1-sigma and truth in the catalog's display unit.
    """

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


def write_lab_html(result: Any, ctx: LabContext, title: str) -> None:
    """``index.html`` of a :class:`~imunav.lab.runner.LabResult` in its ``out_dir``: overview, specification, one section per step.

    Parameters
    ----------
    result : imunav.lab.runner.LabResult
        A finished lab run.
    ctx : LabContext
        The run's context (mode, lab definition and its spec).
    title : str
        Page title.
    """

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
        mod = importlib.import_module(f"imunav.lab.steps.{s.name}")
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

    if x is None or not np.isfinite(x):
        return x
    if unit == "abs_ppm":
        return x * 1e6
    return float(to_display(x, unit))
