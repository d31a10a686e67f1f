"""An attitude filter on a PX4 log, compared the way a PX4 user compares it.

PX4 logs its own attitude estimate (``vehicle_attitude``, body -> NED, referenced to true north: the
estimator adds the magnetic declination, ``EKF2_MAG_DECL`` for EKF2, ``ATT_MAG_DECL`` for the Q
estimator).  An imunav filter that takes its heading from the magnetometer references magnetic north;
:func:`declination` reads what PX4 applied, :func:`to_true_north` applies it, and :func:`compare` gives
the per-axis RMS difference to the log's attitude on the log's one clock (PX4 boot time: each topic's
``t`` counts from its own first stamp ``meta["t0_ns"]``).  :func:`magnetometer_topic` names the topic that
holds the magnetometer when the IMU topic does not carry one (``sensor_combined`` of newer logs).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np
from numpy.typing import ArrayLike

from imunav.errors import InvalidInputError
from imunav.io.logs import list_topics
from imunav.io.topics import TopicData
from imunav.rotation import euler_from_quat, quat_from_euler, quat_interp, quat_multiply
from imunav.timeseries import ImuData

__all__ = ["MAG_TOPICS", "REFERENCE_TOPICS", "AttitudeComparison", "compare", "declination",
           "magnetometer_topic", "to_true_north"]

#: magnetometer topics, in the order they are tried
MAG_TOPICS = ("vehicle_magnetometer", "sensor_mag")
#: PX4's attitude topics, in the order they are tried as the reference
REFERENCE_TOPICS = ("vehicle_attitude", "vehicle_attitude_groundtruth")


def magnetometer_topic(path: str | os.PathLike[str], imu: ImuData) -> str | None:
    """The magnetometer topic to merge onto ``imu``, or None when ``imu`` carries one with data.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.ulg`` file ``imu`` was read from.
    imu : ImuData
        The IMU as read (``sensor_combined`` of older logs carries ``magnetometer_ga``).

    Returns
    -------
    str or None
        ``"name"`` or ``"name:instance"`` of the first of :data:`MAG_TOPICS` with at least two messages (the
        lowest instance), or None when ``imu.mag`` holds finite, non-zero data or the log has no such topic.
    """
    if imu.mag is not None and np.all(np.isfinite(imu.mag)) and np.any(imu.mag != 0):
        return None
    topics = list_topics(path)
    for name in MAG_TOPICS:
        found = sorted((ti.instance or 0) for ti in topics if ti.topic == name and ti.count >= 2)
        if found:
            many = sum(ti.topic == name for ti in topics) > 1
            return f"{name}:{found[0]}" if many else name
    return None


def declination(meta: Mapping[str, Any]) -> tuple[float | None, str | None]:
    """The magnetic declination PX4 applied, deg, and the parameter it comes from.

    Parameters
    ----------
    meta : mapping
        ``ImuData.meta`` of a ULog (its ``px4_params``: ``SYS_MC_EST_GROUP``, ``EKF2_MAG_DECL``,
        ``ATT_MAG_DECL``).

    Returns
    -------
    tuple
        ``(declination_deg, parameter)``; ``(None, None)`` when the log has neither parameter.
    """
    prm = dict(meta.get("px4_params") or {})
    group = prm.get("SYS_MC_EST_GROUP")
    order = ["ATT_MAG_DECL", "EKF2_MAG_DECL"] if group is not None and int(group) == 1 else ["EKF2_MAG_DECL",
                                                                                                "ATT_MAG_DECL"]
    for key in order:
        if key in prm and np.isfinite(float(prm[key])):
            return float(prm[key]), key
    return None, None


def to_true_north(q_nb: ArrayLike, declination_deg: float) -> np.ndarray:
    """Attitudes referenced to magnetic north turned to true north (a yaw of ``+declination``).

    Parameters
    ----------
    q_nb : array_like, (N, 4)
        Body -> NED quaternions whose north is magnetic north.
    declination_deg : float
        Magnetic declination, deg (east positive).

    Returns
    -------
    numpy.ndarray
        (N, 4) body -> NED quaternions, true north.
    """
    q = np.asarray(q_nb, dtype=float)
    return quat_multiply(quat_from_euler(0.0, 0.0, np.deg2rad(declination_deg)), q)


@dataclass(frozen=True)
class AttitudeComparison:
    """Per-axis RMS difference between an estimate and a log's attitude.

    Attributes
    ----------
    topic : str
        The reference topic.
    rms_deg : dict
        ``roll``, ``pitch``, ``yaw`` RMS of the Euler-angle differences (yaw wrapped to +-180), deg.
    t_from_s : float
        Comparison from this many seconds after the IMU's first sample (the filter's convergence left out).
    samples : int
        Reference samples compared.
    declination_deg : float or None
        Declination added to the estimate's yaw before the comparison (None: none applied).
    """

    topic: str
    rms_deg: dict[str, float]
    t_from_s: float
    samples: int
    declination_deg: float | None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary.

        Returns
        -------
        dict
            The attributes by name.
        """
        return {"topic": self.topic, "rms_deg": dict(self.rms_deg), "t_from_s": self.t_from_s,
                "samples": self.samples, "declination_deg": self.declination_deg}


def compare(imu: ImuData, q_nb: ArrayLike, ref: TopicData, *, t_from: float = 10.0,
            declination_deg: float | None = None) -> AttitudeComparison:
    """RMS difference per axis between an estimate on ``imu``'s stamps and a log's attitude topic.

    Both are put on the log's one clock (``t + meta["t0_ns"]``), the estimate is interpolated
    (slerp) onto the reference's stamps inside the IMU's span, from ``t_from`` seconds on.

    Parameters
    ----------
    imu : ImuData
        The recording the estimate ran on (its ``meta["t0_ns"]`` gives the clock origin).
    q_nb : array_like, (N, 4)
        The estimate on ``imu.t``, body -> NED.
    ref : TopicData
        The log's attitude topic (``q_nb`` values; :func:`imunav.io.logs.read_topic`).
    t_from : float
        Seconds after the IMU's first sample from which to compare.
    declination_deg : float, optional
        Declination to add to the estimate's yaw first (:func:`declination`).

    Returns
    -------
    AttitudeComparison
        The per-axis RMS.

    Raises
    ------
    InvalidInputError
        If the reference has no sample inside the compared span.
    """
    q = np.asarray(q_nb, dtype=float)
    if declination_deg is not None:
        q = to_true_north(q, declination_deg)
    shift = (int(ref.meta.get("t0_ns", 0)) - int(imu.meta.get("t0_ns", 0))) * 1e-9
    tr = np.asarray(ref.t, dtype=float) + shift
    sel = (tr >= imu.t[0] + t_from) & (tr <= imu.t[-1])
    if not np.any(sel):
        raise InvalidInputError(f"{ref.topic}: no sample between {t_from:g} s after the IMU's start and its end "
                                f"({imu.duration:.4g} s); the log's attitude does not overlap the recording")
    e_est = np.degrees(euler_from_quat(quat_interp(imu.t, q, tr[sel])))
    e_ref = np.degrees(euler_from_quat(np.asarray(ref.values["q_nb"], dtype=float)[sel]))
    de = e_est - e_ref
    de[:, 2] = (de[:, 2] + 180.0) % 360.0 - 180.0
    rms = np.sqrt(np.mean(de**2, axis=0))
    return AttitudeComparison(ref.topic, {"roll": float(rms[0]), "pitch": float(rms[1]), "yaw": float(rms[2])},
                              float(t_from), int(np.sum(sel)), declination_deg)
