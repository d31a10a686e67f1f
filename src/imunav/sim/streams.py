"""Random streams of the simulators: one reproducible, independent stream per (sensor, process, axis, component).

The root :class:`numpy.random.SeedSequence` comes from the caller's ``rng`` (:func:`seed_sequence`); a
stream's xoshiro256++ state depends only on the root and on its key (:func:`stream_state`), never on which
other streams exist, so adding an error term to a model leaves the other terms' noise unchanged.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav.errors import InvalidInputError
from imunav.sim import _kernels as _k

__all__ = ["seed_sequence", "stream_state", "normals"]


def seed_sequence(rng: Any) -> np.random.SeedSequence:
    """Root SeedSequence from rng (Generator | int seed | SeedSequence | None).

    A Generator contributes 128 bits drawn from it (so successive calls with
    the same Generator give new, reproducible realisations).

    Parameters
    ----------
    rng : numpy.random.Generator, int, numpy.random.SeedSequence or None
        Source of the root entropy: a Generator (128 bits drawn from it), a non-negative integer seed,
        a SeedSequence (returned as is) or None (fresh OS entropy, not reproducible).

    Returns
    -------
    numpy.random.SeedSequence
        The root of every stream of one simulation.

    Raises
    ------
    InvalidInputError
        If ``rng`` is a negative integer, a bool or of another type.
    """
    if rng is None:
        return np.random.SeedSequence()
    if isinstance(rng, np.random.SeedSequence):
        return rng
    if isinstance(rng, np.random.Generator):
        return np.random.SeedSequence([int(x) for x in rng.integers(0, 2**32, size=4, dtype=np.uint64)])
    if isinstance(rng, (int, np.integer)) and not isinstance(rng, bool):
        if rng < 0:
            raise InvalidInputError(f"rng: a seed must be a non-negative integer, got {rng}")
        return np.random.SeedSequence(int(rng))
    raise InvalidInputError(
        f"rng: expected a numpy Generator, a non-negative integer seed or None, got {type(rng).__name__}"
    )


def stream_state(root: np.random.SeedSequence, *key: int) -> NDArray[np.uint64]:
    """256-bit xoshiro256++ state of the stream ``key`` under ``root``.

    The stream depends only on the root entropy and on ``key`` =
    (sensor, process, axis, component), never on which other streams exist.

    Parameters
    ----------
    root : numpy.random.SeedSequence
        Root of the simulation (:func:`seed_sequence`).
    *key : int
        Non-negative integers appended to the root's spawn key, e.g. (sensor, process, axis, component).

    Returns
    -------
    numpy.ndarray of uint64, shape (4,)
        Generator state, never all-zero (the one invalid xoshiro256++ state; Blackman & Vigna, "Scrambled
        linear pseudorandom number generators", ACM TOMS 47(4), 2021).
    """
    ss = np.random.SeedSequence(entropy=root.entropy, spawn_key=tuple(root.spawn_key) + tuple(key))
    st = ss.generate_state(4, np.uint64)
    if not np.any(st):  # the all-zero state is the one invalid state
        st[0] = np.uint64(1)
    return st


def normals(root: np.random.SeedSequence, key: tuple[int, ...], n: int) -> NDArray[np.float64]:
    """n standard normals of the stream ``key`` (same generator as the IMU kernels).

    Parameters
    ----------
    root : numpy.random.SeedSequence
        Root of the simulation (:func:`seed_sequence`).
    key : tuple of int
        Stream key (:func:`stream_state`).
    n : int
        Number of samples.

    Returns
    -------
    numpy.ndarray, shape (n,)
        Independent N(0, 1) samples; the same ``root`` and ``key`` always give the same values.
    """
    out = np.empty(n)
    _k.fill_normal(stream_state(root, *key), out)
    return out
