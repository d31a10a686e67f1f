"""Is a recording static?  The gate in front of noise identification.

Allan-variance noise identification assumes the sensor did not move: a pose
change or a rotation shows up as a huge "random walk" or "rate ramp" (the
issue behind this module: a multi-position test read as ARW 320 °/√h).
:func:`check_static` judges a recording from two things:

1. **The mean specific force** must be about g: ``g/4 ≤ |f̄| ≤ 2 g`` (at rest
   in one pose the accelerometer reads gravity; 1 m/s² means the file is in g,
   0 no accelerometer data, 9807 mg).  The band is wide because uncalibrated
   accelerometers have large biases: the thesis's real unit (preset
   ``thesis_real``) has ``|b| = 6.0 m/s²``, so at rest it reads between 3.8 and
   15.8 m/s² depending on the pose.  A multi-position test averages gravity
   over poses; the window test below catches it.
2. **Window means** of the specific force and of the angular rate, over
   non-overlapping windows of ``window_s`` (1 s), must not move away from their
   median.  This is the Allan deviation at ``τ = window_s`` seen one window at
   a time: for white noise of the per-sample standard deviation ``σ0`` (the
   short-τ Allan deviation, estimated robustly from first differences) each
   window mean differs from the median by ``d`` with ``|d|² / s² ~ χ²₃``,
   ``s = σ0 √(1/w + π/(2 K w))`` (``w`` samples per window, ``K`` windows; the
   second term is the median's own spread).  A window is flagged when ``|d|``
   exceeds *both*

   * the χ²₃ quantile at a false-alarm probability ``alpha / K`` per window
     (Bonferroni: at most ``alpha`` = 1e-6 per record and sensor under white
     noise), and
   * a physical allowance for the slow bias drift a resting sensor shows and a
     white-noise model does not include (bias instability, random walk,
     warm-up): a change of the specific force by more than ``max_tilt_deg``
     (2°, i.e. 0.34 m/s²) of tilt, or a rotation by more than
     ``max_rotation_deg`` (2°) within one window.

   A multi-position test changes the specific force by tens of degrees and
   rotates by tens of degrees per second; a rate table turns at degrees per
   second: both are refused.  A resting sensor's drift is orders of magnitude
   below the allowances (a consumer MEMS accelerometer drifts a few mg over its
   warm-up, 0.2° of tilt; a gyro a few 0.01 °/s).

The Allan slope between ``τ0`` and ``window_s`` is reported for each sensor
(−1/2 for white noise; near 0 or positive when the window means wander).

Not detected: a rotation at one constant rate about the vertical for the whole
record (indistinguishable from a gyro bias).  The command line and
:func:`imunav.lab.batch.noise_unit` call :func:`require_static`, which raises
:class:`~imunav.errors.NotStaticError` unless ``force=True``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from imunav._quantiles import chi2_isf
from imunav.errors import InvalidInputError, NotStaticError
from imunav.files import jsonable
from imunav.results import Result
from imunav.timeseries import G_REF, ImuData, rest_force_problem

__all__ = ["StaticCheck", "check_static", "require_static", "rest_force_problem", "G_REF"]

@dataclass(frozen=True)
class StaticCheck(Result):
    """Outcome of :func:`check_static`.

    Attributes
    ----------
    static : bool
        No test failed.
    reasons : list of str
        One sentence per failed test (empty when static).
    mean_specific_force : float
        ``|f̄|``, m/s² (norm of the median window mean).
    max_tilt_deg : float
        Largest change of a window's mean specific force from the median, as an angle
        (``|d| / |f̄|`` in degrees).
    max_rotation_deg : float
        Largest ``|ω̄_k − median| · window`` (degrees turned within a window beyond the bias).
    tilt_limit_deg, rotation_limit_deg : float
        The thresholds applied (the larger of the statistical and physical ones).
    allan_slope : dict
        Per sensor, the largest slope of the Allan deviation between ``τ0`` and ``window_s``
        over the axes (−0.5 for white noise).
    window_s : float
        Window length used, s.
    n_windows : int
        Number of windows (no window test with fewer than 2).
    flagged_windows : dict
        Per sensor, start times (s) of the first flagged windows.
    """

    static: bool
    reasons: list[str]
    mean_specific_force: float
    max_tilt_deg: float
    max_rotation_deg: float
    tilt_limit_deg: float
    rotation_limit_deg: float
    allan_slope: dict[str, float]
    window_s: float
    n_windows: int
    flagged_windows: dict[str, list[float]] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary of the outcome.

        Returns
        -------
        dict
            Every attribute under its own name (angles in degrees, force in m/s², window in s).
        """
        return jsonable(self.__dict__)


