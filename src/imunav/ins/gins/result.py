"""Results of the GNSS/INS filter: :class:`GinsResult` (the forward filter) and :class:`SmoothedTrack` (the RTS
smoother)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav.ins.gins.config import GinsConfig
from imunav.results import EulerMixin, Result

__all__ = ["AidRecord", "GinsResult", "SmoothedTrack"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class AidRecord(Result):
    """The updates of one aid (or the joint updates of a group of aids) in a GNSS/INS run.

    Attributes
    ----------
    t : numpy.ndarray, shape (U,)
        Times of the updates, s.
    nis : numpy.ndarray, shape (U,)
        Normalised innovation squared of the aid's own rows before the update (in a joint update: the marginal of
        the joint innovation), χ²(dof) for a consistent filter.
    dof : numpy.ndarray of int, shape (U,)
        Rows of each update.
    accepted : numpy.ndarray of bool, shape (U,)
        Whether the update passed its χ² gate (in a joint update, the gate of the whole).
    sample : numpy.ndarray of int, shape (U,)
        Index of the IMU sample at (or, for a timed aid, ending the interval holding) the update.
    logdet : numpy.ndarray, shape (U,), or None
        For withheld measurements (``GinsResult.aids['<aid>_withheld']``: scored, never applied; ``accepted`` is
        then what the gate would have said): ``ln det S`` of each one's innovation covariance, so that
        ``nis + logdet`` is its negative log predictive density up to ``dof · ln 2π``.  None for applied updates.
    """

    t: Array
    nis: Array
    dof: Array
    accepted: Array
    sample: Array
    logdet: Array | None = None

    @classmethod
    def empty(cls) -> AidRecord:
        """A record without updates.

        Returns
        -------
        AidRecord
            Empty arrays.
        """
        return cls(np.zeros(0), np.zeros(0), np.zeros(0, dtype=int), np.zeros(0, dtype=bool), np.zeros(0, dtype=int))


@dataclass(frozen=True)
class GinsResult(EulerMixin, Result):
    """Output of :class:`GinsFilter` (SI).

    Attributes
    ----------
    t : numpy.ndarray, shape (N,)
        IMU times, s.
    lla : numpy.ndarray, shape (N, 3)
        Estimated position of the IMU: lat rad, lon rad, ellipsoidal height m.
    vel_ned : numpy.ndarray, shape (N, 3)
        Estimated velocity, NED, m/s.
    q_nb : numpy.ndarray, shape (N, 4)
        Estimated attitude, Hamilton scalar-first quaternion, body (FRD) -> NED.
    gyro_bias, accel_bias, gyro_scale, accel_scale : numpy.ndarray, shape (N, 3)
        Estimated IMU errors: biases rad/s and m/s², scale factors dimensionless (zero for 15 states).
    odo_scale : numpy.ndarray, shape (N,)
        Estimated odometer scale factor (zero without odometer).
    cov_t : numpy.ndarray, shape (M,)
        Times of the covariance records, s (every covariance step, barometer and magnetometer sample).
    cov_diag : numpy.ndarray, shape (M, n)
        Variances of the error states (:data:`STATE_NAMES`, then the odometer scale), SI squared.
    cov_nav : numpy.ndarray, shape (M, 9, 9)
        Position (m, NED) / velocity (m/s) / attitude (rad) block of the covariance.
    gnss_t : numpy.ndarray, shape (G,)
        Times of the fixes used, s.
    nis : numpy.ndarray, shape (G, 2)
        Normalised innovation squared of the position / velocity update of each fix (NaN: not used).
    accepted : numpy.ndarray of bool, shape (G, 2)
        Whether the position / velocity update passed the χ² gate.
    vehicle_t : numpy.ndarray, shape (V,)
        Times of the odometer / NHC updates, s.
    vehicle_nis : numpy.ndarray, shape (V,)
        Their normalised innovation squared.
    vehicle_dof : numpy.ndarray of int, shape (V,)
        Their number of measurement rows (1-3).
    vehicle_accepted : numpy.ndarray of bool, shape (V,)
        Whether they passed the χ² gate.
    config : GinsConfig
        The configuration.
    meta : dict
        Removed fixes, number of states, gate threshold, covariance step, aids used.
    smoothed : SmoothedTrack or None
        The RTS solution when asked for (``GinsFilter.run(..., smoother=True)``).
    zupt_nis, baro_nis, mag_nis : numpy.ndarray, shape (N,), or None
        NIS of the ZUPT + ZARU (6 dof), barometer (1 dof) and magnetometer-heading (1 dof) updates per IMU
        sample, NaN where none was applied.
    odo_nis, nhc_nis, zupt_vel_nis, zaru_nis : numpy.ndarray, shape (N,), or None
        Each aiding model's own NIS per IMU sample (NaN where it was not applied): the odometer row (1 dof)
        and the NHC rows (2 dof) of the joint vehicle update, the ZUPT velocity rows (3 dof) and the ZARU
        rate rows (3 dof) of the joint rest update — the marginals of the joint innovation before the
        update, χ²(dof) for a consistent filter.
    q_vb : numpy.ndarray, shape (N, 4), or None
        Estimated IMU mounting (IMU FRD -> vehicle FRD, scalar first; constant where not estimated).
    odo_lever_arm : numpy.ndarray, shape (N, 3), or None
        Wheel contact point from the IMU, body FRD, m.
    gnss_delay : numpy.ndarray, shape (N,), or None
        GNSS receiver latency, s.
    gnss_bias : numpy.ndarray, shape (N, 3), or None
        The GNSS fixes' correlated error the filter estimated (``GinsConfig.gnss_bias_std``), NED, m.
    gnss_noise_scale : numpy.ndarray, shape (N,), or None
        The factor on the fixes' reported covariance that the adaptive noise estimate had reached
        (``GinsConfig.gnss_adaptive``; 1 without it).
    side_slip : numpy.ndarray, shape (N,), or None
        The vehicle's side slip per m/s² of lateral acceleration (``GinsConfig.side_slip_std``), rad/(m/s²): its
        lateral velocity is ``−β v_x² ω_z``; 0 where it was not estimated.
    odo_noise_scale, nhc_noise_scale : numpy.ndarray, shape (N,), or None
        The factors on the odometer's and the NHC's covariance that their adaptive noise estimates had reached
        (``GinsConfig.wheel_adaptive``; 1 without it).
    odo_turn : numpy.ndarray, shape (N,), or None
        The odometer's over-reading per rad/s of yaw rate (``GinsConfig.odo_turn_std``), s/rad; 0 where it was
        not estimated.
    aids : dict of str to AidRecord
        Every update of each aid model of :mod:`imunav.ins.gins.aids` that was applied, by aid name
        (``gnss_position``, ``gnss_velocity``, ``odometer``, ``nhc``, ``zupt``, ``zaru``, ``baro``,
        ``mag_heading``, ...).
    """

    t: Array
    lla: Array
    vel_ned: Array
    q_nb: Array
    gyro_bias: Array
    accel_bias: Array
    gyro_scale: Array
    accel_scale: Array
    odo_scale: Array
    cov_t: Array
    cov_diag: Array
    cov_nav: Array
    gnss_t: Array
    nis: Array
    accepted: Array
    vehicle_t: Array
    vehicle_nis: Array
    vehicle_dof: Array
    vehicle_accepted: Array
    config: GinsConfig
    meta: dict[str, Any] = field(default_factory=dict)
    smoothed: SmoothedTrack | None = None
    zupt_nis: Array | None = None
    baro_nis: Array | None = None
    mag_nis: Array | None = None
    odo_nis: Array | None = None
    nhc_nis: Array | None = None
    zupt_vel_nis: Array | None = None
    zaru_nis: Array | None = None
    aids: dict[str, AidRecord] = field(default_factory=dict)
    q_vb: Array | None = None
    odo_lever_arm: Array | None = None
    gnss_delay: Array | None = None
    gnss_bias: Array | None = None
    gnss_noise_scale: Array | None = None
    odo_turn: Array | None = None
    odo_noise_scale: Array | None = None
    side_slip: Array | None = None
    nhc_noise_scale: Array | None = None

    def gnss_summary(self) -> dict[str, Any]:
        """How the GNSS fixes were used: one definition for the CLI summary and the lab step.

        Returns
        -------
        dict
            ``gnss_fixes``: fixes the filter processed (after the first IMU sample); ``gnss_used``: those whose position
            update was evaluated (finite NIS); ``gnss_position_nis_mean``: the mean NIS of those (χ²(3) mean 3
            for a consistent filter; None when there is none); ``gnss_accepted_share``: the share of them that
            passed the χ² gate (None when there is none).
        """
        nis = self.nis[:, 0] if self.nis.size else np.zeros(0)
        used = np.isfinite(nis)
        n = int(used.sum())
        return {"gnss_fixes": int(self.gnss_t.size), "gnss_used": n,
                "gnss_position_nis_mean": float(np.mean(nis[used])) if n else None,
                "gnss_accepted_share": float(np.mean(self.accepted[used, 0])) if n else None}


@dataclass(frozen=True)
class SmoothedTrack(EulerMixin, Result):
    """RTS-smoothed navigation (Rauch, Tung & Striebel, "Maximum likelihood estimates of linear dynamic
    systems", AIAA Journal 3(8), 1965), SI.

    Attributes
    ----------
    t : numpy.ndarray, shape (N,)
        IMU times, s.
    lla : numpy.ndarray, shape (N, 3)
        Smoothed position: lat rad, lon rad, ellipsoidal height m.
    vel_ned : numpy.ndarray, shape (N, 3)
        Smoothed velocity, NED, m/s.
    q_nb : numpy.ndarray, shape (N, 4)
        Smoothed attitude, Hamilton scalar-first quaternion, body (FRD) -> NED.
    cov_t : numpy.ndarray, shape (M,)
        Times of the smoother epochs, s.
    cov_nav : numpy.ndarray, shape (M, 9, 9)
        Smoothed position (m, NED) / velocity (m/s) / attitude (rad) covariance.
    """

    t: Array
    lla: Array
    vel_ned: Array
    q_nb: Array
    cov_t: Array
    cov_nav: Array
