"""The take-off's ground roll for one case or many: the runway's net force, its quadrature,
the time history, the catapult's release and the arc to the obstacle, on arrays of rows.

Equation of motion on the runway (Raymer, *Aircraft Design*, 17.8.1):
``m dV/dt = T(1, V) - D_g(V) - mu max(W - L_g(V), 0)``, the right-hand side
:func:`tuflexperf.models.aircraft.ground_roll_net_force_n` at the full-throttle thrust. With
the airspeed as the independent variable the roll's distance and time are the integrals
``integral m V / F dV`` and ``integral m / F dV`` from rest to lift-off: composite
Gauss-Legendre sums over the pieces where the force is smooth (a stretched rule near a
force peak), in :class:`GroundRollRows`. ``takeoff`` flies it on one row, ``--samples``,
``sweep`` and ``margins`` on many (:class:`tuflexperf.analysis.batch_model.BatchModel`
extends it); :func:`release_acceleration` is the catapult's release.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tuflexperf.analysis.airborne import ObstaclePath, obstacle_path
from tuflexperf.analysis.batch_kernels import fan_power_rows, stall_speed
from tuflexperf.analysis.constants import BURST_OVER_CONTINUOUS, SECONDS_PER_HOUR
from tuflexperf.analysis.level_flight import LevelFlightRows
from tuflexperf.analysis.pack_limits import (
    PackRows,
    operating_point,
    pack_rows,
    within_limits,
)
from tuflexperf.models.aircraft import (
    Aircraft,
    catapult_energy_shortfall,
    climb_gradient,
    ground_roll_net_force_n,
    level_flight_drag_n,
    liftoff_speed_m_s,
    transition_beyond_cl_max,
    transition_radius_m,
    transition_speed_m_s,
    true_airspeed_m_s,
)
from tuflexperf.models.powertrain import beyond_jet_velocity
from tuflexperf.models.thrust import (
    Propulsion,
    density_ratio,
    engine_thrust_n,
    total_thrust_n,
)

Array = NDArray[np.float64]

HISTORY_POINTS = 101  # equally spaced airspeeds of the roll's time and distance history

CHECK_POINTS = 2001  # the single case's airspeeds where the net force must be positive


def net_force_n(
    aircraft: Aircraft, propulsion: Propulsion, airspeed_m_s: Any, density_kg_m3: float
) -> Any:
    """Accelerating force at full throttle on the runway in N (floats, numpy or CasADi)."""
    thrust = total_thrust_n(propulsion, 1.0, airspeed_m_s, density_kg_m3)
    return ground_roll_net_force_n(aircraft, thrust, airspeed_m_s, density_kg_m3)


RELEASE_NODES = 32  # Gauss-Legendre nodes of a catapult's acceleration after the release

_RELEASE_CHECK = 201  # airspeeds where its excess thrust must stay positive


def release_acceleration(mass_kg: Any, release_m_s: Any, transition_m_s: Any, forces: Any
                         ) -> tuple[Any, Any, Any, Any]:
    """A catapult's level full-throttle acceleration from the release to the transition
    speed per row: distance [m], time [s], charge drawn per engine [Ah] (``None`` where
    ``forces`` gives no current) and whether it accelerates at all (the excess thrust
    positive at :data:`_RELEASE_CHECK` airspeeds); none where the release is already that
    fast.

    ``s = int m V / (T - D) dV`` and ``t = int m / (T - D) dV`` from ``V_rel`` to ``V_tr``
    (``L = W``: the level-flight drag), by :data:`RELEASE_NODES`-point Gauss-Legendre;
    ``forces(V)`` gives ``T - D`` [N] at airspeeds ``(rows, K)`` and the current per engine
    [A] ``(engines, rows, K)`` or None (on full packs: the seconds are few). The
    arc and the climb to the obstacle follow at ``V_tr`` (Anderson's transition, 1.15
    V_stall): a release below it had started the arc at ``V_tr`` for nothing, 11.7 m short
    of the obstacle distance (outside audit).

    References
    ----------
    Raymer, *Aircraft Design*, 17.8.1 (the acceleration integral); Anderson, *Aircraft
    Performance and Design*, 6.7.2 (the transition speed).
    """
    release = np.atleast_1d(np.asarray(release_m_s, dtype=float))
    span = np.maximum(np.atleast_1d(np.asarray(transition_m_s, dtype=float)) - release, 0.0)
    nodes, weights = np.polynomial.legendre.leggauss(RELEASE_NODES)
    speeds = release[:, None] + span[:, None] * 0.5 * (nodes[None, :] + 1.0)
    check = release[:, None] + span[:, None] * np.linspace(0.0, 1.0, _RELEASE_CHECK)[None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        accelerates = (span == 0.0) | np.all(np.asarray(forces(check)[0]) > 0.0, axis=1)
        excess, current = forces(speeds)
        dt_dv = np.atleast_1d(np.asarray(mass_kg, dtype=float)).reshape(-1, 1) / np.asarray(
            excess)
        half = 0.5 * span
        time = half * np.sum(weights * dt_dv, axis=1)
        distance = half * np.sum(weights * speeds * dt_dv, axis=1)
        charge = None if current is None else half * np.sum(
            weights * np.asarray(current) * dt_dv, axis=-1) / SECONDS_PER_HOUR
    return (np.where(span > 0.0, distance, 0.0), np.where(span > 0.0, time, 0.0),
            None if charge is None else np.where(span > 0.0, charge, 0.0), accelerates)


_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(16)


def _unit_rule(panels: int) -> tuple[Array, Array]:
    """Composite Gauss-Legendre nodes and weights on [0, 1], ``(1, panels x 16)`` each."""
    nodes = ((np.arange(panels)[:, None] + 0.5 * (_GL_NODES + 1.0)) / panels).reshape(1, -1)
    return nodes, np.tile(_GL_WEIGHTS, panels)[None, :] * 0.5 / panels

_ROLL_PROBES = np.array([0.25, 0.5, 0.75, 0.9])  # three fix a piece's quadratic, one checks it

_STEEP_FORCE_SHARE = 0.05  # a least net force below this share of the greatest: a peak

_PEAK_PANELS = 16  # Gauss panels on each monotone half of a piece, in the stretched variable

_HISTORY_GL = np.polynomial.legendre.leggauss(3)  # per part of a history interval

_FINE_GL = _GL_NODES, _GL_WEIGHTS  # per part where the force comes near vanishing

_BLOCK_ROWS = 1024  # rows of the history's nodes at a time

_NEAR_FORCE_SHARE = 0.25  # a least net force below this share of the greatest: _FINE_GL

# those nodes on a roll of one piece, in its own coordinate s = V / V_LO - 1/2
_HISTORY_S = ((np.arange(HISTORY_POINTS - 1)[:, None] + 0.5 * (_HISTORY_GL[0] + 1.0))
              / (HISTORY_POINTS - 1)).reshape(1, -1) - 0.5


_PEAK_RULE = _unit_rule(_PEAK_PANELS)



def roll_integrals_near_a_peak(low: Array, width: Array, c0: Array, c1: Array, c2: Array,
                               mass: Array, rule: tuple[Array, Array] = _PEAK_RULE
                               ) -> tuple[Array, Array]:
    """``integral m V / F dV`` [m] and ``integral m / F dV`` [s] per row over one piece of
    airspeed ``V = low + width (s + 1/2)``, ``s`` in [-1/2, 1/2], whose net force is the
    positive quadratic ``F = c0 + c1 s + c2 s^2`` [N] however nearly it vanishes.

    Where ``F`` all but vanishes ``1/F`` is a spike as narrow as ``F_min / |F'|`` (or
    ``sqrt(F_min / c2)`` at a vertex): fixed nodes miss it (4,096 of them gave a roll 40 %
    short; outside audit). Each half of the piece on which ``F`` is monotone (split at the
    vertex) is stretched about its least force ``F*`` at ``s*``, ``s = s* +- w sinh(t)``
    with ``w`` the spike's width, so the integrand in ``t`` is smooth and bounded (``w /
    (F* cosh t)`` for the vertex's Lorentzian) and a composite Gauss rule on ``t`` is exact
    to ~1e-12 for any ``F* > 0``; where nothing vanishes ``w`` is the half's length and
    the stretch is mild.

    References
    ----------
    Davis & Rabinowitz, *Methods of Numerical Integration*, 2nd ed., 3.9 (a change of
    variable that removes a near-singularity).
    """
    u, weights = rule
    distance = np.zeros(np.shape(c0)[0])
    time = np.zeros(np.shape(c0)[0])
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        vertex = -c1 / (2.0 * c2)
    split = np.where(np.isfinite(vertex) & (np.abs(vertex) < 0.5), vertex, 0.0)
    for a, b in ((np.full_like(split, -0.5), split), (split, np.full_like(split, 0.5))):
        f_a, f_b = c0 + a * (c1 + a * c2), c0 + b * (c1 + b * c2)
        at_a = f_a <= f_b
        s_least = np.where(at_a, a, b)
        f_least = np.minimum(f_a, f_b)
        slope = c1 + 2.0 * c2 * s_least
        length = b - a
        with np.errstate(divide="ignore", invalid="ignore"):
            width_of_spike = f_least / np.maximum(
                np.abs(slope), np.sqrt(np.abs(f_least * c2)))
        stretch = np.maximum(np.minimum(np.nan_to_num(width_of_spike, nan=np.inf), length),
                             1e-300)
        span = np.arcsinh(length / stretch)
        t = span * u
        offset = np.where(at_a, 1.0, -1.0) * stretch * np.sinh(t)  # s - s*
        # about s*, where the force is least: its cancellation is not repeated node by node
        force = f_least + offset * (slope + offset * c2)
        ds = stretch * np.cosh(t) * span * weights
        speed = low + width * (s_least + offset + 0.5)
        with np.errstate(divide="ignore", invalid="ignore"):
            over = ds * width * mass / force
            distance = distance + np.sum(over * speed, axis=1)
            time = time + np.sum(over, axis=1)
    return distance, time




def _running_sum(parts: Array) -> Array:
    """``numpy.cumsum(parts, axis=1)`` in place, column by column (the same sums; along a
    short second axis of many rows three times faster)."""
    for column in range(1, parts.shape[1]):
        parts[:, column] += parts[:, column - 1]
    return parts


@dataclass(frozen=True)
class LaunchOnPacks:
    """Full throttle on the packs over a take-off (:meth:`GroundRollRows.launch_on_packs`), per
    engine flown ``j`` (one for a shared power model): its power [W] at the reference voltage
    ``(B, K)``; on full packs (``2 j``) and after the take-off's charge (``2 j + 1``) the
    loaded voltage [V], current per pack [A] and where they are within the limits; that
    charge [Ah] ``(B,)``; the burst rating per pack [A] ``(B,)`` (None: no rating)."""

    power_w: list[Array]
    points: list[tuple[Array, Array]]
    within: list[NDArray[np.bool_]]
    charge_ah: list[Array]
    burst_a: Array | None


@dataclass
class GroundRollRows(LevelFlightRows):
    """The ground roll, release and arc of ``size`` rows (fields as :class:`LevelFlightRows`;
    one row for ``takeoff``, the batch's for :class:`BatchModel`, which fills the take-off's
    results on sagging packs in)."""

    _uniform: Array | None = None
    _histories: tuple[Array, Array] | None = None  # memo of roll_histories
    _pieces: Any = None  # memo of _roll_pieces (False: evaluate node by node)
    _force_range: tuple[Array, Array] | None = None  # memo of force_range
    # the take-off on sagging packs (batch_takeoff_packs.RollOnPacks), where one is flown
    packs_roll: Any = None
    # a catapult's level acceleration from release to the transition speed (distance [m],
    # time [s], charge per fan [Ah] or None, accelerates): release_acceleration
    release: Any = None
    # the arc and climb to the obstacle on sagging packs [m] (batch_takeoff_packs)
    packs_airborne: Array | None = None
    # where those packs reach their cut-off in the climb, before the obstacle
    packs_beyond: NDArray[np.bool_] | None = None

    def net_force(self, speed: Array) -> Array:
        """Full-throttle net force on the runway [N] at ``speed`` [m/s] ``(B, K)``."""
        thrust = self.thrust(1.0, speed)
        return np.asarray(
            ground_roll_net_force_n(self.aircraft, thrust, speed, self.density), dtype=float
        ) * np.ones((self.size, 1))

    def liftoff_speed(self) -> Array:
        """The lift-off true airspeed [m/s] per row ``(B, 1)``."""
        return np.asarray(liftoff_speed_m_s(self.aircraft, self.density), dtype=float) \
            * np.ones((self.size, 1))

    def transition_speed(self) -> Array:
        """The take-off arc's true airspeed [m/s] per row ``(B,)``: 1.15 V_stall."""
        return np.asarray(transition_speed_m_s(self.aircraft, self.density),
                          dtype=float).reshape(-1) * np.ones(self.size)

    def engine_thrust(self, index: int, throttle: Any, speed: Array) -> Array:
        """One live engine's thrust [N], as :meth:`thrust` counts it in the total (its model
        at the row's density, its extrapolation error beyond the tested range)."""
        own = engine_thrust_n(self.propulsion.engines[index], throttle, speed,
                              density_ratio(self.propulsion, self.density))
        errors = self.extrapolation_errors_n(speed)
        return self._per_row(own if errors is None else own + errors[index])

    def _breaks(self, v_lo: Array) -> list[Array]:
        """Where the integrand kinks in [0, V_LO]: friction clamp (L = W), tested range end."""
        to = self.aircraft.takeoff
        with np.errstate(divide="ignore", invalid="ignore"):
            clamp = np.sqrt(2.0 * self.aircraft.weight_n / (np.asarray(
                self.density, dtype=float) * self.aircraft.wing_area_m2 * to.cl_ground))
        clamp = np.where(np.isfinite(clamp), clamp, np.inf) * np.ones_like(v_lo)
        edge = np.full_like(v_lo, self.propulsion.tested_airspeed_m_s[1])
        first = np.minimum(np.minimum(clamp, edge), v_lo)
        second = np.minimum(np.maximum(clamp, edge), v_lo)
        # a sampled mean model-form error is linear between its grid's airspeeds: each a kink
        nodes = sorted({float(g) for e in self.propulsion.engines if e.thrust_offset is not None
                        for g in getattr(e.thrust_offset, "airspeed", ())
                        if 0.0 < g < float(np.max(v_lo))})
        if not nodes:
            return [np.zeros_like(v_lo), first, second, v_lo]
        inner = np.sort(np.stack([first, second, *(np.minimum(np.full_like(v_lo, g), v_lo)
                                                   for g in nodes)]), axis=0)
        return [np.zeros_like(v_lo), *inner, v_lo]

    def _roll_pieces(self) -> tuple[list[Array], list[tuple[Array, ...]]] | None:
        """The net force on each smooth piece of [0, V_LO] as a quadratic (memoised).

        Between the kinks of :meth:`_breaks` the full-throttle net force is quadratic in
        airspeed (poly22 thrust at a fixed throttle, drag, lift and wheel load all ~V^2, the
        extrapolation error constant), so three values of :meth:`net_force` per piece give
        it exactly, as ``c0 + c1 s + c2 s^2`` with ``s = u - 1/2`` and ``u`` the piece's own
        coordinate in [0, 1] (Lagrange through u = 1/4, 1/2, 3/4). A fourth value checks it;
        where it does not hold (a model that is not quadratic, a jump inside a piece) the
        force is evaluated node by node instead (None).
        """
        if self._pieces is not None:
            return self._pieces or None
        low_edge = self.propulsion.tested_airspeed_m_s[0]
        if self.extrapolation_n is not None and low_edge > 0.0:
            self._pieces = False  # a jump at the low edge lies inside the first piece
            return None
        breaks = self._breaks(self.liftoff_speed())
        fits = []
        ok = True
        for low, high in zip(breaks[:-1], breaks[1:], strict=True):
            width = high - low
            f = self.net_force(low + width * _ROLL_PROBES[None, :])
            c0 = f[:, 1:2]
            c1 = 2.0 * (f[:, 2:3] - f[:, 0:1])
            c2 = 8.0 * (f[:, 0:1] - 2.0 * f[:, 1:2] + f[:, 2:3])
            s = _ROLL_PROBES[3] - 0.5
            predicted = c0 + s * (c1 + s * c2)
            scale = np.max(np.abs(f), axis=1, keepdims=True) + 1.0
            with np.errstate(invalid="ignore"):
                ok = ok and bool(np.all((np.abs(predicted - f[:, 3:4]) <= 1e-9 * scale)
                                        | ~np.isfinite(f[:, 3:4])))
            fits.append((low, width, c0, c1, c2))
        self._pieces = (breaks, fits) if ok else False
        return self._pieces or None

    def force_range(self) -> tuple[Array, Array]:
        """Least and greatest full-throttle net force [N] per row from rest to lift-off.

        On the quadratic pieces of :meth:`_roll_pieces` both are exact (each piece's ends and
        vertex), so a dip between any check points counts; node by node, the single case's
        2001 equally spaced airspeeds (``analysis.takeoff``). Memoised: the roll, its
        history and the launch ask for it.
        """
        if self._force_range is None:
            self._force_range = self._least_and_greatest_force()
        return self._force_range

    def _least_and_greatest_force(self) -> tuple[Array, Array]:
        pieces = self._roll_pieces()
        if pieces is None:
            speeds = self.liftoff_speed() * np.linspace(0.0, 1.0, CHECK_POINTS)[None, :]
            force = self.net_force(speeds)
            return np.min(force, axis=1), np.max(force, axis=1)
        least = np.full(self.size, np.inf)
        most = np.full(self.size, -np.inf)
        for _, width, c0, c1, c2 in pieces[1]:
            # s in [-1/2, 1/2]: the ends, and the vertex where it lies inside
            ends = (c0 - 0.5 * c1 + 0.25 * c2, c0 + 0.5 * c1 + 0.25 * c2)
            with np.errstate(divide="ignore", invalid="ignore"):
                vertex = -c1 / (2.0 * c2)
                inside = (np.abs(vertex) <= 0.5) & (c2 != 0.0)
                top = c0 - c1 * c1 / (4.0 * c2)
            used = (np.asarray(width) > 0.0).reshape(-1)
            low = np.minimum(np.minimum(*ends), np.where(inside, top, np.inf)).reshape(-1)
            high = np.maximum(np.maximum(*ends), np.where(inside, top, -np.inf)).reshape(-1)
            least = np.where(used, np.minimum(least, low), least)
            most = np.where(used, np.maximum(most, high), most)
        return least, most

    def uniform_force(self) -> Array:
        """Net force [N] at 101 equally spaced airspeeds from rest to V_LO (memoised)."""
        if self._uniform is None:
            v_lo = self.liftoff_speed()
            speeds = v_lo * np.linspace(0.0, 1.0, HISTORY_POINTS)[None, :]
            pieces = self._roll_pieces()
            if pieces is None:
                self._uniform = self.net_force(speeds)
                return self._uniform
            breaks, fits = pieces
            # a roll that is one smooth piece (no kink before lift-off): the airspeeds' own
            # coordinate on it is k/100
            u = np.linspace(0.0, 1.0, HISTORY_POINTS)[None, :] - 0.5
            _, _, c0, c1, c2 = fits[0]
            force = c0 + u * (c1 + u * c2)
            kinked = np.flatnonzero(breaks[1][:, 0] < v_lo[:, 0])
            if kinked.size:
                # each airspeed on its piece; an airspeed within 1e-9 above the tested
                # range's end still counts as tested, as the thrust model decides (thrust)
                edge = self.propulsion.tested_airspeed_m_s[1]
                at = speeds[kinked]
                index = sum((at > np.where(b[kinked] == edge, b[kinked] + 1e-9, b[kinked]))
                            .astype(np.intp) for b in breaks[1:-1])
                low, width, c0, c1, c2 = (np.take_along_axis(
                    np.concatenate([f[i][kinked] for f in fits], axis=1), index, axis=1)
                    for i in range(5))
                with np.errstate(divide="ignore", invalid="ignore"):
                    s = (at - low) / width - 0.5
                force[kinked] = c0 + s * (c1 + s * c2)
            self._uniform = force
        return self._uniform

    def ground_roll(self) -> tuple[Array, Array, Array, Array]:
        """Ground roll [m], time [s], lift-off speed [m/s], and attainable (1/0) per row: the
        last of :meth:`roll_histories`, plus the rotation.

        Not attainable where the net force is not positive from rest to the lift-off speed
        (:meth:`force_range`; a vanishing force means no lift-off).
        """
        v_lo = self.liftoff_speed()
        # a sampled lift-off speed below stall cannot lift off (bad input for one case)
        stall = stall_speed(self)[:, None]
        least, most = self.force_range()
        attainable = (least > 0.0) & (v_lo >= stall * (1.0 - 1e-12))[:, 0]
        # beyond the fans' jet velocity an extrapolated thrust model is not physics (as
        # solve_takeoff says); v_lo is a column, as the jet velocity of sampled rows is
        attainable &= ~beyond_jet_velocity(self.propulsion, v_lo, self.density)[:, 0]
        time, distance = (h[:, -1] for h in self.roll_histories())
        # a sum over 1/F is no roll unless it is positive (a force negative between check
        # points summed to -796 m and passed; outside audit)
        ok = attainable & (distance > 0.0) & (time > 0.0) & np.isfinite(distance) \
            & np.isfinite(time)
        # rotation on the ground at the lift-off speed (Raymer 17.8.2: S_R = V_LO t_R)
        rotation = np.asarray(self.aircraft.takeoff.rotation_time_s, dtype=float).reshape(-1) \
            * np.ones(self.size)
        distance = distance + v_lo[:, 0] * rotation
        time = time + rotation
        return (np.where(ok, distance, np.nan), np.where(ok, time, np.nan), v_lo[:, 0],
                ok.astype(float))

    def release_run(self, thrust_and_current: Any = None
                    ) -> tuple[Array, Array, Array | None, Array]:
        """A catapult's acceleration after the release per row
        (:func:`tuflexperf.analysis.ground_roll.release_acceleration`): at the model's thrust, or
        at ``thrust_and_current(V)`` (thrust [N], current per fan [A]; on sagging packs)."""
        release = np.asarray(true_airspeed_m_s(self.aircraft.launch_speed_m_s, self.density),
                             dtype=float).reshape(-1) * np.ones(self.size)
        v_tr = self.transition_speed()

        def forces(speed: Array) -> tuple[Array, Array | None]:
            drag = np.asarray(level_flight_drag_n(self.aircraft, speed, self.density),
                              dtype=float)
            if thrust_and_current is None:
                return self.thrust(1.0, speed) - drag, None
            thrust, current = thrust_and_current(speed)
            return thrust - drag, current

        return release_acceleration(self.aircraft.mass_kg, release, v_tr, forces)

    def catapult_release(self) -> tuple[Array, Array, Array, Array]:
        """A catapult launch as :meth:`ground_roll` reports a roll: no distance, no time, the
        release true airspeed [m/s] (``launch_speed_m_s`` is an EAS) and attainable (1/0).

        The catapult's energy is the ground equipment's, not the battery's (SPEC 4): the
        flight starts airborne at the release speed, which must not be below stall (bad input
        for one case; not attainable for a sampled mass or ``cl_max`` that raises the stall),
        and which the catapult's ``launch_energy_j`` must give the mass (m V^2 / 2).
        """
        release = np.asarray(true_airspeed_m_s(self.aircraft.launch_speed_m_s, self.density),
                             dtype=float).reshape(-1) * np.ones(self.size)
        mass = np.asarray(self.aircraft.mass_kg, dtype=float).reshape(-1) * np.ones(self.size)
        energy = self.aircraft.launch_energy_j
        short = catapult_energy_shortfall(
            mass, release, None if energy is None else np.asarray(energy, dtype=float).reshape(-1))
        ok = (release >= stall_speed(self) * (1.0 - 1e-12)) & ~short
        # no thrust to climb away beyond the fans' jet velocity (solve_takeoff)
        density = np.asarray(self.density, dtype=float).reshape(-1, 1)
        ok &= ~np.asarray(beyond_jet_velocity(self.propulsion, release[:, None], density),
                          dtype=bool).reshape(-1)
        zero = np.zeros(self.size)
        return zero, zero, release, ok.astype(float)

    def launch_within_packs(self, roll: tuple[Array, Array, Array, Array], height: Any,
                            catapult: bool, packs: Any, battery: dict[str, Array]
                            ) -> NDArray[np.bool_]:
        """Per row: the packs give full throttle over the take-off (:meth:`launch_on_packs`)
        over the roll's 101 history airspeeds (a catapult: its release) and the transition
        speed, for the roll's, rotation's, and the arc and climb's seconds to the obstacle
        at the transition speed; and, on sagging packs, the climb reaching the obstacle
        before their cut-off (:attr:`packs_beyond`)."""
        v_tr = self.transition_speed()[:, None]
        airborne = self.airborne_m(height)
        airborne = np.where(np.isfinite(airborne), airborne, 0.0)
        seconds = np.nan_to_num(roll[1]) + airborne / v_tr[:, 0]
        if catapult:  # and its level acceleration after the release, as the single case
            seconds = seconds + np.nan_to_num(self.release[1])
        v_lo = np.nan_to_num(roll[2]).reshape(-1, 1)
        along = (v_lo if catapult else
                 v_lo * np.linspace(0.0, 1.0, HISTORY_POINTS)[None, :])
        speeds = np.concatenate([along * np.ones((self.size, 1)), v_tr], axis=1)
        launch = self.launch_on_packs(packs, pack_rows(packs.battery, battery), speeds,
                                      seconds)
        ok = np.all([np.all(within, axis=1) for within in launch.within], axis=0)
        if self.packs_beyond is not None:  # the packs give out in the climb (solve_takeoff)
            ok &= ~self.packs_beyond
        return ok

    def launch_on_packs(self, packs: Any, rows: PackRows, speeds: Array, seconds: Array,
                        each_point: bool = False) -> LaunchOnPacks:
        """Full throttle on the packs ``packs`` (a :class:`~.pack_limits.PackSide`) of
        ``rows`` at the airspeeds ``speeds`` [m/s] ``(B, K)`` of a take-off lasting
        ``seconds`` [s] ``(B,)``: on full packs, and after the charge the most current for
        the whole take-off would draw (an upper bound: the packs sag as they give it), each
        engine's loaded voltage at or above the cut-off and each pack within its burst
        rating (:class:`LaunchOnPacks`; ``takeoff`` asks one row, every point solved
        (``each_point``), the batch many)."""
        prop = self.propulsion
        circuit, cutoff = rows.circuit_packs[:, None], rows.cutoff_v[:, None]
        burst = (None if rows.rating_a is None
                 else BURST_OVER_CONTINUOUS * rows.rating_a[:, None])
        seconds = np.asarray(seconds, dtype=float).reshape(-1)
        fans = prop.engines if packs.own_surfaces else (None,)
        powers, points, within, charges = [], [], [], []
        for engine in fans:
            power = np.maximum(fan_power_rows(packs, self, 1.0, speeds, engine), 0.0)
            power = power * np.ones_like(speeds)
            if not each_point and prop.reference_voltage_v is None \
                    and packs.params.resistance_ohm > 0.0 and np.all(circuit > 0.0):
                # at a fixed power the loaded voltage falls and the current rises with the
                # power (each rounded step monotone too): a row's most power decides both
                power = np.max(power, axis=1, keepdims=True)
            powers.append(power)
            charge = np.zeros((self.size, 1))
            for after in (False, True):  # on full packs, then after the take-off's charge
                u, current, _ = operating_point(
                    packs.params, charge, power, circuit, rows.packs_per_engine,
                    prop.reference_voltage_v, prop.voltage_exponent)
                points.append((u, current))
                within.append(within_limits(u, current, cutoff, burst))
                if not after:
                    charge = (np.max(current, axis=1) * rows.packs_per_engine * seconds
                              / SECONDS_PER_HOUR)[:, None]
                    charges.append(charge[:, 0])
        return LaunchOnPacks(powers, points, within, charges,
                             None if burst is None else burst[:, 0])

    def airborne_m(self, height: Any) -> Array:
        """Transition arc + climb to the obstacle [m] per row (``inf`` where never cleared):
        on the sagging packs where they were flown (:attr:`packs_airborne`), else at the
        model's thrust (:meth:`obstacle_path`)."""
        if self.packs_airborne is not None:
            return self.packs_airborne
        return self.obstacle_path(height).distance_m

    def obstacle_path(self, height: Any) -> ObstaclePath:
        """The arc at 1.15 V_stall and the full-throttle climb to the obstacle ``height``
        [m] per row at the model's thrust (Anderson 6.7.2; ``takeoff`` flies one row)."""
        v_tr = self.transition_speed()[:, None]
        radius = transition_radius_m(v_tr, self.aircraft.takeoff.transition_load_factor)
        gradient = climb_gradient(self.aircraft, self.thrust(1.0, v_tr), v_tr, self.density)
        # a height per row, (B,) or (B, 1), is a column against the rows' (B, 1)
        column = np.reshape(height, (-1, 1)) if np.ndim(height) else height
        return obstacle_path(v_tr, radius, column, gradient)

    def distance_to_obstacle(self, roll: tuple[Array, Array, Array, Array],
                             height: Any) -> Array:
        """Ground roll + transition arc + climb to the obstacle [m] (as :func:`solve_takeoff`),
        a catapult's level acceleration after the release included."""
        airborne = self.airborne_m(height)
        if self.release is not None:
            airborne = airborne + self.release[0]
        total = roll[0] + airborne
        # a launch that is not attainable (a catapult's "roll" of 0 m included) reaches nothing;
        # nor does an arc that needs more than cl_max (solve_takeoff)
        flown = ~np.asarray(transition_beyond_cl_max(np.asarray(
            self.aircraft.takeoff.transition_load_factor, dtype=float)), dtype=bool).reshape(-1)
        return np.where(np.isfinite(total) & (roll[3] > 0.5) & flown, total, np.nan)


    def roll_histories(self) -> tuple[Array, Array]:
        """Time [s] and distance [m] of the acceleration at the :data:`HISTORY_POINTS`
        equally spaced airspeeds from rest to V_LO per row ``(B, 101)`` (memoised): the
        roll's one quadrature, its last node the roll's (:meth:`ground_roll`).

        Each interval between two history airspeeds is cut at the force's kinks (the
        friction clamp, the tested range's end; its start too where a sampled error jumps
        there); on each part the net force is one quadratic (:meth:`_roll_pieces`) and
        ``integral m / F dV``, ``integral m V / F dV`` take 3 Gauss-Legendre nodes, or
        :func:`roll_integrals_near_a_peak` where the part's least force is below
        ``_STEEP_FORCE_SHARE`` of the roll's greatest; 16 nodes on the force node by node
        where it is not quadratic. Against ``solve_ivp`` at rtol 1e-12 these sums are within
        5e-13, CVODES at rtol 1e-11 was 2.4e-10 (2e-9 in the distance history) and a
        four-point rule on the history's airspeeds alone 3e-6 in time.
        """
        if self._histories is None:
            self._histories = self._roll_histories()
        return self._histories

    def _roll_histories(self) -> tuple[Array, Array]:
        v_lo = self.liftoff_speed()
        pieces = self._roll_pieces()
        breaks = self._breaks(v_lo) if pieces is None else pieces[0]
        kinks = [np.minimum(b, v_lo) for b in breaks[1:-1]]
        if pieces is None:  # a jump at the tested range's start lies inside the first piece
            kinks.append(np.minimum(self.propulsion.tested_airspeed_m_s[0], v_lo)
                         * np.ones_like(v_lo))
        mass = np.asarray(self.aircraft.mass_kg, dtype=float).reshape(-1, 1) \
            * np.ones((self.size, 1))
        least, most = self.force_range()
        with np.errstate(invalid="ignore"):
            steep = (least > 0.0) & (least < _STEEP_FORCE_SHARE * most)
        # rows on one smooth piece from rest to lift-off, none steep: one shared grid
        smooth = np.zeros(self.size, dtype=bool) if pieces is None else ~steep & np.all(
            [k[:, 0] >= v_lo[:, 0] for k in kinks], axis=0)
        u, w = _HISTORY_GL
        parts = HISTORY_POINTS - 1
        time = np.zeros((self.size, HISTORY_POINTS))
        length = np.zeros((self.size, HISTORY_POINTS))
        smooth_rows = np.flatnonzero(smooth)
        # blocks of rows whose nodes stay in the cache (one 10,000-row array: 24 MB)
        for start in range(0, smooth_rows.size, _BLOCK_ROWS):
            rows = smooth_rows[start:start + _BLOCK_ROWS]
            rows = slice(rows[0], rows[-1] + 1) if rows[-1] - rows[0] + 1 == rows.size \
                else rows  # consecutive rows: views, not copies
            _, width, c0, c1, c2 = (x[rows] for x in pieces[1][0])  # type: ignore[index]
            over = _HISTORY_S * c2  # the force at the nodes in place, then 1/F
            over += c1
            over *= _HISTORY_S
            over += c0
            with np.errstate(divide="ignore", invalid="ignore"):
                np.divide(1.0, over, out=over)
            scale = width * mass[rows] * (0.5 / parts)
            # per interval p: T_p = sum_k w_k / F_pk; its distance's V / V_LO = (p + x_k) / 100
            # with x_k the node in the interval (einsum, not BLAS: its threads contend on a
            # loaded machine, twice the time)
            over = over.reshape(c0.shape[0], parts, -1)
            each = np.einsum("rpk,k->rp", over, w)
            along = np.einsum("rpk,k->rp", over, 0.5 * w * (u + 1.0))
            along += each * np.arange(parts)
            time[rows, 1:] = _running_sum(each) * scale
            length[rows, 1:] = _running_sum(along) * (scale * width / parts)
        # 4 nodes a part were 2.4e-10 off scipy's quad where the least force was 5.4 % of the
        # greatest: 16 below a quarter of it (3 above it: within 1e-11)
        with np.errstate(invalid="ignore"):
            near = least < _NEAR_FORCE_SHARE * most
        for chosen, rule in ((~smooth & ~near, _HISTORY_GL), (~smooth & near, _FINE_GL)):
            rows = np.flatnonzero(chosen)
            if pieces is None and chosen.any():  # node by node: every row at once
                rows, rule = np.arange(self.size), _FINE_GL
            if rows.size:
                time[rows], length[rows] = self._cut_histories(
                    rows, v_lo, kinks, pieces, mass, most, steep, rule)
            if pieces is None:
                break
        return time, length

    def _cut_histories(self, rows: Array, v_lo: Array, kinks: list[Array], pieces: Any,
                       mass: Array, most: Array, steep: Array, rule: tuple[Array, Array]
                       ) -> tuple[Array, Array]:
        """:meth:`roll_histories` of ``rows`` (indices; all where ``pieces`` is None), the
        intervals cut at the ``kinks`` [m/s], each part by the Gauss-Legendre ``rule`` on
        [-1, 1] (node by node: 16 nodes), the ``steep`` rows' peaked parts by
        :meth:`_parts_near_a_peak` (node by node: 8 panels a part)."""
        v_lo = v_lo[rows]
        kinks = [k[rows] for k in kinks]
        nodes = v_lo * np.linspace(0.0, 1.0, HISTORY_POINTS)[None, :]
        cuts = np.sort(np.concatenate([nodes, *kinks], axis=1), axis=1)
        a, b = cuts[:, :-1, None], cuts[:, 1:, None]  # (rows, parts, 1)
        mass = mass[rows][:, :, None]
        if pieces is None:  # the force may be any smooth function: 16 nodes a part
            time, distance = self._sums_by_node(a, b, mass)
            if steep.any():  # 1/F peaks where the force all but vanishes: 8 panels a part
                fine = [self._sums_by_node(a + (b - a) * k / 8, a + (b - a) * (k + 1) / 8,
                                           mass) for k in range(8)]
                time = np.where(steep[:, None], sum(f[0] for f in fine), time)
                distance = np.where(steep[:, None], sum(f[1] for f in fine), distance)
        else:
            u, w = rule
            speed = a + (b - a) * 0.5 * (u + 1.0)
            # each part on one piece: its middle against the kinks
            which = sum((0.5 * (a + b) > k[rows][:, :, None])
                        for k in pieces[0][1:-1]).astype(np.intp)
            part = [np.take_along_axis(np.concatenate(
                [f[i][rows] for f in pieces[1]], axis=1)[:, None, :], which, axis=2)
                for i in range(5)]
            low, width, c0, c1, c2 = part
            with np.errstate(divide="ignore", invalid="ignore"):
                s = (speed - low) / width - 0.5
                over = np.where(b > a, 0.5 * (b - a) * w * mass / (c0 + s * (c1 + s * c2)),
                                0.0)
            time, distance = np.sum(over, axis=2), np.sum(over * speed, axis=2)
            peaked = steep[rows]
            if peaked.any():
                time[peaked], distance[peaked] = self._parts_near_a_peak(
                    a[peaked, :, 0], b[peaked, :, 0], [x[peaked, :, 0] for x in part],
                    mass[peaked, :, 0], most[rows][peaked], time[peaked], distance[peaked])
        # each history airspeed's place among the cuts: its own index and the kinks below it
        at = np.arange(HISTORY_POINTS)[None, :] + sum((k < nodes) for k in kinks)
        zero = np.zeros((rows.size, 1))
        return (np.take_along_axis(np.concatenate([zero, np.cumsum(time, axis=1)], axis=1),
                                   at, axis=1),
                np.take_along_axis(np.concatenate([zero, np.cumsum(distance, axis=1)], axis=1),
                                   at, axis=1))

    def _sums_by_node(self, a: Array, b: Array, mass: Array) -> tuple[Array, Array]:
        """``integral m / F dV`` [s] and ``integral m V / F dV`` [m] over each part [a, b]
        ``(B, parts, 1)`` of every row, 16 Gauss-Legendre nodes on the force node by node."""
        speed = a + (b - a) * 0.5 * (_GL_NODES + 1.0)
        force = self.net_force(speed.reshape(self.size, -1)).reshape(speed.shape)
        with np.errstate(divide="ignore", invalid="ignore"):
            over = np.where(b > a, 0.5 * (b - a) * _GL_WEIGHTS * mass / force, 0.0)
        return np.sum(over, axis=2), np.sum(over * speed, axis=2)

    @staticmethod
    def _parts_near_a_peak(a: Array, b: Array, piece: list[Array], mass: Array, most: Array,
                           time: Array, distance: Array) -> tuple[Array, Array]:
        """:meth:`roll_histories`' parts [a, b] [m/s] ``(rows, parts)`` whose least force is
        below ``_STEEP_FORCE_SHARE`` of ``most`` [N] by :func:`roll_integrals_near_a_peak`
        (each part's own quadratic from its piece's), the others' ``time`` and ``distance``
        kept."""
        low, width, c0, c1, c2 = piece

        def force(speed: Array) -> Array:
            with np.errstate(divide="ignore", invalid="ignore"):
                s = (speed - low) / width - 0.5
            return c0 + s * (c1 + s * c2)

        f_a, f_m, f_b = force(a), force(0.5 * (a + b)), force(b)
        local = (a, b - a, f_m, f_b - f_a, 2.0 * (f_a - 2.0 * f_m + f_b))
        with np.errstate(divide="ignore", invalid="ignore"):
            vertex = -local[3] / (2.0 * local[4])
            top = np.where(np.abs(vertex) < 0.5, f_m - local[3] ** 2 / (4.0 * local[4]), np.inf)
        peaked = (np.minimum(np.minimum(f_a, f_b), top) < _STEEP_FORCE_SHARE * most[:, None]) \
            & (b > a)
        time, distance = time.copy(), distance.copy()
        if peaked.any():
            d, t = roll_integrals_near_a_peak(
                *(x[peaked][:, None] for x in local),
                np.broadcast_to(mass, a.shape)[peaked][:, None])
            time[peaked], distance[peaked] = t, d
        return time, distance

    def roll_history(self, wanted: NDArray[np.bool_] | None = None) -> Array:
        """Time [s] at the 101 history airspeeds per row (:meth:`roll_histories`: every
        row is summed, whatever rows are ``wanted``)."""
        return self.roll_histories()[0]