def _sigma0(x: np.ndarray) -> np.ndarray:
    """Per-axis white-noise standard deviation from first differences (robust to the few large jumps of motion).

    ``Δx = x[i+1] − x[i]`` has standard deviation ``σ0 √2`` for white noise; the MAD gives it with 50 %
    breakdown.  Quantised data (median |Δx| = 0) fall back to the RMS difference.
    """
    dx = np.diff(x, axis=0)
    mad = 1.4826 * np.median(np.abs(dx - np.median(dx, axis=0)), axis=0)
    rms = np.sqrt(np.mean(dx**2, axis=0))
    return np.where(mad > 0, mad, rms) / math.sqrt(2.0)


def _window_test(x: np.ndarray, w: int, k: int, alpha: float) -> tuple[np.ndarray, float, float]:
    """Distances of the window means from their median, the statistical limit on them, and the Allan slope."""

    means = x[: k * w].reshape(k, w, 3).mean(axis=1)
    d = np.linalg.norm(means - np.median(means, axis=0), axis=1)
    s0 = _sigma0(x)
    s = float(s0.max()) * math.sqrt(1.0 / w + math.pi / (2.0 * k * w))
    limit = s * math.sqrt(float(chi2_isf(alpha / k, 3)))
    # Allan deviation at tau0 (sigma0) and at the window (non-overlapping window means): slope in log-log
    adev_w = np.sqrt(0.5 * np.mean(np.diff(means, axis=0) ** 2, axis=0))
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = np.log(adev_w / s0) / math.log(w)
    slope = slope[np.isfinite(slope)]
    return d, limit, float(slope.max()) if slope.size else float("nan")


