"""Attitude estimation: complementary, Mahony, Madgwick, MEKF, UKF, adaptive MEKF,
RTS smoother, the Candan & Söken gravity-vector KFs, alignment and the BROAD metric.

Every filter has ``run(data: ImuData) -> AttitudeResult`` (numba kernel over the
whole recording) and, except the offline smoother, a per-sample ``step(gyro,
accel, mag, dt)``.  Quaternions are ``q_nb`` (body -> NED), Hamilton, scalar first.
"""

from imunav.attitude.adaptive import ADAPTIVE_DEFAULTS, ADAPTIVE_DEFAULTS_6D, AdaptiveMEKF
from imunav.attitude.alignment import align, broad_reference_start, tilt_from_accel
from imunav.attitude.complementary import Complementary
from imunav.attitude.gravity_kf import GravityKF, GravityKfConfig, JavedKF, LeeKF, ProposedKF
from imunav.attitude.madgwick import Madgwick
from imunav.attitude.mahony import Mahony
from imunav.attitude.mekf import MEKF, MekfConfig
from imunav.attitude.metrics import attitude_rmse, error_angles, euler_rmse
from imunav.attitude.result import AttitudeResult
from imunav.attitude.smoother import SMOOTHER_DEFAULTS, Smoother
from imunav.attitude.ukf import UKF, UkfConfig

__all__ = [
    "ADAPTIVE_DEFAULTS", "ADAPTIVE_DEFAULTS_6D", "AdaptiveMEKF", "AttitudeResult", "Complementary", "GravityKF", "GravityKfConfig",
    "JavedKF", "LeeKF", "MEKF", "Madgwick", "Mahony", "MekfConfig", "ProposedKF", "SMOOTHER_DEFAULTS", "Smoother", "UKF", "UkfConfig",
    "align", "attitude_rmse", "broad_reference_start", "error_angles", "euler_rmse", "tilt_from_accel",
]
