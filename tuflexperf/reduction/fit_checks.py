"""What a fit refuses and what it notes: a fit the evidence does not back is never written.

Degenerate set points, a load cell out of scale or deaf to its throttle, an unphysical
surface (negative drag, thrust falling with throttle) are refused as bad input naming the
run; a poor but usable fit and an extrapolated airspeed range are notes.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import numpy as np

from tuflexperf.errors import InputError
from tuflexperf.reduction.drag import DragModel
from tuflexperf.reduction.poly22fit import Poly22Fit
from tuflexperf.reduction.step_runs import Point, StepRunResult

# A thrust surface that explains less of its points than this is no fan's (the paper's
# 0.9968; a run with its force sign flipped gives 0.43); below
# POOR_POLY22_R2 it is said (a small fan's noisy table gave 0.89 and is a fit)
MIN_POLY22_R2 = 0.5
POOR_POLY22_R2 = 0.9

# --- campaign ---------------------------------------------------------------------------------
MIN_SWEEP_THROTTLE_SWING = 0.05  # a sweep whose throttle barely moves measures no delay

MIN_DRAG_SWEEP_AIRSPEED_M_S = 1.0  # a drag sweep that never blows measures no drag

MIN_DRAG_SWEEP_SPAN_M_S = 5.0  # ... and one that holds one airspeed measures no curve

SET_POINT_RESOLUTION_M_S = 0.5  # tunnel set points closer than this are one set point

MIN_SET_POINTS = 3  # airspeeds a poly22 surface (quadratic in airspeed) needs


def check_set_points(campaign: Any, step_results: list[Any]) -> list[str]:
    """Bad input: an engine whose step runs cover fewer than 3 airspeed set points; and a
    note per set point an engine has two or more runs at (repeats are fitted together; a run
    labelled with the wrong engine looks the same, and only the user can tell).

    Counted from each run's median airspeed rounded to the set-point resolution, not from
    the measured values (their noise makes any two runs look like many airspeeds and
    defeats the rank test of the fit).
    """
    by_engine: dict[str, dict[float, list[str]]] = {}
    empty: dict[str, list[str]] = {}
    for result in step_results:
        runs = by_engine.setdefault(str(result.run.engine), {})
        speeds = [seg.airspeed_m_s for seg in result.segments]
        if not speeds:  # no test point: no airspeed either (not 0 m/s)
            empty.setdefault(str(result.run.engine), []).append(result.run.file)
            continue
        runs.setdefault(set_point(float(np.median(speeds))), []).append(result.run.file)
    for engine, points in by_engine.items():
        if len(points) < MIN_SET_POINTS:
            listed = "; ".join(f"{v:g} m/s ({', '.join(files)})" for v, files in
                               sorted(points.items()))
            without = empty.get(engine, [])
            raise InputError(
                f"{campaign.path}: {engine}: the throttle-step runs cover only {len(points)} "
                f"airspeed set point(s){', ' + listed if listed else ''}; a poly22 surface "
                f"needs at least {MIN_SET_POINTS}"
                + (f" ({', '.join(without)} gave no test point)" if without else "")
            )
    return [
        f"{engine}: {len(files)} throttle-step runs at {v:g} m/s ({', '.join(files)}): fitted "
        "together as repeats; is one another engine's?"
        for engine, points in by_engine.items() for v, files in sorted(points.items())
        if len(files) > 1
    ]


def set_point(airspeed_m_s: float) -> float:
    """The tunnel set point [m/s] an airspeed belongs to (:data:`SET_POINT_RESOLUTION_M_S`)."""
    return round(airspeed_m_s / SET_POINT_RESOLUTION_M_S) * SET_POINT_RESOLUTION_M_S


# --- table ----------------------------------------------------------------------------------
# A structure drag this far below zero at the top airspeed (as a share of the largest force
# the fans' runs measured) is no drag: the sweep's sign is flipped, not noise around a clean rig
NEGATIVE_DRAG_SHARE = 0.01

DEAD_LOAD_CELL_N = 1e-9  # a drag sweep's force spanning no more than this never moved [N]


# A throttle-step run whose steady force moves by less than this share of the campaign's
# largest while its throttle moves by at least DEAF_THROTTLE_SPAN measured no thrust
DEAF_FORCE_SHARE = 0.02

DEAF_THROTTLE_SPAN = 0.3

FORCE_SCALE_RATIO = 20.0
"""Two runs of one fan whose largest forces are this many times apart: one is in another
unit (mN, kgf), or another engine's (a run of low throttle steps alone reaches ~1/10)."""


def _largest_force(result: StepRunResult) -> float:
    return max((abs(s.force_n) for s in result.segments), default=0.0)


