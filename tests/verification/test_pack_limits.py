"""Take-off, trim and OEI flown on the packs (analysis.pack_limits).

Each figure is checked against an independent SciPy solution of the same equations (the
fitted circuit ``U = OCV(q/n) - (R/n) I``, ``P = U I``, thrust ``T (U/U_ref)^k`` and power
``P (U/U_ref)^(1.5 k)``); the single case is the batch's code on one row. The outside
audit's cases are here: a 1.2 Ah pack that PASSed a full-throttle take-off it sags below
its cut-off for, a 8 C pack that PASSed trim at 45 m/s beyond its rating, and a propulsion
file with the test's reference voltage (as ``fit`` writes it) that PASSed trim at 45 m/s at
a voltage the pack holds only when fresh.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from tests.conftest import copy_shipped_case
from tuflexperf.analysis.batch import BatchEvaluator
from tuflexperf.analysis.oei import solve_oei
from tuflexperf.analysis.pack_limits import fan_power_w, pack_side
from tuflexperf.analysis.requirements import check_case
from tuflexperf.analysis.takeoff import solve_takeoff
from tuflexperf.analysis.trim import solve_trim
from tuflexperf.cli import load_case_with
from tuflexperf.errors import NotAttainable
from tuflexperf.models.aircraft import level_flight_drag_n, transition_speed_m_s
from tuflexperf.models.battery import (
    DischargeParameters,
    loaded_voltage_at_power_v,
    open_circuit_voltage_v,
)
from tuflexperf.models.thrust import density_ratio, engine_thrust_n

SHIPPED_PACK = DischargeParameters(48.475, 0.6518, 1.7168, 2.5309, 0.45777, 5.5353, 0.05026)


def _case(folder: Path, reference_v: float | None = None, c_rate: float | None = None,
          sets: tuple[str, ...] = ()) -> object:
    case = copy_shipped_case(folder)
    data = folder / "data" / "tuflex"
    if reference_v is not None:  # as fit writes it from runs that log the pack's voltage
        with (data / "propulsion.yaml").open("a") as handle:
            handle.write(f"reference_voltage_v: {reference_v}\nvoltage_exponent: 2\n")
    if c_rate is not None:
        battery = data / "battery.yaml"
        battery.write_text(battery.read_text().replace("max_discharge_c: 40 ",
                                                       f"max_discharge_c: {c_rate:g} "))
    return load_case_with(case, list(sets))


@pytest.mark.parametrize("exponent", [0.0, 1.5, 3.0, 4.5])
def test_loaded_voltage_is_the_root_of_the_circuit(exponent: float) -> None:
    rng = np.random.default_rng(3)
    reference = 44.4
    for _ in range(40):
        charge, packs, power = rng.uniform(0, 9), rng.choice([1.0, 2.0, 3.5]), rng.uniform(0, 9e3)
        ocv = float(open_circuit_voltage_v(SHIPPED_PACK, charge, packs))
        r = SHIPPED_PACK.resistance_ohm / packs

        def g(u: float, p: float = power, o: float = ocv, rr: float = r) -> float:
            drawn = p * (u / reference) ** exponent
            return u - o + rr * drawn / u

        ours = float(loaded_voltage_at_power_v(SHIPPED_PACK, charge, power, packs,
                                               reference if exponent else None, exponent))
        if exponent == 0.0 and ocv * ocv < 4 * r * power:
            assert np.isnan(ours)  # beyond the packs' maximum power: no operating point
            continue
        if charge >= packs * SHIPPED_PACK.max_capacity_ah:
            assert np.isnan(ours)  # past the circuit's pole: no pack there
            continue
        # the normal branch: the largest root (U above OCV / 2 at fixed power)
        low = 0.5 * ocv if exponent == 0.0 else 1e-9 * ocv
        assert ours == pytest.approx(brentq(g, low, ocv, xtol=1e-13), rel=1e-10)


def test_a_pack_that_sags_below_its_cutoff_at_full_throttle_cannot_take_off(tmp_path):
    case = _case(tmp_path, sets=("battery.capacity_ah=1.2",))
    with pytest.raises(NotAttainable, match="beyond the battery") as caught:
        solve_takeoff(case)
    assert "cut-off" in str(caught.value)
    # independent: the full-throttle static power of either fan, the circuit at full packs
    side = pack_side(case)
    battery = side.battery
    n = battery.circuit_packs  # 1.2 Ah flies as 0.48 measured packs per fan
    ocv = float(open_circuit_voltage_v(side.params, 0.0, n))
    r = side.params.resistance_ohm / n
    power = max(float(fan_power_w(side, case, j, 1.0, 0.0)) for j in range(2))
    assert ocv * ocv < 4 * r * power or 0.5 * (ocv + np.sqrt(ocv**2 - 4 * r * power)) \
        < battery.cutoff_voltage_v
    # the shipped 5 Ah packs take off
    assert solve_takeoff(_case(tmp_path / "five")).ground_roll_m > 0


def test_the_sag_message_names_the_power_drawn_at_the_sagged_voltage(tmp_path):
    """With a reference voltage the fans draw P (U/U_ref)^(1.5 k): at 40.04 V of a 47 V
    reference, 2628 W of the reference's 4250 W. The message named the reference's power,
    at a voltage it does not flow at (outside audit). The power is the one at the airspeed
    the message names (the climb's: the take-off's charge is drawn by its end)."""
    import re

    case = _case(tmp_path, reference_v=47.0, sets=("battery.capacity_ah=1.0",))
    with pytest.raises(NotAttainable) as caught:
        solve_takeoff(case)
    found = re.search(r"(EDF\d): the packs sag to ([\d.]+) V under (\d+) W", str(caught.value))
    assert found is not None, str(caught.value)
    engine = ["EDF1", "EDF2"].index(found.group(1))
    voltage, said = float(found.group(2)), float(found.group(3))
    airspeed = float(re.search(r"full throttle at ([\d.]+) m/s", str(caught.value)).group(1))
    reference = float(fan_power_w(pack_side(case), case, engine, 1.0, airspeed))
    assert said == pytest.approx(reference * (voltage / 47.0) ** 3, abs=1.0)
    assert said < 0.7 * reference


def test_trim_beyond_the_continuous_rating_is_not_attainable_there(tmp_path):
    case = _case(tmp_path, c_rate=8)
    trim = solve_trim(case)
    assert trim.max_throttle is None  # FAIL, not a PASS with a note
    beyond = [v for v, r in zip(trim.airspeed_m_s, trim.reasons, strict=True)
              if r == "beyond the battery"]
    assert beyond and min(beyond) > 35.0
    # independent: at the reserve the current of the trim throttle at reference, P / U
    side = pack_side(case)
    q = side.reserve_charge_ah
    reference = solve_trim(_case(tmp_path / "shipped"))
    for v, x in zip(reference.airspeed_m_s, reference.throttle, strict=True):
        currents = []
        for j in range(2):
            p = float(fan_power_w(side, case, j, x, v))
            u = float(loaded_voltage_at_power_v(side.params, q, p, side.battery.circuit_packs))
            currents.append(p / u / side.battery.packs_in_parallel_per_engine)
        assert (v in beyond) == (max(currents) > 8 * 5.0), (v, currents)


def _independent_level_throttle(case, side, v: float, dead: int | None = None) -> float:
    """Least throttle with sum_j T_j(x, V) (U_j/U_ref)^k >= D at the reserve (brentq twice)."""
    prop, rho = case.propulsion, case.density_kg_m3
    u_ref, k = prop.reference_voltage_v, prop.voltage_exponent
    scale = float(density_ratio(prop, rho))
    q, n = side.reserve_charge_ah, side.battery.circuit_packs
    ocv = float(open_circuit_voltage_v(side.params, q, n))
    r = side.params.resistance_ohm / n

    def thrust(x: float) -> float:
        total = 0.0
        for j, engine in enumerate(prop.engines):
            if j == dead:
                continue
            p0 = float(fan_power_w(side, case, j, x, v))
            u = brentq(lambda u, p0=p0: u - ocv + r * p0 * (u / u_ref) ** (1.5 * k) / u,
                       1e-6, ocv, xtol=1e-14)
            total += float(engine_thrust_n(engine, x, v, scale)) * (u / u_ref) ** k
        if dead is not None:  # SPEC 3: a windmilling dead engine's drag, -Cd q A_fan
            engine = prop.engines[dead]
            cd, area = engine.windmilling_drag_coefficient, prop.fan_area_m2
            total += (-abs(cd) * 0.5 * rho * v * v * area if cd is not None and area
                      else min(float(engine_thrust_n(engine, 0.0, v, scale)), 0.0))
        return total - float(level_flight_drag_n(case.aircraft, v, rho))

    if thrust(0.0) >= 0:
        return 0.0
    # the sagging pack may give the most thrust below full throttle: scan for the first root
    grid = np.linspace(0.0, 1.0, 401)
    excess = np.array([thrust(x) for x in grid])
    above = np.flatnonzero(excess >= 0)
    if not above.size:
        return float("nan")
    return brentq(thrust, grid[above[0] - 1], grid[above[0]], xtol=1e-14)


def test_trim_and_oei_at_the_loaded_voltage_equal_an_independent_solve(tmp_path):
    case = _case(tmp_path, reference_v=47.3)
    side = pack_side(case)
    trim = solve_trim(case)
    for v in (15.0, 20.0, 30.0, 40.0, 43.0, 45.0):
        ours = float(trim.throttle[np.argmin(np.abs(trim.airspeed_m_s - v))])
        theirs = _independent_level_throttle(case, side, v)
        if np.isnan(theirs):
            assert np.isnan(ours)
        else:
            assert ours == pytest.approx(theirs, abs=1e-9)
    # 45 m/s needs more than full throttle at the reserve's voltage: FAIL (it PASSed at the
    # reference voltage, 0.98)
    assert trim.max_throttle is None
    oei = solve_oei(case)
    for dead_case, dead in zip(oei.cases, (0, 1), strict=True):
        v = dead_case.airspeed_at_min_throttle_m_s
        assert dead_case.min_throttle == pytest.approx(
            _independent_level_throttle(case, side, v, dead), abs=1e-9)


def test_sampled_cruises_cross_the_tested_range_on_sagging_packs(tmp_path) -> None:
    """The samples' extrapolation error steps the thrust at the tested range's end; a cruise
    whose airspeed falls through it as the packs sag still flies (168 of 300 samples were
    'not attainable' there, the level-flight root sought across the step)."""

    from tuflexperf.analysis import uncertainty
    from tuflexperf.analysis.error_model import error_model_for
    from tuflexperf.io.schemas import PropulsionUncertaintySchema

    case = _case(tmp_path, 44.0)
    # the thrust model's own sources (the rig's systematic errors would move the median)
    plan = dataclasses.replace(uncertainty.plan_for(case, 300, 1), errors=error_model_for(
        case, PropulsionUncertaintySchema(rig=False, power_model=False, battery_fit=False)))
    draw = uncertainty.draw_chunk(case, plan, 0)
    assert draw.extrapolation_n is not None
    result = uncertainty.evaluator_for(case).evaluate(draw.values, draw.size,
                                                      draw.coefficients, draw.extrapolation_n)
    endurance = result.values["flight_endurance"]
    verdict = next(v for v in check_case(case) if v.name == "flight_endurance")
    # the evaluator flies the case as given: the first reading (the power model)
    nominal = verdict.readings[0].value if verdict.readings else verdict.value
    assert np.isfinite(endurance).all()
    # about the nominal: the error beyond the range now grows with the distance (issue 44),
    # a wider spread through a curved response moves the median a little (0.24 %)
    assert np.median(endurance) == pytest.approx(nominal, rel=5e-3)


@pytest.mark.parametrize("exponent", [0.0, 3.0])
def test_no_voltage_past_the_circuits_pole(exponent: float) -> None:
    """Past q = n Q the knee term changes sign and the formula's "voltage" rose above a full
    pack's: a take-off that drained 11.35 Ah of 10 Ah passed (outside audit). No pack
    voltage there, so the packs cannot fly it."""
    packs = 2.0
    pole = packs * SHIPPED_PACK.max_capacity_ah
    charge = np.array([0.5 * pole, pole * (1 - 1e-9), pole, 1.03 * pole, 2.0 * pole])
    with np.errstate(all="ignore"):  # the formula at its pole divides by zero
        u = np.asarray(loaded_voltage_at_power_v(SHIPPED_PACK, charge, 1000.0, packs,
                                                 44.4 if exponent else None, exponent))
    assert np.isfinite(u[0]) and np.all(np.isnan(u[2:]))
    full = float(loaded_voltage_at_power_v(SHIPPED_PACK, 0.0, 1000.0, packs,
                                           44.4 if exponent else None, exponent))
    assert not np.any(u[np.isfinite(u)] > full)


def test_a_take_off_that_drains_the_packs_is_not_attainable() -> None:
    """k 0.2576: 456 s at full throttle to the obstacle draw 11.35 Ah of two 5 Ah packs;
    it passed between two failures (k 0.2574 and 0.2584), in check and the batch alike."""
    from tuflexperf.io.case import load_case
    from tuflexperf.io.dotted import with_values

    case = load_case(None)
    ks = np.array([0.2572, 0.2576, 0.2582])
    batch = BatchEvaluator(case).evaluate({"aircraft.k": ks}).values["takeoff_ground_roll"]
    assert np.isfinite(batch[0]) and np.all(np.isnan(batch[1:]))
    for k in ks[1:]:
        with pytest.raises(NotAttainable, match="beyond"):
            solve_takeoff(with_values(case, {"aircraft.k": float(k)}))


def test_beyond_the_battery_after_the_take_off_names_the_climb_airspeed(tmp_path) -> None:
    """Packs of 3.92 V/cell cut-off on a 44 V reference hold full throttle at the brake
    release and fall below it by the end of the take-off: the reason named "full throttle at
    0.0 m/s after the take-off's 0.158 Ah", a point never flown (the brake release is on
    full packs); it names the climb's airspeed, where the charge is drawn."""
    case = _case(tmp_path, 44.0, sets=("battery.cutoff_voltage_per_cell_v=3.92",))
    with pytest.raises(NotAttainable) as caught:
        solve_takeoff(case)
    message = str(caught.value)
    v_tr = float(transition_speed_m_s(case.aircraft, case.density_kg_m3))
    assert message.startswith(f"full throttle at {v_tr:.1f} m/s after the take-off's ")
    assert "0.0 m/s" not in message and "beyond the battery" in message


