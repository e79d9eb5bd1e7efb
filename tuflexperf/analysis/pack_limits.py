"""Can the packs fly it? Loaded voltage, current and the voltage effect at steady points.

SPEC 3 and 4: "beyond the battery" fails with a reason, never a PASS. Take-off, trim and
one engine inoperative are point analyses; where the case names a battery file each point
is also flown on the packs (the fitted circuit of :mod:`tuflexperf.models.battery`, the
power model the mission uses: the propulsion's power surfaces, else the battery file's
fan-power law), by the mission's rules (``MissionModel._beyond_rating``):

- **take-off**: from full packs at full throttle over the ground roll's airspeeds. The
  loaded voltage stays at or above the cut-off and no pack's current exceeds its burst
  rating (:data:`~tuflexperf.analysis.mission.BURST_OVER_CONTINUOUS` x the continuous one:
  a roll lasts seconds).
- **level flight** (trim, OEI): at the landing reserve, the lowest charge of a flight and so
  the lowest voltage. The loaded voltage stays at or above the cut-off and the current within
  the continuous rating (steady flight lasts). With the propulsion's ``reference_voltage_v``
  the thrust is ``T (U / U_ref)^k`` and the power ``P (U / U_ref)^(1.5 k)`` at the loaded
  voltage ``U``, so the least throttle and the voltage are solved together (fixed point).

A pack that passed a 4.3 kW full-throttle take-off while sagging to 38.6 V against a 40.8 V
cut-off, and trim at 45 m/s at the test's voltage that the pack holds only when fresh, had
PASSed (outside audit).

References
----------
Tremblay & Dessaint (2009) (the circuit); SPEC 3 (thrust and pack voltage, stall and
"beyond the battery"); paper section 2.1 (two 12S packs per fan, 40 C).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from tuflexperf.analysis.attainable import (
    BELOW_STALL,
    BEYOND_JET_VELOCITY,
    BEYOND_THE_BATTERY,
    AttainableRange,
)
from tuflexperf.analysis.batch_kernels import fan_power_rows
from tuflexperf.io.case import Case
from tuflexperf.models._math import fmax, is_symbolic
from tuflexperf.models.battery import loaded_voltage_at_power_v

_CUTOFF_TOLERANCE = 1e-12  # relative: a loaded voltage at the cut-off is within it
_RATING_TOLERANCE = 1e-9  # relative, as the mission's rating rule
_SCAN = 33  # least_throttle_where: throttles scanned for the first bracket (1/32 apart)
_BISECTIONS = 50  # ... then halved to 2^-55 of full throttle


@dataclass(frozen=True)
class PackSide:
    """What the point analyses fly on: the battery, its circuit and the fans' power."""

    battery: Any  # tuflexperf.io.battery.Battery
    params: Any  # DischargeParameters
    power: Any  # PowerSurfaces or FanPowerModel (per fan, at the case's density)
    own_surfaces: bool
    density_scale: float

    @property
    def rating_a(self) -> float | None:
        """Continuous rating of one pack [A] (None without ``max_discharge_c``)."""
        c_rate = self.battery.max_discharge_c
        return None if c_rate is None else float(c_rate) * float(self.battery.capacity_ah)

    @property
    def reserve_charge_ah(self) -> float:
        """Charge drawn per engine at the landing reserve [Ah]."""
        b = self.battery
        return b.packs_in_parallel_per_engine * b.capacity_ah * (1.0 - b.landing_reserve_fraction)


def sagging_packs(case: Case) -> bool:
    """Whether each fan flies at its packs' loaded voltage: the case names a battery file
    and the propulsion a ``reference_voltage_v`` (SPEC 3)."""
    return case.propulsion.reference_voltage_v is not None and case.battery_path is not None