def _follows_its_throttle(result: StepRunResult) -> bool:
    """The run's force moves with its throttle (by a tenth of its largest, or more)."""
    force = [s.force_n for s in result.segments]
    return len(force) >= 2 and max(force) - min(force) > 0.1 * _largest_force(result)


def _typical_largest_force(results: list[StepRunResult]) -> dict[str, float]:
    """Per engine, the median over its step runs whose force follows the throttle (all of
    them if none does) of each run's largest segment force [N]: stuck runs, however many,
    do not make a good run look like one in another unit."""
    live: dict[str, list[float]] = {}
    every: dict[str, list[float]] = {}
    for r in results:
        if r.segments:
            engine = str(r.run.engine)
            every.setdefault(engine, []).append(_largest_force(r))
            if _follows_its_throttle(r):
                live.setdefault(engine, []).append(_largest_force(r))
    return {engine: float(np.median(live.get(engine) or values))
            for engine, values in every.items()}


def refuse_force_scale_outliers(campaign: Any, results: list[StepRunResult]) -> None:
    """Bad input: two step runs of one engine, each with a force that follows its throttle,
    whose largest forces are more than :data:`FORCE_SCALE_RATIO` apart: one group is in
    another unit (mN, kgf) or another engine's. Which one cannot be told from the runs (one
    run in mN makes a 1.5 MN fan; four of seven, by the median, a 55 kN one)."""
    by_engine: dict[str, list[StepRunResult]] = {}
    for r in results:
        if _follows_its_throttle(r):
            by_engine.setdefault(str(r.run.engine), []).append(r)
    for engine, runs in by_engine.items():
        low = min(runs, key=_largest_force)
        high = max(runs, key=_largest_force)
        small, large = _largest_force(low), _largest_force(high)
        if small > 0 and large > FORCE_SCALE_RATIO * small:
            raise InputError(
                f"{campaign.path}: {engine}: {high.run.file} reaches {large:.4g} N and "
                f"{low.run.file} {small:.4g} N ({large / small:.3g} x): runs of one fan in "
                "another unit (mN, kgf), or another engine's run?"
            )


def deaf_runs(results: list[StepRunResult]) -> tuple[list[str], set[str]]:
    """A note per step run whose force does not follow its throttle (a dead load cell), and
    those runs' files: their points are left out of the fit (fitted, one stuck run brought
    EDF1's surface to R^2 0.78)."""
    # per engine (a small fan beside a big one is no deaf one), the median run's largest
    # force: by the largest of all, one run logged in mN would make six good ones "deaf"
    largest = _typical_largest_force(results)
    notes = []
    deaf: set[str] = set()
    for result in results:
        if len(result.segments) < 2:
            continue
        throttle = [s.throttle for s in result.segments]
        force = [s.force_n for s in result.segments]
        if (max(throttle) - min(throttle) >= DEAF_THROTTLE_SPAN
                and max(force) - min(force) < DEAF_FORCE_SHARE * largest[str(result.run.engine)]):
            notes.append(
                f"{result.run.file}: the force stays within {max(force) - min(force):.3g} N "
                f"while the throttle moves {min(throttle):.2f}-{max(throttle):.2f}: a dead load "
                "cell? its points are left out of the fit"
            )
            deaf.add(result.run.file)
    return notes, deaf


def poor_fit_notes(fits: dict[str, Poly22Fit]) -> list[str]:
    """A note per engine whose surface explains its points poorly, but not so poorly that
    it is refused (:data:`MIN_POLY22_R2` .. :data:`POOR_POLY22_R2`)."""
    return [
        f"engine {engine}: the poly22 surface explains only R^2 = {fit.r2:.3f} of its points "
        f"(the paper's 0.997): noisy points, or a run's force sign, unit or engine label?"
        for engine, fit in fits.items() if math.isfinite(fit.r2) and fit.r2 < POOR_POLY22_R2
    ]


