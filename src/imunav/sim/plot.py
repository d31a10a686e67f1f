"""Figures of simulated test profiles (compute code never plots; these take results)."""

from __future__ import annotations

from typing import Any

import numpy as np

from imunav.units import G0

__all__ = ["plot_test_recording"]


def plot_test_recording(data: Any, segments: Any = None, title: str = "", max_points: int = 20000) -> Any:
    """Accelerometer (g) and gyro (°/s) of a test recording over time, with the static / rate segments shaded.

    An analogue of Günhan 2014, Figs. 4.6 and 4.11 (Y. Günhan, *Detection and compensation of inertial
    measurement unit errors* (in Turkish), MSc thesis, Hacettepe University, 2014).

    Parameters
    ----------
    data : ImuData
        The recording (SI; drawn in g and °/s).
    segments : Segments, optional
        The test's segment table (:class:`imunav.sim.profiles.Segments`), shaded.
    title : str
        Figure title.
    max_points : int
        At most this many samples are drawn (decimation).

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
    import matplotlib

    matplotlib.use("Agg", force=False)
    # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
    import matplotlib.pyplot as plt

    step = max(1, data.t.size // max_points)
    t = data.t[::step]
    fig, ax = plt.subplots(2, 1, figsize=(10, 5.5), sharex=True)
    for i, lab in enumerate("xyz"):
        ax[0].plot(t, data.accel[::step, i] / G0, lw=0.7, label=f"a_{lab}")
        ax[1].plot(t, np.rad2deg(data.gyro[::step, i]), lw=0.7, label=f"ω_{lab}")
    if segments is not None:
        for k in np.flatnonzero(segments.kind == "transition"):
            for a in ax:
                a.axvspan(segments.t_start[k], segments.t_stop[k], color="0.9", lw=0)
    ax[0].set_ylabel("specific force (g)")
    ax[1].set_ylabel("angular rate (°/s)")
    ax[1].set_xlabel("time (s)")
    for a in ax:
        a.legend(loc="upper right", ncol=3, fontsize=8)
        a.grid(True, lw=0.3)
    if title:
        ax[0].set_title(title)
    fig.tight_layout()
    return fig
