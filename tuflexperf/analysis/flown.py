"""The flown side of a flight log: airborne window, energy, power against airspeed.

Every stream stays on its own clock; a quantity is brought to another's samples by linear
interpolation that never bridges a gap longer than :data:`MAX_GAP_S` (a logging dropout is
not flown at the mean of its ends). Pure numpy, vectorised; no case is needed.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from tuflexperf.errors import InputError
from tuflexperf.io.flightlog import NO_CURRENT_SENSOR, FlightLog, Stream

G = 9.80665  # [m/s^2]
MAX_GAP_S = 1.0  # a longer gap between two samples is not integrated nor interpolated across
MIN_BIN_S = 10.0  # a power bin needs this much airborne time
LEVEL_CLIMB_M_S = 0.5  # |climb rate| below this is level flight
GROUND_WINDOW_S = 30.0  # the ground altitude is the median baro altitude over this before take-off
DEFAULT_AIRBORNE_AIRSPEED_M_S = 8.0  # without a case (with one: 1.1 x its stall speed)
DEFAULT_AIRBORNE_HEIGHT_M = 3.0
DEFAULT_CLIMB_EFFICIENCY = 0.5  # electrical -> climb power; stated wherever it is used


@dataclass(frozen=True)
class AirborneWindow:
    """Where the flight is: ``start_s`` to ``end_s`` [s] on the log's clock, and the rule."""

    start_s: float
    end_s: float
    rule: str

    @property
    def duration_s(self) -> float:
        """Airborne time [s]."""
        return self.end_s - self.start_s


@dataclass(frozen=True)
class SpeedBin:
    """One 1 m/s airspeed bin ``[v - 0.5, v + 0.5)``, labelled ``v`` [m/s].

    ``power_w`` is the time-weighted mean electrical power [W] and ``power_std_w`` its
    time-weighted standard deviation [W]; ``throttle`` the mean commanded throttle [-] (NaN
    without a throttle stream); ``time_s`` [s] the airborne time in the bin.
    """

    airspeed_m_s: float
    time_s: float
    samples: int
    power_w: float
    power_std_w: float
    throttle: float
    throttle_std: float
    current_a: float = float("nan")  # mean total battery current [A]

    def to_dict(self, name: str = "flown_power_w") -> dict[str, Any]:
        return {"airspeed_m_s": self.airspeed_m_s, name: self.power_w,
                "power_std_w": self.power_std_w, "time_s": self.time_s,
                "samples": self.samples, "throttle": self.throttle,
                "throttle_std": self.throttle_std, "current_a": self.current_a}


@dataclass(frozen=True)
class FlownResult:
    """Everything the flown side reads off a log (units in the names)."""

    window: AirborneWindow
    energy_wh: float | None
    charge_mah: float | None  # the log's own discharged-mAh counter over the window
    integrated_charge_mah: float | None  # the integral of the current over the window
    mean_power_w: float | None
    bins: tuple[SpeedBin, ...]
    level_bins: tuple[SpeedBin, ...]
    climb_corrected_bins: tuple[SpeedBin, ...]
    climb_efficiency: float
    mass_kg: float | None
    airspeed_kind: str
    series: dict[str, np.ndarray] = field(default_factory=dict)
    notes: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        return {
            "airborne_rule": self.window.rule,
            "airborne_start_s": self.window.start_s, "airborne_end_s": self.window.end_s,
            "airborne_s": self.window.duration_s, "energy_wh": self.energy_wh,
            "charge_mah": self.charge_mah, "integrated_charge_mah": self.integrated_charge_mah,
            "mean_power_w": self.mean_power_w, "airspeed_kind": self.airspeed_kind,
            "min_bin_time_s": MIN_BIN_S,
            "bins": [b.to_dict() for b in self.bins],
            "level_climb_rate_m_s": LEVEL_CLIMB_M_S,
            "level_bins": [b.to_dict() for b in self.level_bins],
            "climb_efficiency": self.climb_efficiency, "mass_kg": self.mass_kg,
            "climb_corrected_bins": [b.to_dict("corrected_power_w")
                                     for b in self.climb_corrected_bins],
            "notes": list(self.notes),
        }


