"""Vehicle level at rest: a ground vehicle standing still stands on roughly level ground, its roll and pitch are 0.

The vehicle's attitude is the IMU's and its mounting together, ``C_nv = C_nb C_vbᵀ``; the direction of gravity in the
vehicle frame ``g = C_vb C_nbᵀ e_D`` gives its roll ``atan2(g_y, g_z)`` and pitch ``atan2(−g_x, √(g_y² + g_z²))``.
With the global attitude error ``C_nb = exp([φ×]) Ĉ_nb`` and the mounting error ``C_vb = exp([μ×]) Ĉ_vb``
(Groves 2013, §5.6.2 for levelling; the mounting as a state as in Chen et al. 2020)::

    ∂g/∂φ = Ĉ_vb Ĉ_nbᵀ [e_D×],   ∂g/∂μ = −[ĝ×]
    ν = −(roll̂, pitcĥ),   H = J [∂g/∂φ | ∂g/∂μ],   J = ∂(roll, pitch)/∂g,   R = σ² I

with σ the ground's slope where the vehicle stops (configuration ``level_noise_std``).  This is what ties the mounting's
roll, which neither the odometer nor the NHC see, to the accelerometers, whose bias the filter separates from
the tilt while the vehicle turns.  Applied with the ZUPT while the vehicle is declared static.

Measurement ``z``: one placeholder column (0 where the vehicle is static, NaN elsewhere).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from imunav._rotation_kernels import dcm_from_quat_1
from imunav.filters._layout import named_layout
from imunav.ins.gins.layout import LAY, NOM

NAME = "vehicle_level"
ROWS = 2
WIDTH = 1
#: own parameters: the variance of the vehicle's roll and pitch at rest, rad²
PARAMS, N_PARAMS = named_layout("VehicleLevelParams", (("var", 1),))


def params(config: Any) -> np.ndarray:
    """This aid's parameter block from a :class:`~imunav.ins.gins.GinsConfig` (``level_noise_std``, rad; 0 when None).

    Parameters
    ----------
    config : GinsConfig
        The filter configuration.

    Returns
    -------
    numpy.ndarray, shape (N_PARAMS,)
        The block, layout :data:`PARAMS`.
    """
    return np.array([0.0 if config.level_noise_std is None else config.level_noise_std**2])


@njit(cache=True)
def rows(xs, ctx, z, r, p, lay, H, R, nu, row):
    """Write the roll and pitch rows at ``row``.

    Parameters
    ----------
    xs : nominal state (layout ``NOM``).
    ctx : update context (not used).
    z : (1,) placeholder.
    r : not used.
    p : parameter block (layout :data:`PARAMS`).
    lay : int state layout (``LAY``).
    H, R, nu : Jacobian, covariance and innovation of the update, written at ``row``.
    row : int, first row.
    """
    Cnb = dcm_from_quat_1(xs[NOM.q:NOM.q + 4])
    Cvb = dcm_from_quat_1(xs[NOM.q_vb:NOM.q_vb + 4])
    A = Cvb @ Cnb.T
    g = A[:, 2]  # C_vb C_nbᵀ e_D
    h2 = g[1] * g[1] + g[2] * g[2]
    h = math.sqrt(h2)
    n2 = h2 + g[0] * g[0]
    nu[row] = -math.atan2(g[1], g[2])
    nu[row + 1] = -math.atan2(-g[0], h)
    J = np.zeros((2, 3))
    J[0, 1] = g[2] / h2
    J[0, 2] = -g[1] / h2
    J[1, 0] = -h / n2
    J[1, 1] = g[0] * g[1] / (h * n2)
    J[1, 2] = g[0] * g[2] / (h * n2)
    # ∂g/∂φ = A [e_D×], [e_D×] = [[0, −1, 0], [1, 0, 0], [0, 0, 0]]
    Gphi = np.zeros((3, 3))
    for i in range(3):
        Gphi[i, 0] = A[i, 1]
        Gphi[i, 1] = -A[i, 0]
    Hphi = J @ Gphi
    ia = lay[LAY.att]
    im = lay[LAY.mount]
    # ∂g/∂μ = −[g×]: J (−[g×]) column c
    Gmu = np.zeros((3, 3))
    Gmu[0, 1] = g[2]
    Gmu[0, 2] = -g[1]
    Gmu[1, 0] = -g[2]
    Gmu[1, 2] = g[0]
    Gmu[2, 0] = g[1]
    Gmu[2, 1] = -g[0]
    Hmu = J @ Gmu
    for i in range(2):
        for j in range(3):
            H[row + i, ia + j] = Hphi[i, j]
            if im >= 0:
                H[row + i, im + j] = Hmu[i, j]
        R[row + i, row + i] = p[PARAMS.var]
