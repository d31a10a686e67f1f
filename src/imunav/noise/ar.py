"""Autocorrelation, Yule-Walker AR(p) and first-order Gauss-Markov models.

After Y. Günhan, *Ataletsel ölçüm birimi hatalarının belirlenmesi ve düzeltilmesi* (Detection and
compensation of inertial measurement unit errors), MSc thesis, Hacettepe University, 2014, §3.3.3 and
Appendix B, with the corrections below; Yule-Walker as in G. E. P. Box, G. M. Jenkins, G. C. Reinsel,
*Time Series Analysis*, 4th ed., Wiley, 2008, §3.2; Gauss-Markov as in R. G. Brown, P. Y. C. Hwang,
*Introduction to Random Signals and Applied Kalman Filtering*, 4th ed., Wiley, 2012.

* AR(p): ``x_k = sum_i c_i x_{k-i} + w_k`` (thesis eq. 8).  Yule-Walker with the
  p x p Toeplitz matrix of the biased autocorrelation R: ``R c = r``, i.e.
  ``c = R^-1 r`` -- *no* minus sign (the printed eq. 10 uses MATLAB aryule's
  convention ``x_k + sum a_i x_{k-i} = w_k``, a = -c).  Driving variance
  ``sigma_w^2 = R(0) - c . r``.
* Gauss-Markov: ``x_k = e^{-dt/T} x_{k-1} + w_k`` with
  ``sigma_w^2 = sigma_x^2 (1 - e^{-2 dt/T})`` (the thesis's eq. 7 lacks the 2).
  From AR(1): ``T = -dt / ln c1``; c1 <= 0 (no positive correlation at one
  lag) and c1 >= 1 (not stationary: a random walk, or a trend) have no GM
  equivalent and raise (or give NaN with ``on_invalid="nan"``).
* Correlation time from the 1/e rule: the lag at which the normalised ACF
  first falls to 1/e (linear interpolation between lags), a cross-check.
* White measurement noise biases c1 down,
  ``c1 = sigma_GM^2 e^{-dt/T} / (sigma_GM^2 + sigma_n^2)``; at high rates
  decimate (block means) or denoise first (``decimate=`` argument).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import solve_toeplitz

from imunav.errors import InsufficientDataError, InvalidInputError, NonFiniteError, ShapeError
from imunav.results import Result

__all__ = [
    "autocorrelation",
    "yule_walker",
    "ARModel",
    "GaussMarkovFit",
    "ar1_correlation_time",
    "correlation_time_acf",
    "fit_gauss_markov",
    "gm_discrete",
    "block_decimate",
    "ar1_noise_bias",
]


def _vec(x: ArrayLike, name: str = "x") -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.ndim != 1:
        raise ShapeError(f"{name} must be 1-D (one channel), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{name} has a non-finite value at index {int(np.flatnonzero(~np.isfinite(a))[0])}")
    return a


def autocorrelation(x: ArrayLike, max_lag: int | None = None, *, demean: bool = True,
                    normalize: bool = False) -> NDArray[np.float64]:
    """Biased sample autocorrelation ``R(k) = (1/N) sum_{i} x_i x_{i+k}``, k = 0..max_lag (FFT, O(N log N)).

    Parameters
    ----------
    x : array_like, shape (N,)
        The series (at least 2 samples), finite.
    max_lag : int, optional
        Largest lag, in samples, 0..N-1 (default N-1).
    demean : bool
        Subtract the mean first (autocovariance).
    normalize : bool
        Divide by R(0), so that R(0) = 1.

    Returns
    -------
    numpy.ndarray, shape (max_lag + 1,)
        R(0..max_lag), in the square of ``x``'s unit (dimensionless when normalised).

    Raises
    ------
    InsufficientDataError
        With fewer than 2 samples.
    InvalidInputError
        If ``max_lag`` is outside 0..N-1.
    """
    a = _vec(x)
    n = a.size
    if n < 2:
        raise InsufficientDataError("autocorrelation needs at least 2 samples")
    if demean:
        a = a - a.mean()
    max_lag = n - 1 if max_lag is None else int(max_lag)
    if not 0 <= max_lag < n:
        raise InvalidInputError(f"max_lag={max_lag} must be in 0..{n - 1}")
    nfft = 1 << int(np.ceil(np.log2(2 * n - 1)))
    spec = np.fft.rfft(a, nfft)
    r = np.fft.irfft(spec * np.conj(spec), nfft)[: max_lag + 1] / n
    if normalize:
        r = r / r[0] if r[0] > 0 else r
    return r


@dataclass(frozen=True)
class ARModel(Result):
    """AR(p) model ``x_k = sum c_i x_{k-i} + w_k``.

    Attributes
    ----------
    c : numpy.ndarray, shape (p,)
        Coefficients c_1..c_p (sign convention ``c = R^-1 r``).
    sigma_w2 : float
        Driving-noise variance, in the square of the series' unit.
    r0 : float
        Process variance R(0).
    """

    c: NDArray[np.float64]
    sigma_w2: float
    r0: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary of the model.

        Returns
        -------
        dict
            ``c`` (list), ``sigma_w2``, ``r0``.
        """
        return {"c": self.c.tolist(), "sigma_w2": self.sigma_w2, "r0": self.r0}


