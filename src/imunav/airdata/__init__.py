"""Air data, Doppler radar and wind estimation.

* the ISA (0-47 km) and pressure altitude are :mod:`imunav.atmosphere` (core: the log readers need them), re-exported here.
* :mod:`~imunav.airdata.airdata` - air-data computer: Mach (subsonic and
  Rayleigh supersonic pitot), CAS, TAS, SAT, density, α/β, TAS into body axes.
* :mod:`~imunav.airdata.doppler` - 3/4-beam Janus geometry, Doppler shifts,
  least-squares velocity, bias / scale / noise / over-water errors.
* :mod:`~imunav.airdata.wind` - the wind triangle.
* :mod:`~imunav.airdata.filter` - the thesis's 6-state wind filter (Akgün
  2002) with a fixed sign convention (``V_G = V_A + W``, ``z = V_D − V_A``)
  and a long-horizon navigation-frame variant for real flights.
* :mod:`~imunav.airdata.scenario` - the thesis scenarios and Monte Carlo.
* :mod:`~imunav.airdata.flightfile` - the flight file of ``imunav airdata simulate`` / ``run`` and the wind
  errors of a filter run over one.
* :mod:`~imunav.airdata.plot` - figures (compute code never plots).
"""

from __future__ import annotations

from imunav.airdata.airdata import (
    AirData,
    air_data,
    aoa_sideslip,
    calibrated_airspeed,
    mach_from_pressures,
    pitot_ratio,
    static_temperature,
    tas_to_body,
    total_temperature,
    true_airspeed,
)
from imunav.airdata.doppler import (
    DopplerErrors,
    DopplerMeasurement,
    janus_beams,
    simulate_doppler,
    velocity_from_beams,
)
from imunav.airdata.filter import (
    BodyWindFilter,
    BodyWindFilterConfig,
    BodyWindState,
    LongHorizonConfig,
    LongHorizonFilter,
    LongHorizonResult,
    LongHorizonState,
    WindFilterResult,
    body_wind_matrices,
    iteration_row,
)
from imunav.airdata.scenario import (
    WindMonteCarlo,
    WindScenario,
    WindScenarioData,
    covariance_sequence,
    simulate_wind_scenario,
    wind_monte_carlo,
    wind_scenario_report,
)
from imunav.airdata.wind import heading_for_course, wind_from_speeds, wind_from_velocities, wind_speed_direction
from imunav.atmosphere import IsaState, isa, pressure_altitude

__all__ = [
    "isa",
    "IsaState",
    "pressure_altitude",
    "air_data",
    "AirData",
    "mach_from_pressures",
    "pitot_ratio",
    "calibrated_airspeed",
    "static_temperature",
    "total_temperature",
    "true_airspeed",
    "aoa_sideslip",
    "tas_to_body",
    "janus_beams",
    "velocity_from_beams",
    "simulate_doppler",
    "DopplerErrors",
    "DopplerMeasurement",
    "wind_from_velocities",
    "wind_from_speeds",
    "wind_speed_direction",
    "heading_for_course",
    "BodyWindFilterConfig",
    "body_wind_matrices",
    "iteration_row",
    "BodyWindFilter",
    "BodyWindState",
    "WindFilterResult",
    "LongHorizonConfig",
    "LongHorizonResult",
    "LongHorizonFilter",
    "LongHorizonState",
    "WindScenario",
    "WindScenarioData",
    "simulate_wind_scenario",
    "covariance_sequence",
    "wind_monte_carlo",
    "WindMonteCarlo",
    "wind_scenario_report",
]
