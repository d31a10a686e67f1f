"""Sensor error models of the virtual IMU.

Measurement model per triad (Y. Günhan, *Ataletsel ölçüm birimi hatalarının belirlenmesi ve düzeltilmesi* (Detection and
compensation of inertial measurement unit errors), MSc thesis, Hacettepe University, 2014,
eqs. 2 and 4, with a full 3x3 gyro g-sensitivity and temperature polynomials)::

    f~ = T_a(dT) f + b_a(dT) + s_a(t) + n_a
    w~ = T_g(dT) w + b_g(dT) + G f + s_g(t) + n_g

    T(dT)  = I + diag(S) + M + diag(sum_k c^S_k dT^k)      scale factor / misalignment
    b(dT)  = b + sum_k c^b_k dT^k                          bias, dT = temp - temp_ref_c
    s(t)   = bias instability (Gauss-Markov or flicker) + rate random walk + rate ramp
    n      = white noise of density N (ARW / VRW): sigma_sample = N sqrt(f_s)

followed by quantization to the LSB q and, optionally, saturation at the
full scale.  ``M`` has a zero diagonal and ``M[i, j]`` is the response of the
axis-i sensor to an axis-j input (matrix convention of the thesis, eq. 2).  Every parameter is SI: rad/s and m/s^2 for biases, unit/sqrt(Hz)
for noise densities, unit/s/sqrt(s) for random walks, unit/s for ramps.

Stochastic terms and their Allan variances (IEEE Std 952-1997, Annex C; the Gauss-Markov form as in
N. El-Sheimy, H. Hou, X. Niu, "Analysis and modeling of inertial sensors using Allan variance", IEEE
Trans. Instrum. Meas. 57(1), 2008)::

    white noise  N         N^2 / tau
    quantization Q         3 Q^2 / tau^2         (integrating output, Q = q dt / sqrt(12))
    bias instab. B         (2 ln 2 / pi) B^2     flat floor: B = sigma_min / 0.6643
    Gauss-Markov (sigma,T) (2 sigma^2 T / tau)[1 - (T / 2tau)(3 - 4 e^(-tau/T) + e^(-2tau/T))]
    random walk  K         K^2 tau / 3
    rate ramp    R         R^2 tau^2 / 2

The Gauss-Markov process is discretised exactly: x_k = phi x_(k-1) +
sigma sqrt(1 - phi^2) w_k with phi = exp(-dt / T) (the thesis's eq. 7 lacks
the factor 2 in 1 - exp(-2 dt / T)).

Random streams: one xoshiro256++ stream per (sensor, process, axis,
component), seeded by ``SeedSequence(seed)`` with the spawn key extended by
(sensor, process, axis, component); normals by a 256-layer ziggurat
(:mod:`imunav.sim._kernels`).  A stream therefore depends only on the seed and on its
own key: switching a process on or off does not change the others, and the
axes are independent.
"""

from __future__ import annotations

import math
import numbers
import os
import warnings
from collections.abc import Mapping
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, fields, replace
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import nnls

from imunav import allan_models as _am
from imunav import units as _units
from imunav.errors import (
    ConfigError,
    FileFormatError,
    ImunavWarning,
    InsufficientDataError,
    InvalidInputError,
    NonFiniteError,
    ShapeError,
    UnitError,
)
from imunav.files import atomic_path
from imunav.results import Result
from imunav.sim import _kernels as _k
from imunav.sim.streams import normals, seed_sequence, stream_state
from imunav.sim.trajectory import ideal_imu
from imunav.toml import read_toml, toml_text

if TYPE_CHECKING:  # pragma: no cover
    from imunav.timeseries import ImuData

__all__ = [
    "BIAS_INSTABILITY_FLOOR",
    "Flicker",
    "GaussMarkov",
    "ImuErrorModel",
    "ImuErrorTruth",
    "TriadErrors",
    "TriadTruth",
    "allan_variance_gauss_markov",
    "allan_variance_ieee952",
    "apply_errors",
    "normals",
    "scale_misalignment_matrix",
    "seed_sequence",
    "simulate_imu",
    "stream_state",
]

#: sigma_A at the flat bias-instability floor is BIAS_INSTABILITY_FLOOR * B,
#: sqrt(2 ln 2 / pi) = 0.6643 (IEEE Std 952-1997, C.3).
BIAS_INSTABILITY_FLOOR = _am.BI_FACTOR

# stream keys (sensor, process): never renumber, streams depend on them
_SENSOR_KEY = {"gyro": 0, "accel": 1, "mag": 2}
_PROC_WHITE, _PROC_BIAS_INSTABILITY, _PROC_RANDOM_WALK = 0, 1, 2


# --------------------------------------------------------------------------
# validation helpers
# --------------------------------------------------------------------------
def _vec3(value: Any, where: str, *, nonneg: bool = False, positive: bool = False) -> NDArray[np.float64]:
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as e:
        raise InvalidInputError(f"{where}: expected a number or 3 numbers, got {value!r}") from e
    if a.ndim == 0:
        a = np.full(3, float(a))
    if a.shape != (3,):
        raise ShapeError(f"{where}: expected a scalar or 3 values (x, y, z), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{where}: values must be finite, got {a.tolist()}")
    if positive and np.any(a <= 0):
        raise InvalidInputError(f"{where}: values must be > 0, got {a.tolist()}")
    if nonneg and np.any(a < 0):
        raise InvalidInputError(
            f"{where}: values must be >= 0 (a standard deviation / density / LSB), got {a.tolist()}"
        )
    a = a.copy()
    a.setflags(write=False)
    return a


def _mat3(value: Any, where: str) -> NDArray[np.float64]:
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as e:
        raise InvalidInputError(f"{where}: expected a 3x3 matrix, got {value!r}") from e
    if a.shape != (3, 3):
        raise ShapeError(f"{where}: expected a 3x3 matrix, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{where}: matrix entries must be finite")
    a = a.copy()
    a.setflags(write=False)
    return a


def _poly(value: Any, where: str) -> NDArray[np.float64]:
    if value is None:
        a = np.zeros((0, 3))
    else:
        a = np.asarray(value, dtype=float)
        if a.size == 0:
            a = np.zeros((0, 3))
    if a.ndim != 2 or a.shape[1] != 3:
        raise ShapeError(
            f"{where}: expected shape (K, 3) - row k-1 holds the coefficients of (T - temp_ref)^k "
            f"for x, y, z - got shape {a.shape}"
        )
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{where}: coefficients must be finite")
    a = a.copy()
    a.setflags(write=False)
    return a


