"""Result type shared by the IMU calibration estimators."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav.calib.model import _OFF, ImuCalibration
from imunav.errors import InvalidInputError
from imunav.results import Result

__all__ = ["CalibrationResult", "parameter_stderr"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class CalibrationResult(Result):
    """An estimated :class:`ImuCalibration` with its uncertainty and diagnostics.

    Attributes
    ----------
    calibration : ImuCalibration
        The estimated model (its ``stderr`` holds the same numbers).
    stderr : dict
        Standard errors, keys ``accel_bias`` (3,), ``accel_matrix`` (3, 3),
        ``gyro_bias``, ``gyro_matrix``, ``g_sensitivity`` (only those estimated).
    residuals : dict
        Per-position / per-step residuals of each fit, raw units.
    condition : dict
        Condition number of each design (column-scaled).
    segments : dict
        Half-open sample-index intervals used by each fit.
    method : str
        Estimator name.
    info : dict
        Further scalars (dof, residual sigma, detector threshold ...).
    """

    calibration: ImuCalibration
    stderr: dict[str, Array]
    residuals: dict[str, Array]
    condition: dict[str, float]
    segments: dict[str, Array] = field(default_factory=dict)
    method: str = ""
    info: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary of the result.

        Returns
        -------
        dict
            ``method``, ``calibration`` (:meth:`ImuCalibration.to_dict`), ``stderr``, ``residuals``,
            ``residual_rms`` (per fit and axis, raw units), ``condition``, ``segments``, and ``info`` (its public
            entries).
        """
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
        """Standard errors in the thesis parameterisation (:func:`parameter_stderr` of :attr:`stderr`).

        Returns
        -------
        dict of str to numpy.ndarray
            The keys of :func:`imunav.calib.model.calibration_parameters`; NaN where not estimated.
        """
        return parameter_stderr(self.stderr)

    def compensation_stderr(self, f_true: Array, w_true: Array | None = None) -> tuple[Array, Array | None]:
        """Standard deviation of the compensated outputs due to the parameter uncertainty.

        First order: ``δf̂ = −T_a⁻¹ (δT_a f + δb_a)`` and
        ``δω̂ = −T_g⁻¹ (δT_g ω + δb_g + δG f)``, each output row of the fits
        being independent (separate regressions).  Needs a multi-position
        (+ rate-table) result.

        Parameters
        ----------
        f_true : array_like, shape (N, 3)
            Specific force at which to evaluate, body frame, m/s².
        w_true : array_like, shape (N, 3), optional
            Angular rate at which to evaluate, body frame, rad/s.

        Returns
        -------
        sf : numpy.ndarray, shape (N, 3)
            Standard deviation of the compensated specific force, m/s².
        sw : numpy.ndarray, shape (N, 3), or None
            Standard deviation of the compensated rate, rad/s (None without ``w_true``).

        Raises
        ------
        InvalidInputError
            If the result carries no parameter covariance (not a multi-position / combined result).
        """

        ca = self.info.get("_cov_accel")
        if ca is None:
            raise InvalidInputError("compensation_stderr needs a multiposition / combined result")
        f = np.atleast_2d(np.asarray(f_true, float))
        x = np.hstack([f, np.ones((len(f), 1))])
        va = np.einsum("np,ipq,nq->ni", x, ca, x)  # variance of (δT f + δb)_i
        Ti = np.linalg.inv(self.calibration.accel_matrix)
        sa = np.sqrt(np.einsum("ij,nj,ij->ni", Ti, va, Ti))
        if w_true is None:
            return sa, None
        w = np.atleast_2d(np.asarray(w_true, float))
        vg = np.zeros_like(w)
        cr = self.info.get("_cov_gyro_rate")
        if cr is not None:
            xr = w if cr.shape[1] == 3 else np.hstack([w, np.ones((len(w), 1))])
            vg = vg + np.einsum("np,ipq,nq->ni", xr, cr, xr)
        cs = self.info.get("_cov_gyro_static")
        if cs is not None:
            mode, C = cs
            for i in range(3):
                if mode == "diagonal":
                    xs = np.stack([f[:, i], np.ones(len(f))], axis=1)
                elif mode == "full":
                    xs = np.hstack([f, np.ones((len(f), 1))])
                else:
                    xs = np.ones((len(f), 1))
                vg[:, i] += np.einsum("np,pq,nq->n", xs, C[i], xs)
        Tg = np.linalg.inv(self.calibration.gyro_matrix)
        return sa, np.sqrt(np.einsum("ij,nj,ij->ni", Tg, vg, Tg))


def parameter_stderr(stderr: dict[str, Array]) -> dict[str, Array]:
    """Standard errors in the thesis parameterisation (see :func:`imunav.calib.model.calibration_parameters`).

    Parameters
    ----------
    stderr : dict of str to numpy.ndarray
        Standard errors keyed like the model fields (``accel_bias``, ``accel_matrix``, ``gyro_bias``,
        ``gyro_matrix``, ``g_sensitivity``).

    Returns
    -------
    dict of str to numpy.ndarray
        ``accel_S``, ``accel_B``, ``accel_M``, ``gyro_S``, ``gyro_B``, ``gyro_M``, ``gyro_BG``; NaN where a
        field was not estimated.
    """
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
    """The :class:`ImuCalibration` of a result, or the calibration itself.

    Parameters
    ----------
    result : CalibrationResult or ImuCalibration
        An estimator's result or a calibration.

    Returns
    -------
    ImuCalibration
        The calibration.
    """
    return result.calibration if isinstance(result, CalibrationResult) else result
