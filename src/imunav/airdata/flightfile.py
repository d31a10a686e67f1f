"""The air-data flight file, and the wind errors of a filter run over one.

A flight file is what ``imunav airdata simulate`` writes and ``imunav airdata run`` reads: a compressed NumPy
archive (``.npz``, no pickled objects) holding

* ``meta``: a JSON string ``{"type": "thesis" | "flight", "scenario" | "config": {...}, "seed": int}``: the
  scenario (:meth:`WindScenario.to_dict <imunav.airdata.scenario.WindScenario>`) of a thesis run, the
  :class:`~imunav.airdata.flight.FlightConfig` of a flight;
* the arrays of the run, in SI, angles in rad:

  - thesis (:class:`~imunav.airdata.scenario.WindScenarioData`): ``t``, ``x_true``, ``wind_true``, ``v_true``, ``v_ads``,
    ``v_doppler``, ``z``, ``ads_noise``, ``anomaly``;
  - flight (:class:`~imunav.airdata.flight.FlightData`): every array of the flight (``t``, ``position_ned``,
    ``velocity_ned``, ``wind_ned``, ``euler``, ..., ``t_ads``, ``v_ads_body``, ``euler_ads``, ``t_doppler``,
    ``v_doppler_body``, ``euler_doppler``, ...).

:func:`simulate_flight_file` makes one, :func:`write_flight_file` / :func:`read_flight_file` store and load it,
and :func:`wind_errors` runs the wind filter of its type over it and scores the estimates against its truth;
:func:`write_wind_estimates` stores the estimates (``imunav airdata run --out``: a compressed ``.npz`` of the
arrays of :attr:`WindErrors.arrays`).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav.airdata.filter import BodyWindFilter, LongHorizonConfig, LongHorizonFilter, iteration_row
from imunav.airdata.flight import FlightConfig, simulate_flight
from imunav.airdata.scenario import WindScenario, simulate_wind_scenario
from imunav.errors import FileFormatError
from imunav.files import atomic_path
from imunav.io._common import wrap_read_errors
from imunav.rotation import dcm_from_euler

__all__ = ["FlightFile", "WindErrors", "FILE_TYPES", "THESIS_ARRAYS", "simulate_flight_file", "write_flight_file",
           "read_flight_file", "wind_errors", "write_wind_estimates"]

Array = NDArray[np.float64]

#: The two kinds of flight file.
FILE_TYPES = ("thesis", "flight")
#: Arrays of a thesis file (the array fields of :class:`~imunav.airdata.scenario.WindScenarioData`).
THESIS_ARRAYS = ("t", "x_true", "wind_true", "v_true", "v_ads", "v_doppler", "z", "ads_noise", "anomaly")


@dataclass(frozen=True)
class FlightFile:
    """The content of a flight file (see the module docstring).

    Attributes
    ----------
    kind : {"thesis", "flight"}
        The file's type (``meta["type"]``).
    meta : dict
        The ``meta`` entry: type, scenario or flight configuration, seed.
    arrays : dict of str to numpy.ndarray
        The run's arrays, SI, angles in rad.
    source : str
        Where it was read from ("" for a simulated one not yet written).
    """

    kind: str
    meta: dict[str, Any]
    arrays: dict[str, np.ndarray] = field(repr=False)
    source: str = ""

    def summary(self, path: str | os.PathLike[str]) -> dict[str, Any]:
        """The JSON summary ``imunav airdata simulate`` prints for this file written to ``path``.

        Parameters
        ----------
        path : str or os.PathLike
            Where the file is written.

        Returns
        -------
        dict
            Thesis: ``file``, ``type``, ``kind`` (the scenario kind), ``steps``, ``seed``; flight: ``file``,
            ``type``, ``profile``, ``duration_s``, ``ads_samples``, ``doppler_samples``, ``seed``.
        """
        seed = self.meta["seed"]
        if self.kind == "thesis":
            return {"file": str(path), "type": "thesis", "kind": self.meta["scenario"]["kind"],
                    "steps": int(self.arrays["t"].size), "seed": seed}
        cfg = self.meta["config"]
        return {"file": str(path), "type": "flight", "profile": cfg["profile"], "duration_s": cfg["duration"],
                "ads_samples": int(self.arrays["t_ads"].size), "doppler_samples": int(self.arrays["t_doppler"].size),
                "seed": seed}


def simulate_flight_file(scenario: WindScenario | FlightConfig, seed: int = 0) -> FlightFile:
    """Simulate the run of a flight file: a thesis scenario or a flight.

    Parameters
    ----------
    scenario : WindScenario or FlightConfig
        A thesis scenario (:func:`~imunav.airdata.scenario.simulate_wind_scenario`) or a flight
        (:func:`~imunav.airdata.flight.simulate_flight`).
    seed : int, optional
        Random seed (stored in ``meta``).

    Returns
    -------
    FlightFile
        Its ``meta`` and arrays.
    """
    if isinstance(scenario, WindScenario):
        d = simulate_wind_scenario(scenario, rng=seed)
        return FlightFile("thesis", {"type": "thesis", "scenario": d.scenario.to_dict(), "seed": seed},
                          {k: getattr(d, k) for k in THESIS_ARRAYS})
    f = simulate_flight(scenario, rng=seed)
    return FlightFile("flight", {"type": "flight", "config": scenario.to_dict(), "seed": seed},
                      {k: v for k, v in f.__dict__.items() if isinstance(v, np.ndarray)})


def write_flight_file(path: str | os.PathLike[str], content: FlightFile) -> Path:
    """Write a flight file (compressed ``.npz``, atomically).

    Parameters
    ----------
    path : str or os.PathLike
        Output file.
    content : FlightFile
        What to write.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        np.savez_compressed(fh, meta=np.array(json.dumps(content.meta)), **content.arrays)
    return Path(path)


