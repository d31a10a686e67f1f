"""GNSS solutions: the :class:`GnssData` recording and its readers.

A :class:`GnssData` holds position fixes (geodetic, radians inside) with their
1-σ north/east/down standard deviations and, optionally, NED velocity with its
σ.  Its constructor refuses what no receiver produces: time stamps that do not
increase, latitudes outside ±90°, longitudes outside ±360°, σ ≤ 0, non-finite
values.

Readers:

* :func:`read_gnss_text`: the KF-GINS / awesome-gins-datasets text file
  (7 columns: seconds of week, lat °, lon °, h m, σ_N σ_E σ_D m; or 13 columns
  with v_N v_E v_D m/s after h and the velocity σ last);
* :func:`read_gnss_csv`: any CSV with a header, columns chosen by name and the
  angle unit declared.

Degrees are declared, never guessed: a file declared in degrees whose every
fix lies inside ±π/2 latitude and ±π longitude looks like radians and is
refused (pass ``angle_unit="deg_small"`` for a track really within 1.57° N/S
and 3.14° E/W of (0°, 0°)); a file declared in radians with a latitude beyond
π/2 is refused as degrees.

:func:`write_gnss_text` writes the KF-GINS text file (atomically).
"""

from __future__ import annotations

import csv
import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import FileFormatError, InvalidInputError, NonFiniteError, ShapeError, TimeOrderError
from imunav.files import atomic_path
from imunav.io._common import check_nonempty, wrap_read_errors

__all__ = ["GnssData", "read_gnss_text", "read_gnss_csv", "write_gnss_text", "read_table", "write_table",
           "ANGLE_UNITS", "lat_lon_radians"]

Array = NDArray[np.float64]

#: Angle units a reader accepts: degrees, radians, or degrees for a track near (0°, 0°) (no radians check).
ANGLE_UNITS = ("deg", "rad", "deg_small")