# ---- streams -------------------------------------------------------------------------------


def ordered(stream: Stream, notes: list[str]) -> Stream:
    """``stream`` sorted by time with repeated timestamps dropped (first kept), said in a note."""
    t = np.asarray(stream.time_s, dtype=float)
    if t.size < 2 or bool(np.all(np.diff(t) > 0)):
        return stream
    order = np.argsort(t, kind="stable")
    t_sorted = t[order]
    keep = np.concatenate(([True], np.diff(t_sorted) > 0))
    backwards = int(np.count_nonzero(np.diff(t) < 0))
    repeated = int(np.count_nonzero(~keep))
    notes.append(f"{stream.source}: {backwards} backwards and {repeated} repeated timestamps; "
                 "sorted by time, repeats dropped (first kept)")
    pick = order[keep]
    return Stream(stream.source, t_sorted[keep],
                  {k: np.asarray(v)[pick] for k, v in stream.values.items()})


def interp_gapped(t_src: np.ndarray, y_src: np.ndarray, t_dst: np.ndarray,
                  max_gap_s: float = MAX_GAP_S) -> np.ndarray:
    """Linear interpolation of ``y_src`` to ``t_dst``; NaN outside, and inside a gap.

    Parameters
    ----------
    t_src : numpy.ndarray
        Increasing sample times [s].
    y_src : numpy.ndarray
        Values there (NaN samples are left out).
    t_dst : numpy.ndarray
        Times wanted [s].
    max_gap_s : float
        A pair of samples further apart [s] is not bridged.
    """
    ok = np.isfinite(y_src)
    t, y = t_src[ok], y_src[ok]
    out = np.full(np.shape(t_dst), np.nan)
    if t.size == 0:
        return out
    if t.size == 1:
        out[np.asarray(t_dst) == t[0]] = y[0]
        return out
    right = np.clip(np.searchsorted(t, t_dst, side="right"), 1, t.size - 1)
    inside = (t_dst >= t[0]) & (t_dst <= t[-1]) & (t[right] - t[right - 1] <= max_gap_s)
    out[inside] = np.interp(t_dst[inside], t, y)
    return out


def integrate_window(t: np.ndarray, y: np.ndarray, start_s: float, end_s: float,
                     max_gap_s: float = MAX_GAP_S) -> tuple[float, float, int]:
    """Trapezoid integral of ``y`` over the samples in ``[start_s, end_s]``, gaps left out.

    Returns
    -------
    integral : float
        [unit of y x s].
    covered_s : float
        Time integrated over [s].
    gaps : int
        Intervals longer than ``max_gap_s`` (or with a NaN end) left out.
    """
    pick = (t >= start_s) & (t <= end_s)
    tw, yw = t[pick], y[pick]
    if tw.size < 2:
        return 0.0, 0.0, 0
    dt = np.diff(tw)
    mean = 0.5 * (yw[1:] + yw[:-1])
    ok = (dt <= max_gap_s) & np.isfinite(mean)
    return float(np.sum(mean[ok] * dt[ok])), float(np.sum(dt[ok])), int(np.count_nonzero(~ok))


# ---- battery -------------------------------------------------------------------------------


@dataclass(frozen=True)
class PackPower:
    """One battery instance that measures current: its power [W] on its own clock."""

    source: str
    time_s: np.ndarray
    power_w: np.ndarray
    current_a: np.ndarray
    discharged_mah: np.ndarray


