"""Shared numpydoc fragments, filled into docstrings at import time.

Sibling functions (the file readers, the attitude filters' ``step`` / ``run`` / ``reset``) document the
same parameters in the same words.  Those words live here once, under a name; a docstring names the
fragment with a placeholder line ``%(name)s`` and :func:`fill_doc` replaces it, indenting every line of
the fragment like the placeholder, so the filled ``__doc__`` is what numpydoc and Sphinx parse.

Core layer: imports nothing from imunav.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Any, TypeVar, overload

__all__ = ["DOCS", "fill_doc"]

F = TypeVar("F")

#: Named fragments, written without indentation (a fragment's lines are indented like its placeholder).
DOCS: dict[str, str] = {}

DOCS["reader_units"] = """\
units : mapping of str to str, optional
    Declared unit of each group (``{"gyro": "deg/s", "accel": "g"}``, or ``"counts"``); default SI.
scales, offsets : mapping of str to float, optional
    For ``"counts"``: ``value_si = (counts - offset) * scale``.
fs : float, optional
    Sample rate, Hz, when the file has no time (``t = t0 + k / fs``).
t0 : float
    Time of the first sample with ``fs``, s."""

DOCS["reader_tail"] = """\
nan_policy : {"raise", "drop", "interpolate"}
    What to do with NaN samples.
mag_unit : str, optional
    Unit of the magnetometer (kept as stored).
meta : mapping, optional
    Entries added to the recording's ``meta``."""

DOCS["reader_options"] = DOCS["reader_units"] + "\n" + DOCS["reader_tail"]

DOCS["reader_returns"] = """\
Returns
-------
ImuData
    The recording, SI.

Raises
------
FileFormatError
    If the file is missing, unreadable, or lacks a required group (the message lists what was found).
NonFiniteError, TimeOrderError, ShapeError, UnitError
    From the validation of the values."""

DOCS["array_columns"] = """\
columns : mapping of str to str, optional
    Where each group is stored (e.g. ``{"gyro": "imu/gyr"}``); by default found by name."""

_PLACEHOLDER = re.compile(r"^([ \t]*)%\((\w+)\)s[ \t]*$", re.MULTILINE)


def _indent(text: str, prefix: str) -> str:
    return "\n".join(prefix + line if line else line for line in text.split("\n"))


@overload
def fill_doc(obj: F, /) -> F: ...
@overload
def fill_doc(obj: None = None, /, **fields: str) -> Callable[[F], F]: ...
def fill_doc(obj: Any = None, /, **fields: str) -> Any:
    """Replace each placeholder line ``%(name)s`` of ``obj.__doc__`` by the fragment ``DOCS[name]``.

    Parameters
    ----------
    obj : function or class, optional
        The object whose docstring holds placeholders, each alone on its line.  Without it (``@fill_doc(step=...)``)
        the decorator to apply is returned.
    **fields : str
        Words a fragment leaves open: ``%(step)s`` inside a fragment's text becomes ``fields["step"]``.

    Returns
    -------
    function or class
        ``obj`` itself, its ``__doc__`` filled (every line of a fragment indented like its placeholder); without
        ``obj``, the decorator that fills it.

    Raises
    ------
    KeyError
        If a placeholder names no fragment of :data:`DOCS` (a typo in the docstring, found at import), or a
        fragment leaves open a field that ``fields`` does not give.
    """
    if obj is None:
        return lambda o: fill_doc(o, **fields)
    doc = getattr(obj, "__doc__", None)
    if doc:

        def sub(m: re.Match[str]) -> str:
            name = m.group(2)
            if name not in DOCS:
                raise KeyError(f"docstring placeholder %({name})s: no such fragment in imunav._docstrings.DOCS")
            text = _FIELD.sub(lambda f: _field(f.group(1), fields, name), DOCS[name])
            return _indent(text, m.group(1))

        obj.__doc__ = _PLACEHOLDER.sub(sub, doc)
    return obj


_FIELD = re.compile(r"%\((\w+)\)s")


def _field(key: str, fields: dict[str, str], fragment: str) -> str:
    if key not in fields:
        raise KeyError(f"fragment {fragment!r} leaves %({key})s open: pass it, e.g. @fill_doc({key}=...)")
    return fields[key]


# --- attitude filters: reset / step / run -------------------------------------------------------------
DOCS["att_q0"] = """\
q0 : array_like, shape (4,)
    Attitude ``q_nb`` [w, x, y, z], body (FRD) to NED (normalised here)."""

