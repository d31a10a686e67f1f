"""Calibration test profiles: multi-position static tests and rate tables.

Every profile is a chain of *pieces* about a fixed body axis ``a`` starting
from attitude ``q0``: ``q(τ) = q0 ⊗ exp(a θ(τ))`` with body rate
``ω_nb^b = a θ̇(τ)``.  Angles and rates are analytic, so the trajectory
carries exact ``omega_nb_b`` and integrating it (:func:`imunav.rotation.integrate_rate`)
reproduces the attitude.  Moves between positions and changes of rate use the
minimum-jerk blend ``s(x) = 10x³ − 15x⁴ + 6x⁵`` (zero rate and angular
acceleration at both ends, so the gyro signal is C² continuous).

Each generator returns a :class:`Profile` (``trajectory`` + ``segments``);
``traj, seg = profile`` also works.  The :class:`Segments` table gives every
static position, rate step, transition and rotation with its time and sample
span, nominal attitude, vertical direction in body axes ``up_b`` (at rest the
accelerometers read ``f_b = g · up_b``), rotation axis and rate: the hints
calibration code needs.

Test designs follow Y. Günhan, *Ataletsel ölçüm birimi hatalarının belirlenmesi ve düzeltilmesi*
(Detection and compensation of inertial measurement unit errors), MSc thesis, Hacettepe University, 2014,
§4.1: the reconstructed 100-position static test (§4.1.1, :func:`hundred_position_up_vectors`),
the exact 120-step ±250 °/s rate-table test (§4.1.2, :func:`rate_table_steps`), the
six-position test (Appendix A), and a Ferraris-style test (six static poses plus a
full turn about each axis; Ferraris et al., Sensors and Actuators A 46-47,
1995).
"""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any, Iterator

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import FileFormatError, InvalidInputError, ShapeError
from imunav.files import atomic_path, read_json, write_json
from imunav.results import EulerMixin
from imunav.rotation import (
    quat_conjugate,
    quat_from_rotvec,
    quat_multiply,
    quat_normalize,
    quat_rotate,
    rotvec_from_quat,
)
from imunav.sim.trajectory import Trajectory
from imunav.units import DEG

__all__ = [
    "Profile",
    "Segments",
    "read_segments",
    "static_profile",
    "multiposition_profile",
    "orientations_from_up",
    "up_from_orientations",
    "hundred_position_up_vectors",
    "hundred_position_orientations",
    "hundred_position_profile",
    "six_position_up_vectors",
    "six_position_orientations",
    "six_position_profile",
    "rate_table_profile",
    "rate_table_steps",
    "rate_table_step_profile",
    "ferraris_profile",
]

Array = NDArray[np.float64]
_UP_N = np.array([0.0, 0.0, -1.0])  # local vertical (up) in NED


