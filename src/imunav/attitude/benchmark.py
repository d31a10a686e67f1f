"""BROAD benchmark runner and parameter grid search (processes on all cores).

``evaluate`` runs one filter with one parameter set on every trial and
returns the BROAD per-trial RMSE (:mod:`imunav.attitude.metrics`);
``grid_search`` evaluates the Cartesian product of parameter values, one
parameter set per task, in a process pool whose workers load the trials once.
The trial-agnostic best set (TAGP, Laidig et al. 2021) minimises the mean total
RMSE over the trials; that mean is an in-sample figure.  ``cv_grid_search``
scores the same choice out of fold (leave one trial out, :mod:`imunav.crossval`):
the figure to expect on trials the parameters never saw.
"""

from __future__ import annotations

import inspect
import itertools
import math
import os
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterable

import numpy as np

from imunav.attitude import adaptive, complementary, madgwick, mahony, mekf, smoother, ukf
from imunav.attitude.alignment import broad_reference_start
from imunav.attitude.metrics import attitude_rmse
from imunav.crossval import CvResult, select_by_cv
from imunav.errors import ConfigError
from imunav.io.broad import load_broad
from imunav.results import Result
from imunav.vocabulary import renamed_hint

if TYPE_CHECKING:  # the noise package imports scipy.stats: a configuration does not need it
    from imunav.noise.profile import NoiseProfile

__all__ = ["FILTERS", "REALTIME", "NOISE_FILTERS", "make_filter", "noise_parameters", "evaluate", "grid_search", "cv_grid_search", "TrialScore",
           "BenchResult", "reference_start"]

REALTIME = ("madgwick", "madgwick_c", "mahony", "complementary", "mekf", "adaptive", "ukf")
FILTERS = (*REALTIME, "smoother")


def make_filter(name: str, params: dict[str, Any] | None = None) -> Any:
    """Filter object by name with parameter overrides.

    Parameters
    ----------
    name : str
        ``"complementary"``, ``"mahony"``, ``"madgwick"``, ``"madgwick_c"``, ``"mekf"``, ``"adaptive"``,
        ``"ukf"`` or ``"smoother"``.
    params : dict, optional
        Parameter overrides (the filter's fields, SI).

    Returns
    -------
    object
        The filter, with ``run(data)``.

    Raises
    ------
    ConfigError
        If the name or a parameter is unknown.
    """

    p = dict(params or {})
    if name in FILTERS:
        _check_params(name, p)
    try:
        if name == "madgwick":
            return madgwick.Madgwick(**{"beta": 0.1, **p})
        if name == "madgwick_c":
            return madgwick.Madgwick(**{"beta": 0.12, **p}, original_c=True)
        if name == "mahony":
            return mahony.Mahony(**{"kp": 0.74, "ki": 0.0012, **p})
        if name == "complementary":
            return complementary.Complementary(**p)
        if name == "mekf":
            return mekf.MEKF(replace(mekf.MekfConfig(), **p))
        if name == "adaptive":
            return adaptive.AdaptiveMEKF(replace(adaptive.ADAPTIVE_DEFAULTS, **p))
        if name == "smoother":
            return smoother.Smoother(replace(smoother.SMOOTHER_DEFAULTS, **p))
        if name == "ukf":
            return ukf.UKF(replace(ukf.UkfConfig(), **p))
    except TypeError as exc:
        raise ConfigError(f"bad parameter for filter {name!r}: {exc}") from exc
    raise ConfigError(f"unknown filter {name!r}; choose one of {', '.join(FILTERS)}")


#: The filters whose configuration takes noise parameters (:func:`noise_parameters`).
NOISE_FILTERS = ("mekf", "adaptive", "smoother", "ukf")


