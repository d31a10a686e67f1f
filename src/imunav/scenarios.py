"""Monte Carlo scenario functions for :func:`imunav.montecarlo.run_montecarlo`.

Scenario functions must be module-level (workers import them by name).  This
module adapts scenarios that live in the capability packages to the
``f(rngs, **kw) -> [{name: value}, ...]`` batched form, so that any executor
(local processes, Dask) gives the same numbers for the same seed.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

__all__ = ["attitude_paper"]


def attitude_paper(
    rngs: Sequence[np.random.Generator],
    *,
    filters: Sequence[str] = ("proposed",),
    duration: float | None = None,
    gyro_noise_unit: str | None = None,
) -> list[dict[str, Any]]:
    """Batched Monte Carlo runs of the Candan & Söken scenario (:mod:`imunav.attitude.scenario`).

    Each run simulates the 245 s straight-road drive with its own generator and
    runs the named gravity-vector Kalman filters (``"proposed"``, ``"lee"``,
    ``"javed"``); it returns per filter the pitch and roll RMSE in degrees, the metric of Table 2 of
    Candan & Söken, UHUK-2020-173 (Ulusal Havacılık ve Uzay Konferansı, 2020).  Filters are built once per
    batch.

    Parameters
    ----------
    rngs : sequence of numpy.random.Generator
        One generator per run (seeded by the Monte Carlo runner).
    filters : sequence of str
        Filters to run, from ``"proposed"``, ``"lee"``, ``"javed"``.
    duration : float, optional
        Scenario length, s (default: the paper's 245 s).
    gyro_noise_unit : str, optional
        Reading of the paper's gyro-noise unit (see :class:`imunav.attitude.scenario.PaperScenario`).

    Returns
    -------
    list of dict
        One dict per run: ``<filter>_pitch_rmse_deg`` and ``<filter>_roll_rmse_deg``, degrees.

    Raises
    ------
    ConfigError
        If a filter name is unknown.
    """
    from imunav.attitude.gravity_kf import roll_pitch_from_x
    from imunav.attitude.metrics import euler_rmse
    from imunav.attitude.scenario import PaperScenario, default_filters, simulate

    kw: dict[str, Any] = {}
    if duration is not None:
        kw["duration"] = float(duration)
    if gyro_noise_unit is not None:
        kw["gyro_noise_unit"] = gyro_noise_unit
    scn = PaperScenario(**kw)
    every = default_filters(scn)
    unknown = [f for f in filters if f not in every]
    if unknown:
        from imunav.errors import ConfigError

        raise ConfigError(f"unknown attitude filter(s) {unknown}; choose from {sorted(every)}")
    out = []
    for g in rngs:
        data, truth = simulate(scn, g)
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
