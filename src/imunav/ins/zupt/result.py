"""Result type of the zero-velocity detectors (classical in :mod:`imunav.ins.zupt.detectors`,
learned in :mod:`imunav.learn.lstm`): one module below both, so that neither imports the other for it."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav.results import Result

__all__ = ["DetectorResult"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class DetectorResult(Result):
    """Output of a zero-velocity detector.

    Attributes
    ----------
    zv : numpy.ndarray of bool, shape (N,)
        True where the foot is declared stationary.
    statistic : numpy.ndarray, shape (N,)
        Test statistic ``T`` in the detector's units (NaN for learned detectors).
    threshold : numpy.ndarray, shape (N,)
        Threshold applied at each sample (same units as ``statistic``).
    detector : str
        Detector name (``"shoe"``, ``"ared"``, ``"amvd"``, ``"mbgtd"``, ``"adaptive"``,
        ``"freeacc"`` or ``"lstm"``).
    params : dict
        The settings used (window, sigmas, threshold, ...).
    """

    zv: NDArray[np.bool_]
    statistic: Array
    threshold: Array
    detector: str
    params: dict[str, Any] = field(default_factory=dict)

    @property
    def stance_fraction(self) -> float:
        """Fraction of samples declared stationary."""
        return float(np.mean(self.zv))

    def to_dict(self) -> dict[str, Any]:
        """The result as plain JSON types (flags as 0/1 lists).

        Returns
        -------
        dict
            Keys ``detector``, ``params``, ``zv``, ``statistic`` and ``threshold``.
        """
        return {"detector": self.detector, "params": self.params, "zv": self.zv.astype(int).tolist(),
                "statistic": self.statistic.tolist(), "threshold": self.threshold.tolist()}
