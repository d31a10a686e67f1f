"""Non-holonomic constraint: a ground vehicle's wheel contact point does not move sideways or vertically.

``0 = w_y + n``, ``0 = w_z + n`` (``w``: the contact point's velocity in the vehicle frame, :mod:`._wheel`), so
``ν = −ŵ_(y,z)``, ``H = ∂w_(y,z)/∂δx``,
``R = σ² I`` with σ the body's side slip and suspension velocity in motion (Niu et al. 2007; Groves 2013, §16.3.2).
With the side-slip state (``GinsConfig.side_slip_std``) the lateral row holds ``w_y = −β w_x² ω_z`` instead: the
slip angle of a linear tyre, or of a skid-steer robot's body, grows with the lateral acceleration ``w_x ω_z``
(``ω_z`` the vehicle's yaw rate ``(C_vb ω)_z``), so ``ν_y = −ŵ_y − β̂ ŵ_x² ω_z`` and ``H_y`` gains
``ŵ_x² ω_z`` for ``β`` and the terms through ``w_x``, the gyro's bias and scale and the mounting.
Applied at the covariance epochs while the vehicle moves: at rest the ZUPT constrains the same velocity, and using
it twice as two independent measurements would make the filter overconfident.

Measurement ``z``: one placeholder column (0 where the constraint applies, NaN elsewhere).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from imunav.filters._layout import named_layout
from imunav.ins.gins.aids._wheel import add_yaw_rate_rows, vehicle_rate, wheel_velocity
from imunav.ins.gins.layout import LAY, NOM

NAME = "nhc"
ROWS = 2
WIDTH = 1
#: own parameters: the constraint's variance ((m/s)²)
PARAMS, N_PARAMS = named_layout("NhcParams", (("var", 1),))


def params(config: Any) -> np.ndarray:
    """This aid's parameter block from a :class:`~imunav.ins.gins.GinsConfig` (``nhc_noise_std``, m/s).

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
    p[PARAMS.var] = 0.0 if config.nhc_noise_std is None else config.nhc_noise_std**2
    return p


@njit(cache=True)
def rows(xs, ctx, z, r, p, lay, H, R, nu, row):
    """Write the two NHC rows at ``row``.

    Parameters
    ----------
    xs : nominal state (layout ``NOM``).
    ctx : update context (layout ``CTX``; ``w_sample``).
    z : (1,) placeholder.
    r : not used.
    p : parameter block (layout :data:`PARAMS`).
    lay : int state layout (``LAY``).
    H, R, nu : Jacobian, covariance and innovation of the update, written at ``row``.
    row : int, first row.
    """
    nx = lay[LAY.nx]
    Hv = np.zeros((3, nx))
    vw = wheel_velocity(xs, ctx, lay, Hv)
    for a in range(2):
        for j in range(nx):
            H[row + a, j] = Hv[1 + a, j]
        nu[row + a] = -vw[1 + a]
        R[row + a, row + a] = p[PARAMS.var] * xs[NOM.nhc_r_scale]  # the adaptive factor (1 without)
    i_s = lay[LAY.side_slip]
    if i_s >= 0:  # the lateral row holds v_y + β v_x² ω_z = 0: a slip angle β times the lateral acceleration
        beta = xs[NOM.side_slip]
        wv, Cvb = vehicle_rate(xs, ctx)  # the rate in the vehicle frame, C_vb ω
        vx = vw[0]
        nu[row] -= beta * vx * vx * wv[2]
        H[row, i_s] += vx * vx * wv[2]
        for j in range(nx):  # through v_x
            H[row, j] += 2.0 * beta * vx * wv[2] * Hv[0, j]
        add_yaw_rate_rows(beta * vx * vx, wv, Cvb, ctx, lay, H, row)  # through ω_z
