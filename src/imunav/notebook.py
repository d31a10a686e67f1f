"""The entry points of a notebook: read a recording, its noise, a calibration, attitude, GNSS/INS from a log.

``import imunav`` gives these five functions (``imunav.read``, ``imunav.analyse_noise``, ``imunav.calibrate``,
``imunav.estimate_attitude``, ``imunav.navigate``; the package loads this module on first use).  Each calls the
library function a command calls and returns the library's result wrapped with two methods: ``summary()`` (a
dict of the figures the command prints, plain JSON types) and ``plot()`` (the command's figure, a matplotlib
``Figure``).  The library's own result is the wrapper's first field, for everything else.

>>> import imunav
>>> rec = imunav.read("flight.ulg")                               # doctest: +SKIP
>>> imunav.estimate_attitude(rec, "mekf").summary()               # doctest: +SKIP
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from imunav import calib
from imunav.attitude import plot as attitude_plot
from imunav.attitude.benchmark import make_filter
from imunav.attitude.result import AttitudeResult
from imunav.calib import plot as calib_plot
from imunav.calib.result import CalibrationResult
from imunav.errors import InvalidInputError
from imunav.files import jsonable
from imunav.ins.gins import plot as gins_plot
from imunav.ins.gins.logrun import LogRun, LogRunOptions, run_log
from imunav.ins.gins.outputs import log_summary
from imunav.io import read_imu
from imunav.io.navlog import NavSources, read_nav_sources
from imunav.noise import allan_deviation, fit_noise
from imunav.noise import plot as noise_plot
from imunav.noise.allan import AllanResult
from imunav.noise.fit import NoiseFit
from imunav.noise.static import require_static
from imunav.sim import plot as sim_plot
from imunav.timeseries import ImuData, describe

__all__ = ["Recording", "NoiseAnalysis", "Calibration", "AttitudeEstimate", "Navigation", "read", "analyse_noise",
           "calibrate", "estimate_attitude", "navigate"]


@dataclass(frozen=True)
class Recording:
    """A recording read by :func:`read`.

    Attributes
    ----------
    data : ImuData
        The samples in SI units, body FRD axes.
    path : str
        The file it was read from.
    """

    data: ImuData
    path: str

    def summary(self) -> dict[str, Any]:
        """What ``imunav info`` prints: samples, duration, rate, gaps, static intervals, channel statistics.

        Returns
        -------
        dict
            ``n``, ``duration_s``, ``fs_hz``, ``gaps``, ``static_s`` (total time at rest) and ``channels`` (one
            row per channel in display units).
        """
        s = describe(self.data)
        return jsonable({"path": self.path, "n": s.n, "duration_s": s.duration_s, "fs_hz": s.fs_hz,
                         "gaps": len(s.gaps), "static_s": float(np.sum(s.static.t_stop - s.static.t_start)),
                         "channels": s.channels})

    def plot(self) -> Any:
        """Accelerometer (g) and gyro (°/s) against time (:func:`imunav.sim.plot.plot_test_recording`).

        Returns
        -------
        matplotlib.figure.Figure
            The figure.
        """
        return sim_plot.plot_test_recording(self.data, title=os.path.basename(self.path))


@dataclass(frozen=True)
class NoiseAnalysis:
    """The noise of a static recording, per sensor (:func:`analyse_noise`).

    Attributes
    ----------
    fits : dict of str to NoiseFit
        ``"gyro"`` / ``"accel"``: the IEEE-952 terms fitted to the Allan deviation.
    allan : dict of str to AllanResult
        The Allan deviation of each sensor's axes.
    """

    fits: dict[str, NoiseFit]
    allan: dict[str, AllanResult]

    def summary(self) -> dict[str, Any]:
        """The terms of each sensor and axis in display units (what ``imunav noise`` prints).

        Returns
        -------
        dict
            ``{sensor: {term: {channel: value}}}``, e.g. ``["gyro"]["N"]["gx"]`` in deg/sqrt(h), with the term's
            display unit under ``["gyro"]["units"]``.
        """
        out: dict[str, Any] = {}
        for sensor, f in self.fits.items():
            terms = {n: dict(zip(f.channels, f.display(n))) for n, sel in zip(f.names, f.selected) if np.any(sel)}
            out[sensor] = {**terms, "units": {n: u for n, u in zip(f.names, f.display_units) if n in terms}}
        return jsonable(out)

    def plot(self, sensor: str = "gyro") -> Any:
        """The Allan deviation of one sensor with its fit and intervals (:func:`imunav.noise.plot.plot_allan`).

        Parameters
        ----------
        sensor : {"gyro", "accel"}
            Which sensor's axes.

        Returns
        -------
        matplotlib.figure.Figure
            The figure.

        Raises
        ------
        InvalidInputError
            If the analysis has no such sensor.
        """
        if sensor not in self.allan:
            raise InvalidInputError(f"no {sensor!r} in this analysis; it has {sorted(self.allan)}")
        return noise_plot.plot_allan(self.allan[sensor], self.fits[sensor], title=sensor)


@dataclass(frozen=True)
class Calibration:
    """An estimated calibration (:func:`calibrate`).

    Attributes
    ----------
    result : CalibrationResult
        The calibration with its standard errors, residuals and condition numbers.
    """

    result: CalibrationResult

    def summary(self) -> dict[str, Any]:
        """Residual RMS and condition number of each fit, and the parameters with their standard errors (SI).

        Returns
        -------
        dict
            ``method``, ``residual_rms`` and ``condition`` per fit, ``parameters`` and ``stderr``.
        """
        r = self.result
        rms = {k: np.sqrt(np.mean(np.square(v), axis=0)) for k, v in r.residuals.items()}
        return jsonable({"method": r.method, "residual_rms": rms, "condition": r.condition,
                         "parameters": r.calibration.to_dict(), "stderr": r.stderr})

    def plot(self) -> Any:
        """The residual of every pose / step and axis (:func:`imunav.calib.plot.plot_residuals`).

        Returns
        -------
        matplotlib.figure.Figure
            The figure.
        """
        return calib_plot.plot_residuals(self.result)


@dataclass(frozen=True)
class AttitudeEstimate:
    """The attitude of a recording (:func:`estimate_attitude`).

    Attributes
    ----------
    result : AttitudeResult
        ``t``, ``q_nb`` (body -> NED), gyro bias, covariance diagonal where the filter has one.
    """

    result: AttitudeResult

    def summary(self) -> dict[str, Any]:
        """The filter, the sample count and the final roll / pitch / yaw in degrees.

        Returns
        -------
        dict
            ``filter``, ``samples``, ``final_roll_pitch_yaw_deg``.
        """
        e = np.degrees(self.result.euler()[-1])
        return jsonable({"filter": self.result.name, "samples": int(self.result.t.size),
                         "final_roll_pitch_yaw_deg": e})

    def plot(self) -> Any:
        """Roll, pitch and yaw against time (:func:`imunav.attitude.plot.plot_euler`).

        Returns
        -------
        matplotlib.figure.Figure
            The figure.
        """
        return attitude_plot.plot_euler(self.result)


@dataclass(frozen=True)
class Navigation:
    """A GNSS/INS run over a log (:func:`navigate`).

    Attributes
    ----------
    run : LogRun
        The filter's result (``run.result``, a ``GinsResult``), its configuration, the mounting found.
    sources : NavSources
        What the log held: the IMU and each aid, with the topic used.
    """

    run: LogRun
    sources: NavSources

    def summary(self) -> dict[str, Any]:
        """What ``imunav gins run LOG`` writes to ``summary.json``: sources, mounting, odometer scale, latency.

        Returns
        -------
        dict
            The summary (:func:`imunav.ins.gins.outputs.log_summary`).
        """
        return log_summary(self.run, self.sources)

    def plot(self) -> Any:
        """The track on a local map with the GNSS fixes (:func:`imunav.ins.gins.plot.plot_track`).

        Returns
        -------
        matplotlib.figure.Figure
            The figure.
        """
        return gins_plot.plot_track(self.run.result, self.sources.gnss)


def read(path: str | os.PathLike[str], **options: Any) -> Recording:
    """Read an IMU recording of any format imunav reads (:func:`imunav.io.read_imu`).

    Parameters
    ----------
    path : str or path-like
        CSV, Parquet, HDF5, MAT, NPZ, a ROS 1 / ROS 2 bag or a PX4 ULog.
    **options
        The reader's options: ``units={"gyro": "deg/s", "accel": "g"}``, ``scales=``, ``fs=``, ``skiprows=``,
        ``columns=``, ``topic=``, ``instance=``, ``mag_topic=``, ``layout=`` (a reader refuses one that does not
        fit the file, naming it).

    Returns
    -------
    Recording
        The samples (``.data``, SI, FRD) with ``summary()`` and ``plot()``.
    """
    return Recording(read_imu(path, **options), os.fspath(path))


def _imu(recording: Recording | ImuData) -> ImuData:
    return recording.data if isinstance(recording, Recording) else recording


def analyse_noise(recording: Recording | ImuData, *, sensors: tuple[str, ...] = ("gyro", "accel"),
                  taus: Any = "octave", terms: tuple[str, ...] = ("N", "B", "K", "R"),
                  force: bool = False) -> NoiseAnalysis:
    """The Allan deviation of a static recording and the IEEE-952 terms fitted to it, per sensor.

    σ²(τ) = 3Q²/τ² + N²/τ + (2 ln 2/π) B² + K² τ/3 + R² τ²/2 (IEEE Std 952-1997, Annex C), fitted by generalised
    least squares (:func:`imunav.noise.fit_noise`) to the overlapping Allan deviation
    (:func:`imunav.noise.allan_deviation`), with the defaults of ``imunav noise``.

    Parameters
    ----------
    recording : Recording or ImuData
        A static recording (:func:`read`).
    sensors : tuple of str
        ``"gyro"`` and / or ``"accel"``.
    taus : str or array_like
        Cluster times: ``"octave"``, ``"decade"``, ``"all"``, ``("log", n)`` or seconds.
    terms : tuple of str
        The candidate terms among Q, N, B, K, R; BIC selects among them.
    force : bool
        Analyse a recording that is not static (it is refused otherwise: :func:`imunav.noise.require_static`).

    Returns
    -------
    NoiseAnalysis
        ``fits`` and ``allan`` per sensor, with ``summary()`` and ``plot()``.

    Raises
    ------
    InvalidInputError
        If a sensor is neither ``"gyro"`` nor ``"accel"``.
    NotStaticError
        If the recording moved (unless ``force``).
    """
    data = _imu(recording)
    units = {"gyro": "rad/s", "accel": "m/s^2"}
    bad = sorted(set(sensors) - set(units))
    if bad or not sensors:
        raise InvalidInputError(f"sensors {list(sensors)}: choose among 'gyro' and 'accel'")
    require_static(data, force=force, where=getattr(recording, "path", "the recording"),
                   mean_force="accel" in sensors)
    fits, allan = {}, {}
    for s in sensors:
        names = tuple(f"{s[0]}{a}" for a in "xyz")
        allan[s] = allan_deviation(getattr(data, s), data.fs, taus, units=units[s], channels=names, t=data.t,
                                   nan_policy="segments")
        fits[s] = fit_noise(allan[s], terms=terms, quantity=s)
    return NoiseAnalysis(fits, allan)


def calibrate(recording: Recording | ImuData, method: str = "multipose", **options: Any) -> Calibration:
    """Calibrate an accelerometer + gyro triad from a hand-held multi-pose session (Tedaldi et al. 2014).

    The accelerometer model ``ã = T_a f + b_a`` is fitted so that ``|T_a⁻¹(ã − b_a)| = g`` in every pose, the gyro
    model so that the integrated turns between poses carry one pose's gravity to the next's (D. Tedaldi,
    A. Pretto, E. Menegatti, "A robust and easy to implement method for IMU calibration without external
    equipments", ICRA 2014); :func:`imunav.calib.multipose`, as ``imunav calibrate multipose`` calls it.

    Parameters
    ----------
    recording : Recording or ImuData
        The session, read in SI (raw counts scaled to SI through the reader's ``scales=``).
    method : {"multipose"}
        The method; the others (multi-position, rate table, Ferraris) need a segment table: use
        :mod:`imunav.calib` directly.
    **options
        Options of :func:`imunav.calib.multipose`: ``init_s`` (initial rest, s), ``wait_s``, ``gravity``,
        ``accel_misalignment``, ``strict``.

    Returns
    -------
    Calibration
        The result with ``summary()`` and ``plot()``.

    Raises
    ------
    InvalidInputError
        If ``method`` is not ``"multipose"``.
    InsufficientDataError
        If the session has too few poses or too short an initial rest (:func:`imunav.calib.multipose`).
    """
    if method != "multipose":
        raise InvalidInputError(f"method {method!r}: imunav.calibrate does 'multipose'; the multi-position, "
                                "rate-table and Ferraris methods need a segment table (imunav.calib)")
    data = _imu(recording)
    options = {"raw_accel_unit": "m/s^2", "raw_gyro_unit": "rad/s", **options}
    return Calibration(calib.multipose(data.accel, data.gyro, data.fs, **options))


def estimate_attitude(recording: Recording | ImuData, filter: str = "adaptive", **params: Any) -> AttitudeEstimate:
    """Run an attitude filter over a whole recording (:func:`imunav.attitude.benchmark.make_filter`).

    Parameters
    ----------
    recording : Recording or ImuData
        The recording (with its magnetometer for a 9-D filter).
    filter : str
        ``madgwick``, ``madgwick_c``, ``mahony``, ``complementary``, ``mekf``, ``adaptive``, ``ukf`` or
        ``smoother``.
    **params
        The filter's parameters (e.g. ``heading_time_constant=9``); an unknown one is refused, listing the known.

    Returns
    -------
    AttitudeEstimate
        The result (``q_nb`` body -> NED) with ``summary()`` and ``plot()``.
    """
    return AttitudeEstimate(make_filter(filter, params or None).run(_imu(recording)))


def navigate(log: str | os.PathLike[str], *, options: LogRunOptions | None = None,
             **topics: str) -> Navigation:
    """GNSS/INS over a robot's or a drone's log: a ROS 1 / ROS 2 bag, a PX4 ULog or KF-GINS text files with a
    ``sources.toml`` (:func:`imunav.ins.gins.logrun.run_log`, as ``imunav gins run LOG``).

    Parameters
    ----------
    log : str or path-like
        The log.
    options : LogRunOptions, optional
        Preset, mounting, GNSS lever arm, smoother, ... (:class:`imunav.ins.gins.logrun.LogRunOptions`).
    **topics
        ``imu_topic=``, ``gnss_topic=``, ``odo_topic=``, ``mag_topic=``, ``baro_topic=`` where the log has two
        candidates of a type.

    Returns
    -------
    Navigation
        The run and the log's sources, with ``summary()`` and ``plot()``.
    """
    sources = read_nav_sources(log, **topics)
    return Navigation(run_log(sources, options), sources)
