"""numba estimation core: the primitives every imunav filter is built from (private).

Small SPD algebra (Gauss–Jordan and Cholesky inverses), measurement updates (scalar and vector, Joseph form, Schmidt
consider states; the unscented sigma-point update), the χ² innovation gate, error-state injection and covariance
reset, Van Loan discretisation and the strapdown step (local level and NED).  Every
function is ``@njit(cache=True)`` and works in place on caller-owned buffers, so the fused per-sample loops of
:mod:`imunav.attitude`, :mod:`imunav.ins` and :mod:`imunav.airdata` stay allocation-light.  Measurement models
(the ``(innovation, H, R)`` of one sensor) live in :mod:`imunav.filters._core_models`.

Conventions (docs/conventions.md): SI units, NED navigation frame, Hamilton scalar-first quaternions ``q_nb``
(body → nav).  Two attitude-error conventions exist and both are kept:

* *local* (body) error, ``q = q̂ ⊗ exp(δθ)`` (Solà 2017, *Quaternion kinematics for the error-state Kalman
  filter*, §5–6; Markley 2003; the attitude MEKF/UKF/smoother);
* *global* (navigation-frame) error, ``C_nb = exp([δφ×]) Ĉ_nb``, i.e. ``q = exp(δφ) ⊗ q̂`` (Solà 2017, §7;
  Groves 2013, ch. 14; the ZUPT and INS error-state filters).

``exp`` of a rotation vector r is the unit quaternion ``[cos(|r|/2), sin(|r|/2) r/|r|]``
(:func:`imunav._rotation_kernels.qexp_1`).

The signatures of this module are a stable API (tag ``[core-api]``): add functions, do not change these.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from imunav._rotation_kernels import qexp_1, qmul_1, qrot_1
from imunav.earth import radii_gravity_1

# ---------------------------------------------------------------------------------------------------------------
# Small dense linear algebra (no LAPACK: these run inside nopython loops on m <= 6 systems)


@njit(cache=True)
def inv_small(S, Si):
    """Inverse of a small symmetric positive-definite matrix by Gauss–Jordan elimination (in place into ``Si``).

    Parameters
    ----------
    S : (m, m) float64 array, SPD (an innovation covariance), m small (≤ 6 is the intended use).
    Si : (m, m) float64 array that receives ``S⁻¹``.

    Notes
    -----
    No pivoting: SPD matrices have positive pivots (Golub & Van Loan 2013, §4.2).
    """
    m = S.shape[0]
    A = S.copy()
    for i in range(m):
        for j in range(m):
            Si[i, j] = 1.0 if i == j else 0.0
    for c in range(m):
        piv = A[c, c]
        for j in range(m):
            A[c, j] /= piv
            Si[c, j] /= piv
        for r in range(m):
            if r != c:
                fct = A[r, c]
                if fct != 0.0:
                    for j in range(m):
                        A[r, j] -= fct * A[c, j]
                        Si[r, j] -= fct * Si[c, j]


@njit(cache=True)
def cholesky_small(A):
    """Lower Cholesky factor ``L`` (``A = L Lᵀ``) of a small symmetric positive-definite matrix (new array).

    Cholesky–Banachiewicz, row by row (Golub & Van Loan 2013, Algorithm 4.2.1).  A pivot that rounding makes
    non-positive is clamped to 1e-300 (its root to 1e-150) instead of failing inside a filter loop; a caller that
    must refuse a non-positive-definite matrix checks ``min(diag(L)) > 1e-150``.

    Parameters
    ----------
    A : (n, n) float64 array, SPD (only its lower triangle is read).

    Returns
    -------
    (n, n) float64 array, lower triangular.
    """
    n = A.shape[0]
    L = np.zeros((n, n))
    for i in range(n):
        for j in range(i + 1):
            s = A[i, j]
            for k in range(j):
                s -= L[i, k] * L[j, k]
            if i == j:
                L[i, i] = math.sqrt(max(s, 1e-300))
            else:
                L[i, j] = s / L[j, j]
    return L


@njit(cache=True)
def inv_spd_cholesky(A):
    """Inverse of a small symmetric positive-definite matrix through its Cholesky factor (new array).

    ``A⁻¹ = L⁻ᵀ L⁻¹`` with ``L`` from :func:`cholesky_small` and ``L⁻¹`` by forward substitution; the result is
    exactly symmetric.  The unscented update and the RTS smoother use it; :func:`inv_small` (Gauss–Jordan) is the
    one of the Joseph updates.  Both are kept so that every filter's figures stay bit-identical.

    Parameters
    ----------
    A : (n, n) float64 array, SPD.

    Returns
    -------
    (n, n) float64 array, ``A⁻¹``.
    """
    n = A.shape[0]
    L = cholesky_small(A)
    Li = np.zeros((n, n))
    for j in range(n):
        Li[j, j] = 1.0 / L[j, j]
        for i in range(j + 1, n):
            acc = 0.0
            for k in range(j, i):
                acc -= L[i, k] * Li[k, j]
            Li[i, j] = acc / L[i, i]
    out = np.zeros((n, n))
    for i in range(n):
        for j in range(i + 1):
            acc = 0.0
            for k in range(i, n):
                acc += Li[k, i] * Li[k, j]
            out[i, j] = acc
            out[j, i] = acc
    return out


# ---------------------------------------------------------------------------------------------------------------
# Measurement updates


@njit(cache=True)
def _apply_scalar_gain(P, dx, PH, nu, s, n_est):
    """dx += K ν, P −= P hᵀ h P / s with K = P hᵀ / s on the first ``n_est`` states (the shared tail of the
    scalar updates; see :func:`scalar_update`)."""
    n = P.shape[0]
    for i in range(n_est):
        dx[i] += PH[i] * nu / s
    for i in range(n):
        for j in range(n):
            if i < n_est or j < n_est:
                P[i, j] -= PH[i] * PH[j] / s


@njit(cache=True)
def scalar_update(P, dx, h, r, nu, PH, n_est):
    """Scalar measurement update of an error state (dense row ``h``), in place on ``P`` and ``dx``.

    With ``s = h P hᵀ + r``, ``K = P hᵀ / s`` on the first ``n_est`` states and 0 on the others (Schmidt–Kalman
    consider states, Simon 2006, *Optimal State Estimation*, §7.5)::

        ν' = ν − h dx,   dx ← dx + K ν',
        P  ← (I − K h) P (I − K h)ᵀ + K r Kᵀ = P − P hᵀ h P / s   (blocks touching an estimated state)

    The Joseph form (Bucy & Joseph 1968) reduces exactly to the right-hand side for this gain; evaluated as
    ``P[i, j] −= PH[i] PH[j] / s`` it keeps P bit-symmetric.  The consider–consider block is unchanged.

    Parameters
    ----------
    P : (n, n) covariance, updated in place.
    dx : (n,) error-state estimate, updated in place (pass zeros for a fresh error state).
    h : (n,) measurement row.
    r : float, measurement variance.
    nu : float, innovation ``z − ẑ`` at the nominal state (before ``h dx``).
    PH : (n,) scratch that receives ``P hᵀ`` (before the update).
    n_est : int, number of estimated states (``n`` for a plain update).

    Returns
    -------
    nu_post : float, the innovation ``ν'`` used.
    s : float, its variance (``ν'² / s`` is the NIS term).
    """
    n = P.shape[0]
    for i in range(n):
        acc = 0.0
        for j in range(n):
            acc += P[i, j] * h[j]
        PH[i] = acc
    s = r
    hdx = 0.0
    for i in range(n):
        s += h[i] * PH[i]
        hdx += h[i] * dx[i]
    nu = nu - hdx
    _apply_scalar_gain(P, dx, PH, nu, s, n_est)
    return nu, s


@njit(cache=True)
def scalar_update_sparse(P, dx, idx, hv, r, nu, PH, n_est):
    """:func:`scalar_update` for an index-sparse row: ``h[idx[l]] = hv[l]``, zero elsewhere.

    Same equations (Joseph form for the optimal / Schmidt gain), O(n·len(idx) + n²) instead of O(n²) for
    ``P hᵀ``.

    Parameters
    ----------
    P : (n, n) covariance, updated in place.
    dx : (n,) error-state estimate, updated in place.
    idx : (l,) int64 indices of the non-zero entries of h.
    hv : (l,) their values.
    r : float, measurement variance.
    nu : float, innovation at the nominal state.
    PH : (n,) scratch for ``P hᵀ``.
    n_est : int, number of estimated states.

    Returns
    -------
    nu_post : float, innovation used.
    s : float, its variance.
    """
    n = P.shape[0]
    m = idx.shape[0]
    for i in range(n):
        acc = 0.0
        for l in range(m):
            acc += P[i, idx[l]] * hv[l]
        PH[i] = acc
    s = r
    hdx = 0.0
    for l in range(m):
        s += hv[l] * PH[idx[l]]
        hdx += hv[l] * dx[idx[l]]
    nu = nu - hdx
    _apply_scalar_gain(P, dx, PH, nu, s, n_est)
    return nu, s


@njit(cache=True)
def joseph_update(P, dx, H, R, nu, innov_out, S_out):
    """Vector measurement update in Joseph form (m small), in place on ``P`` and ``dx``.

    ::

        ν' = ν − H dx,   S = H P Hᵀ + R,   K = P Hᵀ S⁻¹,   dx ← dx + K ν',
        P ← (I − K H) P (I − K H)ᵀ + K R Kᵀ          (Bucy & Joseph 1968)

    P is symmetrised.  Writes ``ν'`` and ``S`` for NIS records (:func:`nis`, :func:`chi2_gate`).
    :func:`joseph_update_gain` is the same update that also hands back the gain.

    Parameters
    ----------
    P : (n, n) covariance, updated in place.
    dx : (n,) error-state estimate, updated in place.
    H : (m, n) measurement matrix.
    R : (m, m) measurement covariance.
    nu : (m,) innovation at the nominal state.
    innov_out : (m,) receives ``ν'``.
    S_out : (m, m) receives ``S``.

    Returns
    -------
    nis : float, ``ν'ᵀ S⁻¹ ν'``.
    """
    K = np.empty((P.shape[0], H.shape[0]))
    return joseph_update_gain(P, dx, H, R, nu, innov_out, S_out, K)


@njit(cache=True)
def joseph_update_gain(P, dx, H, R, nu, innov_out, S_out, K_out):
    """:func:`joseph_update` that also writes the gain ``K = P Hᵀ S⁻¹`` it applied into ``K_out``.

    Parameters
    ----------
    P : (n, n) covariance, updated in place.
    dx : (n,) error-state estimate, updated in place.
    H : (m, n) measurement matrix.
    R : (m, m) measurement covariance.
    nu : (m,) innovation at the nominal state.
    innov_out : (m,) receives ``ν'``.
    S_out : (m, m) receives ``S``.
    K_out : (n, m) receives ``K``.

    Returns
    -------
    nis : float, ``ν'ᵀ S⁻¹ ν'``.
    """
    return _joseph(P, dx, H, R, nu, innov_out, S_out, K_out, np.zeros(0, dtype=np.bool_))


@njit(cache=True, inline="always")
def joseph_update_consider(P, dx, H, R, nu, innov_out, S_out, K_out, consider):
    """:func:`joseph_update_gain` with Schmidt consider states: the gain rows of the states flagged in ``consider``
    are zero, so that those states are never updated while their uncertainty and its correlations still reach the
    others (the Schmidt-Kalman filter: Schmidt 1966, "Application of state-space methods to navigation problems",
    Advances in Control Systems 3).  The Joseph form holds for any gain, so ``P ← (I − K H) P (I − K H)ᵀ + K R Kᵀ`` is the consider covariance.

    Parameters
    ----------
    P : (n, n) covariance, updated in place.
    dx : (n,) error-state estimate, updated in place (consider states unchanged).
    H : (m, n) measurement matrix.
    R : (m, m) measurement covariance.
    nu : (m,) innovation at the nominal state.
    innov_out : (m,) receives ``ν'``.
    S_out : (m, m) receives ``S``.
    K_out : (n, m) receives the gain applied (zero rows for consider states).
    consider : (n,) bool, the consider states.

    Returns
    -------
    nis : float, ``ν'ᵀ S⁻¹ ν'``.
    """
    return _joseph(P, dx, H, R, nu, innov_out, S_out, K_out, consider)


@njit(cache=True)
def _joseph(P, dx, H, R, nu, innov_out, S_out, K_out, consider):
    """The Joseph update of :func:`joseph_update_gain`; gain rows zeroed where ``consider`` (empty: none)."""
    n = P.shape[0]
    m = H.shape[0]
    PHt = np.empty((n, m))
    for i in range(n):
        for j in range(m):
            acc = 0.0
            for l in range(n):
                acc += P[i, l] * H[j, l]
            PHt[i, j] = acc
    for i in range(m):
        acc = nu[i]
        for l in range(n):
            acc -= H[i, l] * dx[l]
        innov_out[i] = acc
        for j in range(m):
            acc = R[i, j]
            for l in range(n):
                acc += H[i, l] * PHt[l, j]
            S_out[i, j] = acc
    Si = np.empty((m, m))
    inv_small(S_out, Si)
    PS = PHt @ Si
    for i in range(n):  # element by element: a slice assignment compiles numba's shape-error message
        for j in range(m):
            K_out[i, j] = PS[i, j]
    for i in range(consider.shape[0]):
        if consider[i]:
            for j in range(m):
                K_out[i, j] = 0.0
    out = 0.0
    for i in range(m):
        for j in range(m):
            out += innov_out[i] * Si[i, j] * innov_out[j]
    for i in range(n):
        acc = 0.0
        for j in range(m):
            acc += K_out[i, j] * innov_out[j]
        dx[i] += acc
    # I − K H and the sum below element by element, not as array expressions: the same arithmetic in a fraction of
    # the machine code (numba's array expressions compile broadcasting loops, and every kernel that calls this one
    # compiles its code again: issue 35, a first run)
    A = K_out @ H
    for i in range(n):
        for j in range(n):
            A[i, j] = (1.0 if i == j else 0.0) - A[i, j]
    APA = A @ P @ A.T
    KRK = K_out @ R @ K_out.T
    for i in range(n):
        for j in range(n):
            P[i, j] = 0.5 * ((APA[i, j] + KRK[i, j]) + (APA[j, i] + KRK[j, i]))
    return out


@njit(cache=True)
def joseph_update_rows(P, dx, idx, z, r, innov_out, s_out):
    """Vector update in Joseph form for unit rows ``H = [e_idx[0]; …]`` and diagonal ``R = diag(r)``.

    ``S = P[idx, idx] + R``, ``K = P[:, idx] S⁻¹``, ``dx = K z`` (``dx`` is overwritten: a fresh error state),
    ``P ← (I − K H) P (I − K H)ᵀ + K R Kᵀ`` evaluated in O(n² m) because H only selects states
    (``(I − K H) P = P − K P[idx, :]``; Bucy & Joseph 1968).  P is symmetrised.

    Parameters
    ----------
    P : (n, n) covariance, updated in place.
    dx : (n,) receives the error estimate ``K z``.
    idx : (m,) int64 measured state indices.
    z : (m,) innovation (measurement minus nominal prediction).
    r : (m,) measurement variances.
    innov_out : (m,) receives ``z``.
    s_out : (m,) receives the diagonal of S.

    Returns
    -------
    None
    """
    nx = P.shape[0]
    m = idx.shape[0]
    S = np.empty((m, m))
    Si = np.empty((m, m))
    for i in range(m):
        for j in range(m):
            S[i, j] = P[idx[i], idx[j]]
        S[i, i] += r[i]
    inv_small(S, Si)
    K = np.empty((nx, m))
    for i in range(nx):
        for j in range(m):
            acc = 0.0
            for l in range(m):
                acc += P[i, idx[l]] * Si[l, j]
            K[i, j] = acc
    for i in range(nx):
        acc = 0.0
        for j in range(m):
            acc += K[i, j] * z[j]
        dx[i] = acc
    X = np.empty((nx, nx))
    for i in range(nx):
        for j in range(nx):
            acc = P[i, j]
            for l in range(m):
                acc -= K[i, l] * P[idx[l], j]
            X[i, j] = acc
    # P = X (I - K H)^T + K R K^T = X - X[:, idx] K^T + K R K^T
    for i in range(nx):
        for j in range(i, nx):
            acc = X[i, j]
            for l in range(m):
                acc += -X[i, idx[l]] * K[j, l] + K[i, l] * r[l] * K[j, l]
            acc2 = X[j, i]
            for l in range(m):
                acc2 += -X[j, idx[l]] * K[i, l] + K[j, l] * r[l] * K[i, l]
            P[i, j] = 0.5 * (acc + acc2)
            P[j, i] = P[i, j]
    for j in range(m):
        innov_out[j] = z[j]
        s_out[j] = S[j, j]


@njit(cache=True)
def nis(nu, S):
    """Normalised innovation squared ``νᵀ S⁻¹ ν`` (Bar-Shalom, Li & Kirubarajan 2001, §5.4).

    Parameters
    ----------
    nu : (m,) innovation.
    S : (m, m) its covariance (SPD).

    Returns
    -------
    float
    """
    m = nu.shape[0]
    Si = np.empty((m, m))
    inv_small(S, Si)
    out = 0.0
    for i in range(m):
        for j in range(m):
            out += nu[i] * Si[i, j] * nu[j]
    return out


@njit(cache=True)
def chi2_gate(nu, S, threshold):
    """χ² innovation gate: accept when ``νᵀ S⁻¹ ν ≤ threshold`` (Bar-Shalom et al. 2001, §5.4.2).

    ``threshold`` is the χ²(m) quantile of the chosen false-alarm rate, computed outside the kernel
    (e.g. ``scipy.stats.chi2.ppf(1 − α, m)``; :func:`imunav.filters.robust.isolation_thresholds`).

    Parameters
    ----------
    nu : (m,) innovation.
    S : (m, m) its covariance.
    threshold : float.

    Returns
    -------
    accepted : bool.
    nis : float, the statistic.
    """
    d = nis(nu, S)
    return d <= threshold, d


# ---------------------------------------------------------------------------------------------------------------
# Unscented transform (scaled sigma points; Julier 2002, Wan & van der Merwe 2000)


@njit(cache=True)
def unscented_weights(n, alpha, beta, kappa):
    """Spread and weights of the 2n + 1 scaled sigma points.

    ``λ = α² (n + κ) − n``;  ``Wm₀ = λ / (n + λ)``,  ``Wc₀ = Wm₀ + 1 − α² + β``,  ``W_i = 1 / (2 (n + λ))`` for
    i ≥ 1 (Julier 2002; Wan & van der Merwe 2000).

    Parameters
    ----------
    n : int, state dimension.
    alpha, beta, kappa : float, spread, prior-distribution and secondary scaling parameters (n + λ > 0).

    Returns
    -------
    lam : float, λ.
    wm0 : float, mean weight of the centre point.
    wc0 : float, covariance weight of the centre point.
    wi : float, weight of every other point (mean and covariance).
    """
    lam = alpha * alpha * (n + kappa) - n
    wm0 = lam / (n + lam)
    wc0 = wm0 + (1.0 - alpha * alpha + beta)
    wi = 0.5 / (n + lam)
    return lam, wm0, wc0, wi


@njit(cache=True)
def sigma_offsets(P, lam, X):
    """Sigma-point offsets from the mean: ``X₀ = 0``, ``X_i = L_i``, ``X_{n+i} = −L_i`` with ``L_i`` the columns of
    the Cholesky factor of ``(n + λ) P`` (:func:`cholesky_small`), written into X.

    Parameters
    ----------
    P : (n, n) covariance.
    lam : float, λ of :func:`unscented_weights`.
    X : (2n + 1, n) receives the offsets.

    Returns
    -------
    (n, n) float64 array, the Cholesky factor used.
    """
    n = P.shape[0]
    L = cholesky_small((n + lam) * P)
    for j in range(n):
        X[0, j] = 0.0
    for i in range(n):
        X[1 + i] = L[:, i]
        X[1 + n + i] = -L[:, i]
    return L


@njit(cache=True)
def unscented_mean(Y, wm0, wi):
    """Weighted mean ``Wm₀ Y₀ + Σ_{s≥1} W_i Y_s`` of transformed sigma points.

    Parameters
    ----------
    Y : (2n + 1, m) transformed points, centre first.
    wm0, wi : float, weights of :func:`unscented_weights`.

    Returns
    -------
    (m,) float64 array.
    """
    ym = wm0 * Y[0]
    for s in range(1, Y.shape[0]):
        ym += wi * Y[s]
    return ym


@njit(cache=True)
def unscented_cov(A, B, wc0, wi):
    """Weighted outer-product sum ``Wc₀ A₀ B₀ᵀ + Σ_{s≥1} W_i A_s B_sᵀ`` of deviations from the means.

    ``unscented_cov(D, D, …)`` is the covariance of the points ``D`` (e.g. ``P_zz``), ``unscented_cov(X, D, …)``
    the cross-covariance (``P_xz``).

    Parameters
    ----------
    A : (2n + 1, p) deviations, centre first.
    B : (2n + 1, q) deviations, centre first.
    wc0, wi : float, weights of :func:`unscented_weights`.

    Returns
    -------
    (p, q) float64 array.
    """
    C = np.zeros((A.shape[1], B.shape[1]))
    for s in range(A.shape[0]):
        C += (wc0 if s == 0 else wi) * np.outer(A[s], B[s])
    return C


@njit(cache=True)
def unscented_update(P, Pxz, Pzz, nu, dx, K_out):
    """Sigma-point measurement update, in place on ``P``: the gain comes from the cross- and innovation
    covariances of the sigma points, no Jacobian is formed (Julier 2002; Crassidis & Markley 2003)::

        K = P_xz P_zz⁻¹,   dx = K ν,   P ← P − K P_zz Kᵀ (symmetrised)

    ``P_zz⁻¹`` by :func:`inv_spd_cholesky`, used for the gain and the NIS alike.  For the optimal gain
    ``P − K P_zz Kᵀ`` equals the Joseph form of a linear model.

    Parameters
    ----------
    P : (n, n) prior covariance, updated in place.
    Pxz : (n, m) state–measurement cross-covariance.
    Pzz : (m, m) innovation covariance (measurement noise included).
    nu : (m,) innovation ``z − ẑ``.
    dx : (n,) receives the correction ``K ν`` (overwritten: a fresh error state).
    K_out : (n, m) receives the gain.

    Returns
    -------
    nis : float, ``νᵀ P_zz⁻¹ ν``.
    """
    Si = inv_spd_cholesky(Pzz)
    K = Pxz @ Si
    K_out[:, :] = K
    dx[:] = K @ nu
    Pn = P - K @ Pzz @ K.T
    P[:, :] = 0.5 * (Pn + Pn.T)
    return nu @ Si @ nu


# ---------------------------------------------------------------------------------------------------------------
# Error-state injection and reset


@njit(cache=True)
def quat_normalize(q):
    """Unit quaternion ``q / |q|`` (new array).

    Parameters
    ----------
    q : (4,) quaternion.

    Returns
    -------
    (4,) float64 array.
    """
    nn = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    return q / nn


@njit(cache=True)
def inject_additive(x, dx, i0, n):
    """Additive injection ``x[i] += dx[i0 + i]`` for i < n (vector states: position, velocity, biases).

    Parameters
    ----------
    x : (n,) nominal sub-state, updated in place.
    dx : error-state vector.
    i0 : int, first index of the sub-state in ``dx``.
    n : int, its length.

    Returns
    -------
    None
    """
    for j in range(n):
        x[j] += dx[i0 + j]


@njit(cache=True, inline="always")
def _angle_error(dx, i0):
    """A copy of the attitude error ``dx[i0:i0+3]`` (a new (3,) array)."""
    r = np.empty(3)
    for j in range(3):
        r[j] = dx[i0 + j]
    return r


@njit(cache=True)
def inject_attitude_local(q, dx, i0):
    """Multiplicative injection of a body-frame attitude error: ``q ← q ⊗ exp(δθ)``, normalised.

    ``δθ = dx[i0:i0+3]`` (Solà 2017, §6.2, Hamilton product; Markley 2003).

    Parameters
    ----------
    q : (4,) nominal ``q_nb``.
    dx : error-state vector.
    i0 : int, index of δθ_x in ``dx``.

    Returns
    -------
    (4,) the corrected unit quaternion (new array).
    """
    r = _angle_error(dx, i0)
    return quat_normalize(qmul_1(q, qexp_1(r)))


@njit(cache=True)
def inject_attitude_global(q, dx, i0):
    """Multiplicative injection of a navigation-frame attitude error: ``q ← exp(δφ) ⊗ q``, normalised.

    ``C_nb = exp([δφ×]) Ĉ_nb`` with ``δφ = dx[i0:i0+3]`` (Solà 2017, §7.2; Groves 2013, ch. 14).

    Parameters
    ----------
    q : (4,) nominal ``q_nb``.
    dx : error-state vector.
    i0 : int, index of δφ_N in ``dx``.

    Returns
    -------
    (4,) the corrected unit quaternion (new array).
    """
    r = _angle_error(dx, i0)
    return quat_normalize(qmul_1(qexp_1(r), q))


@njit(cache=True)
def reset_attitude_cov(P, dx, i0):
    """Covariance reset after injecting a body attitude error: ``P ← G P Gᵀ``, ``G = I − [½ δθ̂×]`` on the
    attitude rows/columns ``i0:i0+3`` (Markley 2003; Solà 2017, §6.3), in place.

    The error seen from the corrected ``q̂⁺ = q̂ ⊗ exp(δθ̂)`` is ``δθ⁺ ≈ G (δθ − δθ̂)``.

    Parameters
    ----------
    P : (n, n) covariance, updated in place.
    dx : error-state vector holding the injected δθ̂ at ``i0``.
    i0 : int, index of δθ_x.

    Returns
    -------
    None
    """
    n = P.shape[0]
    G = np.eye(n)
    a0 = 0.5 * dx[i0]
    a1 = 0.5 * dx[i0 + 1]
    a2 = 0.5 * dx[i0 + 2]
    G[i0, i0 + 1] = a2
    G[i0, i0 + 2] = -a1
    G[i0 + 1, i0] = -a2
    G[i0 + 1, i0 + 2] = a0
    G[i0 + 2, i0] = a1
    G[i0 + 2, i0 + 1] = -a0
    P[:, :] = G @ P @ G.T


# ---------------------------------------------------------------------------------------------------------------
# Covariance propagation


@njit(cache=True)
def propagate_cov_sparse(Phi, P, Qd, M, nzc, nzn):
    """Covariance prediction ``P ← Φ P Φᵀ + Q_d`` (symmetrised ``Q_d``), skipping the zeros of a sparse Φ, in place.

    The error-state transition of an INS (``Φ = I + F Δt``) is mostly zeros; the products run over the non-zero
    entries of each row of Φ only (Groves 2013, §3.2.2 for the prediction).  P comes out exactly symmetric.

    Parameters
    ----------
    Phi : (n, n) transition matrix.
    P : (n, n) covariance, updated in place.
    Qd : (n, n) discrete process noise.
    M : (n, n) workspace.
    nzc : (n, n) int64 workspace (column indices of the non-zeros of each row of Φ).
    nzn : (n,) int64 workspace (their counts).

    Returns
    -------
    None
    """
    nx = P.shape[0]
    for i in range(nx):
        c = 0
        for l in range(nx):
            if Phi[i, l] != 0.0:
                nzc[i, c] = l
                c += 1
        nzn[i] = c
    for i in range(nx):
        for j in range(nx):
            acc = 0.0
            for c in range(nzn[i]):
                l = nzc[i, c]
                acc += Phi[i, l] * P[l, j]
            M[i, j] = acc
    for i in range(nx):
        for j in range(i, nx):
            acc = 0.0
            for c in range(nzn[j]):
                l = nzc[j, c]
                acc += M[i, l] * Phi[j, l]
            acc += 0.5 * (Qd[i, j] + Qd[j, i])
            P[i, j] = acc
            P[j, i] = acc


# ---------------------------------------------------------------------------------------------------------------
# Discretisation


@njit(cache=True)
def expm(A):
    """Matrix exponential by scaling and squaring with the diagonal Padé(6, 6) approximant.

    Golub & Van Loan 2013, *Matrix Computations*, Algorithm 9.3.1: scale so that ``‖A/2ʲ‖∞ ≤ ½`` and the
    relative truncation error is below 2⁻⁵³-ish (q = 6 gives ≈ 3·10⁻¹⁶), then square j times.

    Parameters
    ----------
    A : (n, n) float64 array.

    Returns
    -------
    (n, n) float64 array, ``exp(A)``.
    """
    n = A.shape[0]
    nrm = 0.0
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += abs(A[i, j])
        nrm = max(nrm, s)
    j = 0
    if nrm > 0.5:
        j = int(math.ceil(math.log2(nrm / 0.5)))
    X = A / (2.0**j)
    q = 6
    c = 1.0
    N = np.eye(n)
    D = np.eye(n)
    Xk = np.eye(n)
    sign = 1.0
    for k in range(1, q + 1):
        c = c * (q - k + 1) / ((2 * q - k + 1) * k)
        Xk = X @ Xk
        N += c * Xk
        sign = -sign
        D += sign * c * Xk
    E = np.ascontiguousarray(np.linalg.solve(D, N))
    for _ in range(j):
        E = E @ E
    return E


@njit(cache=True)
def van_loan(F, GQGt, dt):
    """Exact discretisation of ``ẋ = F x + G w``, ``E[w wᵀ] = Q δ(t)`` over ``dt`` (Van Loan 1978).

    ::

        M = [[−F, G Q Gᵀ], [0, Fᵀ]] dt,   exp(M) = [[·, Φ⁻¹ Q_d], [0, Φᵀ]],
        Φ = exp(F dt) = (lower-right block)ᵀ,   Q_d = Φ (upper-right block), symmetrised.

    Parameters
    ----------
    F : (n, n) continuous system matrix.
    GQGt : (n, n) continuous process-noise spectral density ``G Q Gᵀ``.
    dt : float, step, s.

    Returns
    -------
    Phi : (n, n) transition matrix.
    Qd : (n, n) discrete process-noise covariance.
    """
    n = F.shape[0]
    M = np.zeros((2 * n, 2 * n))
    for i in range(n):
        for j in range(n):
            M[i, j] = -F[i, j] * dt
            M[i, n + j] = GQGt[i, j] * dt
            M[n + i, n + j] = F[j, i] * dt
    E = expm(M)
    Phi = np.ascontiguousarray(E[n:, n:].T)
    Qd = Phi @ np.ascontiguousarray(E[:n, n:])
    return Phi, 0.5 * (Qd + Qd.T)


# ---------------------------------------------------------------------------------------------------------------
# Strapdown step

#: where the velocity increment is resolved: attitude at the start of the interval (the increments already carry
#: the rotation compensation), at mid interval (first-order rotation compensation), or at its end (the
#: thesis / pyshoe first-order ZUPT mechanization)
ATT_START = 0
ATT_MID = 1
ATT_END = 2


@njit(cache=True)
def strapdown_step_local(q, v, p, dth, dv, h, g, att, q_out, v_out, p_out):
    """One strapdown step in a fixed local-level NED frame (no Earth rate; gravity ``(0, 0, g)``).

    ::

        q⁺ = q ⊗ exp(Δθ) (normalised),   Δvⁿ = C(q_a) Δv,   v⁺ = v + Δvⁿ + (0, 0, g) h,
        p⁺ = p + (v + v⁺) h / 2

    with ``q_a`` the attitude of ``att``: ``ATT_START`` (q), ``ATT_MID`` (q ⊗ exp(Δθ/2)) or ``ATT_END`` (q⁺)
    (Savage 2000, *Strapdown Analytics*, §7; Groves 2013, §5.5).  Δθ and Δv may carry coning / sculling
    corrections (:func:`imunav.ins._strapdown_kernels.increments`).

    Parameters
    ----------
    q, v, p : (4,), (3,), (3,) state at the start of the interval.
    dth, dv : (3,) angle [rad] and velocity [m/s] increments in the body frame.
    h : float, interval, s.
    g : float, gravity magnitude, m/s².
    att : int, ``ATT_START``, ``ATT_MID`` or ``ATT_END``.
    q_out, v_out, p_out : (4,), (3,), (3,) receive the state at the end (may not alias the inputs).

    Returns
    -------
    dvn : (3,) the nav-frame velocity increment ``C(q_a) Δv`` (the error-state Jacobian uses it).
    """
    q_new = quat_normalize(qmul_1(q, qexp_1(dth)))
    if att == ATT_END:
        dvn = qrot_1(q_new, dv)
    elif att == ATT_MID:
        half = np.empty(3)
        for j in range(3):
            half[j] = 0.5 * dth[j]
        dvn = qrot_1(qmul_1(q, qexp_1(half)), dv)
    else:
        dvn = qrot_1(q, dv)
    for j in range(4):
        q_out[j] = q_new[j]
    for j in range(3):
        v_out[j] = v[j] + dvn[j]
    v_out[2] += g * h
    for j in range(3):
        p_out[j] = p[j] + 0.5 * (v[j] + v_out[j]) * h
    return dvn


@njit(cache=True)
def strapdown_step_ned(q, v, lla, dth, dv, h, omega_e, att, q_out, v_out, lla_out):
    """One NED strapdown step with Earth rate, transport rate, Coriolis and WGS84 normal gravity.

    ::

        ω_inⁿ = ω_ieⁿ + ω_enⁿ,   q⁺ = exp(−ω_inⁿ h) ⊗ q ⊗ exp(Δθ)        (Groves 2013, eq. 5.44 form)
        v⁺ = v + exp(−ω_inⁿ h/2) C(q_a) Δv + (gⁿ − (2 ω_ieⁿ + ω_enⁿ) × v) h
        φ⁺ = φ + v̄_N h / (R_N + h_e),  λ⁺ = λ + v̄_E h / ((R_E + h_e) cos φ),  h_e⁺ = h_e − v̄_D h

    with v̄ the mean velocity, radii and gravity from :func:`imunav.earth.radii_gravity_1` at the start of the
    interval, and ``q_a`` = q (``ATT_START``) or q ⊗ exp(Δθ/2) (``ATT_MID``).

    Parameters
    ----------
    q, v : (4,), (3,) attitude ``q_nb`` and NED velocity at the start.
    lla : (3,) latitude [rad], longitude [rad], ellipsoidal height [m] at the start.
    dth, dv : (3,) body-frame increments.
    h : float, interval, s.
    omega_e : float, Earth rotation rate, rad/s.
    att : int, ``ATT_START`` or ``ATT_MID``.
    q_out, v_out, lla_out : receive the state at the end (may not alias the inputs).

    Returns
    -------
    dvn : (3,) nav-frame specific-force increment (before gravity and Coriolis).
    """
    lat = lla[0]
    alt = lla[2]
    RN, RE, g = radii_gravity_1(lat, alt)
    w_ie0 = omega_e * math.cos(lat)
    w_ie2 = -omega_e * math.sin(lat)
    w_en0 = v[1] / (RE + alt)
    w_en1 = -v[0] / (RN + alt)
    w_en2 = -v[1] * math.tan(lat) / (RE + alt)
    w_in = np.empty(3)
    w_in[0] = w_ie0 + w_en0
    w_in[1] = w_en1
    w_in[2] = w_ie2 + w_en2
    half = np.empty(3)
    for j in range(3):
        half[j] = 0.0 if att == ATT_START else 0.5 * dth[j]
    qm = qmul_1(q, qexp_1(half))
    for j in range(3):
        half[j] = -0.5 * w_in[j] * h
    qm = qmul_1(qexp_1(half), qm)
    dvn = qrot_1(qm, dv)
    c0 = 2.0 * w_ie0 + w_en0
    c1 = w_en1
    c2 = 2.0 * w_ie2 + w_en2
    cx = c1 * v[2] - c2 * v[1]
    cy = c2 * v[0] - c0 * v[2]
    cz = c0 * v[1] - c1 * v[0]
    v_out[0] = v[0] + dvn[0] - cx * h
    v_out[1] = v[1] + dvn[1] - cy * h
    v_out[2] = v[2] + dvn[2] + (g - cz) * h
    for j in range(3):
        half[j] = -w_in[j] * h
    q_new = quat_normalize(qmul_1(qexp_1(half), qmul_1(q, qexp_1(dth))))
    for j in range(4):
        q_out[j] = q_new[j]
    vm0 = 0.5 * (v[0] + v_out[0])
    vm1 = 0.5 * (v[1] + v_out[1])
    vm2 = 0.5 * (v[2] + v_out[2])
    lla_out[2] = alt - vm2 * h
    lla_out[0] = lat + vm0 / (RN + alt) * h
    lla_out[1] = lla[1] + vm1 / ((RE + alt) * math.cos(lat)) * h
    return dvn


# ---------------------------------------------------------------------------------------------------------------
# Allocation-free 3 × 3 forms (vector filters whose state is a 3-vector, e.g. the gravity-vector filters)


@njit(cache=True)
def inv3(A, out):
    """``out = A⁻¹`` for a 3 × 3 matrix by the adjugate, ``A⁻¹ = adj(A) / det A`` (no allocation).

    Parameters
    ----------
    A : (3, 3) float64 array, non-singular.
    out : (3, 3) float64 array that receives the inverse (distinct from A).

    Returns
    -------
    None
    """
    a00, a01, a02 = A[0, 0], A[0, 1], A[0, 2]
    a10, a11, a12 = A[1, 0], A[1, 1], A[1, 2]
    a20, a21, a22 = A[2, 0], A[2, 1], A[2, 2]
    c00 = a11 * a22 - a12 * a21
    c01 = a02 * a21 - a01 * a22
    c02 = a01 * a12 - a02 * a11
    c10 = a12 * a20 - a10 * a22
    c11 = a00 * a22 - a02 * a20
    c12 = a02 * a10 - a00 * a12
    c20 = a10 * a21 - a11 * a20
    c21 = a01 * a20 - a00 * a21
    c22 = a00 * a11 - a01 * a10
    d = 1.0 / (a00 * c00 + a01 * c10 + a02 * c20)
    out[0, 0], out[0, 1], out[0, 2] = c00 * d, c01 * d, c02 * d
    out[1, 0], out[1, 1], out[1, 2] = c10 * d, c11 * d, c12 * d
    out[2, 0], out[2, 1], out[2, 2] = c20 * d, c21 * d, c22 * d


@njit(cache=True)
def mm3(A, B, C):
    """``C = A B`` for 3 × 3 matrices (C distinct from A and B).

    Parameters
    ----------
    A, B : numpy.ndarray, shape (3, 3)
        The factors, float64.
    C : numpy.ndarray, shape (3, 3)
        Receives the product, float64.

    Returns
    -------
    None
    """
    for i in range(3):
        for j in range(3):
            C[i, j] = A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j]


@njit(cache=True)
def mmt3(A, B, C):
    """``C = A Bᵀ`` for 3 × 3 matrices (C distinct from A and B).

    Parameters
    ----------
    A, B : numpy.ndarray, shape (3, 3)
        The factors, float64.
    C : numpy.ndarray, shape (3, 3)
        Receives the product, float64.

    Returns
    -------
    None
    """
    for i in range(3):
        for j in range(3):
            C[i, j] = A[i, 0] * B[j, 0] + A[i, 1] * B[j, 1] + A[i, 2] * B[j, 2]


@njit(cache=True)
def joseph_cov3(P_prior, KH, K, r0, r1, r2, P_out, A, T):
    """Joseph-form covariance of a 3-state filter with diagonal R, allocation-free:

    ``P = (I − K H) P⁻ (I − K H)ᵀ + K diag(r) Kᵀ`` (Bucy & Joseph 1968), symmetrised.

    Parameters
    ----------
    P_prior : (3, 3) prior covariance P⁻.
    KH : (3, 3) the product K H (the caller forms it: ``g K`` for ``H = g I``).
    K : (3, 3) gain.
    r0, r1, r2 : float, diagonal of R.
    P_out : (3, 3) receives P (may be P_prior only if A and T are distinct from both).
    A, T : (3, 3) workspace.

    Returns
    -------
    None
    """
    for i in range(3):
        for j in range(3):
            A[i, j] = (1.0 if i == j else 0.0) - KH[i, j]
    mm3(A, P_prior, T)
    for i in range(3):
        for j in range(3):
            P_out[i, j] = (T[i, 0] * A[j, 0] + T[i, 1] * A[j, 1] + T[i, 2] * A[j, 2]
                           + K[i, 0] * r0 * K[j, 0] + K[i, 1] * r1 * K[j, 1] + K[i, 2] * r2 * K[j, 2])
    for i in range(3):
        for j in range(i + 1, 3):
            v = 0.5 * (P_out[i, j] + P_out[j, i])
            P_out[i, j] = v
            P_out[j, i] = v
