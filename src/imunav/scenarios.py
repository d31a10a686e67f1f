"""Monte Carlo scenario functions for :func:`imunav.lab.montecarlo.run_montecarlo`.

Scenario functions must be module-level (workers import them by name).  This
module adapts scenarios that live in the capability packages to the
``f(rngs, **kw) -> [{name: value}, ...]`` batched form, so that any executor
(local processes, Dask) gives the same numbers for the same seed.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Literal, Sequence

import numpy as np
from numpy.typing import NDArray

from imunav.attitude.gravity_kf import roll_pitch_from_x
from imunav.attitude.metrics import euler_rmse
from imunav.attitude.scenario import PAPER_TABLE2, PaperScenario, default_filters, simulate
from imunav.errors import ConfigError, InvalidInputError

if TYPE_CHECKING:  # the type only: montecarlo is a layer above the scenarios it runs
    from imunav.lab.montecarlo import MonteCarloResult

__all__ = ["attitude_paper", "paper_rmse", "paper_table", "paper_report"]


def attitude_paper(
    rngs: Sequence[np.random.Generator],
    *,
    filters: Sequence[str] = ("proposed",),
    duration: float | None = None,
    gyro_noise_unit: str | None = None,
    seeding: Literal["generator", "seed_word"] = "generator",
) -> list[dict[str, Any]]:
    """Batched Monte Carlo runs of the Candan & Söken scenario (:mod:`imunav.attitude.scenario`).

    Each run simulates the 245 s straight-road drive with its own generator and
    runs the named gravity-vector Kalman filters (``"proposed"``, ``"lee"``,
    ``"javed"``); it returns per filter the pitch and roll RMSE in degrees
    (``<filter>_pitch_rmse_deg``, ``<filter>_roll_rmse_deg``), the paper's
    Table 2 metric.  Filters are built once per batch.

    Parameters
    ----------
    rngs : sequence of numpy.random.Generator
        One generator per run (from :func:`imunav.lab.montecarlo.spawn_generators`).
    filters : sequence of str
        Filter names, in the order of the result columns.
    duration : float, optional
        Scenario length [s] (default: the paper's 245 s).
    gyro_noise_unit : str, optional
        Reading of the paper's gyro noise figure (see :class:`~imunav.attitude.scenario.PaperScenario`).
    seeding : {"generator", "seed_word"}
        ``"generator"``: the run simulates with its generator (``imunav attitude montecarlo``).
        ``"seed_word"``: with ``numpy.random.default_rng(w)``, ``w`` the first 32-bit word of the
        generator's ``SeedSequence`` — the seeding of the lab's Table 2 since its first version, kept
        so that its figures do not change.

    Returns
    -------
    list of dict
        One row of RMSEs per run.

    Raises
    ------
    InvalidInputError
        If ``seeding`` is neither ``"generator"`` nor ``"seed_word"``.
    ConfigError
        If a name of ``filters`` is not one of the scenario's filters.
    """
    if seeding not in ("generator", "seed_word"):
        raise InvalidInputError(f"seeding={seeding!r}: choose 'generator' or 'seed_word'")

    kw: dict[str, Any] = {}
    if duration is not None:
        kw["duration"] = float(duration)
    if gyro_noise_unit is not None:
        kw["gyro_noise_unit"] = gyro_noise_unit
    scn = PaperScenario(**kw)
    every = default_filters(scn)
    unknown = [f for f in filters if f not in every]
    if unknown:

        raise ConfigError(f"unknown attitude filter(s) {unknown}; choose from {sorted(every)}")
    out = []
    for g in rngs:
        data, truth = simulate(scn, g if seeding == "generator" else int(g.bit_generator.seed_seq.generate_state(1)[0]))
        row: dict[str, Any] = {}
        for name in filters:
            # roll / pitch straight from the filter state (eqs. 4-5): the quaternion
            # round trip of AttitudeResult.euler() gives the same angles at ~9 ms a run more
            rp = roll_pitch_from_x(every[name].run(data).flags["x"])
            roll, pitch = euler_rmse(rp, truth[:, :2])
            row[f"{name}_pitch_rmse_deg"] = float(pitch)
            row[f"{name}_roll_rmse_deg"] = float(roll)
        out.append(row)
    return out


def paper_rmse(mc: MonteCarloResult) -> dict[str, NDArray[np.float64]]:
    """Per-run RMSE [deg] of each filter, ``(n_runs, 2)`` = (pitch, roll), from a Monte Carlo of
    :func:`imunav.scenarios.attitude_paper` (its ``<filter>_pitch_rmse_deg`` / ``_roll_rmse_deg`` columns).

    Parameters
    ----------
    mc : imunav.lab.montecarlo.MonteCarloResult
        The result of ``run_montecarlo(attitude_paper, ...)``.

    Returns
    -------
    dict
        Filter name (in the order of the columns) to its ``(n_runs, 2)`` array.
    """
    m = mc.metrics
    names = [c[: -len("_pitch_rmse_deg")] for c in m.columns if c.endswith("_pitch_rmse_deg")]
    return {k: np.column_stack([m[f"{k}_pitch_rmse_deg"].to_numpy(), m[f"{k}_roll_rmse_deg"].to_numpy()])
            for k in names}


def paper_table(mc: MonteCarloResult) -> dict[str, dict[str, float]]:
    """The paper's Table 2 from a Monte Carlo: mean, standard deviation (ddof 0) and 95th percentile
    of the pitch and roll RMSE [deg] of each filter.

    Parameters
    ----------
    mc : imunav.lab.montecarlo.MonteCarloResult
        The result of ``run_montecarlo(attitude_paper, ...)``.

    Returns
    -------
    dict
        ``{filter: {"pitch_mean", "pitch_std", "pitch_p95", "roll_mean", "roll_std", "roll_p95"}}``.
    """
    out = {}
    for k, v in paper_rmse(mc).items():
        out[k] = {"pitch_mean": float(v[:, 0].mean()), "pitch_std": float(v[:, 0].std()),
                  "pitch_p95": float(np.percentile(v[:, 0], 95)), "roll_mean": float(v[:, 1].mean()),
                  "roll_std": float(v[:, 1].std()), "roll_p95": float(np.percentile(v[:, 1], 95))}
    return out


def paper_report(mc: MonteCarloResult, scn: Any, filters: Mapping[str, Any]) -> dict[str, Any]:
    """The JSON document of ``imunav attitude montecarlo --json``: Table 2, the paper's values, the per-run
    RMSEs, the filter parameters and the scenario.

    Parameters
    ----------
    mc : imunav.lab.montecarlo.MonteCarloResult
        The result of ``run_montecarlo(attitude_paper, ...)``.
    scn : PaperScenario
        The scenario that was run.
    filters : dict
        The filters that were run (name to :class:`~imunav.attitude.gravity_kf.GravityKF`).

    Returns
    -------
    dict
        ``{"table", "paper_table2", "rmse", "params", "scenario"}``.
    """
    return {"table": paper_table(mc),
            "paper_table2": {k: {"pitch": v[0], "roll": v[1]} for k, v in PAPER_TABLE2.items()},
            "rmse": {k: v.tolist() for k, v in paper_rmse(mc).items()},
            "params": {k: f.config.__dict__ | {"kind": f.kind} for k, f in filters.items()},
            "scenario": {k: getattr(scn, k) for k in scn.__dataclass_fields__}}
