"""Magnetometer hard- and soft-iron calibration.

Model: ``h_raw = A⁻¹ h_true + b`` so that ``h_cal = A (h_raw − b)`` lies on a
sphere of radius ``|h_true|`` (the field norm).  Magnetic field stays in the
user's unit throughout.

The estimators:

- :func:`hard_iron_minmax`: per-axis mid-range ``(max + min) / 2`` (E. Atasoy, *Estimation and analysis
  of error parameters of attitude-heading reference system sensors* (in Turkish), MSc thesis, Başkent
  University, ch. 6, eqs. 6.1-6.4).
- :func:`soft_iron_rotation_scale`: the thesis "rotate then scale" method,
  automated: principal axes of the hard-iron-corrected cloud give the
  rotation, the semi-axis ratios ``α_i = r_i / r̄`` (eq. 6.9) the scales, and
  we rotate back: ``A = Rᵀ diag(1/α) R`` (the thesis leaves out the back
  rotation, an 11° frame error in its own example).
- :func:`fit_ellipsoid`: Q. Li, J. G. Griffiths, "Least squares ellipsoid specific fitting", Geometric
  Modeling and Processing 2004: ellipsoid-specific least squares (constraint ``4J − I² = 1``), followed
  by a geometric refinement ``min Σ (|A (h − b)| − F)²`` whose Jacobian gives the standard errors.
  Without a known field norm, ``A`` is normalised to ``det A = 1`` and the
  expected field strength is ``F = (abc)^{1/3}`` of the semi-axes (the convention of MATLAB's
  ``magcal``, MathWorks Sensor Fusion and Tracking Toolbox documentation).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

from imunav.errors import (
    DegenerateGeometryError,
    InsufficientDataError,
    InvalidInputError,
    NonFiniteError,
    ShapeError,
)
from imunav.results import Result
from imunav.rotation import euler_from_dcm

__all__ = [
    "MagCalibration",
    "MAG_METHODS",
    "calibrate_magnetometer",
    "fit_ellipsoid",
    "fit_minmax",
    "hard_iron_minmax",
    "minmax_calibration",
    "soft_iron_rotation_scale",
    "sphere_coverage",
]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class MagCalibration(Result):
    """Hard iron ``b`` (3,), soft iron ``A`` (3, 3): ``h_cal = A (h − b)``.

    Attributes
    ----------
    b : numpy.ndarray, shape (3,)
        Hard-iron offset, in the data's unit.
    A : numpy.ndarray, shape (3, 3)
        Soft-iron matrix (dimensionless).
    field_norm : float
        The (given or estimated) field magnitude, in the data's unit.
    method : str
        The method that produced it.
    stderr : dict of str to numpy.ndarray
        Standard errors of ``b`` and ``A`` (empty when not computed).
    quality : dict of str to float
        Coverage, residual RMS, design condition, relative spread of ``|h_cal|`` before and after.
    extra : dict
        Method-specific outputs (angles, α ...).
    """

    b: Array
    A: Array
    field_norm: float
    method: str
    stderr: dict[str, Array] = field(default_factory=dict)
    quality: dict[str, float] = field(default_factory=dict)
    extra: dict[str, Any] = field(default_factory=dict)

    def apply(self, h: ArrayLike) -> Array:
        """Calibrated field ``A (h − b)``.

        Parameters
        ----------
        h : array_like, shape (N, 3)
            Raw magnetometer samples, any unit (kept), sensor axes.

        Returns
        -------
        numpy.ndarray, shape (N, 3)
            The calibrated field, same unit.
        """
        return (_points(h, minimum=1) - self.b) @ self.A.T

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (format ``imunav.mag-calibration``, version 1).

        Returns
        -------
        dict
            ``format``, ``format_version``, ``model``, ``method``, ``b``, ``A``, ``field_norm``, ``stderr``,
            ``quality``, ``extra``.
        """
        return {
            "format": "imunav.mag-calibration",
            "format_version": 1,
            "model": "h_cal = A (h_raw - b)",
            "method": self.method,
            "b": self.b.tolist(),
            "A": self.A.tolist(),
            "field_norm": self.field_norm,
            "stderr": {k: np.asarray(v).tolist() for k, v in self.stderr.items()},
            "quality": self.quality,
            "extra": {k: (np.asarray(v).tolist() if isinstance(v, np.ndarray) else v) for k, v in self.extra.items()},
        }


