"""Figures of the air-data / Doppler wind filter.

The figure set of O. Akgün, *Integration of an air data system and a Doppler radar via Kalman
filtering* (in Turkish), MSc thesis, Istanbul Technical University, 2002, ch. 6 ("the thesis").
Each function takes results and returns a matplotlib Figure; nothing here computes estimates.
"""

from __future__ import annotations

import numpy as np

__all__ = ["plot_wind", "plot_innovations", "plot_detectors", "plot_long_horizon"]


def _plt():
    # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
    import matplotlib

    matplotlib.use("Agg", force=False)
    # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
    import matplotlib.pyplot as plt

    return plt


def plot_wind(result, data=None, axis_names=("x", "y", "z")):
    """Wind estimate vs truth and the difference-loop wind (the thesis's Figs. 6.1, 6.3, 6.8), with ±σ.

    Parameters
    ----------
    result : WindFilterResult
        Output of :meth:`imunav.airdata.filter.BodyWindFilter.run`; wind in m/s, body axes.
    data : WindScenarioData, optional
        The simulated run, for the true wind.
    axis_names : tuple of str
        Labels of the three axes.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    plt = _plt()
    fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    k = np.arange(result.wind.shape[0])
    for i, ax in enumerate(axes):
        ax.plot(k, result.difference_loop[:, i], color="0.75", lw=0.6, label="difference loop")
        if data is not None:
            ax.plot(k, data.wind_true[:, i], "k:", label="true")
        ax.plot(k, result.wind[:, i], "C0--", label="KF estimate")
        s = np.sqrt(result.cov_diag[:, 3 + i])
        ax.fill_between(k, result.wind[:, i] - s, result.wind[:, i] + s, color="C0", alpha=0.2)
        ax.set_ylabel(f"W_{axis_names[i]} [m/s]")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("step")
    fig.tight_layout()
    return fig


def plot_innovations(result, bound: float = 3.0):
    """Normalised innovations with ±bound lines and rejected samples marked (the thesis's Figs. 6.7, 6.10, 6.13).

    Parameters
    ----------
    result : WindFilterResult
        A filter output with normalised innovations and robust weights.
    bound : float
        Bound drawn at ± ``bound`` (in standard deviations).

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    plt = _plt()
    fig, axes = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
    k = np.arange(result.normalized.shape[0])
    for i, ax in enumerate(axes):
        ax.plot(k, result.normalized[:, i], lw=0.7)
        rej = result.weights[:, i] < 0.5
        ax.plot(k[rej], result.normalized[rej, i], "rx", label="rejected")
        ax.axhline(bound, color="k", ls="--", lw=0.8)
        ax.axhline(-bound, color="k", ls="--", lw=0.8)
        ax.set_ylabel(f"ν̃_{'xyz'[i]}")
    axes[-1].set_xlabel("step")
    fig.tight_layout()
    return fig


def plot_detectors(detection, names=("alg1", "alg2", "alg3")):
    """Detector statistics with their thresholds (calibrated solid, thesis dashed) (the thesis's Figs. 6.14, 6.16).

    Parameters
    ----------
    detection : dict
        Detector statistics and thresholds (:func:`imunav.filters.faults.detector_statistics`).
    names : tuple of str
        The detectors drawn.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    plt = _plt()
    fig, axes = plt.subplots(len(names), 1, figsize=(8, 2.4 * len(names)), sharex=True)
    axes = np.atleast_1d(axes)
    for ax, n in zip(axes, names):
        d = detection.detectors[n]
        ax.plot(d.statistic, lw=0.8)
        ax.axhline(d.threshold, color="g", label=f"calibrated {d.threshold:.1f}")
        if np.isfinite(d.thesis_threshold):
            ax.axhline(d.thesis_threshold, color="r", ls="--", label=f"thesis {d.thesis_threshold:.1f}")
        if d.first_alarm >= 0:
            ax.axvline(d.first_alarm, color="k", ls=":")
        ax.set_ylabel(n)
        ax.legend(fontsize=8, loc="upper left")
    axes[-1].set_xlabel("step")
    fig.tight_layout()
    return fig


def plot_long_horizon(result, flight=None):
    """Long-horizon wind estimate (NED) with ±σ and, when given, the flight's true wind.

    Parameters
    ----------
    result : LongHorizonResult
        Output of :meth:`imunav.airdata.filter.LongHorizonFilter.run`; wind in m/s, NED.
    flight : object, optional
        The simulated flight (:func:`imunav.sim.flight.simulate_flight`), for the true wind.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    plt = _plt()
    fig, axes = plt.subplots(3, 1, figsize=(9, 7), sharex=True)
    for i, ax in enumerate(axes):
        if flight is not None:
            ax.plot(flight.t, flight.wind_ned[:, i], color="0.7", lw=0.5, label="true (mean + gust)")
        ax.plot(result.t, result.wind[:, i], "C0", lw=0.8, label="estimate")
        ax.fill_between(result.t, result.wind[:, i] - result.wind_std[:, i],
                        result.wind[:, i] + result.wind_std[:, i], color="C0", alpha=0.2)
        ax.plot(result.t, result.mean_wind[:, i], "C1--", lw=1.0, label="mean-wind state")
        ax.set_ylabel(f"W_{'NED'[i]} [m/s]")
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel("t [s]")
    fig.tight_layout()
    return fig