def pack_powers(log: FlightLog, window: AirborneWindow, notes: list[str]) -> list[PackPower]:
    """The instances with a current sensor, current -1 read as "no sensor", signs fixed.

    A pack reported on two instances (one with the current, one without) counts once: the
    instance without current adds nothing, and lends its voltage only where the one with the
    current has none.
    """
    streams = [ordered(b, notes) for b in log.batteries]
    voltages = [np.where(s.column("voltage_v") > 0, s.column("voltage_v"), np.nan)
                for s in streams]
    packs: list[PackPower] = []
    for k, s in enumerate(streams):
        current = s.column("current_a")
        sentinel = current == NO_CURRENT_SENSOR
        current = np.where(sentinel, np.nan, current)
        if not np.any(np.nan_to_num(current) != 0):  # a phantom instance reads 0 A
            why = ("-1 (no sensor)" if sentinel.any() else
                   "0" if np.isfinite(current).any() else "not logged")
            notes.append(f"{s.source}: current {why} throughout; it adds no power")
            continue
        voltage = voltages[k]
        if not np.isfinite(voltage).any():
            lender = next((j for j, v in enumerate(voltages)
                           if j != k and np.isfinite(v).any()), None)
            if lender is None:
                notes.append(f"{s.source}: current but no voltage on any instance; it adds "
                             "no power")
                continue
            voltage = interp_gapped(streams[lender].time_s, voltages[lender], s.time_s)
            notes.append(f"{s.source}: no voltage; {streams[lender].source}'s used")
        flown = (s.time_s >= window.start_s) & (s.time_s <= window.end_s)
        typical = np.nanmedian(current[flown]) if np.isfinite(current[flown]).any() else 0.0
        if typical < 0:  # some monitors report discharge as negative
            current = -current
            notes.append(f"{s.source}: current negative in flight (median {typical:.2f} A): "
                         "read as discharge and its sign flipped (discharge is positive here)")
        packs.append(PackPower(s.source, s.time_s, voltage * current, current,
                               s.column("discharged_mah")))
    return packs


def _energy(packs: list[PackPower], window: AirborneWindow, notes: list[str]
            ) -> tuple[float | None, float | None, float | None, float | None]:
    """Energy [Wh], counter charge [mAh], integrated charge [mAh], mean power [W]."""
    if not packs:
        notes.append("no battery instance measures current: energy, mAh and power are not "
                     "available")
        return None, None, None, None
    energy_j = mean_w = integrated_as = 0.0
    counter: float | None = 0.0
    for pack in packs:
        joules, covered, gaps = integrate_window(pack.time_s, pack.power_w, window.start_s,
                                                 window.end_s)
        charge, _, _ = integrate_window(pack.time_s, pack.current_a, window.start_s,
                                        window.end_s)
        if gaps:
            notes.append(f"{pack.source}: {gaps} gaps longer than {MAX_GAP_S:g} s (or NaN) in "
                         "the airborne window, not integrated across "
                         f"({window.duration_s - covered:.1f} s uncovered)")
        energy_j += joules
        integrated_as += charge
        mean_w += joules / covered if covered > 0 else np.nan
        inside = (pack.time_s >= window.start_s) & (pack.time_s <= window.end_s)
        mah = pack.discharged_mah[inside]
        mah = mah[np.isfinite(mah)]
        if counter is not None and mah.size >= 2:
            counter += float(mah[-1] - mah[0])  # the counter need not start at 0
        else:
            counter = None
    return energy_j / 3600.0, counter, integrated_as / 3.6, float(mean_w)


def power_at(packs: list[PackPower], t: np.ndarray, what: str = "power_w") -> np.ndarray:
    """Total electrical power [W] (or ``what="current_a"``: current [A]) of ``packs`` at
    times ``t`` [s] (NaN where one has none)."""
    total = np.zeros(np.shape(t))
    for pack in packs:
        total = total + interp_gapped(pack.time_s, getattr(pack, what), t)
    return total if packs else np.full(np.shape(t), np.nan)


# ---- airborne window -----------------------------------------------------------------------


