"""numba kernels of the virtual IMU error model (private).

Each kernel works in place on whole float64 arrays and releases the GIL
(``nogil=True``), so the public wrappers in :mod:`imunav.sim.error_model` can
run the axes of a triad in parallel threads.  The random numbers are drawn by
the caller (numpy ``Generator`` per axis and per process) and passed in as
standard-normal arrays ``w``; the kernels only apply the exact discrete-time
recursions.

Time steps: ``dt[k] = t[k] - t[k-1]`` for ``k >= 1``; ``dt[0]`` is the
nominal step (used only by the white-noise scaling of the first sample).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def gauss_markov_add(out, w, dt, sigma, tau):  # pragma: no cover - compiled
    """Add one first-order Gauss-Markov realisation to ``out`` (in place).

    Exact discretisation of dx/dt = -x/T + noise with stationary variance
    sigma^2 (references.md, AR(1) form):

        x_k = phi_k x_{k-1} + sigma sqrt(1 - phi_k^2) w_k,  phi_k = exp(-dt_k / T)

    (note 1 - phi^2 = 1 - exp(-2 dt/T): imu-error-calibration.md eq. 7 misses
    the factor 2).  The first sample is drawn from the stationary law,
    x_0 = sigma w_0, so the process is stationary from the start.
    Returns the last state.
    """
    n = out.shape[0]
    if n == 0 or sigma == 0.0:
        return 0.0
    x = sigma * w[0]
    out[0] += x
    last_dt = -1.0
    phi = 0.0
    drive = 0.0
    for k in range(1, n):
        d = dt[k]
        if d != last_dt:  # recompute only when the step changes
            phi = math.exp(-d / tau)
            drive = sigma * math.sqrt(max(0.0, -math.expm1(-2.0 * d / tau)))
            last_dt = d
        x = phi * x + drive * w[k]
        out[k] += x
    return x


@njit(cache=True, nogil=True)
def random_walk_add(out, w, dt, k_rw):  # pragma: no cover - compiled
    """Add a random walk b_k = b_{k-1} + K sqrt(dt_k) w_k, b_0 = 0, to ``out``.

    K is the IEEE-952 rate-random-walk coefficient (unit/s/sqrt(s));
    the walk starts at zero (the turn-on bias is the constant term).
    """
    n = out.shape[0]
    if k_rw == 0.0:
        return 0.0
    b = 0.0
    last_dt = -1.0
    step = 0.0
    for k in range(1, n):
        d = dt[k]
        if d != last_dt:
            step = k_rw * math.sqrt(d)
            last_dt = d
        b += step * w[k]
        out[k] += b
    return b


@njit(cache=True, nogil=True)
def white_add(out, w, dt, density):  # pragma: no cover - compiled
    """``out[k] += density / sqrt(dt_k) * w[k]``: white noise of density n.

    White noise of density n (unit/sqrt(Hz); the IEEE-952 ARW / VRW
    coefficient N, Allan variance N^2 / tau) sampled with step dt has the
    per-sample standard deviation n sqrt(f_s) = n / sqrt(dt).
    """
    n = out.shape[0]
    last_dt = -1.0
    s = 0.0
    for k in range(n):
        d = dt[k]
        if d != last_dt:
            s = density / math.sqrt(d)
            last_dt = d
        out[k] += s * w[k]


@njit(cache=True, nogil=True)
def quantize(y, q, integrated, full_scale):  # pragma: no cover - compiled
    """Quantize and saturate a (N, 3) array in place.

    ``q[i] > 0``: dither-free rounding to the LSB q[i] (round half up).
    ``integrated``: the quantization residue is carried to the next sample
    (the sensor integrates and outputs increments, as rate-integrating gyros
    and delta-angle / delta-velocity outputs do), so the output error is the
    first difference of a bounded residue: IEEE-952 quantization noise with
    Q = q dt / sqrt(12) in integral units.  Otherwise each sample is rounded
    on its own (error variance q^2 / 12 when the signal moves by more than q).
    ``full_scale[i] > 0`` clips to +-full_scale[i] after quantization.
    Returns the number of saturated samples per axis.
    """
    n = y.shape[0]
    nsat = np.zeros(3, dtype=np.int64)
    for i in range(3):
        qi = q[i]
        fs = full_scale[i]
        carry = 0.0
        for k in range(n):
            v = y[k, i]
            if qi > 0.0:
                if integrated:
                    v = v + carry
                    r = qi * math.floor(v / qi + 0.5)
                    carry = v - r
                    v = r
                else:
                    v = qi * math.floor(v / qi + 0.5)
            if fs > 0.0:
                if v > fs:
                    v = fs
                    nsat[i] += 1
                elif v < -fs:
                    v = -fs
                    nsat[i] += 1
            y[k, i] = v
    return nsat


@njit(cache=True, nogil=True)
def measure_triad(
    x, f, t_mat, g_mat, use_g, bias, dtemp, bias_poly, scale_poly, stoch, q, integrated, full_scale, out
):  # pragma: no cover - compiled
    """Measurement model of one triad: deterministic part, stochastic tracks,
    quantization and saturation in one pass.

    For every sample k (imu-error-calibration.md eqs. 2 and 4, full 3x3
    g-sensitivity, temperature polynomials around the reference):

        y_k = (T + diag(s(dT_k))) x_k + b + b(dT_k) + G f_k + stoch_k
        b(dT)_i = sum_p bias_poly[p, i] dT^(p+1),  s(dT)_i = sum_p scale_poly[p, i] dT^(p+1)

    then quantization and saturation as in :func:`quantize`.  ``dtemp`` has
    length N (temperature minus reference) or 0 (no temperature effect);
    ``use_g`` switches the G f term (gyro only); ``stoch`` is (3, N), one
    contiguous row per axis (stochastic bias tracks plus white noise).
    Returns the number of saturated samples per axis.
    """
    n = x.shape[0]
    npb = bias_poly.shape[0]
    nps = scale_poly.shape[0]
    has_temp = dtemp.shape[0] == n and (npb > 0 or nps > 0)
    bt = np.empty(3)
    st = np.zeros(3)
    carry = np.zeros(3)
    nsat = np.zeros(3, dtype=np.int64)
    any_q = q[0] > 0.0 or q[1] > 0.0 or q[2] > 0.0 or full_scale[0] > 0.0 or full_scale[1] > 0.0 or full_scale[2] > 0.0
    for i in range(3):
        bt[i] = bias[i]
    t00, t01, t02 = t_mat[0, 0], t_mat[0, 1], t_mat[0, 2]
    t10, t11, t12 = t_mat[1, 0], t_mat[1, 1], t_mat[1, 2]
    t20, t21, t22 = t_mat[2, 0], t_mat[2, 1], t_mat[2, 2]
    for k in range(n):
        if has_temp:
            d = dtemp[k]
            for i in range(3):
                acc = bias[i]
                p = d
                for j in range(npb):
                    acc += bias_poly[j, i] * p
                    p *= d
                bt[i] = acc
                acc = 0.0
                p = d
                for j in range(nps):
                    acc += scale_poly[j, i] * p
                    p *= d
                st[i] = acc
        x0 = x[k, 0]
        x1 = x[k, 1]
        x2 = x[k, 2]
        y0 = t00 * x0 + t01 * x1 + t02 * x2 + st[0] * x0 + bt[0] + stoch[0, k]
        y1 = t10 * x0 + t11 * x1 + t12 * x2 + st[1] * x1 + bt[1] + stoch[1, k]
        y2 = t20 * x0 + t21 * x1 + t22 * x2 + st[2] * x2 + bt[2] + stoch[2, k]
        if use_g:
            f0 = f[k, 0]
            f1 = f[k, 1]
            f2 = f[k, 2]
            y0 += g_mat[0, 0] * f0 + g_mat[0, 1] * f1 + g_mat[0, 2] * f2
            y1 += g_mat[1, 0] * f0 + g_mat[1, 1] * f1 + g_mat[1, 2] * f2
            y2 += g_mat[2, 0] * f0 + g_mat[2, 1] * f1 + g_mat[2, 2] * f2
        if any_q:
            y0 = _quantize_1(y0, 0, q, integrated, full_scale, carry, nsat)
            y1 = _quantize_1(y1, 1, q, integrated, full_scale, carry, nsat)
            y2 = _quantize_1(y2, 2, q, integrated, full_scale, carry, nsat)
        out[k, 0] = y0
        out[k, 1] = y1
        out[k, 2] = y2
    return nsat


@njit(cache=True, nogil=True, inline="always")
def _quantize_1(v, i, q, integrated, full_scale, carry, nsat):  # pragma: no cover - compiled
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
    return v
