"""Point performance: stall, minimum-drag speed, level-speed range, climb, ceilings, OEI.

Every answer is bounded by stall (SPEC 3): no airspeed below ``stall_margin x V_stall``
counts. Each quantity is one small CasADi problem built once per case
(:class:`PerformanceProblems`), started from a vectorised scan of the same model
functions that also brackets it (so the local solve finds the global answer to the
scan's resolution and refines it to round-off):

- max / least level speed: Newton rootfinder on ``T(1, V) - D(V) = 0`` in its bracket;
- best rate of climb ``Vy`` (max ``V (T - D) / W``) and best angle ``Vx`` (max
  ``(T - D) / W``): Newton rootfinder on the derivative, or the stall bound;
- ceilings: the highest ``h`` where the best ``R/C(V, h)`` over ``V >= margin V_stall(h)``
  equals ``c`` — a 2x2 Newton rootfinder on ``R/C = c`` with ``dR/C/dV = 0`` (or ``V`` on
  the stall bound) from a (h, V) scan, with
  ``c = 0.5 m/s`` (service) and ``0`` (absolute); density from the ISA at ``h`` with the
  case's temperature offset, thrust scaled by ``rho / rho_ref`` (SPEC 3);
- one engine inoperative: max level speed and max climb gradient, each engine dead in
  turn, the worse reported.

Climb uses the small-angle model (drag at ``L = W``), Anderson, *Aircraft Performance
and Design*, section 5.10. The search for level flight ends where full thrust falls
below parasite drag alone (an exact quadratic bound); a thrust model that keeps up with
parasite drag at every speed has no maximum speed, and the result says so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tuflexperf.analysis.attainable import stall_margin_of
from tuflexperf.errors import NotAttainable
from tuflexperf.io.case import Case
from tuflexperf.models.aircraft import (
    climb_gradient,
    climb_rate_m_s,
    climb_sine,
    level_flight_drag_n,
    minimum_drag_speed_m_s,
    stall_speed_m_s,
)
from tuflexperf.models.atmosphere import isa_density_kg_m3
from tuflexperf.models.powertrain import jet_velocity_ceiling_m_s
from tuflexperf.models.thrust import (
    DeadEngineMode,
    is_extrapolated,
    total_thrust_n,
    unlapsed_density_warning,
)

SERVICE_CEILING_CLIMB_RATE_M_S = 0.5
CEILING_SEARCH_TOP_M = 20_000.0  # the ISA model's range
_SCAN_POINTS = 1201
_CEILING_SCAN_ALTITUDES = 201
_CEILING_SCAN_SPEEDS = 301
_CLIMB_TABLE_STEP_M_S = 0.5
_CLIMB_TABLE_MAX_POINTS = 401


def _dead_mode(case: Case) -> DeadEngineMode:
    oei = case.requirements.oei
    return "windmilling" if oei is None else oei.dead_engine


@dataclass(frozen=True)
class OeiPerformance:
    """One engine dead: its max level speed [m/s] and max climb gradient [-] (and its speed)."""

    dead_engine: str
    max_level_speed_m_s: float | None
    max_climb_gradient: float
    max_climb_gradient_speed_m_s: float
    # full-throttle rate of climb [m/s] at the result's ``climb_airspeed_m_s`` (the report's
    # curve; negative where the live engines cannot hold level flight)
    climb_rate_curve_m_s: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)

    def to_dict(self) -> dict[str, Any]:
        return {
            "dead_engine": self.dead_engine,
            "max_level_speed_m_s": self.max_level_speed_m_s,
            "max_climb_gradient": self.max_climb_gradient,
            "max_climb_gradient_speed_m_s": self.max_climb_gradient_speed_m_s,
            "climb_rate_m_s": [float(v) for v in self.climb_rate_curve_m_s],
        }


@dataclass(frozen=True)
class PerformanceResult:
    """Point performance of a case at its atmosphere (true airspeeds, SI units).

    ``None`` marks what does not exist (no level flight, a ceiling below the
    search's foot or above 20 km); ``notes`` say why.
    """

    density_kg_m3: float
    altitude_m: float
    stall_speed_m_s: float
    stall_margin: float
    least_airspeed_m_s: float
    polar_minimum_drag_speed_m_s: float
    minimum_drag_speed_m_s: float
    min_level_speed_m_s: float | None
    max_level_speed_m_s: float | None
    max_climb_rate_m_s: float
    best_climb_rate_speed_m_s: float
    max_climb_gradient: float
    best_climb_angle_speed_m_s: float
    service_ceiling_m: float | None
    absolute_ceiling_m: float | None
    oei: tuple[OeiPerformance, ...]
    oei_dead_engine_mode: str
    takeoff_distance_to_obstacle_m: float | None
    takeoff_obstacle_height_m: float
    climb_airspeed_m_s: np.ndarray = field(repr=False)
    climb_rate_curve_m_s: np.ndarray = field(repr=False)
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()
    # airspeed from which the fans make no thrust (None without jet_area_m2 or fan_area_m2)
    jet_velocity_ceiling_m_s: float | None = None

    @property
    def oei_critical(self) -> OeiPerformance | None:
        """The dead engine with the lower climb gradient (None for a single engine)."""
        return min(self.oei, key=lambda c: c.max_climb_gradient) if self.oei else None

    @property
    def oei_max_climb_gradient(self) -> float | None:
        worst = self.oei_critical
        return None if worst is None else worst.max_climb_gradient

    @property
    def oei_max_level_speed_m_s(self) -> float | None:
        if not self.oei:
            return None
        speeds = [c.max_level_speed_m_s for c in self.oei]
        return None if any(s is None for s in speeds) else min(speeds)

    def to_dict(self) -> dict[str, Any]:
        worst = self.oei_critical
        return {
            "density_kg_m3": self.density_kg_m3,
            "altitude_m": self.altitude_m,
            "stall_speed_m_s": self.stall_speed_m_s,
            "stall_margin": self.stall_margin,
            "least_airspeed_m_s": self.least_airspeed_m_s,
            "minimum_drag_speed_m_s": self.minimum_drag_speed_m_s,
            "polar_minimum_drag_speed_m_s": self.polar_minimum_drag_speed_m_s,
            "min_level_speed_m_s": self.min_level_speed_m_s,
            "max_level_speed_m_s": self.max_level_speed_m_s,
            "max_climb_rate_m_s": self.max_climb_rate_m_s,
            "best_climb_rate_speed_m_s": self.best_climb_rate_speed_m_s,
            "max_climb_gradient": self.max_climb_gradient,
            "best_climb_angle_speed_m_s": self.best_climb_angle_speed_m_s,
            "service_ceiling_m": self.service_ceiling_m,
            "service_ceiling_climb_rate_m_s": SERVICE_CEILING_CLIMB_RATE_M_S,
            "absolute_ceiling_m": self.absolute_ceiling_m,
            "oei_max_climb_gradient": self.oei_max_climb_gradient,
            "oei_max_level_speed_m_s": self.oei_max_level_speed_m_s,
            "oei_critical_dead_engine": None if worst is None else worst.dead_engine,
            "oei_dead_engine_mode": self.oei_dead_engine_mode,
            "oei": [c.to_dict() for c in self.oei],
            "takeoff_distance_to_obstacle_m": self.takeoff_distance_to_obstacle_m,
            "takeoff_obstacle_height_m": self.takeoff_obstacle_height_m,
            "jet_velocity_ceiling_m_s": self.jet_velocity_ceiling_m_s,
            "climb": {
                "airspeed_m_s": [float(v) for v in self.climb_airspeed_m_s],
                "climb_rate_m_s": [float(v) for v in self.climb_rate_curve_m_s],
            },
            "notes": list(self.notes),
            "warnings": list(self.warnings),
        }


class PerformanceProblems:
    """The case's point-performance problems, each a CasADi rootfinder built once.

    Parameters
    ----------
    case : Case
        The loaded case (aircraft, propulsion, atmosphere, requirements).

    References
    ----------
    Anderson, *Aircraft Performance and Design*, sections 5.4 (max speed), 5.10 (rate of
    climb, Vx, Vy), 5.11 (absolute and service ceilings).
    """

    def __init__(self, case: Case) -> None:
        import casadi as ca

        self.case = case
        self.aircraft = case.aircraft
        self.propulsion = case.propulsion
        self.margin = stall_margin_of(case)
        self.offset_k = case.atmosphere.temperature_offset_k
        self.mode = _dead_mode(case)
        n_engines = len(self.propulsion.engines)
        self.dead_cases: tuple[int | None, ...] = (None,) + (
            tuple(range(n_engines)) if n_engines >= 2 else ()
        )
        v = ca.SX.sym("airspeed_m_s")
        rho = ca.SX.sym("density_kg_m3")
        newton = {"abstol": 1e-12, "max_iter": 60, "error_on_fail": False}
        self._excess_root: dict[int | None, Any] = {}
        self._gradient_peak: dict[int | None, Any] = {}
        for dead in self.dead_cases:
            thrust = total_thrust_n(self.propulsion, 1.0, v, rho, dead, self.mode)
            excess = thrust - level_flight_drag_n(self.aircraft, v, rho)
            gradient = climb_gradient(self.aircraft, thrust, v, rho)
            # level-speed bounds: T(1, V) = D(V); Vx: d/dV (T - D)/W = 0 (Anderson 5.10)
            self._excess_root[dead] = ca.rootfinder(
                "level_speed", "newton", {"x": v, "p": rho, "g": excess}, newton
            )
            self._gradient_peak[dead] = ca.rootfinder(
                "best_angle_speed", "newton",
                {"x": v, "p": rho, "g": ca.jacobian(gradient, v)}, newton,
            )
        thrust = total_thrust_n(self.propulsion, 1.0, v, rho)
        rate = climb_rate_m_s(self.aircraft, thrust, v, rho)
        # Vy: d/dV [V (T - D) / W] = 0
        self._rate_peak = ca.rootfinder(
            "best_rate_speed", "newton", {"x": v, "p": rho, "g": ca.jacobian(rate, v)}, newton
        )
        # ceiling: altitude in km (scaling), density from the ISA at that altitude
        h_km = ca.SX.sym("altitude_km")
        target = ca.SX.sym("climb_rate_m_s")
        rho_h = isa_density_kg_m3(1000.0 * h_km, self.offset_k)
        thrust_h = total_thrust_n(self.propulsion, 1.0, v, rho_h)
        rate_h = climb_rate_m_s(self.aircraft, thrust_h, v, rho_h)
        stall_h = self.margin * stall_speed_m_s(self.aircraft, rho_h)
        # ceiling (V, h): R/C = c at the best airspeed, dR/C/dV = 0 or V on the stall bound
        x = ca.vertcat(v, h_km)
        slope = ca.jacobian(rate_h, v)
        self._ceiling_free = ca.rootfinder(
            "ceiling", "newton", {"x": x, "p": target, "g": ca.vertcat(rate_h - target, slope)},
            newton,
        )
        self._ceiling_stall = ca.rootfinder(
            "ceiling_at_stall", "newton",
            {"x": x, "p": target, "g": ca.vertcat(rate_h - target, v - stall_h)}, newton,
        )
        self._rate_slope = ca.Function("rate_slope", [v, h_km], [slope])
        self._ceiling_grid: tuple[np.ndarray, ...] | None = None

    # --- the model on numpy (the same functions as the NLPs, through the backend) ----------
    def least_airspeed_m_s(self, rho: Any) -> Any:
        """Stall speed times the envelope's margin [m/s] at density ``rho`` [kg/m^3]."""
        return self.margin * stall_speed_m_s(self.aircraft, rho)

    def excess_n(self, v: Any, rho: Any, dead: int | None = None) -> Any:
        """Full-throttle thrust minus level-flight drag [N] (numpy)."""
        thrust = total_thrust_n(self.propulsion, 1.0, v, rho, dead, self.mode)
        return thrust - level_flight_drag_n(self.aircraft, v, rho)

    def climb_rate(self, v: Any, rho: Any, dead: int | None = None) -> Any:
        """Full-throttle rate of climb [m/s], all engines or engine ``dead`` out (numpy)."""
        thrust = total_thrust_n(self.propulsion, 1.0, v, rho, dead, self.mode)
        return climb_rate_m_s(self.aircraft, thrust, v, rho)

    def _steady_gradient(self, v: Any, rho: Any, dead: int | None) -> Any:
        """Full-throttle ``(T - D) / W`` [-] (numpy), not yet bounded by a vertical climb."""
        thrust = total_thrust_n(self.propulsion, 1.0, v, rho, dead, self.mode)
        return climb_gradient(self.aircraft, thrust, v, rho)

    def gradient(self, v: Any, rho: Any, dead: int | None = None) -> Any:
        """Full-throttle climb gradient [-] (numpy), at most 1 (a vertical climb)."""
        return climb_sine(self._steady_gradient(v, rho, dead))

    def vertical_range_m_s(self, rho: float, dead: int | None = None) -> tuple[float, float] | None:
        """(lowest, highest) scanned airspeed [m/s] where full thrust exceeds weight plus drag
        (a gradient above 1: the climb is vertical), or ``None`` where it nowhere does."""
        grid, _ = self.scan(rho)
        over = grid[np.asarray(self._steady_gradient(grid, rho, dead), dtype=float) > 1.0]
        return (float(over[0]), float(over[-1])) if over.size else None

    def speed_cap_m_s(self, rho: Any) -> Any:
        """Speed [m/s] above which full thrust stays below parasite drag (``inf`` if none).

        All engines' full-throttle thrust is a quadratic in V (scaled by ``rho / rho_ref``);
        drag is at least ``q S cd0``, so beyond the largest root of ``T(V) - q S cd0`` there
        is no level flight (a dead engine only adds drag). Vectorised over ``rho``.
        """
        rho = np.asarray(rho, dtype=float)
        t0, t1, t2 = (
            np.asarray(total_thrust_n(self.propulsion, 1.0, x, rho), dtype=float) + 0.0 * rho
            for x in (0.0, 1.0, 2.0)
        )
        a = 0.5 * (t2 - 2.0 * t1 + t0)
        b = t1 - t0 - a
        a = a - 0.5 * rho * self.aircraft.wing_area_m2 * self.aircraft.cd0
        disc = b * b - 4.0 * a * t0
        safe_a = np.where(a < 0.0, a, -1.0)
        root = np.sqrt(np.where(disc > 0.0, disc, 0.0))
        largest = np.maximum((-b - root) / (2.0 * safe_a), (-b + root) / (2.0 * safe_a))
        cap = np.where(a >= 0.0, np.inf, np.where(disc < 0.0, 0.0, largest))
        return float(cap) if cap.ndim == 0 else cap

    # --- solves ------------------------------------------------------------------------------
    @staticmethod
    def _root_in(rootfinder: Any, rho: float, low: float, high: float,
                 residual: Any) -> float:
        """Newton root in the scan's bracket [low, high] (a sign change of ``residual``).

        Newton from the midpoint of a bracket 1/1200 of the speed range wide converges
        quadratically; should it leave the bracket, bisection on the residual's sign
        (numpy, the same model) finishes the job.
        """
        x = float(rootfinder((low + high) / 2.0, rho))
        if math.isfinite(x) and low <= x <= high:
            return x
        f_low = float(residual(low))
        for _ in range(200):
            mid = 0.5 * (low + high)
            if mid in (low, high):
                break
            if (float(residual(mid)) >= 0.0) == (f_low >= 0.0):
                low = mid
            else:
                high = mid
        return 0.5 * (low + high)

    @staticmethod
    def _peak_in(rootfinder: Any, rho: float, grid: np.ndarray, values: np.ndarray,
                 objective: Any) -> float:
        """Airspeed [m/s] of the largest ``objective``: the scan's best point refined.

        At the scan's first point (the stall bound) the answer is that bound; inside,
        Newton on the objective's derivative from the best grid point, kept only if it
        stays between the neighbours and does not lower the objective, else a golden
        section on the objective between the neighbours.
        """
        i = int(np.nanargmax(values))
        if i == 0 or i == len(grid) - 1:
            return float(grid[i])
        low, high, best = float(grid[i - 1]), float(grid[i + 1]), float(grid[i])
        x = float(rootfinder(best, rho))
        if math.isfinite(x) and low <= x <= high and float(objective(x)) >= values[i]:
            return x
        golden = (math.sqrt(5.0) - 1.0) / 2.0
        for _ in range(100):
            a, b = high - golden * (high - low), low + golden * (high - low)
            if float(objective(a)) >= float(objective(b)):
                high = b
            else:
                low = a
        return 0.5 * (low + high)

    def jet_ceiling_m_s(self, rho: Any) -> Any:
        """Airspeed [m/s] from which the fans make no thrust (:func:`jet_velocity_ceiling_m_s`;
        ``inf`` without an area). Vectorised over ``rho``."""
        ceiling = np.asarray(jet_velocity_ceiling_m_s(self.propulsion, rho), dtype=float)
        return float(ceiling) if ceiling.ndim == 0 else ceiling

    def scan(self, rho: float) -> tuple[np.ndarray, float]:
        """Airspeed grid [m/s] from the least airspeed to the speed cap, and that cap.

        The grid ends at the fans' jet velocity when that comes first: beyond it the
        extrapolated thrust model has no fan behind it (then the cap is that ceiling).
        """
        low = float(self.least_airspeed_m_s(rho))
        cap = self.speed_cap_m_s(rho)
        top = cap if math.isfinite(cap) else 10.0 * low
        top = max(top * 1.001, low * 1.001)
        ceiling = self.jet_ceiling_m_s(rho)
        if ceiling < top:
            cap, top = ceiling, max(ceiling, low * 1.001)
        return np.linspace(low, top, _SCAN_POINTS), cap

    def level_speed_range(
        self, rho: float, dead: int | None = None
    ) -> tuple[float | None, float | None, bool]:
        """(least, greatest) airspeed [m/s] of level flight at full throttle, stall-bounded.

        The third value is False when the greatest speed is unbounded within the model
        (then it is ``None``). ``(None, None, True)``: no level flight at any speed.
        """
        grid, cap = self.scan(rho)
        ok = np.asarray(self.excess_n(grid, rho, dead), dtype=float) >= 0.0
        if not ok.any() or self.jet_ceiling_m_s(rho) <= grid[0]:
            return None, None, True
        first, last = int(np.argmax(ok)), int(len(ok) - 1 - np.argmax(ok[::-1]))
        rf = self._excess_root[dead]

        def residual(v: float) -> float:
            return float(self.excess_n(v, rho, dead))

        if first == 0:
            least = float(grid[0])
        else:
            least = self._root_in(rf, rho, float(grid[first - 1]), float(grid[first]), residual)
        if last == len(grid) - 1 and not math.isfinite(cap):
            return least, None, False
        if last == len(grid) - 1:
            return least, float(grid[-1]), True
        greatest = self._root_in(rf, rho, float(grid[last]), float(grid[last + 1]), residual)
        return least, greatest, True

    def max_climb_rate(self, rho: float) -> tuple[float, float]:
        """(max rate of climb [m/s], Vy [m/s]) at density ``rho``, V >= margin x stall."""
        grid, _ = self.scan(rho)
        values = np.asarray(self.climb_rate(grid, rho), dtype=float)
        vy = self._peak_in(self._rate_peak, rho, grid, values,
                           lambda v: self.climb_rate(v, rho))
        return float(self.climb_rate(vy, rho)), vy

    def max_gradient(self, rho: float, dead: int | None = None) -> tuple[float, float]:
        """(max climb gradient [-], Vx [m/s]) at density ``rho``, V >= margin x stall."""
        grid, _ = self.scan(rho)
        values = np.asarray(self.gradient(grid, rho, dead), dtype=float)
        vx = self._peak_in(self._gradient_peak[dead], rho, grid, values,
                           lambda v: self.gradient(v, rho, dead))
        return float(self.gradient(vx, rho, dead)), vx

    def ceiling_m(self, climb_rate_target: float) -> tuple[float | None, str]:
        """Highest altitude [m] where the best rate of climb reaches the target [m/s].

        Searched from ``min(0, case altitude)`` to 20 km. ``None`` with a note when the
        target is not reached at the foot, or is still exceeded at 20 km.
        """
        altitudes, best, best_v, at_stall = self._ceiling_scan()
        foot = float(altitudes[0])
        reach = best >= climb_rate_target
        if not reach[0]:
            return None, (
                f"the best rate of climb at {foot:g} m is {best[0]:.2f} m/s, below "
                f"{climb_rate_target:g} m/s"
            )
        if reach[-1]:
            return None, (
                f"still climbing at {best[-1]:.2f} m/s at {CEILING_SEARCH_TOP_M:g} m, the top of "
                "the ISA model" + ("" if self.propulsion.reference_density_kg_m3 is not None
                                   else " (thrust not scaled with density: no reference density)")
            )
        k = int(len(reach) - 1 - np.argmax(reach[::-1]))
        h_low, h_high = float(altitudes[k]), float(altitudes[k + 1])
        order = (
            (self._ceiling_stall, self._ceiling_free) if at_stall[k]
            else (self._ceiling_free, self._ceiling_stall)
        )
        for rootfinder in order:
            sol = np.asarray(rootfinder([best_v[k], h_low / 1000.0], climb_rate_target)).ravel()
            speed, altitude = float(sol[0]), 1000.0 * float(sol[1])
            if not (np.all(np.isfinite(sol)) and h_low - 1e-6 <= altitude <= h_high + 1e-6):
                continue
            rho = float(isa_density_kg_m3(altitude, self.offset_k))
            least = float(self.least_airspeed_m_s(rho))
            slope = float(self._rate_slope(speed, altitude / 1000.0))
            if rootfinder is self._ceiling_free and speed >= least * (1.0 - 1e-9):
                return altitude, ""
            if rootfinder is self._ceiling_stall and slope <= 1e-9:  # the peak lies below stall
                return altitude, ""
        # Newton left the bracket: bisection on the (stall-bounded) best rate of climb
        for _ in range(80):
            mid = 0.5 * (h_low + h_high)
            rate, _ = self.max_climb_rate(float(isa_density_kg_m3(mid, self.offset_k)))
            if rate >= climb_rate_target:
                h_low = mid
            else:
                h_high = mid
        return 0.5 * (h_low + h_high), ""

    def _ceiling_scan(self) -> tuple[np.ndarray, ...]:
        """Best full-throttle rate of climb per altitude on a 201 x 301 (h, V) grid, once.

        Returns the altitudes [m], the best rate [m/s], its airspeed [m/s] and whether
        that airspeed is the stall bound.
        """
        if self._ceiling_grid is None:
            foot = min(0.0, float(self.case.atmosphere.altitude_m))
            altitudes = np.linspace(foot, CEILING_SEARCH_TOP_M, _CEILING_SCAN_ALTITUDES)
            rho = np.asarray(isa_density_kg_m3(altitudes, self.offset_k), dtype=float)[:, None]
            low = np.asarray(self.least_airspeed_m_s(rho), dtype=float)
            cap = self.speed_cap_m_s(rho)
            top = np.minimum(np.where(np.isfinite(cap), cap, 10.0 * low),
                             self.jet_ceiling_m_s(rho))
            grid = low + (np.maximum(top, 1.001 * low) - low) * np.linspace(
                0.0, 1.0, _CEILING_SCAN_SPEEDS
            )
            rate = np.asarray(self.climb_rate(grid, rho), dtype=float)
            j = np.argmax(rate, axis=1)
            rows = np.arange(len(altitudes))
            self._ceiling_grid = (altitudes, rate[rows, j], grid[rows, j], j == 0)
        return self._ceiling_grid


def solve_performance(case: Case, problems: PerformanceProblems | None = None) -> PerformanceResult:
    """Point performance of ``case`` at its atmosphere (see the module docstring).

    References
    ----------
    Anderson, *Aircraft Performance and Design*, ch. 5 (5.4 max speed, 5.10 climb,
    5.11 ceilings) and 6.7 (take-off to the obstacle).
    """
    from tuflexperf.analysis.airborne import obstacle_height_of
    from tuflexperf.analysis.takeoff import solve_takeoff

    p = problems if problems is not None else PerformanceProblems(case)
    ac, prop = case.aircraft, case.propulsion
    rho = case.density_kg_m3
    notes: list[str] = []
    warnings: list[str] = []
    stall = float(stall_speed_m_s(ac, rho))
    least = float(p.least_airspeed_m_s(rho))
    polar_vmd = float(minimum_drag_speed_m_s(ac, rho))
    vmd = max(polar_vmd, least)
    if polar_vmd < least:
        notes.append(
            f"the polar's minimum-drag speed {polar_vmd:.2f} m/s is below the least airspeed "
            f"{least:.2f} m/s (stall x {p.margin:g}): least drag is at the stall bound"
        )
    v_min, v_max, bounded = p.level_speed_range(rho)
    ceiling = p.jet_ceiling_m_s(rho)
    if v_min is None:
        notes.append("no level flight at full throttle at any airspeed above stall")
    elif not bounded:
        notes.append(
            "full-throttle thrust keeps up with parasite drag at every airspeed: the thrust "
            "model gives no maximum level speed (extrapolation far beyond the tested range)"
        )
    if v_max is not None and v_max >= ceiling * (1.0 - 1e-12):
        notes.append(
            f"max level speed: the fans' static jet velocity {ceiling:.1f} m/s (momentum theory "
            "on jet_area_m2, else fan_area_m2), beyond which a fan makes no thrust; the "
            "extrapolated thrust model would give more"
        )
    if least >= ceiling:
        notes.append(
            f"the least airspeed {least:.2f} m/s is at or beyond the fans' static jet velocity "
            f"{ceiling:.1f} m/s: no level flight"
        )
    max_rate, vy = p.max_climb_rate(rho)
    max_grad, vx = p.max_gradient(rho)
    if vx <= least * (1.0 + 1e-9) and max_grad < 1.0:  # a vertical climb's Vx is said below
        notes.append(f"best climb angle at the least airspeed {least:.2f} m/s (stall-bounded)")
    service, why = p.ceiling_m(SERVICE_CEILING_CLIMB_RATE_M_S)
    if why:
        notes.append(f"service ceiling: {why}")
    absolute, why = p.ceiling_m(0.0)
    if why:
        notes.append(f"absolute ceiling: {why}")
    top = v_max if v_max is not None else float(p.scan(rho)[0][-1])
    top = max(top, least)
    n = min(_CLIMB_TABLE_MAX_POINTS, max(2, math.ceil((top - least) / _CLIMB_TABLE_STEP_M_S) + 1))
    climb_v = np.linspace(least, top, n)
    climb_rate = np.asarray(p.climb_rate(climb_v, rho), dtype=float)
    oei: list[OeiPerformance] = []
    for dead in p.dead_cases[1:]:
        _, oei_max, _ = p.level_speed_range(rho, dead)
        gradient, speed = p.max_gradient(rho, dead)
        curve = np.asarray(p.climb_rate(climb_v, rho, dead), dtype=float) * np.ones_like(climb_v)
        oei.append(OeiPerformance(prop.engines[dead].name, oei_max, gradient, speed, curve))
    height = obstacle_height_of(case)
    try:
        takeoff = solve_takeoff(case)
        obstacle = takeoff.distance_to_obstacle_m
        if obstacle is None:
            notes.append(f"take-off: {takeoff.obstacle_reason}")
    except NotAttainable as exc:
        obstacle = None
        notes.append(f"take-off: {exc}")
    # each answer at the airspeed it is flown at (true): the OEI speeds and the ceilings' Vy
    # (true airspeeds grow with altitude) extrapolate too, unsaid before
    flown: list[tuple[str, float | None]] = [
        ("max level speed", v_max), ("Vy", vy), ("Vx", vx), ("least airspeed", least)]
    for case_oei in oei:
        flown += [("OEI max level speed", case_oei.max_level_speed_m_s),
                  ("OEI Vx", case_oei.max_climb_gradient_speed_m_s)]
    for label, altitude in (("service ceiling", service), ("absolute ceiling", absolute)):
        if altitude is not None:
            flown.append((label, p.max_climb_rate(
                float(isa_density_kg_m3(altitude, p.offset_k)))[1]))
    beyond = {label: v for label, v in flown if v is not None and is_extrapolated(prop, v)}
    if beyond:
        low, high = prop.tested_airspeed_m_s
        values = beyond.values()
        span = f"{min(values):.1f}" + (
            f"-{max(values):.1f}" if max(values) - min(values) >= 0.05 else ""
        )
        warnings.append(
            f"thrust model extrapolated at {span} m/s (tested {low:g}-{high:g} m/s): "
            + ", ".join(dict.fromkeys(beyond))
        )
    for dead in p.dead_cases:
        vertical = p.vertical_range_m_s(rho, dead)
        if vertical is not None:
            who = "full thrust" if dead is None else f"{prop.engines[dead].name} dead, full thrust"
            warnings.append(
                f"{who} exceeds weight plus drag at {vertical[0]:.1f}-{vertical[1]:.1f} m/s: the "
                "climb there is vertical (gradient held at 1, rate of climb at the airspeed); "
                "the steady-climb model (L = W) does not hold, the excess would accelerate it")
    density_note = unlapsed_density_warning(prop, rho)
    if density_note:
        warnings.append(density_note)
    if prop.reference_density_kg_m3 is None:
        warnings.append(
            "ceilings use thrust as measured at every altitude (no reference_density_kg_m3): "
            "they are optimistic"
        )
    return PerformanceResult(
        density_kg_m3=rho,
        altitude_m=float(case.atmosphere.altitude_m),
        stall_speed_m_s=stall,
        stall_margin=p.margin,
        least_airspeed_m_s=least,
        polar_minimum_drag_speed_m_s=polar_vmd,
        minimum_drag_speed_m_s=vmd,
        min_level_speed_m_s=v_min,
        max_level_speed_m_s=v_max,
        max_climb_rate_m_s=max_rate,
        best_climb_rate_speed_m_s=vy,
        max_climb_gradient=max_grad,
        best_climb_angle_speed_m_s=vx,
        service_ceiling_m=service,
        absolute_ceiling_m=absolute,
        oei=tuple(oei),
        oei_dead_engine_mode=p.mode,
        takeoff_distance_to_obstacle_m=obstacle,
        takeoff_obstacle_height_m=height,
        climb_airspeed_m_s=climb_v,
        climb_rate_curve_m_s=climb_rate,
        notes=tuple(notes),
        warnings=tuple(warnings),
        jet_velocity_ceiling_m_s=ceiling if math.isfinite(ceiling) else None,
    )
