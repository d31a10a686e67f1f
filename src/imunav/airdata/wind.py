"""The wind triangle.

Ground velocity = air velocity + wind: ``V_G = V_A + W``, so ``W = V_G − V_A``
(O. Akgün, *Integration of an air data system and a Doppler radar via Kalman filtering* (in Turkish),
MSc thesis, Istanbul Technical University, 2002, §1.4; the "difference loop" takes exactly this
difference of two noisy sensors; see also Kayton & Fried, *Avionics Navigation Systems*, 2nd ed., 1997).
In the horizontal plane with true airspeed V_T and heading ψ, ground speed V_G and track χ (angles from
north, rad)::

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
    """``W = V_G − V_A``, both in the same frame.

    Parameters
    ----------
    v_ground : array_like, shape (..., 3)
        Velocity over the ground, m/s (e.g. NED).
    v_air : array_like, shape (..., 3)
        Velocity relative to the air, same frame, m/s.

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        The wind, m/s, in that frame.

    Raises
    ------
    ShapeError
        If the shapes differ or the last axis is not 3.
    """
    g = np.asarray(v_ground, dtype=np.float64)
    a = np.asarray(v_air, dtype=np.float64)
    if g.shape != a.shape:
        raise ShapeError(f"v_ground {g.shape} and v_air {a.shape} must have the same shape")
    return g - a


def wind_from_speeds(tas: ArrayLike, heading: ArrayLike, ground_speed: ArrayLike, track: ArrayLike
                     ) -> tuple[Array, Array]:
    """Horizontal wind (north, east) from TAS/heading and ground speed/track (module docstring).

    Parameters
    ----------
    tas : array_like
        True airspeed, m/s.
    heading : array_like
        Heading ψ from north, rad.
    ground_speed : array_like
        Ground speed, m/s.
    track : array_like
        Track χ from north, rad.

    Returns
    -------
    w_north, w_east : numpy.ndarray
        Wind components, m/s.
    """
    V, psi, G, chi = (np.asarray(x, dtype=np.float64) for x in (tas, heading, ground_speed, track))
    return G * np.cos(chi) - V * np.cos(psi), G * np.sin(chi) - V * np.sin(psi)


def wind_speed_direction(w_north: ArrayLike, w_east: ArrayLike) -> tuple[Array, Array]:
    """Speed and meteorological direction of a horizontal wind.

    Parameters
    ----------
    w_north, w_east : array_like
        Wind components (the velocity of the air mass), north and east, m/s.

    Returns
    -------
    speed : numpy.ndarray
        Wind speed, m/s.
    direction_from : numpy.ndarray
        Direction the wind blows *from*, rad from north in [0, 2π).
    """
    wn = np.asarray(w_north, dtype=np.float64)
    we = np.asarray(w_east, dtype=np.float64)
    return np.hypot(wn, we), np.mod(np.arctan2(-we, -wn), 2 * np.pi)


def wind_from_speed_direction(speed: ArrayLike, direction_from: ArrayLike) -> tuple[Array, Array]:
    """(north, east) wind components from speed and meteorological direction (rad).

    Parameters
    ----------
    speed : array_like
        Wind speed, m/s.
    direction_from : array_like
        Direction the wind blows *from*, rad from north.

    Returns
    -------
    w_north, w_east : numpy.ndarray
        Wind components (velocity of the air mass), m/s.
    """
    s = np.asarray(speed, dtype=np.float64)
    d = np.asarray(direction_from, dtype=np.float64)
    return -s * np.cos(d), -s * np.sin(d)


def heading_for_course(tas: ArrayLike, course: ArrayLike, w_north: ArrayLike, w_east: ArrayLike
                       ) -> tuple[Array, Array]:
    """(heading, ground speed) that make good ``course`` through the wind (module docstring).

    Parameters
    ----------
    tas : array_like
        True airspeed, m/s, > 0.
    course : array_like
        Desired course χ from north, rad.
    w_north, w_east : array_like
        Wind components (the velocity of the air mass), north and east, m/s.

    Returns
    -------
    heading : numpy.ndarray
        Heading ψ, rad in [0, 2π).
    ground_speed : numpy.ndarray
        Ground speed along the course, m/s.

    Raises
    ------
    InvalidInputError
        Where the crosswind exceeds the TAS (no solution), or the headwind does (ground speed <= 0).
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
    """Drift angle ``χ − ψ`` wrapped to (−π, π].

    Parameters
    ----------
    heading : array_like
        Heading ψ, rad.
    track : array_like
        Track χ, rad.

    Returns
    -------
    numpy.ndarray
        Drift angle, rad.
    """
    d = np.asarray(track, dtype=np.float64) - np.asarray(heading, dtype=np.float64)
    return np.angle(np.exp(1j * d))
