"""Odometer aid: the forward speed of the wheel contact point, with a scale-factor state.

The odometer reads ``(1 + k) w_x`` (``w``: the wheel contact point's velocity in the vehicle frame, :mod:`._wheel`;
``k``: the scale-factor error, estimated when the error state has the ``odo_scale`` block), so (Groves 2013,
§16.3.1)::

    ν = s − (1 + k̂) ŵ_x,   H = (1 + k̂) ∂w_x/∂δx  (+ ŵ_x on δk),   R = σ_s².

Measurement ``z``: speed (m/s) and its variance ((m/s)²), one pair per IMU sample; applied at the covariance
epochs while the vehicle moves (a wheel encoder reads 0 while the body idles: the ZUPT holds the velocity then).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from imunav.filters._layout import named_layout
from imunav.ins.gins.aids._wheel import wheel_velocity
from imunav.ins.gins.layout import LAY, NOM

NAME = "odometer"
ROWS = 1
WIDTH = 2
#: own parameters: none (the wheel contact point and the mounting are in the nominal state)
PARAMS, N_PARAMS = named_layout("OdometerParams", ())


def params(config: Any) -> np.ndarray:
    """This aid's parameter block (empty: the lever arm and mounting are states or nominal values).

    Parameters
    ----------
    config : GinsConfig
        The filter configuration.

    Returns
    -------
    numpy.ndarray, shape (N_PARAMS,)
        The block, layout :data:`PARAMS`.
    """
    return np.zeros(N_PARAMS)


@njit(cache=True)
def rows(xs, ctx, z, r, p, lay, H, R, nu, row):
    """Write the odometer row at ``row``.

    Parameters
    ----------
    xs : nominal state (layout ``NOM``).
    ctx : update context (layout ``CTX``; ``w_sample``).
    z : (2,) speed (m/s) and its variance ((m/s)²).
    r : not used (the variance is ``z[1]``).
    p : parameter block (layout :data:`PARAMS`).
    lay : int state layout (``LAY``).
    H, R, nu : Jacobian, covariance and innovation of the update, written at ``row``.
    row : int, first row.
    """
    nx = lay[LAY.nx]
    Hv = np.zeros((3, nx))
    vw = wheel_velocity(xs, ctx, lay, Hv)
    io = lay[LAY.odo_scale]
    k = xs[NOM.odo_scale] if io >= 0 else 0.0
    for j in range(nx):
        H[row, j] = (1.0 + k) * Hv[0, j]
    if io >= 0:
        H[row, io] = vw[0]
    nu[row] = z[0] - (1.0 + k) * vw[0]
    R[row, row] = z[1]
