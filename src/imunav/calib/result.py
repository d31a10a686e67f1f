"""Result type shared by the IMU calibration estimators."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav.calib.model import ImuCalibration, _OFF

__all__ = ["CalibrationResult", "parameter_stderr"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class CalibrationResult:
    """An estimated :class:`ImuCalibration` with its uncertainty and diagnostics.

    Attributes
    ----------
    calibration : the estimated model (its ``stderr`` holds the same numbers).
    stderr : standard errors, keys ``accel_bias`` (3,), ``accel_matrix`` (3, 3),
        ``gyro_bias``, ``gyro_matrix``, ``g_sensitivity`` (only those estimated).
    residuals : per-position / per-step residuals of each fit, raw units.
    condition : condition number of each design (column-scaled).
    segments : half-open sample-index intervals used by each fit.
    method : estimator name.
    info : further scalars (dof, residual sigma, detector threshold ...).
    """

    calibration: ImuCalibration
    stderr: dict[str, Array]
    residuals: dict[str, Array]
    condition: dict[str, float]
    segments: dict[str, Array] = field(default_factory=dict)
    method: str = ""
    info: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {
            "method": self.method,
            "calibration": self.calibration.to_dict(),
            "stderr": {k: np.asarray(v).tolist() for k, v in self.stderr.items()},
            "residuals": {k: np.asarray(v).tolist() for k, v in self.residuals.items()},
            "residual_rms": {k: np.sqrt(np.mean(np.asarray(v) ** 2, axis=0)).tolist() for k, v in self.residuals.items()},
            "condition": dict(self.condition),
            "segments": {k: np.asarray(v).tolist() for k, v in self.segments.items()},
            "info": {k: v for k, v in self.info.items() if not k.startswith("_")},
        }

    def parameter_stderr(self) -> dict[str, Array]:
        return parameter_stderr(self.stderr)


def parameter_stderr(stderr: dict[str, Array]) -> dict[str, Array]:
    """Standard errors in the thesis parameterisation (see ``calibration_parameters``)."""
    out: dict[str, Array] = {}
    nan3 = np.full(3, np.nan)
    for s in ("accel", "gyro"):
        T = stderr.get(f"{s}_matrix")
        out[f"{s}_S"] = np.diag(T).copy() if T is not None else nan3.copy()
        out[f"{s}_M"] = np.array([T[i, j] for i, j in _OFF]) if T is not None else np.full(6, np.nan)
        out[f"{s}_B"] = np.asarray(stderr.get(f"{s}_bias", nan3), float).copy()
    G = stderr.get("g_sensitivity")
    out["gyro_BG"] = np.diag(G).copy() if G is not None else nan3.copy()
    return out


def as_calibration(result: "CalibrationResult | ImuCalibration") -> ImuCalibration:
    return result.calibration if isinstance(result, CalibrationResult) else result