def scale_misalignment_matrix(scale_factor: ArrayLike = 0.0, misalignment: ArrayLike = 0.0) -> NDArray[np.float64]:
    """T = I + diag(S) + M from scale-factor errors S and misalignments M.

    Parameters
    ----------
    scale_factor : float or (3,)
        Scale-factor errors S_i (ratio; 1e-6 per ppm).
    misalignment : float, (6,) or (3, 3)
        Off-diagonal terms (rad, small angles): six values in the order
        (M_xy, M_xz, M_yx, M_yz, M_zx, M_zy), or a 3x3 matrix with zero
        diagonal.  ``M[i, j]`` is the response of sensor i to an input on
        axis j (Günhan 2014, eq. 2).

    Returns
    -------
    numpy.ndarray, shape (3, 3)
        T, dimensionless.

    Raises
    ------
    ShapeError
        If ``scale_factor`` is not a scalar or 3 values, or ``misalignment`` not a scalar, 6 values or 3x3.
    InvalidInputError
        If a 3x3 ``misalignment`` has a non-zero diagonal, or ``scale_factor`` is not numeric.
    NonFiniteError
        If a value is not finite.
    """
    s = _vec3(scale_factor, "scale_factor")
    m = np.asarray(misalignment, dtype=float)
    if m.ndim == 0:
        mm = np.full((3, 3), float(m))
        np.fill_diagonal(mm, 0.0)
    elif m.shape == (6,):
        mm = np.zeros((3, 3))
        mm[0, 1], mm[0, 2], mm[1, 0], mm[1, 2], mm[2, 0], mm[2, 1] = m
    elif m.shape == (3, 3):
        if np.any(np.diag(m) != 0):
            raise InvalidInputError(
                f"misalignment: the diagonal must be zero (scale factors go in scale_factor), got {np.diag(m).tolist()}"
            )
        mm = m.copy()
    else:
        raise ShapeError(
            f"misalignment: expected a scalar, 6 values (M_xy, M_xz, M_yx, M_yz, M_zx, M_zy) or a 3x3 matrix, "
            f"got shape {m.shape}"
        )
    if not np.all(np.isfinite(mm)):
        raise NonFiniteError("misalignment: values must be finite")
    return np.eye(3) + np.diag(s) + mm


# --------------------------------------------------------------------------
# Allan-variance closed forms
# --------------------------------------------------------------------------
def allan_variance_gauss_markov(tau: ArrayLike, sigma: float, corr_time: float) -> NDArray[np.float64]:
    """Allan variance of a first-order Gauss-Markov process (El-Sheimy, Hou & Niu 2008).

    sigma_A^2(tau) = (2 sigma^2 T / tau) [1 - (T / 2 tau)(3 - 4 e^(-tau/T) + e^(-2 tau/T))]

    evaluated by :func:`imunav.allan_models.gauss_markov` (exact series below
    tau / T = 1/2, shared with :mod:`imunav.noise`).

    Parameters
    ----------
    tau : array_like
        Averaging times, s.
    sigma : float
        Stationary standard deviation of the process (unit of the signal).
    corr_time : float
        Correlation time T, s.

    Returns
    -------
    numpy.ndarray
        sigma_A^2 at each ``tau``, unit².
    """
    return _am.gauss_markov(tau, sigma, corr_time)


def allan_variance_ieee952(
    tau: ArrayLike, *, Q: float = 0.0, N: float = 0.0, B: float = 0.0, K: float = 0.0, R: float = 0.0
) -> NDArray[np.float64]:
    """IEEE-952 sum sigma^2 = 3Q^2/tau^2 + N^2/tau + (2 ln2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2.

    Evaluated by :func:`imunav.allan_models.ieee952` (shared with :mod:`imunav.noise`); IEEE Std 952-1997,
    Annex C.

    Parameters
    ----------
    tau : array_like
        Averaging times, s.
    Q : float
        Quantization noise coefficient (unit·s).
    N : float
        White-noise density, unit/sqrt(Hz).
    B : float
        Bias-instability coefficient, unit.
    K : float
        Random-walk coefficient, unit/sqrt(s).
    R : float
        Rate-ramp coefficient, unit/s.

    Returns
    -------
    numpy.ndarray
        sigma_A^2 at each ``tau``, unit².
    """
    return _am.ieee952(tau, Q=Q, N=N, B=B, K=K, R=R)


