"""Numba kernels behind :mod:`imunav.rotation` (private).

Scalar kernels (``*_1``) work on one quaternion / vector and can be called
from other ``@njit`` code (attitude filters, strapdown).  Their
allocation-free forms (``*_t``) take and return plain floats (tuples) and are
inlined into the caller: hot filter loops use them to avoid a heap array per
operation.  Batch kernels work on ``(N, 4)`` / ``(N, 3)`` / ``(N, 3, 3)``
arrays.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# Below this angle (rad) the series expansions are used; the truncation error
# of sin(x/2)/x ~ 1/2 - x^2/48 + x^4/3840 is then < 1e-20.
_SMALL = 1e-4


@njit(cache=True, fastmath=False, inline="always")
def qmul_t(a0, a1, a2, a3, b0, b1, b2, b3):
    """Hamilton product a ⊗ b on scalars (no allocation)."""
    return (a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
            a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
            a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
            a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0)  # fmt: skip


@njit(cache=True, fastmath=False)
def qmul_1(p, q):
    """Hamilton product p ⊗ q of two scalar-first quaternions."""
    out = np.empty(4)
    out[0], out[1], out[2], out[3] = qmul_t(p[0], p[1], p[2], p[3], q[0], q[1], q[2], q[3])
    return out


@njit(cache=True)
def qconj_1(q):
    """Conjugate ``q*`` of a scalar-first quaternion (the inverse of a unit quaternion)."""
    out = np.empty(4)
    out[0] = q[0]
    out[1] = -q[1]
    out[2] = -q[2]
    out[3] = -q[3]
    return out


@njit(cache=True, inline="always")
def qnormalize_t(a0, a1, a2, a3):
    """Unit quaternion ``a / |a|`` on scalars (no allocation; the array form is
    :func:`imunav.filters._core.quat_normalize`)."""
    n = 1.0 / math.sqrt(a0 * a0 + a1 * a1 + a2 * a2 + a3 * a3)
    return a0 * n, a1 * n, a2 * n, a3 * n


@njit(cache=True, inline="always")
def qrot_t(w, x, y, z, v0, v1, v2):
    """Rotate (v0, v1, v2) by unit (w, x, y, z): q ⊗ [0, v] ⊗ q* on scalars."""
    # t = 2 (q_v x v); v' = v + w t + q_v x t
    tx = 2.0 * (y * v2 - z * v1)
    ty = 2.0 * (z * v0 - x * v2)
    tz = 2.0 * (x * v1 - y * v0)
    return (v0 + w * tx + (y * tz - z * ty), v1 + w * ty + (z * tx - x * tz), v2 + w * tz + (x * ty - y * tx))


@njit(cache=True)
def qrot_1(q, v):
    """Rotate v by unit q: q ⊗ [0, v] ⊗ q* (body -> nav for q = q_nb)."""
    out = np.empty(3)
    out[0], out[1], out[2] = qrot_t(q[0], q[1], q[2], q[3], v[0], v[1], v[2])
    return out


@njit(cache=True, inline="always")
def qexp_t(r0, r1, r2):
    """Quaternion of rotation vector (r0, r1, r2) (rad) on scalars:
    [cos(|r|/2), sin(|r|/2) r/|r|], series below ``_SMALL``."""
    th2 = r0 * r0 + r1 * r1 + r2 * r2
    th = math.sqrt(th2)
    if th < _SMALL:
        c = 1.0 - th2 / 8.0 + th2 * th2 / 384.0
        s = 0.5 - th2 / 48.0 + th2 * th2 / 3840.0
    else:
        c = math.cos(0.5 * th)
        s = math.sin(0.5 * th) / th
    return c, s * r0, s * r1, s * r2


@njit(cache=True)
def qexp_1(r):
    """Quaternion of rotation vector r (rad): [cos(|r|/2), sin(|r|/2) r/|r|]."""
    out = np.empty(4)
    out[0], out[1], out[2], out[3] = qexp_t(r[0], r[1], r[2])
    return out


@njit(cache=True)
def skew_1(v):
    """Cross-product matrix [v]x, so that [v]x u = v x u."""
    S = np.zeros((3, 3))
    S[0, 1] = -v[2]
    S[0, 2] = v[1]
    S[1, 0] = v[2]
    S[1, 2] = -v[0]
    S[2, 0] = -v[1]
    S[2, 1] = v[0]
    return S


@njit(cache=True)
def dcm_exp_into(R, r0, r1, r2):
    """DCM ``exp([r×]) = I + a [r×] + b [r×]²`` of rotation vector (r0, r1, r2) (rad), written into R (3, 3).

    Rodrigues' formula with ``a = sin θ / θ``, ``b = (1 − cos θ) / θ²`` (θ = |r|), and their series
    ``a = 1 − θ²/6``, ``b = ½ − θ²/24`` for θ² < 1e-12, where the closed forms lose digits to cancellation.
    """
    th2 = r0 * r0 + r1 * r1 + r2 * r2
    if th2 < 1e-12:
        a = 1.0 - th2 / 6.0
        b = 0.5 - th2 / 24.0
    else:
        th = math.sqrt(th2)
        a = math.sin(th) / th
        b = (1.0 - math.cos(th)) / th2
    R[0, 0] = 1.0 - b * (r1 * r1 + r2 * r2)
    R[1, 1] = 1.0 - b * (r0 * r0 + r2 * r2)
    R[2, 2] = 1.0 - b * (r0 * r0 + r1 * r1)
    R[0, 1] = -a * r2 + b * r0 * r1
    R[1, 0] = a * r2 + b * r0 * r1
    R[0, 2] = a * r1 + b * r0 * r2
    R[2, 0] = -a * r1 + b * r0 * r2
    R[1, 2] = -a * r0 + b * r1 * r2
    R[2, 1] = a * r0 + b * r1 * r2


@njit(cache=True, inline="always")
def _needs_flip(w, x, y, z):
    """True if -q is the canonical representative: w > 0, or at w == 0 the
    first non-zero vector component positive (makes log(q) == log(-q) at pi)."""
    if w != 0.0:
        return w < 0.0
    if x != 0.0:
        return x < 0.0
    if y != 0.0:
        return y < 0.0
    return z < 0.0


@njit(cache=True, inline="always")
def qlog_t(w, x, y, z):
    """Rotation vector (rad) of unit (w, x, y, z) on scalars, angle in [0, pi] (q and -q give the same)."""
    if _needs_flip(w, x, y, z):
        w, x, y, z = -w, -x, -y, -z
    nv = math.sqrt(x * x + y * y + z * z)
    if nv < _SMALL * 0.5:
        # theta = 2 atan2(nv, w) ~ 2 nv / w (1 - nv^2 / (3 w^2))
        k = 2.0 / w * (1.0 - nv * nv / (3.0 * w * w))
    else:
        k = 2.0 * math.atan2(nv, w) / nv
    return k * x, k * y, k * z


@njit(cache=True)
def qlog_1(q):
    """Rotation vector (rad) of unit q, angle in [0, pi] (q and -q give the same)."""
    out = np.empty(3)
    out[0], out[1], out[2] = qlog_t(q[0], q[1], q[2], q[3])
    return out


@njit(cache=True, inline="always")
def dcm_from_quat_t(w, x, y, z):
    """DCM of unit quaternion (w, x, y, z) on scalars, row by row (C00, C01, C02, C10, …, C22; no allocation)."""
    return (1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y),
            2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x),
            2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y))  # fmt: skip


@njit(cache=True)
def dcm_from_quat_1(q):
    C = np.empty((3, 3))
    (C[0, 0], C[0, 1], C[0, 2], C[1, 0], C[1, 1], C[1, 2],
     C[2, 0], C[2, 1], C[2, 2]) = dcm_from_quat_t(q[0], q[1], q[2], q[3])  # fmt: skip
    return C


@njit(cache=True, inline="always")
def _argmax4(a0, a1, a2, a3):
    """``np.argmax([a0, a1, a2, a3])`` (the first largest; the first NaN if any) without building an array:
    ``np.array`` and ``np.argmax`` are a second of compilation (issue 35, a first run)."""
    if a0 != a0:
        return 0
    i = 0
    m = a0
    if a1 != a1:
        return 1
    if a1 > m:
        i = 1
        m = a1
    if a2 != a2:
        return 2
    if a2 > m:
        i = 2
        m = a2
    if a3 != a3:
        return 3
    if a3 > m:
        i = 3
    return i


@njit(cache=True, inline="always")
def quat_from_dcm_t(C):
    """Shepperd's method: pick the largest of 4w^2, 4x^2, 4y^2, 4z^2; the unit quaternion's components."""
    tr = C[0, 0] + C[1, 1] + C[2, 2]
    i = _argmax4(tr, C[0, 0], C[1, 1], C[2, 2])
    if i == 0:
        s = 2.0 * math.sqrt(1.0 + tr)
        o0 = 0.25 * s
        o1 = (C[2, 1] - C[1, 2]) / s
        o2 = (C[0, 2] - C[2, 0]) / s
        o3 = (C[1, 0] - C[0, 1]) / s
    elif i == 1:
        s = 2.0 * math.sqrt(max(1.0 + C[0, 0] - C[1, 1] - C[2, 2], 0.0))
        o0 = (C[2, 1] - C[1, 2]) / s
        o1 = 0.25 * s
        o2 = (C[0, 1] + C[1, 0]) / s
        o3 = (C[0, 2] + C[2, 0]) / s
    elif i == 2:
        s = 2.0 * math.sqrt(max(1.0 - C[0, 0] + C[1, 1] - C[2, 2], 0.0))
        o0 = (C[0, 2] - C[2, 0]) / s
        o1 = (C[0, 1] + C[1, 0]) / s
        o2 = 0.25 * s
        o3 = (C[1, 2] + C[2, 1]) / s
    else:
        s = 2.0 * math.sqrt(max(1.0 - C[0, 0] - C[1, 1] + C[2, 2], 0.0))
        o0 = (C[1, 0] - C[0, 1]) / s
        o1 = (C[0, 2] + C[2, 0]) / s
        o2 = (C[1, 2] + C[2, 1]) / s
        o3 = 0.25 * s
    if _needs_flip(o0, o1, o2, o3):
        o0, o1, o2, o3 = -o0, -o1, -o2, -o3
    n = math.sqrt(o0 ** 2 + o1 ** 2 + o2 ** 2 + o3 ** 2)
    return o0 / n, o1 / n, o2 / n, o3 / n


@njit(cache=True)
def quat_from_dcm_1(C):
    """Shepperd's method: pick the largest of 4w^2, 4x^2, 4y^2, 4z^2."""
    out = np.empty(4)
    out[0], out[1], out[2], out[3] = quat_from_dcm_t(C)
    return out


