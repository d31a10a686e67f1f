"""Virtual magnetometer with hard iron, soft iron and white noise.

Measurement model (body frame, field in the user's unit, e.g. uT)::

    h_meas = S h_body + b + n,     h_body = C_nb^T h_ned

* ``b`` (hard iron): constant offset from magnetised material on the board;
* ``S`` (soft iron, 3x3): distortion of the field by soft magnetic material,
  together with the sensor's scale factors and non-orthogonality;
* ``n``: white noise, independent per axis, standard deviation ``noise``
  per sample.

At constant field magnitude |h_ned| the measurements lie on the ellipsoid
|A (h_meas - b)| = |h_ned| with A = S^-1.  Magnetometer calibration
(``imunav.calib.fit_ellipsoid``) recovers the hard iron b and the soft-iron
correction A = S^-1 (up to a rotation, fixed by the attitude reference or by
choosing A symmetric), and corrects with ``h_cal = A (h_meas - b)``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import DegenerateGeometryError, InvalidInputError, NonFiniteError, ShapeError
from imunav.rotation import quat_conjugate, quat_rotate
from imunav.sim.error_model import _mat3, _vec3
from imunav.sim.streams import normals, seed_sequence

__all__ = ["MagnetometerModel", "simulate_magnetometer"]

_MAG_SENSOR = 2  # stream key, see error_model._SENSOR_KEY


@dataclass(frozen=True, eq=False)
class MagnetometerModel:
    """Magnetometer errors (same unit as the field you simulate).

    Parameters
    ----------
    hard_iron : (3,)
        Offset b.
    soft_iron : (3, 3)
        Matrix S (identity: none); must be invertible.
    noise : float or (3,)
        Per-sample white-noise standard deviation, >= 0.
    """

    hard_iron: Any = 0.0
    soft_iron: Any = field(default_factory=lambda: np.eye(3))
    noise: Any = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "hard_iron", _vec3(self.hard_iron, "MagnetometerModel.hard_iron"))
        s = _mat3(self.soft_iron, "MagnetometerModel.soft_iron")
        if abs(np.linalg.det(s)) < 1e-12 * max(1.0, float(np.max(np.abs(s))) ** 3):
            raise DegenerateGeometryError(
                "MagnetometerModel.soft_iron: the matrix is singular; a soft-iron matrix must be invertible "
                "(use the identity for no soft iron)"
            )
        object.__setattr__(self, "soft_iron", s)
        object.__setattr__(self, "noise", _vec3(self.noise, "MagnetometerModel.noise", nonneg=True))

    @property
    def correction(self) -> NDArray[np.float64]:
        """A = S^-1, the matrix a calibration recovers (h_cal = A (h - b))."""
        return np.linalg.inv(self.soft_iron)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary of the model.

        Returns
        -------
        dict
            ``hard_iron``, ``soft_iron``, ``noise`` as lists.
        """
        return {
            "hard_iron": self.hard_iron.tolist(),
            "soft_iron": self.soft_iron.tolist(),
            "noise": self.noise.tolist(),
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> MagnetometerModel:
        """Rebuild a model from :meth:`to_dict`.

        Parameters
        ----------
        d : dict
            ``hard_iron``, ``soft_iron``, ``noise``.

        Returns
        -------
        MagnetometerModel
            The model.
        """
        return cls(**d)


def simulate_magnetometer(
    traj_or_q_nb: Any,
    field_ned: ArrayLike,
    model: MagnetometerModel,
    rng: Any = None,
    *,
    return_truth: bool = False,
) -> NDArray[np.float64] | tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Magnetometer readings along a trajectory.

    Parameters
    ----------
    traj_or_q_nb : Trajectory or array_like, shape (N, 4) or (4,)
        Attitude ``q_nb`` (Hamilton, scalar first, body -> NED), or an object
        with a ``q_nb`` attribute (``imunav.sim.Trajectory``).
    field_ned : (3,) or (N, 3)
        Earth field in NED (any unit; the output has the same unit).
    model : MagnetometerModel
        Hard iron, soft iron and noise of the sensor.
    rng : numpy.random.Generator or int, optional
        Random generator or seed.
    return_truth : bool
        Also return the true body-frame field h_body (N, 3).

    Returns
    -------
    h_meas : numpy.ndarray, shape (N, 3)
        ``S h_body + b + n``, in the unit of ``field_ned``.
    h_body : numpy.ndarray, shape (N, 3)
        The true body-frame field (only with ``return_truth``).

    Raises
    ------
    ShapeError
        If ``q_nb`` is not (N, 4) or ``field_ned`` not (3,) / (N, 3).
    NonFiniteError
        If ``q_nb`` or ``field_ned`` is not finite.
    InvalidInputError
        If ``model`` is not a MagnetometerModel.
    """
    q = getattr(traj_or_q_nb, "q_nb", traj_or_q_nb)
    q = np.asarray(q, dtype=float)
    if q.ndim == 1:
        q = q[None, :]
    if q.ndim != 2 or q.shape[1] != 4:
        raise ShapeError(f"simulate_magnetometer: q_nb must have shape (N, 4), got {q.shape}")
    n = q.shape[0]
    h = np.asarray(field_ned, dtype=float)
    if h.shape == (3,):
        h = np.broadcast_to(h, (n, 3))
    if h.shape != (n, 3):
        raise ShapeError(f"simulate_magnetometer: field_ned must have shape (3,) or ({n}, 3), got {h.shape}")
    if not (np.all(np.isfinite(h)) and np.all(np.isfinite(q))):
        raise NonFiniteError("simulate_magnetometer: field_ned and q_nb must be finite")
    if not isinstance(model, MagnetometerModel):
        raise InvalidInputError(f"simulate_magnetometer: model must be a MagnetometerModel, got {type(model).__name__}")
    h_body = quat_rotate(quat_conjugate(q), np.ascontiguousarray(h))
    out = h_body @ model.soft_iron.T + model.hard_iron
    if np.any(model.noise > 0):
        root = seed_sequence(rng)
        for i in range(3):
            if model.noise[i] > 0:
                out[:, i] += model.noise[i] * normals(root, (_MAG_SENSOR, 0, i, 0), n)
    return (out, h_body) if return_truth else out
