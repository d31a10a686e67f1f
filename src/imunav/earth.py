"""WGS84 Earth model: normal gravity, Earth rate, radii of curvature, frames.

Frames: ECEF (x through lat 0 / lon 0, z through the north pole); local
navigation frame NED (north, east, down) at a geodetic position.  Geodetic
coordinates ``lla = (lat, lon, h)`` with ``lat``, ``lon`` in **radians** and
ellipsoidal height ``h`` in metres.

Every function takes scalars or arrays (a single point ``(3,)`` or a batch
``(N, 3)`` for coordinate triples; latitude / height arrays broadcast) and
returns the matching shape.

References
----------
NIMA TR8350.2, *Department of Defense World Geodetic System 1984*, 3rd ed.,
2000 (constants, eq. 4-1 Somigliana, eq. 4-3 height correction).
P. D. Groves, *Principles of GNSS, Inertial, and Multisensor Integrated
Navigation Systems*, 2nd ed., Artech House, 2013: eqs. 2.105-2.106 (radii),
2.112 (geodetic -> ECEF), 2.134 (Somigliana), 2.139 (height correction),
2.123 (Earth rate in NED), 5.44 (transport rate).
B. R. Bowring, "Transformation from spatial to geographical coordinates",
Survey Review 23(181), 1976 (iteration used by :func:`ecef_to_lla`).

Example
-------
>>> from imunav import earth
>>> round(float(earth.normal_gravity(0.0)), 10)
9.7803253359
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InvalidInputError, NonFiniteError, ShapeError

__all__ = [
    "A",
    "F",
    "B",
    "E2",
    "EP2",
    "GM",
    "OMEGA_E",
    "GAMMA_E",
    "GAMMA_P",
    "normal_gravity",
    "gravity_ned",
    "earth_rate_ned",
    "radii",
    "radii_gravity_1",
    "dlla_to_ned",
    "ned_to_dlla",
    "transport_rate_ned",
    "dcm_en",
    "lla_to_ecef",
    "ecef_to_lla",
    "ecef_to_ned",
    "ned_to_ecef",
    "lla_to_ned",
    "ned_to_lla",
    "vel_ned_from_ecef",
]

Array = NDArray[np.float64]

#: Semi-major axis, m (TR8350.2 Table 3.1).
A: Final[float] = 6378137.0
#: Flattening (TR8350.2 Table 3.1).
F: Final[float] = 1.0 / 298.257223563
#: Semi-minor axis, m.
B: Final[float] = A * (1.0 - F)
#: First eccentricity squared.
E2: Final[float] = F * (2.0 - F)
#: Second eccentricity squared.
EP2: Final[float] = E2 / (1.0 - E2)
#: Earth's gravitational constant (with atmosphere), m^3/s^2 (TR8350.2 Table 3.1).
GM: Final[float] = 3.986004418e14
#: Earth rotation rate, rad/s (TR8350.2 Table 3.1).
OMEGA_E: Final[float] = 7.292115e-5
#: Normal gravity at the equator and at the poles, m/s^2 (TR8350.2 Table 3.4).
GAMMA_E: Final[float] = 9.7803253359
GAMMA_P: Final[float] = 9.8321849379
#: Somigliana's constant k = b*gamma_p / (a*gamma_e) - 1 as published in
#: TR8350.2 Table 3.4 (computing it from the rounded gamma values differs by 4e-12).
_K_SOMIGLIANA: Final[float] = 0.00193185265241
#: m = omega^2 a^2 b / GM (TR8350.2 eq. 4-3).
_M: Final[float] = OMEGA_E**2 * A**2 * B / GM
# extended-precision copies for the ECEF conversions
_A_L = np.longdouble(A)
_F_L = np.longdouble(1) / np.longdouble("298.257223563")
_E2_L = _F_L * (2 - _F_L)


def _f(x: ArrayLike) -> Array | float:
    a = np.asarray(x, dtype=float)
    if not np.all(np.isfinite(a)):
        raise NonFiniteError("Earth-model input has NaN or infinite values; pass finite lat/lon (rad) and h (m)")
    return float(a) if a.ndim == 0 else a


def _triple(x: ArrayLike, name: str) -> tuple[Array, bool]:
    a = np.asarray(x, dtype=float)
    if a.shape == (3,):
        a2 = a.reshape(1, 3)
        single = True
    elif a.ndim == 2 and a.shape[1] == 3:
        a2, single = a, False
    else:
        raise ShapeError(f"{name} must have shape (3,) or (N, 3); got {a.shape}")
    if not np.all(np.isfinite(a2)):
        rows = np.flatnonzero(~np.all(np.isfinite(a2), axis=1))
        raise NonFiniteError(f"{name} has non-finite values at rows {rows[:10].tolist()}; remove them first")
    return a2, single


def _out(a: Array, single: bool) -> Array:
    return a[0] if single else a


def normal_gravity(lat: ArrayLike, h: ArrayLike = 0.0) -> Array | float:
    """Magnitude of WGS84 normal gravity (gravitation + centrifugal), m/s².

    Somigliana's closed form on the ellipsoid (TR8350.2 eq. 4-1, Groves 2.134)

        γ₀(φ) = γ_e (1 + k sin²φ) / √(1 − e² sin²φ),   k = b γ_p / (a γ_e) − 1,

    with the second-order height correction (TR8350.2 eq. 4-3, Groves 2.139)

        γ(φ, h) = γ₀(φ) [1 − 2/a (1 + f + m − 2 f sin²φ) h + 3 h² / a²],
        m = ω² a² b / GM.

    The height series is accurate to about 1e-6 m/s² up to 20 km.

    Parameters
    ----------
    lat : array_like
        Geodetic latitude, rad, in [-pi/2, pi/2] (scalar or array).
    h : array_like
        Ellipsoidal height, m (broadcasts with ``lat``), inside :data:`H_RANGE_M`.

    Returns
    -------
    float or numpy.ndarray
        γ(φ, h), m/s², positive (pointing down in NED); a float for scalar inputs.

    Raises
    ------
    InvalidInputError
        If a latitude is outside [-pi/2, pi/2] or a height outside :data:`H_RANGE_M`.
    NonFiniteError
        If an input is NaN or infinite.
    """
    return _radii_gravity(lat, h)[2]


@njit(cache=True)
def radii_gravity_1(lat: float, h: float) -> tuple[float, float, float]:
    """``(R_N, R_E, γ(φ, h))`` at one point: the formulas of :func:`radii` and
    :func:`normal_gravity`, as a numba kernel that strapdown kernels call."""
    s2 = math.sin(lat) ** 2
    d = 1.0 - E2 * s2
    rn = A * (1.0 - E2) / d**1.5
    re = A / math.sqrt(d)
    g0 = GAMMA_E * (1.0 + _K_SOMIGLIANA * s2) / math.sqrt(d)
    g = g0 * (1.0 - 2.0 / A * (1.0 + F + _M - 2.0 * F * s2) * h + 3.0 * h * h / (A * A))
    return rn, re, g


@njit(cache=True)
def _radii_gravity_n(lat, h):
    out = np.empty((3, lat.shape[0]))
    for i in range(lat.shape[0]):
        out[0, i], out[1, i], out[2, i] = radii_gravity_1(lat[i], h[i])
    return out


#: Valid ellipsoidal heights of the normal-gravity model, m: 10 km below the ellipsoid to 100 km above
#: (the height series is only accurate to ~20 km; far outside it the gravity it gives is meaningless).
H_RANGE_M: Final = (-1.0e4, 1.0e5)


def _check_lat_h(lat: Array, h: Array) -> None:
    if np.any(np.abs(lat) > np.pi / 2 + 1e-12):
        bad = float(np.ravel(lat)[np.argmax(np.abs(np.ravel(lat)))])
        raise InvalidInputError(f"latitude {np.degrees(bad):.6g} deg ({bad:.6g} rad) is outside [-90, 90] deg; "
                                "latitudes are geodetic, in radians in the library (--lat-deg in degrees on the CLI)")
    if np.any((h < H_RANGE_M[0]) | (h > H_RANGE_M[1])):
        bad = float(np.ravel(h)[np.argmax(np.maximum(H_RANGE_M[0] - np.ravel(h), np.ravel(h) - H_RANGE_M[1]))])
        raise InvalidInputError(f"height {bad:.6g} m is outside the normal-gravity model's range "
                                f"[{H_RANGE_M[0]:g}, {H_RANGE_M[1]:g}] m (ellipsoidal height, metres)")


def _radii_gravity(lat: ArrayLike, h: ArrayLike) -> tuple[Array | float, Array | float, Array | float]:
    la, ha = np.broadcast_arrays(np.asarray(_f(lat), dtype=float), np.asarray(_f(h), dtype=float))
    _check_lat_h(la, ha)
    res = _radii_gravity_n(np.ascontiguousarray(la.ravel()), np.ascontiguousarray(ha.ravel()))
    if la.ndim == 0:
        return float(res[0, 0]), float(res[1, 0]), float(res[2, 0])
    return res[0].reshape(la.shape), res[1].reshape(la.shape), res[2].reshape(la.shape)


def gravity_ned(lat: ArrayLike, h: ArrayLike = 0.0) -> Array:
    """Normal gravity vector in NED, ``(0, 0, +γ(φ, h))`` (m/s²).

    The small north component of the gravity vector above the ellipsoid
    (≈ −8.08e-9 h sin 2φ m/s², Groves 2.140) is neglected.

    Parameters
    ----------
    lat : array_like
        Geodetic latitude, rad, in [-pi/2, pi/2] (scalar or array).
    h : array_like
        Ellipsoidal height, m (broadcasts with ``lat``).

    Returns
    -------
    numpy.ndarray, shape (3,) or (..., 3)
        ``g_n`` in NED, m/s², one vector per latitude.

    Raises
    ------
    InvalidInputError
        If a latitude is outside [-pi/2, pi/2] or a height outside :data:`H_RANGE_M`.
    NonFiniteError
        If an input is NaN or infinite.
    """
    g = np.asarray(normal_gravity(lat, h))
    out = np.zeros(g.shape + (3,))
    out[..., 2] = g
    return out


def earth_rate_ned(lat: ArrayLike) -> Array:
    """Earth rotation rate resolved in NED, ``ω_ie^n = Ω (cos φ, 0, −sin φ)`` rad/s (Groves 2.123).

    Ω = :data:`OMEGA_E` = 7.292115e-5 rad/s (TR8350.2).

    Parameters
    ----------
    lat : array_like
        Geodetic latitude, rad, in [-pi/2, pi/2] (scalar or array).

    Returns
    -------
    numpy.ndarray, shape (3,) or (..., 3)
        ``ω_ie^n``, rad/s.

    Raises
    ------
    InvalidInputError
        If a latitude is outside [-pi/2, pi/2].
    NonFiniteError
        If an input is NaN or infinite.
    """
    lat = np.asarray(_f(lat))
    _check_lat_h(lat, np.zeros(()))
    out = np.zeros(lat.shape + (3,))
    out[..., 0] = OMEGA_E * np.cos(lat)
    out[..., 2] = -OMEGA_E * np.sin(lat)
    return out


def radii(lat: ArrayLike) -> tuple[Array | float, Array | float]:
    """Meridian and prime-vertical radii of curvature ``(R_N, R_E)``, m (Groves 2.105-2.106).

    R_N = a (1 − e²) / (1 − e² sin²φ)^{3/2},   R_E = a / √(1 − e² sin²φ).

    Parameters
    ----------
    lat : array_like
        Geodetic latitude, rad, in [-pi/2, pi/2] (scalar or array).

    Returns
    -------
    R_N : float or numpy.ndarray
        Meridian radius of curvature, m.
    R_E : float or numpy.ndarray
        Prime-vertical (transverse) radius of curvature, m.

    Raises
    ------
    InvalidInputError
        If a latitude is outside [-pi/2, pi/2].
    NonFiniteError
        If an input is NaN or infinite.
    """
    rn, re, _ = _radii_gravity(lat, 0.0)
    return rn, re


def dlla_to_ned(dlla: ArrayLike, lla: ArrayLike) -> Array:
    """A small geodetic difference in local metres, on the curvilinear radii at ``lla`` (Groves 2013, eq. 2.119).

    ``δN = δφ (R_N + h)``, ``δE = δλ (R_E + h) cos φ``, ``δD = −δh``: the position error states of a NED
    error-state filter.  :func:`lla_to_ned` is the exact (ECEF) form for any distance.

    Parameters
    ----------
    dlla : array_like, shape (N, 3)
        Differences ``(δlat rad, δlon rad, δh m)``.
    lla : array_like, shape (N, 3)
        Where they are taken: lat rad, lon rad, h m.

    Returns
    -------
    numpy.ndarray, shape (N, 3)
        North, east, down, m.
    """
    d, p = np.asarray(dlla, dtype=float), np.asarray(lla, dtype=float)
    rn, re = radii(p[:, 0])
    return np.column_stack([d[:, 0] * (rn + p[:, 2]), d[:, 1] * (re + p[:, 2]) * np.cos(p[:, 0]), -d[:, 2]])


def ned_to_dlla(dned: ArrayLike, lla: ArrayLike) -> Array:
    """Local NED metres as a small geodetic difference at ``lla``: the inverse of :func:`dlla_to_ned`.

    Parameters
    ----------
    dned : array_like, shape (N, 3)
        North, east, down, m.
    lla : array_like, shape (N, 3)
        Where they are applied: lat rad, lon rad, h m.

    Returns
    -------
    numpy.ndarray, shape (N, 3)
        ``(δlat rad, δlon rad, δh m)``; ``lla + ned_to_dlla(d, lla)`` moves ``lla`` by ``d``.
    """
    d, p = np.asarray(dned, dtype=float), np.asarray(lla, dtype=float)
    rn, re = radii(p[:, 0])
    return np.column_stack([d[:, 0] / (rn + p[:, 2]), d[:, 1] / ((re + p[:, 2]) * np.cos(p[:, 0])), -d[:, 2]])


def transport_rate_ned(lat: ArrayLike, h: ArrayLike, vel_ned: ArrayLike) -> Array:
    """Transport rate ``ω_en^n`` (rate of NED w.r.t. ECEF) in NED, rad/s (Groves 5.44).

    ω_en^n = ( v_E/(R_E+h), −v_N/(R_N+h), −v_E tan φ/(R_E+h) ).

    Parameters
    ----------
    lat : array_like
        Geodetic latitude, rad, in [-pi/2, pi/2] (scalar or array).
    h : array_like
        Ellipsoidal height, m.
    vel_ned : array_like, shape (3,) or (N, 3)
        Velocity relative to the Earth, resolved in NED, m/s.

    Returns
    -------
    numpy.ndarray, shape (3,) or (N, 3)
        ``ω_en^n``, rad/s.

    Raises
    ------
    InvalidInputError
        If a latitude is outside [-pi/2, pi/2] or a height outside :data:`H_RANGE_M`.
    NonFiniteError
        If an input is NaN or infinite.
    ShapeError
        If ``vel_ned`` is not (3,) / (N, 3).
    """
    v, single = _triple(vel_ned, "vel_ned")
    lat = np.asarray(_f(lat), dtype=float)
    h = np.asarray(_f(h), dtype=float)
    rn, re = radii(lat)
    rn = np.asarray(rn) + h
    re = np.asarray(re) + h
    out = np.empty_like(v)
    out[:, 0] = v[:, 1] / re
    out[:, 1] = -v[:, 0] / rn
    out[:, 2] = -v[:, 1] * np.tan(lat) / re
    return _out(out, single and lat.ndim == 0 and h.ndim == 0)


def dcm_en(lat: ArrayLike, lon: ArrayLike) -> Array:
    """``C_en``: rotates NED vectors into ECEF, ``v_e = C_en v_n`` (Groves 2.150 transposed).

    Columns are the north, east and down unit vectors in ECEF:
    ``C_en = [[-sφ cλ, -sλ, -cφ cλ], [-sφ sλ, cλ, -cφ sλ], [cφ, 0, -sφ]]``.

    Parameters
    ----------
    lat : array_like
        Geodetic latitude, rad.
    lon : array_like
        Longitude, rad (broadcasts with ``lat``).

    Returns
    -------
    numpy.ndarray, shape (3, 3) or (N, 3, 3)
        ``C_en``; ``(3, 3)`` for scalars.

    Raises
    ------
    NonFiniteError
        If an input is NaN or infinite.
    """
    lat = np.asarray(_f(lat), dtype=float)
    lon = np.asarray(_f(lon), dtype=float)
    sl, cl = np.sin(lat), np.cos(lat)
    so, co = np.sin(lon), np.cos(lon)
    sl, cl, so, co = np.broadcast_arrays(sl, cl, so, co)
    C = np.empty(sl.shape + (3, 3))
    C[..., 0, 0] = -sl * co
    C[..., 0, 1] = -so
    C[..., 0, 2] = -cl * co
    C[..., 1, 0] = -sl * so
    C[..., 1, 1] = co
    C[..., 1, 2] = -cl * so
    C[..., 2, 0] = cl
    C[..., 2, 1] = 0.0
    C[..., 2, 2] = -sl
    return C


def lla_to_ecef(lla: ArrayLike) -> Array:
    """Geodetic ``(lat, lon, h)`` (rad, rad, m) to ECEF position (m) (Groves 2.112).

    x = (R_E + h) cos φ cos λ,  y = (R_E + h) cos φ sin λ,  z = ((1 − e²) R_E + h) sin φ.

    Parameters
    ----------
    lla : array_like, shape (3,) or (N, 3)
        Geodetic latitude (rad), longitude (rad), ellipsoidal height (m).

    Returns
    -------
    numpy.ndarray, shape (3,) or (N, 3)
        ECEF position, m.

    Raises
    ------
    ShapeError
        If a triple is not (3,) / (N, 3).
    NonFiniteError
        If an input is NaN or infinite.
    """
    p, single = _triple(lla, "lla")
    # evaluated in extended precision (where the platform has it) so that the
    # only error left is the final rounding to float64 (< 0.5 ulp per axis)
    q = p.astype(np.longdouble)
    lat, lon, h = q[:, 0], q[:, 1], q[:, 2]
    sl = np.sin(lat)
    re = _A_L / np.sqrt(1 - _E2_L * sl * sl)
    out = np.empty_like(p)
    out[:, 0] = ((re + h) * np.cos(lat) * np.cos(lon)).astype(float)
    out[:, 1] = ((re + h) * np.cos(lat) * np.sin(lon)).astype(float)
    out[:, 2] = (((1 - _E2_L) * re + h) * sl).astype(float)
    return _out(out, single)


def ecef_to_lla(ecef: ArrayLike) -> Array:
    """ECEF position (m) to geodetic ``(lat, lon, h)`` (rad, rad, m).

    Bowring's (1976) parametric-latitude iteration, run four times: each
    iteration cubes the error, so the result is at machine precision
    (< 1e-12 rad, < 1e-9 m) everywhere except within ~50 km of the Earth's
    centre.  Height uses the well-conditioned form
    ``h = p cos φ + z sin φ − a √(1 − e² sin²φ)`` (valid at the poles too).

    Parameters
    ----------
    ecef : array_like, shape (3,) or (N, 3)
        ECEF position, m.

    Returns
    -------
    numpy.ndarray, shape (3,) or (N, 3)
        Geodetic latitude (rad), longitude (rad, in (-pi, pi]), ellipsoidal height (m).

    Raises
    ------
    ShapeError
        If a triple is not (3,) / (N, 3).
    NonFiniteError
        If an input is NaN or infinite.
    """
    r, single = _triple(ecef, "ecef")
    x, y, z = r[:, 0], r[:, 1], r[:, 2]
    p = np.hypot(x, y)
    lon = np.arctan2(y, x)
    # parametric (reduced) latitude start value
    beta = np.arctan2(z, (1.0 - F) * p)
    for _ in range(4):
        sb, cb = np.sin(beta), np.cos(beta)
        lat = np.arctan2(z + EP2 * B * sb**3, p - E2 * A * cb**3)
        beta = np.arctan2((1.0 - F) * np.sin(lat), np.cos(lat))
    # height along the normal from the foot point (p_s, z_s) on the ellipsoid,
    # in extended precision: h = (p - p_s) cos(lat) + (z - z_s) sin(lat)
    latl = lat.astype(np.longdouble)
    sl, cl = np.sin(latl), np.cos(latl)
    re = _A_L / np.sqrt(1 - _E2_L * sl * sl)
    pl = np.hypot(x.astype(np.longdouble), y.astype(np.longdouble))
    h = ((pl - re * cl) * cl + (z.astype(np.longdouble) - (1 - _E2_L) * re * sl) * sl).astype(float)
    return _out(np.stack([lat, lon, h], axis=1), single)


def _ref(ref_lla: ArrayLike) -> Array:
    a = np.asarray(ref_lla, dtype=float)
    if a.shape != (3,):
        raise ShapeError(f"ref_lla must be one point (lat rad, lon rad, h m) of shape (3,); got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise NonFiniteError("ref_lla has non-finite values")
    return a


def ecef_to_ned(ecef: ArrayLike, ref_lla: ArrayLike) -> Array:
    """ECEF position(s) to local NED coordinates (m) about the origin ``ref_lla``.

    ``r_n = C_en(ref)ᵀ (r_e − r_e(ref))`` (the tangent plane at the origin).

    Parameters
    ----------
    ecef : array_like, shape (3,) or (N, 3)
        ECEF position(s), m.
    ref_lla : array_like, shape (3,)
        Origin of the local NED frame: geodetic ``(lat, lon, h)``, rad, rad, m.

    Returns
    -------
    numpy.ndarray, shape (3,) or (N, 3)
        North, east, down coordinates, m.

    Raises
    ------
    ShapeError
        If a triple is not (3,) / (N, 3).
    NonFiniteError
        If an input is NaN or infinite.
    """
    r, single = _triple(ecef, "ecef")
    ref = _ref(ref_lla)
    d = r - lla_to_ecef(ref)
    C = dcm_en(ref[0], ref[1])
    return _out(d @ C, single)


def ned_to_ecef(ned: ArrayLike, ref_lla: ArrayLike) -> Array:
    """Local NED coordinates (m) about ``ref_lla`` to ECEF position(s) (m): ``r_e = r_e(ref) + C_en(ref) r_n``.

    Parameters
    ----------
    ned : array_like, shape (3,) or (N, 3)
        North, east, down coordinates, m.
    ref_lla : array_like, shape (3,)
        Origin of the local NED frame: geodetic ``(lat, lon, h)``, rad, rad, m.

    Returns
    -------
    numpy.ndarray, shape (3,) or (N, 3)
        ECEF position(s), m.

    Raises
    ------
    ShapeError
        If a triple is not (3,) / (N, 3).
    NonFiniteError
        If an input is NaN or infinite.
    """
    n, single = _triple(ned, "ned")
    ref = _ref(ref_lla)
    C = dcm_en(ref[0], ref[1])
    return _out(lla_to_ecef(ref) + n @ C.T, single)


def lla_to_ned(lla: ArrayLike, ref_lla: ArrayLike) -> Array:
    """Geodetic position(s) to local NED coordinates (m) about ``ref_lla`` (via ECEF, exact).

    Parameters
    ----------
    lla : array_like, shape (3,) or (N, 3)
        Geodetic ``(lat, lon, h)``, rad, rad, m.
    ref_lla : array_like, shape (3,)
        Origin of the local NED frame: geodetic ``(lat, lon, h)``, rad, rad, m.

    Returns
    -------
    numpy.ndarray, shape (3,) or (N, 3)
        North, east, down coordinates, m.

    Raises
    ------
    ShapeError
        If a triple is not (3,) / (N, 3).
    NonFiniteError
        If an input is NaN or infinite.
    """
    return ecef_to_ned(lla_to_ecef(lla), ref_lla)


def ned_to_lla(ned: ArrayLike, ref_lla: ArrayLike) -> Array:
    """Local NED coordinates (m) about ``ref_lla`` to geodetic position(s) (via ECEF, exact).

    Parameters
    ----------
    ned : array_like, shape (3,) or (N, 3)
        North, east, down coordinates, m.
    ref_lla : array_like, shape (3,)
        Origin of the local NED frame: geodetic ``(lat, lon, h)``, rad, rad, m.

    Returns
    -------
    numpy.ndarray, shape (3,) or (N, 3)
        Geodetic ``(lat, lon, h)``, rad, rad, m.

    Raises
    ------
    ShapeError
        If a triple is not (3,) / (N, 3).
    NonFiniteError
        If an input is NaN or infinite.
    """
    return ecef_to_lla(ned_to_ecef(ned, ref_lla))


def vel_ned_from_ecef(vel_ecef: ArrayLike, lla: ArrayLike) -> Array:
    """Resolve ECEF velocity (m/s) in the NED frame at each position: ``v_n = C_enᵀ v_e``.

    Parameters
    ----------
    vel_ecef : array_like, shape (3,) or (N, 3)
        Velocity resolved in ECEF, m/s.
    lla : array_like, shape (3,) or (N, 3)
        Geodetic position(s) ``(lat, lon, h)``, rad, rad, m: one, or one per velocity.

    Returns
    -------
    numpy.ndarray, shape (3,) or (N, 3)
        Velocity resolved in NED, m/s.

    Raises
    ------
    ShapeError
        If the shapes are wrong or the row counts differ.
    NonFiniteError
        If an input is NaN or infinite.
    """
    v, single = _triple(vel_ecef, "vel_ecef")
    p, _ = _triple(lla, "lla")
    if p.shape[0] not in (1, v.shape[0]):
        raise ShapeError(f"vel_ecef has {v.shape[0]} rows and lla {p.shape[0]}; they must match")
    C = dcm_en(p[:, 0], p[:, 1])
    return _out(np.einsum("nji,nj->ni", np.broadcast_to(C, (v.shape[0], 3, 3)), v), single)

