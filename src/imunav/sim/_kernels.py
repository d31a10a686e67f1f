"""numba kernels of the virtual IMU error model (private).

Random numbers: every stream (one per sensor, process, axis and component)
is a xoshiro256++ generator (Blackman & Vigna, "Scrambled linear
pseudorandom number generators", ACM TOMS 47(4), 2021) whose 256-bit state
comes from ``numpy.random.SeedSequence``; standard normals come from a
256-layer ziggurat (Marsaglia & Tsang, J. Stat. Softw. 5(8), 2000) that
takes the layer and the sign from the low bits and the abscissa from the
top 53 bits of the same 64-bit word (Doornik 2005's remedy for the
original's correlation between layer and value), with Marsaglia's exact
tail method beyond r.  Drawing inside the kernels avoids one temporary
array per stream and lets a triad be simulated in a single pass.

All kernels release the GIL (``nogil=True``) so the public wrappers run the
gyro and accelerometer triads in parallel threads.

Time steps: with ``dt_const > 0`` the sampling is uniform with that step;
otherwise ``dt[k] = t[k] - t[k-1]`` per sample (``dt[0] = t[1] - t[0]``).
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import njit

# --- ziggurat tables (256 layers of equal area v under f(x) = exp(-x^2/2)) ---
_ZIG_R = 3.6541528853610088  # start of the tail; makes the top layer close to 1e-15


def _ziggurat_tables() -> tuple[np.ndarray, np.ndarray]:
    r = _ZIG_R
    f = lambda x: math.exp(-0.5 * x * x)  # noqa: E731
    v = r * f(r) + math.sqrt(math.pi / 2.0) * math.erfc(r / math.sqrt(2.0))  # layer area
    x = np.zeros(257)
    x[0] = v / f(r)  # base layer: rectangle of area v including the tail
    x[1] = r
    for i in range(1, 255):
        x[i + 1] = math.sqrt(-2.0 * math.log(v / x[i] + f(x[i])))
    x[256] = 0.0
    fx = np.exp(-0.5 * x * x)
    return x, fx


ZIG_X, ZIG_F = _ziggurat_tables()
_TWO_M53 = 1.0 / 9007199254740992.0  # 2^-53
ZIG_XS = ZIG_X * _TWO_M53  # layer widths per unit of the 53-bit integer (exact: power-of-2 scaling)
_U8 = np.uint64(255)
_U1 = np.uint64(1)


@njit(cache=True, nogil=True, inline="always")
def _rotl(x, k):  # pragma: no cover - compiled
    return (x << np.uint64(k)) | (x >> np.uint64(64 - k))


@njit(cache=True, nogil=True, inline="always")
def next_u64(s):  # pragma: no cover - compiled
    """xoshiro256++ step on the state s (4 uint64), returns 64 random bits."""
    s0 = s[0]
    s1 = s[1]
    s2 = s[2]
    s3 = s[3]
    result = _rotl(s0 + s3, 23) + s0
    t = s1 << np.uint64(17)
    s2 ^= s0
    s3 ^= s1
    s1 ^= s2
    s0 ^= s3
    s2 ^= t
    s3 = _rotl(s3, 45)
    s[0] = s0
    s[1] = s1
    s[2] = s2
    s[3] = s3
    return result


@njit(cache=True, nogil=True, inline="always")
def next_double(s):  # pragma: no cover - compiled
    """Uniform in (0, 1] (never 0, safe for log)."""
    return (float(next_u64(s) >> np.uint64(11)) + 1.0) * _TWO_M53


@njit(cache=True, nogil=True, inline="always")
def next_normal(s):  # pragma: no cover - compiled
    """Standard normal deviate (256-layer ziggurat)."""
    while True:
        u = next_u64(s)
        i = np.int64(u & _U8)
        neg = ((u >> np.uint64(8)) & _U1) == _U1
        x = float(u >> np.uint64(11)) * ZIG_XS[i]
        if x < ZIG_X[i + 1]:  # inside the layer's core rectangle: accept (~99 %)
            return -x if neg else x
        if i == 0:  # tail beyond r (Marsaglia 1964)
            while True:
                xt = -math.log(next_double(s)) / _ZIG_R
                yt = -math.log(next_double(s))
                if yt + yt > xt * xt:
                    break
            x = _ZIG_R + xt
            return -x if neg else x
        # wedge between f(X[i]) and f(X[i+1])
        y = ZIG_F[i] + next_double(s) * (ZIG_F[i + 1] - ZIG_F[i])
        if y < math.exp(-0.5 * x * x):
            return -x if neg else x


@njit(cache=True, nogil=True)
def fill_normal(s, out):  # pragma: no cover - compiled
    """Fill ``out`` (1-D) with standard normals from the stream state s."""
    for k in range(out.shape[0]):
        out[k] = next_normal(s)


#: Error parameters of one triad for :func:`simulate_triad` (SI; arrays are float64 and contiguous):
#: ``use_g`` apply the g-sensitivity ``g_mat`` (3, 3) to the specific force; ``t_mat`` (3, 3) scale factor and
#: misalignment; ``bias`` (3,); ``bias_poly``, ``scale_poly`` (P, 3) temperature polynomials; ``nd`` (3,) white-noise
#: density; ``gm_sig``, ``gm_tau`` (3, M) Gauss-Markov components; ``k_rw`` (3,) random walk; ``ramp`` (3,) rate
#: ramp; ``q`` (3,) quantization LSB; ``integrated`` carry the quantization residue; ``full_scale`` (3,) (0: none).
TriadParams = namedtuple(
    "TriadParams",
    ["use_g", "t_mat", "g_mat", "bias", "bias_poly", "scale_poly", "nd", "gm_sig", "gm_tau", "k_rw", "ramp", "q",
     "integrated", "full_scale"],
)


@njit(cache=True, nogil=True)
def simulate_triad(t, dt_const, x, f, dtemp, prm, states, out, truth, keep_truth):  # pragma: no cover - compiled
    """Measurement model of one triad in a single pass over the samples (``prm``: :data:`TriadParams`).

    For every sample k (Günhan 2014, eqs. 2 and 4, full 3x3
    g-sensitivity, temperature polynomials around the reference):

        y_k = (T + diag(s(dT_k))) x_k + b + b(dT_k) + G f_k + e_k
        b(dT)_i = sum_p bias_poly[p, i] dT^(p+1),  s(dT)_i = sum_p scale_poly[p, i] dT^(p+1)
        e_k = sum_j gm_j,k + rw_k + R (t_k - t_0) + n_k

    * Gauss-Markov components, exact discretisation (Brown & Hwang 2012):
      gm_k = phi gm_(k-1) + sigma sqrt(1 - phi^2) w_k, phi = exp(-dt / T),
      with the stationary start gm_0 = sigma w_0 (note 1 - phi^2 =
      1 - exp(-2 dt / T); the thesis's eq. 7 misses the factor 2);
    * random walk rw_k = rw_(k-1) + K sqrt(dt) w_k, rw_0 = 0;
    * white noise n_k = N / sqrt(dt) w_k (sigma = N sqrt(f_s));

    then quantization to the LSB q (round half up, no dither; with
    ``integrated`` the residue is carried to the next sample, giving the
    IEEE-952 quantization noise Q = q dt / sqrt(12)) and saturation at
    +-full_scale (0: none).

    ``states`` (3, 2 + M, 4) uint64 holds one stream per axis and process:
    [white, random walk, GM component 0..M-1]; a stream draws one normal per
    sample only while its process is on.  ``gm_sig``, ``gm_tau`` are (3, M).
    ``dtemp`` has length N or 0 (no temperature effect).  With
    ``keep_truth`` the terms are stored in ``truth`` (4, N, 3): bias
    instability, random walk, ramp, white noise.  Returns the number of
    saturated samples per axis.
    """
    use_g, t_mat, g_mat, bias = prm.use_g, prm.t_mat, prm.g_mat, prm.bias
    bias_poly, scale_poly, nd, gm_sig, gm_tau = prm.bias_poly, prm.scale_poly, prm.nd, prm.gm_sig, prm.gm_tau
    k_rw, ramp, q, integrated, full_scale = prm.k_rw, prm.ramp, prm.q, prm.integrated, prm.full_scale
    n = x.shape[0]
    m = gm_sig.shape[1]
    ns = 2 + m
    npb = bias_poly.shape[0]
    nps = scale_poly.shape[0]
    has_temp = dtemp.shape[0] == n and (npb > 0 or nps > 0)
    active = np.zeros((3, ns), dtype=np.bool_)
    for i in range(3):
        active[i, 0] = nd[i] > 0.0
        active[i, 1] = k_rw[i] > 0.0
        for j in range(m):
            active[i, 2 + j] = gm_sig[i, j] > 0.0
    z = np.zeros((3, ns))
    gm_x = np.zeros((3, m))
    phi = np.zeros((3, m))
    drive = np.zeros((3, m))
    rw = np.zeros(3)
    white_s = np.zeros(3)
    rw_step = np.zeros(3)
    bt = np.empty(3)
    st = np.zeros(3)
    e = np.zeros(3)
    y = np.zeros(3)
    carry = np.zeros(3)
    nsat = np.zeros(3, dtype=np.int64)
    for i in range(3):
        bt[i] = bias[i]
    any_q = False
    for i in range(3):
        if q[i] > 0.0 or full_scale[i] > 0.0:
            any_q = True
    t0 = t[0]
    d_prev = -1.0
    for k in range(n):
        if dt_const > 0.0:
            d = dt_const
        elif k == 0:
            d = t[1] - t[0]
        else:
            d = t[k] - t[k - 1]
        if d != d_prev:
            for i in range(3):
                white_s[i] = nd[i] / math.sqrt(d)
                rw_step[i] = k_rw[i] * math.sqrt(d)
                for j in range(m):
                    if gm_sig[i, j] > 0.0:
                        phi[i, j] = math.exp(-d / gm_tau[i, j])
                        drive[i, j] = gm_sig[i, j] * math.sqrt(-math.expm1(-2.0 * d / gm_tau[i, j]))
            d_prev = d
        # one normal per active stream (the random walk starts at 0: no draw at k = 0)
        for i in range(3):
            for c in range(ns):
                if active[i, c] and (k > 0 or c != 1):
                    z[i, c] = next_normal(states[i, c])
        if has_temp:
            dd = dtemp[k]
            for i in range(3):
                acc = bias[i]
                p = dd
                for j in range(npb):
                    acc += bias_poly[j, i] * p
                    p *= dd
                bt[i] = acc
                acc = 0.0
                p = dd
                for j in range(nps):
                    acc += scale_poly[j, i] * p
                    p *= dd
                st[i] = acc
        tk = t[k] - t0
        for i in range(3):
            s_bi = 0.0
            for j in range(m):
                if active[i, 2 + j]:
                    if k == 0:
                        gm_x[i, j] = gm_sig[i, j] * z[i, 2 + j]  # stationary start
                    else:
                        gm_x[i, j] = phi[i, j] * gm_x[i, j] + drive[i, j] * z[i, 2 + j]
                    s_bi += gm_x[i, j]
            if k > 0 and active[i, 1]:
                rw[i] += rw_step[i] * z[i, 1]
            wn = white_s[i] * z[i, 0] if active[i, 0] else 0.0
            rp = ramp[i] * tk
            e[i] = s_bi + rw[i] + rp + wn
            if keep_truth:
                truth[0, k, i] = s_bi
                truth[1, k, i] = rw[i]
                truth[2, k, i] = rp
                truth[3, k, i] = wn
        x0 = x[k, 0]
        x1 = x[k, 1]
        x2 = x[k, 2]
        for i in range(3):
            v = t_mat[i, 0] * x0 + t_mat[i, 1] * x1 + t_mat[i, 2] * x2
            v += st[i] * x[k, i] + bt[i]
            if use_g:
                v += g_mat[i, 0] * f[k, 0] + g_mat[i, 1] * f[k, 1] + g_mat[i, 2] * f[k, 2]
            y[i] = v + e[i]
        if any_q:
            for i in range(3):
                v = y[i]
                qi = q[i]
                if qi > 0.0:
                    if integrated:
                        v = v + carry[i]
                        r = qi * math.floor(v / qi + 0.5)
                        carry[i] = v - r
                        v = r
                    else:
                        v = qi * math.floor(v / qi + 0.5)
                fs = full_scale[i]
                if fs > 0.0:
                    if v > fs:
                        v = fs
                        nsat[i] += 1
                    elif v < -fs:
                        v = -fs
                        nsat[i] += 1
                y[i] = v
        out[k, 0] = y[0]
        out[k, 1] = y[1]
        out[k, 2] = y[2]
    return nsat