def refuse_unphysical_fit(
    label: str, fits: dict[str, Poly22Fit], drag: DragModel | None = None,
    points: list[Point] | None = None,
) -> None:
    """Bad input: a fit that ``check`` would refuse, or a structure drag no rig has.

    A full-throttle static thrust that is not positive (the runs' force sign flipped); a
    structure drag at the top airspeed that is negative beyond noise (the drag sweep's sign
    flipped) or larger than every force the fans' runs measured (the sweep in mN: it was
    added to every point and "passed" check with a 3000 N fan).
    """
    for engine, fit in fits.items():
        static = float(np.ravel(fit.predict(1.0, 0.0))[0])
        if not static > 0:
            raise InputError(f"{label}: engine {engine}: the fitted full-throttle static thrust "
                             f"is {static:.3g} N, not positive: is the force sign of its runs "
                             "flipped?")
        throttle, airspeed, thrust = fit.points
        if not math.isfinite(fit.r2):  # every point the same thrust
            raise InputError(f"{label}: engine {engine}: every point has the thrust "
                             f"{float(thrust[0]):.4g} N: it answers neither throttle nor airspeed")
        if fit.r2 < MIN_POLY22_R2:
            raise InputError(
                f"{label}: engine {engine}: the poly22 surface explains only R^2 = "
                f"{fit.r2:.3f} of its points (the paper's 0.997; at least {MIN_POLY22_R2:g}): "
                "is a run's force sign, unit or engine label wrong?"
            )
        low, high = float(throttle.min()), float(throttle.max())
        for v in (float(airspeed.min()), float(airspeed.max())):
            rise = float(np.ravel(fit.predict(high, v))[0] - np.ravel(fit.predict(low, v))[0])
            if not rise > 0:
                raise InputError(
                    f"{label}: engine {engine}: the fitted thrust at {v:.1f} m/s does not rise "
                    f"from throttle {low:.2f} to {high:.2f} ({rise:+.3g} N): is a run's force "
                    "sign or throttle column wrong?"
                )
    if drag is None or not points:
        return
    top = max(p.airspeed_measured_m_s for p in points)
    at_top = float(drag.drag_n(top))
    largest = max(abs(p.force_n) for p in points)
    if at_top < -NEGATIVE_DRAG_SHARE * largest:
        raise InputError(f"{label}: drag_sweep: the structure drag at {top:.1f} m/s is "
                         f"{at_top:.3g} N, negative: is the force sign of the drag sweep flipped?")
    if at_top > largest:
        raise InputError(f"{label}: drag_sweep: the structure drag at {top:.1f} m/s is "
                         f"{at_top:.4g} N, more than any force the fans' runs measured "
                         f"({largest:.4g} N): is the drag sweep in other units (mN)?")


def speeds_by_engine(points: Iterable[tuple[str, float]]) -> dict[str, list[float]]:
    """Each engine's tested airspeeds [m/s] from ``(engine, airspeed)`` pairs."""
    speeds: dict[str, list[float]] = {}
    for engine, airspeed in points:
        speeds.setdefault(engine, []).append(float(airspeed))
    return speeds


def _engine_range(speeds: list[float]) -> tuple[float, float]:
    """One engine's airspeed range, to 0.1 m/s (the tunnel's set points are not more exact);
    from no lower than rest (a pitot's zero offset, -0.6 m/s at rest, is no reverse wind)."""
    return max(round(min(speeds), 1), 0.0) + 0.0, round(max(speeds), 1) + 0.0


def tested_range(speeds: dict[str, list[float]], where: str) -> list[float]:
    """The airspeed range [m/s] every engine was tested over (the file has one range, and
    each engine's model is flown over all of it: an engine tested to 25 m/s beside one
    tested to 30 m/s is not tested to 30). Engines with no airspeed in common are bad input."""
    ranges = {engine: _engine_range(v) for engine, v in speeds.items()}
    low = max(r[0] for r in ranges.values())
    high = min(r[1] for r in ranges.values())
    if low >= high:  # one airspeed in common is no range either (the schema's low < high)
        raise InputError(
            f"{where}: the engines were tested at no airspeed range in common ("
            + ", ".join(f"{e} {r[0]:g}-{r[1]:g} m/s" for e, r in ranges.items())
            + "): one propulsion file has one tested airspeed range")
    return [low, high]


# engines' tested ends further apart than this are said (set points are 2.5 m/s or more
# apart; the measured means of one set point scatter by a few 0.1 m/s)
RANGE_NOTE_M_S = 1.0


def tested_range_notes(speeds: dict[str, list[float]]) -> list[str]:
    """A warning where the engines' own tested ranges differ from the one written by more
    than :data:`RANGE_NOTE_M_S` at either end."""
    ranges = {engine: _engine_range(v) for engine, v in speeds.items()}
    lows, highs = [r[0] for r in ranges.values()], [r[1] for r in ranges.values()]
    if max(lows) - min(lows) <= RANGE_NOTE_M_S and max(highs) - min(highs) <= RANGE_NOTE_M_S:
        return []
    return [  # the range they share, as tested_range writes it
        "the engines were tested over different airspeeds ("
        + ", ".join(f"{e} {r[0]:g}-{r[1]:g} m/s" for e, r in ranges.items())
        + f"): the file's tested_airspeed_m_s is the range they share, "
        f"{max(lows):g}-{min(highs):g} m/s"
    ]