# --------------------------------------------------------------------------
# bias-instability processes
# --------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class GaussMarkov:
    """First-order Gauss-Markov bias instability.

    Parameters
    ----------
    sigma : float or (3,)
        Stationary standard deviation (rad/s or m/s^2), >= 0.
    tau : float or (3,)
        Correlation time T_c in seconds, > 0.
    """

    sigma: Any
    tau: Any

    def __post_init__(self) -> None:
        object.__setattr__(self, "sigma", _vec3(self.sigma, "GaussMarkov.sigma", nonneg=True))
        object.__setattr__(self, "tau", _vec3(self.tau, "GaussMarkov.tau (correlation time, s)", positive=True))

    def components(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(sigmas, taus), each (n_components, 3): here one component.

        Returns
        -------
        sigmas : numpy.ndarray, shape (1, 3)
            Stationary standard deviation per axis.
        taus : numpy.ndarray, shape (1, 3)
            Correlation time per axis, s.
        """
        return self.sigma[None, :].copy(), self.tau[None, :].copy()

    def allan_variance(self, tau: ArrayLike) -> NDArray[np.float64]:
        """Closed-form Allan variance, shape (3, len(tau)).

        Parameters
        ----------
        tau : array_like
            Averaging times, s.

        Returns
        -------
        numpy.ndarray, shape (3, len(tau))
            sigma_A^2 per axis (:func:`allan_variance_gauss_markov`).
        """
        return np.stack([allan_variance_gauss_markov(tau, s, t) for s, t in zip(self.sigma, self.tau)])

    def to_dict(self) -> dict[str, Any]:
        """JSON / TOML form (the ``bias_instability`` table of a model file).

        Returns
        -------
        dict
            ``model = "gauss_markov"``, ``sigma`` and ``tau`` (lists of 3).
        """
        return {"model": "gauss_markov", "sigma": self.sigma.tolist(), "tau": self.tau.tolist()}

    def __eq__(self, other: object) -> bool:
        return isinstance(other, GaussMarkov) and _deep_equal(self.to_dict(), other.to_dict())

    __hash__ = None  # type: ignore[assignment]


@lru_cache(maxsize=32)
def _flicker_weights(tau_min: float, tau_max: float, per_decade: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Correlation times and unit-B variances of the GM sum that has a flat Allan floor.

    The targets are sigma_A^2 = (2 ln2 / pi) on 80 log-spaced tau in
    [tau_min, tau_max]; the component variances are the non-negative
    least-squares solution in relative error (scipy.optimize.nnls).  Returns
    (T_j, w_j, max relative deviation of sigma_A from the floor in the band).
    """

    lo = math.log10(tau_min) - 0.6  # a little beyond the band so its edges stay flat
    hi = math.log10(tau_max) + 0.3
    n = max(2, math.ceil((hi - lo) * per_decade) + 1)
    t_c = np.logspace(lo, hi, n)
    taus = np.logspace(math.log10(tau_min), math.log10(tau_max), 80)
    target = BIAS_INSTABILITY_FLOOR**2
    a = np.stack([allan_variance_gauss_markov(taus, 1.0, tc) for tc in t_c], axis=1) / target
    w, _ = nnls(a, np.ones(taus.size))
    dev = float(np.max(np.abs(np.sqrt(a @ w) - 1.0)))
    keep = w > 0
    return t_c[keep], w[keep], dev


@dataclass(frozen=True, eq=False)
class Flicker:
    """Bias instability with a flat Allan floor (1/f noise), IEEE-952 coefficient B.

    The flicker process is generated as a sum of independent first-order
    Gauss-Markov processes whose correlation times are log-spaced
    (``per_decade`` per decade) around the band [tau_min, tau_max] and whose
    variances are fitted (non-negative least squares) so that the closed-form
    Allan deviation of the sum is flat at sigma_min = 0.6643 B over that band,
    i.e. B = sigma_min / 0.6643 (IEEE Std 952-1997, C.3).
    A sum of GM processes with log-spaced T and equal weights has a 1/f power
    spectrum between 1/(2 pi T_max) and 1/(2 pi T_min) (Keshner 1982).  Below
    tau_min the Allan deviation falls like a random walk's inverse (+1/2 slope
    on the short side is hidden by white noise in practice); above tau_max it
    decays as the slowest GM.  ``floor_ripple`` gives the largest relative
    deviation of the fitted sigma_A from 0.6643 B inside the band.

    Parameters
    ----------
    b : float or (3,)
        Bias-instability coefficient B (rad/s or m/s^2), >= 0.
    tau_min, tau_max : float
        Averaging-time band (s) over which the floor is flat.
    per_decade : int
        GM components per decade of correlation time (2 gives < 0.2 % ripple).
    """

    b: Any
    tau_min: float = 1.0
    tau_max: float = 1000.0
    per_decade: int = 2

    def __post_init__(self) -> None:
        object.__setattr__(self, "b", _vec3(self.b, "Flicker.b (bias instability B)", nonneg=True))
        for name in ("tau_min", "tau_max"):
            v = getattr(self, name)
            if not (isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v) and v > 0):
                raise InvalidInputError(f"Flicker.{name}: expected a finite time > 0 s, got {v!r}")
            object.__setattr__(self, name, float(v))
        if self.tau_max <= self.tau_min:
            raise InvalidInputError(
                f"Flicker: tau_max ({self.tau_max}) must be larger than tau_min ({self.tau_min})"
            )
        if self.tau_max / self.tau_min > 1e8:
            raise InvalidInputError("Flicker: the band tau_max / tau_min is limited to 1e8 (8 decades)")
        if not (isinstance(self.per_decade, numbers.Integral) and 1 <= self.per_decade <= 10):
            raise InvalidInputError(f"Flicker.per_decade: expected an integer in 1..10, got {self.per_decade!r}")
        object.__setattr__(self, "per_decade", int(self.per_decade))

    @property
    def floor_ripple(self) -> float:
        """Largest relative deviation of the model's sigma_A from 0.6643 B in the band."""
        return _flicker_weights(self.tau_min, self.tau_max, self.per_decade)[2]

    def components(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(sigmas, taus), each (n_components, 3).

        Returns
        -------
        sigmas : numpy.ndarray, shape (M, 3)
            Standard deviation of each Gauss-Markov component per axis, ``sqrt(w_j) B``.
        taus : numpy.ndarray, shape (M, 3)
            Correlation time of each component, s (the same on the three axes).
        """
        t_c, w, _ = _flicker_weights(self.tau_min, self.tau_max, self.per_decade)
        sig = np.sqrt(w)[:, None] * self.b[None, :]
        return sig, np.repeat(t_c[:, None], 3, axis=1)

    def allan_variance(self, tau: ArrayLike) -> NDArray[np.float64]:
        """Closed-form Allan variance of the generated GM sum, shape (3, len(tau)).

        Parameters
        ----------
        tau : array_like
            Averaging times, s.

        Returns
        -------
        numpy.ndarray, shape (3, len(tau))
            Sum over the components of :func:`allan_variance_gauss_markov`, per axis.
        """
        sig, tc = self.components()
        tau = np.atleast_1d(np.asarray(tau, dtype=float))
        out = np.zeros((3, tau.size))
        for j in range(sig.shape[0]):
            for i in range(3):
                out[i] += allan_variance_gauss_markov(tau, sig[j, i], tc[j, i])
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON / TOML form (the ``bias_instability`` table of a model file).

        Returns
        -------
        dict
            ``model = "flicker"``, ``b`` (list of 3), ``tau_min``, ``tau_max``, ``per_decade``.
        """
        return {
            "model": "flicker",
            "b": self.b.tolist(),
            "tau_min": self.tau_min,
            "tau_max": self.tau_max,
            "per_decade": self.per_decade,
        }

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Flicker) and _deep_equal(self.to_dict(), other.to_dict())

    __hash__ = None  # type: ignore[assignment]


def _deep_equal(a: Any, b: Any) -> bool:
    if isinstance(a, Mapping) and isinstance(b, Mapping):
        return a.keys() == b.keys() and all(_deep_equal(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple, np.ndarray)) or isinstance(b, (list, tuple, np.ndarray)):
        try:
            return bool(np.array_equal(np.asarray(a, dtype=float), np.asarray(b, dtype=float)))
        except (TypeError, ValueError):
            return False
    return a == b


# --------------------------------------------------------------------------
# triad and IMU models
# --------------------------------------------------------------------------
_TRIAD_SI = {
    "gyro": {
        "bias": "rad/s",
        "scale_misalignment": "1",
        "bias_temp_poly": "rad/s/degC^k",
        "scale_temp_poly": "1/degC^k",
        "noise_density": "rad/s/sqrt(Hz)",
        "bias_instability": "rad/s",
        "random_walk": "rad/s/sqrt(s)",
        "rate_ramp": "rad/s^2",
        "quantization": "rad/s",
        "full_scale": "rad/s",
    },
    "accel": {
        "bias": "m/s^2",
        "scale_misalignment": "1",
        "bias_temp_poly": "m/s^2/degC^k",
        "scale_temp_poly": "1/degC^k",
        "noise_density": "m/s^2/sqrt(Hz)",
        "bias_instability": "m/s^2",
        "random_walk": "m/s^2/sqrt(s)",
        "rate_ramp": "m/s^3",
        "quantization": "m/s^2",
        "full_scale": "m/s^2",
    },
}
_TRIAD_QUANTITY = {"gyro": "angular_rate", "accel": "acceleration"}
_G_SENS_SI = "rad/s/(m/s^2)"