def airborne_window(log: FlightLog, airborne_airspeed_m_s: float, airborne_height_m: float,
                    notes: list[str]) -> AirborneWindow:
    """The land detector's airborne time where it ever says airborne, else the airspeed rule.

    Raises
    ------
    InputError
        Neither finds any airborne time (a log from the ground).
    """
    if log.landed is not None:
        landed = ordered(log.landed, notes)
        flag = landed.column("landed")
        air = np.flatnonzero(flag == 0)
        if air.size:
            start = float(landed.time_s[air[0]])
            after = np.flatnonzero((flag == 1) & (np.arange(flag.size) > air[-1]))
            end = float(landed.time_s[after[0]]) if after.size else _log_end(log)
            if np.any(flag[air[0]:air[-1] + 1] == 1):
                notes.append(f"{landed.source}: landed between airborne stretches; the window "
                             "spans the first take-off to the last landing")
            return AirborneWindow(start, end, f"land detector ({landed.source}): from its first "
                                  "'airborne' to its first 'landed' after the last 'airborne'")
        notes.append(f"{landed.source} says landed throughout (a log flown without arming, "
                     "or from the ground): the airspeed rule decides")
    if log.airspeed is None:
        raise InputError(f"{log.path}: no airborne window: the land detector never says "
                         "airborne and the log has no airspeed (nor ground speed)")
    speed = ordered(log.airspeed, notes)
    v = speed.column("airspeed_m_s")
    t = speed.time_s
    fast = np.flatnonzero(v >= airborne_airspeed_m_s)
    rule = (f"airspeed rule: first to last {log.airspeed_kind} airspeed sample >= "
            f"{airborne_airspeed_m_s:g} m/s")
    if fast.size == 0:
        top = np.nanmax(v) if np.isfinite(v).any() else float("nan")
        raise InputError(f"{log.path}: no airborne window: the land detector never says "
                         f"airborne and the airspeed never reaches {airborne_airspeed_m_s:g} "
                         f"m/s (greatest {top:.1f} m/s); a log from the ground?")
    ok = v >= airborne_airspeed_m_s
    if log.baro is not None:
        baro = ordered(log.baro, notes)
        alt = baro.column("altitude_m")
        first = t[fast[0]]
        before = (baro.time_s >= first - GROUND_WINDOW_S) & (baro.time_s < first) & np.isfinite(alt)
        if not before.any():
            before = np.isfinite(alt) & (baro.time_s <= baro.time_s[0] + GROUND_WINDOW_S)
            notes.append("no baro altitude in the 30 s before the first fast sample: ground is "
                         "the median of the baro's first 30 s")
        ground = float(np.median(alt[before]))
        ok &= interp_gapped(baro.time_s, alt, t) >= ground + airborne_height_m
        rule += (f" and baro altitude >= ground + {airborne_height_m:g} m (ground {ground:.1f} m, "
                 f"the median over the {GROUND_WINDOW_S:g} s before the first such sample)")
    else:
        notes.append("no baro altitude: the airborne window rests on the airspeed alone")
    hits = np.flatnonzero(ok)
    if hits.size == 0:
        raise InputError(f"{log.path}: no airborne window: no sample is both >= "
                         f"{airborne_airspeed_m_s:g} m/s and {airborne_height_m:g} m above "
                         "ground; a log from the ground?")
    return AirborneWindow(float(t[hits[0]]), float(t[hits[-1]]), rule)


def _log_end(log: FlightLog) -> float:
    ends = [s.time_s[-1] for s in (log.airspeed, log.baro, log.throttle, *log.batteries)
            if s is not None and s.time_s.size]
    return float(max(ends))


# ---- bins ----------------------------------------------------------------------------------


