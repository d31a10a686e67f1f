"""Result type of the zero-velocity detectors (classical in :mod:`imunav.ins.detectors`,
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
    zv : (N,) bool, True where the foot is declared stationary.
    statistic : (N,) float, test statistic ``T`` (NaN for learned detectors).
    threshold : (N,) float, threshold applied at each sample.
    detector : name; ``params`` the settings used.
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
        return {"detector": self.detector, "params": self.params, "zv": self.zv.astype(int).tolist(),
                "statistic": self.statistic.tolist(), "threshold": self.threshold.tolist()}