# ---------------------------------------------------------------------------
# result types
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Segments(EulerMixin):
    """Segment table of a profile (one row per static position, rate step, move).

    Attributes
    ----------
    kind : numpy.ndarray
        (K,) ``"static"``, ``"rate"`` (constant rate, possibly 0),
        ``"transition"`` (move between positions / change of rate) or
        ``"rotation"`` (a commanded turn of known angle, Ferraris-style).
    t_start, t_stop : numpy.ndarray
        (K,) segment times, s (``t_stop`` of one = ``t_start`` of the next).
    i_start, i_stop : numpy.ndarray
        (K,) half-open sample index span (samples with
        ``t_start <= t < t_stop``; the last segment includes the final sample).
    q_nb : numpy.ndarray
        (K, 4) attitude at the segment start.
    up_b : numpy.ndarray
        (K, 3) unit "up" vector in body axes at the segment start
        (``f_b = g · up_b`` at rest).
    axis_b : numpy.ndarray
        (K, 3) body rotation axis (zeros for static segments).
    rate : numpy.ndarray
        (K,) nominal rate about ``axis_b``, rad/s (0 for static, NaN for
        transitions / rotations whose rate varies).
    angle : numpy.ndarray
        (K,) total rotation angle over the segment, rad.
    step : numpy.ndarray
        (K,) index of the position (static) or rate step (rate), -1 otherwise.
    """

    kind: NDArray[np.str_]
    t_start: Array
    t_stop: Array
    i_start: NDArray[np.int64]
    i_stop: NDArray[np.int64]
    q_nb: Array
    up_b: Array
    axis_b: Array
    rate: Array
    angle: Array
    step: NDArray[np.int64]

    def __len__(self) -> int:
        return int(self.kind.size)

    def select(self, kind: str) -> "Segments":
        """Rows of one kind.

        Parameters
        ----------
        kind : {"static", "rate", "transition", "rotation"}
            Segment kind.

        Returns
        -------
        Segments
            The rows of that kind, in time order.
        """
        m = self.kind == kind
        return Segments(**{f.name: getattr(self, f.name)[m] for f in fields(self)})

    def trim(self, start_s: float, stop_s: float | None = None) -> "Segments":
        """Segments shortened at both ends, e.g. to skip settling after a move.

        Sample spans are recomputed from the profile's uniform rate.

        Parameters
        ----------
        start_s : float
            Time removed at the start of each segment, s.
        stop_s : float, optional
            Time removed at the end, s (default ``start_s``).

        Returns
        -------
        Segments
            The shortened table.

        Raises
        ------
        InvalidInputError
            If a trim is negative or a segment would become empty.
        """
        stop_s = start_s if stop_s is None else stop_s
        if start_s < 0 or stop_s < 0:
            raise InvalidInputError(f"trim times must be non-negative; got {start_s}, {stop_s}")
        dur = self.t_stop - self.t_start
        short = np.flatnonzero(dur <= start_s + stop_s)
        if short.size:
            raise InvalidInputError(
                f"trimming {start_s} + {stop_s} s empties segments {short[:10].tolist()} "
                f"(shortest lasts {dur.min():g} s); trim less"
            )
        n = self.i_stop - self.i_start
        fs = float(np.median(n[n > 1] / dur[n > 1])) if np.any(n > 1) else 1.0
        d = {f.name: getattr(self, f.name).copy() for f in fields(self)}
        d["t_start"] = self.t_start + start_s
        d["t_stop"] = self.t_stop - stop_s
        d["i_start"] = self.i_start + int(np.ceil(start_s * fs - 1e-6))
        d["i_stop"] = self.i_stop - int(np.ceil(stop_s * fs - 1e-6))
        return Segments(**d)

    def to_dict(self) -> dict:
        """Column lists for JSON.

        Returns
        -------
        dict
            Every column by name (times in s, angles and rates in rad and rad/s).
        """
        return {f.name: getattr(self, f.name).tolist() for f in fields(self)}

    def write_csv(self, path: str | os.PathLike[str]) -> Path:
        """Write the table as CSV (atomically).

        One row per segment, rates and angles in degrees, ``up``/``axis``/``q`` split into columns.

        Parameters
        ----------
        path : str or os.PathLike
            Output file.

        Returns
        -------
        pathlib.Path
            The file written.
        """

        cols = ["kind", "step", "t_start", "t_stop", "i_start", "i_stop", "up_x", "up_y", "up_z",
                "axis_x", "axis_y", "axis_z", "rate_dps", "angle_deg", "qw", "qx", "qy", "qz"]
        p = Path(path)
        with atomic_path(p) as tmp, open(tmp, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(cols)
            for k in range(len(self)):
                w.writerow([
                    self.kind[k], int(self.step[k]), repr(float(self.t_start[k])), repr(float(self.t_stop[k])),
                    int(self.i_start[k]), int(self.i_stop[k]), *(repr(float(x)) for x in self.up_b[k]),
                    *(repr(float(x)) for x in self.axis_b[k]), repr(float(np.rad2deg(self.rate[k]))),
                    repr(float(np.rad2deg(self.angle[k]))), *(repr(float(x)) for x in self.q_nb[k]),
                ])
        return p

    def write(self, path: str | os.PathLike[str]) -> Path:
        """Write the table in the format of the suffix (atomically): ``.json`` or ``.csv``.

        JSON holds :meth:`to_dict` (SI: s, rad, rad/s), CSV the table of :meth:`write_csv` (degrees);
        :meth:`read` reads both, so what ``imunav simulate --segments`` writes, ``imunav calibrate
        multiposition --segments`` reads.

        Parameters
        ----------
        path : str or os.PathLike
            File to write, ending in ``.json`` or ``.csv``.

        Returns
        -------
        pathlib.Path
            The path written.

        Raises
        ------
        InvalidInputError
            If the suffix is neither ``.json`` nor ``.csv``.
        """
        p = Path(path)
        suffix = p.suffix.lower()
        if suffix == ".csv":
            return self.write_csv(p)
        if suffix != ".json":
            raise InvalidInputError(f"{p}: a segment table is written as .json or .csv, not {p.suffix or 'no suffix'!r}")
        write_json(p, {"segment_table": self.to_dict()}, indent=1)
        return p

    @classmethod
    def read(cls, path: str | os.PathLike[str]) -> "Segments":
        """Read a segment table written by :meth:`write` (JSON or CSV) or by ``Profile.to_dict()`` (JSON).

        Parameters
        ----------
        path : str or os.PathLike
            ``.json`` (the columns of :meth:`to_dict`, alone or under ``segment_table``) or ``.csv``
            (the columns of :meth:`write_csv`).

        Returns
        -------
        Segments
            The table, in SI units.

        Raises
        ------
        FileFormatError
            If the file is not a segment table (not valid JSON / CSV, a column missing).
        """
        return read_segments(path)

    @classmethod
    def _read_csv(cls, p: Path) -> "Segments":
        try:
            with open(p, newline="", encoding="utf-8") as fh:
                rows = list(csv.DictReader(fh))
        except UnicodeDecodeError as e:
            raise FileFormatError(f"{p}: not a text segment table ({e})") from None
        if not rows:
            raise FileFormatError(f"{p}: the segment table has no rows")

        def col(*names: str, dtype: Any = float) -> NDArray[Any]:
            try:
                return np.array([[r[n] for n in names] for r in rows], dtype=dtype).squeeze(axis=1) \
                    if len(names) == 1 else np.array([[r[n] for n in names] for r in rows], dtype=dtype)
            except KeyError as e:
                raise FileFormatError(f"{p}: segment table lacks the column {e} (write it with "
                                      "Segments.write)") from None
            except ValueError as e:
                raise FileFormatError(f"{p}: segment table column {names}: {e}") from None

        return cls(kind=col("kind", dtype=str), step=col("step", dtype=np.int64), t_start=col("t_start"),
                   t_stop=col("t_stop"), i_start=col("i_start", dtype=np.int64), i_stop=col("i_stop", dtype=np.int64),
                   up_b=col("up_x", "up_y", "up_z"), axis_b=col("axis_x", "axis_y", "axis_z"),
                   rate=np.deg2rad(col("rate_dps")), angle=np.deg2rad(col("angle_deg")),
                   q_nb=col("qw", "qx", "qy", "qz"))

    def to_records(self) -> list[dict]:
        """One dict per segment (for tables / CSV).

        Returns
        -------
        list of dict
            Rows with the columns of :meth:`write_csv` (rates and angles in degrees).
        """
        d = self.to_dict()
        return [{k: d[k][i] for k in d} for i in range(len(self))]



def _nulls_to_nan(v: object) -> object:
    if isinstance(v, list):
        return [_nulls_to_nan(x) for x in v]
    return np.nan if v is None else v


def read_segments(path: str | os.PathLike[str]) -> Segments:
    """Read a segment table: a CSV of :meth:`Segments.write_csv`, or a JSON (:meth:`Segments.to_dict`, or a
    profile's ``to_dict`` with ``segment_table``); the one reader behind :meth:`Segments.read`.

    A JSON is checked against its schema before use: an object whose columns are the fields of
    :class:`Segments`, ``kind`` text, every other column numbers (null read as NaN), all of one length.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.csv`` or JSON file.

    Returns
    -------
    Segments
        The table.

    Raises
    ------
    FileFormatError
        Naming the file and the column, for text that is not JSON (a truncated file), a document that is not
        an object, a missing column, a column of the wrong type or length.
    """
    if Path(path).suffix.lower() == ".csv":
        return Segments._read_csv(Path(path))
    d = read_json(path, "segment table JSON (write it with Profile.to_dict() / Segments.to_dict())")
    if isinstance(d, dict):
        d = d.get("segment_table", d)
    if not isinstance(d, dict):
        raise FileFormatError(f"{path}: a segment table JSON is an object with the columns of Segments "
                              f"({', '.join(f.name for f in fields(Segments))}), not {type(d).__name__}")
    cols = {}
    for f in fields(Segments):
        if f.name not in d:
            raise FileFormatError(f"{path}: segment table lacks the column {f.name!r} (write it with Profile.to_dict())")
        v = d[f.name]
        if f.name == "kind":
            a = np.asarray(v)
            ok = a.dtype.kind in "US" and a.ndim == 1
        else:  # numbers; null is a NaN (strict JSON has no NaN token)
            a = np.asarray(_nulls_to_nan(v))
            ok = a.dtype.kind in "fiu" and a.ndim >= 1
        if not ok:
            raise FileFormatError(f"{path}: segment table column {f.name!r} must be a list of "
                                  f"{'names' if f.name == 'kind' else 'numbers (or null)'}, got {v!r:.80}")
        cols[f.name] = a
    lengths = {k: len(v) for k, v in cols.items()}
    if len(set(lengths.values())) > 1:
        raise FileFormatError(f"{path}: segment table columns differ in length {lengths}; the file is damaged")
    try:
        return Segments(**cols)
    except (InvalidInputError, ValueError) as e:
        raise FileFormatError(f"{path}: not a valid segment table ({e})") from None

@dataclass(frozen=True)
class Profile:
    """A test profile: the true motion and its segment table.

    Attributes
    ----------
    name : str
        Profile name.
    trajectory : Trajectory
        The true motion (exact body rates).
    segments : Segments
        Its segment table.
    """

    name: str
    trajectory: Trajectory
    segments: Segments

    def __iter__(self) -> Iterator:
        yield self.trajectory
        yield self.segments

    def summary(self) -> dict:
        """Name, samples, rate, duration and segment counts.

        Returns
        -------
        dict
            ``name``, ``samples``, ``fs_hz``, ``duration_s`` and ``segments`` (the count of segments of each
            kind).
        """
        kinds, counts = np.unique(self.segments.kind, return_counts=True)
        return {
            "name": self.name,
            "samples": self.trajectory.n,
            "fs_hz": self.trajectory.fs,
            "duration_s": self.trajectory.duration,
            "segments": {str(k): int(c) for k, c in zip(kinds, counts)},
        }

    def to_dict(self) -> dict:
        """Summary plus the segment table (not the samples).

        Returns
        -------
        dict
            :meth:`summary` with ``segment_table`` (:meth:`Segments.to_dict`).
        """
        return {**self.summary(), "segment_table": self.segments.to_dict()}


# ---------------------------------------------------------------------------
# piecewise construction
# ---------------------------------------------------------------------------


def _s(x: Array) -> Array:
    """Minimum-jerk blend s(x) = 10x³ − 15x⁴ + 6x⁵ on [0, 1]."""
    return x * x * x * (10.0 + x * (-15.0 + 6.0 * x))


def _ds(x: Array) -> Array:
    """ds/dx = 30x²(1 − x)²."""
    return 30.0 * x * x * (1.0 - x) ** 2


def _int_s(x: Array) -> Array:
    """∫₀ˣ s = 2.5x⁴ − 3x⁵ + x⁶ (= 1/2 at x = 1)."""
    return x**4 * (2.5 + x * (-3.0 + x))


@dataclass
class _Piece:
    T: float
    q0: Array
    axis: Array
    kind: str  # static | rate | transition | rotation
    mode: str  # "blend" (rate r0 -> r1) or "move" (angle phi, rest to rest)
    r0: float = 0.0
    r1: float = 0.0
    phi: float = 0.0
    step: int = -1

    def theta(self, tau: Array) -> tuple[Array, Array]:
        """Angle and rate about ``axis`` at local times ``tau`` in [0, T]."""
        x = np.clip(tau / self.T, 0.0, 1.0)
        if self.mode == "move":
            return self.phi * _s(x), self.phi * _ds(x) / self.T
        dr = self.r1 - self.r0
        return self.r0 * tau + dr * self.T * _int_s(x), self.r0 + dr * _s(x)

    def q_end(self) -> Array:
        th, _ = self.theta(np.array([self.T]))
        return quat_normalize(quat_multiply(self.q0, quat_from_rotvec(self.axis * th[0])))


def _unit(v: ArrayLike, name: str) -> Array:
    a = np.asarray(v, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)) or np.linalg.norm(a) < 1e-12:
        raise InvalidInputError(f"{name} must be a finite non-zero 3-vector; got {v!r}")
    return a / np.linalg.norm(a)


