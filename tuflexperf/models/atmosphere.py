"""International Standard Atmosphere (ISA, ICAO Doc 7488) with a temperature offset.

Valid from -1 km to 20 km geopotential altitude (troposphere and the isothermal
lower stratosphere). The offset shifts temperature only; pressure follows the
standard day, as in the usual "ISA + dT" convention.
"""

from __future__ import annotations

from tuflexperf.models._math import Vectorizable, exp, fmin, where

SEA_LEVEL_TEMPERATURE_K = 288.15
SEA_LEVEL_PRESSURE_PA = 101_325.0
SEA_LEVEL_DENSITY_KG_M3 = 1.225
LAPSE_RATE_K_M = 0.0065
TROPOPAUSE_M = 11_000.0
GAS_CONSTANT_J_KG_K = 287.05287
G0_M_S2 = 9.80665
_EXPONENT = G0_M_S2 / (GAS_CONSTANT_J_KG_K * LAPSE_RATE_K_M)  # 5.25588
_TROPOPAUSE_TEMPERATURE_K = SEA_LEVEL_TEMPERATURE_K - LAPSE_RATE_K_M * TROPOPAUSE_M
_TROPOPAUSE_PRESSURE_PA = (
    SEA_LEVEL_PRESSURE_PA * (_TROPOPAUSE_TEMPERATURE_K / SEA_LEVEL_TEMPERATURE_K) ** _EXPONENT
)


def isa_temperature_k(
    altitude_m: Vectorizable, temperature_offset_k: Vectorizable = 0.0
) -> Vectorizable:
    """Static air temperature in K at ``altitude_m`` (m), offset by ``temperature_offset_k``."""
    return (
        SEA_LEVEL_TEMPERATURE_K
        - LAPSE_RATE_K_M * fmin(altitude_m, TROPOPAUSE_M)
        + (temperature_offset_k)
    )


def isa_pressure_pa(altitude_m: Vectorizable) -> Vectorizable:
    """Static pressure in Pa at ``altitude_m`` (m); the temperature offset does not change it."""
    troposphere = (
        SEA_LEVEL_PRESSURE_PA
        * (1.0 - LAPSE_RATE_K_M * fmin(altitude_m, TROPOPAUSE_M) / SEA_LEVEL_TEMPERATURE_K)
        ** _EXPONENT
    )
    stratosphere = _TROPOPAUSE_PRESSURE_PA * exp(
        -G0_M_S2 * (altitude_m - TROPOPAUSE_M) / (GAS_CONSTANT_J_KG_K * _TROPOPAUSE_TEMPERATURE_K)
    )
    return where(altitude_m <= TROPOPAUSE_M, troposphere, stratosphere)


def isa_density_kg_m3(
    altitude_m: Vectorizable, temperature_offset_k: Vectorizable = 0.0
) -> Vectorizable:
    """Air density in kg/m^3 from the ideal-gas law, ``rho = p / (R T)``."""
    return isa_pressure_pa(altitude_m) / (
        GAS_CONSTANT_J_KG_K * isa_temperature_k(altitude_m, temperature_offset_k)
    )