def check_static(data: Any, *, window_s: float = 1.0, max_tilt_deg: float = 2.0, max_rotation_deg: float = 2.0,
                 alpha: float = 1e-6, gravity: float = G_REF, mean_force: bool = True) -> StaticCheck:
    """Judge whether a recording is static (one pose, no rotation); see the module docstring.

    Parameters
    ----------
    data : ImuData
        The recording, SI units.
    window_s : float
        Window length, s (at least 10 samples are used).
    max_tilt_deg : float
        Physical allowance on the change of the mean specific force, degrees of tilt.
    max_rotation_deg : float
        Physical allowance on the rotation within one window beyond the gyro bias, degrees.
    alpha : float
        False-alarm probability per record and sensor under white noise (statistical limit).
    gravity : float
        Expected ``|f̄|`` at rest, m/s².
    mean_force : bool
        Apply the mean-specific-force test (False when only the gyro is analysed and the
        accelerometer's unit may be undeclared; the window tests still run).

    Returns
    -------
    StaticCheck
        The verdict, the reasons and the figures of each test.

    Raises
    ------
    InvalidInputError
        If ``data`` is not an ImuData with at least 3 samples, a window or allowance is not positive, or
        ``alpha`` is outside (0, 1).
    """
    if not isinstance(data, ImuData):
        raise InvalidInputError(f"check_static needs an ImuData, got {type(data).__name__}")
    for name, v in (("window_s", window_s), ("max_tilt_deg", max_tilt_deg), ("max_rotation_deg", max_rotation_deg),
                    ("gravity", gravity)):
        if not (np.isfinite(v) and v > 0):
            raise InvalidInputError(f"check_static: {name} must be positive and finite, got {v!r}")
    if not 0.0 < alpha < 1.0:
        raise InvalidInputError(f"check_static: alpha must be a probability in (0, 1), got {alpha!r}")
    if data.n < 3:
        raise InvalidInputError(f"check_static: {data.n} samples are too few to judge a recording")
    fs = data.fs
    w = max(int(round(window_s * fs)), 10)
    k = data.n // w
    reasons: list[str] = []
    flagged: dict[str, list[float]] = {}
    slopes: dict[str, float] = {}
    if k >= 2:
        fbar = np.median(data.accel[: k * w].reshape(k, w, 3).mean(axis=1), axis=0)
    else:
        fbar = np.median(data.accel, axis=0)
    fmag = float(np.linalg.norm(fbar))
    problem = rest_force_problem(fmag, gravity) if mean_force else None
    if problem:
        reasons.append(problem)
    tilt = rot = 0.0
    tilt_lim = max_tilt_deg
    rot_lim = max_rotation_deg
    tw = w / fs
    if k >= 2:
        da, lim_a, slopes["accel"] = _window_test(data.accel, w, k, alpha)
        dg, lim_g, slopes["gyro"] = _window_test(data.gyro, w, k, alpha)
        ref = gravity  # tilt of a change d of the specific force at rest: |d| / g
        tilt = math.degrees(float(da.max()) / ref)
        rot = math.degrees(float(dg.max()) * tw)
        tilt_lim = max(max_tilt_deg, math.degrees(lim_a / ref))
        rot_lim = max(max_rotation_deg, math.degrees(lim_g * tw))
        bad_a = np.flatnonzero(np.degrees(da / ref) > tilt_lim)
        bad_g = np.flatnonzero(np.degrees(dg * tw) > rot_lim)
        if bad_a.size:
            flagged["accel"] = (data.t[0] + bad_a[:5] * tw).tolist()
            reasons.append(
                f"the mean specific force changes by up to {tilt:.3g} deg of tilt between {tw:g} s windows "
                f"({bad_a.size} of {k} windows beyond {tilt_lim:.2g} deg, first at t = {flagged['accel'][0]:.6g} s; "
                f"accel Allan slope up to {tw:g} s: {slopes['accel']:+.2f}, white noise -0.50): the sensor changed pose"
            )
        if bad_g.size:
            flagged["gyro"] = (data.t[0] + bad_g[:5] * tw).tolist()
            reasons.append(
                f"the sensor turns by up to {rot:.3g} deg within a {tw:g} s window beyond its bias "
                f"({bad_g.size} of {k} windows beyond {rot_lim:.2g} deg, first at t = {flagged['gyro'][0]:.6g} s; "
                f"gyro Allan slope up to {tw:g} s: {slopes['gyro']:+.2f}, white noise -0.50): the sensor rotated"
            )
    return StaticCheck(static=not reasons, reasons=reasons, mean_specific_force=fmag, max_tilt_deg=tilt,
                       max_rotation_deg=rot, tilt_limit_deg=tilt_lim, rotation_limit_deg=rot_lim, allan_slope=slopes,
                       window_s=tw, n_windows=k, flagged_windows=flagged)


def require_static(data: Any, *, force: bool = False, where: str = "the recording", **kwargs: Any) -> StaticCheck:
    """:func:`check_static`, raising :class:`~imunav.errors.NotStaticError` when the data moved, unless ``force``.

    Parameters
    ----------
    data : ImuData
        The recording, in SI units.
    force : bool
        Return the outcome instead of raising when the recording is not static.
    where : str
        Names the recording in the message.
    **kwargs
        Keywords of :func:`check_static` (``window_s``, ``max_tilt_deg``, ...).

    Returns
    -------
    StaticCheck
        The verdict, the reasons and the figures of each test.
        The outcome of the tests.

    Raises
    ------
    NotStaticError
        If a test failed and ``force`` is False; the message gives the reasons and the ways out.
    """
    res = check_static(data, **kwargs)
    if not res.static and not force:
        raise NotStaticError(
            f"{where} is not static, and noise identification needs a recording at rest in one pose: "
            + "; ".join(res.reasons)
            + ". Record the sensor at rest, cut the static part (ImuData.window; command line: --start / --end), "
            "or pass force=True (command line: --force) to analyse it anyway"
        )
    return res