@njit(cache=True, inline="always")
def quat_from_euler_t(roll, pitch, yaw):
    """ZYX: q = qz(yaw) ⊗ qy(pitch) ⊗ qx(roll), on scalars."""
    cr, sr = math.cos(0.5 * roll), math.sin(0.5 * roll)
    cp, sp = math.cos(0.5 * pitch), math.sin(0.5 * pitch)
    cy, sy = math.cos(0.5 * yaw), math.sin(0.5 * yaw)
    return (cr * cp * cy + sr * sp * sy,
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy)  # fmt: skip


@njit(cache=True)
def quat_from_euler_1(roll, pitch, yaw):
    """ZYX: q = qz(yaw) ⊗ qy(pitch) ⊗ qx(roll)."""
    out = np.empty(4)
    out[0], out[1], out[2], out[3] = quat_from_euler_t(roll, pitch, yaw)
    return out


@njit(cache=True, inline="always")
def euler_from_dcm_t(C):
    """(roll, pitch, yaw) of C_nb = Rz(yaw) Ry(pitch) Rx(roll).

    Pitch and yaw come from the first column (body x axis in nav).  Roll is
    then taken from the body y axis after removing yaw,
    (cos r, -sin r) = (-sin y C01 + cos y C11, -(sin y C02 - cos y C12)) with
    sign as below, which stays well conditioned near gimbal lock: whatever
    split of the rotation about the vertical the rounding gives yaw, roll
    absorbs the rest, so the angles always rebuild C to rounding error.  At
    exact gimbal lock (cos pitch < 1e-12) yaw carries the whole rotation
    about the vertical and roll is 0.
    """
    cp = math.sqrt(C[0, 0] * C[0, 0] + C[1, 0] * C[1, 0])
    pitch = math.atan2(-C[2, 0], cp)
    if cp > 1e-12:
        y = math.atan2(C[1, 0], C[0, 0])
    else:
        # C = Rz(yaw) Ry(+-90 deg): C[0,1] = -sin(yaw), C[1,1] = cos(yaw) when roll = 0
        y = math.atan2(-C[0, 1], C[1, 1])
    sy, cy = math.sin(y), math.cos(y)
    return math.atan2(sy * C[0, 2] - cy * C[1, 2], -sy * C[0, 1] + cy * C[1, 1]), pitch, y


