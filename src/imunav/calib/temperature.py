"""Temperature calibration: parameters as polynomials of temperature.

After Y. Günhan, *Ataletsel ölçüm birimi hatalarının belirlenmesi ve düzeltilmesi* (Detection and
compensation of inertial measurement unit errors), MSc thesis, Hacettepe University, 2014, ch. 6
(Tables 6.1/6.2), Y. Günhan, Ç. Ünsal, "Polynomial degree determination for temperature dependent error
compensation of inertial sensors", IEEE/ION PLANS 2014, and E. Atasoy, *Estimation and analysis of error
parameters of attitude-heading reference system sensors* (in Turkish), MSc thesis, Başkent University,
§5.2 and §7.1.  For each parameter p (a bias component, or a diagonal scale element)
measured at temperatures T_k::

    p(T) = Σ_{i=0}^{n} c_i x^i (+ h [T ≥ T_step]),     x = (T − T_c) / T_s

with the temperature centred and scaled (a 5th-order fit in raw °C is badly
conditioned) and an optional step for the abrupt changes seen on real units
(Atasoy, §7.1: a 24-25 °C step).  Each order n = 1…5 is fitted by
least squares and reported with the thesis's metrics: in-sample mean-square
error (Tables 6.1/6.2 print it as "RMS" - it is the MSE), the largest
positive residual and the magnitude of the largest negative one (the tables'
"max"/"min" rows), and the leave-one-out cross-validation MSE (closed form
``e_i / (1 − h_ii)``).  The order is chosen from the LOO MSE (in-sample
residuals always fall with the order,
so they cannot choose it), using the one-standard-error rule (Hastie, Tibshirani & Friedman, *The
Elements of Statistical Learning*, 2nd ed., 2009, §7.10): the smallest
order whose LOO MSE is within one standard error (or ``tol``) of the best.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Iterable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.calib.model import ImuCalibration, TempCurve
from imunav.errors import InsufficientDataError, InvalidInputError, ShapeError
from imunav.results import Result

__all__ = ["OrderMetrics", "TemperatureFit", "fit_temperature_curve", "ThermalResult", "thermal_calibration"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class OrderMetrics(Result):
    """Fit of one order: coefficients, stderr and the thesis's residual metrics.

    Attributes
    ----------
    order : int
        Polynomial order.
    curve : TempCurve
        The fitted curve (temperature in °C, value in the parameter's unit).
    stderr : numpy.ndarray
        Standard errors of the coefficients.
    mse : float
        In-sample mean-square error (the tables' "RMS").
    max_residual : float
        Largest positive residual.
    min_residual_abs : float
        Magnitude of the largest negative residual.
    loo_mse : float
        Leave-one-out cross-validation MSE.
    residuals, loo_residuals : numpy.ndarray, shape (K,)
        In-sample and leave-one-out residuals.
    """

    order: int
    curve: TempCurve
    stderr: Array
    mse: float
    max_residual: float
    min_residual_abs: float
    loo_mse: float
    residuals: Array
    loo_residuals: Array

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary of the fit (residual arrays left out).

        Returns
        -------
        dict
            ``order``, ``curve``, ``stderr``, ``mse``, ``rms``, ``max_residual``, ``min_residual_abs``, ``loo_mse``.
        """
        return {
            "order": self.order,
            "curve": self.curve.to_dict(),
            "stderr": self.stderr.tolist(),
            "mse": self.mse,
            "rms": float(np.sqrt(self.mse)),
            "max_residual": self.max_residual,
            "min_residual_abs": self.min_residual_abs,
            "loo_mse": self.loo_mse,
        }


@dataclass(frozen=True)
class TemperatureFit(Result):
    """All fitted orders of one parameter and the chosen one.

    Attributes
    ----------
    temp_c : numpy.ndarray, shape (K,)
        Calibration temperatures, °C.
    values : numpy.ndarray, shape (K,)
        The parameter at each temperature.
    fits : tuple of OrderMetrics
        One fit per order tried.
    chosen_order : int
        The order selected (or forced).
    model : str
        ``"poly"`` or ``"piecewise"``.
    """

    temp_c: Array
    values: Array
    fits: tuple[OrderMetrics, ...]
    chosen_order: int
    model: str

    @property
    def curve(self) -> TempCurve:
        return self.best.curve

    @property
    def best(self) -> OrderMetrics:
        return next(f for f in self.fits if f.order == self.chosen_order)

    def table(self) -> dict[str, list[float]]:
        """Rows of Günhan 2014, Tables 6.1/6.2 (MSE, max residual, |min residual|) plus LOO MSE, per order.

        Returns
        -------
        dict of str to list of float
            ``order``, ``mse``, ``max_residual``, ``min_residual_abs``, ``loo_mse`` (one entry per order).
        """
        return {
            "order": [f.order for f in self.fits],
            "mse": [f.mse for f in self.fits],
            "max_residual": [f.max_residual for f in self.fits],
            "min_residual_abs": [f.min_residual_abs for f in self.fits],
            "loo_mse": [f.loo_mse for f in self.fits],
        }

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary of all fits.

        Returns
        -------
        dict
            ``model``, ``chosen_order``, ``temp_c``, ``values``, ``fits``.
        """
        return {
            "model": self.model,
            "chosen_order": self.chosen_order,
            "temp_c": self.temp_c.tolist(),
            "values": self.values.tolist(),
            "fits": [f.to_dict() for f in self.fits],
        }


def _design(x: Array, order: int, step: Array | None) -> Array:
    X = np.vander(x, order + 1, increasing=True)
    return X if step is None else np.hstack([X, step[:, None]])


def _fit_one(t: Array, y: Array, order: int, cc: float, sc: float, step_c: float | None) -> OrderMetrics:
    x = (t - cc) / sc
    step = None if step_c is None else (t >= step_c).astype(float)
    X = _design(x, order, step)
    k, p = X.shape
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    r = y - X @ coef
    XtXi = np.linalg.pinv(X.T @ X)
    hdiag = np.einsum("ij,jk,ik->i", X, XtXi, X)
    with np.errstate(divide="ignore", invalid="ignore"):
        loo = r / (1.0 - hdiag)
    loo_mse = float(np.mean(loo**2)) if np.all(1.0 - hdiag > 1e-9) else float("inf")
    dof = k - p
    s2 = float(r @ r / dof) if dof > 0 else float("nan")
    se = np.sqrt(np.maximum(np.diag(XtXi) * s2, 0)) if dof > 0 else np.full(p, np.nan)
    curve = TempCurve(coef[: order + 1], cc, sc, step_c, float(coef[-1]) if step_c is not None else 0.0)
    return OrderMetrics(order, curve, se, float(np.mean(r**2)), float(r.max()), float(max(-r.min(), 0.0)), loo_mse, r, loo)


def fit_temperature_curve(
    temp_c: ArrayLike,
    values: ArrayLike,
    *,
    orders: Iterable[int] = range(1, 6),
    model: str = "poly",
    step_c: float | None = None,
    center_c: float | None = None,
    scale_c: float | None = None,
    tol: float = 1.0,
    order: int | None = None,
) -> TemperatureFit:
    """Fit a parameter against temperature for several polynomial orders.

    Parameters
    ----------
    temp_c : array_like, shape (K,)
        Calibration temperatures, °C.
    values : array_like, shape (K,)
        The parameter at each temperature (bias in its unit, or a diagonal element of T).
    orders : iterable of int
        Orders to try (1-5 in the thesis).
    model : {"poly", "piecewise"}
        Polynomial, or polynomial + one step.
    step_c : float, optional
        Temperature of the step of the piecewise model, °C (found by search over the mid-points between
        temperatures if None).
    center_c, scale_c : float, optional
        Temperature normalisation, °C (default: mid-range and half-range of ``temp_c``).
    tol : float
        Relative LOO tolerance: a higher order must beat a lower one by more than a
        factor ``1 + tol`` and by more than one standard error.
    order : int, optional
        Force the chosen order instead of LOO selection.

    Returns
    -------
    TemperatureFit
        Every order's fit and the chosen one.

    Raises
    ------
    ShapeError
        If ``temp_c`` and ``values`` are not equal-length 1-D arrays.
    InvalidInputError
        If a value is not finite, ``orders`` or ``model`` is invalid, ``scale_c`` is not positive, or a
        forced ``order`` was not fitted.
    InsufficientDataError
        With too few temperatures for the highest order.
    """
    t = np.asarray(temp_c, float)
    y = np.asarray(values, float)
    if t.ndim != 1 or y.shape != t.shape:
        raise ShapeError(f"temp_c {t.shape} and values {y.shape} must be equal-length 1-D arrays")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
        raise InvalidInputError("temp_c and values must be finite")
    orders = sorted(set(int(o) for o in orders))
    if not orders or orders[0] < 0:
        raise InvalidInputError(f"orders must be non-negative integers, got {orders}")
    if model not in ("poly", "piecewise"):
        raise InvalidInputError(f"model must be 'poly' or 'piecewise', not {model!r}")
    n_extra = 1 if model == "piecewise" else 0
    need = orders[-1] + 2 + n_extra
    if np.unique(t).size < need:
        raise InsufficientDataError(
            f"temperature fit up to order {orders[-1]} ({model}) needs at least {need} distinct temperatures, "
            f"got {np.unique(t).size}; lower the orders or add temperature points"
        )
    cc = float((t.max() + t.min()) / 2) if center_c is None else float(center_c)
    sc = float((t.max() - t.min()) / 2) if scale_c is None else float(scale_c)
    if sc <= 0:
        raise InvalidInputError(f"scale_c must be positive, got {sc}")
    fits = []
    for o in orders:
        sc_ = None
        if model == "piecewise":
            if step_c is not None:
                sc_ = float(step_c)
            else:
                u = np.unique(t)
                cands = (u[1:-2] + u[2:-1]) / 2 if u.size > 4 else (u[:-1] + u[1:]) / 2
                best = None
                for c in cands:
                    m = _fit_one(t, y, o, cc, sc, float(c))
                    if best is None or m.mse < best[0]:
                        best = (m.mse, float(c))
                sc_ = best[1]  # type: ignore[index]
        fits.append(_fit_one(t, y, o, cc, sc, sc_))
    if order is not None:
        if order not in orders:
            raise InvalidInputError(f"order {order} is not among the fitted orders {orders}")
        chosen = order
    else:
        # one-standard-error rule on the LOO MSE (Hastie et al., ESL §7.10)
        ib = int(np.argmin([f.loo_mse for f in fits]))
        fb = fits[ib]
        se = float(np.std(fb.loo_residuals**2, ddof=1) / np.sqrt(len(t))) if np.isfinite(fb.loo_mse) else 0.0
        limit = max(fb.loo_mse + se, (1 + tol) * fb.loo_mse)
        chosen = next(f.order for f in fits if f.loo_mse <= limit)
    return TemperatureFit(t, y, tuple(fits), chosen, model)


@dataclass(frozen=True)
class ThermalResult(Result):
    """Thermal model of an IMU: per parameter and axis a :class:`TemperatureFit`.

    Attributes
    ----------
    calibration : ImuCalibration
        The calibration with its ``thermal`` curves.
    fits : dict of str to tuple of TemperatureFit
        Per parameter (``accel_bias``, ``accel_scale``, ``gyro_bias``, ``gyro_scale``), one fit per axis.
    """

    calibration: ImuCalibration
    fits: dict[str, tuple[TemperatureFit, TemperatureFit, TemperatureFit]] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary of the model.

        Returns
        -------
        dict
            ``calibration`` and ``fits``.
        """
        return {
            "calibration": self.calibration.to_dict(),
            "fits": {k: [f.to_dict() for f in v] for k, v in self.fits.items()},
        }


def thermal_calibration(
    temps_c: Sequence[float],
    calibrations: Sequence[ImuCalibration],
    *,
    params: Sequence[str] = ("accel_bias", "accel_scale", "gyro_bias", "gyro_scale"),
    orders: Iterable[int] = range(1, 6),
    model: str = "poly",
    order: int | None = None,
    tol: float = 1.0,
) -> ThermalResult:
    """Temperature model from calibrations repeated at several temperatures (Günhan 2014, ch. 6).

    The constant part of the result is the calibration closest to the
    centre temperature; ``params`` get temperature curves (scale = diagonal of T).

    Parameters
    ----------
    temps_c : sequence of float
        Temperature of each calibration, °C.
    calibrations : sequence of ImuCalibration
        One calibration per temperature.
    params : sequence of str
        Parameters that get curves, from ``accel_bias``, ``accel_scale``, ``gyro_bias``, ``gyro_scale``.
    orders : iterable of int
        Orders to try.
    model : {"poly", "piecewise"}
        Curve model.
    order : int, optional
        Force the order.
    tol : float
        LOO tolerance (see :func:`fit_temperature_curve`).

    Returns
    -------
    ThermalResult
        The temperature-dependent calibration and every fit.

    Raises
    ------
    ShapeError
        If the numbers of temperatures and calibrations differ.
    InvalidInputError
        If a parameter name is unknown.
    """
    t = np.asarray(temps_c, float)
    if len(calibrations) != t.size:
        raise ShapeError(f"{t.size} temperatures but {len(calibrations)} calibrations")
    getters = {
        "accel_bias": lambda c: c.accel_bias,
        "gyro_bias": lambda c: c.gyro_bias,
        "accel_scale": lambda c: np.diag(c.accel_matrix),
        "gyro_scale": lambda c: np.diag(c.gyro_matrix),
    }
    fits: dict[str, tuple[TemperatureFit, TemperatureFit, TemperatureFit]] = {}
    for p in params:
        if p not in getters:
            raise InvalidInputError(f"unknown thermal parameter {p!r}; use {list(getters)}")
        v = np.array([getters[p](c) for c in calibrations])
        fits[p] = tuple(
            fit_temperature_curve(t, v[:, i], orders=orders, model=model, order=order, tol=tol) for i in range(3)
        )  # type: ignore[assignment]
    ref = calibrations[int(np.argmin(np.abs(t - (t.max() + t.min()) / 2)))]
    cal = ref.with_(
        thermal={k: tuple(f.curve for f in v) for k, v in fits.items()},
        meta={**ref.meta, "thermal": {k: [f.chosen_order for f in v] for k, v in fits.items()}},
    )
    return ThermalResult(cal, fits)
