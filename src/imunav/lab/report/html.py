"""A small, dependency-free HTML report builder.

The report is one self-contained file: CSS inline, figures embedded as
base64 PNG, no JavaScript (so it renders identically in any browser and
produces no console errors).  Compute code never plots: callers make
matplotlib figures with the ``plot`` functions of each area and hand them to
:meth:`Section.figure`.
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import io
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from imunav import __version__
from imunav.files import atomic_path

__all__ = ["Report", "Section", "Parameter"]

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;margin:2rem auto;max-width:1100px;color:#1b1f23;line-height:1.45}
h1{font-size:1.7rem;margin-bottom:.2rem}h2{font-size:1.3rem;border-bottom:1px solid #d0d7de;padding-bottom:.2rem;margin-top:2rem}
h3{font-size:1.05rem}.sub{color:#57606a;margin-top:0}
table{border-collapse:collapse;margin:.6rem 0 1rem 0;font-size:.88rem}
th,td{border:1px solid #d0d7de;padding:.25rem .55rem;text-align:right}th{background:#f6f8fa}
td.l,th.l{text-align:left}caption{caption-side:bottom;color:#57606a;font-size:.82rem;padding-top:.3rem;text-align:left}
figure{margin:1rem 0}figure img{max-width:100%;border:1px solid #eaeef2}figcaption{color:#57606a;font-size:.85rem}
.pass{color:#1a7f37;font-weight:600}.fail{color:#cf222e;font-weight:600}.na{color:#57606a}
.badge{display:inline-block;padding:.05rem .5rem;border-radius:1rem;font-size:.8rem;margin-left:.5rem}
.badge.pass{background:#dafbe1}.badge.fail{background:#ffebe9}.badge.na{background:#eaeef2}
nav ul{columns:2;font-size:.9rem}pre{background:#f6f8fa;padding:.6rem;overflow-x:auto;font-size:.82rem}
"""


def _fmt(x: Any, digits: int = 5) -> str:
    if x is None:
        return "–"
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, (int,)) and not isinstance(x, bool):
        return str(x)
    try:
        v = float(x)
    except (TypeError, ValueError):
        return html.escape(str(x))
    if math.isnan(v):
        return "NaN"
    if v == 0:
        return "0"
    if 1e-3 <= abs(v) < 1e5:
        return f"{v:.{digits}g}"
    return f"{v:.{max(digits - 1, 1)}e}"


#: Table columns whose boolean / None cells are drawn as PASS / FAIL / n/a badges.
_VERDICT_COLUMNS = ("verdict", "passed", "pass")


def _verdict(passed: bool | None) -> str:
    if passed is None:
        return '<span class="badge na">n/a</span>'
    return '<span class="badge pass">PASS</span>' if passed else '<span class="badge fail">FAIL</span>'


@dataclass(frozen=True)
class Parameter:
    """One estimated parameter with its 1σ uncertainty, unit and optional truth / limit.

    Attributes
    ----------
    name : str
        Parameter name.
    value : float
        Estimate, in ``unit``.
    sigma : float or None
        1σ standard error, in ``unit``.
    unit : str
        Display unit.
    truth : float or None
        True value (simulation), in ``unit``.
    limit : str or None
        The limit as text (:meth:`imunav.lab.report.spec.SpecLimit.describe`).
    passed : bool or None
        Verdict against the limit.
    """

    name: str
    value: float
    sigma: float | None = None
    unit: str = ""
    truth: float | None = None
    limit: str | None = None
    passed: bool | None = None