def noise_parameters(name: str, profile: NoiseProfile, fs: float | None = None,
                     combine: str = "max") -> dict[str, float]:
    """The parameters of filter ``name`` that a noise profile sets (``--noise`` of ``imunav attitude run``).

    The filter's default configuration goes through its ``from_noise_profile``
    (:meth:`~imunav.attitude.mekf.MekfConfig.from_noise_profile` for the MEKF, the adaptive MEKF and the smoother,
    :meth:`~imunav.attitude.ukf.UkfConfig.from_noise_profile` for the UKF); the fields it changed come back as
    :func:`make_filter` overrides.

    Parameters
    ----------
    name : str
        A filter of :data:`NOISE_FILTERS`.
    profile : NoiseProfile
        The sensor's noise profile.
    fs : float, optional
        Sample rate of the recording the filter will run on, Hz (default the profile's).
    combine : {"max", "mean"}
        One value for the three axes.

    Returns
    -------
    dict
        Field name -> value (SI), e.g. ``gyro_noise_density``.

    Raises
    ------
    ConfigError
        If the filter takes no noise parameters, or the profile lacks a sensor it needs.
    """
    bases = {"mekf": lambda: mekf.MekfConfig(), "adaptive": lambda: adaptive.ADAPTIVE_DEFAULTS,
             "smoother": lambda: smoother.SMOOTHER_DEFAULTS, "ukf": lambda: ukf.UkfConfig()}
    if name not in bases:
        raise ConfigError(f"filter {name!r} takes no noise parameters (fixed gains); a noise profile drives "
                          f"{', '.join(NOISE_FILTERS)}")
    base = bases[name]()
    cfg = type(base).from_noise_profile(profile, base=base, fs=fs, combine=combine)
    return {f.name: getattr(cfg, f.name) for f in fields(cfg) if getattr(cfg, f.name) != getattr(base, f.name)}


def filter_parameters(name: str) -> dict[str, Any]:
    """The parameters a filter takes (``--param NAME=VALUE``), with their defaults.

    Parameters
    ----------
    name : str
        A filter name of :data:`FILTERS`.

    Returns
    -------
    dict
        Parameter name -> default value (``inspect.Parameter.empty`` when it has none).

    Raises
    ------
    ConfigError
        If the name is unknown.
    """
    configs = {"mekf": lambda: mekf.MekfConfig(), "adaptive": lambda: adaptive.ADAPTIVE_DEFAULTS,
               "smoother": lambda: smoother.SMOOTHER_DEFAULTS, "ukf": lambda: ukf.UkfConfig()}
    classes = {"madgwick": madgwick.Madgwick, "madgwick_c": madgwick.Madgwick, "mahony": mahony.Mahony,
               "complementary": complementary.Complementary}
    if name in configs:
        cfg = configs[name]()
        return {f.name: getattr(cfg, f.name) for f in fields(cfg)}
    if name in classes:
        sig = inspect.signature(classes[name])
        out = {k: v.default for k, v in sig.parameters.items()
               if v.kind in (v.POSITIONAL_OR_KEYWORD, v.KEYWORD_ONLY)}
        if name == "madgwick_c":
            out.pop("original_c", None)
        return out
    raise ConfigError(f"unknown filter {name!r}; choose one of {', '.join(FILTERS)}")


def _check_params(name: str, p: dict[str, Any]) -> None:
    """Unknown parameters are listed with the known ones; a number where the default is a number must be finite."""
    known = filter_parameters(name)
    unknown = sorted(set(p) - set(known))
    if unknown:
        cls = {"mekf": "MekfConfig", "adaptive": "MekfConfig", "smoother": "MekfConfig",
               "ukf": "UkfConfig"}.get(name, "")
        raise ConfigError(f"filter {name!r} has no parameter {', '.join(map(repr, unknown))}"
                          f"{renamed_hint(cls, unknown)}; its parameters are: {', '.join(sorted(known))}")
    for k, v in p.items():
        d = known[k]
        if isinstance(d, bool):
            if not isinstance(v, bool):
                raise ConfigError(f"filter {name!r} parameter {k!r} is true or false, got {v!r}")
        elif isinstance(d, (int, float)) and d is not None:
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ConfigError(f"filter {name!r} parameter {k!r} is a finite number (default {d!r}), got {v!r}")


