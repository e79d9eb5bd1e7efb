"""Take-off to the obstacle against a published textbook example (not calibrated to).

Source: J. D. Anderson, *Aircraft Performance and Design*, McGraw-Hill 1999,
chapter 6, Example 6.6 (take-off of the "Gulfstream-like" twin jet at sea level):
W = 73,000 lb, W/S = 76.84 lb/ft^2 (the SI wing loading 3,679 N/m^2 is printed
in the example), paved runway mu = 0.04, ground-roll CL = 0.1, CD0 = 0.015 plus
landing-gear increment 0.0177, k1 = 0.02, e = 0.9, AR = 5.92, ground-effect
factor G = 0.588, K_T = T/W - mu = 0.301, lift-off at V_LO = 205.1 ft/s,
V_stall = 186.4 ft/s, N = 3 s of rotation, obstacle 35 ft (FAR 25).
The book's answers: ground roll 2,242 ft + 3 x 205.1 = 615 ft of rotation =
**2,857 ft**; transition radius R = 6.96 V_stall^2 / g = **7,510 ft**; obstacle
cleared during the arc at theta_OB = 5.534 deg, airborne distance
R sin(theta_OB) = **724 ft**.

Mapping onto this project: one constant-thrust engine, T = (K_T + mu) W;
``cd0_ground = CD0 + dCD0``, ``k_ground = k1 + G/(pi e AR)``; clean polar
``k = k1 + 1/(pi e AR)``; lift-off EAS 205.1 ft/s; ``cl_max`` from the book's
stall speed. The book's own climb angle is not printed; the test checks that the
obstacle is cleared in the arc (as in the book).

The same book's Example 6.7 (landing of that airplane) works the same geometry
backwards: a 3 deg straight approach from 50 ft, then a flare arc of
R = V_f^2 / (0.2 g) with V_f = 202.3 ft/s: **R = 6,354.9 ft**, flare height
**h_f = 8.71 ft**, approach **788 ft**, flare **333 ft**. Flown forwards this is the
take-off's arc to a 3 deg climb (n = 1.2) and the straight climb to 50 ft, the branch
Example 6.6 does not reach (it clears its obstacle in the arc);
:func:`obstacle_distances_m` must give the book's numbers.

Tolerance 0.5 %: the book rounds K_T to three digits (+-0.17 % in the ground
roll), uses g = 32.2 ft/s^2 (0.08 % from 9.80665 m/s^2) and 6.96 for
1.15^2/0.19 = 6.9605; the example's answers are printed to 3-4 digits.
"""

from __future__ import annotations

import math

import pytest

from tests.conftest import write_case
from tuflexperf.analysis.takeoff import solve_takeoff
from tuflexperf.io.case import load_case
from tuflexperf.models.aircraft import obstacle_distances_m, transition_radius_m

FT = 0.3048
LB = 4.4482216152605
G0 = 9.80665
RHO = 1.225

WEIGHT_N = 73_000 * LB
WING_LOADING_PA = 76.84 * LB / FT**2
V_STALL = 186.4 * FT
V_LO = 205.1 * FT
MU, CL_GROUND, K_T = 0.04, 0.1, 0.301
CD0, DCD0, K1, E, AR, G_EFFECT = 0.015, 0.0177, 0.02, 0.9, 5.92, 0.588

BOOK_GROUND_ROLL_FT = 2857.0
BOOK_ROTATION_FT = 615.0
BOOK_RADIUS_FT = 7510.0
BOOK_AIRBORNE_FT = 724.0
TOLERANCE = 0.005


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    k3 = 1.0 / (math.pi * E * AR)
    aircraft = {
        "name": "Anderson Example 6.6 (Gulfstream-like)",
        "mass_kg": WEIGHT_N / G0,
        "wing_area_m2": WEIGHT_N / WING_LOADING_PA,
        "cd0": CD0,
        "k": K1 + k3,
        "cl_max": 2 * WING_LOADING_PA / (RHO * V_STALL**2),
        "takeoff": {
            "cl_ground": CL_GROUND,
            "rolling_friction": MU,
            "cd0_ground": CD0 + DCD0,
            "k_ground": K1 + G_EFFECT * k3,
            "liftoff_speed_m_s": V_LO,
            "rotation_time_s": 3.0,
        },
    }
    thrust = (K_T + MU) * WEIGHT_N
    propulsion = {
        "name": "constant thrust",
        "model": "poly22",
        "tested_airspeed_m_s": [0, 100],
        "engines": [{"name": "both", "coefficients": {
            "p00": thrust, "p10": 0.0, "p01": 0.0, "p20": 0.0, "p11": 0.0, "p02": 0.0}}],
    }
    folder = tmp_path_factory.mktemp("anderson66")
    requirements = {"takeoff": {"max_ground_roll_m": 1000, "obstacle_height_m": 35 * FT}}
    return solve_takeoff(load_case(write_case(folder, aircraft, propulsion, requirements)))


def test_ground_roll_with_rotation(result):
    assert result.rotation_distance_m / FT == pytest.approx(BOOK_ROTATION_FT, rel=TOLERANCE)
    assert result.ground_roll_m / FT == pytest.approx(BOOK_GROUND_ROLL_FT, rel=TOLERANCE)


def test_transition_radius(result):
    assert result.transition_radius_m / FT == pytest.approx(BOOK_RADIUS_FT, rel=TOLERANCE)


def test_airborne_distance_to_35_ft(result):
    assert result.obstacle_cleared_in_transition
    assert result.airborne_distance_m / FT == pytest.approx(BOOK_AIRBORNE_FT, rel=TOLERANCE)
    total = BOOK_GROUND_ROLL_FT + BOOK_AIRBORNE_FT
    assert result.distance_to_obstacle_m / FT == pytest.approx(total, rel=TOLERANCE)


def test_arc_then_straight_path_anderson_example_6_7():
    radius = float(transition_radius_m(202.3 * FT, 1.2))
    assert radius / FT == pytest.approx(6354.9, rel=TOLERANCE)
    arc, straight, arc_top = obstacle_distances_m(radius, math.sin(math.radians(3.0)), 50 * FT)
    assert float(arc_top) / FT == pytest.approx(8.71, rel=TOLERANCE)
    assert float(straight) / FT == pytest.approx(788.0, rel=TOLERANCE)
    assert float(arc) / FT == pytest.approx(333.0, rel=TOLERANCE)
