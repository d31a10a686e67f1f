"""Deterministic calibration of IMUs and magnetometers.

- :class:`ImuCalibration`: the model (bias, scale/misalignment, g-sensitivity,
  temperature curves), apply / invert, JSON, imucal conversion.
- Estimators returning :class:`CalibrationResult` (model + standard errors +
  residuals + design condition): :func:`six_position`, :func:`multiposition`,
  :func:`ratetable`, :func:`ferraris`, :func:`multipose`.
- :mod:`.temperature`: polynomial / piecewise B(T), S(T) with LOO order choice.
- :mod:`.magnetometer`: hard/soft iron, :func:`fit_ellipsoid` (Li & Griffiths 2004).
"""

from imunav.calib.ferraris import FERRARIS_SECTIONS, ferraris, ferraris_from_session
from imunav.calib.magnetometer import (
    MAG_METHODS,
    MagCalibration,
    calibrate_magnetometer,
    fit_ellipsoid,
    hard_iron_minmax,
    minmax_calibration,
    soft_iron_rotation_scale,
    sphere_coverage,
)
from imunav.calib.model import FORMAT_VERSION, ImuCalibration, TempCurve, calibration_parameters, success_percentages
from imunav.calib.multipose import multipose
from imunav.calib.ratetable import combine, ratetable, ratetable_from_means
from imunav.calib.result import CalibrationResult, parameter_stderr
from imunav.calib.static import (
    earth_rate_body,
    multiposition,
    multiposition_from_means,
    reference_specific_force,
    six_position,
)
from imunav.calib.temperature import TemperatureFit, ThermalResult, fit_temperature_curve, thermal_calibration

__all__ = [
    "FORMAT_VERSION",
    "ImuCalibration",
    "TempCurve",
    "CalibrationResult",
    "calibration_parameters",
    "parameter_stderr",
    "success_percentages",
    "reference_specific_force",
    "earth_rate_body",
    "six_position",
    "multiposition",
    "multiposition_from_means",
    "ratetable",
    "ratetable_from_means",
    "combine",
    "FERRARIS_SECTIONS",
    "ferraris",
    "ferraris_from_session",
    "multipose",
    "TemperatureFit",
    "ThermalResult",
    "fit_temperature_curve",
    "thermal_calibration",
    "MagCalibration",
    "MAG_METHODS",
    "calibrate_magnetometer",
    "fit_ellipsoid",
    "hard_iron_minmax",
    "minmax_calibration",
    "soft_iron_rotation_scale",
    "sphere_coverage",
]