def pack_side(case: Case) -> PackSide | None:
    """The case's packs and power model, or None when the case names no battery file."""
    if case.battery_path is None:
        return None
    from tuflexperf.analysis.battery_fit import cached_case_battery, characterise_battery
    from tuflexperf.models.powertrain import power_surfaces

    battery = cached_case_battery(case)
    characterised = characterise_battery(battery, case)
    surfaces = power_surfaces(case.propulsion, case.density_kg_m3)
    if surfaces is not None:
        return PackSide(battery, characterised.fit.parameters, surfaces, True,
                        surfaces.density_scale)
    return PackSide(battery, characterised.fit.parameters, characterised.power.model, False, 1.0)


def fan_power_w(side: PackSide, case: Case, engine: int, throttle: Any, airspeed: Any) -> Any:
    """Engine ``engine``'s electrical power [W] at the reference voltage (never negative:
    an ESC draws, it does not charge), as the mission takes it (floats, numpy or CasADi)."""
    from tuflexperf.models.powertrain import engine_power_w

    if side.own_surfaces:
        power = side.density_scale * engine_power_w(case.propulsion.engines[engine], throttle,
                                                    airspeed)
    else:
        power = side.power.electrical_power_w(throttle, airspeed)
    return fmax(power if is_symbolic(power) else np.asarray(power, dtype=float), 0.0)


def operating_point(params: Any, charge_ah: Any, power_w: Any, circuit_packs: Any,
                    packs_per_engine: int, reference_voltage_v: float | None,
                    voltage_exponent: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Loaded voltage [V], current per pack [A] and thrust factor ``(U/U_ref)^k`` [-] of one
    engine's ``circuit_packs`` (measured packs; ``packs_per_engine`` of the battery's own)
    drawing ``power_w`` [W] at the reference voltage after ``charge_ah`` [Ah]; arrays
    broadcast (the single case and the batch alike; CasADi too). NaN voltage: beyond their
    power."""
    u_ref, k = reference_voltage_v, voltage_exponent
    m = 0.0 if u_ref is None else 1.5 * k
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        u = loaded_voltage_at_power_v(params, charge_ah, power_w, circuit_packs, u_ref, m)
        symbolic = is_symbolic(u)  # CasADi for the take-off's integrand, numpy elsewhere
        u = u if symbolic else np.asarray(u, dtype=float)
        if u_ref is None:
            factor = 1.0 if symbolic else np.ones_like(u)
        else:
            factor = (u / u_ref) ** k
        current = power_w * factor ** 1.5 / u / packs_per_engine
    return u, current, factor


def within_limits(voltage_v: Any, current_a: Any, cutoff_v: Any, rating_a: Any) -> Any:
    """Where the packs fly a point: a voltage (NaN: none) at or above the cut-off [V] and a
    current per pack [A] within the rating (``None``: no rating)."""
    with np.errstate(invalid="ignore"):
        ok = np.asarray(voltage_v) >= cutoff_v * (1.0 - _CUTOFF_TOLERANCE)
        if rating_a is not None:
            ok = ok & ~(np.asarray(current_a) > rating_a * (1.0 + _RATING_TOLERANCE))
    return ok


def limit_reason(side: PackSide, voltage_v: float, current_a: float, power_w: float,
                 rating_a: float | None, rating_name: str) -> str | None:
    """Why one engine's packs cannot fly a point (None: they can; :func:`within_limits`)."""
    cutoff = side.battery.cutoff_voltage_v
    if within_limits(voltage_v, current_a, cutoff, rating_a):
        return None
    if not np.isfinite(voltage_v):
        return f"the packs cannot deliver {power_w:.0f} W (beyond their maximum power)"
    if not within_limits(voltage_v, current_a, cutoff, None):
        # the power the packs give at that voltage: with a reference voltage the fans draw
        # less as it sags (power_w is the reference voltage's: 4250 W where 2628 W flow)
        drawn = current_a * voltage_v * side.battery.packs_in_parallel_per_engine
        return (f"the packs sag to {voltage_v:.2f} V under {drawn:.0f} W, below their "
                f"cut-off {cutoff:.2f} V")
    return (f"{current_a:.1f} A per pack, beyond its {rating_name} rating {rating_a:.1f} A "
            f"(max_discharge_c {side.battery.max_discharge_c:g} C x "
            f"{side.battery.capacity_ah:g} Ah)")


