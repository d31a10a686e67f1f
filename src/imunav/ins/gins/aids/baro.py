"""Barometric height aid: ``h_b = h + n`` on the down position error.

``ν = −h_b − (−ĥ)`` (the down position), ``H = e_D`` on δr, ``R = σ²`` with σ the barometer's noise and bias
together (no baro-bias state) (:func:`imunav.filters._core_models.height`; Groves 2013, §16.2.4).

Measurement ``z``: height, m (one column, NaN where there is no sample; each sample sits at its nearest IMU stamp
and forces a covariance epoch there).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from imunav.filters._core_models import height
from imunav.filters._layout import named_layout
from imunav.ins.gins.layout import LAY, NOM

NAME = "baro"
ROWS = 1
WIDTH = 1
#: own parameters: the height σ, m
PARAMS, N_PARAMS = named_layout("BaroParams", (("sigma", 1),))


def params(config: Any) -> np.ndarray:
    """This aid's parameter block from a :class:`~imunav.ins.gins.GinsConfig` (``baro_noise_std``, m).

    Parameters
    ----------
    config : GinsConfig
        The filter configuration.

    Returns
    -------
    numpy.ndarray, shape (N_PARAMS,)
        The block, layout :data:`PARAMS`.
    """
    return np.array([config.baro_noise_std], dtype=float)


@njit(cache=True)
def rows(xs, ctx, z, r, p, lay, H, R, nu, row):
    """Write the height row at ``row``.

    Parameters
    ----------
    xs : nominal state (layout ``NOM``).
    ctx : update context (not used).
    z : (1,) barometric height, m.
    r : not used.
    p : parameter block (layout :data:`PARAMS`).
    lay : int state layout (``LAY``).
    H, R, nu : Jacobian, covariance and innovation of the update, written at ``row``.
    row : int, first row.
    """
    nu1 = np.empty(1)
    r1 = np.empty(1)
    height(-xs[NOM.lla + 2], -z[0], p[PARAMS.sigma], nu1, r1)
    H[row, lay[LAY.pos] + 2] = 1.0
    nu[row] = nu1[0]
    R[row, row] = r1[0]
