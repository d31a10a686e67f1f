"""Estimation-core primitives the GNSS/INS filter needs and :mod:`imunav.filters._core` lacks (private).

* :func:`inject_position_lla`: injection of a NED position error (metres) into a geodetic nominal position.
* :func:`propagate_cov_series`: ``P ← Φ P Φᵀ + Q_d`` with the second-order series ``Φ = I + FΔt + (FΔt)²/2``
  and the trapezoidal ``Q_d = (Φ Q Φᵀ + Q) Δt / 2`` — the cheap discretisation of a 15/21-state INS error model
  over a covariance step of ~0.1 s (:func:`imunav.filters._core.van_loan` is exact but costs a 2n-matrix
  exponential per step).
* :func:`mag_heading`: the magnetometer heading model (innovation, Jacobian row, variance).
* :func:`earth_rate_rows`: the zero-angular-rate model of a platform at rest on the rotating Earth (innovation and
  Jacobian rows).

Same conventions and stability promise as :mod:`imunav.filters._core`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from imunav._rotation_kernels import skew_1
from imunav.earth import radii_gravity_1


@njit(cache=True)
def inject_position_lla(lla, dx, i0):
    """Inject a NED position error ``δr = dx[i0:i0+3]`` (m) into ``lla = (lat rad, lon rad, h m)``, in place.

    ``φ += δr_N / (R_N + h)``, ``λ += δr_E / ((R_E + h) cos φ)``, ``h −= δr_D`` (Groves 2013, eq. 2.119 linearised).

    Parameters
    ----------
    lla : (3,) nominal geodetic position, updated in place.
    dx : error-state vector.
    i0 : int, index of δr_N in ``dx``.

    Returns
    -------
    None
    """
    RN, RE, _ = radii_gravity_1(lla[0], lla[2])
    lat = lla[0]
    lla[0] = lat + dx[i0] / (RN + lla[2])
    lla[1] = lla[1] + dx[i0 + 1] / ((RE + lla[2]) * math.cos(lat))
    lla[2] = lla[2] - dx[i0 + 2]


@njit(cache=True)
def propagate_cov_series(P, F, Q, dt):
    """``P ← Φ P Φᵀ + Q_d`` with ``Φ = I + A + A²/2``, ``A = F dt`` and ``Q_d = (Φ Q Φᵀ + Q) dt / 2``, in place.

    Second order in ``dt`` for Φ and the trapezoid rule for Q_d (Groves 2013, eqs. 3.34 and 3.46); P is
    symmetrised.

    Parameters
    ----------
    P : (n, n) covariance, updated in place.
    F : (n, n) continuous system matrix.
    Q : (n, n) continuous process-noise spectral density ``G Q Gᵀ``.
    dt : float, step, s.

    Returns
    -------
    Phi : (n, n) the transition matrix used.
    """
    n = P.shape[0]
    A = F * dt
    Phi = np.eye(n) + A + 0.5 * (A @ A)
    PhiT = np.ascontiguousarray(Phi.T)
    Pn = Phi @ P @ PhiT + 0.5 * dt * (Phi @ Q @ PhiT + Q)
    for i in range(n):
        for j in range(i, n):
            v = 0.5 * (Pn[i, j] + Pn[j, i])
            P[i, j] = v
            P[j, i] = v
    return Phi


@njit(cache=True)
def mag_heading(C, mb, declination, sigma, h, i_att):
    """Magnetometer heading: the rotation about the vertical that brings the horizontal part of the measured
    field ``m̂ⁿ = Ĉ m^b`` (calibrated 3-axis magnetometer, body frame) onto the magnetic meridian, whose azimuth
    is the ``declination`` (east positive).

    ``ν = wrap(D − atan2(m̂_E, m̂_N))``; with the global attitude error (``C = exp([φ×]) Ĉ``) and the field's
    inclination ``I`` (``tan I = m̂_D / |m̂_h|``, from the measurement), ``ν = φ_D − tan I (cos D φ_N + sin D φ_E)
    + n``: the row ``h`` on the attitude error is ``[−tan I cos D, −tan I sin D, 1]`` (the levelling error
    enters through the inclination; Groves 2013, §6.1.1 and §16.2.1).  ``R = σ²`` (σ: heading noise, rad).

    Parameters
    ----------
    C : (3, 3) nominal ``C_nb``.
    mb : (3,) magnetometer sample, body frame (any unit).
    declination : float, rad.
    sigma : float, heading noise std, rad.
    h : (n,) receives the Jacobian row (zeroed here).
    i_att : int, index of φ_N in the error state.

    Returns
    -------
    nu : float, innovation, rad.
    r : float, variance, rad².
    """
    mn = C @ mb
    bh = math.sqrt(mn[0] * mn[0] + mn[1] * mn[1])
    tan_i = mn[2] / bh
    nu = declination - math.atan2(mn[1], mn[0])
    nu = (nu + math.pi) % (2.0 * math.pi) - math.pi
    h[:] = 0.0
    h[i_att] = -tan_i * math.cos(declination)
    h[i_att + 1] = -tan_i * math.sin(declination)
    h[i_att + 2] = 1.0
    return nu, sigma * sigma


@njit(cache=True)
def earth_rate_rows(C, gyr, bg, sg, w_ie_n, nu, H, r0, i_att, i_bg, i_sg):
    """Zero angular rate on the rotating Earth (ZARU of a vehicle at rest): the gyros read the Earth rate.

    Measured ``ω̃ = (1 + s) ⊙ Cᵀ ω_ie^n + b_g + n`` (``s``: gyro scale factors, ``⊙`` per axis).  With the
    global attitude error ``C = exp([φ×]) Ĉ``, ``Cᵀ ≈ Ĉᵀ (I − [φ×])`` and ``−[φ×] ω = [ω×] φ``::

        ν = ω̃ − (1 + ŝ) ⊙ Ĉᵀ ω_ie^n − b̂_g
          ≈ diag(1 + ŝ) Ĉᵀ [ω_ie^n ×] φ + δb_g + diag(Ĉᵀ ω_ie^n) δs_g + n

    (error states true minus estimate; Groves 2013, §5.6.3 and §14.2.2).  The attitude columns tie the heading to
    the gyro bias along east: a static filter can only estimate ``ε_E − Ω cos L φ_D``, the limit of
    gyrocompassing.

    Parameters
    ----------
    C : (3, 3) nominal ``C_nb``.
    gyr : (3,) measured rate, rad/s (raw, before the bias and scale correction).
    bg, sg : (3,) estimated gyro bias (rad/s) and scale factors.
    w_ie_n : (3,) Earth rate in the navigation frame, rad/s (``Ω (cos L, 0, −sin L)``).
    nu : (m,) receives the innovation in ``nu[r0:r0 + 3]``.
    H : (m, n) receives the rows ``r0 .. r0 + 2`` (only the attitude, bias and scale columns are written; zero
        the others first).
    r0 : int, first row.
    i_att, i_bg : int, indices of φ_N and of the x gyro bias in the error state.
    i_sg : int, index of the x gyro scale factor, or −1 without scale-factor states.
    """
    w_b = C.T @ w_ie_n
    ctw = C.T @ skew_1(w_ie_n)  # Ĉᵀ [ω×]
    for j in range(3):
        k = 1.0 + sg[j]
        nu[r0 + j] = gyr[j] - k * w_b[j] - bg[j]
        for i in range(3):
            H[r0 + j, i_att + i] = k * ctw[j, i]
        H[r0 + j, i_bg + j] = 1.0
        if i_sg >= 0:
            H[r0 + j, i_sg + j] = w_b[j]
