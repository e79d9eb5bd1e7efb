"""Least throttle for steady level flight, ``T(x, V) >= D(V)``, over an airspeed grid.

Shared by trim (all engines) and one-engine-inoperative. The thrust excess
``E(x, V) = T(x, V) - D(V)`` is quadratic in the throttle ``x`` (poly22 thrust), so
the least throttle is the least root in [0, 1] of a quadratic, in closed form over
the whole grid at once (:func:`tuflexperf.models.thrust.least_throttle_of`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from tuflexperf.models.thrust import least_throttle_of

MAX_GRID_STEP_M_S = 0.5

ExcessFunction = Callable[[Any, Any], Any]


def airspeed_grid(min_airspeed_m_s: float, max_airspeed_m_s: float) -> np.ndarray:
    """Airspeeds from min to max, both included, at most 0.5 m/s apart (SPEC 3)."""
    return airspeed_grids(np.array([min_airspeed_m_s]), np.array([max_airspeed_m_s]))[0]


def airspeed_grids(min_airspeed_m_s: np.ndarray, max_airspeed_m_s: np.ndarray) -> np.ndarray:
    """One :func:`airspeed_grid` per pair of bounds, as rows of one array.

    Parameters
    ----------
    min_airspeed_m_s, max_airspeed_m_s : ndarray of shape ``(R,)``
        Each row's bounds [m/s], the least below the greatest.

    Returns
    -------
    ndarray of shape ``(R, K)``
        Row ``i`` holds the ``n_i + 1`` airspeeds of its own grid, numbers identical to
        ``numpy.linspace(min_i, max_i, n_i + 1)``, then its greatest airspeed repeated up
        to the longest row's ``K``: a repeated airspeed changes no highest or least value
        over the row, so a batch whose bounds vary per row answers as each case alone.
    """
    low = np.asarray(min_airspeed_m_s, dtype=float).reshape(-1)
    high = np.asarray(max_airspeed_m_s, dtype=float).reshape(-1)
    steps = np.maximum(1, np.ceil((high - low) / MAX_GRID_STEP_M_S - 1e-9)).astype(np.intp)
    index = np.arange(int(steps.max()) + 1, dtype=float)[None, :]
    # numpy.linspace's own arithmetic (j * step + start, the end set exactly), so one case's
    # grid and its row of a batch are the same numbers
    grids = index * ((high - low) / steps)[:, None] + low[:, None]
    return np.where(index >= steps[:, None], high[:, None], grids)


@dataclass(frozen=True)
class LeastThrottleSolver:
    """Least throttle in [0, 1] with ``excess(x, V) >= 0`` at each airspeed; NaN where none.

    The excess (poly22 thrust minus drag) is quadratic in the throttle, so the least
    throttle is the least root of a quadratic, exact and vectorised over the grid
    (:func:`tuflexperf.models.thrust.least_throttle_of`); nothing iterates.
    """

    excess: ExcessFunction

    def __call__(self, airspeeds_m_s: np.ndarray) -> np.ndarray:
        v = np.asarray(airspeeds_m_s, dtype=float)
        throttle, reached = least_throttle_of(lambda x: self.excess(x, v))
        throttle = np.broadcast_to(np.asarray(throttle, dtype=float), v.shape)
        reached = np.broadcast_to(np.asarray(reached, dtype=float), v.shape)
        return np.where(reached > 0.5, throttle, np.nan)


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
    """A solver for ``excess(throttle, airspeed)`` (one code path: numpy and CasADi)."""
    return LeastThrottleSolver(excess=excess)