def test_beyond_the_battery_only_in_the_bound_says_so(tmp_path) -> None:
    """Where the take-off's charge (the most current for all its seconds) fails only at an
    airspeed before the last, the reason says that point has the charge only in the bound
    and that the last airspeed holds: EDF2 sags more at 16.7 m/s than at rest, so listed
    as [16.7, 0] with a cut-off between its two voltages only the first fails."""
    from tuflexperf.analysis.pack_limits import operating_point
    from tuflexperf.analysis.takeoff import takeoff_beyond_battery

    nominal = _case(tmp_path / "nominal", 44.0)
    side = pack_side(nominal)
    speeds, seconds = np.array([16.7, 0.0]), 5.0
    b, prop = side.battery, nominal.propulsion

    def on_packs(power: np.ndarray, charge: float) -> tuple[np.ndarray, ...]:
        return operating_point(side.params, charge, power, b.circuit_packs,
                               b.packs_in_parallel_per_engine, prop.reference_voltage_v,
                               prop.voltage_exponent)

    volts = []
    for j in range(2):
        power = fan_power_w(side, nominal, j, np.ones(2), speeds)
        current = on_packs(power, 0.0)[1]
        charge = float(np.max(current)) * side.battery.packs_in_parallel_per_engine * seconds \
            / 3600.0
        volts.append(on_packs(power, charge)[0])
    cutoff = 0.5 * (volts[1][0] + volts[1][1])  # EDF2: below it at 16.7 m/s, above at rest
    assert volts[1][0] < cutoff < volts[1][1] and np.all(volts[0] > cutoff)
    cells = cutoff / side.battery.cutoff_voltage_v * side.battery.cutoff_voltage_per_cell_v
    case = _case(tmp_path / "cut", 44.0, sets=(f"battery.cutoff_voltage_per_cell_v={cells}",))
    why = takeoff_beyond_battery(case, pack_side(case), speeds, seconds)
    assert why is not None and why.startswith("full throttle at 16.7 m/s with the take-off's ")
    assert "upper bound" in why and "at the last airspeed 0.0 m/s the packs hold" in why
    assert "EDF2" in why
