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

Adding an aid: write its module, import it here, add it to :data:`MODELS`, to the dispatch of :func:`evaluate`
and to :data:`TIMED` or :data:`SAMPLED`; give :class:`~imunav.ins.gins.GinsConfig` its parameters and
:meth:`~imunav.ins.gins.GinsFilter.run` its input (``docs/design.md``, "How to add an aid").
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np
from numba import njit

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