def _n3(x: ArrayLike | None, n: int, name: str, where: str) -> Array | None:
    if x is None:
        return None
    a = np.array(x, dtype=float)
    if a.ndim == 1 and a.shape == (3,):
        a = np.tile(a, (n, 1))
    if a.shape != (n, 3):
        raise ShapeError(f"{where}: {name} must have shape ({n}, 3) or (3,); got {a.shape}")
    if not np.all(np.isfinite(a)):
        rows = np.flatnonzero(~np.all(np.isfinite(a), axis=1))
        raise NonFiniteError(f"{where}: {name} has non-finite values at rows {rows[:10].tolist()}")
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class GnssData:
    """GNSS fixes in SI units.

    Parameters
    ----------
    t : array_like, shape (N,)
        Strictly increasing time, s (seconds of week, or any clock shared with the IMU).
    lla : array_like, shape (N, 3)
        Geodetic position of the antenna: lat rad (within ±π/2), lon rad (within ±2π), ellipsoidal
        height m.
    pos_std : array_like, shape (N, 3) or (3,)
        1-σ of the position, north/east/down, m (> 0).
    vel_ned : array_like, shape (N, 3), or None
        NED velocity of the antenna, m/s.
    vel_std : array_like, shape (N, 3) or (3,), or None
        1-σ of the velocity, north/east/down, m/s (> 0); given with ``vel_ned`` and only with it.
    meta : dict
        Free-form metadata (``"source"`` file, simulated errors, epochs ``"removed"`` ...).

    Raises
    ------
    ShapeError
        If an array has the wrong shape (or there is no epoch).
    NonFiniteError
        If a value is NaN or infinite.
    TimeOrderError
        If ``t`` does not strictly increase.
    InvalidInputError
        If a latitude or longitude is out of range (degrees given as radians), a σ is <= 0, or only
        one of ``vel_ned`` / ``vel_std`` is given.
    """

    t: Array
    lla: Array
    pos_std: Array
    vel_ned: Array | None = None
    vel_std: Array | None = None
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        where = str(self.meta.get("source", "GnssData"))
        t = np.array(self.t, dtype=float)
        if t.ndim != 1 or t.size < 1:
            raise ShapeError(f"{where}: t must be 1-D with at least one epoch; got shape {t.shape}")
        if not np.all(np.isfinite(t)):
            raise NonFiniteError(f"{where}: t has non-finite values at rows {np.flatnonzero(~np.isfinite(t))[:10].tolist()}")
        bad = np.flatnonzero(np.diff(t) <= 0)
        if bad.size:
            k = int(bad[0]) + 1
            raise TimeOrderError(
                f"{where}: GNSS time is not strictly increasing at row {k} (t = {t[k - 1]!r} then {t[k]!r}; "
                f"{bad.size} such rows); sort the file by time and remove duplicate epochs"
            )
        t.setflags(write=False)
        n = t.size
        lla = _n3(self.lla, n, "lla", where)
        assert lla is not None
        lat_bad = np.flatnonzero(np.abs(lla[:, 0]) > np.pi / 2)
        if lat_bad.size:
            k = int(lat_bad[0])
            raise InvalidInputError(f"{where}: latitude {lla[k, 0]!r} rad at row {k} is outside [-pi/2, pi/2]; "
                                    "GnssData holds radians (did a reader get degrees declared as radians?)")
        lon_bad = np.flatnonzero(np.abs(lla[:, 1]) > 2 * np.pi)
        if lon_bad.size:
            k = int(lon_bad[0])
            raise InvalidInputError(f"{where}: longitude {lla[k, 1]!r} rad at row {k} is outside [-2pi, 2pi]; "
                                    "GnssData holds radians")
        s = object.__setattr__
        s(self, "t", t)
        s(self, "lla", lla)
        s(self, "pos_std", self._sigma(self.pos_std, n, "pos_std", where))
        if (self.vel_ned is None) != (self.vel_std is None):
            raise InvalidInputError(f"{where}: vel_ned and vel_std go together; give both or neither")
        s(self, "vel_ned", _n3(self.vel_ned, n, "vel_ned", where))
        if self.vel_std is not None:
            s(self, "vel_std", self._sigma(self.vel_std, n, "vel_std", where))

    @staticmethod
    def _sigma(x: ArrayLike, n: int, name: str, where: str) -> Array:
        a = _n3(x, n, name, where)
        assert a is not None
        bad = np.argwhere(a <= 0)
        if bad.size:
            r, c = (int(v) for v in bad[0])
            raise InvalidInputError(
                f"{where}: {name}[{r}, {'NED'[c]}] = {a[r, c]!r}; a standard deviation must be > 0 "
                f"({bad.shape[0]} such values). Give the receiver's 1-sigma, or a floor such as 0.01 m"
            )
        return a

    @property
    def n(self) -> int:
        """Number of epochs."""
        return int(self.t.size)

    def select(self, mask: ArrayLike, note: str | None = None) -> "GnssData":
        """The epochs where ``mask`` is true; ``note`` (what removed the others and how many) goes to
        ``meta["removed"]`` so that nothing is dropped silently.

        Parameters
        ----------
        mask : array_like of bool, shape (N,)
            True for the epochs to keep.
        note : str, optional
            Why the other epochs are removed; recorded with their count when some are.

        Returns
        -------
        GnssData
            A new recording with the kept epochs and the updated ``meta``.

        Raises
        ------
        ShapeError
            If ``mask`` does not have the shape of ``t``.
        InvalidInputError
            If no epoch is left.
        """
        m = np.asarray(mask, dtype=bool)
        if m.shape != self.t.shape:
            raise ShapeError(f"mask must have shape {self.t.shape}; got {m.shape}")
        meta = dict(self.meta)
        if note is not None and not m.all():
            meta["removed"] = list(meta.get("removed", [])) + [{"reason": note, "epochs": int((~m).sum())}]
        if not m.any():
            raise InvalidInputError(f"{self.meta.get('source', 'GnssData')}: no GNSS epoch left after {note or 'selection'}")
        return GnssData(self.t[m], self.lla[m], self.pos_std[m],
                        None if self.vel_ned is None else self.vel_ned[m],
                        None if self.vel_std is None else self.vel_std[m], meta)

    def within(self, t_start: float, t_end: float) -> "GnssData":
        """The epochs inside ``[t_start, t_end]`` (the IMU span), recorded in ``meta["removed"]``.

        Parameters
        ----------
        t_start, t_end : float
            The span, s, on the clock of ``t`` (bounds included).

        Returns
        -------
        GnssData
            The epochs inside the span (:meth:`select`).

        Raises
        ------
        InvalidInputError
            When no epoch lies inside the span (the GNSS and IMU files do not overlap: wrong file, or
            another time base such as UTC against GPS seconds of week).
        """
        inside = (self.t >= t_start) & (self.t <= t_end)
        if not inside.any():
            raise InvalidInputError(
                f"{self.meta.get('source', 'GnssData')}: GNSS time {self.t[0]:.3f}..{self.t[-1]:.3f} s lies "
                f"outside the IMU span {t_start:.3f}..{t_end:.3f} s; both must use the same clock "
                "(GPS seconds of week for KF-GINS files)"
            )
        return self.select(inside, f"outside the IMU span {t_start:.3f}..{t_end:.3f} s")


