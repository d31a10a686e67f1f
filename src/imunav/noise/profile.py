"""The noise profile of a sensor: what the filters' noise parameters are made from.

A :class:`NoiseProfile` holds, for each sensor of an IMU record (gyroscope, accelerometer, magnetometer when it was
analysed) and each of its three axes, the three IEEE-952 terms the estimators of the package take, each with its
standard error (IEEE Std 952-1997, Annex C; the Allan fit of :func:`imunav.noise.fit_noise`):

=====================  ==============================  ==========================  ==========================
term (vocabulary)      meaning                         gyro                        accelerometer
=====================  ==============================  ==========================  ==========================
``noise_density``      white noise N (ARW / VRW)       rad/s/sqrt(Hz) = rad/√s     m/s^2/sqrt(Hz) = m/s/√s
``bias_instability``   flicker floor B                 rad/s                       m/s^2
``bias_random_walk``   rate / accel random walk K      rad/s/sqrt(s)               m/s^2/sqrt(s)
=====================  ==============================  ==========================  ==========================

(a magnetometer's terms are in its field unit: ``uT/sqrt(Hz)``, ``uT``, ``uT/sqrt(s)``).  The names are those of
:mod:`imunav.vocabulary` (``<x>_noise_density``, ``<x>_bias_random_walk``), the sensor being the table they sit in.

A term the fit did not identify is marked ``identified = false`` with a standard error NaN; a random walk the
record is too short to show is then the upper bound ``K = sqrt(3 AVAR(tau_max) / tau_max)`` of the fitted curve
(the filters refuse a zero random walk; the same rule as the Kalibr / OpenVINS / VINS writers of
:mod:`imunav.io`), a bias instability the selection left out is 0.

The profile is written as TOML or JSON (by the suffix) and read back exactly (:meth:`NoiseProfile.write`,
:func:`read_noise_profile`): floats are written with ``repr`` (shortest round-trip form); a NaN standard error is
``nan`` in TOML and ``null`` in JSON (strict JSON).  Reading checks the whole document: unknown keys, units other
than the SI ones above, negative or non-finite values, and arrays that are not three per-axis values are refused
with a :class:`~imunav.errors.ConfigError` naming the file, the key and the fix.

The configurations of the filters are built from a profile by their ``from_noise_profile`` class methods
(:class:`~imunav.attitude.mekf.MekfConfig`, :class:`~imunav.attitude.ukf.UkfConfig`,
:class:`~imunav.attitude.gravity_kf.GravityKfConfig`, :class:`~imunav.ins.zupt.filter.ZuptConfig`,
:class:`~imunav.ins.gins.config.GinsConfig`); :meth:`NoiseProfile.noise_std` gives the per-sample standard
deviation ``sigma = N sqrt(fs)`` that per-sample configurations take (white noise of one-sided density N sampled at
fs: AVAR(1/fs) = N^2 fs = sigma^2; IEEE Std 952-1997, C.1).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import ConfigError, InvalidInputError
from imunav.files import atomic_path, json_text, read_json
from imunav.io._noise import _k_upper_bound  # the K bound the Kalibr / OpenVINS / VINS writers use
from imunav.results import Result
from imunav.toml import read_toml, toml_text

if TYPE_CHECKING:  # annotations only
    from imunav.noise.fit import NoiseFit

__all__ = ["FORMAT", "SENSORS", "TERMS", "NoiseProfile", "NoiseTerm", "SensorNoise", "read_noise_profile",
           "term_units"]

#: The ``format`` key of a profile file.
FORMAT = "imunav noise profile"
#: Version of the file layout.
VERSION = 1
#: The sensors a profile may hold, and the unit of each (a magnetometer's is its field unit).
SENSORS: dict[str, tuple[str, ...]] = {"gyro": ("rad/s",), "accel": ("m/s^2",),
                                       "mag": ("uT", "nT", "T", "gauss", "mG")}
#: The terms of each sensor, in file order.
TERMS = ("noise_density", "bias_instability", "bias_random_walk")
_TERM_KEYS = ("unit", "value", "se", "identified")
_TOP_KEYS = ("format", "version", "source", "fs", "duration_s", *SENSORS)


def term_units(unit: str) -> dict[str, str]:
    """The SI unit of each term of a sensor whose output is in ``unit``.

    Parameters
    ----------
    unit : str
        The sensor's unit (``"rad/s"``, ``"m/s^2"``, or a field unit).

    Returns
    -------
    dict
        ``{"noise_density": unit/sqrt(Hz), "bias_instability": unit, "bias_random_walk": unit/sqrt(s)}``.
    """
    return {"noise_density": f"{unit}/sqrt(Hz)", "bias_instability": unit, "bias_random_walk": f"{unit}/sqrt(s)"}


def _axes(x: ArrayLike, dtype: type = float) -> NDArray[Any]:
    a = np.array(x, dtype=dtype).reshape(-1)
    return a


@dataclass(frozen=True, eq=False)
class NoiseTerm(Result):
    """One noise term of one sensor, per axis.

    Attributes
    ----------
    value : numpy.ndarray, shape (3,)
        The term on x, y, z (SI unit of the term; >= 0).
    se : numpy.ndarray, shape (3,)
        Its standard error (NaN where the term was not identified).
    identified : numpy.ndarray of bool, shape (3,)
        Whether the fit identified the term on that axis (else ``value`` is a bound or 0, see the module docstring).

    Raises
    ------
    InvalidInputError
        If an array is not three values, a value is negative or not finite, or a standard error is negative.
    """

    value: NDArray[np.float64]
    se: NDArray[np.float64]
    identified: NDArray[np.bool_]

    def __post_init__(self) -> None:
        s = object.__setattr__
        s(self, "value", _axes(self.value))
        s(self, "se", _axes(self.se))
        s(self, "identified", _axes(self.identified, bool))
        for name in ("value", "se", "identified"):
            if getattr(self, name).shape != (3,):
                raise InvalidInputError(f"NoiseTerm.{name} holds {getattr(self, name).size} values; give one per "
                                        "axis (x, y, z)")
        if not (np.all(np.isfinite(self.value)) and np.all(self.value >= 0)):
            raise InvalidInputError(f"NoiseTerm.value = {self.value.tolist()}: a noise term is finite and >= 0")
        if np.any(self.se < 0) or np.any(np.isinf(self.se)):
            raise InvalidInputError(f"NoiseTerm.se = {self.se.tolist()}: a standard error is >= 0 and finite "
                                    "(NaN where the term was not identified)")

    def __eq__(self, other: object) -> bool:
        return (isinstance(other, NoiseTerm) and np.array_equal(self.value, other.value)
                and np.array_equal(self.se, other.se, equal_nan=True)
                and np.array_equal(self.identified, other.identified))

    __hash__ = None  # type: ignore[assignment]

    def combined(self, combine: str = "max") -> float:
        """One value for the three axes, for a filter that takes one.

        Parameters
        ----------
        combine : {"max", "mean"}
            The largest axis (conservative, default; the rule of the Kalibr writer) or the mean.

        Returns
        -------
        float
            The value, in the term's unit.

        Raises
        ------
        InvalidInputError
            If ``combine`` is neither.
        """
        if combine == "max":
            return float(np.max(self.value))
        if combine == "mean":
            return float(np.mean(self.value))
        raise InvalidInputError(f"combine={combine!r}: use 'max' or 'mean'")

    def to_dict(self) -> dict[str, Any]:
        """The term as plain lists (NaN as None: strict JSON).

        Returns
        -------
        dict
            ``value``, ``se``, ``identified``.
        """
        return {"value": self.value.tolist(), "se": [None if math.isnan(v) else float(v) for v in self.se],
                "identified": [bool(b) for b in self.identified]}


@dataclass(frozen=True)
class SensorNoise(Result):
    """The noise terms of one three-axis sensor.

    Attributes
    ----------
    unit : str
        The sensor's unit: ``"rad/s"`` (gyro), ``"m/s^2"`` (accelerometer), a field unit (magnetometer).
    noise_density : NoiseTerm
        White noise N, unit/sqrt(Hz) (the angle / velocity random walk).
    bias_instability : NoiseTerm
        Bias instability B (flicker floor; Allan deviation ``0.664 B``), unit.
    bias_random_walk : NoiseTerm
        Bias random walk K (rate / acceleration random walk), unit/sqrt(s).
    """

    unit: str
    noise_density: NoiseTerm
    bias_instability: NoiseTerm
    bias_random_walk: NoiseTerm

    def units(self) -> dict[str, str]:
        """The unit of each term (:func:`term_units`).

        Returns
        -------
        dict
            Term name -> unit.
        """
        return term_units(self.unit)

    def to_dict(self) -> dict[str, Any]:
        """The sensor's table: ``unit`` and one table per term with its own ``unit``.

        Returns
        -------
        dict
            ``{"unit": ..., "noise_density": {"unit", "value", "se", "identified"}, ...}``.
        """
        u = self.units()
        return {"unit": self.unit, **{t: {"unit": u[t], **getattr(self, t).to_dict()} for t in TERMS}}


@dataclass(frozen=True)
class NoiseProfile(Result):
    """Noise profile of one sensor unit (module docstring): per sensor and axis N, B, K with standard errors.

    Attributes
    ----------
    fs : float
        Sample rate of the record the profile was identified on, Hz (the default rate of
        :meth:`noise_std`).
    duration_s : float
        Length of that record, s (a random walk shows only on records much longer than 1 / its corner).
    gyro, accel, mag : SensorNoise or None
        The sensors analysed (at least one).
    source : str
        Where it came from (file, segment), for the reader.

    Raises
    ------
    InvalidInputError
        If ``fs`` or ``duration_s`` is not finite and > 0, no sensor is given, or a sensor has the wrong unit.
    """

    fs: float
    duration_s: float
    gyro: SensorNoise | None = None
    accel: SensorNoise | None = None
    mag: SensorNoise | None = None
    source: str = ""

    def __post_init__(self) -> None:
        for name in ("fs", "duration_s"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.floating)) or not (math.isfinite(v) and v > 0):
                raise InvalidInputError(f"NoiseProfile.{name} = {v!r}: must be a finite number > 0")
            object.__setattr__(self, name, float(v))
        if self.sensors() == ():
            raise InvalidInputError("a NoiseProfile holds at least one sensor (gyro, accel or mag)")
        for s in self.sensors():
            unit = getattr(self, s).unit
            if unit not in SENSORS[s]:
                raise InvalidInputError(f"NoiseProfile.{s}.unit = {unit!r}: the {s} is in {' or '.join(SENSORS[s])}")

    def sensors(self) -> tuple[str, ...]:
        """The sensors the profile holds, in the order gyro, accel, mag.

        Returns
        -------
        tuple of str
            Their names.
        """
        return tuple(s for s in SENSORS if getattr(self, s) is not None)

    def sensor(self, name: str, needed_by: str = "this configuration") -> SensorNoise:
        """One sensor's terms, or an error saying which configuration needs it.

        Parameters
        ----------
        name : {"gyro", "accel", "mag"}
            The sensor.
        needed_by : str
            Who asks, for the message.

        Returns
        -------
        SensorNoise
            Its terms.

        Raises
        ------
        ConfigError
            If the profile has no such sensor.
        """
        s = getattr(self, name, None) if name in SENSORS else None
        if s is None:
            raise ConfigError(f"{needed_by} needs the {name} noise; this profile ({self.source or 'no source'}) "
                              f"holds {', '.join(self.sensors())}: make it from a record with {name} channels "
                              f"(imunav noise REC --profile OUT.toml)")
        return s

    def noise_std(self, name: str, fs: float | None = None, combine: str | None = "max") -> Any:
        """Per-sample standard deviation of a sensor's white noise at rate ``fs``: ``sigma = N sqrt(fs)``.

        Parameters
        ----------
        name : {"gyro", "accel", "mag"}
            The sensor.
        fs : float, optional
            Sample rate of the filter, Hz (default: the profile's :attr:`fs`).
        combine : {"max", "mean"} or None
            One value for the three axes (:meth:`NoiseTerm.combined`), or None for the three.

        Returns
        -------
        float or numpy.ndarray, shape (3,)
            sigma in the sensor's unit.

        Raises
        ------
        InvalidInputError
            If ``fs`` is not finite and > 0.
        ConfigError
            If the profile lacks the sensor.
        """
        rate = self.fs if fs is None else fs
        if isinstance(rate, bool) or not (isinstance(rate, (int, float, np.floating)) and math.isfinite(rate)
                                          and rate > 0):
            raise InvalidInputError(f"fs = {fs!r}: the filter's sample rate is a finite number > 0 (Hz)")
        term = self.sensor(name).noise_density
        if combine is None:
            return term.value * math.sqrt(rate)
        return term.combined(combine) * math.sqrt(rate)

    def to_dict(self) -> dict[str, Any]:
        """The document written to TOML / JSON (module docstring).

        Returns
        -------
        dict
            ``format``, ``version``, ``source``, ``fs``, ``duration_s`` and one table per sensor.
        """
        d: dict[str, Any] = {"format": FORMAT, "version": VERSION, "source": self.source, "fs": self.fs,
                             "duration_s": self.duration_s}
        for s in self.sensors():
            d[s] = getattr(self, s).to_dict()
        return d

    def write(self, path: str | os.PathLike[str]) -> Path:
        """Write the profile atomically: TOML for ``.toml``, JSON for ``.json`` (strict: null, never NaN).

        Parameters
        ----------
        path : str or os.PathLike
            The file; its suffix picks the format.

        Returns
        -------
        pathlib.Path
            ``path``.

        Raises
        ------
        InvalidInputError
            If the suffix is neither ``.toml`` nor ``.json``.
        """
        p = Path(path)
        suffix = p.suffix.lower()
        if suffix == ".toml":
            d = self.to_dict()
            for s in self.sensors():  # TOML has no null: a standard error the fit has none for is nan
                for t in TERMS:
                    d[s][t]["se"] = [float("nan") if v is None else v for v in d[s][t]["se"]]
            text = "# imunav noise profile: per axis x, y, z; SI units (the unit of each term beside it)\n" + \
                toml_text(d)
        elif suffix == ".json":
            text = json_text(self.to_dict(), indent=1)
        else:
            raise InvalidInputError(f"{p}: a noise profile is written as .toml or .json; give one of these suffixes")
        with atomic_path(p) as tmp:
            tmp.write_text(text, encoding="utf-8")
        return p

    @classmethod
    def read(cls, path: str | os.PathLike[str]) -> NoiseProfile:
        """Read a profile written by :meth:`write` (:func:`read_noise_profile`).

        Parameters
        ----------
        path : str or os.PathLike
            A ``.toml`` or ``.json`` file.

        Returns
        -------
        NoiseProfile
            The profile.
        """
        return read_noise_profile(path)

    @classmethod
    def from_dict(cls, d: Any, where: str = "noise profile") -> NoiseProfile:
        """Validate a document (as :meth:`to_dict` gives it) into a profile.

        Parameters
        ----------
        d : mapping
            The document.
        where : str
            Its origin (a file name), for the messages.

        Returns
        -------
        NoiseProfile
            The profile.

        Raises
        ------
        ConfigError
            For an unknown or missing key, a wrong unit, a negative, non-finite or ill-shaped value; the message
            names ``where``, the key and the fix.
        """
        _keys(d, _TOP_KEYS, ("format", "version", "fs", "duration_s"), where, "")
        if d["format"] != FORMAT:
            raise ConfigError(f"{where}: format = {d['format']!r}; a noise profile has format = {FORMAT!r} "
                              "(write it with imunav noise REC --profile OUT.toml)")
        if d["version"] != VERSION:
            raise ConfigError(f"{where}: version = {d['version']!r}; this imunav reads version {VERSION}")
        sensors: dict[str, SensorNoise] = {}
        for s in SENSORS:
            if s in d:
                sensors[s] = _sensor_from(d[s], s, where)
        if not sensors:
            raise ConfigError(f"{where}: no sensor table; add [gyro], [accel] or [mag]")
        src = d.get("source", "")
        if not isinstance(src, str):
            raise ConfigError(f"{where}: source must be text; got {src!r}")
        try:
            return cls(fs=_number(d["fs"], where, "fs", positive=True),
                       duration_s=_number(d["duration_s"], where, "duration_s", positive=True),
                       source=src, **sensors)
        except ConfigError:  # _number's: it names the file already
            raise
        except InvalidInputError as exc:
            raise ConfigError(f"{where}: {exc}") from None

    @classmethod
    def from_fits(cls, *, fs: float, duration_s: float, gyro: NoiseFit | None = None, accel: NoiseFit | None = None,
                  mag: NoiseFit | None = None, mag_unit: str = "uT", source: str = "") -> NoiseProfile:
        """The profile of the Allan fits of :func:`imunav.noise.fit_noise` (one per sensor, three axes each).

        Parameters
        ----------
        fs : float
            Sample rate of the record, Hz.
        duration_s : float
            Its length, s.
        gyro, accel, mag : NoiseFit, optional
            The fits (gyro in rad/s, accelerometer in m/s², magnetometer in ``mag_unit``), each of three channels
            x, y, z with the terms N, B and K among the candidates.
        mag_unit : str
            The magnetometer's field unit.
        source : str
            Where the record came from.

        Returns
        -------
        NoiseProfile
            N, B and K per axis with their standard errors; a K the fit did not identify is the upper bound of the
            fitted curve, a B it did not identify 0 (module docstring).

        Raises
        ------
        InvalidInputError
            If a fit has not three channels, has no white noise N identified on an axis, or is of another
            quantity than its argument.
        """
        out: dict[str, SensorNoise] = {}
        for name, fit, unit in (("gyro", gyro, "rad/s"), ("accel", accel, "m/s^2"), ("mag", mag, mag_unit)):
            if fit is None:
                continue
            if fit.quantity not in (None, name) or (name == "mag" and fit.quantity is not None):
                raise InvalidInputError(f"the {name} argument holds a {fit.quantity} fit")
            if len(fit.channels) != 3:
                raise InvalidInputError(f"the {name} fit has {len(fit.channels)} channels {list(fit.channels)}; a "
                                        "noise profile needs the three axes x, y, z")
            terms = {}
            for key, code in zip(TERMS, ("N", "B", "K")):
                if code in fit.names:
                    i = fit.names.index(code)
                    val, se, sel = fit.value[i].astype(float), fit.se[i].astype(float), fit.selected[i] & (
                        fit.value[i] > 0)
                else:
                    val, se, sel = np.zeros(3), np.full(3, np.nan), np.zeros(3, bool)
                if code == "N" and not sel.all():
                    raise InvalidInputError(f"{name} white noise N was not identified on "
                                            f"{[fit.channels[c] for c in np.flatnonzero(~sel)]}: a noise profile "
                                            "needs it; fit with N among the candidate terms")
                if code == "K":
                    val = np.array([val[c] if sel[c] else _k_upper_bound(fit, c) for c in range(3)])
                elif code == "B":
                    val = np.where(sel, val, 0.0)
                se = np.where(sel, se, np.nan)
                terms[key] = NoiseTerm(val, se, sel)
            out[name] = SensorNoise(unit, **terms)
        return cls(fs=fs, duration_s=duration_s, source=source, **out)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, NoiseProfile) and self.to_dict() == other.to_dict() and all(
            getattr(self, s) == getattr(other, s) for s in SENSORS)

    __hash__ = None  # type: ignore[assignment]


def _keys(d: Any, allowed: tuple[str, ...], required: tuple[str, ...], where: str, table: str) -> None:
    at = f"[{table}]" if table else "the top level"
    if not isinstance(d, dict):
        raise ConfigError(f"{where}: {table or 'the document'} must be a table of keys; got {type(d).__name__}")
    unknown = [k for k in d if k not in allowed]
    if unknown:
        raise ConfigError(f"{where}: unknown key {table + '.' if table else ''}{unknown[0]} in {at}; the keys there "
                          f"are {', '.join(allowed)}")
    missing = [k for k in required if k not in d]
    if missing:
        raise ConfigError(f"{where}: {at} lacks {table + '.' if table else ''}{missing[0]}; add it (keys: "
                          f"{', '.join(required)})")


def _number(v: Any, where: str, key: str, *, positive: bool = False, allow_nan: bool = False) -> float:
    if v is None and allow_nan:
        return float("nan")
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ConfigError(f"{where}: {key} = {v!r} is not a number; give a number in the unit stated")
    f = float(v)
    if math.isnan(f) and allow_nan:
        return f
    if not math.isfinite(f) or f < 0 or (positive and f == 0):
        raise ConfigError(f"{where}: {key} = {v!r}; it must be a finite number {'> 0' if positive else '>= 0'}")
    return f


def _sensor_from(d: Any, s: str, where: str) -> SensorNoise:
    _keys(d, ("unit", *TERMS), ("unit", *TERMS), where, s)
    unit = d["unit"]
    if unit not in SENSORS[s]:
        raise ConfigError(f"{where}: {s}.unit = {unit!r}; the {s} profile is in {' or '.join(SENSORS[s])} "
                          "(SI; convert the values, or write the profile again with imunav noise)")
    units = term_units(unit)
    terms = {}
    for t in TERMS:
        tab = f"{s}.{t}"
        _keys(d[t], _TERM_KEYS, _TERM_KEYS, where, tab)
        if d[t]["unit"] != units[t]:
            raise ConfigError(f"{where}: {tab}.unit = {d[t]['unit']!r}; it must be {units[t]!r} (convert the values "
                              "to that unit)")
        arrays = {}
        for k in ("value", "se", "identified"):
            v = d[t][k]
            if not isinstance(v, list) or len(v) != 3:
                raise ConfigError(f"{where}: {tab}.{k} must be a list of three values (x, y, z); got {v!r}")
            if k == "identified":
                if not all(isinstance(b, bool) for b in v):
                    raise ConfigError(f"{where}: {tab}.identified must be three booleans (true / false); got {v!r}")
                arrays[k] = np.array(v, bool)
            else:
                arrays[k] = np.array([_number(x, where, f"{tab}.{k}[{i}]", allow_nan=k == "se")
                                      for i, x in enumerate(v)])
        if t == "noise_density" and not (arrays["identified"].all() and (arrays["value"] > 0).all()):
            axes = [a for a, ok in zip("xyz", arrays["identified"] & (arrays["value"] > 0)) if not ok]
            raise ConfigError(f"{where}: {tab} is not identified (or 0) on axis {', '.join(axes)}: a noise profile "
                              "holds the white noise of every axis (NoiseProfile.from_fits refuses one without it); "
                              "identify it again on a longer static record (imunav noise REC --profile OUT.toml)")
        terms[t] = NoiseTerm(arrays["value"], arrays["se"], arrays["identified"])
    return SensorNoise(unit, **terms)


def read_noise_profile(path: str | os.PathLike[str]) -> NoiseProfile:
    """Read and validate a noise profile file (``.toml`` or ``.json``; module docstring).

    Parameters
    ----------
    path : str or os.PathLike
        The file written by :meth:`NoiseProfile.write` (``imunav noise REC --profile OUT.toml``).

    Returns
    -------
    NoiseProfile
        The profile, equal to the one written.

    Raises
    ------
    ConfigError
        If the file is missing, not valid TOML / JSON, or its document is not a valid profile (the message names
        the file, the key and the fix).
    """
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in (".toml", ".json"):
        raise ConfigError(f"{p}: a noise profile is a .toml or .json file (imunav noise REC --profile OUT.toml)")
    if not p.is_file():
        raise ConfigError(f"noise profile file not found: {p}")
    if suffix == ".toml":
        d = read_toml(p, "noise profile")
    else:
        try:
            d = read_json(p, "noise profile")
        except InvalidInputError as exc:
            raise ConfigError(str(exc)) from None
    return NoiseProfile.from_dict(d, str(p))
