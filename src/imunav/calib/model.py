"""The deterministic IMU calibration model and its (de)serialisation.

Measurement model (Y. Günhan, *Ataletsel ölçüm birimi hatalarının belirlenmesi ve düzeltilmesi* (Detection and compensation of inertial measurement unit errors), MSc thesis, Hacettepe University, 2014, eqs. 2 and 4; E. Atasoy, *Estimation and analysis of error parameters of attitude-heading reference system sensors* (in Turkish), MSc thesis, Başkent University, eqs. 5.1-5.2; with the full 3×3
g-sensitivity allowed)::

    ã = T_a f + b_a                    (accelerometer, raw units)
    ω̃ = T_g ω + b_g + G f              (gyroscope, raw units)

``T = I + diag(S) + M`` when raw units are SI (``M`` zero diagonal, element
``M_ij`` = response of axis i to an input along axis j).  Compensation
(Günhan 2014, eqs. 21-22, §4.1.4; Atasoy, eqs. 5.4-5.5), accelerometer first because the gyro
uses the *compensated* specific force::

    f̂ = T_a⁻¹ (ã − b_a)
    ω̂ = T_g⁻¹ (ω̃ − b_g − G f̂)

Optionally each bias component and each diagonal element of ``T`` is a
function of temperature (:class:`TempCurve`, fitted by
:mod:`imunav.calib.temperature`); it then replaces the constant.

Compensated values are SI (m/s², rad/s).  Raw values are in
``raw_accel_unit`` / ``raw_gyro_unit`` (SI by default, or e.g. ``"counts"``),
so ``T`` carries raw units per SI unit.
"""

from __future__ import annotations

import json
import os
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import (
    FileFormatError,
    ImunavWarning,
    InvalidInputError,
    NonFiniteError,
    ProvenanceError,
    ShapeError,
    UnitError,
)
from imunav.files import write_json
from imunav.provenance import add_step, fingerprint, net_compensations
from imunav.units import DEG, G0

__all__ = [
    "TempCurve",
    "ImuCalibration",
    "FORMAT_VERSION",
    "success_percentages",
    "calibration_parameters",
]

Array = NDArray[np.float64]
FORMAT_VERSION = 1
_FORMAT = "imunav.imu-calibration"
_SI_ACCEL = "m/s^2"
_SI_GYRO = "rad/s"


