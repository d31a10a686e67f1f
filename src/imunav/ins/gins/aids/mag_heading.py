"""Magnetometer heading aid: the rotation about the vertical that brings the horizontal part of the measured field
onto the magnetic meridian.

With ``m̂ⁿ = Ĉ m^b`` (calibrated 3-axis magnetometer, body frame), the declination ``D`` (east positive) and the
field's inclination ``I`` (``tan I = m̂_D / |m̂_h|``, from the measurement)::

    ν = wrap(D − atan2(m̂_E, m̂_N)) ≈ φ_D − tan I (cos D φ_N + sin D φ_E) + n

so the row on the global attitude error is ``[−tan I cos D, −tan I sin D, 1]`` (the levelling error enters through
the inclination; Groves 2013, §6.1.1 and §16.2.1), ``R = σ²`` (σ: heading noise, rad).

Measurement ``z``: the field, 3 columns, any unit (NaN where there is no sample; each sample sits at its nearest
IMU stamp and forces a covariance epoch there).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from imunav._rotation_kernels import dcm_from_quat_1
from imunav.filters._layout import named_layout
from imunav.ins.gins.layout import LAY, NOM

NAME = "mag_heading"
ROWS = 1
WIDTH = 3
#: own parameters: declination (rad, east positive) and heading σ (rad)
PARAMS, N_PARAMS = named_layout("MagHeadingParams", (("declination", 1), ("sigma", 1)))


def params(config: Any) -> np.ndarray:
    """This aid's parameter block from a :class:`~imunav.ins.gins.GinsConfig` (``declination``,
    ``mag_heading_noise_std``, rad).

    Parameters
    ----------
    config : GinsConfig
        The filter configuration.

    Returns
    -------
    numpy.ndarray, shape (N_PARAMS,)
        The block, layout :data:`PARAMS`.
    """
    return np.array([config.declination, config.mag_heading_noise_std], dtype=float)


@njit(cache=True)
def rows(xs, ctx, z, r, p, lay, H, R, nu, row):
    """Write the heading row at ``row``.

    Parameters
    ----------
    xs : nominal state (layout ``NOM``).
    ctx : update context (not used).
    z : (3,) magnetometer sample, body frame.
    r : not used.
    p : parameter block (layout :data:`PARAMS`).
    lay : int state layout (``LAY``).
    H, R, nu : Jacobian, covariance and innovation of the update, written at ``row``.
    row : int, first row.
    """
    mn = dcm_from_quat_1(xs[NOM.q:NOM.q + 4]) @ z[0:3]
    decl = p[PARAMS.declination]
    tan_i = mn[2] / math.sqrt(mn[0] * mn[0] + mn[1] * mn[1])
    v = decl - math.atan2(mn[1], mn[0])
    nu[row] = (v + math.pi) % (2.0 * math.pi) - math.pi
    ia = lay[LAY.att]
    H[row, ia] = -tan_i * math.cos(decl)
    H[row, ia + 1] = -tan_i * math.sin(decl)
    H[row, ia + 2] = 1.0
    R[row, row] = p[PARAMS.sigma] ** 2
