"""The take-off on sagging packs, for one case or many: the propulsion's ``reference_voltage_v``.

With a reference voltage and a battery the take-off rolls, rotates and climbs to the
obstacle with each fan's thrust ``T (U/U_ref)^k`` at its packs' loaded voltage ``U``, the
charge drawn per engine beside the distance and the time. The roll is flown per row
(``takeoff``: one row, :func:`tuflexperf.analysis.takeoff.solve_takeoff`), vectorised, in
the reference roll's own time ``tau`` (the exact quadrature of ``m / F_ref``,
:meth:`tuflexperf.analysis.ground_roll.GroundRollRows.roll_history`):

``dt/dtau = F_ref(V) / F(V, q)``, ``ds/dtau = V dt/dtau``, ``dq/dtau = I(V, q) / 3600 dt/dtau``,

classic RK4 over the 100 intervals between the history's airspeeds, the airspeed inside an
interval by cubic Hermite interpolation (``dV/dtau = F_ref / m`` at both ends). The sagging
packs pass through the same airspeeds as the reference roll, only later, so no event is
needed, and where the net force all but vanishes the reference's long intervals carry it
(the ratio stays smooth). The rotation and the airborne part follow the single case
(:data:`~tuflexperf.analysis.airborne.ROTATION_STEPS` RK4 steps, then
:func:`~tuflexperf.analysis.airborne.settle_airborne`).

References
----------
SPEC 3 (thrust and pack voltage); Raymer, *Aircraft Design*, 17.8 (ground roll); Hairer,
Norsett & Wanner, *Solving Ordinary Differential Equations I*, II.1 and II.6 (RK4, Hermite
interpolation).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.analysis.airborne import (
    BEYOND_THE_BATTERY_STATUS,
    ObstaclePath,
    obstacle_path,
    rotation_charge,
    settle_airborne,
)
from tuflexperf.analysis.batch_sagging import SaggingFlight
from tuflexperf.analysis.ground_roll import GroundRollRows
from tuflexperf.analysis.pack_limits import PackRows, pack_rows
from tuflexperf.models.aircraft import (
    climb_gradient,
    ground_roll_net_force_n,
    transition_radius_m,
)
from tuflexperf.models.battery import SECONDS_PER_HOUR

Array = NDArray[np.float64]


@dataclass(frozen=True)
class RollOnPacks:
    """Per row: ground roll [m] and time [s] (rotation included), lift-off speed [m/s],
    attainable (1/0), the acceleration's time [s] and distance [m] at the 101 history
    airspeeds ``(B, 101)``, the charge per fan there [Ah] ``(fans, B, 101)`` and after the
    rotation ``(fans, B)``."""

    distance: Array
    time: Array
    v_lo: Array
    ok: Array
    history_time: Array
    charge_ah: Array
    history_distance: Array | None = None
    history_charge_ah: Array | None = None

    def as_roll(self) -> tuple[Array, Array, Array, Array]:
        """The batch's roll tuple (:meth:`.GroundRollRows.ground_roll`)."""
        return self.distance, self.time, self.v_lo, self.ok


def _flight(m: Any, packs: Any, rows: PackRows) -> SaggingFlight:
    return SaggingFlight(m, packs, rows,
                         tuple(m.propulsion.engines) if packs.own_surfaces else (None,))