@dataclass
class Section:
    """A titled part of a report, filled with text, tables and figures.

    Attributes
    ----------
    title : str
        Heading.
    passed : bool or None
        Verdict shown beside the heading (None: none).
    """

    title: str
    passed: bool | None = None
    _parts: list[str] = field(default_factory=list)

    def text(self, paragraph: str) -> "Section":
        """A paragraph of plain text (escaped).

        Parameters
        ----------
        paragraph : str
            The text.

        Returns
        -------
        Section
            ``self``, so that calls chain.
        """
        self._parts.append(f"<p>{html.escape(paragraph)}</p>")
        return self

    def code(self, text: str) -> "Section":
        """Preformatted text (a command line, a configuration).

        Parameters
        ----------
        text : str
            The text (escaped).

        Returns
        -------
        Section
            ``self``, so that calls chain.
        """
        self._parts.append(f"<pre>{html.escape(text)}</pre>")
        return self

    def table(
        self,
        rows: Sequence[Mapping[str, Any]] | Any,
        caption: str | None = None,
        columns: Sequence[str] | None = None,
        digits: int = 5,
    ) -> "Section":
        """A table from a list of dicts or a pandas DataFrame (index kept as first column).

        Parameters
        ----------
        rows : sequence of mapping, or pandas.DataFrame
            The rows.
        caption : str, optional
            Caption shown under it.
        columns : sequence of str, optional
            Columns shown, in order (default: all, in order of appearance).
        digits : int
            Significant digits of floats.

        Returns
        -------
        Section
            ``self``, so that calls chain.
        """
        if isinstance(rows, pd.DataFrame):
            df = rows.reset_index() if rows.index.name or not isinstance(rows.index, pd.RangeIndex) else rows
            rows = df.to_dict(orient="records")
        rows = list(rows)
        cols = list(columns) if columns else (list(rows[0].keys()) if rows else [])
        head = "".join(f'<th class="l">{html.escape(str(c))}</th>' if i == 0 else f"<th>{html.escape(str(c))}</th>" for i, c in enumerate(cols))
        body = []
        for r in rows:
            cells = []
            for i, c in enumerate(cols):
                v = r.get(c)
                cls = ' class="l"' if i == 0 or isinstance(v, str) else ""
                if str(c).lower() in _VERDICT_COLUMNS and (v is None or isinstance(v, (bool, np.bool_))):
                    cells.append(f"<td>{_verdict(None if v is None else bool(v))}</td>")
                    continue
                cells.append(f"<td{cls}>{_fmt(v, digits)}</td>")
            body.append("<tr>" + "".join(cells) + "</tr>")
        cap = f"<caption>{html.escape(caption)}</caption>" if caption else ""
        self._parts.append(f"<table>{cap}<thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>")
        return self

    def parameters(self, params: Iterable[Parameter], caption: str | None = None) -> "Section":
        """Table of parameters: value ± 1σ, unit, truth (if known), error in σ, limit, verdict.

        Parameters
        ----------
        params : iterable of Parameter
            The parameters.
        caption : str, optional
            Caption shown under it.

        Returns
        -------
        Section
            ``self``, so that calls chain.
        """
        rows = []
        for p in params:
            row: dict[str, Any] = {
                "parameter": p.name,
                "value": p.value,
                "±1σ": p.sigma,
                "unit": p.unit,
            }
            if p.truth is not None:
                row["truth"] = p.truth
                row["error / σ"] = (p.value - p.truth) / p.sigma if p.sigma else None
            if p.limit is not None:
                row["limit"] = p.limit
            row["verdict"] = p.passed
            rows.append(row)
        cols: list[str] = []
        for r in rows:
            for k in r:
                if k not in cols:
                    cols.append(k)
        self.table([{**{c: None for c in cols}, **r} for r in rows], caption, cols)
        # replace yes/no verdict cells with badges
        self._parts[-1] = self._parts[-1].replace("<td>yes</td>", f"<td>{_verdict(True)}</td>").replace(
            "<td>no</td>", f"<td>{_verdict(False)}</td>"
        ).replace("<td>–</td></tr>", f"<td>{_verdict(None)}</td></tr>")
        return self

    def figure(self, fig: Any, caption: str | None = None, dpi: int = 110) -> "Section":
        """Embed a matplotlib figure as a PNG (the figure is closed afterwards).

        Parameters
        ----------
        fig : matplotlib.figure.Figure
            The figure.
        caption : str, optional
            Caption shown under it.
        dpi : int
            Resolution, dots per inch.

        Returns
        -------
        Section
            ``self``, so that calls chain.
        """
        # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
        import matplotlib.pyplot as plt

        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
        plt.close(fig)
        data = base64.b64encode(buf.getvalue()).decode("ascii")
        cap = f"<figcaption>{html.escape(caption)}</figcaption>" if caption else ""
        alt = html.escape(caption or self.title)
        self._parts.append(f'<figure><img alt="{alt}" src="data:image/png;base64,{data}">{cap}</figure>')
        return self

    def image(self, path: str | Path, caption: str | None = None) -> "Section":
        """Embed a PNG file (e.g. a figure a step already saved).

        Parameters
        ----------
        path : str or pathlib.Path
            The PNG file.
        caption : str, optional
            Caption shown under it.

        Returns
        -------
        Section
            ``self``, so that calls chain.
        """
        data = base64.b64encode(Path(path).read_bytes()).decode("ascii")
        cap = f"<figcaption>{html.escape(caption)}</figcaption>" if caption else ""
        alt = html.escape(caption or Path(path).stem)
        self._parts.append(f'<figure><img alt="{alt}" src="data:image/png;base64,{data}">{cap}</figure>')
        return self

    def html(self, anchor: str) -> str:
        """The section as HTML.

        Parameters
        ----------
        anchor : str
            ``id`` of the ``<section>`` element (for the table of contents).

        Returns
        -------
        str
            The HTML fragment.
        """
        return f'<section id="{anchor}"><h2>{html.escape(self.title)}{_verdict(self.passed) if self.passed is not None else ""}</h2>{"".join(self._parts)}</section>'