DOCS["att_bias"] = """\
bias : array_like, shape (3,), optional
    Initial gyro-bias estimate, rad/s (default zero)."""

DOCS["att_reset_raises"] = """\
Raises
------
ShapeError
    If ``q0`` is not a (4,) quaternion.
NonFiniteError
    If ``q0`` is zero or not finite."""

DOCS["att_step_params"] = """\
gyro : array_like, shape (3,)
    Angular rate, body axes (FRD), rad/s.
accel : array_like, shape (3,)
    Specific force, body axes, m/s² (any unit: only its direction is used).
mag : array_like, shape (3,), or None
    Magnetic field, body axes (any unit); None for a 6D update.
dt : float
    Time since the previous sample, s, > 0."""

DOCS["att_step_returns"] = """\
Returns
-------
numpy.ndarray, shape (4,)
    The new attitude ``q_nb``.

Raises
------
InvalidInputError
    If ``dt`` is not finite and positive, or the rate exceeds 1e4 rad/s (not rad/s).
ShapeError
    If a sample is not a 3-vector.
NonFiniteError
    If a sample is not finite."""

DOCS["att_run_data"] = """\
data : ImuData
    The recording (SI: rad/s, m/s²; magnetometer in any unit), body FRD.
q0 : array_like, shape (4,), optional
    Initial attitude ``q_nb`` (default: :func:`imunav.attitude.alignment.align` of the first accelerometer
    / magnetometer sample)."""

DOCS["att_bias0"] = """\
bias0 : array_like, shape (3,), optional
    Initial gyro-bias estimate, rad/s (default zero)."""

DOCS["att_use_mag"] = """\
use_mag : bool, optional
    Use the magnetometer (9D); default: when the recording has one."""

DOCS["att_run_raises"] = """\
Raises
------
InvalidInputError
    If ``data`` is not an ImuData with at least 2 samples, ``use_mag=True`` without a magnetometer, or a
    rate exceeds 1e4 rad/s."""

# --- generic Kalman filters: predict / update -----------------------------------------------------------
DOCS["kf_predict_params"] = """\
u : array_like, optional
    Control input passed to ``f``.
Q : array_like, shape (n, n), optional
    Process-noise covariance of this step (default: the filter's ``Q``)."""

DOCS["kf_predict_returns"] = """\
Returns
-------
x : numpy.ndarray, shape (n,)
    Predicted state.
P : numpy.ndarray, shape (n, n)
    Predicted covariance."""

DOCS["kf_update_params"] = """\
z : array_like, shape (m,)
    Measurement.
R : array_like, shape (m, m), optional
    Measurement-noise covariance (default: the filter's ``R``)."""

DOCS["kf_update_returns"] = """\
Returns
-------
UpdateResult
    Innovation, its covariance, the gain, the normalised innovation and the NIS.

Raises
------
InvalidInputError
    If ``R`` does not match the size of the measurement."""

# whole sections, so that a filter's docstring is its summary line and one placeholder
_PARAMS = "Parameters\n----------\n"
DOCS["att_reset"] = _PARAMS + DOCS["att_q0"] + "\n\n" + DOCS["att_reset_raises"]
DOCS["att_reset_bias"] = _PARAMS + DOCS["att_q0"] + "\n" + DOCS["att_bias"] + "\n\n" + DOCS["att_reset_raises"]
DOCS["att_step"] = _PARAMS + DOCS["att_step_params"] + "\n\n" + DOCS["att_step_returns"]
DOCS["att_run_params"] = _PARAMS + DOCS["att_run_data"]
DOCS["kf_predict"] = _PARAMS + DOCS["kf_predict_params"] + "\n\n" + DOCS["kf_predict_returns"]
DOCS["kf_update_params_head"] = _PARAMS + DOCS["kf_update_params"]
DOCS["reader_head"] = _PARAMS + """\
path : str or os.PathLike
    The file."""

# --- small kernels and factories ------------------------------------------------------------------------
DOCS["mat3_product"] = """\
Parameters
----------
A, B : (3, 3) float64 arrays.
C : (3, 3) float64 array, receives the product.

Returns
-------
None"""

DOCS["gravity_factory"] = """\
Parameters
----------
config : GravityKfConfig, optional
    Filter settings (default :class:`GravityKfConfig` ()).
**kw
    Further :class:`GravityKF` fields (``accel_convention``).

Returns
-------
GravityKF
    The filter."""

DOCS["frame_vectors"] = """\
Parameters
----------
v : array_like, shape (3,) or (N, 3)
    Vectors."""

