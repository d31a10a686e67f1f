"""International Standard Atmosphere (ISA, ICAO Doc 7488 / ISO 2533:1975), 0-47 km.

Geopotential altitude H (m); layers with lapse rate L (K/m):

=========  ========  ============  ===========
base H     T_b (K)   p_b (Pa)      L (K/m)
=========  ========  ============  ===========
0          288.15    101325        −0.0065
11 000     216.65    22632.06      0
20 000     216.65    5474.889      +0.001
32 000     228.65    868.0187      +0.0028
=========  ========  ============  ===========

``p = p_b (T/T_b)^{−g₀/(L R)}`` in gradient layers, ``p = p_b exp(−g₀ (H − H_b)/(R T_b))``
in isothermal ones.  The troposphere formula is Table 2.1(a) of O. Akgün, *Hava verileri sistemi ile
Doppler radarının Kalman süzgeci temelinde tümleştirilmesi* (Integration of an air data system and a
Doppler radar via Kalman filtering), MSc thesis, Istanbul Technical University, 2002 ("the thesis"
below): ``P_s = 101.325 (1 − 2.25577·10⁻⁵ H)^{5.255879}`` kPa.  Geometric height z
converts by ``H = r₀ z / (r₀ + z)`` (r₀ = 6 356 766 m) in :func:`geopotential_altitude`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InvalidInputError, NonFiniteError
from imunav.results import Result

__all__ = [
    "P0",
    "T0",
    "RHO0",
    "A0",
    "R_AIR",
    "GAMMA",
    "G0",
    "R_EARTH_GEOPOT",
    "IsaState",
    "isa",
    "pressure_altitude",
    "geopotential_altitude",
    "speed_of_sound",
]

Array = NDArray[np.float64]

P0 = 101325.0  # Pa
T0 = 288.15  # K
R_AIR = 287.05287  # J/(kg K)
GAMMA = 1.4
G0 = 9.80665  # m/s^2
RHO0 = P0 / (R_AIR * T0)  # 1.225 kg/m^3
A0 = float(np.sqrt(GAMMA * R_AIR * T0))  # 340.294 m/s
R_EARTH_GEOPOT = 6356766.0  # m

_HB = np.array([0.0, 11000.0, 20000.0, 32000.0, 47000.0])
_LB = np.array([-0.0065, 0.0, 0.001, 0.0028])
_TB = np.array([288.15, 216.65, 216.65, 228.65])


def _layer_pressures() -> Array:
    pb = [P0]
    for i in range(3):
        pb.append(float(_p_in_layer(i, _HB[i + 1], pb[i])))
    return np.array(pb)


def _p_in_layer(i: int, H: ArrayLike, pb: float) -> Array:
    H = np.asarray(H, dtype=np.float64)
    if _LB[i] == 0.0:
        return pb * np.exp(-G0 * (H - _HB[i]) / (R_AIR * _TB[i]))
    T = _TB[i] + _LB[i] * (H - _HB[i])
    return pb * (T / _TB[i]) ** (-G0 / (_LB[i] * R_AIR))


_PB = _layer_pressures()


def _check(x: ArrayLike, name: str) -> Array:
    a = np.asarray(x, dtype=np.float64)
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{name} contains NaN or inf; pass finite values")
    return a


@dataclass(frozen=True)
class IsaState(Result):
    """ISA state at geopotential altitude ``altitude``.

    Attributes
    ----------
    altitude : numpy.ndarray
        Geopotential altitude, m.
    temperature : numpy.ndarray
        Static temperature, K.
    pressure : numpy.ndarray
        Static pressure, Pa.
    density : numpy.ndarray
        Air density, kg/m³.
    speed_of_sound : numpy.ndarray
        Speed of sound, m/s.
    """

    altitude: Array
    temperature: Array
    pressure: Array
    density: Array
    speed_of_sound: Array


def isa(altitude: ArrayLike, delta_t: float = 0.0) -> IsaState:
    """ISA temperature, pressure, density and speed of sound at geopotential altitude (m).

    ``delta_t`` (K) shifts the temperature (ISA+ΔT day) without changing the
    pressure profile (the pressure-altitude convention).  Valid for −500 to 47 000 m.

    Parameters
    ----------
    altitude : array_like
        Geopotential altitude, m, in [−500, 47 000].
    delta_t : float
        Temperature offset from the standard day, K.

    Returns
    -------
    IsaState
        T (K), p (Pa), ρ = p / (R T) (kg/m³) and a (m/s), shaped like ``altitude``.

    Raises
    ------
    InvalidInputError
        If an altitude is outside the model's range or not finite, or the temperature becomes non-positive.
    """
    H = _check(altitude, "altitude")
    if np.any(H < -500.0) or np.any(H > 47000.0):
        raise InvalidInputError(f"altitude must be within -500 .. 47000 m (ISA layers), got {H.min()} .. {H.max()}")
    i = np.clip(np.searchsorted(_HB, H, side="right") - 1, 0, 3)
    T = _TB[i] + _LB[i] * (H - _HB[i])
    p = np.empty_like(H, dtype=np.float64)
    for j in range(4):
        sel = i == j
        if np.any(sel):
            p[sel] = _p_in_layer(j, H[sel], _PB[j])
    T = T + delta_t
    rho = p / (R_AIR * T)
    return IsaState(H, T, p, rho, np.sqrt(GAMMA * R_AIR * T))


def speed_of_sound(temperature: ArrayLike) -> Array:
    """``a = √(γ R T)`` (the thesis's eq. 2.2), γ = 1.4, R = 287.05287 J/(kg K).

    Parameters
    ----------
    temperature : array_like
        Static temperature, K, > 0.

    Returns
    -------
    numpy.ndarray
        Speed of sound, m/s.

    Raises
    ------
    InvalidInputError
        If a temperature is not positive and finite.
    """
    T = _check(temperature, "temperature")
    if np.any(T <= 0):
        raise InvalidInputError("temperature must be > 0 K (pass Kelvin, not °C)")
    return np.sqrt(GAMMA * R_AIR * T)


def pressure_altitude(pressure: ArrayLike) -> Array:
    """Geopotential pressure altitude (m) from static pressure (Pa), the inverse of :func:`isa`.

    Troposphere: ``H = [1 − (p/p₀)^{1/5.255879}] / 2.25577·10⁻⁵`` (the thesis's Table 2.1 inverted);
    stratosphere: ``H = 11000 − ln(p/22632)·R T₁₁/g₀``.

    Parameters
    ----------
    pressure : array_like
        Static pressure, Pa, > 0.

    Returns
    -------
    numpy.ndarray
        Pressure altitude, geopotential m.

    Raises
    ------
    InvalidInputError
        If a pressure is not positive and finite, or lies outside the model's altitude range.
    """
    p = _check(pressure, "pressure")
    if np.any(p <= 0):
        raise InvalidInputError("pressure must be > 0 Pa (pass Pa, not kPa or hPa)")
    pmin = float(_p_in_layer(3, 47000.0, _PB[3]))
    if np.any(p > 107478.0) or np.any(p < pmin):
        raise InvalidInputError(f"pressure must be within {pmin:.1f} .. 107478 Pa (ISA -500 .. 47000 m), "
                                f"got {p.min()} .. {p.max()}; is the unit Pa?")
    i = np.clip(np.searchsorted(-_PB, -p, side="right") - 1, 0, 3)
    H = np.empty_like(p, dtype=np.float64)
    for j in range(4):
        sel = i == j
        if not np.any(sel):
            continue
        if _LB[j] == 0.0:
            H[sel] = _HB[j] - np.log(p[sel] / _PB[j]) * R_AIR * _TB[j] / G0
        else:
            H[sel] = _HB[j] + _TB[j] / _LB[j] * ((p[sel] / _PB[j]) ** (-_LB[j] * R_AIR / G0) - 1.0)
    return H


def geopotential_altitude(height: ArrayLike) -> Array:
    """Geopotential altitude ``H = r₀ z / (r₀ + z)`` from geometric height z (m), r₀ = 6 356 766 m (ISO 2533).

    Parameters
    ----------
    height : array_like
        Geometric height above mean sea level, m.

    Returns
    -------
    numpy.ndarray
        Geopotential altitude, m.
    """
    z = _check(height, "height")
    return R_EARTH_GEOPOT * z / (R_EARTH_GEOPOT + z)
