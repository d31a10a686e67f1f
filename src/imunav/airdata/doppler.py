"""Doppler navigation radar: beam geometry, Doppler shifts, velocity by least squares, errors.

References: O. Akgün, *Hava verileri sistemi ile Doppler radarının Kalman süzgeci temelinde
tümleştirilmesi* (Integration of an air data system and a Doppler radar via Kalman filtering), MSc
thesis, Istanbul Technical University, 2002, ch. 3 ("the thesis"); M. Kayton, W. R. Fried, *Avionics
Navigation Systems*, 2nd ed., Wiley, 1997 (Doppler radar chapter).

Two-way Doppler shift along a beam (Akgün 2002, eqs. 3.1-3.3):
``f_D = 2 V cos γ / λ = 2 (b · v) / λ`` with b the beam unit vector and v the
ground velocity in body axes (FRD).  Beam i of a Janus array points at
azimuth ψ_i from the nose and depression δ below the body x-y plane:
``b_i = [cos δ cos ψ_i, cos δ sin ψ_i, sin δ]`` (z down).  The 4-beam Janus
array uses ψ = 45°, 135°, 225°, 315°; the 3-beam ("λ") array 45°, 315°, 180°.
The body velocity follows from the beam velocities by least squares,
``v = (BᵀB)⁻¹ Bᵀ v_b``, whose noise covariance is ``σ² (BᵀB)⁻¹``.

Beam-pointing error (eq. 3.4): a beam-angle error δγ gives a fractional
velocity error ``ε = tan γ₀ · δγ`` (γ₀ = 70°, 1° → 4.8 %; the thesis rounds
to 4.7 %).  Janus pairs cancel it to first order.

Error model (the error sources of the thesis's §3.3, which it does not simulate: it adds 0.1 m/s
white noise per body axis, eq. 5.10): per-beam bias, common scale-factor
error (calibration, beam-direction, frequency-to-digital), white noise
(fluctuation / scintillation), and over water a calibration shift plus the
water-surface velocity (currents, wind drift) seen as ground motion.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import DegenerateGeometryError, InvalidInputError, NonFiniteError, ShapeError
from imunav.results import Result

__all__ = [
    "JANUS4_AZIMUTHS_DEG",
    "LAMBDA3_AZIMUTHS_DEG",
    "janus_beams",
    "doppler_shift",
    "beam_velocities",
    "velocity_from_beams",
    "velocity_covariance",
    "beam_angle_error",
    "DopplerErrors",
    "DopplerMeasurement",
    "simulate_doppler",
    "doppler_additive",
]

Array = NDArray[np.float64]
JANUS4_AZIMUTHS_DEG = (45.0, 135.0, 225.0, 315.0)
LAMBDA3_AZIMUTHS_DEG = (45.0, 315.0, 180.0)


def janus_beams(n_beams: int = 4, depression_deg: float = 65.0, azimuths_deg: ArrayLike | None = None) -> Array:
    """Beam unit vectors in body axes FRD.

    Parameters
    ----------
    n_beams : {4, 3}
        4 (Janus, azimuths 45/135/225/315°) or 3 (45/315/180°) unless ``azimuths_deg`` is given.
    depression_deg : float
        Depression of each beam below the body x-y plane, degrees, in (0, 90).
    azimuths_deg : array_like, optional
        Beam azimuths from the nose, degrees (overrides ``n_beams``).

    Returns
    -------
    numpy.ndarray, shape (n_beams, 3)
        ``b_i = [cos δ cos ψ_i, cos δ sin ψ_i, sin δ]``.

    Raises
    ------
    InvalidInputError
        If ``n_beams`` is not 3 or 4 (without azimuths), or the depression is out of range.
    """
    if azimuths_deg is None:
        if n_beams == 4:
            az = np.asarray(JANUS4_AZIMUTHS_DEG)
        elif n_beams == 3:
            az = np.asarray(LAMBDA3_AZIMUTHS_DEG)
        else:
            raise InvalidInputError(f"n_beams must be 3 or 4 without azimuths_deg, got {n_beams}")
    else:
        az = np.asarray(azimuths_deg, dtype=np.float64).reshape(-1)
    if not 0 < depression_deg < 90:
        raise InvalidInputError(f"depression_deg must be in (0, 90), got {depression_deg}")
    d = np.deg2rad(depression_deg)
    a = np.deg2rad(az)
    return np.stack([np.cos(d) * np.cos(a), np.cos(d) * np.sin(a), np.full_like(a, np.sin(d))], axis=1)


def _beams(beams: ArrayLike) -> Array:
    B = np.asarray(beams, dtype=np.float64)
    if B.ndim != 2 or B.shape[1] != 3:
        raise ShapeError(f"beams must be (n_beams, 3), got {B.shape}")
    if not np.allclose(np.linalg.norm(B, axis=1), 1.0, atol=1e-9):
        raise InvalidInputError("beam vectors must be unit vectors; use janus_beams()")
    if np.linalg.matrix_rank(B) < 3:
        raise DegenerateGeometryError(f"the {B.shape[0]} beams span fewer than 3 directions; "
                                      "need at least 3 non-coplanar beams")
    return B


def _vel(v: ArrayLike, name: str) -> Array:
    a = np.asarray(v, dtype=np.float64)
    if a.shape[-1] != 3:
        raise ShapeError(f"{name} must be (..., 3), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{name} contains NaN or inf")
    return a


def beam_velocities(v_body: ArrayLike, beams: ArrayLike) -> Array:
    """Velocity along each beam ``b_i · v``.

    Parameters
    ----------
    v_body : array_like, shape (3,) or (N, 3)
        Ground velocity in body axes (FRD), m/s.
    beams : array_like, shape (n_beams, 3)
        Beam unit vectors in body axes (:func:`janus_beams`).

    Returns
    -------
    numpy.ndarray, shape (..., n_beams)
        Beam velocities, m/s.
    """
    return _vel(v_body, "v_body") @ _beams(beams).T


def doppler_shift(v_body: ArrayLike, beams: ArrayLike, wavelength: float) -> Array:
    """Two-way Doppler shifts ``2 b_i·v / λ`` (Akgün 2002, eq. 3.3).

    Parameters
    ----------
    v_body : array_like, shape (3,) or (N, 3)
        Ground velocity in body axes (FRD), m/s.
    beams : array_like, shape (n_beams, 3)
        Beam unit vectors in body axes (:func:`janus_beams`).
    wavelength : float
        Radar wavelength λ, m, > 0 (13.3 GHz: 0.0225 m).

    Returns
    -------
    numpy.ndarray, shape (..., n_beams)
        Doppler shifts, Hz.

    Raises
    ------
    InvalidInputError
        If the wavelength is not positive.
    """
    if not wavelength > 0:
        raise InvalidInputError(f"wavelength must be > 0 m, got {wavelength}")
    return 2.0 * beam_velocities(v_body, beams) / wavelength


def velocity_from_beams(beam_vel: ArrayLike, beams: ArrayLike) -> Array:
    """Least-squares body velocity from beam velocities, ``v = (BᵀB)⁻¹ Bᵀ v_b``.

    Parameters
    ----------
    beam_vel : array_like, shape (..., n_beams)
        Beam velocities, m/s.
    beams : array_like, shape (n_beams, 3)
        Beam unit vectors in body axes (:func:`janus_beams`).

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        Body-axis (FRD) velocity, m/s.

    Raises
    ------
    ShapeError
        If the number of beam velocities does not match the beams.
    """
    B = _beams(beams)
    vb = np.asarray(beam_vel, dtype=np.float64)
    if vb.shape[-1] != B.shape[0]:
        raise ShapeError(f"beam_vel has {vb.shape[-1]} beams, the geometry has {B.shape[0]}")
    return vb @ np.linalg.pinv(B).T


def velocity_covariance(beams: ArrayLike, sigma_beam: float) -> Array:
    """Covariance ``σ² (BᵀB)⁻¹`` of the least-squares velocity for white beam noise σ.

    Parameters
    ----------
    beams : array_like, shape (n_beams, 3)
        Beam unit vectors in body axes (:func:`janus_beams`).
    sigma_beam : float
        Standard deviation of the white noise on each beam velocity, m/s.

    Returns
    -------
    numpy.ndarray, shape (3, 3)
        Covariance of the body velocity, (m/s)².
    """
    B = _beams(beams)
    return sigma_beam**2 * np.linalg.inv(B.T @ B)


def beam_angle_error(gamma0: ArrayLike, dgamma: ArrayLike) -> Array:
    """Fractional velocity error ``tan γ₀ · δγ`` of a beam-angle error (Akgün 2002, eq. 3.4).

    Parameters
    ----------
    gamma0 : array_like
        Angle between the beam and the velocity, rad.
    dgamma : array_like
        Beam-angle error, rad.

    Returns
    -------
    numpy.ndarray
        Fractional velocity error (0.048 = 4.8 %).
    """
    return np.tan(np.asarray(gamma0, dtype=np.float64)) * np.asarray(dgamma, dtype=np.float64)


@dataclass(frozen=True)
class DopplerErrors(Result):
    """Doppler radar error budget (SI), after the error sources of Akgün 2002, §3.3.

    Attributes
    ----------
    bias : float or tuple of float
        Per-beam velocity bias, m/s, scalar or one per beam.
    scale : float
        Common fractional scale error (0.002 = 0.2 %).
    noise : float
        Per-beam white-noise standard deviation, m/s.
    water_scale : float
        Extra fractional scale error over water (calibration shift).
    water_velocity_body : tuple of float
        Surface-water velocity seen as ground motion over water, body axes, m/s.
    """

    bias: float | tuple[float, ...] = 0.0
    scale: float = 0.0
    noise: float = 0.1
    water_scale: float = -0.005
    water_velocity_body: tuple[float, float, float] = (0.5, 0.3, 0.0)


@dataclass(frozen=True)
class DopplerMeasurement(Result):
    """Simulated Doppler output.

    Attributes
    ----------
    beam_velocity : numpy.ndarray, shape (N, n_beams)
        Measured beam velocities, m/s.
    velocity : numpy.ndarray, shape (N, 3)
        Least-squares body velocity (FRD), m/s.
    covariance : numpy.ndarray, shape (3, 3)
        Covariance of ``velocity`` from the beam noise, (m/s)².
    """

    beam_velocity: Array
    velocity: Array
    covariance: Array


def simulate_doppler(
    v_body: ArrayLike,
    beams: ArrayLike | None = None,
    errors: DopplerErrors | None = None,
    over_water: ArrayLike | None = None,
    rng: np.random.Generator | int | None = None,
) -> DopplerMeasurement:
    """Beam-level Doppler simulation.

    ``v_b,i = (1 + scale + water_scale·w) b_i·(v − w·v_water) + bias_i + noise``
    with w = 1 over water; the body velocity is the least-squares solution.

    Parameters
    ----------
    v_body : array_like, shape (3,) or (N, 3)
        Ground velocity in body axes (FRD), m/s.
    beams : array_like, shape (n_beams, 3), optional
        Beam unit vectors (default: the 4-beam Janus array).
    errors : DopplerErrors, optional
        Error budget (default: :class:`DopplerErrors` ()).
    over_water : array_like of bool, shape (N,), optional
        Samples flown over water.
    rng : numpy.random.Generator or int, optional
        Random generator or seed.

    Returns
    -------
    DopplerMeasurement
        Beam velocities, the least-squares velocity and its covariance.

    Raises
    ------
    ShapeError
        If ``v_body`` or ``over_water`` has the wrong shape, or a per-beam bias the wrong length.
    """
    v = _vel(v_body, "v_body")
    v2 = np.atleast_2d(v)
    B = janus_beams() if beams is None else _beams(beams)
    e = DopplerErrors() if errors is None else errors
    gen = np.random.default_rng(rng)
    N = v2.shape[0]
    w = np.zeros(N) if over_water is None else np.asarray(over_water, dtype=np.float64).reshape(-1)
    if w.shape[0] != N:
        raise ShapeError(f"over_water must have {N} flags, got {w.shape[0]}")
    rel = v2 - w[:, None] * np.asarray(e.water_velocity_body, dtype=np.float64)
    scale = 1.0 + e.scale + e.water_scale * w
    bias = np.broadcast_to(np.asarray(e.bias, dtype=np.float64), (B.shape[0],))
    vb = scale[:, None] * (rel @ B.T) + bias + e.noise * gen.standard_normal((N, B.shape[0]))
    vel = velocity_from_beams(vb, B)
    if v.ndim == 1:
        vb, vel = vb[0], vel[0]
    return DopplerMeasurement(vb, vel, velocity_covariance(B, e.noise))


def doppler_additive(v_body: ArrayLike, sigma: float = 0.1, rng: np.random.Generator | int | None = None) -> Array:
    """The thesis's Doppler model (Akgün 2002, eq. 5.10): ``V_D = V + σ·randn`` per body axis.

    Parameters
    ----------
    v_body : array_like, shape (3,) or (N, 3)
        Ground velocity in body axes (FRD), m/s.
    sigma : float
        Noise standard deviation per axis, m/s.
    rng : numpy.random.Generator or int, optional
        Random generator or seed.

    Returns
    -------
    numpy.ndarray
        Noisy body velocity, m/s, shaped like ``v_body``.
    """
    v = _vel(v_body, "v_body")
    return v + sigma * np.random.default_rng(rng).standard_normal(v.shape)
