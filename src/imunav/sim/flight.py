"""The flight simulator (thesis aircraft, air data, Doppler radar): moved to :mod:`imunav.airdata.flight`,
beside the air-data and Doppler models it uses and the scenarios that use it; re-exported here."""

from imunav.airdata.flight import (
    CHARLIE_STATES,
    TURBULENCE_SIGMA,
    FlightConfig,
    FlightData,
    LinearAircraftFlight,
    charlie_model,
    dryden_gusts,
    simulate_flight,
    simulate_linear_aircraft,
)

__all__ = ["CHARLIE_STATES", "charlie_model", "LinearAircraftFlight", "simulate_linear_aircraft", "dryden_gusts",
           "TURBULENCE_SIGMA", "FlightConfig", "FlightData", "simulate_flight"]
