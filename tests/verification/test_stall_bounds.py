"""Stall bounds trim, OEI and endurance (SPEC 3): not attainable below stall, never a note.

Exact attainable ranges on made-up aircraft: the stall speed ``sqrt(2W/(rho S cl_max))``
(x the envelope's ``stall_margin``) and, for quadratic thrust, the closed-form
full-throttle roots of thrust = drag (see test_performance_closed_form).
"""

from __future__ import annotations

import copy
import json
import math

import numpy as np
import pytest

from tests.conftest import MADE_UP_AIRCRAFT, MADE_UP_PROPULSION, SHIPPED_CASE, write_case
from tests.verification.test_performance_closed_form import (
    A_TOTAL,
    AIRCRAFT,
    C_TOTAL,
    ClosedForm,
    _isa_density,
    _propulsion,
)
from tuflexperf.analysis.oei import solve_oei
from tuflexperf.analysis.requirements import check_case
from tuflexperf.analysis.trim import solve_trim
from tuflexperf.cli import main
from tuflexperf.io.case import load_case

G = 9.80665
RHO = _isa_density(0.0)  # ISA sea level, written out in the closed-form test


def _stall(aircraft, rho=RHO):
    return math.sqrt(2 * aircraft["mass_kg"] * G / (rho * aircraft["wing_area_m2"]
                                                    * aircraft["cl_max"]))


def _shipped_variant(tmp_path, **changes):
    """The shipped TU-Flex files with aircraft keys changed (the audit's made-up aircraft)."""
    import yaml

    root = SHIPPED_CASE.parent.parent / "data" / "tuflex"
    aircraft = yaml.safe_load((root / "aircraft.yaml").read_text())
    aircraft.update(changes)
    aircraft["takeoff"].pop("liftoff_speed_m_s", None)  # the default 1.1 x stall EAS
    # the ground roll's lift coefficient at most cl_max (above it: bad input)
    aircraft["takeoff"]["cl_ground"] = min(aircraft["takeoff"]["cl_ground"], aircraft["cl_max"])
    propulsion = yaml.safe_load((root / "propulsion.yaml").read_text())
    requirements = {
        "envelope": {"min_airspeed_m_s": 15, "max_airspeed_m_s": 45, "max_trim_throttle": 1.0},
        "oei": {"dead_engine": "windmilling", "max_throttle": 1.0},
    }
    return write_case(tmp_path, aircraft, propulsion, requirements=requirements), aircraft


def test_heavy_aircraft_trim_is_not_attainable_below_stall(tmp_path, capsys):
    # the audit's made-up aircraft: 60 kg on the polar and cl_max shipped at the time
    path, aircraft = _shipped_variant(tmp_path, mass_kg=60.0, cl_max=1.5, cd0=0.02, k=0.025809)
    stall = _stall(aircraft)
    assert stall == pytest.approx(23.1, abs=0.05)  # the audit's 23.1 m/s
    trim = solve_trim(load_case(path))
    below = trim.airspeed_m_s < stall
    assert np.all(np.isnan(trim.throttle[below]))
    assert all(r == "below stall" for r, b in zip(trim.reasons, below, strict=True) if b)
    assert trim.attainable.low == pytest.approx(stall, rel=1e-12)
    assert not trim.all_feasible and trim.max_throttle is None
    verdicts = {v.name: v for v in check_case(load_case(path))}
    assert not verdicts["trim_throttle_max"].passed
    assert "below stall at 15-23 m/s" in verdicts["trim_throttle_max"].reason
    oei = solve_oei(load_case(path))
    for c in oei.cases:
        assert np.all(np.isnan(c.throttle[below]))
        assert all(r == "below stall" for r, b in zip(c.reasons, below, strict=True) if b)
        if c.level_flight_airspeed_range_m_s is not None:  # on one engine it may fly nowhere
            low, _ = c.level_flight_airspeed_range_m_s
            assert low >= stall * (1 - 1e-12)  # exact: the stall or the thrust bound
    with pytest.raises(SystemExit) as exc:
        main(["trim", "--case", str(path), "--json"])
    assert exc.value.code == 1
    data = json.loads(capsys.readouterr().out)
    assert data["passed"] is False
    assert data["least_attainable_airspeed_m_s"] == pytest.approx(stall, rel=1e-12)
    assert data["not_attainable_reason"][0] == "below stall"
    assert data["throttle"][0] is None


