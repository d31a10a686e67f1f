"""Limits before work: the memory and time a request needs, estimated from its options, checked first.

A command whose options ask for far more than the machine can give (``simulate
--duration 1e12``, ``noise --taus log:1000000000``, ``attitude montecarlo --runs
100000000``, ``attitude benchmark --grid`` of 10^5 parameter sets, ``zupt train --epochs 1000000000``) is
refused before any work with the estimate, unless ``--force`` (then the estimate is still said, a warning line):

``error: simulate static --duration 1e+12 s at --fs 100 Hz: about 1e+14 samples, 45 PiB of memory and 16 years
on the reference machine (24 GiB, 2 cores); reduce the request, or pass --force to run it anyway``

The estimates are deliberately rough (an order of magnitude): bytes and seconds per sample
measured on the reference machine, times the number of samples, runs and terms the options
ask for.  A request is refused when it needs more memory than :data:`MEMORY` or more time than
:data:`TIME` (both far beyond what any test or README example asks).  :data:`ESTIMATORS` maps a
command path to its estimator; every command listed there has a ``--force`` option
(:func:`imunav.cli._errors.install_checks` adds one where the command has none).
"""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from imunav.errors import ImunavWarning, InvalidInputError

__all__ = ["ESTIMATORS", "Estimate", "MEMORY", "TIME", "check_limits"]

#: The reference machine: memory (bytes) and cores.
MACHINE_MEMORY = 24 * 2**30
MACHINE_CORES = 2
#: Refused above: the machine's memory, or 12 hours on its cores.
MEMORY = MACHINE_MEMORY
TIME = 12 * 3600.0
#: Said before the work (one warning line with the estimate): a request estimated to take longer than this.
NOTICE = 60.0


@dataclass(frozen=True)
class Estimate:
    """What a request needs.

    Attributes
    ----------
    what : str
        The request in words (options and the counts derived from them).
    bytes : float
        Peak memory, bytes.
    seconds : float
        Wall time on the reference machine, s.
    """

    what: str
    bytes: float
    seconds: float


