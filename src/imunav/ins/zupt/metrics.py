"""Position-error metrics of pedestrian navigation.

* :func:`error_2d`: the published 2-D error of the Toronto foot dataset
  (pyshoe ``align_plots`` + ``compute_error``).  Both tracks are shifted to
  start at the origin; the estimate is rotated about the vertical so that its
  sample ``i`` points the same way as the reference sample ``i``, where ``i``
  is the first index whose *estimated* horizontal distance from the start at
  index ``i + 1`` reaches ``align_distance`` (0.8 m; ``i = 300`` if never);
  the error is ``mean_k sqrt((dx_k² + dy_k²) / 2)``.
* :func:`loop_closure_error`: distance between the final and the initial
  position (3-D, horizontal, vertical).
* :func:`position_rmse`: RMSE after a least-squares alignment (translation of
  the start, optional yaw rotation).
* :func:`vertical_error`: ``|z_est - z_ref|`` at given samples (stairs).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InsufficientDataError, InvalidInputError, ShapeError
from imunav.results import Result

__all__ = [
    "error_2d",
    "align_heading",
    "LoopClosure",
    "loop_closure_error",
    "position_rmse",
    "vertical_error",
]

Array = NDArray[np.float64]


def _pos(x: ArrayLike, name: str, min_cols: int = 2) -> Array:
    a = np.asarray(x, dtype=float)
    if a.ndim != 2 or a.shape[1] < min_cols or a.shape[1] > 3:
        raise ShapeError(f"{name} must have shape (N, {min_cols}..3); got {a.shape}")
    if a.shape[0] < 2:
        raise InsufficientDataError(f"{name} needs at least 2 samples")
    if not np.all(np.isfinite(a)):
        rows = np.flatnonzero(~np.all(np.isfinite(a), axis=1))
        raise InvalidInputError(f"{name} has non-finite rows {rows[:10].tolist()}")
    return a


def align_heading(estimate: ArrayLike, reference: ArrayLike, align_distance: float = 0.8) -> Array:
    """Estimate shifted to the origin and rotated about z as in :func:`error_2d`.

    Parameters
    ----------
    estimate : array_like, shape (N, 2) or (N, 3)
        Estimated positions, local NED (x, y horizontal), m.
    reference : array_like, shape (N, 2) or (N, 3)
        Reference positions at the same samples, m, frame with the same x-y handedness.
    align_distance : float
        Horizontal distance from the start at which the headings are aligned, m.

    Returns
    -------
    numpy.ndarray
        The aligned estimate, same shape, m.

    Raises
    ------
    ShapeError
        If the two tracks do not have the same number of rows.
    """
    est = _pos(estimate, "estimate")
    ref = _pos(reference, "reference")
    if est.shape[0] != ref.shape[0]:
        raise ShapeError(f"estimate ({est.shape[0]} rows) and reference ({ref.shape[0]} rows) must be "
                         "time-aligned, one row per sample")
    est = est - est[0]
    ref = ref - ref[0]
    d = np.hypot(est[1:, 0], est[1:, 1])
    hit = np.flatnonzero(d >= align_distance)
    i = int(hit[0]) if hit.size else min(300, est.shape[0] - 1)
    a = np.arctan2(ref[i, 1], ref[i, 0]) - np.arctan2(est[i, 1], est[i, 0])
    c, s = np.cos(a), np.sin(a)
    out = est.copy()
    out[:, 0] = c * est[:, 0] - s * est[:, 1]
    out[:, 1] = s * est[:, 0] + c * est[:, 1]
    return out


def error_2d(estimate: ArrayLike, reference: ArrayLike, align_distance: float = 0.8) -> float:
    """Published 2-D error (m) of an estimated track against a time-aligned reference.

    ``mean_k sqrt(((x̂_k - x_k)² + (ŷ_k - y_k)²) / 2)`` after
    :func:`align_heading` (see module docstring).  Both tracks must be
    expressed in frames whose x-y axes have the same handedness (use the
    adapters of :mod:`imunav.io.foot`).

    Parameters
    ----------
    estimate : array_like, shape (N, 2) or (N, 3)
        Estimated positions, local NED (x, y horizontal), m.
    reference : array_like, shape (N, 2) or (N, 3)
        Reference positions at the same samples, m, frame with the same x-y handedness.
    align_distance : float
        Horizontal distance from the start at which the headings are aligned, m.

    Returns
    -------
    float
        The 2-D error, m (Wagstaff, Peretroukhin & Kelly 2020, the pyshoe evaluation).

    Raises
    ------
    ShapeError
        If the two tracks do not have the same number of rows.
    """
    est = align_heading(estimate, reference, align_distance)
    ref = np.asarray(reference, dtype=float)
    ref = ref - ref[0]
    diff = est[:, :2] - ref[:, :2]
    return float(np.mean(np.sqrt(np.mean(diff * diff, axis=1))))


@dataclass(frozen=True)
class LoopClosure(Result):
    """Final-minus-initial position of a closed track.

    Attributes
    ----------
    error_3d : float
        3-D norm of the final-minus-initial position, m.
    horizontal : float
        Its horizontal part, m.
    vertical : float
        Its vertical part, m.
    distance_travelled : float
        Length of the track, m.
    """

    error_3d: float
    horizontal: float
    vertical: float
    distance_travelled: float

    @property
    def percent_of_distance(self) -> float:
        return 100.0 * self.error_3d / self.distance_travelled if self.distance_travelled > 0 else float("nan")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary.

        Returns
        -------
        dict
            The four attributes by name, m.
        """
        return {"error_3d": self.error_3d, "horizontal": self.horizontal, "vertical": self.vertical,
                "distance_travelled": self.distance_travelled}


