"""The air a flight flies in: the ICAO Standard Atmosphere at a field elevation.

``Atmosphere(altitude_m, temperature_c=None)``: the pressure is the standard
atmosphere's at that elevation; the temperature is the standard one there
(15 degC - 6.5 K/km) unless given; the density follows from the ideal gas law.
Troposphere only (0 to 11 km, where multirotors fly), from the Manual of the
ICAO Standard Atmosphere (ICAO Doc 7488/3, 1993), identical to ISO 2533:

    T_std = T0 - L h,   p = p0 (T_std / T0)^(g0 / (R L)),   rho = p / (R T)

with T0 = 288.15 K, p0 = 101325 Pa, L = 0.0065 K/m, g0 = 9.80665 m/s^2 and
R = 287.05287 J/(kg K). At 2000 m: 79.5 kPa, 2.0 degC, 1.0066 kg/m^3.

The density reaches the rotors' thrust (and so the maximum thrust), the body
drag in MuJoCo (``opt.density``) and every air-density term of the energy model.
"""

from __future__ import annotations

from .. import _check
from ..errors import ConfigError
from ..physics import RHO_SEA_LEVEL

T0_K = 288.15
P0_PA = 101325.0
LAPSE_K_PER_M = 0.0065
G0 = 9.80665
R_AIR = 287.05287
MAX_ALTITUDE_M = 11000.0


class Atmosphere:
    """Air at a field elevation (m above mean sea level) and, optionally, a
    temperature (degC) other than the standard one there."""

    def __init__(self, altitude_m: float = 0.0, temperature_c: float | None = None) -> None:
        where = "Atmosphere"
        self.altitude_m = _check.number("altitude_m", altitude_m, where=where, minimum=-500.0,
                                        maximum=MAX_ALTITUDE_M)
        t_std = T0_K - LAPSE_K_PER_M * self.altitude_m
        if temperature_c is None:
            self.temperature_c = t_std - 273.15
        else:
            self.temperature_c = _check.number("temperature_c", temperature_c, where=where,
                                               minimum=-60.0, maximum=60.0)
        self.pressure_pa = P0_PA * (t_std / T0_K) ** (G0 / (R_AIR * LAPSE_K_PER_M))
        self.density = self.pressure_pa / (R_AIR * (self.temperature_c + 273.15))

    @property
    def density_ratio(self) -> float:
        """rho / rho_0 (sea level, 15 degC)."""
        return self.density / RHO_SEA_LEVEL

    @classmethod
    def coerce(cls, value: object) -> Atmosphere:
        """``value`` itself, or sea level for None; ConfigError for anything else."""
        if value is None:
            return cls()
        if isinstance(value, Atmosphere):
            return value
        raise ConfigError(f"Mission: atmosphere = {value!r} is not allowed; expected "
                                 f"fa.Atmosphere(altitude_m, temperature_c) or None (sea level)")

    def to_dict(self) -> dict:
        """JSON-ready description for the flight's scenario."""
        return {"altitude_m": self.altitude_m, "temperature_c": self.temperature_c,
                "pressure_pa": self.pressure_pa, "density_kg_m3": self.density}

    def __repr__(self):
        return (f"Atmosphere(altitude_m={self.altitude_m:g}, temperature_c={self.temperature_c:.4g}; "
                f"rho={self.density:.4f} kg/m^3)")