class TakeoffPacks:
    """One case's sagging packs for the take-off: its batch of one row
    (:class:`~tuflexperf.analysis.ground_roll.GroundRollRows`), its packs ``side``
    (:class:`~tuflexperf.analysis.pack_limits.PackSide`) and their rows, and the packs'
    full-throttle operating point at any airspeeds (:meth:`point`, the batch's
    :class:`~tuflexperf.analysis.batch_sagging.SaggingFlight`)."""

    def __init__(self, case: Any, side: Any) -> None:
        self.n = len(case.propulsion.engines)
        self.cutoff_v = float(side.battery.cutoff_voltage_v)  # the packs' [V]
        self.side = side
        self.model = GroundRollRows(case.aircraft, case.propulsion, case.density_kg_m3, None, 1)
        self.rows = pack_rows(side.battery)
        self.flight = _flight(self.model, side, self.rows)
        self._references: dict[bytes, tuple[Array, Array]] = {}

    def point(self, charge_ah: Array, speeds: Array) -> tuple[Array, Array, Array]:
        """Thrust [N] ``(K,)``, current [A] and loaded voltage [V] per engine ``(n, K)`` at
        the airspeeds ``speeds`` [m/s] ``(K,)`` after ``charge_ah`` ``(n,)`` or ``(n, K)``
        (a shared power surface: every engine draws the first one's)."""
        v = np.atleast_1d(np.asarray(speeds, dtype=float)).reshape(1, -1)
        key = v.tobytes()
        if key not in self._references:  # the arc's settling asks one airspeed ~150 times
            self._references[key] = self.flight.reference(1.0, v)
        fans = len(self.flight.engines)
        q = np.asarray(charge_ah, dtype=float).reshape(self.n, -1) * np.ones((1, v.size))
        thrust, volts, current, _ = self.flight.loaded(*self._references[key],
                                                       q[:fans, None, :])
        shape = (self.n, v.size)
        return (thrust.reshape(-1), np.broadcast_to(current.reshape(fans, -1), shape),
                np.broadcast_to(volts.reshape(fans, -1), shape))

    def obstacle_path(self, charge_ah: Array | None, height: float) -> ObstaclePath:
        """The arc and climb to the obstacle ``height`` [m] from ``charge_ah`` drawn per
        engine ``(n,)`` (None: full packs) (:func:`path_on_packs`, one row)."""
        fans = len(self.flight.engines)
        start = np.zeros((fans, 1)) if charge_ah is None else \
            np.reshape(charge_ah, (self.n, 1))[:fans]
        return path_on_packs(self.model, self.side, self.rows, start, height)

    def roll(self) -> RollOnPacks:
        """The ground roll and rotation on the packs (:func:`roll_on_packs`, one row)."""
        return roll_on_packs(self.model, self.side, self.rows)

    def release(self) -> tuple[Array, Array, Array, Array]:
        """A catapult's acceleration after the release on full packs
        (:func:`release_on_packs`, one row)."""
        return release_on_packs(self.model, self.side, self.rows)


def roll_on_packs(m: Any, packs: Any, rows: PackRows) -> RollOnPacks:
    """The ground roll and rotation of each row on its sagging packs (see the module).

    ``m`` the batch's physics (``analysis.batch_model.BatchModel``), ``packs`` the case's
    :class:`~tuflexperf.analysis.pack_limits.PackSide`, ``rows`` the rows' packs.
    """
    flight = _flight(m, packs, rows)
    reference = m.ground_roll()
    ok = reference[3] > 0.5
    v_lo = np.where(ok, reference[2], 1.0)
    fans = len(flight.engines)
    mass = flight.mass[:, None]
    tau = np.where(ok[:, None], m.roll_history(ok), 0.0)
    speeds = v_lo[:, None] * np.linspace(0.0, 1.0, tau.shape[1])[None, :]
    force_ref = m.uniform_force()
    slope = force_ref / mass  # dV/dtau at the history's airspeeds
    h = np.diff(tau, axis=1)
    middle = 0.5 * (speeds[:, :-1] + speeds[:, 1:]) + h / 8.0 * (slope[:, :-1] - slope[:, 1:])
    force_middle = m.net_force(middle)

    # the packs' power and the fans' thrust at the reference voltage depend on the airspeed
    # alone: once for all the stages' airspeeds (a stage then solves the packs' voltage only;
    # SaggingFlight.point's sum, on one row 3x fewer evaluations)
    stage_speeds = np.concatenate([speeds, middle], axis=1)
    power, thrusts = flight.reference(1.0, stage_speeds)

    def rates(charge: Array, column: int, reference_force: Array) -> tuple[Array, Array]:
        v = stage_speeds[:, column]
        thrust, _, current, _ = flight.loaded(power[:, :, column], thrusts[:, :, column],
                                              charge)
        loaded = np.asarray(ground_roll_net_force_n(m.aircraft, thrust.reshape(-1, 1),
                                                    v.reshape(-1, 1), m.density),
                            dtype=float).reshape(-1) * np.ones(m.size)
        with np.errstate(divide="ignore", invalid="ignore"):
            stretch = np.where(loaded > 0.0, reference_force / loaded, np.nan)
        return current / SECONDS_PER_HOUR * stretch, stretch

    q = np.zeros((fans, m.size))
    t = np.zeros(m.size)
    s = np.zeros(m.size)
    times, lengths, charges = [t], [s], [q]
    with np.errstate(invalid="ignore", over="ignore"):
        for i in range(tau.shape[1] - 1):
            v0, vm, v1 = speeds[:, i], middle[:, i], speeds[:, i + 1]
            f0, fm, f1 = force_ref[:, i], force_middle[:, i], force_ref[:, i + 1]
            step = h[:, i]
            mid = speeds.shape[1] + i  # the middle's column among the stages' airspeeds
            k1, d1 = rates(q, i, f0)
            k2, d2 = rates(q + 0.5 * step * k1, mid, fm)
            k3, d3 = rates(q + 0.5 * step * k2, mid, fm)
            k4, d4 = rates(q + step * k3, i + 1, f1)
            q = q + step / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
            t = t + step / 6.0 * (d1 + 2.0 * d2 + 2.0 * d3 + d4)
            s = s + step / 6.0 * (v0 * d1 + 2.0 * vm * (d2 + d3) + v1 * d4)
            times.append(t)
            lengths.append(s)
            charges.append(q)
        # a row whose loaded force vanished at a stage went NaN: it never lifts off
        ok &= np.isfinite(t) & np.isfinite(s) & np.all(np.isfinite(q), axis=0)
        last = speeds.shape[1] - 1  # the lift-off speed's column
        ok &= rates(q, last, force_ref[:, -1])[1] > 0.0  # and at lift-off itself
        rotation = np.asarray(m.aircraft.takeoff.rotation_time_s, dtype=float).reshape(-1) \
            * np.ones(m.size)
        q = rotation_charge(lambda charge: flight.loaded(
            power[:, :, last], thrusts[:, :, last], charge)[2] / SECONDS_PER_HOUR,
            q, np.where(ok, rotation, 0.0))
    return RollOnPacks(
        distance=np.where(ok, s + v_lo * rotation, np.nan),
        time=np.where(ok, t + rotation, np.nan),
        v_lo=reference[2],
        ok=ok.astype(float),
        history_time=np.where(ok[:, None], np.stack(times, axis=1), np.nan),
        charge_ah=q,
        history_distance=np.where(ok[:, None], np.stack(lengths, axis=1), np.nan),
        history_charge_ah=np.where(ok[:, None], np.stack(charges, axis=-1), np.nan),
    )


