"""What an attitude filter rejected, and when: the summary line of a run, beside the reference error.

The MEKF family (:class:`imunav.attitude.mekf.MEKF`, :class:`imunav.attitude.adaptive.AdaptiveMEKF`, the
smoother's forward pass) flags every sample: ``mag_disturbed`` (the field's norm or dip left the reference band:
the heading update was skipped), ``acc_rejected`` (the specific-force norm left the gravity band: the tilt update
was skipped) and ``rest`` (zero-rate updates of the gyro bias).  :func:`rejection_summary` turns the flags into
fractions, intervals and, given the error angles against a reference (:func:`imunav.attitude.metrics.error_angles`),
the error inside and outside the rejected intervals: a trial whose error grows while the field was rejected went
wrong on the gyro alone (a long disturbance), one whose error grows while the field was *used* went wrong on a
distortion the test let through.  :func:`imunav.attitude.plot.plot_rejections` draws the same beside the error.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from imunav._timeseries_kernels import runs
from imunav.attitude.metrics import ErrorAngles
from imunav.attitude.result import AttitudeResult
from imunav.errors import InvalidInputError, ShapeError
from imunav.results import Result

__all__ = ["RejectionSummary", "rejection_summary", "rejected_intervals"]


def rejected_intervals(t: np.ndarray, flag: np.ndarray) -> list[tuple[float, float]]:
    """The time intervals ``[t_start, t_stop]`` over which ``flag`` is set (one per run of set samples).

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Sample times, s.
    flag : numpy.ndarray, shape (N,)
        Per-sample boolean flag (e.g. ``result.flags["mag_disturbed"]``).

    Returns
    -------
    list of (float, float)
        Start and end time of each run, s (the end is the time of the run's last sample).
    """
    lo, hi = runs(np.ascontiguousarray(flag, dtype=np.bool_))
    return [(float(t[a]), float(t[b - 1])) for a, b in zip(lo, hi)]


def _rms_deg(x: np.ndarray) -> float | None:
    x = x[np.isfinite(x)]
    return float(np.degrees(np.sqrt(np.mean(x * x)))) if x.size else None


@dataclass(frozen=True)
class RejectionSummary(Result):
    """What a filter rejected over a recording (see the module docstring).

    Attributes
    ----------
    name : str
        Filter (and trial) name.
    duration_s : float
        Length of the recording, s.
    mag_rejected_fraction : float or None
        Fraction of the samples whose field was rejected (None: no field flag, e.g. a 6D run).
    mag_intervals : int
        Number of intervals of rejected field.
    mag_longest_s : float
        Longest of them, s (0 when none).
    acc_rejected_fraction : float or None
        Fraction of the samples whose accelerometer was rejected.
    acc_intervals : int
        Number of intervals of rejected accelerometer.
    rest_fraction : float or None
        Fraction of the samples at rest (zero-rate updates).
    error_mag_rejected_deg : float or None
        RMS total error angle over the samples with the field rejected, deg (None without a reference or sample).
    error_mag_used_deg : float or None
        The same over the other samples, deg.
    error_acc_rejected_deg : float or None
        RMS inclination error over the samples with the accelerometer rejected, deg.
    """

    name: str
    duration_s: float
    mag_rejected_fraction: float | None
    mag_intervals: int
    mag_longest_s: float
    acc_rejected_fraction: float | None
    acc_intervals: int
    rest_fraction: float | None
    error_mag_rejected_deg: float | None = None
    error_mag_used_deg: float | None = None
    error_acc_rejected_deg: float | None = None

    def line(self) -> str:
        """One line for a log or a table: what was rejected, how long, and the error inside and outside.

        Returns
        -------
        str
            e.g. ``adaptive: field rejected 12.3 % of 180 s in 4 intervals (longest 9.1 s), error 3.10 deg
            there vs 1.20 deg elsewhere; accelerometer rejected 0.0 %; rest 21.0 %``.
        """

        def pct(x: float | None) -> str:
            return "n/a" if x is None else f"{100.0 * x:.1f} %"

        def deg(x: float | None) -> str:
            return "n/a" if x is None else f"{x:.2f} deg"

        s = f"{self.name}: field rejected {pct(self.mag_rejected_fraction)} of {self.duration_s:.0f} s"
        if self.mag_intervals:
            s += f" in {self.mag_intervals} intervals (longest {self.mag_longest_s:.1f} s)"
        if self.error_mag_used_deg is not None or self.error_mag_rejected_deg is not None:
            s += f", error {deg(self.error_mag_rejected_deg)} there vs {deg(self.error_mag_used_deg)} elsewhere"
        s += f"; accelerometer rejected {pct(self.acc_rejected_fraction)}"
        if self.acc_intervals:
            s += f" in {self.acc_intervals} intervals"
            if self.error_acc_rejected_deg is not None:
                s += f" (inclination error {deg(self.error_acc_rejected_deg)} there)"
        return s + f"; rest {pct(self.rest_fraction)}"


def rejection_summary(result: AttitudeResult, angles: ErrorAngles | None = None, *,
                      name: str | None = None) -> RejectionSummary:
    """Summarise the rejection flags of a run, with the reference error inside and outside them.

    Parameters
    ----------
    result : AttitudeResult
        A run of a filter that flags its samples (``acc_rejected``, ``mag_disturbed``, ``rest``: the MEKF family).
    angles : ErrorAngles, optional
        Error angles of ``result`` against a reference (:func:`imunav.attitude.metrics.error_angles`), one per
        sample, NaN where the reference is missing.
    name : str, optional
        Label of the line (default: the filter's name).

    Returns
    -------
    RejectionSummary
        Fractions, intervals and errors.

    Raises
    ------
    InvalidInputError
        If the result has none of the three flags.
    ShapeError
        If ``angles`` do not have one value per sample.
    """
    fl = result.flags
    if not any(k in fl for k in ("mag_disturbed", "acc_rejected", "rest")):
        raise InvalidInputError(f"result of {result.name!r} has no rejection flags (mag_disturbed, acc_rejected, "
                                "rest); run a filter of the MEKF family (mekf, adaptive)")
    n = result.n
    if angles is not None and np.shape(angles.total) != (n,):
        raise ShapeError(f"angles have {np.shape(angles.total)} values, the result has {n} samples; compute them "
                         "with error_angles(result.q_nb, reference)")
    t = np.asarray(result.t, dtype=float)
    use_mag = bool(result.params.get("use_mag", True))

    def flag(k: str) -> np.ndarray | None:
        return np.asarray(fl[k], dtype=bool) if k in fl else None

    mag = flag("mag_disturbed") if use_mag else None
    acc = flag("acc_rejected")
    rest = flag("rest")
    iv_m = rejected_intervals(t, mag) if mag is not None else []
    iv_a = rejected_intervals(t, acc) if acc is not None else []
    err: dict[str, float | None] = {}
    if angles is not None:
        tot = np.asarray(angles.total, dtype=float)
        if mag is not None:
            err["error_mag_rejected_deg"] = _rms_deg(tot[mag])
            err["error_mag_used_deg"] = _rms_deg(tot[~mag])
        if acc is not None:
            err["error_acc_rejected_deg"] = _rms_deg(np.asarray(angles.inclination, dtype=float)[acc])
    return RejectionSummary(
        name=name or result.name, duration_s=float(t[-1] - t[0]),
        mag_rejected_fraction=float(mag.mean()) if mag is not None else None, mag_intervals=len(iv_m),
        mag_longest_s=max((b - a for a, b in iv_m), default=0.0),
        acc_rejected_fraction=float(acc.mean()) if acc is not None else None, acc_intervals=len(iv_a),
        rest_fraction=float(rest.mean()) if rest is not None else None, **err)