def test_low_cl_max_fails_everything_with_the_reason(tmp_path, capsys):
    # the audit's made-up aircraft: cl_max 0.05 on the mass (22.17 kg) shipped at the time
    path, aircraft = _shipped_variant(tmp_path, cl_max=0.05, mass_kg=22.1732)
    assert _stall(aircraft) == pytest.approx(76.9, abs=0.05)
    verdicts = check_case(load_case(path))
    assert verdicts and not any(v.passed for v in verdicts)
    assert all("below stall" in v.reason for v in verdicts)
    with pytest.raises(SystemExit) as exc:
        main(["oei", "--case", str(path), "--json"])
    assert exc.value.code == 1
    data = json.loads(capsys.readouterr().out)
    assert data["level_flight_airspeed_range_m_s"] is None and data["passed"] is False
    assert set(data["not_attainable_reason"]) == {"below stall"}


def test_exact_range_on_quadratic_thrust_with_stall_margin(tmp_path):
    aircraft = copy.deepcopy(AIRCRAFT)
    requirements = {
        "envelope": {"min_airspeed_m_s": 10, "max_airspeed_m_s": 60, "stall_margin": 1.2},
        "oei": {"dead_engine": "zero", "max_throttle": 1.0},
    }
    case = load_case(write_case(tmp_path, aircraft, _propulsion(), requirements=requirements))
    rho = _isa_density(0.0)
    full = ClosedForm(aircraft, rho, rho / 1.225, A_TOTAL, C_TOTAL, margin=1.2)
    trim = solve_trim(case)
    low, high = full.level_speeds()  # low is the stall bound here, high the thrust limit
    assert trim.attainable.low == pytest.approx(low, rel=1e-12)
    assert trim.attainable.high == pytest.approx(high, rel=1e-12)
    for v, x, why in zip(trim.airspeed_m_s, trim.throttle, trim.reasons, strict=True):
        if v < full.stall:
            assert why == "below stall" and np.isnan(x)
        elif v > high:
            assert why == "needs more than full throttle" and np.isnan(x)
        else:
            assert why is None and np.isfinite(x)
    one = ClosedForm(aircraft, rho, rho / 1.225, A_TOTAL / 2, C_TOTAL / 2, margin=1.2)
    for c in solve_oei(case).cases:
        lo, hi = c.level_flight_airspeed_range_m_s
        assert lo == pytest.approx(one.level_speeds()[0], rel=1e-12)
        assert hi == pytest.approx(one.level_speeds()[1], rel=1e-12)


def test_endurance_level_speed_below_stall_margin_is_not_attainable(tmp_path):
    import yaml

    case = yaml.safe_load(SHIPPED_CASE.read_text())
    root = SHIPPED_CASE.parent
    for key in ("aircraft", "propulsion", "battery"):
        case[key] = str((root / case[key]).resolve())
    # at 50 % throttle the TU-Flex flies 26 m/s; a 2 x stall margin asks for 28 m/s
    case["requirements"]["envelope"]["stall_margin"] = 2.0
    path = tmp_path / "case.yaml"
    path.write_text(yaml.safe_dump(case))
    verdicts = {v.name: v for v in check_case(load_case(path))}
    endurance = verdicts["flight_endurance"]
    assert not endurance.passed and endurance.value is None
    assert "below" in endurance.reason


def test_made_up_case_still_passes_where_attainable(tmp_path):
    """The conftest aircraft (stall 13.7 m/s, envelope from 14) keeps its verdicts."""
    case = load_case(write_case(tmp_path, MADE_UP_AIRCRAFT, MADE_UP_PROPULSION))
    trim = solve_trim(case)
    assert trim.attainable.low == pytest.approx(14.0)
    assert all(r is None or r == "needs more than full throttle" for r in trim.reasons)
