"""Figures of the noise analysis (matplotlib, object API: no global pyplot state).

Every function takes results and returns a :class:`matplotlib.figure.Figure`;
compute code never plots.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Sequence

import numpy as np

from imunav.noise.allan import AllanResult
from imunav.noise.fit import NoiseFit, avar_term
from imunav.noise.psd import PsdFit, PsdResult

if TYPE_CHECKING:  # annotations only
    from matplotlib.figure import Figure

__all__ = ["plot_allan", "plot_psd", "plot_curve_fits"]

_TERM_STYLE = {"Q": ":", "N": "--", "B": "-.", "K": (0, (5, 1, 1, 1)), "R": (0, (1, 2))}


def _figure(figsize: tuple[float, float]) -> Figure:
    """A new figure, constrained layout."""
    # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
    from matplotlib.figure import Figure

    return Figure(figsize=figsize, constrained_layout=True)


def _panels(n: int) -> tuple[Figure, np.ndarray]:
    """A figure with ``n`` panels, at most 3 a row; returns the figure and its axes, flat."""
    cols = min(3, n)
    rows = int(math.ceil(n / cols))
    fig = _figure((4.2 * cols, 3.4 * rows))
    return fig, fig.subplots(rows, cols, squeeze=False).ravel()


def plot_allan(result: AllanResult, fit: NoiseFit | None = None, channels: Sequence[int] | None = None,
               title: str | None = None) -> Figure:
    """Allan deviation per channel with its confidence band, the fitted model and each fitted term (dashed).

    Parameters
    ----------
    result : AllanResult
        The Allan deviation (:func:`imunav.noise.allan_deviation`); tau in s.
    fit : NoiseFit, optional
        Fitted noise terms to draw (:func:`imunav.noise.fit_noise`).
    channels : sequence of int, optional
        Channels to draw (default: all).
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (not shown; save it with ``fig.savefig``).
    """
    adev = result.adev if result.adev.ndim == 2 else result.adev[:, None]
    lo = result.adev_lo if result.adev_lo.ndim == 2 else result.adev_lo[:, None]
    hi = result.adev_hi if result.adev_hi.ndim == 2 else result.adev_hi[:, None]
    chans = list(range(adev.shape[1])) if channels is None else list(channels)
    fig, axes = _panels(len(chans))
    t = result.tau
    tt = np.logspace(np.log10(t[0]), np.log10(t[-1]), 200)
    for k, c in enumerate(chans):
        ax = axes[k]
        ax.fill_between(t, lo[:, c], hi[:, c], color="C0", alpha=0.25, lw=0, label=f"{result.ci:.0%} CI")
        ax.loglog(t, adev[:, c], "o-", ms=3, color="C0", label=f"{result.kind} ADEV")
        if fit is not None:
            ax.loglog(tt, np.sqrt(fit.model_avar(tt, c)), "k-", lw=1.2, label="fit")
            for i, nm in enumerate(fit.names):
                if nm in _TERM_STYLE and fit.selected[i, c] and fit.value[i, c] > 0:
                    ax.loglog(tt, fit.value[i, c] * np.sqrt(avar_term(nm, tt)), linestyle=_TERM_STYLE[nm], lw=0.9,
                              label=f"{nm}")
        name = result.channels[c] if result.channels else f"ch{c}"
        ax.set_title(name)
        ax.set_xlabel("tau (s)")
        ax.set_ylabel(f"deviation ({result.units})" if result.units else "deviation")
        ax.grid(True, which="both", alpha=0.3)
        if k == 0:
            ax.legend(fontsize=7)
    for ax in axes[len(chans):]:
        ax.set_visible(False)
    if title:
        fig.suptitle(title)
    return fig


def plot_psd(res: PsdResult, fit: PsdFit | None = None, averaged: PsdResult | None = None,
             title: str | None = None) -> Figure:
    """One-sided PSD per channel (raw in grey, averaged in colour) with the fitted model.

    Parameters
    ----------
    res : PsdResult
        The raw PSD; frequency in Hz.
    fit : PsdFit, optional
        Fitted terms to draw.
    averaged : PsdResult, optional
        An averaged PSD to draw over the raw one.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (not shown; save it with ``fig.savefig``).
    """
    p = res.psd if res.psd.ndim == 2 else res.psd[:, None]
    n_ch = p.shape[1]
    fig, axes = _panels(n_ch)
    for c in range(n_ch):
        ax = axes[c]
        ax.loglog(res.f, p[:, c], color="0.7", lw=0.5, label=res.method)
        if averaged is not None:
            pa = averaged.psd if averaged.psd.ndim == 2 else averaged.psd[:, None]
            ax.loglog(averaged.f, pa[:, c], "o", ms=2.5, color="C1", label=averaged.method)
        if fit is not None:
            f = np.logspace(np.log10(res.f[0]), np.log10(res.f[-1]), 200)
            ax.loglog(f, fit.model(f, c), "k-", lw=1.2, label="fit")
        ax.set_title(res.channels[c] if res.channels else f"ch{c}")
        ax.set_xlabel("f (Hz)")
        ax.set_ylabel(f"PSD ({res.units}^2/Hz, one-sided)" if res.units else "PSD (one-sided)")
        ax.grid(True, which="both", alpha=0.3)
        if c == 0:
            ax.legend(fontsize=7)
    for ax in axes[n_ch:]:
        ax.set_visible(False)
    if title:
        fig.suptitle(title)
    return fig


def plot_curve_fits(tau: np.ndarray, adev: np.ndarray, fits: dict, title: str | None = None) -> Figure:
    """An Allan curve with smooth curve fits (Atasoy's thesis, Figs. 7.57-7.60; see :mod:`imunav.noise.curvefit`).

    Parameters
    ----------
    tau : numpy.ndarray
        Cluster times, s.
    adev : numpy.ndarray
        Allan deviation of one channel at ``tau``.
    fits : dict of str to CurveFit
        The fits (:func:`imunav.noise.curvefit.compare_curve_fits`).
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (not shown; save it with ``fig.savefig``).
    """
    fig = _figure((5, 3.8))
    ax = fig.subplots()
    ax.loglog(tau, adev, "ko", ms=3, label="ADEV")
    tt = np.logspace(np.log10(np.min(tau)), np.log10(np.max(tau)), 300)
    for name, f in fits.items():
        ax.loglog(tt, f(tt), lw=1, label=f"{name} (rms {f.rms_log10:.3g} dex)")
    ax.set_xlabel("tau (s)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    if title:
        ax.set_title(title)
    return fig
