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
:class:`DualAntennaData`; configuration: ``GinsConfig.dual_antenna_baseline``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from imunav._rotation_kernels import dcm_from_quat_1
from imunav.errors import InvalidInputError, NonFiniteError, ShapeError
from imunav.filters._layout import named_layout
from imunav.ins.gins.layout import LAY, NOM

NAME = "dual_antenna"
ROWS = 2
WIDTH = 2
#: own parameters: the baseline from the primary to the secondary antenna, body FRD, m
PARAMS, N_PARAMS = named_layout("DualAntennaParams", (("baseline", 3),))


def params(config: Any) -> np.ndarray:
    """This aid's parameter block from a :class:`~imunav.ins.gins.GinsConfig` (``dual_antenna_baseline``, m;
    zeros when it is None)."""
    p = np.zeros(N_PARAMS)
    if config.dual_antenna_baseline is not None:
        p[PARAMS.baseline:PARAMS.baseline + 3] = config.dual_antenna_baseline
    return p


@dataclass(frozen=True)
class DualAntennaData:
    """Heading and pitch of a dual-antenna (moving-base) GNSS baseline, at the receiver's time stamps.

    Parameters
    ----------
    t : array_like, shape (K,)
        Time stamps, s, strictly increasing (the IMU's time axis).
    heading : array_like, shape (K,)
        Azimuth of the baseline from north, clockwise, rad.
    pitch : array_like, shape (K,)
        Elevation of the baseline above the horizontal, rad (|pitch| < π/2).
    heading_std, pitch_std : float or array_like, shape (K,)
        Their σ, rad (> 0; a scalar applies to every epoch).
    meta : dict
        Provenance.

    Raises
    ------
    ShapeError
        If the arrays do not have K elements.
    NonFiniteError
        If a value is not finite.
    InvalidInputError
        If the stamps are not strictly increasing, a pitch is outside (−π/2, π/2) or a σ is not > 0.
    """

    t: NDArray[np.float64]
    heading: NDArray[np.float64]
    pitch: NDArray[np.float64]
    heading_std: Any
    pitch_std: Any
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        s = object.__setattr__
        t = np.asarray(self.t, dtype=float)
        k = t.size
        s(self, "t", t)
        for name in ("heading", "pitch", "heading_std", "pitch_std"):
            a = np.asarray(getattr(self, name), dtype=float) * np.ones(k)
            if a.shape != (k,):
                raise ShapeError(f"DualAntennaData.{name} must have {k} values, one per time stamp; got {a.shape}")
            if not np.all(np.isfinite(a)):
                raise NonFiniteError(f"DualAntennaData.{name} has a non-finite value at index "
                                     f"{int(np.flatnonzero(~np.isfinite(a))[0])}")
            s(self, name, a)
        if t.ndim != 1 or k < 1 or np.any(np.diff(t) <= 0):
            raise InvalidInputError("DualAntennaData.t must be strictly increasing time stamps, s")
        if np.any(np.abs(self.pitch) >= math.pi / 2):
            raise InvalidInputError("DualAntennaData.pitch must lie in (-pi/2, pi/2) rad (is it in degrees?)")
        for name in ("heading_std", "pitch_std"):
            if np.any(getattr(self, name) <= 0):
                raise InvalidInputError(f"DualAntennaData.{name} must be > 0 rad")

    def measurements(self, baseline: ArrayLike | None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``z`` (K, 2) and ``r`` (K, 2, 2) of the timed aid, for a configured baseline.

        Parameters
        ----------
        baseline : array_like, shape (3,), or None
            ``GinsConfig.dual_antenna_baseline``, body FRD, m.

        Returns
        -------
        z, r : numpy.ndarray
            Heading and pitch (rad) and their diagonal covariance (rad²).

        Raises
        ------
        InvalidInputError
            If no baseline is configured, or it is shorter than 1 cm.
        """
        if baseline is None or float(np.linalg.norm(baseline)) < 0.01:
            raise InvalidInputError("dual-antenna heading needs GinsConfig.dual_antenna_baseline (the secondary "
                                    f"antenna from the primary, body FRD, m; at least 1 cm); got {baseline!r}")
        r = np.zeros((self.t.size, 2, 2))
        r[:, 0, 0] = self.heading_std**2
        r[:, 1, 1] = self.pitch_std**2
        return np.column_stack([self.heading, self.pitch]), r


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