DOCS["calib_pair_raises"] = """\
Raises
------
ShapeError
    If ``accel`` and ``gyro`` are not both (N, 3).
NonFiniteError
    If a sample or temperature is not finite.
InvalidInputError
    If the calibration is temperature dependent and ``temp_c`` is missing."""

DOCS["track_estimate_reference"] = """\
Parameters
----------
estimate : array_like, shape (N, 2) or (N, 3)
    Estimated positions, local NED (x, y horizontal), m.
reference : array_like, shape (N, 2) or (N, 3)
    Reference positions at the same samples, m, frame with the same x-y handedness."""

DOCS["track_pair"] = DOCS["track_estimate_reference"] + """
align_distance : float
    Horizontal distance from the start at which the headings are aligned, m."""

DOCS["fit_get_params"] = """\
Parameters
----------
name : str
    Term name, one of :attr:`names`.
channel : int
    Channel index."""

DOCS["curvefit_tau_adev"] = """\
Parameters
----------
tau : array_like, shape (T,)
    Cluster times, s (non-positive or non-finite points are left out).
adev : array_like, shape (T,)
    Allan deviation of one channel at ``tau`` (rad/s or m/s²)."""

DOCS["figure_title_returns"] = """\
title : str, optional
    Figure title.

Returns
-------
matplotlib.figure.Figure
    The figure (not shown; save it with ``fig.savefig``)."""

DOCS["kf_x0_P0"] = """\
Parameters
----------
x0 : array_like, shape (n,)
    Initial state.
P0 : array_like, shape (n, n)
    Initial covariance."""

# --- rotation, earth, profiles ----------------------------------------------------------------------------
DOCS["rot_q"] = """\
q : array_like, shape (4,) or (N, 4)
    Quaternion(s) ``[w, x, y, z]`` (Hamilton, scalar first), e.g. ``q_nb`` body (FRD) to navigation (NED)."""

DOCS["rot_shape_raises"] = """\
Raises
------
ShapeError
    If an input does not have the shape given above."""

DOCS["earth_triple_raises"] = """\
Raises
------
ShapeError
    If a triple is not (3,) / (N, 3).
NonFiniteError
    If an input is NaN or infinite."""

DOCS["earth_lat"] = """\
lat : array_like
    Geodetic latitude, rad, in [-pi/2, pi/2] (scalar or array)."""

DOCS["profile_position"] = """\
lat : float, optional
    Geodetic latitude of the fixed position, rad (None: no position).
lon : float
    Longitude, rad.
h : float
    Ellipsoidal height, m."""

DOCS["profile_returns"] = """\
name : str
    Profile name.

Returns
-------
Profile
    The trajectory (exact body rates) and its segment table."""

DOCS["robust_tail"] = """\
gate_m : float, optional
    Per-channel gate half-width, standard deviations (``"gate"``).
alpha : float, optional
    Test level in (0, 1) (``"isolate"``, ``"nis"``).
huber_c : float, optional
    Huber threshold (``"huber"``)."""

DOCS["wind_robust"] = """\
robust : {None, "gate", "isolate", "nis", "huber"}, optional
    None (optimal), ``"gate"`` (thesis, per channel |ν̃| < gate_m),
    ``"nis"`` (vector χ² gate at level alpha: rejects whole-sensor
    outliers, recommended for the ADS), ``"isolate"`` (χ² test + w-test
    isolation of single channels) or ``"huber"``.
""" + DOCS["robust_tail"]

DOCS["batch_executor"] = """\
executor : {"serial", "processes", "dask"}
    Where the units are processed (:func:`imunav.lab.montecarlo.run_batch`).
n_workers : int, optional
    Worker processes (default: number of cores).
address : str, optional
    Dask scheduler address (Dask executor only; None: a local cluster).
progress : bool
    Show a progress bar."""

DOCS["batch_overwrite_returns"] = """\
overwrite : bool
    Clear a previous run in ``out_dir`` instead of refusing.

Returns
-------
BatchSummary
    One row per unit (also written as ``summary.csv`` / ``summary.json``)."""

# --- dedup-io ---
DOCS["lab_step_run"] = """\
Parameters
----------
ctx : LabContext
    The lab's context: the step's option table ``ctx.options`` (``[%(step)s]``), the artifacts it reads and
    sets, the report folder.

Returns
-------
StepResult"""

DOCS["lab_step_report"] = """\
Parameters
----------
section : imunav.lab.report.html.Section
    The step's section.
result : StepResult
    What :func:`run` returned.
ctx : LabContext
    The lab's context (its ``[spec]`` and artifacts)."""

