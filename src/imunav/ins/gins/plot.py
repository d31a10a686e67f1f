"""Figures of the GNSS/INS filter (matplotlib, imported lazily; compute code never plots).

* :func:`plot_track`: the track on a local map (east / north metres from the first position) with the GNSS
  fixes (and the truth);
* :func:`plot_errors`: position, velocity and attitude errors against a truth with the filter's ±3σ;
* :func:`plot_imu_errors`: gyro / accelerometer biases and scale factors with ±3σ;
* :func:`plot_outage_drift`: per-outage drift of the KF-GINS outage protocol
  (:class:`imunav.ins.gins.outage.OutageReport`);
* :func:`write_gins_figures`: all that apply, written atomically as PNG files into a folder.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from imunav import earth
from imunav.files import atomic_path
from imunav.ins.gins import GinsResult
from imunav.io.gnss import GnssData
from imunav.io.kfgins import DPH, MGAL, PPM, NavTrack

if TYPE_CHECKING:
    from imunav.ins.gins.outage import OutageReport
    from imunav.ins.gins.smoother import Separation

__all__ = ["plot_track", "plot_errors", "plot_imu_errors", "plot_outage_drift", "plot_separation",
           "write_gins_figures", "FIGURE_NAMES"]

#: File names written by :func:`write_gins_figures`, by figure.
FIGURE_NAMES = {"track": "gins_track.png", "errors": "gins_errors.png", "imu_errors": "gins_imu_errors.png",
                "outage": "gins_outage_drift.png", "separation": "gins_separation.png"}


def _plt() -> Any:
    # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
    import matplotlib

    matplotlib.use("Agg", force=False)
    # optional: matplotlib loads only when a figure is drawn (import time of imunav and its CLI)
    import matplotlib.pyplot as plt

    return plt


#: Buckets of a long series drawn on screen: each keeps its extreme samples (:func:`_shown`).
_BUCKETS = 2000


def _shown(*cols: np.ndarray) -> np.ndarray | slice:
    """Indices of the samples to draw of series longer than a figure can show: the first and last samples and, in
    each of :data:`_BUCKETS` consecutive buckets, the samples holding the minimum and maximum of every column
    (the line's envelope at the figure's resolution is kept; a series this short is drawn whole).

    Parameters
    ----------
    *cols : numpy.ndarray, shape (N,)
        The series drawn against one another or against time, same N.

    Returns
    -------
    numpy.ndarray or slice
        Sorted indices into the N samples (``slice(None)``: all).
    """
    n = cols[0].size
    if n <= 4 * _BUCKETS:
        return slice(None)
    size = n // _BUCKETS
    m = size * _BUCKETS
    base = np.arange(_BUCKETS) * size
    keep = [np.array([0, n - 1]), np.arange(m, n)]
    for c in cols:
        b = np.nan_to_num(np.asarray(c, dtype=float)[:m]).reshape(_BUCKETS, size)
        keep += [base + b.argmin(axis=1), base + b.argmax(axis=1)]
    return np.unique(np.concatenate(keep))


def _place(fig: Any, *, left: float = 0.95, right: float = 0.2, bottom: float = 0.6, top: float = 0.55,
           wspace: float = 0.95, hspace: float = 0.2) -> None:
    """Fixed axes positions for a grid of panels: margins and gaps in inches, as :meth:`Figure.subplots_adjust`
    takes them in fractions.  ``tight_layout`` would measure every text by drawing the figure once more (a third
    of a figure's cost); these margins leave room for tick labels of up to 6 characters and one line of axis
    label at the default 10 pt, and ``top`` for a title.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure whose axes form one grid (``plt.subplots``).
    left, right, bottom, top : float
        Margins, in.
    wspace, hspace : float
        Gaps between columns and between rows, in.
    """
    w, h = fig.get_size_inches()
    nrows, ncols = fig.axes[0].get_subplotspec().get_gridspec().get_geometry()
    aw = (w - left - right - (ncols - 1) * wspace) / ncols
    ah = (h - bottom - top - (nrows - 1) * hspace) / nrows
    fig.subplots_adjust(left=left / w, right=1 - right / w, bottom=bottom / h, top=1 - top / h,
                        wspace=wspace / aw, hspace=hspace / ah)


def _track(x: GinsResult | NavTrack) -> NavTrack:
    return x if isinstance(x, NavTrack) else NavTrack(x.t, x.lla, x.vel_ned, x.q_nb)


def plot_track(result: GinsResult | NavTrack, gnss: GnssData | None = None, truth: NavTrack | None = None) -> Any:
    """The track on a local map: east / north (m) from the first position, with the GNSS fixes.

    Parameters
    ----------
    result : GinsResult or NavTrack
        The navigation solution.
    gnss : GnssData, optional
        The fixes (antenna positions), drawn as dots.
    truth : NavTrack, optional
        The reference track.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (not shown; save it with ``fig.savefig``).
    """
    plt = _plt()
    nav = _track(result)
    origin = nav.lla[0]
    fig, ax = plt.subplots(figsize=(7, 6))
    if truth is not None:
        p = earth.lla_to_ned(truth.lla, origin)
        k = _shown(p[:, 0], p[:, 1])
        ax.plot(p[k, 1], p[k, 0], "k-", lw=2.5, alpha=0.3, label="truth")
    if gnss is not None:
        g = earth.lla_to_ned(gnss.lla, origin)
        ax.plot(g[:, 1], g[:, 0], ".", ms=3, color="tab:orange", label=f"GNSS ({gnss.n} fixes)")
        rec = getattr(result, "aids", {}).get("gnss_position")
        if rec is not None and not rec.accepted.all():
            bad = np.isin(np.round(gnss.t, 9), np.round(rec.t[~rec.accepted], 9))
            ax.plot(g[bad, 1], g[bad, 0], "x", ms=6, color="tab:red",
                    label=f"rejected by the χ² gate ({int(bad.sum())})")
    p = earth.lla_to_ned(nav.lla, origin)
    k = _shown(p[:, 0], p[:, 1])
    ax.plot(p[k, 1], p[k, 0], "-", lw=1, color="tab:blue", label="GNSS/INS")
    ax.plot(p[0, 1], p[0, 0], "go", label="start")
    ax.set_xlabel("east (m)")
    ax.set_ylabel("north (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True)
    ax.legend()
    ax.set_title("Track on a local map")
    _place(fig, left=1.0, top=0.4)
    return fig


def _sigma_at(t: np.ndarray, cov_t: np.ndarray, var: np.ndarray) -> np.ndarray:
    """σ of the covariance records interpolated to ``t`` (one column per state)."""
    sd = np.sqrt(np.maximum(var, 0.0))
    return np.column_stack([np.interp(t, cov_t, sd[:, j]) for j in range(sd.shape[1])])


def _band(ax: Any, t: np.ndarray, y: np.ndarray, tb: np.ndarray, centre: np.ndarray | float, s: np.ndarray,
          ylabel: str, label: str) -> None:
    """One panel: ``y`` over ``t`` and the band ``centre ± 3 s`` over ``tb`` (long series: their envelope,
    :func:`_shown`)."""
    k = _shown(y)
    ax.plot(t[k], y[k], lw=0.8, label=label)
    hi, lo = centre + 3 * s, centre - 3 * s
    k = _shown(hi, lo)
    ax.plot(tb[k], hi[k], "r--", lw=0.7, label="±3σ")
    ax.plot(tb[k], lo[k], "r--", lw=0.7)
    ax.set_ylabel(ylabel)
    ax.grid(True)


def _finish(fig: Any, axs: Any, t0: float, title: str) -> Any:
    """Legend on the first panel, time labels on the last row, the title; returns ``fig``."""
    axs[0, 0].legend(loc="upper right")
    for ax in axs[-1]:
        ax.set_xlabel(f"time since {t0:.3f} s (s)")
    fig.suptitle(title)
    _place(fig)
    return fig


def plot_errors(result: GinsResult, truth: NavTrack) -> Any:
    """Position (N E D, m), velocity (N E D, m/s) and attitude (roll, pitch, yaw, deg) errors against the truth,
    with the filter's ±3σ (attitude: σ of the error angle φ about N, E, D).

    Parameters
    ----------
    result : GinsResult
        The filter output.
    truth : NavTrack
        The reference, on (some of) the IMU time stamps.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (not shown; save it with ``fig.savefig``).
    """
    plt = _plt()
    t, dp, dv, de = _track(result).difference(truth)
    sd = _sigma_at(t, result.cov_t, result.cov_diag[:, :9])
    t0 = t[0]
    fig, axs = plt.subplots(3, 3, figsize=(12, 8), sharex=True)
    rows = (("position", dp, sd[:, 0:3], "m", ("N", "E", "D")),
            ("velocity", dv, sd[:, 3:6], "m/s", ("N", "E", "D")),
            ("attitude", np.degrees(de), np.degrees(sd[:, 6:9]), "deg", ("roll", "pitch", "yaw")))
    for i, (what, err, s, unit, axes) in enumerate(rows):
        for j in range(3):
            _band(axs[i, j], t - t0, err[:, j], t - t0, 0.0, s[:, j], f"{what} {axes[j]} ({unit})", "error")
    return _finish(fig, axs, t0, "GNSS/INS errors against the truth")


def plot_imu_errors(result: GinsResult) -> Any:
    """Estimated gyro biases (°/h), accelerometer biases (mGal) and, with 21 states, scale factors (ppm), ±3σ.

    Parameters
    ----------
    result : GinsResult
        The filter output.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (not shown; save it with ``fig.savefig``).
    """
    plt = _plt()
    groups = [("gyro bias", result.gyro_bias, 9, DPH, "°/h"), ("accel bias", result.accel_bias, 12, MGAL, "mGal")]
    if result.cov_diag.shape[1] >= 21:
        groups += [("gyro scale", result.gyro_scale, 15, PPM, "ppm"), ("accel scale", result.accel_scale, 18, PPM,
                                                                       "ppm")]
    fig, axs = plt.subplots(len(groups), 3, figsize=(12, 2.4 * len(groups)), sharex=True, squeeze=False)
    t0 = result.t[0]
    for i, (what, est, k, unit, label) in enumerate(groups):
        sd = np.sqrt(np.maximum(result.cov_diag[:, k:k + 3], 0.0)) / unit
        ci = np.clip(np.searchsorted(result.t, result.cov_t), 0, result.t.size - 1)
        for j in range(3):
            _band(axs[i, j], result.t - t0, est[:, j] / unit, result.cov_t - t0, est[ci, j] / unit, sd[:, j],
                  f"{what} {'xyz'[j]} ({label})", "estimate")
    return _finish(fig, axs, t0, "Estimated IMU errors")


def plot_outage_drift(report: OutageReport) -> Any:
    """Per-outage maximum horizontal / vertical drift (m) and heading error (deg) of the outage protocol,
    outages outside the predicted 3σ marked.

    Parameters
    ----------
    report : OutageReport
        The result of :func:`imunav.ins.gins.outage.outage_test`.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (not shown; save it with ``fig.savefig``).
    """
    plt = _plt()
    t0 = float(report.meta.get("t0_s", 0.0))
    start = np.array([s for s, _ in report.outages[:report.horizontal_m.size]]) - t0
    order = np.argsort(start, kind="stable")
    x = np.arange(start.size)
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    w = 0.4
    a1.bar(x - w / 2, report.horizontal_m[order], w, label="horizontal")
    a1.bar(x + w / 2, report.vertical_m[order], w, label="vertical")
    out = ~report.contained[order]
    if out.any():
        a1.plot(x[out], report.drift_3d_m[order][out], "rx", label="outside predicted 3σ")
    r = report.rms()
    a1.axhline(r["horizontal_m"], color="tab:blue", ls=":", lw=1, label=f"RMS horizontal {r['horizontal_m']:.3g} m")
    a1.axhline(r["vertical_m"], color="tab:orange", ls=":", lw=1, label=f"RMS vertical {r['vertical_m']:.3g} m")
    a1.set_ylabel("max drift (m)")
    a1.legend(fontsize=8)
    a1.grid(True, axis="y")
    a2.bar(x, report.heading_deg[order], 0.6, color="tab:green")
    a2.set_ylabel("max heading error (deg)")
    a2.set_xticks(x, [f"{s:.0f}" for s in start[order]], rotation=60, fontsize=7)
    a2.set_xlabel("outage start (s from the start of the recording)" if "t0_s" in report.meta else
                  "outage start (s)")
    a2.grid(True, axis="y")
    length = report.meta.get("length_s")
    fig.suptitle(f"GNSS outages{f' of {length:g} s' if length else ''}: largest drift in each "
                 f"({int(np.sum(report.contained))}/{report.contained.size} inside 3σ)")
    fig.tight_layout()
    return fig


def plot_separation(sep: Separation) -> Any:
    """The forward filter against the smoother, per covariance epoch: the horizontal separation (m) with the ±3σ
    that ``P_f − P_s`` predicts for it, and its normalised square ``d²`` against the χ²(2) 99 % line — a figure of
    the run's honesty that needs no truth (:class:`~imunav.ins.gins.smoother.Separation`).

    Parameters
    ----------
    sep : Separation
        From :func:`~imunav.ins.gins.smoother.forward_backward_separation`.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (not shown; save it with ``fig.savefig``).
    """
    plt = _plt()
    fig, axs = plt.subplots(2, 1, figsize=(10, 6), sharex=True, squeeze=False)
    t0 = float(sep.t[0]) if sep.t.size else 0.0
    t = sep.t - t0
    _band(axs[0, 0], t, sep.horizontal_m, t, 0.0, sep.sigma_m, "forward − smoothed, horizontal (m)",
          "separation")
    ax = axs[1, 0]
    k = _shown(np.nan_to_num(sep.d2))
    ax.semilogy(t[k], np.maximum(sep.d2[k], 1e-3), lw=0.8, label="d² (2 dof)")
    ax.axhline(9.21, color="r", ls="--", lw=0.7, label="χ²(2) 99 %")
    mean = sep.summary()["mean_d2"]
    if mean is not None:
        ax.axhline(mean, color="k", lw=0.7, label=f"mean {mean:.2f} (2 if honest)")
    ax.set_ylabel("normalised separation d²")
    ax.grid(True)
    ax.legend(loc="upper right")
    return _finish(fig, axs, t0, "Forward filter against the smoother (no truth needed)")


def write_gins_figures(folder: str | os.PathLike[str], result: GinsResult | None = None, *,
                       gnss: GnssData | None = None, truth: NavTrack | None = None,
                       outage: OutageReport | None = None, separation: Separation | None = None,
                       track: NavTrack | None = None) -> list[Path]:
    """Draw the figures that the inputs allow and write them as PNG files into ``folder``, atomically.

    Parameters
    ----------
    folder : str or os.PathLike
        Output folder (created).
    result : GinsResult, optional
        The filter run: track (with ``gnss`` and ``truth``), IMU errors, and errors when ``truth`` is given.
    gnss : GnssData, optional
        The fixes for the track.
    truth : NavTrack, optional
        The reference.
    outage : OutageReport, optional
        The outage protocol's drift.
    separation : Separation, optional
        The forward filter against the smoother (:func:`plot_separation`).
    track : NavTrack, optional
        The trajectory the run recommends (the smoothed one), drawn and compared with ``truth`` instead of the
        forward filter's.

    Returns
    -------
    list of pathlib.Path
        The files written (names of :data:`FIGURE_NAMES`).
    """
    plt = _plt()
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    makers: list[tuple[str, Any]] = []
    if result is not None:
        makers.append(("track", lambda: plot_track(result if track is None else track, gnss, truth)))
        if truth is not None:
            makers.append(("errors", lambda: plot_errors(result, truth)))
        makers.append(("imu_errors", lambda: plot_imu_errors(result)))
    if separation is not None and separation.t.size:
        makers.append(("separation", lambda: plot_separation(separation)))
    if outage is not None and outage.contained.size:
        makers.append(("outage", lambda: plot_outage_drift(outage)))
    written = []
    for name, make in makers:
        fig = make()
        path = out / FIGURE_NAMES[name]
        try:
            with atomic_path(path) as tmp:
                fig.savefig(tmp, format="png", dpi=90)
        finally:
            plt.close(fig)
        written.append(path)
    return written
