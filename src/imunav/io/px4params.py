"""PX4 sensor-calibration parameters (``CAL_ACCn_*``, ``CAL_GYROn_*``, ``CAL_MAGn_*``) as a QGroundControl file.

What PX4 applies (``src/lib/sensor_calibration`` in PX4-Autopilot; names,
defaults and ranges: the parameter reference,
https://docs.px4.io/main/en/advanced_config/parameter_reference.html)::

    accelerometer  a = (a_raw - CAL_ACCn_{X,Y,Z}OFF) ⊙ CAL_ACCn_{X,Y,Z}SCALE      m/s^2
    gyroscope      w =  w_raw - CAL_GYROn_{X,Y,Z}OFF                            rad/s
    magnetometer   h = S (h_raw - CAL_MAGn_{X,Y,Z}OFF)                          gauss
                   S = [[XSCALE, XODIAG, YODIAG],
                        [XODIAG, YSCALE, ZODIAG],
                        [YODIAG, ZODIAG, ZSCALE]]                              (symmetric)

followed by the sensor's rotation to the body frame (``CAL_*n_ROT``, not
written: it belongs to the vehicle, not to the sensor's errors).

imunav's models (:class:`~imunav.calib.ImuCalibration`:
``f = T_a⁻¹ (a_raw − b_a)``, ``ω = T_g⁻¹ (ω_raw − b_g − G f)``;
:class:`~imunav.calib.magnetometer.MagCalibration`: ``h = A (h_raw − b)``)
map onto these as: offsets = the biases; accelerometer scales = the diagonal
of ``T_a⁻¹``; magnetometer matrix = ``A``.

What PX4 cannot express -- accelerometer cross-axis terms (off-diagonal
``T_a⁻¹``), every gyro scale factor and misalignment (``T_g ≠ I``), the gyro
g-sensitivity ``G`` and the rotation part of a non-symmetric ``A`` -- is
**dropped with a warning** listed in the file's header (and in
:attr:`Px4Parameters.dropped`), with the size of what was dropped: PX4's own
calibration ignores these terms too, and refusing would make the file
unusable for every calibration that estimated them.  ``strict=True`` refuses
instead.  A temperature model is always refused (PX4 keeps thermal
compensation in its own ``TC_*`` parameters).

The file format is QGroundControl's parameter file: ``#`` comment lines,
then one tab-separated line per parameter ``vehicle-id  component-id  name
value  type`` with the MAVLink type 9 (REAL32) or 6 (INT32)
(https://docs.qgroundcontrol.com/master/en/qgc-dev-guide/file_formats/parameters.html).
Values are written with every digit of the double; PX4 stores them as 32-bit
floats (relative rounding 6e-8).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from imunav import __version__
from imunav.errors import InvalidInputError, UnitError
from imunav.files import atomic_path
from imunav.units import unit_factor

if TYPE_CHECKING:  # annotations only
    from imunav.calib.magnetometer import MagCalibration
    from imunav.calib.model import ImuCalibration
    from imunav.calib.result import CalibrationResult

__all__ = ["MAV_PARAM_TYPE_INT32", "MAV_PARAM_TYPE_REAL32", "Px4Parameters", "px4_parameters", "write_px4_params"]

#: MAVLink ``MAV_PARAM_TYPE`` codes used in the file.
MAV_PARAM_TYPE_INT32 = 6
MAV_PARAM_TYPE_REAL32 = 9
#: PX4's accepted range of every ``*SCALE`` parameter (parameter reference: min 0.1, max 3.0).
SCALE_RANGE = (0.1, 3.0)
_AX = "XYZ"
_GAUSS = 1e-4  # tesla


@dataclass(frozen=True)
class Px4Parameters:
    """PX4 calibration parameters and what could not be expressed.

    Attributes
    ----------
    values : dict
        ``{name: value}``; floats for REAL32 parameters, ints for INT32 ones.
    dropped : tuple of str
        One sentence per term of the imunav model that PX4 has no parameter for (empty when exact).
    converted : tuple of str
        One sentence per quantity converted into PX4's units (e.g. the magnetometer offsets from µT to gauss).
    """

    values: dict[str, float | int]
    dropped: tuple[str, ...] = field(default_factory=tuple)
    converted: tuple[str, ...] = field(default_factory=tuple)

    def param_type(self, name: str) -> int:
        """The MAVLink type code of parameter ``name`` (6 INT32, 9 REAL32).

        Parameters
        ----------
        name : str
            Parameter name (a key of :attr:`values`).

        Returns
        -------
        int
            ``MAV_PARAM_TYPE_INT32`` (6) for integers, ``MAV_PARAM_TYPE_REAL32`` (9) otherwise.
        """
        return MAV_PARAM_TYPE_INT32 if isinstance(self.values[name], int) else MAV_PARAM_TYPE_REAL32

    def text(self, vehicle_id: int = 1, component_id: int = 1) -> str:
        """The QGroundControl parameter file as text (see the module docstring).

        Parameters
        ----------
        vehicle_id, component_id : int
            MAVLink system and component ids of the first two columns (1, 1 for a single vehicle).

        Returns
        -------
        str
            Header comments (with the conversions and the dropped terms) and one tab-separated row per parameter.
        """

        head = [f"# PX4 sensor calibration written by imunav {__version__}",
                "# Load it in QGroundControl: Vehicle Setup > Parameters > Tools > Load from file; then reboot.",
                "# PX4 applies: accel (raw - CAL_ACCn_*OFF) * CAL_ACCn_*SCALE [m/s^2]; gyro raw - CAL_GYROn_*OFF "
                "[rad/s];",
                "#   mag S (raw - CAL_MAGn_*OFF) [gauss], S symmetric from CAL_MAGn_*SCALE and *ODIAG "
                "(X: xy, Y: xz, Z: yz).",
                "# CAL_*n_ROT is not written: keep the vehicle's sensor rotation."]
        head += [f"# Converted: {c}" for c in self.converted]
        if self.dropped:
            head.append("# WARNING: not expressible in PX4, dropped:")
            head += [f"#   - {d}" for d in self.dropped]
        head += ["#", "# Vehicle-Id Component-Id Name Value Type"]
        rows = [f"{vehicle_id}\t{component_id}\t{k}\t{self.values[k]!r}\t{self.param_type(k)}"
                for k in sorted(self.values)]
        return "\n".join(head + rows) + "\n"

    def write(self, path: str | os.PathLike[str], vehicle_id: int = 1, component_id: int = 1) -> Path:
        """Write :meth:`text` to ``path`` atomically.

        Parameters
        ----------
        path : str or os.PathLike
            Output file (``.params``).
        vehicle_id, component_id : int
            MAVLink system and component ids of the first two columns (1, 1 for a single vehicle).

        Returns
        -------
        pathlib.Path
            The file written.
        """

        with atomic_path(path) as tmp:
            tmp.write_text(self.text(vehicle_id, component_id), encoding="utf-8")
        return Path(path)


def _device_id(v: int | None, what: str) -> int | None:
    if v is None:
        return None
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not 0 < int(v) < 2**31:
        raise InvalidInputError(f"{what} must be PX4's device id of the sensor (a positive integer, "
                                f"e.g. from the log's sensor_accel.device_id); got {v!r}")
    return int(v)


def _check_scales(prefix: str, scales: np.ndarray) -> None:
    lo, hi = SCALE_RANGE
    bad = [f"{prefix}_{a}SCALE={s:.6g}" for a, s in zip(_AX, scales) if not lo <= s <= hi]
    if bad:
        raise InvalidInputError(f"{', '.join(bad)} outside PX4's range [{lo}, {hi}]: the calibration does not map "
                                "the sensor's SI output (check the raw units / the field-norm normalisation)")


def _imu_params(cal: ImuCalibration, n: int, out: dict[str, float | int], dropped: list[str]) -> None:
    if cal.thermal:
        raise InvalidInputError("this calibration has a temperature model; PX4 keeps thermal compensation in its own "
                                "TC_* parameters: export a calibration at one temperature (without 'thermal')")
    if (cal.raw_accel_unit, cal.raw_gyro_unit) != ("m/s^2", "rad/s"):
        raise UnitError(f"PX4 calibrates its sensor output in m/s^2 and rad/s; this calibration maps raw "
                        f"{cal.raw_accel_unit}/{cal.raw_gyro_unit}: calibrate data read in SI units")
    tinv = np.linalg.inv(cal.accel_matrix)
    scale = np.diag(tinv).copy()
    _check_scales(f"CAL_ACC{n}", scale)
    for i, a in enumerate(_AX):
        out[f"CAL_ACC{n}_{a}OFF"] = float(cal.accel_bias[i])
        out[f"CAL_ACC{n}_{a}SCALE"] = float(scale[i])
        out[f"CAL_GYRO{n}_{a}OFF"] = float(cal.gyro_bias[i])
    cross = np.max(np.abs(tinv - np.diag(scale)))
    if cross > 0:
        dropped.append(f"accelerometer cross-axis terms (largest off-diagonal of T_a^-1: {cross:.3g})")
    tg = np.max(np.abs(cal.gyro_matrix - np.eye(3)))
    if tg > 0:
        dropped.append(f"gyro scale factors and misalignment (largest |T_g - I|: {tg:.3g}): "
                       "PX4 has gyro offsets only")
    gs = np.max(np.abs(cal.g_sensitivity))
    if gs > 0:
        dropped.append(f"gyro g-sensitivity (largest |G|: {gs:.3g} rad/s per m/s^2)")


#: Field magnitudes (gauss) a magnetometer calibration for PX4 may have: Earth's field is 0.22-0.67 gauss
#: (22-67 µT, IGRF); the bounds leave a factor 4 either way for disturbed sites and coils, and refuse data whose
#: unit is off by 10 or more (µT read as gauss: x 100; tesla: x 1e-4).
EARTH_FIELD_GAUSS = (0.05, 2.5)


def _mag_params(mag: MagCalibration, unit: str, n: int, out: dict[str, float | int], dropped: list[str],
                converted: list[str]) -> None:
    try:
        to_gauss = unit_factor(unit, "magnetic_field") / _GAUSS
    except UnitError as exc:
        raise UnitError(f"mag_unit: {exc}") from None
    norm = float(mag.field_norm) * to_gauss
    lo, hi = EARTH_FIELD_GAUSS
    if not lo <= norm <= hi:
        as_gauss = "" if to_gauss == 1.0 else f" = {norm:.4g} gauss"
        raise UnitError(f"mag_unit={unit!r} (command line: --mag-unit): the calibrated field magnitude "
                        f"{float(mag.field_norm):.4g} {unit}{as_gauss} is outside the {lo:g}-{hi:g} gauss a "
                        "magnetometer sees on Earth (0.22-0.67 gauss); the data are in another unit: give theirs "
                        "(gauss, uT, nT, T) for PX4's gauss offsets")
    if to_gauss != 1.0:
        converted.append(f"CAL_MAG{n}_{{X,Y,Z}}OFF: the offsets converted from {unit} to PX4's gauss "
                         f"(x {to_gauss:g}); the scales are unitless")
    A = np.asarray(mag.A, float)
    # polar decomposition A = U P: P is the symmetric soft-iron matrix PX4 can hold, U a rotation
    if np.max(np.abs(A - A.T)) <= 1e-12 * np.max(np.abs(A)):  # symmetric up to rounding
        S = 0.5 * (A + A.T)
    else:
        W, s, Vt = np.linalg.svd(A)
        U = W @ Vt
        S = Vt.T @ np.diag(s) @ Vt
        ang = float(np.degrees(np.arccos(np.clip((np.trace(U) - 1.0) / 2.0, -1.0, 1.0))))
        dropped.append(f"magnetometer soft-iron rotation of {ang:.3g} deg (A is not symmetric; PX4's matrix is): "
                       "the field magnitude is kept, its direction turns by that angle")
    _check_scales(f"CAL_MAG{n}", np.diag(S))
    for i, a in enumerate(_AX):
        out[f"CAL_MAG{n}_{a}OFF"] = float(mag.b[i] * to_gauss)
        out[f"CAL_MAG{n}_{a}SCALE"] = float(S[i, i])
    for a, (i, j) in zip(_AX, ((0, 1), (0, 2), (1, 2))):
        out[f"CAL_MAG{n}_{a}ODIAG"] = float(S[i, j])


def px4_parameters(imu: ImuCalibration | CalibrationResult | None = None, mag: MagCalibration | None = None, *,
                   instance: int = 0, mag_unit: str = "gauss", accel_id: int | None = None,
                   gyro_id: int | None = None, mag_id: int | None = None, priority: int = 50,
                   strict: bool = False) -> Px4Parameters:
    """PX4 calibration parameters of an IMU and/or magnetometer calibration.

    Parameters
    ----------
    imu : ImuCalibration or CalibrationResult, optional
        Accelerometer + gyro calibration with SI raw units (m/s^2, rad/s) and no temperature model.
    mag : MagCalibration, optional
        Hard- and soft-iron calibration of data in ``mag_unit``.
    instance : int
        The calibration slot ``n`` of ``CAL_ACCn_*`` (0-3).
    mag_unit : str
        Unit of the magnetometer data the calibration was fitted on (gauss, uT, nT, T...); PX4's offsets are gauss.
    accel_id, gyro_id, mag_id : int, optional
        PX4 device ids of the sensors; when given, ``CAL_*n_ID`` and ``CAL_*n_PRIO`` are written too
        (PX4 uses a slot only for the device whose id it holds; without them the vehicle's ids are kept).
    priority : int
        ``CAL_*n_PRIO`` written with an id (PX4: 0 disabled, 1-100; default 50, "Medium").
    strict : bool
        Refuse (:class:`InvalidInputError`) instead of dropping the terms PX4 cannot express.

    Returns
    -------
    Px4Parameters
        The values and the list of dropped terms.

    Raises
    ------
    InvalidInputError
        Nothing to export, a bad slot / id / priority, a temperature model, scales outside PX4's
        [0.1, 3.0], or (``strict``) terms PX4 cannot express.
    UnitError
        Raw IMU units that are not SI, an unknown ``mag_unit``, or one in which the calibrated field magnitude
        is not a field on Earth (:data:`EARTH_FIELD_GAUSS`: the data are in another unit).
    """
    if imu is None and mag is None:
        raise InvalidInputError("nothing to export: give an IMU calibration, a magnetometer calibration or both")
    if isinstance(instance, bool) or not isinstance(instance, (int, np.integer)) or not 0 <= instance <= 3:
        raise InvalidInputError(f"instance must be PX4's calibration slot 0-3; got {instance!r}")
    if isinstance(priority, bool) or not isinstance(priority, (int, np.integer)) or not 0 <= priority <= 100:
        raise InvalidInputError(f"priority must be 0 (disabled) to 100; got {priority!r}")
    out: dict[str, float | int] = {}
    dropped: list[str] = []
    converted: list[str] = []
    ids: dict[str, int | None] = {}
    if imu is not None:
        cal = getattr(imu, "calibration", imu)
        _imu_params(cal, int(instance), out, dropped)
        ids["ACC"], ids["GYRO"] = _device_id(accel_id, "accel_id"), _device_id(gyro_id, "gyro_id")
    if mag is not None:
        _mag_params(mag, mag_unit, int(instance), out, dropped, converted)
        ids["MAG"] = _device_id(mag_id, "mag_id")
    for sensor, dev in ids.items():
        if dev is not None:
            out[f"CAL_{sensor}{instance}_ID"] = dev
            out[f"CAL_{sensor}{instance}_PRIO"] = int(priority)
    if strict and dropped:
        raise InvalidInputError("PX4 cannot express " + "; ".join(dropped) + " (strict=True)")
    return Px4Parameters(out, tuple(dropped), tuple(converted))


def write_px4_params(path: str | os.PathLike[str], imu: ImuCalibration | CalibrationResult | None = None,
                     mag: MagCalibration | None = None, *, vehicle_id: int = 1, component_id: int = 1,
                     **options: Any) -> Px4Parameters:
    """Write the PX4 calibration parameters as a QGroundControl ``.params`` file (atomically).

    Parameters
    ----------
    path : path-like
        The file to write.
    imu, mag
        As for :func:`px4_parameters`.
    vehicle_id, component_id : int
        The MAVLink system and component ids of the first two columns (1, 1 for a single vehicle).
    **options
        ``instance``, ``mag_unit``, ``accel_id``, ``gyro_id``, ``mag_id``, ``priority``, ``strict``
        (see :func:`px4_parameters`).

    Returns
    -------
    Px4Parameters
        What was written, with the list of dropped terms (also in the file's header).
    """
    p = px4_parameters(imu, mag, **options)
    p.write(path, vehicle_id, component_id)
    return p