@njit(cache=True)
def euler_from_dcm_1(C):
    """(roll, pitch, yaw) of C_nb = Rz(yaw) Ry(pitch) Rx(roll) (:func:`euler_from_dcm_t`)."""
    out = np.empty(3)
    out[0], out[1], out[2] = euler_from_dcm_t(C)
    return out


# ---- batch kernels --------------------------------------------------------
# Each writes its rows from the scalar forms (``*_t``, inlined) rather than calling the ``*_1`` kernels: a call to
# another kernel compiles that kernel too, and a row assignment compiles its shape check and error message, seconds
# of compilation in every process that compiles these (issue 35, a first run); the arithmetic is the same.
@njit(cache=True)
def qmul_n(p, q):
    n = max(p.shape[0], q.shape[0])
    out = np.empty((n, 4))
    for i in range(n):
        a = i if p.shape[0] > 1 else 0
        b = i if q.shape[0] > 1 else 0
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = qmul_t(p[a, 0], p[a, 1], p[a, 2], p[a, 3],
                                                            q[b, 0], q[b, 1], q[b, 2], q[b, 3])
    return out


@njit(cache=True)
def qrot_n(q, v):
    n = max(q.shape[0], v.shape[0])
    out = np.empty((n, 3))
    for i in range(n):
        a = i if q.shape[0] > 1 else 0
        b = i if v.shape[0] > 1 else 0
        out[i, 0], out[i, 1], out[i, 2] = qrot_t(q[a, 0], q[a, 1], q[a, 2], q[a, 3], v[b, 0], v[b, 1], v[b, 2])
    return out


