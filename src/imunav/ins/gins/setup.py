"""The setup of a GNSS/INS run: its configuration (imunav TOML or KF-GINS YAML) and its inputs, read from files or
simulated.

What ``imunav gins run``, ``imunav gins outage-test`` and the ``gins`` lab step read, in one place
(:func:`load_inputs`): the files are read by :mod:`imunav.io.navinputs`

* IMU: a KF-GINS text file of increments (seconds of week, Δθ rad, Δv m/s, FRD; recognised by its first line
  of 7 or more numbers, or declared with ``[imu] format = "kf-gins"``), or any recording
  :func:`imunav.io.read_imu` reads (rates, SI, FRD);
* GNSS: the KF-GINS text file (:func:`imunav.io.gnss.read_gnss_text`) or, for a ``.csv``, a generic CSV
  (:func:`imunav.io.gnss.read_gnss_csv`, its column names in the ``[gnss]`` table);
* odometer: a text file of two columns, time (s, the IMU's clock) and forward speed (m/s);

and the configuration is an imunav TOML (:func:`load_gins_toml`) or KF-GINS's own YAML (:func:`setup_from_kfgins`).

The TOML holds :class:`~imunav.ins.gins.GinsConfig` fields at its top level, in SI (``gyro_noise_density``, ``accel_noise_density``,
``gyro_bias_std``, ..., ``lever_arm``, ``nhc_noise_std``, ...), optionally on top of an IMU preset, and three tables::

    preset = "mems_adis16465"      # optional: GinsConfig.from_preset(preset), the fields below override it
    states = 21                    # 15 or 21 (default 21)
    lever_arm = [0.136, -0.301, -0.184]   # GNSS antenna from the IMU, body FRD, m

    [init]                         # initial state at the first IMU sample used
    lla_deg = [30.4447873701, 114.4718632047, 20.899]   # lat deg, lon deg, h m
    vel_ned = [0.0, 0.0, 0.0]      # m/s
    euler_deg = [0.854, -2.035, 185.702]                 # roll, pitch, yaw (ZYX), deg
    imu_errors = [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]   # optional: bg rad/s, ba m/s^2, sg, sa

    [imu]
    format = "kf-gins"             # or a format of imunav.io.read_imu (default: from the file)
    rate_hz = 200                  # optional: checked against the time stamps of a KF-GINS file
    start_time = 456300            # optional window, s (IMU clock)
    end_time = 457000

    [gnss]
    angle_unit = "deg"             # "deg", "rad" or "deg_small"
    # CSV only: time, lat, lon, height, pos_std, vel, vel_std, default_pos_std, default_vel_std

Without ``[init]`` the initial state is taken from a truth track when one is given
(:meth:`GinsSetup.with_truth_init`).
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav.errors import ConfigError, InvalidInputError
from imunav.ins.gins import GinsConfig, GinsFilter, GinsResult
from imunav.io.aiding import OdometerData
from imunav.io.gnss import GnssData, lat_lon_radians
from imunav.io.kfgins import ImuIncrements, KfGinsConfig, NavTrack, load_kfgins_config
from imunav.io.navinputs import read_gnss_input, read_imu_input, read_odometer
from imunav.rotation import quat_from_euler
from imunav.sim import Trajectory, presets, simulate_imu
from imunav.sim.gnss import simulate_gnss
from imunav.sim.vehicle import demo_drive, vehicle_trajectory
from imunav.timeseries import ImuData
from imunav.toml import read_toml
from imunav.units import DEG
from imunav.vocabulary import renamed_hint

__all__ = ["GinsSetup", "GinsInputs", "SimulatedDrive", "load_gins_toml", "setup_from_kfgins", "load_inputs", "simulate_drive", "run_setup", "track_rmse", "TOML_TABLES", "KFGINS_LEVER_ARM",
           "KFGINS_ORIGIN_LLA"]

Array = NDArray[np.float64]

#: Tables of the TOML configuration and their keys (the top level holds GinsConfig fields, ``preset`` and ``states``).
TOML_TABLES: dict[str, tuple[str, ...]] = {
    "init": ("lla_deg", "vel_ned", "euler_deg", "imu_errors"),
    "imu": ("format", "rate_hz", "start_time", "end_time"),
    "gnss": ("format", "angle_unit", "time", "lat", "lon", "height", "pos_std", "vel", "vel_std", "default_pos_std",
             "default_vel_std"),
}
#: Antenna lever arm of KF-GINS's data set (body FRD, m), used by the simulated drives.
KFGINS_LEVER_ARM = (0.136, -0.301, -0.184)
#: Start point of KF-GINS's data set (lat rad, lon rad, h m), used by the simulated drives.
KFGINS_ORIGIN_LLA = (30.4447873701 * DEG, 114.4718632047 * DEG, 20.899)
_CONFIG_FIELDS = tuple(f.name for f in dataclasses.fields(GinsConfig))


@dataclass(frozen=True)
class GinsSetup:
    """Everything a GNSS/INS run needs besides the data: the filter configuration and the initial state.

    Attributes
    ----------
    config : GinsConfig
        The filter configuration (SI).
    lla0 : numpy.ndarray, shape (3,) or None
        Initial position: lat rad, lon rad, h m (None: not configured; take it from a truth).
    vel0 : numpy.ndarray, shape (3,) or None
        Initial NED velocity, m/s.
    q0 : numpy.ndarray, shape (4,) or None
        Initial ``q_nb`` (body FRD -> NED, scalar first).
    imu_errors0 : numpy.ndarray, shape (12,)
        Initial gyro bias (rad/s), accel bias (m/s²), gyro and accel scale factors.
    imu : dict
        The ``[imu]`` options (format, rate_hz, start_time, end_time).
    gnss : dict
        The ``[gnss]`` options (angle unit, CSV column names).
    source : str
        The configuration file.
    """

    config: GinsConfig
    lla0: Array | None
    vel0: Array | None
    q0: Array | None
    imu_errors0: Array = field(default_factory=lambda: np.zeros(12))
    imu: dict[str, Any] = field(default_factory=dict)
    gnss: dict[str, Any] = field(default_factory=dict)
    source: str = ""

    @property
    def has_init(self) -> bool:
        """Whether the initial position, velocity and attitude are configured."""
        return self.lla0 is not None and self.vel0 is not None and self.q0 is not None

    def with_truth_init(self, truth: NavTrack, t0: float) -> GinsSetup:
        """This setup with the initial state of ``truth`` at time ``t0`` (its nearest epoch within 1 ms).

        Parameters
        ----------
        truth : NavTrack
            The reference track.
        t0 : float
            Time of the first IMU sample used, s.

        Returns
        -------
        GinsSetup
            A copy with ``lla0``, ``vel0`` and ``q0`` from the truth.

        Raises
        ------
        InvalidInputError
            If the truth has no epoch within 1 ms of ``t0``.
        """
        k = int(np.argmin(np.abs(truth.t - t0)))
        if abs(truth.t[k] - t0) > 1e-3:
            raise InvalidInputError(f"{truth.meta.get('source', 'the truth')} has no epoch at the first IMU sample "
                                    f"t = {t0:.3f} s; give the initial state in the configuration ([init] table)")
        return dataclasses.replace(self, lla0=truth.lla[k].copy(), vel0=truth.vel_ned[k].copy(),
                                   q0=truth.q_nb[k].copy())


@dataclass(frozen=True)
class GinsInputs:
    """The data of a GNSS/INS run, read and windowed.

    Attributes
    ----------
    imu : ImuData or ImuIncrements
        Rates or increments, inside the configured time window.
    gnss : GnssData
        The fixes.
    setup : GinsSetup
        Filter configuration and initial state.
    odometer : OdometerData or None
        Wheel speeds, when given.
    paths : dict
        The input files by role (``imu``, ``gnss``, ``config``, ``odometer``), for the output checks.
    output_path : pathlib.Path or None
        The KF-GINS YAML's ``outputpath`` (None for a TOML).
    """

    imu: ImuData | ImuIncrements
    gnss: GnssData
    setup: GinsSetup
    odometer: OdometerData | None = None
    paths: dict[str, Path] = field(default_factory=dict)
    output_path: Path | None = None


def _vector(value: Any, n: int, where: str, unit: str) -> Array:
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"{where} must be a list of {n} numbers ({unit}); got {value!r}") from None
    if a.shape != (n,) or not np.all(np.isfinite(a)):
        raise ConfigError(f"{where} must be a list of {n} finite numbers ({unit}); got {value!r}")
    return a


def _check_keys(table: dict[str, Any], allowed: tuple[str, ...], where: str) -> None:
    unknown = sorted(set(table) - set(allowed))
    if unknown:
        raise ConfigError(f"{where}: unknown key(s) {unknown}{renamed_hint('GinsConfig', unknown)}; "
                          f"allowed: {', '.join(allowed)}")


def _states(value: Any, where: str) -> bool:
    if value not in (15, 21) or isinstance(value, bool):
        raise ConfigError(f"{where}: states must be 15 or 21; got {value!r}")
    return value == 21


def _number_like(v: Any) -> bool:
    if isinstance(v, (bool, int, float)):
        return True
    return isinstance(v, list) and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v)


def _gins_config(doc: dict[str, Any], where: str, overrides: dict[str, Any]) -> GinsConfig:
    for k, v in overrides.items():
        if not _number_like(v):
            raise ConfigError(f"{where}: '{k}' = {v!r}; a GinsConfig field is a number, a list of numbers (SI) or "
                              "true / false")
    try:
        if "preset" in doc:
            return GinsConfig.from_preset(str(doc["preset"]), **overrides)
        missing = [k for k in ("gyro_noise_density", "accel_noise_density", "gyro_bias_std", "accel_bias_std") if k not in overrides]
        if missing:
            raise ConfigError(f"{where}: give the IMU noise {missing} (SI: rad/sqrt(s), m/s/sqrt(s), rad/s, m/s^2) "
                              "or a preset = \"<name>\" of imunav.sim.presets to start from")
        return GinsConfig(**overrides)
    except (InvalidInputError, TypeError, ValueError) as exc:
        if isinstance(exc, ConfigError):
            raise
        raise ConfigError(f"{where}: {exc}") from None


def load_gins_toml(path: str | os.PathLike[str], *, states: int | None = None) -> GinsSetup:
    """Read the imunav GNSS/INS TOML configuration (see the module docstring for its keys).

    Parameters
    ----------
    path : str or os.PathLike
        The TOML file.
    states : int, optional
        15 or 21, overriding the file's ``states``.

    Returns
    -------
    GinsSetup
        Configuration and initial state (None where ``[init]`` is absent).

    Raises
    ------
    ConfigError
        Not TOML, an unknown key or table, a value of the wrong shape or range, or missing IMU noise.
    FileNotFoundError
        If the file does not exist.
    """
    p = Path(path)
    src = os.fspath(p)
    doc = read_toml(p, "GNSS/INS configuration", missing=FileNotFoundError)
    _check_keys(doc, ("preset", "states", *TOML_TABLES, *_CONFIG_FIELDS), src)
    for name, keys in TOML_TABLES.items():
        if not isinstance(doc.get(name, {}), dict):
            raise ConfigError(f"{src}: '{name}' must be a table ([{name}])")
        _check_keys(doc.get(name, {}), keys, f"{src}: [{name}]")
    overrides = {k: v for k, v in doc.items() if k in _CONFIG_FIELDS}
    if states is not None or "scale_factors" not in overrides:
        overrides["scale_factors"] = _states(states if states is not None else doc.get("states", 21), src)
    cfg = _gins_config(doc, src, overrides)
    init = doc.get("init", {})
    lla0 = vel0 = q0 = None
    if init:
        missing = [k for k in ("lla_deg", "vel_ned", "euler_deg") if k not in init]
        if missing:
            raise ConfigError(f"{src}: [init] lacks {missing}; give lla_deg (deg, deg, m), vel_ned (m/s) and "
                              "euler_deg (roll, pitch, yaw deg)")
        pos = _vector(init["lla_deg"], 3, f"{src}: [init] lla_deg", "lat deg, lon deg, h m")
        lat, lon = lat_lon_radians(pos[:1], pos[1:2], "deg", f"{src}: [init] lla_deg")
        lla0 = np.array([lat[0], lon[0], pos[2]])
        vel0 = _vector(init["vel_ned"], 3, f"{src}: [init] vel_ned", "m/s")
        q0 = quat_from_euler(_vector(init["euler_deg"], 3, f"{src}: [init] euler_deg", "deg") * DEG)
    err0 = _vector(init.get("imu_errors", np.zeros(12)), 12, f"{src}: [init] imu_errors",
                   "gyro bias rad/s, accel bias m/s^2, gyro scale, accel scale")
    imu = dict(doc.get("imu", {}))
    for key in ("rate_hz", "start_time", "end_time"):
        if key in imu and not (isinstance(imu[key], (int, float)) and np.isfinite(imu[key])):
            raise ConfigError(f"{src}: [imu] {key} must be a number; got {imu[key]!r}")
    if "rate_hz" in imu and imu["rate_hz"] <= 0:
        raise ConfigError(f"{src}: [imu] rate_hz = {imu['rate_hz']!r}; the IMU rate must be > 0 Hz")
    return GinsSetup(cfg, lla0, vel0, q0, err0, imu, dict(doc.get("gnss", {})), src)


def setup_from_kfgins(cfg: KfGinsConfig, *, states: int = 21) -> GinsSetup:
    """The setup of a KF-GINS YAML (:func:`imunav.io.kfgins.load_kfgins_config`).

    The keys KF-GINS does not know (``cfg.options``) may be :class:`~imunav.ins.gins.GinsConfig` fields (SI),
    which override the values taken from the YAML, or ``odopath`` (the odometer file, relative to the YAML).

    Parameters
    ----------
    cfg : KfGinsConfig
        The KF-GINS configuration.
    states : int
        15 or 21.

    Returns
    -------
    GinsSetup
        Configuration, initial state, and the IMU rate and window of the YAML.

    Raises
    ------
    ConfigError
        If ``states`` is not 15 or 21, or the YAML has a key neither KF-GINS nor imunav knows.
    """
    src = os.fspath(cfg.source)
    _check_keys(cfg.options, ("odopath", *_CONFIG_FIELDS), f"{src} (keys beside KF-GINS's)")
    overrides = {k: v for k, v in cfg.options.items() if k in _CONFIG_FIELDS}
    overrides.setdefault("scale_factors", _states(states, src))
    try:
        gcfg = GinsConfig.from_kfgins(cfg, **overrides)
    except (InvalidInputError, TypeError, ValueError) as exc:
        raise ConfigError(f"{src}: {exc}") from None
    err0 = np.concatenate([cfg.init_gyro_bias, cfg.init_accel_bias, cfg.init_gyro_scale, cfg.init_accel_scale])
    imu = {"format": "kf-gins", "rate_hz": cfg.imu_rate_hz, "start_time": cfg.start_time}
    if cfg.end_time is not None:
        imu["end_time"] = cfg.end_time
    return GinsSetup(gcfg, cfg.init_lla.copy(), cfg.init_vel.copy(), quat_from_euler(cfg.init_euler), err0, imu,
                     {}, src)


def load_inputs(imu: str | os.PathLike[str] | None, gnss: str | os.PathLike[str] | None,
                config: str | os.PathLike[str] | None, *, odometer: str | os.PathLike[str] | None = None,
                states: int | None = None) -> GinsInputs:
    """Read the files of a GNSS/INS run, in either form of ``imunav gins run``.

    * KF-GINS form: ``config`` is a KF-GINS YAML (``.yaml`` / ``.yml``) naming the IMU and GNSS files; ``imu``
      and ``gnss`` are None.
    * imunav form: ``imu`` and ``gnss`` files and ``config`` an imunav TOML (:func:`load_gins_toml`).

    Parameters
    ----------
    imu, gnss : str or os.PathLike, or None
        The IMU and GNSS files (imunav form).
    config : str or os.PathLike, or None
        The YAML (KF-GINS form) or TOML (imunav form).
    odometer : str or os.PathLike, optional
        Odometer file (:func:`imunav.io.navinputs.read_odometer`); with a YAML, its ``odopath`` key is used when this is None.
    states : int, optional
        15 or 21, overriding the configuration's (default: the TOML's ``states``, or 21 with a YAML).

    Returns
    -------
    GinsInputs
        Data, setup and the input paths.

    Raises
    ------
    ConfigError
        A YAML given together with IMU / GNSS files, a missing IMU, GNSS or configuration, a TOML or YAML
        error, or a suffix that is neither.
    """
    cpath = Path(config) if config is not None else None
    yaml_form = cpath is not None and cpath.suffix.lower() in (".yaml", ".yml")
    if yaml_form:
        if imu is not None or gnss is not None:
            raise ConfigError(f"{config}: a KF-GINS YAML names its own imupath and gnsspath; give either the YAML "
                              "alone or IMU GNSS files with a TOML (--config gins.toml)")
        kcfg = load_kfgins_config(cpath)
        setup = setup_from_kfgins(kcfg, states=21 if states is None else states)
        imu_p, gnss_p = kcfg.imu_path, kcfg.gnss_path
        odo = odometer
        if odo is None and "odopath" in kcfg.options:
            o = Path(str(kcfg.options["odopath"]))
            odo = o if o.is_absolute() else cpath.resolve().parent / o
        out_path: Path | None = kcfg.output_path
    else:
        if imu is None or gnss is None:
            raise ConfigError("give the IMU and GNSS files (imunav gins run IMU GNSS --config gins.toml --out DIR) "
                              "or a KF-GINS YAML (imunav gins run --config kf-gins.yaml)")
        if cpath is None:
            raise ConfigError("give --config: a TOML with the IMU noise (or a preset) and the initial state, or a "
                              "KF-GINS YAML")
        if cpath.suffix.lower() != ".toml":
            raise ConfigError(f"--config {config}: give an imunav .toml or a KF-GINS .yaml / .yml")
        setup = load_gins_toml(cpath, states=states)
        imu_p, gnss_p, odo, out_path = Path(imu), Path(gnss), odometer, None
    data = read_imu_input(imu_p, setup.imu)
    fixes = read_gnss_input(gnss_p, setup.gnss)
    paths = {"imu": Path(imu_p), "gnss": Path(gnss_p), "config": Path(cpath) if cpath is not None else None}
    odo_data = None
    if odo is not None:
        odo_data = read_odometer(odo)
        paths["odometer"] = Path(odo)
    return GinsInputs(data, fixes, setup, odo_data, {k: v for k, v in paths.items() if v is not None}, out_path)


@dataclass(frozen=True)
class SimulatedDrive:
    """A simulated land-vehicle drive: truth, IMU, GNSS and the matching setup.

    Attributes
    ----------
    truth : Trajectory
        The true trajectory at the IMU stamps.
    imu : ImuData
        The simulated IMU (rates, SI, FRD).
    gnss : GnssData
        1 Hz fixes of the antenna (position only, as a KF-GINS GNSS file).
    setup : GinsSetup
        The preset's filter configuration with the antenna lever arm, initial state from the truth.
    preset : str
        The IMU preset.
    fs : float
        The nominal IMU rate, Hz (the truth's median interval may differ from ``1 / fs`` in the last digits).
    """

    truth: Trajectory
    imu: ImuData
    gnss: GnssData
    setup: GinsSetup
    preset: str
    fs: float

    def truth_track(self) -> NavTrack:
        """The truth as a :class:`~imunav.io.kfgins.NavTrack`.

        Returns
        -------
        NavTrack
            Time, position, velocity and attitude of the truth.
        """
        tr = self.truth
        return NavTrack(tr.t, tr.pos_lla, tr.vel_ned, tr.q_nb, meta={"source": "simulated truth"})


def simulate_drive(duration_s: float = 600.0, *, preset: str = "mems_adis16465", fs: float = 200.0, seed: int = 1,
                   t0: float = 456300.0, pos_noise: tuple[float, float, float] = (0.5, 0.5, 1.0),
                   states: int = 21) -> SimulatedDrive:
    """Simulate a land-vehicle drive (:func:`imunav.sim.vehicle.demo_drive`) where KF-GINS's data set starts.

    Parameters
    ----------
    duration_s : float
        Length of the drive, s (>= 120).
    preset : str
        IMU preset of :mod:`imunav.sim.presets`.
    fs : float
        IMU rate, Hz.
    seed : int
        Seed of the IMU errors (the GNSS uses ``seed + 1``).
    t0 : float
        Time of the first sample (GPS second of week), s.
    pos_noise : tuple of 3 float
        1-σ white noise of the fixes north, east, down, m (> 0).
    states : int
        15 or 21 states of the filter configuration.

    Returns
    -------
    SimulatedDrive
        Truth, IMU, GNSS and setup.

    Raises
    ------
    InvalidInputError
        If the duration is below 120 s or not finite, or a σ is not > 0.
    ConfigError
        If ``states`` is not 15 or 21.
    """
    truth = vehicle_trajectory(demo_drive(duration_s), fs=fs, origin_lla=KFGINS_ORIGIN_LLA, t0=t0)
    imu = simulate_imu(truth, presets.get(preset), rng=seed)
    gnss = simulate_gnss(truth, pos_noise=pos_noise, vel_noise=None, lever_arm=KFGINS_LEVER_ARM, rng=seed + 1)
    cfg = GinsConfig.from_preset(preset, lever_arm=KFGINS_LEVER_ARM,
                                 scale_factors=_states(states, "simulate_drive"))
    setup = GinsSetup(cfg, truth.pos_lla[0].copy(), truth.vel_ned[0].copy(), truth.q_nb[0].copy(),
                      source=f"preset {preset}")
    return SimulatedDrive(truth, imu, gnss, setup, preset, float(fs))


def run_setup(imu: ImuData | ImuIncrements, gnss: GnssData, setup: GinsSetup, *,
              odometer: OdometerData | None = None, smoother: bool = False,
              progress: Callable[[int, int], None] | None = None) -> GinsResult:
    """Run the GNSS/INS filter with a :class:`GinsSetup` (the one call of the filter by the command line and
    the lab step).

    Parameters
    ----------
    imu : ImuData or ImuIncrements
        Rates or increments.
    gnss : GnssData
        The fixes.
    setup : GinsSetup
        Configuration and initial state (``setup.has_init`` must be True).
    odometer : OdometerData, optional
        Wheel speeds.
    smoother : bool
        Also run the RTS smoother.
    progress : callable, optional
        ``progress(done, total)`` as the filter and the smoother go (:meth:`GinsFilter.run`).

    Returns
    -------
    GinsResult
        The output of the GNSS/INS filter of :mod:`imunav.ins.gins`.

    Raises
    ------
    ConfigError
        If the setup has no initial state.
    """
    if not setup.has_init:
        raise ConfigError(f"{setup.source}: no initial state; give [init] (lla_deg, vel_ned, euler_deg) or a truth")
    return GinsFilter(setup.config).run(imu, gnss, lla0=setup.lla0, vel0=setup.vel0, q0=setup.q0,
                                        imu_errors0=setup.imu_errors0, odometer=odometer, smoother=smoother,
                                        progress=progress)


def track_rmse(nav: NavTrack, truth: NavTrack) -> dict[str, Any]:
    """RMSE of a navigation solution against a truth at their common stamps (:meth:`NavTrack.difference`).

    Parameters
    ----------
    nav : NavTrack
        The solution.
    truth : NavTrack
        The reference.

    Returns
    -------
    dict
        ``pos_ned_m`` (N, E, D, m), ``vel_ned_mps`` (m/s), ``att_rpy_deg`` (roll, pitch, yaw, deg): RMSE per
        axis; ``n``: the number of common epochs.
    """
    _, dp, dv, de = nav.difference(truth)

    def r(x: Array) -> list[float]:
        return np.sqrt(np.mean(x**2, axis=0)).tolist()

    return {"pos_ned_m": r(dp), "vel_ned_mps": r(dv), "att_rpy_deg": r(np.degrees(de)), "n": int(dp.shape[0])}