class Report:
    """An HTML report made of sections.

    Parameters
    ----------
    title : str
        Title of the page.
    subtitle : str, optional
        Line under the title.

    Examples
    --------
    >>> r = Report("IMU lab", "virtual IMU, seed 0")
    >>> s = r.section("Noise").text("Allan deviation of the gyro.")
    >>> "<h2>Noise</h2>" in r.to_html()
    True
    """

    def __init__(self, title: str, subtitle: str | None = None) -> None:
        self.title = title
        self.subtitle = subtitle
        self.sections: list[Section] = []

    def section(self, title: str, passed: bool | None = None) -> Section:
        """Add a section at the end.

        Parameters
        ----------
        title : str
            Heading.
        passed : bool, optional
            Verdict shown beside the heading.

        Returns
        -------
        Section
            The new section, to fill.
        """
        s = Section(title, passed)
        self.sections.append(s)
        return s

    @property
    def passed(self) -> bool | None:
        verdicts = [s.passed for s in self.sections if s.passed is not None]
        return None if not verdicts else all(verdicts)

    def to_html(self) -> str:
        """The whole report as one self-contained HTML page.

        Returns
        -------
        str
            The page (inline CSS, embedded images, no JavaScript).
        """
        stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
        toc = "".join(
            f'<li><a href="#s{i}">{html.escape(s.title)}</a> {_verdict(s.passed) if s.passed is not None else ""}</li>'
            for i, s in enumerate(self.sections)
        )
        sub = f'<p class="sub">{html.escape(self.subtitle)}</p>' if self.subtitle else ""
        overall = self.passed
        verdict = "" if overall is None else f"<p>Overall: {_verdict(overall)}</p>"
        body = "".join(s.html(f"s{i}") for i, s in enumerate(self.sections))
        return (
            "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{html.escape(self.title)}</title><style>{_CSS}</style></head><body>"
            f"<h1>{html.escape(self.title)}</h1>{sub}<p class=\"sub\">imunav {__version__} · {stamp}</p>{verdict}"
            f"<nav><ul>{toc}</ul></nav>{body}</body></html>"
        )

    def write(self, path: str | Path) -> Path:
        """Write the report atomically.

        Parameters
        ----------
        path : str or pathlib.Path
            Output file (``.html``).

        Returns
        -------
        pathlib.Path
            The file written.
        """

        p = Path(path)
        with atomic_path(p) as tmp:
            tmp.write_text(self.to_html(), encoding="utf-8")
        return p