@dataclass(frozen=True)
class TempCurve:
    """One parameter as a function of temperature.

    ``p(T) = Σ_k c_k x^k (+ step_height·[T ≥ step_c])`` with the centred and
    scaled temperature ``x = (T − center_c) / scale_c`` (centring keeps a
    5th-order fit well conditioned; the polynomial models of Günhan 2014, ch. 6, and of
    Y. Günhan, Ç. Ünsal, "Polynomial degree determination for temperature dependent error compensation
    of inertial sensors", IEEE/ION PLANS 2014).  Calling it, ``curve(temp_c)``, evaluates p.

    Attributes
    ----------
    coeffs : numpy.ndarray, shape (order + 1,)
        Coefficients c_k, lowest power first, in the parameter's unit.
    center_c : float
        Centre of the temperature normalisation, °C.
    scale_c : float
        Scale of the temperature normalisation, °C.
    step_c : float or None
        Temperature of a step change, °C, or None.
    step_height : float
        Height of that step, in the parameter's unit.
    """

    coeffs: Array  # (order+1,), lowest power first
    center_c: float
    scale_c: float
    step_c: float | None = None
    step_height: float = 0.0

    @property
    def order(self) -> int:
        return len(self.coeffs) - 1

    def __call__(self, temp_c: ArrayLike) -> Array:
        t = np.asarray(temp_c, dtype=float)
        x = (t - self.center_c) / self.scale_c
        y = np.polynomial.polynomial.polyval(x, np.asarray(self.coeffs, dtype=float))
        if self.step_c is not None:
            y = y + self.step_height * (t >= self.step_c)
        return y

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary of the curve.

        Returns
        -------
        dict
            ``coeffs`` (list), ``center_c``, ``scale_c``, ``step_c``, ``step_height``.
        """
        return {
            "coeffs": np.asarray(self.coeffs).tolist(),
            "center_c": self.center_c,
            "scale_c": self.scale_c,
            "step_c": self.step_c,
            "step_height": self.step_height,
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "TempCurve":
        """Rebuild a curve from :meth:`to_dict`.

        Parameters
        ----------
        d : dict
            A dictionary as written by :meth:`to_dict`.

        Returns
        -------
        TempCurve
            The curve.
        """
        return cls(
            np.asarray(d["coeffs"], dtype=float),
            float(d["center_c"]),
            float(d["scale_c"]),
            None if d.get("step_c") is None else float(d["step_c"]),
            float(d.get("step_height", 0.0)),
        )


_THERMAL_KEYS = ("accel_bias", "accel_scale", "gyro_bias", "gyro_scale")


def _vec3(x: ArrayLike, name: str) -> Array:
    a = np.asarray(x, dtype=float)
    if a.shape != (3,):
        raise ShapeError(f"{name} must have shape (3,), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{name} has non-finite values")
    return a


def _mat3(x: ArrayLike, name: str) -> Array:
    a = np.asarray(x, dtype=float)
    if a.shape != (3, 3):
        raise ShapeError(f"{name} must have shape (3, 3), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{name} has non-finite values")
    return a


@dataclass(frozen=True)
class ImuCalibration:
    """Deterministic calibration of an accelerometer + gyroscope triad pair.

    Attributes
    ----------
    accel_bias, gyro_bias : numpy.ndarray
        (3,) raw units.
    accel_matrix, gyro_matrix : numpy.ndarray
        (3, 3) ``T`` (raw units per SI unit).
    g_sensitivity : numpy.ndarray
        (3, 3) ``G`` (raw gyro units per m/s²); diagonal in the theses.
    thermal : dict
        ``{"accel_bias": [TempCurve]*3, ...}``; keys among
        ``accel_bias, accel_scale, gyro_bias, gyro_scale``; a ``*_scale`` curve
        gives the diagonal element ``T_ii(T)``.
    raw_accel_unit, raw_gyro_unit : str
        Units of the raw data.
    stderr : dict
        Standard errors with the same keys/shapes as the parameters.
    meta : dict
        Free-form provenance (method, session, design condition...).
    """

    accel_bias: Array = field(default_factory=lambda: np.zeros(3))
    accel_matrix: Array = field(default_factory=lambda: np.eye(3))
    gyro_bias: Array = field(default_factory=lambda: np.zeros(3))
    gyro_matrix: Array = field(default_factory=lambda: np.eye(3))
    g_sensitivity: Array = field(default_factory=lambda: np.zeros((3, 3)))
    thermal: dict[str, tuple[TempCurve, TempCurve, TempCurve]] = field(default_factory=dict)
    raw_accel_unit: str = _SI_ACCEL
    raw_gyro_unit: str = _SI_GYRO
    stderr: dict[str, Array] = field(default_factory=dict)
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "accel_bias", _vec3(self.accel_bias, "accel_bias"))
        object.__setattr__(self, "gyro_bias", _vec3(self.gyro_bias, "gyro_bias"))
        object.__setattr__(self, "accel_matrix", _mat3(self.accel_matrix, "accel_matrix"))
        object.__setattr__(self, "gyro_matrix", _mat3(self.gyro_matrix, "gyro_matrix"))
        object.__setattr__(self, "g_sensitivity", _mat3(self.g_sensitivity, "g_sensitivity"))
        for name in ("accel_matrix", "gyro_matrix"):
            if not np.linalg.cond(getattr(self, name)) < 1e12:
                raise InvalidInputError(f"{name} is singular; a calibration matrix must be invertible")
        for k, v in self.thermal.items():
            if k not in _THERMAL_KEYS:
                raise InvalidInputError(f"thermal key {k!r} unknown; use one of {_THERMAL_KEYS}")
            if len(v) != 3:
                raise ShapeError(f"thermal[{k!r}] needs one TempCurve per axis (3), got {len(v)}")

    # ------------------------------------------------------------------ views
    def _params_at(self, temp_c: ArrayLike | None, n: int) -> tuple[Array, Array, Array, Array]:
        """Biases (n,3) and matrices (n,3,3) at the given temperatures."""
        ba = np.broadcast_to(self.accel_bias, (n, 3)).copy()
        bg = np.broadcast_to(self.gyro_bias, (n, 3)).copy()
        ta = np.broadcast_to(self.accel_matrix, (n, 3, 3)).copy()
        tg = np.broadcast_to(self.gyro_matrix, (n, 3, 3)).copy()
        if self.thermal:
            if temp_c is None:
                raise InvalidInputError(
                    "this calibration is temperature dependent: pass temp_c (or an ImuData with temp)"
                )
            t = np.broadcast_to(np.asarray(temp_c, dtype=float), (n,))
            if not np.all(np.isfinite(t)):
                raise NonFiniteError("temp_c has non-finite values")
            for key, target in (("accel_bias", ba), ("gyro_bias", bg)):
                if key in self.thermal:
                    for i, c in enumerate(self.thermal[key]):
                        target[:, i] = c(t)
            for key, target in (("accel_scale", ta), ("gyro_scale", tg)):
                if key in self.thermal:
                    for i, c in enumerate(self.thermal[key]):
                        target[:, i, i] = c(t)
        return ba, ta, bg, tg

    # ------------------------------------------------------------ apply/invert
    def apply_arrays(
        self, accel: ArrayLike, gyro: ArrayLike, temp_c: ArrayLike | None = None
    ) -> tuple[Array, Array]:
        """Compensate raw ``accel`` / ``gyro``, raw units → SI (Günhan 2014, eqs. 21-22).

        ``f̂ = T_a⁻¹ (ã − b_a)``, ``ω̂ = T_g⁻¹ (ω̃ − b_g − G f̂)``, each at the sample's temperature when there is
        a thermal part.

        Parameters
        ----------
        accel : array_like, shape (N, 3)
            Raw accelerometer samples, ``raw_accel_unit``.
        gyro : array_like, shape (N, 3)
            Raw gyro samples, ``raw_gyro_unit``.
        temp_c : array_like, optional
            Temperature, °C, scalar or (N,); required when the calibration has a thermal part.

        Returns
        -------
        f : numpy.ndarray, shape (N, 3)
            Compensated specific force, body frame, m/s².
        w : numpy.ndarray, shape (N, 3)
            Compensated angular rate, body frame, rad/s.

        Raises
        ------
        ShapeError
            If ``accel`` and ``gyro`` are not both (N, 3).
        NonFiniteError
            If a sample or temperature is not finite.
        InvalidInputError
            If the calibration is temperature dependent and ``temp_c`` is missing.
        """
        a, g = _pair(accel, gyro)
        n = a.shape[0]
        if not self.thermal:
            f = np.linalg.solve(self.accel_matrix, (a - self.accel_bias).T).T
            w = np.linalg.solve(self.gyro_matrix, (g - self.gyro_bias - f @ self.g_sensitivity.T).T).T
            return f, w
        ba, ta, bg, tg = self._params_at(temp_c, n)
        f = np.linalg.solve(ta, (a - ba)[..., None])[..., 0]
        w = np.linalg.solve(tg, (g - bg - f @ self.g_sensitivity.T)[..., None])[..., 0]
        return f, w

    def invert_arrays(
        self, accel: ArrayLike, gyro: ArrayLike, temp_c: ArrayLike | None = None
    ) -> tuple[Array, Array]:
        """Corrupt true specific force / rate into raw outputs (Günhan 2014, eqs. 2 and 4).

        ``ã = T_a f + b_a``, ``ω̃ = T_g ω + b_g + G f``.

        Parameters
        ----------
        accel : array_like, shape (N, 3)
            True specific force, body frame, m/s².
        gyro : array_like, shape (N, 3)
            True angular rate, body frame, rad/s.
        temp_c : array_like, optional
            Temperature, °C, scalar or (N,); required when the calibration has a thermal part.

        Returns
        -------
        a : numpy.ndarray, shape (N, 3)
            Raw accelerometer output, ``raw_accel_unit``.
        g : numpy.ndarray, shape (N, 3)
            Raw gyro output, ``raw_gyro_unit``.

        Raises
        ------
        ShapeError
            If ``accel`` and ``gyro`` are not both (N, 3).
        NonFiniteError
            If a sample or temperature is not finite.
        InvalidInputError
            If the calibration is temperature dependent and ``temp_c`` is missing.
        """
        f, w = _pair(accel, gyro)
        n = f.shape[0]
        if not self.thermal:
            a = f @ self.accel_matrix.T + self.accel_bias
            g = w @ self.gyro_matrix.T + self.gyro_bias + f @ self.g_sensitivity.T
            return a, g
        ba, ta, bg, tg = self._params_at(temp_c, n)
        a = np.einsum("nij,nj->ni", ta, f) + ba
        g = np.einsum("nij,nj->ni", tg, w) + bg + f @ self.g_sensitivity.T
        return a, g

    @property
    def sha256(self) -> str:
        """Hash of the parameters and units (not ``meta`` nor ``stderr``): the calibration's identity
        in the provenance of the recordings it compensated."""

        d = self.to_dict()
        return fingerprint({k: v for k, v in d.items() if k not in ("meta", "stderr")})

    def apply(self, data: Any, temp_c: ArrayLike | None = None, *, force: bool = False,
              source: str | None = None) -> Any:
        """Compensate an :class:`imunav.timeseries.ImuData` (or ``(accel, gyro)``).

        The step is recorded in ``data.meta["provenance"]`` (see :mod:`imunav.provenance`)
        with the calibration's :attr:`sha256` and ``source`` (e.g. its file).  A recording
        already compensated with this calibration is refused
        (:class:`~imunav.errors.ProvenanceError`) unless ``force=True``; one compensated
        with another calibration gets an :class:`~imunav.errors.ImunavWarning` (right only
        when this calibration is a residual one, estimated on the compensated data).

        Parameters
        ----------
        data : ImuData
            ImuData (SI) or ``(accel, gyro)`` arrays (no provenance for arrays).
        temp_c : array_like, optional
            Temperature, °C (default: ``data.temp``).
        force : bool
            Compensate even if the provenance says it was done with this calibration.
        source : str, optional
            Where the calibration comes from (file name), recorded in the provenance.

        Returns
        -------
        ImuData or tuple of numpy.ndarray
            The compensated recording (SI: m/s², rad/s), with the step in its provenance; or the
            compensated ``(accel, gyro)`` arrays.
        """
        if not isinstance(data, tuple):
            self._require_si("apply")
            self._check_provenance(data, force)
        return self._on_data(data, temp_c, self.apply_arrays, "apply", source, force)

    def invert(self, data: Any, temp_c: ArrayLike | None = None, *, source: str | None = None) -> Any:
        """Corrupt ideal :class:`ImuData` (or ``(accel, gyro)``) with this model (recorded as ``uncompensate``).

        Parameters
        ----------
        data : ImuData or tuple of numpy.ndarray
            An SI recording, or ``(accel, gyro)`` arrays (no provenance for arrays).
        temp_c : array_like, optional
            Temperature, °C (default: ``data.temp``).
        source : str, optional
            Where the calibration comes from (file name), recorded in the provenance.

        Returns
        -------
        ImuData or tuple of numpy.ndarray
            The same kind as ``data``, with the errors of this model added.

        Raises
        ------
        UnitError
            If the calibration maps raw units other than SI (use :meth:`invert_arrays`).
        """
        return self._on_data(data, temp_c, self.invert_arrays, "invert", source, False)

    def _check_provenance(self, data: Any, force: bool) -> None:
        h = self.sha256
        same = net_compensations(data, h)
        if same and not force:
            s = same[-1]
            src = (s.get("calibration") or {}).get("source")
            raise ProvenanceError(
                f"the recording is already compensated with calibration sha256:{h[:12]}"
                f"{f' ({src})' if src else ''} on {s.get('time', '?')}; compensating again applies the bias and "
                "scale corrections twice. Use the raw recording, or pass force=True (command line: --force) to "
                "compensate again"
            )
        other = [s for s in net_compensations(data) if (s.get("calibration") or {}).get("sha256") != h]
        if other:
            o = other[-1].get("calibration") or {}
            where = f" ({o['source']})" if o.get("source") else ""
            warnings.warn(
                f"the recording is already compensated with another calibration sha256:{str(o.get('sha256'))[:12]}"
                f"{where}; "
                f"applying sha256:{h[:12]} on top is right only if it was estimated on the compensated data "
                "(a residual calibration); otherwise compensate the raw recording",
                ImunavWarning, stacklevel=3,
            )

    def _on_data(self, data: Any, temp_c: ArrayLike | None, arrays_fn: Any, what: str,
                 source: str | None = None, force: bool = False) -> Any:
        """``arrays_fn(accel, gyro, temp_c)`` on an ``(accel, gyro)`` tuple, or on
        an SI :class:`ImuData` (temperature from the data unless ``temp_c`` is given)."""

        if isinstance(data, tuple):
            return arrays_fn(data[0], data[1], temp_c)
        self._require_si(what)
        t = temp_c if temp_c is not None else getattr(data, "temp", None)
        a, g = arrays_fn(data.accel, data.gyro, t)
        cal = {"sha256": self.sha256, "source": source if source is not None else self.meta.get("source"),
               "method": self.meta.get("method")}
        params: dict[str, Any] = {"temperature": "data" if temp_c is None and t is not None
                                  else ("given" if temp_c is not None else None)}
        if force:
            params["force"] = True
        op = "compensate" if what == "apply" else "uncompensate"
        return data.with_(accel=a, gyro=g, meta=add_step(data.meta, op, params, calibration=cal))

    def _require_si(self, what: str) -> None:
        if (self.raw_accel_unit, self.raw_gyro_unit) != (_SI_ACCEL, _SI_GYRO):
            raise UnitError(
                f"{what}: this calibration maps raw {self.raw_accel_unit}/{self.raw_gyro_unit} data, while "
                "ImuData holds SI values; use apply_arrays/invert_arrays on the raw arrays"
            )

    # ------------------------------------------------------------ thesis view
    def split_parameters(self) -> dict[str, Array]:
        """Parameters split into scale factors, misalignments, bias and g-sensitivity (the parameterisation of
        Günhan 2014, eqs. 2 and 4; SI raw units required).

        ``S_i = T_ii − 1``, ``M_ij = T_ij`` (i ≠ j), ``B``, ``B_G = diag(G)``.

        Returns
        -------
        dict of str to numpy.ndarray
            As :func:`calibration_parameters`.

        Raises
        ------
        UnitError
            If the raw units are not SI.
        """
        self._require_si("split_parameters")
        return calibration_parameters(self)

    # --------------------------------------------------------------- JSON I/O
    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (the calibration file format, ``format_version`` :data:`FORMAT_VERSION`).

        Returns
        -------
        dict
            ``format``, ``format_version``, ``units``, ``model``, ``accel`` (bias, matrix), ``gyro`` (bias, matrix,
            g_sensitivity), ``thermal``, ``stderr``, ``meta``; arrays as numpy arrays (converted when written).
        """
        return {
            "format": _FORMAT,
            "format_version": FORMAT_VERSION,
            "units": {
                "raw_accel": self.raw_accel_unit,
                "raw_gyro": self.raw_gyro_unit,
                "accel_out": _SI_ACCEL,
                "gyro_out": _SI_GYRO,
                "accel_matrix": f"{self.raw_accel_unit} per {_SI_ACCEL}",
                "gyro_matrix": f"{self.raw_gyro_unit} per {_SI_GYRO}",
                "g_sensitivity": f"{self.raw_gyro_unit} per {_SI_ACCEL}",
                "temperature": "degC",
            },
            "model": "a_raw = Ta f + ba; w_raw = Tg w + bg + G f",
            "accel": {"bias": self.accel_bias, "matrix": self.accel_matrix},
            "gyro": {"bias": self.gyro_bias, "matrix": self.gyro_matrix, "g_sensitivity": self.g_sensitivity},
            "thermal": {k: [c.to_dict() for c in v] for k, v in self.thermal.items()},
            "stderr": {k: np.asarray(v) for k, v in self.stderr.items()},
            "meta": self.meta,
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any], *, source: str = "<dict>") -> "ImuCalibration":
        """Rebuild a calibration from :meth:`to_dict` (or a parsed calibration file).

        Parameters
        ----------
        d : dict
            The dictionary.
        source : str
            Where it comes from, for error messages.

        Returns
        -------
        ImuCalibration
            The calibration.

        Raises
        ------
        FileFormatError
            If the format or its version is not this one, or a field is missing.
        """
        if not isinstance(d, dict):
            raise FileFormatError(f"{source}: a calibration JSON is an object (format, accel, gyro, units), "
                                  f"not {type(d).__name__}")
        if d.get("format") != _FORMAT:
            raise FileFormatError(f"{source}: not an imunav calibration (field 'format' is {d.get('format')!r})")
        v = d.get("format_version")
        if v != FORMAT_VERSION:
            raise FileFormatError(
                f"{source}: calibration format_version {v!r} is not supported (this imunav reads {FORMAT_VERSION})"
            )
        for group, key, shape in (("accel", "bias", (3,)), ("accel", "matrix", (3, 3)), ("gyro", "bias", (3,)),
                                  ("gyro", "matrix", (3, 3)), ("gyro", "g_sensitivity", (3, 3))):
            g = d.get(group)
            if not isinstance(g, dict) or key not in g:
                raise FileFormatError(f"{source}: calibration JSON lacks {group}.{key} (numbers, shape {shape})")
            try:
                ok = np.asarray(g[key], dtype=float).shape == shape
            except (TypeError, ValueError):
                ok = False
            if not ok:
                raise FileFormatError(f"{source}: {group}.{key} must be numbers of shape {shape}, got {g[key]!r:.80}")
        if not isinstance(d.get("units"), dict) or not all(isinstance(d["units"].get(k), str)
                                                           for k in ("raw_accel", "raw_gyro")):
            raise FileFormatError(f"{source}: calibration JSON needs units.raw_accel and units.raw_gyro (unit strings)")
        try:
            u = d["units"]
            return cls(
                accel_bias=d["accel"]["bias"],
                accel_matrix=d["accel"]["matrix"],
                gyro_bias=d["gyro"]["bias"],
                gyro_matrix=d["gyro"]["matrix"],
                g_sensitivity=d["gyro"]["g_sensitivity"],
                thermal={
                    k: tuple(TempCurve.from_dict(c) for c in v) for k, v in d.get("thermal", {}).items()
                },
                raw_accel_unit=u["raw_accel"],
                raw_gyro_unit=u["raw_gyro"],
                stderr={k: np.asarray(v, dtype=float) for k, v in d.get("stderr", {}).items()},
                meta=dict(d.get("meta", {})),
            )
        except KeyError as e:
            raise FileFormatError(f"{source}: calibration JSON lacks the field {e}") from None
        except (TypeError, ValueError, AttributeError) as e:
            raise FileFormatError(f"{source}: a field of the calibration JSON (thermal, stderr or meta) has the "
                                  f"wrong shape or type ({e})") from None

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the calibration as JSON (atomic).

        Parameters
        ----------
        path : str or os.PathLike
            Output file.

        Returns
        -------
        pathlib.Path
            The file written.
        """
        return write_json(path, self.to_dict())

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> "ImuCalibration":
        """Read a calibration file: imunav's JSON, or an imucal Ferraris JSON.

        Parameters
        ----------
        path : str or os.PathLike
            The file.

        Returns
        -------
        ImuCalibration
            The calibration.

        Raises
        ------
        FileFormatError
            If the file does not exist, is not valid JSON, or is not a calibration of a supported format.
        """
        p = Path(path)
        try:
            d = json.loads(p.read_text())
        except FileNotFoundError:
            raise FileFormatError(f"calibration file {p} does not exist") from None
        except json.JSONDecodeError as e:
            raise FileFormatError(f"{p}: invalid JSON at line {e.lineno}: {e.msg}") from None
        if isinstance(d, dict) and d.get("cal_type") == "Ferraris":
            return cls.from_imucal(d)
        return cls.from_dict(d, source=str(p))

    # ----------------------------------------------------- imucal (Ferraris)
    def to_imucal(self, *, acc_unit: str = "m/s^2", gyr_unit: str = "deg/s", from_acc_unit: str | None = None,
                  from_gyr_unit: str | None = None) -> dict[str, Any]:
        """The imucal ``FerrarisCalibrationInfo`` JSON (format 2.0), in the units imucal's user works in.

        imucal: ``a_c = R_a⁻¹ K_a⁻¹ (a_r − b_a)``,
        ``ω_c = R_g⁻¹ K_g⁻¹ (ω_r − K_ga a_c − b_g)``; hence ``T_a = K_a R_a``
        with ``K_a`` the row norms of ``T_a`` and unit-norm rows in ``R_a`` (the model of F. Ferraris,
        U. Grimaldi, M. Parvis, "Procedure for effortless in-field calibration of three-axial rate gyro and
        accelerometers", Sensors and Materials 7(5), 1995).  imucal applies the calibration to the raw data
        as they were recorded: a calibration estimated on SI data that were read from a file in °/s (or g) is
        written for raw data in that unit (``from_gyr_unit="deg/s"``): ``b_g`` and ``K_ga`` in °/s, ``K_g``
        near 1 -- what imucal's own Ferraris computes on that file.

        Parameters
        ----------
        acc_unit : str
            Output accelerometer unit, ``"m/s^2"``.
        gyr_unit : {"deg/s", "rad/s"}
            Output gyro unit.
        from_acc_unit : {"m/s^2", "g"}, optional
            Unit of the raw accelerometer data the file is for; default: the calibration's raw unit. Only for
            a calibration of SI raw data.
        from_gyr_unit : {"rad/s", "deg/s"}, optional
            Unit of the raw gyro data the file is for; default: the calibration's raw unit. Only for a
            calibration of SI raw data.

        Returns
        -------
        dict
            The imucal JSON content (units in ``acc_unit``, ``gyr_unit``, ``from_acc_unit``, ``from_gyr_unit``).

        Raises
        ------
        InvalidInputError
            If the calibration has a thermal part (imucal has none).
        UnitError
            If a unit is not supported, or a raw unit is asked of a calibration of raw counts.
        """
        if self.thermal:
            raise InvalidInputError("imucal has no temperature model; drop the thermal part first")
        fo_a = {"m/s^2": 1.0}.get(acc_unit)
        fo_g = {"deg/s": DEG, "rad/s": 1.0}.get(gyr_unit)
        if fo_a is None or fo_g is None:
            raise UnitError("to_imucal: acc_unit must be 'm/s^2' and gyr_unit 'deg/s' or 'rad/s'")
        fr_a = _raw_factor(self.raw_accel_unit, from_acc_unit, _SI_ACCEL, {"m/s^2": 1.0, "g": G0})
        fr_g = _raw_factor(self.raw_gyro_unit, from_gyr_unit, _SI_GYRO, {"rad/s": 1.0, "deg/s": DEG})
        # raw_r = raw / fr = (T fo / fr) x_o + b / fr (+ G / fr_g a_c for the gyro)
        ta = self.accel_matrix * fo_a / fr_a
        tg = self.gyro_matrix * fo_g / fr_g
        ka = np.linalg.norm(ta, axis=1)
        kg = np.linalg.norm(tg, axis=1)
        return {
            "acc_unit": acc_unit,
            "gyr_unit": gyr_unit,
            "from_acc_unit": _imucal_unit(from_acc_unit or self.raw_accel_unit),
            "from_gyr_unit": _imucal_unit(from_gyr_unit or self.raw_gyro_unit),
            "comment": self.meta.get("comment"),
            "K_a": np.diag(ka).tolist(),
            "R_a": (ta / ka[:, None]).tolist(),
            "b_a": (self.accel_bias / fr_a).tolist(),
            "K_g": np.diag(kg).tolist(),
            "R_g": (tg / kg[:, None]).tolist(),
            "K_ga": (self.g_sensitivity * fo_a / fr_g).tolist(),
            "b_g": (self.gyro_bias / fr_g).tolist(),
            "cal_type": "Ferraris",
            "_format_version": "2.0",
        }

    @classmethod
    def from_imucal(cls, d: dict[str, Any] | str | os.PathLike[str]) -> "ImuCalibration":
        """Build from an imucal Ferraris JSON (dict or path).

        Raw data in °/s or g (``from_gyr_unit`` / ``from_acc_unit``) give a calibration of SI raw data
        (imunav's readers convert them); raw counts (``"a.u."``) stay counts.

        Parameters
        ----------
        d : dict or str or os.PathLike
            The parsed JSON, or its file.

        Returns
        -------
        ImuCalibration
            The equivalent calibration (``T = K R``).

        Raises
        ------
        FileFormatError
            If the calibration type is not Ferraris / Turntable.
        UnitError
            If its output units are not m/s² and deg/s or rad/s.
        """
        if not isinstance(d, dict):
            d = json.loads(Path(d).read_text())
        if d.get("cal_type") not in ("Ferraris", "Turntable"):
            raise FileFormatError(f"imucal calibration of type {d.get('cal_type')!r} is not supported")
        if d.get("acc_unit") != "m/s^2" or d.get("gyr_unit") not in ("deg/s", "rad/s"):
            raise UnitError(
                f"imucal output units {d.get('acc_unit')!r}/{d.get('gyr_unit')!r} unsupported (need m/s^2, deg/s)"
            )
        fo_g = DEG if d["gyr_unit"] == "deg/s" else 1.0
        fr_a = {"m/s^2": 1.0, "g": G0}.get(d.get("from_acc_unit") or "", 1.0)
        fr_g = {"rad/s": 1.0, "deg/s": DEG}.get(d.get("from_gyr_unit") or "", 1.0)
        raw_a = _from_imucal_unit(d.get("from_acc_unit"), _SI_ACCEL)
        raw_g = _from_imucal_unit(d.get("from_gyr_unit"), _SI_GYRO)
        ta = np.asarray(d["K_a"], float) @ np.asarray(d["R_a"], float) * fr_a
        tg = np.asarray(d["K_g"], float) @ np.asarray(d["R_g"], float) / fo_g * fr_g
        return cls(
            accel_bias=np.asarray(d["b_a"], float) * fr_a,
            accel_matrix=ta,
            gyro_bias=np.asarray(d["b_g"], float) * fr_g,
            gyro_matrix=tg,
            g_sensitivity=np.asarray(d["K_ga"], float) * fr_g,
            raw_accel_unit=_SI_ACCEL if raw_a in ("g",) else raw_a,
            raw_gyro_unit=_SI_GYRO if raw_g in ("deg/s",) else raw_g,
            meta={"source": "imucal", "comment": d.get("comment")},
        )

    @classmethod
    def from_error_model(cls, model: Any) -> "ImuCalibration":
        """The calibration that a :class:`imunav.sim.ImuErrorModel` implies (truth for tests).

        Parameters
        ----------
        model : ImuErrorModel
            A simulation error model (SI).

        Returns
        -------
        ImuCalibration
            Its biases, scale-factor / misalignment matrices and g-sensitivity, SI raw units.
        """
        return cls(
            accel_bias=np.asarray(model.accel.bias, float),
            accel_matrix=np.asarray(model.accel.scale_misalignment, float),
            gyro_bias=np.asarray(model.gyro.bias, float),
            gyro_matrix=np.asarray(model.gyro.scale_misalignment, float),
            g_sensitivity=np.asarray(model.g_sensitivity, float),
            meta={"source": f"error model {getattr(model, 'name', '')}".strip()},
        )

    def with_(self, **changes: Any) -> "ImuCalibration":
        """A copy with some fields replaced (:func:`dataclasses.replace`).

        Parameters
        ----------
        **changes
            Field names and their new values.

        Returns
        -------
        ImuCalibration
            The new calibration (validated again).
        """
        return replace(self, **changes)


def _raw_factor(raw: str, wanted: str | None, si: str, factors: dict[str, float]) -> float:
    """SI per unit of the raw data imucal will get: 1 unless an SI calibration is written for raw °/s or g."""
    if wanted is None or wanted == raw:
        return 1.0
    if raw != si or wanted not in factors:
        raise UnitError(f"to_imucal: raw data in {wanted!r} for a calibration of raw {raw!r}: only a calibration "
                        f"of SI raw data is written for raw {' or '.join(factors)}")
    return factors[wanted]


def _imucal_unit(u: str) -> str:
    return {"counts": "a.u.", _SI_GYRO: "rad/s", _SI_ACCEL: "m/s^2"}.get(u, u)


def _from_imucal_unit(u: str | None, si: str) -> str:
    if u is None:
        return si
    return {"a.u.": "counts"}.get(u, u)


def _pair(a: ArrayLike, g: ArrayLike) -> tuple[Array, Array]:
    a = np.asarray(a, dtype=float)
    g = np.asarray(g, dtype=float)
    a2 = np.atleast_2d(a)
    g2 = np.atleast_2d(g)
    if a2.shape[-1] != 3 or g2.shape != a2.shape or a2.ndim != 2:
        raise ShapeError(f"accel {a.shape} and gyro {g.shape} must both be (N, 3)")
    if not (np.all(np.isfinite(a2)) and np.all(np.isfinite(g2))):
        bad = np.flatnonzero(~(np.isfinite(a2).all(1) & np.isfinite(g2).all(1)))
        raise NonFiniteError(f"non-finite accel/gyro at rows {bad[:10].tolist()}")
    return a2, g2


_OFF = [(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)]
_AX = "xyz"


def calibration_parameters(cal: ImuCalibration) -> dict[str, Array]:
    """Thesis parameters as flat arrays (SI): accel ``S, B, M``; gyro ``S, B, B_G, M`` (Günhan 2014, eqs. 2 and 4).

    Parameters
    ----------
    cal : ImuCalibration
        A calibration with SI raw units.

    Returns
    -------
    dict of str to numpy.ndarray
        ``accel_S`` (3,), ``accel_B`` (3,, m/s²), ``accel_M`` (6,) ordered
        xy, xz, yx, yz, zx, zy; ``gyro_S``, ``gyro_B`` (rad/s), ``gyro_BG`` (3,, rad/s per m/s²),
        ``gyro_M`` (6,).  S and M are dimensionless.
    """
    out: dict[str, Array] = {}
    for s, T, B in (("accel", cal.accel_matrix, cal.accel_bias), ("gyro", cal.gyro_matrix, cal.gyro_bias)):
        out[f"{s}_S"] = np.diag(T) - 1.0
        out[f"{s}_B"] = B.copy()
        out[f"{s}_M"] = np.array([T[i, j] for i, j in _OFF])
    out["gyro_BG"] = np.diag(cal.g_sensitivity).copy()
    return out


def parameter_names() -> dict[str, list[str]]:
    """Names matching :func:`calibration_parameters` (for tables).

    Returns
    -------
    dict of str to list of str
        The same keys, each with one name per element (``S_x``, ``B_y``, ``M_xz``, ``B_Gz``, ...).
    """
    m = [f"M_{_AX[i]}{_AX[j]}" for i, j in _OFF]
    s = [f"S_{a}" for a in _AX]
    b = [f"B_{a}" for a in _AX]
    return {
        "accel_S": s, "accel_B": b, "accel_M": m,
        "gyro_S": s, "gyro_B": b, "gyro_M": m, "gyro_BG": [f"B_G{a}" for a in _AX],
    }


def success_percentages(estimate: ImuCalibration, truth: ImuCalibration) -> dict[str, Any]:
    """The thesis "success" metric, ``100 (1 − |p̂ − p| / |p|)`` (Günhan 2014, Tables 5.3-5.4).

    Parameters
    ----------
    estimate : ImuCalibration
        The estimated calibration.
    truth : ImuCalibration
        The true one (e.g. :meth:`ImuCalibration.from_error_model`).

    Returns
    -------
    dict
        ``per_parameter`` (percentages with the keys of :func:`calibration_parameters`), and the means over
        the 12 accelerometer parameters (S, B, M), ``accel_mean``, and over the 15 gyro parameters
        (S, B, B_G, M), ``gyro_mean``, in %.
    """
    pe, pt = calibration_parameters(estimate), calibration_parameters(truth)
    per: dict[str, Array] = {}
    for k in pt:
        with np.errstate(divide="ignore", invalid="ignore"):
            per[k] = 100.0 * (1.0 - np.abs(pe[k] - pt[k]) / np.abs(pt[k]))
    acc = np.concatenate([per["accel_S"], per["accel_B"], per["accel_M"]])
    gyr = np.concatenate([per["gyro_S"], per["gyro_B"], per["gyro_BG"], per["gyro_M"]])
    return {"per_parameter": per, "accel_mean": float(np.mean(acc)), "gyro_mean": float(np.mean(gyr))}