# ---------------------------------------------------------------------------
# text tables (shared with imunav.io.kfgins)
# ---------------------------------------------------------------------------


def _read_table_fast(text: str, ncols: tuple[int, ...]) -> Array | None:
    """The values of a well-formed table without comments, parsed in C (:func:`numpy.fromstring`); None when the
    text has comments, rows of unequal length, another width or a value that is not a number, so that the
    line-by-line reader can name the fault."""
    if "#" in text:
        return None
    lines = text.split("\n")
    counts = [len(ln.split()) for ln in lines]
    nonempty = [c for c in counts if c]
    if not nonempty or nonempty[0] not in ncols or any(c != nonempty[0] for c in nonempty):
        return None
    width = nonempty[0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a token that is not a number ends the parse with a warning
        try:
            arr = np.fromstring(text, dtype=float, sep=" ")
        except (ValueError, DeprecationWarning):
            return None
    if arr.size != width * len(nonempty):
        return None
    return arr.reshape(len(nonempty), width)


def read_table(path: str | os.PathLike[str], ncols: tuple[int, ...], what: str) -> Array:
    """Whitespace- or comma-separated numeric table with one of ``ncols`` columns (``#`` comments).

    Parameters
    ----------
    path : str or os.PathLike
        The text file.
    ncols : tuple of int
        The numbers of columns accepted.
    what : str
        What the file holds, for the error messages (e.g. ``"KF-GINS GNSS"``).

    Returns
    -------
    numpy.ndarray, shape (rows, columns)
        The values, one row per data line.

    Raises
    ------
    FileFormatError
        Naming the file, for an empty, ragged or non-numeric file, or another number of columns.
    NonFiniteError
        If a value is NaN or infinite.
    """
    src = check_nonempty(path)
    with wrap_read_errors(src, what):
        text = Path(src).read_text(encoding="utf-8", errors="strict").replace(",", " ")
        fast = _read_table_fast(text, ncols)
        if fast is not None:
            arr = fast
            if not np.all(np.isfinite(arr)):
                k = int(np.flatnonzero(~np.all(np.isfinite(arr), axis=1))[0])
                raise NonFiniteError(f"{src}: non-finite value on data row {k + 1}")
            return arr
        rows = [ln.split("#", 1)[0].split() for ln in text.splitlines()]
        rows = [(i + 1, r) for i, r in enumerate(rows) if r]
        if not rows:
            raise FileFormatError(f"{src}: no data rows in this {what} file")
        width = len(rows[0][1])
        if width not in ncols:
            raise FileFormatError(f"{src}: {what} has {width} columns on line {rows[0][0]}; expected "
                                  f"{' or '.join(map(str, ncols))}")
        bad = [ln for ln, r in rows if len(r) != width]
        if bad:
            raise FileFormatError(f"{src}: line {bad[0]} has another number of columns than line {rows[0][0]} "
                                  f"({width}); the file may be truncated ({len(bad)} such lines)")
        try:
            arr = np.array([[float(v) for v in r] for _, r in rows])
        except ValueError as exc:
            raise FileFormatError(f"{src}: a value of this {what} file is not a number ({exc})") from None
    if not np.all(np.isfinite(arr)):
        k = int(np.flatnonzero(~np.all(np.isfinite(arr), axis=1))[0])
        raise NonFiniteError(f"{src}: non-finite value on data row {k + 1}")
    return arr


def write_table(path: str | os.PathLike[str], columns: list[ArrayLike], fmt: str = "%-15.9f") -> Path:
    """Write columns side by side as a space-separated text table, atomically (KF-GINS's ``%-15.9lf``).

    Parameters
    ----------
    path : str or os.PathLike
        Output file (replaced atomically: :func:`imunav.files.atomic_path`).
    columns : list of array_like
        The columns, each of shape (N,) or (N, k) (then k columns), same N.
    fmt : str
        ``printf`` format of each value (:func:`numpy.savetxt`).

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    arr = np.column_stack([np.asarray(c, dtype=float) for c in columns])
    row = " ".join([fmt] * arr.shape[1]) + "\n"  # what numpy.savetxt writes, formatted a block of rows at a time
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        for i in range(0, arr.shape[0], _ROWS_PER_BLOCK):
            block = arr[i:i + _ROWS_PER_BLOCK]
            fh.write(((row * block.shape[0]) % tuple(block.ravel().tolist())).encode("latin-1"))
    return Path(path)


_ROWS_PER_BLOCK = 20_000


def lat_lon_radians(lat: Array, lon: Array, angle_unit: str, src: str) -> tuple[Array, Array]:
    """Latitudes and longitudes declared in ``angle_unit`` (:data:`ANGLE_UNITS`) checked and converted to radians.

    Parameters
    ----------
    lat, lon : numpy.ndarray, shape (N,)
        Latitudes and longitudes as read, in ``angle_unit``.
    angle_unit : {"deg", "rad", "deg_small"}
        The declared unit (``"deg_small"``: degrees, without the looks-like-radians check).
    src : str
        The source (file name), for the error messages.

    Returns
    -------
    lat, lon : numpy.ndarray, shape (N,)
        The same angles in radians.

    Raises
    ------
    InvalidInputError
        Naming ``src`` and the row, for an unknown unit, values out of range, degrees declared as
        radians, or radians declared as degrees (see the module docstring).
    """
    if angle_unit not in ANGLE_UNITS:
        raise InvalidInputError(f"angle_unit {angle_unit!r} is unknown; use one of {ANGLE_UNITS}")
    if angle_unit == "rad":
        if np.any(np.abs(lat) > np.pi / 2) or np.any(np.abs(lon) > 2 * np.pi):
            k = int(np.flatnonzero((np.abs(lat) > np.pi / 2) | (np.abs(lon) > 2 * np.pi))[0])
            raise InvalidInputError(f"{src}: lat/lon ({lat[k]!r}, {lon[k]!r}) on data row {k + 1} are not radians "
                                    "(beyond pi/2 / 2pi); declare angle_unit='deg'")
        return lat, lon
    bad = np.flatnonzero((np.abs(lat) > 90) | (np.abs(lon) > 360))
    if bad.size:
        k = int(bad[0])
        raise InvalidInputError(f"{src}: latitude {lat[k]!r} / longitude {lon[k]!r} deg on data row {k + 1} is out "
                                "of range (|lat| <= 90, |lon| <= 360)")
    if angle_unit == "deg" and np.all(np.abs(lat) <= np.pi / 2) and np.all(np.abs(lon) <= np.pi):
        raise InvalidInputError(
            f"{src}: every fix lies within {np.pi / 2:.4f} deg latitude and {np.pi:.4f} deg longitude of (0, 0): "
            "these look like radians where degrees are declared. Convert them to degrees, or declare "
            "angle_unit='rad' (or 'deg_small' for a track that really is that close to (0 deg, 0 deg))"
        )
    return np.radians(lat), np.radians(lon)


def read_gnss_text(path: str | os.PathLike[str], *, angle_unit: str = "deg") -> GnssData:
    """Read a KF-GINS GNSS text file.

    Parameters
    ----------
    path : str or os.PathLike
        File with 7 columns (seconds of week, lat, lon, h m, σ_N σ_E σ_D m) or 13 columns
        (seconds of week, lat, lon, h, v_N v_E v_D m/s, σ_N σ_E σ_D m, σ_vN σ_vE σ_vD m/s).
    angle_unit : {"deg", "rad", "deg_small"}
        Unit of lat and lon in the file: ``"deg"`` for KF-GINS (see the module docstring).

    Returns
    -------
    GnssData
        The fixes, radians inside, ``meta["source"]`` the file.

    Raises
    ------
    FileFormatError
        If the file is empty, ragged, not numeric, or has another number of columns.
    InvalidInputError
        If the angles do not match ``angle_unit``, or a value is not valid for :class:`GnssData`.
    """
    a = read_table(path, (7, 13), "KF-GINS GNSS")
    src = os.fspath(path)
    lat, lon = lat_lon_radians(a[:, 1], a[:, 2], angle_unit, src)
    lla = np.column_stack([lat, lon, a[:, 3]])
    meta = {"source": src, "format": "kf-gins-gnss"}
    if a.shape[1] == 7:
        return GnssData(a[:, 0], lla, a[:, 4:7], meta=meta)
    return GnssData(a[:, 0], lla, a[:, 7:10], vel_ned=a[:, 4:7], vel_std=a[:, 10:13], meta=meta)


def write_gnss_text(path: str | os.PathLike[str], gnss: GnssData) -> Path:
    """Write ``gnss`` as a KF-GINS GNSS text file (7 columns, or 13 with velocity), atomically.

    Latitude and longitude are written in degrees, the layout that :func:`read_gnss_text` reads.

    Parameters
    ----------
    path : str or os.PathLike
        Output file.
    gnss : GnssData
        The fixes.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    cols: list[ArrayLike] = [gnss.t, np.degrees(gnss.lla[:, 0]), np.degrees(gnss.lla[:, 1]), gnss.lla[:, 2]]
    if gnss.vel_ned is not None and gnss.vel_std is not None:
        cols += [*gnss.vel_ned.T, *gnss.pos_std.T, *gnss.vel_std.T]
    else:
        cols += [*gnss.pos_std.T]
    return write_table(path, cols)


def read_gnss_csv(
    path: str | os.PathLike[str],
    *,
    time: str = "t",
    lat: str = "lat",
    lon: str = "lon",
    height: str = "h",
    pos_std: tuple[str, str, str] | None = ("std_n", "std_e", "std_d"),
    vel: tuple[str, str, str] | None = None,
    vel_std: tuple[str, str, str] | None = None,
    angle_unit: str = "deg",
    default_pos_std: ArrayLike | None = None,
    default_vel_std: ArrayLike | None = None,
) -> GnssData:
    """Read GNSS fixes from a CSV file with a header row, columns chosen by name.

    Parameters
    ----------
    path : str or os.PathLike
        CSV file (comma separated, header on the first line, ``#`` lines skipped).
    time, lat, lon, height : str
        Column names of time (s), latitude, longitude (in ``angle_unit``) and ellipsoidal height (m).
    pos_std : tuple of 3 str, or None
        Names of the north/east/down position σ columns (m), or None to use ``default_pos_std``.
    vel, vel_std : tuple of 3 str, or None
        Names of the NED velocity (m/s) and of its σ columns (m/s), or None.
    angle_unit : {"deg", "rad", "deg_small"}
        Unit of the latitude and longitude columns (see the module docstring).
    default_pos_std, default_vel_std : array_like, shape (3,), optional
        σ north/east/down used when the file has no σ columns, m and m/s.

    Returns
    -------
    GnssData
        The fixes, radians inside, ``meta["source"]`` the file.

    Raises
    ------
    FileFormatError
        If the file has no data row, lacks a named column, or a value is empty or not a number.
    NonFiniteError
        If a value is NaN or infinite.
    InvalidInputError
        If no position σ is given (neither columns nor default), velocity has no σ, or the angles do
        not match ``angle_unit``.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "fix.csv"
    >>> _ = p.write_text("t,lat,lon,h\\n0,30.5,114.5,20\\n1,30.5000001,114.5,20\\n")
    >>> read_gnss_csv(p, pos_std=None, default_pos_std=(1, 1, 2)).n
    2
    """
    src = check_nonempty(path)
    with wrap_read_errors(src, "GNSS CSV"), open(src, newline="", encoding="utf-8") as fh:
        rows = [r for r in csv.reader(ln for ln in fh if not ln.lstrip().startswith("#")) if r]
    if len(rows) < 2:
        raise FileFormatError(f"{src}: a GNSS CSV needs a header row and at least one data row")
    header = [h.strip() for h in rows[0]]
    wanted = [time, lat, lon, height, *(pos_std or ()), *(vel or ()), *(vel_std or ())]
    missing = [c for c in wanted if c not in header]
    if missing:
        raise FileFormatError(f"{src}: no column(s) {missing}; the header has {header}. "
                              "Name the columns with time=, lat=, lon=, height=, pos_std=, vel=, vel_std=")
    col: dict[str, Array] = {}
    for c in wanted:
        j = header.index(c)
        vals = np.empty(len(rows) - 1)
        for k, r in enumerate(rows[1:]):
            try:
                vals[k] = float(r[j])
            except (ValueError, IndexError):
                raise FileFormatError(f"{src}: column {c!r} is empty or not a number on data row {k + 1}") from None
        if not np.all(np.isfinite(vals)):
            k = int(np.flatnonzero(~np.isfinite(vals))[0])
            raise NonFiniteError(f"{src}: column {c!r} is not finite on data row {k + 1}")
        col[c] = vals
    la, lo = lat_lon_radians(col[lat], col[lon], angle_unit, src)
    n = la.size
    if pos_std is not None:
        ps: ArrayLike = np.column_stack([col[c] for c in pos_std])
    elif default_pos_std is not None:
        ps = np.broadcast_to(np.asarray(default_pos_std, dtype=float), (n, 3))
    else:
        raise InvalidInputError(f"{src}: give pos_std column names or default_pos_std (m); a fix needs its sigma")
    v = vs = None
    if vel is not None:
        v = np.column_stack([col[c] for c in vel])
        if vel_std is not None:
            vs = np.column_stack([col[c] for c in vel_std])
        elif default_vel_std is not None:
            vs = np.broadcast_to(np.asarray(default_vel_std, dtype=float), (n, 3))
        else:
            raise InvalidInputError(f"{src}: give vel_std column names or default_vel_std (m/s) with vel")
    return GnssData(col[time], np.column_stack([la, lo, col[height]]), ps, v, vs,
                    {"source": src, "format": "csv"})