def speed_bins(airspeed_m_s: np.ndarray, weight_s: np.ndarray, power_w: np.ndarray,
               throttle: np.ndarray, min_time_s: float = MIN_BIN_S) -> tuple[SpeedBin, ...]:
    """Time-weighted power and throttle in 1 m/s airspeed bins with >= ``min_time_s`` each.

    Parameters
    ----------
    airspeed_m_s : numpy.ndarray
        Airspeed samples [m/s].
    weight_s : numpy.ndarray
        Time each sample stands for [s] (0 leaves it out).
    power_w : numpy.ndarray
        Electrical power at the samples [W] (NaN leaves the sample out).
    throttle : numpy.ndarray
        Throttle at the samples [-] (NaN: averaged over the others).
    min_time_s : float
        Least time [s] a bin needs to be reported.
    """
    use = (weight_s > 0) & np.isfinite(airspeed_m_s) & np.isfinite(power_w)
    if not use.any():
        return ()
    label = np.floor(airspeed_m_s[use] + 0.5).astype(int)  # bin v holds [v-0.5, v+0.5)
    low = int(label.min())
    idx = label - low
    w, p, thr = weight_s[use], power_w[use], throttle[use]
    n = int(idx.max()) + 1
    time = np.bincount(idx, w, n)
    count = np.bincount(idx, None, n)
    mean = np.bincount(idx, w * p, n) / np.where(time > 0, time, 1)
    var = np.bincount(idx, w * (p - mean[idx]) ** 2, n) / np.where(time > 0, time, 1)
    has = np.isfinite(thr)
    thr_time = np.bincount(idx[has], w[has], n)
    thr_mean = np.bincount(idx[has], w[has] * thr[has], n) / np.where(thr_time > 0, thr_time,
                                                                      np.nan)
    thr_var = np.bincount(idx[has], w[has] * (thr[has] - thr_mean[idx[has]]) ** 2, n) / np.where(
        thr_time > 0, thr_time, np.nan)
    return tuple(
        SpeedBin(float(low + i), float(time[i]), int(count[i]), float(mean[i]),
                 float(np.sqrt(var[i])), float(thr_mean[i]), float(np.sqrt(thr_var[i])))
        for i in np.flatnonzero(time >= min_time_s)
    )


def sample_weights(t: np.ndarray, window: AirborneWindow) -> np.ndarray:
    """Time [s] each sample stands for: up to the next one, 0 across a gap or outside."""
    dt = np.diff(t, append=t[-1]) if t.size else t
    inside = (t >= window.start_s) & (t < window.end_s)
    return np.where(inside & (dt <= MAX_GAP_S), dt, 0.0)


def climb_rate_at(log: FlightLog, t: np.ndarray, notes: list[str]) -> np.ndarray:
    """Climb rate [m/s] at ``t``: the log's estimate, else the baro altitude's difference
    over +-0.5 s (a 1 s central difference: the baro's noise is not differentiated raw)."""
    if log.climb is not None:
        climb = ordered(log.climb, notes)
        return interp_gapped(climb.time_s, climb.column("climb_rate_m_s"), t)
    if log.baro is None:
        return np.full(np.shape(t), np.nan)
    baro = ordered(log.baro, notes)
    alt = baro.column("altitude_m")
    up = interp_gapped(baro.time_s, alt, t + 0.5)
    down = interp_gapped(baro.time_s, alt, t - 0.5)
    notes.append(f"climb rate: the baro altitude's change over 1 s ({baro.source})")
    return up - down


# ---- the whole flown side ------------------------------------------------------------------