def loop_closure_error(position: ArrayLike) -> LoopClosure:
    """Loop-closure error of a track that ends where it started.

    Parameters
    ----------
    position : array_like, shape (N, 3)
        Positions, local NED, m.

    Returns
    -------
    LoopClosure
        The final-minus-initial position and the distance travelled.
    """
    p = _pos(position, "position", 3)
    d = p[-1] - p[0]
    travelled = float(np.sum(np.linalg.norm(np.diff(p[:, :2], axis=0), axis=1)))
    return LoopClosure(float(np.linalg.norm(d)), float(np.hypot(d[0], d[1])), float(abs(d[2])), travelled)


def position_rmse(estimate: ArrayLike, reference: ArrayLike, *, align: str = "yaw", dims: int = 2) -> float:
    """Position RMSE after aligning the estimate to the reference.

    ``align``: ``"none"``, ``"start"`` (shift both to start at the origin) or
    ``"yaw"`` (shift, then the least-squares rotation about z, closed form
    ``psi = atan2(sum(x̂ y - ŷ x), sum(x̂ x + ŷ y))``).  ``dims``: 2
    (horizontal) or 3.  RMSE = sqrt(mean_k |e_k|²).

    Parameters
    ----------
    estimate : array_like, shape (N, 2) or (N, 3)
        Estimated positions, local NED (x, y horizontal), m.
    reference : array_like, shape (N, 2) or (N, 3)
        Reference positions at the same samples, m, frame with the same x-y handedness.
    align : {"none", "start", "yaw"}
        Alignment before the comparison (see above).
    dims : {2, 3}
        Horizontal or 3-D error.

    Returns
    -------
    float
        The RMSE, m.

    Raises
    ------
    ShapeError
        If the two tracks do not have the same number of rows.
    InvalidInputError
        If ``align`` or ``dims`` is not one of the values above.
    """
    est = _pos(estimate, "estimate", dims)
    ref = _pos(reference, "reference", dims)
    if est.shape[0] != ref.shape[0]:
        raise ShapeError(f"estimate ({est.shape[0]}) and reference ({ref.shape[0]}) need one row per sample")
    if align not in ("none", "start", "yaw"):
        raise InvalidInputError(f"align must be 'none', 'start' or 'yaw'; got {align!r}")
    if dims not in (2, 3):
        raise InvalidInputError(f"dims must be 2 or 3; got {dims}")
    if align != "none":
        est = est - est[0]
        ref = ref - ref[0]
    if align == "yaw":
        x, y = est[:, 0], est[:, 1]
        psi = np.arctan2(np.sum(x * ref[:, 1] - y * ref[:, 0]), np.sum(x * ref[:, 0] + y * ref[:, 1]))
        c, s = np.cos(psi), np.sin(psi)
        est = est.copy()
        est[:, 0], est[:, 1] = c * x - s * y, s * x + c * y
    e = est[:, :dims] - ref[:, :dims]
    return float(np.sqrt(np.mean(np.sum(e * e, axis=1))))


def vertical_error(estimate: ArrayLike, reference_z: ArrayLike, index: ArrayLike | None = None,
                   *, z_down: bool = True) -> Array:
    """Vertical error ``|h_est - h_ref|`` (m) at ``index`` (default: every sample).

    The estimate is a NED track (``z_down=True``: height = -z) shifted to
    start at zero height; ``reference_z`` are reference heights above the
    start (up positive), one per index.

    Parameters
    ----------
    estimate : array_like, shape (N, 3)
        Estimated positions, m.
    reference_z : array_like
        Reference heights above the start (up positive), m, one per index.
    index : array_like of int, optional
        Samples compared (default: every sample).
    z_down : bool
        The estimate's z axis points down (NED).

    Returns
    -------
    numpy.ndarray
        ``|h_est - h_ref|`` at each index, m.

    Raises
    ------
    ShapeError
        If ``reference_z`` does not have one value per index.
    InvalidInputError
        If an index is out of range.
    """
    est = _pos(estimate, "estimate", 3)
    h = est[:, 2] - est[0, 2]
    if z_down:
        h = -h
    idx = np.arange(est.shape[0]) if index is None else np.asarray(index, dtype=int)
    ref = np.asarray(reference_z, dtype=float)
    if ref.shape != idx.shape:
        raise ShapeError(f"reference_z must have one value per index ({idx.shape}); got {ref.shape}")
    if idx.size and (idx.min() < 0 or idx.max() >= est.shape[0]):
        raise InvalidInputError(f"index out of range 0..{est.shape[0] - 1}")
    return np.abs(h[idx] - ref)
