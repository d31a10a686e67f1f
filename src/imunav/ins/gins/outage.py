"""GNSS outage protocol of the KF-GINS paper (Tang et al., GPS Solutions 2025) for :class:`imunav.ins.gins.GinsFilter`.

After a convergence period, a ``length_s`` GNSS outage every ``every_s`` seconds; the run is repeated with the
first outage shifted by each of ``shifts_s`` (KF-GINS: 60 s every 180 s, shifts 0, 60 and 120 s).  For every
outage the maximum horizontal, vertical and 3-D position drift against the truth and the maximum roll, pitch and
heading errors are taken; the report gives their RMS over all outages, and the share of outages whose drift the
filter's predicted 3σ contained (per axis N, E, D at the worst epoch of each axis).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav import earth
from imunav.errors import InvalidInputError
from imunav.ins.gins import GinsConfig, GinsFilter, GinsResult
from imunav.io.gnss import GnssData
from imunav.results import Result
from imunav.rotation import euler_from_quat
from imunav.sim.gnss import outage_schedule
from imunav.timeseries import ImuData

__all__ = ["OutageReport", "check_protocol", "outage_test", "outage_drift"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class OutageReport(Result):
    """Per-outage drift and its RMS (m, deg); ``contained``: whether each outage stayed inside the predicted 3σ.

    One entry per outage in each array, in the order of ``outages``; each is the maximum over the epochs
    of that outage of the error against the truth.

    Attributes
    ----------
    outages : list of tuple of float
        ``(start s, length s)`` of each outage.
    horizontal_m : numpy.ndarray, shape (K,)
        Largest horizontal position error, m.
    vertical_m : numpy.ndarray, shape (K,)
        Largest vertical position error, m.
    drift_3d_m : numpy.ndarray, shape (K,)
        Largest 3-D position error, m.
    roll_deg, pitch_deg, heading_deg : numpy.ndarray, shape (K,)
        Largest absolute ZYX Euler angle errors, deg (wrapped to ±180°).
    contained : numpy.ndarray of bool, shape (K,)
        True when the N, E and D position errors stayed within 3 times the filter's predicted σ at every
        covariance record inside the outage.
    meta : dict
        The protocol's settings (``converge_s``, ``every_s``, ``length_s``, ``shifts_s``) when made by
        :func:`outage_test`.
    """

    outages: list[tuple[float, float]]
    horizontal_m: Array
    vertical_m: Array
    drift_3d_m: Array
    roll_deg: Array
    pitch_deg: Array
    heading_deg: Array
    contained: Array
    meta: dict[str, Any] = field(default_factory=dict)

    def rms(self) -> dict[str, float]:
        """RMS over all outages of the per-outage maxima (the KF-GINS figures), and the 3σ containment share.

        Returns
        -------
        dict
            ``horizontal_m``, ``vertical_m``, ``3d_m`` (m), ``roll_deg``, ``pitch_deg``, ``heading_deg``
            (deg): RMS over the outages (NaN with none); ``contained_3sigma``: the share of outages
            inside 3σ, in [0, 1]; ``n_outages``.
        """
        def r(x: Array) -> float:
            return float(np.sqrt(np.mean(np.square(x)))) if x.size else float("nan")

        return {"horizontal_m": r(self.horizontal_m), "vertical_m": r(self.vertical_m), "3d_m": r(self.drift_3d_m),
                "roll_deg": r(self.roll_deg), "pitch_deg": r(self.pitch_deg), "heading_deg": r(self.heading_deg),
                "contained_3sigma": float(np.mean(self.contained)) if self.contained.size else float("nan"),
                "n_outages": int(self.contained.size)}


def _errors(res: GinsResult, truth: Any) -> tuple[Array, Array]:
    idx = np.searchsorted(truth.t, res.t)
    if np.any(idx >= truth.t.size) or np.any(np.abs(truth.t[np.minimum(idx, truth.t.size - 1)] - res.t) > 1e-6):
        raise InvalidInputError("the truth must be sampled at the IMU time stamps (the simulator's trajectory)")
    ref = truth.pos_lla[idx]
    dn = earth.dlla_to_ned(res.lla - ref, ref)
    de = np.degrees(res.euler() - euler_from_quat(truth.q_nb[idx]))
    return dn, (de + 180.0) % 360.0 - 180.0


def outage_drift(res: GinsResult, truth: Any, outages: list[tuple[float, float]]) -> OutageReport:
    """Drift of a filter run through the given outages (start s, length s) against ``truth``
    (``t``, ``pos_lla``, ``q_nb`` at the IMU stamps, e.g. :class:`imunav.sim.Trajectory`).

    Parameters
    ----------
    res : GinsResult
        The run of :meth:`imunav.ins.gins.GinsFilter.run` whose GNSS had those outages.
    truth : Trajectory
        The true trajectory, sampled at the IMU time stamps (``t`` s, ``pos_lla``, ``q_nb``).
    outages : list of tuple of float
        ``(start s, length s)`` of each outage; one with no epoch of ``res`` is skipped.

    Returns
    -------
    OutageReport
        One entry per outage that holds epochs of ``res``.
    """
    dn, de = _errors(res, truth)
    cidx = np.searchsorted(res.t, res.cov_t)
    out: dict[str, list[float]] = {k: [] for k in ("h", "v", "d3", "r", "p", "y", "c")}
    for s, length in outages:
        m = (res.t >= s) & (res.t <= s + length)
        if not m.any():
            continue
        e = dn[m]
        out["h"].append(float(np.max(np.hypot(e[:, 0], e[:, 1]))))
        out["v"].append(float(np.max(np.abs(e[:, 2]))))
        out["d3"].append(float(np.max(np.linalg.norm(e, axis=1))))
        a = np.abs(de[m])
        out["r"].append(float(a[:, 0].max()))
        out["p"].append(float(a[:, 1].max()))
        out["y"].append(float(a[:, 2].max()))
        # predicted 3 sigma at the covariance records inside the outage
        mc = (res.cov_t >= s) & (res.cov_t <= s + length)
        sd = np.sqrt(res.cov_diag[mc][:, 0:3])
        ec = dn[cidx[mc]]
        out["c"].append(float(np.all(np.abs(ec) <= 3.0 * sd)))
    arr = {k: np.asarray(v) for k, v in out.items()}
    return OutageReport(list(outages), arr["h"], arr["v"], arr["d3"], arr["r"], arr["p"], arr["y"], arr["c"] > 0.5)


def check_protocol(every_s: float, length_s: float, shifts_s: Sequence[float]) -> None:
    """Check the outage protocol's settings before any run.

    Each shift is one filter run whose outages are the period's windows from ``converge_s + shift`` on; a shift
    repeated, or one ``every_s`` (or more) after another, removes the same windows again and counts the same
    outages twice in the RMS and the containment share.

    Parameters
    ----------
    every_s, length_s : float
        Outage period and length, s.
    shifts_s : sequence of float
        Shifts of the first outage, s.

    Raises
    ------
    InvalidInputError
        Unless ``every_s > length_s > 0``, and the shifts are distinct, >= 0 and < ``every_s``.
    """
    if not (np.isfinite(every_s) and np.isfinite(length_s) and every_s > length_s > 0):
        raise InvalidInputError(f"need every_s > length_s > 0 (the outage period and length; command line: --every > "
                                f"--length > 0); got every_s={every_s:g}, length_s={length_s:g}")
    sh = [float(x) for x in shifts_s]
    if not sh:
        raise InvalidInputError("shifts_s is empty (the shifts; command line: --shifts); give at least one shift, e.g. 0")
    bad = [x for x in sh if not (np.isfinite(x) and 0 <= x < every_s)]
    if bad:
        raise InvalidInputError(f"shifts_s {bad[0]:g} s is outside [0, every_s = {every_s:g} s) (the shifts and "
                                "period; command line: --shifts, --every): a shift of a period or more removes the windows of a shorter "
                                "one again and counts its outages twice")
    dup = sorted({x for x in sh if sh.count(x) > 1})
    if dup:
        raise InvalidInputError(f"shifts_s repeats {', '.join(f'{x:g}' for x in dup)} s (the shifts; command line: --shifts): "
                                "the same outages would be counted twice; give each shift once")


def outage_test(imu: ImuData, gnss: GnssData, config: GinsConfig, truth: Any, *, lla0: Any, vel0: Any, q0: Any,
                converge_s: float = 300.0, every_s: float = 180.0, length_s: float = 60.0,
                shifts_s: tuple[float, ...] = (0.0, 60.0, 120.0), odometer: Any = None,
                progress: Any = None) -> OutageReport:
    """The KF-GINS outage protocol: one run per shift with the scheduled outages removed from ``gnss``.

    Parameters
    ----------
    imu, gnss, config, lla0, vel0, q0 : ImuData, GnssData, GinsConfig, array_like
        The inputs and initial state, as :meth:`imunav.ins.gins.GinsFilter.run`.
    truth : Trajectory
        True trajectory sampled at the IMU stamps (``t`` s, ``pos_lla``, ``q_nb``).
    converge_s : float
        Time after the first IMU sample before the first outage, s.
    every_s, length_s : float
        Outage period and length, s (``every_s > length_s > 0``).
    shifts_s : tuple of float
        Shifts of the first outage, s; one filter run per shift.
    odometer : OdometerData, optional
        Wheel speeds for :meth:`~imunav.ins.gins.GinsFilter.run` (kept through the outages), or None.
    progress : callable, optional
        ``progress(done, total)`` after each shift's run.

    Returns
    -------
    OutageReport
        All outages of all shifts.

    Raises
    ------
    InvalidInputError
        If no outage fits in the recording after the convergence time for a shift, or the settings fail
        :func:`check_protocol`.
    """
    check_protocol(every_s, length_s, shifts_s)
    t0, t1 = float(imu.t[0]), float(imu.t[-1])
    reports = []
    for i, sh in enumerate(shifts_s):
        sched = outage_schedule(t0 + converge_s, t1, every_s=every_s, length_s=length_s, first_s=sh)
        if not sched:
            raise InvalidInputError(f"no {length_s:g} s outage fits after {converge_s:g} s of convergence "
                                    f"(shift {sh:g} s) in a {t1 - t0:g} s recording")
        keep = np.ones(gnss.n, dtype=bool)
        for s, d in sched:
            keep &= ~((gnss.t >= s) & (gnss.t < s + d))
        res = GinsFilter(config).run(imu, gnss.select(keep, "outage protocol"), lla0=lla0, vel0=vel0, q0=q0,
                                     odometer=odometer)
        reports.append(outage_drift(res, truth, sched))
        if progress is not None:
            progress(i + 1, len(shifts_s))
    return OutageReport(
        [o for r in reports for o in r.outages],
        *(np.concatenate([getattr(r, k) for r in reports]) for k in ("horizontal_m", "vertical_m", "drift_3d_m",
                                                                    "roll_deg", "pitch_deg", "heading_deg",
                                                                    "contained")),
        meta={"converge_s": converge_s, "every_s": every_s, "length_s": length_s, "shifts_s": list(shifts_s),
              "t0_s": t0},
    )
