"""The GNSS/INS aids: one measurement model per file, registered here.

An aid model is a module with

* ``NAME``: its name (the key of its NIS record and of :data:`AID`);
* ``ROWS``: the rows it writes; ``WIDTH``: the columns of its measurement ``z``;
* ``PARAMS``, ``N_PARAMS``: the layout of its own parameter block and ``params(config)``, which packs the block
  from a :class:`~imunav.ins.gins.GinsConfig`;
* ``rows(xs, ctx, z, r, p, lay, H, R, nu, row)``: a numba function that writes the innovation ``nu``, the
  Jacobian rows ``H`` on the error state (layout ``lay``) and the measurement covariance ``R`` at ``row``, from the
  nominal state ``xs``, the update context ``ctx``, the measurement ``z`` (with its covariance ``r`` where the
  measurement carries one) and the parameters ``p``.

The kernel (:mod:`imunav.ins.gins.kernels`) knows no aid by name: it gates and applies whatever :func:`evaluate`
returns, for two kinds of input:

* timed aids (:data:`TIMED`): measurements at their own time stamps (GNSS), the IMU increments split there;
* sampled aids (:data:`SAMPLED`): columns on the IMU grid applied at the covariance epochs, in the order of
  :data:`SAMPLED`; the aids of one tuple form one joint update (odometer + NHC, ZUPT + ZARU) whose statistic
  is gated as a whole, and each model's own NIS is recorded beside it.

The kernel calls :func:`evaluate_used`, which takes besides the arguments of :func:`evaluate` the set of aids the
run uses (:func:`used`): it compiles the rows of those aids only, one kernel per set (a run without GNSS or
magnetometer compiles neither; issue 35, a first run).

Adding an aid: write its module, import it here, add it to :data:`MODELS`, to the dispatch of :func:`evaluate` and
:func:`_dispatch`, and to :data:`TIMED` or :data:`SAMPLED`; give :class:`~imunav.ins.gins.GinsConfig` its parameters and
:meth:`~imunav.ins.gins.GinsFilter.run` its input (``docs/design.md``, "How to add an aid").
"""

from __future__ import annotations

from collections import namedtuple
from functools import cache

import numpy as np
from numba import njit, types
from numba.extending import overload

from imunav.ins.gins.aids import (
    baro,
    dual_antenna,
    gnss_position,
    gnss_velocity,
    mag_heading,
    nhc,
    odometer,
    vehicle_level,
    zaru,
    zupt,
)

#: Registered models, in kind order (the kind of an aid is its index here).
MODELS = (gnss_position, gnss_velocity, odometer, nhc, zupt, zaru, baro, mag_heading, dual_antenna, vehicle_level)
AID_NAMES = tuple(m.NAME for m in MODELS)
#: Kind of each aid by name (``AID.gnss_position`` == 0 ...), a compile-time constant in the kernels.
AID = namedtuple("AidKind", AID_NAMES)(*range(len(MODELS)))
N_AIDS = len(MODELS)
#: Rows and measurement columns of each kind.
ROWS = np.array([m.ROWS for m in MODELS], dtype=np.int64)
WIDTH = np.array([m.WIDTH for m in MODELS], dtype=np.int64)

#: Aids at their own time stamps, one update each.
TIMED = ("gnss_position", "gnss_velocity", "dual_antenna")
#: Aids on the IMU grid, applied at the covariance epochs in this order; one tuple is one joint update.
SAMPLED = (("odometer", "nhc"), ("zupt", "zaru", "vehicle_level"), ("baro",), ("mag_heading",))


@njit(cache=True)
def evaluate(kind, xs, ctx, z, r, p, lay, H, R, nu, row):
    """Write the rows of the aid ``kind`` at ``row`` (see the module docstring for the arguments)."""
    if kind == AID.gnss_position:
        gnss_position.rows(xs, ctx, z, r, p, lay, H, R, nu, row)
    elif kind == AID.gnss_velocity:
        gnss_velocity.rows(xs, ctx, z, r, p, lay, H, R, nu, row)
    elif kind == AID.odometer:
        odometer.rows(xs, ctx, z, r, p, lay, H, R, nu, row)
    elif kind == AID.nhc:
        nhc.rows(xs, ctx, z, r, p, lay, H, R, nu, row)
    elif kind == AID.zupt:
        zupt.rows(xs, ctx, z, r, p, lay, H, R, nu, row)
    elif kind == AID.zaru:
        zaru.rows(xs, ctx, z, r, p, lay, H, R, nu, row)
    elif kind == AID.baro:
        baro.rows(xs, ctx, z, r, p, lay, H, R, nu, row)
    elif kind == AID.mag_heading:
        mag_heading.rows(xs, ctx, z, r, p, lay, H, R, nu, row)
    elif kind == AID.dual_antenna:
        dual_antenna.rows(xs, ctx, z, r, p, lay, H, R, nu, row)
    elif kind == AID.vehicle_level:
        vehicle_level.rows(xs, ctx, z, r, p, lay, H, R, nu, row)