def reduce_flight(log: FlightLog, airborne_airspeed_m_s: float = DEFAULT_AIRBORNE_AIRSPEED_M_S,
                  airborne_height_m: float = DEFAULT_AIRBORNE_HEIGHT_M,
                  mass_kg: float | None = None,
                  climb_efficiency: float = DEFAULT_CLIMB_EFFICIENCY) -> FlownResult:
    """The flown side of ``log``: window, energy, and power/throttle against airspeed.

    Parameters
    ----------
    log : FlightLog
        The streams read.
    airborne_airspeed_m_s : float
        Airspeed [m/s] at or above which the airspeed rule counts a sample airborne.
    airborne_height_m : float
        Height above ground [m] the airspeed rule also asks.
    mass_kg : float or None
        Aircraft mass [kg] for the climb correction (none without it).
    climb_efficiency : float
        Electrical-to-climb-power efficiency [-]: corrected power is
        ``P - m g dh/dt / climb_efficiency``.
    """
    notes = list(log.notes)
    window = airborne_window(log, airborne_airspeed_m_s, airborne_height_m, notes)
    packs = pack_powers(log, window, notes)
    energy_wh, charge_mah, integrated_mah, mean_power_w = _energy(packs, window, notes)
    bins: tuple[SpeedBin, ...] = ()
    level: tuple[SpeedBin, ...] = ()
    corrected: tuple[SpeedBin, ...] = ()
    series: dict[str, np.ndarray] = {}
    if log.airspeed is None:
        notes.append("no airspeed (nor ground speed): no power against airspeed")
    else:
        speed = ordered(log.airspeed, notes)
        t = speed.time_s
        v = speed.column("airspeed_m_s")
        weight = sample_weights(t, window)
        flown_v = v[weight > 0]
        if flown_v.size and np.nanmax(np.abs(flown_v)) < 1.0:
            notes.append(f"{speed.source}: {log.airspeed_kind} below 1 m/s all flight ("
                         + ("a hover" if log.airspeed_kind == "ground speed"
                            else "a dead or unplugged sensor") + "): no power against airspeed")
            weight = np.zeros_like(weight)
        power = power_at(packs, t)
        throttle = np.full(t.shape, np.nan)
        if log.throttle is not None:
            commanded = ordered(log.throttle, notes)
            throttle = interp_gapped(commanded.time_s, commanded.column("throttle"), t)
        if log.throttle is None:
            notes.append("no throttle logged (e.g. RC pass-through): throttle per bin is n/a")
        climb = climb_rate_at(log, t, notes)
        current = power_at(packs, t, "current_a")
        def with_current(weights: np.ndarray) -> tuple[SpeedBin, ...]:
            # the mean current per bin, for the autopilot hand-off (the same weights)
            amps = {b.airspeed_m_s: b.power_w for b in speed_bins(v, weights, current,
                                                                   throttle)}
            return tuple(replace(b, current_a=amps.get(b.airspeed_m_s, np.nan))
                         for b in speed_bins(v, weights, power, throttle))

        bins = with_current(weight)
        is_level = np.abs(climb) < LEVEL_CLIMB_M_S
        level = with_current(np.where(is_level, weight, 0.0))
        if mass_kg is not None:
            corrected_power = power - mass_kg * G * climb / climb_efficiency
            corrected = speed_bins(v, np.where(np.isfinite(climb), weight, 0.0),
                                   corrected_power, throttle)
        else:
            notes.append("no mass (give --mass or --case): no climb-corrected power")
        altitude = np.full(t.shape, np.nan)
        if log.baro is not None:
            baro = ordered(log.baro, notes)
            altitude = interp_gapped(baro.time_s, baro.column("altitude_m"), t)
        series = {"time_s": t, "airspeed_m_s": v, "power_w": power, "throttle": throttle,
                  "altitude_m": altitude, "climb_rate_m_s": climb,
                  "airborne": ((t >= window.start_s) & (t <= window.end_s)).astype(float)}
        if not bins and weight.any():
            notes.append(f"no airspeed bin holds {MIN_BIN_S:g} s of airborne data with power")
    return FlownResult(window, energy_wh, charge_mah, integrated_mah, mean_power_w, bins, level,
                       corrected, climb_efficiency, mass_kg, log.airspeed_kind, series,
                       tuple(dict.fromkeys(notes)))


def series_csv(series: dict[str, np.ndarray]) -> str:
    """The aligned time series as CSV text (one row per airspeed sample)."""
    names = list(series)
    table = np.column_stack([series[k] for k in names]) if names else np.empty((0, 0))
    lines = [",".join(names)]
    # time keeps microseconds (a PX4 SITL clock counts from 1970: 10 digits are whole seconds)
    formats = ["{:.6f}" if name == "time_s" else "{:.10g}" for name in names]
    lines += [",".join("" if not np.isfinite(x) else f.format(x) for f, x in zip(formats, row,
                                                                               strict=True))
              for row in table]
    return "\n".join(lines) + "\n"