@dataclass(frozen=True)
class PackRows:
    """The battery a batch's rows fly, one value per row ``(R,)`` (dotted.BATTERY_KEYS)."""

    packs_per_engine: int
    capacity_ah: np.ndarray  # rated, per pack
    circuit_packs: np.ndarray  # measured packs per engine (models.battery.equivalent_packs)
    cutoff_v: np.ndarray
    reserve_charge_ah: np.ndarray  # drawn per engine at the landing reserve
    rating_a: np.ndarray | None  # continuous, per pack


def pack_rows(battery: Any, values: dict[str, np.ndarray] | None = None) -> PackRows:
    """:class:`PackRows` of ``battery`` (a :class:`~tuflexperf.io.battery.Battery`) with the
    rows' ``values`` of its varying keys (None: one row, the battery as given)."""
    from tuflexperf.models.battery import equivalent_packs

    if values is None:
        from tuflexperf.io.dotted import battery_key_values

        values = {k: np.array([x], dtype=float) for k, x in battery_key_values(battery).items()}

    per_engine = battery.packs_in_parallel_per_engine
    capacity = np.asarray(values["battery.capacity_ah"], dtype=float)
    return PackRows(
        per_engine, capacity,
        np.asarray(equivalent_packs(per_engine, capacity, battery.as_read.capacity_ah),
                   dtype=float),
        battery.cells_in_series * values["battery.cutoff_voltage_per_cell_v"],
        per_engine * capacity * (1.0 - values["battery.mission.landing_reserve_fraction"]),
        None if battery.max_discharge_c is None
        else float(battery.max_discharge_c) * capacity,
    )


@dataclass(frozen=True)
class LevelOnPacks:
    """Level flight at the landing reserve per airspeed: the least throttle (NaN where not
    attainable), and per airspeed why the packs cannot fly it (None where they can)."""

    throttle: np.ndarray
    beyond: tuple[str | None, ...]
    voltage_v: np.ndarray  # least loaded voltage over the live engines [V]

    @property
    def any_beyond(self) -> bool:
        return any(b is not None for b in self.beyond)


def least_throttle_where(excess: Any, shape: tuple[int, ...]) -> np.ndarray:
    """Least throttle ``x`` in [0, 1] with ``excess(x) >= 0`` at each point (NaN where none):
    a scan of :data:`_SCAN` throttles, then bisection to 1e-15 on the first bracket.

    With the packs' voltage in the thrust the excess need not grow with the throttle (more
    power sags the pack), so no closed form holds: a fixed-point iteration on the closed
    form had "converged" on 0.968 at 43 m/s where no throttle reaches (a test's find).
    ``excess`` takes an array of throttles of ``shape`` (NaN counts as not reaching).
    """
    x = np.zeros(shape)
    with np.errstate(invalid="ignore"):
        found = np.asarray(excess(x)) >= 0.0
        low, high = np.zeros(shape), np.zeros(shape)
        step = 1.0 / (_SCAN - 1)
        for n in range(1, _SCAN):
            at = n * step
            reached = ~found & (np.asarray(excess(np.full(shape, at))) >= 0.0)
            low = np.where(reached, at - step, low)
            high = np.where(reached, at, high)
            found |= reached
        for _ in range(_BISECTIONS):
            mid = 0.5 * (low + high)
            up = np.asarray(excess(mid)) >= 0.0
            low, high = np.where(up, low, mid), np.where(up, mid, high)
    return np.where(found, high, np.nan)


