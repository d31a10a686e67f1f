"""Zero-velocity update of a vehicle at rest: ``0 = v + n``.

``ν = −v̂``, ``H = [0 I 0 …]`` on the velocity error, ``R = σ² I`` with σ the body's vibration at rest (e.g. engine
idle) (:func:`imunav.filters._core_models.zero_velocity`; Groves 2013, §15.3.1).  Joint with the ZARU while the
vehicle is declared static.

Measurement ``z``: one placeholder column (0 where the vehicle is static, NaN elsewhere).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from imunav.filters._core_models import zero_velocity
from imunav.filters._layout import named_layout
from imunav.ins.gins.layout import LAY, NOM

NAME = "zupt"
ROWS = 3
WIDTH = 1
#: own parameters: the velocity σ at rest, m/s
PARAMS, N_PARAMS = named_layout("ZuptParams", (("sigma", 1),))


def params(config: Any) -> np.ndarray:
    """This aid's parameter block from a :class:`~imunav.ins.gins.GinsConfig` (``zupt_noise_std``, m/s).

    Parameters
    ----------
    config : GinsConfig
        The filter configuration.

    Returns
    -------
    numpy.ndarray, shape (N_PARAMS,)
        The block, layout :data:`PARAMS`.
    """
    return np.array([config.zupt_noise_std], dtype=float)


@njit(cache=True)
def rows(xs, ctx, z, r, p, lay, H, R, nu, row):
    """Write the three ZUPT rows at ``row``.

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
    nu3 = np.empty(3)
    r3 = np.empty(3)
    zero_velocity(xs[NOM.vel:NOM.vel + 3], p[PARAMS.sigma], nu3, r3)
    iv = lay[LAY.vel]
    for j in range(3):
        H[row + j, iv + j] = 1.0
        nu[row + j] = nu3[j]
        R[row + j, row + j] = r3[j]
