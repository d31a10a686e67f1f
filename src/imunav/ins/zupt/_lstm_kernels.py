"""Numba kernels of :mod:`imunav.learn` (private): the stance guard of the LSTM detector.

Public, validated wrapper: :func:`imunav.learn.lstm.guard_stances`.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def fill_missed(zv, ref, min_len):
    """Add every run of ``ref`` (>= ``min_len`` samples) that holds no True of ``zv``.

    Returns (out, number of runs added).
    """
    n = zv.shape[0]
    out = zv.copy()
    added = 0
    i = 0
    while i < n:
        if ref[i]:
            j = i
            hit = False
            while j < n and ref[j]:
                if zv[j]:
                    hit = True
                j += 1
            if not hit and j - i >= min_len:
                for k in range(i, j):
                    out[k] = True
                added += 1
            i = j
        else:
            i += 1
    return out, added


@njit(cache=True)
def bridge_gaps(zv, ref, max_len):
    """Fill every False run of ``zv`` (<= ``max_len`` samples) that lies between two True runs and is
    all True in ``ref``.

    Returns (out, number of gaps filled).
    """
    n = zv.shape[0]
    out = zv.copy()
    filled = 0
    i = 0
    seen = False
    while i < n:
        if zv[i]:
            seen = True
            i += 1
            continue
        j = i
        allref = True
        while j < n and not zv[j]:
            if not ref[j]:
                allref = False
            j += 1
        if seen and j < n and allref and j - i <= max_len:
            for k in range(i, j):
                out[k] = True
            filled += 1
        i = j
    return out, filled


@njit(cache=True)
def block_gate(zv, ref, block, min_ratio, max_count_ratio):
    """Per block of ``block`` samples: True where ``zv`` is implausible against ``ref``.

    A block fails when ``ref`` is stationary somewhere in it and ``zv`` marks
    fewer than ``min_ratio`` times as many stationary samples, or when ``zv``
    starts more than ``max_count_ratio`` times as many stances (and at least 3)
    as ``ref`` does.  Returns a (n_blocks,) bool array.
    """
    n = zv.shape[0]
    nb = (n + block - 1) // block
    bad = np.zeros(nb, dtype=np.bool_)
    for b in range(nb):
        a = b * block
        e = min(n, a + block)
        sz = 0
        sr = 0
        cz = 0
        cr = 0
        for k in range(a, e):
            if zv[k]:
                sz += 1
                if k == 0 or not zv[k - 1]:
                    cz += 1
            if ref[k]:
                sr += 1
                if k == 0 or not ref[k - 1]:
                    cr += 1
        if sr > 0 and sz < min_ratio * sr:
            bad[b] = True
        if cz >= 3 and cz > max_count_ratio * cr:
            bad[b] = True
    return bad
