"""Rotation maths: quaternions, direction-cosine matrices, ZYX Euler angles,
rotation vectors.

Conventions (``docs/conventions.md``):

* Quaternions are Hamilton, scalar first ``[w, x, y, z]``.  ``q_nb``
  rotates body vectors into the navigation frame: ``v_n = q ⊗ [0, v_b] ⊗ q*``,
  equivalently ``v_n = C_nb v_b`` with ``C_nb = dcm_from_quat(q_nb)``.
* Euler angles are ZYX: ``C_nb = Rz(yaw) Ry(pitch) Rx(roll)``, returned and
  accepted as ``(roll, pitch, yaw)`` in radians.
* Rotation vectors ``r`` (rad) map to ``q = exp(r) = [cos(|r|/2), sin(|r|/2) r/|r|]``.
* Composition: ``q_ac = q_ab ⊗ q_bc``; attitude propagation with body rates
  ``q_nb(t+dt) = q_nb(t) ⊗ exp(w_b dt)``.

Every function takes a single item (``(4,)``, ``(3,)``, ``(3, 3)``) or a batch
(``(N, 4)``, ``(N, 3)``, ``(N, 3, 3)``) and returns the same kind.  The loops
run in numba kernels (:mod:`imunav._rotation_kernels`), whose scalar forms
(``qmul_1``, ``qrot_1``, ``qexp_1``, ...) other kernels may call directly.

References
----------
J. Solà, "Quaternion kinematics for the error-state Kalman filter",
arXiv:1711.02508, 2017 (Hamilton convention, exp / log maps).
P. D. Groves, *Principles of GNSS, Inertial, and Multisensor Integrated
Navigation Systems*, 2nd ed., Artech House, 2013, §2.2 (DCM, Euler).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav import _rotation_kernels as _k
from imunav.errors import InvalidInputError, NonFiniteError, ShapeError, TimeOrderError

__all__ = [
    "quat_multiply",
    "quat_conjugate",
    "quat_inverse",
    "quat_normalize",
    "quat_canonical",
    "quat_rotate",
    "quat_identity",
    "dcm_from_quat",
    "quat_from_dcm",
    "quat_from_euler",
    "euler_from_quat",
    "dcm_from_euler",
    "euler_from_dcm",
    "quat_from_rotvec",
    "rotvec_from_quat",
    "dcm_from_rotvec",
    "rotvec_from_dcm",
    "quat_exp",
    "quat_log",
    "quat_slerp",
    "quat_interp",
    "quat_angle",
    "quat_error_angle",
    "skew",
    "integrate_rate",
    "C_ENU_NED",
    "Q_ENU_NED",
    "C_FLU_FRD",
    "Q_FRD_FLU",
    "C_NED_NWU",
    "EXTERNAL_CONVENTIONS",
    "to_convention",
    "from_convention",
    "find_convention",
    "ConventionMatch",
]

Array = NDArray[np.float64]


def _as(x: ArrayLike, last: tuple[int, ...], name: str) -> tuple[Array, bool]:
    """Return x as a C-contiguous float64 batch and whether it was a single item."""
    a = np.ascontiguousarray(x, dtype=np.float64)
    k = len(last)
    if a.shape == last:
        return a.reshape((1,) + last), True
    if a.ndim == k + 1 and a.shape[1:] == last:
        return a, False
    raise ShapeError(
        f"{name} must have shape {last} or (N, {', '.join(map(str, last))}); got {a.shape}"
    )


def _finite(a: Array, name: str) -> None:
    if not np.all(np.isfinite(a)):
        bad = np.flatnonzero(~np.all(np.isfinite(a.reshape(a.shape[0], -1)), axis=1))
        raise NonFiniteError(
            f"{name} has non-finite values at rows {bad[:10].tolist()}"
            f"{' ...' if bad.size > 10 else ''}; remove or interpolate them first"
        )


#: How far a quaternion's norm may be from 1 where a rotation (a unit quaternion) is required: far above the
#: drift of a propagated attitude (~1e-12 per step, renormalised), far below any quaternion that is not one.
UNIT_TOL = 1e-3


def _unit(a: Array, name: str) -> Array:
    """``a`` checked to hold rotations: finite unit quaternions (norm within :data:`UNIT_TOL` of 1)."""
    _finite(a, name)
    n = np.sqrt(np.einsum("ij,ij->i", a, a))
    bad = np.flatnonzero(np.abs(n - 1.0) > UNIT_TOL)
    if bad.size:
        raise InvalidInputError(
            f"{name} is not a unit quaternion (a rotation) at rows {bad[:10].tolist()} (norm {n[bad[0]]:.6g}); "
            "give [w, x, y, z] with norm 1, e.g. through quat_normalize (a zero quaternion is no rotation)")
    return a


def _rotation(a: Array, name: str) -> Array:
    """``a`` checked to hold rotation matrices: finite, orthonormal (``C C^T = I`` within :data:`UNIT_TOL`) and
    proper (det +1; a reflection is no rotation)."""
    _finite(a, name)
    err = np.abs(np.einsum("nij,nkj->nik", a, a) - np.eye(3)).max(axis=(1, 2))
    det = np.linalg.det(a)
    bad = np.flatnonzero((err > UNIT_TOL) | (det <= 0))
    if bad.size:
        i = bad[0]
        raise InvalidInputError(
            f"{name} is not a rotation matrix at rows {bad[:10].tolist()} (max |C C^T - I| {err[i]:.3g}, "
            f"det {det[i]:.6g}); give an orthonormal matrix with det +1")
    return a


def _out(a: Array, single: bool) -> Array:
    return a[0] if single else a


def _pairwise(kernel: Callable[[Array, Array], Array], a: ArrayLike, last_a: tuple[int, ...], na: str,
              b: ArrayLike, last_b: tuple[int, ...], nb: str) -> Array:
    """``kernel`` on two batches checked by :func:`_as`, a single one broadcasting; single if both are."""
    aa, sa = _as(a, last_a, na)
    ba, sb = _as(b, last_b, nb)
    if aa.shape[0] != ba.shape[0] and aa.shape[0] != 1 and ba.shape[0] != 1:
        raise ShapeError(f"{na} has {aa.shape[0]} rows and {nb} has {ba.shape[0]}; they must match (or one be single)")
    return _out(kernel(aa, ba), sa and sb)


def quat_identity(n: int | None = None) -> Array:
    """Identity quaternion ``[1, 0, 0, 0]`` (or ``(n, 4)`` of them).

    Parameters
    ----------
    n : int, optional
        Number of quaternions; ``None`` gives a single ``(4,)`` one.

    Returns
    -------
    numpy.ndarray, shape (4,) or (n, 4)
        The identity rotation(s), scalar first.
    """
    q = np.zeros(4 if n is None else (n, 4))
    q[..., 0] = 1.0
    return q


def quat_multiply(p: ArrayLike, q: ArrayLike) -> Array:
    """Hamilton product ``p ⊗ q`` (single or batch; a single one broadcasts).

    ``(p ⊗ q)_w = p_w q_w - p_v · q_v``, ``(p ⊗ q)_v = p_w q_v + q_w p_v + p_v × q_v``; with frames,
    ``q_ac = q_ab ⊗ q_bc`` (Solà 2017).

    Parameters
    ----------
    p, q : array_like, shape (4,) or (N, 4)
        Quaternions ``[w, x, y, z]``; a single one broadcasts against a batch.

    Returns
    -------
    numpy.ndarray, shape (4,) or (N, 4)
        The product, single when both inputs are single.

    Raises
    ------
    ShapeError
        If a shape is not (4,) / (N, 4), or two batches differ in length.
    """
    return _pairwise(_k.qmul_n, p, (4,), "p", q, (4,), "q")


def quat_conjugate(q: ArrayLike) -> Array:
    """Conjugate ``[w, -x, -y, -z]``; the inverse of a unit quaternion.

    Parameters
    ----------
    q : array_like, shape (4,) or (N, 4)
        Quaternion(s) ``[w, x, y, z]`` (Hamilton, scalar first), e.g. ``q_nb`` body (FRD) to navigation (NED).

    Returns
    -------
    numpy.ndarray, shape (4,) or (N, 4)
        ``q*``; for ``q_nb`` this is ``q_bn``.

    Raises
    ------
    ShapeError
        If an input does not have the shape given above.
    """
    a = np.array(q, dtype=float)
    _as(a, (4,), "q")
    a[..., 1:] *= -1.0
    return a


def quat_inverse(q: ArrayLike) -> Array:
    """Inverse ``q* / |q|^2`` (valid for non-unit quaternions).

    Parameters
    ----------
    q : array_like, shape (4,) or (N, 4)
        Quaternion(s) ``[w, x, y, z]`` (Hamilton, scalar first), e.g. ``q_nb`` body (FRD) to navigation (NED).

    Returns
    -------
    numpy.ndarray, shape (4,) or (N, 4)
        ``q^-1`` with ``q ⊗ q^-1 = [1, 0, 0, 0]``.

    Raises
    ------
    NonFiniteError
        If a quaternion is not finite or zero (norm below 1e-12: it has no inverse; the rows are named).
    ShapeError
        If an input does not have the shape given above.
    """
    b, _ = _as(q, (4,), "q")
    _finite(b, "q")
    n2 = np.einsum("ij,ij->i", b, b)
    if np.any(n2 < 1e-24):
        raise NonFiniteError(f"q: a zero quaternion has no inverse (rows {np.flatnonzero(n2 < 1e-24)[:10].tolist()})")
    a = quat_conjugate(q)
    return a / np.sum(a * a, axis=-1, keepdims=True)


def quat_normalize(q: ArrayLike) -> Array:
    """Unit quaternion(s) ``q / |q|``.

    Parameters
    ----------
    q : array_like, shape (4,) or (N, 4)
        Quaternion(s) ``[w, x, y, z]`` (Hamilton, scalar first), e.g. ``q_nb`` body (FRD) to navigation (NED).

    Returns
    -------
    numpy.ndarray, shape (4,) or (N, 4)
        The normalised quaternion(s).

    Raises
    ------
    NonFiniteError
        If a quaternion is not finite or has a norm below 1e-12 (the rows are named).
    ShapeError
        If an input does not have the shape given above.
    """
    a, s = _as(q, (4,), "q")
    _finite(a, "q")
    n = np.linalg.norm(a, axis=1, keepdims=True)
    if np.any(n < 1e-12):
        raise NonFiniteError(f"cannot normalise zero quaternion(s) at rows {np.flatnonzero(n[:, 0] < 1e-12)[:10].tolist()}")
    return _out(a / n, s)


def quat_canonical(q: ArrayLike) -> Array:
    """Representative with ``w > 0`` (at ``w == 0``: first non-zero vector part > 0).

    ``q`` and ``-q`` are the same rotation; this picks one of the two, so that quaternions can be compared
    component by component.

    Parameters
    ----------
    q : array_like, shape (4,) or (N, 4)
        Quaternion(s) ``[w, x, y, z]`` (Hamilton, scalar first), e.g. ``q_nb`` body (FRD) to navigation (NED).

    Returns
    -------
    numpy.ndarray, shape (4,) or (N, 4)
        ``q`` or ``-q``, row by row.

    Raises
    ------
    ShapeError
        If an input does not have the shape given above.
    """
    a, single = _as(q, (4,), "q")
    a = a.copy()
    for i in range(a.shape[0]):
        if _k._needs_flip(a[i, 0], a[i, 1], a[i, 2], a[i, 3]):
            a[i] = -a[i]
    return _out(a, single)


def quat_rotate(q: ArrayLike, v: ArrayLike) -> Array:
    """Rotate vector(s): ``v_n = q ⊗ [0, v_b] ⊗ q*`` (= ``C(q) v_b``).

    For ``q = q_nb`` this maps body-frame vectors to the navigation frame; use
    ``quat_rotate(quat_conjugate(q), v_n)`` for the reverse (Solà 2017).

    Parameters
    ----------
    q : array_like, shape (4,) or (N, 4)
        Quaternion(s) ``[w, x, y, z]`` (Hamilton, scalar first), e.g. ``q_nb`` body (FRD) to navigation (NED).
    v : array_like, shape (3,) or (N, 3)
        Vector(s) in the frame the quaternion rotates from (any unit; the result has the same unit).

    Returns
    -------
    numpy.ndarray, shape (3,) or (N, 3)
        The rotated vector(s); single when both inputs are single.

    Raises
    ------
    InvalidInputError
        If a quaternion is not finite or not a unit quaternion (see :func:`dcm_from_quat`).
    ShapeError
        If a shape is wrong or two batches differ in length.
    """
    _unit(_as(q, (4,), "q")[0], "q")
    return _pairwise(_k.qrot_n, q, (4,), "q", v, (3,), "v")


def dcm_from_quat(q: ArrayLike) -> Array:
    """Direction-cosine matrix ``C_nb`` of a unit quaternion ``q_nb`` (Groves 2013, §2.2).

    Parameters
    ----------
    q : array_like, shape (4,) or (N, 4)
        Quaternion(s) ``[w, x, y, z]`` (Hamilton, scalar first), e.g. ``q_nb`` body (FRD) to navigation (NED).

    Returns
    -------
    numpy.ndarray, shape (3, 3) or (N, 3, 3)
        ``C_nb`` with ``v_n = C_nb v_b``.

    Raises
    ------
    InvalidInputError
        If a quaternion is not finite or not a unit quaternion (norm farther than ``UNIT_TOL`` from 1; the
        rows are named).
    ShapeError
        If an input does not have the shape given above.
    """
    a, s = _as(q, (4,), "q")
    return _out(_k.dcm_from_quat_n(_unit(a, "q")), s)


def quat_from_dcm(C: ArrayLike) -> Array:
    """Unit quaternion (``w >= 0``) of a rotation matrix (Shepperd's method).

    S. W. Shepperd, "Quaternion from rotation matrix", *J. Guidance and Control* 1(3), 1978: the largest of
    ``w², x², y², z²`` is computed first, which keeps the result accurate at every angle.

    Parameters
    ----------
    C : array_like, shape (3, 3) or (N, 3, 3)
        Rotation matrix ``C_nb`` (orthonormal, det +1).

    Returns
    -------
    numpy.ndarray, shape (4,) or (N, 4)
        ``q_nb``, scalar first, with ``w >= 0``.

    Raises
    ------
    InvalidInputError
        If ``C`` is not a rotation matrix (orthonormal within 1e-3, det +1; the rows are named).
    NonFiniteError
        If ``C`` is not finite.
    ShapeError
        If ``C`` is not (3, 3) / (N, 3, 3).
    """
    a, s = _as(C, (3, 3), "C")
    _rotation(a, "C")
    return _out(_k.quat_from_dcm_n(a), s)


def _euler_args(roll: ArrayLike, pitch: ArrayLike | None, yaw: ArrayLike | None) -> tuple[Array, bool]:
    if pitch is None and yaw is None:
        return _as(roll, (3,), "euler (roll, pitch, yaw)")
    if pitch is None or yaw is None:
        raise ShapeError("give either one (…, 3) array of (roll, pitch, yaw) or all three angles")
    r, p, y = np.broadcast_arrays(np.asarray(roll, float), np.asarray(pitch, float), np.asarray(yaw, float))
    single = r.ndim == 0
    e = np.ascontiguousarray(np.stack([np.atleast_1d(r), np.atleast_1d(p), np.atleast_1d(y)], axis=-1))
    return e, single


def quat_from_euler(roll: ArrayLike, pitch: ArrayLike | None = None, yaw: ArrayLike | None = None) -> Array:
    """Quaternion ``q_nb`` of ZYX Euler angles (rad).

    Call as ``quat_from_euler(roll, pitch, yaw)`` or with one ``(…, 3)`` array
    of ``(roll, pitch, yaw)``.  ``q = qz(yaw) ⊗ qy(pitch) ⊗ qx(roll)`` (Groves 2013, §2.2).

    Parameters
    ----------
    roll : array_like
        Roll angle(s), rad, rotation about the body x (forward) axis; or an array of shape (3,) / (N, 3)
        holding ``(roll, pitch, yaw)`` when ``pitch`` and ``yaw`` are omitted.
    pitch : array_like, optional
        Pitch angle(s), rad, about the intermediate y axis.
    yaw : array_like, optional
        Yaw (heading) angle(s), rad, about the navigation down axis.

    Returns
    -------
    numpy.ndarray, shape (4,) or (N, 4)
        ``q_nb``, body (FRD) to navigation (NED).

    Raises
    ------
    NonFiniteError
        If an angle is not finite.
    ShapeError
        If only one of ``pitch`` / ``yaw`` is given, or the shapes do not broadcast.
    """
    e, s = _euler_args(roll, pitch, yaw)
    _finite(e, "euler (roll, pitch, yaw)")
    return _out(_k.quat_from_euler_n(e), s)


def euler_from_dcm(C: ArrayLike) -> Array:
    """ZYX Euler angles ``(roll, pitch, yaw)`` (rad) of ``C_nb`` (Groves 2013, §2.2).

    ``roll = atan2(C32, C33)``, ``pitch = -asin(C31)``, ``yaw = atan2(C21, C11)``; roll, yaw in (-pi, pi],
    pitch in [-pi/2, pi/2].  At gimbal lock roll is set to 0 and yaw carries the rotation about the vertical.

    Parameters
    ----------
    C : array_like, shape (3, 3) or (N, 3, 3)
        Rotation matrix ``C_nb``.

    Returns
    -------
    numpy.ndarray, shape (3,) or (N, 3)
        ``(roll, pitch, yaw)``, rad.

    Raises
    ------
    InvalidInputError
        If ``C`` is not a rotation matrix (orthonormal within 1e-3, det +1; the rows are named).
    NonFiniteError
        If ``C`` is not finite.
    ShapeError
        If ``C`` is not (3, 3) / (N, 3, 3).
    """
    a, s = _as(C, (3, 3), "C")
    _rotation(a, "C")
    return _out(_k.euler_from_dcm_n(a), s)


def euler_from_quat(q: ArrayLike) -> Array:
    """ZYX Euler angles ``(roll, pitch, yaw)`` (rad) of ``q_nb`` (through :func:`euler_from_dcm`).

    Parameters
    ----------
    q : array_like, shape (4,) or (N, 4)
        Quaternion(s) ``[w, x, y, z]`` (Hamilton, scalar first), e.g. ``q_nb`` body (FRD) to navigation (NED).

    Returns
    -------
    numpy.ndarray, shape (3,) or (N, 3)
        ``(roll, pitch, yaw)``, rad; roll, yaw in (-pi, pi], pitch in [-pi/2, pi/2].

    Raises
    ------
    NonFiniteError
        If a quaternion is zero or not finite.
    ShapeError
        If an input does not have the shape given above.
    """
    return euler_from_dcm(dcm_from_quat(quat_normalize(q)))


def dcm_from_euler(roll: ArrayLike, pitch: ArrayLike | None = None, yaw: ArrayLike | None = None) -> Array:
    """``C_nb = Rz(yaw) Ry(pitch) Rx(roll)`` (Groves 2013, §2.2).

    Parameters
    ----------
    roll : array_like
        Roll angle(s), rad; or ``(roll, pitch, yaw)`` as one (3,) / (N, 3) array.
    pitch, yaw : array_like, optional
        Pitch and yaw angle(s), rad.

    Returns
    -------
    numpy.ndarray, shape (3, 3) or (N, 3, 3)
        ``C_nb``, body (FRD) to navigation (NED).

    Raises
    ------
    NonFiniteError
        If an angle is not finite.
    ShapeError
        If only one of ``pitch`` / ``yaw`` is given, or the shapes do not broadcast.
    """
    return dcm_from_quat(quat_from_euler(roll, pitch, yaw))


def quat_from_rotvec(r: ArrayLike) -> Array:
    """``exp`` map: quaternion of rotation vector ``r`` (rad).

    ``q = [cos(|r|/2), sin(|r|/2) r / |r|]`` (Solà 2017; a Taylor series near ``|r| = 0``).

    Parameters
    ----------
    r : array_like, shape (3,) or (N, 3)
        Rotation vector(s), rad: axis times angle.

    Returns
    -------
    numpy.ndarray, shape (4,) or (N, 4)
        Unit quaternion(s).

    Raises
    ------
    NonFiniteError
        If ``r`` is not finite.
    ShapeError
        If ``r`` is not (3,) / (N, 3).
    """
    a, s = _as(r, (3,), "rotation vector")
    _finite(a, "rotation vector")
    return _out(_k.qexp_n(a), s)


def rotvec_from_quat(q: ArrayLike) -> Array:
    """``log`` map: rotation vector (rad, angle in [0, pi]) of unit ``q``.

    ``r = 2 atan2(|q_v|, q_w) q_v / |q_v|`` on the canonical (``w >= 0``) representative (Solà 2017).

    Parameters
    ----------
    q : array_like, shape (4,) or (N, 4)
        Quaternion(s) ``[w, x, y, z]`` (Hamilton, scalar first), e.g. ``q_nb`` body (FRD) to navigation (NED).

    Returns
    -------
    numpy.ndarray, shape (3,) or (N, 3)
        Rotation vector(s), rad, with norm in [0, pi].

    Raises
    ------
    InvalidInputError
        If ``q`` is not a unit quaternion (norm within 1e-3 of 1; the rows are named).
    NonFiniteError
        If ``q`` is not finite.
    ShapeError
        If an input does not have the shape given above.
    """
    a, s = _as(q, (4,), "q")
    _unit(a, "q")
    return _out(_k.qlog_n(a), s)


quat_exp = quat_from_rotvec
quat_log = rotvec_from_quat


def dcm_from_rotvec(r: ArrayLike) -> Array:
    """Rotation matrix of a rotation vector (Rodrigues' formula, ``C = exp([r]x)``).

    Parameters
    ----------
    r : array_like, shape (3,) or (N, 3)
        Rotation vector(s), rad.

    Returns
    -------
    numpy.ndarray, shape (3, 3) or (N, 3, 3)
        The rotation matrix / matrices.

    Raises
    ------
    NonFiniteError
        If ``r`` is not finite.
    ShapeError
        If ``r`` is not (3,) / (N, 3).
    """
    return dcm_from_quat(quat_from_rotvec(r))


def rotvec_from_dcm(C: ArrayLike) -> Array:
    """Rotation vector of a rotation matrix (``log``, through the quaternion).

    Parameters
    ----------
    C : array_like, shape (3, 3) or (N, 3, 3)
        Rotation matrix / matrices.

    Returns
    -------
    numpy.ndarray, shape (3,) or (N, 3)
        Rotation vector(s), rad, norm in [0, pi].

    Raises
    ------
    InvalidInputError
        If ``C`` is not a rotation matrix (orthonormal within 1e-3, det +1; the rows are named).
    NonFiniteError
        If ``C`` is not finite.
    ShapeError
        If ``C`` is not (3, 3) / (N, 3, 3).
    """
    return rotvec_from_quat(quat_from_dcm(C))


def quat_angle(q1: ArrayLike, q2: ArrayLike) -> Array | float:
    """Angle (rad, in [0, pi]) of the rotation between ``q1`` and ``q2``.

    ``angle = 2 atan2(|d_v|, |d_w|)`` with ``d = q1* ⊗ q2``, accurate for small angles, unlike
    ``2 acos(|q1 · q2|)``.

    Parameters
    ----------
    q1, q2 : array_like, shape (4,) or (N, 4)
        Quaternions (normalised here); a single one broadcasts.

    Returns
    -------
    float or numpy.ndarray, shape (N,)
        The angle(s), rad.

    Raises
    ------
    NonFiniteError
        If a quaternion is zero or not finite.
    ShapeError
        If a shape is wrong.
    """
    # 2 atan2(|v|, |w|) of the relative rotation q1* ⊗ q2 is accurate for
    # small angles, unlike 2 acos(|q1·q2|) (error ~ sqrt(eps) ~ 1e-8 rad).
    d = quat_multiply(quat_conjugate(quat_normalize(q1)), quat_normalize(q2))
    out = 2.0 * np.arctan2(np.linalg.norm(d[..., 1:], axis=-1), np.abs(d[..., 0]))
    return float(out) if np.ndim(out) == 0 else out


def quat_error_angle(q_est: ArrayLike, q_ref: ArrayLike) -> Array | float:
    """Alias of :func:`quat_angle` for estimation errors.

    Parameters
    ----------
    q_est : array_like, shape (4,) or (N, 4)
        Estimated attitude ``q_nb``.
    q_ref : array_like, shape (4,) or (N, 4)
        Reference (true) attitude ``q_nb``.

    Returns
    -------
    float or numpy.ndarray, shape (N,)
        Angle of ``q_est* ⊗ q_ref``, rad, in [0, pi].
    """
    return quat_angle(q_est, q_ref)


def quat_slerp(q0: ArrayLike, q1: ArrayLike, s: ArrayLike) -> Array:
    """Spherical linear interpolation ``q0 ⊗ exp(s · log(q0* ⊗ q1))``.

    Takes the short way (``q1`` is flipped when ``q0·q1 < 0``); K. Shoemake, "Animating rotation with
    quaternion curves", SIGGRAPH 1985.

    Parameters
    ----------
    q0, q1 : array_like, shape (4,) or (N, 4)
        End quaternions (normalised here).
    s : array_like
        Fraction(s) in [0, 1] (0 gives ``q0``, 1 gives ``q1``); a scalar or an array broadcasting with the batch.

    Returns
    -------
    numpy.ndarray, shape (4,) or (N, 4)
        The interpolated unit quaternion(s).
    """
    a0 = quat_normalize(q0)
    a1 = quat_normalize(q1)
    d = quat_multiply(quat_conjugate(a0), a1)
    r = rotvec_from_quat(d)  # canonical: short way
    sa = np.asarray(s, dtype=float)
    rs = r * (sa[..., None] if sa.ndim else sa)
    return quat_multiply(a0, quat_from_rotvec(rs))


def quat_interp(t: ArrayLike, q: ArrayLike, t_new: ArrayLike) -> Array:
    """Interpolate an attitude time series by slerp between neighbours (:func:`quat_slerp`).

    Parameters
    ----------
    t : array_like, shape (N,)
        Strictly increasing sample times, s.
    q : array_like, shape (N, 4)
        Attitude at ``t``, scalar first.
    t_new : array_like
        Time(s) at which to interpolate, s, inside ``[t[0], t[-1]]``.

    Returns
    -------
    numpy.ndarray, shape (4,) or (M, 4)
        Attitude at ``t_new`` (a single quaternion for a scalar ``t_new``).

    Raises
    ------
    ShapeError
        If ``t`` is not 1-D with one entry per quaternion.
    TimeOrderError
        If ``t`` has fewer than two entries or is not strictly increasing.
    InvalidInputError
        If ``t_new`` leaves ``[t[0], t[-1]]`` (no extrapolation).
    """

    ta = np.asarray(t, dtype=float)
    qa, _ = _as(q, (4,), "q")
    tn = np.atleast_1d(np.asarray(t_new, dtype=float))
    if ta.ndim != 1 or ta.shape[0] != qa.shape[0]:
        raise ShapeError(f"t must be 1-D with one entry per quaternion; got {ta.shape} and {qa.shape}")
    if ta.size < 2 or np.any(np.diff(ta) <= 0):
        raise TimeOrderError("t must have at least two strictly increasing entries")
    if tn.min() < ta[0] or tn.max() > ta[-1]:
        raise InvalidInputError(
            f"t_new spans [{tn.min()}, {tn.max()}] outside the data [{ta[0]}, {ta[-1]}]; extrapolation is not done"
        )
    i = np.clip(np.searchsorted(ta, tn, side="right") - 1, 0, ta.size - 2)
    s = (tn - ta[i]) / (ta[i + 1] - ta[i])
    out = quat_slerp(qa[i], qa[i + 1], s)
    return out[0] if np.ndim(t_new) == 0 else out


def skew(v: ArrayLike) -> Array:
    """Cross-product matrix ``[v]x`` with ``[v]x u = v x u`` (single or batch).

    ``[v]x = [[0, -v3, v2], [v3, 0, -v1], [-v2, v1, 0]]`` (Groves 2013, §2.2).

    Parameters
    ----------
    v : array_like, shape (3,) or (N, 3)
        Vector(s).

    Returns
    -------
    numpy.ndarray, shape (3, 3) or (N, 3, 3)
        The skew-symmetric matrix / matrices.

    Raises
    ------
    ShapeError
        If ``v`` is not (3,) / (N, 3).
    """
    a, s = _as(v, (3,), "v")
    S = np.zeros((a.shape[0], 3, 3))
    S[:, 0, 1], S[:, 0, 2] = -a[:, 2], a[:, 1]
    S[:, 1, 0], S[:, 1, 2] = a[:, 2], -a[:, 0]
    S[:, 2, 0], S[:, 2, 1] = -a[:, 1], a[:, 0]
    return _out(S, s)


def integrate_rate(
    q0: ArrayLike, t: ArrayLike, gyro: ArrayLike, *, method: str = "zoh"
) -> Array:
    """Integrate body angular rates to attitude ``q_nb`` at every sample.

    ``q_{k+1} = q_k ⊗ exp(phi_k)`` with, for ``method="zoh"``,
    ``phi_k = w_k (t_{k+1} - t_k)`` (exact for a rate held constant over each
    step), or for ``method="trapezoid"`` the mean rate plus the second-order
    coning term ``(w_k × w_{k+1}) dt² / 12`` (P. G. Savage, "Strapdown inertial navigation integration
    algorithm design, part 1: attitude algorithms", *J. Guidance, Control, and Dynamics* 21(1), 1998).
    The Earth's rate is not removed: ``gyro`` is taken as the rate relative to the navigation frame.

    Parameters
    ----------
    q0 : array_like, shape (4,)
        Initial attitude ``q_nb`` at ``t[0]``.
    t : array_like, shape (N,)
        Strictly increasing time, s.
    gyro : array_like, shape (N, 3)
        Body (FRD) angular rates, rad/s.
    method : {"zoh", "trapezoid"}
        Integration rule (see above).

    Returns
    -------
    numpy.ndarray, shape (N, 4)
        Attitude ``q_nb`` at each ``t``.

    Raises
    ------
    ShapeError
        If ``t`` and ``gyro`` differ in length or ``gyro`` is not (N, 3).
    NonFiniteError
        If ``gyro`` is not finite.
    TimeOrderError
        If ``t`` is not strictly increasing.
    InvalidInputError
        If ``method`` is unknown.
    """

    ta = np.ascontiguousarray(t, dtype=float)
    w, _ = _as(gyro, (3,), "gyro")
    if ta.ndim != 1 or ta.shape[0] != w.shape[0]:
        raise ShapeError(f"t {ta.shape} and gyro {w.shape} must have the same number of rows")
    _finite(w, "gyro")
    dt = np.diff(ta)
    if np.any(dt <= 0):
        raise TimeOrderError(f"t is not strictly increasing at rows {np.flatnonzero(dt <= 0)[:10].tolist()}")
    m = {"zoh": 0, "trapezoid": 1}.get(method)
    if m is None:
        raise InvalidInputError(f"method must be 'zoh' or 'trapezoid', not {method!r}")
    return _k.integrate_rate_kernel(quat_normalize(q0), w, dt, m)


# ---- frame-convention constants -------------------------------------------
#: ``v_enu = C_ENU_NED @ v_ned`` (swap north/east, negate down).
C_ENU_NED = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
#: quaternion of ``C_ENU_NED``: a rotation of pi about (1, 1, 0)/sqrt(2), written out (the value
#: ``quat_from_dcm(C_ENU_NED)`` gives, bit for bit; tests/test_rotation.py checks it) so that importing this
#: module runs no numba kernel.
Q_ENU_NED = np.array([0.0, 0.7071067811865476, 0.7071067811865475, 0.0])
#: ``v_flu = C_FLU_FRD @ v_frd`` (forward-left-up from forward-right-down).
C_FLU_FRD = np.diag([1.0, -1.0, -1.0])
#: quaternion ``q_frd_flu`` (rotation of pi about x; its own inverse up to sign), written out as above.
Q_FRD_FLU = np.array([0.0, 1.0, 0.0, 0.0])


# ---- converters to other conventions ----------------------------------------
#: ``v_ned = C_NED_NWU @ v_nwu`` (north-west-up, used by the ``ahrs`` package).
C_NED_NWU = np.diag([1.0, -1.0, -1.0])

#: Known external conventions: name -> (C_ned_ext nav-frame change, scalar_last).
#: All of them express body (sensor) -> navigation quaternions; what differs is
#: the navigation frame and the component order.
EXTERNAL_CONVENTIONS: dict[str, tuple[np.ndarray, bool]] = {
    "ned": (np.eye(3), False),  # imunav itself
    "enu": (C_ENU_NED.T, False),  # q_enu_b, scalar first
    "broad": (C_ENU_NED.T, False),  # BROAD opt_quat: sensor -> ENU, scalar first (Laidig et al. 2021)
    "vqf": (C_ENU_NED.T, False),  # vqf quat6D / quat9D: sensor -> ENU, scalar first
    # ahrs package: sensor -> NWU, scalar first, for Madgwick, Mahony without magnetometer, ...; but ahrs's
    # Mahony WITH a magnetometer references north on its y axis: use "enu" for it (tests/attitude/test_ahrs_peer.py)
    "ahrs": (C_NED_NWU, False),
    "scipy": (np.eye(3), True),  # scipy Rotation.as_quat(): [x, y, z, w], same frames
}


def _conv(name: str) -> tuple[Array, bool]:
    key = name.lower()
    if key not in EXTERNAL_CONVENTIONS:
        raise InvalidInputError(f"unknown convention {name!r}; known: {sorted(EXTERNAL_CONVENTIONS)}")
    return EXTERNAL_CONVENTIONS[key]


def to_convention(q_nb: ArrayLike, convention: str, *, body: str = "same") -> Array:
    """Express imunav quaternions ``q_nb`` (NED, scalar first) in another convention.

    ``q_ext = q_ext_ned ⊗ q_nb [⊗ q_frd_flu]`` reordered as the convention
    wants.  ``body="flu"`` also re-expresses the body frame from FRD to FLU
    (for estimators whose sensor frame is forward-left-up); the default keeps
    the sensor axes as they are.

    Parameters
    ----------
    q_nb : array_like, shape (4,) or (N, 4)
        imunav attitude, body to NED, scalar first.
    convention : str
        A key of :data:`EXTERNAL_CONVENTIONS` (``"ned"``, ``"enu"``, ``"broad"``, ``"vqf"``, ``"ahrs"``,
        ``"scipy"``), case-insensitive.
    body : {"same", "flu"}
        Keep the sensor axes, or re-express them from FRD to FLU.

    Returns
    -------
    numpy.ndarray, shape (4,) or (N, 4)
        The quaternion(s) in the external convention (canonical sign; ``[x, y, z, w]`` for scalar-last
        conventions).

    Raises
    ------
    InvalidInputError
        If the convention or ``body`` is unknown.
    """
    C, scalar_last = _conv(convention)
    q = quat_multiply(quat_from_dcm(C.T), q_nb)
    if body == "flu":
        q = quat_multiply(q, Q_FRD_FLU)
    elif body != "same":
        raise InvalidInputError(f"body must be 'same' or 'flu', not {body!r}")
    q = quat_canonical(q)
    return q[..., [1, 2, 3, 0]] if scalar_last else q


def from_convention(q_ext: ArrayLike, convention: str, *, body: str = "same") -> Array:
    """Inverse of :func:`to_convention`: external quaternions to imunav ``q_nb``.

    Parameters
    ----------
    q_ext : array_like, shape (4,) or (N, 4)
        Quaternion(s) in the external convention.
    convention : str
        A key of :data:`EXTERNAL_CONVENTIONS`, case-insensitive.
    body : {"same", "flu"}
        ``"flu"`` when the external sensor frame is forward-left-up (re-expressed as FRD).

    Returns
    -------
    numpy.ndarray, shape (4,) or (N, 4)
        ``q_nb``, body to NED, scalar first.

    Raises
    ------
    InvalidInputError
        If the convention or ``body`` is unknown.

    Examples
    --------
    A BROAD / vqf quaternion (sensor -> ENU) becomes sensor -> NED with
    ``from_convention(q, "vqf")``; an ``ahrs`` quaternion (sensor -> NWU) with
    ``from_convention(q, "ahrs")``.
    """
    C, scalar_last = _conv(convention)
    q = np.asarray(q_ext, dtype=float)
    if scalar_last:
        q = q[..., [3, 0, 1, 2]]
    q = quat_multiply(quat_from_dcm(C), quat_normalize(q))
    if body == "flu":
        q = quat_multiply(q, quat_conjugate(Q_FRD_FLU))
    elif body != "same":
        raise InvalidInputError(f"body must be 'same' or 'flu', not {body!r}")
    return q


def _axis_rotations() -> list[Array]:
    out = []
    for p in itertools.permutations(range(3)):
        for s in itertools.product((1.0, -1.0), repeat=3):
            M = np.zeros((3, 3))
            for i in range(3):
                M[i, p[i]] = s[i]
            if np.linalg.det(M) > 0:
                out.append(M)
    return out


@dataclass(frozen=True)
class ConventionMatch:
    """Result of :func:`find_convention`: ``q_ref ≈ L ⊗ f(q_ext) ⊗ B``.

    Attributes
    ----------
    nav_dcm : numpy.ndarray, shape (3, 3)
        DCM of L (reference navigation frame from external navigation frame).
    body_dcm : numpy.ndarray, shape (3, 3)
        DCM of B (external body frame from reference body frame).
    scalar_last : bool
        Whether the external quaternions are ``[x, y, z, w]``.
    conjugate : bool
        Whether the external quaternions are conjugated (navigation to body).
    median_error_rad : float
        Median angle between ``q_ref`` and the converted ``q_ext`` over the compared samples, rad.
    """

    nav_dcm: Array
    body_dcm: Array
    scalar_last: bool
    conjugate: bool
    median_error_rad: float

    def apply(self, q_ext: ArrayLike) -> Array:
        """Convert external quaternions to the reference convention, ``L ⊗ f(q_ext) ⊗ B``.

        Parameters
        ----------
        q_ext : array_like, shape (4,) or (N, 4)
            Quaternion(s) in the convention that was found.

        Returns
        -------
        numpy.ndarray, shape (4,) or (N, 4)
            The same attitudes in the reference (imunav) convention.
        """
        q = np.asarray(q_ext, dtype=float)
        if self.scalar_last:
            q = q[..., [3, 0, 1, 2]]
        q = quat_normalize(q)
        if self.conjugate:
            q = quat_conjugate(q)
        return quat_multiply(quat_multiply(quat_from_dcm(self.nav_dcm), q), quat_from_dcm(self.body_dcm))

    def to_dict(self) -> dict:
        """The match as plain JSON types.

        Returns
        -------
        dict
            ``nav_dcm``, ``body_dcm`` (nested lists), ``scalar_last``, ``conjugate``, ``median_error_rad`` (rad).
        """
        return {
            "nav_dcm": self.nav_dcm.tolist(),
            "body_dcm": self.body_dcm.tolist(),
            "scalar_last": self.scalar_last,
            "conjugate": self.conjugate,
            "median_error_rad": self.median_error_rad,
        }


def find_convention(q_ext: ArrayLike, q_ref: ArrayLike, *, max_samples: int = 200) -> ConventionMatch:
    """Find the convention of an external attitude estimate by comparing it with a reference.

    Searches the component order (scalar first / last), conjugation, and the
    24 axis-aligned frame changes on each side, ``q_ref ≈ L ⊗ f(q_ext) ⊗ B``,
    and returns the combination with the smallest median angle error over up
    to ``max_samples`` evenly spaced samples.  Among fits within 5 % of the best, the simplest is reported.

    Parameters
    ----------
    q_ext : array_like, shape (N, 4)
        External attitude estimates, in an unknown convention.
    q_ref : array_like, shape (N, 4)
        Reference attitude in imunav's convention (e.g. a simulated truth), same samples as ``q_ext``.
    max_samples : int
        Number of evenly spaced samples compared.

    Returns
    -------
    ConventionMatch
        The frame changes, order and conjugation found, with the median error.

    Raises
    ------
    ShapeError
        If the two arrays are not both (N, 4) with the same N.
    """
    qe = np.asarray(q_ext, dtype=float)
    qr = quat_normalize(q_ref)
    if qe.ndim != 2 or qe.shape != qr.shape:
        raise ShapeError(f"q_ext {qe.shape} and q_ref {qr.shape} must both be (N, 4) with the same N")
    idx = np.linspace(0, qe.shape[0] - 1, min(max_samples, qe.shape[0])).astype(int)
    qe, qr = qe[idx], qr[idx]
    rots = _axis_rotations()
    qrots = [quat_from_dcm(M) for M in rots]
    cands: list[tuple[float, int, int, bool, bool]] = []
    for scalar_last in (False, True):
        qa = quat_normalize(qe[:, [3, 0, 1, 2]] if scalar_last else qe)
        for conj in (False, True):
            qb = quat_conjugate(qa) if conj else qa
            for i, L in enumerate(qrots):
                lq = quat_multiply(L, qb)
                # best right factor in closed form: B ≈ (L q)^-1 ⊗ q_ref, then snap to the nearest axis rotation
                d = quat_multiply(quat_conjugate(lq), qr)
                d = d * np.where(d[:, :1] < 0, -1.0, 1.0)
                Bm = dcm_from_quat(quat_normalize(np.mean(d, axis=0)))
                j = int(np.argmax([np.trace(M.T @ Bm) for M in rots]))
                err = float(np.median(quat_angle(quat_multiply(lq, qrots[j]), qr)))
                cands.append((err, i, j, scalar_last, conj))
    # Component permutations of a quaternion equal products with constant unit
    # quaternions on both sides, so several descriptions fit equally well;
    # among those within 5 % of the best, report the simplest one.
    e_min = min(c[0] for c in cands)
    ident = int(np.argmax([np.trace(M) for M in rots]))
    ok = [c for c in cands if c[0] <= 1.05 * e_min + 1e-12]
    best = min(ok, key=lambda c: (c[3], c[4], c[2] != ident, c[1] != ident, c[0]))
    return ConventionMatch(rots[best[1]], rots[best[2]], best[3], best[4], best[0])
