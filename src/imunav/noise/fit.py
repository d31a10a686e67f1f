"""Noise-term identification from an Allan-variance curve.

Model (IEEE Std 952-1997 Annex C; the Allan method as applied by E. Atasoy, *Estimation and analysis of
error parameters of attitude-heading reference system sensors* (in Turkish), MSc thesis, Başkent
University, §5.4.2-5.4.4), independent terms:

    AVAR(tau) = 3 Q^2/tau^2 + N^2/tau + (2 ln2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2
                + sum_j (2 s_j^2 T_j/tau) [1 - (T_j/2tau)(3 - 4 e^{-tau/T_j} + e^{-2tau/T_j})]

(the last sum: first-order Gauss-Markov rates with standard deviation s_j and
correlation time T_j).  The coefficients theta = (Q^2, N^2, B^2, K^2, R^2, s_j^2)
enter linearly and are found by **generalized non-negative least squares**:

    min_theta (A - G theta)^T W (A - G theta),   theta >= 0,

where A are the measured AVAR values and W^-1 is the covariance of the
AVAR estimates.  For the overlapping estimator (the default) that covariance is
computed from the current model: each estimate is a mean of squared second
differences d_i of the phase, and for Gaussian noise

    Cov(A(m1), A(m2)) = 2 / (4 tau1^2 tau2^2 n1 n2) sum_{i,j} Cov(d1_i, d2_j)^2,

with Cov(d1_i, d2_j) from the generalized autocovariance of the phase of each
term (white rate: -N^2|h|/2; random-walk rate: K^2|h|^3/12; flicker rate:
B^2 h^2 ln|h| / (2 pi); white phase: Q^2 delta(h); Gauss-Markov:
-s^2 T^2 (|h|/T - 1 + e^{-|h|/T})).  Iterating model -> covariance -> fit
(3 passes) keeps the weights independent of the noise in A (weighting by the
measured values biases the fit low).  Other estimators use the diagonal
variance 2 A^2 / edf.  Standard errors come from the GLS normal equations
(J^T W J)^-1 restricted to the selected terms, where J holds the design
columns and, for each Gauss-Markov term, the derivative of the model with
respect to log T_j (the correlation times are estimated too, so the
covariance of theta is the joint one, not the one conditional on T_j);
95 % intervals are formed on log(theta) and log(T) (delta method) and mapped
to the parameters.

Automatic term selection (``select="bic"`` default, or ``"aic"``, or
``None``): every subset of the candidate terms is fitted and the one with
the smallest information criterion chi^2 + k ln(T) (or + 2k) is kept.

The classic IEEE-952 slope read-outs are computed beside the fit
(:func:`slope_readout`): N from the -1/2 line at tau = 1 s, K from the +1/2
line at tau = 3 s, Q from the -1 line at tau = sqrt(3) s, R from the +1 line
at tau = sqrt(2) s and B = min(sigma)/0.6643.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import minimize_scalar, nnls

from imunav import allan_models as _am
from imunav.errors import ConvergenceError, InsufficientDataError, InvalidInputError
from imunav.noise import _allan_kernels as _ak
from imunav.noise.allan import AllanResult
from imunav.results import Result
from imunav.units import to_display

__all__ = [
    "BI_FACTOR",
    "NoiseFit",
    "SlopeReadout",
    "avar_model",
    "avar_term",
    "fit_noise",
    "identifiability",
    "slope_readout",
]

TERMS = _am.IEEE952_TERMS
#: sqrt(2 ln2 / pi): flat Allan deviation of flicker (bias-instability) noise per unit B
BI_FACTOR = _am.BI_FACTOR

_SI_UNITS = {
    "gyro": {"Q": "rad", "N": "rad/s/sqrt(Hz)", "B": "rad/s", "K": "rad/s^2/sqrt(Hz)", "R": "rad/s^2",
             "sigma": "rad/s", "T": "s"},
    "accel": {"Q": "m/s", "N": "m/s^2/sqrt(Hz)", "B": "m/s^2", "K": "m/s^3/sqrt(Hz)", "R": "m/s^3",
              "sigma": "m/s^2", "T": "s"},
}
_DISPLAY = {
    "gyro": {"Q": "arcsec", "N": "deg/sqrt(h)", "B": "deg/h", "K": "deg/h/sqrt(h)", "R": "deg/h^2",
             "sigma": "deg/h"},
    "accel": {"N": "m/s/sqrt(h)", "B": "ug", "K": "m/s/h/sqrt(h)", "sigma": "ug"},
}


# --------------------------------------------------------------------------- model
def avar_term(name: str, tau: ArrayLike, T: float | None = None) -> NDArray[np.float64]:
    """AVAR of one term per unit coefficient (theta = Q^2, N^2, B^2, K^2, R^2 or s^2).

    The closed forms are those of :mod:`imunav.allan_models` (shared with :mod:`imunav.sim`).

    Parameters
    ----------
    name : {"Q", "N", "B", "K", "R", "GM"}
        The term; ``"GM"`` is a first-order Gauss-Markov process.
    tau : array_like
        Cluster times, s.
    T : float, optional
        Correlation time of the ``"GM"`` term, s, > 0.

    Returns
    -------
    numpy.ndarray
        σ²(τ) per unit coefficient, same shape as ``tau``.

    Raises
    ------
    InvalidInputError
        If the term is unknown, or ``"GM"`` comes without a positive ``T``.
    """
    if name == "GM":
        if T is None or not T > 0:
            raise InvalidInputError("a Gauss-Markov term needs a positive correlation time T")
        return _am.gauss_markov_unit(tau, T)
    if name not in TERMS:
        raise InvalidInputError(f"unknown noise term {name!r}; terms are {TERMS} and 'GM'")
    return _am.ieee952_term(name, tau)


def avar_model(tau: ArrayLike, Q: float = 0.0, N: float = 0.0, B: float = 0.0, K: float = 0.0, R: float = 0.0,
               gm: Sequence[tuple[float, float]] = ()) -> NDArray[np.float64]:
    """Closed-form AVAR of the IEEE-952 terms plus Gauss-Markov terms ``gm = [(sigma, T), ...]``.

    ``3Q²/τ² + N²/τ + (2 ln2/π) B² + K²τ/3 + R²τ²/2 + Σ_j σ_j² (2T_j/τ) f(τ/T_j)`` (module docstring).

    Parameters
    ----------
    tau : array_like
        Cluster times, s.
    Q, N, B, K, R : float
        Term coefficients in SI: Q rad (m/s), N rad/s/√Hz (m/s²/√Hz), B rad/s (m/s²), K rad/s²/√Hz
        (m/s³/√Hz), R rad/s² (m/s³); gyro (accelerometer).
    gm : sequence of (float, float)
        Gauss-Markov terms as ``(sigma, T)``: standard deviation in rad/s (m/s²), correlation time in s.

    Returns
    -------
    numpy.ndarray
        The model Allan variance, (rad/s)² or (m/s²)², same shape as ``tau``.
    """
    out = _am.ieee952(tau, Q=Q, N=N, B=B, K=K, R=R)
    for s, T in gm:
        out = out + s**2 * avar_term("GM", tau, T)
    return out


_CODES = {"Q": 0, "N": 1, "B": 2, "K": 3, "GM": 4, "R": 5}


def _overlapping_cov(tau: np.ndarray, m: np.ndarray, n_phase: int, names: list[str], Ts: list[float | None],
                     theta: np.ndarray, fs: float, max_ratio: float = 64.0, max_lags: int = 4096) -> np.ndarray:
    """Covariance matrix of overlapping AVAR estimates under the model theta.

    Pairs of cluster sizes further apart than ``max_ratio`` are taken as
    uncorrelated; lag sums longer than ``max_lags`` are sampled (Riemann sum)."""
    codes = np.array([_CODES["GM" if nm.startswith("GM") else nm] for nm in names], dtype=np.int64)
    Tv = np.array([T if T is not None else 1.0 for T in Ts], dtype=float)
    return _ak.oavar_cov(np.asarray(tau, float), np.asarray(m, np.int64), int(n_phase), codes, Tv,
                         np.asarray(theta, float), 1.0 / fs, float(max_ratio), int(max_lags))


# --------------------------------------------------------------------------- results
@dataclass(frozen=True)
class SlopeReadout(Result):
    """IEEE-952 slope read-outs (per channel): values (SI) and the tau ranges used.

    Attributes
    ----------
    names : tuple of str
        The terms read, ``("Q", "N", "B", "K", "R")``.
    value : numpy.ndarray, shape (P, C)
        Read-out of each term and channel, SI units (as in :class:`NoiseFit`).
    tau_lo, tau_hi : numpy.ndarray, shape (P, C)
        Range of cluster times, s, that had the term's slope.
    found : numpy.ndarray of bool, shape (P, C)
        False when no tau range had the slope (the two nearest points were used).
    """

    names: tuple[str, ...]
    value: NDArray[np.float64]  # (P, C)
    tau_lo: NDArray[np.float64]  # (P, C)
    tau_hi: NDArray[np.float64]
    found: NDArray[np.bool_]  # (P, C) False when no tau range had the slope (nearest points used)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary of the read-outs.

        Returns
        -------
        dict
            ``names``, ``value``, ``tau_lo``, ``tau_hi``, ``found`` as lists.
        """
        return {"names": list(self.names), "value": self.value.tolist(), "tau_lo": self.tau_lo.tolist(),
                "tau_hi": self.tau_hi.tolist(), "found": self.found.tolist()}


