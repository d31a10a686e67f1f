"""Numeric text tables formatted in bulk: the bytes of ``printf`` / :func:`numpy.savetxt`, without a Python call per
value.

:func:`format_rows` formats a 2-D array as ``numpy.savetxt(..., fmt=fmt, delimiter=" ")`` would.  A left-aligned
fixed-point format ``%-W.Df`` (KF-GINS's ``%-15.9lf``; 1 ≤ D ≤ 9) is formatted with integer arithmetic in one
compiled loop (numba): each value is rounded to D decimals exactly as ``printf`` rounds (the exact binary value, ties
to even: the product ``|x|·10^D`` is carried exactly as a sum of two doubles), its digits are written into one byte
buffer, left-aligned, space-padded to W, with a space between values and a newline after each row.
Rows holding a value the integer path cannot carry (NaN, ±inf, ``|x| ≥ 2^52 / 10^D``) and every other format go
through Python's ``%`` operator, one joined template per block of rows.
"""

from __future__ import annotations

import math
import re

import numpy as np
from numba import njit
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


@njit(cache=True, nogil=True)
def _fixed_into(x: NDArray[np.float64], ncols: int, width: int, decimals: int,
                out: NDArray[np.uint8]) -> int:  # pragma: no cover - numba
    """Write ``%-W.Df`` of every value of ``x`` (finite, ``|x| < 2^52 / 10^D``) into ``out``, a space after each
    value and a newline after every ``ncols`` values; returns the bytes written.

    Each value is rounded as ``printf`` rounds the exact product ``|x| · 10^D`` (ties to even): Dekker's split
    carries the product exactly as ``p + err`` (``10^D`` has at most 21 significant bits for D ≤ 9)."""
    scale = 10.0 ** decimals
    unit = np.int64(10) ** decimals
    digits = np.empty(24, np.uint8)
    pos = 0
    for i in range(x.size):
        v = x[i]
        neg = math.copysign(1.0, v) < 0.0  # printf writes the sign of -0.0 and of negatives that round to 0
        a = abs(v)
        p = a * scale
        hi = a * _SPLIT
        hi = hi - (hi - a)
        err = (hi * scale - p) + (a - hi) * scale  # a · scale = p + err exactly
        n = np.rint(p)
        d = p - n  # exact: |d| ≤ 1/2 and p < 2^52
        if d == 0.5 and err > 0:
            n += 1.0
        elif d == -0.5 and err < 0:
            n -= 1.0
        r = np.int64(n)
        whole, frac = r // unit, r % unit
        start = pos
        if neg:
            out[pos] = 45
            pos += 1
        nd = 0
        while True:
            digits[nd] = 48 + whole % 10
            whole //= 10
            nd += 1
            if whole == 0:
                break
        for k in range(nd - 1, -1, -1):
            out[pos] = digits[k]
            pos += 1
        out[pos] = 46
        pos += 1
        for k in range(decimals - 1, -1, -1):
            out[pos + k] = 48 + frac % 10
            frac //= 10
        pos += decimals
        while pos - start < width:
            out[pos] = 32
            pos += 1
        out[pos] = 10 if (i + 1) % ncols == 0 else 32
        pos += 1
    return pos


def _fixed(a: NDArray[np.float64], width: int, decimals: int) -> bytes:
    """``%-W.Df`` of finite values below ``2^52 / 10^D`` (see the module docstring), row after row."""
    # a field holds the sign, at most 16 - D integer digits (|x| < 2^52 / 10^D < 10^(16 - D)), the point and D
    # decimals, or W characters; one separator after it
    out = np.empty(a.size * (max(width, 18) + 1), np.uint8)
    n = _fixed_into(a.ravel(), a.shape[1], width, decimals, out)
    return out[:n].tobytes()
