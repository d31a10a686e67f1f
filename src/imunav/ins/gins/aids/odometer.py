"""Odometer aid: the forward speed of the wheel contact point, with scale-factor and turn over-reading states.

The odometer reads ``(1 + k)(1 + c |ω_z|) w_x`` (``w``: the wheel contact point's velocity in the vehicle frame,
:mod:`._wheel`; ``k``: the scale-factor error, estimated when the error state has the ``odo_scale`` block; ``c``:
the over-reading per rad/s of the vehicle's yaw rate ``ω_z = (Ĉ_vb ω)_z``, s/rad, estimated when it has the
``odo_turn`` block: the wheels of a skid-steer vehicle slip in its turns and read more than the body moves, Mandow
et al. 2007; the outer wheels of a steered axle run a wider arc, Groves 2013, §16.3.1), so with ``g = 1 + ĉ |ω_z|``
(Groves 2013, §16.3.1 for the scale factor)::

    ν = s − (1 + k̂) g ŵ_x,   H = (1 + k̂) g ∂w_x/∂δx  (+ g ŵ_x on δk, + (1 + k̂) |ω_z| ŵ_x on δc),   R = σ_s².

``|ω_z|`` depends on the gyro's bias and scale and on the mounting too; those columns are small unless ``ĉ`` is
large, and are kept so that ``H`` is the derivative of ``ν``.

Measurement ``z``: speed (m/s) and its variance ((m/s)²), one pair per IMU sample; applied at the covariance
epochs while the vehicle moves (a wheel encoder reads 0 while the body idles: the ZUPT holds the velocity then).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from imunav.filters._layout import named_layout
from imunav.ins.gins.aids._wheel import add_yaw_rate_rows, vehicle_rate, wheel_velocity
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
    ic = lay[LAY.odo_turn]
    c = xs[NOM.odo_turn]
    wv, Cvb = vehicle_rate(xs, ctx)  # the rate in the vehicle frame, C_vb ω
    wz = abs(wv[2]) if ic >= 0 else 0.0
    g = 1.0 + c * wz
    for j in range(nx):
        H[row, j] = (1.0 + k) * g * Hv[0, j]
    if io >= 0:
        H[row, io] = g * vw[0]
    if ic >= 0:
        H[row, ic] = (1.0 + k) * wz * vw[0]
        # |ω_z| through the gyro's bias and scale and the mounting: small unless the over-reading is large, kept so
        # that H is the derivative
        add_yaw_rate_rows((1.0 + k) * vw[0] * c * (1.0 if wv[2] >= 0.0 else -1.0), wv, Cvb, ctx, lay, H, row)
    nu[row] = z[0] - (1.0 + k) * g * vw[0]
    R[row, row] = z[1] * xs[NOM.odo_r_scale]  # the adaptive factor (1 without adaptation)
