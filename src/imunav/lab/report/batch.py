"""The HTML report of a production batch (``imunav batch``): the units table, the unit-to-unit spread with
its figure, estimate against truth for a simulated batch, and the specification checks.

:func:`imunav.lab.batch.write_summary` writes the data files (``summary.csv``, ``summary.json``) and calls
:func:`write_batch_html` for ``index.html``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from imunav.lab.report.catalog import base_name, display_unit, to_display_value
from imunav.lab.report.html import Report

__all__ = ["write_batch_html"]


def write_batch_html(summary: Any, out_dir: Path, title: str) -> Path:
    """Write ``index.html`` of a batch into ``out_dir``.

    Parameters
    ----------
    summary : BatchSummary
        The batch (:class:`imunav.lab.batch.BatchSummary`: table, statistics, spec checks, timing).
    out_dir : Path
        The batch's output folder.
    title : str
        The report title.

    Returns
    -------
    Path
        The HTML file written.
    """
    n = len(summary.table)
    rep = Report(title, f"{n} units · {summary.n_failed} failed to process · {summary.seconds:.1f} s")
    sec = rep.section("Units", summary.passed)
    tab = summary.table
    params = [c for c in tab.columns if c not in ("unit", "status", "passed", "error")
              and not c.endswith("_se") and not c.endswith("_err")]
    sec.text("One row per unit: processing status and the verdict against the specification "
             "(every parameter with a limit must lie inside it). Values in display units; "
             "the per-unit JSON files hold every parameter with its standard error.")

    fams: list[str] = []
    for p in params:
        if base_name(p) not in fams and not base_name(p).endswith("misalignment"):
            fams.append(base_name(p))
    errs_cols = [c for c in tab.columns if c.endswith("_err")]
    short = []
    for r in tab.to_dict(orient="records"):
        row: dict[str, Any] = {"unit": r["unit"], "status": r["status"], "verdict": r["passed"]}
        for f in fams:
            vals = [r.get(f"{f}_{a}") for a in "xyz"]
            row[f"{f} x, y, z ({display_unit(f)})"] = ", ".join(
                "–" if v is None or (isinstance(v, float) and not np.isfinite(v)) else f"{v:.5g}" for v in vals)
        if errs_cols:
            z = [abs(r[c] / r[c[:-4] + "_se"]) for c in errs_cols
                 if isinstance(r.get(c), float) and isinstance(r.get(c[:-4] + "_se"), float) and r[c[:-4] + "_se"] > 0]
            row["max |error|/σ vs truth"] = max(z) if z else None
        if r.get("error"):
            row["error"] = r["error"]
        short.append(row)
    cols: list[str] = []
    for r in short:
        cols += [k for k in r if k not in cols]
    sec.table([{**{c: None for c in cols}, **r} for r in short], "Units (misalignments in the per-unit files and below)", cols)
    if params:
        stats = summary.statistics().loc[[p for p in params if p in summary.statistics().index]]
        stats.insert(0, "unit of measure", [display_unit(p) for p in stats.index])
        stats.index.name = "parameter"
        sec2 = rep.section("Unit-to-unit spread")
        sec2.text("Statistics of each estimated parameter over the batch (display units).")
        sec2.table(stats, "Parameter statistics over the units")
        errs = [c for c in tab.columns if c.endswith("_err")]
        if errs:
            e = tab[errs].apply(pd.to_numeric, errors="coerce")
            se = tab[[c[:-4] + "_se" for c in errs]].apply(pd.to_numeric, errors="coerce").to_numpy()
            with np.errstate(invalid="ignore", divide="ignore"):
                z = np.abs(e.to_numpy() / se)
            rows = [{"parameter": c[:-4], "unit of measure": display_unit(c[:-4]),
                     "RMS error": float(np.sqrt(np.nanmean(e[c].to_numpy() ** 2))),
                     "RMS standard error": float(np.sqrt(np.nanmean(se[:, i] ** 2))),
                     "max |error|/σ": float(np.nanmax(z[:, i])) if np.isfinite(z[:, i]).any() else None}
                    for i, c in enumerate(errs)]
            sec2.table(rows, "Estimate − truth over the units (simulated batch): errors vs reported uncertainty")
        try:
            sec2.figure(_spread_figure(tab, params), "Each parameter over the units (value ± 1σ)")
        except Exception as exc:  # a figure problem must not lose the summary
            sec2.text(f"(figure not drawn: {exc})")
    if summary.spec_checks and any(summary.spec_checks.values()):
        sec3 = rep.section("Specification checks", summary.passed)
        rows = []
        for u, lst in summary.spec_checks.items():
            for c in lst:
                rows.append({"unit": u, "parameter": c["name"],
                             "value": _disp(c["name"], c["value_si"]), "±1σ": _disp(c["name"], c["sigma_si"]),
                             "unit of measure": display_unit(c["name"]), "limit": c["limit"], "verdict": c["passed"]})
        failed = [r for r in rows if r["verdict"] is False]
        sec3.text(f"{len(rows)} checks, {len(failed)} failed." + (" Failed checks first." if failed else ""))
        sec3.table(failed + [r for r in rows if r["verdict"] is not False], "Checks per unit")
    return rep.write(out_dir / "index.html")


def _disp(name: str, v: float | None) -> float | None:
    return to_display_value(name, v)


def _spread_figure(tab: pd.DataFrame, params: list[str]) -> Any:
    # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
    import matplotlib

    matplotlib.use("Agg")
    # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
    import matplotlib.pyplot as plt

    fams: dict[str, list[str]] = {}
    for p in params:
        fams.setdefault(base_name(p), []).append(p)
    n = len(fams)
    cols = min(3, n)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 2.8 * rows), squeeze=False)
    x = np.arange(len(tab))
    for ax, (fam, ps) in zip(axes.flat, fams.items()):
        for j, p in enumerate(ps):
            v = pd.to_numeric(tab[p], errors="coerce").to_numpy()
            s = pd.to_numeric(tab.get(f"{p}_se"), errors="coerce").to_numpy() if f"{p}_se" in tab else None
            ax.errorbar(x + 0.08 * (j - (len(ps) - 1) / 2), v, yerr=s, fmt="o", ms=3, capsize=2,
                        label=p[len(fam) + 1:] or p)
        ax.set_title(f"{fam} [{display_unit(ps[0])}]", fontsize=9)
        ax.set_xlabel("unit #", fontsize=8)
        ax.tick_params(labelsize=7)
        if len(ps) <= 6:
            ax.legend(fontsize=6, ncol=3)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    fig.tight_layout()
    return fig
