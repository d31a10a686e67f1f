"""Shared plumbing of the attitude filters (private)."""

from __future__ import annotations

from dataclasses import asdict, fields
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.attitude._kernels import first_rate_over
from imunav.attitude.alignment import align
from imunav.errors import ConvergenceError, InvalidInputError, NonFiniteError, ShapeError
from imunav.timeseries import ImuData

Array = NDArray[np.float64]


def prepare(data: ImuData, use_mag: bool | None) -> tuple[Array, Array, Array, Array, Array, bool]:
    """(t, gyro, accel, mag, dt, use_mag) as contiguous float64 arrays.

    ``dt[k] = t[k] - t[k-1]`` (``dt[0] = t[1] - t[0]``); the mag array is zeros
    when the recording has none.
    """
    if not isinstance(data, ImuData):
        raise InvalidInputError(
            f"data must be an imunav.timeseries.ImuData, got {type(data).__name__}; "
            "build one with ImuData(t, gyro, accel, mag)"
        )
    if data.n < 2:
        raise InvalidInputError("the recording has fewer than 2 samples; attitude filters need a time step")
    t = np.ascontiguousarray(data.t, dtype=np.float64)
    g = np.ascontiguousarray(data.gyro, dtype=np.float64)
    a = np.ascontiguousarray(data.accel, dtype=np.float64)
    has_mag = data.mag is not None
    if use_mag is None:
        use_mag = has_mag
    if use_mag and not has_mag:
        raise InvalidInputError("use_mag=True but the recording has no magnetometer; pass use_mag=False (6D)")
    m = np.ascontiguousarray(data.mag, dtype=np.float64) if has_mag else np.zeros_like(a)
    k, wk = first_rate_over(g, MAX_RATE)
    if k >= 0:
        raise InvalidInputError(
            f"gyro rate |ω| = {wk:.3g} rad/s at sample {k} (t = {t[k]:.6g} s) exceeds {MAX_RATE:g} rad/s, beyond "
            "any gyro; the samples are not in rad/s (give the file's unit) or are corrupt"
        )
    dt = np.empty_like(t)
    dt[1:] = np.diff(t)
    dt[0] = dt[1]
    return t, g, a, m, dt, bool(use_mag)


def check_q0(q0: ArrayLike) -> Array:
    q = np.asarray(q0, dtype=np.float64).reshape(-1)
    if q.shape != (4,):
        raise ShapeError(f"q0 must be a (4,) quaternion [w, x, y, z], got shape {np.shape(q0)}")
    n = np.linalg.norm(q)
    if not np.isfinite(n) or n == 0.0:
        raise NonFiniteError("q0 must be a finite, non-zero quaternion")
    return q / n


def vec3(v: ArrayLike | None, name: str) -> Array:
    if v is None:
        return np.zeros(3)
    a = np.asarray(v, dtype=np.float64).reshape(-1)
    if a.shape != (3,):
        raise ShapeError(f"{name} must be a 3-vector, got shape {np.shape(v)}")
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{name} contains NaN/inf")
    return a


#: largest angular rate accepted, rad/s (about 570 000 °/s: beyond any gyro's range)
MAX_RATE = 1e4


def step_dt(dt: float) -> float:
    """The time step of a ``step()`` call: finite and > 0, else InvalidInputError.

    Policy: a per-sample ``step`` raises on a bad sample rather than skipping it,
    so that a NaN or negative Δt never corrupts every later attitude silently.
    """
    try:
        d = float(dt)
    except (TypeError, ValueError):
        raise InvalidInputError(f"dt must be a number of seconds, got {dt!r}") from None
    if not (np.isfinite(d) and d > 0.0):
        raise InvalidInputError(f"dt must be finite and > 0 s, got {dt}; pass the time since the previous sample")
    return d


