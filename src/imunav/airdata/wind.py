"""The wind triangle.

Ground velocity = air velocity + wind: ``V_G = V_A + W``, so ``W = V_G − V_A``
(Akgün 2002, §1.4; the "difference loop" takes exactly this difference of two
noisy sensors).  In the horizontal plane with true airspeed V_T and heading
ψ, ground speed V_G and track χ (angles from north, rad)::

    W_N = V_G cos χ − V_T cos ψ,   W_E = V_G sin χ − V_T sin ψ

Wind direction is reported meteorologically (the direction the wind blows
*from*), drift angle is ``χ − ψ``.  Solving for heading and ground speed on a
desired course: ``sin(ψ − χ) = (W_E cos χ − W_N sin χ)/V_T`` (wind-correction
angle), ``V_G = V_T cos(ψ − χ) + W_N cos χ + W_E sin χ``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InvalidInputError, ShapeError

__all__ = [
    "wind_from_velocities",
    "wind_from_speeds",
    "wind_speed_direction",
    "wind_from_speed_direction",
    "heading_for_course",
    "drift_angle",
]

Array = NDArray[np.float64]


def wind_from_velocities(v_ground: ArrayLike, v_air: ArrayLike) -> Array:
    """``W = V_G − V_A`` (…, 3), both in the same frame."""
    g = np.asarray(v_ground, dtype=np.float64)
    a = np.asarray(v_air, dtype=np.float64)
    if g.shape != a.shape:
        raise ShapeError(f"v_ground {g.shape} and v_air {a.shape} must have the same shape")
    return g - a


def wind_from_speeds(tas: ArrayLike, heading: ArrayLike, ground_speed: ArrayLike, track: ArrayLike
                     ) -> tuple[Array, Array]:
    """Horizontal wind (north, east) from TAS/heading and ground speed/track."""
    V, psi, G, chi = (np.asarray(x, dtype=np.float64) for x in (tas, heading, ground_speed, track))
    return G * np.cos(chi) - V * np.cos(psi), G * np.sin(chi) - V * np.sin(psi)


def wind_speed_direction(w_north: ArrayLike, w_east: ArrayLike) -> tuple[Array, Array]:
    """(speed, direction the wind blows *from*, rad in [0, 2π)) of a horizontal wind."""
    wn = np.asarray(w_north, dtype=np.float64)
    we = np.asarray(w_east, dtype=np.float64)
    return np.hypot(wn, we), np.mod(np.arctan2(-we, -wn), 2 * np.pi)


def wind_from_speed_direction(speed: ArrayLike, direction_from: ArrayLike) -> tuple[Array, Array]:
    """(north, east) wind components from speed and meteorological direction (rad)."""
    s = np.asarray(speed, dtype=np.float64)
    d = np.asarray(direction_from, dtype=np.float64)
    return -s * np.cos(d), -s * np.sin(d)


def heading_for_course(tas: ArrayLike, course: ArrayLike, w_north: ArrayLike, w_east: ArrayLike
                       ) -> tuple[Array, Array]:
    """(heading, ground speed) that make good ``course`` through the wind.

    Raises :class:`InvalidInputError` where the crosswind exceeds the TAS (no solution).
    """
    V, chi, wn, we = (np.asarray(x, dtype=np.float64) for x in (tas, course, w_north, w_east))
    s = (we * np.cos(chi) - wn * np.sin(chi)) / V
    if np.any(np.abs(s) > 1):
        raise InvalidInputError("the crosswind component exceeds the true airspeed: no heading makes good this course")
    wca = -np.arcsin(s)
    gs = V * np.cos(wca) + wn * np.cos(chi) + we * np.sin(chi)
    if np.any(gs <= 0):
        raise InvalidInputError("the headwind exceeds the true airspeed: ground speed would be <= 0")
    return np.mod(chi + wca, 2 * np.pi), gs


def drift_angle(heading: ArrayLike, track: ArrayLike) -> Array:
    """Drift angle ``χ − ψ`` wrapped to (−π, π]."""
    d = np.asarray(track, dtype=np.float64) - np.asarray(heading, dtype=np.float64)
    return np.angle(np.exp(1j * d))
