"""Filter consistency: NIS, NEES and their χ² acceptance bounds.

For a consistent filter the normalised innovation squared
``NIS = νᵀ S⁻¹ ν`` is χ²(m) and the normalised estimation error squared
``NEES = eᵀ P⁻¹ e`` is χ²(n) (Bar-Shalom, Li & Kirubarajan 2001, §5.4).
Averaged over ``R`` independent runs (and/or ``K`` steps), ``R·K·mean`` is
χ²(R·K·dof), which gives the two-sided bounds of :func:`chi2_bounds`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav._quantiles import chi2_ppf
from imunav.errors import InvalidInputError, ShapeError
from imunav.results import Result

__all__ = ["nis", "nees", "chi2_bounds", "ConsistencyResult", "consistency_test"]

Array = NDArray[np.float64]


def _quadratic(e: ArrayLike, C: ArrayLike, name_e: str, name_c: str) -> Array:
    e = np.asarray(e, dtype=np.float64)
    C = np.asarray(C, dtype=np.float64)
    if e.ndim == 0 or C.shape[-2:] != (e.shape[-1], e.shape[-1]) or C.shape[:-2] != e.shape[:-1]:
        raise ShapeError(f"{name_e} {e.shape} and {name_c} {C.shape} do not match: need (..., k) and (..., k, k)")
    sol = np.linalg.solve(C, e[..., None])[..., 0]
    return np.einsum("...i,...i->...", e, sol)


def nis(innovation: ArrayLike, S: ArrayLike) -> Array:
    """Normalised innovation squared ``νᵀ S⁻¹ ν`` for (..., m) and (..., m, m).

    Parameters
    ----------
    innovation : array_like, shape (..., m)
        Innovations ν.
    S : array_like, shape (..., m, m)
        Their covariances.

    Returns
    -------
    numpy.ndarray, shape (...)
        NIS values, ~ χ²(m) for a consistent filter.
    """
    return _quadratic(innovation, S, "innovation", "S")


def nees(error: ArrayLike, P: ArrayLike) -> Array:
    """Normalised estimation error squared ``eᵀ P⁻¹ e`` for (..., n) and (..., n, n).

    Parameters
    ----------
    error : array_like, shape (..., n)
        Estimation errors e = x̂ − x.
    P : array_like, shape (..., n, n)
        The filter's covariances.

    Returns
    -------
    numpy.ndarray, shape (...)
        NEES values, ~ χ²(n) for a consistent filter.
    """
    return _quadratic(error, P, "error", "P")


def chi2_bounds(dof: int, n_samples: int = 1, confidence: float = 0.95) -> tuple[float, float]:
    """Two-sided bounds for the mean of ``n_samples`` independent χ²(dof) values.

    ``n·mean ~ χ²(n·dof)`` so the bounds are ``χ²⁻¹((1∓c)/2, n·dof) / n``.
    Example: dof 2, 50 runs, 95 % → (1.60, 2.45) (Bar-Shalom et al. 2001, §5.4.2).

    Parameters
    ----------
    dof : int
        Degrees of freedom of each value, >= 1.
    n_samples : int
        Number of values averaged, >= 1.
    confidence : float
        Two-sided probability in (0, 1).

    Returns
    -------
    lower, upper : float
        Bounds of the mean.

    Raises
    ------
    InvalidInputError
        If ``dof`` or ``n_samples`` is below 1, or ``confidence`` outside (0, 1).
    """
    if dof < 1 or n_samples < 1:
        raise InvalidInputError(f"dof and n_samples must be >= 1, got {dof}, {n_samples}")
    if not 0 < confidence < 1:
        raise InvalidInputError(f"confidence must be in (0, 1), got {confidence}")
    a = (1.0 - confidence) / 2.0
    k = dof * n_samples
    return float(chi2_ppf(a, k) / n_samples), float(chi2_ppf(1 - a, k) / n_samples)


@dataclass(frozen=True)
class ConsistencyResult(Result):
    """Per-step Monte Carlo averages of a χ² statistic and their bounds.

    The pooled ``time_bounds`` assume independent steps, which holds for NIS (white innovations) but not for
    NEES (errors are correlated in time): judge NEES by ``fraction_inside`` and the per-step bounds.

    Attributes
    ----------
    dof : int
        Degrees of freedom of each value.
    n_runs : int
        Number of runs averaged.
    confidence : float
        Two-sided probability of the bounds.
    mean_per_step : numpy.ndarray, shape (steps,)
        Average over runs at each step.
    lower, upper : float
        Bounds for that average (:func:`chi2_bounds`).
    fraction_inside : float
        Share of steps inside the bounds.
    time_average : float
        Average over all runs and steps.
    time_bounds : tuple of float
        Bounds for ``time_average``.
    passed : bool
        ``time_bounds[0] <= time_average <= time_bounds[1]`` and ``fraction_inside >= confidence - 3 sd`` of
        the binomial count.
    """

    dof: int
    n_runs: int
    confidence: float
    mean_per_step: Array
    lower: float
    upper: float
    fraction_inside: float
    time_average: float
    time_bounds: tuple[float, float]
    passed: bool


def consistency_test(values: ArrayLike, dof: int, confidence: float = 0.95) -> ConsistencyResult:
    """χ² consistency check of NIS or NEES values of shape (runs, steps) or (steps,).

    Parameters
    ----------
    values : array_like, shape (runs, steps) or (steps,)
        NIS or NEES values (NaN steps are left out).
    dof : int
        Degrees of freedom of each value.
    confidence : float
        Two-sided probability of the bounds.

    Returns
    -------
    ConsistencyResult
        Averages, bounds and the verdict.

    Raises
    ------
    ShapeError
        If ``values`` is not 1-D or 2-D, or empty.
    InvalidInputError
        If no step is free of NaN, or ``dof`` / ``confidence`` is out of range.
    """
    v = np.asarray(values, dtype=np.float64)
    if v.ndim == 1:
        v = v[None, :]
    if v.ndim != 2 or v.size == 0:
        raise ShapeError(f"values must be (runs, steps) or (steps,), got {np.shape(values)}")
    v = v[:, ~np.isnan(v).any(axis=0)]
    if v.shape[1] == 0:
        raise InvalidInputError("values has no step without NaN")
    R, K = v.shape
    mean = v.mean(axis=0)
    lo, hi = chi2_bounds(dof, R, confidence)
    inside = float(np.mean((mean >= lo) & (mean <= hi)))
    ta = float(v.mean())
    tb = chi2_bounds(dof, R * K, confidence)
    slack = 3.0 * np.sqrt(confidence * (1 - confidence) / K)
    passed = bool(tb[0] <= ta <= tb[1] and inside >= confidence - slack)
    return ConsistencyResult(int(dof), int(R), float(confidence), mean, lo, hi, inside, ta, tb, passed)
