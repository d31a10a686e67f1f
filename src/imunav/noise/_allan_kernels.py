"""numba kernels of the Allan family (private).

All kernels work on a phase series ``x`` (float64, contiguous), the running
integral of the rate: ``x[k] = dt * sum(y[:k])``.  Every statistic of the
family is a sum of squared finite differences of ``x`` at lags that are
multiples of the cluster size ``m``; one kernel call evaluates those sums for
all requested ``m`` in a single pass over the data, split into blocks that the
threads run in parallel (``prange``) and whose partial sums are added pairwise
afterwards (so 1e8-term sums keep their precision).

Blocks are the outer loop and cluster sizes the inner loop: the block of
``x`` starting at ``i0`` stays in cache while every ``m`` reads it, so the
memory traffic is far below ``len(m)`` full passes.  The sum kernels use
``fastmath`` so the squared-difference reductions vectorize (summation order
changes rounding at the 1e-15 level only).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

#: samples per parallel work block
BLOCK = 4096


@njit(cache=True)
def phase_accumulate(y, scale, offset, out, state):  # pragma: no cover - numba
    """Compensated (Kahan) running sum ``out[k+1] = out[k] + (y[k]-offset)*scale``.

    ``out`` has ``len(y)`` entries and receives the phase *after* each
    sample; ``state = [sum, compensation]`` carries the sum between chunks so
    that a record read in chunks gives the same phase as one read at once.
    Non-finite samples contribute zero (their positions are handled by the
    caller as segment boundaries).
    """
    s = state[0]
    c = state[1]
    for k in range(y.size):
        v = y[k]
        if np.isfinite(v):
            inc = (v - offset) * scale - c
            t = s + inc
            c = (t - s) - inc
            s = t
        out[k] = s
    state[0] = s
    state[1] = c


@njit(parallel=True, cache=True, fastmath=True)
def diff_sums(x, ms, order, overlapping):  # pragma: no cover - numba
    """Sums of squared ``order``-th differences at lag m, for every m.

    order 2: ``x[i+2m] - 2x[i+m] + x[i]`` (Allan);
    order 3: ``x[i+3m] - 3x[i+2m] + 3x[i+m] - x[i]`` (Hadamard).
    ``overlapping``: i runs over every sample (stride 1), else over multiples
    of m (stride m, the classic non-overlapping estimator).
    Returns the sums (len(ms),); the term counts are computed by the caller.
    """
    n = x.size
    nt = ms.size
    mmin = ms.min()
    ni = n - order * mmin
    if ni <= 0:
        return np.zeros(nt)
    nb = (ni + BLOCK - 1) // BLOCK
    part = np.zeros((nb, nt))
    for b in prange(nb):
        i0 = b * BLOCK
        i1 = min(i0 + BLOCK, ni)
        for j in range(nt):
            m = ms[j]
            iend = min(i1, n - order * m)
            if iend <= i0:
                continue
            s = 0.0
            if overlapping:
                # unit stride over slices indexed by the loop variable itself: no
                # negative-index wraparound checks, so LLVM vectorizes the reduction
                L = iend - i0
                c0 = x[i0 : i0 + L]
                c1 = x[i0 + m : i0 + m + L]
                c2 = x[i0 + 2 * m : i0 + 2 * m + L]
                if order == 2:
                    for i in range(L):
                        v = c2[i] - 2.0 * c1[i] + c0[i]
                        s += v * v
                else:
                    c3 = x[i0 + 3 * m : i0 + 3 * m + L]
                    for i in range(L):
                        v = c3[i] - 3.0 * c2[i] + 3.0 * c1[i] - c0[i]
                        s += v * v
            else:
                start = ((i0 + m - 1) // m) * m
                if order == 2:
                    for i in range(start, iend, m):
                        v = x[i + 2 * m] - 2.0 * x[i + m] + x[i]
                        s += v * v
                else:
                    for i in range(start, iend, m):
                        v = x[i + 3 * m] - 3.0 * x[i + 2 * m] + 3.0 * x[i + m] - x[i]
                        s += v * v
            part[b, j] = s
    return _column_sums(part)


@njit(cache=True)
def _pairwise_sum(a):  # pragma: no cover - numba
    n = a.size
    while n > 1:
        h = n // 2
        for i in range(h):
            a[i] = a[2 * i] + a[2 * i + 1]
        if n % 2 == 1:
            a[h] = a[n - 1]
            n = h + 1
        else:
            n = h
    return a[0] if a.size > 0 else 0.0


@njit(cache=True)
def _column_sums(part):  # pragma: no cover - numba
    # pairwise-ish reduction over blocks of each column (each partial is already O(BLOCK) terms)
    out = np.zeros(part.shape[1])
    for j in range(part.shape[1]):
        out[j] = _pairwise_sum(part[:, j].copy())
    return out


@njit(parallel=True, cache=True, fastmath=True)
def mod_sum(x, m):  # pragma: no cover - numba
    """Modified-Allan sum for one m: sum_j (sum_{i=j}^{j+m-1} d_i)^2,
    d_i = x[i+2m] - 2x[i+m] + x[i], j = 0 .. n-3m.

    The inner window sum slides (one add, one subtract per step) inside a
    block and is recomputed from scratch at each block start, so rounding
    cannot accumulate over the record.  Blocks are at least 4m long so the
    restarts cost O(n/4) in total.
    """
    n = x.size
    nj = n - 3 * m + 1
    if nj <= 0:
        return 0.0
    blk = max(BLOCK, 4 * m)
    nb = (nj + blk - 1) // blk
    part = np.zeros(nb)
    for b in prange(nb):
        j0 = b * blk
        j1 = min(j0 + blk, nj)
        s = 0.0
        for i in range(j0, j0 + m):
            s += x[i + 2 * m] - 2.0 * x[i + m] + x[i]
        acc = 0.0
        for j in range(j0, j1):
            acc += s * s
            if j + 1 < j1:
                ia = j + m
                s += (x[ia + 2 * m] - 2.0 * x[ia + m] + x[ia]) - (x[j + 2 * m] - 2.0 * x[j + m] + x[j])
        part[b] = acc
    return _pairwise_sum(part)


@njit(cache=True)
def _refl(x, k, n):  # pragma: no cover - numba
    if k < 0:
        return 2.0 * x[0] - x[-k]
    if k > n - 1:
        return 2.0 * x[n - 1] - x[2 * (n - 1) - k]
    return x[k]


@njit(parallel=True, cache=True, fastmath=True)
def tot_sums(x, ms):  # pragma: no cover - numba
    """Total-variance sums: sum_{i=1}^{n-2} (x*[i-m] - 2x[i] + x*[i+m])^2 with
    x* the phase extended by odd reflection about both end points
    (NIST SP 1065 eq. 25)."""
    n = x.size
    nt = ms.size
    ni = n - 2
    if ni <= 0:
        return np.zeros(nt)
    nb = (ni + BLOCK - 1) // BLOCK
    part = np.zeros((nb, nt))
    for b in prange(nb):
        i0 = 1 + b * BLOCK
        i1 = min(i0 + BLOCK, n - 1)
        for j in range(nt):
            m = ms[j]
            s = 0.0
            for i in range(i0, i1):
                if i - m >= 0 and i + m <= n - 1:
                    v = x[i - m] - 2.0 * x[i] + x[i + m]
                else:
                    v = _refl(x, i - m, n) - 2.0 * x[i] + _refl(x, i + m, n)
                s += v * v
            part[b, j] = s
    return _column_sums(part)


@njit(cache=True)
def _gac1(code, h, T):  # pragma: no cover - numba
    # generalized autocovariance of the phase per unit coefficient (see fit.py)
    a = abs(h)
    if code == 0:  # Q: white phase
        return 1.0 if a < 1e-12 else 0.0
    if code == 1:  # N: white rate
        return -0.5 * a
    if code == 2:  # B: flicker rate
        return (h * h * np.log(a)) / (2.0 * np.pi) if a > 0 else 0.0
    if code == 3:  # K: random-walk rate
        return a * a * a / 12.0
    if code == 4:  # Gauss-Markov rate
        u = a / T
        return -(T * T) * (u + np.expm1(-u))
    return 0.0


@njit(parallel=True, cache=True)
def oavar_cov(tau, m, n_phase, codes, Ts, theta, dt, max_ratio, max_lags):  # pragma: no cover - numba
    """Covariance of overlapping AVAR estimates for a model (sum of terms)."""
    nt = tau.size
    cov = np.zeros((nt, nt))
    a = np.array([1.0, -2.0, 1.0])
    for i in prange(nt):
        for j in range(i, nt):
            m1 = m[i]
            m2 = m[j]
            if max(m1, m2) > max_ratio * min(m1, m2):
                continue
            n1 = n_phase - 2 * m1
            n2 = n_phase - 2 * m2
            if n1 <= 0 or n2 <= 0:
                continue
            w = 4 * max(m1, m2)
            lo = -2 * m2 - w
            hi = 2 * m1 + w
            span = hi - lo + 1
            step = max(1, (span + max_lags - 1) // max_lags)
            acc = 0.0
            h = lo
            while h <= hi:
                cnt = min(n1, n2 - h) - max(0, -h)
                if cnt > 0:
                    c12 = 0.0
                    for t in range(codes.size):
                        if theta[t] <= 0.0:
                            continue
                        g = 0.0
                        for k in range(3):
                            for l in range(3):
                                g += a[k] * a[l] * _gac1(codes[t], (h + l * m2 - k * m1) * dt, Ts[t])
                        c12 += theta[t] * g
                    acc += cnt * c12 * c12
                h += step
            s = 2.0 * step * acc / (4.0 * tau[i] ** 2 * tau[j] ** 2 * n1 * n2)
            cov[i, j] = s
            cov[j, i] = s
    return cov


@njit(cache=True)
def lag1_acf(z):  # pragma: no cover - numba
    """Lag-1 autocorrelation of z about its mean (serial: tiny inputs)."""
    n = z.size
    mu = 0.0
    for i in range(n):
        mu += z[i]
    mu /= n
    num = 0.0
    den = 0.0
    for i in range(n):
        d = z[i] - mu
        den += d * d
        if i + 1 < n:
            num += d * (z[i + 1] - mu)
    return num / den if den > 0 else 0.0


@njit(cache=True)
def detrend_quadratic(z):  # pragma: no cover - numba
    """z minus its least-squares quadratic in the (centred, scaled) index."""
    n = z.size
    c = (n - 1) / 2.0
    s = max(c, 1.0)
    A = np.zeros((3, 3))
    b = np.zeros(3)
    for i in range(n):
        t = (i - c) / s
        p1, p2 = t, t * t
        A[0, 0] += 1.0
        A[0, 1] += p1
        A[0, 2] += p2
        A[1, 2] += p1 * p2
        A[2, 2] += p2 * p2
        b[0] += z[i]
        b[1] += p1 * z[i]
        b[2] += p2 * z[i]
    A[1, 0] = A[0, 1]
    A[1, 1] = A[0, 2]
    A[2, 0] = A[0, 2]
    A[2, 1] = A[1, 2]
    coef = np.linalg.solve(A, b)
    out = np.empty(n)
    for i in range(n):
        t = (i - c) / s
        out[i] = z[i] - (coef[0] + coef[1] * t + coef[2] * t * t)
    return out