@dataclass(frozen=True)
class LevelRowsOnPacks:
    """Level flight at the landing reserve on the rows' packs over their grids ``(B, K)``
    (:func:`level_rows_on_packs`): the least throttle before the packs' limits (NaN where
    none reaches), the live engines, and per live engine its loaded voltage [V], current per
    pack [A], power [W] at the reference voltage and where its packs fly the point."""

    throttle: np.ndarray
    live: list[int]
    points: list[tuple[np.ndarray, np.ndarray, np.ndarray]]
    within: list[np.ndarray]

    @property
    def flown(self) -> np.ndarray:
        """The least throttle where every live engine's packs fly it (NaN elsewhere)."""
        ok = np.isfinite(self.throttle) & np.all(self.within, axis=0)
        return np.where(ok, self.throttle, np.nan)


def level_rows_on_packs(m: Any, grid: np.ndarray, dead: int | None, mode: str,
                        packs: PackSide, rows: PackRows, throttle: np.ndarray | None = None,
                        flyable: np.ndarray | None = None) -> LevelRowsOnPacks:
    """The least level-flight throttle on the rows' packs at the landing reserve (module
    docstring), one row for ``trim`` and ``oei``, many for the batch.

    Parameters
    ----------
    m : LevelFlightRows
        The rows' physics (:class:`~tuflexperf.analysis.level_flight.LevelFlightRows`).
    grid : ndarray ``(B, K)`` or ``(1, K)``
        True airspeeds [m/s].
    dead, mode
        The inoperative engine (OEI) and its drag (``windmilling`` or ``zero``).
    packs, rows
        The case's packs and the rows' (:func:`pack_rows`).
    throttle : ndarray, optional
        The least throttle at the reference voltage [fraction] (default ``m``'s).
    flyable : ndarray of bool, optional
        Where level flight may be attainable at all (default ``m``'s: above stall, short
        of the jet velocity); with a reference voltage the throttle is solved again there.
    """
    prop = m.propulsion
    terms = m._grid_terms(grid)
    live = [j for j in range(len(prop.engines)) if j != dead]
    idle = m._excess_quadratic(grid, dead, mode, terms)[2]  # its shape is every row's grid
    shape = idle.shape
    flyable = np.broadcast_to(m._flyable(grid) if flyable is None else flyable, shape)
    # one row's values as floats: the loaded voltage's Newton steps on (1, 1) columns took
    # a fifth longer (the same numbers)
    charge, circuit = (float(a[0]) if a.size == 1 else a[:, None]
                       for a in (rows.reserve_charge_ah, rows.circuit_packs))
    rating = None if rows.rating_a is None else rows.rating_a[:, None]
    engines = [prop.engines[j] if packs.own_surfaces else None for j in live]

    def on_rows(x: np.ndarray) -> list[tuple[np.ndarray, ...]]:
        """Per live engine at throttles ``x``: voltage [V], current per pack [A], thrust
        factor [-] and power [W] at the reference voltage."""
        return [(*operating_point(packs.params, charge, power, circuit, rows.packs_per_engine,
                                  prop.reference_voltage_v, prop.voltage_exponent), power)
                for power in (np.maximum(fan_power_rows(packs, m, x, grid, e), 0.0)
                              * np.ones(shape) for e in engines)]

    if prop.reference_voltage_v is None:
        if throttle is None:
            throttle = m.least_throttle(grid, dead, mode, terms)
        x = np.where(flyable, throttle, np.nan)
    else:  # the thrust follows the sagging pack: no closed form
        # the excess without the live engines: the dead one's drag less the airframe's
        other = idle - sum(terms[0][j][2] for j in live)

        def excess(xs: np.ndarray) -> np.ndarray:
            total = np.broadcast_to(other, shape)
            for j, point in zip(live, on_rows(xs), strict=True):
                a_j, b_j, c_j = terms[0][j]
                total = total + point[2] * ((a_j * xs + b_j) * xs + c_j)
            return total

        x = np.where(flyable, least_throttle_where(excess, shape), np.nan)
    points = [(u, current, power) for u, current, _, power in on_rows(np.nan_to_num(x))]
    within = [within_limits(u, current, rows.cutoff_v[:, None], rating)
              for u, current, _ in points]
    return LevelRowsOnPacks(x, live, points, within)