def used(kinds) -> tuple:
    """The aid set of a kernel call: a tuple of :data:`N_AIDS` items, ``True`` at the kinds in ``kinds``, ``None``
    elsewhere (its numba type is the set: the kernel compiles once per set, with the rows of those aids only).

    Parameters
    ----------
    kinds : iterable of int
        The kinds of the aids the call may apply (timed and sampled; ``−1 − k`` for a withheld measurement of aid
        ``k``, which needs its rows too); ``range(N_AIDS)``: every aid.

    Returns
    -------
    tuple
        ``N_AIDS`` items, ``True`` or ``None``.
    """
    on = {int(k) if k >= 0 else -1 - int(k) for k in kinds}
    return tuple(True if k in on else None for k in range(N_AIDS))


#: every aid (:meth:`~imunav.ins.gins.GinsFilter.step`: the aids of a step are not known ahead)
ALL = used(range(N_AIDS))


def evaluate_used(use, kind, xs, ctx, z, r, p, lay, H, R, nu, row):
    """:func:`evaluate` for the aids of ``use`` (:func:`used`) only, in numba code; a kind outside ``use`` writes
    nothing (the kernel is never handed one).

    Parameters
    ----------
    use : tuple
        The aid set (:func:`used`): ``True`` at the kinds the kernel applies, ``None`` elsewhere.
    kind : int
        The aid whose rows to write (:data:`AID`).
    xs, ctx, z, r, p, lay : numpy.ndarray
        Nominal state, sample context, measurement, its variances, the aid's parameters and the state layout (the
        module docstring).
    H, R, nu : numpy.ndarray
        The measurement matrix, noise covariance and innovation, written at ``row``.
    row : int
        First row to write.

    Raises
    ------
    NotImplementedError
        Called from Python: it exists for numba code (its implementation is :func:`_dispatch`'s).
    """
    raise NotImplementedError("evaluate_used is for numba code; call evaluate")


@njit(cache=True)
def _absent(xs, ctx, z, r, p, lay, H, R, nu, row):
    """The rows of an aid a kernel does not use: none."""


@cache
def _dispatch(on: tuple[bool, ...]):
    """The body of :func:`evaluate_used` for the aid set ``on`` (one bool per kind): the rows of the aids on, a
    no-op for the others, so that numba types and compiles the used models only."""
    if len(on) != 10:
        raise AssertionError("aids._dispatch lists 10 aid models: add the new one")
    r0, r1, r2, r3, r4, r5, r6, r7, r8, r9 = (m.rows if o else _absent for m, o in zip(MODELS, on, strict=True))

    def impl(use, kind, xs, ctx, z, r, p, lay, H, R, nu, row):
        if kind == 0:
            r0(xs, ctx, z, r, p, lay, H, R, nu, row)
        elif kind == 1:
            r1(xs, ctx, z, r, p, lay, H, R, nu, row)
        elif kind == 2:
            r2(xs, ctx, z, r, p, lay, H, R, nu, row)
        elif kind == 3:
            r3(xs, ctx, z, r, p, lay, H, R, nu, row)
        elif kind == 4:
            r4(xs, ctx, z, r, p, lay, H, R, nu, row)
        elif kind == 5:
            r5(xs, ctx, z, r, p, lay, H, R, nu, row)
        elif kind == 6:
            r6(xs, ctx, z, r, p, lay, H, R, nu, row)
        elif kind == 7:
            r7(xs, ctx, z, r, p, lay, H, R, nu, row)
        elif kind == 8:
            r8(xs, ctx, z, r, p, lay, H, R, nu, row)
        elif kind == 9:
            r9(xs, ctx, z, r, p, lay, H, R, nu, row)

    return impl


@overload(evaluate_used)
def _evaluate_used(use, kind, xs, ctx, z, r, p, lay, H, R, nu, row):
    """numba's implementation of :func:`evaluate_used` for the type of ``use`` (the aid set)."""
    if isinstance(use, types.BaseTuple) and len(use) == N_AIDS:
        return _dispatch(tuple(not isinstance(t, types.NoneType) for t in use.types))
    return None
