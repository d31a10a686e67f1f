"""Numeric text tables formatted in bulk: the bytes of ``printf`` / :func:`numpy.savetxt`, without a Python call per
value.

:func:`format_rows` formats a 2-D array as ``numpy.savetxt(..., fmt=fmt, delimiter=" ")`` would.  A left-aligned
fixed-point format ``%-W.Df`` (KF-GINS's ``%-15.9lf``; 1 ≤ D ≤ 9) is formatted with integer arithmetic on whole
arrays: each value is rounded to D decimals exactly as ``printf`` rounds (the exact binary value, ties to even: the
product ``|x|·10^D`` is carried exactly as a sum of two doubles), its digits are cut out column by column, and the
fields are packed left-aligned, space-padded to W, with a space between values and a newline after each row.
Rows holding a value the integer path cannot carry (NaN, ±inf, ``|x| ≥ 2^52 / 10^D``) and every other format go
through Python's ``%`` operator, one joined template per block of rows.
"""

from __future__ import annotations

import re

import numpy as np
from numpy.typing import NDArray

__all__ = ["format_rows"]

_FIXED = re.compile(r"%-(\d+)\.([1-9])f")
_SPLIT = 134217729.0  # 2**27 + 1: Dekker's split of a double into two halves of 26 bits


def format_rows(arr: NDArray[np.float64], fmt: str) -> bytes:
    """The text of ``arr`` as :func:`numpy.savetxt` writes it with ``fmt`` and ``delimiter=" "`` (ASCII).

    Parameters
    ----------
    arr : numpy.ndarray, shape (N, k)
        The values, float.
    fmt : str
        ``printf`` format of every value (one ``%`` conversion).

    Returns
    -------
    bytes
        N lines of k values separated by single spaces, each line ended by ``\\n``.
    """
    a = np.ascontiguousarray(arr, dtype=float)
    m = _FIXED.fullmatch(fmt)
    if m is None or a.size == 0:
        return _percent(a, fmt)
    width, decimals = int(m.group(1)), int(m.group(2))
    ok = np.all(np.isfinite(a) & (np.abs(a) < 2.0**52 / 10.0**decimals), axis=1)
    if ok.all():
        return _fixed(a, width, decimals)
    # rows with a value the integer path cannot carry: Python's %, in order with the rest
    out = []
    edges = np.flatnonzero(np.diff(np.r_[0, ok.astype(np.int8), 0]) != 0)
    bounds = np.r_[0, edges, a.shape[0]]
    for i0, i1 in zip(bounds[:-1], bounds[1:]):
        if i1 > i0:
            block = a[i0:i1]
            out.append(_fixed(block, width, decimals) if ok[i0] else _percent(block, fmt))
    return b"".join(out)


def _percent(a: NDArray[np.float64], fmt: str) -> bytes:
    """Python's ``%`` over one template joined for all the rows (``numpy.savetxt``'s format, one call)."""
    if a.size == 0:
        return b""
    row = " ".join([fmt] * a.shape[1]) + "\n"
    return ((row * a.shape[0]) % tuple(a.ravel().tolist())).encode("latin-1")


def _rounded(x: NDArray[np.float64], scale: float) -> NDArray[np.int64]:
    """``x · scale`` rounded to an integer as ``printf`` rounds the exact product (ties to even), for ``x ≥ 0``,
    ``x · scale < 2^52`` and ``scale = 10^D`` (D ≤ 9: 21 significant bits, so that Dekker's product is exact)."""
    p = x * scale
    hi = x * _SPLIT
    hi = hi - (hi - x)
    err = (hi * scale - p) + (x - hi) * scale  # x · scale = p + err exactly
    n = np.rint(p)
    d = p - n  # exact: |d| ≤ 1/2 and p < 2^52
    n += ((d == 0.5) & (err > 0)).astype(float) - ((d == -0.5) & (err < 0)).astype(float)
    return n.astype(np.int64)


def _digits(t: NDArray[np.uint8], v: NDArray[np.int64], first: int, count: int) -> None:
    """Write the ``count`` last decimal digits of ``v`` (ASCII) into the columns ``first ...`` of ``t``."""
    v = v.astype(np.uint64 if count > 9 else np.uint32)
    for k in range(count):
        q = v // 10
        t[:, first + count - 1 - k] = v - q * 10 + 48
        v = q


def _fixed(a: NDArray[np.float64], width: int, decimals: int) -> bytes:
    """``%-W.Df`` of finite values below ``2^52 / 10^D`` (see the module docstring), row after row."""
    x = a.ravel()
    size = x.size
    neg = np.signbit(x)  # printf writes the sign of -0.0 and of negatives that round to 0
    n = _rounded(np.abs(x), 10.0**decimals)
    whole, frac = np.divmod(n, 10**decimals)
    k = 16 - decimals  # integer digits: |x| < 2^52 / 10^D < 10^k
    span = 2 + k + decimals  # sign slot, k integer digits, the point, D decimals
    t = np.empty((size, span), np.uint8)
    t[:, 0] = 32
    _digits(t, whole, 1, k)
    t[:, k + 1] = 46
    _digits(t, frac, k + 2, decimals)
    nd = np.ones(size, np.int64)  # integer digits written (at least one)
    for j in range(1, k):
        nd += whole >= 10**j
    rows = np.flatnonzero(neg)
    t[rows, k - nd[rows]] = 45
    start = k + 1 - nd - neg
    field = np.maximum(width, span - start)
    cols = int(field.max()) + 1
    f = np.full((size, cols), 32, np.uint8)
    for s in np.flatnonzero(np.bincount(start, minlength=span)):
        r = np.flatnonzero(start == s)
        f[r, :span - s] = t[r, s:]
    sep = np.full(size, 32, np.uint8)
    sep[a.shape[1] - 1::a.shape[1]] = 10
    f[np.arange(size), field] = sep
    return f[np.arange(cols) <= field[:, None]].tobytes()