def read_flight_file(path: str | os.PathLike[str]) -> FlightFile:
    """Read a flight file written by :func:`write_flight_file` (``imunav airdata simulate``).

    Parameters
    ----------
    path : str or os.PathLike
        The ``.npz`` file.

    Returns
    -------
    FlightFile
        Its type, ``meta`` and arrays.

    Raises
    ------
    FileFormatError
        If the file is missing, is not a NumPy archive, has no ``meta`` entry or is of an unknown type.
    """
    p = Path(path)
    if not p.exists():
        raise FileFormatError(f"{p}: no such file; create one with `imunav airdata simulate`")
    with wrap_read_errors(str(p), "an `imunav airdata simulate` .npz file"), open(p, "rb") as fh, \
            np.load(fh, allow_pickle=False) as z:
        if "meta" not in z:
            raise FileFormatError(f"{p}: not an `imunav airdata simulate` file (no 'meta' entry)")
        meta = json.loads(str(z["meta"]))
        arrays = {k: z[k] for k in z.files if k != "meta"}
    kind = meta.get("type")
    if kind not in FILE_TYPES:
        raise FileFormatError(f"{p}: unknown file type {kind!r}")
    return FlightFile(kind, meta, arrays, str(p))


@dataclass(frozen=True)
class WindErrors:
    """The wind filter of a flight file's type run over it, and its errors against the file's truth.

    Attributes
    ----------
    kind : {"thesis", "flight"}
        The file's type: the thesis's 6-state filter, or the long-horizon navigation-frame filter.
    result : WindFilterResult or LongHorizonResult
        The filter's output (what :func:`imunav.airdata.plot.plot_wind` / ``plot_long_horizon`` draw).
    summary : dict
        The error statistics (the JSON of ``imunav airdata run``). Thesis: ``type``, ``robust``,
        ``wind_rms_per_axis`` (m/s, from thesis iteration 100 on), ``difference_loop_rms_per_axis``,
        ``rejected_samples``, ``final_wind``, ``true_wind``, ``P44_final``; flight: ``type``, ``robust``,
        ``epochs``, ``wind_rms_per_axis`` and ``wind_std_mean`` (after the first 100 epochs),
        ``position_error_end``, ``position_std_end`` (m), ``rejected_samples``.
    arrays : dict of str to numpy.ndarray
        The estimates (what ``imunav airdata run --out`` writes).
    """

    kind: str
    result: Any = field(repr=False)
    summary: dict[str, Any]
    arrays: dict[str, np.ndarray] = field(repr=False)

    def to_dict(self) -> dict[str, Any]:
        """The error statistics (:attr:`summary`).

        Returns
        -------
        dict
            JSON-ready.
        """
        return dict(self.summary)


