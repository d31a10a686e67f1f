"""Recordings: :class:`ImuData` and its validation.

An :class:`ImuData` holds one IMU recording in SI units: time ``t`` (s,
strictly increasing), angular rate ``gyro`` (rad/s, body FRD), specific force
``accel`` (m/s², body FRD; at rest and level ``(0, 0, -g)``), optionally the
magnetic field ``mag`` (kept in ``mag_unit``) and the temperature ``temp``
(°C).  The constructor validates everything and raises an
:mod:`imunav.errors` exception naming the rows and columns at fault.  Units
other than SI are declared only at the edge, in :meth:`ImuData.from_arrays`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InvalidInputError, NonFiniteError, ShapeError, TimeOrderError
from imunav.units import to_si

__all__ = ["ImuData", "Gap"]

NanPolicy = Literal["raise", "drop", "interpolate"]
_VECTOR_FIELDS = ("gyro", "accel", "mag")


def _rows(mask: NDArray[np.bool_], limit: int = 10) -> str:
    idx = np.flatnonzero(mask)
    s = ", ".join(map(str, idx[:limit].tolist()))
    return s + (f", ... ({idx.size} rows in all)" if idx.size > limit else "")


@dataclass(frozen=True)
class Gap:
    """A gap in the time stamps: ``t[index + 1] - t[index]`` is ``length_s``."""

    index: int
    t_start: float
    length_s: float
    missing_samples: int


@dataclass(frozen=True, eq=False)
class ImuData:
    """One IMU recording in SI units (see module docstring).

    Parameters
    ----------
    t : (N,) float, s, strictly increasing.
    gyro : (N, 3) float, rad/s.
    accel : (N, 3) float, m/s² (specific force).
    mag : (N, 3) float, optional, in ``mag_unit``.
    temp : (N,) float, optional, °C.
    mag_unit : str
        Unit of ``mag`` (kept as given), default ``"uT"``.
    meta : dict
        Free-form metadata (source file, sensor, what a NaN policy did, ...).
    """

    t: NDArray[np.float64]
    gyro: NDArray[np.float64]
    accel: NDArray[np.float64]
    mag: NDArray[np.float64] | None = None
    temp: NDArray[np.float64] | None = None
    mag_unit: str = "uT"
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        t = np.array(self.t, dtype=np.float64, copy=True)
        if t.ndim != 1:
            raise ShapeError(f"t must be 1-D (N,), got shape {t.shape}")
        n = t.shape[0]
        if n < 1:
            raise ShapeError("the recording is empty: t has no samples")
        object.__setattr__(self, "t", t)
        for name in _VECTOR_FIELDS:
            v = getattr(self, name)
            if v is None:
                continue
            a = np.array(v, dtype=np.float64, copy=True)
            if a.ndim != 2 or a.shape[1] != 3:
                raise ShapeError(f"{name} must have shape (N, 3) = ({n}, 3), got {a.shape}")
            if a.shape[0] != n:
                raise ShapeError(f"{name} has {a.shape[0]} rows but t has {n}; every channel needs one row per time stamp")
            object.__setattr__(self, name, a)
        if self.temp is not None:
            a = np.array(self.temp, dtype=np.float64, copy=True)
            if a.ndim == 2 and a.shape[1] == 1:
                a = a[:, 0]
            if a.shape != (n,):
                raise ShapeError(f"temp must have shape (N,) = ({n},), got {a.shape}")
            object.__setattr__(self, "temp", a)
        object.__setattr__(self, "meta", dict(self.meta or {}))
        self._check_finite()
        self._check_time()
        for name in (*_VECTOR_FIELDS, "temp"):
            a = getattr(self, name)
            if a is not None:
                a.setflags(write=False)
        t.setflags(write=False)

    # -- validation ---------------------------------------------------------
    def _check_finite(self) -> None:
        bad_t = ~np.isfinite(self.t)
        if bad_t.any():
            raise NonFiniteError(f"t has non-finite values at rows {_rows(bad_t)}; time stamps must all be finite")
        for name in (*_VECTOR_FIELDS, "temp"):
            a = getattr(self, name)
            if a is None:
                continue
            bad = ~np.isfinite(a)
            if bad.any():
                rows = bad if bad.ndim == 1 else bad.any(axis=1)
                cols = "" if bad.ndim == 1 else f", columns {sorted(set(np.nonzero(bad)[1].tolist()))}"
                raise NonFiniteError(
                    f"{name} has NaN/inf at rows {_rows(rows)}{cols}. Pass nan_policy='drop' or "
                    "'interpolate' to ImuData.from_arrays / read_imu to handle them explicitly"
                )

    def _check_time(self) -> None:
        if self.t.size < 2:
            return
        d = np.diff(self.t)
        dup = d == 0
        if dup.any():
            raise TimeOrderError(
                f"duplicate time stamps at rows {_rows(dup)} (t[i+1] == t[i]); remove duplicated samples first"
            )
        back = d < 0
        if back.any():
            raise TimeOrderError(
                f"time goes backwards at rows {_rows(back)} (t[i+1] < t[i]); sort the recording or fix the clock"
            )

    # -- construction at the edge --------------------------------------------
    @classmethod
    def from_arrays(
        cls,
        t: ArrayLike,
        gyro: ArrayLike,
        accel: ArrayLike,
        mag: ArrayLike | None = None,
        temp: ArrayLike | None = None,
        *,
        time_unit: str = "s",
        gyro_unit: str = "rad/s",
        accel_unit: str = "m/s^2",
        gyro_scale: float | None = None,
        accel_scale: float | None = None,
        gyro_offset: float = 0.0,
        accel_offset: float = 0.0,
        mag_unit: str = "uT",
        nan_policy: NanPolicy = "raise",
        meta: dict[str, Any] | None = None,
    ) -> "ImuData":
        """Build from arrays in declared units, converting to SI.

        ``gyro_unit`` may be ``"rad/s"``, ``"deg/s"``, ``"rpm"`` or
        ``"counts"`` (then ``gyro_scale`` in rad/s per count is required);
        ``accel_unit`` ``"m/s^2"``, ``"g"``, ``"mg"`` or ``"counts"`` (with
        ``accel_scale`` in m/s² per count).  ``nan_policy``: ``"raise"``
        (default) names the offending rows; ``"drop"`` removes rows with any
        NaN; ``"interpolate"`` fills NaN samples linearly in time.  What was
        done is recorded in ``meta["nan_policy"]``.
        """
        ts = to_si(t, time_unit, "time")
        g = to_si(gyro, gyro_unit, "angular_rate", scale=gyro_scale, offset=gyro_offset)
        a = to_si(accel, accel_unit, "acceleration", scale=accel_scale, offset=accel_offset)
        m = None if mag is None else np.asarray(mag, dtype=float)
        tp = None if temp is None else np.asarray(temp, dtype=float)
        meta = dict(meta or {})
        declared = {"time": time_unit, "gyro": gyro_unit, "accel": accel_unit}
        if declared != {"time": "s", "gyro": "rad/s", "accel": "m/s^2"}:
            meta.setdefault("units_in", declared)
        if nan_policy != "raise":
            ts, g, a, m, tp, info = _apply_nan_policy(ts, g, a, m, tp, nan_policy)
            meta["nan_policy"] = info
        return cls(ts, g, a, m, tp, mag_unit=mag_unit, meta=meta)

    # -- properties -----------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.t.shape[0])

    @property
    def dt(self) -> NDArray[np.float64]:
        """Sample intervals ``t[i+1] - t[i]`` (N-1,)."""
        return np.diff(self.t)

    @property
    def fs(self) -> float:
        """Nominal sample rate (Hz): 1 / median interval."""
        if self.n < 2:
            raise InvalidInputError("a single-sample recording has no sample rate")
        return float(1.0 / np.median(self.dt))

    @property
    def duration(self) -> float:
        """``t[-1] - t[0]`` in s."""
        return float(self.t[-1] - self.t[0])

    def __len__(self) -> int:
        return self.n

    def gaps(self, factor: float = 1.5) -> list[Gap]:
        """Intervals longer than ``factor`` × the median interval."""
        if self.n < 3:
            return []
        d = self.dt
        med = float(np.median(d))
        idx = np.flatnonzero(d > factor * med)
        return [
            Gap(int(i), float(self.t[i]), float(d[i]), int(round(d[i] / med)) - 1)
            for i in idx
        ]

    # -- views / copies -------------------------------------------------------
    def with_(self, **changes: Any) -> "ImuData":
        """Copy with some fields replaced (validated again)."""
        return dataclasses.replace(self, **changes)

    def slice(self, start: int | None = None, stop: int | None = None) -> "ImuData":
        """Samples ``start:stop`` (half-open, Python indexing)."""
        s = np.s_[start:stop]
        return ImuData(
            self.t[s],
            self.gyro[s],
            self.accel[s],
            None if self.mag is None else self.mag[s],
            None if self.temp is None else self.temp[s],
            mag_unit=self.mag_unit,
            meta=dict(self.meta),
        )

    def time_slice(self, t0: float | None = None, t1: float | None = None) -> "ImuData":
        """Samples with ``t0 <= t < t1``."""
        i0 = 0 if t0 is None else int(np.searchsorted(self.t, t0, side="left"))
        i1 = self.n if t1 is None else int(np.searchsorted(self.t, t1, side="left"))
        if i1 <= i0:
            raise InvalidInputError(f"no samples in [{t0}, {t1}); the recording spans [{self.t[0]}, {self.t[-1]}]")
        return self.slice(i0, i1)

    def to_dict(self) -> dict[str, Any]:
        """Plain dict of lists (JSON-friendly)."""
        d: dict[str, Any] = {"t": self.t.tolist(), "gyro": self.gyro.tolist(), "accel": self.accel.tolist()}
        if self.mag is not None:
            d["mag"] = self.mag.tolist()
            d["mag_unit"] = self.mag_unit
        if self.temp is not None:
            d["temp"] = self.temp.tolist()
        d["meta"] = self.meta
        return d


def _apply_nan_policy(t, g, a, m, tp, policy):
    chans = [("gyro", g), ("accel", a)] + ([("mag", m)] if m is not None else []) + ([("temp", tp)] if tp is not None else [])
    if not np.all(np.isfinite(t)):
        raise NonFiniteError(
            f"t has non-finite values at rows {_rows(~np.isfinite(t))}; the NaN policy applies to channels, not to time"
        )
    bad = np.zeros(t.shape[0], dtype=bool)
    for _, c in chans:
        c2 = c.reshape(c.shape[0], -1)
        if c2.shape[0] != t.shape[0]:
            raise ShapeError(f"channel has {c2.shape[0]} rows but t has {t.shape[0]}")
        bad |= ~np.isfinite(c2).all(axis=1)
    info = {"policy": policy, "rows": np.flatnonzero(bad).tolist()}
    if not bad.any():
        return t, g, a, m, tp, info
    if policy == "drop":
        keep = ~bad
        return (t[keep], g[keep], a[keep], None if m is None else m[keep], None if tp is None else tp[keep], info)
    if policy == "interpolate":
        out = []
        for name, c in chans:
            c = np.array(c, dtype=float)
            c2 = c.reshape(c.shape[0], -1)
            for j in range(c2.shape[1]):
                col = c2[:, j]
                ok = np.isfinite(col)
                if not ok.any():
                    raise NonFiniteError(f"{name} column {j} has no finite values to interpolate from")
                if not ok[0] or not ok[-1]:
                    raise NonFiniteError(
                        f"{name} column {j} has NaN at the start or end of the record, which cannot be "
                        "interpolated; use nan_policy='drop' or trim the record"
                    )
                col[~ok] = np.interp(t[~ok], t[ok], col[ok])
            out.append(c2.reshape(c.shape))
        g2, a2 = out[0], out[1]
        k = 2
        m2 = None
        tp2 = None
        if m is not None:
            m2 = out[k]
            k += 1
        if tp is not None:
            tp2 = out[k]
        return t, g2, a2, m2, tp2, info
    raise InvalidInputError(f"nan_policy must be 'raise', 'drop' or 'interpolate', not {policy!r}")
