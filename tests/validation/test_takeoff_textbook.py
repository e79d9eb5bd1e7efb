"""Ground roll against a published textbook answer.

Meriam & Kraige, *Engineering Mechanics: Dynamics*, the take-off-roll problem: an
airplane accelerates from rest as ``a = a0 - k v^2`` with ``a0 = 2 m/s^2`` (engine
thrust) and ``k = 0.00004 1/m`` (aerodynamic drag); the runway needed to reach the
take-off speed of 250 km/h is 1206 m with the drag term excluded and 1268 m with it
(the book's answers, to the metre). Mapped onto this project's ground-roll model:
thrust ``T = m a0``, drag ``0.5 rho S cd0_ground V^2 = m k V^2``, no rolling friction,
no lift on the roll, lift-off speed given.
"""

from __future__ import annotations

import copy

import pytest

from tests.conftest import MADE_UP_AIRCRAFT, MADE_UP_PROPULSION, write_case
from tuflexperf.analysis.takeoff import solve_takeoff
from tuflexperf.io.case import load_case

A0_M_S2 = 2.0
K_PER_M = 0.00004
TAKEOFF_SPEED_M_S = 250.0 / 3.6
MASS_KG = 1000.0
WING_AREA_M2 = 10.0
RHO_SEA_LEVEL = 1.225  # ISA sea level, the case's atmosphere


def _textbook_case(tmp_path, k_per_m: float):
    aircraft = copy.deepcopy(MADE_UP_AIRCRAFT)
    aircraft.update(mass_kg=MASS_KG, wing_area_m2=WING_AREA_M2)
    aircraft["takeoff"] = {
        "cl_ground": 0.0,
        "rolling_friction": 0.0,
        "liftoff_speed_m_s": TAKEOFF_SPEED_M_S,
        "cd0_ground": 2.0 * MASS_KG * k_per_m / (RHO_SEA_LEVEL * WING_AREA_M2),
    }
    propulsion = copy.deepcopy(MADE_UP_PROPULSION)
    propulsion["engines"] = [
        {
            "name": "engine",
            "coefficients": {
                "p00": 0.0, "p10": MASS_KG * A0_M_S2, "p01": 0.0, "p20": 0.0, "p11": 0.0,
                "p02": 0.0,
            },
        }
    ]
    return load_case(write_case(tmp_path, aircraft, propulsion, requirements={}))


@pytest.mark.parametrize(
    ("k_per_m", "published_m"),
    [(1e-12, 1206.0), (K_PER_M, 1268.0)],  # drag excluded (vanishing), included
)
def test_meriam_kraige_runway_length(tmp_path, k_per_m, published_m):
    result = solve_takeoff(_textbook_case(tmp_path, k_per_m))
    assert result.ground_roll_m == pytest.approx(published_m, abs=0.5)