def _size(b: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"):
        if b < 1024 or unit == "EiB":
            return f"{b:.3g} {unit}"
        b /= 1024
    return f"{b:.3g} EiB"


def _time(s: float) -> str:
    for unit, k in (("years", 365.25 * 86400), ("days", 86400), ("hours", 3600), ("minutes", 60)):
        if s >= k:
            return f"{s / k:.3g} {unit}"
    return f"{s:.3g} s"


# bytes and seconds per sample (measured orders of magnitude on the reference machine)
_SIM_BYTES, _SIM_SECONDS = 600.0, 4e-6  # trajectory + sensor model + recording, per IMU sample
_INS_BYTES, _INS_SECONDS = 4000.0, 3e-5  # GNSS/INS: states, covariance, outputs per epoch
_ATT_BYTES, _ATT_SECONDS = 400.0, 3e-6  # attitude filter, per sample and filter
_POSITIONS = {"static": 0, "multiposition": 100, "ratetable": 120, "sixposition": 6, "ferraris": 8}


def _simulate(v: Mapping[str, Any]) -> Estimate | None:
    prof = v.get("profile")
    fs = float(v.get("fs") or 0)
    if prof == "static":
        seconds = float(v.get("duration") or 0)
        span = f"--duration {seconds:.3g} s"
    else:
        dwell, tr = float(v.get("dwell") or 0), float(v.get("transition") or 0)
        seconds = _POSITIONS.get(prof, 120) * (dwell + tr)
        span = f"{_POSITIONS.get(prof, 120)} x (--dwell {dwell:.3g} + --transition {tr:.3g}) = {seconds:.3g} s"
    n = fs * seconds
    return Estimate(f"simulate {prof}: {span} at --fs {fs:g} Hz = {n:.3g} samples",
                    n * _SIM_BYTES, n * _SIM_SECONDS)


def _batch_simulate(v: Mapping[str, Any]) -> Estimate | None:
    units = int(v.get("n_units") or 0)
    fs = float(v.get("fs") or 0)
    if v.get("static"):
        seconds = float(v["static"])
        span = f"--static {seconds:.3g} s"
    else:
        steps = 100 + (120 if v.get("rate_table") else 0)
        dwell, tr = float(v.get("dwell") or 0), float(v.get("transition") or 0)
        seconds = steps * (dwell + tr)
        span = f"{steps} x (--dwell {dwell:.3g} + --transition {tr:.3g}) = {seconds:.3g} s"
    n = fs * seconds
    workers = max(1, min(units, int(v.get("workers") or MACHINE_CORES)))
    return Estimate(f"batch simulate: N_UNITS {units} x {span} at --fs {fs:g} Hz = {units * n:.3g} samples",
                    workers * n * _SIM_BYTES, units * n * _SIM_SECONDS / min(workers, MACHINE_CORES))


def _gins(v: Mapping[str, Any]) -> Estimate | None:
    if v.get("duration") is None or v.get("fs") is None:
        return None
    n = float(v["duration"]) * float(v["fs"])
    return Estimate(f"--duration {v['duration']:g} s at --fs {v['fs']:g} Hz = {n:.3g} epochs", n * _INS_BYTES,
                    n * _INS_SECONDS)


def _attitude_mc(v: Mapping[str, Any]) -> Estimate | None:
    runs = int(v.get("runs") or 0)
    n = float(v.get("duration") or 0) * 100.0  # the paper's scenario runs at 100 Hz
    k = max(1, len([f for f in str(v.get("filters") or "x").split(",") if f.strip()]))
    return Estimate(f"attitude montecarlo: --runs {runs} x --duration {float(v.get('duration') or 0):.3g} s "
                    f"({n:.3g} samples at 100 Hz) x {k} filters",
                    min(runs, 64) * n * _ATT_BYTES * k, runs * n * k * _ATT_SECONDS / MACHINE_CORES)


_BROAD_BYTES = 68.0  # bytes of a BROAD trial file per sample (IMU, magnetometer, optical reference; compressed)
_BROAD_SAMPLES = 5e5  # the shared BROAD trials (10 files, 36 MB), when the folder is not a local one


def _attitude_benchmark(v: Mapping[str, Any]) -> Estimate | None:
    # NAME -> number of values, a repeated NAME replacing the earlier one as in the command
    grid = {str(g).split("=", 1)[0]: len(str(g).split("=", 1)[-1].split(",")) for g in (v.get("grid") or [])}
    combos = math.prod(grid.values())
    filters = 1 if grid else max(1, len(v.get("filter") or ["adaptive", "smoother"]))
    try:
        size = sum(p.stat().st_size for p in Path(v.get("directory") or ".").glob("*.mat"))
    except OSError:
        size = 0
    n = size / _BROAD_BYTES if size else _BROAD_SAMPLES
    workers = int(v.get("workers") or MACHINE_CORES)
    what = " x ".join(f"--grid {name} ({k} values)" for name, k in grid.items())
    return Estimate(f"attitude benchmark: {what + ' = ' if grid else ''}{combos:.3g} parameter set(s) x {filters} "
                    f"filter(s) over about {n:.3g} samples", min(workers, 64) * n * _ATT_BYTES,
                    combos * filters * n * _ATT_SECONDS / min(workers, MACHINE_CORES))


def _airdata_simulate(v: Mapping[str, Any]) -> Estimate | None:
    n = float(v.get("duration") or 0) * (float(v.get("rate_ads") or 0) + float(v.get("rate_doppler") or 0))
    return Estimate(f"airdata simulate: --duration {float(v.get('duration') or 0):.3g} s x (--rate-ads + "
                    f"--rate-doppler) = {n:.3g} samples", n * _SIM_BYTES, n * _SIM_SECONDS)


def _airdata_runs(seconds_per_run: float) -> Callable[[Mapping[str, Any]], Estimate | None]:
    def est(v: Mapping[str, Any]) -> Estimate | None:
        runs = int(v.get("runs") or 0)
        return Estimate(f"--runs {runs} Monte Carlo runs", 1e6 + runs * 1e3, runs * seconds_per_run)

    return est


#: the LSTM's training (imunav.ins.zupt.lstm.LstmConfig defaults, and what a window holds): its cost per window step
#: and layer is ~ hidden x (hidden + inputs) multiply-adds, forward and back
_LSTM = {"windows_per_trial": 1000, "epochs": 3, "layers": 2, "hidden": 48, "window": 100, "inputs": 8, "batch": 64}
_LSTM_SECONDS = 2.7e-9  # x epochs x windows x window x layers x hidden x (hidden + inputs): the defaults on 42 trials, ~3 min


def _zupt_train(v: Mapping[str, Any]) -> Estimate | None:
    try:
        trials = max(1, sum(1 for _ in Path(v.get("directory") or ".").glob("*.mat")))
    except OSError:
        trials = 1
    wpt, epochs, layers, hidden = (int(v.get(key) or _LSTM[key]) for key in ("windows_per_trial", "epochs", "layers",
                                                                             "hidden"))
    windows = trials * wpt
    cell = layers * hidden * (hidden + _LSTM["inputs"])
    seconds = epochs * windows * _LSTM["window"] * cell * _LSTM_SECONDS
    if v.get("budget_s"):
        seconds = min(seconds, float(v["budget_s"]))  # the training stops there
    # the windows' draw (an index per window), the weights with their gradients and Adam's moments, a batch's
    # activations kept for the backward pass
    nbytes = windows * 16.0 + 4 * 4 * 4.0 * cell + _LSTM["batch"] * _LSTM["window"] * layers * 4 * hidden * 4.0 * 6
    return Estimate(f"zupt train: {trials} trials x --windows-per-trial {wpt} x --epochs {epochs} windows of "
                    f"{_LSTM['window']} samples through --layers {layers} x --hidden {hidden} LSTM units",
                    nbytes, seconds)


#: bytes of a recording file per sample: six float64 channels and a time stamp (binary), or ~12 characters each (text)
_FILE_BYTES = {".csv": 7 * 12.0, ".txt": 7 * 12.0}
_BINARY_BYTES = 7 * 8.0
#: the GLS fit of the noise terms over n averaging times: its n x n covariance, per channel and candidate term set
_FIT_SECONDS = 0.03  # x n_tau^1.5 (measured: 200 taus 190 s, 400 taus 525 s on a loaded 2-core machine)


def _samples_in(path: Any) -> float:
    """Samples of a recording file, estimated from its size (an order of magnitude; 0 when unknown)."""
    try:
        size = os.stat(path).st_size
    except (OSError, TypeError, ValueError):
        return 0.0
    return size / _FILE_BYTES.get(os.path.splitext(str(path))[1].lower(), _BINARY_BYTES)


def _noise(v: Mapping[str, Any]) -> Estimate | None:
    spec = str(v.get("taus") or "octave").strip()
    samples = _samples_in(v.get("file"))
    half = max(samples / 2.0, 1.0)  # the largest cluster of the overlapping Allan variance
    if spec == "all":
        n_req = n_tau = half
    elif spec.startswith("log:") and spec[4:].strip().isdigit():
        n_req = float(spec[4:].strip())  # the grid is built at this size, then cut to the record
        n_tau = min(n_req, half) if samples else n_req
    elif spec == "decade":
        n_req = n_tau = 3 * math.log10(half) + 1
    else:
        n_req = n_tau = math.log2(half) + 1
    return Estimate(f"noise --taus {spec}: {n_req:.3g} averaging times of about {samples:.3g} samples",
                    n_req * 6 * 8 * 16.0 + 4 * 8 * n_tau**2,
                    n_req * 6 * min(samples, 1e7) * 1e-9 + _FIT_SECONDS * n_tau**1.5)


#: command path -> estimator of its request (None: nothing to estimate for these options).
ESTIMATORS: dict[str, Callable[[Mapping[str, Any]], Estimate | None]] = {
    "simulate": _simulate,
    "batch simulate": _batch_simulate,
    "gins simulate": _gins,
    "gins outage-test": _gins,
    "attitude montecarlo": _attitude_mc,
    "attitude benchmark": _attitude_benchmark,
    "airdata simulate": _airdata_simulate,
    "airdata faults": _airdata_runs(2e-3),
    "airdata thesis": _airdata_runs(5e-2),
    "noise": _noise,
    "zupt train": _zupt_train,
}


def check_limits(command_path: str, values: Mapping[str, Any]) -> Estimate | None:
    """Refuse a request that needs far more memory or time than the reference machine has.

    Parameters
    ----------
    command_path : str
        The command's words after ``imunav``.
    values : mapping
        Parameter name -> parsed value; ``force`` True skips the refusal.

    Returns
    -------
    Estimate or None
        The estimate (None for a command without an estimator).

    Raises
    ------
    InvalidInputError
        With the estimate, when the request is beyond :data:`MEMORY` or :data:`TIME` and ``force`` is not set.

    Warns
    -----
    ImunavWarning
        With the estimate, when the request will take longer than :data:`NOTICE` (so that a long run is not
        silent), or is beyond the limits and forced.
    """
    fn = ESTIMATORS.get(command_path)
    if fn is None:
        return None
    try:
        est = fn(values)
    except (TypeError, ValueError, OverflowError):
        return None
    if est is None:
        return est
    what = est.what if est.what.startswith(command_path) else f"{command_path}: {est.what}"
    beyond = not (est.bytes <= MEMORY and est.seconds <= TIME) or not (math.isfinite(est.bytes) and math.isfinite(est.seconds))
    if beyond and values.get("force"):  # run as asked, but not without a word
        warnings.warn(f"{what}: about {_size(est.bytes)} of memory and {_time(est.seconds)} on the reference machine "
                      f"({_size(MACHINE_MEMORY)}, {MACHINE_CORES} cores), beyond its limits: running as --force asks "
                      "(a progress bar on a terminal; Ctrl-C stops it)", ImunavWarning, stacklevel=2)
        return est
    if beyond:
        raise InvalidInputError(
            f"{what}: about {_size(est.bytes)} of memory and {_time(est.seconds)} on the reference machine "
            f"({_size(MACHINE_MEMORY)}, {MACHINE_CORES} cores); reduce the request, or pass --force to run it anyway")
    if est.seconds > NOTICE:
        warnings.warn(f"{what}: about {_time(est.seconds)} on the reference machine ({_size(est.bytes)} of memory) "
                      "before any result; reduce the request to go faster (see the option's --help)", ImunavWarning, stacklevel=2)
    return est
