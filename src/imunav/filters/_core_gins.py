"""Estimation-core primitives the GNSS/INS filter needs and :mod:`imunav.filters._core` lacks (private).

* :func:`inject_position_lla`: injection of a NED position error (metres) into a geodetic nominal position.
* :func:`propagate_cov_series`: ``P ← Φ P Φᵀ + Q_d`` with the second-order series ``Φ = I + FΔt + (FΔt)²/2``
  and the trapezoidal ``Q_d = (Φ Q Φᵀ + Q) Δt / 2`` — the cheap discretisation of a 15/21-state INS error model
  over a covariance step of ~0.1 s (:func:`imunav.filters._core.van_loan` is exact but costs a 2n-matrix
  exponential per step).
* :func:`write_skew`, :func:`write_mat3`, :func:`cross3`: the 3×3 blocks of the error dynamics and of the aid
  models' Jacobians, written in place.

The aid models themselves (GNSS, odometer, NHC, ZUPT, ZARU, barometer, magnetometer heading, ...) are one module
each in :mod:`imunav.ins.gins.aids`.

Same conventions and stability promise as :mod:`imunav.filters._core`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

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
    # element loops, not array expressions: the same arithmetic, element by element and in the same order, in a
    # fraction of the machine code (numba's array expressions compile broadcasting loops; every kernel that calls
    # this one compiles its code again: issue 35, a first run)
    n = P.shape[0]
    A = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            A[i, j] = F[i, j] * dt
    AA = A @ A
    Phi = np.empty((n, n))
    PhiT = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            v = ((1.0 if i == j else 0.0) + A[i, j]) + 0.5 * AA[i, j]
            Phi[i, j] = v
            PhiT[j, i] = v
    PP = Phi @ P @ PhiT
    QQ = Phi @ Q @ PhiT
    h = 0.5 * dt
    for i in range(n):
        for j in range(i, n):
            v = 0.5 * ((PP[i, j] + h * (QQ[i, j] + Q[i, j])) + (PP[j, i] + h * (QQ[j, i] + Q[j, i])))
            P[i, j] = v
            P[j, i] = v
    return Phi


@njit(cache=True)
def write_skew(a, M, r0, c0, sign):
    """Write ``sign [a×]`` into ``M[r0:r0+3, c0:c0+3]`` (the cross-product matrix, ``[a×] b = a × b``).

    Parameters
    ----------
    a : (3,) vector.
    M : (m, n) matrix, written in place.
    r0, c0 : int, first row and column of the block.
    sign : float, factor (±1).

    Returns
    -------
    None
    """
    M[r0, c0] = 0.0
    M[r0, c0 + 1] = -sign * a[2]
    M[r0, c0 + 2] = sign * a[1]
    M[r0 + 1, c0] = sign * a[2]
    M[r0 + 1, c0 + 1] = 0.0
    M[r0 + 1, c0 + 2] = -sign * a[0]
    M[r0 + 2, c0] = -sign * a[1]
    M[r0 + 2, c0 + 1] = sign * a[0]
    M[r0 + 2, c0 + 2] = 0.0


@njit(cache=True)
def write_mat3(C, M, r0, c0, sign, d):
    """Write ``sign C diag(d)`` into ``M[r0:r0+3, c0:c0+3]``.

    Parameters
    ----------
    C : (3, 3) matrix.
    M : (m, n) matrix, written in place.
    r0, c0 : int, first row and column of the block.
    sign : float, factor (±1).
    d : (3,) column scales.

    Returns
    -------
    None
    """
    for i in range(3):
        for j in range(3):
            M[r0 + i, c0 + j] = sign * C[i, j] * d[j]


@njit(cache=True)
def cross3(a, b):
    """``a × b`` of two 3-vectors (allocation of one 3-vector; the component order of the textbook formula).

    Parameters
    ----------
    a, b : (3,) vectors.

    Returns
    -------
    (3,) array
    """
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])
