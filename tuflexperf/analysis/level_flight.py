"""Least throttle for steady level flight, ``T(x, V) >= D(V)``, over an airspeed grid.

Shared by trim (all engines) and one-engine-inoperative. The throttle is found
by a CasADi Newton rootfinder on the thrust excess ``E(x, V) = T(x, V) - D(V)``,
mapped over the grid and built once per case. A coarse throttle scan brackets
the least root first, so Newton starts beside the right root; a root that leaves
its bracket falls back to bisection.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

MAX_GRID_STEP_M_S = 0.5
_SCAN = np.linspace(0.0, 1.0, 41)  # bracket width 0.025 in throttle

ExcessFunction = Callable[[Any, Any], Any]


def airspeed_grid(min_airspeed_m_s: float, max_airspeed_m_s: float) -> np.ndarray:
    """Airspeeds from min to max, both included, at most 0.5 m/s apart (SPEC 3)."""
    steps = max(1, math.ceil((max_airspeed_m_s - min_airspeed_m_s) / MAX_GRID_STEP_M_S - 1e-9))
    return np.linspace(min_airspeed_m_s, max_airspeed_m_s, steps + 1)


@dataclass
class LeastThrottleSolver:
    """Least throttle in [0, 1] with ``excess(x, V) >= 0`` at each airspeed; NaN where none."""

    excess: ExcessFunction
    _rootfinders: dict[int, Any]

    def __call__(self, airspeeds_m_s: np.ndarray) -> np.ndarray:
        v = np.asarray(airspeeds_m_s, dtype=float)
        scan = np.asarray(self.excess(_SCAN[:, None], v[None, :]), dtype=float)
        feasible = scan >= 0.0
        reachable = feasible.any(axis=0)
        first = np.argmax(feasible, axis=0)
        result = np.full(v.shape, np.nan)
        result[reachable & (first == 0)] = 0.0
        todo = reachable & (first > 0)
        if not todo.any():
            return result
        low = _SCAN[first[todo] - 1]
        high = _SCAN[first[todo]]
        roots = self._newton(v[todo], high)
        bad = ~((roots >= low - 1e-12) & (roots <= high + 1e-12) & np.isfinite(roots))
        if bad.any():
            roots[bad] = self._bisect(v[todo][bad], low[bad], high[bad])
        result[todo] = np.clip(roots, low, high)
        return result

    def _newton(self, v: np.ndarray, guess: np.ndarray) -> np.ndarray:
        n = v.size
        if n not in self._rootfinders:
            import casadi as ca

            x = ca.MX.sym("throttle")
            speed = ca.MX.sym("airspeed_m_s")
            rf = ca.rootfinder(
                "least_throttle",
                "newton",
                {"x": x, "p": speed, "g": self.excess(x, speed)},
                {"abstol": 1e-13, "max_iter": 60, "error_on_fail": False},
            )
            self._rootfinders[n] = rf.map(n)
        return np.asarray(self._rootfinders[n](guess[None, :], v[None, :]), dtype=float).ravel()

    def _bisect(self, v: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
        low, high = low.copy(), high.copy()
        for _ in range(60):
            mid = 0.5 * (low + high)
            ok = np.asarray(self.excess(mid, v), dtype=float) >= 0.0
            high = np.where(ok, mid, high)
            low = np.where(ok, low, mid)
        return high


@dataclass(frozen=True)
class ThrottleSweep:
    """Least level-flight throttle at each airspeed of a grid; NaN where not attainable."""

    airspeed_m_s: np.ndarray
    throttle: np.ndarray

    @property
    def all_feasible(self) -> bool:
        return bool(np.all(np.isfinite(self.throttle)))

    @property
    def min_throttle(self) -> float | None:
        finite = self.throttle[np.isfinite(self.throttle)]
        return float(finite.min()) if finite.size else None

    @property
    def airspeed_at_min_throttle_m_s(self) -> float | None:
        if self.min_throttle is None:
            return None
        return float(self.airspeed_m_s[np.nanargmin(self.throttle)])

    @property
    def level_flight_airspeed_range_m_s(self) -> list[float] | None:
        """Lowest and highest grid airspeed where level flight is attainable."""
        feasible = self.airspeed_m_s[np.isfinite(self.throttle)]
        return [float(feasible.min()), float(feasible.max())] if feasible.size else None

    def lists(self) -> dict[str, list[float | None]]:
        """The grid as JSON lists (``None`` where not attainable)."""
        return {
            "airspeed_m_s": [float(v) for v in self.airspeed_m_s],
            "throttle": [float(x) if np.isfinite(x) else None for x in self.throttle],
        }


def least_throttle_solver(excess: ExcessFunction) -> LeastThrottleSolver:
    """Build a solver for ``excess(throttle, airspeed)`` (one code path: numpy and CasADi)."""
    return LeastThrottleSolver(excess=excess, _rootfinders={})
