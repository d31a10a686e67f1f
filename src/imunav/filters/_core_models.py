"""Measurement models of the numba estimation core (private).

Each model is a small ``@njit`` function that, for the current nominal state, gives the *innovation*
``ν = z − h(x̂)``, the Jacobian ``H = ∂h/∂δx`` with respect to the error state and the measurement variance R —
the ``compute_matrices(time, state) → (z, H, R)`` of pyins' measurement classes, compiled.  To stay allocation-free
inside the fused per-sample loops a model writes ``ν`` and ``R`` (and, for dense rows, ``H``) into caller-owned
buffers; selection rows (H = unit rows) are given by the filter's layout indices instead of a matrix.  The loop then
calls an update of :mod:`imunav.filters._core` with them.  How to add one: docs/design.md, section 3.

Error conventions: see :mod:`imunav.filters._core` (``local`` body error for the attitude filters, ``global``
navigation-frame error for the INS / ZUPT filters).
"""

from __future__ import annotations

from numba import njit

from imunav._rotation_kernels import qconj_1, qlog_1, qmul_1

# ---------------------------------------------------------------------------------------------------------------
# INS / ZUPT models (global attitude error; H are unit rows on the layout indices the caller passes)


@njit(cache=True)
def zero_velocity(v, sigma, nu, r):
    """ZUPT: the foot is still, ``z = 0 = v + n_v`` (Foxlin 2005; Skog et al. 2010).

    ``ν = −v̂``, ``H = [0 I 0 …]`` on the velocity error, ``R = σ² I``.

    Parameters
    ----------
    v : (3,) nominal velocity, m/s.
    sigma : float, measurement noise std, m/s.
    nu : (3,) receives the innovation.
    r : (3,) receives the variances.

    Returns
    -------
    None
    """
    for j in range(3):
        nu[j] = -v[j]
        r[j] = sigma * sigma


@njit(cache=True)
def zero_rate(gyr, bg, sigma, nu, r):
    """ZARU: the sensor does not rotate, so the gyro measures its bias, ``ω_meas = b_g + n``.

    ``ν = ω_meas − b̂_g``, ``H = [… I]`` on the gyro-bias error, ``R = σ² I`` (Groves 2013, §15.3.2).

    Parameters
    ----------
    gyr : (3,) gyro sample, rad/s.
    bg : (3,) nominal gyro bias, rad/s.
    sigma : float, noise std, rad/s.
    nu, r : (3,) receive innovation and variances.

    Returns
    -------
    None
    """
    for j in range(3):
        nu[j] = gyr[j] - bg[j]
        r[j] = sigma * sigma


@njit(cache=True)
def vertical_rotation(q, q_ref):
    """Vertical (nav z) component of the rotation vector of ``C(q) C(q_ref)ᵀ``: the rotation about the local
    vertical since ``q_ref``, whatever the sensor's mounting (the difference of ZYX yaw angles is not: the yaw of
    a tilted sensor changes when the foot only pitches, heel to toe).

    Parameters
    ----------
    q, q_ref : (4,) ``q_nb``.

    Returns
    -------
    float, rad.
    """
    return qlog_1(qmul_1(q, qconj_1(q_ref)))[2]


@njit(cache=True)
def heading_hold(q, q_ref, sigma, nu, r):
    """Heading hold during a stance: no rotation about the vertical since its first sample.

    With ``C = exp([δφ×]) Ĉ`` the measured change 0 = change(q̂) + δφ_D, so ``ν = −change(q̂)``,
    ``H = e_D`` on the attitude error, ``R = σ²`` (Abdulrahim et al. 2011, heuristic heading drift reduction).

    Parameters
    ----------
    q : (4,) nominal ``q_nb``.
    q_ref : (4,) attitude at the start of the stance.
    sigma : float, std, rad.
    nu, r : (1,) receive innovation and variance.

    Returns
    -------
    None
    """
    nu[0] = -vertical_rotation(q, q_ref)
    r[0] = sigma * sigma


@njit(cache=True)
def height(p_down, h_ref_down, sigma, nu, r):
    """Level floor: the down position equals a reference, ``ν = p_ref − p̂_D``, ``H = e_D`` on the position error.

    Parameters
    ----------
    p_down : float, nominal down position, m.
    h_ref_down : float, reference down position, m.
    sigma : float, std, m.
    nu, r : (1,) receive innovation and variance.

    Returns
    -------
    None
    """
    nu[0] = h_ref_down - p_down
    r[0] = sigma * sigma


# ---------------------------------------------------------------------------------------------------------------
# Attitude models (local error δθ, state [δθ, δb_g]; dense rows of length 6)


@njit(cache=True, inline="always")
def gravity_direction_row(qw, qx, qy, qz, a_unit, i, H):
    """Row ``i`` of the accelerometer-direction model: the unit specific force points up, ``f/|f| = C_nbᵀ (0,0,−1)``.

    ``ĥ = −(row 3 of C_nb)``; with ``q = q̂ ⊗ exp(δθ)``, ``h ≈ ĥ + [ĥ×] δθ``, so ``H_i = ([ĥ×])_i`` on δθ and 0 on
    the bias (Markley 2003; Solà 2017, §7).  Writes ``H`` (length ≥ 6, zeroed here) and returns
    ``ν_i = a_unit − ĥ_i``.  R is the caller's (adaptive) variance.

    Parameters
    ----------
    qw, qx, qy, qz : float, nominal ``q_nb``.
    a_unit : float, component i of the measured unit specific force.
    i : int, 0, 1 or 2.
    H : (6,) receives the row.

    Returns
    -------
    float, the innovation.
    """
    h0 = -2.0 * (qx * qz - qw * qy)
    h1 = -2.0 * (qy * qz + qw * qx)
    h2 = -(1.0 - 2.0 * (qx * qx + qy * qy))
    for j in range(6):
        H[j] = 0.0
    if i == 0:
        H[1] = -h2
        H[2] = h1
        return a_unit - h0
    if i == 1:
        H[0] = h2
        H[2] = -h0
        return a_unit - h1
    H[0] = -h1
    H[1] = h0
    return a_unit - h2


@njit(cache=True, inline="always")
def gyro_rest_row(gyr_i, b_i, i, H):
    """Row ``i`` of the rest (zero-rate) model of the attitude filters: ``ω_meas,i = b_i + n``.

    ``H = e_{3+i}`` (the bias error), returns ``ν = ω_meas,i − b̂_i``.

    Parameters
    ----------
    gyr_i : float, gyro sample component i, rad/s.
    b_i : float, nominal bias component i.
    i : int, 0, 1 or 2.
    H : (6,) receives the row.

    Returns
    -------
    float, the innovation.
    """
    for j in range(6):
        H[j] = 0.0
    H[3 + i] = 1.0
    return gyr_i - b_i
