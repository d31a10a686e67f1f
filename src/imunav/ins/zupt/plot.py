"""Figures of the pedestrian INS (matplotlib, imported lazily; compute code never plots)."""

from __future__ import annotations

from typing import Any

import numpy as np

from imunav.ins.zupt.metrics import align_heading
from imunav.units import DEFAULT_GRAVITY

__all__ = ["plot_trajectory", "plot_zero_velocity"]


def _axes(ax: Any, figsize: tuple[float, float]) -> Any:
    """``ax``, or the axes of a new figure ``figsize`` inches wide and high."""
    if ax is None:
        # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=figsize)
    return ax


def plot_trajectory(result: Any, reference: Any = None, *, ax: Any = None, label: str = "INS") -> Any:
    """Top view (north up, east right) of a :class:`~imunav.ins.ZuptResult` and an optional reference.

    The reference is aligned as in :func:`imunav.ins.error_2d` (start shifted,
    heading rotated) when it has one row per sample.

    Parameters
    ----------
    result : ZuptResult
        The INS output (positions, local NED, m).
    reference : array_like, shape (N, 2) or (N, 3), optional
        Reference positions, m.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into (default: a new figure).
    label : str
        Legend label of the estimate.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn into.
    """
    ax = _axes(ax, (6, 6))
    p = np.asarray(result.position)
    if reference is not None:
        ref = np.asarray(reference, dtype=float)
        ref = ref - ref[0]
        p = align_heading(p, ref) if ref.shape[0] == p.shape[0] else p - p[0]
        ax.plot(ref[:, 1], ref[:, 0], "k-", lw=1, label="reference")
    ax.plot(p[:, 1], p[:, 0], "-", lw=1, label=label)
    ax.plot(p[0, 1], p[0, 0], "go", label="start")
    ax.set_xlabel("east (m)")
    ax.set_ylabel("north (m)")
    ax.set_aspect("equal")
    ax.grid(True)
    ax.legend()
    return ax


def plot_zero_velocity(data: Any, detections: dict[str, Any], *, ax: Any = None) -> Any:
    """Zero-velocity timeline: |ω| and |f| - g with each detector's stance flags underneath.

    Parameters
    ----------
    data : ImuData
        The recording (SI).
    detections : dict
        Detector name -> its stance flags (bool per sample) or :class:`~imunav.ins.DetectorResult`.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into (default: a new figure).

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn into.
    """
    ax = _axes(ax, (10, 4))
    t = np.asarray(data.t)
    ax.plot(t, np.linalg.norm(data.gyro, axis=1), lw=0.7, label="|gyro| (rad/s)")
    ax.plot(t, np.abs(np.linalg.norm(data.accel, axis=1) - DEFAULT_GRAVITY), lw=0.7, label="| |f| - g | (m/s²)")
    for i, (name, det) in enumerate(detections.items()):
        zv = np.asarray(getattr(det, "zv", det), dtype=float)
        ax.fill_between(t, -1.0 - 1.2 * i, -1.0 - 1.2 * i + zv, step="mid", alpha=0.5, label=f"{name} stance")
    ax.set_xlabel("time (s)")
    ax.legend(loc="upper right", fontsize="small")
    ax.grid(True)
    return ax