def _positive(x: float, name: str, allow_zero: bool = False) -> float:
    x = float(x)
    if not np.isfinite(x) or x < 0 or (x == 0 and not allow_zero):
        raise InvalidInputError(f"{name} must be {'non-negative' if allow_zero else 'positive'} seconds; got {x}")
    return x


class _Builder:
    """Chains pieces, keeping attitude and rate continuous."""

    def __init__(self, q0: ArrayLike) -> None:
        self.q = quat_normalize(np.asarray(q0, dtype=float))
        self.axis = np.array([0.0, 0.0, 1.0])
        self.rate = 0.0
        self.pieces: list[_Piece] = []

    def _add(self, p: _Piece) -> None:
        self.pieces.append(p)
        self.q = p.q_end()

    def static(self, T: float, step: int = -1) -> None:
        if self.rate != 0.0:
            raise InvalidInputError("internal: static piece while rotating")
        self._add(_Piece(T, self.q, self.axis, "static", "blend", step=step))

    def rate_const(self, T: float, axis: Array, rate: float, step: int = -1) -> None:
        if rate != self.rate or (rate != 0.0 and not np.allclose(axis, self.axis)):
            raise InvalidInputError("internal: rate jump without ramp")
        self.axis = axis
        self._add(_Piece(T, self.q, axis, "rate", "blend", rate, rate, step=step))

    def ramp(self, T: float, axis: Array, r1: float) -> None:
        if self.rate != 0.0 and not np.allclose(axis, self.axis):
            raise InvalidInputError("internal: axis change while rotating")
        self.axis = axis
        self._add(_Piece(T, self.q, axis, "transition", "blend", self.rate, r1))
        self.rate = r1

    def move_to(self, q_target: Array, T: float, kind: str = "transition") -> None:
        if self.rate != 0.0:
            raise InvalidInputError("internal: move while rotating")
        r = rotvec_from_quat(quat_multiply(quat_conjugate(self.q), q_target))
        phi = float(np.linalg.norm(r))
        if phi < 1e-15:
            return
        self._add(_Piece(T, self.q, r / phi, kind, "move", phi=phi))

    def turn(self, axis: Array, angle: float, T: float) -> None:
        if self.rate != 0.0:
            raise InvalidInputError("internal: turn while rotating")
        self._add(_Piece(T, self.q, axis, "rotation", "move", phi=float(angle)))

    def build(self, name: str, fs: float, t0: float, lat: float | None, lon: float, h: float) -> Profile:
        fs = float(fs)
        if not np.isfinite(fs) or fs <= 0:
            raise InvalidInputError(f"fs must be a positive sample rate in Hz; got {fs}")
        if not self.pieces:
            raise InvalidInputError("the profile is empty: give at least one position or rate step")
        T = np.array([p.T for p in self.pieces])
        edges = np.concatenate([[0.0], np.cumsum(T)])
        total = edges[-1]
        n = int(np.floor(total * fs + 1e-6)) + 1
        k = np.arange(n)
        tau_all = k / fs
        # piece of each sample: the one whose [start, stop) holds it (tolerant of rounding)
        idx_edges = np.ceil(edges * fs - 1e-6).astype(np.int64)
        idx_edges[-1] = n
        q = np.empty((n, 4))
        w = np.empty((n, 3))
        for j, p in enumerate(self.pieces):
            i0, i1 = idx_edges[j], idx_edges[j + 1]
            if i1 <= i0:
                continue
            if p.kind == "static":
                q[i0:i1] = p.q0
                w[i0:i1] = 0.0
                continue
            tau = tau_all[i0:i1] - edges[j]
            th, rt = p.theta(tau)
            q[i0:i1] = quat_multiply(p.q0, quat_from_rotvec(p.axis[None, :] * th[:, None]))
            w[i0:i1] = p.axis[None, :] * rt[:, None]
        t = t0 + tau_all
        pos = None if lat is None else np.tile([float(lat), float(lon), float(h)], (n, 1))
        zeros = None if pos is None else np.zeros((n, 3))
        traj = Trajectory(t, q, vel_ned=zeros, pos_lla=pos, omega_nb_b=w, accel_ned=zeros)

        K = len(self.pieces)
        q0 = np.array([p.q0 for p in self.pieces])
        up = quat_rotate(quat_conjugate(q0), np.tile(_UP_N, (K, 1)))
        kinds = np.array([p.kind for p in self.pieces])
        rate = np.array(
            [0.0 if p.kind == "static" else (p.r0 if p.kind == "rate" else np.nan) for p in self.pieces]
        )
        angle = np.array([p.theta(np.array([p.T]))[0][0] for p in self.pieces])
        axis = np.array([np.zeros(3) if p.kind == "static" else p.axis for p in self.pieces])
        seg = Segments(
            kind=kinds,
            t_start=t0 + edges[:-1],
            t_stop=t0 + edges[1:],
            i_start=idx_edges[:-1].copy(),
            i_stop=idx_edges[1:].copy(),
            q_nb=q0,
            up_b=up,
            axis_b=axis,
            rate=rate,
            angle=angle,
            step=np.array([p.step for p in self.pieces], dtype=np.int64),
        )
        return Profile(name, traj, seg)


