"""Figures for attitude results (matplotlib; compute code never plots)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from imunav.attitude.rejections import rejected_intervals
from imunav.attitude.result import AttitudeResult
from imunav.files import atomic_path

__all__ = ["plot_euler", "plot_errors", "plot_rejections", "plot_montecarlo_box", "save"]


def _plt():
    # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
    import matplotlib

    matplotlib.use("Agg", force=False)
    # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
    import matplotlib.pyplot as plt

    return plt


def plot_euler(result: AttitudeResult, reference: AttitudeResult | None = None):
    """Roll, pitch, yaw (degrees) against time (with a reference if given).

    Parameters
    ----------
    result : AttitudeResult
        The estimate.
    reference : AttitudeResult, optional
        A reference drawn beside it.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    plt = _plt()
    fig, axs = plt.subplots(3, 1, sharex=True, figsize=(8, 6))
    e = np.degrees(result.euler())
    for i, lab in enumerate(("roll", "pitch", "yaw")):
        axs[i].plot(result.t, e[:, i], lw=0.8, label=result.name or "estimate")
        if reference is not None:
            axs[i].plot(reference.t, np.degrees(reference.euler())[:, i], "k--", lw=0.8, label="reference")
        axs[i].set_ylabel(f"{lab} [deg]")
    axs[0].legend(loc="upper right")
    axs[-1].set_xlabel("time [s]")
    fig.tight_layout()
    return fig


def plot_errors(t: np.ndarray, angles: Any, title: str = ""):
    """BROAD error angles (degrees) against time.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Time, s.
    angles : ErrorAngles
        :func:`imunav.attitude.metrics.error_angles` output, rad.
    title : str
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 3.5))
    for k in ("total", "heading", "inclination"):
        ax.plot(t, np.degrees(getattr(angles, k)), lw=0.7, label=k)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("error [deg]")
    ax.set_title(title)
    ax.legend()
    fig.tight_layout()
    return fig


def plot_rejections(result: AttitudeResult, angles: Any | None = None, title: str = ""):
    """What the filter rejected, and when, beside the reference error (one trial).

    Top: the error angles against the reference (degrees; :func:`imunav.attitude.metrics.error_angles`), with the
    intervals of rejected field shaded; bottom: the per-sample flags ``mag_disturbed``, ``acc_rejected`` and
    ``rest`` as bars against time.  :func:`imunav.attitude.rejections.rejection_summary` gives the same as a line.

    Parameters
    ----------
    result : AttitudeResult
        A run of the MEKF family (its ``flags`` hold the three flags).
    angles : ErrorAngles, optional
        Error angles of ``result`` against a reference, one per sample (no top panel without).
    title : str
        Figure title (e.g. the trial and :meth:`RejectionSummary.line`).

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    plt = _plt()
    rows = 2 if angles is not None else 1
    fig, axs = plt.subplots(rows, 1, sharex=True, figsize=(9, 2.2 + 2.3 * rows), squeeze=False,
                            gridspec_kw={"height_ratios": [3, 1.3][:rows] if rows == 2 else [1]})
    t = np.asarray(result.t, dtype=float)
    names = [("mag_disturbed", "field rejected", "tab:red"), ("acc_rejected", "accel. rejected", "tab:orange"),
             ("rest", "rest", "tab:green")]
    if angles is not None:
        ax = axs[0, 0]
        for k in ("total", "heading", "inclination"):
            ax.plot(t, np.degrees(getattr(angles, k)), lw=0.7, label=k)
        if "mag_disturbed" in result.flags:
            for i, (a, b) in enumerate(rejected_intervals(t, np.asarray(result.flags["mag_disturbed"], bool))):
                ax.axvspan(a, b, color="tab:red", alpha=0.15, lw=0, label="field rejected" if i == 0 else None)
        ax.set_ylabel("error [deg]")
        ax.legend(loc="upper right", fontsize=8)
    ax = axs[-1, 0]
    for j, (k, _, col) in enumerate(names):
        if k in result.flags:
            for a, b in rejected_intervals(t, np.asarray(result.flags[k], bool)):
                ax.broken_barh([(a, max(b - a, t[1] - t[0]))], (j - 0.4, 0.8), color=col)
    ax.set_yticks(range(len(names)), [lab for _, lab, _ in names])
    ax.set_ylim(-0.6, len(names) - 0.4)
    ax.set_xlabel("time [s]")
    axs[0, 0].set_title(title, fontsize=9)
    fig.tight_layout()
    return fig


def plot_montecarlo_box(rmse: Mapping[str, np.ndarray]):
    """Box plots of the per-run pitch and roll RMSE of each filter (log scale).

    Parameters
    ----------
    rmse : mapping
        Filter name to its ``(n_runs, 2)`` (pitch, roll) RMSE [deg], e.g.
        :func:`imunav.scenarios.paper_rmse` of a Monte Carlo.

    Returns
    -------
    matplotlib.figure.Figure
        Two panels (pitch, roll), one box per filter, RMSE in deg on a log axis.
    """
    plt = _plt()
    fig, axs = plt.subplots(1, 2, figsize=(9, 4))
    names = list(rmse)
    for j, lab in enumerate(("pitch", "roll")):
        axs[j].boxplot([rmse[n][:, j] for n in names])
        axs[j].set_xticks(range(1, len(names) + 1), names)
        axs[j].set_yscale("log")
        axs[j].set_ylabel(f"{lab} RMSE [deg]")
    fig.tight_layout()
    return fig


def save(fig: Any, path: str | Path) -> Path:
    """Save atomically (:func:`imunav.files.atomic_path`: hidden temp file, usual file mode, rename).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or pathlib.Path
        Output file; the format follows its suffix.

    Returns
    -------
    pathlib.Path
        The file written.
    """

    p = Path(path)
    with atomic_path(p) as tmp:
        fig.savefig(tmp, dpi=120, format=p.suffix.lstrip(".").lower() or "png")
    return p
