"""Result type shared by every attitude filter."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav.results import EulerMixin, Result

Array = NDArray[np.float64]

__all__ = ["AttitudeResult"]


@dataclass(frozen=True)
class AttitudeResult(EulerMixin, Result):
    """Attitude estimate over a recording.

    Attributes
    ----------
    t : numpy.ndarray, shape (N,)
        Time, s.
    q_nb : numpy.ndarray, shape (N, 4)
        Body (FRD) -> NED quaternion, Hamilton, scalar first.
    bias : numpy.ndarray, shape (N, 3), or None
        Gyro-bias estimate, rad/s.
    cov_diag : numpy.ndarray, shape (N, k), or None
        Diagonal of the error-state covariance (attitude error, rad², first, then bias, (rad/s)²).
    flags : dict of str to numpy.ndarray
        Per-sample arrays, filter-specific (e.g. ``acc_rejected``, ``mag_disturbed``, ``rest``, ``nis``).
    name : str
        Filter name.
    params : dict
        The parameters used.
    """

    t: Array
    q_nb: Array
    bias: Array | None = None
    cov_diag: Array | None = None
    flags: dict[str, np.ndarray] = field(default_factory=dict)
    name: str = ""
    params: dict[str, Any] = field(default_factory=dict)

    @property
    def n(self) -> int:
        return int(self.q_nb.shape[0])


    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (lists of floats).

        Returns
        -------
        dict
            ``name``, ``params``, ``t``, ``q_nb``, ``bias`` and ``cov_diag`` when present, and ``flags``.
        """
        d: dict[str, Any] = {
            "name": self.name,
            "params": {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in self.params.items()},
            "t": self.t.tolist(),
            "q_nb": self.q_nb.tolist(),
        }
        if self.bias is not None:
            d["bias"] = self.bias.tolist()
        if self.cov_diag is not None:
            d["cov_diag"] = self.cov_diag.tolist()
        d["flags"] = {k: np.asarray(v).tolist() for k, v in self.flags.items()}
        return d