def release_on_packs(m: Any, packs: Any, rows: PackRows) -> tuple[Array, Array, Array, Array]:
    """A catapult's acceleration after the release on full packs, per row
    (:meth:`.GroundRollRows.release_run`; the charge per fan flown)."""
    flight = _flight(m, packs, rows)
    full = np.zeros((len(flight.engines), m.size, 1))

    def thrust_and_current(speed: Array) -> tuple[Array, Array]:
        thrust, _, current, _ = flight.loaded(*flight.reference(1.0, speed), full)
        return thrust, current

    return m.release_run(thrust_and_current)


def path_on_packs(m: Any, packs: Any, rows: PackRows, start: Array, height: Any
                  ) -> ObstaclePath:
    """Transition arc + climb to the obstacle ``height`` [m] per row on the sagging packs from
    ``start`` [Ah] drawn per fan ``(fans, B)`` after the roll and rotation (a catapult's
    release acceleration): :func:`~tuflexperf.analysis.airborne.settle_airborne` at the
    transition speed, its power and reference thrust taken once for its ~150 iterations
    (``SaggingFlight.reference``). ``takeoff`` flies one row
    (:meth:`TakeoffPacks.obstacle_path`)."""
    flight = _flight(m, packs, rows)
    v_tr = m.transition_speed()
    radius = np.asarray(transition_radius_m(v_tr.reshape(-1, 1),
                                            m.aircraft.takeoff.transition_load_factor),
                        dtype=float).reshape(-1) * np.ones(m.size)
    tall = np.asarray(height, dtype=float).reshape(-1) * np.ones(m.size)
    power, thrusts = (x[:, :, 0] for x in flight.reference(1.0, v_tr.reshape(-1, 1)))

    def point(charge: Array) -> tuple[Array, Array, Array]:
        thrust, volts, current, _ = flight.loaded(power, thrusts, charge)
        return thrust, current, volts

    def gradient_of(thrust: Any) -> Any:
        return np.asarray(climb_gradient(m.aircraft, np.reshape(thrust, (-1, 1)),
                                         v_tr.reshape(-1, 1), m.density),
                          dtype=float).reshape(-1)

    air = settle_airborne(radius, v_tr, tall, start, point, gradient_of, rows.cutoff_v)
    # the climb's gradient is NaN where the obstacle is not reached: an infinite climb
    return obstacle_path(v_tr, radius, tall, air.arc_gradient, air.climb_gradient, air,
                         np.min(point(air.charge_ah)[2], axis=0))


def airborne_on_packs(m: Any, packs: Any, rows: PackRows, roll: RollOnPacks,
                      height: Any) -> tuple[Array, NDArray[np.bool_], Any]:
    """Transition arc + climb to the obstacle [m] per row on the sagging packs from the
    charge after the roll and rotation (:func:`path_on_packs`); ``inf`` where never
    cleared. And per row whether the packs reach their cut-off in the climb before the
    obstacle (the take-off is then not attainable, as the single case's), and the settled
    path (:class:`~tuflexperf.analysis.airborne.AirborneOnPacks`: the mission flies its
    gradients)."""
    path = path_on_packs(m, packs, rows, np.where(roll.ok > 0.5, roll.charge_ah, 0.0), height)
    air = path.settled
    return path.distance_m, air.status == BEYOND_THE_BATTERY_STATUS, air
