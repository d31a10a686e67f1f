"""Smooth curve fits of the Allan deviation curve.

The "proposed method" of E. Atasoy, *Estimation and analysis of error parameters of attitude-heading
reference system sensors* (in Turkish), MSc thesis, Başkent University, §5.5 and §7.3: ordinary
polynomials (degrees 5, 10, 20) and a rational polynomial (numerator degree 4, denominator degree 2)
fitted to the (tau, sigma) curve.  They are smoothers, not physical models; they are
reported beside the physical-term fit (:func:`imunav.noise.fit_noise`).

Both are fitted in log-log space, x = (log10 tau - centre)/scale, y =
log10 sigma (a degree-20 polynomial in linear tau over decades is numerically
meaningless).  The rational model uses a monic denominator (MATLAB ``rat42``
form) ``(p1 x^4 + ... + p5)/(x^2 + q1 x + q2)``, initialised from the
linearised problem ``p(x) - y (q1 x + q2) = y x^2`` and refined by
Levenberg-Marquardt; a real denominator root inside the fitted range is
reported as a pole.  Metrics: RMS and max error in log10 sigma.  Thesis-style
read-outs from the smooth curve (sigma at tau = 1 s, min / 0.6643, sigma at
tau = 3 s; IEEE Std 952-1997, Annex C) are offered, flagged as such.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

from imunav.errors import InsufficientDataError, InvalidInputError
from imunav.noise.fit import BI_FACTOR
from imunav.results import Result

__all__ = ["CurveFit", "fit_polynomial", "fit_rational", "compare_curve_fits"]


@dataclass(frozen=True)
class CurveFit(Result):
    """A smooth fit of log10 sigma against normalised log10 tau, ``y = num(x) / den(x)``.

    Calling it, ``fit(tau)``, gives the fitted deviation at ``tau`` (s).

    Attributes
    ----------
    kind : str
        ``"poly<n>"`` or ``"rational<n>/<m>"``.
    num : numpy.ndarray
        Numerator coefficients, highest power first.
    den : numpy.ndarray
        Denominator coefficients (monic), ``[1.0]`` for polynomials.
    centre, scale : float
        Normalisation ``x = (log10 tau - centre) / scale`` (tau in s).
    rms_log10, max_log10 : float
        RMS and largest absolute residual in log10 sigma (decades).
    has_pole : bool
        Whether a real root of the denominator lies inside the fitted range.
    tau_range : tuple of float
        Smallest and largest fitted tau, s.
    """

    kind: str  # "poly<n>" or "rational<n>/<m>"
    num: NDArray[np.float64]  # numerator coefficients, highest power first
    den: NDArray[np.float64]  # denominator coefficients (monic), [1.0] for polynomials
    centre: float
    scale: float
    rms_log10: float
    max_log10: float
    has_pole: bool
    tau_range: tuple[float, float]

    def __call__(self, tau: ArrayLike) -> NDArray[np.float64]:
        """Fitted deviation at tau."""
        x = (np.log10(np.asarray(tau, dtype=float)) - self.centre) / self.scale
        return 10 ** (np.polyval(self.num, x) / np.polyval(self.den, x))

    def readout(self) -> dict[str, float]:
        """Thesis-style values from the smooth curve.

        sigma(1 s) (N if the -1/2 region reaches 1 s), min sigma / 0.6643 (B), sigma(3 s) (K if the +1/2 region
        covers 3 s), the read-outs of IEEE Std 952-1997, Annex C.  Only meaningful where those slopes hold.

        Returns
        -------
        dict
            ``"B"`` always; ``"N_at_1s"`` and ``"sigma_at_3s"`` when 1 s and 3 s are inside the fitted range.
            In the unit of the fitted deviation.
        """
        t = np.logspace(np.log10(self.tau_range[0]), np.log10(self.tau_range[1]), 400)
        s = self(t)
        out = {"B": float(s.min() / BI_FACTOR)}
        if self.tau_range[0] <= 1.0 <= self.tau_range[1]:
            out["N_at_1s"] = float(self(1.0))
        if self.tau_range[0] <= 3.0 <= self.tau_range[1]:
            out["sigma_at_3s"] = float(self(3.0))
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary of the fit.

        Returns
        -------
        dict
            The attributes, arrays as lists.
        """
        return {"kind": self.kind, "num": self.num.tolist(), "den": self.den.tolist(), "centre": self.centre,
                "scale": self.scale, "rms_log10": self.rms_log10, "max_log10": self.max_log10,
                "has_pole": self.has_pole, "tau_range": list(self.tau_range)}


def _prep(tau: ArrayLike, adev: ArrayLike) -> tuple[np.ndarray, np.ndarray, float, float]:
    t = np.asarray(tau, dtype=float)
    s = np.asarray(adev, dtype=float)
    if t.shape != s.shape or t.ndim != 1:
        raise InvalidInputError("tau and adev must be 1-D arrays of the same length (one channel)")
    ok = np.isfinite(t) & np.isfinite(s) & (t > 0) & (s > 0)
    t, s = t[ok], s[ok]
    lt = np.log10(t)
    c = float(lt.mean())
    sc = float(max(lt.std(), 1e-12))
    return (lt - c) / sc, np.log10(s), c, sc