def level_flight_on_packs(case: Case, side: PackSide, m: Any, grid: np.ndarray,
                          throttle: np.ndarray, flyable: np.ndarray,
                          dead: int | None = None, mode: str = "windmilling") -> LevelOnPacks:
    """The single case's level flight on its packs: :func:`level_rows_on_packs` on its one
    row ``m`` over ``grid`` ``(1, K)`` [m/s], with the reason per airspeed where the packs
    cannot fly it (``throttle`` and ``flyable`` as there)."""
    prop = case.propulsion
    on = level_rows_on_packs(m, grid, dead, mode, side, pack_rows(side.battery),
                             np.asarray(throttle)[None, :],
                             np.asarray(flyable, dtype=bool)[None, :])
    x = on.throttle[0]
    beyond: list[str | None] = [None] * x.size
    if prop.reference_voltage_v is not None:
        for n in np.flatnonzero(flyable & ~np.isfinite(x)):
            beyond[n] = ("needs more than full throttle at the packs' loaded voltage "
                         f"(thrust x (U/{prop.reference_voltage_v:g} V)^"
                         f"{prop.voltage_exponent:g}), or more power than they give")
    least_u = np.full(x.shape, np.inf)
    for j, (u, current, power), within in zip(on.live, on.points, on.within, strict=True):
        u, current, power = u[0], current[0], power[0]
        least_u = np.where(np.isfinite(x), np.fmin(least_u, u), least_u)
        for n in np.flatnonzero(np.isfinite(x) & ~within[0]):
            why = limit_reason(side, float(u[n]), float(current[n]), float(power[n]),
                               side.rating_a, "continuous")
            if why is not None and beyond[n] is None:
                beyond[n] = f"{prop.engines[j].name}: {why}"
    x = np.where([b is None for b in beyond], x, np.nan)
    return LevelOnPacks(x, tuple(beyond), least_u)


def beyond_note(what: str, side: PackSide, speeds: np.ndarray, on: LevelOnPacks) -> str:
    """The warning naming where and why level flight is beyond the battery."""
    hit = np.array([b is not None for b in on.beyond])
    v = np.asarray(speeds, dtype=float)[hit]
    first = next(b for b in on.beyond if b is not None)
    span = f"{v.min():g}" if v.min() == v.max() else f"{v.min():g}-{v.max():g}"
    return (f"{what}: {BEYOND_THE_BATTERY} at {span} m/s at the landing reserve "
            f"({side.battery.landing_reserve_fraction:.0%} of the charge left): {first}")


