"""Air-data computations (Akgün 2002, ch. 2, Table 2.1; Kayton & Fried 1997, ch. 4).

References: O. Akgün, *Hava verileri sistemi ile Doppler radarının Kalman süzgeci temelinde
tümleştirilmesi* (Integration of an air data system and a Doppler radar via Kalman filtering), MSc
thesis, Istanbul Technical University, 2002 ("the thesis"); M. Kayton, W. R. Fried, *Avionics
Navigation Systems*, 2nd ed., Wiley, 1997.

Inputs are total (pitot) pressure ``p_t``, static pressure ``p`` (Pa) and
total air temperature ``T_m`` (K).  Impact pressure ``q_c = p_t − p`` (eq. 2.1).

* Mach, subsonic (isentropic): ``p_t/p = (1 + 0.2 M²)^{3.5}``.
* Mach, supersonic (Rayleigh pitot formula, normal shock ahead of the probe):
  ``p_t/p = 166.92 M⁷ / (7M² − 1)^{2.5}``; both branches meet at M = 1
  (``p_t/p = 1.8929``).  Inverted by Newton iteration.
* Calibrated airspeed: the same laws with sea-level ``p₀``, ``a₀``:
  ``q_c = p₀{[1 + 0.2 (V_c/a₀)²]^{3.5} − 1}`` (subsonic) and the Rayleigh form.
* Static temperature ``T_s = T_m / (1 + 0.2 r M²)`` with recovery factor r.
* TAS ``V_T = M √(γ R T_s)`` (``= 20.0468 M √T_s``).
* Low speed: ``V_T = V_c √(ρ₀/ρ)`` — the thesis's eq. 2.6 prints the density
  ratio inverted.
* Angle of attack / sideslip (eq. 2.5, thesis definition): ``α = atan(V_z/V_x)``,
  ``β = atan(V_y/V_x)`` (β with V_x in the denominator, not ``asin(V_y/V_T)``);
  TAS into body axes (eq. 2.7): ``V_x = V_T/√(1 + tan²α + tan²β)``,
  ``V_y = V_x tan β``, ``V_z = V_x tan α`` (body FRD).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.atmosphere import A0, GAMMA, P0, R_AIR, RHO0, pressure_altitude
from imunav.errors import ConvergenceError, InvalidInputError, NonFiniteError, ShapeError
from imunav.results import Result

__all__ = [
    "PT_RATIO_SONIC",
    "pitot_ratio",
    "mach_from_pressures",
    "calibrated_airspeed",
    "impact_pressure_from_cas",
    "static_temperature",
    "total_temperature",
    "true_airspeed",
    "tas_from_cas_low_speed",
    "density_ratio",
    "aoa_sideslip",
    "tas_to_body",
    "AirData",
    "air_data",
]

Array = NDArray[np.float64]
PT_RATIO_SONIC = (1.2) ** 3.5  # 1.8929
_RAYLEIGH_K = 7.2**3.5 / 6.0  # 166.9216: Rayleigh pitot formula for γ = 1.4


def _arr(x: ArrayLike, name: str, positive: bool = False) -> Array:
    a = np.asarray(x, dtype=np.float64)
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{name} contains NaN or inf; pass finite values")
    if positive and np.any(a <= 0):
        raise InvalidInputError(f"{name} must be > 0 (SI units: Pa, K, m/s), got min {a.min()}")
    return a


def pitot_ratio(mach: ArrayLike) -> Array:
    """``p_t / p`` for a pitot probe at Mach M (isentropic below 1, Rayleigh above; module docstring).

    Parameters
    ----------
    mach : array_like
        Mach number, >= 0.

    Returns
    -------
    numpy.ndarray
        Ratio of total to static pressure, >= 1.

    Raises
    ------
    InvalidInputError
        If a Mach number is negative.
    NonFiniteError
        If a value is NaN or infinite.
    """
    M = _arr(mach, "mach")
    if np.any(M < 0):
        raise InvalidInputError("mach must be >= 0")
    sub = (1.0 + 0.2 * M**2) ** 3.5
    Ms = np.maximum(M, 1.0)
    sup = _RAYLEIGH_K * Ms**7 / (7.0 * Ms**2 - 1.0) ** 2.5
    return np.where(M <= 1.0, sub, sup)


def _invert_pitot(ratio: Array, name: str) -> Array:
    """Mach-like number from ``p_t/p`` (subsonic closed form, supersonic Newton)."""
    if np.any(ratio < 1.0):
        raise InvalidInputError(f"{name}: total pressure below static pressure (ratio {ratio.min():.4f} < 1); "
                                "check the pressure channels")
    shape = np.shape(ratio)
    ratio = np.atleast_1d(ratio)
    M = np.sqrt(5.0 * (ratio ** (2.0 / 7.0) - 1.0))
    sup = ratio > PT_RATIO_SONIC
    if np.any(sup):
        r = ratio[sup]
        m = np.maximum(M[sup], 1.0)
        for _ in range(50):
            f = _RAYLEIGH_K * m**7 / (7 * m**2 - 1) ** 2.5 - r
            # d/dm of m^7 (7m²−1)^−2.5 = m^6 (7m²−1)^−3.5 (7(7m²−1) − 35 m²) = m^6 (14m² − 7)(7m²−1)^−3.5
            df = _RAYLEIGH_K * m**6 * (14 * m**2 - 7) / (7 * m**2 - 1) ** 3.5
            step = f / df
            m = m - step
            if np.max(np.abs(step)) < 1e-13:
                break
        else:  # pragma: no cover - the Newton map is monotone and converges in < 10 steps
            raise ConvergenceError(f"{name}: supersonic pitot inversion did not converge")
        M[sup] = m
    return M.reshape(shape)


def mach_from_pressures(p_total: ArrayLike, p_static: ArrayLike) -> Array:
    """Mach number from total and static pressure (Pa), sub- and supersonic (inverse of :func:`pitot_ratio`).

    Parameters
    ----------
    p_total : array_like
        Total (pitot) pressure, Pa.
    p_static : array_like
        Static pressure, Pa, > 0.

    Returns
    -------
    numpy.ndarray
        Mach number.

    Raises
    ------
    InvalidInputError
        If a pressure is not positive, or ``p_total < p_static``.
    NonFiniteError
        If a value is NaN or infinite.
    ConvergenceError
        If the supersonic inversion does not converge.
    """
    pt = _arr(p_total, "p_total", True)
    ps = _arr(p_static, "p_static", True)
    return _invert_pitot(np.asarray(pt / ps, dtype=np.float64), "mach_from_pressures")


def calibrated_airspeed(impact_pressure: ArrayLike) -> Array:
    """Calibrated airspeed (m/s) from impact pressure ``q_c`` (Pa) (the thesis's Table 2.1 d, inverted).

    Parameters
    ----------
    impact_pressure : array_like
        ``q_c = p_t − p``, Pa, >= 0.

    Returns
    -------
    numpy.ndarray
        Calibrated airspeed, m/s.

    Raises
    ------
    InvalidInputError
        If an impact pressure is negative.
    NonFiniteError
        If a value is NaN or infinite.
    """
    qc = _arr(impact_pressure, "impact_pressure")
    if np.any(qc < 0):
        raise InvalidInputError("impact_pressure must be >= 0 Pa (total pressure below static?)")
    return A0 * _invert_pitot(np.asarray(qc / P0 + 1.0, dtype=np.float64), "calibrated_airspeed")


def impact_pressure_from_cas(cas: ArrayLike) -> Array:
    """Impact pressure (Pa) for a calibrated airspeed (m/s) (the inverse of :func:`calibrated_airspeed`).

    Parameters
    ----------
    cas : array_like
        Calibrated airspeed, m/s, >= 0.

    Returns
    -------
    numpy.ndarray
        Impact pressure ``q_c``, Pa.
    """
    v = _arr(cas, "cas")
    return P0 * (pitot_ratio(v / A0) - 1.0)


def static_temperature(total_temperature_k: ArrayLike, mach: ArrayLike, recovery: float = 1.0) -> Array:
    """``T_s = T_m / (1 + 0.2 r M²)`` (the thesis's Table 2.1 e).

    Parameters
    ----------
    total_temperature_k : array_like
        Measured total air temperature, K, > 0.
    mach : array_like
        Mach number, >= 0.
    recovery : float
        Probe recovery factor r in (0, 1].

    Returns
    -------
    numpy.ndarray
        Static air temperature, K.

    Raises
    ------
    InvalidInputError
        If a temperature is not positive or ``recovery`` is outside (0, 1].
    NonFiniteError
        If a value is NaN or infinite.
    """
    Tm = _arr(total_temperature_k, "total_temperature_k", True)
    M = _arr(mach, "mach")
    if not 0 < recovery <= 1.0:
        raise InvalidInputError(f"recovery factor must be in (0, 1], got {recovery}")
    return Tm / (1.0 + 0.2 * recovery * M**2)


def total_temperature(static_temperature_k: ArrayLike, mach: ArrayLike, recovery: float = 1.0) -> Array:
    """Measured total air temperature ``T_m = T_s (1 + 0.2 r M²)``.

    Parameters
    ----------
    static_temperature_k : array_like
        Static air temperature, K.
    mach : array_like
        Mach number, >= 0.
    recovery : float
        Probe recovery factor r.

    Returns
    -------
    numpy.ndarray
        Total air temperature, K.
    """
    return _arr(static_temperature_k, "static_temperature_k", True) * (1.0 + 0.2 * recovery * _arr(mach, "mach")**2)


def true_airspeed(mach: ArrayLike, static_temperature_k: ArrayLike) -> Array:
    """``V_T = M √(γ R T_s)`` (the thesis's Table 2.1 f: 20.0468 M √T_s).

    Parameters
    ----------
    mach : array_like
        Mach number, >= 0.
    static_temperature_k : array_like
        Static air temperature, K.

    Returns
    -------
    numpy.ndarray
        True airspeed, m/s.
    """
    return _arr(mach, "mach") * np.sqrt(GAMMA * R_AIR * _arr(static_temperature_k, "static_temperature_k", True))


def density_ratio(p_static: ArrayLike, static_temperature_k: ArrayLike) -> Array:
    """``ρ/ρ₀ = p / (R T ρ₀)`` (the thesis's Table 2.1 b; 0.35164 T in kPa units).

    Parameters
    ----------
    p_static : array_like
        Static pressure, Pa.
    static_temperature_k : array_like
        Static air temperature, K.

    Returns
    -------
    numpy.ndarray
        Density relative to the ISA sea-level density ρ₀ = 1.225 kg/m³.
    """
    return _arr(p_static, "p_static", True) / (R_AIR * _arr(static_temperature_k, "static_temperature_k", True) * RHO0)


def tas_from_cas_low_speed(cas: ArrayLike, rho_ratio: ArrayLike, compressibility: ArrayLike = 1.0) -> Array:
    """Low-speed TAS ``V_T = V_c (f/f₀) √(ρ₀/ρ)`` (the thesis's eq. 2.6 with the density ratio corrected).

    Parameters
    ----------
    cas : array_like
        Calibrated airspeed, m/s.
    rho_ratio : array_like
        Density ratio ρ/ρ₀.
    compressibility : array_like
        Compressibility correction ``f/f₀`` (1 at low speed).

    Returns
    -------
    numpy.ndarray
        True airspeed, m/s.
    """
    return _arr(cas, "cas") * _arr(compressibility, "compressibility") / np.sqrt(_arr(rho_ratio, "rho_ratio", True))


def aoa_sideslip(v_air_body: ArrayLike, definition: str = "thesis") -> tuple[Array, Array]:
    """Angle of attack and sideslip (rad) from the body-axis air velocity.

    ``definition="thesis"``: ``α = atan2(V_z, V_x)``, ``β = atan(V_y/V_x)`` (eq. 2.5);
    ``"standard"``: ``β = asin(V_y/|V|)``.

    Parameters
    ----------
    v_air_body : array_like, shape (3,) or (N, 3)
        Air velocity relative to the aircraft in body axes (FRD), m/s.
    definition : {"thesis", "standard"}
        Definition of β.

    Returns
    -------
    alpha : numpy.ndarray
        Angle of attack, rad.
    beta : numpy.ndarray
        Sideslip angle, rad.

    Raises
    ------
    ShapeError
        If ``v_air_body`` is not (3,) / (N, 3).
    InvalidInputError
        If ``definition`` is unknown or the forward component is not positive.
    """
    v = _arr(v_air_body, "v_air_body")
    if v.shape[-1] != 3:
        raise ShapeError(f"v_air_body must be (..., 3), got {v.shape}")
    if np.any(v[..., 0] <= 0):
        raise InvalidInputError("the forward air-velocity component must be > 0 for α/β (flying backwards?)")
    alpha = np.arctan2(v[..., 2], v[..., 0])
    if definition == "thesis":
        beta = np.arctan(v[..., 1] / v[..., 0])
    elif definition == "standard":
        beta = np.arcsin(v[..., 1] / np.linalg.norm(v, axis=-1))
    else:
        raise InvalidInputError(f"definition must be 'thesis' or 'standard', got {definition!r}")
    return alpha, beta


def tas_to_body(tas: ArrayLike, alpha: ArrayLike, beta: ArrayLike, definition: str = "thesis") -> Array:
    """Body-axis air velocity from TAS, α, β (eq. 2.7 for the thesis definition of β).

    Parameters
    ----------
    tas : array_like
        True airspeed, m/s.
    alpha : array_like
        Angle of attack, rad.
    beta : array_like
        Sideslip angle, rad.
    definition : {"thesis", "standard"}
        Definition of β (see :func:`aoa_sideslip`).

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        Air velocity in body axes (FRD), m/s.

    Raises
    ------
    InvalidInputError
        If ``definition`` is unknown.
    """
    V = _arr(tas, "tas")
    a = _arr(alpha, "alpha")
    b = _arr(beta, "beta")
    if definition == "thesis":
        vx = V / np.sqrt(1.0 + np.tan(a) ** 2 + np.tan(b) ** 2)
        return np.stack(np.broadcast_arrays(vx, vx * np.tan(b), vx * np.tan(a)), axis=-1)
    if definition == "standard":
        return np.stack(np.broadcast_arrays(V * np.cos(a) * np.cos(b), V * np.sin(b), V * np.sin(a) * np.cos(b)),
                        axis=-1)
    raise InvalidInputError(f"definition must be 'thesis' or 'standard', got {definition!r}")


@dataclass(frozen=True)
class AirData(Result):
    """Outputs of an air-data computer (SI).

    Attributes
    ----------
    pressure_altitude : numpy.ndarray
        Geopotential pressure altitude, m.
    mach : numpy.ndarray
        Mach number.
    cas : numpy.ndarray
        Calibrated airspeed, m/s.
    tas : numpy.ndarray
        True airspeed, m/s.
    static_temperature : numpy.ndarray
        Static air temperature, K.
    density : numpy.ndarray
        Air density, kg/m³.
    impact_pressure : numpy.ndarray
        Impact pressure ``q_c``, Pa.
    """

    pressure_altitude: Array
    mach: Array
    cas: Array
    tas: Array
    static_temperature: Array
    density: Array
    impact_pressure: Array


def air_data(p_total: ArrayLike, p_static: ArrayLike, total_temperature_k: ArrayLike, recovery: float = 1.0) -> AirData:
    """Air-data computer: pressures (Pa) and TAT (K) → altitude, Mach, CAS, TAS, SAT, ρ (module docstring).

    Parameters
    ----------
    p_total : array_like
        Total (pitot) pressure, Pa.
    p_static : array_like
        Static pressure, Pa.
    total_temperature_k : array_like
        Measured total air temperature, K.
    recovery : float
        Probe recovery factor r.

    Returns
    -------
    AirData
        The derived quantities, shaped like the inputs.

    Raises
    ------
    InvalidInputError
        If a pressure or temperature is not positive, or the total pressure is below the static one.
    NonFiniteError
        If a value is NaN or infinite.
    """
    pt = _arr(p_total, "p_total", True)
    ps = _arr(p_static, "p_static", True)
    M = mach_from_pressures(pt, ps)
    Ts = static_temperature(total_temperature_k, M, recovery)
    qc = pt - ps
    return AirData(pressure_altitude(ps), M, calibrated_airspeed(qc), true_airspeed(M, Ts), Ts,
                   ps / (R_AIR * Ts), qc)
