"""A truth that follows the GNSS/INS filter's own error model: the Monte Carlo under which it must be consistent.

The normalised estimation error squared (NEES) of a Kalman filter is χ²(n) only when the truth is drawn from
the filter's model (Bar-Shalom, Li & Kirubarajan 2001, §5.4).  For :class:`~imunav.ins.gins.GinsConfig` that
is, per axis:

* white rate / specific-force noise of density ``gyro_noise_density`` / ``accel_noise_density``;
* a bias that is a random constant of σ ``√(init² − σ_GM²)`` plus a stationary first-order Gauss–Markov
  process of σ ``gyro_bias_std`` / ``accel_bias_std`` and time constant ``corr_time`` — together of the
  initial σ ``init_gyro_bias_std`` / ``init_accel_bias_std``;
* scale-factor errors that are random constants of the initial σ (the presets' scale factors are constants,
  ``scale_corr_time = inf``);
* an initial position, velocity and attitude error drawn from ``init_pos_std``, ``init_vel_std`` and
  ``init_att_std`` (attitude: φ about N, E, D with ``C = exp([φ×]) Ĉ``);
* the accelerometer axes' misalignment, random constants of σ ``accel_misalignment_std`` off the diagonal of the
  scale-misalignment matrix (no state holds it: the filter adds the tilt it leaves to its reported covariance);
  drawn from a child of the generator (:meth:`numpy.random.Generator.spawn`), so the other draws are those of a
  configuration without it.

The presets' flicker noise, gyro misalignment and g-sensitivity are not in the filter's model; a run on
``simulate_imu(truth, presets.get(name))`` measures robustness, one on :func:`matched_errors` consistency,
with :func:`navigation_errors` and :func:`nees_blocks`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav import earth
from imunav.errors import InvalidInputError
from imunav.ins.gins import GinsConfig
from imunav.rotation import quat_conjugate, quat_from_rotvec, quat_multiply, rotvec_from_quat
from imunav.sim.error_model import GaussMarkov, ImuErrorModel, TriadErrors, scale_misalignment_matrix

__all__ = ["MatchedErrors", "matched_errors", "initial_state_draw", "navigation_errors", "nees_blocks"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class MatchedErrors:
    """IMU errors drawn from a :class:`~imunav.ins.gins.GinsConfig`'s model.

    Attributes
    ----------
    model : ImuErrorModel
        For :func:`imunav.sim.apply_errors` (with ``return_truth=True`` it gives the bias at every sample).
    gyro_scale, accel_scale : numpy.ndarray, shape (3,)
        The drawn scale-factor errors, dimensionless (the filter's scale states).
    """

    model: ImuErrorModel
    gyro_scale: Array
    accel_scale: Array


def _triad(white: Array, gm_sd: Array, init_sd: Array, scale_sd: Array, tc: float,
           rng: np.random.Generator) -> tuple[TriadErrors, Array]:
    """One triad's errors and its scale factors; with ``tc = inf`` the bias is a random constant of ``init_sd``."""
    z = rng.standard_normal(3)
    s = scale_sd * rng.standard_normal(3)
    if not np.isfinite(tc):
        return TriadErrors(bias=init_sd * z, scale_misalignment=scale_misalignment_matrix(s), noise_density=white), s
    return TriadErrors(bias=np.sqrt(np.maximum(init_sd**2 - gm_sd**2, 0.0)) * z,
                       scale_misalignment=scale_misalignment_matrix(s), noise_density=white,
                       bias_instability=GaussMarkov(gm_sd, tc)), s


def matched_errors(cfg: GinsConfig, rng: np.random.Generator) -> MatchedErrors:
    """Draw gyro and accelerometer errors from the model of ``cfg`` (see the module docstring).

    Parameters
    ----------
    cfg : GinsConfig
        The filter's configuration.
    rng : numpy.random.Generator
        Draws the constants (gyro, then accel: bias, then scale factors; the misalignment from a child).  The Gauss–Markov and white noise
        sequences are drawn by :func:`imunav.sim.apply_errors` from its own ``rng``.

    Returns
    -------
    MatchedErrors
        The error model and its scale factors.

    Raises
    ------
    InvalidInputError
        If the configuration has Gauss–Markov scale factors (``scale_corr_time`` not ``inf``), or an initial
        bias σ below the stationary one: the draw would not follow the filter's model.
    """
    if cfg.scale_factors and not (cfg.scale_corr_time is not None and np.isinf(cfg.scale_corr_time)):
        raise InvalidInputError("matched_errors draws the scale factors as random constants: give a configuration "
                                "with scale_corr_time=inf (as GinsConfig.from_preset does) or scale_factors=False")
    for name, init, gm in (("gyro", cfg.init_gyro_bias_std, cfg.gyro_bias_std),
                           ("accel", cfg.init_accel_bias_std, cfg.accel_bias_std)):
        if np.isfinite(cfg.corr_time) and np.any(init < gm * (1 - 1e-12)):
            raise InvalidInputError(f"init_{name}_bias_std {init} is below the stationary {name}_bias_std {gm}: a "
                                    "Gauss-Markov bias cannot start with less variance than it keeps; the truth "
                                    "would not follow the filter's model")
    gyro, sg = _triad(cfg.gyro_noise_density, cfg.gyro_bias_std, cfg.init_gyro_bias_std, cfg.init_gyro_scale_std, cfg.corr_time,
                      rng)
    acc, sa = _triad(cfg.accel_noise_density, cfg.accel_bias_std, cfg.init_accel_bias_std, cfg.init_accel_scale_std, cfg.corr_time,
                     rng)
    if cfg.accel_misalignment_std > 0:
        off = cfg.accel_misalignment_std * rng.spawn(1)[0].standard_normal((3, 3))
        acc = dataclasses.replace(acc, scale_misalignment=acc.scale_misalignment + off * (1.0 - np.eye(3)))
    return MatchedErrors(ImuErrorModel(gyro=gyro, accel=acc, name="matched to the filter"), sg, sa)


def initial_state_draw(lla: Array, vel_ned: Array, q_nb: Array, cfg: GinsConfig,
                       rng: np.random.Generator) -> tuple[Array, Array, Array]:
    """An initial state whose error against the true one is drawn from the initial covariance of ``cfg``.

    Parameters
    ----------
    lla, vel_ned, q_nb : numpy.ndarray, shapes (3,), (3,), (4,)
        The true initial position (lat rad, lon rad, h m), NED velocity (m/s) and attitude (body FRD -> NED).
    cfg : GinsConfig
        ``init_pos_std`` (N, E, D m), ``init_vel_std`` (m/s), ``init_att_std`` (φ N, E, D rad).
    rng : numpy.random.Generator
        Draws position, then velocity, then attitude.

    Returns
    -------
    tuple of numpy.ndarray
        ``(lla0, vel0, q0)`` for :meth:`imunav.ins.gins.GinsFilter.run`: true minus the drawn error (the
        filter's error states are true minus estimate).
    """
    dr = cfg.init_pos_std * rng.standard_normal(3)
    lla0 = np.asarray(lla, dtype=float) - earth.ned_to_dlla(dr[None], np.asarray(lla, dtype=float)[None])[0]
    v0 = np.asarray(vel_ned, dtype=float) - cfg.init_vel_std * rng.standard_normal(3)
    q0 = quat_multiply(quat_from_rotvec(-cfg.init_att_std * rng.standard_normal(3)), np.asarray(q_nb, dtype=float))
    return lla0, v0, q0


def navigation_errors(truth: Any, idx: ArrayLike, est: Any) -> Array:
    """True minus estimated position, velocity and attitude at truth samples ``idx``: the filter's error states.

    Parameters
    ----------
    truth : Trajectory
        ``pos_lla`` (lat rad, lon rad, h m), ``vel_ned`` (m/s) and ``q_nb`` on its time grid.
    idx : array_like of int, shape (K,)
        Indices of the compared samples, the same in ``truth`` and ``est``.
    est : GinsResult or SmoothedTrack
        ``lla``, ``vel_ned`` and ``q_nb`` on the same grid.

    Returns
    -------
    numpy.ndarray, shape (K, 9)
        NED position error (m, ``δr_N = δlat (R_N + h)``, ``δr_E = δlon (R_E + h) cos lat``, ``δr_D = −δh``),
        NED velocity error (m/s) and the attitude error φ (rad) with ``C = exp([φ×]) Ĉ``: the order and the
        convention of :attr:`imunav.ins.gins.GinsResult.cov_nav`, so that ``eᵀ P⁻¹ e`` is the NEES.
    """
    i = np.asarray(idx, dtype=np.int64)
    ref, lla = truth.pos_lla[i], est.lla[i]
    dr = earth.dlla_to_ned(ref - lla, ref)
    phi = rotvec_from_quat(quat_multiply(truth.q_nb[i], quat_conjugate(est.q_nb[i])))
    return np.hstack([dr, truth.vel_ned[i] - est.vel_ned[i], phi])


def nees_blocks(e: Array, P: Array) -> Array:
    """NEES of position, velocity and attitude, each with its own 3x3 block of ``P``.

    Parameters
    ----------
    e : numpy.ndarray, shape (K, 9)
        Errors from :func:`navigation_errors`.
    P : numpy.ndarray, shape (K, 9, 9)
        The matching covariance records (``cov_nav``).

    Returns
    -------
    numpy.ndarray, shape (3, K)
        ``e_bᵀ P_bb⁻¹ e_b`` per block: χ²(3) each for a consistent filter.
    """
    return np.array([np.einsum("ni,nij,nj->n", e[:, b], np.linalg.inv(P[:, b, b]), e[:, b])
                     for b in (slice(0, 3), slice(3, 6), slice(6, 9))])
