"""GNSS dual-antenna heading aid: a moving-base receiver's baseline heading and pitch.

Two antennas on the vehicle, the secondary at ``b`` (body FRD, m) from the primary; the receiver (a moving-base
RTK pair such as u-blox RELPOSNED, Septentrio or Trimble heading receivers) reports the baseline's azimuth ψ (from
north, clockwise, rad) and elevation θ (above the horizontal, rad) at its own time stamps, with their σ.  With the
baseline in the navigation frame ``bⁿ = C b``::

    ψ = atan2(b_E, b_N),   θ = atan2(−b_D, √(b_N² + b_E²))

and the global attitude error (``C = exp([φ×]) Ĉ``, so ``bⁿ ≈ b̂ⁿ − [b̂ⁿ×] φ``), the innovation and the rows on φ
are (Groves 2013, §10.2.5 and §16.2.1, attitude from a GNSS antenna array)::

    ν = ( wrap(ψ̃ − ψ̂),  θ̃ − θ̂ )
    H_φ = −J [b̂ⁿ×],   J = [[−b_E, b_N, 0] / h²,  [b_D b_N, b_D b_E, −h²] / (h |b|²)],   h² = b_N² + b_E²

(no position, velocity or sensor-error columns: the baseline direction depends on the attitude only), ``R`` the
reported covariance.  The lever arm of the antennas does not enter: only their difference does.

Measurement ``z``: heading and pitch (rad); ``r``: their 2×2 covariance (rad²).  Input:
:class:`imunav.io.gnss_heading.DualAntennaData`; configuration: ``GinsConfig.dual_antenna_baseline``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from imunav._rotation_kernels import dcm_from_quat_1
from imunav.filters._layout import named_layout
from imunav.ins.gins.layout import LAY, NOM

NAME = "dual_antenna"
ROWS = 2
WIDTH = 2
#: own parameters: the baseline from the primary to the secondary antenna, body FRD, m
PARAMS, N_PARAMS = named_layout("DualAntennaParams", (("baseline", 3),))


def params(config: Any) -> np.ndarray:
    """This aid's parameter block from a :class:`~imunav.ins.gins.GinsConfig` (``dual_antenna_baseline``, m;
    zeros when it is None).

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
    if config.dual_antenna_baseline is not None:
        p[PARAMS.baseline:PARAMS.baseline + 3] = config.dual_antenna_baseline
    return p


@njit(cache=True)
def rows(xs, ctx, z, r, p, lay, H, R, nu, row):
    """Write the heading and pitch rows at ``row``.

    Parameters
    ----------
    xs : nominal state (layout ``NOM``).
    ctx : update context (not used).
    z : (2,) baseline heading and pitch, rad.
    r : (2, 2) their covariance, rad² (in the first 2×2 block).
    p : parameter block (layout :data:`PARAMS`).
    lay : int state layout (``LAY``).
    H, R, nu : Jacobian, covariance and innovation of the update, written at ``row``.
    row : int, first row.
    """
    bn = dcm_from_quat_1(xs[NOM.q:NOM.q + 4]) @ p[PARAMS.baseline:PARAMS.baseline + 3]
    h2 = bn[0] * bn[0] + bn[1] * bn[1]
    h = math.sqrt(h2)
    b2 = h2 + bn[2] * bn[2]
    d = z[0] - math.atan2(bn[1], bn[0])
    nu[row] = (d + math.pi) % (2.0 * math.pi) - math.pi
    nu[row + 1] = z[1] - math.atan2(-bn[2], h)
    J = np.empty((2, 3))
    J[0, 0] = -bn[1] / h2
    J[0, 1] = bn[0] / h2
    J[0, 2] = 0.0
    J[1, 0] = bn[2] * bn[0] / (h * b2)
    J[1, 1] = bn[2] * bn[1] / (h * b2)
    J[1, 2] = -h / b2
    # H_φ = −J [bⁿ×], with [b×] = [[0, −b_D, b_E], [b_D, 0, −b_N], [−b_E, b_N, 0]]
    ia = lay[LAY.att]
    for i in range(2):
        H[row + i, ia] = -(J[i, 1] * bn[2] - J[i, 2] * bn[1])
        H[row + i, ia + 1] = -(-J[i, 0] * bn[2] + J[i, 2] * bn[0])
        H[row + i, ia + 2] = -(J[i, 0] * bn[1] - J[i, 1] * bn[0])
        for j in range(2):
            R[row + i, row + j] = r[i, j]