def yule_walker(x: ArrayLike, p: int = 1) -> ARModel:
    """Yule-Walker AR(p) estimate with the sign convention ``c = R^-1 r`` (Box, Jenkins & Reinsel 2008, §3.2).

    Parameters
    ----------
    x : array_like, shape (N,)
        One channel of a static record (e.g. gyro rate in rad/s), finite.
    p : int
        Model order, >= 1.

    Returns
    -------
    ARModel
        Coefficients, driving variance and process variance.

    Raises
    ------
    InvalidInputError
        If ``p < 1`` or the signal is constant.
    InsufficientDataError
        With ``p + 1`` samples or fewer.
    """
    if int(p) < 1:
        raise InvalidInputError(f"AR order p={p} must be >= 1")
    a = _vec(x)
    if a.size <= p + 1:
        raise InsufficientDataError(f"AR({p}) needs more than {p + 1} samples, got {a.size}")
    r = autocorrelation(a, p)
    if r[0] <= 0:
        raise InvalidInputError("the signal is constant; an AR model is undefined")
    c = solve_toeplitz(r[:p], r[1 : p + 1])
    return ARModel(c=np.asarray(c, dtype=float), sigma_w2=float(r[0] - c @ r[1 : p + 1]), r0=float(r[0]))


def ar1_correlation_time(c1: float, dt: float, on_invalid: Literal["raise", "nan"] = "raise") -> float:
    """Gauss-Markov correlation time T = -dt / ln c1, guarded for c1 outside (0, 1).

    Parameters
    ----------
    c1 : float
        AR(1) coefficient.
    dt : float
        Step of the series, s.
    on_invalid : {"raise", "nan"}
        What to do when c1 is outside (0, 1).

    Returns
    -------
    float
        T, s; NaN for an invalid c1 with ``on_invalid="nan"``.

    Raises
    ------
    InvalidInputError
        If c1 <= 0 (white noise dominates) or c1 >= 1 (not stationary) and ``on_invalid="raise"``.
    """
    if not (c1 > 0.0 and c1 < 1.0):
        if on_invalid == "nan":
            return float("nan")
        why = ("c1 <= 0: no positive correlation at one lag (white noise dominates; decimate or denoise first)"
               if c1 <= 0 else "c1 >= 1: the series is not stationary (random walk or trend); detrend, or model "
               "it as a random walk instead of Gauss-Markov")
        raise InvalidInputError(f"AR(1) coefficient c1={c1:.6g} has no Gauss-Markov equivalent: {why}")
    return -dt / math.log(c1)