def _rms(e: Array) -> list[float]:
    return np.sqrt(np.mean(e**2, 0)).tolist()


def wind_errors(content: FlightFile, *, robust: str | None = None, gate_m: float = 2.0,
                alpha: float = 1e-3) -> WindErrors:
    """Run the wind filter of a flight file's type over it and score it against the file's truth.

    A thesis file runs :class:`~imunav.airdata.filter.BodyWindFilter` on ``z`` (with ``v_ads``); a flight file runs
    :class:`~imunav.airdata.filter.LongHorizonFilter` on the multi-rate air-data and Doppler velocities.

    Parameters
    ----------
    content : FlightFile
        The file (:func:`read_flight_file` or :func:`simulate_flight_file`).
    robust : {None, "gate", "nis", "isolate", "huber"}, optional
        Robust update of the filter (None: the plain Kalman update).
    gate_m : float, optional
        Per-channel gate, standard deviations (``robust="gate"``).
    alpha : float, optional
        Test level of the ``nis`` / ``isolate`` gates.

    Returns
    -------
    WindErrors
        The filter's result, the error statistics and the estimates.

    Raises
    ------
    FileFormatError
        If the file lacks an array its type needs.
    InvalidInputError
        If the filter options are invalid.
    """
    d = content.arrays
    try:
        if content.kind == "thesis":
            r = BodyWindFilter(robust=robust, gate_m=gate_m, alpha=alpha).run(d["z"], v_ads=d["v_ads"])
            k0 = iteration_row(100)
            summary = {"type": "thesis", "robust": robust or "none", "wind_rms_per_axis": _rms(r.wind[k0:] - d["wind_true"][k0:]),
                       "difference_loop_rms_per_axis": _rms(d["z"][k0:] - d["wind_true"][k0:]),
                       "rejected_samples": int((r.weights == 0).sum()),
                       "final_wind": r.wind[-1].tolist(), "true_wind": d["wind_true"][-1].tolist(),
                       "P44_final": float(r.cov_diag[-1, 3])}
            arrays = {"wind": r.wind, "P_diag": r.cov_diag, "normalized": r.normalized, "weights": r.weights}
            return WindErrors("thesis", r, summary, arrays)
        r = LongHorizonFilter(LongHorizonConfig(robust=robust, alpha=alpha, gate_m=gate_m)).run(
            d["t_ads"], d["v_ads_body"], d["t_doppler"], d["v_doppler_body"],
            dcm_from_euler(d["euler_doppler"]), dcm_from_euler(d["euler_ads"]))
        wt = np.stack([np.interp(r.t, d["t"], d["wind_ned"][:, i]) for i in range(3)], 1)
        pt = np.stack([np.interp(r.t, d["t"], d["position_ned"][:, i]) for i in range(3)], 1)
    except KeyError as exc:
        raise FileFormatError(f"{content.source or 'the flight file'}: missing entry {exc}") from exc
    skip = min(r.t.size - 1, 100)
    summary = {"type": "flight", "robust": robust or "none", "epochs": int(r.t.size),
               "wind_rms_per_axis": _rms(r.wind[skip:] - wt[skip:]),
               "wind_std_mean": r.wind_std[skip:].mean(0).tolist(),
               "position_error_end": (r.position[-1] - pt[-1]).tolist(),
               "position_std_end": r.position_std[-1].tolist(),
               "rejected_samples": int((r.weights == 0).sum())}
    arrays = {"t": r.t, "wind": r.wind, "wind_std": r.wind_std, "position": r.position,
              "normalized": r.normalized, "weights": r.weights}
    return WindErrors("flight", r, summary, arrays)


def write_wind_estimates(path: str | os.PathLike[str], errors: WindErrors) -> Path:
    """Write the estimates of a wind-filter run (compressed ``.npz``, atomically).

    Thesis: ``wind`` (N, 3) m/s, ``P_diag`` (N, 6), ``normalized`` innovations (N, 3), ``weights`` (N, 3: 0 where
    a robust update rejected the sample); flight: ``t`` s, ``wind``, ``wind_std`` m/s, ``position`` m (NED),
    ``normalized``, ``weights``.

    Parameters
    ----------
    path : str or os.PathLike
        Output file.
    errors : WindErrors
        The run (:func:`wind_errors`).

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        np.savez_compressed(fh, **errors.arrays)
    return Path(path)
