"""Loosely coupled GNSS/INS: an error-state Kalman filter on the NED strapdown, aided by GNSS and vehicle sensors.

:class:`GinsFilter` integrates IMU rates (:class:`~imunav.timeseries.ImuData`, with two-sample coning / sculling
corrections) or increments (:class:`~imunav.io.kfgins.ImuIncrements`) with
:func:`imunav.filters._core.strapdown_step_ned` and estimates 15 error states (position, velocity, attitude,
gyro and accelerometer biases) or 21 (plus scale factors), biases and scale factors being first-order
Gauss–Markov processes with configurable σ and correlation time (:class:`~imunav.ins.gins.GinsConfig`).  The aids
are the models of :mod:`imunav.ins.gins.aids` (GNSS position and velocity with the antenna lever arm at their own
time stamps; odometer + non-holonomic constraint, ZUPT + ZARU, barometric height and magnetometer heading on the
IMU grid), each behind a χ² gate with its NIS recorded.  ``GinsFilter(config).run(imu, gnss, ...)`` filters a
recording; ``reset(...)`` then ``step(t, dθ, dv, gnss=..., ...)`` runs the same kernel one increment at a time.
The equations are in :mod:`imunav.ins.gins.kernels` and in each aid's module.

Example
-------
>>> import numpy as np
>>> from imunav.ins.gins import GinsConfig, GinsFilter
>>> from imunav.sim import presets, simulate_imu
>>> from imunav.sim.gnss import simulate_gnss
>>> from imunav.sim.vehicle import demo_drive, vehicle_trajectory
>>> truth = vehicle_trajectory(demo_drive(120), fs=100)
>>> imu = simulate_imu(truth, presets.get("navigation_a15"), rng=1)
>>> gnss = simulate_gnss(truth, rng=2)
>>> cfg = GinsConfig.from_preset("navigation_a15")
>>> res = GinsFilter(cfg).run(imu, gnss, lla0=truth.pos_lla[0], vel0=truth.vel_ned[0], q0=truth.q_nb[0])
>>> bool(np.all(np.isfinite(res.lla)))
True
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav._quantiles import chi2_ppf
from imunav.earth import OMEGA_E
from imunav.errors import ConvergenceError, InvalidInputError, NonFiniteError, ShapeError
from imunav.ins.gins import aids, kernels
from imunav.ins.gins.config import GinsConfig
from imunav.ins.gins.layout import (
    CARRY,
    LAY,
    MAX_GROUP,
    MAX_ROWS,
    N_CARRY,
    N_CARRY_N,
    N_LAY,
    N_NOM,
    N_PRM,
    N_SENSOR_ERRORS,
    NOM,
    PRM,
    REQUIRED_BLOCKS,
    STATE_BLOCKS,
)
from imunav.ins.gins.result import AidRecord, GinsResult
from imunav.ins.gins.smoother import rts_smooth
from imunav.ins.strapdown import coning_sculling_increments
from imunav.io.aiding import BaroData, MagnetometerData, OdometerData
from imunav.io.gnss import GnssData
from imunav.io.gnss_heading import DualAntennaData
from imunav.io.kfgins import ImuIncrements
from imunav.rotation import quat_from_euler, quat_normalize, skew
from imunav.timeseries import ImuData

__all__ = ["GinsFilter"]

Array = NDArray[np.float64]


def _initial_state(lla0: ArrayLike, vel0: ArrayLike, q0: ArrayLike, imu_errors0: ArrayLike | None,
                   config: GinsConfig) -> Array:
    """The nominal state vector (layout ``NOM``) at the start (mounting, wheel lever arm and GNSS latency from
    ``config``)."""
    lla = np.array(lla0, dtype=float)
    if lla.shape != (3,) or not np.all(np.isfinite(lla)) or abs(lla[0]) >= np.pi / 2:
        raise InvalidInputError(f"lla0 must be (lat rad, lon rad, h m) with |lat| < pi/2; got {lla0!r}")
    v = np.array(vel0, dtype=float)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ShapeError(f"vel0 must be a finite 3-vector (NED m/s); got {vel0!r}")
    xs = np.zeros(N_NOM)
    xs[NOM.lla:NOM.lla + 3] = lla
    xs[NOM.vel:NOM.vel + 3] = v
    xs[NOM.q:NOM.q + 4] = quat_normalize(np.array(q0, dtype=float))
    if imu_errors0 is not None:
        e0 = np.asarray(imu_errors0, dtype=float)
        if e0.shape != (12,):
            raise ShapeError(f"imu_errors0 must have 12 values (bg, ba, sg, sa); got shape {e0.shape}")
        xs[NOM.gyro_bias:NOM.gyro_bias + 12] = e0
    xs[NOM.q_vb:NOM.q_vb + 4] = quat_from_euler(config.mounting)
    xs[NOM.odo_lever:NOM.odo_lever + 3] = config.odo_lever_arm
    xs[NOM.gnss_delay] = config.gnss_delay
    xs[NOM.gnss_r_scale] = 1.0
    xs[NOM.gnss_r_est] = 1.0
    xs[NOM.gnss_r_weight] = config.gnss_adaptive_prior_fixes * 3.0 / 2.0  # that many fixes of variance 2 / 3
    for nom, rows in ((NOM.odo_r_scale, 1), (NOM.nhc_r_scale, 2)):
        xs[nom:nom + 3] = 1.0, 1.0, config.wheel_adaptive_prior_updates * rows / 2.0
    return xs


def _state_blocks(c: GinsConfig, odometer: bool) -> tuple[str, ...]:
    """The error-state blocks a configuration estimates, in filter order."""
    use = set(REQUIRED_BLOCKS) | ({"gyro_scale", "accel_scale"} if c.scale_factors else set())
    if odometer:
        use.add("odo_scale")
        if c.odo_turn_std is not None:
            use.add("odo_turn")
    if c.side_slip_std is not None and c.nhc_noise_std is not None:
        use.add("side_slip")
    for block, sd in (("mount", c.mounting_std), ("odo_lever", c.odo_lever_arm_std), ("gnss_delay", c.gnss_delay_std),
                      ("gnss_bias", c.gnss_bias_std)):
        if sd is not None:
            use.add(block)
    if c.bias_model == "constant_and_gauss_markov":
        use |= {"gyro_bias_gm", "accel_bias_gm"}
    return tuple(name for name, _ in STATE_BLOCKS if name in use)


def kernel_setup(c: GinsConfig, fs: float, odometer: bool) -> tuple[Array, NDArray[np.int64], Array]:
    """The kernel's core and aid parameters ``prm``, its integer layout ``lay`` and the initial error covariance.

    ``lay`` holds the first index of each state block (−1 when not estimated), the state size, the covariance step
    in samples, then the offset of each aid's parameter block in ``prm`` (``lay[N_LAY + kind]``).

    Parameters
    ----------
    c : GinsConfig
        The configuration.
    fs : float
        IMU rate, Hz (sets the covariance step in samples).
    odometer : bool
        With the odometer scale-factor state.

    Returns
    -------
    prm : numpy.ndarray
        Core parameters (layout ``PRM``) followed by each aid's block.
    lay : numpy.ndarray of int
        The integer layout.
    P0 : numpy.ndarray, shape (n, n)
        Initial error covariance, in state order: diagonal, except that a bias made of a random constant and a
        Gauss–Markov part (``bias_model="constant_and_gauss_markov"``) has its whole bias (initial σ
        ``init_*_bias_std``) correlated with its Gauss–Markov part (σ ``*_bias_std``): ``cov(c + g, g) = σ_g²``.
    """
    sizes = dict(STATE_BLOCKS)
    lay = np.full(N_LAY + aids.N_AIDS, -1, dtype=np.int64)
    sd0: dict[str, Any] = {"pos": c.init_pos_std, "vel": c.init_vel_std, "att": c.init_att_std,
                           "gyro_bias": c.init_gyro_bias_std, "accel_bias": c.init_accel_bias_std,
                           "gyro_scale": c.init_gyro_scale_std, "accel_scale": c.init_accel_scale_std,
                           "odo_scale": [c.odo_scale_std], "mount": c.mounting_std, "odo_lever": c.odo_lever_arm_std,
                           "gnss_delay": [c.gnss_delay_std], "gyro_bias_gm": c.gyro_bias_std,
                           "accel_bias_gm": c.accel_bias_std, "gnss_bias": c.gnss_bias_std,
                           "odo_turn": [c.odo_turn_std], "side_slip": [c.side_slip_std]}
    nx = 0
    sd = []
    for name in _state_blocks(c, odometer):
        lay[getattr(LAY, name)] = nx
        nx += sizes[name]
        sd.append(np.asarray(sd0[name], dtype=float))
    lay[LAY.nx] = nx
    lay[LAY.cov_step] = max(1, int(round(c.cov_interval_s * fs)))
    lay[LAY.max_rejections] = c.gate_max_rejections
    names = [name for name, _ in STATE_BLOCKS]
    lay[LAY.consider] = sum(1 << names.index(b) for b in c.consider_states if lay[getattr(LAY, b)] >= 0)
    prm = np.zeros(N_PRM)
    prm[PRM.omega_e] = OMEGA_E
    prm[PRM.gyro_noise_density:PRM.gyro_noise_density + 3] = c.gyro_noise_density
    prm[PRM.accel_noise_density:PRM.accel_noise_density + 3] = c.accel_noise_density
    ts = c.corr_time if c.scale_corr_time is None else float(c.scale_corr_time)
    for name, sdv, tc in (("gyro_bias", c.gyro_bias_std, c.corr_time), ("accel_bias", c.accel_bias_std, c.corr_time),
                          ("gyro_scale", c.gyro_scale_std, ts), ("accel_scale", c.accel_scale_std, ts),
                          ("odo_scale", c.odo_scale_std,
                           c.corr_time if c.odo_scale_corr_time is None else float(c.odo_scale_corr_time))):
        n = sizes[name]
        q0, t0 = getattr(PRM, name + "_q"), getattr(PRM, name + "_t")
        prm[q0:q0 + n] = 2.0 * np.asarray(sdv) ** 2 / tc
        prm[t0:t0 + n] = tc
    if c.gnss_bias_std is not None:
        prm[PRM.gnss_bias_q:PRM.gnss_bias_q + 3] = 2.0 * np.asarray(c.gnss_bias_std) ** 2 / c.gnss_bias_corr_time
        prm[PRM.gnss_bias_t] = c.gnss_bias_corr_time
    if c.gnss_adaptive:
        prm[PRM.gnss_adapt] = 1.0 / c.gnss_adaptive_window
        prm[PRM.gnss_adapt + 1:PRM.gnss_adapt + 3] = c.gnss_adaptive_bounds
    if c.wheel_adaptive:
        prm[PRM.wheel_adapt] = 1.0 / c.wheel_adaptive_window
        prm[PRM.wheel_adapt + 1:PRM.wheel_adapt + 3] = c.wheel_adaptive_bounds
    for dof in range(1, MAX_ROWS + 1):
        prm[PRM.gate + dof - 1] = float(chi2_ppf(1 - c.gate_alpha, dof)) if c.gate_alpha > 0 else 1e300
    blocks = [prm]
    off = N_PRM
    for kind, model in enumerate(aids.MODELS):
        lay[N_LAY + kind] = off
        p = np.asarray(model.params(c), dtype=float)
        blocks.append(p)
        off += p.size
    var0 = np.concatenate(sd) ** 2
    P0 = np.diag(var0)
    j = np.arange(3)
    for whole, part in (("gyro_bias", "gyro_bias_gm"), ("accel_bias", "accel_bias_gm")):
        i, k = lay[getattr(LAY, whole)], lay[getattr(LAY, part)]
        if k >= 0:  # cov(c + g, g) = var g, at most var(c + g) (positive semi-definite)
            P0[i + j, k + j] = P0[k + j, i + j] = np.minimum(var0[i:i + 3], var0[k:k + 3])
    return np.concatenate(blocks), lay, P0


class _Timed:
    """Collects the timed aid measurements of a run and packs them in time order for the kernel."""

    def __init__(self) -> None:
        self.parts: list[tuple[int, Array, Array, Array, NDArray[np.int64]]] = []

    def add(self, name: str, t: Array, z: Array, r: Array, source: NDArray[np.int64] | None = None,
            withheld: bool = False) -> None:
        """Measurements of the aid ``name`` at times ``t``: ``z`` (k, w <= 3), covariance ``r`` (k, w, w);
        ``source``: the index of each in its input (default 0..k-1); ``withheld``: scored, not applied (kind
        ``−1 − k`` in the kernel's input)."""
        k = t.size
        zz = np.zeros((k, 3))
        rr = np.zeros((k, 3, 3))
        w = z.shape[1]
        zz[:, :w] = z
        rr[:, :w, :w] = r
        src = np.arange(k, dtype=np.int64) if source is None else source
        kind = int(getattr(aids.AID, name))
        self.parts.append((-1 - kind if withheld else kind, np.asarray(t, dtype=float), zz, rr, src))

    def pack(self) -> tuple[kernels.TimedInput, NDArray[np.int64]]:
        """The kernel input (stable time order: measurements at one stamp in the order they were added) and the
        source index of each."""
        if not self.parts:
            return kernels.TimedInput(np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros((0, 3)),
                                      np.zeros((0, 3, 3))), np.zeros(0, dtype=np.int64)
        t = np.concatenate([p[1] for p in self.parts])
        order = np.argsort(t, kind="stable")
        kind = np.concatenate([np.full(p[1].size, p[0], dtype=np.int64) for p in self.parts])
        z = np.concatenate([p[2] for p in self.parts])
        r = np.concatenate([p[3] for p in self.parts])
        src = np.concatenate([p[4] for p in self.parts])
        return (kernels.TimedInput(np.ascontiguousarray(t[order]), kind[order], np.ascontiguousarray(z[order]),
                                   np.ascontiguousarray(r[order])), src[order])


def _sampled(n: int, columns: dict[str, Array], force: Array) -> kernels.SampledInput:
    """The sampled aids' kernel input from ``columns`` (aid name -> (N, WIDTH) array, NaN where the aid has no
    measurement), in the group order of :data:`imunav.ins.gins.aids.SAMPLED` (aids absent from ``columns`` are
    left out)."""
    kind, col, group, blocks = [], [], [], []
    c = 0
    for g, names in enumerate(aids.SAMPLED):
        for name in names:
            if name in columns:
                a = np.asarray(columns[name], dtype=float).reshape(n, -1)
                kind.append(getattr(aids.AID, name))
                col.append(c)
                group.append(g)
                blocks.append(a)
                c += a.shape[1]
    z = np.ascontiguousarray(np.hstack(blocks)) if blocks else np.zeros((n, 0))
    as_int = lambda x: np.asarray(x, dtype=np.int64)  # noqa: E731
    return kernels.SampledInput(z, np.ascontiguousarray(force, dtype=bool), as_int(kind), as_int(col), as_int(group))


def _output(n: int, nx: int, mmax: int, nlog: int, nrec: int) -> kernels.KernelOutput:
    """Preallocated kernel outputs."""
    return kernels.KernelOutput(
        xs=np.empty((n, N_NOM)), cov_t=np.empty(mmax), cov_diag=np.empty((mmax, nx)), cov_nav=np.empty((mmax, 9, 9)),
        log_t=np.empty(nlog), log_k=np.empty(nlog, dtype=np.int64), log_src=np.empty(nlog, dtype=np.int64),
        log_rows=np.empty(nlog, dtype=np.int64), log_ok=np.empty(nlog, dtype=np.bool_), log_nis=np.empty(nlog),
        log_blk=np.empty((nlog, MAX_GROUP)), log_lds=np.full(nlog, np.nan), rec_t=np.zeros(nrec), rec_phi=np.zeros((nrec, nx, nx)),
        rec_ppri=np.zeros((nrec, nx, nx)), rec_ppost=np.zeros((nrec, nx, nx)), rec_inj=np.zeros((nrec, nx)),
        rec_state=np.zeros((nrec, 10)))


@dataclass
class _Log:
    """The kernel's update log, split by aid: one :class:`~imunav.ins.gins.result.AidRecord` per aid that was
    applied, and the joint record of each sampled group."""

    aids: dict[str, AidRecord] = field(default_factory=dict)
    groups: dict[tuple[str, ...], AidRecord] = field(default_factory=dict)
    timed_index: dict[str, NDArray[np.int64]] = field(default_factory=dict)


def _split_log(o: kernels.KernelOutput, nlog: int, timed_kind: NDArray[np.int64], timed_src: NDArray[np.int64],
               sampled: kernels.SampledInput) -> _Log:
    """Split the update log into per-aid records (a model in a joint update: the NIS of its own rows, the gate
    decision of the joint update)."""
    out = _Log()
    t, k, src = o.log_t[:nlog], o.log_k[:nlog], o.log_src[:nlog]
    rows, ok, d, blk = o.log_rows[:nlog], o.log_ok[:nlog], o.log_nis[:nlog], o.log_blk[:nlog]
    timed = src >= 0
    kind_t = np.where(timed, timed_kind[np.where(timed, src, 0)] if timed_kind.size else -1, -1)
    for name in aids.TIMED:
        a = getattr(aids.AID, name)
        sel = timed & (kind_t == a)
        if sel.any():
            out.aids[name] = AidRecord(t[sel], d[sel], rows[sel], ok[sel], k[sel])
            out.timed_index[name] = timed_src[src[sel]]
        sel = timed & (kind_t == -1 - a)  # withheld: scored, not applied
        if sel.any():
            out.aids[f"{name}_withheld"] = AidRecord(t[sel], d[sel], rows[sel], ok[sel], k[sel],
                                                     o.log_lds[:nlog][sel])
    for g, names in enumerate(aids.SAMPLED):
        sel = src == -1 - g
        if not sel.any():
            continue
        out.groups[names] = AidRecord(t[sel], d[sel], rows[sel], ok[sel], k[sel])
        present = [nm for nm in names if getattr(aids.AID, nm) in sampled.kind]
        for pos, name in enumerate(present):
            s = sel & np.isfinite(blk[:, pos])
            if s.any():
                w = int(aids.ROWS[getattr(aids.AID, name)])
                out.aids[name] = AidRecord(t[s], blk[s, pos], np.full(int(s.sum()), w), ok[s], k[s])
    return out


def _per_sample(n: int, rec: AidRecord | None) -> Array:
    """An aid's NIS per IMU sample, NaN where it was not applied."""
    a = np.full(n, np.nan)
    if rec is not None:
        a[rec.sample] = rec.nis
    return a


#: IMU samples per kernel call when :meth:`GinsFilter.run` reports progress (about 5 min at 200 Hz; one call is some
#: 20 ms of the filter).
PROGRESS_CHUNK = 65536

#: GinsResult's per-sample NIS fields: field prefix -> (an aid of the sampled group, the aid whose own NIS it is or
#: None for the group's joint statistic)
_SAMPLE_NIS = {"zupt": ("zupt", None), "baro": ("baro", None), "mag": ("mag_heading", None),
               "odo": ("odometer", "odometer"), "nhc": ("odometer", "nhc"), "zupt_vel": ("zupt", "zupt"),
               "zaru": ("zupt", "zaru")}


def _increments(imu: ImuData | ImuIncrements) -> tuple[Array, Array, Array]:
    if isinstance(imu, ImuIncrements):
        dth = np.array(imu.dtheta, dtype=float)
        dv = np.array(imu.dvel, dtype=float)
        # two-sample coning / sculling and rotation compensation on the increments (Savage 1998)
        c = np.zeros_like(dth)
        s = np.zeros_like(dv)
        c[1:] = np.cross(dth[:-1], dth[1:]) / 12.0
        s[1:] = (np.cross(dth[:-1], dv[1:]) + np.cross(dv[:-1], dth[1:])) / 12.0
        dv_out = dv + 0.5 * np.cross(dth, dv) + s
        return np.ascontiguousarray(imu.t, dtype=float), dth + c, dv_out
    if isinstance(imu, ImuData):
        dth, dv = coning_sculling_increments(imu, True)
        return np.ascontiguousarray(imu.t, dtype=float), dth, dv
    raise InvalidInputError(f"imu must be an ImuData (rates) or ImuIncrements; got {type(imu).__name__}")


def _on_imu_grid(t: Array, aid: Any, kind: type, name: str, field_name: str) -> Array:
    """An aiding series (odometer speed, barometric height) interpolated to the IMU stamps inside its span,
    NaN outside."""
    out = np.full(t.size, np.nan)
    if not isinstance(aid, kind):
        raise InvalidInputError(f"{name} must be a {kind.__name__}; got {type(aid).__name__}")
    at = np.asarray(aid.t, dtype=float)
    if at.size < 2 or np.any(np.diff(at) <= 0):
        raise InvalidInputError(f"{name} time stamps must be strictly increasing (at least 2 samples)")
    inside = (t >= at[0]) & (t <= at[-1])
    if not inside.any():
        raise InvalidInputError(f"{name} time {at[0]:.3f}..{at[-1]:.3f} s lies outside the IMU span")
    out[inside] = np.interp(t[inside], at, np.asarray(getattr(aid, field_name), dtype=float))
    return out


def _interpolated_variance(t: Array, at: Array, var: Array) -> Array:
    """Variance of a series of independent samples (variances ``var`` at stamps ``at``) linearly interpolated to
    the IMU stamps ``t``: ``(1 − w)² σ_k² + w² σ_{k+1}²`` with ``w = (t − t_k) / (t_{k+1} − t_k)``, NaN outside
    the span.  Between two samples it falls to half a sample's variance: the update at an interpolated value
    must not assume the full σ (its NIS would sit near 2/3 of its χ² mean)."""
    out = np.full(t.size, np.nan)
    inside = (t >= at[0]) & (t <= at[-1])
    ti = t[inside]
    k = np.clip(np.searchsorted(at, ti, side="right") - 1, 0, at.size - 2)
    w = (ti - at[k]) / (at[k + 1] - at[k])
    out[inside] = (1.0 - w) ** 2 * var[k] + w**2 * var[k + 1]
    return out


def _at_imu_samples(t: Array, aid: Any, kind: type, name: str, field_name: str) -> Array:
    """Aiding samples (barometer, magnetometer) placed at the nearest IMU stamp (not interpolated: interpolating
    white noise between two samples would shrink its variance below the σ the update assumes), NaN elsewhere."""
    if not isinstance(aid, kind):
        raise InvalidInputError(f"{name} must be a {kind.__name__}; got {type(aid).__name__}")
    at = np.asarray(aid.t, dtype=float)
    if at.size < 2 or np.any(np.diff(at) <= 0):
        raise InvalidInputError(f"{name} time stamps must be strictly increasing (at least 2 samples)")
    half = 0.5 * float(np.median(np.diff(t)))
    inside = (at >= t[0] - half) & (at <= t[-1] + half)
    if not inside.any():
        raise InvalidInputError(f"{name} time {at[0]:.3f}..{at[-1]:.3f} s lies outside the IMU span")
    k = np.clip(np.searchsorted(t, at[inside]), 1, t.size - 1)
    k = np.where(np.abs(t[k - 1] - at[inside]) < np.abs(t[k] - at[inside]), k - 1, k)
    if np.any(np.diff(k) == 0):
        raise InvalidInputError(f"{name}: two samples fall on one IMU sample (rate above the IMU rate); "
                                "decimate or average it first")
    val = np.asarray(getattr(aid, field_name), dtype=float)
    out = np.full((t.size,) + val.shape[1:], np.nan)
    out[k] = val[inside]
    return out


def _vec3_input(x: ArrayLike, name: str) -> Array:
    a = np.asarray(x, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ShapeError(f"GinsFilter: {name} must be a finite 3-vector; got {x!r}")
    return a


def _check_finite(t: np.ndarray, xs: np.ndarray, cov_t: np.ndarray, cov_diag: np.ndarray, c: GinsConfig) -> None:
    """Raise :class:`ConvergenceError` where the filter's state or covariance stopped being finite (a run that
    overflowed: every later fix is rejected and the σ written are NaN, a solution that only looks complete)."""
    bad_cov = ~np.isfinite(cov_diag).all(axis=1)
    bad_x = ~np.isfinite(xs).all(axis=1)
    if not (bad_cov.any() or bad_x.any()):
        return
    when = min(float(cov_t[np.argmax(bad_cov)]) if bad_cov.any() else np.inf,
               float(t[np.argmax(bad_x)]) if bad_x.any() else np.inf)
    noise = ", ".join(f"{k} {np.max(np.atleast_1d(getattr(c, k))):.3g}" for k in
                      ("gyro_noise_density", "accel_noise_density", "gyro_bias_std", "accel_bias_std"))
    raise ConvergenceError(f"GinsFilter.run diverged: its {'covariance' if bad_cov.any() else 'state'} is not finite "
                           f"from t = {when - float(t[0]):.6g} s after the first sample on; a noise or initial sigma "
                           f"of the configuration is far outside any IMU's (largest: {noise})")


class GinsFilter:
    """The loosely coupled GNSS/INS filter: :meth:`run` over a recording, or :meth:`reset` then :meth:`step`
    sample by sample (the same numba kernel, :func:`imunav.ins.gins.kernels.gins_run`, for both).

    The loosely coupled INS/GNSS integration of Groves (*Principles of GNSS, Inertial, and Multisensor
    Integrated Navigation Systems*, 2nd ed., Artech House 2013, ch. 14): closed-loop error-state Kalman
    filter, the estimated errors fed back into the nominal state after each update.

    Parameters
    ----------
    config : GinsConfig
        Noise model, initial σ, lever arms, aids and gates.

    Attributes
    ----------
    t : float
        Time of the current state, s (after :meth:`reset` / :meth:`step` / :meth:`run`); the state itself is in
        the properties :attr:`lla`, :attr:`vel_ned`, :attr:`q_nb`, :attr:`imu_errors` and :attr:`mounting`.
    P : numpy.ndarray, shape (n, n)
        Current error-state covariance (:data:`~imunav.ins.gins.STATE_NAMES`, then the odometer scale and, with
        ``GinsConfig.odo_turn_std``, the odometer's over-reading in turns last).
    last_nis : dict
        NIS of the updates of the last :meth:`step`: ``gnss`` (G, 2) position / velocity, ``vehicle``,
        ``zupt``, ``baro``, ``mag``, and each model alone: ``odo``, ``nhc``, ``zupt_vel``, ``zaru`` (NaN when
        not applied).

    Raises
    ------
    InvalidInputError
        If ``config`` is not a :class:`GinsConfig`.
    """

    def __init__(self, config: GinsConfig) -> None:
        if not isinstance(config, GinsConfig):
            raise InvalidInputError(f"GinsFilter needs a GinsConfig; got {type(config).__name__}")
        self.config = config
        self._prm: Array | None = None
        self._xs = np.zeros(N_NOM)
        self.last_nis: dict[str, Any] = {}

    @property
    def lla(self) -> Array:
        """Current position: lat rad, lon rad, ellipsoidal height m."""
        return self._xs[NOM.lla:NOM.lla + 3]

    @property
    def vel_ned(self) -> Array:
        """Current NED velocity, m/s."""
        return self._xs[NOM.vel:NOM.vel + 3]

    @property
    def q_nb(self) -> Array:
        """Current attitude, body FRD -> NED, scalar first."""
        return self._xs[NOM.q:NOM.q + 4]

    @property
    def imu_errors(self) -> Array:
        """Current gyro bias (rad/s), accel bias (m/s²), gyro scale, accel scale, odometer scale (13 values)."""
        return self._xs[NOM.gyro_bias:NOM.gyro_bias + N_SENSOR_ERRORS]

    @property
    def mounting(self) -> Array:
        """Current IMU mounting ``q_vb`` (IMU FRD -> vehicle FRD, scalar first)."""
        return self._xs[NOM.q_vb:NOM.q_vb + 4]

    def reset(self, *, lla0: ArrayLike, vel0: ArrayLike, q0: ArrayLike, t0: float, fs: float,
              imu_errors0: ArrayLike | None = None, odometer: bool = False, dtheta0: ArrayLike | None = None,
              dvel0: ArrayLike | None = None) -> None:
        """Set the state the next :meth:`step` starts from (covariance back to the configured initial σ).

        Parameters
        ----------
        lla0, vel0, q0 : array_like, shapes (3,), (3,), (4,)
            Initial position (lat rad, lon rad, h m), NED velocity (m/s) and ``q_nb`` (body FRD -> NED,
            scalar first) at ``t0``.
        t0 : float
            Time of the initial state, s.
        fs : float
            IMU rate, Hz (> 0): sets the covariance step ``cov_interval_s`` in samples.
        imu_errors0 : array_like, shape (12,), optional
            Initial gyro bias (rad/s), accel bias (m/s²), gyro scale, accel scale (default zeros).
        odometer : bool
            Add the odometer scale-factor state, and the over-reading in turns unless ``odo_turn_std`` is None (to
            use ``odometer_speed`` in :meth:`step`).
        dtheta0, dvel0 : array_like, shape (3,), optional
            The raw increments ending at ``t0`` (for the two-sample coning / sculling of the first step;
            default zeros).

        Raises
        ------
        InvalidInputError
            If ``lla0`` is not a position in radians or ``fs`` is not > 0.
        ShapeError
            If ``vel0`` or ``imu_errors0`` has the wrong shape.
        """
        if not (np.isfinite(fs) and fs > 0):
            raise InvalidInputError(f"GinsFilter.reset: fs must be > 0 Hz; got {fs!r}")
        self._xs = _initial_state(lla0, vel0, q0, imu_errors0, self.config)
        self._prm, self._lay, self.P = kernel_setup(self.config, float(fs), odometer)
        self.t = float(t0)
        self._t0 = self.t  # the origin of the NHC's intervals (GinsConfig.nhc_interval_s)
        self._last_fix = -math.inf  # the stamp of the last GNSS fix handed to step()
        self._carry = np.zeros(N_CARRY)
        self._carry_n = np.zeros(N_CARRY_N, dtype=np.int64)
        self._carry[CARRY.t_cov] = self.t
        self._carry[CARRY.t_raw] = self.t
        self._prev = np.zeros((2, 3))
        for row, x, name in ((0, dtheta0, "dtheta0"), (1, dvel0, "dvel0")):
            if x is not None:
                self._prev[row] = _vec3_input(x, name)
        self._odometer = bool(odometer)
        self.last_nis = {}

    def step(self, t: float, dtheta: ArrayLike, dvel: ArrayLike, *, gnss: GnssData | None = None,
             odometer_speed: float | None = None, static: bool = False, baro_height: float | None = None,
             mag_field: ArrayLike | None = None) -> None:
        """Process one IMU increment over ``(self.t, t]`` and the aiding measurements of that interval.

        The state attributes (``lla``, ``vel_ned``, ``q_nb``, ``imu_errors``, ``P``, ``t``) are updated in
        place; :meth:`run` over the same increments gives the same result.

        Parameters
        ----------
        t : float
            End time of the increment, s (> ``self.t``).
        dtheta, dvel : array_like, shape (3,)
            Raw angle (rad) and velocity (m/s) increments over ``(self.t, t]``, body FRD (coning / sculling
            applied here, as :meth:`run` does for :class:`~imunav.io.kfgins.ImuIncrements`).
        gnss : GnssData, optional
            Fixes; those stamped inside ``(self.t, t]`` are used at their own time stamps.
        odometer_speed : float, optional
            Wheel speed at ``t``, m/s (needs ``reset(..., odometer=True)``).
        static : bool
            The vehicle stands still at ``t``: ZUPT + ZARU.
        baro_height : float, optional
            Barometric height at ``t``, m.
        mag_field : array_like, shape (3,), optional
            Calibrated magnetometer sample at ``t``, body frame (any unit): heading update.

        Raises
        ------
        InvalidInputError
            Before :meth:`reset`, if ``t`` is not after the current time, or with an odometer speed and no
            odometer state.
        ShapeError
            If an increment is not a finite 3-vector.
        NonFiniteError
            If ``odometer_speed`` or ``baro_height`` is given but not finite.
        """
        if self._prm is None:
            raise InvalidInputError("GinsFilter.step before reset(): call reset(lla0=..., t0=..., fs=...) first")
        t = float(t)
        if not t > self.t:
            raise InvalidInputError(f"GinsFilter.step: t = {t!r} s is not after the current time {self.t!r} s")
        if odometer_speed is not None and not self._odometer:
            raise InvalidInputError("GinsFilter.step: odometer_speed needs reset(..., odometer=True)")
        raw = np.vstack([self._prev, _vec3_input(dtheta, "dtheta"), _vec3_input(dvel, "dvel")])
        dth = np.array([raw[0], raw[2]])
        dv = np.array([raw[1], raw[3]])
        _, dth, dv = _increments(ImuIncrements(np.array([self.t, t]), dth, dv, np.full(2, t - self.t)))
        self._prev = raw[2:]
        for name, v in (("odometer_speed", odometer_speed), ("baro_height", baro_height)):
            if v is not None and not math.isfinite(float(v)):
                raise NonFiniteError(f"GinsFilter.step: {name} = {v!r} is not finite; pass None when there is no "
                                     "sample at this time")
        sl = slice(0, 0)
        if gnss is not None:
            i0, i1 = np.searchsorted(gnss.t, [self.t, t], side="right")
            sl = slice(int(i0), int(i1))
        odo = np.array([np.nan, np.nan if odometer_speed is None else float(odometer_speed)])
        baro = np.array([np.nan, np.nan if baro_height is None else float(baro_height)])
        mag = np.full((2, 3), np.nan)
        if mag_field is not None:
            mag[1] = _vec3_input(mag_field, "mag_field")
        tt = np.array([self.t, t])
        timed = self._timed(gnss, sl)
        if gnss is not None and sl.stop > sl.start:
            self._last_fix = float(gnss.t[sl.stop - 1])
        sampled = self._sampled(tt, odo if self._odometer else None, np.array([False, bool(static)]), baro, mag,
                                fix_age=tt - self._last_fix)
        log, _ = self._kernel(tt, dth, dv, timed, sampled, 0, False, False)
        self.t = t
        nis = np.full((sl.stop - sl.start, 2), np.nan)
        for col, name in enumerate(aids.TIMED[:2]):
            if name in log.aids:
                nis[log.timed_index[name], col] = log.aids[name].nis
        veh = log.groups.get(next(g for g in aids.SAMPLED if "odometer" in g))
        self.last_nis = {"gnss": nis, "vehicle": float(veh.nis[0]) if veh is not None else math.nan}
        self.last_nis.update({name: float(_sample_nis(log, name, 2)[1]) for name in _SAMPLE_NIS})

    def _timed(self, g: GnssData | None, sl: slice, dual: DualAntennaData | None = None, t0: float = 0.0,
               t1: float = 0.0, withheld: GnssData | None = None
               ) -> tuple[kernels.TimedInput, NDArray[np.int64], NDArray[np.int64]]:
        """The GNSS fixes ``g[sl]`` (position, then velocity when configured and given), the dual-antenna
        epochs inside ``(t0, t1]`` and the ``withheld`` fixes' positions (scored, not applied) as timed aid
        measurements, their kinds and their indices in their inputs."""
        tm = _Timed()
        if withheld is not None and withheld.n:
            tm.add("gnss_position", withheld.t, withheld.lla, _diag(withheld.pos_std ** 2), withheld=True)
        if g is not None and sl.stop > sl.start:
            tm.add("gnss_position", g.t[sl], g.lla[sl], _diag(g.pos_std[sl] ** 2))
            if self.config.use_gnss_velocity and g.vel_ned is not None:
                tm.add("gnss_velocity", g.t[sl], g.vel_ned[sl], _diag(g.vel_std[sl] ** 2))
        if dual is not None:
            if not isinstance(dual, DualAntennaData):
                raise InvalidInputError(f"dual_antenna must be a DualAntennaData; got {type(dual).__name__}")
            z, r = dual.measurements(self.config.dual_antenna_baseline)
            idx = np.flatnonzero((dual.t > t0) & (dual.t <= t1))
            if idx.size == 0:
                raise InvalidInputError(f"dual_antenna time {dual.t[0]:.3f}..{dual.t[-1]:.3f} s lies outside the IMU "
                                        f"span {t0:.3f}..{t1:.3f} s")
            tm.add("dual_antenna", dual.t[idx], z[idx], r[idx], idx)
        packed, src = tm.pack()
        return packed, packed.kind, src

    def _sampled(self, t: Array, odo: Array | None, static: Array, baro: Array, mag: Array,
                 odo_var: Array | None = None, fix_age: Array | None = None) -> kernels.SampledInput:
        """The aids on the IMU grid ``t``: odometer (speed, variance) and NHC while moving, ZUPT + ZARU while
        static, barometer and magnetometer where they have a sample (which forces a covariance epoch there); the
        levelling at rest once per rest interval, at its middle sample (a covariance epoch there): the slope of one
        stop is one measurement, however long the vehicle stands.  With ``nhc_interval_s`` the NHC is applied at
        the first sample of each interval since the run's start (a covariance epoch there) while GNSS fixes arrive
        (``fix_age``, the age of the last fix at each sample, at most two intervals), at every covariance step
        otherwise; on :meth:`run`'s grid and :meth:`step`'s alike."""
        c = self.config
        n = t.size
        cols: dict[str, Array] = {}
        moving = np.where(static, np.nan, 0.0)
        if odo is not None:
            v0 = c.odo_noise_std**2
            var = np.full(n, v0) if odo_var is None else np.where(np.isnan(odo_var), v0, odo_var)
            cols["odometer"] = np.column_stack([odo + moving, var])
        force = np.zeros(n, dtype=bool)
        if c.nhc_noise_std is not None:
            if c.nhc_interval_s is None:
                cols["nhc"] = moving
            else:
                b = np.floor((t - self._t0) / c.nhc_interval_s + 1e-9)
                first = np.r_[False, b[1:] != b[:-1]]
                fixes = np.zeros(n, dtype=bool) if fix_age is None else fix_age <= 2.0 * c.nhc_interval_s
                cols["nhc"] = np.where(first | ~fixes, moving, np.nan)
                force |= first & fixes & ~static
        if static.any():
            rest = np.where(static, 0.0, np.nan)
            cols["zupt"] = rest
            cols["zaru"] = rest
        if static.any() and c.level_noise_std is not None:
            edges = np.flatnonzero(np.diff(np.r_[0, static.astype(np.int8), 0]))
            mid = (edges[0::2] + edges[1::2] - 1) // 2
            level = np.full(n, np.nan)
            level[mid] = 0.0
            force[mid] = True
            cols["vehicle_level"] = level
        has_baro = ~np.isnan(baro)
        has_mag = ~np.isnan(mag[:, 0])
        if has_baro.any():
            cols["baro"] = baro
        if has_mag.any():
            cols["mag_heading"] = mag
        return _sampled(n, cols, force | has_baro | has_mag)

    def _kernel(self, t: Array, dth: Array, dv: Array, timed: tuple[kernels.TimedInput, Any, Any],
                sampled: kernels.SampledInput, nrec: int, first: bool, final: bool,
                progress: Callable[[int, int], None] | None = None, use: tuple = aids.ALL) -> tuple[_Log, Any]:
        """The kernel from the current state over ``t`` (the state at t[0]), in place.

        With ``progress`` the samples go through in chunks of :data:`PROGRESS_CHUNK`, ``progress(done, n)`` after
        each: one kernel carries its state (nominal, covariance, clock) from call to call, and each chunk writes
        into its own slice of the one set of outputs, so the result is the one of a single call, bit for bit.
        ``use``: the aids the kernel may apply (:func:`imunav.ins.gins.aids.used`; the kernel is compiled once per
        set, with those aids' models only): every aid by default (:meth:`step`), those of its inputs for :meth:`run`."""
        packed, kind, src = timed
        n, nx = t.size, self.P.shape[0]
        cs = int(self._lay[LAY.cov_step])
        nforce = int(np.count_nonzero(sampled.force))
        mmax = n // cs + 3 + nforce
        nlog = packed.t.size + (mmax + packed.t.size) * len(aids.SAMPLED)
        o = _output(n, nx, mmax, nlog, nrec)
        c = np.ascontiguousarray
        t, dth, dv = c(t), c(dth), c(dv)
        chunk = n if progress is None else PROGRESS_CHUNK  # without a report: one call over every sample
        # a run without timed measurements hands the kernel None: numba compiles no timed update (step: every aid)
        tin = None if use is not aids.ALL and packed.t.size == 0 else packed
        m = r = L = 0
        a = 0  # each chunk starts at the last sample of the one before (its state)
        while a < n - 1:
            b = min(a + chunk, n - 1)
            sl = slice(a, b + 1)
            part = sampled._replace(z=sampled.z[sl], force=sampled.force[sl])
            # smoother records: a chunk's record 0 is the previous chunk's last epoch (not rewritten, first=False)
            r0 = max(r - 1, 0)
            view = o._replace(xs=o.xs[sl], cov_t=o.cov_t[m:], cov_diag=o.cov_diag[m:], cov_nav=o.cov_nav[m:],
                              log_t=o.log_t[L:], log_k=o.log_k[L:], log_src=o.log_src[L:], log_rows=o.log_rows[L:],
                              log_ok=o.log_ok[L:], log_nis=o.log_nis[L:], log_blk=o.log_blk[L:],
                              log_lds=o.log_lds[L:],
                              **{f: getattr(o, f)[r0:] for f in ("rec_t", "rec_phi", "rec_ppri", "rec_ppost",
                                                                  "rec_inj", "rec_state")})
            dm, dr, dL = kernels.gins_run(kernels.ImuInput(t[sl], dth[sl], dv[sl]), tin, part, self._xs, self.P,
                                          self._carry, self._carry_n, self._prm, self._lay, view, first and a == 0,
                                          final and b == n - 1, use)
            o.log_k[L:L + dL] += a  # the kernel logs its own sample index
            m, L = m + dm, L + dL
            r = r0 + dr if nrec else 0
            a = b
            if progress is not None:
                progress(b + 1, n)
        return _split_log(o, L, kind, src, sampled), (o, m, r)

    def run(self, imu: ImuData | ImuIncrements, gnss: GnssData | None, *, lla0: ArrayLike, vel0: ArrayLike,
            q0: ArrayLike, imu_errors0: ArrayLike | None = None, odometer: OdometerData | None = None,
            smoother: bool = False, static: ArrayLike | None = None, baro: BaroData | None = None,
            mag: MagnetometerData | None = None, dual_antenna: DualAntennaData | None = None,
            progress: Callable[[int, int], None] | None = None, gnss_withheld: GnssData | None = None) -> GinsResult:
        """Run the filter forward over the IMU recording (from a :meth:`reset` at its first sample).

        Parameters
        ----------
        imu : ImuData or ImuIncrements
            Rates (rad/s, m/s², body FRD; coning / sculling applied) or increments (Δθ rad, Δv m/s).
        gnss : GnssData or None
            The fixes; those outside the IMU span, or at its first sample, are removed (recorded in ``meta``),
            none inside is an error.  None: no GNSS (dead reckoning with the other aids).
        lla0, vel0, q0 : array_like, shapes (3,), (3,), (4,)
            Initial position (lat rad, lon rad, h m), NED velocity (m/s) and ``q_nb`` (body FRD -> NED,
            scalar first) at ``imu.t[0]``.
        imu_errors0 : array_like, shape (12,), optional
            Initial gyro bias (rad/s), accel bias (m/s²), gyro scale, accel scale (default zeros).
        odometer : OdometerData, optional
            Wheel speeds (:class:`imunav.io.aiding.OdometerData`), interpolated to the IMU stamps inside
            their span; adds the odometer scale-factor state.  Their ``speed_std`` (when given) is each
            sample's σ, else ``config.odo_noise_std``; an interpolated speed has the variance of the interpolation,
            ``(1 − w)² σ_k² + w² σ_{k+1}²``.
        smoother : bool
            Also run the RTS smoother (``result.smoothed``); keeps three n x n matrices per covariance epoch
            (about 190 MB per hour at 200 Hz with 21 states and the default 0.2 s step).
        static : array_like of bool, shape (N,), optional
            True where the vehicle stands still (e.g. from :mod:`imunav.ins.zupt.detectors`): ZUPT + ZARU.
        baro : BaroData, optional
            Barometric heights (:class:`imunav.sim.vehicle.BaroData`), each used at the nearest IMU stamp (a
            covariance epoch there).
        mag : MagnetometerData, optional
            Calibrated magnetometer (:class:`imunav.sim.gnss.MagnetometerData`): heading updates
            (``config.declination``, ``config.mag_heading_noise_std``), each at the nearest IMU stamp.
        dual_antenna : DualAntennaData, optional
            Baseline heading and pitch of a dual-antenna GNSS receiver at its own time stamps (needs
            ``config.dual_antenna_baseline``); those outside the IMU span or at its first sample are not used.
        progress : callable, optional
            ``progress(done, total)`` as the filter goes through the samples (every :data:`PROGRESS_CHUNK` of
            them; the result is the same bit for bit), and once more after the smoother: ``total`` is the number of
            samples, twice that with ``smoother`` (the smoother's pass counts as many).
        gnss_withheld : GnssData, optional
            Fixes the run predicts without using them (a cross-validation on withheld fixes): at each one inside
            the IMU span the filter computes the position innovation ``ν`` and its covariance ``S = H P Hᵀ + R``
            as for a fix it applies (the correlated error's estimate, the latency, the adaptive factor of ``R``
            included) and records its NIS and ``ln det S`` in ``aids['gnss_position_withheld']``
            (:class:`~imunav.ins.gins.result.AidRecord`); the state and covariance are not updated.

        Returns
        -------
        GinsResult
            The filtered trajectory, IMU errors, covariance records and the NIS of every update.

        Raises
        ------
        InvalidInputError
            If there are fewer than 2 IMU samples, ``lla0`` is not a position in radians, the odometer or
            barometer is not of its type or does not overlap the IMU span, or an aiding σ is not > 0 (also:
            no GNSS fix inside the IMU span).
        ShapeError
            If ``vel0``, ``imu_errors0`` or ``static`` has the wrong shape.
        ConvergenceError
            If the covariance or the state is not finite (a noise or initial σ far outside any IMU's, e.g. a
            noise profile's 1e300: the numbers overflow; the filter would reject every fix and write NaN σ).
        """
        t, dth, dv = _increments(imu)
        if t.size < 2:
            raise InvalidInputError("GinsFilter.run needs at least 2 IMU samples")
        g: GnssData | None = None
        if gnss is not None:
            g = gnss.within(float(t[0]), float(t[-1]))
            g = g.select(g.t > t[0], "at the first IMU sample (the initial state stands for it)")
        ng = 0 if g is None else g.n
        n = t.size
        odo = None if odometer is None else _on_imu_grid(t, odometer, OdometerData, "odometer", "speed")
        odo_var = None
        if odometer is not None:
            sd = self.config.odo_noise_std if odometer.speed_std is None else np.asarray(odometer.speed_std, dtype=float)
            ot = np.asarray(odometer.t, dtype=float)
            odo_var = _interpolated_variance(t, ot, np.square(sd) * np.ones(ot.size))
        st = np.zeros(n, dtype=bool) if static is None else np.asarray(static, dtype=bool)
        if st.shape != (n,):
            raise ShapeError(f"static must be (N,) = ({n},) booleans, one per IMU sample; got {st.shape}")
        hb = np.full(n, np.nan) if baro is None else _at_imu_samples(t, baro, BaroData, "baro", "height")
        mg = np.full((n, 3), np.nan) if mag is None else _at_imu_samples(t, mag, MagnetometerData, "mag", "field_b")
        self.reset(lla0=lla0, vel0=vel0, q0=q0, t0=float(t[0]), fs=1.0 / float(np.median(np.diff(t))),
                   imu_errors0=imu_errors0, odometer=odometer is not None)
        c = self.config
        use_vel = c.use_gnss_velocity and g is not None and g.vel_ned is not None
        gw = None
        if gnss_withheld is not None:
            if not isinstance(gnss_withheld, GnssData):
                raise InvalidInputError(f"gnss_withheld must be a GnssData; got {type(gnss_withheld).__name__}")
            gw = gnss_withheld.within(float(t[0]), float(t[-1]))
            gw = gw.select(gw.t > t[0], "at the first IMU sample")
        timed = self._timed(g, slice(0, ng), dual_antenna, float(t[0]), float(t[-1]), gw)
        age = None
        if g is not None and g.n:
            last = np.searchsorted(g.t, t, side="right") - 1
            age = np.where(last >= 0, t - g.t[np.maximum(last, 0)], np.inf)
        sampled = self._sampled(t, odo, st, hb, mg, odo_var, fix_age=age)
        nrec = (n // int(self._lay[LAY.cov_step]) + ng + 3 + int(np.count_nonzero(sampled.force))) if smoother else 0
        total = 2 * n if smoother else n
        # the kernel compiled for the aids of these inputs only (a run without GNSS compiles no GNSS update)
        use = aids.used(np.r_[timed[1], sampled.kind])
        log, (o, m, r) = self._kernel(t, dth, dv, timed, sampled, nrec, True, True,
                                      None if progress is None else (lambda done, _n: progress(done, total)), use)
        self.t = float(t[-1])
        self._prev = np.vstack([imu.dtheta[-1], imu.dvel[-1]]) if isinstance(imu, ImuIncrements) else np.zeros((2, 3))
        smoothed = None
        if smoother:
            smoothed = rts_smooth(t, o.xs[:, NOM.lla:NOM.lla + 3], o.xs[:, NOM.vel:NOM.vel + 3],
                                  o.xs[:, NOM.q:NOM.q + 4], o.rec_t[:r], o.rec_phi[:r], o.rec_ppri[:r],
                                  o.rec_ppost[:r], o.rec_inj[:r], o.rec_state[:r])
            if progress is not None:
                progress(total, total)
        cov_diag, cov_nav = o.cov_diag[:m], o.cov_nav[:m]
        _check_finite(t, o.xs, o.cov_t[:m], cov_diag, c)
        if c.accel_misalignment_std > 0:  # the accelerometers' axes off the IMU's, which no state holds
            # the wheels measure the velocity in the body's axes: the misalignment turns it
            wheels = odometer is not None or c.nhc_noise_std is not None
            s_t = c.accel_misalignment_std
            vel_m = o.xs[np.clip(np.searchsorted(t, o.cov_t[:m]), 0, n - 1), NOM.vel:NOM.vel + 3] if wheels else None
            cov_diag, cov_nav = unmodelled_misalignment(cov_diag, s_t, vel_m), unmodelled_misalignment(cov_nav, s_t, vel_m)
            if smoothed is not None:
                k = np.clip(np.searchsorted(smoothed.t, smoothed.cov_t), 0, smoothed.t.size - 1)
                smoothed = dataclasses.replace(smoothed, cov_nav=unmodelled_misalignment(
                    smoothed.cov_nav, s_t, smoothed.vel_ned[k] if wheels else None))
        nis = np.full((ng, 2), np.nan)
        acc = np.zeros((ng, 2), dtype=bool)
        for col, name in enumerate(aids.TIMED[:2]):
            if name in log.aids:
                nis[log.timed_index[name], col] = log.aids[name].nis
                acc[log.timed_index[name], col] = log.aids[name].accepted
        veh = log.groups.get(next(g for g in aids.SAMPLED if "odometer" in g), AidRecord.empty())
        xs = o.xs
        meta = {"removed_gnss": [] if g is None else g.meta.get("removed", []), "n_states": self.P.shape[0],
                "gate_threshold": float(self._prm[PRM.gate + 2]), "cov_step_samples": int(self._lay[LAY.cov_step]),
                "gnss_velocity": bool(use_vel), "odometer": odometer is not None, "nhc": c.nhc_noise_std is not None}
        col3 = lambda a: xs[:, a:a + 3]  # noqa: E731  (views of the kernel's output, no copies)
        return GinsResult(t, col3(NOM.lla), col3(NOM.vel), xs[:, NOM.q:NOM.q + 4],
                          col3(NOM.gyro_bias), col3(NOM.accel_bias), col3(NOM.gyro_scale), col3(NOM.accel_scale),
                          xs[:, NOM.odo_scale], o.cov_t[:m], cov_diag, cov_nav,
                          np.zeros(0) if g is None else g.t.copy(), nis,
                          acc, veh.t, veh.nis, veh.dof, veh.accepted, c, meta, smoothed,
                          aids=log.aids, q_vb=xs[:, NOM.q_vb:NOM.q_vb + 4],
                          odo_lever_arm=col3(NOM.odo_lever), gnss_delay=xs[:, NOM.gnss_delay],
                          gnss_bias=col3(NOM.gnss_bias), gnss_noise_scale=xs[:, NOM.gnss_r_scale],
                          odo_noise_scale=xs[:, NOM.odo_r_scale], nhc_noise_scale=xs[:, NOM.nhc_r_scale],
                          odo_turn=xs[:, NOM.odo_turn], side_slip=xs[:, NOM.side_slip],
                          **{f"{name}_nis": _sample_nis(log, name, n) for name in _SAMPLE_NIS})


def _sample_nis(log: _Log, name: str, n: int) -> Array:
    """GinsResult's ``<name>_nis`` per IMU sample (:data:`_SAMPLE_NIS`)."""
    member, aid = _SAMPLE_NIS[name]
    group = next(g for g in aids.SAMPLED if member in g)
    return _per_sample(n, log.groups.get(group) if aid is None else log.aids.get(aid))


def unmodelled_misalignment(cov: Array, std: float, vel: Array | None = None) -> Array:
    """A copy of covariance records with an attitude error that no state holds: the rotation an accelerometer
    triad's axis misalignment leaves (``GinsConfig.accel_misalignment_std``).  The filter finds its attitude by
    matching the measured specific force to gravity (roll, pitch) and to the accelerations the aids show (heading):
    axes off by ``σ`` turn all three by about that much, and nothing it measures tells the turn apart
    (Groves 2013, §4.4.2, §14.2.1).  ``Σ_φ = σ² I`` is added to the attitude errors (entries 6:9 of the
    navigation states).  With ``vel``, the velocity that wheel aids (odometer, NHC) measure in the body's axes is
    turned by the same rotation, ``δv = φ × v = −[v×] φ``: ``[v×] Σ_φ [v×]ᵀ`` is added to the velocity block
    (entries 3:6) and ``−[v×] Σ_φ`` to its covariance with the attitude (a consider parameter's contribution,
    Brown & Hwang 2012, §7.6; a car at 20 m/s and 0.2°: 7 cm/s).

    Parameters
    ----------
    cov : numpy.ndarray, shape (M, n) or (M, n, n)
        Variances (``cov_diag``) or covariances (``cov_nav``), n >= 9, the velocity errors at 3:6 and the attitude
        errors at 6:9.
    std : float
        σ of the rotation per axis, rad.
    vel : numpy.ndarray, shape (M, 3), or None
        The NED velocity at each record, m/s (None: the velocity does not come from the body's axes).

    Returns
    -------
    numpy.ndarray
        The records with the misalignment's variance added.
    """
    out = np.array(cov, dtype=float, copy=True)
    for a in (6, 7, 8):
        if out.ndim == 2:
            out[:, a] += std**2
        else:
            out[:, a, a] += std**2
    if vel is None:
        return out
    vx = skew(np.asarray(vel, dtype=float).reshape(-1, 3))
    cross = -(std**2) * vx  # cov(δv, φ) = −[v×] Σ_φ
    vv = (std**2) * vx @ np.transpose(vx, (0, 2, 1))  # [v×] Σ_φ [v×]ᵀ
    if out.ndim == 2:
        out[:, 3:6] += np.einsum("kii->ki", vv)
    else:
        out[:, 3:6, 3:6] += vv
        out[:, 3:6, 6:9] += cross
        out[:, 6:9, 3:6] += np.transpose(cross, (0, 2, 1))
    return out


def _diag(var: Array) -> Array:
    """(k, w) variances -> (k, w, w) diagonal covariances."""
    k, w = var.shape
    out = np.zeros((k, w, w))
    out[:, np.arange(w), np.arange(w)] = var
    return out