DOCS["imu_writer_params"] = """\
Parameters
----------
data : ImuData
    The recording.
path : str or os.PathLike
    Output file."""

DOCS["returns_file_written"] = """\
Returns
-------
pathlib.Path
    The file written."""

DOCS["noise_yaml_fits"] = """\
Parameters
----------
path : path-like
    The YAML file to write (atomically).
gyro, accel : NoiseFit
    Noise fits of the gyroscope (rad/s) and accelerometer (m/s^2) channels."""

DOCS["noise_yaml_rate"] = """\
update_rate : float
    IMU sample rate, Hz."""

DOCS["noise_yaml_combine_returns"] = """\
combine : {"max", "mean"}
    One value per sensor: the maximum (default) or mean over the axes.

Returns
-------
Path
    ``path``."""

DOCS["topic_returns"] = """\
Returns
-------
TopicData
    The topic in SI units, body FRD / world NED, ``t`` in s since ``meta["t0_ns"]``."""

DOCS["imu_topic_returns"] = DOCS["topic_returns"] + """
    Gyro (rad/s) and specific force (m/s²) in body FRD, ``t`` in s since ``meta["t0_ns"]``.

Raises
------
InvalidInputError"""

DOCS["accel_window"] = """\
Parameters
----------
accel : array_like, shape (N, 3)
    Specific force in the body (FRD) frame, m/s².
window : int, optional
    Window length ``W`` in samples, >= 2 (default 5)."""

DOCS["strapdown_data_q0"] = """\
Parameters
----------
data : ImuData
    The recording (SI: rad/s, m/s², specific force), body FRD.
q0 : array_like, shape (4,)
    Initial attitude ``q_nb`` (unit quaternion)."""

DOCS["section_chain_returns"] = """\
Returns
-------
Section
    ``self``, so that calls chain."""

DOCS["axes_drawn_returns"] = """\
Returns
-------
matplotlib.axes.Axes
    The axes drawn into."""

DOCS["config_to_dict"] = """\
Returns
-------
dict
    One key per field."""

DOCS["fault_innovations_window"] = """\
Parameters
----------
normalized : array_like, shape (N, s)
    Normalised innovations ``ν̃ = S^{-1/2} ν`` (a 1-D array is one channel), finite.
M : int, optional
    Window length in steps, > s (default 20)."""

DOCS["fault_batch_innovations_window"] = """\
Parameters
----------
normalized : array_like, shape (N, s) or (R, N, s)
    Normalised innovations ``ν̃ = S^{-1/2} ν`` of one run or a batch of runs, finite.
M : int, optional
    Window length in steps, > s (default 20)."""
# --- dedup-core ---
DOCS["rot_q_params"] = _PARAMS + DOCS["rot_q"]


DOCS["finite_shape_raises"] = """\
Raises
------
NonFiniteError
    If ``%(arg)s`` is not finite.
ShapeError
    If ``%(arg)s`` is not %(shapes)s."""

DOCS["rot_euler_raises"] = """\
Raises
------
ShapeError
    If only one of ``pitch`` / ``yaw`` is given, or the shapes do not broadcast."""

DOCS["earth_lat_params"] = _PARAMS + DOCS["earth_lat"]

DOCS["earth_lat_h_raises"] = """\
Raises
------
InvalidInputError
    If a latitude is outside [-pi/2, pi/2] or a height outside :data:`H_RANGE_M`.
NonFiniteError
    If an input is NaN or infinite."""

DOCS["earth_lat_raises"] = """\
Raises
------
InvalidInputError
    If a latitude is outside [-pi/2, pi/2].
NonFiniteError
    If an input is NaN or infinite."""

DOCS["earth_ref_lla_returns"] = """\
ref_lla : array_like, shape (3,)
    Origin of the local NED frame: geodetic ``(lat, lon, h)``, rad, rad, m.

Returns
-------
numpy.ndarray, shape (3,) or (N, 3)"""

DOCS["earth_ned_params"] = _PARAMS + """\
ned : array_like, shape (3,) or (N, 3)
    North, east, down coordinates, m."""

DOCS["profile_position_returns"] = DOCS["profile_position"] + """

Returns
-------
Profile
    The trajectory (exact body rates) and its segment table."""

DOCS["profile_t0_returns"] = DOCS["profile_position"] + """
t0 : float
    Time of the first sample, s.
""" + DOCS["profile_returns"]

