"""Figures of calibration results (compute code never plots; these take results)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from imunav.files import atomic_path

__all__ = ["plot_residuals", "plot_temperature_fit", "plot_magnetometer", "save_figure"]


def _plt() -> Any:
    # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
    import matplotlib

    matplotlib.use("Agg", force=False)
    # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig: Any, path: str | os.PathLike[str], dpi: int = 110) -> Path:
    """Save a figure atomically (temp file in the same folder, then rename) and close it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or os.PathLike
        Output file; the format follows its suffix.
    dpi : int
        Resolution, dots per inch.

    Returns
    -------
    pathlib.Path
        The file written.
    """

    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=dpi, bbox_inches="tight")
    finally:
        _plt().close(fig)
    return Path(path)


def plot_residuals(result: Any) -> Any:
    """One panel per fit: residual of every position / step and axis (raw units).

    Parameters
    ----------
    result : CalibrationResult
        A calibration result.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    plt = _plt()
    res = {k: np.atleast_2d(np.asarray(v, float).T).T for k, v in result.residuals.items()}
    n = max(len(res), 1)
    fig, axes = plt.subplots(n, 1, figsize=(8, 2.4 * n), squeeze=False)
    for ax, (k, r) in zip(axes[:, 0], res.items()):
        r = r if r.ndim == 2 else r[:, None]
        for j in range(r.shape[1]):
            ax.plot(np.arange(len(r)), r[:, j], ".-", lw=0.6, ms=3, label="xyz"[j] if r.shape[1] == 3 else None)
        ax.axhline(0, color="k", lw=0.5)
        cond = result.condition.get(k.replace("_norm", "").replace("_direction", ""), None)
        ax.set_title(f"{result.method}: {k} residuals" + (f" (design condition {cond:.3g})" if cond else ""), fontsize=9)
        ax.set_xlabel("position / step / pair")
        ax.set_ylabel("raw units")
        if r.shape[1] == 3:
            ax.legend(fontsize=7, ncol=3)
    fig.tight_layout()
    return fig


def plot_temperature_fit(fit: Any, title: str = "") -> Any:
    """Parameter vs temperature with every fitted order, and the residuals (after Günhan 2014, Figs. 6.1-6.10).

    Parameters
    ----------
    fit : TemperatureFit
        The fits of one parameter (temperature in °C).
    title : str
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    plt = _plt()
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    t = fit.temp_c
    tt = np.linspace(t.min(), t.max(), 300)
    a1.plot(t, fit.values, "ko", label="measured")
    for f in fit.fits:
        lw = 2.0 if f.order == fit.chosen_order else 0.8
        a1.plot(tt, f.curve(tt), lw=lw, label=f"order {f.order} (MSE {f.mse:.3g}, LOO {f.loo_mse:.3g})")
        a2.plot(t, f.residuals, ".-", lw=lw, label=f"order {f.order}")
    a1.set_title(title or f"{fit.model} fit, chosen order {fit.chosen_order}", fontsize=9)
    a1.legend(fontsize=7)
    a2.axhline(0, color="k", lw=0.5)
    a2.set_xlabel("temperature, °C")
    a2.set_ylabel("residual")
    fig.tight_layout()
    return fig


def plot_magnetometer(h: Any, cal: Any) -> Any:
    """Y-Z, Z-X, X-Y projections before and after calibration (after Atasoy's thesis, Figs. 7.61-7.69).

    Parameters
    ----------
    h : array_like, shape (N, 3)
        Raw magnetometer samples.
    cal : MagCalibration
        The calibration applied.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    plt = _plt()
    h = np.asarray(h, float)
    hc = cal.apply(h)
    fig, axes = plt.subplots(2, 3, figsize=(10, 6.5))
    for row, (data, lab) in enumerate(((h, "raw"), (hc, "calibrated"))):
        for col, (i, j) in enumerate(((1, 2), (2, 0), (0, 1))):
            ax = axes[row, col]
            ax.plot(data[:, i], data[:, j], ".", ms=1.5)
            ax.set_aspect("equal", adjustable="datalim")
            ax.set_title(f"{lab} {'xyz'[i]}-{'xyz'[j]}", fontsize=9)
    q = cal.quality
    fig.suptitle(
        f"{cal.method}: |h| spread {100 * q.get('norm_spread_centred_raw', np.nan):.2f} % → "
        f"{100 * q.get('norm_spread_after', np.nan):.2f} %, coverage {100 * q.get('coverage', np.nan):.0f} %",
        fontsize=9,
    )
    fig.tight_layout()
    return fig
