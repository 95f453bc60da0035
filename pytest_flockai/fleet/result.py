"""Moved to ``pytest_flockai.fleet.fleet_result``; the old path warns once per name
(``_deprecation.py``) and will be removed."""

from .._deprecation import moved

__getattr__ = moved(__name__, {
    "FleetResult": "pytest_flockai.fleet.fleet_result.FleetResult",
    "FlightResult": "pytest_flockai.fleet.fleet_result.FlightResult",
    "MAX_GRID": "pytest_flockai.fleet.fleet_result.MAX_GRID",
    "SEPARATION_HZ": "pytest_flockai.fleet.fleet_result.SEPARATION_HZ",
    "Separation": "pytest_flockai.fleet.fleet_result.Separation",
    "TAKEOFF": "pytest_flockai.fleet.fleet_result.TAKEOFF",
    "build": "pytest_flockai.fleet.fleet_result.build",
    "collect": "pytest_flockai.fleet.fleet_result.collect",
    "coverage": "pytest_flockai.fleet.fleet_result.coverage",
    "coverage_time": "pytest_flockai.fleet.fleet_result.coverage_time",
    "fleet_kpis": "pytest_flockai.fleet.fleet_result.fleet_kpis",
    "ground_kpis": "pytest_flockai.fleet.fleet_result.ground_kpis",
    "separation": "pytest_flockai.fleet.fleet_result.separation",
    "stations": "pytest_flockai.fleet.fleet_result.stations",
})