@njit(cache=True)
def qexp_n(r):
    out = np.empty((r.shape[0], 4))
    for i in range(r.shape[0]):
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = qexp_t(r[i, 0], r[i, 1], r[i, 2])
    return out


@njit(cache=True)
def qlog_n(q):
    out = np.empty((q.shape[0], 3))
    for i in range(q.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = qlog_t(q[i, 0], q[i, 1], q[i, 2], q[i, 3])
    return out


@njit(cache=True)
def dcm_from_quat_n(q):
    out = np.empty((q.shape[0], 3, 3))
    for i in range(q.shape[0]):
        (out[i, 0, 0], out[i, 0, 1], out[i, 0, 2], out[i, 1, 0], out[i, 1, 1], out[i, 1, 2],
         out[i, 2, 0], out[i, 2, 1], out[i, 2, 2]) = dcm_from_quat_t(q[i, 0], q[i, 1], q[i, 2], q[i, 3])  # fmt: skip
    return out


@njit(cache=True)
def quat_from_dcm_n(C):
    out = np.empty((C.shape[0], 4))
    for i in range(C.shape[0]):
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = quat_from_dcm_t(C[i])
    return out


@njit(cache=True)
def quat_from_euler_n(e):
    out = np.empty((e.shape[0], 4))
    for i in range(e.shape[0]):
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = quat_from_euler_t(e[i, 0], e[i, 1], e[i, 2])
    return out


@njit(cache=True)
def euler_from_dcm_n(C):
    out = np.empty((C.shape[0], 3))
    for i in range(C.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = euler_from_dcm_t(C[i])
    return out


@njit(cache=True)
def integrate_rate_kernel(q0, w, dt, method):
    """Attitude from body rates.

    q_{k+1} = q_k ⊗ exp(phi_k), with phi_k = w_k dt_k (method 0, rate held
    over the step, exact for piecewise-constant rates) or
    phi_k = (w_k + w_{k+1})/2 dt_k + (w_k x w_{k+1}) dt_k^2 / 12 (method 1,
    trapezoid plus the second-order coning correction for rates that vary
    linearly over the step).
    """
    n = w.shape[0]
    out = np.empty((n, 4))
    out[0] = q0
    phi = np.empty(3)
    for k in range(n - 1):
        h = dt[k]
        if method == 0:
            for j in range(3):
                phi[j] = w[k, j] * h
        else:
            a = w[k]
            b = w[k + 1]
            cx = a[1] * b[2] - a[2] * b[1]
            cy = a[2] * b[0] - a[0] * b[2]
            cz = a[0] * b[1] - a[1] * b[0]
            phi[0] = 0.5 * (a[0] + b[0]) * h + cx * h * h / 12.0
            phi[1] = 0.5 * (a[1] + b[1]) * h + cy * h * h / 12.0
            phi[2] = 0.5 * (a[2] + b[2]) * h + cz * h * h / 12.0
        qn = qmul_1(out[k], qexp_1(phi))
        nn = math.sqrt(qn[0] ** 2 + qn[1] ** 2 + qn[2] ** 2 + qn[3] ** 2)
        out[k + 1] = qn / nn
    return out