def fit_polynomial(tau: ArrayLike, adev: ArrayLike, degree: int) -> CurveFit:
    """Least-squares polynomial of ``degree`` in log-log space (Atasoy, eq. 5.33).

    Solved in the Chebyshev basis (well conditioned at degree 20), converted to power form.

    Parameters
    ----------
    tau : array_like, shape (T,)
        Cluster times, s (non-positive or non-finite points are left out).
    adev : array_like, shape (T,)
        Allan deviation of one channel at ``tau`` (rad/s or m/s²).
    degree : int
        Polynomial degree, >= 0.

    Returns
    -------
    CurveFit
        The fit with its residual metrics.

    Raises
    ------
    InsufficientDataError
        If there are not more points than ``degree``.
    InvalidInputError
        If ``tau`` and ``adev`` are not 1-D of the same length.
    """
    x, y, c, sc = _prep(tau, adev)
    if degree < 0 or x.size <= degree:
        raise InsufficientDataError(f"degree {degree} needs more than {degree} points, got {x.size}")
    # Chebyshev-conditioned solve, converted to power form
    cheb = np.polynomial.chebyshev.Chebyshev.fit(x, y, degree, domain=[-1, 1], window=[-1, 1])
    num = cheb.convert(kind=np.polynomial.Polynomial).coef[::-1]
    r = np.polyval(num, x) - y
    t = np.asarray(tau, dtype=float)
    return CurveFit(kind=f"poly{degree}", num=num, den=np.array([1.0]), centre=c, scale=sc,
                    rms_log10=float(np.sqrt(np.mean(r**2))), max_log10=float(np.max(np.abs(r))), has_pole=False,
                    tau_range=(float(t.min()), float(t.max())))


def fit_rational(tau: ArrayLike, adev: ArrayLike, num_degree: int = 4, den_degree: int = 2) -> CurveFit:
    """Rational fit with monic denominator (Atasoy, eq. 5.34, ``rat42`` by default).

    Parameters
    ----------
    tau : array_like, shape (T,)
        Cluster times, s (non-positive or non-finite points are left out).
    adev : array_like, shape (T,)
        Allan deviation of one channel at ``tau`` (rad/s or m/s²).
    num_degree : int
        Degree of the numerator.
    den_degree : int
        Degree of the (monic) denominator.

    Returns
    -------
    CurveFit
        The fit; ``has_pole`` flags a real denominator root inside the fitted range.

    Raises
    ------
    InsufficientDataError
        If there are not more points than coefficients.
    InvalidInputError
        If ``tau`` and ``adev`` are not 1-D of the same length.
    """
    x, y, c, sc = _prep(tau, adev)
    npar = num_degree + 1 + den_degree
    if x.size <= npar:
        raise InsufficientDataError(f"rational {num_degree}/{den_degree} needs more than {npar} points, got {x.size}")
    # linearised start: p(x) - y * (q_1 x^{m-1} + ... + q_m) = y x^m
    V = np.column_stack([x**k for k in range(num_degree, -1, -1)]
                        + [-y * x**k for k in range(den_degree - 1, -1, -1)])
    z0, *_ = np.linalg.lstsq(V, y * x**den_degree, rcond=None)

    def split(z):
        return z[: num_degree + 1], np.concatenate(([1.0], z[num_degree + 1 :]))

    def resid(z):
        p, q = split(z)
        return np.polyval(p, x) / np.polyval(q, x) - y

    sol = least_squares(resid, z0, method="lm", max_nfev=2000 * npar)
    p, q = split(sol.x)
    roots = np.roots(q)
    real = roots[np.abs(roots.imag) < 1e-9].real
    pole = bool(np.any((real >= x.min()) & (real <= x.max())))
    r = resid(sol.x)
    t = np.asarray(tau, dtype=float)
    return CurveFit(kind=f"rational{num_degree}/{den_degree}", num=p, den=q, centre=c, scale=sc,
                    rms_log10=float(np.sqrt(np.mean(r**2))), max_log10=float(np.max(np.abs(r))), has_pole=pole,
                    tau_range=(float(t.min()), float(t.max())))


def compare_curve_fits(tau: ArrayLike, adev: ArrayLike, degrees: tuple[int, ...] = (5, 10, 20),
                       rational: tuple[int, int] = (4, 2)) -> dict[str, CurveFit]:
    """The thesis's comparison: polynomials of the given degrees (skipped when there are too few points) and the
    rational fit.

    Parameters
    ----------
    tau : array_like, shape (T,)
        Cluster times, s (non-positive or non-finite points are left out).
    adev : array_like, shape (T,)
        Allan deviation of one channel at ``tau`` (rad/s or m/s²).
    degrees : tuple of int
        Polynomial degrees.
    rational : tuple of int
        ``(num_degree, den_degree)`` of the rational fit.

    Returns
    -------
    dict of str to CurveFit
        Keyed ``"poly<n>"`` and ``"rational<n>/<m>"``.

    Raises
    ------
    InvalidInputError
        If ``tau`` and ``adev`` are not 1-D of the same length.
    """
    out: dict[str, CurveFit] = {}
    n = np.count_nonzero(np.isfinite(np.asarray(adev, dtype=float)))
    for d in degrees:
        if n > d:
            out[f"poly{d}"] = fit_polynomial(tau, adev, d)
    out[f"rational{rational[0]}/{rational[1]}"] = fit_rational(tau, adev, *rational)
    return out