@dataclass(frozen=True, eq=False)
class TriadErrors:
    """Error model of one sensor triad (three gyros or three accelerometers), SI.

    Parameters
    ----------
    bias : (3,)
        Constant (turn-on) bias b at temp_ref_c: rad/s or m/s^2.
    scale_misalignment : (3, 3)
        T = I + diag(S) + M; measured = T true + ... (see
        :func:`scale_misalignment_matrix`).
    bias_temp_poly : (K, 3)
        Row k-1: coefficients of (temp - temp_ref_c)^k added to the bias
        (unit/degC^k), k = 1..K.
    scale_temp_poly : (K, 3)
        Row k-1: coefficients of (temp - temp_ref_c)^k added to the scale
        factors (diagonal of T), 1/degC^k.
    noise_density : (3,)
        White-noise density N (ARW rad/s/sqrt(Hz) = rad/sqrt(s), VRW
        m/s^2/sqrt(Hz) = m/s/sqrt(s)); per-sample sigma = N sqrt(f_s).
    bias_instability : GaussMarkov, Flicker or None
        Bias-instability process (None: none).
    random_walk : (3,)
        Rate / acceleration random walk K (unit/s/sqrt(s) = unit/sqrt(s)...),
        Allan variance K^2 tau / 3.
    rate_ramp : (3,)
        Rate ramp R (unit/s): R (t - t_0) added to the output.
    quantization : (3,)
        LSB q of the output (0: none).
    full_scale : (3,) or None
        Output saturates at +-full_scale (None: no saturation).
    quantization_mode : "rate" or "integrated"
        "rate": each sample rounded to the LSB; "integrated": the residue
        is carried (delta-angle / delta-velocity style output), giving the
        IEEE-952 quantization noise Q = q dt / sqrt(12).
    """

    bias: Any = 0.0
    scale_misalignment: Any = field(default_factory=lambda: np.eye(3))
    bias_temp_poly: Any = None
    scale_temp_poly: Any = None
    noise_density: Any = 0.0
    bias_instability: GaussMarkov | Flicker | None = None
    random_walk: Any = 0.0
    rate_ramp: Any = 0.0
    quantization: Any = 0.0
    full_scale: Any = None
    quantization_mode: Literal["rate", "integrated"] = "rate"

    def __post_init__(self) -> None:
        s = object.__setattr__
        s(self, "bias", _vec3(self.bias, "TriadErrors.bias"))
        s(self, "scale_misalignment", _mat3(self.scale_misalignment, "TriadErrors.scale_misalignment (I + diag(S) + M)"))
        s(self, "bias_temp_poly", _poly(self.bias_temp_poly, "TriadErrors.bias_temp_poly"))
        s(self, "scale_temp_poly", _poly(self.scale_temp_poly, "TriadErrors.scale_temp_poly"))
        s(self, "noise_density", _vec3(self.noise_density, "TriadErrors.noise_density", nonneg=True))
        if self.bias_instability is not None and not isinstance(self.bias_instability, (GaussMarkov, Flicker)):
            raise InvalidInputError(
                "TriadErrors.bias_instability: expected GaussMarkov(sigma, tau), Flicker(b) or None, "
                f"got {type(self.bias_instability).__name__}"
            )
        s(self, "random_walk", _vec3(self.random_walk, "TriadErrors.random_walk", nonneg=True))
        s(self, "rate_ramp", _vec3(self.rate_ramp, "TriadErrors.rate_ramp"))
        s(self, "quantization", _vec3(self.quantization, "TriadErrors.quantization (LSB)", nonneg=True))
        if self.full_scale is not None:
            s(self, "full_scale", _vec3(self.full_scale, "TriadErrors.full_scale", positive=True))
        if self.quantization_mode not in ("rate", "integrated"):
            raise InvalidInputError(
                f"TriadErrors.quantization_mode: expected 'rate' or 'integrated', got {self.quantization_mode!r}"
            )

    # --- derived -----------------------------------------------------------
    @property
    def scale_factor(self) -> NDArray[np.float64]:
        """S = diag(T) - 1."""
        return np.diag(self.scale_misalignment) - 1.0

    @property
    def misalignment(self) -> NDArray[np.float64]:
        """M = T - diag(diag(T)) (zero diagonal)."""
        t = np.array(self.scale_misalignment)
        np.fill_diagonal(t, 0.0)
        return t

    @property
    def has_noise(self) -> bool:
        """True when any stochastic term is on."""
        return bool(
            np.any(self.noise_density > 0)
            or np.any(self.random_walk > 0)
            or (self.bias_instability is not None and np.any(self.bias_instability.components()[0] > 0))
        )

    def replace(self, **changes: Any) -> TriadErrors:
        """Copy with some fields changed (validated again).

        Parameters
        ----------
        **changes
            New values of fields.

        Returns
        -------
        TriadErrors
            The copy.
        """
        return replace(self, **changes)

    def deterministic(self) -> TriadErrors:
        """Copy with only bias, T and the temperature polynomials (no noise, ramp, LSB, saturation).

        Returns
        -------
        TriadErrors
            The deterministic part.
        """
        return TriadErrors(
            bias=self.bias,
            scale_misalignment=self.scale_misalignment,
            bias_temp_poly=self.bias_temp_poly,
            scale_temp_poly=self.scale_temp_poly,
        )

    def allan_variance(self, tau: ArrayLike, dt: float | None = None) -> NDArray[np.float64]:
        """Theoretical Allan variance of the stochastic part at constant input, (3, len(tau)).

        Sum of N^2/tau, the bias-instability closed form, K^2 tau/3 and
        R^2 tau^2/2; quantization adds 3 Q^2/tau^2 with Q = q dt/sqrt(12) in
        "integrated" mode, or the white term (q^2/12) dt / tau in "rate" mode
        (valid when the signal moves by more than an LSB between samples).
        ``dt`` (sample interval, s) is needed when quantization is on.

        Parameters
        ----------
        tau : array_like
            Averaging times, s.
        dt : float, optional
            Sample interval, s (required when quantization is on).

        Returns
        -------
        numpy.ndarray, shape (3, len(tau))
            sigma_A^2 per axis, unit².

        Raises
        ------
        InvalidInputError
            If quantization is on and ``dt`` is not given.
        """
        tau = np.atleast_1d(np.asarray(tau, dtype=float))
        out = np.zeros((3, tau.size))
        for i in range(3):
            out[i] = allan_variance_ieee952(
                tau, N=self.noise_density[i], K=self.random_walk[i], R=self.rate_ramp[i]
            )
        if self.bias_instability is not None:
            out += self.bias_instability.allan_variance(tau)
        if np.any(self.quantization > 0):
            if dt is None:
                raise InvalidInputError("TriadErrors.allan_variance: pass dt (s) when quantization is on")
            for i in range(3):
                q = self.quantization[i]
                if self.quantization_mode == "integrated":
                    out[i] += allan_variance_ieee952(tau, Q=q * dt / math.sqrt(12.0))
                else:
                    out[i] += q**2 / 12.0 * dt / tau
        return out

    # --- serialisation ------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """JSON / TOML friendly dict of SI values (units: :meth:`si_units`).

        Returns
        -------
        dict
            One key per field (lists), ``bias_instability`` and ``full_scale`` only when set.
        """
        d: dict[str, Any] = {
            "bias": self.bias.tolist(),
            "scale_misalignment": self.scale_misalignment.tolist(),
            "bias_temp_poly": self.bias_temp_poly.tolist(),
            "scale_temp_poly": self.scale_temp_poly.tolist(),
            "noise_density": self.noise_density.tolist(),
            "random_walk": self.random_walk.tolist(),
            "rate_ramp": self.rate_ramp.tolist(),
            "quantization": self.quantization.tolist(),
            "quantization_mode": self.quantization_mode,
        }
        if self.bias_instability is not None:
            d["bias_instability"] = self.bias_instability.to_dict()
        if self.full_scale is not None:
            d["full_scale"] = self.full_scale.tolist()
        return d

    @staticmethod
    def si_units(kind: Literal["gyro", "accel"]) -> dict[str, str]:
        """SI unit of every field for a gyro or accelerometer triad.

        Parameters
        ----------
        kind : {"gyro", "accel"}
            The triad.

        Returns
        -------
        dict
            Field name -> SI unit string.
        """
        return dict(_TRIAD_SI[kind])

    @classmethod
    def from_dict(
        cls, d: Mapping[str, Any], kind: Literal["gyro", "accel"], units: Mapping[str, str] | None = None
    ) -> TriadErrors:
        """Build from a dict; values in SI unless ``units`` (field -> unit) or an
        inline ``{"value": ..., "unit": ...}`` says otherwise.

        Accepted display units are those of :data:`imunav.units.DISPLAY_UNITS`
        (``"deg/sqrt(h)"``, ``"deg/h"``, ``"ug"``, ``"ppm"``, ``"mrad"``, ...)
        and the quantity units of :func:`imunav.units.to_si` (``"deg/s"``,
        ``"g"``, ``"mg"``).  Instead of ``scale_misalignment`` one may give
        ``scale_factor`` (3,) and ``misalignment`` (6,) or (3, 3).

        Parameters
        ----------
        d : Mapping
            Field name -> value (or ``{"value", "unit"}`` table); missing fields mean "no error".
        kind : {"gyro", "accel"}
            The triad (SI units and quantity of the conversion).
        units : Mapping, optional
            Field name -> unit of the values in ``d``.

        Returns
        -------
        TriadErrors
            The model in SI units.

        Raises
        ------
        InvalidInputError
            If ``kind`` is unknown.
        ConfigError
            If ``d`` is not a table, has unknown keys or gives both ``scale_misalignment`` and
            ``scale_factor`` / ``misalignment``, or ``units`` names an unknown field.
        """
        if kind not in _TRIAD_SI:
            raise InvalidInputError(f"TriadErrors.from_dict: kind must be 'gyro' or 'accel', got {kind!r}")
        if not isinstance(d, Mapping):
            raise ConfigError(f"[{kind}]: expected a table of error parameters, got {type(d).__name__}")
        units = dict(units or {})
        allowed = set(_TRIAD_SI[kind]) | {"scale_factor", "misalignment", "quantization_mode"}
        unknown = set(d) - allowed
        if unknown:
            raise ConfigError(f"[{kind}]: unknown key(s) {sorted(unknown)}; allowed: {sorted(allowed)}")
        bad_units = set(units) - allowed
        if bad_units:
            raise ConfigError(f"[units.{kind}]: unknown key(s) {sorted(bad_units)}; allowed: {sorted(allowed)}")
        q = _TRIAD_QUANTITY[kind]

        def conv(key: str, si: str, quantity: str | None = q) -> Any:
            return _convert(d[key], units.get(key), si, quantity, f"{kind}.{key}")

        kw: dict[str, Any] = {}
        for key in ("bias", "bias_temp_poly", "noise_density", "random_walk", "rate_ramp", "quantization", "full_scale"):
            if key in d:
                kw[key] = conv(key, _TRIAD_SI[kind][key])
        if "scale_temp_poly" in d:
            kw["scale_temp_poly"] = conv("scale_temp_poly", _TRIAD_SI[kind]["scale_temp_poly"], None)
        if "quantization_mode" in d:
            kw["quantization_mode"] = d["quantization_mode"]
        if "scale_misalignment" in d:
            if "scale_factor" in d or "misalignment" in d:
                raise ConfigError(
                    f"[{kind}]: give either scale_misalignment or scale_factor/misalignment, not both"
                )
            kw["scale_misalignment"] = conv("scale_misalignment", "1", None)
        elif "scale_factor" in d or "misalignment" in d:
            sf = conv("scale_factor", "1", None) if "scale_factor" in d else 0.0
            mis = conv("misalignment", "rad", "angle") if "misalignment" in d else 0.0
            kw["scale_misalignment"] = scale_misalignment_matrix(sf, mis)
        if "bias_instability" in d:
            kw["bias_instability"] = _bias_instability_from_dict(
                d["bias_instability"], units.get("bias_instability"), _TRIAD_SI[kind]["bias_instability"], q, kind
            )
        return cls(**kw)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, TriadErrors) and _deep_equal(self.to_dict(), other.to_dict())

    __hash__ = None  # type: ignore[assignment]


def _unwrap(value: Any, unit: str | None, where: str) -> tuple[Any, str | None]:
    if isinstance(value, Mapping):
        if set(value) != {"value", "unit"}:
            raise ConfigError(f"{where}: an inline value must be {{value = ..., unit = \"...\"}}, got keys {sorted(value)}")
        return value["value"], value["unit"]
    return value, unit


def _convert(value: Any, unit: str | None, si_unit: str, quantity: str | None, where: str) -> Any:
    value, unit = _unwrap(value, unit, where)
    if value is None:
        return None
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as e:
        raise ConfigError(f"{where}: expected numbers, got {value!r}") from e
    if unit is None or _units.normalize_unit(unit) == _units.normalize_unit(si_unit):
        return arr
    try:
        return np.asarray(_units.from_display(arr, unit), dtype=float)
    except UnitError:
        pass
    if quantity is not None:
        try:
            return _units.to_si(arr, unit, quantity)
        except UnitError:
            pass
    raise UnitError(
        f"{where}: unknown unit {unit!r} (SI unit is {si_unit}); use an IEEE-952 display unit "
        f"({', '.join(sorted(_units.DISPLAY_UNITS))}) or a {quantity or 'ratio'} unit"
    )


def _bias_instability_from_dict(
    d: Any, unit: str | None, si_unit: str, quantity: str, kind: str
) -> GaussMarkov | Flicker | None:
    where = f"{kind}.bias_instability"
    if d is None:
        return None
    if not isinstance(d, Mapping):
        raise ConfigError(f"{where}: expected a table with model = 'gauss_markov' or 'flicker', got {d!r}")
    model = d.get("model", "gauss_markov")
    if model in ("gauss_markov", "gm"):
        extra = set(d) - {"model", "sigma", "tau"}
        if extra or "sigma" not in d or "tau" not in d:
            raise ConfigError(f"{where}: gauss_markov needs exactly 'sigma' and 'tau', got keys {sorted(d)}")
        return GaussMarkov(
            sigma=_convert(d["sigma"], unit, si_unit, quantity, where + ".sigma"),
            tau=_convert(d["tau"], None, "s", "time", where + ".tau"),
        )
    if model == "flicker":
        extra = set(d) - {"model", "b", "tau_min", "tau_max", "per_decade"}
        if extra or "b" not in d:
            raise ConfigError(
                f"{where}: flicker needs 'b' and optionally tau_min, tau_max, per_decade; got keys {sorted(d)}"
            )
        kw: dict[str, Any] = {"b": _convert(d["b"], unit, si_unit, quantity, where + ".b")}
        for key in ("tau_min", "tau_max"):
            if key in d:
                kw[key] = float(_convert(d[key], None, "s", "time", f"{where}.{key}"))
        if "per_decade" in d:
            kw["per_decade"] = d["per_decade"]
        return Flicker(**kw)
    raise ConfigError(f"{where}: unknown model {model!r}; use 'gauss_markov' or 'flicker'")


@dataclass(frozen=True, eq=False)
class ImuErrorModel:
    """Error model of a 6-axis IMU.

    Parameters
    ----------
    gyro, accel : TriadErrors
        Error models of the gyro and accelerometer triads.
    g_sensitivity : (3, 3) or (3,)
        Gyro g-sensitivity G (rad/s per m/s^2): w~ += G f (f = true specific
        force).  Three values give the diagonal (the thesis's B_G).
    temp_ref_c : float
        Reference temperature of the polynomials (degC).
    name, source : str
        Preset name and the published source of the figures.
    """

    gyro: TriadErrors = field(default_factory=TriadErrors)
    accel: TriadErrors = field(default_factory=TriadErrors)
    g_sensitivity: Any = field(default_factory=lambda: np.zeros((3, 3)))
    temp_ref_c: float = 25.0
    name: str = ""
    source: str = ""

    def __post_init__(self) -> None:
        for nm in ("gyro", "accel"):
            if not isinstance(getattr(self, nm), TriadErrors):
                raise InvalidInputError(
                    f"ImuErrorModel.{nm}: expected TriadErrors, got {type(getattr(self, nm)).__name__}"
                )
        g = np.asarray(self.g_sensitivity, dtype=float)
        if g.shape == (3,) or g.ndim == 0:
            g = np.diag(np.broadcast_to(g, (3,)))
        object.__setattr__(self, "g_sensitivity", _mat3(g, "ImuErrorModel.g_sensitivity (rad/s per m/s^2)"))
        t = self.temp_ref_c
        if not (isinstance(t, numbers.Real) and not isinstance(t, bool) and math.isfinite(t)):
            raise InvalidInputError(f"ImuErrorModel.temp_ref_c: expected a finite temperature in degC, got {t!r}")
        object.__setattr__(self, "temp_ref_c", float(t))

    def deterministic(self) -> ImuErrorModel:
        """Copy without stochastic terms, ramp, quantization and saturation.

        Returns
        -------
        ImuErrorModel
            Both triads :meth:`TriadErrors.deterministic`, same G and reference temperature.
        """
        return replace(self, gyro=self.gyro.deterministic(), accel=self.accel.deterministic())

    def replace(self, **changes: Any) -> ImuErrorModel:
        """Copy with some fields changed (``dataclasses.replace``).

        Parameters
        ----------
        **changes
            New values of fields.

        Returns
        -------
        ImuErrorModel
            The copy (validated again).
        """
        return replace(self, **changes)

    # --- serialisation ------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """SI values plus a ``units`` block naming the unit of every field.

        Returns
        -------
        dict
            ``name``, ``source``, ``temp_ref_c``, ``g_sensitivity``, ``gyro``, ``accel`` and ``units``.
        """
        return {
            "name": self.name,
            "source": self.source,
            "temp_ref_c": self.temp_ref_c,
            "g_sensitivity": self.g_sensitivity.tolist(),
            "gyro": self.gyro.to_dict(),
            "accel": self.accel.to_dict(),
            "units": {
                "g_sensitivity": _G_SENS_SI,
                "gyro": TriadErrors.si_units("gyro"),
                "accel": TriadErrors.si_units("accel"),
            },
        }

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> ImuErrorModel:
        """Inverse of :meth:`to_dict`; also accepts display units (see
        :meth:`TriadErrors.from_dict`), e.g. ``units = {gyro = {noise_density =
        "deg/sqrt(h)", bias_instability = "deg/h"}, accel = {bias = "mg"}}``.
        Missing triads / fields mean "no error".

        Parameters
        ----------
        d : Mapping
            The model's tables.

        Returns
        -------
        ImuErrorModel
            The model in SI units.

        Raises
        ------
        ConfigError
            If ``d`` is not a table, has unknown keys, or ``units`` is malformed.
        """
        if not isinstance(d, Mapping):
            raise ConfigError(f"error model: expected a table, got {type(d).__name__}")
        allowed = {"name", "source", "temp_ref_c", "g_sensitivity", "gyro", "accel", "units"}
        unknown = set(d) - allowed
        if unknown:
            raise ConfigError(f"error model: unknown key(s) {sorted(unknown)}; allowed: {sorted(allowed)}")
        units = d.get("units", {}) or {}
        if not isinstance(units, Mapping) or set(units) - {"gyro", "accel", "g_sensitivity"}:
            raise ConfigError("[units]: expected sub-tables 'gyro', 'accel' and/or a 'g_sensitivity' unit string")
        kw: dict[str, Any] = {}
        for kind in ("gyro", "accel"):
            if kind in d:
                kw[kind] = TriadErrors.from_dict(d[kind], kind, units.get(kind))  # type: ignore[arg-type]
        if "g_sensitivity" in d:
            kw["g_sensitivity"] = _convert(d["g_sensitivity"], units.get("g_sensitivity"), _G_SENS_SI, None, "g_sensitivity")
        if "temp_ref_c" in d:
            kw["temp_ref_c"] = d["temp_ref_c"]
        for key in ("name", "source"):
            if key in d:
                kw[key] = str(d[key])
        return cls(**kw)

    @classmethod
    def from_toml(cls, path: str | os.PathLike[str]) -> ImuErrorModel:
        """Read a TOML error model (layout of :meth:`to_dict`).

        Parameters
        ----------
        path : str or os.PathLike
            The TOML file.

        Returns
        -------
        ImuErrorModel
            The model (:meth:`from_dict`).

        Raises
        ------
        FileFormatError
            If the file does not exist.
        ConfigError
            If it is not valid TOML or its tables are invalid (the message names the file).

        Warns
        -----
        ImunavWarning
            When the model sets no error term (an ideal IMU), so that an empty file is not taken for a model.
        """
        p = Path(path)
        d = read_toml(p, "error-model", missing=FileFormatError)
        try:
            model = cls.from_dict(d)
        except InvalidInputError as e:
            raise type(e)(f"{p}: {e}") from e
        if model == cls(temp_ref_c=model.temp_ref_c, name=model.name, source=model.source):
            warnings.warn(f"{p}: the error model sets no error term ([gyro] / [accel] tables are empty or absent): "
                          "the simulated IMU is ideal", ImunavWarning, stacklevel=2)
        return model

    def to_toml(self, path: str | os.PathLike[str]) -> Path:
        """Write the model as TOML (atomically: temp file, then rename).

        Parameters
        ----------
        path : str or os.PathLike
            Destination file (overwritten).

        Returns
        -------
        pathlib.Path
            ``path``.
        """
        p = Path(path)
        text = toml_text(self.to_dict())
        with atomic_path(p) as tmp:
            tmp.write_text(text, encoding="utf-8")
        return p

    def __eq__(self, other: object) -> bool:
        return isinstance(other, ImuErrorModel) and _deep_equal(self.to_dict(), other.to_dict())

    __hash__ = None  # type: ignore[assignment]


# --------------------------------------------------------------------------
# truth
# --------------------------------------------------------------------------
@dataclass(frozen=True)
class TriadTruth(Result):
    """Realised error terms of one triad, each (N, 3), SI.

    ``bias`` is the total additive bias b + b(dT) + bias_instability +
    random_walk + rate_ramp (everything but white noise, quantization and
    saturation); ``output - (T(dT) x + G f + bias + white_noise)`` is the
    quantization / saturation error.

    Attributes
    ----------
    bias : numpy.ndarray, shape (N, 3)
        Total additive bias.
    bias_instability : numpy.ndarray, shape (N, 3)
        Realised bias-instability process.
    random_walk : numpy.ndarray, shape (N, 3)
        Realised random walk.
    rate_ramp : numpy.ndarray, shape (N, 3)
        Realised ramp ``R (t - t_0)``.
    white_noise : numpy.ndarray, shape (N, 3)
        Realised white noise.
    n_saturated : numpy.ndarray of int64, shape (3,)
        Saturated samples per axis.
    """

    bias: NDArray[np.float64]
    bias_instability: NDArray[np.float64]
    random_walk: NDArray[np.float64]
    rate_ramp: NDArray[np.float64]
    white_noise: NDArray[np.float64]
    n_saturated: NDArray[np.int64]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form.

        Returns
        -------
        dict
            One nested list per field.
        """
        return {f.name: np.asarray(getattr(self, f.name)).tolist() for f in fields(self)}


@dataclass(frozen=True)
class ImuErrorTruth(Result):
    """Realised error terms of a simulated recording (``return_truth=True``).

    Attributes
    ----------
    gyro : TriadTruth
        Realised errors of the gyro triad, rad/s.
    accel : TriadTruth
        Realised errors of the accelerometer triad, m/s².
    model : ImuErrorModel
        The model they were drawn from.
    """

    gyro: TriadTruth
    accel: TriadTruth
    model: ImuErrorModel

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form.

        Returns
        -------
        dict
            ``gyro``, ``accel`` (:meth:`TriadTruth.to_dict`) and ``model`` (:meth:`ImuErrorModel.to_dict`).
        """
        return {"gyro": self.gyro.to_dict(), "accel": self.accel.to_dict(), "model": self.model.to_dict()}


# --------------------------------------------------------------------------
# simulation
# --------------------------------------------------------------------------
_PARALLEL_MIN_SAMPLES = 200_000


def _time_steps(t: NDArray[np.float64]) -> NDArray[np.float64]:
    n = t.size
    dt = np.empty(n)
    if n > 1:
        dt[1:] = np.diff(t)
        dt[0] = dt[1]
    else:
        dt[0] = 1.0
    return dt


def _readonly(a: Any) -> NDArray[np.float64]:
    """C-contiguous float64 read-only view (ImuData arrays are read-only; one
    numba signature whichever array the caller passes)."""
    v = np.ascontiguousarray(a, dtype=float).view()
    v.setflags(write=False)
    return v


def _as_n3(a: Any, n: int, where: str) -> NDArray[np.float64]:
    a = _readonly(a)
    if a.shape != (n, 3):
        raise ShapeError(f"{where}: expected shape ({n}, 3), got {a.shape}")
    return a


def _uniform_step(t: NDArray[np.float64], d: NDArray[np.float64]) -> float:
    """The sampling step when t is uniform to 1e-6 relative, else 0 (per-sample steps).

    1e-6 tolerates the rounding of t = k / f_s at large t (relative jitter of
    the differences ~ eps t / dt) and changes the noise scaling by < 1 ppm.
    """
    if t.size < 2:
        return 1.0
    step = (t[-1] - t[0]) / (t.size - 1)
    return float(step) if float(np.max(np.abs(d - step))) <= 1e-6 * step else 0.0


def _f64(a: Any) -> NDArray[np.float64]:
    """Writable C-contiguous float64 copy (one numba signature for every call)."""
    return np.array(a, dtype=np.float64, order="C", copy=True)


def _states(
    root: np.random.SeedSequence, sensor: int, te: TriadErrors, common: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stream states (3, 2 + M, 4) and GM parameters (3, M) of one triad
    (``common``: the three axes share the x-axis streams)."""
    if te.bias_instability is not None:
        sig, tc = te.bias_instability.components()
    else:
        sig, tc = np.zeros((1, 3)), np.ones((1, 3))
    m = sig.shape[0]
    procs = [(_PROC_WHITE, 0), (_PROC_RANDOM_WALK, 0)] + [(_PROC_BIAS_INSTABILITY, j) for j in range(m)]
    axes = [0, 0, 0] if common else [0, 1, 2]
    states = np.stack([np.stack([stream_state(root, sensor, p, i, j) for p, j in procs]) for i in axes])
    return states, _f64(sig.T), _f64(tc.T)


def _apply_arrays(
    t: NDArray[np.float64],
    gyro: NDArray[np.float64],
    accel: NDArray[np.float64],
    model: ImuErrorModel,
    rng: Any,
    dtemp: NDArray[np.float64] | None,
    return_truth: bool,
    threads: int | None = None,
    common_axis_noise: bool = False,
) -> tuple[NDArray[np.float64], NDArray[np.float64], ImuErrorTruth | None]:
    n = t.size
    root = seed_sequence(rng)
    d = np.diff(t)
    if n > 1 and not np.all(d > 0):
        i = int(np.argmax(~(d > 0))) + 1
        raise InvalidInputError(f"apply_errors: time must be strictly increasing (row {i})")
    triads = (("gyro", model.gyro, gyro), ("accel", model.accel, accel))
    if n < 2 and any(te.has_noise for _, te, _ in triads):
        raise InsufficientDataError("apply_errors: stochastic errors need at least 2 samples (to know the rate)")
    dt_const = _uniform_step(t, d)
    del d
    dtemp_arr = np.zeros(0) if dtemp is None else _f64(dtemp)
    outs: dict[str, np.ndarray] = {}
    nsat: dict[str, np.ndarray] = {}
    truth_arr: dict[str, np.ndarray] = {}

    def run(nm: str, te: TriadErrors, x: np.ndarray) -> None:
        out = np.empty((n, 3))
        tr = np.zeros((4, n, 3)) if return_truth else np.zeros((4, 0, 3))
        is_gyro = nm == "gyro"
        g = model.g_sensitivity if is_gyro else np.zeros((3, 3))
        states, sig, tc = _states(root, _SENSOR_KEY[nm], te, common_axis_noise)
        fs = te.full_scale if te.full_scale is not None else np.zeros(3)
        prm = _k.TriadParams(
            use_g=bool(is_gyro and np.any(g != 0)), t_mat=_f64(te.scale_misalignment), g_mat=_f64(g),
            bias=_f64(te.bias), bias_poly=_f64(te.bias_temp_poly), scale_poly=_f64(te.scale_temp_poly),
            nd=_f64(te.noise_density), gm_sig=sig, gm_tau=tc, k_rw=_f64(te.random_walk), ramp=_f64(te.rate_ramp),
            q=_f64(te.quantization), integrated=te.quantization_mode == "integrated", full_scale=_f64(fs))
        nsat[nm] = _k.simulate_triad(t, dt_const, x, accel, dtemp_arr, prm, states, out, tr, return_truth)
        outs[nm] = out
        truth_arr[nm] = tr

    nthreads = threads if threads is not None else (os.cpu_count() or 1)
    if nthreads > 1 and n >= _PARALLEL_MIN_SAMPLES:
        with ThreadPoolExecutor(max_workers=2) as ex:
            for fut in [ex.submit(run, nm, te, x) for nm, te, x in triads]:
                fut.result()
    else:
        for nm, te, x in triads:
            run(nm, te, x)

    truth = None
    if return_truth:
        tt = {}
        for nm, te, _ in triads:
            bi, rw, ramp, wh = truth_arr[nm]
            const = np.broadcast_to(te.bias, (n, 3)).copy()
            if dtemp is not None and te.bias_temp_poly.shape[0] > 0:
                p = np.ones(n)
                for row in te.bias_temp_poly:
                    p = p * dtemp
                    const += p[:, None] * row[None, :]
            tt[nm] = TriadTruth(
                bias=const + bi + rw + ramp,
                bias_instability=bi,
                random_walk=rw,
                rate_ramp=ramp,
                white_noise=wh,
                n_saturated=nsat[nm],
            )
        truth = ImuErrorTruth(gyro=tt["gyro"], accel=tt["accel"], model=model)
    return outs["gyro"], outs["accel"], truth


def _temperature(temp_c: Any, ideal: Any, n: int) -> NDArray[np.float64] | None:
    if temp_c is None:
        temp = getattr(ideal, "temp", None)
        if temp is None:
            return None
        temp_c = temp
    tc = np.asarray(temp_c, dtype=float)
    if tc.ndim == 0:
        tc = np.full(n, float(tc))
    elif tc.shape == (n, 1):
        tc = tc[:, 0]
    if tc.shape != (n,):
        raise ShapeError(f"temp_c: expected a scalar or {n} values (one per sample), got shape {tc.shape}")
    if not np.all(np.isfinite(tc)):
        bad = np.flatnonzero(~np.isfinite(tc))[:5].tolist()
        raise NonFiniteError(f"temp_c: non-finite temperatures at rows {bad}")
    return tc


def apply_errors(
    ideal: ImuData,
    model: ImuErrorModel,
    rng: Any = None,
    temp_c: ArrayLike | None = None,
    *,
    return_truth: bool = False,
    threads: int | None = None,
    common_axis_noise: bool = False,
) -> ImuData | tuple[ImuData, ImuErrorTruth]:
    """Apply an IMU error model to an ideal recording.

    Parameters
    ----------
    ideal : ImuData
        True angular rate (rad/s) and specific force (m/s^2).
    model : ImuErrorModel
        The errors to apply.
    rng : Generator, int seed, SeedSequence or None
        Seed of the per-(sensor, process, axis) streams; same seed, same output.
    temp_c : float or (N,), optional
        Sensor temperature in degC; default ``ideal.temp``, else the model's
        reference temperature (no temperature effect).  When given it is
        stored in the returned recording.
    return_truth : bool
        Also return an :class:`ImuErrorTruth` with the realised bias tracks
        and white noise.
    threads : int, optional
        Worker threads (default: CPU count; gyro and accelerometer run in
        parallel); results do not depend on it.
    common_axis_noise : bool
        Use the x-axis random streams on all three axes of a triad (same
        normalised realisation, scaled per axis).  Only for reproducing the
        thesis's simulation, whose estimation errors show this pattern
        (Günhan 2014, Tables 5.3/5.4); physically the axes are independent.

    Returns
    -------
    ImuData or tuple of (ImuData, ImuErrorTruth)
        The recording with errors (``meta["error_model"]`` names the model), and the realised errors with
        ``return_truth``.

    Raises
    ------
    InvalidInputError
        If ``model`` is not an ImuErrorModel or ``ideal`` lacks ``t``, ``gyro`` or ``accel``.
    """
    if not isinstance(model, ImuErrorModel):
        raise InvalidInputError(f"apply_errors: model must be an ImuErrorModel, got {type(model).__name__}")
    for attr in ("t", "gyro", "accel"):
        if not hasattr(ideal, attr):
            raise InvalidInputError(f"apply_errors: ideal must be an ImuData (missing .{attr})")
    t = _readonly(ideal.t)
    n = t.size
    gyro = _as_n3(ideal.gyro, n, "ideal.gyro")
    accel = _as_n3(ideal.accel, n, "ideal.accel")
    temp = _temperature(temp_c, ideal, n)
    dtemp = None if temp is None else temp - model.temp_ref_c
    g, a, truth = _apply_arrays(t, gyro, accel, model, rng, dtemp, return_truth, threads, common_axis_noise)
    meta = dict(getattr(ideal, "meta", {}) or {})
    meta["error_model"] = model.name or "custom"
    changes: dict[str, Any] = {"gyro": g, "accel": a, "meta": meta}
    if temp_c is not None:
        changes["temp"] = temp
    out = ideal.with_(**changes)
    return (out, truth) if return_truth else out


def simulate_imu(
    trajectory: Any,
    error_model: ImuErrorModel,
    rng: Any = None,
    *,
    temp_c: ArrayLike | None = None,
    return_truth: bool = False,
    common_axis_noise: bool = False,
    **ideal_kw: Any,
) -> ImuData | tuple[ImuData, ImuErrorTruth]:
    """Virtual IMU: ideal outputs of ``trajectory`` (:func:`imunav.sim.trajectory.ideal_imu`
    with ``ideal_kw``: earth_rate, transport_rate, gravity, lat, h) with the
    errors of ``error_model`` applied (:func:`apply_errors`; same ``rng``,
    ``temp_c``, ``return_truth`` and ``common_axis_noise``).

    Parameters
    ----------
    trajectory : imunav.sim.trajectory.Trajectory
        Position, velocity and attitude ``q_nb`` over time (NED).
    error_model : ImuErrorModel
        The errors to apply (e.g. :func:`imunav.sim.presets.get`).
    rng : numpy.random.Generator, int, numpy.random.SeedSequence or None
        Seed of the random streams.
    temp_c : float or array_like of shape (N,), optional
        Sensor temperature, °C.
    return_truth : bool
        Also return the realised errors.
    common_axis_noise : bool
        Same normalised noise realisation on the three axes (see :func:`apply_errors`).
    **ideal_kw
        Keyword arguments of :func:`imunav.sim.trajectory.ideal_imu` (earth_rate, transport_rate, gravity,
        lat, h).

    Returns
    -------
    ImuData or tuple of (ImuData, ImuErrorTruth)
        As :func:`apply_errors`.

    Raises
    ------
    InvalidInputError
        If ``error_model`` is not an ImuErrorModel.
    """

    if not isinstance(error_model, ImuErrorModel):
        raise InvalidInputError(
            f"simulate_imu: error_model must be an ImuErrorModel (e.g. imunav.sim.presets.get('tactical')), "
            f"got {type(error_model).__name__}"
        )
    ideal = ideal_imu(trajectory, **ideal_kw)
    return apply_errors(
        ideal, error_model, rng, temp_c, return_truth=return_truth, common_axis_noise=common_axis_noise
    )