DOCS["profile_static_params"] = _PARAMS + """\
fs : float
    Sample rate, Hz.
dwell_s : float
    Static time per position, s.
transition_s : float
    Duration of each move, s."""

DOCS["profile_rate_moves"] = """\
transition_s : float
    Duration of each rate ramp, s.
remount_s : float
    Duration of the re-mounting move when the axis changes, s."""

DOCS["write_path_returns"] = _PARAMS + """\
path : str or os.PathLike
    Output file.

""" + DOCS["returns_file_written"]


DOCS["means_fit_raises"] = """\
Raises
------
ShapeError
    If the arrays are not (K, 3) with the same K.
InsufficientDataError
    With too few %(units)s for the parameters.
DegenerateGeometryError
    If the %(inputs)s do not excite every axis."""

DOCS["calib_f_ref_params"] = _PARAMS + """\
f_ref : array_like, shape (K, 3)
    Reference specific force of each position, body frame, m/s² (:func:`reference_specific_force`)."""

DOCS["maneuver_duration_returns"] = """\
duration_s : float
    Length, s (> 0).

Returns
-------
Maneuver"""

DOCS["sim_rng"] = """\
rng : numpy.random.Generator or int, optional
    Random generator or seed."""

DOCS["replace_changes"] = _PARAMS + """\
**changes
    New values of fields.

Returns
-------"""

DOCS["allan_tau_returns"] = _PARAMS + """\
tau : array_like
    Averaging times, s.

Returns
-------
numpy.ndarray, shape (3, len(tau))"""

DOCS["toml_path"] = _PARAMS + """\
path : str or os.PathLike
    The TOML file."""

DOCS["thesis_cfg_steps"] = _PARAMS + """\
cfg : ThesisFilterConfig, optional
    Filter configuration (default: the thesis's values).
n_steps : int
    Number of steps."""

DOCS["doppler_v_beams"] = _PARAMS + """\
v_body : array_like, shape (3,) or (N, 3)
    Ground velocity in body axes (FRD), m/s.
beams : array_like, shape (n_beams, 3)
    Beam unit vectors in body axes (:func:`janus_beams`)."""

DOCS["traj_t_q_nb"] = _PARAMS + """\
t : array_like, shape (N,)
    Strictly increasing time, s.
q_nb : array_like, shape (N, 4)
    Attitude, body (FRD) to NED."""

DOCS["calib_returns_raises"] = """\
Returns
-------
ImuCalibration
    The calibration.

Raises
------
FileFormatError"""

DOCS["mc_attitude_paper"] = _PARAMS + """\
mc : imunav.lab.montecarlo.MonteCarloResult
    The result of ``run_montecarlo(attitude_paper, ...)``.

Returns
-------
dict"""

DOCS["mag_h_raw"] = _PARAMS + """\
h : array_like, shape (N, 3)
    Raw magnetometer samples, any unit (kept), sensor axes.

Returns
-------"""

DOCS["to_dict_attributes"] = """\
Returns
-------
dict
    The attributes by name."""

DOCS["fit_get_returns"] = DOCS["fit_get_params"] + """

Returns
-------
float"""


DOCS["negative_raises"] = """\
Raises
------
InvalidInputError
    If %(value)s is negative.
NonFiniteError
    If a value is NaN or infinite."""

DOCS["figure_returns"] = """\
Returns
-------
matplotlib.figure.Figure
    The figure."""

DOCS["figure_title_str_returns"] = """\
title : str
    Figure title.

""" + DOCS["figure_returns"]

DOCS["save_fig_path"] = _PARAMS + """\
fig : matplotlib.figure.Figure
    The figure.
path : str or os.PathLike
    Output file; the format follows its suffix."""

DOCS["prov_meta_or_data"] = _PARAMS + """\
meta_or_data : ImuData or mapping
    A recording (its ``meta`` is read) or its metadata dict."""

# --- shape ---
DOCS["att_run_bias_mag"] = DOCS["att_run_params"] + "\n" + DOCS["att_bias0"] + "\n" + DOCS["att_use_mag"]

DOCS["att_run_gain"] = DOCS["att_run_params"] + "\n" + DOCS["att_use_mag"] + """

Returns
-------
AttitudeResult
    ``q_nb`` at every sample, with the filter's name and parameters.

""" + DOCS["att_run_raises"]

DOCS["att_q_est_ref"] = """\
q_est : array_like, shape (N, 4)
    Estimated attitude ``q_nb``.
q_ref : array_like, shape (N, 4)
    Reference attitude ``q_nb`` (rows with NaN are skipped)."""
