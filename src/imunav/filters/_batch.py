"""Batched linear Kalman filtering (private).

The per-step loop runs in Python over time while every operation is
vectorised over a leading batch dimension of independent runs (Monte Carlo):
for the small state sizes of these filters this is faster than one numba
run per realisation and needs no compilation.

Rejecting channel i is done exactly by giving it an infinite variance: its
row of H, its entries of R and of the innovation are zeroed and S gets a 1 on
the diagonal there, so the gain column is zero and ``x``/``P`` are those of an
update with the accepted channels only.
"""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import NDArray

from imunav.filters._common import inv_sqrt_spd, symmetrize

Array = NDArray[np.float64]

MODE_NONE = 0  # optimal filter, every channel used
MODE_GATE = 1  # per-channel normalised-innovation gate |ν̃_i| < m (Akgün 2002, eq. 4.17)
MODE_ISOLATE = 2  # NIS χ² test + sequential isolation of the worst channel (w-test)
MODE_HUBER = 3  # Huber M-estimation of the measurement channels by IRLS
MODE_NIS = 4  # vector χ² gate: the whole measurement is rejected when its NIS fails the test


def masked_update(x: Array, P: Array, nu: Array, H: Array, R: Array, acc: Array) -> tuple[Array, Array, Array]:
    """Joseph update of a batch using only channels with ``acc`` (B, m) True.

    R may be (m, m) or (B, m, m).  Returns (x, P, K).
    """
    B, m = acc.shape
    n = x.shape[1]
    a = acc.astype(np.float64)
    Ha = H[None, :, :] * a[:, :, None]  # (B, m, n)
    Rb = np.broadcast_to(R, (B, m, m))
    Ra = Rb * a[:, :, None] * a[:, None, :]
    nua = nu * a
    PHt = P @ np.swapaxes(Ha, 1, 2)  # (B, n, m)
    Sa = Ha @ PHt + Ra + np.eye(m)[None] * (1.0 - a)[:, None, :]
    K = np.swapaxes(np.linalg.solve(Sa, np.swapaxes(PHt, 1, 2)), 1, 2)  # S symmetric
    x = x + np.einsum("bij,bj->bi", K, nua)
    IKH = np.eye(n)[None] - K @ Ha
    P = symmetrize(IKH @ P @ np.swapaxes(IKH, 1, 2) + K @ Ra @ np.swapaxes(K, 1, 2))
    return x, P, K


def isolate_batch(nu: Array, S: Array, thr: Array) -> Array:
    """Accepted mask (B, m) by χ² test and sequential w-test isolation (see robust.isolate_channels)."""
    B, m = nu.shape
    acc = np.ones((B, m), dtype=bool)
    for _ in range(m):
        a = acc.astype(np.float64)
        Sa = S * a[:, :, None] * a[:, None, :] + np.eye(m)[None] * (1.0 - a)[:, None, :]
        Si = np.linalg.inv(Sa)
        g = np.einsum("bij,bj->bi", Si, nu * a)
        q = np.einsum("bi,bi->b", nu * a, g)
        cnt = acc.sum(axis=1)
        fail = (cnt > 0) & (q > thr[np.maximum(cnt - 1, 0)])
        if not fail.any():
            break
        wt = np.abs(g) / np.sqrt(np.einsum("bii->bi", Si))
        wt[~acc] = -1.0
        worst = np.argmax(wt, axis=1)
        rows = np.flatnonzero(fail)
        acc[rows, worst[rows]] = False
    return acc


def huber_batch(x: Array, P: Array, z: Array, H: Array, R: Array, c: float, valid: Array,
                max_iter: int = 50, tol: float = 1e-10) -> tuple[Array, Array, Array]:
    """Huber IRLS update on the measurement channels for a batch.

    Minimises ``|x − x⁻|²_{P⁻⁻¹} + Σ ρ_c(r_i)``, ``r = Lr⁻¹ (z − H x)``
    (``R = Lr Lrᵀ``).  Each iteration is a Kalman update with
    ``R_w = Lr diag(1/w) Lrᵀ``, which is the IRLS normal equation
    ``(MᵀΨM) x = MᵀΨ y`` of the whitened stacked regression.  Channels with
    ``valid`` False are not used.  Returns (x, P, weights (B, m), iterations).
    """
    B, m = z.shape
    Lr = np.linalg.cholesky(R)
    Lri = np.linalg.inv(Lr)
    xe = x.copy()
    w = np.ones((B, m))
    it = 0
    for it in range(1, max_iter + 1):  # noqa: B007 (the count is returned)
        r = np.einsum("ij,bj->bi", Lri, z - xe @ H.T)
        a = np.abs(r)
        w = np.where(a <= c, 1.0, c / np.maximum(a, 1e-300))
        Rw = np.einsum("ij,bj,kj->bik", Lr, 1.0 / w, Lr)
        xn, Pn, _ = masked_update(x, P, z - x @ H.T, H, Rw, valid)
        d = np.max(np.abs(xn - xe)) if B else 0.0
        xe = xn
        if d < tol:
            break
    r = np.einsum("ij,bj->bi", Lri, z - xe @ H.T)
    a = np.abs(r)
    w = np.where(a <= c, 1.0, c / np.maximum(a, 1e-300))
    Rw = np.einsum("ij,bj,kj->bik", Lr, 1.0 / w, Lr)
    xn, Pn, _ = masked_update(x, P, z - x @ H.T, H, Rw, valid)
    return xn, Pn, np.where(valid, w, 0.0), it