def reference_start(name: str) -> bool:
    """Whether a filter is started like the BROAD reference runs (Madgwick and Mahony).

    Parameters
    ----------
    name : str
        Filter name.

    Returns
    -------
    bool
        True for the filters that start from :func:`imunav.attitude.alignment.broad_reference_start`.
    """
    return name in ("madgwick_c", "mahony")


@dataclass(frozen=True)
class TrialScore:
    """BROAD score of one filter on one trial.

    Attributes
    ----------
    trial : str
        Trial name.
    total_rmse_deg, heading_rmse_deg, inclination_rmse_deg : float
        RMSE of the error angles over the movement samples, degrees.
    seconds : float
        Run time of the filter, s.
    """
    trial: str
    total_rmse_deg: float
    heading_rmse_deg: float
    inclination_rmse_deg: float
    seconds: float


@dataclass(frozen=True)
class BenchResult(Result):
    """Scores of one filter and parameter set over the trials.

    Attributes
    ----------
    filter : str
        Filter name.
    params : dict
        The parameter overrides used.
    trials : list of TrialScore
        One score per trial.
    """
    filter: str
    params: dict[str, Any]
    trials: list[TrialScore]

    @property
    def mean_total(self) -> float:
        return float(np.mean([t.total_rmse_deg for t in self.trials]))

    def means(self) -> dict[str, float]:
        """Mean of each RMSE over the trials.

        Returns
        -------
        dict of str to float
            ``total_rmse_deg``, ``heading_rmse_deg``, ``inclination_rmse_deg``, degrees.
        """
        return {k: float(np.mean([getattr(t, k) for t in self.trials]))
                for k in ("total_rmse_deg", "heading_rmse_deg", "inclination_rmse_deg")}

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary.

        Returns
        -------
        dict
            ``filter``, ``params``, ``mean`` (:meth:`means`) and ``trials`` keyed by trial name.
        """
        return {"filter": self.filter, "params": self.params, "mean": self.means(),
                "trials": {t.trial: {"total_rmse_deg": t.total_rmse_deg, "heading_rmse_deg": t.heading_rmse_deg,
                                     "inclination_rmse_deg": t.inclination_rmse_deg, "seconds": t.seconds}
                           for t in self.trials}}


_CACHE: dict[str, Any] = {}


def _load(path: str):
    if path not in _CACHE:
        _CACHE[path] = load_broad(path)
    return _CACHE[path]


def _score_trial(name: str, params: dict[str, Any], path: str) -> TrialScore:
    tr = _load(path)
    f = make_filter(name, params)
    q0 = broad_reference_start(tr.imu.accel[0], tr.imu.mag[0]) if reference_start(name) else None
    t0 = time.perf_counter()
    r = f.run(tr.imu, q0=q0)
    sec = time.perf_counter() - t0
    e = attitude_rmse(r.q_nb, tr.q_ref_nb, tr.movement)
    return TrialScore(tr.name, e.total_rmse_deg, e.heading_rmse_deg, e.inclination_rmse_deg, sec)


def evaluate(name: str, params: dict[str, Any] | None, trials: Iterable[str | Path]) -> BenchResult:
    """Run filter ``name`` with one parameter set on every trial file.

    Parameters
    ----------
    name : str
        Filter name (see :func:`make_filter`).
    params : dict or None
        Parameter overrides.
    trials : iterable of str or pathlib.Path
        BROAD trial files (``.mat``; Laidig et al. 2021).

    Returns
    -------
    BenchResult
        Per-trial BROAD RMSE (degrees) and run time.
    """
    p = dict(params or {})
    return BenchResult(name, p, [_score_trial(name, p, str(t)) for t in trials])


def _task(args: tuple[str, dict[str, Any], list[str]]) -> BenchResult:
    name, params, trials = args
    return evaluate(name, params, trials)


def grid_search(name: str, grid: dict[str, list[Any]], trials: Iterable[str | Path], *,
                workers: int | None = None, progress: Callable[[int, int], None] | None = None
                ) -> list[BenchResult]:
    """Evaluate every parameter combination of ``grid``; sorted by mean total RMSE.

    ``workers`` processes (default: all cores); each task is one parameter set
    over all trials, so a worker's trial cache is reused across tasks.

    Parameters
    ----------
    name : str
        Filter name (see :func:`make_filter`).
    grid : dict of str to list
        Values of each parameter; every combination is evaluated.
    trials : iterable of str or pathlib.Path
        BROAD trial files (``.mat``; Laidig et al. 2021).
    workers : int, optional
        Number of processes (default: all cores).
    progress : callable, optional
        Called as ``progress(done, total)`` after each parameter set.

    Returns
    -------
    list of BenchResult
        One per combination, best (lowest mean total RMSE) first.

    Raises
    ------
    ConfigError
        If the grid is empty (an unknown parameter fails in :func:`make_filter`).
    """
    if not grid:
        raise ConfigError("empty parameter grid; give at least one parameter with a list of values")
    keys = list(grid)
    combos = [dict(zip(keys, vals)) for vals in itertools.product(*(grid[k] for k in keys))]
    tl = [str(t) for t in trials]
    make_filter(name, combos[0])  # validate names early
    n = workers or os.cpu_count() or 1
    out: list[BenchResult] = []
    if n == 1:
        for i, c in enumerate(combos):
            out.append(evaluate(name, c, tl))
            if progress:
                progress(i + 1, len(combos))
    else:
        with ProcessPoolExecutor(max_workers=n) as ex:
            for i, r in enumerate(ex.map(_task, [(name, c, tl) for c in combos])):
                out.append(r)
                if progress:
                    progress(i + 1, len(combos))
    return sorted(out, key=lambda r: r.mean_total)


def cv_grid_search(name: str, grid: dict[str, list[Any]], trials: Iterable[str | Path], *,
                   workers: int | None = None, progress: Callable[[int, int], None] | None = None,
                   results: list[BenchResult] | None = None, metric: str = "total_rmse_deg"
                   ) -> tuple[CvResult, list[BenchResult]]:
    """Grid search scored by leave-one-trial-out cross-validation.

    Each trial is scored with the parameter set that minimises the mean total
    RMSE over the *other* trials (:func:`imunav.crossval.select_by_cv`).

    Parameters
    ----------
    name : str
        Filter name (see :func:`make_filter`).
    grid : dict of str to list
        Values of each parameter.
    trials : iterable of str or pathlib.Path
        BROAD trial files.
    workers : int, optional
        Number of processes (default: all cores).
    progress : callable, optional
        Called as ``progress(done, total)``.
    results : list of BenchResult, optional
        The grid's results when already computed (skips the runs).
    metric : str, optional
        The score chosen on and reported: ``"total_rmse_deg"`` (default), ``"inclination_rmse_deg"`` (6D, where
        the heading is unobservable) or ``"heading_rmse_deg"``.

    Returns
    -------
    (CvResult, results)
        ``CvResult.oof`` per trial score (``metric``) out of fold, ``in_sample`` that of
        the overall best set; ``fold_choice`` / ``in_sample_choice`` are
        parameter dicts.  ``results`` as :func:`grid_search` (best first).

    Raises
    ------
    ConfigError
        If ``results`` do not score the same trials in the same order, the grid is empty or ``metric`` is unknown.
    """
    if metric not in ("total_rmse_deg", "inclination_rmse_deg", "heading_rmse_deg"):
        raise ConfigError(f"unknown metric {metric!r}; use total_rmse_deg, inclination_rmse_deg or heading_rmse_deg")
    tl = [str(t) for t in trials]
    res = results if results is not None else grid_search(name, grid, tl, workers=workers, progress=progress)
    names = [t.trial for t in res[0].trials]
    if any([t.trial for t in r.trials] != names for r in res):
        raise ConfigError("cv_grid_search: the results do not score the same trials in the same order")
    S = np.array([[getattr(t, metric) for t in r.trials] for r in res])
    cv = select_by_cv(S, names, items=names)
    return replace(cv, fold_choice={g: res[j].params for g, j in cv.fold_choice.items()},
                   in_sample_choice=res[cv.in_sample_choice].params), res