def with_packs(case: Case, what: str, m: Any, grid: np.ndarray, throttle: np.ndarray,
               reasons: tuple[str | None, ...], attainable: AttainableRange,
               dead: int | None = None, mode: str = "windmilling"
               ) -> tuple[np.ndarray, tuple[str | None, ...], AttainableRange, list[str]]:
    """Trim's or OEI's grid ``(1, K)`` [m/s] flown on the case's packs (unchanged without a
    battery file) by its one row ``m`` (``LevelFlightRows``): the throttles, each airspeed's
    reason, the attainable range and the notes.

    The range stays the exact one of full throttle at the reference voltage where the packs
    change nothing; otherwise it is the grid's (0.5 m/s steps), as the note says.
    """
    side = pack_side(case)
    if side is None:
        from tuflexperf.models.thrust import reference_voltage_note

        note = reference_voltage_note(case.propulsion, what)
        return throttle, reasons, attainable, [note] if note else []

    flyable = np.array([r not in (BELOW_STALL, BEYOND_JET_VELOCITY) for r in reasons])
    speeds = grid[0]
    on = level_flight_on_packs(case, side, m, grid, throttle, flyable, dead, mode)
    notes = []
    if case.propulsion.reference_voltage_v is not None:
        least = float(np.min(on.voltage_v))
        notes.append(f"{what} at the packs' loaded voltage at the landing reserve "
                     f"({side.battery.landing_reserve_fraction:.0%} of the charge left)"
                     f"{f', least {least:.1f} V' if np.isfinite(least) else ''}: thrust x (U/"
                     f"{case.propulsion.reference_voltage_v:g} V)^"
                     f"{case.propulsion.voltage_exponent:g}")
    measured = side.battery.measured_cutoff_v
    flown_v = on.voltage_v[np.isfinite(on.throttle) & np.isfinite(on.voltage_v)]
    if flown_v.size and float(flown_v.min()) < measured * (1.0 - 1e-9):
        # a cut-off below the runs' lets the packs fly voltages no run measured (a file's
        # 3.0 V/cell turned trim on 3 Ah packs from FAIL into PASS at 40.66 V; outside audit)
        notes.append(f"{what}: the packs fly down to {float(flown_v.min()):.2f} V, below the "
                     f"discharge runs' cut-off {measured:.2f} V: the pack model is "
                     "extrapolated there")
    changed = on.any_beyond or not np.allclose(on.throttle, throttle, rtol=0.0, atol=1e-12,
                                                equal_nan=True)
    if not changed:
        return throttle, reasons, attainable, notes
    reasons = tuple(BEYOND_THE_BATTERY if b is not None else None if np.isfinite(x) else r
                    for r, b, x in zip(reasons, on.beyond, on.throttle, strict=True))
    if on.any_beyond:
        notes.append(beyond_note(what, side, speeds, on))
    flown = np.asarray(speeds, dtype=float)[np.isfinite(on.throttle)]
    if flown.size == 0:
        attainable = AttainableRange(None, None)
    else:
        inside = np.isfinite(on.throttle[(speeds >= flown.min()) & (speeds <= flown.max())])
        attainable = AttainableRange(float(flown.min()), float(flown.max()), bool(inside.all()))
        notes.append(f"{what}: the attainable airspeeds on the packs are the grid's "
                     f"({flown.min():g}-{flown.max():g} m/s, 0.5 m/s steps)")
    return on.throttle, reasons, attainable, notes


def power_limit_w(side: PackSide, battery: dict[str, np.ndarray]) -> np.ndarray:
    """Most power [W] one engine's packs give at the landing reserve without a reference
    voltage, per row of ``battery`` (the varied battery keys): within the cut-off, the
    continuous rating and the packs' maximum power.

    With ``U = OCV - (R/n) P / U`` falling as ``P`` rises: at the cut-off ``U = Vc`` the
    power is ``Vc (OCV - Vc) / (R/n)``, at the rated current ``I`` it is ``I (OCV - (R/n) I)``
    (on the normal branch, ``I <= OCV / (2 R/n)``), and no more than ``OCV^2 / (4 R/n)``.
    """
    from tuflexperf.models.battery import open_circuit_voltage_v

    rows = pack_rows(side.battery, battery)
    cutoff = rows.cutoff_v
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        ocv = np.asarray(open_circuit_voltage_v(side.params, rows.reserve_charge_ah,
                                                rows.circuit_packs), dtype=float)
        r = side.params.resistance_ohm / rows.circuit_packs
        most = ocv * ocv / (4.0 * r)
        limit = np.where(cutoff >= 0.5 * ocv, cutoff * (ocv - cutoff) / r, most)
        if rows.rating_a is not None:
            current = rows.rating_a * rows.packs_per_engine
            limit = np.fmin(limit, np.where(current <= ocv / (2.0 * r),
                                            current * (ocv - r * current), most))
    return np.where(np.isfinite(limit), limit, -np.inf)
