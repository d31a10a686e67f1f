"""Zero angular rate of a vehicle at rest on the rotating Earth: the gyros read the Earth rate.

Measured ``ω̃ = (1 + s) ⊙ Cᵀ ω_ie^n + b_g + n`` (``s``: gyro scale factors, ``⊙`` per axis).  With the global
attitude error ``C = exp([φ×]) Ĉ``, ``Cᵀ ≈ Ĉᵀ (I − [φ×])`` and ``−[φ×] ω = [ω×] φ`` (Groves 2013, §5.6.3 and
§14.2.2)::

    ν = ω̃ − (1 + ŝ) ⊙ Ĉᵀ ω_ie^n − b̂_g
      ≈ diag(1 + ŝ) Ĉᵀ [ω_ie^n ×] φ + δb_g + diag(Ĉᵀ ω_ie^n) δs_g + n

The attitude columns tie the heading to the gyro bias along east: a static filter can only estimate
``ε_E − Ω cos L φ_D``, the limit of gyrocompassing; without them the filter would count the Earth rate as a
direct measurement of the bias and report a heading σ it does not have.

``ω̃`` is the raw mean rate over the last covariance step Δt (context ``w_raw``, ``dt_raw``): white noise of
density ARW gives it the variance ``ARW² / Δt`` per axis, added to ``σ²``, the rate disturbance at rest (engine
vibration).  The core's :func:`~imunav.filters._core_models.zero_rate` is the local-level model without Earth rate.

Measurement ``z``: one placeholder column (0 where the vehicle is static, NaN elsewhere).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from imunav._rotation_kernels import dcm_from_quat_1, skew_1
from imunav.earth import OMEGA_E
from imunav.filters._layout import named_layout
from imunav.ins.gins.layout import CTX, LAY, NOM

NAME = "zaru"
ROWS = 3
WIDTH = 1
#: own parameters: the rate disturbance at rest (rad/s) and the gyro white noise density ARW (rad/√s)
PARAMS, N_PARAMS = named_layout("ZaruParams", (("sigma", 1), ("gyro_noise_density", 3)))


def params(config: Any) -> np.ndarray:
    """This aid's parameter block from a :class:`~imunav.ins.gins.GinsConfig` (``zaru_noise_std`` rad/s, ``gyro_noise_density``).

    Parameters
    ----------
    config : GinsConfig
        The filter configuration.

    Returns
    -------
    numpy.ndarray, shape (N_PARAMS,)
        The block, layout :data:`PARAMS`.
    """
    p = np.zeros(N_PARAMS)
    p[PARAMS.sigma] = config.zaru_noise_std
    p[PARAMS.gyro_noise_density:PARAMS.gyro_noise_density + 3] = config.gyro_noise_density
    return p


@njit(cache=True)
def earth_rate_rows(C, gyr, bg, sg, w_ie_n, nu, H, r0, i_att, i_bg, i_sg):
    """Innovation and Jacobian rows of the zero angular rate on the rotating Earth (equations above).

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


@njit(cache=True)
def rows(xs, ctx, z, r, p, lay, H, R, nu, row):
    """Write the three ZARU rows at ``row``.

    Parameters
    ----------
    xs : nominal state (layout ``NOM``).
    ctx : update context (layout ``CTX``): ``w_raw`` and ``dt_raw``.
    z : (1,) placeholder.
    r : not used.
    p : parameter block (layout :data:`PARAMS`).
    lay : int state layout (``LAY``).
    H, R, nu : Jacobian, covariance and innovation of the update, written at ``row``.
    row : int, first row.
    """
    lat = xs[NOM.lla]
    w_ie_n = np.array([OMEGA_E * math.cos(lat), 0.0, -OMEGA_E * math.sin(lat)])
    isg = lay[LAY.gyro_scale]
    sg = np.zeros(3)
    if isg >= 0:
        sg[:] = xs[NOM.gyro_scale:NOM.gyro_scale + 3]
    earth_rate_rows(dcm_from_quat_1(xs[NOM.q:NOM.q + 4]), ctx[CTX.w_raw:CTX.w_raw + 3],
                    xs[NOM.gyro_bias:NOM.gyro_bias + 3], sg, w_ie_n, nu, H, row, lay[LAY.att], lay[LAY.gyro_bias], isg)
    dt = ctx[CTX.dt_raw]
    for j in range(3):
        R[row + j, row + j] = p[PARAMS.sigma] ** 2 + p[PARAMS.gyro_noise_density + j] ** 2 / dt