# ---------------------------------------------------------------------------
# orientations
# ---------------------------------------------------------------------------


def _shortest_arc(u: Array, v: Array) -> Array:
    """Unit quaternion of the smallest rotation taking unit vector u onto v."""
    c = float(np.dot(u, v))
    if c < -1.0 + 1e-12:  # antiparallel: half turn about an axis normal to u
        ref = np.array([1.0, 0.0, 0.0]) if abs(u[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        ax = np.cross(u, ref)
        ax /= np.linalg.norm(ax)
        return np.array([0.0, *ax])
    q = np.array([1.0 + c, *np.cross(u, v)])
    return q / np.linalg.norm(q)


def _as_up(up_b: ArrayLike) -> Array:
    u = np.asarray(up_b, dtype=float)
    if u.ndim != 2 or u.shape[1] != 3 or u.shape[0] < 1:
        raise ShapeError(f"up vectors must have shape (K, 3); got {u.shape}")
    n = np.linalg.norm(u, axis=1)
    if not np.all(np.isfinite(u)) or np.any(n < 1e-12):
        bad = np.flatnonzero(~np.isfinite(n) | (n < 1e-12))
        raise InvalidInputError(f"up vectors at rows {bad[:10].tolist()} are zero or non-finite")
    return u / n[:, None]


def orientations_from_up(up_b: ArrayLike, q0: ArrayLike | None = None) -> Array:
    """Attitudes ``q_nb`` that put the local vertical along ``up_b`` (body axes).

    The first attitude is ``q0`` if given (it must already satisfy
    ``up_b[0]``), else the smallest rotation from level.  Each next attitude is
    reached from the previous one by the smallest body rotation that moves the
    vertical from ``up_b[k]`` to ``up_b[k+1]`` — the motion of a two-axis
    table stepping about one axis, so heading is carried along physically.

    Parameters
    ----------
    up_b : array_like, shape (K, 3)
        Unit "up" vectors in body axes, one per position.
    q0 : array_like, shape (4,), optional
        First attitude ``q_nb``.

    Returns
    -------
    numpy.ndarray, shape (K, 4)
        Attitudes ``q_nb``.

    Raises
    ------
    InvalidInputError
        If ``q0`` does not put the vertical along ``up_b[0]``.
    """
    u = _as_up(up_b)
    if q0 is None:
        # C_nb up_b = up_n: smallest rotation taking up_b onto up_n
        q = _shortest_arc(u[0], _UP_N)
    else:
        q = quat_normalize(np.asarray(q0, dtype=float))
        if np.linalg.norm(quat_rotate(q, u[0]) - _UP_N) > 1e-9:
            raise InvalidInputError("q0 does not put the vertical along up_b[0]; omit q0 or fix it")
    out = [q]
    for k in range(1, u.shape[0]):
        # q_{k+1} = q_k ⊗ r with R(r) up_{k+1} = up_k
        r = _shortest_arc(u[k], u[k - 1])
        q = quat_normalize(quat_multiply(q, r))
        out.append(q)
    return np.array(out)


def up_from_orientations(q_nb: ArrayLike) -> Array:
    """Unit vertical ("up") in body axes of attitudes ``q_nb``: ``C_bn (0, 0, −1)``.

    Parameters
    ----------
    q_nb : array_like, shape (4,) or (K, 4)
        Attitudes, body (FRD) to NED.

    Returns
    -------
    numpy.ndarray, shape (3,) or (K, 3)
        The up direction in body axes.
    """
    q = np.atleast_2d(np.asarray(q_nb, dtype=float))
    return quat_rotate(quat_conjugate(q), np.tile(_UP_N, (q.shape[0], 1)))


def hundred_position_up_vectors(step_deg: float = 22.5) -> Array:
    """The reconstructed 100-position static test (Günhan 2014, §4.1.1).

    For each axis i = x, y, z with the other two (j, k) in cyclic order, four
    chained half-turn sweeps of the vertical in body axes (u = up, so the
    axis-i accelerometer reads g·cos θ):

    1. i from −1 g to +1 g through +k (9 positions, θ = 180° … 0°);
    2. back to −1 g through −k (8 new);
    3. to +1 g through +j (8 new);
    4. back to −1 g through −j (8 new),

    i.e. 33 positions per axis, then a final "z up" position (0, 0, +1): 100.
    Every consecutive pair differs by one ``step_deg`` turn (90° between the
    axis blocks, 180° for the final one), and every axis sees both signs.
    The thesis's exact list is lost with its figures; this is a reconstruction.

    Parameters
    ----------
    step_deg : float
        Turn between consecutive positions, degrees (180 / step_deg must be an integer).

    Returns
    -------
    numpy.ndarray, shape (K, 3)
        Unit up vectors in body axes (K = 100 at the default step).

    Raises
    ------
    InvalidInputError
        If ``step_deg`` does not divide 180° into at least 2 steps.
    """
    n_half = int(round(180.0 / step_deg))
    if n_half < 2 or abs(n_half * step_deg - 180.0) > 1e-9:
        raise InvalidInputError(f"step_deg must divide 180 into at least 2 steps; got {step_deg}")
    th = np.deg2rad(np.arange(n_half + 1) * step_deg)  # 0 … 180°
    down = th[::-1]  # 180 … 0: -1 g -> +1 g
    rows = []
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        for angles, other, sign in ((down, k, 1.0), (th[1:], k, -1.0), (down[1:], j, 1.0), (th[1:], j, -1.0)):
            for a in angles:
                u = np.zeros(3)
                u[i] = np.cos(a)
                u[other] = sign * np.sin(a)
                rows.append(u)
    rows.append(np.array([0.0, 0.0, 1.0]))
    out = np.array(rows)
    out[np.abs(out) < 1e-15] = 0.0
    return out


def hundred_position_orientations(step_deg: float = 22.5) -> Array:
    """Attitudes ``q_nb`` of :func:`hundred_position_up_vectors` (chained table moves).

    Parameters
    ----------
    step_deg : float
        Turn between consecutive positions, degrees.

    Returns
    -------
    numpy.ndarray, shape (100, 4)
        Attitudes ``q_nb`` (at the default step).
    """
    return orientations_from_up(hundred_position_up_vectors(step_deg))


def six_position_up_vectors() -> Array:
    """Each axis up then down: +x, −x, +y, −y, +z, −z (Günhan 2014, Appendix A).

    Returns
    -------
    numpy.ndarray, shape (6, 3)
        Unit up vectors in body axes.
    """
    return np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)


def six_position_orientations() -> Array:
    """Attitudes of :func:`six_position_up_vectors`.

    Returns
    -------
    numpy.ndarray, shape (6, 4)
        Attitudes ``q_nb``.
    """
    return orientations_from_up(six_position_up_vectors())


# ---------------------------------------------------------------------------
# profiles
# ---------------------------------------------------------------------------


def static_profile(
    duration_s: float,
    fs: float,
    orientation: ArrayLike | None = None,
    *,
    lat: float | None = None,
    lon: float = 0.0,
    h: float = 0.0,
    t0: float = 0.0,
    name: str = "static",
) -> Profile:
    """One static position (level by default) for ``duration_s`` seconds.

    Parameters
    ----------
    duration_s : float
        Length, s.
    fs : float
        Sample rate, Hz.
    orientation : array_like, shape (4,), optional
        Attitude ``q_nb`` (default level, heading north).
    lat : float, optional
        Geodetic latitude of the fixed position, rad (None: no position).
    lon : float
        Longitude, rad.
    h : float
        Ellipsoidal height, m.
    t0 : float
        Time of the first sample, s.
    name : str
        Profile name.

    Returns
    -------
    Profile
        The trajectory (exact body rates) and its segment table.

    Raises
    ------
    ShapeError
        If ``orientation`` is not (4,).
    """
    q = np.array([1.0, 0.0, 0.0, 0.0]) if orientation is None else np.asarray(orientation, float)
    if q.shape != (4,):
        raise ShapeError(f"orientation must be one quaternion q_nb of shape (4,); got {q.shape}")
    b = _Builder(q)
    b.static(_positive(duration_s, "duration_s"), step=0)
    return b.build(name, fs, t0, lat, lon, h)


def _as_orientations(orientations: ArrayLike) -> Array:
    q = np.asarray(orientations, dtype=float)
    if q.ndim != 2 or q.shape[1] != 4 or q.shape[0] < 1:
        raise ShapeError(
            f"orientations must be (K, 4) quaternions q_nb; got {q.shape} "
            "(use orientations_from_up(up_vectors) for 'up' vectors)"
        )
    return quat_normalize(q)


def multiposition_profile(
    orientations: ArrayLike,
    dwell_s: float | ArrayLike,
    fs: float,
    transition_s: float = 2.0,
    *,
    lat: float | None = None,
    lon: float = 0.0,
    h: float = 0.0,
    t0: float = 0.0,
    name: str = "multiposition",
) -> Profile:
    """Static at each orientation for ``dwell_s``, with smooth moves between.

    Each move is the smallest rotation from one attitude to the next, rest to
    rest over ``transition_s`` with the minimum-jerk angle profile (peak rate
    = 1.875 · angle / ``transition_s``).

    Parameters
    ----------
    orientations : array_like
        (K, 4) attitudes ``q_nb``.
    dwell_s : float or array_like
        Static time per position, s (scalar or (K,)).
    fs : float
        Sample rate, Hz.
    transition_s : float
        Duration of each move, s (> 0).
    lat : float, optional
        Geodetic latitude of the fixed position, rad (None: no position).
    lon : float
        Longitude, rad.
    h : float
        Ellipsoidal height, m.

    t0 : float
        Time of the first sample, s.
    name : str
        Profile name.

    Returns
    -------
    Profile
        The trajectory (exact body rates) and its segment table.

    Raises
    ------
    ShapeError
        If ``orientations`` or ``dwell_s`` has the wrong shape.
    """
    q = _as_orientations(orientations)
    K = q.shape[0]
    dw = np.broadcast_to(np.asarray(dwell_s, dtype=float), (K,)) if np.ndim(dwell_s) == 0 else np.asarray(dwell_s, float)
    if dw.shape != (K,):
        raise ShapeError(f"dwell_s must be a scalar or have one entry per orientation ({K}); got {dw.shape}")
    for i, d in enumerate(dw):
        _positive(d, f"dwell_s[{i}]")
    tr = _positive(transition_s, "transition_s")
    b = _Builder(q[0])
    for i in range(K):
        if i:
            b.move_to(q[i], tr)
        b.static(float(dw[i]), step=i)
    return b.build(name, fs, t0, lat, lon, h)


def hundred_position_profile(
    fs: float = 100.0,
    dwell_s: float = 30.0,
    transition_s: float = 2.0,
    *,
    step_deg: float = 22.5,
    lat: float | None = None,
    lon: float = 0.0,
    h: float = 0.0,
) -> Profile:
    """The 100-position static test (Günhan 2014, §4.1.1): 30 s per position by default.

    Parameters
    ----------
    fs : float
        Sample rate, Hz.
    dwell_s : float
        Static time per position, s.
    transition_s : float
        Duration of each move, s.
    step_deg : float
        Turn between consecutive positions, degrees.
    lat : float, optional
        Geodetic latitude of the fixed position, rad (None: no position).
    lon : float
        Longitude, rad.
    h : float
        Ellipsoidal height, m.

    Returns
    -------
    Profile
        The trajectory (exact body rates) and its segment table.
    """
    return multiposition_profile(
        hundred_position_orientations(step_deg), dwell_s, fs, transition_s, lat=lat, lon=lon, h=h,
        name="hundred_position",
    )


def six_position_profile(
    fs: float = 100.0,
    dwell_s: float = 30.0,
    transition_s: float = 4.0,
    *,
    lat: float | None = None,
    lon: float = 0.0,
    h: float = 0.0,
) -> Profile:
    """The six-position test (Günhan 2014, Appendix A): each axis up then down.

    Parameters
    ----------
    fs : float
        Sample rate, Hz.
    dwell_s : float
        Static time per position, s.
    transition_s : float
        Duration of each move, s.
    lat : float, optional
        Geodetic latitude of the fixed position, rad (None: no position).
    lon : float
        Longitude, rad.
    h : float
        Ellipsoidal height, m.

    Returns
    -------
    Profile
        The trajectory (exact body rates) and its segment table.
    """
    return multiposition_profile(
        six_position_orientations(), dwell_s, fs, transition_s, lat=lat, lon=lon, h=h, name="six_position"
    )


def _axis_vectors(axes: ArrayLike, K: int) -> Array:
    a = np.asarray(axes)
    if a.ndim == 1 and a.shape == (K,):
        if not np.all(np.isin(a, [0, 1, 2])):
            raise InvalidInputError(f"axes must be 0 (x), 1 (y) or 2 (z); got values {np.unique(a).tolist()}")
        return np.eye(3)[a.astype(int)]
    if a.shape == (K, 3):
        return np.array([_unit(v, f"axes[{i}]") for i, v in enumerate(a.astype(float))])
    raise ShapeError(f"axes must be (K,) axis indices or (K, 3) body unit vectors with K = {K}; got {a.shape}")


def rate_table_profile(
    rates: ArrayLike,
    axes: ArrayLike,
    dwell_s: float,
    fs: float,
    transition_s: float = 2.0,
    *,
    remount_s: float = 5.0,
    mounting: str = "up",
    lat: float | None = None,
    lon: float = 0.0,
    h: float = 0.0,
    t0: float = 0.0,
    name: str = "rate_table",
) -> Profile:
    """Single-axis rate-table sequence: constant rates about chosen body axes.

    The IMU sits at the table centre (no centripetal acceleration) with the
    commanded body axis along the table axis, which is vertical: pointing up
    (``mounting="up"``, that axis's accelerometer reads +g) or down
    (``"down"``).  Body rate during a step: ``ω_nb^b = rate · axis``.
    Rate changes are minimum-jerk ramps of ``transition_s``; when the axis
    changes the table stops (ramp to 0), the IMU is re-mounted (a rest-to-rest
    move of ``remount_s``) and spun up again.

    Parameters
    ----------
    rates : array_like
        (K,) commanded rates, rad/s (use ``np.deg2rad`` for °/s).
    axes : array_like
        (K,) axis indices (0, 1, 2) or (K, 3) body unit vectors.
    dwell_s : float
        Time at each constant rate, s.
    fs : float
        Sample rate, Hz.

    transition_s : float
        Duration of each rate ramp, s.
    remount_s : float
        Duration of the re-mounting move when the axis changes, s.
    mounting : {"up", "down"}
        Direction of the commanded body axis along the vertical table axis.
    lat : float, optional
        Geodetic latitude of the fixed position, rad (None: no position).
    lon : float
        Longitude, rad.
    h : float
        Ellipsoidal height, m.
    t0 : float
        Time of the first sample, s.
    name : str
        Profile name.

    Returns
    -------
    Profile
        The trajectory (exact body rates) and its segment table.

    Raises
    ------
    ShapeError
        If ``rates`` is not a 1-D array of finite rates, or ``axes`` does not match it.
    InvalidInputError
        If ``mounting`` is unknown.
    """
    r = np.asarray(rates, dtype=float)
    if r.ndim != 1 or r.size < 1 or not np.all(np.isfinite(r)):
        raise ShapeError(f"rates must be a 1-D array of finite rates in rad/s; got shape {r.shape}")
    K = r.size
    ax = _axis_vectors(axes, K)
    if mounting not in ("up", "down"):
        raise InvalidInputError(f"mounting must be 'up' or 'down'; got {mounting!r}")
    sgn = 1.0 if mounting == "up" else -1.0
    dw = _positive(dwell_s, "dwell_s")
    tr = _positive(transition_s, "transition_s")
    rm = _positive(remount_s, "remount_s")

    b = _Builder(orientations_from_up((sgn * ax[0])[None, :])[0])
    for i in range(K):
        if i and not np.allclose(ax[i], ax[i - 1]):
            if b.rate != 0.0:
                b.ramp(tr, b.axis, 0.0)
            up_now = up_from_orientations(b.q)[0]
            q_new = orientations_from_up(np.array([up_now, sgn * ax[i]]), b.q)[1]
            b.move_to(q_new, rm)
        if r[i] != b.rate:
            b.ramp(tr, ax[i], float(r[i]))
        b.rate_const(dw, ax[i], float(r[i]), step=i)
    return b.build(name, fs, t0, lat, lon, h)


def rate_table_steps(step_dps: float = 25.0, max_dps: float = 250.0) -> tuple[Array, NDArray[np.int64]]:
    """The rates and axes of the 120-step rate-table test (:func:`rate_table_step_profile`).

    Per axis (x, then y, then z):
    ``[0, 25, …, 250, 225, …, 25, 0, −25, …, −250, −225, …, −25]`` °/s
    (11 + 9 + 1 + 10 + 9 = 40 rates), 30 s each in the source.

    Parameters
    ----------
    step_dps : float
        Rate step, °/s.
    max_dps : float
        Largest rate, °/s (a multiple of ``step_dps``).

    Returns
    -------
    rates : numpy.ndarray, shape (K,)
        Commanded rates, rad/s.
    axes : numpy.ndarray of int64, shape (K,)
        Body axis index (0, 1, 2) of each step.

    Raises
    ------
    InvalidInputError
        If ``max_dps`` is not a positive multiple of ``step_dps``.

    References
    ----------
    Günhan 2014, §4.1.2.
    """
    n = int(round(max_dps / step_dps))
    if n < 1 or abs(n * step_dps - max_dps) > 1e-9:
        raise InvalidInputError(f"max_dps must be a positive multiple of step_dps; got {max_dps}, {step_dps}")
    up = np.arange(0, n + 1)  # 0 … n
    seq = np.concatenate([up, up[-2:0:-1], [0], -up[1:], -up[-2:0:-1]]) * step_dps
    rates = np.tile(seq, 3) * DEG
    axes = np.repeat(np.arange(3), seq.size)
    return rates, axes


def rate_table_step_profile(
    fs: float = 100.0,
    dwell_s: float = 30.0,
    transition_s: float = 2.0,
    *,
    remount_s: float = 5.0,
    mounting: str = "up",
    lat: float | None = None,
    lon: float = 0.0,
    h: float = 0.0,
) -> Profile:
    """The 120-step ±250 °/s rate-table test: 40 rate steps about each axis in turn, 30 s per step by default.

    Parameters
    ----------
    fs : float
        Sample rate, Hz.
    dwell_s : float
        Time at each constant rate, s.
    transition_s : float
        Duration of each rate ramp, s.
    remount_s : float
        Duration of the re-mounting move when the axis changes, s.
    mounting : {"up", "down"}
        Direction of the commanded body axis along the table axis.
    lat : float, optional
        Geodetic latitude of the fixed position, rad (None: no position).
    lon : float
        Longitude, rad.
    h : float
        Ellipsoidal height, m.

    Returns
    -------
    Profile
        The trajectory (exact body rates) and its segment table.

    References
    ----------
    Günhan 2014, §4.1.2 (the test's rate sequence).
    """
    rates, axes = rate_table_steps()
    return rate_table_profile(
        rates, axes, dwell_s, fs, transition_s, remount_s=remount_s, mounting=mounting,
        lat=lat, lon=lon, h=h, name="thesis_rate_table",
    )


def ferraris_profile(
    fs: float = 100.0,
    dwell_s: float = 30.0,
    transition_s: float = 4.0,
    rotation_s: float = 10.0,
    *,
    angle: float = 2 * np.pi,
    lat: float | None = None,
    lon: float = 0.0,
    h: float = 0.0,
) -> Profile:
    """Ferraris-style test: six static poses, then a known turn about each axis.

    Six positions (:func:`six_position_up_vectors`), then for each body axis
    i: mount with axis i up, rest ``dwell_s``, turn by ``angle`` (rad, default
    one full turn) about axis i over ``rotation_s`` (minimum-jerk, segment kind
    ``"rotation"``), rest ``dwell_s``.  The gyro integral over a rotation
    segment equals ``angle`` (Ferraris et al. 1995).

    Parameters
    ----------
    fs : float
        Sample rate, Hz.
    dwell_s : float
        Rest before and after each pose or turn, s.
    transition_s : float
        Duration of each move, s.
    rotation_s : float
        Duration of each turn, s.
    angle : float
        Turn angle, rad.
    lat : float, optional
        Geodetic latitude of the fixed position, rad (None: no position).
    lon : float
        Longitude, rad.
    h : float
        Ellipsoidal height, m.

    Returns
    -------
    Profile
        The trajectory (exact body rates) and its segment table.
    """
    rs = _positive(rotation_s, "rotation_s")
    tr = _positive(transition_s, "transition_s")
    dw = _positive(dwell_s, "dwell_s")
    q6 = six_position_orientations()
    b = _Builder(q6[0])
    step = 0
    for i in range(6):
        if i:
            b.move_to(q6[i], tr)
        b.static(dw, step=step)
        step += 1
    for i in range(3):
        up_now = up_from_orientations(b.q)[0]
        q_new = orientations_from_up(np.array([up_now, np.eye(3)[i]]), b.q)[1]
        b.move_to(q_new, tr)
        b.static(dw, step=step)
        step += 1
        b.turn(np.eye(3)[i], angle, rs)
        b.static(dw, step=step)
        step += 1
    return b.build("ferraris", fs, 0.0, lat, lon, h)