def gyro3(gyro: ArrayLike) -> Array:
    """A gyro sample as a finite 3-vector whose norm is at most :data:`MAX_RATE`."""
    g = vec3(gyro, "gyro")
    k, n = first_rate_over(g.reshape(1, 3), MAX_RATE)
    if k >= 0:
        raise InvalidInputError(
            f"gyro rate |ω| = {n:.3g} rad/s exceeds {MAX_RATE:g} rad/s, beyond any gyro; the samples are not in rad/s "
            "(convert deg/s with imunav.units) or are corrupt"
        )
    return g


def check_positive(**kw: float) -> None:
    for k, v in kw.items():
        if not (np.isfinite(v) and v >= 0.0):
            raise InvalidInputError(f"{k} must be a finite number >= 0, got {v}")


def initial_q(acc: Array, mag: Array, use_mag: bool, q0: ArrayLike | None) -> Array:
    if q0 is not None:
        return check_q0(q0)
    return align(acc[0], mag[0] if use_mag else None)


def check_finite_result(name: str, t: Array, q: Array, cov: Array | None, params: dict[str, Any]) -> None:
    """Refuse a run whose numbers overflowed: :class:`ConvergenceError` from the first sample that is not finite.

    A noise, gain or initial σ far outside any sensor's range (a hand-edited ``1e300``) makes the filter's
    arithmetic overflow; its quaternions (or covariance) are then NaN, and a caller would otherwise get them
    silently.  The message names the filter, the sample and its time, and the parameter of largest magnitude (the
    gates, whose ``1e9`` means "off", left aside) as the likely culprit.

    Parameters
    ----------
    name : str
        The filter's name.
    t : numpy.ndarray, shape (N,)
        Time stamps, s.
    q : numpy.ndarray, shape (N, 4)
        The attitude at every sample.
    cov : numpy.ndarray, shape (N, k), or None
        The covariance diagonal at every sample.
    params : dict
        The filter's parameters.

    Raises
    ------
    ConvergenceError
        If ``q`` or ``cov`` holds a value that is not finite.
    """
    if np.isfinite(q.sum()) and (cov is None or np.isfinite(cov.sum())):
        return  # all finite (the sums cost 1 % of the MEKF's run; the per-row test below, 14 %)
    what = "attitude"
    bad = ~np.isfinite(q).all(axis=1)
    if not bad.any() and cov is not None:
        bad = ~np.isfinite(cov).all(axis=1)
        what = "covariance"
    if not bad.any():
        return
    k = int(np.argmax(bad))
    num = {p: float(v) for p, v in params.items()
           if isinstance(v, (int, float)) and not isinstance(v, bool) and "threshold" not in p}
    big = max(num, key=lambda p: abs(num[p]) if np.isfinite(num[p]) else -1.0) if num else None
    hint = f" (largest: {big} = {num[big]:g})" if big is not None else ""
    raise ConvergenceError(
        f"{name} diverged: its {what} is not finite from sample {k} (t = {t[k] - t[0]:.6g} s) on; check its "
        f"parameters{hint}: a noise, gain or initial sigma far outside the sensor's range makes its numbers "
        "overflow; give them in SI units (rad, rad/s, s)")


def params_dict(obj: Any) -> dict[str, Any]:
    """A filter configuration's fields and values (a dataclass's fields; ``asdict`` otherwise), the ``params`` of
    its :class:`~imunav.attitude.result.AttitudeResult`."""
    try:
        return {f.name: getattr(obj, f.name) for f in fields(obj)}
    except TypeError:
        return asdict(obj)


class AttitudeReset:
    """Mixin of the filters whose whole state is the attitude (``Complementary``, ``Madgwick``): their ``reset``."""

    def reset(self, q0: ArrayLike) -> None:
        """Set the attitude the next :meth:`step` starts from.

        Parameters
        ----------
        q0 : array_like, shape (4,)
            Attitude ``q_nb`` [w, x, y, z], body (FRD) to NED (normalised here).

        Raises
        ------
        ShapeError
            If ``q0`` is not a (4,) quaternion.
        NonFiniteError
            If ``q0`` is zero or not finite.
        """
        self.q = check_q0(q0)