def correlation_time_acf(x: ArrayLike, fs: float, max_lag: int | None = None) -> float:
    """Correlation time from the 1/e crossing of the normalised ACF (NaN if never reached).

    Parameters
    ----------
    x : array_like, shape (N,)
        One channel of a static record (e.g. gyro rate in rad/s), finite.
    fs : float
        Sample rate, Hz.
    max_lag : int, optional
        Largest lag searched, samples (default N // 2).

    Returns
    -------
    float
        The first lag where the normalised ACF falls to 1/e, interpolated linearly, in s; NaN if it never does.
    """
    a = _vec(x)
    r = autocorrelation(a, max_lag if max_lag is not None else a.size // 2, normalize=True)
    below = np.flatnonzero(r <= math.exp(-1.0))
    if below.size == 0:
        return float("nan")
    k = int(below[0])
    if k == 0:
        return 0.0
    # linear interpolation between lags k-1 and k
    frac = (r[k - 1] - math.exp(-1.0)) / (r[k - 1] - r[k])
    return (k - 1 + frac) / fs


def block_decimate(x: ArrayLike, q: int) -> NDArray[np.float64]:
    """Means of consecutive blocks of q samples (anti-aliasing decimation).

    A partial last block is dropped (and reported by the shorter length).

    Parameters
    ----------
    x : array_like, shape (N,)
        The series.
    q : int
        Block length, samples, >= 1.

    Returns
    -------
    numpy.ndarray, shape (N // q,)
        The block means (sample rate fs / q).

    Raises
    ------
    InvalidInputError
        If ``q < 1``.
    InsufficientDataError
        If fewer than 2 blocks are left.
    """
    a = _vec(x)
    q = int(q)
    if q < 1:
        raise InvalidInputError(f"decimation factor q={q} must be >= 1")
    nb = a.size // q
    if nb < 2:
        raise InsufficientDataError(f"decimating {a.size} samples by {q} leaves fewer than 2")
    return a[: nb * q].reshape(nb, q).mean(axis=1)


def gm_discrete(T: float, sigma: float, dt: float) -> tuple[float, float]:
    """Discrete first-order Gauss-Markov: (phi, sigma_w^2) = (e^{-dt/T}, sigma^2 (1 - e^{-2dt/T})).

    Brown & Hwang 2012 (exact discretisation of ``dx/dt = -x/T + w``).

    Parameters
    ----------
    T : float
        Correlation time, s, > 0.
    sigma : float
        Steady-state standard deviation (any unit), >= 0.
    dt : float
        Step, s, > 0.

    Returns
    -------
    phi : float
        Transition coefficient e^{-dt/T}.
    sigma_w2 : float
        Driving-noise variance per step, in ``sigma``'s unit squared.

    Raises
    ------
    InvalidInputError
        If ``T <= 0``, ``dt <= 0`` or ``sigma < 0``.
    """
    if not (T > 0 and dt > 0 and sigma >= 0):
        raise InvalidInputError("gm_discrete needs T > 0, dt > 0 and sigma >= 0")
    return math.exp(-dt / T), sigma**2 * -math.expm1(-2 * dt / T)


def ar1_noise_bias(sigma_gm: float, sigma_n: float, T: float, dt: float) -> float:
    """Expected Yule-Walker c1 of a GM process plus white noise: sigma_GM^2 e^{-dt/T} / (sigma_GM^2 + sigma_n^2).

    Parameters
    ----------
    sigma_gm : float
        Gauss-Markov standard deviation.
    sigma_n : float
        White-noise standard deviation per sample (same unit).
    T : float
        Correlation time, s.
    dt : float
        Sample interval, s.

    Returns
    -------
    float
        The expected lag-1 coefficient (below e^{-dt/T} whenever ``sigma_n > 0``).
    """
    return sigma_gm**2 * math.exp(-dt / T) / (sigma_gm**2 + sigma_n**2)


@dataclass(frozen=True)
class GaussMarkovFit(Result):
    """First-order Gauss-Markov model of a static record.

    Attributes
    ----------
    T : float
        Correlation time from AR(1), s.
    sigma : float
        Process standard deviation sqrt(R(0)), in the series' unit.
    sigma_w : float
        Driving-noise standard deviation per (decimated) step, sqrt(sigma^2 (1 - c1^2)).
    c1 : float
        AR(1) coefficient.
    dt : float
        Step of the series the AR(1) was fitted on (after decimation), s.
    T_acf : float
        1/e-rule correlation time, s (a cross-check).
    decimate : int
        Block-decimation factor used.
    """

    T: float  # correlation time from AR(1), s
    sigma: float  # process standard deviation sqrt(R(0))
    sigma_w: float  # driving noise std per (decimated) step, sqrt(sigma^2 (1 - c1^2))
    c1: float
    dt: float  # step of the series the AR(1) was fitted on (after decimation), s
    T_acf: float  # 1/e-rule correlation time, s
    decimate: int

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary of the fit.

        Returns
        -------
        dict
            The attributes by name.
        """
        return dict(self.__dict__)


def fit_gauss_markov(x: ArrayLike, fs: float, decimate: int = 1, *,
                     on_invalid: Literal["raise", "nan"] = "raise") -> GaussMarkovFit:
    """AR(1) -> Gauss-Markov pipeline on a static, deterministic-error-free record.

    The steps of Günhan 2014, §3.3.3.4 (AR(1) by Yule-Walker, T = -dt / ln c1, driving variance), after
    block decimation by ``decimate`` (recommended when the sample rate is high against 1/T).

    Parameters
    ----------
    x : array_like, shape (N,)
        One channel of a static record (e.g. gyro rate in rad/s), finite.
    fs : float
        Sample rate, Hz, > 0.
    decimate : int
        Block-decimation factor (1: none).
    on_invalid : {"raise", "nan"}
        What to do when c1 has no Gauss-Markov equivalent.

    Returns
    -------
    GaussMarkovFit
        T, sigma, the driving noise and the 1/e-rule cross-check.

    Raises
    ------
    InvalidInputError
        If ``fs`` is not positive, or c1 is outside (0, 1) with ``on_invalid="raise"``.
    InsufficientDataError
        If the (decimated) record is too short.
    """
    if not (np.isfinite(fs) and fs > 0):
        raise InvalidInputError(f"fs must be positive, got {fs!r}")
    a = block_decimate(x, decimate) if decimate > 1 else _vec(x)
    dt = decimate / fs
    m = yule_walker(a, 1)
    c1 = float(m.c[0])
    T = ar1_correlation_time(c1, dt, on_invalid)
    T_acf = correlation_time_acf(a, 1.0 / dt)
    return GaussMarkovFit(T=T, sigma=math.sqrt(m.r0), sigma_w=math.sqrt(max(m.r0 * (1 - c1**2), 0.0)), c1=c1,
                          dt=dt, T_acf=T_acf, decimate=int(decimate))