@dataclass(frozen=True)
class NoiseFit(Result):
    """Fitted noise terms of every channel.

    Attributes
    ----------
    names : tuple of str
        ``"Q", "N", "B", "K", "R"`` and for Gauss-Markov term j ``"GMj_sigma"``, ``"GMj_T"``.
    value : numpy.ndarray, shape (P, C)
        Estimate of each term and channel, SI units (``units``).
    se : numpy.ndarray, shape (P, C)
        Standard error (NaN for a term the selection dropped).
    ci_lo, ci_hi : numpy.ndarray, shape (P, C)
        Confidence interval at ``ci_level`` (delta method on the log of the term).
    selected : numpy.ndarray of bool, shape (P, C)
        Which terms the selection kept (others are 0 with se NaN).
    units : tuple of str
        SI unit of each term (e.g. ``"rad/s/sqrt(Hz)"`` for a gyro's N).
    display_units : tuple of str
        Display unit of each term (e.g. ``"deg/sqrt(h)"``; see :mod:`imunav.units`).
    chi2 : numpy.ndarray, shape (C,)
        Weighted residual sum of squares of each channel's fit.
    n_points : int
        Number of Allan-variance points fitted.
    channels : tuple of str
        Channel names.
    quantity : str or None
        ``"gyro"``, ``"accel"`` or None (units then unknown).
    method : str
        The weighting used (e.g. generalized least squares with the overlapping covariance).
    tau : numpy.ndarray
        Cluster times fitted, s.
    slopes : SlopeReadout or None
        The classic read-outs, computed beside the fit.
    tau_min : numpy.ndarray, shape (C,)
        Cluster time of the Allan-deviation minimum of each channel, s.
    ci_level : float
        Level of the confidence intervals (0.95).
    """

    names: tuple[str, ...]
    value: NDArray[np.float64]
    se: NDArray[np.float64]
    ci_lo: NDArray[np.float64]
    ci_hi: NDArray[np.float64]
    selected: NDArray[np.bool_]
    units: tuple[str, ...]
    display_units: tuple[str, ...]
    chi2: NDArray[np.float64]
    n_points: int
    channels: tuple[str, ...]
    quantity: str | None
    method: str
    tau: NDArray[np.float64]
    slopes: SlopeReadout | None = None
    tau_min: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    ci_level: float = 0.95

    def get(self, name: str, channel: int = 0) -> float:
        """One fitted value, SI.

        Parameters
        ----------
        name : str
            Term name, one of :attr:`names`.
        channel : int
            Channel index.

        Returns
        -------
        float
            The estimate, in the SI unit of that term.

        Raises
        ------
        ValueError
            If the term is not in :attr:`names`.
        """
        return float(self.value[self.names.index(name), channel])

    def display(self, name: str) -> NDArray[np.float64]:
        """Values of a term in its display unit (e.g. N in deg/sqrt(h)).

        Parameters
        ----------
        name : str
            Term name, one of :attr:`names`.

        Returns
        -------
        numpy.ndarray, shape (C,)
            The estimate of each channel in that term's display unit (:attr:`display_units`).
        """
        i = self.names.index(name)
        du = self.display_units[i]
        if du == self.units[i]:
            return self.value[i].copy()
        return np.asarray(to_display(self.value[i], du), dtype=float)

    def model_avar(self, tau: ArrayLike, channel: int = 0) -> NDArray[np.float64]:
        """Fitted AVAR at ``tau`` for one channel (:func:`avar_model` with the fitted terms).

        Parameters
        ----------
        tau : array_like
            Cluster times, s.
        channel : int
            Channel index.

        Returns
        -------
        numpy.ndarray
            The model Allan variance, in the square of the channel's SI unit.
        """
        v = {nm: self.value[i, channel] for i, nm in enumerate(self.names)}
        gm = [(v[f"GM{j}_sigma"], v[f"GM{j}_T"]) for j in range(1, 10) if f"GM{j}_sigma" in v
              and v[f"GM{j}_sigma"] > 0]
        return avar_model(tau, v.get("Q", 0), v.get("N", 0), v.get("B", 0), v.get("K", 0), v.get("R", 0), gm)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary of the fit.

        Returns
        -------
        dict
            ``method``, ``quantity``, ``channels``, ``n_points``, ``ci_level``, ``chi2``, ``tau_min``, ``terms``
            (per term: SI ``unit``, ``value``, ``se``, ``ci_lo``, ``ci_hi``, ``selected``, ``display_unit``,
            ``display_value``, ``display_se``) and ``slope_readout``.
        """
        out: dict[str, Any] = {
            "method": self.method, "quantity": self.quantity, "channels": list(self.channels),
            "n_points": self.n_points, "ci_level": self.ci_level, "chi2": self.chi2.tolist(),
            "tau_min": self.tau_min.tolist(), "terms": {},
        }
        for i, nm in enumerate(self.names):
            disp = self.display(nm)
            du = self.display_units[i]
            fac = (disp / np.where(self.value[i] != 0, self.value[i], 1.0)) if du != self.units[i] else np.ones(
                len(self.channels))
            out["terms"][nm] = {
                "unit": self.units[i], "value": self.value[i].tolist(), "se": self.se[i].tolist(),
                "ci_lo": self.ci_lo[i].tolist(), "ci_hi": self.ci_hi[i].tolist(),
                "selected": self.selected[i].tolist(), "display_unit": du, "display_value": disp.tolist(),
                "display_se": (self.se[i] * fac).tolist(),
            }
        if self.slopes is not None:
            out["slope_readout"] = self.slopes.to_dict()
        return out


# --------------------------------------------------------------------------- fitting
def _gls_nnls(A: np.ndarray, G: np.ndarray, C: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """NNLS on the whitened system; returns theta, chi2 and the whitening factor."""
    L = np.linalg.cholesky(C)
    Gw = np.linalg.solve(L, G)
    Aw = np.linalg.solve(L, A)
    colscale = np.sqrt(np.sum(Gw**2, axis=0))
    colscale[colscale == 0] = 1.0
    th, _ = nnls(Gw / colscale, Aw, maxiter=50 * G.shape[1])
    th = th / colscale
    r = Aw - Gw @ th
    return th, float(r @ r), L


def _cov_rel(res_tau, m, n_phase, names, Ts, theta, fs, model, edf, overlapping):
    """Covariance of A / model (relative), well conditioned for Cholesky."""
    if overlapping:
        cov = _overlapping_cov(res_tau, m, n_phase, names, Ts, theta, fs)
        d = np.diag(cov).copy()
        bad = ~(d > 0)
        d[bad] = (2.0 * model**2 / edf)[bad]
        cov[np.diag_indices_from(cov)] = d
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            rel = cov / np.outer(model, model)
    else:
        rel = np.diag(2.0 / edf)
    if not np.all(np.isfinite(rel)):

        raise ConvergenceError("the noise terms cannot be fitted: the model variance is zero or not finite at some "
                               "tau, the Allan curve follows none of the terms (is the recording static? choose other "
                               "terms)")
    # keep positive definite (the lag sums are approximate)
    w, v = np.linalg.eigh(0.5 * (rel + rel.T))
    w = np.maximum(w, 1e-6 * w.max())
    return (v * w) @ v.T


def _design(tau: np.ndarray, names: list[str], Ts: list[float | None]) -> np.ndarray:
    return np.column_stack([avar_term("GM" if nm.startswith("GM") else nm, tau, T) for nm, T in zip(names, Ts)])


#: Stages of one channel's fit (its covariance is rebuilt in each): the reweighting passes, the term selection and
#: the final refinement; what ``fit_noise(progress=)`` counts.
_N_ITER = 3
_STAGES = _N_ITER + 2


def _fit_channel(tau, m, A, edf, n_phase, fs, names, Ts0, select, overlapping, n_iter=_N_ITER, tick=lambda: None):
    """GLS-NNLS for one channel; returns dict of theta, cov_theta, chosen mask, Ts, chi2 (``tick()`` after each of
    its :data:`_STAGES` stages)."""
    nT = A.size
    Ts = list(Ts0)
    gm_idx = [i for i, nm in enumerate(names) if nm.startswith("GM")]
    # start: diagonal weights from the measured values
    G = _design(tau, names, Ts)
    Cr = np.diag(2.0 / edf)
    th, _, _ = _gls_nnls(A / A, G / A[:, None], Cr)
    model = np.maximum(G @ th, 1e-300)

    def solve(cols, Ts_, Crel, model_):
        Gs = _design(tau, [names[c] for c in cols], [Ts_[c] for c in cols])
        return _gls_nnls(A / model_, Gs / model_[:, None], Crel)

    for _ in range(n_iter):
        Crel = _cov_rel(tau, m, n_phase, names, Ts, th, fs, model, edf, overlapping)
        # Gauss-Markov correlation times: 1-D searches on log T, others fixed
        for gi in gm_idx:
            def obj(lt, gi=gi, Crel=Crel, model=model):
                T2 = list(Ts)
                T2[gi] = math.exp(lt)
                return solve(range(len(names)), T2, Crel, model)[1]
            lt0 = math.log(Ts[gi])
            r = minimize_scalar(obj, bounds=(math.log(tau[0] / 10), math.log(tau[-1] * 10)), method="bounded",
                                options={"xatol": 1e-3})
            if r.fun <= obj(lt0):
                Ts[gi] = float(math.exp(r.x))
        th, _, _ = solve(range(len(names)), Ts, Crel, model)
        model = np.maximum(_design(tau, names, Ts) @ th, 1e-300)
        tick()

    # term selection on the final covariance
    Crel = _cov_rel(tau, m, n_phase, names, Ts, th, fs, model, edf, overlapping)
    allc = list(range(len(names)))
    best = None
    if select is None:
        cand = [allc]
    else:
        cand = [list(c) for k in range(1, len(names) + 1) for c in itertools.combinations(allc, k)]
    pen = math.log(nT) if select == "bic" else 2.0
    for cols in cand:
        if len(cols) > nT:
            continue
        t_, chi, _ = solve(cols, Ts, Crel, model)
        k_eff = int(np.sum(t_ > 0)) + sum(1 for c in cols if names[c].startswith("GM") and t_[cols.index(c)] > 0)
        crit = chi + pen * k_eff
        if best is None or crit < best[0] - 1e-9:
            best = (crit, cols, t_, chi)
    _, cols, t_, chi = best
    tick()
    thf = np.zeros(len(names))
    thf[cols] = t_
    # final refinement of the selected model's weights
    model = np.maximum(_design(tau, names, Ts) @ thf, 1e-300)
    Crel = _cov_rel(tau, m, n_phase, names, Ts, thf, fs, model, edf, overlapping)
    t_, chi, L = solve(cols, Ts, Crel, model)
    thf = np.zeros(len(names))
    thf[cols] = t_
    keep = [c for c in cols if thf[c] > 0]
    covth = np.full((len(names), len(names)), np.nan)
    se_logT = {}
    if keep:
        # Jacobian of the whitened model w.r.t. (theta_keep, log T of each kept GM term): the GM
        # correlation times are estimated too, and s_j^2 trades off against T_j, so the standard
        # errors of theta must come from the joint covariance (the theta block of (J^T J)^-1), not
        # from the GLS normal equations with T held fixed (that is the conditional covariance and
        # under-states se(GM sigma) by ~1.7 x).  The log T diagonal equals 2 / (chi2 curvature of
        # the profile over log T).
        Gs = _design(tau, [names[c] for c in keep], [Ts[c] for c in keep]) / model[:, None]
        cols_T = []
        for c in keep:
            if names[c].startswith("GM"):
                h = 1e-4
                d = (avar_term("GM", tau, Ts[c] * math.exp(h)) - avar_term("GM", tau, Ts[c] * math.exp(-h))) / (2 * h)
                cols_T.append(thf[c] * d / model)
        J = np.column_stack([Gs, *cols_T]) if cols_T else Gs
        Jw = np.linalg.solve(L, J)
        try:
            cj = np.linalg.inv(Jw.T @ Jw)
        except np.linalg.LinAlgError:
            cj = np.linalg.pinv(Jw.T @ Jw)
        nk = len(keep)
        covth[np.ix_(keep, keep)] = cj[:nk, :nk]
        gk = [c for c in keep if names[c].startswith("GM")]
        for j, gi in enumerate(gk):
            v = cj[nk + j, nk + j]
            se_logT[gi] = math.sqrt(v) if v > 0 else float("nan")
    tick()
    return thf, covth, np.array([c in keep for c in range(len(names))]), Ts, chi, se_logT


def _drop_filtered_start(tau, A, edf, ok, names) -> np.ndarray:
    """Mask without the leading points inconsistent with the model (see fit_noise)."""
    idx = np.flatnonzero(ok)
    base = [nm for nm in names if not nm.startswith("GM")] or ["N"]
    dropped = 0
    while len(idx) - dropped > max(4, len(base) + 2) and dropped < len(idx) // 3:
        sub = idx[dropped:]
        G = _design(tau[sub], base, [None] * len(base))
        a = A[sub]
        rel = 2.0 / edf[sub]
        th, _, _ = _gls_nnls(a / a, G / a[:, None], np.diag(rel))
        for _ in range(2):
            model = np.maximum(G @ th, 1e-300)
            th, _, _ = _gls_nnls(a / model, G / model[:, None], np.diag(rel))
        model = np.maximum(G @ th, 1e-300)
        zres = (a / model - 1.0) / np.sqrt(rel)
        dof = max(1, sub.size - int(np.sum(th > 0)))
        if abs(zres[0]) > 5.0 and float(zres @ zres) / dof > 3.0:
            dropped += 1
            continue
        break
    out = np.zeros_like(ok)
    out[idx[dropped:]] = True
    return out


def fit_noise(
    result: AllanResult,
    terms: Sequence[str] = TERMS,
    *,
    gauss_markov: int = 0,
    select: str | None = "bic",
    quantity: str | None = None,
    tau_range: tuple[float, float] | None = None,
    min_edf: float = 1.0,
    slopes: bool = True,
    auto_tau_min: bool = True,
    progress: Callable[[int, int], None] | None = None,
) -> NoiseFit:
    """Identify IEEE-952 (and Gauss-Markov) noise terms from an Allan result.

    Parameters
    ----------
    result : AllanResult
        From :func:`allan_deviation` with kind ``"overlapping"`` (full GLS
        covariance), ``"standard"`` or ``"total"`` (diagonal weights).
    terms : sequence of str
        Candidate terms, a subset of ("Q", "N", "B", "K", "R").
    gauss_markov : int
        Number of first-order Gauss-Markov terms to add (correlation times
        are fitted).
    select : {"bic", "aic"}, optional
        Automatic term selection over all subsets of the candidates, or keep
        all (non-negative least squares still sets absent terms to 0).
    quantity : {"gyro", "accel"}, optional
        Picks SI and display units; inferred from ``result.units``
        ("rad/s" -> gyro, "m/s^2" -> accel) when None.
    tau_range : (lo, hi), optional
        Use only cluster times inside this range (s).
    min_edf : float
        Ignore points with fewer equivalent degrees of freedom.
    slopes : bool
        Also compute the classic slope read-outs (:func:`slope_readout`).
    auto_tau_min : bool
        Drop leading (short-tau) points that the model cannot fit: real
        sensors low-pass filter their output, which lowers the Allan variance
        at tau of a few samples below the white-noise line (ADIS16405: -37 %
        at 10 ms).  A leading point is dropped while its standardized
        residual exceeds 5 and chi^2/dof exceeds 3 (at most a third of the
        points); ``tau_min`` reports where each channel's fit starts.
    progress : callable, optional
        ``progress(done, total)`` after each stage of each channel's fit (five per channel: the covariance of
        the Allan variances is rebuilt in each, a cost that grows with the square of the number of cluster
        times): a long fit (``taus="all"``) can show its progress.

    Returns
    -------
    NoiseFit
        Q (rad | m/s), N (unit/sqrt(Hz) = unit*sqrt(s)), B (unit), K
        (unit/s/sqrt(Hz)), R (unit/s), Gauss-Markov sigma (unit) and T (s),
        each with standard error and 95 % interval.

    Raises
    ------
    InvalidInputError
        If ``result`` is not an AllanResult of the Allan variance (``overlapping``, ``standard`` or
        ``total``), or a term, ``select``, ``gauss_markov`` or ``quantity`` is invalid.
    InsufficientDataError
        If a channel has fewer than 2 usable tau points.
    """
    if not isinstance(result, AllanResult):
        raise InvalidInputError("fit_noise needs an AllanResult from imunav.noise.allan_deviation")
    if result.kind not in ("overlapping", "standard", "total"):
        raise InvalidInputError(
            f"fit_noise models the Allan variance; got kind={result.kind!r}. Use kind='overlapping' (best), "
            "'standard' or 'total'"
        )
    terms = tuple(terms)
    bad = [t for t in terms if t not in TERMS]
    if bad or not terms and gauss_markov == 0:
        raise InvalidInputError(f"unknown terms {bad}; choose from {TERMS}")
    if select not in ("bic", "aic", None):
        raise InvalidInputError(f"select={select!r}; use 'bic', 'aic' or None")
    if gauss_markov < 0 or gauss_markov > 3:
        raise InvalidInputError(f"gauss_markov={gauss_markov}: use 0 to 3 terms")
    if quantity is None:
        u = result.units.replace(" ", "").lower()
        quantity = "gyro" if u in ("rad/s",) else "accel" if u in ("m/s^2", "m/s2", "m/s**2") else None
    elif quantity not in ("gyro", "accel"):
        raise InvalidInputError(f"quantity={quantity!r}; use 'gyro', 'accel' or None")

    adev = result.adev if result.adev.ndim == 2 else result.adev[:, None]
    edf_all = result.edf if result.edf.ndim == 2 else result.edf[:, None]
    n_ch = adev.shape[1]
    names = list(terms) + [f"GM{j + 1}" for j in range(gauss_markov)]
    out_names: list[str] = list(terms)
    for j in range(gauss_markov):
        out_names += [f"GM{j + 1}_sigma", f"GM{j + 1}_T"]
    P = len(out_names)
    val = np.zeros((P, n_ch))
    se = np.full((P, n_ch), np.nan)
    lo = np.zeros((P, n_ch))
    hi = np.zeros((P, n_ch))
    sel = np.zeros((P, n_ch), dtype=bool)
    chi2 = np.zeros(n_ch)
    tau_min = np.zeros(n_ch)
    z = 1.959963984540054
    n_used = 0
    done = 0

    def tick() -> None:
        nonlocal done
        done += 1
        if progress is not None:
            progress(done, n_ch * _STAGES)

    for c in range(n_ch):
        ok = np.isfinite(adev[:, c]) & (adev[:, c] > 0) & np.isfinite(edf_all[:, c]) & (edf_all[:, c] >= min_edf)
        if tau_range is not None:
            ok &= (result.tau >= tau_range[0]) & (result.tau <= tau_range[1])
        if ok.sum() < 2:
            raise InsufficientDataError(
                f"channel {result.channels[c] if result.channels else c}: only {int(ok.sum())} usable tau points; "
                "use a longer record or a wider tau_range"
            )
        if auto_tau_min:
            ok = _drop_filtered_start(result.tau, adev[:, c] ** 2, edf_all[:, c], ok, names)
        tau_min[c] = result.tau[ok][0]
        tau = result.tau[ok]
        A = adev[ok, c] ** 2
        edf = edf_all[ok, c]
        n_used = int(ok.sum())
        # initial GM correlation times spread over the tau range
        Ts0: list[float | None] = [None] * len(terms)
        for j in range(gauss_markov):
            Ts0.append(float(np.exp(np.log(tau[0]) + (j + 1) / (gauss_markov + 1) * np.log(tau[-1] / tau[0]))))
        th, covth, keep, Ts, chi, se_logT = _fit_channel(
            tau, result.m[ok], A, edf, result.n_samples + 1, result.fs, names, Ts0, select,
            result.kind == "overlapping", tick=tick,
        )
        chi2[c] = chi
        k = 0
        for i, nm in enumerate(names):
            t = th[i]
            v = math.sqrt(t) if t > 0 else 0.0
            s_th = math.sqrt(covth[i, i]) if keep[i] and np.isfinite(covth[i, i]) else float("nan")
            val[k, c] = v
            sel[k, c] = keep[i]
            if keep[i] and np.isfinite(s_th):
                se[k, c] = s_th / (2.0 * v)
                rel = s_th / t  # sd of log theta (delta method)
                lo[k, c] = v * math.exp(-z * rel / 2.0)
                hi[k, c] = v * math.exp(z * rel / 2.0)
            k += 1
            if nm.startswith("GM"):
                T = Ts[i]
                val[k, c] = T
                sel[k, c] = keep[i]
                sl = se_logT.get(i, float("nan"))
                se[k, c] = T * sl
                lo[k, c] = T * math.exp(-z * sl) if np.isfinite(sl) else 0.0
                hi[k, c] = T * math.exp(z * sl) if np.isfinite(sl) else math.inf
                k += 1
    q = quantity or "gyro"
    units = []
    dunits = []
    for nm in out_names:
        key = "sigma" if nm.endswith("_sigma") else "T" if nm.endswith("_T") else nm
        if quantity is None:
            units.append({"Q": "phase", "N": "unit*sqrt(s)", "B": "unit", "K": "unit/sqrt(s)", "R": "unit/s",
                          "sigma": "unit", "T": "s"}[key])
            dunits.append(units[-1])
        else:
            units.append(_SI_UNITS[q][key])
            dunits.append(_DISPLAY[q].get(key, units[-1]))
    slo = slope_readout(result) if slopes else None
    return NoiseFit(
        names=tuple(out_names), value=val, se=se, ci_lo=lo, ci_hi=hi, selected=sel, units=tuple(units),
        display_units=tuple(dunits), chi2=chi2, n_points=n_used,
        channels=result.channels if result.channels else tuple(f"ch{i}" for i in range(n_ch)),
        quantity=quantity, method=f"gls-nnls ({result.kind}, select={select})", tau=result.tau, slopes=slo,
        tau_min=tau_min,
    )


# --------------------------------------------------------------------------- slope read-outs
_SLOPE = {"Q": (-1.0, math.sqrt(3.0), 1.0), "N": (-0.5, 1.0, 1.0), "K": (0.5, 3.0, 1.0),
          "R": (1.0, math.sqrt(2.0), 1.0)}


def slope_readout(result: AllanResult, tol: float = 0.1) -> SlopeReadout:
    """Classic IEEE-952 read-outs from the Allan deviation curve (IEEE Std 952-1997, Annex C).

    For each slope s (-1 Q, -1/2 N, +1/2 K, +1 R) the tau points where the
    local log-log slope lies within ``tol`` of s are taken, a line of slope s
    is fitted through them in log-log space, and the term is read where that
    line crosses tau = sqrt(3) (Q), 1 (N), 3 (K), sqrt(2) s (R).  When no
    point has the slope, the two points whose local slope is nearest are used
    (``found`` False) -- that is what the popular scripts do, and why they
    over-estimate the random walk when its region is not reached.
    B = min(sigma) / 0.6643.

    Parameters
    ----------
    result : AllanResult
        An overlapping (or other) Allan deviation of one or more channels.
    tol : float
        Tolerance on the local log-log slope.

    Returns
    -------
    SlopeReadout
        The read-outs, SI units, with the tau ranges used.

    Raises
    ------
    InsufficientDataError
        With fewer than 3 tau points.
    """
    adev = result.adev if result.adev.ndim == 2 else result.adev[:, None]
    n_ch = adev.shape[1]
    names = ("Q", "N", "B", "K", "R")
    val = np.zeros((5, n_ch))
    tlo = np.full((5, n_ch), np.nan)
    thi = np.full((5, n_ch), np.nan)
    found = np.zeros((5, n_ch), dtype=bool)
    for c in range(n_ch):
        ok = np.isfinite(adev[:, c]) & (adev[:, c] > 0)
        lt = np.log10(result.tau[ok])
        ls = np.log10(adev[ok, c])
        if lt.size < 3:
            raise InsufficientDataError("slope read-out needs at least 3 tau points")
        slope = np.gradient(ls, lt)
        for p, nm in enumerate(names):
            if nm == "B":
                j = int(np.argmin(ls))
                val[p, c] = 10 ** ls[j] / BI_FACTOR
                tlo[p, c] = thi[p, c] = 10 ** lt[j]
                found[p, c] = True
                continue
            s, tread, _ = _SLOPE[nm]
            pick = np.abs(slope - s) <= tol
            if pick.any():
                found[p, c] = True
            else:
                pick = np.zeros_like(pick)
                pick[np.argsort(np.abs(slope - s))[:2]] = True
            b = float(np.mean(ls[pick] - s * lt[pick]))
            sig = 10 ** (b + s * math.log10(tread))
            # the line's value at the read-off tau is the coefficient itself:
            # sqrt(3) Q / tau at sqrt(3); N / sqrt(tau) at 1; K sqrt(tau/3) at 3; R tau / sqrt(2) at sqrt(2)
            val[p, c] = sig
            tlo[p, c] = 10 ** lt[pick].min()
            thi[p, c] = 10 ** lt[pick].max()
    return SlopeReadout(names=names, value=val, tau_lo=tlo, tau_hi=thi, found=found)


def identifiability(fit: NoiseFit, duration: float, clusters: float = 9.0) -> dict[str, list[dict[str, Any]]]:
    """Which fitted long-term terms (B, K, R) a record of ``duration`` seconds can tell apart from white noise.

    A term shows in an Allan curve only from the cluster time ``tau_x`` where its Allan variance exceeds that of
    every other selected term (the white noise ``N^2 / tau`` first); an Allan point at ``tau`` rests on about ``duration / tau`` independent
    clusters, so the term needs ``duration >= clusters * tau_x`` (about 9 clusters: +-25 % on the deviation
    at one sigma).  A term the fit selected on a shorter record is an extrapolation, not an estimate.

    Parameters
    ----------
    fit : NoiseFit
        The fit (:func:`fit_noise`); its N term (or, without it, Q) is the white-noise reference.
    duration : float
        Length of the record the fit came from, s (without its gaps).
    clusters : float
        Independent clusters wanted at ``tau_x`` (default 9).

    Returns
    -------
    dict
        For each of B, K, R among ``fit.names``: one dict per channel with ``selected`` (bool),
        ``identifiable`` (bool, or None when the term was not selected), ``tau_x_s`` and ``needs_s`` (the
        record length the term needs, s; None when not selected or without a white-noise term).

    Raises
    ------
    InvalidInputError
        If ``duration`` is not a positive number of seconds.
    """
    if not (np.isfinite(duration) and duration > 0):
        raise InvalidInputError(f"duration={duration}: give the record length in seconds (> 0)")
    ref = "N" if "N" in fit.names else ("Q" if "Q" in fit.names else None)
    grid = np.logspace(-4, 9, 1301)
    out: dict[str, list[dict[str, Any]]] = {}
    for name in ("B", "K", "R"):
        if name not in fit.names:
            continue
        i = fit.names.index(name)
        rows = []
        for c in range(fit.value.shape[1]):
            sel = bool(fit.selected[i, c]) and fit.value[i, c] > 0
            row: dict[str, Any] = {"selected": sel, "identifiable": None, "tau_x_s": None, "needs_s": None}
            if sel and ref is not None and fit.selected[fit.names.index(ref), c]:
                # the term must exceed every other selected term (white noise below, the steeper ones above)
                v = fit.value[i, c] ** 2 * avar_term(name, grid)
                others = [fit.value[j, c] ** 2 * avar_term(fit.names[j], grid) for j in range(len(fit.names))
                          if j != i and fit.names[j] in TERMS and fit.selected[j, c] and fit.value[j, c] > 0]
                above = np.flatnonzero(np.all([v >= w for w in others], axis=0)) if others else np.arange(grid.size)
                if above.size:  # else the term stays under the white noise at every cluster time
                    tau_x = float(grid[above[0]])
                    row.update(tau_x_s=tau_x, needs_s=clusters * tau_x, identifiable=bool(duration >= clusters * tau_x))
                else:
                    row["identifiable"] = False
            rows.append(row)
        out[name] = rows
    return out