def _points(h: ArrayLike, minimum: int) -> Array:
    a = np.asarray(h, dtype=float)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ShapeError(f"magnetometer samples must be (N, 3), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"magnetometer samples: non-finite rows {np.flatnonzero(~np.isfinite(a).all(1))[:10].tolist()}")
    if a.shape[0] < minimum:
        raise InsufficientDataError(f"magnetometer calibration needs at least {minimum} samples, got {a.shape[0]}")
    big = float(np.abs(a).max())
    if big > _MAX_ABS:
        raise InvalidInputError(f"magnetometer samples reach {big:.3g}, beyond {_MAX_ABS:.0e}: no unit (T, uT, nT, "
                                "gauss, raw counts) gives such values; check the file's scaling")
    return a


#: Largest magnitude accepted in a magnetometer sample (any unit): squares stay far inside the float range.
_MAX_ABS = 1e30


def _fibonacci(n: int) -> Array:
    i = np.arange(n) + 0.5
    phi = np.arccos(1 - 2 * i / n)
    th = np.pi * (1 + 5**0.5) * i
    return np.stack([np.cos(th) * np.sin(phi), np.sin(th) * np.sin(phi), np.cos(phi)], axis=1)


_CELLS = _fibonacci(60)


def sphere_coverage(directions: ArrayLike) -> float:
    """Fraction of 60 equal-area cells of the sphere that hold at least one direction.

    Parameters
    ----------
    directions : array_like, shape (N, 3)
        Direction vectors (normalised here; zero vectors are ignored).

    Returns
    -------
    float
        Coverage in [0, 1].
    """
    d = np.asarray(directions, float)
    n = np.linalg.norm(d, axis=1)
    d = d[n > 0] / n[n > 0, None]
    if d.shape[0] == 0:
        return 0.0
    cell = np.argmax(d @ _CELLS.T, axis=1)
    return float(np.unique(cell).size / len(_CELLS))


def _quality(h: Array, b: Array, A: Array, F: float, cond: float) -> dict[str, float]:
    hc = (h - b) @ A.T
    n = np.linalg.norm(hc, axis=1)
    n0 = np.linalg.norm(h - h.mean(0), axis=1)
    return {
        "coverage": sphere_coverage(hc),
        "residual_rms": float(np.sqrt(np.mean((n - F) ** 2))),
        "condition": float(cond),
        "norm_spread_before": float(np.std(np.linalg.norm(h, axis=1)) / np.mean(np.linalg.norm(h, axis=1))),
        "norm_spread_centred_raw": float(np.std(n0) / np.mean(n0)),
        "norm_spread_after": float(np.std(n) / np.mean(n)),
        "n_samples": int(h.shape[0]),
    }


def _check_planar(h: Array, tol: float) -> None:
    s = np.linalg.svd(h - h.mean(0), compute_uv=False)
    if not s[0] > 1e-12 * max(1.0, float(np.abs(h).max())):
        raise DegenerateGeometryError(
            "magnetometer data are a single repeated point: no rotation was recorded; "
            "rotate the sensor about more than one axis (cover the whole sphere)"
        )
    if s[-1] < tol * s[0]:
        raise DegenerateGeometryError(
            f"magnetometer data are (nearly) planar: thickness/span = {s[-1] / s[0]:.2g} < {tol}; "
            "rotate the sensor about more than one axis (cover the whole sphere)"
        )


def hard_iron_minmax(h: ArrayLike) -> Array:
    """Hard iron as the per-axis mid-range ``(max + min)/2`` (Atasoy, eqs. 6.1-6.3).

    Parameters
    ----------
    h : array_like, shape (N, 3)
        Raw magnetometer samples, any unit (kept), sensor axes.

    Returns
    -------
    numpy.ndarray, shape (3,)
        The hard-iron offset, in the data's unit.

    Raises
    ------
    DegenerateGeometryError
        For a single repeated point, a line or a plane: the mid-range of an axis that was not swept is not
        the hard iron.
    InsufficientDataError
        With too few samples.
    ShapeError
        If ``h`` is not (N, 3).
    NonFiniteError
        If ``h`` has NaN or infinite values.
    """
    a = _points(h, minimum=2)
    _check_planar(a, 0.02)
    return (a.max(0) + a.min(0)) / 2.0


def minmax_calibration(h: ArrayLike) -> MagCalibration:
    """Hard iron only: the per-axis mid-range of :func:`hard_iron_minmax`, soft iron the identity.

    The field magnitude is the mean norm of the corrected samples, and the quality record holds the spread of
    that norm (its standard deviation over its mean), which a soft iron left uncorrected widens.

    Parameters
    ----------
    h : array_like, shape (N, 3)
        Raw magnetometer samples (any unit, kept), sweeping the sphere.

    Returns
    -------
    MagCalibration
        ``b`` the mid-range, ``A`` the identity, ``method = "minmax"``, quality ``norm_spread_after``.

    Raises
    ------
    DegenerateGeometryError
        For a single repeated point, a line or a plane (:func:`hard_iron_minmax`).
    InsufficientDataError
        With too few samples.
    ShapeError
        If ``h`` is not (N, 3).
    NonFiniteError
        If ``h`` has NaN or infinite values.
    """
    b = hard_iron_minmax(h)
    n = np.linalg.norm(np.asarray(h, dtype=float) - b, axis=1)
    return MagCalibration(b, np.eye(3), float(np.mean(n)), "minmax", {},
                          {"norm_spread_after": float(np.std(n) / np.mean(n))})


#: Methods of :func:`calibrate_magnetometer`.
MAG_METHODS = ("ellipsoid", "rotation-scale", "minmax")


def calibrate_magnetometer(h: ArrayLike, method: str = "ellipsoid", *, field_norm: float | None = None,
                           min_coverage: float = 0.3) -> MagCalibration:
    """Hard- and soft-iron calibration of magnetometer samples by one of :data:`MAG_METHODS` (``imunav calibrate
    mag``).

    Parameters
    ----------
    h : array_like, shape (N, 3)
        Raw magnetometer samples (any unit, kept), sweeping the sphere.
    method : {"ellipsoid", "rotation-scale", "minmax"}, optional
        ``"ellipsoid"``: the ellipsoid fit of Li & Griffiths (:func:`fit_ellipsoid`); ``"rotation-scale"``: the
        thesis's mid-range, principal axes and scales (:func:`soft_iron_rotation_scale`); ``"minmax"``: hard iron
        only (:func:`minmax_calibration`).
    field_norm : float, optional
        Known field magnitude in the data's unit (ellipsoid; default: ``det(A) = 1``).
    min_coverage : float, optional
        Smallest accepted sphere coverage (ellipsoid).

    Returns
    -------
    MagCalibration
        ``h_cal = A (h − b)``.

    Raises
    ------
    InvalidInputError
        If ``method`` is none of :data:`MAG_METHODS` (and the errors of the method's function).
    """
    if method == "ellipsoid":
        return fit_ellipsoid(h, field_norm, min_coverage=min_coverage)
    if method == "rotation-scale":
        return soft_iron_rotation_scale(h)
    if method == "minmax":
        return minmax_calibration(h)
    raise InvalidInputError(f"--method must be ellipsoid, rotation-scale or minmax, not {method!r}")


def soft_iron_rotation_scale(h: ArrayLike, *, planar_tol: float = 0.02) -> MagCalibration:
    """Thesis method: mid-range hard iron, then rotate to the principal axes and scale (Atasoy, ch. 6).

    The rotation ``R`` (rows = principal axes of the corrected cloud) replaces
    the thesis's angles picked by eye; ``r_i`` is half the span along axis i,
    ``α_i = r_i / mean(r)`` and ``A = Rᵀ diag(1/α) R``; the field norm is ``mean(r)``.

    Parameters
    ----------
    h : array_like, shape (N, 3)
        Raw magnetometer samples, any unit (kept), sensor axes.
    planar_tol : float
        Smallest accepted thickness / span of the raw cloud.

    Returns
    -------
    MagCalibration
        With extra outputs ``R``, ``alpha``, Euler ``angles`` (roll, pitch, yaw of ``Rᵀ``, rad).

    Raises
    ------
    DegenerateGeometryError
        For planar or degenerate data.
    InsufficientDataError
        With too few samples.
    """
    a = _points(h, minimum=10)
    _check_planar(a, planar_tol)
    b = hard_iron_minmax(a)
    c = a - b
    # principal axes from the centred quadric c^T M c = 1 (linear LS in the 6 entries of M)
    X = np.stack([c[:, 0] ** 2, c[:, 1] ** 2, c[:, 2] ** 2, 2 * c[:, 1] * c[:, 2], 2 * c[:, 0] * c[:, 2], 2 * c[:, 0] * c[:, 1]], 1)
    m, *_ = np.linalg.lstsq(X, np.ones(len(c)), rcond=None)
    M = np.array([[m[0], m[5], m[4]], [m[5], m[1], m[3]], [m[4], m[3], m[2]]])
    w, V = np.linalg.eigh(M)
    if np.any(w <= 0):
        raise DegenerateGeometryError("rotation/scale soft iron: the centred cloud is not an ellipsoid; cover the sphere")
    # order the principal axes like the sensor axes they are closest to
    order: list[int] = []
    for i in range(3):
        cand = [j for j in range(3) if j not in order]
        order.append(max(cand, key=lambda j: abs(V[i, j])))
    V = V[:, order]
    w = w[order]
    V = V * np.sign(np.diag(V))[None, :]
    if np.linalg.det(V) < 0:  # the axes' signs are free (A below is the same): keep R a rotation, not a mirror
        V[:, int(np.argmin(np.abs(np.diag(V))))] *= -1.0
    R = V.T
    r = 1.0 / np.sqrt(w)  # semi-axis lengths along the principal axes
    alpha = r / r.mean()
    A = R.T @ np.diag(1.0 / alpha) @ R

    ang = np.asarray(euler_from_dcm(R.T), float)
    F = float(r.mean())
    return MagCalibration(
        b, A, F, "rotation_scale", {}, _quality(a, b, A, F, float(w.max() / max(w.min(), 1e-300))),
        {"R": R, "alpha": alpha, "angles": ang},
    )


def _sqrtm_spd(M: Array) -> Array:
    w, V = np.linalg.eigh((M + M.T) / 2)
    return (V * np.sqrt(w)) @ V.T


def _li_griffiths(h: Array) -> tuple[Array, Array, float]:
    """Centre ``c`` and shape ``M`` ((h−c)ᵀ M (h−c) = 1) of the LG ellipsoid fit; design condition."""
    m = h.mean(0)
    s = np.sqrt(np.mean(np.sum((h - m) ** 2, axis=1)))
    x, y, z = ((h - m) / s).T
    D = np.stack([x * x, y * y, z * z, 2 * y * z, 2 * x * z, 2 * x * y, 2 * x, 2 * y, 2 * z, np.ones_like(x)])
    sv = np.linalg.svd(D.T / np.linalg.norm(D, axis=1), compute_uv=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    S = D @ D.T
    S11, S12, S22 = S[:6, :6], S[:6, 6:], S[6:, 6:]
    try:
        S22i_S21 = np.linalg.solve(S22, S12.T)
    except np.linalg.LinAlgError:
        raise DegenerateGeometryError("ellipsoid fit: singular scatter matrix; the data do not span 3-D") from None
    Sred = S11 - S12 @ S22i_S21
    # k = 4 guarantees an ellipsoid when its shortest axis is at least half the longest;
    # for more elongated shapes Li & Griffiths lower k towards 3 (the constraint still forces an ellipsoid)
    u1 = None
    for k in (4.0, 3.8, 3.6, 3.4, 3.2, 3.1, 3.05, 3.01):
        C1 = np.zeros((6, 6))
        C1[:3, :3] = k / 2 - 1
        np.fill_diagonal(C1[:3, :3], -1.0)
        C1[3:, 3:] = -k * np.eye(3)
        ev, evec = np.linalg.eig(np.linalg.solve(C1, Sred))
        ev, evec = np.real(ev), np.real(evec)
        # Sred is PSD and C1 has one positive eigenvalue, so one eigenvalue is >= 0;
        # on (nearly) noise-free data it is 0 and rounding can make it -1e-14:
        # accept it within rounding rather than lowering k to a spurious root
        if np.max(ev) > -1e-9 * np.max(np.abs(ev)):
            u1 = evec[:, int(np.argmax(ev))]
            break
    if u1 is None:
        raise DegenerateGeometryError("ellipsoid fit: no ellipsoid solution (Li-Griffiths eigenvalue not positive)")
    u2 = -S22i_S21 @ u1
    a, bb, c, f, g, hh = u1
    p, q, r, d = u2
    Q = np.array([[a, hh, g], [hh, bb, f], [g, f, c]])
    P = np.array([p, q, r])
    try:
        c0 = -np.linalg.solve(Q, P)
    except np.linalg.LinAlgError:
        raise DegenerateGeometryError("ellipsoid fit: degenerate quadric (no centre)") from None
    kk = c0 @ Q @ c0 - d
    M = Q / kk
    if np.any(np.linalg.eigvalsh((M + M.T) / 2) <= 0):
        raise DegenerateGeometryError("ellipsoid fit: the fitted quadric is not an ellipsoid; cover the sphere better")
    return m + s * c0, M / s**2, cond


_IU = np.triu_indices(3)


def _sym(v: Array) -> Array:
    L = np.zeros((3, 3))
    L[_IU] = v
    return L + np.triu(L, 1).T


def _raise_coverage(cov: float, min_coverage: float) -> None:
    raise DegenerateGeometryError(
        f"magnetometer data cover only {100 * cov:.0f} % of the sphere (minimum {100 * min_coverage:.0f} %): "
        "partial coverage leaves the hard and soft iron undetermined; rotate the sensor through all orientations "
        "(or lower min_coverage=... (command line: --min-coverage) at your own risk)"
    )


def _covering_ellipsoid(a: Array, min_coverage: float) -> tuple[Array, Array, float]:
    """Li & Griffiths centre ``c0`` and ``L0`` (``|L0 (h - c0)| = 1``) and condition, after refusing data that
    cover less than ``min_coverage`` of the sphere around it: the one coverage test of every method."""
    try:
        c0, M, cond = _li_griffiths(a)
    except np.linalg.LinAlgError as exc:
        raise DegenerateGeometryError(f"ellipsoid fit: the linear algebra failed ({exc}); the data do not describe "
                                      "an ellipsoid: rotate the sensor over the whole sphere") from None
    L0 = _sqrtm_spd(M)
    cov0 = sphere_coverage((a - c0) @ L0.T)
    if cov0 < min_coverage:
        _raise_coverage(cov0, min_coverage)
    return c0, L0, cond


def fit_minmax(h: ArrayLike, *, min_coverage: float = 0.3, planar_tol: float = 0.02) -> MagCalibration:
    """Hard iron only, by the per-axis mid-range (:func:`hard_iron_minmax`), on data that cover the sphere.

    The mid-range of an axis is the hard iron only when the sensor was turned through both ends of that
    axis; data are refused on the same coverage test as :func:`fit_ellipsoid` (so a cap of the sphere,
    whose mid-range is the field itself, gives no calibration).

    Parameters
    ----------
    h : array_like
        (N, 3) raw magnetometer samples, any unit (kept).
    min_coverage : float
        Smallest accepted fraction of the sphere covered (60 cells), as for :func:`fit_ellipsoid`.
    planar_tol : float
        Smallest accepted thickness/span of the raw cloud.

    Returns
    -------
    MagCalibration
        ``b``, ``A = I``, ``field_norm`` (mean ``|h - b|``) and ``quality`` (coverage, spread of ``|h - b|``).

    Raises
    ------
    InsufficientDataError : fewer than 10 samples.
    DegenerateGeometryError : planar data or partial coverage.
    """
    a = _points(h, minimum=10)
    _check_planar(a, planar_tol)
    _covering_ellipsoid(a, min_coverage)
    b = hard_iron_minmax(a)
    F = float(np.mean(np.linalg.norm(a - b, axis=1)))
    q = _quality(a, b, np.eye(3), F, float("nan"))
    return MagCalibration(b, np.eye(3), F, "minmax", {}, q)


def fit_ellipsoid(
    h: ArrayLike,
    field_norm: float | None = None,
    *,
    min_coverage: float = 0.3,
    planar_tol: float = 0.02,
    refine: bool = True,
) -> MagCalibration:
    """Ellipsoid-specific least-squares fit (Li & Griffiths 2004) with geometric refinement.

    Parameters
    ----------
    h : array_like
        (N, 3) raw magnetometer samples, any unit (kept).
    field_norm : float, optional
        Known field magnitude; ``A`` is scaled so ``|A (h − b)| = field_norm``.
        Default None: ``det A = 1`` and the field norm is estimated.
    min_coverage : float
        Smallest accepted fraction of the sphere covered (60 cells).
    planar_tol : float
        Smallest accepted thickness/span of the raw cloud.
    refine : bool
        Refine geometrically and report standard errors (else stderr empty).

    Returns
    -------
    MagCalibration
        ``b``, ``A``, ``field_norm``, ``stderr["b"]``, ``stderr["A"]`` and ``quality`` (coverage, residual
        RMS, condition, spread of ``|h_cal|``).

    Raises
    ------
    InsufficientDataError : fewer than 10 samples.
    DegenerateGeometryError : planar data, partial coverage or no ellipsoid solution.
    """
    a = _points(h, minimum=10)
    _check_planar(a, planar_tol)
    c0, L0, cond = _covering_ellipsoid(a, min_coverage)
    stderr: dict[str, Array] = {}
    b, L = c0, L0
    if refine:
        x0 = np.concatenate([c0, L0[_IU]])

        def fun(x: Array) -> Array:
            return np.linalg.norm((a - x[:3]) @ _sym(x[3:]).T, axis=1) - 1.0

        sol = least_squares(fun, x0, method="lm", x_scale="jac")
        b, L = sol.x[:3], _sym(sol.x[3:])
        J = sol.jac
        dof = max(len(a) - 9, 1)
        s2 = float(np.sum(sol.fun**2) / dof)
        try:
            cov = s2 * np.linalg.inv(J.T @ J)
        except np.linalg.LinAlgError:
            raise DegenerateGeometryError("ellipsoid fit: singular refinement Jacobian; cover the sphere better") from None
    if not np.linalg.eigvalsh(0.5 * (L + L.T)).min() > 0:
        raise DegenerateGeometryError("ellipsoid fit: the fitted surface is not an ellipsoid (the shape matrix is not "
                                      "positive definite); rotate the sensor through more orientations")
    if field_norm is None:
        det = np.linalg.det(L)
        F = float(det ** (-1.0 / 3.0))
    else:
        if not field_norm > 0:
            raise InsufficientDataError(f"field_norm must be positive, got {field_norm}")
        F = float(field_norm)
    A = F * L
    if refine:
        # delta method for A(x) = F(x) L(x) (F fixed when given)
        x = np.concatenate([b, L[_IU]])

        def amap(v: Array) -> Array:
            Lv = _sym(v[3:])
            Fv = F if field_norm is not None else np.linalg.det(Lv) ** (-1.0 / 3.0)
            return (Fv * Lv).ravel()

        eps = 1e-7 * np.maximum(np.abs(x), 1e-3)
        Jm = np.stack([(amap(x + e) - amap(x - e)) / (2 * ei) for e, ei in zip(np.diag(eps), eps)], axis=1)
        covA = Jm @ cov @ Jm.T
        stderr = {"b": np.sqrt(np.diag(cov)[:3]), "A": np.sqrt(np.maximum(np.diag(covA), 0)).reshape(3, 3)}
        if field_norm is None:
            gF = np.array([(np.linalg.det(_sym((x + e)[3:])) ** (-1 / 3) - np.linalg.det(_sym((x - e)[3:])) ** (-1 / 3)) / (2 * ei) for e, ei in zip(np.diag(eps), eps)])
            stderr["field_norm"] = np.array(np.sqrt(gF @ cov @ gF))
    q = _quality(a, b, A, F, cond)
    if q["coverage"] < min_coverage:
        _raise_coverage(q["coverage"], min_coverage)
    return MagCalibration(b, A, F, "ellipsoid_li_griffiths", stderr, q, {})