def batch_filter(
    x0: Array,
    P0: Array,
    F: Array,
    Qn: Array,
    H: Array,
    R: Array,
    z: Array,
    mode: int = MODE_NONE,
    gate_m: float = 2.0,
    iso_thr: Array | None = None,
    huber_c: float = 1.345,
    store_full: bool = False,
) -> dict[str, Array]:
    """Run B filters over z (B, N, m) (a NaN row = no measurement at that step).

    x0 (n,) or (B, n), P0 (n, n).  Returns a dict with x (B, N, n), P_diag
    (B, N, n), innovation and normalised innovation (B, N, m) (NaN without
    measurement), weights (B, N, m) (1 used, 0 rejected, Huber weight), and
    with ``store_full`` also x_pred, P_pred, P (B, N, n, n) and S (B, N, m, m).
    """
    B, N, m = z.shape
    n = P0.shape[0]
    x = np.broadcast_to(np.asarray(x0, dtype=np.float64), (B, n)).copy()
    P = np.broadcast_to(P0, (B, n, n)).copy()
    out = {
        "x": np.empty((B, N, n)),
        "P_diag": np.empty((B, N, n)),
        "innovation": np.full((B, N, m), np.nan),
        "normalized": np.full((B, N, m), np.nan),
        "weights": np.zeros((B, N, m)),
    }
    if store_full:
        out.update(x_pred=np.empty((B, N, n)), P_pred=np.empty((B, N, n, n)), P=np.empty((B, N, n, n)),
                   S=np.full((B, N, m, m), np.nan))
    Ft = F.T
    if mode == MODE_NONE and not store_full and not np.isnan(z[:, :, 0]).any():
        return _batch_plain(x, P0, F, Qn, H, R, z, out)
    for k in range(N):
        x = x @ Ft
        P = symmetrize(F @ P @ Ft + Qn)
        if store_full:
            out["x_pred"][:, k] = x
            out["P_pred"][:, k] = P
        zk = z[:, k]
        has = ~np.isnan(zk[:, 0])
        if has.any():
            zz = np.where(has[:, None], zk, 0.0)
            nu = zz - x @ H.T
            S = symmetrize(H @ P @ H.T + R)
            nn = np.einsum("bij,bj->bi", inv_sqrt_spd(S), nu)
            valid = np.broadcast_to(has[:, None], (B, m))
            if mode == MODE_NONE:
                acc = valid.copy()
            elif mode == MODE_GATE:
                acc = valid & (np.abs(nn) < gate_m)
            elif mode == MODE_ISOLATE:
                acc = valid & isolate_batch(nu, S, iso_thr)
            elif mode == MODE_NIS:
                q = np.einsum("bi,bi->b", nn, nn)
                acc = valid & (q <= iso_thr[m - 1])[:, None]
            elif mode == MODE_HUBER:
                acc = None
            else:
                raise ValueError(f"unknown robust mode {mode}")
            if acc is None:
                x, P, w, _ = huber_batch(x, P, zz, H, R, huber_c, valid, 30, 1e-9)
            else:
                x, P, _ = masked_update(x, P, nu, H, R, acc)
                w = acc.astype(np.float64)
            out["innovation"][has, k] = nu[has]
            out["normalized"][has, k] = nn[has]
            out["weights"][:, k] = w
            if store_full:
                out["S"][has, k] = S[has]
        out["x"][:, k] = x
        out["P_diag"][:, k] = np.einsum("bii->bi", P)
        if store_full:
            out["P"][:, k] = P
    return out


def _batch_plain(x: Array, P0: Array, F: Array, Qn: Array, H: Array, R: Array, z: Array, out: dict) -> dict:
    """Optimal filter on complete data: P and K are the same for every run (computed once per step)."""
    n = P0.shape[0]
    P = P0.copy()
    I = np.eye(n)
    for k in range(z.shape[1]):
        x = x @ F.T
        P = symmetrize(F @ P @ F.T + Qn)
        S = symmetrize(H @ P @ H.T + R)
        K = np.linalg.solve(S, H @ P).T
        nu = z[:, k] - x @ H.T
        x = x + nu @ K.T
        A = I - K @ H
        P = symmetrize(A @ P @ A.T + K @ R @ K.T)
        w, V = np.linalg.eigh(S)
        out["innovation"][:, k] = nu
        out["normalized"][:, k] = nu @ ((V / np.sqrt(w)) @ V.T).T
        out["x"][:, k] = x
        out["P_diag"][:, k] = np.diag(P)
    out["weights"][:] = 1.0
    return out


def window_stats_batch(nv: Array, M: int, Pinv: Array, L: Array) -> tuple[Array, Array, Array]:
    """Sliding-window Alg. 1 / Alg. 2 / Alg. 3 statistics for nv (..., N, s); NaN for k < M − 1."""

    *lead, N, s = nv.shape
    W = sliding_window_view(nv, M, axis=-2)  # (..., N-M+1, s, M)
    mu = W.mean(axis=-1, keepdims=True)
    D = W - mu
    A = np.einsum("...im,...jm->...ij", D, D)
    C = np.linalg.cholesky(Pinv).T  # P⁻¹ = Cᵀ C, eig(A P⁻¹) = eig(C A Cᵀ)
    lam1 = np.linalg.eigvalsh(C @ A @ C.T)[..., -1]
    Lb = np.broadcast_to(L, A.shape[:-1])
    lam2 = (L @ Pinv @ L) / np.einsum("...i,...i->...", Lb, np.linalg.solve(A, Lb[..., None])[..., 0])
    sq = np.einsum("...im,...im->...", W, W)
    pad = np.full((*lead, M - 1), np.nan)
    return (np.concatenate([pad, lam1], axis=-1), np.concatenate([pad, lam2], axis=-1),
            np.concatenate([pad, sq], axis=-1))
